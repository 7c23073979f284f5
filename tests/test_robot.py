"""Tests for dqlab.robot: chain description, validation, forward kinematics (matrices and
both dual-quaternion constructions)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dqlab import dualquat
from dqlab.models import desk_arm, scara_rsm5, six_r, ur3, ur3_mdh
from dqlab.robot import Link, Robot
from dqlab.testing import assert_dual_quaternion_equal

MODELS = [ur3, ur3_mdh, desk_arm, scara_rsm5, six_r]


def random_joints(robot, rng, size):
    """Uniform joint vectors inside the limits (revolute: within [-pi, pi] as well)."""
    lo = np.maximum(robot.limits[:, 0], -np.pi)
    hi = np.minimum(robot.limits[:, 1], np.pi)
    return rng.uniform(lo, hi, size=tuple(np.atleast_1d(size)) + (robot.n,))


def rot_x(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def rot_z(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def trans(x, y, z):
    T = np.eye(4)
    T[:3, 3] = x, y, z
    return T


def random_transform(rng):
    A = rng.normal(size=(3, 3))
    Q, R = np.linalg.qr(A)
    Q = Q * np.sign(np.diag(R))
    if np.linalg.det(Q) < 0:
        Q[:, 0] *= -1
    T = np.eye(4)
    T[:3, :3] = Q
    T[:3, 3] = rng.normal(size=3)
    return T


# -- Link and Robot description ---------------------------------------------------------

@pytest.mark.parametrize("bad", [np.nan, np.inf, "x", None])
def test_link_rejects_non_finite_parameters(bad):
    with pytest.raises(ValueError, match="Link a"):
        Link(a=bad, alpha=0.0, d=0.0)
    with pytest.raises(ValueError, match="Link d"):
        Link(a=0.0, alpha=0.0, d=bad)


def test_link_rejects_bad_joint_type_and_limits():
    with pytest.raises(ValueError, match="revolute"):
        Link(0.0, 0.0, 0.0, joint="spherical")
    with pytest.raises(ValueError, match="lo <= hi"):
        Link(0.0, 0.0, 0.0, limits=(1.0, -1.0))
    assert Link(0.0, 0.0, 0.0, joint=1).joint == "prismatic"
    assert Link(0.0, 0.0, 0.0, joint="R").sigma == 0
    link = Link(0.1, 0.0, 0.0)
    with pytest.raises(AttributeError, match="immutable"):
        link.a = 0.2
    assert "a=0.1" in repr(link)


def test_robot_rejects_bad_construction():
    with pytest.raises(ValueError, match="at least one link"):
        Robot([])
    with pytest.raises(ValueError, match="convention"):
        Robot([Link(0, 0, 0)], convention="craig")
    with pytest.raises(ValueError, match="Link"):
        Robot([(0, 0, 0)])
    with pytest.raises(ValueError, match="base"):
        Robot([Link(0, 0, 0)], base=np.ones((4, 4)))
    with pytest.raises(ValueError, match="tool"):
        Robot([Link(0, 0, 0)], tool=np.eye(3))


def test_wrong_joint_vector_length_is_a_clear_error():
    robot = ur3()
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 6\).*got shape \(5,\)"):
        robot.fk(np.zeros(5))
    with pytest.raises(ValueError, match="shape"):
        robot.fk(0.0)
    with pytest.raises(ValueError, match="NaN"):
        robot.fk([0, 0, np.nan, 0, 0, 0])
    with pytest.raises(ValueError, match="NaN"):
        robot.jacobian([0, 0, np.inf, 0, 0, 0])


def test_prismatic_joint_beyond_limits_is_rejected():
    scara = scara_rsm5()
    with pytest.raises(ValueError, match=r"joint 3 \(prismatic\) = -0.01 is beyond"):
        scara.fk([0.0, 0.5, -0.01, 0.0])
    with pytest.raises(ValueError, match="joint 3"):
        scara.fk_dq(np.array([[0.0, 0.5, 0.1, 0.0], [0.0, 0.5, 0.2, 0.0]]))
    # revolute limits are enforced only on request
    q = [3.0, 0.5, 0.1, 0.0]          # joint 1 beyond +-120 deg
    scara.fk(q)
    with pytest.raises(ValueError, match=r"joint 1 \(revolute\)"):
        scara.check_joints(q, limits="all")
    with pytest.raises(ValueError, match="limits must be"):
        scara.check_joints(q, limits="some")
    assert scara.check_joints([9.0, 9.0, 9.0, 9.0], limits="none").shape == (4,)


def test_description_attributes():
    robot = ur3_mdh()
    assert robot.n == 6 and robot.convention == "mdh"
    assert robot.joint_types == ("revolute",) * 6
    assert robot.limits.shape == (6, 2)
    np.testing.assert_array_equal(robot.base, np.eye(4))
    b = robot.base
    b[0, 3] = 5.0                       # a copy: the robot is unchanged
    np.testing.assert_array_equal(robot.base, np.eye(4))


def test_dh_table_lists_every_link_in_its_convention():
    text = ur3_mdh().dh_table()
    assert "modified DH" in text and "alpha_i-1" in text
    assert text.splitlines()[0] == "UR3 (report, modified DH), 6 joints"   # said once
    assert "q1 + 90" in text and "q6 - 90" in text and "-0.12" in text
    assert repr(ur3_mdh()) == "Robot('UR3 (report, modified DH)', convention='mdh', n=6)"
    text = scara_rsm5().dh_table()
    assert "q3 + 0.18" in text and "[0, 0.15] m" in text
    assert "standard DH" in ur3().dh_table()
    assert ur3().dh_table().splitlines()[0] == "UR3 (standard DH, 6 joints)"
    text = six_r().dh_table()
    assert "tool X_nT" in text
    robot = Robot([Link(1.0, 0.0, 0.0)], base=trans(0, 0, 1))
    assert "base X_W0" in robot.dh_table()
    assert "-" in robot.dh_table().splitlines()[2]          # no limits


# -- forward kinematics -----------------------------------------------------------------

def test_standard_dh_link_is_rz_tz_tx_rx():
    rng = np.random.default_rng(1)
    a, alpha, d, off = rng.normal(size=4)
    robot = Robot([Link(a, alpha, d, theta_offset=off)])
    q = rng.normal()
    want = rot_z(q + off) @ trans(0, 0, d) @ trans(a, 0, 0) @ rot_x(alpha)
    np.testing.assert_allclose(robot.fk([q]), want, atol=1e-15)


def test_modified_dh_link_matches_course_formula_2_1():
    rng = np.random.default_rng(2)
    a, alpha, r, off = rng.normal(size=4)
    robot = Robot([Link(a, alpha, r, theta_offset=off)], convention="mdh")
    q = rng.normal()
    t = q + off
    ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(t), np.sin(t)
    want = np.array([[ct, -st, 0, a],
                     [ca * st, ca * ct, -sa, -r * sa],
                     [sa * st, sa * ct, ca, r * ca],
                     [0, 0, 0, 1]])
    np.testing.assert_allclose(robot.fk([q]), want, atol=1e-15)


def test_prismatic_joint_moves_along_its_axis():
    robot = Robot([Link(0.2, 0.3, 0.5, theta_offset=0.4, joint="prismatic")], convention="dh")
    for q in (0.0, 0.7):
        want = rot_z(0.4) @ trans(0, 0, 0.5 + q) @ trans(0.2, 0, 0) @ rot_x(0.3)
        np.testing.assert_allclose(robot.fk([q]), want, atol=1e-15)


@pytest.mark.parametrize("model", MODELS)
def test_fk_is_the_product_of_link_transforms_with_base_and_tool(model):
    """link_transforms is the definition of the chain: fk (the compiled chain, on floats
    for one joint vector, on arrays for a batch) is that product with the base and tool."""
    rng = np.random.default_rng(3)
    robot = model()
    robot.base = random_transform(rng)
    robot.tool = random_transform(rng) @ robot.tool
    q = random_joints(robot, rng, 1)[0]
    X = robot.base
    for A in robot.link_transforms(q):
        X = X @ A
    np.testing.assert_allclose(robot.fk(q), X @ robot.tool, atol=1e-13)
    batch = random_joints(robot, rng, 50)
    X = np.broadcast_to(robot.base, (50, 4, 4))
    for i in range(robot.n):
        X = X @ robot.link_transforms(batch)[:, i]
    np.testing.assert_allclose(robot.fk(batch), X @ robot.tool, atol=1e-13)
    frames = robot.fk(q, all_frames=True)
    assert frames.shape == (robot.n + 1, 4, 4)
    np.testing.assert_allclose(frames[0], robot.base, atol=1e-15)
    np.testing.assert_allclose(frames[-1], robot.fk(q), atol=1e-13)


@pytest.mark.parametrize("model", MODELS)
def test_batches_of_0_1_2_leading_dimensions_match_single_calls(model):
    rng = np.random.default_rng(4)
    robot = model()
    q = random_joints(robot, rng, (3, 2))
    for method in (robot.fk, robot.fk_dq, robot.fk_dq_screw, robot.jacobian,
                   lambda x: robot.fk(x, all_frames=True)):
        batch = method(q)
        assert batch.shape[:2] == (3, 2)
        for i in range(3):
            np.testing.assert_allclose(method(q[i]), batch[i], atol=1e-14)
            for j in range(2):
                np.testing.assert_allclose(method(q[i, j]), batch[i, j], atol=1e-14)


@pytest.mark.parametrize("model", MODELS)
def test_large_batches_are_computed_in_blocks_and_agree(model):
    """A batch larger than one block (8192 joint vectors) equals small batches and single
    calls: one product for every size."""
    rng = np.random.default_rng(5)
    robot = model()
    robot.base = random_transform(rng)
    q = random_joints(robot, rng, (10, 1000))
    small = np.stack([robot.fk(block) for block in q.reshape(-1, 20, robot.n)])
    big = robot.fk(q)
    assert big.shape == (10, 1000, 4, 4)
    np.testing.assert_allclose(big.reshape(small.shape), small, atol=1e-14)
    for index in [(0, 0), (8, 191), (9, 999)]:
        np.testing.assert_allclose(robot.fk(q[index]), big[index], atol=1e-15)
    np.testing.assert_allclose(big[..., 3, :], np.broadcast_to([0, 0, 0, 1.0], (10, 1000, 4)))


@pytest.mark.parametrize("model", MODELS)
def test_matrix_fk_equals_both_dual_quaternion_constructions(model):
    """1,000 random configurations: fk = fk_dq = fk_dq_screw to 1e-12 (thesis section 4.2)."""
    rng = np.random.default_rng(6)
    robot = model()
    robot.base = random_transform(rng)
    robot.tool = random_transform(rng)
    q = random_joints(robot, rng, 1000)
    X = robot.fk(q)
    Q_links = robot.fk_dq(q)
    Q_screws = robot.fk_dq_screw(q)
    assert Q_links.shape == Q_screws.shape == (1000, 8)
    np.testing.assert_allclose(dualquat.transform_from_dual_quaternion(Q_links), X, atol=1e-12)
    np.testing.assert_allclose(dualquat.transform_from_dual_quaternion(Q_screws), X, atol=1e-12)
    assert_dual_quaternion_equal(Q_links, Q_screws, atol=1e-12)
    assert_dual_quaternion_equal(Q_links, dualquat.dual_quaternion_from_transform(X), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(Q_links[:, :4], axis=-1), 1.0, atol=1e-13)


@pytest.mark.parametrize("model", [ur3, scara_rsm5])
def test_dual_quaternion_fk_in_blocks_and_after_a_new_base_and_tool(model):
    """More configurations than one block of the batch kernels, and the cached constant
    factors follow a change of base and tool."""
    rng = np.random.default_rng(7)
    robot = model()
    q = random_joints(robot, rng, 9000)
    for method in (robot.fk_dq, robot.fk_dq_screw):
        Q = method(q)
        np.testing.assert_allclose(dualquat.transform_from_dual_quaternion(Q), robot.fk(q),
                                   atol=1e-12)
        np.testing.assert_allclose(Q[-3:], np.stack([method(row) for row in q[-3:]]),
                                   atol=1e-15)
    robot.base = random_transform(rng)
    robot.tool = random_transform(rng)
    for method in (robot.fk_dq, robot.fk_dq_screw):
        X = dualquat.transform_from_dual_quaternion(method(q[:50]))
        np.testing.assert_allclose(X, robot.fk(q[:50]), atol=1e-12)


def test_zero_pose_screws_are_the_joint_axes_at_q_zero():
    robot = ur3()
    points, axes, X0 = robot.zero_pose_screws()
    np.testing.assert_allclose(X0, robot.fk(np.zeros(6)))
    np.testing.assert_allclose(np.linalg.norm(axes, axis=-1), 1.0)
    # UR3: z, then three axes along -y, then -z, then -y (thesis section 4.2.1)
    want = [[0, 0, 1], [0, -1, 0], [0, -1, 0], [0, -1, 0], [0, 0, -1], [0, -1, 0]]
    np.testing.assert_allclose(axes, want, atol=1e-15)


def test_joint_axes_for_both_conventions():
    rng = np.random.default_rng(7)
    for robot in (ur3(), ur3_mdh()):
        q = random_joints(robot, rng, 1)[0]
        points, axes = robot.joint_axes(q)
        frames = robot.fk(q, all_frames=True)
        if robot.convention == "dh":      # joint i turns about z of frame i-1
            np.testing.assert_allclose(axes, frames[:-1, :3, 2], atol=1e-14)
            np.testing.assert_allclose(points, frames[:-1, :3, 3], atol=1e-14)
        else:                             # joint i turns about z of frame i
            np.testing.assert_allclose(axes, frames[1:, :3, 2], atol=1e-14)
            off = frames[1:, :3, 3] - points      # on the axis
            np.testing.assert_allclose(np.cross(off, axes), 0.0, atol=1e-14)


def test_thesis_ur3_pose_by_the_screw_construction():
    """Thesis 4.5: (0, -pi/2, 0, -pi/2, 0, 0), TCP 0.2 m along flange z -> (0, -0.394, 0.694)."""
    robot = ur3()
    q = [0, -np.pi / 2, 0, -np.pi / 2, 0, 0]
    for Q in (robot.fk_dq(q), robot.fk_dq_screw(q)):
        tcp = dualquat.dual_quaternion_apply(Q, [0.0, 0.0, 0.2])
        np.testing.assert_allclose(tcp, [0.0, -0.39425, 0.69415], atol=1e-12)
        np.testing.assert_allclose(tcp.round(3), [0.0, -0.394, 0.694], atol=1e-12)


# -- property: random chains of both conventions -----------------------------------------

_finite = st.floats(min_value=-2.0, max_value=2.0, allow_nan=False, allow_infinity=False)
_link = st.tuples(_finite, _finite, _finite, _finite, st.booleans())


@given(links=st.lists(_link, min_size=1, max_size=7),
                  convention=st.sampled_from(["dh", "mdh"]),
                  seed=st.integers(0, 2**32 - 1))
@settings(max_examples=60, deadline=None)
def test_random_chains_fk_dual_quaternions_and_jacobian_agree(links, convention, seed):
    rng = np.random.default_rng(seed)
    chain = [Link(a, alpha, d, theta_offset=off, joint="prismatic" if p else "revolute")
             for a, alpha, d, off, p in links]
    robot = Robot(chain, convention=convention, base=random_transform(rng),
                  tool=random_transform(rng))
    q = rng.uniform(-np.pi, np.pi, size=(5, robot.n))
    X = robot.fk(q)
    np.testing.assert_allclose(dualquat.transform_from_dual_quaternion(robot.fk_dq(q)), X,
                               atol=1e-11)
    np.testing.assert_allclose(dualquat.transform_from_dual_quaternion(robot.fk_dq_screw(q)),
                               X, atol=1e-11)
    h = 1e-6
    J = robot.jacobian(q)
    for j in range(robot.n):
        dq = np.zeros(robot.n)
        dq[j] = h
        v = (robot.fk(q + dq)[:, :3, 3] - robot.fk(q - dq)[:, :3, 3]) / (2 * h)
        np.testing.assert_allclose(J[:, :3, j], v, atol=1e-6)


@pytest.mark.parametrize("name", ["ur3", "ur3_mdh", "desk_arm", "six_r", "scara_rsm5"])
def test_one_joint_vector_on_floats_equals_the_batch(name):
    """A single float64 joint vector goes through Python floats, a batch through numpy:
    the same formulas, the same numbers (to the last bit for fk)."""
    import dqlab.models as models

    robot = getattr(models, name)()
    rng = np.random.default_rng(8)
    lo, hi = robot.limits.T
    q = rng.uniform(np.maximum(lo, -np.pi), np.minimum(hi, np.pi), (200, robot.n))
    X, Q = robot.fk(q), robot.fk_dq(q)
    for i, row in enumerate(q):
        np.testing.assert_array_equal(robot.fk(row), X[i])
        np.testing.assert_allclose(robot.fk_dq(row), Q[i], rtol=0, atol=1e-16)
        np.testing.assert_array_equal(robot.fk(row.tolist()), X[i])
    bad = q[0].copy()
    bad[1] = np.nan
    for method in (robot.fk, robot.fk_dq):
        with pytest.raises(ValueError, match="NaN or infinity"):
            method(bad)
