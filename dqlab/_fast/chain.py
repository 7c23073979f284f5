r"""The compiled chain behind :class:`dqlab.robot.Robot`: the speed machinery of its forward
kinematics and Jacobian.

What it does. A :class:`CompiledChain` is built once per robot (and again when its base or
tool is assigned) from the constant factors of the links: the factors of neighbouring links
are multiplied in advance, :math:`X_{WT} = K_0 J_1 K_1 J_2 \cdots J_n K_n` with the joint
motions :math:`J_i = R_z(\theta_i) T_z(d_i)`, and a factor that is a screw about :math:`x`
(every one between two DH links, :math:`T_x(a) R_x(\alpha)`) is recognised, so that
multiplying by it touches only the entries it changes. The product is then unrolled on the
twelve entries of the top three rows (as matrices) or the eight components (as dual
quaternions), one formula for Python floats and for arrays, and run in three regimes: one
joint vector on Python floats (after a gate that checks a float64 vector of the right shape
as :meth:`~dqlab.robot.Robot.check_joints` would), a few joint vectors one by one, a batch
column by column in blocks (:func:`dqlab._checks.batched`).

Tested equal to the readable definition. :meth:`dqlab.robot.Robot.link_transforms` is the
definition: :math:`X_{WT} = X_{W0} X_{01}(q_1) \cdots X_{n-1,n}(q_n) X_{nT}`, each link a
product of 4x4 matrices. ``tests/test_robot.py`` holds the compiled chain to it
(``test_fk_is_the_product_of_link_transforms_with_base_and_tool``), to the two
dual-quaternion constructions and to finite differences (the Jacobian), for batches of
every size and for one joint vector on floats.
"""

import numpy as np

from .._checks import batched
from .._formulas import dual_quaternion_mul, functions_for, screw_entries
from ..dualquat import dual_quaternion_from_transform

__all__ = ["CompiledChain"]

_FEW = 8    # up to this many joint vectors, Python floats beat numpy's per-call overhead
_FLOAT64 = np.dtype(np.float64)


class CompiledChain:
    r"""The precomputed constants of a chain and its unrolled products.

    Parameters
    ----------
    joints : list of (float, float, bool)
        Per link: the angle offset :math:`\theta^0_i`, the offset :math:`d_i` and whether
        the joint is revolute.
    L, R : ndarray, shape (n, 4, 4)
        The constant factors of the links, :math:`X_{i-1,i} = L_i J_i R_i`.
    base, tool : ndarray, shape (4, 4)
    check : callable
        The robot's :meth:`~dqlab.robot.Robot.check_joints`, for joint vectors that the
        float gate does not take.
    """

    def __init__(self, joints, L, R, base, tool, check):
        n = len(joints)
        self._n = n
        self._R = R
        self._check = check
        # (theta_i offset, d_i offset, revolute?) as Python values for the products
        self._joint_constants = joints
        # the shape of a joint vector that the float path takes: none with prismatic joints
        # (their limits are checked by check_joints)
        self._float_path_shape = (n,) if all(r for _, _, r in joints) else None
        # The constant factors of neighbouring links multiplied once:
        # X_WT = K_0 J_1 K_1 J_2 ... J_n K_n, K_0 = X_W0 L_1, K_i = R_i L_{i+1}, K_n = R_n X_nT
        K = np.concatenate([base[None] @ L[:1], R[:-1] @ L[1:], R[-1:] @ tool[None]])
        self._K0_columns = [tuple(K[0, :3, j].tolist()) for j in range(4)]
        self._base_columns = [tuple(base[:3, j].tolist()) for j in range(4)]
        # the top three rows of each K_i, for a constant factor that is not a screw about x
        K_rows = [tuple(map(tuple, K[i, :3].tolist())) for i in range(n + 1)]
        self._K_dual_quaternions = dual_quaternion_from_transform(K).tolist()
        # which K_i are screws about x (every one between two DH links is: Tx(a) Rx(alpha)):
        # (cos alpha, sin alpha, a) for the matrices, (cos alpha/2, sin alpha/2, a/2) for the
        # dual quaternions; None for another K_i, () for the identity
        screws = [_x_screw_constants(K[i], self._K_dual_quaternions[i]) for i in range(n + 1)]
        matrix_screws = [None if c is None else () if c[:3] == (1.0, 0.0, 0.0)
                         else c[:3] for c in screws]
        dq_screws = [None if c is None else () if c[:3] == (1.0, 0.0, 0.0)
                     else c[3:] for c in screws]
        # per link, what the products read: the joint's constants and the factor after it
        self._matrix_steps = list(zip(joints, matrix_screws[1:], K_rows[1:], strict=True))
        self._dq_steps = list(zip(joints, dq_screws[1:], self._K_dual_quaternions[1:],
                                  strict=True))
        # the zero pose: joint axes in the world frame and the TCP (fk_dq_screw's constants)
        X0, before, _ = self._product([0.0] * n, record=True)
        self.zero_pose = (np.array([X[3] for X in before]), np.array([X[2] for X in before]),
                          _matrix_from_columns(X0))
        points, axes, X_WT0 = self.zero_pose
        lines = np.concatenate([axes, np.cross(points, axes)], axis=-1)
        self._screw_constants = (lines.tolist(), dual_quaternion_from_transform(X_WT0).tolist())

    # -- the regimes ---------------------------------------------------------------------
    def joint_floats(self, q):
        """One joint vector as a list of Python floats, checked as
        :meth:`~dqlab.robot.Robot.check_joints` checks it, for the float path of a single
        call; None when ``q`` is anything but a float64 array of shape (n,) of a robot
        without prismatic joints, or when the check fails (``check_joints`` then says why)."""
        if not (type(q) is np.ndarray and q.shape == self._float_path_shape
                and q.dtype is _FLOAT64):
            return None
        floats = q.tolist()
        total = sum(floats)            # NaN or inf in q make it NaN or inf
        return floats if total - total == 0.0 else None

    # -- what the robot asks for -----------------------------------------------------------
    # Each product is run on one joint vector through the float gate (Python floats), and on
    # anything else after the robot's check, on components (_on_components).

    def pose(self, q):
        """:math:`X_{WT}` (..., 4, 4) of joint vectors (unchecked)."""
        floats = self.joint_floats(q)
        if floats is not None:
            return np.array(self._pose_entries(floats)).reshape(4, 4)
        return _on_components(self._pose_entries, self._check(q), (4, 4))

    def frames(self, q):
        """The frames 0..n in W (..., n + 1, 4, 4) of checked joint vectors, the last one
        the TCP."""
        last = self._n + 1
        frames = _on_components(self._frame_entries, q, (last, 4, 4))
        # frames hold K_0 J_1 ... J_i (after joint i); frame i is that times R_i
        frames[..., 1:last - 1, :, :] = frames[..., 1:last - 1, :, :] @ self._R[:-1]
        return frames

    def axes_and_tcp_position(self, q):
        """Joint axis points and directions (..., n, 3) and the TCP position (..., 3) of
        checked joint vectors."""
        n = self._n
        flat = _on_components(self._axes_entries, q, (2 * n + 1, 3))
        return flat[..., 0:2 * n:2, :], flat[..., 1:2 * n:2, :], flat[..., 2 * n, :]

    def dual_quaternion(self, q):
        r""":math:`\hat Q_{WT}` (..., 8) of joint vectors (unchecked), link by link."""
        floats = self.joint_floats(q)
        if floats is not None:
            return np.array(self._fk_dq_parts(floats))
        return _on_components(self._fk_dq_parts, self._check(q), (8,))

    def screw_dual_quaternion(self, q):
        r""":math:`\hat Q_{WT}` (..., 8) of checked joint vectors, by base-frame screws."""
        return _on_components(self._fk_dq_screw_parts, q, (8,))

    def jacobian(self, q):
        """The geometric Jacobian (..., 6, n) of joint vectors (unchecked)."""
        floats = self.joint_floats(q)
        if floats is not None:
            return np.array(self._jacobian_entries(floats)).reshape(6, self._n)
        return _on_components(self._jacobian_entries, self._check(q), (6, self._n))

    def pose_and_jacobian(self, q):
        """:meth:`pose` and :meth:`jacobian` (..., 4, 4), (..., 6, n) from one product."""
        floats = self.joint_floats(q)
        if floats is not None:
            flat = np.array(self._pose_jacobian_entries(floats))
        else:
            flat = _on_components(self._pose_jacobian_entries, self._check(q),
                                  (16 + 6 * self._n,))
        lead = flat.shape[:-1]
        return flat[..., :16].reshape(lead + (4, 4)), flat[..., 16:].reshape(lead + (6, self._n))

    # -- the unrolled products -----------------------------------------------------------
    def _product(self, q, record=False):
        r"""The chain's one product, :math:`X_{WT} = K_0 J_1 K_1 \cdots J_n K_n`.

        The top three rows of the running product are kept as four columns
        :math:`(u, v, w, p)`, entry by entry: the joint motion ``X @ Rz(theta) Tz(d)``
        turns :math:`u, v` and moves :math:`p` along :math:`w`; the constant factor between
        two DH links, ``@ Tx(a) Rx(alpha)``, turns :math:`v, w` and moves :math:`p` along
        :math:`u`; any other constant factor (a base or a tool) adds multiples of columns.
        ``q`` holds the joint values: Python floats (one joint vector; an entry is a float)
        or arrays of shape (N,) (a batch; an entry is an array of shape (N,) or a constant
        float), one formula for both.

        Returns the four columns of :math:`X_{WT}`; with ``record``, also the running
        products before and after each joint motion (lists of n column sets): before joint
        i it is the frame whose z axis is joint i's axis.
        """
        f = functions_for(type(q[0]))
        cos, sin = f.cos, f.sin
        (ux, uy, uz), (vx, vy, vz), (wx, wy, wz), (px, py, pz) = self._K0_columns
        before, after = [], []
        for q_i, ((theta0, d0, revolute), screw, K) in zip(q, self._matrix_steps, strict=True):
            if record:
                before.append(((ux, uy, uz), (vx, vy, vz), (wx, wy, wz), (px, py, pz)))
            if revolute:
                c, s = cos(q_i + theta0), sin(q_i + theta0)
                d = d0
            else:
                c, s = cos(theta0), sin(theta0)
                d = q_i + d0
            # @ Rz(theta) Tz(d)
            ux, uy, uz, vx, vy, vz = (c * ux + s * vx, c * uy + s * vy, c * uz + s * vz,
                                      c * vx - s * ux, c * vy - s * uy, c * vz - s * uz)
            if not revolute or d != 0.0:
                px, py, pz = px + d * wx, py + d * wy, pz + d * wz
            if record:
                after.append(((ux, uy, uz), (vx, vy, vz), (wx, wy, wz), (px, py, pz)))
            if screw:                                   # @ Tx(a) Rx(alpha)
                ca, sa, a = screw
                if sa != 0.0 or ca != 1.0:
                    vx, vy, vz, wx, wy, wz = (ca * vx + sa * wx, ca * vy + sa * wy,
                                              ca * vz + sa * wz, ca * wx - sa * vx,
                                              ca * wy - sa * vy, ca * wz - sa * vz)
                if a != 0.0:
                    px, py, pz = px + a * ux, py + a * uy, pz + a * uz
            elif screw is None:                         # @ K, any rigid transform
                (k00, k01, k02, k03), (k10, k11, k12, k13), (k20, k21, k22, k23) = K
                ux, uy, uz, vx, vy, vz, wx, wy, wz, px, py, pz = (
                    k00 * ux + k10 * vx + k20 * wx, k00 * uy + k10 * vy + k20 * wy,
                    k00 * uz + k10 * vz + k20 * wz,
                    k01 * ux + k11 * vx + k21 * wx, k01 * uy + k11 * vy + k21 * wy,
                    k01 * uz + k11 * vz + k21 * wz,
                    k02 * ux + k12 * vx + k22 * wx, k02 * uy + k12 * vy + k22 * wy,
                    k02 * uz + k12 * vz + k22 * wz,
                    k03 * ux + k13 * vx + k23 * wx + px, k03 * uy + k13 * vy + k23 * wy + py,
                    k03 * uz + k13 * vz + k23 * wz + pz)
        X = ((ux, uy, uz), (vx, vy, vz), (wx, wy, wz), (px, py, pz))
        return (X, before, after) if record else X

    def _pose_entries(self, q):
        return _entries(self._product(q))

    def _frame_entries(self, q):
        X, _, after = self._product(q, record=True)
        return (_entries(self._base_columns) + sum((_entries(Y) for Y in after[:-1]), ())
                + _entries(X))

    def _axes_entries(self, q):
        X, before, _ = self._product(q, record=True)
        return sum((tuple(B[3]) + tuple(B[2]) for B in before), ()) + tuple(X[3])


    def _fk_dq_parts(self, q):
        r"""The product :math:`\hat K_0 \hat J_1 \hat K_1 \cdots \hat J_n \hat K_n` on the
        eight components :math:`(r, d)` of the running product :math:`\hat Q = r +
        \varepsilon d`.

        Both factors of a link are screws, about z (the joint) and about x (the constant
        factor between two DH links), and multiplying by a screw skips the zeros of the
        general product. With :math:`(c, s)` the cosine and sine of half the angle and
        :math:`h` half the displacement, the screw about the unit axis :math:`u = k` or
        :math:`i` is :math:`\hat S = \rho + \varepsilon\, h u \rho`, :math:`\rho = c + s u`;
        since :math:`u` and :math:`\rho` commute,

        .. math::

            \hat Q \hat S = r \rho + \varepsilon\,\bigl(d \rho + h\, (r \rho)\, u\bigr),

        where, for :math:`p = (w, x, y, z)`, :math:`p\,(c + s k) = (c w - s z, c x + s y,
        c y - s x, c z + s w)`, :math:`p k = (-z, y, -x, w)`, :math:`p\,(c + s i) = (c w - s x,
        c x + s w, c y + s z, c z - s y)` and :math:`p i = (-x, w, z, -y)`.

        ``q`` holds the joint values one per joint: Python floats (one joint vector) or
        arrays of shape (N,) (a batch), one formula for both. The factors are validated unit
        dual quaternions, so nothing is checked here.
        """
        f = functions_for(type(q[0]))
        cos, sin = f.cos, f.sin
        rw, rx, ry, rz, dw, dx, dy, dz = self._K_dual_quaternions[0]
        for q_i, ((theta0, d0, revolute), screw, K) in zip(q, self._dq_steps, strict=True):
            if revolute:
                half, h = 0.5 * (q_i + theta0), 0.5 * d0
            else:
                half, h = 0.5 * theta0, 0.5 * (q_i + d0)
            c, s = cos(half), sin(half)                 # the joint, a screw about z
            rw, rx, ry, rz, dw, dx, dy, dz = (
                c * rw - s * rz, c * rx + s * ry, c * ry - s * rx, c * rz + s * rw,
                c * dw - s * dz, c * dx + s * dy, c * dy - s * dx, c * dz + s * dw)
            if not revolute or h != 0.0:
                dw, dx, dy, dz = dw - h * rz, dx + h * ry, dy - h * rx, dz + h * rw
            if screw:                                   # the constant, a screw about x
                c, s, h = screw
                if s != 0.0 or c != 1.0:
                    rw, rx, ry, rz, dw, dx, dy, dz = (
                        c * rw - s * rx, c * rx + s * rw, c * ry + s * rz, c * rz - s * ry,
                        c * dw - s * dx, c * dx + s * dw, c * dy + s * dz, c * dz - s * dy)
                if h != 0.0:
                    dw, dx, dy, dz = dw - h * rx, dx + h * rw, dy + h * rz, dz - h * ry
            elif screw is None:                         # any other rigid transform
                rw, rx, ry, rz, dw, dx, dy, dz = dual_quaternion_mul(
                    (rw, rx, ry, rz, dw, dx, dy, dz), K)
        return rw, rx, ry, rz, dw, dx, dy, dz



    def _fk_dq_screw_parts(self, q):
        """The product S_1 S_2 ... S_n Q_WT(0) on components (``q`` as in _fk_dq_parts)."""
        f = functions_for(type(q[0]))
        cos, sin = f.cos, f.sin
        lines, Q = self._screw_constants
        for i in range(self._n - 1, -1, -1):
            if self._joint_constants[i][2]:
                half, h = 0.5 * q[i], 0.0
            else:
                half, h = 0.0, 0.5 * q[i]
            Q = dual_quaternion_mul(screw_entries(*lines[i], cos(half), sin(half), h), Q)
        return Q


    def _jacobian_entries(self, q):
        X, before, _ = self._product(q, record=True)
        return self._jacobian_of(before, X[3])

    def _pose_jacobian_entries(self, q):
        X, before, _ = self._product(q, record=True)
        return _entries(X) + self._jacobian_of(before, X[3])

    def _jacobian_of(self, before, p):
        """The 6 n entries of the Jacobian, row by row, from the running products before
        each joint (whose columns 2 and 3 are the joint's axis z_i and a point o_i on it)
        and the TCP position ``p``: the column is (z_i x (p - o_i), z_i) for a revolute
        joint, (z_i, 0) for a prismatic one."""
        px, py, pz = p
        columns = []
        for (_, _, (zx, zy, zz), (ox, oy, oz)), (_, _, revolute) in zip(
                before, self._joint_constants, strict=True):
            if revolute:
                rx, ry, rz = px - ox, py - oy, pz - oz
                columns.append((zy * rz - zz * ry, zz * rx - zx * rz, zx * ry - zy * rx,
                                zx, zy, zz))
            else:
                columns.append((zx, zy, zz, 0.0, 0.0, 0.0))
        return sum(zip(*columns, strict=True), ())         # row by row


def _on_components(parts, q, trailing):
    """Run a formula on joint values, ``parts(q_1, ..., q_n) -> entries``, for checked joint
    vectors ``q`` of shape (..., n): with Python floats for one joint vector (or each of a
    few), and with arrays of shape (N,) per joint for blocks of a batch. Returns shape
    (...) + trailing."""
    if q.ndim == 1:
        return np.array(parts(q.tolist())).reshape(trailing)
    if q.size <= _FEW * q.shape[-1]:
        rows = q.reshape(-1, q.shape[-1]).tolist()
        return np.array([parts(row) for row in rows]).reshape(q.shape[:-1] + trailing)

    def kernel(block):
        entries = parts(list(np.ascontiguousarray(block.T)))
        out = np.empty((block.shape[0], len(entries)))
        for k, entry in enumerate(entries):     # constants (floats) broadcast
            out[:, k] = entry
        return out.reshape(out.shape[:1] + trailing)

    return batched(kernel, [(q, 1)], trailing)


def _x_screw_constants(K, K_dual_quaternion):
    r"""``(cos alpha, sin alpha, a, cos alpha/2, sin alpha/2, a/2)`` when the constant
    factor ``K`` is a screw about x, :math:`T_x(a) R_x(\alpha)` (the factor between two
    links in either DH convention), else None."""
    (k00, k01, k02, a), (k10, c, k12, k13), (k20, s, k22, k23), _ = K.tolist()
    if not (k00 == 1.0 and k01 == k02 == k10 == k20 == k13 == k23 == 0.0
            and k22 == c and k12 == -s):
        return None
    cw, cx, cy, cz, *_ = K_dual_quaternion
    if not cy == cz == 0.0:  # pragma: no cover -- Shepperd's quaternion of Rx is (c, s, 0, 0)
        return None
    return c, s, a, cw, cx, 0.5 * a


def _entries(X):
    """The 16 entries, row by row, of the 4x4 whose top rows are the columns ``X``."""
    return (X[0][0], X[1][0], X[2][0], X[3][0],
            X[0][1], X[1][1], X[2][1], X[3][1],
            X[0][2], X[1][2], X[2][2], X[3][2],
            0.0, 0.0, 0.0, 1.0)


def _matrix_from_columns(X):
    """A (4, 4) array from the float columns of a product."""
    return np.array(_entries(X)).reshape(4, 4)
