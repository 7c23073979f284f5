r"""Identification of a robot's geometric parameters from measurements (chapter 12).

Two problems, one result type (:class:`Identification`):

- **Linear** (:func:`fit_linear`, :func:`identify_desk_arm`). When the measured quantity is
  linear in the unknown lengths for known joint angles, :math:`b = A(q)\,\ell`, stacking the
  equations of all poses gives an ordinary least-squares problem, solved by
  ``numpy.linalg.lstsq``. The desktop arm of the lab report is such a case.
- **Nonlinear** (:func:`identify_dh_parameters`: a kinematic calibration). The flange
  position of a chain depends on its Denavit--Hartenberg parameters through sines and
  cosines; Gauss--Newton with Levenberg--Marquardt damping solves it, with the
  identification Jacobian :math:`\partial p / \partial \pi` of
  :func:`identification_jacobian` derived from the chain. (Reading the calibration a UR
  controller holds is :mod:`dqlab.ur.calibration`'s work.)

In both, the parameters that the measurements cannot separate are found from the singular
values of the column-scaled regressor (or Jacobian), reported by name, and held at their
reference values; what *can* be estimated is printed as named combinations
(``"l0 - l4"``). The covariance of the estimate follows from the residual variance,

.. math::

   \hat\sigma^2 = \frac{\lVert b - A\hat\ell\rVert^2}{k - r},\qquad
   \operatorname{cov}(\hat\ell) = \hat\sigma^2\,(A^\mathsf{T} A)^{-1},

with :math:`k` equations and :math:`r` estimated parameters. Units are metres and radians.
"""

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from ._checks import (
    as_float_array,
    check_instance,
    check_scalar,
    check_tolerance,
    components,
    stack_components,
)
from ._formulas import rotation_vector_from_matrix_entries
from .robot import Link, Robot
from .transforms import check_transform

__all__ = [
    "Identification", "IllConditionedWarning", "fit_linear", "DESK_ARM_PARAMETERS",
    "desk_arm_regressor", "identify_desk_arm", "dh_parameter_names", "dh_parameters",
    "robot_from_dh_parameters", "identification_jacobian", "identify_dh_parameters",
]

#: The desktop arm's lengths in the order of :func:`desk_arm_regressor`'s columns.
DESK_ARM_PARAMETERS = ("l0", "l1", "l2", "l3", "l4")


class IllConditionedWarning(UserWarning):
    """The estimated parameters are poorly determined by the measurements.

    Raised as a warning when the condition number of the column-scaled regressor (or
    identification Jacobian) of the *estimated* parameters exceeds ``max_condition``: the
    problem has a solution, but small measurement errors move it a lot.
    """


@dataclass(frozen=True, eq=False)
class Identification:
    r"""The result of an identification: estimate, its uncertainty and what is identifiable.

    Attributes
    ----------
    names : tuple of str, length p
        Parameter names, in the order of every array below.
    estimate : ndarray, shape (p,)
        Estimated parameters. Parameters that are not estimated (see ``estimated``) keep
        their reference values.
    estimated : ndarray of bool, shape (p,)
        Which parameters were estimated; the others were held (unidentifiable, or fixed by
        the caller).
    scaled_unit_covariance : ndarray, shape (p, p)
        :math:`(J_s^\mathsf{T} J_s)^{-1}` of the estimated parameters in the column-scaled
        problem :math:`J_s = J D^{-1}` (zero rows and columns for the held ones).
    column_scales : ndarray, shape (p,)
        :math:`D`, the column norms of the regressor (1 for a column without effect).
        :attr:`unit_covariance` is :math:`D^{-1} (J_s^\mathsf{T} J_s)^{-1} D^{-1}`; the
        covariance and the standard errors are computed from the scaled form, so that they
        do not overflow or underflow when the problem is given in very large or very small
        units.
    sigma : float
        Residual standard deviation :math:`\hat\sigma = \sqrt{\lVert r\rVert^2 / (k - r)}`.
    residuals : ndarray, shape (k,)
        Measured minus model, at the estimate.
    singular_values : ndarray, shape (p,)
        Singular values of the column-scaled regressor (or identification Jacobian at the
        reference parameters), largest first; those below ``rank_tol`` times the largest are
        treated as zero.
    rank : int
        Number of identifiable combinations (= number of estimated parameters).
    condition_number : float
        Condition number of the column-scaled regressor of the estimated parameters.
    null_space : ndarray, shape (p, p - rank)
        Parameter changes (in parameter units) that do not change any measurement.
    unidentifiable : tuple of str
        The null space as named combinations: ``"l0 + l4"`` means that increasing ``l0``
        and ``l4`` by the same amount changes no measurement. A single name means that the
        parameter has no effect at all.
    identifiable_rows : ndarray, shape (rank, p)
        Coefficients of the identifiable combinations (reduced row-echelon basis of the
        regressor's row space): ``identifiable_rows @ estimate`` does not depend on the
        values at which the held parameters were fixed.
    identifiable : tuple of str
        ``identifiable_rows`` as text, e.g. ``("l0 - l4", "l1", "l2", "l3")``.
    iterations : int
        Gauss--Newton / Levenberg--Marquardt iterations (0 for a linear fit).
    converged : bool
    robot : Robot or None
        For :func:`identify_dh_parameters`: the chain with the estimated parameters.

    Examples
    --------
    >>> import numpy as np
    >>> A = np.array([[1.0, 0.0, 1.0], [1.0, 1.0, 1.0], [1.0, 2.0, 1.0], [1.0, 3.0, 1.0]])
    >>> fit = fit_linear(A, [0.1, 1.0, 2.1, 2.9], names=["b", "m", "b2"])
    >>> fit.held, fit.unidentifiable
    (('b2',), ('b - b2',))
    >>> [(label, round(value, 6)) for label, value, _ in fit.combinations()]
    [('b + b2', 0.1), ('m', 0.95)]
    """

    names: tuple
    estimate: np.ndarray
    estimated: np.ndarray
    scaled_unit_covariance: np.ndarray
    column_scales: np.ndarray
    sigma: float
    residuals: np.ndarray
    singular_values: np.ndarray
    rank: int
    condition_number: float
    null_space: np.ndarray
    unidentifiable: tuple
    identifiable_rows: np.ndarray
    identifiable: tuple
    iterations: int = 0
    converged: bool = True
    robot: object = field(default=None, repr=False)

    @property
    def held(self):
        """Names of the parameters that were not estimated."""
        return tuple(n for n, e in zip(self.names, self.estimated, strict=True) if not e)

    @property
    def unit_covariance(self):
        r""":math:`(J^\mathsf{T} J)^{-1}` of the estimated parameters (zero rows and columns for
        the held ones): the covariance of the estimate per unit measurement variance, shape
        (p, p)."""
        inverse = 1.0 / self.column_scales
        return inverse[:, None] * self.scaled_unit_covariance * inverse[None, :]

    @property
    def covariance(self):
        r""":math:`\hat\sigma^2 (J^\mathsf{T} J)^{-1}`, shape (p, p)."""
        w = self.sigma / self.column_scales
        return w[:, None] * self.scaled_unit_covariance * w[None, :]

    @property
    def standard_errors(self):
        """Standard errors of the parameters from the residual variance (0 when held)."""
        return self.sigma / self.column_scales * np.sqrt(np.diag(self.scaled_unit_covariance))

    def value(self, name):
        """The estimate of one parameter, by name."""
        return float(self.estimate[self._index(name)])

    def _index(self, name):
        if not isinstance(name, str) or name not in self.names:
            raise ValueError(f"name must be one of the parameters {', '.join(self.names)}; "
                             f"got {name!r}")
        return self.names.index(name)

    def combinations(self):
        """The identifiable combinations with their estimates and standard errors.

        Returns
        -------
        list of (str, float, float)
            ``(label, value, standard error)``, one per row of ``identifiable_rows``.
        """
        values = self.identifiable_rows @ self.estimate
        w = self.identifiable_rows * (self.sigma / self.column_scales)
        var = np.einsum("ij,jk,ik->i", w, self.scaled_unit_covariance, w)
        return [(label, float(v), float(np.sqrt(max(s, 0.0))))
                for label, v, s in zip(self.identifiable, values, var, strict=True)]

    def summary(self, *, scale=1.0, unit=""):
        """A text table of the estimates, their standard errors and the held parameters.

        Parameters
        ----------
        scale : float or dict of str to float, optional
            Factor applied for printing (e.g. 1000 for metres to mm): one number for every
            parameter and for ``sigma``, or one per parameter name (``sigma`` unscaled).
        unit : str, optional
            Printed after the header.

        Examples
        --------
        >>> import numpy as np
        >>> fit = fit_linear(np.column_stack([np.ones(4), np.arange(4.0)]),
        ...                  [1.0, 2.1, 2.9, 4.0], names=["b", "m"])
        >>> print(fit.summary())
        parameter          estimate    std error
        b                      1.03       0.0794
        m                      0.98       0.0424
        rank 2 of 2, condition number 3.01, residual sigma 0.0949
        """
        if isinstance(scale, dict):
            unknown = [k for k in scale if k not in self.names]
            if unknown:
                raise ValueError(f"scale names unknown parameters {unknown}; parameters are "
                                 f"{', '.join(self.names)}")
            per_name = {k: check_scalar(v, f"scale[{k!r}]") for k, v in scale.items()}
            sigma_scale = 1.0
        else:
            sigma_scale = check_scalar(scale, "scale")
            per_name = dict.fromkeys(self.names, sigma_scale)
        if not isinstance(unit, str):
            raise ValueError(f"unit must be text, got {unit!r}")
        se = self.standard_errors
        lines = [f"{'parameter':12s} {'estimate':>14s} {'std error':>12s}  {unit}".rstrip()]
        for k, name in enumerate(self.names):
            f = per_name.get(name, 1.0)
            if self.estimated[k]:
                lines.append(f"{name:12s} {self.estimate[k] * f:14.6g} {se[k] * f:12.3g}")
            else:
                lines.append(f"{name:12s} {self.estimate[k] * f:14.6g} {'held':>12s}")
        lines.append(f"rank {self.rank} of {len(self.names)}, condition number "
                     f"{self.condition_number:.3g}, residual sigma "
                     f"{self.sigma * sigma_scale:.3g}")
        if self.unidentifiable:
            lines.append("not identifiable: " + ", ".join(self.unidentifiable))
        return "\n".join(lines)


# -- rank analysis shared by the linear and nonlinear problems --------------------------------


def _norm(v, axis=None):
    """Euclidean norm(s) of ``v`` without overflow or underflow: each vector is divided by
    its largest entry first (infinite if an entry is)."""
    big = np.max(np.abs(v), axis=axis, keepdims=True, initial=0.0)
    safe = np.where((big > 0.0) & (big < np.inf), big, 1.0)
    with np.errstate(over="ignore"):
        out = np.linalg.norm(v / safe, axis=axis, keepdims=True) * np.minimum(big, safe)
    out = np.where(big == np.inf, np.inf, out)
    return out.reshape(np.shape(out)[:0] if axis is None else np.delete(np.shape(out), axis))


def _column_scales(J, zero_tol):
    """Column norms of J and which columns have an effect.

    A column is without effect when its norm is at most ``zero_tol`` times the largest
    (its scale is then set to 1): ``zero_tol = 0`` for a regressor given by the caller,
    whose columns may be in any units (only a zero column has no effect); ``rank_tol`` for
    the identification Jacobian, whose columns share the chain's units and where a
    parameter without effect shows as rounding noise.
    """
    norms = _norm(J, axis=0)
    nonzero = norms > zero_tol * norms.max(initial=0.0)
    return np.where(nonzero, norms, 1.0), nonzero


def _select_columns(Js, nonzero, rank_tol):
    """Greedy, in parameter order: keep a column if it is not (numerically) a combination of
    the columns kept before it. Returns the kept indices."""
    basis = np.zeros((Js.shape[0], 0))
    kept = []
    for j in range(Js.shape[1]):
        if not nonzero[j]:
            continue
        c = Js[:, j]
        r = c - basis @ (basis.T @ c)
        r = r - basis @ (basis.T @ r)           # twice is enough (Kahan)
        norm = np.linalg.norm(r)
        if norm > rank_tol * max(1.0, np.linalg.norm(c)):
            basis = np.column_stack([basis, r / norm])
            kept.append(j)
    return np.array(kept, dtype=int)


def _rref(M, tol=1e-9):
    """Reduced row-echelon form of M (rows spanning a subspace), zero rows dropped.

    ``tol`` is absolute: M must be of order 1 (see :func:`_rref_in_units`)."""
    M = np.array(M, dtype=float)
    rows, cols = M.shape
    r = 0
    for c in range(cols):
        if r == rows:
            break
        p = r + int(np.argmax(np.abs(M[r:, c])))
        if abs(M[p, c]) <= tol:
            M[r:, c] = 0.0
            continue
        M[[r, p]] = M[[p, r]]
        M[r] /= M[r, c]
        others = np.arange(rows) != r
        M[others] -= np.outer(M[others, c], M[r])
        r += 1
    M = M[:r]
    M[np.abs(M) < tol] = 0.0
    return M


def _rref_in_units(M_scaled, factor):
    """The reduced row-echelon form of ``M_scaled * factor`` (columns multiplied by
    ``factor``), found in the scaled space where the entries are of order 1.

    If :math:`E_s` is the RREF of :math:`M_s`, then :math:`E_s F` is row-equivalent to
    :math:`M_s F` with zeros in the pivot columns but the pivots' own rows; dividing each row
    by its pivot's factor makes the pivots 1. So the tolerance of the elimination does not
    depend on the units of the parameters."""
    E = _rref(M_scaled)
    if E.size == 0:
        return np.zeros((0, M_scaled.shape[1]))
    pivots = np.argmax(E != 0.0, axis=1)
    with np.errstate(over="ignore"):
        return E * factor[None, :] / factor[pivots][:, None]


def _label(row, names):
    """A combination as text: ``[1, 0, -1] -> "a - c"``."""
    text = ""
    for coef, name in zip(row, names, strict=True):
        if coef == 0.0:
            continue
        magnitude = abs(coef)
        term = name if abs(magnitude - 1.0) < 1e-9 else f"{magnitude:.4g} {name}"
        if not text:
            text = term if coef > 0 else "-" + term
        else:
            text += (" + " if coef > 0 else " - ") + term
    return text


def _rank_analysis(J, names, free, rank_tol, zero_tol):
    """Singular values, kept columns, null space and named combinations of a regressor.

    ``free`` marks the parameters the caller lets vary; the others are fixed and do not take
    part; ``zero_tol`` is that of :func:`_column_scales`. Returns a dict."""
    scales, nonzero = _column_scales(J, zero_tol)
    Js = np.where(nonzero, J / scales, 0.0)
    Jf = Js[:, free]
    # the whole V (the null space) but only the thin U: a full U of 3m x 3m rows costs
    # 20 times the rest for m = 160 poses
    _, s, Vt = np.linalg.svd(Jf, full_matrices=Jf.shape[0] < Jf.shape[1])
    s_max = s[0] if s.size and s[0] > 0 else 1.0
    rank = int(np.count_nonzero(s > rank_tol * s_max))
    free_idx = np.flatnonzero(free)
    kept_local = _select_columns(Jf, nonzero[free], rank_tol)
    kept = free_idx[kept_local]
    if kept.size != rank:       # the greedy choice and the SVD disagree: trust the smaller
        rank = min(rank, kept.size)
        kept = kept[:rank]
    p = J.shape[1]
    # null space and row space, scaled (J_s n_s = 0, rows r_s of J_s), as (p,) vectors
    null_scaled = np.zeros((p, Vt.shape[0] - rank))
    null_scaled[free_idx] = Vt[rank:].T
    rows_scaled = np.zeros((rank, p))
    rows_scaled[:, free_idx] = Vt[:rank]
    # in parameter units: n = D^-1 n_s (unit columns), r = r_s D
    with np.errstate(under="ignore"):
        null = null_scaled / scales[:, None]
    null = null / np.where(_norm(null, axis=0) > 0.0, _norm(null, axis=0), 1.0)
    identifiable_rows = _rref_in_units(rows_scaled, scales)
    unidentifiable_rows = _rref_in_units(null_scaled.T, 1.0 / scales)
    full_s = np.zeros(p)
    full_s[: s.size] = s
    return {
        "scales": scales, "singular_values": full_s, "rank": rank, "kept": kept,
        "null_space": null,
        "identifiable_rows": identifiable_rows,
        "identifiable": tuple(_label(r, names) for r in identifiable_rows),
        "unidentifiable": tuple(_label(r, names) for r in unidentifiable_rows),
    }


def _kept_condition(J, kept, scales):
    if kept.size == 0:
        return math.inf
    s = np.linalg.svd(J[:, kept] / scales[kept], compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else math.inf


def _scaled_unit_covariance(J, kept, scales, p):
    """:math:`(J_{s,K}^T J_{s,K})^{-1}` of the kept scaled columns, embedded in (p, p)."""
    Js = J[:, kept] / scales[kept]
    _, s, Vt = np.linalg.svd(Js, full_matrices=False)
    cov = np.zeros((p, p))
    cov[np.ix_(kept, kept)] = (Vt.T / s**2) @ Vt
    return cov


def _sigma(residuals, dof):
    r""":math:`\hat\sigma = \lVert r \rVert / \sqrt{k - r}`."""
    return float(_norm(residuals) / math.sqrt(dof))


def _check_rank_tol(rank_tol, max_condition):
    rank_tol = check_tolerance(rank_tol, "rank_tol")
    if not rank_tol < 1.0:
        raise ValueError(f"rank_tol must be a relative threshold in [0, 1), got {rank_tol!r}")
    return rank_tol, check_tolerance(max_condition, "max_condition")


def _finite_result(estimate, sigma):
    if not (np.isfinite(estimate).all() and math.isfinite(sigma)):
        raise ValueError("the identification overflows: the measurements or the regressor "
                         "are too large for the estimate or its residuals to be represented")


def _check_names(names, p):
    if names is None:
        return tuple(f"x{k}" for k in range(p))
    if isinstance(names, (str, bytes)) or not hasattr(names, "__iter__"):
        raise ValueError(f"names must be a sequence of {p} strings, got {names!r}")
    names = tuple(str(n) for n in names)
    if len(names) != p:
        raise ValueError(f"names must have one entry per column of A ({p}), got {len(names)}")
    if len(set(names)) != p:
        raise ValueError(f"names must be distinct, got {names}")
    return names


def _check_equations(k, p):
    """Before the rank analysis: at least as many equations as unknowns."""
    if k < p:
        raise ValueError(f"too few measurements: {k} equations for {p} unknowns "
                         f"(at least {p} needed; add poses)")


def _check_enough(k, r, what):
    """After the rank analysis: more equations than estimated parameters, to estimate the
    noise from the residuals."""
    if k <= r:
        raise ValueError(
            f"too few measurements: {k} equations for {r} identifiable unknowns; {what} "
            f"needs more equations than unknowns (at least {r + 1}) to estimate them and "
            "the noise")


def _warn_condition(cond, max_condition):
    if cond > max_condition:
        warnings.warn(
            f"ill-conditioned identification: condition number {cond:.3g} of the scaled "
            f"regressor exceeds {max_condition:.3g}; the estimate is poorly determined by "
            "these measurements (add poses that excite the parameters differently)",
            IllConditionedWarning, stacklevel=4)


def _identification(names, estimate, J, kept, scales, residuals, info, max_condition, **more):
    r"""The result of a fit, linear or not: :math:`\hat\sigma` from the residuals (with
    :math:`k - r` degrees of freedom, :math:`k` the rows of the regressor or Jacobian ``J``),
    the estimate checked finite, the condition number of the kept columns scaled by
    ``scales`` (a warning above ``max_condition``) and their covariance, and the rank
    analysis ``info``; ``more``: the iterations, convergence and robot of a calibration."""
    p = estimate.size
    sigma = _sigma(residuals, J.shape[0] - kept.size)
    _finite_result(estimate, sigma)
    cond = _kept_condition(J, kept, scales)
    _warn_condition(cond, max_condition)
    estimated = np.zeros(p, dtype=bool)
    estimated[kept] = True
    return Identification(
        names=names, estimate=estimate, estimated=estimated,
        scaled_unit_covariance=_scaled_unit_covariance(J, kept, scales, p),
        column_scales=scales, sigma=sigma,
        residuals=residuals, singular_values=info["singular_values"], rank=int(kept.size),
        condition_number=cond, null_space=info["null_space"],
        unidentifiable=info["unidentifiable"], identifiable_rows=info["identifiable_rows"],
        identifiable=info["identifiable"], **more)


# -- the linear problem -------------------------------------------------------------------------


def fit_linear(A, b, *, names=None, reference=None, rank_tol=1e-8, max_condition=1e6):
    r"""Linear least squares :math:`\min_\ell \lVert A\ell - b\rVert` with a rank report.

    The columns of :math:`A` are scaled to unit norm, :math:`A_s = A D^{-1}`, and the
    singular values of :math:`A_s` give the number :math:`r` of identifiable combinations.
    The columns are then taken in order and a column is kept when it is not a combination
    of the columns kept before it; the others are *held* at ``reference``. The kept
    parameters are estimated with ``numpy.linalg.lstsq``, and

    .. math::

       \hat\sigma^2 = \frac{\lVert b - A\hat\ell\rVert^2}{k - r},\qquad
       \operatorname{cov}(\hat\ell_K) = \hat\sigma^2\,(A_K^\mathsf{T} A_K)^{-1},\qquad
       \kappa = \frac{s_{\max}(A_{s,K})}{s_{\min}(A_{s,K})} .

    Parameters
    ----------
    A : array_like, shape (k, p)
        Regressor: one row per scalar measurement equation.
    b : array_like, shape (k,)
        Measurements.
    names : sequence of str, optional
        Parameter names (``x0, x1, ...`` by default).
    reference : array_like, shape (p,), optional
        Values of the held parameters (zeros by default).
    rank_tol : float, optional
        Relative threshold on the singular values (and on the part of a column not explained
        by the kept ones).
    max_condition : float, optional
        Above this condition number an :class:`IllConditionedWarning` is issued.

    Returns
    -------
    Identification

    Raises
    ------
    ValueError
        On mismatched shapes, NaN or infinity, or too few equations (fewer than the
        unknowns, or no more than the identifiable combinations).

    Warns
    -----
    IllConditionedWarning
        When the condition number exceeds ``max_condition``.

    Examples
    --------
    A line through noisy points; the third column duplicates the first, so only their sum is
    identifiable:

    >>> import numpy as np
    >>> t = np.arange(5.0)
    >>> A = np.column_stack([np.ones(5), t, np.ones(5)])
    >>> fit = fit_linear(A, 2.0 + 0.5 * t, names=["c", "m", "c2"])
    >>> fit.estimate.round(12) + 0.0, fit.rank
    (array([2. , 0.5, 0. ]), 2)
    >>> fit.unidentifiable, fit.identifiable
    (('c - c2',), ('c + c2', 'm'))
    """
    A = as_float_array(A, "A")
    if A.ndim != 2:
        raise ValueError(f"A must have shape (k, p), got shape {A.shape}")
    k, p = A.shape
    b = as_float_array(b, "b")
    if b.shape != (k,):
        raise ValueError(f"b must have shape ({k},) to match A of shape {A.shape}, "
                         f"got shape {b.shape}")
    names = _check_names(names, p)
    x0 = np.zeros(p) if reference is None else as_float_array(reference, "reference")
    if x0.shape != (p,):
        raise ValueError(f"reference must have shape ({p},), got shape {x0.shape}")
    rank_tol, max_condition = _check_rank_tol(rank_tol, max_condition)
    if k == 0 or p == 0:
        raise ValueError(f"A must have at least one row and one column, got shape {A.shape}")
    _check_equations(k, p)
    info = _rank_analysis(A, names, np.ones(p, dtype=bool), rank_tol, zero_tol=0.0)
    kept, scales = info["kept"], info["scales"]
    _check_enough(k, kept.size, "a least-squares fit")
    estimated = np.zeros(p, dtype=bool)
    estimated[kept] = True
    with np.errstate(over="ignore", invalid="ignore"):
        rhs = b - A[:, ~estimated] @ x0[~estimated]
        solution, *_ = np.linalg.lstsq(A[:, kept] / scales[kept], rhs, rcond=None)
        estimate = x0.copy()
        estimate[kept] = solution / scales[kept]
        residuals = b - A @ estimate
    return _identification(names, estimate, A, kept, scales, residuals, info, max_condition)


def desk_arm_regressor(q_lab):
    r"""The desktop arm's tool position as a linear function of its five lengths.

    With the lab's angles :math:`(q_0, q_1, q_2)` (base angle from the y axis, upper arm
    above the horizontal, forearm *below* the horizontal), the lab's forward model is linear
    in :math:`\ell = (l_0, l_1, l_2, l_3, l_4)`:

    .. math::

       \begin{pmatrix} x \\ y \\ z \end{pmatrix} =
       \begin{pmatrix}
       0 & \sin q_0\cos q_1 & \sin q_0\cos q_2 & \sin q_0 & 0\\
       0 & \cos q_0\cos q_1 & \cos q_0\cos q_2 & \cos q_0 & 0\\
       1 & \sin q_1 & -\sin q_2 & 0 & -1
       \end{pmatrix} \ell .

    The columns of :math:`l_0` and :math:`l_4` are opposite for every pose, so only
    :math:`l_0 - l_4` can be identified.

    Parameters
    ----------
    q_lab : array_like, shape (..., 3)
        The lab's angles in radians.

    Returns
    -------
    ndarray, shape (..., 3, 5)

    Examples
    --------
    >>> import numpy as np
    >>> A = desk_arm_regressor(np.radians([90, 90, 0]))
    >>> A.round(12) + 0.0
    array([[ 0.,  0.,  1.,  1.,  0.],
           [ 0.,  0.,  0.,  0.,  0.],
           [ 1.,  1.,  0.,  0., -1.]])
    >>> (A @ [0.035, 0.144, 0.162, 0.067, 0.0] * 1000).round(6) + 0.0
    array([229.,   0., 179.])
    """
    q = as_float_array(q_lab, "q_lab", (3,))
    s0, c0 = np.sin(q[..., 0]), np.cos(q[..., 0])
    s1, c1 = np.sin(q[..., 1]), np.cos(q[..., 1])
    s2, c2 = np.sin(q[..., 2]), np.cos(q[..., 2])
    zero, one = np.zeros_like(s0), np.ones_like(s0)
    rows = [
        [zero, s0 * c1, s0 * c2, s0, zero],
        [zero, c0 * c1, c0 * c2, c0, zero],
        [one, s1, -s2, zero, -one],
    ]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def identify_desk_arm(q_lab, positions, *, rank_tol=1e-8, max_condition=1e6):
    r"""Identify the desktop arm's lengths from measured angles and tool positions.

    Stacks :func:`desk_arm_regressor` over the poses and calls :func:`fit_linear` with the
    names ``l0 ... l4``. The fit reports that :math:`l_0 + l_4` is not identifiable, holds
    :math:`l_4` at 0 and estimates :math:`l_0 - l_4, l_1, l_2, l_3`.

    Parameters
    ----------
    q_lab : array_like, shape (m, 3)
        The lab's angles of the m poses, radians.
    positions : array_like, shape (m, 3)
        Measured tool positions, metres.
    rank_tol, max_condition : float, optional
        See :func:`fit_linear`.

    Returns
    -------
    Identification

    Raises
    ------
    ValueError
        On mismatched shapes, NaN, or too few poses.

    Examples
    --------
    The lab's verification table (answer 7) in metres, fitted back:

    >>> import numpy as np
    >>> q = np.radians([[90, 90, 0], [90, 51, 65], [90, 42, 21], [90, 90, 45]])
    >>> p = np.array([[229, 0, 179], [226, 0, 0], [325, 0, 73], [182, 0, 64]]) / 1000
    >>> fit = identify_desk_arm(q, p)
    >>> fit.unidentifiable, fit.held
    (('l0 + l4',), ('l4',))
    >>> [(label, round(value * 1000)) for label, value, _ in fit.combinations()]
    [('l0 - l4', 35), ('l1', 144), ('l2', 162), ('l3', 67)]
    """
    q = as_float_array(q_lab, "q_lab", (3,))
    p = as_float_array(positions, "positions", (3,))
    if q.ndim != 2:
        raise ValueError(f"q_lab must have shape (m, 3), got shape {q.shape}")
    if p.shape != q.shape:
        raise ValueError(f"positions must have shape {q.shape} (one per pose of q_lab), "
                         f"got shape {p.shape}")
    A = desk_arm_regressor(q).reshape(-1, 5)
    return fit_linear(A, p.reshape(-1), names=DESK_ARM_PARAMETERS, rank_tol=rank_tol,
                      max_condition=max_condition)


# -- the nonlinear problem: DH parameters of a chain -------------------------------------------

_KINDS = ("theta", "d", "a", "alpha")


def dh_parameter_names(robot):
    r"""Names of a chain's geometric parameters, four per link in the DH table's order.

    ``theta{i}`` is the constant :math:`\theta^0_i` of link i (the joint-angle offset of a
    revolute joint; the constant angle of a prismatic one), ``d{i}`` its offset along the
    joint axis (the constant added to a prismatic joint's variable), ``a{i}`` and
    ``alpha{i}`` its length and twist, as stored in :class:`~dqlab.robot.Link` (for modified
    DH these are :math:`a_{i-1}, \alpha_{i-1}`).

    Examples
    --------
    >>> from dqlab.models import desk_arm
    >>> dh_parameter_names(desk_arm())[:5]
    ('theta1', 'd1', 'a1', 'alpha1', 'theta2')
    """
    check_instance(robot, Robot, "robot")
    return tuple(f"{kind}{i}" for i in range(1, robot.n + 1) for kind in _KINDS)


def dh_parameters(robot):
    """A chain's geometric parameters as one vector, in the order of :func:`dh_parameter_names`.

    Returns
    -------
    ndarray, shape (4 n,)

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> dh_parameters(ur3())[:4]
    array([0.        , 0.1519    , 0.        , 1.57079633])
    """
    check_instance(robot, Robot, "robot")
    return np.array([[lk.theta_offset, lk.d, lk.a, lk.alpha] for lk in robot.links]).ravel()


def robot_from_dh_parameters(robot, parameters):
    """A copy of ``robot`` (same joints, limits, base, tool) with other DH parameters.

    Parameters
    ----------
    robot : Robot
    parameters : array_like, shape (4 n,)
        In the order of :func:`dh_parameter_names`.

    Returns
    -------
    Robot

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> nominal = ur3()
    >>> params = dh_parameters(nominal)
    >>> params[1] += 0.001                       # d1 one millimetre longer
    >>> longer = robot_from_dh_parameters(nominal, params)
    >>> round(float(longer.fk([0] * 6)[2, 3] - nominal.fk([0] * 6)[2, 3]), 12)
    0.001
    """
    check_instance(robot, Robot, "robot")
    x = as_float_array(parameters, "parameters", (4 * robot.n,))
    if x.ndim != 1:
        raise ValueError(f"parameters must have shape ({4 * robot.n},), got shape {x.shape}")
    rows = x.reshape(robot.n, 4)
    links = [Link(a=a, alpha=alpha, d=d, theta_offset=theta, joint=lk.joint,
                  limits=lk.limits, name=lk.name)
             for lk, (theta, d, a, alpha) in zip(robot.links, rows, strict=True)]
    return Robot(links, convention=robot.convention, base=robot.base, tool=robot.tool,
                 name=robot.name)


def _check_measure(measure):
    if not isinstance(measure, str) or measure not in ("position", "pose"):
        raise ValueError(f"measure must be 'position' or 'pose', got {measure!r}")


def identification_jacobian(robot, q, *, measure="position"):
    r"""Derivative of the TCP position (and orientation) with respect to the DH parameters.

    A small change of one parameter moves everything beyond it by an elementary motion of
    a frame of the chain, so each column is a point velocity (the same construction as the
    geometric Jacobian). For standard DH, link :math:`i` is
    :math:`R_z(\theta_i) T_z(d_i) T_x(a_i) R_x(\alpha_i)`: :math:`\theta_i` and :math:`d_i`
    turn about and slide along :math:`z_{i-1}` through :math:`o_{i-1}`, :math:`a_i` and
    :math:`\alpha_i` slide along and turn about :math:`x_i` through :math:`o_i`:

    .. math::

       \frac{\partial p}{\partial\theta_i} = z_{i-1}\times(p - o_{i-1}),\quad
       \frac{\partial p}{\partial d_i} = z_{i-1},\quad
       \frac{\partial p}{\partial a_i} = x_i,\quad
       \frac{\partial p}{\partial\alpha_i} = x_i\times(p - o_i),

    and the orientation rows are :math:`z_{i-1}, 0, 0, x_i`. For modified DH
    (:math:`R_x(\alpha_{i-1}) T_x(a_{i-1}) R_z(\theta_i) T_z(r_i)`) the roles are taken by
    :math:`x_{i-1}, o_{i-1}` for ``alpha`` and ``a`` and :math:`z_i, o_i` for ``theta``
    and ``d``. All vectors are in the world frame; :math:`p` is the TCP.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (..., n)
        Joint vectors.
    measure : {"position", "pose"}, optional
        ``"pose"`` appends the three rows of the orientation (a small rotation vector in the
        world frame).

    Returns
    -------
    ndarray, shape (..., 3, 4 n) or (..., 6, 4 n)
        Columns in the order of :func:`dh_parameter_names`.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> J = identification_jacobian(ur3(), np.zeros(6))
    >>> J.shape
    (3, 24)
    >>> J[:, 1]                                  # d1 lifts the whole arm
    array([0., 0., 1.])
    """
    check_instance(robot, Robot, "robot")
    _check_measure(measure)
    q = robot.check_joints(q)
    frames = robot.fk(q, all_frames=True)                   # (..., n + 1, 4, 4), last = TCP
    p = frames[..., -1, :3, 3]                               # TCP
    flange = frames[..., -1, :, :] @ np.linalg.inv(robot.tool)
    F = np.concatenate([frames[..., :-1, :, :], flange[..., None, :, :]], axis=-3)
    o, x, z = F[..., :3, 3], F[..., :3, 0], F[..., :3, 2]    # (..., n + 1, 3)
    if robot.convention == "dh":
        z_axis, z_point = z[..., :-1, :], o[..., :-1, :]     # z_{i-1} through o_{i-1}
        x_axis, x_point = x[..., 1:, :], o[..., 1:, :]       # x_i through o_i
    else:
        z_axis, z_point = z[..., 1:, :], o[..., 1:, :]       # z_i through o_i
        x_axis, x_point = x[..., :-1, :], o[..., :-1, :]     # x_{i-1} through o_{i-1}
    pp = p[..., None, :]
    linear = np.stack([np.cross(z_axis, pp - z_point), z_axis, x_axis,
                       np.cross(x_axis, pp - x_point)], axis=-2)   # (..., n, 4, 3)
    columns = [linear]
    if measure == "pose":
        zero = np.zeros_like(z_axis)
        columns.append(np.stack([z_axis, zero, zero, x_axis], axis=-2))
    J = np.concatenate(columns, axis=-1)                    # (..., n, 4, rows)
    lead = J.shape[:-3]
    return np.swapaxes(J.reshape(lead + (4 * robot.n, J.shape[-1])), -1, -2)


def _levenberg_marquardt_step(H, g, lam):
    r"""The scaled step :math:`\delta` of
    :math:`(H + \lambda \operatorname{diag} H)\,\delta = g` (least squares if singular)."""
    A = H + lam * np.diag(np.diag(H))
    try:
        return np.linalg.solve(A, g)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(A, g, rcond=None)[0]


def _residuals(robot, q, measured, measure, rotation_scale):
    X = robot.fk(q)
    dp = measured[..., :3, 3] - X[..., :3, 3] if measure == "pose" else measured - X[..., :3, 3]
    if measure == "position":
        return dp.reshape(-1)
    R = measured[..., :3, :3] @ np.swapaxes(X[..., :3, :3], -1, -2)
    dr = stack_components(rotation_vector_from_matrix_entries(*components(R.reshape(-1, 9))))
    return np.concatenate([dp.reshape(-1, 3), rotation_scale * dr], axis=-1).reshape(-1)


def _stacked_jacobian(robot, q, measure, rotation_scale):
    J = identification_jacobian(robot, q, measure=measure)
    if measure == "pose":
        J = J.copy()
        J[..., 3:, :] *= rotation_scale
    return J.reshape(-1, J.shape[-1])


def identify_dh_parameters(robot, q, measured, *, measure="position", fixed=(),
                           rotation_scale=0.1, rank_tol=1e-8, max_condition=1e6, tol=1e-12,
                           max_iter=100):
    r"""Kinematic calibration: the DH parameters that best explain measured TCP positions.

    Minimises :math:`\tfrac12\lVert r(\pi)\rVert^2`, the residuals
    :math:`r = p_{\text{measured}} - p(q; \pi)` stacked over the poses, over the parameters
    :math:`\pi` of :func:`dh_parameter_names`, starting from ``robot``'s (the nominal
    model). First the identification Jacobian at the nominal parameters is scaled to unit
    columns and its singular values counted: the parameters that the poses cannot separate
    are reported by name and held at their nominal values (see :func:`fit_linear`). The
    others are found by Levenberg--Marquardt steps,

    .. math::

       \bigl(J^\mathsf{T}J + \lambda\,\operatorname{diag}(J^\mathsf{T}J)\bigr)\,\delta
       = J^\mathsf{T} r, \qquad \pi \leftarrow \pi + \delta,

    with :math:`\lambda` divided by 10 after a step that lowers the cost and multiplied by
    10 (step rejected) otherwise; :math:`\lambda \to 0` is Gauss--Newton. The iteration stops
    when the scaled step :math:`\lVert D\delta\rVert` falls below ``tol`` (:math:`D` the
    column norms of :math:`J`).

    Parameters
    ----------
    robot : Robot
        The nominal model. Its base and tool are taken as known.
    q : array_like, shape (m, n)
        Joint vectors of the m measured poses.
    measured : array_like, shape (m, 3) or (m, 4, 4)
        Measured TCP positions (``measure="position"``) or poses (``"pose"``) in the world
        frame, metres.
    measure : {"position", "pose"}, optional
    fixed : str or sequence of str, optional
        Parameter names to hold at their nominal values (known by construction).
    rotation_scale : float, optional
        Metres per radian: weight of the orientation residuals for ``measure="pose"``.
    rank_tol, max_condition : float, optional
        See :func:`fit_linear`.
    tol : float, optional
        Convergence threshold on the scaled step.
    max_iter : int, optional

    Returns
    -------
    Identification
        With ``robot`` the calibrated chain. The residuals, ``sigma`` and covariance are
        evaluated at the estimate.

    Raises
    ------
    ValueError
        On mismatched shapes, NaN, measured poses that are not rigid transforms, unknown
        names in ``fixed``, or too few measurements (fewer equations than free
        parameters, or no more than the identifiable ones).

    Warns
    -----
    IllConditionedWarning
        When the estimated parameters are ill-conditioned, or when the iteration does not
        converge in ``max_iter`` steps.

    Examples
    --------
    A UR3 whose upper arm is 1 mm longer than its data sheet says, measured at 12 poses:

    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> nominal = ur3()
    >>> params = dh_parameters(nominal)
    >>> params[dh_parameter_names(nominal).index("a2")] -= 0.001    # a2 is negative
    >>> real = robot_from_dh_parameters(nominal, params)
    >>> q = np.random.default_rng(0).uniform(-np.pi, np.pi, size=(12, 6))
    >>> fit = identify_dh_parameters(nominal, q, real.fk(q)[:, :3, 3])
    >>> round(fit.value("a2"), 9), fit.rank
    (-0.24465, 18)
    >>> fit.unidentifiable
    ('d2 - d4', 'd3 - d4', 'theta5 + 0.0819 a5', 'd5 - 12.21 alpha5', 'theta6', 'alpha6')
    """
    check_instance(robot, Robot, "robot")
    _check_measure(measure)
    q = robot.check_joints(q)
    if q.ndim != 2:
        raise ValueError(f"q must have shape (m, {robot.n}), got shape {q.shape}")
    m = q.shape[0]
    if measure == "position":
        measured = as_float_array(measured, "measured", (3,))
        if measured.shape != (m, 3):
            raise ValueError(f"measured positions must have shape ({m}, 3) to match q, "
                             f"got shape {measured.shape}")
    else:
        measured = as_float_array(measured, "measured", (4, 4))
        if measured.shape != (m, 4, 4):
            raise ValueError(f"measured poses must have shape ({m}, 4, 4) to match q, "
                             f"got shape {measured.shape}")
        measured = check_transform(measured, tol=1e-6, name="measured")
    rotation_scale = check_scalar(rotation_scale, "rotation_scale", minimum=0, strict=True)
    rank_tol, max_condition = _check_rank_tol(rank_tol, max_condition)
    tol = check_scalar(tol, "tol", minimum=0)     # finite: inf would stop at the first step
    max_iter = check_scalar(max_iter, "max_iter", minimum=1, integer=True)
    if fixed is None:
        fixed = ()
    if isinstance(fixed, str):
        fixed = (fixed,)
    if not hasattr(fixed, "__iter__"):
        raise ValueError(f"fixed must be a parameter name or a sequence of them, got "
                         f"{fixed!r}")
    names = dh_parameter_names(robot)
    unknown = [f for f in fixed if f not in names]
    if unknown:
        raise ValueError(f"fixed names unknown parameters {unknown}; parameters are "
                         f"{', '.join(names)}")
    free = np.array([n not in fixed for n in names])
    x = dh_parameters(robot)
    J = _stacked_jacobian(robot, q, measure, rotation_scale)
    _check_equations(J.shape[0], int(free.sum()))
    info = _rank_analysis(J, names, free, rank_tol, zero_tol=rank_tol)
    kept = info["kept"]
    _check_enough(J.shape[0], kept.size, "the calibration")

    current = robot
    r = _residuals(current, q, measured, measure, rotation_scale)
    cost = _norm(r)                    # the cost is 0.5 cost**2; the norm does not overflow
    if not math.isfinite(cost):
        raise ValueError("measured: the residuals overflow (the measurements are too large "
                         "for the model)")
    lam = 1e-3
    converged = False
    iterations = 0
    while iterations < max_iter:
        iterations += 1
        Jk = _stacked_jacobian(current, q, measure, rotation_scale)[:, kept]
        D = _norm(Jk, axis=0)
        D = np.where(D > 0.0, D, 1.0)
        Js = Jk / D                                  # unit columns: a well-scaled system
        g = Js.T @ r
        H = Js.T @ Js
        while True:
            step_s = _levenberg_marquardt_step(H, g, lam)
            trial_x = x.copy()
            with np.errstate(over="ignore"):
                trial_x[kept] += step_s / D
            cost_trial, trial, r_trial = math.inf, None, None
            if np.isfinite(trial_x).all():
                trial = robot_from_dh_parameters(robot, trial_x)
                with np.errstate(over="ignore", invalid="ignore"):
                    r_trial = _residuals(trial, q, measured, measure, rotation_scale)
                if np.isfinite(r_trial).all():
                    cost_trial = _norm(r_trial)
            if cost_trial <= cost or lam > 1e12:
                break
            lam *= 10.0
        with np.errstate(over="ignore"):
            small_step = _norm(step_s) <= tol * (1.0 + _norm(x[kept] * D))
        if cost_trial <= cost:
            x, current, r, cost = trial_x, trial, r_trial, cost_trial
            lam = max(lam / 10.0, 1e-12)
        if small_step:
            converged = True
            break
    if not converged:
        warnings.warn(f"calibration did not converge in {max_iter} iterations",
                      IllConditionedWarning, stacklevel=2)
    J_final = _stacked_jacobian(current, q, measure, rotation_scale)
    scales_final, _ = _column_scales(J_final, rank_tol)
    return _identification(names, x, J_final, kept, scales_final, r, info, max_condition,
                           iterations=iterations, converged=converged, robot=current)
