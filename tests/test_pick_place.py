"""Tests of dqlab.pick_place: task -> joint targets -> timed trajectory -> object motion."""

import numpy as np
import pytest

from dqlab import ik
from dqlab import pick_place as pp
from dqlab.models import desk_arm

# the lab's sequence (mm, suction, degrees): start p_i, pick at p_m, place at p_f, with
# approach points 50 mm above the pick and place points
LAB_ROWS = [[228.8, 0, 178.1, 0, 0],
            [0, 170, 80, 0, 0],
            [0, 170, 30, 1, 0],
            [0, 170, 80, 1, 0],
            [0, -170, 85, 1, 180],
            [0, -170, 35, 0, 180],
            [0, -170, 85, 0, 180],
            [228.8, 0, 178.1, 0, 0]]


@pytest.fixture(scope="module")
def arm():
    return desk_arm()


@pytest.fixture(scope="module")
def plan(arm):
    return pp.plan_pick_place(arm, pp.task_from_lab(LAB_ROWS))


def within_limits(arm, q, wrist_limits=(-np.pi, np.pi)):
    lo = np.append(arm.limits[:, 0], wrist_limits[0])
    hi = np.append(arm.limits[:, 1], wrist_limits[1])
    return np.all((q >= lo) & (q <= hi))


def test_task_from_lab_converts_units_and_checks_suction():
    task = pp.task_from_lab(LAB_ROWS)
    assert len(task) == 8
    assert np.allclose(task.positions[2], [0.0, 0.17, 0.03])
    assert task.suction.tolist() == [False, False, True, True, True, False, False, False]
    assert np.isclose(task.wrist[4], np.pi)
    with pytest.raises(ValueError, match="step 1 has 0.5"):
        pp.task_from_lab([[0, 170, 30, 0, 0], [0, 170, 30, 0.5, 0]])
    with pytest.raises(ValueError, match="rows contains NaN"):
        pp.task_from_lab([[0, 170, np.nan, 0, 0]])
    with pytest.raises(ValueError, match=r"rows must have shape \(\.\.\., 5\)"):
        pp.task_from_lab([[0, 170, 30, 0]])
    with pytest.raises(ValueError, match="wrist must have shape"):
        pp.PickPlaceTask(positions=np.zeros((2, 3)), suction=[0, 1], wrist=[0.0])


def test_targets_reach_their_points_on_one_branch(arm):
    task = pp.task_from_lab(LAB_ROWS)
    targets = pp.joint_targets(arm, task)
    assert np.allclose(arm.fk(targets[:, :3])[:, :3, 3], task.positions, atol=1e-12)
    assert np.array_equal(targets[:, 3], task.wrist)
    # branch 0 (facing the point, elbow up) every time: theta3 <= 0
    assert np.all(targets[:, 2] <= 0)
    assert np.allclose(targets[:, :3], ik.desk_arm(arm, task.positions).solutions[:, 0])


def test_plan_is_finite_within_limits_and_reaches_every_target(arm, plan):
    assert np.all(np.isfinite(plan.q)) and np.all(np.isfinite(plan.qd))
    assert np.all(np.isfinite(plan.qdd)) and np.all(np.isfinite(plan.object))
    assert within_limits(arm, plan.q)
    assert np.all(np.diff(plan.t) > 0) and plan.t[0] == 0.0
    # every step's target is a sample, at the end of the samples of that step
    for k, target in enumerate(plan.targets):
        last = np.flatnonzero(plan.step == k)[-1]
        assert np.allclose(plan.q[last], target, atol=1e-12)
    assert np.allclose(plan.q[-1], plan.targets[-1])
    assert np.allclose(plan.qd[[0, -1]], 0.0) and np.allclose(plan.qdd[[0, -1]], 0.0)


def test_plan_respects_the_speed_and_acceleration_limits(arm):
    plan = pp.plan_pick_place(arm, pp.task_from_lab(LAB_ROWS), v_max=0.8, a_max=2.0,
                              dt=0.005)
    assert np.abs(plan.qd).max() <= 0.8 + 1e-12
    assert np.abs(plan.qdd).max() <= 2.0 + 1e-9
    # the speeds and accelerations are the derivatives of the positions
    dq = np.gradient(plan.q, plan.t, axis=0)
    inside = np.flatnonzero(np.diff(plan.step, prepend=-1, append=-1)[1:] == 0)[5:-5]
    assert np.allclose(dq[inside], plan.qd[inside], atol=2e-3)


def test_segments_are_the_chapter_10_quintic_motions(arm, plan):
    from dqlab.trajectory import joint_trajectory

    first = plan.step == 1
    segment = joint_trajectory(plan.targets[0], plan.targets[1], v_max=1.0, a_max=4.0,
                               law="quintic", dt=0.02)
    assert np.allclose(plan.q[first], segment.q[1:], atol=1e-15)
    assert np.allclose(plan.t[first], segment.t[1:], atol=1e-15)
    # joint 1 (the base) turns pi/2 and sets the pace at v_max = 1 rad/s: T = 15/8 pi/2
    assert np.isclose(segment.duration, 15 / 8 * np.pi / 2)


def test_object_moves_with_the_cup_while_sucking(plan):
    on = plan.suction
    assert plan.grasps == ((2, 5),)
    X_CO = np.linalg.inv(plan.cup) @ plan.object
    first_on = np.flatnonzero(on)[0]
    assert np.allclose(X_CO[on], X_CO[first_on], atol=1e-12)        # rigidly attached
    # still before the pick and after the release
    before, after = np.arange(first_on), np.flatnonzero(~on & (np.arange(len(on)) > first_on))
    assert np.allclose(plan.object[before], plan.object[0])
    assert np.allclose(plan.object[after], plan.object[-1])
    # it ends under the place point, turned back to its starting yaw by the wrist's 180 deg
    assert np.allclose(plan.object[-1, :3, 3], [0.0, -0.17, 0.035], atol=1e-12)
    assert np.allclose(plan.object[-1, :3, :3], plan.object[0, :3, :3], atol=1e-12)


def test_without_the_wrist_turn_the_object_arrives_turned_half_a_turn(arm):
    rows = np.array(LAB_ROWS, dtype=float)
    rows[:, 4] = 0.0
    plan = pp.plan_pick_place(arm, pp.task_from_lab(rows))
    assert np.allclose(plan.object[-1, :3, :3], np.diag([-1.0, -1.0, 1.0])
                       @ plan.object[0, :3, :3], atol=1e-12)


def test_an_unreachable_step_is_refused_with_its_index(arm):
    rows = [list(r) for r in LAB_ROWS]
    rows[4] = [0, -400, 85, 1, 180]
    with pytest.raises(ValueError, match=r"step 4: \(0, -400, 85\) mm is unreachable"):
        pp.plan_pick_place(arm, pp.task_from_lab(rows))


def test_a_step_outside_the_wrist_limits_is_refused(arm):
    with pytest.raises(ValueError, match="step 4: wrist angle 180 deg is outside"):
        pp.plan_pick_place(arm, pp.task_from_lab(LAB_ROWS), wrist_limits=(-2.0, 2.0))


def test_a_branch_outside_the_joint_limits_is_refused(arm):
    # the point behind the base axis is only reached facing it if the base may turn there;
    # with the base limited to +-60 deg only the turned-away solutions remain
    from dqlab.robot import Link, Robot

    limited = Robot([Link(a=lk.a, alpha=lk.alpha, d=lk.d,
                          limits=(-1.05, 1.05) if i == 0 else lk.limits)
                     for i, lk in enumerate(arm.links)], name="limited desk arm")
    rows = [[200, 0, 50, 0, 0], [-150, 0, 50, 0, 0]]
    with pytest.raises(ValueError, match="step 1: .* has no 'facing, elbow up' solution"):
        pp.joint_targets(limited, pp.task_from_lab(rows))
    targets = pp.joint_targets(limited, pp.task_from_lab(rows), branch="closest")
    assert within_limits(limited, targets)


def test_suction_without_an_object_under_the_cup_is_refused(arm):
    far = np.eye(4)
    far[:3, 3] = [0.2, 0.0, 0.0]
    with pytest.raises(ValueError, match="step 2: the suction comes on with no object"):
        pp.plan_pick_place(arm, pp.task_from_lab(LAB_ROWS), object_pose=far)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"v_max": 0.0}, "v_max must be a finite number > 0"),
    ({"a_max": np.nan}, "a_max must be a finite number > 0"),
    ({"dt": -0.1}, "dt must be a finite number > 0"),
    ({"dwell": -1.0}, "dwell must be a finite number >= 0"),
    ({"branch": 4}, "branch must be"),
    ({"wrist_limits": (1.0, 0.0)}, "wrist_limits must be"),
])
def test_plan_rejects_bad_arguments(arm, kwargs, message):
    with pytest.raises(ValueError, match=message):
        pp.plan_pick_place(arm, pp.task_from_lab(LAB_ROWS), **kwargs)


def test_plan_rejects_a_task_of_another_type(arm):
    with pytest.raises(TypeError, match="task must be a PickPlaceTask"):
        pp.plan_pick_place(arm, LAB_ROWS)


def test_random_reachable_tasks_never_give_nan_or_out_of_limit_samples(arm):
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = np.column_stack([rng.uniform(-3.0, 3.0, 6), rng.uniform(0.3, 1.4, 6),
                             rng.uniform(-2.6, -0.3, 6)])
        rows = np.column_stack([arm.fk(q)[:, :3, 3] * 1000, np.zeros(6),
                                rng.uniform(-170, 170, 6)])
        plan = pp.plan_pick_place(arm, pp.task_from_lab(rows), dt=0.05)
        assert np.all(np.isfinite(plan.q)) and within_limits(arm, plan.q)


def test_animation_records_the_arm_the_cup_and_the_object(arm, plan):
    viz = pytest.importorskip("dqlab.viz")
    scene = viz.Scene(grid_size=0.8, grid_step=0.05)
    viz.animate_pick_place(scene, arm, plan)
    paths = {c.get("path", "") for c in scene.commands()}
    assert any(p.endswith("/object/box") for p in paths)
    assert any(p.endswith("/cup/on") for p in paths)
    assert any(p.endswith("/pads/start") for p in paths)
    animation = [c for c in scene.commands() if c["type"] == "set_animation"]
    assert len(animation) == 1
    light = viz.Scene()
    viz.animate_pick_place(light, arm, plan, stride=4)
    assert len(light.html(bundle="none")) < len(scene.html(bundle="none"))
    with pytest.raises(ValueError, match="stride must be"):
        viz.animate_pick_place(viz.Scene(), arm, plan, stride=0)


@pytest.mark.parametrize("branch", [1.0, True, "1", None, 4, -1])
def test_a_branch_that_is_not_a_row_number_is_refused(arm, branch):
    with pytest.raises(ValueError, match="^branch must be 0, 1, 2, 3 or 'closest'"):
        pp.joint_targets(arm, pp.task_from_lab(LAB_ROWS), branch=branch)


def test_functions_that_take_a_robot_refuse_none(plan):
    task = pp.task_from_lab(LAB_ROWS)
    for call in (lambda: pp.joint_targets(None, task), lambda: pp.cup_poses(None, plan.targets),
                 lambda: pp.plan_pick_place(None, task)):
        with pytest.raises(TypeError, match="^robot must be a Robot, got None"):
            call()


def test_instants_that_cannot_be_told_apart_are_refused(arm):
    with pytest.raises(ValueError, match="dt = 1e.199 s and dwell = 0.3 s are too large"):
        pp.plan_pick_place(arm, pp.task_from_lab(LAB_ROWS), dt=1e199)


def test_a_tolerance_of_infinity_would_accept_any_target_and_is_refused(arm):
    with pytest.raises(ValueError, match="^tol must be a finite number >= 0, got inf"):
        pp.joint_targets(arm, pp.task_from_lab(LAB_ROWS), tol=np.inf)
