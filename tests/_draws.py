"""Random inputs shared by the tests (seeded by the caller's generator)."""

import numpy as np


def random_unit_quaternions(rng, shape=()):
    """Unit quaternions ``(w, x, y, z)`` of shape ``shape + (4,)``, uniform on the 3-sphere
    (normalised Gaussian samples); ``shape`` an int or a tuple."""
    shape = (shape,) if isinstance(shape, int) else tuple(shape)
    q = rng.normal(size=shape + (4,))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)
