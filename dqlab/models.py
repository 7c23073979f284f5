r"""The book's robots as :class:`~dqlab.robot.Robot` chains.

=====================  ==========  ===========================================================
function               convention  source
=====================  ==========  ===========================================================
:func:`ur3`            DH          Universal Robots' published DH parameters (thesis, table 4.2)
:func:`ur5`            DH          Universal Robots' published DH parameters
:func:`ur10`           DH          Universal Robots' published DH parameters
:func:`ur3e`, ...      DH          Universal Robots' published DH parameters: :func:`ur3e`,
                                   :func:`ur5e` (:func:`ur7e`), :func:`ur10e` (:func:`ur12e`),
                                   :func:`ur16e`, :func:`ur15`, :func:`ur18`, :func:`ur8_long`,
                                   :func:`ur20`, :func:`ur30` (:data:`UR_MODELS` by name)
:func:`ur3_mdh`        MDH         the UR3 project report (modified DH with "q_fig" offsets)
:func:`desk_arm`       DH          the 3-DOF desktop arm of the lab report (identified lengths)
:func:`scara_rsm5`     MDH         the Samsung RSM-5 SCARA of the course notes, annex A
:func:`six_r`          MDH         the 6R arm with a spherical wrist of the course notes, ch. 2
=====================  ==========  ===========================================================

Every model is built fresh on each call, so changing its base or tool does not affect
other users. Units are metres and radians.

.. rubric:: The UR models and their sources

Every number a UR model carries is Universal Robots' own, from these publications:

[DH]
    Universal Robots, "DH parameters for calculations of kinematics and dynamics" (support
    article): the lengths :math:`d_i, a_i` of :data:`UR_DH`.
[R2]
    Universal Robots' ROS 2 description, ``UniversalRobots/Universal_Robots_ROS2_Description``
    (BSD-3-Clause), ``config/<model>/``: ``default_kinematics.yaml`` (the joint origins),
    ``physical_parameters.yaml`` (masses, centres of mass and inertia tensors in its own link
    frames) and ``joint_limits.yaml`` (position, speed and effort limits, which cite the
    user manuals' technical specifications and UR's article "Max. joint torques").
[R1]
    The ROS 1 description, ``ros-industrial/universal_robot`` (BSD), ``ur_description/config/
    <model>/``: the same three files for the UR12e, UR15, UR18 and UR8 Long; its ``ur7e`` and
    ``ur12e`` folders are links to ``ur5e`` and ``ur10e``.

The files are stored with the tests (``tests/data/ur_description``, with their commits), and
the tests compare every model with them: the flange pose of the files' joint chain, the
masses, the centres of mass and the principal moments seen from the base, and the gravity
torques of an independent rigid-body library (pinocchio) on the files' chain and inertias.

==========  =====  ===================================================  =======================
model       DH     masses, centres of mass, tensors                     speeds, torques, ranges
==========  =====  ===================================================  =======================
UR3         [DH]   [R2] ``ur3`` (its tensors: stated solid cylinders)   [R2] ``ur3`` (1)
UR5         [DH]   [R2] ``ur5`` (its tensors: stated solid cylinders)   [R2] ``ur5``
UR10        [DH]   [R2] ``ur10`` (tensors extracted from URSim)         [R2] ``ur10``
UR3e        [DH]   [R2] ``ur3e`` (2025 tensors from CAD)                [R2] ``ur3e`` (1)
UR5e, UR7e  [DH]   [R2] ``ur5e``, ``ur7e`` (2025 tensors from CAD)      [R2] ``ur5e`` (2)
UR10e       [DH]   [R2] ``ur10e`` (the UR10's URSim tensors)            [R2] ``ur10e``
UR12e       [DH]   [R2] ``ur12e`` (the UR10e's)                         [R2] ``ur12e``
UR16e       [DH]   [R2] ``ur16e``                                       [R2] ``ur16e``
UR15        [DH]   [R2] ``ur15`` (= [R1] ``ur15``)                      [R1] ``ur15``
UR18        [DH]   [R2] ``ur18`` (= [R1] ``ur18``)                      [R2] ``ur18``
UR8 Long    [DH]   [R1] ``ur8long``                                     none published (3)
UR20        [DH]   [R2] ``ur20`` (2025: wrist 3 of 0.926 kg)            [R2] ``ur20``
UR30        [DH]   [R2] ``ur30``, without its tensors (4)               [R2] ``ur30``
==========  =====  ===================================================  =======================

(1) The wrist 3 of the UR3 and the UR3e turns without limit: UR removed its position limit
from [R2] in 2024 "to reflect UR3(e)'s infinite wrist 3 joint", as their data sheets give
its range; every other joint of every model turns
:math:`\pm 360°` (the elbow too: the files' :math:`\pm 180°` for the elbow is, as they say,
an artificial limit for motion planners). (2) [R1]'s ``ur7e`` is a link to ``ur5e``. (3) The
UR8 Long's links carry no rated speed or torque. (4) [R2]'s UR30 tensors are the UR16e's,
digit for digit but for one sign, which a 30 kg arm with 0.64 m and 0.50 m tubes cannot have
(a uniform 28.5 kg tube of 0.64 m alone has 0.97 kg m^2 about its middle, the file says 0.48):
the UR30's links carry the stated cylinders of :func:`ur_link_inertias` instead.
:data:`UR_PHYSICAL_PARAMETERS` names the file and commit of every model's inertial numbers.

The files state each link's inertia in ROS's link frames, which are not the DH frames of
these models; :func:`ur_link_inertias_from_ros` moves them (the transforms are in its
docstring).
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import as_float_array, check_instance, check_scalar
from .inertia import LinkInertia
from .robot import PRISMATIC, Link, Robot
from .rotations import matrix_from_rpy

__all__ = [
    "ur3", "ur5", "ur10", "ur3_mdh", "desk_arm", "scara_rsm5", "six_r",
    "ur3e", "ur5e", "ur7e", "ur10e", "ur12e", "ur16e", "ur15", "ur18", "ur8_long", "ur20",
    "ur30", "UR_CURRENT_DH", "UR_MAX_JOINT_SPEED_DEG", "UR_MAX_JOINT_TORQUE",
    "UR_JOINT_RANGE_DEG", "UR_PHYSICAL_PARAMETERS", "UR_MODELS",
    "UR_DH", "UR_ALPHA", "UR3_MDH", "DESK_ARM", "SCARA_RSM5",
    "desk_arm_joints_from_lab", "desk_arm_lab_from_joints",
    "ChainShape", "UR_SHAPE", "DESK_ARM_SHAPE", "SCARA_SHAPE",
    "UR_DYNAMICS", "UR3_MDH_JOINT_MAP", "ur_link_inertias", "ur_link_inertias_from_ros",
    "rod_link_inertias", "with_model_inertias",
]

PI = math.pi

#: Universal Robots' standard DH parameters (metres, radians), as published by the maker
#: ([DH]; the CB3 arms here, the current models in :data:`UR_CURRENT_DH`).
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

#: The published standard DH lengths of the current UR models, added to :data:`UR_DH` (same
#: form, metres; the twists are :data:`UR_ALPHA`). Source: [DH], as also tabulated by
#: ``ur_analytic_ik``. The e-series, UR20 and UR30 values are those the controller simulator
#: reports in its kinematics-info message: they reproduce the ``calib_...`` hashes of UR's ROS
#: description files (checked in the tests), and every model's flange pose is that of the
#: joint chain of [R2]'s or [R1]'s ``default_kinematics.yaml`` (also checked). UR renamed
#: the UR5e "UR7e" and the UR10e "UR12e" in 2025: the same arms, with the same parameters.
UR_CURRENT_DH = {
    "UR3e": {"d": (0.15185, 0.0, 0.0, 0.13105, 0.08535, 0.0921),
             "a": (0.0, -0.24355, -0.2132, 0.0, 0.0, 0.0)},
    "UR5e": {"d": (0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996),
             "a": (0.0, -0.425, -0.3922, 0.0, 0.0, 0.0)},
    "UR10e": {"d": (0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655),
              "a": (0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0)},
    "UR16e": {"d": (0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655),
              "a": (0.0, -0.4784, -0.36, 0.0, 0.0, 0.0)},
    "UR15": {"d": (0.2186, 0.0, 0.0, 0.1824, 0.1361, 0.1434),
             "a": (0.0, -0.6475, -0.5164, 0.0, 0.0, 0.0)},
    "UR18": {"d": (0.2186, 0.0, 0.0, 0.1824, 0.1361, 0.1434),
             "a": (0.0, -0.475, -0.3389, 0.0, 0.0, 0.0)},
    "UR8 Long": {"d": (0.2186, 0.0, 0.0, 0.1824, 0.1361, 0.1434),
                 "a": (0.0, -0.8989, -0.7149, 0.0, 0.0, 0.0)},
    "UR20": {"d": (0.2363, 0.0, 0.0, 0.201, 0.1593, 0.1543),
             "a": (0.0, -0.862, -0.7287, 0.0, 0.0, 0.0)},
    "UR30": {"d": (0.2363, 0.0, 0.0, 0.201, 0.1593, 0.1543),
             "a": (0.0, -0.637, -0.5037, 0.0, 0.0, 0.0)},
}
UR_CURRENT_DH["UR7e"] = UR_CURRENT_DH["UR5e"]
UR_CURRENT_DH["UR12e"] = UR_CURRENT_DH["UR10e"]
UR_DH.update(UR_CURRENT_DH)

#: Universal Robots' published maximum joint speeds, degrees per second, joints 1 to 6 (base,
#: shoulder, elbow, wrists 1-3): the user manuals' technical specifications, as the
#: ``max_velocity`` of [R2]'s ``joint_limits.yaml`` of each model ([R1]'s for the UR15; the
#: UR7e is the UR5e, the UR12e [R2]'s own file). None published for the UR8 Long. The models
#: carry them, in rad/s, as the ``max_speed`` of their links.
UR_MAX_JOINT_SPEED_DEG = {
    "UR3": (180.0, 180.0, 180.0, 360.0, 360.0, 360.0),
    "UR5": (180.0,) * 6,
    "UR10": (120.0, 120.0, 180.0, 180.0, 180.0, 180.0),
    "UR3e": (180.0, 180.0, 180.0, 360.0, 360.0, 360.0),
    "UR5e": (180.0,) * 6,
    "UR10e": (120.0, 120.0, 180.0, 180.0, 180.0, 180.0),
    "UR12e": (120.0, 120.0, 180.0, 180.0, 180.0, 180.0),
    "UR16e": (120.0, 120.0, 180.0, 180.0, 180.0, 180.0),
    "UR15": (180.0, 180.0, 240.0, 300.0, 300.0, 300.0),
    "UR18": (180.0, 180.0, 240.0, 300.0, 300.0, 300.0),
    "UR20": (120.0, 120.0, 150.0, 210.0, 210.0, 210.0),
    "UR30": (120.0, 120.0, 150.0, 210.0, 210.0, 210.0),
}
UR_MAX_JOINT_SPEED_DEG["UR7e"] = UR_MAX_JOINT_SPEED_DEG["UR5e"]      # the same arm, renamed

#: Universal Robots' rated joint torques, N m, joints 1 to 6: the ``max_effort`` of the same
#: ``joint_limits.yaml`` files (which take them from UR's article "Max. joint torques").
#: None published for the UR8 Long. The models carry them as the ``max_torque`` of their
#: links; :class:`dqlab.ur.script.SafetyLimits` refuses motions that need more.
UR_MAX_JOINT_TORQUE = {
    "UR3": (56.0, 56.0, 28.0, 12.0, 12.0, 12.0),
    "UR5": (150.0, 150.0, 150.0, 28.0, 28.0, 28.0),
    "UR10": (330.0, 330.0, 150.0, 56.0, 56.0, 56.0),
    "UR3e": (54.0, 54.0, 28.0, 9.0, 9.0, 9.0),
    "UR5e": (150.0, 150.0, 150.0, 28.0, 28.0, 28.0),
    "UR10e": (330.0, 330.0, 150.0, 54.0, 54.0, 54.0),
    "UR12e": (330.0, 330.0, 150.0, 54.0, 54.0, 54.0),
    "UR16e": (330.0, 330.0, 150.0, 54.0, 54.0, 54.0),
    "UR15": (433.0, 433.0, 204.0, 70.0, 70.0, 70.0),
    "UR18": (433.0, 433.0, 204.0, 70.0, 70.0, 70.0),
    "UR20": (738.0, 738.0, 433.0, 107.0, 107.0, 107.0),
    "UR30": (738.0, 738.0, 433.0, 107.0, 107.0, 107.0),
}
UR_MAX_JOINT_TORQUE["UR7e"] = UR_MAX_JOINT_TORQUE["UR5e"]

#: The joints' working ranges, :math:`\pm` degrees (``inf``: no limit), joints 1 to 6: the
#: user manuals' :math:`\pm 360°` on every joint but the wrist 3 of the UR3 and the UR3e,
#: which turns without limit ([R2]'s ``joint_limits.yaml`` of both has no position limit for
#: it). The models carry them as the ``limits`` of their links.
UR_JOINT_RANGE_DEG = {name: (360.0,) * 6 for name in UR_DH}
UR_JOINT_RANGE_DEG["UR3"] = UR_JOINT_RANGE_DEG["UR3e"] = (360.0,) * 5 + (math.inf,)

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


#: The rotation block of [R2]'s physical parameters (``rotation``: roll, pitch, yaw of each
#: link's inertial frame in its ROS link frame) for the tensors measured or extracted from
#: URSim, which are stated in the axes of the DH frames ...
_RPY_DH_AXES = ((1.570796326794897, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                (1.570796326794897, 0.0, 0.0), (-1.570796326794897, 0.0, 0.0), (0.0, 0.0, 0.0))
#: ... and for the stated cylinders of the UR3 and the UR5 (the arm tubes along the link).
_RPY_CYLINDERS = ((0.0, 0.0, 0.0), (0.0, 1.570796326794897, 0.0),
                  (0.0, 1.570796326794897, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                  (0.0, 0.0, 0.0))

_R2 = "UniversalRobots/Universal_Robots_ROS2_Description config/{}/physical_parameters.yaml"
_R1 = "ros-industrial/universal_robot ur_description/config/{}/physical_parameters.yaml"

#: Universal Robots' inertial parameters of the six moving links, as the ROS descriptions
#: publish them ([R2], [R1]; ``source``: the file and its commit, also stored in the tests):
#: ``mass`` in kg; ``cog``, the centre of mass in the ROS link frame, m; ``rpy``, the
#: orientation (roll, pitch, yaw, URDF's fixed axes) of the frame in which ``tensor`` is
#: stated; ``tensor``, the inertia tensor about the centre of mass,
#: ``(ixx, iyy, izz, ixy, ixz, iyz)`` in kg m^2. The numbers are the files' own;
#: :func:`ur_link_inertias_from_ros` turns them into the DH frames of the models
#: (:data:`UR_DYNAMICS`).
UR_PHYSICAL_PARAMETERS = {
    "UR3": {
        "source": _R2.format("ur3") + " @ 2221ec0f (2.4.5, 2024; the same numbers in 2025)",
        "rpy": _RPY_CYLINDERS,
        "mass": (2.0, 3.42, 1.26, 0.8, 0.8, 0.35),
        "cog": ((0.0, 0.0, -0.02), (-0.11365, 0.0, 0.1157), (-0.16325, 0.0, 0.0238),
                (0.0, -0.01, 0.0), (0.0, 0.01, 0.0), (0.0, 0.0, -0.02)),
        "tensor": ((0.008093166666666665, 0.008093166666666665, 0.005625, 0.0, 0.0, 0.0),
                   (0.021728491912499998, 0.021728491912499998, 0.00961875, 0.0, 0.0, 0.0),
                   (0.0065468090625, 0.0065468090625, 0.00354375, 0.0, 0.0, 0.0),
                   (0.0016106414999999998, 0.0016106414999999998, 0.00225, 0.0, 0.0, 0.0),
                   (0.0015721739999999998, 0.0015721739999999998, 0.00225, 0.0, 0.0, 0.0),
                   (0.00013626666666666665, 0.00013626666666666665, 0.0001792, 0.0, 0.0, 0.0))},
    "UR5": {
        "source": _R2.format("ur5") + " @ 2221ec0f (2.4.5, 2024; the same numbers in 2025)",
        "rpy": _RPY_CYLINDERS,
        "mass": (3.7000, 8.3930, 2.33, 1.2190, 1.2190, 0.1879),
        "cog": ((0.0, -0.00193, -0.02561), (-0.2125, 0.0, 0.11336), (-0.24225, 0.0, 0.0265),
                (0.0, -0.01634, -0.0018), (0.0, 0.01634, -0.0018), (0.0, 0.0, -0.001159)),
        "tensor": ((0.014972358333333331, 0.014972358333333331, 0.01040625, 0.0, 0.0, 0.0),
                   (0.13388583541666665, 0.13388583541666665, 0.0151074, 0.0, 0.0, 0.0),
                   (0.031216803515624995, 0.031216803515624995, 0.004095, 0.0, 0.0, 0.0),
                   (0.002013889583333333, 0.002013889583333333, 0.0021942, 0.0, 0.0, 0.0),
                   (0.0018310395833333333, 0.0018310395833333333, 0.0021942, 0.0, 0.0, 0.0),
                   (8.062475833333332e-05, 8.062475833333332e-05, 0.0001321171875, 0.0, 0.0, 0.0))},
    "UR10": {
        "source": _R2.format("ur10") + " @ 2221ec0f (2.4.5, 2024; the same numbers in 2025)",
        "rpy": _RPY_DH_AXES,
        "mass": (7.1, 12.7, 4.27, 2.0, 2.0, 0.365),
        "cog": ((0.021, -0.027, 0.0), (-0.232, 0.0, 0.158), (-0.3323, 0.0, 0.068),
                (0.0, -0.018, 0.007), (0.0, 0.018, -0.007), (0.0, 0.0, -0.026)),
        "tensor": ((0.03408, 0.03529, 0.02156, 0.00002, -0.00425, 0.00008),
                   (0.02814, 0.77068, 0.76943, 0.00005, -0.01561, 0.00002),
                   (0.01014, 0.30928, 0.30646, 0.00008, 0.00916, 0.0),
                   (0.00296, 0.00222, 0.00258, -0.00001, 0.0, -0.00024),
                   (0.00296, 0.00222, 0.00258, -0.00001, 0.0, -0.00024),
                   (0.00040, 0.00041, 0.00034, 0.0, 0.0, 0.0))},
    "UR3e": {
        "source": _R2.format("ur3e") + " @ 9743c966 (2025)", "rpy": _RPY_DH_AXES,
        "mass": (1.98, 3.4445, 1.437, 0.871, 0.805, 0.261),
        "cog": ((0.0, 0.0, -0.02), (-0.11355, 0.0, 0.1157), (-0.1632, 0.0, 0.0238),
                (0.0, -0.01, 0.0), (0.0, 0.01, 0.0), (0.0, 0.0, -0.02)),
        "tensor": ((0.0027657, 0.0021501, 0.0025626, 0.0000096, -0.0000149, 0.0001873),
                   (0.0042623, 0.0460284, 0.0448947, -0.0000409, -0.0014960, -0.0000129),
                   (0.0010511, 0.0113396, 0.0110895, 0.0, -0.0000331, 0.0000022),
                   (0.0008174, 0.0006844, 0.0005497, -0.0000005, 0.0000021, 0.0000617),
                   (0.0006059, 0.0005837, 0.0003831, -0.0000006, -0.0000006, -0.0000271),
                   (0.0001080, 0.0001086, 0.0001371, -0.0000001, -0.0000001, -0.0000002))},
    "UR5e": {
        "source": _R2.format("ur5e") + " @ 3426d674 (2025)", "rpy": _RPY_DH_AXES,
        "mass": (3.761, 8.058, 2.846, 1.37, 1.3, 0.365),
        "cog": ((0.0, -0.00193, -0.02561), (-0.2125, 0.0, 0.11336), (-0.2422, 0.0, 0.0265),
                (0.0, -0.01634, -0.0018), (0.0, 0.01634, -0.0018), (0.0, 0.0, -0.001159)),
        "tensor": ((0.00700210, 0.00648091, 0.00657286, 0.00000073, -0.00001053, 0.00049994),
                   (0.01505885, 0.33388086, 0.33247207, -0.00005400, 0.00000563, -0.00000181),
                   (0.00399632, 0.07879254, 0.07848510, -0.00001365, 0.00137272, -0.00000660),
                   (0.00165491, 0.00135962, 0.00126279, -0.00000282, -0.00000438, 0.00010157),
                   (0.00135617, 0.00127827, 0.00096614, -0.00000274, 0.00000444, -0.00005048),
                   (0.00018694, 0.00018908, 0.00025756, 0.00000006, -0.00000017, -0.00000092))},
    "UR10e": {
        "source": _R2.format("ur10e") + " @ 2221ec0f (2.4.5, 2024; the same numbers in 2025)",
        "rpy": _RPY_DH_AXES,
        "mass": (7.369, 13.051, 3.989, 2.1, 1.98, 0.615),
        "cog": ((0.021, -0.027, 0.0), (-0.2327, 0.0, 0.158), (-0.33155, 0.0, 0.068),
                (0.0, -0.018, 0.007), (0.0, 0.018, -0.007), (0.0, 0.0, -0.026)),
        "tensor": ((0.03408, 0.03529, 0.02156, 0.00002, -0.00425, 0.00008),
                   (0.02814, 0.77068, 0.76943, 0.00005, -0.01561, 0.00002),
                   (0.01014, 0.30928, 0.30646, 0.00008, 0.00916, 0.0),
                   (0.00296, 0.00222, 0.00258, -0.00001, 0.0, -0.00024),
                   (0.00296, 0.00222, 0.00258, -0.00001, 0.0, -0.00024),
                   (0.00040, 0.00041, 0.00034, 0.0, 0.0, 0.0))},
    "UR16e": {
        "source": _R2.format("ur16e") + " @ 2221ec0f (2.4.5, 2024; the same numbers in 2025)",
        "rpy": _RPY_DH_AXES,
        "mass": (7.369, 10.450, 4.321, 2.180, 2.033, 0.907),
        "cog": ((0.0, -0.030, -0.016), (-0.1764, 0.0, 0.16), (-0.166, 0.0, 0.065),
                (0.0, -0.011, -0.009), (0.0, 0.012, -0.018), (0.0, 0.0, -0.044)),
        "tensor": ((0.03351, 0.03374, 0.02100, 0.00002, -0.00001, 0.00374),
                   (0.02796, 0.47558, 0.47635, -0.00010, -0.00720, 0.00003),
                   (0.01091, 0.12060, 0.11714, 0.00006, 0.01012, 0.00001),
                   (0.00609, 0.00245, 0.00579, -0.00001, 0.0, 0.00083),
                   (0.00389, 0.00219, 0.00363, -0.00001, 0.0, -0.00045),
                   (0.00117, 0.00118, 0.00084, 0.0, 0.0, 0.0))},
    "UR15": {
        "source": _R2.format("ur15") + " @ 2cb0bf15 (2025; [R1]'s at 499e728e the same)",
        "rpy": _RPY_DH_AXES,
        "mass": (9.9883, 14.9255, 6.1015, 2.089, 2.0869, 1.0666),
        "cog": ((0.000024, -0.025304, -0.033309), (-0.228491, -0.000083, 0.192787),
                (-0.210929, 0.000019, 0.070552), (0.000025, -0.016413, -0.019695),
                (0.000025, 0.015886, -0.019960), (-0.000018, -0.000112, -0.053397)),
        "tensor": ((0.051334, 0.047702, 0.034263, 0.000025, -0.000016, 0.008805),
                   (0.048202, 1.188499, 1.182771, 0.000232, -0.032135, -0.000017),
                   (0.018481, 0.303502, 0.296843, -0.000005, 0.013601, 0.000003),
                   (0.004339, 0.002548, 0.003912, 0.000019, 0.000001, 0.000706),
                   (0.004288, 0.002566, 0.003927, 0.000017, -0.000003, -0.000716),
                   (0.001406, 0.001404, 0.001002, -0.000003, 0.000010, -0.000024))},
    "UR18": {
        "source": _R2.format("ur18") + " @ 6ffee81d (2025; [R1]'s at f2f8613b the same)",
        "rpy": _RPY_DH_AXES,
        "mass": (9.9883, 14.2009, 5.52, 2.089, 2.0869, 1.0666),
        "cog": ((0.000024, -0.025304, -0.033309), (-0.166336, -0.000088, 0.190204),
                (-0.139248, 0.000021, 0.073101), (0.000025, -0.016413, -0.019695),
                (0.000025, 0.015886, -0.019960), (-0.000018, -0.000112, -0.053397)),
        "tensor": ((0.051334, 0.047702, 0.034263, 0.000025, -0.000016, 0.008805),
                   (0.045094, 0.630805, 0.625724, 0.000179, -0.024705, -0.000020),
                   (0.016891, 0.129732, 0.123451, 0.000000, 0.009081, 0.000003),
                   (0.004339, 0.002548, 0.003912, 0.000019, 0.000001, 0.000706),
                   (0.004288, 0.002566, 0.003927, 0.000017, -0.000003, -0.000716),
                   (0.001406, 0.001404, 0.001002, -0.000003, 0.000010, -0.000024))},
    "UR8 Long": {
        "source": _R1.format("ur8long") + " @ 31e22940 (2025)", "rpy": _RPY_DH_AXES,
        "mass": (9.9883, 17.0738, 7.6393, 2.089, 2.0869, 1.0666),
        "cog": ((0.000024, -0.025304, -0.033309), (-0.333471, -0.000074, 0.195420),
                (-0.298798, 0.000058, 0.065663), (0.000025, -0.016413, -0.019695),
                (0.000025, 0.015886, -0.019960), (-0.000018, -0.000112, -0.053397)),
        "tensor": ((0.051334, 0.047702, 0.034263, 0.000025, -0.000016, 0.008805),
                   (0.056709, 2.440120, 2.432744, 0.000292, -0.054852, -0.000014),
                   (0.022148, 0.633274, 0.625889, 0.000052, 0.019779, 0.000003),
                   (0.004339, 0.002548, 0.003912, 0.000019, 0.000001, 0.000706),
                   (0.004288, 0.002566, 0.003927, 0.000017, -0.000003, -0.000716),
                   (0.001406, 0.001404, 0.001002, -0.000003, 0.000010, -0.000024))},
    "UR20": {
        "source": _R2.format("ur20") + " @ 2221ec0f (2.4.5, 2024; the same numbers in 2025)",
        "rpy": _RPY_DH_AXES,
        "mass": (16.343, 29.632, 7.879, 3.054, 3.126, 0.926),
        "cog": ((0.0, -0.0062, -0.061), (-0.3394, 0.0, 0.2098), (-0.4053, 0.0, 0.0604),
                (0.0, -0.0393, -0.0026), (0.0, 0.0379, -0.0024), (0.0, 0.0, -0.0293)),
        "tensor": ((0.08866, 0.07632, 0.08418, -0.00011, -0.00011, 0.00720),
                   (0.14670, 4.66590, 4.63480, 0.00019, -0.05163, 0.00004),
                   (0.02612, 0.75763, 0.75327, -0.00005, -0.02898, -0.00001),
                   (0.00555, 0.00537, 0.00402, -0.00001, -0.00002, 0.00036),
                   (0.00586, 0.00578, 0.00427, -0.00001, -0.00002, -0.00037),
                   (0.00092, 0.00091, 0.00117, 0.0, 0.0, 0.0))},
    "UR30": {
        "source": _R2.format("ur30") + " @ 2221ec0f (2.4.5, 2024; the same numbers in 2025)",
        "rpy": _RPY_DH_AXES,
        "mass": (16.343, 28.542, 7.156, 3.054, 3.126, 0.926),
        "cog": ((-0.0001, -0.0069, -0.06), (-0.2476, 0.0, 0.2103), (-0.278, 0.0, 0.0629),
                (0.0, -0.0353, -0.0048), (0.0, 0.0341, -0.0046), (0.0, 0.0, -0.0293)),
        "tensor": ((0.03351, 0.03374, 0.02100, 0.00002, -0.00001, 0.00374),
                   (0.02796, 0.47558, 0.47635, -0.00010, -0.00720, 0.00003),
                   (0.01091, 0.12060, 0.11714, 0.00006, 0.01012, 0.00001),
                   (0.00609, 0.00245, 0.00579, -0.00001, 0.0, 0.00083),
                   (0.00389, 0.00219, 0.00363, 0.00001, 0.0, -0.00045),
                   (0.00117, 0.00118, 0.00084, 0.0, 0.0, 0.0))},
}
UR_PHYSICAL_PARAMETERS["UR7e"] = dict(UR_PHYSICAL_PARAMETERS["UR5e"],
                                      source=_R2.format("ur7e") + " @ 305c5cef (2025)")
UR_PHYSICAL_PARAMETERS["UR12e"] = dict(UR_PHYSICAL_PARAMETERS["UR10e"],
                                       source=_R2.format("ur12e") + " @ 9743c966 (2025)")

#: How far apart (m, largest coordinate at sample joint vectors) the flanges of two
#: descriptions of one arm may be in :func:`with_model_inertias`: a calibration moves them
#: by millimetres, the links of two different arms are centimetres to metres apart.
_SAME_ARM = 0.02

#: Published tensors the models do not take (see the module docstring, note 4), and why.
_TENSORS_NOT_TAKEN = {
    "UR30": "the UR16e's tensors copied (one sign apart), too small for the UR30's links"}


def ur_link_inertias(masses: ArrayLike, centres_of_mass: ArrayLike,
                     tensors: ArrayLike | None = None, *, a: ArrayLike | None = None,
                     radius: float = 0.075) -> tuple[LinkInertia, ...]:
    r"""The six link inertias of a UR arm from a table of masses and centres of mass.

    The table is in the standard-DH link frames (the frames of :func:`ur3`), as
    :data:`UR_DYNAMICS` holds it; the inertia tensors about the centres of mass, when given,
    in the axes of the same frames. This helper turns such a table into
    :class:`~dqlab.inertia.LinkInertia` objects for ``Link(..., inertia=...)``.

    Parameters
    ----------
    masses : array_like, shape (6,)
        kg.
    centres_of_mass : array_like, shape (6, 3)
        m, link :math:`i`'s in DH frame :math:`i`.
    tensors : array_like, shape (6, 6) or (6, 3, 3), optional
        Inertia tensors about the centres of mass in the axes of the DH frames, rows
        ``(ixx, iyy, izz, ixy, ixz, iyz)`` or 3x3 matrices, kg m^2. When they are not given,
        a stated approximation after the cylinders of Universal Robots' ROS description:
        every link a solid cylinder of radius ``radius`` centred on its centre of mass, the
        upper arm and the forearm (links 2 and 3) along the link (the DH :math:`x` axis) with
        the lengths
        :math:`\lvert a_2\rvert, \lvert a_3\rvert` (``a`` must then be given), the four joint
        housings (links 1, 4, 5 and 6) along their own joint's axis with the length
        :math:`2r`.
    a : array_like, shape (6,), optional
        The DH link lengths, needed only without ``tensors``.
    radius : float, optional
        The cylinders' radius in m, only without ``tensors``.

    Returns
    -------
    tuple of LinkInertia

    Raises
    ------
    TypeError, ValueError
        Naming the argument: not real numbers of its shape, NaN or infinity, a negative
        mass or radius, ``a`` missing without ``tensors``; a row of the table that is no
        rigid body (a tensor that is not symmetric, has a negative principal moment or breaks
        the triangle inequality) or whose inertia overflows, naming the link.

    Examples
    --------
    >>> p = UR_DYNAMICS["UR3"]
    >>> inertias = ur_link_inertias(p["mass"], p["com"], p["tensor"])
    >>> round(sum(I.mass for I in inertias), 6)      # kg, the six moving links of the UR3
    8.63
    >>> approx = ur_link_inertias(p["mass"], p["com"], a=UR_DH["UR3"]["a"])
    >>> approx[1].tensor.diagonal().round(6)     # the upper arm: the table's first row
    array([0.009619, 0.021728, 0.021728])
    """
    masses = _table(masses, "masses", (6,))
    wrong = np.flatnonzero(masses < 0.0)
    if wrong.size:
        raise ValueError(f"masses must be >= 0, got {float(masses[wrong[0]])!r} kg for link "
                         f"{wrong[0] + 1}")
    coms = _table(centres_of_mass, "centres_of_mass", (6, 3))
    a = None if a is None else _table(a, "a", (6,))
    radius = check_scalar(radius, "radius", minimum=0.0)
    if tensors is None:
        if a is None:
            raise ValueError("without tensors, give the DH lengths a for the cylinders")
        # the axis of each cylinder in its DH frame: along x for the upper arm and the
        # forearm; along the joint's own axis for the housings (z_{i-1} seen from frame i:
        # y for links 1, 4 and 5, whose twist alpha is +-pi/2, z for link 6)
        axes = np.array([[0, 1, 0], [1, 0, 0], [1, 0, 0], [0, 1, 0], [0, 1, 0], [0, 0, 1.0]])
        lengths = [2 * radius, abs(a[1]), abs(a[2]), 2 * radius, 2 * radius, 2 * radius]
        return _bodies(lambda m, c, u, h: LinkInertia.rod(m, c - 0.5 * h * u, c + 0.5 * h * u,
                                                          radius),
                       zip(masses, coms, axes, lengths, strict=True),
                       "masses, centres_of_mass, a and radius")
    tensors = as_float_array(tensors, "tensors")
    if tensors.shape not in ((6, 6), (6, 3, 3)):
        raise ValueError(f"tensors must have shape (6, 6) or (6, 3, 3), got {tensors.shape}")
    return _bodies(LinkInertia, zip(masses, coms, tensors, strict=True),
                   "masses, centres_of_mass and tensors")


def _table(value, name, shape):
    """A table of finite numbers of the given ``shape``, or an error naming ``name``."""
    table = as_float_array(value, name)
    if table.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got shape {table.shape}")
    return table


def _bodies(make, rows, names):
    """``make(*row)`` of each link's row, as a tuple; a ValueError naming the link and
    ``names`` (the arguments its row comes from) when the row is no rigid body."""
    bodies = []
    for i, row in enumerate(rows):
        try:
            bodies.append(make(*row))
        except ValueError as exc:
            raise ValueError(f"link {i + 1} of {names}: {exc}") from None
    return tuple(bodies)


def _quarter_turns(R):
    """``R`` with entries within 1e-12 of an integer snapped to it: the files write the
    quarter turns of their frames as 1.570796326794897, whose cosine is 3e-16, not 0."""
    return np.where(np.abs(R - np.round(R)) < 1e-12, np.round(R), R)


def ur_link_inertias_from_ros(mass: ArrayLike, cog: ArrayLike, rpy: ArrayLike,
                              tensor: ArrayLike, a: ArrayLike) -> tuple[LinkInertia, ...]:
    r"""The six link inertias of a UR arm in its DH frames, from the physical parameters of
    Universal Robots' ROS description (``physical_parameters.yaml``; see
    :data:`UR_PHYSICAL_PARAMETERS`).

    The ROS description states link :math:`i`'s centre of mass :math:`\mathbf c_R` in its
    ROS link frame :math:`R_i` (on joint :math:`i`'s axis, the frame the joint turns), and its
    inertia tensor :math:`I_F` about the centre of mass in a frame turned by ``rpy`` (URDF's
    ``<inertial><origin rpy>``, :math:`R_{RF} = R_z(\text{yaw}) R_y(\text{pitch})
    R_x(\text{roll})`). The models' link frame is DH frame :math:`i` (on the next joint's
    axis). Following the joint origins of the description's ``default_kinematics.yaml``
    (from the same DH table) link by link, the two frames of one link are related by the
    constant transform

    .. math::

        X_{D_1R_1} = R_x(-\tfrac\pi2),\quad X_{D_2R_2} = T_x(-a_2),\quad
        X_{D_3R_3} = T_x(-a_3),\quad X_{D_4R_4} = R_x(-\tfrac\pi2),\quad
        X_{D_5R_5} = R_x(\tfrac\pi2),\quad X_{D_6R_6} = I

    (ROS's upper arm and forearm frames sit at the near end of the tube, the DH frames at the
    far end; the wrist 3 frames coincide, as do ROS's ``base_link_inertia`` and DH frame 0).
    So, with :math:`X_{D_iR_i} = (R, \mathbf t)`,

    .. math::

        \mathbf c = R\,\mathbf c_R + \mathbf t, \qquad I_c = (R R_{RF})\, I_F\, (R R_{RF})^\top .

    Quarter turns are exact (see ``_quarter_turns``). The tests check the result
    frame-independently against the files read as a joint chain (centres of mass and
    principal moments seen from the base, gravity torques by pinocchio).

    Parameters
    ----------
    mass : array_like, shape (6,)
        kg.
    cog : array_like, shape (6, 3)
        The centres of mass in the ROS link frames, m.
    rpy : array_like, shape (6, 3)
        Roll, pitch, yaw of each tensor's frame in its link frame, rad.
    tensor : array_like, shape (6, 6)
        Rows ``(ixx, iyy, izz, ixy, ixz, iyz)``, kg m^2.
    a : array_like, shape (6,)
        The arm's DH lengths (:math:`a_2, a_3` place the ROS frames of the tubes).

    Returns
    -------
    tuple of LinkInertia
        In the DH frames of :func:`ur3` and the other UR models.

    Examples
    --------
    The UR5e's upper arm: its centre of mass 0.2125 m from the shoulder axis, that is
    0.2125 m short of the elbow, where its DH frame is.

    >>> p = UR_PHYSICAL_PARAMETERS["UR5e"]
    >>> inertias = ur_link_inertias_from_ros(p["mass"], p["cog"], p["rpy"], p["tensor"],
    ...                                      UR_DH["UR5e"]["a"])
    >>> p["cog"][1], inertias[1].com.round(6).tolist()
    ((-0.2125, 0.0, 0.11336), [0.2125, 0.0, 0.11336])
    """
    mass = _table(mass, "mass", (6,))
    cog = _table(cog, "cog", (6, 3))
    rpy = _table(rpy, "rpy", (6, 3))
    tensor = _table(tensor, "tensor", (6, 6))
    a = _table(a, "a", (6,))
    turn_down = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])        # R_x(-pi/2)
    turns = (turn_down, np.eye(3), np.eye(3), turn_down, turn_down.T, np.eye(3))
    shifts = (np.zeros(3), np.array([-a[1], 0, 0]), np.array([-a[2], 0, 0]),
              np.zeros(3), np.zeros(3), np.zeros(3))
    inertias = []
    for i in range(6):
        ixx, iyy, izz, ixy, ixz, iyz = tensor[i]
        I_F = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        R = turns[i] @ _quarter_turns(matrix_from_rpy(rpy[i]))
        inertias.append(LinkInertia(mass[i], turns[i] @ cog[i] + shifts[i], R @ I_F @ R.T))
    return tuple(inertias)


def _dynamics_table(name):
    """:data:`UR_DYNAMICS`' entry of one model, from its published parameters."""
    p = UR_PHYSICAL_PARAMETERS[name]
    inertias = ur_link_inertias_from_ros(p["mass"], p["cog"], p["rpy"], p["tensor"],
                                         UR_DH[name]["a"])
    table = {"mass": tuple(I.mass for I in inertias),
             "com": tuple(tuple(I.com.tolist()) for I in inertias)}
    if name not in _TENSORS_NOT_TAKEN:
        table["tensor"] = tuple(tuple(float(I.tensor[i, j]) for i, j in
                                      ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)))
                                for I in inertias)
    return table


#: The inertial parameters the UR models carry, in their standard-DH link frames: ``mass``
#: in kg, ``com`` (centre of mass) in m, ``tensor`` about the centre of mass in the axes of
#: the link frame, ``(ixx, iyy, izz, ixy, ixz, iyz)`` in kg m^2 -- Universal Robots'
#: published numbers (:data:`UR_PHYSICAL_PARAMETERS`) moved into these frames by
#: :func:`ur_link_inertias_from_ros` (for the e-series and the UR10 the tensors are the
#: files' own numbers: their inertial frames are the DH axes). Without ``tensor`` (the
#: UR30), :func:`ur_link_inertias` gives the links its stated cylinders.
UR_DYNAMICS = {name: _dynamics_table(name) for name in UR_PHYSICAL_PARAMETERS}


def _ur(name, label):
    p = UR_DH[name]
    dynamics = UR_DYNAMICS[name]
    inertias = ur_link_inertias(dynamics["mass"], dynamics["com"], dynamics.get("tensor"),
                                a=p["a"])
    speeds = [math.radians(v) for v in UR_MAX_JOINT_SPEED_DEG[name]] \
        if name in UR_MAX_JOINT_SPEED_DEG else [None] * 6
    torques = UR_MAX_JOINT_TORQUE.get(name, (None,) * 6)
    ranges = [math.radians(v) for v in UR_JOINT_RANGE_DEG[name]]
    links = [Link(a=a, alpha=alpha, d=d, limits=(-r, r), inertia=inertia, max_speed=speed,
                  max_torque=torque)
             for a, alpha, d, r, inertia, speed, torque in zip(
                 p["a"], UR_ALPHA, p["d"], ranges, inertias, speeds, torques, strict=True)]
    return Robot(links, convention="dh", name=label)


def rod_link_inertias(robot: Robot, *, base_mass: float = 0.5, mass_per_metre: float = 4.0,
                      radius: float = 0.03) -> tuple[LinkInertia, ...]:
    r"""Plausible inertias for a chain whose maker gives none: every link a uniform rod.

    The constant path of link :math:`i` runs from its own joint's axis to the next joint's
    frame: in standard DH from :math:`(-a_i, 0, 0)` (the foot of the common normal on joint
    :math:`i`'s axis) through the origin of frame :math:`i` to :math:`(0, 0, d_{i+1})`; in
    modified DH from the origin of frame :math:`i` (on joint :math:`i`'s axis) through
    :math:`(a_i, 0, 0)` to the next frame's origin :math:`(a_i, -r_{i+1}\sin\alpha_i,
    r_{i+1}\cos\alpha_i)` (the constant :math:`d` of a prismatic joint stands for its
    offset). The link is a solid cylinder of radius ``radius`` along the straight line
    between the two ends (along its joint axis, of length :math:`2r`, if they coincide), of
    mass ``base_mass + mass_per_metre * path length``: 0.5 kg plus 4 kg per metre by default.
    This is a stated approximation, not a measurement.

    Parameters
    ----------
    robot : Robot
    base_mass, mass_per_metre, radius : float, optional
        Numbers >= 0 (kg, kg/m, m).

    Returns
    -------
    tuple of LinkInertia
        One per link, in the link frames of the robot's convention.

    Raises
    ------
    TypeError
        If ``robot`` is not a :class:`~dqlab.robot.Robot`.
    ValueError
        If a number is text, a boolean, negative, NaN or infinite (the message names it).

    Examples
    --------
    >>> [round(I.mass, 3) for I in rod_link_inertias(desk_arm())]
    [0.768, 1.076, 1.148]
    """
    check_instance(robot, Robot, "robot")
    base_mass = check_scalar(base_mass, "base_mass", minimum=0.0)
    mass_per_metre = check_scalar(mass_per_metre, "mass_per_metre", minimum=0.0)
    radius = check_scalar(radius, "radius", minimum=0.0)
    links = robot.links
    inertias = []
    for i, lk in enumerate(links):
        nxt = links[i + 1] if i + 1 < len(links) else None
        if robot.convention == "dh":
            start, corner = np.array([-lk.a, 0.0, 0.0]), np.zeros(3)
            end = np.array([0.0, 0.0, nxt.d if nxt is not None else 0.0])
            axis = np.array([0.0, math.sin(lk.alpha), math.cos(lk.alpha)])
        else:
            start, axis = np.zeros(3), np.array([0.0, 0.0, 1.0])
            if nxt is None:
                corner = end = np.zeros(3)
            else:
                corner = np.array([nxt.a, 0.0, 0.0])
                end = corner + nxt.d * np.array([0.0, -math.sin(nxt.alpha),
                                                 math.cos(nxt.alpha)])
        path = math.hypot(*(corner - start)) + math.hypot(*(end - corner))   # no overflow
        if math.hypot(*(end - start)) < 1e-9:
            start, end = start - radius * axis, start + radius * axis
        try:
            inertias.append(LinkInertia.rod(base_mass + mass_per_metre * path, start, end,
                                            radius))
        except ValueError as exc:
            raise ValueError(f"link {i + 1} of the robot, a rod of {path:g} m: base_mass + "
                             f"mass_per_metre x length and radius give no finite inertia "
                             f"({exc})") from None
    return tuple(inertias)


def with_model_inertias(robot: Robot, model: Robot) -> Robot:
    r"""``robot`` -- the arm of ``model`` described by other DH parameters, a calibrated UR
    -- carrying ``model``'s link inertias, moved into its own link frames.

    A link is one body in both descriptions, but its frame is not at the same place on it: a
    real calibration moves the DH frames of the nearly parallel joints 2 to 4 by metres along
    their axes (:mod:`dqlab.ur.calibration`), so the model's centres of mass, copied as
    numbers, would sit metres away from the arm. At the joints' zero the two descriptions
    put each link at the same place (to the calibration's millimetre), so link :math:`i`'s
    frame of ``model`` sits at the constant pose
    :math:`X_i = X^{robot}_{0i}(0)^{-1}\,X^{model}_{0i}(0)` in its frame of ``robot``, and its
    inertia moves by :meth:`~dqlab.inertia.LinkInertia.moved` (as :func:`ur3_mdh` carries
    the UR3's into the report's frames). Links of ``model`` without inertia stay without.

    Parameters
    ----------
    robot, model : Robot
        Two descriptions of one arm: the same number of joints, and flanges (bases and tools
        left out) within 2 cm of each other at sample joint vectors.

    Returns
    -------
    Robot
        ``robot`` with these inertias (everything else kept).

    Raises
    ------
    TypeError
        If ``robot`` or ``model`` is not a :class:`~dqlab.robot.Robot`.
    ValueError
        If they are not two descriptions of one arm (the message names both): the links of
        another arm would be carried to places they do not have.

    Examples
    --------
    A UR3 whose frames 2 and 3 moved 12 m along their axes, as real calibrations do: the
    gravity torques are the model's, not those of an arm 12 m long.

    >>> import numpy as np
    >>> d = list(UR_DH["UR3"]["d"]); d[1], d[2] = 12.0, -12.0
    >>> far = Robot.from_dh_table(d=d, a=UR_DH["UR3"]["a"], alpha=UR_ALPHA)
    >>> q = np.array([0.3, -1.0, 0.8, -1.2, 0.5, 0.1])
    >>> from dqlab.dynamics import gravity_torques
    >>> bool(np.allclose(gravity_torques(with_model_inertias(far, ur3()), q),
    ...                  gravity_torques(ur3(), q), atol=1e-9))
    True
    """
    check_instance(robot, Robot, "robot")
    check_instance(model, Robot, "model")
    if robot.n != model.n:
        raise ValueError(f"robot and model must have as many joints, got {robot.n} and "
                         f"{model.n}")
    gap = _flange_gap(robot, model)
    if not gap <= _SAME_ARM:
        raise ValueError(f"robot and model must describe one arm: their flanges are {gap:.3g} m "
                         f"apart at sample joint vectors (at most {_SAME_ARM:g} m)")
    zero = np.zeros(robot.n)
    mine = np.linalg.inv(robot.base) @ robot.fk(zero, all_frames=True)
    theirs = np.linalg.inv(model.base) @ model.fk(zero, all_frames=True)
    inertias = []
    for i, link in enumerate(model.links, start=1):
        X = np.linalg.inv(mine[i]) @ theirs[i]
        X[3] = (0.0, 0.0, 0.0, 1.0)
        inertias.append(None if link.inertia is None else link.inertia.moved(X))
    return _with_inertias(robot, inertias)


def _flange_gap(robot, model):
    """The largest distance between the flanges of ``robot`` and ``model`` (bases and tools
    left out) at 16 joint vectors drawn within ``robot``'s limits (clipped to one turn)."""
    lo, hi = np.clip(robot.limits, -PI, PI).T
    q = lo + (hi - lo) * np.random.default_rng(5).uniform(size=(16, robot.n))
    bare = [Robot(r.links, convention=r.convention) for r in (robot, model)]
    with np.errstate(over="ignore", invalid="ignore"):
        gap = bare[0].fk(q)[:, :3, 3] - bare[1].fk(q)[:, :3, 3]
        return float(np.max(np.abs(gap)))


def _with_inertias(robot, inertias):
    """The robot with every link carrying its inertia (a new Robot, nothing else changed)."""
    links = [lk.with_inertia(inertia) for lk, inertia in zip(robot.links, inertias,
                                                               strict=True)]
    return Robot(links, convention=robot.convention, base=robot.base, tool=robot.tool,
                 name=robot.name)


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
    foot of the first joint's axis, z up. Joint limits are :math:`\pm 2\pi`, but wrist 3
    turns without limit (:data:`UR_JOINT_RANGE_DEG`); the joints' rated speeds
    (:data:`UR_MAX_JOINT_SPEED_DEG`) and torques (:data:`UR_MAX_JOINT_TORQUE`) are the links'
    ``max_speed`` and ``max_torque``, Universal Robots' inertial parameters
    (:data:`UR_DYNAMICS`) their ``inertia``; the sources are in the module docstring. These
    are also
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


# --------------------------------------------------------------------------------------
# The current UR models: e-series, UR15, UR18, UR8 Long, UR20, UR30


def ur3e() -> Robot:
    r"""The Universal Robots UR3e with the maker's standard DH parameters.

    :math:`d_1 = 0.15185`, :math:`a_2 = -0.24355`, :math:`a_3 = -0.2132`,
    :math:`d_4 = 0.13105`, :math:`d_5 = 0.08535`, :math:`d_6 = 0.0921` m, the twists of
    :data:`UR_ALPHA`, and the conventions of :func:`ur3` (those of ``ur_analytic_ik``): no
    tool, base at the foot of joint 1, limits :math:`\pm 2\pi` (wrist 3 of the UR3e without
    limit, :data:`UR_JOINT_RANGE_DEG`). Source: :data:`UR_CURRENT_DH`. Every current model is
    built the same way; its links carry the inertias of :data:`UR_DYNAMICS`, and the rated
    speeds of :data:`UR_MAX_JOINT_SPEED_DEG` and torques of :data:`UR_MAX_JOINT_TORQUE`
    (none published for the UR8 Long); the sources of every number are in the module
    docstring.

    Returns
    -------
    Robot

    Examples
    --------
    At :math:`q = 0` the flange is at :math:`(a_2 + a_3,\ -d_4 - d_6,\ d_1 - d_5)`:

    >>> ur3e().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-0.45675, -0.22315,  0.0665 ])
    """
    return _ur("UR3e", "UR3e")


def ur5e() -> Robot:
    """The Universal Robots UR5e (since 2025 also sold as the UR7e), with the maker's
    standard DH parameters (see :func:`ur3e` and :data:`UR_CURRENT_DH`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur5e().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-0.8172, -0.2329,  0.0628])
    """
    return _ur("UR5e", "UR5e")


def ur7e() -> Robot:
    """The Universal Robots UR7e: the UR5e under its 2025 name (see :func:`ur5e`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur7e().name, bool((ur7e().fk([0.1] * 6) == ur5e().fk([0.1] * 6)).all())
    ('UR7e', True)
    """
    return _ur("UR7e", "UR7e")


def ur10e() -> Robot:
    """The Universal Robots UR10e (since 2025 also sold as the UR12e), with the maker's
    standard DH parameters (see :func:`ur3e` and :data:`UR_CURRENT_DH`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur10e().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-1.18425, -0.2907 ,  0.06085])
    """
    return _ur("UR10e", "UR10e")


def ur12e() -> Robot:
    """The Universal Robots UR12e: the UR10e under its 2025 name (see :func:`ur10e`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur12e().name, bool((ur12e().fk([0.1] * 6) == ur10e().fk([0.1] * 6)).all())
    ('UR12e', True)
    """
    return _ur("UR12e", "UR12e")


def ur16e() -> Robot:
    """The Universal Robots UR16e with the maker's standard DH parameters (see
    :func:`ur3e` and :data:`UR_CURRENT_DH`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur16e().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-0.8384 , -0.2907 ,  0.06085])
    """
    return _ur("UR16e", "UR16e")


def ur15() -> Robot:
    """The Universal Robots UR15 with the maker's standard DH parameters (see
    :func:`ur3e` and :data:`UR_CURRENT_DH`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur15().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-1.1639, -0.3258,  0.0825])
    """
    return _ur("UR15", "UR15")


def ur18() -> Robot:
    """The Universal Robots UR18 with the maker's standard DH parameters (see
    :func:`ur3e` and :data:`UR_CURRENT_DH`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur18().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-0.8139, -0.3258,  0.0825])
    """
    return _ur("UR18", "UR18")


def ur8_long() -> Robot:
    """The Universal Robots UR8 Long with the maker's standard DH parameters (see
    :func:`ur3e` and :data:`UR_CURRENT_DH`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur8_long().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-1.6138, -0.3258,  0.0825])
    """
    return _ur("UR8 Long", "UR8 Long")


def ur20() -> Robot:
    """The Universal Robots UR20 with the maker's standard DH parameters (see
    :func:`ur3e` and :data:`UR_CURRENT_DH`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur20().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-1.5907, -0.3553,  0.077 ])
    """
    return _ur("UR20", "UR20")


def ur30() -> Robot:
    """The Universal Robots UR30 with the maker's standard DH parameters (see
    :func:`ur3e` and :data:`UR_CURRENT_DH`).

    Returns
    -------
    Robot

    Examples
    --------
    >>> ur30().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(5)
    array([-1.1407, -0.3553,  0.077 ])
    """
    return _ur("UR30", "UR30")


#: The function of :mod:`dqlab.models` that builds each UR model, by the model's name (as
#: the controller and :data:`UR_DH` spell it).
UR_MODELS = {"UR3": ur3, "UR5": ur5, "UR10": ur10, "UR3e": ur3e, "UR5e": ur5e, "UR7e": ur7e,
             "UR10e": ur10e, "UR12e": ur12e, "UR16e": ur16e, "UR15": ur15, "UR18": ur18,
             "UR8 Long": ur8_long, "UR20": ur20, "UR30": ur30}


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
    report = Robot(links, convention="mdh", name="UR3 (report, modified DH)")
    return _with_inertias(report, _ur3_mdh_inertias(report))


#: The map from the UR3 report's joint angles to UR's (chapter 6):
#: :math:`q_{UR} = S\,q_{report} + o`, with UR's base frame a quarter turn,
#: :math:`R_z(\pi/2)`, from the report's.
UR3_MDH_JOINT_MAP = ((1.0, -1.0, -1.0, -1.0, 1.0, 1.0), (0.0, 0.0, 0.0, -PI / 2, PI, -PI / 2))


def _ur3_mdh_inertias(report):
    r"""UR's link inertias (:data:`UR_DYNAMICS`) carried into the report's link frames.

    Link :math:`i` is the same body in both models, so its report frame sits at a constant
    pose in its DH frame, :math:`X_i = X^{UR}_{0i}(S q + o)^{-1} R_z(\pi/2)\, X^{rep}_{0i}(q)`,
    read at :math:`q = 0`. The rotation is a signed permutation (rounded to it); the
    translation carries the few millimetres by which the report's lengths differ from UR's.
    """
    ur = ur3()
    S, o = (np.array(v) for v in UR3_MDH_JOINT_MAP)
    q = np.zeros(6)
    F_ur = ur.fk(S * q + o, all_frames=True)
    F_rep = report.fk(q, all_frames=True)
    turn = np.eye(4)
    turn[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
    inertias = []
    for i, link in enumerate(ur.links, start=1):
        X_ur_rep = np.linalg.inv(F_ur[i]) @ turn @ F_rep[i]
        X_ur_rep[:3, :3] = np.round(X_ur_rep[:3, :3])
        inertias.append(link.inertia.moved(np.linalg.inv(X_ur_rep)))
    return inertias


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
    arm = Robot(links, convention="dh", name="desktop arm (lab report)")
    return _with_inertias(arm, rod_link_inertias(arm))


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
    scara = Robot(links, convention="mdh", name="Samsung RSM-5 SCARA")
    return _with_inertias(scara, rod_link_inertias(scara))


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

    Raises
    ------
    ValueError
        If a length is not a finite number (text and booleans included; the message names
        it), or so large that the links' inertias overflow.

    Examples
    --------
    >>> six_r().fk([0, 0, 0, 0, 0, 0])[:3, 3].round(6) + 0.0
    array([ 0.4 ,  0.  , -0.45])
    """
    a2, r4, r7 = (check_scalar(x, name) for x, name in ((a2, "a2"), (r4, "r4"), (r7, "r7")))
    alpha = (0.0, PI / 2, 0.0, PI / 2, -PI / 2, PI / 2)
    a = (0.0, 0.0, a2, 0.0, 0.0, 0.0)
    r = (0.0, 0.0, 0.0, r4, 0.0, 0.0)
    links = [Link(a=ai, alpha=al, d=ri, limits=(-PI, PI))
             for al, ai, ri in zip(alpha, a, r, strict=True)]
    tool = np.eye(4)
    tool[2, 3] = r7
    arm = Robot(links, convention="mdh", tool=tool, name="6R with spherical wrist")
    return _with_inertias(arm, rod_link_inertias(arm))


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
            Tolerance of the comparisons (lengths in metres, angles in radians), a finite
            number >= 0.

        Raises
        ------
        TypeError
            If ``robot`` is not a :class:`~dqlab.robot.Robot`.
        ValueError
            If ``atol`` is not a finite number >= 0, or the robot does not have the shape.
        """
        check_instance(robot, Robot, "robot")
        atol = check_scalar(atol, "atol", minimum=0.0)
        problem = self._difference(robot, atol)
        if problem:
            raise ValueError(f"{self.label} needs {self.description}; {problem}")

    def _difference(self, robot, atol):
        links = robot.links
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
                    return (f"link {i + 1} has {name} = {getattr(links[i], name)!r}, zero "
                            f"within atol = {atol:g}")
        return ""


#: The UR family (UR3, UR5, UR10, e-series) for :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`.
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
