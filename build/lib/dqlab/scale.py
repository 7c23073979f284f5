r"""Beyond one machine: dqlab's batch functions on dask arrays, and the UR3's reachability map.

Every batch function of dqlab works on the leading axes of its arrays, pose by pose, with
no coupling between poses. That is exactly what `dask.array
<https://docs.dask.org/en/stable/array.html>`_ distributes: an array cut into chunks along
its leading (batch) axes, one task per chunk. The functions here take dask arrays chunked
that way and call the unchanged numpy function on each chunk
(``dask.array.blockwise``, the general form of ``dask.array.map_blocks``), so that

- :func:`fk` is :meth:`dqlab.robot.Robot.fk`, :func:`ik_ur` is
  :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>` and :func:`dexterity` is
  :func:`pose_dexterity`, chunk by chunk, and their results are those of the numpy call on
  the whole batch, number for number;
- nothing here schedules anything: the chunks run on whatever dask scheduler is asked for
  or active -- the synchronous one (examples, debugging), threads, processes, a
  ``distributed.LocalCluster`` on one machine, or a cluster whose scheduler listens at an
  address such as ``"tcp://scheduler-host:8786"``, with the same code.

:func:`reachability_map` applies this to a question of the book: over a grid of tool
positions and a set of orientations, how many inverse-kinematics branches reach each pose,
and how well conditioned is the best of them (:func:`pose_dexterity`)? It reduces the
samples to statistics per position (:class:`ReachabilityMap`);
:func:`reachability_statistics` is the same computation with numpy in one process, the
reference the dask version is checked against. Chapter 11 plots a map of :math:`10^7`
samples made by ``benchmarks/bench_reachability.py``.

dask is an optional dependency (the extra ``scale``: ``pip install 'dqlab[scale]'``). This
module imports numpy alone; dask is imported when a function that needs it is called, and
its absence is reported with the command that installs it. :func:`pose_dexterity`,
:func:`reachability_statistics`, :func:`super_fibonacci_quaternions` and
:class:`ReachabilityMap` need numpy only.
"""

import functools
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import as_float_array
from .ik import ur
from .jacobian import manipulability
from .quaternion import check_unit_quaternion, matrix_from_quaternion
from .robot import Robot

__all__ = [
    "fk", "ik_ur", "IKArrays", "dexterity", "pose_dexterity", "reachability_map",
    "reachability_statistics", "ReachabilityMap", "super_fibonacci_quaternions",
]

#: The command that installs what this module needs, quoted in its error messages.
INSTALL = "pip install 'dqlab[scale]'"

_SAMPLES_PER_TASK = 2 ** 16       # default work of one task of reachability_map (~1 s)
_BLOCK = 8192                     # poses per numpy call inside a task: small temporaries
_SCHEDULER_NAMES = ("synchronous", "sync", "single-threaded", "threads", "threading",
                    "processes", "multiprocessing", "distributed", "dask.distributed")


def _dask_array():
    """``dask.array``, or an ImportError that says how to install it."""
    try:
        import dask.array as da
    except ImportError:
        raise ImportError(f"dqlab.scale needs dask to work on dask arrays: install the extra "
                          f"with {INSTALL} (or pip install 'dask[array]' distributed)"
                          ) from None
    return da


def _distributed():
    """``distributed``, or an ImportError that says how to install it."""
    try:
        import distributed
    except ImportError:
        raise ImportError(f"connecting to a dask scheduler address needs dask.distributed: "
                          f"install the extra with {INSTALL} (or pip install distributed)"
                          ) from None
    return distributed


def _as_dask(x, name):
    """``x`` as a float dask array (a numpy array becomes one chunk)."""
    da = _dask_array()
    if not isinstance(x, da.Array):
        x = da.asarray(as_float_array(x, name))
    if x.dtype.kind not in "fiu":
        raise TypeError(f"{name} must hold real numbers, got dtype {x.dtype}")
    return x if x.dtype == np.float64 else x.astype(np.float64)


def _check_trailing(x, name, trailing):
    """ValueError naming ``name`` unless ``x.shape`` ends with one of the ``trailing``
    shapes; returns the one it ends with."""
    for t in trailing:
        if x.ndim >= len(t) and tuple(x.shape[x.ndim - len(t):]) == t:
            return t
    want = " or ".join("(..., " + ", ".join(map(str, t)) + ")" for t in trailing)
    raise ValueError(f"{name} must have shape {want}, got shape {tuple(x.shape)}")


def _map_leading(func, x, n_in, out_trailing, dtype):
    """``func(block)`` on every chunk of the dask array ``x``, whose last ``n_in`` axes hold
    one item and are brought into one chunk; each call maps a block of shape
    ``lead + x.shape[-n_in:]`` to one of shape ``lead + out_trailing``."""
    da = _dask_array()
    lead = x.ndim - n_in
    if any(len(c) > 1 for c in x.chunks[lead:]):
        x = x.rechunk({axis: -1 for axis in range(lead, x.ndim)})
    lead_ind = tuple(f"l{i}" for i in range(lead))
    new_axes = {f"o{i}": size for i, size in enumerate(out_trailing)}
    out_ind = lead_ind + tuple(new_axes)
    return da.blockwise(func, out_ind, x, lead_ind + tuple(f"i{i}" for i in range(n_in)),
                        new_axes=new_axes, dtype=dtype, concatenate=True,
                        meta=np.empty((0,) * len(out_ind), dtype=dtype))


# -- forward and inverse kinematics, chunk by chunk ----------------------------------------

def _fk_block(robot, q):
    return robot.fk(q)


def fk(robot: Robot, q):
    r"""Forward kinematics of a dask array of joint vectors, chunk by chunk.

    :meth:`dqlab.robot.Robot.fk` on every chunk: :math:`X_{WT}(q)`, the pose of the tool
    (the flange without a tool) in the world frame.

    Parameters
    ----------
    robot : dqlab.robot.Robot
    q : dask.array.Array or array_like, shape (..., n)
        Joint vectors (radians, metres for prismatic joints), chunked along the leading
        axes in any way (the last axis is brought into one chunk). A numpy array is one
        chunk.

    Returns
    -------
    dask.array.Array, shape (..., 4, 4)
        Lazy; the leading chunks are those of ``q``. Values equal ``robot.fk`` of the whole
        batch.

    Raises
    ------
    ValueError
        If ``q`` does not end with the robot's number of joints. NaN or a prismatic joint
        beyond its limits raise when the chunk holding it is computed.
    ImportError
        Without dask (install the extra: ``pip install 'dqlab[scale]'``).

    Examples
    --------
    >>> import dask.array as da
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> q = np.random.default_rng(1).uniform(-np.pi, np.pi, (10, 6))
    >>> X = fk(robot, da.from_array(q, chunks=(4, 6)))
    >>> X.shape, X.chunks
    ((10, 4, 4), ((4, 4, 2), (4,), (4,)))
    >>> bool(np.array_equal(X.compute(scheduler="synchronous"), robot.fk(q)))
    True
    """
    q = _as_dask(q, "q")
    _check_trailing(q, "q", [(robot.n,)])
    return _map_leading(functools.partial(_fk_block, robot), q, 1, (4, 4), np.float64)


@dataclass
class IKArrays:
    """The arrays of an :class:`~dqlab.ik.result.IKResult` as lazy dask arrays.

    Every field is a view of one array of records per chunk, so computing several of them
    together (``dask.compute(result.solutions, result.valid)``) solves each chunk once.
    ``reason`` (text) is not carried: solve the few poses of interest again with
    :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>` to read it.

    Attributes
    ----------
    solutions : dask.array.Array, shape (..., k, n)
    valid : dask.array.Array of bool, shape (..., k)
    position_error, rotation_error : dask.array.Array, shape (..., k)
    flags : dict of str to dask.array.Array of bool, shape (...)
    """

    solutions: object
    valid: object
    position_error: object
    rotation_error: object
    flags: dict = field(default_factory=dict)

    @property
    def count(self):
        """Number of valid solutions per pose, dask array of int, shape (...)."""
        return self.valid.sum(axis=-1)


def _ik_block(robot, options, dtype, poses):
    result = ur(robot, poses, **options)
    out = np.empty(result.valid.shape[:-1], dtype=dtype)
    for name in ("solutions", "valid", "position_error", "rotation_error"):
        out[name] = getattr(result, name)
    for name, flag in result.flags.items():
        out["flag_" + name] = flag
    return out


def _probe_pose(robot, kind):
    """A pose of ``robot`` in the form ``kind`` (``(4, 4)`` or ``(8,)``), to check the
    arguments of a solver before the chunks are computed."""
    X = robot.fk(np.zeros(robot.n))
    if kind == (4, 4):
        return X
    from .dualquat import dual_quaternion_from_transform
    return dual_quaternion_from_transform(X)


def _check_ik_options(robot, kind, options):
    """Solve one pose with ``options`` (raising what ``dqlab.ik.ur`` raises for a wrong
    robot or option); ``q_ref`` must be one joint vector."""
    q_ref = options.get("q_ref")
    if q_ref is not None and np.shape(q_ref) != (6,):
        raise ValueError(f"q_ref must be one joint vector of shape (6,) here (the same "
                         f"reference for every pose), got shape {np.shape(q_ref)}")
    return ur(robot, _probe_pose(robot, kind), **options)


def ik_ur(robot: Robot, poses, **options) -> IKArrays:
    r"""Every closed-form UR solution of a dask array of poses, chunk by chunk.

    :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>` on every chunk of ``poses``; the arrays of its
    :class:`~dqlab.ik.result.IKResult` come back as dask arrays with the chunks of
    ``poses`` on the leading axes.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm (see :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>`).
    poses : dask.array.Array or array_like, shape (..., 4, 4) or (..., 8)
        Target poses as rigid transforms or unit dual quaternions, chunked along the leading
        axes (the trailing axes are brought into one chunk).
    **options
        Passed to :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>` (``tol``, ``tool``,
        ``singular_tol``, ``pose_tol``, ``residuals``, ``q_ref``); ``q_ref`` must be one
        joint vector, shape (6,).

    Returns
    -------
    IKArrays
        ``solutions`` (..., 8, 6), ``valid`` (..., 8), ``position_error`` and
        ``rotation_error`` (..., 8), ``flags`` (dict of (...) bool arrays) and ``count``
        (...), equal to the fields of ``dqlab.ik.ur(robot, poses, **options)``.

    Raises
    ------
    ValueError
        For a wrong shape of ``poses``, a robot that is not UR-shaped or a wrong option
        (checked at once, on one pose); a pose that is not rigid raises when its chunk is
        computed. Unreachable poses do not raise.
    ImportError
        Without dask (install the extra: ``pip install 'dqlab[scale]'``).

    Examples
    --------
    A regular pose, the thesis's test pose (every singularity at once) and a pose out of
    reach, in two chunks:

    >>> import dask
    >>> import dask.array as da
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> X = robot.fk(np.array([[0.3, -1.2, 1.1, -0.4, 0.9, 0.2],
    ...                        [0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0]]))
    >>> far = np.eye(4)
    >>> far[:3, 3] = [1.0, 0.0, 0.2]
    >>> poses = da.from_array(np.stack([X[0], X[1], far]), chunks=(2, 4, 4))
    >>> result = ik_ur(robot, poses)
    >>> count, singular = dask.compute(result.count, result.flags["wrist_singular"],
    ...                                scheduler="synchronous")
    >>> count, singular
    (array([8, 8, 0]), array([False,  True, False]))
    """
    poses = _as_dask(poses, "poses")
    kind = _check_trailing(poses, "poses", [(4, 4), (8,)])
    probe = _check_ik_options(robot, kind, options)
    k, n = probe.solutions.shape[-2:]
    dtype = np.dtype([("solutions", np.float64, (k, n)), ("valid", np.bool_, (k,)),
                      ("position_error", np.float64, (k,)),
                      ("rotation_error", np.float64, (k,))]
                     + [("flag_" + name, np.bool_) for name in probe.flags])
    records = _map_leading(functools.partial(_ik_block, robot, options, dtype), poses,
                           len(kind), (), dtype)
    return IKArrays(solutions=records["solutions"], valid=records["valid"],
                    position_error=records["position_error"],
                    rotation_error=records["rotation_error"],
                    flags={name: records["flag_" + name] for name in probe.flags})


# -- the dexterity of a pose -------------------------------------------------------------

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
    does (see :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>`).

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm.
    poses : array_like, shape (..., 4, 4) or (..., 8)
        Target poses (see :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>`).
    **options
        Passed to :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>`.

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
    result = ur(robot, poses, **options)
    w = np.zeros(result.valid.shape)
    if result.valid.any():
        w[result.valid] = manipulability(robot.jacobian(result.solutions[result.valid]))
    return result.count, w.max(axis=-1, initial=0.0)


def _dexterity_block(robot, options, dtype, poses):
    out = np.empty(poses.shape[:-2] if poses.shape[-1] == 4 else poses.shape[:-1], dtype)
    out["count"], out["manipulability"] = pose_dexterity(robot, poses, **options)
    return out


def dexterity(robot: Robot, poses, **options):
    r""":func:`pose_dexterity` of a dask array of poses, chunk by chunk.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm.
    poses : dask.array.Array or array_like, shape (..., 4, 4) or (..., 8)
        Chunked along the leading axes.
    **options
        Passed to :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>` (``q_ref`` must have shape (6,)).

    Returns
    -------
    count : dask.array.Array of int, shape (...)
    manipulability : dask.array.Array, shape (...)
        Lazy; computed together, each chunk is solved once.

    Raises
    ------
    ValueError
        As :func:`ik_ur`.
    ImportError
        Without dask (install the extra: ``pip install 'dqlab[scale]'``).

    Examples
    --------
    >>> import dask
    >>> import dask.array as da
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> q = np.random.default_rng(3).uniform(-np.pi, np.pi, (6, 6))
    >>> count, w = dexterity(robot, da.from_array(robot.fk(q), chunks=(4, 4, 4)))
    >>> count, w = dask.compute(count, w, scheduler="synchronous")
    >>> count_np, w_np = pose_dexterity(robot, robot.fk(q))
    >>> bool(np.array_equal(count, count_np) and np.array_equal(w, w_np))
    True
    """
    poses = _as_dask(poses, "poses")
    kind = _check_trailing(poses, "poses", [(4, 4), (8,)])
    _check_ik_options(robot, kind, options)
    dtype = np.dtype([("count", np.int64), ("manipulability", np.float64)])
    records = _map_leading(functools.partial(_dexterity_block, robot, options, dtype), poses,
                           len(kind), (), dtype)
    return records["count"], records["manipulability"]


# -- the reachability map ------------------------------------------------------------------

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
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"k must be an int >= 1, got {k!r}")
    s = np.arange(k) + 0.5
    r, rr = np.sqrt(s / k), np.sqrt(1.0 - s / k)
    alpha = 2.0 * np.pi * s / np.sqrt(2.0)
    beta = 2.0 * np.pi * s / 1.533751168755204288118041
    return np.stack([r * np.sin(alpha), r * np.cos(alpha), rr * np.sin(beta),
                     rr * np.cos(beta)], axis=-1)


@dataclass
class ReachabilityMap:
    r"""Statistics of a UR arm's reach and dexterity per tool position.

    Made by :func:`reachability_map` (dask) or :func:`reachability_statistics` (numpy)
    from the :math:`M \times K` samples :math:`X_{mk} = (R(q_k), p_m)`: every position
    :math:`p_m` with every orientation :math:`q_k`, each scored by :func:`pose_dexterity`
    (:math:`c_{mk}` branches, manipulability :math:`w_{mk}`).

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
    """

    positions: np.ndarray
    orientations: np.ndarray
    reachable: np.ndarray
    branches: np.ndarray
    median_manipulability: np.ndarray
    metadata: dict = field(default_factory=dict)

    _ARRAYS = ("positions", "orientations", "reachable", "branches", "median_manipulability")

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
        meta = {**self.metadata, **metadata}
        arrays = {name: getattr(self, name) for name in self._ARRAYS}
        for key, value in meta.items():
            value = np.asarray(value)
            if value.dtype.kind not in "biufU":
                raise ValueError(f"metadata {key!r} must be numbers or text, got {value.dtype}")
            arrays["meta_" + key] = value
        np.savez_compressed(path, **arrays)

    @classmethod
    def load(cls, path) -> "ReachabilityMap":
        """Read a map written by :meth:`save` (numbers and text only, no pickles)."""
        with np.load(path, allow_pickle=False) as data:
            arrays = {name: data[name] for name in cls._ARRAYS}
            meta = {key[5:]: data[key][()] if data[key].ndim == 0 else data[key]
                    for key in data.files if key.startswith("meta_")}
        meta = {key: value.item() if isinstance(value, np.generic) else value
                for key, value in meta.items()}
        return cls(**arrays, metadata=meta)


def _check_grid(positions, orientations):
    """``positions`` (..., 3) and ``orientations`` (K, 4), checked."""
    positions = as_float_array(positions, "positions", (3,))
    orientations = check_unit_quaternion(orientations, name="orientations")
    if orientations.ndim != 2 or len(orientations) == 0:
        raise ValueError(f"orientations must have shape (K, 4) with K >= 1, got shape "
                         f"{orientations.shape}")
    return positions, orientations


def _check_count(value, name):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name} must be an int >= 1, got {value!r}")
    return int(value)


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


_STATISTICS = np.dtype([("reachable", np.int64), ("branches", np.int64),
                        ("median_manipulability", np.float64)])


def _statistics_block(robot, R, block, options, positions):
    out = np.empty(len(positions), dtype=_STATISTICS)
    (out["reachable"], out["branches"],
     out["median_manipulability"]) = _statistics(robot, positions, R, block, options)
    return out


def reachability_statistics(robot: Robot, positions: ArrayLike, orientations: ArrayLike, *,
                            block: int = _BLOCK, **options) -> ReachabilityMap:
    r"""The reachability map with numpy, in this process (the reference of
    :func:`reachability_map`).

    Scores every pose :math:`X_{mk} = (R(q_k), p_m)` -- the tool at position :math:`p_m`
    with orientation :math:`q_k` -- by :func:`pose_dexterity` and reduces over the
    orientations: see :class:`ReachabilityMap`. The poses are built as 4x4 transforms with
    :func:`dqlab.quaternion.matrix_from_quaternion`, ``block`` of them per call of
    :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>`.

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
        Passed to :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>`.

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
    block = _check_count(block, "block")
    _check_ik_options(robot, (4, 4), options)
    R = matrix_from_quaternion(orientations)
    flat = positions.reshape(-1, 3)
    reachable, branches, median = _statistics(robot, flat, R, block, options)
    lead = positions.shape[:-1]
    return ReachabilityMap(positions=positions, orientations=orientations,
                           reachable=reachable.reshape(lead), branches=branches.reshape(lead),
                           median_manipulability=median.reshape(lead))


def _compute(scheduler, *arrays):
    """``dask.compute(*arrays)`` on ``scheduler``: None (the active one), a name, a
    ``distributed.Client`` or the address of a scheduler (connected for this call)."""
    import dask
    if isinstance(scheduler, str):
        if "://" in scheduler:
            distributed = _distributed()
            with distributed.Client(scheduler, set_as_default=False) as client:
                return dask.compute(*arrays, scheduler=client)
        if scheduler not in _SCHEDULER_NAMES:
            raise ValueError(f"scheduler must be None, one of {', '.join(_SCHEDULER_NAMES)}, "
                             f"a distributed.Client or an address such as "
                             f"'tcp://host:8786', got {scheduler!r}")
    return dask.compute(*arrays, scheduler=scheduler)


def reachability_map(robot: Robot, positions: ArrayLike, orientations: ArrayLike, *,
                     chunk: int | None = None, scheduler=None, block: int = _BLOCK,
                     **options) -> ReachabilityMap:
    r"""The reachability and dexterity map of a UR arm, computed by dask.

    For every tool position :math:`p_m` (``positions``, any grid) and orientation
    :math:`q_k` (``orientations``), the pose :math:`X_{mk} = (R(q_k), p_m)` is scored by
    :func:`pose_dexterity`: :math:`c_{mk}`, the number of valid inverse-kinematics
    branches of :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>` (0 to 8), and :math:`w_{mk}`, the
    largest manipulability :math:`\lvert\det J\rvert` over them (:math:`\mathrm m^3`, 0 when
    :math:`c_{mk} = 0`). Each position is then summarised over the :math:`K` orientations
    (:class:`ReachabilityMap`):

    .. math::

        \text{reachable}_m = \#\{k : c_{mk} > 0\},\qquad
        \text{branches}_m = \sum_k c_{mk},\qquad
        \tilde w_m = \operatorname{median}\{w_{mk} : c_{mk} > 0\},

    whose ratios to :math:`K` are the fraction of orientations reachable and the mean
    branch count. The positions are cut into chunks of ``chunk`` positions; one task scores
    the ``chunk`` :math:`\times K` samples of a chunk (with
    :func:`reachability_statistics`'s numpy code) and returns only their statistics, so
    the samples never travel. The result equals :func:`reachability_statistics` number for
    number.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm.
    positions : array_like, shape (..., 3)
        Tool positions in the world frame (metres).
    orientations : array_like, shape (K, 4)
        Tool orientations, unit quaternions.
    chunk : int, optional
        Positions per task; default :math:`\max(1, \lfloor 2^{16}/K \rfloor)`, about
        65 000 samples (a second or two of work).
    scheduler : None, str or distributed.Client, optional
        Where the tasks run. None: the active dask scheduler (the ``distributed.Client``
        created last, if any; otherwise dask's default for arrays, threads). A name
        (``"synchronous"``, ``"threads"``, ``"processes"``). A ``distributed.Client``, for
        example of a ``distributed.LocalCluster``. Or the address of a running scheduler,
        ``"tcp://host:8786"``: a client connects for this call and disconnects after (the
        cluster keeps running).
    block : int
        Poses per numpy call inside a task.
    **options
        Passed to :func:`dqlab.ik.ur <dqlab.ik.ur_closed_form.ur>`.

    Returns
    -------
    ReachabilityMap

    Raises
    ------
    ValueError
        Wrong shapes or values of the arguments (checked before anything is computed).
    ImportError
        Without dask, or without ``distributed`` for an address (install the extra:
        ``pip install 'dqlab[scale]'``).

    Notes
    -----
    The work is numpy code on many temporaries of a few hundred kilobytes. dask's worker
    processes start by default with ``MALLOC_TRIM_THRESHOLD_=65536``, which makes glibc
    return each of them to the system and fault it in again, and measurably slowed this code
    (by about a third, in CPU time, in ``benchmarks/bench_reachability.py``); the benchmark
    starts its workers with ``dask.config.set({"distributed.nanny.pre-spawn-environ":
    {"MALLOC_TRIM_THRESHOLD_": None}})``. Threads (``scheduler="threads"``) give little
    here: the many small numpy operations hold the GIL between them.

    Examples
    --------
    Two positions of chapter 11's board, one out of reach, 16 orientations:

    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> robot, quats = ur3(), super_fibonacci_quaternions(16)
    >>> grid = [[0.0, -0.35, 0.25], [0.0, -0.35, 0.45], [0.9, 0.0, 0.2]]
    >>> rmap = reachability_map(robot, grid, quats, chunk=2, scheduler="synchronous")
    >>> rmap.fraction, rmap.mean_count
    (array([1.    , 0.9375, 0.    ]), array([7.25, 4.5 , 0.  ]))
    >>> reference = reachability_statistics(robot, grid, quats)
    >>> bool(np.array_equal(rmap.median_manipulability, reference.median_manipulability,
    ...                     equal_nan=True))
    True

    On a cluster, the same call with ``scheduler="tcp://scheduler-host:8786"``, or with a
    client: ``with distributed.Client(distributed.LocalCluster(n_workers=2)) as client:
    reachability_map(robot, grid, quats, scheduler=client)``.
    """
    da = _dask_array()
    positions, orientations = _check_grid(positions, orientations)
    block = _check_count(block, "block")
    k = len(orientations)
    chunk = max(1, _SAMPLES_PER_TASK // k) if chunk is None else _check_count(chunk, "chunk")
    if not (scheduler is None or isinstance(scheduler, str) or hasattr(scheduler, "get")
            or callable(scheduler)):
        raise ValueError(f"scheduler must be None, a name, a distributed.Client or an "
                         f"address, got {scheduler!r}")
    _check_ik_options(robot, (4, 4), options)
    R = matrix_from_quaternion(orientations)
    flat = positions.reshape(-1, 3)
    records = _map_leading(functools.partial(_statistics_block, robot, R, block, options),
                           da.from_array(flat, chunks=(chunk, 3)), 1, (), _STATISTICS)
    (out,) = _compute(scheduler, records)
    lead = positions.shape[:-1]
    return ReachabilityMap(
        positions=positions, orientations=orientations,
        reachable=out["reachable"].reshape(lead), branches=out["branches"].reshape(lead),
        median_manipulability=out["median_manipulability"].reshape(lead))

