r"""The Newton steps of :mod:`dqlab.ik.ur_calibrated`, compiled (optional: needs numba).

:func:`newton` does what ``dqlab.ik.ur_calibrated._newton`` does on numpy arrays, one branch
at a time in compiled code: forward kinematics of the calibrated chain, the residual
:math:`e = (p^\ast - p,\ \tfrac12 (R^\ast R^\mathsf{T} - R R^{\ast\mathsf{T}})^\vee)`, the
Jacobian at the TCP and the damped step
:math:`(J^\mathsf{T} J + \lambda I)^{-1} J^\mathsf{T} e` by Cholesky, with the same stop,
give-up and shortening rules and the same frames layout as ``_EntryChain``. It is tested
equal to the numpy path, which stays the one the module's docstring describes and the one
used where numba is not installed (``pip install dqlab[fast]`` installs it; the in-browser
chapters run without it).

:func:`unique` and :func:`are_new` are ``_Polished.unique`` and ``_Polished.are_new`` of
that module, compiled the same way. :func:`ready` says whether numba is there; the first
compilation takes seconds, and is cached on disk for the next processes.

The kernel differs from the numpy path in one way that changes no result beyond rounding:
after the first step, the cosine and sine of each joint angle are turned by the step
(:func:`_turn`) instead of being computed again.
"""

import importlib.util
import math

import numpy as np

__all__ = ["ready", "newton", "unique", "are_new"]

_COMPILED = []     # the functions below the wrappers, compiled in place by ready()
_READY = None      # ready()'s answer, once known


def ready():
    """Whether the compiled kernels can be used: numba is installed and imports (it is
    imported, and the kernels compiled or read from the cache, at the first call only, so
    that importing dqlab stays quick)."""
    global _READY
    if _READY is None:
        _READY = False
        if importlib.util.find_spec("numba") is not None:
            try:
                import numba
            except ImportError:                         # e.g. a numpy it does not support
                return False
            jit = numba.njit(cache=True, nogil=True, error_model="numpy")
            for name in _COMPILED:
                globals()[name] = jit(globals()[name])
            _READY = True
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


def _angles(links, q, cs):
    """cs (6, 2): the cosines and sines of the joint angles theta_i = q_i + theta0_i."""
    for i in range(6):
        cs[i, 0] = math.cos(q[i] + links[i, 4])
        cs[i, 1] = math.sin(q[i] + links[i, 4])


def _turn(links, q, step, cs):
    r"""q += step, and cs turned by each step :math:`\delta`: :math:`(c, s) \leftarrow
    (c \cos\delta - s \sin\delta,\ s \cos\delta + c \sin\delta)`, the cosine and sine of
    a step below 0.02 rad by their Taylor series to :math:`\delta^7` (truncation below
    1e-18), of a longer one from the new angle."""
    for i in range(6):
        d = step[i]
        q[i] += d
        if abs(d) < 0.02:
            d2 = d * d
            cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0 - d2 * (1.0 / 720.0)))
            sd = d * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0 - d2 * (1.0 / 5040.0))))
            c, s = cs[i, 0], cs[i, 1]
            cs[i, 0] = c * cd - s * sd
            cs[i, 1] = s * cd + c * sd
        else:
            cs[i, 0] = math.cos(q[i] + links[i, 4])
            cs[i, 1] = math.sin(q[i] + links[i, 4])


_TWO_PI = 2.0 * math.pi


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
        for i in range(8 * pose, 8 * pose + 8):
            out[i] = converged[i]
            if converged[i]:
                for k in range(8 * pose, i):
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


def _frames(links, tool, no_tool, cs, F):
    """Frames of one branch into F (48,) from the cosines and sines of its joint angles:
    z_1..z_5, o_1..o_5, x_2, x_3, the TCP position and its rotation row by row
    (``_EntryChain``'s layout)."""
    ca, sa, a, d = links[0, 0], links[0, 1], links[0, 2], links[0, 3]
    c, s = cs[0, 0], cs[0, 1]
    x0, x1, x2 = c, s, 0.0
    y0, y1, y2 = -ca * s, ca * c, sa
    z0, z1, z2 = sa * s, -sa * c, ca
    o0, o1, o2 = a * c, a * s, d
    F[0], F[1], F[2] = z0, z1, z2
    F[15], F[16], F[17] = o0, o1, o2
    for i in range(1, 6):
        ca, sa, a, d = links[i, 0], links[i, 1], links[i, 2], links[i, 3]
        c, s = cs[i, 0], cs[i, 1]
        n0, n1, n2 = c * x0 + s * y0, c * x1 + s * y1, c * x2 + s * y2
        p0, p1, p2 = c * y0 - s * x0, c * y1 - s * x1, c * y2 - s * x2
        o0, o1, o2 = o0 + d * z0 + a * n0, o1 + d * z1 + a * n1, o2 + d * z2 + a * n2
        y0, y1, y2 = ca * p0 + sa * z0, ca * p1 + sa * z1, ca * p2 + sa * z2
        z0, z1, z2 = ca * z0 - sa * p0, ca * z1 - sa * p1, ca * z2 - sa * p2
        x0, x1, x2 = n0, n1, n2
        if i < 5:
            F[3 * i], F[3 * i + 1], F[3 * i + 2] = z0, z1, z2
            F[15 + 3 * i], F[16 + 3 * i], F[17 + 3 * i] = o0, o1, o2
        if i == 1 or i == 2:
            F[27 + 3 * i], F[28 + 3 * i], F[29 + 3 * i] = x0, x1, x2
    if no_tool:
        F[36], F[37], F[38] = o0, o1, o2
        F[39], F[40], F[41] = x0, y0, z0
        F[42], F[43], F[44] = x1, y1, z1
        F[45], F[46], F[47] = x2, y2, z2
    else:
        tx, ty, tz = tool[0, 3], tool[1, 3], tool[2, 3]
        F[36] = o0 + tx * x0 + ty * y0 + tz * z0
        F[37] = o1 + tx * x1 + ty * y1 + tz * z1
        F[38] = o2 + tx * x2 + ty * y2 + tz * z2
        for k in range(3):
            xk, yk, zk = (x0, x1, x2)[k], (y0, y1, y2)[k], (z0, z1, z2)[k]
            for j in range(3):
                F[39 + 3 * k + j] = xk * tool[0, j] + yk * tool[1, j] + zk * tool[2, j]


def _residual(F, X_target, e):
    """e (6,): the position error and half the skew part of R* R^T (``_EntryChain``'s)."""
    e[0] = X_target[0, 3] - F[36]
    e[1] = X_target[1, 3] - F[37]
    e[2] = X_target[2, 3] - F[38]
    for k in range(3):
        i, j = (2, 0, 1)[k], (1, 2, 0)[k]
        tr_i = X_target[i, 0] * F[39 + 3 * j] + X_target[i, 1] * F[40 + 3 * j] \
            + X_target[i, 2] * F[41 + 3 * j]
        tr_j = X_target[j, 0] * F[39 + 3 * i] + X_target[j, 1] * F[40 + 3 * i] \
            + X_target[j, 2] * F[41 + 3 * i]
        e[3 + k] = 0.5 * (tr_i - tr_j)


def _error_size(e):
    """The larger of the position and rotation errors (Euclidean)."""
    return math.sqrt(max(e[0] * e[0] + e[1] * e[1] + e[2] * e[2],
                         e[3] * e[3] + e[4] * e[4] + e[5] * e[5]))


def _jacobian(F, J):
    """J (6, 6) at the TCP, row j holding column j of the Jacobian (linear part first)."""
    px, py, pz = F[36], F[37], F[38]
    J[0, 0], J[0, 1], J[0, 2], J[0, 3], J[0, 4], J[0, 5] = -py, px, 0.0, 0.0, 0.0, 1.0
    for i in range(5):
        zx, zy, zz = F[3 * i], F[3 * i + 1], F[3 * i + 2]
        rx, ry, rz = px - F[15 + 3 * i], py - F[16 + 3 * i], pz - F[17 + 3 * i]
        J[i + 1, 0] = zy * rz - zz * ry
        J[i + 1, 1] = zz * rx - zx * rz
        J[i + 1, 2] = zx * ry - zy * rx
        J[i + 1, 3], J[i + 1, 4], J[i + 1, 5] = zx, zy, zz


def _solve_damped(J, e, damping, H, g, inv, step):
    """(J^T J + lambda I) x = J^T e, lambda = damping tr(J^T J) / 6, by Cholesky."""
    trace = 0.0
    for i in range(6):
        for j in range(i + 1):
            s = 0.0
            for k in range(6):
                s += J[i, k] * J[j, k]
            H[i, j] = s
        trace += H[i, i]
        s = 0.0
        for k in range(6):
            s += J[i, k] * e[k]
        g[i] = s
    lam = (damping / 6.0) * trace
    for i in range(6):
        H[i, i] += lam
    for j in range(6):                                  # L in H's lower triangle
        s = H[j, j]
        for k in range(j):
            s -= H[j, k] * H[j, k]
        H[j, j] = math.sqrt(s) if s >= 0.0 else math.nan
        inv[j] = 1.0 / H[j, j]
        for i in range(j + 1, 6):
            s = H[i, j]
            for k in range(j):
                s -= H[i, k] * H[j, k]
            H[i, j] = s * inv[j]
    for i in range(6):                                  # L y = J^T e
        s = g[i]
        for k in range(i):
            s -= H[i, k] * g[k]
        g[i] = s * inv[i]
    for i in range(5, -1, -1):                          # L^T x = y
        s = g[i]
        for k in range(i + 1, 6):
            s -= H[k, i] * step[k]
        step[i] = s * inv[i]


def _step(F, e, damping, max_step, J, H, g, inv, step):
    """The damped Newton step into ``step`` (6,), shortened to ``max_step``."""
    _jacobian(F, J)
    _solve_damped(J, e, damping, H, g, inv, step)
    longest, nan = 0.0, False
    for i in range(6):
        if step[i] != step[i]:
            nan = True
        else:
            longest = max(longest, abs(step[i]))
    factor = math.nan if nan else min(1.0, max_step / max(longest, 1e-300))
    for i in range(6):
        step[i] *= factor


def _row(links, tool, no_tool, q, X_target, stop, plain, max_iter, give_up_after, damping,
         max_step, F, cs, e, J, H, g, inv, step):
    """One branch: the plain steps, then steps until it stops; whether it converged."""
    _angles(links, q, cs)
    for _ in range(plain):
        _frames(links, tool, no_tool, cs, F)
        _residual(F, X_target, e)
        _step(F, e, damping, max_step, J, H, g, inv, step)
        _turn(links, q, step, cs)
    _frames(links, tool, no_tool, cs, F)
    _residual(F, X_target, e)
    size = _error_size(e)
    if size > stop and plain < max_iter:
        size = math.inf
        before0, before1 = math.inf, math.inf
        for iteration in range(plain, max_iter + 1):
            if iteration > plain:
                _frames(links, tool, no_tool, cs, F)
                _residual(F, X_target, e)
            before0, before1 = before1, size
            size = _error_size(e)
            keep = size > stop
            if iteration >= give_up_after:
                keep = keep and size < 0.5 * before0
            if iteration == max_iter or not keep:
                break
            _step(F, e, damping, max_step, J, H, g, inv, step)
            _turn(links, q, step, cs)
    return size <= stop


def _kernel(links, tool, q, X_target, stop, plain, max_iter, give_up_after, damping,
            max_step, converged, X, measures, errors):
    """Every branch (rows of q, in place)."""
    no_tool = True
    for i in range(4):
        for j in range(4):
            if tool[i, j] != (1.0 if i == j else 0.0):
                no_tool = False
    F, e, g, inv, step = np.empty(48), np.empty(6), np.empty(6), np.empty(6), np.empty(6)
    J, H, cs = np.empty((6, 6)), np.empty((6, 6)), np.empty((6, 2))
    for r in range(q.shape[0]):
        qr = q[r]
        converged[r] = _row(links, tool, no_tool, qr, X_target[r], stop, plain, max_iter,
                            give_up_after, damping, max_step, F, cs, e, J, H, g, inv, step)
        lost = False
        for i in range(6):
            if not math.isfinite(qr[i]):                # a step that overflowed: back to 0
                qr[i] = 0.0
                lost = True
        if lost:
            _angles(links, qr, cs)
            _frames(links, tool, no_tool, cs, F)
        for i in range(3):
            for j in range(3):
                X[r, i, j] = F[39 + 3 * i + j]
            X[r, i, 3] = F[36 + i]
        X[r, 3, 3] = 1.0
        z3x, z3y, z3z = F[6], F[7], F[8]                # |z3 x z5|, |x2 x x3|, shoulder
        z5x, z5y, z5z = F[12], F[13], F[14]
        measures[0, r] = math.sqrt((z3y * z5z - z3z * z5y) ** 2 + (z3z * z5x - z3x * z5z) ** 2
                                   + (z3x * z5y - z3y * z5x) ** 2)
        ax, ay, az, bx, by, bz = F[30], F[31], F[32], F[33], F[34], F[35]
        measures[1, r] = math.sqrt((ay * bz - az * by) ** 2 + (az * bx - ax * bz) ** 2
                                   + (ax * by - ay * bx) ** 2)
        measures[2, r] = abs(F[0] * F[28] - F[1] * F[27]) / math.hypot(F[0], F[1])
        _pose_errors(X[r], X_target[r], errors[:, r])


def _pose_errors(X, X_target, out):
    """out (2,): ``dqlab._kernels.pose_error_entries`` of X and X_target (4, 4)."""
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


_COMPILED += ["_angles", "_turn", "_same", "_unique", "_are_new", "_frames", "_residual",
              "_error_size", "_jacobian", "_solve_damped", "_step", "_row", "_kernel",
              "_pose_errors", "_dot_rows"]
