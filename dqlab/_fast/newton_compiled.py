r"""The Newton steps of :mod:`dqlab.ik.ur_calibrated`, compiled (optional: needs numba).

:func:`newton` does what ``dqlab.ik.ur_calibrated._newton`` does on numpy arrays, in
compiled code, eight branches at a time: forward kinematics of the calibrated chain, the
residual :math:`e = (p^\ast - p,\ \tfrac12 (R^\ast R^\mathsf{T} - R R^{\ast\mathsf{T}})^\vee)`,
the Jacobian at the TCP and the damped step
:math:`(J^\mathsf{T} J + \lambda I)^{-1} J^\mathsf{T} e` by Cholesky, with the same stop,
give-up and shortening rules and the same frames layout as
``calibrated_entries.EntryChain``. The steps
themselves are straight-line code over the eight branches (``dqlab._fast.newton_lanes``,
written by ``tools/generate_newton_lanes.py``), which the compiler turns into vector
instructions; a branch that has stopped takes steps of zero while the others go on. It is
tested equal to the numpy path, which stays the one the module's docstring describes and the
one used where numba is not installed (``pip install dqlab[fast]`` installs it; the
in-browser chapters run without it).

:func:`unique` and :func:`are_new` are ``_Polished.unique`` and ``_Polished.are_new`` of
that module, compiled; :func:`one_pose` is its ``_one_pose``, the closed form included,
:func:`accept` its ``_accept`` (which restarts replace a row), :func:`nearness` its
``_nearness`` (how near a singularity of the exact arm each row is: which valid rows
``_polish`` steps further, which are flagged near singular), :func:`gram` the
:math:`J^\mathsf{T} J` of its ``_near_singular`` and :func:`smallest` that function's test
and direction by inverse iteration wherever they are certain (``eigh`` answers elsewhere,
and is what the numpy path uses). :func:`exact_one_pose` is the nearest exact
arm's closed form of one pose that the one-pose path starts from: the loop of
``dqlab._fast.ur_engine.solve_single`` over the steps of ``dqlab.ik.ur_steps``, written out on
floats (tested equal to it bit for bit), with what the closed form's batch path adds (a
wrist family's member near the wrist singularity, chosen by the reference's theta6 and
checked by forward kinematics; the clipping inside the shoulder cylinder; the reason where
no row is valid; tested equal to it to the rounding), and :func:`exact_poses` the same for
a batch of poses, which the batch path and the wrist family's starts come from (a wrist
centre far beyond reach goes to the closed form's own batch path), :func:`exact_fk` that
arm's forward kinematics; :func:`deflated` the deflated Newton steps of its ``_deflate``,
and :func:`repairs` its steps 4 (``_repair``, ``_family`` and ``_deflate``) step by step,
around the same kernels; :func:`array_poses` its array path for a few poses, up to the
search beyond the rows, and :func:`array_start` and :func:`array_finish` the same for a
batch, on either side of the repairs.
:func:`ready` says whether numba is there and the environment variable ``DQLAB_COMPILED``
(:mod:`dqlab._fast.compiled`, read again by :func:`refresh`) does not switch the compiled paths
off; the first compilation takes seconds, and is cached on disk for the next processes.

The compiled path differs from the numpy path in two ways that change no result beyond
rounding: after a step, the cosine and sine of each joint angle are turned by the step
(Taylor series of a step below 0.02 rad) instead of being computed again; and the most
singular direction comes from inverse iteration instead of ``eigh`` (the same to 1e-9
where the two smallest eigenvalues of :math:`J^\mathsf{T} J` are apart, tested; where they
are not, neither direction is better defined than the other), or, in :func:`repairs` where
inverse iteration is not certain of it, from Jacobi's rotations (eigenvalues and vectors
of a symmetric matrix, as ``eigh`` gives them).
"""

import math

import numpy as np

from .compiled import compile_in_place, compiled_allowed
from .newton_lanes import INDEX, NV, W
from .newton_lanes import angles as lane_angles
from .newton_lanes import deflated_step as lane_deflated_step
from .newton_lanes import frames as lane_frames
from .newton_lanes import recompute as lane_recompute
from .newton_lanes import size as lane_size
from .newton_lanes import step as lane_step

__all__ = ["ready", "refresh", "newton", "one_pose", "exact_one_pose", "exact_poses", "exact_fk",
           "unique", "are_new", "accept", "nearness", "gram", "smallest", "deflated", "repairs",
           "array_poses", "array_start", "array_finish"]

_COMPILED = []     # the functions below the wrappers, compiled in place by ready()
_READY = None      # whether numba is there (the kernels compiled), once known
_ALLOWED = True    # DQLAB_COMPILED as last read (refresh)


def refresh():
    """Read the environment variable ``DQLAB_COMPILED`` again
    (:func:`dqlab._fast.compiled.compiled_allowed`): ``dqlab.ik.ur`` does at each call on a
    calibrated UR, so that a process may switch the compiled kernels on and off; until
    then :func:`ready` answers with the value read last."""
    global _ALLOWED
    _ALLOWED = compiled_allowed()


def ready():
    """Whether the compiled kernels can be used: ``DQLAB_COMPILED`` allows them (as last
    read, :func:`refresh`) and numba is installed and imports (it is imported, and the
    kernels compiled or read from the cache, at the first call only, so that importing
    dqlab stays quick)."""
    global _READY
    if not _ALLOWED:
        return False
    if _READY is None:
        _READY = compile_in_place(globals(), _COMPILED)
    return _READY


def newton(links, tool, q, X_target, tol, max_iter, *, plain, stop_factor, give_up_after,
           damping, max_step):
    """``dqlab.ik.ur_calibrated._newton`` compiled: the joint vectors (m, 6), whether each
    converged (m,), the TCP poses (m, 4, 4), the singularity measures (3, m) and the
    position and rotation errors (2, m) of ``dqlab.ik.targets.pose_errors``."""
    m = q.shape[0]
    q_out = np.array(q, dtype=float, order="C", copy=True)
    converged = np.zeros(m, dtype=np.bool_)
    X = np.zeros((m, 4, 4))
    measures, errors = np.zeros((3, m)), np.zeros((2, m))
    _kernel(np.asarray(links, dtype=float), np.ascontiguousarray(tool, dtype=float), q_out,
            np.ascontiguousarray(X_target, dtype=float), float(stop_factor * tol),
            int(min(plain, max_iter)), int(max_iter), int(give_up_after), float(damping),
            float(max_step), converged, X, measures, errors)
    return q_out, converged, X, measures, errors


def one_pose(links, tool, exact, X_06, X_0T, theta6_ref, tol, wide, singular_tol,
             near_wrist, near_tol, max_iter, *, plain, stop_factor, give_up_after, damping,
             max_step, polish_near, family):
    """``dqlab.ik.ur_calibrated._one_pose`` compiled: the exact arm's closed form of the flange
    ``X_06`` (4, 4) (tolerance ``wide``, the reference's ``theta6_ref``), its rows clipped at
    the elbow moved off it, the Newton steps of the rows it found towards ``X_0T`` (4, 4),
    the test for the wrist family's starts (``family``: members, ``_NEAR_MEASURE``,
    ``_FEW_BRANCHES``, ``_FEW_WRIST``) and for the valid rows near a singularity of the
    exact arm (``polish_near``), and the near_singular flag. None when the pose needs the
    array path: the closed form found no row or missed one by ten times ``wide`` or less, a
    row does not converge or two converge to the same solution, or the pose seeks the wrist
    family's starts. Else how it ended (1: done; 2: a valid row within ``polish_near`` of a
    singularity, which the caller polishes and searches beyond), the solutions (8, 6)
    (wrapped, zero where not valid), ``valid`` (8,), the position and rotation errors (8,)
    (the polished rows' in place of the closed form's) and the flags (6,): wrist, shoulder
    and elbow singular, near singular (a measure of the calibrated arm or, when done, of
    the exact arm at a valid row or at its own rows, below ``near_tol``), unreachable, not
    converged; the closed form's own near-singular flag, and its exact solutions (8,)
    (found, and within ``tol``: a row of them that does not end valid is not_converged)."""
    solutions, valid = np.zeros((8, 6)), np.zeros(8, dtype=np.bool_)
    pe, re = np.zeros(8), np.zeros(8)
    flags, start_flags = np.zeros(6, dtype=np.bool_), np.zeros(4, dtype=np.bool_)
    exact_rows = np.zeros(8, dtype=np.bool_)
    members, near_measure, few_branches, few_wrist = family
    ended = _lean_pose(np.asarray(links, dtype=float), np.ascontiguousarray(tool, dtype=float),
                       np.asarray(exact, dtype=float), np.ascontiguousarray(X_06, dtype=float),
                       np.ascontiguousarray(X_0T, dtype=float), float(theta6_ref), float(tol),
                       float(wide), float(singular_tol), float(near_wrist), float(near_tol),
                       float(stop_factor * tol), int(min(plain, max_iter)), int(max_iter),
                       int(give_up_after), float(damping), float(max_step), float(polish_near),
                       (int(members), float(near_measure), int(few_branches),
                        float(few_wrist)), solutions, valid, pe, re, flags, start_flags,
                       exact_rows)
    if not ended:
        return None
    return ended, solutions, valid, pe, re, flags, bool(start_flags[3]), exact_rows


def _lean_pose(links, tool, exact, X_06, X_0T, theta6_ref, tol, wide, singular_tol, near_wrist,
               near_tol, stop, plain, max_iter, give_up_after, damping, max_step, polish_near,
               family, solutions, valid, pe, re, flags, start_flags, exact_rows):
    """:func:`one_pose`'s work: 0 as soon as the pose needs the array path."""
    qw, qx, qy, qz = _quaternion(X_06)
    start, errors = np.zeros((8, 6)), np.zeros((2, 8))
    if _exact_one_pose(qw, qx, qy, qz, X_06[0, 3], X_06[1, 3], X_06[2, 3], X_06[0, 2],
                       X_06[1, 2], X_06[2, 2], X_06, theta6_ref, exact, wide, singular_tol,
                       near_wrist, near_tol, start, errors, start_flags) != SOLVED:
        return 0
    found = np.empty(8, dtype=np.bool_)
    for k in range(8):
        found[k] = errors[0, k] <= wide and errors[1, k] <= wide
        exact_rows[k] = found[k] and errors[0, k] <= tol
        if found[k]:
            if errors[0, k] > tol:                          # (a clipped row)
                _off_the_edge(start, k, k, errors[0, k], exact)
        pe[k], re[k] = errors[0, k], errors[1, k]
    if not _one_pose(links, tool, start, found, X_0T, tol, stop, plain, max_iter, give_up_after,
                     damping, max_step, singular_tol, exact[3], 10.0 * wide, near_tol,
                     solutions, valid, pe, re, flags):
        return 0
    members, near_measure, few_branches, few_wrist = family
    have, wrist = 0, False                              # _family_members (done, have: found):
    for k in range(8):                                  # a pose missing a branch seeks the
        if found[k]:                                    # family's starts near the wrist
            have += 1                                   # singularity or with few branches
            wrist = wrist or abs(math.sin(solutions[k, 4] + exact[10])) < near_measure
    if have < 8 and (wrist or have <= few_branches):
        return 0
    near = np.zeros(8, dtype=np.bool_)
    _near_rows(solutions, valid, exact, polish_near, near)
    for k in range(8):
        if near[k]:
            return 2                                    # polish and search beyond: the caller
    if near_tol > polish_near:                          # (near: all False so far)
        _near_rows(solutions, valid, exact, near_tol, near)
        for k in range(8):
            flags[3] = flags[3] or near[k]
    flags[3] = flags[3] or start_flags[3]
    return 1


def unique(q, converged):
    """``_Polished.unique`` compiled: converged rows (8 n,) that do not repeat a converged row
    of lower number of their pose (every joint within 1e-6 rad, modulo 2 pi)."""
    out = np.empty(converged.shape[0], dtype=np.bool_)
    _unique(np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(converged), out)
    return out


def are_new(rows, q_rows, q, unique):
    """``_Polished.are_new`` compiled: whether each joint vector ``q_rows[j]`` differs from
    every unique row of the pose of ``rows[j]``."""
    out = np.empty(rows.shape[0], dtype=np.bool_)
    _are_new(np.ascontiguousarray(rows, dtype=np.int64),
             np.ascontiguousarray(q_rows, dtype=float), np.ascontiguousarray(q, dtype=float),
             np.ascontiguousarray(unique), out)
    return out


def accept(owners, converged, q_starts, q, unique):
    """``dqlab.ik.ur_calibrated._accept`` compiled: the starts j (in order) whose solution
    ``q_starts[j]`` replaces row ``owners[j]``, each written to ``q`` and marked in
    ``unique`` (both in place, C-contiguous) as it is taken."""
    if not (q.flags.c_contiguous and unique.flags.c_contiguous):
        raise ValueError("accept writes q and unique in place: they must be C-contiguous")
    taken = np.empty(owners.shape[0], dtype=np.int64)
    k = _accept(np.ascontiguousarray(owners, dtype=np.int64), np.ascontiguousarray(converged),
                np.ascontiguousarray(q_starts, dtype=float), q, unique, taken)
    return taken[:k]


def exact_fk(q, constants):
    """Forward kinematics (m, 4, 4) of the exact UR of ``constants`` (``_NearestExact.exact``)
    at the joint vectors q (m, 6): ``Robot.fk`` of that arm (bare), compiled (tested equal
    to the rounding)."""
    X = np.zeros((q.shape[0], 4, 4))
    _exact_fk(np.ascontiguousarray(q, dtype=float), np.asarray(constants, dtype=float), X)
    return X


def _exact_fk(q, constants, X):
    """:func:`exact_fk`'s work."""
    for i in range(q.shape[0]):
        _exact_flange(q[i], constants, X[i])


def nearness(solutions, valid, constants):
    r"""``dqlab.ik.ur_calibrated._nearness`` compiled: how near a singularity of the exact arm
    of ``constants`` (``_NearestExact.exact``) each valid row of ``solutions`` (m, 6) is, the
    least of :math:`|\sin\theta_3|`, :math:`|\sin\theta_5|` and :math:`|h| / |a_2|`
    (infinite where not valid)."""
    out = np.full(solutions.shape[0], np.inf)
    _nearness(np.ascontiguousarray(solutions, dtype=float), np.ascontiguousarray(valid),
              np.asarray(constants, dtype=float), out)
    return out


def _nearness(solutions, valid, constants, out):
    """:func:`nearness`' work."""
    for r in range(solutions.shape[0]):
        if valid[r]:
            out[r] = _row_nearness(solutions[r], constants)


def _row_nearness(q, constants):
    """:func:`nearness` of one joint vector q (6,)."""
    a2, a3, d5 = constants[1], constants[2], constants[4]
    t2 = q[1] + constants[7]
    t3 = q[2] + constants[8]
    t4 = q[3] + constants[9]
    t5 = q[4] + constants[10]
    h = a2 * math.cos(t2) + a3 * math.cos(t2 + t3) + d5 * math.sin(t2 + t3 + t4)
    return min(abs(math.sin(t3)), abs(math.sin(t5)), abs(h) / abs(a2))


def _near_rows(solutions, valid, constants, threshold, near):
    """Which valid rows of ``solutions`` are within ``threshold`` of a singularity of the
    exact arm (:func:`nearness` below it), into ``near``."""
    for r in range(solutions.shape[0]):
        near[r] = valid[r] and _row_nearness(solutions[r], constants) < threshold


def gram(links, tool, q):
    r""":math:`J^\mathsf{T} J` (m, 6, 6) of the calibrated chain (links, tool) at the joint
    vectors q (m, 6), J the Jacobian at the TCP of
    ``calibrated_matrices.MatrixChain.jacobian``: the lanes'
    frames, then the columns of ``calibrated_entries.EntryChain._columns``."""
    H = np.empty((q.shape[0], 6, 6))
    _gram(np.asarray(links, dtype=float), np.ascontiguousarray(tool, dtype=float),
          np.ascontiguousarray(q, dtype=float), H)
    return H


def smallest(H, ratio):
    r"""The test and direction of ``dqlab.ik.ur_calibrated._near_singular`` from
    :math:`H = J^\mathsf{T} J` (m, 6, 6), without a full eigendecomposition: whether the
    smallest eigenvalue is below ``ratio`` times the largest (``near``, m), the eigenvector
    of the smallest (m, 6; its largest entry positive), and where both are ``known`` (m).

    Where the answer is certain it is known: not near when
    :math:`1/\lVert H^{-1}\rVert \ge` ``ratio`` :math:`\lVert H\rVert` (bounds by the
    trace and the largest row sum); near when the Rayleigh quotient of the eigenvector found
    by inverse iteration (with :math:`H^{-1}` from Cholesky) is below ``ratio`` times that
    of a few power iterations (a lower bound of the largest eigenvalue), the inverse
    iteration having converged. Elsewhere (a Cholesky that fails, an iteration that does
    not settle, a ratio too close to call) it is not known, and the caller asks
    ``numpy.linalg.eigh``."""
    m = H.shape[0]
    near, known = np.zeros(m, dtype=np.bool_), np.zeros(m, dtype=np.bool_)
    V = np.zeros((m, 6))
    _smallest(np.ascontiguousarray(H, dtype=float), float(ratio), near, V, known)
    return near, V, known


def deflated(links, tool, q, X_target, known, steps, *, stop, give_up_after, damping,
             max_step):
    """``dqlab.ik.ur_calibrated._deflated_newton`` compiled: at most ``steps`` deflated
    Newton steps from the joint vectors q (m, 6) towards X_target (m, 4, 4), row by row,
    each deflating the known solutions ``known`` (m, k, 6) of its pose (NaN rows: none),
    with the stop and give-up rules of that function. The joint vectors reached (m, 6)."""
    out = np.array(q, dtype=float, order="C", copy=True)
    have = ~np.isnan(known[..., 0])
    _deflated(np.asarray(links, dtype=float), np.ascontiguousarray(tool, dtype=float), out,
              np.ascontiguousarray(X_target, dtype=float),
              np.ascontiguousarray(np.where(have[..., None], known, 0.0), dtype=float),
              np.ascontiguousarray(have), int(steps), float(stop), int(give_up_after),
              float(damping), float(max_step))
    return out


def exact_one_pose(flange, X_target, theta6_ref, constants, tol, singular_tol, near_wrist,
                   near_tol):
    """The closed form of the exact UR of ``constants`` (12,) (``d1, a2, a3, d4, d5, d6`` and
    the six joint offsets) for one flange pose, compiled: ``flange`` its ``(q, p, z6)``
    (rotation quaternion, position, z axis) and ``X_target`` (4, 4) its transform,
    ``theta6_ref`` the theta6 of ``q_ref`` (0 without one). The solutions (8, 6), ``valid``
    (8,), the position and rotation errors (8,) each, the flags (4,) wrist, shoulder and
    elbow singular and near singular (``near_tol``) and how it ended (:data:`SOLVED`, or the
    reason no row is valid) of the closed form's result (``dqlab._fast.ur_engine``); None
    where the wrist centre is far beyond reach (which the closed form's batch path solves
    for a stand-in). The same steps of ``dqlab.ik.ur_steps`` in the same
    order, on the same floats: equal bit for bit to the closed form's one-pose path
    (``dqlab._fast.ur_engine.solve_single``), and near the wrist singularity, where that path
    hands the pose to the batch path, to the batch path (a wrist family's members checked
    by forward kinematics; tested equal to the rounding)."""
    q, p, z6 = flange
    solutions, errors = np.zeros((8, 6)), np.zeros((2, 8))
    flags = np.zeros(4, dtype=np.bool_)
    ended = _exact_one_pose(q[0], q[1], q[2], q[3], p[0], p[1], p[2], z6[0], z6[1], z6[2],
                            np.ascontiguousarray(X_target, dtype=float), float(theta6_ref),
                            constants, float(tol), float(singular_tol), float(near_wrist),
                            float(near_tol), solutions, errors, flags)
    if not ended:
        return None
    valid = (ended == SOLVED) & (errors[0] <= tol) & (errors[1] <= tol)
    return solutions, valid, errors[0], errors[1], flags, ended


def exact_poses(Q, P, Z, X, theta6_ref, constants, tol, singular_tol, near_wrist, near_tol):
    """:func:`exact_one_pose` of n flanges at once, pose by pose in compiled code: rotation
    quaternions ``Q`` (n, 4), positions ``P`` (n, 3), z axes ``Z`` (n, 3), transforms ``X``
    (n, 4, 4) and ``theta6_ref`` (n,). The solutions (n, 8, 6), ``valid`` (n, 8), the
    position and rotation errors (n, 8) each, the flags (n, 4) and how each ended (n,): 0
    where :func:`exact_one_pose` returns None (those poses' other arrays are zeros)."""
    n = Q.shape[0]
    solutions, errors = np.zeros((n, 8, 6)), np.zeros((n, 2, 8))
    flags, ended = np.zeros((n, 4), dtype=np.bool_), np.zeros(n, dtype=np.int64)
    _exact_poses(np.ascontiguousarray(Q, dtype=float), np.ascontiguousarray(P, dtype=float),
                 np.ascontiguousarray(Z, dtype=float), np.ascontiguousarray(X, dtype=float),
                 np.ascontiguousarray(theta6_ref, dtype=float), constants, float(tol),
                 float(singular_tol), float(near_wrist), float(near_tol), solutions, errors,
                 flags, ended)
    valid = (ended == SOLVED)[:, None] & (errors[:, 0] <= tol) & (errors[:, 1] <= tol)
    return solutions, valid, errors[:, 0], errors[:, 1], flags, ended


def _exact_poses(Q, P, Z, X, theta6_ref, constants, tol, singular_tol, near_wrist, near_tol,
                 solutions, errors, flags, ended):
    """:func:`exact_poses`' work: :func:`_exact_one_pose` of each pose, a pose it hands on
    cleared again."""
    for i in range(Q.shape[0]):
        ended[i] = _exact_one_pose(Q[i, 0], Q[i, 1], Q[i, 2], Q[i, 3], P[i, 0], P[i, 1], P[i, 2],
                                  Z[i, 0], Z[i, 1], Z[i, 2], X[i], theta6_ref[i], constants,
                                  tol, singular_tol, near_wrist, near_tol, solutions[i],
                                  errors[i], flags[i])
        if not ended[i]:
            solutions[i], errors[i], flags[i] = 0.0, 0.0, False


#: What the closed form of :func:`exact_one_pose` ends with: a valid row, or none for the
#: reason numbered (``dqlab.ik.ur_steps``' REASON_TOL, REASON_REACH, REASON_INNER,
#: REASON_OUTER, REASON_SHOULDER); 0: handed on.
SOLVED, NO_ROW_TOL, NO_ROW_REACH, NO_ROW_INNER, NO_ROW_OUTER, NO_ROW_SHOULDER = range(1, 7)
_TOL, _REACH, _INNER, _OUTER, _SHOULDER = (NO_ROW_TOL, NO_ROW_REACH, NO_ROW_INNER,
                                           NO_ROW_OUTER, NO_ROW_SHOULDER)
_TWO_PI = 2.0 * math.pi
_HALF_SQRT2 = math.sqrt(0.5)
_UR_TWISTS = ((0.0, 1.0), (1.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, 0.0))
_EPSILON = float(np.finfo(np.float64).eps)


def _same(u, v):
    """Every joint of u and v (6,) within 1e-6 rad modulo 2 pi (False with a NaN)."""
    for j in range(6):
        d = u[j] - v[j]
        if not abs(d - _TWO_PI * np.rint(d / _TWO_PI)) < 1e-6:
            return False
    return True


def _unique(q, converged, out):
    """out (8 n,): the converged rows that repeat no converged row before them in their pose."""
    for pose in range(q.shape[0] // 8):
        _unique_pose(q, converged, out, 8 * pose)


def _full(unique, base):
    """Whether the eight rows of the pose that begin at ``base`` are all ``unique`` (eight
    distinct solutions: no branch missing)."""
    for i in range(base, base + 8):
        if not unique[i]:
            return False
    return True


def _unique_pose(q, converged, out, base):
    """:func:`_unique` of the pose whose rows begin at ``base`` (rows base..base + 7 of the
    arrays, read and written in place: no views)."""
    for i in range(base, base + 8):
        out[i] = converged[i]
        if converged[i]:
            for k in range(base, i):
                if converged[k] and _same(q[k], q[i]):
                    out[i] = False
                    break


def _are_new(rows, q_rows, q, unique, out):
    """out (m,): q_rows[j] repeats no unique row of the pose of rows[j]."""
    for j in range(rows.shape[0]):
        first = rows[j] - rows[j] % 8
        out[j] = True
        for k in range(first, first + 8):
            if unique[k] and _same(q[k], q_rows[j]):
                out[j] = False
                break


def _accept(owners, converged, q_starts, q, unique, taken):
    """:func:`accept`'s loop: the number of starts taken, their indices in ``taken``."""
    fresh = np.empty(owners.shape[0], dtype=np.bool_)   # new to the pose before any is taken
    _are_new(owners, q_starts, q, unique, fresh)
    fixed = np.zeros(unique.shape[0], dtype=np.bool_)
    k = 0
    for j in range(owners.shape[0]):
        row = owners[j]
        if not (converged[j] and fresh[j]) or fixed[row]:
            continue
        first = row - row % 8
        new = True
        for i in range(first, first + 8):
            if unique[i] and _same(q[i], q_starts[j]):
                new = False
                break
        if new:
            q[row] = q_starts[j]
            unique[row] = fixed[row] = True
            taken[k] = j
            k += 1
    return k


def _gram(links, tool, q, H):
    """:func:`gram`'s work, W rows at a time."""
    S = np.empty(NV * W)                                # (every entry written before read)
    J = np.empty((6, 6))
    m = q.shape[0]
    for first in range(0, m, W):
        n = min(W, m - first)
        for r in range(W):
            for i in range(6):
                S[(_Q + i) * W + r] = q[first + min(r, n - 1), i]
        lane_angles(S, links)
        lane_frames(S, links, tool)
        for r in range(n):
            px, py, pz = S[(_F + 36) * W + r], S[(_F + 37) * W + r], S[(_F + 38) * W + r]
            J[0, 0], J[1, 0], J[2, 0] = -py, px, 0.0      # joint 1: z_0 = (0, 0, 1), o_0 = 0
            J[3, 0], J[4, 0], J[5, 0] = 0.0, 0.0, 1.0
            for i in range(5):
                zx, zy, zz = (S[(_F + 3 * i) * W + r], S[(_F + 3 * i + 1) * W + r],
                              S[(_F + 3 * i + 2) * W + r])
                rx = px - S[(_F + 15 + 3 * i) * W + r]
                ry = py - S[(_F + 16 + 3 * i) * W + r]
                rz = pz - S[(_F + 17 + 3 * i) * W + r]
                J[0, i + 1], J[1, i + 1], J[2, i + 1] = (zy * rz - zz * ry, zz * rx - zx * rz,
                                                         zx * ry - zy * rx)
                J[3, i + 1], J[4, i + 1], J[5, i + 1] = zx, zy, zz
            for a in range(6):
                for b in range(6):
                    total = 0.0
                    for k in range(6):
                        total += J[k, a] * J[k, b]
                    H[first + r, a, b] = total


def _smallest(H, ratio, near, V, known):
    """:func:`smallest`'s work, matrix by matrix."""
    L, Li, G = np.empty((6, 6)), np.empty((6, 6)), np.empty((6, 6))
    v, w, u = np.empty(6), np.empty(6), np.empty(6)
    for r in range(H.shape[0]):
        A = H[r]
        trace, row_sum = 0.0, 0.0
        for i in range(6):
            trace += A[i, i]
            total = 0.0
            for j in range(6):
                total += abs(A[i, j])
            row_sum = max(row_sum, total)
        largest = min(trace, row_sum)                   # >= the largest eigenvalue
        if not (largest > 0.0 and largest < math.inf):
            continue
        if not _cholesky(A, 0.0, L):                    # A = L L^T
            continue
        for j in range(6):                              # Li = L^-1 (lower), G = Li^T Li
            for i in range(6):
                Li[i, j] = 0.0
            Li[j, j] = 1.0 / L[j, j]
            for i in range(j + 1, 6):
                x = 0.0
                for k in range(j, i):
                    x -= L[i, k] * Li[k, j]
                Li[i, j] = x / L[i, i]
        inverse_trace, inverse_row_sum = 0.0, 0.0
        for i in range(6):
            for j in range(6):
                x = 0.0
                for k in range(max(i, j), 6):
                    x += Li[k, i] * Li[k, j]
                G[i, j] = x
            inverse_trace += G[i, i]
        for i in range(6):
            total = 0.0
            for j in range(6):
                total += abs(G[i, j])
            inverse_row_sum = max(inverse_row_sum, total)
        if 1.0 / min(inverse_trace, inverse_row_sum) >= ratio * largest:
            known[r] = True                             # smallest >= ratio largest: not near
            continue
        _largest_diagonal_column(G, v)                  # inverse iteration, from the column
        settled = False                                 # of H^-1 of largest diagonal
        for _ in range(64):
            size = _times(G, v, w)
            dot = 0.0
            for i in range(6):
                dot += w[i] * v[i]
            scale = (1.0 if dot >= 0.0 else -1.0) / size
            change = 0.0
            for i in range(6):
                x = w[i] * scale
                change = max(change, abs(x - v[i]))
                v[i] = x
            if change <= 1e-14:
                settled = True
                break
        lowest = _rayleigh(A, v)                        # >= the smallest eigenvalue
        _largest_diagonal_column(A, w)                  # power iteration, from the column
        for _ in range(8):                              # of H of largest diagonal
            size = _times(A, w, u)
            for i in range(6):
                w[i] = u[i] / size
        if settled and lowest < ratio * _rayleigh(A, w):   # <= the largest eigenvalue
            near[r] = known[r] = True
            top = 0
            for i in range(6):
                if abs(v[i]) > abs(v[top]):
                    top = i
            sign = 1.0 if v[top] > 0.0 else -1.0
            for i in range(6):
                V[r, i] = sign * v[i]


def _deflated(links, tool, q, X_target, known, have, steps, stop, give_up_after, damping,
              max_step):
    r""":func:`deflated`'s work, W rows at a time in the lanes of :func:`_kernel`: the
    frames, the stop rules of ``_deflated_newton`` lane by lane, each lane's
    :math:`\nabla \log m = \sum_k -2 d_k / (r_k^2 (1 + r_k^2))` (:math:`d_k` the wrapped
    difference from known solution k, :math:`r_k^2 = \lVert d_k \rVert^2`), then the
    deflated step of every lane still going (``newton_lanes.deflated_step``)."""
    S = np.zeros(NV * W)
    size, before0, before1 = np.empty(W), np.empty(W), np.empty(W)
    rows = np.empty(W, dtype=np.int64)
    d = np.empty(6)
    m = q.shape[0]
    for first in range(0, m, W):
        n = min(W, m - first)
        for r in range(W):
            rows[r] = first + min(r, n - 1)                 # extra lanes repeat the last row
            size[r], before0[r], before1[r] = math.inf, math.inf, math.inf
        _load(links, q, X_target, rows, S)
        for iteration in range(steps + 1):
            lane_frames(S, links, tool)
            lane_size(S)
            more = False
            for r in range(W):
                if S[_ACT * W + r] > 0.0:
                    before0[r], before1[r] = before1[r], size[r]
                    size[r] = S[_SIZE * W + r]
                    keep = size[r] > stop               # (not a number stops too)
                    if iteration >= give_up_after:
                        keep = keep and size[r] < 0.5 * before0[r]
                    if iteration == steps or not keep:
                        S[_ACT * W + r] = 0.0
                if S[_ACT * W + r] > 0.0:
                    more = True
                    row = rows[r]
                    for i in range(6):
                        S[(_G + i) * W + r] = 0.0
                    for k in range(known.shape[1]):
                        if have[row, k]:
                            r2 = 0.0
                            for i in range(6):
                                d[i] = _wrap(S[(_Q + i) * W + r] - known[row, k, i])
                                r2 += d[i] * d[i]
                            w = -2.0 / (r2 * (1.0 + r2))
                            for i in range(6):
                                S[(_G + i) * W + r] += w * d[i]
                else:
                    S[_ACT * W + r] = 0.0
            if not more:
                break
            lane_deflated_step(S, damping, max_step)
            if _long_step(S):
                lane_recompute(S, links)
        for r in range(n):
            for i in range(6):
                q[first + r, i] = S[(_Q + i) * W + r]


def _cholesky(A, shift, L):
    """L (6, 6, lower) with A + shift I = L L^T; False where A + shift I is not positive
    definite (or not a number)."""
    for j in range(6):
        d = A[j, j] + shift
        for k in range(j):
            d -= L[j, k] * L[j, k]
        if not d > 0.0:
            return False
        L[j, j] = math.sqrt(d)
        for i in range(j + 1, 6):
            x = A[i, j]
            for k in range(j):
                x -= L[i, k] * L[j, k]
            L[i, j] = x / L[j, j]
    return True


def _largest_diagonal_column(A, out):
    """out (6,): the column of A (6, 6) whose diagonal entry is the largest."""
    best = 0
    for i in range(6):
        if A[i, i] > A[best, best]:
            best = i
    for i in range(6):
        out[i] = A[i, best]


def _times(A, v, out):
    """out (6,) = A v; returns its length."""
    size = 0.0
    for i in range(6):
        x = 0.0
        for j in range(6):
            x += A[i, j] * v[j]
        out[i] = x
        size += x * x
    return math.sqrt(size)


def _rayleigh(A, v):
    """v^T A v / v^T v."""
    x, n = 0.0, 0.0
    for i in range(6):
        n += v[i] * v[i]
        for j in range(6):
            x += v[i] * A[i, j] * v[j]
    return x / n


def _wrap(theta):
    """``dqlab.rotations.wrap_angle`` of one angle: into (-pi, pi]."""
    w = theta - _TWO_PI * np.rint(theta * (1.0 / _TWO_PI))
    if not abs(w) < math.pi:
        w = w - _TWO_PI if w > math.pi else (w + _TWO_PI if w <= -math.pi else w)
    return w


def _exact_one_pose(qw, qx, qy, qz, px, py, pz, zx, zy, zz, X_target, theta6_ref, constants,
                    tol, singular_tol, near_wrist, near_tol, solutions, errors, flags):
    """:func:`exact_one_pose`'s work: the closed form's steps, each line the step of
    ``dqlab.ik.ur_steps`` (or the function of ``dqlab._fast.ur_engine``) named beside it;
    ``errors`` (2, 8) the position and rotation errors. Returns :data:`SOLVED`, the number
    of the reason where no row is valid, or 0 where the wrist centre is far beyond
    reach."""
    d1, a2, a3, d4, d5, d6 = (constants[0], constants[1], constants[2], constants[3],
                              constants[4], constants[5])
    family_tol = tol / (8.0 * max(1.0, abs(d6)))       # dqlab._fast.ur_engine.wrist_family_tol
    offset = False
    for i in range(6):
        offset = offset or constants[6 + i] != 0.0
    ref = constants[11] + theta6_ref                    # _wrist_family's theta6 wanted
    # target_rotation: r_D = q (1 - i) / sqrt 2
    rw = _HALF_SQRT2 * (qw * 1.0 - qx * -1.0 - qy * 0.0 - qz * 0.0)
    rx = _HALF_SQRT2 * (qw * -1.0 + qx * 1.0 + qy * 0.0 - qz * 0.0)
    ry = _HALF_SQRT2 * (qw * 0.0 - qx * 0.0 + qy * 1.0 + qz * -1.0)
    rz = _HALF_SQRT2 * (qw * 0.0 + qx * 0.0 - qy * -1.0 + qz * 1.0)
    x5, y5, z5 = px - d6 * zx, py - d6 * zy, pz - d6 * zz          # wrist_center
    reach = math.sqrt(d4 * d4 + (abs(a2) + abs(a3) + abs(d5)) ** 2)  # far_wrist
    if not abs(x5) + abs(y5) + abs(z5 - d1) <= reach / _EPSILON:
        return 0
    any_valid = wrist_singular = elbow_singular = near = False
    beyond = within = clipped = True      # every row's wrist-1 point beyond, within, either
    radius = math.sqrt(x5 * x5 + y5 * y5)                            # shoulder_gap
    shoulder_gap = max(-(x5 * x5 + y5 * y5 - d4 * d4), 0.0) / (d4 + radius)
    h = 0.0
    m = 2.0 * abs(a2 * a3)
    r_out, r_in = abs(a2 + a3), abs(a2 - a3)
    X = np.zeros((4, 4))
    for s in range(2):
        shoulder = 1.0 if s == 0 else -1.0
        h2 = x5 * x5 + y5 * y5 - d4 * d4                            # shoulder_angles
        h = math.sqrt(h2 if h2 > 0.0 else 0.0)
        hpm = shoulder * h
        num_c = x5 * hpm - y5 * d4
        num_s = y5 * hpm + x5 * d4
        theta1 = math.atan2(num_s + 0.0, num_c)
        r = math.sqrt(num_c * num_c + num_s * num_s)
        c1, s1 = (num_c / r, num_s / r) if r > 0.0 else (1.0, 0.0)
        big = math.sqrt(0.5 + 0.5 * abs(c1))                         # half_angle_cos_sin
        other = 0.5 * s1 / big
        if c1 >= 0.0:
            hc, hs = big, other
        else:
            hc, hs = abs(other), (-big if s1 < 0.0 else big)
        Lw, Lx = hc * rw + hs * rz, hc * rx + hs * ry               # relative_rotation_
        Ly, Lz = hc * ry - hs * rx, hc * rz - hs * rw               # coefficients
        u5, v5 = c1 * x5 + s1 * y5, z5 - d1                          # arm_plane_wrist
        c5bar = math.sqrt(Lw * Lw + Ly * Ly)                         # wrist_angles
        s5bar = math.sqrt(Lx * Lx + Lz * Lz)
        theta5 = 1.0 * (2.0 * math.atan2(s5bar, c5bar))
        if theta5 == -math.pi:
            theta5 = math.pi
        half_sum = math.atan2(-Ly, Lw)
        half_diff = math.atan2(1.0 * Lx, -1.0 * Lz)                  # half_difference
        sin5 = 2.0 * s5bar * c5bar
        # at the wrist singularity for tol, a member of the wrist family (_wrist_family);
        # rep0: theta5 near 0, where theta234 + theta6 is fixed (near pi, theta234 - theta6)
        at_family = min(s5bar, c5bar) <= family_tol
        rep0 = s5bar <= c5bar
        sin234 = cos234 = 0.0
        if not at_family:
            k = 1.0 / (c5bar * s5bar)                                # theta234_sine_cosine
            sin234, cos234 = k * (Lw * Lx + Ly * Lz), k * (Lx * Ly - Lw * Lz)
        for w in range(2):
            if w == 1:                                               # the flipped wrist
                theta5 = -theta5 if theta5 != math.pi else theta5
                half_diff = math.atan2(-1.0 * Lx, 1.0 * Lz)       # sigma = -1
                sin234, cos234 = -sin234, -cos234
            theta234 = half_sum + half_diff
            theta6 = half_sum - half_diff
            s234, c234 = sin234, cos234
            represented = at_family
            if at_family:
                want = 2.0 * half_sum - ref if rep0 else 2.0 * half_diff + ref
                theta234, theta6 = _family_member(u5, v5, want, half_sum, half_diff, rep0,
                                                  a2, a3, d5)
                s234, c234 = math.sin(theta234), math.cos(theta234)
            u4, v4 = u5 - d5 * s234, v5 + d5 * c234                 # wrist1_point
            rho2 = u4 * u4 + v4 * v4                                 # elbow_triangle
            rho = math.sqrt(rho2)
            outer = (r_out - rho) * (r_out + rho)
            inner = (rho - r_in) * (rho + r_in)
            if (sin5 < near_wrist and not at_family
                    and (outer < -tol * r_out or inner < -tol * r_in)):   # _out_of_reach:
                theta234, theta6 = _family_member(u5, v5, theta234, half_sum, half_diff,
                                                  rep0, a2, a3, d5)   # the nearest member
                s234, c234 = math.sin(theta234), math.cos(theta234)  # that reaches
                represented = True
                u4, v4 = u5 - d5 * s234, v5 + d5 * c234
                rho2 = u4 * u4 + v4 * v4
                rho = math.sqrt(rho2)
                outer = (r_out - rho) * (r_out + rho)
                inner = (rho - r_in) * (rho + r_in)
            theta6 = _wrap(theta6)
            beyond = beyond and outer < 0.0                          # (_reasons)
            within = within and inner < 0.0
            clipped = clipped and (outer < 0.0 or inner < 0.0)
            kk = outer * inner
            kk = math.sqrt(kk if kk > 0.0 else 0.0)
            cos_num = rho2 - (a2 * a2 + a3 * a3)
            if a2 * a3 < 0:
                cos_num = -cos_num
            angle3 = math.atan2(kk, cos_num)
            gap = 0.0                                    # _clipping_distance
            if outer < 0.0 or inner < 0.0:
                rho = math.sqrt(u4 * u4 + v4 * v4)                   # reach_gap
                gap = rho - r_out
                if r_in - rho > gap:
                    gap = r_in - rho
                if 0.0 > gap:
                    gap = 0.0
            if h2 < 0.0:                                 # inside the shoulder cylinder
                gap = math.sqrt(shoulder_gap * shoulder_gap + gap * gap)
            errors[0, 4 * s + w] = errors[0, 4 * s + 2 + w] = gap
            if gap > tol and not represented:
                continue
            for e in range(2):
                row = 4 * s + 2 * e + w
                elbow = 1.0 if e == 0 else -1.0
                theta3 = angle3 * elbow                              # elbow_angles
                if theta3 == -math.pi:
                    theta3 = math.pi
                k1 = a2 + (a3 / m) * cos_num
                k2 = (a3 / m) * kk
                theta2 = math.atan2(v4 * k1 - elbow * (u4 * k2) + 0.0,
                                    u4 * k1 + elbow * (v4 * k2))
                solutions[row, 0], solutions[row, 1], solutions[row, 2] = theta1, theta2, theta3
                solutions[row, 3] = _wrap(theta234 - theta2 - theta3)
                solutions[row, 4], solutions[row, 5] = theta5, theta6
                if offset:
                    inside = True
                    for i in range(6):
                        solutions[row, i] = solutions[row, i] - constants[6 + i]
                        inside = inside and -math.pi < solutions[row, i] <= math.pi
                    if not inside:
                        for i in range(6):
                            solutions[row, i] = _wrap(solutions[row, i])
                if represented:                                      # checked by forward
                    _exact_flange(solutions[row], constants, X)      # kinematics (_errors)
                    _pose_errors(X, X_target, errors[:, row])
                    if not (errors[0, row] <= tol and errors[1, row] <= tol):
                        for i in range(6):                           # (as finish() does)
                            solutions[row, i] = 0.0
                        continue
                elbow_singular = elbow_singular or kk / m < singular_tol
                near = near or kk / m < near_tol or sin5 < near_tol
                wrist_singular = wrist_singular or sin5 < singular_tol
                any_valid = True
    if not any_valid:                   # _reasons: the first step failing on every branch
        if shoulder_gap > tol:
            return _SHOULDER
        return _OUTER if beyond else (_INNER if within else (_REACH if clipped else _TOL))
    flags[0], flags[1], flags[2] = wrist_singular, h < singular_tol * d4, elbow_singular
    flags[3] = near or h < near_tol * d4
    return SOLVED


def _family_member(u5, v5, want, half_sum, half_diff, rep0, a2, a3, d5):
    """theta234 and theta6 of the member of a wrist family with theta234 nearest ``want``
    that the arm reaches (``dqlab._fast.ur_engine._wrist_family``): theta234 + theta6 fixed
    at ``2 half_sum`` where ``rep0`` (theta5 near 0), else theta234 - theta6 at
    ``2 half_diff``; both wrapped."""
    got = _feasible_theta234(u5, v5, want, a2, a3, d5)
    theta6 = 2.0 * half_sum - got if rep0 else got - 2.0 * half_diff
    return _wrap(got), _wrap(theta6)


def _feasible_theta234(u5, v5, want, a2, a3, d5):
    """``dqlab.ik.ur_steps.feasible_theta234`` of one wrist centre (u5, v5)."""
    norm_p = math.sqrt(u5 * u5 + v5 * v5)
    psi = math.atan2(v5, u5)
    two_d5p = 2.0 * d5 * norm_p
    u_ref = _wrap(want - psi)
    sin_ref = math.sin(u_ref)
    r_out, r_in = abs(a2 + a3), abs(a2 - a3)
    s_lo_num = norm_p * norm_p + d5 * d5 - r_out * r_out
    s_hi_num = norm_p * norm_p + d5 * d5 - r_in * r_in
    if sin_ref * two_d5p >= s_lo_num and sin_ref * two_d5p <= s_hi_num:
        return want
    best, nearest = 0.5 * math.pi, math.inf      # nothing feasible: the outer tangency
    for R, num in ((r_out, s_lo_num), (r_in, s_hi_num)):
        f = (R - norm_p + d5) * (R + norm_p - d5) * (norm_p + d5 - R) * (norm_p + d5 + R)
        if not f >= 0.0:
            continue
        c = math.sqrt(f)
        for candidate in (math.atan2(num, c), math.atan2(num, -c)):
            distance = abs(_wrap(candidate - u_ref))
            if distance < nearest:
                best, nearest = candidate, distance
    return psi + best


def _exact_flange(t, constants, X):
    """X (4, 4): forward kinematics of the exact UR of ``constants`` at the joint values t
    (6,), the product of its six standard DH transforms (twists pi/2, 0, 0, pi/2, -pi/2, 0)."""
    lengths = ((0.0, constants[0]), (constants[1], 0.0), (constants[2], 0.0),
               (0.0, constants[3]), (0.0, constants[4]), (0.0, constants[5]))   # (a, d)
    for i in range(4):
        for j in range(4):
            X[i, j] = 1.0 if i == j else 0.0
    for k in range(6):
        theta = t[k] + constants[6 + k]
        c, s = math.cos(theta), math.sin(theta)
        a, d = lengths[k]
        ca, sa = _UR_TWISTS[k]
        for i in range(3):                  # X <- X A_k, A_k's columns one by one
            x0, x1, x2 = X[i, 0], X[i, 1], X[i, 2]
            X[i, 0] = x0 * c + x1 * s
            X[i, 1] = -x0 * s * ca + x1 * c * ca + x2 * sa
            X[i, 2] = x0 * s * sa - x1 * c * sa + x2 * ca
            X[i, 3] = X[i, 3] + x0 * a * c + x1 * a * s + x2 * d


def _one_pose(links, tool, q_start, found, X_0T, tol, stop, plain, max_iter, give_up_after,
              damping, max_step, singular_tol, d4, near, near_singular, solutions, valid, pe,
              re, flags):
    """:func:`one_pose`'s work: False as soon as the pose needs the array path."""
    for r in range(8):
        if not found[r] and pe[r] <= near:
            return False
    rows = np.flatnonzero(found)
    if rows.shape[0] == 0:
        return False
    k = rows.shape[0]
    q, X_target = np.empty((k, 6)), np.empty((k, 4, 4))
    for j in range(k):
        q[j] = q_start[rows[j]]
        X_target[j] = X_0T
    converged, X = np.zeros(k, dtype=np.bool_), np.zeros((k, 4, 4))
    measures, errors = np.zeros((3, k)), np.zeros((2, k))
    _kernel(links, tool, q, X_target, stop, plain, max_iter, give_up_after, damping,
            max_step, converged, X, measures, errors)
    for j in range(k):
        if not converged[j]:
            return False
        for i in range(j):
            if _same(q[i], q[j]):
                return False
    exact = np.zeros(8, dtype=np.bool_)                 # the exact arm's own solutions
    for r in range(8):
        exact[r] = found[r] and pe[r] <= tol
    for j in range(k):
        r = rows[j]
        pe[r], re[r] = errors[0, j], errors[1, j]
        if pe[r] <= tol and re[r] <= tol:
            valid[r] = True
            for i in range(6):
                solutions[r, i] = _wrap(q[j, i])
            flags[0] = flags[0] or measures[0, j] < singular_tol
            flags[1] = flags[1] or measures[2, j] / d4 < singular_tol
            flags[2] = flags[2] or measures[1, j] < singular_tol
            flags[3] = flags[3] or min(min(measures[0, j], measures[1, j]),
                                       measures[2, j] / d4) < near_singular
    flags[4] = True
    for r in range(8):
        flags[4] = flags[4] and not valid[r]
        flags[5] = flags[5] or (exact[r] and not valid[r])
    return True


def _load(links, q, X_target, rows, S):
    """Lanes 0..W-1 of S from the rows ``rows`` (W,): joints, cosines and sines of the
    joint angles, targets; every lane active."""
    for r in range(W):
        row = rows[r]
        for i in range(6):
            S[(_Q + i) * W + r] = q[row, i]
        for i in range(3):
            for j in range(3):
                S[(_T + 3 * i + j) * W + r] = X_target[row, i, j]
            S[(_TP + i) * W + r] = X_target[row, i, 3]
        S[_ACT * W + r] = 1.0
    lane_angles(S, links)


def _long_step(S):
    """Whether a lane's joint took a step of 0.02 rad or more (or not a number): then the
    cosines and sines of such joints come from their new angle, all lanes at once
    (``newton_lanes.recompute``; the Taylor series of the lanes' step is for short
    steps)."""
    for k in range(_X * W, (_X + 6) * W):
        if not abs(S[k]) < 0.02:
            return True
    return False


def _kernel(links, tool, q, X_target, stop, plain, max_iter, give_up_after, damping,
            max_step, converged, X, measures, errors):
    """Every branch (rows of q, in place), W at a time: the plain steps of all lanes, then
    each lane stepped while its rule says go on (the others take steps of 0)."""
    S = np.empty(NV * W)                                # (every entry written before read)
    F = np.empty(48)
    size, before0, before1 = np.empty(W), np.empty(W), np.empty(W)
    going = np.zeros(W, dtype=np.bool_)
    rows = np.empty(W, dtype=np.int64)
    m = q.shape[0]
    for first in range(0, m, W):
        n = min(W, m - first)
        for r in range(W):
            rows[r] = first + min(r, n - 1)                 # extra lanes repeat the last row
        _load(links, q, X_target, rows, S)
        for _ in range(plain):
            lane_frames(S, links, tool)
            lane_step(S, damping, max_step)
            if _long_step(S):
                lane_recompute(S, links)
        lane_frames(S, links, tool)
        lane_size(S)
        more = False
        for r in range(W):
            size[r] = S[_SIZE * W + r]
            going[r] = size[r] > stop and plain < max_iter
            if going[r]:
                size[r], before0[r], before1[r] = math.inf, math.inf, math.inf
                more = True
        iteration = plain
        while more:
            more = False
            for r in range(W):
                if going[r]:
                    before0[r], before1[r] = before1[r], size[r]
                    size[r] = S[_SIZE * W + r]
                    keep = size[r] > stop
                    if iteration >= give_up_after:
                        keep = keep and size[r] < 0.5 * before0[r]
                    going[r] = keep and iteration < max_iter
                    more = more or going[r]
                S[_ACT * W + r] = 1.0 if going[r] else 0.0
            if not more:
                break
            lane_step(S, damping, max_step)
            if _long_step(S):
                lane_recompute(S, links)
            lane_frames(S, links, tool)
            lane_size(S)
            iteration += 1
        lost = False
        for r in range(W):
            for i in range(6):
                if not math.isfinite(S[(_Q + i) * W + r]):  # a step that overflowed: back
                    S[(_Q + i) * W + r] = 0.0               # to 0, and its frames again
                    lost = True
        if lost:
            lane_angles(S, links)
            lane_frames(S, links, tool)
        for r in range(n):
            row = first + r
            converged[row] = size[r] <= stop
            for i in range(6):
                q[row, i] = S[(_Q + i) * W + r]
            for k in range(48):
                F[k] = S[(_F + k) * W + r]
            _outputs(F, X_target, X, measures, errors, row)


def _outputs(F, X_target, X, measures, errors, row):
    """Row ``row`` of the TCP poses X (m, 4, 4), the singularity measures (3, m) and the
    pose errors (2, m) against ``X_target[row]``, from a branch's frames F."""
    for i in range(3):
        for j in range(3):
            X[row, i, j] = F[39 + 3 * i + j]
        X[row, i, 3] = F[36 + i]
    X[row, 3, 3] = 1.0
    z3x, z3y, z3z = F[6], F[7], F[8]                    # |z3 x z5|, |x2 x x3|, shoulder
    z5x, z5y, z5z = F[12], F[13], F[14]
    measures[0, row] = math.sqrt((z3y * z5z - z3z * z5y) ** 2 + (z3z * z5x - z3x * z5z) ** 2
                                 + (z3x * z5y - z3y * z5x) ** 2)
    ax, ay, az, bx, by, bz = F[30], F[31], F[32], F[33], F[34], F[35]
    measures[1, row] = math.sqrt((ay * bz - az * by) ** 2 + (az * bx - ax * bz) ** 2
                                 + (ax * by - ay * bx) ** 2)
    measures[2, row] = abs(F[0] * F[28] - F[1] * F[27]) / math.hypot(F[0], F[1])
    _pose_errors(X[row], X_target[row], errors[:, row])


def _pose_errors(X, X_target, out):
    """out (2,): ``dqlab._formulas.pose_error_entries`` of X and X_target (4, 4)."""
    dx, dy, dz = X[0, 3] - X_target[0, 3], X[1, 3] - X_target[1, 3], X[2, 3] - X_target[2, 3]
    vx = _dot_rows(X, 1, X_target, 2) - _dot_rows(X, 2, X_target, 1)
    vy = _dot_rows(X, 2, X_target, 0) - _dot_rows(X, 0, X_target, 2)
    vz = _dot_rows(X, 0, X_target, 1) - _dot_rows(X, 1, X_target, 0)
    trace = _dot_rows(X, 0, X_target, 0) + _dot_rows(X, 1, X_target, 1) \
        + _dot_rows(X, 2, X_target, 2)
    out[0] = math.sqrt(dx * dx + dy * dy + dz * dz)
    out[1] = math.atan2(math.sqrt(vx * vx + vy * vy + vz * vz), trace - 1.0)


def _dot_rows(A, i, B, j):
    """M_ij = R_i . R*_j: row i of A's rotation dotted with row j of B's."""
    return A[i, 0] * B[j, 0] + A[i, 1] * B[j, 1] + A[i, 2] * B[j, 2]


# --------------------------------------------------------------------------------------
# The repairs of ``dqlab.ik.ur_calibrated`` (_repair, _family, _deflate), compiled


def repairs(links, tool, exact, theta6_ref, wide, singular_tol, near_wrist, near_tol, q, done,
            converged, X, measures, errors, q0, found, X_0T, X_T6, X_06, tol, max_iter, *,
            restart_iter, restart_give_up, plain, stop_factor, give_up_after, damping,
            max_step, ways, near_ratio, family, deflation_ways, deflation_iter):
    """``_repair``, ``_family`` and ``_deflate`` of ``dqlab.ik.ur_calibrated`` compiled, step
    by step as those functions take them, each step's starts of every pose stepped together:
    the restarts of the branches missing from each pose (the corrected closed
    form, the flips, the moves along the most singular direction), the wrist family's
    members as starts, and deflated Newton; the arrays of its ``_Polished`` (``q``,
    ``done``, ``converged``, ``X``, ``measures``, ``errors``; C-contiguous) updated in
    place. ``exact`` the nearest exact arm's constants, ``theta6_ref`` (n,) the theta6 of
    each pose's reference (0 without one), ``wide``, ``singular_tol``, ``near_tol`` the
    tolerances of its closed form; ``q0`` (8 n, 6) the branches' starts, ``found`` (8 n,)
    those the exact arm found, ``X_0T``, ``X_06`` (n, 4, 4) the targets and flanges;
    ``restart_iter`` and ``restart_give_up`` a restart's Newton steps at most and after
    which it must keep halving its error, ``deflation_iter`` the deflated steps at most;
    ``ways`` the moves along the most singular direction of ``_repair``,
    ``deflation_ways`` those of ``_deflate``, ``near_ratio`` the eigenvalue ratio below
    which a joint vector is near a singularity, ``family`` the wrist family's numbers
    (members, ``_NEAR_MEASURE``, ``_FEW_BRANCHES``, ``_FEW_WRIST``, the closed form's
    tolerance and near_tol for them). The same steps in the same order as those functions
    (tested equal to the rounding); the most singular direction by inverse iteration where
    it is certain, by Jacobi's method elsewhere (``numpy.linalg.eigh``'s answer)."""
    unique = np.empty(converged.shape[0], dtype=np.bool_)
    _unique(q, converged, unique)
    members, near_measure, few_branches, few_wrist, member_tol, member_near = family
    _repairs(np.asarray(links, dtype=float), np.ascontiguousarray(tool, dtype=float),
             np.asarray(exact, dtype=float), np.ascontiguousarray(theta6_ref, dtype=float),
             float(wide), float(singular_tol), float(near_wrist), float(near_tol), q, done,
             converged, X, measures, errors, np.ascontiguousarray(q0, dtype=float),
             np.ascontiguousarray(found), np.ascontiguousarray(X_0T, dtype=float),
             np.ascontiguousarray(X_T6, dtype=float), np.ascontiguousarray(X_06, dtype=float),
             unique, float(tol), float(stop_factor * tol),
             int(min(plain, restart_iter, max_iter)), int(min(max_iter, restart_iter)),
             int(restart_give_up), float(damping), float(max_step),
             np.asarray(ways, dtype=float), float(near_ratio),
             (int(members), float(near_measure), int(few_branches), float(few_wrist),
              float(member_tol), float(member_near)),
             np.asarray(deflation_ways, dtype=float), int(min(max_iter, deflation_iter)),
             int(give_up_after))


def array_poses(links, tool, exact, X_06, X_0T, X_T6, theta6_ref, tol, wide, singular_tol,
                near_wrist, near_tol, max_iter, *, restart_iter, restart_give_up, plain,
                stop_factor, give_up_after, damping, max_step, ways, near_ratio, family,
                deflation_ways, deflation_iter, polish_near):
    """The array path of ``dqlab.ik.ur_calibrated.calibrated_ur`` for a few poses, compiled
    pose by pose, up to the search beyond the rows: the exact arm's closed form of each
    flange ``X_06`` (n, 4, 4) (tolerance ``wide``, the references' ``theta6_ref`` (n,)),
    its branches missed by a little solved again at ten times ``wide``, Newton from them
    towards ``X_0T`` (n, 4, 4), the repairs of :func:`repairs`, the polish of the valid rows
    within ``polish_near`` of a singularity of the exact arm, and the flags. None when a
    wrist centre is far beyond reach (the caller's array path); else the solutions (n, 8,
    6) (wrapped; rows not valid as the steps left them), ``valid`` (n, 8), the position and
    rotation errors (n, 8) each, the flags (n, 6) (wrist, shoulder and elbow singular, near
    singular, unreachable, not converged), how the closed form of each pose ended (n,),
    with whether it found a branch (n,) (for the reason of a pose with no valid row), and
    the rows made invalid as repeats of a row of lower number (n, 8). The same steps in the
    same order as that path (tested equal)."""
    n = X_0T.shape[0]
    solutions, valid = np.zeros((n, 8, 6)), np.zeros((n, 8), dtype=np.bool_)
    errors, flags = np.zeros((n, 2, 8)), np.zeros((n, 6), dtype=np.bool_)
    ended, started = np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.bool_)
    repeated = np.zeros((n, 8), dtype=np.bool_)
    members, near_measure, few_branches, few_wrist, member_tol, member_near = family
    done = _array_poses(np.asarray(links, dtype=float), np.ascontiguousarray(tool, dtype=float),
                        np.asarray(exact, dtype=float), np.ascontiguousarray(X_06, dtype=float),
                        np.ascontiguousarray(X_0T, dtype=float),
                        np.ascontiguousarray(X_T6, dtype=float),
                        np.ascontiguousarray(theta6_ref, dtype=float), float(tol), float(wide),
                        float(singular_tol), float(near_wrist), float(near_tol),
                        float(stop_factor * tol), int(min(plain, max_iter)), int(max_iter),
                        int(min(plain, restart_iter, max_iter)),
                        int(min(max_iter, restart_iter)), int(give_up_after),
                        int(restart_give_up), float(damping),
                        float(max_step), np.asarray(ways, dtype=float), float(near_ratio),
                        (int(members), float(near_measure), int(few_branches),
                         float(few_wrist), float(member_tol), float(member_near)),
                        np.asarray(deflation_ways, dtype=float),
                        int(min(max_iter, deflation_iter)), float(polish_near),
                        int(plain), solutions, valid, errors, flags, ended, started, repeated)
    if not done:
        return None
    return solutions, valid, errors[:, 0], errors[:, 1], flags, ended, started, repeated


def array_start(links, tool, exact, X_06, X_0T, theta6_ref, tol, wide, singular_tol,
                near_wrist, near_tol, max_iter, *, plain, stop_factor, give_up_after, damping,
                max_step):
    """The first steps of :func:`array_poses` for any number of poses, pose by pose, for a
    caller that repairs the rows between this and :func:`array_finish`
    (:func:`repairs`): the closed form, its branches missed by a little solved again,
    Newton from them. None when a wrist centre is far beyond reach;
    else the arrays of ``dqlab.ik.ur_calibrated._Polished`` (``q`` (8 n, 6), ``done``,
    ``converged`` (8 n,), ``X`` (8 n, 4, 4), ``measures`` (3, 8 n), ``errors`` (2, 8 n)),
    the starts ``q0`` (8 n, 6), the branches ``found`` (8 n,), the closed form's errors
    (2, 8 n) and near flags (n,), how it ended (n,) and whether it started each pose (n,),
    for :func:`array_finish`."""
    n = X_0T.shape[0]
    q, done, converged = np.zeros((8 * n, 6)), np.zeros(8 * n, dtype=np.bool_), \
        np.zeros(8 * n, dtype=np.bool_)
    X, measures, errors = np.zeros((8 * n, 4, 4)), np.zeros((3, 8 * n)), np.zeros((2, 8 * n))
    q0, found = np.zeros((8 * n, 6)), np.zeros(8 * n, dtype=np.bool_)
    start_errors, start_near = np.zeros((2, 8 * n)), np.zeros(n, dtype=np.bool_)
    ended, started = np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.bool_)
    if not _array_start(np.asarray(links, dtype=float), np.ascontiguousarray(tool, dtype=float),
                        np.asarray(exact, dtype=float), np.ascontiguousarray(X_06, dtype=float),
                        np.ascontiguousarray(X_0T, dtype=float),
                        np.ascontiguousarray(theta6_ref, dtype=float), float(tol), float(wide),
                        float(singular_tol), float(near_wrist), float(near_tol),
                        float(stop_factor * tol), int(min(plain, max_iter)), int(max_iter),
                        int(give_up_after), float(damping), float(max_step), q, done,
                        converged, X, measures, errors, q0, found, start_errors, start_near,
                        ended, started):
        return None
    return (q, done, converged, X, measures, errors, q0, found, start_errors, start_near, ended,
            started)


def array_finish(links, tool, exact, X_0T, tol, singular_tol, near_tol, q, done, converged,
                 measures, errors, found, start_errors, start_near, *, plain, stop_factor,
                 give_up_after, damping, max_step, polish_near):
    """The last steps of :func:`array_poses`, pose by pose, after the repairs, from the
    arrays of :func:`array_start` (repaired): the solutions (n, 8, 6) (wrapped), ``valid``
    (n, 8), the position and rotation errors (n, 8) each, the flags (n, 6), how near a
    singularity of the exact arm each row is (8 n,) (``dqlab.ik.ur_calibrated._nearness``)
    and the rows made invalid as repeats (n, 8) (both for the search beyond the rows)."""
    n = X_0T.shape[0]
    solutions, valid = np.zeros((n, 8, 6)), np.zeros((n, 8), dtype=np.bool_)
    pose_errors, flags = np.zeros((n, 2, 8)), np.zeros((n, 6), dtype=np.bool_)
    nearness, repeated = np.empty(8 * n), np.zeros((n, 8), dtype=np.bool_)
    _array_finish(np.asarray(links, dtype=float), np.ascontiguousarray(tool, dtype=float),
                  np.asarray(exact, dtype=float), np.ascontiguousarray(X_0T, dtype=float),
                  float(tol), float(singular_tol), float(near_tol), float(stop_factor * tol),
                  int(give_up_after), float(damping), float(max_step), float(polish_near),
                  int(plain), q, done, converged, measures, errors, found, start_errors,
                  start_near, solutions, valid, pose_errors, flags, nearness, repeated)
    return solutions, valid, pose_errors[:, 0], pose_errors[:, 1], flags, nearness, repeated


def _array_poses(links, tool, exact, X_06, X_0T, X_T6, theta6_ref, tol, wide, singular_tol,
                 near_wrist, near_tol, stop, plain, max_iter, restart_plain, restart_iter,
                 give_up_after, restart_give_up, damping, max_step, ways, near_ratio, family,
                 deflation_ways, deflation_steps, polish_near, polish_steps, solutions, valid,
                 errors, flags, ended, started, repeated):
    """:func:`array_poses`' work: False as soon as a wrist centre is far beyond reach."""
    n = X_0T.shape[0]
    q, done, converged = np.zeros((8 * n, 6)), np.zeros(8 * n, dtype=np.bool_), \
        np.zeros(8 * n, dtype=np.bool_)
    X, measures, steps_errors = np.zeros((8 * n, 4, 4)), np.zeros((3, 8 * n)), \
        np.zeros((2, 8 * n))
    q0, found = np.zeros((8 * n, 6)), np.zeros(8 * n, dtype=np.bool_)
    start_errors, start_near = np.zeros((2, 8 * n)), np.zeros(n, dtype=np.bool_)
    if not _array_start(links, tool, exact, X_06, X_0T, theta6_ref, tol, wide, singular_tol,
                        near_wrist, near_tol, stop, plain, max_iter, give_up_after, damping,
                        max_step, q, done, converged, X, measures, steps_errors, q0, found,
                        start_errors, start_near, ended, started):
        return False
    unique = np.empty(8 * n, dtype=np.bool_)            # steps 4: the repairs
    _unique(q, converged, unique)
    _repairs(links, tool, exact, theta6_ref, wide, singular_tol, near_wrist, near_tol, q, done,
             converged, X, measures, steps_errors, q0, found, X_0T, X_T6, X_06, unique, tol,
             stop, restart_plain, restart_iter, restart_give_up, damping, max_step, ways,
             near_ratio, family, deflation_ways, deflation_steps, give_up_after)
    nearness = np.empty(8 * n)
    _array_finish(links, tool, exact, X_0T, tol, singular_tol, near_tol, stop, give_up_after,
                  damping, max_step, polish_near, polish_steps, q, done, converged, measures,
                  steps_errors, found, start_errors, start_near, solutions, valid, errors,
                  flags, nearness, repeated)
    return True


def _array_start(links, tool, exact, X_06, X_0T, theta6_ref, tol, wide, singular_tol,
                 near_wrist, near_tol, stop, plain, max_iter, give_up_after, damping, max_step,
                 q, done, converged, X, measures, steps_errors, q0, found, start_errors,
                 start_near, ended, started):
    """The array path's first steps, pose by pose: the exact arm's closed form, its branches
    missed by a little solved again, Newton from them (``_Polished``'s arrays ``q``,
    ``done``, ``converged``, ``X``, ``measures``, ``steps_errors`` filled, with the starts
    ``q0``, the branches ``found``, the closed form's errors, near flags, ends and whether
    it started each pose). False as soon as a wrist centre is far beyond reach."""
    n = X_0T.shape[0]
    start_flags, flags_again = np.zeros(4, dtype=np.bool_), np.zeros(4, dtype=np.bool_)
    e, again, e2 = np.zeros((2, 8)), np.zeros((8, 6)), np.zeros((2, 8))
    rows, unique = np.empty(8, dtype=np.int64), np.empty(8, dtype=np.bool_)
    qs, targets = np.empty((8, 6)), np.empty((8, 4, 4))
    ok, Xs = np.zeros(8, dtype=np.bool_), np.zeros((8, 4, 4))
    ms, es = np.zeros((3, 8)), np.zeros((2, 8))
    extra = np.empty(8 * n, dtype=np.int64)             # the branches missed by a little
    x = 0
    for pose in range(n):                               # the exact arm's closed form
        base = 8 * pose
        C = X_06[pose]
        qw, qx, qy, qz = _quaternion(C)
        start_flags[:] = False
        e[:] = 0.0
        ended[pose] = _exact_one_pose(qw, qx, qy, qz, C[0, 3], C[1, 3], C[2, 3], C[0, 2],
                                      C[1, 2], C[2, 2], C, theta6_ref[pose], exact, wide,
                                      singular_tol, near_wrist, near_tol, q0[base:base + 8], e,
                                      start_flags)
        if ended[pose] == 0:
            return False
        start_near[pose] = start_flags[3]
        near_any = False
        for k in range(8):
            r = base + k
            start_errors[0, r], start_errors[1, r] = e[0, k], e[1, k]
            found[r] = e[0, k] <= wide and e[1, k] <= wide
            if found[r]:
                if e[0, k] > tol:                               # (a clipped row)
                    _off_the_edge(q0, r, k, e[0, k], exact)
                started[pose] = True
            near_any = near_any or (not found[r] and e[0, k] <= 10.0 * wide)
        if near_any:                                    # solved again at ten times wide
            again[:], e2[:] = 0.0, 0.0
            _exact_one_pose(qw, qx, qy, qz, C[0, 3], C[1, 3], C[2, 3], C[0, 2], C[1, 2],
                            C[2, 2], C, theta6_ref[pose], exact, 10.0 * wide, singular_tol,
                            near_wrist, near_tol, again, e2, flags_again)
            for k in range(8):
                r = base + k
                if (not found[r] and e[0, k] <= 10.0 * wide and e2[0, k] <= 10.0 * wide
                        and e2[1, k] <= 10.0 * wide):
                    if e2[0, k] > tol:                          # (a clipped row)
                        _off_the_edge(again, k, k, e2[0, k], exact)
                    for i in range(6):
                        q0[r, i] = again[k, i]
                    done[r] = True
                    extra[x] = r
                    x += 1
        m = 0                                           # Newton: the found branches
        for k in range(8):
            if found[base + k]:
                rows[m] = base + k
                for i in range(6):
                    qs[m, i] = q0[base + k, i]
                for i in range(4):
                    for j in range(4):
                        targets[m, i, j] = X_0T[pose, i, j]
                m += 1
        if m:
            _kernel(links, tool, qs[:m], targets[:m], stop, plain, max_iter, give_up_after,
                    damping, max_step, ok[:m], Xs[:m], ms[:, :m], es[:, :m])
        for j in range(m):                              # (entry by entry: no views)
            r = rows[j]
            converged[r], done[r] = ok[j], True
            for i in range(6):
                q[r, i] = qs[j, i]
            for i in range(4):
                for k in range(4):
                    X[r, i, k] = Xs[j, i, k]
            for i in range(3):
                measures[i, r] = ms[i, j]
            steps_errors[0, r], steps_errors[1, r] = es[0, j], es[1, j]
    if x == 0:
        return True
    # then those missed by a little, all together (they seldom converge, and each group of
    # eight branches that the kernel takes together runs as long as its slowest)
    q_x, targets_x = np.empty((x, 6)), np.empty((x, 4, 4))
    for j in range(x):
        q_x[j], targets_x[j] = q0[extra[j]], X_0T[extra[j] // 8]
    ok_x, X_x = np.zeros(x, dtype=np.bool_), np.zeros((x, 4, 4))
    ms_x, es_x = np.zeros((3, x)), np.zeros((2, x))
    _kernel(links, tool, q_x, targets_x, stop, plain, max_iter, give_up_after, damping,
            max_step, ok_x, X_x, ms_x, es_x)
    for j in range(x):
        r = extra[j]
        q[r], converged[r], X[r] = q_x[j], ok_x[j], X_x[j]
        measures[:, r], steps_errors[:, r] = ms_x[:, j], es_x[:, j]
    whole = np.zeros(8 * n, dtype=np.bool_)             # an extra row is kept if new
    new = np.empty(1, dtype=np.bool_)
    j = 0
    while j < x:
        base = 8 * (extra[j] // 8)
        _unique(q[base:base + 8], converged[base:base + 8], unique)
        for k in range(8):
            whole[base + k] = unique[k] and found[base + k]
        while j < x and extra[j] < base + 8:            # (extra: by pose, in order)
            _are_new(extra[j:j + 1], q[extra[j:j + 1]], q, whole, new)
            converged[extra[j]] = converged[extra[j]] and new[0]
            j += 1
    return True


def _array_finish(links, tool, exact, X_0T, tol, singular_tol, near_tol, stop, give_up_after,
                  damping, max_step, polish_near, polish_steps, q, done, converged, measures,
                  steps_errors, found, start_errors, start_near, solutions, valid, errors,
                  flags, nearness, repeated):
    """The array path's last steps, pose by pose, after the repairs: each row's errors
    (Newton's where it ran, else the closed form's) and validity, the polish of the valid
    rows within ``polish_near`` of a singularity of the exact arm, the rows on a solution a
    row of lower number has (``repeated``, made invalid), the flags, and how near such a
    singularity each row is (``nearness``, infinite where not valid: ``_nearness`` of the
    rows polished)."""
    n = X_0T.shape[0]
    d4 = exact[3]
    distinct = np.empty(8, dtype=np.bool_)
    for pose in range(n):                               # errors, validity, polish, flags
        base = 8 * pose
        f = flags[pose]
        m = 0
        for k in range(8):
            r = base + k
            pe = steps_errors[0, r] if done[r] else start_errors[0, r]
            re = steps_errors[1, r] if done[r] else start_errors[1, r]
            errors[pose, 0, k], errors[pose, 1, k] = pe, re
            valid[pose, k] = converged[r] and pe <= tol and re <= tol
            for i in range(6):
                solutions[pose, k, i] = _wrap(q[r, i])
            nearness[r] = _row_nearness(solutions[pose, k], exact) if valid[pose, k] \
                else math.inf
            m += nearness[r] < polish_near
        if m:                                           # _polish
            rows = np.empty(m, dtype=np.int64)
            m = 0
            for k in range(8):
                if nearness[base + k] < polish_near:
                    rows[m] = k
                    m += 1
            qs, targets = np.empty((m, 6)), np.empty((m, 4, 4))
            for j in range(m):
                qs[j], targets[j] = solutions[pose, rows[j]], X_0T[pose]
            ok, Xs = np.zeros(m, dtype=np.bool_), np.zeros((m, 4, 4))
            ms, es = np.zeros((3, m)), np.zeros((2, m))
            _kernel(links, tool, qs, targets, stop, polish_steps, polish_steps, give_up_after,
                    damping, max_step, ok, Xs, ms, es)
            for j in range(m):
                finite = True
                for i in range(6):
                    finite = finite and math.isfinite(qs[j, i])
                if es[0, j] <= tol and es[1, j] <= tol and finite:
                    k = rows[j]
                    for i in range(6):
                        solutions[pose, k, i] = _wrap(qs[j, i])
                    errors[pose, 0, k], errors[pose, 1, k] = es[0, j], es[1, j]
                    nearness[base + k] = _row_nearness(solutions[pose, k], exact)
        _unique(solutions[pose], valid[pose], distinct)  # a row on another's solution
        for k in range(8):
            if valid[pose, k] and not distinct[k]:
                valid[pose, k] = False
                repeated[pose, k] = True
                nearness[base + k] = math.inf
        any_valid = False                               # _flags
        for k in range(8):
            r = base + k
            if valid[pose, k]:
                any_valid = True
                f[0] = f[0] or measures[0, r] < singular_tol
                f[1] = f[1] or measures[2, r] / d4 < singular_tol
                f[2] = f[2] or measures[1, r] < singular_tol
                f[3] = f[3] or min(min(measures[0, r], measures[1, r]),
                                   measures[2, r] / d4) < near_tol
            f[5] = f[5] or (found[r] and start_errors[0, r] <= tol and not valid[pose, k])
            f[3] = f[3] or nearness[r] < near_tol
        f[4] = not any_valid
        f[3] = f[3] or start_near[pose]


def _repairs(links, tool, exact, theta6_ref, wide, singular_tol, near_wrist, near_tol, q, done,
             converged, X, measures, errors, q0, found, X_0T, X_T6, X_06, unique, tol, stop,
             plain, max_iter, give_up_after, damping, max_step, ways, near_ratio, family,
             deflation_ways, deflation_steps, deflation_give_up):
    """:func:`repairs`' work, step by step as the numpy path takes them: each step gathers
    the starts of every pose (pose by pose: the poses are independent), then steps them all
    together, so that the kernel's lanes are full (:func:`_run`), and offers each pose's
    solutions to its rows in the order of its starts."""
    n = X_0T.shape[0]
    state = (links, tool, X_0T, stop, plain, max_iter, give_up_after, damping, max_step, q,
             done, converged, X, measures, errors, unique)
    missing = np.zeros(n, dtype=np.bool_)               # _repair: the corrected closed form
    queue = _queue(8 * n)
    for pose in range(n):
        for k in range(8):
            missing[pose] = missing[pose] or (done[8 * pose + k] and not unique[8 * pose + k])
        if missing[pose]:
            owners, starts = _corrected_starts(pose, exact, theta6_ref[pose], wide,
                                               singular_tol, near_wrist, near_tol, X_T6, state)
            queue = _push(queue, pose, owners, starts, np.arange(owners.shape[0]))
    _run(queue, state)
    wanted = np.empty(8, dtype=np.int64)                # the flips
    queue = _cleared(queue)
    for pose in range(n):
        w = _wanted(pose, done, unique, found, False, wanted) if missing[pose] else 0
        if w:
            owners, starts = _flip_starts(wanted[:w], exact, q, unique)
            queue = _push(queue, pose, owners, starts, np.arange(owners.shape[0]))
    _run(queue, state)
    queue = _cleared(queue)                             # the moves
    for pose in range(n):
        w = _wanted(pose, done, unique, found, True, wanted) if missing[pose] else 0
        if w:
            owners, starts, which = _move_starts(wanted[:w], q0, ways, near_ratio, links, tool,
                                                 q, converged, unique)
            queue = _push(queue, pose, owners, starts, which)
    _run(queue, state)
    queue = _cleared(queue)                             # _family
    for pose in range(n):
        count = 0 if _full(unique, 8 * pose) else _family_count(pose, exact, family, q,
                                                                  done, converged, unique)
        if count:
            owners, starts, which = _family_starts(pose, count, exact, X_06[pose],
                                                   singular_tol, near_wrist, family, tol,
                                                   unique)
            queue = _push(queue, pose, owners, starts, which)
    _run(queue, state)
    _deflation(exact, deflation_ways, near_ratio, family[1], deflation_steps, deflation_give_up,
               state)


def _queue(size):
    """An empty queue of restarts for :func:`_run`: the rows offered a solution (``owners``),
    the start each is offered (``which``), the starts and their poses, and how many of
    each there are; room for ``size`` of each, grown as needed (:func:`_push`)."""
    return (np.empty(size, dtype=np.int64), np.empty(size, dtype=np.int64),
            np.empty((size, 6)), np.empty(size, dtype=np.int64), np.zeros(2, dtype=np.int64))


def _cleared(queue):
    """The queue emptied (its room kept)."""
    queue[4][:] = 0
    return queue


def _push(queue, pose, owners, starts, which):
    """The queue with the restarts of one pose appended: ``owners[j]`` offered start
    ``which[j]`` of ``starts`` (which become the queue's next starts, of ``pose``; a start
    equal to one before it is queued once, and its owners offered that one, as
    ``dqlab.ik.ur_calibrated._stepped_once`` does); the arrays of the queue grown (twice
    their size) when full."""
    queued_owners, queued_which, queued_starts, poses, count = queue
    o, s = count[0], count[1]
    if o + owners.shape[0] > queued_owners.shape[0]:
        size = max(2 * queued_owners.shape[0], o + owners.shape[0])
        grown_owners, grown_which = np.empty(size, dtype=np.int64), np.empty(size, np.int64)
        grown_owners[:o], grown_which[:o] = queued_owners[:o], queued_which[:o]
        queued_owners, queued_which = grown_owners, grown_which
    if s + starts.shape[0] > queued_starts.shape[0]:
        size = max(2 * queued_starts.shape[0], s + starts.shape[0])
        grown_starts, grown_poses = np.empty((size, 6)), np.empty(size, dtype=np.int64)
        grown_starts[:s], grown_poses[:s] = queued_starts[:s], poses[:s]
        queued_starts, poses = grown_starts, grown_poses
    place = np.empty(starts.shape[0], dtype=np.int64)  # where each start is queued
    kept = s
    for j in range(starts.shape[0]):
        place[j] = kept
        for i in range(s, kept):
            if _equal(queued_starts, i, starts, j):
                place[j] = i
                break
        if place[j] == kept:
            for k in range(6):
                queued_starts[kept, k] = starts[j, k]
            poses[kept] = pose
            kept += 1
    for j in range(owners.shape[0]):
        queued_owners[o + j], queued_which[o + j] = owners[j], place[which[j]]
    count[0], count[1] = o + owners.shape[0], kept
    return queued_owners, queued_which, queued_starts, poses, count


def _equal(A, i, B, j):
    """Whether rows A[i] and B[j] (6,) are the same joint vector, joint by joint."""
    for k in range(6):
        if A[i, k] != B[j, k]:
            return False
    return True


def _run(queue, state):
    """``dqlab.ik.ur_calibrated._restart`` of the queued restarts: Newton from every start
    towards its pose, eight at a time, then row ``owners[j]`` offered the solution from
    start ``which[j]`` in the queue's order; the first that converges to a solution its
    pose does not have replaces the row."""
    (links, tool, X_0T, stop, plain, max_iter, give_up_after, damping, max_step, q, done,
     converged, X, measures, errors, unique) = state
    owners, which, starts, poses, count = queue
    o, m = count[0], count[1]
    if o == 0:
        return
    q_new = starts[:m].copy()
    targets = np.empty((m, 4, 4))
    for i in range(m):
        targets[i] = X_0T[poses[i]]
    ok = np.zeros(m, dtype=np.bool_)
    X_new, measures_new, errors_new = np.zeros((m, 4, 4)), np.zeros((3, m)), np.zeros((2, m))
    _kernel(links, tool, q_new, targets, stop, plain, max_iter, give_up_after, damping,
            max_step, ok, X_new, measures_new, errors_new)
    offered = np.empty((o, 6))
    offered_ok = np.empty(o, dtype=np.bool_)
    for j in range(o):
        offered[j] = q_new[which[j]]
        offered_ok[j] = ok[which[j]]
    taken = np.empty(o, dtype=np.int64)
    for t in taken[:_accept(owners[:o], offered_ok, offered, q, unique, taken)]:
        row, s = owners[t], which[t]
        converged[row] = done[row] = True
        X[row] = X_new[s]
        measures[:, row] = measures_new[:, s]
        errors[:, row] = errors_new[:, s]


def _wanted(pose, done, unique, found, only_found, out):
    """The rows of ``pose`` missing a branch (done, not unique; and ``found`` by the exact
    arm if ``only_found``) into ``out``; how many."""
    w = 0
    for k in range(8):
        r = 8 * pose + k
        if done[r] and not unique[r] and (found[r] or not only_found):
            out[w] = r
            w += 1
    return w


def _corrected_starts(pose, exact, theta6_ref, wide, singular_tol, near_wrist, near_tol, X_T6,
                      state):
    """_repair's first restarts of one pose: the exact arm's solutions of the pose corrected
    by the two arms' difference at its first solution, for its missing branches (owners
    and starts)."""
    X_0T, q, done, X, unique = state[2][pose], state[9], state[10], state[12], state[15]
    base = 8 * pose
    owners, starts = np.empty(8, dtype=np.int64), np.empty((8, 6))
    first = -1
    for k in range(8):
        if unique[base + k]:
            first = base + k
            break
    if first < 0:
        return owners[:0], starts[:0]
    X_cal6 = _times4(X[first], X_T6)                    # the calibrated flange at q*
    X_exact6 = np.empty((4, 4))
    _exact_flange(q[first], exact, X_exact6)
    C = _times4(_times4(_times4(X_0T, X_T6), _rigid_inverse(X_cal6)), X_exact6)
    qw, qx, qy, qz = _quaternion(C)
    solutions, errs = np.zeros((8, 6)), np.zeros((2, 8))
    flags = np.zeros(4, dtype=np.bool_)
    ended = _exact_one_pose(qw, qx, qy, qz, C[0, 3], C[1, 3], C[2, 3], C[0, 2], C[1, 2],
                            C[2, 2], C, theta6_ref, exact, wide, singular_tol, near_wrist,
                            near_tol, solutions, errs, flags)
    m = 0
    for k in range(8):
        if (ended == SOLVED and errs[0, k] <= wide and errs[1, k] <= wide
                and done[base + k] and not unique[base + k]):
            owners[m] = base + k
            starts[m] = solutions[k]
            m += 1
    return owners[:m], starts[:m]


def _flip_starts(wanted, exact, q, unique):
    """_repair's second restarts: each missing branch from its siblings' solutions flipped
    at the exact arm's elbow, wrist, and both (``_flip``); owners and starts."""
    owners = np.empty(3 * wanted.shape[0], dtype=np.int64)
    starts = np.empty((3 * wanted.shape[0], 6))
    m = 0
    for bits in (2, 1, 3):
        for row in wanted:
            sibling = row ^ bits
            if unique[sibling]:
                owners[m] = row
                _flip(q[sibling], bits, exact, starts[m])
                m += 1
    return owners[:m], starts[:m]


def _move_starts(wanted, q0, ways, near_ratio, links, tool, q, converged, unique):
    """_repair's last restarts: each missing branch from its own start and from the other
    shoulder's solutions, moved along the calibrated arm's most singular direction where
    near a singularity (each vector moved, and each move stepped, once); owners, starts
    and which start each owner is offered."""
    w = wanted.shape[0]
    known = np.empty(4 * w, dtype=np.int64)             # the other shoulder's solutions,
    count = 0                                           # sorted, each once
    for row in wanted:
        for bits in (4, 5, 6, 7):
            sibling = row ^ bits
            if unique[sibling]:
                known[count] = sibling
                count += 1
    known = np.unique(known[:count])
    vectors = np.empty((w + known.shape[0], 6))
    for i in range(w):
        vectors[i] = q0[wanted[i]]
    for i in range(known.shape[0]):
        vectors[w + i] = q[known[i]]
    near, step = _near_singular_directions(links, tool, vectors, near_ratio)
    n_ways = ways.shape[0]
    owners = np.empty(n_ways * 5 * w, dtype=np.int64)
    moves = np.empty(n_ways * 5 * w, dtype=np.int64)
    m = 0
    for b in range(5):                                  # base by base: the branch's own
        rows = np.empty(w, dtype=np.int64)              # start, then each sibling's
        source = np.empty(w, dtype=np.int64)
        k = 0
        for i in range(w):
            keep = converged[wanted[i]] or near[i]
            if not keep:
                continue
            if b == 0:
                rows[k], source[k] = wanted[i], i
                k += 1
            else:
                sibling = wanted[i] ^ (3 + b)
                if unique[sibling]:
                    rows[k] = wanted[i]
                    source[k] = w + np.searchsorted(known, sibling)
                    k += 1
        for way in range(n_ways):                       # each way in turn, the vectors
            for j in range(k):                          # near a singularity moved
                if near[source[j]]:
                    owners[m] = rows[j]
                    moves[m] = n_ways * source[j] + way
                    m += 1
    used, which = _distinct(moves[:m], n_ways * vectors.shape[0])   # each move stepped once
    starts = np.empty((used.shape[0], 6))
    for u in range(used.shape[0]):
        vector, way = used[u] // n_ways, used[u] % n_ways
        for j in range(6):
            starts[u, j] = vectors[vector, j] + ways[way] * step[vector, j]
    return owners[:m], starts, which


def _family_count(pose, exact, family, q, done, converged, unique):
    """``dqlab.ik.ur_calibrated._family_members`` of one pose (its rows' uniqueness marked
    first): how many members of the exact arm's wrist family it takes as starts."""
    members, near_measure, few_branches, few_wrist = family[0], family[1], family[2], family[3]
    base = 8 * pose
    _unique_pose(q, converged, unique, base)
    have, wrist, near_wrist_found = 0, False, False
    for k in range(8):
        sin5 = abs(math.sin(q[base + k, 4] + exact[10]))
        if unique[base + k]:
            have += 1
            near_wrist_found = near_wrist_found or sin5 >= few_wrist
        wrist = wrist or (done[base + k] and sin5 < near_measure)
    few = have <= few_branches
    if have == 8:
        return 0
    if wrist or (few and not near_wrist_found):
        return members
    return 1 if few else 0


def _family_starts(pose, count, exact, X_06, singular_tol, near_wrist, family, tol, unique):
    """``dqlab.ik.ur_calibrated._family`` of one pose: ``count`` members of the exact arm's
    wrist family (``family``: their number, the thresholds of ``_family_members`` and the
    closed form's tolerance and near_tol there), or all of them where the one member's
    start for a missing branch is at the wrist singularity, offered to its missing branches
    (owners, starts, which start each owner is offered: :func:`_offer`)."""
    members, near_measure = family[0], family[1]
    base = 8 * pose
    missing = np.empty(8, dtype=np.bool_)
    for k in range(8):
        missing[k] = not unique[base + k]
    starts = np.empty((8 * max(count, members), 6))
    labels = np.empty(8 * max(count, members), dtype=np.int64)
    qw, qx, qy, qz = _quaternion(X_06)
    m = 0
    if count == 1:
        m = _member_starts(0.0, qw, qx, qy, qz, X_06, exact, singular_tol, near_wrist, family,
                           tol, unique, base, starts, labels, 0)
        for i in range(m):
            if abs(math.sin(starts[i, 4] + exact[10])) < near_measure:
                count, m = members, 0                   # the whole family instead
                break
    if count > 1:
        for j in range(count):
            m = _member_starts(-math.pi + 2.0 * math.pi / members * j, qw, qx, qy, qz, X_06,
                               exact, singular_tol, near_wrist, family, tol, unique, base,
                               starts, labels, m)
    return _offer(pose, starts[:m], labels[:m], missing)


def _member_starts(theta6, qw, qx, qy, qz, X_06, exact, singular_tol, near_wrist, family, tol,
                   unique, base, starts, labels, m):
    """``dqlab.ik.ur_calibrated._members`` of one member (the reference ``theta6``): its
    rows valid to the family's tolerance, moved off the elbow singularity, for the missing
    branches of the pose whose rows begin at ``base``, appended to ``starts`` and their
    ``labels`` from m on; how many there are then."""
    member_tol, member_near = family[4], family[5]
    solutions, errs = np.zeros((8, 6)), np.zeros((2, 8))
    flags = np.zeros(4, dtype=np.bool_)
    ended = _exact_one_pose(qw, qx, qy, qz, X_06[0, 3], X_06[1, 3], X_06[2, 3], X_06[0, 2],
                            X_06[1, 2], X_06[2, 2], X_06, theta6, exact, member_tol,
                            singular_tol, near_wrist, member_near, solutions, errs, flags)
    if ended != SOLVED:
        return m
    for k in range(8):
        if not (errs[0, k] <= member_tol and errs[1, k] <= member_tol):
            continue
        if errs[0, k] > tol:                                # (a clipped row)
            _off_the_edge(solutions, k, k, errs[0, k], exact)
        label = _branch(solutions[k], exact)
        if not unique[base + label]:                    # a start for a missing branch
            starts[m] = solutions[k]
            labels[m] = label
            m += 1
    return m


def _deflation(exact, ways, near_ratio, near_measure, steps, give_up_after, state):
    """``dqlab.ik.ur_calibrated._deflate``: deflated Newton from the solutions of each pose
    near a singularity, moved along the most singular direction by ``ways`` (every pose's
    starts stepped together, :func:`_deflated`), then offered to the pose's branches still
    missing (:func:`_run`)."""
    (links, tool, X_0T, stop, _, _, _, damping, max_step, q, done, converged, _, measures, _,
     unique) = state
    n = X_0T.shape[0]
    n_ways = ways.shape[0]
    wanted = np.zeros((n, 8), dtype=np.bool_)
    first = np.zeros(n + 1, dtype=np.int64)             # pose i: starts first[i]:first[i+1]
    starts = np.empty((8 * n_ways, 6))
    moved = np.empty(8, dtype=np.int64)
    for pose in range(n):
        first[pose + 1] = first[pose]
        base = 8 * pose
        if _full(unique, base):                         # (eight distinct solutions: none wanted)
            continue
        _unique_pose(q, converged, unique, base)
        any_wanted, count = False, 0
        for k in range(8):
            r = base + k
            wanted[pose, k] = done[r] and not unique[r]
            any_wanted = any_wanted or wanted[pose, k]
            if unique[r] and min(measures[0, r], measures[1, r],
                                 measures[2, r] / exact[3]) < near_measure:
                moved[count] = r
                count += 1
        if not any_wanted or count == 0:
            continue
        near, direction = _near_singular_directions(links, tool, q[moved[:count]], near_ratio)
        m = first[pose]
        if m + count * n_ways > starts.shape[0]:
            grown = np.empty((max(2 * starts.shape[0], m + count * n_ways), 6))
            grown[:m] = starts[:m]
            starts = grown
        for i in range(count):
            if near[i]:
                for way in range(n_ways):
                    for j in range(6):
                        starts[m, j] = q[moved[i], j] + ways[way] * direction[i, j]
                    m += 1
        first[pose + 1] = m
    m = first[n]
    if m == 0:
        return
    known, have = np.zeros((m, 8, 6)), np.zeros((m, 8), dtype=np.bool_)
    targets = np.empty((m, 4, 4))
    for pose in range(n):
        for i in range(first[pose], first[pose + 1]):
            targets[i] = X_0T[pose]
            for k in range(8):
                if unique[8 * pose + k]:
                    have[i, k] = True
                    known[i, k] = q[8 * pose + k]
    starts = starts[:m].copy()
    _deflated(links, tool, starts, targets, known, have, steps, stop, give_up_after, damping,
              max_step)
    queue = _queue(8 * m)
    for pose in range(n):
        if first[pose + 1] > first[pose]:
            mine = starts[first[pose]:first[pose + 1]]
            labels = np.empty(mine.shape[0], dtype=np.int64)
            for i in range(mine.shape[0]):
                labels[i] = _branch(mine[i], exact)
            owners, used, which = _offer(pose, mine, labels, wanted[pose])
            queue = _push(queue, pose, owners, used, which)
    _run(queue, state)


def _offer(pose, starts, labels, missing):
    """``dqlab.ik.ur_calibrated._offer`` of one pose: each start offered to every branch
    ``missing`` (8,), the branch of its label first, then the others in order; each start
    stepped once. The owners, the starts used and which of them each owner is offered."""
    m = starts.shape[0]
    owners = np.empty(8 * m, dtype=np.int64)
    which = np.empty(8 * m, dtype=np.int64)
    e = 0
    for j in range(m):                                  # its own branch first ...
        if missing[labels[j]]:
            owners[e], which[e] = 8 * pose + labels[j], j
            e += 1
    for j in range(m):                                  # ... then the others
        for k in range(8):
            if missing[k] and k != labels[j]:
                owners[e], which[e] = 8 * pose + k, j
                e += 1
    used, rank = _distinct(which[:e], m)                # each start stepped once
    return owners[:e], starts[used], rank


def _distinct(values, size):
    """The distinct ``values`` (k,), each below ``size``, in increasing order, and the rank
    of each value among them: ``np.unique`` and ``np.searchsorted`` of small integers,
    without sorting."""
    seen = np.zeros(size, dtype=np.bool_)
    for v in values:
        seen[v] = True
    order = np.empty(size, dtype=np.int64)
    used = np.empty(size, dtype=np.int64)
    k = 0
    for v in range(size):
        if seen[v]:
            order[v], used[k] = k, v
            k += 1
    rank = np.empty(values.shape[0], dtype=np.int64)
    for j in range(values.shape[0]):
        rank[j] = order[values[j]]
    return used[:k], rank


def _off_the_edge(rows, r, k, error, exact):
    """``dqlab.ik.ur_calibrated._off_the_edge`` of ``rows[r]``, branch k of a pose, valid
    with the error ``error`` above the tolerance (a clipped row; the callers test it before
    the call): moved off the elbow singularity where it clips the elbow."""
    theta3 = rows[r, 2] + exact[8]
    if not abs(math.sin(theta3)) < 1e-6:
        return
    a2, a3 = exact[1], exact[2]
    delta = max(math.sqrt(2.0 * abs(a2 + a3) * error / abs(a2 * a3)), 0.01)
    up = 1.0 if k // 2 % 2 == 0 else -1.0
    rows[r, 2] += up * _sign(math.cos(theta3)) * _sign(a2 * a3) * delta


def _sign(x):
    """numpy's sign of a float: -1, 0 or 1."""
    return 1.0 if x > 0.0 else (-1.0 if x < 0.0 else 0.0)


def _branch(q, exact):
    """``dqlab.ik.ur_calibrated._branches`` of one joint vector: 4 s + 2 e + w from the signs
    of ``branch_measures`` on the exact arm."""
    t1, t2, t3, t4 = (q[1] + exact[7], q[2] + exact[8], q[3] + exact[9], q[4] + exact[10])
    h = exact[1] * math.cos(t1) + exact[2] * math.cos(t1 + t2) + exact[4] * math.sin(
        t1 + t2 + t3)
    return 4 * (h < 0.0) + 2 * (math.sin(t2) < 0.0) + (math.sin(t4) < 0.0)


def _flip(q, bits, exact, out):
    """``dqlab.ik.ur_calibrated._flip`` of one joint vector q (6,) into ``out``."""
    t = np.empty(6)
    for i in range(6):
        t[i] = q[i] + exact[6 + i]
    if bits & 2:
        a2, a3 = exact[1], exact[2]
        beta = math.atan2(a3 * math.sin(t[2]), a2 + a3 * math.cos(t[2]))
        t[1], t[2], t[3] = t[1] + 2.0 * beta, -t[2], t[3] + 2.0 * t[2] - 2.0 * beta
    if bits & 1:
        t[3], t[4], t[5] = t[3] + math.pi, -t[4], t[5] + math.pi
    for i in range(6):
        out[i] = t[i] - exact[6 + i]


def _near_singular_directions(links, tool, q, ratio):
    """``dqlab.ik.ur_calibrated._near_singular`` of the joint vectors q (m, 6): whether each
    is near a singularity (m,) and the step direction (m, 6): the most singular direction
    where near, 0 elsewhere."""
    m = q.shape[0]
    H = np.empty((m, 6, 6))
    _gram(links, tool, q, H)
    near, known = np.zeros(m, dtype=np.bool_), np.zeros(m, dtype=np.bool_)
    V = np.zeros((m, 6))
    _smallest(H, ratio, near, V, known)
    for r in range(m):
        if not known[r]:
            near[r] = _jacobi_smallest(H[r], ratio, V[r])
        if not near[r]:
            V[r] = 0.0
    return near, V


def _jacobi_smallest(A, ratio, v):
    """Whether the smallest eigenvalue of the symmetric A (6, 6) is below ``ratio`` times
    the largest (the smallest clipped at 0), and its eigenvector in ``v``, largest entry
    positive: cyclic Jacobi rotations until the off-diagonal entries vanish against the
    diagonal."""
    B = A.copy()
    E = np.eye(6)
    for _ in range(64):
        off = 0.0
        for i in range(6):
            for j in range(i + 1, 6):
                off += B[i, j] * B[i, j]
        if off == 0.0:
            break
        for p in range(6):
            for r in range(p + 1, 6):
                if B[p, r] == 0.0:
                    continue
                theta = (B[r, r] - B[p, p]) / (2.0 * B[p, r])
                t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + math.sqrt(theta * theta
                                                                                + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(6):                      # B <- J^T B J, E <- E J
                    bkp, bkr = B[k, p], B[k, r]
                    B[k, p], B[k, r] = c * bkp - s * bkr, s * bkp + c * bkr
                for k in range(6):
                    bpk, brk = B[p, k], B[r, k]
                    B[p, k], B[r, k] = c * bpk - s * brk, s * bpk + c * brk
                for k in range(6):
                    ekp, ekr = E[k, p], E[k, r]
                    E[k, p], E[k, r] = c * ekp - s * ekr, s * ekp + c * ekr
    low = high = 0
    for i in range(6):
        if B[i, i] < B[low, low]:
            low = i
        if B[i, i] > B[high, high]:
            high = i
    top = 0
    for i in range(6):
        if abs(E[i, low]) > abs(E[top, low]):
            top = i
    sign = 1.0 if E[top, low] >= 0.0 else -1.0
    for i in range(6):
        v[i] = sign * E[i, low]
    return max(B[low, low], 0.0) < ratio * B[high, high]


def _times4(A, B):
    """The product A B of two (4, 4) matrices."""
    C = np.empty((4, 4))
    for i in range(4):
        for j in range(4):
            C[i, j] = (A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]
                       + A[i, 3] * B[3, j])
    return C


def _rigid_inverse(T):
    """The inverse of the rigid transform T (4, 4): (R^T, -R^T p)."""
    inverse = np.zeros((4, 4))
    for i in range(3):
        for j in range(3):
            inverse[i, j] = T[j, i]
        inverse[i, 3] = -(T[0, i] * T[0, 3] + T[1, i] * T[1, 3] + T[2, i] * T[2, 3])
    inverse[3, 3] = 1.0
    return inverse


def _quaternion(R):
    """``dqlab._formulas.quaternion_from_matrix_entries`` of the rotation block of R on
    floats: Shepperd's row of the largest diagonal entry of K = 4 q q^T, w >= 0."""
    r00, r01, r02 = R[0, 0], R[0, 1], R[0, 2]
    r10, r11, r12 = R[1, 0], R[1, 1], R[1, 2]
    r20, r21, r22 = R[2, 0], R[2, 1], R[2, 2]
    tr = r00 + r11 + r22
    K = (1.0 + tr, 1.0 + r00 - r11 - r22, 1.0 - r00 + r11 - r22, 1.0 - r00 - r11 + r22,
         r21 - r12, r02 - r20, r10 - r01, r01 + r10, r02 + r20, r12 + r21)
    k = 1 if K[1] > K[0] else 0
    if K[2] > K[k]:
        k = 2
    if K[3] > K[k]:
        k = 3
    if k == 0:
        w, x, y, z = K[0], K[4], K[5], K[6]
    elif k == 1:
        w, x, y, z = K[4], K[1], K[7], K[8]
    elif k == 2:
        w, x, y, z = K[5], K[7], K[2], K[9]
    else:
        w, x, y, z = K[6], K[8], K[9], K[3]
    s = 0.5 / math.sqrt(K[k])
    if w < 0.0:
        s = -s
    return w * s, x * s, y * s, z * s


_Q, _C, _S, _T, _TP, _F, _X, _ACT, _SIZE, _G = (
    INDEX[name] for name in ("q0", "c0", "s0", "t00", "tp0", "F0", "x0", "act", "size", "g0"))
_COMPILED += ["lane_angles", "lane_recompute", "lane_frames", "lane_step", "lane_deflated_step",
              "lane_size", "_same", "_unique", "_unique_pose", "_full", "_wrap",
              "_exact_one_pose", "_family_member",
              "_feasible_theta234", "_exact_flange", "_exact_fk", "_exact_poses", "_array_poses",
              "_array_start", "_array_finish", "_repairs", "_queue", "_cleared", "_push",
              "_equal", "_run", "_wanted", "_corrected_starts", "_family_count", "_family_starts",
              "_deflation", "_offer", "_distinct", "_member_starts",
              "_off_the_edge", "_sign", "_branch",
              "_flip_starts", "_move_starts", "_flip",
              "_near_singular_directions", "_jacobi_smallest", "_times4", "_rigid_inverse",
              "_quaternion", "_one_pose", "_lean_pose", "_accept", "_gram",
              "_smallest", "_largest_diagonal_column", "_times", "_rayleigh", "_are_new",
              "_load", "_long_step", "_kernel", "_outputs", "_pose_errors", "_dot_rows",
              "_deflated", "_cholesky", "_near_rows", "_nearness",
              "_row_nearness"]
