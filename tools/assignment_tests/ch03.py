"""Hidden tests of chapter 3, quaternions."""

import numpy as np
from dqlab_grading import agrees, hidden

import dqlab


def _axis_angle(q):
    axis, angle = dqlab.axis_angle_from_quaternion(q)
    return np.r_[axis, angle]


@hidden("ch3-ex1")
def hamilton_product_on_new_pairs(hamilton_product):
    """hamilton_product multiplies new pairs, large and small, pure and real"""
    def sample(rng):
        q1, q2 = rng.normal(size=(2, 4)) * 10.0 ** rng.uniform(-3, 3, (2, 1))
        if rng.random() < 0.2:
            q1[0] = 0.0                         # a pure quaternion
        if rng.random() < 0.2:
            q2[1:] = 0.0                        # a real one
        return q1, q2
    agrees(hamilton_product, dqlab.quaternion_product, sample, n=100, seed=301, atol=1e-6)


@hidden("ch3-ex1")
def hamilton_product_is_own_code(hamilton_product):
    """hamilton_product computes the product itself, with dot and cross, not with dqlab"""
    agrees(hamilton_product, dqlab.quaternion_product, lambda rng: tuple(rng.normal(size=(2, 4))),
           n=5, seed=302, forbid=("dqlab",))


@hidden("ch3-ex2")
def rotate_on_new_vectors(rotate):
    """rotate turns new vectors by new unit quaternions, either sign"""
    def sample(rng):
        q = rng.normal(size=4)
        return q / np.linalg.norm(q) * rng.choice([-1.0, 1.0]), rng.normal(0, 5, 3)
    agrees(rotate, dqlab.rotate_vector, sample, n=100, seed=303)


@hidden("ch3-ex2")
def rotate_is_own_code(rotate):
    """rotate applies the rotation formula itself, not dqlab.rotate_vector"""
    def sample(rng):
        q = rng.normal(size=4)
        return q / np.linalg.norm(q), rng.normal(size=3)
    agrees(rotate, dqlab.rotate_vector, sample, n=5, seed=304, forbid=("dqlab",))


@hidden("ch3-ex4")
def axis_angle_near_the_identity_and_the_half_turn(axis_angle):
    """axis_angle is right for tiny angles, nearly half turns, the identity and negative w"""
    def sample(rng):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        angle = rng.choice([1e-9, 1e-4, np.pi - 1e-6, rng.uniform(0, np.pi)])
        q = np.r_[np.cos(angle / 2), np.sin(angle / 2) * n]
        return (q * rng.choice([-1.0, 1.0]),)
    agrees(axis_angle, _axis_angle, sample, n=100, seed=305, atol=1e-8)
    for identity in ([1.0, 0, 0, 0], [-1.0, 0, 0, 0]):
        assert np.allclose(axis_angle(np.array(identity)), [1.0, 0, 0, 0]), "at the identity"


@hidden("ch3-ex4")
def axis_angle_is_own_code(axis_angle):
    """axis_angle computes the axis and angle itself, not with dqlab"""
    def sample(rng):
        q = rng.normal(size=4)
        return (q / np.linalg.norm(q),)
    agrees(axis_angle, _axis_angle, sample, n=5, seed=306, forbid=("dqlab",))
