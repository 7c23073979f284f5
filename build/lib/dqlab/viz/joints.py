r"""A robot with one slider per joint, in a 3D view that needs no kernel and no server.

:class:`JointSliders` draws a serial robot in a :class:`dqlab.viz.Scene` as a chain of nested
nodes, one per joint, so that each joint moves only its own node: the pose of body
:math:`i` in body :math:`i-1` is

.. math::

    X_{i-1,i}(q_i) = P_i \; M(q_i) \; S_i ,

with constant transforms :math:`P_i` (body :math:`i-1` to the joint's axis frame, whose z
axis is the joint axis) and :math:`S_i` (that axis frame at :math:`q_i = 0` to body
:math:`i`), and :math:`M(q_i)` a turn about z by :math:`q_i` (revolute) or a shift along z
(prismatic). Both constants are read off the robot's own forward kinematics and joint axes
at :math:`q = 0`, so the drawing works for standard and modified DH alike.

Each joint's motion over its range is recorded as one animation clip of meshcat's static
viewer, the joint angle being the clip's time axis. A small control panel in the view sets
each clip's time separately: one range slider per joint, no kernel needed. With
``jacobian=True`` the panel also redraws the linear parts of the geometric Jacobian's
columns, :math:`z_i \times (p - o_i)`, from the tool point whenever a slider moves.

In a live notebook, :meth:`JointSliders.set_joints` poses the arm from Python (mirrored to
the live meshcat server by :meth:`dqlab.viz.scene.Scene.live`) and :meth:`JointSliders.widgets`
returns ``ipywidgets`` sliders that call it (``ipywidgets`` comes with the ``viz`` extra).
"""

import json

import meshcat.geometry as g
import numpy as np

from .scene import Scene

__all__ = ["JointSliders"]

_JOINT_COLOR = 0x2F6DB5
_LINK_COLOR = 0xC9CED4
_AXIS_COLORS = (0xD62728, 0x2CA02C, 0x1F77B4)
COLUMN_COLORS = (0xE6194B, 0x3CB44B, 0xFFB000, 0x4363D8, 0x911EB4, 0x00A3A3)


def _frame_with_z(origin, z):
    """A frame whose z axis is the unit vector ``z`` and whose origin is ``origin``."""
    z = np.asarray(z, dtype=float) / np.linalg.norm(z)
    helper = np.eye(3)[np.argmin(np.abs(z))]
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    X = np.eye(4)
    X[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    X[:3, 3] = origin
    return X


def _motion(value, prismatic):
    """M(q): a turn about z by ``value`` radians, or a shift along z by ``value`` metres."""
    X = np.eye(4)
    if prismatic:
        X[2, 3] = value
    else:
        c, s = np.cos(value), np.sin(value)
        X[:2, :2] = [[c, -s], [s, c]]
    return X


def _material(color):
    return g.MeshLambertMaterial(color=int(color), reflectivity=0.5)


def _rod(node, start, end, radius, color):
    """A cylinder from ``start`` to ``end`` (node coordinates, metres)."""
    start, end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    length = float(np.linalg.norm(end - start))
    if length < 1e-9:
        return
    node.set_object(g.Cylinder(length, radius), _material(color))
    y = (end - start) / length                     # meshcat's cylinders lie along y
    helper = np.eye(3)[np.argmin(np.abs(y))]
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    X = np.eye(4)
    X[:3, :3] = np.column_stack([x, y, np.cross(x, y)])
    X[:3, 3] = (start + end) / 2
    node.set_transform(X)


class JointSliders:
    """A robot in a 3D view with one slider per joint (and, optionally, its Jacobian).

    Parameters
    ----------
    robot : dqlab.robot.Robot
        The chain to draw (``links``, ``fk(q, all_frames=True)``, ``joint_axes(q)``,
        ``jacobian(q)``).
    q : array_like, shape (n,), optional
        Initial joint vector (radians, metres for prismatic joints); zeros by default.
    ranges : array_like, shape (n, 2), optional
        Slider range of each joint. By default the joint limits, clipped to
        :math:`[-\\pi, \\pi]` for revolute joints.
    samples : int
        Keyframes per joint clip; the view interpolates between them.
    frames : bool
        Draw the frame of every body (RGB = x, y, z).
    jacobian : bool
        Draw the linear parts of the Jacobian's columns from the tool point, updated by the
        sliders.
    scale : float
        Metres drawn per m/s for the Jacobian's columns (joint speed 1 rad/s).
    grid_size : float
        Side of the floor grid, metres.

    Raises
    ------
    ValueError
        When ``q`` or ``ranges`` has the wrong shape, is not finite, ``q`` lies outside its
        range, or ``samples`` is below 2.

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> view = JointSliders(ur3(), [0.0, -1.2, 1.0, -0.5, 1.1, 0.2], jacobian=True)
    >>> doc = view.document(bundle="none")
    >>> doc.count('class="dqlab-joint"')
    6
    """

    def __init__(self, robot, q=None, *, ranges=None, samples=61, frames=True, jacobian=False,
                 scale=0.5, grid_size=1.0):
        self.robot = robot
        links = list(robot.links)
        self.n = n = len(links)
        self.prismatic = [getattr(link, "joint", "revolute") == "prismatic" for link in links]
        q = np.zeros(n) if q is None else np.asarray(q, dtype=float)
        if q.shape != (n,) or not np.all(np.isfinite(q)):
            raise ValueError(f"q must be {n} finite joint values, got {q!r}")
        if ranges is None:
            ranges = []
            for link, prismatic in zip(links, self.prismatic, strict=True):
                lo, hi = link.limits
                if not prismatic:
                    lo, hi = max(lo, -np.pi), min(hi, np.pi)
                ranges.append((lo, hi))
        ranges = np.asarray(ranges, dtype=float)
        if ranges.shape != (n, 2) or not np.all(np.isfinite(ranges)) or np.any(
                ranges[:, 1] <= ranges[:, 0]):
            raise ValueError(f"ranges must be {n} finite increasing pairs (lo, hi), "
                             f"got {ranges!r}")
        if np.any(q < ranges[:, 0]) or np.any(q > ranges[:, 1]):
            raise ValueError(f"q = {q!r} lies outside the slider ranges {ranges.tolist()}")
        if int(samples) < 2:
            raise ValueError(f"samples must be at least 2, got {samples}")
        self.q = q.copy()
        self.ranges = ranges
        self.scale = float(scale)
        self.jacobian = bool(jacobian)
        self.scene = Scene(grid_size=grid_size)
        self._build(frames)
        self._record_clips(int(samples))
        self.set_joints(q)
        frames0 = robot.fk(q, all_frames=True)
        center = frames0[:, :3, 3].mean(axis=0)
        reach = float(np.max(np.linalg.norm(frames0[:, :3, 3] - center, axis=1))) + 0.15
        self.scene.set_camera(center + reach * np.array([1.0, -1.25, 0.7]), center)

    # -- the nested drawing -----------------------------------------------------------

    def _build(self, frames):
        robot, n = self.robot, self.n
        zero = np.zeros(n)
        F = np.asarray(robot.fk(zero, all_frames=True), dtype=float)[: n + 1]
        points, axes = robot.joint_axes(zero)
        reach = max(float(np.max(np.linalg.norm(F[:, :3, 3] - F[0, :3, 3], axis=1))), 0.05)
        r_joint = 0.045 * reach
        self.pre, self.post, self.paths = [], [], []
        parent = "sliders/base"
        base = self.scene.vis[parent]
        base.set_transform(F[0])
        if frames:
            self._triad(base["frame"], 0.18 * reach)
        for i in range(n):
            A = _frame_with_z(points[i], axes[i])                  # axis frame at q = 0
            pre = np.linalg.inv(F[i]) @ A
            post = np.linalg.inv(A) @ F[i + 1]
            self.pre.append(pre)
            self.post.append(post)
            joint_path = f"{parent}/pre{i + 1}/joint{i + 1}"
            self.scene.vis[f"{parent}/pre{i + 1}"].set_transform(pre)
            joint = self.scene.vis[joint_path]
            _rod(joint["cylinder"], [0, 0, -1.3 * r_joint], [0, 0, 1.3 * r_joint], r_joint,
                 _JOINT_COLOR)
            body_path = f"{joint_path}/body{i + 1}"
            self.scene.vis[body_path].set_transform(post)
            body = self.scene.vis[body_path]
            # a rod from this joint's axis point to the next one (or to the flange)
            start = np.linalg.inv(F[i + 1]) @ np.r_[points[i], 1.0]
            end = (np.linalg.inv(F[i + 1]) @ np.r_[points[i + 1], 1.0] if i + 1 < n
                   else np.r_[0.0, 0.0, 0.0, 1.0])
            _rod(body["link"], start[:3], end[:3], 0.55 * r_joint, _LINK_COLOR)
            if frames or i + 1 == n:
                self._triad(body["frame"], (0.3 if i + 1 == n else 0.18) * reach)
            self.paths.append(joint_path)
            parent = body_path
        self.flange_path = parent
        if self.jacobian:
            J = self.robot.jacobian(self.q)
            p = self.robot.fk(self.q)[:3, 3]
            for i in range(n):
                self.scene.add_path(np.array([p, p + self.scale * J[:3, i]]),
                                    name=f"sliders/columns/col{i + 1}",
                                    color=COLUMN_COLORS[i % len(COLUMN_COLORS)])

    def _triad(self, node, length):
        for axis, label, color in zip(np.eye(3), "xyz", _AXIS_COLORS, strict=True):
            _rod(node[label], np.zeros(3), length * axis, 0.06 * length, color)

    def _local(self, i, value):
        """X_{i-1,i}(value) = P_i M(value) S_i, the pose of body i in body i - 1."""
        return self.pre[i] @ _motion(value, self.prismatic[i]) @ self.post[i]

    def _record_clips(self, samples):
        """One clip per joint: its node's motion over the slider range, 1 s long."""
        self.duration = 1.0
        times = np.linspace(0.0, self.duration, samples)
        for i, (lo, hi) in enumerate(self.ranges):
            values = lo + (hi - lo) * times / self.duration
            poses = np.array([_motion(v, self.prismatic[i]) for v in values])
            self.scene.animate_transforms(self.paths[i], poses, times=times, loop=False,
                                          play=False)

    # -- posing from Python -------------------------------------------------------------

    def set_joints(self, q):
        """Pose the arm at ``q`` (and redraw the Jacobian's columns); reaches a live view."""
        q = np.asarray(q, dtype=float)
        if q.shape != (self.n,) or not np.all(np.isfinite(q)):
            raise ValueError(f"q must be {self.n} finite joint values, got {q!r}")
        for i in range(self.n):
            self.scene.vis[self.paths[i]].set_transform(_motion(q[i], self.prismatic[i]))
        if self.jacobian:
            J = self.robot.jacobian(q)
            p = self.robot.fk(q)[:3, 3]
            for i in range(self.n):
                self.scene.add_path(np.array([p, p + self.scale * J[:3, i]]),
                                    name=f"sliders/columns/col{i + 1}",
                                    color=COLUMN_COLORS[i % len(COLUMN_COLORS)])
        self.q = q.copy()

    def body_poses(self, q):
        """World poses of the bodies as the nested drawing composes them, ``(n + 1, 4, 4)``.

        The same as ``robot.fk(q, all_frames=True)`` (without a tool): tests use it to
        check the drawing.
        """
        q = np.asarray(q, dtype=float)
        X = [np.asarray(self.robot.fk(np.zeros(self.n), all_frames=True))[0]]
        for i in range(self.n):
            X.append(X[-1] @ self._local(i, q[i]))
        return np.array(X)

    def widgets(self):
        """``ipywidgets`` sliders that pose the arm from Python, one per joint.

        Moving a slider calls :meth:`set_joints` with the values of all the sliders, so the
        arm (and, with ``jacobian=True``, the Jacobian's columns) moves on the live meshcat
        view that ``view.scene.live()`` opens. The sliders span the view's ``ranges``, start at its
        current joint vector ``q`` and step by 0.01 rad (1 mm for a prismatic joint).
        Building them needs no kernel; they move the arm only in a running notebook.

        Returns
        -------
        ipywidgets.VBox
            The sliders ``q1 ... qn``, in joint order, as its ``children``.

        Raises
        ------
        ImportError
            With an explanation, when ipywidgets is not installed (it comes with the ``viz``
            extra: ``pip install dqlab[viz]``).

        Examples
        --------
        In a running notebook, one cell opens the live view (embedded, with its address
        for a browser tab) and the next shows the sliders that move it::

            view = JointSliders(ur3(), q_home)
            view.scene.live()

            view.widgets()
        """
        try:
            import ipywidgets
        except ImportError:
            raise ImportError("JointSliders.widgets needs ipywidgets: pip install ipywidgets "
                              "(it comes with dqlab[viz]; the static view's sliders need "
                              "nothing)") from None
        sliders = []
        for i, (value, (lo, hi), prismatic) in enumerate(
                zip(self.q, self.ranges, self.prismatic, strict=True)):
            sliders.append(ipywidgets.FloatSlider(
                value=float(value), min=float(lo), max=float(hi),
                step=0.001 if prismatic else 0.01,
                readout_format=".3f" if prismatic else ".2f",
                description=f"q{i + 1}", continuous_update=True))

        def update(_change):
            self.set_joints([slider.value for slider in sliders])

        for slider in sliders:
            slider.observe(update, names="value")
        return ipywidgets.VBox(sliders)

    # -- output -------------------------------------------------------------------------

    def _spec(self):
        return {
            "joints": [{"path": ["meshcat", *p.split("/")], "lo": float(lo), "hi": float(hi),
                        "q0": float(v), "prismatic": bool(pr)}
                       for p, (lo, hi), v, pr in zip(self.paths, self.ranges, self.q,
                                                     self.prismatic, strict=True)],
            "duration": self.duration,
            "flange": ["meshcat", *self.flange_path.split("/")],
            "columns": ([["meshcat", "sliders", "columns", f"col{i + 1}", "<object>"]
                         for i in range(self.n)] if self.jacobian else None),
            "scale": self.scale,
        }

    def document(self, *, bundle="auto"):
        """The view's HTML document: the scene and the joint control panel."""
        doc = self.scene.document(bundle=bundle)
        rows = "".join(
            f'<label>q{i + 1} <input class="dqlab-joint" type="range" data-joint="{i}" '
            f'min="{lo!r}" max="{hi!r}" step="any" value="{v!r}"> '
            f'<span class="dqlab-joint-value"></span></label>'
            for i, ((lo, hi), v) in enumerate(zip(self.ranges.tolist(), self.q.tolist(),
                                                  strict=True)))
        panel = _PANEL.replace("%ROWS%", rows).replace("%SPEC%", json.dumps(self._spec()))
        head, tail = doc.rsplit("</body>", 1)
        return head + panel + "</body>" + tail

    def html(self, *, height=460, bundle="auto", title="3D view with joint sliders"):
        """An ``<iframe>`` of the view, like :meth:`dqlab.viz.scene.Scene.html`."""
        doc = self.document(bundle=bundle)
        escaped = doc.replace("&", "&amp;").replace('"', "&quot;")
        count = len(self.scene.commands())
        return (f'<iframe class="dqlab-scene dqlab-joint-sliders" data-dqlab-scene="{count}" '
                f'title="{title}" style="width: 100%; height: {int(height)}px; '
                f'border: 1px solid #d0d7de; border-radius: 4px;" srcdoc="{escaped}"></iframe>')

    def show(self, *, height=460, bundle="auto"):
        """Display the view in a notebook (it survives into the built book)."""
        from .scene import SceneView

        return SceneView(self.html(height=height, bundle=bundle))

    def _repr_html_(self):
        return self.html()


# The control panel: one range input per joint. Each joint's clip is an animation action of
# meshcat's viewer; a slider sets that action's time (joint value -> time in the clip) and
# the mixer applies it. The Jacobian's columns are redrawn from the nodes' world matrices.
_PANEL = """<style>
#dqlab-joints { position: absolute; left: 6px; bottom: 6px; background: rgba(255,255,255,.85);
  font: 12px sans-serif; padding: 4px 6px; border-radius: 4px; }
#dqlab-joints label { display: block; white-space: nowrap; }
#dqlab-joints input { width: 140px; vertical-align: middle; }
</style>
<div id="dqlab-joints">%ROWS%</div>
<script>
(function () {
  var spec = %SPEC%;
  var state = window.dqlabJoints = {q: spec.joints.map(function (j) { return j.q0; }),
                                    columns: null, ready: false};
  if (!window.viewer || dqlab.status !== "ok") return;
  var anim = viewer.animator;
  anim.pause();
  anim.actions.forEach(function (a) { a.reset(); a.play(); a.paused = true; });
  var V3 = viewer.camera.position.constructor;               // three.js's Vector3
  function node(path) { return viewer.scene_tree.find(path).object; }
  function worldOf(obj) {
    var m = obj.matrixWorld.elements;
    return {z: new V3(m[8], m[9], m[10]).normalize(),
            o: new V3(m[12], m[13], m[14])};
  }
  function redraw() {
    viewer.scene.updateMatrixWorld(true);
    if (spec.columns) {
      var p = worldOf(node(spec.flange)).o;
      state.columns = spec.joints.map(function (j, i) {
        var axis = worldOf(node(j.path));
        var v = j.prismatic ? axis.z.clone()
                            : axis.z.clone().cross(p.clone().sub(axis.o));
        var line = node(spec.columns[i]);
        var a = line.worldToLocal(p.clone());
        var b = line.worldToLocal(p.clone().add(v.clone().multiplyScalar(spec.scale)));
        var pos = line.geometry.attributes.position;
        pos.setXYZ(0, a.x, a.y, a.z);
        pos.setXYZ(1, b.x, b.y, b.z);
        pos.needsUpdate = true;
        line.geometry.computeBoundingSphere();
        return [(b.x - a.x) / spec.scale, (b.y - a.y) / spec.scale, (b.z - a.z) / spec.scale];
      });
    }
    viewer.set_dirty();
  }
  function setJoint(i, value) {
    var j = spec.joints[i];
    var t = (value - j.lo) / (j.hi - j.lo) * spec.duration;
    anim.actions[i].time = Math.max(0, Math.min(spec.duration, t));
    state.q[i] = value;
    anim.mixer.update(0);
    redraw();
  }
  var inputs = document.querySelectorAll("#dqlab-joints input.dqlab-joint");
  inputs.forEach(function (input) {
    var i = Number(input.dataset.joint), label = input.nextElementSibling;
    function show() {
      label.textContent = Number(input.value).toFixed(2) +
        (spec.joints[i].prismatic ? " m" : " rad");
    }
    input.addEventListener("input", function () { setJoint(i, Number(input.value)); show(); });
    show();
    setJoint(i, Number(input.value));
  });
  state.ready = true;
})();
</script>
"""
