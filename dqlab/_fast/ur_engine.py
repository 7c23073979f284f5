r"""The speed machinery of :func:`dqlab.ik.ur`: the steps of :mod:`dqlab.ik.ur_steps`, run
fast, with the checks, flags and reasons of the result.

What it does. :func:`solve` solves one pose on Python floats (:func:`solve_single`, one
branch at a time, where numpy's per-call overhead would dominate) and a batch on arrays
(:func:`solve_batch`): the batch axis goes last, ``(branch axes..., n)``, so that every
operation runs over long contiguous rows; all eight branches are computed at once on arrays
of shape ``(2, 2, 2, n)`` over (shoulder, elbow, wrist), with the branch axes first; big
batches are cut into blocks of :data:`CHUNK` poses whose temporaries stay in the cache; the
results of a batch live in one allocation (:class:`Block`: the floats, then the booleans),
written in place by the steps and handed to the caller as poses-first views; one pose
takes its flipped wrist (:math:`\sigma = -1`) from the :math:`\sigma = +1` values by exact
sign identities, computing only the half difference anew; the residuals come from the
steps' clipping instead of forward kinematics. It also handles what the readable path
leaves out: a base, a tool, joint offsets, the choice of a member of the family at a wrist
singularity, the validity of each row, the singularity flags and the reason of a pose
without solution.

Tested equal to the readable path. Every row it marks valid away from a wrist singularity
is, bit for bit, the row of :func:`dqlab.ik.ur_steps.candidate_solutions` (on floats for
one pose, on arrays for a batch): ``tests/test_ik_ur.py::test_engine_equals_the_readable_path``.
A pose given as a list takes the same path as the same pose as an array (bitwise the same
result); one pose solved alone and within a batch agree to the last bit wherever ``math``
and numpy evaluate ``atan2`` alike, and to a tested bound elsewhere.
"""

import math
from dataclasses import dataclass

import numpy as np

from .._checks import (
    as_float_array,
    component_rows,
    real_array,
    rigid_rows,
    unit_dual_quaternion_or_raise,
)
from .._formulas import (
    dual_quaternion_mul,
    quaternion_from_matrix_entries,
    quaternion_mul,
    quaternion_rotate,
    translation_from_dual_quaternion_entries,
)
from ..dualquat import (
    dual_quaternion_conjugate,
    dual_quaternion_from_transform,
    dual_quaternion_inverse,
    dual_quaternion_product,
)
from ..ik import ur_steps as steps
from ..ik.result import IKResult, finish
from ..ik.targets import RIGID_TOL, parse_targets, pose_errors
from ..ik.ur_steps import (
    NEAR_SINGULAR,
    REASON_FAR,
    REASON_INNER,
    REASON_OUTER,
    REASON_REACH,
    REASON_SHOULDER,
    REASON_TOL,
)
from ..rotations import wrap_angle
from ..transforms import transform_inverse

__all__ = ["solve", "solve_single", "arm_constants", "solve_batch", "Block", "CHUNK",
           "REASON_SHOULDER", "REASON_OUTER", "REASON_INNER", "REASON_REACH", "REASON_TOL",
           "REASON_FAR"]

CHUNK = 2048                     # poses per block: temporaries of 128 kB at most (L2-sized)
_FLOAT64 = np.dtype(np.float64)
_EPSILON = float(np.finfo(np.float64).eps)
_TWO_PI = 2.0 * math.pi
_ONE_TURN = 1.0 / _TWO_PI
#: The flags of a result, in order: the calibrated solver's too, whose last one, a branch
#: that did not converge, an exact arm's closed form never sets.
_FLAGS = ("wrist_singular", "shoulder_singular", "elbow_singular", "near_singular",
          "unreachable", "not_converged")
_EYE_BYTES = np.eye(4).tobytes()
_EIGHT_TRUE = np.ones(8, dtype=bool)      # (copied: np.ones runs Python code)
_DQ_IDENTITY = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
_SHOULDER = np.array([[1.0], [-1.0]])     # h+- = +h, -h: axis 0 of (s, n)
_SIGMA = np.array([[1.0], [-1.0]])        # wrist branch w = 0, 1, axis -2 of (s, w, n)
_ELBOW = np.array([[[1.0]], [[-1.0]]])    # elbow branch e = 0, 1, axis -3 of (s, e, w, n)

def solve(robot, prm, target, tol, singular_tol, pose_tol, tool, q_ref, residuals,
          near_tol=NEAR_SINGULAR):
    """:func:`dqlab.ik.ur` after its checks of ``tol``, ``singular_tol``, ``pose_tol``,
    ``residuals`` and ``near_tol``, with ``prm`` the robot's
    :func:`~dqlab.ik.ur_parameters`: one pose on floats when it can, else the batch path."""
    if type(target) is not np.ndarray or target.dtype is not _FLOAT64:
        target = real_array(target, "target")   # a list takes the same path as an array
    if residuals == "equations" and pose_tol <= RIGID_TOL:
        result = solve_single(robot, prm, target, tol, singular_tol, pose_tol, q_ref, tool,
                              near_tol)
        if result is not None:
            return result
    return solve_batch(robot, prm, target, tol, singular_tol, pose_tol, tool, q_ref, residuals,
                       near_tol)


# --------------------------------------------------------------------------------------
# One pose on Python floats


def _single_flange(robot, target, pose_tol, tool):
    """The rotation quaternion, position and z axis of one flange pose
    :math:`X_{06} = X_{W0}^{-1} X_{WT}^* X_{6T}^{-1}` as floats, the target checked as
    :func:`~dqlab.ik.targets.parse_targets` checks it; None when the pose is not a plain
    (4, 4) or (8,) one, or a check fails (the batch path then raises its message)."""
    if target.shape == (4, 4):
        rows = rigid_rows(target, pose_tol)
        if rows is None:
            return None
        a, b, c = rows
        q = quaternion_from_matrix_entries(a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2])
        if robot.bare and tool is None:
            return q, (a[3], b[3], c[3]), (a[2], b[2], c[2])
        Q = q + quaternion_mul(0.0, 0.5 * a[3], 0.5 * b[3], 0.5 * c[3], *q)
    elif target.shape == (8,):
        Q = tuple(target.tolist())
        try:
            unit_dual_quaternion_or_raise(Q, "target", pose_tol)
        except ValueError:
            return None
    else:
        return None
    if not robot.bare or tool is not None:
        base, tool = _single_base_tool(robot, tool, pose_tol)
        if base is not None:                # X_{W0}^{-1} X_{WT}: the base's conjugate first
            Q = dual_quaternion_mul(base, Q)
        if tool is not None:                # X_{WT} X_{6T}^{-1}: the tool's conjugate last
            Q = dual_quaternion_mul(Q, tool)
    q = Q[:4]
    return q, translation_from_dual_quaternion_entries(*Q), quaternion_rotate(*q, 0.0, 0.0, 1.0)


def _single_base_tool(robot, tool, pose_tol):
    """The conjugates (inverses) of the base's and the tool's dual quaternions as tuples of
    floats, None for an identity; the tool argument, when given, in place of the robot's
    (checked as :func:`_tool` checks it)."""
    base = robot.base_dq.tolist()
    base = None if base == _DQ_IDENTITY else _conjugate(base)
    if tool is None:
        tool_dq = robot.tool_dq.tolist()
        return base, None if tool_dq == _DQ_IDENTITY else _conjugate(tool_dq)
    tool_dq = dual_quaternion_from_transform(tool, tol=pose_tol, name="tool")
    if np.shape(tool) != (4, 4):
        raise ValueError(f"tool must have shape (4, 4), got {np.shape(tool)}")
    return base, _conjugate(tool_dq.tolist())


def _conjugate(Q):
    """:math:`Q^* = q_r^* + \\varepsilon q_d^*` on eight floats, the inverse of a unit dual
    quaternion."""
    rw, rx, ry, rz, dw, dx, dy, dz = Q
    return rw, -rx, -ry, -rz, dw, -dx, -dy, -dz


def arm_constants(prm):
    """What :func:`solve_single` reads of an arm, from its parameters ``prm``
    (:func:`~dqlab.ik.ur_closed_form.ur_parameters`), as the steps compute them: ``d1, a2,
    a3, d4, d5, d6``, the joint offsets (None when all are 0), the distance of a wrist
    centre from the shoulder beyond which it is far (:func:`~dqlab.ik.ur_steps.far_wrist`),
    ``|a2 + a3|``, ``|a2 - a3|``, ``a2^2 + a3^2`` and ``a2 a3 < 0``
    (:func:`~dqlab.ik.ur_steps.elbow_triangle`), ``m = 2 |a2 a3|`` and ``a3 / m``
    (:func:`~dqlab.ik.ur_steps.elbow_angles`). The solver of an exact arm computes them once
    per robot and hands them over in ``prm["one pose"]``."""
    d1, a2, a3, d4, d5, d6 = prm["d1"], prm["a2"], prm["a3"], prm["d4"], prm["d5"], prm["d6"]
    offsets = prm["offsets"] if any(prm["offsets"]) else None
    far = math.sqrt(d4 * d4 + (abs(a2) + abs(a3) + abs(d5)) ** 2) / _EPSILON
    m = 2.0 * abs(a2 * a3)
    return (d1, a2, a3, d4, d5, d6, offsets, far, abs(a2 + a3), abs(a2 - a3),
            a2 * a2 + a3 * a3, a2 * a3 < 0, m, a3 / m)


def solve_single(robot, prm, target, tol, singular_tol, pose_tol, q_ref, tool=None,
                 near_tol=NEAR_SINGULAR):
    """One pose on Python floats: the loop of :func:`~dqlab.ik.ur_steps.candidate_solutions`
    with the checks and flags of the batch path.

    Returns the :class:`~dqlab.ik.result.IKResult` of the pose, the same as the batch
    path's, or None when the pose needs what only the batch path does: a wrist near its
    singularity (``|sin theta5|`` below ``NEAR_WRIST``, or at it within ``tol``: the wrist
    family, :func:`wrist_family_tol`), a wrist centre inside the shoulder cylinder or no
    valid row (the reasons), or a target that fails its check (the error message). A base
    and a tool (``tool``, else the robot's) are taken off the target first, on floats.

    Each step of :mod:`dqlab.ik.ur_steps` is written out in place (its name beside it), on
    ``math`` and plain arithmetic: a function call per step and branch would cost as much as
    the arithmetic itself. The values that do not depend on the branch (the shoulder's
    ``h``, the arm's lengths combined) are computed once, and a step with a sign argument
    ``sigma`` or ``elbow`` of 1 or -1 is written with the sign applied (exact: a product by
    -1 is a negation, and ``a - (-b)`` is ``a + b``), so that every row is, bit for bit,
    the steps' row (``tests/test_ik_ur.py::test_engine_equals_the_readable_path``).
    """
    flange = _single_flange(robot, target, pose_tol, tool)
    if flange is None:
        return None
    if q_ref is not None and not (type(q_ref) is np.ndarray and q_ref.dtype is _FLOAT64
                                  and q_ref.shape == (6,)
                                  and math.isfinite(math.fsum(q_ref.tolist()))):
        theta6_reference(q_ref, ())                # checked; it matters only at the wrist
    q, p, z6 = flange
    (d1, a2, a3, d4, d5, d6, offsets, far, r_out, r_in, sum_sq, turned, m,
     a3_m) = prm.get("one pose") or arm_constants(prm)
    family_tol = wrist_family_tol(tol, d6)
    rw, rx, ry, rz = steps.target_rotation(q)
    x5, y5, z5 = steps.wrist_center(p, z6, d6)
    if not abs(x5) + abs(y5) + abs(z5 - d1) <= far:   # far_wrist (or not finite): the batch
        return None                                  # path
    # shoulder_angles, the part shared by both shoulders
    h2 = x5 * x5 + y5 * y5 - d4 * d4
    if h2 < 0.0:                                   # inside the shoulder cylinder
        return None
    h = math.sqrt(h2) if h2 > 0.0 else 0.0         # (clip0: never -0.0)
    y5d4, x5d4 = y5 * d4, x5 * d4
    v5 = z5 - d1                                   # arm_plane_wrist's v5
    atan2, sqrt, pi = math.atan2, math.sqrt, math.pi
    solutions, errors = [0.0] * 48, [0.0] * 8     # (8, 6) row by row; rows not valid stay 0
    any_valid = wrist_singular = elbow_singular = near = clipped = False
    for s in (0, 1):
        hpm = h if s == 0 else -h                  # shoulder_angles: sign h
        num_c = x5 * hpm - y5d4
        num_s = y5 * hpm + x5d4
        theta1 = atan2(num_s + 0.0, num_c)
        r = sqrt(num_c * num_c + num_s * num_s)
        c1, s1 = (num_c / r, num_s / r) if r > 0.0 else (1.0, 0.0)
        big = sqrt(0.5 + 0.5 * abs(c1))            # half_angle_cos_sin
        other = 0.5 * s1 / big
        if c1 >= 0.0:
            hc, hs = big, other
        else:
            hc, hs = abs(other), (-big if s1 < 0.0 else big)
        Lw, Lx = hc * rw + hs * rz, hc * rx + hs * ry          # relative_rotation_
        Ly, Lz = hc * ry - hs * rx, hc * rz - hs * rw          # coefficients
        u5 = c1 * x5 + s1 * y5                     # arm_plane_wrist
        c5bar = sqrt(Lw * Lw + Ly * Ly)            # wrist_angles (sigma = 1)
        s5bar = sqrt(Lx * Lx + Lz * Lz)
        sin5 = 2.0 * s5bar * c5bar
        if sin5 < steps.NEAR_WRIST or min(s5bar, c5bar) <= family_tol:
            return None
        theta5 = 2.0 * atan2(s5bar, c5bar)         # in [0, pi]: never -pi
        half_sum = atan2(-Ly, Lw)
        k = 1.0 / (c5bar * s5bar)                  # theta234_sine_cosine (sigma = 1)
        sin234, cos234 = k * (Lw * Lx + Ly * Lz), k * (Lx * Ly - Lw * Lz)
        for w in (0, 1):
            if w == 0:
                half_diff = atan2(Lx, -Lz)         # half_difference, sigma = 1
            else:
                # the flipped wrist, sigma = -1, from the sigma = +1 values: wrist_angles'
                # theta5 and theta234_sine_cosine's k = sigma / (c5bar s5bar) change sign
                # exactly; the half difference is computed anew
                theta5 = -theta5 if theta5 != pi else theta5      # never -pi
                half_diff = atan2(-Lx, Lz)         # half_difference, sigma = -1
                sin234, cos234 = -sin234, -cos234
            theta234 = half_sum + half_diff
            theta6 = half_sum - half_diff
            if not -pi < theta6 <= pi:             # wrap_angle, as on a float
                theta6 -= _TWO_PI * round(theta6 * _ONE_TURN)
                if not abs(theta6) < pi:
                    theta6 = (theta6 - _TWO_PI if theta6 > pi
                              else theta6 + _TWO_PI if theta6 <= -pi else theta6)
            u4, v4 = u5 - d5 * sin234, v5 + d5 * cos234        # wrist1_point
            rho2 = u4 * u4 + v4 * v4               # elbow_triangle
            rho = sqrt(rho2)
            outer = (r_out - rho) * (r_out + rho)
            inner = (rho - r_in) * (rho + r_in)
            kk = outer * inner
            kk = sqrt(kk) if kk > 0.0 else 0.0
            cos_num = rho2 - sum_sq
            if turned:
                cos_num = -cos_num
            angle3 = atan2(kk, cos_num)            # in [0, pi]
            # the residual of the rows: the clipping of the elbow, if any (h2 >= 0: no
            # shoulder gap); margins >= 0 mean the wrist-1 point is within reach, gap 0
            if outer < 0.0 or inner < 0.0:
                clipped = True
                error = errors[4 * s + w] = errors[4 * s + 2 + w] = steps.reach_gap(
                    u4, v4, a2, a3)
                if error > tol:                 # both rows stay zero, as finish() writes them
                    continue
            k1, k2 = a2 + a3_m * cos_num, a3_m * kk             # elbow_angles
            vk1, uk2, uk1, vk2 = v4 * k1, u4 * k2, u4 * k1, v4 * k2
            up = 24 * s + 6 * w                    # row k = 4 s + 2 e + w, elbow e = 0
            for first, theta2, theta3 in (
                    (up, atan2(vk1 - uk2 + 0.0, uk1 + vk2), angle3),           # elbow = 1
                    (up + 12, atan2(vk1 + uk2 + 0.0, uk1 - vk2),                # elbow = -1
                     -angle3 if angle3 != pi else angle3)):                    # (never -pi)
                theta4 = theta234 - theta2 - theta3
                if not -pi < theta4 <= pi:         # wrap_angle, as on a float
                    theta4 -= _TWO_PI * round(theta4 * _ONE_TURN)
                    if not abs(theta4) < pi:
                        theta4 = (theta4 - _TWO_PI if theta4 > pi
                                  else theta4 + _TWO_PI if theta4 <= -pi else theta4)
                if offsets is None:
                    solutions[first:first + 6] = theta1, theta2, theta3, theta4, theta5, theta6
                    continue
                row = [t - o for t, o in zip((theta1, theta2, theta3, theta4, theta5, theta6),
                                             offsets, strict=True)]
                if not (min(row) > -pi and max(row) <= pi):   # else wrap them
                    row = [wrap_angle(t) for t in row]
                solutions[first:first + 6] = row
            sin3 = kk / m
            elbow_singular = elbow_singular or sin3 < singular_tol
            near = near or sin3 < near_tol
            any_valid = True
            wrist_singular = wrist_singular or sin5 < singular_tol
            near = near or sin5 < near_tol
    if not any_valid:
        return None
    if clipped:
        numbers = np.fromiter(solutions + errors, float, 56)    # (8, 6) solutions, 8 errors
        solutions, errors = numbers[:48].reshape(8, 6), numbers[48:]
        valid = errors <= tol
    else:                                       # nothing clipped: every row valid, exact
        solutions = np.fromiter(solutions, float, 48).reshape(8, 6)
        errors, valid = np.zeros(8), _EIGHT_TRUE.copy()
    flags = {"wrist_singular": np.array(wrist_singular),
             "shoulder_singular": np.array(h < singular_tol * d4),
             "elbow_singular": np.array(elbow_singular),
             "near_singular": np.array(near or h < near_tol * d4),
             "unreachable": np.array(False), "not_converged": np.array(False)}
    return IKResult(solutions, valid, errors, np.zeros(8), flags, np.array("", dtype=object))


# --------------------------------------------------------------------------------------
# A batch on arrays, the poses last


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
    near_tol: float


@dataclass
class _Branches:
    """The eight candidate joint vectors of a block of n poses and the intermediate values
    the checks need; arrays over the branch axes (s, e, w) with the poses last."""

    solutions: np.ndarray      # (6, 8, n), wrapped to (-pi, pi]
    h: np.ndarray              # (n,) sqrt(x5^2 + y5^2 - d4^2), clipped at 0
    h2: np.ndarray             # (n,) x5^2 + y5^2 - d4^2 before clipping (negative: inside)
    sin5: np.ndarray           # (2, 1, n) |sin(theta5)| = 2 |sin(theta5 / 2) cos(theta5 / 2)|
    u4: np.ndarray             # (2, 1, 2, n) wrist-1 point in the arm plane
    v4: np.ndarray
    sin3: np.ndarray           # (2, 1, 2, n) |sin(theta3)|, the same on both elbow branches
    outer: np.ndarray          # (2, 1, 2, n) margin to the outer reach (negative: beyond)
    inner: np.ndarray          # (2, 1, 2, n) margin to the inner reach
    represented: np.ndarray    # (2, 2, n) over (s, w) rows standing for a wrist family, or None


@dataclass
class Block:
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
        floats = np.empty(64 * n + -(-14 * n // 8))    # 48 + 8 + 8 floats, 14 booleans
        solutions = floats[:48 * n].reshape(6, 8, n)
        pe = floats[48 * n:56 * n].reshape(8, n)
        re = floats[56 * n:64 * n].reshape(8, n)
        bools = floats[64 * n:].view(bool)
        valid = bools[:8 * n].reshape(8, n)
        flags = {name: bools[(8 + i) * n:(9 + i) * n] for i, name in enumerate(_FLAGS)}
        flags["not_converged"][...] = False              # a closed form has no iterations
        return cls(solutions, valid, pe, re, flags, reason)

    def __getitem__(self, part):
        return Block(self.solutions[..., part], self.valid[:, part],
                     self.position_error[:, part], self.rotation_error[:, part],
                     {name: flag[part] for name, flag in self.flags.items()},
                     self.reason[part])

    def result(self, batch):
        """The :class:`~dqlab.ik.result.IKResult` of poses of leading shape ``batch``, poses
        first."""
        return finish(self.solutions.T.reshape(batch + (8, 6)),
                      self.valid.T.reshape(batch + (8,)),
                      self.position_error.T.reshape(batch + (8,)),
                      self.rotation_error.T.reshape(batch + (8,)),
                      {name: f.reshape(batch) for name, f in self.flags.items()},
                      self.reason.reshape(batch))


def solve_batch(robot, prm, target, tol, singular_tol, pose_tol, tool, q_ref, residuals,
                near_tol=NEAR_SINGULAR):
    """Any poses (one or a batch) with array operations, without a Python loop over the
    poses, in blocks of :data:`CHUNK`."""
    targets = parse_targets(target, tol=pose_tol)
    tool, tool_dq, tool_fix = _tool(robot, tool, pose_tol)
    batch = targets.batch
    n = math.prod(batch)
    theta6_ref = theta6_reference(q_ref, batch)
    targets = targets.reshape((n,))
    flange = _flange(robot, targets, tool, tool_dq, prm["d6"])
    options = _Options(tol, singular_tol, residuals, tool_fix, near_tol)
    out = Block.empty(n)
    for start in range(0, n, CHUNK):
        part = slice(start, start + CHUNK)
        if n <= CHUNK:                                    # one block: no slicing
            _solve_block(robot, prm, flange, targets, theta6_ref, options, out)
        else:
            _solve_block(robot, prm, flange[part], targets[part],
                         None if theta6_ref is None else theta6_ref[part], options, out[part])
    return out.result(batch)


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
        # (a position near the largest float may overflow on the way: far_wrist finds it
        # infinitely far, and _stand_in_far_wrists refuses it)
        with np.errstate(over="ignore", invalid="ignore"):
            if moved:
                Q = dual_quaternion_product(
                    dual_quaternion_conjugate(dual_quaternion_from_transform(robot.base)), Q)
            if tooled:
                if tool_dq is None:
                    tool_dq = dual_quaternion_from_transform(tool)
                Q = dual_quaternion_product(Q, dual_quaternion_inverse(tool_dq))
            c = component_rows(Q.reshape(n, 8))               # (8, n), ours to overwrite
            q, p = c[:4], c[4:7]
            z6 = np.array(quaternion_rotate(*q, 0.0, 0.0, 1.0))
            _write_rows(p, translation_from_dual_quaternion_entries(*c))   # over the dual part
    _write_rows(p, steps.wrist_center(p, z6, d6))
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


def theta6_reference(q_ref, batch):
    """The theta6 of ``q_ref`` (checked) for every pose, shape (n,), or None."""
    if q_ref is None:
        return None
    q_ref = as_float_array(q_ref, "q_ref", (6,))
    try:
        return np.broadcast_to(q_ref[..., 5], batch).reshape(math.prod(batch))
    except ValueError:
        raise ValueError(f"q_ref of shape {q_ref.shape} does not broadcast against the "
                         f"poses' leading shape {batch}") from None


def _solve_block(robot, prm, flange, targets, theta6_ref, options, out):
    """Every branch of a block of n poses (batch axis last), checked and flagged, written
    into ``out`` (a :class:`Block` of n poses). A pose whose wrist centre is far beyond
    reach (:func:`~dqlab.ik.ur_steps.far_wrist`) is solved for a stand-in wrist centre
    twice the reach away in the same direction (so the steps square nothing large), and
    gets the distance as the error of every row."""
    far = _stand_in_far_wrists(prm, flange)
    branches = _branches(prm, flange, theta6_ref, options.tol, out.solutions)
    pe, re = _errors(robot, prm, flange, branches, targets, options, out, far)  # (8, n) each
    ok = np.less_equal(pe, options.tol, out=out.valid)
    if options.residuals == "fk" or branches.represented is not None:   # else re is 0
        ok &= re <= options.tol
    any_valid = ok.any(axis=0)                                              # (n,)
    _flags(prm, branches, ok, any_valid, options.singular_tol, options.near_tol, out.flags)
    if not any_valid.all():
        out.reason[...] = _reasons(prm, flange, branches, any_valid, options.tol)
        if far is not None:
            out.reason[far[0]] = REASON_FAR


def _stand_in_far_wrists(prm, flange):
    """The poses of a block whose wrist centre is far beyond reach, ``(columns, distances)``
    (or None), their wrist centres in ``flange`` replaced by a stand-in out of reach
    (twice the reach from the shoulder, along x), which the steps can square."""
    p5 = flange.p5
    d1, a2, a3, d4, d5 = prm["d1"], prm["a2"], prm["a3"], prm["d4"], prm["d5"]
    with np.errstate(over="ignore", invalid="ignore"):     # (a flange that overflowed)
        distance = steps.far_wrist(p5, d1, a2, a3, d4, d5)
    if not distance.any():
        return None
    if distance.max() == math.inf:
        raise ValueError("target: a position is so far from the robot (some 1e308 m) that "
                         "its distance overflows")
    cols = np.flatnonzero(distance)
    reach = math.sqrt(d4 * d4 + (abs(a2) + abs(a3) + abs(d5)) ** 2)
    p5[:, cols] = np.array([[2.0 * reach], [0.0], [d1]])
    return cols, distance[cols]


def _branches(prm, flange, theta6_ref, tol, out):
    """The steps for every branch at once: the candidate joint vectors of a block of
    poses, written into ``out`` (6, 8, n)."""
    d1, d4 = prm["d1"], prm["d4"]
    p5 = flange.p5

    # theta1: arrays (2, n) over the shoulder branch s
    theta1, c1, s1, h, h2 = steps.shoulder_angles(p5[0], p5[1], d4, _SHOULDER)

    # the rotation: r_D = q q0^*, L = r1^* r_D, arrays (2, 1, n) over (s, w)
    r_D = steps.target_rotation(flange.q)
    L = steps.relative_rotation_coefficients(r_D, steps.half_angle_cos_sin(c1, s1))
    L = tuple(c[:, None] for c in L)
    # arrays (2, 2, n) over (s, w), sigma = +1, -1 (half_sum, c5bar, s5bar: (2, 1, n))
    theta5, half_sum, half_diff, c5bar, s5bar = steps.wrist_angles(L, _SIGMA)
    u5, v5 = steps.arm_plane_wrist(p5, c1, s1, d1)
    u5 = u5[:, None, :]                                       # (2, 1, n)
    family = (prm, half_sum, half_diff, s5bar, c5bar, u5, v5, theta6_ref, tol)
    theta234, theta6, represented = _wrist_family(*family)
    if represented is None:          # no wrist family: c5bar s5bar > 0 everywhere
        sine_cosine = steps.theta234_sine_cosine(L, _SIGMA, c5bar, s5bar)    # (2, 2, n)
    else:                            # a member of a wrist family: its own sine and cosine
        with np.errstate(divide="ignore", invalid="ignore"):  # 0/0 only in the family
            sine_cosine = steps.theta234_sine_cosine(L, _SIGMA, c5bar, s5bar)
        for part, f in zip(sine_cosine, (np.sin, np.cos), strict=True):
            part[represented] = f(theta234[represented])

    # the planar chain: arrays (2, 2, 2, n) over (s, e, w)
    u4, v4, theta2, theta3, outer, inner, sin3 = _planar_chain(prm, u5, v5, *sine_cosine)
    # Near the wrist singularity theta234 comes from coefficients of the size of theta5 and
    # may be off by eps / |theta5|: enough to put the wrist-1 point of a stretched or folded
    # elbow out of reach. Such rows move within their wrist family to where the forearm
    # reaches (and are checked by forward kinematics).
    sin5 = 2.0 * s5bar * c5bar                                # (2, 1, n), |sin theta5|
    near = sin5 < steps.NEAR_WRIST
    repair = _out_of_reach(prm, outer, inner, tol) & near if near.any() else None
    if repair is not None and repair.any():
        theta234, theta6, represented = _wrist_family(*family, repair=repair)
        cols = np.flatnonzero(repair.any(axis=(0, 1)))        # the poses concerned
        moved, member = represented[..., cols], theta234[..., cols]
        sin234, cos234 = (np.where(moved, f(member), part[..., cols])   # the rows moved
                          for f, part in zip((np.sin, np.cos), sine_cosine, strict=True))
        chain = (u4, v4, theta2, theta3, outer, inner, sin3)
        for whole, part in zip(chain, _planar_chain(prm, u5[..., cols], v5[..., cols],
                                                    sin234, cos234), strict=True):
            whole[..., cols] = part
    # theta4 = theta234 - theta2 - theta3, in (-4 pi, 4 pi) before wrapping
    theta4 = wrap_angle(theta234[:, None] - theta2 - theta3)
    _joint_vectors((theta1[:, None, None, :], theta2, theta3, theta4, theta5[:, None],
                    wrap_angle(theta6)[:, None]), prm["offsets"], out)
    return _Branches(solutions=out, h=h, h2=h2, sin5=sin5, u4=u4, v4=v4,
                     sin3=sin3, outer=outer, inner=inner, represented=represented)


def wrist_family_tol(tol, d6):
    r"""The :math:`\bar c_5` or :math:`\bar s_5` (cosine or sine of half of
    :math:`\theta_5`) at or below which a pose is at the wrist singularity for the
    tolerance ``tol``: its rows are members of a wrist family (:func:`_wrist_family`), whose
    joint vectors stay within ``tol`` of the pose. :math:`\mathrm{tol} / (8 \max(1,
    |d_6|))`."""
    return tol / (8.0 * max(1.0, abs(d6)))


def _wrist_family(prm, half_sum, half_diff, s5bar, c5bar, u5, v5, theta6_ref, tol,
                  repair=None):
    """theta234 and theta6 (2, 2, n) from the half sum and difference; at a wrist
    singularity, where only theta234 -+ theta6 is fixed, the member of the family whose
    theta6 is nearest ``theta6_ref`` among those the arm can reach; for the rows in
    ``repair`` (near the singularity), the member nearest the computed theta234 that the arm
    can reach (``repair``, when given, marks some rows). Also returns the mask of the rows
    so chosen (None when there is none)."""
    theta234 = half_sum + half_diff
    theta6 = half_sum - half_diff
    rep_tol = wrist_family_tol(tol, prm["d6"])
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
    got = steps.feasible_theta234(np.broadcast_to(u5[..., cols], shape)[rep_c],
                                  np.broadcast_to(v5[..., cols], shape)[rep_c], want,
                                  prm["a2"], prm["a3"], prm["d5"])
    theta6_got = np.where(rep0[rep_c], full_sum[rep_c] - got, got - full_diff[rep_c])
    for whole, member in ((theta234, got), (theta6, theta6_got)):
        part = whole[..., cols]
        part[rep_c] = wrap_angle(member)
        whole[..., cols] = part
    return theta234, theta6, rep


def _out_of_reach(prm, outer, inner, tol):
    """Rows (2, 2, n) over (s, w) whose wrist-1 point lies more than tol / 2 beyond the
    forearm's reach on some elbow branch."""
    r_out, r_in = abs(prm["a2"] + prm["a3"]), abs(prm["a2"] - prm["a3"])
    far = (outer < -tol * r_out) | (inner < -tol * r_in)     # (2, 1 or 2, 2, n)
    return far.any(axis=1)


def _planar_chain(prm, u5, v5, sin234, cos234):
    """The wrist-1 point (2, 1, 2, n) and the elbow angles (2, 2, 2, n)."""
    u4, v4 = steps.wrist1_point(u5, v5, sin234, cos234, prm["d5"])   # (2, 2, n), (s, w)
    u4, v4 = u4[:, None], v4[:, None]                         # (2, 1, 2, n)
    theta2, theta3, outer, inner, sin3 = steps.elbow_angles(u4, v4, prm["a2"], prm["a3"],
                                                            _ELBOW)
    return u4, v4, theta2, theta3, outer, inner, sin3


def _joint_vectors(thetas, offsets, out):
    """Write the joint vectors (6, 8, n) -- joint j of row k = 4 s + 2 e + w of pose i at
    ``[j, k, i]`` -- from the six angle arrays over (s, e, w, n) into ``out``, joint offsets
    removed."""
    view = out.reshape(6, 2, 2, 2, out.shape[-1])   # splits the row axis: a view of ``out``
    for j, theta in enumerate(thetas):
        view[j] = theta
    if any(offsets):
        out[...] = wrap_angle(out - np.array(offsets)[:, None, None])


def _errors(robot, prm, flange, branches, targets, options, out, far=None):
    """Position and rotation errors (8, n) of every row, written into ``out`` (a
    :class:`Block`): from the clipping of the steps (``residuals="equations"``) or by
    forward kinematics (``"fk"``); for the poses ``far`` (``(columns, distances)`` of
    :func:`_stand_in_far_wrists`, whose rows were solved for a stand-in), their distance."""
    pe, re = out.position_error, out.rotation_error
    n = pe.shape[1]
    poses = slice(None) if far is None else np.setdiff1d(np.arange(n), far[0])
    if options.residuals == "fk":
        pe[:, poses], re[:, poses] = (e.T for e in _fk_errors(
            robot, branches.solutions[:, :, poses].T, targets[poses].transforms[:, None],
            options.tool_fix))
    else:
        re[...] = 0.0
        _clipping_distance(prm, flange, branches, pe)
        if branches.represented is not None:
            rows = np.broadcast_to(branches.represented[:, None], (2, 2, 2, n)).reshape(8, n)
            if far is not None:
                rows = rows & np.isin(np.arange(n), poses)
            k, i = np.nonzero(rows)                           # row k of pose i
            pe[k, i], re[k, i] = _fk_errors(robot, branches.solutions[:, k, i].T,
                                            targets[i].transforms, options.tool_fix)
    if far is not None:
        pe[:, far[0]], re[:, far[0]] = far[1], 0.0
    return pe, re


def _clipping_distance(prm, flange, branches, out):
    """Distance (8, n) a row misses the pose by, from the clipping of the steps: the
    wrist centre inside the shoulder cylinder (normal to the arm plane) and the wrist-1 point
    out of the forearm's reach (in it); written into ``out``."""
    n = flange.q.shape[1]
    inside = branches.h2.min() < 0.0   # some wrist centre inside the shoulder cylinder
    if not inside and branches.outer.min() >= 0.0 and branches.inner.min() >= 0.0:
        out[...] = 0.0                                        # nothing was clipped
        return
    e = steps.reach_gap(branches.u4, branches.v4, prm["a2"], prm["a3"])     # (2, 1, 2, n)
    if inside:
        e1 = steps.shoulder_gap(flange.p5[0], flange.p5[1], branches.h2, prm["d4"])  # (n,)
        e = np.sqrt(e1 * e1 + e * e)
    out.reshape(2, 2, 2, n)[...] = e                          # splits the rows: a view


def _fk_errors(robot, solutions, X_target, tool_fix):
    """pose_errors of robot.fk of joint vectors (..., 6) against X_target (..., 4, 4),
    with the tool changed by ``tool_fix`` when not None."""
    X = robot.fk(solutions)
    if tool_fix is not None:
        X = X @ tool_fix
    return pose_errors(X, X_target)


def _flags(prm, branches, ok, any_valid, singular_tol, near_tol, out):
    """The singularity and reach flags (n,) of a block, over its valid rows, written into
    ``out`` (the block's flags)."""
    n = ok.shape[1]
    ok4 = ok.reshape(2, 2, 2, n)
    shoulder = np.less(branches.h, singular_tol * prm["d4"], out=out["shoulder_singular"])
    shoulder &= any_valid
    near = np.less(branches.h, near_tol * prm["d4"], out=out["near_singular"])
    near &= any_valid
    np.logical_not(any_valid, out=out["unreachable"])
    # |sin theta5| (2, 1, 1, n) over (s, w) and |sin theta3| (2, 1, 2, n) over (s, w)
    for name, sine in (("wrist_singular", branches.sin5[:, None]),
                       ("elbow_singular", branches.sin3)):
        if sine.min() < singular_tol:
            (ok4 & (sine < singular_tol)).reshape(8, n).any(axis=0, out=out[name])
        else:
            out[name][...] = False
        if sine.min() < near_tol:
            near |= (ok4 & (sine < near_tol)).reshape(8, n).any(axis=0)


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
    gap = steps.shoulder_gap(flange.p5[0], flange.p5[1], branches.h2, prm["d4"])
    reason[none & (gap > tol)] = REASON_SHOULDER
    return reason
