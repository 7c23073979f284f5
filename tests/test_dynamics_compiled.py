"""The compiled kernels of dqlab.dynamics (dqlab._fast.dynamics_compiled, with numba) against the
numpy path, which stays the reference and the one used without numba or with
DQLAB_COMPILED=0: inverse dynamics, the mass matrix, forward dynamics and the regressor on
random states of every model, one state and batches, and the prepared NewtonEuler."""

import numpy as np
import pytest
from test_dynamics import ROBOTS, random_states

from dqlab import dynamics, models
from dqlab._fast import dynamics_compiled as compiled
from dqlab._fast.compiled import compiled_allowed
from dqlab.inertia import LinkInertia

pytest.importorskip("numba")
pytestmark = pytest.mark.skipif(not compiled_allowed(),
                                reason="DQLAB_COMPILED switches the compiled paths off")


def everything(robot, q, qd, qdd):
    return (dynamics.inverse_dynamics(robot, q, qd, qdd), dynamics.mass_matrix(robot, q),
            dynamics.forward_dynamics(robot, q, qd, qdd), dynamics.regressor(robot, q, qd, qdd),
            dynamics.gravity_torques(robot, q), dynamics.coriolis_torques(robot, q, qd))


def test_the_switch_is_read_at_every_call(monkeypatch):
    monkeypatch.setenv("DQLAB_COMPILED", "0")
    assert not compiled.switched_on() and not compiled.ready()
    monkeypatch.setenv("DQLAB_COMPILED", "1")
    assert compiled.switched_on() and compiled.ready()
    monkeypatch.delenv("DQLAB_COMPILED")
    assert compiled.ready()


@pytest.mark.parametrize("name", list(ROBOTS))
def test_the_compiled_kernels_equal_the_numpy_path(name, monkeypatch):
    robot = ROBOTS[name]()
    q, qd, qdd = random_states(robot, 40, seed=31)
    fast = everything(robot, q, qd, qdd)
    singles = [everything(robot, *state) for state in zip(q[:3], qd[:3], qdd[:3], strict=True)]
    monkeypatch.setenv("DQLAB_COMPILED", "0")
    reference = everything(robot, q, qd, qdd)
    for a, b in zip(fast, reference, strict=True):
        assert a.shape == b.shape
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * max(1.0, np.abs(b).max()))
    for k, single in enumerate(singles):
        for a, b in zip(single, reference, strict=True):
            np.testing.assert_allclose(a, b[k], rtol=0, atol=1e-12 * max(1.0, np.abs(b).max()))


def test_the_prepared_newton_euler_is_compiled_and_checks_like_the_rest(monkeypatch):
    robot = models.ur3()
    newton_euler = dynamics.NewtonEuler(robot)
    assert newton_euler._compiled is not None
    q, qd, qdd = random_states(robot, 20, seed=32)
    for state in zip(q, qd, qdd, strict=True):
        np.testing.assert_allclose(newton_euler(*state), dynamics.inverse_dynamics(robot, *state),
                                   rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="qd contains NaN"):
        newton_euler(q[0], np.full(6, np.nan), qdd[0])
    with pytest.raises(ValueError, match="overflow"):
        newton_euler(q[0], np.full(6, 1e200), qdd[0])
    monkeypatch.setenv("DQLAB_COMPILED", "0")
    plain = dynamics.NewtonEuler(robot)
    assert plain._compiled is None
    np.testing.assert_allclose(plain(q[0], qd[0], qdd[0]), newton_euler(q[0], qd[0], qdd[0]),
                               rtol=0, atol=1e-12)


def test_the_compiled_forward_dynamics_refuses_a_joint_that_moves_no_mass():
    links = [link.inertia for link in models.ur3().links]
    massless = dynamics.with_inertias(models.ur3(), links[:5] + [LinkInertia(0.0, [0, 0, 0])])
    q = np.zeros((4, 6))
    with pytest.raises(ValueError, match=r"singular at q\[0\]: joint 6 moves no mass"):
        dynamics.forward_dynamics(massless, q, q, q)


def test_empty_and_broadcast_batches():
    robot = models.ur3_mdh()
    empty = np.zeros((0, 6))
    assert dynamics.mass_matrix(robot, empty).shape == (0, 6, 6)
    assert dynamics.regressor(robot, empty, empty, empty).shape == (0, 6, 60)
    assert dynamics.forward_dynamics(robot, empty, np.zeros(6), np.zeros(6)).shape == (0, 6)
    q, qd, qdd = random_states(robot, 5, seed=33)
    Y = dynamics.regressor(robot, q, qd[0], qdd[0])            # a state broadcast over a batch
    np.testing.assert_allclose(Y[3], dynamics.regressor(robot, q[3], qd[0], qdd[0]), atol=1e-12)
    fortran = np.asfortranarray(np.tile(q, (2, 1)))            # not C-contiguous
    np.testing.assert_allclose(dynamics.mass_matrix(robot, fortran)[7],
                               dynamics.mass_matrix(robot, q[2]), atol=1e-14)
