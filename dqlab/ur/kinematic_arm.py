"""An arm in this process that executes URScript motions without physics.

:class:`KinematicBackend` is the controller of the stand-in (:mod:`dqlab.ur.standin`) and a
back end of :class:`~dqlab.ur.client.URClient` in its own right: a program (one command or
several) is planned and checked as a whole with :func:`dqlab.ur.script.plan_program` from the
arm's joints and speeds -- the motions of :mod:`dqlab.ur.motion`, their peaks and the changes
of speed between them -- and only then executed; a program refused anywhere moves nothing.
:class:`StepClock` gives it a simulated clock for tests and notebooks.
"""

import math
import time

from ._args import positive_number
from .client import robot_and_limits
from .motion import (
    GAIN,
    LOOKAHEAD_TIME,
    MOVEJ_A,
    MOVEJ_V,
    MOVEL_A,
    MOVEL_V,
    SERVOJ_T,
    STOPJ_A,
    Timeline,
    controller_pose,
)
from .script import check_joint_targets, plan_program
from .state import HOME, ROBOT_MODE_RUNNING, URState

__all__ = ["StepClock", "KinematicBackend"]


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
        self.dt = positive_number(dt, "dt")
        self._k = 0

    def __call__(self):
        now = self._k * self.dt
        self._k += 1
        return now


class KinematicBackend:
    """An in-process UR arm that executes the motions of :mod:`dqlab.ur.motion`, without physics.

    ``movej`` follows the leading joint's trapezoid with every joint scaled to arrive
    together; ``movel`` moves the TCP on a straight line (joints by inverse kinematics with
    branch tracking); ``servoj`` moves at constant speed to its target in ``t``; ``stop``
    decelerates every joint to rest, the fastest at ``a``. A new program replaces the one
    running (as on a controller): a ``movej`` or ``movel`` arriving while the arm moves
    first brakes it to rest at the limits' ``max_joint_acceleration``; a ``servoj`` takes
    over from where the arm is (a stream). Blend radii ``r`` are accepted and not executed.
    Every program is checked as a whole, as the controller would run it, by
    :func:`dqlab.ur.script.plan_program`: a refused program raises and moves nothing.

    Parameters
    ----------
    robot : dqlab.robot.Robot, optional
        Default :func:`dqlab.models.ur3`.
    q0 : array_like, shape (6,), optional
        Initial joints, rad (default the thesis's home, ``(0, -pi/2, 0, -pi/2, 0, 0)``).
    speedup : float
        Simulated seconds per real second (with the default clock; > 0).
    clock : callable, optional
        Returns the simulated time in seconds (e.g. :class:`StepClock`); replaces the real
        clock and ``speedup``.
    limits : SafetyLimits or array_like of shape (6, 2), optional
        Default: ``robot``'s limits, or the UR3's (see
        :func:`~dqlab.ur.script.as_safety_limits`).

    Examples
    --------
    >>> arm = KinematicBackend(clock=StepClock(0.5))
    >>> arm.connect()
    >>> arm.run([("movej", [0.5, -1.5, 0, -1.5, 0, 0], {}), ("movej", [9.0] * 6, {})])
    Traceback (most recent call last):
    ...
    dqlab.ur.script.UnsafeTargetError: line 2: movej target: joint 1 = 9 rad is outside ...
    >>> arm.read_state().q.round(6) + 0.0                 # nothing moved
    array([ 0.      , -1.570796,  0.      , -1.570796,  0.      ,  0.      ])
    """

    name = "kinematic"

    def __init__(self, robot=None, q0=None, *, speedup=1.0, clock=None, limits=None):
        self.robot, self.limits = robot_and_limits(robot, limits)
        q0 = HOME if q0 is None else q0
        self._q0 = check_joint_targets(q0, limits=self.limits, command="q0")
        self.speedup = positive_number(speedup, "speedup")
        if clock is not None and not callable(clock):
            raise TypeError(f"clock must be a callable returning seconds, got {clock!r}")
        self._clock = clock if clock is not None else (
            lambda: time.monotonic() * self.speedup)
        self._t_connect = None
        self._timeline = Timeline(self._q0)

    def connect(self, timeout=0.0):
        """Start the arm's clock (time 0); the arm stands where it stopped."""
        q = self._timeline.state(self._timeline.end_time)[0]
        self._t_connect = self._clock()
        self._timeline = Timeline(q)

    def close(self):
        self._t_connect = None

    def _now(self):
        if self._t_connect is None:
            raise RuntimeError("KinematicBackend is not connected")
        now = float(self._clock()) - self._t_connect
        if not math.isfinite(now):
            raise RuntimeError(f"the clock returned {now!r}")
        return now

    @property
    def timeline(self):
        """The :class:`~dqlab.ur.motion.Timeline` being executed (times since connect)."""
        return self._timeline

    def run(self, commands, *, streaming=False):
        """Replace what the arm is doing with a program: commands executed one after the
        other, once all are checked.

        Parameters
        ----------
        commands : sequence of (name, target, kwargs)
            ``name`` in ``movej``, ``movel``, ``servoj``, ``stopj``.
        streaming : bool
            One ``servoj`` line of a stream (see :func:`dqlab.ur.script.plan_program`).

        Raises
        ------
        UnsafeTargetError, TypeError
            Naming the line and the reason; the arm carries on with what it was doing.
        """
        now = self._now()
        q, qd, _ = self._timeline.state(now)
        motions = plan_program(commands, q_now=q, qd_now=qd, limits=self.limits,
                               robot=self.robot, streaming=streaming)
        self._timeline.run(motions, now)

    @property
    def is_moving(self):
        """True until the last motion of the running program has ended."""
        return self._t_connect is not None and self._now() < self._timeline.end_time

    def read_state(self):
        """The arm's :class:`~dqlab.ur.state.URState` now: joints, speeds, and the TCP pose in
        the controller's base frame (the robot's DH frame 0,
        :func:`dqlab.ur.motion.controller_pose`)."""
        now = self._now()
        q, qd, _ = self._timeline.state(now)
        return URState(time=now, q=q, qd=qd, tcp_pose=controller_pose(self.robot, q),
                       robot_mode=ROBOT_MODE_RUNNING)

    def movej(self, q, *, a=MOVEJ_A, v=MOVEJ_V, t=0.0, r=0.0):
        """Start ``movej(q, a, v, t, r)`` (a one-line program: see :meth:`run`)."""
        self.run([("movej", q, {"a": a, "v": v, "t": t, "r": r})])

    def movel(self, pose, *, a=MOVEL_A, v=MOVEL_V, t=0.0, r=0.0):
        """Start ``movel(pose, a, v, t, r)``; ``pose`` is a UR pose vector
        ``[x, y, z, rx, ry, rz]`` of the TCP in the controller's base frame."""
        self.run([("movel", pose, {"a": a, "v": v, "t": t, "r": r})])

    def servoj(self, q, *, t=SERVOJ_T, lookahead_time=LOOKAHEAD_TIME, gain=GAIN):
        """One ``servoj`` of a stream: from where the arm is to ``q`` in ``t`` seconds."""
        self.run([("servoj", q, {"t": t, "lookahead_time": lookahead_time, "gain": gain})],
                 streaming=True)

    def stop(self, a=STOPJ_A):
        """``stopj(a)``: every joint brakes to rest, the fastest at ``a`` rad/s^2."""
        self.run([("stopj", None, {"a": a})])
