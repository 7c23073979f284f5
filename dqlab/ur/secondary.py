r"""The secondary interface (TCP port 30002): URScript in, binary state messages out.

A UR controller runs every line (or ``def ... end`` program) it receives on port 30002 as a
program; a new one replaces the running one. It also sends, on the same connection,
binary messages at 10 Hz and on events. Every message is a header -- a big-endian ``int32``
size (header included) and a ``uint8`` message type -- and a payload:

====  ======================  ===============================================================
type  message                 payload
====  ======================  ===============================================================
16    ROBOT_STATE             sub-packages, each an ``int32`` size (its header included), a
                              ``uint8`` package type (0 robot mode data, 1 joint data, ...,
                              5 kinematics info, ...) and its data
20    ROBOT_MESSAGE           ``uint64`` timestamp, ``int8`` source, ``uint8`` robot message
                              type, then per type; 3 (version): ``uint8`` length + project
                              name, ``uint8`` major, ``uint8`` minor, ``int32`` bugfix,
                              ``int32`` build, the build date (the rest)
====  ======================  ===============================================================

(The layout of the state sub-packages changes between controller versions, which is why
:class:`SecondaryInterfaceBackend` reads the state from RTDE instead.) :func:`pack_message`,
:func:`pack_package`, :func:`version_message` and :func:`robot_state_message` write the
messages -- the one place where the stand-in (:mod:`dqlab.ur.standin`) encodes what it sends
on this port; :class:`MessageBuffer` splits a stream into messages and refuses a corrupt
size.
"""

import socket
import struct

import numpy as np

from .._checks import short_repr
from . import script
from .motion import GAIN, LOOKAHEAD_TIME, MOVEJ_A, MOVEJ_V, MOVEL_A, MOVEL_V, SERVOJ_T, STOPJ_A
from .rtde import STATE_VARIABLES, RTDEReader
from .script import as_safety_limits
from .state import URState

__all__ = ["SecondaryInterfaceBackend", "MessageBuffer", "SecondaryError", "pack_message",
           "pack_package", "version_message", "robot_state_message", "ROBOT_STATE",
           "ROBOT_MESSAGE", "ROBOT_MESSAGE_VERSION", "KINEMATICS_INFO", "MAX_MESSAGE_SIZE"]

ROBOT_STATE = 16
ROBOT_MESSAGE = 20
ROBOT_MESSAGE_VERSION = 3
#: Robot-state sub-package type of the kinematics info (the calibrated DH parameters).
KINEMATICS_INFO = 5
#: Largest message accepted, bytes (a controller's are a few kilobytes).
MAX_MESSAGE_SIZE = 1 << 20

_HEADER = struct.Struct(">iB")
_ROBOT_MESSAGE_HEAD = struct.Struct(">QbB")


class SecondaryError(ConnectionError):
    """The peer broke the secondary interface's message framing."""


def pack_message(mtype, payload=b""):
    """One message: header (size, type) and payload.

    Examples
    --------
    >>> pack_message(ROBOT_STATE, b"")
    b'\\x00\\x00\\x00\\x05\\x10'
    """
    return _HEADER.pack(_HEADER.size + len(payload), mtype) + payload


def pack_package(ptype, data=b""):
    """One sub-package of a robot-state message: header (size, type) and data.

    Examples
    --------
    >>> pack_package(KINEMATICS_INFO, b"\\x01")
    b'\\x00\\x00\\x00\\x06\\x05\\x01'
    """
    return _HEADER.pack(_HEADER.size + len(data), ptype) + data


def robot_state_message(packages):
    """A ROBOT_STATE message holding the packed sub-packages ``packages`` (bytes each)."""
    return pack_message(ROBOT_STATE, b"".join(packages))


def version_message(version, *, project="URControl", build_date="", timestamp=0):
    """The version message a controller sends when a client connects.

    Parameters
    ----------
    version : tuple of 4 int
        (major, minor, bugfix, build).

    Examples
    --------
    >>> MessageBuffer().feed(version_message((5, 11, 0, 0)))[0][0]
    20
    """
    major, minor, bugfix, build = (int(v) for v in version)
    name = project.encode("ascii")
    body = (_ROBOT_MESSAGE_HEAD.pack(timestamp, -2, ROBOT_MESSAGE_VERSION)
            + struct.pack(">B", len(name)) + name
            + struct.pack(">BBii", major, minor, bugfix, build) + build_date.encode("ascii"))
    return pack_message(ROBOT_MESSAGE, body)


class MessageBuffer:
    """Split a byte stream from the secondary interface into ``(type, payload)`` messages.

    Raises :class:`SecondaryError` for a size below the header's or above
    :data:`MAX_MESSAGE_SIZE` (the stream is then out of step and cannot be trusted).

    Examples
    --------
    >>> buf = MessageBuffer()
    >>> data = pack_message(ROBOT_STATE, pack_package(0, b"x"))
    >>> buf.feed(data[:3]), buf.feed(data[3:])
    ([], [(16, b'\\x00\\x00\\x00\\x06\\x00x')])
    """

    def __init__(self):
        self._data = bytearray()

    def feed(self, data):
        """Add bytes; return the complete messages."""
        self._data += data
        out = []
        while len(self._data) >= _HEADER.size:
            size, mtype = _HEADER.unpack_from(self._data)
            if not _HEADER.size <= size <= MAX_MESSAGE_SIZE:
                raise SecondaryError(f"secondary-interface message of impossible size {size}")
            if len(self._data) < size:
                break
            out.append((mtype, bytes(self._data[_HEADER.size:size])))
            del self._data[:size]
        return out


class SecondaryInterfaceBackend:
    """A UR controller (or URSim, or the stand-in) through its text and state ports.

    Commands are URScript lines sent as text to the **secondary interface** (TCP port
    30002), which runs each line it receives as a program; a new line replaces the running
    program. The state is read from the **RTDE** stream (port 30004, protocol version 2,
    output recipe ``timestamp, actual_q, actual_qd, actual_TCP_pose, robot_mode``), not from
    the secondary interface's own binary state messages, whose layout changes between
    controller versions. Whatever the controller sends on port 30002 is read and discarded.

    The texts are written by :mod:`dqlab.ur.script`, which checks every target once more
    against ``limits`` (the client has checked them against its own already).

    Parameters
    ----------
    host : str
        The controller's address (the stand-in: ``"127.0.0.1"``).
    port : int
        Secondary interface port.
    rtde_port : int
        RTDE port.
    frequency : float
        RTDE output frequency requested, Hz.
    robot : dqlab.robot.Robot, optional
        The arm (default :func:`dqlab.models.ur3`): ``movel`` targets are checked for its
        reach.
    limits : SafetyLimits, optional
        Default: ``robot``'s, or the UR3's.
    """

    name = "secondary interface + RTDE"

    def __init__(self, host, port=30002, *, rtde_port=30004, frequency=125.0, robot=None,
                 limits=None):
        if not isinstance(host, str) or not host:
            raise TypeError(f"host must be a host name or address (a non-empty str), got "
                            f"{host!r}")
        self.host, self.port, self.rtde_port = host, _port(port, "port"), \
            _port(rtde_port, "rtde_port")
        self.limits = as_safety_limits(limits, robot)
        self.robot = robot if robot is not None else self.limits.robot
        self._reader = RTDEReader(host, self.rtde_port, STATE_VARIABLES, frequency)
        self._sock = None
        self._t0 = None

    @property
    def controller_version(self):
        """(major, minor, bugfix, build) from RTDE, once connected."""
        return self._reader.controller_version

    def connect(self, timeout=5.0):
        self._sock = socket.create_connection((self.host, self.port), timeout=timeout)
        try:
            self._reader.connect(timeout)
            self._t0 = float(self._reader.read(timeout)["timestamp"])
        except BaseException:
            self.close()
            raise

    def close(self):
        self._reader.close()
        if self._sock is not None:
            try:
                self._sock.close()
            finally:
                self._sock = None

    def _drain(self):
        self._sock.setblocking(False)
        try:
            for _ in range(1024):           # at most 64 MB: a flooding peer cannot hold us
                try:
                    if not self._sock.recv(65536):
                        raise ConnectionError("the controller closed the secondary interface")
                except (BlockingIOError, InterruptedError):
                    return
        finally:
            self._sock.setblocking(True)

    def send_script(self, text):
        """Send URScript text (a line or a ``def ... end`` program) as it is."""
        if self._sock is None:
            raise RuntimeError("SecondaryInterfaceBackend is not connected")
        if not isinstance(text, str):
            raise TypeError(f"text must be a str, got {type(text).__name__}")
        self._drain()
        if not text.endswith("\n"):
            text += "\n"
        self._sock.sendall(text.encode("utf-8"))

    def read_state(self):
        d = self._reader.read()
        return URState(time=d["timestamp"] - self._t0, q=d["actual_q"], qd=d["actual_qd"],
                       tcp_pose=d["actual_TCP_pose"], robot_mode=d["robot_mode"])

    def movej(self, q, *, a=MOVEJ_A, v=MOVEJ_V, t=0.0, r=0.0):
        self.send_script(script.movej(q, a=a, v=v, t=t, r=r, limits=self.limits))

    def movel(self, pose, *, a=MOVEL_A, v=MOVEL_V, t=0.0, r=0.0):
        """Send ``movel``; ``pose`` is a UR pose vector ``[x, y, z, rx, ry, rz]`` of the TCP in
        the controller's base frame."""
        self.send_script(script.movel(pose, a=a, v=v, t=t, r=r, limits=self.limits,
                                      robot=self.robot))

    def servoj(self, q, *, t=SERVOJ_T, lookahead_time=LOOKAHEAD_TIME, gain=GAIN):
        self.send_script(script.servoj(q, t=t, lookahead_time=lookahead_time, gain=gain,
                                       limits=self.limits))

    def stop(self, a=STOPJ_A):
        self.send_script(script.stopj(a, limits=self.limits))


def _port(value, name):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) \
            or not 0 <= value <= 65535:
        raise ValueError(f"{name} must be a TCP port number (an int in 0..65535), got "
                         f"{short_repr(value)}")
    return int(value)

