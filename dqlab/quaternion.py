r"""Quaternion algebra and rotations by unit quaternions.

Conventions (the book's preface): a quaternion is stored scalar first,
``q = (w, x, y, z)`` for :math:`q = w + x\,i + y\,j + z\,k`, multiplied with the Hamilton
rule :math:`i^2 = j^2 = k^2 = ijk = -1`; a unit quaternion acts on a vector by the active
rotation :math:`p' = q\,p\,q^*`. Every function takes array-likes of shape ``(..., 4)``
(quaternions), ``(..., 3)`` (vectors) or ``(..., 3, 3)`` (matrices) and broadcasts over the
leading axes. pyquaternion uses the same order; scipy's ``(x, y, z, w)`` does not (nor do
ROS messages or Eigen's ``coeffs()``): :func:`quaternion_from_xyzw` and
:func:`xyzw_from_quaternion` convert. A unit quaternion given in the wrong order is a unit
quaternion of another rotation, so no check can catch it: convert at the boundary.

Array functions do the work; :class:`Quaternion` is a thin wrapper for notebooks.
"""


import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import (
    as_float_array,
    batch_shape,
    batched,
    check_finite,
    components,
    float_array,
    pack,
    rotation_or_raise,
    stack_components,
    unit_quaternion_or_raise,
)
from ._formulas import (
    matrix_entries_from_quaternion,
    norm_last_axis,
    orthonormality,
    quaternion_from_matrix_entries,
    quaternion_mul,
    quaternion_rotate,
)
from ._wrapper import ArrayWrapper, array_of, float_if_single

__all__ = [
    "quaternion_product", "quaternion_conjugate", "quaternion_norm", "quaternion_inverse",
    "quaternion_normalize", "check_unit_quaternion", "rotate_vector",
    "quaternion_from_axis_angle", "axis_angle_from_quaternion", "quaternion_from_matrix",
    "matrix_from_quaternion", "quaternion_exp", "quaternion_log", "quaternion_power", "slerp",
    "quaternion_distance", "quaternion_from_pyquaternion", "pyquaternion_from_quaternion",
    "quaternion_identity", "Quaternion",
]

_Q = (4,)
_V = (3,)
_M = (3, 3)


# --------------------------------------------------------------------------------------
# Input handling (kept lean: a float64 ndarray goes through untouched)


def _in(x, name, trailing=_Q):
    return float_array(x, name, trailing)


# --------------------------------------------------------------------------------------
# Algebra


def quaternion_identity(shape=()):
    """Identity quaternion(s) ``(1, 0, 0, 0)`` of shape ``shape + (4,)``.

    Examples
    --------
    >>> quaternion_identity()
    array([1., 0., 0., 0.])
    >>> quaternion_identity((2,)).shape
    (2, 4)
    """
    q = np.zeros(batch_shape(shape) + (4,))
    q[..., 0] = 1.0
    return q


def quaternion_product(a: ArrayLike, b: ArrayLike) -> NDArray[np.float64]:
    r"""Hamilton product :math:`a b` of quaternions.

    .. math::

        a b = (a_w b_w - \mathbf a\cdot\mathbf b,\;
               a_w \mathbf b + b_w \mathbf a + \mathbf a \times \mathbf b)

    Parameters
    ----------
    a, b : array_like, shape (..., 4)
        Quaternions ``(w, x, y, z)``; leading axes broadcast.

    Returns
    -------
    ndarray, shape (..., 4)
        The product. As rotations, :math:`ab` applies ``b`` first, then ``a``.

    Raises
    ------
    ValueError
        If a shape is wrong or an input holds NaN or infinity.

    Examples
    --------
    >>> i, j = [0, 1, 0, 0], [0, 0, 1, 0]
    >>> quaternion_product(i, j)        # i j = k
    array([0., 0., 0., 1.])
    >>> quaternion_product(j, i)        # j i = -k
    array([ 0.,  0.,  0., -1.])
    """
    a = _in(a, "a")
    b = _in(b, "b")
    if a.ndim == 1 and b.ndim == 1:
        return pack(quaternion_mul(*a.tolist(), *b.tolist()), (a, "a", _Q), (b, "b", _Q))
    check_finite(a, "a")
    check_finite(b, "b")
    return batched(_product_kernel, [(a, 1), (b, 1)], _Q)


def _product_kernel(a, b):
    return stack_components(quaternion_mul(*components(a), *components(b)))


def quaternion_conjugate(q: ArrayLike) -> NDArray[np.float64]:
    r"""Conjugate :math:`q^* = (w, -x, -y, -z)`; the inverse rotation when ``q`` is unit.

    Parameters
    ----------
    q : array_like, shape (..., 4)

    Returns
    -------
    ndarray, shape (..., 4)

    Examples
    --------
    >>> quaternion_conjugate([1, 2, 3, 4])
    array([ 1., -2., -3., -4.])
    """
    q = as_float_array(q, "q", _Q)
    out = -q
    out[..., 0] = q[..., 0]
    return out


def quaternion_norm(q: ArrayLike) -> NDArray[np.float64]:
    r"""Norm :math:`|q| = \sqrt{w^2 + x^2 + y^2 + z^2}`.

    It is multiplicative: :math:`|ab| = |a|\,|b|`.

    Parameters
    ----------
    q : array_like, shape (..., 4)

    Returns
    -------
    ndarray, shape (...)

    Examples
    --------
    >>> float(quaternion_norm([1, 1, 1, 1]))
    2.0
    """
    q = as_float_array(q, "q", _Q)
    return norm_last_axis(q)


def _nonzero_norm(q, name):
    n = norm_last_axis(q)
    if np.any(n == 0.0):
        raise ValueError(f"{name} is the zero quaternion, which has no inverse or direction")
    return n


def quaternion_inverse(q: ArrayLike) -> NDArray[np.float64]:
    r"""Inverse :math:`q^{-1} = q^* / |q|^2` (equal to :math:`q^*` for a unit quaternion).

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Non-zero quaternions.

    Returns
    -------
    ndarray, shape (..., 4)

    Raises
    ------
    ValueError
        If ``q`` is zero, holds NaN/inf, or has the wrong shape.

    Examples
    --------
    >>> quaternion_inverse([0, 0, 2, 0]) + 0.0
    array([ 0. ,  0. , -0.5,  0. ])
    """
    q = as_float_array(q, "q", _Q)
    n = _nonzero_norm(q, "q")
    return quaternion_conjugate(q) / n[..., None] / n[..., None]


def quaternion_normalize(q: ArrayLike) -> NDArray[np.float64]:
    r"""Unit quaternion :math:`q / |q|` with the same direction.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Non-zero, finite quaternions.

    Returns
    -------
    ndarray, shape (..., 4)

    Raises
    ------
    ValueError
        If ``q`` is zero, holds NaN/inf, or has the wrong shape.

    Examples
    --------
    >>> quaternion_normalize([0, 3, 0, 4])
    array([0. , 0.6, 0. , 0.8])
    """
    q = as_float_array(q, "q", _Q)
    return q / _nonzero_norm(q, "q")[..., None]


def check_unit_quaternion(q: ArrayLike, tol: float = 1e-9, name: str = "q") -> NDArray[np.float64]:
    r"""Return ``q`` as a float array, or raise if it is not a unit quaternion.

    Parameters
    ----------
    q : array_like, shape (..., 4)
    tol : float
        Largest accepted :math:`\bigl||q| - 1\bigr|`.
    name : str
        Name used in the error message.

    Returns
    -------
    ndarray, shape (..., 4)

    Raises
    ------
    ValueError
        Wrong shape, NaN/inf, zero quaternion, or norm not 1 within ``tol``.

    Examples
    --------
    >>> check_unit_quaternion([0, 0, 0, 1])
    array([0., 0., 0., 1.])
    >>> check_unit_quaternion([1, 1, 0, 0])
    Traceback (most recent call last):
    ...
    ValueError: q must be a unit quaternion (norm 1 within 1e-09), got norm 1.41421356237; ...
    """
    q = as_float_array(q, name, _Q)
    unit_quaternion_or_raise(components(q), name, tol)
    return q


def rotate_vector(q: ArrayLike, v: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Rotate vectors by unit quaternions: :math:`v' = q\,v\,q^*` (active rotation).

    With :math:`q = (w, \mathbf u)` and :math:`\mathbf t = 2\,\mathbf u \times \mathbf v`
    this is computed as

    .. math::

        \mathbf v' = \mathbf v + w\,\mathbf t + \mathbf u \times \mathbf t .

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions (not normalised here: a non-unit ``q`` raises).
    v : array_like, shape (..., 3)
        Vectors; leading axes broadcast with those of ``q``.
    tol : float
        Tolerance on :math:`|q| = 1`.

    Returns
    -------
    ndarray, shape (..., 3)

    Raises
    ------
    ValueError
        Wrong shapes, NaN/inf, or ``q`` not unit.

    Examples
    --------
    The thesis's example, the point (2, 1, 1) turned by 90 degrees about z:

    >>> import numpy as np
    >>> q = quaternion_from_axis_angle([0, 0, 1], np.pi / 2)
    >>> np.round(rotate_vector(q, [2, 1, 1]), 12)
    array([-1.,  2.,  1.])
    """
    q = _in(q, "q")
    v = _in(v, "v", _V)
    if q.ndim == 1 and v.ndim == 1:
        qc = q.tolist()
        unit_quaternion_or_raise(qc, "q", tol)
        return pack(quaternion_rotate(*qc, *v.tolist()), (v, "v", _V))
    check_finite(q, "q")
    check_finite(v, "v")

    def kernel(q, v):
        qc = components(q)
        unit_quaternion_or_raise(qc, "q", tol)
        return stack_components(quaternion_rotate(*qc, *components(v)))

    return batched(kernel, [(q, 1), (v, 1)], _V)


# --------------------------------------------------------------------------------------
# Conversions


def quaternion_from_axis_angle(axis: ArrayLike, angle: ArrayLike) -> NDArray[np.float64]:
    r"""Unit quaternion of the rotation by ``angle`` about ``axis``.

    .. math::

        q = \left(\cos\tfrac{\theta}{2},\; \sin\tfrac{\theta}{2}\,\mathbf n\right),
        \qquad \mathbf n = \mathbf{axis} / |\mathbf{axis}|

    Parameters
    ----------
    axis : array_like, shape (..., 3)
        Rotation axes, normalised here (a zero axis raises).
    angle : array_like, shape (...)
        Angles in radians (right-hand rule).

    Returns
    -------
    ndarray, shape (..., 4)

    Raises
    ------
    ValueError
        Zero axis, NaN/inf, wrong shape.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(quaternion_from_axis_angle([0, 0, 2], np.pi / 2), 6)
    array([0.707107, 0.      , 0.      , 0.707107])
    """
    axis = as_float_array(axis, "axis", _V)
    angle = as_float_array(angle, "angle")
    n = norm_last_axis(axis)
    if np.any(n == 0.0):
        raise ValueError("axis is the zero vector, which has no direction")
    half = 0.5 * angle
    s = np.sin(half) / n
    return stack_components([np.cos(half)] + [axis[..., i] * s for i in range(3)])


def axis_angle_from_quaternion(q: ArrayLike, *, tol: float = 1e-9
                               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Axis and angle of the rotation of a unit quaternion.

    .. math::

        \theta = 2\,\operatorname{atan2}(|\mathbf u|, |w|) \in [0, \pi], \qquad
        \mathbf n = \operatorname{sign}(w)\,\mathbf u / |\mathbf u|

    ``q`` and ``-q`` give the same result. For the identity (:math:`\theta = 0`) the axis
    is undetermined and ``(1, 0, 0)`` is returned.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions.
    tol : float
        Tolerance on :math:`|q| = 1`.

    Returns
    -------
    axis : ndarray, shape (..., 3)
        Unit axes.
    angle : ndarray, shape (...)
        Angles in :math:`[0, \pi]`.

    Examples
    --------
    >>> import numpy as np
    >>> axis, angle = axis_angle_from_quaternion([0, 0, 0, -1])
    >>> axis, round(float(angle), 12)
    (array([ 0.,  0., -1.]), 3.14159265359)
    """
    q = check_unit_quaternion(q, tol)
    u = q[..., 1:]
    s = np.sqrt(np.sum(u * u, axis=-1))
    w = q[..., 0]
    angle = 2.0 * np.arctan2(s, np.abs(w))
    sign = np.where(w < 0.0, -1.0, 1.0)
    zero = s == 0.0
    axis = u * (sign / np.where(zero, 1.0, s))[..., None]
    axis = np.where(zero[..., None], np.array([1.0, 0.0, 0.0]), axis)
    return axis, angle


def quaternion_from_matrix(R: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Unit quaternion (with :math:`w \ge 0`) of a rotation matrix, by Shepperd's method.

    For the active convention :math:`R\,\mathbf v = q\,\mathbf v\,q^*` the symmetric matrix
    :math:`K = 4\,q q^\mathsf{T}` is a linear function of the entries of :math:`R`:

    .. math::

        K = \begin{pmatrix}
        1 + r_{00} + r_{11} + r_{22} & r_{21} - r_{12} & r_{02} - r_{20} & r_{10} - r_{01}\\
        r_{21} - r_{12} & 1 + r_{00} - r_{11} - r_{22} & r_{01} + r_{10} & r_{02} + r_{20}\\
        r_{02} - r_{20} & r_{01} + r_{10} & 1 - r_{00} + r_{11} - r_{22} & r_{12} + r_{21}\\
        r_{10} - r_{01} & r_{02} + r_{20} & r_{12} + r_{21} & 1 - r_{00} - r_{11} + r_{22}
        \end{pmatrix}.

    Of the four ways to read :math:`q` off :math:`K` (the thesis's four cases), the one
    dividing by the largest component, :math:`q = K_{k\cdot} / (2\sqrt{K_{kk}})` with
    :math:`k = \arg\max_k K_{kk}`, is taken, so the result is accurate to rounding for
    every angle, including 180 degrees. The thesis prints the four cases for the passive
    convention; they return :math:`q^*`.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices (checked: orthonormal with determinant +1 within ``tol``).
    tol : float
        Tolerance of the rotation-matrix check.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions with :math:`w \ge 0`.

    Raises
    ------
    ValueError
        If ``R`` is not a rotation matrix, holds NaN/inf, or has the wrong shape.

    Examples
    --------
    >>> import numpy as np
    >>> R = np.diag([-1.0, -1.0, 1.0])          # half turn about z
    >>> quaternion_from_matrix(R)
    array([0., 0., 0., 1.])
    """
    R = float_array(R, "R", _M)
    if R.ndim == 2:
        a, b, c = R.tolist()
        err, det = orthonormality(a, b, c)
        if not (err <= tol and det > 0.0):  # also catches NaN
            check_finite(R, "R")
            rotation_or_raise("R", err, det, tol)
        return np.array(quaternion_from_matrix_entries(*a, *b, *c))
    check_finite(R, "R")

    def kernel(R):
        e = components(R.reshape(-1, 9))
        err, det = orthonormality(e[0:3], e[3:6], e[6:9])
        if not (err <= tol and det > 0.0):
            rotation_or_raise("R", err, det, tol)
        return stack_components(quaternion_from_matrix_entries(*e))

    return batched(kernel, [(R, 2)], _Q)


def matrix_from_quaternion(q: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Rotation matrix of a unit quaternion (active: :math:`R\mathbf v = q\mathbf v q^*`).

    .. math::

        R = \begin{pmatrix}
        1 - 2(y^2 + z^2) & 2(xy - wz) & 2(xz + wy)\\
        2(xy + wz) & 1 - 2(x^2 + z^2) & 2(yz - wx)\\
        2(xz - wy) & 2(yz + wx) & 1 - 2(x^2 + y^2)
        \end{pmatrix}

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions (a non-unit ``q`` raises; normalise it first).
    tol : float
        Tolerance on :math:`|q| = 1`.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> q = quaternion_from_axis_angle([0, 0, 1], np.pi / 2)
    >>> np.round(matrix_from_quaternion(q), 12)
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    q = _in(q, "q")
    if q.ndim == 1:
        qc = q.tolist()
        unit_quaternion_or_raise(qc, "q", tol)
        return np.array(matrix_entries_from_quaternion(*qc)).reshape(3, 3)
    check_finite(q, "q")

    def kernel(q):
        qc = components(q)
        unit_quaternion_or_raise(qc, "q", tol)
        return stack_components(matrix_entries_from_quaternion(*qc))

    m = batched(kernel, [(q, 1)], (9,))
    return m.reshape(m.shape[:-1] + (3, 3))


# --------------------------------------------------------------------------------------
# Exponential, logarithm, power, interpolation


def quaternion_exp(q: ArrayLike) -> NDArray[np.float64]:
    r"""Quaternion exponential.

    .. math::

        \exp(w, \mathbf v) = e^{w}\left(\cos|\mathbf v|,\;
        \sin|\mathbf v|\,\frac{\mathbf v}{|\mathbf v|}\right)

    The exponential of a pure quaternion :math:`(0, \tfrac{\theta}{2}\mathbf n)` is the
    rotation by :math:`\theta` about :math:`\mathbf n`.

    Parameters
    ----------
    q : array_like, shape (..., 4)

    Returns
    -------
    ndarray, shape (..., 4)

    Examples
    --------
    >>> import numpy as np
    >>> np.round(quaternion_exp([0, 0, 0, np.pi / 4]), 6)
    array([0.707107, 0.      , 0.      , 0.707107])
    """
    q = as_float_array(q, "q", _Q)
    v = q[..., 1:]
    a = norm_last_axis(v)
    with np.errstate(over="ignore", invalid="ignore"):
        e = np.exp(q[..., 0])
        # sin(a)/a written with np.sinc, which is exact at a = 0
        s = e * np.sinc(a / np.pi)
        out = np.empty(np.shape(q))
        out[..., 0] = e * np.cos(a)
        out[..., 1:] = v * s[..., None]
    if not np.isfinite(out).all():
        raise ValueError("q is too large: its exponential overflows")
    return out


def quaternion_log(q: ArrayLike) -> NDArray[np.float64]:
    r"""Quaternion logarithm (principal value).

    .. math::

        \log q = \left(\ln|q|,\; \operatorname{atan2}(|\mathbf u|, w)\,
        \frac{\mathbf u}{|\mathbf u|}\right)

    For a unit quaternion of angle :math:`\theta` about :math:`\mathbf n` this is
    :math:`(0, \tfrac{\theta}{2}\mathbf n)`. For a negative real ``q`` the direction is
    undetermined and :math:`(1, 0, 0)` is used.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Non-zero quaternions.

    Returns
    -------
    ndarray, shape (..., 4)

    Raises
    ------
    ValueError
        If ``q`` is zero (its logarithm is :math:`-\infty`), NaN/inf, or of wrong shape.

    Examples
    --------
    >>> import numpy as np
    >>> q = quaternion_from_axis_angle([0, 1, 0], np.pi / 2)
    >>> np.round(quaternion_log(q) / np.pi, 12)
    array([0.  , 0.  , 0.25, 0.  ])
    """
    q = as_float_array(q, "q", _Q)
    n = _nonzero_norm(q, "q")
    u = q[..., 1:]
    s = norm_last_axis(u)
    phi = np.arctan2(s, q[..., 0])
    zero = s == 0.0
    out = np.empty(np.shape(q))
    out[..., 0] = np.log(n)
    out[..., 1:] = u * (phi / np.where(zero, 1.0, s))[..., None]
    out[..., 1] = np.where(zero, phi, out[..., 1])  # phi = pi for negative reals, else 0
    return out


def quaternion_power(q: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
    r"""Power :math:`q^t = \exp(t \log q)` of a non-zero quaternion.

    For a unit quaternion of angle :math:`\theta` about :math:`\mathbf n`, :math:`q^t`
    is the rotation by :math:`t\theta` about the same axis. Note that :math:`q` and
    :math:`-q` have different powers (they travel the long and the short way round).

    Parameters
    ----------
    q : array_like, shape (..., 4)
    t : array_like, shape (...)
        Exponents; broadcast with the leading axes of ``q``.

    Returns
    -------
    ndarray, shape (..., 4)

    Examples
    --------
    >>> import numpy as np
    >>> q = quaternion_from_axis_angle([0, 0, 1], np.pi / 2)
    >>> np.allclose(quaternion_power(q, 2), [0, 0, 0, 1])
    True
    """
    t = as_float_array(t, "t")
    return quaternion_exp(quaternion_log(q) * t[..., None])


def slerp(q0: ArrayLike, q1: ArrayLike, t: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Spherical linear interpolation between unit quaternions, along the shortest arc.

    If :math:`q_0 \cdot q_1 < 0`, :math:`q_1` is replaced by :math:`-q_1` (same rotation),
    so the path turns by at most 180 degrees. With :math:`\Omega` the angle between
    :math:`q_0` and :math:`q_1` in :math:`\mathbb R^4`:

    .. math::

        \operatorname{slerp}(q_0, q_1, t)
        = \frac{\sin((1-t)\Omega)}{\sin\Omega} q_0 + \frac{\sin(t\Omega)}{\sin\Omega} q_1
        = q_0 (q_0^* q_1)^t .

    The weights are computed with :math:`\operatorname{sinc}`, so :math:`q_0 = q_1` needs
    no special case.

    Parameters
    ----------
    q0, q1 : array_like, shape (..., 4)
        Unit quaternions (checked).
    t : array_like, shape (...)
        Interpolation parameters (0 gives ``q0``, 1 gives ``q1`` or ``-q1``).
    tol : float
        Tolerance on the unit norms.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit quaternions; leading axes are those of ``q0``, ``q1`` and ``t`` broadcast.

    Examples
    --------
    >>> import numpy as np
    >>> q0 = [1, 0, 0, 0]
    >>> q1 = quaternion_from_axis_angle([0, 0, 1], np.pi / 2)
    >>> q = slerp(q0, q1, 0.5)
    >>> round(float(np.degrees(axis_angle_from_quaternion(q)[1])), 9)
    45.0
    """
    q0 = check_unit_quaternion(q0, tol, "q0")
    q1 = check_unit_quaternion(q1, tol, "q1")
    t = as_float_array(t, "t")
    d = np.sum(q0 * q1, axis=-1)
    q1 = np.where((d < 0.0)[..., None], -q1, q1)
    omega = 2.0 * np.arctan2(np.linalg.norm(q0 - q1, axis=-1),
                             np.linalg.norm(q0 + q1, axis=-1))
    sinc = np.sinc(omega / np.pi)
    a = (1.0 - t) * np.sinc((1.0 - t) * omega / np.pi) / sinc
    b = t * np.sinc(t * omega / np.pi) / sinc
    return a[..., None] * q0 + b[..., None] * q1


def quaternion_distance(q0: ArrayLike, q1: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Angle of the rotation taking ``q0`` to ``q1``, in :math:`[0, \pi]`.

    .. math::

        d(q_0, q_1) = 4\,\operatorname{atan2}\bigl(|q_0 - q_1|,\; |q_0 + q_1|\bigr),
        \quad\text{with } q_1 \to -q_1 \text{ if } q_0\cdot q_1 < 0 .

    This is the angle of :math:`q_0^* q_1`; it is the same for :math:`\pm q_0`,
    :math:`\pm q_1`, and is accurate for tiny angles (no ``arccos``).

    Parameters
    ----------
    q0, q1 : array_like, shape (..., 4)
        Unit quaternions.
    tol : float
        Tolerance on the unit norms.

    Returns
    -------
    ndarray, shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> a = quaternion_from_axis_angle([1, 0, 0], 0.1)
    >>> b = quaternion_from_axis_angle([1, 0, 0], -0.2)
    >>> round(float(quaternion_distance(a, -b)), 12)
    0.3
    """
    q0 = check_unit_quaternion(q0, tol, "q0")
    q1 = check_unit_quaternion(q1, tol, "q1")
    d = np.sum(q0 * q1, axis=-1)
    q1 = np.where((d < 0.0)[..., None], -q1, q1)
    return 4.0 * np.arctan2(np.linalg.norm(q0 - q1, axis=-1),
                            np.linalg.norm(q0 + q1, axis=-1))


# --------------------------------------------------------------------------------------
# pyquaternion interoperability


def quaternion_from_pyquaternion(pq) -> NDArray[np.float64]:
    """Array ``(w, x, y, z)`` from a ``pyquaternion.Quaternion`` (or a nested list of them).

    pyquaternion stores the scalar first too, so no reordering is needed.

    Parameters
    ----------
    pq : pyquaternion.Quaternion or sequence of them

    Returns
    -------
    ndarray, shape (..., 4)

    Examples
    --------
    >>> from pyquaternion import Quaternion as PyQuaternion
    >>> quaternion_from_pyquaternion(PyQuaternion(1, 2, 3, 4))
    array([1., 2., 3., 4.])
    """
    if hasattr(pq, "elements"):
        return as_float_array(pq.elements, "pq", _Q).copy()
    return np.array([quaternion_from_pyquaternion(p) for p in pq], dtype=float)


def pyquaternion_from_quaternion(q: ArrayLike):
    """``pyquaternion.Quaternion`` from an array ``(w, x, y, z)``.

    Parameters
    ----------
    q : array_like, shape (4,) or (..., 4)

    Returns
    -------
    pyquaternion.Quaternion, or nested lists of them for a batch

    Examples
    --------
    >>> pq = pyquaternion_from_quaternion([1, 0, 0, 0])
    >>> type(pq).__name__, pq.elements
    ('Quaternion', array([1., 0., 0., 0.]))
    """
    try:
        from pyquaternion import Quaternion as PyQuaternion
    except ImportError:
        raise ImportError("pyquaternion_from_quaternion needs pyquaternion: "
                          "pip install pyquaternion (or dqlab[interop])") from None

    q = as_float_array(q, "q", _Q)
    if q.ndim == 1:
        return PyQuaternion(*q.tolist())
    return [pyquaternion_from_quaternion(p) for p in q]


# --------------------------------------------------------------------------------------
# Class wrapper


class Quaternion(ArrayWrapper):
    """A quaternion, or a batch of them, for readable notebook code.

    A thin wrapper over the array functions of this module: every method calls one of
    them, nothing is computed twice. ``.array`` is the ``(..., 4)`` float array, ``.shape``
    its leading (batch) shape. Indexing, ``len``, ``*`` (the product, or scaling by a
    number), ``+``, ``-``, ``**`` and ``==`` work as for :class:`dqlab.dualquat.DualQuaternion`
    (both classes share them).

    Parameters
    ----------
    q : array_like, shape (..., 4), or Quaternion
        Components ``(w, x, y, z)``.

    Examples
    --------
    >>> import numpy as np
    >>> Qz = Quaternion.from_axis_angle([0, 0, 1], np.pi / 2)
    >>> Qy = Quaternion.from_axis_angle([0, 1, 0], np.pi)
    >>> (Qy * Qz).apply([1, 0, 0]).round(12) + 0.0
    array([0., 1., 0.])
    >>> Quaternion([1, 2, 3, 4])
    Quaternion([1., 2., 3., 4.])
    """

    __slots__ = ()
    _trailing, _name, _product = _Q, "q", staticmethod(quaternion_product)

    # construction
    @classmethod
    def identity(cls, shape=()):
        """The identity rotation ``(1, 0, 0, 0)`` (or a batch of them)."""
        return cls(quaternion_identity(shape))

    @classmethod
    def from_axis_angle(cls, axis, angle):
        """See :func:`quaternion_from_axis_angle`."""
        return cls(quaternion_from_axis_angle(axis, angle))

    @classmethod
    def from_matrix(cls, R, *, tol=1e-9):
        """See :func:`quaternion_from_matrix`."""
        return cls(quaternion_from_matrix(R, tol=tol))

    @classmethod
    def from_pyquaternion(cls, pq):
        """See :func:`quaternion_from_pyquaternion`."""
        return cls(quaternion_from_pyquaternion(pq))

    @classmethod
    def exp(cls, q):
        """See :func:`quaternion_exp`."""
        return cls(quaternion_exp(array_of(q)))

    # components
    @property
    def w(self):
        """Scalar part, shape (...)."""
        return self.array[..., 0]

    @property
    def vector(self):
        """Vector part ``(x, y, z)``, shape (..., 3)."""
        return self.array[..., 1:]

    # algebra (product, sums, scaling, ``**`` and ``==`` come from the shared wrapper)
    def __truediv__(self, other):
        if np.ndim(other) == 0:
            return Quaternion(self.array / float(other))
        return NotImplemented

    def conjugate(self):
        """See :func:`quaternion_conjugate`."""
        return Quaternion(quaternion_conjugate(self.array))

    def inverse(self):
        """See :func:`quaternion_inverse`."""
        return Quaternion(quaternion_inverse(self.array))

    def norm(self):
        """See :func:`quaternion_norm` (a float for a single quaternion)."""
        n = quaternion_norm(self.array)
        return float_if_single(n)

    def normalized(self):
        """See :func:`quaternion_normalize`."""
        return Quaternion(quaternion_normalize(self.array))

    def log(self):
        """See :func:`quaternion_log`."""
        return Quaternion(quaternion_log(self.array))

    def power(self, t):
        """See :func:`quaternion_power`."""
        return Quaternion(quaternion_power(self.array, t))

    # rotations
    def apply(self, v):
        """Rotate vectors ``(..., 3)``; see :func:`rotate_vector`."""
        return rotate_vector(self.array, v)

    rotate = apply

    def matrix(self):
        """See :func:`matrix_from_quaternion`."""
        return matrix_from_quaternion(self.array)

    def axis_angle(self):
        """``(axis, angle)``; see :func:`axis_angle_from_quaternion`."""
        return axis_angle_from_quaternion(self.array)

    def angle(self):
        """Rotation angle in :math:`[0, \\pi]`."""
        a = axis_angle_from_quaternion(self.array)[1]
        return float_if_single(a)

    def distance(self, other):
        """See :func:`quaternion_distance`."""
        d = quaternion_distance(self.array, array_of(other))
        return float_if_single(d)

    def slerp(self, other, t):
        """See :func:`slerp`."""
        return Quaternion(slerp(self.array, array_of(other), t))

    def to_pyquaternion(self):
        """See :func:`pyquaternion_from_quaternion`."""
        return pyquaternion_from_quaternion(self.array)

    def __str__(self):
        if self.array.ndim != 1:
            return repr(self)
        w, x, y, z = self.array.tolist()
        return f"{w:.6g} {x:+.6g}i {y:+.6g}j {z:+.6g}k"



# --------------------------------------------------------------------------------------
# Rates: the derivative of a moving rotation (chapter "Differential kinematics")

__all__ += ["quaternion_rate", "angular_velocity_from_quaternion_rate"]


def quaternion_rate(q, omega, *, frame="world", tol=1e-9):
    r"""Time derivative of a unit quaternion turning at the angular velocity ``omega``.

    With :math:`\omega` in the world (fixed) frame, or :math:`\omega_b` in the body
    (moving) frame, both as pure quaternions :math:`(0, \omega)`:

    .. math::

        \dot q = \tfrac12\, \omega\, q
        \qquad\text{or}\qquad
        \dot q = \tfrac12\, q\, \omega_b ,

    since over a short time :math:`h` the rotation becomes
    :math:`\exp(\tfrac h2 \omega)\, q \approx (1 + \tfrac h2 \omega)\, q`.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions ``(w, x, y, z)``.
    omega : array_like, shape (..., 3)
        Angular velocities in rad/s; broadcast with the leading axes of ``q``.
    frame : {"world", "body"}
        Frame in which ``omega`` is expressed.
    tol : float
        Accepted deviation of :math:`|q|` from 1.

    Returns
    -------
    ndarray, shape (..., 4)
        :math:`\dot q`, orthogonal to :math:`q` in :math:`\mathbb R^4`.

    Raises
    ------
    ValueError
        ``q`` not a unit quaternion, ``omega`` of the wrong shape or not finite, or an
        unknown ``frame``.

    See Also
    --------
    angular_velocity_from_quaternion_rate : the inverse map.

    Examples
    --------
    Turning about z at 2 rad/s from the identity:

    >>> quaternion_rate([1, 0, 0, 0], [0, 0, 2])
    array([0., 0., 0., 1.])
    """
    q = check_unit_quaternion(q, tol)
    omega = as_float_array(omega, "omega", _V)
    w = np.concatenate([np.zeros(omega.shape[:-1] + (1,)), omega], axis=-1)
    if frame == "world":
        return 0.5 * quaternion_product(w, q)
    if frame == "body":
        return 0.5 * quaternion_product(q, w)
    raise ValueError(f"frame must be 'world' or 'body', got {frame!r}")


def angular_velocity_from_quaternion_rate(q, q_dot, *, frame="world", tol=1e-9):
    r"""Angular velocity of a unit quaternion moving at the rate ``q_dot``.

    The inverse of :func:`quaternion_rate`:

    .. math::

        \omega = 2\, \dot q\, q^* \qquad\text{or}\qquad \omega_b = 2\, q^* \dot q .

    Only the part of :math:`\dot q` tangent to the unit sphere counts: the real part of
    :math:`2\dot q q^*`, which is :math:`\tfrac{d}{dt}|q|^2`, is dropped.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions.
    q_dot : array_like, shape (..., 4)
        Their time derivatives.
    frame : {"world", "body"}
        Frame in which to express the result.
    tol : float
        Accepted deviation of :math:`|q|` from 1.

    Returns
    -------
    ndarray, shape (..., 3)
        :math:`\omega` in rad/s (per unit of the time of ``q_dot``).

    Raises
    ------
    ValueError
        ``q`` not a unit quaternion, ``q_dot`` of the wrong shape or not finite, or an
        unknown ``frame``.

    Examples
    --------
    >>> import numpy as np
    >>> q = quaternion_from_axis_angle([1, 0, 0], 0.3)
    >>> omega = [0.1, -0.2, 0.5]
    >>> np.allclose(angular_velocity_from_quaternion_rate(q, quaternion_rate(q, omega)),
    ...             omega)
    True
    """
    q = check_unit_quaternion(q, tol)
    q_dot = as_float_array(q_dot, "q_dot", _Q)
    if frame == "world":
        return 2.0 * quaternion_product(q_dot, quaternion_conjugate(q))[..., 1:]
    if frame == "body":
        return 2.0 * quaternion_product(quaternion_conjugate(q), q_dot)[..., 1:]
    raise ValueError(f"frame must be 'world' or 'body', got {frame!r}")


__all__ += ["quaternion_from_xyzw", "xyzw_from_quaternion"]


def quaternion_from_xyzw(q_xyzw: ArrayLike) -> NDArray[np.float64]:
    r"""A quaternion stored scalar last, ``(x, y, z, w)``, in dqlab's order ``(w, x, y, z)``.

    scipy (``Rotation.as_quat``), ROS messages, Eigen's ``coeffs()`` and many file formats
    store the scalar last; every function of dqlab takes it first. Nothing can tell the two
    orders apart from the numbers (both are unit quaternions, of different rotations), so a
    quaternion given in the wrong order is taken silently: convert at the boundary.

    Parameters
    ----------
    q_xyzw : array_like, shape (..., 4)
        Quaternions ``(x, y, z, w)``.

    Returns
    -------
    ndarray, shape (..., 4)
        The same quaternions as ``(w, x, y, z)``.

    Raises
    ------
    ValueError
        If ``q_xyzw`` is not of shape (..., 4) or holds NaN or infinity.

    See Also
    --------
    xyzw_from_quaternion : the other way.

    Examples
    --------
    A quarter turn about z, as scipy prints it, ``[0, 0, sin(pi/4), cos(pi/4)]``:

    >>> import numpy as np
    >>> quaternion_from_xyzw([0.0, 0.0, np.sin(np.pi / 4), np.cos(np.pi / 4)]).round(6)
    array([0.707107, 0.      , 0.      , 0.707107])
    """
    q = as_float_array(q_xyzw, "q_xyzw", _Q)
    return q[..., [3, 0, 1, 2]]


def xyzw_from_quaternion(q: ArrayLike) -> NDArray[np.float64]:
    r"""A quaternion in dqlab's order ``(w, x, y, z)`` stored scalar last, ``(x, y, z, w)``
    (the order of scipy, ROS and Eigen's ``coeffs()``; see :func:`quaternion_from_xyzw`).

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Quaternions ``(w, x, y, z)``.

    Returns
    -------
    ndarray, shape (..., 4)

    Examples
    --------
    >>> xyzw_from_quaternion([1.0, 0.0, 0.0, 0.0])
    array([0., 0., 0., 1.])
    """
    q = as_float_array(q, "q", _Q)
    return q[..., [1, 2, 3, 0]]
