"""Tests for the rates of rotations and rigid motions and for the analytic Jacobians:
quaternion rate and its inverse, dual-quaternion twist, the RPY and quaternion rate matrices,
all against central differences and, where one exists, an independent library."""

import numpy as np
import pytest
from _draws import random_unit_quaternions

from dqlab.dualquat import (
    dual_quaternion_from_rotation_translation,
    dual_quaternion_from_transform,
    dual_quaternion_rate,
    twist_from_dual_quaternion_rate,
)
from dqlab.jacobian import (
    analytic_jacobian,
    quaternion_rate_matrix,
    rpy_rate_matrix,
)
from dqlab.models import six_r, ur3, ur3_mdh
from dqlab.quaternion import (
    angular_velocity_from_quaternion_rate,
    quaternion_exp,
    quaternion_from_matrix,
    quaternion_product,
    quaternion_rate,
)
from dqlab.rotations import axis_angle_from_matrix, matrix_from_rpy, rpy_from_matrix

H = 1e-6



def pure(v):
    v = np.asarray(v, dtype=float)
    return np.concatenate([np.zeros(v.shape[:-1] + (1,)), v], axis=-1)


# -- quaternion rate ------------------------------------------------------------------------


@pytest.mark.parametrize("frame", ["world", "body"])
def test_quaternion_rate_is_the_derivative_of_a_constant_rotation_rate(frame):
    rng = np.random.default_rng(1)
    q0 = random_unit_quaternions(rng, 50)
    omega = rng.normal(size=(50, 3))

    def q_at(t):
        step = quaternion_exp(pure(0.5 * t * omega))
        return (quaternion_product(step, q0) if frame == "world"
                else quaternion_product(q0, step))

    finite = (q_at(H) - q_at(-H)) / (2 * H)
    assert np.allclose(quaternion_rate(q0, omega, frame=frame), finite, atol=1e-8)


def test_quaternion_rate_against_scipy():
    Rotation = pytest.importorskip("scipy.spatial.transform").Rotation
    rng = np.random.default_rng(2)
    q0 = random_unit_quaternions(rng, 30)
    omega = rng.normal(size=(30, 3))
    R0 = Rotation.from_quat(q0[:, [1, 2, 3, 0]])          # scipy is (x, y, z, w)

    def q_at(t):                                           # world-frame rotation rate
        xyzw = (Rotation.from_rotvec(t * omega) * R0).as_quat()
        wxyz = xyzw[:, [3, 0, 1, 2]]
        return wxyz * np.sign(np.sum(wxyz * q0, axis=-1))[:, None]   # q0's sign

    finite = (q_at(H) - q_at(-H)) / (2 * H)
    assert np.allclose(quaternion_rate(q0, omega), finite, atol=1e-8)


@pytest.mark.parametrize("frame", ["world", "body"])
def test_angular_velocity_inverts_the_quaternion_rate(frame):
    rng = np.random.default_rng(3)
    q = random_unit_quaternions(rng, 40)
    omega = rng.normal(size=(40, 3))
    q_dot = quaternion_rate(q, omega, frame=frame)
    assert np.allclose(np.sum(q * q_dot, axis=-1), 0.0, atol=1e-15)   # tangent to |q| = 1
    assert np.allclose(angular_velocity_from_quaternion_rate(q, q_dot, frame=frame), omega,
                       atol=1e-14)


def test_world_and_body_rates_are_related_by_the_rotation():
    rng = np.random.default_rng(4)
    q = random_unit_quaternions(rng, 20)
    omega_b = rng.normal(size=(20, 3))
    q_dot = quaternion_rate(q, omega_b, frame="body")
    omega = angular_velocity_from_quaternion_rate(q, q_dot)
    from dqlab.quaternion import rotate_vector

    assert np.allclose(omega, rotate_vector(q, omega_b), atol=1e-14)


@pytest.mark.parametrize("lead", [(), (3,), (2, 3)])
def test_rates_batch_equals_single(lead):
    rng = np.random.default_rng(5)
    q = random_unit_quaternions(rng, int(np.prod(lead, dtype=int))).reshape(lead + (4,))
    omega = rng.normal(size=lead + (3,))
    batch = quaternion_rate(q, omega)
    assert batch.shape == lead + (4,)
    for index in np.ndindex(*lead):
        assert np.array_equal(batch[index], quaternion_rate(q[index], omega[index]))
    Q = dual_quaternion_from_rotation_translation(q, rng.normal(size=lead + (3,)))
    twist = rng.normal(size=lead + (6,))
    Q_dot = dual_quaternion_rate(Q, twist)
    assert Q_dot.shape == lead + (8,)
    for index in np.ndindex(*lead):
        assert np.array_equal(Q_dot[index], dual_quaternion_rate(Q[index], twist[index]))


def test_quaternion_rate_rejects_bad_input():
    with pytest.raises(ValueError, match="q must be a unit quaternion"):
        quaternion_rate([1.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="omega"):
        quaternion_rate([1.0, 0.0, 0.0, 0.0], [0.0, 1.0])
    with pytest.raises(ValueError, match="omega contains NaN"):
        quaternion_rate([1.0, 0.0, 0.0, 0.0], [0.0, np.nan, 1.0])
    with pytest.raises(ValueError, match="frame"):
        quaternion_rate([1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0], frame="tool")
    with pytest.raises(ValueError, match="q_dot"):
        angular_velocity_from_quaternion_rate([1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    with pytest.raises(ValueError, match="frame"):
        angular_velocity_from_quaternion_rate([1, 0, 0, 0], [0, 1, 0, 0], frame="x")


# -- dual-quaternion twist ------------------------------------------------------------------


def test_dual_quaternion_rate_is_the_derivative_of_rotation_and_translation():
    rng = np.random.default_rng(6)
    q0 = random_unit_quaternions(rng, 40)
    t0, t_dot, omega = rng.normal(size=(3, 40, 3))

    def Q_at(s):
        q = quaternion_product(quaternion_exp(pure(0.5 * s * omega)), q0)
        return dual_quaternion_from_rotation_translation(q, t0 + s * t_dot)

    finite = (Q_at(H) - Q_at(-H)) / (2 * H)
    v_origin = t_dot - np.cross(omega, t0)       # the body point at the world origin
    twist = np.concatenate([v_origin, omega], axis=-1)
    assert np.allclose(dual_quaternion_rate(Q_at(0.0), twist), finite, atol=1e-8)
    assert np.allclose(twist_from_dual_quaternion_rate(Q_at(0.0), finite), twist, atol=1e-8)


def test_dual_quaternion_rate_against_pytransform3d_exponential():
    pt = pytest.importorskip("pytransform3d.transformations")
    rng = np.random.default_rng(7)
    for _ in range(20):
        X0 = pt.random_transform(rng)
        omega, v = rng.normal(size=(2, 3))

        def Q_at(s, X0=X0, omega=omega, v=v):    # pytransform3d: (omega, v), spatial
            X = pt.transform_from_exponential_coordinates(np.r_[omega, v] * s) @ X0
            return dual_quaternion_from_transform(X)

        Q0 = Q_at(0.0)
        plus, minus = Q_at(H), Q_at(-H)
        plus *= np.sign(np.dot(plus, Q0))                  # same sign as Q0
        minus *= np.sign(np.dot(minus, Q0))
        finite = (plus - minus) / (2 * H)
        assert np.allclose(dual_quaternion_rate(Q0, np.r_[v, omega]), finite, atol=1e-8)


def test_twist_of_a_robot_flange_is_the_geometric_jacobian_times_the_joint_speed():
    rng = np.random.default_rng(8)
    robot = ur3()
    q, q_dot = rng.uniform(-np.pi, np.pi, 6), rng.normal(size=6)
    Q_plus, Q_minus = robot.fk_dq(q + H * q_dot), robot.fk_dq(q - H * q_dot)
    Q = robot.fk_dq(q)
    Q_plus *= np.sign(np.dot(Q_plus, Q))
    Q_minus *= np.sign(np.dot(Q_minus, Q))
    twist = twist_from_dual_quaternion_rate(Q, (Q_plus - Q_minus) / (2 * H))
    v_flange, omega = np.split(robot.jacobian(q) @ q_dot, 2)
    p = robot.fk(q)[:3, 3]
    assert np.allclose(twist[3:], omega, atol=1e-8)
    assert np.allclose(twist[:3] + np.cross(omega, p), v_flange, atol=1e-8)


def test_dual_quaternion_rate_rejects_bad_input():
    with pytest.raises(ValueError, match="Q"):
        dual_quaternion_rate([2, 0, 0, 0, 0, 0, 0, 0], np.zeros(6))
    with pytest.raises(ValueError, match="twist"):
        dual_quaternion_rate([1, 0, 0, 0, 0, 0, 0, 0], np.zeros(3))
    with pytest.raises(ValueError, match="twist contains NaN"):
        dual_quaternion_rate([1, 0, 0, 0, 0, 0, 0, 0], [0, 0, 0, np.inf, 0, 0])
    with pytest.raises(ValueError, match="Q_dot"):
        twist_from_dual_quaternion_rate([1, 0, 0, 0, 0, 0, 0, 0], np.zeros(4))


# -- rate matrices and analytic Jacobians --------------------------------------------------


def test_rpy_rate_matrix_against_finite_differences():
    rng = np.random.default_rng(9)
    rpy = rng.uniform(-1.2, 1.2, (50, 3))
    rpy_dot = rng.normal(size=(50, 3))
    R_step = (matrix_from_rpy(rpy + H * rpy_dot)
              @ np.swapaxes(matrix_from_rpy(rpy - H * rpy_dot), -1, -2))
    axis, angle = axis_angle_from_matrix(R_step)
    omega = axis * angle[:, None] / (2 * H)
    assert np.allclose((rpy_rate_matrix(rpy) @ rpy_dot[..., None])[..., 0], omega, atol=1e-8)
    assert np.allclose(np.linalg.det(rpy_rate_matrix(rpy)), np.cos(rpy[:, 1]), atol=1e-15)


def test_quaternion_rate_matrix_is_the_quaternion_rate():
    rng = np.random.default_rng(10)
    q = random_unit_quaternions(rng, 30)
    omega = rng.normal(size=(30, 3))
    G = quaternion_rate_matrix(q)
    assert G.shape == (30, 4, 3)
    assert np.allclose((G @ omega[..., None])[..., 0], quaternion_rate(q, omega), atol=1e-15)
    assert np.allclose(np.swapaxes(G, -1, -2) @ G, np.eye(3) / 4, atol=1e-15)


@pytest.mark.parametrize("make_robot", [ur3, ur3_mdh, six_r])
def test_analytic_jacobians_against_finite_differences(make_robot):
    robot = make_robot()
    rng = np.random.default_rng(11)
    for q in rng.uniform(-2.0, 2.0, (10, len(robot.links))):
        steps = H * np.eye(len(q))
        X_plus, X_minus = robot.fk(q + steps), robot.fk(q - steps)
        rpy_plus = rpy_from_matrix(X_plus[:, :3, :3])
        rpy_minus = rpy_from_matrix(X_minus[:, :3, :3])
        d_rpy = (rpy_plus - rpy_minus + np.pi) % (2 * np.pi) - np.pi
        J_rpy = analytic_jacobian(robot, q)
        assert np.allclose(J_rpy[3:], d_rpy.T / (2 * H), atol=1e-6)
        assert np.allclose(J_rpy[:3], (X_plus - X_minus)[:, :3, 3].T / (2 * H), atol=1e-7)
        r = quaternion_from_matrix(robot.fk(q)[:3, :3])
        r_plus = quaternion_from_matrix(X_plus[:, :3, :3])
        r_minus = quaternion_from_matrix(X_minus[:, :3, :3])
        r_plus *= np.sign(r_plus @ r)[:, None]
        r_minus *= np.sign(r_minus @ r)[:, None]
        J_quat = analytic_jacobian(robot, q, orientation="quaternion")
        assert J_quat.shape == (7, len(q))
        assert np.allclose(J_quat[3:], (r_plus - r_minus).T / (2 * H), atol=1e-7)
        # back to the geometric Jacobian: omega = E J_rpy = 4 G^T J_quat
        J = robot.jacobian(q)
        rpy = rpy_from_matrix(robot.fk(q)[:3, :3])
        assert np.allclose(rpy_rate_matrix(rpy) @ J_rpy[3:], J[3:], atol=1e-12)
        assert np.allclose(4 * quaternion_rate_matrix(r).T @ J_quat[3:], J[3:], atol=1e-12)


def test_analytic_jacobian_batch_and_errors():
    robot = ur3()
    rng = np.random.default_rng(12)
    q = rng.uniform(-2.0, 2.0, (2, 3, 6))
    batch = analytic_jacobian(robot, q)
    assert batch.shape == (2, 3, 6, 6)
    assert np.allclose(batch[1, 2], analytic_jacobian(robot, q[1, 2]), atol=1e-15)
    # a configuration whose flange has pitch pi/2 (its x axis straight down), found by IK
    from dqlab import ik

    X_lock = np.eye(4)
    X_lock[:3, :3] = matrix_from_rpy([0.2, np.pi / 2, -0.4])
    X_lock[:3, 3] = [0.25, 0.1, 0.2]
    solutions = ik.ur(robot, X_lock)
    q_lock = solutions.solutions[solutions.valid][0]
    assert abs(np.cos(rpy_from_matrix(robot.fk(q_lock)[:3, :3])[1])) < 1e-9
    with pytest.raises(ValueError, match="gimbal lock"):
        analytic_jacobian(robot, q_lock)
    assert analytic_jacobian(robot, q_lock, orientation="quaternion").shape == (7, 6)
    assert np.all(np.isfinite(analytic_jacobian(robot, q_lock, orientation="quaternion")))
    with pytest.raises(ValueError, match="orientation"):
        analytic_jacobian(robot, q_lock, orientation="euler")
