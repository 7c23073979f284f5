"""Argument checks shared by the modules of :mod:`dqlab.ur` (and its MuJoCo back end)."""

import math

import numpy as np

from .._checks import short_repr

__all__ = ["real_number", "positive_number"]


def real_number(value, name):
    """``value`` as a float, or ``TypeError`` naming ``name`` for anything but one real
    number: text, bools, None, complex numbers (never truncated), sequences and arrays of
    more than one value.

    >>> real_number(2, "a")
    2.0
    >>> real_number(1j, "a")
    Traceback (most recent call last):
    ...
    TypeError: a must be a real number, got 1j
    """
    if value is None or isinstance(value, (bool, np.bool_, str, bytes, complex,
                                           np.complexfloating, list, tuple, dict, set)):
        raise TypeError(f"{name} must be a real number, got {short_repr(value)}")
    if isinstance(value, np.ndarray) and (value.ndim != 0 or value.dtype.kind not in "iuf"):
        raise TypeError(f"{name} must be a real number, got {short_repr(value)}")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a real number, got {short_repr(value)}") from None


def positive_number(value, name):
    """``value`` as a finite float > 0, or an error naming ``name``.

    >>> positive_number(0.5, "dt")
    0.5
    """
    x = real_number(value, name)
    if not (x > 0.0 and math.isfinite(x)):
        raise ValueError(f"{name} must be a finite number > 0, got {short_repr(value)}")
    return x
