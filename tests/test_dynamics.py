"""dqlab.dynamics and dqlab.inertia: Newton-Euler on dual vectors against MuJoCo and pinocchio,
closed forms, the energy balance, batches, and bad input."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from dqlab import dynamics, models
from dqlab.inertia import LinkInertia
from dqlab.robot import Link, Robot

ROBOTS = {"ur3": models.ur3, "ur3_mdh": models.ur3_mdh, "scara": models.scara_rsm5,
          "desk_arm": models.desk_arm, "ur5": models.ur5, "ur10": models.ur10,
          "six_r": models.six_r}


def random_states(robot, count, seed):
    """(q, qd, qdd) of shape (count, n): joints inside their limits (within +-pi)."""
    rng = np.random.default_rng(seed)
    lo, hi = np.clip(robot.limits.T, -np.pi, np.pi)
    q = rng.uniform(lo, hi, size=(count, robot.n))
    return q, rng.normal(size=(count, robot.n)), rng.normal(size=(count, robot.n))


def relative_gap(a, b):
    return float(np.abs(a - b).max() / np.abs(b).max())


# --------------------------------------------------------------------------------------
# MuJoCo, on the model the project generates from the same robot

def mujoco_model(robot, **options):
    mujoco = pytest.importorskip("mujoco")
    from dqlab.sim import mjcf_from_robot

    model = mujoco.MjModel.from_xml_string(
        mjcf_from_robot(robot, damping=0.0, armature=0.0, **options))
    return mujoco, model, mujoco.MjData(model)


def mujoco_inverse_and_mass_matrix(robot, q, qd, qdd, **options):
    mujoco, model, data = mujoco_model(robot, **options)
    taus, masses = [], []
    for state in zip(q, qd, qdd, strict=True):
        data.qpos[:], data.qvel[:], data.qacc[:] = state
        mujoco.mj_inverse(model, data)
        taus.append(data.qfrc_inverse.copy())
        M = np.zeros((robot.n, robot.n))
        try:
            mujoco.mj_fullM(model, data, M)            # MuJoCo 4
        except TypeError:
            mujoco.mj_fullM(model, M, data.qM)         # MuJoCo 3
        masses.append(M)
    return np.array(taus), np.array(masses)


@pytest.mark.parametrize("name", ["ur3", "ur3_mdh", "scara", "desk_arm", "ur10", "six_r"])
def test_inverse_dynamics_and_mass_matrix_equal_mujoco(name):
    robot = ROBOTS[name]()
    q, qd, qdd = random_states(robot, 50, seed=1)
    tau_mj, M_mj = mujoco_inverse_and_mass_matrix(robot, q, qd, qdd)
    for tau in (dynamics.inverse_dynamics(robot, q, qd, qdd),               # a batch
                np.array([dynamics.inverse_dynamics(robot, *s)              # one at a time
                          for s in zip(q, qd, qdd, strict=True)])):
        assert relative_gap(tau, tau_mj) <= 1e-9
    assert relative_gap(dynamics.mass_matrix(robot, q), M_mj) <= 1e-9


def test_base_tool_and_payload_are_honoured_like_mujoco():
    robot = models.ur3_mdh()
    X = np.eye(4)
    X[:3, :3] = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]   # mounted on a wall
    X[:3, 3] = [0.1, -0.2, 0.8]
    robot.base = X
    tool = np.eye(4)
    tool[:3, 3] = [0.01, 0.02, 0.15]
    robot.tool = tool
    q, qd, qdd = random_states(robot, 20, seed=2)
    tau_mj, _ = mujoco_inverse_and_mass_matrix(robot, q, qd, qdd, payload=1.5)
    mujoco, model, _ = mujoco_model(robot, payload=1.5)
    radius = float(model.geom("payload").size[0])
    loaded = dynamics.with_payload(robot, 1.5, tool[:3, 3], radius=radius)   # at the TCP
    assert relative_gap(dynamics.inverse_dynamics(loaded, q, qd, qdd), tau_mj) <= 1e-9


def test_other_gravity_like_mujoco():
    robot = models.ur3()
    q, qd, qdd = random_states(robot, 10, seed=3)
    tau_mj, _ = mujoco_inverse_and_mass_matrix(robot, q, qd, qdd, gravity=3.7)
    tau = dynamics.inverse_dynamics(robot, q, qd, qdd, gravity=[0.0, 0.0, -3.7])
    assert relative_gap(tau, tau_mj) <= 1e-9


# --------------------------------------------------------------------------------------
# A second, independent oracle: pinocchio (spatial algebra, Featherstone's algorithms)

def pinocchio_model(robot):
    pin = pytest.importorskip("pinocchio")
    from dqlab.sim.mjcf import link_placements

    placements, _, corners = link_placements(robot)
    model = pin.Model()
    model.gravity.linear = np.array([0.0, 0.0, -9.81])
    parent = 0
    for i, (link, X) in enumerate(zip(robot.links, placements, strict=True)):
        if i == 0:
            X = robot.base @ X
        joint = pin.JointModelRZ() if link.is_revolute else pin.JointModelPZ()
        parent = model.addJoint(parent, joint, pin.SE3(X[:3, :3], X[:3, 3]), f"joint{i + 1}")
        inertia = link.inertia.moved(corners[i + 1])      # from the DH frame to the body's
        model.appendBodyToJoint(parent, pin.Inertia(inertia.mass, inertia.com,
                                                    inertia.tensor), pin.SE3.Identity())
    return pin, model, model.createData()


@pytest.mark.parametrize("name", ["ur3", "ur3_mdh", "scara"])
def test_inverse_dynamics_and_mass_matrix_equal_pinocchio(name):
    robot = ROBOTS[name]()
    pin, model, data = pinocchio_model(robot)
    q, qd, qdd = random_states(robot, 50, seed=4)
    tau = dynamics.inverse_dynamics(robot, q, qd, qdd)
    M = dynamics.mass_matrix(robot, q)
    for k in range(len(q)):
        assert relative_gap(tau[k], pin.rnea(model, data, q[k], qd[k], qdd[k])) <= 1e-9
        M_pin = pin.crba(model, data, q[k]).copy()
        M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T        # pinocchio fills the upper half
        assert relative_gap(M[k], M_pin) <= 1e-9


@pytest.mark.parametrize("name", ["ur3", "ur3_mdh", "scara"])
def test_the_urdf_carries_the_same_dynamics(name):
    # pinocchio reads the URDF that dqlab writes: its inverse dynamics must be dqlab's
    pin = pytest.importorskip("pinocchio")
    from dqlab.sim import urdf_from_robot

    robot = ROBOTS[name]()
    model = pin.buildModelFromXML(urdf_from_robot(robot))
    model.gravity.linear = np.array([0.0, 0.0, -9.81])
    data = model.createData()
    assert model.nv == robot.n          # (an unlimited joint is continuous: nq = 2 there)
    q, qd, qdd = random_states(robot, 20, seed=13)
    tau = dynamics.inverse_dynamics(robot, q, qd, qdd)
    for k in range(len(q)):
        q_pin = pin.integrate(model, pin.neutral(model), q[k])
        assert relative_gap(tau[k], pin.rnea(model, data, q_pin, qd[k], qdd[k])) <= 1e-9


# --------------------------------------------------------------------------------------
# Closed forms

def test_a_pendulum_obeys_its_closed_form():
    # a rod of mass m and length l turning about the world's y axis (the link frame's z,
    # alpha = 0, base turned so that the joint axis is horizontal)
    m, l, r = 2.0, 0.5, 0.01
    rod = LinkInertia.rod(m, [-l, 0, 0], [0, 0, 0], r)     # standard DH: from the axis to the tip
    base = np.eye(4)
    base[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]    # frame 0's z along world -y
    pendulum = Robot([Link(l, 0.0, 0.0, inertia=rod)], base=base, name="pendulum")
    I_axis = m * l**2 / 3 + m * r**2 / 4                  # rod about its end
    for q, qd, qdd in [(0.3, 0.0, 0.0), (-1.2, 2.0, 0.7), (2.5, -1.0, -3.0)]:
        tau = dynamics.inverse_dynamics(pendulum, [q], [qd], [qdd])[0]
        # the centre of mass at l/2 (cos q, 0, sin q) in the world: gravity pulls it down
        assert math.isclose(tau, I_axis * qdd + m * 9.81 * l / 2 * math.cos(q), rel_tol=1e-12)


def test_a_payload_adds_m_g_times_the_jacobian():
    robot = models.ur3()
    q, _, _ = random_states(robot, 20, seed=5)
    extra = (dynamics.gravity_torques(dynamics.with_payload(robot, 3.0), q)
             - dynamics.gravity_torques(robot, q))
    np.testing.assert_allclose(extra, 3.0 * 9.81 * robot.jacobian(q)[:, 2], atol=1e-12)


def test_the_terms_add_up_and_forward_dynamics_inverts_inverse_dynamics():
    for name in ("ur3", "ur3_mdh", "scara"):
        robot = ROBOTS[name]()
        q, qd, qdd = random_states(robot, 30, seed=6)
        M = dynamics.mass_matrix(robot, q)
        tau = dynamics.inverse_dynamics(robot, q, qd, qdd)
        parts = ((M @ qdd[..., None])[..., 0] + dynamics.coriolis_torques(robot, q, qd)
                 + dynamics.gravity_torques(robot, q))
        np.testing.assert_allclose(parts, tau, atol=1e-10 * np.abs(tau).max())
        np.testing.assert_allclose(dynamics.forward_dynamics(robot, q, qd, tau), qdd,
                                   atol=1e-9)
        assert np.allclose(M, np.swapaxes(M, -1, -2), atol=1e-14)
        assert (np.linalg.eigvalsh(M) > 0).all()
        T = dynamics.kinetic_energy(robot, q, qd)
        np.testing.assert_allclose(T, 0.5 * np.einsum("ki,kij,kj->k", qd, M, qd), rtol=1e-12)


def test_the_coriolis_matrix_property_mdot_minus_2c_is_skew():
    # qd^T (Mdot - 2C) qd = 0 with C qd = c: d/dt(qd^T M qd)/2 = qd^T c + ... (power of c)
    robot = models.ur3()
    q, qd, _ = random_states(robot, 10, seed=7)
    h = 1e-6
    M_dot = (dynamics.mass_matrix(robot, q + h * qd)
             - dynamics.mass_matrix(robot, q - h * qd)) / (2 * h)
    c = dynamics.coriolis_torques(robot, q, qd)
    power = 0.5 * np.einsum("ki,kij,kj->k", qd, M_dot, qd) - np.einsum("ki,ki->k", qd, c)
    assert np.abs(power).max() < 1e-7


# --------------------------------------------------------------------------------------
# The power balance along a motion, d(T + V)/dt = qd . tau, by finite differences

@given(seed=st.integers(0, 2**32 - 1), name=st.sampled_from(["ur3", "ur3_mdh", "scara"]))
def test_power_balance_along_a_motion(seed, name):
    robot = ROBOTS[name]()
    rng = np.random.default_rng(seed)
    lo, hi = np.clip(robot.limits.T, -np.pi, np.pi)
    q0 = rng.uniform(lo + 0.02, hi - 0.02)
    qd0, qdd0, qddd0 = rng.normal(size=(3, robot.n))
    if name == "scara":                       # keep the slide well inside its travel
        qd0[2], qdd0[2], qddd0[2] = 0.1 * qd0[2], 0.1 * qdd0[2], 0.1 * qddd0[2]

    def motion(t):                           # a cubic in time through (q0, qd0, qdd0)
        return (q0 + qd0 * t + qdd0 * t**2 / 2 + qddd0 * t**3 / 6,
                qd0 + qdd0 * t + qddd0 * t**2 / 2)

    def energy(t):
        q, qd = motion(t)
        return dynamics.kinetic_energy(robot, q, qd) + dynamics.potential_energy(robot, q)

    h = 1e-4
    rate = (energy(h) - energy(-h)) / (2 * h)
    power = qd0 @ dynamics.inverse_dynamics(robot, q0, qd0, qdd0)
    scale = np.abs(qd0) @ np.abs(dynamics.inverse_dynamics(robot, q0, qd0, qdd0)) + 1.0
    assert abs(rate - power) < 1e-6 * scale


# --------------------------------------------------------------------------------------
# Batches, the fast path, the pieces

@pytest.mark.parametrize("lead", [(), (1,), (4,), (2, 3)])
def test_a_batch_equals_its_single_calls(lead):
    robot = models.ur3_mdh()
    q, qd, qdd = (x.reshape(lead + (6,)) for x in random_states(robot, math.prod(lead), 8))
    tau = dynamics.inverse_dynamics(robot, q, qd, qdd)
    M = dynamics.mass_matrix(robot, q)
    assert tau.shape == lead + (6,) and M.shape == lead + (6, 6)
    for index in np.ndindex(*lead):
        np.testing.assert_allclose(tau[index], dynamics.inverse_dynamics(
            robot, q[index], qd[index], qdd[index]), rtol=0, atol=1e-12)
        np.testing.assert_allclose(M[index], dynamics.mass_matrix(robot, q[index]),
                                   rtol=0, atol=1e-15)


def test_broadcasting_and_an_empty_batch():
    robot = models.ur3()
    q, qd, qdd = random_states(robot, 5, seed=9)
    tau = dynamics.inverse_dynamics(robot, q, qd[0], np.zeros(6))
    np.testing.assert_allclose(tau[2], dynamics.inverse_dynamics(robot, q[2], qd[0],
                                                                 np.zeros(6)), atol=1e-12)
    assert dynamics.inverse_dynamics(robot, np.zeros((0, 6)), np.zeros(6),
                                     np.zeros(6)).shape == (0, 6)
    assert dynamics.mass_matrix(robot, np.zeros((0, 6))).shape == (0, 6, 6)


@pytest.mark.parametrize("name", list(ROBOTS))
def test_the_float_path_equals_the_readable_path(name, monkeypatch):
    # without the compiled kernels, a single state runs on Python floats
    # (dqlab._fast.dynamics_floats) and a batch of one the dual-quaternion recursion on arrays
    monkeypatch.setenv("DQLAB_COMPILED", "0")
    robot = ROBOTS[name]()
    q, qd, qdd = random_states(robot, 100, seed=10)
    for state in zip(q, qd, qdd, strict=True):
        single = dynamics.inverse_dynamics(robot, *state)
        batch = dynamics.inverse_dynamics(robot, *(x[None] for x in state))[0]
        np.testing.assert_allclose(single, batch, rtol=0,
                                   atol=1e-12 * max(1.0, np.abs(batch).max()))


def test_joint_twists_are_the_joint_axes_as_lines():
    robot = models.ur3()
    q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    frames = robot.fk(q, all_frames=True)
    points, axes = robot.joint_axes(q)
    for i, (l, m) in enumerate(dynamics.joint_twists(robot)):
        X = frames[i + 1]                                   # link frame i, in the world
        l_W = X[:3, :3] @ l
        m_W = X[:3, :3] @ m + np.cross(X[:3, 3], l_W)
        np.testing.assert_allclose(l_W, axes[i], atol=1e-12)
        np.testing.assert_allclose(m_W, np.cross(points[i], axes[i]), atol=1e-12)


def test_dual_cross_is_half_the_commutator_of_pure_dual_quaternions():
    from dqlab import dual_quaternion_product

    rng = np.random.default_rng(11)
    a, a_d, b, b_d = rng.normal(size=(4, 3))
    pure = [np.concatenate([[0.0], x, [0.0], y]) for x, y in ((a, a_d), (b, b_d))]
    commutator = 0.5 * (dual_quaternion_product(*pure) - dual_quaternion_product(*pure[::-1]))
    real, dual = dynamics.dual_cross(a, a_d, b, b_d)
    np.testing.assert_allclose(commutator, np.concatenate([[0.0], real, [0.0], dual]),
                               atol=1e-15)


# --------------------------------------------------------------------------------------
# The inertias

def test_ur_inertias_are_the_makers_table():
    for name, label in (("UR3", models.ur3), ("UR5", models.ur5), ("UR10", models.ur10)):
        p = models.UR_DYNAMICS[name]
        links = label().links
        assert [lk.inertia.mass for lk in links] == list(p["mass"])
        np.testing.assert_array_equal([lk.inertia.com for lk in links], p["com"])
    # the upper arm of the UR3: a cylinder of radius 0.075 m and length |a2| along x
    rod = models.ur3().links[1].inertia.tensor
    m, r, length = 3.42, 0.075, 0.24365
    np.testing.assert_allclose(np.diag(rod), [m * r**2 / 2] + 2 * [m * (3 * r**2 + length**2)
                                                                   / 12], rtol=1e-12)


def test_ur_link_inertias_approximation_matches_ur_description_cylinders():
    p = models.UR_DYNAMICS["UR3"]
    approx = models.ur_link_inertias(p["mass"], p["com"], a=models.UR_DH["UR3"]["a"])
    for k in (1, 2):          # the two arm tubes are exactly the ROS file's cylinders
        np.testing.assert_allclose(approx[k].tensor.diagonal(),
                                   np.array(p["tensor"][k][:3]), rtol=1e-12)
    with pytest.raises(ValueError, match="DH lengths"):
        models.ur_link_inertias(p["mass"], p["com"])


def test_the_report_ur3_carries_the_same_bodies_as_ur3():
    # the two models of one arm, seen from one base, put every link's centre of mass at the
    # same place up to the report's length differences (a few millimetres)
    ur, report = models.ur3(), models.ur3_mdh()
    S, o = (np.array(v) for v in models.UR3_MDH_JOINT_MAP)
    rng = np.random.default_rng(12)
    turn = np.eye(4)
    turn[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
    for q in rng.uniform(-np.pi, np.pi, size=(20, 6)):
        F_ur, F_rep = ur.fk(S * q + o, all_frames=True), report.fk(q, all_frames=True)
        for i in range(1, 7):
            c_ur = F_ur[i] @ np.append(ur.links[i - 1].inertia.com, 1.0)
            c_rep = turn @ F_rep[i] @ np.append(report.links[i - 1].inertia.com, 1.0)
            assert np.linalg.norm(c_ur - c_rep) < 0.01
    np.testing.assert_allclose(
        dynamics.gravity_torques(ur, [0.0, -1.0, 1.0, 0.0, 0.5, 0.0])[1],
        -dynamics.gravity_torques(report, (np.array([0.0, -1.0, 1.0, 0.0, 0.5, 0.0]) - o) / S)[1],
        rtol=0.02)


def test_link_inertia_checks_and_algebra():
    with pytest.raises(ValueError, match="mass"):
        LinkInertia(-1.0, [0, 0, 0])
    with pytest.raises(ValueError, match="mass"):
        LinkInertia(float("nan"), [0, 0, 0])
    with pytest.raises(ValueError, match="com"):
        LinkInertia(1.0, [0, 0])
    with pytest.raises(ValueError, match="symmetric"):
        LinkInertia(1.0, [0, 0, 0], [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match="triangle"):
        LinkInertia(1.0, [0, 0, 0], np.diag([0.1, 0.1, 0.3]))
    with pytest.raises(ValueError, match="semidefinite"):
        LinkInertia(1.0, [0, 0, 0], np.diag([-0.1, 0.1, 0.1]))
    with pytest.raises(TypeError, match="com"):
        LinkInertia(1.0, [0, 0, 1j])
    a = LinkInertia.rod(1.0, [0, 0, 0], [0.4, 0, 0], 0.02)
    b = LinkInertia.sphere(0.5, [0.4, 0.1, 0], 0.03)
    both = a + b
    w, v = np.array([0.3, -0.2, 0.9]), np.array([0.1, 0.5, -0.4])
    for total, parts in ((both.momentum(w, v), (a.momentum(w, v), b.momentum(w, v))),):
        np.testing.assert_allclose(total[0], parts[0][0] + parts[1][0], atol=1e-15)
        np.testing.assert_allclose(total[1], parts[0][1] + parts[1][1], atol=1e-15)
    G = both.spatial_matrix()
    np.testing.assert_allclose(G @ np.concatenate([v, w]), np.concatenate(both.momentum(w, v)),
                               atol=1e-15)
    assert both.scaled(2.0).mass == 3.0
    with pytest.raises(AttributeError):
        a.mass = 2.0


def test_a_robot_with_inertias_pickles():
    # dask sends robots to its workers by pickling them
    import pickle

    robot = models.ur3_mdh()
    again = pickle.loads(pickle.dumps(robot))
    assert [lk.inertia for lk in again.links] == [lk.inertia for lk in robot.links]
    q, qd, qdd = random_states(robot, 3, seed=14)
    np.testing.assert_array_equal(dynamics.inverse_dynamics(again, q, qd, qdd),
                                  dynamics.inverse_dynamics(robot, q, qd, qdd))


# --------------------------------------------------------------------------------------
# Bad input

def test_bad_input_is_refused_by_name():
    robot = models.ur3()
    zero = np.zeros(6)
    bare = Robot([Link(0.3, 0.0, 0.0), Link(0.2, 0.0, 0.0)], name="bare 2R")
    with pytest.raises(ValueError, match="link 1 of bare 2R has no inertial parameters"):
        dynamics.inverse_dynamics(bare, [0, 0], [0, 0], [0, 0])
    with pytest.raises(TypeError, match="robot must be a dqlab Robot"):
        dynamics.mass_matrix("ur3", zero)
    with pytest.raises(ValueError, match="gravity"):
        dynamics.inverse_dynamics(robot, zero, zero, zero, gravity=[0, 0, np.nan])
    with pytest.raises(ValueError, match="gravity"):
        dynamics.gravity_torques(robot, zero, gravity=[0, -9.81])
    with pytest.raises(ValueError, match="qd must have shape"):
        dynamics.inverse_dynamics(robot, zero, np.zeros(5), zero)
    with pytest.raises(ValueError, match="do not broadcast"):
        dynamics.inverse_dynamics(robot, np.zeros((3, 6)), np.zeros((2, 6)), zero)
    with pytest.raises(ValueError, match="qdd contains NaN"):
        dynamics.inverse_dynamics(robot, zero, zero, [0, 0, np.nan, 0, 0, 0])
    with pytest.raises(TypeError, match="tau"):
        dynamics.forward_dynamics(robot, zero, zero, zero + 1j)
    with pytest.raises(ValueError, match="overflow"):
        dynamics.inverse_dynamics(robot, zero, np.full(6, 1e200), zero)
    with pytest.raises(ValueError, match="joint 3"):
        dynamics.mass_matrix(models.scara_rsm5(), [0, 0, 0.5, 0])
    with pytest.raises(ValueError, match="inertias must hold 6"):
        dynamics.with_inertias(robot, [None])
    with pytest.raises(ValueError, match="inertia must be"):
        Link(0.3, 0.0, 0.0, inertia=2.0)
