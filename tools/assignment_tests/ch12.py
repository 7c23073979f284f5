"""Hidden tests of chapter 12, identification and pick-and-place."""

import numpy as np
from dqlab_grading import agrees, hidden

from dqlab import identify


def _lab_fit(q_lab, p):
    return [value for _, value, _ in identify.identify_desk_arm(q_lab, p).combinations()]


@hidden("ch12-ex1")
def my_lab_fit_on_new_experiments(my_lab_fit, true_lengths):
    """my_lab_fit finds the lab's four lengths from new noisy experiments of 5 to 40 poses"""
    def experiment(rng):
        m = int(rng.integers(5, 41))
        q = np.radians(np.column_stack([rng.uniform(-90, 90, m), rng.uniform(10, 80, m),
                                        rng.uniform(-20, 70, m)]))
        return q, identify.desk_arm_regressor(q) @ true_lengths + rng.normal(0, 1e-3, (m, 3))
    agrees(my_lab_fit, _lab_fit, experiment, n=30, seed=1201, atol=1e-10)


@hidden("ch12-ex1")
def my_lab_fit_is_own_code(my_lab_fit, true_lengths):
    """my_lab_fit builds and solves the lab's 2m x 4 system itself, not with dqlab.identify"""
    def experiment(rng):
        q = np.radians(np.column_stack([rng.uniform(-90, 90, 10), rng.uniform(10, 80, 10),
                                        rng.uniform(-20, 70, 10)]))
        return q, identify.desk_arm_regressor(q) @ true_lengths + rng.normal(0, 5e-4, (10, 3))
    agrees(my_lab_fit, _lab_fit, experiment, n=3, seed=1202, atol=1e-10,
           forbid=("dqlab.identify",))
