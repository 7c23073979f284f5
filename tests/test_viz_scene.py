"""meshcat scenes of dqlab.viz: recorded commands, the self-contained HTML, the live server."""

import base64
import html
import os
import re
import subprocess
import sys
import time
import types
import urllib.request
from pathlib import Path

import numpy as np
import pytest
import umsgpack

from dqlab import models, viz
from dqlab.viz import scene as scene_module
from dqlab.viz import sphinxext

SERVER_MODULE = "dqlab.viz._server"
Q_HOME = np.array([0, -np.pi / 2, 0, -np.pi / 2, 0, 0])


def _commands(scene, kind=None, under=None):
    return [c for c in scene.commands()
            if (kind is None or c["type"] == kind)
            and (under is None or c.get("path", "").startswith(under))]


def _matrix(command):
    """The 4x4 matrix of a set_transform command (meshcat sends it column-major)."""
    return np.asarray(command["matrix"], dtype=float).reshape(4, 4).T


def _replayed(document):
    """The commands a view's document replays, decoded."""
    blobs = re.search(r"var commands = \[(.*?)\];", document, re.S).group(1)
    return [umsgpack.unpackb(base64.b64decode(b)) for b in re.findall(r'"([^"]*)"', blobs)]


# --- recording ----------------------------------------------------------------------------


def test_recorder_keeps_the_final_scene():
    scene = viz.Scene(grid=False)
    before = len(scene.commands())
    scene.add_frame(np.eye(4), name="a")
    X = np.eye(4)
    X[:3, 3] = [1, 2, 3]
    scene.add_frame(X, name="a")  # same node: replaced, not duplicated
    frames = _commands(scene, under="/meshcat/a")
    assert len(frames) == 7  # 3 rods (object + transform) + the node's transform
    np.testing.assert_allclose(_matrix(_commands(scene, "set_transform", "/meshcat/a")[-1]), X)
    scene.vis["a"].delete()
    assert not _commands(scene, "set_object", "/meshcat/a")
    assert len(scene.commands()) == before + 1  # the delete itself


def test_robot_bodies_are_posed_at_the_fk_frames():
    robot = models.ur3()
    scene = viz.Scene()
    scene.add_robot(robot, Q_HOME)
    frames = robot.fk(Q_HOME, all_frames=True)
    for i in range(robot.n + 1):
        [pose] = [c for c in _commands(scene, "set_transform")
                  if c["path"] == f"/meshcat/robot/body{i}"]
        np.testing.assert_allclose(_matrix(pose), frames[i], atol=1e-12)


def test_robot_primitives_are_sized_by_the_dh_values():
    robot = models.ur3()
    scene = viz.Scene()
    scene.add_robot(robot, Q_HOME)
    objects = {c["path"]: c["object"] for c in _commands(scene, "set_object", "/meshcat/robot")}
    rods = [o["geometries"][0]["height"] for p, o in objects.items() if "/rod" in p]
    dh_lengths = [abs(x) for link in robot.links for x in (link.a, link.d) if x != 0]
    assert sorted(np.round(rods, 9)) == sorted(np.round(dh_lengths, 9))
    joints = [p for p in objects if p.endswith("/joint")]
    assert len(joints) == robot.n  # one cylinder per joint
    assert any("/flange/" in p for p in objects)  # the flange frame
    # the joint axes are the z axes of frames 0..n-1 in standard DH
    for i in range(robot.n):
        rod = _commands(scene, "set_transform", f"/meshcat/robot/body{i}/joint")[0]
        axis = _matrix(rod)[:3, 1]  # three.js cylinders are along y
        np.testing.assert_allclose(np.abs(axis), [0, 0, 1], atol=1e-12)


@pytest.mark.parametrize("make", [models.ur3_mdh, models.scara_rsm5, models.desk_arm,
                                  models.six_r])
def test_every_model_can_be_drawn(make):
    robot = make()
    scene = viz.Scene()
    scene.add_robot(robot, frames=True)
    assert len(_commands(scene, "set_transform", "/meshcat/robot/body")) > robot.n
    joints = [c for c in _commands(scene, "set_object") if c["path"].endswith("/joint")]
    assert len(joints) == robot.n


def test_a_tool_is_drawn_beyond_the_flange():
    robot = models.ur3()
    tool = np.eye(4)
    tool[:3, 3] = [0, 0, 0.1]
    robot.tool = tool
    scene = viz.Scene()
    scene.add_robot(robot, Q_HOME)
    [flange] = [c for c in _commands(scene, "set_transform")
                if c["path"] == "/meshcat/robot/body6"]
    np.testing.assert_allclose(_matrix(flange) @ tool, robot.fk(Q_HOME), atol=1e-12)
    [tcp] = [c for c in _commands(scene, "set_transform")
             if c["path"] == "/meshcat/robot/body6/tcp"]
    np.testing.assert_allclose(_matrix(tcp), tool)


def test_set_joints_moves_the_bodies():
    robot = models.ur3()
    scene = viz.Scene()
    scene.add_robot(robot, Q_HOME)
    q = Q_HOME + 0.3
    scene.set_joints(q)
    [pose] = [c for c in _commands(scene, "set_transform")
              if c["path"] == "/meshcat/robot/body6"]
    np.testing.assert_allclose(_matrix(pose), robot.fk(q), atol=1e-12)
    with pytest.raises(ValueError, match="no robot named 'other'"):
        scene.set_joints(q, name="other")


def test_points_and_paths():
    scene = viz.Scene()
    P = np.array([[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0.05]])
    scene.add_path(P, name="tcp_path", color=0x112233)
    [line] = _commands(scene, "set_object", "/meshcat/tcp_path")
    assert line["object"]["object"]["type"] == "Line"
    assert line["object"]["materials"][0]["color"] == 0x112233
    position = line["object"]["geometries"][0]["data"]["attributes"]["position"]
    assert position["itemSize"] == 3 and len(position["array"].data) == P.size * 4  # float32
    scene.add_points(P, name="samples")
    assert len(_commands(scene, "set_object", "/meshcat/samples/")) == 3
    scene.add_points(np.zeros((300, 3)), name="cloud")
    [cloud] = _commands(scene, "set_object", "/meshcat/cloud")
    assert cloud["object"]["object"]["type"] == "Points"
    with pytest.raises(ValueError, match="at least 2"):
        scene.add_path(P[:1], name="short")
    with pytest.raises(ValueError, match="shape"):
        scene.add_points(np.zeros((2, 2)), name="bad")
    with pytest.raises(ValueError, match="NaN"):
        scene.add_path([[0, 0, 0], [np.nan, 0, 0]], name="bad")
    with pytest.raises(ValueError, match="transform"):
        scene.add_frame(np.eye(3), name="bad")


def test_animation_plays_the_joint_trajectory():
    robot = models.ur3()
    t = np.linspace(0, 2, 11)
    Q = Q_HOME + np.outer(np.sin(t), np.ones(6))
    scene = viz.Scene()
    scene.add_robot(robot, Q[0])
    scene.animate(Q, times=t)
    last = scene.commands()[-1]
    assert last["type"] == "set_animation"
    assert last["options"]["play"] is True
    clips = {a["path"]: a["clip"] for a in last["animations"]}
    assert set(clips) == {f"/meshcat/robot/body{i}" for i in range(7)}
    clip = clips["/meshcat/robot/body6"]
    tracks = {track["name"]: track["keys"] for track in clip["tracks"]}
    times = np.array([k["time"] for k in tracks[".position"]]) / clip["fps"]
    np.testing.assert_allclose(times, t)
    positions = np.array([k["value"] for k in tracks[".position"]])
    np.testing.assert_allclose(positions, robot.fk(Q)[:, :3, 3], atol=1e-12)
    # a second animated node shares the time slider: still one set_animation
    scene.add_frame(np.eye(4), name="target")
    scene.animate_transforms("target", robot.fk(Q), times=t)
    animations = _commands(scene, "set_animation")
    assert len(animations) == 1 and len(animations[0]["animations"]) == 8


def test_animation_rejects_bad_input():
    scene = viz.Scene()
    scene.add_robot(models.ur3())
    with pytest.raises(ValueError, match="shape"):
        scene.animate(np.zeros((5, 5)))
    with pytest.raises(ValueError, match="increasing"):
        scene.animate(np.zeros((3, 6)), times=[0, 1, 1])
    with pytest.raises(ValueError, match="poses"):
        scene.animate_transforms("x", np.zeros((3, 3, 3)))


# --- HTML -----------------------------------------------------------------------------------


def _srcdoc(iframe):
    return html.unescape(re.search(r'srcdoc="([^"]*)"', iframe).group(1))


def test_html_view_replays_the_recorded_commands():
    scene = viz.Scene()
    scene.add_robot(models.ur3(), Q_HOME)
    scene.add_frame(np.eye(4), name="world_frame")
    iframe = scene.html(bundle="none", height=300)
    assert iframe.startswith('<iframe class="dqlab-scene"')
    assert "height: 300px" in iframe
    count = int(re.search(r'data-dqlab-scene="(\d+)"', iframe).group(1))
    document = _srcdoc(iframe)
    replayed = _replayed(document)
    assert count == len(replayed) == len(scene.commands())
    assert replayed == scene.commands()
    paths = {c.get("path") for c in replayed}
    assert "/meshcat/robot/body6/flange/x" in paths and "/meshcat/world_frame/z" in paths
    assert "<script src=" not in document and "MeshCat.Viewer" in document


def test_bundle_modes(tmp_path, monkeypatch):
    scene = viz.Scene()
    monkeypatch.delenv(scene_module.BOOK_ROOT_ENV, raising=False)
    inline = scene.document(bundle="inline")
    assert len(inline) > 800_000 and "<script src=" not in inline
    assert scene.document(bundle="auto") == inline  # a live notebook: the script inside

    # while the book is built (the Sphinx extension sets the variable), a notebook in book/
    # loads the shared copy relative to its page
    (tmp_path / "book").mkdir()
    monkeypatch.setenv(scene_module.BOOK_ROOT_ENV, str(tmp_path))
    monkeypatch.chdir(tmp_path / "book")
    shared = scene.document(bundle="auto")
    assert '<script src="../_static/dqlab/meshcat.min.js"' in shared
    assert len(shared) < 10_000
    monkeypatch.chdir(tmp_path)
    assert '<script src="_static/dqlab/meshcat.min.js"' in scene.document(bundle="shared")
    with pytest.raises(ValueError, match="bundle"):
        scene.document(bundle="cdn")


def test_show_and_repr_html(monkeypatch):
    monkeypatch.setenv(scene_module.BOOK_ROOT_ENV, os.getcwd())
    scene = viz.Scene()
    view = scene.show(height=250)
    assert isinstance(view, viz.SceneView)
    assert view._repr_html_() == scene.html(height=250)
    assert scene._repr_html_() == scene.html()
    assert "KB of HTML" in repr(view)


def test_camera(monkeypatch):
    scene = viz.Scene()
    scene.set_camera([1.0, -1.0, 0.5], target=[0.0, 0.0, 0.2])
    document = scene.document(bundle="none")
    assert '"position": [1.0, -1.0, 0.5], "target": [0.0, 0.0, 0.2]' in document
    [position] = _commands(scene, "set_property", "/Cameras/default/rotated/<object>")
    assert position["value"] == [1.0, 0.5, 1.0]  # meshcat's y-up camera frame


def test_save_html(tmp_path):
    scene = viz.Scene()
    scene.add_frame(np.eye(4), name="W")
    path = scene.save_html(tmp_path / "scene.html")
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and "MeshCat" in text and len(text) > 800_000


# --- the Sphinx extension -------------------------------------------------------------------


def test_sphinx_extension(tmp_path, monkeypatch):
    # the extension sets the variable for the rest of a build; here it is undone after the test
    monkeypatch.setenv(scene_module.BOOK_ROOT_ENV, "")
    monkeypatch.delenv(scene_module.BOOK_ROOT_ENV)
    connected = {}
    app = types.SimpleNamespace(
        srcdir=str(tmp_path), outdir=str(tmp_path / "html"),
        builder=types.SimpleNamespace(format="html"),
        connect=lambda event, handler, priority=500: connected.setdefault(event, handler))
    metadata = sphinxext.setup(app)
    assert metadata["parallel_read_safe"]
    assert os.environ[scene_module.BOOK_ROOT_ENV] == str(tmp_path.resolve())
    connected["build-finished"](app, None)
    copied = tmp_path / "html" / scene_module.SHARED_SCRIPT
    assert copied.read_bytes() == scene_module.viewer_script_path().read_bytes()

    from sphinx.builders.html._assets import _JavaScript

    scripts = [_JavaScript(None, body="const A = 1"), _JavaScript("", body="const A = 1"),
               _JavaScript("_static/x.js")]
    context = {"script_files": scripts}
    connected["html-page-context"](app, "page", "page.html", context, None)
    assert [s.filename for s in context["script_files"]] == [None, "_static/x.js"]


# --- the live server ------------------------------------------------------------------------


def _server_processes():
    psutil = pytest.importorskip("psutil")
    found = []
    for proc in psutil.process_iter(["cmdline"]):
        cmdline = proc.info.get("cmdline") or []
        if SERVER_MODULE in cmdline or "meshcat.servers.zmqserver" in cmdline:
            found.append(proc)
    return found


@pytest.fixture
def no_server_left():
    yield
    viz.stop_live_server()
    mine = [p for p in _server_processes() if p.ppid() == os.getpid()]
    assert not mine, f"meshcat server processes left: {[p.pid for p in mine]}"


def test_live_server_on_loopback_reused_and_stopped(no_server_left):
    psutil = pytest.importorskip("psutil")
    window = viz.live_server()
    assert window.web_url.startswith("http://127.0.0.1:")
    assert window.zmq_url.startswith("tcp://127.0.0.1:")
    assert viz.live_server() is window  # reused within the kernel
    listening = [c for c in psutil.Process(window.server_proc.pid).net_connections("inet")
                 if c.status == psutil.CONN_LISTEN]
    assert len(listening) == 2
    assert {c.laddr.ip for c in listening} == {"127.0.0.1"}
    with urllib.request.urlopen(window.web_url, timeout=10) as response:
        assert response.status == 200 and b"MeshCat" in response.read()

    scene = viz.Scene()
    scene.add_robot(models.ur3(), Q_HOME)
    view = scene.live()
    assert view.url == window.web_url and window.web_url in view._repr_html_()
    before = window.get_scene().count("handle_command_bytearray")
    scene.add_frame(np.eye(4), name="target")  # mirrored to the server as it is made
    after = window.get_scene().count("handle_command_bytearray")
    assert after > before >= len(_commands(scene, "set_object", "/meshcat/robot"))

    proc = window.server_proc
    viz.stop_live_server()
    assert proc.poll() is not None
    assert not psutil.pid_exists(proc.pid) or psutil.Process(proc.pid).status() == "zombie"


def test_live_server_dies_with_its_kernel(no_server_left):
    psutil = pytest.importorskip("psutil")
    code = ("from dqlab import viz; import time; w = viz.live_server(); "
            "print(w.server_proc.pid, flush=True); time.sleep(60)")
    kernel = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                              cwd=Path(__file__).resolve().parents[1])
    try:
        server_pid = int(kernel.stdout.readline())
        assert psutil.pid_exists(server_pid)
    finally:
        kernel.kill()  # no atexit handler runs: the server must notice on its own
        kernel.wait()
        kernel.stdout.close()
    deadline = time.time() + 10
    while time.time() < deadline and psutil.pid_exists(server_pid):
        try:
            if psutil.Process(server_pid).status() == psutil.STATUS_ZOMBIE:
                break
        except psutil.NoSuchProcess:
            break
        time.sleep(0.1)
    alive = psutil.pid_exists(server_pid) and \
        psutil.Process(server_pid).status() != psutil.STATUS_ZOMBIE
    assert not alive, "the meshcat server outlived the process that started it"


def test_no_meshcat_server_remains():
    assert not [p for p in _server_processes() if p.ppid() in (os.getpid(), 1)
                and SERVER_MODULE in (p.info.get("cmdline") or [])]
