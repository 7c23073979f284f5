"""Hidden tests of chapter 13, programming a UR3."""

import numpy as np
from dqlab_grading import agrees, hidden

from dqlab import ur


def _rotation(rng, largest=np.pi - 0.01):
    axis = rng.normal(size=3)
    angle = rng.uniform(1e-3, largest)
    return (ur.matrix_from_rotation_vector(angle * axis / np.linalg.norm(axis)),)


@hidden("ch13-ex1")
def my_rotation_vector_on_new_rotations(my_rotation_vector):
    """my_rotation_vector reads the rotation vector of new rotations, small ones included"""
    agrees(my_rotation_vector, ur.rotation_vector_from_matrix, _rotation, n=100, seed=1301,
           atol=1e-10)


@hidden("ch13-ex1")
def my_rotation_vector_is_own_code(my_rotation_vector):
    """my_rotation_vector uses atan2 and the skew part of R itself, not dqlab"""
    agrees(my_rotation_vector, ur.rotation_vector_from_matrix, _rotation, n=5, seed=1302,
           atol=1e-10, forbid=("dqlab",))
