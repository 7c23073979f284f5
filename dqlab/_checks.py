"""Input validation shared by every module: shapes, finiteness, clear ``ValueError`` s."""

import math
import os
import re
import unicodedata
from pathlib import Path

import numpy as np

from ._formulas import functions_for, orthonormality

_FLOAT64 = np.dtype(np.float64)


def real_array(x, name):
    """``x`` as a float array: ``TypeError`` naming ``name`` for complex numbers or text,
    ``ValueError`` for anything else that is not an array of numbers (ragged, None...).

    >>> real_array([1, 2], "v")
    array([1., 2.])
    >>> real_array([1j], "v")
    Traceback (most recent call last):
    ...
    TypeError: v must hold real numbers, got complex numbers (dtype complex128)
    """
    if x is None:
        raise TypeError(f"{name} must be an array of numbers, got None")
    try:
        a = np.asarray(x)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"{name} must be an array of numbers: {exc}") from None
    kind = a.dtype.kind
    if kind == "f":
        return a if a.dtype == _FLOAT64 else a.astype(float)
    if kind == "c":
        raise TypeError(f"{name} must hold real numbers, got complex numbers (dtype {a.dtype})")
    if kind in "USV":
        raise TypeError(f"{name} must hold numbers, got {a.dtype.name} data")
    if kind == "O" and any(v is None for v in a.flat):
        raise TypeError(f"{name} must be an array of numbers, got None in it")
    try:
        return a.astype(float)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"{name} must be an array of numbers: {exc}") from None


def batch_shape(shape, name="shape"):
    """A batch shape as a tuple of non-negative ints (an int or a sequence of ints).

    >>> batch_shape(3), batch_shape((2, 0))
    ((3,), (2, 0))
    """
    if isinstance(shape, tuple) and not shape:
        return ()
    dims = np.atleast_1d(np.asarray(shape, dtype=object))
    out = []
    for d in dims:
        if isinstance(d, (bool, np.bool_)) or not isinstance(d, (int, np.integer)) or d < 0:
            raise ValueError(f"{name} must be a non-negative int or a tuple of them, "
                             f"got {shape!r}")
        out.append(int(d))
    return tuple(out)


def check_tolerance(value, name):
    """``value`` as a float, or ``ValueError`` naming ``name`` unless it is a number >= 0
    (``inf`` switches a check off; NaN and negative numbers are refused).

    >>> check_tolerance(1e-9, "tol")
    1e-09
    >>> check_tolerance(float("nan"), "tol")
    Traceback (most recent call last):
    ...
    ValueError: tol must be a number >= 0, got nan
    """
    return check_scalar(value, name, minimum=0, finite=False)


def check_scalar(value, name, *, minimum=None, maximum=None, strict=False, finite=True,
                 integer=False):
    """``value`` as a float (an int with ``integer``), or ``ValueError`` naming ``name``.

    The one check of a scalar argument, with one exception type for every mistake: text,
    None, a bool, a complex number, an array of more than one number, NaN, infinity (unless
    ``finite`` is False, which lets ``+inf`` through as "no limit"), a value below
    ``minimum`` (or equal to it, with ``strict``) or above ``maximum``, and with ``integer``
    anything but an integer type.

    Parameters
    ----------
    value : object
        The argument as given.
    name : str
        Its name, quoted in the message.
    minimum, maximum : float, optional
        Bounds; ``minimum`` is excluded with ``strict``, ``maximum`` is always included.
    strict : bool
        Require ``value > minimum`` rather than ``>=``.
    finite : bool
        Refuse infinities (default); with False, ``inf`` is a valid value within the bounds.
    integer : bool
        Require an integer type (Python ``int`` or a numpy integer; not ``2.0``).

    Returns
    -------
    float or int

    Examples
    --------
    >>> check_scalar(0.5, "dt", minimum=0, strict=True)
    0.5
    >>> check_scalar(3, "stride", minimum=1, integer=True)
    3
    >>> check_scalar(float("nan"), "dt", minimum=0, strict=True)
    Traceback (most recent call last):
    ...
    ValueError: dt must be a finite number > 0, got nan
    >>> check_scalar("1 s", "duration", minimum=0, strict=True)
    Traceback (most recent call last):
    ...
    ValueError: duration must be a finite number > 0, got '1 s'
    """
    if type(value) is float and not integer:            # the common cases, without numpy
        v = value
    elif type(value) is int and (integer or abs(value) < 2 ** 1000):
        v = value if integer else float(value)
    else:
        if isinstance(value, (bool, np.bool_, str, bytes)) or value is None:
            _refuse(value, name, minimum, maximum, strict, finite, integer)
        try:
            a = np.asarray(value)
        except Exception:
            a = np.asarray(None)
        if a.ndim != 0 or a.dtype.kind not in ("iu" if integer else "iuf"):
            _refuse(value, name, minimum, maximum, strict, finite, integer)
        v = int(a) if integer else float(a)
    if ((not integer and (math.isnan(v) or (finite and math.isinf(v)) or v == -math.inf))
            or (minimum is not None and not (v > minimum if strict else v >= minimum))
            or (maximum is not None and not v <= maximum)):
        _refuse(value, name, minimum, maximum, strict, finite, integer)
    return v


def _refuse(value, name, minimum, maximum, strict, finite, integer):
    """The ``ValueError`` of :func:`check_scalar`: what ``name`` must be, and what it got."""
    want = "an integer" if integer else ("a finite number" if finite else "a number")
    if minimum is not None:
        want += f" {'>' if strict else '>='} {minimum:g}"
    if maximum is not None:
        want += f"{' and' if minimum is not None else ''} <= {maximum:g}"
    raise ValueError(f"{name} must be {want}, got {short_repr(value)}")


def short_repr(value, limit=80):
    """The ``repr`` of ``value`` for an error message: at most ``limit`` characters on one
    line (a long text or a big container is described, not printed whole).

    >>> short_repr("x" * 1000, limit=10)
    "'xxxxxxxxx... (1000 characters)"
    >>> short_repr(list(range(100)))
    'a list of 100 entries'
    >>> short_repr(np.zeros((3, 4)))
    'an array of shape (3, 4)'
    """
    if isinstance(value, (list, tuple, dict, set, frozenset)) and len(value) > 8:
        return f"a {type(value).__name__} of {len(value)} entries"
    if isinstance(value, (np.ndarray, np.generic)) and value.size > 8:
        return f"an array of shape {value.shape}"
    if isinstance(value, (str, bytes)) and len(value) > limit:
        text = repr(value[:limit])
        return f"{text[:limit]}... ({len(value)} characters)"
    try:
        text = repr(value)
    except Exception:                           # a repr that fails says nothing useful
        text = f"a {type(value).__name__}"
    text = " ".join(text.split())               # one line
    return text if len(text) <= limit else text[:limit] + "..."


#: What no text of dqlab may hold: control characters (C0, DEL, C1), lone surrogates,
#: the line and paragraph separators and the code points XML 1.0 excludes (U+FFFE, U+FFFF).
_ILLEGAL_TEXT = re.compile("[\x00-\x1f\x7f-\x9f\ud800-\udfff\u2028\u2029\ufffe\uffff]")


def check_text(value, name, *, max_length=200, forbidden="", why=""):
    r"""``value`` itself when it is one line of text, or an error naming ``name``.

    The check of a name or label that dqlab writes into a file (XML, G-code, a pose file):
    text (``TypeError`` otherwise), not empty, at most ``max_length`` characters, and
    without control characters (a line end would start a new line of the file), lone
    surrogates or the other code points XML 1.0 cannot hold, or any of the characters
    ``forbidden`` (``why`` says why they are). The message names the first bad character
    and its position, never the whole text.

    Examples
    --------
    >>> check_text("UR5e on the bench", "name")
    'UR5e on the bench'
    >>> check_text("x\nM2231 V1", "name")
    Traceback (most recent call last):
    ...
    ValueError: name must be one line of printable text: character '\n' at position 1 ...
    >>> check_text("stop!", "name", forbidden="!~?@", why="the firmware obeys them anywhere")
    Traceback (most recent call last):
    ...
    ValueError: name must not hold '!' (the firmware obeys them anywhere), found at position 4
    """
    if not isinstance(value, str):
        raise TypeError(f"{name} must be text, got {short_repr(value)}")
    if not value:
        raise ValueError(f"{name} must not be empty")
    bad = _ILLEGAL_TEXT.search(value)
    if bad:
        raise ValueError(f"{name} must be one line of printable text: character "
                         f"{bad.group()!r} at position {bad.start()} is a control character"
                         if unicodedata.category(bad.group()) == "Cc" else
                         f"{name} must be one line of printable text: character "
                         f"{ascii(bad.group())} at position {bad.start()} cannot be written "
                         "in a text file")
    if len(value) > max_length:
        raise ValueError(f"{name} must be at most {max_length} characters, got "
                         f"{len(value)}")
    for k, char in enumerate(value):
        if char in forbidden:
            reason = f" ({why})" if why else ""
            raise ValueError(f"{name} must not hold {char!r}{reason}, found at position {k}")
    return value


def is_boolean(value):
    """True for a boolean or an array of booleans: not numbers, though numpy reads them as
    0 and 1 (anything numpy cannot read as an array is not boolean here).

    >>> is_boolean(True), is_boolean([True, False]), is_boolean([1, 0]), is_boolean([[1], []])
    (True, True, False, False)
    """
    try:
        return np.asarray(value).dtype.kind == "b"
    except (TypeError, ValueError):
        return False


def check_instance(value, kind, name):
    """``value`` itself, or ``TypeError`` naming ``name`` unless it is an instance of
    ``kind`` (a class or a tuple of classes).

    >>> check_instance(None, float, "robot")
    Traceback (most recent call last):
    ...
    TypeError: robot must be a float, got None
    """
    if not isinstance(value, kind):
        names = " or ".join(k.__name__ for k in (kind if isinstance(kind, tuple) else (kind,)))
        got = "None" if value is None else f"a {type(value).__name__}"
        raise TypeError(f"{name} must be a {names}, got {got}")
    return value


def check_path(path, name="path"):
    """``path`` as a :class:`pathlib.Path`, or ``TypeError`` naming ``name`` unless it is
    text or an ``os.PathLike`` (an int would be taken for an open file descriptor).

    >>> check_path("poses.csv").name
    'poses.csv'
    """
    if not isinstance(path, (str, os.PathLike)):
        got = "None" if path is None else f"a {type(path).__name__}"
        raise TypeError(f"{name} must be a file path (text or os.PathLike), got {got}")
    return Path(path)


def as_float_array(x, name, trailing=None):
    """Return ``x`` as a float array whose trailing shape is ``trailing``.

    Raises ``ValueError`` naming ``name`` when the trailing shape is wrong or when ``x``
    holds NaN or infinity.

    >>> as_float_array([1, 0, 0, 0], "q", (4,))
    array([1., 0., 0., 0.])
    """
    a = real_array(x, name)
    if trailing is not None:
        trailing = tuple(trailing)
        if a.ndim < len(trailing) or a.shape[a.ndim - len(trailing):] != trailing:
            want = "(..., " + ", ".join(map(str, trailing)) + ")"
            raise ValueError(f"{name} must have shape {want}, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or infinity")
    return a


# --- Fast paths shared by the math core -------------------------------------------------
#
# A single value (a 1-D array) is computed with Python floats, which is several times faster
# than numpy on four numbers; a batch is computed column by column with numpy. The formulas
# are written once, on "components", and run unchanged on floats or on arrays.


def float_array(x, name, trailing):
    """Like :func:`as_float_array`, but a float64 ndarray of the right shape is returned as is.

    ``trailing`` must be a tuple. Finiteness of such an array is *not* checked here: callers
    check their result (see :func:`finite_or_raise`) or call :func:`check_finite` on batches.

    >>> float_array([0, 1, 0], "v", (3,))
    array([0., 1., 0.])
    """
    if (type(x) is np.ndarray and x.dtype is _FLOAT64 and x.shape[-len(trailing):] == trailing
            and x.ndim >= len(trailing)):
        return x
    return as_float_array(x, name, trailing)



def check_finite(a, name):
    """Raise ``ValueError`` naming ``name`` when the array ``a`` holds NaN or infinity.

    >>> check_finite(np.zeros(3), "v")
    """
    if not np.isfinite(a).all():
        raise ValueError(f"{name} contains NaN or infinity")


def components(a):
    """Split the last axis of ``a``: Python floats for a 1-D array, column views otherwise.

    >>> components(np.array([1.0, 2.0]))
    [1.0, 2.0]
    """
    if a.ndim == 1:
        return a.tolist()
    # one copy to a component-major layout makes every later operation contiguous
    return list(np.ascontiguousarray(_last_axis_first(a)))


def component_rows(a):
    """The components of ``a`` (its last axis) as the rows of a new C-ordered array: a copy,
    always, which the caller may overwrite.

    >>> component_rows(np.arange(6.0).reshape(3, 2))
    array([[0., 2., 4.],
           [1., 3., 5.]])
    """
    return _last_axis_first(a).copy()


def _last_axis_first(a):
    """A view of ``a`` with its last axis first (``np.moveaxis(a, -1, 0)``, cheaper)."""
    return a.transpose((a.ndim - 1,) + tuple(range(a.ndim - 1)))


def stack_components(parts):
    """Inverse of :func:`components`: a new float array with ``parts`` on the last axis.

    >>> stack_components([1.0, 2.0])
    array([1., 2.])
    """
    return functions_for((type(parts[0]), type(parts[-1]))).stack(parts)


def finite_or_raise(out, *named):
    """Return ``out`` if it is finite; otherwise find the bad input and raise ``ValueError``.

    ``named`` are ``(array, name, trailing)`` triples of the inputs, checked in order with
    :func:`as_float_array` so that the message names the argument at fault.

    >>> finite_or_raise(np.ones(2), (np.ones(2), "a", (2,)))
    array([1., 1.])
    """
    if np.isfinite(out).all():
        return out
    for x, name, trailing in named:
        as_float_array(x, name, trailing)
    raise ValueError("the result is not finite: the inputs are too large (overflow)")


def pack(parts, *named):
    """Stack ``parts`` (see :func:`stack_components`) and make sure the result is finite.

    The test is on the sum of the parts, which NaN or infinity in any part makes NaN or
    infinite (a sum that overflows is told apart by :func:`finite_or_raise`, which also
    names the input at fault). ``named`` are the inputs as in :func:`finite_or_raise`.

    >>> pack([1.0, 2.0], (np.ones(2), "a", (2,)))
    array([1., 2.])
    """
    f = functions_for((type(parts[0]), type(parts[-1])))
    total = sum(parts)                  # NaN or inf in a part make it NaN or inf
    out = f.stack(parts)
    return out if f.all_finite(total) else finite_or_raise(out, *named)


CHUNK = 8192


def batched(kernel, inputs, out_trailing, chunk=CHUNK):
    """Apply ``kernel`` to a batch in chunks of ``chunk`` elements and assemble the result.

    ``inputs`` are ``(array, k)`` pairs, ``k`` being the number of trailing (per-element)
    axes of that array; the leading axes broadcast. ``kernel`` receives the chunks (each
    with one leading axis) and returns an array of trailing shape ``out_trailing``.
    Chunks that fit in the processor cache make the many small element-wise operations of
    a component formula about twice as fast as one pass over a large batch.

    >>> batched(lambda a, b: a + b, [(np.ones((3, 2)), 1), (np.ones(2), 1)], (2,))
    array([[2., 2.],
           [2., 2.],
           [2., 2.]])
    """
    shape = np.broadcast_shapes(*(a.shape[:a.ndim - k] for a, k in inputs))
    n = 1
    for s in shape:
        n *= s
    flat = [np.broadcast_to(a, shape + a.shape[a.ndim - k:]).reshape((n,) + a.shape[a.ndim - k:])
            for a, k in inputs]
    if n <= chunk:
        out = kernel(*flat)
    else:
        out = np.empty((n,) + tuple(out_trailing))
        for start in range(0, n, chunk):
            out[start:start + chunk] = kernel(*(f[start:start + chunk] for f in flat))
    return out.reshape(shape + tuple(out_trailing))


# --- Checks on components (see dqlab._formulas) ------------------------------------------


def unit_quaternion_or_raise(parts, name, tol, subject=None):
    """Raise unless the quaternion given by its components has norm 1 within ``tol``.

    ``parts`` are four floats or four arrays; ``name`` is the argument, ``subject`` what the
    message says is not unit (default ``name``, e.g. "the real part of Q").

    >>> unit_quaternion_or_raise((0.0, 0.0, 0.0, 1.0), "q", 1e-9)
    >>> unit_quaternion_or_raise((0.0, 0.0, 0.0, 0.0), "Q", 1e-9, "the real part of Q")
    Traceback (most recent call last):
    ...
    ValueError: the real part of Q is the zero quaternion, which is not a rotation
    """
    w, x, y, z = parts
    n2 = w * w + x * x + y * y + z * z
    f = functions_for(type(n2))
    if f.max_abs(n2 - 1.0) <= tol:  # implies | |q| - 1 | <= tol / 2 (NaN and inf fail it)
        return
    if not f.all_finite(n2):
        raise ValueError(f"{name} contains NaN or infinity")
    norm = f.sqrt(n2)
    off = abs(norm - 1.0)
    if not f.largest(off) <= tol:
        _raise_not_unit(subject or name, f.first(norm, np.logical_not(off <= tol)), tol)


def _raise_not_unit(subject, n, tol):
    check_tolerance(tol, "tol")
    if n == 0.0:
        raise ValueError(f"{subject} is the zero quaternion, which is not a rotation")
    raise ValueError(
        f"{subject} must be a unit quaternion (norm 1 within {tol:g}), got norm {n:.12g}; "
        "normalise it with quaternion_normalize first")


def rigid_rows(T, tol):
    """The top three rows of one (4, 4) float array as lists of Python floats when it is a
    rigid transform within ``tol`` (finite, orthonormal rotation block with determinant
    +1, last row ``(0, 0, 0, 1)``); None otherwise, for the caller's full check to say why.

    >>> rigid_rows(np.eye(4), 1e-9)[0]
    [1.0, 0.0, 0.0, 0.0]
    >>> rigid_rows(np.diag([1.0, 1.0, -1.0, 1.0]), 1e-9) is None
    True
    """
    a, b, c, d = T.tolist()
    err, det = orthonormality(a, b, c)  # NaN or inf in R fail this test too
    t = a[3] + b[3] + c[3]
    if err <= tol and det > 0.0 and t - t == 0.0 and d == [0.0, 0.0, 0.0, 1.0]:
        return a, b, c
    return None


def unit_dual_quaternion_or_raise(parts, name, tol):
    """Raise unless :math:`|q_r| = 1` and :math:`\\langle q_r, q_d\\rangle = 0` within ``tol``.

    >>> unit_dual_quaternion_or_raise((1.0, 0, 0, 0, 0, 0.5, 0, 0), "Q", 1e-9)
    """
    rw, rx, ry, rz, dw, dx, dy, dz = parts
    unit_quaternion_or_raise((rw, rx, ry, rz), name, tol, f"the real part of {name}")
    dot = rw * dw + rx * dx + ry * dy + rz * dz
    bad = functions_for(type(dot)).max_abs(dot)
    if not bad - bad == 0.0:
        raise ValueError(f"{name} contains NaN or infinity")
    if not bad <= tol:
        check_tolerance(tol, "tol")
        raise ValueError(
            f"{name} must be a unit dual quaternion: <q_r, q_d> = {bad:.3g} should be 0 "
            f"(tolerance {tol:g}); normalise it with dual_quaternion_normalize first")


def rotation_or_raise(name, err, det, tol):
    """Raise unless ``err`` (largest entry of :math:`|R^T R - I|`, see
    :func:`dqlab._formulas.orthonormality`) is within ``tol`` and ``det`` is positive.

    >>> rotation_or_raise("R", 0.0, -1.0, 1e-9)
    Traceback (most recent call last):
    ...
    ValueError: R is a reflection (determinant -1), not a rotation
    """
    check_tolerance(tol, "tol")
    if not err <= tol:
        rounding = ("; that tolerance is too small: rounding alone leaves errors of a few "
                    "1e-16 in a rotation stored in floats" if err <= 1e-14 else "")
        raise ValueError(f"{name} is not orthonormal: |R^T R - I| reaches {err:.3g} "
                         f"(tolerance {tol:g}){rounding}")
    if not det > 0.0:
        raise ValueError(f"{name} is a reflection (determinant -1), not a rotation")
