"""Tests for dqlab.ik.desk_arm: the lab report's tables, its IK erratum, round trips."""

import numpy as np
import pytest

from dqlab.ik import desk_arm as solve
from dqlab.models import (
    DESK_ARM,
    desk_arm,
    desk_arm_joints_from_lab,
    desk_arm_lab_from_joints,
    ur3,
)

# seeds/004, "Vérification du modèle" (MGD): lab angles in degrees -> position in mm
LAB_FK_TABLE = [((90, 90, 0), (229, 0, 179)),
                ((90, 51, 65), (226, 0, 0)),
                ((90, 42, 21), (325, 0, 73)),
                ((90, 90, 45), (182, 0, 64))]
# seeds/004, "Vérification du modèle" (MGI): position in mm -> lab angles in degrees, as
# printed. Two inputs differ by 1 mm from the FK table's outputs (178 vs 179; 181, 63 vs
# 182, 64): the lab typed them by hand.
LAB_IK_TABLE = [((229, 0, 178), (90, 82, -6)),
                ((226, 0, 0), (90, 52, 66)),
                ((325, 0, 73), (90, 39, 19)),
                ((181, 0, 63), (90, 86, 44))]


def lab_mgi_as_printed(x, y, z, restore_offset=False):
    """The lab's MGI code (Réponse 10), in mm and degrees, transcribed faithfully.

    Its law-of-cosines line uses ``z`` where the derivation (Réponse 9) has
    ``z - (l0 - l4)``; ``restore_offset=True`` puts the offset back.
    """
    l0_l4, l1, l2, l3 = 35.0, 144.0, 162.0, 67.0
    d = (x ** 2 + y ** 2) ** 0.5
    q0 = np.arctan2(x, y)
    height = z - l0_l4 if restore_offset else z
    q2q1 = np.arccos(((d - l3) ** 2 + height ** 2 - (l1 ** 2 + l2 ** 2)) / (2 * l1 * l2))
    num = l2 * np.sin(q2q1) * (d - l3) + (l1 + l2 * np.cos(q2q1)) * (z - l0_l4)
    den = -l2 * np.sin(q2q1) * (z - l0_l4) + (l1 + l2 * np.cos(q2q1)) * (d - l3)
    q1 = np.arctan2(num, den)
    q2 = q2q1 - q1
    return np.degrees([q0, q1, q2])


def test_lab_derivation_sign_slip_gives_q1_minus_pi():
    """Réponse 9 prints Cramer's determinant as +k^2 (it is -k^2): its atan2 for q1 is off
    by pi; the code (Réponse 10) has the signs right."""
    l0_l4, l1, l2, l3 = 35.0, 144.0, 162.0, 67.0
    q = desk_arm_joints_from_lab(np.radians([90, 51, 65]))
    x, y, z = desk_arm().fk(q)[:3, 3] * 1000
    d, h = np.hypot(x, y), z - l0_l4
    qbar = np.arccos(((d - l3) ** 2 + h ** 2 - l1 ** 2 - l2 ** 2) / (2 * l1 * l2))
    s, c = np.sin(qbar), np.cos(qbar)
    printed = np.arctan2(-l2 * s * (d - l3) - (l1 + l2 * c) * h,
                         l2 * s * h - (l1 + l2 * c) * (d - l3))
    code = np.arctan2(l2 * s * (d - l3) + (l1 + l2 * c) * h,
                      -l2 * s * h + (l1 + l2 * c) * (d - l3))
    np.testing.assert_allclose(np.degrees(code), 51.0, atol=1e-9)
    np.testing.assert_allclose(np.degrees(printed), 51.0 - 180.0, atol=1e-9)


def lab_angles_deg(result):
    return np.degrees(desk_arm_lab_from_joints(result.solutions))


@pytest.mark.parametrize("q_deg, xyz_mm", LAB_FK_TABLE)
def test_ik_round_trips_the_lab_forward_table(q_deg, xyz_mm):
    arm = desk_arm()
    q = desk_arm_joints_from_lab(np.radians(q_deg))
    p = arm.fk(q)[:3, 3]
    np.testing.assert_array_equal(np.round(p * 1000) + 0.0, xyz_mm)
    result = solve(arm, p)
    assert result.valid[:2].all()            # facing the point: both elbows
    assert np.all(result.position_error[result.valid] < 1e-12)
    # facing the point with the elbow up: exactly the lab's angles
    np.testing.assert_allclose(lab_angles_deg(result)[0], q_deg, atol=1e-9)
    # from the printed (rounded) position: the lab's angles to within a degree
    rounded = solve(arm, np.array(xyz_mm) / 1000.0)
    np.testing.assert_allclose(lab_angles_deg(rounded)[0], q_deg, atol=1.0)


@pytest.mark.parametrize("xyz_mm, printed", LAB_IK_TABLE)
def test_lab_ik_erratum_reproduces_its_wrong_table(xyz_mm, printed):
    """The lab's formula without the l0 - l4 offset gives its printed (wrong) angles; with
    the offset restored it gives the FK table's angles, and so does dqlab."""
    wrong = lab_mgi_as_printed(*xyz_mm)
    np.testing.assert_array_equal(np.round(wrong) + 0.0, printed)
    fixed = lab_mgi_as_printed(*xyz_mm, restore_offset=True)
    ours = lab_angles_deg(solve(desk_arm(), np.array(xyz_mm) / 1000.0))[0]
    np.testing.assert_allclose(ours, fixed, atol=1e-9)
    fk_angles = dict((xyz, q) for q, xyz in LAB_FK_TABLE)
    nearest_fk_row = min(fk_angles, key=lambda xyz: np.linalg.norm(np.subtract(xyz, xyz_mm)))
    np.testing.assert_allclose(fixed, fk_angles[nearest_fk_row], atol=1.0)
    assert np.max(np.abs(wrong - np.array(fk_angles[nearest_fk_row]))) > 0.5


def test_random_round_trips_find_all_four_solutions():
    rng = np.random.default_rng(30)
    arm = desk_arm()
    q = rng.uniform(-np.pi, np.pi, size=(1000, 3))
    p = arm.fk(q)[:, :3, 3]
    result = solve(arm, p)
    assert result.solutions.shape == (1000, 4, 3)
    assert result.success.all()
    # the shoulder sits l3 out from the base axis, so the turned-away pair exists only for
    # points close enough to the base
    assert 0 < result.valid[:, 2:].mean() < 1
    reached = arm.fk(result.solutions)[..., :3, 3]
    err = np.linalg.norm(reached - p[:, None, :], axis=-1)
    assert np.all(err[result.valid] < 1e-12)
    np.testing.assert_allclose(result.position_error[result.valid], err[result.valid],
                               atol=1e-15)
    diff = np.angle(np.exp(1j * (result.solutions - q[:, None, :])))
    dist = np.where(result.valid, np.max(np.abs(diff), axis=-1), np.inf)
    assert np.all(np.min(dist, axis=-1) < 1e-7)
    # elbow labels: facing -> theta3 <= 0 first; turned away -> theta3 >= 0 first
    v = result.valid
    assert np.all(result.solutions[v[:, 0], 0, 2] <= 1e-12)
    assert np.all(result.solutions[v[:, 2], 2, 2] >= -1e-12)
    assert np.all(result.rotation_error == 0.0)


def test_unreachable_points_say_why():
    arm = desk_arm()
    reach = DESK_ARM["l1"] + DESK_ARM["l2"]
    shoulder = np.array([DESK_ARM["l3"], 0.0, DESK_ARM["l0_minus_l4"]])
    far = shoulder + [reach + 0.05, 0.0, 0.0]
    result = solve(arm, [far, far + [0.0, 0.0, 0.1]])
    assert not result.success.any()
    assert not result.valid.any()
    assert np.all(result.solutions == 0.0)
    assert "facing it, 0.05 m beyond the reach" in result.reason[0]
    assert "turned away" in result.reason[0]
    assert result.flags["unreachable"].all()
    # the error of the nearest pose says how far out of reach the point is
    np.testing.assert_allclose(result.position_error[0, 0], 0.05, atol=1e-12)


def test_close_to_the_shoulder_only_the_turned_away_pair_exists():
    arm = desk_arm()
    shoulder = np.array([DESK_ARM["l3"], 0.0, DESK_ARM["l0_minus_l4"]])
    result = solve(arm, shoulder + [0.01, 0.0, 0.0])     # 1 cm, inside |l2 - l1| = 18 mm
    assert result.valid.tolist() == [False, False, True, True]
    assert result.reason == ""


def test_flags_on_the_base_axis_and_at_full_stretch():
    arm = desk_arm()
    on_axis = arm.fk(desk_arm_joints_from_lab(np.radians([0, 60, 160])))[:3, 3].copy()
    on_axis[:2] = 0.0                      # straight above the base
    stretched = arm.fk([0.3, 0.4, 0.0])[:3, 3]
    result = solve(arm, np.stack([on_axis, stretched]))
    assert result.flags["base_singular"].tolist() == [True, False]
    assert result.flags["elbow_singular"].tolist() == [False, True]
    assert result.success.all()


def test_batches_and_base_transform():
    rng = np.random.default_rng(31)
    arm = desk_arm()
    base = np.eye(4)
    base[:3, 3] = [0.5, -0.2, 0.8]
    base[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    arm.base = base
    q = rng.uniform(-np.pi, np.pi, size=(2, 3, 3))
    p = arm.fk(q)[..., :3, 3]
    result = solve(arm, p)
    assert result.solutions.shape == (2, 3, 4, 3)
    assert result.reason.shape == (2, 3)
    assert result.success.all()
    reached = arm.fk(result.solutions)[..., :3, 3]
    err = np.linalg.norm(reached - p[..., None, :], axis=-1)
    assert np.all(err[result.valid] < 1e-12)
    single = solve(arm, p[1, 2])
    np.testing.assert_allclose(single.solutions, result.solutions[1, 2])


def test_other_robots_are_refused():
    with pytest.raises(ValueError, match="desk_arm"):
        solve(ur3(), [0.1, 0.1, 0.1])
    with pytest.raises(ValueError, match="position"):
        solve(desk_arm(), [0.1, 0.1])
