"""Inputs a careful user might try: empty batches, complex numbers, text, None, NaN or negative
tolerances, huge integers, fractional shapes, wrappers multiplied by arrays, and probing
for modules that are not there. Each gets a correct result or an error naming the argument."""

import importlib.util

import numpy as np
import pytest

import dqlab
from dqlab import dualquat, ik, quaternion, rotations, transforms
from dqlab.models import desk_arm, scara_rsm5, ur3

ROBOT = ur3()
Q_UR = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
X_UR = ROBOT.fk(Q_UR)
UNIT_DQ = dualquat.dual_quaternion_from_transform(X_UR)


# --- empty batches ------------------------------------------------------------------------

EMPTY_CASES = [
    (dualquat.dual_quaternion_product, (np.zeros((0, 8)), np.zeros((0, 8))), (0, 8)),
    (dualquat.dual_quaternion_conjugate, (np.zeros((0, 8)),), (0, 8)),
    (dualquat.dual_quaternion_norm, (np.zeros((0, 8)),), (0, 2)),
    (dualquat.dual_quaternion_normalize, (np.zeros((0, 8)),), (0, 8)),
    (dualquat.dual_quaternion_inverse, (np.zeros((0, 8)),), (0, 8)),
    (dualquat.check_unit_dual_quaternion, (np.zeros((0, 8)),), (0, 8)),
    (dualquat.transform_from_dual_quaternion, (np.zeros((0, 8)),), (0, 4, 4)),
    (dualquat.dual_quaternion_from_transform, (np.zeros((0, 4, 4)),), (0, 8)),
    (dualquat.dual_quaternion_apply, (np.zeros((0, 8)), np.zeros((0, 3))), (0, 3)),
    (dualquat.dual_quaternion_apply_vector, (np.zeros((0, 8)), np.zeros((0, 3))), (0, 3)),
    (dualquat.dual_quaternion_power, (np.zeros((0, 8)), np.zeros(0)), (0, 8)),
    (dualquat.sclerp, (np.zeros((0, 8)), np.zeros((0, 8)), np.zeros(0)), (0, 8)),
    (lambda Q: dualquat.rotation_translation_from_dual_quaternion(Q)[1], (np.zeros((0, 8)),),
     (0, 3)),
    (lambda Q: dualquat.screw_from_dual_quaternion(Q)[0], (np.zeros((0, 8)),), (0, 3)),
    (quaternion.quaternion_product, (np.zeros((0, 4)), np.zeros((0, 4))), (0, 4)),
    (quaternion.rotate_vector, (np.zeros((0, 4)), np.zeros((0, 3))), (0, 3)),
    (quaternion.matrix_from_quaternion, (np.zeros((0, 4)),), (0, 3, 3)),
    (quaternion.quaternion_from_matrix, (np.zeros((0, 3, 3)),), (0, 4)),
    (quaternion.slerp, (np.zeros((0, 4)), np.zeros((0, 4)), np.zeros(0)), (0, 4)),
    (rotations.check_rotation_matrix, (np.zeros((0, 3, 3)),), (0, 3, 3)),
    (transforms.check_transform, (np.zeros((0, 4, 4)),), (0, 4, 4)),
    (transforms.transform_inverse, (np.zeros((0, 4, 4)),), (0, 4, 4)),
    (ROBOT.fk, (np.zeros((0, 6)),), (0, 4, 4)),
    (ROBOT.fk_dq, (np.zeros((0, 6)),), (0, 8)),
    (ROBOT.jacobian, (np.zeros((0, 6)),), (0, 6, 6)),
]


@pytest.mark.parametrize("function, args, shape", EMPTY_CASES,
                         ids=[getattr(c[0], "__name__", "lambda") for c in EMPTY_CASES])
def test_an_empty_batch_gives_an_empty_result(function, args, shape):
    assert np.shape(function(*args)) == shape


@pytest.mark.parametrize("target", [np.zeros((0, 8)), np.zeros((0, 4, 4)),
                                    np.zeros((2, 0, 4, 4))])
def test_ur_ik_of_an_empty_batch(target):
    result = ik.ur(ROBOT, target)
    lead = target.shape[:-1] if target.shape[-1] == 8 else target.shape[:-2]
    assert result.solutions.shape == lead + (8, 6)
    assert result.valid.shape == lead + (8,) and result.reason.shape == lead
    assert all(f.shape == lead for f in result.flags.values())


def test_other_solvers_on_an_empty_batch():
    assert ik.scara(scara_rsm5(), np.zeros((0, 4, 4))).solutions.shape == (0, 2, 4)
    assert ik.desk_arm(desk_arm(), np.zeros((0, 3))).solutions.shape == (0, 4, 3)
    assert ik.numerical(ROBOT, np.zeros((0, 4, 4)), Q_UR).solutions.shape == (0, 1, 6)


# --- the wrappers and numpy arrays --------------------------------------------------------

def test_a_wrapper_times_an_array_is_refused_not_element_wise():
    q = dqlab.Quaternion([0.0, 1.0, 0.0, 0.0])
    with pytest.raises(TypeError):
        q * np.array([0.0, 0.0, 1.0, 0.0])
    with pytest.raises(TypeError):
        np.array([0.0, 0.0, 1.0, 0.0]) * q
    D = dqlab.DualQuaternion(UNIT_DQ)
    with pytest.raises(TypeError):
        D * UNIT_DQ
    with pytest.raises(TypeError):
        UNIT_DQ * D
    # the products of wrappers and the scalings still work, numpy scalars included
    np.testing.assert_allclose((q * dqlab.Quaternion([0.0, 0.0, 1.0, 0.0])).array,
                               [0, 0, 0, 1])
    np.testing.assert_allclose((np.float64(2.0) * q).array, [0, 2, 0, 0])
    np.testing.assert_allclose(np.asarray(q), [0, 1, 0, 0])


# --- complex numbers, text, None ----------------------------------------------------------

@pytest.mark.parametrize("call, name", [
    (lambda: ik.ur(ROBOT, X_UR + 0.3j), "target"),
    (lambda: rotations.rot_z(np.array(1j)), "theta"),
    (lambda: quaternion.quaternion_product([1j, 0, 0, 0], [1, 0, 0, 0]), "a"),
    (lambda: ROBOT.fk(Q_UR + 1j), "q"),
    (lambda: dualquat.dual_quaternion_from_transform(X_UR + 0j), "T"),
    (lambda: rotations.wrap_angle(1j), "theta"),
])
def test_complex_input_is_refused_naming_the_argument(call, name):
    with pytest.raises(TypeError, match=f"^{name} must hold real numbers"):
        call()


@pytest.mark.parametrize("call, name", [
    (lambda: rotations.wrap_angle(None), "theta"),
    (lambda: quaternion.quaternion_norm(None), "q"),
    (lambda: quaternion.quaternion_norm([1.0, None, 0.0, 0.0]), "q"),
    (lambda: ROBOT.fk("0 0 0 0 0 0"), "q"),
    (lambda: ik.ur(ROBOT, "pose"), "target"),
])
def test_none_and_text_are_refused_naming_the_argument(call, name):
    with pytest.raises(TypeError, match=f"^{name} must"):
        call()


def test_the_complex_module_takes_complex_numbers():
    np.testing.assert_allclose(dqlab.complex.rotate_planar(1 + 0j, np.pi / 2), 1j, atol=1e-15)


# --- tolerances ---------------------------------------------------------------------------

@pytest.mark.parametrize("bad", [np.nan, -1.0, "x", None])
@pytest.mark.parametrize("call, name", [
    (lambda t: ik.ur(ROBOT, X_UR, tol=t), "tol"),
    (lambda t: ik.ur(ROBOT, X_UR, singular_tol=t), "singular_tol"),
    (lambda t: ik.ur(ROBOT, X_UR, pose_tol=t), "pose_tol"),
    (lambda t: ik.scara(scara_rsm5(), np.eye(4), tol=t), "tol"),
    (lambda t: ik.scara(scara_rsm5(), np.eye(4), rotation_tol=t), "rotation_tol"),
    (lambda t: ik.desk_arm(desk_arm(), [0.2, 0.0, 0.1], tol=t), "tol"),
    (lambda t: ik.numerical(ROBOT, X_UR, Q_UR, tol=t), "tol"),
    (lambda t: ik.numerical(ROBOT, X_UR, Q_UR, damping=t), "damping"),
])
def test_a_tolerance_must_be_a_number_at_least_zero(call, name, bad):
    if bad is None and name == "rotation_tol":
        pytest.skip("rotation_tol=None is the default: the same as tol")
    with pytest.raises(ValueError, match=f"^{name} must be a number >= 0"):
        call(bad)


@pytest.mark.parametrize("bad", [np.nan, -1.0])
@pytest.mark.parametrize("call", [
    lambda t: quaternion.matrix_from_quaternion([2.0, 0, 0, 0], tol=t),
    lambda t: quaternion.matrix_from_quaternion(np.array([[2.0, 0, 0, 0]] * 3), tol=t),
    lambda t: quaternion.check_unit_quaternion([0.6, 0.0, 0.0, 0.0], tol=t),
    lambda t: dualquat.check_unit_dual_quaternion([1.0, 0, 0, 0, 1.0, 0, 0, 0], tol=t),
    lambda t: rotations.check_rotation_matrix(2 * np.eye(3), tol=t),
])
def test_a_nan_or_negative_tolerance_never_lets_bad_input_through(call, bad):
    with pytest.raises(ValueError, match="^tol must be a number >= 0"):
        call(bad)


def test_good_input_passes_whatever_the_checks_tolerance():
    # the tolerance is checked when a value fails the test, so good input costs nothing
    assert quaternion.matrix_from_quaternion([1.0, 0, 0, 0], tol=np.inf).shape == (3, 3)


# --- shapes and magnitudes ----------------------------------------------------------------

@pytest.mark.parametrize("function", [quaternion.quaternion_identity,
                                      dualquat.dual_quaternion_identity,
                                      transforms.transform_identity])
def test_identity_shapes_must_be_whole_numbers(function):
    assert function(3).shape[:1] == (3,) and function((2, 0)).shape[:2] == (2, 0)
    for bad in (2.7, -1, (2, 1.5), "2", True):
        with pytest.raises(ValueError, match="shape must be a non-negative int"):
            function(bad)


def test_a_python_int_beyond_the_float_range_is_a_value_error():
    with pytest.raises(ValueError, match="q must be an array of numbers"):
        quaternion.quaternion_norm([10 ** 400, 0, 0, 0])


# --- lazily imported sub-packages ---------------------------------------------------------

def test_probing_for_a_missing_sub_package_is_false_not_an_import_error():
    assert not hasattr(dqlab, "no_such_module")
    for name in sorted(dqlab._SUBMODULES):
        present = importlib.util.find_spec(f"dqlab.{name}") is not None
        assert hasattr(dqlab, name) == present, name


# --- the IK helpers ----------------------------------------------------------------------

RESULT = ik.ur(ROBOT, X_UR)


@pytest.mark.parametrize("call, error, message", [
    (lambda: RESULT.best(np.full(6, np.nan)), ValueError, "q_ref contains NaN"),
    (lambda: RESULT.best(np.zeros(5)), ValueError, r"q_ref must have shape \(\.\.\., 6\)"),
    (lambda: ik.closest_solution(RESULT, None), TypeError, "q_ref must be an array"),
    (lambda: ik.equivalent_solutions(1.0), ValueError, r"q must have shape \(\.\.\., n\)"),
    (lambda: ik.equivalent_solutions([np.nan] * 6), ValueError, "q contains NaN"),
    (lambda: ik.equivalent_solutions(np.zeros(30)), ValueError, "at most 12 joints"),
    (lambda: ik.equivalent_solutions(np.zeros(6), limits=[1.0]), ValueError,
     r"limits must have shape"),
])
def test_ik_helpers_validate_their_arguments(call, error, message):
    with pytest.raises(error, match=message):
        call()


def test_ik_helpers_still_answer_good_input():
    np.testing.assert_allclose(RESULT.best(Q_UR), Q_UR, atol=1e-12)
    np.testing.assert_allclose(ik.closest_solution(RESULT, Q_UR), Q_UR, atol=1e-12)


@pytest.mark.parametrize("args, message", [
    (([1, 0, 0, 0], [0, 0, 0], [0, 0, 0, 0], [0, 0, 0]), "q2 is the zero quaternion"),
    (([1, 0, 0, 0], [0, 0, 0], [np.nan, 0, 0, 0], [0, 0, 0]), "q2 contains NaN"),
    (([2, 0, 0, 0], [0, 0, 0], [1, 0, 0, 0], [0, 0, 0]), "q1 must be a unit quaternion"),
    (([1, 0, 0, 0], [0, 0, 0], [1, 0, 0, 0], [np.inf, 0, 0]), "p2 contains NaN"),
    (([1, 0, 0, 0], [0, 0], [1, 0, 0, 0], [0, 0, 0]), r"p1 must have shape"),
])
def test_pair_product_checks_both_pairs_by_name(args, message):
    with pytest.raises(ValueError, match=message):
        dualquat.pair_product(*args)


# --- huge and tiny magnitudes ------------------------------------------------------------

@pytest.mark.parametrize("scale", [1e-200, 1e-160, 1e160, 1e200])
def test_norms_and_normalisations_neither_overflow_nor_underflow(scale):
    q = np.array([1.0, 1.0, 0.0, 0.0]) * scale
    np.testing.assert_allclose(quaternion.quaternion_norm(q), np.sqrt(2) * scale, rtol=1e-15)
    np.testing.assert_allclose(quaternion.quaternion_normalize(q), q / scale / np.sqrt(2),
                               rtol=1e-15)
    np.testing.assert_allclose(quaternion.quaternion_product(
        quaternion.quaternion_inverse(q), q), [1, 0, 0, 0], atol=1e-15)
    axis = np.array([1.0, 1.0, 0.0]) * scale
    R = rotations.matrix_from_axis_angle(axis, 0.5)
    np.testing.assert_allclose(R, rotations.matrix_from_axis_angle([1, 1, 0], 0.5),
                               atol=1e-15)
    np.testing.assert_allclose(quaternion.quaternion_from_axis_angle(axis, 0.5),
                               quaternion.quaternion_from_axis_angle([1, 1, 0], 0.5),
                               atol=1e-15)
    Q = np.array([1.0, 1.0, 0, 0, 0, 0, 0, 0]) * scale
    np.testing.assert_allclose(dualquat.dual_quaternion_normalize(Q)[:4],
                               [np.sqrt(0.5), np.sqrt(0.5), 0, 0], rtol=1e-15)


def test_norms_of_ordinary_values_are_the_plain_formula():
    rng = np.random.default_rng(3)
    q = rng.normal(size=(100, 4))
    assert np.array_equal(quaternion.quaternion_norm(q), np.sqrt(np.sum(q * q, axis=-1)))
