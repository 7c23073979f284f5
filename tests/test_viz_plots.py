"""matplotlib helpers of dqlab.viz: what they draw, on the Agg backend."""

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.colors import to_rgba

from dqlab import models, viz
from dqlab.viz.plots import AXIS_COLORS


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def test_backend_is_non_interactive():
    assert matplotlib.get_backend().lower() == "agg"


def _ranges(ax):
    return [hi - lo for lo, hi in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())]


def test_axes_3d_labels_and_title():
    ax = viz.axes_3d(title="UR3")
    assert ax.name == "3d"
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ("x (m)", "y (m)", "z (m)")
    assert ax.get_title() == "UR3"


def test_set_axes_equal_3d_and_2d():
    ax = viz.set_axes_equal(viz.axes_3d(), [[0, 0, 0], [1, 2, 0.5]], margin=0.0)
    np.testing.assert_allclose(_ranges(ax), [2.0, 2.0, 2.0])
    np.testing.assert_allclose(ax.get_ylim(), [0.0, 2.0])
    _, ax2 = plt.subplots()
    viz.set_axes_equal(ax2, [[0, 0], [4, 1]], margin=0.0)
    np.testing.assert_allclose(ax2.get_xlim(), [0.0, 4.0])
    np.testing.assert_allclose(ax2.get_ylim(), [-1.5, 2.5])


def test_plot_frame_draws_rgb_axes_along_the_rotation_columns():
    X = np.eye(4)
    X[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # 90 degrees about z
    X[:3, 3] = [1.0, 2.0, 3.0]
    ax = viz.plot_frame(viz.axes_3d(), X, label="{E}", length=0.5)
    quivers = ax.collections
    assert len(quivers) == 3
    for k, quiver in enumerate(quivers):
        np.testing.assert_allclose(quiver.get_color()[0], to_rgba(AXIS_COLORS[k]))
        shaft = np.asarray(quiver._segments3d[0])  # first segment: the shaft (3D data)
        ends = sorted(map(tuple, shaft.round(12)))
        assert ends == sorted(map(tuple, np.array([X[:3, 3], X[:3, 3] + 0.5 * X[:3, k]])))
    assert ax.texts[0].get_text().strip() == "{E}"


def test_plot_frame_rejects_a_bad_shape():
    with pytest.raises(ValueError, match="shape"):
        viz.plot_frame(viz.axes_3d(), np.eye(3))


def test_plot_frames_labels():
    F = np.tile(np.eye(4), (3, 1, 1))
    ax = viz.plot_frames(viz.axes_3d(), F)
    assert [t.get_text().strip() for t in ax.texts] == ["{0}", "{1}", "{2}"]
    assert len(ax.collections) == 9
    ax = viz.plot_frames(viz.axes_3d(), F, labels=False)
    assert len(ax.texts) == 0
    with pytest.raises(ValueError):
        viz.plot_frames(viz.axes_3d(), F, labels=["only one"])


def test_plot_vector_2d_and_3d():
    _, ax = plt.subplots()
    viz.plot_vector(ax, [1.0, 2.0], origin=[1.0, 0.0], label="v")
    arrow = ax.texts[0]
    assert arrow.xy == (2.0, 2.0) and arrow.xyann == (1.0, 0.0)
    assert ax.texts[-1].get_text().strip() == "v"
    ax3 = viz.plot_vector(viz.axes_3d(), [0.0, 0.0, 1.0])
    assert len(ax3.collections) == 1
    with pytest.raises(ValueError, match="shape"):
        viz.plot_vector(ax, [1.0, 2.0, 3.0])


def test_plot_planar_arm_complex_and_xy_agree():
    z = np.cumsum([0, 1.0, 0.8 * np.exp(0.5j)])
    ax1 = viz.plot_planar_arm(None, z, label="arm")
    ax2 = viz.plot_planar_arm(None, np.column_stack([z.real, z.imag]))
    for ax in (ax1, ax2):
        x, y = ax.lines[0].get_data()
        np.testing.assert_allclose(x + 1j * y, z)
        assert ax.get_aspect() == 1.0
        assert ax.get_xlabel() == "x (m)"
    assert ax1.lines[0].get_label() == "arm"
    with pytest.raises(ValueError):
        viz.plot_planar_arm(None, np.zeros((3, 3)))


def test_plot_arm_from_ur3_frames():
    robot = models.ur3()
    frames = robot.fk(np.array([0, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0]),
                      all_frames=True)
    ax = viz.plot_arm(None, frames, label="UR3")
    x, y, z = ax.lines[0].get_data_3d()
    np.testing.assert_allclose(np.column_stack([x, y, z]), frames[:, :3, 3])
    ranges = _ranges(ax)
    np.testing.assert_allclose(ranges, ranges[0])
    assert len(ax.collections) == 2 + 6  # joints, tip, base and flange frames
    with pytest.raises(ValueError, match="shape"):
        viz.plot_arm(None, frames[0])


def test_plot_complex_arrows_and_unit_circle():
    ax = viz.plot_complex(None, [1 + 1j, -0.5j], labels=["z", "w"], unit_circle=True)
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("Re", "Im")
    arrows = [t for t in ax.texts if t.get_text() == ""]
    assert [a.xy for a in arrows] == [(1.0, 1.0), (0.0, -0.5)]
    circle = ax.lines[0].get_xydata()
    np.testing.assert_allclose(np.hypot(*circle.T), 1.0)
    assert ax.get_aspect() == 1.0
    dots = viz.plot_complex(None, 2.0, arrows=False)
    assert dots.lines[-1].get_xydata().tolist() == [[2.0, 0.0]]
