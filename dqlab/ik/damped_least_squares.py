r"""Numerical inverse kinematics by damped least squares (Levenberg--Marquardt).

Works for any :class:`~dqlab.robot.Robot`: full pose (position and orientation) or position
only, one target or a batch solved together (every iteration is one vectorised step for
the whole batch). The UR3 report solves its circular path this way, each point warm-started
from the previous solution.
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._checks import check_tolerance, components, rigid_rows, stack_components
from .._formulas import pose_error_entries, rotation_vector_from_matrix_entries
from ..robot import Robot
from .result import IKResult, finish, target_reasons
from .targets import RIGID_TOL, parse_targets, pose_errors

__all__ = ["numerical", "pose_errors"]

_FLOAT64 = np.dtype(np.float64)

#: A step is taken when it lowers E below the largest E of the last ``_WINDOW`` iterates.
_WINDOW = 5
#: The factors of the Levenberg--Marquardt damping lambda: divided by ``_SHRINK`` after a step
#: that lowers E by at least the fraction ``_PROGRESS``, multiplied by ``_GROW`` after any other.
_SHRINK, _GROW, _PROGRESS = 3.0, 5.0, 1e-3


def _residual_entries(a, b, position_only):
    r"""The error vector of a pose towards a target, both given by their 16 entries row by
    row (floats for one pose, columns for a batch): :math:`p^\ast - p`, then the rotation
    vector of :math:`R^\ast R^\top`, in the world frame."""
    e = [b[3] - a[3], b[7] - a[7], b[11] - a[11]]
    if not position_only:
        # (R* R^T)_ij: row i of R* dotted with row j of R
        rows, target_rows = (a[0:3], a[4:7], a[8:11]), (b[0:3], b[4:7], b[8:11])
        e.extend(rotation_vector_from_matrix_entries(*[
            s0 * r0 + s1 * r1 + s2 * r2 for s0, s1, s2 in target_rows for r0, r1, r2 in rows]))
    return e


def _residual(X, X_target, position_only):
    """Error vectors (..., 3) or (..., 6) of poses ``X`` towards ``X_target`` (..., 4, 4)
    (see :func:`_residual_entries`)."""
    lead = X.shape[:-2]
    return stack_components(_residual_entries(components(X.reshape(lead + (16,))),
                                              components(X_target.reshape(lead + (16,))),
                                              position_only))


def numerical(robot: Robot, target: ArrayLike, q0: ArrayLike, *, position_only: bool = False,
              tol: float = 1e-10, rotation_tol: float | None = None, max_iter: int = 100,
              damping: float = 1e-5, error_damping: float = 0.1, min_damping: float = 1e-9,
              max_damping: float = 1e6, max_step: float = 0.5, history: bool = False
              ) -> IKResult:
    r"""Inverse kinematics by damped least squares, from a warm start ``q0``.

    Each iteration linearises the forward kinematics at :math:`q_k` with the geometric
    Jacobian :math:`J` (:meth:`dqlab.robot.Robot.jacobian`) and takes the
    Levenberg--Marquardt step, the :math:`\Delta q` that minimises
    :math:`\lVert e_k - J \Delta q \rVert^2 + \mu_k \lVert \Delta q \rVert^2`:

    .. math::

       \Delta q = \left(J^\top J + \mu_k I\right)^{-1} J^\top e_k, \qquad
       \mu_k = \lambda_k^2 + w E_k, \qquad E_k = \tfrac12 e_k^\top e_k, \qquad
       e_k = \begin{pmatrix} p^\ast - p \\ \log(R^\ast R^\top)^\vee \end{pmatrix}

    (only the position rows with ``position_only``). The damping :math:`\mu_k` has two
    terms. :math:`w E_k` is proportional to the squared error, as proposed by Chan and
    Lawrence (1988) and by Sugihara (2011, "Solvability-unconcerned inverse kinematics by
    the Levenberg--Marquardt method"): far from the target, or near a singularity where
    :math:`J^\top J` has tiny eigenvalues, it keeps the step short; at a solution it
    vanishes like :math:`\lVert e \rVert^2`, so that the convergence stays quadratic.
    :math:`\lambda_k^2` takes the place of Sugihara's small constant bias and is adapted as
    Levenberg and Marquardt adapt their damping, a safeguard: it stays negligible while the
    steps succeed and grows when they fail, until a target out of reach makes it run away
    and the solver stops.

    A step is taken when :math:`E(q_k + \Delta q)` is below the largest :math:`E` of the
    last five iterates, and rejected otherwise (the iterate stays): a non-monotone test, as
    in Grippo, Lampariello and Lucidi (1986, "A nonmonotone line search technique for
    Newton's method"), because near a wrist singularity the error of a converging iteration
    may rise for a step or two. :math:`\lambda` is divided by 3 after a step that lowers
    :math:`E` by at least 0.1 % and multiplied by 5 after any other, so that at a target out
    of reach, where the error settles at a nonzero minimum, it runs away within a few dozen
    iterations. :math:`\lambda_0` is small: the error term does the damping while the
    steps succeed. Joints are clipped to their limits after every step, steps are capped at
    ``max_step`` per joint. The linear system is solved by Cholesky factorisation (by least
    squares if it is singular to working precision).

    Parameters
    ----------
    robot : Robot
    target : array_like, shape (..., 4, 4), (..., 8) or (..., 3)
        Targets :math:`X_{WT}^\ast` as transforms or unit dual quaternions, or positions
        (with ``position_only=True``).
    q0 : array_like, shape (..., n)
        Initial guesses, broadcast against the targets.
    position_only : bool, optional
        Solve for the TCP position only (the report's path following).
    tol : float, optional
        Position tolerance in metres.
    rotation_tol : float, optional
        Rotation tolerance in radians (default: ``tol``).
    max_iter : int, optional
        Largest number of iterations.
    damping : float, optional
        Initial :math:`\lambda`.
    error_damping : float, optional
        The weight :math:`w` of the error term. With a weight near 1 the damping stays
        near 1 at a target out of reach, where the iteration then creeps instead of
        stopping; 0 gives plain Levenberg--Marquardt.
    min_damping, max_damping : float, optional
        Bounds of :math:`\lambda`; reaching ``max_damping`` means the solver is stuck
        (target out of reach, or a local minimum) and it stops for that target.
    max_step : float, optional
        Largest change of one joint per iteration (radians or metres).
    history : bool, optional
        Also record, for every iteration, each target's errors and damping (the
        convergence plot of the inverse-kinematics chapter).

    Returns
    -------
    IKResult
        ``solutions`` of shape (..., 1, n); ``valid`` (..., 1) True where the tolerances
        are met; ``position_error`` and ``rotation_error`` of the last iterate (also when
        it failed); ``flags["not_converged"]``; ``reason`` says how far from the target a
        failed solve stopped. ``rotation_error`` is 0 when only a position was given.
        With ``history``, ``result.history`` is a dict of arrays of shape (k + 1, ...),
        row 0 at ``q0`` and row i after iteration i: ``"position_error"`` and
        ``"rotation_error"`` (the norms of the two parts of :math:`e`, metres and radians)
        and ``"damping"`` (:math:`\mu` of the next step); a target that has stopped keeps
        its last values.

    Raises
    ------
    ValueError
        On malformed targets or initial guesses.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> q_true = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    >>> result = numerical(robot, robot.fk(q_true), q_true + 0.1)
    >>> result.valid
    array([ True])
    >>> np.allclose(result.solutions[0], q_true)
    True
    >>> bool(result.position_error[0] < 1e-10)
    True

    A target out of reach fails, and says so:

    >>> far = robot.fk(q_true)
    >>> far[:3, 3] = [2.0, 0.0, 0.0]
    >>> result = numerical(robot, far, q_true)
    >>> result.valid
    array([False])
    >>> print(result.reason)
    stalled (damping above 1e+06) after ... iterations: position error 1.62 m, rotation error
    ... rad (tolerances 1e-10 m, 1e-10 rad)
    """
    tol = check_tolerance(tol, "tol")
    rotation_tol = tol if rotation_tol is None else check_tolerance(rotation_tol, "rotation_tol")
    for value, label in ((damping, "damping"), (error_damping, "error_damping"),
                         (min_damping, "min_damping"), (max_damping, "max_damping"),
                         (max_step, "max_step")):
        check_tolerance(value, label)
    lower, upper = robot.limits.T
    options = _Options(position_only, tol, rotation_tol, int(max_iter), float(damping),
                       float(error_damping), min_damping, max_damping, max_step, lower, upper)
    one = _one_target(robot, target, q0, position_only)
    if one is not None:                 # one checked target and start, on floats
        X_target, has_rotation, q = one
        q = _clip(q, options.lower_list, options.upper_list)
        return _one_result(*_iterate_one(robot, q, X_target, options, history), has_rotation,
                           options, history)
    targets = parse_targets(target, position=position_only)
    q0 = robot.check_joints(q0, limits="none", name="q0")
    batch = np.broadcast_shapes(targets.batch, q0.shape[:-1])
    n = robot.n
    has_rotation = targets.has_rotation
    X_target = targets.transforms
    if targets.batch != batch:
        X_target = np.broadcast_to(X_target, batch + (4, 4))
    if q0.shape[:-1] != batch:
        q0 = np.broadcast_to(q0, batch + (n,))
    X_target = X_target.reshape(-1, 4, 4)
    q = np.clip(q0.reshape(-1, n), lower, upper)
    if q.shape[0] == 1:
        *run, record = _iterate_one(robot, q[0].tolist(), X_target[0].ravel().tolist(),
                                    options, history)
        q, position_error, rotation_error, iterations, stuck = (np.array([v]) for v in run)
    else:
        q, position_error, rotation_error, iterations, stuck, record = _iterate(
            robot, q, X_target, options, history)
    if not has_rotation:
        rotation_error = np.zeros_like(rotation_error)
    valid = options.met(position_error, rotation_error)

    def explain(index):
        (b,) = index
        return options.reason(iterations[b], stuck[b], position_error[b],
                              rotation_error[b] if has_rotation else None)

    result = finish(q.reshape(batch + (1, n)), valid.reshape(batch + (1,)),
                    position_error.reshape(batch + (1,)), rotation_error.reshape(batch + (1,)),
                    {"not_converged": (~valid).reshape(batch),
                     "stalled": (stuck & ~valid).reshape(batch)},
                    target_reasons(~valid, explain).reshape(batch))
    if history:
        result.history = {name: np.array(rows).reshape((len(rows),) + batch)
                          for name, rows in record.items()}
    return result


def _one_result(q, position_error, rotation_error, iterations, stuck, record, has_rotation,
                options, history):
    """The :class:`IKResult` of one target (as :func:`numerical` assembles it for a batch)
    from what :func:`_iterate_one` returns, on floats."""
    if not has_rotation:
        rotation_error = 0.0
    valid = options.met(position_error, rotation_error)
    reason = "" if valid else options.reason(iterations, stuck, position_error,
                                             rotation_error if has_rotation else None)
    result = finish(np.array([q]), np.array([valid]), np.array([position_error]),
                    np.array([rotation_error]),
                    {"not_converged": np.array(not valid),
                     "stalled": np.array(stuck and not valid)},
                    np.array(reason, dtype=object))
    if history:
        result.history = {name: np.array(rows) for name, rows in record.items()}
    return result


def _one_target(robot, target, q0, position_only):
    """One target as its 16 entries (a rigid transform, row by row), whether it has a
    rotation, and ``q0`` as n floats, when ``target`` is one float64 transform (or, with
    ``position_only``, one position) and ``q0`` one float64 joint vector that pass the checks
    of :func:`~dqlab.ik.targets.parse_targets` and :meth:`~dqlab.robot.Robot.check_joints`;
    None otherwise (the general path then checks them and says what is wrong)."""
    if not (type(target) is np.ndarray and target.dtype is _FLOAT64
            and type(q0) is np.ndarray and q0.dtype is _FLOAT64 and q0.shape == (robot.n,)):
        return None
    q = q0.tolist()
    total = sum(q)
    if not total - total == 0.0:                      # NaN or infinity
        return None
    if target.shape == (4, 4):
        rows = rigid_rows(target, RIGID_TOL)
        if rows is None:
            return None
        a, b, c = rows
        return a + b + c + [0.0, 0.0, 0.0, 1.0], True, q
    if position_only and target.shape == (3,):
        x, y, z = target.tolist()
        total = x + y + z
        if not total - total == 0.0:
            return None
        return [1.0, 0.0, 0.0, x, 0.0, 1.0, 0.0, y, 0.0, 0.0, 1.0, z, 0.0, 0.0, 0.0, 1.0], False, q
    return None


@dataclass
class _Options:
    """The solver's settings (see :func:`numerical`)."""

    position_only: bool
    tol: float
    rotation_tol: float
    max_iter: int
    damping: float
    error_damping: float
    min_damping: float
    max_damping: float
    max_step: float
    lower: np.ndarray          # the joint limits
    upper: np.ndarray

    def __post_init__(self):
        self.lower_list, self.upper_list = self.lower.tolist(), self.upper.tolist()

    def met(self, position_error, rotation_error):
        """Where the tolerances are met."""
        done = position_error <= self.tol
        if not self.position_only:
            done &= rotation_error <= self.rotation_tol
        return done

    def reason(self, iterations, stuck, position_error, rotation_error=None):
        """Why a target failed, and how far from it the solver stopped (``rotation_error``
        None for a position target)."""
        why = (f"stalled (damping above {self.max_damping:g}) after {iterations} iterations"
               if stuck else f"did not converge after {iterations} iterations")
        text = f"{why}: position error {position_error:.3g} m"
        if rotation_error is not None:
            text += f", rotation error {rotation_error:.3g} rad"
        text += f" (tolerances {self.tol:g} m"
        return text + (")" if self.position_only else f", {self.rotation_tol:g} rad)")

    def errors(self, e):
        """The position and rotation errors (norms of the two parts of the residual, given
        by its components ``e``: the distance, and the angle of the rotation vector): floats
        for one residual, arrays for a batch."""
        position_error = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) ** 0.5
        if self.position_only:
            return position_error, 0.0 * position_error
        return position_error, (e[3] * e[3] + e[4] * e[4] + e[5] * e[5]) ** 0.5

    def mu(self, lam, E):
        r"""The damping :math:`\mu = \lambda^2 + w E` of the step (floats or arrays)."""
        return lam * lam + self.error_damping * E


def _iterate(robot, q, X_target, options, history=False):
    """Levenberg--Marquardt iterations from ``q`` (B, n) towards ``X_target`` (B, 4, 4),
    every target that has not converged or stalled moved together. Returns the last
    iterates ``q``, their position and rotation errors (by
    :func:`~dqlab.ik.targets.pose_errors`), the number of iterations and whether the damping
    ran away (stalled), per target, and the history (a dict of lists, empty without
    ``history``). The stopping test reads the errors from the residual."""
    B = q.shape[0]
    lam = np.full(B, options.damping)
    X, J = robot.fk_with_jacobian(q)
    e = _residual(X, X_target, options.position_only)
    E = _half_squared_norm(components(e))
    recent = np.repeat(E[:, None], _WINDOW, axis=1)
    iterations = np.zeros(B, dtype=int)
    stuck = np.zeros(B, dtype=bool)
    errors = options.errors(components(e))
    active = ~options.met(*errors)
    record = {"position_error": [], "rotation_error": [], "damping": []}

    def remember():
        if history:
            for name, value in zip(record, (*errors, options.mu(lam, E)), strict=True):
                record[name].append(value.copy())

    remember()
    everyone = slice(None)
    for _ in range(options.max_iter):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        if idx.size == B:
            idx = everyone                       # a view instead of copies
        q_try = _step(J[idx], q[idx], e[idx], options.mu(lam[idx], E[idx]), options)
        X_try, J_try = robot.fk_with_jacobian(q_try)
        e_try = _residual(X_try, X_target[idx], options.position_only)
        E_try = _half_squared_norm(components(e_try))
        progress = E_try < (1.0 - _PROGRESS) * E[idx]
        taken = E_try < recent[idx].max(axis=1)
        acc = np.flatnonzero(taken) if idx is everyone else idx[taken]
        q[acc], X[acc], J[acc], e[acc], E[acc] = (
            q_try[taken], X_try[taken], J_try[taken], e_try[taken], E_try[taken])
        recent[acc] = np.column_stack([E[acc], recent[acc, :-1]])
        lam[idx] = np.where(progress, np.maximum(lam[idx] / _SHRINK, options.min_damping),
                            lam[idx] * _GROW)
        iterations[idx] += 1
        stuck[idx] = lam[idx] > options.max_damping
        errors = options.errors(components(e))
        active[idx] = ~options.met(errors[0][idx], errors[1][idx]) & ~stuck[idx]
        remember()
    return (q, *pose_errors(X, X_target), iterations, stuck, record)


def _iterate_one(robot, q, X_target, options, history=False):
    """:func:`_iterate` for one target, ``q`` (n floats) towards ``X_target`` (its 16
    entries): the same iterates up to rounding, computed on Python floats (the step by
    :func:`_step_one`), several times cheaper than numpy on one-element arrays. Returns
    what :func:`_iterate` returns, as floats, an int and a bool instead of arrays."""
    X, J = robot.fk_with_jacobian(np.array(q))
    X = X.ravel().tolist()
    e = _residual_entries(X, X_target, options.position_only)
    E = _half_squared_norm(e)
    errors = options.errors(e)
    lam = options.damping
    recent = [E] * _WINDOW
    record = {"position_error": [], "rotation_error": [], "damping": []}

    def remember():
        if history:
            for name, value in zip(record, (*errors, options.mu(lam, E)), strict=True):
                record[name].append(value)

    iterations, stuck = 0, False
    while iterations < options.max_iter and not (stuck or options.met(*errors)):
        remember()
        q_try = _step_one(J, q, e, options.mu(lam, E), options)
        X_try, J_try = robot.fk_with_jacobian(np.array(q_try))
        X_try = X_try.ravel().tolist()
        e_try = _residual_entries(X_try, X_target, options.position_only)
        E_try = _half_squared_norm(e_try)
        progress = E_try < (1.0 - _PROGRESS) * E
        if E_try < max(recent):
            q, X, J, e, E = q_try, X_try, J_try, e_try, E_try
            recent = [E] + recent[:-1]
            errors = options.errors(e)
        lam = max(lam / _SHRINK, options.min_damping) if progress else lam * _GROW
        iterations += 1
        stuck = lam > options.max_damping
    remember()
    return (q, *pose_error_entries(X, X_target), iterations, stuck, record)


def _half_squared_norm(e):
    r""":math:`E = \tfrac12 e^\top e` of residuals given by their components ``e``, summed in
    order (a float for one residual, an array for a batch)."""
    total = e[0] * e[0]
    for x in e[1:]:
        total = total + x * x
    return 0.5 * total


def _damped_system(J, e, mu, position_only):
    r"""The damped least-squares step as a symmetric positive-definite system, from
    Jacobians ``J`` (..., 6, n), residuals ``e`` (..., m) and dampings ``mu`` (...):

    .. math::

       \Delta q = \left(J^\top J + \mu I_n\right)^{-1} J^\top e
                = J^\top \left(J J^\top + \mu I_m\right)^{-1} e,

    returned as ``A``, ``b`` and ``M``, the step being ``x`` with :math:`A x = b` (``M`` is
    None) in the first form, used when :math:`m \ge n`, and :math:`M x = J^\top x` in the
    second, a smaller and better conditioned system when :math:`m < n` (a position-only
    target of the UR3: m = 3, n = 6)."""
    if position_only:
        J = J[..., :3, :]                                             # (..., m, n)
    m, n = J.shape[-2:]
    Jt = J.T if J.ndim == 2 else np.swapaxes(J, -1, -2)
    if m < n:
        A, b, M = J @ Jt, e, Jt
    else:
        A, b, M = Jt @ J, (Jt @ e[..., None])[..., 0], None
    k = A.shape[-1]
    A.reshape(A.shape[:-2] + (k * k,))[..., ::k + 1] += np.asarray(mu)[..., None]
    return A, b, M


def _least_squares(A, b):
    """The least-squares solutions of ``A x = b`` (by the pseudo-inverse), for a system
    that is singular to working precision."""
    return (np.linalg.pinv(A) @ b[..., None])[..., 0]


def _step(J, q, e, mu, options):
    r"""The damped least-squares step :math:`(J^\top J + \mu I)^{-1} J^\top e` from ``q``
    (..., n) with the Jacobian ``J`` (..., 6, n) there (``mu`` of shape (...)), capped at
    ``max_step`` per joint and clipped to the joint limits. Arrays; :func:`_step_one` is
    the same step on floats."""
    A, b, M = _damped_system(J, e, mu, options.position_only)
    try:
        x = np.linalg.solve(A, b[..., None])[..., 0]
    except np.linalg.LinAlgError:   # an exactly singular system: least-squares step
        x = _least_squares(A, b)
    step = x if M is None else (M @ x[..., None])[..., 0]
    biggest = np.abs(step).max(axis=-1, keepdims=True)
    step *= np.minimum(1.0, options.max_step / np.maximum(biggest, 1e-300))
    return np.clip(q + step, options.lower, options.upper)


def _step_one(J, q, e, mu, options):
    """:func:`_step` for one joint vector ``q`` and residual ``e`` (lists of floats, ``J``
    an array (6, n)): the same system, solved by :func:`_cholesky_solve` on floats, and a
    list of floats back."""
    A, b, M = _damped_system(J, np.array(e), mu, options.position_only)
    x = _cholesky_solve(A.tolist(), b.tolist())
    if x is None:                   # not positive definite to working precision
        x = _least_squares(A, b).tolist()
    step = x if M is None else (M @ x).tolist()
    biggest = max(map(abs, step))
    if biggest > options.max_step:
        scale = options.max_step / biggest
        step = [s * scale for s in step]
    return _clip([v + s for v, s in zip(q, step, strict=True)], options.lower_list,
                 options.upper_list)


def _clip(q, lower, upper):
    """The floats ``q`` clipped to ``[lower, upper]``, entry by entry, as ``np.clip`` does
    it."""
    return [min(max(v, lo), hi) for v, lo, hi in zip(q, lower, upper, strict=True)]


def _cholesky_solve(A, b):
    r"""The solution of :math:`A x = b` for a symmetric positive-definite matrix ``A``
    (a list of n rows of floats, only the lower triangle is read) and ``b`` (n floats), by
    the Cholesky factorisation :math:`A = L L^\top`, then :math:`L y = b` and
    :math:`L^\top x = y`; None when a pivot is not positive (``A`` is not positive definite
    to working precision).

    >>> _cholesky_solve([[4.0, 2.0], [2.0, 5.0]], [2.0, 5.0])      # L = [[2, 0], [1, 2]]
    [0.0, 1.0]
    >>> _cholesky_solve([[1.0, 1.0], [1.0, 1.0]], [1.0, 1.0]) is None
    True
    """
    n = len(b)
    L = []                                       # rows of L, each up to its diagonal
    y = []
    for i in range(n):
        Ai = A[i]
        Li = [0.0] * (i + 1)
        for j in range(i):
            Lj = L[j]
            s = Ai[j]
            for k in range(j):
                s -= Li[k] * Lj[k]
            Li[j] = s / Lj[j]
        d = Ai[i]
        s = b[i]
        for k in range(i):
            d -= Li[k] * Li[k]
            s -= Li[k] * y[k]
        if not d > 0.0:
            return None
        Li[i] = d = math.sqrt(d)
        L.append(Li)
        y.append(s / d)                          # forward substitution, row by row
    x = y
    for i in range(n - 1, -1, -1):               # back substitution, L^T x = y
        s = x[i]
        for k in range(i + 1, n):
            s -= L[k][i] * x[k]
        x[i] = s / L[i][i]
    return x
