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
