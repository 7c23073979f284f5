"""The primary/secondary-interface stream as real clients read it: dqlab's reader on URSim's
recorded message (UR's Client Library), the stand-in's stream read by an independent decoder
(tests/ur_primary_decoder.py) and by python-urx."""

import socket
import time
from pathlib import Path

import numpy as np
import pytest
import ur_primary_decoder as independent

from dqlab.models import ur5e
from dqlab.ur import ControllerStandIn, URClient, pose_from_transform
from dqlab.ur.calibration import kinematics_info_from_robot, robot_from_kinematics_info
from dqlab.ur.secondary import (
    _sub_packages,
    pack_cartesian_info,
    pack_joint_data,
    pack_robot_mode_data,
    robot_state_from_message,
    version_from_message,
)

psutil = pytest.importorskip("psutil", reason="psutil (test extra) checks for leftovers")

DATA = Path(__file__).parent / "data" / "ur_calibration"
CAPTURE = (DATA / "ursim_5_8_ur5e_robot_state.bin").read_bytes()
Q = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])


def test_dqlabs_reader_reads_urs_recorded_message_bit_exactly():
    """URSim 5.8's robot state: the four sub-packages dqlab reads are written back by dqlab's
    writers byte for byte; the values are those of the independent decoder; the TCP pose is
    the forward kinematics of the joints on the kinematics info's arm (to 1e-15 m)."""
    state = robot_state_from_message(CAPTURE)
    assert state.package_types == (0, 1, 4, 5, 9, 3, 2, 6, 7, 8, 10, 11, 12)
    original = dict(_sub_packages(CAPTURE, "capture"))
    assert pack_robot_mode_data(state.robot_mode) == original[0]
    assert pack_joint_data(state.joints) == original[1]
    assert pack_cartesian_info(state.cartesian) == original[4]
    other = independent.decode(CAPTURE)["packages"]
    assert other[0]["robot_mode"] == state.robot_mode.robot_mode == 7
    assert other[0]["timestamp"] == state.robot_mode.timestamp
    assert other[1]["q_actual"] == list(state.joints.q_actual)
    assert other[4]["tcp_pose"] == list(state.cartesian.tcp_pose)
    assert other[5]["dh_d"] == list(state.kinematics.d)
    arm = robot_from_kinematics_info(state.kinematics)
    tcp = pose_from_transform(arm.fk(np.array(state.joints.q_actual)))
    np.testing.assert_allclose(tcp, state.cartesian.tcp_pose, rtol=0, atol=1e-14)


def test_dqlabs_reader_reads_urs_recorded_version_message():
    message = (DATA / "ursim_version_message.bin").read_bytes()
    version = version_from_message(message)
    assert (version.project_name, version.major, version.minor, version.bugfix,
            version.build, version.build_date) == ("URControl", 5, 24, 0, 0,
                                                   "04-10-2025, 00:25:33")
    assert independent.decode(message)["version"] == ("URControl", 5, 24, 0, 0,
                                                      "04-10-2025, 00:25:33")


def _read_stream(host, port, seconds):
    """Every message the stand-in sends on ``port`` in the next ``seconds``."""
    got, rest = [], b""
    with socket.create_connection((host, port), timeout=5) as s:
        deadline = time.monotonic() + seconds
        while (left := deadline - time.monotonic()) > 0:
            s.settimeout(left)
            try:
                data = s.recv(65536)
            except socket.timeout:
                break
            assert data, "the stand-in closed the connection"
            whole, rest = independent.messages(rest + data)
            got += whole
    return got


def test_the_standin_streams_as_a_controller_on_both_ports_read_independently():
    """On the primary and the secondary port: the version message, then robot states at
    10 Hz whose joints, TCP and kinematics info -- decoded independently -- are the arm's."""
    with ControllerStandIn("ur5e", q0=Q, speedup=1.0) as standin:
        for port in (standin.primary_port, standin.secondary_port):
            stream = [independent.decode(m) for m in _read_stream(standin.host, port, 0.65)]
            assert stream[0]["version"][:3] == ("URControl", 5, 11)
            states = [m["packages"] for m in stream[1:]]
            assert 5 <= len(states) <= 8 and all(m["type"] == 16 for m in stream[1:])
            times = np.array([p[0]["timestamp"] for p in states]) * 1e-6
            assert 0.07 < np.median(np.diff(times)) < 0.15         # 10 Hz, controller time
            for p in states:
                assert sorted(p) == [0, 1, 4, 5] and p[0]["robot_mode"] == 7
                np.testing.assert_array_equal(p[1]["q_actual"], Q)
                np.testing.assert_allclose(p[4]["tcp_pose"], pose_from_transform(
                    ur5e().fk(Q)), rtol=0, atol=1e-12)
                info = kinematics_info_from_robot(ur5e())
                assert p[5]["dh_d"] == list(info.d) and p[5]["checksum"] == [0xFFFFFFFF] * 6


def test_a_moving_arm_is_streamed_and_a_silent_client_never_blocks_the_standin():
    """A client that connects and never reads is not waited for: another one moves the arm,
    and the independent decoder sees it arrive."""
    with ControllerStandIn("ur5e", speedup=25) as standin:
        with socket.create_connection((standin.host, standin.secondary_port)) as silent:
            silent.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            with URClient(standin.backend(), poll_interval=0.001) as ur:
                ur.movej(Q)
                time.sleep(0.3)
                last = independent.decode(
                    _read_stream(standin.host, standin.primary_port, 0.25)[-1])["packages"]
                np.testing.assert_allclose(last[1]["q_actual"], Q, rtol=0, atol=1e-12)
                np.testing.assert_allclose(last[4]["tcp_pose"], ur.actual_tcp_pose(),
                                           rtol=0, atol=1e-12)
        assert standin.running


@pytest.mark.filterwarnings("ignore:notifyAll:DeprecationWarning")
def test_python_urx_reads_joints_and_tcp_from_the_standin(monkeypatch):
    """python-urx's SecondaryMonitor (an independent client, optional) reads the stand-in's
    secondary interface: the joints and the TCP of its arm."""
    ursecmon = pytest.importorskip("urx.ursecmon", reason="python-urx is not installed")
    with ControllerStandIn("ur5e", q0=Q) as standin:
        port = standin.secondary_port
        real = socket.create_connection
        monkeypatch.setattr(ursecmon.socket, "create_connection",       # urx dials 30002
                            lambda address, timeout=None: real((address[0], port), timeout))
        monitor = ursecmon.SecondaryMonitor(standin.host)
        try:
            joints = monitor.get_joint_data(wait=True)
            cartesian = monitor.get_cartesian_info(wait=True)
        finally:
            monitor.close()
            monitor._s_secondary.close()
    np.testing.assert_allclose([joints[f"q_actual{k}"] for k in range(6)], Q, atol=1e-12)
    tcp = [cartesian[k] for k in ("X", "Y", "Z", "Rx", "Ry", "Rz")]
    np.testing.assert_allclose(tcp, pose_from_transform(ur5e().fk(Q)), rtol=0, atol=1e-12)
    assert psutil.Process().children(recursive=True) == []
