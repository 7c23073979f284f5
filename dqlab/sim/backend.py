r"""The simulated UR3 as a back end of the UR client: URScript's moves executed in physics.

:class:`MujocoBackend` has the methods of the client's ``Backend`` protocol
(:mod:`dqlab.ur.client`): ``connect``, ``close``, ``read_state``, ``movej``, ``movel``,
``servoj`` and ``stop``. A move call plans a joint reference and returns at once; the
simulated controller (computed torque by default) tracks it while the simulation runs. The
simulation advances when the state is read: by one controller period (8 ms, the 125 Hz of
the UR3's CB3 controller) per :meth:`MujocoBackend.read_state` with the default simulated
clock, or up to the wall-clock time since :meth:`~MujocoBackend.connect` with
``clock="wall"``.

The references are the motions of :mod:`dqlab.ur.motion`, planned and checked exactly as the
kinematic arm and the controller stand-in plan and check them
(:func:`dqlab.ur.script.plan_program`): what the safety checks accept is what this back end
commands.

- ``movej(q, a, v, t)``: every joint moves on the line to ``q`` with the leading joint's
  trapezoid (acceleration ``a`` up to speed ``v``; with ``t > 0`` the duration ``t``, the
  time having priority), the others scaled to arrive together.
- ``movel(pose, a, v, t)``: the TCP moves on a straight line to the pose (a UR pose vector
  in the controller's base frame) while its orientation turns by SLERP, with the same law on
  the distance; the joints follow the closed-form inverse kinematics with branch tracking.
- ``servoj(q, t)``: the reference moves at constant speed to ``q`` in ``t`` seconds (one
  streaming step).
- ``stop(a)``: the reference decelerates to rest, the fastest joint at ``a``.

A ``movej`` or ``movel`` started while the reference moves first brakes it to rest. Every
target is checked before anything moves: a NaN, an infinity, complex numbers, a wrong shape
or a joint beyond the robot's limits raises ``ValueError`` (or ``TypeError``); a motion that
the limits (:class:`dqlab.ur.script.SafetyLimits`) refuse raises
:class:`~dqlab.ur.script.UnsafeTargetError`.
"""

import math
import time as _time

import numpy as np

from .._checks import check_scalar, real_array
from ..models import ur3
from ..transforms import transform_inverse
from ..ur import ROBOT_MODE_RUNNING, URState, check_pose, pose_from_transform
from ..ur.motion import (
    GAIN,
    LOOKAHEAD_TIME,
    MAX_DURATION,
    MOVEJ_A,
    MOVEJ_V,
    MOVEL_A,
    MOVEL_V,
    SERVOJ_T,
    STOPJ_A,
    Timeline,
)
from ..ur.script import UnsafeTargetError, as_safety_limits, plan_program
from .simulation import ArmSimulation, ComputedTorque

__all__ = ["MujocoBackend", "UR3_HOME"]

#: Where the simulated arm starts, away from the singularities: upper arm up, forearm
#: horizontal, wrist bent.
UR3_HOME = (0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0)


class MujocoBackend:
    r"""A simulated UR arm in MuJoCo behind the UR client's back-end protocol.

    Parameters
    ----------
    robot : Robot, optional
        A six-joint arm (default :func:`dqlab.models.ur3`).
    q_home : array_like, shape (6,), optional
        Where the arm stands after :meth:`connect` (default :data:`UR3_HOME`).
    controller : optional
        The joint controller (default :class:`~dqlab.sim.simulation.ComputedTorque`).
    period : float, optional
        Simulated seconds per :meth:`read_state` with ``clock="sim"`` (default 0.008 s).
    clock : {"sim", "wall"}, optional
        ``"sim"``: each state read advances the simulation by ``period`` (deterministic,
        as fast as the computer allows). ``"wall"``: the simulation keeps up with the wall
        clock since :meth:`connect`.
    limits : SafetyLimits, optional
        The limits the moves are checked against (default: ``robot``'s,
        :meth:`~dqlab.ur.script.SafetyLimits.for_robot`; a robot without rated joint speeds
        needs them given).
    **model_options
        Passed to :class:`~dqlab.sim.simulation.ArmSimulation` (``payload``, ``timestep``...).

    Attributes
    ----------
    sim : ArmSimulation
    name : str
    timeline : dqlab.ur.motion.Timeline
        The reference being executed (simulation time).

    Examples
    --------
    >>> import numpy as np
    >>> arm = MujocoBackend()
    >>> arm.connect(timeout=1.0)
    >>> target = np.array([0.3, -1.2, 1.2, -1.5, -1.5, 0.4])
    >>> arm.movej(target, a=1.4, v=1.05, t=0.0, r=0.0)
    >>> while arm.is_moving:
    ...     state = arm.read_state()
    >>> state.robot_mode
    7
    >>> bool(np.abs(state.q - target).max() < 1e-3)
    True
    >>> arm.close()
    """

    def __init__(self, robot=None, *, q_home=UR3_HOME, controller=None, period=0.008,
                 clock="sim", limits=None, **model_options):
        robot = ur3() if robot is None else robot
        if not hasattr(robot, "fk") or not hasattr(robot, "n"):
            raise TypeError(f"robot must be a dqlab.robot.Robot, got {type(robot).__name__}")
        if robot.n != 6:
            raise ValueError(f"robot must have 6 joints like a UR arm, it has {robot.n}")
        if not isinstance(clock, str) or clock not in ("sim", "wall"):
            raise ValueError(f"clock must be 'sim' or 'wall', got {clock!r}")
        self.limits = as_safety_limits(limits, robot)
        self.name = f"MuJoCo simulation of the {robot.name or 'arm'}"
        self.sim = ArmSimulation(robot, **model_options)
        self.controller = ComputedTorque() if controller is None else controller
        if not callable(getattr(self.controller, "torque", None)):
            raise TypeError(f"controller must have a torque(sim, q, qd, qdd) method, got "
                            f"{type(self.controller).__name__}")
        self.period = check_scalar(period, "period", minimum=0.0, strict=True)
        self.clock = clock
        self.q_home = self._target(q_home, "q_home")
        self._connected = False
        self.timeline = Timeline(self.q_home)
        self._wall_start = None

    def _target(self, q, name):
        """A joint target: real numbers (complex refused, not truncated), then the
        simulation's own check (shape, finite, within the joint limits)."""
        return self.sim.check_target(real_array(q, name), name)

    # -- connection ---------------------------------------------------------------------------
    def connect(self, timeout=1.0):
        """Start the simulation with the arm at rest at ``q_home`` (time 0)."""
        check_scalar(timeout, "timeout", minimum=0.0)
        self.sim.reset(self.q_home)
        self.timeline = Timeline(self.q_home)
        self._connected = True
        self._wall_start = _time.monotonic()

    def close(self):
        """Stop simulating (a later :meth:`connect` starts again from ``q_home``)."""
        self._connected = False

    def _require_connected(self):
        if not self._connected:
            raise RuntimeError("the simulated arm is not connected; call connect() first")

    # -- running -----------------------------------------------------------------------------
    def reference(self, times, velocity_lag=0.0):
        """The commanded ``(q, qd, qdd)`` at the simulation ``times`` (shape (k,) -> (k, 6)
        each); the velocity ``velocity_lag`` seconds earlier (see
        :func:`~dqlab.sim.simulation.track`)."""
        times = np.asarray(times, dtype=float)
        q, qd, qdd = self.timeline.state(times)
        if velocity_lag:
            qd = self.timeline.state(times - velocity_lag)[1]
        return q, qd, qdd

    def advance(self, duration):
        """Run the simulation for ``duration`` seconds under the controller."""
        self._require_connected()
        duration = check_scalar(duration, "duration", minimum=0.0)
        if duration > MAX_DURATION:
            raise ValueError(f"duration = {duration!r} s is longer than {MAX_DURATION:g} s")
        sim = self.sim
        steps = int(round(duration / sim.timestep))
        controller = self.controller
        for first in range(0, steps, 4096):          # the reference, a block at a time
            times = sim.time + sim.timestep * np.arange(min(4096, steps - first))
            q_d, qd_d, qdd_d = self.reference(times, sim.timestep / 2)
            for k in range(len(times)):
                sim.step(controller.torque(sim, q_d[k], qd_d[k], qdd_d[k]))

    @property
    def is_moving(self):
        """True while the reference of the last move is still running."""
        return self._connected and self.sim.time < self.timeline.end_time

    def read_state(self):
        """Advance the simulation (see ``clock``) and report the state.

        Returns
        -------
        URState
            time (s), q and qd (6,), tcp_pose (6,) as ``[x, y, z, rx, ry, rz]`` in the
            controller's base frame (the robot's DH frame 0), robot_mode 7 (running).
        """
        self._require_connected()
        if self.clock == "sim":
            self.advance(self.period)
        else:
            self.advance(max(0.0, _time.monotonic() - self._wall_start - self.sim.time))
        X_WT = self.sim.flange_pose()
        base = self.sim.robot.base
        X_0T = X_WT if np.array_equal(base, np.eye(4)) else transform_inverse(base) @ X_WT
        return URState(time=self.sim.time, q=self.sim.q, qd=self.sim.qd,
                       tcp_pose=pose_from_transform(X_0T), robot_mode=ROBOT_MODE_RUNNING)

    # -- moves -------------------------------------------------------------------------------
    def _run(self, command, *, streaming=False):
        """Plan and check a command from where the reference is now, then run it."""
        now = self.sim.time
        q, qd, _ = self.timeline.state(now)
        try:
            motions = plan_program([command], q_now=q, qd_now=qd, limits=self.limits,
                                   robot=self.sim.robot, streaming=streaming)
        except UnsafeTargetError as exc:
            what = "pose" if command[0] == "movel" else "q"
            raise UnsafeTargetError(f"{what}: {exc}") from None
        self.timeline.run(motions, now)

    def movej(self, q, *, a=MOVEJ_A, v=MOVEJ_V, t=0.0, r=0.0):
        """Start a move in joint space to ``q`` (rad) with URScript's ``movej`` speed law.

        ``r`` (blend radius) is accepted and checked; moves are not blended. A move
        started while another is running first brakes the reference to rest.

        Raises
        ------
        ValueError
            For a target with NaN or infinity, the wrong shape or a joint beyond its limits,
            or a non-positive ``a`` or ``v``, negative ``t`` or ``r``; an
            :class:`~dqlab.ur.script.UnsafeTargetError` for a motion beyond the limits.
        TypeError
            For complex numbers or text.
        """
        self._require_connected()
        target = self._target(q, "q")
        a = check_scalar(a, "a", minimum=0.0, strict=True)
        v = check_scalar(v, "v", minimum=0.0, strict=True)
        t, r = check_scalar(t, "t", minimum=0.0), check_scalar(r, "r", minimum=0.0)
        self._run(("movej", target, {"a": a, "v": v, "t": t, "r": r}))

    def movel(self, pose, *, a=MOVEL_A, v=MOVEL_V, t=0.0, r=0.0):
        """Start a straight-line move of the TCP to a pose.

        ``pose`` is a UR pose vector ``[x, y, z, rx, ry, rz]`` in the controller's base frame
        (the robot's DH frame 0). The position moves on a line and the orientation by SLERP,
        both with one speed law on the line's length (m/s and m/s^2; on the rotation angle
        in rad/s and rad/s^2 for a pure rotation); the joints follow the closed-form inverse
        kinematics with branch tracking (:func:`dqlab.ur.motion.plan_movel`).

        Raises
        ------
        ValueError
            For a pose with NaN or infinity or the wrong shape, a pose out of reach, a path
            that leaves the joint limits or would switch branches (a singularity on the way),
            a motion beyond the limits, or bad ``a``, ``v``, ``t``, ``r``.
        """
        self._require_connected()
        pose = check_pose(pose, "pose")
        if pose.shape != (6,):
            raise ValueError(f"pose must be one UR pose vector of shape (6,), got {pose.shape}")
        a = check_scalar(a, "a", minimum=0.0, strict=True)
        v = check_scalar(v, "v", minimum=0.0, strict=True)
        t, r = check_scalar(t, "t", minimum=0.0), check_scalar(r, "r", minimum=0.0)
        self._run(("movel", pose, {"a": a, "v": v, "t": t, "r": r}))

    def servoj(self, q, *, t=SERVOJ_T, lookahead_time=LOOKAHEAD_TIME, gain=GAIN):
        """One streaming step: the reference moves at constant speed to ``q`` in ``t`` s.

        ``lookahead_time`` (0.03-0.2 s) and ``gain`` (100-2000) are checked as URScript does;
        the tracking itself is this back end's controller.

        Raises
        ------
        ValueError
            For a bad target (as :meth:`movej`), ``t <= 0``, a speed beyond the limits, or
            ``lookahead_time`` or ``gain`` out of range.
        """
        self._require_connected()
        target = self._target(q, "q")
        t = check_scalar(t, "t", minimum=0.0, strict=True)
        lookahead_time = check_scalar(lookahead_time, "lookahead_time", minimum=0.0, strict=True)
        gain = check_scalar(gain, "gain", minimum=0.0, strict=True)
        if not 0.03 <= lookahead_time <= 0.2:
            raise ValueError(f"lookahead_time must be in [0.03, 0.2] s, got {lookahead_time}")
        if not 100 <= gain <= 2000:
            raise ValueError(f"gain must be in [100, 2000], got {gain}")
        self._run(("servoj", target, {"t": t, "lookahead_time": lookahead_time, "gain": gain}),
                  streaming=True)

    def stop(self, a=STOPJ_A):
        """Bring the reference to rest with deceleration ``a`` (rad/s^2) on the fastest joint.

        Raises
        ------
        ValueError
            If ``a`` is not a positive number (or above the limits' acceleration).
        """
        self._require_connected()
        a = check_scalar(a, "a", minimum=0.0, strict=True)
        self._run(("stopj", None, {"a": a}))
