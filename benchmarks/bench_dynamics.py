"""Speed of dqlab's dynamics of the UR3 next to MuJoCo's and pinocchio's, called from Python.

Run with ``python benchmarks/bench_dynamics.py`` (add ``--quick`` for a short run). It prints
one table per quantity, the inverse dynamics (RNEA), the mass matrix ``M(q)``, forward
dynamics and the regressor of the inertial parameters: the time of a single call
(microseconds) and per configuration of a batch of 10,000, with the ratio of each to dqlab's
first row (above 1: dqlab is faster). Then the goals: a batch of RNEA per configuration
faster than pinocchio's single call, a batch of M faster than pinocchio's ``crba``, one
prepared call (``NewtonEuler``) within 10 times pinocchio's ``rnea``.

- dqlab: the checked functions ``dynamics.inverse_dynamics``, ``mass_matrix`` (composite
  rigid bodies), ``forward_dynamics`` (articulated bodies) and ``regressor``, and
  ``dynamics.NewtonEuler``, prepared once for a controller's loop. With numba installed they
  run compiled kernels (``dqlab._fast.dynamics_compiled``); ``DQLAB_COMPILED=0`` runs the numpy
  path instead (and the float path for one state), to see what numba buys.
- MuJoCo (C, called from Python) on ``mjcf_from_robot(ur3(), damping=0, armature=0)``:
  ``mj_inverse`` after writing the state; ``mj_fwdPosition`` with ``mj_fullM``;
  ``mj_forward`` with the torques in ``qfrc_applied``. It has no regressor. A batch is a
  Python loop.
- pinocchio (C++, optional: ``pip install pin``) on the same bodies: ``rnea``, ``crba`` (its
  upper triangle, as it returns it), ``aba`` and ``computeJointTorqueRegressor``; a batch is
  a Python loop. Its column is left out when it is not installed.

The three are checked against each other before timing. This is not a test; timings vary
between machines and with the load on them (the best CPU time of several rounds, interleaved,
is reported).
"""

import argparse
import importlib.util
import os

import numpy as np
from timing import calls_lasting, interleaved_best

from dqlab import dynamics
from dqlab.models import ur3
from dqlab.sim.mjcf import link_placements, mjcf_from_robot

N_BATCH = 10_000


def mujoco_functions(robot):
    import mujoco

    model = mujoco.MjModel.from_xml_string(mjcf_from_robot(robot, damping=0.0, armature=0.0))
    data = mujoco.MjData(model)
    n = robot.n

    def inverse(q, qd, qdd):
        data.qpos[:], data.qvel[:], data.qacc[:] = q, qd, qdd
        mujoco.mj_inverse(model, data)
        return data.qfrc_inverse.copy()

    def mass(q):
        data.qpos[:] = q
        mujoco.mj_fwdPosition(model, data)
        M = np.empty((n, n))
        try:
            mujoco.mj_fullM(model, data, M)            # MuJoCo 4
        except TypeError:
            mujoco.mj_fullM(model, M, data.qM)         # MuJoCo 3
        return M

    def forward(q, qd, tau):
        data.qpos[:], data.qvel[:], data.qfrc_applied[:] = q, qd, tau
        mujoco.mj_forward(model, data)
        return data.qacc.copy()

    return {"inverse": inverse, "mass": mass, "forward": forward}


def pinocchio_functions(robot):
    try:
        import pinocchio as pin
    except ImportError:
        return None
    placements, _, corners = link_placements(robot)
    model = pin.Model()
    model.gravity.linear = np.array([0.0, 0.0, -9.81])
    parent = 0
    for i, (link, X) in enumerate(zip(robot.links, placements, strict=True)):
        X = robot.base @ X if i == 0 else X
        parent = model.addJoint(parent, pin.JointModelRZ(), pin.SE3(X[:3, :3], X[:3, 3]),
                                f"joint{i + 1}")
        inertia = link.inertia.moved(corners[i + 1])
        model.appendBodyToJoint(parent, pin.Inertia(inertia.mass, inertia.com, inertia.tensor),
                                pin.SE3.Identity())
    data = model.createData()
    return {"inverse": lambda q, qd, qdd: pin.rnea(model, data, q, qd, qdd),
            "mass": lambda q: pin.crba(model, data, q),
            "forward": lambda q, qd, tau: pin.aba(model, data, q, qd, tau),
            "regressor": lambda q, qd, qdd: pin.computeJointTorqueRegressor(model, data, q,
                                                                              qd, qdd)}


def check_agreement(robot, peers, Q, QD, QDD):
    """Every peer agrees with dqlab on 50 states (the regressor through Y pi = tau)."""
    tau = dynamics.inverse_dynamics(robot, Q, QD, QDD)
    M = dynamics.mass_matrix(robot, Q)
    qdd = dynamics.forward_dynamics(robot, Q, QD, tau)
    assert np.allclose(dynamics.regressor(robot, Q, QD, QDD) @ dynamics.inertial_parameters(robot),
                       tau, atol=1e-9)
    for name, f in peers.items():
        states = list(zip(Q, QD, QDD, strict=True))
        theirs = np.array([f["inverse"](*s) for s in states])
        assert np.abs(theirs - tau).max() < 1e-9 * np.abs(tau).max(), f"{name} disagrees (ID)"
        theirs = np.array([f["mass"](q) for q in Q])
        theirs = np.triu(theirs) + np.swapaxes(np.triu(theirs, 1), -1, -2)
        assert np.abs(theirs - M).max() < 1e-9 * np.abs(M).max(), f"{name} disagrees (M)"
        theirs = np.array([f["forward"](q, qd, t) for q, qd, t in zip(Q, QD, tau, strict=True)])
        assert np.abs(theirs - qdd).max() < 1e-8 * np.abs(qdd).max(), f"{name} disagrees (FD)"


def main(quick=False):
    rng = np.random.default_rng(0)
    repeat, brepeat = (3, 2) if quick else (7, 3)
    robot = ur3()
    q, qd, qdd = rng.uniform(-np.pi, np.pi, 6), rng.normal(size=6), rng.normal(size=6)
    Q, QD, QDD = (rng.uniform(-np.pi, np.pi, (N_BATCH, 6)), rng.normal(size=(N_BATCH, 6)),
                  rng.normal(size=(N_BATCH, 6)))
    newton_euler = dynamics.NewtonEuler(robot)
    peers = {"MuJoCo": mujoco_functions(robot)}
    pinocchio = pinocchio_functions(robot)
    if pinocchio is not None:
        peers["pinocchio"] = pinocchio
    check_agreement(robot, peers, Q[:50], QD[:50], QDD[:50])
    assert np.allclose(newton_euler(q, qd, qdd), dynamics.inverse_dynamics(robot, q, qd, qdd),
                       atol=1e-12)

    sub = N_BATCH // 10                      # the Python loops run on a tenth of the batch
    states = list(zip(Q[:sub], QD[:sub], QDD[:sub], strict=True))
    ours = {
        "RNEA": {"dqlab inverse_dynamics": (lambda: dynamics.inverse_dynamics(robot, q, qd, qdd),
                                            lambda: dynamics.inverse_dynamics(robot, Q, QD, QDD)),
                 "dqlab NewtonEuler": (lambda: newton_euler(q, qd, qdd), None)},
        "mass matrix": {"dqlab mass_matrix": (lambda: dynamics.mass_matrix(robot, q),
                                              lambda: dynamics.mass_matrix(robot, Q))},
        "forward dynamics": {"dqlab forward_dynamics": (
            lambda: dynamics.forward_dynamics(robot, q, qd, qdd),
            lambda: dynamics.forward_dynamics(robot, Q, QD, QDD))},
        "regressor": {"dqlab regressor": (lambda: dynamics.regressor(robot, q, qd, qdd),
                                          lambda: dynamics.regressor(robot, Q, QD, QDD))},
    }
    peer_calls = {"RNEA": ("inverse", lambda f: f(q, qd, qdd), lambda f: [f(*s) for s in states]),
                  "mass matrix": ("mass", lambda f: f(q), lambda f: [f(s[0]) for s in states]),
                  "forward dynamics": ("forward", lambda f: f(q, qd, qdd),
                                       lambda f: [f(*s) for s in states]),
                  "regressor": ("regressor", lambda f: f(q, qd, qdd),
                                lambda f: [f(*s) for s in states])}
    rows = {}
    for what, mine in ours.items():
        singles = {name: pair[0] for name, pair in mine.items()}
        batches = {name: (pair[1], 1, N_BATCH, 1) for name, pair in mine.items()
                   if pair[1] is not None}
        key, single_call, batch_call = peer_calls[what]
        for name, functions in peers.items():
            if key in functions:
                f = functions[key]
                singles[name] = (lambda f=f, call=single_call: call(f))
                batches[name] = ((lambda f=f, call=batch_call: call(f)), 1, sub)
        single_time = interleaved_best({n: (f, calls_lasting(f), 1) for n, f in singles.items()},
                                       repeat)
        batch_time = interleaved_best(batches, brepeat)
        rows[what] = (single_time, batch_time)

    switched_off = os.environ.get("DQLAB_COMPILED", "1").strip() == "0"
    compiled = ("numpy, DQLAB_COMPILED=0" if switched_off
                else "compiled (numba)" if importlib.util.find_spec("numba") else "numpy")
    print(f"UR3 dynamics: one call, and a batch of {N_BATCH:,} configurations (best CPU time; "
          f"dqlab {compiled}; the peers' batches are Python loops)")
    for what, (single_time, batch_time) in rows.items():
        print(f"\n{what}")
        print(f"{'implementation':24s} {'single [us]':>12s} {'ratio':>7s} "
              f"{'batch [us/config]':>18s} {'ratio':>7s}")
        ref_single = next(iter(single_time.values()))
        ref_batch = next(iter(batch_time.values()))
        for name, s in single_time.items():
            b = batch_time.get(name)
            batch = (f"{b * 1e6:18.2f} {b / ref_batch:7.2f}" if b is not None
                     else f"{'-':>18s} {'-':>7s}")
            print(f"{name:24s} {s * 1e6:12.2f} {s / ref_single:7.2f} {batch}")
    if pinocchio is None:
        print("\nnot installed (column left out): pinocchio")
        return
    rnea_single, rnea_batch = rows["RNEA"]
    mass_single, mass_batch = rows["mass matrix"]
    print("\ngoals against pinocchio")
    print(f"  batch RNEA per configuration / pinocchio's rnea call: "
          f"{rnea_batch['dqlab inverse_dynamics'] / rnea_single['pinocchio']:.2f} (goal < 1)")
    print(f"  batch M per configuration / pinocchio's crba call:    "
          f"{mass_batch['dqlab mass_matrix'] / mass_single['pinocchio']:.2f} (goal < 1)")
    print(f"  prepared NewtonEuler call / pinocchio's rnea call:    "
          f"{rnea_single['dqlab NewtonEuler'] / rnea_single['pinocchio']:.2f} (goal < 10)")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    main(parser.parse_args().quick)
