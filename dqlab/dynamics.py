r"""Rigid-body dynamics of a serial arm: twists and wrenches as dual vectors.

The arm's equations of motion are

.. math::

   M(q)\,\ddot q + c(q, \dot q) + g(q) = \tau ,

with the mass matrix :math:`M`, the Coriolis and centrifugal torques :math:`c` and the
gravity torques :math:`g` (chapter "Dynamics"). This module computes them from the robot's
kinematics (:meth:`~dqlab.robot.Robot.link_transforms`) and the inertial parameters its
links carry (:class:`~dqlab.inertia.LinkInertia`), by the field's algorithms written with
dual vectors: the recursive Newton--Euler algorithm (:func:`inverse_dynamics`), the
composite-rigid-body algorithm (:func:`mass_matrix`), the articulated-body algorithm
(:func:`forward_dynamics`) and the inverse dynamics as a linear function of the inertial
parameters (:func:`regressor`, :func:`inertial_parameters`).

Dual vectors
------------
A *twist* is the dual vector :math:`\xi = \omega + \varepsilon\,\mathbf v` (angular
velocity, and velocity of the body point at the frame's origin: the twist of chapter
"Differential kinematics"); a *wrench* is :math:`\mathcal F = \mathbf f + \varepsilon\,\mathbf n`
(force, and moment about the frame's origin). As 6-vectors they are ordered real part first,
:math:`(\omega, \mathbf v)` and :math:`(\mathbf f, \mathbf n)` (the *dual order*; the
Jacobian's rows are :math:`(\mathbf v, \omega)`, Featherstone's force vectors
:math:`(\mathbf n, \mathbf f)`). Both are moved from frame B to frame A, where
:math:`Q_{AB}` is the pose of B, by the dual-quaternion sandwich of lines (chapter "Dual
quaternions"), the *adjoint*:

.. math::

   \xi_A = Q_{AB}\,\xi_B\,Q_{AB}^{*},\qquad
   \mathcal F_A = Q_{AB}\,\mathcal F_B\,Q_{AB}^{*}

(:func:`dqlab.dualquat.dual_quaternion_apply_line`); in the dual order both are the matrix
:math:`\operatorname{Ad}_Q = \left(\begin{smallmatrix} R & 0 \\ [\mathbf t]_\times R & R
\end{smallmatrix}\right)`. The cross product of dual vectors,

.. math::

   a \times b = \mathbf a \times \mathbf b
   + \varepsilon\,(\mathbf a \times \mathbf b^\circ + \mathbf a^\circ \times \mathbf b),

is the rate of change of a twist or of a momentum carried by a moving frame (one operator
for both: Featherstone's :math:`\times` and :math:`\times^*` differ only by the order of a
force's components), and the power of a wrench on a twist is the dual part of their dual dot
product, :math:`\langle\xi, \mathcal F\rangle = \omega\cdot\mathbf n + \mathbf v\cdot\mathbf f`.

Recursive Newton--Euler
-----------------------
In the link frames :math:`i` of the robot's convention, with
:math:`Q_i = Q_{i-1,i}(q_i)` and the unit twist :math:`\mathcal S_i` of joint :math:`i`
(its axis as a line, :math:`\mathbf l + \varepsilon\,\mathbf m`, for a revolute joint;
:math:`\varepsilon\,\mathbf l` for a prismatic one), seen from frame :math:`i`:

.. math::

   \xi_i &= Q_i^{*}\,\xi_{i-1}\,Q_i + \mathcal S_i\,\dot q_i, \\
   \dot\xi_i &= Q_i^{*}\,\dot\xi_{i-1}\,Q_i + \mathcal S_i\,\ddot q_i
     + \xi_i \times \mathcal S_i\,\dot q_i, \\
   \mathcal F_i &= \mathcal M_i\,\dot\xi_i + \xi_i \times \mathcal M_i\,\xi_i
     + Q_{i+1}\,\mathcal F_{i+1}\,Q_{i+1}^{*}, \\
   \tau_i &= \langle \mathcal S_i, \mathcal F_i \rangle,

from the base at rest, :math:`\xi_0 = 0`, accelerating upwards at :math:`-\mathbf g`,
:math:`\dot\xi_0 = -\varepsilon\,\mathbf g_0` (gravity is felt as that acceleration),
and :math:`\mathcal F_{n+1} = 0`. :math:`\dot\xi_i` is the rate of the components of
:math:`\xi_i` in frame :math:`i`. :math:`\mathcal M_i` is link :math:`i`'s inertia as a map
from twists to momenta (:meth:`~dqlab.inertia.LinkInertia.momentum`).

Every function takes joint vectors of shape ``(..., n)`` and broadcasts over the leading axes
like :meth:`~dqlab.robot.Robot.fk`. Gravity is a vector in the world frame (the robot's base
transform turns it into frame 0), :math:`(0, 0, -9.81)` m/s^2 by default. The tool frame
carries no mass; a payload is part of the last link's inertia
(:func:`with_payload`). Units: radians, metres, seconds, kilograms, newtons.

With numba installed, the batch and single-state paths run compiled kernels
(``dqlab._fast.dynamics_compiled``, tested equal to the numpy code here, which stays the
reference and the path without numba); ``DQLAB_COMPILED=0`` in the environment switches them
off.
"""

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import (
    as_float_array,
    check_instance,
    components,
    finite_or_raise,
    short_repr,
    stack_components,
)
from ._fast.dynamics_compiled import constants as compiled_constants
from ._fast.dynamics_compiled import forward as compiled_forward
from ._fast.dynamics_compiled import inverse as compiled_inverse
from ._fast.dynamics_compiled import kernel_inverse as compiled_kernel_inverse
from ._fast.dynamics_compiled import mass as compiled_mass
from ._fast.dynamics_compiled import ready as compiled_ready
from ._fast.dynamics_compiled import regressor_rows as compiled_regressor
from ._fast.dynamics_floats import constants as float_constants
from ._fast.dynamics_floats import inverse_dynamics as inverse_dynamics_on_floats
from ._formulas import dual_cross as _dual_cross
from ._formulas import dual_quaternion_mul, momentum
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
    "link_jacobians", "regressor", "inertial_parameters", "inertias_from_parameters",
    "PARAMETER_NAMES", "SINGULAR_PIVOT",
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
    r"""The unit twist :math:`\mathcal S_i` of every joint, seen from its link's frame :math:`i`.

    A revolute joint turns link :math:`i` about its axis at unit speed: the twist is the axis
    as a line, :math:`\mathcal S_i = \mathbf l + \varepsilon\,\mathbf m` (unit direction, and
    moment :math:`\mathbf m = \mathbf c \times \mathbf l` for a point :math:`\mathbf c` on
    the axis, chapter "Dual quaternions"). A prismatic joint slides it along its axis:
    :math:`\mathcal S_i = \varepsilon\,\mathbf l`. In modified DH the axis is frame :math:`i`'s
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
    check_instance(robot, Robot, "robot")
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
    r"""Cross product of the dual vectors :math:`a = \mathbf a + \varepsilon\mathbf a^\circ`
    and :math:`b = \mathbf b + \varepsilon\mathbf b^\circ`.

    .. math::

       a \times b = \mathbf a \times \mathbf b
       + \varepsilon\,(\mathbf a \times \mathbf b^\circ + \mathbf a^\circ \times \mathbf b)

    It is half the commutator of the two as pure dual quaternions,
    :math:`\tfrac12(ab - ba)`. With a twist :math:`\xi` on the left
    it is the rate of change of a twist or of a momentum :math:`b` carried by a frame
    moving with :math:`\xi`.

    Parameters
    ----------
    a, a_dual, b, b_dual : array_like, shape (..., 3)

    Returns
    -------
    real, dual : ndarray, shape (..., 3)

    Raises
    ------
    ValueError
        Naming the argument: a shape other than (..., 3), shapes that do not broadcast, NaN
        or infinity, or a product too large for a float.

    Examples
    --------
    >>> dual_cross([0, 0, 1], [0, 0, 0], [1, 0, 0], [0, 0, 0])
    (array([0., 1., 0.]), array([0., 0., 0.]))
    """
    named = [(as_float_array(x, name, (3,)), name, (3,))
             for x, name in ((a, "a"), (a_dual, "a_dual"), (b, "b"), (b_dual, "b_dual"))]
    try:
        np.broadcast_shapes(*(x.shape for x, _, _ in named))
    except ValueError:
        shapes = ", ".join(f"{name} {x.shape}" for x, name, _ in named)
        raise ValueError(f"a, a_dual, b and b_dual must broadcast together, got {shapes}") \
            from None
    with np.errstate(over="ignore", invalid="ignore"):
        real, dual = _dual_cross(*(x for x, _, _ in named))
    finite_or_raise(real + dual, *named)
    return real, dual


def _adjoint(Q, real, dual):
    r""":math:`Q\,(\mathbf a + \varepsilon\mathbf a^\circ)\,Q^*` on dual vectors,
    by two dual-quaternion products on the components: what
    :func:`~dqlab.dualquat.dual_quaternion_apply_line` computes, without its argument checks
    (the recursion's intermediate values are not the caller's input, and an input so large
    that they overflow must reach the check of the result, which names it)."""
    Qc = components(Q)
    x = (0.0, *components(real), 0.0, *components(dual))
    conjugate = (Qc[0], -Qc[1], -Qc[2], -Qc[3], Qc[4], -Qc[5], -Qc[6], -Qc[7])
    y = dual_quaternion_mul(dual_quaternion_mul(Qc, x), conjugate)
    return stack_components(y[1:4]), stack_components(y[5:8])


def _compiled_or_none(robot, inertias):
    """The constants of ``robot`` for the compiled kernels of :mod:`dqlab._fast.dynamics_compiled`
    (``inertias`` None: without inertias, for the regressor), or None where they cannot be
    used (numba absent, or ``DQLAB_COMPILED=0``)."""
    if not compiled_ready():
        return None
    return compiled_constants(robot, inertias, joint_twists(robot))


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


def _outwards(robot, q, qd, qdd, g_0):
    """The outward pass: per link, its twist and the twist's rate in its own frame,
    ``(omega, v, omega_dot, v_dot)`` of shape (..., 3) each, from the base at rest rising at
    -g; and the link dual quaternions Q_{i-1,i} (..., n, 8)."""
    Q = dual_quaternion_from_transform(robot.link_transforms(q))      # Q_{i-1,i}, (..., n, 8)
    Q_star = dual_quaternion_conjugate(Q)
    s = joint_twists(robot)
    lead = q.shape[:-1]
    omega, v = np.zeros(lead + (3,)), np.zeros(lead + (3,))            # the base at rest,
    omega_dot, v_dot = np.zeros(lead + (3,)), np.broadcast_to(-g_0, lead + (3,))  # rising at -g
    twists = []
    for i in range(robot.n):
        qd_i, qdd_i = qd[..., i, None], qdd[..., i, None]
        s_real, s_dual = s[i]
        # the twist and its rate, carried from frame i-1 into frame i, plus the joint's own
        omega, v = _adjoint(Q_star[..., i, :], omega, v)
        omega, v = omega + s_real * qd_i, v + s_dual * qd_i
        omega_dot, v_dot = _adjoint(Q_star[..., i, :], omega_dot, v_dot)
        turn, slide = _dual_cross(omega, v, s_real * qd_i, s_dual * qd_i)
        omega_dot = omega_dot + s_real * qdd_i + turn
        v_dot = v_dot + s_dual * qdd_i + slide
        twists.append((omega, v, omega_dot, v_dot))
    return twists, Q


def _recursion(robot, inertias, q, qd, qdd, g_0, energy):
    twists, Q = _outwards(robot, q, qd, qdd, g_0)
    s = joint_twists(robot)
    lead = q.shape[:-1]
    wrenches, kinetic = [], 0.0
    for inertia, (omega, v, omega_dot, v_dot) in zip(inertias, twists, strict=True):
        # Newton-Euler for link i: the rate of its momentum h = M xi
        p, L = momentum(inertia.mass, inertia.com, inertia.tensor, omega, v)
        p_dot, L_dot = momentum(inertia.mass, inertia.com, inertia.tensor, omega_dot, v_dot)
        carried_f, carried_n = _dual_cross(omega, v, p, L)
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
    """:func:`_newton_euler`'s torques: compiled when it can be
    (:mod:`dqlab._fast.dynamics_compiled`); else one state (q of shape (n,)) runs the same
    recursion on Python floats (:mod:`dqlab._fast.dynamics_floats`), a batch on numpy arrays. All
    tested equal."""
    consts = _compiled_or_none(robot, inertias)
    if consts is not None:
        with np.errstate(over="ignore", invalid="ignore"):
            return compiled_inverse(consts, q, qd, qdd, g_0)
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
        self._g_0 = np.array(g_0, dtype=float)
        self._constants = float_constants(robot, inertias, joint_twists(robot), g_0)
        self._compiled = _compiled_or_none(robot, inertias)

    def __call__(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> NDArray[np.float64]:
        """Joint torques, shape (n,) for one state (a batch goes to
        :func:`inverse_dynamics`)."""
        shape = (self.robot.n,)
        if not (type(q) is np.ndarray and type(qd) is np.ndarray and type(qdd) is np.ndarray
                and q.shape == qd.shape == qdd.shape == shape and q.dtype == qd.dtype
                == qdd.dtype == np.float64):    # anything but one float state: checked path
            return inverse_dynamics(self.robot, q, qd, qdd, gravity=self.gravity)
        if self._slides:
            self.robot.check_joints(q, name="q")        # a slide beyond its travel
        if self._compiled is not None:                  # NaN or infinity in makes NaN out
            standard, links = self._compiled
            out = np.empty((1, shape[0]))
            with np.errstate(over="ignore", invalid="ignore"):
                compiled_kernel_inverse(standard, links, q[None], qd[None], qdd[None],
                                        self._g_0, out)
            tau = out[0]
            check = sum(tau.tolist())
            if check - check == 0.0:
                return tau
            return inverse_dynamics(self.robot, q, qd, qdd, gravity=self.gravity)
        state = [q.tolist(), qd.tolist(), qdd.tolist()]
        total = sum(state[0]) + sum(state[1]) + sum(state[2])
        if not total - total == 0.0:           # NaN or infinity: the checked path names it
            return inverse_dynamics(self.robot, q, qd, qdd, gravity=self.gravity)
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


# --------------------------------------------------------------------------------------
# Dual 6-vectors as matrices: the spatial inertia, the adjoint, the power

def _spatial_inertia(inertia):
    r""":math:`\mathcal M` as a 6x6 matrix in the dual orders, twist :math:`(\omega,
    \mathbf v)` to momentum :math:`(\mathbf p, \mathbf L)`: the matrix of
    :meth:`~dqlab.inertia.LinkInertia.momentum`,

    .. math::

       \mathcal M = \begin{pmatrix} -m[\mathbf c]_\times & m I \\ I_O & m[\mathbf c]_\times
       \end{pmatrix}

    (:math:`\mathbf p = m\mathbf v + \omega\times m\mathbf c`,
    :math:`\mathbf L = I_O\,\omega + m\mathbf c\times\mathbf v`)."""
    m, (x, y, z) = inertia.mass, inertia.com
    mc = m * np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.block([[-mc, m * np.eye(3)], [inertia.tensor_at_origin, mc]])


def _adjoint_matrix(X):
    r""":math:`\operatorname{Ad}_Q`, the 6x6 matrix of the sandwich :math:`x \mapsto Q\,x\,Q^*`
    on dual 6-vectors (real part first) for the pose :math:`X = (R, \mathbf t)` of :math:`Q`,
    shape (..., 6, 6): the same matrix for twists and wrenches,

    .. math::

       \operatorname{Ad}_Q = \begin{pmatrix} R & 0 \\ [\mathbf t]_\times R & R\end{pmatrix}

    (:math:`\omega' = R\,\omega`, :math:`\mathbf v' = R\,\mathbf v + \mathbf t\times
    R\,\omega`: what :func:`~dqlab.dualquat.dual_quaternion_apply_line` computes)."""
    R, t = X[..., :3, :3], X[..., :3, 3]
    tx = np.zeros(X.shape[:-2] + (3, 3))
    tx[..., 0, 1], tx[..., 0, 2], tx[..., 1, 2] = -t[..., 2], t[..., 1], -t[..., 0]
    tx[..., 1, 0], tx[..., 2, 0], tx[..., 2, 1] = t[..., 2], -t[..., 1], t[..., 0]
    Ad = np.zeros(X.shape[:-2] + (6, 6))
    Ad[..., :3, :3] = Ad[..., 3:, 3:] = R
    Ad[..., 3:, :3] = tx @ R
    return Ad


def _apply(A, x):
    """A x for stacks of 6x6 matrices and 6-vectors."""
    return (A @ x[..., None])[..., 0]


def _power(twist, wrench):
    r""":math:`\langle\xi, \mathcal F\rangle = \omega\cdot\mathbf n + \mathbf v\cdot\mathbf f` of
    6-vectors in the dual orders (the pairing that swaps the halves)."""
    return (np.sum(twist[..., :3] * wrench[..., 3:], axis=-1)
            + np.sum(twist[..., 3:] * wrench[..., :3], axis=-1))


def _cross(x, y):
    r""":math:`x\times y` of :func:`dual_cross` on 6-vectors in the dual order (..., 6)."""
    a, a_dual, b, b_dual = x[..., :3], x[..., 3:], y[..., :3], y[..., 3:]
    real, dual = _cross3(a, b), _cross3(a, b_dual) + _cross3(a_dual, b)
    return np.concatenate([real, dual], axis=-1)


def _cross3(a, b):
    """The cross product of 3-vectors on the last axis, written out (numpy's is slow on small
    arrays)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0], out[..., 1], out[..., 2] = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
    return out


def _transforms(robot, q):
    """The adjoint matrices of the links' poses :math:`X_{i-1,i}` and of their inverses
    (..., n, 6, 6), and the joint twists as 6-vectors (n, 6)."""
    X = robot.link_transforms(q)
    X_inverse = np.zeros_like(X)
    R_T = np.swapaxes(X[..., :3, :3], -1, -2)
    X_inverse[..., :3, :3] = R_T
    X_inverse[..., :3, 3] = -(R_T @ X[..., :3, 3, None])[..., 0]
    return (_adjoint_matrix(X), _adjoint_matrix(X_inverse),
            joint_twists(robot).reshape(robot.n, 6))


# --------------------------------------------------------------------------------------
# The mass matrix: composite rigid bodies

def mass_matrix(robot: Robot, q: ArrayLike) -> NDArray[np.float64]:
    r""":math:`M(q)`, the joint-space mass matrix, by the composite-rigid-body algorithm.

    Freeze joints :math:`i+1, \dots, n`: links :math:`i` to :math:`n` move as one rigid body,
    the *composite* body :math:`i`, whose spatial inertia, in frame :math:`i`, gathers the
    links' inertias moved there by the adjoint on both sides,

    .. math::

       \mathcal M^c_i = \mathcal M_i + \operatorname{Ad}_{Q_{i+1}}\,\mathcal M^c_{i+1}\,
       \operatorname{Ad}_{Q_{i+1}}^{-1}, \qquad \mathcal M^c_n = \mathcal M_n .

    Joint :math:`i` turning at unit rate gives it the momentum
    :math:`h_i = \mathcal M^c_i\,\mathcal S_i`, and the power of that momentum on the unit
    twist of any joint :math:`j \le i`, both in frame :math:`j`, is the entry

    .. math::

       M_{ji} = M_{ij} = \bigl\langle \mathcal S_j,\
       \operatorname{Ad}_{Q_{j+1}} \cdots \operatorname{Ad}_{Q_i}\, h_i \bigr\rangle

    (Featherstone 2008, section 6.2, in dual-vector form: :math:`\operatorname{Ad}_Q` is the
    sandwich :math:`Q\,x\,Q^*`, the same matrix for twists and momenta).

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (..., n)

    Returns
    -------
    ndarray, shape (..., n, n)
        Symmetric, positive semidefinite (definite unless a joint moves no mass); kg m^2
        (kg for a prismatic joint's entries).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> M = mass_matrix(ur3(), np.zeros(6))
    >>> bool(np.allclose(M, M.T)), bool(np.all(np.linalg.eigvalsh(M) > 0))
    (True, True)
    >>> unit = np.eye(6)          # column j: the torques of a unit acceleration of joint j
    >>> columns = inverse_dynamics(ur3(), np.zeros(6), np.zeros(6), unit, gravity=(0, 0, 0))
    >>> bool(np.allclose(M, columns.T))
    True
    """
    (q,), _, inertias = _check(robot, q, (), (0.0, 0.0, 0.0))
    return finite_or_raise(_mass_matrix(robot, inertias, q), (q, "q", (robot.n,)))


def _mass_matrix(robot, inertias, q):
    """:func:`mass_matrix` on checked arrays: compiled when it can be
    (:mod:`dqlab._fast.dynamics_compiled`), one state on Python floats, else the composite rigid
    bodies below."""
    consts = _compiled_or_none(robot, inertias)
    if consts is not None:
        with np.errstate(over="ignore", invalid="ignore"):
            return compiled_mass(consts, q)
    if q.ndim == 1:         # one state: n runs of the float path, its constants read once
        consts = float_constants(robot, inertias, joint_twists(robot), np.zeros(3))
        q_list, zero = q.tolist(), [0.0] * robot.n
        return np.array([inverse_dynamics_on_floats(consts, q_list, zero, e_j)
                         for e_j in np.eye(robot.n).tolist()]).T.copy()
    with np.errstate(over="ignore", invalid="ignore"):
        return _composite_rigid_body(robot, inertias, q)


def _composite_rigid_body(robot, inertias, q):
    """The algorithm of :func:`mass_matrix`'s docstring, on arrays of shape (..., n)."""
    n, lead = robot.n, q.shape[:-1]
    Ad, Ad_inverse, S = _transforms(robot, q)
    composite = [np.broadcast_to(_spatial_inertia(inertia), lead + (6, 6))
                 for inertia in inertias]
    M = np.empty(lead + (n, n))
    for i in range(n - 1, -1, -1):
        h = composite[i] @ S[i]              # momentum of links i..n, joint i at unit rate
        M[..., i, i] = _power(S[i], h)
        for j in range(i - 1, -1, -1):       # carried down the chain into frame j
            h = _apply(Ad[..., j + 1, :, :], h)
            M[..., i, j] = M[..., j, i] = _power(S[j], h)
        if i > 0:                             # the composite body i-1 takes body i in
            composite[i - 1] = (composite[i - 1]
                                + Ad[..., i, :, :] @ composite[i] @ Ad_inverse[..., i, :, :])
    return M


def link_jacobians(robot: Robot, q: ArrayLike) -> NDArray[np.float64]:
    r"""The Jacobian of every link's twist, in the link's own frame, dual order.

    Link :math:`i` moves with :math:`\xi_i = J_i(q)\,\dot q`; column :math:`j \le i` of
    :math:`J_i` is joint :math:`j`'s unit twist carried out to frame :math:`i`,
    :math:`\operatorname{Ad}_{Q_{j,i}}^{-1}\mathcal S_j`, and the columns :math:`j > i` are
    zero. The kinetic energy :math:`\tfrac12\sum_i\langle\xi_i, \mathcal M_i\xi_i\rangle`
    then gives the mass matrix as a sum over the links,

    .. math::

       M(q) = \sum_i J_i^\top\, \Pi\,\mathcal M_i\, J_i ,\qquad
       \Pi = \begin{pmatrix} 0 & I \\ I & 0 \end{pmatrix}

    (:math:`\Pi` the pairing of the power, :math:`\langle\xi, h\rangle = \xi^\top\Pi h`).

    Parameters
    ----------
    robot : Robot
    q : array_like, shape (..., n)

    Returns
    -------
    ndarray, shape (..., n, 6, n)
        Entry ``[..., i, :, j]``: rows :math:`(\omega, \mathbf v)`, the velocity of the body
        point at frame ``i + 1``'s origin, in that frame.

    Examples
    --------
    The last link's Jacobian, turned and moved to the flange, is the geometric Jacobian of
    :meth:`~dqlab.robot.Robot.jacobian` (rows :math:`(\mathbf v, \omega)`, base frame):

    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> J6 = link_jacobians(ur3(), q)[-1]
    >>> R = ur3().fk(q)[:3, :3]
    >>> bool(np.allclose(R @ J6[:3], ur3().jacobian(q)[3:]))      # the angular rows
    True
    """
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a dqlab Robot, got {type(robot).__name__}")
    q = robot.check_joints(q, name="q")
    n, lead = robot.n, q.shape[:-1]
    _, Ad_inverse, S = _transforms(robot, q)
    J = np.zeros(lead + (n, 6, n))
    for i in range(n):
        if i > 0:                             # carried out from frame i-1 into frame i
            J[..., i, :, :i] = Ad_inverse[..., i, :, :] @ J[..., i - 1, :, :i]
        J[..., i, :, i] = S[i]
    return finite_or_raise(J, (q, "q", (n,)))


# --------------------------------------------------------------------------------------
# Forward dynamics: articulated bodies

def forward_dynamics(robot: Robot, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, *,
                     gravity: ArrayLike = GRAVITY) -> NDArray[np.float64]:
    r"""Joint accelerations under the torques ``tau``,
    :math:`\ddot q = M(q)^{-1}\bigl(\tau - c(q, \dot q) - g(q)\bigr)`, by the
    articulated-body algorithm.

    Three passes over the chain, :math:`O(n)` operations, without forming :math:`M`
    (Featherstone 2008, section 7.3, in dual-vector form, with the power
    :math:`\langle\cdot,\cdot\rangle` and :math:`\operatorname{Ad}_Q` as in
    :func:`mass_matrix`):

    1. outwards, the twists :math:`\xi_i` of the recursive Newton--Euler algorithm, the
       velocity-product accelerations :math:`\mathbf c_i = \xi_i\times\mathcal S_i\dot q_i`
       and the bias wrenches :math:`\mathcal F^A_i = \xi_i\times\mathcal M_i\xi_i`;
    2. inwards, the *articulated* inertia of links :math:`i..n` with their joints free,
       :math:`\mathcal M^A_i`: with :math:`U_i = \mathcal M^A_i\mathcal S_i`,
       :math:`D_i = \langle\mathcal S_i, U_i\rangle` and
       :math:`u_i = \tau_i - \langle\mathcal S_i, \mathcal F^A_i\rangle`, link :math:`i-1`
       takes in
       :math:`\mathcal M^a_i = \mathcal M^A_i - U_i\,\langle U_i, \cdot\rangle / D_i` and
       :math:`\mathcal F^a_i = \mathcal F^A_i + \mathcal M^a_i\mathbf c_i + U_i u_i / D_i`,
       moved by :math:`\operatorname{Ad}_{Q_i}` (on both sides for the inertia);
    3. outwards from the base rising at :math:`-\mathbf g`, the accelerations
       :math:`\ddot q_i = \bigl(u_i - \langle\dot\xi'_i, U_i\rangle\bigr) / D_i` with
       :math:`\dot\xi'_i = \operatorname{Ad}^{-1}_{Q_i}\dot\xi_{i-1} + \mathbf c_i`, and
       :math:`\dot\xi_i = \dot\xi'_i + \mathcal S_i\ddot q_i`.

    :math:`D_i` is the inertia joint :math:`i` feels when the joints beyond it are free; the
    :math:`D_i` are the pivots of a factorisation of :math:`M`, which is singular exactly when
    one of them is zero: when a joint moves no mass.

    Parameters
    ----------
    robot : Robot
    q, qd, tau : array_like, shape (..., n)
    gravity : array_like, shape (3,), optional

    Returns
    -------
    ndarray, shape (..., n)

    Raises
    ------
    ValueError
        As :func:`inverse_dynamics`; and when :math:`M(q)` is singular, naming the joint that
        moves no mass (a massless last link, a point mass on its own joint's axis), or when
        the inertias are so large that it overflows.

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
    consts = _compiled_or_none(robot, inertias)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        if consts is not None:
            qdd, D = compiled_forward(consts, q, qd, tau, g_0)
        else:
            qdd, D = _articulated_body(robot, inertias, q, qd, tau, g_0)
    _check_pivots(robot, inertias, D, q, qd, tau)
    return finite_or_raise(qdd, (q, "q", (robot.n,)), (qd, "qd", (robot.n,)),
                           (tau, "tau", (robot.n,)))


def _articulated_body(robot, inertias, q, qd, tau, g_0):
    """The three passes of :func:`forward_dynamics`'s docstring on arrays of shape (..., n);
    returns the accelerations and the pivots D, both (..., n)."""
    n, lead = robot.n, q.shape[:-1]
    Ad, Ad_inverse, S = _transforms(robot, q)
    xi = np.zeros(lead + (6,))
    c, M_A, F_A = [], [], []
    for i, inertia in enumerate(inertias):             # 1. outwards: twists and biases
        joint = S[i] * qd[..., i, None]
        xi = _apply(Ad_inverse[..., i, :, :], xi) + joint
        M_i = np.broadcast_to(_spatial_inertia(inertia), lead + (6, 6))
        c.append(_cross(xi, joint))
        M_A.append(M_i)
        F_A.append(_cross(xi, _apply(M_i, xi)))
    U, D, u = [None] * n, np.empty(lead + (n,)), [None] * n
    for i in range(n - 1, -1, -1):                     # 2. inwards: articulated inertias
        U[i] = M_A[i] @ S[i]
        D[..., i] = _power(S[i], U[i])
        u[i] = tau[..., i] - _power(S[i], F_A[i])
        if i > 0:
            M_a = M_A[i] - U[i][..., :, None] * _swap(U[i])[..., None, :] / D[..., i, None, None]
            F_a = F_A[i] + _apply(M_a, c[i]) + U[i] * (u[i] / D[..., i])[..., None]
            M_A[i - 1] = M_A[i - 1] + Ad[..., i, :, :] @ M_a @ Ad_inverse[..., i, :, :]
            F_A[i - 1] = F_A[i - 1] + _apply(Ad[..., i, :, :], F_a)
    qdd = np.empty(lead + (n,))
    xi_dot = np.broadcast_to(np.concatenate([np.zeros(3), -g_0]), lead + (6,))  # rising at -g
    for i in range(n):                                 # 3. outwards: accelerations
        xi_dot = _apply(Ad_inverse[..., i, :, :], xi_dot) + c[i]
        qdd[..., i] = (u[i] - _power(xi_dot, U[i])) / D[..., i]
        xi_dot = xi_dot + S[i] * qdd[..., i, None]
    return qdd, D


def _swap(x):
    r""":math:`\Pi x`: the two halves of 6-vectors exchanged (so that
    :math:`\langle\xi, h\rangle = \xi\cdot\Pi h`)."""
    return np.concatenate([x[..., 3:], x[..., :3]], axis=-1)


#: A pivot of the articulated-body algorithm below this fraction of the largest one is taken
#: as zero: the mass matrix is then singular to working precision.
SINGULAR_PIVOT = 1e-12


def _check_pivots(robot, inertias, D, q, qd, tau):
    """A ValueError naming the joint that moves no mass, or the inertias that overflow.

    The inward pass meets the pivots from the flange down; after a zero pivot the inner ones
    are not numbers, so the joint named is the outermost one with a zero pivot."""
    finite = np.isfinite(D)
    scale = np.where(finite, D, 0.0).max(axis=-1, keepdims=True, initial=0.0)
    small = finite & (D <= SINGULAR_PIVOT * scale)
    if small.any():
        config = tuple(int(k) for k in np.argwhere(small.any(axis=-1))[0])
        joint = int(np.flatnonzero(small[config])[-1]) + 1
        where = f" at q[{', '.join(map(str, config))}]" if config else ""
        moved = (f"links {joint} to {robot.n}, with the joints beyond it free, have"
                 if joint < robot.n else f"link {joint} has")
        raise ValueError(
            f"the mass matrix M(q) is singular{where}: joint {joint} moves no mass ({moved} "
            f"no inertia for its motion; pivot D_{joint} = {D[config + (joint - 1,)]:.3g}). "
            f"Give link {joint} a mass away from its joint's axis or an inertia about it")
    if not finite.all():
        for x, name in ((q, "q"), (qd, "qd"), (tau, "tau")):
            as_float_array(x, name)
        largest = max(range(robot.n), key=lambda k: np.abs(inertias[k].tensor).max()
                      + inertias[k].mass)
        raise ValueError(
            f"the mass matrix M(q) overflows: the links' inertias are too large to be "
            f"represented (link {largest + 1} has mass {inertias[largest].mass:.3g} kg and "
            f"a tensor up to {np.abs(inertias[largest].tensor).max():.3g} kg m^2)")


# --------------------------------------------------------------------------------------
# Linear in the inertial parameters: the regressor

#: The ten inertial parameters of one link, in the order of :func:`inertial_parameters`:
#: mass, first moment m c, and the inertia tensor about the link frame's origin.
PARAMETER_NAMES = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")


def inertial_parameters(robot: Robot) -> NDArray[np.float64]:
    r"""The robot's inertial parameters :math:`\pi`, ten per link, shape (10 n,).

    Per link, in its own frame: :math:`m`, :math:`m\mathbf c` (three), and the inertia tensor
    about the frame's origin :math:`I_O = I_c + m(\lVert\mathbf c\rVert^2 I -
    \mathbf c\mathbf c^\top)` as :math:`I_{xx}, I_{xy}, I_{yy}, I_{xz}, I_{yz}, I_{zz}`
    (:data:`PARAMETER_NAMES`; pinocchio's order). The link's momentum is linear in them,
    :math:`\mathbf p = m\mathbf v + \omega\times m\mathbf c`,
    :math:`\mathbf L = I_O\,\omega + m\mathbf c\times\mathbf v`, and so are the joint torques:
    :math:`\tau = Y(q, \dot q, \ddot q)\,\pi` (:func:`regressor`).

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> pi = inertial_parameters(ur3())
    >>> pi.shape, pi[[0, 10]]                  # the masses of links 1 and 2
    ((60,), array([2.  , 3.42]))
    """
    parameters = []
    for inertia in link_inertias(robot):
        I_O = inertia.tensor_at_origin
        parameters += [inertia.mass, *(inertia.mass * inertia.com),
                       I_O[0, 0], I_O[0, 1], I_O[1, 1], I_O[0, 2], I_O[1, 2], I_O[2, 2]]
    return np.array(parameters)


def inertias_from_parameters(parameters: ArrayLike) -> tuple[LinkInertia, ...]:
    r"""The link inertias of inertial parameters :math:`\pi` (:func:`inertial_parameters`'s
    layout, ten per link), or a ValueError naming the first link whose ten numbers no rigid
    body has (a negative mass, a first moment without mass, a tensor about the centre of mass
    that is not positive semidefinite or breaks the triangle inequality).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> inertias = inertias_from_parameters(inertial_parameters(ur3()))
    >>> bool(np.allclose(inertias[1].com, link_inertias(ur3())[1].com))
    True
    """
    pi = as_float_array(parameters, "parameters")
    if pi.ndim != 1 or pi.size == 0 or pi.size % 10:
        raise ValueError(f"parameters must have shape (10 n,), ten per link, got shape "
                         f"{pi.shape}")
    inertias = []
    for k, (m, mx, my, mz, ixx, ixy, iyy, ixz, iyz, izz) in enumerate(pi.reshape(-1, 10), 1):
        scale = max(abs(m), 1e-300)
        if m < 0 or (m == 0 and (mx, my, mz) != (0.0, 0.0, 0.0)):
            raise ValueError(f"parameters of link {k}: a mass of {m:.6g} kg with a first "
                             f"moment ({mx:.3g}, {my:.3g}, {mz:.3g}) kg m is no rigid body")
        com = np.array([mx, my, mz]) / scale if m > 0 else np.zeros(3)
        I_O = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        I_c = I_O - m * (np.dot(com, com) * np.eye(3) - np.outer(com, com))
        try:
            inertias.append(LinkInertia(m, com, I_c))
        except ValueError as error:
            raise ValueError(f"parameters of link {k} are no rigid body's: {error}") from None
    return tuple(inertias)


def regressor(robot: Robot, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, *,
              gravity: ArrayLike = GRAVITY) -> NDArray[np.float64]:
    r"""The joint torques as a linear function of the inertial parameters,
    :math:`\tau = Y(q, \dot q, \ddot q)\,\pi`, with :math:`\pi` = :func:`inertial_parameters`.

    The net wrench of link :math:`j` in Newton--Euler form,
    :math:`\mathcal M_j\dot\xi_j + \xi_j\times\mathcal M_j\xi_j`, is linear in its ten
    parameters because the momentum is: column :math:`k` of link :math:`j` is that wrench for
    the momentum of the :math:`k`-th parameter alone (:math:`m`: :math:`h = \mathbf v`;
    :math:`m c_x`: :math:`h = \omega\times\mathbf e_x + \varepsilon\,\mathbf e_x\times\mathbf v`;
    :math:`I_{xy}`: :math:`h = \varepsilon E_{xy}\,\omega`, ...). Carried inwards as the
    recursion carries wrenches, its power on the unit twist of each joint :math:`i \le j` is

    .. math::

       Y_{i,\,10j+k} = \bigl\langle \mathcal S_i,\ \operatorname{Ad}_{Q_{i+1}}\cdots
       \operatorname{Ad}_{Q_j}\,\bigl(\mathcal M^{(k)}\dot\xi_j + \xi_j\times
       \mathcal M^{(k)}\xi_j\bigr)\bigr\rangle ,

    zero for :math:`i > j`, with the twists and their rates of :func:`inverse_dynamics`
    (gravity included, as the base rising at :math:`-\mathbf g`).

    Parameters
    ----------
    robot : Robot
        Its links' inertias are not used (only their presence is checked), but every link must
        carry one, as for :func:`inverse_dynamics`.
    q, qd, qdd : array_like, shape (..., n)
    gravity : array_like, shape (3,), optional

    Returns
    -------
    ndarray, shape (..., n, 10 n)

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> q, qd, qdd = np.zeros(6), np.ones(6), np.full(6, 0.5)
    >>> Y = regressor(ur3(), q, qd, qdd)
    >>> Y.shape
    (6, 60)
    >>> bool(np.allclose(Y @ inertial_parameters(ur3()), inverse_dynamics(ur3(), q, qd, qdd)))
    True
    """
    (q, qd, qdd), g_0, _ = _check(robot, q, [(qd, "qd"), (qdd, "qdd")], gravity)
    consts = _compiled_or_none(robot, None)
    with np.errstate(over="ignore", invalid="ignore"):
        if consts is not None:
            Y = compiled_regressor(consts, q, qd, qdd, g_0)
        else:
            Y = _regressor(robot, q, qd, qdd, g_0)
    return finite_or_raise(Y, (q, "q", (robot.n,)), (qd, "qd", (robot.n,)),
                           (qdd, "qdd", (robot.n,)))


def _momentum_per_parameter(omega, v):
    r"""The momentum of a twist for each of the ten parameters alone, (..., 10, 3) twice:
    :math:`\mathbf p = m\mathbf v + \omega\times m\mathbf c`,
    :math:`\mathbf L = I_O\omega + m\mathbf c\times\mathbf v`, term by term."""
    lead = np.broadcast_shapes(omega.shape, v.shape)[:-1]
    p, L = np.zeros(lead + (10, 3)), np.zeros(lead + (10, 3))
    p[..., 0, :] = v                                          # m
    for k, e in enumerate(np.eye(3), start=1):                # m c_x, m c_y, m c_z
        p[..., k, :] = np.cross(omega, e)
        L[..., k, :] = np.cross(e, v)
    wx, wy, wz = omega[..., 0], omega[..., 1], omega[..., 2]
    # I_O omega, one entry of I_O at a time: Ixx, Ixy, Iyy, Ixz, Iyz, Izz
    L[..., 4, 0] = wx
    L[..., 5, 0], L[..., 5, 1] = wy, wx
    L[..., 6, 1] = wy
    L[..., 7, 0], L[..., 7, 2] = wz, wx
    L[..., 8, 1], L[..., 8, 2] = wz, wy
    L[..., 9, 2] = wz
    return p, L


def _regressor(robot, q, qd, qdd, g_0):
    """The regressor of :func:`regressor`'s docstring on checked arrays (..., n)."""
    n, lead = robot.n, q.shape[:-1]
    twists, Q = _outwards(robot, q, qd, qdd, g_0)
    s = joint_twists(robot)
    columns = []                       # per link: the net wrenches of its ten parameters
    for omega, v, omega_dot, v_dot in twists:
        p, L = _momentum_per_parameter(omega, v)
        p_dot, L_dot = _momentum_per_parameter(omega_dot, v_dot)
        carried_f, carried_n = _dual_cross(omega[..., None, :], v[..., None, :], p, L)
        columns.append((p_dot + carried_f, L_dot + carried_n))          # (..., 10, 3) each
    Y = np.zeros(lead + (n, 10 * n))
    f, m = np.zeros(lead + (0, 10, 3)), np.zeros(lead + (0, 10, 3))    # links i+1..n
    for i in range(n - 1, -1, -1):     # inwards: carried into frame i, then link i's own
        if i < n - 1:
            f, m = _adjoint(Q[..., i + 1, None, None, :], f, m)
        f = np.concatenate([columns[i][0][..., None, :, :], f], axis=-3)
        m = np.concatenate([columns[i][1][..., None, :, :], m], axis=-3)
        s_real, s_dual = s[i]
        power = m @ s_real + f @ s_dual                       # (..., n - i, 10)
        Y[..., i, 10 * i:] = power.reshape(lead + (10 * (n - i),))
    return Y


# --------------------------------------------------------------------------------------
# Energy

def kinetic_energy(robot: Robot, q: ArrayLike, qd: ArrayLike) -> NDArray[np.float64]:
    r"""Kinetic energy :math:`T = \tfrac12\sum_i \langle\xi_i, \mathcal M_i\xi_i\rangle
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
    :math:`Q_{Wi} = Q_{W0}\,Q_{01} \cdots Q_{i-1,i}`.

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
    if isinstance(inertias, (str, bytes)) or not hasattr(inertias, "__iter__"):
        raise TypeError(f"inertias must be a sequence of {robot.n} LinkInertia (or None), "
                        f"got {short_repr(inertias)}")
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
