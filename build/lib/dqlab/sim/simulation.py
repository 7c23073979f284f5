r"""The robot under physics: a MuJoCo simulation, two joint controllers and tracking runs.

The arm's equations of motion are

.. math::

   M(q)\,\ddot q + c(q, \dot q) + g(q) + D\,\dot q = \tau,

with the mass matrix :math:`M` (armature included), the Coriolis and centrifugal torques
:math:`c`, gravity :math:`g`, the joint damping :math:`D` and the motor torques
:math:`\tau`. MuJoCo integrates them; its inverse dynamics (``mj_inverse``) returns the
:math:`\tau` that produces a given :math:`\ddot q` at a given :math:`(q, \dot q)`.

Two controllers track a reference :math:`(q_d, \dot q_d, \ddot q_d)(t)`, with the errors
:math:`e = q_d - q` and :math:`\dot e = \dot q_d - \dot q`:

- joint PD (:class:`JointPD`), optionally with gravity compensation,
  :math:`\tau = K_p e + K_d \dot e\ [+\ g(q)]`: every joint a spring and a damper; the
  error depends on the load the springs must carry;
- computed torque (:class:`ComputedTorque`),
  :math:`\tau = M(q)\bigl(\ddot q_d + K_d \dot e + K_p e\bigr) + c(q, \dot q) + g(q) + D\dot q`,
  which cancels the dynamics when the model is right and leaves
  :math:`\ddot e + K_d \dot e + K_p e = 0` on every joint.

:func:`track` runs a controller along a joint trajectory (any object with arrays ``t``
``(N,)``, ``q``, ``qd``, ``qdd`` ``(N, n)``, such as :class:`dqlab.trajectory.joint.Trajectory`)
and returns a :class:`TrackingResult` of arrays.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from .. import dynamics
from ._checks import number, vector
from .mjcf import mjcf_from_robot

__all__ = ["ArmSimulation", "JointPD", "ComputedTorque", "DynamicsModel", "TrackingResult",
           "track",
           "check_trajectory", "sample_reference", "require_mujoco"]


def require_mujoco():
    """Import MuJoCo, or raise an ImportError that says how to install it.

    Returns
    -------
    module
        The ``mujoco`` module.

    Examples
    --------
    >>> require_mujoco().__name__
    'mujoco'
    """
    try:
        import mujoco
    except ImportError:
        raise ImportError("dqlab.sim needs MuJoCo to simulate: install the extra with "
                          "pip install 'dqlab[sim]' (or pip install mujoco)") from None
    return mujoco


class ArmSimulation:
    r"""A MuJoCo simulation of a :class:`~dqlab.robot.Robot` driven by joint torques.

    Parameters
    ----------
    robot : Robot
        The arm; the model is generated once by :func:`~dqlab.sim.mjcf.mjcf_from_robot`
        (later changes to the robot's base or tool are not seen).
    **model_options
        Passed to :func:`~dqlab.sim.mjcf.mjcf_from_robot` (``masses``, ``payload``,
        ``timestep``, ``damping``, ``armature``, ``gravity``...).

    Attributes
    ----------
    robot : Robot
    xml : str
        The generated MJCF.
    model, data : mujoco.MjModel, mujoco.MjData

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> sim = ArmSimulation(ur3())
    >>> q0 = np.array([0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0])
    >>> sim.reset(q0)
    >>> np.allclose(sim.flange_pose(), ur3().fk(q0))
    True
    >>> sim.step(sim.inverse_dynamics(q0, np.zeros(6), np.zeros(6)), steps=100)
    >>> bool(np.abs(sim.q - q0).max() < 1e-9)      # gravity held exactly: the arm stays
    True
    """

    def __init__(self, robot, **model_options):
        mujoco = require_mujoco()
        self._mj = mujoco
        self.robot = robot
        self.xml = mjcf_from_robot(robot, **model_options)
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        # inverse dynamics consistent with the discrete-time step of the integrator
        # (implicit damping included); MuJoCo (3.1 and later) offers it for all but RK4
        discrete = getattr(mujoco.mjtEnableBit, "mjENBL_INVDISCRETE", None)
        if discrete is not None and self.model.opt.integrator != mujoco.mjtIntegrator.mjINT_RK4:
            self.model.opt.enableflags |= discrete
        self.data = mujoco.MjData(self.model)
        self._scratch = mujoco.MjData(self.model)
        self._flange = self.model.site("flange").id
        self._payload_body = self.model.body("payload").id
        self._payload_radius = float(self.model.geom("payload").size[0])
        self._lo, self._hi = robot.limits.T
        mujoco.mj_forward(self.model, self.data)

    # -- state -----------------------------------------------------------------------------
    @property
    def n(self):
        return self.robot.n

    @property
    def timestep(self):
        """Integration step in seconds."""
        return float(self.model.opt.timestep)

    @property
    def time(self):
        """Simulated time in seconds."""
        return float(self.data.time)

    @property
    def q(self):
        """Joint positions, shape (n,) (a copy)."""
        return self.data.qpos.copy()

    @property
    def qd(self):
        """Joint velocities, shape (n,) (a copy)."""
        return self.data.qvel.copy()

    def reset(self, q, qd=None, *, time=0.0):
        """Put the arm at rest (or moving with ``qd``) at ``q`` and set the clock.

        Raises
        ------
        ValueError
            If ``q`` or ``qd`` has the wrong shape, holds NaN or infinity, or ``q`` is
            outside the robot's joint limits.
        """
        q = self.check_target(q, "q")
        qd = np.zeros(self.n) if qd is None else vector(qd, self.n, "qd")
        self._mj.mj_resetData(self.model, self.data)
        self.data.qpos[:] = q
        self.data.qvel[:] = qd
        self.data.time = float(time)
        self._mj.mj_forward(self.model, self.data)

    def check_target(self, q, name="q"):
        """``q`` as a float array of shape (n,), or a ValueError naming ``name``: wrong
        shape, NaN or infinity, or a joint beyond its limits."""
        q = vector(q, self.n, name)
        bad = np.flatnonzero((q < self._lo) | (q > self._hi))
        if bad.size:
            j = bad[0]
            raise ValueError(f"{name}: joint {j + 1} = {q[j]:.6g} is beyond its limits "
                             f"[{self._lo[j]:.6g}, {self._hi[j]:.6g}]")
        return q

    def flange_positions(self, q):
        """Positions of the flange site (the TCP) in the world for joint vectors ``q``
        (N, n), shape (N, 3), by MuJoCo's forward kinematics (equal to ``robot.fk``; no
        limit check, so a sample a hair beyond a prismatic joint's travel is fine).
        """
        q = np.asarray(q, dtype=float)
        scratch = self._scratch
        out = np.empty((len(q), 3))
        for k, q_k in enumerate(q):
            scratch.qpos[:] = q_k
            self._mj.mj_kinematics(self.model, scratch)
            out[k] = scratch.site_xpos[self._flange]
        return out

    def flange_pose(self):
        """:math:`X_{WT}`, the pose of the flange site (the TCP) in the world, shape (4, 4)."""
        X = np.eye(4)
        X[:3, :3] = self.data.site_xmat[self._flange].reshape(3, 3)
        X[:3, 3] = self.data.site_xpos[self._flange]
        return X

    # -- the payload -------------------------------------------------------------------------
    @property
    def payload(self):
        """Mass in kg of the payload at the TCP (a solid sphere); assign to change it."""
        mass = float(self.model.body_mass[self._payload_body])
        return 0.0 if mass <= 1e-9 else mass

    @payload.setter
    def payload(self, mass):
        mass = number(mass, "payload", strict=False)
        self.model.body_mass[self._payload_body] = mass
        self.model.body_inertia[self._payload_body] = 0.4 * mass * self._payload_radius ** 2
        # recompute the model's derived constants on the scratch data (mj_setConst moves the
        # data it is given to the reference configuration)
        self._mj.mj_setConst(self.model, self._scratch)

    # -- dynamics ----------------------------------------------------------------------------
    def step(self, torque, steps=1):
        """Apply joint torques (N m; N for a prismatic joint) and advance ``steps`` steps.

        Raises
        ------
        ValueError
            If ``torque`` has the wrong shape or holds NaN or infinity.
        """
        self.data.ctrl[:] = vector(torque, self.n, "torque")
        for _ in range(int(steps)):
            self._mj.mj_step(self.model, self.data)

    def inverse_dynamics(self, q, qd, qdd):
        r"""The joint torques :math:`\tau` that give the acceleration ``qdd`` at ``(q, qd)``.

        .. math::

           \tau = M(q)\,\ddot q + c(q, \dot q) + g(q) + D\,\dot q

        by MuJoCo's ``mj_inverse`` (consistent with the implicit integrator's step).

        Parameters
        ----------
        q, qd, qdd : array_like, shape (n,)

        Returns
        -------
        ndarray, shape (n,)
        """
        scratch = self._scratch
        scratch.qpos[:] = q
        scratch.qvel[:] = qd
        scratch.qacc[:] = qdd
        self._mj.mj_inverse(self.model, scratch)
        return scratch.qfrc_inverse.copy()

    def gravity_torque(self, q):
        """:math:`g(q)`, the torques that hold the arm still at ``q``, shape (n,)."""
        zero = np.zeros(self.n)
        return self.inverse_dynamics(q, zero, zero)

    def mass_matrix(self, q):
        """:math:`M(q)`, shape (n, n), armature included."""
        scratch = self._scratch
        scratch.qpos[:] = q
        self._mj.mj_fwdPosition(self.model, scratch)
        M = np.empty((self.n, self.n))
        try:
            self._mj.mj_fullM(self.model, scratch, M)             # MuJoCo 4
        except TypeError:
            self._mj.mj_fullM(self.model, M, scratch.qM)          # MuJoCo 3
        return M


def _gains(controller, n):
    """The controller's ``kp`` and ``kd`` as checked arrays of shape (n,), checked once per
    number of joints and kept with the (immutable) controller."""
    cache = controller.__dict__.setdefault("_gain_vectors", {})
    if n not in cache:
        cache[n] = (vector(controller.kp, n, "kp"), vector(controller.kd, n, "kd"))
    return cache[n]


@dataclass(frozen=True)
class JointPD:
    r"""Joint PD control, :math:`\tau = K_p (q_d - q) + K_d (\dot q_d - \dot q)`,
    plus :math:`g(q)` when ``gravity_compensation`` is true.

    Parameters
    ----------
    kp : float or array_like, shape (n,)
        Stiffness per joint, N m/rad.
    kd : float or array_like, shape (n,)
        Damping per joint, N m s/rad.
    gravity_compensation : bool, optional
        Add the model's gravity torques.
    model : ArmSimulation, optional
        The controller's own model for the gravity torques (for instance without the
        payload the arm really carries). Default: the simulated arm itself.

    Examples
    --------
    >>> JointPD(kp=100.0, kd=10.0).name
    'PD'
    >>> JointPD(kp=100.0, kd=10.0, gravity_compensation=True).name
    'PD + gravity'
    """

    kp: object
    kd: object
    gravity_compensation: bool = False
    model: object = field(default=None, repr=False, compare=False)

    @property
    def name(self):
        return "PD + gravity" if self.gravity_compensation else "PD"

    def torque(self, sim, q_d, qd_d, qdd_d):
        """Motor torques for the reference ``(q_d, qd_d, qdd_d)``, shape (n,)."""
        kp, kd = _gains(self, sim.n)
        q = sim.data.qpos
        tau = kp * (q_d - q) + kd * (qd_d - sim.data.qvel)
        if self.gravity_compensation:
            tau = tau + (self.model or sim).gravity_torque(q)
        return tau


@dataclass(frozen=True)
class ComputedTorque:
    r"""Computed-torque control by inverse dynamics,
    :math:`\tau = \mathrm{ID}\bigl(q, \dot q,\ \ddot q_d + K_d \dot e + K_p e\bigr)`.

    With an exact model the closed loop is :math:`\ddot e + K_d \dot e + K_p e = 0` on
    every joint: critically damped for :math:`K_p = \omega^2,\ K_d = 2\omega`.

    Parameters
    ----------
    kp : float or array_like, shape (n,)
        1/s^2. Default :math:`20^2`.
    kd : float or array_like, shape (n,)
        1/s. Default :math:`2 \cdot 20`.
    model : DynamicsModel or ArmSimulation, optional
        The controller's own model of the arm: a :class:`DynamicsModel` (dqlab's
        Newton--Euler on the robot's inertial parameters, which may be wrong, as a real
        controller's are), or another simulation (for instance without the payload the arm
        really carries). Default: the simulated arm itself, an exact model that no real
        controller has.

    Examples
    --------
    >>> ComputedTorque().name
    'computed torque'
    """

    kp: object = 400.0
    kd: object = 40.0
    model: object = field(default=None, repr=False, compare=False)

    name = "computed torque"

    def torque(self, sim, q_d, qd_d, qdd_d):
        """Motor torques for the reference ``(q_d, qd_d, qdd_d)``, shape (n,)."""
        kp, kd = _gains(self, sim.n)
        q, qd = sim.data.qpos, sim.data.qvel
        qdd_cmd = qdd_d + kd * (qd_d - qd) + kp * (q_d - q)
        return (self.model or sim).inverse_dynamics(q, qd, qdd_cmd)


@dataclass(frozen=True)
class DynamicsModel:
    r"""A controller's model of the arm by :mod:`dqlab.dynamics`, not by the simulator.

    .. math::

       \tau = M(q)\,\ddot q + c(q, \dot q) + g(q) + \operatorname{diag}(a)\,\ddot q
       + D\,\dot q

    with :math:`M, c, g` from :func:`dqlab.dynamics.inverse_dynamics` on ``robot``'s link
    inertias, the motors' armature :math:`a` (reflected rotor inertia) and the joints'
    viscous damping :math:`D`. Give it a robot whose inertias are wrong (a payload it does
    not know, scaled masses) to study a controller whose model is not the plant.

    Parameters
    ----------
    robot : Robot
        Every link must carry inertial parameters (``Link.inertia``).
    armature, damping : float or array_like, shape (n,), optional
        kg m^2 and N m s/rad (0 by default).
    gravity : float, optional
        m/s^2 along the world's -z.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> sim = ArmSimulation(ur3())
    >>> model = DynamicsModel.of_simulation(sim)
    >>> q = np.array([0.3, -1.1, 1.4, -1.6, -1.5, 0.2])
    >>> bool(np.allclose(model.gravity_torque(q), sim.gravity_torque(q), atol=1e-12))
    True
    """

    robot: object
    armature: object = 0.0
    damping: object = 0.0
    gravity: float = 9.81
    name = "dqlab dynamics"
    _prepared: object = field(init=False, repr=False, compare=False, default=None)

    def __post_init__(self):
        n = self.robot.n
        g = (0.0, 0.0, -number(self.gravity, "gravity", strict=False))
        prepared = (dynamics.NewtonEuler(self.robot, gravity=g),
                    vector(self.armature, n, "armature"), vector(self.damping, n, "damping"))
        object.__setattr__(self, "_prepared", prepared)

    @classmethod
    def of_simulation(cls, sim, robot=None):
        """The model with the motors (armature, damping) and gravity of the simulation
        ``sim`` and the rigid bodies of ``robot`` (default: the simulated robot itself, an
        exact rigid-body model)."""
        return cls(sim.robot if robot is None else robot,
                   armature=sim.model.dof_armature.copy(), damping=sim.model.dof_damping.copy(),
                   gravity=-float(sim.model.opt.gravity[2]))

    @property
    def n(self):
        return self.robot.n

    def inverse_dynamics(self, q, qd, qdd):
        """Joint torques for the accelerations ``qdd`` at ``(q, qd)``, shape (n,)."""
        newton_euler, armature, damping = self._prepared
        return newton_euler(q, qd, qdd) + armature * np.asarray(qdd) + damping * np.asarray(qd)

    def gravity_torque(self, q):
        """:math:`g(q)`, shape (n,)."""
        zero = np.zeros(self.n)
        return self._prepared[0](q, zero, zero)

    def mass_matrix(self, q):
        r""":math:`M(q) + \operatorname{diag}(a)`, shape (n, n)."""
        return dynamics.mass_matrix(self.robot, q) + np.diag(self._prepared[1])


@dataclass(frozen=True)
class TrackingResult:
    """A simulated run: the state, the torques and the reference at every time step.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Times in s.
    q, qd : ndarray, shape (N, n)
        Joint positions (rad or m) and velocities reached.
    torque : ndarray, shape (N, n)
        Motor torques applied from each time on (N m, or N for a prismatic joint).
    q_desired, qd_desired : ndarray, shape (N, n)
        The reference at the same times.
    tcp, tcp_desired : ndarray, shape (N, 3)
        The TCP (flange site) positions reached and those of the reference, m.
    flange_error : ndarray, shape (N,)
        Distance in m between the two, :math:`\\lVert p(q) - p(q_d) \\rVert`.
    controller : str
        Which controller ran.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    torque: np.ndarray
    q_desired: np.ndarray
    qd_desired: np.ndarray
    tcp: np.ndarray
    tcp_desired: np.ndarray
    flange_error: np.ndarray
    controller: str

    @property
    def error(self):
        """Joint tracking error :math:`q_d - q`, shape (N, n)."""
        return self.q_desired - self.q

    @property
    def max_error(self):
        """Largest absolute joint error per joint, shape (n,)."""
        return np.abs(self.error).max(axis=0)

    def frames(self, fps=25.0):
        """Samples for playing the run back at ``fps`` frames per second.

        Returns
        -------
        times : ndarray, shape (k,)
        q : ndarray, shape (k, n)
            The joint positions reached at those times, for
            :meth:`dqlab.viz.scene.Scene.animate` (``scene.animate(q, times=times)``).
        """
        if not (math.isfinite(fps) and fps > 0):
            raise ValueError(f"fps must be a positive number, got {fps!r}")
        wanted = np.arange(self.t[0], self.t[-1] + 1e-12, 1.0 / fps)
        index = np.searchsorted(self.t, wanted - 1e-9)      # the first step at or after
        index = np.unique(np.clip(index, 0, self.t.size - 1))
        return self.t[index], self.q[index]


def check_trajectory(trajectory, robot):
    """Validate a joint trajectory for ``robot``: arrays ``t`` (N,) and ``q``, ``qd``, ``qdd``
    (N, n), finite, times increasing, every ``q`` inside the joint limits.

    Returns
    -------
    t, q, qd, qdd : ndarray

    Raises
    ------
    ValueError
        Naming the field: a missing or misshapen array, NaN or infinity, times that do not
        increase, or a joint beyond its limits.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from dqlab.models import ur3
    >>> bad = SimpleNamespace(t=np.arange(3.0), q=np.full((3, 6), 7.0), qd=np.zeros((3, 6)),
    ...                       qdd=np.zeros((3, 6)))
    >>> check_trajectory(bad, ur3())
    Traceback (most recent call last):
    ...
    ValueError: trajectory.q: joint 1 (revolute) = 7 is beyond its limits [-6.28319, 6.28319]
    """
    arrays = {}
    for key in ("t", "q", "qd", "qdd"):
        if not hasattr(trajectory, key):
            raise ValueError(f"trajectory must have arrays t, q, qd and qdd; no {key!r}")
        try:
            arrays[key] = np.asarray(getattr(trajectory, key), dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"trajectory.{key} must be an array of numbers") from None
        if not np.isfinite(arrays[key]).all():
            raise ValueError(f"trajectory.{key} contains NaN or infinity")
    t = arrays["t"]
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"trajectory.t must have shape (N,) with N >= 2, got {t.shape}")
    if not (np.diff(t) > 0).all():
        raise ValueError("trajectory.t must increase strictly")
    for key in ("q", "qd", "qdd"):
        if arrays[key].shape != (t.size, robot.n):
            raise ValueError(f"trajectory.{key} must have shape ({t.size}, {robot.n}), "
                             f"got {arrays[key].shape}")
    try:
        robot.check_joints(arrays["q"], limits="all")
    except ValueError as exc:
        raise ValueError(f"trajectory.q: {exc}") from None
    return t, arrays["q"], arrays["qd"], arrays["qdd"]


def sample_reference(t, q, qd, qdd, times, *, velocity_lag=0.0):
    r"""A sampled joint reference at other ``times``.

    Positions by cubic Hermite interpolation with the velocities as slopes (exact for a
    cubic between samples), velocities and accelerations linearly; before the first and
    after the last sample the end values are held. The velocity is taken ``velocity_lag``
    seconds earlier (see :func:`track`).

    Parameters
    ----------
    t : array_like, shape (N,)
        Increasing sample times, s.
    q, qd, qdd : array_like, shape (N, n)
    times : array_like, shape (k,)
    velocity_lag : float, optional

    Returns
    -------
    q, qd, qdd : ndarray, shape (k, n)

    Examples
    --------
    >>> import numpy as np
    >>> t = np.array([0.0, 1.0])
    >>> q, qd, qdd = sample_reference(t, [[0.0], [1.0]], [[0.0], [0.0]], [[6.0], [-6.0]],
    ...                               [0.5])
    >>> q, qd, qdd                              # the cubic 3 t^2 - 2 t^3 at t = 0.5
    (array([[0.5]]), array([[0.]]), array([[0.]]))
    """
    t = np.asarray(t, dtype=float)
    q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
    times = np.asarray(times, dtype=float)

    def locate(times):
        times = np.clip(times, t[0], t[-1])
        k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, t.size - 2)
        h = (t[k + 1] - t[k])[:, None]
        return k, h, ((times - t[k])[:, None]) / h

    k, h, s = locate(times)
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    q_ref = h00 * q[k] + h10 * h * qd[k] + h01 * q[k + 1] + h11 * h * qd[k + 1]
    qdd_ref = (1 - s) * qdd[k] + s * qdd[k + 1]
    if velocity_lag:
        k, h, s = locate(times - velocity_lag)
    qd_ref = (1 - s) * qd[k] + s * qd[k + 1]
    return q_ref, qd_ref, qdd_ref


def track(sim, trajectory, controller, *, start_from_trajectory=True, payload=None):
    r"""Run ``controller`` along a joint trajectory in the simulation.

    The controller computes the torques once per simulation step from the state and the
    reference at that instant (the trajectory is interpolated: cubic Hermite for positions,
    linear for velocities and accelerations), and holds them over the step.

    MuJoCo's Euler-type integrators (``implicitfast`` included) update the velocity first
    and move the position with the new one, :math:`\dot q_{k+1} = \dot q_k + h \ddot q_k`,
    :math:`q_{k+1} = q_k + h \dot q_{k+1}`: the velocity is the midpoint velocity of the
    step that just ended, :math:`\dot q_k \approx \dot q(t_k - h/2)` (as a backward
    difference of measured positions would be). The reference velocity is therefore taken
    at :math:`t_k - h/2`; comparing it at :math:`t_k` instead would leave a lag of order
    :math:`h K_d \ddot q_d / (2 K_p)`, about five times the error left with the shift.

    Parameters
    ----------
    sim : ArmSimulation
    trajectory : object with arrays ``t`` (N,), ``q``, ``qd``, ``qdd`` (N, n)
        For instance :class:`dqlab.trajectory.joint.Trajectory`.
    controller : JointPD or ComputedTorque
        Or any object with ``torque(sim, q_d, qd_d, qdd_d)`` and a ``name``.
    start_from_trajectory : bool, optional
        Reset the arm to the first sample (position and velocity) before the run (default);
        otherwise start from the simulation's current state.
    payload : array_like, shape (N,), optional
        The mass (kg) the arm really carries at each sample of the trajectory, held until
        the next sample (an object picked and placed). The controller is not told: a
        :class:`ComputedTorque` keeps its own model. Default: the simulation's payload
        throughout. The simulation's payload is restored after the run.

    Returns
    -------
    TrackingResult
        Sampled at every simulation step from the first to the last time of the trajectory.

    Raises
    ------
    ValueError
        If the trajectory is misshapen, holds NaN or infinity, or leaves the joint limits
        (see :func:`check_trajectory`); nothing is simulated then.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from dqlab.models import ur3
    >>> t = np.linspace(0.0, 1.0, 201)
    >>> s = 3 * t**2 - 2 * t**3                          # a smooth rest-to-rest law
    >>> q0 = np.array([0.0, -1.5, 1.0, -1.0, -1.5, 0.0])
    >>> step = np.array([0.5, 0.3, -0.4, 0.2, 0.1, 0.6])
    >>> move = SimpleNamespace(t=t, q=q0 + s[:, None] * step,
    ...                        qd=(6 * t - 6 * t**2)[:, None] * step,
    ...                        qdd=(6 - 12 * t)[:, None] * step)
    >>> result = track(ArmSimulation(ur3()), move, ComputedTorque())
    >>> result.t.shape, result.q.shape
    ((1001,), (1001, 6))
    >>> bool(result.max_error.max() < 5e-5)              # rad
    True
    """
    t, q, qd, qdd = check_trajectory(trajectory, sim.robot)
    masses = None
    if payload is not None:
        masses = np.asarray(payload, dtype=float)
        if masses.shape != t.shape or not np.isfinite(masses).all() or (masses < 0).any():
            raise ValueError(f"payload must hold {t.size} finite masses >= 0 (one per "
                             f"trajectory sample), got shape {masses.shape}")
    if start_from_trajectory:
        sim.reset(q[0], qd[0], time=t[0])
    dt = sim.timestep
    steps = int(math.floor((t[-1] - t[0]) / dt + 1e-9))
    times = sim.time + dt * np.arange(steps + 1)
    q_ref, qd_ref, qdd_ref = sample_reference(t, q, qd, qdd, times - sim.time + t[0],
                                              velocity_lag=dt / 2)
    n = sim.n
    q_out = np.empty((steps + 1, n))
    qd_out = np.empty((steps + 1, n))
    tau_out = np.empty((steps + 1, n))
    data = sim.data
    if masses is not None:
        saved_payload = sim.payload
        sample = np.clip(np.searchsorted(t, times - sim.time + t[0] + 1e-12, side="right") - 1,
                         0, t.size - 1)
        carried = masses[sample]
    for k in range(steps + 1):
        if masses is not None and (k == 0 or carried[k] != carried[k - 1]):
            sim.payload = carried[k]
        q_out[k] = data.qpos
        qd_out[k] = data.qvel
        tau = controller.torque(sim, q_ref[k], qd_ref[k], qdd_ref[k])
        tau_out[k] = tau
        if k < steps:
            sim.step(tau)
    if masses is not None:
        sim.payload = saved_payload
    # (after mj_step, MuJoCo's site positions still belong to the state before the step:
    # both are recomputed from the joints)
    tcp, tcp_desired = sim.flange_positions(q_out), sim.flange_positions(q_ref)
    return TrackingResult(t=times, q=q_out, qd=qd_out, torque=tau_out, q_desired=q_ref,
                          qd_desired=qd_ref, tcp=tcp, tcp_desired=tcp_desired,
                          flange_error=np.linalg.norm(tcp - tcp_desired, axis=-1),
                          controller=getattr(controller, "name", type(controller).__name__))
