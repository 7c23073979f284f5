"""URScript generation: golden strings, exact numbers, and every safety refusal."""

import re
from types import SimpleNamespace

import numpy as np
import pytest

import dqlab
from dqlab.ur import script as S
from dqlab.ur.script import UnsafeTargetError

HOME = [0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0]


def test_golden_movej():
    assert S.movej(HOME, a=1.2, v=0.5) == (
        "movej([0.0, -1.5707963267948966, 0.0, -1.5707963267948966, 0.0, 0.0], "
        "a=1.2, v=0.5, t=0.0, r=0.0)")
    assert S.movej([0.1, 0.2, -0.3, 0.4, -0.5, 0.6], t=2.0, r=0.01) == (
        "movej([0.1, 0.2, -0.3, 0.4, -0.5, 0.6], a=1.4, v=1.05, t=2.0, r=0.01)")


def test_golden_movel_servoj_stopj():
    assert S.movel([0.25, -0.1, 0.3, 0.0, np.pi, 0.0], a=0.5, v=0.1) == (
        "movel(p[0.25, -0.1, 0.3, 0.0, 3.141592653589793, 0.0], a=0.5, v=0.1, t=0.0, r=0.0)")
    assert S.servoj(HOME, t=0.002, lookahead_time=0.05, gain=500) == (
        "servoj([0.0, -1.5707963267948966, 0.0, -1.5707963267948966, 0.0, 0.0], "
        "t=0.002, lookahead_time=0.05, gain=500.0)")
    assert S.stopj(3) == "stopj(3.0)"


def test_numbers_survive_the_text_exactly():
    rng = np.random.default_rng(7)
    q = rng.uniform(-3, 3, 6)
    text = S.movej(q)
    back = np.array([float(x) for x in re.search(r"\[(.*?)\]", text).group(1).split(",")])
    np.testing.assert_array_equal(back, q)
    assert "-0.0" not in S.movej([-0.0] * 6)


def test_program_from_trajectory_golden():
    traj = SimpleNamespace(t=np.array([0.0, 0.01, 0.02]),
                           q=np.array([HOME, np.add(HOME, 0.001), np.add(HOME, 0.002)]))
    text = S.program_from_trajectory(traj, name="replay", gain=400)
    lines = text.splitlines()
    assert lines[0] == "def replay():" and lines[-1] == "end" and text.endswith("end\n")
    assert lines[1].startswith("  movej([0.0, -1.5707963267948966,")
    assert lines[2] == ("  servoj([0.001, -1.5697963267948967, 0.001, -1.5697963267948967, "
                        "0.001, 0.001], t=0.01, lookahead_time=0.1, gain=400.0)")
    assert lines[4] == "  stopj(2.0)"
    assert len(lines) == 6


def test_program_accepts_a_trajectory_with_more_fields():
    t = np.linspace(0, 1, 101)
    q = np.outer(0.5 * (1 - np.cos(np.pi * t)), [0.3, -0.2, 0.1, 0, 0, 0.4]) + HOME
    traj = SimpleNamespace(t=t, q=q, qd=np.gradient(q, t, axis=0), qdd=None)
    text = S.program_from_trajectory(traj)
    assert text.count("servoj(") == 100


# --- refusals -------------------------------------------------------------------------

@pytest.mark.parametrize("q, words", [
    ([0, 0, 0, 0, 0, np.nan], "movej target: joint 6 is nan, not a finite number"),
    ([0, np.inf, 0, 0, 0, 0], "joint 2 is inf"),
    ([0, 0, 7.0, 0, 0, 0], "joint 3 = 7 rad is outside its limits [-6.28319, 6.28319]"),
    ([0, 0, 0, -6.3, 0, 0], "joint 4 = -6.3 rad is outside"),
    ([0, 0, 0, 0, 0], "must have 6 values"),
])
def test_movej_refuses_bad_targets(q, words):
    with pytest.raises(UnsafeTargetError) as info:
        S.movej(q)
    assert words in str(info.value)


def test_wrist_3_is_unlimited_on_the_ur3_but_not_for_a_model_with_limits():
    assert S.movej([0, 0, 0, 0, 0, 20.0]).startswith("movej(")
    for model in (dqlab.models.ur3, dqlab.models.ur3e):      # the data sheets' "infinite"
        limits = S.SafetyLimits.for_robot(model())
        assert S.movej([0, 0, 0, 0, 0, 20.0], limits=limits).startswith("movej(")
    limits = S.SafetyLimits.for_robot(dqlab.models.ur5())
    with pytest.raises(UnsafeTargetError, match="joint 6 = 20 rad is outside"):
        S.movej([0, 0, 0, 0, 0, 20.0], limits=limits)
    with pytest.raises(ValueError, match="joint 6 = 20 rad is outside"):       # robot.limits
        S.movej([0, 0, 0, 0, 0, 20.0], limits=dqlab.models.ur5().limits)


@pytest.mark.parametrize("kwargs, words", [
    ({"a": 50.0}, "movej: a = 50.0 refused: must be > 0 and <= 10"),
    ({"v": 4.0}, "movej: v = 4.0 refused"),
    ({"v": 0.0}, "v = 0.0 refused: must be > 0"),
    ({"a": np.nan}, "a = nan refused"),
    ({"t": -1.0}, "t = -1.0 refused"),
    ({"r": -0.1}, "r = -0.1 refused"),
])
def test_movej_refuses_bad_speeds(kwargs, words):
    with pytest.raises(UnsafeTargetError) as info:
        S.movej(HOME, **kwargs)
    assert words in str(info.value)


def test_movej_refuses_a_joint_jump_and_a_too_short_time():
    far = np.add(HOME, [0, 0, 0, 0, 3.5, 0])
    with pytest.raises(UnsafeTargetError, match=r"joint 5 would jump by 3\.5 rad from the "
                                                r"current position.*another IK branch"):
        S.movej(far, q_from=HOME)
    near = np.add(HOME, [1.0, 0, 0, 0, 0, 0])
    assert S.movej(near, q_from=HOME, t=1.0)
    # 1 rad in 0.2 s peaks at 10 rad/s (a triangle), not the average 5 the check once used
    with pytest.raises(UnsafeTargetError, match=r"joint 1 speed 10 rad/s exceeds 3\.14159 "
                                                r"rad/s at its peak"):
        S.movej(near, q_from=HOME, t=0.2)


def test_movel_refusals():
    with pytest.raises(UnsafeTargetError, match="out of the UR3's reach"):
        S.movel([0.0, 0.0, 1.5, 0.0, 0.0, 0.0])
    with pytest.raises(UnsafeTargetError, match="movel target contains NaN"):
        S.movel([0.2, 0.0, np.nan, 0.0, 3.1, 0.0])
    with pytest.raises(UnsafeTargetError, match="movel: v = 2.0 refused"):
        S.movel([0.2, 0.0, 0.3, 0.0, 3.1, 0.0], v=2.0)
    with pytest.raises(UnsafeTargetError, match="movel: a = 9.0 refused"):
        S.movel([0.2, 0.0, 0.3, 0.0, 3.1, 0.0], a=9.0)


@pytest.mark.parametrize("kwargs, words", [
    ({"lookahead_time": 0.01}, "lookahead_time = 0.01 refused: must be >= 0.03 and <= 0.2"),
    ({"gain": 50}, "gain = 50.0 refused: must be >= 100 and <= 2000"),
    ({"gain": 3000}, "gain = 3000.0 refused"),
    ({"t": 0.0}, "t = 0.0 refused: must be > 0"),
])
def test_servoj_parameter_ranges(kwargs, words):
    with pytest.raises(UnsafeTargetError) as info:
        S.servoj(HOME, **kwargs)
    assert words in str(info.value)


def test_servoj_refuses_a_step_faster_than_the_joint_can_go():
    nxt = np.add(HOME, [0, 0.05, 0, 0, 0, 0])   # 0.05 rad in 8 ms = 6.25 rad/s
    with pytest.raises(UnsafeTargetError, match="joint 2 speed 6.25 rad/s exceeds"):
        S.servoj(nxt, t=0.008, q_from=HOME)
    assert S.servoj(nxt, t=0.1, q_from=HOME)


def _traj(n=50, dt=0.01):
    """Joints 1 and 2 from rest to rest (a half cosine)."""
    t = np.arange(n) * dt
    s = 0.5 * (1 - np.cos(np.pi * t / t[-1]))
    q = np.tile(HOME, (n, 1)) + np.outer(s, [0.2, 0.1, 0, 0, 0, 0])
    return SimpleNamespace(t=t, q=q)


@pytest.mark.parametrize("edit, words", [
    (lambda tr: tr.q.__setitem__((17, 2), np.nan), "trajectory target 17: joint 3 is nan"),
    (lambda tr: tr.q.__setitem__((20, 0), 6.5), "trajectory target 20: joint 1 = 6.5 rad is "
                                                "outside"),
    (lambda tr: tr.q.__setitem__((30, 1), tr.q[30, 1] + 4.0), "trajectory target 30: joint 2 "
                                                              "would jump by"),
    (lambda tr: tr.q.__setitem__((30, 1), tr.q[30, 1] + 0.1), "trajectory target 30 (t = 0.3 "
                                                              "s): joint 2 speed"),
    (lambda tr: tr.q.__setitem__((30, 1), tr.q[30, 1] + 0.01), "joint 2 acceleration"),
    (lambda tr: tr.t.__setitem__(10, tr.t[9]), "trajectory target 10: time 0.09 s does not "
                                               "increase"),
])
def test_program_refuses_a_bad_sample_and_names_it(edit, words):
    tr = _traj()
    edit(tr)
    with pytest.raises(UnsafeTargetError) as info:
        S.program_from_trajectory(tr)
    assert words in str(info.value), str(info.value)


def test_program_checks_the_approach_and_the_arguments():
    with pytest.raises(UnsafeTargetError, match="would jump by"):
        S.program_from_trajectory(_traj(), q_from=np.add(HOME, [3.5, 0, 0, 0, 0, 0]))
    with pytest.raises(TypeError, match="must have arrays t"):
        S.program_from_trajectory(np.zeros((3, 6)))
    with pytest.raises(ValueError, match="URScript identifier"):
        S.program_from_trajectory(_traj(), name="my program")


def test_safety_limits_validate_themselves():
    with pytest.raises(ValueError, match="max_joint_step must be a finite number > 0"):
        S.SafetyLimits(max_joint_step=0.0)
    with pytest.raises(ValueError, match="joint_limits"):
        S.SafetyLimits(joint_limits=[[1.0, -1.0]] * 6)


@pytest.mark.parametrize("name", ["end", "def", "while", "thread", "halt", "True"])
def test_program_names_may_not_be_keywords(name):
    with pytest.raises(ValueError, match="not a keyword"):
        S.program_from_trajectory(_traj(), name=name)


def test_a_program_starts_and_ends_at_rest_and_keeps_the_tcp_speed():
    # leaving the movej's rest at full speed: 2 rad/s after the first 10 ms is 200 rad/s^2
    t = np.arange(5) * 0.01
    q = np.tile(HOME, (5, 1)) + np.outer(t * 2.0, [1, 0, 0, 0, 0, 0])
    with pytest.raises(UnsafeTargetError, match=r"trajectory target 0 \(t = 0 s\): joint 1 "
                                                r"acceleration 200 rad/s\^2 \(from rest\)"):
        S.program_from_trajectory(SimpleNamespace(t=t, q=q))
    # a TCP faster than max_tcp_speed (1 m/s): the wrist 1 sweeps the arm's end
    tr = _traj()
    limits = S.SafetyLimits(max_tcp_speed=0.05, robot=dqlab.models.ur3())
    with pytest.raises(UnsafeTargetError, match="TCP speed .* exceeds max_tcp_speed = 0.05"):
        S.program_from_trajectory(tr, limits=limits)


@pytest.mark.parametrize("speed", [-1.0, 0.0, np.nan, np.inf, "fast", [1.0]])
def test_a_links_rated_speed_is_a_positive_number(speed):
    with pytest.raises(ValueError, match="Link max_speed must be"):
        dqlab.robot.Link(0.1, 0.0, 0.0, max_speed=speed)
    assert dqlab.robot.Link(0.1, 0.0, 0.0).max_speed is None
    assert dqlab.robot.Link(0.1, 0.0, 0.0, max_speed=2).max_speed == 2.0


def test_urscript_never_holds_nan_or_infinity():
    for bad in ([np.nan] * 6, [0.0] * 5 + [np.inf], [-np.inf, 0, 0, 0, 0, 0]):
        with pytest.raises(UnsafeTargetError, match="URScript has no such number"):
            S.urscript_list(bad)


def test_the_torque_ratings_and_payload_of_the_limits():
    limits = S.SafetyLimits.for_robot(dqlab.models.ur10e(), payload=5.0,
                                      payload_cog=[0.0, 0.0, 0.05])
    np.testing.assert_array_equal(limits.max_joint_torque, [330, 330, 150, 54, 54, 54])
    assert limits.checks_torques and limits.payload == 5.0
    assert not S.SafetyLimits().checks_torques                  # no robot: no torques
    assert S.as_safety_limits(None).checks_torques              # the default UR3's: checked
    np.testing.assert_array_equal(S.as_safety_limits(None).max_joint_torque,
                                  S.UR3_MAX_JOINT_TORQUE)
    # a robot without ratings has no torque check, unless given; with some, refused
    custom = S.SafetyLimits.for_robot(dqlab.models.ur3_mdh(), max_joint_speed=1.0)
    assert not custom.checks_torques
    with pytest.raises(ValueError, match="payload and payload_cog are only used by the torque"):
        S.SafetyLimits.for_robot(dqlab.models.ur3_mdh(), max_joint_speed=1.0, payload=1.0)
    links = list(dqlab.models.ur3().links)
    links[2] = dqlab.robot.Link(a=links[2].a, alpha=links[2].alpha, d=links[2].d,
                                inertia=links[2].inertia, max_speed=links[2].max_speed)
    partial = dqlab.robot.Robot(links, name="partial")
    with pytest.raises(ValueError, match=r"no rated torque for joints \[3\]"):
        S.SafetyLimits.for_robot(partial)
    bare = dqlab.models.ur3().links
    no_inertia = dqlab.robot.Robot([lk.with_inertia(None) for lk in bare], name="bare")
    with pytest.raises(ValueError, match="max_joint_torque: the torque check needs the robot's "
                                         "inertias"):
        S.SafetyLimits.for_robot(no_inertia)
