"""The UR models' inertial parameters, rated joint speeds and torques: one table each
(models.UR_DYNAMICS, derived from the published models.UR_PHYSICAL_PARAMETERS;
models.UR_MAX_JOINT_SPEED_DEG; models.UR_MAX_JOINT_TORQUE), carried by every model's links.
The tables against the published files themselves: tests/test_models_ur_published.py."""

import math

import numpy as np
import pytest

from dqlab import dynamics, models
from dqlab.models import (
    UR_DYNAMICS,
    UR_MAX_JOINT_SPEED_DEG,
    UR_MAX_JOINT_TORQUE,
    UR_MODELS,
    UR_PHYSICAL_PARAMETERS,
)
from dqlab.robot import Robot
from dqlab.ur.script import SafetyLimits

#: What the sources leave out (see the module docstring of dqlab.models).
NO_RATINGS = {"UR8 Long"}
#: Published tensors not taken (the UR30's): those links carry the stated cylinders.
CYLINDERS = {"UR30"}

#: The UR20's inertia matrices as Universal Robots' page prints them (four decimals, row
#: major), the independent check of the five-decimal tensors of the table.
UR20_PAGE = (
    (0.0887, -0.0001, -0.0001, -0.0001, 0.0763, 0.0072, -0.0001, 0.0072, 0.0842),
    (0.1467, 0.0002, -0.0516, 0.0002, 4.6659, 0.0000, -0.0516, 0.0000, 4.6348),
    (0.0261, -0.0001, -0.0290, -0.0001, 0.7576, -0.0000, -0.0290, -0.0000, 0.7533),
    (0.0056, -0.0000, -0.0000, -0.0000, 0.0054, 0.0004, -0.0000, 0.0004, 0.0040),
    (0.0059, -0.0000, 0.0000, -0.0000, 0.0058, -0.0004, 0.0000, -0.0004, 0.0043),
    (0.0009, 0.0000, 0.0000, 0.0000, 0.0009, 0.0000, 0.0000, 0.0000, 0.0012),
)


def test_the_tables_cover_every_model_but_the_unpublished():
    assert set(UR_PHYSICAL_PARAMETERS) == set(UR_DYNAMICS) == set(UR_MODELS)
    assert set(UR_MAX_JOINT_SPEED_DEG) == set(UR_MAX_JOINT_TORQUE) == set(UR_MODELS) - NO_RATINGS
    assert not hasattr(models, "UR_PUBLISHED_MASSES")           # one table, not two
    for name, p in UR_PHYSICAL_PARAMETERS.items():
        assert p["source"].endswith(")") and " @ " in p["source"]        # file @ commit (date)
        assert name.lower().replace(" ", "") in p["source"]


@pytest.mark.parametrize("name", sorted(UR_MODELS))
def test_every_model_carries_its_table(name):
    robot = UR_MODELS[name]()
    table = UR_DYNAMICS[name]
    assert [link.inertia.mass for link in robot.links] == list(table["mass"])
    np.testing.assert_allclose([link.inertia.com for link in robot.links], table["com"],
                               rtol=0, atol=1e-15)      # a cylinder's: its ends' midpoint
    assert ("tensor" in table) == (name not in CYLINDERS)
    if "tensor" in table:
        for link, (ixx, iyy, izz, ixy, ixz, iyz) in zip(robot.links, table["tensor"],
                                                           strict=True):
            np.testing.assert_array_equal(
                link.inertia.tensor, [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    for link in robot.links:            # a rigid body's tensor, whatever its source
        moments = np.linalg.eigvalsh(link.inertia.tensor)
        assert moments.min() > 0 and moments[0] + moments[1] >= moments[2]
    if name in NO_RATINGS:
        assert all(link.max_speed is None and link.max_torque is None for link in robot.links)
    else:
        assert [link.max_speed for link in robot.links] == [
            math.radians(v) for v in UR_MAX_JOINT_SPEED_DEG[name]]
        assert [link.max_torque for link in robot.links] == list(UR_MAX_JOINT_TORQUE[name])


def test_the_dh_axes_tensors_are_the_files_numbers():
    # the e-series and the UR10 state their tensors in the DH axes: the models carry the
    # files' numbers unchanged (the quarter turns exact)
    for name, p in UR_PHYSICAL_PARAMETERS.items():
        if p["rpy"] is models._RPY_DH_AXES and name not in CYLINDERS:
            assert UR_DYNAMICS[name]["tensor"] == p["tensor"], name
def test_ur20_tensors_round_to_the_page():
    for row, page in zip(UR_DYNAMICS["UR20"]["tensor"], UR20_PAGE, strict=True):
        ixx, iyy, izz, ixy, ixz, iyz = row
        matrix = np.array([ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz])
        np.testing.assert_allclose(matrix, page, atol=0.5e-4 + 1e-12)


def test_renamed_models_share_their_numbers():
    for new, old in (("UR7e", "UR5e"), ("UR12e", "UR10e")):
        assert UR_DYNAMICS[new] == UR_DYNAMICS[old]
        assert UR_MAX_JOINT_SPEED_DEG[new] == UR_MAX_JOINT_SPEED_DEG[old]
        assert UR_MAX_JOINT_TORQUE[new] == UR_MAX_JOINT_TORQUE[old]


def test_safety_limits_of_a_model_are_its_rated_speeds():
    limits = SafetyLimits.for_robot(models.ur5e())
    np.testing.assert_array_equal(limits.max_joint_speed, np.full(6, math.pi))   # 180 deg/s
    np.testing.assert_array_equal(limits.joint_limits, models.ur5e().limits)
    np.testing.assert_allclose(SafetyLimits.for_robot(models.ur20()).max_joint_speed,
                               np.radians([120, 120, 150, 210, 210, 210]), rtol=1e-15)
    np.testing.assert_array_equal(limits.max_joint_torque, [150, 150, 150, 28, 28, 28])
    with pytest.raises(ValueError, match=r"UR8 Long has no rated speed for joints \[1, 2, 3, 4, "
                                         r"5, 6\]"):
        SafetyLimits.for_robot(models.ur8_long())


def test_heavier_model_needs_more_shoulder_torque_to_hold_the_arm_out():
    """A check of the tables' scale through the dynamics: the shoulder's gravity torque with
    the arm stretched out horizontally is the arm's moment about the shoulder axis."""
    q = np.array([0.0, 0.0, 0.0, -np.pi / 2, 0.0, 0.0])
    torque = {name: abs(dynamics.gravity_torques(UR_MODELS[name](), q)[1])
              for name in ("UR3e", "UR5e", "UR10e", "UR16e", "UR20", "UR30", "UR15", "UR18",
                           "UR8 Long")}
    assert torque["UR3e"] < torque["UR5e"] < torque["UR16e"] < torque["UR10e"] < torque["UR20"]
    assert torque["UR30"] < torque["UR20"]          # the same shoulder, shorter tubes
    assert torque["UR18"] < torque["UR15"] < torque["UR8 Long"]     # one shoulder, three reaches
    for name, tau in torque.items():                # and each holds itself within its rating
        assert tau < UR_MAX_JOINT_TORQUE.get(name, (np.inf,) * 6)[1], name
    # the UR5e by hand: sum of m_i g times the horizontal distance of each centre of mass
    robot = models.ur5e()
    frames = robot.fk(q, all_frames=True)
    moment = sum(link.inertia.mass * 9.81 * (X[:3, :3] @ link.inertia.com + X[:3, 3])[0]
                 for link, X in zip(robot.links, frames[1:], strict=True))
    assert torque["UR5e"] == pytest.approx(abs(moment), rel=1e-12)


# --------------------------------------------------------------------------------------
# Inertias and payloads: numbers through check_scalar, degenerate bodies refused by name

def test_numbers_are_numbers_not_text_or_booleans():
    from dqlab.inertia import LinkInertia

    c = [0.1, 0.0, 0.0]
    robot = models.ur3()
    for call, name in [(lambda: dynamics.with_payload(robot, "3"), "mass"),
                       (lambda: dynamics.with_payload(robot, True), "mass"),
                       (lambda: dynamics.with_payload(robot, 1.0, radius="0.1"), "radius"),
                       (lambda: LinkInertia("2", c), "mass"),
                       (lambda: LinkInertia(True, c), "mass"),
                       (lambda: LinkInertia.sphere(1.0, c).scaled("2"), "factor"),
                       (lambda: LinkInertia.rod(1.0, [0, 0, 0], c, radius=False), "radius"),
                       (lambda: models.rod_link_inertias(robot, base_mass="1"), "base_mass"),
                       (lambda: models.rod_link_inertias(robot, radius=True), "radius")]:
        with pytest.raises(ValueError, match=rf"^{name} must be a finite number >= 0, got "):
            call()


def test_degenerate_bodies_are_refused_by_name():
    from dqlab.inertia import LinkInertia

    c = [0.1, 0.0, 0.0]
    with pytest.raises(ValueError, match=r"a rod of mass 1 kg, length 1e\+200 m .* overflows"):
        LinkInertia.rod(1.0, [0, 0, 0], [1e200, 0, 0], radius=0.01)
    with pytest.raises(ValueError, match="start and end are too far apart"):
        LinkInertia.rod(1.0, [-1e308, 0, 0], [1e308, 0, 0], radius=0.01)
    with pytest.raises(ValueError, match=r"a sphere of mass 1 kg and radius 1e\+200 m"):
        LinkInertia.sphere(1.0, c, 1e200)
    # a tensor of 1e308 is a tensor: checked without overflow (no LinAlgError), and a wrong
    # one is refused for what it is
    huge = LinkInertia(1.0, c, np.diag([1e308, 1e308, 1e308]))
    assert np.isfinite(dynamics.inverse_dynamics(
        dynamics.with_inertias(models.ur3(), [huge] + [lk.inertia for lk in
                                                      models.ur3().links[1:]]),
        np.zeros(6), np.ones(6), np.ones(6))).all()
    with pytest.raises(ValueError, match="triangle inequality"):
        LinkInertia(1.0, c, np.diag([1e307, 1e307, 1e308]))
    # moved() takes rigid transforms only, and names X_AB
    body = LinkInertia.rod(1.0, [0, 0, 0], [0.2, 0, 0], 0.01)
    scaled = np.eye(4)
    scaled[:3, :3] *= 1.001
    bad_row = np.eye(4)
    bad_row[3, 2] = 0.1
    with pytest.raises(ValueError, match=r"the rotation block of X_AB is not orthonormal"):
        body.moved(scaled)
    with pytest.raises(ValueError, match=r"X_AB must have bottom row"):
        body.moved(bad_row)
    X = np.eye(4)
    X[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    np.testing.assert_allclose(body.moved(X).tensor.diagonal(), body.tensor.diagonal()[[1, 0, 2]])


def test_a_payload_composes_with_a_tool_in_either_order():
    robot = models.ur5e()
    tool = np.eye(4)
    tool[:3, :3] = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]
    tool[:3, 3] = [0.02, 0.0, 0.15]
    cog = [0.01, -0.02, 0.08]
    a = dynamics.with_payload(robot, 2.5, cog, radius=0.04).with_tool(tool)
    b = dynamics.with_payload(robot.with_tool(tool), 2.5, cog, radius=0.04)
    assert [lk.inertia for lk in a.links] == [lk.inertia for lk in b.links]
    np.testing.assert_array_equal(a.tool, b.tool)
    q = np.random.default_rng(7).uniform(-np.pi, np.pi, (5, 6))
    np.testing.assert_array_equal(dynamics.gravity_torques(a, q), dynamics.gravity_torques(b, q))
    # the centre of gravity is the flange's, as URScript's set_payload(m, cog): the extra
    # torques are those of m g at the flange point cog, whatever the tool
    extra = dynamics.gravity_torques(a, q) - dynamics.gravity_torques(robot, q)
    X = robot.fk(q)
    p = np.einsum("kab,b->ka", X[:, :3, :3], cog) + X[:, :3, 3]
    for k in range(len(q)):
        J = robot.with_tool(z=0.0).jacobian(q[k])        # flange Jacobian; the point's:
        J_p = J[:3] - np.cross(p[k] - X[k, :3, 3], J[3:].T).T
        np.testing.assert_allclose(extra[k], 2.5 * 9.81 * J_p[2], rtol=0, atol=1e-10)


def test_a_calibrated_arm_keeps_its_models_ratings_and_bodies():
    from dqlab.ur.calibration import CalibrationConf, robot_from_corrections

    # a real UR3's calibration.conf (MyRobotLab/pyrobotlab, issue 145): its DH frames 2 to 4
    # lie 12 to 30 m along their axes from the model's
    conf = CalibrationConf(
        delta_theta=(9.14361764983717684e-08, 0.178461025123001604, 6.68283349819805572,
                     -0.578116982609792496, 6.11299818305960363e-06, -5.03926212855332345e-07),
        delta_a=(-0.000243788991999517813, 0.00381165418642351317, 0.034503078453104935,
                 0.000107694612896758047, -0.000198736633205663144, 0.0),
        delta_d=(9.225352853908797e-05, 12.0620003757611567, 17.6719025641737275,
                 -29.7339960369544869, -2.8164617795367608e-05, 0.000217420471082099831),
        delta_alpha=(0.00115615746589403656, 0.0035851898103369975, 0.00392132336586574568,
                     0.000406668888106365145, -0.00201170396009153762, 0.0))
    calibrated, nominal = robot_from_corrections(conf, "UR3"), models.ur3()
    for mine, theirs in zip(calibrated.links, nominal.links, strict=True):
        assert (mine.max_speed, mine.max_torque, mine.limits) == (
            theirs.max_speed, theirs.max_torque, theirs.limits)
        assert mine.inertia.mass == theirs.inertia.mass
        np.testing.assert_allclose(np.linalg.eigvalsh(mine.inertia.tensor),
                                   np.linalg.eigvalsh(theirs.inertia.tensor), rtol=1e-9)
    np.testing.assert_array_equal(SafetyLimits.for_robot(calibrated).max_joint_torque,
                                  UR_MAX_JOINT_TORQUE["UR3"])
    # the bodies are where the arm is: the torques are the model's to the calibration's
    # millimetre, not those of links tens of metres long
    q, qd, qdd = np.random.default_rng(8).normal(0.0, 1.5, (3, 20, 6))
    tau, tau_nominal = (dynamics.inverse_dynamics(r, q, qd, qdd) for r in (calibrated, nominal))
    assert np.abs(tau - tau_nominal).max() < 0.02 * np.abs(tau_nominal).max()
    copied = dynamics.with_inertias(calibrated, [lk.inertia for lk in nominal.links])
    tau_copied = dynamics.inverse_dynamics(copied, q, qd, qdd)     # the numbers copied: bodies
    assert np.abs(tau_copied[:, 0]).max() > 10 * np.abs(tau_nominal).max()   # metres away


def test_model_inertias_go_only_onto_a_description_of_the_same_arm():
    """Another arm's bodies would land where this arm has no links: refused, naming both."""
    d = list(models.UR_DH["UR3"]["d"])
    d[1], d[2] = 12.0, -12.0                         # the UR3, its frames 12 m along the axes
    far = Robot.from_dh_table(d=d, a=models.UR_DH["UR3"]["a"], alpha=models.UR_ALPHA)
    assert models.with_model_inertias(far, models.ur3()).links[1].inertia is not None
    with pytest.raises(ValueError, match=r"^robot and model must describe one arm: their "
                                         r"flanges are 0\.\d+ m apart"):
        models.with_model_inertias(far, models.ur5e())
    with pytest.raises(TypeError, match="^model must be a Robot, got None"):
        models.with_model_inertias(far, None)
