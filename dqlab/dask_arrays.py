r"""Beyond one machine: dqlab's batch functions on dask arrays, chunk by chunk.

Every batch function of dqlab works on the leading axes of its arrays, pose by pose, with
no coupling between poses. That is exactly what `dask.array
<https://docs.dask.org/en/stable/array.html>`_ distributes: an array cut into chunks along
its leading (batch) axes, one task per chunk. The functions here take dask arrays chunked
that way, call the unchanged numpy function on each chunk (``dask.array.blockwise``, the
general form of ``dask.array.map_blocks``) and return lazy dask arrays -- hence the
``_dask`` in their names:

- :func:`fk_dask` is :meth:`dqlab.robot.Robot.fk`, :func:`ik_ur_dask` is
  :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` and :func:`dexterity_dask` is
  :func:`dqlab.reachability.pose_dexterity`, chunk by chunk, and their results are those
  of the numpy call on the whole batch, number for number;
- :func:`reachability_map` runs :func:`dqlab.reachability.reachability_statistics` on
  chunks of a grid of tool positions and gathers the statistics into one
  :class:`~dqlab.reachability.ReachabilityMap`, equal to the numpy map number for number
  (chapter 11 plots a map of :math:`10^7` samples made by
  ``benchmarks/bench_reachability.py``);
- nothing here schedules anything: the chunks run on whatever dask scheduler is asked for
  or active -- the synchronous one (examples, debugging), threads, processes, a
  ``distributed.LocalCluster`` on one machine, or a cluster whose scheduler listens at an
  address such as ``"tcp://scheduler-host:8786"``, with the same code.

dask is an optional dependency (the extra ``scale``: ``pip install 'dqlab[scale]'``). This
module imports numpy alone; dask is imported when a function that needs it is called, and
its absence is reported with the command that installs it. The map itself, and the numpy
functions it is made of, are in :mod:`dqlab.reachability`.
"""

import functools
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ._checks import as_float_array, check_instance, check_scalar
from .ik import ur
from .reachability import (
    BLOCK,
    ReachabilityMap,
    check_ik_options,
    pose_dexterity,
    reachability_statistics,
)
from .robot import Robot

__all__ = ["fk_dask", "ik_ur_dask", "IKArrays", "dexterity_dask", "reachability_map"]

#: The command that installs what this module needs, quoted in its error messages.
INSTALL = "pip install 'dqlab[scale]'"

_SAMPLES_PER_TASK = 2 ** 16       # default work of one task of reachability_map (~1 s)
_SCHEDULER_NAMES = ("synchronous", "sync", "single-threaded", "threads", "threading",
                    "processes", "multiprocessing", "distributed", "dask.distributed")


def _dask_array():
    """``dask.array``, or an ImportError that says how to install it."""
    try:
        import dask.array as da
    except ImportError:
        raise ImportError(f"dqlab.dask_arrays needs dask to work on dask arrays: install the "
                          f"extra with {INSTALL} (or pip install 'dask[array]' distributed)"
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


def fk_dask(robot: Robot, q):
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
    >>> X = fk_dask(robot, da.from_array(q, chunks=(4, 6)))
    >>> X.shape, X.chunks
    ((10, 4, 4), ((4, 4, 2), (4,), (4,)))
    >>> bool(np.array_equal(X.compute(scheduler="synchronous"), robot.fk(q)))
    True
    """
    check_instance(robot, Robot, "robot")
    q = _as_dask(q, "q")
    _check_trailing(q, "q", [(robot.n,)])
    return _map_leading(functools.partial(_fk_block, robot), q, 1, (4, 4), np.float64)


@dataclass
class IKArrays:
    """The arrays of an :class:`~dqlab.ik.result.IKResult` as lazy dask arrays.

    Every field is a view of one array of records per chunk, so computing several of them
    together (``dask.compute(result.solutions, result.valid)``) solves each chunk once.
    ``reason`` (text) is not carried: solve the few poses of interest again with
    :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` to read it.

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
    try:
        result = ur(robot, poses, **options)
    except (ValueError, TypeError) as exc:     # the solver calls its argument "target"
        raise type(exc)(f"poses: {exc}") from None
    out = np.empty(result.valid.shape[:-1], dtype=dtype)
    for name in ("solutions", "valid", "position_error", "rotation_error"):
        out[name] = getattr(result, name)
    for name, flag in result.flags.items():
        out["flag_" + name] = flag
    return out


def ik_ur_dask(robot: Robot, poses, **options) -> IKArrays:
    r"""Every closed-form UR solution of a dask array of poses, chunk by chunk.

    :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` on every chunk of ``poses``; the arrays of its
    :class:`~dqlab.ik.result.IKResult` come back as dask arrays with the chunks of
    ``poses`` on the leading axes.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm (see :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`).
    poses : dask.array.Array or array_like, shape (..., 4, 4) or (..., 8)
        Target poses as rigid transforms or unit dual quaternions, chunked along the leading
        axes (the trailing axes are brought into one chunk).
    **options
        Passed to :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` (``tol``, ``tool``,
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
    >>> result = ik_ur_dask(robot, poses)
    >>> count, singular = dask.compute(result.count, result.flags["wrist_singular"],
    ...                                scheduler="synchronous")
    >>> count, singular
    (array([8, 8, 0]), array([False,  True, False]))
    """
    probe = check_ik_options(robot, options, (4, 4))
    poses = _as_dask(poses, "poses")
    kind = _check_trailing(poses, "poses", [(4, 4), (8,)])
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
def _dexterity_block(robot, options, dtype, poses):
    out = np.empty(poses.shape[:-2] if poses.shape[-1] == 4 else poses.shape[:-1], dtype)
    out["count"], out["manipulability"] = pose_dexterity(robot, poses, **options)
    return out


def dexterity_dask(robot: Robot, poses, **options):
    r""":func:`dqlab.reachability.pose_dexterity` of a dask array of poses, chunk by chunk.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm.
    poses : dask.array.Array or array_like, shape (..., 4, 4) or (..., 8)
        Chunked along the leading axes.
    **options
        Passed to :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` (``q_ref`` must have shape (6,)).

    Returns
    -------
    count : dask.array.Array of int, shape (...)
    manipulability : dask.array.Array, shape (...)
        Lazy; computed together, each chunk is solved once.

    Raises
    ------
    ValueError
        As :func:`ik_ur_dask`.
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
    >>> count, w = dexterity_dask(robot, da.from_array(robot.fk(q), chunks=(4, 4, 4)))
    >>> count, w = dask.compute(count, w, scheduler="synchronous")
    >>> from dqlab.reachability import pose_dexterity
    >>> count_np, w_np = pose_dexterity(robot, robot.fk(q))
    >>> bool(np.array_equal(count, count_np) and np.array_equal(w, w_np))
    True
    """
    check_ik_options(robot, options)
    poses = _as_dask(poses, "poses")
    kind = _check_trailing(poses, "poses", [(4, 4), (8,)])
    dtype = np.dtype([("count", np.int64), ("manipulability", np.float64)])
    records = _map_leading(functools.partial(_dexterity_block, robot, options, dtype), poses,
                           len(kind), (), dtype)
    return records["count"], records["manipulability"]


# -- the reachability map ------------------------------------------------------------------
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
                     chunk: int | None = None, scheduler=None, block: int = BLOCK,
                     **options) -> ReachabilityMap:
    r"""The reachability and dexterity map of a UR arm, computed by dask.

    For every tool position :math:`p_m` (``positions``, any grid) and orientation
    :math:`q_k` (``orientations``), the pose :math:`X_{mk} = (R(q_k), p_m)` is scored by
    :func:`~dqlab.reachability.pose_dexterity`: :math:`c_{mk}`, the number of valid
    inverse-kinematics branches of :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>` (0 to 8),
    and :math:`w_{mk}`, the largest manipulability :math:`\lvert\det J\rvert` over them
    (:math:`\mathrm m^3`, 0 when :math:`c_{mk} = 0`). Each position is then summarised over
    the :math:`K` orientations (:class:`~dqlab.reachability.ReachabilityMap`):

    .. math::

        \text{reachable}_m = \#\{k : c_{mk} > 0\},\qquad
        \text{branches}_m = \sum_k c_{mk},\qquad
        \tilde w_m = \operatorname{median}\{w_{mk} : c_{mk} > 0\},

    whose ratios to :math:`K` are the fraction of orientations reachable and the mean
    branch count. The positions are cut into chunks of ``chunk`` positions; one task scores
    the ``chunk`` :math:`\times K` samples of a chunk with
    :func:`~dqlab.reachability.reachability_statistics` (the numpy code) and returns only
    their statistics, so the samples never travel. The result equals
    :func:`~dqlab.reachability.reachability_statistics` of the whole grid number for number.

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
        Passed to :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`.

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
    >>> from dqlab.reachability import reachability_statistics, super_fibonacci_quaternions
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
    positions = as_float_array(positions, "positions", (3,))
    # the numpy reference checks the robot, the orientations, block and the options
    orientations = reachability_statistics(robot, np.zeros((0, 3)), orientations, block=block,
                                           **options).orientations
    k = len(orientations)
    chunk = (max(1, _SAMPLES_PER_TASK // k) if chunk is None
             else check_scalar(chunk, "chunk", minimum=1, integer=True))
    if not (scheduler is None or isinstance(scheduler, str) or hasattr(scheduler, "get")
            or callable(scheduler)):
        raise ValueError(f"scheduler must be None, a name, a distributed.Client or an "
                         f"address, got {scheduler!r}")
    flat = positions.reshape(-1, 3)
    chunk = min(chunk, max(len(flat), 1))           # a chunk beyond the grid: the whole grid
    records = _map_leading(functools.partial(_statistics_block, robot, orientations, block,
                                             options),
                           da.from_array(flat, chunks=(chunk, 3)), 1, (), _STATISTICS)
    (out,) = _compute(scheduler, records)
    lead = positions.shape[:-1]
    return ReachabilityMap(
        positions=positions, orientations=orientations,
        reachable=out["reachable"].reshape(lead), branches=out["branches"].reshape(lead),
        median_manipulability=out["median_manipulability"].reshape(lead))


_STATISTICS = np.dtype([("reachable", np.int64), ("branches", np.int64),
                        ("median_manipulability", np.float64)])


def _statistics_block(robot, orientations, block, options, positions):
    """:func:`dqlab.reachability.reachability_statistics` of one chunk of positions, as an
    array of records (one task's whole result)."""
    rmap = reachability_statistics(robot, positions, orientations, block=block, **options)
    out = np.empty(len(positions), dtype=_STATISTICS)
    out["reachable"] = rmap.reachable
    out["branches"] = rmap.branches
    out["median_manipulability"] = rmap.median_manipulability
    return out
