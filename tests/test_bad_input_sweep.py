"""Every public array function, every array argument, every kind of bad value.

For each function a good call is given; each of its array arguments is then replaced, one at
a time, by NaN, inf, None, text, complex numbers, the wrong shape, a ragged list, an empty
batch, and huge or tiny magnitudes. The call must either raise ValueError or TypeError
whose message names that argument (or, for magnitudes, says the result overflows), or
return finite arrays (with an empty batch: of size 0). Anything else fails.
"""

import inspect
import re
from collections import Counter

import numpy as np
import pytest

import dqlab
from dqlab import dynamics, ik, jacobian
from dqlab import dynamics_identification as dyn_id
from dqlab.identify import dh_parameters, robot_from_dh_parameters
from dqlab.models import desk_arm, scara_rsm5, ur3
from dqlab.robot import Robot
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
    """The public function ``name`` of the math core, from the module that holds it."""
    modules = (dqlab.quaternion, dqlab.rotations, dqlab.transforms, dqlab.dualquat)
    return next(getattr(m, name) for m in modules if name in m.__all__)


def _cases():
    calls = {name: (_function(name), args) for name, args in GOOD_CALLS.items()}
    calls.update(OTHER_CALLS)
    for name, (function, args) in calls.items():
        names = _parameter_names(function, len(args))
        for i, label in enumerate(names):
            for kind in BAD_KINDS:
                yield pytest.param(function, args, i, label, kind, id=f"{name}-{label}-{kind}")


def _bad_value(value, kind):
    a = np.asarray(value, dtype=float)
    if kind == "nan":
        return np.where(np.arange(a.size).reshape(a.shape) == 0, np.nan, a)
    if kind == "inf":
        return np.where(np.arange(a.size).reshape(a.shape) == 0, np.inf, a)
    if kind == "none":
        return None
    if kind == "text":
        return "abc"
    if kind == "complex":
        return a + 1j
    if kind == "wrong_shape":
        return a[..., :-1] if a.ndim else np.ones((2, 3, 5))
    if kind == "ragged":
        return [[1.0, 2.0], [3.0]]
    if kind == "empty":
        return np.zeros((0,) + a.shape)
    if kind == "huge":
        return a * 1e200
    if kind == "tiny":
        return a * 1e-200
    raise AssertionError(kind)


BAD_KINDS = ("nan", "inf", "none", "text", "complex", "wrong_shape", "ragged", "empty",
             "huge", "tiny")
OUTCOMES = Counter()


def _all_finite(result):
    parts = result if isinstance(result, tuple) else (result,)
    arrays = [np.asarray(getattr(p, "solutions", p), dtype=float) for p in parts]
    return all(np.all(np.isfinite(a)) for a in arrays), any(a.size == 0 for a in arrays)


@pytest.mark.parametrize("function, args, index, name, kind", list(_cases()))
def test_bad_argument_is_refused_by_name_or_gives_a_correct_result(function, args, index,
                                                                     name, kind):
    args = list(args)
    args[index] = _bad_value(args[index], kind)
    try:
        result = function(*args)
    except (ValueError, TypeError) as exc:
        message = str(exc)
        named = re.search(rf"(?<![\w.]){re.escape(name)}(?!\w)", message) is not None
        if kind in ("huge", "tiny") and ("overflow" in message or "too large" in message):
            named = True
        OUTCOMES["clear error" if named else "other"] += 1
        assert named, f"the error does not name {name!r}: {message}"
        return
    finite, empty = _all_finite(result)
    correct = (kind == "empty" and empty) or (kind in ("huge", "tiny") and finite)
    if kind == "wrong_shape" and finite and (np.ndim(args[index]) == 3
                                             or function is jacobian.singular_values):
        correct = True      # a scalar argument broadcast over a batch; any (m, n) matrix
    OUTCOMES["correct result" if correct else "other"] += 1
    assert correct, f"{kind} {name!r} was accepted: {result!r}"


def test_zz_summary_of_the_sweep(capsys):
    """The counts of the sweep above (run in the same session): no case may be "other"."""
    if not OUTCOMES:
        pytest.skip("the sweep did not run in this session")
    total = sum(OUTCOMES.values())
    with capsys.disabled():
        print(f"\nbad-input sweep: {total} cases, {OUTCOMES['clear error']} clear errors, "
              f"{OUTCOMES['correct result']} correct results, {OUTCOMES['other']} other")
    assert OUTCOMES["other"] == 0
