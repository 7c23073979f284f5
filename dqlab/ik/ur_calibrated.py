r"""Inverse kinematics of a calibrated UR: the closed form of the nearest exact UR, then Newton.

Every UR leaves the factory with its own kinematic calibration: its :math:`\theta_i, a_i,
d_i, \alpha_i` differ from the published ones by millimetres and milliradians (read them with
:mod:`dqlab.ur.calibration`). The calibrated chain no longer has the exact UR shape the closed
form of :func:`dqlab.ik.ur_closed_form.exact_ur` needs (axes 2, 3, 4 exactly parallel, the others
exactly perpendicular), so ``dqlab.ik.ur`` hands such a robot to :func:`calibrated_ur`, which
keeps its contract (every branch, flags, reasons, batches) in these steps:

1. **The nearest exact UR** (:func:`nominal_ur`). Its lengths are read off the calibrated joint
   axes at :math:`q = 0` in the *arm plane*, the plane through joint 2 perpendicular to its
   axis: joints 3 and 4 cross it at :math:`P_3, P_4`, and with :math:`P_2` on joint 2,

   .. math::

      a_2 = -\lVert P_3 - P_2\rVert,\quad a_3 = -\lVert P_4 - P_3\rVert,\quad
      d_4 = (o_4 - P_4)\cdot z_1,

   the joint offsets :math:`\theta^0_2, \theta^0_3, \theta^0_4` being the angles between the
   successive directions :math:`x_1, (P_3 - P_2)/a_2, (P_4 - P_3)/a_3, x_4` about
   :math:`z_1`. Joints 1, 5 and 6 keep their calibrated :math:`d_i, \theta^0_i` (their axes
   meet their neighbours at right angles, where the DH parameters are well conditioned). This
   reads the same arm whatever the calibrated parameters look like: a controller expresses
   nearly parallel axes with common normals hundreds of metres away (:math:`d_2 = 305.9` m,
   :math:`d_3 = -305.7` m), which the arm plane does not see.
2. **The closed form** of that exact UR gives every branch of every target, with the tolerance
   widened to twice the distance between the two arms (so that a target at the edge of the
   calibrated arm's reach, which the exact arm misses by a little, still gets its branches).
3. **Newton steps on the calibrated chain**, from each branch:

   .. math::

      q \leftarrow q + \bigl(J^\mathsf{T} J + \lambda I\bigr)^{-1} J^\mathsf{T} e(q),\qquad
      e = \begin{pmatrix} p^\ast - p \\ \tfrac12 (R^\ast R^\mathsf{T}
          - R R^{\ast\mathsf{T}})^\vee \end{pmatrix},

   with :math:`J` the geometric Jacobian at the TCP and :math:`\lambda = 10^{-12}\,
   \operatorname{tr}(J^\mathsf{T}J)/6` (a guard at exact singularities, negligible
   elsewhere); steps longer than half a radian are shortened. A branch stops when its error
   is below a tenth of ``tol`` (or stops improving); it is valid when forward kinematics of the
   calibrated chain reproduces the target to ``tol`` (and is not another row's solution). A
   branch that started from a solution of the exact arm but does not get there, or gets to
   a solution a row of lower number has, is kept as an invalid row with its errors and
   flagged ``"not_converged"``, never dropped silently; so is a pose whose solutions (the
   rows and those beyond them, step 6) are odd in number, since a general 6R arm reaches a
   pose in an even number of joint vectors (the real roots of a polynomial of degree 16;
   two meet and vanish together at a singularity). With numba installed (the ``fast``
   extra), these steps run compiled, on the eight branches of a pose at once
   (``dqlab._fast.newton_compiled``, tested to give the same solutions), and so does the
   exact arm's closed form of step 2 (and of step 4's wrist family), pose by pose (tested
   equal to it: bit for bit, and to the rounding at a wrist singularity); numpy runs them
   otherwise. One pose whose branches all converge, to distinct solutions, is
   finished with a few calls (``_one_pose``, with numba one compiled call; tested equal to
   the array path); the others go on to the restarts of ``_repair``. With numba, the
   array path runs compiled up to step 6 (``dqlab._fast.newton_compiled.array_poses``;
   for a batch of more than eight poses ``array_start``, ``repairs`` and ``array_finish``;
   tested equal to it): steps 2, 3 and 5 pose by pose, the repairs of steps 4 step by step
   as ``_repairs`` takes them, each step's restarts of every pose stepped together in the
   Newton kernel's eight lanes.
4. **The branches still missing**, near a singularity: members of the exact arm's wrist
   family as starts (``_family``, also for a pose with at most two branches near the wrist
   singularity, or none, where the exact arm's closed form may miss a whole shoulder; such
   a pose elsewhere takes the exact arm's clipped rows), and Newton steps deflated so that
   they cannot return to a solution the pose already has (``_deflate``).
5. **The valid rows near a singularity** of the exact arm take three Newton steps more
   (``_polish``): there a row stopped at a tenth of ``tol`` may lie 1e-5 rad from its
   solution (the smallest singular value of :math:`J` is small), and the steps bring the
   joints, not only the pose, to it.
6. **The solutions beyond the eight rows** (``_beyond``): a pose whose eight rows are all
   valid, one of them near a singularity of both arms, may have ten or twelve solutions
   (a general 6R arm has up to 16); deflated Newton from that row, moved 0.05 rad either
   way along its most singular direction, finds the others, which the result gives in
   ``result.more`` (eight rows more, valid where there is one).

Why step 4. A real calibration is not a few millimetres from an exact UR in every
direction: the controllers' parameters put joint axes 2, 3 and 4 out of parallel by 3 to
13 mrad (the calibrations of ``tests/data/real_calibrations``), which no exact UR can follow.
Measured, the nearest exact UR read off the axes here is as close as any: a least-squares fit
of the exact arm's twelve parameters, with or without a base and a tool transform, to the
calibrated arm's forward kinematics leaves the same gap (2-7 mm and 5-23 mrad on sample
configurations). Away from singularities Newton's steps cross that gap from every branch.
Within about the gap of a singularity they do not map one to one: two branches' starts lead
to one solution and the other is missed; the exact arm clips a row at the edge of its reach
that the calibrated arm reaches (``_off_the_edge`` moves such a start off the elbow
singularity, where Newton cannot start); near the wrist singularity a shoulder and elbow
may have four solutions along the exact arm's wrist family, not two. Steps 1-3 alone found
the generating configuration of 99.75-99.88 % of random poses of those arms; with steps 4
and 5, 99.88-99.99 % on each of three sets of 10,000
(``benchmarks/bench_ik_ur_calibrated.py``), the rest mostly at poses with more solutions
than the eight rows (a general 6R arm has up to 16): near a singularity of the exact arm the
calibrated one may have ten or twelve, and a row holds one of them. With step 6, which
gives the others in ``result.more``, 99.96-100 % on the same sets, every pose missed
flagged ``"near_singular"`` (the threshold is at least four times the arms' rotation gap,
and the exact arm's measures count too, at its own branches and at the valid rows) or
``"not_converged"`` (an odd count of solutions); on twelve sets of 10,000 per arm, 99.94-100
%, one pose of the UR3's in 120,000 missed without a flag (eight valid rows within 0.2 of
the wrist singularity, the configuration a ninth solution at :math:`\theta_5 = 0.009`).
"""

import math
import weakref
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from .._checks import as_float_array, rigid_rows
from .._fast import ur_engine as exact_engine
from .._fast.calibrated_entries import EntryChain
from .._fast.calibrated_matrices import DAMPING, MatrixChain
from .._fast.newton_compiled import (
    NO_ROW_INNER,
    NO_ROW_OUTER,
    NO_ROW_REACH,
    NO_ROW_SHOULDER,
    NO_ROW_TOL,
    SOLVED,
)
from .._fast.newton_compiled import accept as compiled_accept
from .._fast.newton_compiled import are_new as compiled_are_new
from .._fast.newton_compiled import array_finish as compiled_array_finish
from .._fast.newton_compiled import array_poses as compiled_array_poses
from .._fast.newton_compiled import array_start as compiled_array_start
from .._fast.newton_compiled import deflated as compiled_deflated
from .._fast.newton_compiled import exact_fk as compiled_exact_fk
from .._fast.newton_compiled import exact_one_pose as compiled_exact_one_pose
from .._fast.newton_compiled import exact_poses as compiled_exact_poses
from .._fast.newton_compiled import gram as compiled_gram
from .._fast.newton_compiled import nearness as compiled_nearness
from .._fast.newton_compiled import newton as compiled_newton
from .._fast.newton_compiled import one_pose as compiled_one_pose
from .._fast.newton_compiled import ready as compiled_ready
from .._fast.newton_compiled import refresh as compiled_refresh
from .._fast.newton_compiled import repairs as compiled_repairs
from .._fast.newton_compiled import smallest as compiled_smallest
from .._fast.newton_compiled import unique as compiled_unique
from .._formulas import quaternion_from_matrix_entries, rigid_inverse
from ..dualquat import dual_quaternion_from_transform
from ..models import UR_ALPHA, UR_SHAPE
from ..robot import Link, Robot
from ..rotations import wrap_angle
from .result import IKResult, check_ur_options, finish
from .targets import RIGID_TOL, parse_targets, pose_errors
from .ur_closed_form import branch_measures
from .ur_steps import (
    NEAR_SINGULAR,
    NEAR_WRIST,
    REASON_INNER,
    REASON_OUTER,
    REASON_REACH,
    REASON_SHOULDER,
    REASON_TOL,
)

__all__ = ["calibrated_ur", "nominal_ur", "REASON_NOT_CONVERGED", "MAX_DISCREPANCY"]

#: Why a pose without a valid row has none although the exact arm had branches for it.
REASON_NOT_CONVERGED = ("calibrated chain: no branch of the nearest exact UR's solution "
                        "converged to the pose within tol")

#: The largest distance (metres, and radians for the rotation) between a calibrated arm and
#: its nearest exact UR that :func:`nominal_ur` accepts: calibrations differ by millimetres;
#: a robot farther off is not a calibrated UR.
MAX_DISCREPANCY = 0.05

_STOP = 0.1            # a Newton branch stops when its errors are below _STOP tol
_MAX_STEP = 0.5        # longest Newton step, rad (a longer one is shortened)
_GIVE_UP_AFTER = 8     # steps after which a branch must keep halving its error
_FEW_ROWS = 192        # up to this many branches, the kernel working on whole matrices
_PLAIN_STEPS = 3       # first steps taken by every branch together, none stopped
_BLOCK = 2048          # branches per block of the Newton steps
_RESTART_ITER = 16     # Newton steps of a restart at most ...
_RESTART_GIVE_UP = 8   # ... after which it must keep halving its error
_DEFLATION_ITER = 10   # deflated Newton steps at most
_NEAR = 1e-4          # near a singularity: smallest eigenvalue of J^T J below _NEAR largest
#: The flags of a result, in order (the compiled one-pose path returns them so).
_FLAG_NAMES = ("wrist_singular", "shoulder_singular", "elbow_singular", "near_singular",
               "unreachable",
               "not_converged")
_WAYS = np.array([0.05, -0.05, 0.2, -0.2, 0.6, -0.6])
_NEAR_GAPS = 4.0       # near_singular on a calibrated arm: at least this many rotation gaps
_NEAR_MEASURE = 0.1    # a singularity measure below which a pose's missing branches are sought
_FAMILY = 6            # members of the exact arm's wrist family taken as starts
_FAMILY_TOL = 0.5      # the closed form's tolerance for them
_PER_POSE = 8          # up to this many poses, the compiled array path is one call
_FAR = 1e6             # a flange this many reaches away takes the numpy path (see _within)
_FEW_BRANCHES = 2      # a pose with this many branches or fewer ...
_FEW_WRIST = 0.2       # ... none with |sin theta_5| above this, takes the family's starts
_DEFLATION_WAYS = np.array([0.05, -0.05, 0.3, -0.3])   # the moves of a deflation's starts
_POLISH_NEAR = 0.04    # a valid row this near a singularity of the exact arm is polished
_MORE = 8              # rows of result.more: a 6R arm has up to 16 solutions, 8 in the rows
_MORE_WAYS = np.array([0.05, -0.05])   # the moves of the starts that seek more solutions
_SAMPLES = np.random.default_rng(20260531).uniform(-np.pi, np.pi, (64, 6))
_FLIPS = np.array([2, 1, 3])   # the flips of _repair's second restart: elbow, wrist, both
#: The reason of the compiled closed form's result, by how it ended
#: (``dqlab._fast.newton_compiled.SOLVED`` and the others).
_REASON_OF = np.full(7, "", dtype=object)
_REASON_OF[[SOLVED, NO_ROW_TOL, NO_ROW_REACH, NO_ROW_INNER, NO_ROW_OUTER, NO_ROW_SHOULDER]] = (
    "", REASON_TOL, REASON_REACH, REASON_INNER, REASON_OUTER, REASON_SHOULDER)
#: The numbers of the compiled steps (``dqlab._fast.newton_compiled``): Newton's rules ...
_NEWTON_STEPS = dict(plain=_PLAIN_STEPS, stop_factor=_STOP, give_up_after=_GIVE_UP_AFTER,
                     damping=DAMPING, max_step=_MAX_STEP)
#: ... the wrist family's: members, the tests of _family_members, the closed form's tol and
#: near_tol for them ...
_FAMILY_NUMBERS = (_FAMILY, _NEAR_MEASURE, _FEW_BRANCHES, _FEW_WRIST, _FAMILY_TOL,
                   NEAR_SINGULAR)
#: ... and the repairs' (steps 4).
_REPAIR_STEPS = dict(_NEWTON_STEPS, restart_iter=_RESTART_ITER, restart_give_up=_RESTART_GIVE_UP,
                     ways=_WAYS, near_ratio=_NEAR, family=_FAMILY_NUMBERS,
                     deflation_ways=_DEFLATION_WAYS, deflation_iter=_DEFLATION_ITER)


@dataclass(frozen=True)
class _NearestExact:
    """What a calibrated robot's solves need, computed once per robot: the nearest exact UR
    (bare), the largest position and rotation differences between the two arms on sample
    configurations, the calibrated chain's constants for the Newton kernels and the exact
    arm's for its closed form (compiled, and :func:`dqlab.ik.ur_parameters`' dict)."""

    robot: Robot
    position_gap: float
    rotation_gap: float
    links: np.ndarray     # (6, 5): per link (cos alpha, sin alpha, a, d, theta offset)
    exact: np.ndarray     # (12,): d1, a2, a3, d4, d5, d6 and the six offsets of the exact arm
    parameters: dict = field(compare=False)   # the exact arm's, as ur_parameters gives them
    matrix_chains: dict = field(default_factory=dict, compare=False)   # _matrix_chain's


_NEAREST_EXACT = weakref.WeakKeyDictionary()   # calibrated robot -> _NearestExact (immutable)


def nominal_ur(robot: Robot) -> Robot:
    r"""The exact UR nearest a calibrated one: the arm whose closed form starts the Newton steps.

    Read off the calibrated joint axes at :math:`q = 0` (see the module's step 1): the
    lengths :math:`d_1, a_2, a_3, d_4, d_5, d_6` and the joint offsets of an arm with the
    exact UR twists :math:`\alpha = (\pi/2, 0, 0, \pi/2, -\pi/2, 0)` and
    :math:`a_1 = a_4 = a_5 = a_6 = d_2 = d_3 = 0`. For an exact UR it is the same arm.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A calibrated UR: six revolute joints in standard DH whose parameters may differ from
        a UR's by millimetres and milliradians (or be written with far common normals, as a
        controller writes them). Its base and tool are not part of the answer.

    Returns
    -------
    Robot
        UR-shaped (:data:`dqlab.models.UR_SHAPE`), no base and no tool, the calibrated
        robot's joint limits.

    Raises
    ------
    ValueError
        If the robot is not six revolute joints in standard DH, or if the nearest exact UR
        is farther than :data:`MAX_DISCREPANCY` from it (0.05 m or 0.05 rad on sample
        configurations): then it is not a calibrated UR.

    Examples
    --------
    A UR5e whose upper arm is 1 mm longer than published, and whose shoulder turns 1 mrad
    about the upper arm's direction:

    >>> from dqlab.models import ur5e
    >>> from dqlab.identify import dh_parameters, dh_parameter_names, robot_from_dh_parameters
    >>> p = dh_parameters(ur5e())
    >>> names = dh_parameter_names(ur5e())
    >>> p[names.index("a2")] -= 0.001
    >>> p[names.index("alpha2")] += 0.001
    >>> calibrated = robot_from_dh_parameters(ur5e(), p)
    >>> exact = nominal_ur(calibrated)
    >>> round(exact.links[1].a, 6), exact.links[1].alpha
    (-0.426, 0.0)
    """
    return _nearest_exact(robot).robot


def _nearest_exact(robot):
    """The :class:`_NearestExact` of a calibrated robot, computed once."""
    try:
        return _NEAREST_EXACT[robot]
    except (KeyError, TypeError):
        pass
    links = getattr(robot, "links", None)
    if (links is None or robot.convention != "dh" or robot.n != 6
            or not all(lk.is_revolute for lk in links)):
        raise ValueError("a calibrated UR must be six revolute joints in standard DH, got "
                         f"{robot!r}")
    for i, (lk, alpha) in enumerate(zip(links, UR_ALPHA, strict=True), start=1):
        if not abs(math.remainder(lk.alpha - alpha, 2 * math.pi)) <= MAX_DISCREPANCY:
            raise ValueError(f"link {i} of a calibrated UR twists by about {alpha:.4g} rad, "
                             f"not {lk.alpha!r}")
    bare = Robot(links, convention="dh")
    F = bare.fk(np.zeros(6), all_frames=True)              # frames 0..6 (and the TCP = 6)
    x, z, o = F[:, :3, 0], F[:, :3, 2], F[:, :3, 3]
    n = z[1]                                              # the arm plane's normal, joint 2
    P2 = o[1]
    P3 = o[2] + ((P2 - o[2]) @ n) / (z[2] @ n) * z[2]     # joint 3 crosses the arm plane
    P4 = o[3] + ((P2 - o[3]) @ n) / (z[3] @ n) * z[3]     # joint 4 crosses the arm plane
    a2 = -float(np.linalg.norm(P3 - P2))
    a3 = -float(np.linalg.norm(P4 - P3))
    x2, x3 = (P3 - P2) / a2, (P4 - P3) / a3
    offsets = [links[0].theta_offset, _angle_about(x[1], x2, n), _angle_about(x2, x3, n),
               _angle_about(x3, x[4], n), links[4].theta_offset, links[5].theta_offset]
    d = [links[0].d, 0.0, 0.0, float((o[4] - P4) @ n), links[4].d, links[5].d]
    a = [0.0, a2, a3, 0.0, 0.0, 0.0]
    exact = Robot([Link(a=ai, alpha=al, d=di, theta_offset=t, limits=lk.limits)
                   for ai, al, di, t, lk in zip(a, UR_ALPHA, d, offsets, links, strict=True)],
                  convention="dh", name=f"{robot.name or 'calibrated UR'} (nearest exact UR)")
    UR_SHAPE.check(exact)
    position_gap, rotation_gap = (float(e.max()) for e in pose_errors(exact.fk(_SAMPLES),
                                                                      bare.fk(_SAMPLES)))
    if not (position_gap <= MAX_DISCREPANCY and rotation_gap <= MAX_DISCREPANCY):
        raise ValueError(f"the nearest exact UR is {position_gap:.3g} m and "
                         f"{rotation_gap:.3g} rad from this robot on sample configurations "
                         f"(a calibrated UR differs by millimetres; at most "
                         f"{MAX_DISCREPANCY} is accepted)")
    constants = np.array([(math.cos(lk.alpha), math.sin(lk.alpha), lk.a, lk.d, lk.theta_offset)
                          for lk in links])
    exact_constants = np.array([d[0], a2, a3, d[3], d[4], d[5], *offsets], dtype=float)
    constants.flags.writeable = exact_constants.flags.writeable = False
    L = exact.links                                      # (UR_SHAPE checked above)
    parameters = {"d1": L[0].d, "a2": L[1].a, "a3": L[2].a, "d4": L[3].d, "d5": L[4].d,
                  "d6": L[5].d, "offsets": [lk.theta_offset for lk in L]}
    nearest = _NearestExact(exact, position_gap, rotation_gap, constants, exact_constants,
                       parameters)
    _NEAREST_EXACT[robot] = nearest
    return nearest


def _angle_about(u, v, n):
    """The angle (rad) from the direction u to the direction v about the unit axis n."""
    return float(math.atan2(np.cross(u, v) @ n, u @ v - (u @ n) * (v @ n)))


def calibrated_ur(robot: Robot, target: ArrayLike, closed_form=None, *, tol: float = 1e-9,
                  tool: ArrayLike | None = None, q_ref: ArrayLike | None = None,
                  singular_tol: float = 5e-7, pose_tol: float = 1e-9,
                  residuals: str = "equations", max_iter: int = 16,
                  near_tol: float = NEAR_SINGULAR) -> IKResult:
    r"""Every inverse-kinematics solution of a calibrated UR: ``dqlab.ik.ur`` for such a robot.

    ``dqlab.ik.ur`` calls this when its robot is a calibrated UR; call that instead. The
    steps are the module's: the closed form of :func:`nominal_ur`, then Newton steps on the
    calibrated chain from every branch.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        A calibrated UR (see :func:`nominal_ur`); its base and tool are taken into account.
    target : array_like, shape (..., 4, 4) or (..., 8)
        TCP poses in the world frame (transforms or unit dual quaternions).
    closed_form : callable, optional
        The closed-form solver of the exact UR, called as ``closed_form(robot, X, tol=...,
        q_ref=..., singular_tol=..., near_tol=...)``; by default ``dqlab.ik.ur``'s engine,
        called directly (the same results as passing ``dqlab.ik.ur``).
    tol, tool, q_ref, singular_tol, pose_tol, near_tol
        As for ``dqlab.ik.ur``. ``q_ref`` (one per pose, or one for all) reaches the closed
        form (the member of a wrist family it starts from); ``singular_tol`` applies to the
        calibrated arm's own singularity measures (see Returns); ``near_tol`` too, raised to
        four times the rotation gap between the arm and its nearest exact UR, and to the
        exact arm's branches.
    residuals : {"equations", "fk"}
        Accepted for ``dqlab.ik.ur``'s signature; a calibrated chain has no solved equations,
        so the errors always come from forward kinematics.
    max_iter : int
        Newton steps per branch at most.

    Returns
    -------
    IKResult
        As ``dqlab.ik.ur``'s: ``solutions`` (..., 8, 6) in the exact arm's branch order
        (:data:`dqlab.ik.ur_closed_form.SOLUTION_ORDER`), wrapped to :math:`(-\pi, \pi]`;
        ``valid``; the errors of forward kinematics of the calibrated chain for every branch
        that was polished (the exact arm's errors for a branch it could not start); ``flags``
        ``"wrist_singular"``, ``"elbow_singular"``, ``"shoulder_singular"`` measured on the
        calibrated arm at its valid rows (the sines of the angles between joint axes 4 and
        6 and between the common normals of joints 2-3 and 3-4, and the distance of the
        wrist centre from the plane of joint 1 and joint 2's direction over :math:`d_4`),
        ``"near_singular"`` (one of them below the near threshold, or a measure of the
        nearest exact UR's at a valid row: :math:`|\sin\theta_3|`, :math:`|\sin\theta_5|`,
        :math:`|h| / |a_2|`), ``"unreachable"``, and
        ``"not_converged"`` (a branch started from a solution of the exact arm did not
        converge, or converged to a solution a row of lower number has: its row is invalid
        and keeps its errors; or the pose's solutions, the valid rows and ``more``, are odd
        in number, one of an even count missing): the keys of the exact closed
        form's result, in its order; ``reason``; ``more``: the solutions beyond the eight
        rows, (..., 8, 6), valid where a pose has one (step 6 of the module).

    Raises
    ------
    ValueError
        As :func:`nominal_ur` for a robot that is not a calibrated UR, and as ``dqlab.ik.ur``
        for a bad target, tool or tolerance.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.ik import ur
    >>> from dqlab.models import ur5e
    >>> from dqlab.identify import dh_parameters, robot_from_dh_parameters
    >>> p = dh_parameters(ur5e()) + np.random.default_rng(3).uniform(-2e-3, 2e-3, 24)
    >>> robot = robot_from_dh_parameters(ur5e(), p)          # off by up to 2 mm and 2 mrad
    >>> q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> result = ur(robot, robot.fk(q))
    >>> int(result.count), bool(result.position_error[result.valid].max() <= 1e-10)
    (8, True)
    >>> bool(np.any(np.abs(result.solutions - q).max(axis=-1) < 1e-9))
    True
    """
    compiled_refresh()                                  # DQLAB_COMPILED, read once a call
    nearest = _nearest_exact(robot)
    tol, singular_tol, near_tol, pose_tol = check_ur_options(tol, singular_tol, near_tol,
                                                             pose_tol, residuals)
    if closed_form is None:
        closed_form = _closed_form
    else:                                               # a solver of the exact robot
        closed_form = _solver_of_robot(closed_form)
    plain = _plain_pose(target, pose_tol)
    if plain:                                           # one transform, checked on floats
        batch, X_W = (), target[None]
    else:
        targets = parse_targets(target, tol=pose_tol)
        batch = targets.batch
        X_W = targets.transforms.reshape((-1, 4, 4))
    n = X_W.shape[0]
    if tool is None and robot.bare:                     # frame 0 is the world, TCP the flange
        X_6T, X_T6, X_0T, X_06 = robot.tool, robot.tool, X_W, X_W
    else:
        X_6T = robot.tool if tool is None else _checked_tool(tool, pose_tol)
        X_T6 = rigid_inverse(X_6T)                     # (base and tool checked already)
        with np.errstate(over="ignore", invalid="ignore"):
            X_0T = rigid_inverse(robot.base) @ X_W     # the targets in frame 0 ...
            X_06 = X_0T @ X_T6                          # ... and the flanges they mean
        if not np.isfinite(X_06).all():
            raise ValueError("target: a position is so far from the robot (some 1e308 m) "
                             "that it overflows in the robot's base frame")
    wide = max(tol, 2.0 * nearest.position_gap)
    references = _references(q_ref, batch)              # (n, 6), or None

    near_limit = max(near_tol, _NEAR_GAPS * nearest.rotation_gap)

    def exact_solutions(X, poses=None, tol=wide, near_tol=near_limit, ref=None,
                        checked=True):
        """The exact arm's closed form of the flanges X (m, 4, 4), which are those of the
        poses ``poses`` (all n when None): each with its own reference, or the references
        ``ref`` (m, 6) given (its near_singular flag with the calibrated arm's threshold).
        ``checked``: X is known to be rigid to the closed form's tolerance (the flanges
        of the targets once checked, and products of rigid transforms)."""
        if ref is None and references is not None:
            ref = references if poses is None else references[poses]
        if batch == () and X.shape[0] == 1:             # one pose (compiled, with numba)
            if compiled_ready():
                result = _exact_one_pose(nearest, X[0], None if ref is None else ref[0], tol,
                                         singular_tol, near_tol, checked)
                if result is not None:
                    return result
            X, ref = X[0], None if ref is None else ref[0]
        elif pose_tol <= RIGID_TOL and compiled_ready():
            # (the targets are checked at least as strictly as the closed form checks them)
            return _exact_poses(nearest, X, ref, tol, singular_tol, near_tol, closed_form)
        return closed_form(nearest, X, tol=tol, q_ref=ref, singular_tol=singular_tol,
                           near_tol=near_tol)

    if n == 0:                                          # an empty batch: nothing to solve
        return _unsolved(nearest, X_6T, X_0T, np.zeros(0), np.zeros(0), np.zeros(0, bool),
                         np.zeros(0, dtype=object), tol, max_iter, batch)
    start = None
    if batch == ():
        result, start = _one_pose(nearest, exact_solutions, X_06[0], X_0T[0], X_6T,
                                  None if references is None else references[0], plain, tol,
                                  singular_tol, max_iter, wide, near_limit)
        if result is not None:
            return result
    within = _within(nearest, X_06)
    if not within.any():                                # none of them in reach: the exact
        start = exact_solutions(X_06, checked=plain)    # arm's errors, flag and reason
        return _unsolved(nearest, X_6T, X_0T, start.position_error, start.rotation_error,
                         start.flags["near_singular"], start.reason, tol, max_iter, batch)
    compiled = pose_tol <= RIGID_TOL and compiled_ready() and within.all()
    if n <= _PER_POSE and compiled:
        # (the targets are checked at least as strictly as the closed form checks them)
        done = compiled_array_poses(
            nearest.links, X_6T, nearest.exact, X_06, X_0T, X_T6,
            np.zeros(n) if references is None else references[:, 5], tol, wide,
            singular_tol, NEAR_WRIST, near_limit, max_iter, polish_near=_POLISH_NEAR,
            **_REPAIR_STEPS)
        if done is not None:                            # (None: a wrist far beyond reach)
            solutions, valid, pe, re, flags, ended, started, repeated = done
            return _compiled_result(nearest, X_6T, solutions, valid, pe, re, flags, ended,
                                    started, None, repeated, X_0T, tol, max_iter, batch)
    if start is None and compiled:
        result = _compiled_poses(nearest, exact_solutions, X_06, X_0T, X_6T, X_T6, references,
                                 tol, wide, singular_tol, near_limit, max_iter, batch)
        if result is not None:                          # (None: a wrist far beyond reach)
            return result
    if start is None:
        start = exact_solutions(X_06, checked=plain)
        start.solutions = _off_the_edge(nearest.robot, start.solutions, start.valid,
                                        start.position_error, tol)
    q0 = start.solutions.reshape(n * 8, 6).copy()
    errors = start.position_error.reshape(n * 8)
    found = start.valid.reshape(n * 8)                 # the branches the exact arm found
    exact = found & (errors <= tol)                     # ... of them, its exact solutions
    near = ~found & (errors <= 10.0 * wide)             # those it misses by a little more
    started = found.copy()
    if near.any():                                      # (as near a wrist singularity)
        poses = np.flatnonzero(near.reshape(n, 8).any(axis=1))
        again = exact_solutions(X_06[poses], poses, tol=10.0 * wide)
        rows = (8 * poses[:, None] + np.arange(8)).reshape(-1)
        use = near[rows] & again.valid.reshape(-1)
        again.solutions = _off_the_edge(nearest.robot, again.solutions, again.valid,
                                        again.position_error, tol)
        q0[rows[use]] = again.solutions.reshape(-1, 6)[use]
        started[rows[use]] = True
    chain = (nearest.links, X_6T)
    polished = _Polished.empty(n)
    # the branches the exact arm misses go last: they seldom converge, and each group of
    # eight branches that the compiled steps take together runs as long as its slowest
    extra = np.flatnonzero(started & ~found)
    rows = np.concatenate([np.flatnonzero(found), extra])
    polished.record(rows, *_newton(*chain, q0[rows], X_0T[rows // 8], tol, max_iter))
    polished.converged[extra] &= polished.are_new(extra, polished.q[extra],   # keep them
                                                  polished.unique() & found)  # if new
    _repairs(chain, nearest, polished, q0, found, exact_solutions, X_06, X_0T, X_T6, tol,
             max_iter, (references, wide, singular_tol, near_limit))
    done = np.flatnonzero(polished.done)
    pe = start.position_error.reshape(n * 8).copy()
    re = start.rotation_error.reshape(n * 8).copy()
    pe[done], re[done] = polished.errors[:, done]
    valid = polished.converged & (pe <= tol) & (re <= tol)
    solutions = wrap_angle(polished.q)
    near = _nearness(nearest, solutions, valid)
    solutions = _polish(nearest, X_6T, solutions, valid, pe, re, X_0T, tol, near)
    repeated = _repeated(solutions, valid)
    valid &= ~repeated
    near[repeated] = np.inf
    flags = _flags(polished.measures, valid, singular_tol, nearest.robot.links[3].d,
                   near_limit)
    flags["near_singular"] |= start.flags["near_singular"].reshape(n)   # the exact arm's,
    flags["near_singular"] |= (near < near_limit).reshape(n, 8).any(axis=1)  # at its rows
    flags["not_converged"] = (exact & ~valid).reshape(n, 8).any(axis=1)
    started = start.valid.reshape(n, 8).any(axis=1)
    reason = np.where(started, REASON_NOT_CONVERGED, start.reason.reshape(n))
    return _poses_result(nearest, X_6T, solutions, valid, pe, re, flags, reason, X_0T, tol,
                         max_iter, batch, near, repeated)


def _within(nearest, X_06):
    r"""Which flanges of ``X_06`` (n, 4, 4) lie within :data:`_FAR` reaches of the exact
    arm's shoulder (its reach :math:`\sqrt{d_4^2 + (|a_2| + |a_3| + |d_5|)^2}`, and d1 and
    d6 more), (n,). Beyond, no arm near it reaches them, and the compiled array paths would
    hand them on to the numpy path (a wrist centre far beyond reach is solved for a stand-in
    there): a batch with one goes to it at once, without compiling them, and one with
    nothing else is answered by the exact arm's closed form (:func:`_unsolved`)."""
    d1, a2, a3, d4, d5, d6 = np.abs(nearest.exact[:6])
    reach = math.hypot(d4, a2 + a3 + d5) + d1 + d6
    return np.abs(X_06[:, :3, 3]).sum(axis=-1) <= _FAR * reach


def _unsolved(nearest, tool, X_0T, pe, re, near_singular, reason, tol, max_iter, batch):
    """The result of poses with no valid row and nothing to start from: an empty batch, or
    poses none of which is within :data:`_FAR` reaches (:func:`_within`), given the exact
    arm's errors ``pe``, ``re`` (n, 8), near_singular flags and reasons (n,) (the numpy
    path's result for them, without its Newton steps and restarts, which start from no
    branch)."""
    n = X_0T.shape[0]
    flags = {name: np.zeros(n, dtype=bool) for name in _FLAG_NAMES}
    flags["unreachable"][:] = True
    flags["near_singular"] = np.array(near_singular, dtype=bool).reshape(n)
    return _poses_result(nearest, tool, np.zeros((8 * n, 6)), np.zeros(8 * n, dtype=bool),
                         pe.reshape(-1), re.reshape(-1), flags, reason.reshape(n), X_0T, tol,
                         max_iter, batch)


def _compiled_poses(nearest, exact_solutions, X_06, X_0T, X_6T, X_T6, references, tol, wide,
                    singular_tol, near_limit, max_iter, batch):
    """The array path of :func:`calibrated_ur` for a batch, with numba: steps 2 and 3 pose by
    pose in compiled code (``dqlab._fast.newton_compiled.array_start``), the repairs of
    steps 4 (:func:`_repairs`), step 5 and the flags pose by pose
    (``dqlab._fast.newton_compiled.array_finish``), then step 6. Tested equal to the numpy
    path. None when a wrist centre is far beyond reach (the numpy path's closed form solves
    it for a stand-in)."""
    n = X_0T.shape[0]
    begun = compiled_array_start(nearest.links, X_6T, nearest.exact, X_06, X_0T,
                                 np.zeros(n) if references is None else references[:, 5], tol,
                                 wide, singular_tol, NEAR_WRIST, near_limit, max_iter,
                                 **_NEWTON_STEPS)
    if begun is None:
        return None
    q, done, converged, X, measures, errors, q0, found, start_errors, start_near, ended, \
        started = begun
    polished = _Polished(q, done, converged, X, measures, errors)
    _repairs((nearest.links, X_6T), nearest, polished, q0, found, exact_solutions, X_06, X_0T,
             X_T6, tol, max_iter, (references, wide, singular_tol, near_limit))
    solutions, valid, pe, re, flags, near, repeated = compiled_array_finish(
        nearest.links, X_6T, nearest.exact, X_0T, tol, singular_tol, near_limit, q, done,
        converged, measures, errors, found, start_errors, start_near,
        polish_near=_POLISH_NEAR, **_NEWTON_STEPS)
    return _compiled_result(nearest, X_6T, solutions, valid, pe, re, flags, ended, started,
                            near, repeated, X_0T, tol, max_iter, batch)


def _compiled_result(nearest, tool, solutions, valid, pe, re, flags, ended, started, near,
                     repeated, X_0T, tol, max_iter, batch):
    """:func:`_poses_result` of the compiled array paths' arrays, pose by pose: the
    solutions (n, 8, 6), ``valid``, errors and ``repeated`` (n, 8), the flags (n, 6) in the
    order of :data:`_FLAG_NAMES`, how each pose's closed form ended and whether it started
    (n,) (the reason of a pose with no valid row), ``near`` (8 n,) or None."""
    reason = np.where(started, REASON_NOT_CONVERGED, _REASON_OF[ended])
    return _poses_result(nearest, tool, solutions.reshape(-1, 6), valid.reshape(-1),
                         pe.reshape(-1), re.reshape(-1),
                         dict(zip(_FLAG_NAMES, flags.T, strict=True)), reason, X_0T, tol,
                         max_iter, batch, near, repeated.reshape(-1))


def _poses_result(nearest, tool, solutions, valid, pe, re, flags, reason, X_0T, tol, max_iter,
                  batch, near=None, repeated=None):
    """The :class:`IKResult` of the array path: the rows (8 n, 6), their validity and errors
    (8 n,), the flags (n,) each (not_converged also where a pose's solutions are odd in
    number, :func:`_odd_count`), the reason (n,) a pose would have without a valid row, and
    the solutions beyond the rows (:func:`_beyond`; ``near`` the rows' :func:`_nearness`
    where known, ``repeated`` the rows made invalid as repeats), shaped for the targets
    ``batch``."""
    reason = np.where(valid.reshape(-1, 8).any(axis=1), "", reason).astype(object)
    more = _beyond(nearest, tool, solutions, valid, X_0T, tol, max_iter, near, repeated)
    flags["not_converged"] = flags["not_converged"] | _odd_count(valid.reshape(-1, 8), more[1])
    return finish(solutions.reshape(batch + (8, 6)), valid.reshape(batch + (8,)),
                  pe.reshape(batch + (8,)), re.reshape(batch + (8,)),
                  {name: f.reshape(batch) for name, f in flags.items()},
                  reason.reshape(batch), more=_more_result(*more, batch))


def _closed_form(nearest, X_06, *, tol, q_ref=None, singular_tol=5e-7,
                 near_tol=NEAR_SINGULAR):
    """``dqlab.ik.ur`` of the exact arm ``nearest.robot`` for the flange poses ``X_06``, its
    tolerances checked already: the engine's :func:`~dqlab._fast.ur_engine.solve` with ``ur``'s
    defaults (``pose_tol`` :data:`~dqlab.ik.targets.RIGID_TOL`, no tool, the residuals of
    the solved equations)."""
    return exact_engine.solve(nearest.robot, nearest.parameters, X_06, tol, singular_tol, RIGID_TOL,
                       None, q_ref, "equations", near_tol)


def _solver_of_robot(closed_form):
    """A ``closed_form(robot, X, **options)`` given to :func:`calibrated_ur`, called as
    :func:`_closed_form` is, with the :class:`_NearestExact`."""
    def solver(nearest, X_06, **options):
        return closed_form(nearest.robot, X_06, **options)
    return solver


def _references(q_ref, batch):
    """``q_ref`` (checked) as one reference per pose, (n, 6) for the n poses of leading
    shape ``batch``, or None."""
    if q_ref is None:
        return None
    q_ref = as_float_array(q_ref, "q_ref", (6,))
    try:
        return np.broadcast_to(q_ref, batch + (6,)).reshape(-1, 6)
    except ValueError:
        raise ValueError(f"q_ref of shape {q_ref.shape} does not broadcast against the "
                         f"poses' leading shape {batch}") from None


def _off_the_edge(exact, solutions, valid, errors, tol):
    r"""The exact arm's rows ``solutions`` (..., 8, 6), those that reach their pose only by
    clipping the elbow (the wrist-1 point beyond the forearm's reach: :math:`\theta_3 = 0`
    or :math:`\pi`, where the Jacobian is singular) moved off the elbow singularity to their
    own elbow's side: :math:`\theta_3` by :math:`\pm\delta`, :math:`\delta =
    \sqrt{2 R e / |a_2 a_3|}` (at least 0.01 rad), the bend at which the arm of reach
    :math:`R = |a_2 + a_3|` is shorter by the row's error :math:`e`. Newton on the
    calibrated arm, which may reach where the exact arm does not, starts there instead of
    at a singularity. ``solutions`` itself when no row moves, else a copy."""
    clipped = np.flatnonzero((valid & (errors > tol)).reshape(-1))
    if not clipped.size:
        return solutions
    rows = solutions.reshape(-1, 6)[clipped]
    theta3 = rows[:, 2] + exact.links[2].theta_offset
    edge = np.abs(np.sin(theta3)) < 1e-6
    if not edge.any():
        return solutions
    clipped, theta3 = clipped[edge], theta3[edge]
    a2, a3 = exact.links[1].a, exact.links[2].a
    delta = np.maximum(np.sqrt(2.0 * abs(a2 + a3) * errors.reshape(-1)[clipped]
                               / abs(a2 * a3)), 0.01)
    up = np.where(clipped // 2 % 2 == 0, 1.0, -1.0)     # row 4 s + 2 e + w: elbow e up
    moved = np.array(solutions, dtype=float, order="C").reshape(-1, 6)          # a copy
    moved[clipped, 2] += up * np.sign(np.cos(theta3)) * np.sign(a2 * a3) * delta
    return moved.reshape(solutions.shape)


def _plain_pose(target, pose_tol):
    """Whether ``target`` is one rigid transform, a (4, 4) float array that passes
    :func:`~dqlab.ik.targets.parse_targets`'s check at the default tolerance (checked on
    floats, as the closed form's one-pose path checks it); anything else is parsed."""
    return (type(target) is np.ndarray and target.shape == (4, 4)
            and target.dtype == np.float64 and pose_tol <= RIGID_TOL
            and rigid_rows(target, pose_tol) is not None)


def _exact_one_pose(nearest, X_06, q_ref, tol, singular_tol, near_tol, checked=False):
    """The exact arm's closed form of one flange pose ``X_06`` (4, 4) with the tolerance
    ``tol`` and the reference ``q_ref`` (6,) or None, compiled
    (``dqlab._fast.newton_compiled.exact_one_pose``): the :class:`IKResult` the closed form
    gives (at its default ``pose_tol``), or None where the pose is not a rigid transform to
    that tolerance (checked unless ``checked``) or its wrist centre is far beyond reach (the
    closed form then solves it, or gives the error)."""
    if checked:                                         # the flange: rotation quaternion,
        a, b, c = X_06[:3].tolist()                     # position, z6
    else:
        rows = rigid_rows(X_06, RIGID_TOL)              # (the closed form's check)
        if rows is None:
            return None
        a, b, c = rows
    q = quaternion_from_matrix_entries(a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2])
    done = compiled_exact_one_pose((q, (a[3], b[3], c[3]), (a[2], b[2], c[2])), X_06,
                                   0.0 if q_ref is None else q_ref[5], nearest.exact, tol,
                                   singular_tol, NEAR_WRIST, near_tol)
    if done is None:
        return None
    solutions, valid, pe, re, flags, ended = done
    flags = dict(zip(_FLAG_NAMES[:4], flags, strict=True))   # wrist, shoulder, elbow, near
    flags["unreachable"] = np.bool_(ended != SOLVED)
    flags["not_converged"] = np.bool_(False)
    return IKResult(solutions, valid, pe, re, flags, np.array(_REASON_OF[ended], dtype=object))


def _exact_poses(nearest, X_06, q_ref, tol, singular_tol, near_tol, closed_form):
    """The exact arm's closed form of the flange poses ``X_06`` (n, 4, 4) (rigid transforms,
    checked) with the tolerance ``tol`` and the references ``q_ref`` (n, 6) or None,
    compiled pose by pose (``dqlab._fast.newton_compiled.exact_poses``, the loop of
    :func:`_exact_one_pose`); the poses that path hands on (a wrist centre far beyond
    reach) are solved by ``closed_form`` itself.
    The :class:`IKResult` ``closed_form`` gives for them all (tested equal)."""
    R = X_06[:, :3, :3]
    q = quaternion_from_matrix_entries(*(R[:, i, j] for i in range(3) for j in range(3)))
    theta6 = np.zeros(X_06.shape[0]) if q_ref is None else q_ref[:, 5]
    solutions, valid, errors, rotation_errors, flags, ended = compiled_exact_poses(
        np.stack(q, axis=-1), X_06[:, :3, 3], X_06[:, :3, 2], X_06, theta6, nearest.exact,
        tol, singular_tol, NEAR_WRIST, near_tol)
    flags = dict(zip(_FLAG_NAMES[:4], flags.T, strict=True))   # wrist, shoulder, elbow, near
    flags["unreachable"] = ended != SOLVED
    flags["not_converged"] = np.zeros(ended.shape, dtype=bool)
    reason = _REASON_OF[ended]
    rest = np.flatnonzero(ended == 0)
    if rest.size:
        other = closed_form(nearest, X_06[rest], tol=tol, singular_tol=singular_tol,
                            near_tol=near_tol, q_ref=None if q_ref is None else q_ref[rest])
        solutions[rest], valid[rest] = other.solutions, other.valid
        errors[rest], rotation_errors[rest] = other.position_error, other.rotation_error
        for name, flag in flags.items():
            flag[rest] = other.flags[name]
        reason[rest] = other.reason
    return IKResult(solutions, valid, errors, rotation_errors, flags, reason)


def _one_pose(nearest, exact_solutions, X_06, X_0T, tool, q_ref, checked, tol, singular_tol,
              max_iter, wide, near):
    """The result of :func:`calibrated_ur` for one pose (``X_06``, ``X_0T`` (4, 4) its
    flange and target in frame 0, ``q_ref`` its reference or None, ``exact_solutions`` the
    exact arm's closed form) with a few numpy calls, when Newton from the exact arm's
    branches is all it takes: every branch the exact arm found converges, to distinct
    solutions, none is missed by a little, and the pose does not seek missing branches from
    the wrist family (:func:`_family_members`; four poses in five). Returns the result, or
    None and the pose takes the array path, which this is tested equal to; and the exact
    arm's :class:`IKResult` of the pose (its rows clipped at the elbow moved off it,
    :func:`_off_the_edge`) where it was computed, else None. With numba, all of it but the
    polish and the search beyond the rows is one compiled call
    (``dqlab._fast.newton_compiled.one_pose``), the flange known rigid (``checked``, else
    checked here as the closed form checks it)."""
    d4 = nearest.robot.links[3].d
    if compiled_ready() and (checked or rigid_rows(X_06, RIGID_TOL) is not None):
        done = compiled_one_pose(nearest.links, tool, nearest.exact, X_06, X_0T,
                                 0.0 if q_ref is None else q_ref[5], tol, wide, singular_tol,
                                 NEAR_WRIST, near, max_iter, polish_near=_POLISH_NEAR,
                                 family=_FAMILY_NUMBERS[:4], **_NEWTON_STEPS)
        if done is None:
            return None, None
        ended, solutions, valid, pe, re, flags, start_near, exact = done
        flags = dict(zip(_FLAG_NAMES, flags.tolist(), strict=True))
        if ended == 1:                                  # (no row near a singularity)
            return _one_pose_result(solutions, valid, pe, re, flags, None), None
        return _near_a_singularity(nearest, tool, solutions, valid, pe, re, flags, start_near,
                                   exact, X_0T, tol, max_iter, near), None
    start = exact_solutions(X_06[None], checked=checked)
    start.solutions = _off_the_edge(nearest.robot, start.solutions, start.valid,
                                    start.position_error, tol)
    found, pe, re = start.valid, start.position_error, start.rotation_error
    if (~found & (pe <= 10.0 * wide)).any() or not found.any():
        return None, start
    rows = np.flatnonzero(found)
    q, converged, _, measures, errors = _newton(nearest.links, tool, start.solutions[rows],
                                                np.broadcast_to(X_0T, (rows.size, 4, 4)),
                                                tol, max_iter)
    Q, M = np.zeros((8, 6)), np.zeros((3, 8))
    Q[rows], M[:, rows] = q, measures
    if not converged.all() or (found & ~_unique(Q, found)).any():   # a restart: _repair
        return None, start
    exact = found & (pe <= tol)
    pe, re = pe.copy(), re.copy()
    pe[rows], re[rows] = errors
    valid = found & (pe <= tol) & (re <= tol)
    solutions = wrap_angle(Q)
    flags = _flags(M, valid, singular_tol, d4, near)
    flags["not_converged"] = (exact & ~valid).any()
    if not found.all() and _family_members(nearest, solutions, found, found)[0]:
        return None, start                              # (found: all converged)
    return _near_a_singularity(nearest, tool, solutions, valid, pe, re, flags,
                               start.flags["near_singular"], exact, X_0T, tol, max_iter,
                               near), start


def _near_a_singularity(nearest, tool, solutions, valid, pe, re, flags, start_near, exact,
                        X_0T, tol, max_iter, near):
    """The end of :func:`_one_pose`: a pose with no valid row near a singularity of the
    exact arm (most) has none to polish, none near at a lower threshold, and no solutions
    beyond its rows; the others are polished (:func:`_polish`), lose a row the polish
    brought to another's solution (:func:`_repeated`; not_converged if it was one of the
    ``exact`` arm's solutions) and are searched beyond (:func:`_beyond`). The near_singular
    flag also counts the exact arm's measures at the valid rows and its own
    (``start_near``)."""
    nearness = _nearness(nearest, solutions, valid)
    polish = (nearness < _POLISH_NEAR).any()
    if polish:
        solutions = _polish(nearest, tool, solutions, valid, pe, re, X_0T, tol, nearness)
        repeated = _repeated(solutions, valid)
        if repeated.any():
            valid = valid & ~repeated
            nearness[repeated] = np.inf
            flags["not_converged"] = bool(flags["not_converged"] or (exact & repeated).any())
    else:
        repeated = None
    flags["near_singular"] = bool(flags["near_singular"] or start_near
                                  or (nearness < near).any())
    more = _beyond(nearest, tool, solutions, valid, X_0T[None], tol, max_iter, nearness,
                   repeated) if polish else None
    return _one_pose_result(solutions, valid, pe, re, flags, more)


def _one_pose_result(solutions, valid, pe, re, flags, more):
    """The :class:`IKResult` of one pose: its flags as 0-d arrays (not_converged also where
    its solutions are odd in number, :func:`_odd_count`), its reason, and ``more``
    (:func:`_beyond`'s arrays, or None: no solution beyond the rows)."""
    if more is None:
        more = (np.zeros((1, _MORE, 6)), np.zeros((1, _MORE), dtype=bool),
                np.zeros((1, _MORE)), np.zeros((1, _MORE)))
    flags["not_converged"] = bool(flags["not_converged"]) or bool(_odd_count(valid, more[1][0]))
    flags = {name: np.array(bool(flag)) for name, flag in flags.items()}
    return finish(solutions, valid, pe, re, flags,
                  np.array(REASON_NOT_CONVERGED if flags["unreachable"] else "", dtype=object),
                  more=_more_result(*more, ()))


def _polish(nearest, tool, solutions, valid, pe, re, X_0T, tol, near):
    r"""The valid rows ``solutions`` (m, 6) (wrapped) near a singularity of the exact arm
    (their :func:`_nearness` ``near`` (m,) below :data:`_POLISH_NEAR`) taken
    ``_PLAIN_STEPS`` Newton steps further towards their targets ``X_0T``.

    A row stops once its errors are below a tenth of ``tol``; near a singularity, where
    the smallest singular value :math:`\sigma` of :math:`J` is small, that leaves the
    joints :math:`10^{-10}/\sigma` from the solution (1e-5 rad at :math:`\sigma \approx
    10^{-5}`), and a solution that a singularity nearly pairs with another is not told
    apart from it. The steps further bring such a row to the solution (quadratic
    convergence). The errors ``pe``, ``re`` and the nearness ``near`` (m,) of a row polished
    are updated in place; returns the solutions, wrapped (``solutions`` itself if no row
    moves). ``X_0T`` holds the targets of the poses whose rows are ``solutions``, eight
    each."""
    rows = np.flatnonzero(near < _POLISH_NEAR)
    if not rows.size:
        return solutions
    q, _, _, _, errors = _newton(nearest.links, tool, solutions[rows],
                                 X_0T.reshape(-1, 4, 4)[rows // 8], tol, _PLAIN_STEPS)
    better = (errors <= tol).all(axis=0) & np.isfinite(q).all(axis=1)
    rows, q = rows[better], q[better]
    solutions = solutions.copy()
    solutions[rows] = wrap_angle(q)
    pe[rows], re[rows] = errors[:, better]
    near[rows] = _nearness(nearest, solutions[rows], valid[rows])
    return solutions


def _beyond(nearest, tool, solutions, valid, X_0T, tol, max_iter, near=None, repeated=None):
    r"""The solutions of each pose beyond its eight rows (``result.more``).

    Within about the two arms' gap of a singularity of the exact arm, the calibrated arm
    may reach a pose in ten or twelve joint vectors, not eight (a general 6R arm has up to
    16): where the exact arm has two branches meeting, the calibrated one may have two
    solutions on either side. A pose whose eight rows ``solutions`` (8 n, 6), wrapped, are
    all ``valid`` (8 n,) or ``repeated`` (invalid as another row's solution: the pose
    misses one), and one of them within :data:`_POLISH_NEAR` of a singularity of the exact
    arm (its :func:`_nearness`, ``near`` (8 n,) where known) and near singular on the
    calibrated arm (:func:`_near_singular`), seeks more: deflated Newton
    (:func:`_deflated_newton`, the pose's eight rows deflated) from that row moved by
    :data:`_MORE_WAYS` along its most singular direction, then Newton (whose first steps,
    taken by every start, polish the joints as :func:`_polish` does). A solution valid to
    ``tol`` and not one of the pose's rows nor of the ones found before it
    (:func:`_one_of`) fills the pose's next row of ``more``. Returns the solutions
    (n, 8, 6), their validity (n, 8) and their position and rotation errors (n, 8) each."""
    n = valid.size // 8
    Q, V = np.zeros((n, _MORE, 6)), np.zeros((n, _MORE), dtype=bool)
    PE, RE = np.zeros((n, _MORE)), np.zeros((n, _MORE))
    covered = valid if repeated is None else valid | repeated
    if n == 1:                                          # (one pose: fewer calls)
        if not covered.all():
            return Q, V, PE, RE
        full = valid
    else:
        full = valid & np.repeat(covered.reshape(n, 8).all(axis=1), 8)
        if not full.any():
            return Q, V, PE, RE
    if near is None:
        near = _nearness(nearest, solutions, valid)
    rows = np.flatnonzero(full & (near < _POLISH_NEAR))
    if not rows.size:
        return Q, V, PE, RE
    singular, direction = _near_singular(nearest, tool, solutions[rows])
    rows = rows[singular]
    if not rows.size:
        return Q, V, PE, RE
    ways = _MORE_WAYS
    starts = (solutions[rows, None] + ways[:, None] * direction[:, None]).reshape(-1, 6)
    pose_of = np.repeat(rows // 8, ways.size)
    known = solutions.reshape(n, 8, 6)[pose_of]
    chain = (nearest.links, tool)
    q = _deflated_newton(chain, starts, X_0T[pose_of], known, tol,
                         min(max_iter, _DEFLATION_ITER))
    q, converged, _, _, errors = _newton(*chain, q, X_0T[pose_of], tol, max_iter)
    q = wrap_angle(q)
    with np.errstate(invalid="ignore"):                 # (a first screen: every start that
        new = converged & (errors <= tol).all(axis=0)   # reached the pose, against its rows)
    reached = np.flatnonzero(new)
    new[reached] = _are_new(8 * pose_of[reached], q[reached], solutions,
                            np.ones(valid.size, dtype=bool))
    count = np.zeros(n, dtype=np.int64)
    rows_of = solutions.reshape(n, 8, 6)
    for j in np.flatnonzero(new):                       # a few: each against those before
        i, m = pose_of[j], count[pose_of[j]]
        if m == _MORE or _one_of(chain, q[j], np.concatenate([rows_of[i], Q[i, :m]]),
                                 X_0T[i], tol):
            continue
        Q[i, m], V[i, m], (PE[i, m], RE[i, m]) = q[j], True, errors[:, j]
        count[i] += 1
    return Q, V, PE, RE


def _one_of(chain, q, known, X_target, tol):
    """Whether the joint vector q (6,), a solution of the pose ``X_target`` (4, 4) in frame
    0, is one of the solutions ``known`` (m, 6): within 1e-6 rad of one, or within 0.1 rad
    of one and their midpoint reaching the pose to ``tol`` too. (Where two solutions meet at
    a singularity of the calibrated arm, the pose error is flat along the direction that
    joins them, and Newton stops anywhere along it within ``tol``: rows 1e-4 rad apart,
    one solution. Two solutions that a singularity separates, 0.05 rad or more apart,
    miss the pose by far more than ``tol`` half way.)"""
    gap = np.abs(wrap_angle(known - q)).max(axis=-1)
    if (gap < 1e-6).any():
        return True
    close = np.flatnonzero(gap < 0.1)
    if not close.size:
        return False
    kernel = _newton_kernel(*chain, close.size)
    X = kernel.transforms(kernel.frames(q + 0.5 * wrap_angle(known[close] - q)))
    position, rotation = pose_errors(X, np.broadcast_to(X_target, X.shape))
    return bool(((position <= tol) & (rotation <= tol)).any())


def _nearness(nearest, solutions, valid):
    """How near a singularity of the exact arm each ``valid`` (m,) row of ``solutions``
    (m, 6) is (:func:`_exact_nearness`; infinite where not valid); with numba, compiled
    (``dqlab._fast.newton_compiled.nearness``, tested equal)."""
    if compiled_ready():
        return compiled_nearness(solutions, valid, nearest.exact)
    return np.where(valid, _exact_nearness(nearest.robot, solutions), np.inf)


def _exact_fk(nearest, q):
    """Forward kinematics of the exact arm of ``nearest`` at the joint vectors q (m, 6):
    ``Robot.fk``; with numba, compiled (``dqlab._fast.newton_compiled.exact_fk``, tested
    equal)."""
    if compiled_ready():
        return compiled_exact_fk(q, nearest.exact)
    return nearest.robot.fk(q)


def _more_result(solutions, valid, pe, re, batch):
    """The :class:`IKResult` of :func:`_beyond`'s arrays, shaped for the targets ``batch``
    (its rows that are not valid hold zeros already, as :func:`finish` makes them)."""
    return IKResult(solutions.reshape(batch + (_MORE, 6)), valid.reshape(batch + (_MORE,)),
                    pe.reshape(batch + (_MORE,)), re.reshape(batch + (_MORE,)), {})


def _repeated(solutions, valid):
    """The valid rows of ``solutions`` (8 n, 6) that repeat a valid row of lower number of
    their pose (joint-wise within 1e-6 rad, :func:`_unique`): near a singularity the polish,
    or a branch that converged to another's solution which the repairs could not replace,
    may leave two rows on one solution; the later is not a solution of its own branch.
    With numba, compiled (``dqlab._fast.newton_compiled.unique``)."""
    if compiled_ready():
        return valid & ~compiled_unique(solutions, valid)
    return valid & ~_unique(solutions, valid)


def _odd_count(valid, more_valid):
    r"""Whether a pose has an odd number of solutions: its valid rows ``valid`` (..., 8) and
    the solutions beyond them ``more_valid`` (..., 8), (...). A general 6R arm, as a
    calibrated UR is, reaches a pose in an even number of joint vectors: they are the real
    roots of a polynomial of degree 16 whose other roots come in complex pairs, and two
    real ones meet and vanish together at a singularity (Raghavan and Roth, *Inverse
    kinematics of the general 6R manipulator and related linkages*, J. Mech. Des. 115,
    1993). An odd count means a solution is missing: such a pose is flagged
    ``"not_converged"``."""
    return (valid.sum(axis=-1) + more_valid.sum(axis=-1)) % 2 == 1


def _exact_nearness(exact, q):
    r"""How near a singularity of the exact arm the joint vectors q (m, 6) are: the least of
    its measures of :func:`~dqlab.ik.ur_closed_form.branch_measures`,
    :math:`|\sin\theta_3|`, :math:`|\sin\theta_5|` and :math:`|h| / |a_2|`."""
    h, sin_theta3, sin_theta5 = branch_measures(exact, q)
    return np.minimum(np.minimum(np.abs(sin_theta3), np.abs(sin_theta5)),
                      np.abs(h) / abs(exact.links[1].a))


@dataclass
class _Polished:
    """The branches of n poses after Newton, row ``8 i + k`` for branch k of pose i: joint
    vectors ``q`` (8 n, 6), which rows were polished (``done``) and converged, the TCP pose
    ``X`` (8 n, 4, 4) in frame 0, the singularity measures (3, 8 n) at ``q`` and the
    position and rotation errors (2, 8 n) from the target (:func:`pose_errors`)."""

    q: np.ndarray
    done: np.ndarray
    converged: np.ndarray
    X: np.ndarray
    measures: np.ndarray
    errors: np.ndarray

    @classmethod
    def empty(cls, n):
        return cls(np.zeros((8 * n, 6)), np.zeros(8 * n, dtype=bool),
                   np.zeros(8 * n, dtype=bool), np.zeros((8 * n, 4, 4)), np.zeros((3, 8 * n)),
                   np.zeros((2, 8 * n)))

    def record(self, rows, q, converged, X, measures, errors):
        self.q[rows], self.converged[rows], self.X[rows] = q, converged, X
        self.measures[:, rows], self.errors[:, rows] = measures, errors
        self.done[rows] = True

    def unique(self):
        """Converged rows that do not repeat a converged row of lower number of their pose
        (joint-wise within 1e-6 rad, modulo 2 pi). The 28 pairs of rows of a pose are
        compared on joints 1, 3 and 5 first (the shoulder, elbow and wrist tell the branches
        apart), and on all six joints where those agree."""
        if compiled_ready():
            return compiled_unique(self.q, self.converged)
        return _unique(self.q, self.converged)

    def are_new(self, rows, q, unique):
        """Whether each joint vector ``q[j]`` differs from every unique row of the pose of
        ``rows[j]`` (:func:`_are_new`)."""
        return _are_new(rows, q, self.q, unique)

    def is_new(self, row, q, unique):
        """Whether the joint vector ``q`` (6,) differs from every unique row of the pose of
        ``row``."""
        return bool(self.are_new(np.array([row]), q[None], unique)[0])


def _are_new(rows, q, known, unique):
    """Whether each joint vector ``q[j]`` (m, 6) differs (some joint by 1e-6 rad or more,
    modulo 2 pi) from every row of ``known`` (8 n, 6) marked ``unique`` (8 n,) of the pose
    of row ``rows[j]``, (m,); with numba, compiled
    (``dqlab._fast.newton_compiled.are_new``, tested equal)."""
    if compiled_ready():
        return compiled_are_new(rows, q, known, unique)
    Q = np.where(unique[:, None], known, np.nan).reshape(-1, 8, 6)[rows // 8]
    with np.errstate(invalid="ignore"):
        same = np.abs(wrap_angle(Q - q[:, None])).max(axis=-1) < 1e-6
    return ~same.any(axis=-1)


def _unique(q, converged):
    """``_Polished.unique`` of the joint vectors q (8 n, 6) and their ``converged`` (8 n,)."""
    Q, C = q.reshape(-1, 8, 6), converged.reshape(-1, 8)
    earlier, later = _PAIRS
    with np.errstate(invalid="ignore"):
        coarse = np.abs(wrap_angle(Q[:, earlier][..., _COARSE]
                                   - Q[:, later][..., _COARSE])).max(axis=-1) < 1e-6
        pose, pair = np.nonzero(coarse & C[:, earlier] & C[:, later])
        same = np.abs(wrap_angle(Q[pose, earlier[pair]]
                                 - Q[pose, later[pair]])).max(axis=-1) < 1e-6
    repeats = np.zeros(converged.size, dtype=bool)
    repeats[8 * pose[same] + later[pair[same]]] = True
    return converged & ~repeats


def _checked_tool(tool, pose_tol):
    """The tool transform asked for, checked as ``dqlab.ik.ur`` checks it."""
    dual_quaternion_from_transform(tool, tol=pose_tol, name="tool")
    tool = np.asarray(tool, dtype=float)
    if tool.shape != (4, 4):
        raise ValueError(f"tool must have shape (4, 4), got {tool.shape}")
    return tool


def _repairs(chain, nearest, polished, q0, found, exact_solutions, X_06, X_0T, X_T6, tol,
             max_iter, closed_form_options):
    """Steps 4 of the module: :func:`_repair`, :func:`_family` and :func:`_deflate` of the
    poses, ``polished`` updated in place; ``exact_solutions`` the exact arm's closed form
    of the poses, whose references, tolerance and singular and near tolerances are
    ``closed_form_options``. With numba, the three run compiled
    (``dqlab._fast.newton_compiled.repairs``, tested equal to them): step by step as here,
    each step's starts gathered pose by pose and stepped all together, without the numpy
    arrays of every row around the compiled kernels."""
    if not compiled_ready():
        _repair(chain, nearest, polished, q0, found, exact_solutions, X_0T, X_T6, tol,
                max_iter)
        _family(chain, nearest, polished, X_06, X_0T, exact_solutions, tol, max_iter)
        _deflate(chain, nearest, polished, X_0T, tol, max_iter)
        return
    references, wide, singular_tol, near_tol = closed_form_options
    n = X_0T.shape[0]
    compiled_repairs(nearest.links, chain[1], nearest.exact,
                     np.zeros(n) if references is None else references[:, 5], wide,
                     singular_tol, NEAR_WRIST, near_tol, polished.q, polished.done,
                     polished.converged, polished.X, polished.measures, polished.errors, q0,
                     found, X_0T, X_T6, X_06, tol, max_iter, **_REPAIR_STEPS)


def _repair(chain, nearest, polished, q0, found, exact_solutions, X_0T, X_T6, tol, max_iter):
    r"""Restart the branches missing from a pose: converged onto another branch's solution
    (near a singularity the exact arm's start may lie on the wrong side of the calibrated
    arm's), or not converged. Restarts, in turn:

    1. the exact arm's solutions of the pose corrected by the two arms' difference at a
       solution :math:`q^\ast` the pose already has,
       :math:`X' = X\, X_{cal}(q^\ast)^{-1} X_{exact}(q^\ast)`, which the exact arm reaches
       in :math:`q^\ast` exactly and, nearby, in the other branches;
    2. a sibling's solution flipped by the exact arm's elbow or wrist flip (:func:`_flip`);
       and, for a branch the exact arm ``found`` that repeats another or did not converge
       from a start near a singularity (from a regular start it has no solution nearby),
       its own start ``q0`` and the solutions of the other shoulder's branches, when near a
       singularity, moved along the calibrated arm's most singular direction there (by
       0.05, 0.2 and 0.6 rad either way): the two solutions a singularity separates lie on
       either side.

    The first restart that converges to a solution the pose does not have yet replaces the
    branch; ``polished`` is updated in place. A joint vector that several branches of a pose
    move (the same sibling's solution) is screened, and each of its moves stepped, once.
    With numba, this step runs compiled (:func:`_repairs`)."""
    unique = polished.unique()
    missing = polished.done & ~unique
    if not missing.any():
        return
    poses = np.flatnonzero(missing.reshape(-1, 8).any(axis=1)
                           & unique.reshape(-1, 8).any(axis=1))
    if poses.size:
        first = 8 * poses + np.argmax(unique.reshape(-1, 8)[poses], axis=1)
        X_cal6 = polished.X[first] @ X_T6               # the calibrated flange at q*
        X_exact6 = _exact_fk(nearest, polished.q[first])
        corrected = exact_solutions(X_0T[poses] @ X_T6 @ rigid_inverse(X_cal6)
                                    @ X_exact6, poses)
        rows = (8 * poses[:, None] + np.arange(8)).reshape(-1)
        use = missing[rows] & corrected.valid.reshape(-1)
        _restart(chain, polished, unique, rows[use], corrected.solutions.reshape(-1, 6)[use],
                 X_0T, tol, max_iter)
    wanted = np.flatnonzero(polished.done & ~unique)
    if not wanted.size:
        return
    bits = _FLIPS[:, None]                              # elbow, wrist, both (3, 1)
    sibling = wanted ^ bits                             # (3, w)
    ok = unique[sibling]
    _restart(chain, polished, unique, np.broadcast_to(wanted, sibling.shape)[ok],
             _flip(nearest, polished.q[sibling[ok]], np.broadcast_to(bits, ok.shape)[ok]),
             X_0T, tol, max_iter)
    wanted = wanted[~unique[wanted]]                    # still missing after the flips
    wanted = wanted[found[wanted]]
    if not wanted.size:
        return
    shoulder = [wanted ^ bits for bits in (4, 5, 6, 7)]  # the other shoulder's solutions
    known = np.unique(np.concatenate([s[unique[s]] for s in shoulder]))
    # the joint vectors to move, each once: the branches' own starts, then the solutions
    q = np.concatenate([q0[wanted], polished.q[known]])
    near, direction = _near_singular(nearest, chain[1], q)
    step = np.zeros_like(q)
    step[near] = direction
    keep = polished.converged[wanted] | near[:wanted.size]   # a branch that did not converge
    bases = [(wanted[keep], np.flatnonzero(keep))]     # only near a singularity (else: no
    for sibling in shoulder:                            # solution nearby); per base, the
        ok = keep & unique[sibling]                     # rows and their joint vectors in q
        bases.append((wanted[ok], wanted.size + np.searchsorted(known, sibling[ok])))
    owners, moves = [], []                              # base by base, each way in turn, the
    for rows, source in bases:                          # vectors near a singularity moved;
        moved = near[source]                            # a move: vector and way
        owners.append(np.tile(rows[moved], _WAYS.size))
        moves.append((_WAYS.size * source[moved] + np.arange(_WAYS.size)[:, None]).ravel())
    owners = np.concatenate(owners)
    if not owners.size:                                 # (none near a singularity: none)
        return
    moves, which = np.unique(np.concatenate(moves), return_inverse=True)   # each stepped once
    vector, way = np.divmod(moves, _WAYS.size)
    starts = q[vector] + _WAYS[way, None] * step[vector]
    _restart(chain, polished, unique, owners, starts, X_0T, tol, max_iter, which)


def _family(chain, nearest, polished, X_06, X_0T, exact_solutions, tol, max_iter):
    r"""Near the wrist singularity, seek the missing branches of a pose from the exact arm's
    wrist family.

    At :math:`\theta_5 = 0` (or :math:`\pi`) the exact arm reaches its pose along a family
    of joint vectors (:math:`\theta_4 + \theta_6` fixed); within about the two arms' gap of
    it, the calibrated arm's solutions of a shoulder and elbow lie near that family, some
    far along it from the exact arm's two branches (one pose has up to four such
    solutions, not two). A pose with a branch missing and a solution whose
    :math:`|\sin\theta_5|` is below :data:`_NEAR_MEASURE`, or with at most
    :data:`_FEW_BRANCHES` solutions none of which has :math:`|\sin\theta_5|` above
    :data:`_FEW_WRIST` (or none at all: within the gap of the wrist singularity the exact
    arm's closed form may miss a whole shoulder of the calibrated arm's, or every branch),
    takes :data:`_FAMILY` members of the family as starts; a pose with at most
    :data:`_FEW_BRANCHES` solutions elsewhere (a whole shoulder of the calibrated arm's that
    the exact arm's closed form clips, centimetres off) takes one (:func:`_family_members`),
    or the whole family where that one's start for a missing branch is at the wrist
    singularity (:math:`|\sin\theta_5|` below :data:`_NEAR_MEASURE`: the shoulder clipped is
    also within the gap of it, and its solution may lie anywhere along the family).
    A member is the exact arm's closed form with a tolerance of :data:`_FAMILY_TOL`, 0.5 (which
    makes every pose within :math:`|\theta_5| \lesssim 0.1` a family, and clipped rows
    valid) and references :math:`\theta_6 = -\pi + 2\pi j / 6` (the one member: 0,
    :func:`_members`). Each start is offered to
    the missing branches of its pose, the branch of its own label
    (:func:`_branches`) first (:func:`_restart`)."""
    unique = polished.unique()
    if unique.all():                                    # (no branch missing: no member)
        return
    missing = ~unique.reshape(-1, 8)
    count = _family_members(nearest, polished.q, polished.done, unique)
    poses = np.flatnonzero(count)
    if not poses.size:
        return
    count = count[poses]
    one = np.flatnonzero(count == 1)
    if one.size:                                        # its start at the wrist singularity:
        q, label, ok = _members(nearest, exact_solutions, X_06, poses[one],   # the family
                                np.zeros(one.size), tol)
        ok &= missing[np.repeat(poses[one], 8), label]
        wrist = ok & (_wrist_measure(nearest, q) < _NEAR_MEASURE)
        count[one[wrist.reshape(-1, 8).any(axis=1)]] = _FAMILY
    member_of = np.repeat(poses, count)                 # one entry per member
    j = np.arange(member_of.size) - np.repeat(np.cumsum(count) - count, count)
    family = np.repeat(count, count) > 1                # else one member, theta_6 from 0
    solutions, label, ok = _members(nearest, exact_solutions, X_06, member_of,
                                    np.where(family, -np.pi + 2.0 * np.pi / _FAMILY * j, 0.0),
                                    tol)
    pose_of = np.repeat(member_of, 8)
    ok &= missing[pose_of, label]                       # a start for a missing branch
    _offer(chain, polished, unique, missing, solutions[ok], pose_of[ok], label[ok], X_0T,
           tol, max_iter)


def _members(nearest, exact_solutions, X_06, member_of, theta6, tol):
    r"""Members of the exact arm's wrist family for :func:`_family`: its closed form of the
    flanges ``X_06[member_of]`` with the tolerance :data:`_FAMILY_TOL` and the references
    :math:`\theta_6` ``theta6`` (k,); the rows (8 k, 6), moved off the elbow singularity
    where they clip the elbow (:func:`_off_the_edge`), their branches (:func:`_branches`)
    and whether each is valid (8 k,)."""
    references = np.zeros((member_of.size, 6))
    references[:, 5] = theta6
    members = exact_solutions(X_06[member_of], tol=_FAMILY_TOL, near_tol=NEAR_SINGULAR,
                              ref=references)
    solutions = _off_the_edge(nearest.robot, members.solutions, members.valid,
                              members.position_error, tol).reshape(-1, 6)
    return solutions, _branches(nearest.robot, solutions), members.valid.reshape(-1)


def _family_members(nearest, q, done, have):
    r"""How many members of the exact arm's wrist family :func:`_family` gives each pose as
    starts, from its rows ``q`` (8 m, 6), the rows ``done`` (8 m,) that Newton ran from the
    exact arm's branches and the rows ``have`` (8 m,) holding distinct solutions: for a pose
    with a branch missing, :data:`_FAMILY` if a row done has :math:`|\sin\theta_5|` below
    :data:`_NEAR_MEASURE` or if it has at most :data:`_FEW_BRANCHES` solutions none of which
    has :math:`|\sin\theta_5|` above :data:`_FEW_WRIST`; one (the exact arm's rows, clipped
    ones included, :math:`\theta_6` from 0) if it has at most :data:`_FEW_BRANCHES` solutions
    otherwise; none else.
    (m,) integers; one pose alone (:func:`_one_pose`) asks too."""
    sin5 = _wrist_measure(nearest, q).reshape(-1, 8)
    have = have.reshape(-1, 8)
    missing = ~have.all(axis=1)
    wrist = (done.reshape(-1, 8) & (sin5 < _NEAR_MEASURE)).any(axis=1)
    few = have.sum(axis=1) <= _FEW_BRANCHES
    near_wrist = few & ~(have & (sin5 >= _FEW_WRIST)).any(axis=1)
    return np.where(missing & (wrist | near_wrist), _FAMILY, np.where(missing & few, 1, 0))


def _wrist_measure(nearest, q):
    r""":math:`|\sin\theta_5|` of the exact arm at the joint vectors q (m, 6), (m,)."""
    return np.abs(np.sin(q[:, 4] + nearest.robot.links[4].theta_offset))


def _offer(chain, polished, unique, missing, starts, pose_of, label, X_0T, tol, max_iter):
    """Newton from ``starts`` (m, 6), the start j for the pose ``pose_of[j]`` of label
    ``label[j]``, each offered to every branch ``missing`` (n, 8) of its pose, the branch
    of its label first (:func:`_restart`, which takes for a branch the first start that
    converges to a solution its pose does not have)."""
    k, which = np.nonzero(missing[pose_of].T)         # branch by branch, the starts in order
    if not k.size:
        return
    owners, rank = 8 * pose_of[which] + k, label[which] != k
    order = np.lexsort((which, rank))
    used, which = np.unique(which[order], return_inverse=True)   # each start stepped once
    _restart(chain, polished, unique, owners[order], starts[used], X_0T, tol, max_iter,
             which)


def _deflate(chain, nearest, polished, X_0T, tol, max_iter):
    r"""Seek the branches still missing from a pose by deflation: Newton steps that cannot
    end at a solution the pose already has.

    Within about the two arms' gap of a singularity (or of the edge of the reach) the
    calibrated arm's solutions do not follow the exact arm's branches one to one: two
    branches' starts may lead to one solution, and the other lies where no start of
    :func:`_repair` leads. For the residual :math:`e(q)` of the pose and its known solutions
    :math:`q_k`, the deflated residual :math:`m(q)\, e(q)` with

    .. math::

        m(q) = \prod_k \bigl(\lVert q - q_k \rVert^{-2} + 1\bigr)

    has the same solutions but the known ones (Farrell, Birkisson and Funke, *Deflation
    techniques for finding distinct solutions of nonlinear partial differential equations*,
    SIAM J. Sci. Comput. 37, 2015). Its Newton step is the plain step :math:`\delta`
    scaled, :math:`\delta / (1 - \nabla \log m \cdot \delta)`. It starts from the known
    solutions near a singularity (a measure below :data:`_NEAR_MEASURE`, and :math:`J^T J`
    near singular, :func:`_near_singular`), moved along the most singular direction (0.05
    and 0.3 rad either way): the solutions a singularity separates lie on either side. Where
    it ends, plain Newton finishes, and a solution the pose does not have fills a missing
    branch (:func:`_offer`). Only for the branches started from the exact arm (the others
    are missing because nothing reaches them, as the exact arm's closed form says), at most
    ``_DEFLATION_ITER`` deflated steps. ``polished`` is updated in place."""
    unique = polished.unique()
    wanted = polished.done & ~unique
    poses = np.flatnonzero(wanted.reshape(-1, 8).any(axis=1))
    if not poses.size:
        return
    rows = (8 * poses[:, None] + np.arange(8)).reshape(-1)
    scale = np.array([[1.0], [1.0], [nearest.robot.links[3].d]])  # shoulder measure / d4
    near_measure = (polished.measures[:, rows] / scale).min(axis=0) < _NEAR_MEASURE
    moved = np.flatnonzero(unique[rows] & near_measure)
    if not moved.size:
        return
    near, direction = _near_singular(nearest, chain[1], polished.q[rows[moved]])
    moved = moved[near]
    if not moved.size:
        return
    ways = _DEFLATION_WAYS
    starts = (polished.q[rows[moved], None] + ways[:, None] * direction[:, None]).reshape(-1, 6)
    pose_of = np.repeat(poses[moved // 8], ways.size)
    known = np.where(unique[rows, None], polished.q[rows], np.nan).reshape(-1, 8, 6)
    q = _deflated_newton(chain, starts, X_0T[pose_of],
                         known[np.repeat(moved // 8, ways.size)], tol,
                         min(max_iter, _DEFLATION_ITER))
    _offer(chain, polished, unique, wanted.reshape(-1, 8), q, pose_of,
           _branches(nearest.robot, q), X_0T, tol, max_iter)


def _deflated_newton(chain, q, X_target, known, tol, steps):
    """At most ``steps`` deflated Newton steps (see :func:`_deflate`) from the joint vectors
    q (m, 6) towards the poses X_target (m, 4, 4) of frame 0, each deflating the known
    solutions ``known`` (m, k, 6) of its pose (NaN rows: none). A row stops as Newton's do
    (:func:`_newton_rows`): below ``_STOP tol``, or no longer halving its error in two
    steps after ``_GIVE_UP_AFTER``. With numba, compiled
    (``dqlab._fast.newton_compiled.deflated``, tested equal)."""
    if compiled_ready():
        return compiled_deflated(*chain, q, X_target, known, steps, stop=_STOP * tol,
                                 give_up_after=_GIVE_UP_AFTER, damping=DAMPING,
                                 max_step=_MAX_STEP)
    kernel = _newton_kernel(*chain, q.shape[0])
    q = q.copy()
    have = ~np.isnan(known[..., 0])                     # (m, k)
    known = np.where(have[..., None], known, 0.0)
    size = np.full(q.shape[0], np.inf)
    before = np.full((2, q.shape[0]), np.inf)
    active = np.arange(q.shape[0])
    for iteration in range(steps + 1):
        frames = kernel.frames(q[active])
        e = kernel.residual(frames, kernel.targets(X_target[active]))
        before[:, active] = before[1, active], size[active]
        size[active] = _error_size(e)
        keep = size[active] > _STOP * tol               # (NaN stops too)
        if iteration >= _GIVE_UP_AFTER:
            keep &= size[active] < 0.5 * before[0, active]
        if iteration == steps or not keep.any():
            break
        active, e = active[keep], e[keep]
        frames = kernel.take(frames, np.flatnonzero(keep))
        step = kernel.newton_step(frames, e)
        d = wrap_angle(q[active, None] - known[active])     # (m, k, 6)
        r2 = np.where(have[active], (d * d).sum(axis=-1), 1.0)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            # grad log m = sum_k -2 d_k / (|d_k|^4 (|d_k|^-2 + 1)) = -2 d_k / (r2 (1 + r2))
            weight = np.where(have[active], -2.0 / (r2 * (1.0 + r2)), 0.0)
            grad = (weight[..., None] * d).sum(axis=1)
            step = step / (1.0 - (grad * step).sum(axis=1))[:, None]
        step = np.where(np.isfinite(step), step, 0.0)
        q[active] += _shortened(step)
    return q


def _branches(exact, q):
    r"""The branch ``4 s + 2 e + w`` of the exact arm's row order that joint vectors q (m, 6)
    have on the exact arm, as :func:`dqlab.ik.ur_branch` tells it (from the signs of
    :func:`~dqlab.ik.ur_closed_form.branch_measures`)."""
    h, sin_theta3, sin_theta5 = branch_measures(exact, q)
    return 4 * (h < 0) + 2 * (sin_theta3 < 0) + (sin_theta5 < 0)


def _matrix_chain(nearest, tool):
    """The :class:`MatrixChain` of a calibrated arm with the tool ``tool`` (4, 4), built
    once for each of the last few tools used (one pose's repair needs it on every call)."""
    key = tool.tobytes()
    chain = nearest.matrix_chains.get(key)
    if chain is None:
        if len(nearest.matrix_chains) >= 4:
            nearest.matrix_chains.clear()
        chain = nearest.matrix_chains[key] = MatrixChain(nearest.links, tool)
    return chain


def _near_singular(nearest, tool, q):
    r"""Which joint vectors q (m, 6) are near a singularity of the calibrated arm with the
    tool ``tool`` (the smallest singular value of J below 1e-2 of the largest), and the most
    singular direction there, (k, 6) for those k: the eigenvector of :math:`J^\mathsf{T} J`
    of its smallest eigenvalue (the last right singular vector of J), its largest entry made
    positive. With numba, :math:`J^\mathsf{T} J` comes from the compiled frames
    (``dqlab._fast.newton_compiled.gram``), and the test and direction from inverse iteration
    (``dqlab._fast.newton_compiled.smallest``) wherever it is certain of them, ``eigh``
    elsewhere."""
    if not compiled_ready():
        kernel = _matrix_chain(nearest, tool)
        J = kernel.jacobian(kernel.frames(q))
        near, v = _smallest_eigenvector(np.swapaxes(J, -1, -2) @ J)
        return near, v[near]
    H = compiled_gram(nearest.links, tool, q)
    near, v, known = compiled_smallest(H, _NEAR)
    if not known.all():
        rest = ~known
        near[rest], v[rest] = _smallest_eigenvector(H[rest])
    return near, v[near]


def _smallest_eigenvector(H):
    r"""Whether the smallest eigenvalue of each :math:`J^\mathsf{T} J` of H (m, 6, 6) is below
    ``_NEAR`` times its largest, and its eigenvector (m, 6), largest entry positive."""
    w, V = np.linalg.eigh(H)                                             # ascending
    v = V[:, :, 0]
    largest = v[np.arange(v.shape[0]), np.abs(v).argmax(axis=1)]
    return (np.maximum(w[:, 0], 0.0) < _NEAR * w[:, -1],
            np.where(largest[:, None] < 0.0, -v, v))


def _restart(chain, polished, unique, owners, starts, X_0T, tol, max_iter, which=None):
    """Newton from ``starts`` (k, 6); row ``owners[j]`` is offered the solution reached from
    start ``which[j]`` (start j without ``which``; the owners of a start are rows of one
    pose, whose target it steps to). The first start of a row that converges to a solution
    its pose does not have replaces the row. Starts equal to one before them are stepped
    once (:func:`_stepped_once`)."""
    if not owners.size:
        return
    if which is None:
        which = np.arange(owners.size)
    poses = np.full(starts.shape[0], -1)              # (-1: a start no row is offered)
    poses[which] = owners // 8
    used, which = np.unique(_stepped_once(starts, poses)[which], return_inverse=True)
    q, converged, X, measures, errors = _newton(*chain, starts[used], X_0T[poses[used]], tol,
                                                min(max_iter, _RESTART_ITER), _RESTART_GIVE_UP)
    q, converged = q[which], converged[which]
    if compiled_ready():
        taken = compiled_accept(owners, converged, q, polished.q, unique)
    else:
        taken = _accept(polished, unique, owners, converged, q)
    polished.record(owners[taken], q[taken], True, X[which[taken]], measures[:, which[taken]],
                    errors[:, which[taken]])


def _stepped_once(starts, poses):
    """For each of the starts (m, 6), of the poses ``poses`` (m,), the first start of its
    pose equal to it, joint by joint (itself if none before it is): a start repeated
    converges where the first does, and is stepped once. (The members of the exact arm's
    wrist family hold one joint vector for each branch away from the wrist singularity;
    the moves of two rows that hold one start are the same moves.)"""
    keys = np.column_stack([poses, starts])
    order = np.lexsort(keys.T[::-1])                    # (stable: equal keys by index)
    ordered = keys[order]
    new = np.ones(order.size, dtype=bool)
    new[1:] = (ordered[1:] != ordered[:-1]).any(axis=1)
    first = np.empty_like(order)
    first[order] = order[np.flatnonzero(new)][np.cumsum(new) - 1]
    return first


def _accept(polished, unique, owners, converged, q):
    """The starts j whose solution ``q[j]`` replaces row ``owners[j]``: in the order of the
    starts, the first converged one of a row that the pose does not have yet (the rows taken
    meanwhile included). Their rows' joints are written to ``polished.q`` and marked in
    ``unique`` as they are taken."""
    new = converged & polished.are_new(owners, q, unique)
    taken, fixed = [], set()
    for j in np.flatnonzero(new):                       # in the order of the starts
        row = owners[j]
        if row in fixed or not polished.is_new(row, q[j], unique):   # taken meanwhile
            continue
        polished.q[row], unique[row] = q[j], True
        fixed.add(row)
        taken.append(j)
    return np.array(taken, dtype=np.int64)


def _flip(nearest, q, bits):
    r"""The joint vectors ``q`` (m, 6) flipped at the exact arm's elbow (``bits & 2``) and
    wrist (``bits & 1``), ``bits`` (m,) one per vector: with :math:`\theta = q + \theta^0`,
    the elbow flip :math:`(\theta_2 + 2\beta, -\theta_3, \theta_4 + 2\theta_3 - 2\beta)`,
    :math:`\beta = \operatorname{atan2}(a_3 \sin\theta_3, a_2 + a_3 \cos\theta_3)`,
    reaches the same pose, and the wrist flip :math:`(\theta_4 + \pi, -\theta_5, \theta_6 +
    \pi)` the same orientation (the exact arm of ``nearest``, a :class:`_NearestExact`):
    starts near the pose's other branches."""
    offsets = nearest.exact[6:]
    a2, a3 = nearest.exact[1], nearest.exact[2]
    t = q + offsets
    elbow, wrist = (bits & 2).astype(bool), (bits & 1).astype(bool)
    if elbow.any():
        e = t[elbow]
        beta = np.arctan2(a3 * np.sin(e[:, 2]), a2 + a3 * np.cos(e[:, 2]))
        e[:, 1], e[:, 2], e[:, 3] = (e[:, 1] + 2.0 * beta, -e[:, 2],
                                     e[:, 3] + 2.0 * e[:, 2] - 2.0 * beta)
        t[elbow] = e
    if wrist.any():
        w = t[wrist]
        w[:, 3], w[:, 4], w[:, 5] = w[:, 3] + np.pi, -w[:, 4], w[:, 5] + np.pi
        t[wrist] = w
    return t - offsets


def _newton(links, tool, q, X_target, tol, max_iter, give_up_after=_GIVE_UP_AFTER):
    """Newton steps from the joint vectors ``q`` (m, 6) towards the poses ``X_target``
    (m, 4, 4) of frame 0, until each row's position and rotation errors (Euclidean) are
    below ``_STOP tol``, or it stops making progress (after ``give_up_after`` steps, less
    than halving its error in two steps), or ``max_iter`` steps. Returns the joint vectors,
    whether each converged, the TCP poses (m, 4, 4), the singularity measures (3, m) at
    them and their position and rotation errors (2, m) (:func:`pose_errors`).

    The first ``_PLAIN_STEPS`` steps are taken by every row together, none stopped or taken
    out (:func:`_plain_steps`): from the closed form's start, millimetres away, Newton's
    quadratic convergence brings nearly every row below the stop in three steps, and whole
    arrays cost less than following each row (a row already there takes a step of the size
    of its error). The few rows still above the stop then go on together, each stopped as
    soon as it is done (:func:`_newton_rows`). Many rows go through in blocks of
    ``_BLOCK`` (temporaries that stay in the cache).

    With numba installed, the same steps run compiled, eight branches at a time
    (:mod:`dqlab._fast.newton_compiled`, tested equal to this path)."""
    if compiled_ready():
        return compiled_newton(links, tool, q, X_target, tol, max_iter,
                               **dict(_NEWTON_STEPS, give_up_after=give_up_after))
    m = q.shape[0]
    q = q.copy()
    converged, size = np.zeros(m, dtype=bool), np.zeros(m)
    X, measures = np.zeros((m, 4, 4)), np.zeros((3, m))
    plain = min(_PLAIN_STEPS, max_iter)
    for i in range(0, m, _BLOCK):
        rows = slice(i, i + _BLOCK)
        q[rows], size[rows], X[rows], measures[:, rows] = _plain_steps(
            links, tool, q[rows], X_target[rows], plain)
    converged = size <= _STOP * tol
    left = np.flatnonzero(size > _STOP * tol)           # (NaN stops)
    if left.size and plain < max_iter:
        for i in range(0, left.size, _BLOCK):
            rows = left[i:i + _BLOCK]
            q[rows], converged[rows], X[rows], measures[:, rows] = _newton_rows(
                links, tool, q[rows], X_target[rows], tol, plain, max_iter, give_up_after)
    lost = np.flatnonzero(~np.isfinite(q).all(axis=1))  # a step that overflowed: back to 0
    if lost.size:
        q[lost] = np.where(np.isfinite(q[lost]), q[lost], 0.0)
        again = _newton_kernel(links, tool, lost.size)
        frames = again.frames(q[lost])
        X[lost], measures[:, lost] = again.transforms(frames), again.singularity_measures(frames)
    return q, converged, X, measures, np.stack(pose_errors(X, X_target))


def _plain_steps(links, tool, q, X_target, steps):
    """``steps`` Newton steps of every row (m, 6), none stopped: the joint vectors, the size
    of their errors (:func:`_error_size`), the TCP poses (m, 4, 4) and the singularity
    measures (3, m) at them."""
    chain = _newton_kernel(links, tool, q.shape[0])
    q = q.copy()
    targets = chain.targets(X_target)
    frames = chain.frames(q)
    for _ in range(steps):
        q += _shortened(chain.newton_step(frames, chain.residual(frames, targets)))
        frames = chain.frames(q)
    return (q, _error_size(chain.residual(frames, targets)), chain.transforms(frames),
            chain.singularity_measures(frames))


def _error_size(e):
    """The larger of the position and rotation errors (Euclidean) of residuals e (m, 6)."""
    ee = e * e
    return np.sqrt(np.maximum(ee[:, :3].sum(axis=1), ee[:, 3:].sum(axis=1)))


def _newton_rows(links, tool, q, X_target, tol, first, max_iter, give_up_after):
    """Steps ``first`` to ``max_iter`` of :func:`_newton`, each row stopped as soon as it is
    below the stop or no longer halving its error (returns as :func:`_newton` does)."""
    m = q.shape[0]
    chain = _newton_kernel(links, tool, m)
    q = q.copy()
    frames = chain.frames(q)
    targets = chain.targets(X_target)
    size = np.full(m, np.inf)                  # |e| at the current q of each row
    before = np.full((2, m), np.inf)           # ... and at the two previous iterates
    stop = _STOP * tol
    active = np.arange(m)
    for iteration in range(first, max_iter + 1):
        whole = active.size == m
        part = frames if whole else chain.take(frames, active)
        e = chain.residual(part, targets if whole else chain.take(targets, active))
        before[:, active] = before[1, active], size[active]
        size[active] = _error_size(e)
        keep = size[active] > stop             # NaN stops too
        if iteration >= give_up_after:         # no longer making progress: give up
            keep &= size[active] < 0.5 * before[0, active]
        if iteration == max_iter or not keep.any():
            break
        if not keep.all():
            active, part, e = active[keep], chain.take(part, np.flatnonzero(keep)), e[keep]
        q[active] += _shortened(chain.newton_step(part, e))
        chain.put(frames, active, q[active])
    return q, size <= stop, chain.transforms(frames), chain.singularity_measures(frames)


def _shortened(step):
    """Newton steps (m, 6) longer than ``_MAX_STEP`` (largest joint) shortened to it."""
    with np.errstate(invalid="ignore"):
        longest = np.abs(step).max(axis=1, keepdims=True)
        return step * np.minimum(1.0, _MAX_STEP / np.maximum(longest, 1e-300))


def _flags(measures, valid, singular_tol, d4, near):
    """The singularity and reach flags (n,) of the calibrated arm, over the valid rows (8 n,),
    from the singularity measures (3, 8 n), ``near_singular`` below the threshold ``near``;
    in the order of :data:`_FLAG_NAMES` (``not_converged`` left to the caller)."""
    wrist, elbow, shoulder = measures
    flags = {}
    for name, measure in (("wrist_singular", wrist), ("shoulder_singular", shoulder / d4),
                          ("elbow_singular", elbow)):
        flags[name] = (valid & (measure < singular_tol)).reshape(-1, 8).any(axis=1)
    smallest = np.minimum(np.minimum(wrist, elbow), shoulder / d4)
    flags["near_singular"] = (valid & (smallest < near)).reshape(-1, 8).any(axis=1)
    flags["unreachable"] = ~valid.reshape(-1, 8).any(axis=1)
    return flags


_PAIRS = np.array([(k, i) for i in range(8) for k in range(i)]).T     # (2, 28): rows k < i
_COARSE = [0, 2, 4]


def _newton_kernel(links, tool, m):
    """The Newton kernel for m branches: whole matrices for a few (one pose), entries for
    many (a batch); both in :mod:`dqlab._fast`, tested equal to
    :meth:`dqlab.robot.Robot.fk_with_jacobian`."""
    return (MatrixChain if m <= _FEW_ROWS else EntryChain)(links, tool)
