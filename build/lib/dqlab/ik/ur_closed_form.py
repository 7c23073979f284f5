r"""Closed-form inverse kinematics of the Universal Robots arms, by dual quaternions.

:func:`ur` returns every solution of a UR-family arm (UR3, UR5, UR10 and the e-series share
the structure) for one pose or a batch, following the route of the thesis (section 4.3):
write the pose as the product of the joint dual quaternions :math:`Q_1 \cdots Q_6` and
equate the products :math:`M_i = Q_i M_{i+1}` with :math:`N_{i+1} = Q_i^{-1} N_i` term by
term. The route has four steps, each a small function of :mod:`dqlab.ik.ur_steps`:

1. :math:`\theta_1` from the translation of :math:`M_5 = N_5`: the wrist centre
   :math:`p_5 = p_6 - d_6 z_6` satisfies :math:`\sin\theta_1 x_5 - \cos\theta_1 y_5 = d_4`,
   two roots when :math:`x_5^2 + y_5^2 \ge d_4^2`
   (:func:`~dqlab.ik.ur_steps.shoulder_angles`);
2. :math:`\theta_5` and the sum and difference :math:`\theta_{234} \pm \theta_6` from the
   rotation part of :math:`M_2 = N_2`, four quaternion coefficients read with ``atan2`` only
   (:func:`~dqlab.ik.ur_steps.wrist_angles`);
3. the wrist-1 point from the translation of :math:`Q_2 Q_3 Q_4 Q_4^{-1}`
   (:func:`~dqlab.ik.ur_steps.wrist1_point`);
4. the planar chain :math:`\theta_3, \theta_2` by the law of cosines and ``atan2``, then
   :math:`\theta_4 = \theta_{234} - \theta_2 - \theta_3`
   (:func:`~dqlab.ik.ur_steps.elbow_angles`).

A candidate is valid when it reproduces the pose to ``tol`` (1e-9 m and 1e-9 rad by
default; the thesis filters by forward kinematics with ``np.allclose(..., atol=1e-3)``). Its
distance to the pose comes from the solved equations (only a step that had to clip leaves
one) or, with ``residuals="fk"``, from :meth:`dqlab.robot.Robot.fk` of every row.

The frames are UR's standard-DH ones, base at the foot of joint 1 and the flange frame of
the DH chain, the same as the controller's and as ``ur_analytic_ik``'s (whose
``*_with_tcp(pose, X_6T)`` variants match ``tool=X_6T`` here), so results compare directly.

.. rubric:: Solution order

Row ``k = 4 s + 2 e + w`` of the ``(..., 8, 6)`` solutions holds

- ``s`` -- shoulder: 0 ("left") when the wrist centre lies on the :math:`+x_1` side of the
  base axis, :math:`\cos\theta_1 x_5 + \sin\theta_1 y_5 \ge 0`; 1 ("right") otherwise;
- ``e`` -- elbow: 0 ("up") when :math:`\sin\theta_3 \ge 0`; 1 ("down") when
  :math:`\sin\theta_3 \le 0`;
- ``w`` -- wrist: 0 (not flipped) when :math:`\theta_5 \in [0, \pi]`; 1 (flipped) when
  :math:`\theta_5 \in [-\pi, 0]`.

Angles are wrapped to :math:`(-\pi, \pi]`; :func:`equivalent_solutions` lists their
:math:`2\pi`-equivalents within the joint limits and :func:`closest_solution` picks the one
nearest a given configuration.

.. rubric:: Errata of the source

The thesis (section 4.3, program in 4.4) reaches the right solutions in exact arithmetic,
but:

1. The printed :math:`Q_5^{-1}` carries the translation :math:`\langle d_6 i\rangle`; undoing
   :math:`Q_5` needs :math:`\langle d_6 j\rangle` (the program has it right:
   ``vector=[0, d[5], 0]``).
2. The :math:`Q_4^{-1}` of section 4.3.4 is a copy of :math:`Q_5^{-1}`; undoing the wrist-1
   offset needs the translation :math:`\langle d_5 k\rangle` (again the program is right).
3. (4.18)-(4.21) divide the four rotation equations by :math:`\bar c_5 =
   \cos\frac{\theta_5}{2}` (for :math:`\alpha, \gamma`) and :math:`\bar s_5 =
   \sin\frac{\theta_5}{2}` (for :math:`\beta, \delta`), which blows up near
   :math:`\theta_5 = \pm\pi` and :math:`\theta_5 = 0`. The restatement of :math:`\alpha`
   and :math:`\gamma` in section 4.4 divides them by :math:`\bar s_5` instead of
   :math:`\bar c_5` (the program's ``tm1``, ``tm3`` divide correctly). Here nothing is
   divided: :math:`\frac{\Sigma}{2} = \operatorname{atan2}(-L_y, L_w)` and
   :math:`\frac{\Delta}{2} = \operatorname{atan2}(\sigma L_x, -\sigma L_z)`, with
   :math:`\alpha = \cos\frac{\Sigma}{2}`, :math:`\gamma = \sin\frac{\Sigma}{2}`,
   :math:`\beta = \sin\frac{\Delta}{2}`, :math:`\delta = \cos\frac{\Delta}{2}`.
4. The :math:`\theta_6` formula (4.28), :math:`\theta_6 = 2\operatorname{atan2}(\gamma -
   \beta, \alpha + \delta)`, is 0/0 whenever :math:`\theta_2 + \theta_3 + \theta_4 \equiv
   \pi`: by the sum-to-product formulas :math:`\gamma - \beta = 2\cos\frac{\theta_{234}}{2}
   \sin\frac{\theta_6}{2}` and :math:`\alpha + \delta = 2\cos\frac{\theta_{234}}{2}
   \cos\frac{\theta_6}{2}`, both zero there -- a regular configuration, and the thesis's own
   test pose is one. It also needs :math:`\theta_5 \neq 0, \pm\pi` for the divisions above. Here
   :math:`\theta_6 = \frac{\Sigma}{2} - \frac{\Delta}{2}` and
   :math:`\theta_{234} = \frac{\Sigma}{2} + \frac{\Delta}{2}`, defined everywhere.
5. :math:`\theta_5` by (4.13), :math:`\pm\arccos\frac{x_6 \sin\theta_1 - y_6 \cos\theta_1 -
   d_4}{d_6}`, loses half the digits near :math:`\theta_5 = 0` and :math:`\pm\pi`: an error
   of :math:`10^{-16}` in the argument becomes :math:`10^{-8}` in the angle, although the
   orientation determines :math:`\theta_5` to full accuracy there (the wrist singularity
   spoils :math:`\theta_4` and :math:`\theta_6`, not :math:`\theta_5`). Here
   :math:`\theta_5 = 2\operatorname{atan2}(\bar s_5, \bar c_5)` with both half-angle terms
   computed as norms of quaternion coefficients. (For :math:`\theta_3`, (4.38), the
   ``acos`` costs little more than the problem's own conditioning: near a straight or
   folded elbow a rounding of the position moves :math:`\theta_3` by
   :math:`\sqrt{\varepsilon}` whatever the formula -- the thesis's run prints
   :math:`\theta_3 = \pm 2.98 \cdot 10^{-8}` at its test pose, which reproduces the pose
   to :math:`10^{-16}` just as :math:`\theta_3 = 0` does.)
6. The program repairs ``acos`` arguments slightly outside :math:`[-1, 1]` by rounding them
   to an integer: any argument in :math:`(-1.5, 1.5)` passes, so unreachable poses give
   spurious "solutions" that only the 1e-3 forward-kinematics filter can reject (and
   1e-3 is loose enough to let some through). Here the clipped candidates are kept only if
   they reproduce the pose to ``tol``.
7. The :math:`\theta_1` square root :math:`\sqrt{x_5^2 + y_5^2 - d_4^2}` of (4.11) fails
   (NaN) at the shoulder singularity unless its argument is clipped at zero.
8. The program's parameter arrays are laid out in the row order of table 4.1 (Craig's
   modified DH, :math:`\alpha_{i-1}, a_{i-1}`), while the text gives table 4.2 (UR's
   standard DH, :math:`\alpha_i, a_i`) as the parameters: read with table 4.2's indices,
   ``a`` and ``alpha`` are shifted by one joint. Here the lengths come from the robot's
   standard-DH links, ``robot.links[i].d / .a / .alpha``.
9. At the wrist singularity (:math:`\theta_5 = 0` or :math:`\pm\pi`, where the thesis's
   test pose lies) only :math:`\theta_{234} + \theta_6` (or the difference) is determined;
   the thesis reports a single :math:`\theta_6 = 0` without saying that it chose it. Here
   the choice is explicit (``q_ref``) and flagged.
"""

import math
import weakref
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._checks import (
    as_float_array,
    check_tolerance,
    component_rows,
    rigid_rows,
    unit_dual_quaternion_or_raise,
)
from .._kernels import (
    quaternion_from_matrix_entries,
    quaternion_rotate,
    translation_from_dual_quaternion_entries,
    wrapped_angle,
)
from ..dualquat import (
    dual_quaternion_conjugate,
    dual_quaternion_from_transform,
    dual_quaternion_inverse,
    dual_quaternion_product,
)
from ..models import UR_SHAPE
from ..robot import Robot
from ..transforms import transform_inverse
from . import ur_steps as steps
from .result import IKResult, finish
from .targets import RIGID_TOL, parse_targets, pose_errors
from .ur_calibrated import calibrated_ur, nominal_ur

__all__ = ["ur", "ur_parameters", "equivalent_solutions", "closest_solution",
           "distinct_solutions", "SOLUTION_ORDER"]

_HALF_SQRT2 = math.sqrt(0.5)           # a Python float: it serves floats and arrays
_FLOAT64 = np.dtype(np.float64)
_CHUNK = 2048                    # poses per block: temporaries of 128 kB at most (L2-sized)
_FLAGS = ("wrist_singular", "shoulder_singular", "elbow_singular", "unreachable")
_EYE_BYTES = np.eye(4).tobytes()
_MAX_EQUIVALENT_JOINTS = 12                # 4096 candidates per joint vector
_NEAR_WRIST = 1e-3                        # |sin theta5| below which a clipped row is moved
_SIGMA = np.array([[1.0], [-1.0]])        # wrist branch w = 0, 1, axis -2 of (s, w, n)
_ELBOW = np.array([[[1.0]], [[-1.0]]])    # elbow branch e = 0, 1, axis -3 of (s, e, w, n)

#: ``(shoulder, elbow, wrist)`` labels of the eight rows, in order ``k = 4 s + 2 e + w``.
SOLUTION_ORDER = tuple(
    (s, e, w) for s in ("left", "right") for e in ("up", "down") for w in ("noflip", "flip"))

#: Why a pose has no solution (``IKResult.reason``), from the first step that fails.
REASON_SHOULDER = ("shoulder: the wrist centre p5 = p6 - d6 z6 lies inside the cylinder "
                   "x5^2 + y5^2 < d4^2 about the base axis")
REASON_OUTER = ("elbow: the wrist-1 point is farther from the shoulder than |a2| + |a3| on "
                "every branch")
REASON_INNER = ("elbow: the wrist-1 point is closer to the shoulder than ||a2| - |a3|| on "
                "every branch")
REASON_REACH = "elbow: the wrist-1 point is out of the forearm's reach on every branch"
REASON_TOL = "no branch reproduces the pose within tol"


_CHECKED = weakref.WeakKeyDictionary()    # robot -> its parameters (links are immutable)


def _parameters(robot):
    """:func:`ur_parameters` of a robot, checked once per robot."""
    try:
        return _CHECKED[robot]
    except (KeyError, TypeError):
        prm = ur_parameters(robot)
        a2, a3 = prm["a2"], prm["a3"]
        # what one pose on floats reads: the lengths, the forearm's reach, the offsets
        prm["single"] = (prm["d1"], a2, a3, prm["d4"], prm["d5"], abs(a2 + a3),
                         abs(a2 - a3), prm["offsets"] if any(prm["offsets"]) else None)
        _CHECKED[robot] = prm
        return prm


def ur_parameters(robot: Robot, *, atol: float = 1e-12) -> dict:
    r"""The standard DH lengths of a UR-family arm, checked.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        Six revolute joints in standard DH with :math:`\alpha = (\pi/2, 0, 0, \pi/2,
        -\pi/2, 0)`, :math:`a_1 = a_4 = a_5 = a_6 = 0` and :math:`d_2 = d_3 = 0`.
    atol : float
        Tolerance of the structural checks.

    Returns
    -------
    dict
        ``d1, a2, a3, d4, d5, d6`` (floats) and ``offsets`` (the six joint-angle offsets,
        a list of floats).

    Raises
    ------
    ValueError
        If the robot does not have the UR structure.

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> p = ur_parameters(ur3())
    >>> p["d1"], p["a2"], p["a3"], p["d4"], p["d5"], p["d6"]
    (0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819)
    """
    UR_SHAPE.check(robot, atol=atol)
    links = robot.links
    return {"d1": links[0].d, "a2": links[1].a, "a3": links[2].a, "d4": links[3].d,
            "d5": links[4].d, "d6": links[5].d,
            "offsets": [lk.theta_offset for lk in links]}


@dataclass
class _Flange:
    """The flange poses :math:`X_{06}` of a block of n targets, batch axis last: rotation
    quaternions ``q`` (4, n) and wrist centres ``p5`` (3, n) in the base frame 0."""

    q: np.ndarray
    p5: np.ndarray

    def __getitem__(self, part):
        return _Flange(self.q[:, part], self.p5[:, part])


@dataclass
class _Options:
    """What the steps need besides the poses: tolerances, residual mode, the tool change
    ``tool_fix`` (``None``, or :math:`X_{6T_r}^{-1} X_{6T}` from the robot's tool to the
    one asked for) for forward kinematics."""

    tol: float
    singular_tol: float
    residuals: str
    tool_fix: np.ndarray


@dataclass
class _Branches:
    """The eight candidate joint vectors of a block of n poses and the intermediate values
    the checks need; arrays over the branch axes (s, e, w) with the poses last."""

    solutions: np.ndarray      # (6, 8, n), wrapped to (-pi, pi]
    h: np.ndarray              # (n,) sqrt(x5^2 + y5^2 - d4^2), clipped at 0
    h2: np.ndarray             # (n,) x5^2 + y5^2 - d4^2 before clipping (negative: inside)
    sin5: np.ndarray           # (2, 1, n) |sin(theta5)| = 2 |sin(theta5 / 2) cos(theta5 / 2)|
    X: np.ndarray              # (2, 1, 2, n) wrist-1 point in the arm plane
    Y: np.ndarray
    sin3: np.ndarray           # (2, 1, 2, n) |sin(theta3)|, the same on both elbow branches
    outer: np.ndarray          # (2, 1, 2, n) margin to the outer reach (negative: beyond)
    inner: np.ndarray          # (2, 1, 2, n) margin to the inner reach
    represented: np.ndarray    # (2, 2, n) over (s, w) rows standing for a wrist family, or None


@dataclass
class _Block:
    """The results of n poses, poses last: ``solutions`` (6, 8, n), ``valid``,
    ``position_error``, ``rotation_error`` (8, n), ``flags`` (n,) each, ``reason`` (n,).
    A block of a batch is a view of the whole batch's arrays (``out[part]``), which
    :func:`_solve_block` fills; :meth:`result` gives them to the caller poses first, as
    transposed views (the arrays are written where the steps compute them, row by row)."""

    solutions: np.ndarray
    valid: np.ndarray
    position_error: np.ndarray
    rotation_error: np.ndarray
    flags: dict
    reason: np.ndarray

    @classmethod
    def empty(cls, n):
        """The arrays of n poses, the numbers all in one allocation: one large block of
        memory, which the allocator keeps for the next call more readily than many (memory
        handed back to the system costs a page fault per 4 kB when it is used again)."""
        reason = np.empty(n, dtype=object)
        reason.fill("")
        floats = np.empty(64 * n + -(-12 * n // 8))    # 48 + 8 + 8 floats, 12 booleans
        solutions = floats[:48 * n].reshape(6, 8, n)
        pe = floats[48 * n:56 * n].reshape(8, n)
        re = floats[56 * n:64 * n].reshape(8, n)
        bools = floats[64 * n:].view(bool)
        valid = bools[:8 * n].reshape(8, n)
        flags = {name: bools[(8 + i) * n:(9 + i) * n] for i, name in enumerate(_FLAGS)}
        return cls(solutions, valid, pe, re, flags, reason)

    def __getitem__(self, part):
        return _Block(self.solutions[..., part], self.valid[:, part],
                      self.position_error[:, part], self.rotation_error[:, part],
                      {name: flag[part] for name, flag in self.flags.items()},
                      self.reason[part])

    def result(self, batch):
        """The :class:`IKResult` of poses of leading shape ``batch``, poses first."""
        return finish(self.solutions.T.reshape(batch + (8, 6)),
                      self.valid.T.reshape(batch + (8,)),
                      self.position_error.T.reshape(batch + (8,)),
                      self.rotation_error.T.reshape(batch + (8,)),
                      {name: f.reshape(batch) for name, f in self.flags.items()},
                      self.reason.reshape(batch))


def _flange(robot, targets, tool, tool_dq, d6):
    r"""The flange poses :math:`X_{06} = X_{W0}^{-1} X_{WT}^* X_{6T}^{-1}` of the targets
    (checked, of leading shape (n,)), read on components. They are written over rows of the
    components read, once used: nothing else of the size of the batch stays in memory."""
    moved = robot.base.tobytes() != _EYE_BYTES
    tooled = tool.tobytes() != _EYE_BYTES
    n = math.prod(targets.batch)
    if targets.kind == "transform" and not (moved or tooled):
        # Shepperd's quaternion of the rotation block; the position and z axis read off
        e = targets.take_transform_entries()                  # (16, n), ours to overwrite
        q, p, z6 = e[12:16], e[3:12:4], e[2:11:4]
        _write_rows(q, quaternion_from_matrix_entries(*e[0:3], *e[4:7], *e[8:11]))  # bottom row
    else:
        Q = targets.dual_quaternions
        if moved:
            Q = dual_quaternion_product(
                dual_quaternion_conjugate(dual_quaternion_from_transform(robot.base)), Q)
        if tooled:
            if tool_dq is None:
                tool_dq = dual_quaternion_from_transform(tool)
            Q = dual_quaternion_product(Q, dual_quaternion_inverse(tool_dq))
        c = component_rows(Q.reshape(n, 8))                   # (8, n), ours to overwrite
        q, p = c[:4], c[4:7]
        z6 = np.array(quaternion_rotate(*q, 0.0, 0.0, 1.0))
        _write_rows(p, translation_from_dual_quaternion_entries(*c))   # over the dual part
    p[...] = steps.wrist_center(p, z6, d6)
    return _Flange(q=q, p5=p)


def _write_rows(out, rows):
    """Write the arrays ``rows`` into the rows of ``out``."""
    for target, row in zip(out, rows, strict=True):
        target[...] = row


def _tool(robot, tool, pose_tol):
    """The tool to solve for (checked), its dual quaternion and the change from the
    robot's own tool for forward kinematics (or None)."""
    if tool is None:
        return robot.tool, None, None
    tool_dq = dual_quaternion_from_transform(tool, tol=pose_tol, name="tool")
    tool = np.asarray(tool, dtype=float)
    if tool.shape != (4, 4):
        raise ValueError(f"tool must have shape (4, 4), got {tool.shape}")
    robot_tool = robot.tool
    fix = None if np.array_equal(tool, robot_tool) else transform_inverse(robot_tool) @ tool
    return tool, tool_dq, fix


def _theta6_reference(q_ref, batch):
    """The theta6 of ``q_ref`` for every pose, shape (n,), or None."""
    if q_ref is None:
        return None
    q_ref = as_float_array(q_ref, "q_ref", (6,))
    try:
        return np.broadcast_to(q_ref[..., 5], batch).reshape(math.prod(batch))
    except ValueError:
        raise ValueError(f"q_ref of shape {q_ref.shape} does not broadcast against the "
                         f"poses' leading shape {batch}") from None


def _single_flange(robot, target, d6, pose_tol):
    """The rotation quaternion and the wrist centre of one flange pose as floats, checked
    as :func:`~dqlab.ik.targets.parse_targets` checks it; None when the pose is not a
    plain (4, 4) or (8,) one, the robot has a base or a tool, or the check fails (the batch
    path then raises its message)."""
    if target.shape == (4, 4):
        rows = rigid_rows(target, pose_tol)
        if rows is None:
            return None
        a, b, c = rows
        q = quaternion_from_matrix_entries(a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2])
        p, z6 = (a[3], b[3], c[3]), (a[2], b[2], c[2])
    elif target.shape == (8,):
        Q = target.tolist()
        try:
            unit_dual_quaternion_or_raise(Q, "target", pose_tol)
        except ValueError:
            return None
        q = tuple(Q[:4])
        p = translation_from_dual_quaternion_entries(*Q)
        z6 = quaternion_rotate(*q, 0.0, 0.0, 1.0)
    else:
        return None
    if not robot.bare:
        return None
    return q, (p[0] - d6 * z6[0], p[1] - d6 * z6[1], p[2] - d6 * z6[2])   # wrist_center


def _solve_single(robot, prm, target, tol, singular_tol, pose_tol, q_ref):
    """One pose on Python floats: the steps of a batch, one branch at a time.

    Returns the :class:`IKResult` of the pose, the same as the batch path's, or None when
    the pose needs what only the batch path does: a wrist near its singularity (the wrist
    family), a wrist centre inside the shoulder cylinder or no valid row (the reasons), a
    base or tool, or a target that fails its check (the error message).
    """
    flange = _single_flange(robot, target, prm["d6"], pose_tol)
    if flange is None:
        return None
    if q_ref is not None:
        _theta6_reference(q_ref, ())               # checked; it matters only at the wrist
    (qw, qx, qy, qz), p5 = flange
    x5, y5, _ = p5
    d1, a2, a3, d4, d5, r_out, r_in, offsets = prm["single"]
    r = _HALF_SQRT2
    qD = (r * (qw + qx), r * (qx - qw), r * (qy - qz), r * (qy + qz))
    solutions, errors = [0.0] * 48, [0.0] * 8     # (8, 6) row by row; rows not valid stay 0
    any_valid = wrist_singular = elbow_singular = False
    for s, shoulder in enumerate((1.0, -1.0)):
        theta1, c1, s1, h, h2 = steps.shoulder_angles(x5, y5, d4, shoulder)
        if h2 < 0.0:
            return None
        L = steps.relative_rotation_coefficients(qD, steps.half_angle_cos_sin(c1, s1))
        Px, Py = steps.arm_plane_wrist(p5, c1, s1, d1)
        theta5, half_sum, half_diff, c5bar, s5bar = steps.wrist_angles(L, 1.0)
        sin5 = 2.0 * s5bar * c5bar
        if sin5 < _NEAR_WRIST:
            return None
        s234, c234 = steps.theta234_sine_cosine(L, 1.0, c5bar, s5bar)
        for w in (0, 1):
            if w == 1:           # the wrist flip, sigma = -1: theta234 and theta6 turn by pi
                theta5, half_diff = steps.wrist_flip(theta5, half_diff)
                s234, c234 = -s234, -c234
            theta234 = half_sum + half_diff
            theta6 = wrapped_angle(half_sum - half_diff)
            X, Y = steps.wrist1_point(Px, Py, theta234, d5, (s234, c234))
            # the distance of _clipping_distance, sqrt(e1^2 + e2^2) with e1 = 0 (h2 >= 0)
            rho = math.sqrt(X * X + Y * Y)
            error = rho - r_out if rho > r_out else (r_in - rho if rho < r_in else 0.0)
            errors[4 * s + w] = errors[4 * s + 2 + w] = error
            if error > tol:                     # both rows stay zero, as finish() writes them
                continue
            triangle = steps.elbow_triangle(X, Y, a2, a3)
            for k, elbow in ((4 * s + w, 1.0), (4 * s + 2 + w, -1.0)):   # k = 4 s + 2 e + w
                theta2, theta3, _, _, sin3 = steps.elbow_angles(X, Y, a2, a3, elbow, triangle)
                row = [theta1, theta2, theta3, wrapped_angle(theta234 - theta2 - theta3),
                       theta5, theta6]
                if offsets is not None:
                    row = [wrapped_angle(t - o) for t, o in zip(row, offsets, strict=True)]
                solutions[6 * k:6 * k + 6] = row
            any_valid = True
            wrist_singular = wrist_singular or sin5 < singular_tol
            elbow_singular = elbow_singular or sin3 < singular_tol
    if not any_valid:
        return None
    numbers = np.fromiter(solutions + errors, float, 56)    # (8, 6) solutions, 8 errors
    errors = numbers[48:]
    flags = {"wrist_singular": np.array(wrist_singular),
             "shoulder_singular": np.array(h < singular_tol * d4),
             "elbow_singular": np.array(elbow_singular), "unreachable": np.array(False)}
    return IKResult(numbers[:48].reshape(8, 6), errors <= tol, errors, np.zeros(8), flags,
                    np.array("", dtype=object))


def ur(robot: Robot, target: ArrayLike, *, tol: float = 1e-9, tool: ArrayLike | None = None,
       q_ref: ArrayLike | None = None, singular_tol: float = 5e-7, pose_tol: float = 1e-9,
       residuals: str = "equations") -> IKResult:
    r"""Every closed-form inverse-kinematics solution of a UR-family arm.

    Solves :math:`X_{W0}\, X_{06}(q)\, X_{6T} = X` for the joint vector :math:`q` by the
    dual-quaternion route of the thesis (section 4.3), corrected (see the module's
    "Errata of the source"). A batch of poses is solved with array operations, without a
    Python loop over the poses (a big batch goes through in blocks of 2048 poses, which keeps
    the temporaries small and fast). One pose is solved on Python floats, by the same steps.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm in standard DH (for example :func:`dqlab.models.ur3`); its base
        transform and tool are taken into account, and joint offsets are honoured. A
        calibrated UR (parameters millimetres off the exact shape) is solved by
        :func:`dqlab.ik.ur_calibrated.calibrated_ur`, with the same result.
    target : array_like, shape (..., 4, 4) or (..., 8)
        Target pose(s) of the TCP in the world frame, as rigid transforms or unit dual
        quaternions ``(q_r, q_d)`` (told apart by the trailing shape; see
        :func:`dqlab.ik.targets.parse_targets`).
    tool : array_like, shape (4, 4), optional
        Flange-to-TCP transform :math:`X_{6T}` to use instead of ``robot.tool``.
    q_ref : array_like, shape (6,) or (..., 6), optional
        Reference configuration. At a wrist singularity, where only
        :math:`\theta_{234} \pm \theta_6` is determined, :math:`\theta_6` is taken from
        it (default 0), moved as little as needed for the arm to reach.
    tol : float
        A row is valid when it reproduces the pose to ``tol`` metres and ``tol`` radians.
    singular_tol : float
        A pose is flagged singular when a valid row has :math:`|\sin\theta_5|` (wrist) or
        :math:`|\sin\theta_3|` (elbow) below it, or when :math:`h / d_4 =
        \sqrt{x_5^2 + y_5^2 - d_4^2} / d_4` (shoulder) is. At an exactly singular elbow
        or shoulder these come out near :math:`\sqrt{\varepsilon} \approx 10^{-8}` (up
        to about :math:`10^{-7}`), the conditioning of those angles; the default leaves a
        margin above that. :math:`\theta_5` itself is computed to full accuracy.
    pose_tol : float
        Tolerance of the rigidity check of ``target`` (and ``tool``). With a tolerance above
        the default (for poses read from rounded numbers, as in the thesis's pose file),
        each pose is replaced by the rigid pose of its normalised dual quaternion, which is
        what the solutions and the residuals then refer to.
    residuals : {"equations", "fk"}
        How ``position_error`` and ``rotation_error`` are obtained (the ``valid`` mask is
        the same either way). ``"equations"`` (default, fast): every step solves its
        equation exactly unless it has to clip -- the wrist centre inside the shoulder
        cylinder (by :math:`e_1 = d_4 - \sqrt{x_5^2 + y_5^2}`, normal to the arm plane)
        or the wrist-1 point out of the forearm's reach (by :math:`e_2`, the distance to
        the reach circle, in the arm plane) -- and the rotation is always reproduced, so
        the forward-kinematics distance of a row is :math:`\sqrt{e_1^2 + e_2^2}` in
        position and 0 in rotation, up to rounding (below 1e-14, reported as 0). Rows that
        represent a wrist-singular family are checked by forward kinematics.
        ``"fk"``: :meth:`dqlab.robot.Robot.fk` of every row against the target, as the
        thesis filters its candidates (several times slower on batches).

    Returns
    -------
    IKResult
        ``solutions`` (..., 8, 6) in radians, wrapped to :math:`(-\pi, \pi]`, row
        ``4 s + 2 e + w`` for shoulder ``s``, elbow ``e``, wrist ``w`` (see
        :data:`SOLUTION_ORDER`; invalid rows hold zeros); ``valid`` (..., 8);
        ``position_error`` and ``rotation_error`` (..., 8) of every row (before zeroing);
        ``flags`` with boolean arrays (...) ``"wrist_singular"``, ``"shoulder_singular"``,
        ``"elbow_singular"`` (set when a valid solution is near that singularity) and
        ``"unreachable"`` (no valid solution); ``reason`` (...) says why a pose has no
        solution. Branches that coincide at a singularity are all returned (equal rows);
        :func:`distinct_solutions` marks the first of each group. For a batch, the arrays
        are stored with the poses last in memory (as the solver computes them) and given as
        transposed views, shape as above (``np.ascontiguousarray`` gives a C-ordered copy).

    Raises
    ------
    ValueError
        If the robot is not UR-shaped (:data:`dqlab.models.UR_SHAPE`), or ``target`` has
        the wrong shape, holds NaN, is not a rigid transform or not a unit dual quaternion.
        Unreachable poses do not raise.

    Notes
    -----
    Steps, with :math:`X_{06} = (q, p)` the flange pose in the base frame and
    :math:`q_D = q\, q_0^*` its rotation relative to the zero pose
    (:math:`q_0 = \cos\frac{\pi}{4} + \sin\frac{\pi}{4}\, i`, the flange at :math:`q = 0`):

    .. math::

        p_5 &= p - d_6 z_6, \qquad
        \theta_1 = \operatorname{atan2}(y_5 h_\pm + x_5 d_4,\ x_5 h_\pm - y_5 d_4),\\
        L &= r_z(\theta_1)^* q_D, \qquad
        \theta_5 = 2 \operatorname{atan2}\big(\sigma\sqrt{L_x^2 + L_z^2},
                                             \sqrt{L_w^2 + L_y^2}\big),\\
        \theta_{234} &= \operatorname{atan2}(-L_y, L_w) + \operatorname{atan2}(\sigma L_x,
                        -\sigma L_z), \quad
        \theta_6 = \operatorname{atan2}(-L_y, L_w) - \operatorname{atan2}(\sigma L_x,
                        -\sigma L_z),\\
        (X, Y) &= (c_1 x_5 + s_1 y_5 - d_5 s_{234},\ z_5 - d_1 + d_5 c_{234}),\\
        \theta_3 &= \operatorname{atan2}\big(\pm\sqrt{((a_2 + a_3)^2 - \rho^2)
                     (\rho^2 - (a_2 - a_3)^2)},\ \rho^2 - a_2^2 - a_3^2\big), \quad
        \theta_2 = \operatorname{atan2}(Y k_1 - X k_2, X k_1 + Y k_2),\\
        \theta_4 &= \theta_{234} - \theta_2 - \theta_3 ,

    with :math:`\rho^2 = X^2 + Y^2`, :math:`k_1 = a_2 + a_3 c_3`, :math:`k_2 = a_3 s_3`.

    Singularities: at the shoulder singularity (:math:`h = 0`) and the elbow singularity
    (:math:`\sin\theta_3 = 0`) two branches coincide and both are returned. At the wrist
    singularity the family :math:`\theta_6 \in \mathbb R` is represented by the member
    nearest ``q_ref``'s :math:`\theta_6` that the arm can reach; this is done when the
    whole family reproduces the pose within ``tol`` (:math:`|\sin\frac{\theta_5}{2}|` or
    :math:`|\cos\frac{\theta_5}{2}|` below :math:`tol / (8\max(1, d_6))`); slightly further
    from the singularity the unique, ill-conditioned solution is returned instead. Both are
    flagged when :math:`|\sin\theta_5| <` ``singular_tol``.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> from dqlab.ik import ur
    >>> robot = ur3()
    >>> q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> result = ur(robot, robot.fk(q))
    >>> result.solutions.shape, int(result.count)
    ((8, 6), 8)
    >>> bool(np.any(np.all(np.abs(result.solutions - q) < 1e-12, axis=-1)))
    True
    >>> bool(result.position_error[result.valid].max() < 1e-12)
    True

    A batch: a regular pose and the thesis's test pose (every singularity at once):

    >>> poses = robot.fk(np.array([q, [0, -np.pi / 2, 0, -np.pi / 2, 0, 0]]))
    >>> result = ur(robot, poses)
    >>> result.count
    array([8, 8])
    >>> for name, flag in result.flags.items():
    ...     print(name, flag)
    wrist_singular [False  True]
    shoulder_singular [False  True]
    elbow_singular [False  True]
    unreachable [False False]
    """
    tol = check_tolerance(tol, "tol")
    singular_tol = check_tolerance(singular_tol, "singular_tol")
    pose_tol = check_tolerance(pose_tol, "pose_tol")
    if residuals not in ("fk", "equations"):
        raise ValueError(f"residuals must be 'fk' or 'equations', got {residuals!r}")
    try:
        prm = _parameters(robot)
    except ValueError as exc:                   # not the exact UR shape: a calibrated UR?
        try:
            nominal_ur(robot)
        except ValueError as why:
            raise ValueError(f"{exc}; nor is it a calibrated UR: {why}") from None
        return calibrated_ur(robot, target, ur, tol=tol, tool=tool, q_ref=q_ref,
                             singular_tol=singular_tol, pose_tol=pose_tol, residuals=residuals)
    if (tool is None and residuals == "equations" and type(target) is np.ndarray
            and target.dtype is _FLOAT64 and pose_tol <= RIGID_TOL):
        result = _solve_single(robot, prm, target, tol, singular_tol, pose_tol, q_ref)
        if result is not None:
            return result
    targets = parse_targets(target, tol=pose_tol)
    tool, tool_dq, tool_fix = _tool(robot, tool, pose_tol)
    batch = targets.batch
    n = math.prod(batch)
    theta6_ref = _theta6_reference(q_ref, batch)
    targets = targets.reshape((n,))
    flange = _flange(robot, targets, tool, tool_dq, prm["d6"])
    options = _Options(tol, singular_tol, residuals, tool_fix)
    # The batch axis goes last, (branch axes..., n), so that every operation runs over long
    # contiguous rows; big batches are cut into blocks whose temporaries stay small, each
    # written into its part of the batch's arrays.
    out = _Block.empty(n)
    for start in range(0, n, _CHUNK):
        part = slice(start, start + _CHUNK)
        if n <= _CHUNK:                                   # one block: no slicing
            _solve_block(robot, prm, flange, targets, theta6_ref, options, out)
        else:
            _solve_block(robot, prm, flange[part], targets[part],
                         None if theta6_ref is None else theta6_ref[part], options, out[part])
    return out.result(batch)


def _solve_block(robot, prm, flange, targets, theta6_ref, options, out):
    """Every branch of a block of n poses (batch axis last), checked and flagged, written
    into ``out`` (a :class:`_Block` of n poses)."""
    branches = _branches(prm, flange, theta6_ref, options.tol, out.solutions)
    pe, re = _errors(robot, prm, flange, branches, targets, options, out)   # (8, n) each
    ok = np.less_equal(pe, options.tol, out=out.valid)
    if options.residuals == "fk" or branches.represented is not None:   # else re is 0
        ok &= re <= options.tol
    any_valid = ok.any(axis=0)                                              # (n,)
    _flags(prm, branches, ok, any_valid, options.singular_tol, out.flags)
    if not any_valid.all():
        out.reason[...] = _reasons(prm, flange, branches, any_valid, options.tol)


def _branches(prm, flange, theta6_ref, tol, out):
    """Steps 1 to 4 for every branch: the candidate joint vectors of a block of poses,
    written into ``out`` (6, 8, n)."""
    d1, d4 = prm["d1"], prm["d4"]
    x5, y5, z5 = flange.p5

    # Step 1, theta1: arrays (2, n) over the shoulder branch s
    theta1, c1, s1, h, h2 = steps.shoulder_angles(x5, y5, d4)

    # Step 2, rotation: q_D = q q0^* with q0 = (1 + i)/sqrt(2), then L = r_z(theta1)^* q_D
    qw, qx, qy, qz = flange.q
    qD = (_HALF_SQRT2 * (qw + qx), _HALF_SQRT2 * (qx - qw),
          _HALF_SQRT2 * (qy - qz), _HALF_SQRT2 * (qy + qz))
    L = steps.relative_rotation_coefficients(qD, steps.half_angle_cos_sin(c1, s1))
    # arrays (2, 2, n) over (s, w): the wrist branch sigma = +1, and its wrist flip
    theta5, half_sum, half_diff, c5bar, s5bar = steps.wrist_angles(L, 1.0)
    theta5, half_diff = (_over_wrists(*pair) for pair in zip(
        (theta5, half_diff), steps.wrist_flip(theta5, half_diff), strict=True))
    L, half_sum, c5bar, s5bar = (tuple(c[:, None] for c in L), half_sum[:, None],
                                 c5bar[:, None], s5bar[:, None])
    Px, Py = steps.arm_plane_wrist((x5, y5, z5), c1, s1, d1)
    Px = Px[:, None, :]                                       # (2, 1, n)
    family = (prm, half_sum, half_diff, s5bar, c5bar, Px, Py, theta6_ref, tol)
    theta234, theta6, represented = _wrist_family(*family)
    if represented is None:          # no wrist family: c5bar s5bar > 0 everywhere
        sine_cosine = steps.theta234_sine_cosine(L, _SIGMA, c5bar, s5bar)    # (2, 2, n)
    else:                            # a member of a wrist family: its own sine and cosine
        with np.errstate(divide="ignore", invalid="ignore"):  # 0/0 only in the family
            sine_cosine = steps.theta234_sine_cosine(L, _SIGMA, c5bar, s5bar)
        for part, f in zip(sine_cosine, (np.sin, np.cos), strict=True):
            part[represented] = f(theta234[represented])

    # Steps 3 and 4, the planar chain: arrays (2, 2, 2, n) over (s, e, w)
    X, Y, theta2, theta3, outer, inner, sin3 = _planar_chain(prm, Px, Py, theta234,
                                                             sine_cosine)
    # Near the wrist singularity theta234 comes from coefficients of the size of theta5 and
    # may be off by eps / |theta5|: enough to put the wrist-1 point of a stretched or folded
    # elbow out of reach. Such rows move within their wrist family to where the forearm
    # reaches (and are checked by forward kinematics).
    sin5 = 2.0 * s5bar * c5bar                                # (2, 1, n), |sin theta5|
    near = sin5 < _NEAR_WRIST
    repair = _out_of_reach(prm, outer, inner, tol) & near if near.any() else None
    if repair is not None and repair.any():
        theta234, theta6, represented = _wrist_family(*family, repair=repair)
        cols = np.flatnonzero(repair.any(axis=(0, 1)))        # the poses concerned
        chain = (X, Y, theta2, theta3, outer, inner, sin3)
        for whole, part in zip(chain, _planar_chain(prm, Px[..., cols], Py[..., cols],
                                                    theta234[..., cols]), strict=True):
            whole[..., cols] = part
    # theta4 = theta234 - theta2 - theta3, in (-4 pi, 4 pi) before wrapping
    theta4 = wrapped_angle(theta234[:, None] - theta2 - theta3)
    _joint_vectors((theta1[:, None, None, :], theta2, theta3, theta4, theta5[:, None],
                    wrapped_angle(theta6)[:, None]), prm["offsets"], out)
    return _Branches(solutions=out, h=h, h2=h2, sin5=sin5, X=X, Y=Y,
                     sin3=sin3, outer=outer, inner=inner, represented=represented)


def _over_wrists(unflipped, flipped):
    """One array (2, 2, n) over (s, w) from the two wrist branches' arrays (2, n)."""
    both = np.empty((2, 2, unflipped.shape[-1]))
    both[:, 0] = unflipped
    both[:, 1] = flipped
    return both


def _wrist_family(prm, half_sum, half_diff, s5bar, c5bar, Px, Py, theta6_ref, tol, repair=None):
    """theta234 and theta6 (2, 2, n) from the half sum and difference; at a wrist
    singularity, where only theta234 -+ theta6 is fixed, the member of the family whose
    theta6 is nearest ``theta6_ref`` among those the arm can reach; for the rows in
    ``repair`` (near the singularity), the member nearest the computed theta234 that the arm
    can reach (``repair``, when given, marks some rows). Also returns the mask of the rows
    so chosen (None when there is none)."""
    theta234 = half_sum + half_diff
    theta6 = half_sum - half_diff
    rep_tol = tol / (8.0 * max(1.0, abs(prm["d6"])))
    if repair is None and min(s5bar.min(), c5bar.min()) > rep_tol:
        return theta234, theta6, None                         # no family (the common case)
    exact = (s5bar <= rep_tol) | (c5bar <= rep_tol)           # (2, 1, n)
    rep = np.broadcast_to(exact, theta234.shape) if repair is None else exact | repair
    # the few poses concerned, cols, as arrays (2, 2, m)
    cols = np.flatnonzero(rep.any(axis=(0, 1)))
    rep_c = rep[..., cols]
    shape = rep_c.shape
    exact = np.broadcast_to(exact[..., cols], shape)
    # rep0: theta5 near 0, where theta234 + theta6 is fixed (near pi, theta234 - theta6)
    rep0 = np.broadcast_to(s5bar[..., cols] <= c5bar[..., cols], shape)
    ref = prm["offsets"][5] + (0.0 if theta6_ref is None else theta6_ref[cols])
    full_sum = np.broadcast_to(2.0 * half_sum[..., cols], shape)
    full_diff = 2.0 * half_diff[..., cols]
    want = np.where(exact, np.where(rep0, full_sum - ref, full_diff + ref),
                    theta234[..., cols])[rep_c]
    got = steps.feasible_theta234(np.broadcast_to(Px[..., cols], shape)[rep_c],
                                  np.broadcast_to(Py[..., cols], shape)[rep_c], want,
                                  prm["a2"], prm["a3"], prm["d5"])
    theta6_got = np.where(rep0[rep_c], full_sum[rep_c] - got, got - full_diff[rep_c])
    for whole, member in ((theta234, got), (theta6, theta6_got)):
        part = whole[..., cols]
        part[rep_c] = steps.wrap_angle(member)
        whole[..., cols] = part
    return theta234, theta6, rep


def _out_of_reach(prm, outer, inner, tol):
    """Rows (2, 2, n) over (s, w) whose wrist-1 point lies more than tol / 2 beyond the
    forearm's reach on some elbow branch."""
    r_out, r_in = abs(prm["a2"] + prm["a3"]), abs(prm["a2"] - prm["a3"])
    far = (outer < -tol * r_out) | (inner < -tol * r_in)     # (2, 1 or 2, 2, n)
    return far.any(axis=1)


def _planar_chain(prm, Px, Py, theta234, sine_cosine=None):
    """Steps 3 and 4: the wrist-1 point (2, 1, 2, n) and the elbow angles (2, 2, 2, n)."""
    X, Y = steps.wrist1_point(Px, Py, theta234, prm["d5"], sine_cosine)   # (2, 2, n), (s, w)
    X, Y = X[:, None], Y[:, None]                             # (2, 1, 2, n)
    theta2, theta3, outer, inner, sin3 = steps.elbow_angles(X, Y, prm["a2"], prm["a3"], _ELBOW)
    return X, Y, theta2, theta3, outer, inner, sin3


def _joint_vectors(thetas, offsets, out):
    """Write the joint vectors (6, 8, n) -- joint j of row k = 4 s + 2 e + w of pose i at
    ``[j, k, i]`` -- from the six angle arrays over (s, e, w, n) into ``out``, joint offsets
    removed."""
    view = out.reshape(6, 2, 2, 2, out.shape[-1])   # splits the row axis: a view of ``out``
    for j, theta in enumerate(thetas):
        view[j] = theta
    if any(offsets):
        out[...] = steps.wrap_angle(out - np.array(offsets)[:, None, None])


def _errors(robot, prm, flange, branches, targets, options, out):
    """Position and rotation errors (8, n) of every row, written into ``out`` (a
    :class:`_Block`): from the clipping of the steps (``residuals="equations"``) or by
    forward kinematics (``"fk"``)."""
    pe, re = out.position_error, out.rotation_error
    if options.residuals == "fk":
        pe.T[...], re.T[...] = _fk_errors(robot, branches.solutions.T,
                                          targets.transforms[:, None], options.tool_fix)
        return pe, re
    re[...] = 0.0
    _clipping_distance(prm, flange, branches, pe)
    if branches.represented is not None:
        n = branches.solutions.shape[2]
        rows = np.broadcast_to(branches.represented[:, None], (2, 2, 2, n)).reshape(8, n)
        k, i = np.nonzero(rows)                               # row k of pose i
        pe[k, i], re[k, i] = _fk_errors(robot, branches.solutions[:, k, i].T,
                                        targets[i].transforms, options.tool_fix)
    return pe, re


def _clipping_distance(prm, flange, branches, out):
    """Distance (8, n) a row misses the pose by, from the clipping of steps 1 and 4: the
    wrist centre inside the shoulder cylinder (normal to the arm plane) and the wrist-1 point
    out of the forearm's reach (in it); written into ``out``."""
    n = flange.q.shape[1]
    inside = branches.h2.min() < 0.0   # some wrist centre inside the shoulder cylinder
    if not inside and branches.outer.min() >= 0.0 and branches.inner.min() >= 0.0:
        out[...] = 0.0                                        # nothing was clipped
        return
    a2, a3 = prm["a2"], prm["a3"]
    r_out, r_in = abs(a2 + a3), abs(a2 - a3)
    X, Y = branches.X, branches.Y
    rho = np.sqrt(X * X + Y * Y)
    e = np.maximum(np.maximum(rho - r_out, r_in - rho), 0.0)                  # (2, 1, 2, n)
    if inside:
        e1 = _shoulder_gap(prm, flange, branches)             # (n,)
        e = np.sqrt(e1 * e1 + e * e)
    out.reshape(2, 2, 2, n)[...] = e                          # splits the rows: a view


def _shoulder_gap(prm, flange, branches):
    """How far (n,) the wrist centre lies inside the shoulder cylinder (0 outside)."""
    x5, y5 = flange.p5[0], flange.p5[1]
    return np.maximum(-branches.h2, 0.0) / (prm["d4"] + np.sqrt(x5 * x5 + y5 * y5))


def _fk_errors(robot, solutions, X_target, tool_fix):
    """pose_errors of robot.fk of joint vectors (..., 6) against X_target (..., 4, 4),
    with the tool changed by ``tool_fix`` when not None."""
    X = robot.fk(solutions)
    if tool_fix is not None:
        X = X @ tool_fix
    return pose_errors(X, X_target)


def _flags(prm, branches, ok, any_valid, singular_tol, out):
    """The singularity and reach flags (n,) of a block, over its valid rows, written into
    ``out`` (the block's flags)."""
    n = ok.shape[1]
    ok4 = ok.reshape(2, 2, 2, n)
    shoulder = np.less(branches.h, singular_tol * prm["d4"], out=out["shoulder_singular"])
    shoulder &= any_valid
    np.logical_not(any_valid, out=out["unreachable"])
    # |sin theta5| (2, 1, 1, n) over (s, w) and |sin theta3| (2, 1, 2, n) over (s, w)
    for name, sine in (("wrist_singular", branches.sin5[:, None]),
                       ("elbow_singular", branches.sin3)):
        if sine.min() < singular_tol:
            (ok4 & (sine < singular_tol)).reshape(8, n).any(axis=0, out=out[name])
        else:
            out[name][...] = False


def _reasons(prm, flange, branches, any_valid, tol):
    """Why each pose of a block without a valid row has none (n,): the first step that
    fails on every branch."""
    reason = np.full(any_valid.shape, "", dtype=object)
    if any_valid.all():
        return reason
    none = ~any_valid
    outer, inner = branches.outer < 0, branches.inner < 0
    reason[none] = REASON_TOL
    reason[none & (outer | inner).all(axis=(0, 1, 2))] = REASON_REACH
    reason[none & inner.all(axis=(0, 1, 2))] = REASON_INNER
    reason[none & outer.all(axis=(0, 1, 2))] = REASON_OUTER
    reason[none & (_shoulder_gap(prm, flange, branches) > tol)] = REASON_SHOULDER
    return reason


def distinct_solutions(result: IKResult, atol: float = 1e-9) -> NDArray[np.bool_]:
    r"""Mark the first valid row of each group of equal solutions (angles compared mod 2 pi).

    Parameters
    ----------
    result : IKResult
        As returned by :func:`ur`.
    atol : float
        Two rows are equal when every joint differs by at most ``atol`` (mod :math:`2\pi`).

    Returns
    -------
    ndarray of bool, shape (..., k)
        True for valid rows that do not repeat an earlier valid row.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> from dqlab.ik import ur
    >>> robot = ur3()
    >>> result = ur(robot, robot.fk([0, -np.pi / 2, 0, -np.pi / 2, 0, 0]))
    >>> int(result.count), int(distinct_solutions(result, atol=1e-7).sum())
    (8, 1)

    (``atol=1e-7``: at that pose the elbow is straight, and a rounding of the pose moves
    :math:`\theta_3` by up to :math:`\sqrt{\varepsilon}`.)
    """
    sol = result.solutions
    valid = result.valid
    diff = np.abs(steps.wrap_angle(sol[..., :, None, :] - sol[..., None, :, :]))
    same = np.all(diff <= atol, axis=-1) & valid[..., :, None] & valid[..., None, :]
    k = sol.shape[-2]
    earlier = np.tril(np.ones((k, k), dtype=bool), -1)
    return valid & ~np.any(same & earlier, axis=-1)


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
    limits = as_float_array(limits, "limits")
    if limits.shape not in ((2,), (n, 2)):
        raise ValueError(f"limits must have shape (2,) or ({n}, 2), got {limits.shape}")
    lo = np.broadcast_to(limits[..., 0], (n,))
    hi = np.broadcast_to(limits[..., 1], (n,))
    if np.any(hi - lo > 4 * np.pi + 1e-12):
        raise ValueError("equivalent_solutions handles joint ranges of at most 4 pi")
    bits = (np.arange(2 ** n)[:, None] >> np.arange(n)) & 1          # (2**n, n)
    shift = np.where(q >= 0, -2 * np.pi, 2 * np.pi)[..., None, :]
    cands = q[..., None, :] + bits * shift
    within = np.all((cands >= lo) & (cands <= hi), axis=-1)
    return cands, within


def closest_solution(result: IKResult, q_ref: ArrayLike,
                     limits: ArrayLike = (-2 * np.pi, 2 * np.pi)) -> NDArray[np.float64]:
    r"""The valid solution nearest ``q_ref``, unwrapped to the equivalent nearest ``q_ref``.

    The branch is chosen exactly as :meth:`~dqlab.ik.result.IKResult.best` does (joint-wise
    distance modulo :math:`2\pi`); then each joint is replaced by its :math:`2\pi`-equivalent
    within the limits that is nearest ``q_ref`` (what a robot at ``q_ref`` should be sent, so
    that no joint turns by more than half a turn when avoidable).

    Parameters
    ----------
    result : IKResult
    q_ref : array_like, shape (..., 6)
    limits : array_like, shape (2,) or (6, 2)

    Returns
    -------
    ndarray, shape (..., 6)

    Raises
    ------
    ValueError
        If some target has no valid solution (as :meth:`~dqlab.ik.result.IKResult.best`).

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> from dqlab.ik import ur
    >>> robot = ur3()
    >>> q = np.array([3.0, -1.0, 1.0, -2.0, 1.0, 6.0])      # joint 6 beyond pi
    >>> closest_solution(ur(robot, robot.fk(q)), q).round(6)
    array([ 3., -1.,  1., -2.,  1.,  6.])
    """
    best = result.best(q_ref)
    q_ref = as_float_array(q_ref, "q_ref")
    cands, within = equivalent_solutions(best, limits)
    dist = np.abs(cands - q_ref[..., None, :]).sum(axis=-1)
    dist = np.where(within, dist, np.inf)
    index = np.argmin(dist, axis=-1)
    return np.take_along_axis(cands, index[..., None, None], axis=-2)[..., 0, :]
