"""Speed of dqlab's dynamics of the UR3 next to MuJoCo's and pinocchio's, called from Python.

Run with ``python benchmarks/bench_dynamics.py`` (add ``--quick`` for a short run). It prints
one table: for the inverse dynamics (``tau = ID(q, qd, qdd)``) and the mass matrix ``M(q)``,
the time of a single call (microseconds) and per configuration of a batch of 10,000, with the
ratio of each to dqlab's (above 1: dqlab is faster).

- dqlab: ``dynamics.inverse_dynamics`` and ``dynamics.mass_matrix`` (a single state runs the
  recursion on Python floats, a batch the dual-quaternion recursion on numpy arrays), and
  ``dynamics.NewtonEuler``, prepared once for a controller's loop.
- MuJoCo (C, called from Python) on the model ``mjcf_from_robot(ur3(), damping=0,
  armature=0)``: ``mj_inverse`` after writing the state, and ``mj_fwdPosition`` with
  ``mj_fullM``; a batch is a Python loop.
- pinocchio (C++, optional: ``pip install pin``) on the same bodies: ``rnea`` and ``crba``; a
  batch is a Python loop. Its column is left out when it is not installed.

The three are checked against each other before timing. This is not a test; timings vary
between machines and with the load on them (the best CPU time of several rounds, interleaved,
is reported).
"""

import argparse

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

    return inverse, mass


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

    def mass(q):
        M = pin.crba(model, data, q).copy()
        return np.triu(M) + np.triu(M, 1).T

    return (lambda q, qd, qdd: pin.rnea(model, data, q, qd, qdd).copy()), mass


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

    # agreement first
    tau, M = dynamics.inverse_dynamics(robot, Q[:50], QD[:50], QDD[:50]), \
        dynamics.mass_matrix(robot, Q[:50])
    for name, (inverse, mass) in peers.items():
        theirs = np.array([inverse(*s) for s in zip(Q[:50], QD[:50], QDD[:50], strict=True)])
        assert np.abs(theirs - tau).max() < 1e-9 * np.abs(tau).max(), f"{name} disagrees (ID)"
        theirs = np.array([mass(x) for x in Q[:50]])
        assert np.abs(theirs - M).max() < 1e-9 * np.abs(M).max(), f"{name} disagrees (M)"
    assert np.allclose(newton_euler(q, qd, qdd), dynamics.inverse_dynamics(robot, q, qd, qdd),
                       atol=1e-12)

    def single_jobs(functions):
        return {name: (f, calls_lasting(f), 1) for name, f in functions.items()}

    sub = N_BATCH // 10                      # the Python loops run on a tenth of the batch
    rows = []
    for what, ours, per_peer in (
            ("inverse dynamics",
             {"dqlab inverse_dynamics": (lambda: dynamics.inverse_dynamics(robot, q, qd, qdd),
                                         lambda: dynamics.inverse_dynamics(robot, Q, QD, QDD)),
              "dqlab NewtonEuler": (lambda: newton_euler(q, qd, qdd), None)},
             lambda inverse, mass: (lambda: inverse(q, qd, qdd),
                                    lambda: [inverse(*s) for s in zip(Q[:sub], QD[:sub],
                                                                     QDD[:sub], strict=True)])),
            ("mass matrix",
             {"dqlab mass_matrix": (lambda: dynamics.mass_matrix(robot, q),
                                    lambda: dynamics.mass_matrix(robot, Q))},
             lambda inverse, mass: (lambda: mass(q), lambda: [mass(x) for x in Q[:sub]]))):
        singles = {name: pair[0] for name, pair in ours.items()}
        batches = {name: (pair[1], 1, N_BATCH, 1) for name, pair in ours.items()
                   if pair[1] is not None}
        for name, functions in peers.items():
            single, batch = per_peer(*functions)
            singles[name] = single
            batches[name] = (batch, 1, sub)
        single_time = interleaved_best(single_jobs(singles), repeat)
        batch_time = interleaved_best(batches, brepeat)
        rows.append((what, single_time, batch_time))

    print(f"UR3 dynamics: one call, and a batch of {N_BATCH:,} configurations "
          "(best CPU time; the peers' batches are Python loops)")
    for what, single_time, batch_time in rows:
        print(f"\n{what}")
        print(f"{'implementation':24s} {'single [us]':>12s} {'ratio':>7s} "
              f"{'batch [us/config]':>18s} {'ratio':>7s}")
        ref_single = next(iter(single_time.values()))
        ref_batch = next(iter(batch_time.values()))
        for name, s in single_time.items():
            b = batch_time.get(name)
            batch = (f"{b * 1e6:18.2f} {b / ref_batch:7.2f}" if b is not None
                     else f"{'-':>18s} {'-':>7s}")
            print(f"{name:24s} {s * 1e6:12.1f} {s / ref_single:7.2f} {batch}")
    if pinocchio is None:
        print("\nnot installed (column left out): pinocchio")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    main(parser.parse_args().quick)
