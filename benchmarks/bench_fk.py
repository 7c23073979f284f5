"""Speed of dqlab's UR3 forward kinematics next to ur_analytic_ik and roboticstoolbox.

Run with ``python benchmarks/bench_fk.py`` (add ``--quick`` for a short run). It prints one
table: a single call (microseconds per call) and a batch of 100,000 joint vectors
(microseconds per configuration), with the ratio of each peer's time to dqlab's (above 1:
dqlab is faster).

Goals: ``ur3().fk(q)`` under 30 microseconds for one joint vector, under 1 microsecond per
configuration for a batch of 100,000.

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
import time
import timeit

import numpy as np

from dqlab.models import ur3

N_BATCH = 100_000
N_LOOP = 10_000  # configurations for the one-at-a-time peers


def best_time(f, number, repeat):
    """Best CPU time per call, in seconds, over ``repeat`` runs of ``number`` calls.

    CPU time of this process (``time.process_time``) rather than wall time, so that other
    programs running on a shared machine inflate the numbers less.
    """
    timer = timeit.Timer(f, timer=time.process_time)
    return min(timer.repeat(number=number, repeat=repeat)) / number


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
    if "ur_analytic_ik" in peers:
        fk = peers["ur_analytic_ik"]
        theirs = np.array([fk(*row) for row in Q[:100]])
        assert np.abs(X - theirs).max() < 1e-9, "ur_analytic_ik disagrees"
    if "roboticstoolbox" in peers:
        theirs = np.array([T.A for T in peers["roboticstoolbox"].fkine(Q[:100])])
        assert np.abs(X - theirs).max() < 1e-9, "roboticstoolbox disagrees"

    rows = []
    single = best_time(lambda: robot.fk(q), number, repeat)
    batch = best_time(lambda: robot.fk(Q), bnumber, brepeat) / N_BATCH
    rows.append(("dqlab ur3().fk", single, batch, "vectorised"))
    single_dq = best_time(lambda: robot.fk_dq(q), number // 4, repeat)
    batch_dq = best_time(lambda: robot.fk_dq(Q), bnumber, brepeat) / N_BATCH
    rows.append(("dqlab ur3().fk_dq", single_dq, batch_dq, "vectorised"))
    if "ur_analytic_ik" in peers:
        fk = peers["ur_analytic_ik"]
        s = best_time(lambda: fk(*q), number, repeat)
        sub = Q[:N_LOOP]
        b = best_time(lambda: [fk(*row) for row in sub], 1, brepeat) / N_LOOP
        rows.append(("ur_analytic_ik", s, b, "Python loop"))
    if "roboticstoolbox" in peers:
        model = peers["roboticstoolbox"]
        s = best_time(lambda: model.fkine(q), number // 10, repeat)
        b = best_time(lambda: model.fkine(Q), 1, brepeat) / N_BATCH
        rows.append(("roboticstoolbox fkine", s, b, "(N, 6) array"))

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
    ok_single = ref_single < 30e-6
    ok_batch = ref_batch < 1e-6
    print(f"goals: single < 30 us: {'met' if ok_single else 'MISSED'}; "
          f"batch < 1 us/config: {'met' if ok_batch else 'MISSED'}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    main(parser.parse_args().quick)
