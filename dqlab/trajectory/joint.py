r"""Joint-space trajectories: the :class:`Trajectory` type, point-to-point motions with
synchronised joints, motions through via-points, and CSV files.

A point-to-point motion moves every joint along the straight line of joint space,
:math:`q(t) = q_A + s(t)\,(q_B - q_A)` with one normalised time law :math:`s: 0 \to 1`
(:mod:`dqlab.trajectory.time_laws`), so that all joints start, peak and stop together.
Chapter 10 of the book derives them.
"""

import math
from dataclasses import dataclass

import numpy as np

from .._checks import as_float_array, check_path, check_scalar, is_boolean, short_repr
from .._files import read_bytes, write_atomically
from . import time_laws

__all__ = ["Trajectory", "joint_trajectory", "via_points", "MAX_CSV_BYTES"]

_LAWS = ("trapezoidal", "cubic", "quintic")
_POSE_COLUMNS = ("x [m]", "y [m]", "z [m]", "qw", "qx", "qy", "qz")

#: The largest trajectory file :meth:`Trajectory.load_csv` reads, bytes: 256 MiB, half a
#: million samples of a six-joint arm with its tool poses.
MAX_CSV_BYTES = 1 << 28


@dataclass(frozen=True)
class Trajectory:
    r"""A sampled joint trajectory: instants, joint positions, speeds and accelerations.

    Validated on construction: shapes agree, every value is finite, the instants increase
    strictly. Arrays are stored as read-only float arrays.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Instants in seconds, strictly increasing.
    q, qd, qdd : ndarray, shape (N, n)
        Joint positions (rad, or m for prismatic joints), speeds (rad/s) and accelerations
        (rad/s^2).
    poses : ndarray, shape (N, 4, 4), optional
        The tool poses :math:`X_{WT}` the trajectory is meant to reach, when it follows a
        Cartesian path.

    Examples
    --------
    >>> import numpy as np
    >>> traj = Trajectory(t=[0.0, 0.5, 1.0], q=np.zeros((3, 2)), qd=np.zeros((3, 2)),
    ...                   qdd=np.zeros((3, 2)))
    >>> len(traj), traj.n, traj.duration
    (3, 2, 1.0)
    >>> Trajectory(t=[0.0, 0.0], q=np.zeros((2, 1)), qd=np.zeros((2, 1)),
    ...            qdd=np.zeros((2, 1)))
    Traceback (most recent call last):
    ...
    ValueError: t must increase strictly: t[1] = 0 follows t[0] = 0
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    poses: np.ndarray = None

    def __post_init__(self):
        t = as_float_array(self.t, "t")
        if t.ndim != 1 or t.size == 0:
            raise ValueError(f"t must have shape (N,) with N >= 1, got shape {t.shape}")
        steps = np.diff(t)
        if np.any(steps <= 0.0):
            i = int(np.argmax(steps <= 0.0)) + 1
            raise ValueError(f"t must increase strictly: t[{i}] = {t[i]:.9g} follows "
                             f"t[{i - 1}] = {t[i - 1]:.9g}")
        q = as_float_array(self.q, "q")
        if q.ndim != 2 or q.shape[0] != t.size or q.shape[1] == 0:
            raise ValueError(f"q must have shape (N, n) = ({t.size}, n), one row per instant of "
                             f"t, got shape {q.shape}")
        fields = {"t": t, "q": q}
        for name in ("qd", "qdd"):
            a = as_float_array(getattr(self, name), name)
            if a.shape != q.shape:
                raise ValueError(f"{name} must have the shape of q, {q.shape}, got {a.shape}")
            fields[name] = a
        if self.poses is not None:
            fields["poses"] = as_float_array(self.poses, "poses", (4, 4))
            if fields["poses"].shape != (t.size, 4, 4):
                raise ValueError(f"poses must have shape ({t.size}, 4, 4), one pose per instant "
                                 f"of t, got {fields['poses'].shape}")
        for name, a in fields.items():
            a = np.array(a, dtype=float)
            a.flags.writeable = False
            object.__setattr__(self, name, a)

    def __len__(self):
        return self.t.size

    @property
    def n(self):
        """Number of joints."""
        return self.q.shape[1]

    @property
    def duration(self):
        """Last instant minus first, seconds."""
        return float(self.t[-1] - self.t[0])

    def columns(self):
        """The CSV column names, units in brackets."""
        cols = ["t [s]"]
        cols += [f"q{i + 1} [rad]" for i in range(self.n)]
        cols += [f"qd{i + 1} [rad/s]" for i in range(self.n)]
        cols += [f"qdd{i + 1} [rad/s^2]" for i in range(self.n)]
        if self.poses is not None:
            cols += list(_POSE_COLUMNS)
        return cols

    def save_csv(self, path):
        r"""Write the trajectory to a CSV file: one header line with units, one row per
        instant (``repr`` precision, so that :meth:`load_csv` gives back the same floats).

        Columns: ``t [s]``, ``q1 [rad]`` ... ``qn [rad]``, ``qd1 [rad/s]`` ...,
        ``qdd1 [rad/s^2]`` ..., and with poses the tool position ``x [m], y [m], z [m]``
        and its unit quaternion ``qw, qx, qy, qz`` (scalar first).

        Examples
        --------
        >>> import numpy as np, tempfile, os
        >>> traj = joint_trajectory([0.0, 0.0], [1.0, -0.5], duration=1.0, dt=0.25)
        >>> path = os.path.join(tempfile.mkdtemp(), "move.csv")
        >>> traj.save_csv(path)
        >>> open(path).readline().strip()
        't [s],q1 [rad],q2 [rad],qd1 [rad/s],qd2 [rad/s],qdd1 [rad/s^2],qdd2 [rad/s^2]'
        >>> back = Trajectory.load_csv(path)
        >>> bool(np.array_equal(back.q, traj.q))
        True
        """
        path = check_path(path)
        blocks = [self.t[:, None], self.q, self.qd, self.qdd]
        if self.poses is not None:
            from ..quaternion import quaternion_from_matrix

            blocks += [self.poses[:, :3, 3], quaternion_from_matrix(self.poses[:, :3, :3])]
        table = np.concatenate(blocks, axis=1)
        lines = [",".join(self.columns())]
        lines += [",".join(repr(float(x)) for x in row) for row in table]
        write_atomically(path, "\n".join(lines) + "\n")

    @classmethod
    def load_csv(cls, path):
        """Read a trajectory written by :meth:`save_csv`.

        Raises
        ------
        ValueError
            Naming the file and the line: an empty file, bytes that are not UTF-8 text,
            a file larger than :data:`MAX_CSV_BYTES`, a header that is not the one
            :meth:`save_csv` writes, a row with the wrong
            number of values, a value that is not a finite number, instants that do not
            increase, or a last line without its line end (a truncated file, even if the
            cut fell inside the last number).

        Examples
        --------
        >>> import tempfile, os
        >>> path = os.path.join(tempfile.mkdtemp(), "bad.csv")
        >>> with open(path, "w") as f:
        ...     _ = f.write("t [s],q1 [rad],qd1 [rad/s],qdd1 [rad/s^2]\\n0,0,0,0\\n0.1,0.2,0")
        >>> Trajectory.load_csv(path)
        Traceback (most recent call last):
        ...
        ValueError: .../bad.csv, line 3: expected 4 values, got 3 (truncated or corrupt row)
        """
        path = check_path(path)
        raw = read_bytes(path, max_bytes=MAX_CSV_BYTES, what="trajectory file")
        lines = []
        for number, line in enumerate(raw.split(b"\n"), start=1):
            try:
                lines.append(line.decode("utf-8").rstrip("\r"))
            except UnicodeDecodeError as exc:
                raise ValueError(f"{path}, line {number}: byte {line[exc.start]:#04x} at "
                                 f"column {exc.start + 1} is not UTF-8 text (a binary or "
                                 f"damaged file?)") from None
        ends_with_newline = raw.endswith(b"\n")
        if ends_with_newline:
            lines.pop()
        if not lines or not lines[0].strip():
            raise ValueError(f"{path}, line 1: empty file, expected the header line")
        header = [c.strip() for c in lines[0].split(",")]
        with_poses = header[-len(_POSE_COLUMNS):] == list(_POSE_COLUMNS)
        k = len(header) - 1 - (len(_POSE_COLUMNS) if with_poses else 0)
        n = k // 3
        expected = Trajectory(t=[0.0], q=np.zeros((1, max(n, 1))), qd=np.zeros((1, max(n, 1))),
                              qdd=np.zeros((1, max(n, 1))),
                              poses=np.eye(4)[None] if with_poses else None).columns()
        if n == 0 or k % 3 or header != expected:
            raise ValueError(f"{path}, line 1: header {short_repr(lines[0])} is not a "
                             f"trajectory header (expected 't [s],q1 [rad],...')")
        rows = []
        for number, line in enumerate(lines[1:], start=2):
            if not line.strip():
                if all(not rest.strip() for rest in lines[number - 1:]):
                    break                                   # trailing blank lines
                raise ValueError(f"{path}, line {number}: empty line inside the table")
            fields = line.split(",")
            if len(fields) != len(header):
                raise ValueError(f"{path}, line {number}: expected {len(header)} values, got "
                                 f"{len(fields)} (truncated or corrupt row)")
            try:
                values = [float(x) for x in fields]
            except ValueError:
                raise ValueError(f"{path}, line {number}: a value is not a number: "
                                 f"{short_repr(line)}") from None
            if not np.all(np.isfinite(values)):
                raise ValueError(f"{path}, line {number}: NaN or infinity in "
                                 f"{short_repr(line)}")
            if rows and values[0] <= rows[-1][0]:
                raise ValueError(f"{path}, line {number}: time {values[0]!r} does not "
                                 f"increase (previous {rows[-1][0]!r})")
            rows.append(values)
        if not rows:
            raise ValueError(f"{path}, line 2: no data rows after the header")
        if not ends_with_newline:
            raise ValueError(f"{path}, line {len(lines)}: the last line has no line end: the "
                             f"file is truncated (its last value may be cut)")
        table = np.array(rows)
        poses = None
        if with_poses:
            from ..quaternion import matrix_from_quaternion

            p, quat = table[:, 1 + 3 * n:4 + 3 * n], table[:, 4 + 3 * n:]
            bad = np.abs(np.linalg.norm(quat, axis=1) - 1.0) > 1e-9
            if np.any(bad):
                raise ValueError(f"{path}, line {int(np.argmax(bad)) + 2}: the orientation "
                                 f"quaternion is not unit")
            poses = np.zeros((len(rows), 4, 4))
            poses[:, :3, :3] = matrix_from_quaternion(quat)
            poses[:, :3, 3] = p
            poses[:, 3, 3] = 1.0
        return cls(t=table[:, 0], q=table[:, 1:1 + n], qd=table[:, 1 + n:1 + 2 * n],
                   qdd=table[:, 1 + 2 * n:1 + 3 * n], poses=poses)


def _joint_limits(value, name, n):
    if value is None:
        return None
    if is_boolean(value):
        raise TypeError(f"{name} must be numbers, got booleans {short_repr(value)}")
    a = as_float_array(value, name)
    if a.ndim > 1 or (a.ndim == 1 and a.size != n):
        raise ValueError(f"{name} must be a number or have shape ({n},), got {a.shape}")
    if np.any(a <= 0):
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return np.broadcast_to(a, (n,))


def _unit_law(law, duration):
    if law == "cubic":
        return time_laws.cubic(duration)
    if law == "quintic":
        return time_laws.quintic(duration)
    return time_laws.trapezoidal(1.0, duration=duration)


def joint_trajectory(q_start, q_goal, *, duration=None, v_max=None, a_max=None,
                     law="quintic", dt=0.005):
    r"""A rest-to-rest motion between two configurations, all joints synchronised.

    .. math::

        q(t) = q_A + s(t)\,\Delta q, \quad \dot q = \dot s\,\Delta q, \quad
        \ddot q = \ddot s\,\Delta q, \qquad \Delta q = q_B - q_A,

    with one normalised law :math:`s: 0 \to 1`. Without ``duration`` the shortest law that
    keeps every joint within ``v_max`` and ``a_max`` is used: the joint with the largest
    :math:`|\Delta q_i| / v_{max,i}` (or :math:`/a_{max,i}`) sets the pace, the others
    move proportionally slower. For the cubic and quintic laws, with peak factors
    :math:`c_v, c_a` (1.5 and 6; 1.875 and :math:`10/\sqrt3`),
    :math:`T = \max\bigl(c_v \max_i \frac{|\Delta q_i|}{v_{max,i}},
    \sqrt{c_a \max_i \frac{|\Delta q_i|}{a_{max,i}}}\bigr)`; the trapezoidal law is
    :func:`~dqlab.trajectory.time_laws.trapezoidal` with the normalised limits
    :math:`\min_i v_{max,i}/|\Delta q_i|` and :math:`\min_i a_{max,i}/|\Delta q_i|`.

    Parameters
    ----------
    q_start, q_goal : array_like, shape (n,)
        Start and goal configurations.
    duration : float, optional
        :math:`T` in seconds. With limits as well, they are checked.
    v_max, a_max : float or array_like (n,), optional
        Joint speed and acceleration limits (rad/s, rad/s^2).
    law : {"quintic", "cubic", "trapezoidal"}
        The normalised law. With a duration, the trapezoid accelerates for a third of it.
    dt : float
        Sampling period in seconds; the last instant is the duration itself.

    Returns
    -------
    Trajectory

    Raises
    ------
    ValueError
        On NaN, mismatched shapes, a bad law name, ``dt <= 0``, no duration and not enough
        limits, or a duration too short for the limits.

    Examples
    --------
    >>> import numpy as np
    >>> traj = joint_trajectory([0, 0, 0], [1.0, -2.0, 0.5], v_max=1.0, a_max=2.0,
    ...                         law="trapezoidal")
    >>> round(traj.duration, 6)                 # joint 2 sets the pace: 2/1 + 1/2
    2.5
    >>> np.abs(traj.qd).max(axis=0).round(6)
    array([0.5 , 1.  , 0.25])
    >>> joint_trajectory([0, 0], [1, 1], duration=1.0, v_max=1.0)
    Traceback (most recent call last):
    ...
    ValueError: duration 1 s is too short for v_max: joint 1 would reach 1.875 rad/s > 1
    """
    q_start = as_float_array(q_start, "q_start")
    q_goal = as_float_array(q_goal, "q_goal")
    if q_start.ndim != 1 or q_start.shape != q_goal.shape:
        raise ValueError(f"q_start and q_goal must have the same shape (n,), got "
                         f"{q_start.shape} and {q_goal.shape}")
    if not isinstance(law, str) or law not in _LAWS:
        raise ValueError(f"law must be one of {_LAWS}, got {law!r}")
    dt = check_scalar(dt, "dt", minimum=0, strict=True)
    n = q_start.size
    v_lim = _joint_limits(v_max, "v_max", n)
    a_lim = _joint_limits(a_max, "a_max", n)
    with np.errstate(over="ignore"):
        delta = q_goal - q_start
    if not np.isfinite(delta).all():
        raise ValueError("q_goal - q_start overflows: the joint values are too large")
    span = np.abs(delta)
    if duration is not None:
        unit = _unit_law(law, check_scalar(duration, "duration", minimum=0, strict=True))
    else:
        unit = _shortest_unit_law(law, span, v_lim, a_lim)
    for lim, peak, name, unit_name in ((v_lim, unit.peak_speed, "v_max", "rad/s"),
                                       (a_lim, unit.peak_acceleration, "a_max", "rad/s^2")):
        if lim is not None and duration is not None:
            need = peak * span
            over = need > lim * (1 + 1e-9)
            if np.any(over):
                i = int(np.argmax(over))
                raise ValueError(f"duration {unit.duration:g} s is too short for {name}: "
                                 f"joint {i + 1} would reach {need[i]:.6g} {unit_name} > "
                                 f"{lim[i]:.6g}")
    t, s, sd, sdd = unit.sample(dt)
    return Trajectory(t=t, q=q_start + s[:, None] * delta, qd=sd[:, None] * delta,
                      qdd=sdd[:, None] * delta)


def _shortest_unit_law(law, span, v_lim, a_lim):
    """The normalised law of the shortest motion over ``span`` within the limits."""
    if not np.any(span > 0):
        raise ValueError("q_start equals q_goal: give a duration to hold the pose")
    moving = span > 0
    with np.errstate(over="ignore", divide="ignore"):
        v_unit = None if v_lim is None else float(np.min(v_lim[moving] / span[moving]))
        a_unit = None if a_lim is None else float(np.min(a_lim[moving] / span[moving]))
    for value, name in ((v_unit, "v_max"), (a_unit, "a_max")):
        if value is not None and not 0.0 < value < math.inf:
            raise ValueError(f"{name} / |q_goal - q_start| = {value:g} is out of range: the "
                             f"limits and the distance differ too much (overflow)")
    if law == "trapezoidal":
        if v_unit is None or a_unit is None:
            raise ValueError("a trapezoidal law without duration needs v_max and a_max")
        return time_laws.trapezoidal(1.0, v_max=v_unit, a_max=a_unit)
    if v_unit is None and a_unit is None:
        raise ValueError("give a duration, or v_max and/or a_max")
    shape = _unit_law(law, 1.0)
    T = 0.0
    if v_unit is not None:
        T = max(T, shape.peak_speed / v_unit)
    if a_unit is not None:
        T = max(T, math.sqrt(shape.peak_acceleration / a_unit))
    if not T < math.inf:
        raise ValueError("the motion's duration overflows: the distance is too large for "
                         "the limits")
    return _unit_law(law, T)


def via_points(q_points, times, *, dt=0.005, method="spline"):
    r"""A motion through via-points at given instants, starting and ending at rest.

    ``method="spline"``: the clamped cubic spline, :math:`C^2` (continuous acceleration).
    On :math:`[t_k, t_{k+1}]`, with :math:`h_k = t_{k+1} - t_k`, the cubic Hermite segment
    between :math:`(q_k, \dot q_k)` and :math:`(q_{k+1}, \dot q_{k+1})`; the knot speeds
    solve the tridiagonal system that makes the acceleration continuous,

    .. math::

        \frac{\dot q_{k-1}}{h_{k-1}} + 2\Bigl(\frac1{h_{k-1}} + \frac1{h_k}\Bigr)\dot q_k
        + \frac{\dot q_{k+1}}{h_k}
        = 3\Bigl(\frac{q_k - q_{k-1}}{h_{k-1}^2} + \frac{q_{k+1} - q_k}{h_k^2}\Bigr),

    with :math:`\dot q_0 = \dot q_m = 0`. ``method="stop"``: a quintic rest-to-rest motion
    between consecutive points (the arm stops at every via-point).

    Parameters
    ----------
    q_points : array_like, shape (m, n)
        The configurations to pass through, m >= 2.
    times : array_like, shape (m,)
        When to pass through them, strictly increasing, starting at any instant.
    dt : float
        Sampling period in seconds.
    method : {"spline", "stop"}

    Returns
    -------
    Trajectory
        Passes through every via-point exactly (each knot instant is on the grid).

    Examples
    --------
    >>> import numpy as np
    >>> traj = via_points([[0.0], [1.0], [0.5]], [0.0, 1.0, 2.0], dt=0.5)
    >>> traj.q[:, 0].round(4)
    array([0.    , 0.4531, 1.    , 0.7969, 0.5   ])
    >>> traj.qd[[0, -1], 0]
    array([0., 0.])
    """
    Q = as_float_array(q_points, "q_points")
    if Q.ndim != 2 or Q.shape[0] < 2:
        raise ValueError(f"q_points must have shape (m, n) with m >= 2, got {Q.shape}")
    tk = as_float_array(times, "times")
    if tk.shape != (Q.shape[0],):
        raise ValueError(f"times must have shape ({Q.shape[0]},), got {tk.shape}")
    if np.any(np.diff(tk) <= 0):
        raise ValueError("times must increase strictly")
    if method not in ("spline", "stop"):
        raise ValueError(f"method must be 'spline' or 'stop', got {method!r}")
    dt = check_scalar(dt, "dt", minimum=0, strict=True)
    h = np.diff(tk)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        t, q, qd, qdd = _via_point_samples(Q, tk, h, dt, method)
    if not (np.isfinite(qd).all() and np.isfinite(qdd).all()):
        raise ValueError(f"times: via-points {h.min():g} s apart are too close for the motion "
                         f"between them (the speeds or accelerations overflow)")
    return Trajectory(t=t, q=q, qd=qd, qdd=qdd)


def _via_point_samples(Q, tk, h, dt, method):
    """The sampled motion of :func:`via_points`: ``(t, q, qd, qdd)``."""
    m = Q.shape[0]
    if method == "spline":
        V = np.zeros_like(Q)
        if m > 2:
            A = np.zeros((m - 2, m - 2))
            rhs = np.zeros((m - 2, Q.shape[1]))
            for j, k in enumerate(range(1, m - 1)):
                A[j, j] = 2.0 * (1.0 / h[k - 1] + 1.0 / h[k])
                if j > 0:
                    A[j, j - 1] = 1.0 / h[k - 1]
                if j < m - 3:
                    A[j, j + 1] = 1.0 / h[k]
                rhs[j] = 3.0 * ((Q[k] - Q[k - 1]) / h[k - 1] ** 2
                                + (Q[k + 1] - Q[k]) / h[k] ** 2)
            V[1:-1] = np.linalg.solve(A, rhs)
    ts, qs, qds, qdds = [], [], [], []
    for k in range(m - 1):
        local = time_laws.time_grid(h[k], dt)
        if k > 0:
            local = local[1:]                       # the knot belongs to the previous piece
        u = local / h[k]
        if method == "stop":
            law = time_laws.quintic(h[k])
            s, sd, sdd = law(local)
            d = Q[k + 1] - Q[k]
            q, qd, qdd = (Q[k] + s[:, None] * d, sd[:, None] * d, sdd[:, None] * d)
        else:
            # cubic Hermite basis on u in [0, 1]
            h00, h10, h01, h11 = (2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u,
                                  -2 * u**3 + 3 * u**2, u**3 - u**2)
            d00, d10, d01, d11 = (6 * u**2 - 6 * u, 3 * u**2 - 4 * u + 1,
                                  -6 * u**2 + 6 * u, 3 * u**2 - 2 * u)
            e00, e10, e01, e11 = 12 * u - 6, 6 * u - 4, -12 * u + 6, 6 * u - 2
            q0, q1, v0, v1 = Q[k], Q[k + 1], V[k] * h[k], V[k + 1] * h[k]
            q = h00[:, None] * q0 + h10[:, None] * v0 + h01[:, None] * q1 + h11[:, None] * v1
            qd = (d00[:, None] * q0 + d10[:, None] * v0 + d01[:, None] * q1
                  + d11[:, None] * v1) / h[k]
            qdd = (e00[:, None] * q0 + e10[:, None] * v0 + e01[:, None] * q1
                   + e11[:, None] * v1) / h[k] ** 2
        t = tk[k] + local
        t[-1] = tk[k + 1]                           # the knot itself, not a rounding of it
        ts.append(t)
        qs.append(q)
        qds.append(qd)
        qdds.append(qdd)
    return np.concatenate(ts), np.concatenate(qs), np.concatenate(qds), np.concatenate(qdds)
