"""Hidden tests of chapter 4, rigid transformations."""

import numpy as np
from dqlab_grading import agrees, hidden

import dqlab


def _transform(rng):
    """A random rigid transform."""
    q = rng.normal(size=4)
    X = np.eye(4)
    X[:3, :3] = dqlab.matrix_from_quaternion(q / np.linalg.norm(q))
    X[:3, 3] = rng.normal(0, 2, 3)
    return X


@hidden("ch4-ex1")
def invert_on_new_transforms(invert):
    """invert gives X^-1 of new transforms, as np.linalg.inv does"""
    agrees(invert, np.linalg.inv, lambda rng: (_transform(rng),), n=100, seed=401)


@hidden("ch4-ex1")
def invert_is_own_code(invert):
    """invert uses the block formula, not dqlab or np.linalg"""
    agrees(invert, np.linalg.inv, lambda rng: (_transform(rng),), n=5, seed=402,
           forbid=("dqlab", "numpy.linalg.inv", "numpy.linalg.solve", "numpy.linalg.pinv"))


@hidden("ch4-ex2")
def compose_blocks_on_new_pairs(compose_blocks):
    """compose_blocks gives X_AB X_BC for new pairs of transforms"""
    agrees(compose_blocks, lambda A, B: A @ B, lambda rng: (_transform(rng), _transform(rng)),
           n=100, seed=403)


@hidden("ch4-ex2")
def compose_blocks_is_own_code(compose_blocks):
    """compose_blocks multiplies the blocks itself, not with dqlab.compose"""
    agrees(compose_blocks, lambda A, B: A @ B, lambda rng: (_transform(rng), _transform(rng)),
           n=5, seed=404, forbid=("dqlab",))


@hidden("ch4-ex4")
def transforms_commute_on_screws(transforms_commute):
    """transforms_commute says True for motions along one screw axis, False for random pairs"""
    rng = np.random.default_rng(405)
    for _ in range(20):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        c = rng.normal(size=3)
        pair = []
        for _ in range(2):
            angle, d = rng.uniform(-3, 3), rng.normal()
            R = dqlab.rotations.matrix_from_axis_angle(n, angle)
            X = np.eye(4)
            X[:3, :3], X[:3, 3] = R, c - R @ c + d * n
            pair.append(X)
        assert transforms_commute(*pair), "two motions along one screw axis commute"
        assert not transforms_commute(_transform(rng), _transform(rng)), (
            "two random motions do not commute")
