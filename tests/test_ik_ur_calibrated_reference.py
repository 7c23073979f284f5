"""The readable reference of a calibrated UR's inverse kinematics
(``dqlab.ik.ur_calibrated_reference``) against the fast solver (``dqlab.ik.ur`` on a
calibrated arm, ``dqlab.ik.ur_calibrated``), on the six real calibrations of
``tests/data/real_calibrations``: seeded random configurations, and configurations within
a milliradian of the wrist (theta_5 = 0 or pi) and elbow (theta_3 = 0) singularities.

Measured (seed 20261128, 30 random and 18 near-singular configurations per arm, 288 poses;
the fast path as installed, compiled or not, which are tested equal elsewhere; a pose's
solutions are its valid rows and those beyond them, ``result.more``):
- random poses: 179 of 180 have the same solutions in both, 176 the same rows branch by
  branch (the others: the same solutions under other branch labels). The rows agree to
  9e-11 rad (7e-12 at the poses neither flags ``near_singular``). The one pose whose
  solutions differ has a solution near a singularity (flagged ``near_singular`` by both):
  the fast solver finds eight and solutions beyond them, the reference seven. Both find the
  configuration each target came from, every time.
- near-singular configurations (within a milliradian of theta_5 = 0, pi or theta_3 = 0): 97
  of 108 have the same solution sets, 87 the same rows; the rows both hold agree to
  1.6e-8 rad (both take three Newton steps more near a singularity of the exact arm). 16
  poses have solutions beyond their rows in the fast solver, 15 in the reference. At the
  other 11, where a pose has nine or ten solutions, or solutions that do not follow the
  exact arm's branches, the two repairs start from different points and one of them
  misses one to four solutions the other finds. The generating configuration: the fast
  solver 105 of 108, the reference 100 (97 and 94 among the rows alone).
The test asserts what holds, with a margin: every valid row of both is a solution; the same
sets on all but two random poses, which both flag near_singular, and on 85 % of the poses
near a singularity; the same flags where the rows are the same; the generating configuration
on every random pose, and near a singularity by the reference on 85 % of the poses, at most
seven fewer than the fast solver. Rows agree to 1e-9 rad at the poses neither solver flags
near_singular, 1e-7 at the random ones, 1e-6 rad (the solvers' own test of one solution)
near a singularity.
"""

import numpy as np
import pytest
from real_calibrations import real_calibrations
from scipy.spatial.transform import Rotation

from dqlab.ik import ur
from dqlab.ik.targets import pose_errors
from dqlab.ik.ur_calibrated_reference import calibrated_ur_reference, newton_step
from dqlab.models import ur5e
from dqlab.rotations import wrap_angle

RANDOM, NEAR = 30, 18                  # configurations per calibration: random, near-singular
SAME = 1e-6                            # two joint vectors are one solution (as the solvers say)


def _configurations(rng):
    q = rng.uniform(-np.pi, np.pi, (RANDOM + NEAR, 6))
    third = NEAR // 3
    near = q[RANDOM:]
    near[:third, 4] = rng.uniform(-1e-3, 1e-3, third)                   # wrist, theta_5 = 0
    near[third:2 * third, 4] = np.pi + rng.uniform(-1e-3, 1e-3, third)  # wrist, theta_5 = pi
    near[2 * third:, 2] = rng.uniform(-1e-3, 1e-3, NEAR - 2 * third)    # elbow, theta_3 = 0
    return q


def _contains(rows, q):
    return len(rows) > 0 and bool(np.abs(wrap_angle(rows - q)).max(axis=-1).min() < SAME)


def _every(result, i):
    """Every solution of pose i: its valid rows and those beyond them (``result.more``)."""
    return np.concatenate([result.solutions[i][result.valid[i]],
                           result.more.solutions[i][result.more.valid[i]]])


@pytest.fixture(scope="module")
def solved():
    """Per calibration: the configurations, the fast result and the reference's."""
    rng = np.random.default_rng(20261128)
    out = {}
    for name, robot in real_calibrations().items():
        q = _configurations(rng)
        X = robot.fk(q)
        out[name] = (robot, q, ur(robot, X), calibrated_ur_reference(robot, X))
    return out


def _compare(fast, reference, i):
    """For pose i: whether the valid rows are the same rows (branch by branch), the same
    set, and the largest joint difference of the rows both hold."""
    A, B = _every(fast, i), _every(reference, i)
    same_set = (all(_contains(A, x) for x in B) and all(_contains(B, x) for x in A))
    both = fast.valid[i] & reference.valid[i]
    gap = np.abs(wrap_angle(fast.solutions[i] - reference.solutions[i]))[both].max(initial=0.0)
    same_rows = bool(np.array_equal(fast.valid[i], reference.valid[i]) and gap < SAME)
    return same_rows, same_set, gap


def test_the_reference_and_the_fast_solver_give_the_same_solutions(solved):
    counts = {"random": np.zeros(3), "near": np.zeros(3)}     # poses, same rows, same sets
    largest_gap = {"random": 0.0, "near": 0.0, "regular": 0.0}   # regular: not near_singular
    for robot, q, fast, reference in solved.values():
        for result in (fast, reference):                      # every valid row is a solution
            pe, re = pose_errors(robot.fk(result.solutions), robot.fk(q)[:, None])
            assert pe[result.valid].max() <= 1e-9 and re[result.valid].max() <= 1e-9
        for i in range(q.shape[0]):
            kind = "random" if i < RANDOM else "near"
            same_rows, same_set, gap = _compare(fast, reference, i)
            counts[kind] += (1, same_rows, same_set)
            if same_rows:
                largest_gap[kind] = max(largest_gap[kind], gap)
                if not fast.flags["near_singular"][i]:
                    largest_gap["regular"] = max(largest_gap["regular"], gap)
            if not same_set and kind == "random":       # only at a near-singular pose
                assert fast.flags["near_singular"][i] and reference.flags["near_singular"][i]
            if same_rows and same_set:      # then the flags agree too (not_converged counts
                assert all(fast.flags[k][i] == reference.flags[k][i]   # the solutions beyond
                           for k in fast.flags), i                     # the rows as well)
            if same_rows and not same_set:  # the one with an odd count says one is missing
                odd = [(r.valid[i].sum() + r.more.valid[i].sum()) % 2 for r in (fast, reference)]
                assert all(r.flags["not_converged"][i] for r, o in zip((fast, reference), odd,
                                                                         strict=True) if o), i
    poses, same_rows, same_sets = counts["random"]
    assert same_sets >= poses - 2 and same_rows >= 0.95 * poses
    poses, same_rows, same_sets = counts["near"]
    assert same_sets >= 0.85 * poses and same_rows >= 0.6 * poses
    assert largest_gap["regular"] < 1e-9
    assert largest_gap["random"] < 1e-7 and largest_gap["near"] < SAME


def test_the_reference_finds_the_generating_configuration(solved):
    found = {"random": [], "near": []}
    for _robot, q, fast, reference in solved.values():
        for i in range(q.shape[0]):
            kind = "random" if i < RANDOM else "near"
            found[kind].append([_contains(_every(r, i), q[i]) for r in (fast, reference)])
    random, near = np.array(found["random"]), np.array(found["near"])
    assert random.all()                                       # both, every random pose
    assert near[:, 1].sum() >= near[:, 0].sum() - 7 and near[:, 1].mean() >= 0.85


def test_newton_step_is_the_damped_normal_equations():
    """One step from a joint vector 1e-3 rad off: the step of (J^T J + lambda I) d = J^T e,
    and the error it returns is the larger of the position and rotation errors."""
    robot = ur5e()
    q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    X_target = robot.fk(q)
    q0 = q + 1e-3 * np.array([1.0, -1.0, 2.0, 0.5, -0.5, 1.0])
    step, error = newton_step(robot, q0, X_target)
    X = robot.fk(q0)
    rotation = Rotation.from_matrix(X_target[:3, :3] @ X[:3, :3].T).as_rotvec()   # (scipy's)
    e = np.concatenate([X_target[:3, 3] - X[:3, 3], rotation])
    gauss_newton = np.linalg.lstsq(robot.jacobian(q0), e, rcond=None)[0]
    assert np.abs(step - gauss_newton).max() < 1e-5 * np.abs(step).max()   # sin vs angle
    assert error == pytest.approx(max(pose_errors(X, X_target)), rel=1e-5)
    assert np.abs(q0 + step - q).max() < 1e-5                     # quadratic: 1e-3 -> ~1e-6
