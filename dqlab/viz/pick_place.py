"""The pick-and-place task of :mod:`dqlab.pick_place` in a 3D scene (chapter 12).

:func:`animate_pick_place` plays a :class:`~dqlab.pick_place.PickPlacePlan` in a
:class:`~dqlab.viz.scene.Scene`: the arm along its joint trajectory, the suction cup (red while
it sucks), the object it carries, and the pads the object rests on.
"""

import numpy as np

from .._checks import as_float_array, check_instance, check_scalar
from ..pick_place import PickPlacePlan
from ..robot import Robot
from .scene import PATH_COLOR, Scene

__all__ = ["animate_pick_place"]


def animate_pick_place(scene, robot, plan, *, size=(0.06, 0.04, 0.004), name="robot",
                       object_color=0x2E86C1, stride=1, loop=True):
    """Animate a plan in a :class:`dqlab.viz.scene.Scene`: the arm, its cup, the object, pads.

    Draws the arm (:meth:`~dqlab.viz.scene.Scene.add_robot`) and plays ``plan.q`` on it; a cup
    (a short cylinder, red while sucking) follows ``plan.cup``; the object, a box of
    ``size`` whose top face is at its frame, follows ``plan.object``; a grey pad supports
    the object where it starts and where it is left; the cup's path is drawn in orange.

    Parameters
    ----------
    scene : dqlab.viz.scene.Scene
    robot : Robot
        :func:`dqlab.models.desk_arm`, the arm the plan was made for.
    plan : dqlab.pick_place.PickPlacePlan
    size : (float, float, float), optional
        The object's length, width and thickness, metres.
    name : str, optional
        The robot's name in the scene.
    object_color : int, optional
    stride : int, optional
        Animate every ``stride``-th sample (and the last): a lighter view for the book; the
        viewer interpolates between the kept samples.
    loop : bool, optional
        Repeat the animation.

    Examples
    --------
    >>> from dqlab import viz
    >>> from dqlab.models import desk_arm
    >>> from dqlab.pick_place import plan_pick_place, task_from_lab
    >>> task = task_from_lab([[0, 170, 80, 0, 0], [0, 170, 30, 1, 0], [0, -170, 35, 0, 180]])
    >>> scene = viz.Scene(grid_size=0.8, grid_step=0.05)
    >>> animate_pick_place(scene, desk_arm(), plan_pick_place(desk_arm(), task), stride=2)
    >>> paths = {c.get("path", "") for c in scene.commands()}
    >>> {"/meshcat/cup/on", "/meshcat/object/box", "/meshcat/pads/start"} <= paths
    True
    """
    import meshcat.geometry as g  # (imported by dqlab.viz.scene, warnings filtered)

    check_instance(scene, Scene, "scene")
    check_instance(robot, Robot, "robot")
    check_instance(plan, PickPlacePlan, "plan")
    stride = min(check_scalar(stride, "stride", minimum=1, integer=True), len(plan.t))
    keep = np.unique(np.append(np.arange(0, len(plan.t), stride), len(plan.t) - 1))
    t, q, suction = plan.t[keep], plan.q[keep], plan.suction[keep]
    cup, obj = plan.cup[keep], plan.object[keep]
    size = as_float_array(size, "size")
    if size.shape != (3,) or not np.all(size > 0):
        raise ValueError(f"size must be three lengths > 0, got {size!r}")
    lx, ly, lz = size.tolist()
    scene.add_robot(robot, q[0, :3], name=name)
    scene.animate(q[:, :3], name=name, times=t, loop=loop)
    scene.add_path(plan.cup[:, :3, 3], name="cup_path", color=PATH_COLOR)

    def material(color):
        return g.MeshLambertMaterial(color=int(color))

    # the cup: a cylinder (three.js cylinders run along y) just above the cup point
    turn = np.eye(4)
    turn[:3, :3] = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]              # y -> -z (upwards)
    turn[:3, 3] = [0.0, 0.0, -0.01]
    for state, color in (("off", 0x555555), ("on", 0xC0392B)):
        node = scene.vis["cup"][state]
        node.set_object(g.Cylinder(0.02, 0.012), material(color))
        node.set_transform(turn)
    hidden = np.diag([1e-6, 1e-6, 1e-6, 1.0]) @ turn              # shrunk to nothing
    sucking = suction[:, None, None]
    scene.animate_transforms("cup", cup, times=t, loop=loop)
    scene.animate_transforms("cup/on", np.where(sucking, turn, hidden), times=t, loop=loop)
    scene.animate_transforms("cup/off", np.where(sucking, hidden, turn), times=t, loop=loop)

    # the object: a box whose frame is the centre of its top face
    box = np.eye(4)
    box[2, 3] = -lz / 2
    scene.vis["object"]["box"].set_object(g.Box([lx, ly, lz]), material(object_color))
    scene.vis["object"]["box"].set_transform(box)
    scene.animate_transforms("object", obj, times=t, loop=loop)

    # pads under the object where it starts and where it is left
    for label, X in (("start", plan.object[0]), ("end", plan.object[-1])):
        height = float(X[2, 3]) - lz
        if height <= 1e-4:
            continue
        pad = np.eye(4)
        pad[:3, 3] = [X[0, 3], X[1, 3], height / 2]
        scene.vis["pads"][label].set_object(g.Box([lx * 1.3, ly * 1.3, height]),
                                            material(0xB3B6B7))
        scene.vis["pads"][label].set_transform(pad)
