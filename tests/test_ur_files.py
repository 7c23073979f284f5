"""Pose files: exact round trips, and every kind of damage refused with file and line."""

import numpy as np
import pytest

import dqlab
from dqlab.ur import files as F
from dqlab.ur.poses import dual_quaternion_from_pose, pose_from_transform


def _poses(n=5, seed=1):
    rng = np.random.default_rng(seed)
    robot = dqlab.models.ur3()
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    return pose_from_transform(robot.fk(q))


def test_ur_pose_round_trip_is_bit_exact(tmp_path):
    p = _poses()
    path = tmp_path / "poses.csv"
    F.write_poses(path, p, names=[f"p{k}" for k in range(len(p))])
    got = F.read_poses(path)
    assert got.kind == "ur_pose" and got.names == tuple(f"p{k}" for k in range(5))
    assert (got.robot, got.frame, got.tcp) == ("UR3", "base", "flange")
    np.testing.assert_array_equal(got.values, p)
    np.testing.assert_allclose(got.transforms(), dqlab.ur.transform_from_pose(p), atol=0)


def test_dual_quaternion_round_trip_and_views(tmp_path):
    Q = dual_quaternion_from_pose(_poses())
    path = tmp_path / "dq.csv"
    F.write_poses(path, Q, kind="dual_quaternion")
    got = F.read_poses(path)
    np.testing.assert_array_equal(got.values, Q)
    np.testing.assert_allclose(got.poses(), _poses(), atol=1e-14)
    np.testing.assert_allclose(got.transforms(), dqlab.transform_from_dual_quaternion(Q),
                               atol=1e-15)
    assert len(got) == 5


def test_append_builds_the_file_pose_by_pose(tmp_path):
    path = tmp_path / "rec.csv"
    p = _poses(3)
    names = [F.append_pose(path, row) for row in p]
    assert names == ["pose_1", "pose_2", "pose_3"]
    np.testing.assert_array_equal(F.read_poses(path).values, p)
    with pytest.raises(ValueError, match="holds kind 'ur_pose', not 'dual_quaternion'"):
        F.append_pose(path, [1, 0, 0, 0, 0, 0, 0, 0], kind="dual_quaternion")
    assert [p.name for p in tmp_path.iterdir()] == ["rec.csv"]   # no temporary file left


def _good_text(kind="ur_pose"):
    if kind == "ur_pose":
        rows = ["a,0.1,0.2,0.3,0.0,0.0,1.0", "b,0.2,-0.1,0.3,0.0,3.0,0.0"]
        cols, units = "name,x,y,z,rx,ry,rz", "m, rad"
    else:
        rows = ["a,1.0,0.0,0.0,0.0,0.0,0.05,0.0,0.0", "b,0.0,0.0,1.0,0.0,0.0,0.0,0.0,0.1"]
        cols, units = "name,qr_w,qr_x,qr_y,qr_z,qd_w,qd_x,qd_y,qd_z", "m"
    return ("# dqlab pose file\n# version: 1\n# kind: " + kind + "\n# units: " + units
            + "\n# frame: base\n# robot: UR3\n# tcp: flange\n" + cols + "\n"
            + "\n".join(rows) + "\n# end: 2\n")


def test_the_reference_texts_load(tmp_path):
    for kind in ("ur_pose", "dual_quaternion"):
        path = tmp_path / f"{kind}.csv"
        path.write_text(_good_text(kind))
        assert len(F.read_poses(path)) == 2


# (what is done to the good file, the line the error must name, words of the message)
CORRUPTIONS = [
    ("not a pose file", lambda t: "x,y\n" + t, 1, "not a dqlab pose file"),
    ("empty file", lambda t: "", 1, "not a dqlab pose file"),
    ("other version", lambda t: t.replace("version: 1", "version: 2"), 2,
     "version '2' is not supported"),
    ("unknown kind", lambda t: t.replace("kind: ur_pose", "kind: euler"), 3, "kind 'euler'"),
    ("millimetre units", lambda t: t.replace("units: m, rad", "units: mm, deg"), 4,
     "units 'mm, deg' are not supported"),
    ("missing header entry", lambda t: t.replace("# robot: UR3\n", ""), 7,
     "'robot' is missing"),
    ("unknown header entry", lambda t: t.replace("# tcp: flange", "# tool: flange"), 7,
     "unknown header entry"),
    ("wrong columns", lambda t: t.replace("name,x,y,z,rx,ry,rz", "name,x,y,z,r,p,y"), 8,
     "column line"),
    ("truncated line", lambda t: t.replace("b,0.2,-0.1,0.3,0.0,3.0,0.0", "b,0.2,-0.1,0.3"),
     10, "4 fields, expected 7"),
    ("not a number", lambda t: t.replace("a,0.1,0.2", "a,0.1,zero"), 9,
     "column y is 'zero', not a number"),
    ("NaN", lambda t: t.replace("3.0,0.0\n", "nan,0.0\n"), 10, "column ry is nan"),
    ("infinity", lambda t: t.replace("a,0.1", "a,inf"), 9, "column x is inf"),
    ("degrees", lambda t: t.replace("0.0,3.0,0.0", "0.0,180.0,0.0"), 10,
     "degrees written as radians"),
    ("millimetres", lambda t: t.replace("b,0.2,-0.1,0.3", "b,200.0,-100.0,300.0"), 10,
     "millimetres written as metres"),
    ("repeated name", lambda t: t.replace("\nb,", "\na,"), 10, "repeats line 9"),
    ("bad name", lambda t: t.replace("\nb,", "\nb c,"), 10, "pose name 'b c'"),
    ("file cut before end", lambda t: t.replace("# end: 2\n", ""), 11, "without its '# end"),
    ("line lost", lambda t: t.replace("a,0.1,0.2,0.3,0.0,0.0,1.0\n", ""), 10,
     "'# end' says 2 poses, the file holds 1"),
    ("text after end", lambda t: t + "c,0,0,0,0,0,0\n", 12, "after the '# end'"),
    ("stray comment", lambda t: t.replace("\nb,", "\n# hello\nb,"), 10, "unexpected comment"),
    ("binary garbage", lambda t: t.replace("\nb,", "\n\xff\xfeb,"), 10, "not UTF-8"),
]


@pytest.mark.parametrize("label, damage, line, words", CORRUPTIONS,
                         ids=[c[0] for c in CORRUPTIONS])
def test_every_corruption_is_refused_with_file_and_line(tmp_path, label, damage, line, words):
    path = tmp_path / "poses.csv"
    text = damage(_good_text())
    if label == "binary garbage":
        path.write_bytes(text.encode("latin-1"))
    else:
        path.write_text(text)
    with pytest.raises(F.PoseFileError) as info:
        F.read_poses(path)
    err = info.value
    assert err.line == line, str(err)
    assert words in str(err), str(err)
    assert str(err).startswith(f"{path}, line {line}: ")
    assert isinstance(err, ValueError)


@pytest.mark.parametrize("damage, line, words", [
    (lambda t: t.replace("a,1.0,0.0", "a,1.1,0.0"), 9, "q_r has norm 1.1"),
    (lambda t: t.replace("0.0,0.0,0.0,0.1\n", "0.0,0.0,0.3,0.1\n"), 10, "q_r . q_d = 0.3"),
    (lambda t: t.replace("0.0,0.0,0.0,0.1\n", "0.0,0.0,0.0,100.0\n"), 10, "millimetres"),
])
def test_dual_quaternion_damage_is_refused(tmp_path, damage, line, words):
    path = tmp_path / "dq.csv"
    path.write_text(damage(_good_text("dual_quaternion")))
    with pytest.raises(F.PoseFileError) as info:
        F.read_poses(path)
    assert info.value.line == line and words in str(info.value), str(info.value)


def test_missing_file_names_the_file(tmp_path):
    with pytest.raises(F.PoseFileError, match="nothere.csv: cannot be read"):
        F.read_poses(tmp_path / "nothere.csv")


@pytest.mark.parametrize("values, kwargs, words", [
    ([[0, 0, 0, 0, 0, np.nan]], {}, "pose 0 ('pose_1'): column rz is nan"),
    ([[0, 0, 0, 0, 0]], {}, "shape (N, 6)"),
    ([[0, 0, 0, 0, 0, 0]], {"kind": "matrix"}, "kind must be one of"),
    ([[0, 0, 0, 0, 0, 0]], {"names": ["a b"]}, "names[0] = 'a b'"),
    ([[0, 0, 0, 0, 0, 0]] * 2, {"names": ["a", "a"]}, "repeats names[0]"),
    ([[2, 0, 0, 0, 0, 0, 0, 0]], {"kind": "dual_quaternion"}, "q_r has norm 2"),
])
def test_write_refuses_what_read_would_refuse(tmp_path, values, kwargs, words):
    path = tmp_path / "out.csv"
    with pytest.raises(ValueError) as info:
        F.write_poses(path, values, **kwargs)
    assert words in str(info.value)
    assert not path.exists()


@pytest.mark.parametrize("kwargs, words", [
    ({"max_reach": float("nan")}, "max_reach must be a number >= 0, got nan"),
    ({"max_reach": -1.0}, "max_reach must be a number >= 0, got -1.0"),
    ({"unit_tol": float("nan")}, "unit_tol must be a number >= 0, got nan"),
    ({"unit_tol": -1e-9}, "unit_tol must be a number >= 0"),
])
def test_tolerances_and_reach_are_checked_numbers(tmp_path, kwargs, words):
    for call in (lambda: F.write_poses(tmp_path / "p.csv", _poses(2), **kwargs),
                 lambda: F.append_pose(tmp_path / "p.csv", _poses(1)[0], **kwargs)):
        with pytest.raises(ValueError, match=words):
            call()
    F.write_poses(tmp_path / "ok.csv", _poses(2))
    with pytest.raises(ValueError, match=words):
        F.read_poses(tmp_path / "ok.csv", **kwargs)
    with pytest.raises(TypeError, match="values must hold real numbers, got complex"):
        F.write_poses(tmp_path / "c.csv", _poses(2) + 1j)
    with pytest.raises(TypeError, match="value must hold real numbers, got complex"):
        F.append_pose(tmp_path / "c.csv", _poses(1)[0] + 1j)
