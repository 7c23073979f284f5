r"""Choosing among inverse-kinematics solutions: the one nearest a configuration.

A revolute joint at :math:`\theta` is also at :math:`\theta + 2\pi m` for every integer
:math:`m`, and a joint that turns :math:`\pm 360` degrees (a UR's) can be sent either. The
solvers of :mod:`dqlab.ik` return angles wrapped to :math:`(-\pi, \pi]`; what a robot at
:math:`q_{ref}` should be sent is, among all valid rows and all their :math:`2\pi`-equivalents
*within the joint limits*, the joint vector nearest :math:`q_{ref}`:

.. math::

    q^\ast = \operatorname*{arg\,min}_{\text{valid rows } \theta,\ m \in \mathbb Z^n,\
             lo \le \theta + 2\pi m \le hi} \lVert \theta + 2\pi m - q_{ref} \rVert .

The joints are independent, so each joint takes its own nearest equivalent. The one nearest
:math:`q_{ref,i}` is :math:`u_i = q_{ref,i} + \operatorname{wrap}(\theta_i - q_{ref,i})`;
when it lies below :math:`lo_i`, the nearest within the limits is the smallest equivalent
above :math:`lo_i` (the distance grows with every further turn), when above :math:`hi_i` the
largest below :math:`hi_i`; when that one is not within the limits either, no equivalent is
and the row cannot be sent. The row with the smallest distance wins.
:func:`closest_solution` does this for one target or a batch, joint by joint on arrays;
:func:`equivalent_solutions` lists every equivalent within the limits (for teaching and for
tests).
"""

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._checks import as_float_array, is_boolean, real_array, short_repr
from ..rotations import wrap_angle

__all__ = ["closest_solution", "equivalent_solutions", "check_joint_limits",
           "check_reference", "MAX_REFERENCE"]

_TWO_PI = 2.0 * math.pi
_MAX_EQUIVALENT_JOINTS = 12

#: The largest joint value (radians, some 160,000 turns) a reference configuration may hold:
#: a joint value v is stored to about :math:`10^{-16} |v|`, so the :math:`2\pi`-equivalents
#: near a larger one would miss the solution by more than :math:`10^{-10}` rad.
MAX_REFERENCE = 1e6


def check_joint_limits(limits: ArrayLike, n: int, name: str = "limits"
                       ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Joint limits, checked: the lowest and highest value of each of ``n`` joints.

    Parameters
    ----------
    limits : array_like, shape (2,) or (n, 2)
        ``(lo, hi)`` for every joint, or one row per joint; ``-inf`` / ``inf`` for a joint
        without a lower / upper limit.
    n : int
        Number of joints.
    name : str
        Name of the argument in error messages.

    Returns
    -------
    lo, hi : ndarray, shape (n,)

    Raises
    ------
    ValueError
        Naming ``name`` and the joint: a wrong shape, a NaN, :math:`lo > hi`, or an interval
        that lies beyond :data:`MAX_REFERENCE` (:math:`10^6` rad; such as
        :math:`lo = hi = \pm\infty`, which holds no joint value).

    Examples
    --------
    >>> check_joint_limits([-np.pi, np.pi], 2)
    (array([-3.14159265, -3.14159265]), array([3.14159265, 3.14159265]))
    >>> check_joint_limits([[0.0, 1.0], [np.inf, np.inf]], 2)       # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: limits: joint 2 has [inf, inf], an interval beyond 1e+06 rad, where ...
    """
    lim = real_array(limits, name)
    if lim.shape not in ((2,), (n, 2)):
        raise ValueError(f"{name} must have shape (2,) or ({n}, 2), got {lim.shape}")
    lo, hi = (lim[:, 0], lim[:, 1]) if lim.ndim == 2 else (np.full(n, lim[0]),
                                                            np.full(n, lim[1]))
    # NaN fails every comparison; an interval beyond MAX_REFERENCE would give joints near it
    bad = ~((lo <= hi) & (lo <= MAX_REFERENCE) & (hi >= -MAX_REFERENCE))
    if bad.any():
        j = int(np.argmax(bad))
        why = ("a NaN" if np.isnan([lo[j], hi[j]]).any() else
               "lo > hi: rows are (lo, hi)" if lo[j] > hi[j] else
               f"an interval beyond {MAX_REFERENCE:.0e} rad, where joint values are not "
               f"accurate to 1e-10 rad")
        raise ValueError(f"{name}: joint {j + 1} has [{lo[j]:.6g}, {hi[j]:.6g}], {why}")
    return lo.astype(float), hi.astype(float)


def check_reference(q_ref: ArrayLike, n: int, name: str = "q_ref") -> NDArray[np.float64]:
    r"""A reference configuration, checked: joint vectors near which a solution is chosen.

    Parameters
    ----------
    q_ref : array_like, shape (n,) or (..., n)
        Joint values (radians).
    n : int
        Number of joints.
    name : str
        Name of the argument in error messages.

    Returns
    -------
    ndarray, shape (..., n)

    Raises
    ------
    ValueError
        Naming ``name``: a wrong shape, a NaN or infinity, or a joint value beyond
        :data:`MAX_REFERENCE` (:math:`10^6` rad) in size, near which the joint values are
        not accurate to :math:`10^{-10}` rad.

    Examples
    --------
    >>> check_reference([0.0, 1e10], 2)                  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: q_ref: joint 2 = 1e+10 rad is beyond 1e+06 rad (some 160,000 turns): ...
    """
    q = as_float_array(q_ref, name, (n,))
    big = np.abs(q) > MAX_REFERENCE
    if big.any():
        index = tuple(np.argwhere(big)[0])
        j, value = int(index[-1]), float(q[index])
        raise ValueError(f"{name}: joint {j + 1} = {value:.6g} rad is beyond "
                         f"{MAX_REFERENCE:.0e} rad (some 160,000 turns): the joint values "
                         f"near it are not accurate to 1e-10 rad")
    return q


def _joint_limits(limits, n):
    """``(lo, hi)`` of shape (n,) each (infinite for an unlimited joint), or ``None``."""
    return None if limits is None else check_joint_limits(limits, n)


def _nearest_equivalent(theta, ref, lo, hi):
    r"""The :math:`2\pi`-equivalent of ``theta`` nearest ``ref`` within ``[lo, hi]`` and
    whether one exists (arrays of one shape; ``lo``, ``hi`` broadcast)."""
    u = ref + wrap_angle(theta - ref)
    below, above = u < lo, u > hi
    if below.any():
        u = np.where(below, u + _TWO_PI * np.ceil((lo - u) / _TWO_PI), u)
    if above.any():
        u = np.where(above, u - _TWO_PI * np.ceil((u - hi) / _TWO_PI), u)
    if below.any() or above.any():
        return u, (u >= lo) & (u <= hi)
    return u, None


def closest_solution(result, q_ref: ArrayLike, limits: ArrayLike | None = None, *,
                     wrapped: bool = False, weights: ArrayLike | None = None
                     ) -> NDArray[np.float64]:
    r"""The valid solution nearest ``q_ref``, as the :math:`2\pi`-equivalent nearest it within
    the joint limits.

    Among every valid row of ``result`` (and of ``result.more``, the solutions beyond its
    rows) and every :math:`2\pi`-equivalent of it within ``limits``, the joint vector with
    the smallest Euclidean distance to ``q_ref`` (see the module docstring): the vector a
    robot standing at ``q_ref`` should be sent, so that no joint turns by more than half a
    turn when a shorter way exists within its limits.

    Parameters
    ----------
    result : IKResult
        Solutions ``(..., k, n)`` and their validity ``(..., k)``, from any solver of
        :mod:`dqlab.ik`.
    q_ref : array_like, shape (n,) or (..., n)
        The configuration to be near (radians), for all targets or one per target.
    limits : array_like, shape (2,) or (n, 2), optional
        Lowest and highest value of each joint (for example ``robot.limits``; ``inf`` for a
        joint without limit). Default: no limits.
    wrapped : bool
        Return the chosen row as the solver gives it (angles in :math:`(-\pi, \pi]`), not its
        equivalent nearest ``q_ref`` (what :meth:`dqlab.ik.result.IKResult.best` returns;
        only without ``limits``).
    weights : array_like, shape (n,), optional
        The distance is :math:`\sum_j w_j (q_j - q_{ref,j})^2` (default: every
        :math:`w_j = 1`). Larger weights on the big joints (shoulder, elbow) make a
        solution that moves the wrist more and the arm less the nearer one, for example
        ``weights=(10, 10, 5, 1, 1, 1)``. Positive and finite.

    Returns
    -------
    ndarray, shape (..., n)

    Raises
    ------
    ValueError
        If some target has no valid solution, or no valid solution has an equivalent within
        the limits (the message says which target), or ``q_ref`` or ``limits`` are not
        numbers of the right shape.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> from dqlab.ik import ur
    >>> robot = ur3()
    >>> q = np.array([3.0, -1.0, 1.0, -2.0, 1.0, 6.0])      # joint 6 beyond pi
    >>> closest_solution(ur(robot, robot.fk(q)), q).round(6)
    array([ 3., -1.,  1., -2.,  1.,  6.])

    With joint 3 limited to :math:`[-\pi, 0]` the nearest solution has the elbow on the
    other side (a different row), not the row nearest ``q`` moved into the limits:

    >>> limits = robot.limits.copy(); limits[2] = [-np.pi, 0.0]
    >>> closest_solution(ur(robot, robot.fk(q)), q, limits)[2] < 0
    np.True_
    """
    if not (hasattr(result, "solutions") and hasattr(result, "valid")):
        raise TypeError(f"result must be an IKResult (a solver's answer), got "
                        f"{short_repr(result)}")
    if not is_boolean(wrapped):
        raise TypeError(f"wrapped must be True or False, got {short_repr(wrapped)}")
    solutions = np.asarray(result.solutions)
    valid = np.asarray(result.valid)
    more = getattr(result, "more", None)            # the solutions beyond the rows, if any
    if more is not None and more.valid.any():
        solutions = np.concatenate([solutions, more.solutions], axis=-2)
        valid = np.concatenate([valid, more.valid], axis=-1)
    k, n = solutions.shape[-2:]
    q_ref = check_reference(q_ref, n)
    bounds = _joint_limits(limits, n)
    weights = _weights(weights, n)
    if wrapped and bounds is not None:
        raise ValueError("wrapped=True returns a row as the solver gives it, which ignores "
                         "limits; give one or the other")
    if not valid.any(axis=-1).all():
        raise ValueError("some targets have no valid solution; check result.reason")
    batch = np.broadcast_shapes(valid.shape[:-1], q_ref.shape[:-1])
    if not batch:                          # one target: on Python floats
        return _closest_one(solutions, valid, q_ref, bounds, wrapped, weights)
    rows = np.broadcast_to(solutions, batch + (k, n)).reshape(-1, k, n)
    index = _nearest_rows(rows, np.broadcast_to(valid, batch + (k,)).reshape(-1, k),
                          np.broadcast_to(q_ref, batch + (n,)).reshape(-1, n), bounds,
                          weights)
    if np.any(index < 0):
        where = np.unravel_index(int(np.argmin(index)), batch) if batch else ()
        target = f"target {tuple(int(i) for i in where)}" if batch else "the target"
        lo, hi = bounds
        raise ValueError(f"{target} has no valid solution within the joint limits "
                         f"{np.stack([lo, hi], axis=-1).tolist()}")
    columns, targets = rows.transpose(2, 1, 0), np.arange(len(rows))   # the solvers' layout
    chosen = np.stack([columns[j][index, targets] for j in range(n)], axis=-1)
    chosen = chosen.reshape(batch + (n,))
    if wrapped:
        return chosen
    ref = np.broadcast_to(q_ref, chosen.shape)
    if bounds is None:
        return ref + wrap_angle(chosen - ref)
    return _nearest_equivalent(chosen, ref, *bounds)[0]


def _weights(weights, n):
    """The joint weights of a distance (n,), checked, or None (all 1)."""
    if weights is None:
        return None
    w = as_float_array(weights, "weights")
    if w.shape != (n,):
        raise ValueError(f"weights must have shape ({n},), one per joint, got {w.shape}")
    if not (w > 0.0).all():
        raise ValueError(f"weights must be positive, got {w.tolist()}")
    return w


def _closest_one(rows, valid, q_ref, bounds, wrapped, weights=None):
    """:func:`closest_solution` of one target: rows (k, n), valid (k,), q_ref (n,), with
    :func:`_nearest_equivalent` on the whole (k, n) block at once (the chunked loop of a
    batch would cost more than the work)."""
    if bounds is None:
        u, reach = q_ref + wrap_angle(rows - q_ref), valid
    else:
        u, inside = _nearest_equivalent(rows, q_ref, *bounds)
        reach = valid if inside is None else valid & inside.all(axis=-1)
    squares = np.square(u - q_ref) if weights is None else weights * np.square(u - q_ref)
    distance = np.where(reach, squares.sum(axis=-1), np.inf)
    best = int(np.argmin(distance))
    if not reach[best]:
        raise ValueError(f"the target has no valid solution within the joint limits "
                         f"{np.stack(bounds, axis=-1).tolist()}")
    return rows[best].copy() if wrapped else u[best]


_CHUNK = 4096      # targets per block: a block's (k, 4096) temporaries stay in the cache


def _nearest_rows(rows, valid, q_ref, bounds, weights=None):
    r"""For each target (rows ``(N, k, n)``, valid ``(N, k)``, q_ref ``(N, n)``) the index of
    the row whose nearest equivalent within ``bounds`` is nearest ``q_ref``, or -1.

    The arrays are read joint by joint as ``(k, N)`` blocks, the layout in which the
    solvers of :mod:`dqlab.ik` store a batch, and in chunks of :data:`_CHUNK` targets,
    with the temporaries written over (the operations of :func:`_nearest_equivalent`, the
    wrap written out as :math:`d - 2\pi\operatorname{rint}(d / 2\pi)`).
    """
    N, k, n = rows.shape
    columns = rows.transpose(2, 1, 0)                         # (n, k, N), joint-major
    refs = np.ascontiguousarray(q_ref.T)                      # (n, N)
    ok = np.ascontiguousarray(valid.T)                        # (k, N)
    index = np.empty(N, dtype=np.intp)
    for a in range(0, N, _CHUNK):
        b = min(a + _CHUNK, N)
        m = b - a
        dist = np.zeros((k, m))
        d, w = np.empty((k, m)), np.empty((k, m))
        reach = ok[:, a:b].copy()
        for j in range(n):
            ref = refs[j, a:b]
            np.subtract(columns[j, :, a:b], ref, out=d)
            np.multiply(d, 1.0 / _TWO_PI, out=w)
            np.rint(w, out=w)
            w *= _TWO_PI
            d -= w                                            # wrap(theta - ref)
            if bounds is not None:
                lo, hi = bounds[0][j], bounds[1][j]
                d += ref                                      # u, the nearest equivalent
                below, above = d < lo, d > hi
                if below.any() or above.any():
                    u, inside = _nearest_equivalent(d, ref, lo, hi)
                    if inside is not None:   # None: within the limits after all (rounding)
                        reach &= inside
                    np.copyto(d, u)
                d -= ref
            np.multiply(d, d, out=w)
            if weights is not None:
                w *= weights[j]
            dist += w
        dist[~reach] = np.inf
        best = dist.argmin(axis=0)
        index[a:b] = np.where(np.isfinite(dist[best, np.arange(m)]), best, -1)
    return index


def equivalent_solutions(q: ArrayLike, limits: ArrayLike = (-2 * np.pi, 2 * np.pi)
                         ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    r"""All :math:`2\pi`-equivalents of joint vectors within the joint limits.

    A UR joint turns :math:`\pm 360` degrees, so each angle in :math:`(-\pi, \pi]` has one
    more equivalent, :math:`q_i - 2\pi\operatorname{sgn} q_i`, and a joint vector up to
    :math:`2^6 = 64`.

    Parameters
    ----------
    q : array_like, shape (..., n)
        Joint vectors (radians).
    limits : array_like, shape (2,) or (n, 2)
        Lowest and highest joint value, for all joints or per joint (for example
        ``robot.limits``). Each joint may have at most two equivalents within the limits
        (a span of at most :math:`4\pi`).

    Returns
    -------
    candidates : ndarray, shape (..., 2**n, n)
        Candidate ``m`` shifts joint ``i`` by :math:`\pm 2\pi` when bit ``i`` of ``m`` is
        set (towards zero); candidate 0 is ``q`` itself.
    within : ndarray of bool, shape (..., 2**n)
        Which candidates are within the limits.

    Examples
    --------
    >>> import numpy as np
    >>> cands, ok = equivalent_solutions([0.5, -3.0, 0.0, 1.0, 2.0, -1.0])
    >>> cands.shape, int(ok.sum())
    ((64, 6), 64)
    >>> cands[1].round(4)
    array([-5.7832, -3.    ,  0.    ,  1.    ,  2.    , -1.    ])
    """
    q = as_float_array(q, "q")
    if q.ndim == 0:
        raise ValueError("q must have shape (..., n), a joint vector or a batch of them")
    n = q.shape[-1]
    if n > _MAX_EQUIVALENT_JOINTS:
        raise ValueError(f"equivalent_solutions lists 2**n candidates: at most "
                         f"{_MAX_EQUIVALENT_JOINTS} joints, got {n}")
    rows = real_array(limits, "limits").shape
    if len(rows) == 2 and rows[0] != n:
        raise ValueError(f"q has {n} joints but limits has {rows[0]} rows: one (lo, hi) per "
                         f"joint, or a single (lo, hi) for all")
    lo, hi = check_joint_limits(limits, n)
    wide = np.flatnonzero(hi - lo > 4 * np.pi + 1e-12)
    if wide.size:
        j = int(wide[0])
        raise ValueError(f"limits: equivalent_solutions handles joint ranges of at most 4 pi, "
                         f"joint {j + 1} has [{lo[j]:.6g}, {hi[j]:.6g}]")
    bits = (np.arange(2 ** n)[:, None] >> np.arange(n)) & 1          # (2**n, n)
    shift = np.where(q >= 0, -2 * np.pi, 2 * np.pi)[..., None, :]
    cands = q[..., None, :] + bits * shift
    within = np.all((cands >= lo) & (cands <= hi), axis=-1)
    return cands, within
