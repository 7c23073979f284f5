"""Speed of dqlab's UR3 forward kinematics next to ur_analytic_ik and roboticstoolbox.

Run with ``python benchmarks/bench_fk.py`` (add ``--quick`` for a short run). It prints one
table: a single call (microseconds per call) and a batch of 100,000 joint vectors
(microseconds per configuration), with the ratio of each peer's time to dqlab's (above 1:
dqlab is faster).

Goals: ``ur3().fk(q)`` and ``ur3().fk_dq(q)`` for one joint vector at most 3 times
ur_analytic_ik's single call in the same run (one joint vector is computed on Python
floats), under 1 microsecond per configuration for a batch of 100,000. The rows ``fk_dq``
(product of per-link dual quaternions) and ``fk_dq_screw`` (product of base-frame screws)
are the two dual-quaternion constructions of the thesis; their ratios are to ``fk``.

- ``ur_analytic_ik`` (C++ with Python bindings) takes one configuration per call; its batch
  column is a Python loop over the configurations (timed on 10,000 of them).
- ``roboticstoolbox-python`` is optional: when it is importable, its ``models.DH.UR3()``
  ``fkine`` is timed for one configuration and for the whole batch (it accepts an (N, 6)
  array). Its column is left out otherwise.

The poses are checked against each other before timing. This is not a test; timings vary
between machines and with the load on them (the best CPU time of several runs is
reported).
"""

import argparse

import numpy as np
from timing import interleaved_best

from dqlab.dualquat import transform_from_dual_quaternion
from dqlab.models import ur3

N_BATCH = 100_000
N_LOOP = 10_000  # configurations for the one-at-a-time peers


def optional_peers():
    peers = {}
    try:
        import ur_analytic_ik

        peers["ur_analytic_ik"] = ur_analytic_ik.ur3.forward_kinematics
    except ImportError:
        pass
    try:
        import roboticstoolbox as rtb

        peers["roboticstoolbox"] = rtb.models.DH.UR3()
    except Exception:  # not installed, or fails to import with this numpy  # noqa: BLE001
        pass
    return peers


def main(quick=False):
    rng = np.random.default_rng(0)
    number, repeat = (2_000, 3) if quick else (20_000, 7)
    bnumber, brepeat = (1, 3) if quick else (3, 5)
    robot = ur3()
    q = rng.uniform(-np.pi, np.pi, size=6)
    Q = rng.uniform(-np.pi, np.pi, size=(N_BATCH, 6))
    peers = optional_peers()

    # agreement first: every peer returns the same base->flange pose
    X = robot.fk(Q[:100])
    for method in (robot.fk_dq, robot.fk_dq_screw):
        ours = transform_from_dual_quaternion(method(Q[:100]))
        assert np.abs(X - ours).max() < 1e-12, f"{method.__name__} disagrees with fk"
    if "ur_analytic_ik" in peers:
        fk = peers["ur_analytic_ik"]
        theirs = np.array([fk(*row) for row in Q[:100]])
        assert np.abs(X - theirs).max() < 1e-9, "ur_analytic_ik disagrees"
    if "roboticstoolbox" in peers:
        theirs = np.array([T.A for T in peers["roboticstoolbox"].fkine(Q[:100])])
        assert np.abs(X - theirs).max() < 1e-9, "roboticstoolbox disagrees"

    singles, batches, how = {}, {}, {}      # name: (function, calls per run, items per call)
    for method in (robot.fk, robot.fk_dq, robot.fk_dq_screw):
        name = f"dqlab ur3().{method.__name__}"
        singles[name] = (lambda m=method: m(q), number, 1)
        batches[name] = (lambda m=method: m(Q), bnumber, N_BATCH)
        how[name] = "vectorised"
    if "ur_analytic_ik" in peers:
        fk = peers["ur_analytic_ik"]
        sub = Q[:N_LOOP]
        singles["ur_analytic_ik"] = (lambda: fk(*q), number, 1)
        batches["ur_analytic_ik"] = (lambda: [fk(*row) for row in sub], 1, N_LOOP)
        how["ur_analytic_ik"] = "Python loop"
    if "roboticstoolbox" in peers:
        model = peers["roboticstoolbox"]
        singles["roboticstoolbox fkine"] = (lambda: model.fkine(q), number // 10, 1)
        batches["roboticstoolbox fkine"] = (lambda: model.fkine(Q), 1, N_BATCH)
        how["roboticstoolbox fkine"] = "(N, 6) array"
    single, batch = interleaved_best(singles, repeat), interleaved_best(batches, brepeat)
    rows = [(name, single[name], batch[name], by) for name, by in how.items()]

    ref_single, ref_batch = rows[0][1], rows[0][2]
    print(f"UR3 forward kinematics: one call, and a batch of {N_BATCH:,} configurations "
          "(best CPU time)")
    print(f"{'implementation':24s} {'single [us]':>12s} {'ratio':>7s} "
          f"{'batch [us/config]':>18s} {'ratio':>7s}  batch by")
    for name, s, b, how in rows:
        print(f"{name:24s} {s * 1e6:12.2f} {s / ref_single:7.2f} "
              f"{b * 1e6:18.3f} {b / ref_batch:7.2f}  {how}")
    missing = [p for p in ("ur_analytic_ik", "roboticstoolbox") if p not in peers]
    if missing:
        print("not installed (column left out):", ", ".join(missing))
    peer = next((s for name, s, _, _ in rows if name == "ur_analytic_ik"), None)
    for name, s, b, _ in rows[:2]:
        single = ("single <= 3 x ur_analytic_ik: "
                  + (f"{s / peer:.2f} x, {'met' if s <= 3 * peer else 'MISSED'}" if peer
                     else "(ur_analytic_ik absent)"))
        print(f"goals for {name}: {single}; "
              f"batch < 1 us/config: {'met' if b < 1e-6 else 'MISSED'}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    main(parser.parse_args().quick)
