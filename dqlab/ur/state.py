"""What a UR controller reports, and the check that a report can be trusted.

:class:`URState` is one report; :func:`check_state` refuses a report that is not six finite
joint positions, six finite joint speeds, a finite pose and an integer robot mode -- a NaN
from a controller is an error (:class:`ControllerError`), never a value a safety check
compares against (``NaN > step`` is False, so it would pass every check).
"""

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["HOME", "ROBOT_MODE_RUNNING", "URState", "ControllerError", "check_state"]

#: The thesis's home joints (arm straight up), rad.
HOME = np.array([0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0])

#: UR robot mode reported while the arm is powered, released and ready to move.
ROBOT_MODE_RUNNING = 7


class ControllerError(RuntimeError):
    """The controller reported a state that cannot be trusted (NaN, wrong shape or type)."""


@dataclass(frozen=True)
class URState:
    """What a controller reports at one instant.

    Attributes
    ----------
    time : float
        Seconds since the back end connected (controller time).
    q : ndarray, shape (6,)
        Actual joint positions, rad.
    qd : ndarray, shape (6,)
        Actual joint speeds, rad/s.
    tcp_pose : ndarray, shape (6,)
        Actual TCP pose: the UR pose vector ``[x, y, z, rx, ry, rz]`` (metres and a rotation
        vector in radians) of the TCP in the controller's base frame, which is DH frame 0 of
        the robot (not the world frame of a robot with a ``base`` transform; see
        :mod:`dqlab.ur.motion`).
    robot_mode : int
        UR robot mode (7 = RUNNING).
    """

    time: float
    q: np.ndarray
    qd: np.ndarray
    tcp_pose: np.ndarray
    robot_mode: int


def _vector(value, name, n, source):
    try:
        a = np.asarray(value)
        if a.dtype.kind not in "iuf" or a.shape != (n,):
            raise ValueError
        a = a.astype(float)
    except (TypeError, ValueError):
        raise ControllerError(f"{source} reported {name} = {value!r}, not {n} real "
                              "numbers") from None
    if not np.all(np.isfinite(a)):
        raise ControllerError(f"{source} reported {name} = {a.tolist()}: not finite (a "
                              "controller fault or a corrupt packet); nothing was sent")
    return a


def check_state(state, source="the controller", n=6):
    """``state`` as a :class:`URState` of finite float arrays, or :class:`ControllerError`.

    Parameters
    ----------
    state : URState
    source : str
        Named in the message (e.g. the back end).
    n : int
        Number of joints.

    Returns
    -------
    URState

    Examples
    --------
    >>> s = URState(0.0, HOME, np.zeros(6), np.zeros(6), ROBOT_MODE_RUNNING)
    >>> check_state(s).robot_mode
    7
    >>> check_state(URState(0.0, HOME + np.nan, np.zeros(6), np.zeros(6), 7))
    Traceback (most recent call last):
    ...
    dqlab.ur.state.ControllerError: the controller reported q = [nan, nan, ...
    """
    if not isinstance(state, URState):
        raise ControllerError(f"{source} returned {type(state).__name__}, not a URState")
    t = state.time
    if isinstance(t, (bool, np.bool_)) or not isinstance(t, (int, float, np.integer,
                                                            np.floating)) \
            or not math.isfinite(t):
        raise ControllerError(f"{source} reported time = {t!r}, not a finite number")
    mode = state.robot_mode
    if isinstance(mode, (bool, np.bool_)) or not isinstance(mode, (int, np.integer)):
        raise ControllerError(f"{source} reported robot_mode = {mode!r}, not an integer")
    return URState(time=float(t), q=_vector(state.q, "q", n, source),
                   qd=_vector(state.qd, "qd", n, source),
                   tcp_pose=_vector(state.tcp_pose, "tcp_pose", 6, source),
                   robot_mode=int(mode))
