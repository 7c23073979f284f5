"""Tests for dqlab.viz.joints: the nested drawing of JointSliders poses every body like the
forward kinematics, one animation clip per joint, and the control panel of the static view."""

import sys

import numpy as np
import pytest
import umsgpack

from dqlab.models import scara_rsm5, six_r, ur3, ur3_mdh
from dqlab.viz.joints import JointSliders


@pytest.mark.parametrize("make_robot", [ur3, ur3_mdh, six_r, scara_rsm5])
def test_nested_drawing_composes_to_the_forward_kinematics(make_robot):
    robot = make_robot()
    view = JointSliders(robot)
    rng = np.random.default_rng(1)
    for _ in range(20):
        lo, hi = view.ranges[:, 0], view.ranges[:, 1]
        q = lo + (hi - lo) * rng.uniform(size=len(lo))
        assert np.allclose(view.body_poses(q), robot.fk(q, all_frames=True), atol=1e-12)


def test_one_clip_per_joint_in_joint_order():
    view = JointSliders(ur3(), samples=11)
    animation = [c for c in view.scene.commands() if c["type"] == "set_animation"]
    assert len(animation) == 1
    clips = animation[0]["animations"]
    assert [c["path"] for c in clips] == [f"/meshcat/{p}" for p in view.paths]
    for clip in clips:
        times = [key["time"] for key in clip["clip"]["tracks"][0]["keys"]]
        assert clip["clip"]["fps"] == 1000               # times in ms: a 1 s clip
        assert len(times) == 11 and times[0] == 0 and np.isclose(times[-1], 1000.0)
    assert animation[0]["options"]["play"] is False


def test_the_view_has_one_slider_per_joint_and_starts_at_q():
    q = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    view = JointSliders(ur3(), q, jacobian=True)
    html = view.html(bundle="none")
    assert 'class="dqlab-scene dqlab-joint-sliders"' in html
    assert f'data-dqlab-scene="{len(view.scene.commands())}"' in html
    doc = view.document(bundle="none")
    assert doc.count('class="dqlab-joint"') == 6
    for value in q:
        assert f'value="{float(value)!r}"' in doc
    # the joint nodes start at q, the columns at the Jacobian's linear parts
    commands = {(c["type"], c.get("path")): c for c in view.scene.commands()}
    J, p = ur3().jacobian(q), ur3().fk(q)[:3, 3]
    for i in range(6):
        line = commands[("set_object", f"/meshcat/sliders/columns/col{i + 1}")]
        geometry = line["object"]["geometries"][0]["data"]["attributes"]["position"]
        ends = np.frombuffer(geometry["array"].data if hasattr(geometry["array"], "data")
                             else geometry["array"], dtype=np.float32).reshape(-1, 3)
        assert np.allclose(ends[0], p, atol=1e-6)
        assert np.allclose(ends[1], p + 0.5 * J[:3, i], atol=1e-6)
    assert umsgpack.packb(view.scene.commands()[0])   # the commands serialise


def test_set_joints_moves_the_joint_nodes():
    view = JointSliders(ur3())
    q = np.array([0.1, -0.4, 0.8, 0.0, 0.5, -0.3])
    view.set_joints(q)
    commands = {(c["type"], c.get("path")): c for c in view.scene.commands()}
    for i, path in enumerate(view.paths):
        X = np.array(commands[("set_transform", f"/meshcat/{path}")]["matrix"]).reshape(4, 4).T
        assert np.allclose(X[:2, :2], [[np.cos(q[i]), -np.sin(q[i])],
                                       [np.sin(q[i]), np.cos(q[i])]], atol=1e-7)
    assert np.array_equal(view.q, q)


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="q must be 6"):
        JointSliders(ur3(), [0.0, 1.0])
    with pytest.raises(ValueError, match="q must be 6"):
        JointSliders(ur3(), [0.0, np.nan, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="ranges"):
        JointSliders(ur3(), ranges=[(0, 1)] * 5)
    with pytest.raises(ValueError, match="outside the slider ranges"):
        JointSliders(ur3(), [4.0, 0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="samples"):
        JointSliders(ur3(), samples=1)
    view = JointSliders(ur3())
    with pytest.raises(ValueError, match="q must be 6"):
        view.set_joints([0.0])


def test_widgets_explain_a_missing_ipywidgets(monkeypatch):
    monkeypatch.setitem(sys.modules, "ipywidgets", None)      # as if it were not installed
    with pytest.raises(ImportError, match="pip install ipywidgets"):
        JointSliders(ur3()).widgets()


def test_widgets_are_built_without_a_kernel_and_pose_the_arm():
    ipywidgets = pytest.importorskip("ipywidgets")
    q = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    view = JointSliders(ur3(), q, jacobian=True)
    box = view.widgets()
    assert isinstance(box, ipywidgets.VBox) and len(box.children) == 6
    for i, slider in enumerate(box.children):
        assert isinstance(slider, ipywidgets.FloatSlider)
        assert slider.description == f"q{i + 1}" and slider.value == q[i]
        assert (slider.min, slider.max) == tuple(view.ranges[i])
    # moving one slider poses the arm at all the sliders' values, Jacobian included
    box.children[2].value = 0.25
    q_moved = q.copy()
    q_moved[2] = 0.25
    assert np.array_equal(view.q, q_moved)
    commands = {(c["type"], c.get("path")): c for c in view.scene.commands()}
    X = np.array(commands[("set_transform", f"/meshcat/{view.paths[2]}")]["matrix"])
    assert np.allclose(X.reshape(4, 4).T[:2, :2], [[np.cos(0.25), -np.sin(0.25)],
                                                   [np.sin(0.25), np.cos(0.25)]], atol=1e-7)
    assert np.allclose(view.body_poses(view.q), ur3().fk(q_moved, all_frames=True))


def test_widgets_of_a_prismatic_joint_step_by_a_millimetre():
    pytest.importorskip("ipywidgets")
    view = JointSliders(scara_rsm5())
    slider = view.widgets().children[2]                      # the vertical slide
    assert slider.step == 0.001 and (slider.min, slider.max) == tuple(view.ranges[2])
    slider.value = 0.1
    assert np.isclose(view.q[2], 0.1)
