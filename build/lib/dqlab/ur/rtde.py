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

__all__ = ["RTDEError", "RTDEReader", "PROTOCOL_VERSION", "TYPES", "pack", "PacketBuffer",
           "REQUEST_PROTOCOL_VERSION", "GET_URCONTROL_VERSION", "TEXT_MESSAGE", "DATA_PACKAGE",
           "CONTROL_PACKAGE_SETUP_OUTPUTS", "CONTROL_PACKAGE_SETUP_INPUTS",
           "CONTROL_PACKAGE_START", "CONTROL_PACKAGE_PAUSE", "STATE_VARIABLES"]

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

#: the output recipe a :class:`~dqlab.ur.client.URState` is read from
STATE_VARIABLES = ("timestamp", "actual_q", "actual_qd", "actual_TCP_pose", "robot_mode")

_HEADER = struct.Struct(">HB")


class RTDEError(ConnectionError):
    """The RTDE peer broke the protocol, refused a request, or went silent."""


def pack(ptype, payload=b""):
    """One RTDE package: header (size, type) and payload.

    Examples
    --------
    >>> pack(REQUEST_PROTOCOL_VERSION, struct.pack(">H", 2))
    b'\\x00\\x05V\\x00\\x02'
    """
    return _HEADER.pack(_HEADER.size + len(payload), ptype) + payload


def recipe_struct(types):
    """The ``struct.Struct`` of a data package's values for a list of RTDE type names."""
    try:
        return struct.Struct(">" + "".join(TYPES[t] for t in types))
    except KeyError as exc:
        raise RTDEError(f"unknown RTDE type {exc.args[0]!r}") from None


class PacketBuffer:
    """Split a byte stream into RTDE packages.

    Examples
    --------
    >>> buf = PacketBuffer()
    >>> data = pack(CONTROL_PACKAGE_START, b"\\x01")
    >>> buf.feed(data[:2]), buf.feed(data[2:])
    ([], [(83, b'\\x01')])
    """

    def __init__(self):
        self._data = bytearray()

    def feed(self, data):
        """Add bytes; return the complete packages as ``(type, payload)`` pairs."""
        self._data += data
        out = []
        while len(self._data) >= _HEADER.size:
            size, ptype = _HEADER.unpack_from(self._data)
            if size < _HEADER.size:
                raise RTDEError(f"package of impossible size {size}")
            if len(self._data) < size:
                break
            out.append((ptype, bytes(self._data[_HEADER.size:size])))
            del self._data[:size]
        return out


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
        self.host, self.port = host, int(port)
        self.variables = tuple(variables)
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
        deadline = time.monotonic() + timeout
        self._sock = socket.create_connection((self.host, self.port), timeout=timeout)
        try:
            self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            reply = self._request(REQUEST_PROTOCOL_VERSION, struct.pack(">H", PROTOCOL_VERSION),
                                  deadline)
            if reply[:1] != b"\x01":
                raise RTDEError(f"controller refused RTDE protocol version {PROTOCOL_VERSION}")
            reply = self._request(GET_URCONTROL_VERSION, b"", deadline)
            self.controller_version = struct.unpack(">IIII", reply[:16])
            names = ",".join(self.variables).encode()
            reply = self._request(CONTROL_PACKAGE_SETUP_OUTPUTS,
                                  struct.pack(">d", self.frequency) + names, deadline)
            self._recipe_id = reply[0]
            self.types = tuple(reply[1:].decode().split(","))
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
                    self._pending.append(body)
                # text messages and anything else during the handshake are skipped

    def _decode(self, body):
        if body[0] != self._recipe_id:
            raise RTDEError(f"data package of unknown recipe {body[0]}")
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
        """
        if self._sock is None:
            raise RTDEError("not connected")
        deadline = time.monotonic() + timeout
        newest = self._pending.pop() if self._pending else None
        self._pending.clear()
        self._sock.setblocking(False)
        try:
            while True:
                try:
                    data = self._sock.recv(65536)
                except (BlockingIOError, InterruptedError):
                    break
                if not data:
                    raise RTDEError("controller closed the RTDE connection")
                for rtype, body in self._buffer.feed(data):
                    if rtype == DATA_PACKAGE:
                        newest = body
        finally:
            self._sock.setblocking(True)
        while newest is None:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise RTDEError(f"no RTDE data package within {timeout:g} s")
            for rtype, body in self._recv_packages(remaining):
                if rtype == DATA_PACKAGE:
                    newest = body
        return self._decode(newest)
