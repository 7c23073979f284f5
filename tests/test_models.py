"""Tests for dqlab.models: every model against its source's numbers and an independent
oracle where one exists (ur_analytic_ik for the UR family)."""

import numpy as np
import pytest

from dqlab.models import (
    DESK_ARM,
    SCARA_RSM5,
    desk_arm,
    desk_arm_joints_from_lab,
    desk_arm_lab_from_joints,
    scara_rsm5,
    six_r,
    ur3,
    ur3_mdh,
    ur5,
    ur10,
)

try:
    import ur_analytic_ik
except ImportError:  # the test extra brings it; without it only the cross-check skips
    ur_analytic_ik = None

# The UR3 report (seeds/003): T_{0,1} ... T_{0,6}, top three rows, as printed.
REPORT_T0I = [
    [[-0.09983342, -0.99500417, 0, 0],
     [0.99500417, -0.09983342, 0, 0],
     [0, 0, 1, 0.152]],
    [[-0.0876120655, -0.0478626895, 0.995004165, -0.119400500],
     [0.873198304, 0.477030408, 0.0998334166, -0.0119800100],
     [-0.479425539, 0.877582562, 6.12323400e-17, 0.152000000]],
    [[-0.0953745058, 0.0295027919, 0.995004165, -0.140777844],
     [0.950563786, -0.294043837, 0.0998334166, 0.201080376],
     [0.295520207, 0.955336489, 6.12323400e-17, 0.0350201686]],
    [[0.00996671108, 0.0993346654, 0.995004165, -0.151142572],
     [-0.0993346654, -0.990033289, 0.0998334166, 0.404548797],
     [0.995004165, -0.0998334166, 6.12323400e-17, 0.0979659726]],
    [[0.48577702, 0.86842001, -0.09933467, -0.15938735],
     [-0.03931168, 0.13523564, 0.99003329, 0.48672156],
     [0.87319830, -0.47703041, 0.09983342, 0.10625215]],
    [[-0.05034163, 0.49326708, 0.86842001, -0.08817691],
     [0.98116263, -0.13795369, 0.13523564, 0.49781088],
     [0.18650904, 0.85886924, -0.47703041, 0.06713565]],
]

#: The report's joint angles, recovered from its printed frames (see
#: test_report_joint_angles_are_recovered_by_peeling_the_printed_frames).
REPORT_Q = np.array([0.1, -0.5, 0.8, -0.2, 0.5, 0.1])

# The lab report (seeds/004), forward-model check: (q0, q1, q2) deg -> (x, y, z) mm.
LAB_FK_TABLE = [((90, 90, 0), (229, 0, 179)),
                ((90, 51, 65), (226, 0, 0)),
                ((90, 42, 21), (325, 0, 73)),
                ((90, 90, 45), (182, 0, 64))]


def homogeneous(rows):
    return np.vstack([np.asarray(rows, dtype=float), [0, 0, 0, 1]])


# -- UR family, standard DH -------------------------------------------------------------

def test_ur3_parameters_are_the_published_ones():
    robot = ur3()
    assert robot.convention == "dh" and robot.n == 6
    np.testing.assert_array_equal([lk.d for lk in robot.links],
                                  [0.1519, 0, 0, 0.11235, 0.08535, 0.0819])
    np.testing.assert_array_equal([lk.a for lk in robot.links],
                                  [0, -0.24365, -0.21325, 0, 0, 0])
    np.testing.assert_array_equal([lk.alpha for lk in robot.links],
                                  [np.pi / 2, 0, 0, np.pi / 2, -np.pi / 2, 0])
    np.testing.assert_array_equal(robot.tool, np.eye(4))
    np.testing.assert_array_equal(robot.base, np.eye(4))
    np.testing.assert_array_equal(robot.limits,      # wrist 3 turns without limit
                                  [[-2 * np.pi, 2 * np.pi]] * 5 + [[-np.inf, np.inf]])


def test_thesis_ur3_tcp_check():
    """Thesis 4.5: TCP 0.2 m along flange z at (0, -pi/2, 0, -pi/2, 0, 0) -> (0, -0.394, 0.694)."""
    X_WF = ur3().fk([0, -np.pi / 2, 0, -np.pi / 2, 0, 0])
    p = (X_WF @ [0, 0, 0.2, 1])[:3]
    np.testing.assert_allclose(p, [0.0, -0.39425, 0.69415], atol=1e-12)
    np.testing.assert_allclose(np.round(p, 3), [0.0, -0.394, 0.694], atol=1e-12)
    # the thesis's printed pose: flange at (0, -0.194, 0.694), tool z along -y
    np.testing.assert_allclose(X_WF[:3, 3], [0, -0.19425, 0.69415], atol=1e-12)
    np.testing.assert_allclose(X_WF[:3, 2], [0, -1, 0], atol=1e-12)


@pytest.mark.skipif(ur_analytic_ik is None, reason="ur_analytic_ik (test extra) is absent")
@pytest.mark.parametrize("model, oracle", [(ur3, "ur3"), (ur5, "ur5"), (ur10, "ur10")])
def test_ur_fk_equals_ur_analytic_ik(model, oracle):
    """ur_analytic_ik's forward_kinematics(q1..q6) returns the base->flange pose in the same
    base frame and flange frame as UR's standard DH, so the relation is the identity:
    X_ours = X_theirs (to rounding), for 1,000 random configurations."""
    rng = np.random.default_rng(10)
    robot = model()
    fk = getattr(ur_analytic_ik, oracle).forward_kinematics
    q = rng.uniform(-2 * np.pi, 2 * np.pi, size=(1000, 6))
    ours = robot.fk(q)
    theirs = np.array([fk(*row) for row in q])
    np.testing.assert_allclose(ours, theirs, atol=1e-9)
    assert np.abs(ours - theirs).max() < 1e-13


# -- UR3, modified DH of the project report ---------------------------------------------

def test_ur3_mdh_table():
    robot = ur3_mdh()
    assert robot.convention == "mdh"
    np.testing.assert_allclose([lk.alpha for lk in robot.links],
                               [0, np.pi / 2, 0, 0, np.pi / 2, -np.pi / 2])
    np.testing.assert_allclose([lk.a for lk in robot.links], [0, 0, 0.244, 0.213, 0, 0])
    np.testing.assert_allclose([lk.d for lk in robot.links],
                               [0.152, -0.120, 0, 0.010, 0.083, 0.082])
    np.testing.assert_allclose([lk.theta_offset for lk in robot.links],
                               [np.pi / 2, 0, 0, np.pi / 2, 0, -np.pi / 2])


def test_ur3_mdh_elementary_matrices_are_the_reports():
    rng = np.random.default_rng(11)
    q = rng.uniform(-np.pi, np.pi, 6)
    s, c = np.sin(q), np.cos(q)
    r1, r2, a2, a3, r4, r5, r6 = 0.152, 0.120, 0.244, 0.213, 0.010, 0.083, 0.082
    want = [
        [[-s[0], -c[0], 0, 0], [c[0], -s[0], 0, 0], [0, 0, 1, r1]],
        [[c[1], -s[1], 0, 0], [0, 0, -1, r2], [s[1], c[1], 0, 0]],
        [[c[2], -s[2], 0, a2], [s[2], c[2], 0, 0], [0, 0, 1, 0]],
        [[-s[3], -c[3], 0, a3], [c[3], -s[3], 0, 0], [0, 0, 1, r4]],
        [[c[4], -s[4], 0, 0], [0, 0, -1, -r5], [s[4], c[4], 0, 0]],
        [[s[5], c[5], 0, 0], [0, 0, 1, r6], [c[5], -s[5], 0, 0]],
    ]
    got = ur3_mdh().link_transforms(q)
    for i in range(6):
        np.testing.assert_allclose(got[i], homogeneous(want[i]), atol=1e-15)


def test_ur3_mdh_zero_pose_is_the_reports():
    X = ur3_mdh().fk(np.zeros(6))
    np.testing.assert_allclose(X[:3, 0], [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(X[:3, 1], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(X[:3, 2], [1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(X[:3, 3], [-0.028, 0.54, 0.152], atol=1e-12)
    # as printed (two decimals)
    np.testing.assert_allclose(X[:3, 3].round(2), [-0.03, 0.54, 0.15], atol=1e-12)


def test_report_joint_angles_are_recovered_by_peeling_the_printed_frames():
    """The report prints T_{0,1} ... T_{0,6} but not the joint angles. Peel one link at a
    time: X_{i-1,i} = T_{0,i-1}^{-1} T_{0,i} = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(r_i),
    so Rx(alpha_{i-1})^T R_{i-1,i} = Rz(theta_i) gives theta_i = atan2(m10, m00), and
    q_i = theta_i - q_fig_i. Result: q = (0.1, -0.5, 0.8, -0.2, 0.5, 0.1) rad."""
    robot = ur3_mdh()
    previous = np.eye(4)
    q = []
    for link, printed in zip(robot.links, REPORT_T0I, strict=True):
        T = homogeneous(printed)
        X = np.linalg.inv(previous) @ T
        ca, sa = np.cos(link.alpha), np.sin(link.alpha)
        Rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
        M = Rx.T @ X[:3, :3]
        q.append(np.arctan2(M[1, 0], M[0, 0]) - link.theta_offset)
        previous = T
    np.testing.assert_allclose(q, REPORT_Q, atol=1e-7)


def test_report_frames_reproduced_at_the_recovered_angles():
    frames = ur3_mdh().fk(REPORT_Q, all_frames=True)
    for i, printed in enumerate(REPORT_T0I, start=1):
        # the report prints 8 to 9 significant digits
        np.testing.assert_allclose(frames[i][:3], printed, atol=1e-8)


# -- the desktop arm of the lab report ---------------------------------------------------

def test_desk_arm_dimensions():
    arm = desk_arm()
    assert DESK_ARM == {"l0_minus_l4": 0.035, "l1": 0.144, "l2": 0.162, "l3": 0.067}
    assert [lk.a for lk in arm.links] == [0.067, 0.144, 0.162]
    assert arm.links[0].d == 0.035


@pytest.mark.parametrize("q_deg, xyz_mm", LAB_FK_TABLE)
def test_lab_forward_table_is_reproduced(q_deg, xyz_mm):
    q = desk_arm_joints_from_lab(np.radians(q_deg))
    p_mm = desk_arm().fk(q)[:3, 3] * 1000
    np.testing.assert_array_equal(np.round(p_mm) + 0.0, xyz_mm)


def test_desk_arm_chain_equals_the_labs_formula():
    rng = np.random.default_rng(12)
    lab = rng.uniform(-np.pi, np.pi, size=(500, 3))
    q0, q1, q2 = lab.T
    l1, l2, l3, h = 0.144, 0.162, 0.067, 0.035
    d = l1 * np.cos(q1) + l2 * np.cos(q2) + l3
    want = np.stack([d * np.sin(q0), d * np.cos(q0),
                     l1 * np.sin(q1) - l2 * np.sin(q2) + h], axis=-1)
    got = desk_arm().fk(desk_arm_joints_from_lab(lab))[..., :3, 3]
    np.testing.assert_allclose(got, want, atol=1e-15)
    np.testing.assert_allclose(desk_arm_lab_from_joints(desk_arm_joints_from_lab(lab)), lab,
                               atol=1e-15)


# -- SCARA RSM-5 ---------------------------------------------------------------------------

def test_scara_forward_model():
    rng = np.random.default_rng(13)
    robot = scara_rsm5()
    lo, hi = robot.limits.T
    q = rng.uniform(lo, hi, size=(200, 4))
    X = robot.fk(q)
    l1, l2, z_low = SCARA_RSM5["l1"], SCARA_RSM5["l2"], SCARA_RSM5["z_low"]
    q1, q2, q3, q4 = q.T
    np.testing.assert_allclose(X[:, 0, 3], l1 * np.cos(q1) + l2 * np.cos(q1 + q2), atol=1e-15)
    np.testing.assert_allclose(X[:, 1, 3], l1 * np.sin(q1) + l2 * np.sin(q1 + q2), atol=1e-15)
    np.testing.assert_allclose(X[:, 2, 3], z_low + q3, atol=1e-15)
    yaw = q1 + q2 + q4
    np.testing.assert_allclose(X[:, :3, 0], np.stack([np.cos(yaw), np.sin(yaw), 0 * yaw], -1),
                               atol=1e-15)
    np.testing.assert_allclose(X[:, :3, 2], np.broadcast_to([0, 0, 1.0], (200, 3)), atol=1e-15)


def test_scara_limits_and_the_155_mm_clearance():
    robot = scara_rsm5()
    np.testing.assert_allclose(np.degrees(robot.limits[[0, 1, 3]]),
                               [[-120, 120], [-145, 145], [-180, 180]])
    np.testing.assert_allclose(robot.limits[2], [0, 0.150])
    # Al Kashi: closest approach to axis 1, with joint 2 at its stop, is above 155 mm
    X = robot.fk([0.0, np.radians(145), 0.0, 0.0])
    assert np.hypot(X[0, 3], X[1, 3]) > 0.155


# -- 6R with spherical wrist (course notes, chapter 2) ----------------------------------------

def test_six_r_matches_the_course_notes_closed_form():
    rng = np.random.default_rng(14)
    a2, r4, r7 = 0.4, 0.35, 0.1
    q = rng.uniform(-np.pi, np.pi, size=(300, 6))
    C = np.cos(q).T
    S = np.sin(q).T
    C23, S23 = np.cos(q[:, 1] + q[:, 2]), np.sin(q[:, 1] + q[:, 2])
    D1, D2 = a2 * C[1], a2 * S[1]
    D3 = C[4] * C[5]
    D4 = -S[4] * C[5]
    D5 = C[3] * D3 - S[3] * S[5]
    D6 = C[3] * S[4]
    D7 = S[3] * D3 + C[3] * S[5]
    D8 = S[3] * S[4]
    D9 = C23 * D5 + S23 * D4
    D10 = C23 * D6 + S23 * C[4]
    D11 = r4 * S23 + D1
    px, py, pz = C[0] * D11, S[0] * D11, -r4 * C23 + D2
    xx, xy, xz = C[0] * D9 + S[0] * D7, S[0] * D9 - C[0] * D7, S23 * D5 - C23 * D4
    zx, zy, zz = C[0] * D10 + S[0] * D8, S[0] * D10 - C[0] * D8, S23 * D6 - C23 * C[4]
    X = six_r(a2=a2, r4=r4, r7=r7).fk(q)
    np.testing.assert_allclose(X[:, :3, 0], np.stack([xx, xy, xz], -1), atol=1e-14)
    np.testing.assert_allclose(X[:, :3, 2], np.stack([zx, zy, zz], -1), atol=1e-14)
    np.testing.assert_allclose(X[:, :3, 3],
                               np.stack([px + r7 * zx, py + r7 * zy, pz + r7 * zz], -1),
                               atol=1e-14)
