r"""The steps of the closed-form UR inverse kinematics, one equation per function.

These are the building blocks of :func:`dqlab.ik.ur_closed_form.ur`; each function solves
one equation of the derivation (the book's inverse-kinematics chapter, after section 4.3 of
the thesis). Each is one formula for two kinds of numbers: numpy arrays of any shape, so
that a whole batch of poses is solved for all branches at once without a Python loop, and
plain Python floats with the functions of ``math``, one pose and one branch at a time
(the fast path of a single pose, where numpy's per-call overhead would dominate). Angles
are in radians, lengths in metres, and the UR's standard Denavit-Hartenberg values are used
with their published signs (``a2``, ``a3`` are negative).

Notation. The pose is written relative to the arm's *zero pose* as the product of the six
joint screws about their zero-pose axes (the thesis's axis-angle dual quaternions
:math:`Q_1 \dots Q_6`): joint 1 turns about :math:`+z`, joints 2, 3, 4 and 6 about
:math:`-y`, joint 5 about :math:`-z`. The rotation part of that product is

.. math::

    q_D = r_z(\theta_1)\, r_{-y}(\theta_{234})\, r_{-z}(\theta_5)\, r_{-y}(\theta_6),
    \qquad \theta_{234} = \theta_2 + \theta_3 + \theta_4,

where :math:`r_u(\theta) = \cos\frac{\theta}{2} + \sin\frac{\theta}{2}\, u` is the unit
quaternion of a turn by :math:`\theta` about the unit axis :math:`u`.
"""

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..rotations import wrap_angle  # noqa: F401  (the steps' angle wrapping)

#: The arrays of the steps: float64 arrays of any shape.
Array = NDArray[np.float64]

_PLUS_MINUS = np.array([[1.0], [-1.0]])


def _float_clip0(x):
    return x if x > 0.0 else 0.0


def _float_no_minus_pi(theta):
    return math.pi if theta == -math.pi else theta


def _float_cos_sin(x, y):
    r = math.sqrt(x * x + y * y)
    return (x / r, y / r) if r > 0.0 else (1.0, 0.0)


def _float_half_cos_sin(c, s):
    big = math.sqrt(0.5 + 0.5 * abs(c))
    other = 0.5 * s / big
    if c >= 0.0:
        return big, other
    return abs(other), (-big if s < 0.0 else big)


def _array_clip0(x):
    return np.maximum(x, 0.0)


def _array_no_minus_pi(theta):
    # the smallest entry tells whether some entry is -pi (or below), in one pass
    return np.where(theta == -np.pi, np.pi, theta) if theta.min(initial=0.0) <= -np.pi else theta


def _array_cos_sin(x, y):
    r = np.sqrt(x * x + y * y)
    if r.min(initial=np.inf) > 0.0:       # no zero (the common case)
        return x / r, y / r
    with np.errstate(divide="ignore", invalid="ignore"):
        c, s = x / r, y / r
    zero = r == 0.0
    c[zero], s[zero] = 1.0, 0.0
    return c, s


def _array_half_cos_sin(c, s):
    big = np.sqrt(0.5 + 0.5 * np.abs(c))
    other = 0.5 * s / big
    first = c >= 0.0
    signed_big = np.where(s < 0.0, -big, big)
    return np.where(first, big, np.abs(other)), np.where(first, other, signed_big)


class _FLOAT:
    """The elementary functions of the steps for Python floats: ``math``'s. (The class
    itself is the namespace: its attributes are read without binding.)"""

    sqrt = math.sqrt
    atan2 = math.atan2
    sin = math.sin
    cos = math.cos
    copysign = math.copysign
    clip0 = staticmethod(_float_clip0)                # max(x, 0)
    no_minus_pi = staticmethod(_float_no_minus_pi)    # -pi -> pi, other angles unchanged
    cos_sin = staticmethod(_float_cos_sin)    # (x, y) / |(x, y)|, (1, 0) at 0: atan2(y, x)'s
    half_cos_sin = staticmethod(_float_half_cos_sin)  # see half_angle_cos_sin


class _ARRAY:
    """The same functions for numpy arrays."""

    sqrt = np.sqrt
    atan2 = np.arctan2
    sin = np.sin
    cos = np.cos
    copysign = np.copysign
    clip0 = staticmethod(_array_clip0)
    no_minus_pi = staticmethod(_array_no_minus_pi)
    cos_sin = staticmethod(_array_cos_sin)
    half_cos_sin = staticmethod(_array_half_cos_sin)


# Each step picks ``math``'s functions for a Python float (one pose, one branch at a time)
# and numpy's for arrays (a batch, all branches at once): one formula for both.


def wrist_center(p: ArrayLike, z6: ArrayLike, d6: float) -> Array:
    r"""Position of the wrist-2 point, :math:`p_5 = p_6 - d_6\, z_6`.

    Joint 6 only turns the flange about its own :math:`z_6` axis, so the origin of frame 5
    lies :math:`d_6` behind the flange along :math:`z_6`. In the thesis this is the
    translation part of :math:`Q_{FK}\, Q_6^{-1} Q_5^{-1}`-type products, equation (4.5)
    (whose printed :math:`Q_5^{-1}` carries the translation along :math:`i` instead of
    :math:`j`).

    Parameters
    ----------
    p, z6 : ndarray, shape (..., 3)
        Flange position and flange :math:`z` axis in the base frame.
    d6 : float
        Wrist-3 offset.

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> wrist_center(np.array([0.0, -0.19425, 0.69415]), np.array([0.0, -1.0, 0.0]), 0.0819)
    array([ 0.     , -0.11235,  0.69415])
    """
    return p - d6 * z6


def shoulder_angles(x5: Array, y5: Array, d4: float, sign: ArrayLike | None = None
                    ) -> tuple[Array, Array, Array, Array, Array]:
    r"""Both solutions of :math:`\sin\theta_1\, x_5 - \cos\theta_1\, y_5 = d_4` (thesis 4.9).

    With :math:`h = \sqrt{x_5^2 + y_5^2 - d_4^2}` the two roots are
    :math:`\theta_1 = \operatorname{atan2}(y_5, x_5) + \operatorname{atan2}(d_4, \pm h)`,
    that is :math:`e^{i\theta_1} \propto (x_5 + i y_5)(h_\pm + i d_4)`, computed as one
    well-conditioned ``atan2``:

    .. math::

        \theta_1 = \operatorname{atan2}(y_5 h_\pm + x_5 d_4,\; x_5 h_\pm - y_5 d_4),
        \qquad h_\pm = \pm h .

    The sign of :math:`h_\pm` is the shoulder branch: :math:`h_\pm = \cos\theta_1 x_5 +
    \sin\theta_1 y_5` is the wrist centre's coordinate along :math:`x_1`. A solution exists
    only if :math:`x_5^2 + y_5^2 \ge d_4^2`; when the difference is negative it is clipped to
    zero here (the caller judges whether the clipped answer is good enough), and when it is
    zero the two roots coincide (shoulder singularity).

    Parameters
    ----------
    x5, y5 : ndarray, shape (n,)
        Wrist-centre coordinates in the base frame.
    d4 : float
        Shoulder offset (distance of the arm plane from the base axis).
    sign : float, optional
        The one branch to compute, +1.0 (:math:`h_\pm = +h`) or -1.0, with float inputs;
        by default both branches, on a new first axis.

    Returns
    -------
    theta1, c1, s1 : ndarray, shape (2, n)
        :math:`\theta_1`, :math:`\cos\theta_1`, :math:`\sin\theta_1`; row 0 with
        :math:`h_\pm = +h`, row 1 with :math:`h_\pm = -h` (floats with ``sign``).
    h : ndarray, shape (n,)
        :math:`h \ge 0` after clipping.
    h2 : ndarray, shape (n,)
        :math:`x_5^2 + y_5^2 - d_4^2` before clipping (negative: the wrist centre is inside
        the cylinder of radius :math:`d_4` about the base axis).

    Examples
    --------
    >>> theta1, c1, s1, h, h2 = shoulder_angles(np.array([0.3]), np.array([-0.11235]), 0.11235)
    >>> np.round(theta1.ravel(), 6), np.round(h, 12)
    (array([0.      , 2.424928]), array([0.3]))
    >>> round(shoulder_angles(0.3, -0.11235, 0.11235, sign=-1.0)[0], 6)     # one branch
    2.424928
    """
    f = _FLOAT if type(x5) is float else _ARRAY
    h2 = x5 * x5 + y5 * y5 - d4 * d4
    h = f.sqrt(f.clip0(h2))
    hpm = (_PLUS_MINUS if sign is None else sign) * h
    num_c = x5 * hpm - y5 * d4
    num_s = y5 * hpm + x5 * d4
    theta1 = f.atan2(num_s + 0.0, num_c)    # + 0.0 turns -0.0 into 0.0: never -pi
    c1, s1 = f.cos_sin(num_c, num_s)         # the same direction, without trigonometry
    return theta1, c1, s1, h, h2


def half_angle_cos_sin(c: Array, s: Array) -> tuple[Array, Array]:
    r""":math:`\cos\frac{\theta}{2}` and :math:`\sin\frac{\theta}{2}` of an angle
    :math:`\theta \in (-\pi, \pi]` given by its cosine ``c`` and sine ``s``, without
    trigonometry.

    The larger of the two is :math:`\sqrt{(1 + |\cos\theta|)/2} \ge 1/\sqrt 2` (the
    cosine when :math:`\cos\theta \ge 0`, else the sine), and the other follows from
    :math:`\sin\theta = 2 \sin\frac{\theta}{2} \cos\frac{\theta}{2}`, a division by a
    number that is never small: both are as accurate as ``c`` and ``s``. On
    :math:`(-\pi, \pi]`, :math:`\cos\frac{\theta}{2} \ge 0` and
    :math:`\sin\frac{\theta}{2}` has the sign of :math:`\sin\theta` (positive at
    :math:`\theta = \pi`, where ``s`` may be :math:`-0`).

    Parameters
    ----------
    c, s : ndarray, shape (...)
        :math:`\cos\theta` and :math:`\sin\theta`, as from :func:`shoulder_angles`.

    Returns
    -------
    tuple of two ndarrays
        :math:`(\cos\frac{\theta}{2}, \sin\frac{\theta}{2})`.

    Examples
    --------
    >>> theta = np.array([-2.5, 0.4, np.pi])
    >>> c, s = half_angle_cos_sin(np.cos(theta), np.sin(theta))
    >>> bool(np.allclose(c, np.cos(theta / 2)) and np.allclose(s, np.sin(theta / 2)))
    True
    """
    f = _FLOAT if type(c) is float else _ARRAY
    return f.half_cos_sin(c, s)


def relative_rotation_coefficients(q: tuple, half1: Array | tuple[Array, Array]
                                   ) -> tuple[Array, Array, Array, Array]:
    r"""The four coefficients of :math:`L = r_z(\theta_1)^{-1} q_D` (thesis 4.14-4.17).

    With :math:`q_D = (w, x, y, z)` and :math:`\bar c_1 = \cos\frac{\theta_1}{2}`,
    :math:`\bar s_1 = \sin\frac{\theta_1}{2}`:

    .. math::

        L = (\bar c_1 w + \bar s_1 z,\; \bar c_1 x + \bar s_1 y,\;
             \bar c_1 y - \bar s_1 x,\; \bar c_1 z - \bar s_1 w),

    the right-hand sides of the thesis's equations :math:`M_2 = N_2` (4.14)-(4.17).

    Parameters
    ----------
    q : sequence of four ndarrays, each of shape (...)
        Components :math:`(w, x, y, z)` of the zero-pose-relative rotation :math:`q_D`.
    half1 : ndarray, shape (...), or a pair of them
        :math:`\theta_1 / 2`, or its cosine and sine (see :func:`half_angle_cos_sin`).

    Returns
    -------
    tuple of four ndarrays
        :math:`(L_w, L_x, L_y, L_z)`.

    Examples
    --------
    >>> half = np.float64(0.25)
    >>> q = np.cos(half), 0.0, 0.0, np.sin(half)  # a pure turn about z by 0.5 rad
    >>> [round(float(c), 12) for c in relative_rotation_coefficients(q, half)]
    [1.0, 0.0, 0.0, 0.0]
    """
    w, x, y, z = q
    if type(half1) is tuple:
        c, s = half1
    else:
        f = _FLOAT if type(half1) is float else _ARRAY
        c, s = f.cos(half1), f.sin(half1)
    return c * w + s * z, c * x + s * y, c * y - s * x, c * z - s * w


def wrist_angles(L: tuple, sigma: ArrayLike) -> tuple[Array, Array, Array, Array, Array]:
    r""":math:`\theta_5` and the half sum/difference of :math:`\theta_{234}` and :math:`\theta_6`.

    Expanding :math:`r_{-y}(\theta_{234})\, r_{-z}(\theta_5)\, r_{-y}(\theta_6)` gives

    .. math::

        L = \Big(\bar c_5 \cos\tfrac{\Sigma}{2},\; \bar s_5 \sin\tfrac{\Delta}{2},\;
            -\bar c_5 \sin\tfrac{\Sigma}{2},\; -\bar s_5 \cos\tfrac{\Delta}{2}\Big),
        \qquad \Sigma = \theta_{234} + \theta_6,\ \Delta = \theta_{234} - \theta_6,

    with :math:`\bar c_5 = \cos\frac{\theta_5}{2}`, :math:`\bar s_5 = \sin\frac{\theta_5}{2}`.
    Hence, with the wrist branch :math:`\sigma = \pm 1`,

    .. math::

        \bar c_5 = \sqrt{L_w^2 + L_y^2},\quad \bar s_5 = \sigma\sqrt{L_x^2 + L_z^2},\quad
        \theta_5 = 2\operatorname{atan2}(\bar s_5, \bar c_5),

        \tfrac{\Sigma}{2} = \operatorname{atan2}(-L_y, L_w),\qquad
        \tfrac{\Delta}{2} = \operatorname{atan2}(\sigma L_x, -\sigma L_z).

    No division by :math:`\bar s_5` or :math:`\bar c_5` occurs (the thesis divides by them
    in 4.18-4.21 and then solves the 0/0-prone (4.28)); every quantity is an ``atan2`` of
    two directly computed numbers, so :math:`\theta_5` keeps full accuracy near 0 and
    :math:`\pm\pi`. Equivalently :math:`\cos\theta_5 = \bar c_5^2 - \bar s_5^2` is the
    projection of the flange :math:`z` axis on the joint-2 axis.
    The branch :math:`\sigma = -1` is the wrist flip of :math:`\sigma = +1`
    (:func:`wrist_flip`), which the solver uses instead of a second call.

    Parameters
    ----------
    L : tuple of four ndarrays, shape (...)
        Output of :func:`relative_rotation_coefficients`.
    sigma : ndarray or float
        Wrist branch, +1 (:math:`\theta_5 \in [0, \pi]`) or -1, broadcast against ``L``.

    Returns
    -------
    theta5, half_sum, half_diff, c5bar, s5bar : ndarrays
        :math:`\theta_5`, :math:`\Sigma/2`, :math:`\Delta/2`, and the magnitudes
        :math:`|\bar c_5|`, :math:`|\bar s_5|`.

    Examples
    --------
    >>> L = (np.cos(0.3) * np.cos(0.1), np.sin(0.3) * np.sin(0.2),
    ...      -np.cos(0.3) * np.sin(0.1), -np.sin(0.3) * np.cos(0.2))
    >>> [round(float(v), 12) for v in wrist_angles(L, 1.0)[:3]]
    [0.6, 0.1, 0.2]
    """
    Lw, Lx, Ly, Lz = L
    f = _FLOAT if type(Lw) is float else _ARRAY
    c5bar = f.sqrt(Lw * Lw + Ly * Ly)
    s5bar = f.sqrt(Lx * Lx + Lz * Lz)
    # (sigma * sigma = 1 gives c5bar the broadcast shape: atan2 is fastest on equal shapes)
    theta5 = f.no_minus_pi(2.0 * f.atan2(sigma * s5bar, (sigma * sigma) * c5bar))
    half_sum = f.atan2(-Ly, Lw)
    half_diff = f.atan2(sigma * Lx, -sigma * Lz)
    return theta5, half_sum, half_diff, c5bar, s5bar


def wrist_flip(theta5: Array, half_diff: Array) -> tuple[Array, Array]:
    r"""The other wrist branch from one: :math:`\theta_5 \to -\theta_5`,
    :math:`\frac{\Delta}{2} \to \frac{\Delta}{2} \mp \pi`.

    Changing the wrist branch :math:`\sigma` of :func:`wrist_angles` negates the ``atan2``
    of :math:`\theta_5` and turns the direction of :math:`\frac{\Delta}{2}` by
    :math:`\pi`; :math:`\frac{\Sigma}{2}`, :math:`\bar c_5` and :math:`|\bar s_5|` stay.
    So :math:`\theta_{234}` and :math:`\theta_6` move by :math:`\mp\pi` and
    :math:`\pm\pi`: the familiar wrist flip :math:`(\theta_4 + \pi, -\theta_5,
    \theta_6 + \pi)` (mod :math:`2\pi`). It reaches the same orientation because
    :math:`r_{-y}(\pi)\, r_{-z}(-\theta_5)\, r_{-y}(-\pi) = (-j)\, r_{-z}(-\theta_5)\, j
    = r_{-z}(\theta_5)`. The results are those of ``atan2`` with :math:`\sigma` changed:
    :math:`\theta_5 \in (-\pi, \pi]` and :math:`\frac{\Delta}{2} \in [-\pi, \pi]`.

    Parameters
    ----------
    theta5, half_diff : ndarray or float
        :math:`\theta_5` and :math:`\frac{\Delta}{2}` of one wrist branch.

    Returns
    -------
    theta5, half_diff : ndarrays or floats
        Those of the other branch.

    Examples
    --------
    >>> L = (math.cos(0.3) * math.cos(0.1), math.sin(0.3) * math.sin(0.2),
    ...      -math.cos(0.3) * math.sin(0.1), -math.sin(0.3) * math.cos(0.2))
    >>> theta5, half_sum, half_diff, c5bar, s5bar = wrist_angles(L, 1.0)
    >>> flipped = wrist_angles(L, -1.0)
    >>> [round(a - b, 15) for a, b in zip(wrist_flip(theta5, half_diff), flipped[::2])]
    [0.0, 0.0]
    """
    f = _FLOAT if type(theta5) is float else _ARRAY
    return f.no_minus_pi(-theta5), half_diff - f.copysign(math.pi, half_diff)


def arm_plane_wrist(p5: tuple, c1: Array, s1: Array, d1: float) -> tuple[Array, Array]:
    r"""Wrist centre in the arm plane: :math:`P = (c_1 x_5 + s_1 y_5,\; z_5 - d_1)`.

    The plane of the planar 3R chain (joints 2, 3, 4) contains the shoulder point
    :math:`(0, 0, d_1)` and is spanned by :math:`x_1 = (c_1, s_1, 0)` and :math:`y_1 = z_0`.

    Parameters
    ----------
    p5 : sequence of three ndarrays, shape (...)
        Wrist-centre coordinates.
    c1, s1 : ndarray
        Cosine and sine of :math:`\theta_1`, broadcast against ``p5``.
    d1 : float
        Base height.

    Returns
    -------
    Px, Py : ndarrays

    Examples
    --------
    >>> [round(v, 12) for v in arm_plane_wrist((0.3, -0.11235, 0.2), 1.0, 0.0, 0.1519)]
    [0.3, 0.0481]
    """
    x5, y5, z5 = p5
    return c1 * x5 + s1 * y5, z5 - d1


def theta234_sine_cosine(L: tuple, sigma: ArrayLike, c5bar: Array, s5bar: Array
                         ) -> tuple[Array, Array]:
    r""":math:`\sin\theta_{234}` and :math:`\cos\theta_{234}` from the coefficients of
    :func:`wrist_angles`, without trigonometry.

    :math:`\theta_{234} = \frac{\Sigma}{2} + \frac{\Delta}{2}`, whose cosines and sines are
    :math:`(L_w, -L_y) / \bar c_5` and :math:`(-\sigma L_z, \sigma L_x) / \bar s_5`; the
    angle-addition formulas give

    .. math::

        \sin\theta_{234} = \sigma\,\frac{L_w L_x + L_y L_z}{\bar c_5 \bar s_5},\qquad
        \cos\theta_{234} = \sigma\,\frac{L_x L_y - L_w L_z}{\bar c_5 \bar s_5}

    (the two numerators have the squared sum :math:`\bar c_5^2 \bar s_5^2`). Undefined at
    the wrist singularity, :math:`\bar c_5 \bar s_5 = 0`, where :math:`\theta_{234}` is
    chosen from its family instead (:func:`feasible_theta234`) and its sine and cosine
    taken directly.

    Examples
    --------
    >>> L = (math.cos(0.3) * math.cos(0.1), math.sin(0.3) * math.sin(0.2),
    ...      -math.cos(0.3) * math.sin(0.1), -math.sin(0.3) * math.cos(0.2))
    >>> theta5, half_sum, half_diff, c5bar, s5bar = wrist_angles(L, 1.0)
    >>> s, c = theta234_sine_cosine(L, 1.0, c5bar, s5bar)
    >>> round(s - math.sin(0.3), 15), round(c - math.cos(0.3), 15)
    (0.0, 0.0)
    """
    Lw, Lx, Ly, Lz = L
    k = sigma / (c5bar * s5bar)
    return k * (Lw * Lx + Ly * Lz), k * (Lx * Ly - Lw * Lz)


def wrist1_point(Px: Array, Py: Array, theta234: Array, d5: float,
                 sine_cosine: tuple | None = None) -> tuple[Array, Array]:
    r"""Wrist-1 point in the arm plane, :math:`(X, Y) = P - d_5 (s_{234}, -c_{234})`.

    The wrist-2 axis :math:`z_4 = (c_1 s_{234},\, s_1 s_{234},\, -c_{234})` carries the
    offset :math:`d_5` from the wrist-1 point to the wrist centre; the thesis undoes it with
    :math:`Q_4^{-1}` in (4.33)-(4.34) (where the printed :math:`Q_4^{-1}` is a copy of
    :math:`Q_5^{-1}`). :math:`(X, Y)` is the point the planar 2R chain
    :math:`a_2, a_3` must reach: :math:`X = a_2 c_2 + a_3 c_{23}`, :math:`Y = a_2 s_2 + a_3 s_{23}`.

    Examples
    --------
    The thesis's pose, arm straight up: the wrist-1 point is :math:`|a_2 + a_3|` above the
    shoulder.

    >>> X, Y = wrist1_point(0.0, 0.54235, -np.pi, 0.08535)
    >>> round(float(X), 12), round(float(Y), 12)
    (0.0, 0.457)

    ``sine_cosine``, when given, is :math:`(\sin\theta_{234}, \cos\theta_{234})`
    already known (:func:`theta234_sine_cosine`).
    """
    if sine_cosine is None:
        f = _FLOAT if type(theta234) is float else _ARRAY
        sine_cosine = f.sin(theta234), f.cos(theta234)
    s234, c234 = sine_cosine
    return Px - d5 * s234, Py + d5 * c234


def elbow_triangle(X: Array, Y: Array, a2: float, a3: float
                   ) -> tuple[Array, Array, Array, Array, Array]:
    r"""The law of cosines of the planar 2R chain, the part both elbow branches share.

    See :func:`elbow_angles`: with :math:`\rho^2 = X^2 + Y^2`,

    .. math::

        c = \operatorname{sgn}(a_2 a_3)(\rho^2 - a_2^2 - a_3^2) = 2|a_2 a_3|\cos\theta_3,
        \qquad k = \sqrt{K} = 2|a_2 a_3|\,|\sin\theta_3|,

    with :math:`K` clipped at zero out of reach, and the elbow's magnitude
    :math:`|\theta_3| = \operatorname{atan2}(k, c)`.

    Parameters
    ----------
    X, Y : ndarray or float
        Wrist-1 point in the arm plane, relative to the shoulder.
    a2, a3 : float

    Returns
    -------
    cos_num, k, outer, inner, angle3 : ndarrays or floats
        :math:`c`, :math:`k`, the reach margins of :func:`elbow_angles` and
        :math:`|\theta_3|`.

    Examples
    --------
    >>> c, k, outer, inner, angle3 = elbow_triangle(-0.3, 0.2, -0.24365, -0.21325)
    >>> round(angle3, 6)
    1.326258
    """
    f = _FLOAT if type(X) is float else _ARRAY
    rho2 = X * X + Y * Y
    rho = f.sqrt(rho2)
    r_out = abs(a2 + a3)
    r_in = abs(a2 - a3)
    outer = (r_out - rho) * (r_out + rho)
    inner = (rho - r_in) * (rho + r_in)
    k = f.sqrt(f.clip0(outer * inner))      # one factor negative: out of reach, k = 0
    cos_num = rho2 - (a2 * a2 + a3 * a3)
    if a2 * a3 < 0:
        cos_num = -cos_num
    return cos_num, k, outer, inner, f.atan2(k, cos_num)


def elbow_angles(X: Array, Y: Array, a2: float, a3: float, elbow_sign: ArrayLike,
                 triangle: tuple | None = None) -> tuple[Array, Array, Array, Array, Array]:
    r"""Planar 2R: :math:`\theta_3` from the law of cosines, :math:`\theta_2` by ``atan2``.

    With :math:`\rho^2 = X^2 + Y^2` the law of cosines (thesis 4.37) reads
    :math:`2 a_2 a_3 \cos\theta_3 = \rho^2 - a_2^2 - a_3^2`, and

    .. math::

        (2 a_2 a_3 \sin\theta_3)^2 = K = \big((a_2 + a_3)^2 - \rho^2\big)
                                         \big(\rho^2 - (a_2 - a_3)^2\big),

    whose factors are computed as products of sums and differences of lengths, so that the
    sine keeps the digits the data carry near full stretch (:math:`\rho = |a_2 + a_3|`) or
    full fold (there :math:`\theta_3` itself is ill-conditioned: a rounding of
    :math:`\rho` moves it by about :math:`\sqrt{\varepsilon}`). Then

    .. math::

        \theta_3 = \pm\operatorname{atan2}\!\big(\sqrt{K},\;
                   \operatorname{sgn}(a_2 a_3)(\rho^2 - a_2^2 - a_3^2)\big),\qquad
        \theta_2 = \operatorname{atan2}(Y k_1 - X k_2,\; X k_1 + Y k_2),

    with :math:`k_1 = a_2 + a_3\cos\theta_3`, :math:`k_2 = a_3 \sin\theta_3` (thesis 4.41,
    which is right), :math:`\cos\theta_3` and :math:`\sin\theta_3` taken from the same two
    numbers divided by :math:`2|a_2 a_3|`. Negative :math:`K` (the point is out of the 2R
    chain's reach) is clipped to zero: the arm is then stretched or folded towards the
    point.

    Parameters
    ----------
    X, Y : ndarray, shape (..., 1, m)
        Wrist-1 point in the arm plane, relative to the shoulder.
    a2, a3 : float
        Upper-arm and forearm lengths (signed, as UR publishes them).
    elbow_sign : ndarray, shape (2, 1), or float
        ``[[1], [-1]]``: the elbow branches (sign of :math:`\sin\theta_3` when
        :math:`a_2 a_3 > 0`), on the second-last axis; +1.0 or -1.0 for one branch with
        float inputs.
    triangle : tuple, optional
        :func:`elbow_triangle` of the same point, when already computed (one pose solved
        branch by branch computes it once for both elbows).

    Returns
    -------
    theta2, theta3 : ndarrays, shape (..., 2, m)
    outer, inner : ndarrays, shape (..., 1, m)
        :math:`(|a_2 + a_3| - \rho)(|a_2 + a_3| + \rho)` and
        :math:`(\rho - |a_2 - a_3|)(\rho + |a_2 - a_3|)` before clipping; a negative value
        says the point is beyond the outer or inside the inner reach.
    sin3 : ndarray, shape (..., 1, m)
        :math:`|\sin\theta_3|`.

    Examples
    --------
    >>> t2, t3, outer, inner, s3 = elbow_angles(np.array([[-0.3]]), np.array([[0.2]]),
    ...                                         -0.24365, -0.21325, np.array([[1.0], [-1.0]]))
    >>> np.round(t2.ravel(), 6), np.round(t3.ravel(), 6), bool(outer > 0), bool(inner > 0)
    (array([-1.199206,  0.0232  ]), array([ 1.326258, -1.326258]), True, True)
    """
    f = _FLOAT if type(X) is float else _ARRAY
    cos_num, k, outer, inner, angle3 = triangle or elbow_triangle(X, Y, a2, a3)
    m = 2.0 * abs(a2 * a3)
    # the folded elbow has theta3 = pi on both branches
    theta3 = f.no_minus_pi(angle3 * elbow_sign)
    k1 = a2 + (a3 / m) * cos_num
    k2 = (a3 / m) * k
    # + 0.0: never -0.0, so theta2 is never -pi
    theta2 = f.atan2(Y * k1 - elbow_sign * (X * k2) + 0.0, X * k1 + elbow_sign * (Y * k2))
    return theta2, theta3, outer, inner, k / m


def feasible_theta234(Px: Array, Py: Array, theta234_ref: Array, a2: float, a3: float,
                      d5: float) -> Array:
    r"""The angle :math:`\theta_{234}` nearest to a wanted value for which the arm reaches.

    Used at a wrist singularity, where only :math:`\theta_{234} \pm \theta_6` is fixed by
    the orientation: the wrist-1 point :math:`(X, Y) = P - d_5 (\sin t, -\cos t)` then
    moves on a circle of radius :math:`d_5` about :math:`P`, and the 2R chain reaches it iff
    :math:`(a_2 - a_3)^2 \le \rho^2(t) \le (a_2 + a_3)^2` with

    .. math::

        \rho^2(t) = |P|^2 + d_5^2 - 2 d_5 |P| \sin(t - \psi),
        \qquad \psi = \operatorname{atan2}(P_y, P_x).

    Each bound :math:`\rho^2 = R^2` gives :math:`\sin(t - \psi) = s_R =
    (|P|^2 + d_5^2 - R^2) / (2 d_5 |P|)`, solved as
    :math:`t = \psi + \operatorname{atan2}(2 d_5 |P| s_R, \pm\sqrt{F_R})` with
    :math:`F_R = (R - |P| + d_5)(R + |P| - d_5)(|P| + d_5 - R)(|P| + d_5 + R)` (digits kept
    at tangency). The wanted angle is returned when it is feasible, otherwise the feasible
    boundary point nearest to it; when nothing is feasible the outer-reach tangency (the
    closest approach) is returned and the caller's forward-kinematics check rejects it.

    Parameters
    ----------
    Px, Py : ndarray, shape (...)
        Wrist centre in the arm plane (see :func:`arm_plane_wrist`).
    theta234_ref : ndarray, shape (...)
        The wanted :math:`\theta_{234}`.
    a2, a3, d5 : float

    Returns
    -------
    ndarray, shape (...)

    Examples
    --------
    The thesis's pose: the arm stands straight up, so only :math:`\theta_{234} = -\pi`
    reaches, whatever is asked for.

    >>> t = feasible_theta234(np.array([0.0]), np.array([0.5423500]), np.array([-2.8]),
    ...                       -0.24365, -0.21325, 0.08535)
    >>> np.round(np.abs(t), 6)
    array([3.141593])
    """
    Px, Py, theta234_ref = np.broadcast_arrays(Px, Py, theta234_ref)
    norm_p = np.sqrt(Px * Px + Py * Py)
    psi = np.arctan2(Py, Px)
    two_d5p = 2.0 * d5 * norm_p
    u_ref = wrap_angle(theta234_ref - psi)
    sin_ref = np.sin(u_ref)
    r_out, r_in = abs(a2 + a3), abs(a2 - a3)
    s_lo_num = norm_p * norm_p + d5 * d5 - r_out * r_out   # 2 d5 |P| * s_lo (rho <= r_out)
    s_hi_num = norm_p * norm_p + d5 * d5 - r_in * r_in     # 2 d5 |P| * s_hi (rho >= r_in)
    ok = (sin_ref * two_d5p >= s_lo_num) & (sin_ref * two_d5p <= s_hi_num)

    def roots(R, num):
        f = (R - norm_p + d5) * (R + norm_p - d5) * (norm_p + d5 - R) * (norm_p + d5 + R)
        c = np.sqrt(np.maximum(f, 0.0))
        return np.arctan2(num, c), np.arctan2(num, -c), f >= 0

    lo_a, lo_b, lo_ok = roots(r_out, s_lo_num)
    hi_a, hi_b, hi_ok = roots(r_in, s_hi_num)
    cands = np.stack([lo_a, lo_b, hi_a, hi_b], axis=-1)
    usable = np.stack([lo_ok, lo_ok, hi_ok, hi_ok], axis=-1)
    dist = np.abs(wrap_angle(cands - u_ref[..., None]))
    dist = np.where(usable, dist, np.inf)
    best = np.take_along_axis(cands, np.argmin(dist, axis=-1)[..., None], axis=-1)[..., 0]
    # nothing feasible at all: the outer tangency u = pi/2 is the closest approach
    best = np.where(np.any(usable, axis=-1), best, 0.5 * np.pi)
    return np.where(ok, theta234_ref, psi + best)
