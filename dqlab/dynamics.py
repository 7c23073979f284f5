r"""Rigid-body dynamics of a serial arm: Newton--Euler on twists and wrenches as dual vectors.

The arm's equations of motion are

.. math::

   M(q)\,\ddot q + c(q, \dot q) + g(q) = \tau ,

with the mass matrix :math:`M`, the Coriolis and centrifugal torques :math:`c` and the
gravity torques :math:`g` (chapter "Dynamics"). This module computes them from the robot's
kinematics (:meth:`~dqlab.robot.Robot.link_transforms`) and the inertial parameters its
links carry (:class:`~dqlab.inertia.LinkInertia`), by the recursive Newton--Euler algorithm
written with dual vectors.

Dual vectors
------------
A *twist* is the dual vector :math:`\hat\xi = \omega + \varepsilon\,\mathbf v` (angular
velocity, and velocity of the body point at the frame's origin: the twist of chapter
"Differential kinematics"); a *wrench* is :math:`\hat w = \mathbf f + \varepsilon\,\mathbf n`
(force, and moment about the frame's origin). Both are moved from frame B to frame A, where
:math:`\hat Q_{AB}` is the pose of B, by the dual-quaternion sandwich of lines (chapter "Dual
quaternions"), the *adjoint*:

.. math::

   \hat\xi_A = \hat Q_{AB}\,\hat\xi_B\,\hat Q_{AB}^{*},\qquad
   \hat w_A = \hat Q_{AB}\,\hat w_B\,\hat Q_{AB}^{*}

(:func:`dqlab.dualquat.dual_quaternion_apply_line`). The cross product of dual vectors,

.. math::

   \hat a \times \hat b = \mathbf a \times \mathbf b
   + \varepsilon\,(\mathbf a \times \mathbf b^\circ + \mathbf a^\circ \times \mathbf b),

is the rate of change of a twist or of a momentum carried by a moving frame, and the power of
a wrench on a twist is the dual part of their dual dot product,
:math:`\langle\hat\xi, \hat w\rangle = \omega\cdot\mathbf n + \mathbf v\cdot\mathbf f`.

Recursive Newton--Euler
-----------------------
In the link frames :math:`i` of the robot's convention, with
:math:`\hat Q_i = \hat Q_{i-1,i}(q_i)` and the unit twist :math:`\hat s_i` of joint :math:`i`
(its axis as a line, :math:`\mathbf l + \varepsilon\,\mathbf m`, for a revolute joint;
:math:`\varepsilon\,\mathbf l` for a prismatic one), seen from frame :math:`i`:

.. math::

   \hat\xi_i &= \hat Q_i^{*}\,\hat\xi_{i-1}\,\hat Q_i + \hat s_i\,\dot q_i, \\
   \dot{\hat\xi}_i &= \hat Q_i^{*}\,\dot{\hat\xi}_{i-1}\,\hat Q_i + \hat s_i\,\ddot q_i
     + \hat\xi_i \times \hat s_i\,\dot q_i, \\
   \hat w_i &= \mathcal M_i\,\dot{\hat\xi}_i + \hat\xi_i \times \mathcal M_i\,\hat\xi_i
     + \hat Q_{i+1}\,\hat w_{i+1}\,\hat Q_{i+1}^{*}, \\
   \tau_i &= \langle \hat s_i, \hat w_i \rangle,

from the base at rest, :math:`\hat\xi_0 = 0`, accelerating upwards at :math:`-\mathbf g`,
:math:`\dot{\hat\xi}_0 = -\varepsilon\,\mathbf g_0` (gravity is felt as that acceleration),
and :math:`\hat w_{n+1} = 0`. :math:`\mathcal M_i` is link :math:`i`'s inertia as a map from
twists to momenta (:meth:`~dqlab.inertia.LinkInertia.momentum`).

Every function takes joint vectors of shape ``(..., n)`` and broadcasts over the leading axes
like :meth:`~dqlab.robot.Robot.fk`. Gravity is a vector in the world frame (the robot's base
transform turns it into frame 0), :math:`(0, 0, -9.81)` m/s^2 by default. The tool frame
carries no mass; a payload is part of the last link's inertia
(:func:`with_payload`). Units: radians, metres, seconds, kilograms, newtons.
"""

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import as_float_array, components, finite_or_raise, stack_components
from ._dynamics_floats import constants as float_constants
from ._dynamics_floats import inverse_dynamics as inverse_dynamics_on_floats
from ._kernels import dual_quaternion_mul, momentum
from .dualquat import (
    dual_quaternion_apply,
    dual_quaternion_conjugate,
    dual_quaternion_from_transform,
    dual_quaternion_product,
)
from .inertia import LinkInertia
from .robot import Robot

__all__ = [
    "inverse_dynamics", "mass_matrix", "gravity_torques", "coriolis_torques",
    "forward_dynamics", "kinetic_energy", "potential_energy", "link_inertias",
    "joint_twists", "dual_cross", "with_payload", "with_inertias", "NewtonEuler", "GRAVITY",
]

#: Gravity in the world frame by default, m/s^2: 9.81 along -z.
GRAVITY = (0.0, 0.0, -9.81)


# --------------------------------------------------------------------------------------
# The pieces: inertias, joint twists, the cross product of dual vectors

def link_inertias(robot: Robot) -> tuple[LinkInertia, ...]:
    """The inertias of the robot's links, or a ValueError naming the first link without one.

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> [I.mass for I in link_inertias(ur3())]
    [2.0, 3.42, 1.26, 0.8, 0.8, 0.35]
    """
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a dqlab Robot, got {type(robot).__name__}")
    inertias = tuple(link.inertia for link in robot.links)
    for i, inertia in enumerate(inertias, start=1):
        if inertia is None:
            raise ValueError(
                f"link {i} of {robot.name or 'the robot'} has no inertial parameters: give "
                "its links Link(..., inertia=LinkInertia(...)) (see dqlab.models for the "
                "book's robots, dqlab.models.rod_link_inertias for a plausible guess)")
    return inertias


def joint_twists(robot: Robot) -> NDArray[np.float64]:
    r"""The unit twist :math:`\hat s_i` of every joint, seen from its link's frame :math:`i`.

    A revolute joint turns link :math:`i` about its axis at unit speed: the twist is the axis
    as a line, :math:`\hat s_i = \mathbf l + \varepsilon\,\mathbf m` (unit direction, and
    moment :math:`\mathbf m = \mathbf c \times \mathbf l` for a point :math:`\mathbf c` on
    the axis, chapter "Dual quaternions"). A prismatic joint slides it along its axis:
    :math:`\hat s_i = \varepsilon\,\mathbf l`. In modified DH the axis is frame :math:`i`'s
    :math:`z` axis, :math:`\mathbf l = (0, 0, 1)`, :math:`\mathbf m = 0`. In standard DH it
    is the :math:`z` axis of frame :math:`i-1`, which the constant part
    :math:`T_x(a_i) R_x(\alpha_i)` of the link moves to
    :math:`\mathbf l = (0, \sin\alpha_i, \cos\alpha_i)` through
    :math:`\mathbf c = (-a_i, 0, 0)`.

    Returns
    -------
    ndarray, shape (n, 2, 3)
        ``[i, 0]`` the real part (:math:`\omega`) and ``[i, 1]`` the dual part
        (:math:`\mathbf v`) of joint ``i + 1``'s twist.

    Examples
    --------
    >>> from dqlab.models import ur3, scara_rsm5
    >>> joint_twists(ur3())[1]            # the shoulder: l = z, through (0.24365, 0, 0)
    array([[ 0.     ,  0.     ,  1.     ],
           [ 0.     , -0.24365,  0.     ]])
    >>> joint_twists(scara_rsm5())[2]     # the SCARA's slide: eps z
    array([[0., 0., 0.],
           [0., 0., 1.]])
    """
    twists = []
    for link in robot.links:
        if robot.convention == "dh":
            # l = (0, sin alpha, cos alpha) through c = (-a, 0, 0): m = c x l
            s, c = math.sin(link.alpha), math.cos(link.alpha)
            l, m = (0.0, s, c), (0.0, link.a * c, -link.a * s)
        else:
            l, m = (0.0, 0.0, 1.0), (0.0, 0.0, 0.0)
        twists.append((l, m) if link.is_revolute else ((0.0, 0.0, 0.0), l))
    return np.array(twists) + 0.0


def dual_cross(a: ArrayLike, a_dual: ArrayLike, b: ArrayLike, b_dual: ArrayLike
               ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Cross product of the dual vectors :math:`\hat a = \mathbf a + \varepsilon\mathbf a^\circ`
    and :math:`\hat b = \mathbf b + \varepsilon\mathbf b^\circ`.

    .. math::

       \hat a \times \hat b = \mathbf a \times \mathbf b
       + \varepsilon\,(\mathbf a \times \mathbf b^\circ + \mathbf a^\circ \times \mathbf b)

    It is half the commutator of the two as pure dual quaternions,
    :math:`\tfrac12(\hat a\hat b - \hat b\hat a)`. With a twist :math:`\hat\xi` on the left
    it is the rate of change of a twist or of a momentum :math:`\hat b` carried by a frame
    moving with :math:`\hat\xi`.

    Parameters
    ----------
    a, a_dual, b, b_dual : array_like, shape (..., 3)

    Returns
    -------
    real, dual : ndarray, shape (..., 3)

    Examples
    --------
    >>> dual_cross([0, 0, 1], [0, 0, 0], [1, 0, 0], [0, 0, 0])
    (array([0, 1, 0]), array([0, 0, 0]))
    """
    return np.cross(a, b), np.cross(a, b_dual) + np.cross(a_dual, b)


def _adjoint(Q, real, dual):
    r""":math:`\hat Q\,(\mathbf a + \varepsilon\mathbf a^\circ)\,\hat Q^*` on dual vectors,
    by two dual-quaternion products on the components: what
    :func:`~dqlab.dualquat.dual_quaternion_apply_line` computes, without its argument checks
    (the recursion's intermediate values are not the caller's input, and an input so large
    that they overflow must reach the check of the result, which names it)."""
    Qc = components(Q)
    x = (0.0, *components(real), 0.0, *components(dual))
    conjugate = (Qc[0], -Qc[1], -Qc[2], -Qc[3], Qc[4], -Qc[5], -Qc[6], -Qc[7])
    y = dual_quaternion_mul(dual_quaternion_mul(Qc, x), conjugate)
    return stack_components(y[1:4]), stack_components(y[5:8])


# --------------------------------------------------------------------------------------
# Argument checks

def _check(robot, q, more=(), gravity=GRAVITY):
    """Checked (q, *more, gravity in frame 0, inertias); ``more`` are (value, name) pairs of
    joint-sized arrays broadcast with q."""
    inertias = link_inertias(robot)
    q = robot.check_joints(q, name="q")
    arrays = [q]
    for value, name in more:
        a = as_float_array(value, name)
        if a.ndim == 0 or a.shape[-1] != robot.n:
            raise ValueError(f"{name} must have shape (..., {robot.n}) for this "
                             f"{robot.n}-joint robot, got shape {a.shape}")
        arrays.append(a)
    if any(a.shape != q.shape for a in arrays):
        try:
            shape = np.broadcast_shapes(*(a.shape for a in arrays))
        except ValueError:
            names = ", ".join(["q"] + [name for _, name in more])
            raise ValueError(f"the shapes of {names} do not broadcast: "
                             f"{[a.shape for a in arrays]}") from None
        arrays = [np.broadcast_to(a, shape) for a in arrays]
    g = as_float_array(gravity, "gravity", (3,))
    if g.shape != (3,):
        raise ValueError(f"gravity must be one vector of shape (3,), got shape {g.shape}")
    g_0 = robot.base[:3, :3].T @ g            # gravity in frame 0
    return arrays, g_0, inertias


# --------------------------------------------------------------------------------------
# Newton--Euler

def _newton_euler(robot, inertias, q, qd, qdd, g_0, *, energy=False):
    """The recursion of the module docstring on checked arrays of shape (..., n); returns
    the torques (..., n), or with ``energy`` the kinetic energy (...). Inputs so large that
    the result overflows give infinities here, which the callers turn into a ValueError."""
    with np.errstate(over="ignore", invalid="ignore"):
        return _recursion(robot, inertias, q, qd, qdd, g_0, energy)


def _recursion(robot, inertias, q, qd, qdd, g_0, energy):
    Q = dual_quaternion_from_transform(robot.link_transforms(q))      # Q_{i-1,i}, (..., n, 8)
    Q_star = dual_quaternion_conjugate(Q)
    s = joint_twists(robot)
    lead = q.shape[:-1]
    omega, v = np.zeros(lead + (3,)), np.zeros(lead + (3,))            # the base at rest,
    omega_dot, v_dot = np.zeros(lead + (3,)), np.broadcast_to(-g_0, lead + (3,))  # rising at -g
    wrenches, kinetic = [], 0.0
    for i, inertia in enumerate(inertias):
        qd_i, qdd_i = qd[..., i, None], qdd[..., i, None]
        s_real, s_dual = s[i]
        # the twist and its rate, carried from frame i-1 into frame i, plus the joint's own
        omega, v = _adjoint(Q_star[..., i, :], omega, v)
        omega, v = omega + s_real * qd_i, v + s_dual * qd_i
        omega_dot, v_dot = _adjoint(Q_star[..., i, :], omega_dot, v_dot)
        turn, slide = dual_cross(omega, v, s_real * qd_i, s_dual * qd_i)
        omega_dot = omega_dot + s_real * qdd_i + turn
        v_dot = v_dot + s_dual * qdd_i + slide
        # Newton-Euler for link i: the rate of its momentum h = M xi
        p, L = momentum(inertia.mass, inertia.com, inertia.tensor, omega, v)
        p_dot, L_dot = momentum(inertia.mass, inertia.com, inertia.tensor, omega_dot, v_dot)
        carried_f, carried_n = dual_cross(omega, v, p, L)
        wrenches.append((p_dot + carried_f, L_dot + carried_n))
        if energy:
            kinetic = kinetic + 0.5 * (np.sum(omega * L, axis=-1) + np.sum(v * p, axis=-1))
    if energy:
        return kinetic
    tau = np.empty(lead + (robot.n,))
    f, n = np.zeros(lead + (3,)), np.zeros(lead + (3,))
    for i in range(robot.n - 1, -1, -1):
        if i < robot.n - 1:                   # the wrench link i+1 takes from link i
            f, n = _adjoint(Q[..., i + 1, :], f, n)
        f, n = f + wrenches[i][0], n + wrenches[i][1]
        s_real, s_dual = s[i]
        tau[..., i] = n @ s_real + f @ s_dual     # <s_i, w_i>: omega . n + v . f
    return tau


def _torques(robot, inertias, q, qd, qdd, g_0):
    """:func:`_newton_euler`'s torques; one state (q of shape (n,)) runs the same recursion
    on Python floats (:mod:`dqlab._dynamics_floats`, tested equal), much faster."""
    if q.ndim != 1:
        return _newton_euler(robot, inertias, q, qd, qdd, g_0)
    consts = float_constants(robot, inertias, joint_twists(robot), g_0)
    return np.array(inverse_dynamics_on_floats(consts, q.tolist(), qd.tolist(),
                                                      qdd.tolist()))


def inverse_dynamics(robot: Robot, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, *,
                     gravity: ArrayLike = GRAVITY) -> NDArray[np.float64]:
    r"""Joint torques that give the accelerations ``qdd`` at the state ``(q, qd)``.

    .. math::

       \tau = M(q)\,\ddot q + c(q, \dot q) + g(q)

    by the recursive Newton--Euler algorithm on dual vectors of the module docstring.

    Parameters
    ----------
    robot : Robot
        Every link must carry a :class:`~dqlab.inertia.LinkInertia`.
    q, qd, qdd : array_like, shape (..., n)
        Joint positions (rad, or m for a prismatic joint), velocities and accelerations;
        leading axes broadcast.
    gravity : array_like, shape (3,), optional
        The acceleration of gravity in the world frame, m/s^2 (default 9.81 along -z).

    Returns
    -------
    ndarray, shape (..., n)
        N m for revolute joints, N for prismatic ones.

    Raises
    ------
    ValueError
        A link without inertia; a wrong shape, NaN or infinity in ``q``, ``qd``, ``qdd`` or
        ``gravity`` (the message names it); a prismatic joint beyond its travel; a result
        that overflows.
    TypeError
        ``robot`` not a Robot, or complex numbers or text in an argument.

    Examples
    --------
    The torques that hold the UR3 still, stretched out horizontally along -x (q = 0): the
    shoulder carries the whole arm beyond it, the elbow the forearm and the wrist. Their
    axes point along -y, so holding the arm up is a negative torque.

    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> inverse_dynamics(ur3(), np.zeros(6), np.zeros(6), np.zeros(6)).round(3) + 0.0
    array([  0.   , -17.583,  -6.097,   0.   ,   0.   ,   0.   ])
    """
    (q, qd, qdd), g_0, inertias = _check(robot, q, [(qd, "qd"), (qdd, "qdd")], gravity)
    tau = _torques(robot, inertias, q, qd, qdd, g_0)
    return finite_or_raise(tau, (q, "q", (robot.n,)), (qd, "qd", (robot.n,)),
                           (qdd, "qdd", (robot.n,)))


class NewtonEuler:
    r""":func:`inverse_dynamics` of one robot, prepared once for many calls on single states.

    A controller evaluates the inverse dynamics once per time step, always of the same robot;
    this object checks the robot and reads its constants (link parameters, joint twists,
    inertias, gravity in frame 0) once, and then each call only checks the state. It is a
    snapshot: later changes to the robot's base are not seen.

    Parameters
    ----------
    robot : Robot
    gravity : array_like, shape (3,), optional
        World frame, m/s^2.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> rnea = NewtonEuler(ur3())
    >>> q, qd, qdd = np.zeros(6), np.ones(6), np.zeros(6)
    >>> bool(np.allclose(rnea(q, qd, qdd), inverse_dynamics(ur3(), q, qd, qdd), atol=1e-12))
    True
    """

    def __init__(self, robot: Robot, *, gravity: ArrayLike = GRAVITY):
        (_,), g_0, inertias = _check(robot, np.zeros(robot.n) if isinstance(robot, Robot)
                                     else None, (), gravity)
        self.robot = robot
        self._slides = "prismatic" in robot.joint_types
        self.gravity = tuple(float(x) for x in robot.base[:3, :3] @ g_0)
        self._constants = float_constants(robot, inertias, joint_twists(robot),
                                                     g_0)

    def __call__(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> NDArray[np.float64]:
        """Joint torques, shape (n,) for one state (a batch goes to
        :func:`inverse_dynamics`)."""
        shape = (self.robot.n,)
        if not all(type(x) is np.ndarray and x.dtype == np.float64 and x.shape == shape
                   for x in (q, qd, qdd)):    # anything but one float state: the checked path
            return inverse_dynamics(self.robot, q, qd, qdd, gravity=self.gravity)
        state = [q.tolist(), qd.tolist(), qdd.tolist()]
        total = sum(state[0]) + sum(state[1]) + sum(state[2])
        if not total - total == 0.0:           # NaN or infinity: the checked path names it
            return inverse_dynamics(self.robot, q, qd, qdd, gravity=self.gravity)
        if self._slides:
            self.robot.check_joints(q, name="q")        # a slide beyond its travel
        tau = inverse_dynamics_on_floats(self._constants, *state)
        check = sum(tau)
        if not check - check == 0.0:
            return inverse_dynamics(self.robot, q, qd, qdd, gravity=self.gravity)
        return np.array(tau)


def gravity_torques(robot: Robot, q: ArrayLike, *, gravity: ArrayLike = GRAVITY
                    ) -> NDArray[np.float64]:
    r""":math:`g(q)`, the torques that hold the arm still at ``q``: the inverse dynamics at
    :math:`\dot q = \ddot q = 0`. Shape (..., n).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> gravity_torques(ur3(), [0, -np.pi / 2, 0, -np.pi / 2, 0, 0]).round(12) + 0.0
    array([0., 0., 0., 0., 0., 0.])
    """
    (q,), g_0, inertias = _check(robot, q, (), gravity)
    zero = np.zeros_like(q)
    return finite_or_raise(_torques(robot, inertias, q, zero, zero, g_0),
                           (q, "q", (robot.n,)))


def coriolis_torques(robot: Robot, q: ArrayLike, qd: ArrayLike) -> NDArray[np.float64]:
    r""":math:`c(q, \dot q)`, the Coriolis and centrifugal torques: the inverse dynamics
    without gravity at :math:`\ddot q = 0`, quadratic in :math:`\dot q`. Shape (..., n).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> q, qd = np.zeros(6), np.array([1.0, 0, 0, 0, 0, 0])
    >>> bool(np.allclose(coriolis_torques(ur3(), q, 2 * qd), 4 * coriolis_torques(ur3(), q, qd)))
    True
    """
    (q, qd), g_0, inertias = _check(robot, q, [(qd, "qd")], (0.0, 0.0, 0.0))
    return finite_or_raise(_torques(robot, inertias, q, qd, np.zeros_like(q), g_0),
                           (q, "q", (robot.n,)), (qd, "qd", (robot.n,)))


def mass_matrix(robot: Robot, q: ArrayLike) -> NDArray[np.float64]:
    r""":math:`M(q)`, the joint-space mass matrix: column :math:`j` is the inverse dynamics
    without gravity at rest with :math:`\ddot q = e_j`.

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (..., n)

    Returns
    -------
    ndarray, shape (..., n, n)
        Symmetric, positive definite; kg m^2 (kg for a prismatic joint's entries).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> M = mass_matrix(ur3(), np.zeros(6))
    >>> bool(np.allclose(M, M.T)), bool(np.all(np.linalg.eigvalsh(M) > 0))
    (True, True)
    """
    (q,), g_0, inertias = _check(robot, q, (), (0.0, 0.0, 0.0))
    return _mass_matrix(robot, inertias, q, g_0)


def _mass_matrix(robot, inertias, q, g_0):
    n = robot.n
    if q.ndim == 1:         # one state: n runs of the float path, its constants read once
        consts = float_constants(robot, inertias, joint_twists(robot), g_0)
        q_list, zero = q.tolist(), [0.0] * n
        return np.array([inverse_dynamics_on_floats(consts, q_list, zero, e_j)
                         for e_j in np.eye(n).tolist()]).T.copy()
    q_columns = np.broadcast_to(q[..., None, :], q.shape[:-1] + (n, n))
    unit = np.broadcast_to(np.eye(n), q_columns.shape)
    columns = _newton_euler(robot, inertias, q_columns, np.zeros_like(q_columns), unit, g_0)
    return np.swapaxes(columns, -1, -2).copy()


def forward_dynamics(robot: Robot, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, *,
                     gravity: ArrayLike = GRAVITY) -> NDArray[np.float64]:
    r"""Joint accelerations under the torques ``tau``:
    :math:`\ddot q = M(q)^{-1}\bigl(\tau - c(q, \dot q) - g(q)\bigr)`.

    Parameters
    ----------
    robot : Robot
    q, qd, tau : array_like, shape (..., n)
    gravity : array_like, shape (3,), optional

    Returns
    -------
    ndarray, shape (..., n)

    Examples
    --------
    Released at rest, the stretched UR3 falls like a double pendulum: the shoulder swings
    down (positively about its axis, which points along -y) and the forearm folds back
    relative to the upper arm.

    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> forward_dynamics(ur3(), np.zeros(6), np.zeros(6), np.zeros(6))[1:4].round(1)
    array([ 55. , -72.4,  17.4])
    """
    (q, qd, tau), g_0, inertias = _check(robot, q, [(qd, "qd"), (tau, "tau")], gravity)
    bias = _torques(robot, inertias, q, qd, np.zeros_like(q), g_0)
    M = _mass_matrix(robot, inertias, q, np.zeros(3))
    qdd = np.linalg.solve(M, (tau - bias)[..., None])[..., 0]
    return finite_or_raise(qdd, (q, "q", (robot.n,)), (qd, "qd", (robot.n,)),
                           (tau, "tau", (robot.n,)))


# --------------------------------------------------------------------------------------
# Energy

def kinetic_energy(robot: Robot, q: ArrayLike, qd: ArrayLike) -> NDArray[np.float64]:
    r"""Kinetic energy :math:`T = \tfrac12\sum_i \langle\hat\xi_i, \mathcal M_i\hat\xi_i\rangle
    = \tfrac12\,\dot q^\top M(q)\,\dot q`, shape (...), J.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> q, qd = np.zeros(6), np.array([0.3, -0.2, 0.5, 0.1, 0.4, -0.6])
    >>> T = kinetic_energy(ur3(), q, qd)
    >>> bool(np.isclose(T, 0.5 * qd @ mass_matrix(ur3(), q) @ qd))
    True
    """
    (q, qd), g_0, inertias = _check(robot, q, [(qd, "qd")], (0.0, 0.0, 0.0))
    T = _newton_euler(robot, inertias, q, qd, np.zeros_like(q), g_0, energy=True)
    return finite_or_raise(np.asarray(T, dtype=float), (q, "q", (robot.n,)),
                           (qd, "qd", (robot.n,)))


def potential_energy(robot: Robot, q: ArrayLike, *, gravity: ArrayLike = GRAVITY
                     ) -> NDArray[np.float64]:
    r"""Potential energy of gravity, :math:`V = -\sum_i m_i\, \mathbf g \cdot \mathbf c_i(q)`,
    with the centres of mass :math:`\mathbf c_i` in the world frame (zero at the world
    origin), shape (...), J.

    The centres of mass are placed by the product of chapter "Forward kinematics",
    :math:`\hat Q_{Wi} = \hat Q_{W0}\,\hat Q_{01} \cdots \hat Q_{i-1,i}`.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> bool(potential_energy(ur3(), [0, -np.pi / 2, 0, -np.pi / 2, 0, 0])
    ...      > potential_energy(ur3(), np.zeros(6)))        # upright is higher
    True
    """
    (q,), g_0, inertias = _check(robot, q, (), gravity)
    g_W = robot.base[:3, :3] @ g_0
    Q = dual_quaternion_from_transform(robot.link_transforms(q))
    Q_W = dual_quaternion_from_transform(robot.base)
    V = np.zeros(q.shape[:-1])
    for i, inertia in enumerate(inertias):
        Q_W = dual_quaternion_product(Q_W, Q[..., i, :])
        c_W = dual_quaternion_apply(Q_W, np.broadcast_to(inertia.com, Q_W.shape[:-1] + (3,)))
        V = V - inertia.mass * (c_W @ g_W)
    return finite_or_raise(V, (q, "q", (robot.n,)))


# --------------------------------------------------------------------------------------
# Robots with other inertias

def with_inertias(robot: Robot, inertias) -> Robot:
    """The same robot (links, base, tool, name) with other link inertias.

    Parameters
    ----------
    robot : Robot
    inertias : sequence of LinkInertia or None, length n

    Returns
    -------
    Robot

    Examples
    --------
    A model whose every link is 10 % heavier than the book's UR3:

    >>> from dqlab.models import ur3
    >>> heavier = with_inertias(ur3(), [I.scaled(1.1) for I in link_inertias(ur3())])
    >>> round(sum(I.mass for I in link_inertias(heavier)), 3)
    9.493
    """
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a dqlab Robot, got {type(robot).__name__}")
    inertias = list(inertias)
    if len(inertias) != robot.n:
        raise ValueError(f"inertias must hold {robot.n} entries, got {len(inertias)}")
    links = [link.with_inertia(inertia) for link, inertia in zip(robot.links, inertias,
                                                                   strict=True)]
    return Robot(links, convention=robot.convention, base=robot.base, tool=robot.tool,
                 name=robot.name)


def with_payload(robot: Robot, mass: float, cog: ArrayLike = (0.0, 0.0, 0.0), *,
                 radius: float = 0.0) -> Robot:
    r"""The robot carrying a payload of ``mass`` kg whose centre of gravity is ``cog``, in the
    flange frame, welded to the last link: a solid sphere of radius ``radius`` (a point mass
    for ``radius = 0``).

    As in URScript's ``set_payload(m, cog)``, the centre of gravity is given from the tool
    flange (frame :math:`n`, where the tool sits at :math:`X_{nT}`), not from the TCP: the
    payload does not depend on the tool, so ``with_payload`` and
    :meth:`~dqlab.robot.Robot.with_tool` compose in either order to the same robot. A
    payload centred at the TCP is ``cog=robot.tool[:3, 3]``. The sphere's inertia,
    :math:`\tfrac25 m r^2` about its centre, is added to the last link's (``+`` of two
    :class:`~dqlab.inertia.LinkInertia`).

    Parameters
    ----------
    robot : Robot
        Every link must carry a :class:`~dqlab.inertia.LinkInertia`.
    mass : float
        kg, >= 0.
    cog : array_like, shape (3,), optional
        The payload's centre of gravity in the flange frame, m (default: the flange's
        centre).
    radius : float, optional
        m, >= 0.

    Returns
    -------
    Robot

    Raises
    ------
    ValueError
        If ``mass`` or ``radius`` is not a number >= 0 (text and booleans included) or
        ``cog`` not three finite numbers; a link without inertia.

    Examples
    --------
    The UR3's rated 3 kg, held at the stretched pose: the shoulder takes another
    3 kg x 9.81 m/s^2 x 0.457 m, the elbow 3 kg x 9.81 m/s^2 x 0.213 m.

    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> q = np.zeros(6)
    >>> extra = gravity_torques(with_payload(ur3(), 3.0), q) - gravity_torques(ur3(), q)
    >>> extra.round(3) + 0.0
    array([  0.   , -13.447,  -6.276,   0.   ,   0.   ,   0.   ])

    The payload stays where it is put whatever the tool, and the tool whatever the payload:

    >>> a = with_payload(ur3(), 3.0, [0.0, 0.0, 0.1]).with_tool(z=0.2)
    >>> b = with_payload(ur3().with_tool(z=0.2), 3.0, [0.0, 0.0, 0.1])
    >>> a.links[-1].inertia == b.links[-1].inertia and np.array_equal(a.tool, b.tool)
    True
    """
    cog = as_float_array(cog, "cog", (3,))
    if cog.shape != (3,):
        raise ValueError(f"cog must be one point of shape (3,), got shape {cog.shape}")
    sphere = LinkInertia.sphere(mass, np.zeros(3), radius)        # (checks mass and radius)
    with np.errstate(over="ignore"):
        moment = sphere.mass * float(cog @ cog)
    if not math.isfinite(moment):
        raise ValueError("mass and cog: the payload's moment about the flange, m |cog|^2, "
                         "overflows")
    sphere = LinkInertia(sphere.mass, cog, sphere.tensor)
    inertias = list(link_inertias(robot))
    try:
        inertias[-1] = inertias[-1] + sphere
    except ValueError as exc:
        raise ValueError(f"mass and cog: the last link with the payload overflows ({exc})"
                         ) from None
    return with_inertias(robot, inertias)
