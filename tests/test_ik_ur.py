"""Tests of the closed-form UR inverse kinematics, :func:`dqlab.ik.ur`.

Oracles: the project's forward kinematics (``robot.fk``), recomputed independently of the
solver's own residuals, and ``ur_analytic_ik`` (C++ implementation of Hawkins' UR IK). Both
use UR's standard DH frames: base frame at the foot of joint 1, z up; flange frame of the
standard DH chain (z along the last joint axis); no tool. ``ur_analytic_ik``'s
``*_with_tcp(pose, X_6T)`` variants solve for ``pose @ inv(X_6T)``, our ``tool=X_6T``.
So the two solvers answer the same question without any frame conversion.
"""


import numpy as np
import pytest

from dqlab._fast import ur_engine as engine
from dqlab.dualquat import dual_quaternion_from_transform
from dqlab.ik import IKResult, ur, ur_parameters
from dqlab.ik import ur_closed_form as urmod
from dqlab.ik.ur_steps import candidate_solutions
from dqlab.models import ur3
from dqlab.robot import Link, Robot
from dqlab.testing import quiet_stdout

try:
    import ur_analytic_ik as uik
except ImportError:  # the test extra brings it; without it only the cross-checks skip
    uik = None
needs_uik = pytest.mark.skipif(uik is None, reason="ur_analytic_ik (test extra) is absent")

TWO_PI = 2.0 * np.pi
THESIS_Q = np.array([0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0])
UR3 = dict(d1=0.1519, a2=-0.24365, a3=-0.21325, d4=0.11235, d5=0.08535, d6=0.0819)


@pytest.fixture(scope="module")
def robot():
    return ur3()



def uik_solutions(module, poses):
    with quiet_stdout():
        return [np.array(module.inverse_kinematics(np.ascontiguousarray(T))).reshape(-1, 6)
                for T in poses]


def wrapped(x):
    return np.angle(np.exp(1j * np.asarray(x)))


def fk_errors(robot, q, T):
    """Independent residuals: position (m) and rotation angle (rad) of fk(q) against T."""
    X = robot.fk(q)
    dp = np.linalg.norm(X[..., :3, 3] - T[..., :3, 3], axis=-1)
    E = np.swapaxes(X[..., :3, :3], -1, -2) @ T[..., :3, :3]
    v = np.stack([E[..., 2, 1] - E[..., 1, 2], E[..., 0, 2] - E[..., 2, 0],
                  E[..., 1, 0] - E[..., 0, 1]], axis=-1)
    angle = np.arctan2(np.linalg.norm(v, axis=-1), np.trace(E, axis1=-2, axis2=-1) - 1.0)
    return dp, angle


def recovery_error(result, q):
    """Smallest joint-wise (mod 2 pi) distance from q to a valid solution, shape (...)."""
    d = np.abs(wrapped(result.solutions - np.asarray(q)[..., None, :])).max(axis=-1)
    return np.where(result.valid, d, np.inf).min(axis=-1)


def assert_reproduces(robot, result, T, tol=1e-9):
    """Every valid row reproduces its target (independent FK) and nothing is NaN."""
    assert np.all(np.isfinite(result.solutions))
    assert np.all(result.solutions[~result.valid] == 0.0)
    assert np.all(np.abs(result.solutions) <= np.pi)
    assert np.all(result.solutions[result.valid] > -np.pi)
    Tb = np.broadcast_to(np.asarray(T)[..., None, :, :], result.solutions.shape[:-1] + (4, 4))
    dp, da = fk_errors(robot, result.solutions[result.valid], Tb[result.valid])
    assert dp.size == 0 or dp.max() <= tol, dp.max()
    assert da.size == 0 or da.max() <= tol, da.max()


def shoulder_margin(q, p=UR3):
    """h = cos(t1) x5 + sin(t1) y5 of a configuration: 0 at the shoulder singularity."""
    t2, t3, t4 = q[..., 1], q[..., 2], q[..., 3]
    return (p["a2"] * np.cos(t2) + p["a3"] * np.cos(t2 + t3)
            + p["d5"] * np.sin(t2 + t3 + t4))


# --------------------------------------------------------------------------------------
# The big round trip


@needs_uik
@pytest.mark.slow
def test_round_trip_100k_against_fk_and_ur_analytic_ik(robot):
    rng = np.random.default_rng(20260521)
    q = rng.uniform(-np.pi, np.pi, (100_000, 6))
    T = robot.fk(q)
    result = ur(robot, T)
    assert isinstance(result, IKResult)
    assert result.solutions.shape == (100_000, 8, 6)

    # 1. every valid solution reproduces the pose to 1e-9 m and 1e-9 rad (independent FK)
    assert_reproduces(robot, result, T, tol=1e-9)
    assert not result.flags["unreachable"].any()

    # 2. the generating configuration is among the solutions for every non-singular pose
    regular = ((np.abs(np.sin(q[:, 2])) > 1e-6) & (np.abs(np.sin(q[:, 4])) > 1e-6)
               & (np.abs(shoulder_margin(q)) > 1e-6))
    assert regular.mean() > 0.999
    err = recovery_error(result, q)
    assert err[regular].max() < 1e-8, err[regular].max()

    # 3. as many solutions as ur_analytic_ik: it deduplicates (to 1e-12) and FK-filters
    # (1e-9 per matrix entry); on random configurations no pose is near a boundary, and
    # the counts agree on every pose (>= 99.9 % required). Where they can differ is shown
    # by test_counts_near_boundaries_versus_ur_analytic_ik.
    theirs = np.array([len(s) for s in uik_solutions(uik.ur3, T)])
    agree = np.mean(result.count == theirs)
    assert agree >= 0.999, agree
    # the residuals of the fast mode are those of forward kinematics
    fk_mode = ur(robot, T[:5000], residuals="fk")
    np.testing.assert_array_equal(fk_mode.valid, result.valid[:5000])
    assert fk_mode.position_error[fk_mode.valid].max() < 1e-14
    assert fk_mode.rotation_error[fk_mode.valid].max() < 1e-13


@needs_uik
def test_counts_near_boundaries_versus_ur_analytic_ik(robot):
    """Poses within 1e-14 .. 1e-4 of a singularity, where the two solvers may disagree.

    Every disagreement found is near a singularity (some valid row within 1e-6 of it:
    |sin t3|, |sin t5| or h / d4 below 1e-6), and comes from how each solver treats it:

    - shoulder: ur_analytic_ik takes sqrt(x5^2 + y5^2 - d4^2) without clipping; where
      rounding makes the argument negative it gets NaN and returns no solution at all,
      where rounding makes it positive it returns both t1 roots, split by the noise (about
      1e-8 apart). We clip: the double root is returned once per shoulder branch and
      flagged.
    - elbow: it snaps sin^2(t3) < 1e-12 to zero, which merges the two genuine elbow
      branches t3 = +-e for |e| up to 1e-6, and it deduplicates without wrapping, so
      t3 = pi and t3 = -pi count as two.
    - wrist: at t5 = 0 (or pi) the solutions form a continuum. It returns up to two
      members per branch (t6 = 0 and t6 = -pi after snapping its atan2 arguments below
      1e-12 to zero), or drops branches through its 1e-9 per-entry FK filter; we return
      one member per branch, the one nearest q_ref's t6 that the arm reaches (equal rows
      for the two wrist branches), flagged.

    All our valid rows reproduce the pose to 1e-9 (checked); where ur_analytic_ik lists
    more distinct rows than we do, it is one of the cases above.
    """
    rng = np.random.default_rng(7)
    n = 3000
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    kind = rng.integers(0, 3, n)
    tiny = 10.0 ** rng.uniform(-14, -4, n) * rng.choice([-1.0, 1.0], n)
    at = rng.choice([0.0, np.pi], n)
    q[kind == 0, 2] = (at + tiny)[kind == 0]
    q[kind == 1, 4] = (at + tiny)[kind == 1]
    sel = np.flatnonzero(kind == 2)
    v = -(UR3["a2"] * np.cos(q[sel, 1]) + UR3["a3"] * np.cos(q[sel, 1] + q[sel, 2]))
    v /= UR3["d5"]
    sel, v = sel[np.abs(v) <= 1], v[np.abs(v) <= 1]
    q[sel, 3] = np.arcsin(v) + tiny[sel] - q[sel, 1] - q[sel, 2]
    T = robot.fk(q)
    result = ur(robot, T)
    assert_reproduces(robot, result, T)
    assert result.count.min() >= 2
    theirs = uik_solutions(uik.ur3, T)
    count = np.array([len(s) for s in theirs])
    distinct = urmod.distinct_solutions(result, atol=1e-12).sum(axis=-1)
    differ = np.flatnonzero(distinct != count)
    assert 0 < len(differ) < n
    sin3 = np.abs(np.sin(result.solutions[..., 2]))
    sin5 = np.abs(np.sin(result.solutions[..., 4]))
    near = np.where(result.valid, np.minimum(sin3, sin5), np.inf).min(axis=-1)
    near = np.minimum(near, np.abs(shoulder_margin(q)) / UR3["d4"])
    assert near[differ].max() < 1e-6
    more = np.flatnonzero(count > distinct)
    for i in more:
        pi_twice = np.any(np.isclose(np.abs(theirs[i][:, 2]), np.pi, atol=1e-12))
        assert (result.flags["wrist_singular"][i] or result.flags["shoulder_singular"][i]
                or pi_twice), i


# --------------------------------------------------------------------------------------
# The thesis's run


def test_thesis_pose_is_singular_three_ways_and_has_one_solution(robot):
    """q = (0, -pi/2, 0, -pi/2, 0, 0): the arm stands straight up (section 4.5).

    - wrist: t5 = 0, so only t234 + t6 = -pi is fixed by the orientation;
    - elbow: t3 = 0, the arm is stretched, the wrist-1 point is on the outer boundary of
      the forearm's reach (|a2| + |a3| from the shoulder);
    - shoulder: h = a2 c2 + a3 c23 + d5 s234 = 0, the wrist centre is on the cylinder
      x5^2 + y5^2 = d4^2, the two t1 roots coincide;
    - and the wrist-singular family t6 -> t6 + u, t234 -> t234 - u would move the wrist-1
      point on a circle of radius d5 about the wrist centre, which here lies straight above
      it: every u != 0 puts it beyond the reach. So the pose has exactly one solution,
      the generating one, and all eight branches collapse onto it.

    The thesis prints four "combinations", all this one solution: t1 = 0 or 2 pi, t4 =
    -pi/2 or 3 pi/2, and t3 = +-2.98e-8 from acos(1 - 4.4e-16). That 3e-8 is not only the
    acos: at a stretched elbow a rounding of the position moves t3 by sqrt(eps) in any
    formula, so a correct solver may return anything within a few 1e-8 of t3 = 0 (ours
    happens to return 0 here); all of them reproduce the pose to 1e-16. ur_analytic_ik
    returns no solution here.
    """
    T = robot.fk(THESIS_Q)
    assert np.allclose(T[:3, 3], [0.0, -0.19425, 0.69415], atol=1e-12)
    assert np.allclose(T @ [0, 0, 0.2, 1], [0.0, -0.39425, 0.69415, 1.0], atol=1e-12)
    for q_ref in (None, [0, 0, 0, 0, 0, 0.7], [0, 0, 0, 0, 0, -2.5]):
        result = ur(robot, T, q_ref=q_ref)
        assert result.valid.all()
        assert {k: bool(v) for k, v in result.flags.items()} == {
            "wrist_singular": True, "shoulder_singular": True, "elbow_singular": True,
            "near_singular": True, "unreachable": False, "not_converged": False}
        assert result.reason == ""
        assert_reproduces(robot, result, T, tol=1e-15)
        # one solution: every row is the generating configuration, to sqrt(eps)
        assert np.abs(wrapped(result.solutions - THESIS_Q)).max() < 1e-7
        assert urmod.distinct_solutions(result, atol=1e-7).sum() == 1
    if uik is not None:
        with quiet_stdout():
            assert len(uik.ur3.inverse_kinematics(T)) == 0
    # just beyond the boundary: 1e-6 m higher is out of reach; 1e-12 m higher is within tol
    up = T.copy()
    up[2, 3] += 1e-6
    result = ur(robot, up)
    assert result.flags["unreachable"] and not result.valid.any()
    assert result.reason == urmod.REASON_OUTER
    assert np.all(result.solutions == 0.0)
    up[2, 3] = T[2, 3] + 1e-12
    result = ur(robot, up)
    assert result.valid.all() and result.flags["elbow_singular"]


def test_thesis_pose_as_its_program_stores_it(robot):
    """The pose file holds the dual quaternion; the same answer comes from it."""
    from dqlab.dualquat import dual_quaternion_from_transform

    Q = dual_quaternion_from_transform(robot.fk(THESIS_Q))
    result = ur(robot, Q)
    assert result.valid.all() and result.flags["wrist_singular"]
    assert np.abs(wrapped(result.solutions - THESIS_Q)).max() < 1e-7
    result_neg = ur(robot, -Q)  # -Q is the same pose
    np.testing.assert_allclose(result_neg.solutions, result.solutions, atol=1e-12)


# --------------------------------------------------------------------------------------
# Accuracy where the thesis's formulas lose it


def test_theta234_near_pi_recovers_configuration(robot):
    """(4.28) is 0/0 when t2 + t3 + t4 = pi; the half-angle atan2 forms are not."""
    rng = np.random.default_rng(11)
    q = rng.uniform(-np.pi, np.pi, (2000, 6))
    q[:, 2] = rng.uniform(0.3, 2.8, 2000) * rng.choice([-1, 1], 2000)
    q[:, 4] = rng.uniform(0.3, 2.8, 2000) * rng.choice([-1, 1], 2000)
    delta = rng.uniform(-1e-12, 1e-12, 2000)
    q[:, 3] = rng.choice([np.pi, -np.pi], 2000) + delta - q[:, 1] - q[:, 2]
    regular = np.abs(shoulder_margin(q)) > 1e-4
    T = robot.fk(q)
    result = ur(robot, T)
    assert_reproduces(robot, result, T)
    assert recovery_error(result, q)[regular].max() < 1e-9


@pytest.mark.parametrize("at", [0.0, np.pi, -np.pi])
def test_theta5_near_wrist_singularity(robot, at):
    """1e-6 <= |t5 - {0, pi}| <= 1e-3: recovered to 1e-8; the thesis divides by sin(t5/2)."""
    rng = np.random.default_rng(12)
    n = 2000
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, 2] = rng.uniform(0.3, 2.8, n) * rng.choice([-1, 1], n)
    off = 10.0 ** rng.uniform(-6, -3, n) * rng.choice([-1, 1], n)
    q[:, 4] = wrapped(at + off)
    # away from the shoulder singularity: there the rounding of the wrist centre moves t1
    # by eps d4 / h, which the wrist's 1 / sin(t5) amplifies (any solver)
    regular = np.abs(shoulder_margin(q)) > 1e-2
    T = robot.fk(q)
    result = ur(robot, T)
    assert_reproduces(robot, result, T)
    assert not result.flags["wrist_singular"].any()
    assert recovery_error(result, q)[regular].max() < 1e-8


@pytest.mark.parametrize("at", [0.0, np.pi])
@pytest.mark.parametrize("off", [0.0, 1e-15, 3e-12, 1e-10, 5e-8])
def test_theta5_at_wrist_singularity(robot, at, off):
    """Closer than singular_tol: flagged, and every returned row reproduces the pose."""
    rng = np.random.default_rng(13)
    n = 500
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, 2] = rng.uniform(0.3, 2.8, n) * rng.choice([-1, 1], n)
    q[:, 4] = at + off * rng.choice([-1, 1], n)
    T = robot.fk(q)
    for q_ref in (None, rng.uniform(-np.pi, np.pi, (n, 6)), np.full(6, 20.0)):
        result = ur(robot, T, q_ref=q_ref)
        assert_reproduces(robot, result, T)
        assert result.flags["wrist_singular"].all()
        assert not result.flags["unreachable"].any()
        # the generating configuration's branch is present: same t1, t5 and the
        # determined combination t234 -+ t6 (where the arm reaches t6_ref)
        t234 = q[:, 1] + q[:, 2] + q[:, 3]
        comb = t234 + q[:, 5] if at == 0.0 else t234 - q[:, 5]
        s = result.solutions
        s_comb = (s[..., 1] + s[..., 2] + s[..., 3]
                  + (s[..., 5] if at == 0.0 else -s[..., 5]))
        match = (result.valid
                 & (np.abs(wrapped(s[..., 0] - q[:, None, 0])) < 1e-6)
                 & (np.abs(wrapped(s_comb - comb[:, None])) < 1e-6))
        assert match.any(axis=-1).mean() > 0.99
    # with q_ref = the generating configuration, the exact member comes back
    result = ur(robot, T, q_ref=q)
    regular = np.abs(shoulder_margin(q)) > 1e-4
    assert recovery_error(result, q)[regular].max() < 1e-6


def test_elbow_singularity(robot):
    rng = np.random.default_rng(14)
    n = 500
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, 2] = rng.choice([0.0, np.pi], n)
    q[:, 4] = rng.uniform(0.3, 2.8, n)
    T = robot.fk(q)
    result = ur(robot, T)
    assert_reproduces(robot, result, T)
    assert result.flags["elbow_singular"].all()
    assert not result.flags["unreachable"].any()
    # the two elbow branches of the generating shoulder/wrist branch coincide
    err = recovery_error(result, q)
    assert err.max() < 1e-6   # sqrt(eps) conditioning of t3 at a straight/folded elbow
    regular = np.abs(shoulder_margin(q)) > 1e-4
    assert (urmod.distinct_solutions(result, atol=1e-6).sum(-1)[regular]
            < result.count[regular]).all()


def test_shoulder_singularity(robot):
    rng = np.random.default_rng(15)
    n = 800
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, 2] = rng.uniform(0.3, 2.8, n) * rng.choice([-1, 1], n)
    q[:, 4] = rng.uniform(0.3, 2.8, n)
    v = -(UR3["a2"] * np.cos(q[:, 1]) + UR3["a3"] * np.cos(q[:, 1] + q[:, 2])) / UR3["d5"]
    keep = np.abs(v) <= 0.99
    q, v = q[keep], v[keep]
    q[:, 3] = np.arcsin(v) - q[:, 1] - q[:, 2]
    assert np.abs(shoulder_margin(q)).max() < 1e-15
    T = robot.fk(q)
    result = ur(robot, T)
    assert_reproduces(robot, result, T)
    assert result.flags["shoulder_singular"].all()
    assert recovery_error(result, q).max() < 1e-6
    # both shoulder branches give the same t1
    t1 = result.solutions[..., 0]
    both = result.valid[:, :4].any(-1) & result.valid[:, 4:].any(-1)
    assert both.mean() > 0.99
    assert np.abs(wrapped(t1[:, 0] - t1[:, 4]))[result.valid[:, 0] & result.valid[:, 4]].max() \
        < 1e-6


def test_just_beyond_the_shoulder_cylinder(robot):
    """Wrist centre 1e-6 m inside the cylinder of radius d4: unreachable, with reason."""
    rng = np.random.default_rng(16)
    q = rng.uniform(-np.pi, np.pi, (200, 6))
    q[:, 2] = rng.uniform(0.5, 2.5, 200)
    q[:, 4] = rng.uniform(0.5, 2.5, 200)
    v = -(UR3["a2"] * np.cos(q[:, 1]) + UR3["a3"] * np.cos(q[:, 1] + q[:, 2])) / UR3["d5"]
    keep = np.abs(v) <= 0.99
    q, v = q[keep], v[keep]
    q[:, 3] = np.arcsin(v) - q[:, 1] - q[:, 2]
    T = robot.fk(q)
    p5 = T[:, :3, 3] - UR3["d6"] * T[:, :3, 2]
    radial = p5[:, :2] / np.linalg.norm(p5[:, :2], axis=-1, keepdims=True)
    inside = T.copy()
    inside[:, :2, 3] -= 1e-6 * radial
    result = ur(robot, inside)
    assert result.flags["unreachable"].all()
    assert (result.reason == urmod.REASON_SHOULDER).all()
    assert not np.any(result.valid) and np.all(result.solutions == 0.0)
    # 1e-11 m inside is within tol: clipped, valid, flagged
    inside[:, :2, 3] = T[:, :2, 3] - 1e-11 * radial
    result = ur(robot, inside)
    assert result.success.all() and result.flags["shoulder_singular"].all()
    assert result.position_error[result.valid].max() < 1e-9


def test_just_beyond_the_outer_reach(robot):
    """A stretched arm whose target moves 1e-6 m further out: that branch is lost, and its
    residual is exactly the distance beyond the reach, in both residual modes."""
    rng = np.random.default_rng(26)
    n = 300
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, 2] = 0.0
    q[:, 4] = rng.uniform(0.5, 2.5, n)
    keep = np.abs(shoulder_margin(q)) > 1e-2
    q = q[keep]
    frames = robot.fk(q, all_frames=True)
    T = frames[:, -1].copy()
    u = frames[:, 3, :3, 3] - frames[:, 1, :3, 3]        # shoulder -> wrist-1 point
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    beyond = T.copy()
    beyond[:, :3, 3] += 1e-6 * u
    for mode in ("equations", "fk"):
        result = ur(robot, beyond, residuals=mode)
        assert_reproduces(robot, result, beyond)
        # rows of the generating shoulder and wrist branch: t1 and t5 as generated
        same = ((np.abs(wrapped(ur(robot, T).solutions[..., 0] - q[:, None, 0])) < 1e-9)
                & (np.abs(wrapped(ur(robot, T).solutions[..., 4] - q[:, None, 4])) < 1e-9))
        assert same.sum(axis=-1).min() == 2                 # the two (equal) elbow rows
        assert not result.valid[same].any()
        np.testing.assert_allclose(result.position_error[same], 1e-6, rtol=1e-6)


def test_far_and_near_targets_are_unreachable_with_reasons(robot):
    T = np.eye(4)
    T[:3, 3] = [2.0, 0.3, 0.4]                  # 2 m away: beyond every branch
    result = ur(robot, T)
    assert result.flags["unreachable"] and result.reason == urmod.REASON_OUTER
    # wrist centre exactly on the base axis: inside the shoulder cylinder
    T = np.eye(4)
    T[:3, 3] = [0.0, 0.0, 0.3 + UR3["d6"]]
    result = ur(robot, T)
    assert result.flags["unreachable"] and result.reason == urmod.REASON_SHOULDER
    # (an inner-reach failure on every branch cannot happen on a UR: the two wrist
    # branches put the wrist-1 point 2 d5 apart, more than 2 ||a2| - |a3||)
    assert 2 * UR3["d5"] > 2 * abs(abs(UR3["a2"]) - abs(UR3["a3"]))


@pytest.mark.filterwarnings("error")
def test_far_targets_are_unreachable_with_their_distance(robot):
    """Targets from 10 m to 1e300 m away, on a bare arm and on one with a base and a tool,
    alone, in a batch and in both residual modes, without a warning: no valid row, every
    row's error the distance (beyond R5 / eps, the steps are not run: far_wrist) or the
    clipping distance below it, never 0 or NaN; closest_ur_solution refuses them; a
    position whose distance overflows is refused naming the target."""
    from dqlab.ik import closest_ur_solution
    from dqlab.ik.ur_steps import far_wrist
    from dqlab.rotations import rot_z

    q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    based = ur3().with_tool(z=0.15)
    based.base = np.eye(4)
    based.base[:3, :3], based.base[:3, 3] = rot_z(0.7), (0.1, -0.2, 0.3)
    distances = np.array([10.0, 1e10, 1e15, 1e17, 1e77, 1e100, 1e154, 1e156, 1e200, 1e300])
    directions = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0],
                           [-0.6, 0.0, 0.8]])
    for arm in (robot, based):
        T = np.repeat(arm.fk(q)[None], distances.size * len(directions), axis=0)
        T[:, :3, 3] = (distances[:, None, None] * directions).reshape(-1, 3)
        D = np.linalg.norm(T[:, :3, 3] / distances.repeat(len(directions))[:, None],
                           axis=-1) * distances.repeat(len(directions))
        results = [ur(arm, T), ur(arm, T, residuals="fk")]
        results += [ur(arm, X, residuals=mode) for X in T[::7] for mode in ("equations", "fk")]
        for result in results:
            assert not result.valid.any() and result.flags["unreachable"].all()
            assert np.isfinite(result.position_error).all()
        for result in results[:2]:
            # within the arm's size (below 1 m) of the distance, to rounding
            gap = np.abs(result.position_error - D[:, None])
            assert (gap <= 1.0 + 1e-15 * D[:, None]).all(), gap.max()
            far = D > 1e16
            assert (result.reason[far] == urmod.REASON_FAR).all()
            assert (result.reason[~far] != urmod.REASON_FAR).all()
        with pytest.raises(ValueError, match="no solution: the wrist centre is farther"):
            closest_ur_solution(arm, T[-1], q)
    assert far_wrist((1e100, 0.0, 0.0), *(UR3[k] for k in ("d1", "a2", "a3", "d4", "d5"))) \
        == 1e100
    T = based.fk(q)
    T[:3, 3] = (1.7e308, -1.7e308, 1.7e308)
    with pytest.raises(ValueError, match="target: a position is so far"):
        ur(based, T)


def test_random_targets_never_raise_and_modes_agree(robot):
    """Random poses, most unreachable: no NaN, no exception, the same valid mask whether
    the residuals come from the equations or from forward kinematics."""
    from dqlab.rotations import matrix_from_axis_angle

    rng = np.random.default_rng(17)
    n = 5000
    T = np.tile(np.eye(4), (n, 1, 1))
    axis = rng.normal(size=(n, 3))
    T[:, :3, :3] = matrix_from_axis_angle(axis, rng.uniform(0, np.pi, n))
    T[:, :3, 3] = rng.uniform(-0.6, 0.6, (n, 3))
    fast = ur(robot, T)
    slow = ur(robot, T, residuals="fk")
    np.testing.assert_array_equal(fast.valid, slow.valid)
    assert 0.05 < fast.flags["unreachable"].mean() < 0.95
    assert_reproduces(robot, fast, T)
    assert set(fast.reason[fast.flags["unreachable"]]) <= {
        urmod.REASON_SHOULDER, urmod.REASON_OUTER, urmod.REASON_INNER,
        urmod.REASON_REACH}
    assert (fast.reason[~fast.flags["unreachable"]] == "").all()
    # the analytic residuals are the FK distances wherever a row was clipped
    np.testing.assert_allclose(fast.position_error, slow.position_error,
                               atol=1e-12, rtol=1e-9)
    assert slow.rotation_error.max() < 1e-12
    if uik is not None:
        theirs = np.array([len(s) for s in uik_solutions(uik.ur3, T)])
        assert np.mean(theirs == fast.count) > 0.999


# --------------------------------------------------------------------------------------
# Conventions, order, inputs


def test_solution_order(robot):
    rng = np.random.default_rng(18)
    q = rng.uniform(-np.pi, np.pi, (3000, 6))
    T = robot.fk(q)
    result = ur(robot, T)
    s = result.solutions
    p5 = T[:, :3, 3] - UR3["d6"] * T[:, :3, 2]
    h = np.cos(s[..., 0]) * p5[:, None, 0] + np.sin(s[..., 0]) * p5[:, None, 1]
    v = result.valid
    assert np.all(h[:, :4][v[:, :4]] >= -1e-12) and np.all(h[:, 4:][v[:, 4:]] <= 1e-12)
    for k in range(8):
        e, w = (k >> 1) & 1, k & 1
        sin3 = np.sin(s[v[:, k], k, 2])
        t5 = s[v[:, k], k, 4]
        assert np.all(sin3 >= 0) if e == 0 else np.all(sin3 <= 0)
        assert np.all(t5 >= 0) if w == 0 else np.all(t5 <= 0)
    assert urmod.SOLUTION_ORDER[5] == ("right", "up", "flip")


@pytest.mark.parametrize("layout", ["C", "F", "strided"])
def test_finish_zeroes_the_invalid_rows_in_any_memory_layout(layout):
    """finish() zeroes rows by row numbers in C order and with the targets last in memory
    (the batch UR solver's layout), and by a mask otherwise; NaN rows included."""
    from dqlab.ik.result import finish

    rng = np.random.default_rng(5)
    solutions = rng.normal(size=(3, 4, 8, 6))
    solutions[0, 1, 2] = np.nan
    valid = rng.random((3, 4, 8)) < 0.6
    valid[0, 1, 2] = False
    if layout == "F":
        solutions, valid = np.asfortranarray(solutions), np.asfortranarray(valid)
    elif layout == "strided":
        solutions, valid = solutions[:, ::2], valid[:, ::2]
    expected = np.where(valid[..., None], solutions, 0.0)
    result = finish(solutions, valid, np.zeros(valid.shape), np.zeros(valid.shape), {})
    assert result.solutions is solutions
    np.testing.assert_array_equal(result.solutions, expected)


def test_batch_result_is_the_poses_first_view_of_the_rows():
    """A batch is solved with the poses last in memory; the result's arrays are poses-first
    views of those rows (chunked and reshaped), equal to one pose's own result."""
    robot = ur3()
    rng = np.random.default_rng(8)
    n = 7 * (2 * engine.CHUNK // 7 + 1)                         # three blocks
    T = robot.fk(rng.uniform(-np.pi, np.pi, (n, 6)))
    T[5, :3, 3] *= 5.0                                            # no solution
    result = ur(robot, T.reshape(7, -1, 4, 4))
    assert result.solutions.shape == (7, n // 7, 8, 6)
    assert result.solutions.base is not None and result.valid.shape == (7, n // 7, 8)
    flat = result.solutions.reshape(n, 8, 6)
    valid = result.valid.reshape(n, 8)
    assert not valid[5].any() and np.all(flat[5] == 0.0)
    assert np.all(flat[~valid] == 0.0) and (~valid).sum() > 100
    for i in (0, 5, engine.CHUNK, n - 1):
        one = ur(robot, T[i])
        np.testing.assert_array_equal(one.valid, valid[i])
        np.testing.assert_allclose(one.solutions, flat[i], rtol=0, atol=1e-12)


@pytest.mark.parametrize("lead", [(), (1,), (7,), (2, 3)])
def test_batch_shapes_match_single(robot, lead):
    rng = np.random.default_rng(19)
    q = rng.uniform(-np.pi, np.pi, lead + (6,))
    T = robot.fk(q)
    result = ur(robot, T)
    assert result.solutions.shape == lead + (8, 6)
    assert result.valid.shape == result.position_error.shape == lead + (8,)
    assert result.reason.shape == lead
    assert all(f.shape == lead for f in result.flags.values())
    for idx in np.ndindex(*lead):
        single = ur(robot, T[idx])
        # one pose goes through math's sin and cos, a batch through numpy's: the last bit
        # may differ (see test_single_pose_path_equals_the_batch_path)
        np.testing.assert_allclose(single.solutions, result.solutions[idx], rtol=0, atol=1e-12)
        np.testing.assert_array_equal(single.valid, result.valid[idx])


def offset_ur3():
    """The UR3 with joint offsets (as a controller with another zero would have)."""
    links = [Link(a=lk.a, alpha=lk.alpha, d=lk.d, theta_offset=off)
             for lk, off in zip(ur3().links, [0.1, -np.pi / 2, 0.0, -np.pi / 2, 0.3, np.pi],
                                strict=True)]
    return Robot(links, name="UR3 with offsets")


def poses_of_every_kind(robot):
    """Regular, singular (wrist, elbow, shoulder, the thesis's pose), near-singular and
    unreachable poses (beyond reach, inside the shoulder cylinder) of one robot."""
    rng = np.random.default_rng(41)
    q = rng.uniform(-np.pi, np.pi, (600, 6))
    q[100:150, 4] = rng.choice([0.0, np.pi, 1e-5, np.pi - 1e-4, 2e-3], 50)   # wrist
    q[150:200, 2] = rng.choice([0.0, np.pi, 1e-9, 3e-7], 50)                  # elbow
    v = -(UR3["a2"] * np.cos(q[200:250, 1]) + UR3["a3"] * np.cos(q[200:250, 1]
                                                                  + q[200:250, 2])) / UR3["d5"]
    q[200:250, 3] = np.arcsin(np.clip(v, -1, 1)) - q[200:250, 1] - q[200:250, 2]  # shoulder
    q[250] = THESIS_Q
    q -= [lk.theta_offset for lk in robot.links]          # the DH angles above, as joints
    T = robot.fk(q)
    T[250:260, :3, 3] *= 5.0                                       # beyond reach
    T[260:270, :3, 3] = [0.0, 0.0, 0.3]                            # wrist centre near the axis
    T[260:270, :3, :3] = np.eye(3)
    return T


@pytest.mark.parametrize("which", ["ur3", "offsets", "dual quaternions", "q_ref", "loose tol"])
def test_single_pose_path_equals_the_batch_path(which):
    """One pose at a time runs the steps on Python floats (math), a batch on arrays
    (numpy); poses that need the batch path's extra work (the wrist family, reasons) are
    handed to it. Both must give the same result on every kind of pose, also with a tol
    loose enough (2e-2) that a wrist within 0.005 rad of its singularity is at it (a member
    of a wrist family), which the float path alone would solve otherwise."""
    from dqlab.dualquat import dual_quaternion_from_transform

    robot = offset_ur3() if which == "offsets" else ur3()
    T = poses_of_every_kind(robot)
    poses = dual_quaternion_from_transform(T) if which == "dual quaternions" else T
    kw = {"q_ref": [0.0, 0.0, 0.0, 0.0, 0.0, 1.0]} if which == "q_ref" else {}
    if which == "loose tol":
        kw = {"tol": 2e-2}
        sin5 = np.abs(np.sin(ur(robot, T).solutions[..., 4]))
        assert ((sin5 > 1e-3) & (sin5 < 5e-3)).any(axis=-1).sum() >= 5   # such wrists
    batch = ur(robot, poses, **kw)
    assert batch.flags["wrist_singular"].sum() > 10 and batch.flags["elbow_singular"].sum() > 10
    assert batch.flags["shoulder_singular"].sum() > 10 and batch.flags["unreachable"].sum() >= 20
    fast = 0
    for i, pose in enumerate(poses):
        single = ur(robot, pose, **kw)
        fast += engine.solve_single(robot, ur_parameters(robot), pose, 1e-9, 5e-7, 1e-9,
                                    None) is not None
        np.testing.assert_array_equal(single.valid, batch.valid[i])
        # math's and numpy's sin and cos may differ in the last bit, which the elbow angles
        # amplify by 1 / |sin theta3| near a straight or folded elbow
        sin3 = np.maximum(np.abs(np.sin(batch.solutions[i, :, 2])), 1e-9)
        assert np.all(np.abs(single.solutions - batch.solutions[i])
                      <= 1e-12 + 4e-15 / sin3[:, None])
        np.testing.assert_allclose(single.position_error, batch.position_error[i], rtol=0,
                                   atol=1e-15)
        np.testing.assert_array_equal(single.rotation_error, batch.rotation_error[i])
        for name, flag in batch.flags.items():
            assert single.flags[name].shape == () and single.flags[name] == flag[i], name
        assert single.reason.shape == () and single.reason == batch.reason[i]
    assert 450 < fast < len(poses)            # most poses take the float path, not all


def test_dual_quaternion_input_matches_matrix_input(robot):
    from dqlab.dualquat import dual_quaternion_from_transform

    rng = np.random.default_rng(20)
    q = rng.uniform(-np.pi, np.pi, (500, 6))
    T = robot.fk(q)
    Q = dual_quaternion_from_transform(T)
    a, b = ur(robot, T), ur(robot, Q)
    np.testing.assert_array_equal(a.valid, b.valid)
    np.testing.assert_allclose(a.solutions, b.solutions, atol=1e-12)
    c = ur(robot, robot.fk_dq(q[0]))
    assert recovery_error(c, q[0]) < 1e-10


def test_rounded_pose_from_a_file(robot):
    """The thesis's pose file holds rounded dual-quaternion coefficients: rejected by the
    default check, solved (as the nearest rigid pose) with a loosened pose_tol."""
    from dqlab.dualquat import dual_quaternion_from_transform

    rng = np.random.default_rng(27)
    q = rng.uniform(-np.pi, np.pi, (200, 6))
    Q = np.round(dual_quaternion_from_transform(robot.fk(q)), 6)
    with pytest.raises(ValueError, match="target"):
        ur(robot, Q)
    for mode in ("equations", "fk"):
        result = ur(robot, Q, pose_tol=1e-5, residuals=mode)
        assert result.success.all()
        assert result.position_error[result.valid].max() < 1e-12
        err = recovery_error(result, q)       # the rounding moved the pose a little
        assert np.median(err) < 1e-4 and err.max() < 1e-2


def test_invalid_inputs_raise(robot):
    T = robot.fk(np.zeros(6))
    bad = T.copy()
    bad[0, 0] = 1.1
    with pytest.raises(ValueError, match="target"):
        ur(robot, bad)
    bad = T.copy()
    bad[3, 0] = 0.5
    with pytest.raises(ValueError):
        ur(robot, bad)
    with pytest.raises(ValueError, match="target"):
        ur(robot, np.array([1.0, 0, 0, 0, 0, 1, 0, 0]) * 1.01)
    with pytest.raises(ValueError, match="target"):
        ur(robot, np.array([1.0, 0, 0, 0, 1.0, 0, 0, 0]))   # <q_r, q_d> != 0
    with pytest.raises(ValueError, match="shape"):
        ur(robot, np.eye(3))
    nan = np.tile(T, (3, 1, 1))
    nan[1, 0, 3] = np.nan
    with pytest.raises(ValueError):
        ur(robot, nan)
    with pytest.raises(ValueError, match="UR"):
        ur(Robot([Link(0, 0, 0)] * 6), T)
    from dqlab.models import ur3_mdh

    with pytest.raises(ValueError):
        ur(ur3_mdh(), T)
    with pytest.raises(ValueError, match="residuals"):
        ur(robot, T, residuals="maybe")
    with pytest.raises(ValueError, match="q_ref"):
        ur(robot, T, q_ref=[0.0] * 5)
    with pytest.raises(ValueError, match="q_ref"):
        ur(robot, np.stack([T, T, T]), q_ref=np.zeros((2, 6)))


# --------------------------------------------------------------------------------------
# Tool, base, offsets, other UR models


def test_tool_and_base(robot):
    from dqlab.rotations import matrix_from_axis_angle
    from dqlab.transforms import transform_from

    rng = np.random.default_rng(21)
    X_6T = transform_from(matrix_from_axis_angle([1, 2, 3], 0.7), [0.01, -0.02, 0.15])
    X_W0 = transform_from(matrix_from_axis_angle([0, 1, 1], 2.0), [1.0, -0.5, 0.2])
    q = rng.uniform(-np.pi, np.pi, (300, 6))
    # tool given to ur(): pose = fk(q) @ X_6T
    T = robot.fk(q) @ X_6T
    result = ur(robot, T, tool=X_6T)
    assert recovery_error(result, q).max() < 1e-9
    if uik is None:
        return
    with quiet_stdout():
        theirs = [uik.ur3.inverse_kinematics_with_tcp(np.ascontiguousarray(X), X_6T)
                  for X in T[:50]]
    for i, sols in enumerate(theirs):
        assert len(sols) == result.count[i]
        for s in sols:
            d = np.abs(wrapped(result.solutions[i] - s)).max(-1)
            assert np.where(result.valid[i], d, np.inf).min() < 1e-9
    # tool and base on the robot
    equipped = ur3()
    equipped.base = X_W0
    equipped.tool = X_6T
    T = equipped.fk(q)
    for mode in ("equations", "fk"):
        result = ur(equipped, T, residuals=mode)
        assert recovery_error(result, q).max() < 1e-9
        assert_reproduces(equipped, result, T)
    # a tool given to ur() replaces the robot's
    X_6S = transform_from(matrix_from_axis_angle([0, 0, 1], 0.3), [0.0, 0.05, 0.1])
    T2 = T @ np.linalg.inv(X_6T) @ X_6S
    for mode in ("equations", "fk"):
        result = ur(equipped, T2, tool=X_6S, residuals=mode)
        assert recovery_error(result, q).max() < 1e-9
        assert result.position_error[result.valid].max() < 1e-12
    with pytest.raises(ValueError, match="tool"):
        ur(equipped, T2, tool=2 * np.eye(4))


def test_joint_offsets_are_honoured():
    links = [Link(a=lk.a, alpha=lk.alpha, d=lk.d, theta_offset=off)
             for lk, off in zip(ur3().links, [0.1, -np.pi / 2, 0.0, -np.pi / 2, 0.3, np.pi],
                                strict=True)]
    robot = Robot(links, name="UR3 with offsets")
    rng = np.random.default_rng(22)
    q = rng.uniform(-np.pi, np.pi, (500, 6))
    T = robot.fk(q)
    result = ur(robot, T)
    assert_reproduces(robot, result, T)
    assert recovery_error(result, q).max() < 1e-9


#: e-series DH values as Universal Robots publish them (the ones ur_analytic_ik uses)
E_SERIES = {"ur3e": dict(d=(0.15185, 0, 0, 0.13105, 0.08535, 0.0921),
                         a=(0, -0.24355, -0.2132, 0, 0, 0)),
            "ur5e": dict(d=(0.1625, 0, 0, 0.1333, 0.0997, 0.0996),
                         a=(0, -0.425, -0.3922, 0, 0, 0))}


@needs_uik
@pytest.mark.parametrize("name", ["ur5", "ur10", "ur3e", "ur5e"])
def test_other_ur_models(name):
    import dqlab.models as models

    if name in E_SERIES:
        alpha = (np.pi / 2, 0, 0, np.pi / 2, -np.pi / 2, 0)
        dh = E_SERIES[name]
        robot = Robot([Link(a=a, alpha=al, d=d)
                       for a, al, d in zip(dh["a"], alpha, dh["d"], strict=True)])
        X = getattr(uik, name).forward_kinematics(0.1, -1.0, 1.2, 0.3, 0.8, -0.5)
        np.testing.assert_allclose(robot.fk([0.1, -1.0, 1.2, 0.3, 0.8, -0.5]), X,
                                   atol=1e-12)
    else:
        robot = getattr(models, name)()
    rng = np.random.default_rng(23)
    q = rng.uniform(-np.pi, np.pi, (3000, 6))
    T = robot.fk(q)
    result = ur(robot, T)
    assert_reproduces(robot, result, T)
    assert recovery_error(result, q).max() < 1e-8
    theirs = np.array([len(s) for s in uik_solutions(getattr(uik, name), T)])
    assert np.mean(theirs == result.count) >= 0.999


@needs_uik
def test_every_ur_analytic_ik_solution_is_ours(robot):
    rng = np.random.default_rng(24)
    q = rng.uniform(-np.pi, np.pi, (2000, 6))
    T = robot.fk(q)
    result = ur(robot, T)
    for i, sols in enumerate(uik_solutions(uik.ur3, T)):
        for s in sols:
            d = np.abs(wrapped(result.solutions[i] - s)).max(-1)
            assert np.where(result.valid[i], d, np.inf).min() < 1e-9


# --------------------------------------------------------------------------------------
# Helpers


def readable_rows(robot, X):
    """The rows of the readable path, ur_steps.candidate_solutions, for the robot's lengths."""
    p = ur_parameters(robot)
    return candidate_solutions(X, *(p[k] for k in ("d1", "a2", "a3", "d4", "d5", "d6")))


def poses_off_the_wrist_family(robot):
    """Regular poses, elbow- and shoulder-singular ones, theta234 = pi, wrists near (not at)
    the singularity and unreachable targets: every kind of pose on which dqlab.ik.ur
    computes its rows without choosing a member of a wrist family."""
    rng = np.random.default_rng(42)
    q = rng.uniform(-np.pi, np.pi, (700, 6))
    q[100:150, 4] = rng.choice([1e-2, -2e-3, np.pi - 1e-2, 3e-3 - np.pi], 50)      # wrist
    q[150:200, 2] = rng.choice([0.0, np.pi, 1e-9, 3e-7], 50)                     # elbow
    v = -(UR3["a2"] * np.cos(q[200:250, 1]) + UR3["a3"] * np.cos(q[200:250, 1]
                                                                  + q[200:250, 2])) / UR3["d5"]
    q[200:250, 3] = np.arcsin(np.clip(v, -1, 1)) - q[200:250, 1] - q[200:250, 2]  # shoulder
    q[250:300, 3] = np.pi - q[250:300, 1] - q[250:300, 2]                       # theta234
    T = robot.fk(q)
    T[300:310, :3, 3] *= 5.0                                       # beyond reach
    T[310:320, :3, 3] = [0.0, 0.0, 0.3]                            # wrist centre near the axis
    return T


def test_engine_equals_the_readable_path(robot):
    """Every row dqlab.ik.ur marks valid is, bit for bit, the row of the readable path
    ur_steps.candidate_solutions: a batch (the engine's arrays over all branches at once, in
    blocks) against the readable path on arrays, one pose (the engine's float path) against
    it on floats, on every kind of pose off the wrist family."""
    T = poses_off_the_wrist_family(robot)
    batch = ur(robot, T)
    rows = readable_rows(robot, T)
    assert rows.shape == (len(T), 8, 6)
    assert batch.flags["elbow_singular"].sum() > 10 and batch.flags["shoulder_singular"].sum() > 10
    assert batch.flags["unreachable"].sum() >= 20 and batch.valid.sum() > 4500
    np.testing.assert_array_equal(batch.solutions[batch.valid], rows[batch.valid])
    floats = 0
    for X, valid in zip(T, batch.valid, strict=True):
        one = ur(robot, X)
        on_floats = engine.solve_single(robot, ur_parameters(robot), X, 1e-9, 5e-7, 1e-9,
                                        None) is not None
        floats += on_floats
        np.testing.assert_array_equal(one.valid, valid)
        # a pose the float path hands on is solved on arrays: the readable path on arrays
        rows = readable_rows(robot, X) if on_floats else readable_rows(robot, X[None])[0]
        np.testing.assert_array_equal(one.solutions[valid], rows[valid])
    assert floats > 600                        # most poses went through the float path
    # several blocks, the near-wrist rows included
    big = robot.fk(np.random.default_rng(43).uniform(-np.pi, np.pi, (2 * engine.CHUNK + 5, 6)))
    result = ur(robot, big)
    np.testing.assert_array_equal(result.solutions[result.valid],
                                  readable_rows(robot, big)[result.valid])


def test_the_readable_path_refuses_a_wrist_singular_pose(robot):
    """theta1 = 0 and theta5 = 0 exactly: the flange turned as at q = 0, the wrist centre at
    (x5, -d4); there only theta234 + theta6 is determined, and dqlab.ik.ur chooses."""
    X = np.eye(4)
    X[:3, :3] = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]
    X[:3, 3] = [0.3, -UR3["d4"] - UR3["d6"], 0.2]
    with pytest.raises(ValueError, match="wrist-singular"):
        readable_rows(robot, X)
    with pytest.raises(ValueError, match="wrist-singular"):
        readable_rows(robot, np.stack([robot.fk(np.ones(6)), X]))
    result = ur(robot, X)
    assert result.flags["wrist_singular"] and result.count == 8
    assert_reproduces(robot, result, X)
    with pytest.raises(ValueError, match="X must have bottom row"):
        readable_rows(robot, 2 * X)


def test_a_pose_as_a_list_takes_the_path_of_the_same_array(robot):
    """ur(robot, X) and ur(robot, X.tolist()) are the same computation: bitwise equal."""
    T = poses_of_every_kind(robot)
    for target in (T, dual_quaternion_from_transform(T)):
        for X in target[::3]:
            a, b = ur(robot, X), ur(robot, X.tolist())
            for name in ("solutions", "valid", "position_error", "rotation_error", "reason"):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
            assert a.flags == b.flags


def test_distinct_solutions(robot):
    result = ur(robot, robot.fk(np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])))
    assert urmod.distinct_solutions(result).all()
    result = ur(robot, robot.fk(THESIS_Q))
    mask = urmod.distinct_solutions(result, atol=1e-7)
    assert mask.tolist() == [True] + [False] * 7


def test_wrap_angle():
    from dqlab.rotations import wrap_angle

    x = np.array([-np.pi, np.pi, -3 * np.pi, 3 * np.pi, 0.0, -1e-300, 7.0])
    w = wrap_angle(x)
    assert np.all(w > -np.pi) and np.all(w <= np.pi)
    assert np.allclose(np.exp(1j * w), np.exp(1j * x))


def test_the_flipped_wrist_is_the_other_sign_of_sigma():
    """wrist_angles with sigma = -1 is the wrist flip of sigma = +1: theta5 negated exactly,
    the half sum unchanged, the half difference turned by pi (to a rounding of pi), on
    arrays and (bitwise the same) on floats; the flipped wrist turns the same rotation."""
    from dqlab.ik.ur_steps import wrist_angles
    from dqlab.quaternion import quaternion_from_axis_angle, quaternion_product

    rng = np.random.default_rng(12)
    L = rng.normal(size=(4, 300))
    L /= np.linalg.norm(L, axis=0)
    theta5, half_sum, half_diff, c5, s5 = wrist_angles(tuple(L), 1.0)
    flip5, flip_sum, flip_diff, flip_c5, flip_s5 = wrist_angles(tuple(L), -1.0)
    np.testing.assert_array_equal(flip5, -theta5)
    np.testing.assert_array_equal(flip_sum, half_sum)
    np.testing.assert_array_equal(flip_c5, c5)
    np.testing.assert_array_equal(flip_s5, s5)
    assert np.abs(wrapped(flip_diff - half_diff - np.pi)).max() <= 4.5e-16
    assert np.all(np.abs(flip_diff) <= np.pi) and np.all(flip5 > -np.pi)
    both = wrist_angles(tuple(c[None] for c in L), np.array([[1.0], [-1.0]]))
    for k, sigma in enumerate((1.0, -1.0)):               # both branches at once: the same
        one = wrist_angles(tuple(L), sigma)
        for whole, part in zip(both, one, strict=True):
            np.testing.assert_array_equal(np.broadcast_to(whole, (2, 300))[k], part)
    for k in range(5):                                    # floats: the same formula
        one = wrist_angles(tuple(float(c) for c in L[:, k]), -1.0)
        assert one[:3] == (flip5[k], flip_sum[k], flip_diff[k])

    def wrist(t234, t5, t6):      # r_-y(theta234) r_-z(theta5) r_-y(theta6)
        minus_y, minus_z = np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, -1.0])
        return quaternion_product(quaternion_product(
            quaternion_from_axis_angle(minus_y, t234), quaternion_from_axis_angle(minus_z, t5)),
            quaternion_from_axis_angle(minus_y, t6))

    for k in range(20):
        a = wrist(half_sum[k] + half_diff[k], theta5[k], half_sum[k] - half_diff[k])
        b = wrist(half_sum[k] + flip_diff[k], flip5[k], half_sum[k] - flip_diff[k])
        assert min(np.abs(a - b).max(), np.abs(a + b).max()) < 1e-15
        np.testing.assert_allclose(np.abs(a), np.abs(L[:, k]), atol=1e-15)


def test_half_angle_cos_sin_without_trigonometry():
    """half_angle_cos_sin gives cos and sin of theta / 2 for theta in (-pi, pi], to a
    rounding, from cos theta and sin theta: on arrays and (bitwise the same) on floats,
    with cos(theta / 2) >= 0 and sin(pi / 2) = +1 whatever the sign of the zero sine."""
    from dqlab.ik.ur_steps import half_angle_cos_sin

    rng = np.random.default_rng(13)
    theta = np.concatenate([rng.uniform(-np.pi, np.pi, 2000),
                            [np.pi, 0.0, np.pi / 2, -np.pi / 2, np.nextafter(-np.pi, 0.0),
                             np.nextafter(np.pi / 2, 0.0), np.nextafter(np.pi / 2, 4.0)]])
    c, s = half_angle_cos_sin(np.cos(theta), np.sin(theta))
    assert np.abs(c - np.cos(theta / 2)).max() <= 4.5e-16
    assert np.abs(s - np.sin(theta / 2)).max() <= 4.5e-16
    assert np.all(c >= 0.0) and np.all(np.hypot(c, s) - 1.0 < 4.5e-16)
    for k in (0, 1, 2000, 2003, 2004, 2005, 2006):                  # floats: the same formula
        one = half_angle_cos_sin(float(np.cos(theta[k])), float(np.sin(theta[k])))
        assert one == (c[k], s[k])
    for zero in (0.0, -0.0):                                        # theta = pi
        assert half_angle_cos_sin(-1.0, zero) == (0.0, 1.0)
        assert [float(v[0]) for v in half_angle_cos_sin(np.array([-1.0]),
                                                        np.array([zero]))] == [0.0, 1.0]


def test_batch_solve_leaves_the_targets_as_they_were():
    """The flange poses are written over the components the solver reads: always a copy,
    never the caller's array, also when that is laid out component by component."""
    robot = ur3()
    q = np.random.default_rng(14).uniform(-np.pi, np.pi, (50, 6))
    T = np.ascontiguousarray(np.moveaxis(robot.fk(q), 0, -1))      # (4, 4, n) in memory
    T_view = np.moveaxis(T, -1, 0)                                  # (n, 4, 4), entries first
    Q = np.ascontiguousarray(dual_quaternion_from_transform(T_view).T).T    # (n, 8) view
    kept_T, kept_Q = T.copy(), Q.copy()
    for target in (T_view, Q):
        result = ur(robot, target)
        assert result.count.min() >= 2
    np.testing.assert_array_equal(T, kept_T)
    np.testing.assert_array_equal(Q, kept_Q)
    C_ordered = np.ascontiguousarray(np.moveaxis(kept_T, -1, 0))
    np.testing.assert_array_equal(ur(robot, T_view).solutions, ur(robot, C_ordered).solutions)


# --------------------------------------------------------------------------------------
# The errata are real: the thesis's formulas, evaluated in floating point


def _thesis_quantities(robot, q):
    """L = r_z(t1)^* q_D of the generating configurations (the thesis's M2 = N2 terms)."""
    from dqlab.ik.ur_steps import relative_rotation_coefficients
    from dqlab.quaternion import quaternion_from_matrix, quaternion_product

    T = robot.fk(q)
    q0_conj = np.array([np.sqrt(0.5), -np.sqrt(0.5), 0.0, 0.0])
    qD = quaternion_product(quaternion_from_matrix(T[..., :3, :3]), q0_conj)
    half1 = np.cos(0.5 * q[..., 0]), np.sin(0.5 * q[..., 0])
    return T, relative_rotation_coefficients(np.moveaxis(qD, -1, 0), half1)


def test_thesis_theta6_formula_fails_at_theta234_pi(robot):
    """(4.28) with (4.18)-(4.21): 0/0 at t2 + t3 + t4 = pi; the atan2 forms are exact."""
    rng = np.random.default_rng(30)
    q = rng.uniform(-np.pi, np.pi, (500, 6))
    q[:, 4] = rng.uniform(0.5, 2.5, 500)
    q[:, 3] = np.pi - q[:, 1] - q[:, 2]
    T, (Lw, Lx, Ly, Lz) = _thesis_quantities(robot, q)
    c5, s5 = np.cos(q[:, 4] / 2), np.sin(q[:, 4] / 2)
    alpha, beta, gamma, delta = Lw / c5, Lx / s5, -Ly / c5, -Lz / s5
    assert np.abs(gamma - beta).max() < 1e-14 and np.abs(alpha + delta).max() < 1e-14
    theta6_thesis = 2 * np.arctan2(gamma - beta, alpha + delta)
    assert np.abs(wrapped(theta6_thesis - q[:, 5])).max() > 0.5     # garbage
    result = ur(robot, T)
    regular = np.abs(shoulder_margin(q)) > 1e-2
    assert recovery_error(result, q)[regular].max() < 1e-9
    # away from that line the thesis's formula is right
    q[:, 3] += 1.0
    T, (Lw, Lx, Ly, Lz) = _thesis_quantities(robot, q)
    alpha, beta, gamma, delta = Lw / c5, Lx / s5, -Ly / c5, -Lz / s5
    theta6_thesis = 2 * np.arctan2(gamma - beta, alpha + delta)
    assert np.abs(wrapped(theta6_thesis - q[:, 5])).max() < 1e-12


def test_thesis_theta5_acos_loses_half_the_digits(robot):
    """(4.13) by acos near t5 = 0 against 2 atan2(s5bar, c5bar)."""
    rng = np.random.default_rng(31)
    q = rng.uniform(-np.pi, np.pi, (500, 6))
    q[:, 2] = rng.uniform(0.5, 2.5, 500)
    q[:, 4] = 1e-7
    T = robot.fk(q)
    x6, y6 = T[:, 0, 3], T[:, 1, 3]
    t1 = q[:, 0]
    arg = (x6 * np.sin(t1) - y6 * np.cos(t1) - UR3["d4"]) / UR3["d6"]
    theta5_thesis = np.arccos(np.clip(arg, -1, 1))
    thesis_error = np.abs(theta5_thesis - 1e-7)
    result = ur(robot, T)
    ours = result.solutions[..., 4]
    our_error = np.where(result.valid, np.abs(ours - 1e-7), np.inf).min(axis=-1)
    assert thesis_error.max() > 1e-9          # digits lost
    assert our_error.max() < 1e-14


def test_no_missed_solution_near_the_wrist_and_elbow_singularities_together(robot):
    """100,000 configurations with theta5 log-uniform within 1e-12..1e-5 of 0 (half of them
    of +-pi) and theta3 within 1e-4..1e-1 of 0 (a nearly stretched elbow), the other joints
    uniform. Near the wrist singularity theta234 is ill-conditioned; a row whose wrist-1
    point it pushes out of the forearm's reach moves within its wrist family instead of
    being declared unreachable. Every pose is solved, the generating configuration is among
    the valid rows (exactly, or as the member of its wrist family: same theta1, theta5 and
    theta234 -+ theta6, to 1e-6 rad), and every valid row reproduces the pose to 1e-9 m."""
    rng = np.random.default_rng(11)
    n = 100_000
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, 4] = rng.choice([-1.0, 1.0], n) * 10 ** rng.uniform(-12, -5, n)
    half = n // 2
    q[half:, 4] = rng.choice([-np.pi, np.pi], n - half) - q[half:, 4]
    q[:, 2] = rng.choice([-1.0, 1.0], n) * 10 ** rng.uniform(-4, -1, n)
    q = wrapped(q)
    T = robot.fk(q)
    result = ur(robot, T)
    assert result.success.all() and not result.flags["unreachable"].any()
    sol = result.solutions
    exact = (np.abs(wrapped(sol - q[:, None, :])).max(-1) < 1e-6) & result.valid
    near0 = np.abs(q[:, 4]) < 1.0
    theta234 = sol[..., 1] + sol[..., 2] + sol[..., 3]
    fixed = np.where(near0[:, None], theta234 + sol[..., 5], theta234 - sol[..., 5])
    q_fixed = np.where(near0, q[:, 1:4].sum(-1) + q[:, 5], q[:, 1:4].sum(-1) - q[:, 5])
    family = (result.valid
              & (np.abs(wrapped(sol[..., 0] - q[:, None, 0])) < 1e-6)
              & (np.abs(wrapped(sol[..., 4] - q[:, None, 4])) < 1e-6)
              & (np.abs(wrapped(fixed - q_fixed[:, None])) < 1e-6))
    assert (exact | family).any(-1).all()
    assert_reproduces(robot, result, T, tol=1e-9)


def test_ur_calls_the_solver_of_the_arms_kind():
    """dqlab.ik.ur (dqlab.ik.ur_solver) solves an exact UR by the closed form exact_ur, the
    same result to the last bit, and a calibrated UR by calibrated_ur; exact_ur refuses a
    calibrated arm (each time: the refusal is remembered) and says where it is solved."""
    from dqlab.identify import dh_parameters, robot_from_dh_parameters
    from dqlab.ik.ur_calibrated import calibrated_ur

    robot = ur3()
    q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    T = robot.fk(np.stack([q, -q]))
    for target in (T[0], T):
        a, b = ur(robot, target), urmod.exact_ur(robot, target)
        for name in ("solutions", "valid", "position_error", "rotation_error", "reason"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert a.row_names == b.row_names == urmod.ROW_NAMES
    calibrated = robot_from_dh_parameters(robot, dh_parameters(robot) + 1e-3)
    X = calibrated.fk(q)
    for _ in range(2):
        with pytest.raises(ValueError, match=r"a calibrated UR is solved by dqlab\.ik\.ur"):
            urmod.exact_ur(calibrated, X)
    a, b = ur(calibrated, X), calibrated_ur(calibrated, X)
    np.testing.assert_array_equal(a.solutions, b.solutions)
    assert a.row_names == urmod.ROW_NAMES and recovery_error(a, q) < 1e-9
