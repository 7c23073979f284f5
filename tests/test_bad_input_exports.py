"""What dqlab writes for another program is accepted by it, or refused here by name.

MJCF goes to MuJoCo and URDF to any XML reader: a link MuJoCo cannot move (no mass, a point
mass) is refused with the link's name, and a model name that XML cannot hold is refused, the
output of every name accepted being parsed back. A robot's base and tool are rigid within an
absolute tolerance, checked where they enter; a maker's table gives its prismatic joints'
travel and its angles in radians.
"""

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from dqlab.inertia import LinkInertia
from dqlab.models import ur3, ur5e
from dqlab.robot import Robot
from dqlab.sim import mjcf_from_robot, urdf_from_robot
from dqlab.sim.mjcf import MIN_INERTIA

UR3 = ur3()


def _with_link_inertia(robot, i, inertia):
    links = list(robot.links)
    links[i] = links[i].with_inertia(inertia)
    return Robot(links, convention=robot.convention, base=robot.base, tool=robot.tool,
                 name=robot.name)


def test_a_link_mujoco_cannot_move_is_refused_by_link():
    mujoco = pytest.importorskip("mujoco")
    c = [0.0, 0.02, 0.1]
    point = _with_link_inertia(UR3, 2, LinkInertia.sphere(1.2, c))
    massless = _with_link_inertia(UR3, 4, LinkInertia(0.0, c))
    thin = _with_link_inertia(UR3, 1, LinkInertia(1.0, c, [0.0, 0.01, 0.01, 0, 0, 0]))
    # what is refused here, MuJoCo refuses too (written without the check)
    from dqlab.sim import mjcf as module

    original = module._check_moving_body
    module._check_moving_body = lambda *args: None
    try:
        for robot in (point, massless, thin):
            with pytest.raises(ValueError, match="inertia must have positive eigenvalues"):
                mujoco.MjModel.from_xml_string(mjcf_from_robot(robot))
    finally:
        module._check_moving_body = original
    with pytest.raises(ValueError, match=r"^link 3's inertia \(robot.links\[2\].inertia\) has "
                                         r"a principal moment of 0 kg m\^2, below 1e-12"):
        mjcf_from_robot(point)
    with pytest.raises(ValueError, match=r"scaled to masses\[2\]\) has a principal moment"):
        mjcf_from_robot(point, masses=[1.0] * 6)
    with pytest.raises(ValueError, match=r"^link 5's inertia .* has mass 0 kg, below 1e-06"):
        mjcf_from_robot(massless)
    with pytest.raises(ValueError, match=r"^link 5's inertia .*scaled to masses\[4\]\) has a "
                                         r"principal moment"):
        mjcf_from_robot(massless, masses=[1.0] * 6)        # a point mass of the given mass
    with pytest.raises(ValueError, match=r"^link 2's inertia"):
        mjcf_from_robot(thin)
    # a small body, just above the bound, in a turned frame: written, and MuJoCo loads it
    tensor = np.diag([1.0, 2.0, 2.5]) * 1.01 * MIN_INERTIA
    small = _with_link_inertia(UR3, 3, LinkInertia(1e-3, c, tensor))
    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(small))
    assert np.isclose(model.body_inertia[5].min(), 1.01 * MIN_INERTIA, rtol=1e-9)
    with pytest.raises(ValueError, match=r"^link 4's inertia .* principal moment of 9.9e-13"):
        mjcf_from_robot(_with_link_inertia(UR3, 3, LinkInertia(1e-3, c, tensor * 0.98)))


NAMES_REFUSED = {"x\x00y": r"'\\x00' at position 1 is a control character",
                 "arm\n<joint/>": r"'\\n' at position 3 is a control character",
                 "tab\there": r"'\\t' at position 3", "esc\x1b": r"'\\x1b' at position 3",
                 "del\x7f": r"'\\x7f' at position 3", "c1\x85": r"'\\x85' at position 2",
                 "half \ud800": r"'\\ud800' at position 5 cannot be written in a text file",
                 "nonchar \uffff": r"'\\uffff' at position 8", "line\u2028sep": "position 4",
                 "": "not be empty", "x" * 201: "be at most 200 characters"}


def test_a_name_xml_cannot_hold_is_refused_and_every_other_is_written_well_formed():
    mujoco = pytest.importorskip("mujoco")
    for generate in (mjcf_from_robot, urdf_from_robot):
        for name, message in NAMES_REFUSED.items():
            with pytest.raises(ValueError, match=r"^name must .*" + message):
                generate(UR3, name=name)
            if name:                      # a robot without a name is written as "robot"
                with pytest.raises(ValueError, match=r"^name must .*" + message):
                    Robot(UR3.links, name=name)             # refused where it enters
                robot = ur3()
                with pytest.raises(ValueError, match=r"^name must .*" + message):
                    robot.name = name
                assert robot.name == "UR3"
        with pytest.raises(TypeError, match="^name must be text, got 123"):
            generate(UR3, name=123)
    for name in ["UR3 <bench> & \"lab\" 'one'", "Démo bras ☃ 𝔘𝔯3", "]]> --> <!--", "a" * 200]:
        root = ET.fromstring(urdf_from_robot(UR3, name=name))
        assert root.tag == "robot" and root.get("name") == name
        xml = mjcf_from_robot(UR3, name=name)
        assert ET.fromstring(xml).get("model") == name
        assert mujoco.MjModel.from_xml_string(xml).nbody == 9
    assert ET.fromstring(urdf_from_robot(Robot(UR3.links))).get("name") == "robot"


def test_a_base_or_tool_off_rigid_is_refused_by_its_name():
    off = np.eye(4)
    off[:3, :3] *= 1 + 1e-6                # passes allclose's default rtol, not 1e-9
    skew = np.eye(4)
    skew[3, 0] = 1e-12
    for call, name in [(lambda T: ur5e().with_tool(T), "X_nT"),
                       (lambda T: Robot(UR3.links, base=T), "base"),
                       (lambda T: Robot(UR3.links, tool=T), "tool"),
                       (lambda T: setattr(ur3(), "base", T), "base"),
                       (lambda T: Robot.from_dh_table(d=[0.1], a=[0.2], alpha=[0.0], tool=T),
                        "tool")]:
        with pytest.raises(ValueError, match=rf"^{name} must be a rigid transform: the "
                                             rf"rotation block of {name} is not orthonormal: "
                                             r"\|R\^T R - I\| reaches 2e-06"):
            call(off)
        with pytest.raises(ValueError, match=rf"^{name} must be a rigid transform: {name} "
                                             r"must have bottom row \(0, 0, 0, 1\)"):
            call(skew)
    rigid = np.eye(4)
    rigid[:3, :3] = [[math.cos(0.3), -math.sin(0.3), 0], [math.sin(0.3), math.cos(0.3), 0],
                     [0, 0, 1]]
    assert np.array_equal(ur5e().with_tool(rigid).tool, rigid)


def test_a_table_gives_its_prismatic_travel_and_its_angles_in_radians():
    table = {"d": [0.4, 0.0, 0.0, 0.05], "a": [0.25, 0.2, 0.0, 0.0],
             "alpha": [0.0, math.pi, 0.0, 0.0]}
    joints = ["revolute", "revolute", "prismatic", "revolute"]
    with pytest.raises(ValueError, match=r"^limits: joint 3 is prismatic and has no default "
                                         r"range: give the joints' limits \(metres"):
        Robot.from_dh_table(**table, joint=joints)
    travel = [[-2.6, 2.6], [-2.6, 2.6], [0.0, 0.2], [-6.3, 6.3]]
    robot = Robot.from_dh_table(**table, joint=joints, limits=travel)
    assert np.array_equal(robot.limits, travel)
    assert np.all(np.isinf(Robot.from_dh_table(**table, joint=joints, limits=None).limits))
    q = np.array([0.3, -0.5, 0.1, 0.7])
    lowered = robot.fk(q + [0, 0, 0.05, 0])[:3, 3] - robot.fk(q)[:3, 3]
    assert np.allclose(lowered, [0.0, 0.0, -0.05], atol=1e-15)    # metres, along -z (alpha2 = pi)
    with pytest.raises(ValueError, match=r"^theta_offset\[1\] = 90 is more than 2 pi: angle "
                                         r"offsets are in radians \(a table in degrees\?"):
        Robot.from_dh_table(**table, theta_offset=[0, 90, 0, 0], limits=None)
    with pytest.raises(ValueError, match=r"^alpha\[1\] = 180 is more than 2 pi"):
        Robot.from_dh_table(**{**table, "alpha": [0, 180, 0, 0]}, limits=None)
    with pytest.raises(ValueError, match="^joint must be one type or one per joint"):
        Robot.from_dh_table(**table, joint=7.5)
