"""dqlab.dynamics' algorithms in dual-vector form: the composite rigid bodies (mass matrix), the
articulated bodies (forward dynamics), the link Jacobians and the regressor, each against the
recursion the module had before (inverse dynamics column by column, a solve with M), against
pinocchio (crba, aba, computeJointTorqueRegressor) and MuJoCo (qM, mj_forward), and on bodies
that make M singular."""

import numpy as np
import pytest
from test_dynamics import ROBOTS, mujoco_model, pinocchio_model, random_states, relative_gap

from dqlab import dynamics, models
from dqlab.inertia import LinkInertia
from dqlab.robot import Link, Robot

PI = np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]])


def columns_of_inverse_dynamics(robot, q):
    """M column by column: ID(q, 0, e_j) without gravity, as dqlab computed it before."""
    n = robot.n
    unit = np.broadcast_to(np.eye(n), q.shape[:-1] + (n, n))
    tau = dynamics.inverse_dynamics(robot, q[..., None, :], np.zeros(n), unit,
                                    gravity=(0.0, 0.0, 0.0))
    return np.swapaxes(tau, -1, -2)


@pytest.mark.parametrize("name", list(ROBOTS))
def test_the_algorithms_equal_the_recursion(name):
    # CRBA = n runs of Newton-Euler; ABA = a solve with that M; Y pi = Newton-Euler;
    # sum_i J_i^T Pi M_i J_i = M
    robot = ROBOTS[name]()
    q, qd, qdd = random_states(robot, 40, seed=21)
    M_columns = columns_of_inverse_dynamics(robot, q)
    M = dynamics.mass_matrix(robot, q)
    assert relative_gap(M, M_columns) <= 1e-13
    tau = dynamics.inverse_dynamics(robot, q, qd, qdd)
    bias = dynamics.inverse_dynamics(robot, q, qd, np.zeros_like(q))
    solved = np.linalg.solve(M_columns, (tau - bias)[..., None])[..., 0]
    qdd_aba = dynamics.forward_dynamics(robot, q, qd, tau)
    assert relative_gap(qdd_aba, solved) <= 1e-11 and relative_gap(qdd_aba, qdd) <= 1e-11
    pi = dynamics.inertial_parameters(robot)
    Y = dynamics.regressor(robot, q, qd, qdd)
    assert Y.shape == (40, robot.n, 10 * robot.n)
    assert relative_gap(Y @ pi, tau) <= 1e-13
    J = dynamics.link_jacobians(robot, q)
    spatial = [dynamics._spatial_inertia(inertia) for inertia in dynamics.link_inertias(robot)]
    M_sum = sum(np.swapaxes(J[:, i], -1, -2) @ PI @ spatial[i] @ J[:, i]
                for i in range(robot.n))
    assert relative_gap(M_sum, M_columns) <= 1e-13


def test_the_spatial_inertia_and_adjoint_matrices_are_those_of_the_dual_vector_maps():
    rng = np.random.default_rng(22)
    inertia = models.ur3().links[1].inertia
    M = dynamics._spatial_inertia(inertia)
    for omega, v in rng.normal(size=(5, 2, 3)):
        np.testing.assert_allclose(M @ np.concatenate([omega, v]),
                                   np.concatenate(inertia.momentum(omega, v)), atol=1e-15)
    X = models.ur3().fk(rng.uniform(-3, 3, 6))
    from dqlab import dual_quaternion_apply_line, dual_quaternion_from_transform

    Q = dual_quaternion_from_transform(X)
    Ad = dynamics._adjoint_matrix(X)
    for a, a_dual in rng.normal(size=(5, 2, 3)):
        np.testing.assert_allclose(Ad @ np.concatenate([a, a_dual]),
                                   np.concatenate(dual_quaternion_apply_line(Q, a, a_dual)),
                                   atol=1e-14)


def test_the_last_link_jacobian_is_the_geometric_jacobian():
    robot = models.ur3_mdh()
    q, _, _ = random_states(robot, 10, seed=23)
    J = dynamics.link_jacobians(robot, q)[:, -1]             # (omega, v_O) in frame n
    X = robot.fk(q) @ np.linalg.inv(robot.tool)              # frame n in the base
    R, p = X[:, :3, :3], X[:, :3, 3]
    omega = R @ J[:, :3]
    v_origin = R @ J[:, 3:]                                   # the body point at frame n
    geometric = robot.jacobian(q)
    p_T = robot.fk(q)[:, :3, 3]
    v_flange = v_origin + np.cross(omega, (p_T - p)[:, :, None], axis=1)
    np.testing.assert_allclose(omega, geometric[:, 3:], atol=1e-12)
    np.testing.assert_allclose(v_flange, geometric[:, :3], atol=1e-12)


# --------------------------------------------------------------------------------------
# pinocchio and MuJoCo

def parameters_moved(pi, X_AB):
    """The ten parameters of a body described in frame B, described in frame A (X_AB the pose
    of B in A): m, R mc + m t, and the tensor about A's origin. Linear in pi."""
    m, mc = pi[0], pi[1:4]
    ixx, ixy, iyy, ixz, iyz, izz = pi[4:]
    I_B = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    R, t = X_AB[:3, :3], X_AB[:3, 3]
    Rmc = R @ mc
    I_A = (R @ I_B @ R.T + (2 * Rmc @ t + m * t @ t) * np.eye(3) - np.outer(Rmc, t)
           - np.outer(t, Rmc) - m * np.outer(t, t))
    return np.array([m, *(Rmc + m * t), I_A[0, 0], I_A[0, 1], I_A[1, 1], I_A[0, 2], I_A[1, 2],
                     I_A[2, 2]])


@pytest.mark.parametrize("name", ["ur3", "ur3_mdh", "scara"])
def test_the_algorithms_equal_pinocchio(name):
    robot = ROBOTS[name]()
    pin, model, data = pinocchio_model(robot)
    from dqlab.sim.mjcf import link_placements

    corners = link_placements(robot)[2]
    # pinocchio's parameters are in its joint frames (the bodies' frames), dqlab's in the DH
    # frames: per link a linear map T_i, pi_pin = T_i pi, hence Y = Y_pin blockdiag(T_i)
    T = np.zeros((10 * robot.n, 10 * robot.n))
    for i in range(robot.n):
        T[10 * i:10 * i + 10, 10 * i:10 * i + 10] = np.column_stack(
            [parameters_moved(e, corners[i + 1]) for e in np.eye(10)])
    pi = dynamics.inertial_parameters(robot)
    pi_pin = np.concatenate([model.inertias[i + 1].toDynamicParameters()
                             for i in range(robot.n)])
    np.testing.assert_allclose(T @ pi, pi_pin, atol=1e-12)
    q, qd, qdd = random_states(robot, 30, seed=24)
    tau = dynamics.inverse_dynamics(robot, q, qd, qdd)
    Y = dynamics.regressor(robot, q, qd, qdd)
    qdd_aba = dynamics.forward_dynamics(robot, q, qd, tau)
    M = dynamics.mass_matrix(robot, q)
    for k in range(len(q)):
        Y_pin = pin.computeJointTorqueRegressor(model, data, q[k], qd[k], qdd[k]).copy()
        assert relative_gap(Y[k], Y_pin @ T) <= 1e-12
        assert relative_gap(pin.aba(model, data, q[k], qd[k], tau[k]), qdd_aba[k]) <= 1e-10
        M_pin = pin.crba(model, data, q[k]).copy()
        assert relative_gap(M[k], np.triu(M_pin) + np.triu(M_pin, 1).T) <= 1e-12


@pytest.mark.parametrize("name", ["ur3", "ur3_mdh", "scara", "desk_arm"])
def test_forward_dynamics_equals_mujoco(name):
    robot = ROBOTS[name]()
    mujoco, model, data = mujoco_model(robot)
    q, qd, qdd = random_states(robot, 30, seed=25)
    tau = dynamics.inverse_dynamics(robot, q, qd, qdd)
    qdd_aba = dynamics.forward_dynamics(robot, q, qd, tau)
    for k in range(len(q)):
        data.qpos[:], data.qvel[:], data.ctrl[:] = q[k], qd[k], 0.0
        data.qfrc_applied[:] = tau[k]
        mujoco.mj_forward(model, data)
        assert relative_gap(qdd_aba[k], data.qacc) <= 1e-9


# --------------------------------------------------------------------------------------
# The parameters, and the bodies that make M singular

def test_inertial_parameters_round_trip_and_refuse_what_no_body_has():
    for name in ROBOTS:
        robot = ROBOTS[name]()
        back = dynamics.inertias_from_parameters(dynamics.inertial_parameters(robot))
        for a, b in zip(back, dynamics.link_inertias(robot), strict=True):
            assert a.mass == b.mass
            np.testing.assert_allclose(a.com, b.com, atol=1e-15)
            np.testing.assert_allclose(a.tensor, b.tensor, atol=1e-14)
    pi = dynamics.inertial_parameters(models.ur3())
    bad = pi.copy()
    bad[20] = -1.0                                     # link 3's mass
    with pytest.raises(ValueError, match="link 3"):
        dynamics.inertias_from_parameters(bad)
    bad = pi.copy()
    bad[14 + 10] = -0.5                               # link 3's Ixx: not a tensor
    with pytest.raises(ValueError, match="link 3"):
        dynamics.inertias_from_parameters(bad)
    with pytest.raises(ValueError, match=r"shape \(10 n,\)"):
        dynamics.inertias_from_parameters(pi[:15])


def two_link(second):
    """A planar 2R arm whose second link carries ``second``."""
    first = LinkInertia.rod(1.0, [-0.3, 0, 0], [0, 0, 0], 0.02)
    return Robot([Link(0.3, 0.0, 0.0, inertia=first), Link(0.2, 0.0, 0.0, inertia=second)],
                 name="2R")


def test_forward_dynamics_names_the_joint_that_moves_no_mass():
    zero = np.zeros(2)
    with pytest.raises(ValueError, match="singular: joint 2 moves no mass"):
        dynamics.forward_dynamics(two_link(LinkInertia(0.0, [0, 0, 0])), zero, zero, zero)
    # a point mass on joint 2's own axis: frame 2 sits 0.2 m beyond it
    on_axis = LinkInertia.sphere(0.5, [-0.2, 0.0, 0.3])
    with pytest.raises(ValueError, match="joint 2 moves no mass"):
        dynamics.forward_dynamics(two_link(on_axis), zero, zero, zero)
    q = np.zeros((3, 6))
    massless_wrist = dynamics.with_inertias(
        models.ur3(), [lk.inertia for lk in models.ur3().links[:5]] + [LinkInertia(0.0, [0, 0, 0])])
    with pytest.raises(ValueError, match=r"singular at q\[0\]: joint 6 moves no mass"):
        dynamics.forward_dynamics(massless_wrist, q, q, q)
    huge = LinkInertia(1.0, [0.0, 0.0, 0.0], np.eye(3) * 1e306)
    with pytest.raises(ValueError, match="overflows.*link 2"):
        dynamics.forward_dynamics(two_link(huge), zero, zero, zero)
    # a light last link is not a massless one
    light = LinkInertia.sphere(1e-6, [-0.1, 0.0, 0.0], 0.01)
    assert np.isfinite(dynamics.forward_dynamics(two_link(light), zero, zero, zero)).all()


@pytest.mark.parametrize("lead", [(), (1,), (2, 3)])
def test_the_new_functions_broadcast_like_the_others(lead):
    robot = models.ur3()
    q, qd, qdd = (x.reshape(lead + (6,)) for x in random_states(robot, int(np.prod(lead)), 26))
    Y = dynamics.regressor(robot, q, qd, qdd)
    J = dynamics.link_jacobians(robot, q)
    qdd_aba = dynamics.forward_dynamics(robot, q, qd, qdd)
    assert Y.shape == lead + (6, 60) and J.shape == lead + (6, 6, 6)
    for index in np.ndindex(*lead):
        np.testing.assert_allclose(Y[index], dynamics.regressor(robot, q[index], qd[index],
                                                                qdd[index]), atol=1e-12)
        np.testing.assert_allclose(qdd_aba[index], dynamics.forward_dynamics(
            robot, q[index], qd[index], qdd[index]), atol=1e-10)
