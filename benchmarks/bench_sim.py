"""Speed of the MuJoCo simulation of the UR3: steps per second and real-time factor.

Run with ``python benchmarks/bench_sim.py`` (add ``--quick`` for a short run). It prints one
table with, for each way of running the arm, the simulation steps per second of CPU time and
the real-time factor (simulated seconds per CPU second; above 1: faster than real time):

- ``mj_step`` alone (constant torques): MuJoCo's own cost, the ceiling;
- ``track`` with joint PD, with PD plus gravity compensation, and with computed torque
  (one ``mj_inverse`` per step) along a smooth 6-joint trajectory;
- ``MujocoBackend`` executing a ``movej`` (computed torque, the reference sampled per step).

The model is ``ArmSimulation(ur3())`` with its default 1 ms step. This is not a test;
timings vary between machines and with the load on them (the best CPU time of several runs
is reported).
"""

import argparse
import time
from types import SimpleNamespace

import numpy as np

from dqlab.models import ur3
from dqlab.sim import ArmSimulation, ComputedTorque, JointPD, MujocoBackend, track

UR3_PD_GAINS = {"kp": [400, 400, 200, 50, 50, 50], "kd": [40, 40, 20, 5, 5, 5]}


def smooth_trajectory(duration, dt=0.005):
    t = np.arange(0.0, duration + dt / 2, dt)
    q0 = np.array([0.2, -1.3, 1.4, -1.6, -1.5, 0.3])
    amp = np.array([0.6, 0.4, 0.5, 0.7, 0.5, 0.9])
    w = 2 * np.pi / duration * np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])
    phase = t[:, None] * w
    return SimpleNamespace(t=t, q=q0 + amp * (1 - np.cos(phase)), qd=amp * w * np.sin(phase),
                           qdd=amp * w**2 * np.cos(phase))


def best_cpu_time(f, repeat):
    best = np.inf
    for _ in range(repeat):
        start = time.process_time()
        f()
        best = min(best, time.process_time() - start)
    return best


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="shorter runs")
    args = parser.parse_args()
    duration = 1.0 if args.quick else 5.0
    repeat = 2 if args.quick else 5

    sim = ArmSimulation(ur3())
    dt = sim.timestep
    steps = int(round(duration / dt))
    move = smooth_trajectory(duration)
    rows = []

    def raw():
        sim.reset(move.q[0])
        sim.step(sim.gravity_torque(move.q[0]), steps=steps)

    rows.append(("mj_step, constant torques", best_cpu_time(raw, repeat)))
    for name, controller in [
        ("track, joint PD", JointPD(**UR3_PD_GAINS)),
        ("track, PD + gravity", JointPD(**UR3_PD_GAINS, gravity_compensation=True)),
        ("track, computed torque", ComputedTorque()),
    ]:
        rows.append((name, best_cpu_time(lambda c=controller: track(sim, move, c), repeat)))

    arm = MujocoBackend()

    def backend_movej():
        arm.connect(timeout=1.0)
        arm.movej(np.asarray(arm.q_home) + 0.5, a=1.4, v=1.05, t=duration, r=0.0)
        arm.advance(duration)
        arm.close()

    rows.append(("MujocoBackend movej, computed torque", best_cpu_time(backend_movej, repeat)))

    print(f"UR3 in MuJoCo, time step {dt * 1e3:g} ms, {duration:g} s simulated per run")
    print(f"{'run':40s} {'steps/s':>10s} {'real-time factor':>18s} {'vs mj_step':>11s}")
    base = rows[0][1]
    for name, seconds in rows:
        print(f"{name:40s} {steps / seconds:10.0f} {duration / seconds:18.1f} "
              f"{base / seconds:11.2f}")


if __name__ == "__main__":
    main()
