"""Inverse kinematics of a calibrated UR5e against the nominal closed form, batch and one pose.

    PYTHONPATH=. python benchmarks/bench_ik_ur_calibrated.py [N]

The calibrated arm is the UR5e with every theta, a, d, alpha off by up to 2 mm / 2 mrad
(seeded); the poses are forward kinematics of N random configurations (default 5000) of each
arm; one pose at a time is timed on the first 1000 of them (poses that need a restart, one
in eight or so, cost far more than the others: a smaller sample moves the mean by tenths of
the ratio). Prints the best CPU time per pose (``timing.interleaved_best``), the ratios, and the
accuracy the calibrated solver keeps: the share of poses whose generating configuration is
among the valid rows, and the largest position and rotation errors of a valid row.

The calibrated solver is timed twice: with its Newton steps (and, for one pose, the nearest
exact arm's closed form) compiled (numba, the ``fast`` extra; ``dqlab.ik._newton_compiled``)
and on the numpy path it takes without numba.
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import calls_lasting, interleaved_best  # noqa: E402

from dqlab import ik  # noqa: E402
from dqlab.identify import dh_parameters, robot_from_dh_parameters  # noqa: E402
from dqlab.ik import _newton_compiled  # noqa: E402
from dqlab.models import ur5e  # noqa: E402


def main(n=5000, singles=1000, repeat=3):
    nominal = ur5e()
    rng = np.random.default_rng(7)
    calibrated = robot_from_dh_parameters(nominal,
                                          dh_parameters(nominal) + rng.uniform(-2e-3, 2e-3, 24))
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    X_nominal, X_calibrated = nominal.fk(q), calibrated.fk(q)
    one_nominal, one_calibrated = X_nominal[:singles], X_calibrated[:singles]

    def batch_nominal():
        ik.ur(nominal, X_nominal)

    def numpy_path(f):
        def run():
            ready = _newton_compiled._READY
            _newton_compiled._READY = False
            try:
                f()
            finally:
                _newton_compiled._READY = ready
        return run

    def batch_calibrated():
        ik.ur(calibrated, X_calibrated)

    def single_nominal():
        for X in one_nominal:
            ik.ur(nominal, X)

    def single_calibrated():
        for X in one_calibrated:
            ik.ur(calibrated, X)

    compiled = _newton_compiled.ready()
    if compiled:
        ik.ur(calibrated, X_calibrated[:8])                 # compiled (or read) before timing
    jobs = {"batch, nominal": (batch_nominal, calls_lasting(batch_nominal), n, 1),
            "batch, calibrated": (batch_calibrated, 1, n, 1),
            "batch, calibrated, numpy path": (numpy_path(batch_calibrated), 1, n, 1),
            "one pose, nominal": (single_nominal, 1, singles),
            "one pose, calibrated": (single_calibrated, 1, singles),
            "one pose, calibrated, numpy path": (numpy_path(single_calibrated), 1, singles)}
    if not compiled:
        print("numba is not installed: both calibrated rows take the numpy path")
    best = interleaved_best(jobs, repeat)
    for label, seconds in best.items():
        print(f"{label:34s} {seconds * 1e6:9.1f} us per pose")
    for what in ("batch", "one pose"):
        nominal_time = best[f"{what}, nominal"]
        print(f"ratio, {what:8s}  {best[f'{what}, calibrated'] / nominal_time:6.1f} "
              f"(numpy path {best[f'{what}, calibrated, numpy path'] / nominal_time:.1f}; "
              f"goal: at most 5)")
    result = ik.ur(calibrated, X_calibrated)
    gap = np.abs(np.angle(np.exp(1j * (result.solutions - q[:, None])))).max(axis=-1)
    found = ((gap < 1e-6) & result.valid).any(axis=-1)
    print(f"generating configuration found on {found.mean():.2%} of {n} poses; worst valid "
          f"row {result.position_error[result.valid].max():.2e} m, "
          f"{result.rotation_error[result.valid].max():.2e} rad; not_converged on "
          f"{result.flags['not_converged'].mean():.2%}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5000)
