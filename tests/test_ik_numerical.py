"""Tests for dqlab.ik.numerical: damped least squares, full pose and position only."""

import time

import numpy as np
import pytest

from dqlab import dualquat
from dqlab.ik import damped_least_squares, numerical, pose_errors
from dqlab.ik.damped_least_squares import _cholesky_solve
from dqlab.models import desk_arm, scara_rsm5, ur3
from dqlab.robot import Link, Robot


def test_full_pose_from_a_nearby_warm_start_on_1000_random_ur3_poses():
    """>= 99 % converge; each converged answer reproduces the pose to 1e-9 m / 1e-9 rad."""
    rng = np.random.default_rng(50)
    robot = ur3()
    q_true = rng.uniform(-np.pi, np.pi, size=(1000, 6))
    q0 = q_true + rng.normal(scale=0.1, size=q_true.shape)
    X = robot.fk(q_true)
    start = time.perf_counter()
    result = numerical(robot, X, q0)
    elapsed = time.perf_counter() - start
    assert result.solutions.shape == (1000, 1, 6)
    assert result.valid.mean() >= 0.99
    ok = result.valid[:, 0]
    pe, re = pose_errors(robot.fk(result.solutions[ok, 0]), X[ok])
    assert pe.max() <= 1e-9 and re.max() <= 1e-9
    np.testing.assert_allclose(result.position_error[ok, 0], pe, atol=1e-15)
    # failures (if any) are reported, never returned as answers
    bad = ~ok
    assert np.all(result.solutions[bad] == 0.0)
    assert all("m" in r and ("converge" in r or "stalled" in r) for r in result.reason[bad])
    assert np.all(result.reason[ok] == "")
    assert elapsed < 5.0


def test_position_only_and_dual_quaternion_targets():
    rng = np.random.default_rng(51)
    robot = ur3()
    q_true = rng.uniform(-np.pi, np.pi, size=(300, 6))
    q0 = q_true + rng.normal(scale=0.1, size=q_true.shape)
    X = robot.fk(q_true)
    result = numerical(robot, X[:, :3, 3], q0, position_only=True)
    assert result.valid.mean() >= 0.99
    ok = result.valid[:, 0]
    reached = robot.fk(result.solutions[ok, 0])[:, :3, 3]
    assert np.linalg.norm(reached - X[ok, :3, 3], axis=-1).max() <= 1e-9
    assert np.all(result.rotation_error == 0.0)
    # a full pose with position_only reports the (unconstrained) rotation error
    with_pose = numerical(robot, X[:5], q0[:5], position_only=True)
    assert with_pose.valid.all()
    # dual quaternion targets
    Q = dualquat.dual_quaternion_from_transform(X[:20])
    by_dq = numerical(robot, Q, q0[:20])
    by_matrix = numerical(robot, X[:20], q0[:20])
    np.testing.assert_allclose(by_dq.solutions, by_matrix.solutions, atol=1e-8)


def test_unreachable_target_fails_with_a_reason():
    robot = ur3()
    X = robot.fk([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    X[:3, 3] = [1.0, 0.0, 0.3]                # the UR3 reaches about 0.5 m
    result = numerical(robot, X, np.zeros(6), max_iter=50)
    assert not result.success
    assert result.valid.shape == (1,) and result.reason.shape == ()
    assert np.all(result.solutions == 0.0)
    assert result.position_error[0] > 0.4
    assert "position error" in str(result.reason) and "rotation error" in str(result.reason)
    assert bool(result.flags["not_converged"])
    short = numerical(robot, robot.fk(np.ones(6)), np.zeros(6), max_iter=1)
    assert not short.success
    assert "did not converge after 1 iterations" in str(short.reason)


def test_joint_limits_are_respected():
    rng = np.random.default_rng(52)
    q_true = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    links = [Link(lk.a, lk.alpha, lk.d, limits=(q - 0.15, q + 0.15))
             for lk, q in zip(ur3().links, q_true, strict=True)]
    robot = Robot(links, name="UR3 with tight limits")
    q0 = q_true + rng.uniform(-0.3, 0.3, size=(50, 6))   # some starts outside the limits
    result = numerical(robot, robot.fk(q_true), q0)
    assert result.valid.all()
    lo, hi = robot.limits.T
    assert np.all((result.solutions >= lo) & (result.solutions <= hi))
    # a target only reachable beyond the limits is not reached
    outside = robot.fk(np.clip(q_true + 0.3, -np.pi, np.pi))
    assert not numerical(robot, outside, q_true).success


def test_prismatic_and_small_robots():
    rng = np.random.default_rng(53)
    scara = scara_rsm5()
    lo, hi = scara.limits.T
    q_true = rng.uniform(lo + 0.02, hi - 0.02, size=(100, 4))
    q_true[:, 2] = rng.uniform(0.02, 0.13, size=100)
    q0 = np.clip(q_true + rng.normal(scale=0.05, size=q_true.shape), lo, hi)
    result = numerical(scara, scara.fk(q_true), q0)
    assert result.valid.mean() >= 0.97
    arm = desk_arm()
    q = rng.uniform(-2, 2, size=(100, 3))
    p = arm.fk(q)[:, :3, 3]
    result = numerical(arm, p, q + 0.05, position_only=True)
    assert result.valid.mean() >= 0.97


def test_warm_started_path_like_the_report():
    """A circle of radius 5 cm in the (X, Z) plane, each point solved from the previous."""
    robot = ur3()
    q = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    centre = robot.fk(q)[:3, 3]
    u = np.linspace(0, 2 * np.pi, 100)
    R = 0.05
    path = centre + R * np.stack([-np.sin(u), 0 * u, np.cos(u) - 1], axis=-1)
    solutions = []
    for p in path:
        result = numerical(robot, p, q, position_only=True)
        assert result.success
        q = result.solutions[0]
        solutions.append(q)
    steps = np.abs(np.diff(np.array(solutions), axis=0)).max()
    assert steps < 0.1                         # a continuous joint path


def test_broadcasting_and_input_errors():
    robot = ur3()
    X = robot.fk([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    q0 = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2]) + np.linspace(-0.1, 0.1, 4)[:, None]
    result = numerical(robot, X, q0.reshape(2, 2, 6))
    assert result.solutions.shape == (2, 2, 1, 6)
    assert result.reason.shape == (2, 2) and result.flags["not_converged"].shape == (2, 2)
    with pytest.raises(ValueError, match="position_only"):
        numerical(robot, X[:3, 3], q0[0])
    with pytest.raises(ValueError, match="target must have shape"):
        numerical(robot, np.zeros(5), q0[0])
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 6\)"):
        numerical(robot, X, np.zeros(5))
    bad = X.copy()
    bad[0, 0] = 2.0
    with pytest.raises(ValueError):
        numerical(robot, bad, q0[0])


def test_an_exactly_singular_step_falls_back_to_least_squares(monkeypatch):
    """The batch solves with numpy, one target with its own Cholesky factorisation; both
    fall back to the least-squares step when their factorisation fails."""
    robot = ur3()
    q_true = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    X = robot.fk(q_true)

    def singular(*args, **kwargs):
        raise np.linalg.LinAlgError("Singular matrix")

    monkeypatch.setattr(np.linalg, "solve", singular)
    monkeypatch.setattr(damped_least_squares, "_cholesky_solve", lambda A, b: None)
    batch = numerical(robot, np.stack([X, X]), np.stack([q_true + 0.05, q_true - 0.05]))
    assert batch.success.all()
    assert numerical(robot, X, q_true + 0.05).success


def test_cholesky_solve_agrees_with_numpy_and_refuses_a_singular_matrix():
    rng = np.random.default_rng(14)
    for n in (1, 3, 4, 6, 7):
        J = rng.normal(size=(6, n))
        A = J.T @ J + 1e-3 * np.eye(n)
        b = rng.normal(size=n)
        x = _cholesky_solve(A.tolist(), b.tolist())
        assert type(x) is list and len(x) == n
        np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-12, atol=1e-14)
    # only the lower triangle is read
    A = np.array([[4.0, 99.0], [2.0, 5.0]])
    assert _cholesky_solve(A.tolist(), [2.0, 5.0]) == [0.0, 1.0]
    # exactly singular or indefinite: None
    for A in ([[1.0, 2.0], [2.0, 4.0]], [[1.0, 0.0], [0.0, -1.0]], [[0.0, 0.0], [0.0, 0.0]]):
        assert _cholesky_solve(A, [1.0, 1.0]) is None
    # then the step is the least-squares one: a Jacobian with a zero column (a joint that
    # does not move the tool) and no damping
    robot = ur3()
    q = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    _, J = robot.fk_with_jacobian(q)
    J[:, 2] = 0.0
    e = [1e-3, -2e-3, 5e-4, 1e-3, 0.0, -1e-3]
    options = damped_least_squares._Options(False, 1e-10, 1e-10, 100, 0.0, 0.0, 0.0, 1e6, 0.5,
                                            *robot.limits.T)
    step = np.array(damped_least_squares._step_one(J, q.tolist(), e, 0.0, options)) - q
    np.testing.assert_allclose(step, np.linalg.pinv(J) @ e, rtol=0, atol=1e-12)
    assert step[2] == 0.0


@pytest.mark.parametrize("n_poses", [2000, 10000])
def test_every_warm_started_pose_of_the_benchmark_is_solved(n_poses):
    """The 500 poses that benchmarks/bench_ik_ur.py solves one at a time (drawn as it draws
    them, with ``--n 2000`` and with its default): every one is solved, alone and in a batch,
    in a few iterations. Pose 111 is near the wrist singularity (sin q5 = 1.4e-3), where
    plain Levenberg--Marquardt damping that starts at 1e-2 takes 72 iterations."""
    robot = ur3()
    rng = np.random.default_rng(2026)
    q = rng.uniform(-np.pi, np.pi, (n_poses, 6))
    T = np.ascontiguousarray(robot.fk(q))
    q0 = q + rng.uniform(-0.1, 0.1, q.shape)
    T, q0 = T[:500], q0[:500]
    batch = numerical(robot, T, q0)
    assert batch.valid.all()
    iterations = []
    for X, g in zip(T, q0, strict=True):
        one = numerical(robot, X, g, history=True)
        assert one.success
        iterations.append(len(one.history["damping"]) - 1)
    assert np.mean(iterations) < 4.5 and max(iterations) <= 15
    if n_poses == 2000:
        assert abs(np.sin(q[111, 4])) < 1.5e-3 and iterations[111] <= 8


def test_near_the_wrist_singularity_a_step_may_raise_the_error(monkeypatch):
    """Poses within 1e-4 to 3e-3 rad of the wrist singularity (q5 near 0 or pi), warm-started
    0.1 rad away: all are solved, some after steps that raised the error E (the
    non-monotone test takes a step below the largest E of the last five iterates). With a
    test that requires every step to lower E, some are not solved within 100 iterations."""
    robot = ur3()
    rng = np.random.default_rng(7)
    q = rng.uniform(-np.pi, np.pi, (300, 6))
    q[:, 4] = (rng.choice([0.0, np.pi, -np.pi], 300)
               + rng.choice([-1.0, 1.0], 300) * 10 ** rng.uniform(-4, -2.5, 300))
    T = robot.fk(q)
    q0 = q + rng.uniform(-0.1, 0.1, q.shape)
    result = numerical(robot, T, q0, history=True)
    assert result.valid.all()
    E = result.history["position_error"] ** 2 + result.history["rotation_error"] ** 2
    assert np.any(np.diff(E, axis=0) > 0)
    monkeypatch.setattr(damped_least_squares, "_WINDOW", 1)
    assert not numerical(robot, T, q0).valid.all()


def test_history_records_every_iteration():
    """With history=True the solver records, per iteration, the errors it stops on and the
    damping; the last row is the returned solution's error, rows are non-increasing in the
    residual (rejected steps keep the iterate)."""
    robot = ur3()
    rng = np.random.default_rng(12)
    q_true = rng.uniform(-2.0, 2.0, (3, 6))
    T = robot.fk(q_true)
    result = numerical(robot, T, q_true + 0.1, history=True)
    h = result.history
    assert set(h) == {"position_error", "rotation_error", "damping"}
    k = h["position_error"].shape[0]
    assert k >= 3 and all(a.shape == (k, 3) for a in h.values())
    # a step is taken only below the largest error of the last five iterates (rejected
    # steps keep the iterate)
    total = h["position_error"] ** 2 + h["rotation_error"] ** 2
    for i in range(1, k):
        assert np.all(total[i] <= total[max(0, i - 5):i].max(axis=0) * (1 + 1e-12))
    assert result.valid.all()
    np.testing.assert_allclose(h["position_error"][-1], result.position_error[:, 0],
                               rtol=1e-6, atol=1e-14)
    assert np.all(h["position_error"][0] > 1e-2)
    assert numerical(robot, T, q_true + 0.1).history is None


@pytest.mark.parametrize("position_only", [False, True])
def test_one_target_iterates_as_in_a_batch(position_only):
    """One target runs the loop on Python floats and solves each step by its own Cholesky
    factorisation; a batch runs on arrays and solves with numpy (LU). The two solve the same
    equations with different roundings, so the iterates agree to rounding, not bit for bit:
    the converging targets take the same number of iterations, with the same flags, reasons
    and history, to the same solutions within 1e-12 rad. The target out of reach stalls in
    both, at the same point; but once its error has settled at the local minimum, whether
    a step lowers it is decided by rounding, so the number of iterations before the
    damping runs away may differ."""
    robot = ur3()
    rng = np.random.default_rng(13)
    q_true = rng.uniform(-2.0, 2.0, (6, 6))
    T = robot.fk(q_true)
    T[5, :3, 3] = [2.0, 0.0, 0.5]                       # out of reach: stalls
    target = T[:, :3, 3] if position_only else T
    q0 = q_true + rng.uniform(-0.3, 0.3, q_true.shape)
    batch = numerical(robot, target, q0, position_only=position_only, history=True)
    assert batch.valid[:5].all() and not batch.valid[5, 0]
    for i in range(len(T)):
        one = numerical(robot, target[i], q0[i], position_only=position_only, history=True)
        np.testing.assert_array_equal(one.valid, batch.valid[i])
        for name, flag in batch.flags.items():
            assert one.flags[name] == flag[i]
        k = one.history["damping"].shape[0]
        if i == 5:
            assert one.flags["stalled"] and str(one.reason).startswith("stalled")
            assert abs(one.position_error[0] - batch.position_error[i, 0]) < 1e-6
            np.testing.assert_allclose(one.history["position_error"][:20],
                                       batch.history["position_error"][:20, i], rtol=1e-9)
            continue
        np.testing.assert_allclose(one.solutions, batch.solutions[i], rtol=0, atol=1e-12)
        np.testing.assert_allclose(one.position_error, batch.position_error[i], atol=1e-15)
        assert one.reason == batch.reason[i] == ""
        for name, rows in batch.history.items():       # the same number of iterations:
            np.testing.assert_allclose(one.history[name], rows[:k, i], rtol=1e-9, atol=1e-15)
            assert np.all(rows[k:, i] == rows[k - 1, i])  # the batch stopped there too
