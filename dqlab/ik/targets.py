r"""Targets of inverse kinematics: parsed and checked once, and the one pose-error measure.

Every solver of :mod:`dqlab.ik` takes its targets the same way: rigid transforms
``(..., 4, 4)`` or unit dual quaternions ``(..., 8)`` (told apart by the trailing shape),
and, for the solvers that place a point, positions ``(..., 3)``. :func:`parse_targets`
checks them in one pass and keeps the form it was given; the other form is computed when a
solver asks for it. :func:`pose_errors` is how every solver measures how far a pose is from
its target.
"""

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._checks import as_float_array, check_tolerance, component_rows, components, real_array
from .._formulas import pose_error_entries
from ..dualquat import (
    check_unit_dual_quaternion,
    dual_quaternion_from_transform,
    dual_quaternion_normalize,
    transform_from_dual_quaternion,
)
from ..transforms import checked_transform_entries

__all__ = ["Targets", "parse_targets", "pose_errors"]

#: The tolerance of a rigid pose; a looser ``tol`` in :func:`parse_targets` replaces each pose
#: by the nearest rigid one.
RIGID_TOL = 1e-9

_KINDS = {(4, 4): "transform", (8,): "dual_quaternion", (3,): "position"}


@dataclass
class Targets:
    """Checked targets, in the form they were given; the other form on demand.

    Attributes
    ----------
    kind : {"transform", "dual_quaternion", "position"}
        The form of the targets as given (a transform checked with a loosened tolerance
        is held as its normalised dual quaternion).
    batch : tuple of int
        Their leading shape.
    """

    kind: str
    batch: tuple
    _transforms: np.ndarray = field(default=None, repr=False)
    _dual_quaternions: np.ndarray = field(default=None, repr=False)
    _entries: np.ndarray = field(default=None, repr=False)    # (16, ...), see below

    def reshape(self, batch):
        """The same targets with the leading shape ``batch``."""
        batch = tuple(batch)
        return Targets(self.kind, batch, *(
            None if a is None else a.reshape(batch + a.shape[len(self.batch):])
            for a in (self._transforms, self._dual_quaternions)),
            None if self._entries is None else self._entries.reshape((16,) + batch))

    def __getitem__(self, index):
        """A part of a one-dimensional batch of targets (``index`` a slice or an array of
        indices)."""
        parts = [None if a is None else a[index]
                 for a in (self._transforms, self._dual_quaternions)]
        batch = next(a for a in parts if a is not None).shape[:1]
        entries = None if self._entries is None else self._entries[:, index]
        return Targets(self.kind, batch, *parts, entries)

    @property
    def has_rotation(self):
        """False for positions (a position-only problem)."""
        return self.kind != "position"

    @property
    def transforms(self):
        """The targets as rigid transforms :math:`X_{WT}^*`, shape (..., 4, 4); positions
        get the identity rotation."""
        if self._transforms is None:
            self._transforms = transform_from_dual_quaternion(self._dual_quaternions,
                                                              tol=np.inf)
        return self._transforms

    def take_transform_entries(self):
        """The sixteen entries of the transforms, in the order of their rows, as the rows of
        an array (16, ...) (the copy the check of a batch read, or one made now). They are
        handed over: the targets forget them, and the caller may overwrite them (as big as
        the transforms, they would otherwise stay in memory as long as the targets)."""
        entries = self._entries
        if entries is None:
            entries = component_rows(self.transforms.reshape(self.batch + (16,)))
        self._entries = None
        return entries

    @property
    def dual_quaternions(self):
        """The targets as unit dual quaternions, shape (..., 8)."""
        if self._dual_quaternions is None:
            self._dual_quaternions = dual_quaternion_from_transform(self._transforms,
                                                                    tol=np.inf)
        return self._dual_quaternions

    @property
    def positions(self):
        """The target positions, shape (..., 3)."""
        return self.transforms[..., :3, 3]


def parse_targets(target: ArrayLike, *, position: bool | str = False, tol: float = RIGID_TOL,
                  name: str = "target") -> Targets:
    r"""Check IK targets once and return them as :class:`Targets`.

    Parameters
    ----------
    target : array_like, shape (..., 4, 4), (..., 8) or (..., 3)
        Rigid transforms, unit dual quaternions ``(q_r, q_d)`` or (with ``position``)
        positions, told apart by the trailing shape.
    position : bool or "only"
        Whether positions are accepted (``True``), required (``"only"``) or refused
        (``False``).
    tol : float
        Tolerance of the rigidity check. Above the default (poses read from rounded
        numbers), each pose is replaced by the rigid pose of its normalised dual quaternion.
    name : str
        Name of the argument in error messages.

    Returns
    -------
    Targets

    Raises
    ------
    ValueError
        Naming ``name``: a wrong trailing shape, NaN or infinity, a transform that is not
        rigid, a dual quaternion that is not unit.

    Examples
    --------
    >>> import numpy as np
    >>> targets = parse_targets(np.eye(4))
    >>> targets.kind, targets.dual_quaternions
    ('transform', array([1., 0., 0., 0., 0., 0., 0., 0.]))
    >>> parse_targets([0.1, 0.2, 0.3], position="only").positions
    array([0.1, 0.2, 0.3])
    >>> parse_targets(np.zeros(5))
    Traceback (most recent call last):
    ...
    ValueError: target must have shape (..., 4, 4) (a transform) or (..., 8) (a unit dual ...
    """
    a = real_array(target, name)
    tol = check_tolerance(tol, "pose_tol" if name == "target" else "tol")
    kind = _kind(a, position, name)
    if kind == "position":
        a = as_float_array(a, name, (3,))
        X = np.broadcast_to(np.eye(4), a.shape[:-1] + (4, 4)).copy()
        X[..., :3, 3] = a
        return Targets(kind, a.shape[:-1], _transforms=X)
    if kind == "transform" and tol <= RIGID_TOL:   # checked; converted when a solver asks
        T, entries = checked_transform_entries(a, tol, name)
        return Targets(kind, a.shape[:-2], _transforms=T, _entries=entries)
    if kind == "transform":
        Q = dual_quaternion_from_transform(a, tol=tol, name=name)   # checks while converting
    else:
        Q = check_unit_dual_quaternion(a, tol, name=name)
        if tol <= RIGID_TOL:
            return Targets(kind, a.shape[:-1], _dual_quaternions=Q)
    # a loosened tolerance: the rigid pose of the normalised dual quaternion
    return Targets("dual_quaternion", Q.shape[:-1], _dual_quaternions=dual_quaternion_normalize(Q))


def _kind(a, position, name):
    kind = next((k for trailing, k in _KINDS.items()
                 if a.ndim >= len(trailing) and a.shape[a.ndim - len(trailing):] == trailing),
                None)
    if position == "only":
        if kind == "position":
            return kind
        want = "(..., 3) (a position)"
    elif kind == "position" and not position and a.shape[-2:] != (3, 3):
        want = ("(..., 4, 4) (a transform) or (..., 8) (a unit dual quaternion), got shape "
                f"{a.shape}: a position, which only a position-only solve accepts "
                "(position_only=True where the solver has one)")
        raise ValueError(f"{name} must have shape {want}")
    elif kind is not None and not (kind == "position" and not position):
        return kind
    else:
        want = "(..., 4, 4) (a transform) or (..., 8) (a unit dual quaternion)"
        if position:
            want = ("(..., 4, 4) (a transform), (..., 8) (a unit dual quaternion) or "
                    "(..., 3) (a position)")
    raise ValueError(f"{name} must have shape {want}, got shape {a.shape}{_hint(a.shape)}")


#: What a target of another trailing shape probably is, and how to make a pose of it.
_HINTS = {
    (3, 3): ("a rotation matrix? A pose needs the position too: "
             "dqlab.transforms.transform_from(R, p)"),
    (3, 4): "the top three rows of a transform? Append the row [0, 0, 0, 1]",
    (6,): ("a UR pose vector [x, y, z, rx, ry, rz]? Convert it with "
           "dqlab.ur.transform_from_pose(p)"),
    (7,): ("a position and a quaternion? Build the transform with "
           "dqlab.transforms.transform_from(dqlab.matrix_from_quaternion(q), p); quaternions "
           "are (w, x, y, z) in dqlab, dqlab.quaternion.quaternion_from_xyzw converts from "
           "(x, y, z, w)"),
    (4,): ("a quaternion? A pose needs the position too: "
           "dqlab.dual_quaternion_from_rotation_translation(q, p), with q as (w, x, y, z)"),
}


def _hint(shape):
    """``": <what it probably is>"`` for a target of the wrong shape, or ``""``."""
    for trailing, hint in _HINTS.items():
        if len(shape) >= len(trailing) and shape[len(shape) - len(trailing):] == trailing:
            return f": {hint}"
    return ""


def _distances(X, X_target):
    r"""The distances between the positions of poses (..., 4, 4), each computed as
    :math:`m \sqrt{\sum (d_i / m)^2}` with :math:`m = \max |d_i|`, which overflows only
    when the distance itself exceeds the largest float; one float for one pose, as
    :func:`pose_errors` computes it."""
    with np.errstate(over="ignore", invalid="ignore"):
        d = X[..., :3, 3] - X_target[..., :3, 3]
        m = np.abs(d).max(axis=-1)
        scaled = d / np.where(m > 0.0, m, 1.0)[..., None]
        distance = m * np.sqrt((scaled * scaled).sum(axis=-1))
    return float(distance.reshape(-1)[0]) if X.size == 16 else distance


def pose_errors(X: ArrayLike, X_target: ArrayLike
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Position and rotation errors between poses: the one error measure of :mod:`dqlab.ik`.

    .. math::

       e_p = \lVert p - p^\ast \rVert, \qquad
       e_R = \angle\bigl(R\, R^{\ast\top}\bigr)
           = \operatorname{atan2}\bigl(\lVert (M - M^\top)^\vee \rVert,\;
             \operatorname{tr} M - 1\bigr) \in [0, \pi],\quad M = R\, R^{\ast\top},

    the angle read from the sine (the vector part) and the cosine (the trace) together,
    accurate for tiny errors as well as near a half turn.

    Parameters
    ----------
    X, X_target : array_like, shape (..., 4, 4)
        Poses; leading axes broadcast.

    Returns
    -------
    position_error : ndarray, shape (...)
        Metres.
    rotation_error : ndarray, shape (...)
        Radians.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.rotations import rot_z
    >>> X = np.eye(4)
    >>> Y = np.eye(4)
    >>> Y[:3, :3] = rot_z(1e-12)
    >>> Y[0, 3] = 3e-3
    >>> pose_errors(X, Y)
    (array(0.003), array(1.e-12))
    """
    X = as_float_array(X, "X", (4, 4))
    X_target = as_float_array(X_target, "X_target", (4, 4))
    if X.shape != X_target.shape:
        X, X_target = np.broadcast_arrays(X, X_target)
    lead = X.shape[:-2]
    # on components: Python floats for one pose (whatever its leading shape), columns for
    # a batch
    one = X.size == 16
    with np.errstate(over="ignore", invalid="ignore"):
        position_error, rotation_error = pose_error_entries(
            components(X.reshape(16 if one else lead + (16,))),
            components(X_target.reshape(16 if one else lead + (16,))))
    if not np.isfinite(position_error).all():      # squares beyond the largest float:
        position_error = _distances(X, X_target)   # the distance with the squares scaled
    if not (np.isfinite(position_error).all() and np.isfinite(rotation_error).all()):
        raise ValueError("X and X_target are too large for their errors (overflow): they "
                         "must be rigid transforms whose positions are less than 1e308 m "
                         "apart")
    if one:
        return np.full(lead, position_error), np.full(lead, rotation_error)
    return np.asarray(position_error), np.asarray(rotation_error)
