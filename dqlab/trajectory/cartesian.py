r"""Cartesian paths: where the tool should be, and how fast, at each instant.

- :func:`line_slerp` -- the tool point on a straight line, its orientation by SLERP;
- :func:`screw_path` -- the whole pose along one screw motion (ScLERP of dual quaternions);
- :func:`circle_three_phase` -- the UR3 report's circle with its three-phase speed law.

Each returns a :class:`CartesianPath`: instants, tool positions, linear velocities and
accelerations, and (when the orientation is given) unit quaternions and angular
velocities, all in the world frame. Chapter 11 of the book derives them.
"""

import math
from dataclasses import dataclass, replace

import numpy as np

from .._checks import as_float_array, check_scalar
from ..dualquat import (
    dual_quaternion_conjugate,
    dual_quaternion_from_transform,
    dual_quaternion_product,
    sclerp,
    screw_from_dual_quaternion,
    transform_from_dual_quaternion,
)
from ..quaternion import (
    axis_angle_from_quaternion,
    check_unit_quaternion,
    matrix_from_quaternion,
    quaternion_conjugate,
    quaternion_from_matrix,
    quaternion_product,
    slerp,
)
from ..rotations import check_rotation_matrix
from ..transforms import check_transform
from . import time_laws

__all__ = ["CartesianPath", "line_slerp", "screw_path", "circle_three_phase"]

_PLANES = {"xy": (0, 1, 2), "xz": (0, 2, 1), "yz": (1, 2, 0)}


@dataclass(frozen=True)
class CartesianPath:
    r"""A sampled tool path in the world frame.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Instants in seconds.
    position, velocity, acceleration : ndarray, shape (N, 3)
        Tool point :math:`p(t)`, :math:`\dot p(t)`, :math:`\ddot p(t)` (m, m/s, m/s^2).
    orientation : ndarray, shape (N, 4), optional
        Tool orientation as unit quaternions :math:`(w, x, y, z)`, when prescribed.
    angular_velocity : ndarray, shape (N, 3), optional
        :math:`\omega(t)` in the world frame (rad/s); zeros for a fixed orientation.
    s, sd, sdd : ndarray, shape (N,), optional
        The path parameter and its derivatives (the arc length for the circle, a
        normalised parameter for the line and the screw).
    law : TimeLaw, optional
        The time law that produced ``s``.
    """

    t: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    orientation: np.ndarray = None
    angular_velocity: np.ndarray = None
    s: np.ndarray = None
    sd: np.ndarray = None
    sdd: np.ndarray = None
    law: object = None

    def __post_init__(self):
        t = as_float_array(self.t, "t")
        if t.ndim != 1 or t.size == 0:
            raise ValueError(f"t must have shape (N,), got {t.shape}")
        N = t.size
        shapes = {"position": (N, 3), "velocity": (N, 3), "acceleration": (N, 3),
                  "orientation": (N, 4), "angular_velocity": (N, 3), "s": (N,), "sd": (N,),
                  "sdd": (N,)}
        object.__setattr__(self, "t", t)
        for name, shape in shapes.items():
            value = getattr(self, name)
            if value is None:
                if name in ("position", "velocity", "acceleration"):
                    raise ValueError(f"{name} is required: an array of shape {shape}")
                continue
            a = as_float_array(value, name)
            if a.shape != shape:
                raise ValueError(f"{name} must have shape {shape} (one row per instant of "
                                 f"t), got {a.shape}")
            object.__setattr__(self, name, a)
        if self.orientation is not None and self.angular_velocity is None:
            raise ValueError("an orientation needs its angular_velocity (zeros if fixed)")

    def __len__(self):
        return self.t.size

    @property
    def speed(self):
        r""":math:`\lVert \dot p \rVert`, shape (N,)."""
        return np.linalg.norm(self.velocity, axis=-1)

    @property
    def poses(self):
        """Tool poses :math:`X_{WT}(t)` as transforms, shape (N, 4, 4)."""
        if self.orientation is None:
            raise ValueError("this path has no orientation: use with_orientation(R) first")
        X = np.zeros((len(self), 4, 4))
        X[:, :3, :3] = matrix_from_quaternion(self.orientation)
        X[:, :3, 3] = self.position
        X[:, 3, 3] = 1.0
        return X

    @property
    def twist(self):
        r"""Spatial velocity :math:`(\dot p, \omega)`, shape (N, 6) (zeros for
        :math:`\omega` when no orientation is prescribed)."""
        w = np.zeros_like(self.velocity) if self.angular_velocity is None else \
            self.angular_velocity
        return np.concatenate([self.velocity, w], axis=-1)

    def with_orientation(self, rotation):
        r"""The same path with a fixed tool orientation.

        Parameters
        ----------
        rotation : array_like, shape (3, 3) or (4,)
            :math:`R_{WT}` as a rotation matrix or a unit quaternion.

        Returns
        -------
        CartesianPath
        """
        q = _orientation(rotation, "rotation")
        return replace(self, orientation=np.broadcast_to(q, (len(self), 4)).copy(),
                       angular_velocity=np.zeros((len(self), 3)))


def _orientation(rotation, name):
    r = as_float_array(rotation, name)
    if r.shape == (3, 3):
        return quaternion_from_matrix(check_rotation_matrix(r, name=name))
    if r.shape == (4,):
        return check_unit_quaternion(r, name=name)
    raise ValueError(f"{name} must be a (3, 3) matrix or a (4,) quaternion, got shape "
                     f"{r.shape}")


def _one_transform(X, name):
    X = check_transform(X, name=name)
    if X.shape != (4, 4):
        raise ValueError(f"{name} must be one (4, 4) transform, got shape {X.shape}")
    return X


#: The smallest normalised speed and acceleration of a line's time law (a normal float).
_TINY = 1e-300
#: How far from the origin a screw path's poses may be, metres: beyond, the rounding of a
#: unit dual quaternion's dual part (1e-16 of the distance) exceeds the unit checks' 1e-9.
MAX_SCREW_REACH = 1e6


def _within_screw_reach(X, name):
    distance = math.hypot(*X[:3, 3])
    if not distance <= MAX_SCREW_REACH:
        raise ValueError(f"{name} is {distance:.3g} m from the origin: too far for a screw "
                         f"path (at most {MAX_SCREW_REACH:g} m, where dual quaternions still "
                         "hold their unit norm to 1e-9)")
    return X


def _normalised_law(law, duration):
    if law is None:
        if duration is None:
            raise ValueError("give a duration or a normalised time law")
        return time_laws.quintic(check_scalar(duration, "duration", minimum=0, strict=True))
    if duration is not None:
        raise ValueError("give a duration or a law, not both (the law has its duration)")
    if not isinstance(law, time_laws.TimeLaw):
        raise TypeError(f"law must be a TimeLaw, got {type(law).__name__}")
    if abs(law.distance - 1.0) > 1e-12:
        raise ValueError(f"law must take s from 0 to 1, it ends at {law.distance:.12g}")
    return law


def line_slerp(X_A, X_B, *, duration=None, law=None, speed=None, acceleration=None,
               dt=0.005):
    r"""Straight line for the tool point, SLERP for its orientation.

    With :math:`s(t)` from 0 to 1 and :math:`q_B q_A^* = (\cos\frac\theta2,
    \sin\frac\theta2\,\mathbf u)` (shortest arc, :math:`\theta \le \pi`):

    .. math::

        p = p_A + s\,(p_B - p_A),\qquad q = (q_B q_A^*)^s\, q_A,\qquad
        \dot p = \dot s\,(p_B - p_A),\qquad \omega = \dot s\,\theta\,\mathbf u .

    The timing is given one of three ways: a ``duration`` (a quintic law), a normalised
    ``law``, or the tool's ``speed`` and ``acceleration`` along the line (metres per second
    and per second squared): the shortest trapezoidal law within both,
    :func:`~dqlab.trajectory.time_laws.trapezoidal` with :math:`v_{max} = V / L` and
    :math:`a_{max} = A / L` for the length :math:`L = \lVert p_B - p_A\rVert`, so that
    :math:`\lVert\dot p\rVert \le V` and :math:`\lVert\ddot p\rVert \le A`.

    Parameters
    ----------
    X_A, X_B : array_like, shape (4, 4)
        Start and end poses :math:`X_{WT}`.
    duration : float, optional
        Duration in seconds of a quintic law.
    law : TimeLaw, optional
        A normalised law (``distance`` 1).
    speed, acceleration : float, optional
        Largest tool speed (m/s) and acceleration (m/s^2) along the line, given together.
    dt : float
        Sampling period in seconds.

    Returns
    -------
    CartesianPath

    Raises
    ------
    ValueError
        If the poses are not rigid transforms, more or less than one timing is given, or a
        speed is given for a line of zero length (a turn on the spot: give a duration).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab import rot_z, transform_from
    >>> path = line_slerp(np.eye(4), transform_from(rot_z(np.pi / 2), [0.3, 0, 0]),
    ...                   duration=1.0, dt=0.5)
    >>> path.position[:, 0], path.angular_velocity[1].round(6)
    (array([0.  , 0.15, 0.3 ]), array([0.      , 0.      , 2.945243]))
    >>> path = line_slerp(np.eye(4), transform_from(np.eye(3), [0.3, 0, 0]), speed=0.25,
    ...                   acceleration=0.5, dt=0.01)
    >>> round(path.law.duration, 6), round(float(path.speed.max()), 6)     # 0.3/0.25 + 0.5
    (1.7, 0.25)
    """
    X_A = _one_transform(X_A, "X_A")
    X_B = _one_transform(X_B, "X_B")
    if speed is not None or acceleration is not None:
        if law is not None or duration is not None:
            raise ValueError("give a duration, a law, or a speed and an acceleration: one "
                             "timing, not several")
        law = _line_law(X_A, X_B, speed, acceleration)
    law = _normalised_law(law, duration)
    t, s, sd, sdd = law.sample(check_scalar(dt, "dt", minimum=0, strict=True))
    p_A, p_B = X_A[:3, 3], X_B[:3, 3]
    q_A, q_B = quaternion_from_matrix(X_A[:3, :3]), quaternion_from_matrix(X_B[:3, :3])
    if np.dot(q_A, q_B) < 0:
        q_B = -q_B
    axis, angle = axis_angle_from_quaternion(quaternion_product(q_B, quaternion_conjugate(q_A)))
    return CartesianPath(
        t=t, position=p_A + s[:, None] * (p_B - p_A), velocity=sd[:, None] * (p_B - p_A),
        acceleration=sdd[:, None] * (p_B - p_A), orientation=slerp(q_A, q_B, s),
        angular_velocity=(sd * angle)[:, None] * axis, s=s, sd=sd, sdd=sdd, law=law)


def _line_law(X_A, X_B, speed, acceleration):
    """The normalised trapezoid of a line of length L run within ``speed`` (m/s) and
    ``acceleration`` (m/s^2)."""
    if speed is None or acceleration is None:
        raise ValueError("give the speed and the acceleration together")
    V = check_scalar(speed, "speed", minimum=0, strict=True)
    A = check_scalar(acceleration, "acceleration", minimum=0, strict=True)
    L = math.hypot(*(X_B[:3, 3] - X_A[:3, 3]))            # no overflow for far poses
    if L == 0.0:
        raise ValueError("speed: the line has length 0 (a turn on the spot): give a duration")
    if not (V / L >= _TINY and A / L >= _TINY):
        raise ValueError(f"X_A and X_B are {L:.3g} m apart: too far for a speed of {V:g} m/s "
                         f"and an acceleration of {A:g} m/s^2 (the motion would last longer "
                         "than a float can count)")
    return time_laws.trapezoidal(1.0, v_max=V / L, a_max=A / L)


def screw_path(X_A, X_B, *, duration=None, law=None, dt=0.005):
    r"""The tool's pose along the screw motion from ``X_A`` to ``X_B`` (ScLERP).

    With :math:`D = Q_B Q_A^*` the displacement in the world frame, a rotation by
    :math:`\theta` about the line :math:`(\mathbf l, \mathbf m)` through
    :math:`\mathbf c = \mathbf l \times \mathbf m` and a slide :math:`d` along it
    (:func:`dqlab.dualquat.screw_from_dual_quaternion`):

    .. math::

        Q(s) = D^s Q_A = \operatorname{ScLERP}(Q_A, Q_B, s),\qquad
        \omega = \dot s\,\theta\,\mathbf l,\qquad
        \dot p = \dot s\,\bigl(\theta\,\mathbf l \times (p - \mathbf c) + d\,\mathbf l\bigr),

    and :math:`\ddot p = \ddot s\, p' + \dot s^2\, \theta\, \mathbf l \times p'` with
    :math:`p' = \theta\,\mathbf l \times (p - \mathbf c) + d\,\mathbf l`. The tool point
    travels on a helix about the screw axis, not on a straight line.

    Parameters
    ----------
    X_A, X_B : array_like, shape (4, 4)
    duration : float, optional
        Duration in seconds of a quintic law (used when ``law`` is None).
    law : TimeLaw, optional
        A normalised law (``distance`` 1).
    dt : float

    Returns
    -------
    CartesianPath

    Examples
    --------
    A quarter turn about the vertical line through the origin: the tool point at (0.3, 0, 0)
    swings on an arc, the middle of which is off the straight line.

    >>> import numpy as np
    >>> from dqlab import rot_z, transform_from
    >>> X_A = transform_from(np.eye(3), [0.3, 0, 0])
    >>> X_B = transform_from(rot_z(np.pi / 2), [0, 0.3, 0])
    >>> screw_path(X_A, X_B, duration=1.0, dt=0.5).position[1].round(6)
    array([0.212132, 0.212132, 0.      ])
    """
    X_A = _within_screw_reach(_one_transform(X_A, "X_A"), "X_A")
    X_B = _within_screw_reach(_one_transform(X_B, "X_B"), "X_B")
    law = _normalised_law(law, duration)
    t, s, sd, sdd = law.sample(check_scalar(dt, "dt", minimum=0, strict=True))
    Q_A, Q_B = dual_quaternion_from_transform(X_A), dual_quaternion_from_transform(X_B)
    if np.dot(Q_A[:4], Q_B[:4]) < 0:
        Q_B = -Q_B
    X = transform_from_dual_quaternion(sclerp(Q_A, Q_B, s))
    D = dual_quaternion_product(Q_B, dual_quaternion_conjugate(Q_A))
    l, m, theta, d = screw_from_dual_quaternion(D)
    c = np.cross(l, m)
    p = X[:, :3, 3]
    dp_ds = theta * np.cross(l, p - c) + d * l
    d2p_ds2 = theta * np.cross(l, dp_ds)
    return CartesianPath(
        t=t, position=p, velocity=sd[:, None] * dp_ds,
        acceleration=sdd[:, None] * dp_ds + (sd ** 2)[:, None] * d2p_ds2,
        orientation=quaternion_from_matrix(X[:, :3, :3]),
        angular_velocity=(sd * theta)[:, None] * l, s=s, sd=sd, sdd=sdd, law=law)


def circle_three_phase(center, radius, speed, dt=0.005, plane="xz", *,
                       fractions=(0.25, 0.25, 0.5), orientation=None):
    r"""The UR3 report's circle: one full turn with the three-phase speed law.

    The arc length :math:`s(t)` follows :func:`~dqlab.trajectory.time_laws.three_phase`
    over :math:`2\pi R` (accelerate over a quarter turn, cruise over a quarter, decelerate
    over a half), sampled as the report does on ``numpy.arange(0, t_f, dt)``. With
    :math:`u = s / R` and the plane's axes :math:`(e_1, e_2)` (``"xz"``: x then z):

    .. math::

        p &= c - R \sin u\; e_1 + R \cos u\; e_2,\\
        \dot p &= -\dot s \cos u\; e_1 - \dot s \sin u\; e_2,\\
        \ddot p &= \Bigl(-\ddot s \cos u + \frac{\dot s^2}{R}\sin u\Bigr) e_1
                 + \Bigl(-\ddot s \sin u - \frac{\dot s^2}{R}\cos u\Bigr) e_2,

    so :math:`\lVert\dot p\rVert = \dot s` and the tool starts at the top of the circle
    (:math:`c + R e_2`) moving towards :math:`-e_1`.

    Parameters
    ----------
    center : array_like, shape (3,)
        Centre :math:`c` in metres, world frame.
    radius : float
        :math:`R` in metres (> 0).
    speed : float
        Peak tool speed :math:`V` in m/s (> 0).
    dt : float
        Sampling period in seconds (> 0).
    plane : {"xz", "xy", "yz"}
        The plane of the circle.
    fractions : sequence of 3 floats
        Fractions of the turn for acceleration, cruise and deceleration.
    orientation : array_like, shape (3, 3) or (4,), optional
        A fixed tool orientation :math:`R_{WT}` (the report prescribes none).

    Returns
    -------
    CartesianPath
        With ``s``, ``sd``, ``sdd`` the arc length and its derivatives, and ``law``.

    Examples
    --------
    >>> import numpy as np
    >>> path = circle_three_phase([0.0, -0.35, 0.25], 0.1, 0.05)
    >>> len(path), round(float(path.speed.max()), 4)
    (4399, 0.05)
    >>> path.position[0]
    array([ 0.  , -0.35,  0.35])
    """
    c = as_float_array(center, "center", (3,))
    if c.shape != (3,):
        raise ValueError(f"center must have shape (3,), got {c.shape}")
    R = check_scalar(radius, "radius", minimum=0, strict=True)
    V = check_scalar(speed, "speed", minimum=0, strict=True)
    dt = check_scalar(dt, "dt", minimum=0, strict=True)
    if not isinstance(plane, str) or plane not in _PLANES:
        raise ValueError(f"plane must be one of {sorted(_PLANES)}, got {plane!r}")
    law = time_laws.three_phase(2 * np.pi * R, V, fractions)
    t, s, sd, sdd = law.sample(dt, endpoint=False)
    u = s / R
    i, j, k = _PLANES[plane]
    N = t.size
    position = np.empty((N, 3))
    velocity = np.zeros((N, 3))
    acceleration = np.zeros((N, 3))
    position[:, i] = c[i] - R * np.sin(u)
    position[:, j] = c[j] + R * np.cos(u)
    position[:, k] = c[k]
    velocity[:, i] = -sd * np.cos(u)
    velocity[:, j] = -sd * np.sin(u)
    acceleration[:, i] = -sdd * np.cos(u) + sd ** 2 / R * np.sin(u)
    acceleration[:, j] = -sdd * np.sin(u) - sd ** 2 / R * np.cos(u)
    path = CartesianPath(t=t, position=position, velocity=velocity, acceleration=acceleration,
                         s=s, sd=sd, sdd=sdd, law=law)
    if orientation is not None:
        q = _orientation(orientation, "orientation")
        path = replace(path, orientation=np.broadcast_to(q, (len(path), 4)).copy(),
                       angular_velocity=np.zeros((len(path), 3)))
    return path
