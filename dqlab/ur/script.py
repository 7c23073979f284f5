r"""URScript generation with safety checks: ``movej``, ``movel``, ``servoj`` and programs.

URScript is the language of the UR controller; a client sends it as text. This module writes
the commands with URScript's argument names and units (defaults: :mod:`dqlab.ur.motion`):

``movej(q, a, v, t, r)``
    Move in joint space to ``q`` [rad]; the leading joint accelerates at ``a`` [rad/s^2] up
    to ``v`` [rad/s]; ``t`` [s] (if > 0) sets the duration instead; ``r`` [m] is a blend
    radius.
``movel(pose, a, v, t, r)``
    Move the TCP on a straight line to the pose ``p[x, y, z, rx, ry, rz]`` [m, rad]; ``a``
    [m/s^2], ``v`` [m/s].
``servoj(q, t, lookahead_time, gain)``
    Track ``q`` for ``t`` [s] (blocking); ``lookahead_time`` in [0.03, 0.2] s smooths,
    ``gain`` in [100, 2000] stiffens.
``stopj(a)``
    Decelerate the joints to rest at ``a`` [rad/s^2].

Here, as everywhere in :mod:`dqlab.ur`, a **pose** is UR's 6-vector ``[x, y, z, rx, ry, rz]``:
the TCP's position in metres and its orientation as a rotation vector in radians, in the
controller's base frame (DH frame 0 of the robot; see :mod:`dqlab.ur.motion` for the
frames).

**Safety.** No text is produced for a target that is NaN, infinite or complex, a joint
outside the robot's limits, a pose out of the arm's reach, a joint jump between successive
targets larger than ``max_joint_step``, or a motion whose speeds or accelerations exceed the
stated limits (:class:`SafetyLimits`), or whose joint torques -- the inverse dynamics of the
arm with its stated payload along the motion -- exceed the joints' rated torques. Speeds and
accelerations are checked on the motion the controller executes, planned by
:mod:`dqlab.ur.motion` -- its peaks, not its averages: ``movej(t=1)`` over 3 rad peaks at
6 rad/s, not 3; torques on the same motion sampled every servo period and on either side of
every change of acceleration (:meth:`dqlab.ur.motion.Motion.samples`). Each refusal is an
:class:`UnsafeTargetError` (a ``ValueError``) that names the command, the target and the
reason; an argument of the wrong type is a ``TypeError`` that names it. These checks are the
client's first line of defence; the controller's own safety system (joint and TCP limits set
on the teach pendant) remains the last.

:func:`plan_program` checks a whole program as a controller would run it from the arm's
state -- every line, and the changes of speed between them -- and returns its motions; the
kinematic arm and the MuJoCo back end execute nothing else.

Numbers are written with 17 significant digits (Python's ``repr``), so the controller
receives exactly the float that was checked.
"""

import keyword
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from .._checks import as_float_array, check_scalar, real_array, short_repr
from ..dynamics import NewtonEuler, inverse_dynamics, link_inertias, with_payload
from ..models import UR_MAX_JOINT_SPEED_DEG, UR_MAX_JOINT_TORQUE
from . import motion
from ._args import real_number
from .motion import GAIN, LOOKAHEAD_TIME, MOVEJ_A, MOVEJ_V, MOVEL_A, MOVEL_V, SERVOJ_T, STOPJ_A
from .poses import check_pose, transform_from_pose

__all__ = [
    "UR3_JOINT_LIMITS", "UR3_MAX_JOINT_SPEED", "UR3_MAX_JOINT_TORQUE", "TORQUE_SAMPLE_PERIOD",
    "SafetyLimits",
    "UnsafeTargetError",
    "as_safety_limits", "check_joint_targets", "check_motion", "movej", "movel", "servoj",
    "stopj", "program_from_trajectory", "check_trajectory", "plan_command", "plan_program",
    "urscript_list", "urscript_pose", "URSCRIPT_KEYWORDS",
]

#: UR3 joint ranges, rad: +-360 degrees on joints 1-5; wrist 3 turns without limit.
UR3_JOINT_LIMITS = np.array([[-2 * np.pi, 2 * np.pi]] * 5 + [[-np.inf, np.inf]])

#: UR3 maximum joint speeds, rad/s: 180 deg/s (base, shoulder, elbow), 360 deg/s (wrists),
#: :data:`dqlab.models.UR_MAX_JOINT_SPEED_DEG`.
UR3_MAX_JOINT_SPEED = np.radians(UR_MAX_JOINT_SPEED_DEG["UR3"])

#: UR3 rated joint torques, N m: 56 (base, shoulder), 28 (elbow), 12 (wrists),
#: :data:`dqlab.models.UR_MAX_JOINT_TORQUE`.
UR3_MAX_JOINT_TORQUE = np.array(UR_MAX_JOINT_TORQUE["UR3"])

#: Longest step between two samples of a planned motion whose torques are checked, s: the
#: servo period (:meth:`dqlab.ur.motion.Motion.samples`).
TORQUE_SAMPLE_PERIOD = SERVOJ_T

#: A motion longer than 160 s is sampled for its torques in this many steps, not every servo
#: period: between samples a joint moves by at most 1/20,000 of its travel (0.6 mrad of 4 pi).
_MAX_TORQUE_SAMPLES = 20_000

#: Fewer samples than this are checked one state at a time (:class:`dqlab.dynamics.NewtonEuler`),
#: more in one batch (:func:`dqlab.dynamics.inverse_dynamics`): the batch costs a fixed few
#: milliseconds, one state some 35 microseconds (the tests check that both give the same).
_BATCH_FROM = 256

#: Relative allowance for rounding when a speed or acceleration is compared with its limit
#: (a motion planned exactly at a limit is not refused for a rounding of its last digit).
ROUNDING = 1e-12

LOOKAHEAD_RANGE = (0.03, 0.2)
GAIN_RANGE = (100.0, 2000.0)

#: Words a URScript program may not be named (the language's keywords and Python's, whose
#: syntax URScript follows).
URSCRIPT_KEYWORDS = frozenset(keyword.kwlist) | {
    "def", "end", "thread", "run", "join", "kill", "halt", "sec", "local", "enter_critical",
    "exit_critical", "True", "False"}


class UnsafeTargetError(ValueError):
    """A target refused by the safety checks (the message says which and why)."""


@dataclass(frozen=True, eq=False)
class SafetyLimits:
    """The limits every target is checked against before any text reaches a controller.

    Attributes
    ----------
    joint_limits : ndarray, shape (6, 2)
        Lowest and highest joint position, rad (default: the UR3's,
        :data:`UR3_JOINT_LIMITS`).
    max_joint_speed : ndarray, shape (6,)
        rad/s (default: the UR3's rated speeds, :data:`UR3_MAX_JOINT_SPEED`).
    max_joint_acceleration : float
        rad/s^2 (default 10: a conservative teaching-lab value; URScript's default ``a`` is
        1.4).
    max_joint_step : float
        Largest change of any joint between successive targets, rad (default pi: a joint
        asked to turn more than half a turn in one move could reach the same angle the short
        way, so such a target is almost always a wrong IK branch).
    max_tcp_speed : float
        m/s (default 1.0).
    max_tcp_acceleration : float
        m/s^2 (default 5.0).
    robot : dqlab.robot.Robot, optional
        The arm these limits are for: poses are checked for reach and TCP speeds computed
        with it (:meth:`for_robot` sets it).
    max_joint_torque : ndarray, shape (6,), optional
        The joints' rated torques, N m (:meth:`for_robot` sets those of the model,
        :data:`dqlab.models.UR_MAX_JOINT_TORQUE`). With them, every motion's joint torques
        -- :func:`dqlab.dynamics.inverse_dynamics` of ``robot`` carrying ``payload`` along
        the motion -- must stay within them at every sample; ``robot`` must then be given and
        carry inertias. None (the default of a bare ``SafetyLimits()``): torques are not
        checked.
    payload : float
        The payload the arm carries, kg (default 0), as URScript's ``set_payload``.
    payload_cog : array_like, shape (3,)
        Its centre of gravity in the flange frame, m (default the flange's centre;
        :func:`dqlab.dynamics.with_payload`).

    Notes
    -----
    The torques are those of ``robot`` as it is when the limits are made (its base sets the
    direction of gravity); a later change to its base is not seen.
    """

    joint_limits: np.ndarray = field(default_factory=lambda: UR3_JOINT_LIMITS.copy())
    max_joint_speed: np.ndarray = field(default_factory=lambda: UR3_MAX_JOINT_SPEED.copy())
    max_joint_acceleration: float = 10.0
    max_joint_step: float = np.pi
    max_tcp_speed: float = 1.0
    max_tcp_acceleration: float = 5.0
    robot: object = None
    max_joint_torque: np.ndarray = None
    payload: float = 0.0
    payload_cog: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        lim = real_array(self.joint_limits, "joint_limits")
        if lim.ndim != 2 or lim.shape[1] != 2:
            raise ValueError(f"joint_limits must have shape (n, 2), rows (lo, hi), got shape "
                             f"{lim.shape}")
        wrong = np.flatnonzero(~(lim[:, 0] <= lim[:, 1]))          # NaN included
        if wrong.size:
            j = int(wrong[0])
            raise ValueError(f"joint_limits must be rows (lo, hi) with lo <= hi: joint {j + 1} "
                             f"has {short_repr(lim[j].tolist())}")
        speed = _per_joint(self.max_joint_speed, "max_joint_speed", len(lim))
        for key in ("max_joint_acceleration", "max_joint_step", "max_tcp_speed",
                    "max_tcp_acceleration"):
            object.__setattr__(self, key, check_scalar(getattr(self, key), key, minimum=0.0,
                                                       strict=True))
        if self.robot is not None and getattr(self.robot, "n", None) != len(lim):
            raise ValueError(f"robot must be a Robot with {len(lim)} joints, got "
                             f"{type(self.robot).__name__}")
        payload = check_scalar(self.payload, "payload", minimum=0.0)
        cog = as_float_array(self.payload_cog, "payload_cog", (3,))
        if cog.shape != (3,):
            raise ValueError(f"payload_cog must be one point (3,), got shape {cog.shape}")
        torque, loaded = self.max_joint_torque, None
        if torque is not None:
            torque = _per_joint(torque, "max_joint_torque", len(lim))
            if self.robot is None:
                raise ValueError("max_joint_torque needs robot=: the torques are the robot's "
                                 "inverse dynamics (SafetyLimits.for_robot(robot) gives both)")
            try:
                link_inertias(self.robot)
            except (TypeError, ValueError) as exc:
                raise ValueError(f"max_joint_torque: the torque check needs the robot's "
                                 f"inertias: {exc}") from None
            try:
                loaded = with_payload(self.robot, payload, cog)
            except ValueError as exc:
                raise ValueError(f"payload, payload_cog: {exc}") from None
        elif payload or cog.any():
            raise ValueError("payload and payload_cog are only used by the torque check: "
                             "give max_joint_torque too (SafetyLimits.for_robot fills it)")
        object.__setattr__(self, "joint_limits", lim.copy())
        object.__setattr__(self, "max_joint_speed", speed)
        object.__setattr__(self, "max_joint_torque", torque)
        object.__setattr__(self, "payload", payload)
        object.__setattr__(self, "payload_cog", cog.copy())
        object.__setattr__(self, "_loaded", loaded)      # the robot carrying the payload

    @property
    def checks_torques(self):
        """Whether motions are checked against ``max_joint_torque``."""
        return self.max_joint_torque is not None

    @cached_property
    def _newton_euler(self):
        return NewtonEuler(self._loaded)

    def joint_torques(self, q, qd, qdd):
        r"""The torques the joints of ``robot`` carrying ``payload`` need at the states
        ``(q, qd, qdd)``: :math:`\tau = M(q)\ddot q + c(q, \dot q) + g(q)`
        (:func:`dqlab.dynamics.inverse_dynamics`), what the checks compare with
        ``max_joint_torque``.

        Parameters
        ----------
        q, qd, qdd : array_like, shape (N, n)

        Returns
        -------
        ndarray, shape (N, n)
            N m. From 256 states on in one batch, below one state at a time
            (:class:`dqlab.dynamics.NewtonEuler`, faster for a few; the same numbers).

        Raises
        ------
        ValueError
            If these limits check no torques (``max_joint_torque`` is None), or a state is
            not finite (the message names it).

        Examples
        --------
        >>> from dqlab.models import ur3
        >>> limits = SafetyLimits.for_robot(ur3(), payload=3.0)
        >>> q = [[0.0, 0.0, 0.0, 0.0, 0.0, 0.0]]          # stretched out, at rest
        >>> limits.joint_torques(q, np.zeros((1, 6)), np.zeros((1, 6))).round(2) + 0.0
        array([[  0.  , -31.03, -12.37,   0.  ,   0.  ,   0.  ]])
        """
        if not self.checks_torques:
            raise ValueError("these limits check no torques (max_joint_torque is None)")
        n = len(self.joint_limits)
        q, qd, qdd = (np.ascontiguousarray(real_array(x, name), dtype=float)
                      for x, name in ((q, "q"), (qd, "qd"), (qdd, "qdd")))
        for x, name in ((q, "q"), (qd, "qd"), (qdd, "qdd")):
            if x.ndim != 2 or x.shape[1] != n or x.shape != q.shape:
                raise ValueError(f"{name} must have shape (N, {n}) like q, got {x.shape}")
        try:
            if len(q) >= _BATCH_FROM:
                return inverse_dynamics(self._loaded, q, qd, qdd)
            rnea = self._newton_euler
            return np.array([rnea(q[k], qd[k], qdd[k]) for k in range(len(q))]).reshape(q.shape)
        except ValueError as exc:
            raise ValueError(f"q, qd, qdd: {exc}") from None

    @classmethod
    def for_robot(cls, robot, **overrides):
        """The limits of ``robot``: its joint limits, rated joint speeds and torques (the
        links' ``max_speed`` and ``max_torque``), other values default or given
        (``payload=``, ``payload_cog=``, ...).

        Raises
        ------
        ValueError
            If a joint of the robot has no rated speed and ``max_joint_speed`` is not given,
            or only some joints have a rated torque and ``max_joint_torque`` is not given
            (when none has one, torques are not checked).

        Examples
        --------
        >>> from dqlab.models import ur5
        >>> limits = SafetyLimits.for_robot(ur5(), payload=2.0)
        >>> limits.max_joint_speed.round(4)
        array([3.1416, 3.1416, 3.1416, 3.1416, 3.1416, 3.1416])
        >>> limits.max_joint_torque, limits.payload
        (array([150., 150., 150.,  28.,  28.,  28.]), 2.0)
        """
        links = getattr(robot, "links", None)
        if links is None:
            raise TypeError(f"robot must be a dqlab.robot.Robot, got {type(robot).__name__}")
        if "max_joint_speed" not in overrides:
            speeds = [link.max_speed for link in links]
            missing = [i + 1 for i, s in enumerate(speeds) if s is None]
            if missing:
                raise ValueError(
                    f"the {robot.name or 'robot'} has no rated speed for joints {missing} "
                    "(Link.max_speed): give max_joint_speed= explicitly")
            overrides["max_joint_speed"] = np.array(speeds)
        if "max_joint_torque" not in overrides:
            torques = [getattr(link, "max_torque", None) for link in links]
            missing = [i + 1 for i, t in enumerate(torques) if t is None]
            if missing and len(missing) < len(torques):
                raise ValueError(
                    f"the {robot.name or 'robot'} has no rated torque for joints {missing} "
                    "(Link.max_torque): give max_joint_torque= explicitly")
            overrides["max_joint_torque"] = None if missing else np.array(torques)
        overrides.setdefault("joint_limits", robot.limits)
        return cls(robot=robot, **overrides)


def _per_joint(value, name, n):
    """One positive finite number per joint (a scalar is broadcast), a new array."""
    a = real_array(value, name)
    try:
        a = np.broadcast_to(a, (n,))
    except ValueError:
        raise ValueError(f"{name} must have {n} values (one per joint), got shape "
                         f"{a.shape}") from None
    wrong = np.flatnonzero(~((a > 0) & np.isfinite(a)))
    if wrong.size:
        j = int(wrong[0])
        raise ValueError(f"{name} must be positive and finite, got {float(a[j])!r} for joint "
                         f"{j + 1}")
    return a.copy()


def as_safety_limits(limits, robot=None):
    """``limits`` as :class:`SafetyLimits`.

    ``None``: the limits of ``robot`` (:meth:`SafetyLimits.for_robot`), or without a robot the
    UR3's (:class:`SafetyLimits` with :func:`dqlab.models.ur3` as its robot and its rated
    torques, :data:`UR3_MAX_JOINT_TORQUE`); a
    ``SafetyLimits`` as it is (with ``robot`` if it has none); joint limits of shape (n, 2)
    such as ``robot.limits``: those, with the other limits of ``robot`` (or the UR3's
    defaults).

    Examples
    --------
    >>> from dqlab.models import ur5
    >>> as_safety_limits(ur5().limits).joint_limits[5]
    array([-6.28318531,  6.28318531])
    """
    if isinstance(limits, SafetyLimits):
        return limits if robot is None or limits.robot is not None else replace(limits,
                                                                               robot=robot)
    if limits is None:
        if robot is None:
            from ..models import ur3

            return SafetyLimits(robot=ur3(), max_joint_torque=UR3_MAX_JOINT_TORQUE)
        return SafetyLimits.for_robot(robot)
    if robot is None:
        return SafetyLimits(joint_limits=limits)
    return SafetyLimits.for_robot(robot, joint_limits=limits)


def _fmt(x):
    return repr(float(x) + 0.0)  # + 0.0: no "-0.0"


def urscript_list(q):
    """A joint vector as URScript writes it: ``[q1, q2, ...]``.

    Raises
    ------
    UnsafeTargetError
        For NaN or infinity (URScript has no such number: it would not reach a controller
        as the number meant).

    Examples
    --------
    >>> urscript_list([0, -1.5707963267948966, 0.5])
    '[0.0, -1.5707963267948966, 0.5]'
    >>> urscript_list([float("nan")] * 6)
    Traceback (most recent call last):
    ...
    dqlab.ur.script.UnsafeTargetError: q holds nan at index 0: URScript has no such number
    """
    values = real_array(q, "q").ravel()
    bad = ~np.isfinite(values)
    if bad.any():
        k = int(np.argmax(bad))
        raise UnsafeTargetError(f"q holds {float(values[k])!r} at index {k}: URScript has no such "
                                "number")
    return "[" + ", ".join(_fmt(x) for x in values) + "]"


def urscript_pose(p):
    """A UR pose vector as URScript writes it: ``p[x, y, z, rx, ry, rz]``.

    Examples
    --------
    >>> urscript_pose([0.2, 0, 0.3, 0, 3.14, 0])
    'p[0.2, 0.0, 0.3, 0.0, 3.14, 0.0]'
    """
    return "p" + urscript_list(check_pose(p))


def _number(value, name, command):
    """``value`` as a float, or ``TypeError`` naming the argument for anything but a real
    number (text, bool, complex, None, arrays)."""
    return real_number(value, f"{command}: {name}")


def _scalar(value, name, command, *, lo=0.0, hi=np.inf, lo_open=False):
    x = _number(value, name, command)
    if not np.isfinite(x) or x < lo or (lo_open and x == lo) or x > hi:
        low = f"> {lo:g}" if lo_open else f">= {lo:g}"
        rng = f"{low} and <= {hi:g}" if np.isfinite(hi) else low
        raise UnsafeTargetError(f"{command}: {name} = {x!r} refused: must be {rng}")
    return x


def _joint_array(q, name, command):
    """``q`` as a real float array: ``TypeError`` naming it for text, complex, None."""
    try:
        return real_array(q, f"{command}: {name}")
    except ValueError as exc:
        raise UnsafeTargetError(str(exc)) from None


def check_joint_targets(q, *, limits=None, q_from=None, command="movej", times=None,
                        at_rest=False):
    r"""Check joint targets; return them as a float array (the checks of every command).

    Refused: a wrong shape, NaN, infinity or complex numbers, a joint outside
    ``limits.joint_limits``, a change of any joint larger than ``limits.max_joint_step``
    between successive targets (and from ``q_from`` to the first), and -- when ``times`` are
    given -- a joint speed :math:`v_k = \Delta q_k / \Delta t_k` above
    ``limits.max_joint_speed`` or an acceleration
    :math:`(v_{k+1} - v_k) / \tfrac12(\Delta t_k + \Delta t_{k+1})` above
    ``limits.max_joint_acceleration``; with ``at_rest`` the arm is at rest before the first
    target and after the last (a speed of 0 over one more step of the same length at each
    end, so the first speed :math:`v_1` needs :math:`v_1 / \Delta t_1` of acceleration).

    Parameters
    ----------
    q : array_like, shape (6,) or (N, 6)
        Joint targets, rad.
    limits : SafetyLimits or array_like of shape (6, 2), optional
        Default: the UR3's (:class:`SafetyLimits`); joint limits alone (e.g. ``robot.limits``)
        replace only the joint ranges.
    q_from : array_like, shape (6,), optional
        Where the arm is before the first target.
    command : str
        Named in the messages.
    times : array_like, shape (N,), optional
        Times of the targets, s (strictly increasing).
    at_rest : bool
        The samples start and end at rest (a trajectory played by ``servoj`` from a
        standstill to a standstill).

    Returns
    -------
    ndarray, shape (6,) or (N, 6)

    Raises
    ------
    UnsafeTargetError
        Naming the target (its index when ``q`` holds several), the joint and the reason.
    TypeError
        For text, complex numbers or None.

    Examples
    --------
    >>> import numpy as np
    >>> check_joint_targets([0, -1.57, 0, -1.57, 0, 7.0])      # wrist 3 turns freely
    array([ 0.  , -1.57,  0.  , -1.57,  0.  ,  7.  ])
    >>> check_joint_targets([7.0, 0, 0, 0, 0, 0])
    Traceback (most recent call last):
    ...
    dqlab.ur.script.UnsafeTargetError: movej target: joint 1 = 7 rad is outside its limits ...
    """
    limits = as_safety_limits(limits)
    n = len(limits.joint_limits)
    arr = _joint_array(q, "the joint target", command)
    single = arr.ndim == 1
    targets = arr[None, :] if single else arr
    if targets.ndim != 2 or targets.shape[1] != n or targets.shape[0] == 0:
        raise UnsafeTargetError(f"{command}: a joint target must have {n} values, got shape "
                                f"{arr.shape}")

    def where(k):
        return f"{command} target" if single else f"{command} target {k}"

    bad = ~np.isfinite(targets)
    if bad.any():
        k, j = np.argwhere(bad)[0]
        raise UnsafeTargetError(f"{where(k)}: joint {j + 1} is {float(targets[k, j])!r}, "
                                "not a finite number")
    lo, hi = limits.joint_limits[:, 0], limits.joint_limits[:, 1]
    out = (targets < lo) | (targets > hi)
    if out.any():
        k, j = np.argwhere(out)[0]
        raise UnsafeTargetError(f"{where(k)}: joint {j + 1} = {targets[k, j]:.6g} rad is "
                                f"outside its limits [{lo[j]:.6g}, {hi[j]:.6g}] rad")
    path = targets
    offset = 0
    if q_from is not None:
        start = _joint_array(q_from, "q_from", command)
        if start.shape != (n,) or not np.all(np.isfinite(start)):
            raise UnsafeTargetError(f"{command}: q_from (where the arm is) must be {n} finite "
                                    f"numbers, got {start.tolist()}")
        if not np.all((start >= lo) & (start <= hi)):
            j = int(np.argmax(~((start >= lo) & (start <= hi))))
            raise UnsafeTargetError(f"{command}: q_from (where the arm is) has joint {j + 1} = "
                                    f"{start[j]:.6g} rad, outside its limits [{lo[j]:.6g}, "
                                    f"{hi[j]:.6g}] rad")
        path = np.concatenate([start[None], targets])
        offset = 1
    steps = np.abs(np.diff(path, axis=0))
    jump = ~(steps <= limits.max_joint_step)
    if jump.any():
        k, j = np.argwhere(jump)[0]
        frm = "the current position" if (offset and k == 0) else f"target {k - offset}"
        raise UnsafeTargetError(
            f"{where(k + 1 - offset)}: joint {j + 1} would jump by {steps[k, j]:.6g} rad from "
            f"{frm}, more than max_joint_step = {limits.max_joint_step:.6g} rad "
            "(another IK branch?)")
    if times is not None:
        _check_sample_rates(targets, times, limits, where, at_rest, command)
    return targets[0].copy() if single else targets.copy()


def _check_sample_rates(targets, times, limits, where, at_rest, command):
    t = _joint_array(times, "times", command)
    if t.shape != (len(targets),) or not np.all(np.isfinite(t)):
        raise UnsafeTargetError(f"{command}: times must be {len(targets)} finite numbers, "
                                f"got shape {t.shape}")
    dt = np.diff(t)
    if np.any(dt <= 0):
        k = int(np.argmax(dt <= 0)) + 1
        raise UnsafeTargetError(f"{where(k)}: time {float(t[k])!r} s does not increase")
    qd = np.diff(targets, axis=0) / dt[:, None]
    fast = ~(np.abs(qd) <= limits.max_joint_speed * (1.0 + ROUNDING))
    if fast.any():
        k, j = np.argwhere(fast)[0]
        raise UnsafeTargetError(
            f"{where(k + 1)} (t = {t[k + 1]:.6g} s): joint {j + 1} speed "
            f"{abs(qd[k, j]):.6g} rad/s exceeds {limits.max_joint_speed[j]:.6g} rad/s")
    if at_rest and len(dt):
        zero = np.zeros((1, targets.shape[1]))
        qd = np.concatenate([zero, qd, zero])
        dt = np.concatenate([dt[:1], dt, dt[-1:]])
        first = 0
    else:
        first = 1
    if len(qd) > 1:
        qdd = np.abs(np.diff(qd, axis=0)) / (0.5 * (dt[1:] + dt[:-1]))[:, None]
        hard = ~(qdd <= limits.max_joint_acceleration * (1.0 + ROUNDING))
        if hard.any():
            k, j = np.argwhere(hard)[0]
            k = k + first                   # the sample where the speed changes
            rest = (" (from rest)" if k == 0 else " (to rest)" if k == len(targets) - 1
                    else "") if at_rest else ""
            raise UnsafeTargetError(
                f"{where(k)} (t = {t[k]:.6g} s): joint {j + 1} acceleration "
                f"{qdd[k - first, j]:.6g} rad/s^2{rest} exceeds "
                f"{limits.max_joint_acceleration:.6g} rad/s^2")


def _robot_for(robot, limits, command):
    """The robot whose reach and TCP are checked: ``robot``, or the limits' robot."""
    robot = robot if robot is not None else limits.robot
    if robot is None:
        raise ValueError(f"{command}: which robot? Give robot= or limits="
                         "SafetyLimits.for_robot(robot) (poses are checked for its reach)")
    if not hasattr(robot, "fk") or getattr(robot, "n", None) != len(limits.joint_limits):
        raise TypeError(f"{command}: robot must be a dqlab.robot.Robot with "
                        f"{len(limits.joint_limits)} joints, got {type(robot).__name__}")
    return robot


def check_motion(m, limits, command="movej", t=0.0):
    r"""Check a planned :class:`~dqlab.ur.motion.Motion` against ``limits``: the joints stay
    within their limits all along, and the peaks of its joint speeds and accelerations
    (and, for ``movel``, of the TCP's speed and acceleration) stay within the limits; with
    rated torques (``limits.max_joint_torque``), the joint torques
    :math:`\tau = M(q)\ddot q + c(q, \dot q) + g(q)` of ``limits.robot`` carrying
    ``limits.payload``, at every sample of :meth:`~dqlab.ur.motion.Motion.samples` (every
    servo period, :data:`TORQUE_SAMPLE_PERIOD` -- in 20,000 steps for a motion longer than
    160 s -- and either side of every change of acceleration), stay within them.

    Raises
    ------
    UnsafeTargetError
        Naming the command, the joint and the peak (for a torque, when it comes).

    Examples
    --------
    >>> from dqlab.ur.motion import plan_movej
    >>> check_motion(plan_movej([0.0] * 6, [3.0, 0, 0, 0, 0, 0], t=1.0), SafetyLimits())
    Traceback (most recent call last):
    ...
    dqlab.ur.script.UnsafeTargetError: movej: joint 1 speed 6 rad/s exceeds 3.14159 rad/s ...
    """
    _check_motion(m, limits, command, t)


def _check_motion(m, limits, command, t, torques=None):
    """:func:`check_motion`; its torques now, or collected in ``torques``."""
    lo, hi = m.joint_range()
    below, above = ~(lo >= limits.joint_limits[:, 0]), ~(hi <= limits.joint_limits[:, 1])
    if below.any() or above.any():
        j = int(np.argmax(below | above))
        value = lo[j] if below[j] else hi[j]
        raise UnsafeTargetError(
            f"{command}: joint {j + 1} would reach {value:.6g} rad on the way, outside its "
            f"limits [{limits.joint_limits[j, 0]:.6g}, {limits.joint_limits[j, 1]:.6g}] rad")
    why = f" (with t = {t:.6g} s)" if t > 0 else (
        f" (the motion lasts {m.duration:.6g} s)" if m.duration else "")
    speed = m.peak_joint_speed()
    fast = ~(speed <= limits.max_joint_speed * (1.0 + ROUNDING))
    if fast.any():
        j = int(np.argmax(fast))
        raise UnsafeTargetError(f"{command}: joint {j + 1} speed {speed[j]:.6g} rad/s exceeds "
                                f"{limits.max_joint_speed[j]:.6g} rad/s at its peak{why}")
    acc = m.peak_joint_acceleration()
    hard = ~(acc <= limits.max_joint_acceleration * (1.0 + ROUNDING))
    if hard.any():
        j = int(np.argmax(hard))
        raise UnsafeTargetError(
            f"{command}: joint {j + 1} acceleration {acc[j]:.6g} rad/s^2 exceeds "
            f"{limits.max_joint_acceleration:.6g} rad/s^2 at its peak{why}")
    if m.tcp_unit == "m" and not m.tcp_peak_speed <= limits.max_tcp_speed * (1.0 + ROUNDING):
        raise UnsafeTargetError(f"{command}: TCP speed {m.tcp_peak_speed:.6g} m/s exceeds "
                                f"max_tcp_speed = {limits.max_tcp_speed:.6g} m/s{why}")
    if m.tcp_unit == "m" and \
            not m.tcp_peak_acceleration <= limits.max_tcp_acceleration * (1.0 + ROUNDING):
        raise UnsafeTargetError(
            f"{command}: TCP acceleration {m.tcp_peak_acceleration:.6g} m/s^2 exceeds "
            f"max_tcp_acceleration = {limits.max_tcp_acceleration:.6g} m/s^2{why}")
    _motion_torques(m, limits, command, torques)


def _motion_torques(m, limits, command, torques=None):
    """The torque check of a motion's samples: now, or (``torques``, a list) collected for
    one evaluation with the rest of a program."""
    if not limits.checks_torques:
        return
    t_s, q, qd, qdd = m.samples(max(TORQUE_SAMPLE_PERIOD, m.duration / _MAX_TORQUE_SAMPLES))
    block = (q, qd, qdd, lambda k: f"{command} ({t_s[k]:.6g} s into the motion)")
    if torques is None:
        _check_torque_blocks(limits, [block])
    else:
        torques.append(block)


def _check_torques(limits, q, qd, qdd, describe):
    """Refuse the states (N, n) if a joint torque exceeds its rating anywhere (NaN fails):
    the message names the worst joint, its peak torque, the rating and, by ``describe(k)``,
    the command and when its peak comes."""
    _check_torque_blocks(limits, [(q, qd, qdd, describe)])


def _check_torque_blocks(limits, blocks):
    """:func:`_check_torques` of several blocks of states ``(q, qd, qdd, describe)`` (the
    motions of a program and its changes of speed), in one evaluation."""
    if not blocks:
        return
    q, qd, qdd = (np.ascontiguousarray(np.concatenate([b[i] for b in blocks]), dtype=float)
                  for i in range(3))
    sizes = np.cumsum([0] + [len(b[0]) for b in blocks])

    def describe(k):
        i = int(np.searchsorted(sizes, k, side="right")) - 1
        return blocks[i][3](k - sizes[i])

    try:
        tau = limits.joint_torques(q, qd, qdd)
    except ValueError as exc:
        raise UnsafeTargetError(f"{describe(0)}: the joint torques cannot be computed "
                                f"({exc})") from None
    ratio = np.abs(tau) / limits.max_joint_torque
    bad = ~(ratio <= 1.0 + ROUNDING)
    if bad.any():
        k, j = np.unravel_index(int(np.argmax(np.where(bad, np.nan_to_num(ratio, nan=np.inf),
                                                       -1.0))), ratio.shape)
        load = (f" with a payload of {limits.payload:g} kg" if limits.payload
                else " without payload")
        raise UnsafeTargetError(
            f"{describe(k)}: joint {j + 1} torque {abs(tau[k, j]):.4g} N m exceeds its rated "
            f"{limits.max_joint_torque[j]:.4g} N m (the peak of the joint torques{load})")


def _movej_args(a, v, t, r, limits):
    a = _scalar(a, "a", "movej", lo=0.0, hi=limits.max_joint_acceleration, lo_open=True)
    v = _scalar(v, "v", "movej", lo=0.0, hi=float(np.min(limits.max_joint_speed)),
                lo_open=True)
    return a, v, _scalar(t, "t", "movej"), _scalar(r, "r", "movej")


def movej(q, a=MOVEJ_A, v=MOVEJ_V, t=0.0, r=0.0, *, limits=None, q_from=None):
    """The URScript ``movej`` line for a joint target, after the safety checks.

    Parameters
    ----------
    q : array_like, shape (6,)
        Joint target, rad.
    a : float
        Acceleration of the leading joint, rad/s^2 (URScript's default 1.4).
    v : float
        Speed of the leading joint, rad/s (URScript's default 1.05); at most the slowest
        joint's limit (any joint may lead).
    t : float
        Duration, s (0: set by ``a`` and ``v``).
    r : float
        Blend radius, m.
    limits : SafetyLimits or array_like of shape (6, 2), optional
        Default: the UR3's (see :func:`as_safety_limits`).
    q_from : array_like, shape (6,), optional
        The arm's joints before the move: enables the joint-jump check and the check of the
        planned motion's peak speeds and accelerations (:func:`dqlab.ur.motion.plan_movej`),
        which a move with a given ``t`` needs.

    Returns
    -------
    str

    Raises
    ------
    UnsafeTargetError
        For a NaN/inf target, a joint outside the limits, a joint jump, a motion too fast
        for the limits, or ``a``, ``v``, ``t``, ``r`` out of range.
    TypeError
        For a target or an argument that is not made of real numbers.

    Examples
    --------
    >>> import numpy as np
    >>> print(movej([0, -np.pi / 2, 0, -np.pi / 2, 0, 0]))
    movej([0.0, -1.5707963267948966, 0.0, -1.5707963267948966, 0.0, 0.0],
          a=1.4, v=1.05, t=0.0, r=0.0)
    >>> movej([0, 0, 0, 0, 0, float("nan")])
    Traceback (most recent call last):
    ...
    dqlab.ur.script.UnsafeTargetError: movej target: joint 6 is nan, not a finite number
    """
    limits = as_safety_limits(limits)
    a, v, t, r = _movej_args(a, v, t, r, limits)
    q = check_joint_targets(q, limits=limits, q_from=q_from, command="movej")
    if q_from is not None:
        check_motion(_plan(motion.plan_movej, "movej", q_from, q, a, v, t), limits, "movej",
                     t)
    return f"movej({urscript_list(q)}, a={_fmt(a)}, v={_fmt(v)}, t={_fmt(t)}, r={_fmt(r)})"


def _plan(planner, command, *args):
    """A planned motion; the planner's ValueError (an impossible time law) as an
    UnsafeTargetError naming the command."""
    try:
        return planner(*args)
    except ValueError as exc:
        raise UnsafeTargetError(f"{command}: {exc}") from None


def _movel_args(a, v, t, r, limits):
    a = _scalar(a, "a", "movel", lo=0.0, hi=limits.max_tcp_acceleration, lo_open=True)
    v = _scalar(v, "v", "movel", lo=0.0, hi=limits.max_tcp_speed, lo_open=True)
    return a, v, _scalar(t, "t", "movel"), _scalar(r, "r", "movel")


def _movel_target(pose):
    try:
        p = check_pose(pose, "movel target")
    except ValueError as exc:
        raise UnsafeTargetError(str(exc)) from None
    if p.shape != (6,):
        raise UnsafeTargetError(f"movel target must be one pose (6,), got shape {p.shape}")
    try:
        transform_from_pose(p)
    except ValueError as exc:
        raise UnsafeTargetError(f"movel target: {exc}") from None
    return p


def movel(pose, a=MOVEL_A, v=MOVEL_V, t=0.0, r=0.0, *, limits=None, robot=None, q_from=None):
    """The URScript ``movel`` line for a TCP pose, after the safety checks.

    Parameters
    ----------
    pose : array_like, shape (6,)
        The target pose: UR pose vector ``[x, y, z, rx, ry, rz]`` of the TCP in the
        controller's base frame (DH frame 0), m and rad.
    a, v : float
        TCP acceleration (m/s^2, default 1.2) and speed (m/s, default 0.25).
    t, r : float
        Duration (s) and blend radius (m).
    limits : SafetyLimits or array_like of shape (6, 2), optional
        Default: ``robot``'s limits, or the UR3's.
    robot : dqlab.robot.Robot, optional
        The arm whose reach is checked: default ``limits.robot`` (the UR3 when no limits are
        given; with limits that name no robot, ``robot`` must be given). A pose without an
        inverse-kinematics solution is refused.
    q_from : array_like, shape (6,), optional
        The arm's joints before the move: the line's motion is then planned
        (:func:`dqlab.ur.motion.plan_movel`) and checked all along -- reach, joint limits,
        singularities and jumps of the tracked joints, the joints' peak speeds and
        accelerations, the TCP's.

    Returns
    -------
    str

    Examples
    --------
    >>> movel([0.2, -0.1, 0.3, 0.0, 3.1, 0.0])
    'movel(p[0.2, -0.1, 0.3, 0.0, 3.1, 0.0], a=1.2, v=0.25, t=0.0, r=0.0)'
    >>> movel([0.2, -0.1, 3.0, 0.0, 3.1, 0.0])
    Traceback (most recent call last):
    ...
    dqlab.ur.script.UnsafeTargetError: movel target p[0.2, -0.1, 3.0, 0.0, 3.1, 0.0]: out of ...
    """
    limits = as_safety_limits(limits, robot)
    a, v, t, r = _movel_args(a, v, t, r, limits)
    p = _movel_target(pose)
    robot = _robot_for(robot, limits, "movel")
    _check_reach(robot, p)
    if q_from is not None:
        q_from = check_joint_targets(q_from, limits=limits, command="movel (q_from)")
        _plan_movel(robot, q_from, p, a, v, t, limits)
    return f"movel({urscript_pose(p)}, a={_fmt(a)}, v={_fmt(v)}, t={_fmt(t)}, r={_fmt(r)})"


def _check_reach(robot, p):
    from .. import ik

    result = ik.ur(robot, motion.world_transform(robot, p))
    if not bool(result.success):
        raise UnsafeTargetError(f"movel target {urscript_pose(p)}: out of the "
                                f"{robot.name or 'robot'}'s reach (the pose has no IK "
                                f"solution: {result.reason})")


def _plan_movel(robot, q_from, p, a, v, t, limits, torques=None):
    _check_reach(robot, p)
    try:
        m = motion.plan_movel(robot, q_from, p, a, v, t)
    except ValueError as exc:
        raise UnsafeTargetError(f"movel target {urscript_pose(p)}: {exc}") from None
    _check_motion(m, limits, "movel", t, torques)
    return m


def _servoj_args(t, lookahead_time, gain):
    t = _scalar(t, "t", "servoj", lo_open=True)
    lookahead_time = _scalar(lookahead_time, "lookahead_time", "servoj",
                             lo=LOOKAHEAD_RANGE[0], hi=LOOKAHEAD_RANGE[1])
    gain = _scalar(gain, "gain", "servoj", lo=GAIN_RANGE[0], hi=GAIN_RANGE[1])
    return t, lookahead_time, gain


def servoj(q, t=SERVOJ_T, lookahead_time=LOOKAHEAD_TIME, gain=GAIN, *, limits=None,
           q_from=None):
    """The URScript ``servoj`` line for one sample of a joint stream, after the checks.

    Parameters
    ----------
    q : array_like, shape (6,)
        Joint target, rad.
    t : float
        How long this target controls the arm, s (the sample period; > 0).
    lookahead_time : float
        In [0.03, 0.2] s.
    gain : float
        In [100, 2000].
    limits : SafetyLimits or array_like of shape (6, 2), optional
    q_from : array_like, shape (6,), optional
        The previous sample: enables the joint-jump and joint-speed checks. (A single line
        cannot know the speed before it; a stream's changes of speed are checked over the
        whole stream, by :func:`check_joint_targets` with ``times``.)

    Returns
    -------
    str

    Examples
    --------
    >>> servoj([0, -1.5, 0, -1.5, 0, 0], t=0.008)
    'servoj([0.0, -1.5, 0.0, -1.5, 0.0, 0.0], t=0.008, lookahead_time=0.1, gain=300.0)'
    >>> servoj([0, -1.5, 0, -1.5, 0, 0], lookahead_time=0.5)
    Traceback (most recent call last):
    ...
    dqlab.ur.script.UnsafeTargetError: servoj: lookahead_time = 0.5 refused: must be >= 0.03 ...
    """
    limits = as_safety_limits(limits)
    t, lookahead_time, gain = _servoj_args(t, lookahead_time, gain)
    q = check_joint_targets(q, limits=limits, q_from=q_from, command="servoj")
    if q_from is not None:
        check_motion(_plan(motion.plan_servoj, "servoj", q_from, q, t), limits, "servoj", t)
    return (f"servoj({urscript_list(q)}, t={_fmt(t)}, lookahead_time={_fmt(lookahead_time)}, "
            f"gain={_fmt(gain)})")


def stopj(a=STOPJ_A, *, limits=None):
    """The URScript ``stopj`` line: decelerate the joints at ``a`` rad/s^2 to rest.

    ``a`` must be positive and at most ``limits.max_joint_acceleration``.

    Examples
    --------
    >>> stopj()
    'stopj(2.0)'
    """
    limits = as_safety_limits(limits)
    return f"stopj({_fmt(_stopj_arg(a, limits))})"


def _stopj_arg(a, limits):
    return _scalar(a, "a", "stopj", lo_open=True, hi=limits.max_joint_acceleration)


def _program_name(name):
    if not (isinstance(name, str) and name.isidentifier()) or name in URSCRIPT_KEYWORDS:
        raise ValueError(f"name must be a URScript identifier that is not a keyword, got "
                         f"{name!r}")
    return name


def program_from_trajectory(trajectory, *, name="dqlab_trajectory", a=MOVEJ_A, v=MOVEJ_V,
                            lookahead_time=LOOKAHEAD_TIME, gain=GAIN, limits=None,
                            q_from=None, robot=None):
    r"""A URScript program (``def ... end``) that plays a joint trajectory with ``servoj``.

    The program moves to the first sample with ``movej`` (at ``a``, ``v``), then sends one
    ``servoj`` per following sample, each controlling the arm for the time to that sample,
    and ends with ``stopj``. The whole program is checked first, as the controller will run
    it: every sample finite, within the joint limits, joint steps at most
    ``max_joint_step``; joint speeds and accelerations (finite differences) within the
    limits, **from the rest where the approach ``movej`` leaves the arm and to the rest at
    the end** (:func:`check_joint_targets` with ``at_rest``); the TCP's speed between
    samples (of the ``robot``'s forward kinematics) within ``max_tcp_speed``; the joint
    torques with the stated payload within the rated ones (:func:`check_trajectory`); and,
    with ``q_from``, the approach ``movej``'s motion. The whole program is refused if one
    sample fails.

    Parameters
    ----------
    trajectory : object with arrays ``t`` (N,) and ``q`` (N, 6)
        For example a ``dqlab.trajectory.Trajectory`` (its ``qd`` and ``qdd`` are not
        needed), or any object with those two attributes. Times in s, strictly increasing;
        joints in rad.
    name : str
        The program's name (a URScript identifier, not a keyword).
    a, v : float
        Acceleration and speed of the approach ``movej``.
    lookahead_time, gain : float
        Of every ``servoj``.
    limits : SafetyLimits or array_like of shape (6, 2), optional
        Default: ``robot``'s limits, or the UR3's.
    q_from : array_like, shape (6,), optional
        The arm's joints now (checks the approach for a joint jump and its motion).
    robot : dqlab.robot.Robot, optional
        The arm whose TCP speed is checked (default ``limits.robot``; see :func:`movel`).

    Returns
    -------
    str
        The program text, ending with a newline.

    Raises
    ------
    UnsafeTargetError
        Naming the first sample that fails and why.
    TypeError
        If ``trajectory`` lacks ``t`` or ``q``.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> t = np.array([0.0, 0.5, 1.0, 1.5])
    >>> q = np.zeros((4, 6)); q[:, 0] = [0.0, 0.05, 0.15, 0.2]
    >>> print(program_from_trajectory(SimpleNamespace(t=t, q=q)), end="")
    def dqlab_trajectory():
      movej([0.0, 0.0, 0.0, 0.0, 0.0, 0.0], a=1.4, v=1.05, t=0.0, r=0.0)
      servoj([0.05, 0.0, 0.0, 0.0, 0.0, 0.0], t=0.5, lookahead_time=0.1, gain=300.0)
      servoj([0.15, 0.0, 0.0, 0.0, 0.0, 0.0], t=0.5, lookahead_time=0.1, gain=300.0)
      servoj([0.2, 0.0, 0.0, 0.0, 0.0, 0.0], t=0.5, lookahead_time=0.1, gain=300.0)
      stopj(2.0)
    end
    """
    name = _program_name(name)
    limits = as_safety_limits(limits, robot)
    _, lookahead_time, gain = _servoj_args(SERVOJ_T, lookahead_time, gain)
    t, q = check_trajectory(trajectory, limits=limits, robot=robot)
    lines = [f"def {name}():",
             "  " + movej(q[0], a=a, v=v, limits=limits, q_from=q_from)]
    dt = np.diff(t)
    for k in range(1, len(q)):
        lines.append("  " + servoj(q[k], t=dt[k - 1], lookahead_time=lookahead_time,
                                   gain=gain, limits=limits))
    lines += ["  " + stopj(limits=limits), "end"]
    return "\n".join(lines) + "\n"


def check_trajectory(trajectory, *, limits=None, robot=None, command="trajectory"):
    r"""Check a joint trajectory played by ``servoj`` from rest to rest; its times and joints.

    The checks of :func:`program_from_trajectory`: :func:`check_joint_targets` with the
    times and ``at_rest``, the TCP's speed between samples,
    :math:`\lVert p_{k+1} - p_k \rVert / (t_{k+1} - t_k)` with :math:`p` the TCP position of
    the ``robot``'s forward kinematics, within ``max_tcp_speed``, and, with rated torques
    (``limits.max_joint_torque``), the joint torques of ``limits.robot`` carrying
    ``limits.payload`` at every sample, with the acceleration the speed check measures there
    and the speed on either side of it, within them (in one batch of
    :func:`dqlab.dynamics.inverse_dynamics`).

    Parameters
    ----------
    trajectory : object with arrays ``t`` (N,) and ``q`` (N, 6)
    limits : SafetyLimits, optional
    robot : dqlab.robot.Robot, optional
        Default ``limits.robot`` (see :func:`movel`).
    command : str
        Named in the messages.

    Returns
    -------
    t : ndarray, shape (N,)
    q : ndarray, shape (N, 6)

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> t = np.array([0.0, 0.1])
    >>> check_trajectory(SimpleNamespace(t=t, q=np.zeros((2, 6)) + [1.0, 0, 0, 0, 0, 0]))[1][1]
    array([1., 0., 0., 0., 0., 0.])
    >>> check_trajectory(SimpleNamespace(t=t, q=[[0.0] * 6, [0.3, 0, 0, 0, 0, 0]]))
    Traceback (most recent call last):
    ...
    dqlab.ur.script.UnsafeTargetError: trajectory target 0 (t = 0 s): joint 1 acceleration ...
    """
    if not (hasattr(trajectory, "t") and hasattr(trajectory, "q")):
        raise TypeError(f"{command}: the trajectory must have arrays t (N,) and q (N, 6), got "
                        f"{type(trajectory).__name__}")
    limits = as_safety_limits(limits, robot)
    robot = _robot_for(robot, limits, command)
    t = _joint_array(trajectory.t, "t", command)
    q = _joint_array(trajectory.q, "q", command)
    if q.ndim != 2 or len(q) < 1:
        raise UnsafeTargetError(f"{command}: q must have shape (N, 6) with N >= 1, got "
                                f"{q.shape}")
    q = check_joint_targets(q, limits=limits, command=command, times=t, at_rest=True)
    if len(q) > 1:
        p = robot.fk(q)[:, :3, 3]
        speed = np.linalg.norm(np.diff(p, axis=0), axis=-1) / np.diff(t)
        k = int(np.argmax(speed))
        if not speed[k] <= limits.max_tcp_speed * (1.0 + ROUNDING):
            raise UnsafeTargetError(
                f"{command} target {k + 1} (t = {t[k + 1]:.6g} s): TCP speed {speed[k]:.6g} "
                f"m/s exceeds max_tcp_speed = {limits.max_tcp_speed:.6g} m/s")
    if limits.checks_torques:
        _check_sample_torques(t, q, limits, command)
    return t, q


def _check_sample_torques(t, q, limits, command):
    r"""The joint torques of a trajectory played by ``servoj`` from rest to rest, sampled as
    its speeds and accelerations are checked and as :func:`plan_program` checks the program
    that plays it: at each sample :math:`k`, the acceleration
    :math:`a_k = (v_{k+1} - v_k) / \tfrac12(\Delta t_{k-1} + \Delta t_k)` with the speed
    before it and the speed after it (:math:`v_{k+1} = (q_{k+1} - q_k) / \Delta t_k`, 0 before
    the first sample and after the last); between samples, the constant speed without
    acceleration at both ends of the step."""
    n, zero = len(q), np.zeros((1, q.shape[1]))
    if n == 1:
        _check_torques(limits, q, zero, zero, lambda k: f"{command} target 0 (at rest)")
        return
    dt = np.diff(t)
    v = np.diff(q, axis=0) / dt[:, None]
    v_before, v_after = np.concatenate([zero, v]), np.concatenate([v, zero])
    spans = np.concatenate([dt[:1], dt, dt[-1:]])
    a = (v_after - v_before) / (0.5 * (spans[:-1] + spans[1:]))[:, None]
    knot = np.concatenate([np.arange(n), np.arange(n), np.arange(n - 1), np.arange(1, n)])
    _check_torques(limits, q[knot], np.concatenate([v_before, v_after, v, v]),
                   np.concatenate([a, a, np.zeros_like(v), np.zeros_like(v)]),
                   lambda k: f"{command} target {knot[k]} (t = {t[knot[k]]:.6g} s)")


# --------------------------------------------------------------------------------------
# Whole programs, as a controller runs them


def plan_command(name, target, kwargs=None, *, q_from, limits=None, robot=None):
    """Check one motion command as it would run from the joints ``q_from``; its motion.

    The checks of :func:`movej`, :func:`movel`, :func:`servoj` or :func:`stopj` with
    ``q_from`` (a ``stopj`` from ``q_from`` at rest holds there).

    Parameters
    ----------
    name : {"movej", "movel", "servoj", "stopj"}
    target : array_like or None
        Joints (``movej``, ``servoj``), a pose (``movel``), None (``stopj``).
    kwargs : dict, optional
        The command's other arguments by name (``a``, ``v``, ``t``, ``r``,
        ``lookahead_time``, ``gain``; URScript's defaults for the others).
    q_from : array_like, shape (6,)
    limits : SafetyLimits, optional
    robot : dqlab.robot.Robot, optional
        For ``movel`` (default ``limits.robot``).

    Returns
    -------
    Motion

    Examples
    --------
    >>> m = plan_command("movej", [0.5, -1.5, 0, -1.5, 0, 0], {"v": 0.5},
    ...                  q_from=[0, -1.5, 0, -1.5, 0, 0])
    >>> round(m.duration, 6), float(m.peak_joint_speed()[0])
    (1.357143, 0.5)
    """
    return _plan_command(name, target, kwargs, q_from, as_safety_limits(limits, robot), robot)


def _plan_command(name, target, kwargs, q_from, limits, robot, torques=None):
    """:func:`plan_command`; its torque check now, or collected in ``torques`` (a list)."""
    kw = dict(kwargs or {})
    q_from = check_joint_targets(q_from, limits=limits, command=f"{name} (q_from)")

    def take(*names):
        unknown = set(kw) - set(names)
        if unknown:
            raise TypeError(f"{name}: unexpected argument {sorted(unknown)[0]!r}")
        return kw

    if name == "movej":
        kw = take("a", "v", "t", "r")
        a, v, t, _ = _movej_args(kw.get("a", MOVEJ_A), kw.get("v", MOVEJ_V),
                                 kw.get("t", 0.0), kw.get("r", 0.0), limits)
        q = check_joint_targets(target, limits=limits, q_from=q_from, command="movej")
        m = _plan(motion.plan_movej, "movej", q_from, q, a, v, t)
        _check_motion(m, limits, "movej", t, torques)
        return m
    if name == "movel":
        kw = take("a", "v", "t", "r")
        a, v, t, _ = _movel_args(kw.get("a", MOVEL_A), kw.get("v", MOVEL_V),
                                 kw.get("t", 0.0), kw.get("r", 0.0), limits)
        p = _movel_target(target)
        robot = _robot_for(robot, limits, "movel")
        return _plan_movel(robot, q_from, p, a, v, t, limits, torques)
    if name == "servoj":
        kw = take("a", "v", "t", "lookahead_time", "gain")    # a, v: not used by servoj
        t, _, _ = _servoj_args(kw.get("t", SERVOJ_T), kw.get("lookahead_time", LOOKAHEAD_TIME),
                               kw.get("gain", GAIN))
        q = check_joint_targets(target, limits=limits, q_from=q_from, command="servoj")
        m = _plan(motion.plan_servoj, "servoj", q_from, q, t)
        _check_motion(m, limits, "servoj", t, torques)
        return m
    if name == "stopj":
        kw = take("a")
        _stopj_arg(kw.get("a", STOPJ_A), limits)
        return motion.plan_hold(q_from)
    raise ValueError(f"unknown command {name!r}: movej, movel, servoj or stopj")


def plan_program(commands, *, q_now, qd_now=None, limits=None, robot=None, streaming=False):
    r"""Check a whole program as a controller would run it from the arm's state; its motions.

    The motions, one after the other: if the arm is moving (``qd_now`` not zero) a braking
    motion first (every joint along its direction, the fastest at
    ``limits.max_joint_acceleration``, :func:`dqlab.ur.motion.plan_stop`) -- unless the
    program starts with ``servoj``, which takes over from the motion -- then each command
    from where the previous one ends (:func:`plan_command`; a ``stopj`` first in the program
    brakes the arm at its ``a``, after another command it holds: every motion ends at rest, a
    ``servoj`` when its time is up).
    Between them the speed must not jump by more than ``max_joint_acceleration`` times the
    servo period: :math:`|\dot q_{next} - \dot q_{prev}| / T` with :math:`T` the mean period
    of the ``servoj`` on either side (the acceleration of a ``servoj`` stream, as
    :func:`check_joint_targets` measures it), from the arm's speed before the first and to
    rest after the last. With rated torques, the joint torques of every motion
    (:func:`check_motion`) and of every such change of speed (its acceleration with the
    speed before and after it) must stay within them.

    Any failure refuses the whole program; nothing is returned to run.

    Parameters
    ----------
    commands : sequence of (name, target, kwargs)
        As :func:`dqlab.ur.standin.parse_urscript` returns them.
    q_now : array_like, shape (6,)
        The arm's joints.
    qd_now : array_like, shape (6,), optional
        The arm's joint speeds (default: at rest).
    limits : SafetyLimits, optional
    robot : dqlab.robot.Robot, optional
    streaming : bool
        The program is one ``servoj`` line of a stream sent line by line: it takes over from
        the running motion, and its changes of speed are not checked (a line cannot know
        them; the stream's sender checks them over the whole stream).

    Returns
    -------
    list of Motion

    Raises
    ------
    UnsafeTargetError, TypeError
        Naming the line (from 1) and the reason.

    Examples
    --------
    >>> home = [0.0, -1.5, 0.0, -1.5, 0.0, 0.0]
    >>> program = [("movej", [0.2, -1.5, 0.0, -1.5, 0.0, 0.0], {}),
    ...            ("servoj", [0.2004, -1.5, 0.0, -1.5, 0.0, 0.0], {"t": 0.008})]
    >>> [m.command for m in plan_program(program, q_now=home)]
    ['movej', 'servoj']
    >>> program[1] = ("servoj", [0.21, -1.5, 0.0, -1.5, 0.0, 0.0], {"t": 0.008})
    >>> plan_program(program, q_now=home)
    Traceback (most recent call last):
    ...
    dqlab.ur.script.UnsafeTargetError: line 2: the joint speeds jump from the previous motion: ...
    """
    limits = as_safety_limits(limits, robot)
    q = check_joint_targets(q_now, limits=limits, command="the arm's joints (q_now)")
    qd = np.zeros_like(q) if qd_now is None else _joint_array(qd_now, "qd_now", "program")
    if qd.shape != q.shape or not np.all(np.isfinite(qd)):
        raise UnsafeTargetError(f"the arm's joint speeds (qd_now) must be {q.size} finite "
                                f"numbers, got {qd.tolist()}")
    commands = list(commands)
    if not commands:
        raise UnsafeTargetError("the program has no motion command")
    motions = []
    first = commands[0][0] if isinstance(commands[0], (tuple, list)) and commands[0] else None
    if np.any(qd != 0.0) and first in ("movej", "movel"):
        motions.append(motion.plan_stop(q, qd, limits.max_joint_acceleration))
        q, qd = motions[-1].q_end, motions[-1].qd_end
    check_speed_changes = not streaming
    torques = []                    # every line's, checked in one evaluation at the end
    for k, command in enumerate(commands, start=1):
        first_block = len(torques)
        try:
            name, target, kw = command
            if name == "stopj":      # brakes the arm's motion; after a motion, it is at rest
                moving = qd if (k == 1 and not motions and qd is not None) else 0.0 * q
                a = _stopj_arg(dict(kw or {}).get("a", STOPJ_A), limits)
                m = _plan(motion.plan_stop, "stopj", q, moving, a)
            else:
                m = _plan_command(name, target, kw, q, limits, robot, torques)
            if check_speed_changes:
                _check_junction(qd, motions[-1] if motions else None, m, limits, torques)
        except (ValueError, TypeError) as exc:
            raise type(exc)(f"line {k}: {exc}") from None
        _label_line(torques, first_block, k)
        motions.append(m)
        q, qd = m.q_end, m.qd_end
    if check_speed_changes:
        first_block = len(torques)
        try:
            _check_junction(qd, motions[-1], None, limits, torques)
        except UnsafeTargetError as exc:
            raise UnsafeTargetError(f"line {len(commands)}: {exc}") from None
        _label_line(torques, first_block, len(commands))
    _check_torque_blocks(limits, torques)
    return motions


def _label_line(blocks, first, line):
    """Prefix ``line {line}: `` to the descriptions of the blocks from ``first`` on."""
    for i in range(first, len(blocks)):
        q, qd, qdd, describe = blocks[i]
        blocks[i] = (q, qd, qdd, lambda k, describe=describe: f"line {line}: {describe(k)}")


def _check_junction(v0, before, after, limits, torques=None):
    """The speed change from ``v0`` (at the end of ``before``, or the arm's before the
    program) to the start of ``after`` (None: rest after the program); its torques now, or
    collected in ``torques``."""
    v1 = after.qd_start if after is not None else np.zeros_like(v0)
    jump = np.abs(v1 - v0)
    if np.all(jump <= ROUNDING * (1.0 + np.abs(v0) + np.abs(v1))):   # continuous, to rounding
        return
    periods = [m.duration for m in (before, after) if m is not None and m.command == "servoj"]
    period = float(np.mean(periods)) if periods else 0.0
    acc = jump / period if period > 0.0 else np.where(jump > 0.0, np.inf, 0.0)
    hard = ~(acc <= limits.max_joint_acceleration * (1.0 + ROUNDING))
    if hard.any():
        j = int(np.argmax(hard))
        where = "to rest" if after is None else "from the previous motion"
        raise UnsafeTargetError(
            f"the joint speeds jump {where}: joint {j + 1} changes by {jump[j]:.6g} rad/s in "
            f"{period:.6g} s, an acceleration of {acc[j]:.6g} rad/s^2 above "
            f"{limits.max_joint_acceleration:.6g} rad/s^2")
    if limits.checks_torques and period > 0.0:
        # the acceleration of the change, with the speed before and the speed after it
        q = after.q_start if after is not None else before.q_end
        signed = (v1 - v0) / period
        where = "at the change of speed to rest" if after is None else \
            "at the change of speed from the previous motion"
        block = (np.stack([q, q]), np.stack([v0, v1]), np.stack([signed, signed]),
                 lambda k: where)
        if torques is None:
            _check_torque_blocks(limits, [block])
        else:
            torques.append(block)
