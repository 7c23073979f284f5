"""Tests of dqlab.sim: the generated MuJoCo model is the robot, the controllers track, the
simulated arm serves the UR client."""

import numpy as np
import pytest

from dqlab import models
from dqlab.rotations import matrix_from_axis_angle
from dqlab.sim import UR3_LINK_MASSES, mjcf_from_robot
from dqlab.transforms import transform_from

mujoco = pytest.importorskip("mujoco")


def site_pose(model, data, name="flange"):
    sid = model.site(name).id
    X = np.eye(4)
    X[:3, :3] = data.site_xmat[sid].reshape(3, 3)
    X[:3, 3] = data.site_xpos[sid]
    return X


def ur3_with_base_and_tool():
    robot = models.ur3()
    robot.base = transform_from(matrix_from_axis_angle([1.0, 2.0, 3.0], 0.7), [0.3, -0.2, 0.8])
    robot.tool = transform_from(matrix_from_axis_angle([0.0, 1.0, 1.0], 0.4), [0.01, 0.02, 0.15])
    return robot


ROBOTS = {
    "ur3": models.ur3,
    "ur3_mdh": models.ur3_mdh,
    "scara_rsm5": models.scara_rsm5,
    "six_r": models.six_r,
    "ur3_base_tool": ur3_with_base_and_tool,
}


def random_joints(robot, count, seed):
    """Joint vectors inside the limits (revolute ones within +-pi where unlimited)."""
    rng = np.random.default_rng(seed)
    lo, hi = robot.limits.T
    lo, hi = np.maximum(lo, -2 * np.pi), np.minimum(hi, 2 * np.pi)
    return rng.uniform(lo, hi, size=(count, robot.n))


@pytest.mark.parametrize("name", ROBOTS)
def test_flange_site_pose_equals_robot_fk(name):
    """The test that proves the generated model is the robot: 1,000 random configurations."""
    robot = ROBOTS[name]()
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(robot))
    data = mujoco.MjData(model)
    Q = random_joints(robot, 1000, seed=1)
    X_expected = robot.fk(Q)
    worst = 0.0
    for q, X in zip(Q, X_expected, strict=True):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        worst = max(worst, np.abs(site_pose(model, data) - X).max())
    assert worst <= 1e-9, f"{name}: flange pose differs from robot.fk by {worst:.3g}"


@pytest.mark.parametrize("name", ROBOTS)
def test_one_joint_per_link_in_chain_order(name):
    robot = ROBOTS[name]()
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(robot))
    assert model.njnt == model.nq == model.nv == model.nu == robot.n
    want = [mujoco.mjtJoint.mjJNT_HINGE if j == "revolute" else mujoco.mjtJoint.mjJNT_SLIDE
            for j in robot.joint_types]
    assert list(model.jnt_type) == want
    # each joint moves the body of its own link, and bodies nest in chain order
    bodies = [model.body(f"link{i + 1}").id for i in range(robot.n)]
    assert list(model.jnt_bodyid) == bodies
    assert [model.body_parentid[b] for b in bodies[1:]] == bodies[:-1]
    # joint ranges from the robot's limits
    lo, hi = robot.limits.T
    finite = np.isfinite(lo) & np.isfinite(hi)
    np.testing.assert_allclose(model.jnt_range[finite], robot.limits[finite])
    assert model.jnt_limited[finite].all()


def test_ur3_masses_match_the_data_sheet():
    """Moving links from UR's table, the whole arm 11 kg as in the thesis's annex A."""
    robot = models.ur3()
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(robot))
    links = [model.body_mass[model.body(f"link{i + 1}").id] for i in range(6)]
    np.testing.assert_allclose(links, UR3_LINK_MASSES)
    base = model.body("base").id
    assert model.body_subtreemass[base] == pytest.approx(11.0, abs=1e-6)
    # the links' inertias are the robot's (positive); the empty payload body weighs nothing
    for i, link in enumerate(robot.links, start=1):
        np.testing.assert_allclose(np.sort(model.body(f"link{i}").inertia),
                                   np.linalg.eigvalsh(link.inertia.tensor), rtol=1e-9)
    assert model.body("payload").mass[0] == 0.0


def test_payload_is_a_mass_at_the_tcp():
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(models.ur3(), payload=3.0))
    assert model.body_mass[model.body("payload").id] == pytest.approx(3.0)


@pytest.mark.parametrize("kwargs, word", [
    ({"masses": [1, 2, 3]}, "masses"),
    ({"masses": [1, 1, 1, 1, 1, -1]}, "masses"),
    ({"payload": -1.0}, "payload"),
    ({"payload": float("nan")}, "payload"),
    ({"timestep": 0.0}, "timestep"),
    ({"damping": float("inf")}, "damping"),
    ({"radius": -0.1}, "radius"),
    ({"integrator": "leapfrog"}, "integrator"),
])
def test_mjcf_refuses_bad_arguments(kwargs, word):
    with pytest.raises(ValueError, match=word):
        mjcf_from_robot(models.ur3(), **kwargs)


def test_mjcf_refuses_a_non_robot():
    with pytest.raises(TypeError, match="robot"):
        mjcf_from_robot("UR3")


# -- simulation and controllers ---------------------------------------------------------------

from types import SimpleNamespace  # noqa: E402

from dqlab.sim import (  # noqa: E402
    ArmSimulation,
    ComputedTorque,
    JointPD,
    MujocoBackend,
    check_trajectory,
    track,
)

UR3_PD = JointPD(kp=[400, 400, 200, 50, 50, 50], kd=[40, 40, 20, 5, 5, 5])


def smooth_trajectory(duration=2.0, dt=0.005):
    """Every UR3 joint on a sine about a bent configuration (q, qd, qdd in closed form)."""
    t = np.arange(0.0, duration + dt / 2, dt)
    q0 = np.array([0.2, -1.3, 1.4, -1.6, -1.5, 0.3])
    amp = np.array([0.6, 0.4, 0.5, 0.7, 0.5, 0.9])
    w = 2 * np.pi / duration * np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])
    phase = t[:, None] * w
    return SimpleNamespace(t=t, q=q0 + amp * (1 - np.cos(phase)), qd=amp * w * np.sin(phase),
                           qdd=amp * w**2 * np.cos(phase))


@pytest.fixture(scope="module")
def ur3_sim():
    return ArmSimulation(models.ur3())


def test_computed_torque_tracks_a_smooth_trajectory_and_pd_does_worse(ur3_sim):
    move = smooth_trajectory()
    ct = track(ur3_sim, move, ComputedTorque())
    pd = track(ur3_sim, move, UR3_PD)
    assert ct.t.shape == (2001,) and ct.q.shape == ct.torque.shape == (2001, 6)
    # stated bounds: computed torque within 0.5 mrad per joint and 0.2 mm at the flange
    assert ct.max_error.max() < 5e-4
    assert ct.flange_error.max() < 2e-4
    # PD sags under gravity and lags: at least ten times worse
    assert pd.flange_error.max() > 10 * ct.flange_error.max()
    assert pd.max_error.max() > 10 * ct.max_error.max()
    np.testing.assert_allclose(ct.error, ct.q_desired - ct.q)


def test_computed_torque_error_shrinks_with_the_time_step():
    move = smooth_trajectory(duration=1.0)
    errors = [track(ArmSimulation(models.ur3(), timestep=dt), move, ComputedTorque())
              .max_error.max() for dt in (0.002, 0.001)]
    assert errors[1] < 0.6 * errors[0]          # first order in the time step


def test_gravity_compensation_helps_pd(ur3_sim):
    move = smooth_trajectory(duration=6.0)           # slow: the error is mostly the sag
    pd = track(ur3_sim, move, UR3_PD)
    pdg = track(ur3_sim, move, JointPD(UR3_PD.kp, UR3_PD.kd, gravity_compensation=True))
    assert pdg.flange_error.max() < 0.5 * pd.flange_error.max()
    assert pdg.controller == "PD + gravity"


def test_an_unknown_payload_spoils_computed_torque():
    move = smooth_trajectory()
    plant = ArmSimulation(models.ur3(), payload=2.0)
    exact = track(plant, move, ComputedTorque())
    blind = track(plant, move, ComputedTorque(model=ArmSimulation(models.ur3())))
    assert blind.flange_error.max() > 5 * exact.flange_error.max()


def test_inverse_dynamics_is_mass_matrix_times_acceleration_plus_bias(ur3_sim):
    """tau = (M + h D) qdd + bias: the implicit step's damping term h D is part of the
    discrete-time inverse dynamics."""
    rng = np.random.default_rng(3)
    h_D = ur3_sim.timestep * np.diag(ur3_sim.model.dof_damping)
    for _ in range(20):
        q, qd, qdd = rng.uniform(-2, 2, (3, 6))
        M = ur3_sim.mass_matrix(q)
        np.testing.assert_allclose(M, M.T, atol=1e-12)
        assert np.linalg.eigvalsh(M).min() > 0
        bias = ur3_sim.inverse_dynamics(q, qd, np.zeros(6))
        np.testing.assert_allclose(ur3_sim.inverse_dynamics(q, qd, qdd),
                                   (M + h_D) @ qdd + bias, atol=1e-9)


def test_gravity_torque_is_the_gradient_of_the_potential_energy(ur3_sim):
    """g(q) = dU/dq, U = sum of m_i g z_i over the links' centres of mass (by kinematics)."""
    mujoco_ = pytest.importorskip("mujoco")
    model, scratch = ur3_sim.model, mujoco_.MjData(ur3_sim.model)

    def potential(q):
        scratch.qpos[:] = q
        mujoco_.mj_kinematics(model, scratch)
        mujoco_.mj_comPos(model, scratch)
        return 9.81 * float(model.body_mass @ scratch.xipos[:, 2])

    q = np.array([0.3, -1.1, 0.9, -1.2, 0.7, 0.2])
    h = 1e-6
    grad = [(potential(q + h * e) - potential(q - h * e)) / (2 * h) for e in np.eye(6)]
    np.testing.assert_allclose(ur3_sim.gravity_torque(q), grad, atol=1e-6)


def test_gravity_is_held_exactly(ur3_sim):
    q = np.array([0.0, -0.5, 0.5, -1.0, 0.5, 0.0])
    ur3_sim.reset(q)
    ur3_sim.step(ur3_sim.gravity_torque(q), steps=500)
    assert np.abs(ur3_sim.q - q).max() < 1e-9


@pytest.mark.parametrize("field, value, message", [
    ("q", np.nan, "trajectory.q contains NaN"),
    ("qd", np.inf, "trajectory.qd contains NaN or infinity"),
    ("q", 7.0, "trajectory.q: joint 2 .* beyond its limits"),
])
def test_tracking_refuses_nan_and_out_of_limit_targets(ur3_sim, field, value, message):
    move = smooth_trajectory(duration=0.5)
    getattr(move, field)[10, 1] = value
    time_before = ur3_sim.time
    with pytest.raises(ValueError, match=message):
        track(ur3_sim, move, ComputedTorque())
    assert ur3_sim.time == time_before          # nothing was simulated


def test_trajectory_checks_shapes_and_times():
    robot = models.ur3()
    move = smooth_trajectory(duration=0.5)
    with pytest.raises(ValueError, match="no 'qdd'"):
        check_trajectory(SimpleNamespace(t=move.t, q=move.q, qd=move.qd), robot)
    with pytest.raises(ValueError, match=r"trajectory.qd must have shape \(101, 6\)"):
        check_trajectory(SimpleNamespace(t=move.t, q=move.q, qd=move.qd[:, :5],
                                         qdd=move.qdd), robot)
    with pytest.raises(ValueError, match="increase"):
        check_trajectory(SimpleNamespace(t=move.t[::-1], q=move.q, qd=move.qd,
                                         qdd=move.qdd), robot)


def test_simulation_refuses_bad_states_and_torques(ur3_sim):
    with pytest.raises(ValueError, match="q contains NaN"):
        ur3_sim.reset([0, np.nan, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="joint 3 = -7 is beyond"):
        ur3_sim.reset([0, 0, -7, 0, 0, 0])
    with pytest.raises(ValueError, match="torque contains NaN"):
        ur3_sim.step([0, 0, np.nan, 0, 0, 0])
    with pytest.raises(ValueError, match="payload"):
        ur3_sim.payload = -1.0


def test_payload_can_be_changed(ur3_sim):
    q = np.array([0.0, -0.5, 0.5, -1.0, 0.5, 0.0])
    g0 = ur3_sim.gravity_torque(q)
    ur3_sim.payload = 3.0
    try:
        assert ur3_sim.payload == 3.0
        # 3 kg at the flange: the shoulder holds 3 kg * g * the flange's horizontal reach
        reach = np.linalg.norm(models.ur3().fk(q)[:2, 3] - [0.0, 0.0])
        assert abs(ur3_sim.gravity_torque(q)[0] - g0[0]) < 1e-9     # vertical axis: none
        assert ur3_sim.gravity_torque(q)[1] != pytest.approx(g0[1])
        assert reach > 0
    finally:
        ur3_sim.payload = 0.0
    assert ur3_sim.payload == 0.0


def test_prismatic_robot_tracks_too():
    scara = models.scara_rsm5()
    sim = ArmSimulation(scara)
    t = np.linspace(0.0, 1.0, 201)
    s, sd, sdd = 3 * t**2 - 2 * t**3, 6 * t - 6 * t**2, 6 - 12 * t
    q0, step = np.array([0.2, 0.5, 0.02, 0.0]), np.array([0.8, -0.6, 0.1, 1.0])
    move = SimpleNamespace(t=t, q=q0 + s[:, None] * step, qd=sd[:, None] * step,
                           qdd=sdd[:, None] * step)
    result = track(sim, move, ComputedTorque())
    assert result.max_error.max() < 2e-4
    # the prismatic joint lifts the rest of the arm: its force includes their weight
    assert result.torque[0, 2] > 9.0


# -- the simulated arm behind the UR client's protocol ---------------------------------------

from dqlab.sim import UR3_HOME  # noqa: E402
from dqlab.ur import pose_from_transform, transform_from_pose  # noqa: E402


@pytest.fixture()
def arm():
    backend = MujocoBackend()
    backend.connect(timeout=1.0)
    yield backend
    backend.close()


def run_until_still(arm, settle=0.2):
    while arm.is_moving:
        state = arm.read_state()
    for _ in range(int(round(settle / arm.period))):
        state = arm.read_state()
    return state


def test_backend_starts_at_home_and_reports_the_state(arm):
    state = arm.read_state()
    assert state.time == pytest.approx(arm.period)
    assert state.robot_mode == 7
    np.testing.assert_allclose(state.q, UR3_HOME, atol=1e-6)
    X = transform_from_pose(state.tcp_pose)
    np.testing.assert_allclose(X, arm.sim.robot.fk(state.q), atol=1e-9)
    assert arm.read_state().time == pytest.approx(2 * arm.period)


def test_backend_movej_reaches_the_joints(arm):
    target = np.array([0.4, -1.2, 1.3, -1.9, -1.2, 0.5])
    arm.movej(target, a=1.4, v=1.05, t=0.0, r=0.0)
    assert arm.is_moving
    speeds = []
    while arm.is_moving:
        state = arm.read_state()
        speeds.append(np.abs(state.qd).max())
    assert np.abs(state.q - target).max() < 1e-3
    assert max(speeds) < 1.05 * 1.01                   # the speed limit v, tracked
    state = run_until_still(arm)
    assert np.abs(state.q - target).max() < 1e-5


def test_backend_movej_with_a_time(arm):
    target = np.asarray(UR3_HOME) + 0.2
    start = arm.read_state().time
    arm.movej(target, a=1.0, v=1.0, t=1.5, r=0.0)
    state = run_until_still(arm, settle=0.0)
    assert state.time - start == pytest.approx(1.5, abs=2 * arm.period)


def test_backend_movel_moves_the_tcp_on_a_line(arm):
    X0 = arm.sim.robot.fk(arm.read_state().q)
    X1 = X0.copy()
    X1[:3, 3] += [0.05, 0.08, -0.1]
    arm.movel(pose_from_transform(X1), a=1.2, v=0.1, t=0.0, r=0.0)
    p0, p1 = X0[:3, 3], X1[:3, 3]
    u = (p1 - p0) / np.linalg.norm(p1 - p0)
    off_line = []
    while arm.is_moving:
        p = arm.read_state().tcp_pose[:3]
        off_line.append(np.linalg.norm((p - p0) - np.dot(p - p0, u) * u))
    assert max(off_line) < 5e-4                           # within half a millimetre
    state = run_until_still(arm)
    np.testing.assert_allclose(transform_from_pose(state.tcp_pose), X1, atol=1e-4)


def test_backend_servoj_streams_and_stop_brings_the_arm_to_rest(arm):
    q0 = np.asarray(UR3_HOME)
    for k in range(1, 51):
        arm.servoj(q0 + 0.004 * k, t=0.008, lookahead_time=0.1, gain=300)
        state = arm.read_state()
    assert np.abs(state.q - (q0 + 0.2)).max() < 0.02
    arm.movej(q0 - 0.5, a=2.0, v=1.0, t=0.0, r=0.0)
    for _ in range(40):
        state = arm.read_state()
    assert np.abs(state.qd).max() > 0.5
    arm.stop(a=3.0)
    state = run_until_still(arm)
    assert np.abs(state.qd).max() < 1e-3


@pytest.mark.parametrize("call, message", [
    (lambda arm: arm.movej([0, np.nan, 0, 0, 0, 0]), "q contains NaN"),
    (lambda arm: arm.movej([0, 0, 0, 7.0, 0, 0]), "joint 4 = 7 is beyond its limits"),
    (lambda arm: arm.movej([0, 0, 0]), r"q must have shape \(6,\)"),
    (lambda arm: arm.movej(UR3_HOME, a=0.0), "a must be"),
    (lambda arm: arm.movej(UR3_HOME, v=np.inf), "v must be"),
    (lambda arm: arm.movel([0.3, 0.1, np.nan, 0, 0, 0]), "pose contains NaN"),
    (lambda arm: arm.movel([2.0, 0.0, 0.3, 0, 3.14, 0]), "pose: .* has no IK solution"),
    (lambda arm: arm.servoj([0, 0, 0, 0, 9.0, 0]), "joint 5 = 9 is beyond"),   # (6: no limit)
    (lambda arm: arm.servoj(UR3_HOME, gain=5000), "gain"),
    (lambda arm: arm.stop(a=-1.0), "a must be"),
])
def test_backend_refuses_bad_targets_before_moving(arm, call, message):
    q_before = arm.read_state().q
    with pytest.raises(ValueError, match=message):
        call(arm)
    assert not arm.is_moving
    np.testing.assert_allclose(arm.read_state().q, q_before, atol=1e-6)


def test_backend_needs_a_connection():
    backend = MujocoBackend()
    with pytest.raises(RuntimeError, match="connect"):
        backend.read_state()
    with pytest.raises(ValueError, match="6 joints"):
        MujocoBackend(models.scara_rsm5())
    with pytest.raises(ValueError, match="clock"):
        MujocoBackend(clock="cpu")


def test_backend_wall_clock_keeps_up_with_time():
    import time

    backend = MujocoBackend(clock="wall")
    backend.connect(timeout=1.0)
    time.sleep(0.05)
    state = backend.read_state()
    backend.close()
    assert 0.04 <= state.time <= 1.0


# -- the UR3 report's circle, executed in physics ---------------------------------------------

def test_computed_torque_tracks_the_reports_circle():
    """Radius 0.1 m, V = 0.05 m/s, dt = 5 ms (4399 points), followed by the closed-form IK:
    computed torque keeps the flange within 1 micrometre of the circle's joint reference,
    PD without gravity compensation sags by more than a centimetre."""
    from dqlab import rot_x
    from dqlab.trajectory import Trajectory, circle_three_phase, follow_path_ur

    robot = models.ur3()
    center = np.array([0.0, -0.35, 0.25])              # chapter 11's circle
    path = circle_three_phase(center, 0.1, 0.05, orientation=rot_x(np.pi / 2))
    circle, report = follow_path_ur(robot, path, branch=("left", "down", "noflip"))
    assert isinstance(circle, Trajectory) and len(circle) == 4399 and not report.switches
    sim = ArmSimulation(robot)
    ct = track(sim, circle, ComputedTorque())
    pd = track(sim, circle, UR3_PD)
    assert ct.t[-1] == pytest.approx(circle.t[-1], abs=sim.timestep)
    assert ct.flange_error.max() < 1e-6
    assert ct.max_error.max() < 1e-5
    assert pd.flange_error.max() > 0.01
    # the TCP reached in the simulation lies on the circle (radius 0.1 m about the centre)
    p = robot.fk(ct.q)[:, :3, 3]
    radius = np.linalg.norm((p - center)[:, [0, 2]], axis=1)
    assert np.abs(radius - 0.1).max() < 2e-6
    assert np.abs(p[:, 1] - center[1]).max() < 2e-6


def test_a_payload_picked_during_the_run_is_felt_while_carried(ur3_sim):
    move = smooth_trajectory(duration=2.0)
    carried = np.where((move.t >= 0.5) & (move.t < 1.5), 2.0, 0.0)
    blind = ComputedTorque(model=ArmSimulation(models.ur3()))
    result = track(ur3_sim, move, blind, payload=carried)
    error = result.flange_error
    before = error[result.t < 0.5].max()
    during = error[(result.t > 0.6) & (result.t < 1.5)].max()
    assert during > 20 * before
    assert ur3_sim.payload == 0.0                        # restored after the run
    with pytest.raises(ValueError, match="payload must hold 401 finite masses"):
        track(ur3_sim, move, blind, payload=carried[:-1])


def test_frames_for_playback(ur3_sim):
    result = track(ur3_sim, smooth_trajectory(duration=1.0), ComputedTorque())
    times, q = result.frames(fps=20)
    assert times.shape == (21,) and q.shape == (21, 6)
    np.testing.assert_allclose(times, np.arange(21) / 20, atol=1e-9)
    np.testing.assert_array_equal(q[-1], result.q[-1])


# -- the same chain as URDF, read by an independent library ------------------------------------

@pytest.mark.parametrize("name", ROBOTS)
def test_urdf_flange_equals_robot_fk_in_pytransform3d(name):
    """pytransform3d's URDF reader composes the generated joints to robot.fk."""
    urdf = pytest.importorskip("pytransform3d.urdf")
    from dqlab.sim import urdf_from_robot

    robot = ROBOTS[name]()
    tm = urdf.UrdfTransformManager()
    tm.load_urdf(urdf_from_robot(robot))
    Q = random_joints(robot, 100, seed=5)
    worst = 0.0
    for q, X in zip(Q, robot.fk(Q), strict=True):
        for i, value in enumerate(q, start=1):
            tm.set_joint(f"joint{i}", value)
        worst = max(worst, np.abs(tm.get_transform("flange", "world") - X).max())
    assert worst <= 1e-9


# -- the same program drives the simulated arm through URClient -------------------------------

def test_urclient_moves_the_simulated_arm():
    from dqlab.trajectory import joint_trajectory
    from dqlab.ur import UnsafeTargetError, URClient

    target = np.array([0.4, -1.2, 1.3, -1.9, -1.2, 0.5])
    with URClient(MujocoBackend(), poll_interval=0) as ur:
        state = ur.movej(target, a=1.4, v=1.05)
        assert np.abs(state.q - target).max() <= ur.tol       # the reached joints
        assert state.time > 1.0                              # it took simulated time
        pose = state.tcp_pose.copy()
        pose[2] -= 0.1
        state = ur.movel(pose, a=1.2, v=0.1)
        assert np.abs(state.tcp_pose[:3] - pose[:3]).max() <= ur.tol
        move = joint_trajectory(state.q, state.q + 0.3, duration=2.0, dt=0.008)
        log = ur.servoj_stream(move)
        assert np.abs(log[-1].q - move.q[-1]).max() <= ur.tol
        with pytest.raises(UnsafeTargetError):
            ur.movej([0, 0, 0, np.nan, 0, 0])
        assert np.abs(ur.read_state().q - move.q[-1]).max() <= ur.tol     # nothing moved


def test_tcp_positions_are_robot_fk(ur3_sim):
    result = track(ur3_sim, smooth_trajectory(duration=0.5), ComputedTorque())
    np.testing.assert_allclose(result.tcp, models.ur3().fk(result.q)[:, :3, 3], atol=1e-12)
    np.testing.assert_allclose(result.tcp_desired,
                               models.ur3().fk(result.q_desired)[:, :3, 3], atol=1e-12)


def test_a_prismatic_joint_driven_to_the_end_of_its_stroke():
    """The SCARA's z axis goes down to 0, its lower limit: the run completes (a hair of
    overshoot in the simulation is no error) and ends there."""
    scara = models.scara_rsm5()
    t = np.linspace(0.0, 1.0, 201)
    s, sd, sdd = 3 * t**2 - 2 * t**3, 6 * t - 6 * t**2, 6 - 12 * t
    q0, step = np.array([0.2, 0.5, 0.1, 0.0]), np.array([0.0, 0.0, -0.1, 0.0])
    move = SimpleNamespace(t=t, q=q0 + s[:, None] * step, qd=sd[:, None] * step,
                           qdd=sdd[:, None] * step)
    result = track(ArmSimulation(scara), move, JointPD(kp=2000.0, kd=20.0))
    assert abs(result.q[-1, 2]) < 2e-3


def test_pd_gravity_compensation_from_the_controllers_own_model():
    move = smooth_trajectory(duration=8.0)          # slow: the error is mostly the sag
    plant = ArmSimulation(models.ur3(), payload=2.0)
    informed = track(plant, move, JointPD(UR3_PD.kp, UR3_PD.kd, gravity_compensation=True))
    blind = track(plant, move, JointPD(UR3_PD.kp, UR3_PD.kd, gravity_compensation=True,
                                       model=ArmSimulation(models.ur3())))
    assert blind.flange_error.max() > 2 * informed.flange_error.max()


# -- any chain: a property test ---------------------------------------------------------------

from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from dqlab.robot import Link, Robot  # noqa: E402

_length = st.floats(-0.5, 0.5, allow_nan=False)
_angle = st.floats(-np.pi, np.pi, allow_nan=False)
_link = st.tuples(_length, _angle, _length, _angle, st.sampled_from(["revolute", "prismatic"]))


@given(links=st.lists(_link, min_size=1, max_size=7),
       convention=st.sampled_from(["dh", "mdh"]),
       seed=st.integers(0, 2**31 - 1))
def test_any_chain_generates_a_model_with_its_forward_kinematics(links, convention, seed):
    rng = np.random.default_rng(seed)
    chain = [Link(a, alpha, d, theta_offset=theta, joint=kind,
                  limits=(0.0, 0.3) if kind == "prismatic" else None)
             for a, alpha, d, theta, kind in links]
    base = transform_from(matrix_from_axis_angle(rng.normal(size=3), rng.uniform(0, 3)),
                          rng.normal(size=3))
    tool = transform_from(matrix_from_axis_angle(rng.normal(size=3), rng.uniform(0, 3)),
                          rng.normal(scale=0.1, size=3))
    robot = Robot(chain, convention=convention, base=base, tool=tool)
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(robot))
    data = mujoco.MjData(model)
    lo, hi = np.nan_to_num(robot.limits.T, posinf=np.pi, neginf=-np.pi)
    Q = rng.uniform(lo, hi, size=(20, robot.n))
    for q, X in zip(Q, robot.fk(Q), strict=True):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        np.testing.assert_allclose(site_pose(model, data), X, atol=1e-9)


def test_without_mujoco_the_message_says_how_to_install_it(monkeypatch):
    import sys

    from dqlab.sim import require_mujoco

    monkeypatch.setitem(sys.modules, "mujoco", None)       # as if it were not installed
    with pytest.raises(ImportError, match=r"pip install 'dqlab\[sim\]'"):
        ArmSimulation(models.ur3())
    with pytest.raises(ImportError, match="MuJoCo"):
        require_mujoco()
    assert "<mujoco" in mjcf_from_robot(models.ur3())        # generating needs no MuJoCo


def test_a_link_of_a_micrometre_is_not_drawn_but_kept_in_the_kinematics():
    """Found by the property test: MuJoCo refuses a capsule between points 1e-7 m apart."""
    robot = Robot([Link(0.0, 0.0, 0.0), Link(0.0, 0.0, 1e-7)], convention="dh")
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(robot))
    data = mujoco.MjData(model)
    data.qpos[:] = [0.3, -0.2]
    mujoco.mj_kinematics(model, data)
    np.testing.assert_allclose(site_pose(model, data), robot.fk([0.3, -0.2]), atol=1e-15)


# -- nothing returned silently wrong, no failure hidden -----------------------------------------

from dqlab.sim import SimulationError, urdf_from_robot  # noqa: E402

Q_BENT = np.array([0.0, -1.5, 1.0, -1.0, -1.5, 0.0])


@pytest.mark.parametrize("method, args", [
    ("inverse_dynamics", (Q_BENT, np.zeros(6), np.zeros(6))),
    ("gravity_torque", (Q_BENT,)),
    ("mass_matrix", (Q_BENT,)),
    ("flange_positions", (Q_BENT,)),
])
def test_dynamics_refuse_nan_and_complex_joints(ur3_sim, method, args):
    bad = np.array(args[0])
    bad[2] = np.nan
    with pytest.raises(ValueError, match="^q contains NaN or infinity"):
        getattr(ur3_sim, method)(bad, *args[1:])
    with pytest.raises(TypeError, match="^q must hold real numbers"):
        getattr(ur3_sim, method)(args[0] + 1e-3j, *args[1:])


def test_flange_positions_keep_the_leading_shape(ur3_sim):
    one = ur3_sim.flange_positions(Q_BENT)
    assert one.shape == (3,)
    np.testing.assert_allclose(one, models.ur3().fk(Q_BENT)[:3, 3], atol=1e-12)
    assert ur3_sim.flange_positions(np.stack([[Q_BENT] * 3] * 2)).shape == (2, 3, 3)


def test_the_time_step_is_written_exactly_and_bounded():
    assert 'timestep="1.25e-05"' in mjcf_from_robot(models.ur3(), timestep=1.25e-5)
    for bad in (1e-16, 0.0, 2.0, np.nan):
        with pytest.raises(ValueError, match="^timestep must be a finite number >= 1e-09"):
            mjcf_from_robot(models.ur3(), timestep=bad)


def test_complex_masses_and_a_name_that_is_not_text_are_refused():
    with pytest.raises(TypeError, match="^masses must hold real numbers"):
        mjcf_from_robot(models.ur3(), masses=np.ones(6) + 1j)
    for generate in (mjcf_from_robot, urdf_from_robot):
        with pytest.raises(TypeError, match="^name must be text"):
            generate(models.ur3(), name=123)
        with pytest.raises(TypeError, match="^robot must be a Robot, got None"):
            generate(None)


def test_a_control_that_mujoco_would_ignore_is_refused(ur3_sim):
    ur3_sim.reset(Q_BENT)
    with pytest.raises(ValueError, match="torque: joint 2 = 1e\\+11 is too large"):
        ur3_sim.step([0.0, 1e11, 0.0, 0.0, 0.0, 0.0])
    assert np.array_equal(ur3_sim.q, Q_BENT)


def test_unstable_gains_raise_instead_of_returning_a_reset_arm(ur3_sim, tmp_path, monkeypatch):
    """kp = 2000, kd = 100 at 1 ms: the state blows up, MuJoCo resets it to q = 0 and goes
    on; the run is reported as failed, and MuJoCo writes no log file."""
    monkeypatch.chdir(tmp_path)
    move = SimpleNamespace(t=np.linspace(0.0, 1.0, 201), q=np.tile(Q_BENT, (201, 1)),
                           qd=np.zeros((201, 6)), qdd=np.zeros((201, 6)))
    with pytest.raises(SimulationError, match="diverged in the step from t = .* an "
                                              "acceleration became NaN, infinite"):
        track(ur3_sim, move, JointPD(kp=2000.0, kd=100.0))
    assert list(tmp_path.iterdir()) == []
    # the same trajectory with gains the step can integrate is tracked
    result = track(ur3_sim, move, JointPD(kp=200.0, kd=20.0, gravity_compensation=True))
    assert result.max_error.max() < 1e-6


def test_a_failed_run_restores_the_payload(ur3_sim):
    move = smooth_trajectory(duration=0.2)
    with pytest.raises(SimulationError):
        track(ur3_sim, move, ComputedTorque(kp=1e12, kd=1e6), payload=np.full(len(move.t), 2.0))
    assert ur3_sim.payload == 0.0


def test_runs_of_less_than_one_step_or_too_many_are_refused(ur3_sim):
    short = SimpleNamespace(t=np.array([0.0, 1e-4]), q=np.tile(Q_BENT, (2, 1)),
                            qd=np.zeros((2, 6)), qdd=np.zeros((2, 6)))
    with pytest.raises(ValueError, match="less than one time step"):
        track(ur3_sim, short, ComputedTorque())
    long = SimpleNamespace(t=np.array([0.0, 1e5]), q=np.tile(Q_BENT, (2, 1)),
                           qd=np.zeros((2, 6)), qdd=np.zeros((2, 6)))
    with pytest.raises(ValueError, match="time steps of 0.001 s is too large"):
        track(ur3_sim, long, ComputedTorque())
