"""The bad-input sweep of the models and their exports: dynamics and link inertias, the UR
family and its calibration (the readers, the controller's message, the stand-in's
calibration), the closed-form IK of calibrated arms and the closest solutions, robots from a
maker's table and their tools, the uArm's G-code and the URDF/MJCF exports.

Every public callable of ``dqlab.dynamics``, ``dqlab.inertia``, ``dqlab.models``,
``dqlab.desk_arm_firmware``, ``dqlab.sim.mjcf``, ``dqlab.sim.urdf``, ``dqlab.ur.calibration``,
the solution pickers of ``dqlab.ik`` and ``dqlab.ik.ur_calibrated_reference`` is here or in
another sweep (the last test checks it), each argument with every bad value of its kind
(``tests/_sweep.py``) and the kinds these modules meet: far targets (1e100 to 1e300 m),
limits that are not limits, booleans and numbers as text, integers beyond 32 or 64 bits,
text that XML or G-code cannot carry, robots with a massless or point-mass link, corrupt,
huge, deeply nested or self-referencing files, and a failed write over an existing file.
What a call returns is checked, not only its finiteness: IK rows marked valid reach their
target, chosen joints lie within the limits, G-code holds only firmware commands, URDF
parses and MJCF loads in MuJoCo.
"""

import functools
import math
import re
import socket
import threading
from xml.etree import ElementTree

import numpy as np
import pytest
from _sweep import (
    A,
    F,
    Fine,
    Flag,
    Int,
    Name,
    O,
    P,
    Registry,
    S,
    T,
    joints_reach_target,
    numbers_finite,
    reaches_target,
    sweep_test,
    warm_ik_batches,
)
from test_ur_calibration import _conf_text, _deltas, dh_origins, ros_yaml

import dqlab
from dqlab import desk_arm_firmware, dynamics, ik, models
from dqlab import pick_place as pp
from dqlab.ik.ur_calibrated_reference import calibrated_ur_reference, newton_step
from dqlab.inertia import LinkInertia
from dqlab.robot import Link, Robot
from dqlab.sim import mjcf, urdf
from dqlab.ur import ControllerStandIn, calibration
from dqlab.ur.calibration import CalibrationConf, KinematicsInfo

UR3 = models.ur3()
UR5E = models.ur5e()
Q6 = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
X_TARGET = UR5E.fk(Q6)
GRAVITY = [0.0, 0.0, -9.81]
DH5E = {"d": [lk.d for lk in UR5E.links], "a": [lk.a for lk in UR5E.links],
        "alpha": [lk.alpha for lk in UR5E.links]}
TOOL = dqlab.transform_from(dqlab.rot_z(0.4), [0.01, 0.0, 0.15])
BODY = LinkInertia.rod(1.5, [0.0, 0.0, 0.0], [0.2, 0.0, 0.0], radius=0.03)


def _with_link(robot, i, inertia, name=None):
    links = list(robot.links)
    links[i] = links[i].with_inertia(inertia)
    return Robot(links, convention=robot.convention, base=robot.base, tool=robot.tool,
                 name=robot.name if name is None else name)


# A calibrated UR5e: its joint origins moved by millimetres, written in standard DH as a
# controller writes it (the far common normals of its parallel axes).
_rng = np.random.default_rng(39)
_origins = dh_origins(UR5E)
for _i in range(1, 6):
    _P = np.eye(4)
    _P[:3, :3] = dqlab.rot_x(_rng.uniform(-2e-3, 2e-3)) @ dqlab.rot_z(_rng.uniform(-2e-3, 2e-3))
    _P[:3, 3] = _rng.uniform(-2e-3, 2e-3, 3)
    _origins[_i] = _origins[_i] @ _P
CALIBRATED = calibration.robot_from_joint_origins(_origins, name="UR5e (calibrated)")
X_CALIBRATED = CALIBRATED.fk(Q6)
INFO = calibration.kinematics_info_from_robot(CALIBRATED, checksum=(1, 2, 3, 4, 5, 6))
MESSAGE = calibration.message_from_kinematics_info(INFO)
CONF = CalibrationConf(**{k: tuple(v) for k, v in _deltas(CALIBRATED, UR5E).items()},
                       joint_checksum=(1, 2, 3, 4, 5, 6), calibration_status=2)
RESULT = ik.ur(UR5E, X_TARGET)
LIMITS = UR5E.limits

#: Robots at the edge of what dynamics and exports can use. A massless last link, or a point
#: mass on the last joint's axis, leaves that joint nothing to move: the mass matrix is
#: singular (forward dynamics must refuse it, MuJoCo refuses such a body); a link of 1e300 kg
#: and a robot without link inertias (the plausible rods are used) are valid.
MASSLESS = _with_link(UR3, 5, LinkInertia(0.0, [0.0, 0.0, 0.01]))
POINT_MASS = _with_link(UR3, 5, LinkInertia.sphere(0.35, [0.0, 0.0, 0.01]))
HEAVY = _with_link(UR3, 1, LinkInertia(1e300, [0.1, 0.0, 0.0], [1e300, 1e300, 1e300, 0, 0, 0]))
BARE = Robot([Link(lk.a, lk.alpha, lk.d, lk.theta_offset, limits=lk.limits)
              for lk in UR3.links], name="UR3 without inertias")
VALID_EDGES = {"massless last link": Fine(MASSLESS), "point mass on the last axis":
               Fine(POINT_MASS), "heavy link": Fine(HEAVY), "no link inertias": Fine(BARE)}
SINGULAR = {"massless last link": MASSLESS, "point mass on the last axis": POINT_MASS,
            "heavy link": Fine(HEAVY), "no link inertias": Fine(BARE)}
ROBOT_NAMES = ("robot", "link", "links", "mass", "inertia", "masses", "link 6", "joint 6")

# -- checks of what a call returns ----------------------------------------------------------


def _torques_match(result, kwargs):
    """forward dynamics, then inverse dynamics, give the torques back (to the rounding of
    the largest of the torques, the bias forces and the inertial forces)."""
    robot, q, qd = kwargs["robot"], kwargs["q"], kwargs["qd"]
    gravity = kwargs.get("gravity", GRAVITY)
    tau = dynamics.inverse_dynamics(robot, q, qd, result, gravity=gravity)
    bias = dynamics.inverse_dynamics(robot, q, qd, np.zeros_like(result), gravity=gravity)
    scale = 1.0 + max(float(np.max(np.abs(x))) for x in (kwargs["tau"], bias, tau - bias))
    gap = float(np.max(np.abs(tau - kwargs["tau"])))
    return True if gap <= 1e-9 * scale else f"tau comes back {gap:.3g} off (of {scale:.3g})"


def _symmetric_semidefinite(M, kwargs):
    """A mass matrix: symmetric, positive semidefinite (singular for a joint that moves
    nothing)."""
    M = np.asarray(M)
    if not np.allclose(M, np.swapaxes(M, -1, -2), rtol=1e-12, atol=0.0):
        return "the mass matrix is not symmetric"
    if np.linalg.eigvalsh(M).min() < -1e-12 * np.abs(M).max():
        return "the mass matrix is not positive semidefinite"
    return True


def _rigid_body(inertia, kwargs):
    """A link inertia that a rigid body can have: mass >= 0, principal moments >= 0 and
    satisfying the triangle inequality (relative to the largest)."""
    moments = np.linalg.eigvalsh(inertia.tensor)
    top = max(float(moments[-1]), 1e-300)
    ok = (inertia.mass >= 0 and moments[0] >= -1e-9 * top
          and moments[0] + moments[1] >= moments[2] * (1 - 1e-9))
    return True if ok and numbers_finite(inertia.com) else f"not a rigid body: {moments}"


def _within_limits(q, kwargs, limits_key="limits"):
    limits = kwargs.get(limits_key)
    if limits is None:
        return True
    lims = np.broadcast_to(np.asarray(limits, dtype=float), np.shape(q)[-1:] + (2,))
    if np.any(q < lims[..., 0] - 1e-12) or np.any(q > lims[..., 1] + 1e-12):
        return f"{np.round(q, 4).tolist()} is outside the limits"
    return True


def _a_valid_row(q, kwargs):
    """closest_solution: an equivalent of a valid row (mod 2 pi), within the limits."""
    result = kwargs["result"]
    rows = np.asarray(result.solutions)[np.asarray(result.valid)]
    turns = (np.asarray(q) - rows) / (2 * np.pi)
    if not np.any(np.all(np.abs(turns - np.round(turns)) < 1e-9, axis=-1)):
        return "not an equivalent of a valid row"
    return _within_limits(q, kwargs)


#: The commands the uArm's firmware gets, each with an optional comment
#: (tests/test_desk_arm_firmware).
_COMMAND = re.compile(r"(G0 X-?\d+\.\d\d Y-?\d+\.\d\d Z-?\d+\.\d\d F\d+|G2202 N3 V\d+\.\d\d"
                      r"|M2231 V[01]|G2004 P\d+)( ;[ -~]*)?")


def _firmware_program(text, kwargs=None):
    """G-code the firmware reads as meant: ASCII lines, each a comment or a command, no
    real-time character anywhere (the firmware obeys ? ! ~ @ even inside a comment)."""
    if isinstance(text, (str, bytes)) is False:
        text = text.read_text(encoding="ascii")
    if not text.isascii() or any(c in text for c in "?!~@\r\x18"):
        return "a character the firmware obeys anywhere"
    for line in text.splitlines():
        if not (line.startswith("; ") and line.isprintable()) and not _COMMAND.fullmatch(line):
            return f"a line that is not a command: {line[:80]!r}"
    return True


def _written_program(path, kwargs):
    written = open(path, encoding="ascii").read()
    options = {k: v for k, v in kwargs.items() if k not in ("path", "plan")}
    if written != desk_arm_firmware.gcode_from_plan(kwargs["plan"], **options):
        return "the file is not the program"
    return _firmware_program(written)


def _xml(text, kwargs):
    ElementTree.fromstring(text)
    return True


# -- the cases ------------------------------------------------------------------------------

CASES = Registry()
add = CASES.add
ROBOT = dict(names=ROBOT_NAMES, extra=VALID_EDGES)

M = "dynamics"
add(M, "inverse_dynamics", dynamics.inverse_dynamics, robot=O(UR3, **ROBOT), q=A(Q6),
    qd=A(Q6 / 2), qdd=A(Q6 / 3), gravity=A(GRAVITY))
add(M, "mass_matrix", dynamics.mass_matrix, robot=O(UR3, **ROBOT), q=A(Q6),
    check=_symmetric_semidefinite)
add(M, "gravity_torques", dynamics.gravity_torques, robot=O(UR3, **ROBOT), q=A(Q6),
    gravity=A(GRAVITY))
add(M, "coriolis_torques", dynamics.coriolis_torques, robot=O(UR3, **ROBOT), q=A(Q6),
    qd=A(Q6 / 2))
add(M, "forward_dynamics", dynamics.forward_dynamics,
    robot=O(UR3, names=ROBOT_NAMES, extra=SINGULAR), q=A(Q6),
    qd=A(Q6 / 2), tau=A(Q6 * 10), gravity=A(GRAVITY), check=_torques_match)
add(M, "kinetic_energy", dynamics.kinetic_energy, robot=O(UR3, **ROBOT), q=A(Q6), qd=A(Q6))
add(M, "potential_energy", dynamics.potential_energy, robot=O(UR3, **ROBOT), q=A(Q6),
    gravity=A(GRAVITY))
add(M, "link_inertias", dynamics.link_inertias, robot=O(UR3, **ROBOT))
add(M, "joint_twists", dynamics.joint_twists, robot=O(UR3))
add(M, "inertial_parameters", dynamics.inertial_parameters, robot=O(UR3, **ROBOT))
add(M, "dual_cross", dynamics.dual_cross, a=A([0.1, 0.2, 0.3]), a_dual=A([1.0, 0.0, 0.5]),
    b=A([0.0, 1.0, 0.0]), b_dual=A([0.3, 0.3, 0.0]))
add(M, "with_payload", lambda **kw: dynamics.with_payload(**kw).links[-1].inertia,
    robot=O(UR3), mass=S(1.5), radius=S(0.05), check=_rigid_body)
add(M, "with_inertias", lambda **kw: dynamics.with_inertias(**kw).fk(Q6), robot=O(UR3),
    inertias=O([BODY] * 6))
add(M, "NewtonEuler", lambda **kw: dynamics.NewtonEuler(**kw)(Q6, Q6 / 2, Q6 / 3),
    robot=O(UR3, **ROBOT), gravity=A(GRAVITY))
add(M, "NewtonEuler.__call__", lambda **kw: dynamics.NewtonEuler(UR3)(**kw), q=A(Q6),
    qd=A(Q6 / 2), qdd=A(Q6 / 3))

M = "inertia"
add(M, "LinkInertia", LinkInertia, mass=S(2.0), com=A([0.1, 0.0, 0.02]),
    tensor=A([0.02, 0.03, 0.04, 0.001, 0.0, 0.0], none_ok=True), check=_rigid_body)
add(M, "LinkInertia.sphere", LinkInertia.sphere, mass=S(2.0), centre=A([0.1, 0.0, 0.0]),
    radius=S(0.05), check=_rigid_body)
add(M, "LinkInertia.rod", LinkInertia.rod, mass=S(1.0), start=A([0.0, 0.0, 0.0]),
    end=A([0.3, 0.0, 0.0]), radius=S(0.03), check=_rigid_body)
add(M, "LinkInertia.momentum", BODY.momentum, omega=A([0.1, 0.2, 0.3]), v=A([1.0, 0.0, 0.0]))
add(M, "LinkInertia.scaled", BODY.scaled, factor=S(2.5), check=_rigid_body)
add(M, "LinkInertia.moved", BODY.moved, X_AB=A(TOOL, extra={
    "scaled rotation": TOOL @ np.diag([1.001, 1.001, 1.001, 1.0]),
    "bad last row": TOOL + np.diag([0.0, 0.0, 0.0, 1e-3])}), check=_rigid_body)
add(M, "LinkInertia.__add__", lambda other: BODY + other,
    other=O(LinkInertia.sphere(0.5, [0.0, 0.1, 0.0], 0.02), names=("unsupported operand",)),
    check=_rigid_body)

M = "models"
add(M, "six_r", lambda **kw: models.six_r(**kw).fk(Q6), a2=S(0.4), r4=S(0.35), r7=S(0.1))
add(M, "ur_link_inertias", models.ur_link_inertias,
    masses=A(models.UR_DYNAMICS["UR5e"]["mass"]),
    centres_of_mass=A(models.UR_DYNAMICS["UR5e"]["com"]),
    tensors=A(np.tile([0.01, 0.01, 0.01, 0.0, 0.0, 0.0], (6, 1)), none_ok=True),
    a=A(DH5E["a"], none_ok=True), radius=S(0.06),
    check=lambda r, kw: all(_rigid_body(x, kw) is True for x in r) or "not rigid bodies")
add(M, "rod_link_inertias", models.rod_link_inertias, robot=O(UR3), base_mass=S(0.5),
    mass_per_metre=S(4.0), radius=S(0.03),
    check=lambda r, kw: all(_rigid_body(x, kw) is True for x in r) or "not rigid bodies")
add(M, "desk_arm_joints_from_lab", models.desk_arm_joints_from_lab, q_lab=A([0.1, 1.2, -0.4]))
add(M, "desk_arm_lab_from_joints", models.desk_arm_lab_from_joints,
    q_lab=A([0.1, 1.2, -0.4]))
add(M, "ChainShape.check", models.UR_SHAPE.check, robot=O(UR5E), atol=S(1e-12))


def _the_models_torques(tau, kwargs):
    """with_model_inertias: the arm's gravity torques are the model's (to the millimetres of
    a calibration), not those of bodies copied as numbers into frames metres away."""
    wanted = dynamics.gravity_torques(kwargs["model"], Q6)
    gap = float(np.max(np.abs(tau - wanted)))
    scale = 1.0 + float(np.max(np.abs(wanted)))
    return True if gap <= 0.02 * scale else f"gravity torques {gap:.3g} N m off the model's"


#: The UR5e with its frames 2 and 3 twelve metres along their axes, as real calibrations
#: write them: one arm with the UR5e.
_FAR_FRAMES = Robot.from_dh_table(d=[DH5E["d"][0], 12.0, -12.0, *DH5E["d"][3:]], a=DH5E["a"],
                                  alpha=DH5E["alpha"], name="UR5e, far frames")
_ARMS = ("robot", "model")
add(M, "with_model_inertias", lambda **kw: dynamics.gravity_torques(
    models.with_model_inertias(**kw), Q6), check=_the_models_torques,
    robot=O(_FAR_FRAMES, names=_ARMS, extra={"calibrated": Fine(CALIBRATED),
                                             "another arm": models.ur10e(),
                                             "another number of joints": models.desk_arm()}),
    model=O(UR5E, names=_ARMS, extra={"another arm": UR3, "the 6R": models.six_r()}))

M = "robot"
add(M, "Robot.from_dh_table", lambda **kw: Robot.from_dh_table(**kw).fk(Q6), d=A(DH5E["d"]),
    a=A(DH5E["a"]), alpha=A(DH5E["alpha"]), theta_offset=A(np.zeros(6), none_ok=True),
    joint=O("revolute"),
    limits=A([-2 * np.pi, 2 * np.pi], none_ok=True, extra={
        "degrees": [-360.0, 360.0], "(inf, inf)": [np.inf, np.inf],
        "(-inf, -inf)": [-np.inf, -np.inf], "reversed": [1.0, -1.0]}),
    max_speed=A(np.full(6, 3.0), none_ok=True), convention=O("dh"),
    base=A(np.eye(4), none_ok=True, extra={"not rigid by 1e-6": np.diag([1 + 1e-6] * 3 + [1])}),
    tool=A(TOOL, none_ok=True, extra={"not rigid by 1e-6": TOOL @ np.diag([1 + 1e-6] * 3 + [1])}),
    name=Name("my UR5e"))
add(M, "Robot.from_dh_table(joint)", lambda **kw: Robot.from_dh_table(**DH5E, **kw).fk(Q6),
    joint=O("revolute", extra={"prismatic, no limits given": "prismatic",
                               "one prismatic, no limits given": ["revolute"] * 5
                               + ["prismatic"]}))
add(M, "Robot.with_tool", lambda **kw: UR5E.with_tool(**kw).tool, X_nT=A(TOOL, extra={
    "not rigid by 1e-6": TOOL @ np.diag([1 + 1e-6] * 3 + [1]),
    "a reflection": TOOL @ np.diag([1.0, 1.0, -1.0, 1.0])}))
add(M, "Robot.with_tool(x, y, z)", lambda **kw: UR5E.with_tool(**kw).tool, x=S(0.01),
    y=S(-0.02), z=S(0.15))
add(M, "Robot", lambda **kw: Robot(UR5E.links, **kw).fk(Q6), convention=O("dh"),
    base=A(np.eye(4), none_ok=True), tool=A(TOOL, none_ok=True), name=Name("UR5e"))
add(M, "Link", lambda **kw: Robot([Link(**kw)]).fk([0.2]), a=S(0.3), alpha=S(0.5), d=S(0.1),
    theta_offset=S(0.2), joint=O("revolute"), limits=A([-1.0, 1.0], none_ok=True, extra={
        "(inf, inf)": [np.inf, np.inf], "reversed": [1.0, -1.0]}),
    name=T("upper arm"), inertia=O(BODY, none_ok=True), max_speed=S(3.0, none_ok=True))

M = "ik"
# far targets: a result with no valid row for them (flagged unreachable) is right, as is an
# error; reaches_target fails any valid row off its target
_IK_TARGET = A(X_TARGET, extra={"dual quaternion at 1e100 m": Fine(np.array(
    [1.0, 0, 0, 0, 0, 5e99, 0, 0])), "batch at 1e154 m": Fine(np.stack(
    [X_TARGET, X_TARGET + np.pad([[0, 0, 0, 1e154]], ((0, 3), (0, 0)))]))})
add(M, "ik.ur", ik.ur, robot=O(UR5E, names=ROBOT_NAMES, extra={"calibrated UR3": models.ur3_mdh()}),
    target=_IK_TARGET, tol=S(1e-9, inf_ok=True), tool=A(TOOL, none_ok=True),
    q_ref=A(Q6, none_ok=True), singular_tol=S(5e-7, inf_ok=True), pose_tol=S(1e-9, inf_ok=True),
    residuals=O("equations"), check=reaches_target())
add(M, "ik.ur_closed_form.exact_ur", ik.ur_closed_form.exact_ur, robot=O(UR5E, names=ROBOT_NAMES,
    extra={"calibrated UR3": CALIBRATED}), target=_IK_TARGET, tol=S(1e-9, inf_ok=True),
    q_ref=A(Q6, none_ok=True), check=reaches_target())
add(M, "ik.ur_closed_form.branch_measures",
    lambda **kw: np.stack(ik.ur_closed_form.branch_measures(**kw)),
    robot=O(UR5E, names=ROBOT_NAMES, extra={"calibrated UR3": CALIBRATED}), q=A(Q6))
add(M, "ik.ur(calibrated)", ik.ur, robot=O(CALIBRATED), target=A(X_CALIBRATED, extra={
    "at 1e200 m": Fine(X_CALIBRATED + np.pad([[0, 0, 0, 1e200]], ((0, 3), (0, 0))))}),
    tol=S(1e-9, inf_ok=True), q_ref=A(Q6, none_ok=True), check=reaches_target()
    ).setup = warm_ik_batches(CALIBRATED)
add(M, "calibrated_ur_reference", calibrated_ur_reference, robot=O(CALIBRATED, extra={
    "an exact UR5e": Fine(UR5E), "the 6R": models.six_r()}), target=A(X_CALIBRATED, extra={
        "at 1e200 m": Fine(X_CALIBRATED + np.pad([[0, 0, 0, 1e200]], ((0, 3), (0, 0))))}),
    tol=S(1e-9, inf_ok=True), singular_tol=S(5e-7, inf_ok=True),
    near_tol=S(0.01, inf_ok=True), check=reaches_target())
add(M, "newton_step", lambda **kw: newton_step(**kw)[0], arm=O(CALIBRATED), q=A(Q6 + 1e-3),
    X_target=A(X_CALIBRATED))
add(M, "closest_solution", ik.closest_solution, result=O(RESULT), q_ref=A(Q6),
    limits=A(LIMITS, none_ok=True, extra={
        "(-inf, -inf)": [-np.inf, -np.inf], "(inf, inf)": [np.inf, np.inf],
        "NaN": [np.nan, 1.0], "reversed": [1.0, -1.0], "narrow": [0.5, 0.50001]}),
    wrapped=Flag(False), check=_a_valid_row)
add(M, "closest_solution(q_ref far)", ik.closest_solution, result=O(RESULT),
    q_ref=A(Q6, extra={"1e10 (an exact answer is right)": Fine(np.full(6, 1e10))}),
    limits=A(LIMITS, none_ok=True), check=_a_valid_row)
add(M, "closest_ur_solution", ik.closest_ur_solution, robot=O(UR5E), target=_IK_TARGET,
    q_now=A(Q6), limits=A(LIMITS, none_ok=True, extra={
        "(-inf, -inf)": [-np.inf, -np.inf], "(inf, inf)": [np.inf, np.inf]}),
    tol=S(1e-9, inf_ok=True), check=joints_reach_target(limits="limits"))
add(M, "equivalent_solutions", ik.equivalent_solutions, q=A(Q6), limits=A(LIMITS))
add(M, "distinct_solutions", ik.distinct_solutions, result=O(RESULT), atol=S(1e-9))
add(M, "IKResult.best", RESULT.best, q_ref=A(Q6))
add(M, "ur_parameters", ik.ur_parameters, robot=O(UR5E), atol=S(1e-12))
add(M, "check_ur_options",               # which tolerances are off (inf is a valid one)
    lambda **kw: np.isinf(ik.result.check_ur_options(**kw)), tol=S(1e-9, inf_ok=True),
    singular_tol=S(5e-7, inf_ok=True), near_tol=S(0.01, inf_ok=True),
    pose_tol=S(1e-9, inf_ok=True), residuals=O("equations"))

M = "desk_arm_firmware"
_ROWS = [[228.66, 0, 174.12, 0, 0], [0, 170, 80, 0, 0], [0, 170, 30, 1, 0]]
PLAN = pp.plan_pick_place(models.desk_arm(), pp.task_from_lab(_ROWS), dt=0.1)
add(M, "motor_angles_from_lab", desk_arm_firmware.motor_angles_from_lab, q_lab=A([0.1, 1.2, 1.0]))
add(M, "lab_angles_from_motor", desk_arm_firmware.lab_angles_from_motor, q_lab=A([1.5, 1.2, 1.0]))
add(M, "motor_angles", desk_arm_firmware.motor_angles, positions=A([[0.0, 0.17, 0.03]]),
    where=T("point", only=("none", "number", "list", "control", "newline", "long")))
add(M, "gcode_from_plan", desk_arm_firmware.gcode_from_plan, plan=O(PLAN), name=Name("lab task"),
    start_feed=S(3000.0), check=_firmware_program)
add(M, "write_gcode", desk_arm_firmware.write_gcode, path=P("task.gcode"), plan=O(PLAN),
    name=Name("lab task"), start_feed=S(3000.0), writes="path", check=_written_program)

M = "sim"


def _mjcf(**kw):
    mujoco = pytest.importorskip("mujoco")
    xml = mjcf.mjcf_from_robot(**kw)
    mujoco.MjModel.from_xml_string(xml)          # what it writes, MuJoCo loads
    return xml


_EXPORT_NAMES = ROBOT_NAMES + ("link 6's inertia",)
add(M, "mjcf_from_robot(robot)", _mjcf, robot=O(UR3, names=_EXPORT_NAMES, extra=SINGULAR))
add(M, "urdf_from_robot(robot)", urdf.urdf_from_robot, check=_xml, robot=O(
    UR3, names=_EXPORT_NAMES, extra={**SINGULAR, "point mass on the last axis": Fine(POINT_MASS)}))
add(M, "robot_inertias", mjcf.robot_inertias, robot=O(UR3))

M = "ur.calibration"


class _KinematicsServer:
    """A local server (127.0.0.1, an ephemeral port) that sends the kinematics message to
    every client, from a thread; stopped by the module's fixture."""

    def __init__(self):
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.sock.settimeout(0.05)                  # accept() wakes up to see the stop
        self.port = self.sock.getsockname()[1]
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self):
        while not self.stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            with conn:
                try:
                    conn.sendall(MESSAGE)
                except OSError:
                    pass

    def close(self):
        self.stop.set()
        self.thread.join(10.0)
        self.sock.close()
        assert not self.thread.is_alive()


SERVER = []


def _read_kinematics_info(**kw):
    """read_kinematics_info from the module's server: the good port, 30002, stands for the
    server's (of the same type: a numpy integer stays one)."""
    port = kw["port"]
    if isinstance(port, (int, np.integer)) and not isinstance(port, bool) and port == 30002:
        kw["port"] = type(port)(SERVER[0].port)
    return calibration.read_kinematics_info(**kw)


_INFO = dict(checksum=INFO.checksum, theta=INFO.theta, a=INFO.a, d=INFO.d, alpha=INFO.alpha,
             calibration_status=INFO.calibration_status)
_CONF = dict(delta_theta=CONF.delta_theta, delta_a=CONF.delta_a, delta_d=CONF.delta_d,
             delta_alpha=CONF.delta_alpha, joint_checksum=CONF.joint_checksum,
             calibration_status=CONF.calibration_status)
#: The joint checksums of the calibration.conf test file (tests/test_ur_calibration.py).
_CHECKSUM = (0x6E0F7BF, 0xA32A713F, 0xF636A50, 0x9EC2338A, 0xA1AFDED8, 0xB29B2979)
_WORDS = {"beyond 32 bits": (2 ** 32,) * 6, "negative": (-1,) * 6, "fractions": (2.7,) * 6,
          "booleans": (True,) * 6}
_STATUS = {"beyond 32 bits": 2 ** 32, "negative": -1, "fraction": 2.7}


def _LABEL(value):
    """A text quoted in messages (a source's name): any one line, but an error must not
    quote a long one whole."""
    return T(value, only=("control", "newline", "surrogate", "long"))


def _ints(value, names=()):
    """A tuple of six unsigned 32-bit words: its bad values, and those of integers."""
    return A(value, names=names, extra=_WORDS)


#: How calibration errors name a field of a source: "message: dh_d: ...", "corrections:
#: delta_a: ..." (a source and its field, as the controller's message and calibration.conf
#: call them).
_INFO_NAMES = ("info", "message", "dh_theta", "dh_a", "dh_d", "dh_alpha")
_CONF_NAMES = ("corrections", "calibration", "delta_theta", "delta_a", "delta_d",
               "delta_alpha", "joint_checksum", "calibration_status")


add(M, "check_identifiers", calibration.check_identifiers, checksum=_ints(INFO.checksum),
    calibration_status=Int(2, extra=_STATUS))
add(M, "kinematics_info_from_robot", calibration.kinematics_info_from_robot,
    robot=O(CALIBRATED), checksum=_ints(INFO.checksum),
    calibration_status=Int(0, extra=_STATUS))
for _field, _value in _INFO.items():
    _arg = (_ints(_value) if _field == "checksum" else Int(_value, extra=_STATUS)
            if _field == "calibration_status" else A(_value))
    _arg.names = _INFO_NAMES
    add(M, f"message_from_kinematics_info(KinematicsInfo.{_field})",
        lambda _f=_field, **kw: calibration.message_from_kinematics_info(
            KinematicsInfo(**{**_INFO, **kw})), group="KinematicsInfo", **{_field: _arg})
    if _field in ("theta", "a", "d", "alpha"):        # what the robot is made of
        add(M, f"robot_from_kinematics_info(KinematicsInfo.{_field})",
            lambda _f=_field, **kw: calibration.robot_from_kinematics_info(
                KinematicsInfo(**{**_INFO, **kw}), model="UR5e").fk(Q6),
            group="KinematicsInfo", **{_field: _arg})
add(M, "message_from_kinematics_info", calibration.message_from_kinematics_info,
    info=O(INFO))
add(M, "kinematics_info_from_message", calibration.kinematics_info_from_message,
    message=O(MESSAGE, names=("message", "size", "type"), extra={
        "truncated": MESSAGE[:100], "garbage": bytes(range(256)),
        "a size of 2 GB": b"\x7f\xff\xff\xff\x10" + MESSAGE[5:],
        "16 MB": MESSAGE + bytes(16 << 20)}), source=_LABEL("message"))
add(M, "read_kinematics_info", _read_kinematics_info,
    host=T("127.0.0.1", only=("none", "number", "list", "surrogate")),   # (no name lookups)
    port=Int(30002, extra={"one turn beyond 65535": 65536 + 30002, "negative": -1}),
    timeout=S(5.0, extra={"zero": 0.0}))
add(M, "robot_from_kinematics_info", calibration.robot_from_kinematics_info, info=O(INFO),
    model=O("UR5e", none_ok=True, names=_INFO_NAMES, extra={
        "another model": "UR10e", "no such model": "UR6"}),
    name=T("", none_ok=True), source=_LABEL("message"))
add(M, "read_calibration_conf", calibration.read_calibration_conf,
    path=F("calibration.conf", extra={"a 400-digit status": lambda folder: _file(
        folder, "big.conf", _conf_text(_deltas(CALIBRATED, UR5E), status="9" * 400))}))
add(M, "robot_from_calibration_conf", lambda **kw: calibration.robot_from_calibration_conf(
    **kw).fk(Q6), path=F("calibration.conf"),
    model=O("UR5e", extra={"another (corrections fit any model)": Fine("UR3e")}),
    checksum=A(_CHECKSUM, none_ok=True, names=("joint_checksum",),
               extra={"another arm's": (7,) * 6}),
    name=T("", none_ok=True))
for _field, _value in _CONF.items():
    _arg = (_ints(_value) if _field == "joint_checksum" else Int(_value, extra=_STATUS)
            if _field == "calibration_status" else A(_value))
    _arg.names = _CONF_NAMES
    _arg.none_ok = _field in ("joint_checksum", "calibration_status")  # None: not given
    if _field.startswith("delta_"):                   # what the robot is made of
        add(M, f"robot_from_corrections(CalibrationConf.{_field})",
            lambda **kw: calibration.robot_from_corrections(
                CalibrationConf(**{**_CONF, **kw}), "UR5e").fk(Q6), group="CalibrationConf",
            **{_field: _arg})
    add("ur.standin", f"ControllerStandIn(calibration=CalibrationConf.{_field})",
        lambda **kw: ControllerStandIn("ur5e", calibration=CalibrationConf(**{**_CONF, **kw})),
        group="ControllerStandIn(calibration)", **{_field: _arg})
add(M, "robot_from_corrections", lambda **kw: calibration.robot_from_corrections(
    **kw).fk(Q6), corrections=O(CONF),
    model=O("UR5e", extra={"another (corrections fit any model)": Fine("UR10e")}),
    name=T("", none_ok=True), source=_LABEL("corrections"))
add(M, "robot_from_joint_origins", lambda **kw: calibration.robot_from_joint_origins(
    **kw).fk(Q6), origins=A(_origins), name=T("", none_ok=True))


def _file(folder, name, text):
    path = folder / name
    path.write_text(text)
    return path


_ROS = ros_yaml(_origins, INFO.hash)
_LAUGHS = ("a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
    for p, c in zip("abcdefgh", "bcdefghi", strict=True)) + "kinematics: *i\n")
_YAML_FILES = {
    "billion laughs": lambda folder: _file(folder, "laughs.yaml", _LAUGHS),
    "3000 levels": lambda folder: _file(folder, "deep.yaml", "kinematics: " + "[" * 3000
                                        + "]" * 3000 + "\n"),
    "a 400-digit number": lambda folder: _file(folder, "digits.yaml", _ROS.replace(
        "    x: ", "    x: " + "9" * 400 + "  # ", 1)),
    "50 MB": lambda folder: _file(folder, "big.yaml", _ROS + "#" * (50 << 20) + "\n"),
}
add(M, "read_ros_calibration", calibration.read_ros_calibration,
    path=F("calibration.yaml", extra=_YAML_FILES))
add(M, "robot_from_ros_calibration", lambda **kw: calibration.robot_from_ros_calibration(
    **kw).fk(Q6), path=F("calibration.yaml", extra=_YAML_FILES),
    model=O("UR5e", none_ok=True, names=("kinematics",), extra={"another": "UR10e"}),
    expected_hash=T(INFO.hash, none_ok=True, only=("number", "list")), name=T("", none_ok=True))


def _setup(folder, then=None):
    """The files the cases read, then a case's own setup (``then``)."""
    (folder / "calibration.conf").write_text(_conf_text(_deltas(CALIBRATED, UR5E)))
    (folder / "calibration.yaml").write_text(_ROS)
    if then is not None:
        then(folder)


for _case in CASES.values():
    _case.setup = functools.partial(_setup, then=_case.setup)


@pytest.fixture(scope="module", autouse=True)
def server():
    """The kinematics server of the read_kinematics_info cases, for this module's tests."""
    SERVER.append(_KinematicsServer())
    yield SERVER[0]
    SERVER.pop().close()



@pytest.mark.sweep
@pytest.mark.parametrize("group", list(CASES.groups))
def test_bad_arguments_are_refused_by_name_or_give_a_correct_result(group, request, tmp_path):
    sweep_test(request, CASES.groups[group], tmp_path, "models and exports")


# -- every public callable is swept -------------------------------------------------------

#: The modules whose public callables are swept (data -- tables, constants, shapes -- is not
#: callable and has nothing to sweep).
MODULES = ("dqlab.dynamics", "dqlab.inertia", "dqlab.models", "dqlab.desk_arm_firmware",
           "dqlab.sim.mjcf", "dqlab.sim.urdf", "dqlab.ur.calibration", "dqlab.ik",
           "dqlab.ik.ur_closed_form", "dqlab.ik.ur_solver", "dqlab.ik.ur_calibrated_reference")
#: Public callables that take no input to sweep: exception types.
NOT_SWEPT = {"CalibrationError"}
#: Callables without arguments: nothing to sweep, each called once here.
NO_ARGUMENTS = {"model"} | {n for n in models.__all__ if re.fullmatch(
    r"ur\d+\w*|ur3_mdh|desk_arm|scara_rsm5", n)}


def test_the_sweeps_cover_every_public_callable_of_these_modules():
    import test_bad_input_sweep
    import test_bad_input_sweep_applications

    swept = " ".join(list(CASES) + list(test_bad_input_sweep.CASES)
                     + list(test_bad_input_sweep_applications.CASES))
    words = set(re.findall(r"[A-Za-z_][\w]*", swept))
    missing = {}
    for module_name in MODULES:
        module = __import__(module_name, fromlist=["__all__"])
        names = {name for name in module.__all__
                 if callable(getattr(module, name))} - NOT_SWEPT - NO_ARGUMENTS
        if module_name == "dqlab.ik":
            names &= {"closest_solution", "closest_ur_solution", "equivalent_solutions",
                      "distinct_solutions", "ur", "ur_parameters", "numerical"}
        if names - words:
            missing[module_name] = sorted(names - words)
    assert missing == {}
    for name in NO_ARGUMENTS:
        robot = getattr(models, name, None) or getattr(desk_arm_firmware, name)
        assert np.all(np.isfinite(robot().fk(np.zeros(robot().n)))), name
    assert math.isfinite(float(models.rod_link_inertias(UR3)[0].mass))
