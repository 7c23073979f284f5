r"""Numerical inverse kinematics by damped least squares (Levenberg--Marquardt).

Works for any :class:`~dqlab.robot.Robot`: full pose (position and orientation) or position
only, one target or a batch solved together (every iteration is one vectorised step for
the whole batch). The UR3 report solves its circular path this way, each point warm-started
from the previous solution.
"""

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._checks import check_tolerance, components, stack_components
from .._kernels import pose_error_entries, rotation_vector_from_matrix_entries
from ..robot import Robot
from .result import IKResult, finish, target_reasons
from .targets import parse_targets, pose_errors

__all__ = ["numerical", "pose_errors"]


def _residual(X, X_target, position_only):
    r"""Error vectors (..., 3) or (..., 6) of poses ``X`` towards ``X_target`` (..., 4, 4):
    :math:`p^\ast - p`, then the rotation vector of :math:`R^\ast R^\top`, in the world
    frame. Written on components: Python floats for one pose, columns for a batch."""
    lead = X.shape[:-2]
    a = components(X.reshape(lead + (16,)))
    b = components(X_target.reshape(lead + (16,)))
    e = [b[3] - a[3], b[7] - a[7], b[11] - a[11]]
    if not position_only:
        # (R* R^T)_ij: row i of R* dotted with row j of R
        e.extend(rotation_vector_from_matrix_entries(*(
            b[4 * i] * a[4 * j] + b[4 * i + 1] * a[4 * j + 1] + b[4 * i + 2] * a[4 * j + 2]
            for i in range(3) for j in range(3))))
    return stack_components(e)


def numerical(robot: Robot, target: ArrayLike, q0: ArrayLike, *, position_only: bool = False,
              tol: float = 1e-10, rotation_tol: float | None = None, max_iter: int = 100,
              damping: float = 1e-2, min_damping: float = 1e-9, max_damping: float = 1e6,
              max_step: float = 0.5, history: bool = False) -> IKResult:
    r"""Inverse kinematics by damped least squares, from a warm start ``q0``.

    Each iteration linearises the forward kinematics at :math:`q` with the geometric
    Jacobian :math:`J` (:func:`dqlab.jacobian.geometric_jacobian`) and takes the
    Levenberg--Marquardt step

    .. math::

       \Delta q = \left(J^\top J + \lambda^2 I\right)^{-1} J^\top e,
       \qquad e = \begin{pmatrix} p^\ast - p \\ \log(R^\ast R^\top)^\vee \end{pmatrix}

    (only the position rows with ``position_only``). A step that lowers :math:`\lVert e
    \rVert` is accepted and :math:`\lambda` shrinks (towards Gauss--Newton, quadratic
    convergence); a step that does not is rejected and :math:`\lambda` grows (towards small
    gradient steps). Joints are clipped to their limits after every step, steps are capped
    at ``max_step`` per joint.

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
        and ``"damping"`` (:math:`\lambda` used next); a target that has stopped keeps
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
    stalled (damping above 1e+06) after ... iterations: position error 1.49 m, rotation error
    ... rad (tolerances 1e-10 m, 1e-10 rad)
    """
    tol = check_tolerance(tol, "tol")
    rotation_tol = tol if rotation_tol is None else check_tolerance(rotation_tol, "rotation_tol")
    for value, label in ((damping, "damping"), (min_damping, "min_damping"),
                         (max_damping, "max_damping"), (max_step, "max_step")):
        check_tolerance(value, label)
    targets = parse_targets(target, position=position_only)
    q0 = robot.check_joints(q0, limits="none", name="q0")
    batch = np.broadcast_shapes(targets.batch, q0.shape[:-1])
    n = robot.n
    X_target = targets.transforms
    if targets.batch != batch:
        X_target = np.broadcast_to(X_target, batch + (4, 4))
    if q0.shape[:-1] != batch:
        q0 = np.broadcast_to(q0, batch + (n,))
    lower, upper = robot.limits.T
    X_target = X_target.reshape(-1, 4, 4)
    q = np.clip(q0.reshape(-1, n), lower, upper)
    options = _Options(position_only, tol, rotation_tol, int(max_iter), float(damping),
                       min_damping, max_damping, max_step, lower, upper)
    iterate = _iterate_one if q.shape[0] == 1 else _iterate
    q, X, iterations, stuck, record = iterate(robot, q, X_target, options, history)

    if X.shape[0] == 1:        # pose_errors without its checks: both are rigid transforms
        position_error, rotation_error = (np.array([v]) for v in pose_error_entries(
            X.ravel().tolist(), X_target.ravel().tolist()))
    else:
        position_error, rotation_error = pose_errors(X, X_target)
    if not targets.has_rotation:
        rotation_error = np.zeros_like(rotation_error)
    valid = options.met(position_error, rotation_error)

    def explain(index):
        (b,) = index
        why = (f"stalled (damping above {max_damping:g}) after {iterations[b]} iterations"
               if stuck[b] else f"did not converge after {iterations[b]} iterations")
        text = f"{why}: position error {position_error[b]:.3g} m"
        if targets.has_rotation:
            text += f", rotation error {rotation_error[b]:.3g} rad"
        text += f" (tolerances {tol:g} m"
        return text + (")" if position_only else f", {rotation_tol:g} rad)")

    result = finish(q.reshape(batch + (1, n)), valid.reshape(batch + (1,)),
                    position_error.reshape(batch + (1,)), rotation_error.reshape(batch + (1,)),
                    {"not_converged": (~valid).reshape(batch),
                     "stalled": (stuck & ~valid).reshape(batch)},
                    target_reasons(~valid, explain).reshape(batch))
    if history:
        result.history = {name: np.array(rows).reshape((len(rows),) + batch)
                          for name, rows in record.items()}
    return result


@dataclass
class _Options:
    """The solver's settings (see :func:`numerical`)."""

    position_only: bool
    tol: float
    rotation_tol: float
    max_iter: int
    damping: float
    min_damping: float
    max_damping: float
    max_step: float
    lower: np.ndarray          # the joint limits
    upper: np.ndarray

    def met(self, position_error, rotation_error):
        """Where the tolerances are met."""
        done = position_error <= self.tol
        if not self.position_only:
            done &= rotation_error <= self.rotation_tol
        return done

    def errors(self, e):
        """The position and rotation errors (norms of the two parts of the residual ``e``:
        the distance, and the angle of the rotation vector): floats for one residual,
        arrays for a batch."""
        c = components(e)
        position_error = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) ** 0.5
        if self.position_only:
            return position_error, 0.0 * position_error
        return position_error, (c[3] * c[3] + c[4] * c[4] + c[5] * c[5]) ** 0.5


def _iterate(robot, q, X_target, options, history=False):
    """Levenberg--Marquardt iterations from ``q`` (B, n) towards ``X_target`` (B, 4, 4),
    every target that has not converged or stalled moved together. Returns the last
    iterates ``q`` and their poses ``X``, the number of iterations and whether the damping
    ran away (stalled), per target, and the history (a dict of lists, empty without
    ``history``). The stopping test reads the errors from the residual; the caller measures
    the final errors with :func:`~dqlab.ik.targets.pose_errors`."""
    B = q.shape[0]
    lam = np.full(B, options.damping)
    X, J = robot.fk_with_jacobian(q)
    e = _residual(X, X_target, options.position_only)
    cost = _cost(e)
    iterations = np.zeros(B, dtype=int)
    stuck = np.zeros(B, dtype=bool)
    errors = options.errors(e)
    active = ~options.met(*errors)
    record = {"position_error": [], "rotation_error": [], "damping": []}

    def remember():
        if history:
            for name, value in zip(record, (*errors, lam), strict=True):
                record[name].append(value.copy())

    remember()
    everyone = slice(None)
    for _ in range(options.max_iter):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        if idx.size == B:
            idx = everyone                       # a view instead of copies, as for one pose
        q_try = _step(J[idx], q[idx], e[idx], lam[idx], options)
        X_try, J_try = robot.fk_with_jacobian(q_try)
        e_try = _residual(X_try, X_target[idx], options.position_only)
        cost_try = _cost(e_try)
        better = cost_try < cost[idx]
        acc = np.flatnonzero(better) if idx is everyone else idx[better]
        q[acc], X[acc], J[acc], e[acc], cost[acc] = (
            q_try[better], X_try[better], J_try[better], e_try[better], cost_try[better])
        lam[idx] = np.where(better, np.maximum(lam[idx] / 3.0, options.min_damping),
                            lam[idx] * 5.0)
        iterations[idx] += 1
        stuck[idx] = lam[idx] > options.max_damping
        errors = options.errors(e)
        active[idx] = ~options.met(errors[0][idx], errors[1][idx]) & ~stuck[idx]
        remember()
    return q, X, iterations, stuck, record


def _iterate_one(robot, q, X_target, options, history=False):
    """:func:`_iterate` for one target (``q`` (1, n), ``X_target`` (1, 4, 4)): the same
    iterates, computed without the batch axis (the forward kinematics, Jacobian and
    residual then run on Python floats) and with the bookkeeping (cost, damping, stopping
    tests) on Python numbers, several times cheaper than numpy's on one-element arrays."""
    q, X_target = q[0], X_target[0]
    lam = options.damping
    X, J = robot.fk_with_jacobian(q)
    e = _residual(X, X_target, options.position_only)
    cost = _cost(e)
    errors = options.errors(e)
    record = {"position_error": [], "rotation_error": [], "damping": []}

    def remember():
        if history:
            for name, value in zip(record, (*errors, lam), strict=True):
                record[name].append(np.array([value]))

    iterations, stuck = 0, False
    while iterations < options.max_iter and not (stuck or options.met(*errors)):
        remember()
        q_try = _step(J, q, e, lam, options)
        X_try, J_try = robot.fk_with_jacobian(q_try)
        e_try = _residual(X_try, X_target, options.position_only)
        cost_try = _cost(e_try)
        if cost_try < cost:
            q, X, J, e, cost = q_try, X_try, J_try, e_try, cost_try
            lam = max(lam / 3.0, options.min_damping)
            errors = options.errors(e)
        else:
            lam = lam * 5.0
        iterations += 1
        stuck = lam > options.max_damping
    remember()
    return q[None], X[None], np.array([iterations]), np.array([stuck]), record


def _cost(e):
    """The squared norm of residuals ``e`` (..., m), summed in order (a float for one)."""
    c = components(e)
    total = c[0] * c[0]
    for x in c[1:]:
        total = total + x * x
    return total


def _step(J, q, e, lam, options):
    r"""The damped least-squares step :math:`(J^\top J + \lambda^2 I)^{-1} J^\top e` from
    ``q`` (..., n) with the Jacobian ``J`` (..., 6, n) there (``lam`` of shape (...)),
    capped at ``max_step`` per joint and clipped to the joint limits."""
    if options.position_only:
        J = J[..., :3, :]                                             # (..., m, n)
    Jt = np.swapaxes(J, -1, -2)
    A = Jt @ J
    n = A.shape[-1]
    A.reshape(A.shape[:-2] + (n * n,))[..., ::n + 1] += np.asarray(lam)[..., None] ** 2
    g = (Jt @ e[..., None])[..., 0]
    try:
        step = np.linalg.solve(A, g[..., None])[..., 0]
    except np.linalg.LinAlgError:   # an exactly singular system: least-squares step
        step = (np.linalg.pinv(A) @ g[..., None])[..., 0]
    biggest = np.abs(step).max(axis=-1, keepdims=True)
    step *= np.minimum(1.0, options.max_step / np.maximum(biggest, 1e-300))
    return np.clip(q + step, options.lower, options.upper)
