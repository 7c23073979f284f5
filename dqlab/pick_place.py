r"""A pick-and-place task for the desktop arm, driven by its closed-form inverse model.

The lab report drives its arm with a list of rows ``[x, y, z, suction, q3]``: go to the
point, then switch the suction cup on (1) or off (0); ``q3`` turns the cup about the
vertical. This module turns such a list into a timed joint trajectory that a robot may be
sent, in two steps (chapter 12):

1. :func:`joint_targets` -- every point to a joint target by
   :func:`dqlab.ik.desk_arm_closed_form.desk_arm`,
   always on the same branch (the arm facing the point, elbow up, by default); a point that
   is out of reach or whose solution breaks a joint limit is refused with the step's index;
2. :func:`plan_pick_place` -- rest-to-rest segments between consecutive targets with the
   quintic time law of :func:`dqlab.trajectory.joint.joint_trajectory` (chapter 10), a dwell
   where the cup switches, and the object carried by the cup
   while the suction is on; the result is checked once more (finite, within limits).

:func:`dqlab.viz.pick_place.animate_pick_place` plays a plan in a 3D scene.

A target is four numbers: the chain angles :math:`(\theta_1, \theta_2, \theta_3)` of
:func:`dqlab.models.desk_arm` and the wrist (cup) angle. The cup hangs vertically below the
hand (the parallelogram keeps it so) and turns about the vertical with the base and the
wrist: its yaw in the world is :math:`\theta_1 + q_{wrist}`.
"""

import math
from dataclasses import dataclass

import numpy as np

from . import ik
from ._checks import as_float_array, check_instance, check_scalar, check_tolerance
from .robot import Robot
from .trajectory import Trajectory, joint_trajectory
from .trajectory.time_laws import MAX_SAMPLES
from .transforms import check_transform

__all__ = ["PickPlaceTask", "PickPlacePlan", "task_from_lab", "joint_targets",
           "cup_poses", "plan_pick_place", "BRANCH_NAMES"]

#: The rows of :func:`dqlab.ik.desk_arm_closed_form.desk_arm`'s solutions, by name.
BRANCH_NAMES = ("facing, elbow up", "facing, elbow down", "turned away, elbow up",
                "turned away, elbow down")


@dataclass(frozen=True, eq=False)
class PickPlaceTask:
    """A pick-and-place task: where the cup goes, and what it does there.

    Attributes
    ----------
    positions : ndarray, shape (K, 3)
        Cup positions in the world frame, metres.
    suction : ndarray of bool, shape (K,)
        The cup's state once the step's position is reached (True: sucking).
    wrist : ndarray, shape (K,)
        Wrist angles in radians.
    """

    positions: np.ndarray
    suction: np.ndarray
    wrist: np.ndarray

    def __post_init__(self):
        p = as_float_array(self.positions, "positions", (3,))
        if p.ndim != 2 or len(p) == 0:
            raise ValueError(f"positions must have shape (K, 3) with K >= 1, got {p.shape}")
        k = len(p)
        s_num = as_float_array(self.suction, "suction")
        if s_num.shape != (k,):
            raise ValueError(f"suction must have shape ({k},), got {s_num.shape}")
        if not np.all((s_num == 0) | (s_num == 1)):
            bad = int(np.flatnonzero((s_num != 0) & (s_num != 1))[0])
            raise ValueError(f"suction must be 0 (off) or 1 (on); step {bad} has "
                             f"{float(s_num[bad]):g}")
        s = s_num == 1
        w = as_float_array(self.wrist, "wrist")
        if w.shape != (k,):
            raise ValueError(f"wrist must have shape ({k},), got {w.shape}")
        object.__setattr__(self, "positions", p)
        object.__setattr__(self, "suction", s)
        object.__setattr__(self, "wrist", w)

    def __len__(self):
        return len(self.positions)


def task_from_lab(rows):
    """A task from the lab's rows ``[x, y, z, suction, q3]`` in millimetres and degrees.

    Parameters
    ----------
    rows : array_like, shape (K, 5)
        Positions in mm, suction 1 (on) or 0 (off), wrist angle ``q3`` in degrees.

    Returns
    -------
    PickPlaceTask
        In metres and radians.

    Raises
    ------
    ValueError
        On a wrong shape, NaN, or a suction value other than 0 or 1 (naming the step).

    Examples
    --------
    >>> task = task_from_lab([[0, 170, 30, 1, 0], [0, -170, 35, 0, 180]])
    >>> task.positions
    array([[ 0.   ,  0.17 ,  0.03 ],
           [ 0.   , -0.17 ,  0.035]])
    >>> task.suction, task.wrist.round(6)
    (array([ True, False]), array([0.      , 3.141593]))
    """
    rows = as_float_array(rows, "rows", (5,))
    if rows.ndim != 2:
        raise ValueError(f"rows must have shape (K, 5), got shape {rows.shape}")
    try:
        return PickPlaceTask(positions=rows[:, :3] / 1000.0, suction=rows[:, 3],
                             wrist=np.radians(rows[:, 4]))
    except ValueError as exc:
        raise ValueError(f"rows: {exc}") from None


def _check_wrist_limits(wrist_limits):
    limits = as_float_array(wrist_limits, "wrist_limits")
    if limits.shape != (2,) or not limits[0] < limits[1]:
        raise ValueError(f"wrist_limits must be two finite numbers (lo, hi) with lo < hi, got "
                         f"{wrist_limits!r}")
    return float(limits[0]), float(limits[1])


def _check_branch(branch):
    if isinstance(branch, str) and branch == "closest":
        return branch
    if (isinstance(branch, (int, np.integer)) and not isinstance(branch, (bool, np.bool_))
            and 0 <= branch < len(BRANCH_NAMES)):
        return int(branch)
    raise ValueError(f"branch must be 0, 1, 2, 3 or 'closest', got {branch!r}")


def joint_targets(robot, task, *, branch=0, wrist_limits=(-math.pi, math.pi), tol=1e-9):
    r"""Joint targets of every step of a task, on one branch of the closed-form solution.

    Each position goes through :func:`dqlab.ik.desk_arm_closed_form.desk_arm`; the target is
    the row ``branch`` of its solutions (``0``: facing the point with the elbow up, see
    :data:`BRANCH_NAMES`), followed by the step's wrist angle. Keeping one branch keeps
    the arm in one posture for the whole task, so that no segment flips the elbow or
    swings the base half a turn.

    Parameters
    ----------
    robot : Robot
        :func:`dqlab.models.desk_arm` (or a chain of the same shape).
    task : PickPlaceTask
    branch : int or "closest", optional
        A row of :data:`BRANCH_NAMES`, or ``"closest"``: for each step the valid solution
        nearest to the previous target (the first step takes row 0 if valid).
    wrist_limits : (float, float), optional
        Lowest and highest wrist angle, radians.
    tol : float, optional
        Position tolerance of the inverse model, metres.

    Returns
    -------
    ndarray, shape (K, 4)
        :math:`(\theta_1, \theta_2, \theta_3, q_{wrist})` per step, radians.

    Raises
    ------
    ValueError
        Naming the first step that is out of reach, whose solution on ``branch`` is
        outside the joint limits, or whose wrist angle is outside ``wrist_limits``.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import desk_arm
    >>> task = task_from_lab([[226, 0, 0, 0, 0], [0, 170, 30, 1, 90]])
    >>> np.degrees(joint_targets(desk_arm(), task)).round(1)
    array([[   0. ,   51. , -116. ,    0. ],
           [  90. ,   77.3, -141.2,   90. ]])
    >>> joint_targets(desk_arm(), task_from_lab([[0, 0, 0, 0, 0], [400, 0, 0, 0, 0]]))
    Traceback (most recent call last):
    ...
    ValueError: step 1: (400, 0, 0) mm is unreachable: facing it, 0.02883 m beyond the ...
    """
    check_instance(robot, Robot, "robot")
    check_instance(task, PickPlaceTask, "task")
    branch = _check_branch(branch)
    lo, hi = _check_wrist_limits(wrist_limits)
    tol = check_scalar(tol, "tol", minimum=0)     # finite: inf would accept any solution
    result = ik.desk_arm(robot, task.positions, tol=tol)
    targets = np.empty((len(task), 4))
    previous = None
    for k in range(len(task)):
        where = "(" + ", ".join(f"{v:.4g}" for v in task.positions[k] * 1000) + ") mm"
        if not result.success[k]:
            reason = str(result.reason[k]).removeprefix("unreachable: ")
            raise ValueError(f"step {k}: {where} is unreachable: {reason} (position "
                             f"tolerance tol = {tol:g} m)")
        if branch == "closest":
            rows = np.flatnonzero(result.valid[k])
            if previous is None:
                row = 0 if result.valid[k, 0] else int(rows[0])
            else:
                gap = np.abs(result.solutions[k, rows] - previous[:3]).max(axis=-1)
                row = int(rows[np.argmin(gap)])
        else:
            row = branch
            if not result.valid[k, row]:
                valid = [BRANCH_NAMES[r] for r in np.flatnonzero(result.valid[k])]
                raise ValueError(
                    f"step {k}: {where} has no '{BRANCH_NAMES[row]}' solution within the "
                    f"joint limits (valid: {'; '.join(valid)})")
        w = task.wrist[k]
        if not lo <= w <= hi:
            raise ValueError(f"step {k}: wrist angle {math.degrees(w):.6g} deg is outside "
                             f"wrist_limits [{math.degrees(lo):.6g}, "
                             f"{math.degrees(hi):.6g}] deg")
        targets[k, :3] = result.solutions[k, row]
        targets[k, 3] = w
        previous = targets[k]
    return targets


def cup_poses(robot, q):
    r"""Poses :math:`X_{WC}` of the suction cup: at the hand, z pointing down, yaw
    :math:`\theta_1 + q_{wrist}`.

    Parameters
    ----------
    robot : Robot
        :func:`dqlab.models.desk_arm`.
    q : array_like, shape (..., 4)
        Chain angles and wrist angle.

    Returns
    -------
    ndarray, shape (..., 4, 4)

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import desk_arm
    >>> X_WC = cup_poses(desk_arm(), [0.0, np.radians(51), np.radians(-116), 0.0])
    >>> (X_WC[:3, 3] * 1000).round() + 0.0, X_WC[:3, 2].round(12) + 0.0
    (array([226.,   0.,   0.]), array([ 0.,  0., -1.]))
    """
    check_instance(robot, Robot, "robot")
    q = as_float_array(q, "q", (4,))
    p = robot.fk(q[..., :3])[..., :3, 3]
    yaw = q[..., 0] + q[..., 3]
    c, s = np.cos(yaw), np.sin(yaw)
    X = np.zeros(q.shape[:-1] + (4, 4))
    # columns: x = (c, s, 0), y = (s, -c, 0), z = (0, 0, -1): Rz(yaw) Rx(pi)
    X[..., 0, 0], X[..., 1, 0] = c, s
    X[..., 0, 1], X[..., 1, 1] = s, -c
    X[..., 2, 2] = -1.0
    X[..., :3, 3] = p
    X[..., 3, 3] = 1.0
    return X


# -- the plan ---------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class PickPlacePlan:
    """A timed pick-and-place motion and what the cup and the object do along it.

    Attributes
    ----------
    targets : ndarray, shape (K, 4)
        The joint target of every step (:func:`joint_targets`).
    trajectory : dqlab.trajectory.joint.Trajectory
        Instants ``t`` (N,), seconds from 0, and the chain and wrist angles ``q``, their
        speeds ``qd`` and accelerations ``qdd``, (N, 4) each.
    step : ndarray of int, shape (N,)
        The step being moved to (or dwelt at) at each instant.
    suction : ndarray of bool, shape (N,)
        The cup's state at each instant.
    cup : ndarray, shape (N, 4, 4)
        Cup poses :math:`X_{WC}` (:func:`cup_poses`).
    object : ndarray, shape (N, 4, 4)
        Poses :math:`X_{WO}` of the object.
    grasps : tuple of (int, int)
        The (pick step, place step) pairs.
    """

    targets: np.ndarray
    trajectory: Trajectory
    step: np.ndarray
    suction: np.ndarray
    cup: np.ndarray
    object: np.ndarray
    grasps: tuple

    @property
    def t(self):
        """Instants, seconds, shape (N,)."""
        return self.trajectory.t

    @property
    def q(self):
        """Chain and wrist angles, shape (N, 4)."""
        return self.trajectory.q

    @property
    def qd(self):
        """Joint speeds, shape (N, 4)."""
        return self.trajectory.qd

    @property
    def qdd(self):
        """Joint accelerations, shape (N, 4)."""
        return self.trajectory.qdd

    @property
    def duration(self):
        """Length of the motion in seconds."""
        return float(self.t[-1])


def plan_pick_place(robot, task, *, object_pose=None, branch=0,
                    wrist_limits=(-math.pi, math.pi), v_max=1.0, a_max=4.0, dwell=0.3,
                    dt=0.02, grasp_tol=0.002):
    r"""Joint targets, a timed trajectory and the object's motion for a pick-and-place task.

    The arm starts at the first step's target (the lab initialises its arm there). For each
    following step it moves to the step's target along a straight line of joint space with
    the quintic law, as fast as ``v_max`` and ``a_max`` allow
    (:func:`dqlab.trajectory.joint.joint_trajectory`; the law stays within [0, 1], so every
    sample lies between two targets that are within the joint limits), then, if the
    cup's state changes there, waits ``dwell`` seconds while it switches. When the suction
    comes on, the object is attached if the cup touches it (within ``grasp_tol`` of its
    frame's origin, the centre of its top face); it then moves rigidly with the cup,
    :math:`X_{WO}(t) = X_{WC}(t)\,X_{CO}` with :math:`X_{CO}` frozen at the grasp, until
    the suction goes off.

    Parameters
    ----------
    robot : Robot
        :func:`dqlab.models.desk_arm`.
    task : PickPlaceTask
    object_pose : array_like, shape (4, 4), optional
        :math:`X_{WO}` at the start, with O at the centre of the object's top face. By
        default the object lies under the first step that switches the suction on, aligned
        with the cup there.
    branch, wrist_limits
        See :func:`joint_targets`.
    v_max, a_max : float, optional
        Joint speed and acceleration limits (rad/s, rad/s^2).
    dwell : float, optional
        Seconds spent at a step where the suction switches.
    dt : float, optional
        Sampling period, seconds.
    grasp_tol : float, optional
        Largest distance between cup and object at a grasp, metres.

    Returns
    -------
    PickPlacePlan

    Raises
    ------
    ValueError
        From :func:`joint_targets` (naming the step); when the suction comes on with no
        object under the cup (naming the step); on non-positive ``v_max``, ``a_max``,
        ``dt`` or a negative ``dwell``; and if a sample were ever NaN or beyond a joint
        limit (a safety net: by construction it is not).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import desk_arm
    >>> task = task_from_lab([[0, 170, 80, 0, 0], [0, 170, 30, 1, 0], [0, 170, 80, 1, 0],
    ...                       [0, -170, 85, 1, 180], [0, -170, 35, 0, 180]])
    >>> plan = plan_pick_place(desk_arm(), task)
    >>> plan.grasps
    ((1, 4),)
    >>> (plan.object[-1, :3, 3] * 1000).round(3) + 0.0     # left at the place point
    array([   0., -170.,   35.])
    """
    check_instance(robot, Robot, "robot")
    check_instance(task, PickPlaceTask, "task")
    v_max = check_scalar(v_max, "v_max", minimum=0, strict=True)
    a_max = check_scalar(a_max, "a_max", minimum=0, strict=True)
    dt = check_scalar(dt, "dt", minimum=0, strict=True)
    dwell = check_scalar(dwell, "dwell", minimum=0)
    grasp_tol = check_tolerance(grasp_tol, "grasp_tol")
    if object_pose is not None:
        object_pose = check_transform(object_pose, name="object_pose")
        if object_pose.shape != (4, 4):
            raise ValueError(f"object_pose must be one (4, 4) transform, got shape "
                             f"{object_pose.shape}")
    targets = joint_targets(robot, task, branch=branch, wrist_limits=wrist_limits)

    # sampled motion: start at step 0, then one segment (and maybe a dwell) per step
    ts, qs, qds, qdds, steps, states = [np.zeros(1)], [targets[:1]], [np.zeros((1, 4))], \
        [np.zeros((1, 4))], [np.zeros(1, dtype=int)], [np.array([task.suction[0]])]
    now = 0.0
    state = bool(task.suction[0])
    for k in range(1, len(task)):
        if np.any(targets[k] != targets[k - 1]):
            segment = joint_trajectory(targets[k - 1], targets[k], v_max=v_max,
                                       a_max=a_max, law="quintic", dt=dt)
            # the law's rounding may overshoot its end by an ulp: keep every sample in the
            # box spanned by the two targets (and so within the joint limits)
            low = np.minimum(targets[k - 1], targets[k])
            high = np.maximum(targets[k - 1], targets[k])
            ts.append(now + segment.t[1:])
            qs.append(np.clip(segment.q[1:], low, high))
            qds.append(segment.qd[1:])
            qdds.append(segment.qdd[1:])
            steps.append(np.full(len(segment) - 1, k))
            states.append(np.full(len(segment) - 1, state))
            now += segment.duration
        if bool(task.suction[k]) != state or k == len(task) - 1:
            state = bool(task.suction[k])
            hold = max(dwell, dt)
            count = max(1, math.ceil(hold / dt - 1e-9))
            if count > MAX_SAMPLES:
                raise ValueError(f"dwell / dt = {dwell:g} s / {dt:g} s: {count:.3g} samples is "
                                 f"too large (at most {MAX_SAMPLES:.0e})")
            ts.append(now + np.linspace(hold / count, hold, count))
            qs.append(np.repeat(targets[k:k + 1], count, axis=0))
            qds.append(np.zeros((count, 4)))
            qdds.append(np.zeros((count, 4)))
            steps.append(np.full(count, k))
            states.append(np.full(count, state))
            now += hold
    t = np.concatenate(ts)
    if not np.all(np.diff(t) > 0.0):
        raise ValueError(f"dt = {dt:g} s and dwell = {dwell:g} s are too large for the motion: "
                         f"its instants can no longer be told apart in floating point")
    trajectory = Trajectory(t=t, q=np.concatenate(qs), qd=np.concatenate(qds),
                            qdd=np.concatenate(qdds))
    t, q = trajectory.t, trajectory.q
    step = np.concatenate(steps)
    suction = np.concatenate(states)
    _check_samples(robot, q, wrist_limits)
    cup = cup_poses(robot, q)

    # the object: where it starts, when it is picked, carried and left
    switch_on = [k for k in range(len(task))
                 if task.suction[k] and (k == 0 or not task.suction[k - 1])]
    if object_pose is None:
        X_WO = cup_poses(robot, targets[switch_on[0] if switch_on else 0])
    else:
        X_WO = object_pose
    obj = np.empty_like(cup)
    X_CO = None
    grasps = []
    pick_step = None
    for i in range(len(t)):
        if suction[i] and X_CO is None and (i == 0 or not suction[i - 1]):
            gap = math.hypot(*(cup[i, :3, 3] - X_WO[:3, 3]))     # far objects: no overflow
            if not gap <= grasp_tol:
                raise ValueError(
                    f"step {step[i]}: the suction comes on with no object under the cup "
                    f"(the object, at object_pose, is {gap * 1000:.4g} mm away, grasp_tol "
                    f"{grasp_tol * 1000:.4g} mm)")
            X_CO = np.linalg.inv(cup[i]) @ X_WO
            pick_step = int(step[i])
        elif not suction[i] and X_CO is not None:
            X_CO = None
            grasps.append((pick_step, int(step[i])))
        if X_CO is not None:
            X_WO = cup[i] @ X_CO
        obj[i] = X_WO
    if X_CO is not None:
        grasps.append((pick_step, None))
    return PickPlacePlan(targets=targets, trajectory=trajectory, step=step,
                         suction=suction, cup=cup, object=obj, grasps=tuple(grasps))


def _check_samples(robot, q, wrist_limits):
    """The safety net: every sample finite and within the joint and wrist limits."""
    if not np.all(np.isfinite(q)):
        raise ValueError("the planned trajectory contains NaN or infinity")
    lo = np.append(robot.limits[:, 0], wrist_limits[0])
    hi = np.append(robot.limits[:, 1], wrist_limits[1])
    bad = (q < lo) | (q > hi)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise ValueError(f"sample {i}: joint {j + 1} = {q[i, j]:.6g} rad is beyond its "
                         f"limits [{lo[j]:.6g}, {hi[j]:.6g}]")
