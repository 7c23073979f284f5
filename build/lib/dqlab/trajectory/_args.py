"""Argument checks shared by the modules of :mod:`dqlab.trajectory`."""

import numpy as np


def positive(value, name):
    """``value`` as a float; ``TypeError``/``ValueError`` naming ``name`` unless finite > 0.

    >>> positive(0.5, "dt")
    0.5
    """
    x = finite(value, name)
    if x <= 0.0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return x


def finite(value, name):
    """``value`` as a float; ``TypeError``/``ValueError`` naming ``name`` unless finite.

    >>> finite(-2, "distance")
    -2.0
    """
    if isinstance(value, (str, bytes)) or np.ndim(value) != 0:
        raise TypeError(f"{name} must be a number, got {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(x):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return x
