"""A client for a Universal Robots controller with interchangeable back ends.

:class:`Backend` is the protocol every back end implements; :class:`URClient` checks every
target and every state the controller reports, and drives any back end:

- :class:`~dqlab.ur.kinematic_arm.KinematicBackend` -- an arm in this process that executes
  the motions of :mod:`dqlab.ur.motion` (no physics; the MuJoCo arm of ``dqlab.sim`` adds
  them);
- :class:`~dqlab.ur.secondary.SecondaryInterfaceBackend` -- a real controller, URSim, or the
  stand-in of :mod:`dqlab.ur.standin`: URScript text to the secondary interface (port
  30002), state from the RTDE stream (port 30004);
- :class:`~dqlab.ur.rtde_backend.RTDEBackend` -- a real controller through the ``ur_rtde``
  package (optional extra ``robot``).

A **pose** here is UR's 6-vector ``[x, y, z, rx, ry, rz]`` of the TCP in the controller's base
frame (DH frame 0 of ``robot``; see :mod:`dqlab.ur.motion`).
"""

import time
import typing

import numpy as np

from .._checks import check_tolerance
from ..quaternion import quaternion_distance
from . import motion, script
from .motion import GAIN, LOOKAHEAD_TIME, MOVEJ_A, MOVEJ_V, MOVEL_A, MOVEL_V, STOPJ_A
from .poses import check_pose, quaternion_from_rotation_vector
from .script import UnsafeTargetError, as_safety_limits, check_joint_targets
from .state import ROBOT_MODE_RUNNING, URState, check_state

__all__ = ["Backend", "URClient", "robot_and_limits"]


class Backend(typing.Protocol):
    """What :class:`URClient` needs from a controller connection.

    Motion calls *start* a move and return at once; the client polls ``read_state``.
    Units and argument names are URScript's: joint targets in rad, poses as UR pose vectors
    in the controller's base frame, ``a`` acceleration (rad/s^2 or m/s^2), ``v`` speed
    (rad/s or m/s), ``t`` time (s), ``r`` blend radius (m).
    """

    name: str

    def connect(self, timeout: float) -> None: ...

    def close(self) -> None: ...

    def read_state(self) -> URState: ...

    def movej(self, q, *, a: float, v: float, t: float, r: float) -> None: ...

    def movel(self, pose, *, a: float, v: float, t: float, r: float) -> None: ...

    def servoj(self, q, *, t: float, lookahead_time: float, gain: float) -> None: ...

    def stop(self, a: float) -> None: ...


def _duration(value, name):
    """A finite number of seconds >= 0 (named in the error)."""
    value = check_tolerance(value, name)
    if not np.isfinite(value):
        raise ValueError(f"{name} must be a finite number of seconds, got {value!r}")
    return value


def robot_and_limits(robot, limits):
    """The arm and the :class:`~dqlab.ur.script.SafetyLimits` of a client or a back end:
    ``limits`` by :func:`~dqlab.ur.script.as_safety_limits`; ``robot`` as given, else the
    limits' robot, else :func:`dqlab.models.ur3`. ``TypeError`` naming ``robot`` unless it
    is a six-joint robot.

    Examples
    --------
    >>> from dqlab.models import ur5e
    >>> robot, limits = robot_and_limits(ur5e(), None)
    >>> limits.robot.name
    'UR5e'
    """
    limits = as_safety_limits(limits, robot)
    if robot is None:
        from ..models import ur3

        robot = limits.robot if limits.robot is not None else ur3()
    if not hasattr(robot, "fk") or getattr(robot, "n", None) != 6:
        raise TypeError(f"robot must be a dqlab.robot.Robot with 6 joints, got "
                        f"{type(robot).__name__}")
    return robot, limits


def _units_hint(target, kind):
    """What to add to a refusal when the target looks like degrees or millimetres."""
    try:
        a = np.asarray(target, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        return ""
    if a.size != 6 or not np.all(np.isfinite(a)):
        return ""
    if kind == "pose":
        with np.errstate(over="ignore"):     # a norm beyond any float is inf: too large
            position, rotation = np.linalg.norm(a[:3]), np.linalg.norm(a[3:])
        if position > 5.0:
            return " (millimetres? poses are in metres: divide by 1000)"
        if rotation > 2 * np.pi:
            return " (degrees? the rotation vector is in radians: np.radians(...))"
    elif np.max(np.abs(a)) > 2 * np.pi:
        return " (degrees? joint targets are in radians: np.radians(...))"
    return ""


def _checked(check, target, kind):
    """Run a script check; a refusal gets the degrees or millimetres hint it deserves."""
    try:
        return check()
    except UnsafeTargetError as exc:
        raise UnsafeTargetError(f"{exc}{_units_hint(target, kind)}") from None


_BACKEND_METHODS = ("connect", "close", "read_state", "movej", "movel", "servoj", "stop")


class URClient:
    r"""One interface to a UR controller, whatever the back end; every target checked first.

    Every motion is checked by :mod:`dqlab.ur.script` as the controller will execute it from
    the joints the controller reports (finite targets, within the joint limits, no joint
    jump, poses within the robot's reach, and the peaks of the planned motion's joint and TCP
    speeds and accelerations within :class:`~dqlab.ur.script.SafetyLimits`) *before* the back
    end sees it; a refused target raises :class:`~dqlab.ur.script.UnsafeTargetError` and
    nothing moves (with a hint when it looks like degrees or millimetres: joints beyond
    :math:`2\pi`, a position beyond 5 m). Every state the controller reports is checked
    too: a NaN, a wrong shape or type raises :class:`~dqlab.ur.state.ControllerError` (it
    would switch the checks off).

    Parameters
    ----------
    backend : Backend
        :class:`~dqlab.ur.kinematic_arm.KinematicBackend`,
        :class:`~dqlab.ur.secondary.SecondaryInterfaceBackend`,
        :class:`~dqlab.ur.rtde_backend.RTDEBackend`, or the MuJoCo back end of ``dqlab.sim``.
    robot : dqlab.robot.Robot, optional
        The arm's model, for inverse kinematics, reach and the limits. Default: the back
        end's (``backend.robot`` and ``backend.limits``: the stand-in's arm, a calibrated one
        included), else :func:`dqlab.models.ur3`. Poses are in its base frame (DH frame 0),
        not in the world frame of ``robot.base``.
    limits : SafetyLimits or array_like of shape (6, 2), optional
        Default: the back end's, or ``robot``'s (:meth:`~dqlab.ur.script.SafetyLimits.for_robot`),
        or without a robot the UR3's (see :func:`~dqlab.ur.script.as_safety_limits`).
    tol : float
        A joint target is reached when every joint is within ``tol`` rad of it and every
        joint speed below ``tol`` rad/s (a pose: ``tol`` m and rad); >= 0.
    poll_interval : float
        Pause between two state reads while waiting, s (>= 0).
    connect_timeout : float
        s (>= 0).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.ur import URClient, KinematicBackend, StepClock
    >>> home = [0, -np.pi / 2, 0, -np.pi / 2, 0, 0]
    >>> with URClient(KinematicBackend(q0=home, clock=StepClock(0.01)), poll_interval=0) as ur:
    ...     state = ur.movej([0.5, -1.2, 0.8, -1.5, -1.0, 0.3])
    >>> state.q.round(6) + 0.0
    array([ 0.5, -1.2,  0.8, -1.5, -1. ,  0.3])
    """

    def __init__(self, backend, robot=None, *, limits=None, tol=1e-4, poll_interval=0.002,
                 connect_timeout=5.0):
        missing = [m for m in _BACKEND_METHODS if not callable(getattr(backend, m, None))]
        if missing:
            raise TypeError(f"backend must implement the Backend protocol; "
                            f"{type(backend).__name__} lacks {missing}")
        self.backend = backend
        if robot is None and limits is None:          # the back end's arm and limits
            robot, limits = getattr(backend, "robot", None), getattr(backend, "limits", None)
        self.robot, self.limits = robot_and_limits(robot, limits)
        self.tol = check_tolerance(tol, "tol")
        self.poll_interval = _duration(poll_interval, "poll_interval")
        self.connect_timeout = _duration(connect_timeout, "connect_timeout")
        self._connected = False

    # connection ------------------------------------------------------------------------
    def connect(self):
        """Connect the back end."""
        self.backend.connect(self.connect_timeout)
        self._connected = True

    def close(self):
        """Close the back end (idempotent)."""
        if self._connected:
            self._connected = False
            self.backend.close()

    def __enter__(self):
        self.connect()
        return self

    def __exit__(self, *exc):
        self.close()

    # state -----------------------------------------------------------------------------
    def read_state(self):
        """The controller's current :class:`~dqlab.ur.state.URState`, checked.

        Raises
        ------
        ControllerError
            If the controller reports NaN, infinity, a wrong shape or type.
        """
        if not self._connected:
            raise RuntimeError("URClient is not connected (use it in a with-block)")
        return check_state(self.backend.read_state(), f"the {self.backend.name} back end")

    def actual_q(self):
        """Actual joint positions, rad, shape (6,)."""
        return self.read_state().q

    def actual_tcp_pose(self):
        """Actual TCP pose (UR pose vector in the controller's base frame), shape (6,)."""
        return self.read_state().tcp_pose

    def _running_state(self, command):
        state = self.read_state()
        if state.robot_mode != ROBOT_MODE_RUNNING:
            raise RuntimeError(f"{command} refused: robot mode is {state.robot_mode}, not "
                               f"RUNNING ({ROBOT_MODE_RUNNING})")
        return state

    def _timeout(self, timeout, duration):
        if timeout is None:
            return 3.0 * duration + 2.0
        return check_tolerance(timeout, "timeout")

    # motions ---------------------------------------------------------------------------
    def movej(self, q, a=MOVEJ_A, v=MOVEJ_V, t=0.0, r=0.0, *, wait=True, timeout=None):
        """Move in joint space to ``q`` (checked first); wait until it is reached.

        Parameters
        ----------
        q : array_like, shape (6,)
            Joint target, rad.
        a, v, t, r : float
            URScript's ``movej`` arguments (rad/s^2, rad/s, s, m).
        wait : bool
            Poll the state until the target is reached (else return at once).
        timeout : float, optional
            s; default: three times the duration of the planned move, plus 2 s.

        Returns
        -------
        URState
            The state in which the target was found reached (or the state before the move
            when ``wait`` is False).

        Raises
        ------
        UnsafeTargetError
            If a safety check refuses the target (nothing is sent).
        ControllerError
            If the controller reports an untrustworthy state (nothing is sent).
        TimeoutError
            If the arm did not reach the target in time (says by how much it missed).
        """
        state = self._running_state("movej")
        _checked(lambda: script.movej(q, a=a, v=v, t=t, r=r, limits=self.limits,
                                      q_from=state.q), q, "joints")
        q = check_joint_targets(q, limits=self.limits)
        planned = motion.plan_movej(state.q, q, a, v, t)
        timeout = self._timeout(timeout, planned.duration)
        self.backend.movej(q, a=float(a), v=float(v), t=float(t), r=float(r))
        if not wait:
            return state
        return self._wait_joints(q, timeout, "movej")

    def movel(self, pose, a=MOVEL_A, v=MOVEL_V, t=0.0, r=0.0, *, wait=True, timeout=None):
        """Move the TCP on a straight line to a pose (checked first); wait for it.

        The line is planned from the current joints and checked all along
        (:func:`dqlab.ur.script.movel` with ``q_from``): reach, joint limits, singularities,
        joint jumps, the peaks of the joints' and the TCP's speeds and accelerations.

        Parameters
        ----------
        pose : array_like, shape (6,)
            The target pose: ``[x, y, z, rx, ry, rz]`` of the TCP in the controller's base
            frame, m and rad.
        a, v, t, r : float
            URScript's ``movel`` arguments (m/s^2, m/s, s, m).
        wait : bool
        timeout : float, optional

        Returns
        -------
        URState
        """
        state = self._running_state("movel")
        _checked(lambda: script.movel(pose, a=a, v=v, t=t, r=r, limits=self.limits,
                                      robot=self.robot, q_from=state.q), pose, "pose")
        pose = check_pose(pose)
        planned = motion.plan_movel(self.robot, state.q, pose, a, v, t)
        timeout = self._timeout(timeout, planned.duration)
        self.backend.movel(pose, a=float(a), v=float(v), t=float(t), r=float(r))
        if not wait:
            return state
        return self._wait_pose(pose, timeout)

    def closest_joints(self, pose, q_ref=None):
        """The inverse-kinematics solution of a pose nearest ``q_ref`` (default: the current
        joints) within the joint limits (:func:`dqlab.ik.solutions.closest_solution`).

        Raises
        ------
        UnsafeTargetError
            If the pose has no solution within the limits.
        """
        from .. import ik

        q_ref = self.actual_q() if q_ref is None else q_ref
        try:
            X = motion.world_transform(self.robot, check_pose(pose, "pose"))
        except ValueError as exc:
            raise UnsafeTargetError(f"pose: {exc}{_units_hint(pose, 'pose')}") from None
        result = ik.ur(self.robot, X)
        try:
            return ik.closest_solution(result, q_ref, self.limits.joint_limits)
        except ValueError as exc:
            raise UnsafeTargetError(f"pose {script.urscript_pose(pose)}: {exc}"
                                    f"{_units_hint(pose, 'pose')}") from None

    def servoj_stream(self, trajectory, *, lookahead_time=LOOKAHEAD_TIME, gain=GAIN,
                      start_tol=1e-3, timeout=None):
        """Stream a joint trajectory with ``servoj``, paced by the controller's clock.

        The whole trajectory is checked first (:func:`dqlab.ur.script.check_trajectory`, as
        :func:`~dqlab.ur.script.program_from_trajectory` does: from rest to rest); its first
        sample must be where the arm is (within ``start_tol`` rad: move there with
        :meth:`movej` first), and the arm's speed may differ from the first sample's only by
        what the acceleration limit allows in one sample period. Then sample ``k`` is sent when the
        controller's time reaches ``t[k-1]`` after the start, to be reached
        ``t[k] - t[k-1]`` later.

        Parameters
        ----------
        trajectory : object with arrays ``t`` (N,) and ``q`` (N, 6)
            E.g. a ``dqlab.trajectory.Trajectory``.
        lookahead_time, gain : float
            Of every ``servoj``.
        start_tol : float
            rad (>= 0).
        timeout : float, optional
            s; default: three times the trajectory's duration plus 2 s.

        Returns
        -------
        list of URState
            The state read when each sample was sent, and the final state.
        """
        start_tol = check_tolerance(start_tol, "start_tol")
        t, q = script.check_trajectory(trajectory, limits=self.limits, robot=self.robot,
                                       command="servoj_stream")
        script.servoj(q[0], lookahead_time=lookahead_time, gain=gain, limits=self.limits)
        state = self._running_state("servoj_stream")
        gap = np.abs(q[0] - state.q)
        if not np.max(gap) <= start_tol:
            j = int(np.argmax(gap))
            raise UnsafeTargetError(
                f"servoj_stream: the first sample is {gap[j]:.3g} rad from the arm at joint "
                f"{j + 1} (more than start_tol = {start_tol:g}); movej to q[0] first")
        if len(q) > 1:          # the first speed change, from the arm's actual speed
            dt = float(t[1] - t[0])
            acc = np.abs((q[1] - q[0]) / dt - state.qd) / dt
            if not np.max(acc) <= self.limits.max_joint_acceleration:
                j = int(np.argmax(acc))
                raise UnsafeTargetError(
                    f"servoj_stream: the arm moves at {state.qd[j]:.3g} rad/s at joint {j + 1};"
                    f" the first sample would change that by {acc[j]:.3g} rad/s^2, above "
                    f"{self.limits.max_joint_acceleration:g} (wait for the arm to stop)")
        timeout = self._timeout(timeout, float(t[-1] - t[0]))
        deadline = time.monotonic() + timeout
        t0 = state.time
        log = [state]
        for k in range(1, len(q)):
            while state.time < t0 + (t[k - 1] - t[0]) - 1e-9:     # (clock rounding)
                if time.monotonic() > deadline:
                    raise TimeoutError(f"servoj_stream: controller time did not advance to "
                                       f"sample {k} within {timeout:.3g} s")
                self._pause()
                state = self.read_state()
            self.backend.servoj(q[k], t=float(t[k] - t[k - 1]),
                                lookahead_time=float(lookahead_time), gain=float(gain))
            log.append(state)
        log.append(self._wait_joints(q[-1], max(deadline - time.monotonic(), 0.0) + 1.0,
                                     "servoj_stream"))
        return log

    def stop(self, a=STOPJ_A):
        """Decelerate the joints to rest (``stopj``): ``a`` rad/s^2, positive and at most the
        limits' ``max_joint_acceleration``."""
        script.stopj(a, limits=self.limits)          # refuses NaN, <= 0, above the limit
        self.backend.stop(float(a))

    # waiting ---------------------------------------------------------------------------
    def _pause(self):
        if self.poll_interval > 0:
            time.sleep(self.poll_interval)

    def _wait_joints(self, q, timeout, command):
        deadline = time.monotonic() + timeout
        while True:
            state = self.read_state()
            err = np.abs(state.q - q)
            if np.max(err) <= self.tol and np.max(np.abs(state.qd)) <= self.tol:
                return state
            if time.monotonic() > deadline:
                j = int(np.argmax(err))
                raise TimeoutError(
                    f"{command}: target not reached within {timeout:.3g} s; joint {j + 1} is "
                    f"{err[j]:.3g} rad away (robot mode {state.robot_mode})")
            self._pause()

    def _wait_pose(self, pose, timeout):
        deadline = time.monotonic() + timeout
        q_goal = quaternion_from_rotation_vector(pose[3:])
        while True:
            state = self.read_state()
            dp = float(np.linalg.norm(state.tcp_pose[:3] - pose[:3]))
            dr = float(quaternion_distance(quaternion_from_rotation_vector(state.tcp_pose[3:]),
                                           q_goal))
            if dp <= self.tol and dr <= self.tol and np.max(np.abs(state.qd)) <= self.tol:
                return state
            if time.monotonic() > deadline:
                raise TimeoutError(f"movel: target not reached within {timeout:.3g} s; the "
                                   f"TCP is {dp:.3g} m and {dr:.3g} rad away")
            self._pause()
