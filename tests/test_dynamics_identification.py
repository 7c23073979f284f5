"""dqlab.dynamics_identification: the regressor with motors, the base parameters (against
scipy's pivoted QR and the rank of pinocchio's own regressor), the Fourier excitation within
its bounds, and the identified model."""

import numpy as np
import pytest
from test_dynamics import pinocchio_model, random_states

from dqlab import dynamics, models
from dqlab import dynamics_identification as dyn_id

UR3 = models.ur3()
NAMES = dyn_id.parameter_names(UR3)


@pytest.fixture(scope="module")
def ur3_base():
    q, qd, qdd = random_states(UR3, 150, seed=41)
    W = dyn_id.regressor_with_motors(UR3, q, qd, qdd).reshape(-1, len(NAMES))
    return W, dyn_id.base_parameters(W, NAMES, prefer=dyn_id.preferred_order(UR3))


def test_the_regressor_with_motors_adds_armature_and_friction():
    q, qd, qdd = random_states(UR3, 20, seed=42)
    rng = np.random.default_rng(42)
    a, f_v, f_c = rng.uniform(0.01, 1.0, (3, 6))
    phi = np.concatenate([dynamics.inertial_parameters(UR3), np.column_stack([a, f_v, f_c])
                          .ravel()])
    W = dyn_id.regressor_with_motors(UR3, q, qd, qdd)
    assert W.shape == (20, 6, 78) and len(NAMES) == 78
    expected = dynamics.inverse_dynamics(UR3, q, qd, qdd) + a * qdd + f_v * qd + f_c * np.sign(qd)
    np.testing.assert_allclose(W @ phi, expected, atol=1e-12)
    M = dyn_id.motor_regressor([0.01, -0.5], [1.0, 2.0], zero_speed=0.02)
    np.testing.assert_array_equal(M, [[1.0, 0.01, 0.0, 0, 0, 0], [0, 0, 0, 2.0, -0.5, -1.0]])
    assert dyn_id.preferred_order(UR3)[60:] == NAMES[60:]
    assert sorted(dyn_id.preferred_order(UR3)) == sorted(NAMES)


def test_the_pivoted_qr_is_scipys():
    linalg = pytest.importorskip("scipy.linalg")
    rng = np.random.default_rng(43)
    A = rng.normal(size=(40, 12)) @ np.diag(rng.uniform(0.1, 10, 12))
    A[:, 5] = A[:, 1] - 2 * A[:, 3]                         # a dependent column
    R, order = dyn_id._qr_with_pivoting(A)
    _, R_scipy, order_scipy = linalg.qr(A, pivoting=True, mode="economic")
    np.testing.assert_array_equal(order[:11], order_scipy[:11])
    np.testing.assert_allclose(np.abs(np.diag(R)), np.abs(np.diag(R_scipy)), atol=1e-10)
    np.testing.assert_allclose(np.abs(R), np.abs(R_scipy), atol=1e-10)


def test_the_ur3_has_52_base_parameters_named_and_exact(ur3_base):
    W, base = ur3_base
    assert base.rank == 52 and len(base.unidentifiable) == 26
    assert base.diagonal[51] > 1e9 * base.diagonal[52]
    phi = np.random.default_rng(44).normal(size=78)
    np.testing.assert_allclose(W @ phi, base.columns(W) @ base.values(phi), atol=1e-9)
    # the named unidentifiable directions change nothing
    null = np.zeros((78, len(base.dependent)))
    null[base.dependent, np.arange(len(base.dependent))] = 1.0
    null[base.independent] = -base.K
    assert np.abs(W @ null).max() < 1e-9
    assert {"m1", "Izz1", "Ia1 - Iyy1", "Ia2 - Izz2"} <= set(base.unidentifiable)
    assert any(label.startswith("Iyy1 ") and "Ia1" in label for label in base.labels)
    # in the names' own order the same rank, other representatives
    plain = dyn_id.base_parameters(W, NAMES)
    assert plain.rank == 52 and plain.labels != base.labels


def test_the_links_base_parameters_are_as_many_as_pinocchio_s_regressor_has_rank():
    # an independent count: the rank of pinocchio's joint-torque regressor (its own frames)
    pin, model, data = pinocchio_model(UR3)
    q, qd, qdd = random_states(UR3, 60, seed=45)
    Y_pin = np.vstack([pin.computeJointTorqueRegressor(model, data, *s).copy()
                       for s in zip(q, qd, qdd, strict=True)])
    s = np.linalg.svd(Y_pin / np.abs(Y_pin).max(), compute_uv=False)
    rank_pin = int(np.count_nonzero(s > 1e-9 * s[0]))
    Y = dynamics.regressor(UR3, q, qd, qdd).reshape(-1, 60)
    base = dyn_id.base_parameters(Y, dyn_id.parameter_names(UR3, motors=False))
    assert rank_pin == base.rank == 36


def test_the_fourier_trajectory_and_its_derivatives():
    rng = np.random.default_rng(46)
    f = dyn_id.FourierTrajectory(rng.normal(size=3), rng.normal(size=(3, 4)),
                                 rng.normal(size=(3, 4)), 5.0)
    t, h = np.linspace(0.0, 5.0, 50), 1e-5
    q, qd, qdd = f.sample(t)
    np.testing.assert_allclose((f.sample(t + h)[0] - f.sample(t - h)[0]) / (2 * h), qd,
                               atol=1e-7)
    np.testing.assert_allclose((f.sample(t + h)[1] - f.sample(t - h)[1]) / (2 * h), qdd,
                               atol=1e-6)
    np.testing.assert_allclose(f.sample(t + 5.0)[0], q, atol=1e-12)        # periodic
    rest = f.starting_at_rest()
    assert np.allclose([rest.sample(0.0)[1], rest.sample(0.0)[2]], 0.0, atol=1e-12)


def test_the_exciting_trajectory_keeps_its_bounds_and_lowers_the_condition(ur3_base):
    _, base = ur3_base
    bounds = dict(centre=[0.0, -1.57, 0.0, -1.57, 0.0, 0.0],
                  half_range=[1.5, 0.8, 1.2, 1.5, 1.5, 1.5], qd_max=[1.5, 1.5, 1.5, 2, 2, 2],
                  qdd_max=[5.0] * 6)
    f, history = dyn_id.exciting_trajectory(UR3, base, **bounds, iterations=40, samples=60,
                                            seed=3)
    again, _ = dyn_id.exciting_trajectory(UR3, base, **bounds, iterations=40, samples=60,
                                          seed=3)
    np.testing.assert_array_equal(f.a, again.a)                            # seeded
    assert np.all(np.diff(history) <= 0) and history[-1] < history[0]
    q, qd, qdd = f.sample(np.linspace(0.0, f.period, 5001))
    assert np.all(np.abs(q - bounds["centre"]) <= np.array(bounds["half_range"]) + 1e-9)
    assert np.all(np.abs(qd) <= np.array(bounds["qd_max"]) + 1e-9)
    assert np.all(np.abs(qdd) <= 5.0 + 1e-9)
    assert np.allclose(q[0], bounds["centre"]) and np.allclose(qd[0], 0.0, atol=1e-12)
    with pytest.raises(ValueError, match="joint limits"):
        dyn_id.exciting_trajectory(UR3, base, **{**bounds, "half_range": [9.0] * 6})
    with pytest.raises(ValueError, match="qd_max"):
        dyn_id.exciting_trajectory(UR3, base, **{**bounds, "qd_max": [0.0] * 6})
    with pytest.raises(ValueError, match="iterations"):
        dyn_id.exciting_trajectory(UR3, base, **bounds, iterations=2.5)


def test_the_identified_model_of_true_parameters_is_the_model(ur3_base):
    _, base = ur3_base
    rng = np.random.default_rng(47)
    motors = rng.uniform(0.05, 1.0, (6, 3))
    phi = np.concatenate([dynamics.inertial_parameters(UR3), motors.ravel()])
    model = dyn_id.IdentifiedModel(UR3, base, base.values(phi))
    q, qd, qdd = random_states(UR3, 10, seed=47)
    expected = (dynamics.inverse_dynamics(UR3, q, qd, qdd) + motors[:, 0] * qdd
                + motors[:, 1] * qd + motors[:, 2] * np.sign(qd))
    np.testing.assert_allclose(model.inverse_dynamics(q, qd, qdd), expected, atol=1e-10)
    np.testing.assert_allclose(model.inverse_dynamics(q[0], qd[0], qdd[0]), expected[0],
                               atol=1e-10)
    with pytest.raises(ValueError, match="beta"):
        dyn_id.IdentifiedModel(UR3, base, np.zeros(3))


def test_bad_input_is_refused_by_name(ur3_base):
    W, _ = ur3_base
    with pytest.raises(ValueError, match="names"):
        dyn_id.base_parameters(W, NAMES[:-1])
    with pytest.raises(ValueError, match="prefer"):
        dyn_id.base_parameters(W, NAMES, prefer=NAMES[:-1] + ("x",))
    with pytest.raises(ValueError, match="W must stack"):
        dyn_id.base_parameters(W[:10], NAMES)
    with pytest.raises(ValueError, match="all zeros"):
        dyn_id.base_parameters(np.zeros((100, 78)), NAMES)
    with pytest.raises(ValueError, match="qd"):
        dyn_id.motor_regressor([1.0, np.nan], [0.0, 0.0])
    with pytest.raises(ValueError, match="broadcast"):
        dyn_id.motor_regressor(np.zeros(3), np.zeros(4))
    with pytest.raises(TypeError, match="robot"):
        dyn_id.parameter_names("UR3")
