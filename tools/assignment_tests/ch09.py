"""Hidden tests of chapter 9, differential kinematics."""

import numpy as np
from dqlab_grading import agrees, hidden

import dqlab

#: Solvers that dls_by_svd must not use (the exercise allows np.linalg.svd only).
_SOLVERS = ("numpy.linalg.solve", "numpy.linalg.inv", "numpy.linalg.pinv", "numpy.linalg.lstsq",
            "dqlab")


def _dls(J, x_dot, lam):
    return J.T @ np.linalg.solve(J @ J.T + lam**2 * np.eye(len(J)), x_dot)


def _jacobian_speed_damping(rng):
    m, n = rng.choice([2, 3, 6]), rng.choice([6, 7])
    J = rng.normal(size=(m, n))
    if rng.random() < 0.5:                       # nearly singular: two rows almost equal
        J[-1] = J[0] + 1e-7 * rng.normal(size=n)
    return J, rng.normal(size=m), rng.uniform(0.005, 0.5)


def _radial(q):
    return np.array([np.cos(q[0]), np.sin(q[0]), 0.0, 0.0])


def _stretched(rng):
    return (np.array([rng.uniform(-2.5, 2.5), 0.0, rng.uniform(0.0, 0.15),
                      rng.uniform(-3.0, 3.0)]),)


@hidden("ch9-ex1")
def dls_by_svd_on_new_jacobians(dls_by_svd):
    """dls_by_svd gives the damped speeds of new Jacobians, wide and nearly singular"""
    agrees(dls_by_svd, _dls, _jacobian_speed_damping, n=100, seed=901, atol=1e-8)


@hidden("ch9-ex1")
def dls_by_svd_uses_the_svd_only(dls_by_svd):
    """dls_by_svd uses np.linalg.svd and no solver (solve, inv, pinv, lstsq, dqlab)"""
    agrees(dls_by_svd, _dls, _jacobian_speed_damping, n=5, seed=902, atol=1e-8, forbid=_SOLVERS,
           require=("numpy.linalg.svd",))


@hidden("ch9-ex2")
def lost_direction_from_the_jacobian(lost_direction):
    """lost_direction is computed from the SCARA's Jacobian and is the radial direction"""
    agrees(lost_direction, _radial, _stretched, n=20, seed=903, atol=1e-9, forbid=(),
           require=("dqlab.jacobian.scara_jacobian",))


@hidden("ch9-ex3")
def u5_from_fk_reads_the_frames(u5_from_fk, u5_of):
    """u5_from_fk reads the frames of the forward kinematics, not the chapter's formula u5_of"""
    agrees(u5_from_fk, u5_of, lambda rng: (rng.uniform(-7, 7, 6),), n=50, seed=904, atol=1e-12,
           forbid=(u5_of,), require=("dqlab.robot.Robot.fk",))


@hidden("ch9-ex6")
def printed_formula_jacobian_as_printed(printed_formula_jacobian):
    """printed_formula_jacobian applies z_{i-1} x (o_6 - o_{i-1}), z_{i-1} as printed"""
    report = dqlab.models.ur3_mdh()

    def as_printed(q):
        frames = report.fk(q, all_frames=True)
        z, o, p = frames[:6, :3, 2], frames[:6, :3, 3], frames[-1, :3, 3]
        return np.vstack([np.cross(z, p - o).T, z.T])
    agrees(printed_formula_jacobian, as_printed, lambda rng: (rng.uniform(-3, 3, 6),), n=20,
           seed=905, atol=1e-12)


@hidden("ch9-ex6")
def corrected_jacobian_from_the_frames(corrected_jacobian):
    """corrected_jacobian builds the columns from the frames, not with the robot's Jacobian"""
    report = dqlab.models.ur3_mdh()
    agrees(corrected_jacobian, report.jacobian, lambda rng: (rng.uniform(-7, 7, 6),), n=20,
           seed=906, atol=1e-12,
           forbid=("dqlab.jacobian", "dqlab.robot.Robot.jacobian",
                   "dqlab.robot.Robot.fk_with_jacobian"))
