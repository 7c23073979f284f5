"""What the thin classes over ``(..., k)`` arrays share: :class:`dqlab.quaternion.Quaternion`
and :class:`dqlab.dualquat.DualQuaternion` hold only what is specific to them.

A subclass sets ``_trailing`` (the shape of one element), ``_name`` (the argument name in
error messages) and ``_product`` (the array function behind ``*``, as a ``staticmethod``),
and defines ``power`` (behind ``**``).
"""

import numpy as np

from ._checks import as_float_array


class ArrayWrapper:
    """A value of shape ``(..., k)``, or a batch of them, kept as a float array ``.array``.

    >>> class Pair(ArrayWrapper):
    ...     __slots__ = ()
    ...     _trailing, _name, _product = (2,), "p", staticmethod(np.multiply)
    >>> P = Pair([[1, 2], [3, 4]])
    >>> P.shape, len(P), P[1] * P[1]
    ((2,), 2, Pair([ 9., 16.]))
    """

    __slots__ = ("array",)
    __array_priority__ = 20
    # numpy must not apply its ufuncs element-wise to a wrapper (``Q * ndarray`` would be
    # an element-wise product): binary operators with arrays defer to the methods below,
    # which refuse them (TypeError); ``np.asarray(Q)`` still gives the array.
    __array_ufunc__ = None
    _trailing = None
    _name = "x"
    _product = None

    def __init__(self, x):
        if isinstance(x, type(self)):
            x = x.array
        self.array = as_float_array(x, self._name, self._trailing)

    @property
    def shape(self):
        """Leading (batch) shape: ``()`` for a single element."""
        return self.array.shape[:-len(self._trailing)]

    def __len__(self):
        if not self.shape:
            raise TypeError(f"a single {type(self).__name__} has no len()")
        return self.shape[0]

    def __getitem__(self, index):
        return type(self)(self.array[index])

    def __array__(self, dtype=None, copy=None):
        return self.array if dtype is None else self.array.astype(dtype)

    def __mul__(self, other):
        if isinstance(other, type(self)):
            return type(self)(self._product(self.array, other.array))
        if np.ndim(other) == 0:
            return type(self)(self.array * float(other))
        return NotImplemented

    def __rmul__(self, other):
        if np.ndim(other) == 0:
            return type(self)(self.array * float(other))
        return NotImplemented

    def __add__(self, other):
        if isinstance(other, type(self)):
            return type(self)(self.array + other.array)
        return NotImplemented

    def __sub__(self, other):
        if isinstance(other, type(self)):
            return type(self)(self.array - other.array)
        return NotImplemented

    def __neg__(self):
        return type(self)(-self.array)

    def __pow__(self, t):
        return self.power(t)

    def __eq__(self, other):
        if isinstance(other, type(self)):
            return bool(np.array_equal(self.array, other.array))
        return NotImplemented

    __hash__ = None

    def __repr__(self):
        name = type(self).__name__
        body = np.array2string(self.array, separator=", ", prefix=f"{name}(")
        return f"{name}({body})"


def array_of(x):
    """The ``.array`` of a wrapper, anything else unchanged.

    >>> array_of([1.0, 0.0])
    [1.0, 0.0]
    """
    return getattr(x, "array", x)


def float_if_single(a):
    """A float for a single value (an array of shape ()), the array itself for a batch: what
    a wrapper's scalar-valued methods (``norm``, ``angle``...) return.

    >>> float_if_single(np.array(2.0)), float_if_single(np.array([1.0, 2.0]))
    (2.0, array([1., 2.]))
    """
    return float(a) if a.ndim == 0 else a
