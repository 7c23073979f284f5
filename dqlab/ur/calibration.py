r"""A UR's own kinematic calibration, read without ROS, each into a :class:`~dqlab.robot.Robot`.

Every UR leaves the factory with corrections to the :math:`\theta_i, a_i, d_i, \alpha_i` of
its joints; with them the controller's forward kinematics is accurate to a fraction of a
millimetre, without them the tool is off by millimetres. They can be read in three places:

1. **From the controller**, in the kinematics-info package of the primary and secondary
   interfaces (TCP ports 30001 and 30002): sub-package type 5 of the robot-state message
   (type 16), sent when a client connects. All numbers big-endian:

   ========================  ==========================================================
   field                     content
   ========================  ==========================================================
   ``int32`` size            of the whole robot-state message, header included
   ``uint8`` type            16 (robot state), then sub-packages, each:
   ``uint32`` size           of the sub-package, these five header bytes included
   ``uint8`` type            5 (kinematics info)
   ``uint32[6]`` checksum    one per joint (``0xFFFFFFFF``: not calibrated, the simulator)
   ``double[6]`` dh_theta    :math:`\theta_i` (the joint-angle offsets)
   ``double[6]`` dh_a        :math:`a_i`
   ``double[6]`` dh_d        :math:`d_i`
   ``double[6]`` dh_alpha    :math:`\alpha_i`
   ``uint32`` status         calibration status (UR's table says ``uint8``; controllers
                             send four bytes: the sub-package is 225 bytes long)
   ========================  ==========================================================

   On the edge cases the reader does what UR's Client Library does (its primary parser,
   ``KinematicsInfo::parseWith``): a sub-package longer than 225 bytes is read and its
   trailing bytes ignored, with a warning (a newer controller may add fields); a shorter one
   -- such as a 217-byte variant with a one-byte status -- is refused (the library throws).
   Unlike the library, dqlab also refuses NaN or infinity in the parameters.

   The parameters are the calibrated ones (the published values plus the corrections):
   standard DH, the conventions of :func:`dqlab.models.ur3`. Nearly parallel axes (joints 2,
   3, 4) have their common normals far away, so :math:`d_2, d_3, d_4` may read hundreds of
   metres and :math:`\theta_2, \theta_3, \theta_4` tenths of a radian: the arm is the same,
   and :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` solves it (:mod:`dqlab.ik.ur_calibrated`).
   :func:`read_kinematics_info` reads the package from a controller (or the controller
   stand-in, which serves one), :func:`kinematics_info_from_message` decodes it and
   :func:`message_from_kinematics_info` encodes it.
2. **From the calibration file on the controller**, ``calibration.conf`` in the
   ``.urcontrol`` folder: the corrections alone (``delta_theta``, ``delta_a``, ``delta_d``,
   ``delta_alpha``, the ``joint_checksum`` of each joint and the ``calibration_status``),
   added to the published parameters of the model (:func:`robot_from_calibration_conf`).
3. **From ROS's** ``ur_calibration`` **output**, a YAML file ``kinematics:`` with, for
   ``shoulder, upper_arm, forearm, wrist_1, wrist_2, wrist_3``, the fixed transform before
   each joint (``x, y, z`` and ``roll, pitch, yaw``) and a ``hash`` of the controller's
   parameters (:func:`robot_from_ros_calibration`). The tool moves the far common normals
   back onto the arm, which changes the numbers but not the arm; the DH parameters are read
   back from the joint axes (:func:`robot_from_joint_origins`), and the file's hash must be
   the hash of *the controller's own* values among the sets that describe the same arm (see
   :func:`robot_from_ros_calibration`).

Every reader refuses a corrupt or mismatched source with a :class:`CalibrationError` that
names the source and the field: a missing or malformed field, a wrong length, NaN or
infinity, a checksum or hash that does not match the one given, or a calibration that does
not belong to the model given (a calibrated arm is millimetres from its model's nominal one;
:data:`MODEL_TOLERANCE` is allowed). Every file reader is bounded: at most
:data:`MAX_FILE_SIZE` bytes, no YAML aliases, at most 16 levels of nesting; an error quotes
at most a line of what it refuses.
"""

import configparser
import itertools
import math
import socket
import struct
import time
import warnings
from dataclasses import dataclass

import numpy as np

from .._checks import (
    check_instance,
    check_path,
    check_scalar,
    check_text,
    real_array,
    short_repr,
)
from ..ik import pose_errors
from ..models import UR_MODELS, with_model_inertias
from ..robot import Link, Robot
from ..rotations import rot_x, rot_y, rot_z
from ..transforms import check_transform

__all__ = ["CalibrationError", "KinematicsInfo", "CalibrationConf", "MODEL_TOLERANCE",
           "ROBOT_STATE", "KINEMATICS_INFO", "UNCALIBRATED", "kinematics_info_from_robot",
           "message_from_kinematics_info", "kinematics_info_from_message",
           "read_kinematics_info", "robot_from_kinematics_info", "read_calibration_conf",
           "robot_from_calibration_conf", "robot_from_corrections",
           "robot_from_joint_origins",
           "read_ros_calibration", "robot_from_ros_calibration", "ROS_LINKS", "MAX_FILE_SIZE",
           "check_identifiers"]

#: Message type of a robot-state message, and sub-package type of the kinematics info.
ROBOT_STATE, KINEMATICS_INFO = 16, 5
#: The joint checksum of a joint without calibration (what the simulator reports).
UNCALIBRATED = 0xFFFFFFFF
#: How far (metres, on sample configurations) a calibrated arm may be from its model's
#: nominal one: calibrations move it by millimetres; two models differ by centimetres.
MODEL_TOLERANCE = 0.02
#: The link names of ``ur_calibration``'s YAML, joints 1 to 6.
ROS_LINKS = ("shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3")
#: The largest calibration file read, bytes (a controller's or ``ur_calibration``'s is about 1 kB).
MAX_FILE_SIZE = 1 << 16

_BODY = struct.Struct(">6I24dI")                  # 220 bytes: the four-byte status
_HEADER = struct.Struct(">IB")                    # a sub-package's size and type
_MESSAGE_HEADER = struct.Struct(">iB")            # a message's size and type
_MAX_MESSAGE = 1 << 20
_SAMPLES = np.random.default_rng(20260601).uniform(-np.pi, np.pi, (64, 6))
_LIMITS = (-2 * math.pi, 2 * math.pi)
#: What reading DH parameters back from joint axes may leave (metres and radians): common
#: normals of nearly parallel axes lie far away, and their feet carry the rounding there.
_ROUNDING = 1e-9
#: A value read back from joint axes within this of zero was a zero of the controller's.
_NEAR_ZERO = 1e-12
#: How many rewritings of a ur_calibration file's parameters are hashed before giving up.
_MAX_REWRITINGS = 60_000
_MAX_DEPTH = 16
#: The longest a socket waits at once, s (it cannot wait beyond what the platform's clock
#: holds, ~1e9 s): a longer timeout is waited in turns.
_LONGEST_WAIT = 3600.0


def _quote(value, limit=60):
    """``repr(value)`` on one line of at most ``limit`` characters, for error messages."""
    return _one_line(repr(value), limit)


def _one_line(text, limit=200):
    """``text`` on one line of at most ``limit`` characters, for error messages."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit] + " ..."


class CalibrationError(ValueError):
    """A calibration source that cannot be used; ``source`` (a file or "message") and
    ``field`` say where."""

    def __init__(self, source, field, message):
        self.source, self.field = str(source), str(field)
        super().__init__(f"{self.source}: {self.field}: {message}")


@dataclass(frozen=True)
class KinematicsInfo:
    """The controller's kinematics-info package: the calibrated DH parameters of its arm.

    Attributes
    ----------
    checksum : tuple of 6 int
        One per joint (:data:`UNCALIBRATED` for a joint without calibration).
    theta, a, d, alpha : tuple of 6 float
        Standard DH, metres and radians; ``theta`` holds the joint-angle offsets.
    calibration_status : int

    Raises
    ------
    TypeError, ValueError
        Naming the field, unless the checksums and the status are unsigned 32-bit integers
        (:func:`check_identifiers`) and ``theta``, ``a``, ``d``, ``alpha`` six finite real
        numbers each: what the controller's message can carry.

    Examples
    --------
    >>> KinematicsInfo((1,) * 6, (0,) * 6, (0,) * 6, (0.1,) * 6, (0,) * 6).d
    (0.1, 0.1, 0.1, 0.1, 0.1, 0.1)
    >>> KinematicsInfo((1,) * 6, (0,) * 6, (0,) * 6, (float("nan"),) * 6, (0,) * 6)
    Traceback (most recent call last):
    ...
    ValueError: d must be 6 finite numbers, got nan for joint 1
    """

    checksum: tuple
    theta: tuple
    a: tuple
    d: tuple
    alpha: tuple
    calibration_status: int = 0

    def __post_init__(self):
        checksum, status = check_identifiers(self.checksum, self.calibration_status)
        object.__setattr__(self, "checksum", checksum)
        object.__setattr__(self, "calibration_status", status)
        for field in ("theta", "a", "d", "alpha"):
            object.__setattr__(self, field, _six_numbers(getattr(self, field), field))

    @property
    def hash(self) -> str:
        r"""The ``calib_...`` identifier ROS's UR driver gives these parameters.

        UR's Client Library (``KinematicsInfo::toHash``): :math:`\theta_i, d_i, a_i,
        \alpha_i` of each joint in turn, streamed into a ``std::stringstream`` as C++ prints
        a double by default (``%g``: six significant digits; ``-0`` for minus zero,
        ``1e-17`` for a tiny value -- nothing is rounded to zero), hashed by the GNU C++
        library's ``std::hash<std::string>`` (64-bit MurmurHash2 variant, seed
        ``0xc70f6907``).

        Examples
        --------
        The UR5e as the simulator reports it, and the hash of UR's ROS description files:

        >>> from dqlab.models import ur5e
        >>> kinematics_info_from_robot(ur5e()).hash
        'calib_12788084448423163542'
        """
        return _hash(_hash_text(self.theta, self.d, self.a, self.alpha))


def _six_numbers(value, name):
    """``value`` as a tuple of six finite floats (one per joint), or an error naming
    ``name``."""
    a = real_array(value, name)
    if a.shape != (6,):
        raise ValueError(f"{name} must be 6 finite numbers (one per joint), got shape "
                         f"{a.shape}")
    wrong = np.flatnonzero(~np.isfinite(a))
    if wrong.size:
        j = int(wrong[0])
        raise ValueError(f"{name} must be 6 finite numbers, got {float(a[j])!r} for joint "
                         f"{j + 1}")
    return tuple(a.tolist())


def _hash_text(theta, d, a, alpha):
    """What ``toHash`` streams: each joint's theta, d, a, alpha as C++ prints a double."""
    return "".join("%g%g%g%g" % row for row in zip(theta, d, a, alpha, strict=True))


def _hash(text):
    return f"calib_{_std_hash(text.encode())}"


def _std_hash(data, seed=0xC70F6907):
    """``std::hash<std::string>`` of GNU libstdc++ on 64-bit machines (``_Hash_bytes``)."""
    mask, mul = (1 << 64) - 1, (0xC6A4A793 << 32) + 0x5BD1E995
    length = len(data)
    h = (seed ^ (length * mul)) & mask
    aligned = length & ~7
    for i in range(0, aligned, 8):
        v = (int.from_bytes(data[i:i + 8], "little") * mul) & mask
        h = ((h ^ ((v ^ (v >> 47)) * mul & mask)) * mul) & mask
    if length & 7:
        h = ((h ^ int.from_bytes(data[aligned:], "little")) * mul) & mask
    h = ((h ^ (h >> 47)) * mul) & mask
    return h ^ (h >> 47)


# --------------------------------------------------------------------------------------
# (a) The controller's kinematics-info package


def kinematics_info_from_robot(robot: Robot, *, checksum=(UNCALIBRATED,) * 6,
                               calibration_status: int = 0) -> KinematicsInfo:
    """The kinematics-info package of a robot: what a controller of this arm sends.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        Six revolute joints in standard DH (its base and tool are not part of it).
    checksum : sequence of 6 int
        The joints' checksums (default: not calibrated, as the simulator reports).
    calibration_status : int

    Returns
    -------
    KinematicsInfo

    Raises
    ------
    ValueError
        If the robot is not six revolute joints in standard DH.

    Examples
    --------
    >>> from dqlab.models import ur5e
    >>> info = kinematics_info_from_robot(ur5e())
    >>> info.d
    (0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996)
    """
    links = getattr(robot, "links", None)
    if (links is None or robot.convention != "dh" or len(links) != 6
            or not all(lk.is_revolute for lk in links)):
        raise ValueError(f"robot must be six revolute joints in standard DH, got "
                         f"{short_repr(robot)}")
    return KinematicsInfo(checksum, *(tuple(getattr(lk, k) for lk in links)
                                      for k in ("theta_offset", "a", "d", "alpha")),
                          calibration_status)


def check_identifiers(checksum, calibration_status, *,
                      names=("checksum", "calibration_status")):
    """The joints' checksums (six unsigned 32-bit integers) and the calibration status (one),
    checked, as a controller sends them: ``ValueError`` naming them (by ``names``) for
    anything else -- 2.7, a bool, text, a number beyond 32 bits.

    >>> check_identifiers([1, 2, 3, 4, 5, 6], 2)
    ((1, 2, 3, 4, 5, 6), 2)
    >>> check_identifiers([1, 2, 3, 4, 5, 6], 2.7)
    Traceback (most recent call last):
    ...
    ValueError: calibration_status must be an integer >= 0 and <= 4.29497e+09, got 2.7
    """
    if isinstance(checksum, (str, bytes)) or not hasattr(checksum, "__len__") \
            or len(checksum) != 6:
        raise ValueError(f"{names[0]} must be six unsigned 32-bit integers, got "
                         f"{_quote(checksum)}")
    checksum = tuple(check_scalar(c, f"{names[0]}[{k}]", minimum=0, maximum=0xFFFFFFFF,
                                  integer=True) for k, c in enumerate(checksum))
    status = check_scalar(calibration_status, names[1], minimum=0, maximum=0xFFFFFFFF,
                          integer=True)
    return checksum, status


def message_from_kinematics_info(info: KinematicsInfo) -> bytes:
    """A robot-state message (type 16) holding the kinematics info (sub-package type 5).

    Examples
    --------
    >>> from dqlab.models import ur5e
    >>> message = message_from_kinematics_info(kinematics_info_from_robot(ur5e()))
    >>> len(message), message[4], message[9]        # header, then one sub-package of 225
    (230, 16, 5)
    """
    check_instance(info, KinematicsInfo, "info")        # its fields checked when it was made
    body = _BODY.pack(*info.checksum, *info.theta, *info.a, *info.d, *info.alpha,
                      info.calibration_status)
    package = _HEADER.pack(_HEADER.size + len(body), KINEMATICS_INFO) + body
    return _MESSAGE_HEADER.pack(_MESSAGE_HEADER.size + len(package), ROBOT_STATE) + package


def kinematics_info_from_message(message: bytes, *, source: str = "message"
                                 ) -> KinematicsInfo:
    """Decode the kinematics info of a robot-state message of the primary/secondary interface.

    Parameters
    ----------
    message : bytes, bytearray or memoryview
        One whole message, header included; the other sub-packages are skipped.
    source : str
        Named in error messages.

    Returns
    -------
    KinematicsInfo

    Raises
    ------
    TypeError
        If ``message`` is not bytes.
    CalibrationError
        Naming the field: a message that is not a robot state, a size that does not match,
        no kinematics info, a kinematics info of another length, NaN or infinity.

    Examples
    --------
    >>> from dqlab.models import ur5e
    >>> info = kinematics_info_from_robot(ur5e())
    >>> kinematics_info_from_message(message_from_kinematics_info(info)) == info
    True
    >>> kinematics_info_from_message(message_from_kinematics_info(info)[:-1])
    Traceback (most recent call last):
    ...
    dqlab.ur.calibration.CalibrationError: message: size: the header says 230 bytes, ...
    """
    if not isinstance(message, (bytes, bytearray, memoryview)):
        raise TypeError(f"message must be bytes, got {short_repr(message)}")
    message = bytes(message)
    if len(message) < _MESSAGE_HEADER.size:
        raise CalibrationError(source, "size", f"{len(message)} bytes, shorter than a header")
    size, kind = _MESSAGE_HEADER.unpack_from(message)
    if size != len(message):
        raise CalibrationError(source, "size", f"the header says {size} bytes, the message "
                               f"has {len(message)}")
    if kind != ROBOT_STATE:
        raise CalibrationError(source, "type", f"message type {kind}, not a robot state "
                               f"({ROBOT_STATE})")
    offset = _MESSAGE_HEADER.size
    while offset < size:
        if size - offset < _HEADER.size:
            raise CalibrationError(source, "sub-package size", f"{size - offset} bytes left, "
                                   "shorter than a sub-package header")
        length, sub = _HEADER.unpack_from(message, offset)
        if length < _HEADER.size or offset + length > size:
            raise CalibrationError(source, "sub-package size", f"sub-package of type {sub} "
                                   f"claims {length} bytes at byte {offset} of {size}")
        if sub == KINEMATICS_INFO:
            return _decode_body(message[offset + _HEADER.size:offset + length], source)
        offset += length
    raise CalibrationError(source, "kinematics info", "the message has no kinematics-info "
                           f"sub-package (type {KINEMATICS_INFO})")


def _decode_body(body, source):
    """The kinematics info's fields, read as UR's Client Library reads them: the 220 bytes of
    its layout; trailing bytes are ignored with a warning, a shorter body is refused."""
    if len(body) < _BODY.size:
        hint = (" (a one-byte calibration status, as UR's table has it: controllers send "
                "four bytes, and UR's Client Library refuses this too)"
                if len(body) == _BODY.size - 3 else "")
        raise CalibrationError(source, "kinematics info", f"{len(body)} bytes of data, fewer "
                               f"than the {_BODY.size} of its layout{hint}")
    if len(body) > _BODY.size:
        warnings.warn(f"{source}: kinematics info: {len(body)} bytes of data, {_BODY.size} "
                      f"read; the {len(body) - _BODY.size} trailing bytes are ignored (as UR's "
                      "Client Library does)", stacklevel=3)
    values = _BODY.unpack_from(body)
    groups = {"dh_theta": values[6:12], "dh_a": values[12:18], "dh_d": values[18:24],
              "dh_alpha": values[24:30]}
    for field, numbers in groups.items():
        if not all(math.isfinite(v) for v in numbers):
            raise CalibrationError(source, field, f"not finite: {_quote(numbers)}")
    return KinematicsInfo(tuple(values[:6]), *groups.values(), values[30])


def read_kinematics_info(host: str, port: int = 30002, *, timeout: float = 5.0
                         ) -> KinematicsInfo:
    """Read the kinematics info from a controller (or URSim, or the stand-in).

    Connects to the primary or secondary interface, reads messages until a robot state with
    the kinematics info arrives (a controller sends it when a client connects), and closes.
    Nothing is sent.

    Parameters
    ----------
    host : str
        A host name or address (one line of text).
    port : int
        30001 (primary) or 30002 (secondary) on a robot.
    timeout : float
        Seconds to wait for it, any finite number > 0 (a long wait is waited in turns of
        an hour: a socket cannot wait beyond what the platform's clock holds).

    Returns
    -------
    KinematicsInfo

    Raises
    ------
    TypeError, ValueError
        Naming ``host``, ``port`` (an int in 1..65535) or ``timeout`` (a finite number of
        seconds > 0).
    TimeoutError
        If no kinematics info arrives in time.
    CalibrationError
        If a message is malformed.
    """
    if not isinstance(host, str) or not host.strip():
        raise TypeError(f"host must be a host name or address (a non-empty str), got "
                        f"{_quote(host)}")
    check_text(host, "host", max_length=253)
    port = check_scalar(port, "port", minimum=1, maximum=65535, integer=True)
    timeout = check_scalar(timeout, "timeout", minimum=0, strict=True)
    source = f"{host}:{port}"
    deadline = time.monotonic() + timeout
    try:
        sock = socket.create_connection((host, port), timeout=min(timeout, _LONGEST_WAIT))
    except UnicodeError as exc:                 # what the name lookup cannot encode (IDNA)
        raise ValueError(f"host must be a host name or address, got {_quote(host)}: "
                         f"{_one_line(exc)}") from None
    with sock:
        buffer = b""
        while True:
            while len(buffer) >= _MESSAGE_HEADER.size:
                size, kind = _MESSAGE_HEADER.unpack_from(buffer)
                if not _MESSAGE_HEADER.size <= size <= _MAX_MESSAGE:
                    raise CalibrationError(source, "size", f"message of {size} bytes")
                if len(buffer) < size:
                    break
                message, buffer = buffer[:size], buffer[size:]
                if kind == ROBOT_STATE:
                    try:
                        return kinematics_info_from_message(message, source=source)
                    except CalibrationError as exc:
                        if exc.field != "kinematics info":
                            raise
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"{source}: no kinematics info within {timeout} s")
            sock.settimeout(min(left, _LONGEST_WAIT))
            try:
                data = sock.recv(65536)
            except socket.timeout:
                continue                        # the deadline above says whether time is up
            if not data:
                raise ConnectionError(f"{source}: closed before sending the kinematics info")
            buffer += data


def robot_from_kinematics_info(info: KinematicsInfo, *, model=None, name: str = "",
                               source: str = "message") -> Robot:
    """The calibrated arm of a kinematics-info package, as a :class:`~dqlab.robot.Robot`.

    Parameters
    ----------
    info : KinematicsInfo
    model : str or Robot, optional
        The model it must be (a name of :data:`dqlab.models.UR_MODELS`, or a nominal
        robot): a calibration farther than :data:`MODEL_TOLERANCE` from it is refused.
    name : str, optional
        The robot's name (default: the model's, "calibrated").
    source : str
        Named in error messages.

    Returns
    -------
    Robot
        Standard DH with the package's parameters; the model's joint limits, rated speeds
        and inertias (without a model: limits :math:`\\pm 2\\pi`); no base, no tool.

    Raises
    ------
    CalibrationError
        For a calibration that does not fit ``model``.

    Examples
    --------
    >>> from dqlab.models import ur5e
    >>> info = kinematics_info_from_robot(ur5e())
    >>> robot = robot_from_kinematics_info(info, model="UR5e")
    >>> robot.name, bool((robot.fk([0.1] * 6) == ur5e().fk([0.1] * 6)).all())
    ('UR5e (calibrated)', True)
    >>> robot_from_kinematics_info(info, model="UR10e")
    Traceback (most recent call last):
    ...
    dqlab.ur.calibration.CalibrationError: message: dh_a, dh_d: the calibrated arm is 0.39 m ...
    """
    _nominal(model, required=False)
    if not isinstance(info, KinematicsInfo):
        raise TypeError(f"info must be a KinematicsInfo, got {type(info).__name__}")
    robot = _robot(info.theta, info.a, info.d, info.alpha, model, name, source, "dh_a, dh_d")
    return robot


def _robot(theta, a, d, alpha, model, name, source, field):
    """The calibrated arm: these DH parameters, and the model's joint limits, rated speeds
    and torques, joint names and inertias (moved into the calibrated frames); without a
    model: limits of +-2 pi and nothing else. A calibration that does not fit the model is
    refused first, naming ``source`` and ``field`` (:func:`_check_model`)."""
    nominal = _nominal(model, required=False)
    label = name or f"{_model_name(model) or 'UR'} (calibrated)"
    ratings = [{"limits": _LIMITS}] * 6
    if nominal is not None:
        ratings = [{"limits": lk.limits, "name": lk.name, "inertia": lk.inertia,
                    "max_speed": lk.max_speed, "max_torque": lk.max_torque}
                   for lk in nominal.links]
    robot = Robot([Link(a=ai, alpha=al, d=di, theta_offset=t, **rating)
                   for t, ai, di, al, rating in zip(theta, a, d, alpha, ratings, strict=True)],
                  convention="dh", name=label)
    if nominal is None:
        return robot
    _check_model(robot, model, source, field)
    return with_model_inertias(robot, nominal)      # the model's bodies in these frames


def _model_name(model):
    if model is None:
        return ""
    if isinstance(model, str):
        return _model_key(model)
    return getattr(model, "name", "") or "the model"


def _model_key(name):
    """The key of :data:`dqlab.models.UR_MODELS` for a model name ("ur5e", "UR8 Long")."""
    wanted = name.replace(" ", "").replace("_", "").lower()
    for key in UR_MODELS:
        if key.replace(" ", "").lower() == wanted:
            return key
    raise ValueError(f"model must be one of {', '.join(UR_MODELS)} or a Robot, got "
                     f"{_quote(name)}")


def _nominal(model, required=True):
    """The nominal robot of ``model`` (a name of UR_MODELS or a six-joint standard-DH Robot;
    None when not ``required``), or ``ValueError`` naming ``model``."""
    if model is None and not required:
        return None
    if isinstance(model, str):
        return UR_MODELS[_model_key(model)]()
    if not isinstance(model, Robot):
        raise ValueError(f"model must be one of {', '.join(UR_MODELS)} or a Robot, got "
                         f"{_quote(model)}")
    if model.convention != "dh" or len(model.links) != 6:
        raise ValueError(f"model must be a six-joint standard-DH robot, got {model!r}")
    return model


def _check_model(robot, model, source, field):
    """Refuse a calibrated arm farther than MODEL_TOLERANCE from the model's nominal one."""
    nominal = _nominal(model, required=False)
    if nominal is None:
        return
    bare = Robot(nominal.links, convention=nominal.convention)
    gap, _ = pose_errors(robot.fk(_SAMPLES), bare.fk(_SAMPLES))
    gap = float(gap.max())
    if not gap <= MODEL_TOLERANCE:
        raise CalibrationError(source, field, f"the calibrated arm is {gap:.3g} m from the "
                               f"nominal {_model_name(model)} on sample configurations (a "
                               f"calibration moves it by millimetres): not a "
                               f"{_model_name(model)}")


# --------------------------------------------------------------------------------------
# (b) calibration.conf on the controller

_DELTAS = ("delta_theta", "delta_a", "delta_d", "delta_alpha")


@dataclass(frozen=True)
class CalibrationConf:
    """The corrections of a controller's ``calibration.conf``.

    Attributes
    ----------
    delta_theta, delta_a, delta_d, delta_alpha : tuple of 6 float
        Added to the published :math:`\\theta_i (= 0), a_i, d_i, \\alpha_i`.
    joint_checksum : tuple of 6 int or None
    calibration_status : int or None
        0 not initialised, 1 not linearised, 2 linearised (the file's own comment).
    """

    delta_theta: tuple
    delta_a: tuple
    delta_d: tuple
    delta_alpha: tuple
    joint_checksum: tuple = None
    calibration_status: int = None


def read_calibration_conf(path) -> CalibrationConf:
    """Read a controller's ``calibration.conf`` (an INI file with ``key = [ ... ]`` lists).

    Raises
    ------
    CalibrationError
        Naming the file and the field: a missing delta list, a list of another length, a
        value that is not a number (or not finite), a checksum that is not an integer.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "calibration.conf"
    >>> _ = path.write_text("[mounting]\\n"
    ...     "delta_theta = [ 0.001, 0, 0, 0, 0, 0]\\n"
    ...     "delta_a = [ 0, 0.0005, 0, 0, 0, 0]\\n"
    ...     "delta_d = [ 0, 0, 0, 0, 0, 0]\\n"
    ...     "delta_alpha = [ 0, 0, 0, 0, 0, 0]\\n"
    ...     "joint_checksum = [ 0x1, 0x2, 0x3, 0x4, 0x5, 0x6]\\n"
    ...     "calibration_status = 2 # 2 == Linearised\\n")
    >>> conf = read_calibration_conf(path)
    >>> conf.delta_a[1], conf.joint_checksum, conf.calibration_status
    (0.0005, (1, 2, 3, 4, 5, 6), 2)
    """
    path = check_path(path)
    text = _read_text(path)
    if text.startswith("\ufeff"):
        raise CalibrationError(path, "file", "starts with a byte-order mark (U+FEFF), as some "
                               "editors save UTF-8; a controller writes none: save the file "
                               "as UTF-8 without BOM")
    first = next((k for k, line in enumerate(text.splitlines(), 1)
                  if line.strip() and line.lstrip()[0] not in "#;"), None)
    if first is not None and not text.splitlines()[first - 1].lstrip().startswith("["):
        raise CalibrationError(path, "file", f"line {first}: no section header before the "
                               "first key; a controller's calibration.conf starts with "
                               "'[mounting]' (was the file copied in part?)")
    parser = configparser.ConfigParser(inline_comment_prefixes=("#", ";"), strict=True,
                                       interpolation=None)
    try:
        parser.read_string(text, source=str(path))
    except configparser.Error as exc:
        raise CalibrationError(path, "file", _one_line(str(exc).splitlines()[0])) from None
    section = next((s for s in parser.sections() if parser.has_option(s, "delta_theta")), None)
    if section is None:
        raise CalibrationError(path, "delta_theta", "missing")
    values = {}
    for field in _DELTAS:
        if not parser.has_option(section, field):
            raise CalibrationError(path, field, "missing")
        values[field] = tuple(_list(parser.get(section, field), path, field, float))
    checksum = status = None
    if parser.has_option(section, "joint_checksum"):
        checksum = tuple(_list(parser.get(section, "joint_checksum"), path, "joint_checksum",
                               _unsigned))
    if parser.has_option(section, "calibration_status"):
        status = _unsigned(parser.get(section, "calibration_status"), path,
                           "calibration_status")
    return CalibrationConf(**values, joint_checksum=checksum, calibration_status=status)


def _read_text(path):
    """The text of a calibration file: UTF-8, at most MAX_FILE_SIZE bytes (read no further)."""
    try:
        with open(path, "rb") as f:
            data = f.read(MAX_FILE_SIZE + 1)
    except OSError as exc:
        raise CalibrationError(path, "file", _one_line(exc)) from None
    if len(data) > MAX_FILE_SIZE:
        raise CalibrationError(path, "file", f"more than {MAX_FILE_SIZE} bytes: not a "
                               "calibration file (a controller's is about 1 kB)")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise CalibrationError(path, "file", f"not UTF-8 text (byte {exc.start})") from None


def _list(text, path, field, convert):
    text = text.strip()
    if not (text.startswith("[") and text.endswith("]")):
        raise CalibrationError(path, field, f"not a list [ ... ]: {_quote(text)}")
    items = [item.strip() for item in text[1:-1].split(",")]
    if len(items) != 6:
        raise CalibrationError(path, field, f"{len(items)} values, not 6")
    return [convert(item, path, field) if convert is _unsigned else _number(item, path, field)
            for item in items]


def _number(text, path, field):
    try:
        value = float(text)
    except ValueError:
        raise CalibrationError(path, field, f"not a number: {_quote(text)}") from None
    if not math.isfinite(value):
        raise CalibrationError(path, field, f"not finite: {_quote(text)}")
    return value


def _unsigned(text, path=None, field=None):
    try:
        value = int(text.strip(), 0)
    except ValueError:
        raise CalibrationError(path, field, f"not an integer: {_quote(text)}") from None
    if not 0 <= value <= 0xFFFFFFFF:
        raise CalibrationError(path, field, f"not an unsigned 32-bit integer: {_quote(text)}")
    return value


def robot_from_calibration_conf(path, model, *, checksum=None, name: str = "") -> Robot:
    r"""The calibrated arm of a controller's ``calibration.conf`` and its model.

    :math:`\theta^0_i = \delta\theta_i`, :math:`a_i = a^{nom}_i + \delta a_i`,
    :math:`d_i = d^{nom}_i + \delta d_i`, :math:`\alpha_i = \alpha^{nom}_i + \delta\alpha_i`,
    with the published (nominal) parameters of the model.

    Parameters
    ----------
    path : str or path
    model : str or Robot
        A name of :data:`dqlab.models.UR_MODELS` (``"UR5e"``) or a nominal UR robot.
    checksum : sequence of 6 int, optional
        The joints' checksums the file must hold (for example a controller's
        ``KinematicsInfo.checksum``): a file of another robot is refused. This is what ties
        the file to its robot: corrections move any UR by the same millimetres, so they do
        not tell its model (corrections larger than :data:`MODEL_TOLERANCE` are refused).
    name : str, optional

    Returns
    -------
    Robot

    Raises
    ------
    CalibrationError
        As :func:`read_calibration_conf`; ``joint_checksum`` when it differs from
        ``checksum`` (or is missing); the deltas when they do not fit the model.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "calibration.conf"
    >>> _ = path.write_text("[mounting]\n"
    ...     "delta_theta = [ 0, 0, 0, 0, 0, 0]\n"
    ...     "delta_a = [ 0, -0.001, 0, 0, 0, 0]\n"
    ...     "delta_d = [ 0, 0, 0, 0, 0, 0]\n"
    ...     "delta_alpha = [ 0, 0, 0, 0, 0, 0]\n")
    >>> robot_from_calibration_conf(path, "UR5e").links[1].a
    -0.426
    """
    _nominal(model)
    if checksum is not None:
        wanted, _ = check_identifiers(checksum, 0)
    conf = read_calibration_conf(path)
    if checksum is not None:
        if conf.joint_checksum != wanted:
            raise CalibrationError(path, "joint_checksum", f"{conf.joint_checksum} in the "
                                   f"file, {wanted} expected: another robot's calibration")
    return robot_from_corrections(conf, model, name=name, source=path)


def robot_from_corrections(corrections: CalibrationConf, model, *, name: str = "",
                           source: str = "corrections") -> Robot:
    r"""The calibrated arm of a model and its corrections (a :class:`CalibrationConf`).

    :math:`\theta^0_i = \theta^{nom}_i + \delta\theta_i`, :math:`a_i = a^{nom}_i + \delta a_i`,
    :math:`d_i = d^{nom}_i + \delta d_i`, :math:`\alpha_i = \alpha^{nom}_i + \delta\alpha_i`,
    with the published (nominal) parameters of the model: what
    :func:`robot_from_calibration_conf` does with a file, and what the controller stand-in
    serves (``ControllerStandIn(calibration=...)``).

    Parameters
    ----------
    corrections : CalibrationConf
        The deltas (each 6 finite numbers, metres and radians); the checksums and status
        are not used.
    model : str or Robot
        A name of :data:`dqlab.models.UR_MODELS` (``"UR5e"``) or a nominal UR robot.
    name : str, optional
        The robot's name (default: the model's, "calibrated").
    source : str
        Named in error messages.

    Returns
    -------
    Robot
        Standard DH; the model's joint limits, rated speeds and inertias; no base, no tool.

    Raises
    ------
    TypeError
        If ``corrections`` is not a :class:`CalibrationConf`.
    CalibrationError
        Naming the delta: not 6 finite numbers; or deltas that do not fit the model
        (farther than :data:`MODEL_TOLERANCE` from it).

    Examples
    --------
    >>> corrections = CalibrationConf(delta_theta=(0, 0.001, 0, 0, 0, 0),
    ...                               delta_a=(0, -0.0005, 0, 0, 0, 0),
    ...                               delta_d=(0,) * 6, delta_alpha=(0,) * 6)
    >>> robot = robot_from_corrections(corrections, "UR3")
    >>> robot.name, robot.links[1].a, robot.links[1].theta_offset
    ('UR3 (calibrated)', -0.24415, 0.001)
    """
    if not isinstance(corrections, CalibrationConf):
        raise TypeError(f"corrections must be a CalibrationConf, got "
                        f"{type(corrections).__name__}")
    _nominal(model)
    deltas = {}
    for field in _DELTAS:
        try:
            values = real_array(getattr(corrections, field), field)
        except (TypeError, ValueError) as exc:
            raise CalibrationError(source, field, f"not a sequence of real numbers ({exc})"
                                   ) from None
        if values.shape != (6,) or not np.isfinite(values).all():
            raise CalibrationError(source, field, f"must be 6 finite numbers, got "
                                   f"{short_repr(values)}")
        deltas[field] = values.tolist()
    links = _nominal(model).links
    theta = [lk.theta_offset + dt for lk, dt in zip(links, deltas["delta_theta"], strict=True)]
    a = [lk.a + da for lk, da in zip(links, deltas["delta_a"], strict=True)]
    d = [lk.d + dd for lk, dd in zip(links, deltas["delta_d"], strict=True)]
    alpha = [lk.alpha + dl for lk, dl in zip(links, deltas["delta_alpha"], strict=True)]
    robot = _robot(theta, a, d, alpha, model, name, source, ", ".join(_DELTAS))
    return robot


# --------------------------------------------------------------------------------------
# (c) ROS's ur_calibration output


def robot_from_joint_origins(origins, *, name: str = "") -> Robot:
    r"""A standard-DH robot from the fixed transforms before each of its joints.

    The chain :math:`X(q) = S_1 R_z(q_1)\, S_2 R_z(q_2) \cdots S_n R_z(q_n)` (URDF joint
    origins, ``ur_calibration``'s kinematics) has joint :math:`i` turning about the z axis
    of :math:`W_i = S_1 \cdots S_i` at :math:`q = 0`. Its standard DH parameters are those of
    these lines: :math:`x_i` along the common normal of axes :math:`i` and :math:`i + 1`
    (for nearly parallel axes, however far away it lies), with the sign that keeps
    :math:`|\theta_i| \le \pi/2`; the flange is :math:`W_n` (its x axis fixes
    :math:`\theta_n`). When axis 1 is not the z axis through the origin, a base transform
    carries frame 0; what the last link cannot express becomes a tool. Forward kinematics of
    the result equals the chain's.

    Parameters
    ----------
    origins : array_like, shape (n, 4, 4)
        :math:`S_1, \dots, S_n`, rigid transforms.
    name : str, optional

    Returns
    -------
    Robot
        Standard DH, revolute joints, limits :math:`\pm 2\pi`.

    Raises
    ------
    ValueError
        If ``origins`` are not rigid transforms of shape (n, 4, 4) (naming ``origins``).

    Examples
    --------
    The UR5e's chain as ROS describes it, read back into its DH parameters:

    >>> import numpy as np
    >>> from dqlab.rotations import rot_x
    >>> S = np.tile(np.eye(4), (6, 1, 1))
    >>> S[0, 2, 3] = 0.1625
    >>> S[1, :3, :3] = rot_x(np.pi / 2)
    >>> S[2, 0, 3], S[3, 0, 3], S[3, 2, 3] = -0.425, -0.3922, 0.1333
    >>> S[4, :3, :3], S[4, 1, 3] = rot_x(np.pi / 2), -0.0997
    >>> S[5, :3, :3], S[5, 1, 3] = rot_x(-np.pi / 2), 0.0996
    >>> robot = robot_from_joint_origins(S)
    >>> [round(lk.d, 4) for lk in robot.links], [round(lk.a, 4) for lk in robot.links]
    ([0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996], [0.0, -0.425, -0.3922, 0.0, 0.0, 0.0])
    """
    S = check_transform(origins, name="origins")
    if S.ndim != 3 or S.shape[0] < 1:
        raise ValueError(f"origins must have shape (n, 4, 4), got {S.shape}")
    with np.errstate(over="ignore", invalid="ignore"):    # overflow: refused below
        W, base, rows = _dh_rows(S)
    if not (np.isfinite(W).all() and np.isfinite(rows).all()):
        raise ValueError("origins are too large: the joints' positions or the DH parameters "
                         "overflow (no float holds them)")
    robot = Robot([Link(a=a, alpha=al, d=d, theta_offset=t, limits=_LIMITS)
                   for t, d, a, al in rows.tolist()], convention="dh", name=name)
    with np.errstate(over="ignore", invalid="ignore"):
        tool = np.linalg.inv(robot.fk(np.zeros(len(W)))) @ W[-1]
    if not np.isfinite(tool).all():
        raise ValueError("origins are too large: the flange's pose overflows")
    if not np.allclose(base, np.eye(4), rtol=0, atol=_ROUNDING):
        robot.base = base
    if not np.allclose(tool, np.eye(4), rtol=0, atol=_ROUNDING):    # more than rounding
        robot.tool = tool
    return robot


def _dh_rows(S):
    """The joints' frames at q = 0 in frame 0 (n, 4, 4), frame 0 in the world, and the DH
    rows ``(theta, d, a, alpha)`` of :func:`robot_from_joint_origins`."""
    W = np.empty_like(S)
    W[0] = S[0]
    for i in range(1, len(S)):
        W[i] = W[i - 1] @ S[i]
    base = _frame_zero(W[0])
    W = np.linalg.inv(base) @ W                           # everything in frame 0
    x_prev, o_prev = np.array([1.0, 0.0, 0.0]), np.zeros(3)
    rows = []
    for i in range(len(W)):
        p, u = W[i, :3, 3], W[i, :3, 2]                  # axis of joint i + 1: z_i in DH
        if i + 1 < len(W):
            foot, origin, x = _common_normal(p, u, W[i + 1, :3, 3], W[i + 1, :3, 2], o_prev,
                                             x_prev)
            v = W[i + 1, :3, 2]
        else:                                            # the flange
            origin, x, v = W[i, :3, 3], W[i, :3, 0], u
            foot = o_prev + ((origin - o_prev) @ u) * u
        theta = _angle(x_prev, x, u)
        if abs(theta) > math.pi / 2 and i + 1 < len(W):  # the other sign of the normal
            x = -x
            theta = _angle(x_prev, x, u)
        rows.append((theta, float((foot - o_prev) @ u), float((origin - foot) @ x),
                     _angle(u, v, x)))
        x_prev, o_prev = x, origin
    return W, base, np.array(rows)


def _frame_zero(W1):
    """Frame 0 of the DH chain: the world frame when joint 1 turns about its z axis,
    else a frame with z along joint 1's axis, its origin the axis's point nearest the
    world origin."""
    z, p = W1[:3, 2], W1[:3, 3]
    origin = p - (p @ z) * z
    if np.allclose(z, [0, 0, 1], rtol=0, atol=1e-12) and np.allclose(origin, 0, atol=1e-12):
        return np.eye(4)
    x = np.array([1.0, 0.0, 0.0]) - z[0] * z
    if np.linalg.norm(x) < 1e-6:
        x = np.array([0.0, 1.0, 0.0]) - z[1] * z
    x /= np.linalg.norm(x)
    base = np.eye(4)
    base[:3, 0], base[:3, 1], base[:3, 2], base[:3, 3] = x, np.cross(z, x), z, origin
    return base


def _common_normal(p, u, q, v, o_prev, x_prev):
    """The feet of the common normal of the lines (p, u) and (q, v) -- on the first and on
    the second -- and its direction. Parallel lines: the normal through the foot of o_prev."""
    n = np.cross(u, v)
    s = float(n @ n)
    w = q - p
    if s > 1e-20:               # t and r from cross products: no cancellation of u.v ~ 1
        t = float(np.cross(w, v) @ n) / s
        r = float(np.cross(w, u) @ n) / s
        return p + t * u, q + r * v, n / math.sqrt(s)
    foot = p + ((o_prev - p) @ u) * u
    origin = q + ((foot - q) @ v) * v
    gap = origin - foot
    size = math.hypot(*gap.tolist())             # no overflow of the squares far away
    return foot, origin, (gap / size if size > 1e-15 else x_prev)


def _angle(a, b, axis):
    """The angle from the direction a to b about the unit axis."""
    return math.atan2(float(np.cross(a, b) @ axis), float(a @ b))


@dataclass(frozen=True)
class _RosCalibration:
    origins: np.ndarray
    hash: str


def _bounded_loader(yaml):
    """PyYAML's safe loader without aliases and nested at most _MAX_DEPTH levels: a
    ur_calibration file is a flat mapping, and an alias lets a few bytes expand into
    billions of values (the "billion laughs")."""

    class BoundedLoader(yaml.SafeLoader):
        depth = 0

        def compose_node(self, parent, index):
            if self.check_event(yaml.AliasEvent):
                raise yaml.composer.ComposerError(
                    None, None, "YAML aliases (*name) are not allowed in a calibration file",
                    self.peek_event().start_mark)
            self.depth += 1
            try:
                if self.depth > _MAX_DEPTH:
                    raise yaml.composer.ComposerError(
                        None, None, f"nested deeper than {_MAX_DEPTH} levels",
                        self.peek_event().start_mark)
                return super().compose_node(parent, index)
            finally:
                self.depth -= 1

    return BoundedLoader


def read_ros_calibration(path):
    """The joint origins (6, 4, 4) and the hash of a ``ur_calibration`` YAML file.

    ``x, y, z`` in metres; the rotation of ``roll, pitch, yaw`` as ``ur_calibration``
    computes it (Eigen's ``eulerAngles(0, 1, 2)``): :math:`R_x(roll)\\, R_y(pitch)\\,
    R_z(yaw)`, rotations about the moving axes. (A URDF reads the same three numbers about
    fixed axes, :math:`R_z(yaw) R_y(pitch) R_x(roll)`: the same rotation when roll or yaw is
    zero, as in the nominal files, not otherwise.)

    Returns
    -------
    origins : ndarray, shape (6, 4, 4)
    hash : str

    Raises
    ------
    CalibrationError
        Naming the file and the field (``kinematics.forearm.pitch``).
    ImportError
        Without PyYAML (``pip install pyyaml``).
    """
    try:
        import yaml
    except ImportError:  # pragma: no cover -- PyYAML comes with the test and book extras
        raise ImportError("reading a ur_calibration file needs PyYAML: pip install pyyaml"
                          ) from None
    path = check_path(path)
    text = _read_text(path)
    try:
        data = yaml.load(text, Loader=_bounded_loader(yaml))
    except (yaml.YAMLError, RecursionError) as exc:
        message = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise CalibrationError(path, "file", _one_line(message)) from None
    kinematics = data.get("kinematics") if isinstance(data, dict) else None
    if not isinstance(kinematics, dict):
        raise CalibrationError(path, "kinematics", "missing (not a ur_calibration file)")
    origins = np.empty((6, 4, 4))
    for i, link in enumerate(ROS_LINKS):
        entry = kinematics.get(link)
        if not isinstance(entry, dict):
            raise CalibrationError(path, f"kinematics.{link}", "missing")
        v = {}
        for key in ("x", "y", "z", "roll", "pitch", "yaw"):
            value = entry.get(key)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise CalibrationError(path, f"kinematics.{link}.{key}",
                                       f"not a number: {_quote(value)}")
            if isinstance(value, int) and abs(value) > 1e300 or not math.isfinite(value):
                raise CalibrationError(path, f"kinematics.{link}.{key}",
                                       f"not a finite number: {_quote(value)}")
            v[key] = float(value)
        origins[i] = np.eye(4)
        origins[i, :3, :3] = rot_x(v["roll"]) @ rot_y(v["pitch"]) @ rot_z(v["yaw"])
        origins[i, :3, 3] = v["x"], v["y"], v["z"]
    digest = kinematics.get("hash")
    if not isinstance(digest, str) or not digest.startswith("calib_"):
        raise CalibrationError(path, "kinematics.hash",
                               f"not a calib_... hash: {_quote(digest)}")
    return _RosCalibration(origins, digest)


def robot_from_ros_calibration(path, *, model=None, expected_hash: str | None = None,
                               name: str = "") -> Robot:
    r"""The calibrated arm of a ``ur_calibration`` YAML file, with the controller's own DH
    parameters.

    The DH parameters are read back from the joint origins (:func:`robot_from_joint_origins`,
    which chooses :math:`|\theta_i| \le \pi/2`). Other sets describe the same arm: each
    common normal :math:`x_i` (:math:`i < 6`) may point the other way
    (:math:`\theta_i + \pi`, :math:`a_i \to -a_i`, :math:`\alpha_i \to -\alpha_i`,
    :math:`\theta_{i+1} + \pi`), each :math:`\theta_i` may hold whole turns, and a zero
    may be :math:`-0`. The controller keeps one of them -- real ones hold
    :math:`\theta_3 = 6.1968` or :math:`7.129` -- and the file's ``hash`` is the hash of
    *that* set (:attr:`KinematicsInfo.hash`, as UR's Client Library computes it, no
    normalisation). The rewritings are searched, the plainest first (fewest flips, smallest
    :math:`|\theta_i|`, at most :math:`3\pi`), for the one whose hash is the file's: the
    robot gets those values. None matching means the file was edited or damaged.

    Parameters
    ----------
    path : str or path
    model : str or Robot, optional
        The model it must be (see :func:`robot_from_kinematics_info`).
    expected_hash : str, optional
        The hash the file must carry, for example ``KinematicsInfo.hash`` of the robot at
        hand: a file of another robot is refused.
    name : str, optional

    Returns
    -------
    Robot
        Standard DH with the controller's parameters (its kinematics info, to the digits
        the file keeps): ``kinematics_info_from_robot(robot).hash`` is the file's hash.

    Raises
    ------
    CalibrationError
        As :func:`read_ros_calibration`; ``kinematics.hash`` when no rewriting of its
        kinematics has the file's hash, or the hash is not ``expected_hash``; the kinematics
        when they do not fit ``model``.
    """
    _nominal(model, required=False)
    if expected_hash is not None and not isinstance(expected_hash, str):
        raise TypeError(f"expected_hash must be a str (calib_...), got {_quote(expected_hash)}")
    calibration = read_ros_calibration(path)
    if expected_hash is not None and calibration.hash != expected_hash:
        raise CalibrationError(path, "kinematics.hash", f"{calibration.hash} in the file, "
                               f"{_quote(expected_hash)} expected: another robot's calibration")
    chain = robot_from_joint_origins(calibration.origins)
    if not chain.bare:
        raise CalibrationError(path, "kinematics.shoulder", "joint 1 does not turn about the "
                               "z axis of the base, as a UR's does")
    rows = [(lk.theta_offset, lk.d, lk.a, lk.alpha) for lk in chain.links]
    found = _controller_parameters(rows, calibration.hash)
    if found is None:
        read = _hash_text(*zip(*rows, strict=True))
        raise CalibrationError(path, "kinematics.hash", f"{calibration.hash} in the file, but "
                               f"no equivalent set of its DH parameters hashes to it (as read: "
                               f"{_hash(read)}): edited or damaged")
    theta, d, a, alpha = found
    robot = _robot(theta, a, d, alpha, model, name, path, "kinematics")
    return robot


def _controller_parameters(rows, digest):
    """The controller's (theta, d, a, alpha), 6 each, among the rewritings of ``rows`` (the
    parameters read back) that describe the same arm, found by the hash ``digest``; None if
    no rewriting has it (see :func:`robot_from_ros_calibration`). The rewritings of one set
    of flips are hashed together (:func:`_std_hash_many`), the plainest set first."""
    try:
        wanted = int(digest[len("calib_"):])
    except ValueError:
        return None
    n, tried = len(rows), 0
    for flips in sorted(itertools.product((0, 1), repeat=n - 1), key=sum):
        f = (0, *flips, 0)                       # x_0 (the base) and x_n (the flange) stay
        joints = []
        for i, (theta, d, a, alpha) in enumerate(rows):
            sign = -1.0 if f[i + 1] else 1.0
            thetas = sorted((theta + math.pi * (f[i] + f[i + 1]) + 2 * math.pi * k
                             for k in range(-2, 3)), key=abs)
            joints.append([row for t in thetas if abs(t) <= 3 * math.pi + 1e-9
                           for row in itertools.product(_printed(t), _printed(d),
                                                        _printed(sign * a),
                                                        _printed(sign * alpha))])
        choices = list(itertools.islice(itertools.product(*joints), _MAX_REWRITINGS - tried))
        texts = ["".join(text for row in choice for text, _ in row).encode()
                 for choice in choices]
        hits = np.flatnonzero(_std_hash_many(texts) == np.uint64(wanted))
        if hits.size:
            choice = choices[hits[0]]
            return tuple(tuple(row[k][1] for row in choice) for k in range(4))
        tried += len(choices)
        if tried >= _MAX_REWRITINGS:
            break
    return None


def _printed(value):
    """How the controller's value may print, as ((text, value), ...), the likeliest first:
    a value read back within _NEAR_ZERO of zero was a zero (+0: controllers store their zeros
    so); one next to a rounding boundary of the sixth digit may print either way."""
    if abs(value) < _NEAR_ZERO:
        return (("0", 0.0),)
    out = [("%g" % value, value)]
    for nearby in (value * (1 - 1e-10), value * (1 + 1e-10)):
        if all("%g" % nearby != text for text, _ in out):
            out.append(("%g" % nearby, nearby))
    return tuple(out)


def _std_hash_many(texts, seed=0xC70F6907):
    """:func:`_std_hash` of many byte strings at once, with numpy's wrapping uint64
    arithmetic (texts of one length at a time); equal to it, tested."""
    out = np.zeros(len(texts), dtype=np.uint64)
    by_length = {}
    for k, text in enumerate(texts):
        by_length.setdefault(len(text), []).append(k)
    mul, r = np.uint64((0xC6A4A793 << 32) + 0x5BD1E995), np.uint64(47)
    for length, index in by_length.items():
        data = np.frombuffer(b"".join(texts[k] for k in index), dtype=np.uint8)
        data = data.reshape(len(index), length)
        aligned = length & ~7
        h = np.full(len(index), (seed ^ (length * int(mul))) & ((1 << 64) - 1), np.uint64)
        words = np.ascontiguousarray(data[:, :aligned]).view("<u8")
        for j in range(words.shape[1]):
            v = words[:, j] * mul
            h = (h ^ ((v ^ (v >> r)) * mul)) * mul
        if length & 7:
            tail = np.zeros(len(index), dtype=np.uint64)
            for b in range(length - aligned):
                tail |= data[:, aligned + b].astype(np.uint64) << np.uint64(8 * b)
            h = (h ^ tail) * mul
        h = (h ^ (h >> r)) * mul
        out[index] = h ^ (h >> r)
    return out
