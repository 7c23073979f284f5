"""Hidden tests of chapter 1, complex numbers and rotations in the plane."""

import numpy as np
from dqlab_grading import agrees, hidden


@hidden("ch1-ex2")
def rotate_xy_on_new_points(rotate_xy):
    """rotate_xy turns new points, far from the origin and by several turns, as e^{i theta} does"""
    def turned(x, y, theta):
        w = (x + 1j * y) * np.exp(1j * theta)
        return w.real, w.imag
    agrees(rotate_xy, turned,
           lambda rng: (*rng.normal(0, 50, 2), rng.uniform(-20, 20)), n=100, seed=101)


@hidden("ch1-ex2")
def rotate_xy_is_own_code(rotate_xy):
    """rotate_xy computes the turn itself, with sines and cosines, not with dqlab"""
    def turned(x, y, theta):
        w = (x + 1j * y) * np.exp(1j * theta)
        return w.real, w.imag
    agrees(rotate_xy, turned, lambda rng: (*rng.normal(size=2), rng.uniform(-np.pi, np.pi)),
           n=5, seed=102, forbid=("dqlab",))


@hidden("ch1-ex3")
def tip_xy_on_new_arms(tip_xy):
    """tip_xy finds the tip of new three-link arms"""
    def tip(lengths, angles):
        p = np.sum(lengths * np.exp(1j * np.cumsum(angles)))
        return np.array([p.real, p.imag])
    agrees(tip_xy, tip, lambda rng: (rng.uniform(0.01, 2.0, 3), rng.uniform(-7, 7, 3)),
           n=100, seed=103)


@hidden("ch1-ex3")
def tip_xy_is_own_code(tip_xy):
    """tip_xy sums the links itself, not with dqlab.complex.planar_arm_tip"""
    def tip(lengths, angles):
        p = np.sum(lengths * np.exp(1j * np.cumsum(angles)))
        return np.array([p.real, p.imag])
    agrees(tip_xy, tip, lambda rng: (rng.uniform(0.05, 0.3, 3), rng.uniform(-np.pi, np.pi, 3)),
           n=5, seed=104, forbid=("dqlab",))


@hidden("ch1-ex4")
def elbows_from_the_law_of_cosines(elbows):
    """elbows are the two angles +-arccos((0.25^2 - l1^2 - l2^2) / (2 l1 l2))"""
    l1, l2 = 0.144, 0.162
    expected = np.arccos((0.25**2 - l1**2 - l2**2) / (2 * l1 * l2))
    assert np.allclose(np.sort(np.ravel(elbows)), [-expected, expected], atol=1e-9), (
        f"elbows = {np.round(np.ravel(elbows), 6)}")
