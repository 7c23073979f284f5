"""Input validation shared by every module: shapes, finiteness, clear ``ValueError`` s."""

import numpy as np


def as_float_array(x, name, trailing=None):
    """Return ``x`` as a float array whose trailing shape is ``trailing``.

    Raises ``ValueError`` naming ``name`` when the trailing shape is wrong or when ``x``
    holds NaN or infinity.

    >>> as_float_array([1, 0, 0, 0], "q", (4,))
    array([1., 0., 0., 0.])
    """
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of numbers: {exc}") from None
    if trailing is not None:
        trailing = tuple(trailing)
        if a.ndim < len(trailing) or a.shape[a.ndim - len(trailing):] != trailing:
            want = "(..., " + ", ".join(map(str, trailing)) + ")"
            raise ValueError(f"{name} must have shape {want}, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinity")
    return a
