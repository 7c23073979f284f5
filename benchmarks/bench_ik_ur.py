"""Speed of dqlab's closed-form UR3 inverse kinematics next to ur_analytic_ik.

Run with ``python benchmarks/bench_ik_ur.py`` (``--quick`` for a short run, ``--n N`` for
another number of poses). Every method solves the same poses, the forward kinematics of
seeded random configurations, and the table gives microseconds per pose and the ratio of
ur_analytic_ik's time to each method's (above 1: faster than ur_analytic_ik).

- ``dqlab.ik.ur`` batch: one call for all poses, as 4x4 transforms or as unit dual
  quaternions (the thesis's pose-file form), with the residuals from the solved equations
  (default) or from forward kinematics of every row (``residuals="fk"``);
- ``dqlab.ik.ur`` single: one call per pose in a Python loop;
- ``dqlab.ik.ur`` with a tool (the UR3 with a TCP 0.15 m along the flange's z axis), single
  pose and batch: one pose with a tool is solved on Python floats as one without;
- ``dqlab.ik.ur`` on a calibrated UR3 (every :math:`\theta, a, d, \alpha` off by up to 2 mm
  and 2 mrad, seeded; ``dqlab.ik.ur_calibrated``: the nominal closed form, then Newton steps
  on the calibrated chain, compiled when numba is installed: ``benchmarks/
  bench_ik_ur_calibrated.py`` times both paths), batch and single (the single loop on the
  first 500 poses), on poses of the calibrated arm; the share of poses whose generating
  configuration is found and the worst error of a valid row are printed;
- ``ur_analytic_ik`` (C++ with Python bindings): one call per pose in a Python loop, the
  only way it is offered;
- ``dqlab.ik.numerical`` (damped least squares, one solution per pose, warm-started 0.1 rad
  from the answer), batch and single (the single loop on the first 500 poses only);
- ``roboticstoolbox-python``'s ``ik_LM`` (Levenberg--Marquardt in C++), when it is installed
  (optional; not a dependency of dqlab): the same 500 poses from the same warm starts, with
  its tolerance set to the same residual (``tol = 5e-21`` on half the squared error norm, that
  is an error norm of at most 1e-10) and no random restarts; the success counts and mean
  iteration counts of both are printed (ik_LM counts its forward kinematics, one more than
  its steps; the steps are printed).

Before timing, the solution counts of dqlab and ur_analytic_ik are compared. Goals, as
ratios to ur_analytic_ik in the same run: a single pose at most 2 times its single call
(one pose is solved on Python floats, see ``dqlab._fast.ur_engine``); a batch at least 25
times faster per pose than its loop; the numerical solver's single pose at most 60 times its
closed-form single call, and at most half the time of ik_LM with as many poses solved. This
is not a test. Times are the CPU time of this process (``time.process_time``), the best of
several rounds in which every method runs once in turn (a slow spell of the machine then
touches all of them alike), which other load on the machine disturbs less than wall-clock
time; numpy runs single-threaded here, so on an idle machine the two agree. A batch call
is repeated within a run so that the run lasts at least 20 ms, about as long as the loops
of single calls, after one untimed call: the first batch call after the other methods finds
cold caches and gets its memory back from the system (some 1,300 page faults for 10,000
poses), a cost that repeated calls do not pay and that would otherwise fall on whichever
method runs first in a round. The best time of those first calls is printed below the
table.
"""

import argparse

import numpy as np
from timing import calls_lasting, interleaved_best

from dqlab.dualquat import dual_quaternion_from_transform
from dqlab.identify import dh_parameters, robot_from_dh_parameters
from dqlab.ik import ur
from dqlab.models import ur3
from dqlab.rotations import wrap_angle
from dqlab.testing import quiet_stdout


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer poses and repeats")
    parser.add_argument("--n", type=int, default=10_000, help="number of poses")
    args = parser.parse_args()
    n = 1000 if args.quick else args.n
    repeat = 3 if args.quick else 5
    n_loop = min(n, 2000)                   # the one-at-a-time methods: the first 2000 poses

    robot = ur3()
    rng = np.random.default_rng(2026)
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    T = np.ascontiguousarray(robot.fk(q))
    Q = dual_quaternion_from_transform(T)

    try:
        import ur_analytic_ik
    except ImportError:  # pragma: no cover
        ur_analytic_ik = None
    try:
        from dqlab.ik import numerical
    except ImportError:  # pragma: no cover
        numerical = None

    # agreement first
    result = ur(robot, T)
    print(f"{n} poses of the UR3 from seeded random configurations")
    print(f"dqlab: {result.count.sum()} valid solutions, counts per pose "
          f"{np.bincount(result.count, minlength=9).tolist()} (0..8)")
    if ur_analytic_ik is not None:
        with quiet_stdout():
            theirs = [ur_analytic_ik.ur3.inverse_kinematics(X) for X in T]
        counts = np.array([len(s) for s in theirs])
        print(f"ur_analytic_ik: same number of solutions on "
              f"{np.mean(counts == result.count):.4%} of the poses")

    jobs = {}   # label: (function, calls per run, poses per call[, untimed calls first]),
    #             timed together at the end

    def batch(f):   # a batch call, repeated to last as long as a loop of single calls
        return f, calls_lasting(f), n, 1                      # after one untimed call

    jobs["dqlab.ik.ur batch, 4x4 poses"] = batch(lambda: ur(robot, T))
    jobs["dqlab.ik.ur batch, dual quaternions"] = batch(lambda: ur(robot, Q))
    jobs["dqlab.ik.ur batch, residuals='fk'"] = batch(lambda: ur(robot, T, residuals="fk"))

    def single_loop(poses, **kw):
        def run():
            for X in poses:
                ur(robot, X, **kw)
        return run

    jobs["dqlab.ik.ur single pose, in a loop"] = (single_loop(T[:n_loop]), 1, n_loop)
    jobs["dqlab.ik.ur single pose, residuals='fk'"] = (single_loop(T[:n_loop], residuals="fk"),
                                                        1, n_loop)
    tooled = robot.with_tool(z=0.15)
    T_tool = np.ascontiguousarray(tooled.fk(q))
    jobs["dqlab.ik.ur batch, with a tool"] = batch(lambda: ur(tooled, T_tool))

    def tool_loop():
        for X in T_tool[:n_loop]:
            ur(tooled, X)

    jobs["dqlab.ik.ur single pose with a tool, in a loop"] = (tool_loop, 1, n_loop)

    # a calibrated UR3: every theta, a, d, alpha off by up to 2 mm / 2 mrad
    calibrated = robot_from_dh_parameters(
        robot, dh_parameters(robot) + np.random.default_rng(7).uniform(-2e-3, 2e-3, 24))
    T_cal = np.ascontiguousarray(calibrated.fk(q))
    cal = ur(calibrated, T_cal)
    found = np.any(cal.valid & np.all(np.abs(wrap_angle(cal.solutions - q[:, None]))
                                      < 1e-6, axis=-1), axis=-1)
    print(f"calibrated UR3 (2 mm / 2 mrad): generating configuration found on "
          f"{found.mean():.2%} of {n} poses; worst error of a valid row "
          f"{cal.position_error[cal.valid].max():.1e} m, "
          f"{cal.rotation_error[cal.valid].max():.1e} rad")
    jobs["dqlab.ik.ur calibrated batch"] = batch(lambda: ur(calibrated, T_cal))
    n_cal = min(n, 500)

    def calibrated_loop():
        for X in T_cal[:n_cal]:
            ur(calibrated, X)

    jobs[f"dqlab.ik.ur calibrated single pose, in a loop ({n_cal})"] = (calibrated_loop, 1,
                                                                         n_cal)
    if ur_analytic_ik is not None:
        ik = ur_analytic_ik.ur3.inverse_kinematics

        def peer():
            with quiet_stdout():
                for X in T[:n_loop]:
                    ik(X)

        jobs["ur_analytic_ik, in a loop"] = (peer, 1, n_loop)
    if numerical is not None:
        q0 = q + rng.uniform(-0.1, 0.1, q.shape)
        jobs["dqlab.ik.numerical batch (1 solution)"] = batch(lambda: numerical(robot, T, q0))
        print(f"dqlab.ik.numerical batch: {int(numerical(robot, T, q0).valid.sum())} of {n} "
              "poses solved")
        n_single = min(n, 500)              # about 4 ms each: the first 500 poses

        def numerical_loop():
            for X, g in zip(T[:n_single], q0[:n_single], strict=True):
                numerical(robot, X, g)

        jobs[f"dqlab.ik.numerical single pose, in a loop ({n_single})"] = (numerical_loop, 1,
                                                                            n_single)
        ours = [numerical(robot, X, g, history=True)
                for X, g in zip(T[:n_single], q0[:n_single], strict=True)]
        steps = [len(r.history["damping"]) - 1 for r in ours]
        print(f"dqlab.ik.numerical: {sum(bool(r.valid[0]) for r in ours)} of {n_single} "
              f"single poses solved to 1e-10 m and rad, {np.mean(steps):.2f} iterations on "
              f"average (at most {max(steps)})")
        try:
            import roboticstoolbox as rtb
        except Exception:  # not installed, or fails to import  # noqa: BLE001
            rtb = None
            print("roboticstoolbox is not installed: its ik_LM column is left out")
        if rtb is not None:
            peer_robot = rtb.models.DH.UR3()
            assert np.abs(peer_robot.fkine(q[0]).A - T[0]).max() < 1e-12   # same frames

            def peer_numerical():
                return [peer_robot.ik_LM(X, q0=g, tol=5e-21, slimit=1)
                        for X, g in zip(T[:n_single], q0[:n_single], strict=True)]

            jobs[f"roboticstoolbox ik_LM single pose, in a loop ({n_single})"] = (
                peer_numerical, 1, n_single)
            solved = peer_numerical()
            found = np.array([s.q for s in solved])
            good = [bool(s.success) for s in solved]
            err = np.abs(robot.fk(found) - T[:n_single]).max(axis=(-1, -2))
            steps = [s.iterations - 1 for s in solved]
            print(f"roboticstoolbox ik_LM: {sum(good)} of {n_single} reported solved; "
                  f"{int(np.sum(err[good] < 1e-9))} of those within 1e-9 of the pose; "
                  f"{np.mean(steps):.2f} iterations on average (at most {max(steps)})")
    else:
        print("dqlab.ik.numerical is not available: skipped")

    first_calls = {}
    rows = list(interleaved_best(jobs, repeat, first_calls).items())   # (label, s per pose)
    reference = dict(rows).get("ur_analytic_ik, in a loop")
    width = max(len(label) for label, _ in rows)
    print()
    print(f"{'method':<{width}}  {'us/pose':>9}  {'ur_analytic_ik / this':>21}  "
          f"{'this / ur_analytic_ik':>21}")
    for label, seconds in rows:
        ratio = f"{reference / seconds:21.2f}" if reference else f"{'-':>21}"
        inverse = f"{seconds / reference:21.2f}" if reference else f"{'-':>21}"
        print(f"{label:<{width}}  {seconds * 1e6:9.2f}  {ratio}  {inverse}")
    print("\nfirst call of a run (untimed above), us/pose: " + "; ".join(
        f"{label.removeprefix('dqlab.ik.')} {seconds * 1e6:.2f}"
        for label, seconds in first_calls.items()))
    timed = dict(rows)
    nominal_single = timed["dqlab.ik.ur single pose, in a loop"]
    nominal_batch = timed["dqlab.ik.ur batch, 4x4 poses"]
    calibrated_single = timed[f"dqlab.ik.ur calibrated single pose, in a loop ({n_cal})"]
    print(f"\ncalibrated / nominal: single pose {calibrated_single / nominal_single:.1f}"
          f", batch {timed['dqlab.ik.ur calibrated batch'] / nominal_batch:.1f} (goal: at most "
          f"5); with a tool / without: single pose "
          f"{timed['dqlab.ik.ur single pose with a tool, in a loop'] / nominal_single:.2f}, "
          f"batch {timed['dqlab.ik.ur batch, with a tool'] / nominal_batch:.2f}")
    single = [seconds for label, seconds in rows if label.startswith("dqlab.ik.numerical single")]
    peer = [seconds for label, seconds in rows if label.startswith("roboticstoolbox ik_LM")]
    if single and peer:
        print(f"\ndqlab.ik.numerical single / roboticstoolbox ik_LM: {single[0] / peer[0]:.2f} "
              "(goal: at most 0.5)")


if __name__ == "__main__":
    main()
