"""The Newton kernel of the calibrated UR solver on whole matrices (``dqlab.ik.ur_calibrated``
runs it on the branches of one pose): forward kinematics, residual, damped Newton step and
singularity measures of a calibrated chain, a few numpy calls per step whatever the number
of branches. Tested equal to :meth:`dqlab.robot.Robot.fk_with_jacobian`; the readable step is
:func:`dqlab.ik.ur_calibrated_reference.newton_step`.
"""

import numpy as np

__all__ = ["DAMPING", "MatrixChain", "measures"]

DAMPING = 1e-12        # lambda = DAMPING tr(J^T J) / 6
_DIAGONAL = np.arange(6)


class MatrixChain:
    r"""Forward kinematics, residual and Newton step of a calibrated arm on whole matrices:
    frames (m, 7, 4, 4) (frame 0, frames 1..5 and the TCP, in the chain's frame 0), a few
    numpy calls per step whatever m. The kernel of one pose's branches; tested equal to
    :meth:`dqlab.robot.Robot.fk_with_jacobian`.

    Link i is :math:`A_i = \cos\theta_i K_i^c + \sin\theta_i K_i^s + K_i^1` (standard DH,
    the tool folded into :math:`A_6`), and the frames are the prefix products
    :math:`A_1 \cdots A_i`, computed in three rounds of products."""

    def __init__(self, links, tool):
        K = np.zeros((6, 3, 4, 4))
        for i, (ca, sa, a, d, _) in enumerate(links):
            K[i, 0] = [[1, 0, 0, a], [0, ca, -sa, 0], [0, 0, 0, 0], [0, 0, 0, 0]]
            K[i, 1] = [[0, -ca, sa, 0], [1, 0, 0, a], [0, 0, 0, 0], [0, 0, 0, 0]]
            K[i, 2] = [[0, 0, 0, 0], [0, 0, 0, 0], [0, sa, ca, d], [0, 0, 0, 1]]
        K[5] = K[5] @ tool
        self.K = K.reshape(6, 3, 16)
        self.offsets = np.array([lk[4] for lk in links])

    def frames(self, q):
        m = q.shape[0]
        cs = np.empty((m, 6, 1, 3))
        cs[..., 2] = 1.0
        theta = q + self.offsets
        np.cos(theta, out=cs[:, :, 0, 0])
        np.sin(theta, out=cs[:, :, 0, 1])
        F = np.empty((m, 7, 4, 4))
        F[:, 0] = np.eye(4)
        P = F[:, 1:]
        P[...] = (cs @ self.K).reshape(m, 6, 4, 4)      # the links A_1 .. A_6 (tool)
        P[:, 1:] = P[:, :-1] @ P[:, 1:]                  # prefix products in three rounds
        P[:, 2:] = P[:, :-2] @ P[:, 2:]
        P[:, 4:] = P[:, :-4] @ P[:, 4:]
        return F

    @staticmethod
    def take(F, rows):
        return F[rows]

    def put(self, F, rows, q):
        F[rows] = self.frames(q)

    @staticmethod
    def targets(X):
        return X

    @staticmethod
    def transforms(F):
        """The TCP poses (m, 4, 4) in frame 0."""
        return F[:, 6]

    @staticmethod
    def residual(F, X_target):
        """e (m, 6): the position error and the rotation vector (small angles) from the TCP
        to the target, in frame 0."""
        E = X_target[:, :3, :3] @ np.swapaxes(F[:, 6, :3, :3], -1, -2)
        e = np.empty((F.shape[0], 6))
        e[:, :3] = X_target[:, :3, 3] - F[:, 6, :3, 3]
        e[:, 3:] = 0.5 * (E.reshape(-1, 9)[:, [7, 2, 3]] - E.reshape(-1, 9)[:, [5, 6, 1]])
        return e

    @staticmethod
    def jacobian(F):
        """J (m, 6, 6) at the TCP, in frame 0, linear rows first."""
        z, r = F[:, :6, :3, 2], F[:, 6, None, :3, 3] - F[:, :6, :3, 3]
        J = np.empty((F.shape[0], 6, 6))
        J[:, 0] = z[..., 1] * r[..., 2] - z[..., 2] * r[..., 1]
        J[:, 1] = z[..., 2] * r[..., 0] - z[..., 0] * r[..., 2]
        J[:, 2] = z[..., 0] * r[..., 1] - z[..., 1] * r[..., 0]
        J[:, 3:] = np.swapaxes(z, -1, -2)
        return J

    def newton_step(self, F, e):
        """The damped Newton step (J^T J + lambda I)^-1 J^T e of every row (m, 6)."""
        J = self.jacobian(F)
        JT = np.swapaxes(J, -1, -2)
        H = JT @ J
        H[:, _DIAGONAL, _DIAGONAL] += (DAMPING / 6.0) * np.trace(H, axis1=1, axis2=2)[:, None]
        return np.linalg.solve(H, JT @ e[..., None])[..., 0]

    @staticmethod
    def singularity_measures(F):
        """(3, m): |sin| of the angle between joint axes 4 and 6, |sin| of the elbow angle
        (between the common normals x_2 and x_3) and the wrist centre's distance from the
        plane of joint 1 and joint 2's direction."""
        return measures(F[:, 1, :3, 2], F[:, 3, :3, 2], F[:, 5, :3, 2], F[:, 2, :3, 0],
                         F[:, 3, :3, 0], F[:, 5, :3, 3])


def measures(z1, z3, z5, x2, x3, o5):
    """The three singularity measures (3, m) from the vectors (m, 3) they need: |z3 x z5|,
    |x2 x x3| and |(o5 . (z0 x z1))| / |z0 x z1| with z0 = (0, 0, 1)."""
    a, b = np.stack([z3, x2]), np.stack([z5, x3])                  # (2, m, 3)
    cross = a[..., [1, 2, 0]] * b[..., [2, 0, 1]] - a[..., [2, 0, 1]] * b[..., [1, 2, 0]]
    sines = np.sqrt((cross * cross).sum(axis=-1))                   # (2, m)
    shoulder = (np.abs(z1[:, 0] * o5[:, 1] - z1[:, 1] * o5[:, 0])
                / np.hypot(z1[:, 0], z1[:, 1]))
    return np.concatenate([sines, shoulder[None]])
