"""The Newton kernel of the calibrated UR solver entry by entry (``dqlab.ik.ur_calibrated``
runs it on a batch): :class:`~dqlab._fast.calibrated_matrices.MatrixChain`'s forward
kinematics, residual, damped Newton step and singularity measures with one array per entry
of the frames, the branches along it. Tested equal to
:meth:`dqlab.robot.Robot.fk_with_jacobian` and to the matrix kernel.
"""

import numpy as np

from .calibrated_matrices import DAMPING, measures

__all__ = ["EntryChain", "cholesky_solve", "dot"]


class EntryChain:
    """The same as :class:`MatrixChain` on entries: one array per entry of the frames with
    the m branches along it, arithmetic written out (a fixed number of numpy calls per
    entry, none per branch): the kernel of a batch. Frames are an array (48, m) holding
    z_1..z_5, o_1..o_5 (frames 1..5), x_2, x_3, the TCP position and its rotation matrix row
    by row; targets an array (12, m), rotation row by row then position."""

    def __init__(self, links, tool):
        self.links = links
        self.tool = tool.tolist()
        self.no_tool = bool(np.array_equal(tool, np.eye(4)))

    def frames(self, q):
        qT = np.ascontiguousarray(q.T)
        (ca, sa, a, d, t0) = self.links[0]
        theta = qT[0] + t0
        c, s = np.cos(theta), np.sin(theta)
        x, y, z = (c, s, 0.0), (-ca * s, ca * c, sa), (sa * s, -sa * c, ca)
        o = (a * c, a * s, d)
        zs, os_, xs = [z], [o], [x]
        for ca, sa, a, d, t0 in self.links[1:]:
            theta = qT[len(zs)] + t0
            c, s = np.cos(theta), np.sin(theta)
            xn = tuple(c * xk + s * yk for xk, yk in zip(x, y, strict=True))
            yp = tuple(c * yk - s * xk for xk, yk in zip(x, y, strict=True))
            o = tuple(ok + d * zk + a * xk for ok, zk, xk in zip(o, z, xn, strict=True))
            y = tuple(ca * yk + sa * zk for yk, zk in zip(yp, z, strict=True))
            z = tuple(ca * zk - sa * yk for yk, zk in zip(yp, z, strict=True))
            x = xn
            zs.append(z)
            os_.append(o)
            xs.append(x)
        (t00, t01, t02, tx), (t10, t11, t12, ty), (t20, t21, t22, tz), _ = self.tool
        if self.no_tool:
            p, R = list(o), [(x[k], y[k], z[k]) for k in range(3)]            # R by rows
        else:
            p = [o[k] + tx * x[k] + ty * y[k] + tz * z[k] for k in range(3)]
            R = [(x[k] * t00 + y[k] * t10 + z[k] * t20, x[k] * t01 + y[k] * t11 + z[k] * t21,
                  x[k] * t02 + y[k] * t12 + z[k] * t22) for k in range(3)]
        entries = [v for vec in (*zs[:5], *os_[:5], xs[1], xs[2]) for v in vec]
        entries += p + [v for row in R for v in row]
        out = np.empty((48, q.shape[0]))
        for k, v in enumerate(entries):
            out[k] = v
        return out

    @staticmethod
    def take(F, rows):
        return F[:, rows]

    def put(self, F, rows, q):
        F[:, rows] = self.frames(q)

    @staticmethod
    def targets(X):
        return np.concatenate([X[:, :3, :3].reshape(-1, 9).T, X[:, :3, 3].T])

    @staticmethod
    def transforms(F):
        m = F.shape[1]
        X = np.zeros((m, 4, 4))
        X[:, :3, :3] = F[39:48].T.reshape(m, 3, 3)
        X[:, :3, 3] = F[36:39].T
        X[:, 3, 3] = 1.0
        return X

    @staticmethod
    def residual(F, target):
        R, Rt = F[39:48], target[:9]
        e = np.empty((6, F.shape[1]))
        np.subtract(target[9:12], F[36:39], out=e[:3])
        for k, (i, j) in enumerate(((2, 1), (0, 2), (1, 0))):     # (E_ij - E_ji) / 2
            ti, tj, ri, rj = Rt[3 * i:3 * i + 3], Rt[3 * j:3 * j + 3], R[3 * i:3 * i + 3], \
                R[3 * j:3 * j + 3]
            e[3 + k] = 0.5 * ((ti[0] * rj[0] + ti[1] * rj[1] + ti[2] * rj[2])
                              - (tj[0] * ri[0] + tj[1] * ri[1] + tj[2] * ri[2]))
        return e.T

    @staticmethod
    def _columns(F):
        """The six columns of J, each six entries (arrays, or floats for the constants)."""
        px, py, pz = F[36], F[37], F[38]
        columns = [(-py, px, 0.0, 0.0, 0.0, 1.0)]          # joint 1: z_0 = (0, 0, 1), o_0 = 0
        for i in range(5):
            zx, zy, zz = F[3 * i], F[3 * i + 1], F[3 * i + 2]
            rx, ry, rz = px - F[15 + 3 * i], py - F[16 + 3 * i], pz - F[17 + 3 * i]
            columns.append((zy * rz - zz * ry, zz * rx - zx * rz, zx * ry - zy * rx,
                            zx, zy, zz))
        return columns

    def jacobian(self, F):
        m = F.shape[1]
        J = np.empty((m, 6, 6))
        for j, column in enumerate(self._columns(F)):
            for i, v in enumerate(column):
                J[:, i, j] = v
        return J

    def newton_step(self, F, e):
        """The damped Newton step of :meth:`MatrixChain.newton_step`, by the normal
        equations solved with Cholesky on entries."""
        J = self._columns(F)
        e = e.T
        H = [[dot(J[i], J[j]) for j in range(i + 1)] for i in range(6)]
        g = [dot(J[i], e) for i in range(6)]
        lam = (DAMPING / 6.0) * sum(H[i][i] for i in range(6))
        for i in range(6):
            H[i][i] = H[i][i] + lam
        return np.array(cholesky_solve(H, g)).T

    @staticmethod
    def singularity_measures(F):
        return measures(F[0:3].T, F[6:9].T, F[12:15].T, F[30:33].T, F[33:36].T, F[27:30].T)


def dot(u, v):
    """The dot product of two 6-vectors of entries (arrays or floats), zero entries skipped."""
    total = 0.0
    for a, b in zip(u, v, strict=True):
        if not (type(a) is float and a == 0.0) and not (type(b) is float and b == 0.0):
            total = total + a * b
    return total


def cholesky_solve(H, g):
    """Solve H x = g for a symmetric positive definite H given by its lower triangle
    ``H[i][j], j <= i`` (entries), by Cholesky: H = L L^T."""
    n = len(g)
    L = [[None] * n for _ in range(n)]
    for j in range(n):
        s = H[j][j]
        for k in range(j):
            s = s - L[j][k] * L[j][k]
        L[j][j] = np.sqrt(s)
        inv = 1.0 / L[j][j]
        for i in range(j + 1, n):
            s = H[i][j]
            for k in range(j):
                s = s - L[i][k] * L[j][k]
            L[i][j] = s * inv
    y = []
    for i in range(n):
        s = g[i]
        for k in range(i):
            s = s - L[i][k] * y[k]
        y.append(s / L[i][i])
    x = [None] * n
    for i in range(n - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, n):
            s = s - L[k][i] * x[k]
        x[i] = s / L[i][i]
    return x
