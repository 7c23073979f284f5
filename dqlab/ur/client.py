"""A client for a Universal Robots controller with interchangeable back ends.

:class:`URState` is what a controller reports; :class:`Backend` is the protocol every back
end implements (the secondary interface with RTDE state, ``ur_rtde``, the in-process
kinematic arm, and the MuJoCo arm of :mod:`dqlab.sim`).
"""

import typing
from dataclasses import dataclass

import numpy as np

__all__ = ["URState", "Backend", "ROBOT_MODE_RUNNING"]

#: UR robot mode reported while the arm is powered, released and ready to move.
ROBOT_MODE_RUNNING = 7


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
        Actual TCP pose as a UR pose vector ``[x, y, z, rx, ry, rz]``: metres and a rotation
        vector in radians.
    robot_mode : int
        UR robot mode (7 = RUNNING).
    """

    time: float
    q: np.ndarray
    qd: np.ndarray
    tcp_pose: np.ndarray
    robot_mode: int


class Backend(typing.Protocol):
    """What :class:`URClient` needs from a controller connection.

    Motion calls *start* a move and return at once; the client polls :meth:`read_state`.
    Units and argument names are URScript's: joint targets in rad, poses as UR pose vectors,
    ``a`` acceleration (rad/s^2 or m/s^2), ``v`` speed (rad/s or m/s), ``t`` time (s),
    ``r`` blend radius (m).
    """

    name: str

    def connect(self, timeout: float) -> None: ...

    def close(self) -> None: ...

    def read_state(self) -> URState: ...

    def movej(self, q, *, a: float, v: float, t: float, r: float) -> None: ...

    def movel(self, pose, *, a: float, v: float, t: float, r: float) -> None: ...

    def servoj(self, q, *, t: float, lookahead_time: float, gain: float) -> None: ...

    def stop(self, a: float) -> None: ...
