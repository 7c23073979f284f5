"""Tests of dqlab.identify: the lab's linear identification and the UR3's DH calibration."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dqlab import identify as idf
from dqlab.models import desk_arm, desk_arm_joints_from_lab, ur3, ur3_mdh
from dqlab.quaternion import quaternion_from_matrix

# the lab's verification table (answer 7): angles in degrees, positions in mm
LAB_Q_DEG = np.array([[90, 90, 0], [90, 51, 65], [90, 42, 21], [90, 90, 45]])
LAB_P_MM = np.array([[229, 0, 179], [226, 0, 0], [325, 0, 73], [182, 0, 64]])

# the lengths used for synthetic desk-arm data (metres): l0, l1, l2, l3, l4
TRUE_LENGTHS = np.array([0.047, 0.144, 0.162, 0.067, 0.012])

# UR3 parameters that position measurements cannot separate from the others; the greedy
# choice holds these at their nominal values
UR3_HELD_POSITION = ("d3", "d4", "a5", "alpha5", "theta6", "alpha6")
UR3_HELD_POSE = ("d3", "d4")


def random_lab_angles(rng, m):
    return np.column_stack([rng.uniform(-np.pi / 2, np.pi / 2, m),
                            rng.uniform(0.2, 1.4, m), rng.uniform(-0.3, 1.2, m)])


def lab_positions(q_lab, lengths=TRUE_LENGTHS):
    return idf.desk_arm_regressor(q_lab) @ lengths


def perturbed_ur3(rng, held, scale=1e-3, nominal=None):
    """Nominal UR3 and a 'real' one whose parameters differ by ~scale except the held ones."""
    nominal = ur3() if nominal is None else nominal
    names = idf.dh_parameter_names(nominal)
    x0 = idf.dh_parameters(nominal)
    x = x0 + rng.normal(0.0, scale, x0.size)
    for name in held:
        x[names.index(name)] = x0[names.index(name)]
    return nominal, idf.robot_from_dh_parameters(nominal, x), x


# -- the linear problem ------------------------------------------------------------------------


def test_regressor_matches_the_desk_arm_model():
    rng = np.random.default_rng(1)
    q_lab = random_lab_angles(rng, 50)
    lengths = np.array([0.035, 0.144, 0.162, 0.067, 0.0])      # the model's l0 - l4 = 35 mm
    fk = desk_arm().fk(desk_arm_joints_from_lab(q_lab))[:, :3, 3]
    assert np.allclose(lab_positions(q_lab, lengths), fk, atol=1e-15)


def test_regressor_broadcasts_over_leading_axes():
    rng = np.random.default_rng(2)
    q = random_lab_angles(rng, 6).reshape(2, 3, 3)
    A = idf.desk_arm_regressor(q)
    assert A.shape == (2, 3, 3, 5)
    assert np.array_equal(A[1, 2], idf.desk_arm_regressor(q[1, 2]))


def test_exact_desk_arm_data_recover_the_identifiable_lengths():
    rng = np.random.default_rng(3)
    q_lab = random_lab_angles(rng, 8)
    fit = idf.identify_desk_arm(q_lab, lab_positions(q_lab))
    l0, l1, l2, l3, l4 = TRUE_LENGTHS
    values = dict((label, value) for label, value, _ in fit.combinations())
    assert set(values) == {"l0 - l4", "l1", "l2", "l3"}
    assert abs(values["l0 - l4"] - (l0 - l4)) <= 1e-9
    for name, want in (("l1", l1), ("l2", l2), ("l3", l3)):
        assert abs(values[name] - want) <= 1e-9
        assert abs(fit.value(name) - want) <= 1e-9
    assert np.abs(fit.residuals).max() < 1e-12


def test_desk_arm_rank_and_null_space_are_stated_by_name():
    rng = np.random.default_rng(4)
    q_lab = random_lab_angles(rng, 10)
    fit = idf.identify_desk_arm(q_lab, lab_positions(q_lab))
    assert fit.rank == 4
    assert fit.unidentifiable == ("l0 + l4",)
    assert fit.identifiable == ("l0 - l4", "l1", "l2", "l3")
    assert fit.held == ("l4",)
    assert fit.value("l4") == 0.0
    null = fit.null_space[:, 0] * np.sign(fit.null_space[0, 0])
    assert np.allclose(null, np.array([1, 0, 0, 0, 1]) / np.sqrt(2), atol=1e-12)
    assert fit.singular_values[-1] < 1e-12 * fit.singular_values[0]
    assert "l0 + l4" in fit.summary()


def test_the_lab_table_gives_the_lab_lengths_to_the_millimetre():
    fit = idf.identify_desk_arm(np.radians(LAB_Q_DEG), LAB_P_MM / 1000)
    mm = {label: round(value * 1000) for label, value, _ in fit.combinations()}
    assert mm == {"l0 - l4": 35, "l1": 144, "l2": 162, "l3": 67}
    # the table is rounded to the millimetre, so no residual exceeds half a millimetre
    assert np.abs(fit.residuals).max() < 0.5e-3


def test_desk_arm_monte_carlo_spread_matches_the_standard_errors():
    """Over 400 seeded trials with noise sigma = 0.5 mm, the spread of each identifiable
    combination agrees with its predicted standard error within 15 %, and the residual
    sigma estimates the noise within 5 %."""
    rng = np.random.default_rng(5)
    q_lab = random_lab_angles(rng, 12)
    exact = lab_positions(q_lab)
    sigma = 0.5e-3
    fits = [idf.identify_desk_arm(q_lab, exact + rng.normal(0.0, sigma, exact.shape))
            for _ in range(400)]
    values = np.array([[v for _, v, _ in f.combinations()] for f in fits])
    reference = fits[0]
    rows = reference.identifiable_rows
    predicted = sigma * np.sqrt(np.einsum("ij,jk,ik->i", rows, reference.unit_covariance, rows))
    ratio = values.std(axis=0, ddof=1) / predicted
    assert np.all((ratio > 0.85) & (ratio < 1.15)), ratio
    sigmas = np.array([f.sigma for f in fits])
    assert abs(sigmas.mean() / sigma - 1.0) < 0.05
    # unbiased: the mean is within 4 standard errors of the mean of the truth
    truth = rows @ TRUE_LENGTHS
    assert np.all(np.abs(values.mean(axis=0) - truth) < 4 * predicted / np.sqrt(400))


def test_fit_linear_agrees_with_lstsq_and_the_textbook_covariance():
    rng = np.random.default_rng(6)
    A = rng.normal(size=(40, 5)) * [1.0, 10.0, 0.1, 3.0, 1.0]
    b = rng.normal(size=40)
    fit = idf.fit_linear(A, b)
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    assert np.allclose(fit.estimate, x, rtol=1e-12, atol=1e-14)
    r = b - A @ x
    s2 = r @ r / (40 - 5)
    assert np.isclose(fit.sigma**2, s2, rtol=1e-12)
    assert np.allclose(fit.covariance, s2 * np.linalg.inv(A.T @ A), rtol=1e-9, atol=1e-15)
    assert fit.rank == 5 and fit.unidentifiable == () and fit.held == ()
    As = A / np.linalg.norm(A, axis=0)
    assert np.isclose(fit.condition_number, np.linalg.cond(As), rtol=1e-9)


def test_fit_linear_holds_the_reference_value_of_an_unidentifiable_parameter():
    t = np.linspace(0.0, 1.0, 9)
    A = np.column_stack([np.ones_like(t), t, 2.0 * np.ones_like(t)])
    fit = idf.fit_linear(A, 3.0 + t, names=["c", "m", "k"], reference=[0.0, 0.0, 0.5])
    assert fit.held == ("k",)
    assert fit.unidentifiable == ("c - 0.5 k",)
    assert fit.identifiable == ("c + 2 k", "m")
    assert np.isclose(fit.value("k"), 0.5) and np.isclose(fit.value("c"), 2.0)
    label, value, _ = fit.combinations()[0]
    assert label == "c + 2 k" and np.isclose(value, 3.0)


@pytest.mark.parametrize(
    ("A", "b", "kwargs", "message"),
    [
        (np.ones((4, 2)), np.ones(3), {}, "b must have shape"),
        (np.ones(4), np.ones(4), {}, "A must have shape"),
        ([[1.0, np.nan], [0.0, 1.0], [1.0, 1.0]], np.ones(3), {}, "A contains NaN"),
        (np.eye(3)[:, :2], [1.0, np.inf, 0.0], {}, "b contains NaN"),
        (np.eye(2), np.ones(2), {}, "too few measurements: 2 equations for 2 identifiable"),
        (np.ones((2, 3)), np.ones(2), {}, "too few measurements: 2 equations for 3 unknowns"),
        (np.ones((5, 2)) + np.eye(5, 2), np.ones(5), {"names": ["a"]}, "one entry per column"),
        (np.ones((5, 2)) + np.eye(5, 2), np.ones(5), {"names": ["a", "a"]}, "distinct"),
        (np.ones((5, 2)) + np.eye(5, 2), np.ones(5), {"reference": [0.0]}, "reference"),
    ],
)
def test_fit_linear_rejects_bad_input(A, b, kwargs, message):
    with pytest.raises(ValueError, match=message):
        idf.fit_linear(A, b, **kwargs)


def test_identify_desk_arm_rejects_bad_input():
    q = np.radians(LAB_Q_DEG)
    p = LAB_P_MM / 1000
    with pytest.raises(ValueError, match="positions must have shape"):
        idf.identify_desk_arm(q, p[:3])
    with pytest.raises(ValueError, match="q_lab must have shape"):
        idf.identify_desk_arm(q[0], p[0])
    with pytest.raises(ValueError, match="positions contains NaN"):
        idf.identify_desk_arm(q, np.where(p == 0, np.nan, p))
    one_pose = random_lab_angles(np.random.default_rng(0), 1)
    with pytest.raises(ValueError, match="too few measurements: 3 equations for 5 unknowns"):
        idf.identify_desk_arm(one_pose, lab_positions(one_pose))


def test_an_ill_conditioned_fit_is_reported():
    t = np.linspace(0.0, 1.0, 20)
    A = np.column_stack([t, t + 1e-6 * np.sin(7 * t), np.ones_like(t)])
    with pytest.warns(idf.IllConditionedWarning, match="condition number"):
        fit = idf.fit_linear(A, t)
    assert fit.condition_number > 1e6


# -- DH parameters of a chain ----------------------------------------------------------------


def test_dh_parameters_round_trip():
    robot = ur3_mdh()
    x = idf.dh_parameters(robot)
    assert x.shape == (24,) and len(idf.dh_parameter_names(robot)) == 24
    copy = idf.robot_from_dh_parameters(robot, x)
    q = np.random.default_rng(7).uniform(-3, 3, size=(10, 6))
    assert np.array_equal(copy.fk(q), robot.fk(q))
    assert copy.convention == "mdh" and np.array_equal(copy.limits, robot.limits)
    with pytest.raises(ValueError, match="parameters must have shape"):
        idf.robot_from_dh_parameters(robot, x[:-1])


def _rotation_vector(R):
    r = quaternion_from_matrix(R)
    s = np.linalg.norm(r[1:])
    return 2.0 * np.arctan2(s, r[0]) * r[1:] / s if s > 0 else np.zeros(3)


def finite_difference_jacobian(robot, q, h=1e-6):
    """Central differences of the TCP position and orientation over every DH parameter."""
    x0 = idf.dh_parameters(robot)
    J = np.zeros((len(q), 6, x0.size))
    for k in range(x0.size):
        plus, minus = x0.copy(), x0.copy()
        plus[k] += h
        minus[k] -= h
        Xp = idf.robot_from_dh_parameters(robot, plus).fk(q)
        Xm = idf.robot_from_dh_parameters(robot, minus).fk(q)
        J[:, :3, k] = (Xp[:, :3, 3] - Xm[:, :3, 3]) / (2 * h)
        for i in range(len(q)):
            J[i, 3:, k] = _rotation_vector(Xp[i, :3, :3] @ Xm[i, :3, :3].T) / (2 * h)
    return J


def _with_base_and_tool(robot):
    from dqlab.rotations import matrix_from_axis_angle

    base = np.eye(4)
    base[:3, :3] = matrix_from_axis_angle([0.3, -0.2, 0.9], 0.7)
    base[:3, 3] = [0.1, -0.2, 0.3]
    tool = np.eye(4)
    tool[:3, :3] = matrix_from_axis_angle([1.0, 0.4, 0.0], 0.4)
    tool[:3, 3] = [0.02, -0.01, 0.15]
    robot.base = base
    robot.tool = tool
    return robot


@pytest.mark.parametrize("make", [ur3, ur3_mdh, desk_arm,
                                  lambda: _with_base_and_tool(ur3()),
                                  lambda: _with_base_and_tool(ur3_mdh())],
                         ids=["ur3", "ur3_mdh", "desk_arm", "ur3+tool", "ur3_mdh+tool"])
def test_identification_jacobian_matches_finite_differences(make):
    robot = make()
    q = np.random.default_rng(8).uniform(-np.pi, np.pi, size=(6, robot.n))
    J = idf.identification_jacobian(robot, q, measure="pose")
    J_fd = finite_difference_jacobian(robot, q)
    assert np.abs(J - J_fd).max() < 1e-8
    assert np.array_equal(idf.identification_jacobian(robot, q), J[:, :3])


def test_identification_jacobian_broadcasts_over_leading_axes():
    robot = ur3()
    q = np.random.default_rng(9).uniform(-3, 3, size=(2, 3, 6))
    J = idf.identification_jacobian(robot, q)
    assert J.shape == (2, 3, 3, 24)
    assert np.allclose(J[1, 2], idf.identification_jacobian(robot, q[1, 2]), atol=1e-15)
    with pytest.raises(ValueError, match="measure must be"):
        idf.identification_jacobian(robot, q, measure="orientation")


# -- calibration --------------------------------------------------------------------------------


def test_ur3_position_calibration_reports_the_unidentifiable_parameters():
    nominal = ur3()
    q = np.random.default_rng(10).uniform(-np.pi, np.pi, size=(25, 6))
    fit = idf.identify_dh_parameters(nominal, q, nominal.fk(q)[:, :3, 3])
    assert fit.rank == 18
    assert fit.unidentifiable == ("d2 - d4", "d3 - d4", "theta5 + 0.0819 a5",
                                  "d5 - 12.21 alpha5", "theta6", "alpha6")
    assert fit.held == UR3_HELD_POSITION
    assert "d2 + d3 + d4" in fit.identifiable
    s = fit.singular_values
    assert np.all(s[:18] > 0.1) and np.all(s[18:] < 1e-12)


def test_ur3_pose_calibration_identifies_the_wrist_too():
    nominal = ur3()
    q = np.random.default_rng(11).uniform(-np.pi, np.pi, size=(10, 6))
    fit = idf.identify_dh_parameters(nominal, q, nominal.fk(q), measure="pose")
    assert fit.rank == 22
    assert fit.unidentifiable == ("d2 - d4", "d3 - d4")
    assert fit.held == UR3_HELD_POSE


@pytest.mark.parametrize(("measure", "held"), [("position", UR3_HELD_POSITION),
                                               ("pose", UR3_HELD_POSE)])
def test_exact_data_recover_the_ur3_parameters(measure, held):
    rng = np.random.default_rng(12)
    nominal, real, x_true = perturbed_ur3(rng, held, scale=2e-3)
    q = rng.uniform(-np.pi, np.pi, size=(30, 6))
    X = real.fk(q)
    fit = idf.identify_dh_parameters(nominal, q, X[:, :3, 3] if measure == "position" else X,
                        measure=measure)
    assert fit.converged and fit.held == held
    assert np.abs(fit.estimate - x_true).max() <= 1e-9
    assert np.allclose(fit.robot.fk(q), X, atol=1e-12)


def test_exact_data_recover_a_modified_dh_chain():
    rng = np.random.default_rng(13)
    nominal = ur3_mdh()
    q = rng.uniform(-np.pi, np.pi, size=(30, 6))
    probe = idf.identify_dh_parameters(nominal, q, nominal.fk(q)[:, :3, 3])
    _, real, x_true = perturbed_ur3(rng, probe.held, nominal=nominal)
    fit = idf.identify_dh_parameters(nominal, q, real.fk(q)[:, :3, 3])
    assert np.abs(fit.estimate - x_true).max() <= 1e-9


def test_fixed_parameters_stay_at_their_nominal_values():
    rng = np.random.default_rng(14)
    nominal, real, x_true = perturbed_ur3(rng, UR3_HELD_POSITION + ("theta1", "d1"))
    q = rng.uniform(-np.pi, np.pi, size=(20, 6))
    fit = idf.identify_dh_parameters(nominal, q, real.fk(q)[:, :3, 3], fixed=("theta1", "d1"))
    assert fit.held == ("theta1", "d1") + UR3_HELD_POSITION
    assert np.abs(fit.estimate - x_true).max() <= 1e-9


def test_ur3_monte_carlo_spread_matches_the_standard_errors():
    """200 seeded trials, 30 poses, noise sigma = 0.1 mm on each coordinate: the spread of
    every estimated parameter is within a factor 1.25 of its predicted standard error, and
    the residual sigma estimates the noise within 5 %."""
    rng = np.random.default_rng(15)
    nominal, real, x_true = perturbed_ur3(rng, UR3_HELD_POSITION)
    q = rng.uniform(-np.pi, np.pi, size=(30, 6))
    exact = real.fk(q)[:, :3, 3]
    sigma = 1e-4
    fits = [idf.identify_dh_parameters(nominal, q, exact + rng.normal(0.0, sigma, exact.shape))
            for _ in range(200)]
    estimates = np.array([f.estimate for f in fits])
    reference = idf.identify_dh_parameters(nominal, q, exact)
    kept = reference.estimated
    predicted = sigma * np.sqrt(np.diag(reference.unit_covariance))[kept]
    ratio = estimates[:, kept].std(axis=0, ddof=1) / predicted
    assert np.all((ratio > 0.8) & (ratio < 1.25)), ratio
    assert abs(np.mean([f.sigma for f in fits]) / sigma - 1.0) < 0.05
    # the reported standard errors (from the residuals) agree with the predicted ones
    reported = np.array([f.standard_errors[kept] for f in fits]).mean(axis=0)
    assert np.allclose(reported, predicted, rtol=0.1)


def test_calibration_error_shrinks_with_poses_and_grows_with_noise():
    rng = np.random.default_rng(16)
    nominal, real, _ = perturbed_ur3(rng, ())
    q_check = rng.uniform(-np.pi, np.pi, size=(200, 6))

    def error(m, sigma, trials=6):
        """RMS flange-position error on fresh poses after calibrating on m noisy poses."""
        out = []
        for _ in range(trials):
            q = rng.uniform(-np.pi, np.pi, size=(m, 6))
            p = real.fk(q)[:, :3, 3] + rng.normal(0.0, sigma, (m, 3))
            fit = idf.identify_dh_parameters(nominal, q, p)
            e = fit.robot.fk(q_check)[:, :3, 3] - real.fk(q_check)[:, :3, 3]
            out.append(np.sqrt(np.mean(np.sum(e**2, axis=-1))))
        return np.mean(out)

    e10, e80 = error(10, 1e-4), error(80, 1e-4)
    e80_noisy = error(80, 1e-3)
    assert e80 < e10 / 2                     # ~ 1 / sqrt(m): 2.8 times smaller
    assert 5 < e80_noisy / e80 < 20          # ~ sigma: 10 times larger
    before = real.fk(q_check)[:, :3, 3] - nominal.fk(q_check)[:, :3, 3]
    assert e80 < 0.1 * np.sqrt(np.mean(np.sum(before**2, axis=-1)))


def test_calibration_agrees_with_scipy_least_squares():
    optimize = pytest.importorskip("scipy.optimize")
    rng = np.random.default_rng(17)
    nominal, real, _ = perturbed_ur3(rng, ())
    q = rng.uniform(-np.pi, np.pi, size=(20, 6))
    measured = real.fk(q)[:, :3, 3] + rng.normal(0.0, 2e-4, (20, 3))
    fit = idf.identify_dh_parameters(nominal, q, measured)
    x0 = idf.dh_parameters(nominal)
    kept = fit.estimated

    def residuals(free):
        x = x0.copy()
        x[kept] = free
        return (idf.robot_from_dh_parameters(nominal, x).fk(q)[:, :3, 3] - measured).ravel()

    reference = optimize.least_squares(residuals, x0[kept], xtol=1e-15, ftol=1e-15,
                                       gtol=1e-15, method="lm")
    assert np.allclose(fit.estimate[kept], reference.x, atol=1e-9)


def test_identify_dh_parameters_rejects_bad_input():
    robot = ur3()
    q = np.random.default_rng(18).uniform(-3, 3, size=(10, 6))
    p = robot.fk(q)[:, :3, 3]
    with pytest.raises(ValueError, match="q must have shape"):
        idf.identify_dh_parameters(robot, q[:, :5], p)
    with pytest.raises(ValueError, match=r"measured positions must have shape \(10, 3\)"):
        idf.identify_dh_parameters(robot, q, p[:9])
    with pytest.raises(ValueError, match=r"measured must have shape \(\.\.\., 4, 4\)"):
        idf.identify_dh_parameters(robot, q, p, measure="pose")
    with pytest.raises(ValueError, match="measured contains NaN"):
        idf.identify_dh_parameters(robot, q, np.where(p > 0, np.nan, p))
    q_nan = q.copy()
    q_nan[3, 2] = np.nan
    with pytest.raises(ValueError, match="q contains NaN"):
        idf.identify_dh_parameters(robot, q_nan, p)
    with pytest.raises(ValueError, match="too few measurements: 15 equations for 24 unknowns"):
        idf.identify_dh_parameters(robot, q[:5], p[:5])
    with pytest.raises(ValueError, match="unknown parameters"):
        idf.identify_dh_parameters(robot, q, p, fixed=("d7",))
    with pytest.raises(ValueError, match="measure must be"):
        idf.identify_dh_parameters(robot, q, p, measure="orientation")
    sheared = robot.fk(q)
    sheared[:, 0, 1] += 0.1
    with pytest.raises(ValueError, match="measured"):
        idf.identify_dh_parameters(robot, q, sheared, measure="pose")


def test_fixed_accepts_a_single_name():
    robot = ur3()
    q = np.random.default_rng(22).uniform(-3, 3, size=(12, 6))
    fit = idf.identify_dh_parameters(robot, q, robot.fk(q)[:, :3, 3], fixed="d1")
    assert fit.held[0] == "d1" and not fit.estimated[1]


@settings(max_examples=30)
@given(st.integers(min_value=0, max_value=2**32 - 1))
def test_fit_linear_recovers_any_exact_solution(seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(12, 4)) * rng.uniform(0.1, 10.0, size=4)
    x = rng.normal(size=4)
    fit = idf.fit_linear(A, A @ x)
    assert np.allclose(fit.estimate, x, rtol=1e-9, atol=1e-9)
    assert fit.rank == 4 and np.abs(fit.residuals).max() < 1e-9


@settings(max_examples=30)
@given(st.lists(st.floats(min_value=0.01, max_value=0.3), min_size=5, max_size=5),
       st.integers(min_value=0, max_value=2**32 - 1))
def test_desk_arm_identification_recovers_any_lengths(lengths, seed):
    lengths = np.array(lengths)
    q_lab = random_lab_angles(np.random.default_rng(seed), 6)
    fit = idf.identify_desk_arm(q_lab, lab_positions(q_lab, lengths))
    want = [lengths[0] - lengths[4], lengths[1], lengths[2], lengths[3]]
    assert np.allclose([v for _, v, _ in fit.combinations()], want, atol=1e-9)


def test_poses_that_barely_differ_are_reported_as_ill_conditioned():
    robot = ur3()
    rng = np.random.default_rng(19)
    q = np.array([0.3, -1.0, 1.2, -0.5, 0.8, 0.1]) + rng.normal(0.0, 1e-3, (20, 6))
    with pytest.warns(idf.IllConditionedWarning, match="ill-conditioned"):
        fit = idf.identify_dh_parameters(robot, q, robot.fk(q)[:, :3, 3])
    assert fit.condition_number > 1e6


def test_well_posed_calibration_issues_no_warning():
    robot = ur3()
    q = np.random.default_rng(20).uniform(-np.pi, np.pi, size=(15, 6))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = idf.identify_dh_parameters(robot, q, robot.fk(q)[:, :3, 3])
    assert fit.condition_number < 100


def test_non_convergence_is_reported():
    rng = np.random.default_rng(21)
    nominal, real, _ = perturbed_ur3(rng, UR3_HELD_POSITION, scale=0.05)
    q = rng.uniform(-np.pi, np.pi, size=(20, 6))
    with pytest.warns(idf.IllConditionedWarning, match="did not converge"):
        fit = idf.identify_dh_parameters(nominal, q, real.fk(q)[:, :3, 3], max_iter=1)
    assert not fit.converged and fit.iterations == 1


# --- scale invariance and the tolerances --------------------------------------------------

@pytest.mark.parametrize("scale", [1e-160, 1e160])
def test_fit_linear_gives_the_same_answer_in_any_units(scale):
    """The same problem with A and b scaled together: the same estimate, rank, combinations
    and standard errors (the column norms and the covariance never overflow or underflow)."""
    rng = np.random.default_rng(4)
    t = np.linspace(0.0, 1.0, 20)
    A = np.column_stack([np.ones(20), t, t**2, np.ones(20)])
    b = 1.0 + 2.0 * t - 3.0 * t**2 + rng.normal(scale=1e-3, size=20)
    names = ["a", "b", "c", "d"]
    reference = idf.fit_linear(A, b, names=names)
    fit = idf.fit_linear(A * scale, b * scale, names=names)
    assert fit.rank == reference.rank == 3
    assert fit.unidentifiable == reference.unidentifiable == ("a - d",)
    assert fit.identifiable == reference.identifiable
    np.testing.assert_allclose(fit.estimate, reference.estimate, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(fit.standard_errors, reference.standard_errors, rtol=1e-9)
    assert fit.sigma == pytest.approx(reference.sigma * scale, rel=1e-9)
    np.testing.assert_allclose([s for *_, s in fit.combinations()],
                               [s for *_, s in reference.combinations()], rtol=1e-9)


def test_a_column_in_smaller_units_still_has_an_effect():
    """Column scaling is documented: a length given in nanometres is estimated, in
    nanometres, not declared without effect."""
    t = np.linspace(0.0, 1.0, 12)
    A = np.column_stack([np.ones(12), t, 1e-9 * t**2])
    b = 1.0 + 2.0 * t - 3.0 * t**2
    fit = idf.fit_linear(A, b, names=["a", "b", "c"])
    assert fit.held == () and fit.rank == 3
    assert fit.value("c") == pytest.approx(-3e9, rel=1e-9)


@pytest.mark.parametrize("bad", [np.nan, -1.0, 1j, "x", None, 1.0])
def test_rank_tol_must_be_a_relative_threshold(bad):
    with pytest.raises(ValueError, match="^rank_tol must be"):
        idf.fit_linear(np.eye(3), np.ones(3), rank_tol=bad)


@pytest.mark.parametrize("bad", [np.nan, 0.0, -0.1, np.inf, 1j])
def test_identify_dh_parameters_refuses_a_rotation_scale_that_is_not_a_positive_number(bad):
    robot = desk_arm()
    q = np.random.default_rng(2).uniform(0.2, 1.2, (8, 3))
    with pytest.raises(ValueError, match="^rotation_scale must be a finite number > 0"):
        idf.identify_dh_parameters(robot, q, robot.fk(q), measure="pose", rotation_scale=bad)


@pytest.mark.parametrize("name, bad", [("tol", np.inf), ("tol", -1.0), ("max_iter", 2.5),
                                        ("max_iter", 0), ("max_condition", np.nan)])
def test_identify_dh_parameters_refuses_bad_iteration_settings(name, bad):
    robot = desk_arm()
    q = np.random.default_rng(2).uniform(0.2, 1.2, (8, 3))
    with pytest.raises(ValueError, match=f"^{name} must be"):
        idf.identify_dh_parameters(robot, q, robot.fk(q)[:, :3, 3], **{name: bad})


def test_identification_functions_refuse_a_robot_that_is_none():
    for call in (lambda: idf.dh_parameter_names(None), lambda: idf.dh_parameters(None),
                 lambda: idf.identification_jacobian(None, np.zeros(3)),
                 lambda: idf.identify_dh_parameters(None, np.zeros((8, 3)), np.zeros((8, 3)))):
        with pytest.raises(TypeError, match="^robot must be a Robot, got None"):
            call()
