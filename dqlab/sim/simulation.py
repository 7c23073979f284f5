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
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from .. import dynamics
from .._checks import as_float_array, check_instance, check_scalar
from ..robot import Robot
from ._checks import per_joint, vector
from .mjcf import mjcf_from_robot

__all__ = ["ArmSimulation", "JointPD", "ComputedTorque", "DynamicsModel", "TrackingResult",
           "track",
           "check_trajectory", "sample_reference", "require_mujoco", "SimulationError",
           "MAX_CONTROL", "MAX_STEPS"]

#: The largest torque (N m, or force in N) MuJoCo applies: a larger control is set to 0 with
#: a warning (its ``mjMAXVAL``), so :meth:`ArmSimulation.step` refuses it.
MAX_CONTROL = 1e10
#: The most time steps :func:`track` simulates in one run.
MAX_STEPS = 10 ** 7
# MuJoCo's warnings that mean the state or the control was bad and was reset or ignored
_FAILURES = {"mjWARN_BADQACC": "an acceleration", "mjWARN_BADQVEL": "a velocity",
             "mjWARN_BADQPOS": "a position", "mjWARN_BADCTRL": "a control"}


class SimulationError(ValueError):
    """The simulation failed: its state diverged (NaN, infinity or a value beyond
    MuJoCo's 1e10, after which MuJoCo silently resets the arm to q = 0), or a controller
    asked for a torque MuJoCo would ignore. A ``ValueError``, since the cause lies in the
    inputs: gains too high for the time step, torques or a model out of range.
    """


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
        check_instance(robot, Robot, "robot")
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
        self._n = robot.n
        self._failures = {int(getattr(mujoco.mjtWarning, key)): what
                          for key, what in _FAILURES.items()}
        self._mujoco_messages = deque(maxlen=16)
        mujoco.mj_forward(self.model, self.data)

    # -- state -----------------------------------------------------------------------------
    @property
    def n(self):
        """Number of joints."""
        return self._n

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
        time = check_scalar(time, "time")
        self._mj.mj_resetData(self.model, self.data)
        self.data.qpos[:] = q
        self.data.qvel[:] = qd
        self.data.time = time
        previous = self._keep_mujoco_warnings()
        try:
            self._mj.mj_forward(self.model, self.data)
        finally:
            self._mj.set_mju_user_warning(previous)

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
        (..., n), shape (..., 3), by MuJoCo's forward kinematics (equal to ``robot.fk``; no
        limit check, so a sample a hair beyond a prismatic joint's travel is fine).

        Raises
        ------
        ValueError
            If ``q`` does not end with n joints or holds NaN or infinity (``TypeError`` for
            complex numbers or text).
        """
        q = as_float_array(q, "q", (self.n,))
        scratch = self._scratch
        flat = q.reshape(-1, self.n)
        out = np.empty((len(flat), 3))
        for k, q_k in enumerate(flat):
            scratch.qpos[:] = q_k
            self._mj.mj_kinematics(self.model, scratch)
            out[k] = scratch.site_xpos[self._flange]
        return out.reshape(q.shape[:-1] + (3,))

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
        mass = check_scalar(mass, "payload", minimum=0)
        self.model.body_mass[self._payload_body] = mass
        self.model.body_inertia[self._payload_body] = 0.4 * mass * self._payload_radius ** 2
        # recompute the model's derived constants on the scratch data (mj_setConst moves the
        # data it is given to the reference configuration)
        previous = self._keep_mujoco_warnings()
        try:
            self._mj.mj_setConst(self.model, self._scratch)
        finally:
            self._mj.set_mju_user_warning(previous)

    # -- dynamics ----------------------------------------------------------------------------
    def step(self, torque, steps=1):
        """Apply joint torques (N m; N for a prismatic joint) and advance ``steps`` steps.

        Raises
        ------
        ValueError
            If ``torque`` has the wrong shape, holds NaN or infinity or a value beyond
            :data:`MAX_CONTROL` (which MuJoCo would set to 0), or ``steps`` is not an
            integer from 0 to :data:`MAX_STEPS`.
        SimulationError
            If the state diverges during a step (MuJoCo's warnings: NaN, infinity or a
            value beyond 1e10 in an acceleration, velocity or position, after which it
            resets the arm to q = 0 and goes on); the step that failed is the last one
            taken.
        """
        torque = vector(torque, self.n, "torque")
        values = torque.tolist()
        if max(values) > MAX_CONTROL or min(values) < -MAX_CONTROL:
            j = int(np.argmax(np.abs(torque)))
            raise ValueError(f"torque: joint {j + 1} = {torque[j]:.6g} is too large: MuJoCo "
                             f"ignores controls beyond {MAX_CONTROL:g}")
        steps = check_scalar(steps, "steps", minimum=0, maximum=MAX_STEPS, integer=True)
        self.data.ctrl[:] = torque
        counts = self.data.warning.number            # MuJoCo's warning counters (a view)
        before = counts.tolist()
        previous = self._keep_mujoco_warnings()
        try:
            for _ in range(steps):
                start = self.data.time
                self._mj.mj_step(self.model, self.data)
                after = counts.tolist()
                if after != before:
                    self._raise_if_failed(before, after, start)
                    before = after
        finally:
            self._mj.set_mju_user_warning(previous)

    def _keep_mujoco_warnings(self):
        """Keep MuJoCo's warnings (the last few, for the errors of :meth:`step`) instead of
        having them printed and appended to ``MUJOCO_LOG.TXT`` in the working directory;
        returns the handler to put back with ``mujoco.set_mju_user_warning``."""
        previous = self._mj.get_mju_user_warning()
        self._mj.set_mju_user_warning(self._mujoco_messages.append)
        return previous

    def _raise_if_failed(self, before, after, start):
        """SimulationError if one of MuJoCo's failure counters went up during the step that
        began at the time ``start``."""
        what = [w for i, w in self._failures.items() if after[i] != before[i]]
        if not what:
            return
        said = f" (MuJoCo: {self._mujoco_messages[-1]})" if self._mujoco_messages else ""
        self._mujoco_messages.clear()
        raise SimulationError(
            f"the simulation diverged in the step from t = {start:.6g} s: "
            f"{' and '.join(what)} became NaN, infinite or beyond 1e10 and MuJoCo reset the "
            f"arm to q = 0{said}; the gains "
            f"may be too high for the time step {self.timestep:g} s, or the torques too large "
            f"for the arm")

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

        Raises
        ------
        ValueError
            If an argument does not have shape (n,), holds NaN or infinity, or the torques
            overflow (``TypeError`` for complex numbers or text).
        """
        scratch = self._scratch
        scratch.qpos[:] = vector(q, self.n, "q")
        scratch.qvel[:] = vector(qd, self.n, "qd")
        scratch.qacc[:] = vector(qdd, self.n, "qdd")
        previous = self._keep_mujoco_warnings()
        try:
            self._mj.mj_inverse(self.model, scratch)
        finally:
            self._mj.set_mju_user_warning(previous)
        tau = scratch.qfrc_inverse.copy()
        total = sum(tau.tolist())
        if not total - total == 0.0 and not np.isfinite(tau).all():
            raise ValueError("the inverse dynamics overflow: q, qd or qdd is too large")
        return tau

    def gravity_torque(self, q):
        """:math:`g(q)`, the torques that hold the arm still at ``q``, shape (n,)."""
        zero = np.zeros(self.n)
        return self.inverse_dynamics(q, zero, zero)

    def mass_matrix(self, q):
        """:math:`M(q)`, shape (n, n), armature included."""
        scratch = self._scratch
        scratch.qpos[:] = vector(q, self.n, "q")
        previous = self._keep_mujoco_warnings()
        try:
            self._mj.mj_fwdPosition(self.model, scratch)
        finally:
            self._mj.set_mju_user_warning(previous)
        M = np.empty((self.n, self.n))
        try:
            self._mj.mj_fullM(self.model, scratch, M)             # MuJoCo 4
        except TypeError:
            self._mj.mj_fullM(self.model, M, scratch.qM)          # MuJoCo 3
        return M


class _Gains:
    """The gains ``kp`` and ``kd`` of a controller as (n,) arrays >= 0, checked once for a
    number of joints and kept (the controllers are frozen: their gains do not change)."""

    def _gains(self, n):
        checked = getattr(self, "_checked_gains", None)
        if checked is None or checked[0] != n:
            checked = (n, per_joint(self.kp, n, "kp", positive=False),
                       per_joint(self.kd, n, "kd", positive=False))
            object.__setattr__(self, "_checked_gains", checked)
        return checked[1], checked[2]

    def _reference(self, sim, q_d, qd_d, qdd_d):
        """The arguments of ``torque``, checked: a simulation and three (n,) vectors."""
        check_instance(sim, ArmSimulation, "sim")
        n = sim.n
        return vector(q_d, n, "q_d"), vector(qd_d, n, "qd_d"), vector(qdd_d, n, "qdd_d")


@dataclass(frozen=True)
class JointPD(_Gains):
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
        q_d, qd_d, qdd_d = self._reference(sim, q_d, qd_d, qdd_d)
        kp, kd = self._gains(sim.n)
        q = sim.data.qpos
        tau = kp * (q_d - q) + kd * (qd_d - sim.data.qvel)
        if self.gravity_compensation:
            tau = tau + (self.model or sim).gravity_torque(q)
        return tau


@dataclass(frozen=True)
class ComputedTorque(_Gains):
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
        q_d, qd_d, qdd_d = self._reference(sim, q_d, qd_d, qdd_d)
        kp, kd = self._gains(sim.n)
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
        check_instance(self.robot, Robot, "robot")
        n = self.robot.n
        g = (0.0, 0.0, -check_scalar(self.gravity, "gravity", minimum=0))
        prepared = (dynamics.NewtonEuler(self.robot, gravity=g),
                    per_joint(self.armature, n, "armature", positive=False),
                    per_joint(self.damping, n, "damping", positive=False))
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
        fps = check_scalar(fps, "fps", minimum=0, strict=True)
        if (self.t[-1] - self.t[0]) * fps > MAX_STEPS:
            raise ValueError(f"fps = {fps:g} is too large for a run of "
                             f"{self.t[-1] - self.t[0]:g} s (more than {MAX_STEPS:.0e} frames)")
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
    check_instance(robot, Robot, "robot")
    arrays = {}
    for key in ("t", "q", "qd", "qdd"):
        if not hasattr(trajectory, key):
            raise ValueError(f"trajectory must have arrays t, q, qd and qdd; no {key!r}")
        arrays[key] = as_float_array(getattr(trajectory, key), f"trajectory.{key}")
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
    t = as_float_array(t, "t")
    if t.ndim != 1 or t.size < 2 or not (np.diff(t) > 0).all():
        raise ValueError(f"t must be increasing sample times of shape (N,) with N >= 2, got "
                         f"shape {t.shape}")
    q, qd, qdd = (as_float_array(x, name) for x, name in ((q, "q"), (qd, "qd"), (qdd, "qdd")))
    for x, name in ((q, "q"), (qd, "qd"), (qdd, "qdd")):
        if x.ndim != 2 or x.shape[0] != t.size:
            raise ValueError(f"{name} must have shape ({t.size}, n), one row per sample of t, "
                             f"got shape {x.shape}")
        if x.shape != q.shape:
            raise ValueError(f"{name} must have the shape of q, {q.shape}, got {x.shape}")
    times = as_float_array(times, "times")
    if times.ndim != 1:
        raise ValueError(f"times must have shape (k,), got shape {times.shape}")
    velocity_lag = check_scalar(velocity_lag, "velocity_lag")

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
        (see :func:`check_trajectory`), is shorter than one time step or needs more than
        :data:`MAX_STEPS` of them, or ``payload`` is not one mass >= 0 per sample; nothing
        is simulated then.
    SimulationError
        If the run fails: the controller asks for a torque beyond :data:`MAX_CONTROL`
        (which MuJoCo would ignore), or the state diverges (see :meth:`ArmSimulation.step`),
        for instance with gains too high for the time step. No result is returned for a
        failed run.

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
    check_instance(sim, ArmSimulation, "sim")
    if not callable(getattr(controller, "torque", None)):
        raise TypeError(f"controller must have a method torque(sim, q_d, qd_d, qdd_d), got "
                        f"{type(controller).__name__}")
    t, q, qd, qdd = check_trajectory(trajectory, sim.robot)
    masses = None
    if payload is not None:
        masses = as_float_array(payload, "payload")
        if masses.shape != t.shape or (masses < 0).any():
            raise ValueError(f"payload must hold {t.size} finite masses >= 0 (one per "
                             f"trajectory sample), got shape {masses.shape}")
    dt = sim.timestep
    count = (t[-1] - t[0]) / dt
    if count > MAX_STEPS:
        raise ValueError(f"the trajectory lasts {t[-1] - t[0]:g} s: {count:.3g} time steps of "
                         f"{dt:g} s is too large (at most {MAX_STEPS:.0e})")
    steps = int(math.floor(count + 1e-9))
    if steps < 1:
        raise ValueError(f"the trajectory lasts {t[-1] - t[0]:g} s, less than one time step "
                         f"({dt:g} s): there is nothing to simulate")
    if start_from_trajectory:
        sim.reset(q[0], qd[0], time=t[0])
    times = sim.time + dt * np.arange(steps + 1)
    q_ref, qd_ref, qdd_ref = sample_reference(t, q, qd, qdd, times - sim.time + t[0],
                                              velocity_lag=dt / 2)
    n = sim.n
    q_out = np.empty((steps + 1, n))
    qd_out = np.empty((steps + 1, n))
    tau_out = np.empty((steps + 1, n))
    saved_payload = sim.payload
    carried = None
    if masses is not None:
        sample = np.clip(np.searchsorted(t, times - sim.time + t[0] + 1e-12, side="right") - 1,
                         0, t.size - 1)
        carried = masses[sample]
    try:
        _run(sim, controller, times, q_ref, qd_ref, qdd_ref, carried, q_out, qd_out, tau_out)
    finally:
        if carried is not None:
            sim.payload = saved_payload            # restored after a failed run too
    # (after mj_step, MuJoCo's site positions still belong to the state before the step:
    # both are recomputed from the joints)
    tcp, tcp_desired = sim.flange_positions(q_out), sim.flange_positions(q_ref)
    return TrackingResult(t=times, q=q_out, qd=qd_out, torque=tau_out, q_desired=q_ref,
                          qd_desired=qd_ref, tcp=tcp, tcp_desired=tcp_desired,
                          flange_error=np.linalg.norm(tcp - tcp_desired, axis=-1),
                          controller=getattr(controller, "name", type(controller).__name__))


def _run(sim, controller, times, q_ref, qd_ref, qdd_ref, carried, q_out, qd_out, tau_out):
    """The loop of :func:`track`: state, torque and step at every instant of ``times``
    (``carried``: the payload at each, or None), written into the ``*_out`` arrays."""
    data = sim.data
    steps = len(times) - 1
    for k in range(steps + 1):
        if carried is not None and (k == 0 or carried[k] != carried[k - 1]):
            sim.payload = carried[k]
        q_out[k] = data.qpos
        qd_out[k] = data.qvel
        tau = controller.torque(sim, q_ref[k], qd_ref[k], qdd_ref[k])
        tau_out[k] = tau
        values = tau_out[k].tolist()
        if not (max(values) <= MAX_CONTROL and min(values) >= -MAX_CONTROL):
            raise SimulationError(
                f"the controller asked for a torque of {np.abs(tau_out[k]).max():.3g} at t = "
                f"{times[k]:.6g} s, too large: MuJoCo ignores controls beyond "
                f"{MAX_CONTROL:g} (gains too high, or the arm far from the reference)")
        if k < steps:
            sim.step(tau)
