r"""Closed-form inverse kinematics of the Universal Robots arms, by dual quaternions.

:func:`exact_ur` returns every solution of an exact UR-family arm (UR3, UR5, UR10 and the
e-series share the structure) for one pose or a batch, following the route of the thesis
(section 4.3): write the pose as the product of the joint dual quaternions
:math:`Q_1 \cdots Q_6` and equate the products :math:`M_i = Q_i M_{i+1}` with
:math:`N_{i+1} = Q_i^{-1} N_i` term by term. The route has four steps, each a small
function of :mod:`dqlab.ik.ur_steps`:

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

:func:`~dqlab.ik.ur_steps.candidate_solutions` assembles the steps into the eight rows in the
order of the book's chapter 8, readably; :func:`exact_ur` returns the same rows, bit for
bit, from the private engine ``dqlab._fast.ur_engine`` (one pose on Python floats, a batch
with all branches as arrays, in blocks), which also checks every row, sets the flags and, at
a wrist singularity, chooses a member of the family. The arm must have the exact UR shape
(:func:`ur_parameters`); ``dqlab.ik.ur`` (:func:`dqlab.ik.ur_solver.ur`) solves any UR,
exact (here) or calibrated (:func:`dqlab.ik.ur_calibrated.calibrated_ur`, which starts from
the engine's solutions of the nearest exact UR).

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

Angles are wrapped to :math:`(-\pi, \pi]`; :func:`~dqlab.ik.solutions.equivalent_solutions`
lists their :math:`2\pi`-equivalents within the joint limits and
:func:`~dqlab.ik.solutions.closest_solution` picks the one nearest a given configuration.

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

import weakref

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._checks import check_instance, check_scalar
from .._fast import ur_engine as engine
from ..models import UR_SHAPE
from ..robot import Robot
from ..rotations import wrap_angle
from ._per_robot import remembered
from .result import IKResult, check_ur_options
from .ur_steps import (  # noqa: F401  (the reasons, re-exported)
    NEAR_SINGULAR,
    REASON_FAR,
    REASON_INNER,
    REASON_OUTER,
    REASON_REACH,
    REASON_SHOULDER,
    REASON_TOL,
)

__all__ = ["exact_ur", "ur_parameters", "branch_measures", "distinct_solutions",
           "SOLUTION_ORDER", "ROW_NAMES"]

#: Former names of this module, which solve any UR (exact or calibrated): now in
#: :mod:`dqlab.ik.ur_solver`.
#: ``(shoulder, elbow, wrist)`` labels of the eight rows, in order ``k = 4 s + 2 e + w``.
SOLUTION_ORDER = tuple(
    (s, e, w) for s in ("left", "right") for e in ("up", "down") for w in ("noflip", "flip"))

#: The names of the eight rows, ``"shoulder elbow wrist"`` (``"left up noflip"``, ...), as an
#: :class:`~dqlab.ik.result.IKResult` of :func:`exact_ur` prints them.
ROW_NAMES = tuple(" ".join(branch) for branch in SOLUTION_ORDER)

_PARAMETERS = weakref.WeakKeyDictionary()  # robot -> ur_parameters or its error (links are
#                                            immutable)


def _exact_parameters(robot):
    """:func:`ur_parameters` of a robot, computed once per robot (an error too: remembered,
    and raised again, with a pointer to the solver of calibrated arms)."""
    return remembered(_PARAMETERS, robot, _parameters_and_constants)


def _parameters_and_constants(robot):
    """:func:`ur_parameters` with the engine's constants of one pose, or the ValueError."""
    try:
        prm = ur_parameters(robot)
    except ValueError as exc:
        return ValueError(f"{exc} (a calibrated UR is solved by dqlab.ik.ur)")
    prm["one pose"] = engine.arm_constants(prm)      # (this dict is not handed out)
    return prm


def branch_measures(robot: Robot, q: ArrayLike) -> tuple[NDArray[np.float64], ...]:
    r"""The three measures whose signs tell the branches of an exact UR's joint vectors
    apart, and which vanish at its singularities: with :math:`\theta = q + \theta^0` (the
    joint offsets),

    .. math::

       h = a_2 \cos\theta_2 + a_3 \cos(\theta_2 + \theta_3) + d_5 \sin\theta_{234},
       \quad \sin\theta_3, \quad \sin\theta_5,

    :math:`h` the wrist centre's distance from the base axis along :math:`x_1` (shoulder),
    then the elbow and the wrist.

    Parameters
    ----------
    robot : dqlab.robot.Robot
        An exact UR-family arm (:func:`ur_parameters`).
    q : array_like, shape (..., 6)
        Joint vectors, radians.

    Returns
    -------
    h, sin_theta3, sin_theta5 : ndarray, shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur5e
    >>> h, s3, s5 = branch_measures(ur5e(), [0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> int(4 * (h < 0) + 2 * (s3 < 0) + (s5 < 0))      # right (h < 0), up, no flip
    4
    """
    check_instance(robot, Robot, "robot")
    _exact_parameters(robot)
    t = robot.check_joints(q) + np.array([link.theta_offset for link in robot.links])
    a2, a3, d5 = robot.links[1].a, robot.links[2].a, robot.links[4].d
    h = (a2 * np.cos(t[..., 1]) + a3 * np.cos(t[..., 1] + t[..., 2])
         + d5 * np.sin(t[..., 1] + t[..., 2] + t[..., 3]))
    return h, np.sin(t[..., 2]), np.sin(t[..., 4])


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


def exact_ur(robot: Robot, target: ArrayLike, *, tol: float = 1e-9,
             tool: ArrayLike | None = None, q_ref: ArrayLike | None = None,
             singular_tol: float = 5e-7, pose_tol: float = 1e-9, residuals: str = "equations",
             near_tol: float = NEAR_SINGULAR) -> IKResult:
    r"""Every closed-form inverse-kinematics solution of an exact UR-family arm.

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
        calibrated UR (parameters millimetres off the exact shape) is refused here:
        ``dqlab.ik.ur`` (:func:`dqlab.ik.ur_solver.ur`) solves it, with the same result.
    target : array_like, shape (..., 4, 4) or (..., 8)
        Target pose(s) of the TCP in the world frame, as rigid transforms or unit dual
        quaternions ``(q_r, q_d)`` (told apart by the trailing shape; see
        :func:`dqlab.ik.targets.parse_targets`), each part scalar first, ``(w, x, y, z)``.
        A quaternion stored scalar last (scipy, ROS, Eigen) converts with
        :func:`dqlab.quaternion.quaternion_from_xyzw`; given in the wrong order it is still
        a unit quaternion, of another rotation, which no check can detect.
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
    near_tol : float
        A pose is flagged ``"near_singular"`` when a valid row has :math:`|\sin\theta_5|`,
        :math:`|\sin\theta_3|` or :math:`h / d_4` below it (default
        :data:`~dqlab.ik.ur_steps.NEAR_SINGULAR`, 0.01: about 0.57 degrees, or 1 % of
        :math:`d_4`): there the joints are sensitive to the pose (a change
        :math:`\delta` of the pose moves them by up to :math:`\delta` over the measure).
        On a calibrated UR the threshold is at least four times the rotation gap between
        the arm and its nearest exact UR (:func:`~dqlab.ik.ur_calibrated.nominal_ur`), and
        the nearest exact UR's branches count too: within it, the calibrated arm's
        solutions no longer follow the exact arm's branches one to one, and a pose may
        have more solutions than the eight rows (the others in ``result.more``; see
        :mod:`dqlab.ik.ur_calibrated`).
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
        ``"elbow_singular"`` (set when a valid solution is at that singularity, within
        ``singular_tol``), ``"near_singular"`` (a valid solution within ``near_tol`` of
        one),
        ``"unreachable"`` (no valid solution) and ``"not_converged"`` (on a calibrated UR, a
        branch of the nearest exact arm did not converge on the calibrated chain, or the
        pose has an odd number of solutions, one missing; never set by the exact closed
        form, which has nothing to converge: one set of keys for every UR); ``reason``
        (...) says why a pose has no
        solution. Branches that coincide at a singularity are all returned (equal rows);
        :func:`distinct_solutions` marks the first of each group. For a batch, the arrays
        are stored with the poses last in memory (as the solver computes them) and given as
        transposed views, shape as above (``np.ascontiguousarray`` gives a C-ordered copy).

    Raises
    ------
    ValueError
        If the robot is not UR-shaped (:data:`dqlab.models.UR_SHAPE`), or ``target`` has
        the wrong shape, holds NaN, is not a rigid transform or not a unit dual quaternion,
        or is so far (some 1e308 m) that its distance overflows. Unreachable poses do not
        raise: a pose far beyond reach (:func:`~dqlab.ik.ur_steps.far_wrist`) has no valid
        row, each row's error being the pose's distance.

    Notes
    -----
    Steps, with :math:`X_{06} = (q, p)` the flange pose in the base frame and
    :math:`\mathsf r_D = q\, q_0^*` its rotation relative to the zero pose
    (:math:`q_0 = \cos\frac{\pi}{4} + \sin\frac{\pi}{4}\, i`, the flange at :math:`q = 0`):

    .. math::

        p_5 &= p - d_6 z_6, \qquad
        \theta_1 = \operatorname{atan2}(y_5 h_\pm + x_5 d_4,\ x_5 h_\pm - y_5 d_4),\\
        L &= r_z(\theta_1)^* \mathsf r_D, \qquad
        \theta_5 = 2 \operatorname{atan2}\big(\sigma\sqrt{L_x^2 + L_z^2},
                                             \sqrt{L_w^2 + L_y^2}\big),\\
        \theta_{234} &= \operatorname{atan2}(-L_y, L_w) + \operatorname{atan2}(\sigma L_x,
                        -\sigma L_z), \quad
        \theta_6 = \operatorname{atan2}(-L_y, L_w) - \operatorname{atan2}(\sigma L_x,
                        -\sigma L_z),\\
        (u_4, v_4) &= (c_1 x_5 + s_1 y_5 - d_5 s_{234},\ z_5 - d_1 + d_5 c_{234}),\\
        \theta_3 &= \operatorname{atan2}\big(\pm\sqrt{((a_2 + a_3)^2 - \rho^2)
                     (\rho^2 - (a_2 - a_3)^2)},\ \rho^2 - a_2^2 - a_3^2\big), \quad
        \theta_2 = \operatorname{atan2}(v_4 k_1 - u_4 k_2, u_4 k_1 + v_4 k_2),\\
        \theta_4 &= \theta_{234} - \theta_2 - \theta_3 ,

    with :math:`\rho^2 = u_4^2 + v_4^2`, :math:`k_1 = a_2 + a_3 c_3`, :math:`k_2 = a_3 s_3`.

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
    >>> robot = ur3()
    >>> q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
    >>> result = exact_ur(robot, robot.fk(q))
    >>> result.solutions.shape, int(result.count)
    ((8, 6), 8)
    >>> bool(np.any(np.all(np.abs(result.solutions - q) < 1e-12, axis=-1)))
    True
    >>> bool(result.position_error[result.valid].max() < 1e-12)
    True

    A batch: a regular pose and the thesis's test pose (every singularity at once):

    >>> poses = robot.fk(np.array([q, [0, -np.pi / 2, 0, -np.pi / 2, 0, 0]]))
    >>> result = exact_ur(robot, poses)
    >>> result.count
    array([8, 8])
    >>> for name, flag in result.flags.items():
    ...     print(name, flag)
    wrist_singular [False  True]
    shoulder_singular [False  True]
    elbow_singular [False  True]
    near_singular [False  True]
    unreachable [False False]
    not_converged [False False]
    """
    prm = _exact_parameters(robot)
    tol, singular_tol, near_tol, pose_tol = check_ur_options(tol, singular_tol, near_tol,
                                                             pose_tol, residuals)
    result = engine.solve(robot, prm, target, tol, singular_tol, pose_tol, tool, q_ref, residuals,
                   near_tol)
    result.row_names = ROW_NAMES
    return result


def distinct_solutions(result: IKResult, atol: float = 1e-9) -> NDArray[np.bool_]:
    r"""Mark the first valid row of each group of equal solutions (angles compared mod 2 pi).

    Parameters
    ----------
    result : IKResult
        As returned by :func:`exact_ur` or ``dqlab.ik.ur``.
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
    check_instance(result, IKResult, "result")
    atol = check_scalar(atol, "atol", minimum=0)
    sol = result.solutions
    valid = result.valid
    diff = np.abs(wrap_angle(sol[..., :, None, :] - sol[..., None, :, :]))
    same = np.all(diff <= atol, axis=-1) & valid[..., :, None] & valid[..., None, :]
    k = sol.shape[-2]
    earlier = np.tril(np.ones((k, k), dtype=bool), -1)
    return valid & ~np.any(same & earlier, axis=-1)
