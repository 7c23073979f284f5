r"""Identifying an arm's dynamics: what its joint torques can tell about its masses (chapter 16).

The joint torques of an arm driven by geared motors are linear in its parameters,

.. math::

   \tau = Y(q, \dot q, \ddot q)\,\pi + \operatorname{diag}(\ddot q)\,a
   + \operatorname{diag}(\dot q)\,f_v + \operatorname{diag}(\operatorname{sign}\dot q)\,f_c
   = W(q, \dot q, \ddot q)\,\varphi ,

with the ten inertial parameters per link :math:`\pi` of
:func:`dqlab.dynamics.inertial_parameters` and its regressor :func:`dqlab.dynamics.regressor`,
and per joint the motor's reflected inertia (armature) :math:`a_i`, a viscous friction
:math:`f_{v,i}` and a dry (Coulomb) friction :math:`f_{c,i}`
(:func:`regressor_with_motors`, :func:`parameter_names`). Not every parameter changes the
torques: the *base parameters* (:func:`base_parameters`) are the combinations that do, found
by a QR factorisation with column pivoting of :math:`W` on random states (Gautier 1991); the
others are named as the combinations that change nothing, as chapter 12 names its own. An
*exciting trajectory* (:class:`FourierTrajectory`, :func:`exciting_trajectory`) makes the
base parameters' columns as independent as the joint limits allow (Swevers et al. 1997), and
an identified model (:class:`IdentifiedModel`) predicts the torques from the estimated base
parameters, for a computed-torque controller.

Units: radians, metres, seconds, kilograms, newtons; the parameters in kg, kg m, kg m^2,
N m s/rad and N m.
"""

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import dynamics
from ._checks import as_float_array, check_instance, check_scalar, check_tolerance
from .robot import Robot

__all__ = ["parameter_names", "preferred_order", "motor_regressor", "regressor_with_motors",
           "BaseParameters", "base_parameters", "FourierTrajectory", "exciting_trajectory",
           "IdentifiedModel", "MOTOR_PARAMETER_NAMES", "KHALIL_ORDER", "MARGIN", "GRID"]

#: The order in which :func:`preferred_order` prefers a link's parameters as base
#: parameters: the inertia's entries, the first moments, the mass.
KHALIL_ORDER = ("Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz", "mx", "my", "mz", "m")

#: The three parameters of a joint's motor and gear, in the order of
#: :func:`motor_regressor`'s columns: armature (reflected inertia), viscous and dry friction.
MOTOR_PARAMETER_NAMES = ("Ia", "Fv", "Fc")


def parameter_names(robot: Robot, *, motors: bool = True) -> tuple[str, ...]:
    """The names of the parameters :math:`\\varphi`, in the order of
    :func:`regressor_with_motors`'s columns (of :func:`dqlab.dynamics.regressor`'s alone for
    ``motors=False``): ``m1, mx1, my1, mz1, Ixx1, Ixy1, Iyy1, Ixz1, Iyz1, Izz1, m2, ...``, then
    ``Ia1, Fv1, Fc1, Ia2, ...``.

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> names = parameter_names(ur3())
    >>> len(names), names[:4], names[60:63]
    (78, ('m1', 'mx1', 'my1', 'mz1'), ('Ia1', 'Fv1', 'Fc1'))
    """
    check_instance(robot, Robot, "robot")
    names = [f"{p}{i}" for i in range(1, robot.n + 1) for p in dynamics.PARAMETER_NAMES]
    if motors:
        names += [f"{p}{i}" for i in range(1, robot.n + 1) for p in MOTOR_PARAMETER_NAMES]
    return tuple(names)


def preferred_order(robot: Robot) -> tuple[str, ...]:
    """:func:`parameter_names` in the order that Khalil and Dombre's base parameters prefer:
    link by link from the base, each link's inertia entries, first moments and mass
    (:data:`KHALIL_ORDER`), then the motors'. Give it to :func:`base_parameters` as
    ``prefer``.

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> preferred_order(ur3())[:11]
    ('Ixx1', 'Ixy1', 'Iyy1', 'Ixz1', 'Iyz1', 'Izz1', 'mx1', 'my1', 'mz1', 'm1', 'Ixx2')
    """
    check_instance(robot, Robot, "robot")
    return (tuple(f"{p}{i}" for i in range(1, robot.n + 1) for p in KHALIL_ORDER)
            + parameter_names(robot)[10 * robot.n:])


def motor_regressor(qd: ArrayLike, qdd: ArrayLike, *, zero_speed: float = 0.0
                    ) -> NDArray[np.float64]:
    r"""The motors' columns of the regressor, shape (..., n, 3 n): per joint :math:`i`, the
    columns of :math:`a_i` (:math:`\ddot q_i`), :math:`f_{v,i}` (:math:`\dot q_i`) and
    :math:`f_{c,i}` (:math:`\operatorname{sign}\dot q_i`) in row :math:`i`, zero elsewhere.

    Parameters
    ----------
    qd, qdd : array_like, shape (..., n)
    zero_speed : float, optional
        Speeds of at most this magnitude count as zero for the sign (rad/s; 0 by default).

    Examples
    --------
    >>> motor_regressor([0.5, -2.0], [1.0, 0.0])
    array([[ 1. ,  0.5,  1. ,  0. ,  0. ,  0. ],
           [ 0. ,  0. ,  0. ,  0. , -2. , -1. ]])
    """
    qd = as_float_array(qd, "qd")
    qdd = as_float_array(qdd, "qdd")
    zero_speed = check_tolerance(zero_speed, "zero_speed")
    try:
        qd, qdd = np.broadcast_arrays(qd, qdd)
    except ValueError:
        raise ValueError(f"the shapes of qd and qdd do not broadcast: {qd.shape} and "
                         f"{qdd.shape}") from None
    if qd.ndim == 0 or qd.shape[-1] == 0:
        raise ValueError(f"qd and qdd must have shape (..., n), n > 0, got shape {qd.shape}")
    n = qd.shape[-1]
    sign = np.where(np.abs(qd) > zero_speed, np.sign(qd), 0.0)
    columns = np.stack([qdd, qd, sign], axis=-1)                     # (..., n, 3)
    out = np.zeros(qd.shape[:-1] + (n, 3 * n))
    for i in range(n):
        out[..., i, 3 * i:3 * i + 3] = columns[..., i, :]
    return out


def regressor_with_motors(robot: Robot, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, *,
                          gravity: ArrayLike = dynamics.GRAVITY, zero_speed: float = 0.0
                          ) -> NDArray[np.float64]:
    r""":math:`W = [\,Y \mid \text{motors}\,]`, shape (..., n, 13 n): the rigid bodies'
    regressor (:func:`dqlab.dynamics.regressor`) followed by :func:`motor_regressor`, so that
    :math:`\tau = W\varphi` with :math:`\varphi` in the order of :func:`parameter_names`.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab import dynamics
    >>> from dqlab.models import ur3
    >>> q, qd, qdd = np.zeros(6), np.full(6, 0.5), np.ones(6)
    >>> W = regressor_with_motors(ur3(), q, qd, qdd)
    >>> phi = np.concatenate([dynamics.inertial_parameters(ur3()), np.tile([0.1, 0.2, 0.3], 6)])
    >>> tau = dynamics.inverse_dynamics(ur3(), q, qd, qdd) + 0.1 * qdd + 0.2 * qd + 0.3
    >>> bool(np.allclose(W @ phi, tau))
    True
    """
    Y = dynamics.regressor(robot, q, qd, qdd, gravity=gravity)
    qd_b, qdd_b = np.broadcast_arrays(as_float_array(qd, "qd"), as_float_array(qdd, "qdd"))
    shape = Y.shape[:-2] + (robot.n,)
    motors = motor_regressor(np.broadcast_to(qd_b, shape), np.broadcast_to(qdd_b, shape),
                             zero_speed=zero_speed)
    return np.concatenate([Y, motors], axis=-1)


# --------------------------------------------------------------------------------------
# Base parameters

def _qr_with_pivoting(A):
    """R and the column order ``order`` of the Householder QR of ``A`` with column pivoting,
    ``A[:, order] = Q R``, the remaining column of largest norm taken first at every step
    (Golub and Van Loan, algorithm 5.4.1); Q is not formed. The diagonal of R then decreases
    in magnitude, and its small entries reveal the rank."""
    A = np.array(A, dtype=float)
    m, n = A.shape
    order = np.arange(n)
    for k in range(min(m, n)):
        norms = np.einsum("ij,ij->j", A[k:, k:], A[k:, k:])
        j = k + int(np.argmax(norms))
        A[:, [k, j]], order[[k, j]] = A[:, [j, k]], order[[j, k]]
        x = A[k:, k]
        size = math.sqrt(float(x @ x))
        if size == 0.0:
            break
        v = x.copy()
        v[0] += math.copysign(size, x[0])
        v /= math.sqrt(float(v @ v))
        A[k:, k:] -= 2.0 * np.outer(v, v @ A[k:, k:])
    return np.triu(A[:min(m, n)]), order


def _first_independent(W, rank):
    """The first ``rank`` columns of ``W``, in parameter order, each independent of those
    before it (Gram--Schmidt, twice, on the columns scaled to unit norm; a column below
    1e-10 of the largest has no effect); None if fewer are found."""
    norms = np.linalg.norm(W, axis=0)
    basis, kept = [], []
    for k in range(W.shape[1]):
        if norms[k] <= 1e-10 * norms.max():          # a column of rounding errors: no effect
            continue
        residual = W[:, k] / norms[k]
        for _ in range(2):
            for b in basis:
                residual = residual - (b @ residual) * b
        size = math.sqrt(float(residual @ residual))
        if size > 1e-6:
            basis.append(residual / size)
            kept.append(k)
            if len(kept) == rank:
                return np.array(kept)
    return None


def _coefficients(W_b, W_d):
    """K with W_d = W_b K, by the QR factorisation of W_b."""
    if W_d.shape[1] == 0:
        return np.zeros((W_b.shape[1], 0))
    Q, R = np.linalg.qr(W_b)
    return np.linalg.solve(R, Q.T @ W_d)


def _label(coefficients, names, tol=1e-9):
    """A combination as text, coefficients of 1 left out: ``[1, 0, -0.5] -> "a - 0.5 c"``."""
    text = ""
    for coefficient, name in zip(coefficients, names, strict=True):
        if abs(coefficient) <= tol:
            continue
        magnitude = abs(coefficient)
        term = name if abs(magnitude - 1.0) <= 1e-9 else f"{magnitude:.4g} {name}"
        if not text:
            text = term if coefficient > 0 else "-" + term
        else:
            text += (" + " if coefficient > 0 else " - ") + term
    return text or "0"


@dataclass(frozen=True, eq=False)
class BaseParameters:
    r"""The combinations of parameters that a regressor can identify.

    With the columns of :math:`W` split into independent ones :math:`W_b` and the others,
    :math:`W_d = W_b K`, the torques are :math:`W\varphi = W_b\,\beta` with the *base
    parameters* :math:`\beta = \varphi_b + K\varphi_d`.

    Attributes
    ----------
    names : tuple of str
        All the parameters' names (:func:`parameter_names`), length p.
    independent : ndarray of int, shape (r,)
        The columns of :math:`W_b`, in the order of the factorisation.
    dependent : ndarray of int, shape (p - r,)
        The other columns, in parameter order.
    K : ndarray, shape (r, p - r)
        :math:`W_d = W_b K`.
    labels : tuple of str
        Each base parameter as the combination it is, e.g. ``"Izz1 + Ia1 + Iyy2"``.
    unidentifiable : tuple of str
        One combination per dependent parameter that changes no torque: ``"Iyy2 - Izz1"``
        means that increasing ``Iyy2`` and decreasing ``Izz1`` by the same amount changes
        nothing; a single name, that the parameter has no effect at all.
    diagonal : ndarray, shape (p,)
        :math:`|R_{kk}|` of the factorisation, decreasing: the gap after the first r says how
        clearly the rank is decided.
    """

    names: tuple
    independent: np.ndarray
    dependent: np.ndarray
    K: np.ndarray
    labels: tuple
    unidentifiable: tuple
    diagonal: np.ndarray = field(repr=False)

    @property
    def rank(self) -> int:
        """The number of base parameters."""
        return int(self.independent.size)

    def values(self, parameters: ArrayLike) -> NDArray[np.float64]:
        r""":math:`\beta = \varphi_b + K\varphi_d` of full parameters :math:`\varphi`, shape
        (..., r)."""
        phi = as_float_array(parameters, "parameters", (len(self.names),))
        return phi[..., self.independent] + phi[..., self.dependent] @ self.K.T

    def columns(self, W: ArrayLike) -> NDArray[np.float64]:
        """:math:`W_b`: the independent columns of a regressor ``W`` (..., p)."""
        W = as_float_array(W, "W", (len(self.names),))
        return W[..., self.independent]


def base_parameters(W: ArrayLike, names, *, prefer=None, rank_tol: float = 1e-8
                    ) -> BaseParameters:
    r"""The base parameters of a regressor, by a QR factorisation with column pivoting.

    ``W`` stacks the regressor's rows on many random states, so that a column that depends
    on others there depends on them everywhere. With :math:`W P = QR` (columns taken largest
    first), the rank :math:`r` is the number of diagonal entries of :math:`R` above
    ``rank_tol`` times the first; with :math:`R = \left(\begin{smallmatrix} R_1 & R_2 \\ 0 &
    \approx 0\end{smallmatrix}\right)`, :math:`K = R_1^{-1}R_2` expresses the dependent columns
    in the independent ones (Gautier 1991; Khalil and Dombre). Entries of :math:`K` below
    :math:`10^{-9}` of the largest are set to zero (they are rounding).

    Parameters
    ----------
    W : array_like, shape (k, p)
        Stacked regressor rows, for instance of :func:`regressor_with_motors` on random states.
    names : sequence of str, length p
        The parameters' names (:func:`parameter_names`).
    prefer : sequence of str, optional
        The same names, most preferred first, for the base parameters' representatives
        (default: the order of ``names``; :func:`preferred_order` gives Khalil and Dombre's).
    rank_tol : float, optional

    Returns
    -------
    BaseParameters

    Examples
    --------
    Joint 1 of the UR3 turns about the vertical, which is link 1's :math:`y` axis: of link 1's
    ten parameters only ``Iyy1`` matters, and only together with the motor's ``Ia1`` and the
    next links' inertias.

    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> rng = np.random.default_rng(1)
    >>> states = rng.uniform(-3, 3, (3, 40, 6))
    >>> W = regressor_with_motors(ur3(), *states).reshape(-1, 78)
    >>> base = base_parameters(W, parameter_names(ur3()), prefer=preferred_order(ur3()))
    >>> base.rank
    52
    >>> "m1" in base.unidentifiable, "Ia1 - Iyy1" in base.unidentifiable
    (True, True)
    """
    W = as_float_array(W, "W")
    if W.ndim != 2 or W.shape[0] < W.shape[1] or W.shape[1] == 0:
        raise ValueError(f"W must stack at least as many rows as columns, shape (k, p) with "
                         f"k >= p > 0, got shape {W.shape}")
    names = tuple(names) if not isinstance(names, str) else ()
    if len(names) != W.shape[1] or not all(isinstance(x, str) for x in names):
        raise ValueError(f"names must hold one string per column of W ({W.shape[1]}), got "
                         f"{len(names)} entries")
    rank_tol = check_tolerance(rank_tol, "rank_tol")
    if not rank_tol < 1.0:
        raise ValueError(f"rank_tol must be a relative threshold in [0, 1), got {rank_tol!r}")
    largest = float(np.abs(W).max())
    if largest == 0.0:
        raise ValueError("W is all zeros: no parameter changes a torque")
    W = W / largest                     # one scale for all (K and the rank do not change)
    R, order = _qr_with_pivoting(W)
    diagonal = np.abs(np.diag(R))
    rank = int(np.count_nonzero(diagonal > rank_tol * diagonal[0])) if diagonal[0] > 0 else 0
    if prefer is None:
        ranking = np.arange(W.shape[1])
    else:
        prefer = tuple(prefer) if not isinstance(prefer, str) else ()
        if sorted(prefer) != sorted(names):
            raise ValueError("prefer must hold the same names as names, in another order")
        ranking = np.array([names.index(name) for name in prefer])
    chosen = _first_independent(W[:, ranking], rank)
    independent = (np.sort(order[:rank]) if chosen is None     # fewer found: the pivots' set
                   else ranking[chosen])
    dependent = np.setdiff1d(np.arange(W.shape[1]), independent)
    K = _coefficients(W[:, independent], W[:, dependent])
    K = np.where(np.abs(K) > 1e-9 * max(1.0, np.abs(K).max(initial=0.0)), K, 0.0)
    labels = tuple(_label(np.concatenate([[1.0], K[j]]),
                          (names[independent[j]],) + tuple(names[d] for d in dependent))
                   for j in range(rank))
    unidentifiable = tuple(_label(np.concatenate([[1.0], -K[:, k]]),
                                  (names[dependent[k]],) + tuple(names[b] for b in independent))
                           for k in range(dependent.size))
    return BaseParameters(names=names, independent=independent, dependent=dependent, K=K,
                          labels=labels, unidentifiable=unidentifiable,
                          diagonal=np.concatenate([diagonal, np.zeros(W.shape[1] -
                                                                      diagonal.size)]))


# --------------------------------------------------------------------------------------
# Exciting trajectories

@dataclass(frozen=True, eq=False)
class FourierTrajectory:
    r"""A periodic joint trajectory, a finite Fourier series per joint (Swevers et al. 1997):

    .. math::

       q_i(t) = q_{0,i} + \sum_{l=1}^{L}\frac{a_{il}}{\omega_f l}\sin(\omega_f l t)
       - \frac{b_{il}}{\omega_f l}\cos(\omega_f l t), \qquad \omega_f = 2\pi / T,

    so that :math:`\dot q_i = \sum_l a_{il}\cos(\omega_f l t) + b_{il}\sin(\omega_f l t)`. It
    repeats every period :math:`T`, its derivatives are exact, and its spectrum holds only the
    harmonics :math:`l\,\omega_f`: measurements can be averaged over periods and filtered
    without distorting it.

    Attributes
    ----------
    q0 : ndarray, shape (n,)
    a, b : ndarray, shape (n, L)
    period : float
        :math:`T`, s.
    """

    q0: np.ndarray
    a: np.ndarray
    b: np.ndarray
    period: float

    @property
    def n(self) -> int:
        return int(self.a.shape[0])

    def sample(self, t: ArrayLike) -> tuple[NDArray[np.float64], ...]:
        """``(q, qd, qdd)`` at the times ``t`` (..., ), each of shape (..., n).

        Examples
        --------
        >>> import numpy as np
        >>> f = FourierTrajectory(np.zeros(1), np.array([[1.0]]), np.zeros((1, 1)), 2 * np.pi)
        >>> [round(float(x[0]), 12) + 0.0 for x in f.sample(np.pi / 2)]     # q = sin t
        [1.0, 0.0, -1.0]
        """
        t = as_float_array(t, "t")
        w = 2.0 * np.pi / self.period * np.arange(1, self.a.shape[1] + 1)   # (L,)
        phase = t[..., None, None] * w                                       # (..., 1, L)
        s, c = np.sin(phase), np.cos(phase)
        q = self.q0 + np.sum((self.a * s - self.b * c) / w, axis=-1)
        qd = np.sum(self.a * c + self.b * s, axis=-1)
        qdd = np.sum((-self.a * s + self.b * c) * w, axis=-1)
        return q, qd, qdd

    def starting_at_rest(self) -> "FourierTrajectory":
        r"""The same series with :math:`\dot q(0) = \ddot q(0) = 0`: per joint the mean of the
        :math:`a_{il}` and the :math:`l`-weighted part of the :math:`b_{il}` removed (so that
        :math:`\sum_l a_{il} = \sum_l l\,b_{il} = 0`): a real arm can start it from rest."""
        l = np.arange(1, self.a.shape[1] + 1)
        a = self.a - self.a.mean(axis=1, keepdims=True)
        b = self.b - np.outer(self.b @ l, l) / (l @ l)
        return FourierTrajectory(self.q0, a, b, self.period)


#: The bounds of :func:`exciting_trajectory` are reached to this fraction on a grid of
#: :data:`GRID` instants per period: between the grid's instants a peak may rise by at most
#: about :math:`(\pi L / G)^2/2` of itself (L harmonics, G instants), 0.1 % for L = 10.
MARGIN, GRID = 0.99, 1000


def _within(a, b, period, centre, half_range, qd_max, qdd_max, grid):
    """The series of coefficients ``a, b`` started at rest at ``centre`` and scaled joint by
    joint until its tightest bound is just reached: the distance from ``centre`` (over one
    period), the speed or the acceleration."""
    raw = FourierTrajectory(centre, a, b, period).starting_at_rest()
    w = 2.0 * np.pi / period * np.arange(1, a.shape[1] + 1)
    q, qd, qdd = raw.sample(grid)
    away = q - raw.sample(0.0)[0]                     # the motion from where it starts
    scale = MARGIN * np.minimum.reduce([half_range / (np.abs(away).max(axis=0) + 1e-300),
                                        qd_max / (np.abs(qd).max(axis=0) + 1e-300),
                                        qdd_max / (np.abs(qdd).max(axis=0) + 1e-300)])
    a, b = raw.a * scale[:, None], raw.b * scale[:, None]
    return FourierTrajectory(centre + np.sum(b / w, axis=1), a, b, period)   # q(0) = centre


def _condition(W_b):
    """The condition number of ``W_b`` with its columns scaled to unit norm, from the
    eigenvalues of its Gram matrix (the squares of the singular values; exact enough for
    the condition numbers worth optimising, below about 1e7)."""
    norms = np.linalg.norm(W_b, axis=0)
    scaled = W_b / np.where(norms > 0, norms, 1.0)
    eigenvalues = np.linalg.eigvalsh(scaled.T @ scaled)
    return (float(math.sqrt(eigenvalues[-1] / eigenvalues[0])) if eigenvalues[0] > 0
            else math.inf)


def exciting_trajectory(robot: Robot, base: BaseParameters, *, centre: ArrayLike,
                        half_range: ArrayLike, qd_max: ArrayLike, qdd_max: ArrayLike,
                        harmonics: int = 5, period: float = 10.0, samples: int = 100,
                        iterations: int = 200, seed: int = 0
                        ) -> tuple[FourierTrajectory, NDArray[np.float64]]:
    r"""A :class:`FourierTrajectory` that excites the base parameters: the condition number of
    their regressor :math:`W_b` (columns scaled to unit norm), sampled at ``samples`` instants
    of a period, made small within the joint limits (Swevers et al. 1997).

    Every candidate starts at rest at ``centre`` (:meth:`FourierTrajectory.starting_at_rest`)
    and is scaled joint by joint until its tightest bound is reached (to :data:`MARGIN`): a
    distance ``half_range`` from ``centre``, a speed ``qd_max`` or an acceleration
    ``qdd_max``, on a grid of :data:`GRID` instants of the period; so every candidate is
    admissible; the box
    ``centre +- half_range`` must lie within the robot's joint limits. The search is a (1+1)
    evolution strategy on the coefficients with the one-fifth success rule for its step
    (Rechenberg): a random change is kept when it lowers the condition number. It is seeded,
    hence repeatable.

    Parameters
    ----------
    robot : Robot
    base : BaseParameters
        Of :func:`regressor_with_motors`'s columns for ``robot``.
    centre, half_range, qd_max, qdd_max : array_like, shape (n,)
        rad, rad, rad/s, rad/s^2.
    harmonics, samples, iterations, seed : int
    period : float
        s.

    Returns
    -------
    trajectory : FourierTrajectory
    history : ndarray, shape (iterations + 1,)
        The best condition number after each step.
    """
    check_instance(robot, Robot, "robot")
    check_instance(base, BaseParameters, "base")
    n = robot.n
    if len(base.names) != 13 * n:
        raise ValueError(f"base must be of regressor_with_motors' {13 * n} columns for this "
                         f"{n}-joint robot, got {len(base.names)}")
    bounds = [as_float_array(x, name, (n,)) for x, name in
              ((centre, "centre"), (half_range, "half_range"), (qd_max, "qd_max"),
               (qdd_max, "qdd_max"))]
    for x, name in zip(bounds[1:], ("half_range", "qd_max", "qdd_max"), strict=True):
        if x.shape != (n,) or not (x > 0).all():
            raise ValueError(f"{name} must hold {n} numbers > 0, got {x}")
    centre, half_range, qd_max, qdd_max = bounds
    if centre.shape != (n,):
        raise ValueError(f"centre must have shape ({n},), got shape {centre.shape}")
    lo, hi = robot.limits.T
    if not (np.all(centre - half_range >= lo) and np.all(centre + half_range <= hi)):
        raise ValueError("centre +- half_range must lie within the robot's joint limits")
    period = check_scalar(period, "period", minimum=0.0)
    counts = {}
    for value, name, low in ((harmonics, "harmonics", 1), (samples, "samples", 2),
                             (iterations, "iterations", 0)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
            raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
        counts[name] = int(value)
    rng = np.random.default_rng(seed)
    t = np.arange(counts["samples"]) * period / counts["samples"]
    grid = np.linspace(0.0, period, GRID, endpoint=False)

    def candidate(x):
        a, b = x.reshape(2, n, counts["harmonics"])
        return _within(a, b, period, centre, half_range, qd_max, qdd_max, grid)

    def cost(trajectory):
        W = regressor_with_motors(robot, *trajectory.sample(t)).reshape(-1, len(base.names))
        return _condition(base.columns(W))

    x = rng.normal(size=2 * n * counts["harmonics"])
    best = cost(candidate(x))
    history = [best]
    step, successes = 0.3, []
    for _ in range(counts["iterations"]):
        y = x + step * rng.normal(size=x.size)
        value = cost(candidate(y))
        better = value < best
        if better:
            x, best = y, value
        successes.append(better)
        if len(successes) == 10:                # the one-fifth rule, every ten trials
            step *= 1.5 if sum(successes) > 2 else 0.7
            successes = []
        history.append(best)
    if not math.isfinite(best):
        raise ValueError("the bounds half_range, qd_max and qdd_max leave the trajectory no room "
                         "to excite the base parameters (their regressor stays rank deficient)")
    return candidate(x), np.array(history)


# --------------------------------------------------------------------------------------
# A model of identified base parameters

@dataclass(frozen=True, eq=False)
class IdentifiedModel:
    r"""Joint torques predicted from identified base parameters,
    :math:`\tau = W_b(q, \dot q, \ddot q)\,\hat\beta`: a model for
    :class:`dqlab.sim.ComputedTorque` (it has :meth:`inverse_dynamics`), motors and friction
    included.

    Parameters
    ----------
    robot : Robot
        The arm's kinematics (its inertias are not used).
    base : BaseParameters
        Of :func:`regressor_with_motors`'s columns for ``robot``.
    beta : array_like, shape (r,)
        The estimated base parameters.
    gravity : array_like, shape (3,), optional
        World frame, m/s^2.
    zero_speed : float, optional
        As in :func:`motor_regressor`.
    """

    robot: Robot
    base: BaseParameters
    beta: np.ndarray
    gravity: tuple = dynamics.GRAVITY
    zero_speed: float = 0.0
    name = "identified model"

    def __post_init__(self):
        check_instance(self.robot, Robot, "robot")
        check_instance(self.base, BaseParameters, "base")
        if len(self.base.names) != 13 * self.robot.n:
            raise ValueError(f"base must be of regressor_with_motors' {13 * self.robot.n} "
                             f"columns for this robot, got {len(self.base.names)}")
        beta = as_float_array(self.beta, "beta", (self.base.rank,))
        if beta.shape != (self.base.rank,):
            raise ValueError(f"beta must have shape ({self.base.rank},), got {beta.shape}")
        object.__setattr__(self, "beta", beta.copy())

    @property
    def n(self) -> int:
        return self.robot.n

    def inverse_dynamics(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike
                         ) -> NDArray[np.float64]:
        """Joint torques, shape (..., n)."""
        W = regressor_with_motors(self.robot, q, qd, qdd, gravity=self.gravity,
                                  zero_speed=self.zero_speed)
        return self.base.columns(W) @ self.beta
