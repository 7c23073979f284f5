"""Tests for dqlab.jacobian: geometric Jacobian against finite differences and the UR3
report's printed matrix; manipulability and singularities; the SCARA's analytic Jacobian."""

import numpy as np
import pytest

from dqlab.jacobian import (
    is_singular,
    manipulability,
    scara_is_singular,
    scara_jacobian,
    scara_jacobian_determinant,
    singular_values,
    xyz_yaw_jacobian,
)
from dqlab.models import desk_arm, scara_rsm5, six_r, ur3, ur3_mdh

# The UR3 report's geometric Jacobian (seeds/003), at q = (0.1, -0.5, 0.8, -0.2, 0.5, 0.1)
# rad (the angles recovered in tests/test_models.py).
REPORT_Q = np.array([0.1, -0.5, 0.8, -0.2, 0.5, 0.1])
REPORT_J = np.array([
    [-4.97810882e-01, -8.47229774e-03, 3.20619851e-03, -3.07789617e-03, -3.98337156e-02, 0],
    [-8.81769084e-02, 8.44403790e-02, -3.19550405e-02, 3.06762967e-02, 3.22355781e-03, 0],
    [0, 5.04126904e-01, 2.89996758e-01, 8.65100863e-02, -7.16022610e-02, 0],
    [0, 9.95004165e-01, 9.95004165e-01, 9.95004165e-01, -9.93346654e-02, 8.68420009e-01],
    [0, 9.98334166e-02, 9.98334166e-02, 9.98334166e-02, 9.90033289e-01, 1.35235641e-01],
    [1, 6.12323400e-17, 6.12323400e-17, 6.12323400e-17, 9.98334166e-02, -4.77030408e-01],
])


def finite_difference_jacobian(robot, q, h=1e-6):
    """Central differences of the TCP position and of the tool rotation, batched."""
    q = np.asarray(q, dtype=float)
    n = robot.n
    steps = h * np.eye(n)
    plus = robot.fk(q[..., None, :] + steps)                     # (..., n, 4, 4)
    minus = robot.fk(q[..., None, :] - steps)
    linear = (plus[..., :3, 3] - minus[..., :3, 3]) / (2 * h)      # (..., n, 3)
    dR = plus[..., :3, :3] @ np.swapaxes(minus[..., :3, :3], -1, -2)
    # small rotation: R ~ I + [w]x, so w = vee(R - R^T) / 2
    w = 0.5 * np.stack([dR[..., 2, 1] - dR[..., 1, 2], dR[..., 0, 2] - dR[..., 2, 0],
                        dR[..., 1, 0] - dR[..., 0, 1]], axis=-1)
    angular = w / (2 * h)
    return np.concatenate([np.swapaxes(linear, -1, -2), np.swapaxes(angular, -1, -2)], axis=-2)


def random_joints(robot, rng, size):
    lo = np.maximum(robot.limits[:, 0], -np.pi)
    hi = np.minimum(robot.limits[:, 1], np.pi)
    return rng.uniform(lo, hi, size=(size, robot.n))


def test_report_jacobian_is_reproduced():
    J = ur3_mdh().jacobian(REPORT_Q)
    np.testing.assert_allclose(J, REPORT_J, atol=2e-8)


@pytest.mark.parametrize("model", [ur3, ur3_mdh, desk_arm, scara_rsm5, six_r])
def test_geometric_jacobian_equals_finite_differences(model):
    """1,000 random configurations (margin kept from prismatic limits), to 1e-6."""
    rng = np.random.default_rng(20)
    robot = model()
    q = random_joints(robot, rng, 1000)
    if model is scara_rsm5:
        q[:, 2] = rng.uniform(0.01, 0.14, 1000)
    J = robot.jacobian(q)
    assert J.shape == (1000, 6, robot.n)
    np.testing.assert_allclose(J, finite_difference_jacobian(robot, q), atol=1e-6)


def test_jacobian_maps_joint_rates_to_tool_velocity():
    rng = np.random.default_rng(21)
    robot = ur3()
    q, qdot = rng.normal(size=6), rng.normal(size=6)
    h = 1e-6
    X1, X0 = robot.fk(q + h * qdot), robot.fk(q - h * qdot)
    v = (X1[:3, 3] - X0[:3, 3]) / (2 * h)
    np.testing.assert_allclose(robot.jacobian(q)[:3] @ qdot, v, atol=1e-7)


def test_tool_offset_moves_the_linear_rows_only():
    robot = ur3()
    q = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    J_flange = robot.jacobian(q)
    tool = np.eye(4)
    tool[2, 3] = 0.2
    robot.tool = tool
    J_tool = robot.jacobian(q)
    np.testing.assert_allclose(J_tool[3:], J_flange[3:])
    # v_T = v_F + w x (p_T - p_F)
    r = robot.fk(q)[:3, 3] - ur3().fk(q)[:3, 3]
    np.testing.assert_allclose(J_tool[:3], J_flange[:3] + np.cross(J_flange[3:].T, r).T,
                               atol=1e-15)


def test_manipulability_is_sqrt_det_j_jt_and_vanishes_at_singularities():
    rng = np.random.default_rng(22)
    robot = ur3()
    q = random_joints(robot, rng, 50)
    J = robot.jacobian(q)
    w = manipulability(J)
    np.testing.assert_allclose(w, np.sqrt(np.linalg.det(J @ np.swapaxes(J, -1, -2))),
                               rtol=1e-9, atol=1e-15)
    # two of the UR3's singularities: wrist (q5 = 0) and elbow (q3 = 0)
    base = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.0])
    wrist, elbow = base.copy(), base.copy()
    wrist[4] = 0.0
    elbow[2] = 0.0
    Js = robot.jacobian(np.stack([base, wrist, elbow]))
    assert manipulability(Js)[0] > 1e-4
    assert np.all(manipulability(Js)[1:] < 1e-15)
    np.testing.assert_array_equal(is_singular(Js), [False, True, True])
    assert is_singular(Js[0], tol=1.0)
    with pytest.raises(ValueError, match="m <= n"):
        manipulability(np.ones((4, 3)))
    with pytest.raises(ValueError, match="shape"):
        singular_values(np.ones(3))


# -- SCARA analytic Jacobian (course notes, annex A) ----------------------------------------

def scara_coordinates(X):
    return np.stack([X[..., 0, 3], X[..., 1, 3], X[..., 2, 3],
                     np.arctan2(X[..., 1, 0], X[..., 0, 0])], axis=-1)


def test_scara_jacobian_closed_form_equals_the_derivative():
    rng = np.random.default_rng(23)
    robot = scara_rsm5()
    lo, hi = robot.limits.T
    q = rng.uniform(lo + 0.01, hi - 0.01, size=(500, 4))
    J = scara_jacobian(robot, q)
    np.testing.assert_allclose(J, xyz_yaw_jacobian(robot, q), atol=1e-15)
    h = 1e-6
    steps = h * np.eye(4)
    plus = scara_coordinates(robot.fk(q[:, None, :] + steps))
    minus = scara_coordinates(robot.fk(q[:, None, :] - steps))
    diff = plus - minus
    diff[..., 3] = np.angle(np.exp(1j * diff[..., 3]))
    np.testing.assert_allclose(J, np.swapaxes(diff / (2 * h), -1, -2), atol=1e-8)


def test_scara_determinant_and_singular_configurations():
    rng = np.random.default_rng(24)
    robot = scara_rsm5()
    lo, hi = robot.limits.T
    q = rng.uniform(lo, hi, size=(200, 4))
    det = scara_jacobian_determinant(robot, q)
    np.testing.assert_allclose(det, np.linalg.det(scara_jacobian(robot, q)), atol=1e-15)
    np.testing.assert_allclose(det, 0.350 * 0.260 * np.sin(q[:, 1]), atol=1e-15)
    # q2 = 0 (stretched) is singular whatever q1, q3, q4
    q[:, 1] = 0.0
    assert np.all(scara_is_singular(robot, q))
    assert np.all(np.abs(np.linalg.det(scara_jacobian(robot, q))) < 1e-15)
    assert not scara_is_singular(robot, [0.0, 0.3, 0.0, 0.0])


def test_scara_closed_form_refuses_other_robots():
    with pytest.raises(ValueError, match="RRPR"):
        scara_jacobian(ur3(), np.zeros(6))
    robot = scara_rsm5()
    tool = np.eye(4)
    tool[0, 3] = 0.05
    robot.tool = tool
    with pytest.raises(ValueError, match="tool"):
        scara_jacobian_determinant(robot, [0.0, 0.3, 0.0, 0.0])
    # the geometric rows still work with that tool
    assert xyz_yaw_jacobian(robot, [0.0, 0.3, 0.0, 0.0]).shape == (4, 4)
    with pytest.raises(ValueError, match="vertical"):
        xyz_yaw_jacobian(ur3(), np.zeros(6))
