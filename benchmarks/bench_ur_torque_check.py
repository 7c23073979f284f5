"""What the joint-torque check adds to the safety checks of dqlab.ur, measured side by side.

Run with ``python benchmarks/bench_ur_torque_check.py`` (add ``--quick`` for a short run). For
a typical program of each kind, on the UR3 carrying 2 kg, it prints the time of the checks
with the rated torques (``SafetyLimits.for_robot(ur3(), payload=2.0)``) and without them
(the same limits with ``max_joint_torque=None``), their ratio, and the time per sample of the
torque check alone:

- a trajectory of 1,000 samples (8 s at the servo period), checked by ``check_trajectory``:
  the torques of its 4,000 states in one batch of ``dynamics.inverse_dynamics``;
- the program of 1,000 ``servoj`` lines that plays it, checked by ``plan_program`` as the
  stand-in checks what it receives (a few states per line, one at a time with
  ``dynamics.NewtonEuler``);
- a 2 s ``movej`` (``movej(q, q_from=...)``), its 250 samples one at a time;
- the per-state cost of the two evaluations behind ``SafetyLimits.joint_torques``, the batch
  and the loop of single states, on the movej's samples (below ``_BATCH_FROM`` states the
  loop is used).

This is not a test; timings vary between machines and with the load on them (the best CPU
time of several rounds, interleaved, is reported).
"""

import argparse

import numpy as np
from timing import interleaved_best

from dqlab import dynamics
from dqlab.models import ur3
from dqlab.ur import motion
from dqlab.ur import script as S


def main(quick=False):
    repeat = 2 if quick else 5
    robot = ur3()
    torques = S.SafetyLimits.for_robot(robot, payload=2.0, payload_cog=[0.0, 0.0, 0.05])
    speeds_only = S.SafetyLimits.for_robot(robot, max_joint_torque=None)
    q_mid = np.array([0.4, -1.3, 1.1, -1.2, -1.4, 0.6])
    t = np.arange(1001) * S.SERVOJ_T
    wave = 0.5 * (1 - np.cos(2 * np.pi * t / t[-1]))
    trajectory = type("T", (), {"t": t, "q": q_mid + np.outer(wave, [0.3, -0.2, 0.25, 0.1,
                                                                       0.2, 0.3])})()
    program = [("servoj", q, {"t": S.SERVOJ_T}) for q in trajectory.q[1:]]
    target = q_mid + [1.0, -0.5, 0.6, 0.4, 0.5, 0.6]
    movej = motion.plan_movej(q_mid, target, a=1.4, v=0.6)
    _, q, qd, qdd = movej.samples()

    jobs = {}
    for label, limits in (("with torques", torques), ("speeds only", speeds_only)):
        jobs[f"trajectory, {label}"] = (
            lambda limits=limits: S.check_trajectory(trajectory, limits=limits), 1, 1)
        jobs[f"program, {label}"] = (
            lambda limits=limits: S.plan_program(program, q_now=trajectory.q[0],
                                                 limits=limits), 1, 1)
        jobs[f"movej, {label}"] = (
            lambda limits=limits: S.movej(target, a=1.4, v=0.6, limits=limits, q_from=q_mid),
            1, 1)
    loaded = dynamics.with_payload(robot, 2.0, [0.0, 0.0, 0.05])
    newton_euler = dynamics.NewtonEuler(loaded)
    jobs["batch, per state"] = (lambda: dynamics.inverse_dynamics(loaded, q, qd, qdd), 1,
                                len(q))
    jobs["loop, per state"] = (
        lambda: [newton_euler(q[k], qd[k], qdd[k]) for k in range(len(q))], 1, len(q))
    assert np.allclose(torques.joint_torques(q, qd, qdd),
                       dynamics.inverse_dynamics(loaded, q, qd, qdd), atol=1e-12)
    best = interleaved_best(jobs, repeat)

    print("UR3 with 2 kg: the safety checks with and without the rated torques "
          "(best CPU time)\n")
    print(f"{'check':36s} {'with torques':>14s} {'speeds only':>13s} {'ratio':>7s}")
    for what in ("trajectory (1,000 samples)", "program (1,000 servoj lines)",
                 f"movej ({movej.duration:.1f} s, {len(q)} samples)"):
        key = what.split(" ")[0]
        a, b = best[f"{key}, with torques"], best[f"{key}, speeds only"]
        print(f"{what:36s} {a * 1e3:11.1f} ms {b * 1e3:10.1f} ms {a / b:7.1f}")
    print(f"\ntorques per state: batch {best['batch, per state'] * 1e6:.1f} us, "
          f"one at a time {best['loop, per state'] * 1e6:.1f} us "
          f"(the check takes the batch from {S._BATCH_FROM} states on)")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer rounds")
    main(parser.parse_args().quick)
