"""Hidden tests of chapter 6, describing a manipulator."""

import numpy as np
from dqlab_grading import agrees, hidden

import dqlab


def _elementary(alpha, a, theta, r):
    """R_x(alpha) T_x(a) R_z(theta) T_z(r), multiplied out by numpy."""
    def rot(axis, angle):
        X = np.eye(4)
        c, s = np.cos(angle), np.sin(angle)
        i, j = (1, 2) if axis == "x" else (0, 1)
        X[i, i], X[i, j], X[j, i], X[j, j] = c, -s, s, c
        return X

    def slide(axis, d):
        X = np.eye(4)
        X["xyz".index(axis), 3] = d
        return X
    return rot("x", alpha) @ slide("x", a) @ rot("z", theta) @ slide("z", r)


@hidden("ch6-ex1")
def mdh_transform_on_new_parameters(mdh_transform):
    """mdh_transform is R_x(alpha) T_x(a) R_z(theta) T_z(r) for new parameters"""
    agrees(mdh_transform, _elementary,
           lambda rng: (rng.uniform(-7, 7), rng.normal(0, 2), rng.uniform(-7, 7),
                        rng.normal(0, 2)), n=100, seed=601)


@hidden("ch6-ex1")
def mdh_transform_is_own_code(mdh_transform):
    """mdh_transform multiplies the factors out itself, without dqlab"""
    agrees(mdh_transform, _elementary, lambda rng: tuple(rng.uniform(-3, 3, 4)), n=5, seed=602,
           forbid=("dqlab",))


@hidden("ch6-ex2")
def columns_for_batches(x_column, z_column):
    """x_column and z_column take joint vectors of any batch shape and match the 6R arm's fk"""
    six_r = dqlab.models.six_r()
    q = np.random.default_rng(603).uniform(-7, 7, (3, 4, 6))
    R = six_r.fk(q)[..., :3, :3]
    for name, column, k in (("x_column", x_column, 0), ("z_column", z_column, 2)):
        got = np.asarray(column(q))
        assert got.shape == (3, 4, 3), f"{name} of shape (3, 4, 6) gives shape {got.shape}"
        assert np.allclose(got, R[..., k], atol=1e-12), f"{name} differs from the fk's column"


@hidden("ch6-ex2")
def columns_are_own_code(x_column, z_column):
    """x_column and z_column use the notes' closed form, not dqlab's forward kinematics"""
    six_r = dqlab.models.six_r()
    for column, k in ((x_column, 0), (z_column, 2)):
        agrees(column, lambda q, k=k: six_r.fk(q)[..., :3, k],
               lambda rng: (rng.uniform(-3, 3, 6),), n=5, seed=604, forbid=("dqlab",))


@hidden("ch6-ex4")
def report_from_ur_for_batches(report_from_ur, X_UR_rep, ur3_report_layout):
    """report_from_ur maps batches of UR angles to the report's, giving the same flange"""
    ur3 = dqlab.models.ur3()
    q_ur = np.random.default_rng(605).uniform(-7, 7, (4, 5, 6))
    q_rep = np.asarray(report_from_ur(q_ur))
    assert q_rep.shape == q_ur.shape, f"shape {q_rep.shape} for input of shape {q_ur.shape}"
    assert np.allclose(X_UR_rep @ ur3_report_layout.fk(q_rep), ur3.fk(q_ur), atol=1e-12)


@hidden("ch6-ex5")
def standard_from_modified_on_new_arms(standard_from_modified):
    """standard_from_modified keeps every pose of new random modified-DH arms"""
    from dqlab.robot import Link, Robot
    rng = np.random.default_rng(606)
    for n in (2, 4, 6):
        links = [Link(a=rng.normal(0, 0.3), alpha=rng.uniform(-3, 3), d=rng.normal(0, 0.3),
                      theta_offset=rng.uniform(-3, 3)) for _ in range(n)]
        arm = Robot(links, convention="mdh")
        arm_dh = standard_from_modified(arm)
        assert arm_dh.convention == "dh", f"a {n}-joint arm comes back in {arm_dh.convention}"
        q = rng.uniform(-np.pi, np.pi, (50, n))
        assert np.allclose(arm_dh.fk(q), arm.fk(q), atol=1e-12), (
            f"a random {n}-joint arm: the flange poses differ")
