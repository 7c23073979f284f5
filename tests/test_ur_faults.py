"""Fault injection: a controller that lies, breaks the protocol, floods or dies, and programs
with one bad line anywhere. The client says why and keeps its deadlines; the stand-in keeps
serving and moves nothing it refused."""

import os
import select
import signal
import socket
import struct
import threading
import time

import numpy as np
import pytest

import dqlab
from dqlab.ur import HOME, ControllerError, ControllerStandIn, URClient, URState
from dqlab.ur import rtde as R
from dqlab.ur.secondary import MAX_MESSAGE_SIZE, MessageBuffer, SecondaryError
from dqlab.ur.standin import MAX_PROGRAM_SIZE

psutil = pytest.importorskip("psutil", reason="psutil (test extra) checks for leftovers")

STATE = struct.Struct(">B" + "d" + "6d" * 3 + "i")   # recipe id + STATE_VARIABLES


def state_package(t, q, qd=(0.0,) * 6, pose=(0.0,) * 6, mode=7, recipe=1):
    return R.pack(R.DATA_PACKAGE, STATE.pack(recipe, t, *q, *qd, *pose, mode))


class FakeController:
    """A scripted peer on 127.0.0.1: an RTDE port answering the handshake as ``replies``
    says, then running ``stream(sock)``, and a secondary port that reads and discards.

    The threads end when the test leaves the ``with`` block.
    """

    def __init__(self, replies=None, stream=None):
        self.replies = {R.REQUEST_PROTOCOL_VERSION: b"\x01",
                        R.GET_URCONTROL_VERSION: struct.pack(">IIII", 5, 11, 0, 0),
                        R.CONTROL_PACKAGE_SETUP_OUTPUTS:
                            b"\x01DOUBLE,VECTOR6D,VECTOR6D,VECTOR6D,INT32",
                        R.CONTROL_PACKAGE_START: b"\x01"}
        self.replies.update(replies or {})
        self.stream = stream
        self.stop = threading.Event()
        self.threads = []

    def __enter__(self):
        self.rtde = socket.create_server(("127.0.0.1", 0))
        self.secondary = socket.create_server(("127.0.0.1", 0))
        for target, srv in ((self._serve_rtde, self.rtde), (self._serve_secondary,
                                                             self.secondary)):
            srv.settimeout(0.05)
            thread = threading.Thread(target=target, args=(srv,), daemon=True)
            thread.start()
            self.threads.append(thread)
        return self

    def __exit__(self, *exc):
        self.stop.set()
        for thread in self.threads:
            thread.join(5)
        self.rtde.close()
        self.secondary.close()
        assert not any(t.is_alive() for t in self.threads)

    @property
    def ports(self):
        return self.secondary.getsockname()[1], self.rtde.getsockname()[1]

    def _accept(self, srv):
        while not self.stop.is_set():
            try:
                conn, _ = srv.accept()
            except socket.timeout:
                continue
            conn.settimeout(0.05)
            return conn
        return None

    def _serve_secondary(self, srv):
        conn = self._accept(srv)
        while conn is not None and not self.stop.is_set():
            try:
                if not conn.recv(65536):
                    break
            except socket.timeout:
                continue
            except OSError:
                break
        if conn is not None:
            conn.close()

    def _serve_rtde(self, srv):
        conn = self._accept(srv)
        if conn is None:
            return
        buf = R.PacketBuffer()
        try:
            while not self.stop.is_set():
                try:
                    data = conn.recv(65536)
                except socket.timeout:
                    continue
                if not data:
                    return
                for ptype, _ in buf.feed(data):
                    reply = self.replies.get(ptype)
                    if isinstance(reply, bytes):
                        conn.sendall(R.pack(ptype, reply))
                    elif reply is not None:              # raw bytes, header and all
                        conn.sendall(reply())
                    if ptype == R.CONTROL_PACKAGE_START and self.stream:
                        self.stream(conn, self.stop)
                        return
        except OSError:
            pass
        finally:
            conn.close()


def send_until_stopped(conn, data, stop):
    """Send all of ``data`` however long the reader leaves the socket full; False once the
    connection is gone or the test is over.

    ``sendall`` on the peer's 0.05 s timeout would give up on a full socket (the reader is
    allowed to pause) and leave a package cut in half, so a timeout here only means retry.
    """
    data = memoryview(data)
    while data:
        if stop.is_set():
            return False
        try:
            data = data[conn.send(data):]
        except socket.timeout:
            continue
        except OSError:
            return False
    return True


def flood(conn, stop):
    """Data packages as fast as the socket takes them."""
    k = 0
    while send_until_stopped(conn, state_package(0.001 * k, HOME) * 64, stop):
        k += 1


def steady(q):
    def stream(conn, stop):
        k = 0
        while send_until_stopped(conn, state_package(0.008 * k, q), stop):
            k += 1
            time.sleep(0.008)
    return stream


# --- the RTDE reader against a peer that breaks the protocol ------------------------------

@pytest.mark.parametrize("replies, words", [
    ({R.REQUEST_PROTOCOL_VERSION: b""}, "refused RTDE protocol version"),
    ({R.GET_URCONTROL_VERSION: b"\x00\x05"}, "controller version reply of 2 bytes, not 16"),
    ({R.GET_URCONTROL_VERSION: b"\x00" * 40}, "controller version reply of 40 bytes"),
    ({R.CONTROL_PACKAGE_SETUP_OUTPUTS: b""}, "empty reply to the output set-up"),
    ({R.CONTROL_PACKAGE_SETUP_OUTPUTS: b"\x01\xff\xfeDOUBLE"}, "not ASCII text"),
    ({R.CONTROL_PACKAGE_SETUP_OUTPUTS: b"\x01DOUBLE,INT32"}, "answered 2 types for 5 outputs"),
    ({R.CONTROL_PACKAGE_SETUP_OUTPUTS: b"\x01DOUBLE,VECTOR6D,VECTOR6D,VECTOR6D,QUATERNION"},
     "unknown RTDE type 'QUATERNION'"),
    ({R.REQUEST_PROTOCOL_VERSION: lambda: b"\x00\x01V"}, "package of impossible size 1"),
    ({R.REQUEST_PROTOCOL_VERSION: None}, "no reply to RTDE request 'V'"),
])
def test_a_broken_handshake_is_a_clear_rtde_error_within_the_deadline(replies, words):
    with FakeController(replies) as fake:
        reader = R.RTDEReader("127.0.0.1", fake.ports[1])
        start = time.monotonic()
        with pytest.raises(R.RTDEError, match=words):
            reader.connect(timeout=0.5)
        assert time.monotonic() - start < 1.5
        assert reader._sock is None                        # closed on failure


@pytest.mark.parametrize("package, words", [
    (lambda: R.pack(R.DATA_PACKAGE, b""), "empty RTDE data package"),
    (lambda: R.pack(R.DATA_PACKAGE, b"\x01" + b"\x00" * 10), "data package of 10 bytes"),
    (lambda: R.pack(R.DATA_PACKAGE, STATE.pack(1, 0.0, *HOME, *np.zeros(12), 7) + b"\x00" * 5),
     "data package of 161 bytes; the recipe"),
    (lambda: state_package(0.0, HOME, recipe=9), "data package of unknown recipe 9"),
])
def test_malformed_data_packages_are_clear_rtde_errors(package, words):
    def stream(conn, stop):
        conn.sendall(package())
        stop.wait(2)

    with FakeController(stream=stream) as fake:
        reader = R.RTDEReader("127.0.0.1", fake.ports[1])
        reader.connect(timeout=1.0)
        try:
            with pytest.raises(R.RTDEError, match=words):
                reader.read(timeout=1.0)
        finally:
            reader.close()


def test_a_flooding_peer_cannot_hold_a_read_past_its_deadline():
    with FakeController(stream=flood) as fake:
        reader = R.RTDEReader("127.0.0.1", fake.ports[1])
        reader.connect(timeout=1.0)
        try:
            for timeout in (1.0, 0.2, 0.0):
                # a zero timeout returns what is waiting: let the flood refill the socket
                select.select([reader._sock], [], [], 5.0)
                time.sleep(0.05)
                start = time.monotonic()
                got = reader.read(timeout=timeout)
                assert time.monotonic() - start <= timeout + 0.25
                np.testing.assert_array_equal(got["actual_q"], HOME)
        finally:
            reader.close()


def test_a_silent_or_partial_peer_ends_a_read_by_its_deadline():
    def half(conn, stop):
        conn.sendall(state_package(0.0, HOME)[:20])         # half a package, then nothing
        stop.wait(5)

    with FakeController(stream=half) as fake:
        reader = R.RTDEReader("127.0.0.1", fake.ports[1])
        reader.connect(timeout=1.0)
        try:
            start = time.monotonic()
            with pytest.raises(R.RTDEError, match="no RTDE data package within 0.3 s"):
                reader.read(timeout=0.3)
            assert 0.25 <= time.monotonic() - start <= 0.6
            with pytest.raises(ValueError, match="timeout must be a number >= 0"):
                reader.read(timeout=float("nan"))
        finally:
            reader.close()


def test_a_nan_state_from_the_network_is_an_error_and_nothing_is_sent():
    q_nan = HOME.copy()
    q_nan[2] = np.nan
    with FakeController(stream=steady(q_nan)) as fake:
        backend = dqlab.ur.SecondaryInterfaceBackend("127.0.0.1", fake.ports[0],
                                                     rtde_port=fake.ports[1])
        sent = []
        backend.send_script = sent.append
        with URClient(backend, poll_interval=0.001) as ur:
            with pytest.raises(ControllerError, match=r"reported q = \[0.0, .*nan.*not "
                                                      "finite"):
                ur.movej(np.add(HOME, 0.1))
            with pytest.raises(ControllerError):
                ur.movel([0.2, -0.2, 0.3, 0.0, 3.1, 0.0])
    assert sent == []


@pytest.mark.parametrize("bad", [
    dict(q=np.full(6, np.nan)), dict(qd=[0, 0, np.inf, 0, 0, 0]), dict(tcp_pose=[np.nan] * 6),
    dict(time=float("nan")), dict(q=np.zeros(5)), dict(q="abc"), dict(robot_mode=7.5),
    dict(q=np.zeros(6) + 1j),
])
def test_an_untrustworthy_state_from_any_backend_is_refused(bad):
    class Lying:
        name = "lying"
        sent = []

        def connect(self, timeout):
            pass

        def close(self):
            pass

        def read_state(self):
            good = dict(time=0.0, q=HOME, qd=np.zeros(6), tcp_pose=np.zeros(6), robot_mode=7)
            return URState(**{**good, **bad})

        def movej(self, *args, **kw):
            self.sent.append("movej")

        movel = servoj = stop = movej

    backend = Lying()
    with URClient(backend) as ur:
        with pytest.raises(ControllerError, match="the lying back end reported"):
            ur.movej(HOME)
        with pytest.raises(ControllerError):
            ur.read_state()
    assert backend.sent == []


def test_the_secondary_stream_refuses_a_corrupt_message_size():
    buf = MessageBuffer()
    with pytest.raises(SecondaryError, match="impossible size 2"):
        buf.feed(struct.pack(">iB", 2, 16))
    with pytest.raises(SecondaryError, match="impossible size"):
        MessageBuffer().feed(struct.pack(">iB", MAX_MESSAGE_SIZE + 1, 16))


# --- the stand-in: killed, fed garbage, given bad programs ---------------------------------

@pytest.fixture
def standin():
    with ControllerStandIn(speedup=25) as s:
        yield s


def test_a_standin_killed_mid_program_is_reported_by_the_client(standin):
    with URClient(standin.backend(), poll_interval=0.001) as ur:
        ur.movej(np.add(HOME, [1.0, 0, 0, 0, 0, 0]), v=0.2, wait=False)
        os.kill(standin.pid, signal.SIGKILL)
        start = time.monotonic()
        with pytest.raises((R.RTDEError, ConnectionError, OSError)):
            for _ in range(1000):
                ur.read_state()
        assert time.monotonic() - start < 3.0
        with pytest.raises((R.RTDEError, ConnectionError, OSError)):
            ur.movej(HOME)
    standin.stop()
    assert psutil.Process().children(recursive=True) == []


BAD_LINES = {
    "text target": "movej('abc')",
    "text pose": "movel('x')",
    "text argument": "movej([0.1, -1.5, 0, -1.5, 0, 0], a='x')",
    "nested past 64 levels": "movej(" + "[" * 70 + "0" + "]" * 70 + ")",
    "beyond a limit": "movej([9.0, -1.5, 0, -1.5, 0, 0])",
    "NaN": "movej([0.1, -1.5, nan, -1.5, 0, 0])",
    "infinity": "movej([0.1, -1.5, 1e400, -1.5, 0, 0])",
    "unknown command": "popup('hello')",
    "too fast": "movej([0.33, -1.5, 0, -1.5, 0, 0], t=0.001)",
    "jump": "movej([3.5, -1.5, 0, -1.5, 0, 0])",
    "complex": "movej([1j, -1.5, 0, -1.5, 0, 0])",
    "bool": "movej([True, -1.5, 0, -1.5, 0, 0])",
    "servoj from rest at full speed": "servoj([0.5, -1.5, 0, -1.5, 0, 0], t=0.008)",
}


def test_a_program_with_one_bad_line_anywhere_moves_nothing_and_the_standin_serves_on(
        standin):
    good = [f"  movej([{0.05 * k}, -1.5, 0, -1.5, 0, 0], a=1.4, v=1.05)" for k in range(1, 5)]
    backend = standin.backend()
    with URClient(backend, poll_interval=0.001) as ur:
        ur.movej([0, -1.5, 0, -1.5, 0, 0])
        before = ur.actual_q()
        expected = len(BAD_LINES) * (len(good) + 1)
        for bad in BAD_LINES.values():
            for position in range(len(good) + 1):
                lines = good[:position] + ["  " + bad] + good[position:]
                backend.send_script("def p():\n" + "\n".join(lines) + "\nend")
        deadline = time.monotonic() + 10
        while standin.log().count("program refused") < expected:
            assert time.monotonic() < deadline, standin.log()
            time.sleep(0.01)
        np.testing.assert_array_equal(ur.actual_q(), before)        # nothing moved
        assert not ur.read_state().qd.any()
        log = standin.log()
        assert log.count("program refused") == expected
        for position in range(len(good) + 1):
            assert f"line {position + 1}" in log
        # and it still runs a good program
        final = ur.movej([0.2, -1.5, 0, -1.5, 0, 0])
        np.testing.assert_allclose(final.q, [0.2, -1.5, 0, -1.5, 0, 0], atol=1e-12)
    assert standin.running


def test_the_standin_drops_a_client_that_breaks_the_protocol_and_serves_the_others(standin):
    garbage = [
        struct.pack(">HB", 1, ord("V")),                                  # impossible size
        R.pack(R.REQUEST_PROTOCOL_VERSION, b"\x02"),                      # one byte, not two
        R.pack(R.REQUEST_PROTOCOL_VERSION, struct.pack(">H", 2))
        + R.pack(R.CONTROL_PACKAGE_SETUP_OUTPUTS, struct.pack(">d", 125.0) + b"\xff\xfe,x"),
        R.pack(R.REQUEST_PROTOCOL_VERSION, struct.pack(">H", 2))
        + R.pack(R.CONTROL_PACKAGE_SETUP_OUTPUTS, b"\x00"),               # no frequency
        R.pack(R.REQUEST_PROTOCOL_VERSION, struct.pack(">H", 2))          # no package fits
        + R.pack(R.CONTROL_PACKAGE_SETUP_OUTPUTS, struct.pack(">d", 125.0)
                 + ",".join(["actual_q"] * 2000).encode()),
    ]
    for data in garbage:
        with socket.create_connection((standin.host, standin.rtde_port), timeout=5) as s:
            s.sendall(data)
            s.settimeout(2.0)
            try:
                while s.recv(65536):
                    pass                      # until the stand-in closes the connection
            except (ConnectionResetError, socket.timeout):
                pass
    with socket.create_connection((standin.host, standin.secondary_port), timeout=5) as s:
        s.sendall(b"\xff\xfe\x00\x81 binary\n")                           # not UTF-8
        s.sendall(b"x" * (MAX_PROGRAM_SIZE + 10))                         # no newline, ever
        s.settimeout(2.0)
        try:
            while s.recv(65536):
                pass
        except (ConnectionResetError, socket.timeout):
            pass
    time.sleep(0.05)
    log = standin.log()
    assert log.count("RTDE client dropped") == len(garbage)
    assert "impossible size 1" in log and "must be ASCII" in log and "does not fit" in log
    assert "script client dropped" in log and "program refused" in log
    assert standin.running
    with URClient(standin.backend(), poll_interval=0.001) as ur:
        assert ur.movej(np.add(HOME, [0.1, 0, 0, 0, 0, 0])).robot_mode == 7


def test_the_standin_greets_a_script_client_with_its_version(standin):
    with socket.create_connection((standin.host, standin.secondary_port), timeout=5) as s:
        s.settimeout(2.0)
        buf, messages = MessageBuffer(), []
        while not messages:
            messages = buf.feed(s.recv(65536))
    mtype, body = messages[0]
    assert mtype == 20 and body[9] == 3                       # a robot message: the version
    name_length = body[10]
    major, minor, bugfix, build = struct.unpack(">BBii", body[11 + name_length:21 +
                                                              name_length])
    assert (major, minor, bugfix, build) == (5, 11, 0, 0)


def test_a_port_in_use_is_a_clear_error():
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        with pytest.raises(RuntimeError, match="Address already in use"):
            ControllerStandIn(secondary_port=port).start()
    assert psutil.Process().children(recursive=True) == []
