r"""Inverse kinematics of any Universal Robots arm, exact or calibrated: ``dqlab.ik.ur``.

:func:`ur` tells the robot's kind once (remembered per robot) and calls its solver, the
target parsed by that solver alone:

- the exact UR shape (:func:`~dqlab.ik.ur_closed_form.ur_parameters`): the closed form
  :func:`dqlab.ik.ur_closed_form.exact_ur`, every solution by dual quaternions;
- a calibrated UR, whose lengths and angles are millimetres off that shape:
  :func:`dqlab.ik.ur_calibrated.calibrated_ur`, the closed form of its nearest exact UR
  refined by Newton steps on the calibrated chain.

Both return the eight rows of :data:`~dqlab.ik.ur_closed_form.SOLUTION_ORDER` with the
same flags, so a caller need not know which arm it holds. :func:`closest_ur_solution` picks
the joints to send a UR from where it stands, and :func:`ur_branch` tells the row a joint
vector belongs to, on either kind of arm.
"""

import weakref

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._checks import check_instance, real_array
from ..robot import Robot
from ._per_robot import remembered
from .result import IKResult
from .solutions import check_joint_limits, check_reference, closest_solution
from .ur_calibrated import calibrated_ur, nominal_ur
from .ur_closed_form import ROW_NAMES, branch_measures, exact_ur, ur_parameters
from .ur_steps import NEAR_SINGULAR

__all__ = ["ur", "closest_ur_solution", "ur_branch"]

_EXACT, _CALIBRATED = "exact UR", "calibrated UR"
_KINDS = weakref.WeakKeyDictionary()      # robot -> its kind (links are immutable)


def _classify(robot):
    """The kind of a robot, decided once per robot: ``(_EXACT, None)`` for the exact UR
    shape, ``(_CALIBRATED, nominal_ur(robot))`` for a calibrated UR; for neither a
    ValueError naming both reasons (remembered too, and raised again)."""
    return remembered(_KINDS, robot, _kind)


def _kind(robot):
    """:func:`_classify`'s answer, computed (a ValueError is returned, not raised)."""
    try:
        ur_parameters(robot)
        return _EXACT, None          # (not the robot: a value must not hold its weak key)
    except ValueError as exc:
        try:
            return _CALIBRATED, nominal_ur(robot)
        except ValueError as why:
            return ValueError(f"{exc}; nor is it a calibrated UR: {why}")


def ur(robot: Robot, target: ArrayLike, *, tol: float = 1e-9, tool: ArrayLike | None = None,
       q_ref: ArrayLike | None = None, singular_tol: float = 5e-7, pose_tol: float = 1e-9,
       residuals: str = "equations", near_tol: float = NEAR_SINGULAR) -> IKResult:
    r"""Every inverse-kinematics solution of a UR-family arm, exact or calibrated.

    The exact UR shape is solved in closed form by
    :func:`~dqlab.ik.ur_closed_form.exact_ur`, a calibrated UR by
    :func:`~dqlab.ik.ur_calibrated.calibrated_ur`; the robot's kind is told once per robot.
    The arguments, the result and the errors are those of
    :func:`~dqlab.ik.ur_closed_form.exact_ur`, which gives the route, the order of the eight
    rows and the meaning of every option.

    Its former name, ``dqlab.ik.ur_closed_form.ur``, still finds it for one version, with a
    :class:`DeprecationWarning` (as do ``closest_ur_solution`` and ``ur_branch``, now here
    too).

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm in standard DH, exact (for example :func:`dqlab.models.ur3`) or
        calibrated (parameters millimetres off the exact shape); its base transform and
        tool are taken into account.
    target : array_like, shape (..., 4, 4) or (..., 8)
        Target pose(s) of the TCP in the world frame, as rigid transforms or unit dual
        quaternions, each part scalar first, ``(w, x, y, z)``.
    tol, tool, q_ref, singular_tol, pose_tol, residuals, near_tol
        As for :func:`~dqlab.ik.ur_closed_form.exact_ur`.

    Returns
    -------
    IKResult
        As :func:`~dqlab.ik.ur_closed_form.exact_ur` returns it; on a calibrated UR the flag
        ``"not_converged"`` may be set, and a pose near a singularity may have solutions
        beyond its eight rows, in ``result.more`` (see
        :func:`~dqlab.ik.ur_calibrated.calibrated_ur`).

    Raises
    ------
    ValueError
        If the robot is neither an exact nor a calibrated UR (the message gives both
        reasons), besides the errors of the solver called.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.identify import dh_parameters, robot_from_dh_parameters
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> int(ur(robot, robot.fk(q)).count)
    8

    The same arm calibrated, every parameter 1 mm or 1 mrad off:

    >>> calibrated = robot_from_dh_parameters(robot, dh_parameters(robot) + 1e-3)
    >>> result = ur(calibrated, calibrated.fk(q))
    >>> bool(np.any(np.all(np.abs(result.solutions - q) < 1e-9, axis=-1)))
    True
    """
    kind, _ = _classify(robot)
    if kind is _EXACT:
        return exact_ur(robot, target, tol=tol, tool=tool, q_ref=q_ref,
                        singular_tol=singular_tol, pose_tol=pose_tol, residuals=residuals,
                        near_tol=near_tol)
    result = calibrated_ur(robot, target, tol=tol, tool=tool, q_ref=q_ref,
                           singular_tol=singular_tol, pose_tol=pose_tol, residuals=residuals,
                           near_tol=near_tol)
    result.row_names = ROW_NAMES
    return result


def closest_ur_solution(robot: Robot, target: ArrayLike, q_now: ArrayLike, *,
                        limits: ArrayLike | None = None, tol: float = 1e-9,
                        weights: ArrayLike | None = None, keep_branch: bool = False,
                        **options) -> NDArray[np.float64]:
    r"""The joints to send a UR standing at ``q_now`` to reach ``target``: one call.

    Every solution of :func:`ur` (the robot's tool and base included; a calibrated UR
    too), every :math:`2\pi`-equivalent of it within the joint limits (a UR joint turns
    :math:`\pm 2\pi`, so each joint has two candidates), and among them the joint vector
    nearest ``q_now``: :func:`~dqlab.ik.solutions.closest_solution` of :func:`ur`, with
    ``q_now`` also as the reference at a wrist singularity.

    "Nearest" is the plain joint distance by default, which weighs a turn of the base as
    much as a turn of the wrist: when the wrist cannot follow within its limits (a tool
    twist with wrist 3 near :math:`2\pi`), the nearest solution may be on another branch,
    the shoulder or the wrist flipped. ``weights`` makes the big joints dearer;
    ``keep_branch=True`` keeps the arm on the branch it is on (shoulder, elbow, wrist of
    ``q_now``, :func:`ur_branch`), and refuses a target it cannot reach on it.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm, with its tool (:meth:`~dqlab.robot.Robot.with_tool`).
    target : array_like, shape (..., 4, 4) or (..., 8)
        The TCP pose(s) in the world frame (as for :func:`ur`).
    q_now : array_like, shape (6,) or (..., 6)
        The robot's current joints, radians; within the joint limits.
    limits : array_like, shape (2,) or (6, 2), optional
        Joint limits; default ``robot.limits``.
    tol : float
        As for :func:`ur`.
    weights : array_like, shape (6,), optional
        Joint weights of the distance, :math:`\sum_j w_j (q_j - q_{now,j})^2` (default all
        1), for example ``(10, 10, 5, 1, 1, 1)`` to move the wrist rather than the arm.
    keep_branch : bool
        Choose only among the solutions on the branch of ``q_now``.
    **options
        Further keywords of :func:`ur` (``singular_tol``, ``pose_tol``, ``tool``,
        ``near_tol``).

    Returns
    -------
    ndarray, shape (..., 6)

    Raises
    ------
    ValueError
        If a target has no solution (the message gives the solver's reason) or, with
        ``keep_branch``, none on the branch of ``q_now``, no solution is within the limits,
        ``q_now`` is outside the limits (a hint if it looks like degrees) or the weights
        are not positive, besides the errors of :func:`ur`.

    Examples
    --------
    A UR5e with a gripper whose TCP is 0.15 m along the flange's z axis, at ``q_now``, sent
    to a pose 5 cm lower:

    >>> import numpy as np
    >>> from dqlab.models import ur5e
    >>> robot = ur5e().with_tool(z=0.15)
    >>> q_now = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> X = robot.fk(q_now)
    >>> X[2, 3] -= 0.05
    >>> q = closest_ur_solution(robot, X, q_now)
    >>> q.round(3)
    array([ 0.3  , -1.205,  1.234, -0.529,  0.9  ,  0.2  ])
    >>> bool(np.allclose(robot.fk(q), X, atol=1e-12))
    True

    Wrist 3 at 5.9 rad and the tool to be turned by 0.5 rad more, beyond its limit of
    :math:`2\pi`: the nearest solution flips the wrist (joints 4 to 6 move by up to
    2.8 rad); on the same branch, wrist 3 turns back by 5.8 rad instead:

    >>> from dqlab.rotations import rot_z
    >>> q_now = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 5.9])
    >>> twist = np.eye(4)
    >>> twist[:3, :3] = rot_z(0.5)
    >>> X = robot.fk(q_now) @ twist
    >>> (closest_ur_solution(robot, X, q_now) - q_now).round(2) + 0.0     # (no -0.)
    array([ 0.  ,  0.27,  0.03,  2.84, -1.8 , -2.64])
    >>> (closest_ur_solution(robot, X, q_now, keep_branch=True) - q_now).round(2) + 0.0
    array([ 0.  ,  0.  ,  0.  ,  0.  ,  0.  , -5.78])
    """
    limits = robot.limits if limits is None else limits
    lo, hi = check_joint_limits(limits, 6)
    q_now = check_reference(q_now, 6, "q_now")
    if q_now.shape == (6,):                 # one joint vector: on floats
        outside = any(not a <= v <= b for v, a, b in zip(q_now.tolist(), lo.tolist(),
                                                         hi.tolist(), strict=True))
    else:
        outside = not ((q_now >= lo) & (q_now <= hi)).all()
    if outside:
        first = tuple(np.argwhere((q_now < lo) | (q_now > hi))[0])
        j, value = int(first[-1]), float(q_now[first])
        hint = (" (joint angles are radians: degrees? convert with np.radians)"
                if abs(value) > 4 * np.pi else "")     # beyond two turns
        raise ValueError(f"q_now: joint {j + 1} = {value:.6g} is outside its limits "
                         f"[{lo[j]:.6g}, {hi[j]:.6g}]{hint}")
    if type(target) is not np.ndarray:
        target = real_array(target, "target")
    shape = target.shape
    trailing = shape[-2:] if shape[-2:] == (4, 4) else shape[-1:]
    leading = shape[:len(shape) - len(trailing)]
    if q_now.shape[:-1] != leading:          # one q_now for many targets, or the other way
        try:
            batch = np.broadcast_shapes(leading, q_now.shape[:-1])
        except ValueError:
            raise ValueError(f"q_now of shape {q_now.shape} does not broadcast against the "
                             f"targets' leading shape {leading}") from None
        target = np.broadcast_to(target, batch + trailing)
        q_now = np.broadcast_to(q_now, batch + (6,))
    result = ur(robot, target, tol=tol, q_ref=q_now, **options)
    if not result.valid.any(axis=-1).all():
        failed = ~result.valid.any(axis=-1)
        where = tuple(int(i) for i in np.argwhere(failed)[0]) if failed.ndim else ()
        which = f"target {where}" if where else "the target"
        raise ValueError(f"{which} has no solution: {result.reason[where]}")
    if keep_branch:
        branch = np.broadcast_to(ur_branch(robot, q_now), result.valid.shape[:-1])
        on = result.valid & (np.arange(8) == branch[..., None])
        more = result.more                  # the solutions beyond the rows, on the branch
        if more.valid.any():
            more_on = more.valid & (ur_branch(robot, more.solutions) == branch[..., None])
            more = IKResult(more.solutions, more_on, more.position_error,
                            more.rotation_error)
            on_any = on.any(axis=-1) | more_on.any(axis=-1)
        else:
            more, on_any = None, on.any(axis=-1)
        if not on_any.all():
            where = tuple(int(i) for i in np.argwhere(~on_any)[0])
            which = f"target {where}" if where else "the target"
            raise ValueError(f"{which} has no solution on the branch of q_now "
                             f"({ROW_NAMES[int(branch[where])]}), which keep_branch=True "
                             f"keeps; valid rows: "
                             f"{np.flatnonzero(result.valid[where]).tolist()}")
        result = IKResult(result.solutions, on, result.position_error, result.rotation_error,
                          result.flags, result.reason, _more=more)
    return closest_solution(result, q_now, limits, weights=weights)


def ur_branch(robot: Robot, q: ArrayLike) -> NDArray[np.int64]:
    r"""The branch of joint vectors of a UR: the row ``4 s + 2 e + w`` of :func:`ur`'s
    solutions (:data:`~dqlab.ik.ur_closed_form.SOLUTION_ORDER`) that a pose reached with
    them is solved in.

    With the measures of :func:`~dqlab.ik.ur_closed_form.branch_measures`: shoulder
    :math:`s = 1` ("right") when the wrist centre lies behind the base axis along
    :math:`x_1`, :math:`h < 0`; elbow :math:`e = 1` ("down") when :math:`\sin\theta_3 < 0`;
    wrist :math:`w = 1` ("flip") when :math:`\sin\theta_5 < 0`. On a calibrated UR, those
    of its nearest exact UR (:func:`~dqlab.ik.ur_calibrated.nominal_ur`); exactly at a
    singularity the two branches it separates are one, and either is returned.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A UR-family arm (exact or calibrated).
    q : array_like, shape (..., 6)
        Joint vectors, radians.

    Returns
    -------
    ndarray of int, shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur5e
    >>> q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> int(ur_branch(ur5e(), q)), ROW_NAMES[int(ur_branch(ur5e(), q))]
    (4, 'right up noflip')
    """
    check_instance(robot, Robot, "robot")
    q = robot.check_joints(q)
    kind, nominal = _classify(robot)
    h, sin_theta3, sin_theta5 = branch_measures(robot if kind is _EXACT else nominal, q)
    return 4 * (h < 0) + 2 * (sin_theta3 < 0) + (sin_theta5 < 0)
