"""A UR controller through the ``ur_rtde`` package (optional extra ``robot``)."""

import importlib
import time

import numpy as np

from ._args import positive_number
from .motion import GAIN, LOOKAHEAD_TIME, MOVEJ_A, MOVEJ_V, MOVEL_A, MOVEL_V, SERVOJ_T, STOPJ_A
from .state import URState

__all__ = ["RTDEBackend"]


def _import_ur_rtde():
    try:
        return (importlib.import_module("rtde_receive"),
                importlib.import_module("rtde_control"))
    except ImportError:
        raise ImportError(
            "RTDEBackend needs the ur_rtde package, which is not installed. Install dqlab's "
            "optional extra 'robot' (pip install 'dqlab[robot]') or ur_rtde itself "
            "(pip install ur_rtde); or use SecondaryInterfaceBackend, which needs nothing."
        ) from None


def _floats(values, name, n):
    """``values`` as a list of ``n`` finite floats (ur_rtde takes lists)."""
    a = np.asarray(values)
    if a.dtype.kind not in "iuf" or a.shape != (n,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be {n} finite real numbers, got {values!r}")
    return [float(x) for x in a]


class RTDEBackend:
    """A UR controller through the ``ur_rtde`` package (optional extra ``robot``).

    State comes from ``rtde_receive.RTDEReceiveInterface``; motions go through
    ``rtde_control.RTDEControlInterface``, which uploads its own control script to the
    controller (a real robot or URSim; the stand-in serves only the receive side: use
    ``control=False`` with it). ``ur_rtde`` always connects to RTDE port 30004. The motion
    calls pass on what :class:`~dqlab.ur.client.URClient` has checked; they refuse non-finite
    numbers themselves.

    Parameters
    ----------
    host : str
    frequency : float
        RTDE frequency, Hz (-1: the controller's maximum).
    control : bool
        Also open the control interface (needed for motions).
    """

    name = "ur_rtde"

    def __init__(self, host, *, frequency=-1.0, control=True):
        if not isinstance(host, str):
            raise TypeError(f"host must be a str, got {host!r}")
        self._receive_mod, self._control_mod = _import_ur_rtde()
        self.host, self.frequency, self.control = host, float(frequency), bool(control)
        self._rx = self._ctl = None
        self._t0 = None

    def connect(self, timeout=5.0):
        variables = ["timestamp", "actual_q", "actual_qd", "actual_TCP_pose", "robot_mode"]
        self._rx = self._receive_mod.RTDEReceiveInterface(self.host, self.frequency, variables)
        if self.control:
            self._ctl = self._control_mod.RTDEControlInterface(self.host)
        deadline = time.monotonic() + timeout
        while self._rx.getTimestamp() == 0.0 and time.monotonic() < deadline:
            time.sleep(0.005)
        self._t0 = self._rx.getTimestamp()

    def close(self):
        if self._ctl is not None:
            self._ctl.stopScript()
            self._ctl.disconnect()
            self._ctl = None
        if self._rx is not None:
            self._rx.disconnect()
            self._rx = None

    def read_state(self):
        rx = self._rx
        if rx is None:
            raise RuntimeError("RTDEBackend is not connected")
        return URState(time=rx.getTimestamp() - self._t0, q=np.array(rx.getActualQ()),
                       qd=np.array(rx.getActualQd()), tcp_pose=np.array(rx.getActualTCPPose()),
                       robot_mode=rx.getRobotMode())

    def _control(self, command):
        if self._ctl is None:
            raise RuntimeError(f"{command}: this RTDEBackend was opened with control=False")
        return self._ctl

    def movej(self, q, *, a=MOVEJ_A, v=MOVEJ_V, t=0.0, r=0.0):
        if t or r:
            raise ValueError("RTDEBackend.movej: ur_rtde takes no t or r; use "
                             "SecondaryInterfaceBackend for timed or blended moves")
        self._control("movej").moveJ(_floats(q, "q", 6), positive_number(v, "v"),
                                     positive_number(a, "a"), True)

    def movel(self, pose, *, a=MOVEL_A, v=MOVEL_V, t=0.0, r=0.0):
        """``moveL``; ``pose`` is a UR pose vector ``[x, y, z, rx, ry, rz]`` of the TCP in the
        controller's base frame."""
        if t or r:
            raise ValueError("RTDEBackend.movel: ur_rtde takes no t or r")
        self._control("movel").moveL(_floats(pose, "pose", 6), positive_number(v, "v"),
                                     positive_number(a, "a"), True)

    def servoj(self, q, *, t=SERVOJ_T, lookahead_time=LOOKAHEAD_TIME, gain=GAIN):
        self._control("servoj").servoJ(_floats(q, "q", 6), 0.0, 0.0, positive_number(t, "t"),
                                       positive_number(lookahead_time, "lookahead_time"),
                                       positive_number(gain, "gain"))

    def stop(self, a=STOPJ_A):
        self._control("stop").stopJ(positive_number(a, "a"))
