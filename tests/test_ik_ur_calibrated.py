"""dqlab.ik.ur on a calibrated UR (dqlab.ik.ur_calibrated): the sweep over random poses of
UR5e whose DH parameters are off by up to 2 mm and 2 mrad, the same contract as the closed
form, and how close to a singularity the generating configuration is still found."""

import numpy as np
import pytest

from dqlab._fast import calibrated_entries, calibrated_matrices
from dqlab.identify import dh_parameters, robot_from_dh_parameters
from dqlab.ik import IKResult, ur
from dqlab.ik.ur_calibrated import REASON_NOT_CONVERGED, calibrated_ur, nominal_ur
from dqlab.models import UR_SHAPE, ur3, ur5e, ur10e
from dqlab.robot import Link, Robot
from dqlab.rotations import rot_x, rot_z, wrap_angle
from dqlab.ur.calibration import robot_from_joint_origins


@pytest.fixture(autouse=True)
def _compiled_as_the_environment_says():
    """After a test that switched DQLAB_COMPILED, the kernels read it again (dqlab.ik.ur
    does at each call; a test may ask ready() first)."""
    yield
    from dqlab._fast import newton_compiled
    newton_compiled.refresh()


FLAGS = {"wrist_singular", "shoulder_singular", "elbow_singular", "near_singular", "unreachable",
         "not_converged"}


def calibrated(seed, model=ur5e, size=2e-3):
    """The model with each theta, a, d, alpha off by up to ``size`` (m and rad)."""
    nominal = model()
    offsets = np.random.default_rng(seed).uniform(-size, size, 4 * nominal.n)
    return robot_from_dh_parameters(nominal, dh_parameters(nominal) + offsets)


def physically_calibrated(seed, size=2e-3):
    """A UR5e whose links are moved by up to 2 mm and 2 mrad, in standard DH as a
    controller writes it (far common normals of the nearly parallel axes)."""
    rng = np.random.default_rng(seed)
    S = []
    previous = None
    for link in ur5e().links:
        T = np.eye(4)
        if previous is not None:
            T[:3, :3], T[0, 3] = rot_x(previous.alpha), previous.a
        M = np.eye(4)
        M[2, 3] = link.d
        P = np.eye(4)
        if previous is not None:
            P[:3, :3] = rot_x(rng.uniform(-size, size)) @ rot_z(rng.uniform(-size, size))
            P[:3, 3] = rng.uniform(-size, size, 3)
        S.append(T @ M @ P)
        previous = link
    return robot_from_joint_origins(np.array(S), name="UR5e (calibrated)")


def errors(robot, result, T):
    """Independent position and rotation errors of the valid rows (forward kinematics and
    the rotation angle from the trace and the skew part of R^T R*)."""
    X = robot.fk(result.solutions[result.valid])
    Tb = np.broadcast_to(np.asarray(T)[..., None, :, :],
                         result.solutions.shape[:-1] + (4, 4))[result.valid]
    dp = np.linalg.norm(X[:, :3, 3] - Tb[:, :3, 3], axis=-1)
    E = np.swapaxes(X[:, :3, :3], -1, -2) @ Tb[:, :3, :3]
    v = np.stack([E[:, 2, 1] - E[:, 1, 2], E[:, 0, 2] - E[:, 2, 0], E[:, 1, 0] - E[:, 0, 1]], -1)
    return dp, np.arctan2(np.linalg.norm(v, axis=-1), np.trace(E, axis1=1, axis2=2) - 1.0)


def distance_to(result, q):
    """Joint-wise distance (mod 2 pi) from q to the nearest valid row, per pose."""
    d = np.abs(np.angle(np.exp(1j * (result.solutions - np.asarray(q)[..., None, :]))))
    return np.where(result.valid, d.max(axis=-1), np.inf).min(axis=-1)


def distance_to_every(result, q):
    """:func:`distance_to` over the valid rows and the solutions beyond them (``more``)."""
    return np.minimum(distance_to(result, q), distance_to(result.more, q))


def hard_poses(section):
    """A section of tests/data/real_calibrations/hard_poses.json: calibration name ->
    (its robot, the stored configurations (m, 6))."""
    import json
    from pathlib import Path

    from real_calibrations import real_calibrations

    path = Path(__file__).parent / "data" / "real_calibrations" / "hard_poses.json"
    stored = json.loads(path.read_text(encoding="utf-8"))[section]
    robots = real_calibrations()
    return {name: (robots[name], np.array(qs)) for name, qs in stored.items()}


def use_kernels(compiled_kernels, monkeypatch):
    """The compiled Newton kernels (skipped without numba), or the numpy path
    (``DQLAB_COMPILED=0``, read at each call of ur)."""
    if compiled_kernels:
        pytest.importorskip("numba")
    else:
        monkeypatch.setenv("DQLAB_COMPILED", "0")


def check_contract(result, batch):
    assert isinstance(result, IKResult)
    assert result.solutions.shape == batch + (8, 6) and result.valid.shape == batch + (8,)
    assert set(result.flags) == FLAGS
    assert all(f.shape == batch for f in result.flags.values())
    assert np.isfinite(result.solutions).all()
    assert (result.solutions[~result.valid] == 0).all()
    assert (np.abs(result.solutions) <= np.pi).all()
    assert (result.reason[result.count > 0] == "").all()
    Q, V = result.solutions.reshape(-1, 8, 6), result.valid.reshape(-1, 8)
    gap = np.abs(wrap_angle(Q[:, :, None] - Q[:, None, :])).max(axis=-1)
    assert not ((gap < 1e-6) & V[:, :, None] & V[:, None, :]   # no two valid rows on one
                & ~np.eye(8, dtype=bool)).any()                 # solution
    more = result.more                       # the solutions beyond the rows: eight more rows
    assert more.solutions.shape == batch + (8, 6) and more.valid.shape == batch + (8,)
    assert np.isfinite(more.solutions).all() and (more.solutions[~more.valid] == 0).all()
    assert (np.abs(more.solutions) <= np.pi).all()
    # only full poses seek: every row valid, or on a valid row's solution (a repeat, made
    # invalid, which keeps its errors)
    reached = (result.position_error <= 1e-9) & (result.rotation_error <= 1e-9)
    assert not (more.valid.any(axis=-1) & ~(result.valid | reached).all(axis=-1)).any()
    # a general 6R arm reaches a pose in an even number of joint vectors: a pose with an odd
    # count (the rows and beyond) misses one, and says so
    odd = (result.valid.sum(axis=-1) + more.valid.sum(axis=-1)) % 2 == 1
    assert result.flags["not_converged"][odd].all()


# --------------------------------------------------------------------------------------
# The sweep of the goals


def sweep(robots, poses, seed):
    found = total = 0
    worst = 0.0
    for k, robot in enumerate(robots):
        q = np.random.default_rng(seed + k).uniform(-np.pi, np.pi, (poses, 6))
        T = robot.fk(q)
        result = ur(robot, T)
        check_contract(result, (poses,))
        dp, da = errors(robot, result, T)
        dp_more, da_more = errors(robot, result.more, T)
        worst = max(worst, dp.max(), da.max(), dp_more.max(initial=0), da_more.max(initial=0))
        found += int((distance_to_every(result, q) < 1e-6).sum())
        total += poses
    return found / total, worst


def test_calibrated_ur5e_sweep():
    """Four UR5e off by up to 2 mm / 2 mrad in every DH parameter, 500 random poses each:
    every valid row reproduces its pose to 1e-10 m and 1e-10 rad, and the generating
    configuration is among the solutions (the rows and ``more``) of at least 99.9 % of the
    poses."""
    found, worst = sweep([calibrated(300 + k) for k in range(4)], 500, 40)
    assert worst <= 1e-10, worst
    assert found >= 0.999, found


def test_arm_written_as_a_controller_writes_it_sweep():
    """The same goals for arms with far common normals (d2, d3, d4 of metres), the form of
    a controller's kinematics-info package."""
    robots = [physically_calibrated(400 + k) for k in range(3)]
    assert max(abs(robot.links[1].d) for robot in robots) > 0.5
    found, worst = sweep(robots, 500, 50)
    assert worst <= 1e-10, worst
    assert found >= 0.999, found


@pytest.mark.slow
def test_calibrated_ur5e_sweep_10k_poses():
    found, worst = sweep([calibrated(500 + k) for k in range(10)], 1000, 60)
    assert worst <= 1e-10 and found >= 0.999, (found, worst)
    found, worst = sweep([physically_calibrated(600 + k) for k in range(10)], 1000, 70)
    assert worst <= 1e-10 and found >= 0.999, (found, worst)


# --------------------------------------------------------------------------------------
# Near singularities: measured


def singular_poses(robot, kind, distance, n, seed):
    """Configurations whose exact-arm measure of ``kind`` is about ``distance``: |sin q5|,
    |sin q3| or the shoulder margin (through q4) over d4."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    sign = rng.choice([-1.0, 1.0], n)
    at = rng.choice([0.0, np.pi], n)
    if kind == "wrist":
        q[:, 4] = at + sign * distance
    elif kind == "elbow":
        q[:, 2] = at + sign * distance
    else:
        exact = nominal_ur(robot)
        a2, a3, d4, d5 = (exact.links[1].a, exact.links[2].a, exact.links[3].d,
                          exact.links[4].d)
        v = -(a2 * np.cos(q[:, 1]) + a3 * np.cos(q[:, 1] + q[:, 2])) / d5
        keep = np.abs(v) <= 0.99
        q = q[keep]
        q[:, 3] = np.arcsin(v[keep]) + sign[keep] * distance * d4 / d5 - q[:, 1] - q[:, 2]
    return q


@pytest.mark.parametrize("kind", ["wrist", "elbow", "shoulder"])
def test_found_near_singularities(kind):
    """The generating configuration is found on every pose 1e-1 from a singularity and on
    most 1e-2 from it; valid rows always reproduce the pose (measured for the report by
    benchmarks' sweep over more distances)."""
    robot = calibrated(700)
    for distance, wanted in ((1e-1, 1.0), (1e-2, 0.98)):
        q = singular_poses(robot, kind, distance, 150, 80)
        T = robot.fk(q)
        result = ur(robot, T)
        dp, da = errors(robot, result, T)
        assert max(dp.max(), da.max()) <= 1e-10
        found = np.mean(distance_to(result, q) < 1e-6)
        assert found >= wanted, (kind, distance, found)


# --------------------------------------------------------------------------------------
# The contract


def test_the_default_closed_form_is_that_of_dqlab_ik_ur():
    """Without a closed_form, calibrated_ur calls dqlab.ik.ur's engine directly: the same
    result, bit for bit, as with dqlab.ik.ur passed (one pose and a batch); it checks its
    tolerances itself."""
    robot = calibrated(3)
    T = robot.fk(np.random.default_rng(7).uniform(-np.pi, np.pi, (20, 6)))
    for X in (T[0], T):
        own, given = calibrated_ur(robot, X), calibrated_ur(robot, X, ur)
        for name in ("solutions", "valid", "position_error", "rotation_error", "reason"):
            np.testing.assert_array_equal(getattr(own, name), getattr(given, name))
        for name, flag in own.flags.items():
            np.testing.assert_array_equal(flag, given.flags[name])
    with pytest.raises(ValueError, match="near_tol must be a number >= 0"):
        calibrated_ur(robot, T[0], near_tol=-1.0)


def test_an_exact_ur_gives_the_closed_forms_solutions():
    """Called on an exact UR (which dqlab.ik.ur solves in closed form), the Newton route
    finds the same valid rows and solutions."""
    robot = ur5e()
    q = np.random.default_rng(81).uniform(-np.pi, np.pi, (300, 6))
    T = robot.fk(q)
    closed, newton = ur(robot, T), calibrated_ur(robot, T, ur)
    np.testing.assert_array_equal(newton.valid, closed.valid)
    gap = np.abs(np.angle(np.exp(1j * (newton.solutions - closed.solutions))))
    assert gap[closed.valid].max() < 1e-8
    for name in ("wrist_singular", "shoulder_singular", "elbow_singular", "unreachable"):
        np.testing.assert_array_equal(newton.flags[name], closed.flags[name])


def test_nominal_ur_of_an_exact_ur_is_itself():
    robot = ur10e()
    exact = nominal_ur(robot)
    UR_SHAPE.check(exact)
    for a, b in zip(exact.links, robot.links, strict=True):
        assert abs(a.a - b.a) < 1e-12 and abs(a.d - b.d) < 1e-12
        assert abs(a.theta_offset - b.theta_offset) < 1e-12


def test_single_pose_equals_batch():
    """One pose (the kernel on whole matrices) and a batch (the kernel on entries) give the
    same rows."""
    robot = calibrated(82)
    q = np.random.default_rng(83).uniform(-np.pi, np.pi, (80, 6))
    T = robot.fk(q)
    batch = ur(robot, T)
    for i in range(0, 80, 7):
        single = ur(robot, T[i])
        np.testing.assert_array_equal(single.valid, batch.valid[i])
        assert np.abs(single.solutions - batch.solutions[i]).max() < 1e-9


def test_shapes_dual_quaternions_base_and_tool():
    robot = calibrated(84, model=ur3)
    base, tool = np.eye(4), np.eye(4)
    base[:3, :3], base[:3, 3] = rot_z(0.4), (0.3, -0.1, 0.8)
    tool[:3, :3], tool[:3, 3] = rot_x(0.2), (0.0, 0.01, 0.15)
    robot.base, robot.tool = base, tool
    q = np.random.default_rng(85).uniform(-np.pi, np.pi, (2, 3, 6))
    T = robot.fk(q)
    result = ur(robot, T)
    check_contract(result, (2, 3))
    assert max(e.max() for e in errors(robot, result, T)) <= 1e-10
    assert (distance_to(result, q) < 1e-6).all()
    from dqlab.dualquat import dual_quaternion_from_transform
    again = ur(robot, dual_quaternion_from_transform(T))
    np.testing.assert_array_equal(again.valid, result.valid)
    # a tool given to the call replaces the robot's
    other = np.eye(4)
    other[2, 3] = 0.25
    robot.tool = np.eye(4)
    X = robot.fk(q) @ other
    result = ur(robot, X, tool=other)
    assert (distance_to(result, q) < 1e-6).all()


def test_kernels_equal_forward_kinematics_and_jacobian():
    """The speed machinery of ur_calibrated against Robot.fk_with_jacobian."""

    robot = physically_calibrated(86)
    tool = np.eye(4)
    tool[:3, :3], tool[:3, 3] = rot_x(0.3), (0.02, -0.01, 0.12)
    robot.tool = tool
    links = tuple((np.cos(lk.alpha), np.sin(lk.alpha), lk.a, lk.d, lk.theta_offset)
                  for lk in robot.links)
    q = np.random.default_rng(87).uniform(-np.pi, np.pi, (70, 6))
    X, J = robot.fk_with_jacobian(q)
    steps = []
    for kernel in (calibrated_matrices.MatrixChain(links, tool),
                   calibrated_entries.EntryChain(links, tool)):
        F = kernel.frames(q)
        assert np.abs(kernel.transforms(F) - X).max() < 1e-12
        assert np.abs(kernel.jacobian(F) - J).max() < 1e-12
        e = kernel.residual(F, kernel.targets(robot.fk(q + 1e-4)))
        steps.append(kernel.newton_step(F, e))
        matrices = calibrated_matrices.MatrixChain(links, tool)
        np.testing.assert_allclose(kernel.singularity_measures(F),
                                   matrices.singularity_measures(matrices.frames(q)), atol=1e-12)
    np.testing.assert_allclose(steps[0], steps[1], atol=1e-12)
    assert np.median(np.abs(steps[0] - 1e-4)) < 1e-7            # one step goes most of it


def test_unreachable_pose_has_the_closed_forms_reason():
    robot = calibrated(88)
    far = np.eye(4)
    far[:3, 3] = (2.0, 0.0, 0.5)
    result = ur(robot, far)
    assert result.count == 0 and result.flags["unreachable"]
    assert result.reason.item().startswith("elbow")


def test_reason_when_no_branch_converges(monkeypatch):
    from dqlab.ik import ur_calibrated as module

    robot = calibrated(89)
    q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    monkeypatch.setattr(module, "_GIVE_UP_AFTER", 0)   # no step may fail to halve...
    monkeypatch.setattr(module, "_STOP", 0.0)           # ...and none is ever good enough
    result = calibrated_ur(robot, robot.fk(q), ur, max_iter=1)
    assert result.count == 0 and result.reason.item() == REASON_NOT_CONVERGED
    assert result.flags["not_converged"]


def test_not_a_calibrated_ur_is_refused():
    with pytest.raises(ValueError, match="nor is it a calibrated UR"):
        ur(Robot([Link(0.1, 0.0, 0.0)] * 6), np.eye(4))
    p = dh_parameters(ur5e())
    p[1::4] += 0.1                                       # every d 10 cm longer
    p[2::4] += 0.1                                       # and every a
    with pytest.raises(ValueError, match="the nearest exact UR is"):
        ur(robot_from_dh_parameters(ur5e(), p), np.eye(4))
    p = dh_parameters(ur5e())
    p[3] += 0.2                                          # alpha1
    with pytest.raises(ValueError, match="link 1 of a calibrated UR twists"):
        ur(robot_from_dh_parameters(ur5e(), p), np.eye(4))


def test_repeated_rows_are_those_of_the_pairwise_definition():
    """_Polished.unique (joints 1, 3, 5 first, all six where they agree) against every pair
    of rows compared on all six joints, with repeats shifted by 2 pi, near misses that
    differ in one joint only, and rows that did not converge."""
    from dqlab.ik import ur_calibrated as module
    from dqlab.rotations import wrap_angle

    rng = np.random.default_rng(90)
    n = 400
    polished = module._Polished.empty(n)
    q = rng.uniform(-np.pi, np.pi, (n, 8, 6))
    copies = rng.integers(0, 8, (n, 3, 2))                   # row b becomes a copy of row a
    for i in range(n):
        for a, b in copies[i]:
            q[i, b] = q[i, a] + 2 * np.pi * rng.integers(-1, 2, 6)
            if rng.random() < 0.3:                          # ... or a near miss
                q[i, b, rng.integers(0, 6)] += rng.choice([5e-7, 2e-6])
    polished.q[:] = q.reshape(-1, 6)
    polished.converged[:] = rng.random(8 * n) < 0.9
    Q = np.where(polished.converged[:, None], polished.q, np.nan).reshape(-1, 8, 6)
    with np.errstate(invalid="ignore"):
        same = np.abs(wrap_angle(Q[:, :, None] - Q[:, None])).max(axis=-1) < 1e-6
    repeats = (same & np.tri(8, k=-1, dtype=bool)).any(axis=-1).reshape(-1)
    expected = polished.converged & ~repeats
    assert repeats.sum() > 300 and (expected != polished.converged).any()
    np.testing.assert_array_equal(polished.unique(), expected)


@pytest.mark.parametrize("compiled_kernels", [True, False])
def test_one_pose_path_equals_the_array_path(compiled_kernels, monkeypatch):
    """One pose takes _one_pose (a few numpy calls, or one compiled call) when Newton from
    the exact arm's branches is all it takes; its result is the array path's (a batch of
    one) bit for bit, on random poses and poses near each singularity, with a base and a
    tool on the robot or a tool given to the call. Poses that need more (a restart, a
    branch missed by a little, no branch at all) take the array path: both occur here.
    (Without numba one pose starts from the closed form on floats, math's atan2, and a batch
    of one from its array path, numpy's: where the two differ in the last bit, Newton from
    the two starts stops at solutions that agree within its stop, tol / 10.)"""
    from dqlab._fast import newton_compiled
    from dqlab.ik import ur_calibrated as module
    if compiled_kernels:
        pytest.importorskip("numba")
    monkeypatch.setenv("DQLAB_COMPILED", "1" if compiled_kernels else "0")   # (read by ur)
    newton_compiled.refresh()
    assert newton_compiled.ready() == compiled_kernels
    robot = calibrated(90, model=ur10e)
    base, tool = np.eye(4), np.eye(4)
    base[:3, :3], base[:3, 3] = rot_z(-0.7), (0.1, 0.2, 0.5)
    tool[:3, :3], tool[:3, 3] = rot_x(0.1), (0.01, 0.0, 0.18)
    robot.base, robot.tool = base, tool
    q = np.concatenate([np.random.default_rng(91).uniform(-np.pi, np.pi, (120, 6))]
                       + [singular_poses(robot, kind, 1e-2, 20, 92)
                          for kind in ("wrist", "elbow", "shoulder")])
    X = robot.fk(q)
    X[-1, :3, 3] = (5.0, 0.0, 0.0)                      # out of reach
    lean = []
    one_pose = module._one_pose
    monkeypatch.setattr(module, "_one_pose", lambda *args: lean.append(one_pose(*args))
                        or lean[-1])
    other = np.eye(4)
    other[:3, 3] = (0.0, 0.02, 0.25)
    for i, T in enumerate(X):
        given = {} if i % 3 else {"tool": other}
        one, batch = ur(robot, T, **given), ur(robot, T[None], **given)
        assert one.solutions.shape == (8, 6) and one.flags["unreachable"].shape == ()
        for name in ("valid", "reason"):
            np.testing.assert_array_equal(getattr(one, name), getattr(batch, name)[0])
        for name in ("solutions", "position_error", "rotation_error"):
            np.testing.assert_allclose(getattr(one, name), getattr(batch, name)[0], rtol=0,
                                       atol=0 if compiled_kernels else 1e-9)
        assert list(one.flags) == list(batch.flags)
        for name, flag in one.flags.items():
            np.testing.assert_array_equal(flag, batch.flags[name][0], err_msg=f"{i} {name}")
        np.testing.assert_array_equal(one.more.valid, batch.more.valid[0])   # and beyond
        np.testing.assert_allclose(one.more.solutions, batch.more.solutions[0], rtol=0,
                                   atol=0 if compiled_kernels else 1e-9)
    taken = np.array([result is not None for result, _ in lean])
    assert taken.size == len(X)                         # a batch of one does not take it
    assert 0.5 < taken.mean() < 1.0 and not taken[-1]   # ... nor does every single pose


def test_repair_without_singular_directions(monkeypatch):
    """Poses whose missing branches are nowhere near a singularity have no restart along a
    singular direction: the repair ends without one (here every screen says "not near"),
    and the rows it keeps still reproduce their poses."""
    from dqlab.ik import ur_calibrated as module
    robot = calibrated(93)
    q = singular_poses(robot, "wrist", 1e-2, 300, 0)
    T = robot.fk(q)
    calls = []

    def nowhere_near(nominal, tool, q):
        calls.append(len(q))
        return np.zeros(len(q), dtype=bool), np.zeros((0, 6))

    monkeypatch.setattr(module, "_near_singular", nowhere_near)
    result = ur(robot, T)
    assert calls and result.count.sum() > 0
    assert max(e.max() for e in errors(robot, result, T)) <= 1e-10
    single = ur(robot, T[0])
    np.testing.assert_array_equal(single.valid, result.valid[0])


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize("compiled_kernels", [True, False])
def test_reference_batches_far_targets_and_one_set_of_flags(compiled_kernels, monkeypatch):
    """A batch with one reference per pose (or one for all), and closest_ur_solution on it,
    on a calibrated arm with a base and a tool, the poses the exact arm misses by a little
    (which take its closed form again) included; far targets, up to 1e300 m, have no valid
    row and their distance as error, without a warning; exact and calibrated results carry
    the same flags, in the same order."""
    from dqlab.ik import closest_ur_solution
    use_kernels(compiled_kernels, monkeypatch)
    robot = calibrated(94)
    robot.base = np.eye(4)
    robot.base[:3, :3], robot.base[:3, 3] = rot_z(0.3), (0.0, 0.1, 0.2)
    robot = robot.with_tool(z=0.15)
    q = np.concatenate([np.random.default_rng(95).uniform(-np.pi, np.pi, (30, 6)),
                        singular_poses(robot, "wrist", 1e-3, 10, 96)])
    X = robot.fk(q)
    for q_ref in (q, q[0]):
        result = ur(robot, X, q_ref=q_ref)
        check_contract(result, (len(q),))
        assert max(e.max() for e in errors(robot, result, X)) <= 1e-10
    q_send = closest_ur_solution(robot, X, q)
    np.testing.assert_allclose(robot.fk(q_send), X, atol=1e-9)
    assert np.abs(q_send - q).max() < 1e-6                  # standing there: the answer
    with pytest.raises(ValueError, match="q_ref of shape"):
        ur(robot, X, q_ref=q[:3])
    far = np.repeat(X[:1], 4, axis=0)
    far[:, :3, 3] = [[1e100, 0.0, 0.0], [0.0, 1e156, 0.0], [0.0, 0.0, -1e200],
                     [1e300, 1e300, 0.0]]
    for result in (ur(robot, far), ur(robot, far[2]), ur(robot, far, residuals="fk")):
        check_contract(result, result.valid.shape[:-1])
        assert not result.valid.any() and result.flags["unreachable"].all()
        size = np.abs(far[:, :3, 3]).max(axis=-1)
        distance = np.linalg.norm(far[:, :3, 3] / size[:, None], axis=-1) * size
        np.testing.assert_allclose(result.position_error,
                                   np.broadcast_to(distance[:, None], (4, 8))[
                                       2 if result.valid.ndim == 1 else slice(None)],
                                   rtol=1e-15)
    exact = ur(ur5e(), ur5e().fk(q))
    assert list(exact.flags) == list(result.flags) and not exact.flags["not_converged"].any()


def test_real_calibrations_sweep():
    """The calibrations of real arms (tests/data/real_calibrations: the controllers' own
    parameters, hundreds of metres of d on the parallel joints), 3000 random poses each:
    every valid row and every solution beyond the rows reproduces its pose to 1e-10 m and
    1e-10 rad (independent forward kinematics), the generating configuration is among the
    solutions (the rows and ``more``) of at least 99.9 % of each arm's poses (at this size
    one miss is 0.033 %; benchmarks/bench_ik_ur_calibrated.py measures each on more), and
    every pose where it is not carries a flag (near_singular, unreachable or
    not_converged)."""
    from real_calibrations import real_calibrations

    robots = real_calibrations()
    assert len(robots) >= 4 and sum(abs(r.links[1].d) > 100 for r in robots.values()) >= 4
    found = total = 0
    for k, robot in enumerate(robots.values()):
        q = np.random.default_rng(100 + k).uniform(-np.pi, np.pi, (3000, 6))
        T = robot.fk(q)
        result = ur(robot, T)
        check_contract(result, (3000,))
        assert max(e.max() for e in errors(robot, result, T)) <= 1e-10
        assert max(e.max(initial=0) for e in errors(robot, result.more, T)) <= 1e-10
        hit = distance_to_every(result, q) < 1e-6
        flags = result.flags
        assert (hit | flags["near_singular"] | flags["unreachable"]
                | flags["not_converged"]).all(), robot.name
        assert hit.mean() >= 0.999, (robot.name, hit.mean())
        found, total = found + hit.sum(), total + hit.size
    assert found / total >= 0.999, found / total


def test_near_singular_flag():
    """near_singular: a valid row within near_tol (0.01 by default) of a singularity, by
    |sin q5|, |sin q3| or h / d4; on a calibrated UR at least four times its rotation gap
    from the nearest exact UR."""
    robot = ur5e()
    q = np.array([0.3, -1.2, 1.1, -0.4, 1e-4, 0.2])
    assert ur(robot, robot.fk(q)).flags["near_singular"]
    assert "flags: near_singular" in repr(ur(robot, robot.fk(q)))
    q[4] = 0.02
    assert not ur(robot, robot.fk(q)).flags["near_singular"]
    assert ur(robot, robot.fk(q), near_tol=0.05).flags["near_singular"]
    q[4], q[2] = 0.9, 5e-3                                  # the elbow
    assert ur(robot, robot.fk(q)).flags["near_singular"]
    with pytest.raises(ValueError, match="near_tol"):
        ur(robot, robot.fk(q), near_tol=-1.0)
    cal = calibrated(95)
    from dqlab.ik.ur_calibrated import _NEAR_GAPS, _nearest_exact
    limit = max(1e-2, _NEAR_GAPS * _nearest_exact(cal).rotation_gap)
    q = np.array([0.3, -1.2, 1.1, -0.4, 0.5 * limit, 0.2])
    assert ur(cal, cal.fk(q)).flags["near_singular"]
    q[4] = 3.0 * limit
    assert not ur(cal, cal.fk(q)).flags["near_singular"]


@pytest.mark.parametrize("compiled_kernels", [True, False])
def test_hard_poses_of_real_calibrations(compiled_kernels, monkeypatch):
    """Poses of the real calibrations whose generating configuration a solve once missed
    (tests/data/real_calibrations/hard_poses.json): near a singularity of the nearest exact
    UR, where a row stopped at 1e-10 of pose error lies up to 1e-4 rad from its solution
    (the valid rows near a singularity are polished further), and near the wrist
    singularity with a whole shoulder missed by the exact arm's closed form (such a pose
    takes the wrist family's starts; and the whole family where the one start of a shoulder
    the exact arm clips is at the wrist singularity, the UR3's last pose, whose
    configuration is 2.7 rad along the family from that start). Each is found, in a batch
    and one pose at a time,
    every valid row reproducing its pose to 1e-10 (independent forward kinematics)."""
    use_kernels(compiled_kernels, monkeypatch)
    stored = hard_poses("configurations")
    assert len(stored) >= 4 and sum(len(q) for _, q in stored.values()) >= 15
    for name, (robot, q) in stored.items():
        T = robot.fk(q)
        result = ur(robot, T)
        assert max(e.max() for e in errors(robot, result, T)) <= 1e-10, name
        assert (distance_to(result, q) < 1e-6).all(), (name, distance_to(result, q))
        for i in range(len(q)):
            one = ur(robot, T[i])
            assert distance_to(one, q[i]) < 1e-6, (name, i)


def test_one_pose_seeks_the_wrist_family_as_a_batch_does():
    """A pose near the wrist singularity with a branch missing takes the exact arm's wrist
    family as starts in a batch (``_family``); one pose alone must too, and give the batch's
    answer: on the six real calibrations, three configurations (|sin theta_5| of 0.009 to
    0.04) where one pose alone once kept four rows and a batch of one found five to seven."""
    from real_calibrations import real_calibrations

    q = np.array([[2.6108534862111803, -1.4766943594619386, -0.00906504113434492,
                   2.8702145612868692, 3.1322886772315943, -0.9732226721225419],
                  [0.03207725126969141, 1.4158783088420002, 0.21986759611671802,
                   -1.1553436364726026, -0.03580222298377933, -2.8246033557525836],
                  [1.9257764155124288, -1.643822380244287, 0.6212169616805325,
                   -0.4239341919236601, -0.003304536080652287, 2.333305478427987]])
    for robot in real_calibrations().values():
        T = robot.fk(q)
        batch = ur(robot, T)
        for i in range(len(q)):
            one = ur(robot, T[i])
            np.testing.assert_array_equal(one.valid, batch.valid[i])
            np.testing.assert_allclose(one.solutions[one.valid],
                                       batch.solutions[i][one.valid], rtol=0, atol=1e-9)


@pytest.mark.parametrize("compiled_kernels", [True, False])
def test_poses_with_more_than_eight_solutions(compiled_kernels, monkeypatch):
    """Poses of the real calibrations with more than eight solutions
    (tests/data/real_calibrations/hard_poses.json, "beyond_eight"): within the arms' gap of
    a singularity of the nearest exact UR, where the eight rows hold eight of them and the
    generating configuration is another. It is in ``result.more``, in a batch and one pose
    at a time; every row and every solution beyond reproduces its pose to 1e-10
    (independent forward kinematics), and all of them are distinct joint vectors, so that
    the pose has at least nine solutions whatever the solver believes. ``closest_ur_solution``
    from the generating configuration returns it (the plain distance, and on its branch)."""
    from dqlab.ik import closest_ur_solution

    use_kernels(compiled_kernels, monkeypatch)
    stored = hard_poses("beyond_eight")
    assert len(stored) == 6 and sum(len(q) for _, q in stored.values()) >= 10
    for name, (robot, q) in stored.items():
        T = robot.fk(q)
        result = ur(robot, T)
        check_contract(result, (len(q),))
        assert (distance_to(result, q) > 1e-6).all(), name       # not in the rows ...
        assert (distance_to(result.more, q) < 1e-6).all(), name  # ... but beyond them
        assert max(e.max() for e in errors(robot, result.more, T)) <= 1e-10, name
        for i in range(len(q)):
            every = np.concatenate([result.solutions[i][result.valid[i]],
                                    result.more.solutions[i][result.more.valid[i]]])
            assert len(every) >= 9, (name, i)
            gaps = np.abs(np.angle(np.exp(1j * (every[:, None] - every[None]))))
            assert (gaps.max(axis=-1) + np.eye(len(every)) > 1e-6).all(), (name, i)
            one = ur(robot, T[i])
            assert distance_to(one.more, q[i]) < 1e-6, (name, i)
            np.testing.assert_array_equal(one.more.valid, result.more.valid[i])
            for keep_branch in (False, True):
                chosen = closest_ur_solution(robot, T[i], q[i], keep_branch=keep_branch)
                np.testing.assert_allclose(chosen, q[i], rtol=0, atol=1e-6)


def test_more_is_empty_on_an_exact_arm_and_printed_on_a_calibrated_one():
    """``result.more`` of an exact UR has no rows (its eight branches are every solution);
    ``repr`` of a calibrated pose with solutions beyond its rows lists them."""
    X = ur5e().fk(np.array([[0.3, -1.2, 1.1, -0.4, 0.9, 0.2]] * 3))
    exact = ur(ur5e(), X)
    assert exact.more.solutions.shape == (3, 0, 6) and exact.more.valid.shape == (3, 0)
    assert ur(ur5e(), X[0]).more.count == 0
    robot, qs = next(iter(hard_poses("beyond_eight").values()))
    result = ur(robot, robot.fk(qs[0]))
    text = repr(result)
    more = int(result.more.count)
    assert more >= 1 and f"8 of 8 rows valid, {more} more beyond them" in text
    assert text.count("(more)") == more
    both = ur(robot, robot.fk(qs))
    assert (f"targets with solutions beyond the rows (result.more): 2, "
            f"{int(both.more.count.sum())} solutions") in repr(both)


@pytest.mark.parametrize("compiled_kernels", [True, False])
def test_two_rows_on_one_solution(compiled_kernels, monkeypatch):
    """A pose of a real calibration (tests/data/real_calibrations/hard_poses.json,
    "repeated") where branch 0's start converged to branch 4's solution: once both rows were
    listed valid, and the configuration the pose came from was missing without a flag. A
    row on a solution a row of lower number has is invalid, keeps its errors, and flags
    not_converged (it started from a solution of the exact arm), one pose or in a batch."""
    use_kernels(compiled_kernels, monkeypatch)
    for name, (robot, q) in hard_poses("repeated").items():
        T = robot.fk(q)
        for result in (ur(robot, T), *(ur(robot, x) for x in T)):
            check_contract(result, result.valid.shape[:-1])
            missed = ~(distance_to(result, q) < 1e-6)
            assert (result.flags["not_converged"] | ~missed).all(), name
            reached = (result.position_error <= 1e-9) & (result.rotation_error <= 1e-9)
            assert (reached & ~result.valid).any(), name     # the repeat, kept invalid


@pytest.mark.parametrize("compiled_kernels", [True, False])
def test_an_odd_count_of_solutions_is_flagged(compiled_kernels, monkeypatch):
    """Poses of the UR3's calibration (tests/data/real_calibrations/hard_poses.json, "odd")
    whose configuration the solver misses, once without a flag, 0.06 from the exact arm's
    shoulder or elbow singularity: it finds three solutions (each reaching the pose to
    1e-10, by independent forward kinematics), and the configuration is none of them: a
    fourth. A general 6R arm reaches a pose in an even number of joint vectors (the real
    roots of a polynomial of degree 16), so an odd count says one is missing: such a pose
    is flagged not_converged, in a batch and one pose at a time, on both paths."""
    use_kernels(compiled_kernels, monkeypatch)
    for name, (robot, q) in hard_poses("odd").items():
        T = robot.fk(q)
        batch = ur(robot, T)
        assert max(e.max() for e in errors(robot, batch, T)) <= 1e-10, name
        for i, result in enumerate((batch, *(ur(robot, x) for x in T))):
            check_contract(result, result.valid.shape[:-1])
            configurations = q if i == 0 else q[i - 1]
            missed = ~(distance_to_every(result, configurations) < 1e-6)
            count = result.valid.sum(axis=-1) + result.more.valid.sum(axis=-1)
            assert (result.flags["not_converged"] | ~missed).all(), (name, i)
            assert ((count % 2 == 1) | ~missed).all(), (name, i)


def test_a_pose_missed_near_a_singularity_is_flagged():
    """Poses of the real calibrations (tests/data/real_calibrations/hard_poses.json,
    "flagged") whose configuration the solver misses, once without a flag: within a few
    milliradians of a singularity of the nearest exact UR, where the calibrated arm's own
    measures stayed above the near threshold. The exact arm's measures at the valid rows
    count too: each is flagged near_singular. And where two solutions meet (the UR5's pose,
    sin theta_3 = 0.001 on the exact arm), Newton stops anywhere along the flat valley
    between them: the solutions beyond the rows hold no second copy of a row (no two
    solutions within 0.1 rad whose midpoint also reaches the pose, by independent forward
    kinematics)."""
    for name, (robot, q) in hard_poses("flagged").items():
        T = robot.fk(q)
        result = ur(robot, T)
        assert result.flags["near_singular"].all(), name
        for i in range(len(q)):
            more = result.more.solutions[i][result.more.valid[i]]
            every = np.concatenate([result.solutions[i][result.valid[i]], more])
            for x in more:
                gap = np.abs(np.angle(np.exp(1j * (every - x)))).max(axis=-1)
                others = every[(gap > 0) & (gap < 0.1)]
                middle = x + 0.5 * np.angle(np.exp(1j * (others - x)))
                dp = np.linalg.norm(robot.fk(middle)[:, :3, 3] - T[i, :3, 3], axis=-1)
                assert (dp > 1e-9).all(), (name, i)
