r"""The book's robots as :class:`~dqlab.robot.Robot` chains.

=====================  ==========  ===========================================================
function               convention  source
=====================  ==========  ===========================================================
:func:`ur3`            DH          Universal Robots' published DH parameters (thesis, table 4.2)
:func:`ur5`            DH          Universal Robots' published DH parameters
:func:`ur10`           DH          Universal Robots' published DH parameters
:func:`ur3_mdh`        MDH         the UR3 project report (modified DH with "q_fig" offsets)
:func:`desk_arm`       DH          the 3-DOF desktop arm of the lab report (identified lengths)
:func:`scara_rsm5`     MDH         the Samsung RSM-5 SCARA of the course notes, annex A
:func:`six_r`          MDH         the 6R arm with a spherical wrist of the course notes, ch. 2
=====================  ==========  ===========================================================

Every model is built fresh on each call, so changing its base or tool does not affect
other users. Units are metres and radians.
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .robot import PRISMATIC, Link, Robot

__all__ = [
    "ur3", "ur5", "ur10", "ur3_mdh", "desk_arm", "scara_rsm5", "six_r",
    "UR_DH", "UR_ALPHA", "UR3_MDH", "DESK_ARM", "SCARA_RSM5",
    "desk_arm_joints_from_lab", "desk_arm_lab_from_joints",
    "ChainShape", "UR_SHAPE", "DESK_ARM_SHAPE", "SCARA_SHAPE",
]

PI = math.pi

#: Universal Robots' standard DH parameters (metres, radians), as published by the maker.
UR_DH = {
    "UR3": {"d": (0.1519, 0.0, 0.0, 0.11235, 0.08535, 0.0819),
            "a": (0.0, -0.24365, -0.21325, 0.0, 0.0, 0.0)},
    "UR5": {"d": (0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823),
            "a": (0.0, -0.425, -0.39225, 0.0, 0.0, 0.0)},
    "UR10": {"d": (0.1273, 0.0, 0.0, 0.163941, 0.1157, 0.0922),
             "a": (0.0, -0.612, -0.5723, 0.0, 0.0, 0.0)},
}
#: The link twists shared by every UR arm (standard DH), radians.
UR_ALPHA = (PI / 2, 0.0, 0.0, PI / 2, -PI / 2, 0.0)

#: The UR3 report's modified-DH lengths in metres.
UR3_MDH = {"r1": 0.152, "r2": 0.120, "a2": 0.244, "a3": 0.213,
           "r4": 0.010, "r5": 0.083, "r6": 0.082}

#: The desktop arm's lengths in metres, identified by least squares in the lab report.
#: Only the combination ``l0 - l4`` (base height minus the suction cup's drop) is
#: identifiable from positions, so it is stored as one number.
DESK_ARM = {"l0_minus_l4": 0.035, "l1": 0.144, "l2": 0.162, "l3": 0.067}

#: Samsung RSM-5 dimensions and travel. ``l1``, ``l2``, the z stroke and the joint ranges come
#: from the maker's table in the course notes (axis 1: 240 deg / 350 mm, axis 2: 290 deg /
#: 260 mm, z: 150 mm, r: +-180 deg). The height of the flange above the base at the bottom of
#: the z stroke, ``z_low``, is unreadable in the notes' drawing; 0.180 m is our plausible
#: choice, and it is the only place where it is set.
SCARA_RSM5 = {"l1": 0.350, "l2": 0.260, "z_low": 0.180, "stroke": 0.150,
              "q1_range": math.radians(240.0), "q2_range": math.radians(290.0),
              "q4_range": math.radians(360.0)}


def _ur(name, label):
    p = UR_DH[name]
    links = [Link(a=a, alpha=alpha, d=d, limits=(-2 * PI, 2 * PI))
             for a, alpha, d in zip(p["a"], UR_ALPHA, p["d"], strict=True)]
    return Robot(links, convention="dh", name=label)


def ur3() -> Robot:
    r"""The Universal Robots UR3 with the maker's standard DH parameters.

    ==  ==========  ==========  ===========
    i   d_i [m]     a_i [m]     alpha_i
    ==  ==========  ==========  ===========
    1   0.1519      0           pi/2
    2   0           -0.24365    0
    3   0           -0.21325    0
    4   0.11235     0           pi/2
    5   0.08535     0           -pi/2
    6   0.0819      0           0
    ==  ==========  ==========  ===========

    No tool: :meth:`~dqlab.robot.Robot.fk` returns the flange pose. The base frame sits at the
    foot of the first joint's axis, z up. Joint limits are :math:`\pm 2\pi`. These are also
    the conventions of ``ur_analytic_ik``: its ``ur3.forward_kinematics(q1, ..., q6)``
    returns the same base-to-flange matrix as :meth:`~dqlab.robot.Robot.fk` (the tests
    check 1,000 random configurations to 1e-13).

    Returns
    -------
    Robot

    Examples
    --------
    The thesis's check: at :math:`q = (0, -\pi/2, 0, -\pi/2, 0, 0)` a TCP 0.2 m along the
    flange's z axis is at :math:`(0, -0.394, 0.694)` m.

    >>> import numpy as np
    >>> robot = ur3()
    >>> X_WF = robot.fk([0, -np.pi / 2, 0, -np.pi / 2, 0, 0])
    >>> (X_WF @ [0, 0, 0.2, 1])[:3].round(5) + 0.0
    array([ 0.     , -0.39425,  0.69415])
    """
    return _ur("UR3", "UR3")


def ur5() -> Robot:
    """The Universal Robots UR5 with the maker's standard DH parameters (see :func:`ur3`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur5().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-0.81725, -0.19145, -0.00549])
    """
    return _ur("UR5", "UR5")


def ur10() -> Robot:
    """The Universal Robots UR10 with the maker's standard DH parameters (see :func:`ur3`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur10().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-1.1843 , -0.25614,  0.0116 ])
    """
    return _ur("UR10", "UR10")


def ur3_mdh() -> Robot:
    r"""The UR3 in the modified DH convention of the UR3 project report.

    ======================  =======  =========  =====  ========  ========  =========
    i                       1        2          3      4         5         6
    ======================  =======  =========  =====  ========  ========  =========
    :math:`\sigma_i`        0        0          0      0         0         0
    :math:`\alpha_{i-1}`    0        pi/2       0      0         pi/2      -pi/2
    :math:`a_{i-1}`         0        0          a2     a3        0         0
    :math:`r_i`             r1       -r2        0      r4        r5        r6
    :math:`\theta_i`        q1+pi/2  q2         q3     q4+pi/2   q5        q6-pi/2
    ======================  =======  =========  =====  ========  ========  =========

    with r1 = 0.152, r2 = 0.120, a2 = 0.244, a3 = 0.213, r4 = 0.010, r5 = 0.083,
    r6 = 0.082 m. The offsets are the report's "q_fig" row; note the sign of :math:`r_2`
    (frame 2 is 0.120 m back along :math:`z_2`). No tool, limits :math:`\pm 2\pi`.

    The report's elementary matrices :math:`T_{i-1,i}` and its printed :math:`T_{0,1}` to
    :math:`T_{0,6}` and Jacobian are reproduced with the joint angles
    :math:`q = (0.1, -0.5, 0.8, -0.2, 0.5, 0.1)` rad, which the report does not print: they
    are recovered by peeling the printed frames one at a time,
    :math:`T_{i-1,i} = T_{0,i-1}^{-1} T_{0,i}`, and reading
    :math:`\theta_i = \operatorname{atan2}(m_{10}, m_{00})` of
    :math:`R_x(\alpha_{i-1})^\top R_{i-1,i}`. Its joint angles are not those of :func:`ur3`
    (different zero pose and signs).

    Returns
    -------
    Robot

    Examples
    --------
    The report's pose at :math:`q = 0`:

    >>> import numpy as np
    >>> ur3_mdh().fk(np.zeros(6)).round(3) + 0.0
    array([[ 0.   ,  0.   ,  1.   , -0.028],
           [ 1.   ,  0.   ,  0.   ,  0.54 ],
           [ 0.   ,  1.   ,  0.   ,  0.152],
           [ 0.   ,  0.   ,  0.   ,  1.   ]])
    """
    p = UR3_MDH
    alpha = (0.0, PI / 2, 0.0, 0.0, PI / 2, -PI / 2)
    a = (0.0, 0.0, p["a2"], p["a3"], 0.0, 0.0)
    r = (p["r1"], -p["r2"], 0.0, p["r4"], p["r5"], p["r6"])
    q_fig = (PI / 2, 0.0, 0.0, PI / 2, 0.0, -PI / 2)
    links = [Link(a=ai, alpha=al, d=ri, theta_offset=off, limits=(-2 * PI, 2 * PI))
             for al, ai, ri, off in zip(alpha, a, r, q_fig, strict=True)]
    return Robot(links, convention="mdh", name="UR3 (report, modified DH)")


def desk_arm() -> Robot:
    r"""The 3-DOF desktop arm of the lab report, as a standard-DH chain.

    The lab writes its forward model with three angles in degrees: the base angle
    :math:`q_0`, the elevation :math:`q_1` of the first link above the horizontal, and an
    *absolute* angle :math:`q_2` of the second link below the horizontal (a parallelogram
    keeps it independent of :math:`q_1`):

    .. math::

       d = l_1\cos q_1 + l_2\cos q_2 + l_3,\quad
       x = d\sin q_0,\quad y = d\cos q_0,\quad
       z = l_1\sin q_1 - l_2\sin q_2 + (l_0 - l_4).

    Its frame is right-handed with z up, so :math:`q_0` is measured from the y axis towards
    the x axis (clockwise seen from above). A serial chain needs *relative* angles, so the
    chain's joint variables are

    .. math::

       \theta_1 = \frac{\pi}{2} - q_0,\qquad \theta_2 = q_1,\qquad
       \theta_3 = -(q_1 + q_2)

    (:func:`desk_arm_joints_from_lab` and :func:`desk_arm_lab_from_joints` convert; the map
    mixes two angles, so it cannot be written as per-joint offsets). The chain is

    ==  ====================  ==========  ===========
    i   d_i                   a_i         alpha_i
    ==  ====================  ==========  ===========
    1   l0 - l4 = 0.035 m     l3 = 0.067  pi/2
    2   0                     l1 = 0.144  0
    3   0                     l2 = 0.162  0
    ==  ====================  ==========  ===========

    The parallelogram keeps the hand level, so the hand's constant offset (:math:`l_3`
    outwards, :math:`l_4` down) is the same vector in the arm's vertical plane whatever
    :math:`q_1, q_2`; moving it from the hand to the shoulder changes no position. That is
    what the chain does (only the sums :math:`l_3` and :math:`l_0 - l_4` are identifiable
    from the lab's measurements anyway). The flange *position* is the suction cup's; the
    flange *orientation* follows the forearm, not the cup (which stays vertical). Joint
    limits :math:`\pm\pi`.

    Returns
    -------
    Robot

    Examples
    --------
    The lab's first check, :math:`(q_0, q_1, q_2) = (90, 90, 0)` degrees:

    >>> import numpy as np
    >>> arm = desk_arm()
    >>> q = desk_arm_joints_from_lab(np.radians([90, 90, 0]))
    >>> (arm.fk(q)[:3, 3] * 1000).round(6)
    array([229.,   0., 179.])
    """
    p = DESK_ARM
    lim = (-PI, PI)
    links = [Link(a=p["l3"], alpha=PI / 2, d=p["l0_minus_l4"], limits=lim),
             Link(a=p["l1"], alpha=0.0, d=0.0, limits=lim),
             Link(a=p["l2"], alpha=0.0, d=0.0, limits=lim)]
    return Robot(links, convention="dh", name="desktop arm (lab report)")


def desk_arm_joints_from_lab(q_lab: ArrayLike) -> NDArray[np.float64]:
    r"""Chain joint angles of :func:`desk_arm` from the lab's angles, and back.

    .. math:: (\theta_1, \theta_2, \theta_3) = (\pi/2 - q_0,\; q_1,\; -q_1 - q_2)

    The map is an involution (applied twice it gives back its argument):
    :math:`(q_0, q_1, q_2) = (\pi/2 - \theta_1,\; \theta_2,\; -\theta_2 - \theta_3)`.
    :func:`desk_arm_lab_from_joints` is therefore the same function under the name that
    says the other direction.

    Parameters
    ----------
    q_lab : array_like, shape (..., 3)
        The lab's :math:`(q_0, q_1, q_2)` in radians (or the chain angles, to go back).

    Returns
    -------
    ndarray, shape (..., 3)

    Examples
    --------
    >>> import numpy as np
    >>> np.degrees(desk_arm_joints_from_lab(np.radians([90, 51, 65])))
    array([   0.,   51., -116.])
    >>> np.degrees(desk_arm_lab_from_joints(np.radians([0, 51, -116])))
    array([90., 51., 65.])
    """
    from ._checks import as_float_array

    q = as_float_array(q_lab, "q_lab", (3,))
    return np.stack([PI / 2 - q[..., 0], q[..., 1], -q[..., 1] - q[..., 2]], axis=-1)


#: The lab's angles from the chain joint angles of :func:`desk_arm`: the same involution as
#: :func:`desk_arm_joints_from_lab`.
desk_arm_lab_from_joints = desk_arm_joints_from_lab


def scara_rsm5() -> Robot:
    r"""The Samsung RSM-5 SCARA (RRPR) of the course notes' annex A, in modified DH.

    ==  ==============  ======  =====================  ===============  ===========  ==========
    i   sigma_i         alpha   a_{i-1}                theta_i          r_i          limits
    ==  ==============  ======  =====================  ===============  ===========  ==========
    1   0 (revolute)    0       0                      q1               0            +-120 deg
    2   0 (revolute)    0       l1 = 0.350 m           q2               0            +-145 deg
    3   1 (prismatic)   0       l2 = 0.260 m           0                q3 + z_low   0..0.150 m
    4   0 (revolute)    0       0                      q4               0            +-180 deg
    ==  ==============  ======  =====================  ===============  ===========  ==========

    All joint axes point up, so the flange pose is

    .. math::

       x = l_1 \cos q_1 + l_2 \cos(q_1 + q_2),\quad
       y = l_1 \sin q_1 + l_2 \sin(q_1 + q_2),\quad
       z = z_{low} + q_3,\quad
       \text{yaw} = q_1 + q_2 + q_4.

    The prismatic travel is positive (the course's advice): :math:`q_3 = 0` is the bottom of
    the stroke. The drawing that gives the height is unreadable in the notes; the height of
    the flange above the base at the bottom of the stroke, ``z_low = 0.180`` m, is our
    plausible choice, set only in :data:`SCARA_RSM5`.

    Returns
    -------
    Robot

    Examples
    --------
    >>> import numpy as np
    >>> scara = scara_rsm5()
    >>> scara.fk([0, np.pi / 2, 0.1, 0])[:3, 3].round(6)
    array([0.35, 0.26, 0.28])
    """
    p = SCARA_RSM5
    h1, h2, h4 = p["q1_range"] / 2, p["q2_range"] / 2, p["q4_range"] / 2
    links = [Link(a=0.0, alpha=0.0, d=0.0, limits=(-h1, h1)),
             Link(a=p["l1"], alpha=0.0, d=0.0, limits=(-h2, h2)),
             Link(a=p["l2"], alpha=0.0, d=p["z_low"], joint=PRISMATIC,
                  limits=(0.0, p["stroke"])),
             Link(a=0.0, alpha=0.0, d=0.0, limits=(-h4, h4))]
    return Robot(links, convention="mdh", name="Samsung RSM-5 SCARA")


def six_r(a2: float = 0.4, r4: float = 0.35, r7: float = 0.1) -> Robot:
    r"""The 6R arm with a spherical wrist of the course notes, chapter 2 (figure 2.5).

    ==  ===================  =========  =========  =====
    i   alpha_{i-1}          a_{i-1}    theta_i    r_i
    ==  ===================  =========  =========  =====
    1   0                    0          q1         0
    2   pi/2                 0          q2         0
    3   0                    a2         q3         0
    4   pi/2                 0          q4         r4
    5   -pi/2                0          q5         0
    6   pi/2                 0          q6         0
    ==  ===================  =========  =========  =====

    The end-effector point :math:`O_7` is :math:`r_7` along :math:`z_6` (the tool). The notes
    give the structure but no numbers; the defaults are plausible values.

    Parameters
    ----------
    a2, r4, r7 : float, optional
        Upper-arm length, forearm length and tool length in metres.

    Returns
    -------
    Robot

    Examples
    --------
    >>> six_r().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(6) + 0.0
    array([ 0.4 ,  0.  , -0.45])
    """
    alpha = (0.0, PI / 2, 0.0, PI / 2, -PI / 2, PI / 2)
    a = (0.0, 0.0, a2, 0.0, 0.0, 0.0)
    r = (0.0, 0.0, 0.0, r4, 0.0, 0.0)
    links = [Link(a=ai, alpha=al, d=ri, limits=(-PI, PI))
             for al, ai, ri in zip(alpha, a, r, strict=True)]
    tool = np.eye(4)
    tool[2, 3] = r7
    return Robot(links, convention="mdh", tool=tool, name="6R with spherical wrist")


# --------------------------------------------------------------------------------------
# Chain shapes: what a closed-form formula needs of a chain


@dataclass(frozen=True)
class ChainShape:
    r"""The structure a closed-form formula needs of a chain, checked in one place.

    A closed-form solver (or Jacobian) reads its lengths from the robot's links; before it
    does, :meth:`check` makes sure the chain is one the formulas hold for.

    Attributes
    ----------
    label : str
        Who needs the shape, first word of the error message (``"ur()"``).
    description : str
        The shape in words, quoted by the error message.
    convention : {"dh", "mdh"}
    joints : str
        One letter per joint, ``R`` (revolute) or ``P`` (prismatic).
    alpha : tuple of float, optional
        The twist of every link, compared modulo :math:`2\pi`.
    zero_a, zero_d : tuple of int
        Links (0-based) whose ``a`` or ``d`` must be zero.
    nonzero_a, nonzero_d : tuple of int
        Links whose ``a`` or ``d`` must not be zero.
    zero_offsets : bool
        Whether every ``theta_offset`` must be zero.

    Examples
    --------
    >>> UR_SHAPE.check(ur5())
    >>> SCARA_SHAPE.check(ur3())
    Traceback (most recent call last):
    ...
    ValueError: scara() needs a chain like dqlab.models.scara_rsm5() (modified DH, joints RRPR, ...
    """

    label: str
    description: str
    convention: str
    joints: str
    alpha: tuple = None
    zero_a: tuple = ()
    zero_d: tuple = ()
    nonzero_a: tuple = ()
    nonzero_d: tuple = ()
    zero_offsets: bool = False

    def check(self, robot: Robot, *, atol: float = 1e-12) -> None:
        """Raise ``ValueError`` (naming the first difference) unless ``robot`` has the shape.

        Parameters
        ----------
        robot : Robot
        atol : float
            Tolerance of the comparisons (lengths in metres, angles in radians).
        """
        problem = self._difference(robot, atol)
        if problem:
            raise ValueError(f"{self.label} needs {self.description}; {problem}")

    def _difference(self, robot, atol):
        links = getattr(robot, "links", None)
        if links is None:
            return f"got {type(robot).__name__}, not a Robot"
        if robot.convention != self.convention:
            return f"the robot's convention is {robot.convention!r}"
        joints = "".join("R" if lk.is_revolute else "P" for lk in links)
        if joints != self.joints:
            return f"the robot's joints are {joints}"
        for i, lk in enumerate(links):
            if self.alpha is not None and abs(math.remainder(lk.alpha - self.alpha[i],
                                                             2 * PI)) > atol:
                return f"link {i + 1} has alpha = {lk.alpha!r}"
            if self.zero_offsets and abs(lk.theta_offset) > atol:
                return f"link {i + 1} has theta_offset = {lk.theta_offset!r}"
        for name, zero, nonzero in (("a", self.zero_a, self.nonzero_a),
                                    ("d", self.zero_d, self.nonzero_d)):
            for i in zero:
                if abs(getattr(links[i], name)) > atol:
                    return f"link {i + 1} has {name} = {getattr(links[i], name)!r}"
            for i in nonzero:
                if abs(getattr(links[i], name)) <= atol:
                    return f"link {i + 1} has {name} = 0"
        return ""


#: The UR family (UR3, UR5, UR10, e-series) for :func:`dqlab.ik.ur_closed_form.ur`.
UR_SHAPE = ChainShape(
    "ur()", "a UR-family arm like dqlab.models.ur3() (standard DH, six revolute joints, "
    "alpha = (pi/2, 0, 0, pi/2, -pi/2, 0), a1 = a4 = a5 = a6 = 0, d2 = d3 = 0, nonzero a2, "
    "a3 and d4)", "dh", "RRRRRR", alpha=UR_ALPHA, zero_a=(0, 3, 4, 5), zero_d=(1, 2),
    nonzero_a=(1, 2), nonzero_d=(3,))

#: The desktop arm for :func:`dqlab.ik.desk_arm_closed_form.desk_arm`.
DESK_ARM_SHAPE = ChainShape(
    "desk_arm", "a chain like dqlab.models.desk_arm() (standard DH, three revolute joints, "
    "alpha = (pi/2, 0, 0), d_2 = d_3 = 0, no offsets)", "dh", "RRR", alpha=(PI / 2, 0.0, 0.0),
    zero_d=(1, 2), zero_offsets=True)

#: The SCARA for :func:`dqlab.ik.scara_closed_form.scara` and the closed-form SCARA Jacobian.
SCARA_SHAPE = ChainShape(
    "scara()", "a chain like dqlab.models.scara_rsm5() (modified DH, joints RRPR, all "
    "alpha = 0, a_0 = a_3 = 0)", "mdh", "RRPR", alpha=(0.0,) * 4, zero_a=(0, 3))
