r"""UR pose vectors: position and rotation vector, to and from every other pose form.

A Universal Robots controller speaks of a pose as six numbers
``p[x, y, z, rx, ry, rz]``: the position of the TCP in metres and its orientation as a
**rotation vector** :math:`\mathbf r = \theta\,\mathbf n` (unit axis times angle, radians),
both in the robot's base frame. URScript, RTDE (``actual_TCP_pose``) and the secondary
interface all use it; the teach pendant shows the same rotation as a rotation vector or as
roll-pitch-yaw angles.

A rotation vector and a unit quaternion are two forms of the same thing:

.. math::

    q = \Bigl(\cos\tfrac{\theta}{2},\; \tfrac{\sin(\theta/2)}{\theta}\,\mathbf r\Bigr),
    \qquad
    \mathbf r = \frac{2\operatorname{atan2}(|\mathbf u|, w)}{|\mathbf u|}\,\mathbf u
    \quad\text{for } q = (w, \mathbf u),\ w \ge 0 .

Both are computed without loss of accuracy near :math:`\theta = 0` (the factor
:math:`\sin(\theta/2)/\theta` through ``numpy.sinc``; :math:`\theta/|\mathbf u| \to 2/w`)
and near :math:`\theta = \pi` (the angle from ``atan2``, never from ``acos``).

**The half turn.** For :math:`\theta < \pi` the rotation vector with
:math:`|\mathbf r| \le \pi` is unique. At :math:`\theta = \pi`, :math:`\mathbf r` and
:math:`-\mathbf r` are the same rotation, and a matrix that rounding moved a hair off the
half turn would make the sign flip at random. Our choice, stable under rounding: within
``half_turn_tol`` of :math:`\pi`, the rotation vector points into the *upper half-space* --
:math:`r_z > 0`; or :math:`r_z = 0` and :math:`r_y > 0`; or :math:`r_z = r_y = 0` and
:math:`r_x > 0` (a component counts as zero when the axis component is below 1e-9). When
that means reversing the axis, the angle becomes :math:`2\pi - \theta`, so the rotation is
unchanged *exactly* and :math:`|\mathbf r|` may exceed :math:`\pi` by at most
``half_turn_tol``.
"""

import numpy as np

from .._checks import as_float_array, check_tolerance, components, stack_components
from .._formulas import (
    rotation_vector_from_matrix_entries,
    rotation_vector_from_quaternion_entries,
)
from ..dualquat import transform_from_dual_quaternion
from ..quaternion import matrix_from_quaternion
from ..rotations import check_rotation_matrix, matrix_from_rpy, rpy_from_matrix
from ..transforms import check_transform

__all__ = [
    "check_pose", "quaternion_from_rotation_vector", "rotation_vector_from_quaternion",
    "matrix_from_rotation_vector", "rotation_vector_from_matrix", "pose_from_transform",
    "transform_from_pose", "pose_from_dual_quaternion", "dual_quaternion_from_pose",
    "rpy_from_rotation_vector", "rotation_vector_from_rpy",
]

_AXIS_ZERO = 1e-9  # an axis component below this counts as zero in the half-turn sign rule
#: Longest rotation vector accepted, rad: beyond it the spacing of floats exceeds 1e-9 rad.
_MAX_ANGLE = 1e6


def check_pose(p, name="pose"):
    """Return UR pose vectors as a float array of shape ``(..., 6)``.

    Raises
    ------
    ValueError
        Naming ``name``, if the shape is wrong or a value is NaN or infinite.

    Examples
    --------
    >>> check_pose([0.1, 0.2, 0.3, 0, 0, 3.14])
    array([0.1 , 0.2 , 0.3 , 0.  , 0.  , 3.14])
    """
    return as_float_array(p, name, (6,))


def quaternion_from_rotation_vector(r):
    r"""Unit quaternion of rotation vectors.

    .. math::

        q = \Bigl(\cos\tfrac{\theta}{2},\; \tfrac{\sin(\theta/2)}{\theta}\,\mathbf r\Bigr),
        \qquad \theta = |\mathbf r|,

    with :math:`\sin(\theta/2)/\theta = \tfrac12\operatorname{sinc}(\theta / 2\pi)`
    (``numpy.sinc``), exact at and near :math:`\theta = 0`. Any length up to
    :math:`10^6` rad is accepted (:math:`|\mathbf r| > \pi` is a valid, non-canonical
    rotation vector; far beyond, a float no longer determines the rotation).

    Parameters
    ----------
    r : array_like, shape (..., 3)
        Rotation vectors, radians.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions ``(w, x, y, z)``.

    Examples
    --------
    >>> import numpy as np
    >>> quaternion_from_rotation_vector([0, 0, np.pi]).round(12) + 0.0
    array([0., 0., 0., 1.])
    """
    return _quaternions(as_float_array(r, "r", (3,)), "r")


def _quaternions(r, name):
    """:func:`quaternion_from_rotation_vector` of checked rotation vectors; ``name`` is what
    an error message calls them."""
    scale = np.max(np.abs(r), axis=-1, initial=0.0)
    safe = np.where(scale > 0.0, scale, 1.0)[..., None]
    theta = scale * np.sqrt(np.sum((r / safe) ** 2, axis=-1))     # |r| without overflow
    if np.any(theta > _MAX_ANGLE):
        raise ValueError(f"{name} is too long: a rotation vector of {float(np.max(theta)):.3g}"
                         f" rad is beyond {_MAX_ANGLE:g} rad, where a float no longer "
                         "determines the rotation to 1e-9 rad (the angle is too large)")
    w = np.cos(0.5 * theta)
    xyz = r * (0.5 * np.sinc(theta / (2.0 * np.pi)))[..., None]
    return np.concatenate([w[..., None], xyz], axis=-1)


def rotation_vector_from_quaternion(q, *, tol=1e-9, half_turn_tol=1e-12):
    r"""Rotation vectors of unit quaternions (``q`` and ``-q`` give the same result).

    With :math:`q = (w, \mathbf u)` taken with :math:`w \ge 0`:

    .. math::

        \theta = 2\operatorname{atan2}(|\mathbf u|, w) \in [0, \pi], \qquad
        \mathbf r = \frac{\theta}{|\mathbf u|}\,\mathbf u
        \quad (\to 2\mathbf u / w \text{ as } |\mathbf u| \to 0).

    Within ``half_turn_tol`` of :math:`\theta = \pi` the sign is fixed by the upper
    half-space rule of the module docstring, with angle :math:`2\pi - \theta` when the
    axis is reversed (the rotation is unchanged).

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions ``(w, x, y, z)``.
    tol : float
        Tolerance on :math:`|q| = 1`.
    half_turn_tol : float
        How close to :math:`\pi` (radians) the half-turn sign rule applies.

    Returns
    -------
    ndarray, shape (..., 3)
        Rotation vectors with :math:`|\mathbf r| \le \pi + \text{half\_turn\_tol}`.

    Raises
    ------
    ValueError
        If ``q`` has the wrong shape, holds NaN/inf, or is not unit within ``tol``.

    Examples
    --------
    >>> import numpy as np
    >>> rotation_vector_from_quaternion([np.cos(0.25), 0, np.sin(0.25), 0]).round(12) + 0.0
    array([0. , 0.5, 0. ])

    A half turn about -z comes out as a half turn about +z (the same rotation):

    >>> rotation_vector_from_quaternion([0, 0, 0, -1]).round(12) + 0.0
    array([0.        , 0.        , 3.14159265])
    """
    tol = check_tolerance(tol, "tol")
    half_turn_tol = check_tolerance(half_turn_tol, "half_turn_tol")
    q = as_float_array(q, "q", (4,))
    with np.errstate(over="ignore"):
        norm = np.sqrt(np.sum(q * q, axis=-1))
    bad = ~(np.abs(norm - 1.0) <= tol)
    if np.any(bad):
        worst = float(np.max(np.abs(norm - 1.0)))
        raise ValueError(f"q must be a unit quaternion: | |q| - 1 | = {worst:.3g} > tol = {tol:g}")
    q = np.where((q[..., :1] < 0.0), -q, q)
    r = stack_components(list(rotation_vector_from_quaternion_entries(*components(q))))
    return _half_turn(r, half_turn_tol)


def _half_turn(r, half_turn_tol):
    """Within ``half_turn_tol`` of a half turn, point the axis into the upper half-space,
    keeping the rotation exact (see the module docstring)."""
    theta = np.sqrt(np.sum(r * r, axis=-1))
    n = r / np.where(theta > 0.0, theta, 1.0)[..., None]
    nx, ny, nz = n[..., 0], n[..., 1], n[..., 2]
    zero_z, zero_y = np.abs(nz) <= _AXIS_ZERO, np.abs(ny) <= _AXIS_ZERO
    upper = (nz > _AXIS_ZERO) | (zero_z & (ny > _AXIS_ZERO)) | (zero_z & zero_y & (nx > 0.0))
    flip = (np.pi - theta <= half_turn_tol) & ~upper
    if not np.any(flip):
        return r
    return np.where(flip[..., None], -(2.0 * np.pi - theta)[..., None] * n, r)


def matrix_from_rotation_vector(r):
    r"""Rotation matrices of rotation vectors (Rodrigues' formula, through the quaternion).

    Parameters
    ----------
    r : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> matrix_from_rotation_vector([0, 0, np.pi / 2]).round(12) + 0.0
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    return matrix_from_quaternion(quaternion_from_rotation_vector(r))


def rotation_vector_from_matrix(R, *, tol=1e-9, half_turn_tol=1e-12):
    r"""Rotation vectors of rotation matrices (through Shepperd's quaternion: the kernel
    ``dqlab._formulas.rotation_vector_from_matrix_entries``, shared with the rest of
    dqlab, and the half-turn rule of the module docstring).

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices (checked within ``tol``).
    tol, half_turn_tol : float
        See :func:`rotation_vector_from_quaternion`.

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> import numpy as np
    >>> rotation_vector_from_matrix(np.diag([1.0, -1.0, -1.0])).round(12) + 0.0
    array([3.14159265, 0.        , 0.        ])
    """
    tol = check_tolerance(tol, "tol")
    half_turn_tol = check_tolerance(half_turn_tol, "half_turn_tol")
    return _rotation_vectors(check_rotation_matrix(R, tol=tol), half_turn_tol)


def _rotation_vectors(R, half_turn_tol):
    """Rotation vectors of checked rotation matrices ``(..., 3, 3)``: the kernel, then the
    half-turn rule."""
    entries = components(R.reshape(R.shape[:-2] + (9,)))
    r = stack_components(list(rotation_vector_from_matrix_entries(*entries)))
    return _half_turn(r, half_turn_tol)


def pose_from_transform(T, *, tol=1e-9, half_turn_tol=1e-12):
    r"""UR pose vectors ``[x, y, z, rx, ry, rz]`` of homogeneous transforms.

    .. math::

        X = \begin{pmatrix} R & \mathbf p \\ \mathbf 0^\mathsf{T} & 1 \end{pmatrix}
        \;\mapsto\; (\mathbf p, \mathbf r), \qquad R = \exp([\mathbf r]_\times)

    Parameters
    ----------
    T : array_like, shape (..., 4, 4)
        Rigid transforms, e.g. ``X_WT`` (pose of the TCP in the base frame), metres.
    tol, half_turn_tol : float
        Rigidity tolerance, and the half-turn sign rule of
        :func:`rotation_vector_from_quaternion`.

    Returns
    -------
    ndarray, shape (..., 6)

    Raises
    ------
    ValueError
        If ``T`` is not a rigid transform, has the wrong shape, or holds NaN/inf.

    Examples
    --------
    The thesis's recorded pose (flange of the UR3 at its "home" joints), a half turn about
    :math:`(0, -1, 1)/\sqrt 2`, written with :math:`r_z > 0`:

    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> X_WF = ur3().fk([0, -np.pi / 2, 0, -np.pi / 2, 0, 0])
    >>> pose_from_transform(X_WF).round(5) + 0.0
    array([ 0.     , -0.19425,  0.69415,  0.     , -2.22144,  2.22144])
    """
    tol = check_tolerance(tol, "tol")
    half_turn_tol = check_tolerance(half_turn_tol, "half_turn_tol")
    T = check_transform(T, tol=tol)
    r = _rotation_vectors(T[..., :3, :3], half_turn_tol)
    return np.concatenate([T[..., :3, 3], r], axis=-1)


def transform_from_pose(p):
    r"""Homogeneous transforms of UR pose vectors ``[x, y, z, rx, ry, rz]``.

    Parameters
    ----------
    p : array_like, shape (..., 6)
        Positions in metres, rotation vectors in radians.

    Returns
    -------
    ndarray, shape (..., 4, 4)

    Raises
    ------
    ValueError
        If ``p`` has the wrong shape or holds NaN/inf.

    Examples
    --------
    >>> import numpy as np
    >>> transform_from_pose([0.1, 0.2, 0.3, 0, 0, np.pi / 2]).round(12) + 0.0
    array([[ 0. , -1. ,  0. ,  0.1],
           [ 1. ,  0. ,  0. ,  0.2],
           [ 0. ,  0. ,  1. ,  0.3],
           [ 0. ,  0. ,  0. ,  1. ]])
    """
    p = check_pose(p, "p")
    T = np.zeros(p.shape[:-1] + (4, 4))
    T[..., :3, :3] = matrix_from_quaternion(_quaternions(p[..., 3:], "the rotation p[..., 3:]"))
    T[..., :3, 3] = p[..., :3]
    T[..., 3, 3] = 1.0
    return T


def pose_from_dual_quaternion(Q, *, tol=1e-9, half_turn_tol=1e-12):
    r"""UR pose vectors of unit dual quaternions :math:`Q = q_r + \varepsilon q_d`.

    The position is :math:`(0, \mathbf p) = 2 q_d q_r^*`; the rotation vector is that of
    :math:`q_r` (:func:`rotation_vector_from_quaternion`).

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Unit dual quaternions ``(q_r, q_d)`` (checked within ``tol``).
    tol, half_turn_tol : float

    Returns
    -------
    ndarray, shape (..., 6)

    Examples
    --------
    >>> pose_from_dual_quaternion([1, 0, 0, 0, 0, 0.05, 0, 0])
    array([0.1, 0. , 0. , 0. , 0. , 0. ])
    """
    tol = check_tolerance(tol, "tol")
    half_turn_tol = check_tolerance(half_turn_tol, "half_turn_tol")
    Q = as_float_array(Q, "Q", (8,))
    T = transform_from_dual_quaternion(Q, tol=tol)  # checks that Q is a unit dual quaternion
    r = rotation_vector_from_quaternion(Q[..., :4], tol=tol, half_turn_tol=half_turn_tol)
    return np.concatenate([T[..., :3, 3], r], axis=-1)


def dual_quaternion_from_pose(p):
    r"""Unit dual quaternions :math:`q_r + \varepsilon\,\tfrac12 (0, \mathbf p)\, q_r` of UR poses.

    :math:`q_r` is :func:`quaternion_from_rotation_vector` of ``p[..., 3:]`` (so
    :math:`w \ge 0` for :math:`|\mathbf r| \le \pi`).

    Parameters
    ----------
    p : array_like, shape (..., 6)

    Returns
    -------
    ndarray, shape (..., 8)

    Examples
    --------
    >>> dual_quaternion_from_pose([0.1, 0, 0, 0, 0, 0]) + 0.0
    array([1.  , 0.  , 0.  , 0.  , 0.  , 0.05, 0.  , 0.  ])
    """
    p = check_pose(p, "p")
    qr = _quaternions(p[..., 3:], "the rotation p[..., 3:]")
    w, x, y, z = np.moveaxis(qr, -1, 0)
    tx, ty, tz = np.moveaxis(0.5 * p[..., :3], -1, 0)
    # q_d = (0, t/2) q_r, written out (Hamilton product with a pure quaternion)
    qd = np.stack([-tx * x - ty * y - tz * z,
                   tx * w + ty * z - tz * y,
                   -tx * z + ty * w + tz * x,
                   tx * y - ty * x + tz * w], axis=-1)
    return np.concatenate([qr, qd], axis=-1)


def rpy_from_rotation_vector(r, *, singular_tol=1e-12):
    r"""Roll, pitch, yaw as the teach pendant shows them, from rotation vectors.

    The pendant's RPY (and URScript's ``rotvec2rpy``) are Craig's fixed x-y-z angles,
    :math:`R = R_z(\text{yaw})\,R_y(\text{pitch})\,R_x(\text{roll})`
    (:func:`dqlab.rotations.rpy_from_matrix`, with its gimbal-lock convention).

    Parameters
    ----------
    r : array_like, shape (..., 3)
    singular_tol : float
        Passed to :func:`dqlab.rotations.rpy_from_matrix`.

    Returns
    -------
    ndarray, shape (..., 3)
        (roll, pitch, yaw) in radians.

    Examples
    --------
    >>> import numpy as np
    >>> rpy_from_rotation_vector([0, 0, 0.3]).round(12) + 0.0
    array([0. , 0. , 0.3])
    """
    singular_tol = check_tolerance(singular_tol, "singular_tol")
    return rpy_from_matrix(matrix_from_rotation_vector(r), singular_tol=singular_tol)


def rotation_vector_from_rpy(rpy, *, half_turn_tol=1e-12):
    r"""Rotation vectors of roll-pitch-yaw angles (URScript's ``rpy2rotvec``).

    Parameters
    ----------
    rpy : array_like, shape (..., 3)
        (roll, pitch, yaw), radians; :math:`R = R_z(\text{yaw})R_y(\text{pitch})R_x(\text{roll})`.
    half_turn_tol : float
        See :func:`rotation_vector_from_quaternion`.

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> import numpy as np
    >>> rotation_vector_from_rpy([np.pi, 0, 0]).round(12) + 0.0
    array([3.14159265, 0.        , 0.        ])
    """
    half_turn_tol = check_tolerance(half_turn_tol, "half_turn_tol")
    return rotation_vector_from_matrix(matrix_from_rpy(rpy), half_turn_tol=half_turn_tol)
