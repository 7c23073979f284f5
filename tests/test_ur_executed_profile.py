"""What is checked is what runs: for random moves and trajectories that the safety checks
accept, the joint speeds and accelerations sampled from every back end -- the kinematic arm
(hence the stand-in) and the MuJoCo back end's commanded motion -- stay within the limits the
checks enforce, to 1e-9; what they refuse does exceed a limit. The same for the joint
torques of an arm carrying a heavy payload: the inverse dynamics of the executed motion,
sampled four times finer than the check samples it, stays within the rated torques (to the
check's sampling, 1e-3); what the check refuses for a torque does exceed one, as much as its
message says, at the time it says."""

import math
import re
from types import SimpleNamespace

import numpy as np
import pytest

from dqlab import dynamics
from dqlab.models import ur3
from dqlab.ur import KinematicBackend, SafetyLimits, StepClock, UnsafeTargetError, URClient
from dqlab.ur import motion as M
from dqlab.ur import script as S
from dqlab.ur.standin import parse_urscript

ROBOT = ur3()
LIMITS = SafetyLimits.for_robot(ROBOT)
Q_MID = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])       # away from the singularities
EPS = 1e-9


def assert_within_limits(t, q, qd=None, *, servo=False):
    """Sampled peaks: speed |dq/dt| (and the reported |qd|) and acceleration (from the
    reported speeds, or for a servoj stream the second differences at its period)."""
    dt = np.diff(t)[:, None]
    v = np.diff(q, axis=0) / dt
    speed = np.abs(v)
    assert np.all(speed <= LIMITS.max_joint_speed + EPS), speed.max(axis=0)
    if servo:
        acc = np.abs(np.diff(v, axis=0)) / (0.5 * (dt[1:] + dt[:-1]))
    else:
        assert np.all(np.abs(qd) <= LIMITS.max_joint_speed + EPS)
        acc = np.abs(np.diff(qd, axis=0)) / dt
    assert np.all(acc <= LIMITS.max_joint_acceleration + EPS), acc.max()
    return speed.max(), acc.max()


def run_kinematic(q0, command, dt):
    """Execute one command on the kinematic arm; sample it every ``dt`` until it ends."""
    arm = KinematicBackend(q0=q0, clock=StepClock(dt), limits=LIMITS)
    arm.connect()
    before = arm.read_state()
    arm.run([command])
    states = [before]
    while True:
        states.append(arm.read_state())
        if states[-1].time > arm.timeline.end_time + 2 * dt:
            break
    return (np.array([s.time for s in states]), np.array([s.q for s in states]),
            np.array([s.qd for s in states]))


def random_movej(rng):
    q0 = rng.uniform(-5.0, 5.0, 6)
    q1 = np.clip(q0 + rng.uniform(-3.0, 3.0, 6), -6.2, 6.2)
    t = 0.0 if rng.random() < 0.3 else float(rng.uniform(0.3, 3.0))
    return q0, q1, dict(a=float(rng.uniform(0.5, 10.0)), v=float(rng.uniform(0.3, np.pi)),
                        t=t)


def test_movej_with_a_time_is_checked_on_its_peak_not_its_average():
    # the case: 3 rad in t = 1 s averages 3 rad/s but peaks at 6 (triangle)
    with pytest.raises(UnsafeTargetError, match=r"joint 1 speed 6 rad/s exceeds 3\.14159"):
        S.movej([3.0, 0, 0, 0, 0, 0], t=1.0, q_from=np.zeros(6))
    m = M.plan_movej(np.zeros(6), [3.0, 0, 0, 0, 0, 0], t=1.0)
    t = np.linspace(0.0, 1.0, 100_001)
    assert np.abs(m.at(t)[1][:, 0]).max() == pytest.approx(6.0, abs=1e-4)


@pytest.mark.parametrize("law", [M.move_law(1.3, 2.0, 0.7), M.move_law(0.4, 1.0, 1.0, t=2.0),
                                 M.plan_stop([0.0], [1.5], 4.0).law,
                                 M.plan_servoj([0.0], [0.1], 0.008).law,
                                 __import__("dqlab").trajectory.quintic(1.5, 2.0)])
def test_the_fast_law_evaluation_equals_the_time_laws(law):
    t = np.linspace(0.0, law.duration, 1001)
    fast = M._law_values(law, t)
    for got, want in zip(fast, law(t), strict=True):
        np.testing.assert_allclose(got[:-1], want[:-1], rtol=1e-13, atol=1e-13)
    peaks = M._law_peaks(law)
    assert peaks == pytest.approx((law.peak_speed, law.peak_acceleration), rel=1e-12)
    for k in (0, 500):                                  # one instant, as a state read
        np.testing.assert_allclose([x[k] for x in fast],
                                   [float(x) for x in M._law_values(law, np.float64(t[k]))])


def test_random_movej_on_the_kinematic_arm():
    rng = np.random.default_rng(41)
    accepted = refused = 0
    for _ in range(40):
        q0, q1, kw = random_movej(rng)
        try:
            S.movej(q1, **kw, limits=LIMITS, q_from=q0)
        except UnsafeTargetError as exc:
            refused += 1
            if "speed" in str(exc) or "acceleration" in str(exc):   # a real excess
                m = M.plan_movej(q0, q1, **kw)
                t = np.linspace(0.0, m.duration, 20_001)
                _, qd, qdd = m.at(t)
                assert (np.any(np.abs(qd).max(0) > LIMITS.max_joint_speed * (1 - 1e-3))
                        or np.abs(qdd).max() > LIMITS.max_joint_acceleration * (1 - 1e-3))
            continue
        accepted += 1
        t, q, qd = run_kinematic(q0, ("movej", q1, kw), float(rng.uniform(0.005, 0.04)))
        assert_within_limits(t, q, qd)
        np.testing.assert_array_equal(q[-1], q1)
    assert accepted >= 10 and refused >= 10


def random_movel(rng):
    q0 = Q_MID + rng.normal(0.0, 0.25, 6)
    goal = M.controller_pose(ROBOT, q0) + np.r_[rng.normal(0.0, 0.06, 3),
                                                rng.normal(0.0, 0.15, 3)]
    t = 0.0 if rng.random() < 0.6 else float(rng.uniform(0.2, 2.0))
    return q0, goal, dict(a=float(rng.uniform(0.1, 2.0)), v=float(rng.uniform(0.02, 0.6)),
                          t=t)


def test_random_movel_on_the_kinematic_arm():
    rng = np.random.default_rng(42)
    accepted = refused = 0
    for _ in range(24):
        q0, goal, kw = random_movel(rng)
        try:
            S.movel(goal, **kw, limits=LIMITS, q_from=q0)
        except UnsafeTargetError:
            refused += 1
            continue
        accepted += 1
        t, q, qd = run_kinematic(q0, ("movel", goal, kw), float(rng.uniform(0.004, 0.02)))
        assert_within_limits(t, q, qd)
        np.testing.assert_allclose(ROBOT.fk(q[-1]), M.world_transform(ROBOT, goal),
                                   atol=1e-12)
    assert accepted >= 8 and refused >= 3


def random_trajectory(rng, dt=0.008):
    """From rest to rest: q0 + sum_m A_m (1 - cos(2 pi m t / T))."""
    T = float(rng.uniform(0.4, 2.5))
    t = np.arange(int(round(T / dt)) + 1) * dt
    T = t[-1]
    amplitudes = rng.normal(0.0, 0.15, (3, 6)) / np.array([[1.0], [4.0], [9.0]])
    q = Q_MID + sum(np.outer(1 - np.cos(2 * np.pi * m * t / T), amplitudes[m - 1])
                    for m in (1, 2, 3))
    return SimpleNamespace(t=t, q=q)


def test_random_trajectory_programs_on_the_kinematic_arm():
    rng = np.random.default_rng(43)
    accepted = refused = 0
    for _ in range(12):
        traj = random_trajectory(rng)
        try:
            program = S.program_from_trajectory(traj, limits=LIMITS, q_from=traj.q[0])
        except UnsafeTargetError:
            refused += 1
            continue
        accepted += 1
        dt = traj.t[1] - traj.t[0]
        clock = SimpleNamespace(now=0.0)                # read at the servo period exactly
        arm = KinematicBackend(q0=traj.q[0], clock=lambda c=clock: c.now, limits=LIMITS)
        arm.connect()
        states = [arm.read_state()]                    # at rest before the program
        clock.now = dt
        arm.run(parse_urscript(program))
        for k in range(len(traj.t) + 2):
            clock.now = dt * (k + 1)
            states.append(arm.read_state())
        t = np.array([s.time for s in states])
        q = np.array([s.q for s in states])
        assert_within_limits(t, q, servo=True)
        np.testing.assert_allclose(q[1:len(traj.q) + 1], traj.q, atol=1e-12)
    assert accepted >= 5 and refused >= 3


# --- joint torques, with a heavy payload ------------------------------------------------------

#: 4 kg held 0.2 m in front of the flange (the UR3 is rated for 3 kg): about a third of random
#: moves need more torque than the joints are rated for.
PAYLOAD, COG = 4.0, (0.0, 0.0, 0.2)
HEAVY = SafetyLimits.for_robot(ROBOT, payload=PAYLOAD, payload_cog=COG)
#: The same arm built independently of the check, for the oracle's inverse dynamics.
LOADED = dynamics.with_payload(ur3(), PAYLOAD, COG)
RATED = np.array([56.0, 56.0, 28.0, 12.0, 12.0, 12.0])          # the UR3's, N m
#: The check samples every 8 ms and on either side of every change of acceleration; between
#: samples a torque can rise a little above what the samples show.
SAMPLING = 1e-3


def torque_ratio(q, qd, qdd, robot=LOADED):
    """max |tau_j| / rated_j over the samples, and the torques."""
    tau = dynamics.inverse_dynamics(robot, q, qd, qdd)
    return float((np.abs(tau) / RATED).max()), tau


def carrying(payload):
    """The limits of the UR3 carrying ``payload`` kg at COG, and the oracle's arm."""
    return (SafetyLimits.for_robot(ROBOT, payload=payload, payload_cog=COG),
            dynamics.with_payload(ur3(), payload, COG))


def executed(arm, step=0.002):
    """The executed profile of the arm's running program, sampled every ``step`` s."""
    starts = [start for start, _ in arm.timeline.motions]
    t = np.arange(starts[0], arm.timeline.end_time, step)
    return t - starts[0], *arm.timeline.state(t)


def assert_refusal_is_true(message, m, robot=LOADED, payload=PAYLOAD):
    """A torque refusal names the joint, its peak, the rating and when: the motion, sampled
    finely, reaches that torque there and does exceed the rating."""
    found = re.search(r"\(([\d.e+-]+) s into the motion\): joint (\d) torque ([\d.e+-]+) N m "
                      r"exceeds its rated ([\d.e+-]+) N m \(the peak of the joint torques with a "
                      rf"payload of {payload:g} kg\)", message)
    assert found, message
    when, joint, peak, rated = float(found[1]), int(found[2]) - 1, float(found[3]), \
        float(found[4])
    assert rated == RATED[joint]
    t = np.linspace(0.0, m.duration, int(m.duration / 0.002) + 2)
    breaks = m.law.breaks                  # either side of a change of acceleration
    t = np.sort(np.concatenate([t, breaks[1:] - 1e-9, breaks[:-1] + 1e-9]))
    ratio, tau = torque_ratio(*m.at(t), robot=robot)
    assert ratio > 1.0
    assert peak == pytest.approx(np.abs(tau[:, joint]).max(), rel=SAMPLING)
    near = np.abs(t - when) <= 1e-3       # (a peak at a change of acceleration: either side)
    assert np.abs(tau[near, joint]).max() == pytest.approx(peak, rel=SAMPLING)


def test_random_movej_with_a_heavy_payload_on_the_kinematic_arm():
    rng = np.random.default_rng(47)
    accepted = torque_refused = 0
    worst = 0.0
    for _ in range(40):
        q0, q1, kw = random_movej(rng)
        try:
            S.movej(q1, **kw, limits=HEAVY, q_from=q0)
        except UnsafeTargetError as exc:
            if "torque" in str(exc):
                torque_refused += 1
                assert_refusal_is_true(str(exc), M.plan_movej(q0, q1, **kw))
            continue
        accepted += 1
        arm = KinematicBackend(q0=q0, clock=StepClock(0.01), limits=HEAVY)
        arm.connect()
        arm.run([("movej", q1, kw)])
        ratio, _ = torque_ratio(*executed(arm)[1:])
        worst = max(worst, ratio)
    assert worst <= 1.0 + SAMPLING, worst
    assert accepted >= 10 and torque_refused >= 5


def test_random_movel_with_a_heavy_payload_on_the_kinematic_arm():
    rng = np.random.default_rng(48)
    accepted = torque_refused = 0
    for _ in range(24):
        q0, goal, kw = random_movel(rng)
        payload = round(float(rng.uniform(5.0, 12.0)), 3)       # kg, at COG
        limits, robot = carrying(payload)
        try:
            S.movel(goal, **kw, limits=limits, q_from=q0)
        except UnsafeTargetError as exc:
            if "torque" in str(exc):
                torque_refused += 1
                assert_refusal_is_true(str(exc), M.plan_movel(ROBOT, q0, goal, **kw), robot,
                                       payload)
            continue
        accepted += 1
        arm = KinematicBackend(q0=q0, clock=StepClock(0.01), limits=limits)
        arm.connect()
        arm.run([("movel", goal, kw)])
        ratio, _ = torque_ratio(*executed(arm)[1:], robot=robot)
        assert ratio <= 1.0 + SAMPLING
    assert accepted >= 4 and torque_refused >= 4


def test_trajectory_programs_with_a_heavy_payload_on_the_kinematic_arm():
    rng = np.random.default_rng(49)
    accepted = torque_refused = 0
    for _ in range(12):
        traj = random_trajectory(rng)
        limits, robot = carrying(round(float(rng.uniform(4.0, 11.0)), 3))
        try:
            program = S.program_from_trajectory(traj, limits=limits, q_from=traj.q[0])
        except UnsafeTargetError as exc:
            if "torque" in str(exc):
                torque_refused += 1
                found = re.search(r"target (\d+) \(t = ([\d.e+-]+) s\): joint (\d) torque "
                                  r"([\d.e+-]+) N m exceeds its rated", str(exc))
                assert found, str(exc)
                assert float(found[4]) > RATED[int(found[3]) - 1]
            continue
        accepted += 1
        dt = traj.t[1] - traj.t[0]
        clock = SimpleNamespace(now=0.0)
        arm = KinematicBackend(q0=traj.q[0], clock=lambda c=clock: c.now, limits=limits)
        arm.connect()
        clock.now = dt
        arm.run(parse_urscript(program))
        states = []
        for k in range(len(traj.t) + 1):
            clock.now = dt * (k + 1)
            states.append(arm.read_state())
        # the executed samples, from rest to rest: speeds and accelerations as a servo
        # stream has them, the torques of each sample with the speed on either side
        q = np.array([traj.q[0]] + [s.q for s in states[:len(traj.t)]] + [traj.q[-1]])
        v = np.diff(q, axis=0) / dt
        a = np.diff(v, axis=0) / dt
        for speeds in (v[:-1], v[1:]):
            ratio, _ = torque_ratio(q[1:-1], speeds, a, robot=robot)
            assert ratio <= 1.0 + 1e-9
        for ends in (q[1:-2], q[2:-1]):             # between samples: constant speed
            ratio, _ = torque_ratio(ends, v[1:-1], 0.0 * v[1:-1], robot=robot)
            assert ratio <= 1.0 + 1e-9
    assert accepted >= 3 and torque_refused >= 3


def test_a_refused_heavy_move_sends_nothing_and_the_arm_stays():
    up, out = [0, -np.pi / 2, 0, -np.pi / 2, 0, 0], [1.5, 0, 0, -np.pi / 2, 0, 0]
    arm = KinematicBackend(q0=up, clock=StepClock(0.01), limits=HEAVY)
    with URClient(arm, ROBOT, limits=HEAVY, poll_interval=0) as ur:
        before = ur.read_state().q
        with pytest.raises(UnsafeTargetError, match=r"joint 5 torque 17.6\d N m exceeds its "
                                                    r"rated 12 N m"):
            ur.movej(out, a=10.0, v=1.05, wait=False)
        assert len(arm.timeline.motions) == 1 and arm.timeline.motions[0][1].command == "hold"
        np.testing.assert_array_equal(ur.read_state().q, before)
        ur.movej(out, a=1.0, v=1.05)                   # gently: within the ratings
        # the arm's own check, for a program that does not come through the client
        with pytest.raises(UnsafeTargetError, match=r"line 1: movej \(.* s into the motion\): "
                                                    r"joint \d torque"):
            arm.run([("movej", up, {"a": 10.0, "v": 1.05})])
        np.testing.assert_allclose(ur.read_state().q, out, atol=1e-12)


def test_nan_never_switches_the_torque_check_off(monkeypatch):
    for bad in ([np.nan] * 6, [56.0] * 5 + [np.inf], [-1.0] * 6):
        with pytest.raises(ValueError, match="max_joint_torque must be positive and finite"):
            SafetyLimits.for_robot(ROBOT, max_joint_torque=bad)
    for bad in (np.nan, -1.0, np.inf):
        with pytest.raises(ValueError, match="payload must be"):
            SafetyLimits.for_robot(ROBOT, payload=bad)
    with pytest.raises(ValueError, match="payload_cog contains NaN"):
        SafetyLimits.for_robot(ROBOT, payload=1.0, payload_cog=[0.0, np.nan, 0.0])
    with pytest.raises(ValueError, match="max_joint_torque needs robot="):
        SafetyLimits(max_joint_torque=RATED)
    # a torque that comes out NaN is a refusal, not a pass
    monkeypatch.setattr(SafetyLimits, "joint_torques", lambda self, q, qd, qdd: np.full(q.shape,
                                                                                         np.nan))
    with pytest.raises(UnsafeTargetError, match="joint 1 torque nan N m exceeds"):
        S.movej(Q_MID + 0.1, limits=HEAVY, q_from=Q_MID)


def test_the_one_at_a_time_torques_are_the_batch_torques():
    m = M.plan_movej(Q_MID, Q_MID + [1.0, 0.8, -0.9, 0.5, 0.3, 0.2], a=1.0, v=0.5)
    t, q, qd, qdd = m.samples()
    assert len(t) > S._BATCH_FROM                                 # the batch path
    batch = HEAVY.joint_torques(q, qd, qdd)
    single = HEAVY.joint_torques(q[:10], qd[:10], qdd[:10])      # one state at a time
    np.testing.assert_allclose(single, batch[:10], rtol=0, atol=1e-12)
    np.testing.assert_allclose(batch, dynamics.inverse_dynamics(LOADED, q, qd, qdd), rtol=0,
                               atol=1e-12)


# --- the MuJoCo back end's commanded motion -------------------------------------------------

sim = pytest.importorskip("dqlab.sim", reason="the MuJoCo back end needs the extra 'sim'")


class RecordingMujoco(sim.MujocoBackend):
    """The MuJoCo back end, recording the reference it commands at every simulation step."""

    def __init__(self, *args, limits=LIMITS, **kwargs):
        super().__init__(*args, limits=limits, **kwargs)
        self.record = []

    def reference(self, times, velocity_lag=0.0):
        out = super().reference(times, velocity_lag)
        q, qd, _ = super().reference(times)
        self.record.append((np.asarray(times, dtype=float), q, qd))
        return out

    def commanded(self):
        t, q, qd = (np.concatenate(x) for x in zip(*self.record, strict=True))
        return t, q, qd


@pytest.mark.parametrize("kind", ["movej", "movel"])
def test_random_moves_commanded_by_the_mujoco_backend(kind):
    rng = np.random.default_rng(44 if kind == "movej" else 45)
    done = 0
    while done < 4:
        q0, target, kw = random_movej(rng) if kind == "movej" else random_movel(rng)
        if kind == "movej":
            q0 = np.clip(q0, -3.0, 3.0)
            target = np.clip(q0 + (target - q0) * 0.3, -3.0, 3.0)
        try:
            plan = S.plan_program([(kind, target, kw)], q_now=q0, limits=LIMITS, robot=ROBOT)
        except UnsafeTargetError:
            continue
        arm = RecordingMujoco(q_home=q0)
        arm.connect()
        getattr(arm, kind)(target, **kw, r=0.0)
        arm.advance(plan[-1].duration + 0.05)
        t, q, qd = arm.commanded()
        assert_within_limits(t, q, qd)
        np.testing.assert_allclose(q[-1], plan[-1].q_end, atol=1e-12)
        done += 1


def test_heavy_moves_commanded_by_the_mujoco_backend():
    rng = np.random.default_rng(50)
    done, worst = 0, 0.0
    while done < 3:
        q0, target, kw = random_movej(rng)
        q0 = np.clip(q0, -3.0, 3.0)
        target = np.clip(q0 + (target - q0) * 0.5, -3.0, 3.0)
        try:
            plan = S.plan_program([("movej", target, kw)], q_now=q0, limits=HEAVY, robot=ROBOT)
        except UnsafeTargetError:
            continue
        arm = RecordingMujoco(q_home=q0, limits=HEAVY)
        arm.connect()
        arm.movej(target, **kw, r=0.0)
        arm.advance(plan[-1].duration + 0.05)
        t, q, qd = arm.commanded()
        qdd = np.gradient(qd, t, axis=0)       # between two steps: the mean of either side
        ratio, _ = torque_ratio(q, qd, qdd)
        assert ratio <= 1.0 + SAMPLING
        worst = max(worst, ratio)
        done += 1
    assert worst > 0.8, worst               # moves that do come near the ratings


def test_a_trajectory_streamed_to_the_mujoco_backend():
    rng = np.random.default_rng(46)
    while True:
        traj = random_trajectory(rng)
        try:
            S.check_trajectory(traj, limits=LIMITS, robot=ROBOT)
            break
        except UnsafeTargetError:
            continue
    arm = RecordingMujoco(q_home=traj.q[0])
    with URClient(arm, ROBOT, limits=LIMITS, poll_interval=0) as ur:
        log = ur.servoj_stream(traj)
    t, q, _ = arm.commanded()
    knots = log[0].time + traj.t
    q_knots = np.stack([np.interp(knots, t, q[:, j]) for j in range(6)], axis=1)
    np.testing.assert_allclose(q_knots, traj.q, atol=1e-12)     # sent on time, every one
    rest = np.stack([traj.q[0], *q_knots, traj.q[-1]])
    assert_within_limits(np.r_[knots[0] - (traj.t[1] - traj.t[0]), knots,
                               knots[-1] + traj.t[-1] - traj.t[-2]], rest, servo=True)
    assert math.isfinite(log[-1].time)


def test_the_mujoco_backend_reports_and_takes_poses_in_the_base_frame():
    mounted = ur3()
    mounted.base = __import__("dqlab").transform_from(
        __import__("dqlab").rot_z(np.pi / 2), [1.0, 0.5, 0.8])
    arm = sim.MujocoBackend(mounted, q_home=Q_MID, limits=SafetyLimits.for_robot(mounted))
    arm.connect()
    state = arm.read_state()
    np.testing.assert_allclose(state.tcp_pose, M.controller_pose(ROBOT, state.q), atol=1e-9)
    goal = state.tcp_pose + [0.02, 0.0, -0.02, 0, 0, 0]
    arm.movel(goal, a=0.5, v=0.1)
    arm.advance(arm.timeline.end_time - arm.sim.time + 0.5)
    np.testing.assert_allclose(arm.read_state().tcp_pose[:3], goal[:3], atol=1e-4)
