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

A robot state holds, among others, these sub-packages, in the layout of UR's Client Library
and its recorded URSim 5.8 message (e-Series; all big-endian):

====  ====================  ===============================================================
type  sub-package           data
====  ====================  ===============================================================
0     robot mode data       ``uint64`` timestamp, seven ``bool`` (real robot connected,
                            enabled, power on, emergency stopped, protective stopped,
                            program running, program paused), ``uint8`` robot mode,
                            ``uint8`` control mode, ``double`` target speed fraction, speed
                            scaling, target speed fraction limit, ``uint8`` reserved (47
                            bytes; CB3 3.x controllers send 46, without the last byte)
1     joint data            per joint: ``double`` q actual, q target, qd actual, ``float``
                            I actual, V actual, T motor, T micro, ``uint8`` joint mode (251)
4     cartesian info        ``double[6]`` TCP pose (x, y, z, rx, ry, rz), ``double[6]`` TCP
                            offset (101)
5     kinematics info       :mod:`dqlab.ur.calibration` (225)
====  ====================  ===============================================================

A controller sends the version message when a client connects, then robot states at 10 Hz,
on the primary (30001) and secondary (30002) interfaces alike. :func:`robot_state_from_message`
reads those four sub-packages of a robot state (and skips the others, as the Client Library
does); :func:`version_from_message` reads the version. The layout of the state sub-packages
changes between controller versions, which is why :class:`SecondaryInterfaceBackend` reads
the state from RTDE instead. :func:`pack_message`, :func:`pack_package`,
:func:`version_message`, :func:`robot_state_message` and the ``pack_*`` functions of the
sub-packages write the messages -- the one place where the stand-in
(:mod:`dqlab.ur.standin`) encodes what it sends on these ports; :class:`MessageBuffer` splits
a stream into messages and refuses a corrupt size.
"""

import socket
import struct
from dataclasses import dataclass

import numpy as np

from .._checks import short_repr
from . import script
from .calibration import CalibrationError, KinematicsInfo, kinematics_info_from_message
from .client import robot_and_limits
from .motion import GAIN, LOOKAHEAD_TIME, MOVEJ_A, MOVEJ_V, MOVEL_A, MOVEL_V, SERVOJ_T, STOPJ_A
from .rtde import STATE_VARIABLES, FrameBuffer, RTDEReader
from .state import URState

__all__ = ["SecondaryInterfaceBackend", "MessageBuffer", "SecondaryError", "pack_message",
           "pack_package", "version_message", "robot_state_message", "ROBOT_STATE",
           "ROBOT_MESSAGE", "ROBOT_MESSAGE_VERSION", "KINEMATICS_INFO", "MAX_MESSAGE_SIZE",
           "ROBOT_MODE_DATA", "JOINT_DATA", "CARTESIAN_INFO", "RobotModeData", "JointData",
           "CartesianInfo", "RobotState", "VersionMessage", "pack_robot_mode_data",
           "pack_joint_data", "pack_cartesian_info", "robot_state_from_message",
           "version_from_message"]

ROBOT_STATE = 16
ROBOT_MESSAGE = 20
ROBOT_MESSAGE_VERSION = 3
#: Robot-state sub-package types: robot mode data, joint data, cartesian info, and the
#: kinematics info (the calibrated DH parameters).
ROBOT_MODE_DATA, JOINT_DATA, CARTESIAN_INFO, KINEMATICS_INFO = 0, 1, 4, 5
#: Largest message accepted, bytes (a controller's are a few kilobytes).
MAX_MESSAGE_SIZE = 1 << 20

_HEADER = struct.Struct(">iB")
_ROBOT_MESSAGE_HEAD = struct.Struct(">QbB")
_ROBOT_MODE = struct.Struct(">Q7?BBddd")            # 42 bytes, then the reserved byte(s)
_JOINT = struct.Struct(">dddffffB")                  # 41 bytes per joint
_CARTESIAN = struct.Struct(">12d")                   # 96 bytes


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


@dataclass(frozen=True)
class RobotModeData:
    """Sub-package 0 of a robot state (the Client Library's ``RobotModeData``)."""

    timestamp: int
    is_real_robot_connected: bool
    is_real_robot_enabled: bool
    is_robot_power_on: bool
    is_emergency_stopped: bool
    is_protective_stopped: bool
    is_program_running: bool
    is_program_paused: bool
    robot_mode: int
    control_mode: int
    target_speed_fraction: float
    speed_scaling: float
    target_speed_fraction_limit: float
    reserved: bytes = b"\x00"


@dataclass(frozen=True)
class JointData:
    """Sub-package 1: each field a tuple of six values (rad, rad/s, A, V, degrees C)."""

    q_actual: tuple
    q_target: tuple
    qd_actual: tuple
    i_actual: tuple
    v_actual: tuple
    t_motor: tuple
    t_micro: tuple
    joint_mode: tuple


@dataclass(frozen=True)
class CartesianInfo:
    """Sub-package 4: the TCP pose ``[x, y, z, rx, ry, rz]`` in the base frame and the TCP
    offset from the flange, each a tuple of six floats (m, rad)."""

    tcp_pose: tuple
    tcp_offset: tuple


@dataclass(frozen=True)
class RobotState:
    """What :func:`robot_state_from_message` read: each sub-package it knows, or None when
    the message has none; ``package_types`` lists every sub-package in order."""

    robot_mode: RobotModeData | None
    joints: JointData | None
    cartesian: CartesianInfo | None
    kinematics: KinematicsInfo | None
    package_types: tuple


@dataclass(frozen=True)
class VersionMessage:
    """The version message: ``URControl`` and major.minor.bugfix, build, build date."""

    project_name: str
    major: int
    minor: int
    bugfix: int
    build: int
    build_date: str


def pack_robot_mode_data(data):
    """Sub-package 0 (header included) of a :class:`RobotModeData`.

    Examples
    --------
    >>> mode = RobotModeData(0, True, True, True, False, False, False, False, 7, 0,
    ...                      1.0, 1.0, 1.0)
    >>> len(pack_robot_mode_data(mode))
    47
    """
    fields = [getattr(data, name) for name in RobotModeData.__dataclass_fields__]
    return pack_package(ROBOT_MODE_DATA, _ROBOT_MODE.pack(*fields[:-1]) + bytes(fields[-1]))


def pack_joint_data(data):
    """Sub-package 1 (header included) of a :class:`JointData` (251 bytes)."""
    columns = [getattr(data, name) for name in JointData.__dataclass_fields__]
    return pack_package(JOINT_DATA, b"".join(_JOINT.pack(*row)
                                             for row in zip(*columns, strict=True)))


def pack_cartesian_info(data):
    """Sub-package 4 (header included) of a :class:`CartesianInfo` (101 bytes)."""
    return pack_package(CARTESIAN_INFO, _CARTESIAN.pack(*data.tcp_pose, *data.tcp_offset))


def _message_bytes(message):
    """``message`` as bytes, or ``TypeError`` naming it."""
    if not isinstance(message, (bytes, bytearray, memoryview)):
        raise TypeError(f"message must be bytes (one whole message), got "
                        f"{type(message).__name__}")
    return bytes(message)


def _sub_packages(message, source):
    """(type, data) of each sub-package of a robot-state message, as the Client Library's
    PrimaryParser walks them; SecondaryError for a size that does not fit."""
    if len(message) < _HEADER.size:
        raise SecondaryError(f"{source}: {len(message)} bytes, shorter than a header")
    size, mtype = _HEADER.unpack_from(message)
    if size != len(message) or mtype != ROBOT_STATE:
        raise SecondaryError(f"{source}: not a robot state of {len(message)} bytes (header: "
                             f"size {size}, type {mtype})")
    offset, out = _HEADER.size, []
    while offset < size:
        if size - offset < _HEADER.size:
            raise SecondaryError(f"{source}: {size - offset} bytes left at byte {offset}, "
                                 "shorter than a sub-package header")
        length, ptype = _HEADER.unpack_from(message, offset)
        if length < _HEADER.size or offset + length > size:
            raise SecondaryError(f"{source}: sub-package of type {ptype} claims {length} "
                                 f"bytes at byte {offset} of {size}")
        out.append((ptype, message[offset:offset + length]))
        offset += length
    return out


def robot_state_from_message(message, *, source="message"):
    """Read a robot-state message (type 16, header included) of the primary or secondary
    interface: its robot mode data, joint data, cartesian info and kinematics info.

    Parameters
    ----------
    message : bytes
    source : str
        Named in error messages.

    Returns
    -------
    RobotState

    Raises
    ------
    SecondaryError
        For a message whose sizes do not fit, or a sub-package shorter than its layout.

    Examples
    --------
    >>> mode = RobotModeData(0, True, True, True, False, False, False, False, 7, 0,
    ...                      1.0, 1.0, 1.0)
    >>> state = robot_state_from_message(robot_state_message([pack_robot_mode_data(mode)]))
    >>> state.robot_mode.robot_mode, state.joints, state.package_types
    (7, None, (0,))
    """
    message = _message_bytes(message)
    found = {}
    packages = _sub_packages(message, source)
    for ptype, package in packages:
        data = package[_HEADER.size:]
        if ptype in found or ptype not in (ROBOT_MODE_DATA, JOINT_DATA, CARTESIAN_INFO,
                                           KINEMATICS_INFO):
            continue
        need = {ROBOT_MODE_DATA: _ROBOT_MODE.size, JOINT_DATA: 6 * _JOINT.size,
                CARTESIAN_INFO: _CARTESIAN.size, KINEMATICS_INFO: 0}[ptype]
        if len(data) < need:
            raise SecondaryError(f"{source}: sub-package of type {ptype}: {len(data)} bytes of "
                                 f"data, fewer than the {need} of its layout")
        if ptype == ROBOT_MODE_DATA:
            found[ptype] = RobotModeData(*_ROBOT_MODE.unpack_from(data),
                                         reserved=data[_ROBOT_MODE.size:])
        elif ptype == JOINT_DATA:
            rows = [_JOINT.unpack_from(data, k * _JOINT.size) for k in range(6)]
            found[ptype] = JointData(*(tuple(column) for column in zip(*rows, strict=True)))
        elif ptype == CARTESIAN_INFO:
            values = _CARTESIAN.unpack_from(data)
            found[ptype] = CartesianInfo(values[:6], values[6:])
        else:
            one = pack_message(ROBOT_STATE, package)
            try:
                found[ptype] = kinematics_info_from_message(one, source=source)
            except CalibrationError as exc:
                raise SecondaryError(str(exc)) from None
    return RobotState(found.get(ROBOT_MODE_DATA), found.get(JOINT_DATA),
                      found.get(CARTESIAN_INFO), found.get(KINEMATICS_INFO),
                      tuple(ptype for ptype, _ in packages))


def version_from_message(message, *, source="message"):
    """Read the version message (type 20, robot message type 3, header included).

    Examples
    --------
    >>> version_from_message(version_message((5, 11, 0, 0))).minor
    11
    """
    message = _message_bytes(message)
    head = _HEADER.size + _ROBOT_MESSAGE_HEAD.size
    if len(message) < head + 1:
        raise SecondaryError(f"{source}: {len(message)} bytes, too short for a version message")
    size, mtype = _HEADER.unpack_from(message)
    _, _, kind = _ROBOT_MESSAGE_HEAD.unpack_from(message, _HEADER.size)
    if size != len(message) or mtype != ROBOT_MESSAGE or kind != ROBOT_MESSAGE_VERSION:
        raise SecondaryError(f"{source}: not a version message (size {size} of "
                             f"{len(message)}, type {mtype}, robot message type {kind})")
    n = message[head]
    rest = message[head + 1 + n:]
    if len(rest) < 10:
        raise SecondaryError(f"{source}: version message cut short")
    major, minor, bugfix, build = struct.unpack_from(">BBii", rest)
    return VersionMessage(message[head + 1:head + 1 + n].decode("latin-1"), major, minor,
                          bugfix, build, rest[10:].decode("latin-1"))


class MessageBuffer(FrameBuffer):
    """Split a byte stream from the primary or secondary interface into ``(type, payload)``
    messages (a :class:`~dqlab.ur.rtde.FrameBuffer`).

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
        super().__init__(_HEADER, MAX_MESSAGE_SIZE, SecondaryError,
                         "secondary-interface message")


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
        self.robot, self.limits = robot_and_limits(robot, limits)
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

