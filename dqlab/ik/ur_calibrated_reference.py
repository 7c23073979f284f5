r"""The inverse kinematics of a calibrated UR, written to be read: chapter 12's three steps.

:func:`calibrated_ur_reference` solves a calibrated UR as
:func:`dqlab.ik.ur_calibrated.calibrated_ur` does (``dqlab.ik.ur`` on such a robot), pose by
pose, with one forward kinematics (:meth:`dqlab.robot.Robot.fk_with_jacobian`) and one
Newton step (:func:`newton_step`):

1. **The closed form of the nearest exact UR** (:func:`~dqlab.ik.ur_calibrated.nominal_ur`)
   gives a start for each of the eight branches, with the tolerance widened to twice the
   gap between the two arms (ten gaps for a row it misses by a little more; a start on the
   elbow singularity is bent off it).
2. **Newton on the calibrated chain** from each start,
   :math:`q \leftarrow q + (J^\mathsf{T} J + \lambda I)^{-1} J^\mathsf{T} e(q)`,
   :math:`\lambda = 10^{-12}\operatorname{tr}(J^\mathsf{T}J)/6`, a step longer than half a
   radian shortened; a branch stops below a tenth of ``tol`` (after three steps at least),
   or when after eight steps it no longer halves its error in two. It is valid when it
   reaches the target to ``tol`` and repeats no branch before it.
3. **The repair of the branches still missing** (near a singularity, two starts may lead
   to one solution): members of the exact arm's wrist family as starts, and deflated
   Newton from the solutions found, moved along the most singular direction of
   :math:`J^\mathsf{T} J` (every branch, when Newton found at most two: there the exact
   arm may clip a whole shoulder that the calibrated arm reaches). A row near a
   singularity of the exact arm then takes three Newton steps more, which bring its joints,
   not only its pose, to the solution. A pose whose eight rows are all valid, one near a
   singularity, seeks solutions beyond them the same way (``result.more``: within the
   arms' gap of a singularity, a calibrated arm may reach a pose in ten or twelve ways).
   A pose left with an odd number of solutions misses one (a general 6R arm has an even
   number) and is flagged ``"not_converged"``.

The fast solver is tested against it on six real calibrations
(``tests/test_ik_ur_calibrated_reference.py``).
"""

import numpy as np
from numpy.typing import ArrayLike

from ..robot import Robot
from ..rotations import wrap_angle
from .result import IKResult, check_ur_options, finish
from .targets import parse_targets, pose_errors
from .ur_calibrated import REASON_NOT_CONVERGED, nominal_ur
from .ur_closed_form import ROW_NAMES, branch_measures, exact_ur
from .ur_solver import ur_branch
from .ur_steps import NEAR_SINGULAR

__all__ = ["calibrated_ur_reference", "newton_step"]

MAX_ITER = 16                                  # Newton steps per branch at most
RESTART_ITER = 10                              # ... and per start of the repair
SAMPLES = np.random.default_rng(20260531).uniform(-np.pi, np.pi, (64, 6))   # the arms' gap
FAMILY = -np.pi + 2 * np.pi / 6 * np.arange(6)   # theta_6 of the wrist family's members
MOVES = (0.05, -0.05, 0.3, -0.3)               # deflation starts along the singular direction


def newton_step(arm: Robot, q: ArrayLike, X_target: ArrayLike) -> tuple[np.ndarray, float]:
    r"""One damped Newton step of ``arm`` from ``q`` (n,) towards the pose ``X_target``
    (4, 4), both in the world frame.

    .. math::

       \delta = (J^\mathsf{T} J + \lambda I)^{-1} J^\mathsf{T} e,\quad
       e = \begin{pmatrix} p^\ast - p \\ \tfrac12 (R^\ast R^\mathsf{T}
           - R R^{\ast\mathsf{T}})^\vee \end{pmatrix},\quad
       \lambda = 10^{-12}\,\operatorname{tr}(J^\mathsf{T}J)/n,

    with :math:`J` the geometric Jacobian at the TCP, shortened to half a radian on its
    largest joint.

    Returns
    -------
    step : ndarray, shape (n,)
    error : float
        The larger of :math:`\lVert e_p\rVert` and :math:`\lVert e_R\rVert` at ``q``.
    """
    q, X_target = _one_joint_vector_and_pose(arm, q, X_target)
    X, J = arm.fk_with_jacobian(q)
    E = X_target[:3, :3] @ X[:3, :3].T
    e = np.concatenate([X_target[:3, 3] - X[:3, 3],
                        0.5 * np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]])])
    H = J.T @ J
    with np.errstate(over="ignore", invalid="ignore"):
        step = np.linalg.solve(H + 1e-12 * np.trace(H) / q.size * np.eye(q.size), J.T @ e)
        error = max(np.linalg.norm(e[:3]), np.linalg.norm(e[3:]))
    if not (np.isfinite(step).all() and np.isfinite(error)):
        raise ValueError("X_target is so far from the arm that the Newton step overflows")
    step *= min(1.0, 0.5 / max(np.abs(step).max(), 1e-300))
    return step, error


def _one_joint_vector_and_pose(arm, q, X_target):
    """``q`` (n,) and ``X_target`` (4, 4) for :func:`newton_step`, checked."""
    if not isinstance(arm, Robot):
        raise TypeError(f"arm must be a dqlab.robot.Robot, got {type(arm).__name__}")
    q, X_target = arm.check_joints(q), parse_targets(X_target, name="X_target").transforms
    if q.shape != (arm.n,) or X_target.shape != (4, 4):
        raise ValueError(f"newton_step takes one joint vector q ({arm.n},) and one pose "
                         f"X_target (4, 4), got {q.shape} and {X_target.shape}")
    return q, X_target


def newton(arm, q, X_target, tol, max_iter=MAX_ITER, known=()):
    r"""Newton steps from ``q``, at least three (from millimetres away, three steps of
    quadratic convergence reach the rounding), until the error is below ``tol / 10``
    (returns ``q, True``) or, after eight steps, no longer halves in two, or ``max_iter``.

    With ``known`` solutions :math:`q_k`, the steps are deflated: :math:`\delta / (1 -
    \nabla\log m\cdot\delta)`, :math:`m(q) = \prod_k (\lVert q - q_k\rVert^{-2} + 1)`, so
    that they cannot end at a known solution (Farrell, Birkisson and Funke, SIAM J. Sci.
    Comput. 37, 2015)."""
    errors = []
    for i in range(max_iter + 1):
        step, error = newton_step(arm, q, X_target)
        errors.append(error)
        done = not error > tol / 10 and (i >= 3 or len(known))   # (deflated: no minimum)
        if done or i == max_iter or (i >= 8 and error >= 0.5 * errors[-3]):
            return q, bool(error <= tol / 10)
        if len(known):                          # grad log m = sum -2 d / (|d|^2 (1 + |d|^2))
            d = wrap_angle(q - known)
            r2 = (d * d).sum(axis=1)
            step = step / (1 + (2 * (d @ step) / (r2 * (1 + r2))).sum())
        q = q + step
    return q, False


def calibrated_ur_reference(robot: Robot, target: ArrayLike, *, tol: float = 1e-9,
                            singular_tol: float = 5e-7, near_tol: float = NEAR_SINGULAR
                            ) -> IKResult:
    r"""Every inverse-kinematics solution of a calibrated UR, by the module's three steps.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A calibrated UR (see :func:`~dqlab.ik.ur_calibrated.nominal_ur`), with its base and
        tool.
    target : array_like, shape (..., 4, 4) or (..., 8)
        TCP poses in the world frame (transforms or unit dual quaternions).
    tol, singular_tol, near_tol : float
        As for ``dqlab.ik.ur``.

    Returns
    -------
    IKResult
        As :func:`~dqlab.ik.ur_calibrated.calibrated_ur`'s: eight rows per pose in the exact
        arm's branch order, the solutions beyond them (``more``), its flags and reasons.

    Raises
    ------
    ValueError
        For a robot that is not a calibrated UR, a bad target or tolerance.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur5e
    >>> from dqlab.identify import dh_parameters, robot_from_dh_parameters
    >>> p = dh_parameters(ur5e()) + np.random.default_rng(3).uniform(-2e-3, 2e-3, 24)
    >>> robot = robot_from_dh_parameters(ur5e(), p)
    >>> q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> result = calibrated_ur_reference(robot, robot.fk(q))
    >>> int(result.count), bool(np.abs(result.solutions - q).max(axis=-1).min() < 1e-9)
    (8, True)
    """
    try:
        exact = nominal_ur(robot)                  # step 1's arm
    except ValueError as error:
        raise ValueError(f"robot: {error}") from None
    tol, singular_tol, near_tol, _ = check_ur_options(tol, singular_tol, near_tol, 1e-9, "fk")
    arm = Robot(robot.links, convention="dh", tool=robot.tool)       # the chain in frame 0
    gap_p, gap_r = (e.max() for e in pose_errors(exact.fk(SAMPLES), arm.fk(SAMPLES)))
    wide, near_tol = max(tol, 2 * gap_p), max(near_tol, 4 * gap_r)     # the arms' gap
    targets = parse_targets(target)
    X_0T = np.linalg.inv(robot.base) @ targets.transforms.reshape(-1, 4, 4)
    n = X_0T.shape[0]
    q, valid = np.zeros((2, n, 8, 6)), np.zeros((2, n, 8), bool)     # rows, and more
    pe, re = np.zeros((2, n, 8)), np.zeros((2, n, 8))
    flags, reason = {name: np.zeros(n, bool) for name in FLAG_NAMES}, np.full(n, "", object)
    for i in range(n):
        q[0, i], valid[0, i], pe[0, i], re[0, i], flags_i, reason[i] = solve_pose(
            arm, exact, X_0T[i], tol, wide, singular_tol, near_tol)
        for name in FLAG_NAMES:
            flags[name][i] = flags_i[name]
        if valid[0, i].all():
            more = beyond(arm, exact, X_0T[i], q[0, i], tol)
            m = len(more)
            q[1, i, :m], valid[1, i, :m] = more, True
            pe[1, i, :m], re[1, i, :m] = pose_errors(arm.fk(more), X_0T[i])
    # a general 6R arm reaches a pose in an even number of joint vectors (the real roots of
    # a polynomial of degree 16): an odd count of solutions, rows and beyond, misses one
    flags["not_converged"] |= (valid[0].sum(axis=-1) + valid[1].sum(axis=-1)) % 2 == 1
    b = targets.batch
    more = finish(q[1].reshape(b + (8, 6)), valid[1].reshape(b + (8,)),
                  pe[1].reshape(b + (8,)), re[1].reshape(b + (8,)), {})
    result = finish(q[0].reshape(b + (8, 6)), valid[0].reshape(b + (8,)),
                    pe[0].reshape(b + (8,)), re[0].reshape(b + (8,)),
                    {k: f.reshape(b) for k, f in flags.items()}, reason.reshape(b), more)
    result.row_names = ROW_NAMES
    return result


FLAG_NAMES = ("wrist_singular", "shoulder_singular", "elbow_singular", "near_singular",
              "unreachable", "not_converged")


def solve_pose(arm, exact, X_0T, tol, wide, singular_tol, near_tol):
    """Steps 1-3 for one target ``X_0T`` in frame 0: the rows (8, 6), valid, position and
    rotation errors, flags and reason."""
    X_06 = X_0T @ np.linalg.inv(arm.tool)        # step 1: the exact arm's closed form
    start = exact_ur(exact, X_06, tol=wide, singular_tol=singular_tol, near_tol=near_tol)
    starts, found, started = start.solutions.copy(), start.valid, start.valid.copy()
    near = ~found & (start.position_error <= 10 * wide)
    if near.any():                      # a row missed by a little more: ten gaps wide
        again = exact_ur(exact, X_06, tol=10 * wide)
        starts[near], started[near] = again.solutions[near], again.valid[near]
    starts = off_the_edge(exact, starts, started, start.position_error, tol)
    q, converged = starts.copy(), np.zeros(8, dtype=bool)
    # step 2: Newton from each branch, in order, then from the rows the exact arm missed
    for k in [*np.flatnonzero(found), *np.flatnonzero(started & ~found)]:
        q[k], ok = newton(arm, starts[k], X_0T, tol)
        converged[k] = ok and is_new(q[k], q[converged])
    # step 3: the branches still missing; every one when Newton found at most two (there
    # the exact arm may clip a whole shoulder that the calibrated arm reaches, or all)
    open_rows = ~converged if converged.sum() <= 2 else started & ~converged
    if open_rows.any():
        repair(arm, exact, X_06, X_0T, q, converged, open_rows, tol)
    polish(arm, exact, X_0T, q, converged, tol)
    pe, re = pose_errors(arm.fk(q), X_0T)
    valid = converged & (pe <= tol) & (re <= tol)
    pe = np.where(started | converged, pe, start.position_error)
    re = np.where(started | converged, re, start.rotation_error)
    flags = singularity_flags(arm, q, valid, exact.links[3].d, singular_tol, near_tol)
    flags["near_singular"] |= bool(start.flags["near_singular"]
                                   or (valid & near_exact(exact, q, near_tol)).any())
    flags["not_converged"] = bool((found & (start.position_error <= tol) & ~valid).any())
    reason = "" if valid.any() else (REASON_NOT_CONVERGED if found.any() else start.reason[()])
    return wrap_angle(q), valid, pe, re, flags, reason


def off_the_edge(exact, starts, started, errors, tol):
    r"""The starts that reach their pose only by clipping the elbow (:math:`\sin\theta_3 = 0`,
    beyond the exact arm's reach by ``errors``) bent to their own elbow's side by
    :math:`\delta = \sqrt{2 R e / |a_2 a_3|}` (at least 0.01 rad), :math:`R = |a_2 + a_3|`:
    Newton cannot leave the singularity, the calibrated arm may reach past it."""
    a2, a3 = exact.links[1].a, exact.links[2].a
    theta3 = starts[:, 2] + exact.links[2].theta_offset
    edge = started & (errors > tol) & (np.abs(np.sin(theta3)) < 1e-6)
    delta = np.maximum(np.sqrt(2 * abs(a2 + a3) * errors / abs(a2 * a3)), 0.01)
    up = np.where(np.arange(8) // 2 % 2 == 0, 1.0, -1.0)    # row 4 s + 2 e + w: elbow e up
    starts[edge, 2] += (up * np.sign(np.cos(theta3)) * np.sign(a2 * a3) * delta)[edge]
    return starts


def is_new(q, known):
    """Whether the joint vector ``q`` differs from every row of ``known`` (by 1e-6 rad)."""
    return not (np.abs(wrap_angle(known - q)).max(axis=-1) < 1e-6).any()


def near_exact(exact, q, threshold=0.04):
    """Which rows of ``q`` (8, 6) are near a singularity of the exact arm: a measure of
    :func:`~dqlab.ik.ur_closed_form.branch_measures` below ``threshold`` (h over
    :math:`|a_2|`)."""
    h, sin_theta3, sin_theta5 = branch_measures(exact, q)
    return ((np.abs(sin_theta3) < threshold) | (np.abs(sin_theta5) < threshold)
            | (np.abs(h) < threshold * abs(exact.links[1].a)))


def singular_direction(arm, q):
    r"""The most singular direction of :math:`J^\mathsf{T} J` at ``q``, its largest entry
    positive, if its smallest eigenvalue is below 1e-4 of its largest; else None."""
    J = arm.fk_with_jacobian(q)[1]
    w, V = np.linalg.eigh(J.T @ J)
    return V[:, 0] * np.sign(V[np.abs(V[:, 0]).argmax(), 0]) if w[0] < 1e-4 * w[-1] else None


def polish(arm, exact, X_0T, q, converged, tol):
    r"""Three Newton steps more, in place, for the rows ``converged`` near a singularity of
    the exact arm (:math:`|\sin\theta_3|`, :math:`|\sin\theta_5|` or :math:`|h|/|a_2|` of
    :func:`~dqlab.ik.ur_closed_form.branch_measures` below 0.04), where a row
    stopped at ``tol / 10`` may lie :math:`10^{-10}/\sigma_{\min}(J)` rad from its solution."""
    for k in np.flatnonzero(converged & near_exact(exact, q)):
        q_k = q[k]
        for _ in range(3):
            q_k = q_k + newton_step(arm, q_k, X_0T)[0]
        if max(pose_errors(arm.fk(q_k), X_0T)) <= tol:
            q[k] = q_k


def repair(arm, exact, X_06, X_0T, q, converged, started, tol):
    """Fill the rows ``started`` but not ``converged`` in place, from the exact arm's wrist
    family (the closed form with a loose tolerance and :math:`\\theta_6` references) and
    from deflated Newton started near each solution found, along its most singular
    direction. A start that converges to a new solution takes the missing row of its own
    branch (:func:`~dqlab.ik.ur_solver.ur_branch`), or else the first missing row."""
    family = [exact_ur(exact, X_06, tol=0.5, q_ref=[0, 0, 0, 0, 0, t]) for t in FAMILY]
    candidates = [(s, ()) for member in family for s in member.solutions[member.valid]]
    for q_k in q[converged]:
        v = singular_direction(arm, q_k)
        if v is not None:                       # near a singularity: move off it both ways
            candidates += [(q_k + t * v, q[converged]) for t in MOVES]
    for q_start, known in candidates:
        missing = started & ~converged
        if not missing.any():
            return
        if len(known):                  # deflated steps away from the known solutions
            q_start, _ = newton(arm, q_start, X_0T, tol, RESTART_ITER, known)
        q_end, ok = newton(arm, q_start, X_0T, tol, RESTART_ITER)   # then plain ones
        if ok and is_new(q_end, q[converged]):
            k = int(ur_branch(exact, q_end))
            k = k if missing[k] else int(np.flatnonzero(missing)[0])
            q[k], converged[k] = q_end, True


def beyond(arm, exact, X_0T, q, tol):
    """The solutions of a pose beyond its eight valid rows ``q`` (8, 6), (m, 6), m <= 8:
    from each row near a singularity of both arms, deflated Newton (the rows deflated)
    0.05 rad either way along its most singular direction, then plain Newton."""
    more = np.zeros((0, 6))
    for q_k in q[near_exact(exact, q)]:
        v = singular_direction(arm, q_k)
        for t in (0.05, -0.05) if v is not None else ():
            q_start, _ = newton(arm, q_k + t * v, X_0T, tol, RESTART_ITER, q)
            q_end, ok = newton(arm, q_start, X_0T, tol)
            if (ok and max(pose_errors(arm.fk(q_end), X_0T)) <= tol and len(more) < 8
                    and not one_of(arm, q_end, np.vstack([q, more]), X_0T, tol)):
                more = np.vstack([more, wrap_angle(q_end)])
    return more


def one_of(arm, q, known, X_0T, tol):
    """Whether the solution ``q`` is one of ``known``: within 1e-6 rad of one, or within
    0.1 rad and the midpoint reaching the pose to ``tol`` (where two solutions meet, the
    error is flat between them and Newton stops anywhere along it)."""
    gap = np.abs(wrap_angle(known - q)).max(axis=-1)
    middle = q + 0.5 * wrap_angle(known[gap < 0.1] - q)
    return bool((gap < 1e-6).any() or any(max(pose_errors(arm.fk(m), X_0T)) <= tol
                                            for m in middle))


def singularity_flags(arm, q, valid, d4, singular_tol, near_tol):
    """The flags of the valid rows at their joints ``q`` (8, 6): the sines between joint
    axes 4 and 6 (wrist) and between the common normals x_2, x_3 (elbow), the wrist centre's
    distance from the plane of joint 1 and joint 2's axis over d_4 (shoulder)."""
    F = arm.fk(q, all_frames=True)                       # frames 0..6, in frame 0
    z1, z3, z5, x2, x3, o5 = (F[:, 1, :3, 2], F[:, 3, :3, 2], F[:, 5, :3, 2], F[:, 2, :3, 0],
                              F[:, 3, :3, 0], F[:, 5, :3, 3])
    wrist = np.linalg.norm(np.cross(z3, z5), axis=-1)
    elbow = np.linalg.norm(np.cross(x2, x3), axis=-1)
    shoulder = np.abs(z1[:, 0] * o5[:, 1] - z1[:, 1] * o5[:, 0]) / np.hypot(*z1[:, :2].T) / d4
    measures = {"wrist_singular": wrist, "shoulder_singular": shoulder, "elbow_singular": elbow,
                "near_singular": np.minimum(np.minimum(wrist, elbow), shoulder)}
    limit = {name: singular_tol for name in measures} | {"near_singular": near_tol}
    flags = {name: bool((valid & (m < limit[name])).any()) for name, m in measures.items()}
    flags["unreachable"] = not valid.any()
    return flags
