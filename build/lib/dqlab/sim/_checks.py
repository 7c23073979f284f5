"""Argument checks shared by the modules of :mod:`dqlab.sim` (clear ``ValueError`` s that
name the argument)."""

import math

import numpy as np


def number(value, name, *, minimum=0.0, strict=True):
    """``value`` as a finite float above ``minimum`` (or equal, if not ``strict``).

    >>> number(0.5, "dt")
    0.5
    >>> number(0.0, "payload", strict=False)
    0.0
    """
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    ok = value > minimum if strict else value >= minimum
    if not (math.isfinite(value) and ok):
        relation = ">" if strict else ">="
        raise ValueError(f"{name} must be a finite number {relation} {minimum:g}, "
                         f"got {value!r}")
    return value


def vector(value, n, name):
    """``value`` as a finite float array of shape (n,); a single number is repeated.

    >>> vector(2.0, 3, "kp")
    array([2., 2., 2.])
    """
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be numbers, got {value!r}") from None
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} contains NaN or infinity")
    return arr


def per_joint(value, n, name, *, positive):
    """Like :func:`vector`, and every entry > 0 (``positive``) or >= 0.

    >>> per_joint([1.0, 0.0], 2, "damping", positive=False)
    array([1., 0.])
    """
    arr = vector(value, n, name)
    bad = (arr <= 0) if positive else (arr < 0)
    if bad.any():
        kind = "> 0" if positive else ">= 0"
        raise ValueError(f"{name} must be {kind}, got {arr.tolist()}")
    return arr
