"""The desktop arm's firmware (a uArm Swift Pro's): its model, its limits and the G-code of a
plan."""

import re

import numpy as np
import pytest

from dqlab import desk_arm_firmware
from dqlab import pick_place as pp
from dqlab.models import desk_arm, desk_arm_joints_from_lab

#: The lab's task (chapter 12), starting and ending at the uArm's rest point.
REST_MM = [228.66, 0.0, 174.12]
ROWS = [REST_MM + [0, 0], [0, 170, 80, 0, 0], [0, 170, 30, 1, 0], [0, 170, 80, 1, 0],
        [0, -170, 85, 1, 180], [0, -170, 35, 0, 180], [0, -170, 85, 0, 180], REST_MM + [0, 0]]

COMMAND = re.compile(r"^(G0 X-?\d+\.\d\d Y-?\d+\.\d\d Z-?\d+\.\d\d F\d+"
                     r"|G2202 N3 V\d+\.\d\d|M2231 V[01]|G2004 P\d+)$")


@pytest.fixture(scope="module")
def plan():
    return pp.plan_pick_place(desk_arm(), pp.task_from_lab(ROWS), dt=0.04)


@pytest.fixture(scope="module")
def program(plan):
    return desk_arm_firmware.gcode_from_plan(plan, name="lab task")


def commands(program):
    """The commands of a program, comments and blank lines removed."""
    return [line.split(";")[0].strip() for line in program.splitlines()
            if line.split(";")[0].strip()]


def test_the_uarm_model_is_the_firmwares_forward_model():
    rng = np.random.default_rng(40)
    B, L, R = rng.uniform([0, 0, 0], [180, 135.6, 119.9], (400, 3)).T
    keep = (L + R >= 29) & (L + R <= 170)                     # the firmware's other limit
    B, L, R = B[keep], L[keep], R[keep]
    p = desk_arm_firmware.LENGTHS
    stretch = (p["lower_arm"] * np.cos(np.radians(L)) + p["upper_arm"] * np.cos(np.radians(R))
               + p["l2"] + p["front"])
    firmware = np.column_stack([stretch * np.sin(np.radians(B)),
                                -stretch * np.cos(np.radians(B)),
                                p["lower_arm"] * np.sin(np.radians(L))
                                - p["upper_arm"] * np.sin(np.radians(R)) + p["l1"]
                                - p["height"]])
    q_lab = desk_arm_firmware.lab_angles_from_motor(np.radians(np.column_stack([B, L, R])))
    ours = desk_arm_firmware.model().fk(desk_arm_joints_from_lab(q_lab))[:, :3, 3]
    assert np.allclose(ours, firmware, atol=1e-12)
    # and the motor angles of those points are the ones they came from
    assert np.allclose(desk_arm_firmware.motor_angles(firmware), np.column_stack([B, L, R]),
                       atol=1e-9)


def test_motor_angles_refuse_what_the_firmware_refuses():
    with pytest.raises(ValueError, match=r"point 0 \(positions\[0\]\): .* needs R = -1\.4\d deg"):
        desk_arm_firmware.motor_angles([[0.2288, 0.0, 0.1781]])          # the lab's own start point
    with pytest.raises(ValueError, match=r"point 1 \(positions\[1\]\): .* needs B = "):
        desk_arm_firmware.motor_angles([[0.2, 0.0, 0.1], [-0.1, 0.15, 0.05]])    # behind the arm
    with pytest.raises(ValueError, match="out of the uArm Swift Pro's reach"):
        desk_arm_firmware.motor_angles([[0.0, 0.4, 0.05]])
    with pytest.raises(ValueError, match="positions"):
        desk_arm_firmware.motor_angles([[0.1, np.nan, 0.1]])


def test_the_program_has_only_firmware_commands(program):
    lines = commands(program)
    assert lines and all(COMMAND.match(line) for line in lines), [
        line for line in lines if not COMMAND.match(line)]
    assert program.startswith("; lab task: 8 steps, ") and program.endswith("M2231 V0 ; pump off\n")


def test_the_program_visits_the_plans_points_in_order(plan, program):
    moves = [line for line in commands(program) if line.startswith("G0 ")]
    xyz = np.array([[float(v) for v in re.findall(r"[XYZ](-?\d+\.\d+)", m)] for m in moves])
    assert np.allclose(xyz, np.array(ROWS)[:, :3], atol=0.005)
    feeds = [int(m.rsplit("F", 1)[1]) for m in moves]
    assert feeds[0] == 3000 and all(f > 0 for f in feeds)
    # the feed of a segment is its straight distance over the plan's time for it
    at = np.all(np.abs(plan.q[:, None] - plan.targets) <= 1e-12, axis=-1)    # (N, K)
    arrive = [np.flatnonzero((plan.step == k) & at[:, k] & ~plan.qd.any(axis=1))[0]
              for k in range(len(ROWS))]
    start = [np.flatnonzero(plan.step == k)[0] - 1 for k in range(1, len(ROWS))]
    seconds = plan.t[arrive[1:]] - plan.t[start]
    distance = np.linalg.norm(np.diff(xyz, axis=0), axis=1)
    assert np.allclose(feeds[1:], np.round(60 * distance / seconds), atol=1)


def test_the_pump_switches_on_at_the_pick_and_off_at_the_place(program):
    lines = commands(program)
    moves = [k for k, line in enumerate(lines) if line.startswith("G0 ")]
    on, off = lines.index("M2231 V1"), [k for k, x in enumerate(lines) if x == "M2231 V0"]
    assert moves[2] < on < moves[3]                # after arriving at p_m, before lifting
    assert off[0] == 0 and moves[5] < off[1] < moves[6] and off[-1] == len(lines) - 1
    assert len(off) == 3 and lines.count("M2231 V1") == 1
    for k in (on, off[1]):                          # wait for the arm, switch, dwell 0.3 s
        assert lines[k - 1] == "G2004 P0" and lines[k + 1] == "G2004 P300"


def test_the_wrist_turns_before_the_transfer_and_only_when_it_changes(program):
    lines = commands(program)
    wrist = [k for k, line in enumerate(lines) if line.startswith("G2202 N3")]
    moves = [k for k, line in enumerate(lines) if line.startswith("G0 ")]
    assert [lines[k] for k in wrist] == ["G2202 N3 V0.00", "G2202 N3 V180.00",
                                          "G2202 N3 V0.00"]
    assert moves[3] < wrist[1] < moves[4] and lines[wrist[1] - 1] == "G2004 P0"


def test_the_comments_give_the_plans_and_the_firmwares_angles(plan, program):
    rows = re.findall(r"; step (\d): plan \(([^)]*)\), firmware \(([^)]*)\) deg", program)
    assert [int(k) for k, _, _ in rows] == list(range(len(ROWS)))
    firmware = np.array([[float(v) for v in m.split(",")] for _, _, m in rows])
    assert np.allclose(firmware, desk_arm_firmware.motor_angles(np.array(ROWS)[:, :3] / 1000),
                       atol=0.005)
    assert np.allclose(firmware[2], [180.0, 78.7, 62.9], atol=0.05)      # p_m


def test_write_gcode_writes_the_program(tmp_path, plan, program):
    path = desk_arm_firmware.write_gcode(tmp_path / "task.gcode", plan, name="lab task")
    assert path.read_text(encoding="ascii") == program


def test_a_plan_the_firmware_cannot_play_is_refused_by_step():
    rows = [[228.8, 0, 178.1, 0, 0], [0, 170, 80, 0, 0]]       # the lab's own start point
    plan = pp.plan_pick_place(desk_arm(), pp.task_from_lab(rows))
    with pytest.raises(ValueError, match=r"^step 0: \(228\.8, .*, 178\.1\) mm needs R ="):
        desk_arm_firmware.gcode_from_plan(plan)
    rows = [REST_MM + [0, 0], [0, 170, 80, 0, -30]]
    plan = pp.plan_pick_place(desk_arm(), pp.task_from_lab(rows))
    with pytest.raises(ValueError, match="step 1: wrist angle -30 deg is outside"):
        desk_arm_firmware.gcode_from_plan(plan)
    with pytest.raises(ValueError, match="start_feed"):
        desk_arm_firmware.gcode_from_plan(plan, start_feed=float("nan"))


NAMES_REFUSED = [
    ("x\nM2231 V1", r"^name must be one line of printable text: character '\\n' at position 1"),
    ("x\rM2231 V1", r"character '\\r' at position 1 is a control character"),
    ("reset \x18", r"character '\\x18' at position 6 is a control character"),
    ("stop!", r"^name must not hold '!' \(the firmware obeys them even in a comment\)"),
    ("go~", r"must not hold '~'"), ("status?", r"must not hold '\?'"),
    ("door@", r"must not hold '@'"), ("Démo", r"^name must be ASCII text .* 'é' at position 1"),
    ("", r"^name must not be empty"), ("x" * 81, r"^name must be at most 80 characters"),
]


def test_a_name_that_would_reach_the_firmware_is_refused(plan):
    """The firmware ends a line at \\n or \\r and obeys ?, !, ~, @ and Ctrl-X even inside a
    comment (Grbl 0.9's serial interrupt): none of them may reach the program."""
    for name, message in NAMES_REFUSED:
        with pytest.raises(ValueError, match=message):
            desk_arm_firmware.gcode_from_plan(plan, name=name)
    with pytest.raises(TypeError, match="^name must be text"):
        desk_arm_firmware.gcode_from_plan(plan, name=b"lab task")


def test_a_name_with_g_code_letters_stays_in_its_comment(plan):
    name = "G0 X0 Y0 Z0 F1 M2231 V1 (lab) ; $RST=* #1"
    program = desk_arm_firmware.gcode_from_plan(plan, name=name)
    assert program.splitlines()[0].startswith(f"; {name}: 8 steps")
    assert all(COMMAND.match(line) for line in commands(program))
    assert commands(program) == commands(desk_arm_firmware.gcode_from_plan(plan, name="lab task"))


def test_the_start_feed_is_a_number_in_range_written_rounded(plan):
    for start_feed, word in [(3000, "F3000"), (np.int64(3000), "F3000"), (1.9, "F2"),
                             (2500.4, "F2500"), (desk_arm_firmware.MAX_FEED, "F100000")]:
        program = desk_arm_firmware.gcode_from_plan(plan, start_feed=start_feed)
        moves = [line for line in commands(program) if line.startswith("G0 ")]
        assert moves[0].endswith(" " + word), (start_feed, moves[0])
    for start_feed in [True, "3000", 0.5, 1e30, 100_001, float("inf"), None]:
        with pytest.raises(ValueError, match=r"^start_feed must be a finite number >= 1 and "
                                             r"<= 100000, got "):
            desk_arm_firmware.gcode_from_plan(plan, start_feed=start_feed)


def test_a_plan_too_fast_for_the_firmware_is_refused_by_step():
    rows = [REST_MM + [0, 0], [0, 170, 80, 0, 0]]
    plan = pp.plan_pick_place(desk_arm(), pp.task_from_lab(rows), v_max=1e4, a_max=1e6,
                              dt=1e-4)
    with pytest.raises(ValueError, match=r"^step 1: the plan moves .* above the firmware's "
                                         r"maximum 100000 mm/min"):
        desk_arm_firmware.gcode_from_plan(plan)


def test_a_long_dwell_is_split_into_waits_a_16_bit_word_holds():
    rows = [REST_MM + [0, 0], [0, 170, 80, 0, 0], [0, 170, 30, 1, 0]]
    plan = pp.plan_pick_place(desk_arm(), pp.task_from_lab(rows), dwell=65.0, dt=0.5)
    lines = commands(desk_arm_firmware.gcode_from_plan(plan))
    on = lines.index("M2231 V1")
    assert lines[on + 1:on + 4] == ["G2004 P30000", "G2004 P30000", "G2004 P5000"]
    assert all(int(w[7:]) <= 32767 for w in lines if w.startswith("G2004 P"))


def test_write_gcode_refuses_before_opening_and_keeps_an_old_file(tmp_path, plan):
    path = tmp_path / "task.gcode"
    path.write_text("; the old program\n")
    with pytest.raises(ValueError, match="^name must be ASCII"):
        desk_arm_firmware.write_gcode(path, plan, name="Démo")
    with pytest.raises(TypeError, match="^plan must be a PickPlacePlan, got a str"):
        desk_arm_firmware.write_gcode(path, "plan")
    assert path.read_text() == "; the old program\n"
    with pytest.raises(ValueError, match="is a directory"):
        desk_arm_firmware.write_gcode(tmp_path, plan)
