"""Hidden tests of chapter 7, forward kinematics."""

import numpy as np
from dqlab_grading import agrees, hidden

import dqlab

#: What computes a pose of the chain for the student: the forward kinematics of dqlab.
_FK = ("dqlab.robot.Robot.fk", "dqlab.robot.Robot.fk_dq", "dqlab.robot.Robot.fk_dq_screw",
       "dqlab.robot.Robot.fk_with_jacobian")


def _desk_position(q_lab):
    desk = dqlab.models.desk_arm()
    return desk.fk(dqlab.models.desk_arm_joints_from_lab(q_lab))[:3, 3]


def _scara_situation(q):
    X = dqlab.models.scara_rsm5().fk(q)
    return np.array([*X[:3, 3], np.arctan2(X[1, 0], X[0, 0])])


def _scara_sample(rng):
    lo, hi = dqlab.models.scara_rsm5().limits.T
    return (lo + (hi - lo) * rng.uniform(size=4),)


@hidden("ch7-ex1")
def desk_mgd_over_the_whole_range(desk_mgd):
    """desk_mgd finds the cup for new angles over the whole range, the base turned either way"""
    agrees(desk_mgd, _desk_position,
           lambda rng: (rng.uniform([-3.0, -0.5, -1.0], [3.0, 2.0, 2.0]),), n=100, seed=701)


@hidden("ch7-ex1")
def desk_mgd_is_own_code(desk_mgd):
    """desk_mgd evaluates the closed form itself, not the chain's forward kinematics"""
    agrees(desk_mgd, _desk_position, lambda rng: (rng.uniform([-1.5, 0, -0.5], [1.5, 1.5, 1.5]),),
           n=5, seed=702, forbid=("dqlab",))


@hidden("ch7-ex2")
def scara_situation_on_new_configurations(scara_situation):
    """scara_situation gives (x, y, z, yaw) at new configurations, yaw wrapped to (-pi, pi]"""
    agrees(scara_situation, _scara_situation, _scara_sample, n=200, seed=703)


@hidden("ch7-ex2")
def scara_situation_is_own_code(scara_situation):
    """scara_situation evaluates the closed form itself, not scara.fk"""
    agrees(scara_situation, _scara_situation, _scara_sample, n=5, seed=704, forbid=("dqlab",))


@hidden("ch7-ex3")
def fk_dual_on_new_configurations(fk_dual):
    """fk_dual gives the UR3's flange pose at new configurations, several turns"""
    agrees(fk_dual, dqlab.models.ur3().fk, lambda rng: (rng.uniform(-7, 7, 6),), n=50,
           seed=705)


@hidden("ch7-ex3")
def fk_dual_multiplies_dual_quaternions(fk_dual):
    """fk_dual multiplies the links' dual quaternions itself, not with the robot's fk"""
    agrees(fk_dual, dqlab.models.ur3().fk, lambda rng: (rng.uniform(-3, 3, 6),), n=5, seed=706,
           forbid=_FK, require=("dqlab.dual_quaternion_product",))
