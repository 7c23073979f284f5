"""The UR3's reachability and dexterity map with dask: 10^7 poses on 1 and 2 workers.

Run with ``python benchmarks/bench_reachability.py`` (``--quick`` for a small map of 46 656
poses; ``--save PATH`` to write the per-position result; ``--address tcp://host:8786`` to
run on an existing dask cluster instead of the local ones). The map is
``dqlab.dask_arrays.reachability_map``: every tool position of a 3D grid with every orientation of
a set, each pose scored by the number of valid branches of ``dqlab.ik.ur`` and the largest
manipulability |det J| over them, reduced to statistics per position (the fraction of
orientations reachable, the mean branch count, the median manipulability).

- Grid: x, y from -0.60 to 0.60 m and z from -0.45 to 0.75 m in steps of 0.05 m (25^3 =
  15 625 positions; it holds the board points of chapter 11's circle), times 640
  orientations of a super-Fibonacci spiral
  (``dqlab.reachability.super_fibonacci_quaternions``): 10 000 000 poses. Deterministic,
  nothing random. ``--quick``: steps of 0.15 m (9^3) and 64 orientations.
- numpy: ``dqlab.reachability.reachability_statistics``, the same computation in this
  process, one core.
- dask: a ``distributed.LocalCluster`` of 1 worker, then of 2 workers (one process and one
  thread each: ``processes=True, threads_per_worker=1``), ``reachability_map(...,
  scheduler=client)``; or the cluster at ``--address``, the same call with the address.
  Each worker first imports dqlab and solves a small map (not timed). The local workers
  start without distributed's default ``MALLOC_TRIM_THRESHOLD_=65536``: with it, glibc
  hands every freed temporary above 64 kiB back to the system and the next one faults its
  pages in again, which made the map's numpy code a third slower (CPU time) in a worker
  than in this process. A cluster at ``--address`` runs with its own settings.

Every dask map is compared with the numpy one (they must be equal number for number). The
table gives wall-clock times (``time.perf_counter``, one run each: the full map takes
minutes), poses per second, the speed-up from 1 to 2 workers in wall-clock time, and the CPU
time spent (this process for numpy, the worker processes for dask): on a machine shared
with other work, a wall time above the CPU time per worker means the workers waited for a
core. numpy and BLAS run single-threaded, so one worker uses one core. This is not a test.

The stored map of chapter 11, ``book/data/ur3_reachability.npz``, was written by

    python benchmarks/bench_reachability.py --save book/data/ur3_reachability.npz

which also stores the times of the run with it (the chapter prints them).
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")      # one core per worker; inherited by the workers

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

import dqlab  # noqa: E402
from dqlab.dask_arrays import reachability_map  # noqa: E402
from dqlab.models import ur3  # noqa: E402
from dqlab.reachability import (  # noqa: E402
    reachability_statistics,
    super_fibonacci_quaternions,
)


def grid(quick):
    """The tool positions (nx, ny, nz, 3) and orientations (K, 4) of the map."""
    if quick:
        xy, z, k = np.arange(-4, 5) * 0.15, np.arange(-3, 6) * 0.15, 64
    else:
        xy, z, k = np.arange(-12, 13) * 0.05, np.arange(-9, 16) * 0.05, 640
    xy, z = np.round(xy, 10), np.round(z, 10)
    positions = np.stack(np.meshgrid(xy, xy, z, indexing="ij"), axis=-1)
    return positions, super_fibonacci_quaternions(k)


def same_map(a, b):
    return (np.array_equal(a.reachable, b.reachable) and np.array_equal(a.branches, b.branches)
            and np.array_equal(a.median_manipulability, b.median_manipulability,
                               equal_nan=True))


def timed(f):
    start = time.perf_counter()
    out = f()
    return out, time.perf_counter() - start


def cpu_seconds():
    """CPU time of the calling process (run on the workers by ``client.run``)."""
    return time.process_time()


def timed_on(client, f):
    """``f()``'s result, wall time and the CPU time the client's workers spent on it."""
    before = client.run(cpu_seconds)
    out, seconds = timed(f)
    after = client.run(cpu_seconds)
    return out, seconds, sum(after[w] - before[w] for w in before if w in after)


def warm_up(robot, orientations, scheduler, workers):
    """Import dqlab on every worker and solve a little (not timed)."""
    few = np.zeros((4 * workers, 3)) + [0.0, -0.3, 0.3]
    reachability_map(robot, few, orientations[:8], chunk=1, scheduler=scheduler)


def on_local_cluster(robot, positions, orientations, chunk, workers):
    import dask
    import distributed
    no_trim = {"distributed.nanny.pre-spawn-environ": {"MALLOC_TRIM_THRESHOLD_": None}}
    with dask.config.set(no_trim), \
            distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                     dashboard_address=None) as cluster, \
            distributed.Client(cluster, set_as_default=False) as client:
        client.wait_for_workers(workers)
        warm_up(robot, orientations, client, workers)
        return timed_on(client, lambda: reachability_map(robot, positions, orientations,
                                                         chunk=chunk, scheduler=client))


def on_cluster_at(address, robot, positions, orientations, chunk):
    import distributed
    with distributed.Client(address, set_as_default=False) as client:
        info = client.scheduler_info()["workers"].values()
        workers = len(info)
        threads = sum(w.get("nthreads", 1) for w in info)
        warm_up(robot, orientations, client, workers)
        # the map connects to the address itself, as a user's call would
        rmap, seconds, cpu = timed_on(client, lambda: reachability_map(
            robot, positions, orientations, chunk=chunk, scheduler=address))
    return rmap, seconds, cpu, workers, threads


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a small map (46 656 poses)")
    parser.add_argument("--address", help="run on the dask scheduler at this address "
                        "(tcp://host:port) instead of local clusters")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2],
                        help="sizes of the local clusters (default: 1 2)")
    parser.add_argument("--chunk", type=int, help="positions per task")
    parser.add_argument("--no-numpy", action="store_true",
                        help="skip the numpy run (then nothing checks the dask maps)")
    parser.add_argument("--save", help="write the map (.npz) to this path")
    args = parser.parse_args()

    robot = ur3()
    positions, orientations = grid(args.quick)
    m, k = positions[..., 0].size, len(orientations)
    samples = m * k
    chunk = args.chunk or max(1, min(2 ** 16 // k, m // 32))
    tasks = -(-m // chunk)
    print(f"UR3 reachability map: {m} positions {positions.shape[:-1]} x {k} orientations = "
          f"{samples:,} poses, {chunk} positions ({chunk * k:,} poses) per task, "
          f"{tasks} tasks; {os.cpu_count()} CPUs")

    rows = []                          # (what, workers, wall seconds, CPU seconds)
    reference = None
    if not args.no_numpy:
        cpu = time.process_time()
        reference, seconds = timed(lambda: reachability_statistics(robot, positions,
                                                                   orientations))
        rows.append(("numpy, in this process", 1, seconds, time.process_time() - cpu))
        print(f"numpy done in {seconds:.1f} s")
    maps = {}
    if args.address:
        rmap, seconds, cpu, workers, threads = on_cluster_at(args.address, robot, positions,
                                                             orientations, chunk)
        rows.append((f"dask, {args.address}", workers, seconds, cpu))
        print(f"dask on the cluster at {args.address} ({workers} workers, {threads} "
              f"threads) done in {seconds:.1f} s")
        maps[workers] = rmap
    else:
        for workers in args.workers:
            rmap, seconds, cpu = on_local_cluster(robot, positions, orientations, chunk,
                                                  workers)
            rows.append(("dask, LocalCluster", workers, seconds, cpu))
            maps[workers] = rmap
            print(f"dask on {workers} worker(s) done in {seconds:.1f} s")
    if reference is not None:
        for workers, rmap in maps.items():
            equal = same_map(rmap, reference)
            print(f"dask map on {workers} worker(s) equals the numpy map: {equal}")
            if not equal:
                sys.exit("the dask and numpy maps differ")

    one = next((s for what, w, s, _ in rows if w == 1 and what.startswith("dask")), None)
    width = max(len(what) for what, *_ in rows) + 2
    print(f"\n{'run':<{width}}{'workers':>8}{'wall (s)':>10}{'poses/s':>12}{'speed-up':>10}"
          f"{'CPU (s)':>10}")
    for what, workers, seconds, cpu in rows:
        speedup = f"{one / seconds:.2f}" if one and what.startswith("dask") else ""
        print(f"{what:<{width}}{workers:>8}{seconds:>10.1f}{samples / seconds:>12,.0f}"
              f"{speedup:>10}{cpu:>10.1f}")

    rmap = next(iter(maps.values()), reference)
    fraction = rmap.fraction
    print(f"\n{np.mean(fraction > 0):.1%} of the positions reach some orientation, "
          f"{np.mean(fraction == 1):.1%} every one; mean branch count where reachable "
          f"{rmap.branches.sum() / rmap.reachable.sum():.2f}; median manipulability up to "
          f"{np.nanmax(rmap.median_manipulability) * 1e3:.1f} dm^3 (1e-3 m^3)")

    if args.save:
        import dask
        meta = {"command": "python benchmarks/bench_reachability.py "
                + " ".join(sys.argv[1:]),
                "samples": samples, "cpus": os.cpu_count(), "chunk": chunk,
                "dask_version": dask.__version__, "dqlab_version": dqlab.__version__}
        for what, workers, seconds, cpu in rows:
            key = "numpy" if what.startswith("numpy") else f"{workers}_workers"
            meta["seconds_" + key] = round(seconds, 2)
            meta["cpu_seconds_" + key] = round(cpu, 2)
        rmap.save(args.save, **meta)
        print(f"wrote {args.save} ({os.path.getsize(args.save) / 1e3:.0f} kB)")


if __name__ == "__main__":
    main()
