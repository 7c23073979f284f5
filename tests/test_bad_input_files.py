"""A failed write never destroys a file: every writer of dqlab, over an existing file.

Each writer is run over a file that is already there, three ways: with content it must
refuse (the refusal comes before any file is opened), with a write that fails at the disk
(a full disk, made to happen in the one place dqlab writes files, ``dqlab._files``), and
with a write that succeeds. The first two leave the old file byte for byte and no temporary
file behind; the third replaces it and keeps its permissions. A last test checks that no
other place of the package opens a file for writing.
"""

import ast
import errno
import os
import re
import stat
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import dqlab
from dqlab import _files, desk_arm_firmware, ur
from dqlab import pick_place as pp
from dqlab.models import desk_arm, ur3
from dqlab.trajectory import joint_trajectory

OLD = b"an existing file, which a failed write must leave as it is\n"
UR3 = ur3()
POSE = ur.pose_from_transform(UR3.fk([0.4, -1.3, 1.1, -1.2, -1.4, 0.6]))


def _plan():
    rows = [[228.66, 0, 174.12, 0, 0], [0, 170, 80, 0, 0], [0, 170, 30, 1, 0]]
    return pp.plan_pick_place(desk_arm(), pp.task_from_lab(rows), dt=0.1)


def _map():
    from dqlab.reachability import reachability_statistics, super_fibonacci_quaternions

    return reachability_statistics(UR3, [[0.0, -0.35, 0.25]], super_fibonacci_quaternions(2))


def _scene():
    viz = pytest.importorskip("dqlab.viz")
    scene = viz.Scene()
    scene.add_frame(np.eye(4), name="W")
    return scene


def _viewer_copy(path, source):
    """The book's build copies the viewer script: to a site whose script is ``path``."""
    viz = pytest.importorskip("dqlab.viz")
    from dqlab.viz import scene, sphinxext

    outdir = path.parent.parent.parent
    app = SimpleNamespace(builder=SimpleNamespace(format="html"), outdir=str(outdir))
    original = scene.viewer_script_path
    scene.viewer_script_path = lambda: source
    try:
        sphinxext._copy_viewer_script(app, None)
    finally:
        scene.viewer_script_path = original
    assert viz


#: name -> (file name, good write(path, tmp), bad write(path, tmp) refused before opening or
#: None: a trajectory and a scene are checked when they are made, and hold nothing to refuse)
WRITERS = {
    "write_gcode": ("task.gcode", lambda p, t: desk_arm_firmware.write_gcode(p, _plan()),
                    lambda p, t: desk_arm_firmware.write_gcode(p, _plan(), name="Démo")),
    "write_poses": ("poses.csv", lambda p, t: ur.write_poses(p, [POSE]),
                    lambda p, t: ur.write_poses(p, [POSE], robot="UR3\nkind: x")),
    "append_pose": ("poses.csv", lambda p, t: ur.append_pose(p, POSE),
                    lambda p, t: ur.append_pose(p, POSE, kind="dual_quaternion")),
    "Trajectory.save_csv": (
        "traj.csv", lambda p, t: joint_trajectory([0.0], [1.0], duration=0.1, dt=0.05)
        .save_csv(p), None),
    "ReachabilityMap.save": ("map.npz", lambda p, t: _map().save(p),
                             lambda p, t: _map().save(p, note=object())),
    "Scene.save_html": ("scene.html", lambda p, t: _scene().save_html(p), None),
    "viewer script copy": ("site/_static/dqlab/meshcat.min.js",
                           lambda p, t: _viewer_copy(p, t / "viewer.js"),
                           lambda p, t: _viewer_copy(p, t / "missing.js")),
}


@pytest.fixture
def old_file(tmp_path, request):
    """The writer's target, already there (mode 0o640), its name and its old content: OLD,
    or for append_pose, which reads the file first, a pose file."""
    name = request.param
    path = tmp_path / WRITERS[name][0]
    path.parent.mkdir(parents=True, exist_ok=True)
    if name == "append_pose":
        ur.write_poses(path, [POSE])
    else:
        path.write_bytes(OLD)
    path.chmod(0o640)
    (tmp_path / "viewer.js").write_text("// the viewer\n")
    return name, path, path.read_bytes()


def _left_alone(path, old):
    assert path.read_bytes() == old
    assert [p.name for p in path.parent.iterdir() if p.name.endswith(".tmp")] == []


@pytest.mark.parametrize("old_file", [w for w in WRITERS if WRITERS[w][2]], indirect=True)
def test_a_refused_write_leaves_the_old_file(old_file, tmp_path):
    name, path, old = old_file
    with pytest.raises((ValueError, TypeError, OSError)):
        WRITERS[name][2](path, tmp_path)
    _left_alone(path, old)


@pytest.mark.parametrize("old_file", WRITERS, indirect=True)
def test_a_write_that_fails_at_the_disk_leaves_the_old_file(old_file, tmp_path, monkeypatch):
    name, path, old = old_file

    def full_disk(fd):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(_files.os, "fsync", full_disk)
    with pytest.raises(OSError, match="No space left"):
        WRITERS[name][1](path, tmp_path)
    _left_alone(path, old)


@pytest.mark.parametrize("old_file", WRITERS, indirect=True)
def test_a_write_replaces_the_file_and_keeps_its_permissions(old_file, tmp_path):
    name, path, old = old_file
    WRITERS[name][1](path, tmp_path)
    assert path.read_bytes() != old and path.stat().st_size > 0
    assert stat.S_IMODE(path.stat().st_mode) == 0o640
    assert [p.name for p in path.parent.iterdir() if p.name.endswith(".tmp")] == []


def test_a_new_file_gets_the_umask_and_a_directory_is_refused(tmp_path):
    umask = os.umask(0o022)
    try:
        path = _files.write_atomically(tmp_path / "new.txt", "text\n")
    finally:
        os.umask(umask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o644 and path.read_text() == "text\n"
    with pytest.raises(ValueError, match="is a directory"):
        _files.write_atomically(tmp_path, "text\n")
    with pytest.raises(FileNotFoundError):
        _files.write_atomically(tmp_path / "no such folder" / "x.txt", "text\n")
    with pytest.raises(TypeError, match="path must be a file path"):
        _files.write_atomically(None, "text\n")
    link = tmp_path / "link.txt"
    link.symlink_to(path)
    _files.write_atomically(link, "through the link\n")
    assert link.is_symlink() and path.read_text() == "through the link\n"


def _writes_a_file(node):
    """Is ``node`` a call that opens a file for writing or writes one?"""
    if not isinstance(node, ast.Call):
        return False
    func = ast.unparse(node.func)
    if func.split(".")[-1] in ("write_text", "write_bytes", "savez", "savez_compressed",
                               "savetxt", "copyfile", "copy2", "copytree", "mkstemp"):
        return True
    if func in ("np.save", "numpy.save", "shutil.copy", "shutil.move", "os.rename"):
        return True
    if func in ("open", "os.fdopen", "io.open") or func.endswith(".open"):
        modes = [a for a in node.args[1:2]] + [k.value for k in node.keywords if k.arg == "mode"]
        return any(isinstance(m, ast.Constant) and set(str(m.value)) & set("wax+")
                   for m in modes)
    return False


def test_no_other_place_of_the_package_writes_a_file():
    """Only dqlab._files opens a file for writing (a function handed to write_atomically
    writes into the temporary file it is given)."""
    package = Path(dqlab.__file__).parent
    found = []
    for path in sorted(package.rglob("*.py")):
        if path.name == "_files.py":
            continue
        source = path.read_text()
        if not re.search(r"open\(|write_|save|copy|mkstemp|rename|move", source):
            continue                                # nothing that could write: not parsed
        tree = ast.parse(source)
        handed_over = {id(inner) for node in ast.walk(tree) if isinstance(node, ast.Call)
                       and ast.unparse(node.func) == "write_atomically"
                       for arg in node.args[1:] for inner in ast.walk(arg)}
        for node in ast.walk(tree):
            if _writes_a_file(node) and id(node) not in handed_over:
                found.append(f"{path.relative_to(package)}:{node.lineno}")
    assert found == []
