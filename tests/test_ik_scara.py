"""Tests for dqlab.ik.scara: round trips, both elbows, limits, unreachable targets."""

import numpy as np
import pytest

from dqlab import dualquat
from dqlab.ik import scara as solve
from dqlab.models import SCARA_RSM5, scara_rsm5, ur3
from dqlab.rotations import rot_x


def random_joints(robot, rng, size):
    lo, hi = robot.limits.T
    return rng.uniform(lo, hi, size=(size, 4))


def test_round_trip_finds_the_original_and_its_mirror():
    rng = np.random.default_rng(40)
    robot = scara_rsm5()
    q = random_joints(robot, rng, 1000)
    X = robot.fk(q)
    result = solve(robot, X)
    assert result.solutions.shape == (1000, 2, 4)
    assert result.success.all()
    # the original is a valid row
    diff = np.angle(np.exp(1j * (result.solutions - q[:, None, :])))
    diff[..., 2] = result.solutions[..., 2] - q[:, None, 2]
    dist = np.where(result.valid, np.max(np.abs(diff), axis=-1), np.inf)
    assert np.all(np.min(dist, axis=-1) < 1e-9)
    # every valid row reproduces the pose
    Y = robot.fk(result.solutions)
    err = np.abs(Y - X[:, None]).max(axis=(-1, -2))
    assert np.all(err[result.valid] < 1e-12)
    assert np.all(result.position_error[result.valid] < 1e-12)
    assert np.all(result.rotation_error[result.valid] < 1e-12)
    # elbow rows: theta2 >= 0 first
    v = result.valid
    assert np.all(result.solutions[v[:, 0], 0, 1] >= 0)
    assert np.all(result.solutions[v[:, 1], 1, 1] <= 0)
    # the mirror elbow is sometimes beyond joint 1's +-120 deg: then its row is invalid
    assert 0 < (~result.valid).sum()


def test_dual_quaternion_targets_and_batches():
    rng = np.random.default_rng(41)
    robot = scara_rsm5()
    q = random_joints(robot, rng, 6).reshape(2, 3, 4)
    X = robot.fk(q)
    from_matrix = solve(robot, X)
    from_dq = solve(robot, dualquat.dual_quaternion_from_transform(X))
    assert from_dq.solutions.shape == (2, 3, 2, 4)
    assert from_dq.reason.shape == (2, 3)
    np.testing.assert_allclose(from_dq.solutions, from_matrix.solutions, atol=1e-12)
    single = solve(robot, X[1, 2])
    np.testing.assert_allclose(single.solutions, from_matrix.solutions[1, 2])


def test_base_and_tool_are_undone():
    rng = np.random.default_rng(42)
    robot = scara_rsm5()
    base = np.eye(4)
    base[:3, 3] = [1.0, 2.0, 0.5]
    base[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    tool = np.eye(4)
    tool[:3, 3] = [0.03, -0.01, -0.12]
    robot.base, robot.tool = base, tool
    q = random_joints(robot, rng, 200)
    X = robot.fk(q)
    result = solve(robot, X)
    assert result.success.all()
    Y = robot.fk(result.solutions)
    assert np.all(np.abs(Y - X[:, None]).max(axis=(-1, -2))[result.valid] < 1e-12)


def test_singular_configuration_gives_one_repeated_solution():
    robot = scara_rsm5()
    result = solve(robot, robot.fk([0.3, 0.0, 0.1, 0.2]))
    assert bool(result.flags["singular"])
    assert result.valid.all()
    np.testing.assert_allclose(result.solutions[0], result.solutions[1], atol=1e-7)


def test_unreachable_targets_say_why():
    robot = scara_rsm5()
    X = robot.fk([0.3, 0.5, 0.1, 0.2])
    too_far = X.copy()
    too_far[:2, 3] *= 0.7 / np.hypot(*X[:2, 3])
    too_close = X.copy()
    too_close[:2, 3] = [0.05, 0.0]
    too_high = X.copy()
    too_high[2, 3] = SCARA_RSM5["z_low"] + 0.2
    tilted = X.copy()
    tilted[:3, :3] = X[:3, :3] @ rot_x(0.1)
    result = solve(robot, np.stack([too_far, too_close, too_high, tilted]))
    assert not result.valid.any()
    assert result.flags["unreachable"].all()
    assert "beyond the reach" in result.reason[0]
    assert "too close to axis 1" in result.reason[1]
    assert "joint(s) 3" in result.reason[2]
    assert "tilted 0.1 rad" in result.reason[3]
    assert result.flags["tilted"].tolist() == [False, False, False, True]
    assert np.all(result.solutions == 0.0)
    # the errors are those of the nearest reachable pose
    np.testing.assert_allclose(result.position_error[0], 0.7 - 0.61, atol=1e-12)
    np.testing.assert_allclose(result.position_error[2], 0.05, atol=1e-12)
    np.testing.assert_allclose(result.rotation_error[3], 0.1, atol=1e-12)


def test_elbow_beyond_its_stop_is_invalid():
    robot = scara_rsm5()
    # a point whose elbow angle would be 150 deg (the stop is 145)
    q2 = np.radians(150)
    p = 0.350 + 0.260 * np.exp(1j * q2)
    X = np.eye(4)
    X[:3, 3] = [p.real, p.imag, 0.2]
    result = solve(robot, X)
    assert not result.success
    assert "joint(s) 2" in str(result.reason)


def test_other_robots_are_refused():
    with pytest.raises(ValueError, match="RRPR"):
        solve(ur3(), np.eye(4))
    with pytest.raises(ValueError, match=r"target must have shape \(\.\.\., 4, 4\)"):
        solve(scara_rsm5(), np.zeros(3))
