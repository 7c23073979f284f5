"""Tests of dqlab.quaternion: algebra, conversions, interpolation, errors, the class."""

import numpy as np
import pytest
from _draws import random_unit_quaternions
from hypothesis import given, settings
from hypothesis import strategies as st
from pyquaternion import Quaternion as PyQuaternion

import dqlab
from dqlab.quaternion import (
    Quaternion,
    axis_angle_from_quaternion,
    check_unit_quaternion,
    matrix_from_quaternion,
    pyquaternion_from_quaternion,
    quaternion_conjugate,
    quaternion_distance,
    quaternion_exp,
    quaternion_from_axis_angle,
    quaternion_from_matrix,
    quaternion_from_pyquaternion,
    quaternion_identity,
    quaternion_inverse,
    quaternion_log,
    quaternion_norm,
    quaternion_normalize,
    quaternion_power,
    quaternion_product,
    rotate_vector,
    slerp,
)
from dqlab.testing import assert_quaternion_equal

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=40, deadline=None)



# --- the sources' worked examples ------------------------------------------------------


def test_thesis_example_rotate_211_by_90_about_z():
    q = quaternion_from_axis_angle([0, 0, 1], np.pi / 2)
    np.testing.assert_allclose(rotate_vector(q, [2, 1, 1]), [-1, 2, 1], atol=1e-15)
    # the same with the explicit sandwich q p q*
    p = np.array([0.0, 2, 1, 1])
    qpq = quaternion_product(quaternion_product(q, p), quaternion_conjugate(q))
    np.testing.assert_allclose(qpq, [0, -1, 2, 1], atol=1e-15)


def test_hamilton_table():
    one, i, j, k = np.eye(4)
    for a, b, c in [(i, j, k), (j, k, i), (k, i, j)]:
        np.testing.assert_array_equal(quaternion_product(a, b), c)
        np.testing.assert_array_equal(quaternion_product(b, a), -c)
    for u in (i, j, k):
        np.testing.assert_array_equal(quaternion_product(u, u), -one)
    np.testing.assert_array_equal(quaternion_product(quaternion_product(i, j), k), -one)


def test_course_notes_compositions_with_quaternions():
    qz = quaternion_from_axis_angle([0, 0, 1], np.pi / 4)
    qy = quaternion_from_axis_angle([0, 1, 0], np.pi)
    m = [np.sqrt(2), 0, 0]
    # about moving axes: first z, then the new y -> q = qz qy
    np.testing.assert_allclose(rotate_vector(quaternion_product(qz, qy), m), [-1, -1, 0],
                               atol=1e-15)
    # about fixed axes: first z, then the fixed y -> q = qy qz
    np.testing.assert_allclose(rotate_vector(quaternion_product(qy, qz), m), [-1, 1, 0],
                               atol=1e-15)


# --- algebraic properties --------------------------------------------------------------


@FAST
@given(SEEDS)
def test_associativity_and_norm(seed):
    rng = np.random.default_rng(seed)
    a, b, c = rng.normal(size=(3, 4))
    ab_c = quaternion_product(quaternion_product(a, b), c)
    a_bc = quaternion_product(a, quaternion_product(b, c))
    np.testing.assert_allclose(ab_c, a_bc, atol=1e-12 * (1 + np.abs(ab_c).max()))
    np.testing.assert_allclose(quaternion_norm(quaternion_product(a, b)),
                               quaternion_norm(a) * quaternion_norm(b), rtol=1e-13)
    # (ab)* = b* a*
    np.testing.assert_allclose(
        quaternion_conjugate(quaternion_product(a, b)),
        quaternion_product(quaternion_conjugate(b), quaternion_conjugate(a)), atol=1e-13)


@FAST
@given(SEEDS)
def test_inverse_and_normalize(seed):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=4) * rng.uniform(0.1, 10)
    np.testing.assert_allclose(quaternion_product(q, quaternion_inverse(q)), [1, 0, 0, 0],
                               atol=1e-14)
    np.testing.assert_allclose(quaternion_product(quaternion_inverse(q), q), [1, 0, 0, 0],
                               atol=1e-14)
    u = quaternion_normalize(q)
    assert abs(quaternion_norm(u) - 1) < 1e-15
    np.testing.assert_allclose(quaternion_inverse(u), quaternion_conjugate(u), atol=1e-15)


@FAST
@given(SEEDS)
def test_q_and_minus_q_same_rotation(seed):
    rng = np.random.default_rng(seed)
    q = random_unit_quaternions(rng)
    v = rng.normal(size=3)
    np.testing.assert_allclose(rotate_vector(q, v), rotate_vector(-q, v), atol=1e-14)
    np.testing.assert_allclose(matrix_from_quaternion(q), matrix_from_quaternion(-q),
                               atol=1e-15)
    np.testing.assert_allclose(quaternion_from_matrix(matrix_from_quaternion(-q)),
                               q * np.sign(q[0]), atol=1e-14)


@FAST
@given(SEEDS)
def test_rotation_is_sandwich_and_matrix(seed):
    rng = np.random.default_rng(seed)
    q = random_unit_quaternions(rng)
    v = rng.normal(size=3)
    sandwich = quaternion_product(quaternion_product(q, np.r_[0, v]), quaternion_conjugate(q))
    np.testing.assert_allclose(rotate_vector(q, v), sandwich[1:], atol=1e-14)
    np.testing.assert_allclose(matrix_from_quaternion(q) @ v, sandwich[1:], atol=1e-14)
    # composition: rotating by ab is rotating by b, then by a
    p = random_unit_quaternions(rng)
    np.testing.assert_allclose(rotate_vector(quaternion_product(q, p), v),
                               rotate_vector(q, rotate_vector(p, v)), atol=1e-13)


# --- conversions round trips -----------------------------------------------------------

CRITICAL_ANGLES = [0.0, 1e-12, 1e-9, 1e-6, 0.5, np.pi / 2, np.pi - 1e-6, np.pi - 1e-9,
                   np.pi - 1e-12, np.pi]


@pytest.mark.parametrize("angle", CRITICAL_ANGLES)
def test_matrix_round_trip_near_0_and_pi(angle):
    rng = np.random.default_rng(7)
    for axis in list(np.eye(3)) + list(rng.normal(size=(20, 3))):
        axis = axis / np.linalg.norm(axis)
        q = quaternion_from_axis_angle(axis, angle)
        R = matrix_from_quaternion(q)
        q2 = quaternion_from_matrix(R)
        assert q2[0] >= 0
        assert_quaternion_equal(q2, q, atol=2e-15 * 4)
        np.testing.assert_allclose(matrix_from_quaternion(q2), R, atol=1e-15 * 4)
        axis2, angle2 = axis_angle_from_quaternion(q2)
        assert abs(angle2 - angle) < 1e-14
        if angle > 1e-6:
            s = 1.0 if angle < np.pi else np.sign(axis2 @ axis)  # at pi, +-axis are equal
            np.testing.assert_allclose(axis2, s * axis, atol=1e-9)


def test_matrix_to_quaternion_exact_at_180_degrees():
    # half turns about random axes: w = 0, and the branch selection keeps full accuracy
    rng = np.random.default_rng(3)
    n = rng.normal(size=(200, 3))
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    R = 2 * n[:, :, None] * n[:, None, :] - np.eye(3)
    q = quaternion_from_matrix(R)
    assert np.abs(q[:, 0]).max() < 1e-15
    assert_quaternion_equal(q, np.concatenate([np.zeros((200, 1)), n], axis=1), atol=1e-15)


def test_matrix_to_quaternion_uses_active_convention():
    # the thesis prints the passive branches, which give the conjugate; we are active
    R = dqlab.rot_z(0.3)
    q = quaternion_from_matrix(R)
    np.testing.assert_allclose(q, [np.cos(0.15), 0, 0, np.sin(0.15)], atol=1e-16)


@FAST
@given(SEEDS)
def test_axis_angle_round_trip(seed):
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=3)
    angle = rng.uniform(0, np.pi)
    q = quaternion_from_axis_angle(axis, angle)
    a2, t2 = axis_angle_from_quaternion(q)
    np.testing.assert_allclose(a2, axis / np.linalg.norm(axis), atol=1e-12)
    assert abs(t2 - angle) < 1e-13
    a3, t3 = axis_angle_from_quaternion(-q)
    np.testing.assert_allclose(a3, a2, atol=1e-15)
    assert abs(t3 - t2) < 1e-15


def test_axis_angle_identity_convention():
    axis, angle = axis_angle_from_quaternion([1, 0, 0, 0])
    np.testing.assert_array_equal(axis, [1, 0, 0])
    assert angle == 0


@FAST
@given(SEEDS)
def test_exp_log_power(seed):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=4)
    np.testing.assert_allclose(quaternion_exp(quaternion_log(q)), q, atol=1e-13)
    u = random_unit_quaternions(rng)
    np.testing.assert_allclose(quaternion_power(u, 2), quaternion_product(u, u), atol=1e-13)
    h = quaternion_power(u, 0.5)
    np.testing.assert_allclose(quaternion_product(h, h), u, atol=1e-13)
    np.testing.assert_allclose(quaternion_power(u, 0), [1, 0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(quaternion_power(u, 1), u, atol=1e-14)
    np.testing.assert_allclose(quaternion_power(u, -1), quaternion_conjugate(u), atol=1e-14)


def test_log_of_minus_one_and_exp_of_zero():
    np.testing.assert_allclose(quaternion_log([-1, 0, 0, 0]), [0, np.pi, 0, 0])
    np.testing.assert_array_equal(quaternion_exp([0, 0, 0, 0]), [1, 0, 0, 0])


@FAST
@given(SEEDS)
def test_slerp_endpoints_unit_and_shortest(seed):
    rng = np.random.default_rng(seed)
    q0, q1 = random_unit_quaternions(rng, (2,))
    t = np.linspace(0, 1, 11)
    path = slerp(q0, q1, t)
    np.testing.assert_allclose(np.linalg.norm(path, axis=-1), 1, atol=1e-14)
    np.testing.assert_allclose(path[0], q0, atol=1e-14)
    assert_quaternion_equal(path[-1], q1, atol=1e-14)
    # q1 and -q1 give the same path
    np.testing.assert_allclose(slerp(q0, -q1, t), path, atol=1e-14)
    # constant angular speed along the shortest arc
    total = quaternion_distance(q0, q1)
    assert total <= np.pi + 1e-15
    steps = quaternion_distance(path[:-1], path[1:])
    np.testing.assert_allclose(steps, total / 10, atol=1e-12)
    # slerp is q0 (q0* q1)^t
    d = quaternion_product(quaternion_conjugate(q0), q1)
    d = d * np.sign(d[0])
    np.testing.assert_allclose(
        path, quaternion_product(q0, quaternion_power(d, t[:, None][..., 0])), atol=1e-12)


def test_slerp_equal_inputs():
    q = random_unit_quaternions(np.random.default_rng(1))
    np.testing.assert_allclose(slerp(q, q, 0.3), q, atol=1e-15)
    np.testing.assert_allclose(slerp(q, -q, 0.3), q, atol=1e-15)


def test_distance():
    a = quaternion_from_axis_angle([0, 1, 0], 0.25)
    b = quaternion_from_axis_angle([0, 1, 0], 1.0)
    assert abs(quaternion_distance(a, b) - 0.75) < 1e-14
    assert abs(quaternion_distance(a, -b) - 0.75) < 1e-14
    assert quaternion_distance(a, a) == 0
    c = quaternion_from_axis_angle([0, 1, 0], np.pi)
    assert abs(quaternion_distance([1, 0, 0, 0], c) - np.pi) < 1e-15
    tiny = quaternion_from_axis_angle([1, 0, 0], 1e-10)
    assert abs(quaternion_distance([1, 0, 0, 0], tiny) - 1e-10) < 1e-20


# --- cross-checks against pyquaternion --------------------------------------------------


def test_against_pyquaternion():
    rng = np.random.default_rng(2024)
    for _ in range(200):
        a, b = rng.normal(size=(2, 4))
        v = rng.normal(size=3)
        np.testing.assert_allclose(quaternion_product(a, b),
                                   (PyQuaternion(a) * PyQuaternion(b)).elements, atol=1e-12)
        u = a / np.linalg.norm(a)
        pu = PyQuaternion(u)
        np.testing.assert_allclose(rotate_vector(u, v), pu.rotate(v), atol=1e-12)
        np.testing.assert_allclose(matrix_from_quaternion(u), pu.rotation_matrix, atol=1e-12)
        q = quaternion_from_matrix(pu.rotation_matrix)
        assert_quaternion_equal(q, PyQuaternion(matrix=pu.rotation_matrix).elements)
        assert_quaternion_equal(q, u)
        np.testing.assert_allclose(quaternion_inverse(a), PyQuaternion(a).inverse.elements,
                                   atol=1e-12)
        np.testing.assert_allclose(quaternion_exp(a), PyQuaternion.exp(PyQuaternion(a)).elements,
                                   rtol=1e-12, atol=1e-12)
        w = b / np.linalg.norm(b)
        t = rng.uniform()
        assert_quaternion_equal(slerp(u, w, t),
                                PyQuaternion.slerp(pu, PyQuaternion(w), t).elements)
        axis, angle = axis_angle_from_quaternion(u)
        pq = PyQuaternion(axis=axis, angle=angle)
        assert_quaternion_equal(pq.elements, u)


def test_pyquaternion_interop():
    q = np.array([0.5, -0.5, 0.5, 0.5])
    pq = pyquaternion_from_quaternion(q)
    assert isinstance(pq, PyQuaternion)
    np.testing.assert_array_equal(pq.elements, q)
    np.testing.assert_array_equal(quaternion_from_pyquaternion(pq), q)
    batch = pyquaternion_from_quaternion(np.stack([q, -q]))
    np.testing.assert_array_equal(quaternion_from_pyquaternion(batch), np.stack([q, -q]))


# --- batches: 0, 1, 2 leading dimensions ------------------------------------------------


@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_batch_equals_single(shape):
    rng = np.random.default_rng(11)
    a = rng.normal(size=shape + (4,))
    b = rng.normal(size=shape + (4,))
    u = random_unit_quaternions(rng, shape)
    w = random_unit_quaternions(rng, shape)
    v = rng.normal(size=shape + (3,))
    t = rng.uniform(size=shape)
    R = matrix_from_quaternion(u)
    assert R.shape == shape + (3, 3)
    batch = {
        "product": quaternion_product(a, b),
        "rotate": rotate_vector(u, v),
        "from_matrix": quaternion_from_matrix(R),
        "slerp": slerp(u, w, t),
        "log": quaternion_log(a),
        "power": quaternion_power(u, t),
        "axis": axis_angle_from_quaternion(u)[0],
        "distance": quaternion_distance(u, w),
    }
    for idx in np.ndindex(*shape):
        single = {
            "product": quaternion_product(a[idx], b[idx]),
            "rotate": rotate_vector(u[idx], v[idx]),
            "from_matrix": quaternion_from_matrix(R[idx]),
            "slerp": slerp(u[idx], w[idx], t[idx]),
            "log": quaternion_log(a[idx]),
            "power": quaternion_power(u[idx], t[idx]),
            "axis": axis_angle_from_quaternion(u[idx])[0],
            "distance": quaternion_distance(u[idx], w[idx]),
        }
        for key, value in single.items():
            np.testing.assert_allclose(batch[key][idx], value, atol=1e-14, err_msg=key)


def test_broadcasting_single_with_batch():
    rng = np.random.default_rng(4)
    q = random_unit_quaternions(rng)
    v = rng.normal(size=(6, 3))
    out = rotate_vector(q, v)
    assert out.shape == (6, 3)
    np.testing.assert_allclose(out, v @ matrix_from_quaternion(q).T, atol=1e-14)
    qs = random_unit_quaternions(rng, (6,))
    np.testing.assert_allclose(quaternion_product(q, qs)[2], quaternion_product(q, qs[2]))
    np.testing.assert_allclose(rotate_vector(qs, [1, 0, 0])[3], rotate_vector(qs[3], [1, 0, 0]))
    assert quaternion_identity((2, 3)).shape == (2, 3, 4)


def test_outputs_are_new_float_arrays():
    q = np.array([1, 0, 0, 0])  # integers
    out = quaternion_product(q, q)
    assert out.dtype == np.float64
    a = np.array([1.0, 2.0, 3.0, 4.0])
    c = quaternion_conjugate(a)
    c[0] = 99
    assert a[0] == 1.0


# --- bad input -----------------------------------------------------------------------


@pytest.mark.parametrize("call, message", [
    (lambda: quaternion_product([1, 0, 0], [1, 0, 0, 0]), r"a must have shape \(\.\.\., 4\)"),
    (lambda: quaternion_product([1, 0, 0, 0], [np.nan, 0, 0, 0]), "b contains NaN"),
    (lambda: quaternion_product(np.ones((3, 4)), np.full((3, 4), np.inf)), "b contains NaN"),
    (lambda: quaternion_product("abc", [1, 0, 0, 0]), "a must hold numbers"),
    (lambda: rotate_vector([0, 0, 0, 0], [1, 0, 0]), "q is the zero quaternion"),
    (lambda: rotate_vector([1, 1, 0, 0], [1, 0, 0]), "q must be a unit quaternion"),
    (lambda: rotate_vector(np.array([[1.0, 0, 0, 0], [2, 0, 0, 0]]), [1, 0, 0]),
     "q must be a unit quaternion .* got norm 2"),
    (lambda: rotate_vector([1, 0, 0, 0], [1, 0]), r"v must have shape \(\.\.\., 3\)"),
    (lambda: rotate_vector(np.array([1.0, 0, 0, 0]), np.array([np.inf, 0, 0])),
     "v contains NaN"),
    (lambda: rotate_vector(np.array([np.nan, 0, 0, 0]), np.array([1.0, 0, 0])),
     "q contains NaN"),
    (lambda: quaternion_inverse([0, 0, 0, 0]), "q is the zero quaternion"),
    (lambda: quaternion_normalize(np.zeros((2, 4))), "q is the zero quaternion"),
    (lambda: quaternion_normalize([np.nan, 1, 0, 0]), "q contains NaN"),
    (lambda: quaternion_log([0, 0, 0, 0]), "q is the zero quaternion"),
    (lambda: quaternion_from_axis_angle([0, 0, 0], 1.0), "axis is the zero vector"),
    (lambda: quaternion_from_matrix(np.ones((3, 3))), "R is not orthonormal"),
    (lambda: quaternion_from_matrix(np.diag([1.0, -1, 1])), "R is a reflection"),
    (lambda: quaternion_from_matrix(np.eye(4)), r"R must have shape \(\.\.\., 3, 3\)"),
    (lambda: quaternion_from_matrix([[np.nan] * 3] * 3), "R contains NaN"),
    (lambda: matrix_from_quaternion([2, 0, 0, 0]), "q must be a unit quaternion"),
    (lambda: slerp([1, 0, 0, 0], [0, 0, 0, 0], 0.5), "q1 is the zero quaternion"),
    (lambda: quaternion_distance([1, 0, 0, 0.1], [1, 0, 0, 0]), "q0 must be a unit"),
    (lambda: check_unit_quaternion([1, 0, 0, 1e-4]), "q must be a unit quaternion"),
])
def test_bad_input_raises_named_value_error(call, message):
    with pytest.raises((ValueError, TypeError), match=message):
        call()


def test_tolerances_are_keywords():
    q = np.array([1.0 + 1e-7, 0, 0, 0])
    with pytest.raises(ValueError):
        rotate_vector(q, [1, 0, 0])
    np.testing.assert_allclose(rotate_vector(q, [1, 0, 0], tol=1e-6), [1, 0, 0], atol=1e-6)
    check_unit_quaternion(q, tol=1e-6)


# --- the class wrapper ------------------------------------------------------------------


def test_quaternion_class_wraps_array_functions():
    rng = np.random.default_rng(5)
    a, b = random_unit_quaternions(rng, (2,))
    A, B = Quaternion(a), Quaternion(b)
    np.testing.assert_array_equal((A * B).array, quaternion_product(a, b))
    np.testing.assert_array_equal(A.conjugate().array, quaternion_conjugate(a))
    np.testing.assert_array_equal(A.inverse().array, quaternion_inverse(a))
    np.testing.assert_array_equal(A.matrix(), matrix_from_quaternion(a))
    np.testing.assert_array_equal(A.apply([1, 2, 3]), rotate_vector(a, [1, 2, 3]))
    np.testing.assert_allclose((A * A.inverse()).array, [1, 0, 0, 0], atol=1e-15)
    assert abs(A.norm() - 1) < 1e-15
    assert isinstance(A.norm(), float)
    np.testing.assert_array_equal((2 * A).array, 2 * a)
    np.testing.assert_array_equal((A * 2).array, 2 * a)
    np.testing.assert_array_equal((A + B).array, a + b)
    np.testing.assert_array_equal((A - B).array, a - b)
    np.testing.assert_array_equal((-A).array, -a)
    np.testing.assert_allclose((A ** 2).array, (A * A).array, atol=1e-14)
    np.testing.assert_array_equal(A.slerp(B, 0.5).array, slerp(a, b, 0.5))
    assert A.distance(B) == quaternion_distance(a, b)
    np.testing.assert_array_equal(Quaternion.from_matrix(A.matrix()).array,
                                  quaternion_from_matrix(A.matrix()))
    Z = Quaternion.from_axis_angle([0, 0, 1], np.pi / 2)
    np.testing.assert_allclose(Z.apply([2, 1, 1]), [-1, 2, 1], atol=1e-15)
    assert abs(Z.angle() - np.pi / 2) < 1e-15
    assert Quaternion(A) == A
    np.testing.assert_array_equal(np.asarray(A), a)
    assert isinstance(A.to_pyquaternion(), PyQuaternion)
    np.testing.assert_array_equal(Quaternion.from_pyquaternion(PyQuaternion(a)).array, a)
    assert Quaternion.identity() == Quaternion([1, 0, 0, 0])


def test_quaternion_class_batch_and_repr():
    Q = Quaternion(random_unit_quaternions(np.random.default_rng(6), (3,)))
    assert Q.shape == (3,)
    assert len(Q) == 3
    assert Q[1].shape == ()
    assert Q.apply([1, 0, 0]).shape == (3, 3)
    assert (Q * Q[0]).shape == (3,)
    assert repr(Quaternion([1, 0, 0, 0])) == "Quaternion([1., 0., 0., 0.])"
    assert repr(Q).startswith("Quaternion([[")
    assert str(Quaternion([1, -2, 3, 0.5])) == "1 -2i +3j +0.5k"
    with pytest.raises(ValueError, match="q must have shape"):
        Quaternion([1, 2, 3])
    with pytest.raises(TypeError):
        len(Quaternion([1, 0, 0, 0]))


def test_top_level_names():
    for name in ["quaternion_product", "quaternion_from_matrix", "matrix_from_quaternion",
                 "dual_quaternion_product", "dual_quaternion_from_transform",
                 "transform_from_dual_quaternion", "Quaternion", "DualQuaternion", "slerp",
                 "sclerp", "rot_z", "transform_from"]:
        assert callable(getattr(dqlab, name))
        assert name in dqlab.__all__
    # the rest of the core is reached through its module
    assert "skew" not in dqlab.__all__ and callable(dqlab.rotations.skew)
    assert callable(dqlab.complex.planar_arm_joints)
