"""Tests of dqlab.sim: the generated MuJoCo model is the robot, the controllers track, the
simulated arm serves the UR client."""

import numpy as np
import pytest

from dqlab import models
from dqlab.rotations import matrix_from_axis_angle
from dqlab.sim import UR3_LINK_MASSES, mjcf_from_robot
from dqlab.transforms import transform_from

mujoco = pytest.importorskip("mujoco")


def site_pose(model, data, name="flange"):
    sid = model.site(name).id
    X = np.eye(4)
    X[:3, :3] = data.site_xmat[sid].reshape(3, 3)
    X[:3, 3] = data.site_xpos[sid]
    return X


def ur3_with_base_and_tool():
    robot = models.ur3()
    robot.base = transform_from(matrix_from_axis_angle([1.0, 2.0, 3.0], 0.7), [0.3, -0.2, 0.8])
    robot.tool = transform_from(matrix_from_axis_angle([0.0, 1.0, 1.0], 0.4), [0.01, 0.02, 0.15])
    return robot


ROBOTS = {
    "ur3": models.ur3,
    "ur3_mdh": models.ur3_mdh,
    "scara_rsm5": models.scara_rsm5,
    "six_r": models.six_r,
    "ur3_base_tool": ur3_with_base_and_tool,
}


def random_joints(robot, count, seed):
    """Joint vectors inside the limits (revolute ones within +-pi where unlimited)."""
    rng = np.random.default_rng(seed)
    lo, hi = robot.limits.T
    lo, hi = np.maximum(lo, -2 * np.pi), np.minimum(hi, 2 * np.pi)
    return rng.uniform(lo, hi, size=(count, robot.n))


@pytest.mark.parametrize("name", ROBOTS)
def test_flange_site_pose_equals_robot_fk(name):
    """The test that proves the generated model is the robot: 1,000 random configurations."""
    robot = ROBOTS[name]()
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(robot))
    data = mujoco.MjData(model)
    Q = random_joints(robot, 1000, seed=1)
    X_expected = robot.fk(Q)
    worst = 0.0
    for q, X in zip(Q, X_expected, strict=True):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        worst = max(worst, np.abs(site_pose(model, data) - X).max())
    assert worst <= 1e-9, f"{name}: flange pose differs from robot.fk by {worst:.3g}"


@pytest.mark.parametrize("name", ROBOTS)
def test_one_joint_per_link_in_chain_order(name):
    robot = ROBOTS[name]()
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(robot))
    assert model.njnt == model.nq == model.nv == model.nu == robot.n
    want = [mujoco.mjtJoint.mjJNT_HINGE if j == "revolute" else mujoco.mjtJoint.mjJNT_SLIDE
            for j in robot.joint_types]
    assert list(model.jnt_type) == want
    # each joint moves the body of its own link, and bodies nest in chain order
    bodies = [model.body(f"link{i + 1}").id for i in range(robot.n)]
    assert list(model.jnt_bodyid) == bodies
    assert [model.body_parentid[b] for b in bodies[1:]] == bodies[:-1]
    # joint ranges from the robot's limits
    lo, hi = robot.limits.T
    finite = np.isfinite(lo) & np.isfinite(hi)
    np.testing.assert_allclose(model.jnt_range[finite], robot.limits[finite])
    assert model.jnt_limited[finite].all()


def test_ur3_masses_match_the_data_sheet():
    """Moving links from UR's table, the whole arm 11 kg as in the thesis's annex A."""
    robot = models.ur3()
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(robot))
    links = [model.body_mass[model.body(f"link{i + 1}").id] for i in range(6)]
    np.testing.assert_allclose(links, UR3_LINK_MASSES)
    base = model.body("base").id
    assert model.body_subtreemass[base] == pytest.approx(11.0, abs=1e-6)
    # inertias are positive (computed by MuJoCo from the drawn shapes)
    assert (model.body_inertia[1:] > 0).all()


def test_payload_is_a_mass_at_the_tcp():
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(models.ur3(), payload=3.0))
    assert model.body_mass[model.body("payload").id] == pytest.approx(3.0)


@pytest.mark.parametrize("kwargs, word", [
    ({"masses": [1, 2, 3]}, "masses"),
    ({"masses": [1, 1, 1, 1, 1, -1]}, "masses"),
    ({"payload": -1.0}, "payload"),
    ({"payload": float("nan")}, "payload"),
    ({"timestep": 0.0}, "timestep"),
    ({"damping": float("inf")}, "damping"),
    ({"radius": -0.1}, "radius"),
    ({"integrator": "leapfrog"}, "integrator"),
])
def test_mjcf_refuses_bad_arguments(kwargs, word):
    with pytest.raises(ValueError, match=word):
        mjcf_from_robot(models.ur3(), **kwargs)


def test_mjcf_refuses_a_non_robot():
    with pytest.raises(TypeError, match="robot"):
        mjcf_from_robot("UR3")
