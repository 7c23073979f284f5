"""A client for a Universal Robots controller with interchangeable back ends.

:class:`URState` is what a controller reports; :class:`Backend` is the protocol every back
end implements; :class:`URClient` checks every target and drives any back end:

- :class:`KinematicBackend` -- an arm in this process that follows the commands' time laws
  (no physics; the MuJoCo arm of ``dqlab.sim`` adds them);
- :class:`SecondaryInterfaceBackend` -- a real controller, URSim, or the stand-in of
  :mod:`dqlab.ur.standin`: URScript text to the secondary interface (port 30002), state
  from the RTDE stream (port 30004);
- :class:`RTDEBackend` -- a real controller through the ``ur_rtde`` package (optional extra
  ``robot``).
"""

import collections
import importlib
import socket
import time
import typing
from dataclasses import dataclass

import numpy as np

from ..ik import closest_solution
from ..quaternion import quaternion_distance, slerp
from ..trajectory import trapezoidal
from . import script
from .poses import (
    check_pose,
    pose_from_transform,
    quaternion_from_rotation_vector,
    rotation_vector_from_quaternion,
    transform_from_pose,
)
from .rtde import STATE_VARIABLES, RTDEReader
from .script import UnsafeTargetError, as_safety_limits, check_joint_targets

__all__ = ["URState", "Backend", "ROBOT_MODE_RUNNING", "HOME", "URClient",
           "KinematicBackend", "StepClock", "SecondaryInterfaceBackend", "RTDEBackend",
           "closest_joints", "trapezoid_duration", "trapezoid_law"]

#: The thesis's home joints (arm straight up), rad.
HOME = np.array([0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0])

#: UR robot mode reported while the arm is powered, released and ready to move.
ROBOT_MODE_RUNNING = 7


@dataclass(frozen=True)
class URState:
    """What a controller reports at one instant.

    Attributes
    ----------
    time : float
        Seconds since the back end connected (controller time).
    q : ndarray, shape (6,)
        Actual joint positions, rad.
    qd : ndarray, shape (6,)
        Actual joint speeds, rad/s.
    tcp_pose : ndarray, shape (6,)
        Actual TCP pose as a UR pose vector ``[x, y, z, rx, ry, rz]``: metres and a rotation
        vector in radians.
    robot_mode : int
        UR robot mode (7 = RUNNING).
    """

    time: float
    q: np.ndarray
    qd: np.ndarray
    tcp_pose: np.ndarray
    robot_mode: int


class Backend(typing.Protocol):
    """What :class:`URClient` needs from a controller connection.

    Motion calls *start* a move and return at once; the client polls ``read_state``.
    Units and argument names are URScript's: joint targets in rad, poses as UR pose vectors,
    ``a`` acceleration (rad/s^2 or m/s^2), ``v`` speed (rad/s or m/s), ``t`` time (s),
    ``r`` blend radius (m).
    """

    name: str

    def connect(self, timeout: float) -> None: ...

    def close(self) -> None: ...

    def read_state(self) -> URState: ...

    def movej(self, q, *, a: float, v: float, t: float, r: float) -> None: ...

    def movel(self, pose, *, a: float, v: float, t: float, r: float) -> None: ...

    def servoj(self, q, *, t: float, lookahead_time: float, gain: float) -> None: ...

    def stop(self, a: float) -> None: ...


# --------------------------------------------------------------------------------------
# The client


class URClient:
    r"""One interface to a UR controller, whatever the back end; every target checked first.

    Every motion target goes through the checks of :mod:`dqlab.ur.script` (finite, within
    the joint limits, speeds and accelerations within :class:`~dqlab.ur.script.SafetyLimits`,
    no joint jump from the current joints, poses within reach) *before* the back end sees
    it; a refused target raises :class:`~dqlab.ur.script.UnsafeTargetError` and nothing
    moves.

    Parameters
    ----------
    backend : Backend
        :class:`KinematicBackend`, :class:`SecondaryInterfaceBackend`, :class:`RTDEBackend`,
        or the MuJoCo back end of ``dqlab.sim``.
    robot : dqlab.robot.Robot, optional
        The arm's model, for inverse kinematics and reach (default
        :func:`dqlab.models.ur3`).
    limits : SafetyLimits or array_like of shape (6, 2), optional
        Default: the UR3's (see :func:`~dqlab.ur.script.as_safety_limits`).
    tol : float
        A joint target is reached when every joint is within ``tol`` rad of it and every
        joint speed below ``tol`` rad/s (a pose: ``tol`` m and rad).
    poll_interval : float
        Pause between two state reads while waiting, s.
    connect_timeout : float
        s.

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
        from ..models import ur3

        self.backend = backend
        self.robot = ur3() if robot is None else robot
        self.limits = as_safety_limits(limits)
        self.tol = float(tol)
        self.poll_interval = float(poll_interval)
        self.connect_timeout = float(connect_timeout)
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
        """The controller's current :class:`URState`."""
        if not self._connected:
            raise RuntimeError("URClient is not connected (use it in a with-block)")
        return self.backend.read_state()

    def actual_q(self):
        """Actual joint positions, rad, shape (6,)."""
        return self.read_state().q

    def actual_tcp_pose(self):
        """Actual TCP pose as a UR pose vector, shape (6,)."""
        return self.read_state().tcp_pose

    def _running_state(self, command):
        state = self.read_state()
        if state.robot_mode != ROBOT_MODE_RUNNING:
            raise RuntimeError(f"{command} refused: robot mode is {state.robot_mode}, not "
                               f"RUNNING ({ROBOT_MODE_RUNNING})")
        return state

    # motions ---------------------------------------------------------------------------
    def movej(self, q, a=1.4, v=1.05, t=0.0, r=0.0, *, wait=True, timeout=None):
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
            s; default: three times the duration of the move at ``a`` and ``v``, plus 2 s.

        Returns
        -------
        URState
            The state in which the target was found reached (or the state before the move
            when ``wait`` is False).

        Raises
        ------
        UnsafeTargetError
            If a safety check refuses the target (nothing is sent).
        TimeoutError
            If the arm did not reach the target in time (says by how much it missed).
        """
        state = self._running_state("movej")
        script.movej(q, a=a, v=v, t=t, r=r, limits=self.limits, q_from=state.q)
        q = np.asarray(q, dtype=float)
        self.backend.movej(q, a=a, v=v, t=t, r=r)
        if not wait:
            return state
        if timeout is None:
            duration = t if t > 0 else trapezoid_duration(np.max(np.abs(q - state.q)), a, v)
            timeout = 3.0 * duration + 2.0
        return self._wait_joints(q, timeout, "movej")

    def movel(self, pose, a=1.2, v=0.25, t=0.0, r=0.0, *, wait=True, timeout=None):
        """Move the TCP on a straight line to a UR pose (checked first); wait for it.

        Besides the checks of :func:`dqlab.ur.script.movel` (reach, TCP speed and
        acceleration), the joints of the target -- the inverse-kinematics solution closest
        to the current joints -- are checked for limits and jumps.

        Parameters
        ----------
        pose : array_like, shape (6,)
            ``[x, y, z, rx, ry, rz]`` of the TCP in the base frame, m and rad.
        a, v, t, r : float
            URScript's ``movel`` arguments (m/s^2, m/s, s, m).
        wait : bool
        timeout : float, optional

        Returns
        -------
        URState
        """
        state = self._running_state("movel")
        script.movel(pose, a=a, v=v, t=t, r=r, limits=self.limits, robot=self.robot)
        pose = check_pose(pose)
        q_goal = self.closest_joints(pose, state.q)
        check_joint_targets(q_goal, limits=self.limits, q_from=state.q, command="movel")
        self.backend.movel(pose, a=a, v=v, t=t, r=r)
        if not wait:
            return state
        if timeout is None:
            dist = float(np.linalg.norm(pose[:3] - state.tcp_pose[:3]))
            duration = t if t > 0 else trapezoid_duration(dist, a, v)
            timeout = 3.0 * duration + 2.0
        return self._wait_pose(pose, timeout)

    def closest_joints(self, pose, q_ref):
        """The inverse-kinematics solution of a UR pose closest to ``q_ref``.

        See :func:`closest_joints`.

        Raises
        ------
        UnsafeTargetError
            If the pose has no solution.
        """
        try:
            return closest_joints(self.robot, pose, q_ref, self.limits.joint_limits)
        except ValueError as exc:
            raise UnsafeTargetError(str(exc)) from None

    def servoj_stream(self, trajectory, *, lookahead_time=0.1, gain=300, start_tol=1e-3,
                      timeout=None):
        """Stream a joint trajectory with ``servoj``, paced by the controller's clock.

        The whole trajectory is checked first (as :func:`dqlab.ur.script.program_from_trajectory`
        does); its first sample must be where the arm is (within ``start_tol`` rad: move
        there with :meth:`movej` first). Then sample ``k`` is sent when the controller's time
        reaches ``t[k-1]`` after the start, to be reached ``t[k] - t[k-1]`` later.

        Parameters
        ----------
        trajectory : object with arrays ``t`` (N,) and ``q`` (N, 6)
            E.g. a ``dqlab.trajectory.Trajectory``.
        lookahead_time, gain : float
            Of every ``servoj``.
        start_tol : float
            rad.
        timeout : float, optional
            s; default: three times the trajectory's duration plus 2 s.

        Returns
        -------
        list of URState
            The state read when each sample was sent, and the final state.
        """
        t = np.asarray(trajectory.t, dtype=float)
        q = check_joint_targets(np.asarray(trajectory.q, dtype=float), limits=self.limits,
                                command="servoj_stream", times=t)
        script.servoj(q[0], lookahead_time=lookahead_time, gain=gain, limits=self.limits)
        state = self._running_state("servoj_stream")
        gap = np.abs(q[0] - state.q)
        if np.max(gap) > start_tol:
            j = int(np.argmax(gap))
            raise UnsafeTargetError(
                f"servoj_stream: the first sample is {gap[j]:.3g} rad from the arm at joint "
                f"{j + 1} (more than start_tol = {start_tol:g}); movej to q[0] first")
        if timeout is None:
            timeout = 3.0 * float(t[-1] - t[0]) + 2.0
        deadline = time.monotonic() + timeout
        t0 = state.time
        log = [state]
        for k in range(1, len(q)):
            while state.time < t0 + (t[k - 1] - t[0]):
                if time.monotonic() > deadline:
                    raise TimeoutError(f"servoj_stream: controller time did not advance to "
                                       f"sample {k} within {timeout:.3g} s")
                self._pause()
                state = self.read_state()
            self.backend.servoj(q[k], t=float(t[k] - t[k - 1]), lookahead_time=lookahead_time,
                                gain=gain)
            log.append(state)
        log.append(self._wait_joints(q[-1], max(deadline - time.monotonic(), 0.0) + 1.0,
                                     "servoj_stream"))
        return log

    def stop(self, a=2.0):
        """Decelerate the joints to rest (``stopj``)."""
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


# --------------------------------------------------------------------------------------
# The in-process kinematic arm


def closest_joints(robot, pose, q_ref, joint_limits):
    r"""The inverse-kinematics solution of a UR pose closest to the joints ``q_ref``.

    Solves with :func:`dqlab.ik.ur_closed_form.ur`, then takes
    :func:`dqlab.ik.ur_closed_form.closest_solution`:
    the branch nearest ``q_ref`` (joint-wise, modulo :math:`2\pi`), each joint replaced by
    its :math:`2\pi`-equivalent nearest ``q_ref`` within the joint limits (an unlimited
    joint is searched within :math:`\pm 2\pi`).

    Parameters
    ----------
    robot : dqlab.robot.Robot
    pose : array_like, shape (6,)
        UR pose vector of the TCP in the base frame.
    q_ref : array_like, shape (6,)
    joint_limits : array_like, shape (6, 2)

    Returns
    -------
    ndarray, shape (6,)

    Raises
    ------
    ValueError
        If the pose has no solution (out of reach).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> from dqlab.ur.script import UR3_JOINT_LIMITS
    >>> robot = ur3()
    >>> q = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])
    >>> pose = pose_from_transform(robot.fk(q))
    >>> closest_joints(robot, pose, q + 0.1, UR3_JOINT_LIMITS).round(12) + 0.0
    array([ 0.4, -1.3,  1.1, -1.2, -1.4,  0.6])
    """
    from .. import ik

    result = ik.ur(robot, transform_from_pose(pose))
    if not bool(result.success):
        raise ValueError(f"target {script.urscript_pose(pose)} is out of reach: "
                         f"{result.reason}")
    lim = np.asarray(joint_limits, dtype=float)
    lim = np.where(np.isfinite(lim), lim, np.sign(lim) * 2 * np.pi)
    return closest_solution(result, q_ref, limits=lim)


def trapezoid_law(distance, a, v):
    r"""The rest-to-rest trapezoid the arm follows over ``distance`` within ``a`` and ``v``.

    The time law of :func:`dqlab.trajectory.time_laws.trapezoidal` with ``v_max=v`` and ``a_max=a``
    (triangular when the cruise speed is not reached); ``None`` for no motion.

    Examples
    --------
    >>> trapezoid_law(1.0, 1.0, 0.5).duration, trapezoid_law(1.0, 1.0, 2.0).duration
    (2.5, 2.0)
    >>> trapezoid_law(0.0, 1.0, 1.0) is None
    True
    """
    distance = float(distance)
    return trapezoidal(distance, v_max=v, a_max=a) if distance > 0.0 else None


def trapezoid_duration(distance, a, v):
    r"""Duration of a rest-to-rest move over ``distance`` with peak acceleration ``a``, speed ``v``.

    .. math::

        T = \begin{cases} D/v + v/a & D a \ge v^2 \text{ (cruise reached)} \\
        2\sqrt{D/a} & \text{otherwise (triangle)} \end{cases}

    Examples
    --------
    >>> trapezoid_duration(1.0, 1.0, 0.5), trapezoid_duration(1.0, 1.0, 2.0)
    (2.5, 2.0)
    """
    law = trapezoid_law(distance, a, v)
    return 0.0 if law is None else law.duration


def _fraction(law, tau):
    """(s, s') of ``law`` at time ``tau`` as fractions of its distance (1, 0 for no motion)."""
    if law is None:
        return 1.0, 0.0
    return float(law.position(tau)) / law.distance, float(law.speed(tau)) / law.distance


class _Segment:
    """One motion of the kinematic arm from time ``t0`` for ``duration`` seconds."""

    def __init__(self, t0, duration, q_start, q_end):
        self.t0, self.duration = t0, duration
        self.q_start, self.q_end = q_start, q_end

    @property
    def t_end(self):
        return self.t0 + self.duration

    def at(self, now):  # pragma: no cover - overridden
        raise NotImplementedError


class _Hold(_Segment):
    def __init__(self, t0, q):
        super().__init__(t0, 0.0, q, q)

    def at(self, now):
        return self.q_end.copy(), np.zeros_like(self.q_end)


class _JointMove(_Segment):
    """Synchronised joint move: every joint follows the leading joint's time law."""

    def __init__(self, t0, q_start, q_end, a, v, t):
        self.delta = q_end - q_start
        self.dist = float(np.max(np.abs(self.delta)))
        self.law = trapezoid_law(self.dist, a, v)
        natural = 0.0 if self.law is None else self.law.duration
        duration = t if t > 0 else natural
        self.scale = natural / duration if duration > 0 else 1.0
        super().__init__(t0, duration, q_start, q_end)

    def at(self, now):
        if now >= self.t_end:
            return self.q_end.copy(), np.zeros_like(self.q_end)
        s, sd = _fraction(self.law, (now - self.t0) * self.scale)
        return self.q_start + s * self.delta, sd * self.scale * self.delta


class _ServoMove(_Segment):
    """servoj: constant speed to the target over ``t``."""

    def at(self, now):
        if now >= self.t_end:
            return self.q_end.copy(), np.zeros_like(self.q_end)
        s = max(now - self.t0, 0.0) / self.duration
        return self.q_start + s * (self.q_end - self.q_start), (
            self.q_end - self.q_start) / self.duration


class _LineMove(_Segment):
    """movel: the TCP on a straight line (SLERP for the rotation), joints by IK."""

    def __init__(self, t0, q_start, pose_end, a, v, t, solve):
        self.solve = solve
        self.p0 = solve.fk_pose(q_start)
        self.p1 = np.asarray(pose_end, dtype=float)
        self.r0 = quaternion_from_rotation_vector(self.p0[3:])
        self.r1 = quaternion_from_rotation_vector(self.p1[3:])
        dist = float(np.linalg.norm(self.p1[:3] - self.p0[:3]))
        if dist < 1e-12:  # a pure rotation: a and v are read as rad/s^2 and rad/s
            dist = float(quaternion_distance(self.r0, self.r1))
        self.law = trapezoid_law(dist, a, v)
        natural = 0.0 if self.law is None else self.law.duration
        duration = t if t > 0 else natural
        self.scale = natural / duration if duration > 0 else 1.0
        q_end = solve.closest(self.p1, q_start)
        self._q_last = q_start.copy()
        super().__init__(t0, duration, q_start, q_end)

    def _q(self, s):
        if s >= 1.0:
            return self.q_end.copy()
        pos = self.p0[:3] + s * (self.p1[:3] - self.p0[:3])
        rot = rotation_vector_from_quaternion(slerp(self.r0, self.r1, s))
        q = self.solve.closest(np.concatenate([pos, rot]), self._q_last)
        self._q_last = q
        return q

    def at(self, now):
        if now >= self.t_end:
            return self.q_end.copy(), np.zeros_like(self.q_end)
        tau = (now - self.t0) * self.scale
        s, sd = _fraction(self.law, tau)
        h = 1e-6
        q = self._q(s)
        q_ahead = self._q(min(s + h, 1.0))
        self._q_last = q
        qd = (q_ahead - q) / h * sd * self.scale if s < 1.0 else np.zeros_like(q)
        return q, qd


class _Kinematics:
    """FK to UR poses and closest IK for one robot (shared by the arm's segments)."""

    def __init__(self, robot, limits):
        self.robot, self.limits = robot, limits

    def fk_pose(self, q):
        return pose_from_transform(self.robot.fk(q))

    def closest(self, pose, q_ref):
        return closest_joints(self.robot, pose, q_ref, self.limits)


class StepClock:
    """A simulated clock that advances by ``dt`` seconds each time it is read.

    For tests and notebooks: a :class:`KinematicBackend` on a ``StepClock`` runs without
    waiting in real time, and deterministically.

    Examples
    --------
    >>> clock = StepClock(0.5)
    >>> clock(), clock(), clock()
    (0.0, 0.5, 1.0)
    """

    def __init__(self, dt):
        if not dt > 0:
            raise ValueError(f"dt must be positive, got {dt!r}")
        self.dt = float(dt)
        self._k = 0

    def __call__(self):
        now = self._k * self.dt
        self._k += 1
        return now


class KinematicBackend:
    """An in-process UR arm that moves its joints along time laws, without physics.

    ``movej`` follows a synchronised trapezoidal law (the leading joint at ``a`` and ``v``,
    the others scaled to arrive together; ``t > 0`` stretches it to that duration);
    ``movel`` moves the TCP on a straight line with the same law on the distance (joints by
    inverse kinematics, branch tracked from the current joints); ``servoj`` moves at
    constant speed to its target in ``t``; ``stop`` halts at once. A new command replaces
    the one running (as a new program does on a controller) and starts from where the arm is,
    at rest (speeds are not blended); :meth:`run` queues several.
    Blend radii ``r`` are accepted and ignored. Targets are checked with the same safety
    checks as the client (:func:`dqlab.ur.script.check_joint_targets`).

    Parameters
    ----------
    robot : dqlab.robot.Robot, optional
        Default :func:`dqlab.models.ur3`.
    q0 : array_like, shape (6,), optional
        Initial joints, rad (default the thesis's home, ``(0, -pi/2, 0, -pi/2, 0, 0)``).
    speedup : float
        Simulated seconds per real second (with the default clock).
    clock : callable, optional
        Returns the simulated time in seconds (e.g. :class:`StepClock`); replaces the real
        clock and ``speedup``.
    limits : SafetyLimits or array_like of shape (6, 2), optional
        Default: the UR3's (see :func:`~dqlab.ur.script.as_safety_limits`).
    """

    name = "kinematic"

    def __init__(self, robot=None, q0=None, *, speedup=1.0, clock=None, limits=None):
        from ..models import ur3

        self.robot = ur3() if robot is None else robot
        self.limits = as_safety_limits(limits)
        q0 = HOME if q0 is None else q0
        self._q0 = check_joint_targets(q0, limits=self.limits, command="q0")
        if not speedup > 0:
            raise ValueError(f"speedup must be positive, got {speedup!r}")
        self.speedup = float(speedup)
        self._clock = clock if clock is not None else (
            lambda: time.monotonic() * self.speedup)
        self._kin = _Kinematics(self.robot, self.limits.joint_limits)
        self._t_connect = None
        self._segment = _Hold(0.0, self._q0)
        self._plan = collections.deque()

    def connect(self, timeout=0.0):
        self._t_connect = self._clock()
        self._segment = _Hold(0.0, self._segment.q_end)

    def close(self):
        self._t_connect = None

    def _now(self):
        if self._t_connect is None:
            raise RuntimeError("KinematicBackend is not connected")
        return self._clock() - self._t_connect

    def _advance(self, now):
        while self._plan and now >= self._segment.t_end:
            start = self._segment.t_end
            self._segment = self._start(self._plan.popleft(), start, self._segment.q_end)

    def _start(self, command, t0, q_from):
        name, target, kw = command
        if name == "movej":
            q = check_joint_targets(target, limits=self.limits, q_from=q_from, command="movej")
            return _JointMove(t0, q_from, q, kw.get("a", 1.4), kw.get("v", 1.05),
                              kw.get("t", 0.0))
        if name == "movel":
            return _LineMove(t0, q_from, check_pose(target), kw.get("a", 1.2),
                             kw.get("v", 0.25), kw.get("t", 0.0), self._kin)
        if name == "servoj":
            q = check_joint_targets(target, limits=self.limits, q_from=q_from, command="servoj")
            return _ServoMove(t0, float(kw.get("t", 0.002)), q_from, q)
        if name == "stopj":
            return _Hold(t0, q_from)
        raise ValueError(f"unknown command {name!r}")

    def run(self, commands):
        """Replace what the arm is doing with a sequence of commands.

        Parameters
        ----------
        commands : iterable of (name, target, kwargs)
            ``name`` in ``movej``, ``movel``, ``servoj``, ``stopj``; each starts when the
            previous one ends.
        """
        now = self._now()
        self._advance(now)
        q_now, _ = self._segment.at(now)
        self._segment = _Hold(now, q_now)
        self._plan = collections.deque(commands)
        self._advance(now)

    def read_state(self):
        now = self._now()
        self._advance(now)
        q, qd = self._segment.at(now)
        return URState(time=now, q=q, qd=qd, tcp_pose=self._kin.fk_pose(q),
                       robot_mode=ROBOT_MODE_RUNNING)

    def movej(self, q, *, a=1.4, v=1.05, t=0.0, r=0.0):
        self.run([("movej", q, {"a": a, "v": v, "t": t, "r": r})])

    def movel(self, pose, *, a=1.2, v=0.25, t=0.0, r=0.0):
        self.run([("movel", pose, {"a": a, "v": v, "t": t, "r": r})])

    def servoj(self, q, *, t=0.002, lookahead_time=0.1, gain=300):
        self.run([("servoj", q, {"t": t})])

    def stop(self, a=2.0):
        self.run([("stopj", None, {"a": a})])


# --------------------------------------------------------------------------------------
# Back ends that talk to a controller


class SecondaryInterfaceBackend:
    """A UR controller (or URSim, or the stand-in) through its text and state ports.

    Commands are URScript lines sent as text to the **secondary interface** (TCP port
    30002), which runs each line it receives as a program; a new line replaces the running
    program. The state is read from the **RTDE** stream (port 30004, protocol version 2,
    output recipe ``timestamp, actual_q, actual_qd, actual_TCP_pose, robot_mode``), not from
    the secondary interface's own binary state messages, whose layout changes between
    controller versions. Whatever the controller sends on port 30002 is read and discarded.

    Parameters
    ----------
    host : str
        The controller's address (the stand-in: ``"127.0.0.1"``).
    port : int
        Secondary interface port.
    rtde_port : int
        RTDE port.
    frequency : float
        RTDE output frequency requested, Hz.
    """

    name = "secondary interface + RTDE"

    def __init__(self, host, port=30002, *, rtde_port=30004, frequency=125.0):
        self.host, self.port, self.rtde_port = host, int(port), int(rtde_port)
        self._reader = RTDEReader(host, rtde_port, STATE_VARIABLES, frequency)
        self._sock = None
        self._t0 = None

    @property
    def controller_version(self):
        """(major, minor, bugfix, build) from RTDE, once connected."""
        return self._reader.controller_version

    def connect(self, timeout=5.0):
        self._sock = socket.create_connection((self.host, self.port), timeout=timeout)
        try:
            self._reader.connect(timeout)
            self._t0 = float(self._reader.read(timeout)["timestamp"])
        except BaseException:
            self.close()
            raise

    def close(self):
        self._reader.close()
        if self._sock is not None:
            try:
                self._sock.close()
            finally:
                self._sock = None

    def _drain(self):
        self._sock.setblocking(False)
        try:
            while True:
                try:
                    if not self._sock.recv(65536):
                        raise ConnectionError("the controller closed the secondary interface")
                except (BlockingIOError, InterruptedError):
                    return
        finally:
            self._sock.setblocking(True)

    def send_script(self, text):
        """Send URScript text (a line or a ``def ... end`` program) as it is."""
        if self._sock is None:
            raise RuntimeError("SecondaryInterfaceBackend is not connected")
        self._drain()
        if not text.endswith("\n"):
            text += "\n"
        self._sock.sendall(text.encode("utf-8"))

    def read_state(self):
        d = self._reader.read()
        return URState(time=float(d["timestamp"]) - self._t0, q=d["actual_q"],
                       qd=d["actual_qd"], tcp_pose=d["actual_TCP_pose"],
                       robot_mode=int(d["robot_mode"]))

    # The texts are written by dqlab.ur.script; URClient has checked the targets against
    # its limits already, and the generators check them once more here.
    def movej(self, q, *, a=1.4, v=1.05, t=0.0, r=0.0):
        self.send_script(script.movej(q, a=a, v=v, t=t, r=r))

    def movel(self, pose, *, a=1.2, v=0.25, t=0.0, r=0.0):
        self.send_script(script.movel(pose, a=a, v=v, t=t, r=r))

    def servoj(self, q, *, t=0.002, lookahead_time=0.1, gain=300):
        self.send_script(script.servoj(q, t=t, lookahead_time=lookahead_time, gain=gain))

    def stop(self, a=2.0):
        self.send_script(script.stopj(a))


def _import_ur_rtde():
    try:
        return (importlib.import_module("rtde_receive"),
                importlib.import_module("rtde_control"))
    except ImportError:
        raise ImportError(
            "RTDEBackend needs the ur_rtde package, which is not installed. Install dqlab's "
            "optional extra 'robot' (pip install 'dqlab[robot]') or ur_rtde itself "
            "(pip install ur_rtde); or use SecondaryInterfaceBackend, which needs nothing."
        ) from None


class RTDEBackend:
    """A UR controller through the ``ur_rtde`` package (optional extra ``robot``).

    State comes from ``rtde_receive.RTDEReceiveInterface``; motions go through
    ``rtde_control.RTDEControlInterface``, which uploads its own control script to the
    controller (a real robot or URSim; the stand-in serves only the receive side: use
    ``control=False`` with it). ``ur_rtde`` always connects to RTDE port 30004.

    Parameters
    ----------
    host : str
    frequency : float
        RTDE frequency, Hz (-1: the controller's maximum).
    control : bool
        Also open the control interface (needed for motions).
    """

    name = "ur_rtde"

    def __init__(self, host, *, frequency=-1.0, control=True):
        self._receive_mod, self._control_mod = _import_ur_rtde()
        self.host, self.frequency, self.control = host, float(frequency), bool(control)
        self._rx = self._ctl = None
        self._t0 = None

    def connect(self, timeout=5.0):
        variables = ["timestamp", "actual_q", "actual_qd", "actual_TCP_pose", "robot_mode"]
        self._rx = self._receive_mod.RTDEReceiveInterface(self.host, self.frequency, variables)
        if self.control:
            self._ctl = self._control_mod.RTDEControlInterface(self.host)
        deadline = time.monotonic() + timeout
        while self._rx.getTimestamp() == 0.0 and time.monotonic() < deadline:
            time.sleep(0.005)
        self._t0 = self._rx.getTimestamp()

    def close(self):
        if self._ctl is not None:
            self._ctl.stopScript()
            self._ctl.disconnect()
            self._ctl = None
        if self._rx is not None:
            self._rx.disconnect()
            self._rx = None

    def read_state(self):
        rx = self._rx
        return URState(time=rx.getTimestamp() - self._t0, q=np.array(rx.getActualQ()),
                       qd=np.array(rx.getActualQd()), tcp_pose=np.array(rx.getActualTCPPose()),
                       robot_mode=int(rx.getRobotMode()))

    def _control(self, command):
        if self._ctl is None:
            raise RuntimeError(f"{command}: this RTDEBackend was opened with control=False")
        return self._ctl

    def movej(self, q, *, a=1.4, v=1.05, t=0.0, r=0.0):
        if t or r:
            raise ValueError("RTDEBackend.movej: ur_rtde takes no t or r; use "
                             "SecondaryInterfaceBackend for timed or blended moves")
        self._control("movej").moveJ(list(map(float, q)), v, a, True)

    def movel(self, pose, *, a=1.2, v=0.25, t=0.0, r=0.0):
        if t or r:
            raise ValueError("RTDEBackend.movel: ur_rtde takes no t or r")
        self._control("movel").moveL(list(map(float, pose)), v, a, True)

    def servoj(self, q, *, t=0.002, lookahead_time=0.1, gain=300):
        self._control("servoj").servoJ(list(map(float, q)), 0.0, 0.0, t, lookahead_time, gain)

    def stop(self, a=2.0):
        self._control("stop").stopJ(a)
