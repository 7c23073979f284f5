"""Tests of dqlab.complex: planar rotations and planar arms by complex numbers."""

import numpy as np
import pytest

from dqlab.complex import (
    complex_from_point,
    compose_planar,
    from_polar,
    planar_arm_joints,
    planar_arm_tip,
    point_from_complex,
    polar,
    rotate_planar,
    scale_rotate,
)


def planar_matrix(theta):
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def test_rotation_is_the_planar_rotation_matrix():
    rng = np.random.default_rng(41)
    for _ in range(50):
        p = rng.normal(size=2)
        theta = rng.uniform(-4, 4)
        z = rotate_planar(complex_from_point(p), theta)
        np.testing.assert_allclose(point_from_complex(z), planar_matrix(theta) @ p, atol=1e-14)


def test_polar_form_and_scaling():
    r, phi = polar(-2j)
    assert abs(r - 2) < 1e-15 and abs(phi + np.pi / 2) < 1e-15
    np.testing.assert_allclose(from_polar(r, phi), -2j, atol=1e-15)
    np.testing.assert_allclose(scale_rotate(1 + 0j, 3, np.pi / 2), 3j, atol=1e-15)
    z = 0.3 - 1.2j
    r, phi = polar(z)
    np.testing.assert_allclose(from_polar(r, phi), z, atol=1e-15)
    # moduli multiply, arguments add
    w = -0.5 + 2j
    np.testing.assert_allclose(abs(z * w), abs(z) * abs(w))
    np.testing.assert_allclose(np.exp(1j * (polar(z)[1] + polar(w)[1])) * abs(z * w), z * w)


def test_composition_adds_angles():
    np.testing.assert_allclose(compose_planar(0.3, 0.5, -0.1), np.exp(0.7j), atol=1e-15)
    np.testing.assert_allclose(rotate_planar(rotate_planar(1 + 1j, 0.4), 0.6),
                               rotate_planar(1 + 1j, 1.0), atol=1e-15)
    assert compose_planar() == 1


def test_planar_arm_matches_trigonometry():
    l1, l2, l3 = 0.3, 0.25, 0.1
    t1, t2, t3 = 0.4, -1.1, 0.7
    z = planar_arm_joints([l1, l2, l3], [t1, t2, t3])
    assert z.shape == (4,)
    x = [0, l1 * np.cos(t1), l1 * np.cos(t1) + l2 * np.cos(t1 + t2),
         l1 * np.cos(t1) + l2 * np.cos(t1 + t2) + l3 * np.cos(t1 + t2 + t3)]
    y = [0, l1 * np.sin(t1), l1 * np.sin(t1) + l2 * np.sin(t1 + t2),
         l1 * np.sin(t1) + l2 * np.sin(t1 + t2) + l3 * np.sin(t1 + t2 + t3)]
    np.testing.assert_allclose(z.real, x, atol=1e-15)
    np.testing.assert_allclose(z.imag, y, atol=1e-15)
    # absolute angles
    za = planar_arm_joints([l1, l2, l3], np.cumsum([t1, t2, t3]), relative=False)
    np.testing.assert_allclose(za, z, atol=1e-15)
    # tip as a sum of products of unit complex numbers
    e = np.exp(1j * np.array([t1, t2, t3]))
    tip = l1 * e[0] + l2 * e[0] * e[1] + l3 * e[0] * e[1] * e[2]
    np.testing.assert_allclose(planar_arm_tip([l1, l2, l3], [t1, t2, t3]), tip, atol=1e-15)


def test_planar_arm_batch():
    rng = np.random.default_rng(42)
    q = rng.uniform(-np.pi, np.pi, size=(4, 5, 2))
    z = planar_arm_joints([1.0, 0.5], q)
    assert z.shape == (4, 5, 3)
    for idx in np.ndindex(4, 5):
        np.testing.assert_allclose(z[idx], planar_arm_joints([1.0, 0.5], q[idx]), atol=1e-15)


@pytest.mark.parametrize("call, message", [
    (lambda: planar_arm_joints([1, 1], [0, 0, 0]), "lengths and angles must have the same"),
    (lambda: planar_arm_joints([1, np.nan], [0, 0]), "lengths contains NaN"),
    (lambda: rotate_planar(np.inf, 0.1), "z contains NaN"),
    (lambda: rotate_planar(1, "x"), "theta must hold numbers"),
    (lambda: complex_from_point([1, 2, 3]), r"p must have shape \(\.\.\., 2\)"),
])
def test_bad_input_raises_named_value_error(call, message):
    with pytest.raises((ValueError, TypeError), match=message):
        call()
