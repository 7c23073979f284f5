r"""Closed-form inverse kinematics of the SCARA (course notes, annex A, MGI).

For the RRPR chain of :func:`dqlab.models.scara_rsm5` the pose of the flange is

.. math::

   x = l_1 C_1 + l_2 C_{12},\quad y = l_1 S_1 + l_2 S_{12},\quad
   z = z_0 + q_3,\quad \text{yaw} = q_1 + q_2 + q_4 + \text{const},

so the arm in the horizontal plane is a planar two-link problem with two solutions (elbow
on either side), and :math:`q_3, q_4` follow.
"""

import numpy as np
from numpy.typing import ArrayLike

from .._checks import check_tolerance
from ..models import SCARA_SHAPE
from ..robot import Robot
from ..rotations import wrap_angle
from .result import IKResult, finish, target_reasons
from .targets import parse_targets, pose_errors
from .two_link import elbow_cosine, two_link_angles

__all__ = ["scara"]


def scara(robot: Robot, target: ArrayLike, *, tol: float = 1e-9,
          rotation_tol: float | None = None) -> IKResult:
    r"""Both closed-form solutions of the SCARA for a tool pose.

    The target is brought back to the flange in frame 0,
    :math:`X_{0n} = X_{W0}^{-1} X_{WT}^\ast X_{nT}^{-1}` (any base and tool are allowed),
    whose rotation must be a turn about the vertical by :math:`\psi`. Then, with
    :math:`(x, y, z)` its position,

    .. math::

       C_2 &= \frac{x^2 + y^2 - l_1^2 - l_2^2}{2 l_1 l_2},\qquad
       \theta_2 = \pm\arccos C_2,\\
       \theta_1 &= \operatorname{atan2}(y, x)
                   - \operatorname{atan2}(l_2 S_2,\; l_1 + l_2 C_2),\\
       q_3 &= z - (r_1 + r_2 + r_3^0 + r_4),\qquad
       \theta_4 = \psi - \theta_1 - \theta_2 - \theta_3^0,

    and :math:`q_i = \theta_i - \theta^0_i` for the revolute joints (angles wrapped to
    :math:`(-\pi, \pi]`).

    Parameters
    ----------
    robot : Robot
        A SCARA like :func:`dqlab.models.scara_rsm5`.
    target : array_like, shape (..., 4, 4) or (..., 8)
        Target tool poses :math:`X_{WT}^\ast` (transforms or unit dual quaternions).
    tol : float, optional
        Position tolerance in metres of a solution marked valid.
    rotation_tol : float, optional
        Rotation tolerance in radians (default ``tol``); also the largest tilt of the target
        from vertical that is accepted.

    Returns
    -------
    IKResult
        ``solutions`` of shape (..., 2, 4): row 0 with :math:`\theta_2 \ge 0`, row 1 with
        :math:`\theta_2 \le 0`. A row is valid when it is within the joint limits (the
        RSM-5's :math:`\pm 145^\circ` elbow and 150 mm stroke matter) and reproduces the
        pose. ``flags``: ``"unreachable"``, ``"tilted"`` (the target's tool axis is not
        vertical), ``"singular"`` (:math:`\sin\theta_2 = 0`: the two rows coincide).
        Invalid rows hold zeros; their errors are those of the nearest pose the arm
        reaches with that elbow (joints clipped to the limits).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import scara_rsm5
    >>> robot = scara_rsm5()
    >>> q = np.array([0.4, 0.9, 0.05, -0.3])
    >>> result = scara(robot, robot.fk(q))
    >>> result.valid
    array([ True,  True])
    >>> result.solutions.round(4) + 0.0
    array([[ 0.4   ,  0.9   ,  0.05  , -0.3   ],
           [ 1.1577, -0.9   ,  0.05  ,  0.7423]])

    Too high for the 150 mm stroke:

    >>> X = robot.fk(q)
    >>> X[2, 3] += 0.2
    >>> result = scara(robot, X)
    >>> result.valid
    array([False, False])
    >>> print(result.reason)
    unreachable: beyond the limits of joint(s) 3
    """
    tol = check_tolerance(tol, "tol")
    rotation_tol = tol if rotation_tol is None else check_tolerance(rotation_tol, "rotation_tol")
    SCARA_SHAPE.check(robot)
    l1, l2 = robot.links[1].a, robot.links[2].a
    X_WT = parse_targets(target).transforms
    X_0n = np.linalg.inv(robot.base) @ X_WT @ np.linalg.inv(robot.tool)
    raw, reachable, s2, tilt = _candidates(robot, X_0n)             # (..., 2, 4), ...
    lo, hi = robot.limits.T
    within = np.all((raw >= lo - 1e-12) & (raw <= hi + 1e-12), axis=-1)
    clipped = np.clip(raw, lo, hi)
    position_error, rotation_error = pose_errors(robot.fk(clipped), X_WT[..., None, :, :])
    ok = reachable[..., None] & within & (tilt <= rotation_tol)[..., None]
    valid = ok & (position_error <= tol) & (rotation_error <= rotation_tol)
    unreachable = ~np.any(valid, axis=-1)
    k = np.hypot(X_0n[..., 0, 3], X_0n[..., 1, 3])

    def explain(index):
        parts = []
        if tilt[index] > rotation_tol:
            parts.append(f"the tool axis is tilted {float(tilt[index]):.3g} rad from vertical")
        if k[index] > l1 + l2:
            parts.append(f"the point is {float(k[index]) - (l1 + l2):.4g} m beyond the reach")
        elif k[index] < abs(l1 - l2):
            parts.append(f"the point is {abs(l1 - l2) - float(k[index]):.4g} m too close to "
                         "axis 1")
        if not parts:
            bad = (raw[index] < lo - 1e-12) | (raw[index] > hi + 1e-12)
            joints = sorted({int(j) + 1 for j in np.nonzero(bad)[-1]})
            parts.append("beyond the limits of joint(s) " + ", ".join(map(str, joints)))
        return "unreachable: " + "; ".join(parts)

    flags = {
        "unreachable": unreachable,
        "tilted": tilt > rotation_tol,
        "singular": reachable & (s2 < 1e-7),
    }
    return finish(clipped, valid, position_error, rotation_error, flags,
                  target_reasons(unreachable, explain))


def _candidates(robot, X_0n):
    r"""Both elbow branches for flange poses ``X_0n`` in frame 0: joint vectors (..., 2, 4)
    before the limits, whether the point is within the arm's reach, :math:`|\sin\theta_2|`,
    and the tilt of the tool axis from the vertical."""
    R = X_0n[..., :3, :3]
    x, y, z = X_0n[..., 0, 3], X_0n[..., 1, 3], X_0n[..., 2, 3]
    tilt = np.arctan2(np.hypot(R[..., 0, 2], R[..., 1, 2]), R[..., 2, 2])
    psi = np.arctan2(R[..., 1, 0], R[..., 0, 0])
    links = robot.links
    l1, l2 = links[1].a, links[2].a
    off = np.array([lk.theta_offset for lk in links])      # theta_3 is the constant for P
    z0 = links[0].d + links[1].d + links[2].d + links[3].d
    c2, s2, reachable = elbow_cosine(x, y, l1, l2)
    rows = []
    for sign in (1.0, -1.0):
        t1, t2 = two_link_angles(x, y, c2, sign * s2, l1, l2)
        t4 = psi - t1 - t2 - off[2]
        q1, q2, q4 = wrap_angle(t1 - off[0]), wrap_angle(t2 - off[1]), wrap_angle(t4 - off[3])
        rows.append(np.stack([q1, q2, z - z0, q4], axis=-1))
    return np.stack(rows, axis=-2), reachable, s2, tilt
