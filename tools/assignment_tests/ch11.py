"""Hidden tests of chapter 11, Cartesian paths."""

import numpy as np
from dqlab_grading import agrees, hidden


def _nearest(q_prev, theta):
    return q_prev + np.angle(np.exp(1j * (theta - q_prev)))


@hidden("ch11-ex1")
def my_nearest_equivalent_for_any_shape(my_nearest_equivalent):
    """my_nearest_equivalent works joint by joint for scalars and arrays of any shape"""
    agrees(my_nearest_equivalent, _nearest,
           lambda rng: (rng.uniform(-30, 30, (3, 4)), rng.uniform(-30, 30, (3, 4))), n=50,
           seed=1101, atol=1e-9)
    assert np.isclose(my_nearest_equivalent(20.0, 0.5), _nearest(20.0, 0.5)), "for scalars"


@hidden("ch11-ex1")
def my_nearest_equivalent_is_own_code(my_nearest_equivalent):
    """my_nearest_equivalent counts the turns itself, not with dqlab's wrap_angle"""
    agrees(my_nearest_equivalent, _nearest,
           lambda rng: (rng.uniform(-10, 10, 6), rng.uniform(-np.pi, np.pi, 6)), n=5,
           seed=1102, atol=1e-9, forbid=("dqlab",))


@hidden("ch11-ex2")
def largest_is_the_closed_form(largest, V, R):
    """largest is V^2 / R sqrt(1 + 1 / pi^2), the end of the acceleration phase"""
    expected = V**2 / R * np.sqrt(1 + 1 / np.pi**2)
    assert np.isclose(largest, expected, rtol=1e-9, atol=0), f"largest = {largest}"
