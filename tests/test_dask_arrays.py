"""dqlab.dask_arrays and dqlab.reachability: the batch functions on dask arrays equal the numpy
ones number for number, on any chunking and scheduler; the reachability map against a direct
computation; the message without dask. Tests that need dask skip one by one when the extra
``scale`` is absent."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from dqlab import transform_from
from dqlab.dask_arrays import dexterity_dask, fk_dask, ik_ur_dask, reachability_map
from dqlab.dualquat import dual_quaternion_from_transform
from dqlab.ik import ur
from dqlab.jacobian import manipulability
from dqlab.models import scara_rsm5, ur3
from dqlab.quaternion import matrix_from_quaternion
from dqlab.reachability import (
    ReachabilityMap,
    pose_dexterity,
    reachability_statistics,
    super_fibonacci_quaternions,
)

ROOT = Path(__file__).resolve().parents[1]
ROBOT = ur3()
SINGULAR = np.array([0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0])   # wrist, elbow, shoulder


def joint_vectors(n=21, seed=7):
    """Seeded random joint vectors with singular ones among them."""
    q = np.random.default_rng(seed).uniform(-np.pi, np.pi, (n, 6))
    q[3] = SINGULAR
    q[5, 4] = 0.0                # wrist singular
    q[8, 2] = 0.0                # elbow stretched
    return q


def translation(p):
    X = np.eye(4)
    X[:3, 3] = p
    return X


def make_poses():
    """Reachable, singular and unreachable poses (beyond reach; wrist centre inside the
    shoulder cylinder)."""
    X = ROBOT.fk(joint_vectors())
    return np.concatenate([X, [translation([1.0, 0.0, 0.2]), translation([0.0, 0.0, 0.3])]])


POSES = make_poses()


def dask_array():
    return pytest.importorskip("dask.array")


def compute(*arrays):
    import dask
    return dask.compute(*arrays, scheduler="synchronous")


# -- forward and inverse kinematics ---------------------------------------------------------

@pytest.mark.parametrize("chunks", [1, 4, 7, 21, (2, 10, 9)])
def test_fk_equals_numpy_on_every_chunking(chunks):
    da = dask_array()
    q = joint_vectors()
    X = fk_dask(ROBOT, da.from_array(q, chunks=(chunks, 6)))
    assert X.shape == (21, 4, 4) and X.chunks[0] == da.from_array(q, chunks=(chunks, 6)).chunks[0]
    assert np.array_equal(compute(X)[0], ROBOT.fk(q))


def test_fk_two_leading_axes_and_a_chunked_joint_axis():
    da = dask_array()
    q = joint_vectors(24).reshape(4, 6, 6)
    X = fk_dask(ROBOT, da.from_array(q, chunks=(3, 4, 2)))       # joints cut in three chunks too
    assert X.chunks == ((3, 1), (4, 2), (4,), (4,))
    assert np.array_equal(compute(X)[0], ROBOT.fk(q))
    assert np.array_equal(compute(fk_dask(ROBOT, q))[0], ROBOT.fk(q))   # numpy in: one chunk


def assert_ik_equal(lazy, result):
    solutions, valid, pe, re, count, *flags = compute(
        lazy.solutions, lazy.valid, lazy.position_error, lazy.rotation_error, lazy.count,
        *lazy.flags.values())
    assert np.array_equal(solutions, result.solutions)
    assert np.array_equal(valid, result.valid)
    assert np.array_equal(pe, result.position_error)
    assert np.array_equal(re, result.rotation_error)
    assert np.array_equal(count, result.count)
    assert list(lazy.flags) == list(result.flags)
    for got, want in zip(flags, result.flags.values(), strict=True):
        assert np.array_equal(got, want)


@pytest.mark.parametrize("chunks", [1, 3, 8, 23])
def test_ik_ur_equals_numpy_with_singular_and_unreachable_poses(chunks):
    da = dask_array()
    result = ur(ROBOT, POSES)
    # the batch holds what the test is about
    assert result.flags["wrist_singular"][3] and result.flags["shoulder_singular"][3]
    assert result.flags["elbow_singular"][3] and result.flags["wrist_singular"][5]
    assert result.flags["elbow_singular"][8]
    assert result.flags["unreachable"][-2:].all() and result.count[-2:].sum() == 0
    assert_ik_equal(ik_ur_dask(ROBOT, da.from_array(POSES, chunks=(chunks, 4, 4))), result)


def test_ik_ur_dual_quaternions_leading_axes_and_options():
    da = dask_array()
    Q = dual_quaternion_from_transform(POSES[:22]).reshape(2, 11, 8)
    options = dict(tol=1e-8, residuals="fk", q_ref=[0.0, -1.0, 1.0, 0.0, 1.0, 0.5])
    lazy = ik_ur_dask(ROBOT, da.from_array(Q, chunks=(1, 4, 3)), **options)
    assert lazy.solutions.shape == (2, 11, 8, 6) and lazy.valid.chunks[:2] == ((1, 1), (4, 4, 3))
    assert_ik_equal(lazy, ur(ROBOT, Q, **options))


def test_ik_ur_with_a_tool():
    da = dask_array()
    X_6T = transform_from(np.eye(3), [0.0, 0.0, 0.1])
    X = ROBOT.fk(joint_vectors()) @ X_6T
    assert_ik_equal(ik_ur_dask(ROBOT, da.from_array(X, chunks=(5, 4, 4)), tool=X_6T),
                    ur(ROBOT, X, tool=X_6T))


def test_a_pose_that_is_not_rigid_raises_when_computed():
    da = dask_array()
    X = POSES[:4].copy()
    X[2, 0, 0] = 2.0
    lazy = ik_ur_dask(ROBOT, da.from_array(X, chunks=(2, 4, 4)))     # nothing computed yet
    with pytest.raises(ValueError):
        compute(lazy.valid)


# -- dexterity -------------------------------------------------------------------------------

def direct_dexterity(robot, X):
    """count and max manipulability of one pose, row by row."""
    result = ur(robot, X)
    w = [manipulability(robot.jacobian(q)) for q, ok in zip(result.solutions, result.valid,
                                                           strict=True) if ok]
    return int(result.count), max(w, default=0.0)


def test_pose_dexterity_follows_its_definition():
    count, w = pose_dexterity(ROBOT, POSES)
    for i, X in enumerate(POSES):
        c, wi = direct_dexterity(ROBOT, X)
        assert count[i] == c
        assert w[i] == pytest.approx(wi, rel=1e-12, abs=1e-18)
    assert w[3] < 1e-12 and count[3] == 8            # every branch singular
    assert np.all(w[-2:] == 0.0) and np.all(count[-2:] == 0)
    assert np.all(w[count > 0][:3] > 1e-4)


def test_pose_dexterity_is_det_j_and_does_not_depend_on_the_tcp():
    q = joint_vectors()
    J = ROBOT.jacobian(q)
    assert np.allclose(manipulability(J), np.abs(np.linalg.det(J)), rtol=1e-9, atol=1e-15)
    X_6T = transform_from(matrix_from_quaternion([0.9, 0.1, -0.3, 0.2] / np.linalg.norm(
        [0.9, 0.1, -0.3, 0.2])), [0.02, -0.03, 0.15])
    tooled = ur3()
    tooled.tool = X_6T
    count, w = pose_dexterity(ROBOT, ROBOT.fk(q))
    count_t, w_t = pose_dexterity(tooled, tooled.fk(q))
    assert np.array_equal(count, count_t)
    assert np.allclose(w, w_t, rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("chunks", [1, 6, 23])
def test_dexterity_equals_pose_dexterity(chunks):
    da = dask_array()
    count, w = compute(*dexterity_dask(ROBOT, da.from_array(POSES, chunks=(chunks, 4, 4))))
    count_np, w_np = pose_dexterity(ROBOT, POSES)
    assert np.array_equal(count, count_np) and np.array_equal(w, w_np)


# -- the reachability map --------------------------------------------------------------------

GRID = np.stack(np.meshgrid([-0.3, 0.0, 0.45], [-0.35, 0.1], [0.0, 0.25], indexing="ij"),
                axis=-1)
QUATS = super_fibonacci_quaternions(24)


def test_reachability_statistics_against_a_direct_computation():
    rmap = reachability_statistics(ROBOT, GRID, QUATS)
    assert rmap.reachable.shape == (3, 2, 2) and rmap.samples == 12 * 24
    R = matrix_from_quaternion(QUATS)
    for index in np.ndindex(GRID.shape[:-1]):
        X = transform_from(R, GRID[index])                      # (24, 4, 4)
        result = ur(ROBOT, X)
        count = result.count
        w = np.zeros(result.valid.shape)
        w[result.valid] = manipulability(ROBOT.jacobian(result.solutions[result.valid]))
        best = w.max(axis=-1)
        assert rmap.reachable[index] == np.count_nonzero(count)
        assert rmap.branches[index] == count.sum()
        if count.any():
            assert rmap.median_manipulability[index] == np.median(best[count > 0])
        else:
            assert np.isnan(rmap.median_manipulability[index])
    # the grid spans all cases: everything, part and nothing reachable
    assert set(np.unique(rmap.fraction)) >= {0.0, 1.0}
    assert np.any((rmap.fraction > 0) & (rmap.fraction < 1))
    assert np.array_equal(rmap.fraction, rmap.reachable / 24)
    assert np.array_equal(rmap.mean_count, rmap.branches / 24)


def assert_maps_equal(a, b):
    assert np.array_equal(a.positions, b.positions)
    assert np.array_equal(a.orientations, b.orientations)
    assert np.array_equal(a.reachable, b.reachable)
    assert np.array_equal(a.branches, b.branches)
    assert np.array_equal(a.median_manipulability, b.median_manipulability, equal_nan=True)


@pytest.mark.parametrize("chunk, block, scheduler", [
    (1, 8192, "synchronous"), (5, 30, "synchronous"), (None, 8192, "threads"),
    (12, 100, "sync")])
def test_reachability_map_equals_the_numpy_map(chunk, block, scheduler):
    dask_array()
    reference = reachability_statistics(ROBOT, GRID, QUATS)
    assert_maps_equal(reachability_map(ROBOT, GRID, QUATS, chunk=chunk, block=block,
                                       scheduler=scheduler), reference)


def test_the_same_code_on_a_distributed_cluster_by_client_and_by_address():
    dask_array()
    distributed = pytest.importorskip("distributed")
    reference = reachability_statistics(ROBOT, GRID, QUATS)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  protocol="tcp://", dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        assert address.startswith("tcp://")
        with distributed.Client(cluster, set_as_default=False) as client:
            assert_maps_equal(reachability_map(ROBOT, GRID, QUATS, chunk=4,
                                               scheduler=client), reference)
            lazy = ik_ur_dask(ROBOT, __import__("dask.array").array.from_array(
                POSES, chunks=(6, 4, 4)))
            valid, count = client.compute([lazy.valid, lazy.count], sync=True)
            assert np.array_equal(valid, ur(ROBOT, POSES).valid)
            assert np.array_equal(count, ur(ROBOT, POSES).count)
        assert_maps_equal(reachability_map(ROBOT, GRID, QUATS, chunk=4, scheduler=address),
                          reference)


def test_reachability_map_save_and_load(tmp_path):
    rmap = reachability_statistics(ROBOT, GRID, QUATS)
    rmap.save(tmp_path / "map.npz", command="python bench.py --save map.npz", samples=288,
              seconds=1.5)
    back = ReachabilityMap.load(tmp_path / "map.npz")
    assert_maps_equal(back, rmap)
    assert back.metadata == {"command": "python bench.py --save map.npz", "samples": 288,
                             "seconds": 1.5}
    with pytest.raises(ValueError, match="metadata 'robot'"):
        rmap.save(tmp_path / "bad.npz", robot=ROBOT)


def _saved_arrays(rmap, **changes):
    arrays = {name: getattr(rmap, name) for name in ("positions", "orientations", "reachable",
                                                     "branches", "median_manipulability")}
    arrays.update(changes)
    return arrays


@pytest.mark.parametrize("change, match", [
    ({"reachable": np.zeros(3, dtype=int)}, "reachable must have shape"),
    ({"branches": np.array([7.5, 0.0])}, "branches must be an array of integers"),
    ("negative", "reachable must be between 0 and 4"),
    ("more reachable than branches", "branches must be >= reachable"),
    ({"orientations": np.ones((4, 4))}, "orientations must be a unit quaternion"),
    ({"median_manipulability": np.zeros(2)}, "median_manipulability must be NaN exactly"),
    ({"positions": np.full((2, 3), np.nan)}, "positions contains NaN"),
])
def test_a_map_of_inconsistent_arrays_is_refused_by_load_naming_the_file(tmp_path, change,
                                                                        match):
    rmap = reachability_statistics(ROBOT, [[0.0, -0.35, 0.25], [0.9, 0.0, 0.2]],
                                   super_fibonacci_quaternions(4))
    if change == "negative":
        change = {"reachable": np.array([-1, 0])}
    elif change == "more reachable than branches":
        change = {"branches": np.array([3, 0])}
    np.savez(tmp_path / "bad.npz", **_saved_arrays(rmap, **change))
    with pytest.raises(ValueError, match=f"bad.npz: {match}"):
        ReachabilityMap.load(tmp_path / "bad.npz")


def test_a_file_that_is_not_a_map_is_refused_naming_it(tmp_path):
    rmap = reachability_statistics(ROBOT, [[0.0, -0.35, 0.25]], super_fibonacci_quaternions(4))
    rmap.save(tmp_path / "good.npz")
    data = (tmp_path / "good.npz").read_bytes()
    files = {"noise.npz": np.random.default_rng(0).bytes(300), "cut.npz": data[:len(data) // 2],
             "empty.npz": b""}
    for name, content in files.items():
        (tmp_path / name).write_bytes(content)
    np.save(tmp_path / "array.npy", np.zeros(3))
    objects = np.array([{}], dtype=object)
    np.savez(tmp_path / "objects.npz", **_saved_arrays(rmap, reachable=objects))
    np.savez(tmp_path / "missing.npz", positions=rmap.positions)
    for name, match in [("noise.npz", "not a reachability map"),
                        ("cut.npz", "not a reachability map"),
                        ("empty.npz", "not a reachability map"),
                        ("array.npy", "a single array"),
                        ("objects.npz", "stored as Python objects"),
                        ("missing.npz", "no array orientations")]:
        with pytest.raises(ValueError, match=f"{name}.*{match}"):
            ReachabilityMap.load(tmp_path / name)
    with pytest.raises(FileNotFoundError):
        ReachabilityMap.load(tmp_path / "absent.npz")
    with pytest.raises(ValueError, match="is a directory"):
        rmap.save(tmp_path)


def test_super_fibonacci_quaternions_cover_the_rotations_evenly():
    q = super_fibonacci_quaternions(2000)
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-15)
    # uniform rotations average to the zero matrix; a random set of 2000 to about 0.01
    assert np.abs(matrix_from_quaternion(q).mean(axis=0)).max() < 0.005
    # no two closer than a random set's typical nearest pair
    angles = 2 * np.arccos(np.clip(np.abs(q[:300] @ q[:300].T) - 2 * np.eye(300), -1, 1))
    assert angles.min() > 0.1


# -- arguments and the optional dependency ------------------------------------------------

@pytest.mark.parametrize("call, match", [
    (lambda da: fk_dask(ROBOT, da.zeros((4, 5))), r"q must have shape \(\.\.\., 6\)"),
    (lambda da: ik_ur_dask(ROBOT, da.zeros((4, 3, 3))),
     r"poses must have shape \(\.\.\., 4, 4\) or"),
    (lambda da: dexterity_dask(ROBOT, da.zeros((4, 7))), "poses must have shape"),
    (lambda da: ik_ur_dask(ROBOT, da.from_array(POSES), q_ref=np.zeros((2, 6))), "q_ref"),
    (lambda da: ik_ur_dask(ROBOT, da.from_array(POSES), tol=-1.0), "tol"),
    (lambda da: ik_ur_dask(scara_rsm5(), da.from_array(POSES)), "UR|joint"),
    (lambda da: reachability_map(ROBOT, GRID[..., :2], QUATS), "positions must have shape"),
    (lambda da: reachability_map(ROBOT, GRID, QUATS[:, :3]), "orientations"),
    (lambda da: reachability_map(ROBOT, GRID, 2 * QUATS), "orientations"),
    (lambda da: reachability_map(ROBOT, GRID, QUATS[0]), r"orientations must have shape \(K"),
    (lambda da: reachability_map(ROBOT, GRID, QUATS, chunk=0), "chunk"),
    (lambda da: reachability_map(ROBOT, GRID, QUATS, block=2.5), "block"),
    (lambda da: reachability_map(ROBOT, GRID, QUATS, scheduler="fast"), "scheduler"),
    (lambda da: reachability_map(ROBOT, GRID, QUATS, scheduler=3), "scheduler"),
    (lambda da: reachability_statistics(ROBOT, [[0, 0, np.nan]], QUATS), "positions"),
])
def test_wrong_arguments_raise_value_errors_naming_them(call, match):
    da = dask_array()
    with pytest.raises(ValueError, match=match):
        call(da)


def test_wrong_count_of_orientations():
    with pytest.raises(ValueError, match="k must be an integer >= 1"):
        super_fibonacci_quaternions(0)


def test_text_is_refused():
    da = dask_array()
    with pytest.raises(TypeError, match="q must hold real numbers"):
        fk_dask(ROBOT, da.from_array(np.array([["a"] * 6])))


def test_without_dask_the_message_names_the_extra(monkeypatch):
    for name in ("dask", "dask.array"):
        monkeypatch.setitem(sys.modules, name, None)          # `import dask` now fails
    with pytest.raises(ImportError, match=r"pip install 'dqlab\[scale\]'") as info:
        fk_dask(ROBOT, np.zeros((3, 6)))
    assert info.value.__cause__ is None and info.value.__suppress_context__
    with pytest.raises(ImportError, match=r"dqlab\[scale\]"):
        reachability_map(ROBOT, GRID, QUATS)
    # the numpy part works without it
    assert reachability_statistics(ROBOT, GRID[:1, :1, :1], QUATS).samples == 24


def test_an_address_without_distributed_names_the_extra(monkeypatch):
    dask_array()
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(ImportError, match=r"pip install 'dqlab\[scale\]'"):
        reachability_map(ROBOT, GRID, QUATS, scheduler="tcp://127.0.0.1:8786")


def test_importing_dqlab_dask_arrays_does_not_import_dask():
    code = ("import sys, numpy as np, dqlab.dask_arrays, dqlab.reachability as s; "
            "import dqlab.models as m; r = m.ur3(); s.pose_dexterity(r, r.fk(np.zeros(6))); "
            "print(sorted(k for k in ('dask', 'distributed') if k in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr
