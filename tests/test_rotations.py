"""Tests of dqlab.rotations: elementary rotations, Euler ZXZ, RPY, axis-angle, checks."""

import numpy as np
import pytest
import pytransform3d.rotations as pr
from hypothesis import given, settings
from hypothesis import strategies as st

from dqlab.rotations import (
    axis_angle_from_matrix,
    check_rotation_matrix,
    euler_zxz_from_matrix,
    matrix_from_axis_angle,
    matrix_from_euler_zxz,
    matrix_from_rpy,
    rodrigues,
    rot_x,
    rot_y,
    rot_z,
    rpy_from_matrix,
    skew,
)

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=40, deadline=None)


def random_rotation(rng, shape=()):
    q = rng.normal(size=tuple(shape) + (4,))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    R = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                  2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                  2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1)
    return R.reshape(tuple(shape) + (3, 3))


# --- the course notes' worked examples (chapter 1) ---------------------------------------


@pytest.mark.parametrize("theta", [0.0, np.pi / 3, np.pi / 2, 2.0, -1.0])
def test_course_notes_rotation_about_z(theta):
    m = np.array([np.sqrt(3), 0, 1])
    expected = [np.sqrt(3) * np.cos(theta), np.sqrt(3) * np.sin(theta), 1]
    np.testing.assert_allclose(rot_z(theta) @ m, expected, atol=1e-15)


def test_course_notes_rotation_by_pi_over_3():
    np.testing.assert_allclose(rot_z(np.pi / 3) @ [np.sqrt(3), 0, 1],
                               [np.sqrt(3) / 2, 1.5, 1], atol=1e-15)


def test_course_notes_moving_and_fixed_axes():
    m = np.array([np.sqrt(2), 0, 0])
    # pi/4 about z, then pi about the new y': R = Rz Ry (moving axes, post-multiply)
    np.testing.assert_allclose(rot_z(np.pi / 4) @ rot_y(np.pi) @ m, [-1, -1, 0], atol=1e-15)
    # pi/4 about z, then pi about the fixed y: R = Ry Rz (fixed axes, pre-multiply)
    np.testing.assert_allclose(rot_y(np.pi) @ rot_z(np.pi / 4) @ m, [-1, 1, 0], atol=1e-15)
    np.testing.assert_allclose(rot_z(np.pi / 4) @ m, [1, 1, 0], atol=1e-15)


def test_elementary_rotations_against_pytransform3d():
    for theta in np.linspace(-4, 4, 17):
        for basis, R in enumerate([rot_x(theta), rot_y(theta), rot_z(theta)]):
            np.testing.assert_allclose(R, pr.active_matrix_from_angle(basis, theta), atol=1e-15)
            check_rotation_matrix(R)
    assert rot_x(np.zeros((2, 3))).shape == (2, 3, 3, 3)


# --- Euler ZXZ ---------------------------------------------------------------------------


def test_euler_zxz_is_product_of_moving_rotations():
    psi, theta, phi = 0.3, 1.1, -2.0
    np.testing.assert_allclose(matrix_from_euler_zxz([psi, theta, phi]),
                               rot_z(psi) @ rot_x(theta) @ rot_z(phi), atol=1e-15)
    np.testing.assert_allclose(matrix_from_euler_zxz([psi, theta, phi]),
                               pr.matrix_from_euler([psi, theta, phi], 2, 0, 2, False),
                               atol=1e-15)


@FAST
@given(SEEDS)
def test_euler_zxz_round_trips(seed):
    rng = np.random.default_rng(seed)
    angles = np.array([rng.uniform(-np.pi, np.pi), rng.uniform(0.01, np.pi - 0.01),
                       rng.uniform(-np.pi, np.pi)])
    np.testing.assert_allclose(euler_zxz_from_matrix(matrix_from_euler_zxz(angles)), angles,
                               atol=1e-12)
    R = random_rotation(rng)
    np.testing.assert_allclose(matrix_from_euler_zxz(euler_zxz_from_matrix(R)), R, atol=1e-14)


@pytest.mark.parametrize("theta", [0.0, 1e-13, 1e-9, 1e-6, np.pi - 1e-6, np.pi - 1e-9,
                                   np.pi - 1e-13, np.pi])
def test_euler_zxz_near_singular(theta):
    rng = np.random.default_rng(21)
    for psi, phi in rng.uniform(-np.pi, np.pi, size=(20, 2)):
        R = matrix_from_euler_zxz([psi, theta, phi])
        angles = euler_zxz_from_matrix(R)
        # below singular_tol (1e-12) the singular branch drops sin(theta)
        atol = 1e-14 + (abs(np.sin(theta)) if abs(np.sin(theta)) <= 1e-12 else 0)
        np.testing.assert_allclose(matrix_from_euler_zxz(angles), R, atol=atol)
        assert 0 <= angles[1] <= np.pi


def test_euler_zxz_singular_convention():
    # nutation 0: only psi + phi is determined; phi = 0 by convention
    angles = euler_zxz_from_matrix(matrix_from_euler_zxz([0.5, 0.0, 0.25]))
    np.testing.assert_allclose(angles, [0.75, 0, 0], atol=1e-15)
    # nutation pi: only psi - phi is determined (course notes: psi + z_z phi); phi = 0
    angles = euler_zxz_from_matrix(matrix_from_euler_zxz([0.5, np.pi, 0.25]))
    np.testing.assert_allclose(angles, [0.25, np.pi, 0], atol=1e-15)


# --- roll, pitch, yaw (Craig) -------------------------------------------------------------


def test_rpy_is_product_of_fixed_rotations():
    roll, pitch, yaw = 0.3, -0.7, 2.0
    R = matrix_from_rpy([roll, pitch, yaw])
    np.testing.assert_allclose(R, rot_z(yaw) @ rot_y(pitch) @ rot_x(roll), atol=1e-15)
    # Craig's fixed x-y-z equals pytransform3d's extrinsic x-y-z Euler angles
    np.testing.assert_allclose(R, pr.matrix_from_euler([roll, pitch, yaw], 0, 1, 2, True),
                               atol=1e-15)


@FAST
@given(SEEDS)
def test_rpy_round_trips(seed):
    rng = np.random.default_rng(seed)
    rpy = np.array([rng.uniform(-np.pi, np.pi), rng.uniform(-np.pi / 2 + 0.01, np.pi / 2 - 0.01),
                    rng.uniform(-np.pi, np.pi)])
    np.testing.assert_allclose(rpy_from_matrix(matrix_from_rpy(rpy)), rpy, atol=1e-12)
    R = random_rotation(rng)
    np.testing.assert_allclose(matrix_from_rpy(rpy_from_matrix(R)), R, atol=1e-14)


@pytest.mark.parametrize("pitch", [np.pi / 2, np.pi / 2 - 1e-13, np.pi / 2 - 1e-9,
                                   np.pi / 2 - 1e-6, -np.pi / 2, -np.pi / 2 + 1e-6])
def test_rpy_near_gimbal_lock(pitch):
    rng = np.random.default_rng(22)
    for roll, yaw in rng.uniform(-np.pi, np.pi, size=(20, 2)):
        R = matrix_from_rpy([roll, pitch, yaw])
        rpy = rpy_from_matrix(R)
        atol = 1e-14 + (abs(np.cos(pitch)) if abs(np.cos(pitch)) <= 1e-12 else 0)
        np.testing.assert_allclose(matrix_from_rpy(rpy), R, atol=atol)
        assert abs(rpy[1]) <= np.pi / 2


def test_rpy_singular_convention():
    # pitch +pi/2: only yaw - roll is determined; yaw = 0 by convention (Craig)
    rpy = rpy_from_matrix(matrix_from_rpy([0.1, np.pi / 2, 0.3]))
    np.testing.assert_allclose(rpy, [-0.2, np.pi / 2, 0], atol=1e-15)
    # pitch -pi/2: only yaw + roll is determined
    rpy = rpy_from_matrix(matrix_from_rpy([0.1, -np.pi / 2, 0.3]))
    np.testing.assert_allclose(rpy, [0.4, -np.pi / 2, 0], atol=1e-15)


# --- axis-angle and Rodrigues -------------------------------------------------------------


@pytest.mark.parametrize("angle", [0.0, 1e-12, 1e-9, 1e-6, 1.0, np.pi / 2, 2.5, np.pi - 1e-6,
                                   np.pi - 1e-9, np.pi - 1e-12, np.pi])
def test_axis_angle_round_trip(angle):
    rng = np.random.default_rng(23)
    axes = rng.normal(size=(30, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    R = matrix_from_axis_angle(axes, angle)
    check_rotation_matrix(R)
    axis2, angle2 = axis_angle_from_matrix(R)
    np.testing.assert_allclose(angle2, angle, atol=2e-15)
    np.testing.assert_allclose(matrix_from_axis_angle(axis2, angle2), R, atol=1e-14)
    if angle >= 1e-6:
        sign = np.sign(np.sum(axis2 * axes, axis=-1, keepdims=True))
        if angle < np.pi:
            assert (sign > 0).all()
        np.testing.assert_allclose(axis2 * sign, axes, atol=1e-9 if angle < 1e-3 else 1e-12)


def test_axis_angle_identity_convention_and_pytransform3d():
    axis, angle = axis_angle_from_matrix(np.eye(3))
    np.testing.assert_array_equal(axis, [1, 0, 0])
    assert angle == 0
    rng = np.random.default_rng(24)
    for _ in range(50):
        axis = rng.normal(size=3)
        angle = rng.uniform(-2 * np.pi, 2 * np.pi)
        n = axis / np.linalg.norm(axis)
        np.testing.assert_allclose(matrix_from_axis_angle(axis, angle),
                                   pr.matrix_from_axis_angle(np.r_[n, angle]), atol=1e-14)


@FAST
@given(SEEDS)
def test_rodrigues_equals_matrix(seed):
    rng = np.random.default_rng(seed)
    v, axis = rng.normal(size=(2, 3))
    angle = rng.uniform(-4, 4)
    np.testing.assert_allclose(rodrigues(v, axis, angle),
                               matrix_from_axis_angle(axis, angle) @ v, atol=1e-13)


def test_rodrigues_thesis_example_and_skew():
    np.testing.assert_allclose(rodrigues([2, 1, 1], [0, 0, 1], np.pi / 2), [-1, 2, 1],
                               atol=1e-15)
    v, w = np.array([1.0, -2, 0.5]), np.array([0.3, 0.1, 2])
    np.testing.assert_allclose(skew(v) @ w, np.cross(v, w))
    np.testing.assert_allclose(skew(v).T, -skew(v))


# --- batches ----------------------------------------------------------------------------


@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_batch_equals_single(shape):
    rng = np.random.default_rng(25)
    R = random_rotation(rng, shape)
    angles = rng.uniform(-1, 1, size=shape + (3,))
    axis = rng.normal(size=shape + (3,))
    theta = rng.uniform(0, np.pi, size=shape)
    fns = {
        "zxz": lambda i: euler_zxz_from_matrix(R[i]),
        "rpy": lambda i: rpy_from_matrix(R[i]),
        "from_zxz": lambda i: matrix_from_euler_zxz(angles[i]),
        "from_rpy": lambda i: matrix_from_rpy(angles[i]),
        "axis": lambda i: axis_angle_from_matrix(R[i])[0],
        "angle": lambda i: axis_angle_from_matrix(R[i])[1],
        "from_axis_angle": lambda i: matrix_from_axis_angle(axis[i], theta[i]),
        "rodrigues": lambda i: rodrigues(angles[i], axis[i], theta[i]),
        "rot_y": lambda i: rot_y(theta[i]),
    }
    whole = (slice(None),) * len(shape) + (Ellipsis,)
    for key, f in fns.items():
        batch = f(whole)
        for idx in np.ndindex(*shape):
            np.testing.assert_allclose(batch[idx], f(idx), atol=1e-14, err_msg=key)


# --- bad input -----------------------------------------------------------------------


@pytest.mark.parametrize("call, message", [
    (lambda: check_rotation_matrix(np.eye(3) * 1.001), "R is not orthonormal"),
    (lambda: check_rotation_matrix(np.stack([np.eye(3), 2 * np.eye(3)])),
     "R is not orthonormal"),
    (lambda: check_rotation_matrix(-np.eye(3)), "R is a reflection"),
    (lambda: check_rotation_matrix(np.stack([np.eye(3), -np.eye(3)])), "R is a reflection"),
    (lambda: check_rotation_matrix(np.eye(2)), r"R must have shape \(\.\.\., 3, 3\)"),
    (lambda: check_rotation_matrix(np.full((3, 3), np.inf)), "R contains NaN"),
    (lambda: euler_zxz_from_matrix(np.ones((3, 3))), "R is not orthonormal"),
    (lambda: rpy_from_matrix(np.diag([1.0, 1, -1])), "R is a reflection"),
    (lambda: axis_angle_from_matrix(np.zeros((3, 3))), "R is not orthonormal"),
    (lambda: matrix_from_axis_angle([0, 0, 0], 1.0), "axis is the zero vector"),
    (lambda: matrix_from_rpy([0, 1]), r"rpy must have shape \(\.\.\., 3\)"),
    (lambda: matrix_from_euler_zxz([0, np.nan, 1]), "angles contains NaN"),
    (lambda: rodrigues([1, 0, 0], [0, 0, 0], 1.0), "axis is the zero vector"),
    (lambda: rot_x(np.nan), "theta contains NaN"),
])
def test_bad_input_raises_named_value_error(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_tolerance_is_a_keyword():
    R = rot_z(0.3) + 1e-7
    with pytest.raises(ValueError):
        check_rotation_matrix(R)
    check_rotation_matrix(R, tol=1e-5)
    euler_zxz_from_matrix(R, tol=1e-5)
