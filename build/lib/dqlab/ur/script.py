r"""URScript generation with safety checks: ``movej``, ``movel``, ``servoj`` and programs.

URScript is the language of the UR controller; a client sends it as text. This module writes
the commands with URScript's argument names and units:

``movej(q, a, v, t, r)``
    Move in joint space to ``q`` [rad]; the leading joint accelerates at ``a`` [rad/s^2] up
    to ``v`` [rad/s]; ``t`` [s] (if > 0) sets the duration instead; ``r`` [m] is a blend
    radius.
``movel(pose, a, v, t, r)``
    Move the TCP on a straight line to ``p[x, y, z, rx, ry, rz]`` [m, rad]; ``a`` [m/s^2],
    ``v`` [m/s].
``servoj(q, t, lookahead_time, gain)``
    Track ``q`` for ``t`` [s] (blocking); ``lookahead_time`` in [0.03, 0.2] s smooths,
    ``gain`` in [100, 2000] stiffens.
``stopj(a)``
    Decelerate the joints to rest at ``a`` [rad/s^2].

**Safety.** No text is produced for a target that is NaN or infinite, a joint outside the
robot's limits, a speed or acceleration above the stated limits (:class:`SafetyLimits`), a
pose out of the arm's reach, or a joint jump between successive targets larger than
``max_joint_step``. Each refusal is an :class:`UnsafeTargetError` (a ``ValueError``) that
names the command, the target and the reason. These checks are the client's first line of
defence; the controller's own safety system (joint and TCP limits set on the teach pendant)
remains the last.

Numbers are written with 17 significant digits (Python's ``repr``), so the controller
receives exactly the float that was checked.
"""

from dataclasses import dataclass, field, replace

import numpy as np

from .poses import check_pose, transform_from_pose

__all__ = [
    "UR3_JOINT_LIMITS", "UR3_MAX_JOINT_SPEED", "SafetyLimits", "UnsafeTargetError",
    "as_safety_limits", "check_joint_targets", "movej", "movel", "servoj", "stopj",
    "program_from_trajectory", "urscript_list", "urscript_pose",
]

#: UR3 joint ranges, rad: +-360 degrees on joints 1-5; wrist 3 turns without limit.
UR3_JOINT_LIMITS = np.array([[-2 * np.pi, 2 * np.pi]] * 5 + [[-np.inf, np.inf]])

#: UR3 maximum joint speeds, rad/s: 180 deg/s (base, shoulder, elbow), 360 deg/s (wrists).
UR3_MAX_JOINT_SPEED = np.radians([180.0, 180.0, 180.0, 360.0, 360.0, 360.0])

LOOKAHEAD_RANGE = (0.03, 0.2)
GAIN_RANGE = (100.0, 2000.0)


class UnsafeTargetError(ValueError):
    """A target refused by the safety checks (the message says which and why)."""


@dataclass(frozen=True)
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
    """

    joint_limits: np.ndarray = field(default_factory=lambda: UR3_JOINT_LIMITS.copy())
    max_joint_speed: np.ndarray = field(default_factory=lambda: UR3_MAX_JOINT_SPEED.copy())
    max_joint_acceleration: float = 10.0
    max_joint_step: float = np.pi
    max_tcp_speed: float = 1.0
    max_tcp_acceleration: float = 5.0

    def __post_init__(self):
        lim = np.array(self.joint_limits, dtype=float)
        speed = np.broadcast_to(np.array(self.max_joint_speed, dtype=float), (len(lim),))
        if lim.ndim != 2 or lim.shape[1] != 2 or np.any(np.isnan(lim)) or np.any(
                lim[:, 0] > lim[:, 1]):
            raise ValueError(f"joint_limits must be (n, 2) rows lo <= hi, got {lim!r}")
        if np.any(~(speed > 0)):
            raise ValueError(f"max_joint_speed must be positive, got {speed!r}")
        for key in ("max_joint_acceleration", "max_joint_step", "max_tcp_speed",
                    "max_tcp_acceleration"):
            if not getattr(self, key) > 0:
                raise ValueError(f"{key} must be positive, got {getattr(self, key)!r}")
        object.__setattr__(self, "joint_limits", lim)
        object.__setattr__(self, "max_joint_speed", speed.copy())

    @classmethod
    def for_robot(cls, robot, **overrides):
        """Limits with ``robot.limits`` as joint limits (other values default or given).

        The UR3 of :func:`dqlab.models.ur3` is modelled with +-2 pi on every joint; the real
        UR3's wrist 3 turns without limit (use the default :class:`SafetyLimits` for that).
        """
        return replace(cls(), joint_limits=np.asarray(robot.limits, dtype=float), **overrides)


def as_safety_limits(limits):
    """``limits`` as :class:`SafetyLimits`: ``None`` (the UR3's), a ``SafetyLimits``, or joint
    limits of shape (n, 2) such as ``robot.limits`` (other limits the UR3's defaults).

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> as_safety_limits(ur3().limits).joint_limits[5]
    array([-6.28318531,  6.28318531])
    """
    if limits is None:
        return SafetyLimits()
    if isinstance(limits, SafetyLimits):
        return limits
    return SafetyLimits(joint_limits=np.asarray(limits, dtype=float))


def _fmt(x):
    return repr(float(x) + 0.0)  # + 0.0: no "-0.0"


def urscript_list(q):
    """A joint vector as URScript writes it: ``[q1, q2, ...]``.

    Examples
    --------
    >>> urscript_list([0, -1.5707963267948966, 0.5])
    '[0.0, -1.5707963267948966, 0.5]'
    """
    return "[" + ", ".join(_fmt(x) for x in np.asarray(q, dtype=float)) + "]"


def urscript_pose(p):
    """A UR pose vector as URScript writes it: ``p[x, y, z, rx, ry, rz]``.

    Examples
    --------
    >>> urscript_pose([0.2, 0, 0.3, 0, 3.14, 0])
    'p[0.2, 0.0, 0.3, 0.0, 3.14, 0.0]'
    """
    return "p" + urscript_list(check_pose(p))


def _scalar(value, name, command, *, lo=0.0, hi=np.inf, lo_open=False):
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{command}: {name} must be a number, got {value!r}") from None
    if not np.isfinite(x) or x < lo or (lo_open and x == lo) or x > hi:
        low = f"> {lo:g}" if lo_open else f">= {lo:g}"
        rng = f"{low} and <= {hi:g}" if np.isfinite(hi) else low
        raise UnsafeTargetError(f"{command}: {name} = {x!r} refused: must be {rng}")
    return x


def check_joint_targets(q, *, limits=None, q_from=None, command="movej", times=None):
    r"""Check joint targets; return them as a float array (the checks of every command).

    Refused: a wrong shape, NaN or infinity, a joint outside ``limits.joint_limits``, a
    change of any joint larger than ``limits.max_joint_step`` between successive targets
    (and from ``q_from`` to the first), and -- when ``times`` are given -- a joint speed
    :math:`|\Delta q_i| / \Delta t` above ``limits.max_joint_speed`` or an acceleration
    (second difference) above ``limits.max_joint_acceleration``.

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

    Returns
    -------
    ndarray, shape (6,) or (N, 6)

    Raises
    ------
    UnsafeTargetError
        Naming the target (its index when ``q`` holds several), the joint and the reason.

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
    try:
        arr = np.asarray(q, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{command}: the joint target must be numbers, got {q!r}") from None
    single = arr.ndim == 1
    targets = arr[None, :] if single else arr
    if targets.ndim != 2 or targets.shape[1] != n:
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
        start = np.asarray(q_from, dtype=float).reshape(1, n)
        path = np.concatenate([start, targets])
        offset = 1
    steps = np.abs(np.diff(path, axis=0))
    jump = steps > limits.max_joint_step
    if jump.any():
        k, j = np.argwhere(jump)[0]
        frm = "the current position" if (offset and k == 0) else f"target {k - offset}"
        raise UnsafeTargetError(
            f"{where(k + 1 - offset)}: joint {j + 1} would jump by {steps[k, j]:.6g} rad from "
            f"{frm}, more than max_joint_step = {limits.max_joint_step:.6g} rad "
            "(another IK branch?)")
    if times is not None:
        t = np.asarray(times, dtype=float)
        if t.shape != (len(targets),) or not np.all(np.isfinite(t)):
            raise UnsafeTargetError(f"{command}: times must be {len(targets)} finite numbers")
        dt = np.diff(t)
        if np.any(dt <= 0):
            k = int(np.argmax(dt <= 0)) + 1
            raise UnsafeTargetError(f"{where(k)}: time {float(t[k])!r} s does not increase")
        speed = np.abs(np.diff(targets, axis=0)) / dt[:, None]
        fast = speed > limits.max_joint_speed
        if fast.any():
            k, j = np.argwhere(fast)[0]
            raise UnsafeTargetError(
                f"{where(k + 1)} (t = {t[k + 1]:.6g} s): joint {j + 1} speed "
                f"{speed[k, j]:.6g} rad/s exceeds {limits.max_joint_speed[j]:.6g} rad/s")
        if len(targets) > 2:
            qd = np.diff(targets, axis=0) / dt[:, None]
            qdd = np.abs(np.diff(qd, axis=0)) / (0.5 * (dt[1:] + dt[:-1]))[:, None]
            hard = qdd > limits.max_joint_acceleration
            if hard.any():
                k, j = np.argwhere(hard)[0]
                raise UnsafeTargetError(
                    f"{where(k + 1)} (t = {t[k + 1]:.6g} s): joint {j + 1} acceleration "
                    f"{qdd[k, j]:.6g} rad/s^2 exceeds {limits.max_joint_acceleration:.6g} "
                    "rad/s^2")
    return targets[0].copy() if single else targets.copy()


def movej(q, a=1.4, v=1.05, t=0.0, r=0.0, *, limits=None, q_from=None):
    """The URScript ``movej`` line for a joint target, after the safety checks.

    Parameters
    ----------
    q : array_like, shape (6,)
        Joint target, rad.
    a : float
        Acceleration of the leading joint, rad/s^2 (URScript's default 1.4).
    v : float
        Speed of the leading joint, rad/s (URScript's default 1.05); at most the slowest
        joint's limit.
    t : float
        Duration, s (0: set by ``a`` and ``v``).
    r : float
        Blend radius, m.
    limits : SafetyLimits or array_like of shape (6, 2), optional
        Default: the UR3's (see :func:`as_safety_limits`).
    q_from : array_like, shape (6,), optional
        The arm's joints before the move (enables the joint-jump check, and the speed check
        of a move with a given ``t``).

    Returns
    -------
    str

    Raises
    ------
    UnsafeTargetError
        For a NaN/inf target, a joint outside the limits, a joint jump, or ``a``, ``v``,
        ``t``, ``r`` out of range.

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
    a = _scalar(a, "a", "movej", lo=0.0, hi=limits.max_joint_acceleration, lo_open=True)
    v = _scalar(v, "v", "movej", lo=0.0, hi=float(np.min(limits.max_joint_speed)),
                lo_open=True)
    t = _scalar(t, "t", "movej")
    r = _scalar(r, "r", "movej")
    q = check_joint_targets(q, limits=limits, q_from=q_from, command="movej")
    if t > 0 and q_from is not None:
        check_joint_targets(np.stack([np.asarray(q_from, dtype=float), q]), limits=limits,
                            command="movej", times=[0.0, t])
    return f"movej({urscript_list(q)}, a={_fmt(a)}, v={_fmt(v)}, t={_fmt(t)}, r={_fmt(r)})"


def movel(pose, a=1.2, v=0.25, t=0.0, r=0.0, *, limits=None, robot=None):
    """The URScript ``movel`` line for a TCP pose, after the safety checks.

    Parameters
    ----------
    pose : array_like, shape (6,)
        UR pose vector ``[x, y, z, rx, ry, rz]`` of the TCP in the base frame, m and rad.
    a, v : float
        TCP acceleration (m/s^2, default 1.2) and speed (m/s, default 0.25).
    t, r : float
        Duration (s) and blend radius (m).
    limits : SafetyLimits or array_like of shape (6, 2), optional
    robot : dqlab.robot.Robot, optional
        The arm whose reach is checked (default :func:`dqlab.models.ur3`): a pose without an
        inverse-kinematics solution is refused. (Only the end of the line is checked; the
        controller checks the path.)

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
    from .. import ik, models

    limits = as_safety_limits(limits)
    a = _scalar(a, "a", "movel", lo=0.0, hi=limits.max_tcp_acceleration, lo_open=True)
    v = _scalar(v, "v", "movel", lo=0.0, hi=limits.max_tcp_speed, lo_open=True)
    t = _scalar(t, "t", "movel")
    r = _scalar(r, "r", "movel")
    try:
        p = check_pose(pose, "movel target")
    except ValueError as exc:
        raise UnsafeTargetError(str(exc)) from None
    if p.shape != (6,):
        raise UnsafeTargetError(f"movel target must be one pose (6,), got shape {p.shape}")
    robot = models.ur3() if robot is None else robot
    if not bool(ik.ur(robot, transform_from_pose(p)).success):
        raise UnsafeTargetError(f"movel target {urscript_pose(p)}: out of the "
                                f"{robot.name or 'robot'}'s reach (no inverse-kinematics "
                                "solution)")
    return f"movel({urscript_pose(p)}, a={_fmt(a)}, v={_fmt(v)}, t={_fmt(t)}, r={_fmt(r)})"


def servoj(q, t=0.008, lookahead_time=0.1, gain=300, *, limits=None, q_from=None):
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
        The previous sample: enables the joint-jump and joint-speed checks.

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
    t = _scalar(t, "t", "servoj", lo_open=True)
    lookahead_time = _scalar(lookahead_time, "lookahead_time", "servoj",
                             lo=LOOKAHEAD_RANGE[0], hi=LOOKAHEAD_RANGE[1])
    gain = _scalar(gain, "gain", "servoj", lo=GAIN_RANGE[0], hi=GAIN_RANGE[1])
    q = check_joint_targets(q, limits=limits, q_from=q_from, command="servoj")
    if q_from is not None:
        check_joint_targets(np.stack([np.asarray(q_from, dtype=float), q]), limits=limits,
                            command="servoj", times=[0.0, t])
    return (f"servoj({urscript_list(q)}, t={_fmt(t)}, lookahead_time={_fmt(lookahead_time)}, "
            f"gain={_fmt(gain)})")


def stopj(a=2.0):
    """The URScript ``stopj`` line: decelerate the joints at ``a`` rad/s^2 to rest.

    Examples
    --------
    >>> stopj()
    'stopj(2.0)'
    """
    return f"stopj({_fmt(_scalar(a, 'a', 'stopj', lo_open=True))})"


def program_from_trajectory(trajectory, *, name="dqlab_trajectory", a=1.4, v=1.05,
                            lookahead_time=0.1, gain=300, limits=None, q_from=None):
    r"""A URScript program (``def ... end``) that plays a joint trajectory with ``servoj``.

    The program moves to the first sample with ``movej`` (at ``a``, ``v``), then sends one
    ``servoj`` per following sample, each controlling the arm for the time to that sample,
    and ends with ``stopj``. Every sample is checked first: finite, within the joint limits,
    joint steps at most ``max_joint_step``, joint speeds and accelerations (finite
    differences) within the limits; the whole program is refused if one sample fails.

    Parameters
    ----------
    trajectory : object with arrays ``t`` (N,) and ``q`` (N, 6)
        For example a ``dqlab.trajectory.Trajectory`` (its ``qd`` and ``qdd`` are not
        needed), or any object with those two attributes. Times in s, strictly increasing;
        joints in rad.
    name : str
        The program's name (a URScript identifier).
    a, v : float
        Acceleration and speed of the approach ``movej``.
    lookahead_time, gain : float
        Of every ``servoj``.
    limits : SafetyLimits or array_like of shape (6, 2), optional
    q_from : array_like, shape (6,), optional
        The arm's joints now (checks the approach for a joint jump).

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
    >>> t = np.array([0.0, 0.5, 1.0])
    >>> q = np.zeros((3, 6)); q[:, 0] = [0.0, 0.1, 0.2]
    >>> print(program_from_trajectory(SimpleNamespace(t=t, q=q)), end="")
    def dqlab_trajectory():
      movej([0.0, 0.0, 0.0, 0.0, 0.0, 0.0], a=1.4, v=1.05, t=0.0, r=0.0)
      servoj([0.1, 0.0, 0.0, 0.0, 0.0, 0.0], t=0.5, lookahead_time=0.1, gain=300.0)
      servoj([0.2, 0.0, 0.0, 0.0, 0.0, 0.0], t=0.5, lookahead_time=0.1, gain=300.0)
      stopj(2.0)
    end
    """
    if not (hasattr(trajectory, "t") and hasattr(trajectory, "q")):
        raise TypeError("trajectory must have arrays t (N,) and q (N, 6), got "
                        f"{type(trajectory).__name__}")
    if not (isinstance(name, str) and name.isidentifier()):
        raise ValueError(f"name must be a URScript identifier, got {name!r}")
    t = np.asarray(trajectory.t, dtype=float)
    q = np.asarray(trajectory.q, dtype=float)
    if q.ndim != 2 or len(q) < 1:
        raise UnsafeTargetError(f"trajectory q must have shape (N, 6), got {q.shape}")
    q = check_joint_targets(q, limits=limits, command="trajectory", times=t)
    lines = [f"def {name}():",
             "  " + movej(q[0], a=a, v=v, limits=limits, q_from=q_from)]
    dt = np.diff(t)
    for k in range(1, len(q)):
        lines.append("  " + servoj(q[k], t=dt[k - 1], lookahead_time=lookahead_time,
                                   gain=gain, limits=limits))
    lines += ["  " + stopj(), "end"]
    return "\n".join(lines) + "\n"
