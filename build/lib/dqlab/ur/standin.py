r"""A local stand-in for a UR controller, for tests and the book (not a robot, not URSim).

:class:`ControllerStandIn` starts a separate Python process that listens on **127.0.0.1
only**, on two ephemeral ports (or the ones asked for), and speaks just enough of a UR
controller's protocols for the client code of :mod:`dqlab.ur.client` to run unchanged:

- a **script sink** in place of the secondary interface (port 30002 on a robot): it reads
  URScript text, a single line or a ``def name(): ... end`` program; it understands
  ``movej``, ``movel``, ``servoj`` and ``stopj`` with positional or keyword arguments and
  ``p[...]`` poses, and runs them one after the other on a
  :class:`~dqlab.ur.client.KinematicBackend` arm (a new program replaces the running one, as
  on a controller). A program with anything else in it, or with a target the arm's safety
  checks refuse, is refused as a whole (a message in :meth:`ControllerStandIn.log`) and
  nothing moves. To each client it sends one binary message, a robot state with the arm's
  kinematics info (see :mod:`dqlab.ur.calibration`), as a controller does when a client
  connects, and nothing else.
- **RTDE output** (port 30004 on a robot; see :mod:`dqlab.ur.rtde`): protocol version
  negotiation (versions 1 and 2), the controller version (reported as 5.11.0.0 by default),
  output recipe set-up, start and pause, and data packages at the requested frequency (at
  most 500 Hz). It serves ``timestamp``, ``actual_q``, ``actual_qd``, ``actual_TCP_pose``,
  ``robot_mode`` and a few more from its arm (:data:`SERVED_VARIABLES`), and, as zeros, the
  electrical, force, I/O, payload and register outputs that ``ur_rtde``'s default recipe
  asks for (:data:`ZERO_VARIABLES`); any other name is answered ``NOT_FOUND`` and that
  recipe cannot be started. Input recipes are answered ``NOT_FOUND`` (nothing can be
  written, so ``ur_rtde``'s control interface does not work with it).

Time in the stand-in runs ``speedup`` times faster than real time, so a notebook does not
wait for a 3-second move. The process stops when the stand-in is stopped or its parent
goes away (its standard input closes); it never opens an outgoing connection.
"""

import ast
import json
import os
import re
import selectors
import socket
import struct
import subprocess
import sys
import tempfile
import time

import numpy as np

from . import rtde
from .calibration import kinematics_info_from_robot, message_from_kinematics_info
from .client import HOME, KinematicBackend, SecondaryInterfaceBackend

__all__ = ["ControllerStandIn", "SERVED_VARIABLES", "ZERO_VARIABLES", "parse_urscript"]

LOOPBACK = "127.0.0.1"

#: RTDE outputs the stand-in serves with the arm's state: name -> (RTDE type, value from the
#: arm's URState)
SERVED_VARIABLES = {
    "timestamp": ("DOUBLE", lambda s: s.time),
    "actual_q": ("VECTOR6D", lambda s: s.q),
    "actual_qd": ("VECTOR6D", lambda s: s.qd),
    "target_q": ("VECTOR6D", lambda s: s.q),
    "target_qd": ("VECTOR6D", lambda s: s.qd),
    "actual_TCP_pose": ("VECTOR6D", lambda s: s.tcp_pose),
    "target_TCP_pose": ("VECTOR6D", lambda s: s.tcp_pose),
    "robot_mode": ("INT32", lambda s: s.robot_mode),
    "joint_mode": ("VECTOR6INT32", lambda s: [253] * 6),    # 253: joint running
    "safety_mode": ("INT32", lambda s: 1),                  # 1: normal
    "safety_status_bits": ("UINT32", lambda s: 1),          # bit 0: normal mode
    "robot_status_bits": ("UINT32", lambda s: 1),           # bit 0: power on
    "runtime_state": ("UINT32", lambda s: 2 if np.any(s.qd != 0) else 1),  # playing/stopped
    "speed_scaling": ("DOUBLE", lambda s: 1.0),
    "target_speed_fraction": ("DOUBLE", lambda s: 1.0),
}

#: RTDE outputs served as zeros: the stand-in's arm has no accelerations, currents, torques,
#: forces, temperatures, voltages, I/O, payload or registers. (They are served so that
#: ``ur_rtde``'s receive interface with its default recipe can connect; do not read them.)
ZERO_VARIABLES = {
    **dict.fromkeys(["target_qdd", "target_current", "target_moment", "actual_current",
                     "joint_control_output", "actual_TCP_speed", "target_TCP_speed",
                     "actual_TCP_force", "joint_temperatures", "actual_joint_voltage",
                     "ft_raw_wrench", "payload_inertia"], "VECTOR6D"),
    **dict.fromkeys(["actual_tool_accelerometer", "payload_cog"], "VECTOR3D"),
    **dict.fromkeys(["actual_execution_time", "actual_momentum", "actual_main_voltage",
                     "actual_robot_voltage", "actual_robot_current", "payload",
                     "standard_analog_input0", "standard_analog_input1",
                     "standard_analog_output0", "standard_analog_output1"], "DOUBLE"),
    **dict.fromkeys(["actual_digital_input_bits", "actual_digital_output_bits"], "UINT64"),
    **dict.fromkeys(["output_bit_registers0_to_31", "output_bit_registers32_to_63"],
                    "UINT32"),
    **{f"output_int_register_{k}": "INT32" for k in range(48)},
    **{f"output_double_register_{k}": "DOUBLE" for k in range(48)},
}
_ZEROS = {"VECTOR6D": [0.0] * 6, "VECTOR3D": [0.0] * 3, "DOUBLE": 0.0, "UINT64": 0,
          "UINT32": 0, "INT32": 0}


def _output(name):
    """(RTDE type, value function) of an output variable, or None if not served."""
    if name in SERVED_VARIABLES:
        return SERVED_VARIABLES[name]
    if name in ZERO_VARIABLES:
        rtype = ZERO_VARIABLES[name]
        return rtype, lambda s: _ZEROS[rtype]
    return None


_SIGNATURES = {
    "movej": ("q", "a", "v", "t", "r"),
    "movel": ("pose", "a", "v", "t", "r"),
    "servoj": ("q", "a", "v", "t", "lookahead_time", "gain"),
    "stopj": ("a",),
}


def parse_urscript(text):
    """The motion commands of a URScript line or ``def ... end`` program.

    Parameters
    ----------
    text : str

    Returns
    -------
    list of (name, target, kwargs)
        As :meth:`dqlab.ur.client.KinematicBackend.run` takes them.

    Raises
    ------
    ValueError
        For anything but ``movej``, ``movel``, ``servoj``, ``stopj`` calls with literal
        arguments (naming the line).

    Examples
    --------
    >>> parse_urscript("movel(p[0.2, 0, 0.3, 0, 3.1, 0], 1.2, v=0.25)")
    [('movel', [0.2, 0, 0.3, 0, 3.1, 0], {'a': 1.2, 'v': 0.25})]
    """
    lines = [ln.strip() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln and not ln.startswith("#")]
    if lines and lines[0].startswith("def "):
        if not re.fullmatch(r"def\s+\w+\(\)\s*:", lines[0]) or lines[-1] != "end":
            raise ValueError("a program must be 'def name():' ... 'end'")
        lines = lines[1:-1]
    commands = []
    for k, line in enumerate(lines, start=1):
        try:
            node = ast.parse(re.sub(r"\bp\[", "[", line), mode="eval").body
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                    and node.func.id in _SIGNATURES):
                raise ValueError("not a movej, movel, servoj or stopj call")
            names = _SIGNATURES[node.func.id]
            if len(node.args) > len(names):
                raise ValueError("too many arguments")
            values = dict(zip(names, (ast.literal_eval(a) for a in node.args), strict=False))
            for kw in node.keywords:
                if kw.arg not in names or kw.arg in values:
                    raise ValueError(f"unexpected argument {kw.arg!r}")
                values[kw.arg] = ast.literal_eval(kw.value)
        except (SyntaxError, ValueError) as exc:
            raise ValueError(f"line {k} {line!r}: {exc}") from None
        target = values.pop(names[0], None) if names[0] != "a" else None
        if target is None and names[0] != "a":
            raise ValueError(f"line {k} {line!r}: no target")
        commands.append((node.func.id, target, values))
    return commands


class ControllerStandIn:
    """Start and stop a local stand-in for a UR controller (see the module docstring).

    Use it as a context manager; inside, :meth:`backend` gives a
    :class:`~dqlab.ur.client.SecondaryInterfaceBackend` connected to it.

    Parameters
    ----------
    model : str
        Name of a function of :mod:`dqlab.models` that builds the arm (default ``"ur3"``).
    q0 : array_like, shape (6,), optional
        Initial joints, rad (default :data:`dqlab.ur.client.HOME`).
    speedup : float
        Simulated seconds per real second.
    secondary_port, rtde_port : int
        0 (default): an ephemeral port chosen by the system.
    controller_version : tuple of 4 int
        Reported over RTDE.
    start_timeout : float
        s to wait for the process to be ready.

    Attributes
    ----------
    host : str
        Always ``"127.0.0.1"``.
    secondary_port, rtde_port : int
        The ports it listens on (once started).

    Examples
    --------
    >>> from dqlab.ur import ControllerStandIn, URClient
    >>> with ControllerStandIn(speedup=20) as standin:
    ...     with URClient(standin.backend()) as ur:
    ...         state = ur.movej([0.2, -1.4, 0.3, -1.6, 0.1, 0.0])
    >>> state.q.round(9) + 0.0
    array([ 0.2, -1.4,  0.3, -1.6,  0.1,  0. ])
    >>> standin.running
    False
    """

    host = LOOPBACK

    def __init__(self, model="ur3", q0=None, *, speedup=1.0, secondary_port=0, rtde_port=0,
                 controller_version=(5, 11, 0, 0), start_timeout=30.0):
        q0 = HOME if q0 is None else q0
        self._config = {"model": str(model), "q0": [float(x) for x in np.ravel(q0)],
                        "speedup": float(speedup), "secondary_port": int(secondary_port),
                        "rtde_port": int(rtde_port),
                        "controller_version": [int(v) for v in controller_version]}
        self.start_timeout = float(start_timeout)
        self.secondary_port = self.rtde_port = None
        self._proc = None
        self._log_file = None
        self._log_text = ""

    @property
    def running(self):
        """True while the stand-in's process is alive."""
        return self._proc is not None and self._proc.poll() is None

    @property
    def pid(self):
        return None if self._proc is None else self._proc.pid

    def start(self):
        """Start the process and wait until it listens."""
        if self._proc is not None:
            raise RuntimeError("the stand-in is already started")
        import dqlab

        env = dict(os.environ)
        root = os.path.dirname(os.path.dirname(os.path.abspath(dqlab.__file__)))
        env["PYTHONPATH"] = os.pathsep.join([root] + [p for p in env.get(
            "PYTHONPATH", "").split(os.pathsep) if p])
        code = "import sys; from dqlab.ur.standin import _serve; _serve(sys.argv[1])"
        self._log_file = tempfile.TemporaryFile()
        self._log_text = ""
        self._proc = subprocess.Popen(
            [sys.executable, "-c", code, json.dumps(self._config)], stdin=subprocess.PIPE,
            stdout=subprocess.PIPE, stderr=self._log_file, env=env)
        try:
            line = self._read_ready()
            _, sec, rt = line.split()
            self.secondary_port, self.rtde_port = int(sec), int(rt)
        except Exception as exc:
            self.stop()
            raise RuntimeError(f"the stand-in did not start ({exc}); its log:\n"
                               f"{self._log_text}") from exc
        except BaseException:
            self.stop()
            raise
        return self

    def _read_ready(self):
        sel = selectors.DefaultSelector()
        sel.register(self._proc.stdout, selectors.EVENT_READ)
        try:
            if not sel.select(self.start_timeout):
                raise TimeoutError(f"the stand-in did not start within {self.start_timeout} s")
        finally:
            sel.close()
        line = self._proc.stdout.readline().decode()
        if not line.startswith("READY"):
            raise RuntimeError(f"exit code {self._proc.wait(5)}")
        return line

    def stop(self, timeout=5.0):
        """Stop the process (idempotent): ask, then wait, then kill if it must."""
        proc, self._proc = self._proc, None
        if proc is None:
            return
        try:
            if proc.poll() is None:
                try:
                    proc.stdin.write(b"stop\n")
                    proc.stdin.flush()
                except (BrokenPipeError, OSError):
                    pass
                try:
                    proc.wait(timeout)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait(timeout)
        finally:
            for pipe in (proc.stdin, proc.stdout):
                if pipe is not None:
                    pipe.close()
            self._log_text = self.log()
            self._log_file.close()
            self._log_file = None

    def log(self):
        """What the stand-in reported (refused programs, dropped clients), as text."""
        if self._log_file is None:
            return self._log_text
        self._log_file.flush()
        self._log_file.seek(0)
        return self._log_file.read().decode("utf-8", errors="replace")

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()

    def backend(self, **kwargs):
        """A :class:`~dqlab.ur.client.SecondaryInterfaceBackend` for this stand-in."""
        if not self.running:
            raise RuntimeError("the stand-in is not running")
        return SecondaryInterfaceBackend(self.host, self.secondary_port,
                                         rtde_port=self.rtde_port, **kwargs)


# --------------------------------------------------------------------------------------
# The server (runs in the stand-in's own process)


class _RTDEConnection:
    def __init__(self, sock):
        self.sock = sock
        self.buffer = rtde.PacketBuffer()
        self.version = 1
        self.recipe = None     # (names, struct) once set up and complete
        self.period = 1.0 / 125.0
        self.started = False
        self.next_due = 0.0

    def handle(self, ptype, body, controller_version):
        reply = None
        if os.environ.get("DQLAB_STANDIN_DEBUG"):
            print("RTDE <-", chr(ptype), body[:200], file=sys.stderr)
        if ptype == rtde.REQUEST_PROTOCOL_VERSION:
            (version,) = struct.unpack(">H", body[:2])
            ok = version in (1, 2)
            if ok:
                self.version = version
            reply = bytes([ok])
        elif ptype == rtde.GET_URCONTROL_VERSION:
            reply = struct.pack(">IIII", *controller_version)
        elif ptype == rtde.CONTROL_PACKAGE_SETUP_OUTPUTS:
            if self.version >= 2:
                (freq,) = struct.unpack(">d", body[:8])
                body = body[8:]
                if freq > 0:
                    self.period = 1.0 / min(freq, 500.0)
            names = body.decode().rstrip(",").split(",")   # ur_rtde ends the list with ","
            outputs = [_output(n) for n in names]
            types = [o[0] if o else "NOT_FOUND" for o in outputs]
            found = "NOT_FOUND" not in types
            self.recipe = ([o[1] for o in outputs], rtde.recipe_struct(types)) if found else None
            text = ",".join(types).encode()
            reply = (bytes([1 if found else 0]) + text) if self.version >= 2 else text
        elif ptype == rtde.CONTROL_PACKAGE_SETUP_INPUTS:
            names = body.decode().rstrip(",").split(",")
            reply = bytes([0]) + ",".join(["NOT_FOUND"] * len(names)).encode()
        elif ptype == rtde.CONTROL_PACKAGE_START:
            self.started = self.recipe is not None
            self.next_due = time.monotonic()
            reply = bytes([self.started])
        elif ptype == rtde.CONTROL_PACKAGE_PAUSE:
            self.started = False
            reply = b"\x01"
        # text messages and input data packages from the client are ignored
        if reply is not None:
            self.sock.sendall(rtde.pack(ptype, reply))

    def data_package(self, state):
        getters, st = self.recipe
        flat = []
        for get in getters:
            value = get(state)
            flat.extend(np.ravel(value).tolist() if np.ndim(value) else [value])
        head = bytes([1]) if self.version >= 2 else b""
        return rtde.pack(rtde.DATA_PACKAGE, head + st.pack(*flat))


def _serve(config_json):
    """Run the stand-in until told to stop (the body of the stand-in's process)."""
    from .. import models

    config = json.loads(config_json)
    robot = getattr(models, config["model"])()
    arm = KinematicBackend(robot, config["q0"], speedup=config["speedup"])
    kinematics_message = message_from_kinematics_info(kinematics_info_from_robot(robot))
    arm.connect()
    version = tuple(config["controller_version"])
    sel = selectors.DefaultSelector()
    listeners = []
    for kind in ("secondary", "rtde"):
        srv = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        srv.bind((LOOPBACK, config[f"{kind}_port"]))
        srv.listen(4)
        srv.setblocking(False)
        sel.register(srv, selectors.EVENT_READ, ("listen", kind))
        listeners.append(srv)
    control = sys.stdin.buffer.fileno()
    sel.register(control, selectors.EVENT_READ, ("control", None))
    sys.stdout.write(f"READY {listeners[0].getsockname()[1]} {listeners[1].getsockname()[1]}\n")
    sys.stdout.flush()
    texts = {}      # secondary-interface socket -> text received so far
    streams = {}    # RTDE socket -> _RTDEConnection

    def drop(sock):
        sel.unregister(sock)
        texts.pop(sock, None)
        streams.pop(sock, None)
        sock.close()

    def run_text(sock):
        buf = texts[sock]
        while "\n" in buf:
            if buf.lstrip().startswith("def "):
                m = re.search(r"^\s*end\s*$", buf, flags=re.MULTILINE)
                if not m:
                    break
                program, buf = buf[:m.end()], buf[m.end():]
            else:
                program, buf = buf.split("\n", 1)
            if program.strip():
                try:
                    arm.run(parse_urscript(program))
                except ValueError as exc:
                    print(f"controller stand-in: program refused: {exc}", file=sys.stderr)
        texts[sock] = buf

    running = True
    try:
        while running:
            now = time.monotonic()
            due = [c.next_due for c in streams.values() if c.started]
            timeout = max(min(due) - now, 0.0) if due else 0.05
            for key, _ in sel.select(min(timeout, 0.05)):
                role, kind = key.data
                if role == "control":
                    data = os.read(control, 1024)
                    if not data or b"stop" in data:
                        running = False
                elif role == "listen":
                    try:
                        conn, _ = key.fileobj.accept()
                    except BlockingIOError:
                        continue
                    conn.settimeout(2.0)      # a client that stops reading is dropped
                    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                    if kind == "secondary":
                        texts[conn] = ""
                        conn.sendall(kinematics_message)    # what a controller sends first
                    else:
                        streams[conn] = _RTDEConnection(conn)
                    sel.register(conn, selectors.EVENT_READ, ("client", kind))
                else:
                    sock = key.fileobj
                    try:
                        data = sock.recv(65536)
                    except OSError:
                        data = b""
                    if not data:
                        drop(sock)
                    elif kind == "secondary":
                        texts[sock] += data.decode("utf-8", errors="replace")
                        run_text(sock)
                    else:
                        conn = streams[sock]
                        try:
                            for ptype, body in conn.buffer.feed(data):
                                conn.handle(ptype, body, version)
                        except (rtde.RTDEError, struct.error, OSError) as exc:
                            print(f"controller stand-in: RTDE client dropped: {exc}",
                                  file=sys.stderr)
                            drop(sock)
            now = time.monotonic()
            ready = [c for c in streams.values() if c.started and now >= c.next_due]
            if ready:
                state = arm.read_state()
                for conn in ready:
                    try:
                        conn.sock.sendall(conn.data_package(state))
                        conn.next_due = max(conn.next_due + conn.period, now)
                    except OSError:
                        drop(conn.sock)
    finally:
        for sock in list(texts) + list(streams):
            sock.close()
        for srv in listeners:
            srv.close()
        sel.close()
