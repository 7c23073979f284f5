"""The benchmarks' timer: the best CPU time per item of several methods, timed in rounds."""

import math
import time


def interleaved_best(jobs, repeat):
    """Best CPU time per item of each job ``label: (function, calls per run, items per
    call)`` over ``repeat`` rounds, in seconds.

    Every round runs every job in turn, so that a slow spell of the machine touches all of
    them alike and the ratios between them stay fair. The time is the CPU time of this
    process (``time.process_time``), which other programs on a shared machine inflate less
    than wall-clock time.
    """
    best = dict.fromkeys(jobs, math.inf)
    for _ in range(repeat):
        for label, (f, calls, items) in jobs.items():
            start = time.process_time()
            for _ in range(calls):
                f()
            best[label] = min(best[label], (time.process_time() - start) / (calls * items))
    return best


def calls_lasting(f, seconds=0.02):
    """How many calls of ``f`` last at least ``seconds`` of CPU time, from one timed call.

    A job run this often lasts about as long as a loop of single calls, and the first call
    after other work (which finds the caches cold: about 10 % slower for a batch call of a
    few milliseconds) weighs in it no more than in the loop.
    """
    start = time.process_time()
    f()
    return max(1, math.ceil(seconds / max(time.process_time() - start, 1e-9)))
