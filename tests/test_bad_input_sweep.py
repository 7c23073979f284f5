"""Every public array function of the core, every array argument, every kind of bad value.

For each function a good call is given; each of its array arguments is then replaced, one at
a time, by NaN, inf, None, text, complex numbers, the wrong shape, a ragged list, an empty
batch, huge or tiny magnitudes and far values (1e100, -1e300). The call must either raise
ValueError or TypeError whose message names that argument (or, for magnitudes, says the
result overflows), or return finite arrays (with an empty batch: of size 0). Anything else
fails. The machinery is ``tests/_sweep.py``'s, shared by every sweep.
"""

import inspect

import numpy as np
import pytest
from _sweep import (
    Any,
    Arg,
    Registry,
    S,
    joints_reach_target,
    reaches_target,
    sweep_test,
    warm_ik_batches,
)

import dqlab
from dqlab import dynamics, ik, jacobian, testing
from dqlab import dynamics_identification as dyn_id
from dqlab.identify import dh_parameters, robot_from_dh_parameters
from dqlab.models import desk_arm, scara_rsm5, ur3
from dqlab.robot import Robot
from dqlab.trajectory.follow import singular_passes, ur_singularity_margins
from dqlab.ur.calibration import CalibrationConf, robot_from_corrections, robot_from_joint_origins

UR3 = ur3()
CALIBRATED = robot_from_dh_parameters(UR3, dh_parameters(UR3) + 1e-3)   # a calibrated UR3
Q6 = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
Q = np.array([0.5, 0.5, 0.5, 0.5])
V = np.array([1.0, 2.0, 3.0])
R = dqlab.rot_z(0.3) @ dqlab.rot_x(0.2)
T = dqlab.transform_from(R, V)
D = dqlab.dual_quaternion_from_transform(T)
DH = {"d": [lk.d for lk in UR3.links], "a": [lk.a for lk in UR3.links],
      "alpha": [lk.alpha for lk in UR3.links]}

GOOD_CALLS = {
    # quaternion.py
    "quaternion_product": (Q, Q), "quaternion_conjugate": (Q,), "quaternion_norm": (Q,),
    "quaternion_inverse": (Q,), "quaternion_normalize": (Q,), "check_unit_quaternion": (Q,),
    "rotate_vector": (Q, V), "quaternion_from_axis_angle": (V, 0.4),
    "axis_angle_from_quaternion": (Q,), "quaternion_from_matrix": (R,),
    "matrix_from_quaternion": (Q,), "quaternion_exp": (Q,), "quaternion_log": (Q,),
    "quaternion_power": (Q, 0.5), "slerp": (Q, [1.0, 0, 0, 0], 0.3),
    "quaternion_distance": (Q, [1.0, 0, 0, 0]),
    "quaternion_from_xyzw": (Q,), "xyzw_from_quaternion": (Q,),
    # rotations.py
    "rot_x": (0.3,), "rot_y": (0.3,), "rot_z": (0.3,), "matrix_from_euler_zxz": (V,),
    "euler_zxz_from_matrix": (R,), "matrix_from_rpy": (V,), "rpy_from_matrix": (R,),
    "matrix_from_axis_angle": (V, 0.4), "axis_angle_from_matrix": (R,),
    "rodrigues": (V, [0.0, 0, 1], 0.4), "check_rotation_matrix": (R,), "skew": (V,),
    # transforms.py
    "transform_from": (R, V), "transform_inverse": (T,), "compose": (T, T),
    "apply_transform": (T, V), "apply_to_vectors": (T, V), "check_transform": (T,),
    "rotation_translation_from_transform": (T,),
    # dualquat.py
    "dual_quaternion_product": (D, D), "dual_quaternion_conjugate": (D,),
    "dual_quaternion_dual_conjugate": (D,), "dual_quaternion_combined_conjugate": (D,),
    "dual_quaternion_norm": (D,), "check_unit_dual_quaternion": (D,),
    "dual_quaternion_normalize": (D,), "dual_quaternion_inverse": (D,),
    "dual_quaternion_from_rotation_translation": (Q, V),
    "rotation_translation_from_dual_quaternion": (D,),
    "dual_quaternion_from_transform": (T,), "transform_from_dual_quaternion": (D,),
    "dual_quaternion_apply": (D, V), "dual_quaternion_apply_vector": (D, V),
    "dual_quaternion_apply_line": (D, [0.0, 0, 1], [1.0, 0, 0]),
    "dual_quaternion_from_pair": (Q, V), "pair_from_dual_quaternion": (D,),
    "pair_product": (Q, V, Q, V), "screw_from_dual_quaternion": (D,),
    "dual_quaternion_from_screw": ([0.0, 0, 1], [1.0, 0, 0], 0.4, 0.1),
    "dual_quaternion_power": (D, 0.5), "sclerp": (D, dqlab.dual_quaternion_identity(), 0.3),
}

W_UR3 = dyn_id.regressor_with_motors(
    UR3, *np.random.default_rng(0).uniform(-3.0, 3.0, (3, 20, 6))).reshape(-1, 78)
BASE_UR3 = dyn_id.base_parameters(W_UR3, dyn_id.parameter_names(UR3))
FOURIER = dyn_id.FourierTrajectory(np.zeros(2), np.ones((2, 3)), np.ones((2, 3)), 2.0)

OTHER_CALLS = {
    "Robot.fk": (UR3.fk, (Q6,)), "Robot.fk_dq": (UR3.fk_dq, (Q6,)),
    "Robot.fk_dq_screw": (UR3.fk_dq_screw, (Q6,)), "Robot.jacobian": (UR3.jacobian, (Q6,)),
    "Robot.joint_axes": (UR3.joint_axes, (Q6,)),
    "ik.ur": (lambda target: ik.ur(UR3, target), (UR3.fk(Q6),)),
    "ik.numerical": (lambda target, q0: ik.numerical(UR3, target, q0, max_iter=3),
                     (UR3.fk(Q6), Q6)),
    "ik.scara": (lambda target: ik.scara(scara_rsm5(), target),
                 (scara_rsm5().fk([0.2, 0.4, 0.05, 0.1]),)),
    "ik.desk_arm": (lambda target: ik.desk_arm(desk_arm(), target), ([0.2, 0.0, 0.1],)),
    "ik.pose_errors": (ik.pose_errors, (T, T)),
    "jacobian.manipulability": (jacobian.manipulability, (UR3.jacobian(Q6),)),
    "jacobian.singular_values": (jacobian.singular_values, (UR3.jacobian(Q6),)),
    "dynamics.inverse_dynamics": (lambda q, qd, qdd: dynamics.inverse_dynamics(UR3, q, qd, qdd),
                                  (Q6, Q6 / 2, Q6 / 3)),
    "dynamics.mass_matrix": (lambda q: dynamics.mass_matrix(UR3, q), (Q6,)),
    "dynamics.gravity_torques": (lambda q: dynamics.gravity_torques(UR3, q), (Q6,)),
    "dynamics.coriolis_torques": (lambda q, qd: dynamics.coriolis_torques(UR3, q, qd),
                                  (Q6, Q6 / 2)),
    "dynamics.forward_dynamics": (lambda q, qd, tau: dynamics.forward_dynamics(UR3, q, qd, tau),
                                  (Q6, Q6 / 2, Q6)),
    "dynamics.kinetic_energy": (lambda q, qd: dynamics.kinetic_energy(UR3, q, qd), (Q6, Q6)),
    "dynamics.potential_energy": (lambda q: dynamics.potential_energy(UR3, q), (Q6,)),
    "dynamics.NewtonEuler": (lambda q, qd, qdd: dynamics.NewtonEuler(UR3)(q, qd, qdd),
                             (Q6, Q6 / 2, Q6 / 3)),
    "dynamics.gravity": (lambda gravity: dynamics.gravity_torques(UR3, Q6, gravity=gravity),
                         ([0.0, 0.0, -9.81],)),
    "dynamics.regressor": (lambda q, qd, qdd: dynamics.regressor(UR3, q, qd, qdd),
                           (Q6, Q6 / 2, Q6 / 3)),
    "dynamics.link_jacobians": (lambda q: dynamics.link_jacobians(UR3, q), (Q6,)),
    "dynamics.inertias_from_parameters": (
        lambda parameters: np.array([I.tensor for I in
                                     dynamics.inertias_from_parameters(parameters)]),
        (dynamics.inertial_parameters(UR3),)),
    "dynamics_identification.motor_regressor": (dyn_id.motor_regressor, (Q6, Q6 / 3)),
    "dynamics_identification.regressor_with_motors": (
        lambda q, qd, qdd: dyn_id.regressor_with_motors(UR3, q, qd, qdd), (Q6, Q6 / 2, Q6 / 3)),
    "dynamics_identification.base_parameters": (
        lambda W: dyn_id.base_parameters(W, dyn_id.parameter_names(UR3)).K, (W_UR3,)),
    "dynamics_identification.FourierTrajectory.sample": (
        lambda t: FOURIER.sample(t), (0.3,)),
    "dynamics_identification.exciting_trajectory": (
        lambda centre, half_range, qd_max, qdd_max: dyn_id.exciting_trajectory(
            UR3, BASE_UR3, centre=centre, half_range=half_range, qd_max=qd_max,
            qdd_max=qdd_max, iterations=0, samples=30)[0].a,
        ([0.0, -1.5, 0.0, -1.5, 0.0, 0.0], [1.0] * 6, [1.5] * 6, [5.0] * 6)),
    "dynamics_identification.IdentifiedModel": (
        lambda q, qd, qdd: dyn_id.IdentifiedModel(UR3, BASE_UR3, np.ones(BASE_UR3.rank))
        .inverse_dynamics(q, qd, qdd), (Q6, Q6 / 2, Q6 / 3)),
    "ik.ur(calibrated)": (lambda target: ik.ur(CALIBRATED, target), (CALIBRATED.fk(Q6),)),
    "ik.closest_ur_solution": (lambda target, q_now: ik.closest_ur_solution(UR3, target, q_now),
                               (UR3.fk(Q6), Q6)),
    "Robot.from_dh_table": (
        lambda d, a, alpha: Robot.from_dh_table(d=d, a=a, alpha=alpha).fk(np.zeros(6)),
        (DH["d"], DH["a"], DH["alpha"])),
    "Robot.with_tool": (lambda X_nT: UR3.with_tool(X_nT).tool, (T,)),
    "Robot.with_tool(z)": (lambda z: UR3.with_tool(z=z).tool, (0.15,)),
    "ur.calibration.robot_from_joint_origins": (robot_from_joint_origins,
                                                (np.tile(np.eye(4), (6, 1, 1)),)),
    "ur.calibration.robot_from_corrections": (
        lambda delta_theta, delta_a, delta_d, delta_alpha: robot_from_corrections(
            CalibrationConf(delta_theta, delta_a, delta_d, delta_alpha), "UR3").fk(Q6),
        ((0.0,) * 6, (1e-4,) * 6, (-1e-4,) * 6, (1e-4,) * 6)),
    "models.ur_link_inertias_from_ros": (
        lambda mass, cog, rpy, tensor: np.array([
            I.tensor_at_origin for I in dqlab.models.ur_link_inertias_from_ros(
                mass, cog, rpy, tensor, dqlab.models.UR_DH["UR5e"]["a"])]),
        tuple(np.array(dqlab.models.UR_PHYSICAL_PARAMETERS["UR5e"][key])
              for key in ("mass", "cog", "rpy", "tensor"))),
    "models.rod_link_inertias": (
        lambda base_mass, mass_per_metre, radius: np.array([
            I.tensor_at_origin for I in dqlab.models.rod_link_inertias(
                UR3, base_mass=base_mass, mass_per_metre=mass_per_metre, radius=radius)]),
        (0.5, 4.0, 0.03)),
    "LinkInertia": (lambda mass, com: dqlab.inertia.LinkInertia(
        mass, com, np.diag([0.01, 0.02, 0.025])).tensor_at_origin, (2.0, V / 10)),
    "LinkInertia.rod": (lambda mass, start, end, radius: dqlab.inertia.LinkInertia.rod(
        mass, start, end, radius).tensor_at_origin, (1.2, V / 20, V / 10, 0.02)),
    "LinkInertia.sphere": (lambda mass, centre, radius: dqlab.inertia.LinkInertia.sphere(
        mass, centre, radius).tensor_at_origin, (1.2, V / 10, 0.05)),
    "LinkInertia.scaled": (lambda factor: dqlab.inertia.LinkInertia.sphere(
        1.2, V / 10, 0.05).scaled(factor).tensor_at_origin, (1.1,)),
    "LinkInertia.moved": (lambda X_AB: dqlab.inertia.LinkInertia.sphere(
        1.2, V / 10, 0.05).moved(X_AB).tensor_at_origin, (T,)),
    "dynamics.with_payload": (lambda mass, cog: dynamics.gravity_torques(
        dynamics.with_payload(UR3, mass, cog), Q6), (3.0, [0.0, 0.0, 0.1])),
    "ik.solutions.check_joint_limits": (
        lambda limits: ik.solutions.check_joint_limits(limits, 6),
        (UR3.limits[:5].tolist() + [[-6.0, 6.0]],)),     # (its wrist 3 is unlimited: inf)
    "ik.solutions.check_reference": (lambda q_ref: ik.solutions.check_reference(q_ref, 6),
                                     (Q6,)),
    "ik.ur_branch": (lambda q: ik.ur_branch(UR3, q), (Q6,)),
    "trajectory.singular_passes": (
        lambda qd, t: singular_passes(ur_singularity_margins(UR3, np.tile(Q6, (3, 1))), qd,
                                      t, 0.11235), (np.tile(Q6, (3, 1)), [0.0, 0.1, 0.2])),
}


def _parameter_names(function, count):
    """The names of the first ``count`` positional arguments (``Ts[i]`` for ``*Ts``)."""
    names = []
    for p in inspect.signature(function).parameters.values():
        if p.kind == p.VAR_POSITIONAL:
            names += [f"{p.name}[{i}]" for i in range(count - len(names))]
        elif p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD):
            names.append(p.name)
    return names[:count]


def _function(name):
    """The public function ``name`` of the math core, and the module that holds it."""
    modules = (dqlab.quaternion, dqlab.rotations, dqlab.transforms, dqlab.dualquat)
    module = next(m for m in modules if name in m.__all__)
    return getattr(module, name), module.__name__.split(".")[-1]


def _positional(function, names):
    """``function`` called with keyword arguments in the order of ``names``."""
    return lambda **kw: function(*[kw[n] for n in names])


def _arg(function, value):
    """A number broadcast over a batch takes any shape, as J does for singular values (any
    (m, n) matrix); every other argument has its shape."""
    if np.ndim(value) == 0 or function is jacobian.singular_values:
        return Any(value)
    return Arg(value)


CASES = Registry()
for _name, _args in GOOD_CALLS.items():
    _f, _module = _function(_name)
    _names = _parameter_names(_f, len(_args))
    CASES.add(_module, _name, _positional(_f, _names),
              **{n: _arg(_f, v) for n, v in zip(_names, _args, strict=True)})
#: What a result of an IK call must be, beyond finite: valid rows reach their target.
CHECKS = {"ik.ur": reaches_target(UR3), "ik.ur(calibrated)": reaches_target(CALIBRATED),
          "ik.numerical": reaches_target(UR3), "ik.scara": reaches_target(scara_rsm5()),
          "ik.desk_arm": reaches_target(desk_arm(), position_only=True),
          "ik.closest_ur_solution": joints_reach_target(UR3)}
for _name, (_f, _args) in OTHER_CALLS.items():
    _names = _parameter_names(_f, len(_args))
    _module = "robot" if _name.startswith("Robot") else _name.split(".")[0]
    CASES.add(_module, _name, _positional(_f, _names), check=CHECKS.get(_name),
              **{n: _arg(_f, v) for n, v in zip(_names, _args, strict=True)})
CASES["ik.ur(calibrated)"].setup = warm_ik_batches(CALIBRATED)


def _holds(assertion):
    """An assertion of dqlab.testing as a function: per item of the broadcast batch, 1.0
    when it holds and 0.0 when it fails; a bad argument must still be refused by name."""
    def verdict(actual, desired, atol):
        try:
            assertion(actual, desired, atol=atol)
            held = 1.0
        except AssertionError:
            held = 0.0
        items = np.broadcast(np.asarray(actual)[..., 0], np.asarray(desired)[..., 0]).shape
        return np.full(items, held)
    return verdict


for _name, _good in (("assert_quaternion_equal", Q), ("assert_dual_quaternion_equal", D)):
    CASES.add("testing", f"testing.{_name}", _holds(getattr(testing, _name)),
              actual=Arg(_good), desired=Arg(-_good), atol=S(1e-12, inf_ok=True))


@pytest.mark.sweep
@pytest.mark.parametrize("title", list(CASES))
def test_bad_arguments_are_refused_by_name_or_give_a_correct_result(title, request, tmp_path):
    sweep_test(request, CASES[title], tmp_path, "core")
