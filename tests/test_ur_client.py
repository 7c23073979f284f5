"""URClient and the in-process kinematic arm: motions, waiting, and checks before sending."""

from types import SimpleNamespace

import numpy as np
import pytest

import dqlab
from dqlab.ur import HOME, KinematicBackend, StepClock, URClient, URState
from dqlab.ur.motion import move_law
from dqlab.ur.script import UnsafeTargetError
from dqlab.ur.state import ROBOT_MODE_RUNNING


class RecordingBackend:
    """A back end that records what reaches it (and reports a fixed state)."""

    name = "recording"

    def __init__(self, q=HOME, mode=ROBOT_MODE_RUNNING):
        self.calls = []
        self.q = np.array(q, dtype=float)
        self.mode = mode

    def connect(self, timeout):
        self.calls.append(("connect", timeout))

    def close(self):
        self.calls.append(("close",))

    def read_state(self):
        pose = dqlab.ur.pose_from_transform(dqlab.models.ur3().fk(self.q))
        return URState(0.0, self.q.copy(), np.zeros(6), pose, self.mode)

    def movej(self, q, *, a, v, t, r):
        self.calls.append(("movej", q))

    def movel(self, pose, *, a, v, t, r):
        self.calls.append(("movel", pose))

    def servoj(self, q, *, t, lookahead_time, gain):
        self.calls.append(("servoj", q))

    def stop(self, a):
        self.calls.append(("stop", a))


def _client(q0=HOME, dt=0.01):
    return URClient(KinematicBackend(q0=q0, clock=StepClock(dt)), poll_interval=0)


def test_backends_satisfy_the_protocol():
    for backend in (KinematicBackend(), RecordingBackend()):
        for name in ("name", "connect", "close", "read_state", "movej", "movel", "servoj",
                     "stop"):
            assert hasattr(backend, name)


def test_move_law():
    assert move_law(1.0, 2.0, 1.0).duration == pytest.approx(1.5)
    assert move_law(0.1, 1.0, 1.0).duration == pytest.approx(2 * np.sqrt(0.1))
    assert move_law(0.0, 1.0, 1.0) is None
    D, a, v = 1.0, 2.0, 1.0
    law = move_law(D, a, v)
    ts = np.linspace(0, law.duration, 2001)
    s, sd = law.position(ts) / D, law.speed(ts) / D
    assert s[0] == 0 and s[-1] == 1 and np.all(np.diff(s) >= 0)
    assert np.max(sd) * D == pytest.approx(v)
    np.testing.assert_allclose(np.gradient(s, ts), sd, atol=2e-3)


def test_movej_reaches_the_target_exactly_and_follows_the_time_law():
    target = np.array([0.5, -1.2, 0.8, -1.5, -1.0, 0.3])
    with _client() as ur:
        start = ur.read_state()
        final = ur.movej(target, a=1.4, v=1.05)
        np.testing.assert_array_equal(final.q, target)
        np.testing.assert_array_equal(final.qd, np.zeros(6))
        duration = move_law(np.max(np.abs(target - HOME)), 1.4, 1.05).duration
        assert duration <= final.time - start.time <= duration + 0.05
        np.testing.assert_allclose(ur.actual_tcp_pose(), dqlab.ur.pose_from_transform(
            dqlab.models.ur3().fk(target)), atol=1e-15)


def test_movej_with_time_and_halfway_state():
    target = np.add(HOME, [0.4, 0, 0, 0, 0, -0.2])
    backend = KinematicBackend(clock=StepClock(0.05))
    with URClient(backend, poll_interval=0) as ur:
        ur.movej(target, t=2.0, wait=False)
        states = [ur.read_state() for _ in range(50)]
    times = np.array([s.time for s in states])
    q1 = np.array([s.q[0] for s in states])
    # synchronised: joint 6 moves by -1/2 of joint 1 all along
    np.testing.assert_allclose([s.q[5] for s in states], -0.5 * q1, atol=1e-15)
    assert q1[np.argmin(np.abs(times - 1.0 - times[0]))] == pytest.approx(0.2, abs=0.03)
    assert q1[-1] == pytest.approx(0.4)


def test_movel_moves_the_tcp_on_a_line():
    # from a regular configuration (HOME, the arm straight up, is singular: a line out of it
    # needs joint speeds without bound, and is refused)
    q0 = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])
    with _client(q0=q0, dt=0.02) as ur:
        p0 = ur.actual_tcp_pose()
        goal = ur.actual_tcp_pose().copy()
        goal[:3] += [0.05, -0.03, -0.1]
        final = ur.movel(goal, v=0.1)
        np.testing.assert_allclose(final.tcp_pose, goal, atol=1e-9)
        # and in between, the TCP stayed on the segment
        backend = KinematicBackend(q0=q0, clock=StepClock(0.02))
        backend.connect()
        backend.movel(goal, a=1.2, v=0.1, t=0.0, r=0.0)
        u = (goal[:3] - p0[:3]) / np.linalg.norm(goal[:3] - p0[:3])
        for _ in range(80):
            d = backend.read_state().tcp_pose[:3] - p0[:3]
            assert np.linalg.norm(d - (d @ u) * u) < 1e-9
    with _client(dt=0.02) as ur, pytest.raises(UnsafeTargetError, match="singularity"):
        ur.movel(ur.actual_tcp_pose() + [0.05, -0.03, -0.1, 0, 0, 0])


def test_servoj_stream_tracks_a_trajectory():
    t = np.linspace(0.0, 1.0, 51)
    q = HOME + np.outer(0.5 * (1 - np.cos(np.pi * t)), [0.3, 0.2, -0.2, 0.1, 0.0, 0.4])

    class Traj:
        pass

    traj = Traj()
    traj.t, traj.q = t, q
    with _client(dt=0.005) as ur:
        log = ur.servoj_stream(traj)
    np.testing.assert_array_equal(log[-1].q, q[-1])
    sent_at = np.array([s.time for s in log[1:-1]]) - log[0].time
    assert np.all(sent_at >= t[:-1] - 1e-12)
    assert np.all(sent_at <= t[:-1] + 0.0101)


def test_servoj_stream_refuses_a_start_away_from_the_arm():
    class Traj:
        t = np.array([0.0, 0.1])
        q = np.array([np.add(HOME, 0.1), np.add(HOME, 0.1)])

    with _client() as ur, pytest.raises(UnsafeTargetError, match="movej to q\\[0\\] first"):
        ur.servoj_stream(Traj())


@pytest.mark.parametrize("call, words", [
    (lambda ur: ur.movej([0, 0, 0, 0, 0, np.nan]), "joint 6 is nan"),
    (lambda ur: ur.movej([7.0, -1.5, 0, -1.5, 0, 0]), "joint 1 = 7 rad is outside"),
    (lambda ur: ur.movej(np.add(HOME, [0, 0, 3.5, 0, 0, 0])), "would jump by 3.5 rad"),
    (lambda ur: ur.movej(HOME, v=5.0), "v = 5.0 refused"),
    (lambda ur: ur.movel([0.0, 0.0, 1.0, 0, 0, 0]), "out of the UR3's reach"),
    (lambda ur: ur.movel([0.2, -0.2, np.inf, 0, 3.1, 0]), "contains NaN or infinity"),
])
def test_unsafe_targets_never_reach_the_backend(call, words):
    backend = RecordingBackend()
    with URClient(backend) as ur:
        with pytest.raises(UnsafeTargetError) as info:
            call(ur)
    assert words in str(info.value)
    assert [c[0] for c in backend.calls] == ["connect", "close"]


def test_movel_refuses_a_line_that_leaves_the_joint_limits():
    # joint 1 at 6.0 rad, near its +2 pi limit; the line to the target turns joint 1 to
    # 6.8 = 0.517 + 2 pi, beyond the limit: refused, naming the joint and where
    q_now = np.array([6.0, -1.0, 1.2, -1.5, 1.2, 0.0])
    q_goal = q_now + [0.8, 0, 0, 0, 0, 0]
    pose = dqlab.ur.pose_from_transform(dqlab.models.ur3().fk(q_goal))
    backend = RecordingBackend(q_now)
    with URClient(backend) as ur, pytest.raises(
            UnsafeTargetError, match=r"the tracked joints leave the joint limits: joint 1 = "
                                     r"6\.28"):
        ur.movel(pose)
    assert "movel" not in [c[0] for c in backend.calls]


def test_not_running_robot_is_refused():
    with URClient(RecordingBackend(mode=5)) as ur, pytest.raises(RuntimeError,
                                                                 match="robot mode is 5"):
        ur.movej(HOME)


def test_timeout_says_how_far_the_arm_is():
    class StuckBackend(RecordingBackend):
        pass

    with URClient(StuckBackend(), poll_interval=0.001) as ur:
        with pytest.raises(TimeoutError, match=r"joint 1 is 0.1 rad away"):
            ur.movej(np.add(HOME, [0.1, 0, 0, 0, 0, 0]), timeout=0.05)


def test_client_outside_with_block_and_close_is_idempotent():
    backend = RecordingBackend()
    ur = URClient(backend)
    with pytest.raises(RuntimeError, match="not connected"):
        ur.actual_q()
    with ur:
        np.testing.assert_array_equal(ur.actual_q(), HOME)
    ur.close()
    assert [c[0] for c in backend.calls] == ["connect", "close"]


def test_stop_brings_the_arm_to_rest_at_its_deceleration():
    # (the arm used to halt at once, an infinite deceleration; it now brakes at a)
    with _client(dt=0.05) as ur:
        ur.movej(np.add(HOME, [1.0, 0, 0, 0, 0, 0]), wait=False)
        for _ in range(10):
            moving = ur.read_state()
        assert moving.qd[0] > 0.5
        ur.stop(a=2.0)
        states = [ur.read_state() for _ in range(40)]
    qd = np.array([s.qd[0] for s in states])
    t = np.array([s.time for s in states])
    assert np.all(np.abs(np.diff(qd) / np.diff(t)) <= 2.0 + 1e-9)
    assert qd[-1] == 0.0 and states[-1].q[0] == states[-2].q[0]
    assert moving.q[0] < states[-1].q[0] < 1.0


def test_kinematic_backend_refuses_out_of_limit_targets_itself():
    backend = KinematicBackend(clock=StepClock(0.01))
    backend.connect()
    with pytest.raises(ValueError, match="outside its limits"):
        backend.movej([9.0, 0, 0, 0, 0, 0], a=1.0, v=1.0, t=0, r=0)
    with pytest.raises(ValueError, match="speedup must be a finite number > 0"):
        KinematicBackend(speedup=0)


def test_rtde_backend_without_ur_rtde_names_the_extra(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "rtde_receive", None)   # as if ur_rtde were absent
    monkeypatch.setitem(sys.modules, "rtde_control", None)
    with pytest.raises(ImportError, match=r"extra 'robot' \(pip install 'dqlab\[robot\]'\)"):
        dqlab.ur.RTDEBackend("127.0.0.1")


# --- frames, limits from the robot, and NaN never switching a check off ---------------------

def _mounted():
    """A UR3 mounted in a cell: 0.8 m up on a pedestal at (1, 0.5), turned a quarter turn."""
    robot = dqlab.models.ur3()
    robot.base = dqlab.transform_from(dqlab.rot_z(np.pi / 2), [1.0, 0.5, 0.8])
    return robot


def test_poses_are_in_the_controllers_base_frame_for_an_arm_mounted_in_a_cell():
    mounted, floor = _mounted(), dqlab.models.ur3()
    q0 = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])
    arm = KinematicBackend(mounted, q0=q0, clock=StepClock(0.02))
    with URClient(arm, mounted, poll_interval=0) as ur:
        pose = ur.actual_tcp_pose()
        # the controller reports the pose in its base frame (DH frame 0), not the world's
        np.testing.assert_allclose(pose, dqlab.ur.pose_from_transform(floor.fk(q0)),
                                   atol=1e-15)
        # and takes its targets there: a base-frame pose is reached, not refused
        goal = pose + [0.03, -0.02, -0.04, 0, 0, 0]
        final = ur.movel(goal, v=0.1)
        np.testing.assert_allclose(final.tcp_pose, goal, atol=1e-9)
        np.testing.assert_allclose(mounted.fk(final.q),
                                   mounted.base @ dqlab.ur.transform_from_pose(goal),
                                   atol=1e-9)
        # the world pose of the same target is somewhere else, out of the arm's reach
        world = dqlab.ur.pose_from_transform(mounted.base @ dqlab.ur.transform_from_pose(goal))
        with pytest.raises(UnsafeTargetError, match="out of the UR3's reach"):
            ur.movel(world)
    assert dqlab.ur.movel(goal, robot=mounted).startswith("movel(")


def test_the_limits_are_the_robots_own():
    ur5 = dqlab.models.ur5()
    limits = dqlab.ur.SafetyLimits.for_robot(ur5)
    np.testing.assert_allclose(limits.max_joint_speed, np.pi)           # 180 deg/s, all six
    np.testing.assert_allclose(dqlab.ur.SafetyLimits.for_robot(dqlab.models.ur10())
                               .max_joint_speed[:2], np.radians(120))
    assert URClient(RecordingBackend(), ur5).limits.max_joint_speed[5] == pytest.approx(np.pi)
    assert URClient(RecordingBackend()).limits.max_joint_speed[5] == pytest.approx(2 * np.pi)
    with pytest.raises(ValueError, match=r"no rated speed for joints \[1, 2, 3, 4, 5, 6\] "
                                         r"\(Link.max_speed\): give max_joint_speed="):
        dqlab.ur.SafetyLimits.for_robot(dqlab.models.ur3_mdh())
    custom = dqlab.ur.SafetyLimits.for_robot(dqlab.models.ur3_mdh(), max_joint_speed=1.0)
    assert custom.robot.name and np.all(custom.max_joint_speed == 1.0)
    # reach is checked against the robot given, never silently a UR3
    far = dqlab.ur.pose_from_transform(dqlab.models.ur10().fk([0, -0.3, 0.3, 0, 1.0, 0]))
    with pytest.raises(UnsafeTargetError, match="out of the UR3's reach"):
        dqlab.ur.movel(far)
    assert dqlab.ur.movel(far, limits=dqlab.ur.SafetyLimits.for_robot(dqlab.models.ur10()))
    with pytest.raises(ValueError, match="which robot"):
        dqlab.ur.movel(far, limits=dqlab.ur.SafetyLimits())


def test_nan_and_negative_values_never_switch_a_check_off():
    backend = RecordingBackend()
    with URClient(backend) as ur:
        for a in (np.nan, -5.0, 0.0, 50.0):
            with pytest.raises(UnsafeTargetError, match="stopj: a = "):
                ur.stop(a)
        with pytest.raises(ValueError, match="start_tol must be a number >= 0, got nan"):
            ur.servoj_stream(SimpleNamespace(t=[0.0, 0.1], q=[HOME, HOME]), start_tol=np.nan)
        with pytest.raises(UnsafeTargetError, match=r"q must have shape \(N, 6\) with N >= 1"):
            ur.servoj_stream(SimpleNamespace(t=[], q=np.zeros((0, 6))))
    assert [c[0] for c in backend.calls] == ["connect", "close"]
    with pytest.raises(UnsafeTargetError, match=r"q_from \(where the arm is\) must be 6 finite"):
        dqlab.ur.movej(HOME, q_from=[np.nan] * 6)
    for tol in (np.nan, -1.0):
        with pytest.raises(ValueError, match="tol must be a number >= 0"):
            URClient(RecordingBackend(), tol=tol)
        with pytest.raises(ValueError, match="tol must be a number >= 0"):
            dqlab.ur.rotation_vector_from_quaternion([1.0, 0, 0, 0], tol=tol)
    with pytest.raises(TypeError, match="must hold real numbers, got complex"):
        dqlab.ur.movej(np.add(HOME, 1j))


def test_the_client_takes_the_robot_and_limits_of_its_back_end():
    """URClient(standin.backend()) drives the stand-in's arm -- a UR5e, calibrated here --
    not a UR3: the robot, the limits and the poses it checks are that arm's."""
    from dqlab.ur import ControllerStandIn, pose_from_transform
    from dqlab.ur.calibration import CalibrationConf

    factory = CalibrationConf((0, 1e-3, 0, 0, 0, 0), (0, -5e-4, 0, 0, 0, 0), (0.0,) * 6,
                              (0.0,) * 6)
    q = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])
    with ControllerStandIn("ur5e", q0=q, speedup=25, calibration=factory) as standin:
        with URClient(standin.backend(), poll_interval=0.001) as ur:
            assert ur.robot.name == "UR5e (calibrated)" and ur.limits.robot is ur.robot
            assert ur.robot.links[1].theta_offset == 1e-3
            np.testing.assert_allclose(ur.actual_tcp_pose(),
                                       pose_from_transform(ur.robot.fk(q)), atol=1e-12)
            goal = ur.actual_tcp_pose() + [0.02, 0.0, -0.02, 0.0, 0.0, 0.0]
            np.testing.assert_allclose(ur.movel(goal).tcp_pose, goal, atol=1e-9)
    arm = KinematicBackend(dqlab.models.ur10e(), clock=StepClock(0.01))
    assert URClient(arm).robot.name == "UR10e"
    assert URClient(arm, dqlab.models.ur3()).robot.name == "UR3"      # given: it wins


@pytest.mark.parametrize("call, hint", [
    (lambda ur: ur.movej(np.degrees([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])), "degrees? "),
    (lambda ur: ur.movel([200.0, -150.0, 300.0, 0.0, 3.14, 0.0]), "millimetres? "),
    (lambda ur: ur.movel([0.2, -0.15, 0.3, 0.0, 180.0, 0.0]), "degrees? "),
    (lambda ur: ur.closest_joints([200.0, -150.0, 300.0, 0.0, 3.14, 0.0]), "millimetres? "),
])
def test_a_target_in_degrees_or_millimetres_gets_a_hint(call, hint):
    with _client() as ur:
        with pytest.raises(UnsafeTargetError, match=hint.replace("?", r"\?")):
            call(ur)
        with pytest.raises(UnsafeTargetError) as plain:
            ur.movej([0.0, -1.5, 0.0, -1.5, 0.0, 5.0])          # radians: a jump of wrist 3
        assert "degrees?" not in str(plain.value)
