"""Interactive 3D scenes with meshcat, for notebooks and for the built book.

A :class:`Scene` records meshcat drawing commands in Python; nothing is started to build one.
It is then shown in one of two ways:

* ``scene.show()`` (or a ``scene`` at the end of a cell) puts a self-contained view in the
  cell output: an ``<iframe srcdoc=...>`` whose small document replays the recorded commands
  with the meshcat viewer script. The view needs no server and no network, so it survives
  into the built book. When the book is built, the Sphinx extension
  :mod:`dqlab.viz.sphinxext` copies the viewer script (three.js and meshcat, about
  0.85 MB) once into the site's ``_static/dqlab/`` and every view loads it from there by a
  relative URL; in a live notebook the script is written into each view instead.
* ``scene.live()`` mirrors the scene to a meshcat server on 127.0.0.1 (started once per
  kernel, stopped when the kernel exits): the instructor opens its URL in a browser tab and
  every later change to the scene appears there at once.

Geometry is in metres, poses are ``(4, 4)`` homogeneous transforms ``X_WB`` (the pose of a
body B in the world W), points are ``(..., 3)`` arrays.
"""

import atexit
import base64
import hashlib
import json
import os
import subprocess
import sys
import warnings
from html import escape as html_escape
from pathlib import Path

import numpy as np
import umsgpack

with warnings.catch_warnings():
    # meshcat 0.3 imports its server, which uses an event-loop module pyzmq deprecates.
    warnings.filterwarnings("ignore", message="zmq.eventloop.ioloop is deprecated",
                            category=DeprecationWarning)
    import meshcat
    import meshcat.animation
    import meshcat.geometry as g

from .._files import write_atomically

__all__ = ["Scene", "SceneView", "LiveView", "LiveWindow", "live_server", "stop_live_server",
           "viewer_script_path", "view_iframe"]

#: Environment variable naming the book's source directory while the book is built; set by
#: :mod:`dqlab.viz.sphinxext`. When present, views load the shared viewer script.
BOOK_ROOT_ENV = "DQLAB_VIZ_BOOK_ROOT"
#: Where the built site keeps the shared viewer script, relative to the site root.
SHARED_SCRIPT = "_static/dqlab/meshcat.min.js"

AXIS_COLORS = (0xD62728, 0x2CA02C, 0x1F77B4)  # x red, y green, z blue (as in dqlab.viz.plots)
LINK_COLOR = 0xC9CED4
JOINT_COLOR = 0x2F6DB5
BASE_COLOR = 0x4A4F55
PATH_COLOR = 0xE67E22
POINT_COLOR = 0x8E44AD


def viewer_script_path():
    """Path of meshcat's viewer script (three.js and the meshcat viewer, minified).

    Returns
    -------
    pathlib.Path
        ``meshcat/viewer/dist/main.min.js`` inside the installed meshcat package.

    Examples
    --------
    >>> viewer_script_path().name
    'main.min.js'
    """
    return Path(meshcat.__file__).resolve().parent / "viewer" / "dist" / "main.min.js"


# --- recording ----------------------------------------------------------------------------


class _Lowered:
    """A command already lowered to its msgpack-ready dictionary (meshcat's command API)."""

    __slots__ = ["data"]

    def __init__(self, data):
        self.data = data

    def lower(self):
        return self.data


def _under(path, prefix):
    return path == prefix or path.startswith(prefix.rstrip("/") + "/")


class _Recorder:
    """A meshcat "window" that keeps the scene's commands instead of sending them.

    Like meshcat's server it keeps only what matters for the final scene: the last object,
    transform and properties of each path; a deleted path forgets its subtree. The order of
    first appearance is kept, so parents are drawn before their children.
    """

    def __init__(self):
        self.commands = {}
        self.mirror = None

    def send(self, command):
        data = command.lower()
        kind, path = data["type"], data.get("path", "")
        if kind == "set_object":
            for key in [k for k in self.commands if k[1] == path and k[0] in ("o", "p")]:
                del self.commands[key]
            self.commands[("o", path)] = data
        elif kind == "set_transform":
            self.commands[("t", path)] = data
        elif kind == "set_property":
            self.commands[("p", path, data["property"])] = data
        elif kind == "set_animation":
            self.commands.pop(("a", ""), None)
            self.commands[("a", "")] = data
        elif kind == "delete":
            for key in [k for k in self.commands if k[0] != "a" and _under(k[1], path)]:
                del self.commands[key]
            self.commands[("d", path)] = data
        else:
            raise ValueError(f"cannot record a meshcat command of type {kind!r}")
        if self.mirror is not None:
            self.mirror.send(command)

    def ordered(self):
        """The recorded commands, animation last (it refers to objects drawn before it)."""
        cmds = [c for k, c in self.commands.items() if k[0] != "a"]
        return cmds + [c for k, c in self.commands.items() if k[0] == "a"]

    def packed(self):
        return [umsgpack.packb(c) for c in self.ordered()]


# --- geometry helpers ---------------------------------------------------------------------


def _pose(X, name):
    X = np.asarray(X, dtype=float)
    if X.shape != (4, 4) or not np.all(np.isfinite(X)):
        raise ValueError(f"{name} must be a finite (4, 4) transform, got shape {X.shape}")
    return X


def _points(P, name):
    P = np.asarray(P, dtype=float)
    if P.ndim == 1:
        P = P[None, :]
    if P.ndim != 2 or P.shape[1] != 3:
        raise ValueError(f"{name} must have shape (k, 3), got shape {np.shape(P)}")
    if not np.all(np.isfinite(P)):
        raise ValueError(f"{name} contains NaN or infinity")
    return P


def _translation(p):
    X = np.eye(4)
    X[:3, 3] = p
    return X


def _y_to(direction):
    """Rotation matrix (4x4) taking the y axis (three.js cylinders) to ``direction``."""
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    y = np.array([0.0, 1.0, 0.0])
    v = np.cross(y, d)
    c = float(np.dot(y, d))
    X = np.eye(4)
    if np.linalg.norm(v) < 1e-12:
        if c < 0:
            X[:3, :3] = np.diag([1.0, -1.0, -1.0])
        return X
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    X[:3, :3] = np.eye(3) + vx + vx @ vx * (1.0 / (1.0 + c))
    return X


def _material(color, opacity=1.0):
    m = g.MeshLambertMaterial(color=int(color))
    if opacity < 1.0:
        m.transparent = True
        m.opacity = float(opacity)
    return m


def _rod(vis, start, end, radius, color):
    """A cylinder from ``start`` to ``end`` (in the node's frame) at node ``vis``."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    length = float(np.linalg.norm(end - start))
    vis.set_object(g.Cylinder(length, radius), _material(color))
    X = _y_to(end - start)
    X[:3, 3] = (start + end) / 2
    vis.set_transform(X)


def _triad(vis, length, radius=None):
    """Three rods along x, y, z (red, green, blue) at node ``vis``."""
    radius = 0.05 * length if radius is None else radius
    for axis, label, color in zip(np.eye(3), "xyz", AXIS_COLORS, strict=True):
        _rod(vis[label], np.zeros(3), length * axis, radius, color)


def _times(count, fps, times, name):
    if times is None:
        if fps <= 0:
            raise ValueError(f"fps must be positive, got {fps}")
        return np.arange(count) / float(fps)
    t = np.asarray(times, dtype=float)
    if t.shape != (count,) or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise ValueError(f"times must be {count} increasing finite numbers for {name}")
    return t


# --- robots -------------------------------------------------------------------------------


class _RobotDrawing:
    """Where a robot's bodies live in the scene, and how they are posed."""

    def __init__(self, robot, path, n_bodies):
        self.robot = robot
        self.path = path
        self.n_bodies = n_bodies

    def poses(self, q):
        """World poses of the bodies: base, then one body per joint (the FK frames).

        ``fk(q, all_frames=True)`` ends with the TCP (the flange composed with the tool);
        the last body is the flange, so the tool is taken off again.
        """
        frames = np.array(self.robot.fk(q, all_frames=True), dtype=float)
        tool = _tool(self.robot)
        if tool is not None:
            frames[..., -1, :, :] = frames[..., -1, :, :] @ np.linalg.inv(tool)
        return frames


def _tool(robot):
    """The robot's tool transform ``X_FT``, or None when there is no tool."""
    tool = getattr(robot, "tool", None)
    if tool is None:
        return None
    tool = np.asarray(tool, dtype=float)
    return None if np.allclose(tool, np.eye(4)) else tool


def _reach(links):
    sizes = [max(abs(float(link.a)), abs(float(link.d))) for link in links]
    return max(max(sizes, default=0.0), 1e-3)


def _link_geometry(robot):
    """Rods of each body, in that body's own frame, from the DH values.

    Returns a list (one entry per body 0..n) of lists of ``(start, end)`` points and a list
    (one per body) of the joint axis carried by that body as ``(origin, axis)`` or ``None``.

    Standard DH (frame i is carried by body i, joint i turns about z_{i-1}): body i holds the
    offset d_i along z_{i-1}, then a_i along x_i, ending at its origin, and carries the axis
    of joint i+1 (its own z). Modified DH (joint i turns about z_i): body i holds d_i along
    its own z ending at its origin, then a_i (stored with link i+1) along its x, and carries
    the axis of joint i.
    """
    links = list(robot.links)
    n = len(links)
    rods = [[] for _ in range(n + 1)]
    axes = [None] * (n + 1)
    convention = getattr(robot, "convention", "dh")
    for i, link in enumerate(links, start=1):
        a, d, alpha = float(link.a), float(link.d), float(link.alpha)
        prismatic = getattr(link, "joint", "revolute") == "prismatic"
        if prismatic:
            hi = max((abs(x) for x in getattr(link, "limits", None) or ()), default=0.0)
            d = max(abs(d), hi, 0.1 * _reach(links))
        if convention == "mdh":
            rods[i].append((np.array([0.0, 0.0, -d]), np.zeros(3)))
            if i - 1 >= 1 or a != 0.0:
                rods[i - 1].append((np.zeros(3), np.array([a, 0.0, 0.0])))
            axes[i] = np.array([0.0, 0.0, 1.0])
        else:
            corner = np.array([-a, 0.0, 0.0])
            z_prev = np.array([0.0, np.sin(alpha), np.cos(alpha)])
            rods[i].append((corner - d * z_prev, corner))
            rods[i].append((corner, np.zeros(3)))
            axes[i - 1] = np.array([0.0, 0.0, 1.0])
    clean = [[(s, e) for s, e in body if np.linalg.norm(e - s) > 1e-9] for body in rods]
    return clean, axes


# --- the scene ----------------------------------------------------------------------------


class Scene:
    """A 3D scene recorded for meshcat: robots, frames, points, paths and animations.

    Nothing is started to build a scene. Show it in a notebook with :meth:`show` (a
    self-contained interactive view that also appears in the built book) or mirror it to a
    live meshcat server with :meth:`live`.

    Parameters
    ----------
    grid : bool
        Draw a floor grid in the world's xy plane.
    grid_size, grid_step : float
        Side of the square grid and spacing of its lines, metres.
    world_frame : bool
        Show meshcat's own axes at the world origin (off by default: robots draw their base
        frame themselves).

    Attributes
    ----------
    vis : meshcat.Visualizer
        The underlying meshcat visualizer at path ``/meshcat``, for anything this class does
        not wrap; its commands are recorded like the others.

    Examples
    --------
    >>> import numpy as np
    >>> scene = Scene()
    >>> scene.add_frame(np.eye(4), name="W", length=0.2)
    >>> scene.add_path([[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0]], name="tcp_path")
    >>> len(scene.commands()) > 0
    True
    """

    def __init__(self, *, grid=True, grid_size=1.0, grid_step=0.1, world_frame=False):
        self._recorder = _Recorder()
        self.vis = meshcat.Visualizer(window=self._recorder)
        self._robots = {}
        self._animation = None
        self._camera_set = False
        self._view = None
        self._live = None
        if not world_frame:
            self.vis["/Axes"].set_property("visible", False)
        # meshcat's own grid is 20 m wide: too coarse for a desktop arm.
        self.vis["/Grid"].set_property("visible", False)
        if grid:
            self._floor(float(grid_size), float(grid_step))
        # A light background, as on the book's pages.
        self.vis["/Background"].set_property("top_color", [0.97, 0.98, 0.99])
        self.vis["/Background"].set_property("bottom_color", [0.78, 0.82, 0.87])

    def _floor(self, size, step):
        ticks = np.arange(-size / 2, size / 2 + step / 2, step)
        half = size / 2
        segments = [[(t, -half, 0.0), (t, half, 0.0)] for t in ticks]
        segments += [[(-half, t, 0.0), (half, t, 0.0)] for t in ticks]
        P = np.asarray(segments, dtype=np.float32).reshape(-1, 3).T
        self.vis["floor"].set_object(
            g.LineSegments(g.PointsGeometry(P), g.LineBasicMaterial(color=0xA7B1BC)))

    # -- content -----------------------------------------------------------------------

    def add_robot(self, robot, q=None, *, name="robot", frames=False, radius=None,
                  link_color=LINK_COLOR, joint_color=JOINT_COLOR):
        """Draw a serial robot from primitives sized by its DH values, posed at ``q``.

        Every body (the base, then one per joint) is a node of the scene placed at its FK
        frame: joints are cylinders along their axes, the DH offsets ``d`` and lengths ``a``
        are rods, the flange carries a small RGB frame.

        Parameters
        ----------
        robot : dqlab.robot.Robot
            Any chain with ``links`` (each with ``a``, ``d``, ``alpha``), ``convention``
            (``"dh"`` or ``"mdh"``) and ``fk(q, all_frames=True)`` returning the ``(n + 1,
            4, 4)`` frames of base and bodies.
        q : array_like, shape (n,), optional
            Joint vector in radians (metres for prismatic joints); zeros by default.
        name : str
            Name of the robot in the scene (several robots need different names).
        frames : bool
            Also draw the DH frame of every body (RGB = x, y, z).
        radius : float, optional
            Joint radius in metres; by default 17 % of the robot's largest DH length.
        link_color, joint_color : int
            Colours as ``0xRRGGBB``.
        """
        links = list(robot.links)
        n = len(links)
        q = np.zeros(n) if q is None else np.asarray(q, dtype=float)
        reach = _reach(links)
        r_joint = 0.17 * reach if radius is None else float(radius)
        r_link = 0.6 * r_joint
        h_joint = 2.6 * r_joint
        rods, axes = _link_geometry(robot)
        path = f"{name}"
        root = self.vis[path]
        root.delete()
        for i in range(n + 1):
            body = root[f"body{i}"]
            for k, (start, end) in enumerate(rods[i]):
                _rod(body[f"rod{k}"], start, end, r_link, link_color)
            if axes[i] is not None:
                center = np.zeros(3)
                if i == 0 and getattr(robot, "convention", "dh") == "dh" and n:
                    d1 = float(links[0].d)
                    if abs(d1) >= h_joint / 2:  # keep the first joint above the floor
                        center = np.array([0.0, 0.0, np.copysign(h_joint / 2, d1)])
                _rod(body["joint"], center - axes[i] * h_joint / 2,
                     center + axes[i] * h_joint / 2, r_joint, joint_color)
            if frames:
                _triad(body["frame"], 0.35 * reach)
        base = root["body0"]["foot"]
        base.set_object(g.Cylinder(0.2 * r_joint, 1.35 * r_joint), _material(BASE_COLOR))
        base.set_transform(_y_to([0, 0, 1]) @ _translation([0, 0.1 * r_joint, 0]))
        _triad(root[f"body{n}"]["flange"], 0.45 * reach, 0.06 * r_joint)
        tool = _tool(robot)
        if tool is not None:  # a rod to the TCP and the TCP frame
            _rod(root[f"body{n}"]["tool_rod"], np.zeros(3), tool[:3, 3], 0.5 * r_link,
                 link_color)
            _triad(root[f"body{n}"]["tcp"], 0.45 * reach, 0.06 * r_joint)
            root[f"body{n}"]["tcp"].set_transform(tool)
        self._robots[name] = _RobotDrawing(robot, path, n + 1)
        self.set_joints(q, name=name)
        if not self._camera_set:
            self._frame_camera(self._robots[name].poses(q)[:, :3, 3], 1.2 * r_joint)

    def set_joints(self, q, *, name="robot"):
        """Pose a robot already in the scene at the joint vector ``q`` (radians)."""
        drawing = self._robot(name)
        frames = drawing.poses(np.asarray(q, dtype=float))
        for i in range(drawing.n_bodies):
            self.vis[drawing.path][f"body{i}"].set_transform(frames[i])

    def add_frame(self, X, *, name, length=0.1, radius=None):
        """Draw a frame ``X`` (pose of the frame in the world) as RGB rods for x, y, z.

        Parameters
        ----------
        X : array_like, shape (4, 4)
            Homogeneous transform ``X_WF``.
        name : str
            Scene path of the frame (``"target"``, ``"frames/F1"``...).
        length : float
            Length of each axis in metres.
        radius : float, optional
            Rod radius; 5 % of ``length`` by default.
        """
        node = self.vis[name]
        _triad(node, float(length), radius)
        node.set_transform(_pose(X, "X"))

    def add_points(self, points, *, name, color=POINT_COLOR, radius=0.01):
        """Draw points as small spheres (a point cloud beyond 200 points).

        Parameters
        ----------
        points : array_like, shape (k, 3)
            Positions in the world frame, metres.
        name : str
            Scene path of the group.
        color : int
            ``0xRRGGBB``.
        radius : float
            Sphere radius (or point size of a large cloud), metres.
        """
        P = _points(points, "points")
        node = self.vis[name]
        node.delete()
        if len(P) > 200:
            rgb = np.array([(color >> 16) & 255, (color >> 8) & 255, color & 255]) / 255.0
            colors = np.tile(rgb, (len(P), 1)).T.astype(np.float32)
            node.set_object(g.PointCloud(P.T.astype(np.float32), colors, size=2 * radius))
            return
        for k, p in enumerate(P):
            node[f"p{k}"].set_object(g.Sphere(float(radius)), _material(color))
            node[f"p{k}"].set_transform(_translation(p))

    def add_path(self, points, *, name, color=PATH_COLOR):
        """Draw a polyline through ``points`` (a TCP trajectory, a circle...).

        Parameters
        ----------
        points : array_like, shape (k, 3)
            Vertices in order, world frame, metres.
        name : str
            Scene path of the line.
        color : int
            ``0xRRGGBB``. (WebGL draws lines one pixel wide whatever the width.)
        """
        P = _points(points, "points")
        if len(P) < 2:
            raise ValueError("a path needs at least 2 points")
        line = g.Line(g.PointsGeometry(P.T.astype(np.float32)),
                      g.LineBasicMaterial(color=int(color)))
        self.vis[name].set_object(line)

    def set_camera(self, position, target=(0.0, 0.0, 0.0)):
        """Place the camera at ``position`` looking at ``target``, the centre it orbits.

        Parameters
        ----------
        position, target : array_like, shape (3,)
            World coordinates in metres (z up).
        """
        position = _points(position, "position")[0]
        target = _points(target, "target")[0]
        self._view = {"position": position.tolist(), "target": target.tolist()}
        # meshcat's own camera sits in a y-up frame and orbits the world origin: this command
        # serves the live viewer; the book's views apply ``_view`` exactly (see _DOCUMENT).
        self.vis["/Cameras/default/rotated/<object>"].set_property(
            "position", [float(position[0]), float(position[2]), float(-position[1])])
        self._camera_set = True

    def _frame_camera(self, points, pad):
        """Aim the default camera so that ``points`` (k, 3), padded by ``pad``, fill the view."""
        P = np.vstack([np.asarray(points, dtype=float).reshape(-1, 3), np.zeros((1, 3))])
        lo, hi = P.min(axis=0), P.max(axis=0)
        center = (lo + hi) / 2
        radius = float(np.linalg.norm(hi - lo)) / 2 + pad
        direction = np.array([0.62, -0.78, 0.42])
        direction /= np.linalg.norm(direction)
        # meshcat's camera sees 75 degrees vertically: a sphere of that radius fits.
        distance = radius / np.sin(np.radians(75.0 / 2))
        self.set_camera(center + distance * direction, center)
        self._camera_set = False  # the next robot or animation reframes

    # -- animation -----------------------------------------------------------------------

    def animate(self, q_trajectory, *, name="robot", fps=25.0, times=None, loop=True,
                play=True):
        """Play a joint trajectory on a robot of the scene, with meshcat's time slider.

        The robot is left posed at the first sample when the animation is not playing.

        Parameters
        ----------
        q_trajectory : array_like, shape (k, n)
            Joint vectors, one per sample.
        name : str
            The robot to move (as given to :meth:`add_robot`).
        fps : float
            Samples per second when ``times`` is not given.
        times : array_like, shape (k,), optional
            Increasing sample times in seconds.
        loop : bool
            Repeat the animation (otherwise it plays once).
        play : bool
            Start playing as soon as the view opens.
        """
        drawing = self._robot(name)
        Q = np.asarray(q_trajectory, dtype=float)
        if Q.ndim != 2 or Q.shape[1] != drawing.n_bodies - 1:
            raise ValueError(f"q_trajectory must have shape (k, {drawing.n_bodies - 1}), "
                             f"got shape {Q.shape}")
        t = _times(len(Q), fps, times, "q_trajectory")
        frames = drawing.poses(Q)
        for i in range(drawing.n_bodies):
            self._add_track(f"{drawing.path}/body{i}", frames[:, i], t)
        self.set_joints(Q[0], name=name)
        if not self._camera_set:
            self._frame_camera(frames[..., :3, 3], 0.2 * _reach(drawing.robot.links))
        self._send_animation(loop, play)

    def animate_transforms(self, name, poses, *, fps=25.0, times=None, loop=True, play=True):
        """Move a node of the scene (a frame, a tool...) through a sequence of poses.

        Parameters
        ----------
        name : str
            Scene path of the node, as given to :meth:`add_frame` or another ``add_*``.
        poses : array_like, shape (k, 4, 4)
            World poses of the node, one per sample.
        fps, times, loop, play
            As in :meth:`animate`; all animations of a scene share one time slider.
        """
        X = np.asarray(poses, dtype=float)
        if X.ndim != 3 or X.shape[1:] != (4, 4) or not np.all(np.isfinite(X)):
            raise ValueError(f"poses must be finite with shape (k, 4, 4), got {X.shape}")
        t = _times(len(X), fps, times, "poses")
        self._add_track(name, X, t)
        self.vis[name].set_transform(X[0])
        self._send_animation(loop, play)

    def _add_track(self, path, poses, t):
        if self._animation is None:
            self._animation = meshcat.animation.Animation(default_framerate=1000)
        node = self.vis[path]
        for X, time in zip(poses, t, strict=True):
            with self._animation.at_frame(node, round(float(time) * 1000.0, 3)) as frame:
                frame.set_transform(X)

    def _send_animation(self, loop, play):
        repetitions = 1_000_000 if loop else 1
        self.vis.set_animation(self._animation, play=play, repetitions=repetitions)

    def _robot(self, name):
        try:
            return self._robots[name]
        except KeyError:
            raise ValueError(f"no robot named {name!r} in the scene "
                             f"(robots: {sorted(self._robots)})") from None

    # -- output --------------------------------------------------------------------------

    def commands(self):
        """The recorded meshcat commands (dictionaries), in the order they are replayed."""
        return self._recorder.ordered()

    def html(self, *, height=420, bundle="auto", title="3D view", description=None):
        """HTML of a self-contained interactive view: an iframe that replays the scene.

        Parameters
        ----------
        height : int
            Height of the view in CSS pixels (the width follows the page).
        bundle : {"auto", "shared", "inline", "none"}
            Where the view finds the viewer script. ``"shared"``: the copy in the built
            book's ``_static/dqlab/`` (a relative URL, the page stays small); ``"inline"``:
            inside the view (about 0.85 MB, works anywhere, e.g. a live notebook or a saved
            file); ``"none"``: no script, for tests. ``"auto"`` is ``"shared"`` while the
            book is being built (:mod:`dqlab.viz.sphinxext` says so) and ``"inline"``
            otherwise.
        title : str
            Accessible name of the view (the iframe's ``title`` and its document's title):
            what it shows, in a few words.
        description : str, optional
            A one-sentence text alternative of what the view shows, for readers who cannot
            see it; kept in the page for screen readers (:func:`view_iframe`).

        Returns
        -------
        str
            An ``<iframe srcdoc=...>`` element, followed by its description if any.
        """
        doc = self.document(bundle=bundle, title=title)
        return view_iframe(doc, commands=len(self._recorder.commands), height=height,
                           title=title, description=description)

    def document(self, *, bundle="auto", title="3D view"):
        """The HTML document of the view (what the iframe shows); see :meth:`html`."""
        mode = _bundle_mode(bundle)
        if mode == "shared":
            src = _shared_script_url()
            script = (f'<script src="{src}" onerror="dqlabFail(\'the 3D viewer script was '
                      f'not found at {src}\')"></script>')
        elif mode == "inline":
            script = "<script>" + viewer_script_path().read_text(encoding="utf-8") + "</script>"
        else:
            script = ""
        blobs = ",".join(f'"{base64.b64encode(b).decode("ascii")}"'
                         for b in self._recorder.packed())
        view = json.dumps(self._view)
        return _DOCUMENT.format(script=script, commands=blobs, view=view,
                                title=html_escape(str(title)))

    def show(self, *, height=420, bundle="auto", title="3D view", description=None):
        """Display the scene in the notebook as a self-contained interactive view.

        The view is a snapshot: later changes to the scene do not reach it (call ``show``
        again). It needs no server and no network and appears unchanged in the built book.

        Parameters
        ----------
        height : int
            Height in CSS pixels.
        bundle : {"auto", "shared", "inline", "none"}
            See :meth:`html`.
        title, description : str
            The view's accessible name and its one-sentence text alternative; see
            :meth:`html`.

        Returns
        -------
        SceneView
            Shown by Jupyter when it ends a cell.
        """
        return SceneView(self.html(height=height, bundle=bundle, title=title,
                                   description=description))

    def _repr_html_(self):
        return self.html()

    def save_html(self, path):
        """Write the scene as a standalone HTML page (viewer script inside) to ``path``."""
        return write_atomically(path, self.document(bundle="inline"))

    def live(self, *, height=420):
        """Mirror the scene to the live meshcat server (started on first use).

        Everything recorded so far is sent at once, and every later call (``set_joints``,
        ``add_frame``, ``animate``...) reaches the server as it is made. Open the returned
        view's ``url`` in a browser tab, or let the notebook show it.

        Returns
        -------
        LiveView
        """
        window = live_server()
        previous = _live.get("recorder")
        if previous is not None and previous is not self._recorder:
            previous.mirror = None  # one scene at a time on the live server
        if self._recorder.mirror is not window:
            window.send(_Lowered({"type": "delete", "path": "/meshcat"}))
            for data in self._recorder.ordered():
                window.send(_Lowered(data))
            self._recorder.mirror = window
            _live["recorder"] = self._recorder
        return LiveView(window.web_url, height)


class SceneView:
    """A scene's interactive view in a notebook output (shown through ``_repr_html_``).

    Attributes
    ----------
    html : str
        The ``<iframe>`` element.
    """

    def __init__(self, html):
        self.html = html

    def _repr_html_(self):
        return self.html

    def __repr__(self):
        return f"<dqlab 3D view, {len(self.html) / 1024:.0f} KB of HTML>"


class LiveView:
    """The live server's page, embedded in the notebook (only works while the kernel runs).

    Attributes
    ----------
    url : str
        Address of the live viewer, e.g. ``http://127.0.0.1:7000/static/``.
    """

    def __init__(self, url, height=420):
        self.url = url
        self.height = height

    def _repr_html_(self):
        return (f'<p>Live view at <a href="{self.url}" target="_blank">{self.url}</a> '
                f'(open it in a browser tab for a full-screen view).</p>'
                f'<iframe src="{self.url}" style="width: 100%; height: {self.height}px; '
                f'border: 1px solid #d0d7de;"></iframe>')

    def __repr__(self):
        return f"<dqlab live 3D view at {self.url}>"


def _bundle_mode(bundle):
    if bundle not in ("auto", "shared", "inline", "none"):
        raise ValueError(f"bundle must be 'auto', 'shared', 'inline' or 'none', got {bundle!r}")
    if bundle == "auto":
        return "shared" if os.environ.get(BOOK_ROOT_ENV) else "inline"
    return bundle


def _shared_script_url():
    """URL of the shared viewer script relative to the page being executed.

    While the book is built each notebook runs in its own folder, and its page lands at the
    same place relative to the site root as the notebook relative to the book root.
    """
    root = os.environ.get(BOOK_ROOT_ENV) or os.getcwd()
    rel = os.path.relpath(os.path.abspath(root), os.getcwd()).replace(os.sep, "/")
    return SHARED_SCRIPT if rel == "." else f"{rel}/{SHARED_SCRIPT}"


def view_iframe(document, *, commands, height, title, description=None, classes="dqlab-scene"):
    """The ``<iframe>`` that shows a view's document, with its accessible name and description.

    The iframe's ``title`` names the view; a description becomes a paragraph right after it,
    hidden from the eye (the page's prose describes the view for sighted readers) but read
    by screen readers, and tied to the iframe by ``aria-describedby``.

    Parameters
    ----------
    document : str
        The view's HTML document (put in ``srcdoc``).
    commands : int
        Number of recorded commands, for the browser check (``data-dqlab-scene``).
    height : int
        Height in CSS pixels.
    title : str
    description : str, optional
    classes : str
        CSS classes of the iframe.

    Returns
    -------
    str

    Examples
    --------
    >>> print(view_iframe("<p>x</p>", commands=1, height=100, title="A <b> arm",
    ...                   description="An arm."))  # doctest: +ELLIPSIS
    <iframe class="dqlab-scene" ... title="A &lt;b&gt; arm" aria-describedby="dqlab-view-..." ...
    """
    escaped = document.replace("&", "&amp;").replace('"', "&quot;")
    title = html_escape(str(title))
    described, after = "", ""
    if description:
        key = hashlib.sha1((document + str(description)).encode("utf-8")).hexdigest()[:12]
        described = f' aria-describedby="dqlab-view-{key}"'
        after = (f'<p id="dqlab-view-{key}" class="dqlab-scene-description" '
                 f'style="position: absolute; width: 1px; height: 1px; overflow: hidden; '
                 f'clip: rect(0 0 0 0); white-space: nowrap; margin: 0;">'
                 f'{html_escape(str(description))}</p>')
    return (f'<iframe class="{classes}" data-dqlab-scene="{int(commands)}" title="{title}"'
            f'{described} style="width: 100%; height: {int(height)}px; '
            f'border: 1px solid #d0d7de; border-radius: 4px;" srcdoc="{escaped}"></iframe>'
            + after)


_DOCUMENT = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>html, body {{ margin: 0; height: 100%; overflow: hidden; background: #fff; }}
#pane {{ width: 100%; height: 100%; }}
#dqlab-msg {{ font: 14px sans-serif; color: #a40000; padding: 1em; }}</style></head>
<body><div id="pane"></div>
<script>
var dqlab = {{status: "loading", commands: 0}};
function dqlabFail(msg) {{
  dqlab.status = "error: " + msg;
  document.getElementById("pane").innerHTML = '<p id="dqlab-msg"></p>';
  document.getElementById("dqlab-msg").textContent = msg;
}}
</script>
{script}
<script>
(function () {{
  if (typeof MeshCat === "undefined") {{
    if (dqlab.status === "loading") dqlabFail("the 3D viewer script is not loaded");
    return;
  }}
  try {{
    var commands = [{commands}];
    var viewer = new MeshCat.Viewer(document.getElementById("pane"));
    window.viewer = viewer;
    commands.forEach(function (blob) {{
      var raw = atob(blob), bytes = new Uint8Array(raw.length);
      for (var i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
      viewer.handle_command_bytearray(bytes);
      dqlab.commands += 1;
    }});
    var view = {view};
    if (view) {{
      // meshcat turns its z-up scene into three.js's y-up world: (x, y, z) -> (x, z, -y).
      // Its camera orbits the origin; ours orbits the scene's own centre.
      var p = view.position, t = view.target;
      viewer.camera.position.set(p[0], p[2], -p[1]);
      viewer.controls.target.set(t[0], t[2], -t[1]);
      viewer.controls.update();
      viewer.set_dirty();
    }}
  }} catch (err) {{
    dqlabFail("the 3D view failed: " + err);
    throw err;
  }}
  dqlab.status = "ok";
}})();
// The viewer's control panel (dat.gui) leaves its checkboxes and its image-format menu
// without an accessible name: name each after its row or its folder, now and whenever
// the panel grows (animations add rows).
(function () {{
  function text(el) {{ return el ? el.textContent.trim() : ""; }}
  function nameControls() {{
    document.querySelectorAll(".dg input, .dg select").forEach(function (el) {{
      if (el.getAttribute("aria-label")) return;
      var row = el.closest("li");
      var name = text(row && row.querySelector(".property-name"));
      if (!name && el.closest(".meshcat-visibility-checkbox")) {{
        var folder = el.closest("ul");
        name = "show " + (text(folder && folder.querySelector(":scope > li.title")) || "object");
      }}
      if (!name && el.tagName === "SELECT") name = "image format";
      el.setAttribute("aria-label", name || el.type || "control");
    }});
  }}
  nameControls();
  new MutationObserver(nameControls).observe(document.body, {{childList: true, subtree: true}});
}})();
</script></body></html>
"""


# --- the live server ----------------------------------------------------------------------

_live = {"window": None, "recorder": None}


class LiveWindow:
    """The connection to a live meshcat server that this kernel started.

    It speaks meshcat's command protocol (what ``meshcat.visualizer.ViewerWindow.send``
    sends: the command type, its path and the msgpack-encoded command, one reply per
    command) over a ZeroMQ request socket with time-outs, so a dead server raises instead of
    hanging the kernel.

    Attributes
    ----------
    server_proc : subprocess.Popen
        The server process (``python -m dqlab.viz._server``).
    zmq_url, web_url : str
        Where the server takes commands and where a browser opens the viewer.
    """

    def __init__(self, server_proc, zmq_url, web_url, *, timeout_ms=10_000):
        import zmq

        self.server_proc = server_proc
        self.zmq_url = zmq_url
        self.web_url = web_url
        self._context = zmq.Context()
        self.zmq_socket = self._context.socket(zmq.REQ)
        self.zmq_socket.setsockopt(zmq.LINGER, 0)
        self.zmq_socket.setsockopt(zmq.RCVTIMEO, timeout_ms)
        self.zmq_socket.setsockopt(zmq.SNDTIMEO, timeout_ms)
        self.zmq_socket.connect(zmq_url)

    def send(self, command):
        """Send one meshcat command (an object with ``lower()``) and wait for the reply."""
        data = command.lower()
        self.zmq_socket.send_multipart([data["type"].encode("utf-8"),
                                        data["path"].encode("utf-8"), umsgpack.packb(data)])
        self.zmq_socket.recv()

    def get_scene(self):
        """The server's current scene as a self-contained HTML page."""
        self.zmq_socket.send(b"get_scene")
        return self.zmq_socket.recv().decode("utf-8")

    def close(self):
        """Close the socket (the server keeps running; see :func:`stop_live_server`)."""
        self.zmq_socket.close(linger=0)
        self._context.term()


def live_server():
    """Start the meshcat server for this kernel on 127.0.0.1, or return the running one.

    The server is a child process serving the viewer page on the first free port from 7000
    and listening for drawing commands on the first free port from 6000, both on the
    loopback interface only. It stops with :func:`stop_live_server`, when the Python process
    exits, or by itself when its parent process is gone.

    Returns
    -------
    LiveWindow
        The connection; its ``web_url`` is the page to open.

    Raises
    ------
    RuntimeError
        In a browser kernel (Pyodide), which cannot start the server's process
        (``LiveServerUnavailable``, saying so).
    """
    if sys.platform == "emscripten":
        from ._browser import LiveServerUnavailable

        raise LiveServerUnavailable()
    window = _live["window"]
    if window is not None and window.server_proc.poll() is None:
        return window
    proc = subprocess.Popen(
        [sys.executable, "-u", "-m", "dqlab.viz._server", "--parent-pid", str(os.getpid())],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL,
        start_new_session=True)
    urls = {}
    while len(urls) < 2:
        line = proc.stdout.readline().decode("utf-8").strip()
        if not line and proc.poll() is not None:
            raise RuntimeError(f"the meshcat server exited at start (code {proc.returncode})")
        if "=" in line:
            key, value = line.split("=", 1)
            urls[key] = value
    proc.stdout.close()
    window = LiveWindow(proc, urls["zmq_url"], urls["web_url"])
    _live["window"] = window
    return window


def stop_live_server():
    """Stop the live meshcat server of this kernel, if one runs; wait until it is gone."""
    window, _live["window"] = _live["window"], None
    if _live["recorder"] is not None:
        _live["recorder"].mirror = None
        _live["recorder"] = None
    if window is None:
        return
    try:
        window.close()
    finally:
        proc = window.server_proc
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


atexit.register(stop_live_server)
