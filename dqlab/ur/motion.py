r"""How a UR controller executes ``movej``, ``movel``, ``servoj`` and ``stopj``: the motion laws.

This is the one planner of :mod:`dqlab.ur`. The safety checks of :mod:`dqlab.ur.script` check
the motions planned here, the in-process kinematic arm
(:class:`dqlab.ur.kinematic_arm.KinematicBackend`, hence the controller stand-in) executes
them, and so does the MuJoCo back end
(:class:`dqlab.sim.backend.MujocoBackend`) as its reference: what is checked is what runs.

Every motion is a **joint path** :math:`q(\sigma)` followed along its parameter
:math:`\sigma \in [0, D]` by a **time law** :math:`\sigma(t)`
(:class:`dqlab.trajectory.time_laws.TimeLaw`):

.. math::

    q(t) = q(\sigma(t)), \qquad
    \dot q = q'(\sigma)\,\dot\sigma, \qquad
    \ddot q = q''(\sigma)\,\dot\sigma^2 + q'(\sigma)\,\ddot\sigma .

``movej(q, a, v, t)``
    The straight joint-space line :math:`q(\sigma) = q_0 + \sigma\,\Delta q / D` with
    :math:`D = \max_i |\Delta q_i|`, the distance of the leading joint, so that
    :math:`|q_i'| \le 1`; the law is the trapezoid of :func:`move_law` on :math:`D`. Every
    joint follows the leading joint's law scaled to its own distance: all start and stop
    together.
``movel(pose, a, v, t)``
    The TCP on the straight line to ``pose`` with its orientation by SLERP
    (:func:`dqlab.trajectory.cartesian.line_slerp`), :math:`\sigma` its length in metres (or its
    rotation angle in radians for a pure rotation); the joints at knots every millimetre
    and milliradian by the closed-form inverse kinematics with branch tracking
    (:func:`dqlab.trajectory.follow.follow_path_ur`), with their slopes
    :math:`q' = J^{-1}\,\mathrm d X / \mathrm d\sigma`, and between knots the cubic Hermite
    curve through them (continuous slope); the trapezoid of :func:`move_law` on the length.
``servoj(q, t)``
    The joint line to ``q`` at constant speed :math:`\Delta q / t`.
``stopj(a)``
    From the current speed :math:`\dot q_0`, every joint decelerates along its direction of
    motion, the fastest at ``a``: :math:`q = q_0 + \dot q_0 \tau - \tfrac12 (\dot q_0 / T)
    \tau^2` until :math:`T = \max_i |\dot q_{0,i}| / a`.

**The time law** of ``movej`` and ``movel`` (:func:`move_law`): the rest-to-rest trapezoid
that accelerates at ``a`` to the cruise speed ``v`` and brakes at ``a``
(:func:`dqlab.trajectory.time_laws.trapezoidal`; a triangle when ``v`` is not reached). With a time
``t > 0`` the time has priority, as in URScript: the trapezoid of duration ``t`` that
accelerates at ``a`` when ``a`` can cover the distance in ``t``
(:math:`a \ge 4D/t^2`), else the triangle of duration ``t`` (acceleration
:math:`4D/t^2`); ``v`` is not used. Blend radii ``r`` are not executed (moves stop at their
targets).

**Peaks.** :meth:`Motion.peak_joint_speed` and :meth:`Motion.peak_joint_acceleration`
bound the speeds and accelerations of the motion over its whole duration: exactly for the
joint lines of ``movej``, ``servoj`` and ``stopj`` (:math:`|\dot q_i| = |q_i'|\,|\dot
\sigma|`); for ``movel`` by :math:`\max|q_i'|\,\max|\dot\sigma|` and
:math:`\max|q_i''|\max\dot\sigma^2 + \max|q_i'|\max|\ddot\sigma|`, the extremes of each
Hermite piece taken exactly. A sampled motion can therefore never show more than these.
The motions start and end at rest except ``servoj``, which ends at its constant speed (and
``stopj``, which starts at the current one); a chain of ``servoj`` changes speed at its
targets, and the acceleration of such a chain is that of its samples,
:math:`(v_k - v_{k-1}) / \tfrac12(t_k + t_{k-1})` (see
:func:`dqlab.ur.script.check_joint_targets`).

**Frames.** A UR pose vector ``[x, y, z, rx, ry, rz]`` is the TCP pose in the controller's
base frame, which is DH frame 0 of the robot (ROS's ``base`` frame; ROS's ``base_link`` is
the same frame turned by :math:`\pi` about z). A :class:`~dqlab.robot.Robot` places frame 0
in the world W by ``robot.base`` (:math:`X_{W0}`) and its TCP by ``robot.tool``
(:math:`X_{nT}`): the controller's pose of the TCP is :math:`X_{0T} = X_{W0}^{-1} X_{WT}`
(:func:`controller_pose`), and a pose vector ``p`` is the world pose
:math:`X_{W0}\,X(p)` (:func:`world_transform`).
"""

import bisect
import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .._checks import as_float_array, check_scalar
from ..quaternion import quaternion_distance, quaternion_from_matrix
from ..trajectory import TimeLaw, follow_path_ur, joint_velocities, line_slerp, trapezoidal
from ..transforms import transform_inverse
from .poses import pose_from_transform, transform_from_pose

__all__ = [
    "MOVEJ_A", "MOVEJ_V", "MOVEL_A", "MOVEL_V", "SERVOJ_T", "LOOKAHEAD_TIME", "GAIN",
    "STOPJ_A", "MAX_DURATION", "move_law", "LinePath", "SplinePath", "Motion", "Timeline",
    "plan_movej", "plan_movel", "plan_servoj", "plan_stop", "plan_hold", "controller_pose",
    "world_transform",
]

# URScript's default arguments, the one place they are written (URScript manual, module
# "motion"; servoj's t is the CB3 controller's period, 8 ms).
#: ``movej``: acceleration of the leading joint, rad/s^2.
MOVEJ_A = 1.4
#: ``movej``: speed of the leading joint, rad/s.
MOVEJ_V = 1.05
#: ``movel``: TCP acceleration, m/s^2.
MOVEL_A = 1.2
#: ``movel``: TCP speed, m/s.
MOVEL_V = 0.25
#: ``servoj``: how long a target controls the arm, s.
SERVOJ_T = 0.008
#: ``servoj``: look-ahead time, s.
LOOKAHEAD_TIME = 0.1
#: ``servoj``: proportional gain.
GAIN = 300.0
#: ``stopj``: deceleration of the fastest joint, rad/s^2.
STOPJ_A = 2.0

#: Knot spacing of a ``movel`` path: one knot per millimetre of travel and per milliradian
#: of rotation (at least :data:`_MIN_KNOTS` pieces). The Hermite curve between knots then
#: stays on the line to about 1e-12 m on a UR3.
_KNOT_LENGTH = 1e-3
_KNOT_ANGLE = 1e-3
_MIN_KNOTS = 8
#: Below this translation (m) a ``movel`` is a pure rotation, timed on its angle.
_PURE_ROTATION = 1e-9
#: The most samples :meth:`Motion.samples` takes of one motion.
_MAX_SAMPLES = 10_000_000
#: The longest motion planned, s (about 11 days): beyond, the spacing of floats near the
#: end time exceeds a microsecond, and the motion is a mistake anyway.
MAX_DURATION = 1e6


def _uniform_law():
    """The law :math:`s = t` on :math:`[0, 1]` (a path parameter, not a rest-to-rest law)."""
    return TimeLaw(np.array([0.0, 1.0]), np.array([[0.0, 1.0, 0.0, 0.0, 0.0, 0.0]]),
                   "uniform")


def move_law(distance, a, v, t=0.0):
    r"""The time law of a ``movej`` or ``movel`` over ``distance`` (see the module docstring).

    Parameters
    ----------
    distance : float
        :math:`D \ge 0`: the leading joint's travel (rad), or the TCP's (m).
    a, v : float
        Acceleration and cruise speed, > 0.
    t : float
        Duration, s (0: the shortest motion within ``a`` and ``v``).

    Returns
    -------
    TimeLaw or None
        :math:`\sigma(t)` from 0 to :math:`D` (None for :math:`D = 0`).

    Raises
    ------
    ValueError
        For a motion longer than :data:`MAX_DURATION`, or a ``t`` too short to be planned.

    Examples
    --------
    >>> law = move_law(3.0, 1.4, 1.05)
    >>> round(law.duration, 6), law.peak_speed
    (3.607143, 1.05)

    With ``t = 1`` the time has priority: 3 rad in 1 s needs a triangle accelerating at
    12 rad/s^2 and peaking at 6 rad/s (which the safety checks then refuse on a UR3):

    >>> law = move_law(3.0, 1.4, 1.05, t=1.0)
    >>> law.duration, round(law.peak_speed, 12), round(law.peak_acceleration, 9)
    (1.0, 6.0, 12.0)
    """
    distance, a, v, t = float(distance), float(a), float(v), float(t)
    if distance == 0.0:
        return None
    if t > 0.0:
        if t > MAX_DURATION:
            raise ValueError(f"t = {t!r} s is longer than {MAX_DURATION:g} s, the longest "
                             "motion planned")
        needed = 4.0 * distance / (t * t) if t * t > distance * 1e-300 else math.inf
        if not math.isfinite(needed):
            raise ValueError(f"t = {t!r} s is too short to move by {distance:.6g} (it would "
                             "take an infinite acceleration)")
        return trapezoidal(distance, duration=t, a_max=max(a, needed))
    try:
        duration = distance / v + v / a if distance * a >= v * v else 2.0 * math.sqrt(
            distance / a)
    except (ZeroDivisionError, OverflowError):
        duration = math.inf
    if not duration <= MAX_DURATION:
        raise ValueError(f"with v = {v!r} and a = {a!r} the move would last {duration:.3g} s,"
                         f" longer than {MAX_DURATION:g} s, the longest motion planned")
    return trapezoidal(distance, v_max=v, a_max=a)


# --------------------------------------------------------------------------------------
# Joint paths q(sigma)


class LinePath:
    r"""The joint line :math:`q(\sigma) = q_0 + \sigma\,(q_1 - q_0) / D`, :math:`\sigma \in
    [0, D]`, :math:`D = \max_i |q_{1,i} - q_{0,i}|` (0 for a point).

    Examples
    --------
    >>> path = LinePath([0.0, 0.0], [2.0, -1.0])
    >>> path.length, path.slope_bound().tolist()
    (2.0, [1.0, 0.5])
    """

    def __init__(self, q0, q1):
        self.q0 = np.array(q0, dtype=float)
        self.q1 = np.array(q1, dtype=float)
        delta = self.q1 - self.q0
        self.length = float(np.max(np.abs(delta))) if delta.size else 0.0
        self.direction = delta / self.length if self.length > 0.0 else np.zeros_like(delta)

    def __call__(self, sigma):
        r""":math:`(q, q', q'')` at the parameters ``sigma`` (shape (...) -> (..., n))."""
        sigma = np.asarray(sigma, dtype=float)[..., None]
        q = self.q0 + sigma * self.direction
        slope = np.broadcast_to(self.direction, q.shape)
        return q, slope, np.zeros_like(q)

    def slope_bound(self):
        r""":math:`\max_\sigma |q_i'(\sigma)|`, shape (n,)."""
        return np.abs(self.direction)

    def curvature_bound(self):
        r""":math:`\max_\sigma |q_i''(\sigma)|`, shape (n,)."""
        return np.zeros_like(self.direction)

    def joint_range(self):
        """Lowest and highest value of each joint along the path, shape (2, n)."""
        return np.stack([np.minimum(self.q0, self.q1), np.maximum(self.q0, self.q1)])


class SplinePath:
    r"""A joint path through knots :math:`(\sigma_k, q_k, q'_k)`, cubic Hermite between them.

    On piece :math:`k`, with :math:`h = \sigma_{k+1} - \sigma_k`, :math:`u = (\sigma -
    \sigma_k)/h` and :math:`\Delta = q_{k+1} - q_k`:

    .. math::

        q = q_k + c_1 u + c_2 u^2 + c_3 u^3, \quad c_1 = h q'_k, \quad
        c_2 = 3\Delta - h(2q'_k + q'_{k+1}), \quad c_3 = -2\Delta + h(q'_k + q'_{k+1}),

    so that :math:`q` and :math:`q'` are continuous. The extremes of :math:`q'` on a piece are
    at its ends or at :math:`u = -c_2 / 3c_3`, those of :math:`q''` (linear in :math:`u`) at
    its ends, those of :math:`q` at its ends or where :math:`q' = 0`.

    Parameters
    ----------
    sigma : array_like, shape (K,)
        Increasing knots, from 0.
    q, slope : array_like, shape (K, n)
        :math:`q_k` and :math:`q'_k = \mathrm dq / \mathrm d\sigma`.

    Examples
    --------
    >>> path = SplinePath([0.0, 1.0], [[0.0], [1.0]], [[0.0], [0.0]])
    >>> [float(x[0, 0]) for x in path([0.5])]       # 3 u^2 - 2 u^3 at u = 1/2
    [0.5, 1.5, 0.0]
    >>> path.slope_bound(), path.curvature_bound()
    (array([1.5]), array([6.]))
    """

    def __init__(self, sigma, q, slope):
        self.sigma = np.array(sigma, dtype=float)
        self.q = np.array(q, dtype=float)
        self.slope = np.array(slope, dtype=float)
        self.length = float(self.sigma[-1])
        h = np.diff(self.sigma)[:, None]
        delta = np.diff(self.q, axis=0)
        m0, m1 = self.slope[:-1], self.slope[1:]
        self._h = h
        self._c = (h * m0, 3.0 * delta - h * (2.0 * m0 + m1), -2.0 * delta + h * (m0 + m1))

    def __call__(self, sigma):
        r""":math:`(q, q', q'')` at the parameters ``sigma`` (shape (...) -> (..., n))."""
        sigma = np.clip(np.asarray(sigma, dtype=float), 0.0, self.length)
        k = np.clip(np.searchsorted(self.sigma, sigma, side="right") - 1, 0,
                    len(self.sigma) - 2)
        h = self._h[k]
        u = ((sigma - self.sigma[k])[..., None]) / h
        c1, c2, c3 = (c[k] for c in self._c)
        q = self.q[k] + u * (c1 + u * (c2 + u * c3))
        slope = (c1 + u * (2.0 * c2 + 3.0 * u * c3)) / h
        curvature = (2.0 * c2 + 6.0 * u * c3) / (h * h)
        return q, slope, curvature

    def _vertex(self):
        """``u = -c2 / 3 c3`` where it lies inside a piece, else NaN, shape (K-1, n)."""
        _, c2, c3 = self._c
        with np.errstate(divide="ignore", invalid="ignore"):
            u = -c2 / (3.0 * c3)
        return np.where((u > 0.0) & (u < 1.0), u, np.nan)

    def piece_slopes(self):
        r""":math:`\max |q_i'|` on each piece (exact), shape (K-1, n)."""
        c1, c2, c3 = self._c
        u = self._vertex()
        inner = np.abs(c1 + u * (2.0 * c2 + 3.0 * u * c3)) / self._h
        ends = np.maximum(np.abs(self.slope[:-1]), np.abs(self.slope[1:]))
        return np.maximum(ends, np.where(np.isnan(inner), 0.0, inner))

    def piece_curvatures(self):
        r""":math:`\max |q_i''|` on each piece (exact: it is linear there), shape (K-1, n)."""
        _, c2, c3 = self._c
        return np.maximum(np.abs(2.0 * c2), np.abs(2.0 * c2 + 6.0 * c3)) / (self._h * self._h)

    def slope_bound(self):
        r""":math:`\max_\sigma |q_i'(\sigma)|` (exact), shape (n,)."""
        return np.max(self.piece_slopes(), axis=0)

    def curvature_bound(self):
        r""":math:`\max_\sigma |q_i''(\sigma)|` (exact), shape (n,)."""
        return np.max(self.piece_curvatures(), axis=0)

    def joint_range(self):
        """Lowest and highest value of each joint along the path (exact), shape (2, n)."""
        c1, c2, c3 = self._c
        lo, hi = np.min(self.q, axis=0), np.max(self.q, axis=0)
        # q' = 0 on a piece: c1 + 2 c2 u + 3 c3 u^2 = 0
        A, B, C = 3.0 * c3, 2.0 * c2, c1
        disc = B * B - 4.0 * A * C
        with np.errstate(divide="ignore", invalid="ignore"):
            root = np.sqrt(np.where(disc >= 0.0, disc, np.nan))
            roots = [np.where(np.abs(A) > 0.0, (-B + s * root) / (2.0 * A),
                              np.where(np.abs(B) > 0.0, -C / B, np.nan)) for s in (1.0, -1.0)]
        for u in roots:
            inside = (u > 0.0) & (u < 1.0)
            value = np.where(inside, self.q[:-1] + u * (c1 + u * (c2 + u * c3)), np.nan)
            if inside.any():
                lo = np.minimum(lo, np.nanmin(np.where(inside, value, np.inf), axis=0))
                hi = np.maximum(hi, np.nanmax(np.where(inside, value, -np.inf), axis=0))
        return np.stack([lo, hi])


# --------------------------------------------------------------------------------------
# Motions


@dataclass(frozen=True)
class Motion:
    r"""One planned motion: a joint path followed by a time law, for ``duration`` seconds.

    Attributes
    ----------
    command : str
        ``"movej"``, ``"movel"``, ``"servoj"``, ``"stopj"`` or ``"hold"``.
    path : LinePath or SplinePath
        :math:`q(\sigma)`.
    law : TimeLaw or None
        :math:`\sigma(t)` (None: the arm holds ``path``'s start for ``duration``).
    duration : float
        s.
    tcp_distance : float
        For ``movel``: the length of the TCP's line, m, or its rotation angle, rad, when it
        does not move (``tcp_unit`` says which); 0 otherwise.
    tcp_unit : str
        ``"m"`` or ``"rad"``.
    """

    command: str
    path: object
    law: object
    duration: float
    tcp_distance: float = 0.0
    tcp_unit: str = "m"

    @cached_property
    def q_start(self):
        """Joints at the start, shape (n,)."""
        return self.path(0.0)[0]

    @cached_property
    def q_end(self):
        """Joints at the end, shape (n,) (exactly the target of a move)."""
        return self.path.q1.copy() if isinstance(self.path, LinePath) else self.path.q[-1].copy()

    @property
    def qd_start(self):
        """Joint speeds at the start (zero except for ``servoj`` and ``stopj``)."""
        if self.law is None:
            return np.zeros_like(self.q_start)
        h = float(self.law.breaks[1] - self.law.breaks[0])
        return self.path(0.0)[1] * float(self.law.coefficients[0, 1] / h)   # u = t / h

    @property
    def qd_end(self):
        """Joint speeds just before the end (zero except for ``servoj``)."""
        if self.law is None or self.command != "servoj":
            return np.zeros_like(self.q_start)
        c = self.law.coefficients[-1]                       # in the local time u, at u = 1
        h = float(self.law.breaks[-1] - self.law.breaks[-2])
        speed = (c[1] + 2.0 * c[2] + 3.0 * c[3] + 4.0 * c[4] + 5.0 * c[5]) / h
        return self.path(self.path.length)[1] * float(speed)

    def at(self, t):
        r"""``(q, qd, qdd)`` at the times ``t`` since the start (shape (...) -> (..., n)).

        Before the start the arm is at ``q_start``, from ``duration`` on at ``q_end``, at
        rest.
        """
        t = np.asarray(t, dtype=float)
        n = self.q_start.size
        if self.law is None:
            q = np.broadcast_to(self.q_start, t.shape + (n,)).copy()
            return q, np.zeros_like(q), np.zeros_like(q)
        inside = (t >= 0.0) & (t < self.duration)
        sigma, sd, sdd = _law_values(self.law, np.clip(t, 0.0, self.duration))
        q, slope, curvature = self.path(sigma)
        sd, sdd = sd[..., None], sdd[..., None]
        qd = slope * sd
        qdd = curvature * sd * sd + slope * sdd
        q = np.where((t >= self.duration)[..., None], self.q_end, q)
        keep = inside[..., None]
        return q, np.where(keep, qd, 0.0), np.where(keep, qdd, 0.0)

    def samples(self, period=SERVOJ_T):
        r"""The motion sampled for the checks that cannot be bounded in closed form (the
        joint torques): ``(t, q, qd, qdd)`` at steps of at most ``period`` within each
        segment of the time law, both ends of every segment included -- so at a break of the
        law, where the acceleration jumps, on either side of it (two samples at one time).

        Parameters
        ----------
        period : float
            Longest step, s (default the servo period, :data:`SERVOJ_T`).

        Returns
        -------
        t : ndarray, shape (N,)
            Times since the start of the motion, s (one sample at rest for a motion without
            a law: a hold).
        q, qd, qdd : ndarray, shape (N, n)

        Examples
        --------
        The trapezoid of a ``movej`` over 1 rad at 1 rad/s^2 up to 0.5 rad/s: 0.5 s of
        acceleration, 1.5 s of cruise, 0.5 s of braking; at its two breaks the accelerations
        of either side:

        >>> m = plan_movej([0.0, 0.0], [1.0, 0.0], a=1.0, v=0.5)
        >>> t, q, qd, qdd = m.samples(period=0.5)
        >>> t.tolist()
        [0.0, 0.5, 0.5, 1.0, 1.5, 2.0, 2.0, 2.5]
        >>> qdd[:, 0].tolist()
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0, -1.0]
        """
        period = check_scalar(period, "period", minimum=0.0, strict=True)
        if self.law is None:
            q = self.q_start[None, :]
            return np.zeros(1), q, np.zeros_like(q), np.zeros_like(q)
        law = self.law
        h = np.diff(law.breaks)
        steps = np.ceil(h / period)
        if not steps.sum() <= _MAX_SAMPLES:
            raise ValueError(f"period = {period!r} s would sample the {self.duration:.6g} s "
                             f"motion {steps.sum():.3g} times (at most {_MAX_SAMPLES:g}): "
                             "give a longer period")
        counts = np.maximum(steps.astype(int), 1)
        k = np.repeat(np.arange(len(h)), counts + 1)                 # the segment of each sample
        u = np.concatenate([np.linspace(0.0, 1.0, c + 1) for c in counts])
        sigma, sd, sdd = _law_values(law, k=k, u=u)
        q, slope, curvature = self.path(sigma)
        sd, sdd = sd[:, None], sdd[:, None]
        return (law.breaks[k] + u * h[k], q, slope * sd, curvature * sd * sd + slope * sdd)

    def peak_joint_speed(self):
        r"""Bound on :math:`|\dot q_i|` over the motion, rad/s, shape (n,) (see the module
        docstring)."""
        if self.law is None:
            return np.zeros_like(self.q_start)
        pieces = self._piece_law()
        if pieces is None:
            return self.path.slope_bound() * self._peaks[0]
        speed2, _ = pieces
        return np.max(self.path.piece_slopes() * np.sqrt(speed2)[:, None], axis=0)

    def peak_joint_acceleration(self):
        r"""Bound on :math:`|\ddot q_i|` over the motion (inside it: not the speed change at
        a ``servoj``'s ends), rad/s^2, shape (n,)."""
        if self.law is None:
            return np.zeros_like(self.q_start)
        pieces = self._piece_law()
        if pieces is None:
            v, a = self._peaks
            return self.path.curvature_bound() * v * v + self.path.slope_bound() * a
        speed2, accel = pieces
        return np.max(self.path.piece_curvatures() * speed2[:, None]
                      + self.path.piece_slopes() * accel[:, None], axis=0)

    @cached_property
    def _peaks(self):
        return _law_peaks(self.law)

    def _piece_law(self):
        r"""On each piece of a :class:`SplinePath`, :math:`\max \dot\sigma^2` and
        :math:`\max |\ddot\sigma|`, or None (a joint line, or a law that is not piecewise
        quadratic).

        On a segment of the law where :math:`\ddot\sigma` is a constant :math:`\alpha_j`,
        :math:`\dot\sigma^2 = \dot\sigma_j^2 + 2\alpha_j(\sigma - \sigma_j)` is linear in
        :math:`\sigma`: over all segments it is piecewise linear, with its maxima on a piece
        at the piece's ends or at a segment boundary inside it.
        """
        if not isinstance(self.path, SplinePath):
            return None
        law = self.law
        c = law.coefficients                    # in the local time u = (t - t_k) / h_k
        if np.any(c[:, 3:] != 0.0):
            return None
        h = np.diff(law.breaks)
        s_knots = np.append(c[:, 0], law.distance)          # sigma at the segments' ends
        v_last = (c[-1, 1] + 2.0 * c[-1, 2]) / h[-1]
        speed2_knots = np.append(c[:, 1] / h, v_last) ** 2
        sigma = self.path.sigma
        a_seg = np.abs(2.0 * c[:, 2]) / h ** 2
        lo, hi = sigma[:-1], sigma[1:]
        speed2 = np.maximum(np.interp(lo, s_knots, speed2_knots),
                            np.interp(hi, s_knots, speed2_knots))
        accel = np.zeros_like(lo)
        for j in range(len(a_seg)):             # the law's segments overlapping each piece
            overlap = (lo <= s_knots[j + 1]) & (hi >= s_knots[j])
            accel = np.where(overlap, np.maximum(accel, a_seg[j]), accel)
            inside = (lo < s_knots[j]) & (s_knots[j] < hi)
            speed2 = np.where(inside, np.maximum(speed2, speed2_knots[j]), speed2)
        return speed2 * (1.0 + 1e-12), accel

    def joint_range(self):
        """Lowest and highest value of each joint during the motion, shape (2, n)."""
        return self.path.joint_range()

    @property
    def tcp_peak_speed(self):
        """Peak TCP speed along a ``movel``'s line (m/s, or rad/s for a pure rotation)."""
        return 0.0 if self.law is None or not self.tcp_distance else self._peaks[0]

    @property
    def tcp_peak_acceleration(self):
        """Peak TCP acceleration along a ``movel``'s line (m/s^2, or rad/s^2)."""
        return 0.0 if self.law is None or not self.tcp_distance else self._peaks[1]


def _law_values(law, t=None, *, k=None, u=None):
    r""":math:`(\sigma, \dot\sigma, \ddot\sigma)` of a
    :class:`~dqlab.trajectory.time_laws.TimeLaw` at the times ``t`` in :math:`[0, T]`, in one
    pass (Horner's rule in the local time :math:`u` of each time's segment, the derivatives
    divided by :math:`h_k` and :math:`h_k^2`): the values of ``law(t)``, several times faster
    for one instant (the kinematic arm reads one per state; tested equal to ``law(t)``).
    Given the segments ``k`` and local times ``u`` instead of ``t``, the values of those
    segments' polynomials there (at a break, either side of it)."""
    c = law.coefficients
    if k is None:
        k = np.clip(np.searchsorted(law.breaks, t, side="right") - 1, 0, len(c) - 1)
    h = law.breaks[k + 1] - law.breaks[k]
    if u is None:
        u = (t - law.breaks[k]) / h
    c0, c1, c2, c3, c4, c5 = (c[k, j] for j in range(6))
    sigma = c0 + u * (c1 + u * (c2 + u * (c3 + u * (c4 + u * c5))))
    sd = (c1 + u * (2.0 * c2 + u * (3.0 * c3 + u * (4.0 * c4 + u * 5.0 * c5)))) / h
    sdd = (2.0 * c2 + u * (6.0 * c3 + u * (12.0 * c4 + u * 20.0 * c5))) / h / h
    return sigma, sd, sdd


def _law_peaks(law):
    r"""``(law.peak_speed, law.peak_acceleration)``; for a piecewise-quadratic law (all the
    laws planned here) directly from its coefficients -- :math:`|\dot\sigma|` is largest at
    a segment's end, :math:`|\ddot\sigma| = 2|c_2| / h^2` -- rather than from polynomial
    roots (tested equal)."""
    c = law.coefficients                        # in the local time u = (t - t_k) / h_k
    if np.any(c[:, 3:] != 0.0):
        return law.peak_speed, law.peak_acceleration
    h = np.diff(law.breaks)
    speed = max(float(np.max(np.abs(c[:, 1]) / h)),
                float(np.max(np.abs(c[:, 1] + 2 * c[:, 2]) / h)))
    return speed, float(np.max(np.abs(2.0 * c[:, 2]) / h / h))


def _joints(q, name):
    q = as_float_array(q, name)
    if q.ndim != 1:
        raise ValueError(f"{name} must be one joint vector, got shape {q.shape}")
    return q


def plan_hold(q, duration=0.0):
    """The arm standing at ``q`` for ``duration`` seconds.

    Examples
    --------
    >>> plan_hold([0.0, 1.0], 2.0).at(1.0)[0]
    array([0., 1.])
    """
    q = _joints(q, "q")
    return Motion("hold", LinePath(q, q), None, float(duration))


def plan_movej(q_from, q, a=MOVEJ_A, v=MOVEJ_V, t=0.0):
    r"""The ``movej`` from ``q_from`` to ``q``: the joint line with :func:`move_law`.

    Parameters
    ----------
    q_from, q : array_like, shape (n,)
        Start and target joints, rad.
    a, v, t : float
        URScript's arguments (checked by :func:`dqlab.ur.script.movej`).

    Returns
    -------
    Motion

    Examples
    --------
    The issue with a given time: 3 rad in ``t = 1`` s peaks at 6 rad/s, not the average 3:

    >>> m = plan_movej([0.0] * 6, [3.0, 0, 0, 0, 0, 1.5], t=1.0)
    >>> m.peak_joint_speed().round(9).tolist()
    [6.0, 0.0, 0.0, 0.0, 0.0, 3.0]
    """
    path = LinePath(_joints(q_from, "q_from"), _joints(q, "q"))
    law = move_law(path.length, a, v, t)
    if law is None:
        return Motion("movej", path, None, float(t))
    return Motion("movej", path, law, law.duration)


def plan_servoj(q_from, q, t=SERVOJ_T):
    r"""One ``servoj``: the joint line to ``q`` at constant speed :math:`(q - q_{from})/t`.

    Examples
    --------
    >>> plan_servoj([0.0, 0.0], [0.01, -0.02], t=0.01).qd_end
    array([ 1., -2.])
    """
    path = LinePath(_joints(q_from, "q_from"), _joints(q, "q"))
    t = float(t)
    if not 0.0 < t <= MAX_DURATION:
        raise ValueError(f"t = {t!r} s must be > 0 and at most {MAX_DURATION:g} s")
    if path.length == 0.0:
        return Motion("servoj", path, None, t)
    speed = path.length / t if t > path.length * 1e-300 else math.inf
    if not math.isfinite(speed):
        raise ValueError(f"t = {t!r} s is too short to move by {path.length:.6g} (an "
                         "infinite speed)")
    law = TimeLaw(np.array([0.0, t]), np.array([[0.0, path.length, 0, 0, 0, 0]]),
                  "constant speed")        # coefficients in the local time u = tau / t
    return Motion("servoj", path, law, t)


def plan_stop(q, qd, a=STOPJ_A):
    r"""``stopj(a)`` from joints ``q`` moving at ``qd``: each joint brakes along its
    direction of motion, the fastest at ``a``, all stopping together.

    Examples
    --------
    >>> m = plan_stop([0.0, 0.0], [2.0, -1.0], a=4.0)
    >>> m.duration, m.q_end.tolist(), m.peak_joint_acceleration().tolist()
    (0.5, [0.5, -0.25], [4.0, 2.0])
    """
    q, qd = _joints(q, "q"), _joints(qd, "qd")
    speed = float(np.max(np.abs(qd))) if qd.size else 0.0
    if speed == 0.0:
        return plan_hold(q)
    a = float(a)
    T = speed / a if a > speed * 1e-300 else math.inf
    if not (T <= MAX_DURATION and a > 0.0):
        raise ValueError(f"a = {a!r}: braking from {speed:.6g} would take {T:.3g} s, longer "
                         f"than {MAX_DURATION:g} s")
    distance = 0.5 * speed * T
    law = TimeLaw(np.array([0.0, T]), np.array([[0.0, speed * T, -0.5 * a * T * T, 0, 0, 0]]),
                  "stop")                  # coefficients in the local time u = tau / T
    return Motion("stopj", LinePath(q, q + qd / speed * distance), law, T)


def controller_pose(robot, q):
    r"""The UR pose vector of the TCP in the controller's base frame (DH frame 0):
    :math:`X_{0T} = X_{W0}^{-1}\,X_{WT}(q)`.

    Parameters
    ----------
    robot : dqlab.robot.Robot
    q : array_like, shape (..., n)

    Returns
    -------
    ndarray, shape (..., 6)

    Examples
    --------
    An arm mounted 0.8 m up and turned a quarter turn about z reports the same pose as the
    arm on the floor:

    >>> import numpy as np
    >>> from dqlab import rot_z, transform_from
    >>> from dqlab.models import ur3
    >>> robot, mounted = ur3(), ur3()
    >>> mounted.base = transform_from(rot_z(np.pi / 2), [0.0, 0.0, 0.8])
    >>> q = [0.4, -1.3, 1.1, -1.2, -1.4, 0.6]
    >>> bool(np.allclose(controller_pose(mounted, q), controller_pose(robot, q), atol=1e-15))
    True
    """
    X_WT = robot.fk(q)
    if robot.base.tobytes() != np.eye(4).tobytes():
        X_WT = transform_inverse(robot.base) @ X_WT
    return pose_from_transform(X_WT)


def world_transform(robot, pose):
    r"""The world pose :math:`X_{WT} = X_{W0}\,X(p)` of a UR pose vector ``p`` given in the
    controller's base frame.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> robot.base = np.array([[1.0, 0, 0, 1.0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    >>> world_transform(robot, [0.2, 0, 0, 0, 0, 0])[:3, 3]
    array([1.2, 0. , 0. ])
    """
    X_0T = transform_from_pose(pose)
    with np.errstate(over="ignore", invalid="ignore"):
        X_WT = robot.base @ X_0T
    if not np.isfinite(X_WT).all():
        raise ValueError("pose is too far: its position in the world frame overflows a float")
    return X_WT


def plan_movel(robot, q_from, pose, a=MOVEL_A, v=MOVEL_V, t=0.0):
    r"""The ``movel`` from the joints ``q_from`` to a UR pose: see the module docstring.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm.
    q_from : array_like, shape (6,)
        Start joints, rad.
    pose : array_like, shape (6,)
        Target ``[x, y, z, rx, ry, rz]`` of the TCP in the controller's base frame.
    a, v, t : float
        URScript's arguments (m/s^2 and m/s; rad/s^2 and rad/s for a pure rotation).

    Returns
    -------
    Motion

    Raises
    ------
    ValueError
        If a point of the line has no inverse-kinematics solution, the tracked joints leave
        the joint limits, or the line crosses a singularity (the tracked branch would switch
        or jump).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> q0 = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])
    >>> goal = controller_pose(robot, q0) + [0.05, 0.0, -0.05, 0, 0, 0]
    >>> m = plan_movel(robot, q0, goal, v=0.1)
    >>> round(m.tcp_distance, 6), round(m.duration, 4), m.tcp_peak_speed
    (0.070711, 0.7904, 0.1)
    >>> bool(np.allclose(controller_pose(robot, m.q_end), goal, atol=1e-12))
    True
    """
    q_from = _joints(q_from, "q_from")
    X_A = robot.fk(q_from)
    X_B = world_transform(robot, pose)
    length = float(np.linalg.norm(X_B[:3, 3] - X_A[:3, 3]))
    angle = float(quaternion_distance(quaternion_from_matrix(X_A[:3, :3]),
                                      quaternion_from_matrix(X_B[:3, :3])))
    unit = "m" if length >= _PURE_ROTATION else "rad"
    distance = length if unit == "m" else angle
    if distance == 0.0:
        return Motion("movel", LinePath(q_from, q_from), None, float(t))
    law = move_law(distance, a, v, t)              # (an impossible law fails before the IK)
    pieces = max(_MIN_KNOTS, math.ceil(length / _KNOT_LENGTH), math.ceil(angle / _KNOT_ANGLE))
    geometry = line_slerp(X_A, X_B, law=_uniform_law(), dt=1.0 / pieces)
    trajectory, report = follow_path_ur(robot, geometry, q_start=q_from)
    if report.switches:
        raise ValueError(f"the line crosses a singularity or needs a jump of the joints "
                         f"({report.switches[0]})")
    q = trajectory.q.copy()
    if np.max(np.abs(q[0] - q_from)) > 1e-6:
        raise ValueError("the line starts at a singular configuration (the joints are not "
                         "determined by the pose)")
    q[0] = q_from
    # the slopes dq/dsigma = J^-1 dX/dsigma; the line's twist per unit of its parameter is
    # constant (the uniform law's end sample reports a law at rest, so it is read at 0)
    slope = joint_velocities(robot.jacobian(q), geometry.twist[0]) / distance
    path = SplinePath(geometry.t * distance, q, slope)
    return Motion("movel", path, law, law.duration, tcp_distance=distance, tcp_unit=unit)


# --------------------------------------------------------------------------------------
# Executing motions one after the other


class Timeline:
    r"""What a controller executes: motions one after the other from given start times.

    Before the first motion and after the last the arm stands still. :meth:`run` replaces
    the motions from an instant on (a new program), :meth:`state` samples the joints.

    Parameters
    ----------
    q : array_like, shape (n,)
        Where the arm stands.
    t : float
        From when, s.

    Examples
    --------
    >>> line = Timeline([0.0, 0.0])
    >>> line.run([plan_movej([0.0, 0.0], [1.0, 0.5], a=1.0, v=1.0)], now=2.0)
    >>> line.end_time
    4.0
    >>> [x.tolist() for x in line.state(2.5)]        # accelerating, 0.5 s after the start
    [[0.125, 0.0625], [0.5, 0.25], [1.0, 0.5]]
    """

    def __init__(self, q, t=0.0):
        self._starts = [float(t)]
        self._motions = [plan_hold(q)]

    @property
    def end_time(self):
        """When the last motion ends, s."""
        return self._starts[-1] + self._motions[-1].duration

    @property
    def motions(self):
        """The motions and their start times, as a list of ``(start, Motion)``."""
        return list(zip(self._starts, self._motions, strict=True))

    def run(self, motions, now):
        """Execute ``motions`` one after the other from ``now`` (what ran before is cut)."""
        motions = list(motions)
        if not motions:
            return
        starts = [float(now)]
        for m in motions[:-1]:
            starts.append(starts[-1] + m.duration)
        self._starts, self._motions = starts, motions

    def state(self, t):
        """``(q, qd, qdd)`` at the times ``t`` (shape (...) -> (..., n))."""
        t = np.asarray(t, dtype=float)
        if t.ndim == 0:                       # one instant (a state read): no masks
            i = max(bisect.bisect_right(self._starts, float(t)) - 1, 0)
            return self._motions[i].at(t - self._starts[i])
        k = np.clip(np.searchsorted(self._starts, t, side="right") - 1, 0, len(self._starts) - 1)
        n = self._motions[0].q_start.size
        q, qd, qdd = (np.empty(t.shape + (n,)) for _ in range(3))
        for i in np.unique(k):
            mask = k == i
            parts = self._motions[i].at(t[mask] - self._starts[i])
            for out, part in zip((q, qd, qdd), parts, strict=True):
                out[mask] = part
        return q, qd, qdd
