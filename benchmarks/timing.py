"""The benchmarks' timer: the best CPU time per item of several methods, timed in rounds."""

import math
import time


def interleaved_best(jobs, repeat, first_calls=None):
    """Best CPU time per item of each job ``label: (function, calls per run, items per
    call)`` or ``(function, calls per run, items per call, untimed calls)`` over ``repeat``
    rounds, in seconds.

    Every round runs every job in turn, so that a slow spell of the machine touches all of
    them alike and the ratios between them stay fair. The time is the CPU time of this
    process (``time.process_time``), which other programs on a shared machine inflate less
    than wall-clock time. A run first makes its untimed calls, if any: the first call of a
    batch method after the other methods finds cold caches and has its memory handed back
    by the system (a page fault per 4 kB), which a steady stream of calls does not pay.
    With ``first_calls`` (a dict), the best time per item of those untimed calls is stored
    there too.
    """
    best = dict.fromkeys(jobs, math.inf)
    for _ in range(repeat):
        for label, (f, calls, items, *untimed) in jobs.items():
            untimed = untimed[0] if untimed else 0
            start = time.process_time()
            for _ in range(untimed):
                f()
            if untimed and first_calls is not None:
                first = (time.process_time() - start) / (untimed * items)
                first_calls[label] = min(first_calls.get(label, math.inf), first)
            start = time.process_time()
            for _ in range(calls):
                f()
            best[label] = min(best[label], (time.process_time() - start) / (calls * items))
    return best


def calls_lasting(f, seconds=0.02):
    """How many calls of ``f`` last at least ``seconds`` of CPU time, from one timed call.

    A job run this often lasts about as long as a loop of single calls, so that a slow
    moment weighs in it no more than in the loop.
    """
    start = time.process_time()
    f()
    return max(1, math.ceil(seconds / max(time.process_time() - start, 1e-9)))
