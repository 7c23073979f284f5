r"""Homogeneous transforms: build, compose, invert, apply.

A rigid transform is stored as a ``(..., 4, 4)`` matrix

.. math::

    X_{AB} = \begin{pmatrix} R_{AB} & \mathbf p_{AB} \\ \mathbf 0^\mathsf{T} & 1
    \end{pmatrix},

the pose of frame B in frame A (monogram notation): the columns of :math:`R_{AB}` are B's
axes and :math:`\mathbf p_{AB}` is B's origin, both written in A. Composition reads
:math:`X_{AC} = X_{AB} X_{BC}`, and a point known in B is known in A by
:math:`\mathbf p_A = R_{AB}\,\mathbf p_B + \mathbf p_{AB}`.
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import as_float_array, batch_shape, component_rows, rotation_or_raise
from ._formulas import orthonormality, rigid_inverse
from .rotations import check_rotation_matrix

__all__ = [
    "transform_from", "transform_inverse", "compose", "apply_transform", "apply_to_vectors",
    "check_transform", "rotation_translation_from_transform", "transform_identity",
]


def check_transform(T: ArrayLike, tol: float = 1e-9, name: str = "T") -> NDArray[np.float64]:
    r"""Return ``T`` as a float array, or raise if it is not a rigid transform.

    The bottom row must be exactly ``(0, 0, 0, 1)`` and the upper-left block a rotation
    matrix (see :func:`dqlab.rotations.check_rotation_matrix`).

    Parameters
    ----------
    T : array_like, shape (..., 4, 4)
    tol : float
        Tolerance of the orthonormality check.
    name : str
        Name used in the error message.

    Returns
    -------
    ndarray, shape (..., 4, 4)

    Raises
    ------
    ValueError
        Wrong shape, NaN/inf, bottom row not ``(0, 0, 0, 1)``, rotation block not a rotation.

    Examples
    --------
    >>> check_transform(np.eye(4)).shape
    (4, 4)
    >>> check_transform(2 * np.eye(4))
    Traceback (most recent call last):
    ...
    ValueError: T must have bottom row (0, 0, 0, 1), got [0.0, 0.0, 0.0, 2.0]
    """
    return checked_transform_entries(T, tol, name)[0]


def checked_transform_entries(T, tol, name):
    """:func:`check_transform`, which also returns the sixteen entries of a batch it read
    to check it, for a caller that goes on with them: the rows, in the order of the
    transforms' rows, of a new array (16, ...) (None for one transform)."""
    T = as_float_array(T, name, (4, 4))
    bottom = T[..., 3, :]
    if T.ndim == 2:
        if bottom.tolist() != [0.0, 0.0, 0.0, 1.0]:
            raise ValueError(f"{name} must have bottom row (0, 0, 0, 1), got {bottom.tolist()}")
        check_rotation_matrix(T[:3, :3], tol, f"the rotation block of {name}")
        return T, None
    # a batch: the entries, one copy to a component-major layout
    e = component_rows(T.reshape(T.shape[:-2] + (16,)))
    if any(e[k].any() for k in (12, 13, 14)) or (e[15] != 1.0).any():   # no NaN: checked
        bad = bottom[np.any(bottom != np.array([0.0, 0.0, 0.0, 1.0]), axis=-1)][0]
        raise ValueError(f"{name} must have bottom row (0, 0, 0, 1), got {bad.tolist()}")
    err, det = orthonormality(e[0:3], e[4:7], e[8:11])
    if not (err <= tol and det > 0.0):
        rotation_or_raise(f"the rotation block of {name}", err, det, tol)
    return T, e


def transform_identity(shape=()):
    """Identity transforms of shape ``shape + (4, 4)``.

    Examples
    --------
    >>> transform_identity((2,)).shape
    (2, 4, 4)
    """
    return np.broadcast_to(np.eye(4), batch_shape(shape) + (4, 4)).copy()


def transform_from(R: ArrayLike, p: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Homogeneous transform from a rotation matrix and a translation.

    .. math::

        X = \begin{pmatrix} R & \mathbf p \\ \mathbf 0^\mathsf{T} & 1 \end{pmatrix}

    Parameters
    ----------
    R : array_like, shape (..., 3, 3)
        Rotation matrices (checked).
    p : array_like, shape (..., 3)
        Translations; leading axes broadcast with those of ``R``.
    tol : float
        Tolerance of the rotation-matrix check.

    Returns
    -------
    ndarray, shape (..., 4, 4)

    Examples
    --------
    >>> transform_from(np.eye(3), [1, 2, 3])
    array([[1., 0., 0., 1.],
           [0., 1., 0., 2.],
           [0., 0., 1., 3.],
           [0., 0., 0., 1.]])
    """
    R = check_rotation_matrix(R, tol)
    p = as_float_array(p, "p", (3,))
    shape = np.broadcast_shapes(R.shape[:-2], p.shape[:-1])
    T = np.zeros(shape + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = p
    T[..., 3, 3] = 1.0
    return T


def rotation_translation_from_transform(T: ArrayLike, *, tol: float = 1e-9):
    """Split a transform into its rotation matrix ``(..., 3, 3)`` and translation ``(..., 3)``.

    Examples
    --------
    >>> R, p = rotation_translation_from_transform(transform_from(np.eye(3), [1, 2, 3]))
    >>> p
    array([1., 2., 3.])
    """
    T = check_transform(T, tol)
    return T[..., :3, :3].copy(), T[..., :3, 3].copy()


def transform_inverse(T: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Inverse of rigid transforms, without a general matrix inverse.

    .. math::

        X^{-1} = \begin{pmatrix} R^\mathsf{T} & -R^\mathsf{T}\mathbf p \\
        \mathbf 0^\mathsf{T} & 1 \end{pmatrix}, \qquad X_{BA} = X_{AB}^{-1}

    Parameters
    ----------
    T : array_like, shape (..., 4, 4)
        Rigid transforms (checked).
    tol : float
        Tolerance of the check.

    Returns
    -------
    ndarray, shape (..., 4, 4)

    Examples
    --------
    >>> from dqlab.rotations import rot_z
    >>> X = transform_from(rot_z(0.5), [1, 2, 3])
    >>> np.allclose(transform_inverse(X) @ X, np.eye(4))
    True
    """
    return rigid_inverse(check_transform(T, tol))


def compose(*Ts: ArrayLike) -> NDArray[np.float64]:
    r"""Product of transforms, left to right: ``compose(X_AB, X_BC, X_CD)`` is ``X_AD``.

    .. math::

        X_{AD} = X_{AB}\, X_{BC}\, X_{CD}

    Parameters
    ----------
    *Ts : array_like, shape (..., 4, 4)
        Transforms (shape-checked, not checked for rigidity); leading axes broadcast.

    Returns
    -------
    ndarray, shape (..., 4, 4)
        The identity when called without arguments.

    Examples
    --------
    >>> a = transform_from(np.eye(3), [1, 0, 0])
    >>> compose(a, a, a)[:3, 3]
    array([3., 0., 0.])
    """
    if not Ts:
        return np.eye(4)
    out = as_float_array(Ts[0], "Ts[0]", (4, 4))
    for i, T in enumerate(Ts[1:], 1):
        out = out @ as_float_array(T, f"Ts[{i}]", (4, 4))
    return out if len(Ts) > 1 else out.copy()


def apply_transform(T: ArrayLike, points: ArrayLike) -> NDArray[np.float64]:
    r"""Transform points: :math:`\mathbf p_A = R_{AB}\,\mathbf p_B + \mathbf p_{AB}`.

    Parameters
    ----------
    T : array_like, shape (..., 4, 4)
        Transforms ``X_AB``.
    points : array_like, shape (..., 3)
        Points in B; leading axes broadcast with those of ``T``.

    Returns
    -------
    ndarray, shape (..., 3)
        The points in A.

    Examples
    --------
    >>> from dqlab.rotations import rot_z
    >>> X = transform_from(rot_z(np.pi / 2), [1, 0, 0])
    >>> np.round(apply_transform(X, [1, 0, 0]), 12)
    array([1., 1., 0.])
    """
    T = as_float_array(T, "T", (4, 4))
    p = as_float_array(points, "points", (3,))
    return (T[..., :3, :3] @ p[..., None])[..., 0] + T[..., :3, 3]


def apply_to_vectors(T: ArrayLike, vectors: ArrayLike) -> NDArray[np.float64]:
    r"""Transform free vectors (directions, velocities): rotation only, :math:`R\,\mathbf v`.

    Parameters
    ----------
    T : array_like, shape (..., 4, 4)
    vectors : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> from dqlab.rotations import rot_z
    >>> X = transform_from(rot_z(np.pi / 2), [1, 0, 0])
    >>> np.round(apply_to_vectors(X, [1, 0, 0]), 12) + 0.0
    array([0., 1., 0.])
    """
    T = as_float_array(T, "T", (4, 4))
    v = as_float_array(vectors, "vectors", (3,))
    return (T[..., :3, :3] @ v[..., None])[..., 0]
