"""Choosing the solution to send: the nearest 2 pi-equivalent within the joint limits."""

import itertools

import numpy as np
import pytest

from dqlab.ik import IKResult, closest_solution, equivalent_solutions, scara, ur
from dqlab.models import scara_rsm5, ur3

TWO_PI = 2.0 * np.pi


def wrapped(x):
    return (np.asarray(x) + np.pi) % TWO_PI - np.pi


@pytest.fixture(scope="module")
def robot():
    return ur3()


def brute_force(result, q_ref, limits):
    """Every valid row, every equivalent within the limits (turns -3..3): the nearest, or
    None."""
    best = None
    for row, ok in zip(result.solutions, result.valid, strict=True):
        if not ok:
            continue
        joints = []
        for theta, ref, (lo, hi) in zip(row, q_ref, limits, strict=True):
            options = [theta + TWO_PI * m for m in range(-3, 4)]
            options = [x for x in options if lo <= x <= hi]
            if not options:
                break
            joints.append(min(options, key=lambda x, ref=ref: abs(x - ref)))
        else:
            d = np.linalg.norm(np.subtract(joints, q_ref))
            if best is None or d < best[0]:
                best = (d, np.array(joints))
    return None if best is None else best[1]


def one(result, i):
    return IKResult(result.solutions[i], result.valid[i], result.position_error[i],
                    result.rotation_error[i])


def test_equivalent_solutions():
    q = np.array([0.5, -3.0, 0.0, 3.1, -np.pi / 2, 2.0])
    cands, within = equivalent_solutions(q)
    assert cands.shape == (64, 6) and within.all()
    assert np.allclose(wrapped(cands - q), 0.0)
    assert len(np.unique(np.round(cands, 12), axis=0)) == 64
    cands, within = equivalent_solutions(q, limits=(-np.pi, np.pi))
    assert within.sum() == 1 and np.array_equal(cands[within][0], q)
    lim = np.array([[-2 * np.pi, 2 * np.pi]] * 5 + [[-np.pi, np.pi]])
    assert equivalent_solutions(q, limits=lim)[1].sum() == 32
    batch = np.stack([q, -q])
    assert equivalent_solutions(batch)[0].shape == (2, 64, 6)


def test_closest_solution_is_consistent_with_best(robot):
    rng = np.random.default_rng(25)
    q = rng.uniform(-TWO_PI, TWO_PI, (200, 6))
    T = robot.fk(q)
    result = ur(robot, T)
    best = result.best(q)
    close = closest_solution(result, q)
    assert np.allclose(wrapped(close - best), 0.0)
    np.testing.assert_allclose(close, q, atol=1e-9)     # the unwrapped generating config
    assert np.all(np.abs(close) <= TWO_PI)
    assert np.all(np.abs(best) <= np.pi)                  # best: the rows as solved


def test_the_nearest_solution_within_the_limits_not_the_nearest_row_moved_into_them(robot):
    # joint 3 limited to [-pi, 0]: the row nearest q has +1.6 there; the answer is the other
    # elbow's row, -1.6 (the branch chosen modulo 2 pi first would give +1.6, outside)
    q = np.array([0.3, -1.2, 1.6, -0.4, 0.9, 0.2])
    limits = robot.limits.copy()
    limits[2] = [-np.pi, 0.0]
    result = ur(robot, robot.fk(q))
    q_star = closest_solution(result, q, limits)
    assert np.all((q_star >= limits[:, 0]) & (q_star <= limits[:, 1]))
    assert q_star[2] == pytest.approx(-1.6, abs=1e-9)
    np.testing.assert_allclose(robot.fk(q_star), robot.fk(q), atol=1e-12)
    np.testing.assert_allclose(q_star, brute_force(result, q, limits), atol=1e-12)


def test_no_solution_within_the_limits_is_an_error_naming_the_target(robot):
    q = np.array([0.3, -1.2, 1.6, -0.4, 0.9, 0.2])
    limits = robot.limits.copy()
    limits[2] = [2.0, 2.1]                  # no row has joint 3 there
    with pytest.raises(ValueError, match=r"the target has no valid solution within the "
                                         r"joint limits \[\[-6\.28"):
        closest_solution(ur(robot, robot.fk(q)), q, limits)
    batch = np.stack([q, q])
    with pytest.raises(ValueError, match=r"target \(0,\) has no valid solution within"):
        closest_solution(ur(robot, robot.fk(batch)), batch, limits)
    far = np.eye(4)
    far[:3, 3] = [2.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="some targets have no valid solution"):
        closest_solution(ur(robot, far), q)


def test_batch_equals_brute_force_with_random_limits(robot):
    rng = np.random.default_rng(3)
    q = rng.uniform(-TWO_PI, TWO_PI, (400, 6))
    q_ref = q + rng.normal(0.0, 0.7, q.shape)
    limits = np.array([[-TWO_PI, TWO_PI], [-np.pi, 0.5], [-np.pi, 0.0], [-TWO_PI, TWO_PI],
                       [-1.0, 3.0], [-np.inf, np.inf]])
    result = ur(robot, robot.fk(q))
    expected = [brute_force(one(result, i), q_ref[i], limits) for i in range(len(q))]
    reachable = [i for i, e in enumerate(expected) if e is not None]
    assert 100 < len(reachable) < len(q)          # both kinds of case occur
    got = closest_solution(one(result, reachable), q_ref[reachable], limits)
    np.testing.assert_allclose(got, np.array([expected[i] for i in reachable]), atol=1e-12)
    for i in sorted(set(range(len(q))) - set(reachable))[:20]:
        with pytest.raises(ValueError, match="within the joint limits"):
            closest_solution(one(result, i), q_ref[i], limits)


@pytest.mark.parametrize("shape", [(), (3,), (2, 3)])
def test_batch_shapes_and_a_reference_shared_by_all_targets(robot, shape):
    rng = np.random.default_rng(5)
    q = rng.uniform(-np.pi, np.pi, shape + (6,))
    result = ur(robot, robot.fk(q))
    got = closest_solution(result, q, robot.limits)
    assert got.shape == shape + (6,)
    np.testing.assert_allclose(got, q, atol=1e-9)
    shared = closest_solution(result, np.zeros(6), robot.limits)
    assert shared.shape == shape + (6,)
    for index in itertools.product(*map(range, shape)):
        np.testing.assert_array_equal(shared[index],
                                      closest_solution(one(result, index), np.zeros(6),
                                                       robot.limits))


def test_any_solver_and_bad_arguments():
    robot = scara_rsm5()
    q = np.array([0.3, 0.5, 0.05, 0.2])
    result = scara(robot, robot.fk(q))
    np.testing.assert_allclose(closest_solution(result, q, robot.limits), q, atol=1e-9)
    with pytest.raises(ValueError, match=r"limits must have shape \(2,\) or \(4, 2\)"):
        closest_solution(result, q, np.zeros((3, 2)))
    with pytest.raises(ValueError, match=r"limits: joint 1 has \[1, 0\], lo > hi"):
        closest_solution(result, q, [[1.0, 0.0]] * 4)
    with pytest.raises(ValueError, match=r"limits: joint 1 has \[nan, 1\], a NaN"):
        closest_solution(result, q, [np.nan, 1.0])
    for empty in ([-np.inf, -np.inf], [np.inf, np.inf], [2e6, 3e6]):     # no usable joint
        with pytest.raises(ValueError, match="limits: joint 1 has .* beyond 1e"):
            closest_solution(result, q, empty)
    for far in (1e10, -1e300):                    # joint values not accurate near there
        with pytest.raises(ValueError, match=r"q_ref: joint 2 = .* beyond 1e\+06 rad"):
            closest_solution(result, [0.0, far, 0.0, 0.0], [-np.inf, np.inf])
    turns = 2 * np.pi * np.array([16000, 0, 0, -16000])               # far, but accurate
    unlimited = closest_solution(result, q + turns, [-1e300, 1e300])
    assert np.abs(np.angle(np.exp(1j * (unlimited - q)))).max() < 1e-10
    assert np.abs(unlimited - q - turns).max() < np.pi
    with pytest.raises(TypeError, match="limits must hold real numbers"):
        closest_solution(result, q, np.zeros((4, 2)) + 1j)
    with pytest.raises(ValueError, match="q_ref contains NaN"):
        closest_solution(result, [np.nan] * 4)
    with pytest.raises(ValueError, match="wrapped=True"):
        closest_solution(result, q, robot.limits, wrapped=True)
