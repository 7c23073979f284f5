r"""Rotation matrices: elementary rotations, Euler angles, roll-pitch-yaw, axis-angle.

Conventions (chapter "Rotations in 3D"): matrices act on column vectors,
:math:`\mathbf v' = R\,\mathbf v` (active rotations), right-handed frames. The columns of
:math:`R_{AB}` are the axes of frame B written in frame A (the course notes' "direction
cosines"). Products read left to right about *moving* axes (:math:`R = R_1 R_2`: first
:math:`R_1`, then :math:`R_2` about the new axes) or right to left about *fixed* axes.
Every function takes array-likes and broadcasts over leading axes.
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import as_float_array, components, real_array, rotation_or_raise
from ._formulas import functions_for, norm_last_axis, orthonormality

_PI = np.pi
_TWO_PI = 2.0 * np.pi
_ONE_TURN = 1.0 / _TWO_PI

__all__ = [
    "rot_x", "rot_y", "rot_z", "matrix_from_euler_zxz", "euler_zxz_from_matrix",
    "matrix_from_rpy", "rpy_from_matrix", "matrix_from_axis_angle", "axis_angle_from_matrix",
    "rodrigues", "check_rotation_matrix", "skew", "wrap_angle",
]



def _elementary(theta, i, j):
    theta = as_float_array(theta, "theta")
    c, s = np.cos(theta), np.sin(theta)
    R = np.zeros(theta.shape + (3, 3))
    k = 3 - i - j
    R[..., k, k] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    return R


def rot_x(theta: ArrayLike) -> NDArray[np.float64]:
    r"""Rotation by ``theta`` about the x axis.

    .. math::

        R_x(\theta) = \begin{pmatrix} 1 & 0 & 0 \\ 0 & \cos\theta & -\sin\theta \\
        0 & \sin\theta & \cos\theta \end{pmatrix}

    Parameters
    ----------
    theta : array_like, shape (...)
        Angles in radians.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> np.round(rot_x(np.pi / 2), 12) + 0.0
    array([[ 1.,  0.,  0.],
           [ 0.,  0., -1.],
           [ 0.,  1.,  0.]])
    """
    return _elementary(theta, 1, 2)


def rot_y(theta: ArrayLike) -> NDArray[np.float64]:
    r"""Rotation by ``theta`` about the y axis.

    .. math::

        R_y(\theta) = \begin{pmatrix} \cos\theta & 0 & \sin\theta \\ 0 & 1 & 0 \\
        -\sin\theta & 0 & \cos\theta \end{pmatrix}

    Parameters
    ----------
    theta : array_like, shape (...)
        Angles in radians.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> rot_y(np.pi).round(12) + 0.0
    array([[-1.,  0.,  0.],
           [ 0.,  1.,  0.],
           [ 0.,  0., -1.]])
    """
    return _elementary(theta, 2, 0)


def rot_z(theta: ArrayLike) -> NDArray[np.float64]:
    r"""Rotation by ``theta`` about the z axis.

    .. math::

        R_z(\theta) = \begin{pmatrix} \cos\theta & -\sin\theta & 0 \\
        \sin\theta & \cos\theta & 0 \\ 0 & 0 & 1 \end{pmatrix}

    Parameters
    ----------
    theta : array_like, shape (...)
        Angles in radians.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    The course notes' example: the point :math:`(\sqrt 3, 0, 1)` turned by
    :math:`\pi/3` about z.

    >>> import numpy as np
    >>> np.round(rot_z(np.pi / 3) @ [np.sqrt(3), 0, 1], 6)
    array([0.866025, 1.5     , 1.      ])
    """
    return _elementary(theta, 0, 1)


def skew(v: ArrayLike) -> NDArray[np.float64]:
    r"""Cross-product matrix :math:`[\mathbf v]_\times`, with :math:`[\mathbf v]_\times
    \mathbf w = \mathbf v \times \mathbf w`.

    .. math::

        [\mathbf v]_\times = \begin{pmatrix} 0 & -v_z & v_y \\ v_z & 0 & -v_x \\
        -v_y & v_x & 0 \end{pmatrix}

    Parameters
    ----------
    v : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> skew([1, 2, 3]) @ [0, 0, 1]
    array([ 2., -1.,  0.])
    """
    v = as_float_array(v, "v", (3,))
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    S = np.zeros(v.shape[:-1] + (3, 3))
    S[..., 0, 1], S[..., 0, 2] = -z, y
    S[..., 1, 0], S[..., 1, 2] = z, -x
    S[..., 2, 0], S[..., 2, 1] = -y, x
    return S


def check_rotation_matrix(R: ArrayLike, tol: float = 1e-9, name: str = "R") -> NDArray[np.float64]:
    r"""Return ``R`` as a float array, or raise if it is not a rotation matrix.

    A rotation matrix is orthonormal, :math:`R^\mathsf{T} R = I`, with
    :math:`\det R = +1` (a determinant of -1 is a reflection).

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
    tol : float
        Largest accepted entry of :math:`|R^\mathsf{T} R - I|`.
    name : str
        Name used in the error message.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Raises
    ------
    ValueError
        Wrong shape, NaN/inf, not orthonormal, or a reflection.

    Examples
    --------
    >>> check_rotation_matrix(np.eye(3)).shape
    (3, 3)
    >>> check_rotation_matrix(np.diag([1.0, 1.0, -1.0]))
    Traceback (most recent call last):
    ...
    ValueError: R is a reflection (determinant -1), not a rotation
    """
    R = as_float_array(R, name, (3, 3))
    if R.ndim == 2:
        err, det = orthonormality(*R.tolist())
    else:
        e = components(R.reshape(R.shape[:-2] + (9,)))
        err, det = orthonormality(e[0:3], e[3:6], e[6:9])
    if not (err <= tol and det > 0.0):
        rotation_or_raise(name, err, det, tol)
    return R


def matrix_from_euler_zxz(angles: ArrayLike) -> NDArray[np.float64]:
    r"""Rotation matrix from classical Euler angles (precession, nutation, spin).

    The rotations are about moving axes: :math:`\psi` about z, then :math:`\theta` about
    the new x, then :math:`\varphi` about the new z:

    .. math::

        R = R_z(\psi)\, R_x(\theta)\, R_z(\varphi) =
        \begin{pmatrix}
        c_\psi c_\varphi - s_\psi c_\theta s_\varphi &
        -c_\psi s_\varphi - s_\psi c_\theta c_\varphi & s_\psi s_\theta \\
        s_\psi c_\varphi + c_\psi c_\theta s_\varphi &
        -s_\psi s_\varphi + c_\psi c_\theta c_\varphi & -c_\psi s_\theta \\
        s_\theta s_\varphi & s_\theta c_\varphi & c_\theta
        \end{pmatrix}

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        :math:`(\psi, \theta, \varphi)` in radians.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> R = matrix_from_euler_zxz([np.pi / 2, 0, np.pi / 2])   # nutation 0: Rz(pi)
    >>> np.round(R, 12) + 0.0
    array([[-1.,  0.,  0.],
           [ 0., -1.,  0.],
           [ 0.,  0.,  1.]])
    """
    angles = as_float_array(angles, "angles", (3,))
    return rot_z(angles[..., 0]) @ rot_x(angles[..., 1]) @ rot_z(angles[..., 2])


def euler_zxz_from_matrix(R: ArrayLike, *, tol: float = 1e-9, singular_tol: float = 1e-12
                          ) -> NDArray[np.float64]:
    r"""Classical Euler angles :math:`(\psi, \theta, \varphi)` of a rotation matrix.

    With :math:`\mathbf x, \mathbf y, \mathbf z` the columns of :math:`R` (course notes,
    chapter 1), in the regular case :math:`z_z \ne \pm 1`:

    .. math::

        \psi = \operatorname{atan2}(z_x, -z_y), \quad
        \theta = \operatorname{atan2}\Bigl(\sqrt{z_x^2 + z_y^2},\, z_z\Bigr) \in (0, \pi),
        \quad \varphi = \operatorname{atan2}(x_z, y_z).

    (:math:`\theta = \arccos z_z` in exact arithmetic; ``atan2`` keeps full accuracy near
    0 and :math:`\pi`.) The other solution :math:`(\psi + \pi, -\theta, \varphi + \pi)`
    is not returned.

    **Singular case** :math:`z_z = \pm 1` (nutation 0 or :math:`\pi`): only
    :math:`\psi + z_z\varphi = \operatorname{atan2}(y_x, x_x)` is determined. Convention:
    the spin is set to :math:`\varphi = 0` and the whole angle goes to the precession,
    :math:`\theta = \pi(1 - z_z)/2`, :math:`\psi = \operatorname{atan2}(y_x, x_x)`.
    The case is detected when :math:`\sqrt{z_x^2 + z_y^2} \le` ``singular_tol``.

    Near the singularity :math:`\psi` and :math:`\varphi` alone are ill-conditioned but
    :math:`\psi \pm \varphi` is not (:math:`r_{00} + r_{11} = (1 + c_\theta)\cos(\psi +
    \varphi)`, :math:`r_{10} - r_{01} = (1 + c_\theta)\sin(\psi + \varphi)`, and with
    :math:`1 - c_\theta` for the difference); :math:`\varphi` is computed from it, so the
    angles always reproduce :math:`R` to rounding error.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices (checked).
    tol : float
        Tolerance of the rotation-matrix check.
    singular_tol : float
        Threshold on :math:`\sin\theta` below which the singular branch is used.

    Returns
    -------
    ndarray, shape (..., 3)
        :math:`(\psi, \theta, \varphi)` with :math:`\psi, \varphi \in (-\pi, \pi]`,
        :math:`\theta \in [0, \pi]`.

    Examples
    --------
    >>> import numpy as np
    >>> R = matrix_from_euler_zxz([0.1, 0.2, 0.3])
    >>> np.round(euler_zxz_from_matrix(R), 12)
    array([0.1, 0.2, 0.3])
    >>> np.round(euler_zxz_from_matrix(matrix_from_euler_zxz([0.1, 0, 0.3])), 12)
    array([0.4, 0. , 0. ])
    """
    R = check_rotation_matrix(R, tol)
    zx, zy, zz = R[..., 0, 2], R[..., 1, 2], R[..., 2, 2]
    s = np.hypot(zx, zy)
    singular = s <= singular_tol
    # psi + phi and psi - phi stay accurate where psi and phi alone do not (near the
    # singularity): R00 + R11 = (1 + c_theta) cos(psi + phi), R10 - R01 = (1 + c_theta)
    # sin(psi + phi), R00 - R11 = (1 - c_theta) cos(psi - phi), R10 + R01 = (1 - c_theta)
    # sin(psi - phi). The spin is taken from the better-conditioned one.
    upper = zz >= 0.0
    total = np.where(upper, np.arctan2(R[..., 1, 0] - R[..., 0, 1], R[..., 0, 0] + R[..., 1, 1]),
                     np.arctan2(R[..., 1, 0] + R[..., 0, 1], R[..., 0, 0] - R[..., 1, 1]))
    psi = np.where(singular, total, np.arctan2(zx, -zy))
    theta = np.where(singular, np.where(upper, 0.0, np.pi), np.arctan2(s, zz))
    phi = np.where(upper, total - psi, psi - total)
    phi = np.where(singular, 0.0, wrap_angle(phi))
    return np.stack([psi, theta, phi], axis=-1)


def wrap_angle(theta: ArrayLike) -> NDArray[np.float64]:
    r"""Wrap angles to the interval :math:`(-\pi, \pi]`.

    .. math::

        \theta - 2\pi k, \qquad k = \operatorname{rint}\Big(\frac{\theta}{2\pi}\Big)

    (exact when :math:`|\theta| < \pi`), then :math:`-\pi` and the roundings of
    :math:`\theta / 2\pi` moved inside. The one angle wrapping of the package: every
    module calls it, on arrays or, in the single-value fast paths, on Python floats (which
    need no check and come back as floats).

    Parameters
    ----------
    theta : array_like, shape (...), or float
        Angles in radians.

    Returns
    -------
    ndarray, shape (...), or float
        ``theta - 2 pi k`` with the integer ``k`` that puts the result in (-pi, pi].

    Examples
    --------
    >>> import numpy as np
    >>> wrap_angle([np.pi, -np.pi, 3 * np.pi / 2, 0.5])
    array([ 3.14159265,  3.14159265, -1.57079633,  0.5       ])
    >>> wrap_angle(7.0)
    0.7168146928204138
    """
    if type(theta) is float:          # a Python float needs no check
        if -_PI < theta <= _PI:       # already inside: nothing to do
            return theta
    else:
        theta = real_array(theta, "theta")
    f = functions_for(type(theta))
    w = theta - _TWO_PI * f.rint(theta * _ONE_TURN)
    if not f.max_abs(w) < _PI:                # -pi, or a rounding of theta / (2 pi)
        w = f.where(w > _PI, w - _TWO_PI, f.where(w <= -_PI, w + _TWO_PI, w))
    return w


def matrix_from_rpy(rpy: ArrayLike) -> NDArray[np.float64]:
    r"""Rotation matrix from roll, pitch, yaw (Craig's fixed x-y-z angles).

    Roll :math:`\gamma` about x, then pitch :math:`\beta` about the fixed y, then yaw
    :math:`\alpha` about the fixed z:

    .. math::

        R = R_z(\alpha)\, R_y(\beta)\, R_x(\gamma) =
        \begin{pmatrix}
        c_\alpha c_\beta & c_\alpha s_\beta s_\gamma - s_\alpha c_\gamma &
        c_\alpha s_\beta c_\gamma + s_\alpha s_\gamma \\
        s_\alpha c_\beta & s_\alpha s_\beta s_\gamma + c_\alpha c_\gamma &
        s_\alpha s_\beta c_\gamma - c_\alpha s_\gamma \\
        -s_\beta & c_\beta s_\gamma & c_\beta c_\gamma
        \end{pmatrix}

    Parameters
    ----------
    rpy : array_like, shape (..., 3)
        :math:`(\gamma, \beta, \alpha)` = (roll, pitch, yaw) in radians.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> np.allclose(matrix_from_rpy([0, 0, 0.5]), rot_z(0.5))
    True
    """
    rpy = as_float_array(rpy, "rpy", (3,))
    return rot_z(rpy[..., 2]) @ rot_y(rpy[..., 1]) @ rot_x(rpy[..., 0])


def rpy_from_matrix(R: ArrayLike, *, tol: float = 1e-9, singular_tol: float = 1e-12
                    ) -> NDArray[np.float64]:
    r"""Roll, pitch, yaw :math:`(\gamma, \beta, \alpha)` of a rotation matrix (Craig).

    With :math:`\mathbf x, \mathbf y, \mathbf z` the columns of :math:`R`, in the regular
    case :math:`\beta \ne \pm\pi/2`:

    .. math::

        \alpha = \operatorname{atan2}(x_y, x_x), \quad
        \beta = \operatorname{atan2}\Bigl(-x_z, \sqrt{x_x^2 + x_y^2}\Bigr), \quad
        \gamma = \operatorname{atan2}(y_z, z_z).

    **Singular case** :math:`\beta = \pm\pi/2` (gimbal lock, :math:`x_z = \mp 1`): only
    :math:`\alpha - \operatorname{sign}(\beta)\,\gamma = \operatorname{atan2}(z_y, z_x)`
    is determined. Convention (Craig's): the yaw is set to :math:`\alpha = 0` and
    :math:`\gamma = -\operatorname{sign}(\beta)\operatorname{atan2}(z_y, z_x)`. The case is
    detected when :math:`\sqrt{x_x^2 + x_y^2} \le` ``singular_tol``.

    Near gimbal lock :math:`\alpha` and :math:`\gamma` alone are ill-conditioned but
    :math:`\alpha \mp \gamma` is not (:math:`r_{12} - r_{01} = (1 + s_\beta)
    \sin(\alpha - \gamma)`, :math:`r_{02} + r_{11} = (1 + s_\beta)\cos(\alpha - \gamma)`,
    and with :math:`1 - s_\beta` for the sum); the roll is computed from it, so the angles
    always reproduce :math:`R` to rounding error.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices (checked).
    tol : float
        Tolerance of the rotation-matrix check.
    singular_tol : float
        Threshold on :math:`\cos\beta` below which the singular branch is used.

    Returns
    -------
    ndarray, shape (..., 3)
        (roll, pitch, yaw) with pitch in :math:`[-\pi/2, \pi/2]`.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(rpy_from_matrix(matrix_from_rpy([0.1, 0.2, 0.3])), 12)
    array([0.1, 0.2, 0.3])
    >>> np.round(rpy_from_matrix(matrix_from_rpy([0.1, np.pi / 2, 0.3])), 6)
    array([-0.2     ,  1.570796,  0.      ])
    """
    R = check_rotation_matrix(R, tol)
    xx, xy, xz = R[..., 0, 0], R[..., 1, 0], R[..., 2, 0]
    c = np.hypot(xx, xy)
    singular = c <= singular_tol
    # yaw - roll (pitch > 0) and yaw + roll (pitch < 0) stay accurate near gimbal lock:
    # R12 - R01 = (1 + s_beta) sin(alpha - gamma), R02 + R11 = (1 + s_beta) cos(alpha - gamma),
    # R12 + R01 = -(1 - s_beta) sin(alpha + gamma), R11 - R02 = (1 - s_beta) cos(alpha + gamma).
    up = xz <= 0.0  # pitch >= 0
    combo = np.where(up, np.arctan2(R[..., 1, 2] - R[..., 0, 1], R[..., 0, 2] + R[..., 1, 1]),
                     np.arctan2(-(R[..., 1, 2] + R[..., 0, 1]), R[..., 1, 1] - R[..., 0, 2]))
    yaw = np.where(singular, 0.0, np.arctan2(xy, xx))
    pitch = np.where(singular, np.where(up, np.pi / 2, -np.pi / 2), np.arctan2(-xz, c))
    roll = wrap_angle(np.where(up, yaw - combo, combo - yaw))
    return np.stack([roll, pitch, yaw], axis=-1)


def _unit_axis(axis):
    axis = as_float_array(axis, "axis", (3,))
    n = norm_last_axis(axis)
    if np.any(n == 0.0):
        raise ValueError("axis is the zero vector, which has no direction")
    return axis / n[..., None]


def matrix_from_axis_angle(axis: ArrayLike, angle: ArrayLike) -> NDArray[np.float64]:
    r"""Rotation matrix of the rotation by ``angle`` about ``axis`` (Rodrigues' formula).

    .. math::

        R = I + \sin\theta\,[\mathbf n]_\times + (1 - \cos\theta)\,[\mathbf n]_\times^2
          = \cos\theta\, I + \sin\theta\,[\mathbf n]_\times
            + (1 - \cos\theta)\,\mathbf n \mathbf n^\mathsf{T}

    Parameters
    ----------
    axis : array_like, shape (..., 3)
        Rotation axes (normalised here; a zero axis raises).
    angle : array_like, shape (...)
        Angles in radians.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> np.allclose(matrix_from_axis_angle([0, 0, 5], 0.3), rot_z(0.3))
    True
    """
    n = _unit_axis(axis)
    angle = as_float_array(angle, "angle")
    c, s = np.cos(angle)[..., None, None], np.sin(angle)[..., None, None]
    nnT = n[..., :, None] * n[..., None, :]
    return c * np.eye(3) + s * skew(n) + (1.0 - c) * nnT


def axis_angle_from_matrix(R: ArrayLike, *, tol: float = 1e-9
                           ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Axis and angle of a rotation matrix, accurate for every angle in :math:`[0, \pi]`.

    .. math::

        \theta = \operatorname{atan2}\Bigl(\tfrac12 |\mathbf r|,\,
        \tfrac12(\operatorname{tr} R - 1)\Bigr), \qquad
        \mathbf r = (r_{21} - r_{12},\; r_{02} - r_{20},\; r_{10} - r_{01})
        = 2 \sin\theta\, \mathbf n .

    For :math:`\theta < \pi/2` the axis is :math:`\mathbf r / |\mathbf r|`. Near
    :math:`\pi`, :math:`\mathbf r` vanishes and the axis is read from the symmetric part,
    :math:`\tfrac12(R + R^\mathsf{T}) - \cos\theta\, I = (1 - \cos\theta)\,\mathbf n
    \mathbf n^\mathsf{T}` (its largest column), with the sign of :math:`\mathbf r`.
    For :math:`\theta = 0` the axis is undetermined and ``(1, 0, 0)`` is returned.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices (checked).
    tol : float
        Tolerance of the rotation-matrix check.

    Returns
    -------
    axis : ndarray, shape (..., 3)
    angle : ndarray, shape (...)
        In :math:`[0, \pi]`.

    Examples
    --------
    >>> import numpy as np
    >>> axis, angle = axis_angle_from_matrix(rot_y(np.pi))
    >>> axis + 0.0, round(float(angle), 12)
    (array([0., 1., 0.]), 3.14159265359)
    """
    R = check_rotation_matrix(R, tol)
    r = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                  R[..., 1, 0] - R[..., 0, 1]], axis=-1)
    rn = np.sqrt(np.sum(r * r, axis=-1))
    cos = 0.5 * (np.trace(R, axis1=-2, axis2=-1) - 1.0)
    angle = np.arctan2(0.5 * rn, cos)
    # small and medium angles: the skew part
    axis_skew = r / np.where(rn == 0.0, 1.0, rn)[..., None]
    # large angles: the largest column of the symmetric part
    B = 0.5 * (R + np.swapaxes(R, -1, -2)) - cos[..., None, None] * np.eye(3)
    k = np.argmax(np.diagonal(B, axis1=-2, axis2=-1), axis=-1)
    col = np.take_along_axis(B, k[..., None, None], axis=-1)[..., 0]
    cn = np.sqrt(np.sum(col * col, axis=-1))
    col = col / np.where(cn == 0.0, 1.0, cn)[..., None]
    col = np.where((np.sum(col * r, axis=-1) < 0.0)[..., None], -col, col)
    axis = np.where((cos < 0.0)[..., None], col, axis_skew)
    axis = np.where((rn == 0.0)[..., None] & (cos > 0.0)[..., None],
                    np.array([1.0, 0.0, 0.0]), axis)
    return axis, angle


def rodrigues(v: ArrayLike, axis: ArrayLike, angle: ArrayLike) -> NDArray[np.float64]:
    r"""Rotate vectors by ``angle`` about ``axis`` with Rodrigues' formula.

    .. math::

        \mathbf v' = \mathbf v\cos\theta + (\mathbf n \times \mathbf v)\sin\theta
                   + \mathbf n\,(\mathbf n\cdot\mathbf v)(1 - \cos\theta)

    Parameters
    ----------
    v : array_like, shape (..., 3)
        Vectors to rotate.
    axis : array_like, shape (..., 3)
        Rotation axes (normalised here; a zero axis raises).
    angle : array_like, shape (...)
        Angles in radians.

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> import numpy as np
    >>> np.round(rodrigues([2, 1, 1], [0, 0, 1], np.pi / 2), 12)
    array([-1.,  2.,  1.])
    """
    v = as_float_array(v, "v", (3,))
    n = _unit_axis(axis)
    angle = as_float_array(angle, "angle")[..., None]
    c, s = np.cos(angle), np.sin(angle)
    return (v * c + np.cross(n, v) * s
            + n * np.sum(n * v, axis=-1, keepdims=True) * (1.0 - c))
