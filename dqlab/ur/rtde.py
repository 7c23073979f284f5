r"""The RTDE wire protocol (Real-Time Data Exchange, TCP port 30004), output side.

RTDE is the controller's stable, versioned state stream. Every package is a header -- a
big-endian ``uint16`` size (header included) and a ``uint8`` type -- and a payload:

=====  ==============================  =================================================
type   package                         payload (protocol version 2)
=====  ==============================  =================================================
'V'    REQUEST_PROTOCOL_VERSION        client: ``uint16`` version; controller: ``uint8``
                                       accepted
'v'    GET_URCONTROL_VERSION           controller: ``uint32`` major, minor, bugfix, build
'M'    TEXT_MESSAGE                    ``uint8`` length + message, ``uint8`` length +
                                       source, ``uint8`` warning level
'O'    CONTROL_PACKAGE_SETUP_OUTPUTS   client: ``double`` frequency + comma-separated
                                       variable names; controller: ``uint8`` recipe id +
                                       comma-separated types (``NOT_FOUND`` for unknown
                                       names)
'I'    CONTROL_PACKAGE_SETUP_INPUTS    client: names; controller: recipe id + types
'S'    CONTROL_PACKAGE_START           controller: ``uint8`` accepted
'P'    CONTROL_PACKAGE_PAUSE           controller: ``uint8`` accepted
'U'    DATA_PACKAGE                    ``uint8`` recipe id + the recipe's values, packed
                                       big-endian in recipe order
=====  ==============================  =================================================

Types: ``DOUBLE`` (8 bytes), ``VECTOR6D`` (6 doubles), ``VECTOR3D``, ``INT32``, ``UINT32``,
``UINT64``, ``VECTOR6INT32``, ``VECTOR6UINT32``, ``BOOL``, ``UINT8``.

:class:`RTDEReader` is a small output-only client (no thread: it reads the socket when asked
for the newest state); the controller stand-in (:mod:`dqlab.ur.standin`) serves the same
packages.
"""

import socket
import struct
import time

import numpy as np

from .._checks import check_tolerance, short_repr
from ._args import real_number

__all__ = ["RTDEError", "RTDEReader", "PROTOCOL_VERSION", "TYPES", "pack", "PacketBuffer",
           "REQUEST_PROTOCOL_VERSION", "GET_URCONTROL_VERSION", "TEXT_MESSAGE", "DATA_PACKAGE",
           "CONTROL_PACKAGE_SETUP_OUTPUTS", "CONTROL_PACKAGE_SETUP_INPUTS",
           "CONTROL_PACKAGE_START", "CONTROL_PACKAGE_PAUSE", "STATE_VARIABLES",
           "MAX_PACKAGE_SIZE", "FrameBuffer"]

PROTOCOL_VERSION = 2
REQUEST_PROTOCOL_VERSION = ord("V")
GET_URCONTROL_VERSION = ord("v")
TEXT_MESSAGE = ord("M")
DATA_PACKAGE = ord("U")
CONTROL_PACKAGE_SETUP_OUTPUTS = ord("O")
CONTROL_PACKAGE_SETUP_INPUTS = ord("I")
CONTROL_PACKAGE_START = ord("S")
CONTROL_PACKAGE_PAUSE = ord("P")

#: struct format of each RTDE type (big-endian, added when packing)
TYPES = {"DOUBLE": "d", "VECTOR6D": "6d", "VECTOR3D": "3d", "INT32": "i", "UINT32": "I",
         "UINT64": "Q", "VECTOR6INT32": "6i", "VECTOR6UINT32": "6I", "BOOL": "?",
         "UINT8": "B"}

#: number of values of the vector types (every other type holds one value)
COUNTS = {"VECTOR6D": 6, "VECTOR3D": 3, "VECTOR6INT32": 6, "VECTOR6UINT32": 6}

#: the output recipe a :class:`~dqlab.ur.state.URState` is read from
STATE_VARIABLES = ("timestamp", "actual_q", "actual_qd", "actual_TCP_pose", "robot_mode")

_HEADER = struct.Struct(">HB")

#: The largest package the header's ``uint16`` size can describe, bytes.
MAX_PACKAGE_SIZE = 0xFFFF


class RTDEError(ConnectionError):
    """The RTDE peer broke the protocol, refused a request, or went silent."""


def pack(ptype, payload=b""):
    """One RTDE package: header (size, type) and payload.

    Examples
    --------
    >>> pack(REQUEST_PROTOCOL_VERSION, struct.pack(">H", 2))
    b'\\x00\\x05V\\x00\\x02'
    """
    size = _HEADER.size + len(payload)
    if size > MAX_PACKAGE_SIZE:
        raise RTDEError(f"an RTDE package holds at most {MAX_PACKAGE_SIZE} bytes, this one "
                        f"{size}")
    return _HEADER.pack(size, ptype) + payload


def recipe_struct(types):
    """The ``struct.Struct`` of a data package's values for a list of RTDE type names."""
    try:
        return struct.Struct(">" + "".join(TYPES[t] for t in types))
    except KeyError as exc:
        raise RTDEError(f"unknown RTDE type {exc.args[0]!r}") from None


class FrameBuffer:
    """Split a byte stream into ``(type, payload)`` frames, each a header -- its size (header
    included) and its type, packed by ``header`` -- then the payload: the framing of RTDE
    (:class:`PacketBuffer`) and of the primary and secondary interfaces
    (:class:`dqlab.ur.secondary.MessageBuffer`).

    A size below the header's or above ``max_size`` raises ``error`` (the stream is then out
    of step and cannot be trusted).

    Examples
    --------
    >>> buf = FrameBuffer(struct.Struct(">HB"), 0xFFFF, RTDEError, "package")
    >>> buf.feed(b"\\x00\\x04S"), buf.feed(b"\\x01")
    ([], [(83, b'\\x01')])
    """

    def __init__(self, header, max_size, error, what):
        self._header, self._max, self._error, self._what = header, max_size, error, what
        self._data = bytearray()

    def feed(self, data):
        """Add bytes; return the complete frames as ``(type, payload)`` pairs."""
        self._data += data
        out = []
        header = self._header
        while len(self._data) >= header.size:
            size, ftype = header.unpack_from(self._data)
            if not header.size <= size <= self._max:
                raise self._error(f"{self._what} of impossible size {size}")
            if len(self._data) < size:
                break
            out.append((ftype, bytes(self._data[header.size:size])))
            del self._data[:size]
        return out


class PacketBuffer(FrameBuffer):
    """Split a byte stream into RTDE packages (a :class:`FrameBuffer`).

    Examples
    --------
    >>> buf = PacketBuffer()
    >>> data = pack(CONTROL_PACKAGE_START, b"\\x01")
    >>> buf.feed(data[:2]), buf.feed(data[2:])
    ([], [(83, b'\\x01')])
    """

    def __init__(self):
        super().__init__(_HEADER, MAX_PACKAGE_SIZE, RTDEError, "package")


class RTDEReader:
    """A minimal RTDE output client: negotiate, set up one output recipe, read packages.

    Parameters
    ----------
    host : str
    port : int
        30004 on a real controller.
    variables : sequence of str
        The output recipe (default :data:`STATE_VARIABLES`).
    frequency : float
        Output frequency requested, Hz (125 on a CB3, up to 500 on an e-Series).

    Notes
    -----
    The controller keeps sending at ``frequency`` whether or not the packages are read; a
    reader idle for long fills the socket's buffers, and a controller may then drop the
    connection (the stand-in does after 2 s of back-pressure). Read regularly, or close and
    reconnect.

    Attributes
    ----------
    controller_version : tuple of int
        (major, minor, bugfix, build) reported by the controller.
    types : tuple of str
        The RTDE types of the recipe's variables.
    """

    def __init__(self, host, port=30004, variables=STATE_VARIABLES, frequency=125.0):
        if not isinstance(host, str) or not host:
            raise TypeError(f"host must be a host name or address (a non-empty str), got "
                            f"{short_repr(host)}")
        if isinstance(port, (bool, np.bool_)) or not isinstance(port, (int, np.integer)) \
                or not 0 <= port <= 65535:
            raise ValueError(f"port must be a TCP port number (an int in 0..65535), got "
                             f"{short_repr(port)}")
        if isinstance(variables, (str, bytes)) or not all(
                isinstance(v, str) and v.isidentifier() and v.isascii() for v in variables):
            raise ValueError(f"variables must be a sequence of RTDE output names, got "
                             f"{variables!r}")
        if not np.isfinite(real_number(frequency, "frequency")):
            raise ValueError(f"frequency must be a finite number (Hz), got {frequency!r}")
        self.host, self.port = host, int(port)
        self.variables = tuple(variables)
        if not self.variables:
            raise ValueError("variables must name at least one RTDE output")
        self.frequency = float(frequency)
        self.controller_version = None
        self.types = None
        self._sock = None
        self._buffer = PacketBuffer()
        self._pending = []
        self._struct = None
        self._recipe_id = None

    def connect(self, timeout=5.0):
        """Open the connection and run the handshake; the stream is started."""
        timeout = check_tolerance(timeout, "timeout")
        deadline = time.monotonic() + timeout
        self._sock = socket.create_connection((self.host, self.port), timeout=timeout)
        try:
            self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            reply = self._request(REQUEST_PROTOCOL_VERSION, struct.pack(">H", PROTOCOL_VERSION),
                                  deadline)
            if reply[:1] != b"\x01":
                raise RTDEError(f"controller refused RTDE protocol version {PROTOCOL_VERSION}")
            reply = self._request(GET_URCONTROL_VERSION, b"", deadline)
            if len(reply) != 16:
                raise RTDEError(f"controller version reply of {len(reply)} bytes, not 16")
            self.controller_version = struct.unpack(">IIII", reply)
            names = ",".join(self.variables).encode()
            reply = self._request(CONTROL_PACKAGE_SETUP_OUTPUTS,
                                  struct.pack(">d", self.frequency) + names, deadline)
            if not reply:
                raise RTDEError("empty reply to the output set-up")
            self._recipe_id = reply[0]
            try:
                types = tuple(reply[1:].decode("ascii").split(","))
            except UnicodeDecodeError:
                raise RTDEError("the output set-up reply is not ASCII text") from None
            if len(types) != len(self.variables):
                raise RTDEError(f"the controller answered {len(types)} types for "
                                f"{len(self.variables)} outputs")
            self.types = types
            missing = [v for v, t in zip(self.variables, self.types, strict=True)
                       if t == "NOT_FOUND"]
            if missing:
                raise RTDEError(f"controller does not serve the RTDE outputs {missing}")
            self._struct = recipe_struct(self.types)
            reply = self._request(CONTROL_PACKAGE_START, b"", deadline)
            if reply[:1] != b"\x01":
                raise RTDEError("controller refused to start the RTDE stream")
        except BaseException:
            self.close()
            raise

    def close(self):
        """Close the socket (idempotent)."""
        if self._sock is not None:
            try:
                self._sock.close()
            finally:
                self._sock = None

    def _recv_packages(self, timeout):
        self._sock.settimeout(max(timeout, 1e-4))
        try:
            data = self._sock.recv(65536)
        except socket.timeout:
            return []
        if not data:
            raise RTDEError("controller closed the RTDE connection")
        return self._buffer.feed(data)

    def _request(self, ptype, payload, deadline):
        self._sock.sendall(pack(ptype, payload))
        while True:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise RTDEError(f"no reply to RTDE request {chr(ptype)!r}")
            for rtype, body in self._recv_packages(remaining):
                if rtype == ptype:
                    return body
                if rtype == DATA_PACKAGE:
                    self._pending = [body]          # only the newest is ever used
                # text messages and anything else during the handshake are skipped

    def _decode(self, body):
        if not body:
            raise RTDEError("empty RTDE data package")
        if body[0] != self._recipe_id:
            raise RTDEError(f"data package of unknown recipe {body[0]}")
        if len(body) - 1 != self._struct.size:
            raise RTDEError(f"data package of {len(body) - 1} bytes; the recipe "
                            f"{self.types} needs {self._struct.size}")
        flat = self._struct.unpack(body[1:])
        out, k = {}, 0
        for name, rtype in zip(self.variables, self.types, strict=True):
            width = COUNTS.get(rtype, 1)
            out[name] = np.array(flat[k:k + width]) if width > 1 else flat[k]
            k += width
        return out

    def read(self, timeout=1.0):
        """The newest data package as a dict of variable values (waits for one if needed).

        Packages that arrived since the last call are read and all but the newest dropped.
        The call returns within ``timeout`` seconds (plus one socket read), whatever the
        peer sends.

        Raises
        ------
        RTDEError
            If no data package arrived in time, the connection closed, or the peer sent a
            package that does not fit the protocol (the message says what).
        """
        if self._sock is None:
            raise RTDEError("not connected")
        timeout = check_tolerance(timeout, "timeout")
        deadline = time.monotonic() + timeout
        newest = self._pending.pop() if self._pending else None
        self._pending.clear()
        self._sock.setblocking(False)
        try:
            while True:                             # what is waiting, until the deadline
                try:
                    data = self._sock.recv(65536)
                except (BlockingIOError, InterruptedError):
                    break
                if not data:
                    raise RTDEError("controller closed the RTDE connection")
                for rtype, body in self._buffer.feed(data):
                    if rtype == DATA_PACKAGE:
                        newest = body
                if time.monotonic() > deadline:
                    break
        finally:
            if self._sock is not None:
                self._sock.setblocking(True)
        while newest is None:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise RTDEError(f"no RTDE data package within {timeout:g} s")
            for rtype, body in self._recv_packages(remaining):
                if rtype == DATA_PACKAGE:
                    newest = body
        return self._decode(newest)
