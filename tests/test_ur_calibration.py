"""Reading a UR's calibration (dqlab.ur.calibration): the controller's kinematics-info package,
calibration.conf and ur_calibration's YAML; bad sources refused with the source and field."""

import math
import socket
import struct
import threading
from pathlib import Path

import numpy as np
import pytest

from dqlab.identify import dh_parameter_names, dh_parameters, robot_from_dh_parameters
from dqlab.ik import pose_errors
from dqlab.models import UR_MODELS, ur3, ur5, ur5e, ur10, ur10e
from dqlab.rotations import rot_x, rot_y, rot_z
from dqlab.ur import ControllerStandIn
from dqlab.ur.calibration import (
    MODEL_TOLERANCE,
    ROS_LINKS,
    UNCALIBRATED,
    CalibrationConf,
    CalibrationError,
    KinematicsInfo,
    _std_hash,
    _std_hash_many,
    kinematics_info_from_message,
    kinematics_info_from_robot,
    message_from_kinematics_info,
    read_calibration_conf,
    read_kinematics_info,
    robot_from_calibration_conf,
    robot_from_corrections,
    robot_from_joint_origins,
    robot_from_kinematics_info,
    robot_from_ros_calibration,
)

#: The ``hash`` of the default kinematics files of Universal Robots' ROS 2 description
#: (config/<model>/default_kinematics.yaml, release 2.4.5): the controller simulator's
#: parameters of each model, which dqlab's published tables must reproduce.
ROS_HASHES = {"UR3": "calib_9122066269688285636", "UR5": "calib_209549117540498681",
              "UR10": "calib_17227329492635474227", "UR3e": "calib_16756443741236045476",
              "UR5e": "calib_12788084448423163542", "UR10e": "calib_5119701370761913513",
              "UR16e": "calib_1935737212149401527", "UR20": "calib_4890363623803256388",
              "UR30": "calib_12001109639981648826"}

Q = np.random.default_rng(2031).uniform(-np.pi, np.pi, (200, 6))


def chain_fk(origins, q):
    """Forward kinematics of S_1 Rz(q_1) ... S_n Rz(q_n), written out here (the oracle)."""
    X = np.tile(np.eye(4), (len(q), 1, 1))
    for i, S in enumerate(origins):
        R = np.zeros((len(q), 4, 4))
        R[:, :3, :3] = rot_z(q[:, i])
        R[:, 3, 3] = 1.0
        X = X @ S @ R
    return X


def dh_origins(robot):
    """The joint origins of a standard-DH robot, S_1 = Rz(t1) Tz(d1),
    S_i = Tx(a_{i-1}) Rx(alpha_{i-1}) Rz(t_i) Tz(d_i): what ur_calibration starts from."""
    S = []
    previous = None
    for link in robot.links:
        T = np.eye(4)
        if previous is not None:
            T[:3, :3], T[0, 3] = rot_x(previous.alpha), previous.a
        M = np.eye(4)
        M[:3, :3], M[2, 3] = rot_z(link.theta_offset), link.d
        S.append(T @ M)
        previous = link
    return np.array(S)


def physically_perturbed_ur5e(seed, size=2e-3):
    """A UR5e whose link geometry is moved by up to 2 mm and 2 mrad, written in standard DH
    as a controller writes it: the common normals of its nearly parallel axes far away."""
    rng = np.random.default_rng(seed)
    S = dh_origins(ur5e())
    for i in range(1, 6):
        P = np.eye(4)
        P[:3, :3] = rot_x(rng.uniform(-size, size)) @ rot_z(rng.uniform(-size, size))
        P[:3, 3] = rng.uniform(-size, size, 3)
        S[i] = S[i] @ P
    return S, robot_from_joint_origins(S, name="UR5e (perturbed)")


def moved_along_axes(origins, seed, reach=0.5):
    """The same chain with each joint frame slid along and turned about its own axis (the
    freedom ur_calibration uses to bring far common normals back onto the arm)."""
    rng = np.random.default_rng(seed)
    S = origins.copy()
    for i in range(len(S) - 1):
        M = np.eye(4)
        M[:3, :3], M[2, 3] = rot_z(rng.uniform(-1, 1)), rng.uniform(-reach, reach)
        S[i] = S[i] @ M
        S[i + 1] = np.linalg.inv(M) @ S[i + 1]
    return S


def eigen_xyz(R):
    """(roll, pitch, yaw) with R = Rx(roll) Ry(pitch) Rz(yaw): Eigen's eulerAngles(0, 1, 2),
    as ur_calibration writes them."""
    return (math.atan2(-R[1, 2], R[2, 2]), math.asin(max(-1.0, min(1.0, R[0, 2]))),
            math.atan2(-R[0, 1], R[0, 0]))


def ros_yaml(origins, digest):
    lines = ["kinematics:"]
    for name, S in zip(ROS_LINKS, origins, strict=True):
        roll, pitch, yaw = eigen_xyz(S[:3, :3])
        lines.append(f"  {name}:")
        for key, value in zip(("x", "y", "z", "roll", "pitch", "yaw"),
                              (*S[:3, 3], roll, pitch, yaw), strict=True):
            lines.append(f"    {key}: {float(value)!r}")
    lines.append(f"  hash: {digest}")
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------------------
# The hash and the models


@pytest.mark.parametrize("name", sorted(ROS_HASHES))
def test_hash_of_each_model_is_the_one_of_urs_ros_description(name):
    """The published DH parameters of dqlab.models give the controller simulator's hash."""
    assert kinematics_info_from_robot(UR_MODELS[name]()).hash == ROS_HASHES[name]


def test_hash_changes_with_the_sixth_significant_digit_only():
    info = kinematics_info_from_robot(ur5e())
    d = list(info.d)
    d[3] += 1e-8                                   # 0.1333 prints the same
    same = KinematicsInfo(info.checksum, info.theta, info.a, tuple(d), info.alpha)
    d[3] += 1e-4                                   # 0.1334 does not
    other = KinematicsInfo(info.checksum, info.theta, info.a, tuple(d), info.alpha)
    assert same.hash == info.hash != other.hash


# --------------------------------------------------------------------------------------
# (a) The kinematics-info package


def test_message_layout_is_the_documented_one():
    """Sub-package 225 bytes: sizes, types, then checksum, theta, a, d, alpha, status at the
    offsets of UR's client-interface table (written here with struct, independently)."""
    info = KinematicsInfo((1, 2, 3, 4, 5, 6), tuple(range(10, 16)), tuple(range(20, 26)),
                          tuple(range(30, 36)), tuple(range(40, 46)), 2)
    message = message_from_kinematics_info(info)
    assert struct.unpack(">iB", message[:5]) == (len(message), 16)
    assert struct.unpack(">IB", message[5:10]) == (225, 5)
    assert struct.unpack(">6I", message[10:34]) == (1, 2, 3, 4, 5, 6)
    for k, first in enumerate((10, 20, 30, 40)):
        start = 34 + 48 * k
        assert struct.unpack(">6d", message[start:start + 48]) == tuple(range(first,
                                                                              first + 6))
    assert struct.unpack(">I", message[226:230]) == (2,)


def test_message_round_trip_of_a_calibrated_arm():
    _, robot = physically_perturbed_ur5e(1)
    info = kinematics_info_from_robot(robot, checksum=(7, 8, 9, 10, 11, 12),
                                      calibration_status=2)
    back = kinematics_info_from_message(message_from_kinematics_info(info))
    assert back == info
    again = robot_from_kinematics_info(back, model="UR5e")
    assert np.array_equal(again.fk(Q), robot.fk(Q))


def _with_other_packages(info, status_bytes=4):
    """A robot state with a robot-mode sub-package (type 0) before the kinematics info, and
    the status as one byte when asked (UR's table)."""
    body = struct.pack(">6I24d", *info.checksum, *info.theta, *info.a, *info.d, *info.alpha)
    body += struct.pack(">I" if status_bytes == 4 else ">B", info.calibration_status)
    other = struct.pack(">IB", 5 + 7, 0) + bytes(7)
    kin = struct.pack(">IB", 5 + len(body), 5) + body
    payload = other + kin
    return struct.pack(">iB", 5 + len(payload), 16) + payload


def test_decoder_skips_other_sub_packages():
    info = kinematics_info_from_robot(ur10e(), calibration_status=1)
    assert kinematics_info_from_message(_with_other_packages(info)) == info


def test_a_one_byte_status_is_refused_as_the_client_library_refuses_it():
    """217 bytes of data (UR's table's uint8 status): the Client Library's parser throws."""
    info = kinematics_info_from_robot(ur10e(), calibration_status=1)
    with pytest.raises(CalibrationError, match="217 bytes .* one-byte calibration status"):
        kinematics_info_from_message(_with_other_packages(info, status_bytes=1))


def test_corrupt_messages_are_refused_naming_the_field():
    info = kinematics_info_from_robot(ur5e())
    message = bytearray(message_from_kinematics_info(info))
    cases = {
        "size": bytes(message[:-3]),                                         # truncated
        "type": bytes(message[:4]) + b"\x14" + bytes(message[5:]),           # a text message
        "sub-package size": bytes(message[:5]) + struct.pack(">IB", 900, 5) + bytes(
            message[10:]),
    }
    nan = bytearray(message)
    nan[34 + 96 + 8:34 + 96 + 16] = struct.pack(">d", float("nan"))         # dh_d[1]
    cases["dh_d"] = bytes(nan)
    short = struct.pack(">IB", 5 + 100, 5) + bytes(100)
    cases["kinematics info"] = struct.pack(">iB", 5 + len(short), 16) + short
    other = struct.pack(">IB", 12, 0) + bytes(7)
    cases["kinematics info "] = struct.pack(">iB", 5 + len(other), 16) + other
    for field, data in cases.items():
        with pytest.raises(CalibrationError) as caught:
            kinematics_info_from_message(data, source="test")
        assert caught.value.field == field.strip() and caught.value.source == "test"
        assert str(caught.value).startswith(f"test: {field.strip()}: ")


class _OneShotServer:
    """A local TCP server (127.0.0.1, ephemeral port) that sends ``data`` to its one client,
    then waits for the test to stop it."""

    def __init__(self, data):
        self.data = data
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        self.sock.settimeout(5.0)
        try:
            conn, _ = self.sock.accept()
        except OSError:
            return
        with conn:
            for i in range(0, len(self.data), 7):          # in small pieces, as TCP may
                conn.sendall(self.data[i:i + 7])
            self.stop.wait(10.0)

    def __enter__(self):
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.stop.set()
        self.sock.close()
        self.thread.join(10.0)
        assert not self.thread.is_alive()


def test_read_kinematics_info_from_a_socket_after_other_messages():
    _, robot = physically_perturbed_ur5e(2)
    info = kinematics_info_from_robot(robot, checksum=(1, 2, 3, 4, 5, 6))
    version = struct.pack(">iB", 5 + 11, 20) + bytes(11)             # a version message
    with _OneShotServer(version + _with_other_packages(info)) as server:
        assert read_kinematics_info("127.0.0.1", server.port, timeout=5.0) == info


def test_read_kinematics_info_times_out_without_it():
    with _OneShotServer(struct.pack(">iB", 5 + 11, 20) + bytes(11)) as server:
        with pytest.raises(TimeoutError, match="no kinematics info"):
            read_kinematics_info("127.0.0.1", server.port, timeout=0.3)


def test_the_controller_stand_in_serves_its_arms_kinematics_info():
    with ControllerStandIn("ur5e") as standin:
        info = read_kinematics_info(standin.host, standin.secondary_port, timeout=10.0)
    assert not standin.running
    assert info.hash == ROS_HASHES["UR5e"] and info.checksum == (0xFFFFFFFF,) * 6
    robot = robot_from_kinematics_info(info, model="ur5e")
    assert np.array_equal(robot.fk(Q), ur5e().fk(Q))


def test_wrong_model_is_refused():
    info = kinematics_info_from_robot(physically_perturbed_ur5e(3)[1])
    robot_from_kinematics_info(info, model="UR5e")                  # millimetres: accepted
    robot_from_kinematics_info(info, model="UR7e")                  # the same arm renamed
    for model in ("UR10e", "UR3e", ur5()):
        with pytest.raises(CalibrationError, match="not a") as caught:
            robot_from_kinematics_info(info, model=model)
        assert caught.value.field == "dh_a, dh_d"
    with pytest.raises(ValueError, match="model must be one of"):
        robot_from_kinematics_info(info, model="UR6")


# --------------------------------------------------------------------------------------
# (b) calibration.conf


def _conf_text(deltas, checksum="[ 0x6e0f7bf, 0xa32a713f, 0xf636a50, 0x9ec2338a, "
               "0xa1afded8, 0xb29b2979]", status="2 # 0 == notInitialized / 2 == Linearised"):
    lines = ["[mounting]"]
    for name, values in deltas.items():
        lines.append(f"{name} = [ " + ", ".join(repr(float(v)) for v in values) + "]")
    if checksum is not None:
        lines.append(f"joint_checksum = {checksum}")
    lines.append(f"calibration_status = {status}")
    return "\n".join(lines) + "\n"


def _deltas(robot, nominal):
    """The corrections of calibration.conf that make ``nominal`` into ``robot``."""
    fields = {"delta_theta": "theta_offset", "delta_a": "a", "delta_d": "d",
              "delta_alpha": "alpha"}
    return {name: [getattr(r, k) - getattr(n, k) for r, n in
                   zip(robot.links, nominal.links, strict=True)]
            for name, k in fields.items()}


def test_calibration_conf_adds_the_corrections_to_the_model(tmp_path):
    _, robot = physically_perturbed_ur5e(4)          # far common normals: d2 of metres
    path = tmp_path / "calibration.conf"
    path.write_text(_conf_text(_deltas(robot, ur5e())))
    conf = read_calibration_conf(path)
    assert conf.calibration_status == 2 and conf.joint_checksum[1] == 0xA32A713F
    read = robot_from_calibration_conf(path, "UR5e",
                                       checksum=(0x6E0F7BF, 0xA32A713F, 0xF636A50, 0x9EC2338A,
                                                 0xA1AFDED8, 0xB29B2979))
    assert np.abs(read.fk(Q) - robot.fk(Q)).max() < 1e-12
    assert abs(robot.links[1].d) > 0.1               # the representation a controller writes


def test_calibration_conf_of_another_robot_or_model_is_refused(tmp_path):
    _, robot = physically_perturbed_ur5e(5)
    path = tmp_path / "calibration.conf"
    path.write_text(_conf_text(_deltas(robot, ur5e())))
    with pytest.raises(CalibrationError, match="another robot") as caught:
        robot_from_calibration_conf(path, "UR5e", checksum=(1, 2, 3, 4, 5, 6))
    assert caught.value.field == "joint_checksum" and caught.value.source == str(path)
    # Corrections move any UR by the same millimetres: they do not tell the model (the
    # checksum ties the file to its robot), but corrections larger than a calibration's --
    # here a digit wrong in delta_d -- are refused.
    robot_from_calibration_conf(path, "UR10e")
    deltas = _deltas(robot, ur5e())
    deltas["delta_d"][4] += 0.05
    path.write_text(_conf_text(deltas))
    with pytest.raises(CalibrationError, match="not a UR5e") as caught:
        robot_from_calibration_conf(path, "UR5e")
    assert caught.value.field == "delta_theta, delta_a, delta_d, delta_alpha"


@pytest.mark.parametrize("field, text", [
    ("delta_d", "delta_theta = [0,0,0,0,0,0]\ndelta_a = [0,0,0,0,0,0]\n"
                "delta_alpha = [0,0,0,0,0,0]\n"),
    ("delta_a", "delta_theta = [0,0,0,0,0,0]\ndelta_a = [0,0,0,0,0]\n"
                "delta_d = [0,0,0,0,0,0]\ndelta_alpha = [0,0,0,0,0,0]\n"),
    ("delta_alpha", "delta_theta = [0,0,0,0,0,0]\ndelta_a = [0,0,0,0,0,0]\n"
                    "delta_d = [0,0,0,0,0,0]\ndelta_alpha = [0,0,0,nan,0,0]\n"),
    ("delta_theta", "delta_theta = [0,0,0,zero,0,0]\ndelta_a = [0,0,0,0,0,0]\n"
                    "delta_d = [0,0,0,0,0,0]\ndelta_alpha = [0,0,0,0,0,0]\n"),
    ("delta_a", "delta_theta = [0,0,0,0,0,0]\ndelta_a = 0,0,0,0,0,0\n"
                "delta_d = [0,0,0,0,0,0]\ndelta_alpha = [0,0,0,0,0,0]\n"),
    ("joint_checksum", "delta_theta = [0,0,0,0,0,0]\ndelta_a = [0,0,0,0,0,0]\n"
                       "delta_d = [0,0,0,0,0,0]\ndelta_alpha = [0,0,0,0,0,0]\n"
                       "joint_checksum = [ 0x1, 0x2, 0xg, 0x4, 0x5, 0x6]\n"),
    ("file", "delta_theta = [0,0,0,0,0,0]\ndelta_theta = [0,0,0,0,0,0]\n"),
])
def test_corrupt_calibration_conf_names_file_and_field(tmp_path, field, text):
    path = tmp_path / "calibration.conf"
    path.write_text("[mounting]\n" + text)
    with pytest.raises(CalibrationError) as caught:
        robot_from_calibration_conf(path, "UR5e")
    assert caught.value.field == field and str(path) in str(caught.value)


# --------------------------------------------------------------------------------------
# (c) ROS's ur_calibration output


def test_ros_default_kinematics_read_back_with_the_controllers_hash(tmp_path):
    """The UR5e as the simulator reports it (alpha = 1.570796327, the package's precision)
    written as ur_calibration writes it: the hash of UR's ROS description file."""
    p = dh_parameters(ur5e())
    names = dh_parameter_names(ur5e())
    for i, sign in ((1, 1), (4, 1), (5, -1)):
        p[names.index(f"alpha{i}")] = sign * 1.570796327
    reported = robot_from_dh_parameters(ur5e(), p)
    path = tmp_path / "ur5e.yaml"
    path.write_text(ros_yaml(dh_origins(reported), ROS_HASHES["UR5e"]))
    robot = robot_from_ros_calibration(path, model="UR5e", expected_hash=ROS_HASHES["UR5e"])
    assert robot.bare and np.abs(robot.fk(Q) - reported.fk(Q)).max() < 1e-12


@pytest.mark.parametrize("seed", [6, 7, 8])
def test_ros_calibration_of_a_calibrated_arm_reads_back_the_controllers_arm(tmp_path, seed):
    """Frames slid along the joint axes (as ur_calibration slides them) change the numbers of
    the file, not the arm: the DH parameters read back hash to the controller's hash, and
    forward kinematics is the controller's arm's to 1e-9 m."""
    origins, robot = physically_perturbed_ur5e(seed)
    digest = kinematics_info_from_robot(robot).hash
    path = tmp_path / "calibrated.yaml"
    path.write_text(ros_yaml(moved_along_axes(origins, seed), digest))
    read = robot_from_ros_calibration(path, model="UR5e", expected_hash=digest)
    position, rotation = pose_errors(read.fk(Q), robot.fk(Q))
    assert position.max() < 1e-9 and rotation.max() < 1e-9
    assert read.name == "UR5e (calibrated)"


def test_ros_calibration_edited_or_of_another_robot_is_refused(tmp_path):
    origins, robot = physically_perturbed_ur5e(9)
    digest = kinematics_info_from_robot(robot).hash
    path = tmp_path / "calibrated.yaml"
    text = ros_yaml(origins, digest)
    path.write_text(text)
    with pytest.raises(CalibrationError, match="another robot") as caught:
        robot_from_ros_calibration(path, expected_hash=ROS_HASHES["UR5e"])
    assert caught.value.field == "kinematics.hash"
    edited = origins.copy()
    edited[2, 0, 3] += 1e-3                              # the forearm one millimetre longer
    path.write_text(ros_yaml(edited, digest))
    with pytest.raises(CalibrationError, match="edited or damaged") as caught:
        robot_from_ros_calibration(path)
    assert caught.value.field == "kinematics.hash"
    path.write_text(ros_yaml(origins, digest))
    with pytest.raises(CalibrationError, match="not a UR10e"):
        robot_from_ros_calibration(path, model="UR10e")


def _edit_forearm_pitch(text):
    start, end = text.index("  forearm:"), text.index("  wrist_1:")
    block = text[start:end]
    return text[:start] + block.replace(block.splitlines()[5], "    pitch: oops") + text[end:]


@pytest.mark.parametrize("field, edit", [
    ("kinematics.forearm.pitch", lambda t: _edit_forearm_pitch(t)),
    ("kinematics.wrist_2", lambda t: t.replace("  wrist_2:", "  wrist_two:")),
    ("kinematics.hash", lambda t: t.replace("hash: calib_", "hash: ")),
    ("kinematics", lambda t: t.replace("kinematics:", "kinematic:")),
    ("file", lambda t: t + "  - [unbalanced\n"),
])
def test_corrupt_ros_calibration_names_file_and_field(tmp_path, field, edit):
    path = tmp_path / "calibration.yaml"
    path.write_text(edit(ros_yaml(dh_origins(ur5e()), ROS_HASHES["UR5e"])))
    with pytest.raises(CalibrationError) as caught:
        robot_from_ros_calibration(path)
    assert caught.value.field == field and str(path) in str(caught.value)


# --------------------------------------------------------------------------------------
# The DH parameters of a chain of joint origins


def test_joint_origins_with_a_moved_base_and_a_tool_keep_forward_kinematics():
    rng = np.random.default_rng(12)
    origins = dh_origins(ur10())
    B = np.eye(4)
    B[:3, :3], B[:3, 3] = rot_x(0.3) @ rot_z(0.2), (0.1, -0.2, 0.3)
    origins[0] = B @ origins[0]                          # joint 1 not about the world z
    origins = moved_along_axes(origins, 13)
    robot = robot_from_joint_origins(origins)
    assert not robot.bare
    assert np.abs(robot.fk(Q) - chain_fk(origins, Q)).max() < 1e-12
    q = rng.uniform(-np.pi, np.pi, (5, 6))
    assert np.abs(robot.fk(q) - chain_fk(origins, q)).max() < 1e-12


def test_joint_origins_far_away_keep_forward_kinematics_or_are_refused():
    """Origins 1e300 m apart give the chain's own forward kinematics (no overflow in a norm);
    beyond what a float holds, a clear refusal."""
    origins = dh_origins(ur5e())
    origins[:, 0, 3] = -1e300
    robot = robot_from_joint_origins(origins)
    assert np.abs(robot.fk(Q) - chain_fk(origins, Q)).max() < 1e-15 * 1e300
    origins[:, 0, 3] = 1.5e308
    with pytest.raises(ValueError, match="^origins are too large"):
        robot_from_joint_origins(origins)


def test_joint_origins_of_a_controllers_arm_give_its_dh_parameters_back():
    """Reading the DH parameters of a physically perturbed arm (far common normals), then
    its origins, then the parameters again, gives the same parameters."""
    origins, robot = physically_perturbed_ur5e(14)
    again = robot_from_joint_origins(dh_origins(robot))
    for a, b in zip(robot.links, again.links, strict=True):
        assert abs(a.theta_offset - b.theta_offset) < 1e-12 and abs(a.alpha - b.alpha) < 1e-12
        assert abs(a.a - b.a) < 1e-9 and abs(a.d - b.d) < 1e-9
    assert np.abs(robot.fk(Q) - chain_fk(origins, Q)).max() < 1e-9
    assert MODEL_TOLERANCE > pose_errors(robot.fk(Q), ur5e().fk(Q))[0].max() > 1e-4


def test_model_names_are_read_loosely():
    info = kinematics_info_from_robot(ur3())
    for spelling in ("UR3", "ur3", " ur3 ".strip()):
        robot_from_kinematics_info(info, model=spelling)
    robot_from_kinematics_info(kinematics_info_from_robot(UR_MODELS["UR8 Long"]()),
                               model="ur8_long")


# --------------------------------------------------------------------------------------
# Golden data: genuine files no one here wrote (tests/data/ur_calibration/ORIGIN.md)

DATA = Path(__file__).parent / "data" / "ur_calibration"
#: The genuine ur_calibration files and the model of each robot.
GENUINE_YAML = {"liu_jinxin_ur5e.yaml": "UR5e", "kiminyeop_ur5e.yaml": "UR5e",
                "kevinhpham_ur3e_1.yaml": "UR3e", "kevinhpham_ur3e_4.yaml": "UR3e",
                "kevinhpham_ursim_ur3e.yaml": "UR3e", "jinxiao_ur10.yaml": "UR10"}


def _file_origins(path, fixed_axes=False):
    """The joint origins of a ur_calibration file, computed here from its numbers with
    R = Rx(roll) Ry(pitch) Rz(yaw) (Eigen's eulerAngles(0, 1, 2), which wrote them), or
    with ``fixed_axes`` as a URDF reads them, R = Rz(yaw) Ry(pitch) Rx(roll)."""
    import yaml

    kinematics = yaml.safe_load(path.read_text())["kinematics"]
    S = np.tile(np.eye(4), (6, 1, 1))
    for i, link in enumerate(ROS_LINKS):
        v = kinematics[link]
        rx, ry, rz = rot_x(v["roll"]), rot_y(v["pitch"]), rot_z(v["yaw"])
        S[i, :3, :3] = rz @ ry @ rx if fixed_axes else rx @ ry @ rz
        S[i, :3, 3] = v["x"], v["y"], v["z"]
    return S, kinematics["hash"]


def _logged_kinematics_info(path):
    """The Client Library's KinematicsInfo::toString() as ur_calibration logged it."""
    fields = {}
    for line in path.read_text().splitlines():
        key, _, rest = line.partition(":")
        fields[key] = rest.strip().strip("[]").split()
    return KinematicsInfo(tuple(int(c) for c in fields["checksum"]),
                          *(tuple(float(v) for v in fields[k])
                            for k in ("dh_theta", "dh_a", "dh_d", "dh_alpha")),
                          int(fields["calibration_status"][0]))


@pytest.mark.parametrize("name", sorted(GENUINE_YAML))
def test_every_genuine_ur_calibration_file_is_read_with_its_controllers_values(name):
    """Each published file is accepted: the DH parameters found hash to the file's hash (the
    controller's own values, theta_3 = 6.1968 on one UR5e), and the arm is the file's chain
    (forward kinematics of its origins, computed here) to 1e-9 m, of the right model."""
    path = DATA / name
    origins, digest = _file_origins(path)
    robot = robot_from_ros_calibration(path, model=GENUINE_YAML[name], expected_hash=digest)
    assert kinematics_info_from_robot(robot).hash == digest
    position, rotation = pose_errors(robot.fk(Q), chain_fk(origins, Q))
    assert position.max() < 1e-9 and rotation.max() < 1e-9
    assert all(abs(lk.theta_offset) <= 3 * np.pi for lk in robot.links)


def test_the_controllers_logged_values_hash_to_the_file_it_wrote_and_are_read_back():
    """One robot, two published records: the kinematics info ur_calibration logged and the
    file it wrote. The values hash to the file's hash; the file reads back those values."""
    info = _logged_kinematics_info(DATA / "liu_jinxin_ur5e_kinematics_info.log")
    assert info.hash == "calib_3992041561913322003" and info.calibration_status == 2
    robot = robot_from_ros_calibration(DATA / "liu_jinxin_ur5e.yaml", model="UR5e")
    read = kinematics_info_from_robot(robot)
    for mine, logged in zip((read.theta, read.a, read.d, read.alpha),
                            (info.theta, info.a, info.d, info.alpha), strict=True):
        np.testing.assert_allclose(mine, logged, rtol=1e-12, atol=1e-12)
    assert max(abs(d) for d in info.d) > 300                  # hundreds of metres in d
    controller = robot_from_kinematics_info(info, model="UR5e")
    assert pose_errors(robot.fk(Q), controller.fk(Q))[0].max() < 1e-9


def test_roll_pitch_yaw_are_read_in_the_order_ur_calibration_writes_them():
    """Eigen's eulerAngles(0, 1, 2): R = Rx Ry Rz. Read so, the file gives the controller's
    arm to 1e-9 m; read as URDF's fixed axes (Rz Ry Rx) it is 2 micrometres off here (30 on
    the UR10's file): a thousand times more."""
    info = _logged_kinematics_info(DATA / "liu_jinxin_ur5e_kinematics_info.log")
    controller = robot_from_kinematics_info(info).fk(Q)
    origins, _ = _file_origins(DATA / "liu_jinxin_ur5e.yaml")
    assert pose_errors(chain_fk(origins, Q), controller)[0].max() < 1e-9
    fixed, _ = _file_origins(DATA / "liu_jinxin_ur5e.yaml", fixed_axes=True)
    assert pose_errors(chain_fk(fixed, Q), controller)[0].max() > 1e-6


def test_the_client_librarys_ursim_capture_gives_what_its_own_test_expects():
    """URSim 5.8's first robot state of a UR5e (1386 bytes, 13 sub-packages): the kinematics
    info the Client Library's test_primary_parser.cpp expects, and UR's ROS hash."""
    message = (DATA / "ursim_5_8_ur5e_robot_state.bin").read_bytes()
    assert len(message) == 1386
    info = kinematics_info_from_message(message)
    assert info.checksum == (UNCALIBRATED,) * 6 and info.theta == (0.0,) * 6
    assert info.a == (0, -0.425, -0.3922, 0, 0, 0)
    assert info.d == (0.1625, 0, 0, 0.1333, 0.0997, 0.0996)
    assert info.alpha == (1.570796327, 0, 0, 1.570796327, -1.570796327, 0)
    assert info.hash == ROS_HASHES["UR5e"]


def _controller_values():
    import json

    return json.loads((DATA / "ur_calibration_controller_values.json").read_text())


def test_real_corrections_of_ur_calibrations_tests_make_arms_of_their_model():
    """Three controllers' corrections (metres of d on joints 2-4, theta_3 = 7.129 rad): each
    gives an arm millimetres from its model; the UR10e's is the one its documentation
    prints as the controller's DH parameters, digit for digit, and hashes the same."""
    values = list(_controller_values().values())
    for entry in values[:3]:
        conf = CalibrationConf(*(tuple(entry[k]) for k in
                                 ("delta_theta", "delta_a", "delta_d", "delta_alpha")))
        robot = robot_from_corrections(conf, entry["model"])
        gap = pose_errors(robot.fk(Q), UR_MODELS[entry["model"]]().fk(Q))[0].max()
        assert 1e-4 < gap < 1e-2
    documented = values[3]
    info = kinematics_info_from_robot(robot)
    np.testing.assert_allclose(info.d, documented["dh_d"], rtol=1e-14)
    np.testing.assert_allclose(info.theta, documented["dh_theta"], rtol=1e-13)
    np.testing.assert_allclose(info.a, documented["dh_a"], rtol=1e-13)
    # (the controller adds the corrections to its alpha = 1.570796327, dqlab's is pi / 2)
    np.testing.assert_allclose(info.alpha, documented["dh_alpha"], rtol=0, atol=3e-10)
    assert info.hash == KinematicsInfo(info.checksum, *(tuple(documented[k]) for k in (
        "dh_theta", "dh_a", "dh_d", "dh_alpha"))).hash


def test_a_genuine_calibration_conf_reads_into_an_arm_of_its_model():
    """A UR5's file as quoted (header with trailing spaces, four deltas of hundreds of
    metres): an arm millimetres from the nominal UR5."""
    path = DATA / "ur_modern_driver_179_ur5.conf"
    conf = read_calibration_conf(path)
    assert conf.delta_d[1] == 278.244144925623573 and conf.joint_checksum is None
    robot = robot_from_calibration_conf(path, "UR5")
    assert 1e-4 < pose_errors(robot.fk(Q), ur5().fk(Q))[0].max() < 1e-2
    with pytest.raises(CalibrationError, match="not a UR10"):
        robot_from_calibration_conf(path, "UR10e")


def test_a_calibration_conf_quoted_without_its_header_gets_a_precise_message(tmp_path):
    """The UR3 file of an issue, as quoted (no [mounting] line, extra keys): refused naming
    the line and the header; with the header the controller writes, read whole."""
    path = DATA / "myrobotlab_145_ur3.conf"
    with pytest.raises(CalibrationError, match=r"line 1: no section header .*'\[mounting\]'"):
        read_calibration_conf(path)
    whole = tmp_path / "calibration.conf"
    whole.write_text("[mounting]\n" + path.read_text())
    conf = read_calibration_conf(whole)
    assert conf.joint_checksum == (0xB3241580, 0xB10112F1, 0x290CAC88, 0xA8D3F155, 0xA8B7E9EB,
                                   0xA8DBBFA3)
    assert conf.calibration_status == 2 and conf.delta_theta[2] == 6.68283349819805572
    robot = robot_from_calibration_conf(whole, "UR3", checksum=conf.joint_checksum)
    assert 1e-4 < pose_errors(robot.fk(Q), ur3().fk(Q))[0].max() < 1e-2
    bom = tmp_path / "bom.conf"
    bom.write_bytes(b"\xef\xbb\xbf" + whole.read_bytes())
    with pytest.raises(CalibrationError, match="byte-order mark"):
        read_calibration_conf(bom)


# --------------------------------------------------------------------------------------
# The Client Library's edge cases


def test_the_hash_text_is_cs_printf_g_without_rounding_to_zero():
    """C++ streams a double as printf's %g (libc's snprintf, called here, is the oracle):
    -0.0 prints "-0" and 1e-17 "1e-17", as toHash() streams them; nothing is zeroed."""
    import ctypes
    import ctypes.util

    libc = ctypes.CDLL(ctypes.util.find_library("c"))
    buf = ctypes.create_string_buffer(64)

    def printf_g(x):
        libc.snprintf(buf, 64, b"%g", ctypes.c_double(x))
        return buf.value.decode()

    rng = np.random.default_rng(7)
    values = np.concatenate([[0.0, -0.0, 1e-17, -3e-13, 1e300, 439.140974079901, 0.1625],
                             rng.normal(0, 1, 200) * 10.0 ** rng.integers(-20, 5, 200)])
    for x in values:
        assert "%g" % x == printf_g(x)
    base = kinematics_info_from_robot(ur5e())
    theta = (-0.0, *base.theta[1:])
    tiny = (1e-17, *base.theta[1:])
    assert len({base.hash, KinematicsInfo(base.checksum, theta, base.a, base.d, base.alpha).hash,
                KinematicsInfo(base.checksum, tiny, base.a, base.d, base.alpha).hash}) == 3


def test_the_batch_hash_equals_the_readable_one():
    rng = np.random.default_rng(8)
    texts = [bytes(rng.integers(32, 127, n).astype(np.uint8)) for n in range(0, 60)]
    fast = _std_hash_many(texts)
    assert [int(h) for h in fast] == [_std_hash(t) for t in texts]


def test_trailing_bytes_after_the_kinematics_info_warn_and_are_ignored():
    """The Client Library's own case: 10 bytes 0xAA after the 220, then another sub-package
    (its parser warns outside strict mode and carries on)."""
    info = kinematics_info_from_robot(ur10e(), checksum=(1, 2, 3, 4, 5, 6))
    body = message_from_kinematics_info(info)[10:] + b"\xaa" * 10
    kin = struct.pack(">IB", 5 + len(body), 5) + body
    other = struct.pack(">IB", 6, 8) + b"\x42"
    message = struct.pack(">iB", 5 + len(kin) + len(other), 16) + kin + other
    with pytest.warns(UserWarning, match="10 trailing bytes are ignored"):
        assert kinematics_info_from_message(message) == info


# --------------------------------------------------------------------------------------
# Bounded readers and argument checks


def _one_line_naming(exc, *words):
    message = str(exc.value)
    return "\n" not in message and len(message) < 400 and all(w in message for w in words)


@pytest.mark.parametrize("case", ["billion laughs", "50 MB", "nesting", "400 digits"])
def test_a_hostile_ros_calibration_file_is_refused_quickly_in_one_line(tmp_path, case):
    import time

    path = tmp_path / "calibration.yaml"
    if case == "billion laughs":
        lines = ["a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
        lines += [f"{chr(98 + k)}: &{chr(98 + k)} [{', '.join(['*' + chr(97 + k)] * 9)}]"
                  for k in range(8)]
        path.write_text("\n".join(lines) + "\nkinematics: *i\n")
        field = "file"
    elif case == "50 MB":
        with open(path, "wb") as f:
            f.truncate(50 * 1024 * 1024)
        field = "file"
    elif case == "nesting":
        path.write_text("kinematics: " + "[" * 3000 + "]" * 3000 + "\n")
        field = "file"
    else:
        text = ros_yaml(dh_origins(ur5e()), ROS_HASHES["UR5e"])
        path.write_text(text.replace("    z: 0.1625", "    z: " + "9" * 400, 1))
        field = "kinematics.shoulder.z"
    start = time.monotonic()
    with pytest.raises(CalibrationError) as caught:
        robot_from_ros_calibration(path)
    assert time.monotonic() - start < 1.0
    assert caught.value.field == field and _one_line_naming(caught, str(path), field)


def test_a_huge_calibration_conf_or_value_is_refused_in_one_line(tmp_path):
    path = tmp_path / "calibration.conf"
    with open(path, "wb") as f:
        f.truncate(50 * 1024 * 1024)
    with pytest.raises(CalibrationError, match="more than 65536 bytes") as caught:
        read_calibration_conf(path)
    assert _one_line_naming(caught, str(path))
    path.write_text("[mounting]\ndelta_theta = [0,0,0,0,0,0]\ndelta_a = [0,0,0,0,0,0]\n"
                    "delta_d = [0,0,0,0,0,0]\ndelta_alpha = [0,0,0,0,0,0]\n"
                    f"joint_checksum = [{'9' * 400},0,0,0,0,0]\n")
    with pytest.raises(CalibrationError) as caught:
        read_calibration_conf(path)
    assert caught.value.field == "joint_checksum" and _one_line_naming(caught, str(path))


@pytest.mark.parametrize("model", [None, 123, 5, 2.5, ["UR5e"]])
def test_a_model_that_is_not_a_model_names_model(model, tmp_path):
    conf = CalibrationConf((0.0,) * 6, (0.0,) * 6, (0.0,) * 6, (0.0,) * 6)
    path = tmp_path / "calibration.conf"
    path.write_text("[mounting]\ndelta_theta = [0,0,0,0,0,0]\ndelta_a = [0,0,0,0,0,0]\n"
                    "delta_d = [0,0,0,0,0,0]\ndelta_alpha = [0,0,0,0,0,0]\n")
    calls = [lambda: robot_from_corrections(conf, model),
             lambda: robot_from_calibration_conf(path, model)]
    if model is not None:                       # optional there: None is "no model"
        info = kinematics_info_from_robot(ur5e())
        calls += [lambda: robot_from_kinematics_info(info, model=model),
                  lambda: robot_from_ros_calibration(DATA / "kiminyeop_ur5e.yaml",
                                                     model=model)]
    for call in calls:
        with pytest.raises(ValueError, match=r"^model must be one of .* or a Robot"):
            call()


@pytest.mark.parametrize("checksum, status, name", [
    ((1, 2, 3, 4, 5, 2 ** 32), 2, r"checksum\[5\]"), ((1,) * 6, 2 ** 32, "calibration_status"),
    ((1,) * 6, 2.7, "calibration_status"), ((1,) * 6, True, "calibration_status"),
    ((1.5,) * 6, 2, r"checksum\[0\]"), ((-1,) * 6, 2, r"checksum\[0\]"),
    ((1,) * 5, 2, "checksum"), ("123456", 2, "checksum")])
def test_checksums_and_status_are_unsigned_32_bit_integers(checksum, status, name):
    with pytest.raises(ValueError, match=f"^{name} must be"):
        kinematics_info_from_robot(ur5e(), checksum=checksum, calibration_status=status)


def test_kinematics_info_is_checked_when_it_is_made():
    """What the controller's message cannot carry is refused by its field, before a message
    packs NaN or struct fails on a number; the encoder and decoder name their argument."""
    info = kinematics_info_from_robot(ur5e())
    fields = dict(checksum=info.checksum, theta=info.theta, a=info.a, d=info.d,
                  alpha=info.alpha, calibration_status=0)
    for field, bad, error in [("d", (math.nan,) * 6, ValueError), ("theta", (0.0,) * 5, ValueError),
                              ("a", None, TypeError), ("alpha", ("0",) * 6, TypeError),
                              ("checksum", (2 ** 32,) * 6, ValueError),
                              ("calibration_status", True, ValueError)]:
        with pytest.raises(error, match=rf"^{field}(\[0\])? must"):
            KinematicsInfo(**{**fields, field: bad})
    assert KinematicsInfo(**{**fields, "d": np.array(info.d)}) == info     # as tuples
    with pytest.raises(TypeError, match="^info must be a KinematicsInfo, got None"):
        message_from_kinematics_info(None)
    with pytest.raises(TypeError, match="^message must be bytes, got 'abc'"):
        kinematics_info_from_message("abc")


@pytest.mark.parametrize("kwargs, name", [
    (dict(host=None), "host"), (dict(host=""), "host"), (dict(host=123), "host"),
    (dict(host="x\ud800"), "host"), (dict(host="x\ny"), "host"),
    (dict(port=30002 + 65536), "port"), (dict(port=0), "port"), (dict(port="30002"), "port"),
    (dict(port=30002.0), "port"), (dict(timeout=0), "timeout"),
    (dict(timeout=float("nan")), "timeout"), (dict(timeout="1"), "timeout"),
    (dict(timeout=float("inf")), "timeout"), (dict(timeout=-1), "timeout")])
def test_read_kinematics_info_refuses_bad_arguments_by_name(kwargs, name):
    args = {"host": "127.0.0.1", "port": 30002, "timeout": 1.0, **kwargs}
    with pytest.raises((TypeError, ValueError), match=f"^{name} must be"):
        read_kinematics_info(args.pop("host"), **args)
