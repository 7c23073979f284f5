"""Tests of dqlab.transforms: building, composing, inverting and applying rigid transforms."""

import re

import numpy as np
import pytest
import pytransform3d.transformations as pt
from hypothesis import given, settings
from hypothesis import strategies as st

from dqlab.rotations import matrix_from_axis_angle, rot_y, rot_z
from dqlab.transforms import (
    apply_to_vectors,
    apply_transform,
    check_transform,
    compose,
    rotation_translation_from_transform,
    transform_from,
    transform_identity,
    transform_inverse,
)

SEEDS = st.integers(0, 2**32 - 1)
FAST = settings(max_examples=40, deadline=None)


def random_transform(rng, shape=()):
    R = matrix_from_axis_angle(rng.normal(size=shape + (3,)), rng.uniform(0, np.pi, size=shape))
    return transform_from(R, rng.normal(size=shape + (3,)))


def test_course_notes_compositions_as_transforms():
    m = [np.sqrt(2), 0, 0]
    X_01 = transform_from(rot_z(np.pi / 4), [0, 0, 0])
    X_12 = transform_from(rot_y(np.pi), [0, 0, 0])
    np.testing.assert_allclose(apply_transform(compose(X_01, X_12), m), [-1, -1, 0], atol=1e-15)
    np.testing.assert_allclose(apply_transform(compose(X_12, X_01), m), [-1, 1, 0], atol=1e-15)


def test_transform_from_and_split():
    R = rot_z(0.4)
    T = transform_from(R, [1, 2, 3])
    np.testing.assert_array_equal(T[:3, :3], R)
    np.testing.assert_array_equal(T[:3, 3], [1, 2, 3])
    np.testing.assert_array_equal(T[3], [0, 0, 0, 1])
    R2, p2 = rotation_translation_from_transform(T)
    np.testing.assert_array_equal(R2, R)
    np.testing.assert_array_equal(p2, [1, 2, 3])
    np.testing.assert_allclose(T, pt.transform_from(R, [1, 2, 3]))
    assert transform_from(R, np.zeros((5, 3))).shape == (5, 4, 4)
    np.testing.assert_array_equal(transform_identity(), np.eye(4))
    assert transform_identity((2, 3)).shape == (2, 3, 4, 4)


@FAST
@given(SEEDS)
def test_inverse_compose_apply(seed):
    rng = np.random.default_rng(seed)
    X_AB, X_BC, X_CD = random_transform(rng), random_transform(rng), random_transform(rng)
    np.testing.assert_allclose(transform_inverse(X_AB), np.linalg.inv(X_AB), atol=1e-13)
    np.testing.assert_allclose(compose(X_AB, transform_inverse(X_AB)), np.eye(4), atol=1e-14)
    np.testing.assert_allclose(compose(X_AB, X_BC, X_CD), X_AB @ X_BC @ X_CD, atol=1e-14)
    np.testing.assert_allclose(transform_inverse(X_AB), pt.invert_transform(X_AB), atol=1e-14)
    p = rng.normal(size=3)
    np.testing.assert_allclose(apply_transform(X_AB, p), (X_AB @ np.r_[p, 1])[:3], atol=1e-14)
    np.testing.assert_allclose(apply_transform(X_AB, p), pt.transform(X_AB, np.r_[p, 1])[:3],
                               atol=1e-14)
    np.testing.assert_allclose(apply_to_vectors(X_AB, p), (X_AB @ np.r_[p, 0])[:3], atol=1e-14)
    # points in C seen from A
    np.testing.assert_allclose(apply_transform(compose(X_AB, X_BC), p),
                               apply_transform(X_AB, apply_transform(X_BC, p)), atol=1e-13)


def test_compose_edge_cases():
    np.testing.assert_array_equal(compose(), np.eye(4))
    T = transform_from(rot_z(1.0), [1, 0, 0])
    out = compose(T)
    out[0, 0] = 7
    assert T[0, 0] != 7


@pytest.mark.parametrize("shape", [(), (4,), (2, 3)])
def test_batch_equals_single(shape):
    rng = np.random.default_rng(31)
    A, B = random_transform(rng, shape), random_transform(rng, shape)
    p = rng.normal(size=shape + (3,))
    fns = {
        "inverse": lambda i: transform_inverse(A[i]),
        "compose": lambda i: compose(A[i], B[i]),
        "apply": lambda i: apply_transform(A[i], p[i]),
        "vectors": lambda i: apply_to_vectors(A[i], p[i]),
    }
    whole = (slice(None),) * len(shape) + (Ellipsis,)
    for key, f in fns.items():
        batch = f(whole)
        for idx in np.ndindex(*shape):
            np.testing.assert_allclose(batch[idx], f(idx), atol=1e-14, err_msg=key)
    assert apply_transform(A, np.zeros((7,) + (1,) * len(shape) + (3,))).shape == \
        (7,) + shape + (3,)


@pytest.mark.parametrize("call, message", [
    (lambda: transform_from(np.ones((3, 3)), [0, 0, 0]), "R is not orthonormal"),
    (lambda: transform_from(np.eye(3), [0, 0]), r"p must have shape \(\.\.\., 3\)"),
    (lambda: transform_from(np.eye(3), [0, np.nan, 0]), "p contains NaN"),
    (lambda: transform_inverse(np.eye(3)), r"T must have shape \(\.\.\., 4, 4\)"),
    (lambda: transform_inverse(2 * np.eye(4)), "T must have bottom row"),
    (lambda: check_transform(np.stack([np.eye(4), np.diag([1.0, 1, 2, 1])])),
     "the rotation block of T is not orthonormal"),
    (lambda: check_transform(np.diag([-1.0, 1, 1, 1])), "the rotation block of T is a reflection"),
    (lambda: compose(np.eye(4), np.eye(3)), r"Ts\[1\] must have shape"),
    (lambda: apply_transform(np.eye(4), [1, 2]), r"points must have shape \(\.\.\., 3\)"),
    (lambda: apply_transform(np.full((4, 4), np.nan), [1, 2, 3]), "T contains NaN"),
    (lambda: apply_to_vectors(np.eye(4), [np.inf, 0, 0]), "vectors contains NaN"),
])
def test_bad_input_raises_named_value_error(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_batch_bottom_row_check_names_the_first_bad_row():
    """A batch's bottom rows are checked exactly: the first row that is not (0, 0, 0, 1) is
    named (a signed zero is a zero)."""
    T = np.tile(np.eye(4), (5, 1, 1))
    T[1, 3, :3] = -0.0
    check_transform(T)
    for row, entry, value in ((3, 2, 1e-300), (2, 3, 1.0 + 2e-16), (0, 0, -1e-3)):
        bad = T.copy()
        bad[row, 3, entry] = value
        bad[4, 3, 1] = 7.0                                   # a later bad row is not named
        expected = [0.0, 0.0, 0.0, 1.0]
        expected[entry] = value
        with pytest.raises(ValueError, match=re.escape(f"got {expected}")):
            check_transform(bad)
