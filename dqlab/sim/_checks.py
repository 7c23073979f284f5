"""Argument checks of :mod:`dqlab.sim`: joint-space vectors (clear errors that name the
argument). Scalars go through :func:`dqlab._checks.check_scalar`, like everywhere else."""

import numpy as np

from .._checks import is_boolean, real_array

_FLOAT64 = np.dtype(np.float64)


def vector(value, n, name):
    """``value`` as a finite float array of shape (n,); a single number is repeated.
    Complex numbers, text and None are refused (``TypeError``), like every array of dqlab.

    >>> vector(2.0, 3, "kp")
    array([2., 2., 2.])
    """
    if type(value) is np.ndarray and value.dtype is _FLOAT64 and value.shape == (n,):
        total = sum(value.tolist())                   # a float: fast for a few joints
        if total - total == 0.0:                      # NaN or inf, or an overflow: check
            return value
    if is_boolean(value):
        raise TypeError(f"{name} must hold numbers, got booleans")
    arr = real_array(value, name)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} contains NaN or infinity")
    return arr


def per_joint(value, n, name, *, positive, minimum=None):
    """Like :func:`vector`, and every entry > 0 (``positive``) or >= 0, and >= ``minimum``
    when given.

    >>> per_joint([1.0, 0.0], 2, "damping", positive=False)
    array([1., 0.])
    """
    arr = vector(value, n, name)
    bad = (arr <= 0) if positive else (arr < 0)
    if minimum is not None:
        bad |= arr < minimum
    if bad.any():
        kind = "> 0" if positive else ">= 0"
        if minimum is not None:
            kind += f" and >= {minimum:g}"
        raise ValueError(f"{name} must be {kind}, got {arr.tolist()}")
    return arr
