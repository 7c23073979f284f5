"""The practitioner's path: a UR5e from the maker's table, a 0.15 m gripper, one IK call,
the solution to send from where the robot stands, a readable result, errors that point at
the likely mistake."""

import math
import re

import numpy as np
import pytest

import dqlab
from dqlab._fast import ur_engine
from dqlab.ik import closest_solution, closest_ur_solution, ur
from dqlab.ik.ur_closed_form import ROW_NAMES, SOLUTION_ORDER
from dqlab.models import UR_DH, UR_SHAPE, ur3_mdh, ur5e
from dqlab.quaternion import quaternion_from_xyzw, xyzw_from_quaternion
from dqlab.robot import Link, Robot

UR5E_TABLE = {"d": [0.1625, 0, 0, 0.1333, 0.0997, 0.0996],
              "a": [0, -0.425, -0.3922, 0, 0, 0],
              "alpha": [math.pi / 2, 0, 0, math.pi / 2, -math.pi / 2, 0]}
Q_NOW = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])


def random_joints(n, seed=0):
    return np.random.default_rng(seed).uniform(-np.pi, np.pi, (n, 6))


# -- building a robot from a maker's table ------------------------------------------------

def test_from_dh_table_is_the_model_and_gets_ur_limits():
    robot = Robot.from_dh_table(**UR5E_TABLE, name="UR5e")
    q = random_joints(50)
    assert np.array_equal(robot.fk(q), ur5e().fk(q))
    assert np.array_equal(robot.limits, np.tile([-2 * np.pi, 2 * np.pi], (6, 1)))
    UR_SHAPE.check(robot)                                   # the closed form takes it
    assert UR_DH["UR5e"]["d"] == tuple(UR5E_TABLE["d"])     # the table above is the model's


def test_from_dh_table_takes_columns_only_by_name():
    with pytest.raises(TypeError):
        Robot.from_dh_table(UR5E_TABLE["d"], UR5E_TABLE["a"], UR5E_TABLE["alpha"])


def test_from_dh_table_options():
    robot = Robot.from_dh_table(**UR5E_TABLE, limits=None)
    assert np.all(np.isinf(robot.limits))
    per_joint = np.tile([-1.0, 2.0], (6, 1))
    per_joint[5] = [-np.inf, np.inf]
    robot = Robot.from_dh_table(**UR5E_TABLE, limits=per_joint, max_speed=[3.0] * 6,
                                theta_offset=[0, 0.1, 0, 0, 0, 0])
    assert np.array_equal(robot.limits, per_joint)
    assert [lk.max_speed for lk in robot.links] == [3.0] * 6
    assert robot.links[1].theta_offset == 0.1
    # modified DH: the report's UR3 rebuilt from its columns
    mdh = ur3_mdh()
    rebuilt = Robot.from_dh_table(d=[lk.d for lk in mdh.links], a=[lk.a for lk in mdh.links],
                                  alpha=[lk.alpha for lk in mdh.links],
                                  theta_offset=[lk.theta_offset for lk in mdh.links],
                                  convention="mdh", limits=None, base=mdh.base,
                                  tool=mdh.tool)
    q = random_joints(10, seed=3)
    assert np.array_equal(rebuilt.fk(q), mdh.fk(q))


@pytest.mark.parametrize("change, message", [
    ({"a": [0, -0.425, -0.3922, 0, 0]}, r"one entry per joint; got d: 6, a: 5"),
    ({"alpha": [90, 0, 0, 90, -90, 0]}, r"alpha\[0\] = 90 .*degrees\? convert with np.radians"),
    ({"d": [[0.1625] * 6]}, r"d must be a column of the table"),
    ({"d": [0.1625, 0, 0, np.nan, 0.0997, 0.0996]}, r"d contains NaN"),
    ({"limits": [1.0, -1.0]}, r"limits must satisfy lo <= hi"),
    ({"limits": np.zeros((5, 2))}, r"limits must have shape \(2,\) or \(6, 2\)"),
    ({"joint": ["revolute"] * 5}, r"joint must be one type or one per joint"),
])
def test_from_dh_table_refuses_a_mistake_by_name(change, message):
    with pytest.raises(ValueError, match=message):
        Robot.from_dh_table(**{**UR5E_TABLE, **change})


def test_link_docstring_and_joint_limit_error_point_at_the_usual_mistakes():
    assert "from_dh_table" in Link.__doc__
    with pytest.raises(ValueError, match=r"joint 1 .* = 17.1887 is beyond its limits .*degrees\?"):
        ur5e().check_joints(np.degrees(Q_NOW), limits="all")
    narrow = Robot.from_dh_table(**UR5E_TABLE, limits=[-1.0, 1.0])
    with pytest.raises(ValueError, match=r"joint 6 \(revolute\) = 1.5 is beyond its limits "
                                         r"\[-1, 1\]$"):        # no hint within 2 pi
        narrow.check_joints([0, 0, 0, 0, 0, 1.5], limits="all")
    with pytest.raises(ValueError, match=r"= 7 is beyond its limits \[-6.28319, 6.28319\]$"):
        ur5e().check_joints([0, 0, 0, 0, 0, 7.0], limits="all")   # within two turns: no hint


# -- the tool -----------------------------------------------------------------------------

def test_with_tool_offset_along_the_flange_z():
    bare = ur5e()
    robot = bare.with_tool(z=0.15)
    X_WF, X_WT = bare.fk(Q_NOW), robot.fk(Q_NOW)
    assert np.allclose(X_WT[:3, 3], X_WF[:3, 3] + 0.15 * X_WF[:3, 2], atol=1e-15)
    assert np.array_equal(X_WT[:3, :3], X_WF[:3, :3])
    assert bare.bare and not robot.bare                      # the original is not changed
    assert robot.name == "UR5e" and robot.links is bare.links
    X_6T = dqlab.transform_from(dqlab.rot_z(0.4), [0.01, 0.0, 0.2])
    assert np.array_equal(robot.with_tool(X_6T).tool, X_6T)  # replaces, not composes
    assert robot.with_tool().bare
    assert np.allclose(dqlab.transform_from_dual_quaternion(robot.tool_dq), robot.tool)
    assert np.array_equal(robot.base_dq, [1, 0, 0, 0, 0, 0, 0, 0])


@pytest.mark.parametrize("call, error, message", [
    (lambda r: r.with_tool(np.eye(4), z=0.1), ValueError, "not both"),
    (lambda r: r.with_tool(np.diag([1.0, 1.0, -1.0, 1.0])), ValueError, "X_nT must be a rigid"),
    (lambda r: r.with_tool(np.eye(3)), ValueError, "X_nT must"),
    (lambda r: r.with_tool(z=float("nan")), ValueError, "z must be"),
    (lambda r: r.with_tool(z="0.15"), ValueError, "z must be"),
    (lambda r: r.with_tool(None), TypeError, "X_nT must be a 4x4 transform, got None"),
])
def test_with_tool_refuses(call, error, message):
    with pytest.raises(error, match=re.escape(message)):
        call(ur5e())


# -- one pose with a tool: the single-pose path -------------------------------------------

def _robots():
    base = dqlab.transform_from(dqlab.rot_z(0.7) @ dqlab.rot_x(0.1), [0.3, -0.2, 0.8])
    tooled = ur5e().with_tool(z=0.15)
    moved = Robot(ur5e().links, base=base, tool=tooled.tool, name="moved UR5e")
    return {"tool": tooled, "base and tool": moved}


@pytest.mark.parametrize("kind", ["tool", "base and tool"])
def test_one_pose_with_a_tool_is_solved_on_floats_as_in_a_batch(kind, monkeypatch):
    robot = _robots()[kind]
    q = random_joints(300, seed=1)
    X = robot.fk(q)
    batch = ur(robot, X)
    singles = []
    calls = []
    monkeypatch.setattr(ur_engine, "solve_batch",
                        lambda *a, **k: calls.append(1) or _SOLVE_BATCH(*a, **k))
    for i in range(len(q)):
        singles.append(ur(robot, X[i]))
        singles.append(ur(robot, robot.fk_dq(q[i])))          # the dual-quaternion form too
    # away from the wrist singularity and the clipping cases, no pose leaves the float path
    assert len(calls) <= 3, len(calls)
    for i in range(len(q)):
        for one in singles[2 * i:2 * i + 2]:
            assert np.array_equal(one.valid, batch.valid[i])
            assert np.abs(one.solutions - batch.solutions[i]).max() < 1e-12
            assert np.array_equal(one.flags["unreachable"], batch.flags["unreachable"][i])
        assert batch.valid[i].any()
        best = closest_solution(singles[2 * i], q[i])
        assert np.allclose(best, q[i], atol=1e-9)
    assert all(r.position_error[r.valid].max() < 1e-12 for r in singles)


_SOLVE_BATCH = ur_engine.solve_batch


def test_one_pose_with_the_tool_argument_equals_the_robot_with_that_tool():
    robot = ur5e().with_tool(z=0.15)
    X = robot.fk(random_joints(50, seed=2))
    for i in range(len(X)):
        a = ur(robot, X[i])
        b = ur(ur5e(), X[i], tool=robot.tool)
        assert np.array_equal(a.valid, b.valid)
        assert np.array_equal(a.solutions, b.solutions)
    with pytest.raises(ValueError, match="tool"):
        ur(ur5e(), X[0], tool=np.diag([1.0, 1.0, -1.0, 1.0]))


# -- the printed result -------------------------------------------------------------------

def test_printed_result_names_the_branches_and_reads():
    robot = ur5e().with_tool(z=0.15)
    result = ur(robot, robot.fk(Q_NOW))
    text = repr(result)
    assert str(result) == text and "array(" not in text
    assert text.splitlines()[0] == "IKResult: one target, 8 of 8 rows valid; flags: none"
    assert ROW_NAMES == tuple(" ".join(b) for b in SOLUTION_ORDER)
    for name in ROW_NAMES:
        assert re.search(rf"^  \d +{name} +yes ", text, re.M), name
    row = np.degrees(Q_NOW).round(1)
    assert " ".join(f"{v:g}" for v in row) in text          # the generating row, in degrees


def test_printed_batch_result_counts_reasons_and_flags():
    robot = ur5e().with_tool(z=0.15)
    q = random_joints(100, seed=4)
    q[0] = [0, -np.pi / 2, 0, -np.pi / 2, 0, 0]             # every singularity at once
    X = robot.fk(q)
    X[1:4, 0, 3] += 3.0                                      # three out of reach
    result = ur(robot, X)
    text = repr(result)
    assert text.startswith("IKResult: 100 targets (shape (100,)), rows of 8 branches x 6 joints")
    counts = np.bincount(result.count, minlength=9)
    for c in range(9):
        assert (f"targets with {c} valid rows: {counts[c]}" in text) == (counts[c] > 0)
    assert "no solution: 3 targets: elbow" in text
    assert "unreachable on 3 targets" in text and "wrist_singular on" in text
    assert "array(" not in text


# -- errors that name the likely mistake -------------------------------------------------

@pytest.mark.parametrize("target, hint", [
    (np.eye(3), "a rotation matrix? A pose needs the position too: "
                "dqlab.transforms.transform_from(R, p)"),
    ([0.3, 0.1, 0.4, 0.0, 3.14, 0.0], "dqlab.ur.transform_from_pose(p)"),
    (np.eye(4)[:3], "Append the row [0, 0, 0, 1]"),
    ([0.1, 0.2, 0.3, 0.0, 0.0, 0.0, 1.0], "quaternion_from_xyzw"),
    ([1.0, 0.0, 0.0, 0.0], "with q as (w, x, y, z)"),
    (np.zeros((5, 3)), "a position, which only a position-only solve accepts"),
])
def test_a_target_of_the_wrong_shape_is_named_for_what_it_probably_is(target, hint):
    with pytest.raises(ValueError, match=re.escape(hint)) as info:
        ur(ur5e(), target)
    assert "target must have shape (..., 4, 4)" in str(info.value)
    # and every name the hint gives exists
    for name in re.findall(r"dqlab(?:\.\w+)+", str(info.value)):
        obj = dqlab
        for part in name.split(".")[1:]:
            obj = getattr(obj, part)


def test_xyzw_converters():
    q = dqlab.quaternion_normalize(np.random.default_rng(5).normal(size=(7, 4)))
    assert np.array_equal(quaternion_from_xyzw(xyzw_from_quaternion(q)), q)
    assert np.array_equal(xyzw_from_quaternion([1.0, 2, 3, 4]), [2.0, 3, 4, 1])
    Rotation = pytest.importorskip("scipy.spatial.transform").Rotation
    R = Rotation.from_quat(xyzw_from_quaternion(q)).as_matrix()     # scipy is scalar last
    assert np.allclose(R, dqlab.matrix_from_quaternion(q), atol=1e-14)
    back = quaternion_from_xyzw(Rotation.from_matrix(R).as_quat())
    back *= np.sign(np.sum(back * q, axis=-1))[:, None]          # q and -q: one rotation
    assert np.allclose(back, q, atol=1e-14)


# -- the one call ------------------------------------------------------------------------

def test_closest_ur_solution_is_the_composition_and_recovers_turned_joints():
    robot = ur5e().with_tool(z=0.15)
    rng = np.random.default_rng(6)
    q_now = rng.uniform(-2 * np.pi + 0.01, 2 * np.pi - 0.01, (200, 6))   # joints beyond pi
    X = robot.fk(q_now)
    q = closest_ur_solution(robot, X, q_now)
    assert np.allclose(q, q_now, atol=1e-8)          # standing there, it is the answer
    assert np.array_equal(q, closest_solution(ur(robot, X, q_ref=q_now), q_now, robot.limits))
    for i in range(5):          # one pose at a time (on floats): the same, to rounding
        assert np.allclose(closest_ur_solution(robot, X[i], q_now[i]), q[i], rtol=0,
                           atol=1e-13)
    # from elsewhere: within the limits, reproduces the pose, no nearer equivalent exists
    q_start = rng.uniform(-2 * np.pi + 0.01, 2 * np.pi - 0.01, (200, 6))
    q = closest_ur_solution(robot, X, q_start)
    assert np.all(np.abs(q) <= 2 * np.pi)
    assert np.allclose(robot.fk(q), X, atol=1e-10)
    result = ur(robot, X)
    cands, within = dqlab.ik.equivalent_solutions(result.solutions, robot.limits)
    dist = np.linalg.norm(cands - q_start[:, None, None], axis=-1)
    dist[~(within & result.valid[..., None])] = np.inf
    assert np.allclose(np.linalg.norm(q - q_start, axis=-1), dist.min(axis=(1, 2)), atol=1e-9)


def test_closest_ur_solution_limits_and_errors():
    robot = ur5e().with_tool(z=0.15)
    X = robot.fk(Q_NOW)
    limits = robot.limits.copy()
    limits[2] = [-np.pi, 0.0]                          # elbow down only
    q = closest_ur_solution(robot, X, np.minimum(Q_NOW, [9, 9, 0, 9, 9, 9]), limits=limits)
    assert q[2] < 0 and np.allclose(robot.fk(q), X, atol=1e-10)
    with pytest.raises(ValueError, match=r"q_now: joint 1 = 17.1887 is outside its limits "
                                         r".*degrees\? convert with np.radians"):
        closest_ur_solution(robot, X, np.degrees(Q_NOW))
    far = X.copy()
    far[0, 3] += 3.0
    with pytest.raises(ValueError, match=r"the target has no solution: elbow"):
        closest_ur_solution(robot, far, Q_NOW)
    with pytest.raises(ValueError, match=r"target \(1,\) has no solution"):
        closest_ur_solution(robot, np.stack([X, far]), Q_NOW)
    with pytest.raises(ValueError, match=r"q_now of shape \(3, 6\) does not broadcast"):
        closest_ur_solution(robot, np.stack([X, X]), np.tile(Q_NOW, (3, 1)))
    with pytest.raises(ValueError, match="within the joint limits"):
        closest_ur_solution(robot, X, [0, 0, 0, 0, 0, 0], limits=np.tile([0.0, 0.01], (6, 1)))


def test_closest_solution_where_a_wrap_rounds_back_within_the_limits():
    """A joint whose nearest equivalent falls just outside a limit by the rounding of one
    wrap formula and within it by the other's (found by the README's batch)."""
    robot = ur5e().with_tool(z=0.15)
    q = np.array([0.24922976250609086, -0.9208492660821479, -5.772769971235005,
                  -3.844964399535359, 5.592344663120784, -4.240273895255029])
    best = closest_solution(ur(robot, robot.fk(q)), q, robot.limits)
    assert np.allclose(best, q, atol=1e-9)


@pytest.mark.parametrize("limited", [True, False])
def test_closest_solution_of_one_target_equals_the_batch_path(limited):
    """One target is chosen on Python floats; a batch on arrays: the same answers."""
    robot = ur5e().with_tool(z=0.15)
    rng = np.random.default_rng(8)
    q = rng.uniform(-2 * np.pi + 1e-3, 2 * np.pi - 1e-3, (400, 6))
    q_ref = np.where(rng.random((400, 1)) < 0.5, q, rng.uniform(-6, 6, (400, 6)))
    limits = robot.limits if limited else None
    if limited:
        limits[2] = [-np.pi, 1.0]
        q[:, 2] = np.clip(q[:, 2], -np.pi, 1.0)
        q_ref[:, 2] = np.clip(q_ref[:, 2], -np.pi, 1.0)
    result = ur(robot, robot.fk(q))
    batch = closest_solution(result, q_ref, limits)
    for i in range(len(q)):
        one = IKResultRow(result, i)
        assert np.array_equal(closest_solution(one, q_ref[i], limits), batch[i]), i
        if not limited:
            assert np.array_equal(closest_solution(one, q_ref[i], wrapped=True),
                                  result.best(q_ref)[i])


def IKResultRow(result, i):
    return dqlab.ik.IKResult(result.solutions[i], result.valid[i], result.position_error[i],
                             result.rotation_error[i])


def test_closest_ur_solution_with_weights_or_on_the_branch():
    """A 0.5 rad tool twist with wrist 3 at 5.9 rad (it cannot follow within 2 pi): by plain
    joint distance the nearest solution turns the base by 2.25 rad and changes the shoulder;
    with weights on the big joints the base stays; keep_branch stays on the branch of q_now
    and unwinds wrist 3 instead; a target the branch cannot reach is refused by name."""
    from dqlab.ik import ur_branch
    from dqlab.rotations import rot_z

    robot = ur5e().with_tool(z=0.15)
    q_now = np.array([-2.603, -1.654, 1.893, 0.516, -2.55, 5.9])
    twist = np.eye(4)
    twist[:3, :3] = rot_z(0.5)
    X = robot.fk(q_now) @ twist
    plain = closest_ur_solution(robot, X, q_now)
    weighted = closest_ur_solution(robot, X, q_now, weights=(10, 10, 5, 1, 1, 1))
    kept = closest_ur_solution(robot, X, q_now, keep_branch=True)
    assert abs(plain[0] - q_now[0]) > 2.0 and ur_branch(robot, plain) // 4 != ur_branch(
        robot, q_now) // 4                                  # the shoulder changed
    assert abs(weighted[0] - q_now[0]) < 1e-9
    assert ur_branch(robot, kept) == ur_branch(robot, q_now) == 5
    assert np.allclose(kept[:5], q_now[:5], atol=1e-9)
    assert abs(kept[5] - (5.9 + 0.5 - 2 * np.pi)) < 1e-9
    for q in (plain, weighted, kept):
        assert np.allclose(robot.fk(q), X, atol=1e-10)
    # the weights' distance is the smallest: no other valid equivalent is nearer
    w = np.array([10, 10, 5, 1, 1, 1.0])
    cands, within = dqlab.ik.equivalent_solutions(ur(robot, X).solutions, robot.limits)
    ok = within & ur(robot, X).valid[:, None]
    assert ((w * (weighted - q_now) ** 2).sum()
            <= (w * (cands[ok] - q_now) ** 2).sum(axis=-1).min() + 1e-12)
    # batches, and a branch that cannot reach
    batch = closest_ur_solution(robot, np.stack([X, X]), np.stack([q_now, q_now]),
                                keep_branch=True)
    assert np.allclose(batch, kept)
    q = random_joints(400, seed=11)
    results = ur(robot, robot.fk(q))
    i = int(np.argmax(results.count < 8))                # a pose some branches cannot reach
    b = int(np.argmin(results.valid[i]))
    q_there = q[int(np.argmax(ur_branch(robot, q) == b))]   # a robot on such a branch
    with pytest.raises(ValueError, match="has no solution on the branch of q_now"):
        closest_ur_solution(robot, robot.fk(q[i]), q_there, keep_branch=True)
    closest_ur_solution(robot, robot.fk(q[i]), q_there)         # another branch reaches it
    with pytest.raises(ValueError, match="weights must be positive"):
        closest_ur_solution(robot, X, q_now, weights=(1, 1, 1, 1, 1, 0))
    with pytest.raises(ValueError, match=r"weights must have shape \(6,\)"):
        closest_ur_solution(robot, X, q_now, weights=(1, 1))
    # the branch is the row a pose reached with the joints is solved in (on a calibrated
    # UR, by its nearest exact UR's measures: the same row but within the arms' gap of a
    # singularity)
    from dqlab.identify import dh_parameters, robot_from_dh_parameters
    p = dh_parameters(ur5e()) + np.random.default_rng(9).uniform(-2e-3, 2e-3, 24)
    calibrated = robot_from_dh_parameters(ur5e(), p)
    q = random_joints(300, seed=10)
    for arm, share in ((robot, 1.0), (calibrated, 0.98)):
        result = ur(arm, arm.fk(q))
        gap = np.abs(np.angle(np.exp(1j * (result.solutions - q[:, None])))).max(axis=-1)
        row = np.argmin(np.where(result.valid, gap, np.inf), axis=-1)
        assert (row == ur_branch(arm, q)).mean() >= share
