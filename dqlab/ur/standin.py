r"""A local stand-in for a UR controller, for tests and the book (not a robot, not URSim).

:class:`ControllerStandIn` starts a separate Python process that listens on **127.0.0.1
only**, on two ephemeral ports (or the ones asked for), and speaks just enough of a UR
controller's protocols for the client code of :mod:`dqlab.ur.client` to run unchanged:

- a **script sink** in place of the secondary interface (port 30002 on a robot): it reads
  URScript text, a single line or a ``def name(): ... end`` program; it understands
  ``movej``, ``movel``, ``servoj`` and ``stopj`` with positional or keyword arguments and
  ``p[...]`` poses (numbers and flat lists of numbers only), and runs them one after the
  other on a :class:`~dqlab.ur.kinematic_arm.KinematicBackend` arm (a new program replaces
  the running one, as on a controller). The whole program is planned and checked first
  (:func:`dqlab.ur.script.plan_program`); a program with anything else in it, or with any
  line the checks refuse, is refused as a whole (a message in
  :meth:`ControllerStandIn.log`) and nothing moves. The **primary interface** (port 30001 on
  a robot) does the same. On both, as a controller, it sends the version message when a
  client connects, then a robot state at 10 Hz: robot mode data, joint data, cartesian info
  and the arm's kinematics info, in the layout of UR's Client Library (URSim 5.8, e-Series;
  :mod:`dqlab.ur.secondary`, where they are encoded, and :mod:`dqlab.ur.calibration`). A
  client that does not read misses states (none is queued behind an unsent one) and is never
  blocked on. The arm is the model's nominal one (joint checksums ``0xFFFFFFFF``, as the
  simulator reports), or, with ``calibration=``, the model with a calibration's corrections:
  then the arm moves, reports its TCP and sends its kinematics info as a calibrated
  controller does.
- **RTDE output** (port 30004 on a robot; see :mod:`dqlab.ur.rtde`): protocol version
  negotiation (versions 1 and 2), the controller version (reported as 5.11.0.0 by default),
  output recipe set-up, start and pause, and data packages at the requested frequency (at
  most 500 Hz). It serves ``timestamp``, ``actual_q``, ``actual_qd``, ``actual_TCP_pose``,
  ``robot_mode`` and a few more from its arm (:data:`SERVED_VARIABLES`), and, as zeros, the
  electrical, force, I/O, payload and register outputs that ``ur_rtde``'s default recipe
  asks for (:data:`ZERO_VARIABLES`); any other name is answered ``NOT_FOUND`` and that
  recipe cannot be started. Input recipes are answered ``NOT_FOUND`` (nothing can be
  written, so ``ur_rtde``'s control interface does not work with it).

Whatever a client sends, the stand-in keeps serving: a malformed RTDE package drops that
client, text that never completes a program (:data:`MAX_PROGRAM_SIZE`) too, each with a
message in the log. Time in the stand-in runs ``speedup`` times faster than real time, so a
notebook does not wait for a 3-second move. The process stops when the stand-in is stopped
or its parent goes away (its standard input closes); it never opens an outgoing connection.
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
import zlib

import numpy as np

from .._checks import check_scalar, real_array, short_repr
from . import rtde
from ._args import positive_number
from .calibration import (
    ROBOT_STATE,
    CalibrationConf,
    check_identifiers,
    kinematics_info_from_robot,
    message_from_kinematics_info,
    robot_from_corrections,
)
from .kinematic_arm import KinematicBackend
from .poses import pose_from_transform
from .secondary import (
    CartesianInfo,
    JointData,
    RobotModeData,
    SecondaryInterfaceBackend,
    pack_cartesian_info,
    pack_joint_data,
    pack_message,
    pack_robot_mode_data,
    version_message,
)
from .state import HOME

__all__ = ["ControllerStandIn", "SERVED_VARIABLES", "ZERO_VARIABLES", "parse_urscript",
           "MAX_PROGRAM_SIZE", "STATE_PERIOD"]

LOOPBACK = "127.0.0.1"

#: Longest URScript text the stand-in holds for one client, bytes; a client that sends more
#: without completing a program is dropped (with a message in the log).
MAX_PROGRAM_SIZE = 1 << 20

#: Period of the robot-state stream of the primary and secondary interfaces, s (10 Hz).
STATE_PERIOD = 0.1

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


def _literal(node, line):
    """A URScript argument: a number, or a flat list of numbers (``p[...]`` for a pose)."""
    try:
        value = ast.literal_eval(node)
    except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
        raise ValueError("an argument is not a literal number or list of numbers") from None

    def number(x):
        return isinstance(x, (int, float)) and not isinstance(x, bool)

    if number(value) or (isinstance(value, list) and all(number(x) for x in value)):
        return value
    raise ValueError(f"an argument must be a number or a list of numbers, got "
                     f"{type(value).__name__} {str(value)[:40]!r}")


def parse_urscript(text):
    """The motion commands of a URScript line or ``def ... end`` program.

    Parameters
    ----------
    text : str

    Returns
    -------
    list of (name, target, kwargs)
        As :meth:`dqlab.ur.kinematic_arm.KinematicBackend.run` takes them: targets are lists
        of numbers, arguments numbers.

    Raises
    ------
    ValueError
        For anything but ``movej``, ``movel``, ``servoj``, ``stopj`` calls whose arguments
        are literal numbers or flat lists of numbers (naming the line).

    Examples
    --------
    >>> parse_urscript("movel(p[0.2, 0, 0.3, 0, 3.1, 0], 1.2, v=0.25)")
    [('movel', [0.2, 0, 0.3, 0, 3.1, 0], {'a': 1.2, 'v': 0.25})]
    >>> parse_urscript("movej('abc')")
    Traceback (most recent call last):
    ...
    ValueError: line 1 "movej('abc')": an argument must be a number or a list of numbers, ...
    """
    if not isinstance(text, str):
        raise TypeError(f"text must be a str, got {type(text).__name__}")
    lines = [ln.strip() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln and not ln.startswith("#")]
    if lines and lines[0].startswith("def "):
        if not re.fullmatch(r"def\s+\w+\(\)\s*:", lines[0]) or lines[-1] != "end":
            raise ValueError("a program must be 'def name():' ... 'end'")
        lines = lines[1:-1]
    if not lines:
        raise ValueError("no command")
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
            values = dict(zip(names, (_literal(a, line) for a in node.args), strict=False))
            for kw in node.keywords:
                if kw.arg not in names or kw.arg in values:
                    raise ValueError(f"unexpected argument {kw.arg!r}")
                values[kw.arg] = _literal(kw.value, line)
        except (SyntaxError, ValueError, MemoryError, RecursionError) as exc:
            message = exc.msg if isinstance(exc, SyntaxError) else str(exc) or \
                type(exc).__name__
            raise ValueError(f"line {k} {line[:80]!r}: {message}") from None
        target = values.pop(names[0], None) if names[0] != "a" else None
        if target is None and names[0] != "a":
            raise ValueError(f"line {k} {line[:80]!r}: no target")
        commands.append((node.func.id, target, values))
    return commands


class ControllerStandIn:
    r"""Start and stop a local stand-in for a UR controller (see the module docstring).

    Use it as a context manager; inside, :meth:`backend` gives a
    :class:`~dqlab.ur.secondary.SecondaryInterfaceBackend` connected to it.

    Parameters
    ----------
    model : str
        Name of a function of :mod:`dqlab.models` that builds the arm (default ``"ur3"``).
    q0 : array_like, shape (6,), optional
        Initial joints, rad (default :data:`dqlab.ur.state.HOME`).
    speedup : float
        Simulated seconds per real second.
    primary_port, secondary_port, rtde_port : int
        0 (default): an ephemeral port chosen by the system.
    controller_version : tuple of 4 int
        Reported over RTDE.
    start_timeout : float
        s to wait for the process to be ready.
    calibration : dqlab.ur.calibration.CalibrationConf, optional
        The arm's calibration, as the controller's ``calibration.conf`` holds it: the
        corrections of :math:`\theta_i, a_i, d_i, \alpha_i` added to the model's published
        parameters (:func:`dqlab.ur.calibration.robot_from_corrections`), the joints'
        checksums and the calibration status. The stand-in's arm is then that calibrated
        arm, and its kinematics info carries its parameters, the checksums (where the
        corrections have none, the CRC-32 of each joint's four corrections: UR's own
        checksum is not published) and the status (default 2, linearised). Default: the
        nominal arm, uncalibrated.

    Attributes
    ----------
    host : str
        Always ``"127.0.0.1"``.
    primary_port, secondary_port, rtde_port : int
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

    A calibrated arm, whose calibration a client reads back:

    >>> from dqlab.ur.calibration import CalibrationConf, read_kinematics_info
    >>> factory = CalibrationConf(delta_theta=(0, 0.001, 0, 0, 0, 0), delta_a=(0,) * 6,
    ...                           delta_d=(0,) * 6, delta_alpha=(0,) * 6)
    >>> with ControllerStandIn("ur5e", calibration=factory) as standin:
    ...     info = read_kinematics_info(standin.host, standin.secondary_port)
    >>> info.theta[1], info.calibration_status
    (0.001, 2)
    """

    host = LOOPBACK

    def __init__(self, model="ur3", q0=None, *, speedup=1.0, secondary_port=0, rtde_port=0,
                 primary_port=0,
                 controller_version=(5, 11, 0, 0), start_timeout=30.0, calibration=None):
        from .. import models

        if not isinstance(model, str) or not callable(getattr(models, model, None)) \
                or model.startswith("_"):
            raise ValueError(f"model must name a function of dqlab.models, got "
                             f"{short_repr(model)}")
        q0 = HOME if q0 is None else q0
        q0 = real_array(q0, "q0")
        if q0.shape != (6,) or not np.all(np.isfinite(q0)):
            raise ValueError(f"q0 must be 6 finite joint angles, got "
                             f"{q0.tolist() if q0.shape == (6,) else f'shape {q0.shape}'}")
        version = tuple(controller_version) if isinstance(controller_version,
                                                          (tuple, list)) else ()
        if len(version) != 4 or not all(isinstance(v, (int, np.integer)) and
                                        not isinstance(v, bool) and 0 <= v < 2 ** 32
                                        for v in version):
            raise ValueError(f"controller_version must be 4 ints (major, minor, bugfix, build),"
                             f" got {short_repr(controller_version)}")
        if calibration is not None:
            if not isinstance(calibration, CalibrationConf):
                raise TypeError(f"calibration must be a dqlab.ur.calibration.CalibrationConf "
                                f"(or None), got {type(calibration).__name__}")
            # refused here, with the field, before any process starts
            robot_from_corrections(calibration, getattr(models, model)(),
                                   source="calibration")
            calibration = _served_calibration(calibration)
        self._config = {"model": model, "q0": q0.tolist(), "calibration": calibration,
                        "speedup": positive_number(speedup, "speedup"),
                        "primary_port": _port(primary_port, "primary_port"),
                        "secondary_port": _port(secondary_port, "secondary_port"),
                        "rtde_port": _port(rtde_port, "rtde_port"),
                        "controller_version": [int(v) for v in version]}
        self.start_timeout = positive_number(start_timeout, "start_timeout")
        self.primary_port = self.secondary_port = self.rtde_port = None
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
            _, primary, secondary, rt = line.split()
            self.primary_port, self.secondary_port, self.rtde_port = (
                int(primary), int(secondary), int(rt))
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
        """What the stand-in reported (refused programs, dropped clients), as text.

        The stand-in writes its log through a copy of this file's descriptor, which shares
        its offset: the log is read with ``os.pread``, which leaves the offset alone (a seek
        here would send the stand-in's next line over the log's first ones)."""
        if self._log_file is None:
            return self._log_text
        fd = self._log_file.fileno()
        if hasattr(os, "pread"):
            data = os.pread(fd, os.fstat(fd).st_size, 0)
        else:                                   # (no pread: seek, read, and back to the end)
            self._log_file.seek(0)
            data = self._log_file.read()
        return data.decode("utf-8", errors="replace")

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()

    def backend(self, **kwargs):
        """A :class:`~dqlab.ur.secondary.SecondaryInterfaceBackend` for this stand-in, for its
        arm: ``robot`` defaults to the stand-in's (the model, with its calibration if it has
        one), which :class:`~dqlab.ur.client.URClient` then takes; other arguments are passed
        on."""
        if not self.running:
            raise RuntimeError("the stand-in is not running")
        if "robot" not in kwargs:
            kwargs["robot"] = self.robot
        return SecondaryInterfaceBackend(self.host, self.secondary_port,
                                         rtde_port=self.rtde_port, **kwargs)

    @property
    def robot(self):
        """The stand-in's arm, as a :class:`~dqlab.robot.Robot` (built on each call)."""
        return _arm_robot(self._config)


# --------------------------------------------------------------------------------------
# The server (runs in the stand-in's own process)


def _port(value, name):
    """A TCP port to listen on: an int in 0..65535, 0 for any free port."""
    return check_scalar(value, f"{name} (a TCP port, 0: any free port)", minimum=0,
                        maximum=65535, integer=True)


def _names(body, what):
    """Comma-separated RTDE variable names (``ur_rtde`` ends the list with a comma)."""
    try:
        text = body.decode("ascii")
    except UnicodeDecodeError:
        raise rtde.RTDEError(f"{what}: variable names must be ASCII text") from None
    return text.rstrip(",").split(",")


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
        """Answer one package; ``RTDEError`` for a malformed one (the client is dropped)."""
        reply = None
        if os.environ.get("DQLAB_STANDIN_DEBUG"):
            print("RTDE <-", chr(ptype), body[:200], file=sys.stderr)
        if ptype == rtde.REQUEST_PROTOCOL_VERSION:
            if len(body) != 2:
                raise rtde.RTDEError(f"protocol version request of {len(body)} bytes, not 2")
            (version,) = struct.unpack(">H", body)
            ok = version in (1, 2)
            if ok:
                self.version = version
            reply = bytes([ok])
        elif ptype == rtde.GET_URCONTROL_VERSION:
            reply = struct.pack(">IIII", *controller_version)
        elif ptype == rtde.CONTROL_PACKAGE_SETUP_OUTPUTS:
            if self.version >= 2:
                if len(body) < 8:
                    raise rtde.RTDEError("output set-up without its frequency")
                (freq,) = struct.unpack(">d", body[:8])
                body = body[8:]
                if freq > 0:
                    self.period = 1.0 / min(freq, 500.0)
            outputs = [_output(n) for n in _names(body, "output set-up")]
            types = [o[0] if o else "NOT_FOUND" for o in outputs]
            found = "NOT_FOUND" not in types
            recipe = rtde.recipe_struct(types) if found else None
            if recipe is not None and recipe.size + 4 > rtde.MAX_PACKAGE_SIZE:
                raise rtde.RTDEError(f"a recipe of {len(types)} outputs does not fit in a "
                                     "data package")
            self.recipe = ([o[1] for o in outputs], recipe) if found else None
            text = ",".join(types).encode()
            reply = (bytes([1 if found else 0]) + text) if self.version >= 2 else text
        elif ptype == rtde.CONTROL_PACKAGE_SETUP_INPUTS:
            names = _names(body, "input set-up")
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


def _served_calibration(calibration):
    """A calibration as the stand-in's configuration holds it (JSON): the corrections as
    floats, the checksums (the CRC-32 of each joint's four corrections where there are
    none) and the status (2, linearised, where there is none)."""
    served = {k: [float(v) for v in getattr(calibration, k)] for k in
              ("delta_theta", "delta_a", "delta_d", "delta_alpha")}
    checksum = calibration.joint_checksum
    if checksum is None:
        checksum = [zlib.crc32(struct.pack(">4d", *(served[k][i] for k in served)))
                    for i in range(6)]
    status = 2 if calibration.calibration_status is None else calibration.calibration_status
    checksum, status = check_identifiers(checksum, status, names=(
        "calibration.joint_checksum", "calibration.calibration_status"))
    served["joint_checksum"] = list(checksum)
    served["calibration_status"] = status
    return served


def _arm_robot(config):
    """The stand-in's arm: the model, with the calibration's corrections if it has one (the
    corrected DH parameters; the model's joint limits, speeds, inertias, base and tool)."""
    from .. import models
    from ..robot import Link, Robot

    nominal = getattr(models, config["model"])()
    if config.get("calibration") is None:
        return nominal
    corrected = robot_from_corrections(CalibrationConf(**config["calibration"]), nominal)
    links = [Link(a=c.a, alpha=c.alpha, d=c.d, theta_offset=c.theta_offset, joint=n.joint,
                  limits=n.limits, name=n.name, inertia=c.inertia, max_speed=n.max_speed,
                  max_torque=n.max_torque)
             for c, n in zip(corrected.links, nominal.links, strict=True)]
    return Robot(links, convention=nominal.convention, base=nominal.base, tool=nominal.tool,
                 name=f"{nominal.name} (calibrated)")


def _kinematics_package(config, robot):
    """The arm's kinematics-info sub-package (header included): the calibrated parameters,
    checksums and status with a calibration, else the nominal ones, uncalibrated."""
    calibration = config.get("calibration")
    if calibration is None:
        info = kinematics_info_from_robot(robot)
    else:
        info = kinematics_info_from_robot(robot, checksum=calibration["joint_checksum"],
                                          calibration_status=calibration["calibration_status"])
    return message_from_kinematics_info(info)[5:]


def _state_message(state, tcp_offset, kinematics, moving):
    """A robot-state message of the arm's state (a URState): robot mode data, joint data,
    cartesian info and the kinematics info, as a controller sends them at 10 Hz. (The one
    place where the stand-in encodes that stream, with :mod:`dqlab.ur.secondary`.)"""
    mode = RobotModeData(timestamp=int(state.time * 1e6), is_real_robot_connected=True,
                         is_real_robot_enabled=True, is_robot_power_on=True,
                         is_emergency_stopped=False, is_protective_stopped=False,
                         is_program_running=moving, is_program_paused=False,
                         robot_mode=state.robot_mode, control_mode=0,
                         target_speed_fraction=1.0, speed_scaling=1.0,
                         target_speed_fraction_limit=1.0)
    joints = JointData(q_actual=tuple(state.q), q_target=tuple(state.q),
                       qd_actual=tuple(state.qd), i_actual=(0.0,) * 6, v_actual=(48.0,) * 6,
                       t_motor=(30.0,) * 6, t_micro=(30.0,) * 6, joint_mode=(253,) * 6)
    cartesian = CartesianInfo(tcp_pose=tuple(state.tcp_pose), tcp_offset=tcp_offset)
    return pack_message(ROBOT_STATE, pack_robot_mode_data(mode) + pack_joint_data(joints)
                        + pack_cartesian_info(cartesian) + kinematics)


def _log(message):
    print(f"controller stand-in: {message}", file=sys.stderr, flush=True)


def _serve(config_json):
    """Run the stand-in until told to stop (the body of the stand-in's process).

    Whatever a client sends -- any text, any bytes -- the stand-in answers, refuses or drops
    that client with a message in its log, and keeps serving: a program is refused as a
    whole (nothing moves) when any of its lines fails, for any reason.
    """
    config = json.loads(config_json)
    robot = _arm_robot(config)
    arm = KinematicBackend(robot, config["q0"], speedup=config["speedup"])
    arm.connect()
    greeting = version_message(config["controller_version"])
    kinematics = _kinematics_package(config, robot)
    tcp_offset = (0.0,) * 6 if robot.tool is None else tuple(pose_from_transform(robot.tool))
    version = tuple(config["controller_version"])
    sel = selectors.DefaultSelector()
    listeners = []
    for kind in ("primary", "secondary", "rtde"):
        srv = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        srv.bind((LOOPBACK, config[f"{kind}_port"]))
        srv.listen(4)
        srv.setblocking(False)
        sel.register(srv, selectors.EVENT_READ, ("listen", kind))
        listeners.append(srv)
    control = sys.stdin.buffer.fileno()
    sel.register(control, selectors.EVENT_READ, ("control", None))
    ports = " ".join(str(srv.getsockname()[1]) for srv in listeners)
    sys.stdout.write(f"READY {ports}\n")
    sys.stdout.flush()
    texts = {}      # primary/secondary-interface socket -> text received so far
    outgoing = {}   # primary/secondary-interface socket -> bytes not yet sent
    streams = {}    # RTDE socket -> _RTDEConnection
    next_state = time.monotonic()

    def drop(sock, why=None):
        if why:
            _log(why)
        try:
            sel.unregister(sock)
        except (KeyError, ValueError):
            pass
        texts.pop(sock, None)
        outgoing.pop(sock, None)
        streams.pop(sock, None)
        sock.close()

    def run_program(program):
        try:
            commands = parse_urscript(program)
            single_servo = len(commands) == 1 and commands[0][0] == "servoj" and \
                not program.lstrip().startswith("def ")
            arm.run(commands, streaming=single_servo)
        except Exception as exc:              # any failure refuses the program, nothing moves
            _log(f"program refused: {type(exc).__name__}: {exc}")

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
                run_program(program)
        texts[sock] = buf
        if len(buf) > MAX_PROGRAM_SIZE:
            drop(sock, f"script client dropped: {len(buf)} bytes without a complete program")

    def flush(sock):
        """Send what the socket takes now; listen for writability while bytes are left."""
        pending = outgoing[sock]
        try:
            sent = sock.send(pending) if pending else 0
        except (BlockingIOError, InterruptedError):
            sent = 0
        except OSError:
            drop(sock)
            return
        del pending[:sent]
        events = selectors.EVENT_READ | (selectors.EVENT_WRITE if pending else 0)
        sel.modify(sock, events, ("client", "script"))

    def accept(listener, kind):
        try:
            conn, _ = listener.accept()
        except (BlockingIOError, InterruptedError):
            return
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        if kind == "rtde":
            conn.settimeout(2.0)      # a client that stops reading is dropped
            streams[conn] = _RTDEConnection(conn)
            sel.register(conn, selectors.EVENT_READ, ("client", kind))
            return
        conn.setblocking(False)
        texts[conn] = ""
        state = _state_message(arm.read_state(), tcp_offset, kinematics, arm.is_moving)
        outgoing[conn] = bytearray(greeting + state)
        sel.register(conn, selectors.EVENT_READ, ("client", "script"))
        flush(conn)

    def receive(sock, kind):
        try:
            data = sock.recv(65536)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            data = b""
        if not data:
            drop(sock)
        elif kind == "script":
            texts[sock] += data.decode("utf-8", errors="replace")
            run_text(sock)
        else:
            conn = streams[sock]
            try:
                for ptype, body in conn.buffer.feed(data):
                    conn.handle(ptype, body, version)
            except Exception as exc:          # a malformed package: drop that client only
                drop(sock, f"RTDE client dropped: {type(exc).__name__}: {exc}")

    running = True
    try:
        while running:
            now = time.monotonic()
            due = [c.next_due for c in streams.values() if c.started] + [next_state]
            timeout = min(max(min(due) - now, 0.0), 0.05)
            for key, events in sel.select(timeout):
                role, kind = key.data
                if role == "control":
                    data = os.read(control, 1024)
                    if not data or b"stop" in data:
                        running = False
                elif role == "listen":
                    accept(key.fileobj, kind)
                else:
                    if events & selectors.EVENT_WRITE and key.fileobj in outgoing:
                        flush(key.fileobj)
                    if events & selectors.EVENT_READ and (key.fileobj in texts
                                                          or key.fileobj in streams):
                        receive(key.fileobj, kind)
            now = time.monotonic()
            if now >= next_state:                 # the 10 Hz robot state, to who can take it
                next_state = max(next_state + STATE_PERIOD, now)
                if outgoing:
                    state = _state_message(arm.read_state(), tcp_offset, kinematics,
                                           arm.is_moving)
                    for sock in list(outgoing):
                        if sock in outgoing and not outgoing[sock]:
                            outgoing[sock] += state
                            flush(sock)
            ready = [c for c in streams.values() if c.started and now >= c.next_due]
            if ready:
                state = arm.read_state()
                for conn in ready:
                    try:
                        conn.sock.sendall(conn.data_package(state))
                        conn.next_due = max(conn.next_due + conn.period, now)
                    except Exception as exc:
                        drop(conn.sock, f"RTDE client dropped: {type(exc).__name__}: {exc}")
    finally:
        for sock in list(texts) + list(streams):
            sock.close()
        for srv in listeners:
            srv.close()
        sel.close()
