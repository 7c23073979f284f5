r"""Differential kinematics: Jacobians, manipulability and singularities.

The direct kinematic model (MCD in the French course notes) maps joint velocities to the
velocity of the tool, :math:`\dot x = J(q)\, \dot q`. Two forms are used in the book:

- the *geometric* Jacobian (:meth:`dqlab.robot.Robot.jacobian`, a method of the robot),
  whose rows are the linear velocity of the tool centre point and the angular velocity of
  the tool, both in the world frame;
- an *analytic* Jacobian, the derivative of a minimal set of coordinates; for the SCARA,
  :math:`(x, y, z, \text{yaw})` (:func:`scara_jacobian`).
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import as_float_array
from .models import SCARA_SHAPE
from .robot import Robot

__all__ = [
    "manipulability", "singular_values", "is_singular",
    "xyz_yaw_jacobian", "scara_jacobian", "scara_jacobian_determinant", "scara_is_singular",
]


def singular_values(J: ArrayLike) -> NDArray[np.float64]:
    """Singular values of Jacobians, largest first.

    Parameters
    ----------
    J : array_like, shape (..., m, n)

    Returns
    -------
    ndarray, shape (..., min(m, n))

    Examples
    --------
    >>> singular_values([[2.0, 0.0], [0.0, 0.5]])
    array([2. , 0.5])
    """
    J = as_float_array(J, "J")
    if J.ndim < 2:
        raise ValueError(f"J must have shape (..., m, n), got shape {J.shape}")
    return np.linalg.svd(J, compute_uv=False)


def manipulability(J: ArrayLike) -> NDArray[np.float64]:
    r"""Yoshikawa's manipulability measure :math:`w = \sqrt{\det(J J^\top)}`.

    Computed as the product of the singular values of :math:`J`, which is the same number
    and stays accurate near singularities. It is zero exactly at a singular configuration.
    Rows with different units (metres, radians) are mixed: compare values of one robot, or
    pass only the linear rows ``J[..., :3, :]``.

    Parameters
    ----------
    J : array_like, shape (..., m, n), m <= n

    Returns
    -------
    ndarray, shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> q = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.0])
    >>> bool(manipulability(robot.jacobian(q)) > 0)
    True
    >>> q[4] = 0.0   # wrist singularity: joints 4 and 6 aligned
    >>> float(manipulability(robot.jacobian(q))) < 1e-15
    True
    """
    J = as_float_array(J, "J")
    if J.ndim < 2 or J.shape[-2] > J.shape[-1]:
        raise ValueError(f"J must have shape (..., m, n) with m <= n, got shape {J.shape}")
    with np.errstate(over="ignore"):
        w = np.prod(singular_values(J), axis=-1)
    if not np.isfinite(w).all():
        raise ValueError("J is too large: its manipulability overflows")
    return w


def is_singular(J: ArrayLike, tol: float = 1e-6) -> NDArray[np.bool_]:
    r"""Whether Jacobians are singular: smallest singular value below ``tol``.

    Parameters
    ----------
    J : array_like, shape (..., m, n)
    tol : float, optional
        Threshold on :math:`\sigma_{\min}(J)`. For the UR3 (lengths of a few tenths of a
        metre) ``1e-6`` flags configurations within about a micro-radian of a singularity.

    Returns
    -------
    ndarray of bool, shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> bool(is_singular(robot.jacobian([0.3, -1.2, 1.0, -0.5, 1.1, 0.0])))
    False
    >>> bool(is_singular(robot.jacobian([0.3, -1.2, 0.0, -0.5, 1.1, 0.0])))   # elbow straight
    True
    """
    return singular_values(J)[..., -1] < tol


def xyz_yaw_jacobian(robot: Robot, q: ArrayLike, *, tol: float = 1e-9) -> NDArray[np.float64]:
    r"""Analytic Jacobian of :math:`(x, y, z, \text{yaw})` for a robot whose joint axes are
    all vertical (a SCARA).

    When every joint axis is parallel to the world z axis, the tool only turns about z, so
    :math:`\dot{\text{yaw}} = \omega_z` and the analytic Jacobian is the geometric one
    without the rows of :math:`\omega_x, \omega_y`: rows 0, 1, 2, 5.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (..., n)
    tol : float, optional
        Tolerance on the axes' deviation from vertical.

    Returns
    -------
    ndarray, shape (..., 4, n)

    Raises
    ------
    ValueError
        If some joint axis is not vertical.

    Examples
    --------
    >>> from dqlab.models import scara_rsm5
    >>> xyz_yaw_jacobian(scara_rsm5(), [0.0, 0.0, 0.1, 0.0]).round(6)
    array([[0.  , 0.  , 0.  , 0.  ],
           [0.61, 0.26, 0.  , 0.  ],
           [0.  , 0.  , 1.  , 0.  ],
           [1.  , 1.  , 0.  , 1.  ]])
    """
    _, axes = robot.joint_axes(q)
    if np.any(np.abs(np.abs(axes[..., 2]) - 1.0) > tol):
        raise ValueError("xyz_yaw_jacobian needs every joint axis vertical (a SCARA)")
    return robot.jacobian(q)[..., [0, 1, 2, 5], :]


def _scara_lengths(robot):
    """``l1, l2`` of a SCARA whose x, y, yaw are the world's: the chain of
    :data:`dqlab.models.SCARA_SHAPE` on an upright base, with a tool without x/y offset."""
    SCARA_SHAPE.check(robot)
    if not (np.allclose(robot.base[:3, :3], np.eye(3)) and np.allclose(robot.tool[:2, 3], 0.0)):
        raise ValueError(
            "the closed-form SCARA Jacobian needs an upright base and a tool without x/y "
            "offset (its x, y and yaw are the world's); use xyz_yaw_jacobian otherwise")
    return robot.links[1].a, robot.links[2].a


def scara_jacobian(robot: Robot, q: ArrayLike) -> NDArray[np.float64]:
    r"""Closed-form analytic Jacobian of the SCARA in :math:`(x, y, z, \text{yaw})`.

    Differentiating the forward model of :func:`dqlab.models.scara_rsm5`,
    :math:`x = l_1 C_1 + l_2 C_{12}`, :math:`y = l_1 S_1 + l_2 S_{12}`,
    :math:`z = z_0 + q_3`, :math:`\text{yaw} = q_1 + q_2 + q_4 + \text{const}`:

    .. math::

       J(q) = \begin{pmatrix}
         -l_1 S_1 - l_2 S_{12} & -l_2 S_{12} & 0 & 0 \\
          l_1 C_1 + l_2 C_{12} &  l_2 C_{12} & 0 & 0 \\
          0 & 0 & 1 & 0 \\
          1 & 1 & 0 & 1
       \end{pmatrix}

    Parameters
    ----------
    robot : Robot
        A SCARA as described by :func:`dqlab.models.scara_rsm5` (``l1 = links[1].a``,
        ``l2 = links[2].a``).
    q : array_like, shape (..., 4)

    Returns
    -------
    ndarray, shape (..., 4, 4)

    Raises
    ------
    ValueError
        If the robot does not have that structure.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import scara_rsm5
    >>> scara = scara_rsm5()
    >>> q = [0.3, 0.8, 0.05, -0.2]
    >>> np.allclose(scara_jacobian(scara, q), xyz_yaw_jacobian(scara, q))
    True
    """
    l1, l2 = _scara_lengths(robot)
    q = robot.check_joints(q)
    q1, q2 = q[..., 0], q[..., 1]
    s1, c1 = np.sin(q1), np.cos(q1)
    s12, c12 = np.sin(q1 + q2), np.cos(q1 + q2)
    J = np.zeros(q.shape[:-1] + (4, 4))
    J[..., 0, 0] = -l1 * s1 - l2 * s12
    J[..., 0, 1] = -l2 * s12
    J[..., 1, 0] = l1 * c1 + l2 * c12
    J[..., 1, 1] = l2 * c12
    J[..., 2, 2] = 1.0
    J[..., 3, 0] = 1.0
    J[..., 3, 1] = 1.0
    J[..., 3, 3] = 1.0
    return J


def scara_jacobian_determinant(robot: Robot, q: ArrayLike) -> NDArray[np.float64]:
    r"""Determinant of the SCARA's analytic Jacobian: :math:`\det J = l_1 l_2 \sin q_2`.

    The last two columns only touch :math:`z` and yaw, so the determinant is that of the
    planar 2x2 block, :math:`l_1 l_2 (S_{12} C_1 - C_{12} S_1) = l_1 l_2 S_2`. It vanishes
    for :math:`q_2 = 0` (arm stretched, the boundary of the workspace) and
    :math:`q_2 = \pm\pi` (arm folded back, outside the RSM-5's :math:`\pm 145^\circ` range):
    the singular configurations, independent of :math:`q_1, q_3, q_4`.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (..., 4)

    Returns
    -------
    ndarray, shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import scara_rsm5
    >>> round(float(scara_jacobian_determinant(scara_rsm5(), [0, np.pi / 2, 0, 0])), 6)
    0.091
    """
    l1, l2 = _scara_lengths(robot)
    q = robot.check_joints(q)
    return l1 * l2 * np.sin(q[..., 1])


def scara_is_singular(robot: Robot, q: ArrayLike, tol: float = 1e-6) -> NDArray[np.bool_]:
    r"""Whether the SCARA is (within ``tol``) at a singular configuration.

    Tests :math:`|\det J| < \text{tol}\; l_1 l_2`, that is :math:`|\sin q_2| < \text{tol}`.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (..., 4)
    tol : float, optional

    Returns
    -------
    ndarray of bool, shape (...)

    Examples
    --------
    >>> from dqlab.models import scara_rsm5
    >>> scara_is_singular(scara_rsm5(), [[0.2, 0.0, 0.1, 0.0], [0.2, 0.5, 0.1, 0.0]])
    array([ True, False])
    """
    l1, l2 = _scara_lengths(robot)
    return np.abs(scara_jacobian_determinant(robot, q)) < tol * l1 * l2


# --------------------------------------------------------------------------------------
# Analytic Jacobians: rates of orientation coordinates instead of the angular velocity

__all__ += ["rpy_rate_matrix", "quaternion_rate_matrix", "analytic_jacobian"]


def rpy_rate_matrix(rpy):
    r"""The matrix :math:`E` with :math:`\omega = E(\phi)\, \dot\phi` for roll, pitch, yaw.

    For Craig's angles :math:`\phi = (\gamma, \beta, \alpha)`,
    :math:`R = R_z(\alpha) R_y(\beta) R_x(\gamma)` (see
    :func:`dqlab.rotations.matrix_from_rpy`), each rate turns about its own axis as it sits
    at that moment: :math:`\dot\alpha` about :math:`z`, :math:`\dot\beta` about
    :math:`R_z(\alpha)\,y`, :math:`\dot\gamma` about :math:`R_z(\alpha) R_y(\beta)\,x`:

    .. math::

        E(\phi) = \begin{pmatrix}
        c_\alpha c_\beta & -s_\alpha & 0 \\
        s_\alpha c_\beta & c_\alpha & 0 \\
        -s_\beta & 0 & 1
        \end{pmatrix},
        \qquad \det E = \cos\beta .

    It is singular at :math:`\beta = \pm\pi/2`, the gimbal lock of these angles.

    Parameters
    ----------
    rpy : array_like, shape (..., 3)
        :math:`(\gamma, \beta, \alpha)` in radians.

    Returns
    -------
    ndarray, shape (..., 3, 3)

    Examples
    --------
    >>> import numpy as np
    >>> E = rpy_rate_matrix([0.0, 0.0, 0.0])
    >>> np.allclose(E, np.eye(3))
    True
    >>> bool(np.isclose(np.linalg.det(rpy_rate_matrix([0.3, 0.4, 0.5])), np.cos(0.4)))
    True
    """
    rpy = as_float_array(rpy, "rpy", (3,))
    beta, alpha = rpy[..., 1], rpy[..., 2]
    ca, sa, cb, sb = np.cos(alpha), np.sin(alpha), np.cos(beta), np.sin(beta)
    E = np.zeros(rpy.shape[:-1] + (3, 3))
    E[..., 0, 0], E[..., 1, 0], E[..., 2, 0] = ca * cb, sa * cb, -sb
    E[..., 0, 1], E[..., 1, 1] = -sa, ca
    E[..., 2, 2] = 1.0
    return E


def quaternion_rate_matrix(q):
    r"""The matrix :math:`G` with :math:`\dot q = G(q)\, \omega` for a unit quaternion.

    From :math:`\dot q = \tfrac12 (0, \omega)\, q` with :math:`q = (w, \mathbf v)`:

    .. math::

        G(q) = \frac12 \begin{pmatrix} -\mathbf v^\top \\
        w I - [\mathbf v]_\times \end{pmatrix}
        = \frac12 \begin{pmatrix}
        -x & -y & -z \\ w & z & -y \\ -z & w & x \\ y & -x & w
        \end{pmatrix},
        \qquad G^\top G = \tfrac14 I ,

    so the world-frame angular velocity is read back as :math:`\omega = 4\, G(q)^\top \dot q`.

    Parameters
    ----------
    q : array_like, shape (..., 4)
        Unit quaternions ``(w, x, y, z)`` (not checked: the formula holds for any ``q``,
        the inverse :math:`4G^\top` only for unit ones).

    Returns
    -------
    ndarray, shape (..., 4, 3)

    Examples
    --------
    >>> import numpy as np
    >>> G = quaternion_rate_matrix([1, 0, 0, 0])
    >>> G @ [0, 0, 2.0]
    array([0., 0., 0., 1.])
    >>> q = np.array([0.5, 0.5, -0.5, 0.5])
    >>> np.allclose(quaternion_rate_matrix(q).T @ quaternion_rate_matrix(q), np.eye(3) / 4)
    True
    """
    q = as_float_array(q, "q", (4,))
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    rows = [[-x, -y, -z], [w, z, -y], [-z, w, x], [y, -x, w]]
    return 0.5 * np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def analytic_jacobian(robot, q, *, orientation="rpy", tol=1e-9):
    r"""Analytic Jacobian: rates of the tool's position and orientation coordinates.

    The geometric Jacobian gives :math:`(\dot p, \omega) = J(q)\,\dot q`. With orientation
    coordinates :math:`\phi` whose rates map to :math:`\omega` by a matrix,
    :math:`\omega = E(\phi)\,\dot\phi` for roll-pitch-yaw (:func:`rpy_rate_matrix`) and
    :math:`\dot r = G(r)\,\omega` for the unit quaternion :math:`r` of the tool
    (:func:`quaternion_rate_matrix`), the analytic Jacobian is

    .. math::

        J_{\mathrm{rpy}} = \begin{pmatrix} I & 0 \\ 0 & E(\phi)^{-1} \end{pmatrix} J ,
        \qquad
        J_{\mathrm{quat}} = \begin{pmatrix} I & 0 \\ 0 & G(r) \end{pmatrix} J .

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (..., n)
        Joint vectors.
    orientation : {"rpy", "quaternion"}
        The orientation coordinates: roll, pitch, yaw (Craig,
        :func:`dqlab.rotations.rpy_from_matrix`), or the quaternion of
        :func:`dqlab.quaternion.quaternion_from_matrix`.
    tol : float
        For ``"rpy"``: the smallest accepted :math:`|\cos\beta|`; closer to the gimbal lock
        the rates of the angles are unbounded and a ``ValueError`` is raised.

    Returns
    -------
    ndarray, shape (..., 6, n) or (..., 7, n)
        Rows :math:`(\dot x, \dot y, \dot z, \dot\gamma, \dot\beta, \dot\alpha)` or
        :math:`(\dot x, \dot y, \dot z, \dot r_w, \dot r_x, \dot r_y, \dot r_z)`.

    Raises
    ------
    ValueError
        An unknown ``orientation``, or a configuration in the gimbal lock of the angles.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot, q = ur3(), np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    >>> J_rpy = analytic_jacobian(robot, q)
    >>> J_rpy.shape
    (6, 6)
    >>> np.allclose(J_rpy[:3], robot.jacobian(q)[:3])
    True
    """
    from .quaternion import quaternion_from_matrix
    from .rotations import rpy_from_matrix

    J = robot.jacobian(q)
    R = robot.fk(q)[..., :3, :3]
    if orientation == "rpy":
        rpy = rpy_from_matrix(R)
        cos_beta = np.cos(rpy[..., 1])
        if np.any(np.abs(cos_beta) < tol):
            raise ValueError(f"q puts the tool in the gimbal lock of roll-pitch-yaw "
                             f"(|cos pitch| < tol = {tol:g}): the angle rates are unbounded")
        angular = np.linalg.solve(rpy_rate_matrix(rpy), J[..., 3:, :])
    elif orientation == "quaternion":
        angular = quaternion_rate_matrix(quaternion_from_matrix(R)) @ J[..., 3:, :]
    else:
        raise ValueError(f"orientation must be 'rpy' or 'quaternion', got {orientation!r}")
    return np.concatenate([J[..., :3, :], angular], axis=-2)
