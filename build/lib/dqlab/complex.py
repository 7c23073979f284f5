r"""Planar rotations with complex numbers, and planar serial arms as sums of products.

A point :math:`(x, y)` of the plane is the complex number :math:`z = x + iy`.
Multiplying by :math:`r e^{i\theta}` scales it by :math:`r` and turns it by :math:`\theta`
about the origin; multiplying rotations adds their angles,
:math:`e^{i\alpha} e^{i\beta} = e^{i(\alpha + \beta)}`. Every function takes array-likes
and broadcasts (NumPy's ``complex128``).
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import as_float_array

__all__ = [
    "rotate_planar", "scale_rotate", "polar", "from_polar", "compose_planar",
    "planar_arm_joints", "planar_arm_tip", "point_from_complex", "complex_from_point",
]


def _complex(z, name):
    try:
        z = np.asarray(z, dtype=complex)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of numbers: {exc}") from None
    if not np.all(np.isfinite(z)):
        raise ValueError(f"{name} contains NaN or infinity")
    return z


def rotate_planar(z: ArrayLike, theta: ArrayLike) -> NDArray[np.float64]:
    r"""Turn points of the plane by ``theta`` about the origin: :math:`z' = z\,e^{i\theta}`.

    .. math::

        (x + iy)(\cos\theta + i\sin\theta)
        = (x\cos\theta - y\sin\theta) + i\,(x\sin\theta + y\cos\theta)

    which is the rotation matrix :math:`R(\theta)` acting on :math:`(x, y)`.

    Parameters
    ----------
    z : array_like of complex, shape (...)
        Points of the plane.
    theta : array_like, shape (...)
        Angles in radians (counter-clockwise); broadcasts with ``z``.

    Returns
    -------
    ndarray of complex, shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> np.round(rotate_planar(1 + 0j, np.pi / 2), 12)
    np.complex128(1j)
    """
    z = _complex(z, "z")
    theta = as_float_array(theta, "theta")
    return z * np.exp(1j * theta)


def scale_rotate(z: ArrayLike, r: ArrayLike, theta: ArrayLike) -> NDArray[np.float64]:
    r"""Scale by ``r`` and turn by ``theta``: :math:`z' = r e^{i\theta} z`.

    Parameters
    ----------
    z : array_like of complex, shape (...)
    r : array_like, shape (...)
        Scale factors.
    theta : array_like, shape (...)
        Angles in radians.

    Returns
    -------
    ndarray of complex, shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> np.round(scale_rotate(1 + 1j, 2, np.pi / 4), 12)
    np.complex128(2.828427124746j)
    """
    return _complex(z, "z") * from_polar(r, theta)


def polar(z: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Modulus and argument of complex numbers, :math:`z = r e^{i\varphi}`.

    Parameters
    ----------
    z : array_like of complex, shape (...)

    Returns
    -------
    r : ndarray, shape (...)
        :math:`|z|`.
    phi : ndarray, shape (...)
        :math:`\arg z \in (-\pi, \pi]` (0 for :math:`z = 0`).

    Examples
    --------
    >>> import numpy as np
    >>> r, phi = polar(1 + 1j)
    >>> round(float(r), 12), round(float(phi / np.pi), 12)
    (1.414213562373, 0.25)
    """
    z = _complex(z, "z")
    return np.abs(z), np.angle(z)


def from_polar(r: ArrayLike, phi: ArrayLike) -> NDArray[np.float64]:
    r"""Complex numbers :math:`r e^{i\varphi} = r(\cos\varphi + i\sin\varphi)`.

    Parameters
    ----------
    r : array_like, shape (...)
    phi : array_like, shape (...)

    Returns
    -------
    ndarray of complex, shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> np.round(from_polar(2, np.pi), 12)
    np.complex128(-2+0j)
    """
    r = as_float_array(r, "r")
    phi = as_float_array(phi, "phi")
    return r * np.exp(1j * phi)


def compose_planar(*thetas: ArrayLike) -> NDArray[np.float64]:
    r"""The single rotation :math:`e^{i(\theta_1 + \theta_2 + \cdots)}` of successive ones.

    Planar rotations commute; their composition is the product of unit complex numbers,
    whose angle is the sum of the angles.

    Parameters
    ----------
    *thetas : array_like, shape (...)

    Returns
    -------
    ndarray of complex, shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> np.round(compose_planar(np.pi / 6, np.pi / 3), 12)
    np.complex128(1j)
    """
    out = np.ones((), dtype=complex)
    for i, theta in enumerate(thetas):
        out = out * np.exp(1j * as_float_array(theta, f"thetas[{i}]"))
    return out


def planar_arm_joints(lengths: ArrayLike, angles: ArrayLike, relative: bool = True
                      ) -> NDArray[np.float64]:
    r"""Positions of the joints and the tip of a planar serial arm, as complex numbers.

    Link :math:`k` has length :math:`l_k` and absolute direction
    :math:`\varphi_k = \theta_1 + \cdots + \theta_k` (relative joint angles) so

    .. math::

        z_k = \sum_{j=1}^{k} l_j\, e^{i\varphi_j}
            = \sum_{j=1}^{k} l_j\, e^{i\theta_1} \cdots e^{i\theta_j},
        \qquad z_0 = 0,

    and the tip is :math:`z_n`.

    Parameters
    ----------
    lengths : array_like, shape (..., n)
        Link lengths.
    angles : array_like, shape (..., n)
        Joint angles in radians: relative (each measured from the previous link), or
        absolute (each from the x axis) when ``relative=False``.
    relative : bool

    Returns
    -------
    ndarray of complex, shape (..., n + 1)
        The base (0), the joints, and the tip last.

    Examples
    --------
    >>> import numpy as np
    >>> z = planar_arm_joints([1, 1], [np.pi / 2, -np.pi / 2])
    >>> np.round(z, 12)
    array([0.+0.j, 0.+1.j, 1.+1.j])
    """
    lengths = as_float_array(lengths, "lengths")
    angles = as_float_array(angles, "angles")
    if lengths.ndim == 0 or angles.ndim == 0 or lengths.shape[-1] != angles.shape[-1]:
        raise ValueError(
            "lengths and angles must have the same last dimension n (one per link), got "
            f"shapes {lengths.shape} and {angles.shape}")
    phi = np.cumsum(angles, axis=-1) if relative else angles
    links = lengths * np.exp(1j * phi)
    z = np.cumsum(links, axis=-1)
    base = np.zeros(z.shape[:-1] + (1,), dtype=complex)
    return np.concatenate([base, z], axis=-1)


def planar_arm_tip(lengths: ArrayLike, angles: ArrayLike, relative: bool = True):
    r"""Tip of a planar serial arm, :math:`\sum_k l_k e^{i(\theta_1 + \cdots + \theta_k)}`.

    See :func:`planar_arm_joints`.

    Examples
    --------
    >>> import numpy as np
    >>> np.round(planar_arm_tip([1, 1], [0, np.pi / 2]), 12)
    np.complex128(1+1j)
    """
    return planar_arm_joints(lengths, angles, relative)[..., -1]


def point_from_complex(z: ArrayLike):
    """``(..., 2)`` real coordinates ``(x, y)`` of complex numbers.

    Examples
    --------
    >>> point_from_complex([1 + 2j])
    array([[1., 2.]])
    """
    z = _complex(z, "z")
    return np.stack([z.real, z.imag], axis=-1)


def complex_from_point(p: ArrayLike):
    """Complex numbers ``x + iy`` of ``(..., 2)`` points.

    Examples
    --------
    >>> complex_from_point([3, 4])
    np.complex128(3+4j)
    """
    p = as_float_array(p, "p", (2,))
    return p[..., 0] + 1j * p[..., 1]
