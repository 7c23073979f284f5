"""Inverse kinematics of calibrated URs against the nominal closed form, batch and one pose.

    PYTHONPATH=. python benchmarks/bench_ik_ur_calibrated.py [N] [SINGLES]

The calibrated arms: every real calibration of ``tests/data/real_calibrations`` (the
controllers' own parameters, hundreds of metres of d on the parallel joints; their origins
are in the README there), and a UR5e with every theta, a, d, alpha off by up to 2 mm / 2 mrad
(seeded). For each arm, the poses are forward kinematics of N random configurations (default
5000), and one pose at a time is timed on the first SINGLES of them (default 500; poses that
need a restart cost far more than the others, so a small sample moves the mean). The
reference is the nominal closed form of the arm's model (``dqlab.ik.ur`` on the exact UR) on
its own poses, timed in the same rounds (``timing.interleaved_best``: best CPU time per
pose).

It prints, per arm: the share of poses whose generating configuration is among the
solutions (to 1e-6 rad; the valid rows and those beyond them, ``result.more``), and among the
rows alone, the share of poses with solutions beyond the rows, the share flagged
``near_singular`` and of the misses how many carry no flag, the largest position and
rotation errors of a valid solution, and the batch and one-pose
ratios to the nominal closed form (goals: a batch at about 10-12 times, one pose at most 5).
``--numpy`` times the numpy path (``DQLAB_COMPILED=0``) instead of the compiled one.
"""

import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT.parent / "tests"))

from real_calibrations import real_calibrations  # noqa: E402
from timing import calls_lasting, interleaved_best  # noqa: E402

from dqlab import ik, models  # noqa: E402
from dqlab.identify import dh_parameters, robot_from_dh_parameters  # noqa: E402


def arms():
    """name -> (calibrated robot, its model's exact robot)."""
    found = {}
    for name, robot in real_calibrations().items():
        found[name] = (robot, getattr(models, name.split()[0].lower())())
    nominal = models.ur5e()
    offsets = np.random.default_rng(7).uniform(-2e-3, 2e-3, 24)
    found["UR5e, 2 mm / 2 mrad off (synthetic)"] = (
        robot_from_dh_parameters(nominal, dh_parameters(nominal) + offsets), nominal)
    return found


def accuracy(robot, X, q):
    """Found share (the rows and ``more``; the rows alone), share with solutions beyond the
    rows, near-singular share, unflagged misses, worst valid position and rotation
    errors."""
    result = ik.ur(robot, X)
    more = getattr(result, "more", None)            # (an older dqlab has no more)

    def found_in(rows):
        gap = np.abs(np.angle(np.exp(1j * (rows.solutions - q[:, None])))).max(axis=-1)
        return ((gap < 1e-6) & rows.valid).any(axis=-1)

    in_rows = found_in(result)
    found = in_rows | (found_in(more) if more is not None else False)
    beyond = more.valid.any(axis=-1).mean() if more is not None else 0.0
    valid = [result] + ([more] if more is not None else [])
    none = np.zeros(len(q), dtype=bool)            # (a flag an older dqlab does not set)
    near, unreachable, not_converged = (result.flags.get(name, none) for name in (
        "near_singular", "unreachable", "not_converged"))
    flagged = near | unreachable | not_converged
    return (found.mean(), in_rows.mean(), beyond, near.mean(), int((~found & ~flagged).sum()),
            max(r.position_error[r.valid].max(initial=0) for r in valid),
            max(r.rotation_error[r.valid].max(initial=0) for r in valid))


def times(robot, nominal, q, singles, repeat):
    """Best CPU time per pose of the calibrated arm and of its model's closed form on the
    poses of the joint vectors q, in a batch and one at a time."""
    X, X_nominal = robot.fk(q), nominal.fk(q)
    n = len(q)
    ik.ur(robot, X[:8])                                 # compiled (or read) before timing
    jobs = {
        "batch, nominal": (lambda: ik.ur(nominal, X_nominal),
                           calls_lasting(lambda: ik.ur(nominal, X_nominal)), n, 1),
        "batch, calibrated": (lambda: ik.ur(robot, X), 1, n, 1),
        "one pose, nominal": (lambda: [ik.ur(nominal, T) for T in X_nominal[:singles]], 1,
                              singles),
        "one pose, calibrated": (lambda: [ik.ur(robot, T) for T in X[:singles]], 1, singles),
    }
    return interleaved_best(jobs, repeat)


def main(n=5000, singles=500, repeat=3):
    rng = np.random.default_rng(11)
    rows = []
    for name, (robot, nominal) in arms().items():
        q = rng.uniform(-np.pi, np.pi, (n, 6))
        best = times(robot, nominal, q, singles, repeat)
        found, in_rows, beyond, near, unflagged, worst_p, worst_r = accuracy(
            robot, robot.fk(q), q)
        rows.append((name, found, in_rows, beyond, near, unflagged, worst_p, worst_r,
                     best["batch, calibrated"] / best["batch, nominal"],
                     best["one pose, calibrated"] / best["one pose, nominal"],
                     best["batch, calibrated"] * 1e6, best["one pose, calibrated"] * 1e6))
    path = "numpy path (DQLAB_COMPILED=0)" if os.environ.get("DQLAB_COMPILED") == "0" else \
        "compiled where numba is installed"
    print(f"{n} random poses per arm, {singles} of them one at a time; {path}")
    print(f"{'arm':44s} {'found':>8s} {'in rows':>8s} {'more':>6s} {'near':>6s} "
          f"{'unflagged':>9s} {'worst m':>8s} {'worst rad':>9s} {'batch':>6s} {'one':>5s}   "
          f"us/pose batch, one")
    for name, found, in_rows, beyond, near, unflagged, wp, wr, batch, one, tb, to in rows:
        print(f"{name:44s} {found:8.3%} {in_rows:8.3%} {beyond:6.2%} {near:6.1%} "
              f"{unflagged:9d} {wp:8.1e} {wr:9.1e} {batch:6.1f} {one:5.1f}   {tb:.1f}, {to:.0f}")
    print("goals: found >= 99.9 %, valid rows to 1e-10, batch about 10-12, one pose <= 5")


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if "--numpy" in sys.argv:
        os.environ["DQLAB_COMPILED"] = "0"
    main(*(int(a) for a in args))
