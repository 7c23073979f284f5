"""Speed of following the UR3 report's circle in joint space, three ways, in one run.

Run with ``python benchmarks/bench_trajectory.py`` (``--quick`` for fewer repeats). The
path is the circle of chapter 11: R = 0.1 m, V = 0.05 m/s, dt = 5 ms (4399 points), centre
(0, -0.35, 0.25) m, the tool's z axis along -y. Methods:

- closed form, batched: ``dqlab.ik.ur`` on all 4399 poses in one call, then
  ``dqlab.trajectory.track_branches`` (one branch kept, angles unwrapped, switches
  reported) -- the joint positions;
- the same through ``follow_path_ur``: positions plus speeds by J^-1 and accelerations by
  finite differences, plus the singularity margins;
- ur_analytic_ik point by point (C++ with Python bindings): ``inverse_kinematics`` (all
  solutions) and ``inverse_kinematics_closest`` (the one nearest the previous point, its own
  branch tracking), one call per point in a Python loop, as it is offered;
- the report's method, ``follow_path_numerical``: damped least squares on the position,
  warm-started from the previous point, J_v^+ for the speeds (one run; seconds).

Before timing, the closed-form joint positions are checked against ur_analytic_ik's nearest
solutions. Goals: closed-form following at least 100 times faster than the numerical
following and at least 5 times faster than ur_analytic_ik point by point. Times are CPU
times of this process (``time.process_time``, best of several runs). This is not a test.
"""

import argparse
import time
import timeit

import numpy as np

from dqlab import rot_x
from dqlab.ik import ur
from dqlab.models import ur3
from dqlab.testing import quiet_stdout
from dqlab.trajectory import (
    circle_three_phase,
    follow_path_numerical,
    follow_path_ur,
    track_branches,
)

CENTER = (0.0, -0.35, 0.25)
BRANCH = ("left", "down", "noflip")


def best_time(f, number, repeat):
    """Best CPU time per call, in seconds, over ``repeat`` runs of ``number`` calls."""
    timer = timeit.Timer(f, timer=time.process_time)
    return min(timer.repeat(number=number, repeat=repeat)) / number



def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats")
    args = parser.parse_args()
    repeat = 3 if args.quick else 7

    robot = ur3()
    path = circle_three_phase(CENTER, 0.1, 0.05, 0.005, orientation=rot_x(np.pi / 2))
    poses = np.ascontiguousarray(path.poses)
    n = len(path)
    print(f"the report's circle: {n} points, peak tool speed {path.speed.max():.4f} m/s")

    def closed_form():
        return track_branches(ur(robot, poses), branch=BRANCH)

    q, rows, switches = closed_form()
    traj, report = follow_path_ur(robot, path, branch=BRANCH)
    assert np.array_equal(traj.q, q)
    print(f"closed form: {len(switches)} branch switches, largest joint step "
          f"{report.max_step.max():.2e} rad, position error <= "
          f"{np.abs(robot.fk(q)[:, :3, 3] - path.position).max():.1e} m")

    try:
        import ur_analytic_ik
    except ImportError:  # pragma: no cover
        ur_analytic_ik = None
    rows_out = []   # (label, seconds for the whole circle)
    rows_out.append(("closed form batched + track_branches (q)",
                     best_time(closed_form, 1, repeat)))
    rows_out.append(("follow_path_ur (q, J^-1 qd, finite-difference qdd)",
                     best_time(lambda: follow_path_ur(robot, path, branch=BRANCH), 1, repeat)))
    if ur_analytic_ik is not None:
        ik_all = ur_analytic_ik.ur3.inverse_kinematics
        ik_closest = ur_analytic_ik.ur3.inverse_kinematics_closest

        def peer_closest():
            out = np.empty((n, 6))
            previous = q[0]
            with quiet_stdout():
                for k, X in enumerate(poses):
                    previous = out[k] = ik_closest(X, *previous)[0]
            return out

        def peer_all():
            with quiet_stdout():
                for X in poses:
                    ik_all(X)

        theirs = peer_closest()
        gap = np.abs(np.angle(np.exp(1j * (theirs - q)))).max()
        print(f"ur_analytic_ik nearest solutions agree with the tracked branch to {gap:.1e} rad")
        rows_out.append(("ur_analytic_ik.inverse_kinematics_closest, loop",
                         best_time(peer_closest, 1, max(1, repeat // 2))))
        rows_out.append(("ur_analytic_ik.inverse_kinematics (all), loop",
                         best_time(peer_all, 1, max(1, repeat // 2))))
    else:
        print("ur_analytic_ik is not installed: skipped")
    t0 = time.process_time()
    traj_num, report_num = follow_path_numerical(robot, path, q[0])
    rows_out.append(("follow_path_numerical (the report's method)", time.process_time() - t0))
    print(f"numerical: position error <= {report_num.position_error.max():.1e} m")

    reference = rows_out[0][1]
    width = max(len(label) for label, _ in rows_out)
    print()
    print(f"{'method':<{width}}  {'ms/circle':>10}  {'us/point':>9}  {'this / closed form':>18}")
    for label, seconds in rows_out:
        print(f"{label:<{width}}  {seconds * 1e3:10.2f}  {seconds / n * 1e6:9.2f}  "
              f"{seconds / reference:18.1f}")
    times = dict(rows_out)
    full = times["follow_path_ur (q, J^-1 qd, finite-difference qdd)"]
    print()
    print(f"numerical following / closed-form following (with speeds): "
          f"{times['follow_path_numerical (the report' + chr(39) + 's method)'] / full:.0f}x "
          f"(goal >= 100)")
    if ur_analytic_ik is not None:
        for label in ("ur_analytic_ik.inverse_kinematics_closest, loop",
                      "ur_analytic_ik.inverse_kinematics (all), loop"):
            print(f"{label} / closed form batched + tracking: {times[label] / reference:.1f}x "
                  f"(goal >= 5)")


if __name__ == "__main__":
    main()
