r"""The planar two-link arm, the closed-form core of the desk-arm and SCARA solvers.

A point :math:`(u, v)` relative to the shoulder of two links :math:`l_1, l_2` is reached
with the elbow angle :math:`\theta_b` from the law of cosines and the shoulder angle
:math:`\theta_a` from two ``atan2``:

.. math::

   \cos\theta_b = \frac{u^2 + v^2 - l_1^2 - l_2^2}{2 l_1 l_2},\qquad
   \theta_a = \operatorname{atan2}(v, u)
              - \operatorname{atan2}(l_2 \sin\theta_b,\; l_1 + l_2 \cos\theta_b).
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["elbow_cosine", "two_link_angles"]


def elbow_cosine(u: ArrayLike, v: ArrayLike, l1: float, l2: float
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    r"""Cosine and (non-negative) sine of the elbow angle, and whether the point is reached.

    An unreachable point (:math:`|\cos\theta_b| > 1`) gets the clipped cosine: the arm
    stretched or folded towards it, the closest it comes.

    Parameters
    ----------
    u, v : array_like, shape (...)
        The point in the arm's plane, relative to the shoulder.
    l1, l2 : float
        Link lengths.

    Returns
    -------
    c, s : ndarray, shape (...)
        :math:`\cos\theta_b` in [-1, 1] and :math:`|\sin\theta_b|`.
    reachable : ndarray of bool, shape (...)

    Examples
    --------
    >>> c, s, reachable = elbow_cosine([1.0, 3.0], [1.0, 0.0], 1.0, 1.0)
    >>> c, s, reachable
    (array([0., 1.]), array([1., 0.]), array([ True, False]))
    """
    u, v = np.asarray(u, dtype=float), np.asarray(v, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):   # far away: c = inf, out of reach
        c = (u * u + v * v - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    reachable = np.abs(c) <= 1.0 + 1e-12
    c = np.clip(c, -1.0, 1.0)
    return c, np.sqrt(1.0 - c * c), reachable


def two_link_angles(u: ArrayLike, v: ArrayLike, c: ArrayLike, s: ArrayLike, l1: float,
                    l2: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Shoulder and elbow angles :math:`(\theta_a, \theta_b)` for the elbow's cosine ``c``
    and signed sine ``s`` (the sign picks the branch).

    Examples
    --------
    >>> import numpy as np
    >>> a, b = two_link_angles(1.0, 1.0, 0.0, 1.0, 1.0, 1.0)
    >>> float(a), float(np.degrees(b))
    (0.0, 90.0)
    """
    theta_b = np.arctan2(s, c)
    theta_a = np.arctan2(v, u) - np.arctan2(l2 * np.asarray(s), l1 + l2 * np.asarray(c))
    return theta_a, theta_b
