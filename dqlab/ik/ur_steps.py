r"""The steps of the closed-form UR inverse kinematics, one equation of chapter 8 per function,
and their assembly into the eight candidate solutions, :func:`candidate_solutions`.

Chapter 8 (:ref:`ch-inverse-kinematics`) derives the UR's inverse kinematics with dual
quaternions, after section 4.3 of the thesis; each function here is one of its equations,
under the chapter's names: the wrist centre :math:`p_5` and the shoulder angle
:math:`\theta_1` (:func:`wrist_center`, :func:`shoulder_angles`), the four rotation
coefficients :math:`L` and the wrist angles (:func:`relative_rotation_coefficients`,
:func:`wrist_angles`), the arm-plane coordinates :math:`(u_5, v_5)` of the wrist centre and
:math:`(u_4, v_4)` of the wrist-1 point (:func:`arm_plane_wrist`, :func:`wrist1_point`) and
the planar two-link arm (:func:`elbow_angles`). :func:`candidate_solutions` runs them in the
chapter's order and is what the chapter shows.
:func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` computes the same rows with the speed
machinery of the private module ``dqlab._fast.ur_engine`` (tested equal, bit for bit) and
adds the checks, the flags and the choice at a wrist singularity.

Each step is one formula for two kinds of numbers, told apart by one switch
(``dqlab._formulas.functions_for``): Python floats, computed with ``math`` (one pose, one
branch at a time), and numpy arrays of any shape (a batch, all branches at once). Angles
are in radians, lengths in metres; UR's standard Denavit--Hartenberg values keep their
published signs (:math:`a_2`, :math:`a_3` are negative).

Notation. With all frames parallel to the base frame in the zero configuration, the joints
are the pairs :math:`Q_i = (\mathsf r_i, \mathbf t_i)` of the chapter: joint 1 turns about
:math:`+\mathbf k`, joints 2, 3, 4 and 6 about :math:`-\mathbf j`, joint 5 about
:math:`-\mathbf k`. The rotation part of their product is

.. math::

    \mathsf r_D = \mathsf r_{\mathbf k}(\theta_1)\, \mathsf r_{-\mathbf j}(\theta_{234})\,
                  \mathsf r_{-\mathbf k}(\theta_5)\, \mathsf r_{-\mathbf j}(\theta_6),
    \qquad \theta_{234} = \theta_2 + \theta_3 + \theta_4,

where :math:`\mathsf r_{\mathbf u}(\theta) = \cos\frac{\theta}{2} + \sin\frac{\theta}{2}\,
\mathbf u` is the unit quaternion of a turn by :math:`\theta` about the unit axis
:math:`\mathbf u`.
"""

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._checks import components
from .._formulas import functions_for, quaternion_from_matrix_entries, quaternion_mul
from ..rotations import wrap_angle
from ..transforms import check_transform

__all__ = [
    "target_rotation", "wrist_center", "far_wrist", "shoulder_angles", "half_angle_cos_sin",
    "relative_rotation_coefficients", "wrist_angles", "half_difference", "theta234_sine_cosine",
    "arm_plane_wrist", "wrist1_point", "elbow_triangle", "elbow_angles", "reach_gap",
    "shoulder_gap", "feasible_theta234", "candidate_solutions", "NEAR_WRIST", "NEAR_SINGULAR",
]

#: The arrays of the steps: float64 arrays of any shape (or Python floats).
Array = NDArray[np.float64]

_HALF_SQRT2 = math.sqrt(0.5)           # a Python float: it serves floats and arrays
_EPSILON = float(np.finfo(float).eps)

#: :math:`|\sin\theta_5|` below which the closed form treats the wrist as at its singularity:
#: there :math:`\theta_{234}` comes from coefficients of the size of :math:`\theta_5`, and a
#: row the forearm cannot reach moves within its wrist family (``dqlab.ik.ur``).
NEAR_WRIST = 1e-3

#: The default ``near_tol`` of :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`: a valid row
#: whose :math:`|\sin\theta_5|`, :math:`|\sin\theta_3|` or :math:`h / d_4` is below it
#: (about 0.57 degrees, or 1 % of :math:`d_4`) is near a singularity, where its joints are
#: sensitive to the pose.
NEAR_SINGULAR = 1e-2

#: Why a pose has no solution (``IKResult.reason``), from the first step that fails.
REASON_SHOULDER = ("shoulder: the wrist centre p5 = p6 - d6 z6 lies inside the cylinder "
                   "x5^2 + y5^2 < d4^2 about the base axis")
REASON_OUTER = ("elbow: the wrist-1 point is farther from the shoulder than |a2| + |a3| on "
                "every branch")
REASON_INNER = ("elbow: the wrist-1 point is closer to the shoulder than ||a2| - |a3|| on "
                "every branch")
REASON_REACH = "elbow: the wrist-1 point is out of the forearm's reach on every branch"
REASON_TOL = "no branch reproduces the pose within tol"
REASON_FAR = ("the wrist centre is farther from the shoulder than 1 / eps times the arm's "
              "reach: out of reach, its distance the error of every row")


def target_rotation(q: tuple) -> tuple:
    r"""The target's rotation in the frames of the pairs, :math:`\mathsf r_D = q\, q_0^*`.

    UR's DH flange frame is the pairs' last frame turned by :math:`\pi/2` about :math:`x`,
    whose quaternion is :math:`q_0 = (1 + \mathbf i)/\sqrt 2`; undoing that turn on the
    flange rotation :math:`q` is the quaternion product

    .. math::

        \mathsf r_D = q\, q_0^* = \frac{q\,(1 - \mathbf i)}{\sqrt 2},

    whose product with :math:`1 - \mathbf i` only adds and subtracts components (exact).

    Parameters
    ----------
    q : sequence of four floats or arrays
        Components :math:`(w, x, y, z)` of the flange rotation (a unit quaternion).

    Returns
    -------
    tuple of four floats or arrays
        :math:`\mathsf r_D`.

    Examples
    --------
    At :math:`\theta = 0` the flange rotation is :math:`q_0` itself:

    >>> [round(c, 15) for c in target_rotation((math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0))]
    [1.0, 0.0, 0.0, 0.0]
    """
    w, x, y, z = quaternion_mul(*q, 1.0, -1.0, 0.0, 0.0)
    return _HALF_SQRT2 * w, _HALF_SQRT2 * x, _HALF_SQRT2 * y, _HALF_SQRT2 * z


def wrist_center(p: tuple, z6: tuple, d6: float) -> tuple:
    r"""The wrist centre :math:`p_5 = p - d_6\, z_6`, chapter 8's :eq:`eq-ik-wrist-point`.

    Joint 6 only turns the flange about its own :math:`z_6` axis, so the origin of frame 5
    (where the axes of joints 5 and 6 meet) lies :math:`d_6` behind the flange along
    :math:`z_6`. In the pairs' frames this is the translation of
    :math:`(\mathsf r_D, p)(1, d_6\mathbf j)`, the thesis's (4.5) (whose printed
    :math:`Q_5^{-1}` carries the translation along :math:`\mathbf i` instead of
    :math:`\mathbf j`).

    Parameters
    ----------
    p, z6 : sequences of three floats or arrays
        Flange position :math:`p` and flange :math:`z` axis :math:`z_6` in the base frame,
        component by component.
    d6 : float
        Wrist-3 offset.

    Returns
    -------
    tuple of three floats or arrays
        :math:`(x_5, y_5, z_5)`.

    Examples
    --------
    >>> [round(c, 12) for c in wrist_center((0.0, -0.19425, 0.69415), (0.0, -1.0, 0.0), 0.0819)]
    [0.0, -0.11235, 0.69415]
    """
    return p[0] - d6 * z6[0], p[1] - d6 * z6[1], p[2] - d6 * z6[2]


def far_wrist(p5: tuple, d1: float, a2: float, a3: float, d4: float, d5: float) -> Array:
    r"""The distance of a wrist centre from the shoulder point when it is far beyond the arm's
    reach (0 when it is not): a pose the steps below must not solve.

    Every configuration puts the wrist centre within

    .. math::

        R_5 = \sqrt{d_4^2 + (|a_2| + |a_3| + |d_5|)^2}

    of the shoulder point :math:`s = (0, 0, d_1)` (the wrist centre lies :math:`d_4` off the
    arm plane, and in it within :math:`|a_2| + |a_3| + |d_5|` of the shoulder). A wrist
    centre as far as :math:`R_5 / \varepsilon` (about :math:`4.5 \cdot 10^{15} R_5`) is out of
    reach, and its distance :math:`D = \lVert p_5 - s \rVert` is the position error of
    every row to rounding (the arm's whole reach is within :math:`D`'s last two digits). The steps
    are not run for it: they square lengths, and products of squares
    (:func:`shoulder_angles` normalises :math:`x_5 h`, of size :math:`D^2`) overflow from
    about :math:`10^{77}` m on, where a direction of length 0 would make the errors vanish.

    Far is tested on the sum of the coordinates' sizes, :math:`m = \sum |p_5 - s|_i >
    R_5 / \varepsilon`: a pose called far has :math:`D \ge m / \sqrt 3`; the others lie
    within :math:`R_5 / \varepsilon`, whose squares are safe. :math:`D` is computed as
    :math:`m \sqrt{\sum (p_{5,i} - s_i)^2 / m^2}`, which cannot overflow below the largest
    float (beyond it, or where the position overflowed on its way here, :math:`D = \infty`).

    Parameters
    ----------
    p5 : sequence of three floats or arrays
        The wrist centre :math:`(x_5, y_5, z_5)` (:func:`wrist_center`).
    d1, a2, a3, d4, d5 : float
        UR's standard DH lengths.

    Returns
    -------
    float or ndarray
        :math:`D` where the wrist centre is far, 0 elsewhere.

    Examples
    --------
    >>> far_wrist((1e100, 0.0, 0.0), 0.1625, -0.425, -0.3922, 0.1333, 0.0997)
    1e+100
    >>> far_wrist((2.0, 0.0, 0.5), 0.1625, -0.425, -0.3922, 0.1333, 0.0997)
    0.0
    """
    x, y, z = p5[0], p5[1], p5[2] - d1
    limit = math.sqrt(d4 * d4 + (abs(a2) + abs(a3) + abs(d5)) ** 2) / _EPSILON
    f = functions_for(type(x))
    m = abs(x) + abs(y) + abs(z)                      # (a NaN or an infinity stays one)
    if f.largest(m) <= limit:                         # (the common case: nothing far)
        return 0.0 * m
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        x, y, z = x / m, y / m, z / m
        distance = m * f.sqrt(x * x + y * y + z * z)
    # beyond the largest float (a pose whose frame change overflowed): infinitely far
    distance = f.where(distance < math.inf, distance, math.inf)
    return f.where(m <= limit, 0.0, distance)


def shoulder_angles(x5: Array, y5: Array, d4: float, sign: ArrayLike
                    ) -> tuple[Array, Array, Array, Array, Array]:
    r"""The shoulder angle :math:`\theta_1` of :eq:`eq-ik-theta1`, from the plane equation
    :math:`-x_5 \sin\theta_1 + y_5 \cos\theta_1 = -d_4` (thesis 4.9).

    With :math:`h = \sqrt{x_5^2 + y_5^2 - d_4^2}` the two roots are
    :math:`\theta_1 = \operatorname{atan2}(-x_5, y_5) \pm \operatorname{atan2}(h, -d_4)`,
    that is :math:`e^{i\theta_1} \propto (x_5 + i y_5)(h_\pm + i d_4)`, computed as one
    well-conditioned ``atan2``:

    .. math::

        \theta_1 = \operatorname{atan2}(y_5 h_\pm + x_5 d_4,\; x_5 h_\pm - y_5 d_4),
        \qquad h_\pm = \pm h .

    The sign of :math:`h_\pm` is the shoulder branch: :math:`h_\pm = u_5 = \cos\theta_1 x_5
    + \sin\theta_1 y_5` is the wrist centre's coordinate along :math:`x_1`. A solution
    exists only if :math:`x_5^2 + y_5^2 \ge d_4^2`; when the difference is negative it is
    clipped to zero here (the caller judges whether the clipped answer is good enough), and
    when it is zero the two roots coincide (shoulder singularity).

    Parameters
    ----------
    x5, y5 : float or ndarray
        Wrist-centre coordinates in the base frame.
    d4 : float
        Shoulder offset (distance of the arm plane from the base axis).
    sign : float or ndarray
        The shoulder branch: +1.0 (:math:`h_\pm = +h`, "left") or -1.0 ("right"), or an
        array of signs that broadcasts against ``x5`` (``[[1.0], [-1.0]]``: both at once,
        on a new first axis).

    Returns
    -------
    theta1, c1, s1 : float or ndarray
        :math:`\theta_1`, :math:`\cos\theta_1`, :math:`\sin\theta_1` (the last two from the
        same two numbers as the ``atan2``, without trigonometry).
    h : float or ndarray
        :math:`h \ge 0` after clipping.
    h2 : float or ndarray
        :math:`x_5^2 + y_5^2 - d_4^2` before clipping (negative: the wrist centre is inside
        the shoulder cylinder of radius :math:`d_4` about the base axis).

    Examples
    --------
    >>> theta1, c1, s1, h, h2 = shoulder_angles(0.3, -0.11235, 0.11235, 1.0)
    >>> round(theta1, 12), round(h, 12)
    (0.0, 0.3)
    >>> both = shoulder_angles(np.array([0.3]), np.array([-0.11235]), 0.11235,
    ...                        np.array([[1.0], [-1.0]]))
    >>> np.round(both[0].ravel(), 6)                                 # left, right
    array([0.      , 2.424928])
    """
    f = functions_for(type(x5))
    h2 = x5 * x5 + y5 * y5 - d4 * d4
    h = f.sqrt(f.clip0(h2))
    hpm = sign * h
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
    c, s : float or ndarray
        :math:`\cos\theta` and :math:`\sin\theta`, as from :func:`shoulder_angles`.

    Returns
    -------
    tuple of two floats or ndarrays
        :math:`(\cos\frac{\theta}{2}, \sin\frac{\theta}{2})`.

    Examples
    --------
    >>> theta = np.array([-2.5, 0.4, np.pi])
    >>> c, s = half_angle_cos_sin(np.cos(theta), np.sin(theta))
    >>> bool(np.allclose(c, np.cos(theta / 2)) and np.allclose(s, np.sin(theta / 2)))
    True
    """
    return functions_for(type(c)).half_cos_sin(c, s)


def relative_rotation_coefficients(r_D: tuple, half1: tuple) -> tuple:
    r"""The four coefficients :math:`L = \mathsf r_1^* \mathsf r_D` of the rotation equations
    :eq:`eq-ik-theta6-system` (thesis 4.14-4.17).

    With :math:`\mathsf r_D = r_w + r_x\mathbf i + r_y\mathbf j + r_z\mathbf k`,
    :math:`\mathsf r_1 = \bar c_1 + \bar s_1\mathbf k`, :math:`\bar c_1 =
    \cos\frac{\theta_1}{2}` and :math:`\bar s_1 = \sin\frac{\theta_1}{2}`:

    .. math::

        L = (r_w\bar c_1 + r_z\bar s_1,\; r_x\bar c_1 + r_y\bar s_1,\;
             r_y\bar c_1 - r_x\bar s_1,\; r_z\bar c_1 - r_w\bar s_1),

    the right-hand sides of the rotation part of :math:`M_2 = N_2`.

    Parameters
    ----------
    r_D : sequence of four floats or arrays
        :math:`(r_w, r_x, r_y, r_z)`, see :func:`target_rotation`.
    half1 : pair of floats or arrays
        :math:`(\bar c_1, \bar s_1)` (see :func:`half_angle_cos_sin`).

    Returns
    -------
    tuple of four floats or arrays
        :math:`(L_w, L_x, L_y, L_z)`.

    Examples
    --------
    >>> half = (math.cos(0.25), math.sin(0.25))
    >>> r_D = half[0], 0.0, 0.0, half[1]           # a pure turn about z by 0.5 rad
    >>> [round(c, 12) for c in relative_rotation_coefficients(r_D, half)]
    [1.0, 0.0, 0.0, 0.0]
    """
    w, x, y, z = r_D
    c, s = half1
    return c * w + s * z, c * x + s * y, c * y - s * x, c * z - s * w


def wrist_angles(L: tuple, sigma: ArrayLike) -> tuple[Array, Array, Array, Array, Array]:
    r""":math:`\theta_5` and the half sum and difference of :math:`\theta_{234}` and
    :math:`\theta_6`, chapter 8's :eq:`eq-ik-wrist`.

    Expanding :math:`\mathsf r_{-\mathbf j}(\theta_{234})\, \mathsf r_{-\mathbf k}(\theta_5)
    \, \mathsf r_{-\mathbf j}(\theta_6)` gives

    .. math::

        L = \Big(\bar c_5 \cos\tfrac{\Sigma}{2},\; \bar s_5 \sin\tfrac{\Delta}{2},\;
            -\bar c_5 \sin\tfrac{\Sigma}{2},\; -\bar s_5 \cos\tfrac{\Delta}{2}\Big),
        \qquad \Sigma = \theta_{234} + \theta_6,\ \Delta = \theta_{234} - \theta_6,

    with :math:`\bar c_5 = \cos\frac{\theta_5}{2}`, :math:`\bar s_5 = \sin\frac{\theta_5}{2}`.
    Hence, with the wrist branch :math:`\sigma = \pm 1` (the sign of :math:`\bar s_5`),

    .. math::

        \theta_5 = 2\operatorname{atan2}\Big(\sigma\sqrt{L_x^2 + L_z^2},\;
                   \sqrt{L_w^2 + L_y^2}\Big),\qquad
        \tfrac{\Sigma}{2} = \operatorname{atan2}(-L_y, L_w),\qquad
        \tfrac{\Delta}{2} = \operatorname{atan2}(\sigma L_x, -\sigma L_z).

    No division by :math:`\bar s_5` or :math:`\bar c_5` occurs (the thesis divides by them
    in 4.18-4.21 and then solves the 0/0-prone (4.28)); every quantity is an ``atan2`` of
    two directly computed numbers, so :math:`\theta_5` keeps full accuracy near 0 and
    :math:`\pm\pi`. Both wrist branches come from this one formula, :math:`\sigma = +1`
    ("not flipped") and :math:`\sigma = -1` ("flipped"); :math:`\theta_5` is computed as
    :math:`\sigma \cdot 2\operatorname{atan2}(\sqrt{L_x^2 + L_z^2}, \sqrt{L_w^2 + L_y^2})`,
    the same number (``atan2`` is odd in its first argument, exactly), with :math:`-\pi`
    written :math:`\pi`.

    Parameters
    ----------
    L : tuple of four floats or arrays
        Output of :func:`relative_rotation_coefficients`.
    sigma : float or ndarray
        Wrist branch, +1 (:math:`\theta_5 \in [0, \pi]`) or -1, broadcast against ``L``.

    Returns
    -------
    theta5, half_sum, half_diff : floats or ndarrays
        :math:`\theta_5 \in (-\pi, \pi]`, :math:`\Sigma/2` and :math:`\Delta/2`.
    c5bar, s5bar : floats or ndarrays
        The magnitudes :math:`|\bar c_5| = \sqrt{L_w^2 + L_y^2}` and
        :math:`|\bar s_5| = \sqrt{L_x^2 + L_z^2}`.

    Examples
    --------
    >>> L = (math.cos(0.3) * math.cos(0.1), math.sin(0.3) * math.sin(0.2),
    ...      -math.cos(0.3) * math.sin(0.1), -math.sin(0.3) * math.cos(0.2))
    >>> [round(v, 12) for v in wrist_angles(L, 1.0)[:3]]
    [0.6, 0.1, 0.2]
    >>> [round(v, 12) for v in wrist_angles(L, -1.0)[:3]]      # the flipped wrist
    [-0.6, 0.1, -2.94159265359]
    """
    Lw, Lx, Ly, Lz = L
    f = functions_for(type(Lw))
    c5bar = f.sqrt(Lw * Lw + Ly * Ly)
    s5bar = f.sqrt(Lx * Lx + Lz * Lz)
    theta5 = f.no_minus_pi(sigma * (2.0 * f.atan2(s5bar, c5bar)))    # atan2 is odd in y
    half_sum = f.atan2(-Ly, Lw)
    return theta5, half_sum, half_difference(L, sigma), c5bar, s5bar


def half_difference(L: tuple, sigma: ArrayLike) -> Array:
    r"""The half difference :math:`\tfrac{\theta_{234} - \theta_6}{2} =
    \operatorname{atan2}(\sigma L_x, -\sigma L_z)` of :func:`wrist_angles`, the one wrist
    quantity that depends on the branch :math:`\sigma` otherwise than by its sign.

    Examples
    --------
    >>> L = (math.cos(0.3) * math.cos(0.1), math.sin(0.3) * math.sin(0.2),
    ...      -math.cos(0.3) * math.sin(0.1), -math.sin(0.3) * math.cos(0.2))
    >>> round(half_difference(L, 1.0), 12), round(half_difference(L, -1.0), 12)
    (0.2, -2.94159265359)
    """
    _, Lx, _, Lz = L
    return functions_for(type(Lx)).atan2(sigma * Lx, -sigma * Lz)


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
    the wrist singularity, :math:`\bar c_5 \bar s_5 = 0`, where only
    :math:`\theta_{234} \pm \theta_6` is determined and
    :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` chooses :math:`\theta_{234}` from its family
    (:func:`feasible_theta234`).

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


def arm_plane_wrist(p5: tuple, c1: Array, s1: Array, d1: float) -> tuple[Array, Array]:
    r"""The wrist centre in the arm plane, :math:`(u_5, v_5) = (c_1 x_5 + s_1 y_5,\;
    z_5 - d_1)`.

    The arm plane, the plane of the planar chain of joints 2, 3 and 4, contains the shoulder
    point :math:`(0, 0, d_1)` and is spanned by :math:`x_1 = (c_1, s_1, 0)` (the :math:`u`
    axis) and the vertical (the :math:`v` axis).

    Parameters
    ----------
    p5 : sequence of three floats or arrays
        Wrist-centre coordinates :math:`(x_5, y_5, z_5)`.
    c1, s1 : float or ndarray
        Cosine and sine of :math:`\theta_1`, broadcast against ``p5``.
    d1 : float
        Base height.

    Returns
    -------
    u5, v5 : floats or ndarrays

    Examples
    --------
    >>> [round(v, 12) for v in arm_plane_wrist((0.3, -0.11235, 0.2), 1.0, 0.0, 0.1519)]
    [0.3, 0.0481]
    """
    x5, y5, z5 = p5
    return c1 * x5 + s1 * y5, z5 - d1


def wrist1_point(u5: Array, v5: Array, sin234: Array, cos234: Array, d5: float
                 ) -> tuple[Array, Array]:
    r"""The wrist-1 point in the arm plane, :eq:`eq-ik-wrist1-point`:
    :math:`(u_4, v_4) = (u_5 - d_5 \sin\theta_{234},\; v_5 + d_5\cos\theta_{234})`.

    The offset :math:`d_5` from the wrist-1 point to the wrist centre is :math:`Q_4`'s
    translation turned by :math:`\theta_2 + \theta_3`, :math:`d_5(\sin\theta_{234},
    -\cos\theta_{234})` in the plane; the thesis removes it with :math:`Q_4^{-1}` in
    (4.33)-(4.34) (where the printed :math:`Q_4^{-1}` is a copy of :math:`Q_5^{-1}`).
    :math:`(u_4, v_4)` is the point the planar two-link arm :math:`a_2, a_3` must reach.

    Parameters
    ----------
    u5, v5 : float or ndarray
        The wrist centre in the arm plane (:func:`arm_plane_wrist`).
    sin234, cos234 : float or ndarray
        :math:`\sin\theta_{234}` and :math:`\cos\theta_{234}` (for example from
        :func:`theta234_sine_cosine`).
    d5 : float

    Returns
    -------
    u4, v4 : floats or ndarrays

    Examples
    --------
    The thesis's pose, arm straight up: the wrist-1 point is :math:`|a_2 + a_3|` above the
    shoulder.

    >>> u4, v4 = wrist1_point(0.0, 0.54235, math.sin(-math.pi), math.cos(-math.pi), 0.08535)
    >>> round(u4, 12), round(v4, 12)
    (0.0, 0.457)
    """
    return u5 - d5 * sin234, v5 + d5 * cos234


def elbow_triangle(u4: Array, v4: Array, a2: float, a3: float
                   ) -> tuple[Array, Array, Array, Array, Array]:
    r"""The law of cosines of the planar two-link arm, the part both elbow branches share.

    See :func:`elbow_angles`: with :math:`\rho^2 = u_4^2 + v_4^2`,

    .. math::

        c = \operatorname{sgn}(a_2 a_3)(\rho^2 - a_2^2 - a_3^2) = 2|a_2 a_3|\cos\theta_3,
        \qquad k = \sqrt{K} = 2|a_2 a_3|\,|\sin\theta_3|,

    with :math:`K` clipped at zero out of reach, and the elbow's magnitude
    :math:`|\theta_3| = \operatorname{atan2}(k, c)`.

    Parameters
    ----------
    u4, v4 : float or ndarray
        The wrist-1 point in the arm plane, relative to the shoulder.
    a2, a3 : float

    Returns
    -------
    cos_num, k, outer, inner, angle3 : floats or ndarrays
        :math:`c`, :math:`k`, the reach margins of :func:`elbow_angles` and
        :math:`|\theta_3|`.

    Examples
    --------
    >>> c, k, outer, inner, angle3 = elbow_triangle(-0.3, 0.2, -0.24365, -0.21325)
    >>> round(angle3, 6)
    1.326258
    """
    f = functions_for(type(u4))
    rho2 = u4 * u4 + v4 * v4
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


def elbow_angles(u4: Array, v4: Array, a2: float, a3: float, elbow: ArrayLike,
                 triangle: tuple | None = None) -> tuple[Array, Array, Array, Array, Array]:
    r"""The planar two-link arm: :math:`\theta_3` by the law of cosines :eq:`eq-ik-theta3`,
    then :math:`\theta_2` by :eq:`eq-ik-theta2`.

    With :math:`\rho^2 = u_4^2 + v_4^2` the law of cosines (thesis 4.37) reads
    :math:`2 a_2 a_3 \cos\theta_3 = \rho^2 - a_2^2 - a_3^2`; squaring and subtracting from
    :math:`(2 a_2 a_3)^2` gives its sine,

    .. math::

        (2 a_2 a_3 \sin\theta_3)^2 = K = \big((a_2 + a_3)^2 - \rho^2\big)
                                         \big(\rho^2 - (a_2 - a_3)^2\big),

    and :math:`\theta_3 = \pm\arccos\frac{\rho^2 - a_2^2 - a_3^2}{2 a_2 a_3}` is computed as
    the same angle

    .. math::

        \theta_3 = \pm\operatorname{atan2}\!\big(\sqrt{K},\;
                   \operatorname{sgn}(a_2 a_3)(\rho^2 - a_2^2 - a_3^2)\big),\qquad
        \theta_2 = \operatorname{atan2}(v_4 k_1 - u_4 k_2,\; u_4 k_1 + v_4 k_2),

    with :math:`k_1 = a_2 + a_3\cos\theta_3`, :math:`k_2 = a_3 \sin\theta_3` (thesis 4.41),
    :math:`\cos\theta_3` and :math:`\sin\theta_3` taken from the same two numbers divided by
    :math:`2|a_2 a_3|`. Why not the ``arccos``: the factors of :math:`K` are products of sums
    and differences of lengths, so the sine keeps the digits the data carry near a stretched
    (:math:`\rho = |a_2 + a_3|`) or folded elbow, where it is exactly 0 when :math:`\rho`
    is; there the ``arccos`` of a cosine that rounds to :math:`1 - 2\varepsilon` returns
    :math:`\sqrt{4\varepsilon} \approx 3 \cdot 10^{-8}` (the thesis's printed
    :math:`\theta_3 = \pm 2.98 \cdot 10^{-8}`). Away from there both agree to rounding.
    Negative :math:`K` (the point is out of the two-link arm's reach) is clipped to zero:
    the arm is then stretched or folded towards the point.

    Parameters
    ----------
    u4, v4 : float or ndarray
        The wrist-1 point in the arm plane, relative to the shoulder.
    a2, a3 : float
        Upper-arm and forearm lengths (signed, as UR publishes them).
    elbow : float or ndarray
        The elbow branch: +1.0 ("up", the sign of :math:`\sin\theta_3` when
        :math:`a_2 a_3 > 0`) or -1.0 ("down"), or an array of signs that broadcasts against
        ``u4``.
    triangle : tuple, optional
        :func:`elbow_triangle` of the same point, when already computed (it is the same for
        both elbows).

    Returns
    -------
    theta2, theta3 : floats or ndarrays
    outer, inner : floats or ndarrays
        :math:`(|a_2 + a_3| - \rho)(|a_2 + a_3| + \rho)` and
        :math:`(\rho - |a_2 - a_3|)(\rho + |a_2 - a_3|)` before clipping; a negative value
        says the point is beyond the outer or inside the inner reach.
    sin3 : floats or ndarrays
        :math:`|\sin\theta_3|`.

    Examples
    --------
    >>> up = elbow_angles(-0.3, 0.2, -0.24365, -0.21325, 1.0)
    >>> down = elbow_angles(-0.3, 0.2, -0.24365, -0.21325, -1.0)
    >>> [round(v, 6) for v in (up[0], up[1], down[0], down[1])]
    [-1.199206, 1.326258, 0.0232, -1.326258]
    """
    f = functions_for(type(u4))
    cos_num, k, outer, inner, angle3 = triangle or elbow_triangle(u4, v4, a2, a3)
    m = 2.0 * abs(a2 * a3)
    # the folded elbow has theta3 = pi on both branches
    theta3 = f.no_minus_pi(angle3 * elbow)
    k1 = a2 + (a3 / m) * cos_num
    k2 = (a3 / m) * k
    # + 0.0: never -0.0, so theta2 is never -pi
    theta2 = f.atan2(v4 * k1 - elbow * (u4 * k2) + 0.0, u4 * k1 + elbow * (v4 * k2))
    return theta2, theta3, outer, inner, k / m


def reach_gap(u4: Array, v4: Array, a2: float, a3: float) -> Array:
    r"""How far the wrist-1 point lies outside the two-link arm's reach,
    :math:`\max(\rho - |a_2 + a_3|,\; |a_2 - a_3| - \rho,\; 0)`, :math:`\rho =
    \sqrt{u_4^2 + v_4^2}`: the distance by which the clipped elbow of :func:`elbow_angles`
    misses the point (in the arm plane).

    Examples
    --------
    >>> round(reach_gap(0.5, 0.0, -0.24365, -0.21325), 12), reach_gap(0.3, 0.0, -0.24365, -0.21325)
    (0.0431, 0.0)
    """
    f = functions_for(type(u4))
    rho = f.sqrt(u4 * u4 + v4 * v4)
    r_out, r_in = abs(a2 + a3), abs(a2 - a3)
    return f.maximum(f.maximum(rho - r_out, r_in - rho), 0.0)


def shoulder_gap(x5: Array, y5: Array, h2: Array, d4: float) -> Array:
    r"""How far the wrist centre lies inside the shoulder cylinder (0 outside):
    :math:`d_4 - \sqrt{x_5^2 + y_5^2} = \max(-h^2, 0) / (d_4 + \sqrt{x_5^2 + y_5^2})`, the
    distance (normal to the arm plane) by which the clipped :math:`\theta_1` of
    :func:`shoulder_angles` misses the pose; written with ``h2`` to keep its digits.

    Examples
    --------
    >>> round(shoulder_gap(0.1, 0.0, 0.1**2 - 0.11235**2, 0.11235), 12)
    0.01235
    """
    f = functions_for(type(x5))
    return f.clip0(-h2) / (d4 + f.sqrt(x5 * x5 + y5 * y5))


def feasible_theta234(u5: Array, v5: Array, theta234_ref: Array, a2: float, a3: float,
                      d5: float) -> Array:
    r"""The angle :math:`\theta_{234}` nearest to a wanted value for which the arm reaches.

    Used at a wrist singularity, where only :math:`\theta_{234} \pm \theta_6` is fixed by
    the orientation: the wrist-1 point :math:`(u_4, v_4) = (u_5, v_5) - d_5 (\sin t,
    -\cos t)` then moves on a circle of radius :math:`d_5` about the wrist centre
    :math:`P = (u_5, v_5)`, and the two-link arm reaches it iff
    :math:`(a_2 - a_3)^2 \le \rho^2(t) \le (a_2 + a_3)^2` with

    .. math::

        \rho^2(t) = |P|^2 + d_5^2 - 2 d_5 |P| \sin(t - \psi),
        \qquad \psi = \operatorname{atan2}(v_5, u_5).

    Each bound :math:`\rho^2 = R^2` gives :math:`\sin(t - \psi) = s_R =
    (|P|^2 + d_5^2 - R^2) / (2 d_5 |P|)`, solved as
    :math:`t = \psi + \operatorname{atan2}(2 d_5 |P| s_R, \pm\sqrt{F_R})` with
    :math:`F_R = (R - |P| + d_5)(R + |P| - d_5)(|P| + d_5 - R)(|P| + d_5 + R)` (digits kept
    at tangency). The wanted angle is returned when it is feasible, otherwise the feasible
    boundary point nearest to it; when nothing is feasible the outer-reach tangency (the
    closest approach) is returned and the caller's check rejects it.

    Parameters
    ----------
    u5, v5 : ndarray, shape (...)
        The wrist centre in the arm plane (see :func:`arm_plane_wrist`).
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
    u5, v5, theta234_ref = np.broadcast_arrays(u5, v5, theta234_ref)
    norm_p = np.sqrt(u5 * u5 + v5 * v5)
    psi = np.arctan2(v5, u5)
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


def candidate_solutions(X: ArrayLike, d1: float, a2: float, a3: float, d4: float, d5: float,
                        d6: float) -> NDArray[np.float64]:
    r"""The eight candidate solutions of chapter 8: the steps above, in the chapter's order.

    For the flange pose :math:`X = (\mathsf r, p)` of a UR arm in its base frame (UR's
    standard DH frames, no base or tool transform) and each shoulder branch :math:`s`
    (:math:`h_\pm = \pm h`), wrist branch :math:`w` (:math:`\sigma = \pm 1`) and elbow
    branch :math:`e`:

    1. :math:`\theta_1` from the wrist centre :math:`p_5 = p - d_6 z_6`
       (:eq:`eq-ik-wrist-point`, :eq:`eq-ik-theta1`);
    2. the coefficients :math:`L = \mathsf r_1^* \mathsf r_D` of the rotation equations,
       :math:`\mathsf r_D = \mathsf r\, q_0^*` (:eq:`eq-ik-theta6-system`);
    3. :math:`\theta_5`, :math:`\theta_{234}` and :math:`\theta_6` from :math:`L`
       (:eq:`eq-ik-wrist`);
    4. the wrist-1 point :math:`(u_4, v_4)` (:eq:`eq-ik-wrist1-point`), then the two-link arm
       :math:`\theta_3`, :math:`\theta_2` (:eq:`eq-ik-theta3`, :eq:`eq-ik-theta2`) and
       :math:`\theta_4 = \theta_{234} - \theta_2 - \theta_3`.

    Row :math:`k = 4s + 2e + w` holds :math:`(\theta_1, \dots, \theta_6)`, each in
    :math:`(-\pi, \pi]`. These are candidates: a step that has no exact solution (a target out
    of reach) clips, and :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` keeps a row only if it
    reproduces the pose. It returns these same rows, bit for bit, for every row it marks
    valid away from a wrist singularity. At a wrist singularity
    (:math:`\bar c_5 \bar s_5 = 0`) only :math:`\theta_{234} \pm \theta_6` is fixed and
    it chooses a member of the family; this function refuses such a pose.

    Parameters
    ----------
    X : array_like, shape (4, 4) or (..., 4, 4)
        Flange pose(s) :math:`X_{06}`, rigid transforms.
    d1, a2, a3, d4, d5, d6 : float
        UR's standard DH lengths (see
        :func:`dqlab.ik.ur_parameters <dqlab.ik.ur_closed_form.ur_parameters>`).

    Returns
    -------
    ndarray, shape (..., 8, 6)
        The joint angles :math:`\theta_1, \dots, \theta_6` of the eight rows.

    Raises
    ------
    ValueError
        If ``X`` is not a rigid transform, or a pose is wrist-singular.

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> from dqlab.ik import ur, ur_parameters
    >>> robot = ur3()
    >>> X = robot.fk([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> p = ur_parameters(robot)
    >>> rows = candidate_solutions(X, p["d1"], p["a2"], p["a3"], p["d4"], p["d5"], p["d6"])
    >>> rows[4].round(6)                                 # shoulder right, elbow up, wrist
    array([ 0.3, -1.2,  1.1, -0.4,  0.9,  0.2])
    >>> bool(np.array_equal(rows, ur(robot, X).solutions))
    True
    """
    X = check_transform(X, name="X")
    entries = components(X.reshape(X.shape[:-2] + (16,)))    # row by row
    p, z6 = entries[3:12:4], entries[2:11:4]                  # position, z axis
    q = quaternion_from_matrix_entries(*entries[0:3], *entries[4:7], *entries[8:11])
    r_D = target_rotation(q)                                           # r_D = q q0*
    p5 = wrist_center(p, z6, d6)                                       # eq-ik-wrist-point
    rows = [None] * 8
    for s, shoulder in enumerate((1.0, -1.0)):           # left (h+ = +h), right (h+ = -h)
        theta1, c1, s1, *_ = shoulder_angles(p5[0], p5[1], d4, shoulder)     # eq-ik-theta1
        L = relative_rotation_coefficients(r_D, half_angle_cos_sin(c1, s1))  # eq-ik-theta6-system
        u5, v5 = arm_plane_wrist(p5, c1, s1, d1)                       # the arm plane
        for w, sigma in enumerate((1.0, -1.0)):          # wrist not flipped, flipped
            theta5, half_sum, half_diff, c5bar, s5bar = wrist_angles(L, sigma)  # eq-ik-wrist
            if not functions_for(type(c5bar)).smallest(c5bar * s5bar) > 0.0:
                raise ValueError("X is wrist-singular (theta5 = 0 or pi): only theta234 +- "
                                 "theta6 is determined; dqlab.ik.ur chooses a member")
            theta234, theta6 = half_sum + half_diff, half_sum - half_diff
            sin234, cos234 = theta234_sine_cosine(L, sigma, c5bar, s5bar)
            u4, v4 = wrist1_point(u5, v5, sin234, cos234, d5)          # eq-ik-wrist1-point
            for e, elbow in enumerate((1.0, -1.0)):      # elbow up, down
                theta2, theta3, *_ = elbow_angles(u4, v4, a2, a3, elbow)   # eq-ik-theta3-atan2
                theta4 = theta234 - theta2 - theta3                        # and eq-ik-theta2
                rows[4 * s + 2 * e + w] = (theta1, theta2, theta3, wrap_angle(theta4),
                                           theta5, wrap_angle(theta6))
    return np.moveaxis(np.array(rows, dtype=float), (0, 1), (-2, -1))
