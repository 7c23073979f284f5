"""The current UR models of dqlab.models against ur_analytic_ik, an independent implementation
that tabulates the same published DH parameters: forward kinematics to 1e-12 and the same
number of inverse-kinematics solutions on random poses."""

import math

import numpy as np
import pytest

from dqlab import models
from dqlab.ik import ur
from dqlab.models import UR_ALPHA, UR_DH, UR_MODELS, UR_SHAPE
from dqlab.testing import quiet_stdout

try:
    import ur_analytic_ik as uik
except ImportError:  # the test extra brings it; without it only the cross-checks skip
    uik = None

#: dqlab's function and ur_analytic_ik's module of each current model
CURRENT = [("ur3e", "ur3e"), ("ur5e", "ur5e"), ("ur7e", "ur7e"), ("ur10e", "ur10e"),
           ("ur12e", "ur12e"), ("ur16e", "ur16e"), ("ur15", "ur15"), ("ur18", "ur18"),
           ("ur8_long", "ur8long"), ("ur20", "ur20"), ("ur30", "ur30")]


def oracle(name):
    """ur_analytic_ik's module for a model, or a skip of this one test."""
    if uik is None:
        pytest.skip("ur_analytic_ik (test extra) is absent")
    if not hasattr(uik, name):
        pytest.skip(f"this version of ur_analytic_ik has no {name}")
    return getattr(uik, name)


@pytest.mark.parametrize("function, theirs", CURRENT, ids=[c[0] for c in CURRENT])
def test_fk_equals_ur_analytic_ik(function, theirs):
    """The same base->flange pose for 1,000 random configurations (the identity relation,
    as for the UR3 in test_models), to 1e-12."""
    fk = oracle(theirs).forward_kinematics
    robot = getattr(models, function)()
    q = np.random.default_rng(31).uniform(-2 * np.pi, 2 * np.pi, size=(1000, 6))
    ours = robot.fk(q)
    with quiet_stdout():
        expected = np.array([fk(*row) for row in q])
    assert np.abs(ours - expected).max() < 1e-12


@pytest.mark.parametrize("function, theirs", CURRENT, ids=[c[0] for c in CURRENT])
def test_ik_solution_counts_equal_ur_analytic_ik(function, theirs):
    """dqlab.ik.ur and ur_analytic_ik find as many solutions on 500 poses of random
    configurations (no pose near a boundary: the counts agree on every one), and every
    valid row reproduces its pose to 1e-9 and the generating configuration is among them."""
    module = oracle(theirs)
    robot = getattr(models, function)()
    q = np.random.default_rng(32).uniform(-np.pi, np.pi, size=(500, 6))
    T = robot.fk(q)
    result = ur(robot, T)
    with quiet_stdout():
        counts = np.array([np.reshape(module.inverse_kinematics(np.ascontiguousarray(X)),
                                      (-1, 6)).shape[0] for X in T])
    np.testing.assert_array_equal(result.count, counts)
    X = robot.fk(result.solutions[result.valid])
    Tb = np.broadcast_to(T[:, None], result.solutions.shape[:-1] + (4, 4))[result.valid]
    assert np.abs(X - Tb).max() < 1e-9
    found = np.abs(np.angle(np.exp(1j * (result.solutions - q[:, None])))).max(axis=-1)
    assert np.where(result.valid, found, np.inf).min(axis=-1).max() < 1e-8


@pytest.mark.parametrize("name", sorted(UR_MODELS))
def test_every_ur_model_is_ur_shaped_with_its_published_lengths(name):
    robot = UR_MODELS[name]()
    assert robot.name == name and robot.n == 6 and robot.convention == "dh"
    UR_SHAPE.check(robot)
    p = UR_DH[name]
    for link, a, alpha, d in zip(robot.links, p["a"], UR_ALPHA, p["d"], strict=True):
        assert (link.a, link.alpha, link.d, link.theta_offset) == (a, alpha, d, 0.0)
    for link, limit in zip(robot.links, models.UR_JOINT_RANGE_DEG[name], strict=True):
        assert link.limits == (-math.radians(limit), math.radians(limit))
        assert link.limits == ((-math.inf, math.inf) if link is robot.links[5] and name in
                               ("UR3", "UR3e") else (-2 * math.pi, 2 * math.pi))
    assert robot.bare


def test_renamed_models_are_the_same_arms():
    assert UR_DH["UR7e"] == UR_DH["UR5e"] and UR_DH["UR12e"] == UR_DH["UR10e"]
    # the models of the published table differ from each other otherwise
    tables = {name: (p["d"], p["a"]) for name, p in UR_DH.items()
              if name not in ("UR7e", "UR12e")}
    assert len(set(tables.values())) == len(tables)


def test_published_speeds_and_masses_are_complete_rows():
    for name, speeds in models.UR_MAX_JOINT_SPEED_DEG.items():
        assert name in UR_DH and len(speeds) == 6 and min(speeds) >= 120.0
    for name, table in models.UR_DYNAMICS.items():
        assert name in UR_DH and len(table["mass"]) == 6 and len(table["com"]) == 6
        assert all(mass > 0 for mass in table["mass"])
        assert all(len(com) == 3 for com in table["com"])
        # the arm gets lighter towards the wrist, as every published table has it
        assert table["mass"][1] > table["mass"][2] > table["mass"][5]
