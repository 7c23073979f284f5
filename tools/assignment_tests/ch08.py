"""Hidden tests of chapter 8, inverse kinematics."""

import numpy as np
from dqlab_grading import agrees, hidden

import dqlab


def _row0(p):
    return dqlab.ik.desk_arm(dqlab.models.desk_arm(), p).solutions[0]


def _target(rng):
    q = np.array([rng.uniform(-3.0, 3.0), rng.uniform(0.0, 1.4), rng.uniform(-2.6, -0.3)])
    return (dqlab.models.desk_arm().fk(q)[:3, 3],)


@hidden("ch8-ex1")
def my_desk_arm_ik_on_new_targets(my_desk_arm_ik):
    """my_desk_arm_ik finds the facing, elbow-up angles of new reachable targets"""
    agrees(my_desk_arm_ik, _row0, _target, n=100, seed=801)


@hidden("ch8-ex1")
def my_desk_arm_ik_is_own_code(my_desk_arm_ik):
    """my_desk_arm_ik solves with the law of cosines itself, not with dqlab.ik"""
    agrees(my_desk_arm_ik, _row0, _target, n=5, seed=802, forbid=("dqlab.ik",))
