r"""Following a Cartesian path with a robot: joint positions, speeds and accelerations.

Two ways, as chapter 11 of the book compares them:

- :func:`follow_path_ur` -- the closed-form UR solver (:func:`dqlab.ik.ur_solver.ur`) on
  the whole path at once, with **branch tracking**: keep the same shoulder/elbow/wrist row along the
  path, take for each joint the :math:`2\pi`-equivalent nearest the previous point, and
  report every place where the row must change (a singularity crossed, or a jump);
- :func:`follow_path_numerical` -- the UR3 report's method: numerical inverse kinematics of
  the tool position only, warm-started from the previous point.

In both, :math:`\dot q = J^+ \dot x` (:func:`joint_velocities`, optionally damped) and
:math:`\ddot q` is the central difference of :math:`\dot q` on the time grid, as in the
report.
"""

from dataclasses import dataclass, field, replace

import numpy as np

from .._checks import as_float_array, check_instance, check_scalar
from ..ik import SOLUTION_ORDER, IKResult, numerical, ur
from ..ik.ur_calibrated import nominal_ur
from ..ik.ur_steps import NEAR_SINGULAR
from ..models import UR_SHAPE
from ..robot import Robot
from ..rotations import wrap_angle
from .cartesian import CartesianPath
from .joint import Trajectory

__all__ = ["BranchSwitch", "SingularPass", "FollowReport", "follow_path_ur",
           "follow_path_numerical", "joint_velocities", "track_branches",
           "ur_singularity_margins", "singular_passes"]


def joint_velocities(J, twist, *, damping=0.0):
    r"""Joint speeds that produce a tool velocity: pseudo-inverse or damped least squares.

    .. math::

        \dot q = J^\top \bigl(J J^\top + \lambda^2 I\bigr)^{-1} \dot x ,

    which is :math:`J^+ \dot x` for :math:`\lambda = 0` and a full-row-rank :math:`J`
    (the exact inverse when :math:`J` is square). With :math:`\lambda > 0` every singular
    value :math:`\sigma` of :math:`J` is inverted as :math:`\sigma / (\sigma^2 +
    \lambda^2) \le 1 / (2\lambda)`: the speeds stay bounded near a singularity, at the
    price of a tool velocity error there.

    Parameters
    ----------
    J : array_like, shape (..., m, n)
        Jacobians (for example the 3 linear rows :math:`J_v`, or all 6).
    twist : array_like, shape (..., m)
        Desired tool velocities :math:`\dot x`.
    damping : float
        :math:`\lambda >= 0` (same units as :math:`\sigma`: metres for :math:`J_v`).

    Returns
    -------
    ndarray, shape (..., n)

    Examples
    --------
    >>> import numpy as np
    >>> J = np.array([[1.0, 0.0], [0.0, 1e-6]])       # nearly singular
    >>> joint_velocities(J, [0.0, 1.0])
    array([      0., 1000000.])
    >>> joint_velocities(J, [0.0, 1.0], damping=0.01).round(6)
    array([0.  , 0.01])
    """
    J = as_float_array(J, "J")
    x = as_float_array(twist, "twist")
    if J.ndim < 2:
        raise ValueError(f"J must have shape (..., m, n), got shape {J.shape}")
    if x.shape[-1:] != J.shape[-2:-1]:
        raise ValueError(f"twist must have shape (..., {J.shape[-2]}) to match J of shape "
                         f"{J.shape}, got {x.shape}")
    lam = check_scalar(damping, "damping", minimum=0)
    # q_dot does not change when J, twist and lambda are divided by the same number, and
    # (J / k)(J / k)^T neither overflows nor underflows for k the largest |J_ij|
    k = np.max(np.abs(J), axis=(-2, -1), keepdims=True)
    k = np.where(k > 0.0, k, 1.0)
    Js, xs = J / k, x[..., None] / k
    with np.errstate(over="ignore", under="ignore"):
        lam_s = lam / k
        # lambda far above every singular value (|J_s| <= 1): q_dot = J^T x / lambda^2
        huge = lam_s > 1e100
        Jt = np.swapaxes(Js, -1, -2)
        A = Js @ Jt + np.where(huge, 1.0, lam_s) ** 2 * np.eye(J.shape[-2])
        try:
            q_dot = (Jt @ np.linalg.solve(A, xs))[..., 0]
        except np.linalg.LinAlgError:             # exactly rank deficient: J^+ by SVD
            q_dot = (np.linalg.pinv(Js) @ xs)[..., 0]
        if huge.any():
            q_dot = np.where(huge[..., 0], (Jt @ xs)[..., 0] / lam_s[..., 0] / lam_s[..., 0],
                             q_dot)
    if not np.isfinite(q_dot).all():
        raise ValueError("the joint velocities overflow: the twist is too large for J "
                         "(or J too close to singular without damping)")
    return q_dot


def ur_singularity_margins(robot, q):
    r"""How far UR configurations are from the arm's singularities and reach limits.

    - ``"wrist"``: :math:`|\sin\theta_5|` (0 when the axes of joints 4 and 6 align);
    - ``"elbow"``: :math:`|\sin\theta_3|` (0 with the forearm straight or folded);
    - ``"reach"``: :math:`|a_2| + |a_3| - \rho` in metres, the distance of the wrist-1
      point from the outer reach circle of the shoulder--elbow pair, with
      :math:`\rho^2 = a_2^2 + a_3^2 + 2 a_2 a_3 \cos\theta_3`;
    - ``"shoulder"``: :math:`\sqrt{x_5^2 + y_5^2} - |d_4| = \sqrt{h^2 + d_4^2} - |d_4|`
      in metres, the distance of the wrist centre :math:`p_5` (base frame) from the
      cylinder about the base axis where the shoulder is singular; :math:`h = c_1 x_5 +
      s_1 y_5 = a_2 c_2 + a_3 c_{23} + d_5 s_{234}` is the wrist centre's coordinate along
      the arm, the quantity :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` tests.

    All four come from the joint angles, without forward kinematics, and from the UR's
    standard DH lengths: those of the robot, or for a calibrated UR (whose table holds far
    common normals on the parallel joints) those of its nearest exact UR
    (:func:`dqlab.ik.ur_calibrated.nominal_ur`), which differ by millimetres.

    Parameters
    ----------
    robot : Robot
        A UR-family arm in standard DH (exact or calibrated).
    q : array_like, shape (..., 6)

    Returns
    -------
    dict of str to ndarray, shape (...)

    Raises
    ------
    ValueError
        If the robot is in modified DH (the formulas read a standard-DH table: use the
        standard-DH model, such as :func:`dqlab.models.ur3`) or is not a UR-family arm.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> m = ur_singularity_margins(ur3(), [0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> {k: round(float(v), 4) for k, v in m.items()}
    {'wrist': 0.7833, 'elbow': 0.8912, 'reach': 0.0671, 'shoulder': 0.2471}
    """
    check_instance(robot, Robot, "robot")
    q = robot.check_joints(q)
    if robot.n != 6:
        raise ValueError(f"robot: a UR-family arm has 6 joints, this robot has {robot.n}")
    if robot.convention != "dh":
        raise ValueError("robot: ur_singularity_margins reads a UR's standard DH table, and "
                         f"this robot is in modified DH ({robot.name or 'unnamed'}); use "
                         "the standard-DH model of the arm, such as dqlab.models.ur3()")
    links = _ur_links(robot)
    theta = q + np.array([lk.theta_offset for lk in links])
    a2, a3, d4, d5 = links[1].a, links[2].a, links[3].d, links[4].d
    t2, t23 = theta[..., 1], theta[..., 1] + theta[..., 2]
    rho = np.sqrt(np.maximum(a2 * a2 + a3 * a3 + 2 * a2 * a3 * np.cos(theta[..., 2]), 0.0))
    h = a2 * np.cos(t2) + a3 * np.cos(t23) + d5 * np.sin(t23 + theta[..., 3])
    return {"wrist": np.abs(np.sin(theta[..., 4])),
            "elbow": np.abs(np.sin(theta[..., 2])),
            "reach": abs(a2) + abs(a3) - rho,
            "shoulder": np.hypot(h, d4) - abs(d4)}


def _ur_links(robot):
    """The standard-DH links of a UR (exact, or a calibrated UR's nearest exact UR)."""
    try:
        UR_SHAPE.check(robot)
        return robot.links
    except ValueError:
        try:
            return nominal_ur(robot).links          # a calibrated UR: its nearest exact UR
        except ValueError as why:
            raise ValueError(f"robot: ur_singularity_margins needs a UR-family arm: {why}") \
                from None


@dataclass(frozen=True)
class BranchSwitch:
    """A place on the path where the tracked solution row changes.

    Attributes
    ----------
    index : int
        First path point on the new row.
    time : float
        Its instant, seconds.
    from_row, to_row : int
        Rows of :data:`dqlab.ik.ur_closed_form.SOLUTION_ORDER` before and after (equal for a
        jump that no row avoids).
    step : float
        Largest joint change from the previous point, radians.
    kind : str
        ``"singularity"`` when the motion stays continuous (the row labels change because a
        singularity is crossed, for example :math:`\\theta_5` changing sign), ``"jump"``
        when no row continues the motion within ``max_step``.
    reason : str
        Why the previous row could not be kept.
    """

    index: int
    time: float
    from_row: int
    to_row: int
    step: float
    kind: str
    reason: str

    def __str__(self):
        a = "/".join(SOLUTION_ORDER[self.from_row])
        b = "/".join(SOLUTION_ORDER[self.to_row])
        return (f"t = {self.time:.3f} s (point {self.index}): {self.kind}, row {self.from_row} "
                f"({a}) -> {self.to_row} ({b}), step {self.step:.3g} rad; {self.reason}")


@dataclass(frozen=True)
class SingularPass:
    r"""A stretch of a followed path within ``near_tol`` of a singularity of the arm.

    Attributes
    ----------
    kind : str
        ``"wrist"`` (:math:`|\sin\theta_5|`), ``"elbow"`` (:math:`|\sin\theta_3|`) or
        ``"shoulder"`` (:math:`h / |d_4|`, the wrist centre's distance from the plane
        of the base axis and joint 2's direction over :math:`d_4`), the measures of
        :func:`ur_singularity_margins`.
    index, time : int, float
        The point of the stretch nearest the singularity, and its instant (seconds).
    measure : float
        The smallest measure on the stretch.
    first, last : int
        The stretch's first and last points.
    speed : float
        The largest joint speed on the stretch (rad/s), and ``joint`` (1-based) the joint
        that reaches it: near a singularity a Cartesian path asks for joint speeds that
        grow as the measure shrinks.
    joint : int
    """

    kind: str
    index: int
    time: float
    measure: float
    first: int
    last: int
    speed: float
    joint: int

    @property
    def closest(self):
        """The smallest measure, with its name: ``"|sin q5| = 0.002"``."""
        what = {"wrist": "|sin q5|", "elbow": "|sin q3|", "shoulder": "h / d4"}[self.kind]
        return f"{what} = {self.measure:.2g}"

    def __str__(self):
        return (f"t = {self.time:.3f} s (point {self.index}): passes the {self.kind} "
                f"singularity, {self.closest}; joint {self.joint} at {self.speed:.3g} "
                f"rad/s (points {self.first}-{self.last})")


def singular_passes(margins, qd, t, d4, near_tol=NEAR_SINGULAR):
    r"""The stretches of a path within ``near_tol`` of a singularity, each one
    :class:`SingularPass`.

    Parameters
    ----------
    margins : dict of str to ndarray, shape (N,)
        :func:`ur_singularity_margins` along the path.
    qd : ndarray, shape (N, 6)
        The joint speeds along it.
    t : ndarray, shape (N,)
        Its instants.
    d4 : float
        The arm's :math:`d_4` (the shoulder margin is read as :math:`h / |d_4|`, with
        :math:`h^2 = (m + |d_4|)^2 - d_4^2` from the margin :math:`m`).
    near_tol : float
        The threshold of the measures (default
        :data:`dqlab.ik.ur_steps.NEAR_SINGULAR`, 0.01), as ``near_tol`` of
        :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`.

    Returns
    -------
    list of SingularPass
        In the order of the path.

    Examples
    --------
    >>> import numpy as np
    >>> m = {"wrist": np.array([0.5, 0.005, 0.002, 0.3]), "elbow": np.ones(4),
    ...      "shoulder": np.ones(4)}
    >>> qd = np.zeros((4, 6)); qd[2, 3] = 60.0
    >>> [p] = singular_passes(m, qd, np.arange(4) * 0.1, 0.13)
    >>> p.kind, p.index, p.closest, p.joint, p.speed, (p.first, p.last)
    ('wrist', 2, '|sin q5| = 0.002', 4, 60.0, (1, 2))
    """
    near_tol = check_scalar(near_tol, "near_tol", minimum=0)
    d4 = check_scalar(d4, "d4")
    if d4 == 0.0:
        raise ValueError("d4 must not be 0 (the shoulder margin is read over |d4|)")
    qd = as_float_array(qd, "qd", (6,))
    t = as_float_array(t, "t")
    if qd.ndim != 2 or t.shape != qd.shape[:1]:
        raise ValueError(f"qd must have shape (N, 6) and t shape (N,), got {qd.shape} and "
                         f"{t.shape}")
    if not isinstance(margins, dict) or not {"wrist", "elbow", "shoulder"} <= set(margins):
        raise ValueError("margins must be the dict of ur_singularity_margins (wrist, elbow, "
                         "shoulder)")
    wrist, elbow, shoulder = (as_float_array(margins[k], f"margins['{k}']") for k in
                              ("wrist", "elbow", "shoulder"))
    if not wrist.shape == elbow.shape == shoulder.shape == t.shape:
        raise ValueError(f"margins must hold arrays of shape {t.shape}, one value per point")
    h = np.sqrt(np.maximum((shoulder + abs(d4)) ** 2 - d4 * d4, 0.0))
    measures = {"wrist": wrist, "elbow": elbow, "shoulder": h / abs(d4)}
    speed = np.abs(qd)
    passes = []
    for kind, measure in measures.items():
        near = measure < near_tol
        if not near.any():
            continue
        edges = np.flatnonzero(np.diff(np.concatenate([[0], near.astype(np.int8), [0]])))
        for first, end in zip(edges[::2], edges[1::2], strict=True):
            index = first + int(np.argmin(measure[first:end]))
            peak = np.unravel_index(int(np.argmax(speed[first:end])), speed[first:end].shape)
            passes.append(SingularPass(kind, int(index), float(t[index]),
                                       float(measure[index]), int(first), int(end - 1),
                                       float(speed[first:end][peak]), int(peak[1]) + 1))
    return sorted(passes, key=lambda p: p.first)


@dataclass(frozen=True)
class FollowReport:
    """What happened while following a path.

    Attributes
    ----------
    method : str
        ``"closed-form"`` or ``"numerical"``.
    position_error, rotation_error : ndarray, shape (N,)
        Distance (m) and angle (rad) between each point's solution and its target, as the
        solver measures them: the numerical method by the forward kinematics; the closed
        form by the residual of its equations (the clipping of its steps, the default
        ``residuals="equations"`` of :func:`dqlab.ik.ur_solver.ur`), which is exactly 0
        when no step was clipped, so an independent check takes ``robot.fk`` of the joints. The
        rotation error is 0 when only positions were followed.
    max_step : ndarray, shape (N - 1,)
        Largest joint change between consecutive points, radians.
    margins : dict of str to ndarray (N,)
        :func:`ur_singularity_margins` along the path.
    branch : ndarray of int, shape (N,), optional
        The solution row used at each point (closed form only).
    switches : list of BranchSwitch
        Every change of row (closed form only); one at a point within ``near_tol`` of a
        singularity says so in its ``reason``.
    singularities : list of SingularPass
        Every stretch of the path within ``near_tol`` of a singularity, with the joint
        speed it asks for there (:func:`singular_passes`).
    """

    method: str
    position_error: np.ndarray
    rotation_error: np.ndarray
    max_step: np.ndarray
    margins: dict
    branch: np.ndarray = None
    switches: list = field(default_factory=list)
    singularities: list = field(default_factory=list)

    def summary(self):
        """A few lines for printing."""
        lines = [f"{self.method} following of {self.position_error.size} points: position "
                 f"error <= {self.position_error.max():.2e} m, rotation error <= "
                 f"{self.rotation_error.max():.2e} rad, largest joint step "
                 f"{self.max_step.max(initial=0.0):.4f} rad"]
        lines.append("smallest margins: " + ", ".join(
            f"{k} {v.min():.4f}" for k, v in self.margins.items()))
        if self.branch is not None:
            lines.append(f"{len(self.switches)} branch switch(es)" + "".join(
                "\n  " + str(s) for s in self.switches))
        if self.singularities:
            lines.append(f"{len(self.singularities)} pass(es) near a singularity" + "".join(
                "\n  " + str(p) for p in self.singularities))
        return "\n".join(lines)


def _row_index(branch):
    if isinstance(branch, (int, np.integer)) and not isinstance(branch, (bool, np.bool_)):
        if not 0 <= branch < 8:
            raise ValueError(f"branch must be a row 0..7 or a label tuple, got {branch!r}")
        return int(branch)
    try:
        return SOLUTION_ORDER.index(tuple(branch))
    except (TypeError, ValueError):
        raise ValueError(f"branch must be a row 0..7 or one of {SOLUTION_ORDER}, got "
                         f"{branch!r}") from None


def _check_path(path):
    check_instance(path, CartesianPath, "path")


def _acceptance_tolerance(tol):
    """``tol`` of a solver that accepts a solution within it: a number >= 0 and finite (with
    an infinite tolerance any joint vector would pass for a solution)."""
    return check_scalar(tol, "tol", minimum=0)


def track_branches(result, *, q_start=None, branch=None, max_step=0.1, t=None):
    r"""Follow one solution branch through a batch of closed-form IK results.

    Given the eight rows of :func:`dqlab.ik.ur_solver.ur` at consecutive points of a path,
    keep the starting row, unwrap its angles (each joint takes the :math:`2\pi`-equivalent nearest
    its previous value, :math:`q_k = q_{k-1} + \operatorname{wrap}(\theta_k - q_{k-1})`),
    and where that row is invalid or would move a joint by more than ``max_step``, continue
    with the valid row nearest the previous point, recording a :class:`BranchSwitch`. The
    work is done with array operations between switches.

    Parameters
    ----------
    result : IKResult
        Of :func:`dqlab.ik.ur_solver.ur` for N consecutive poses: ``solutions`` (N, 8, 6).
    q_start : array_like, shape (6,), optional
        Where the arm starts: picks the starting row (nearest modulo :math:`2\pi`) and the
        equivalents of the first point.
    branch : int or tuple of str, optional
        Starting row, ``4 s + 2 e + w`` or a label of :data:`dqlab.ik.ur_closed_form.SOLUTION_ORDER`
        (default: the row nearest ``q_start``, else the first valid row).
    max_step : float
        Largest joint change between consecutive points that counts as continuous (rad).
    t : array_like, shape (N,), optional
        Instants, for the switch records (default: the point indices).

    Returns
    -------
    q : ndarray, shape (N, 6)
        The tracked joint positions (unwrapped, so they may leave :math:`(-\pi, \pi]`).
    rows : ndarray of int, shape (N,)
        The row used at each point.
    switches : list of BranchSwitch

    Raises
    ------
    ValueError
        If some point has no valid row, or ``branch`` is not valid at the first point.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> from dqlab.ik import ur
    >>> robot = ur3()
    >>> q_path = np.linspace([3.0, -1.0, 1.2, -1.5, 1.0, 3.0], [3.4, -1.2, 1.0, -1.3, 1.2, 3.4],
    ...                      50)                   # joints 1 and 6 cross pi
    >>> q, rows, switches = track_branches(ur(robot, robot.fk(q_path)), q_start=q_path[0])
    >>> bool(np.allclose(q, q_path)), set(rows.tolist()), switches
    (True, {4}, [])
    """
    check_instance(result, IKResult, "result")
    sol, valid = result.solutions, result.valid
    if sol.ndim != 3 or sol.shape[1:] != (8, 6) or valid.shape != sol.shape[:2]:
        raise ValueError(f"result must hold solutions of shape (N, 8, 6), got {sol.shape}")
    N = sol.shape[0]
    if N == 0:
        raise ValueError("result holds no point (N = 0): there is nothing to track")
    if not np.all(valid.any(axis=-1)):
        i = int(np.argmin(valid.any(axis=-1)))
        raise ValueError(f"point {i} has no valid solution: {result.reason[i]}")
    t = np.arange(N, dtype=float) if t is None else as_float_array(t, "t")
    if t.shape != (N,):
        raise ValueError(f"t must have shape ({N},), one instant per point of result, "
                         f"got shape {t.shape}")
    max_step = check_scalar(max_step, "max_step", minimum=0, strict=True, finite=False)
    if q_start is not None:
        q_start = as_float_array(q_start, "q_start")
        if q_start.shape != (6,):
            raise ValueError(f"q_start must have shape (6,), got {q_start.shape}")
    if branch is not None:
        row = _row_index(branch)
        if not valid[0, row]:
            raise ValueError(f"branch {row} {SOLUTION_ORDER[row]} has no solution at the first "
                             f"point; valid rows: {np.flatnonzero(valid[0]).tolist()}")
    elif q_start is not None:
        dist = np.max(np.abs(wrap_angle(sol[0] - q_start)), axis=-1)
        row = int(np.argmin(np.where(valid[0], dist, np.inf)))
    else:
        row = int(np.argmax(valid[0]))
    q_prev = sol[0, row] if q_start is None else q_start
    q = np.empty((N, 6))
    rows = np.empty(N, dtype=int)
    switches = []
    i = 0
    while i < N:
        seg = sol[i:, row]
        steps = wrap_angle(np.diff(seg, axis=0))
        bad = ~valid[i:, row]
        bad[1:] |= np.max(np.abs(steps), axis=-1) > max_step
        bad[0] = False
        j = int(np.argmax(bad)) if bad.any() else seg.shape[0]
        first = q_prev + wrap_angle(seg[0] - q_prev)
        q[i] = first
        np.cumsum(steps[:j - 1], axis=0, out=q[i + 1:i + j])
        q[i + 1:i + j] += first
        rows[i:i + j] = row
        if j == seg.shape[0]:
            break
        k = i + j
        q_prev = q[k - 1]
        dist = np.max(np.abs(wrap_angle(sol[k] - q_prev)), axis=-1)
        new = int(np.argmin(np.where(valid[k], dist, np.inf)))
        why = ("the row has no valid solution here" if not valid[k, row] else
               f"the row would move a joint by "
               f"{np.max(np.abs(wrap_angle(sol[k, row] - q_prev))):.3g} rad")
        switches.append(BranchSwitch(index=k, time=float(t[k]), from_row=row, to_row=new,
                                     step=float(dist[new]),
                                     kind="singularity" if dist[new] <= max_step else "jump",
                                     reason=why))
        row, i = new, k
    return q, rows, switches


def follow_path_ur(robot, path, *, q_start=None, branch=None, max_step=0.1, damping=0.0,
                   tol=1e-9, near_tol=NEAR_SINGULAR):
    r"""Follow a Cartesian path with the closed-form UR solver and branch tracking.

    1. Every pose of the path is solved at once by :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` (all
       eight rows).
    2. The starting row is ``branch``, or the valid row nearest ``q_start`` (modulo
       :math:`2\pi`), or the first valid row.
    3. Along the path the same row is kept and unwrapped: each joint takes the
       :math:`2\pi`-equivalent nearest its previous value,
       :math:`q_k = q_{k-1} + \operatorname{wrap}(\theta_k - q_{k-1})`.
    4. Where the row is not valid, or where it would move a joint by more than ``max_step``
       between two points, the valid row nearest the previous point is taken instead and
       the change is recorded as a :class:`BranchSwitch` (``"singularity"`` if that row
       continues the motion within ``max_step``, ``"jump"`` if no row does).
    5. :math:`\dot q = J^{-1} (\dot p, \omega)` (:func:`joint_velocities`, optionally
       damped) and :math:`\ddot q` the central difference of :math:`\dot q`
       (``numpy.gradient``).
    6. Every stretch within ``near_tol`` of a singularity is named in the report
       (``report.singularities``): there a Cartesian path asks for joint speeds that grow
       as the measure shrinks (a straight line through the wrist singularity turns joints
       4 and 6 at hundreds of rad/s), which a program's speed check refuses later; a branch
       switch there says which singularity it is at.

    Parameters
    ----------
    robot : Robot
        A UR-family arm (standard DH).
    path : CartesianPath
        With an orientation (see :meth:`dqlab.trajectory.cartesian.CartesianPath.with_orientation`).
    q_start : array_like, shape (6,), optional
        The configuration the arm starts from; the first point is the equivalent of the
        chosen row nearest it.
    branch : int or tuple of str, optional
        Starting row, ``4 s + 2 e + w`` or a label such as ``("left", "up", "noflip")``.
    max_step : float
        Largest joint change between consecutive points (radians) that counts as
        continuous. At 5 ms and a few cm/s a regular path moves the UR3's joints by about
        :math:`10^{-3}` rad per point.
    damping : float
        :math:`\lambda` of :func:`joint_velocities` (0: the exact inverse).
    tol : float
        Passed to :func:`dqlab.ik.ur_solver.ur`: every point reproduces its pose to ``tol``.
    near_tol : float
        A stretch of the path where :math:`|\sin\theta_5|`, :math:`|\sin\theta_3|` or
        :math:`h / d_4` is below it passes a singularity: it is reported
        (``report.singularities``, :func:`singular_passes`), with the joint speed it asks
        for, and a branch switch there names it (default 0.01, as ``dqlab.ik.ur``).

    Returns
    -------
    trajectory : Trajectory
        With ``poses`` the targets.
    report : FollowReport

    Raises
    ------
    ValueError
        If a pose of the path has no solution (naming the first), the path has no
        orientation, the starting branch is not valid at the first pose, or the tracked
        joints leave the robot's joint limits.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> from dqlab import rot_x
    >>> from dqlab.trajectory import circle_three_phase
    >>> robot = ur3()
    >>> path = circle_three_phase([0.0, -0.35, 0.25], 0.1, 0.05, dt=0.05,
    ...                           orientation=rot_x(np.pi / 2))
    >>> traj, report = follow_path_ur(robot, path, branch=("right", "up", "noflip"))
    >>> len(traj), len(report.switches), bool(report.position_error.max() < 1e-9)
    (440, 0, True)
    """
    check_instance(robot, Robot, "robot")
    _check_path(path)
    tol = _acceptance_tolerance(tol)
    poses = path.poses
    N = len(path)
    res = ur(robot, poses, tol=tol)
    if not np.all(res.success):
        i = int(np.argmin(res.success))
        raise ValueError(f"path point {i} (t = {path.t[i]:.4g} s, position "
                         f"{np.round(path.position[i], 6).tolist()}) has no IK solution: "
                         f"{res.reason[i]}")
    if q_start is not None:
        q_start = robot.check_joints(q_start, name="q_start")
    q, rows, switches = track_branches(res, q_start=q_start, branch=branch,
                                       max_step=max_step, t=path.t)
    lo, hi = robot.limits.T
    outside = (q < lo) | (q > hi)
    if outside.any():
        k, jnt = np.argwhere(outside)[0]
        raise ValueError(f"the tracked joints leave the joint limits: joint {jnt + 1} = "
                         f"{q[k, jnt]:.6g} rad at point {k} (t = {path.t[k]:.4g} s); start "
                         f"from another q_start or branch")
    qd = joint_velocities(robot.jacobian(q), path.twist, damping=damping)
    qdd = np.gradient(qd, path.t, axis=0) if N > 1 else np.zeros_like(qd)
    pick = (np.arange(N), rows)
    margins = ur_singularity_margins(robot, q)
    passes = singular_passes(margins, qd, path.t, _ur_links(robot)[3].d, near_tol)
    report = FollowReport(
        method="closed-form", position_error=res.position_error[pick],
        rotation_error=res.rotation_error[pick],
        max_step=np.max(np.abs(np.diff(q, axis=0)), axis=-1),
        margins=margins, branch=rows, switches=_named(switches, passes),
        singularities=passes)
    return Trajectory(t=path.t, q=q, qd=qd, qdd=qdd, poses=poses), report


def _named(switches, passes):
    """The switches, each within a pass near a singularity (or next to one) with that
    singularity named in its reason."""
    named = []
    for switch in switches:
        near = [p for p in passes if p.first - 1 <= switch.index <= p.last + 1]
        if near:
            p = min(near, key=lambda p: p.measure)
            switch = replace(switch, reason=f"{switch.reason}; at the {p.kind} singularity "
                                            f"({p.closest})")
        named.append(switch)
    return named


def follow_path_numerical(robot, path, q_start, *, damping=0.0, tol=1e-10, max_iter=100,
                          near_tol=NEAR_SINGULAR):
    r"""Follow the positions of a path as the UR3 report does: numerical IK, warm start.

    For each point :math:`k`, :math:`q_k` solves :math:`p(q_k) = p_k` by damped least
    squares (:func:`dqlab.ik.damped_least_squares.numerical`, position only) starting from
    :math:`q_{k-1}`
    (from ``q_start`` for the first point); then :math:`\dot q_k = J_v(q_k)^+ \dot p_k`
    (:func:`joint_velocities` with the three linear rows, optionally damped) and
    :math:`\ddot q` is the central difference of :math:`\dot q`. The orientation of the
    tool is left free: six joints for three constraints, the warm start picks the
    solution near the previous one.

    Parameters
    ----------
    robot : Robot
    path : CartesianPath
    q_start : array_like, shape (n,)
        Initial guess for the first point.
    damping : float
        :math:`\lambda` of the joint speeds (0: :math:`J_v^+`, the report's choice).
    tol : float
        Position tolerance of each solve, metres.
    max_iter : int
        Iteration limit of each solve.
    near_tol : float
        As for :func:`follow_path_ur`: the passes near a singularity reported.

    Returns
    -------
    trajectory : Trajectory
        Without ``poses`` (the orientation is not prescribed).
    report : FollowReport

    Raises
    ------
    ValueError
        If a point is not reached (naming it and the solver's reason).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> from dqlab.trajectory import circle_three_phase
    >>> path = circle_three_phase([0.0, -0.35, 0.25], 0.1, 0.05, dt=0.5)
    >>> traj, report = follow_path_numerical(ur3(), path,
    ...                                      [-1.1, -1.9, -1.9, 0.6, 1.1, 3.1])
    >>> len(traj), bool(report.position_error.max() <= 1e-10)
    (44, True)
    """
    check_instance(robot, Robot, "robot")
    _check_path(path)
    q_prev = robot.check_joints(q_start, name="q_start")
    if q_prev.shape != (robot.n,):
        raise ValueError(f"q_start must have shape ({robot.n},), got shape {q_prev.shape}")
    damping = check_scalar(damping, "damping", minimum=0)
    tol = _acceptance_tolerance(tol)
    max_iter = check_scalar(max_iter, "max_iter", minimum=1, integer=True)
    N = len(path)
    q = np.empty((N, robot.n))
    error = np.empty(N)
    for k in range(N):
        res = numerical(robot, path.position[k], q_prev, position_only=True, tol=tol,
                        max_iter=max_iter)
        if not res.valid[0]:
            start = "q_start" if k == 0 else "the previous point"
            raise ValueError(f"path point {k} (t = {path.t[k]:.4g} s) not reached from {start} "
                             f"with tol = {tol:g} m and max_iter = {max_iter}: {res.reason}")
        q_prev = q[k] = res.solutions[0]
        error[k] = res.position_error[0]
    J_v = robot.jacobian(q)[:, :3, :]
    qd = joint_velocities(J_v, path.velocity, damping=damping)
    qdd = np.gradient(qd, path.t, axis=0) if N > 1 else np.zeros_like(qd)
    margins = ur_singularity_margins(robot, q)
    report = FollowReport(method="numerical", position_error=error,
                          rotation_error=np.zeros(N),
                          max_step=np.max(np.abs(np.diff(q, axis=0)), axis=-1),
                          margins=margins,
                          singularities=singular_passes(margins, qd, path.t,
                                                        _ur_links(robot)[3].d, near_tol))
    return Trajectory(t=path.t, q=q, qd=qd, qdd=qdd), report
