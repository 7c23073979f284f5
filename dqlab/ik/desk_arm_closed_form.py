r"""Closed-form inverse kinematics of the 3-DOF desktop arm (lab report, MGI).

The chain is :func:`dqlab.models.desk_arm`: a base joint about the vertical, then a planar
two-link arm (lengths :math:`l_1, l_2`) whose shoulder sits :math:`l_3` out and
:math:`h = l_0 - l_4` up from the base frame. Every reachable point has up to four
solutions: the arm faces the point or turns its back to it (base angle :math:`\varphi` or
:math:`\varphi + \pi`), each with the elbow above or below the shoulder--hand line.
"""

import numpy as np
from numpy.typing import ArrayLike

from .._checks import check_tolerance
from .._formulas import norm_last_axis
from ..models import DESK_ARM_SHAPE
from ..robot import Robot
from ..rotations import wrap_angle
from .result import IKResult, finish, target_reasons
from .targets import parse_targets
from .two_link import elbow_cosine, two_link_angles

__all__ = ["desk_arm"]


def _lengths(robot):
    """The arm's ``h = l0 - l4, l3, l1, l2`` (checked shape)."""
    DESK_ARM_SHAPE.check(robot)
    if not np.allclose(robot.tool[:3, 3], 0.0):
        raise ValueError("desk_arm needs a tool without translation (the hand's offset is "
                         "part of the chain)")
    links = robot.links
    return links[0].d, links[0].a, links[1].a, links[2].a


def desk_arm(robot: Robot, target: ArrayLike, *, tol: float = 1e-9) -> IKResult:
    r"""All closed-form solutions for the desktop arm to put its hand at ``position``.

    With the target in the base frame :math:`(x, y, z)`, :math:`\rho = \sqrt{x^2 + y^2}` and
    :math:`\varphi = \operatorname{atan2}(y, x)`:

    .. math::

       \theta_1 &= \varphi \;\text{(facing, } r = \rho) \quad\text{or}\quad
       \varphi + \pi \;\text{(turned away, } r = -\rho),\\
       u &= r - l_3,\qquad v = z - (l_0 - l_4),\\
       \cos\theta_3 &= \frac{u^2 + v^2 - l_1^2 - l_2^2}{2 l_1 l_2},\qquad
       \theta_3 = \pm\arccos(\cdot),\\
       \theta_2 &= \operatorname{atan2}(v, u)
                   - \operatorname{atan2}(l_2 \sin\theta_3,\; l_1 + l_2\cos\theta_3).

    The angles are the chain's; :func:`dqlab.models.desk_arm_lab_from_joints` converts
    them to the lab's :math:`(q_0, q_1, q_2)`.

    **Erratum (lab report, MGI).** The report's law-of-cosines step computes
    :math:`q_1 + q_2 = \arccos\big(((d - l_3)^2 + z^2 - l_1^2 - l_2^2) / (2 l_1 l_2)\big)`
    with :math:`z` where it needs :math:`z - (l_0 - l_4)`, the height above the shoulder
    (its derivation has it right; its code drops the offset). That is why its IK table
    returns (90, 82, -6), (90, 52, 66), (90, 39, 19), (90, 86, 44) degrees instead of the
    angles (90, 90, 0), (90, 51, 65), (90, 42, 21), (90, 90, 45) of its FK table; with the
    offset restored, the formula returns the FK table's angles. A second slip, in the
    derivation only: Cramer's determinant is
    :math:`-l_2^2\sin^2\bar q_2 - (l_1 + l_2\cos\bar q_2)^2 = -k^2`, printed as
    :math:`+k^2`, so the printed :math:`\cos q_1, \sin q_1` and the atan2 built from them
    have the wrong sign and give :math:`q_1 - \pi`; the code's ``num`` and ``den`` carry the
    right signs.

    Parameters
    ----------
    robot : Robot
        :func:`dqlab.models.desk_arm` (lengths are read from its links; a base transform is
        allowed).
    target : array_like, shape (..., 3)
        Target hand positions in the world frame, metres.
    tol : float, optional
        Largest position error (metres) of a solution marked valid.

    Returns
    -------
    IKResult
        ``solutions`` of shape (..., 4, 3) in the order: facing with the elbow up, facing
        with the elbow down, turned away with the elbow up, turned away with the elbow down
        ("up": the elbow above the shoulder--hand line; :math:`\theta_3 \le 0` when facing,
        :math:`\theta_3 \ge 0` when turned away). Angles are wrapped to
        :math:`(-\pi, \pi]`. ``flags``: ``"unreachable"`` (no solution),
        ``"base_singular"`` (target on the base axis: :math:`\theta_1` is arbitrary and
        returned as 0 or :math:`\pi`), ``"elbow_singular"`` (arm stretched or folded: the
        two elbows coincide). ``rotation_error`` is 0 (position-only problem).

    Examples
    --------
    The lab's second check, 226 mm forwards along x at the table's height:

    >>> import numpy as np
    >>> from dqlab.models import desk_arm as desk_arm_model, desk_arm_lab_from_joints
    >>> arm = desk_arm_model()
    >>> result = desk_arm(arm, [0.226, 0.0, 0.0])
    >>> result.valid
    array([ True,  True,  True,  True])
    >>> np.degrees(desk_arm_lab_from_joints(result.solutions[:2])).round(1)
    array([[ 90. ,  51. ,  65. ],
           [ 90. , -75.8, -40.2]])
    >>> bool(desk_arm(arm, [1.0, 0.0, 0.0]).success)
    False
    """
    tol = check_tolerance(tol, "tol")
    h, l3, l1, l2 = _lengths(robot)
    p = parse_targets(target, position="only").positions
    solutions, reachable, s3, base_singular, k = _candidates(robot, p, (h, l3, l1, l2))
    ok = np.repeat(reachable, 2, axis=-1)
    lo, hi = robot.limits.T
    ok &= np.all((solutions >= lo) & (solutions <= hi), axis=-1)
    # For an unreachable point the clipped cosine gives the closest pose, so the reported
    # position error says how far out of reach the point is.
    X = robot.fk(solutions)
    position_error = norm_last_axis(X[..., :3, 3] - p[..., None, :])
    valid = ok & (position_error <= tol)
    unreachable = ~np.any(valid, axis=-1)

    def explain(index):
        parts = []
        for branch, label in ((0, "facing it"), (1, "turned away")):
            kk = float(k[index + (branch,)])
            if kk > l1 + l2:
                parts.append(f"{label}, {kk - (l1 + l2):.4g} m beyond the reach")
            elif kk < abs(l1 - l2):
                parts.append(f"{label}, {abs(l1 - l2) - kk:.4g} m too close to the shoulder")
            else:
                parts.append(f"{label}, beyond the joint limits")
        return "unreachable: " + "; ".join(parts)

    flags = {
        "unreachable": unreachable,
        "base_singular": base_singular,
        "elbow_singular": np.any(reachable & (np.abs(s3) < 1e-7), axis=-1) & ~unreachable,
    }
    return finish(solutions, valid, position_error, np.zeros(valid.shape), flags,
                  target_reasons(unreachable, explain))


def _candidates(robot, p, lengths):
    r"""The four candidates (..., 4, 3) for hand positions ``p`` in the world frame, whether
    each side reaches, :math:`|\sin\theta_3|` per side, whether the point is on the base
    axis, and the shoulder-to-point distance per side (..., 2)."""
    h, l3, l1, l2 = lengths
    X_0W = np.linalg.inv(robot.base)
    p0 = p @ X_0W[:3, :3].T + X_0W[:3, 3]
    x, y, z = p0[..., 0], p0[..., 1], p0[..., 2]
    rho = np.hypot(x, y)
    phi = np.arctan2(y, x)
    base_singular = rho < 1e-12

    theta1 = np.stack([phi, phi + np.pi], axis=-1)                  # (..., 2)
    u = np.stack([rho, -rho], axis=-1) - l3
    v = (z - h)[..., None]
    c3, s3, reachable = elbow_cosine(u, v, l1, l2)
    # facing: elbow up is theta3 <= 0; turned away: elbow up is theta3 >= 0
    s3_up = np.stack([-s3[..., 0], s3[..., 1]], axis=-1)
    sols = []
    for branch in (0, 1):
        for sign in (1.0, -1.0):
            t2, t3 = two_link_angles(u[..., branch], v[..., 0], c3[..., branch],
                                     sign * s3_up[..., branch], l1, l2)
            sols.append(np.stack([theta1[..., branch], t2, t3], axis=-1))
    solutions = wrap_angle(np.stack(sols, axis=-2))                 # (..., 4, 3)
    return solutions, reachable, s3, base_singular, np.hypot(u, v)
