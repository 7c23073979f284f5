r"""Pose files: record poses to a text file and load them back, validated.

The thesis's program records the pose of the UR3 as the eight coefficients of a dual
quaternion, one pose per line of a text file, and later reads them back to move the robot.
This module keeps that idea and makes the file self-describing and safe to load.

The format (version 1)
----------------------
A UTF-8 text file in CSV form, with a header of ``# key: value`` lines, one column line, one
line per pose, and a closing ``# end: N`` line::

    # dqlab pose file
    # version: 1
    # kind: ur_pose
    # units: m, rad
    # frame: base
    # robot: UR3
    # tcp: flange
    name,x,y,z,rx,ry,rz
    home,0.0,-0.19425,0.69415,0.0,-2.221441469079183,2.221441469079183
    # end: 1

- ``kind`` is ``ur_pose`` (columns ``x, y, z, rx, ry, rz``: UR pose vectors, metres and a
  rotation vector in radians, units ``m, rad``) or ``dual_quaternion`` (columns
  ``qr_w, qr_x, qr_y, qr_z, qd_w, qd_x, qd_y, qd_z``: the thesis's coefficients, unit dual
  quaternions :math:`q_r + \varepsilon q_d`, :math:`q_d = \tfrac12 (0, \mathbf p)\, q_r`,
  units ``m``).
- ``frame`` names the frame the poses are expressed in (the robot's base), ``robot`` the
  model, ``tcp`` the point the pose is of (``flange``, or a tool's name).
- Numbers are written with 17 significant digits (Python's ``repr``), so a pose survives a
  write and a read bit for bit.
- The ``# end: N`` line closes the file; a file without it was cut short.

Loading checks every line and refuses the whole file at the first problem, with a
:class:`PoseFileError` that names the file and the line: a missing or unknown header entry,
another version, units other than the ones above, a line with the wrong number of fields,
a field that is not a number, NaN or infinity, a rotation vector longer than :math:`\pi`
(degrees written as radians?), a position farther than ``max_reach`` (millimetres written as
metres?), a dual quaternion that is not unit, a repeated name, a missing or wrong ``# end``.
Nothing is returned unless every line passed. Writing is atomic (a temporary file renamed
over the target), so a crash never leaves half a file.
"""

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._checks import check_text, check_tolerance, real_array, short_repr
from .._files import read_bytes, write_atomically
from ..dualquat import transform_from_dual_quaternion
from .poses import (
    dual_quaternion_from_pose,
    pose_from_dual_quaternion,
    transform_from_pose,
)

__all__ = ["FORMAT_VERSION", "COLUMNS", "PoseFile", "PoseFileError", "read_poses",
           "write_poses", "append_pose"]

FORMAT_VERSION = 1
_MAGIC = "# dqlab pose file"
COLUMNS = {
    "ur_pose": ("x", "y", "z", "rx", "ry", "rz"),
    "dual_quaternion": ("qr_w", "qr_x", "qr_y", "qr_z", "qd_w", "qd_x", "qd_y", "qd_z"),
}
_UNITS = {"ur_pose": "m, rad", "dual_quaternion": "m"}
_HEADER_KEYS = ("version", "kind", "units", "frame", "robot", "tcp")
_NAME = re.compile(r"[A-Za-z0-9_.\-]+")

#: The largest pose file :func:`read_poses` reads, bytes (a pose takes under 200).
MAX_FILE_BYTES = 1 << 24


class PoseFileError(ValueError):
    """A pose file that cannot be loaded; ``path`` and ``line`` (1-based) say where."""

    def __init__(self, path, line, message):
        self.path = str(path)
        self.line = line
        where = f"{self.path}, line {line}" if line is not None else self.path
        super().__init__(f"{where}: {message}")


@dataclass(frozen=True)
class PoseFile:
    """The poses of a pose file and its header.

    Attributes
    ----------
    kind : str
        ``"ur_pose"`` or ``"dual_quaternion"``.
    names : tuple of str
        One name per pose.
    values : ndarray, shape (N, 6) or (N, 8)
        The numbers as stored.
    frame, robot, tcp : str
        From the header.
    """

    kind: str
    names: tuple
    values: np.ndarray
    frame: str = "base"
    robot: str = "UR3"
    tcp: str = "flange"

    def __len__(self):
        return len(self.names)

    def poses(self):
        """UR pose vectors, shape (N, 6)."""
        if self.kind == "ur_pose":
            return self.values.copy()
        return pose_from_dual_quaternion(self.values)

    def dual_quaternions(self):
        """Unit dual quaternions ``(q_r, q_d)``, shape (N, 8)."""
        if self.kind == "dual_quaternion":
            return self.values.copy()
        return dual_quaternion_from_pose(self.values)

    def transforms(self):
        """Homogeneous transforms ``X_WT`` (pose of the TCP in the base frame), (N, 4, 4)."""
        if self.kind == "ur_pose":
            return transform_from_pose(self.values)
        return transform_from_dual_quaternion(self.values, tol=np.inf)


def _path(path):
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or a path-like object, got {short_repr(path)}")
    return Path(path)


def _check_values(kind, row, *, max_reach, unit_tol):
    """Why one row of numbers is not a valid pose of ``kind`` (``None`` if it is)."""
    for col, x in zip(COLUMNS[kind], row, strict=True):
        if not math.isfinite(x):
            return f"column {col} is {short_repr(x)}, not a finite number"
    if kind == "ur_pose":
        reach = math.hypot(*row[:3])
        angle = math.hypot(*row[3:])
        if reach > max_reach:
            return (f"position is {reach:.6g} m from the base, beyond max_reach = "
                    f"{max_reach:g} m (millimetres written as metres?)")
        if angle > math.pi + 1e-9:
            return (f"rotation vector has length {angle:.6g} rad > pi (degrees written as "
                    "radians?)")
        return None
    qr, qd = np.asarray(row[:4]), np.asarray(row[4:])
    norm = float(np.linalg.norm(qr))
    if abs(norm - 1.0) > unit_tol:
        return (f"q_r has norm {norm:.12g}, not 1 within unit_tol = {unit_tol:g} (not a unit "
                "dual quaternion)")
    dot = float(qr @ qd)
    if abs(dot) > unit_tol:
        return (f"q_r . q_d = {dot:.3g}, not 0 within unit_tol = {unit_tol:g} (not a unit "
                "dual quaternion)")
    reach = 2.0 * float(np.linalg.norm(qd))  # |p| = 2 |q_d| for a unit q_r
    if reach > max_reach:
        return (f"position is {reach:.6g} m from the base, beyond max_reach = {max_reach:g} m "
                "(millimetres written as metres?)")
    return None


def read_poses(path, *, max_reach=2.0, unit_tol=1e-9):
    """Load a pose file, checking every line; nothing is returned unless all lines pass.

    Parameters
    ----------
    path : str or path-like
    max_reach : float
        Largest distance of a pose from the base, metres (the UR3 reaches 0.5 m; the default
        catches millimetres written as metres).
    unit_tol : float
        Tolerance of the unit and orthogonality checks of dual quaternions.

    Returns
    -------
    PoseFile

    Raises
    ------
    PoseFileError
        (a ``ValueError``) naming the file and the line, for any problem listed in the
        module docstring.

    Examples
    --------
    >>> import os, tempfile
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = os.path.join(folder.name, "poses.csv")
    >>> write_poses(path, [[0.2, -0.1, 0.3, 0.0, 3.1, 0.0]], names=["above_box"])
    >>> loaded = read_poses(path)
    >>> loaded.names, loaded.poses()
    (('above_box',), array([[ 0.2, -0.1,  0.3,  0. ,  3.1,  0. ]]))
    >>> folder.cleanup()
    """
    path = _path(path)
    max_reach = check_tolerance(max_reach, "max_reach")
    unit_tol = check_tolerance(unit_tol, "unit_tol")

    def fail(line, message):
        raise PoseFileError(path, line, message)

    try:
        raw = read_bytes(path, max_bytes=MAX_FILE_BYTES, what="pose file")
    except OSError as exc:
        raise PoseFileError(path, None, f"cannot be read: {exc.strerror}") from None
    except ValueError as exc:
        raise PoseFileError(path, None, str(exc).rpartition(": ")[2]) from None
    lines = raw.split(b"\n")
    if lines and lines[-1] == b"":
        lines.pop()
    text = []
    for i, b in enumerate(lines, start=1):
        try:
            text.append(b.decode("utf-8").rstrip("\r"))
        except UnicodeDecodeError:
            fail(i, "is not UTF-8 text (a binary or damaged file?)")
    if not text or text[0].strip() != _MAGIC:
        fail(1, f"does not start with {_MAGIC!r}: not a dqlab pose file")
    header = {}
    i = 1
    while i < len(text) and text[i].startswith("#"):
        entry = text[i][1:].strip()
        key, sep, value = entry.partition(":")
        key, value = key.strip(), value.strip()
        if not sep or key not in _HEADER_KEYS:
            fail(i + 1, f"unknown header entry {short_repr(entry)} (expected one of "
                        f"{_HEADER_KEYS})")
        if key in header:
            fail(i + 1, f"header entry {short_repr(key)} is repeated")
        header[key] = (value, i + 1)
        i += 1
    for key in _HEADER_KEYS:
        if key not in header:
            fail(i + 1, f"header entry {short_repr(key)} is missing")
    version, line = header["version"]
    if version != str(FORMAT_VERSION):
        fail(line, f"format version {short_repr(version)} is not supported (this is version "
                   f"{FORMAT_VERSION})")
    kind, line = header["kind"]
    if kind not in COLUMNS:
        fail(line, f"kind {short_repr(kind)} is unknown (expected one of {tuple(COLUMNS)})")
    units, line = header["units"]
    if [u.strip() for u in units.split(",")] != _UNITS[kind].split(", "):
        fail(line, f"units {short_repr(units)} are not supported for {kind}: expected "
                   f"{_UNITS[kind]!r} (convert millimetres and degrees before writing)")
    columns = ("name",) + COLUMNS[kind]
    if i >= len(text):
        fail(i + 1, "the column line is missing (file truncated?)")
    if tuple(c.strip() for c in text[i].split(",")) != columns:
        fail(i + 1, f"column line is {short_repr(text[i])}, expected {','.join(columns)!r}")
    i += 1
    names, rows, seen = [], [], {}
    end_count = None
    for j in range(i, len(text)):
        line, n = text[j], j + 1
        if end_count is not None:
            fail(n, "text after the '# end' line")
        if line.startswith("#"):
            m = re.fullmatch(r"#\s*end:\s*(\d+)\s*", line)
            if not m:
                fail(n, f"unexpected comment {short_repr(line)} among the poses")
            end_count = int(m.group(1))
            if end_count != len(rows):
                fail(n, f"'# end' says {end_count} poses, the file holds {len(rows)} "
                        "(lines lost?)")
            continue
        fields = line.split(",")
        if len(fields) != len(columns):
            fail(n, f"{len(fields)} fields, expected {len(columns)} ({','.join(columns)}): "
                    "truncated or damaged line")
        name = fields[0].strip()
        if not _NAME.fullmatch(name):
            fail(n, f"pose name {short_repr(name)} is empty or has characters other than letters, "
                    "digits, '_', '.', '-'")
        if name in seen:
            fail(n, f"pose name {short_repr(name)} repeats line {seen[name]}")
        row = []
        for col, field in zip(columns[1:], fields[1:], strict=True):
            try:
                row.append(float(field))
            except ValueError:
                fail(n, f"column {col} is {short_repr(field.strip())}, not a number")
        problem = _check_values(kind, row, max_reach=max_reach, unit_tol=unit_tol)
        if problem:
            fail(n, f"pose {short_repr(name)}: {problem}")
        seen[name] = n
        names.append(name)
        rows.append(row)
    if end_count is None:
        fail(len(text) + 1, "the file ends without its '# end: N' line (truncated?)")
    values = np.array(rows, dtype=float).reshape(len(rows), len(columns) - 1)
    return PoseFile(kind=kind, names=tuple(names), values=values,
                    frame=header["frame"][0], robot=header["robot"][0], tcp=header["tcp"][0])


def write_poses(path, values, *, kind="ur_pose", names=None, robot="UR3", frame="base",
                tcp="flange", max_reach=2.0, unit_tol=1e-9):
    """Write poses to a pose file (atomically), refusing anything :func:`read_poses` would.

    Parameters
    ----------
    path : str or path-like
    values : array_like, shape (N, 6) or (N, 8)
        UR pose vectors (``kind="ur_pose"``) or unit dual quaternions
        (``kind="dual_quaternion"``).
    kind : {"ur_pose", "dual_quaternion"}
    names : sequence of str, optional
        One per pose; default ``pose_1``, ``pose_2``, ...
    robot, frame, tcp : str
        Written to the header.
    max_reach, unit_tol : float
        As in :func:`read_poses`.

    Raises
    ------
    ValueError
        For a bad ``kind``, shape, name or pose (naming the pose).

    Examples
    --------
    >>> import os, tempfile
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = os.path.join(folder.name, "poses.csv")
    >>> write_poses(path, [[1, 0, 0, 0, 0, 0.1, 0, 0]], kind="dual_quaternion")
    >>> print(open(path).read(), end="")
    # dqlab pose file
    # version: 1
    # kind: dual_quaternion
    # units: m
    # frame: base
    # robot: UR3
    # tcp: flange
    name,qr_w,qr_x,qr_y,qr_z,qd_w,qd_x,qd_y,qd_z
    pose_1,1.0,0.0,0.0,0.0,0.0,0.1,0.0,0.0
    # end: 1
    >>> folder.cleanup()
    """
    if not isinstance(kind, str) or kind not in COLUMNS:
        raise ValueError(f"kind must be one of {tuple(COLUMNS)}, got {short_repr(kind)}")
    max_reach = check_tolerance(max_reach, "max_reach")
    unit_tol = check_tolerance(unit_tol, "unit_tol")
    path = _path(path)
    width = len(COLUMNS[kind])
    values = real_array(values, "values")
    if values.ndim == 1:
        values = values[None, :]
    if values.ndim != 2 or values.shape[1] != width:
        raise ValueError(f"values must have shape (N, {width}) for kind {short_repr(kind)}, "
                         f"got {values.shape}")
    if names is None:
        names = [f"pose_{k + 1}" for k in range(len(values))]
    names = [str(n) for n in names]
    if len(names) != len(values):
        raise ValueError(f"names has {len(names)} entries for {len(values)} poses")
    for k, (name, row) in enumerate(zip(names, values, strict=True)):
        if not _NAME.fullmatch(name):
            raise ValueError(f"names[{k}] = {short_repr(name)}: use letters, digits, '_', '.', '-'")
        if names.index(name) != k:
            raise ValueError(f"names[{k}] = {short_repr(name)} repeats names[{names.index(name)}]")
        problem = _check_values(kind, row.tolist(), max_reach=max_reach, unit_tol=unit_tol)
        if problem:
            raise ValueError(f"pose {k} ({short_repr(name)}): {problem}")
    for key, value in (("robot", robot), ("frame", frame), ("tcp", tcp)):
        check_text(value, key)                      # one printable line: no header injection
    lines = [_MAGIC, f"# version: {FORMAT_VERSION}", f"# kind: {kind}",
             f"# units: {_UNITS[kind]}", f"# frame: {frame}", f"# robot: {robot}",
             f"# tcp: {tcp}", ",".join(("name",) + COLUMNS[kind])]
    lines += [",".join([name] + [repr(float(x)) for x in row])
              for name, row in zip(names, values, strict=True)]
    lines.append(f"# end: {len(values)}")
    write_atomically(path, "\n".join(lines) + "\n")


def append_pose(path, value, *, name=None, kind="ur_pose", robot="UR3", frame="base",
                tcp="flange", max_reach=2.0, unit_tol=1e-9):
    """Add one pose to a pose file (created if absent), as the thesis's ``record_pose`` does.

    The existing file is read and checked first (its kind, robot, frame and tcp must match);
    the whole file is then rewritten atomically.

    Parameters
    ----------
    path : str or path-like
    value : array_like, shape (6,) or (8,)
    name : str, optional
        Default ``pose_<N+1>``.
    kind, robot, frame, tcp, max_reach, unit_tol
        As in :func:`write_poses`.

    Returns
    -------
    str
        The name given to the pose.

    Examples
    --------
    >>> import os, tempfile
    >>> folder = tempfile.TemporaryDirectory()
    >>> path = os.path.join(folder.name, "poses.csv")
    >>> append_pose(path, [0.2, 0.0, 0.3, 0.0, 3.1, 0.0])
    'pose_1'
    >>> append_pose(path, [0.2, 0.1, 0.3, 0.0, 3.1, 0.0], name="next")
    'next'
    >>> read_poses(path).names
    ('pose_1', 'next')
    >>> folder.cleanup()
    """
    path = _path(path)
    if not isinstance(kind, str) or kind not in COLUMNS:
        raise ValueError(f"kind must be one of {tuple(COLUMNS)}, got {short_repr(kind)}")
    value = real_array(value, "value")
    if value.shape != (len(COLUMNS[kind]),):
        raise ValueError(f"value must be one pose of shape ({len(COLUMNS[kind])},) for kind "
                         f"{short_repr(kind)}, got shape {value.shape}")
    if path.exists():
        old = read_poses(path, max_reach=max_reach, unit_tol=unit_tol)
        for key, want in (("kind", kind), ("robot", robot), ("frame", frame), ("tcp", tcp)):
            if getattr(old, key) != want:
                raise ValueError(f"{path} holds {key} {getattr(old, key)!r}, not "
                                 f"{short_repr(want)}")
        names, values = list(old.names), list(old.values)
    else:
        names, values = [], []
    name = f"pose_{len(names) + 1}" if name is None else str(name)
    values.append(value)
    write_poses(path, np.array(values), kind=kind, names=names + [name], robot=robot,
                frame=frame, tcp=tcp, max_reach=max_reach, unit_tol=unit_tol)
    return name
