"""Hidden tests of chapter 2, rotations in space."""

import numpy as np
from dqlab_grading import agrees, hidden

import dqlab


@hidden("ch2-ex1")
def axis_angle_matrix_on_new_axes(axis_angle_matrix):
    """axis_angle_matrix turns about axes of any length, by angles of several turns"""
    def sample(rng):
        return rng.normal(size=3) * 10.0 ** rng.uniform(-3, 3), rng.uniform(-10, 10)
    agrees(axis_angle_matrix, dqlab.rotations.matrix_from_axis_angle, sample, n=100, seed=201)


@hidden("ch2-ex1")
def axis_angle_matrix_is_own_code(axis_angle_matrix):
    """axis_angle_matrix builds [n]x and Rodrigues' formula itself, not with dqlab"""
    agrees(axis_angle_matrix, dqlab.rotations.matrix_from_axis_angle,
           lambda rng: (rng.normal(size=3), rng.uniform(-np.pi, np.pi)), n=5, seed=202,
           forbid=("dqlab",))


@hidden("ch2-ex2")
def rpy_angles_on_new_orientations(rpy_angles):
    """rpy_angles reads roll, pitch and yaw back from new matrices, pitch up to 1.5 rad"""
    def sample(rng):
        angles = np.r_[rng.uniform(-np.pi, np.pi), rng.uniform(-1.5, 1.5),
                       rng.uniform(-np.pi, np.pi)]
        return (dqlab.rotations.matrix_from_rpy(angles),)
    agrees(rpy_angles, dqlab.rotations.rpy_from_matrix, sample, n=100, seed=203)


@hidden("ch2-ex2")
def rpy_angles_is_own_code(rpy_angles):
    """rpy_angles applies the regular-case formulas itself, not dqlab's rpy_from_matrix"""
    def sample(rng):
        angles = np.r_[rng.uniform(-3, 3), rng.uniform(-1.4, 1.4), rng.uniform(-3, 3)]
        return (dqlab.rotations.matrix_from_rpy(angles),)
    agrees(rpy_angles, dqlab.rotations.rpy_from_matrix, sample, n=5, seed=204,
           forbid=("dqlab",))
