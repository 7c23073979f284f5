"""Tests of dqlab.dualquat: algebra, rigid motions, pairs, screws, ScLERP, errors, class."""

import numpy as np
import pytest
import pytransform3d.rotations as pr
import pytransform3d.transformations as pt
from _draws import random_unit_quaternions
from hypothesis import given, settings
from hypothesis import strategies as st

from dqlab.dualquat import (
    DualQuaternion,
    check_unit_dual_quaternion,
    dual_quaternion_apply,
    dual_quaternion_apply_line,
    dual_quaternion_apply_vector,
    dual_quaternion_combined_conjugate,
    dual_quaternion_conjugate,
    dual_quaternion_dual_conjugate,
    dual_quaternion_from_pair,
    dual_quaternion_from_rotation_translation,
    dual_quaternion_from_screw,
    dual_quaternion_from_transform,
    dual_quaternion_identity,
    dual_quaternion_inverse,
    dual_quaternion_norm,
    dual_quaternion_normalize,
    dual_quaternion_power,
    dual_quaternion_product,
    pair_from_dual_quaternion,
    pair_product,
    rotation_translation_from_dual_quaternion,
    sclerp,
    screw_from_dual_quaternion,
    transform_from_dual_quaternion,
)
from dqlab.quaternion import (
    Quaternion,
    matrix_from_quaternion,
    quaternion_from_axis_angle,
    quaternion_product,
    rotate_vector,
)
from dqlab.testing import assert_dual_quaternion_equal

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=40, deadline=None)



def random_dq(rng, shape=()):
    return dual_quaternion_from_rotation_translation(random_unit_quaternions(rng, shape),
                                                     rng.normal(size=tuple(shape) + (3,)))


def random_transform(rng):
    return pt.transform_from(matrix_from_quaternion(random_unit_quaternions(rng)),
                             rng.normal(size=3))


def qmul(*qs):
    out = np.array([1.0, 0, 0, 0])
    for q in qs:
        out = quaternion_product(out, q)
    return out


# --- fixed examples ----------------------------------------------------------------------


def test_thesis_example_with_a_translation():
    # rotate (2, 1, 1) by 90 degrees about z, then move by (1, 0, 0)
    Q = dual_quaternion_from_rotation_translation(
        quaternion_from_axis_angle([0, 0, 1], np.pi / 2), [1, 0, 0])
    np.testing.assert_allclose(dual_quaternion_apply(Q, [2, 1, 1]), [0, 2, 1], atol=1e-15)
    T = transform_from_dual_quaternion(Q)
    np.testing.assert_allclose(T @ [2, 1, 1, 1], [0, 2, 1, 1], atol=1e-15)


def test_identity_and_pure_translation():
    I = dual_quaternion_identity()
    np.testing.assert_array_equal(transform_from_dual_quaternion(I), np.eye(4))
    Q = dual_quaternion_from_rotation_translation([1, 0, 0, 0], [2, 4, 6])
    np.testing.assert_array_equal(Q, [1, 0, 0, 0, 0, 1, 2, 3])
    np.testing.assert_array_equal(dual_quaternion_apply(Q, [1, 1, 1]), [3, 5, 7])
    np.testing.assert_array_equal(dual_quaternion_apply_vector(Q, [1, 1, 1]), [1, 1, 1])


# --- algebra -----------------------------------------------------------------------------


@FAST
@given(SEEDS)
def test_product_is_transform_product(seed):
    rng = np.random.default_rng(seed)
    T1, T2 = random_transform(rng), random_transform(rng)
    Q1, Q2 = dual_quaternion_from_transform(T1), dual_quaternion_from_transform(T2)
    np.testing.assert_allclose(transform_from_dual_quaternion(dual_quaternion_product(Q1, Q2)),
                               T1 @ T2, atol=1e-12)


@FAST
@given(SEEDS)
def test_associativity_and_inverse(seed):
    rng = np.random.default_rng(seed)
    A, B, C = rng.normal(size=(3, 8))
    np.testing.assert_allclose(
        dual_quaternion_product(dual_quaternion_product(A, B), C),
        dual_quaternion_product(A, dual_quaternion_product(B, C)), atol=1e-12)
    one = dual_quaternion_identity()
    np.testing.assert_allclose(dual_quaternion_product(A, dual_quaternion_inverse(A)), one,
                               atol=1e-12)
    np.testing.assert_allclose(dual_quaternion_product(dual_quaternion_inverse(A), A), one,
                               atol=1e-12)
    Q = random_dq(rng)
    np.testing.assert_allclose(dual_quaternion_inverse(Q), dual_quaternion_conjugate(Q),
                               atol=1e-15)
    np.testing.assert_allclose(transform_from_dual_quaternion(dual_quaternion_inverse(Q)),
                               np.linalg.inv(transform_from_dual_quaternion(Q)), atol=1e-12)


@FAST
@given(SEEDS)
def test_conjugates(seed):
    rng = np.random.default_rng(seed)
    A, B = random_dq(rng, (2,))
    # the quaternion conjugate reverses products
    np.testing.assert_allclose(
        dual_quaternion_conjugate(dual_quaternion_product(A, B)),
        dual_quaternion_product(dual_quaternion_conjugate(B), dual_quaternion_conjugate(A)),
        atol=1e-13)
    # the combined conjugate moves points: Q (1 + eps p) conj(Q) = 1 + eps p'
    p = rng.normal(size=3)
    P = np.r_[1, 0, 0, 0, 0, p]
    moved = dual_quaternion_product(dual_quaternion_product(A, P),
                                    dual_quaternion_combined_conjugate(A))
    np.testing.assert_allclose(moved[:5], [1, 0, 0, 0, 0], atol=1e-13)
    np.testing.assert_allclose(moved[5:], dual_quaternion_apply(A, p), atol=1e-13)
    # the combined conjugate is both conjugates in either order
    np.testing.assert_array_equal(
        dual_quaternion_combined_conjugate(A),
        dual_quaternion_dual_conjugate(dual_quaternion_conjugate(A)))
    np.testing.assert_array_equal(
        dual_quaternion_combined_conjugate(A),
        dual_quaternion_conjugate(dual_quaternion_dual_conjugate(A)))


@FAST
@given(SEEDS)
def test_norm_and_normalize(seed):
    rng = np.random.default_rng(seed)
    Q = random_dq(rng)
    np.testing.assert_allclose(dual_quaternion_norm(Q), [1, 0], atol=1e-14)
    check_unit_dual_quaternion(Q)
    X = rng.normal(size=8)
    N = dual_quaternion_normalize(X)
    np.testing.assert_allclose(dual_quaternion_norm(N), [1, 0], atol=1e-14)
    check_unit_dual_quaternion(N)
    # Q Q* = |Q|^2 as a dual number: (a^2, 2ab)
    a, b = dual_quaternion_norm(X)
    QQ = dual_quaternion_product(X, dual_quaternion_conjugate(X))
    np.testing.assert_allclose(QQ, [a * a, 0, 0, 0, 2 * a * b, 0, 0, 0], atol=1e-12)
    # normalising a scaled unit dual quaternion gives it back
    np.testing.assert_allclose(dual_quaternion_normalize(3.5 * Q), Q, atol=1e-14)
    np.testing.assert_allclose(dual_quaternion_normalize(Q), Q, atol=1e-15)


# --- rigid motions ------------------------------------------------------------------------


@FAST
@given(SEEDS)
def test_conversions_round_trip(seed):
    rng = np.random.default_rng(seed)
    T = random_transform(rng)
    Q = dual_quaternion_from_transform(T)
    assert Q[0] >= 0
    np.testing.assert_allclose(transform_from_dual_quaternion(Q), T, atol=1e-14)
    q, t = rotation_translation_from_dual_quaternion(Q)
    np.testing.assert_allclose(matrix_from_quaternion(q), T[:3, :3], atol=1e-14)
    np.testing.assert_allclose(t, T[:3, 3], atol=1e-14)
    np.testing.assert_allclose(dual_quaternion_from_rotation_translation(q, t), Q, atol=1e-15)
    p = rng.normal(size=3)
    np.testing.assert_allclose(dual_quaternion_apply(Q, p), T[:3, :3] @ p + T[:3, 3],
                               atol=1e-13)
    np.testing.assert_allclose(dual_quaternion_apply_vector(Q, p), T[:3, :3] @ p, atol=1e-13)


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-6, np.pi - 1e-6, np.pi - 1e-9, np.pi])
def test_transform_round_trip_near_0_and_pi(angle):
    rng = np.random.default_rng(8)
    for _ in range(20):
        q = quaternion_from_axis_angle(rng.normal(size=3), angle)
        T = pt.transform_from(matrix_from_quaternion(q), rng.normal(size=3))
        Q = dual_quaternion_from_transform(T)
        assert_dual_quaternion_equal(Q, dual_quaternion_from_rotation_translation(q, T[:3, 3]),
                                     atol=1e-14)
        np.testing.assert_allclose(transform_from_dual_quaternion(Q), T, atol=1e-14)


def test_apply_line():
    rng = np.random.default_rng(9)
    for _ in range(20):
        Q = random_dq(rng)
        c, l = rng.normal(size=(2, 3))
        l /= np.linalg.norm(l)
        m = np.cross(c, l)
        l2, m2 = dual_quaternion_apply_line(Q, l, m)
        c2 = dual_quaternion_apply(Q, c)  # a point of the moved line
        np.testing.assert_allclose(l2, dual_quaternion_apply_vector(Q, l), atol=1e-14)
        np.testing.assert_allclose(m2, np.cross(c2, l2), atol=1e-12)
        # as dual quaternions: L' = Q L Q*
        L = np.r_[0, l, 0, m]
        L2 = dual_quaternion_product(dual_quaternion_product(Q, L), dual_quaternion_conjugate(Q))
        np.testing.assert_allclose(L2, np.r_[0, l2, 0, m2], atol=1e-12)


# --- the thesis's (q, p) pairs ------------------------------------------------------------


@FAST
@given(SEEDS)
def test_pair_form_equals_dual_number_form(seed):
    rng = np.random.default_rng(seed)
    q1, q2 = random_unit_quaternions(rng, (2,))
    p1, p2 = rng.normal(size=(2, 3))
    q, p = pair_product(q1, p1, q2, p2)
    Q = dual_quaternion_product(dual_quaternion_from_pair(q1, p1),
                                dual_quaternion_from_pair(q2, p2))
    np.testing.assert_allclose(dual_quaternion_from_pair(q, p), Q, atol=1e-13)
    qq, pp = pair_from_dual_quaternion(Q)
    np.testing.assert_allclose(qq, q, atol=1e-14)
    np.testing.assert_allclose(pp, p, atol=1e-13)
    # (q, p) acts on x as q x q^-1 + p
    x = rng.normal(size=3)
    np.testing.assert_allclose(dual_quaternion_apply(dual_quaternion_from_pair(q1, p1), x),
                               rotate_vector(q1, x) + p1, atol=1e-13)
    # the rule written with quaternions: q1 p2 q1^-1
    qpq = qmul(q1, np.r_[0, p2], q1 * [1, -1, -1, -1])
    np.testing.assert_allclose(p, qpq[1:] + p1, atol=1e-13)


# --- screws, powers, ScLERP ---------------------------------------------------------------


@FAST
@given(SEEDS)
def test_screw_round_trip(seed):
    rng = np.random.default_rng(seed)
    Q = random_dq(rng)
    l, m, theta, d = screw_from_dual_quaternion(Q)
    assert 0 <= theta <= np.pi
    assert abs(np.linalg.norm(l) - 1) < 1e-14
    assert abs(l @ m) < 1e-12
    assert_dual_quaternion_equal(dual_quaternion_from_screw(l, m, theta, d), Q, atol=1e-12)
    # the screw axis is fixed by the rotation part and moved along itself by d
    c = np.cross(l, m)  # the point of the axis closest to the origin
    np.testing.assert_allclose(dual_quaternion_apply(Q, c), c + d * l, atol=1e-11)


def test_screw_special_cases():
    l, m, theta, d = screw_from_dual_quaternion(dual_quaternion_identity())
    np.testing.assert_array_equal(l, [1, 0, 0])
    assert theta == 0 and d == 0 and not m.any()
    Q = dual_quaternion_from_rotation_translation([1, 0, 0, 0], [0, 3, 4])
    l, m, theta, d = screw_from_dual_quaternion(Q)
    np.testing.assert_allclose(l, [0, 0.6, 0.8])
    assert theta == 0 and abs(d - 5) < 1e-15 and not m.any()
    # -Q gives the same screw
    Q = random_dq(np.random.default_rng(1))
    for a, b in zip(screw_from_dual_quaternion(Q), screw_from_dual_quaternion(-Q), strict=True):
        np.testing.assert_allclose(a, b, atol=1e-14)


@FAST
@given(SEEDS)
def test_power_and_sclerp(seed):
    rng = np.random.default_rng(seed)
    Q0, Q1 = random_dq(rng, (2,))
    np.testing.assert_allclose(dual_quaternion_power(Q0, 0), dual_quaternion_identity(),
                               atol=1e-14)
    assert_dual_quaternion_equal(dual_quaternion_power(Q0, 1), Q0)
    H = dual_quaternion_power(Q0, 0.5)
    assert_dual_quaternion_equal(dual_quaternion_product(H, H), Q0, atol=1e-12)
    t = np.linspace(0, 1, 7)
    path = sclerp(Q0, Q1, t)
    np.testing.assert_allclose(path[0], Q0, atol=1e-13)
    assert_dual_quaternion_equal(path[-1], Q1, atol=1e-12)
    np.testing.assert_allclose(dual_quaternion_norm(path), np.tile([1, 0], (7, 1)), atol=1e-13)
    assert_dual_quaternion_equal(sclerp(Q0, -Q1, t), path, atol=1e-12)


# --- cross-checks against pytransform3d ---------------------------------------------------


def test_against_pytransform3d():
    rng = np.random.default_rng(42)
    for _ in range(100):
        T1, T2 = random_transform(rng), random_transform(rng)
        Q1, Q2 = dual_quaternion_from_transform(T1), dual_quaternion_from_transform(T2)
        # pytransform3d also stores (w, x, y, z) real then dual, translation after rotation
        assert_dual_quaternion_equal(Q1, pt.dual_quaternion_from_transform(T1))
        np.testing.assert_allclose(transform_from_dual_quaternion(Q1),
                                   pt.transform_from_dual_quaternion(Q1), atol=1e-12)
        np.testing.assert_allclose(dual_quaternion_product(Q1, Q2),
                                   pt.concatenate_dual_quaternions(Q1, Q2), atol=1e-12)
        # pytransform3d's concat(A2B, B2C) is our X_AB @ X_BC written the other way round
        np.testing.assert_allclose(
            transform_from_dual_quaternion(dual_quaternion_product(Q1, Q2)),
            pt.concat(T2, T1), atol=1e-12)
        np.testing.assert_allclose(dual_quaternion_conjugate(Q1), pt.dq_q_conj(Q1), atol=0)
        np.testing.assert_allclose(dual_quaternion_combined_conjugate(Q1), pt.dq_conj(Q1),
                                   atol=0)
        p = rng.normal(size=3)
        np.testing.assert_allclose(dual_quaternion_apply(Q1, p),
                                   pt.dq_prod_vector(Q1, p), atol=1e-12)
        t = rng.uniform()
        assert_dual_quaternion_equal(sclerp(Q1, Q2, t), pt.dual_quaternion_sclerp(Q1, Q2, t))
        assert_dual_quaternion_equal(dual_quaternion_power(Q1, t),
                                     pt.dual_quaternion_power(Q1, t))
        # screw parameters: pytransform3d returns (point c, axis l, pitch h, angle theta)
        l, m, theta, d = screw_from_dual_quaternion(Q1)
        c, s, h, th = pt.screw_parameters_from_dual_quaternion(Q1)
        if np.dot(s, l) < 0:  # pytransform3d may return the angle in (pi, 2 pi)
            s, th, h = -s, 2 * np.pi - th, -h * th / (2 * np.pi - th)
        np.testing.assert_allclose(l, s, atol=1e-12)
        assert abs(theta - th) < 1e-12
        assert abs(d - h * th) < 1e-12
        np.testing.assert_allclose(m, np.cross(c, s), atol=1e-12)
        assert_dual_quaternion_equal(dual_quaternion_from_screw(l, m, theta, d),
                                     pt.dual_quaternion_from_screw_parameters(c, s, h, th))


def test_against_pytransform3d_batches():
    import pytransform3d.trajectories as ptr

    rng = np.random.default_rng(43)
    Qs = random_dq(rng, (50,))
    Ts = ptr.transforms_from_dual_quaternions(Qs)
    np.testing.assert_allclose(transform_from_dual_quaternion(Qs), Ts, atol=1e-12)
    assert_dual_quaternion_equal(dual_quaternion_from_transform(Ts),
                                 ptr.dual_quaternions_from_transforms(Ts))
    Rs = random_dq(rng, (50,))
    np.testing.assert_allclose(dual_quaternion_product(Qs, Rs),
                               ptr.batch_concatenate_dual_quaternions(Qs, Rs), atol=1e-12)


# --- batches: 0, 1, 2 leading dimensions ------------------------------------------------


@pytest.mark.parametrize("shape", [(), (4,), (2, 3)])
def test_batch_equals_single(shape):
    rng = np.random.default_rng(12)
    A, B = random_dq(rng, shape), random_dq(rng, shape)
    X = rng.normal(size=shape + (8,))
    p = rng.normal(size=shape + (3,))
    t = rng.uniform(size=shape)
    T = transform_from_dual_quaternion(A)
    assert T.shape == shape + (4, 4)
    fns = {
        "product": lambda i: dual_quaternion_product(X[i], B[i]),
        "from_transform": lambda i: dual_quaternion_from_transform(T[i]),
        "to_transform": lambda i: transform_from_dual_quaternion(A[i]),
        "apply": lambda i: dual_quaternion_apply(A[i], p[i]),
        "inverse": lambda i: dual_quaternion_inverse(X[i]),
        "normalize": lambda i: dual_quaternion_normalize(X[i]),
        "norm": lambda i: dual_quaternion_norm(X[i]),
        "sclerp": lambda i: sclerp(A[i], B[i], t[i]),
        "power": lambda i: dual_quaternion_power(A[i], t[i]),
        "translation": lambda i: rotation_translation_from_dual_quaternion(A[i])[1],
        "screw_m": lambda i: screw_from_dual_quaternion(A[i])[1],
    }
    whole = (slice(None),) * len(shape) + (Ellipsis,)
    for key, f in fns.items():
        batch = f(whole)
        for idx in np.ndindex(*shape):
            np.testing.assert_allclose(batch[idx], f(idx), atol=1e-14, err_msg=key)


def test_broadcasting_single_with_batch():
    rng = np.random.default_rng(13)
    Q = random_dq(rng)
    P = rng.normal(size=(5, 3))
    np.testing.assert_allclose(dual_quaternion_apply(Q, P)[2], dual_quaternion_apply(Q, P[2]))
    Bs = random_dq(rng, (5,))
    np.testing.assert_allclose(dual_quaternion_product(Q, Bs)[3],
                               dual_quaternion_product(Q, Bs[3]))
    q = random_unit_quaternions(rng)
    assert dual_quaternion_from_rotation_translation(q, P).shape == (5, 8)
    assert sclerp(Q, Bs[0], np.linspace(0, 1, 9)).shape == (9, 8)


# --- bad input -----------------------------------------------------------------------


def _not_rotation():
    T = np.eye(4)
    T[0, 0] = 2
    return T


@pytest.mark.parametrize("call, message", [
    (lambda: dual_quaternion_product(np.ones(7), np.ones(8)), r"A must have shape \(\.\.\., 8\)"),
    (lambda: dual_quaternion_product(np.ones(8), np.r_[np.ones(7), np.nan]), "B contains NaN"),
    (lambda: dual_quaternion_product(np.ones((2, 8)), [np.inf] * 8), "B contains NaN"),
    (lambda: dual_quaternion_from_transform(np.eye(3)), r"T must have shape \(\.\.\., 4, 4\)"),
    (lambda: dual_quaternion_from_transform(_not_rotation()),
     "the rotation block of T is not orthonormal"),
    (lambda: dual_quaternion_from_transform(np.stack([np.eye(4), _not_rotation()])),
     "the rotation block of T is not orthonormal"),
    (lambda: dual_quaternion_from_transform(np.diag([1.0, 1, -1, 1])),
     "the rotation block of T is a reflection"),
    (lambda: dual_quaternion_from_transform(2 * np.eye(4)), "T must have bottom row"),
    (lambda: dual_quaternion_from_transform(np.full((4, 4), np.nan)), "T contains NaN"),
    (lambda: transform_from_dual_quaternion(np.zeros(8)),
     "the real part of Q is the zero quaternion"),
    (lambda: transform_from_dual_quaternion([1, 0, 0, 0, 1, 0, 0, 0]),
     "Q must be a unit dual quaternion"),
    (lambda: transform_from_dual_quaternion([2, 0, 0, 0, 0, 0, 0, 0]),
     "the real part of Q must be a unit quaternion"),
    (lambda: transform_from_dual_quaternion([1, 0, 0, 0, 0, np.nan, 0, 0]), "Q contains NaN"),
    (lambda: dual_quaternion_apply([1, 0, 0, 0, 0, 0, 0, 0], [1, 2]),
     r"points must have shape \(\.\.\., 3\)"),
    (lambda: dual_quaternion_apply(np.zeros((2, 8)), np.zeros(3)),
     "the real part of Q is the zero quaternion"),
    (lambda: dual_quaternion_inverse(np.zeros(8)), "the real part of Q is the zero quaternion"),
    (lambda: dual_quaternion_normalize(np.r_[np.zeros(4), np.ones(4)]),
     "the real part of Q is the zero quaternion"),
    (lambda: dual_quaternion_from_rotation_translation([0, 0, 0, 0], [1, 2, 3]),
     "q is the zero quaternion"),
    (lambda: dual_quaternion_from_rotation_translation([1, 0, 0, 0], [np.nan, 2, 3]),
     "t contains NaN"),
    (lambda: sclerp(np.zeros(8), dual_quaternion_identity(), 0.5),
     "the real part of Q0 is the zero quaternion"),
    (lambda: dual_quaternion_from_screw([0, 0, 2], [0, 0, 0], 1.0, 0.0), "l must be a unit"),
    (lambda: dual_quaternion_from_screw([0, 0, 1], [0, 0, 1], 1.0, 0.0),
     "m must be orthogonal to l"),
])
def test_bad_input_raises_named_value_error(call, message):
    with pytest.raises(ValueError, match=message):
        call()


# --- the class wrapper ------------------------------------------------------------------


def test_dual_quaternion_class():
    rng = np.random.default_rng(14)
    a, b = random_dq(rng, (2,))
    A, B = DualQuaternion(a), DualQuaternion(b)
    np.testing.assert_array_equal((A * B).array, dual_quaternion_product(a, b))
    np.testing.assert_array_equal(A.inverse().array, dual_quaternion_inverse(a))
    np.testing.assert_array_equal(A.conjugate().array, dual_quaternion_conjugate(a))
    np.testing.assert_array_equal(A.dual_conjugate().array, dual_quaternion_dual_conjugate(a))
    np.testing.assert_array_equal(A.combined_conjugate().array,
                                  dual_quaternion_combined_conjugate(a))
    np.testing.assert_array_equal(A.matrix(), transform_from_dual_quaternion(a))
    np.testing.assert_array_equal(A.apply([1, 2, 3]), dual_quaternion_apply(a, [1, 2, 3]))
    np.testing.assert_array_equal(A.apply_vector([1, 2, 3]),
                                  dual_quaternion_apply_vector(a, [1, 2, 3]))
    np.testing.assert_allclose((A * A.inverse()).array, dual_quaternion_identity(), atol=1e-15)
    np.testing.assert_array_equal(A.real, a[:4])
    np.testing.assert_array_equal(A.dual, a[4:])
    np.testing.assert_array_equal(DualQuaternion.from_matrix(A.matrix()).array,
                                  dual_quaternion_from_transform(A.matrix()))
    q, t = A.rotation_translation()
    C = DualQuaternion.from_rotation_translation(Quaternion(q), t)
    np.testing.assert_allclose(C.array, a, atol=1e-15)
    np.testing.assert_allclose(A.translation(), t)
    assert isinstance(A.rotation(), Quaternion)
    np.testing.assert_array_equal(A.sclerp(B, 0.25).array, sclerp(a, b, 0.25))
    np.testing.assert_array_equal((A ** 0.5).array, dual_quaternion_power(a, 0.5))
    np.testing.assert_array_equal(A.norm(), dual_quaternion_norm(a))
    assert A.is_unit() and not (2 * A).is_unit()
    np.testing.assert_allclose((2 * A).normalized().array, a, atol=1e-15)
    assert DualQuaternion(A) == A
    np.testing.assert_array_equal(np.asarray(A), a)
    l, m, theta, d = A.screw()
    np.testing.assert_allclose(DualQuaternion.from_screw(l, m, theta, d).array,
                               a * np.sign(a[0]), atol=1e-12)
    qq, pp = A.pair()
    np.testing.assert_allclose(DualQuaternion.from_pair(qq, pp).array, a, atol=1e-15)


def test_dual_quaternion_class_batch_and_repr():
    D = DualQuaternion(random_dq(np.random.default_rng(15), (4,)))
    assert D.shape == (4,) and len(D) == 4
    assert D[0].shape == ()
    assert D.apply([0, 0, 0]).shape == (4, 3)
    assert D.matrix().shape == (4, 4, 4)
    assert repr(DualQuaternion.identity()) == "DualQuaternion([1., 0., 0., 0., 0., 0., 0., 0.])"
    assert str(DualQuaternion.identity()) == "(1 +0i +0j +0k) + eps (0 +0i +0j +0k)"
    with pytest.raises(ValueError, match="Q must have shape"):
        DualQuaternion([1, 0, 0, 0])


def test_pytransform3d_rotation_helpers_agree():
    # a sanity check of the cross-check itself: same quaternion convention
    q = random_unit_quaternions(np.random.default_rng(16))
    np.testing.assert_allclose(matrix_from_quaternion(q), pr.matrix_from_quaternion(q),
                               atol=1e-14)


def test_nan_in_dual_part_of_an_array_is_named():
    Q = np.array([1.0, 0, 0, 0, 0, np.nan, 0, 0])
    with pytest.raises(ValueError, match="Q contains NaN"):
        transform_from_dual_quaternion(Q)
    with pytest.raises(ValueError, match="Q contains NaN"):
        dual_quaternion_apply(Q, np.zeros(3))


@pytest.mark.parametrize("angle", [0.0, 1e-14, 1e-10, 1e-7, 1e-4, np.pi - 1e-9, np.pi])
def test_power_and_sclerp_accurate_for_nearly_pure_translations(angle):
    rng = np.random.default_rng(17)
    for _ in range(10):
        q = quaternion_from_axis_angle(rng.normal(size=3), angle)
        Q = dual_quaternion_from_rotation_translation(q, 10 * rng.normal(size=3))
        H = dual_quaternion_power(Q, 0.5)
        check_unit_dual_quaternion(H, tol=1e-14)
        assert_dual_quaternion_equal(dual_quaternion_product(H, H), Q, atol=1e-13)
        T = dual_quaternion_power(Q, 1 / 3)
        assert_dual_quaternion_equal(dual_quaternion_product(T, dual_quaternion_product(T, T)),
                                     Q, atol=1e-13)
        # ScLERP between poses of (almost) the same orientation: the position moves on
        # the straight line
        P0 = dual_quaternion_from_rotation_translation(q, [0, 0, 0])
        P1 = dual_quaternion_from_rotation_translation(q, [1, 2, 3])
        mid = rotation_translation_from_dual_quaternion(sclerp(P0, P1, 0.25))[1]
        np.testing.assert_allclose(mid, [0.25, 0.5, 0.75], atol=1e-14)


@pytest.mark.parametrize("angle, atol", [(1e-8, 1e-7), (1e-6, 1e-9), (1e-3, 1e-12),
                                         (np.pi - 1e-6, 1e-12), (np.pi, 1e-12)])
def test_screw_round_trip_near_0_and_pi(angle, atol):
    # near 0 the axis recedes to infinity: the round trip loses about eps / angle
    rng = np.random.default_rng(18)
    for _ in range(10):
        q = quaternion_from_axis_angle(rng.normal(size=3), angle)
        Q = dual_quaternion_from_rotation_translation(q, rng.normal(size=3))
        l, m, theta, d = screw_from_dual_quaternion(Q)
        assert abs(theta - angle) < 1e-12
        assert_dual_quaternion_equal(dual_quaternion_from_screw(l, m, theta, d), Q, atol=atol)


def test_fk_dq_multiplies_by_screws_as_the_general_product():
    """Robot.fk_dq multiplies by each joint's screw about z and each link's screw about x
    without the zeros of the general product; the result is the general product of the link
    dual quaternions all the same (revolute and prismatic joints, both DH conventions, with a
    base and a tool, one joint vector on floats and a batch on arrays)."""
    from dqlab.robot import Link, Robot

    rng = np.random.default_rng(19)
    for convention in ("dh", "mdh"):
        links = [Link(a=rng.normal(), alpha=rng.uniform(-np.pi, np.pi), d=rng.normal(),
                      theta_offset=rng.normal()),
                 Link(a=rng.normal(), alpha=rng.uniform(-np.pi, np.pi), d=rng.normal(),
                      theta_offset=rng.normal(), joint="prismatic", limits=(-5.0, 5.0)),
                 Link(a=0.0, alpha=np.pi / 2, d=0.0)]
        base = transform_from_dual_quaternion(random_dq(rng))
        tool = transform_from_dual_quaternion(random_dq(rng))
        robot = Robot(links, convention=convention, base=base, tool=tool)
        q = rng.uniform(-1.0, 1.0, (50, 3))
        expected = dual_quaternion_from_transform(base)
        for X in np.moveaxis(robot.link_transforms(q), -3, 0):
            expected = dual_quaternion_product(expected, dual_quaternion_from_transform(X))
        expected = dual_quaternion_product(expected, dual_quaternion_from_transform(tool))
        assert_dual_quaternion_equal(robot.fk_dq(q), expected, atol=1e-13)
        assert_dual_quaternion_equal(robot.fk_dq(q[7]), expected[7], atol=1e-13)
