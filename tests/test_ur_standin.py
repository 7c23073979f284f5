"""The controller stand-in: the thesis's record/replay loop end to end, RTDE, and cleanliness."""

import os
import socket
import struct
import threading
import time
from types import SimpleNamespace

import numpy as np
import pytest

import dqlab
from dqlab.ur import HOME, ControllerStandIn, URClient
from dqlab.ur import rtde as R

psutil = pytest.importorskip("psutil", reason="psutil (test extra) checks for leftovers")


def _open_fds():
    return len(os.listdir("/proc/self/fd")) if os.path.isdir("/proc/self/fd") else 0


@pytest.fixture
def standin():
    with ControllerStandIn(speedup=25) as s:
        yield s


def test_record_file_ik_movej_round_trip(standin, tmp_path):
    """The thesis's program: record a pose to a file, later read it, solve IK, movej there."""
    robot = dqlab.models.ur3()
    q_recorded = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])
    path = tmp_path / "poses.csv"
    with URClient(standin.backend(), poll_interval=0.001) as ur:
        ur.movej(q_recorded)
        # record: joints -> forward kinematics -> dual quaternion -> file
        Q = robot.fk_dq(ur.actual_q())
        dqlab.ur.append_pose(path, Q, name="recorded", kind="dual_quaternion")
        ur.movej(HOME)
        # replay: file -> IK -> the solution closest to the current joints -> movej
        X_WF = dqlab.ur.read_poses(path).transforms()[0]
        result = dqlab.ik.ur(robot, X_WF)
        q_chosen = dqlab.ik.closest_solution(result, ur.actual_q())
        final = ur.movej(q_chosen)
        np.testing.assert_allclose(ur.actual_q(), q_chosen, atol=1e-9, rtol=0)
        np.testing.assert_allclose(final.q, q_chosen, atol=1e-9, rtol=0)
        np.testing.assert_allclose(q_chosen, q_recorded, atol=1e-9)
        np.testing.assert_allclose(ur.actual_tcp_pose(),
                                   dqlab.ur.pose_from_dual_quaternion(Q), atol=1e-9)
        assert int(result.count) == 4          # a real choice among branches


def test_movel_and_a_trajectory_program(standin):
    # a wave from rest to rest (one that starts at full speed is refused: see test_ur_script)
    t = np.linspace(0.0, 0.5, 26)
    q_mid = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])
    q = q_mid + np.outer(np.sin(np.pi * t) ** 2, [0.2, 0.1, -0.1, 0.0, 0.3, 0.0])
    program = dqlab.ur.program_from_trajectory(SimpleNamespace(t=t, q=q), name="wave")
    backend = standin.backend()
    with URClient(backend, poll_interval=0.001) as ur:
        ur.movej(q_mid)
        backend.send_script(program)
        final = ur._wait_joints(q[-1], 10.0, "program")
        np.testing.assert_allclose(final.q, q[-1], atol=1e-12)
        goal = ur.actual_tcp_pose() + [0.03, 0.02, -0.05, 0, 0, 0]
        state = ur.movel(goal, a=0.5, v=0.2)       # (a = 1.2 peaks joint 3 at 10.8 rad/s^2)
        np.testing.assert_allclose(state.tcp_pose, goal, atol=1e-9)


def test_a_refused_program_moves_nothing(standin):
    backend = standin.backend()
    with URClient(backend, poll_interval=0.001) as ur:
        before = ur.actual_q()
        backend.send_script("movej([9.0, 0, 0, 0, 0, 0])")       # beyond joint 1's limit
        backend.send_script("def p():\n  movej([0.1, -1.5, 0, -1.5, 0, 0])\n  popup(1)\nend")
        time.sleep(0.2)
        np.testing.assert_array_equal(ur.actual_q(), before)
        assert ur.read_state().robot_mode == 7
    err = standin.log()
    assert "program refused" in err and "outside its limits" in err and "popup" in err


def test_rtde_handshake_versions_and_recipes(standin):
    reader = R.RTDEReader(standin.host, standin.rtde_port, frequency=250)
    reader.connect(5.0)
    try:
        assert reader.controller_version == (5, 11, 0, 0)
        assert reader.types == ("DOUBLE", "VECTOR6D", "VECTOR6D", "VECTOR6D", "INT32")
        a = reader.read()
        time.sleep(0.02)
        b = reader.read()
        assert b["timestamp"] > a["timestamp"]
        np.testing.assert_array_equal(a["actual_q"], HOME)
        assert a["robot_mode"] == 7
    finally:
        reader.close()
    bad = R.RTDEReader(standin.host, standin.rtde_port, variables=["actual_q", "joint_torques"])
    with pytest.raises(R.RTDEError, match=r"does not serve the RTDE outputs \['joint_torques'\]"):
        bad.connect(5.0)
    with socket.create_connection((standin.host, standin.rtde_port), timeout=5) as s:
        s.sendall(R.pack(R.REQUEST_PROTOCOL_VERSION, struct.pack(">H", 7)))
        assert s.recv(16) == R.pack(R.REQUEST_PROTOCOL_VERSION, b"\x00")
        s.sendall(R.pack(R.CONTROL_PACKAGE_START))
        assert s.recv(16) == R.pack(R.CONTROL_PACKAGE_START, b"\x00")   # no recipe yet


def test_rtde_pause_stops_the_data_packages(standin):
    with socket.create_connection((standin.host, standin.rtde_port), timeout=5) as s:
        buf = R.PacketBuffer()

        def packages(seconds):
            """Every package received during the next ``seconds``."""
            deadline = time.monotonic() + seconds
            got = []
            while (remaining := deadline - time.monotonic()) > 0:
                s.settimeout(remaining)
                try:
                    data = s.recv(65536)
                except socket.timeout:
                    break
                assert data, "the stand-in closed the connection"
                got += buf.feed(data)
            return got

        s.sendall(R.pack(R.REQUEST_PROTOCOL_VERSION, struct.pack(">H", 2)))
        s.sendall(R.pack(R.CONTROL_PACKAGE_SETUP_OUTPUTS,
                         struct.pack(">d", 100.0) + b"timestamp,actual_q"))
        s.sendall(R.pack(R.CONTROL_PACKAGE_START))
        got = packages(0.3)
        assert got[:3] == [(ord("V"), b"\x01"), (ord("O"), b"\x01DOUBLE,VECTOR6D"),
                           (ord("S"), b"\x01")]
        data = [body for ptype, body in got if ptype == R.DATA_PACKAGE]
        assert 10 <= len(data) <= 40 and all(len(b) == 1 + 7 * 8 for b in data)
        s.sendall(R.pack(R.CONTROL_PACKAGE_PAUSE))
        got = packages(0.2)
        paused_at = [ptype for ptype, _ in got].index(ord("P"))
        assert got[paused_at] == (ord("P"), b"\x01")
        assert packages(0.2) == []                   # nothing after the pause


def test_standin_listens_on_loopback_only(standin):
    conns = psutil.Process(standin.pid).net_connections(kind="inet")
    listening = [c for c in conns if c.status == psutil.CONN_LISTEN]
    assert {c.laddr.port for c in listening} == {standin.primary_port, standin.secondary_port,
                                                 standin.rtde_port}
    assert all(c.laddr.ip == "127.0.0.1" for c in conns)


def test_nothing_is_left_behind():
    threads, fds = threading.active_count(), _open_fds()
    standin = ControllerStandIn(speedup=25)
    with standin:
        pid = standin.pid
        with URClient(standin.backend(), poll_interval=0.001) as ur:
            ur.movej(np.add(HOME, [0.1, 0, 0, 0, 0, 0]))
    assert not standin.running
    assert not psutil.pid_exists(pid) or psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    assert psutil.Process().children(recursive=True) == []
    assert threading.active_count() == threads
    assert _open_fds() == fds
    standin.stop()                                   # idempotent


def test_the_standin_exits_when_its_parent_goes_away():
    standin = ControllerStandIn().start()
    proc = standin._proc
    proc.stdin.close()                               # what the parent's death does
    assert proc.wait(10) == 0
    standin.stop()


def test_a_failed_start_says_why():
    with pytest.raises(ValueError, match="model must name a function of dqlab.models"):
        ControllerStandIn(model="nope")
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        with pytest.raises(RuntimeError, match="Address already in use"):
            ControllerStandIn(rtde_port=busy.getsockname()[1]).start()


def test_connecting_where_nothing_listens_fails_fast():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    backend = dqlab.ur.SecondaryInterfaceBackend("127.0.0.1", port, rtde_port=port)
    with pytest.raises(ConnectionRefusedError):
        backend.connect(1.0)


def _port_free(port):
    with socket.socket() as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def test_ur_rtde_receive_interface_reads_the_standin():
    rtde_receive = pytest.importorskip(
        "rtde_receive", reason="ur_rtde is not installed (optional extra 'robot')")
    if not _port_free(30004):
        pytest.skip("ur_rtde connects to port 30004 only, and 127.0.0.1:30004 is in use")
    target = np.array([-0.3, -1.2, 0.9, -1.1, 0.4, 0.2])
    with ControllerStandIn(speedup=25, rtde_port=30004) as standin:
        rx = rtde_receive.RTDEReceiveInterface(
            "127.0.0.1", 125.0, ["timestamp", "actual_q", "actual_qd", "actual_TCP_pose",
                                 "robot_mode"])
        try:
            deadline = time.monotonic() + 5
            while rx.getTimestamp() == 0.0 and time.monotonic() < deadline:
                time.sleep(0.01)
            np.testing.assert_array_equal(rx.getActualQ(), HOME)
            assert rx.getRobotMode() == 7
            with URClient(standin.backend(), poll_interval=0.001) as ur:
                ur.movej(target)
            deadline = time.monotonic() + 5
            while not np.allclose(rx.getActualQ(), target) and time.monotonic() < deadline:
                time.sleep(0.01)
            np.testing.assert_allclose(rx.getActualQ(), target, atol=1e-12)
            np.testing.assert_allclose(rx.getActualTCPPose(), dqlab.ur.pose_from_transform(
                dqlab.models.ur3().fk(target)), atol=1e-12)
            # ur_rtde's default recipe (every output) connects too
            rx_all = rtde_receive.RTDEReceiveInterface("127.0.0.1", 125.0)
            try:
                time.sleep(0.05)
                np.testing.assert_allclose(rx_all.getActualQ(), target, atol=1e-12)
                assert rx_all.getActualCurrent() == [0.0] * 6      # served as zeros
            finally:
                rx_all.disconnect()
            # and dqlab's own ur_rtde back end, read-only against the stand-in
            with URClient(dqlab.ur.RTDEBackend("127.0.0.1", frequency=125.0,
                                               control=False)) as ur:
                np.testing.assert_allclose(ur.actual_q(), target, atol=1e-12)
                with pytest.raises(RuntimeError, match="control=False"):
                    ur.backend.movej(HOME, a=1, v=1, t=0, r=0)
        finally:
            rx.disconnect()
