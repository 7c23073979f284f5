"""The compiled kernels of the calibrated UR solver (dqlab._fast.newton_compiled, with numba)
against the numpy path of dqlab.ik.ur_calibrated, which stays the one used without numba:
the Newton steps row by row, the repeated-row tests, and whole results of dqlab.ik.ur on
random and near-singular poses."""

import numpy as np
import pytest
from test_ik_ur_calibrated import calibrated, physically_calibrated, singular_poses

from dqlab._fast import calibrated_matrices
from dqlab._fast import compiled as dqlab_compiled
from dqlab._fast import newton_compiled as compiled
from dqlab._fast.compiled import compiled_allowed
from dqlab._formulas import quaternion_from_matrix_entries
from dqlab.ik import ur
from dqlab.ik import ur_calibrated as module
from dqlab.ik.targets import pose_errors
from dqlab.ik.ur_steps import NEAR_SINGULAR, NEAR_WRIST
from dqlab.rotations import rot_x

pytest.importorskip("numba")
pytestmark = pytest.mark.skipif(not compiled_allowed(),
                                reason="DQLAB_COMPILED switches the compiled paths off")


@pytest.fixture(autouse=True)
def _compiled_as_the_environment_says():
    """After a test that switched DQLAB_COMPILED, the kernels read it again (dqlab.ik.ur
    does at each call; a test may ask ready() first)."""
    yield
    from dqlab._fast import newton_compiled
    newton_compiled.refresh()


@pytest.fixture
def numpy_path(monkeypatch):
    """A function that runs its argument with the compiled kernels switched off, as a user
    does: DQLAB_COMPILED=0 (read again here, as dqlab.ik.ur reads it at each call)."""
    def run(f, *args, **kwargs):
        try:
            with monkeypatch.context() as m:
                m.setenv("DQLAB_COMPILED", "0")
                compiled.refresh()
                return f(*args, **kwargs)
        finally:
            compiled.refresh()
    return run


def chain_and_starts(robot, seed, n):
    """The calibrated chain of robot (with a tool), and start rows as the solver makes
    them: the nearest exact UR's branches of poses of the calibrated arm, plus random starts
    (many of which converge nowhere or elsewhere), a start at a singularity and a start
    that is not a number."""
    tool = np.eye(4)
    tool[:3, :3], tool[:3, 3] = rot_x(0.3), (0.02, -0.01, 0.12)
    robot.tool = tool
    nearest = module._nearest_exact(robot)
    rng = np.random.default_rng(seed)
    X = robot.fk(rng.uniform(-np.pi, np.pi, (n, 6)))
    start = ur(nearest.robot, X @ np.linalg.inv(tool), tol=2 * nearest.position_gap)
    q0 = start.solutions.reshape(-1, 6)[start.valid.reshape(-1)]
    targets = np.repeat(X, 8, axis=0)[start.valid.reshape(-1)]
    far = rng.uniform(-np.pi, np.pi, (50, 6))
    singular = np.array([[0.3, -1.2, 1.1, -0.4, 0.0, 0.2]])          # theta5 = 0: wrist
    odd = np.array([[np.nan, 0.0, 0.0, 0.0, 0.0, 0.0]])
    q0 = np.concatenate([q0, far, singular, odd])
    targets = np.concatenate([targets, targets[:50], targets[:1], targets[:1]])
    return (nearest.links, tool), q0, targets


@pytest.mark.parametrize("make", [calibrated, physically_calibrated])
def test_compiled_newton_equals_the_numpy_path(make, numpy_path):
    robot = make(41)
    chain, q0, targets = chain_and_starts(robot, 42, 300)
    for max_iter in (16, 3, 1):
        q, converged, X, measures, errors = module._newton(*chain, q0, targets, 1e-9, max_iter)
        q_n, converged_n, X_n, measures_n, errors_n = numpy_path(
            module._newton, *chain, q0, targets, 1e-9, max_iter)
        np.testing.assert_array_equal(converged, converged_n)
        if max_iter == 16:
            assert converged.sum() > 0.9 * len(q0)
        # the same rows reach the same solutions, to well within the stop (1e-10)
        assert np.abs(q - q_n)[converged].max(initial=0.0) < 1e-9
        assert np.isfinite(q).all() and np.isfinite(q_n).all()      # overflowed: back to 0
        # what is reported belongs to the joint vectors returned, in both paths
        robot.tool = chain[1]
        for qq, XX, ee, mm in ((q, X, errors, measures), (q_n, X_n, errors_n, measures_n)):
            assert np.abs(XX - robot.fk(qq)).max() < 1e-12
            np.testing.assert_allclose(ee, np.stack(pose_errors(XX, targets)), atol=1e-15)
            frames = calibrated_matrices.MatrixChain(*chain).frames(qq)
            np.testing.assert_allclose(
                mm, calibrated_matrices.MatrixChain.singularity_measures(frames), atol=1e-12)
        far = slice(-52, -2)
        assert converged[far].sum() < 50                     # random starts: some fail


def test_compiled_repeats_equal_the_numpy_path(numpy_path):
    rng = np.random.default_rng(43)
    n = 300
    polished = module._Polished.empty(n)
    q = rng.uniform(-np.pi, np.pi, (n, 8, 6))
    for i in range(n):
        for a, b in rng.integers(0, 8, (3, 2)):
            q[i, b] = q[i, a] + 2 * np.pi * rng.integers(-1, 2, 6)
            if rng.random() < 0.3:
                q[i, b, rng.integers(0, 6)] += rng.choice([5e-7, 2e-6])
    q[0, 3, 2] = np.nan
    polished.q[:] = q.reshape(-1, 6)
    polished.converged[:] = rng.random(8 * n) < 0.9
    unique = polished.unique()
    np.testing.assert_array_equal(unique, numpy_path(polished.unique))
    rows = rng.integers(0, 8 * n, 500)
    candidates = polished.q[rng.integers(0, 8 * n, 500)]
    candidates[::3] = polished.q[rows[::3]] + 2 * np.pi
    new = polished.are_new(rows, candidates, unique)
    np.testing.assert_array_equal(new, numpy_path(polished.are_new, rows, candidates, unique))
    assert new.any() and not new.all()
    assert polished.is_new(5, polished.q[5] + 1.0, unique) == numpy_path(
        polished.is_new, 5, polished.q[5] + 1.0, unique)


@pytest.mark.parametrize("kind", ["random", "wrist", "elbow", "shoulder"])
def test_results_are_the_same_with_and_without_the_compiled_kernels(kind, numpy_path):
    robot = calibrated(44)
    if kind == "random":
        q = np.random.default_rng(45).uniform(-np.pi, np.pi, (300, 6))
    else:
        q = singular_poses(robot, kind, 1e-2, 100, 46)
    X = robot.fk(q)
    fast, plain = ur(robot, X), numpy_path(ur, robot, X)
    np.testing.assert_array_equal(fast.valid, plain.valid)
    both = fast.valid & plain.valid
    d = np.abs(np.angle(np.exp(1j * (fast.solutions - plain.solutions))))[both]
    assert d.max() < 1e-8
    for name in fast.flags:
        np.testing.assert_array_equal(fast.flags[name], plain.flags[name])
    np.testing.assert_array_equal(fast.reason, plain.reason)
    one = ur(robot, X[0])
    np.testing.assert_array_equal(one.valid, fast.valid[0])


def test_the_environment_variable_switches_the_compiled_paths(monkeypatch):
    """DQLAB_COMPILED=0 switches the compiled kernels off at the next call of dqlab.ik.ur
    (the same solutions, within the Newton steps' stop), 1 or unset on; anything else is
    refused naming the variable."""
    robot = calibrated(48)
    X = robot.fk(np.random.default_rng(49).uniform(-np.pi, np.pi, (20, 6)))
    fast = ur(robot, X)
    assert compiled.ready()
    monkeypatch.setenv("DQLAB_COMPILED", "0")
    plain = ur(robot, X)
    assert not compiled.ready()
    np.testing.assert_array_equal(plain.valid, fast.valid)
    assert np.abs(plain.solutions - fast.solutions).max() < 1e-8
    monkeypatch.setenv("DQLAB_COMPILED", "1")
    ur(robot, X[0])
    assert compiled.ready()
    monkeypatch.setenv("DQLAB_COMPILED", "maybe")
    with pytest.raises(ValueError, match="DQLAB_COMPILED must be 0"):
        ur(robot, X[0])
    monkeypatch.delenv("DQLAB_COMPILED")
    compiled.refresh()


def test_ready_without_numba(monkeypatch):
    """Without numba (as in the browser), ready() says so and the numpy path is used."""
    monkeypatch.setattr(compiled, "_READY", None)
    monkeypatch.setattr(dqlab_compiled.importlib.util, "find_spec", lambda name: None)
    assert compiled.ready() is False
    robot = calibrated(47)
    q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    result = ur(robot, robot.fk(q))
    assert result.count == 8 and (np.abs(result.solutions - q).max(axis=-1) < 1e-9).any()


def test_the_generated_lanes_are_those_of_the_generator():
    """dqlab/_fast/newton_lanes.py is what tools/generate_newton_lanes.py writes."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    run = subprocess.run([sys.executable, str(root / "tools" / "generate_newton_lanes.py"),
                          "--check"], capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr


def test_the_lanes_cosines_and_sines_are_the_librarys():
    """The kernel's own cosine and sine (reduction by pi/2, fdlibm's polynomials, on eight
    branches at once) within an ulp of numpy's, over four turns and at multiples of pi/4."""
    assert compiled.ready()
    W, index = compiled.W, compiled.INDEX
    rng = np.random.default_rng(48)
    links = np.zeros((6, 5))
    links[:, 4] = rng.uniform(-1.0, 1.0, 6)
    angles = np.concatenate([rng.uniform(-4 * np.pi, 4 * np.pi, 48 * 400),
                             np.arange(-16, 32) * np.pi / 4])
    S = np.zeros(compiled.NV * W)
    worst = 0.0
    for chunk in angles.reshape(-1, 6, W):
        for i in range(6):
            S[(index["q0"] + i) * W:(index["q0"] + i + 1) * W] = chunk[i] - links[i, 4]
        compiled.lane_angles(S, links)
        for i in range(6):
            c = S[(index["c0"] + i) * W:(index["c0"] + i + 1) * W]
            s = S[(index["s0"] + i) * W:(index["s0"] + i + 1) * W]
            theta = S[(index["q0"] + i) * W:(index["q0"] + i + 1) * W] + links[i, 4]
            worst = max(worst, np.abs(c - np.cos(theta)).max(), np.abs(s - np.sin(theta)).max())
    assert worst <= 2.3e-16, worst



def test_the_lanes_recompute_the_joints_that_took_a_long_step():
    """After a step, the joints that moved 0.02 rad or more (or by no number) get the
    cosine and sine of their new angle, as the lanes compute them at a start; the others
    keep the values their step turned, bit for bit."""
    assert compiled.ready()
    W, index = compiled.W, compiled.INDEX
    rng = np.random.default_rng(49)
    links = np.zeros((6, 5))
    links[:, 4] = rng.uniform(-1.0, 1.0, 6)
    S = np.zeros(compiled.NV * W)
    for _ in range(50):
        S[:] = rng.uniform(-1.0, 1.0, S.size)           # turned values: anything
        q = slice(index["q0"] * W, (index["q0"] + 6) * W)
        x = slice(index["x0"] * W, (index["x0"] + 6) * W)
        cs = slice(index["c0"] * W, (index["s0"] + 6) * W)
        S[q] = rng.uniform(-4 * np.pi, 4 * np.pi, 6 * W)
        S[x] = rng.choice([0.0, 0.019, -0.0199, 0.02, -0.3, 2.0, np.nan], 6 * W)
        before = S.copy()
        compiled.lane_recompute(S, links)
        fresh = before.copy()
        compiled.lane_angles(fresh, links)
        long_step = ~(np.abs(before[x]) < 0.02)
        assert long_step.any() and not long_step.all()
        changed = np.tile(long_step, 2)                 # (c0..c5, s0..s5 lane by lane)
        assert np.array_equal(S[cs][changed], fresh[cs][changed])
        assert np.array_equal(S[cs][~changed], before[cs][~changed])
        outside = np.ones(S.size, dtype=bool)
        outside[cs] = False
        assert np.array_equal(S[outside], before[outside], equal_nan=True)

def test_distinct_small_integers_are_unique_and_searchsorted():
    """The repairs' distinct starts (``_distinct``): numpy's ``unique`` of small integers
    and each one's rank among them (``searchsorted``), empty and repeated values too."""
    assert compiled.ready()
    rng = np.random.default_rng(50)
    for size in (1, 2, 7, 48, 300):
        for count in (0, 1, 5, 40):
            values = rng.integers(0, size, count)
            used, rank = compiled._distinct(values, size)
            np.testing.assert_array_equal(used, np.unique(values))
            np.testing.assert_array_equal(rank, np.searchsorted(np.unique(values), values))


def test_a_repeated_start_is_stepped_once_on_both_paths():
    """A start equal to an earlier one of its pose (the wrist family's members away from
    the wrist singularity are one joint vector) is stepped once: numpy's
    ``_stepped_once`` names the first equal start of the pose (against a loop over the
    pairs), and the compiled queue (``_push``, pose by pose) holds each distinct start
    once and offers every owner the start equal to its own."""
    assert compiled.ready()
    rng = np.random.default_rng(51)
    pool = rng.uniform(-np.pi, np.pi, (4, 6))
    for count in (1, 6, 30):
        poses = np.sort(rng.integers(0, 3, count))
        starts = pool[rng.integers(0, pool.shape[0], count)]
        first = module._stepped_once(starts, poses)
        expected = [next(i for i in range(j + 1) if poses[i] == poses[j]
                         and np.array_equal(starts[i], starts[j])) for j in range(count)]
        np.testing.assert_array_equal(first, expected)
        queue = compiled._queue(2)
        for pose in np.unique(poses):
            mine = np.flatnonzero(poses == pose)
            owners = np.repeat(8 * pose + np.arange(2), mine.size)
            which = np.tile(np.arange(mine.size), 2)
            queue = compiled._push(queue, pose, owners, starts[mine], which)
        queued_owners, queued_which, queued_starts, queued_poses, (o, m) = queue
        assert m == np.unique(np.column_stack([poses, starts]), axis=0).shape[0]
        assert o == 2 * count
        for j in range(o):
            pose = queued_owners[j] // 8
            assert queued_poses[queued_which[j]] == pose
        offered = queued_starts[queued_which[:o]]
        mine_in_order = np.concatenate([np.tile(starts[poses == pose], (2, 1))
                                        for pose in np.unique(poses)])
        np.testing.assert_array_equal(offered, mine_in_order)


def test_compiled_gram_and_acceptance_equal_the_numpy_path(numpy_path):
    """J^T J from the lanes' frames equals the matrix kernel's to rounding (with a tool, at
    and near singular configurations); the restarts' acceptance takes the same starts and
    leaves the same rows and unique marks as the Python loop."""
    robot = calibrated(48)
    chain, q0, targets = chain_and_starts(robot, 49, 40)
    q = q0[np.isfinite(q0).all(axis=1)]
    kernel = calibrated_matrices.MatrixChain(*chain)
    J = kernel.jacobian(kernel.frames(q))
    np.testing.assert_allclose(compiled.gram(*chain, q), np.swapaxes(J, -1, -2) @ J,
                               rtol=0, atol=1e-13)
    nearest = module._nearest_exact(robot)
    near, direction = module._near_singular(nearest, chain[1], q)
    near_n, direction_n = numpy_path(module._near_singular, nearest, chain[1], q)
    np.testing.assert_array_equal(near, near_n)
    assert near.any() and not near.all()
    np.testing.assert_allclose(direction, direction_n, rtol=0, atol=1e-9)
    # acceptance: starts that repeat rows, each other, or fail, in one pose and across poses
    rng = np.random.default_rng(50)
    polished = module._Polished.empty(6)
    polished.q[:] = rng.uniform(-np.pi, np.pi, (48, 6))
    polished.converged[:] = rng.random(48) < 0.7
    unique = polished.unique()
    owners = rng.integers(0, 48, 120)
    starts = rng.uniform(-np.pi, np.pi, (120, 6))
    starts[::4] = polished.q[owners[::4] ^ 1] + 2 * np.pi     # a repeat of a neighbour
    starts[1::7] = starts[0::7][:starts[1::7].shape[0]]        # a repeat of another start
    converged = rng.random(120) < 0.8
    fast = (polished.q.copy(), unique.copy())
    taken = compiled.accept(owners, converged, starts, fast[0], fast[1])
    other = module._Polished(polished.q.copy(), polished.done, polished.converged, polished.X,
                             polished.measures, polished.errors)
    plain_unique = unique.copy()
    taken_n = numpy_path(module._accept, other, plain_unique, owners, converged, starts)
    np.testing.assert_array_equal(taken, taken_n)
    np.testing.assert_array_equal(fast[0], other.q)
    np.testing.assert_array_equal(fast[1], plain_unique)
    assert 0 < taken.size < converged.sum()


def poses_of_every_kind(robot, seed, random, near):
    """Poses (4, 4) of robot: ``random`` random ones, then ``near`` at 1e-2 and at 1e-4 from
    each of its wrist, elbow and shoulder singularities."""
    rng = np.random.default_rng(seed)
    q = np.concatenate([rng.uniform(-np.pi, np.pi, (random, 6))]
                       + [singular_poses(robot, kind, distance, near, seed + 1)
                          for kind in ("wrist", "elbow", "shoulder")
                          for distance in (1e-2, 1e-4)])
    return robot.fk(q)


def at_the_wrist(robot, n, seed):
    """Poses (4, 4) at the wrist singularity of robot's nearest exact arm (theta5 = 0 or pi
    exactly), where only theta234 -+ theta6 is fixed: the closed form picks a member."""
    exact = module.nominal_ur(robot)
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, 4] = rng.choice([0.0, np.pi], n) - exact.links[4].theta_offset
    return exact.fk(q)


def assert_results_equal(fast, other, exactly, poses=..., elbow_offset=0.0):
    """The IKResults fast and other are equal (at the poses ``poses`` of a batch): bit for
    bit, or to the rounding: 1e-12, but 1e-6 rad on the rows of a stretched or folded elbow
    (|sin theta3| below 1e-2, theta3 of the exact arm, whose joint offset is
    ``elbow_offset``), where a wrist family's member is chosen at the edge of the reach and
    the rounding of its theta234 is magnified in theta3 by a square root."""
    for name in ("valid", "reason"):
        np.testing.assert_array_equal(getattr(fast, name)[poses], getattr(other, name)[poses])
    for name in ("solutions", "position_error", "rotation_error"):
        a, b = getattr(fast, name)[poses], getattr(other, name)[poses]
        if exactly:
            np.testing.assert_array_equal(a, b)
        elif name == "solutions":
            stretched = np.abs(np.sin(b[..., 2] + elbow_offset)) < 1e-2
            np.testing.assert_allclose(a[~stretched], b[~stretched], rtol=0, atol=1e-12)
            np.testing.assert_allclose(a[stretched], b[stretched], rtol=0, atol=1e-6)
        else:
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    assert list(fast.flags) == list(other.flags)
    for name, flag in fast.flags.items():
        np.testing.assert_array_equal(flag[poses], other.flags[name][poses])


@pytest.mark.parametrize("make", [calibrated, physically_calibrated])
def test_compiled_exact_one_pose_equals_the_closed_form(make):
    """The exact arm's closed form of one pose, compiled (module._exact_one_pose), is the
    IKResult of the closed form's one-pose path on floats (dqlab._fast.ur_engine.solve_single)
    bit for bit wherever that path solves the pose: solutions (joint offsets subtracted and
    wrapped), valid rows, errors and flags, at four tolerances (the solver's three and the
    wrist family's 0.5), with and without a reference, on random poses, poses near each
    singularity and out of reach. Where that path hands the pose to the batch path (a wrist
    near its singularity), it is the batch path's, to the rounding: the members of a wrist
    family chosen by the reference's theta6 and checked by forward kinematics, and the rows
    moved along it to where the forearm reaches; with the wrist centre inside the shoulder
    cylinder; and where no row is valid, its reason."""
    from dqlab._fast import ur_engine
    from dqlab.ik import ur_parameters
    assert compiled.ready()
    robot = make(51)
    nearest = module._nearest_exact(robot)
    assert any(nearest.exact[6:])                       # offsets to subtract
    X = np.concatenate([poses_of_every_kind(robot, 52, 150, 15), at_the_wrist(robot, 30, 53)])
    X[:10, :3, 3] *= 3.0                                 # out of reach
    X[10:14, :3, 3] = [0.0, 0.0, 0.3]                    # wrist centre near the axis
    references = np.random.default_rng(54).uniform(-np.pi, np.pi, (len(X), 6))
    prm = ur_parameters(nearest.robot)
    wide = 2 * nearest.position_gap
    d4, d6 = nearest.exact[3], nearest.exact[5]
    counts = {"floats": 0, "batch": 0, "no row": 0, "inside": 0}
    for tol in (1e-9, wide, 10 * wide, 0.5):
        for T, reference in zip(X, references, strict=True):
            for q_ref in (None, reference):
                fast = module._exact_one_pose(nearest, T, q_ref, tol, 5e-7, 1e-2)
                floats = ur_engine.solve_single(nearest.robot, prm, T, tol, 5e-7, 1e-9, q_ref,
                                                None, 1e-2)
                if floats is not None:
                    counts["floats"] += 1
                    assert_results_equal(fast, floats, exactly=True)
                    continue
                batch = ur_engine.solve_batch(nearest.robot, prm, T, tol, 5e-7, 1e-9, None,
                                              q_ref, "equations", 1e-2)
                x5, y5 = T[:2, 3] - d6 * T[:2, 2]
                counts["inside"] += x5 * x5 + y5 * y5 < d4 * d4
                counts["batch" if batch.valid.any() else "no row"] += 1
                assert_results_equal(fast, batch, exactly=False,
                                     elbow_offset=nearest.exact[8])
    assert (counts["floats"] >= 1000 and counts["batch"] >= 200 and counts["no row"] >= 60
            and counts["inside"] >= 20), counts


@pytest.mark.parametrize("make", [calibrated, physically_calibrated])
def test_compiled_exact_poses_equal_the_batch_closed_form(make):
    """The exact arm's closed form of a batch, compiled pose by pose with the poses it does
    not solve handed to the closed form (module._exact_poses, what the batch path and the
    wrist family's members start from), is the closed form's own IKResult of the batch, at
    the tolerances the solver uses (tol, twice and twenty times the arms' gap, and 0.5 for
    the wrist family: at the last two, wrists up to about 0.01 and 0.1 rad from their
    singularity are at it), with references and without: the poses handed over (a wrist
    centre far beyond reach) bit for bit; those solved compiled (a wrist centre inside the
    shoulder cylinder too), with a valid row or with the reason of none, with the same
    valid rows, flags and reasons and the same numbers to the rounding in which math's and
    numpy's functions may differ."""
    assert compiled.ready()
    robot = make(54)
    nearest = module._nearest_exact(robot)
    X = np.concatenate([poses_of_every_kind(robot, 55, 1500, 50), at_the_wrist(robot, 50, 56)])
    X[:20, :3, 3] *= 5.0                                 # out of reach
    X[20:30, :3, 3] = [0.0, 0.0, 0.3]                    # wrist centre near the axis
    X[30:35, :3, 3] = [[1e100, 0.0, 0.0], [0.0, -1e200, 0.0], [0.0, 0.0, 1e300],
                       [-3e16, 3e16, 3e16], [1e10, 0.0, 0.0]]          # far beyond reach
    references = np.random.default_rng(57).uniform(-np.pi, np.pi, (len(X), 6))
    handed_over = []
    for tol in (1e-9, 2 * nearest.position_gap, 20 * nearest.position_gap, 0.5):
        for q_ref in (None, references):
            fast = module._exact_poses(nearest, X, q_ref, tol, 5e-7, 1e-2, module._closed_form)
            batch = ur(nearest.robot, X, tol=tol, q_ref=q_ref)
            R = X[:, :3, :3].reshape(-1, 9).T
            done = compiled.exact_poses(np.stack(quaternion_from_matrix_entries(*R), axis=-1),
                                        X[:, :3, 3], X[:, :3, 2], X,
                                        np.zeros(len(X)) if q_ref is None else q_ref[:, 5],
                                        nearest.exact, tol, 5e-7, NEAR_WRIST,
                                        NEAR_SINGULAR)[-1] != 0
            handed_over.append(int((~done).sum()))
            assert_results_equal(fast, batch, exactly=True, poses=~done)
            assert_results_equal(fast, batch, exactly=False, poses=done,
                                 elbow_offset=nearest.exact[8])
            assert not done[30:34].any() and (batch.position_error[30:34] >= 3e16).all()
            assert tol == 0.5 or batch.reason[:20].all()
            assert batch.rotation_error.any()            # rows checked by forward kinematics
    assert handed_over == [4] * 8                        # the four far beyond reach


@pytest.mark.parametrize("make", [calibrated, physically_calibrated])
def test_compiled_exact_fk_equals_the_robot_fk(make):
    """Forward kinematics of the nearest exact arm, compiled (what _repair corrects a pose
    with), is Robot.fk of that arm to the rounding, with joint offsets, at random joint
    vectors and at angles of many turns; and the flips of its restarts, one call for rows
    of different flips, are the exact arm's other elbow and wrist."""
    robot = make(58)
    nearest = module._nearest_exact(robot)
    assert any(nearest.exact[6:])
    q = np.random.default_rng(59).uniform(-np.pi, np.pi, (500, 6))
    q[:50] *= 7.0
    np.testing.assert_allclose(compiled.exact_fk(q, nearest.exact), nearest.robot.fk(q),
                               rtol=0, atol=1e-14)
    # _flip, the restarts' starts: the elbow flip reaches the same pose, the wrist flip
    # (theta4 + pi, -theta5, theta6 + pi) the same orientation (the arm then moves the wrist
    # centre back, which Newton does); each row flipped by its own bits
    bits = np.repeat([2, 1, 3, 0], 10)
    flips, X = module._flip(nearest, q[:40], bits), nearest.robot.fk(q[:40])
    X_flipped = nearest.robot.fk(flips)
    np.testing.assert_allclose(X_flipped[:10], X[:10], rtol=0, atol=1e-12)
    np.testing.assert_allclose(X_flipped[:30, :3, :3], X[:30, :3, :3], rtol=0, atol=1e-12)
    assert (np.abs(flips[:30] - q[:30]) > 1e-3).any(axis=1).all()
    np.testing.assert_array_equal(flips[30:], q[30:40])


def spectra(rng, n):
    """J^T J-like matrices Q diag(lambda) Q^T (n, 6, 6), the smallest eigenvalue a ratio of
    the largest spread from 1e-14 to 1, some within 1e-3 of the threshold 1e-4, some with
    two small eigenvalues (the direction is then ill-defined)."""
    Q, _ = np.linalg.qr(rng.normal(size=(n, 6, 6)))
    top = 10.0 ** rng.uniform(-2, 2, n)
    lam = top[:, None] * rng.uniform(0.05, 1.0, (n, 6))
    lam[:, 0] = top * 10.0 ** rng.uniform(-14, 0, n)
    edge = slice(0, n // 10)
    lam[edge, 0] = top[edge] * 1e-4 * (1 + rng.uniform(-1e-3, 1e-3, n // 10))
    lam[edge, 1:] = top[edge, None]                             # largest = top exactly
    pair = slice(n // 10, n // 5)
    lam[pair, 1] = lam[pair, 0] * (1 + 10.0 ** rng.uniform(-6, 0, n // 10))
    return Q @ (lam[..., None] * np.swapaxes(Q, -1, -2)), lam


def test_smallest_eigenvector_where_certain_is_eighs():
    """The compiled screen (inverse and power iteration, with bounds) answers where it is
    certain, as eigh does: the same near/not near, the same direction (largest entry
    positive) to 1e-9 where the two smallest eigenvalues are apart; elsewhere it says it
    does not know, and _near_singular asks eigh."""
    compiled.ready()
    rng = np.random.default_rng(52)
    H, lam = spectra(rng, 4000)
    H[-1] = np.eye(6) - np.outer(np.ones(6), np.ones(6)) / 6     # singular
    H[-2] = np.nan
    H[-3] = 0.0
    near, V, known = compiled.smallest(H, 1e-4)
    near_e, V_e = module._smallest_eigenvector(H[:-3])
    ok = known[:-3]
    np.testing.assert_array_equal(near[:-3][ok], near_e[ok])
    assert not known[-3:-1].any() and not near[-3:-1].any()     # nothing to say: eigh's
    assert near[-1] or not known[-1]                            # singular: near, or eigh's
    lam = np.sort(lam[:-3], axis=1)
    apart = lam[:, 1] > 2 * lam[:, 0]
    assert np.abs(V[:-3] - V_e)[ok & near[:-3] & apart].max() < 1e-9
    assert not V[:-3][~near[:-3]].any()                         # directions only where near
    ratio = lam[:, 0] / lam[:, -1]
    clear = (ratio < 0.5e-4) & apart | (ratio > 1e-2)
    assert known[:-3][clear].mean() > 0.995                      # certain nearly everywhere
    assert near_e.any() and (~near_e).any() and (~ok).any()      # ... but not at the edge


def test_compiled_quaternion_is_the_librarys_bit_for_bit():
    """The compiled paths read a flange's rotation quaternion with newton_compiled._quaternion,
    the float twin of dqlab._formulas.quaternion_from_matrix_entries (Shepperd): the same
    floats on random rotations and on half turns about each axis and about random axes
    (where each of the four rows of K is the largest)."""
    from dqlab.rotations import rot_y, rot_z
    compiled.ready()
    rng = np.random.default_rng(65)
    axes = rng.normal(size=(40, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    half_turns = 2.0 * axes[:, :, None] * axes[:, None, :] - np.eye(3)
    R = np.concatenate([np.linalg.qr(rng.normal(size=(400, 3, 3)))[0], half_turns,
                        [rot_x(np.pi), rot_y(np.pi), rot_z(np.pi), np.eye(3)]])
    R[:400] *= np.sign(np.linalg.det(R[:400]))[:, None, None]          # rotations
    for rotation in R:
        X = np.eye(4)
        X[:3, :3] = rotation
        assert compiled._quaternion(X) == quaternion_from_matrix_entries(
            *rotation.ravel().tolist())


def test_jacobi_smallest_eigenvector_is_eighs():
    """Where inverse iteration is not certain, the compiled repairs ask Jacobi's rotations:
    on the spectra of the test above (ratios from 1e-14 to 1, some at the threshold, some
    with two small eigenvalues) and a singular matrix, the same near / not near as eigh
    (but within 1e-12 of the threshold, where rounding decides), and the same direction
    (largest entry positive) to 1e-9 where the two smallest eigenvalues are apart."""
    compiled.ready()
    H, lam = spectra(np.random.default_rng(62), 2000)
    H[-1] = np.eye(6) - np.outer(np.ones(6), np.ones(6)) / 6     # singular
    near_e, V_e = module._smallest_eigenvector(H)
    near, V = np.zeros(len(H), dtype=bool), np.zeros((len(H), 6))
    for r in range(len(H)):
        near[r] = compiled._jacobi_smallest(H[r], 1e-4, V[r])
    lam = np.sort(lam, axis=1)
    ratio = lam[:, 0] / lam[:, -1]
    clear = np.abs(ratio / 1e-4 - 1.0) > 1e-12
    clear[-1] = True
    np.testing.assert_array_equal(near[clear], near_e[clear])
    apart = lam[:, 1] > 2 * lam[:, 0]
    assert np.abs(V - V_e)[apart].max() < 1e-9
    assert near[-1] and near.any() and (~near).any()


def test_restarts_step_a_shared_start_once(numpy_path):
    """A start shared by several rows (given once, with which) leaves the same rows, joint
    vectors, errors and marks as the same start given once per row (fewer than _FEW_ROWS
    starts either way: the numpy path's kernel is the same one)."""
    robot = calibrated(53)
    nearest = module._nearest_exact(robot)
    chain = (nearest.links, np.eye(4))
    rng = np.random.default_rng(54)
    X = robot.fk(rng.uniform(-np.pi, np.pi, (20, 6)))
    start = ur(nearest.robot, X, tol=2 * nearest.position_gap)
    rows = np.flatnonzero(start.valid.reshape(-1))
    X_0T = X
    owners = np.repeat(rows[::3], 3)                            # rows to restart, each from
    moves = start.solutions.reshape(-1, 6)[owners ^ rng.integers(1, 8, owners.size)][::3]
    moves = moves + rng.normal(0, 0.05, moves.shape)            # a sibling's start, moved,
    which = np.repeat(np.arange(moves.shape[0]), 3)             # three rows sharing each
    for run in (lambda f, *a: f(*a), numpy_path):
        results = []
        for shared in (False, True):
            polished = module._Polished.empty(20)
            polished.record(rows, *module._newton(*chain, start.solutions.reshape(-1, 6)[rows],
                                                  X_0T[rows // 8], 1e-9, 16))
            polished.converged[rows[::3]] = False
            unique = polished.unique()
            if shared:
                run(module._restart, chain, polished, unique, owners, moves, X_0T, 1e-9, 16,
                    which)
            else:
                run(module._restart, chain, polished, unique, owners, moves[which], X_0T, 1e-9,
                    16)
            results.append((polished, unique))
        (a, ua), (b, ub) = results
        np.testing.assert_array_equal(ua, ub)
        for name in ("q", "done", "converged", "X", "measures", "errors"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert owners.size <= module._FEW_ROWS
        assert (ua & ~a.converged).sum() == 0 and ua[rows[::3]].any()


def copied(polished):
    """A copy of a module._Polished, its arrays copied."""
    return module._Polished(*(np.array(getattr(polished, name)) for name in
                              ("q", "done", "converged", "X", "measures", "errors")))


@pytest.mark.parametrize("which", ["UR10e (ur_calibration documentation)",
                                   "UR3 (calibration.conf)", "synthetic, with a tool"])
def test_compiled_repairs_equal_the_numpy_path(which, numpy_path, monkeypatch):
    """The repairs (_repair, _family and _deflate), compiled step by step
    (dqlab._fast.newton_compiled.repairs), leave the branches of the poses that need them
    as the numpy path does: the same rows restarted and converged, the same distinct
    solutions, the joint vectors to the rounding (1e-8 rad: Newton stops at tol / 10,
    which a singularity magnifies), each reproducing its pose. The states are the solver's
    own, recorded where it calls the repairs: poses near each singularity of two real
    calibrations and of a synthetic one with a tool and a reference (theta6 for the wrist
    family's member of the corrected pose's closed form)."""
    from real_calibrations import real_calibrations
    if which.startswith("synthetic"):
        robot = calibrated(60)
        robot.tool = np.eye(4)
        robot.tool[:3, 3] = (0.0, 0.03, 0.15)
        options = {"q_ref": np.array([0.1, -1.0, 1.0, 0.3, 0.2, 2.5])}
    else:
        robot, options = real_calibrations()[which], {}
    q = np.concatenate([singular_poses(robot, kind, distance, 60, 61)
                        for kind in ("wrist", "elbow", "shoulder") for distance in (1e-2, 1e-3)])
    calls = []
    repairs = module._repairs

    def record(chain, nearest, polished, *rest):
        calls.append((chain, nearest, copied(polished), *rest))
        return repairs(chain, nearest, polished, *rest)

    monkeypatch.setattr(module, "_repairs", record)
    ur(robot, robot.fk(q), **options)
    assert len(calls) == 1
    chain, nearest, before, *rest = calls[0]
    tol = rest[6]
    fast, plain = copied(before), copied(before)
    repairs(chain, nearest, fast, *rest)
    numpy_path(repairs, chain, nearest, plain, *rest)
    restarted = fast.done & ~before.done | (fast.converged & ~before.converged)
    assert restarted.sum() >= 20, restarted.sum()               # many rows restarted
    for name in ("done", "converged"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(plain, name))
    np.testing.assert_array_equal(module._unique(fast.q, fast.converged),
                                  module._unique(plain.q, plain.converged))
    gap = np.abs(np.angle(np.exp(1j * (fast.q - plain.q))))[fast.converged]
    assert gap.max() < 1e-8
    assert (fast.errors[:, fast.converged] <= tol).all()


@pytest.mark.parametrize("which", ["UR10 (ur_calibration test, first set)",
                                   "UR5e (ur_calibration log)", "synthetic, with a tool"])
def test_compiled_array_path_equals_the_numpy_path(which, numpy_path, monkeypatch):
    """One pose, and batches of up to eight, take the array path compiled pose by pose
    (dqlab._fast.newton_compiled.array_poses) where the lean path does not do: its results
    are the numpy path's, on poses near each singularity of two real calibrations and of a
    synthetic one with a tool and a reference: the same valid rows, flags and reasons, the
    same solutions beyond the rows, the joints within 1e-8 rad (1e-6 where the smallest
    singular value of J is below 1e-4: there joints 1e-8 rad apart reach the pose within
    1e-12, and two paths that round differently stop apart along the flat direction). Many
    poses take it."""
    from real_calibrations import real_calibrations
    if which.startswith("synthetic"):
        robot = calibrated(63)
        robot.tool = np.eye(4)
        robot.tool[:3, 3] = (0.01, 0.0, 0.12)
        options = {"q_ref": np.array([-0.4, -1.3, 1.2, 0.1, -0.3, -2.0])}
    else:
        robot, options = real_calibrations()[which], {}
    q = np.concatenate([singular_poses(robot, kind, distance, 12, 64)
                        for kind in ("wrist", "elbow", "shoulder") for distance in (1e-2, 1e-3)])
    X = robot.fk(q)
    X[-1, :3, 3] = (3.0, 0.0, 0.0)                      # out of reach
    compiled_poses = []
    array_poses = module.compiled_array_poses
    monkeypatch.setattr(module, "compiled_array_poses", lambda *a, **k: compiled_poses.append(
        a[3].shape[0]) or array_poses(*a, **k))
    for chunk in [X[i:i + 4] for i in range(0, len(X), 4)] + list(X[:40]):
        fast, plain = ur(robot, chunk, **options), numpy_path(ur, robot, chunk, **options)
        for a, b in ((fast, plain), (fast.more, plain.more)):
            np.testing.assert_array_equal(a.valid, b.valid)
            both = a.valid & b.valid
            gap = np.abs(np.angle(np.exp(1j * (a.solutions - b.solutions)))).max(axis=-1)
            for q_row, row_gap in zip(a.solutions[both], gap[both], strict=True):
                if row_gap >= 1e-8:
                    assert row_gap < 1e-6, row_gap
                    assert np.linalg.svd(robot.jacobian(q_row), compute_uv=False)[-1] < 1e-4
        for name in fast.flags:
            np.testing.assert_array_equal(fast.flags[name], plain.flags[name], err_msg=name)
        np.testing.assert_array_equal(fast.reason, plain.reason)
    assert sum(compiled_poses) >= 40 and compiled_poses.count(1) >= 5, compiled_poses


def test_compiled_deflation_equals_the_numpy_path(numpy_path):
    """The deflated Newton steps of _deflate, compiled and on numpy, from starts near known
    solutions (some converge to a new one, some wander and give up), with a tool: the same
    joint vectors to 1e-8 rad on every row that stops below the stop, the same to 1e-6 on
    most of the others (a wandering row amplifies rounding)."""
    robot = physically_calibrated(56)
    (links, tool), q0, targets = chain_and_starts(robot, 57, 60)
    rng = np.random.default_rng(58)
    known = np.where(rng.random((len(q0), 8, 1)) < 0.5,
                     q0[:, None] + rng.normal(0.0, 0.3, (len(q0), 8, 6)), np.nan)
    starts = q0 + rng.normal(0.0, 0.05, q0.shape)
    starts[-1] = 0.0                                     # (the start that is not a number)
    fast = module._deflated_newton((links, tool), starts, targets, known, 1e-9, 10)
    plain = numpy_path(module._deflated_newton, (links, tool), starts, targets, known, 1e-9,
                       10)
    chain = calibrated_matrices.MatrixChain(links, tool)
    errors = np.stack(pose_errors(chain.transforms(chain.frames(fast)), targets))
    converged = errors.max(axis=0) < 1e-10
    assert converged.mean() > 0.3 and not converged.all()
    gap = np.abs(np.angle(np.exp(1j * (fast - plain)))).max(axis=1)
    assert gap[converged].max() < 1e-8
    assert np.mean(gap < 1e-6) > 0.9


def test_compiled_nearness_equals_the_numpy_path():
    """How near a singularity of the exact arm each valid row is (which rows _polish steps
    further, which are flagged near singular), in compiled code, is the numpy formula's,
    on random rows and rows at each singularity; at a singularity it is 0, and invalid rows
    are infinitely far."""
    robot = calibrated(3)
    nearest = module._nearest_exact(robot)
    q = np.random.default_rng(4).uniform(-np.pi, np.pi, (400, 6))
    q[:50, 2] = -nearest.exact[8] + np.linspace(-0.1, 0.1, 50)       # elbow
    q[50:100, 4] = -nearest.exact[10] + np.linspace(-0.1, 0.1, 50)   # wrist
    q[100, 2], q[101, 4] = -nearest.exact[8], -nearest.exact[10]      # at them
    valid = np.random.default_rng(5).random(400) < 0.8
    valid[100:102] = True
    fast = compiled.nearness(q, valid, nearest.exact)
    plain = np.where(valid, module._exact_nearness(nearest.robot, q), np.inf)
    np.testing.assert_allclose(fast, plain, rtol=1e-12, atol=1e-15)
    assert np.isinf(fast[~valid]).all() and fast[100:102].max() < 1e-15
    near = fast < module._POLISH_NEAR
    np.testing.assert_array_equal(near, plain < module._POLISH_NEAR)
    assert 40 < near.sum() < 200


def test_targets_far_beyond_reach_skip_the_compiled_array_paths(numpy_path, monkeypatch):
    """A batch of targets a million reaches away is answered by the exact arm's closed form
    (no branch to start from; nothing compiled beyond the closed form), and one with such a
    target among others takes the numpy path: the same results as the numpy path's, the
    others solved."""
    from real_calibrations import real_calibrations
    robot = real_calibrations()["UR5e (ur_calibration log)"]
    q = np.random.default_rng(70).uniform(-np.pi, np.pi, (12, 6))
    X = robot.fk(q)
    X[:2, :3, 3] = [(1e100, 0.0, 0.0), (0.0, -3e7, 1.0)]
    monkeypatch.setattr(module, "compiled_array_start", None)      # (not called)
    monkeypatch.setattr(module, "compiled_array_poses", None)
    for batch in (X[:2], X[:1], X):
        fast, plain = ur(robot, batch), numpy_path(ur, robot, batch)
        np.testing.assert_array_equal(fast.valid, plain.valid)
        np.testing.assert_allclose(fast.solutions, plain.solutions, rtol=0, atol=1e-8)
        np.testing.assert_allclose(fast.position_error[:2], plain.position_error[:2])
        for name in fast.flags:
            np.testing.assert_array_equal(fast.flags[name], plain.flags[name], err_msg=name)
        np.testing.assert_array_equal(fast.reason, plain.reason)
    assert not fast.valid[:2].any() and fast.flags["unreachable"][:2].all()
    assert fast.valid[2:].any(axis=-1).all() and "far" in fast.reason[0]
