r"""Unchecked component formulas shared by every layer of dqlab.

Each function here is one formula written on *components*: its arguments are the entries of
quaternions, dual quaternions, vectors or matrices, either Python floats (one value, the
fast path) or numpy arrays of one common shape (a batch, column by column). Nothing is
checked: the public functions of :mod:`dqlab.quaternion`, :mod:`dqlab.rotations`,
:mod:`dqlab.dualquat` and :mod:`dqlab.robot` validate their arguments once (with
:mod:`dqlab._checks`) and then call these.

Conventions: quaternions ``(w, x, y, z)`` with the Hamilton product, dual quaternions
``(q_r, q_d)`` as eight numbers, matrices row by row.

>>> quaternion_mul(0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0)     # i j = k
(0.0, 0.0, 0.0, 1.0)
"""

import math

import numpy as np

# --------------------------------------------------------------------------------------
# Floats or arrays: the one switch


def _float_where(condition, a, b):
    return a if condition else b


def _float_clip0(x):
    return x if x > 0.0 else 0.0


def _float_no_minus_pi(theta):
    return math.pi if theta == -math.pi else theta


def _float_cos_sin(x, y):
    r = math.sqrt(x * x + y * y)
    return (x / r, y / r) if r > 0.0 else (1.0, 0.0)


def _float_half_cos_sin(c, s):
    big = math.sqrt(0.5 + 0.5 * abs(c))
    other = 0.5 * s / big
    if c >= 0.0:
        return big, other
    return abs(other), (-big if s < 0.0 else big)


def _float_first(x, where):
    return x


def _float_row_of_largest(K, rows):
    k = 1 if K[1] > K[0] else 0
    if K[2] > K[k]:
        k = 2
    if K[3] > K[k]:
        k = 3
    i, j, m, n = rows[k]
    return (K[i], K[j], K[m], K[n]), K[k]


def _array_largest(x):
    return float(x.max(initial=-math.inf))


def _array_smallest(x):
    return float(x.min(initial=math.inf))


def _array_largest_of(values):
    return max(_array_largest(x) for x in values)


def _array_max_abs(x):
    return float(np.abs(x).max(initial=0.0))


def _array_first(x, where):
    return x[where].flat[0]


def _array_all_finite(x):
    return bool(np.isfinite(x).all())


def _array_row_of_largest(K, rows):
    best, row = K[0], [K[i] for i in rows[0]]
    for k in (1, 2, 3):
        larger = K[k] > best
        best = np.where(larger, K[k], best)
        row = [np.where(larger, K[i], r) for i, r in zip(rows[k], row, strict=True)]
    return row, best


def _array_clip0(x):
    return np.maximum(x, 0.0)


def _array_no_minus_pi(theta):
    # the smallest entry tells whether some entry is -pi (or below), in one pass
    return np.where(theta == -np.pi, np.pi, theta) if theta.min(initial=0.0) <= -np.pi else theta


def _array_cos_sin(x, y):
    r = np.sqrt(x * x + y * y)
    if r.min(initial=np.inf) > 0.0:       # no zero (the common case)
        return x / r, y / r
    with np.errstate(divide="ignore", invalid="ignore"):
        c, s = x / r, y / r
    zero = r == 0.0
    c[zero], s[zero] = 1.0, 0.0
    return c, s


def _array_half_cos_sin(c, s):
    big = np.sqrt(0.5 + 0.5 * np.abs(c))
    other = 0.5 * s / big
    first = c >= 0.0
    signed_big = np.where(s < 0.0, -big, big)
    return np.where(first, big, np.abs(other)), np.where(first, other, signed_big)


def _array_stack(parts):
    return np.stack(np.broadcast_arrays(*parts), axis=-1).astype(float, copy=False)


class _OnFloats:
    """The functions of a component formula on Python floats (one value): ``math``'s, and
    plain Python for the rest. The class is only a namespace (nothing binds)."""

    sqrt = math.sqrt
    sin = math.sin
    cos = math.cos
    atan2 = math.atan2
    copysign = math.copysign
    rint = round                                     # half to even, as numpy's rint
    where = staticmethod(_float_where)               # a if condition else b
    largest = float                                  # the largest entry: the value itself
    smallest = float
    largest_of = max                                 # the largest entry of several
    max_abs = abs                                    # the largest |entry|
    maximum = max                                    # the larger of two, entry by entry
    first = staticmethod(_float_first)               # the first entry where a mask is True
    all_finite = math.isfinite
    clip0 = staticmethod(_float_clip0)               # max(x, 0), never -0.0
    no_minus_pi = staticmethod(_float_no_minus_pi)   # -pi -> pi, other angles unchanged
    cos_sin = staticmethod(_float_cos_sin)           # (x, y) / |(x, y)|, (1, 0) at 0
    half_cos_sin = staticmethod(_float_half_cos_sin)  # see dqlab.ik.ur_steps.half_angle_cos_sin
    row_of_largest = staticmethod(_float_row_of_largest)   # see quaternion_from_matrix_entries
    stack = np.array                                 # parts on a last axis


class _OnArrays:
    """The same functions on numpy arrays of one common shape (a batch, column by column)."""

    sqrt = np.sqrt
    sin = np.sin
    cos = np.cos
    atan2 = np.arctan2
    copysign = np.copysign
    rint = np.rint
    where = np.where
    largest = staticmethod(_array_largest)
    smallest = staticmethod(_array_smallest)
    largest_of = staticmethod(_array_largest_of)
    max_abs = staticmethod(_array_max_abs)
    maximum = np.maximum
    first = staticmethod(_array_first)
    all_finite = staticmethod(_array_all_finite)
    clip0 = staticmethod(_array_clip0)
    no_minus_pi = staticmethod(_array_no_minus_pi)
    cos_sin = staticmethod(_array_cos_sin)
    half_cos_sin = staticmethod(_array_half_cos_sin)
    row_of_largest = staticmethod(_array_row_of_largest)
    stack = staticmethod(_array_stack)


class _FunctionsByType(dict):
    r"""The functions a component formula uses, by the type of its numbers: ``float`` (and a
    pair of floats) to :class:`_OnFloats`, any other type to :class:`_OnArrays`.

    The one switch between the two paths of every formula written on components: Python
    floats (one value; ``math`` is several times faster than numpy on single numbers) get
    ``math``'s functions, anything else (arrays of one common shape, a batch) numpy's. A
    formula reads ``f = functions_for(type(x))`` and then ``f.sqrt``, ``f.atan2``,
    ``f.where``..., the same text for both kinds; a formula whose parts may mix constants
    and arrays asks with the pair ``(type(first), type(last))``. (A dictionary lookup, not a
    Python function: the float path of one pose asks it dozens of times.)

    The namespace holds the elementary functions (``sqrt``, ``sin``, ``cos``, ``atan2``,
    ``copysign``, ``rint``, ``where``, ``maximum``) and a few small operations whose float and array
    forms differ:

    - ``largest(x)``, ``smallest(x)``, ``largest_of(values)`` and ``max_abs(x)``: the value
      itself for a float; the extreme entry of an array, as a float (:math:`\mp\infty` for
      an array without entries);
    - ``first(x, where)``: the first entry of ``x`` where the mask is true;
    - ``all_finite(x)``; ``clip0(x)``: :math:`\max(x, 0)`; ``no_minus_pi(theta)``:
      :math:`-\pi \to \pi`; ``cos_sin(x, y)``: the unit vector of :math:`(x, y)`,
      :math:`(1, 0)` at 0; ``half_cos_sin(c, s)``: see
      :func:`dqlab.ik.ur_steps.half_angle_cos_sin`;
    - ``row_of_largest(K, rows)``: Shepperd's choice, the entries ``rows[k]`` of ``K`` for
      the first ``k`` with the largest ``K[k]``, and that ``K[k]``;
    - ``stack(parts)``: the parts on a last axis.

    >>> functions_for(float).sqrt is math.sqrt, functions_for(np.ndarray).sqrt is np.sqrt
    (True, True)
    >>> functions_for((float, np.ndarray)) is functions_for(np.float64) is _OnArrays
    True
    """

    def __missing__(self, kind):
        return _OnArrays


functions_for = _FunctionsByType({float: _OnFloats, (float, float): _OnFloats}).__getitem__


# --------------------------------------------------------------------------------------
# Quaternions


def quaternion_mul(aw, ax, ay, az, bw, bx, by, bz):
    r"""Hamilton product :math:`a b`, component by component.

    >>> quaternion_mul(0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0)   # j i = -k
    (0.0, 0.0, 0.0, -1.0)
    """
    return (aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw)


def quaternion_rotate(w, x, y, z, vx, vy, vz):
    r"""The vector :math:`q\,v\,q^*` for a unit quaternion :math:`q = (w, \mathbf u)`.

    With :math:`\mathbf t = 2\,\mathbf u \times \mathbf v`:
    :math:`\mathbf v' = \mathbf v + w\,\mathbf t + \mathbf u \times \mathbf t`.

    >>> quaternion_rotate(0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0)     # half turn about z
    (-1.0, 0.0, 0.0)
    """
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    return (vx + w * tx + (y * tz - z * ty),
            vy + w * ty + (z * tx - x * tz),
            vz + w * tz + (x * ty - y * tx))


def matrix_entries_from_quaternion(w, x, y, z):
    """The nine entries (row by row) of the rotation matrix of a unit quaternion.

    >>> matrix_entries_from_quaternion(1.0, 0.0, 0.0, 0.0)
    (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    """
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    return (1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy),
            2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx),
            2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy))


# Positions of the rows of K = 4 q q^T in the tuple returned by shepperd_terms.
_K_ROWS = ((0, 4, 5, 6), (4, 1, 7, 8), (5, 7, 2, 9), (6, 8, 9, 3))


def shepperd_terms(r00, r01, r02, r10, r11, r12, r20, r21, r22):
    """The ten distinct entries of :math:`K = 4 q q^T` written with the entries of R.

    The diagonal :math:`4w^2, 4x^2, 4y^2, 4z^2`, then :math:`4wx, 4wy, 4wz, 4xy, 4xz, 4yz`
    (active convention).

    >>> shepperd_terms(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)[:4]
    (4.0, 0.0, 0.0, 0.0)
    """
    tr = r00 + r11 + r22
    return (1.0 + tr, 1.0 + r00 - r11 - r22, 1.0 - r00 + r11 - r22, 1.0 - r00 - r11 + r22,
            r21 - r12, r02 - r20, r10 - r01, r01 + r10, r02 + r20, r12 + r21)


def quaternion_from_matrix_entries(r00, r01, r02, r10, r11, r12, r20, r21, r22):
    """Unit quaternion (``w >= 0``) of a rotation matrix given by its nine entries.

    Row k of :math:`K` divided by :math:`2\\sqrt{K_{kk}}` is q, for any k; Shepperd's method
    takes the row of the largest diagonal entry (it divides by the largest component of q).

    >>> quaternion_from_matrix_entries(-1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0)
    (0.0, 0.0, 0.0, 1.0)
    """
    K = shepperd_terms(r00, r01, r02, r10, r11, r12, r20, r21, r22)
    f = functions_for(type(r00))
    (w, x, y, z), best = f.row_of_largest(K, _K_ROWS)   # the row of the largest diagonal
    s = 0.5 / f.sqrt(best)
    s = f.where(w < 0.0, -s, s)                 # canonical sign: w >= 0
    return w * s, x * s, y * s, z * s


def rotation_vector_from_quaternion_entries(w, x, y, z):
    r"""The rotation vector :math:`\theta\,\mathbf u` (:math:`\theta \in [0, \pi]`) of a unit
    quaternion :math:`(w, \mathbf v)` with :math:`w \ge 0`:
    :math:`2 \operatorname{atan2}(\lVert\mathbf v\rVert, w)\,\mathbf v / \lVert\mathbf v
    \rVert`, and 0 for the identity.

    >>> [round(c, 12) for c in rotation_vector_from_quaternion_entries(
    ...     math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))]                     # quarter turn about z
    [0.0, 0.0, 1.570796326795]
    """
    f = functions_for(type(w))
    norm_v = f.sqrt(x * x + y * y + z * z)
    turned = norm_v > 0.0
    scale = f.where(turned, 2.0 * f.atan2(norm_v, w) / f.where(turned, norm_v, 1.0), 2.0)
    return x * scale, y * scale, z * scale


def rotation_vector_from_matrix_entries(r00, r01, r02, r10, r11, r12, r20, r21, r22):
    r"""The rotation vector :math:`\theta\,\mathbf u` (axis times angle, :math:`\theta
    \in [0, \pi]`) of a rotation matrix given by its nine entries: its quaternion
    (Shepperd, :math:`w \ge 0`), then :func:`rotation_vector_from_quaternion_entries`.

    >>> [round(c, 12) for c in rotation_vector_from_matrix_entries(
    ...     0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0)]               # quarter turn about z
    [0.0, 0.0, 1.570796326795]
    """
    return rotation_vector_from_quaternion_entries(
        *quaternion_from_matrix_entries(r00, r01, r02, r10, r11, r12, r20, r21, r22))


def rigid_inverse(T):
    r"""The inverse of rigid transforms already checked (float arrays (..., 4, 4)):
    :math:`(R^\mathsf{T}, -R^\mathsf{T} p)`; :func:`dqlab.transforms.transform_inverse`
    checks its argument, then calls this."""
    Rt = np.swapaxes(T[..., :3, :3], -1, -2)
    out = np.zeros(T.shape)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -(Rt @ T[..., :3, 3:4])[..., 0]
    out[..., 3, 3] = 1.0
    return out


def pose_error_entries(a, b):
    r"""Position and rotation errors between two poses given by their 16 entries, row by row
    (see :func:`dqlab.ik.targets.pose_errors`): :math:`\lVert p - p^\ast \rVert` and the
    angle :math:`\operatorname{atan2}(\lVert (M - M^\top)^\vee\rVert, \operatorname{tr}M - 1)`
    of :math:`M = R R^{\ast\top}`.

    >>> pose_error_entries([1.0, 0, 0, 0.3, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0],
    ...                    [1.0, 0, 0, 0.0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0])
    (0.3, 0.0)
    """
    dx, dy, dz = a[3] - b[3], a[7] - b[7], a[11] - b[11]

    def dot(i, j):            # M_ij = R_i . R*_j: row i of R dotted with row j of R*
        return a[4 * i] * b[4 * j] + a[4 * i + 1] * b[4 * j + 1] + a[4 * i + 2] * b[4 * j + 2]

    vx = dot(1, 2) - dot(2, 1)
    vy = dot(2, 0) - dot(0, 2)
    vz = dot(0, 1) - dot(1, 0)
    trace = dot(0, 0) + dot(1, 1) + dot(2, 2)
    f = functions_for(type(dx))
    return (f.sqrt(dx * dx + dy * dy + dz * dz),
            f.atan2(f.sqrt(vx * vx + vy * vy + vz * vz), trace - 1.0))


# --------------------------------------------------------------------------------------
# Rotation matrices


def orthonormality(a, b, c):
    """Largest entry of :math:`|R^T R - I|` and :math:`\\det R`, R given by its rows.

    The entries are floats (one matrix) or arrays (a batch: the largest error over the batch
    and the smallest determinant are returned).

    >>> orthonormality((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, -1.0))
    (0.0, -1.0)
    """
    a0, a1, a2 = a[0], a[1], a[2]
    b0, b1, b2 = b[0], b[1], b[2]
    c0, c1, c2 = c[0], c[1], c[2]
    errs = (abs(a0 * a0 + b0 * b0 + c0 * c0 - 1.0),
            abs(a1 * a1 + b1 * b1 + c1 * c1 - 1.0),
            abs(a2 * a2 + b2 * b2 + c2 * c2 - 1.0),
            abs(a0 * a1 + b0 * b1 + c0 * c1),
            abs(a0 * a2 + b0 * b2 + c0 * c2),
            abs(a1 * a2 + b1 * b2 + c1 * c2))
    det = a0 * (b1 * c2 - b2 * c1) - a1 * (b0 * c2 - b2 * c0) + a2 * (b0 * c1 - b1 * c0)
    f = functions_for(type(det))
    return f.largest_of(errs), f.smallest(det)


# --------------------------------------------------------------------------------------
# Dual quaternions


def dual_quaternion_mul(a, b):
    r""":math:`(a_r + \varepsilon a_d)(b_r + \varepsilon b_d) = a_r b_r + \varepsilon (a_r b_d
    + a_d b_r)` on the eight components of ``a`` and ``b``.

    >>> dual_quaternion_mul((1.0, 0, 0, 0, 0, 0.5, 0, 0), (1.0, 0, 0, 0, 0, 0, 1.0, 0))
    (1.0, 0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 0.0)
    """
    arw, arx, ary, arz, adw, adx, ady, adz = a
    brw, brx, bry, brz, bdw, bdx, bdy, bdz = b
    rw, rx, ry, rz = quaternion_mul(arw, arx, ary, arz, brw, brx, bry, brz)
    d1w, d1x, d1y, d1z = quaternion_mul(arw, arx, ary, arz, bdw, bdx, bdy, bdz)
    d2w, d2x, d2y, d2z = quaternion_mul(adw, adx, ady, adz, brw, brx, bry, brz)
    return rw, rx, ry, rz, d1w + d2w, d1x + d2x, d1y + d2y, d1z + d2z


def screw_entries(lx, ly, lz, mx, my, mz, c, s, h):
    r"""The unit dual quaternion of the screw about the line :math:`(\mathbf l, \mathbf m)`.

    ``c, s`` are the cosine and sine of half the angle, ``h`` half the displacement along
    the axis (see :func:`dqlab.dualquat.dual_quaternion_from_screw`).

    >>> screw_entries(0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.5)
    (1.0, 0.0, 0.0, 0.0, -0.0, 0.0, 0.0, 0.5)
    """
    hc = h * c
    return (c, s * lx, s * ly, s * lz,
            -h * s, s * mx + hc * lx, s * my + hc * ly, s * mz + hc * lz)


def translation_from_dual_quaternion_entries(rw, rx, ry, rz, dw, dx, dy, dz):
    r"""The translation :math:`\mathbf t` of a unit dual quaternion, :math:`(0, \mathbf t) =
    2\, q_d\, q_r^*`, as three components.

    >>> translation_from_dual_quaternion_entries(1.0, 0, 0, 0, 0, 0.5, 1.0, 1.5)
    (1.0, 2.0, 3.0)
    """
    _, tx, ty, tz = quaternion_mul(dw, dx, dy, dz, rw, -rx, -ry, -rz)
    return 2.0 * tx, 2.0 * ty, 2.0 * tz


# --------------------------------------------------------------------------------------
# Norms


def norm_last_axis(a):
    r"""Euclidean norm over the last axis of an array, without overflow or underflow.

    :math:`\sqrt{\sum a_i^2}` directly where the sum of squares is a normal number (the
    result is then exactly that of the plain formula), and as
    :math:`m \sqrt{\sum (a_i / m)^2}` with :math:`m = \max |a_i|` elsewhere (entries near
    1e±154 and beyond, whose squares overflow or underflow).

    >>> norm_last_axis(np.array([3e200, 4e200])), norm_last_axis(np.array([3e-200, 4e-200]))
    (array(5.e+200), array(5.e-200))
    """
    with np.errstate(over="ignore", under="ignore"):
        n2 = np.sum(a * a, axis=-1)
    n = np.array(np.sqrt(n2))
    risky = ~((n2 > 1e-290) & (n2 < 1e290))
    if risky.any():
        sub = a[risky]
        m = np.max(np.abs(sub), axis=-1)
        safe = np.where(m > 0.0, m, 1.0)
        n[risky] = m * np.sqrt(np.sum((sub / safe[..., None]) ** 2, axis=-1))
    return n


# --------------------------------------------------------------------------------------
# Rigid bodies


def dual_cross(a, a_dual, b, b_dual):
    r"""The cross product of dual vectors (arrays (..., 3)): :math:`\mathbf a\times\mathbf b
    + \varepsilon\,(\mathbf a\times\mathbf b^\circ + \mathbf a^\circ\times\mathbf b)`
    (:func:`dqlab.dynamics.dual_cross`, which checks its arguments and calls this).

    >>> dual_cross(np.array([0.0, 0.0, 1.0]), np.zeros(3), np.array([1.0, 0.0, 0.0]),
    ...            np.zeros(3))
    (array([0., 1., 0.]), array([0., 0., 0.]))
    """
    return np.cross(a, b), np.cross(a, b_dual) + np.cross(a_dual, b)


def momentum(mass, com, tensor, omega, v):
    r"""The momentum :math:`\mathbf p + \varepsilon\mathbf L` of a body (mass :math:`m`,
    centre of mass :math:`\mathbf c`, tensor :math:`I_c` about it) moving with the twist
    :math:`\omega + \varepsilon\mathbf v` (arrays (..., 3)): :math:`\mathbf p = m\,(\mathbf v
    + \omega\times\mathbf c)`, :math:`\mathbf L = I_c\,\omega + \mathbf c\times\mathbf p`
    (:meth:`dqlab.inertia.LinkInertia.momentum`, which checks its arguments and calls this).

    >>> momentum(2.0, np.array([0.1, 0.0, 0.0]), np.zeros((3, 3)), np.array([0.0, 0.0, 1.0]),
    ...          np.zeros(3))
    (array([0. , 0.2, 0. ]), array([0.  , 0.  , 0.02]))
    """
    p = mass * (v + np.cross(omega, com))
    return p, omega @ tensor.T + np.cross(com, p)
