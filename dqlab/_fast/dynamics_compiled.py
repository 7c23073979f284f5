r"""The speed machinery of :mod:`dqlab.dynamics`, compiled (optional: needs numba).

The algorithms of :mod:`dqlab.dynamics` written out on floats, one configuration at a time,
for batches of configurations: the recursive Newton--Euler algorithm (:func:`inverse`), the
composite rigid bodies (:func:`mass`), the articulated bodies (:func:`forward`) and the
regressor (:func:`regressor_rows`). Twists and wrenches are 6-vectors in the dual order of
:mod:`dqlab.dynamics` (real part first: :math:`(\omega, \mathbf v)`, :math:`(\mathbf f,
\mathbf n)`), the adjoint of a link's pose :math:`(R, \mathbf p)` is applied as

.. math::

   \operatorname{Ad}^{-1}: (\omega, \mathbf v) \mapsto (R^\top\omega,\
   R^\top(\mathbf v + \omega\times\mathbf p)),\qquad
   \operatorname{Ad}: (\mathbf f, \mathbf n) \mapsto (R\mathbf f,\ R\mathbf n + \mathbf p
   \times R\mathbf f),

and an inertia moves as :math:`\operatorname{Ad}\,\mathcal M\,\operatorname{Ad}^{-1}`. The
numpy code of :mod:`dqlab.dynamics` stays the reference and the path without numba
(``pip install dqlab[fast]`` installs it); the tests check these kernels against it on random
states of every model. :func:`ready` says whether they can be used: numba is installed and
imports, and the environment does not say ``DQLAB_COMPILED=0``. The first compilation takes
seconds, and is cached on disk for the next processes.
"""

import math

import numpy as np

from .compiled import compile_in_place, compiled_allowed

_COMPILED = []     # the kernels below, compiled in place by ready()
_READY = None      # whether numba imported and the kernels compiled (once known)

#: Columns of a link's row in the constants: revolute, theta0, d0, a, cos alpha, sin alpha,
#: the joint twist (6, dual order), mass, centre of mass (3), tensor about the centre of mass
#: (xx, yy, zz, xy, xz, yz).
WIDTH = 22


def switched_on():
    """Whether ``DQLAB_COMPILED`` lets compiled kernels run (:mod:`dqlab._fast.compiled`). Read at
    every call, so that a test or a session can switch them off."""
    return compiled_allowed()


def ready():
    """Whether the compiled kernels can be used: switched on (:func:`switched_on`), and numba
    installed and importable (imported, and the kernels compiled or read from the cache, at
    the first call only, so that importing dqlab stays quick)."""
    global _READY
    if not switched_on():
        return False
    if _READY is None:
        _READY = compile_in_place(globals(), _COMPILED)
    return _READY


def constants(robot, inertias, twists):
    """``(standard, links)``: whether the robot is in standard DH, and its links' constants as
    an array (n, :data:`WIDTH`); ``inertias`` may be None (the regressor needs none)."""
    links = np.zeros((robot.n, WIDTH))
    for i, (link, s) in enumerate(zip(robot.links, twists, strict=True)):
        links[i, :6] = (link.is_revolute, link.theta_offset, link.d, link.a,
                        math.cos(link.alpha), math.sin(link.alpha))
        links[i, 6:12] = np.asarray(s).reshape(6)
        if inertias is not None:
            inertia = inertias[i]
            (ixx, ixy, ixz), (_, iyy, iyz), (_, _, izz) = inertia.tensor
            links[i, 12] = inertia.mass
            links[i, 13:16] = inertia.com
            links[i, 16:22] = (ixx, iyy, izz, ixy, ixz, iyz)
    return robot.convention == "dh", links


def _rows(*arrays):
    """The arrays (..., n), all of one shape, as C-contiguous (m, n) rows (views where they
    can be), and the leading shape."""
    shape = arrays[0].shape
    lead, n = shape[:-1], shape[-1]
    return lead, [a.reshape(-1, n) if a.flags.c_contiguous and a.dtype == np.float64
                  else np.ascontiguousarray(a, dtype=np.float64).reshape(-1, n)
                  for a in (np.broadcast_to(a, shape) if a.shape != shape else a
                            for a in arrays)]


def kernel_inverse(standard, links, q, qd, qdd, g_0, out):
    """The compiled Newton--Euler kernel itself, for a caller that has checked its arrays:
    C-contiguous float rows (m, n), ``g_0`` (3,), ``out`` (m, n) written in place."""
    _inverse(standard, links, q, qd, qdd, g_0, out)


def inverse(consts, q, qd, qdd, g_0):
    """Joint torques (..., n) of the recursive Newton--Euler algorithm."""
    standard, links = consts
    lead, (q, qd, qdd) = _rows(q, qd, qdd)
    out = np.empty_like(q)
    _inverse(standard, links, q, qd, qdd, np.asarray(g_0, dtype=float), out)
    return out.reshape(lead + (links.shape[0],))


def mass(consts, q):
    """:math:`M(q)` (..., n, n) by the composite rigid bodies."""
    standard, links = consts
    lead, (q,) = _rows(q)
    n = links.shape[0]
    out = np.empty((q.shape[0], n, n))
    _mass(standard, links, q, out)
    return out.reshape(lead + (n, n))


def forward(consts, q, qd, tau, g_0):
    """Accelerations (..., n) and the pivots D (..., n) of the articulated bodies."""
    standard, links = consts
    lead, (q, qd, tau) = _rows(q, qd, tau)
    qdd, D = np.empty_like(q), np.empty_like(q)
    _forward(standard, links, q, qd, tau, np.asarray(g_0, dtype=float), qdd, D)
    n = links.shape[0]
    return qdd.reshape(lead + (n,)), D.reshape(lead + (n,))


def regressor_rows(consts, q, qd, qdd, g_0):
    """The regressor (..., n, 10 n)."""
    standard, links = consts
    lead, (q, qd, qdd) = _rows(q, qd, qdd)
    n = links.shape[0]
    out = np.zeros((q.shape[0], n, 10 * n))
    _regressor(standard, links, q, qd, qdd, np.asarray(g_0, dtype=float), out)
    return out.reshape(lead + (n, 10 * n))


# --------------------------------------------------------------------------------------
# The kernels (plain Python on floats and small arrays; numba compiles them in ready())

def _pose(standard, links, i, q_i, R, p):
    """R (3, 3) and p (3,) of link i's pose X_{i-1,i}(q_i)."""
    if links[i, 0] > 0.5:
        theta, d = q_i + links[i, 1], links[i, 2]
    else:
        theta, d = links[i, 1], q_i + links[i, 2]
    a, ca, sa = links[i, 3], links[i, 4], links[i, 5]
    ct, st = math.cos(theta), math.sin(theta)
    if standard:            # Rz(theta) Tz(d) Tx(a) Rx(alpha)
        R[0, 0], R[0, 1], R[0, 2] = ct, -st * ca, st * sa
        R[1, 0], R[1, 1], R[1, 2] = st, ct * ca, -ct * sa
        R[2, 0], R[2, 1], R[2, 2] = 0.0, sa, ca
        p[0], p[1], p[2] = a * ct, a * st, d
    else:                   # Rx(alpha) Tx(a) Rz(theta) Tz(d)
        R[0, 0], R[0, 1], R[0, 2] = ct, -st, 0.0
        R[1, 0], R[1, 1], R[1, 2] = ca * st, ca * ct, -sa
        R[2, 0], R[2, 1], R[2, 2] = sa * st, sa * ct, ca
        p[0], p[1], p[2] = a, -sa * d, ca * d


def _inward(R, p, x, out):
    """Ad^{-1} of the pose (R, p) on a twist x (6,): into the link's frame."""
    u0 = x[3] + x[1] * p[2] - x[2] * p[1]
    u1 = x[4] + x[2] * p[0] - x[0] * p[2]
    u2 = x[5] + x[0] * p[1] - x[1] * p[0]
    w0 = R[0, 0] * x[0] + R[1, 0] * x[1] + R[2, 0] * x[2]
    w1 = R[0, 1] * x[0] + R[1, 1] * x[1] + R[2, 1] * x[2]
    w2 = R[0, 2] * x[0] + R[1, 2] * x[1] + R[2, 2] * x[2]
    out[3] = R[0, 0] * u0 + R[1, 0] * u1 + R[2, 0] * u2
    out[4] = R[0, 1] * u0 + R[1, 1] * u1 + R[2, 1] * u2
    out[5] = R[0, 2] * u0 + R[1, 2] * u1 + R[2, 2] * u2
    out[0], out[1], out[2] = w0, w1, w2


def _outward(R, p, x, out):
    """Ad of the pose (R, p) on a wrench x (6,): into the parent's frame."""
    f0 = R[0, 0] * x[0] + R[0, 1] * x[1] + R[0, 2] * x[2]
    f1 = R[1, 0] * x[0] + R[1, 1] * x[1] + R[1, 2] * x[2]
    f2 = R[2, 0] * x[0] + R[2, 1] * x[1] + R[2, 2] * x[2]
    n0 = R[0, 0] * x[3] + R[0, 1] * x[4] + R[0, 2] * x[5] + p[1] * f2 - p[2] * f1
    n1 = R[1, 0] * x[3] + R[1, 1] * x[4] + R[1, 2] * x[5] + p[2] * f0 - p[0] * f2
    n2 = R[2, 0] * x[3] + R[2, 1] * x[4] + R[2, 2] * x[5] + p[0] * f1 - p[1] * f0
    out[0], out[1], out[2], out[3], out[4], out[5] = f0, f1, f2, n0, n1, n2


def _cross(x, y, out):
    """The dual cross product x x y of 6-vectors."""
    r0 = x[1] * y[2] - x[2] * y[1]
    r1 = x[2] * y[0] - x[0] * y[2]
    r2 = x[0] * y[1] - x[1] * y[0]
    d0 = x[1] * y[5] - x[2] * y[4] + x[4] * y[2] - x[5] * y[1]
    d1 = x[2] * y[3] - x[0] * y[5] + x[5] * y[0] - x[3] * y[2]
    d2 = x[0] * y[4] - x[1] * y[3] + x[3] * y[1] - x[4] * y[0]
    out[0], out[1], out[2], out[3], out[4], out[5] = r0, r1, r2, d0, d1, d2


def _power(s, w):
    """<s, w> = omega . n + v . f."""
    return (s[0] * w[3] + s[1] * w[4] + s[2] * w[5]
            + s[3] * w[0] + s[4] * w[1] + s[5] * w[2])


def _momentum(links, i, x, out):
    """The momentum M_i x of link i for the twist x: p = m (v + w x c), L = I_c w + c x p."""
    m = links[i, 12]
    cx, cy, cz = links[i, 13], links[i, 14], links[i, 15]
    ixx, iyy, izz, ixy, ixz, iyz = (links[i, 16], links[i, 17], links[i, 18], links[i, 19],
                                    links[i, 20], links[i, 21])
    w0, w1, w2 = x[0], x[1], x[2]
    p0 = m * (x[3] + w1 * cz - w2 * cy)
    p1 = m * (x[4] + w2 * cx - w0 * cz)
    p2 = m * (x[5] + w0 * cy - w1 * cx)
    out[3] = ixx * w0 + ixy * w1 + ixz * w2 + cy * p2 - cz * p1
    out[4] = ixy * w0 + iyy * w1 + iyz * w2 + cz * p0 - cx * p2
    out[5] = ixz * w0 + iyz * w1 + izz * w2 + cx * p1 - cy * p0
    out[0], out[1], out[2] = p0, p1, p2


def _spatial(links, i, out):
    """Link i's spatial inertia (6, 6) in the dual orders,
    ((-m [c]x, m I), (I_O, m [c]x)), with I_O = I_c + m (|c|^2 I - c c^T)."""
    m = links[i, 12]
    cx, cy, cz = links[i, 13], links[i, 14], links[i, 15]
    ixx, iyy, izz, ixy, ixz, iyz = (links[i, 16], links[i, 17], links[i, 18], links[i, 19],
                                    links[i, 20], links[i, 21])
    out[:, :] = 0.0
    out[0, 3] = out[1, 4] = out[2, 5] = m
    # m [c]x, in the top-left with a minus and the bottom-right with a plus
    out[0, 1], out[0, 2], out[1, 2] = m * cz, -m * cy, m * cx
    out[1, 0], out[2, 0], out[2, 1] = -m * cz, m * cy, -m * cx
    out[3, 4], out[3, 5], out[4, 5] = -m * cz, m * cy, -m * cx
    out[4, 3], out[5, 3], out[5, 4] = m * cz, -m * cy, m * cx
    cc = cx * cx + cy * cy + cz * cz
    out[3, 0] = ixx + m * (cc - cx * cx)
    out[4, 1] = iyy + m * (cc - cy * cy)
    out[5, 2] = izz + m * (cc - cz * cz)
    out[3, 1] = out[4, 0] = ixy - m * cx * cy
    out[3, 2] = out[5, 0] = ixz - m * cx * cz
    out[4, 2] = out[5, 1] = iyz - m * cy * cz


def _add_moved(R, p, A, out, unit, twist, h):
    """out += Ad A Ad^{-1} for the pose (R, p): an inertia (6, 6) of the child's frame added in
    the parent's, column by column: A's columns are momenta of the child's unit twists, and
    Ad A Ad^{-1} e is the momentum, moved out, of the twist e moved in (``unit``, ``twist``,
    ``h``: work arrays of 6)."""
    for k in range(6):
        unit[:] = 0.0
        unit[k] = 1.0
        _inward(R, p, unit, twist)
        for r in range(6):
            s = 0.0
            for c in range(6):
                s += A[r, c] * twist[c]
            h[r] = s
        _outward(R, p, h, h)
        for r in range(6):
            out[r, k] += h[r]


def _twists(standard, links, q, qd, qdd, g_0, R, p, xi, rate, joint, tmp):
    """The outward pass of Newton--Euler for one state: every link's pose (R, p), twist
    (xi, (n, 6)) and its rate (rate, (n, 6)), from the base at rest rising at -g
    (``joint``, ``tmp``: work arrays of 6)."""
    n = q.shape[0]
    for i in range(n):
        _pose(standard, links, i, q[i], R[i], p[i])
        if i == 0:
            xi[0, :] = 0.0
            rate[0, :] = 0.0
            rate[0, 3], rate[0, 4], rate[0, 5] = -g_0[0], -g_0[1], -g_0[2]
            _inward(R[0], p[0], xi[0], xi[0])
            _inward(R[0], p[0], rate[0], rate[0])
        else:
            _inward(R[i], p[i], xi[i - 1], xi[i])
            _inward(R[i], p[i], rate[i - 1], rate[i])
        for c in range(6):
            joint[c] = links[i, 6 + c] * qd[i]
            xi[i, c] += joint[c]
        _cross(xi[i], joint, tmp)
        for c in range(6):
            rate[i, c] += links[i, 6 + c] * qdd[i] + tmp[c]


def _inverse(standard, links, q, qd, qdd, g_0, out):
    m, n = q.shape
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    xi, rate, net = np.empty((n, 6)), np.empty((n, 6)), np.empty((n, 6))
    joint, h, tmp, w = np.empty(6), np.empty(6), np.empty(6), np.empty(6)
    for k in range(m):
        _twists(standard, links, q[k], qd[k], qdd[k], g_0, R, p, xi, rate, joint, tmp)
        for i in range(n):
            _momentum(links, i, rate[i], net[i])
            _momentum(links, i, xi[i], h)
            _cross(xi[i], h, tmp)
            for c in range(6):
                net[i, c] += tmp[c]
        w[:] = 0.0
        for i in range(n - 1, -1, -1):
            if i < n - 1:
                _outward(R[i + 1], p[i + 1], w, w)
            for c in range(6):
                w[c] += net[i, c]
            out[k, i] = _power(links[i, 6:12], w)


def _parameters(links, i, out):
    """Link i's ten parameters (m, m c, I_O as xx, xy, yy, xz, yz, zz) into ``out``."""
    m = links[i, 12]
    cx, cy, cz = links[i, 13], links[i, 14], links[i, 15]
    cc = cx * cx + cy * cy + cz * cz
    out[0], out[1], out[2], out[3] = m, m * cx, m * cy, m * cz
    out[4] = links[i, 16] + m * (cc - cx * cx)
    out[5] = links[i, 19] - m * cx * cy
    out[6] = links[i, 17] + m * (cc - cy * cy)
    out[7] = links[i, 20] - m * cx * cz
    out[8] = links[i, 21] - m * cy * cz
    out[9] = links[i, 18] + m * (cc - cz * cz)


def _add_moved_parameters(R, p, x, out):
    """out += the parameters x of a body described in a child frame, described in its parent,
    where the child sits at (R, p): m, R h + m p, and the tensor about the parent's origin,
    R I R^T + (2 (R h).p + m |p|^2) I - (R h) p^T - p (R h)^T - m p p^T."""
    m = x[0]
    h0 = R[0, 0] * x[1] + R[0, 1] * x[2] + R[0, 2] * x[3]
    h1 = R[1, 0] * x[1] + R[1, 1] * x[2] + R[1, 2] * x[3]
    h2 = R[2, 0] * x[1] + R[2, 1] * x[2] + R[2, 2] * x[3]
    # R I R^T, I symmetric from its six entries
    a00, a01, a11, a02, a12, a22 = x[4], x[5], x[6], x[7], x[8], x[9]
    t00 = a00 * R[0, 0] + a01 * R[0, 1] + a02 * R[0, 2]      # rows of I R^T
    t01 = a00 * R[1, 0] + a01 * R[1, 1] + a02 * R[1, 2]
    t02 = a00 * R[2, 0] + a01 * R[2, 1] + a02 * R[2, 2]
    t10 = a01 * R[0, 0] + a11 * R[0, 1] + a12 * R[0, 2]
    t11 = a01 * R[1, 0] + a11 * R[1, 1] + a12 * R[1, 2]
    t12 = a01 * R[2, 0] + a11 * R[2, 1] + a12 * R[2, 2]
    t20 = a02 * R[0, 0] + a12 * R[0, 1] + a22 * R[0, 2]
    t21 = a02 * R[1, 0] + a12 * R[1, 1] + a22 * R[1, 2]
    t22 = a02 * R[2, 0] + a12 * R[2, 1] + a22 * R[2, 2]
    r00 = R[0, 0] * t00 + R[0, 1] * t10 + R[0, 2] * t20
    r01 = R[0, 0] * t01 + R[0, 1] * t11 + R[0, 2] * t21
    r11 = R[1, 0] * t01 + R[1, 1] * t11 + R[1, 2] * t21
    r02 = R[0, 0] * t02 + R[0, 1] * t12 + R[0, 2] * t22
    r12 = R[1, 0] * t02 + R[1, 1] * t12 + R[1, 2] * t22
    r22 = R[2, 0] * t02 + R[2, 1] * t12 + R[2, 2] * t22
    p0, p1, p2 = p[0], p[1], p[2]
    s = 2.0 * (h0 * p0 + h1 * p1 + h2 * p2) + m * (p0 * p0 + p1 * p1 + p2 * p2)
    out[0] += m
    out[1] += h0 + m * p0
    out[2] += h1 + m * p1
    out[3] += h2 + m * p2
    out[4] += r00 + s - 2.0 * h0 * p0 - m * p0 * p0
    out[5] += r01 - h0 * p1 - p0 * h1 - m * p0 * p1
    out[6] += r11 + s - 2.0 * h1 * p1 - m * p1 * p1
    out[7] += r02 - h0 * p2 - p0 * h2 - m * p0 * p2
    out[8] += r12 - h1 * p2 - p1 * h2 - m * p1 * p2
    out[9] += r22 + s - 2.0 * h2 * p2 - m * p2 * p2


def _parameters_momentum(x, s, out):
    """The momentum of the body of parameters x for the twist s: p = m v + w x (m c),
    L = I_O w + (m c) x v."""
    m, h0, h1, h2 = x[0], x[1], x[2], x[3]
    w0, w1, w2, v0, v1, v2 = s[0], s[1], s[2], s[3], s[4], s[5]
    out[0] = m * v0 + w1 * h2 - w2 * h1
    out[1] = m * v1 + w2 * h0 - w0 * h2
    out[2] = m * v2 + w0 * h1 - w1 * h0
    out[3] = x[4] * w0 + x[5] * w1 + x[7] * w2 + h1 * v2 - h2 * v1
    out[4] = x[5] * w0 + x[6] * w1 + x[8] * w2 + h2 * v0 - h0 * v2
    out[5] = x[7] * w0 + x[8] * w1 + x[9] * w2 + h0 * v1 - h1 * v0


def _mass(standard, links, q, out):
    m, n = q.shape
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    composite = np.empty((n, 10))                  # the composite bodies' ten parameters
    h = np.empty(6)
    for k in range(m):
        for i in range(n):
            _pose(standard, links, i, q[k, i], R[i], p[i])
            _parameters(links, i, composite[i])
        for i in range(n - 1, -1, -1):
            _parameters_momentum(composite[i], links[i, 6:12], h)
            out[k, i, i] = _power(links[i, 6:12], h)
            for j in range(i - 1, -1, -1):
                _outward(R[j + 1], p[j + 1], h, h)
                out[k, i, j] = out[k, j, i] = _power(links[j, 6:12], h)
            if i > 0:
                _add_moved_parameters(R[i], p[i], composite[i], composite[i - 1])


def _forward(standard, links, q, qd, tau, g_0, qdd, D):
    m, n = q.shape
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    M_A = np.empty((n, 6, 6))
    F_A, c, U = np.empty((n, 6)), np.empty((n, 6)), np.empty((n, 6))
    u = np.empty(n)
    M_a = np.empty((6, 6))
    xi, joint, h, F_a, rate, swapped = (np.empty(6), np.empty(6), np.empty(6), np.empty(6),
                                        np.empty(6), np.empty(6))
    work = np.empty((3, 6))
    for k in range(m):
        xi[:] = 0.0
        for i in range(n):                         # 1. outwards: twists and biases
            _pose(standard, links, i, q[k, i], R[i], p[i])
            _inward(R[i], p[i], xi, xi)
            for e in range(6):
                joint[e] = links[i, 6 + e] * qd[k, i]
                xi[e] += joint[e]
            _cross(xi, joint, c[i])
            _spatial(links, i, M_A[i])
            _momentum(links, i, xi, h)
            _cross(xi, h, F_A[i])
        for i in range(n - 1, -1, -1):             # 2. inwards: articulated inertias
            for r in range(6):
                s = 0.0
                for e in range(6):
                    s += M_A[i, r, e] * links[i, 6 + e]
                U[i, r] = s
            D[k, i] = _power(links[i, 6:12], U[i])
            u[i] = tau[k, i] - _power(links[i, 6:12], F_A[i])
            if i > 0:
                swapped[:3], swapped[3:] = U[i, 3:], U[i, :3]
                for r in range(6):
                    for e in range(6):
                        M_a[r, e] = M_A[i, r, e] - U[i, r] * swapped[e] / D[k, i]
                for r in range(6):
                    s = F_A[i, r] + U[i, r] * (u[i] / D[k, i])
                    for e in range(6):
                        s += M_a[r, e] * c[i, e]
                    F_a[r] = s
                _add_moved(R[i], p[i], M_a, M_A[i - 1], work[0], work[1], work[2])
                _outward(R[i], p[i], F_a, F_a)
                F_A[i - 1] += F_a
        rate[:] = 0.0
        rate[3], rate[4], rate[5] = -g_0[0], -g_0[1], -g_0[2]
        for i in range(n):                         # 3. outwards: accelerations
            _inward(R[i], p[i], rate, rate)
            for e in range(6):
                rate[e] += c[i, e]
            qdd[k, i] = (u[i] - _power(rate, U[i])) / D[k, i]
            for e in range(6):
                rate[e] += links[i, 6 + e] * qdd[k, i]


def _parameter_wrenches(xi, rate, out):
    """The net wrench M xi_dot + xi x M xi of a link for each of its ten parameters alone,
    (10, 6): m; m c_x, m c_y, m c_z; Ixx, Ixy, Iyy, Ixz, Iyz, Izz (about the origin)."""
    w0, w1, w2, v0, v1, v2 = xi[0], xi[1], xi[2], xi[3], xi[4], xi[5]
    a0, a1, a2, b0, b1, b2 = rate[0], rate[1], rate[2], rate[3], rate[4], rate[5]
    out[:, :] = 0.0
    # m: f = v_dot + w x v
    out[0, 0] = b0 + w1 * v2 - w2 * v1
    out[0, 1] = b1 + w2 * v0 - w0 * v2
    out[0, 2] = b2 + w0 * v1 - w1 * v0
    # m c along e: f = a x e + w x (w x e), n = e x (v_dot + w x v)
    for k in range(3):
        e0, e1, e2 = 0.0, 0.0, 0.0
        if k == 0:
            e0 = 1.0
        elif k == 1:
            e1 = 1.0
        else:
            e2 = 1.0
        t0, t1, t2 = w1 * e2 - w2 * e1, w2 * e0 - w0 * e2, w0 * e1 - w1 * e0     # w x e
        out[1 + k, 0] = a1 * e2 - a2 * e1 + w1 * t2 - w2 * t1
        out[1 + k, 1] = a2 * e0 - a0 * e2 + w2 * t0 - w0 * t2
        out[1 + k, 2] = a0 * e1 - a1 * e0 + w0 * t1 - w1 * t0
        out[1 + k, 3] = e1 * out[0, 2] - e2 * out[0, 1]
        out[1 + k, 4] = e2 * out[0, 0] - e0 * out[0, 2]
        out[1 + k, 5] = e0 * out[0, 1] - e1 * out[0, 0]
    # one entry E of I_O: n = E a + w x (E w)
    E = np.zeros((3, 3))
    rows, cols = (0, 0, 1, 0, 1, 2), (0, 1, 1, 2, 2, 2)
    for k in range(6):
        E[:, :] = 0.0
        E[rows[k], cols[k]] = 1.0
        E[cols[k], rows[k]] = 1.0
        l0 = E[0, 0] * w0 + E[0, 1] * w1 + E[0, 2] * w2
        l1 = E[1, 0] * w0 + E[1, 1] * w1 + E[1, 2] * w2
        l2 = E[2, 0] * w0 + E[2, 1] * w1 + E[2, 2] * w2
        out[4 + k, 3] = E[0, 0] * a0 + E[0, 1] * a1 + E[0, 2] * a2 + w1 * l2 - w2 * l1
        out[4 + k, 4] = E[1, 0] * a0 + E[1, 1] * a1 + E[1, 2] * a2 + w2 * l0 - w0 * l2
        out[4 + k, 5] = E[2, 0] * a0 + E[2, 1] * a1 + E[2, 2] * a2 + w0 * l1 - w1 * l0


def _regressor(standard, links, q, qd, qdd, g_0, out):
    m, n = q.shape
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    columns = np.empty((n, 10, 6))
    xi, rate, joint, tmp = np.empty((n, 6)), np.empty((n, 6)), np.empty(6), np.empty(6)
    for k in range(m):
        _twists(standard, links, q[k], qd[k], qdd[k], g_0, R, p, xi, rate, joint, tmp)
        for i in range(n):
            _parameter_wrenches(xi[i], rate[i], columns[i])
        for i in range(n - 1, -1, -1):             # columns of links i..n in frame i
            for j in range(i, n):
                for e in range(10):
                    if j > i:
                        _outward(R[i + 1], p[i + 1], columns[j, e], columns[j, e])
                    out[k, i, 10 * j + e] = _power(links[i, 6:12], columns[j, e])


_COMPILED += ["_pose", "_inward", "_outward", "_cross", "_power", "_momentum", "_spatial",
              "_add_moved", "_parameters", "_add_moved_parameters", "_parameters_momentum",
              "_twists", "_inverse", "_mass", "_forward", "_parameter_wrenches",
              "_regressor"]
