"""Hidden tests of chapter 5, dual quaternions."""

import numpy as np
from dqlab_grading import agrees, hidden

import dqlab


def _motion(rng):
    """A random unit dual quaternion."""
    q = rng.normal(size=4)
    return dqlab.dual_quaternion_from_rotation_translation(q / np.linalg.norm(q),
                                                          rng.normal(0, 2, 3))


def _derivatives(q1, q2, l1=0.3, l2=0.2):
    return np.array([-l1 * np.sin(q1) - l2 * np.sin(q1 + q2), -l2 * np.sin(q1 + q2)])


@hidden("ch5-ex1")
def tip_x_derivatives_at_new_angles(tip_x_derivatives):
    """tip_x_derivatives gives both partial derivatives at new joint angles, several turns"""
    agrees(tip_x_derivatives, _derivatives, lambda rng: tuple(rng.uniform(-10, 10, 2)), n=100,
           seed=501, atol=1e-12)


@hidden("ch5-ex1")
def tip_x_derivatives_on_dual_numbers(tip_x_derivatives, Dual):
    """tip_x_derivatives evaluates x on dual numbers (the chapter's Dual), not with dqlab"""
    agrees(tip_x_derivatives, _derivatives, lambda rng: tuple(rng.uniform(-3, 3, 2)), n=5,
           seed=502, atol=1e-12, forbid=("dqlab",), require=(Dual,))


@hidden("ch5-ex2")
def dq_log_inverts_dq_exp(dq_log, dq_exp):
    """dq_log is the inverse of the text's dq_exp: a pure dual quaternion whose exp is Q"""
    rng = np.random.default_rng(503)
    for _ in range(50):
        Q = _motion(rng)
        Q = Q if Q[0] >= 0 else -Q                  # rotation angle in [0, pi]
        eta = np.asarray(dq_log(Q), dtype=float)
        assert eta.shape == (8,), f"dq_log returns shape {eta.shape}"
        assert abs(eta[0]) < 1e-9 and abs(eta[4]) < 1e-9, "dq_log(Q) is not pure"
        back = dq_exp(eta)
        assert np.allclose(back, Q, atol=1e-9) or np.allclose(back, -Q, atol=1e-9), (
            f"dq_exp(dq_log(Q)) = {np.round(back, 6)} for Q = {np.round(Q, 6)}")


@hidden("ch5-ex2")
def my_sclerp_on_new_motions(my_sclerp):
    """my_sclerp interpolates new pairs of motions as dqlab.sclerp does"""
    agrees(my_sclerp, dqlab.sclerp, lambda rng: (_motion(rng), _motion(rng), rng.uniform(0, 1)),
           n=100, seed=504)


@hidden("ch5-ex2")
def my_sclerp_is_own_code(my_sclerp):
    """my_sclerp goes through dq_log and dq_exp, not through dqlab's ScLERP or power"""
    agrees(my_sclerp, dqlab.sclerp, lambda rng: (_motion(rng), _motion(rng), rng.uniform(0, 1)),
           n=5, seed=505, forbid=("dqlab.sclerp", "dqlab.dualquat.dual_quaternion_power"))


@hidden("ch5-ex3")
def printed_right_side_is_the_printed_formula(printed_right_side):
    """printed_right_side transcribes the printed cross products (no dqlab)"""
    def printed(q, t):
        w, v = q[0], q[1:]
        return -t + (-2 * w * np.cross(v, -t) + 2 * np.cross(v, np.cross(v, -t)))

    def sample(rng):
        q = rng.normal(size=4)
        return q / np.linalg.norm(q), rng.normal(size=3)
    agrees(printed_right_side, printed, sample, n=20, seed=506, forbid=("dqlab",))


@hidden("ch5-ex3")
def what_it_equals_is_minus_r_transpose_t(what_it_equals):
    """what_it_equals is -q^-1 t q, that is -R^T t"""
    def minus_rt_t(q, t):
        return -dqlab.matrix_from_quaternion(q).T @ t

    def sample(rng):
        q = rng.normal(size=4)
        return q / np.linalg.norm(q), rng.normal(size=3)
    agrees(what_it_equals, minus_rt_t, sample, n=50, seed=507)


@hidden("ch5-ex4")
def inverse_by_conjugate_is_the_conjugate(inverse_by_conjugate):
    """inverse_by_conjugate inverts new transforms through the conjugate, not a matrix inverse"""
    def sample(rng):
        return (dqlab.transform_from_dual_quaternion(_motion(rng)),)
    agrees(inverse_by_conjugate, np.linalg.inv, sample, n=20, seed=508,
           forbid=("dqlab.transform_inverse", "numpy.linalg.inv", "numpy.linalg.solve",
                   "dqlab.dual_quaternion_inverse"))
