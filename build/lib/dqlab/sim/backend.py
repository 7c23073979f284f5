r"""The simulated UR3 as a back end of the UR client: URScript's moves executed in physics.

:class:`MujocoBackend` has the methods of the client's ``Backend`` protocol
(:mod:`dqlab.ur.client`): ``connect``, ``close``, ``read_state``, ``movej``, ``movel``,
``servoj`` and ``stop``. A move call plans a joint reference and returns at once; the
simulated controller (computed torque by default) tracks it while the simulation runs. The
simulation advances when the state is read: by one controller period (8 ms, the 125 Hz of
the UR3's CB3 controller) per :meth:`MujocoBackend.read_state` with the default simulated
clock, or up to the wall-clock time since :meth:`~MujocoBackend.connect` with
``clock="wall"``.

The references are URScript's:

- ``movej(q, a, v, t)``: every joint moves from the current target to ``q`` with one
  trapezoidal speed law, scaled so that all joints start and stop together; the joint that
  moves most accelerates at ``a`` (rad/s^2) up to ``v`` (rad/s). With ``t > 0`` the move
  lasts ``t`` seconds instead (a third of it accelerating, a third braking). This is
  :func:`dqlab.trajectory.joint.joint_trajectory` with the trapezoidal law.
- ``movel(pose, a, v, t)``: the TCP moves on a straight line while its orientation turns
  by SLERP (:func:`dqlab.trajectory.cartesian.line_slerp`), with the same speed law on the distance
  (m/s, m/s^2); the joints follow by the closed-form inverse kinematics with branch
  tracking (:func:`dqlab.trajectory.follow.follow_path_ur`), from the branch of the start.
- ``servoj(q, t)``: the target moves linearly to ``q`` in ``t`` seconds (one streaming
  step).
- ``stop(a)``: the reference decelerates at ``a`` to rest.

Every target is checked before anything moves: a NaN, an infinity, a wrong shape or a joint
beyond the robot's limits raises ``ValueError``.
"""

import math
import time as _time

import numpy as np

from ..models import ur3
from ..quaternion import quaternion_distance, quaternion_from_matrix
from ..trajectory import follow_path_ur, joint_trajectory, line_slerp, trapezoidal
from ..ur import ROBOT_MODE_RUNNING, URState, check_pose, pose_from_transform, transform_from_pose
from ._checks import number
from .simulation import ArmSimulation, ComputedTorque, sample_reference

__all__ = ["MujocoBackend", "UR3_HOME"]

#: Where the simulated arm starts, away from the singularities: upper arm up, forearm
#: horizontal, wrist bent.
UR3_HOME = (0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0)


class _Motion:
    """A joint reference on a grid of times, sampled by cubic Hermite interpolation."""

    def __init__(self, t, q, qd, qdd, end=None):
        self.t, self.q, self.qd, self.qdd = t, q, qd, qdd
        self.end = t[-1] if end is None else end     # when the move is over

    @classmethod
    def hold(cls, t0, q):
        q = np.asarray(q, dtype=float)
        zero = np.zeros((2, q.size))
        return cls(np.array([t0, t0 + 1.0]), np.array([q, q]), zero, zero, end=t0)

    def sample(self, times, velocity_lag=0.0):
        """Reference positions, velocities (``velocity_lag`` seconds earlier, as in
        :func:`~dqlab.sim.simulation.track`) and accelerations at ``times`` (shape (k,) -> (k, 6)
        each). After the last sample the reference holds the last position at rest."""
        times = np.asarray(times, dtype=float)
        q, qd, qdd = sample_reference(self.t, self.q, self.qd, self.qdd, times,
                                      velocity_lag=velocity_lag)
        over = times >= self.t[-1]
        qd[over] = 0.0
        qdd[over] = 0.0
        return q, qd, qdd


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
    **model_options
        Passed to :class:`~dqlab.sim.simulation.ArmSimulation` (``payload``, ``timestep``...).

    Attributes
    ----------
    sim : ArmSimulation
    name : str

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
                 clock="sim", **model_options):
        robot = ur3() if robot is None else robot
        if robot.n != 6:
            raise ValueError(f"robot must have 6 joints like a UR arm, it has {robot.n}")
        if clock not in ("sim", "wall"):
            raise ValueError(f"clock must be 'sim' or 'wall', got {clock!r}")
        self.name = f"MuJoCo simulation of the {robot.name or 'arm'}"
        self.sim = ArmSimulation(robot, **model_options)
        self.controller = ComputedTorque() if controller is None else controller
        self.period = number(period, "period")
        self.clock = clock
        self.q_home = self.sim.check_target(q_home, "q_home")
        self._connected = False
        self._motion = None
        self._wall_start = None

    # -- connection ---------------------------------------------------------------------------
    def connect(self, timeout=1.0):
        """Start the simulation with the arm at rest at ``q_home`` (time 0)."""
        number(timeout, "timeout")
        self.sim.reset(self.q_home)
        self._motion = _Motion.hold(0.0, self.q_home)
        self._connected = True
        self._wall_start = _time.monotonic()

    def close(self):
        """Stop simulating (a later :meth:`connect` starts again from ``q_home``)."""
        self._connected = False

    def _require_connected(self):
        if not self._connected:
            raise RuntimeError("the simulated arm is not connected; call connect() first")

    # -- running -----------------------------------------------------------------------------
    def advance(self, duration):
        """Run the simulation for ``duration`` seconds under the controller."""
        self._require_connected()
        sim = self.sim
        steps = int(round(number(duration, "duration", strict=False) / sim.timestep))
        controller = self.controller
        times = sim.time + sim.timestep * np.arange(steps)
        q_d, qd_d, qdd_d = self._motion.sample(times, sim.timestep / 2)
        for k in range(steps):
            sim.step(controller.torque(sim, q_d[k], qd_d[k], qdd_d[k]))

    @property
    def is_moving(self):
        """True while the reference of the last move is still running."""
        return self._connected and self.sim.time < self._motion.end

    def read_state(self):
        """Advance the simulation (see ``clock``) and report the state.

        Returns
        -------
        URState
            time (s), q and qd (6,), tcp_pose (6,) as ``[x, y, z, rx, ry, rz]``,
            robot_mode 7 (running).
        """
        self._require_connected()
        if self.clock == "sim":
            self.advance(self.period)
        else:
            self.advance(max(0.0, _time.monotonic() - self._wall_start - self.sim.time))
        return _state(self.sim.time, self.sim.q, self.sim.qd, self.sim.flange_pose())

    # -- moves -------------------------------------------------------------------------------
    def _start(self, motion):
        self._motion = motion

    def _current_target(self):
        """Where the reference is now (a new move starts there)."""
        q, _, _ = self._motion.sample([self.sim.time])
        return q[0]

    @property
    def _dt(self):
        """Sampling period of the planned references (four simulation steps)."""
        return 4 * self.sim.timestep

    def _grid(self, duration):
        count = max(int(math.ceil(duration / self._dt)), 1)
        return np.linspace(0.0, duration, count + 1)

    def movej(self, q, *, a=1.4, v=1.05, t=0.0, r=0.0):
        """Start a move in joint space to ``q`` (rad) with URScript's ``movej`` speed law.

        ``r`` (blend radius) is accepted and checked; moves are not blended. A move
        started while another is running starts where the reference is, from rest (the
        client waits for each move to end, so this only happens on purpose).

        Raises
        ------
        ValueError
            For a target with NaN or infinity, the wrong shape or a joint beyond its limits,
            or a non-positive ``a`` or ``v``, negative ``t`` or ``r``.
        """
        self._require_connected()
        target = self.sim.check_target(q, "q")
        a, v = number(a, "a"), number(v, "v")
        t, r = number(t, "t", strict=False), number(r, "r", strict=False)
        start = self._current_target()
        t0 = self.sim.time
        if np.array_equal(start, target):
            self._start(_Motion.hold(t0, target))
            return
        if t > 0:                  # URScript: with a time, a and v are not used
            move = joint_trajectory(start, target, duration=t, law="trapezoidal",
                                    dt=self._dt)
        else:
            move = joint_trajectory(start, target, v_max=v, a_max=a, law="trapezoidal",
                                    dt=self._dt)
        self._start(_Motion(t0 + move.t, move.q, move.qd, move.qdd))

    def movel(self, pose, *, a=1.2, v=0.25, t=0.0, r=0.0):
        """Start a straight-line move of the TCP to the UR pose vector ``pose``.

        The position moves on a line and the orientation by SLERP, both with one speed law
        on the line's length (m/s and m/s^2; on the rotation angle in rad/s and rad/s^2 for
        a pure rotation): :func:`dqlab.trajectory.cartesian.line_slerp` with the trapezoidal
        law. The joints follow the closed-form inverse kinematics with branch tracking
        (:func:`dqlab.trajectory.follow.follow_path_ur`), from the branch of the start.

        Raises
        ------
        ValueError
            For a pose with NaN or infinity or the wrong shape, a pose out of reach, a path
            that leaves the joint limits or would switch branches (a singularity on the way),
            or bad ``a``, ``v``, ``t``, ``r``.
        """
        self._require_connected()
        pose = check_pose(pose, "pose")
        if pose.shape != (6,):
            raise ValueError(f"pose must be one UR pose vector of shape (6,), got {pose.shape}")
        a, v = number(a, "a"), number(v, "v")
        t, r = number(t, "t", strict=False), number(r, "r", strict=False)
        robot = self.sim.robot
        q_start = self._current_target()
        t0 = self.sim.time
        X_start, X_goal = robot.fk(q_start), transform_from_pose(pose)
        length = float(np.linalg.norm(X_goal[:3, 3] - X_start[:3, 3]))
        angle = quaternion_distance(quaternion_from_matrix(X_start[:3, :3]),
                                    quaternion_from_matrix(X_goal[:3, :3]))
        distance = length if length > 1e-9 else float(angle)
        if distance == 0:
            self._start(_Motion.hold(t0, q_start))
            return
        if t > 0:
            law = trapezoidal(1.0, duration=t)
        else:                      # the limits on the line, for the normalised law s: 0 -> 1
            law = trapezoidal(1.0, v_max=v / distance, a_max=a / distance)
        path = line_slerp(X_start, X_goal, law=law, dt=self._dt)
        try:
            move, report = follow_path_ur(robot, path, q_start=q_start)
        except ValueError as exc:
            raise ValueError(f"pose: {exc}") from None
        if report.switches:
            raise ValueError(f"pose: the line crosses a singularity or needs a jump "
                             f"({report.switches[0]})")
        self._start(_Motion(t0 + move.t, move.q, move.qd, move.qdd))

    def servoj(self, q, *, t=0.008, lookahead_time=0.1, gain=300):
        """One streaming step: the target moves linearly to ``q`` in ``t`` seconds.

        ``lookahead_time`` (0.03-0.2 s) and ``gain`` (100-2000) are checked as URScript does;
        the tracking itself is this back end's controller.

        Raises
        ------
        ValueError
            For a bad target (as :meth:`movej`), ``t <= 0``, or ``lookahead_time`` or
            ``gain`` out of range.
        """
        self._require_connected()
        target = self.sim.check_target(q, "q")
        t = number(t, "t")
        lookahead_time = number(lookahead_time, "lookahead_time")
        gain = number(gain, "gain")
        if not 0.03 <= lookahead_time <= 0.2:
            raise ValueError(f"lookahead_time must be in [0.03, 0.2] s, got {lookahead_time}")
        if not 100 <= gain <= 2000:
            raise ValueError(f"gain must be in [100, 2000], got {gain}")
        start = self._current_target()
        t0 = self.sim.time
        rate = (target - start) / t
        # a line to the target at the constant rate, then a hold (the rate drops to 0 within
        # one simulation step)
        qd = np.array([rate, rate, np.zeros(6)])
        self._start(_Motion(np.array([t0, t0 + t, t0 + t + self.sim.timestep]),
                            np.array([start, target, target]), qd, np.zeros((3, 6))))

    def stop(self, a=2.0):
        """Bring the reference to rest with deceleration ``a`` (rad/s^2) on the fastest joint.

        Raises
        ------
        ValueError
            If ``a`` is not a positive number.
        """
        self._require_connected()
        a = number(a, "a")
        t0 = self.sim.time
        q0, qd0, _ = (x[0] for x in self._motion.sample([t0]))
        fastest = float(np.abs(qd0).max())
        if fastest == 0:
            self._start(_Motion.hold(t0, q0))
            return
        duration = fastest / a
        grid = self._grid(duration)
        tau = grid[:, None]
        decel = qd0 / duration
        q = q0 + qd0 * tau - 0.5 * decel * tau**2
        qd = qd0 - decel * tau
        qdd = np.broadcast_to(-decel, q.shape).copy()
        self._start(_Motion(t0 + grid, q, qd, qdd))


def _state(time, q, qd, X_WT):
    return URState(time=time, q=q, qd=qd, tcp_pose=pose_from_transform(X_WT),
                   robot_mode=ROBOT_MODE_RUNNING)
