r"""Dual quaternions: rigid motions as eight numbers.

Convention (the book's preface): a dual quaternion :math:`Q = q_r + \varepsilon q_d`
(:math:`\varepsilon^2 = 0`) is stored as ``(..., 8)``, the real part ``(w, x, y, z)`` then
the dual part. A rigid motion "rotate by :math:`q`, then translate by :math:`\mathbf t`"
(the transform :math:`X = (R(q), \mathbf t)`) is the unit dual quaternion

.. math::

    Q = q + \varepsilon\, \tfrac12\, \mathbf t\, q ,

and products compose like transform matrices: ``Q_AC = Q_AB * Q_BC`` is
``X_AC = X_AB @ X_BC``. The thesis writes the same object as a quaternion-vector pair
:math:`(q, \mathbf p)`; see :func:`dual_quaternion_from_pair` and :func:`pair_product`.

Array functions do the work; :class:`DualQuaternion` is a thin wrapper for notebooks.
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
    rigid_rows,
    rotation_or_raise,
    stack_components,
    unit_dual_quaternion_or_raise,
    unit_quaternion_or_raise,
)
from ._formulas import (
    dual_quaternion_mul,
    matrix_entries_from_quaternion,
    norm_last_axis,
    orthonormality,
    quaternion_from_matrix_entries,
    quaternion_mul,
    quaternion_rotate,
    screw_entries,
    translation_from_dual_quaternion_entries,
)
from ._wrapper import ArrayWrapper, array_of
from .quaternion import check_unit_quaternion, quaternion_product, rotate_vector
from .transforms import check_transform

__all__ = [
    "dual_quaternion_product", "dual_quaternion_conjugate", "dual_quaternion_dual_conjugate",
    "dual_quaternion_combined_conjugate", "dual_quaternion_norm", "check_unit_dual_quaternion",
    "dual_quaternion_normalize", "dual_quaternion_inverse",
    "dual_quaternion_from_rotation_translation", "rotation_translation_from_dual_quaternion",
    "dual_quaternion_from_transform", "transform_from_dual_quaternion",
    "dual_quaternion_apply", "dual_quaternion_apply_vector", "dual_quaternion_apply_line",
    "dual_quaternion_from_pair", "pair_from_dual_quaternion", "pair_product",
    "screw_from_dual_quaternion", "dual_quaternion_from_screw", "dual_quaternion_power",
    "sclerp", "dual_quaternion_identity", "DualQuaternion",
]

_D = (8,)
_Q = (4,)
_V = (3,)


def _in(x, name, trailing=_D):
    a = float_array(x, name, trailing)
    if a.ndim > len(trailing):
        check_finite(a, name)
    return a


# --------------------------------------------------------------------------------------
# Algebra


def dual_quaternion_identity(shape=()):
    """Identity dual quaternion(s) ``(1, 0, 0, 0, 0, 0, 0, 0)`` of shape ``shape + (8,)``.

    Examples
    --------
    >>> dual_quaternion_identity()
    array([1., 0., 0., 0., 0., 0., 0., 0.])
    """
    Q = np.zeros(batch_shape(shape) + (8,))
    Q[..., 0] = 1.0
    return Q


def dual_quaternion_product(A: ArrayLike, B: ArrayLike) -> NDArray[np.float64]:
    r"""Product of dual quaternions.

    .. math::

        (a_r + \varepsilon a_d)(b_r + \varepsilon b_d)
        = a_r b_r + \varepsilon\,(a_r b_d + a_d b_r)

    For unit dual quaternions this composes rigid motions like
    ``X_AC = X_AB @ X_BC``.

    Parameters
    ----------
    A, B : array_like, shape (..., 8)
        Dual quaternions; leading axes broadcast.

    Returns
    -------
    ndarray, shape (..., 8)

    Raises
    ------
    ValueError
        Wrong shape, NaN or infinity.

    Examples
    --------
    >>> import numpy as np
    >>> A = dual_quaternion_from_rotation_translation([1, 0, 0, 0], [1, 0, 0])
    >>> B = dual_quaternion_from_rotation_translation([1, 0, 0, 0], [0, 2, 0])
    >>> rotation_translation_from_dual_quaternion(dual_quaternion_product(A, B))[1]
    array([1., 2., 0.])
    """
    A = _in(A, "A")
    B = _in(B, "B")
    if A.ndim == 1 and B.ndim == 1:
        return pack(dual_quaternion_mul(A.tolist(), B.tolist()), (A, "A", _D), (B, "B", _D))
    check_finite(A, "A")
    check_finite(B, "B")
    return batched(_product_kernel, [(A, 1), (B, 1)], _D)


def _product_kernel(A, B):
    return stack_components(dual_quaternion_mul(components(A), components(B)))


def dual_quaternion_conjugate(Q: ArrayLike) -> NDArray[np.float64]:
    r"""Quaternion conjugate of both parts, :math:`Q^* = q_r^* + \varepsilon q_d^*`.

    This is the conjugate that reverses products, :math:`(AB)^* = B^* A^*`, and the inverse
    of a unit dual quaternion: :math:`Q Q^* = 1`. Use it to undo a motion.

    Parameters
    ----------
    Q : array_like, shape (..., 8)

    Returns
    -------
    ndarray, shape (..., 8)

    Examples
    --------
    >>> dual_quaternion_conjugate([1, 2, 3, 4, 5, 6, 7, 8])
    array([ 1., -2., -3., -4.,  5., -6., -7., -8.])
    """
    Q = as_float_array(Q, "Q", _D)
    out = -Q
    out[..., 0] = Q[..., 0]
    out[..., 4] = Q[..., 4]
    return out


def dual_quaternion_dual_conjugate(Q: ArrayLike) -> NDArray[np.float64]:
    r"""Dual-number conjugate, :math:`\bar Q = q_r - \varepsilon q_d`.

    It flips the sign of :math:`\varepsilon`, as :math:`\overline{a + \varepsilon b} =
    a - \varepsilon b` does for dual numbers. On its own it has no simple meaning as a
    rigid motion; it is one half of the combined conjugate
    (:func:`dual_quaternion_combined_conjugate`) that moves points.

    Parameters
    ----------
    Q : array_like, shape (..., 8)

    Returns
    -------
    ndarray, shape (..., 8)

    Examples
    --------
    >>> dual_quaternion_dual_conjugate([1, 2, 3, 4, 5, 6, 7, 8])
    array([ 1.,  2.,  3.,  4., -5., -6., -7., -8.])
    """
    Q = as_float_array(Q, "Q", _D)
    out = Q.copy()
    out[..., 4:] = -Q[..., 4:]
    return out


def dual_quaternion_combined_conjugate(Q: ArrayLike) -> NDArray[np.float64]:
    r"""Both conjugates at once, :math:`\bar Q^* = q_r^* - \varepsilon q_d^*`.

    This is the one that transforms points written as dual quaternions
    :math:`P = 1 + \varepsilon\,\mathbf p`:

    .. math::

        1 + \varepsilon\,\mathbf p' = Q\,(1 + \varepsilon\,\mathbf p)\,\bar Q^* ,
        \qquad \mathbf p' = R\,\mathbf p + \mathbf t .

    Parameters
    ----------
    Q : array_like, shape (..., 8)

    Returns
    -------
    ndarray, shape (..., 8)

    Examples
    --------
    >>> dual_quaternion_combined_conjugate([1, 2, 3, 4, 5, 6, 7, 8])
    array([ 1., -2., -3., -4., -5.,  6.,  7.,  8.])
    """
    Q = as_float_array(Q, "Q", _D)
    out = Q.copy()
    out[..., 1:4] = -Q[..., 1:4]
    out[..., 4] = -Q[..., 4]
    return out


def dual_quaternion_norm(Q: ArrayLike) -> NDArray[np.float64]:
    r"""Norm of a dual quaternion, a dual number :math:`\|Q\| = a + \varepsilon b`.

    .. math::

        \|Q\|^2 = Q Q^* = |q_r|^2 + 2\varepsilon\,\langle q_r, q_d\rangle
        \quad\Longrightarrow\quad
        \|Q\| = |q_r| + \varepsilon\,\frac{\langle q_r, q_d\rangle}{|q_r|}

    :math:`Q` is a unit dual quaternion (a rigid motion) when :math:`\|Q\| = 1 + 0\varepsilon`.

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Dual quaternions with a non-zero real part.

    Returns
    -------
    ndarray, shape (..., 2)
        ``(a, b)``: real and dual parts of the norm.

    Raises
    ------
    ValueError
        If the real part is zero (the norm is then not a function of ``Q``).

    Examples
    --------
    >>> dual_quaternion_norm([2, 0, 0, 0, 1, 0, 0, 0])
    array([2., 1.])
    """
    Q = as_float_array(Q, "Q", _D)
    qr, qd = Q[..., :4], Q[..., 4:]
    a = norm_last_axis(qr)
    if np.any(a == 0.0):
        raise ValueError("the real part of Q is the zero quaternion: the norm is undefined")
    return np.stack([a, np.sum((qr / a[..., None]) * qd, axis=-1)], axis=-1)


def check_unit_dual_quaternion(Q: ArrayLike, tol: float = 1e-9, name: str = "Q"
                               ) -> NDArray[np.float64]:
    r"""Return ``Q`` as a float array, or raise if it is not a unit dual quaternion.

    Unit means :math:`|q_r| = 1` and :math:`\langle q_r, q_d\rangle = 0` (within ``tol``).

    Parameters
    ----------
    Q : array_like, shape (..., 8)
    tol : float
    name : str
        Name used in the error message.

    Returns
    -------
    ndarray, shape (..., 8)

    Raises
    ------
    ValueError
        Wrong shape, NaN/inf, or not unit.

    Examples
    --------
    >>> check_unit_dual_quaternion([1, 0, 0, 0, 0, 1, 0, 0])
    array([1., 0., 0., 0., 0., 1., 0., 0.])
    >>> check_unit_dual_quaternion([1, 0, 0, 0, 1, 0, 0, 0])
    Traceback (most recent call last):
    ...
    ValueError: Q must be a unit dual quaternion: <q_r, q_d> = 1 should be 0 ...
    """
    Q = as_float_array(Q, name, _D)
    unit_dual_quaternion_or_raise(components(Q), name, tol)
    return Q


def dual_quaternion_normalize(Q: ArrayLike) -> NDArray[np.float64]:
    r"""Unit dual quaternion :math:`Q / \|Q\|` (division by the dual-number norm).

    With :math:`\|Q\| = a + \varepsilon b` and
    :math:`1/(a + \varepsilon b) = 1/a - \varepsilon\, b/a^2`:

    .. math::

        \frac{Q}{\|Q\|} = \hat q_r + \varepsilon\,\bigl(\hat q_d
        - \langle \hat q_r, \hat q_d\rangle\, \hat q_r\bigr),
        \qquad \hat q_r = q_r / a,\; \hat q_d = q_d / a .

    The real part is normalised and the dual part made orthogonal to it.

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Dual quaternions with a non-zero real part.

    Returns
    -------
    ndarray, shape (..., 8)

    Raises
    ------
    ValueError
        If the real part is zero, NaN/inf, wrong shape.

    Examples
    --------
    >>> dual_quaternion_normalize([2, 0, 0, 0, 1, 0, 2, 0])
    array([1., 0., 0., 0., 0., 0., 1., 0.])
    """
    Q = as_float_array(Q, "Q", _D)
    a = dual_quaternion_norm(Q)[..., 0:1]
    qr, qd = Q[..., :4] / a, Q[..., 4:] / a
    qd = qd - np.sum(qr * qd, axis=-1, keepdims=True) * qr
    return np.concatenate([qr, qd], axis=-1)


def dual_quaternion_inverse(Q: ArrayLike) -> NDArray[np.float64]:
    r"""Inverse :math:`Q^{-1}`, with :math:`Q Q^{-1} = Q^{-1} Q = 1`.

    .. math::

        (q_r + \varepsilon q_d)^{-1} = q_r^{-1} - \varepsilon\, q_r^{-1} q_d\, q_r^{-1}

    For a unit dual quaternion this equals the conjugate
    :func:`dual_quaternion_conjugate`: the inverse motion.

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Dual quaternions with a non-zero real part.

    Returns
    -------
    ndarray, shape (..., 8)

    Raises
    ------
    ValueError
        If the real part is zero (no inverse), NaN/inf, wrong shape.

    Examples
    --------
    >>> Q = dual_quaternion_from_rotation_translation([0, 0, 0, 1], [1, 2, 3])
    >>> np.allclose(dual_quaternion_product(Q, dual_quaternion_inverse(Q)),
    ...             dual_quaternion_identity())
    True
    """
    Q = as_float_array(Q, "Q", _D)
    qr, qd = Q[..., :4], Q[..., 4:]
    n = norm_last_axis(qr)[..., None]
    if np.any(n == 0.0):
        raise ValueError("the real part of Q is the zero quaternion: Q has no inverse")
    ri = qr * np.array([1.0, -1.0, -1.0, -1.0]) / n / n
    di = -quaternion_product(quaternion_product(ri, qd), ri)
    return np.concatenate([ri, di], axis=-1)


# --------------------------------------------------------------------------------------
# Rigid motions


def dual_quaternion_from_rotation_translation(q: ArrayLike, t: ArrayLike, *, tol: float = 1e-9
                                              ) -> NDArray[np.float64]:
    r"""Unit dual quaternion of "rotate by ``q``, then translate by ``t``".

    .. math::

        Q = q + \varepsilon\,\tfrac12\,(0, \mathbf t)\, q

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions (checked).
    t : array_like, shape (..., 3)
        Translations; leading axes broadcast with those of ``q``.
    tol : float
        Tolerance on :math:`|q| = 1`.

    Returns
    -------
    ndarray, shape (..., 8)

    Examples
    --------
    >>> dual_quaternion_from_rotation_translation([1, 0, 0, 0], [2, 4, 6])
    array([1., 0., 0., 0., 0., 1., 2., 3.])
    """
    q = float_array(q, "q", _Q)
    t = float_array(t, "t", _V)
    if q.ndim > 1 or t.ndim > 1:
        check_finite(q, "q")
        check_finite(t, "t")
    qc = components(q)
    unit_quaternion_or_raise(qc, "q", tol)
    tx, ty, tz = components(t)
    d = quaternion_mul(0.0, 0.5 * tx, 0.5 * ty, 0.5 * tz, *qc)
    return pack(tuple(qc) + d, (t, "t", _V))


def rotation_translation_from_dual_quaternion(Q: ArrayLike, *, tol: float = 1e-9
                                              ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Rotation quaternion and translation of a unit dual quaternion.

    .. math::

        q = q_r, \qquad (0, \mathbf t) = 2\, q_d\, q_r^*

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Unit dual quaternions (checked).
    tol : float

    Returns
    -------
    q : ndarray, shape (..., 4)
    t : ndarray, shape (..., 3)

    Examples
    --------
    >>> Q = dual_quaternion_from_rotation_translation([0, 1, 0, 0], [1, 2, 3])
    >>> q, t = rotation_translation_from_dual_quaternion(Q)
    >>> q, t
    (array([0., 1., 0., 0.]), array([1., 2., 3.]))
    """
    Q = _in(Q, "Q")
    c = components(Q)
    unit_dual_quaternion_or_raise(c, "Q", tol)
    return Q[..., :4].copy(), stack_components(translation_from_dual_quaternion_entries(*c))


def dual_quaternion_from_transform(T: ArrayLike, *, tol: float = 1e-9, name: str = "T"
                                   ) -> NDArray[np.float64]:
    r"""Unit dual quaternion of a homogeneous transform.

    :math:`q_r` is the quaternion of the rotation block (Shepperd's method, :math:`w \ge 0`,
    see :func:`dqlab.quaternion.quaternion_from_matrix`) and
    :math:`q_d = \tfrac12 (0, \mathbf t)\, q_r`.

    Parameters
    ----------
    T : array_like, shape (..., 4, 4)
        Rigid transforms (checked: bottom row ``(0, 0, 0, 1)``, rotation block orthonormal
        with determinant +1 within ``tol``).
    tol : float
    name : str
        Name of the argument in error messages (the conversion is also the validation).

    Returns
    -------
    ndarray, shape (..., 8)

    Raises
    ------
    ValueError
        If ``T`` is not a rigid transform, holds NaN/inf, or has the wrong shape.

    Examples
    --------
    >>> import numpy as np
    >>> T = np.eye(4)
    >>> T[:3, 3] = [2, 0, 0]
    >>> dual_quaternion_from_transform(T)
    array([1., 0., 0., 0., 0., 1., 0., 0.])
    """
    T = float_array(T, name, (4, 4))
    if T.ndim == 2:
        rows = rigid_rows(T, tol)
        if rows is None:
            check_transform(T, tol, name)  # raises with the right message
            raise ValueError(f"{name} contains NaN or infinity")
        a, b, c = rows
        qr = quaternion_from_matrix_entries(a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2])
        qd = quaternion_mul(0.0, 0.5 * a[3], 0.5 * b[3], 0.5 * c[3], *qr)
        return np.array(qr + qd)
    check_finite(T, name)

    def kernel(T):
        e = components(T.reshape(-1, 16))
        if not ((e[12] == 0.0).all() and (e[13] == 0.0).all() and (e[14] == 0.0).all()
                and (e[15] == 1.0).all()):
            check_transform(T, tol, name)  # raises with the right message
        err, det = orthonormality(e[0:3], e[4:7], e[8:11])
        if not (err <= tol and det > 0.0):
            rotation_or_raise(f"the rotation block of {name}", err, det, tol)
        qr = quaternion_from_matrix_entries(e[0], e[1], e[2], e[4], e[5], e[6], e[8], e[9], e[10])
        qd = quaternion_mul(0.0, 0.5 * e[3], 0.5 * e[7], 0.5 * e[11], *qr)
        return stack_components(qr + qd)

    return batched(kernel, [(T, 2)], _D)


def transform_from_dual_quaternion(Q: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Homogeneous transform of a unit dual quaternion.

    .. math::

        X = \begin{pmatrix} R(q_r) & \mathbf t \\ \mathbf 0^\mathsf{T} & 1 \end{pmatrix},
        \qquad (0, \mathbf t) = 2\, q_d\, q_r^*

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Unit dual quaternions (checked).
    tol : float

    Returns
    -------
    ndarray, shape (..., 4, 4)

    Examples
    --------
    >>> transform_from_dual_quaternion([1, 0, 0, 0, 0, 1, 0, 0])
    array([[1., 0., 0., 2.],
           [0., 1., 0., 0.],
           [0., 0., 1., 0.],
           [0., 0., 0., 1.]])
    """
    Q = _in(Q, "Q")
    if Q.ndim == 1:
        return np.array(_transform_parts(Q.tolist(), tol)).reshape(4, 4)

    def kernel(Q):
        return stack_components(_transform_parts(components(Q), tol))

    T = batched(kernel, [(Q, 1)], (16,))
    return T.reshape(T.shape[:-1] + (4, 4))


def _transform_parts(c, tol):
    """The 16 entries of the 4x4 of a unit dual quaternion given by its components."""
    unit_dual_quaternion_or_raise(c, "Q", tol)
    tx, ty, tz = translation_from_dual_quaternion_entries(*c)
    m = matrix_entries_from_quaternion(*c[:4])
    z = 0.0 * c[0]
    return (m[0:3] + (tx,) + m[3:6] + (ty,) + m[6:9] + (tz,) + (z, z, z, z + 1.0))


def dual_quaternion_apply(Q: ArrayLike, points: ArrayLike, *, tol: float = 1e-9
                          ) -> NDArray[np.float64]:
    r"""Apply rigid motions to points: :math:`\mathbf p' = R(q_r)\,\mathbf p + \mathbf t`.

    This equals the sandwich :math:`1 + \varepsilon\mathbf p' = Q\,(1 + \varepsilon
    \mathbf p)\,\bar Q^*` with the combined conjugate
    (:func:`dual_quaternion_combined_conjugate`).

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Unit dual quaternions (checked).
    points : array_like, shape (..., 3)
        Leading axes broadcast with those of ``Q``.
    tol : float

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> import numpy as np
    >>> Q = dual_quaternion_from_rotation_translation(
    ...     [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)], [1, 0, 0])
    >>> np.round(dual_quaternion_apply(Q, [2, 1, 1]), 12)
    array([0., 2., 1.])
    """
    Q = _in(Q, "Q")
    p = _in(points, "points", _V)
    if Q.ndim == 1 and p.ndim == 1:
        return pack(_apply_parts(Q.tolist(), p.tolist(), tol), (p, "points", _V))
    check_finite(Q, "Q")
    check_finite(p, "points")

    def kernel(Q, p):
        return stack_components(_apply_parts(components(Q), components(p), tol))

    return batched(kernel, [(Q, 1), (p, 1)], _V)


def _apply_parts(c, p, tol):
    """R p + t on components, with (0, t) = 2 q_d q_r^*."""
    unit_dual_quaternion_or_raise(c, "Q", tol)
    tx, ty, tz = translation_from_dual_quaternion_entries(*c)
    x, y, z = quaternion_rotate(*c[:4], *p)
    return x + tx, y + ty, z + tz


def dual_quaternion_apply_vector(Q: ArrayLike, vectors: ArrayLike, *, tol: float = 1e-9
                                 ) -> NDArray[np.float64]:
    r"""Apply the rotation of rigid motions to free vectors: :math:`\mathbf v' = R\mathbf v`.

    Directions and velocities do not move with the translation. As dual quaternions,
    :math:`\mathbf v' = Q\,\mathbf v\,Q^*` (plain conjugate, :math:`\mathbf v` pure real).

    Parameters
    ----------
    Q : array_like, shape (..., 8)
    vectors : array_like, shape (..., 3)
    tol : float

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> Q = dual_quaternion_from_rotation_translation([0, 0, 0, 1], [5, 5, 5])
    >>> dual_quaternion_apply_vector(Q, [1, 0, 0]) + 0.0
    array([-1.,  0.,  0.])
    """
    Q = _in(Q, "Q")
    v = _in(vectors, "vectors", _V)
    if Q.ndim > 1 or v.ndim > 1:
        check_finite(Q, "Q")
        check_finite(v, "vectors")
    c = components(Q)
    unit_dual_quaternion_or_raise(c, "Q", tol)
    return pack(quaternion_rotate(*c[:4], *components(v)), (v, "vectors", _V))


def dual_quaternion_apply_line(Q: ArrayLike, direction: ArrayLike, moment: ArrayLike, *,
                               tol: float = 1e-9
                               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Apply rigid motions to lines in Plücker coordinates :math:`(\mathbf l, \mathbf m)`.

    A line through the point :math:`\mathbf c` with direction :math:`\mathbf l` has moment
    :math:`\mathbf m = \mathbf c \times \mathbf l`. Written as the dual vector
    :math:`L = \mathbf l + \varepsilon\mathbf m`, it moves as :math:`L' = Q L Q^*`:

    .. math::

        \mathbf l' = R\,\mathbf l, \qquad
        \mathbf m' = R\,\mathbf m + \mathbf t \times R\,\mathbf l .

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Unit dual quaternions.
    direction, moment : array_like, shape (..., 3)
    tol : float

    Returns
    -------
    direction : ndarray, shape (..., 3)
    moment : ndarray, shape (..., 3)

    Examples
    --------
    >>> Q = dual_quaternion_from_rotation_translation([1, 0, 0, 0], [0, 1, 0])
    >>> dual_quaternion_apply_line(Q, [0, 0, 1], [0, 0, 0])   # z axis moved to y = 1
    (array([0., 0., 1.]), array([1., 0., 0.]))
    """
    direction = as_float_array(direction, "direction", _V)
    moment = as_float_array(moment, "moment", _V)
    t = rotation_translation_from_dual_quaternion(Q, tol=tol)[1]
    l2 = dual_quaternion_apply_vector(Q, direction, tol=tol)
    m2 = dual_quaternion_apply_vector(Q, moment, tol=tol) + np.cross(t, l2)
    return l2, m2


# --------------------------------------------------------------------------------------
# The thesis's quaternion-vector pairs


def dual_quaternion_from_pair(q: ArrayLike, p: ArrayLike, *, tol: float = 1e-9
                              ) -> NDArray[np.float64]:
    r"""Dual quaternion of the thesis's pair :math:`(q, \mathbf p)`.

    The thesis describes a rigid motion by a unit quaternion :math:`q` and a translation
    vector :math:`\mathbf p`, acting as :math:`\mathbf x \mapsto q\mathbf x q^{-1} +
    \mathbf p`. It is the dual quaternion :math:`q + \varepsilon\,\tfrac12\,\mathbf p\,q`
    (same as :func:`dual_quaternion_from_rotation_translation`).

    Parameters
    ----------
    q : array_like, shape (..., 4)
    p : array_like, shape (..., 3)
    tol : float

    Returns
    -------
    ndarray, shape (..., 8)

    Examples
    --------
    >>> dual_quaternion_from_pair([1, 0, 0, 0], [0, 0, 2])
    array([1., 0., 0., 0., 0., 0., 0., 1.])
    """
    return dual_quaternion_from_rotation_translation(q, as_float_array(p, "p", _V), tol=tol)


def pair_from_dual_quaternion(Q: ArrayLike, *, tol: float = 1e-9
                              ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""The thesis's pair :math:`(q, \mathbf p)` of a unit dual quaternion.

    .. math::

        q = q_r, \qquad \mathbf p = 2\, q_d\, q_r^*

    Parameters
    ----------
    Q : array_like, shape (..., 8)
    tol : float

    Returns
    -------
    q : ndarray, shape (..., 4)
    p : ndarray, shape (..., 3)

    Examples
    --------
    >>> pair_from_dual_quaternion([1, 0, 0, 0, 0, 0, 0, 1])
    (array([1., 0., 0., 0.]), array([0., 0., 2.]))
    """
    return rotation_translation_from_dual_quaternion(Q, tol=tol)


def pair_product(q1: ArrayLike, p1: ArrayLike, q2: ArrayLike, p2: ArrayLike, *, tol: float = 1e-9
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Product of quaternion-vector pairs (the thesis's composition rule).

    .. math::

        (q_1, \mathbf p_1)(q_2, \mathbf p_2)
        = (q_1 q_2,\; q_1 \mathbf p_2 q_1^{-1} + \mathbf p_1)

    It agrees with the dual-quaternion product of the corresponding dual quaternions.

    Parameters
    ----------
    q1, q2 : array_like, shape (..., 4)
        Unit quaternions.
    p1, p2 : array_like, shape (..., 3)
        Translations.
    tol : float

    Returns
    -------
    q : ndarray, shape (..., 4)
    p : ndarray, shape (..., 3)

    Examples
    --------
    >>> q, p = pair_product([0, 0, 0, 1], [1, 0, 0], [1, 0, 0, 0], [1, 0, 0])
    >>> q, p + 0.0
    (array([0., 0., 0., 1.]), array([0., 0., 0.]))
    """
    q1 = check_unit_quaternion(q1, tol, "q1")
    q2 = check_unit_quaternion(q2, tol, "q2")
    p1 = as_float_array(p1, "p1", _V)
    p2 = as_float_array(p2, "p2", _V)
    return quaternion_product(q1, q2), rotate_vector(q1, p2, tol=np.inf) + p1


# --------------------------------------------------------------------------------------
# Screw motions, powers, interpolation


def screw_from_dual_quaternion(
        Q: ArrayLike, *, tol: float = 1e-9, small_angle: float = 1e-12
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    r"""Screw parameters of a unit dual quaternion (Chasles' theorem).

    Every rigid motion is a rotation by :math:`\theta` about a line
    :math:`(\mathbf l, \mathbf m)` (unit direction, moment :math:`\mathbf m = \mathbf c
    \times \mathbf l` for any point :math:`\mathbf c` on it) combined with a translation
    :math:`d` along it:

    .. math::

        Q = \Bigl(\cos\tfrac\theta2,\; \sin\tfrac\theta2\,\mathbf l\Bigr)
          + \varepsilon\Bigl(-\tfrac d2\sin\tfrac\theta2,\;
            \sin\tfrac\theta2\,\mathbf m + \tfrac d2\cos\tfrac\theta2\,\mathbf l\Bigr).

    With :math:`\mathbf t` the translation of :math:`Q`, :math:`d = \mathbf t\cdot\mathbf l`
    and :math:`\mathbf m = \tfrac12\bigl(\mathbf t \times \mathbf l + \cot\tfrac\theta2\,
    (\mathbf t - d\,\mathbf l)\bigr)`. The pitch is :math:`h = d / \theta`.

    The sign of :math:`Q` is chosen so that :math:`\theta \in [0, \pi]`. A pure
    translation (:math:`\theta \le` ``small_angle``) returns :math:`\theta = 0`,
    :math:`\mathbf l = \mathbf t / |\mathbf t|`, :math:`\mathbf m = 0`, :math:`d =
    |\mathbf t|`; the identity returns :math:`\mathbf l = (1, 0, 0)`, :math:`d = 0`.
    For small non-zero angles the position of the axis is ill-conditioned (it recedes to
    infinity as the motion tends to a translation); :func:`dual_quaternion_power` and
    :func:`sclerp` therefore do not go through the screw parameters.

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Unit dual quaternions (checked).
    tol : float
        Tolerance of the unit check.
    small_angle : float
        Angles below this are treated as pure translations.

    Returns
    -------
    l : ndarray, shape (..., 3)
        Unit direction of the screw axis.
    m : ndarray, shape (..., 3)
        Moment of the axis.
    theta : ndarray, shape (...)
        Rotation angle in :math:`[0, \pi]`.
    d : ndarray, shape (...)
        Translation along the axis.

    Examples
    --------
    A half turn about the vertical line through (1, 0, 0), rising by 0.5:

    >>> import numpy as np
    >>> Q = dual_quaternion_from_screw([0, 0, 1], np.cross([1, 0, 0], [0, 0, 1]), np.pi, 0.5)
    >>> l, m, theta, d = screw_from_dual_quaternion(Q)
    >>> np.round(l, 12) + 0.0, np.round(m, 12) + 0.0, round(float(theta), 12), float(d)
    (array([0., 0., 1.]), array([ 0., -1.,  0.]), 3.14159265359, 0.5)
    """
    Q = check_unit_dual_quaternion(Q, tol)
    sign = np.where(Q[..., :1] < 0.0, -1.0, 1.0)
    Q = Q * sign
    q, t = rotation_translation_from_dual_quaternion(Q, tol=np.inf)
    v = q[..., 1:]
    s = np.sqrt(np.sum(v * v, axis=-1))
    theta = 2.0 * np.arctan2(s, q[..., 0])
    pure = theta <= small_angle
    tn = np.sqrt(np.sum(t * t, axis=-1))
    l_rot = v / np.where(pure, 1.0, s)[..., None]
    l_tr = np.where((tn == 0.0)[..., None], np.array([1.0, 0.0, 0.0]),
                    t / np.where(tn == 0.0, 1.0, tn)[..., None])
    l = np.where(pure[..., None], l_tr, l_rot)
    d = np.sum(t * l, axis=-1)
    cot = np.where(pure, 0.0, q[..., 0] / np.where(pure, 1.0, s))
    m = 0.5 * (np.cross(t, l) + cot[..., None] * (t - d[..., None] * l))
    m = np.where(pure[..., None], 0.0, m)
    return l, m, theta, d


def dual_quaternion_from_screw(l: ArrayLike, m: ArrayLike, theta: ArrayLike, d: ArrayLike
                               ) -> NDArray[np.float64]:
    r"""Unit dual quaternion of a screw motion (inverse of :func:`screw_from_dual_quaternion`).

    .. math::

        Q = \Bigl(\cos\tfrac\theta2,\; \sin\tfrac\theta2\,\mathbf l\Bigr)
          + \varepsilon\Bigl(-\tfrac d2\sin\tfrac\theta2,\;
            \sin\tfrac\theta2\,\mathbf m + \tfrac d2\cos\tfrac\theta2\,\mathbf l\Bigr)

    Parameters
    ----------
    l : array_like, shape (..., 3)
        Unit direction of the axis (checked to be unit within 1e-9).
    m : array_like, shape (..., 3)
        Moment of the axis (checked orthogonal to ``l`` within 1e-9 relative to
        :math:`\max(1, |\mathbf m|)`).
    theta : array_like, shape (...)
        Rotation angle.
    d : array_like, shape (...)
        Translation along the axis.

    Returns
    -------
    ndarray, shape (..., 8)

    Examples
    --------
    >>> import numpy as np
    >>> np.round(dual_quaternion_from_screw([0, 0, 1], [0, 0, 0], 0.0, 2.0), 12) + 0.0
    array([1., 0., 0., 0., 0., 0., 0., 1.])
    """
    l = as_float_array(l, "l", _V)
    m = as_float_array(m, "m", _V)
    theta = as_float_array(theta, "theta")
    d = as_float_array(d, "d")
    ln = norm_last_axis(l)
    if np.any(np.abs(ln - 1.0) > 1e-9):
        raise ValueError("l must be a unit vector (the direction of the screw axis)")
    mn = norm_last_axis(m)
    if np.any(np.abs(np.sum(l * m, axis=-1)) > 1e-9 * np.maximum(1.0, mn)):
        raise ValueError("m must be orthogonal to l (it is the moment c x l of the axis)")
    shape = np.broadcast_shapes(l.shape[:-1], m.shape[:-1], theta.shape, d.shape)
    parts = screw_entries(*np.moveaxis(l, -1, 0), *np.moveaxis(m, -1, 0),
                         np.cos(0.5 * theta), np.sin(0.5 * theta), 0.5 * d)
    Q = np.empty(shape + (8,))
    for k, part in enumerate(parts):
        Q[..., k] = part
    return Q


def dual_quaternion_power(Q: ArrayLike, t: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Power :math:`Q^t` of a unit dual quaternion: the same screw, scaled.

    In screw form (:func:`screw_from_dual_quaternion`) :math:`Q^t` turns by
    :math:`t\theta` about the same axis and moves by :math:`t d` along it; :math:`Q^0 = 1`,
    :math:`Q^1 = Q`, :math:`Q^{1/2} Q^{1/2} = Q`. The sign of :math:`Q` is chosen first so
    that :math:`\theta \le \pi` (the short way round).

    The screw axis is ill-conditioned for small angles (it recedes to infinity as the
    motion tends to a translation), so the power is computed without it. With
    :math:`Q = (\cos h, \mathbf u) + \varepsilon(q_{d,w}, \mathbf q_{d,v})`,
    :math:`h = \theta/2`, :math:`\mathbf u = \sin h\, \mathbf l`, translation
    :math:`\mathbf p` and :math:`\rho = \sin(th)/\sin h`:

    .. math::

        Q^t = \bigl(\cos th,\; \rho\,\mathbf u\bigr)
        + \varepsilon\Bigl(-\tfrac t2\,\rho\,(\mathbf p\cdot\mathbf u),\;
        \rho\,\mathbf q_{d,v}
        + \tfrac12\,\frac{t\cos th - \rho\cos h}{\sin^2 h}\,
        (\mathbf p\cdot\mathbf u)\,\mathbf u\Bigr),

    where every factor stays accurate as :math:`h \to 0` (the fraction tends to
    :math:`t(1 - t^2)/3`).

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Unit dual quaternions.
    t : array_like, shape (...)
        Exponents.
    tol : float

    Returns
    -------
    ndarray, shape (..., 8)

    Examples
    --------
    >>> Q = dual_quaternion_from_rotation_translation([1, 0, 0, 0], [2, 0, 0])
    >>> dual_quaternion_power(Q, 0.5) + 0.0
    array([1. , 0. , 0. , 0. , 0. , 0.5, 0. , 0. ])
    """
    Q = check_unit_dual_quaternion(Q, tol)
    t = as_float_array(t, "t")
    Q = Q * np.where(Q[..., :1] < 0.0, -1.0, 1.0)
    w, u, qd = Q[..., 0], Q[..., 1:4], Q[..., 4:]
    p = rotation_translation_from_dual_quaternion(Q, tol=np.inf)[1]
    s2 = np.sum(u * u, axis=-1)
    h = np.arctan2(np.sqrt(s2), w)
    th = t * h
    rho = t * np.sinc(th / np.pi) / np.sinc(h / np.pi)
    small = s2 == 0.0
    pu = np.sum(p * u, axis=-1)
    shape = np.broadcast_shapes(Q.shape[:-1], t.shape)
    out = np.empty(shape + (8,))
    with np.errstate(over="ignore", invalid="ignore"):
        frac = np.where(small, t * (1.0 - t * t) / 3.0,
                        (t * np.cos(th) - rho * w) / np.where(small, 1.0, s2))
        out[..., 0] = np.cos(th)
        out[..., 1:4] = rho[..., None] * u
        out[..., 4] = -0.5 * t * rho * pu
        out[..., 5:8] = rho[..., None] * qd[..., 1:] + (0.5 * frac * pu)[..., None] * u
    if not np.isfinite(out).all():
        raise ValueError("t is too large: the power overflows")
    return out


def sclerp(Q0: ArrayLike, Q1: ArrayLike, t: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Screw linear interpolation between unit dual quaternions.

    .. math::

        \operatorname{ScLERP}(Q_0, Q_1, t) = Q_0\,(Q_0^{*} Q_1)^t

    The motion from :math:`Q_0` to :math:`Q_1` is a single screw (constant rotation and
    translation rates about and along one axis). As with :func:`dqlab.quaternion.slerp`
    the shortest rotation is taken (:math:`Q_1` and :math:`-Q_1` give the same path).

    Parameters
    ----------
    Q0, Q1 : array_like, shape (..., 8)
        Unit dual quaternions (checked).
    t : array_like, shape (...)
        Interpolation parameters, 0 gives ``Q0``, 1 gives ``Q1`` (up to sign).
    tol : float

    Returns
    -------
    ndarray, shape (..., 8)

    Examples
    --------
    >>> Q0 = dual_quaternion_identity()
    >>> Q1 = dual_quaternion_from_rotation_translation([0, 0, 0, 1], [0, 0, 1])
    >>> Q = sclerp(Q0, Q1, 0.5)          # a quarter turn and half the rise
    >>> np.round(transform_from_dual_quaternion(Q)[:3, 3], 12) + 0.0
    array([0. , 0. , 0.5])
    """
    Q0 = check_unit_dual_quaternion(Q0, tol, "Q0")
    Q1 = check_unit_dual_quaternion(Q1, tol, "Q1")
    D = dual_quaternion_product(dual_quaternion_conjugate(Q0), Q1)
    return dual_quaternion_product(Q0, dual_quaternion_power(D, t, tol=10 * tol))


# --------------------------------------------------------------------------------------
# Class wrapper


class DualQuaternion(ArrayWrapper):
    """A dual quaternion, or a batch of them, for readable notebook code.

    A thin wrapper over the array functions of this module. ``.array`` is the ``(..., 8)``
    float array, ``.real`` and ``.dual`` its two quaternion halves, ``.shape`` its leading
    (batch) shape. Indexing, ``len``, ``*`` (the product, or scaling by a number), ``+``,
    ``-``, ``**`` and ``==`` work as for :class:`dqlab.quaternion.Quaternion` (both classes
    share them).

    Parameters
    ----------
    Q : array_like, shape (..., 8), or DualQuaternion

    Examples
    --------
    >>> import numpy as np
    >>> A = DualQuaternion.from_rotation_translation([0, 0, 0, 1], [1, 0, 0])
    >>> B = DualQuaternion.from_matrix(np.eye(4))
    >>> (A * B).apply([1, 0, 0]).round(12) + 0.0
    array([0., 0., 0.])
    >>> DualQuaternion.identity()
    DualQuaternion([1., 0., 0., 0., 0., 0., 0., 0.])
    """

    __slots__ = ()
    _trailing, _name, _product = _D, "Q", staticmethod(dual_quaternion_product)

    @classmethod
    def identity(cls, shape=()):
        """The identity motion (or a batch of them)."""
        return cls(dual_quaternion_identity(shape))

    @classmethod
    def from_matrix(cls, T, *, tol=1e-9):
        """See :func:`dual_quaternion_from_transform`."""
        return cls(dual_quaternion_from_transform(T, tol=tol))

    from_transform = from_matrix

    @classmethod
    def from_rotation_translation(cls, q, t):
        """See :func:`dual_quaternion_from_rotation_translation` (``q`` may be a Quaternion)."""
        return cls(dual_quaternion_from_rotation_translation(array_of(q), t))

    @classmethod
    def from_pair(cls, q, p):
        """See :func:`dual_quaternion_from_pair`."""
        return cls(dual_quaternion_from_pair(array_of(q), p))

    @classmethod
    def from_screw(cls, l, m, theta, d):
        """See :func:`dual_quaternion_from_screw`."""
        return cls(dual_quaternion_from_screw(l, m, theta, d))

    @property
    def real(self):
        """Real part :math:`q_r`, shape (..., 4)."""
        return self.array[..., :4]

    @property
    def dual(self):
        """Dual part :math:`q_d`, shape (..., 4)."""
        return self.array[..., 4:]

    def conjugate(self):
        """See :func:`dual_quaternion_conjugate`."""
        return DualQuaternion(dual_quaternion_conjugate(self.array))

    def dual_conjugate(self):
        """See :func:`dual_quaternion_dual_conjugate`."""
        return DualQuaternion(dual_quaternion_dual_conjugate(self.array))

    def combined_conjugate(self):
        """See :func:`dual_quaternion_combined_conjugate`."""
        return DualQuaternion(dual_quaternion_combined_conjugate(self.array))

    def inverse(self):
        """See :func:`dual_quaternion_inverse`."""
        return DualQuaternion(dual_quaternion_inverse(self.array))

    def norm(self):
        """See :func:`dual_quaternion_norm`: ``(..., 2)`` dual numbers."""
        return dual_quaternion_norm(self.array)

    def normalized(self):
        """See :func:`dual_quaternion_normalize`."""
        return DualQuaternion(dual_quaternion_normalize(self.array))

    def is_unit(self, tol=1e-9):
        """True when this is a unit dual quaternion (a rigid motion) within ``tol``."""
        try:
            check_unit_dual_quaternion(self.array, tol)
        except ValueError:
            return False
        return True

    def apply(self, points):
        """Move points; see :func:`dual_quaternion_apply`."""
        return dual_quaternion_apply(self.array, points)

    def apply_vector(self, vectors):
        """Rotate free vectors; see :func:`dual_quaternion_apply_vector`."""
        return dual_quaternion_apply_vector(self.array, vectors)

    def matrix(self):
        """See :func:`transform_from_dual_quaternion`."""
        return transform_from_dual_quaternion(self.array)

    def rotation_translation(self):
        """``(q, t)``; see :func:`rotation_translation_from_dual_quaternion`."""
        return rotation_translation_from_dual_quaternion(self.array)

    def pair(self):
        """``(q, p)``; see :func:`pair_from_dual_quaternion`."""
        return pair_from_dual_quaternion(self.array)

    def translation(self):
        """Translation ``(..., 3)``."""
        return rotation_translation_from_dual_quaternion(self.array)[1]

    def rotation(self):
        """Rotation part as a :class:`dqlab.quaternion.Quaternion`."""
        from .quaternion import Quaternion

        return Quaternion(rotation_translation_from_dual_quaternion(self.array)[0])

    def screw(self):
        """``(l, m, theta, d)``; see :func:`screw_from_dual_quaternion`."""
        return screw_from_dual_quaternion(self.array)

    def power(self, t):
        """See :func:`dual_quaternion_power`."""
        return DualQuaternion(dual_quaternion_power(self.array, t))

    def sclerp(self, other, t):
        """See :func:`sclerp`."""
        return DualQuaternion(sclerp(self.array, array_of(other), t))

    def __str__(self):
        if self.array.ndim != 1:
            return repr(self)
        r = self.array.tolist()
        return ("({:.6g} {:+.6g}i {:+.6g}j {:+.6g}k) + eps ({:.6g} {:+.6g}i {:+.6g}j {:+.6g}k)"
                .format(*r))



# --------------------------------------------------------------------------------------
# Rates: the derivative of a moving rigid motion (chapter "Differential kinematics")

__all__ += ["dual_quaternion_rate", "twist_from_dual_quaternion_rate"]


def dual_quaternion_rate(Q, twist, *, tol=1e-9):
    r"""Time derivative of a unit dual quaternion moving with the spatial twist ``twist``.

    With the twist as the pure dual quaternion
    :math:`\xi = (0, \omega) + \varepsilon\,(0, \mathbf v_O)`:

    .. math::

        \dot Q = \tfrac12\, \xi\, Q .

    Here :math:`\omega` is the angular velocity and :math:`\mathbf v_O` the velocity of the
    body point that is passing through the world origin, both in the world frame. For
    :math:`Q = q + \varepsilon\tfrac12 \mathbf t q` the real part is the quaternion rate
    :math:`\dot q = \tfrac12\omega q` and the dual part gives
    :math:`\mathbf v_O = \dot{\mathbf t} - \omega \times \mathbf t`; the velocity of any
    other body point :math:`\mathbf p` is :math:`\mathbf v_O + \omega \times \mathbf p`.

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Unit dual quaternions.
    twist : array_like, shape (..., 6)
        :math:`(\mathbf v_O, \omega)`, linear part first as in a geometric Jacobian;
        broadcast with the leading axes of ``Q``.
    tol : float
        Accepted deviation from the unit conditions.

    Returns
    -------
    ndarray, shape (..., 8)
        :math:`\dot Q`.

    Raises
    ------
    ValueError
        ``Q`` not a unit dual quaternion, or ``twist`` of the wrong shape or not finite.

    See Also
    --------
    twist_from_dual_quaternion_rate : the inverse map.
    dqlab.quaternion.quaternion_rate : the real part alone.

    Examples
    --------
    A pure translation at 1 m/s along x, seen from the identity:

    >>> dual_quaternion_rate([1, 0, 0, 0, 0, 0, 0, 0], [1, 0, 0, 0, 0, 0])
    array([0. , 0. , 0. , 0. , 0. , 0.5, 0. , 0. ])
    """
    Q = check_unit_dual_quaternion(Q, tol)
    twist = as_float_array(twist, "twist", (6,))
    zero = np.zeros(twist.shape[:-1] + (1,))
    xi = np.concatenate([zero, twist[..., 3:], zero, twist[..., :3]], axis=-1)
    return 0.5 * dual_quaternion_product(xi, Q)


def twist_from_dual_quaternion_rate(Q, Q_dot, *, tol=1e-9):
    r"""Spatial twist :math:`(\mathbf v_O, \omega)` of a unit dual quaternion moving at ``Q_dot``.

    The inverse of :func:`dual_quaternion_rate`, since :math:`Q^{-1} = Q^*` for a unit
    dual quaternion:

    .. math::

        \xi = 2\, \dot Q\, Q^* = (0, \omega) + \varepsilon\,(0, \mathbf v_O).

    Parameters
    ----------
    Q : array_like, shape (..., 8)
        Unit dual quaternions.
    Q_dot : array_like, shape (..., 8)
        Their time derivatives.
    tol : float
        Accepted deviation from the unit conditions.

    Returns
    -------
    ndarray, shape (..., 6)
        :math:`(\mathbf v_O, \omega)`: the velocity of the body point at the world origin and
        the angular velocity, world frame.

    Raises
    ------
    ValueError
        ``Q`` not a unit dual quaternion, or ``Q_dot`` of the wrong shape or not finite.

    Examples
    --------
    >>> import numpy as np
    >>> Q = dual_quaternion_from_rotation_translation([0, 0, 0, 1], [0.1, 0.2, 0.3])
    >>> twist = [0.05, 0.0, -0.02, 0.0, 0.3, 1.0]
    >>> np.allclose(twist_from_dual_quaternion_rate(Q, dual_quaternion_rate(Q, twist)),
    ...             twist)
    True
    """
    Q = check_unit_dual_quaternion(Q, tol)
    Q_dot = as_float_array(Q_dot, "Q_dot", _D)
    xi = 2.0 * dual_quaternion_product(Q_dot, dual_quaternion_conjugate(Q))
    return np.concatenate([xi[..., 5:8], xi[..., 1:4]], axis=-1)
