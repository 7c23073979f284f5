"""The exercises' checker: a reader's own function compared with dqlab's on random inputs.

Each chapter's automatically checked exercises call :func:`check_function`:
the reader writes a function, the check draws inputs with a seeded generator, calls the
reader's function and dqlab's on each, and says how far apart they were -- or stops at the
first input where they differ, quoting it.
"""

import numpy as np

__all__ = ["check_function"]


def check_function(candidate, reference, sample, *, n=100, seed=0, atol=1e-9, name=None):
    """Compare ``candidate`` with ``reference`` on ``n`` random inputs and report.

    Parameters
    ----------
    candidate, reference : callable
        The function to check and the function it must agree with. Both receive the same
        positional arguments.
    sample : callable
        ``sample(rng)`` returns a tuple of positional arguments drawn with the generator
        ``rng`` (a :class:`numpy.random.Generator`).
    n : int
        Number of random trials.
    seed : int
        Seed of the generator, so that a check is repeatable.
    atol : float
        Largest allowed absolute difference between the two outputs.
    name : str, optional
        Name printed in the report (defaults to ``candidate.__name__``).

    Returns
    -------
    float
        The largest absolute difference seen.

    Raises
    ------
    AssertionError
        With the first failing input, when the outputs differ by more than ``atol``.

    Examples
    --------
    >>> import numpy as np
    >>> def my_norm(v):
    ...     return sum(x * x for x in v) ** 0.5
    >>> worst = check_function(my_norm, np.linalg.norm, lambda rng: (rng.normal(size=3),))
    my_norm agrees with the reference on 100 random inputs (largest difference ...)
    >>> worst < 1e-15
    True
    """
    rng = np.random.default_rng(seed)
    label = name or getattr(candidate, "__name__", "candidate")
    worst = 0.0
    for _ in range(n):
        args = sample(rng)
        got = np.asarray(candidate(*args), dtype=float)
        want = np.asarray(reference(*args), dtype=float)
        if got.shape != want.shape:
            raise AssertionError(
                f"{label}{args!r} has shape {got.shape}, expected {want.shape}")
        diff = float(np.max(np.abs(got - want), initial=0.0))
        if not diff <= atol:
            raise AssertionError(
                f"{label} differs from the reference by {diff:.3g} for input {args!r}:\n"
                f"got {got!r}\nexpected {want!r}")
        worst = max(worst, diff)
    print(f"{label} agrees with the reference on {n} random inputs "
          f"(largest difference {worst:.2g})")
    return worst
