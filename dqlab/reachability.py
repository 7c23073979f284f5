r"""The reachability and dexterity map of a UR arm: how many inverse-kinematics branches reach
each tool pose, and how well conditioned the best of them is (chapter 11).

- :func:`pose_dexterity` scores poses: :math:`c(X)`, the number of valid branches of
  :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`, and :math:`w(X)`, the best
  manipulability :math:`\lvert\det J\rvert` among them;
- :func:`super_fibonacci_quaternions` spreads orientations evenly over the rotations;
- :func:`reachability_statistics` scores a grid of positions with a set of orientations and
  reduces the samples to statistics per position, a :class:`ReachabilityMap`, which
  :meth:`ReachabilityMap.save` writes to a file and :meth:`ReachabilityMap.load` reads back
  (checked).

Everything here needs numpy only. The same map on many processes or machines is
:func:`dqlab.dask_arrays.reachability_map`, which runs :func:`reachability_statistics` on
chunks of the grid with dask; chapter 11 plots a map of :math:`10^7` samples made that way by
``benchmarks/bench_reachability.py``.
"""

import zipfile
import zlib
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import as_float_array, check_instance, check_path, check_scalar
from ._files import write_atomically
from .ik import ur
from .jacobian import manipulability
from .quaternion import check_unit_quaternion, matrix_from_quaternion
from .robot import Robot

__all__ = ["pose_dexterity", "super_fibonacci_quaternions", "ReachabilityMap",
           "reachability_statistics"]

#: Poses per call of the solver inside :func:`reachability_statistics`: small temporaries.
BLOCK = 8192
#: The most orientations :func:`super_fibonacci_quaternions` makes (320 MB of them).
MAX_ORIENTATIONS = 10 ** 7


def pose_dexterity(robot: Robot, poses: ArrayLike, **options
                   ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    r"""How many UR inverse-kinematics branches reach each pose, and the best manipulability.

    For a pose :math:`X`, with :math:`q_1, \dots, q_c` the valid rows of
    ``dqlab.ik.ur(robot, X)`` (:math:`0 \le c \le 8`):

    .. math::

        c(X) = \#\{\text{valid rows}\},\qquad
        w(X) = \max_{1 \le i \le c} \sqrt{\det\bigl(J(q_i)\, J(q_i)^\top\bigr)}
             = \max_i\, \lvert\det J(q_i)\rvert ,\qquad w = 0 \text{ when } c = 0,

    with :math:`J` the full :math:`6 \times 6` geometric Jacobian
    (:meth:`dqlab.robot.Robot.jacobian`, linear rows first) and the measure computed by
    :func:`dqlab.jacobian.manipulability` (Yoshikawa's, as the product of the singular
    values). Why the full :math:`J` and not its linear rows :math:`J_v`: a pose fixes the
    orientation too, and :math:`w` must vanish at every singularity of the arm -- wrist,
    elbow and shoulder -- while :math:`\sqrt{\det J_v J_v^\top}` stays positive at the wrist
    singularity (three of six joints suffice for the position). Units: the linear rows are
    metres per radian and the angular rows radians per radian, so :math:`w` is in
    :math:`\mathrm m^3`; and since :math:`J` is square, :math:`\lvert\det J\rvert` does not
    depend on the point of the tool chosen as TCP nor on the orientation of the world frame
    (both multiply :math:`J` by a matrix of determinant 1): it is a property of the
    configuration. The maximum is over branches because a task can choose its branch: it
    measures the best way the arm can hold the pose.

    Branches that coincide at a singularity are counted once per row, as ``IKResult.count``
    does (see :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`).

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm.
    poses : array_like, shape (..., 4, 4) or (..., 8)
        Target poses (see :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`).
    **options
        Passed to :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`.

    Returns
    -------
    count : ndarray of int, shape (...)
        :math:`c`, the number of valid branches.
    manipulability : ndarray, shape (...)
        :math:`w` in :math:`\mathrm m^3`.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> q = np.array([[0.3, -1.2, 1.1, -0.4, 0.9, 0.2],     # regular
    ...               [0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0]])  # every singularity
    >>> count, w = pose_dexterity(robot, robot.fk(q))
    >>> count, (w * 1e3).round(3)
    (array([8, 8]), array([16.03,  0.  ]))
    """
    check_instance(robot, Robot, "robot")
    check_ik_options(robot, options)
    try:
        # a pose far beyond reach (1e150 m) overflows inside the solver, which then reports
        # no valid branch: the right count, 0
        with np.errstate(over="ignore", invalid="ignore"):
            result = ur(robot, poses, **options)
    except (ValueError, TypeError) as exc:     # the solver calls its argument "target"
        raise type(exc)(f"poses: {exc}") from None
    w = np.zeros(result.valid.shape)
    if result.valid.any():
        w[result.valid] = manipulability(robot.jacobian(result.solutions[result.valid]))
    return result.count, w.max(axis=-1, initial=0.0)


def _probe_pose(robot, kind):
    """A pose of ``robot`` in the form ``kind`` (``(4, 4)`` or ``(8,)``), to check the
    arguments of a solver before a long computation."""
    X = robot.fk(np.zeros(robot.n))
    if kind == (4, 4):
        return X
    from .dualquat import dual_quaternion_from_transform
    return dual_quaternion_from_transform(X)


def check_ik_options(robot, options, kind=(4, 4)):
    """Solve one pose of ``robot`` with the options of :func:`dqlab.ik.ur
    <dqlab.ik.ur_solver.ur>`, to refuse a wrong robot or option before a long
    computation (raising what the solver raises); ``q_ref`` must be one joint vector, the
    same for every pose. ``kind`` is the form of the poses, ``(4, 4)`` or ``(8,)``.

    Returns
    -------
    IKResult
        Of the probe pose (the robot at its zero configuration).
    """
    check_instance(robot, Robot, "robot")
    if kind not in ((4, 4), (8,)):
        raise ValueError(f"kind must be (4, 4) or (8,), the form of the poses, got {kind!r}")
    q_ref = options.get("q_ref")
    if q_ref is not None and np.shape(q_ref) != (6,):
        raise ValueError(f"q_ref must be one joint vector of shape (6,) here (the same "
                         f"reference for every pose), got shape {np.shape(q_ref)}")
    return ur(robot, _probe_pose(robot, kind), **options)


def super_fibonacci_quaternions(k: int) -> NDArray[np.float64]:
    r"""``k`` unit quaternions spread evenly over the rotations (a super-Fibonacci spiral).

    Point :math:`i` of Alexa's spiral (CVPR 2022), with :math:`s = i + \frac12`,
    :math:`\phi = \sqrt2` and :math:`\psi \approx 1.533751168755204`:

    .. math::

        q_i = \Bigl(\sqrt{s/k}\,\sin\frac{2\pi s}{\phi},\ \sqrt{s/k}\,\cos\frac{2\pi s}{\phi},\
              \sqrt{1 - s/k}\,\sin\frac{2\pi s}{\psi},\
              \sqrt{1 - s/k}\,\cos\frac{2\pi s}{\psi}\Bigr),

    read as :math:`(w, x, y, z)`. The points cover the unit sphere of quaternions evenly (low
    discrepancy, nearly equal Voronoi cells), so the rotations cover SO(3) evenly: a
    deterministic stand-in for ``k`` uniformly random orientations.

    Parameters
    ----------
    k : int
        Number of orientations, at least 1.

    Returns
    -------
    ndarray, shape (k, 4)

    Examples
    --------
    >>> import numpy as np
    >>> q = super_fibonacci_quaternions(100)
    >>> q.shape, bool(np.allclose(np.linalg.norm(q, axis=1), 1.0))
    ((100, 4), True)
    """
    k = check_scalar(k, "k", minimum=1, maximum=MAX_ORIENTATIONS, integer=True)
    s = np.arange(k) + 0.5
    r, rr = np.sqrt(s / k), np.sqrt(1.0 - s / k)
    alpha = 2.0 * np.pi * s / np.sqrt(2.0)
    beta = 2.0 * np.pi * s / 1.533751168755204288118041
    return np.stack([r * np.sin(alpha), r * np.cos(alpha), rr * np.sin(beta),
                     rr * np.cos(beta)], axis=-1)


@dataclass
class ReachabilityMap:
    r"""Statistics of a UR arm's reach and dexterity per tool position.

    Made by :func:`dqlab.dask_arrays.reachability_map` (dask) or
    :func:`reachability_statistics` (numpy) from the :math:`M \times K` samples
    :math:`X_{mk} = (R(q_k), p_m)`: every position :math:`p_m` with every orientation
    :math:`q_k`, each scored by :func:`pose_dexterity` (:math:`c_{mk}` branches,
    manipulability :math:`w_{mk}`).

    Attributes
    ----------
    positions : ndarray, shape (..., 3)
        The tool positions :math:`p_m` in the world frame (metres), any leading shape (a 3D
        grid: ``(nx, ny, nz, 3)``).
    orientations : ndarray, shape (K, 4)
        The tool orientations :math:`q_k`, unit quaternions ``(w, x, y, z)``.
    reachable : ndarray of int, shape (...)
        How many of the K orientations have at least one valid branch at each position.
    branches : ndarray of int, shape (...)
        :math:`\sum_k c_{mk}`, the valid branches over all K orientations.
    median_manipulability : ndarray, shape (...)
        Median of :math:`w_{mk}` (:math:`\mathrm m^3`) over the reachable orientations at
        each position; NaN where none is reachable.
    metadata : dict
        Anything stored with the map (how and when it was computed), numbers and text.

    Raises
    ------
    ValueError
        On construction (and so on :meth:`load`), naming the array: shapes that do not
        agree, NaN or infinite positions, orientations that are not unit quaternions,
        counts that are not integers between 0 and their bound (:math:`K` orientations,
        :math:`8K` branches, at least one branch per reachable orientation), or a median
        that is not NaN exactly where nothing is reachable and a finite number >= 0
        elsewhere.
    """

    positions: np.ndarray
    orientations: np.ndarray
    reachable: np.ndarray
    branches: np.ndarray
    median_manipulability: np.ndarray
    metadata: dict = field(default_factory=dict)

    _ARRAYS = ("positions", "orientations", "reachable", "branches", "median_manipulability")

    def __post_init__(self):
        self.positions = as_float_array(self.positions, "positions", (3,))
        lead = self.positions.shape[:-1]
        self.orientations = _unit_quaternions(self.orientations)
        if self.orientations.ndim != 2 or len(self.orientations) == 0:
            raise ValueError(f"orientations must have shape (K, 4) with K >= 1, got shape "
                             f"{self.orientations.shape}")
        k = len(self.orientations)
        self.reachable = _counts(self.reachable, "reachable", lead, k)
        self.branches = _counts(self.branches, "branches", lead, 8 * k)
        if np.any(self.branches < self.reachable):
            raise ValueError("branches must be >= reachable at every position (each reachable "
                             "orientation has at least one branch)")
        try:
            median = np.asarray(self.median_manipulability)
        except ValueError:
            median = np.asarray(None)
        if median.dtype.kind not in "iuf":
            raise ValueError(f"median_manipulability must be an array of real numbers, got "
                             f"{self.median_manipulability!r}"[:200])
        median = median.astype(float)
        if median.shape != lead:
            raise ValueError(f"median_manipulability must have shape {lead}, that of "
                             f"positions[..., 0], got shape {median.shape}")
        reached = self.reachable > 0
        good = np.isfinite(median) & (median >= 0)
        if np.any(np.isnan(median) == reached) or not np.all(good[reached]):
            raise ValueError("median_manipulability must be NaN exactly where no orientation "
                             "is reachable and a finite number >= 0 elsewhere")
        self.median_manipulability = np.where(reached, median, np.nan)
        if not isinstance(self.metadata, dict):
            raise ValueError(f"metadata must be a dict, got {type(self.metadata).__name__}")

    @property
    def samples(self) -> int:
        """The number of poses scored, :math:`M K`."""
        return int(self.reachable.size * len(self.orientations))

    @property
    def fraction(self) -> NDArray[np.float64]:
        """The fraction of the orientations reachable at each position, shape (...)."""
        return self.reachable / len(self.orientations)

    @property
    def mean_count(self) -> NDArray[np.float64]:
        """The mean number of valid branches over the orientations, shape (...)."""
        return self.branches / len(self.orientations)

    def save(self, path, **metadata) -> None:
        """Write the map (and ``metadata``: numbers or text) to a compressed ``.npz`` file.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> from dqlab.models import ur3
        >>> grid = [[0.0, -0.35, 0.25], [0.9, 0.0, 0.2]]
        >>> rmap = reachability_statistics(ur3(), grid, super_fibonacci_quaternions(8))
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "map.npz"
        >>> rmap.save(path, command="an example")
        >>> back = ReachabilityMap.load(path)
        >>> back.reachable, back.metadata["command"]
        (array([8, 0]), 'an example')
        """
        path = check_path(path)
        if path.is_dir():
            raise ValueError(f"path {path} is a directory: give the file to write")
        meta = {**self.metadata, **metadata}
        arrays = {name: getattr(self, name) for name in self._ARRAYS}
        for key, value in meta.items():
            value = np.asarray(value)
            if value.dtype.kind not in "biufU":
                raise ValueError(f"metadata {key!r} must be numbers or text, got {value.dtype}")
            arrays["meta_" + key] = value
        if path.suffix != ".npz":                 # as numpy names the file it writes
            path = path.with_name(path.name + ".npz")
        write_atomically(path, lambda f: np.savez_compressed(f, **arrays))

    @classmethod
    def load(cls, path) -> "ReachabilityMap":
        """Read a map written by :meth:`save` (numbers and text only, no pickles).

        Raises
        ------
        ValueError
            Naming the file: not a ``.npz`` archive, a damaged one, an array missing or
            stored as Python objects, or arrays that do not make a valid map (see
            :class:`ReachabilityMap`).
        FileNotFoundError
            If there is no such file.
        """
        path = check_path(path)
        try:
            data = np.load(path, allow_pickle=False)
            if not isinstance(data, np.lib.npyio.NpzFile):
                raise ValueError("a single array, not an .npz archive of a map")
            with data:
                missing = [name for name in cls._ARRAYS if name not in data.files]
                if missing:
                    raise ValueError(f"no array {', '.join(missing)} (not a reachability map)")
                arrays = {name: data[name] for name in cls._ARRAYS}
                meta = {key[5:]: data[key] for key in data.files if key.startswith("meta_")}
        except FileNotFoundError:
            raise
        except (ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
            raise ValueError(f"{path}: not a reachability map written by "
                             f"ReachabilityMap.save: {_why(exc)}") from None
        meta = {key: value[()].item() if value.ndim == 0 else value
                for key, value in meta.items()}
        try:
            return cls(**arrays, metadata=meta)
        except (ValueError, TypeError) as exc:
            raise ValueError(f"{path}: {exc}") from None


def _why(exc):
    """A short reason for a failed load (numpy's message about pickles says what to do
    with ``allow_pickle``, which is not the remedy here)."""
    text = str(exc)
    if "pickle" in text:
        return "an array is stored as Python objects"
    return text or type(exc).__name__


def _counts(value, name, shape, bound):
    """Integer counts of shape ``shape`` between 0 and ``bound``."""
    try:
        a = np.asarray(value)
    except ValueError:
        a = np.asarray(None)
    if a.dtype.kind not in "iu":
        raise ValueError(f"{name} must be an array of integers, got {value!r}"[:200])
    if a.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, that of positions[..., 0], got "
                         f"shape {a.shape}")
    if a.size and (a.min() < 0 or a.max() > bound):
        raise ValueError(f"{name} must be between 0 and {bound}, got values from {a.min()} "
                         f"to {a.max()}")
    return a.astype(np.int64)


def _unit_quaternions(orientations):
    """``orientations`` checked as unit quaternions (huge ones overflow in the norm: they
    are refused as not finite, without a warning)."""
    with np.errstate(over="ignore"):
        return check_unit_quaternion(orientations, name="orientations")


def _check_grid(positions, orientations):
    """``positions`` (..., 3) and ``orientations`` (K, 4), checked."""
    positions = as_float_array(positions, "positions", (3,))
    orientations = _unit_quaternions(orientations)
    if orientations.ndim != 2 or len(orientations) == 0:
        raise ValueError(f"orientations must have shape (K, 4) with K >= 1, got shape "
                         f"{orientations.shape}")
    return positions, orientations


def _median_of_reachable(w, ok):
    """Median over axis 1 of ``w`` where ``ok`` (the number ``np.median`` gives for those
    values), NaN where none is."""
    s = np.sort(np.where(ok, w, np.inf), axis=1)
    r = ok.sum(axis=1)
    rows = np.arange(len(s))
    lo = s[rows, np.maximum(r - 1, 0) // 2]
    hi = s[rows, r // 2]
    return np.where(r > 0, (lo + hi) / 2, np.nan)


def _statistics(robot, positions, R, block, options):
    """reachable, branches, median manipulability (m,) of positions (m, 3) over the
    orientations R (K, 3, 3), ``block`` samples at a time."""
    m, k = len(positions), len(R)
    reachable = np.zeros(m, dtype=np.int64)
    branches = np.zeros(m, dtype=np.int64)
    median = np.full(m, np.nan)
    step = max(1, block // k)
    for start in range(0, m, step):
        part = slice(start, min(start + step, m))
        p = positions[part]
        X = np.zeros((len(p), k, 4, 4))
        X[..., :3, :3] = R
        X[..., :3, 3] = p[:, None, :]
        X[..., 3, 3] = 1.0
        count, w = pose_dexterity(robot, X, **options)
        ok = count > 0
        reachable[part] = ok.sum(axis=1)
        branches[part] = count.sum(axis=1)
        median[part] = _median_of_reachable(w, ok)
    return reachable, branches, median


def reachability_statistics(robot: Robot, positions: ArrayLike, orientations: ArrayLike, *,
                            block: int = BLOCK, **options) -> ReachabilityMap:
    r"""The reachability map with numpy, in this process (the reference of
    :func:`dqlab.dask_arrays.reachability_map`, which runs it on chunks of ``positions``).

    Scores every pose :math:`X_{mk} = (R(q_k), p_m)` -- the tool at position :math:`p_m`
    with orientation :math:`q_k` -- by :func:`pose_dexterity` and reduces over the
    orientations: see :class:`ReachabilityMap`. The poses are built as 4x4 transforms with
    :func:`dqlab.quaternion.matrix_from_quaternion`, ``block`` of them per call of
    :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm.
    positions : array_like, shape (..., 3)
        Tool positions in the world frame (metres).
    orientations : array_like, shape (K, 4)
        Tool orientations as unit quaternions (for example
        :func:`super_fibonacci_quaternions`).
    block : int
        Poses per call (memory: about 3 kB each).
    **options
        Passed to :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`.

    Returns
    -------
    ReachabilityMap

    Raises
    ------
    ValueError
        Wrong shapes, NaN, non-unit quaternions, a robot that is not UR-shaped.

    Examples
    --------
    The centre of chapter 11's circle, and a point out of reach:

    >>> from dqlab.models import ur3
    >>> rmap = reachability_statistics(ur3(), [[0.0, -0.35, 0.25], [0.9, 0.0, 0.2]],
    ...                                super_fibonacci_quaternions(64))
    >>> rmap.samples, rmap.reachable, rmap.mean_count
    (128, array([64,  0]), array([7.53125, 0.     ]))
    >>> (rmap.median_manipulability * 1e3).round(2)
    array([13.91,   nan])
    """
    positions, orientations = _check_grid(positions, orientations)
    block = check_scalar(block, "block", minimum=1, integer=True)
    check_ik_options(robot, options)
    R = matrix_from_quaternion(orientations)
    flat = positions.reshape(-1, 3)
    reachable, branches, median = _statistics(robot, flat, R, block, options)
    lead = positions.shape[:-1]
    return ReachabilityMap(positions=positions, orientations=orientations,
                           reachable=reachable.reshape(lead), branches=branches.reshape(lead),
                           median_manipulability=median.reshape(lead))
