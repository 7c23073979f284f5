r"""Assertions for tests of code that uses dqlab, and a silencer for oracles that print.

A rotation has two unit quaternions, :math:`q` and :math:`-q`, and a rigid motion two unit
dual quaternions, :math:`Q` and :math:`-Q` (chapters 3 and 5): two correct programs may
return either. :func:`assert_quaternion_equal` and :func:`assert_dual_quaternion_equal`
compare arrays of them item by item up to that sign, where
``numpy.testing.assert_allclose`` would report half of the right answers as wrong.

The exercises' checker, ``check_function``, is :func:`dqlab.exercises.check_function`.
"""

import contextlib
import os
import sys

import numpy as np

from ._checks import as_float_array, check_tolerance

__all__ = ["assert_quaternion_equal", "assert_dual_quaternion_equal", "quiet_stdout"]


def _assert_equal_up_to_sign(actual, desired, atol, size, what):
    a = as_float_array(actual, "actual", (size,))
    d = as_float_array(desired, "desired", (size,))
    atol = check_tolerance(atol, "atol")
    try:
        shape = np.broadcast_shapes(a.shape, d.shape)
    except ValueError:
        raise ValueError(f"actual of shape {a.shape} and desired of shape {d.shape} do not "
                         "broadcast together") from None
    a, d = np.broadcast_to(a, shape), np.broadcast_to(d, shape)
    with np.errstate(over="ignore"):
        gap = np.minimum(np.abs(a - d).max(axis=-1), np.abs(a + d).max(axis=-1))
    if gap.size == 0 or gap.max() <= atol:
        return
    worst = tuple(int(i) for i in np.unravel_index(np.argmax(gap), gap.shape))
    where = f" at index {worst}" if worst else ""
    raise AssertionError(
        f"the {what}s differ by {gap[worst]:.3g} up to sign (atol {atol:.3g}){where}, "
        f"{int((gap > atol).sum())} of {gap.size} items:\n"
        f"actual  {_one_line(a[worst])}\ndesired {_one_line(d[worst])}")


def _one_line(x):
    return "[" + ", ".join(f"{v:.17g}" for v in x) + "]"


def assert_quaternion_equal(actual, desired, *, atol=1e-12):
    r"""Fail unless each quaternion of ``actual`` is that of ``desired`` or its negative.

    Item by item over the leading axes (which broadcast):
    :math:`\min(\lVert a - d\rVert_\infty, \lVert a + d\rVert_\infty) \le` ``atol``.

    Parameters
    ----------
    actual, desired : array_like, shape (..., 4)
        Quaternions ``(w, x, y, z)``.
    atol : float, optional
        Largest allowed difference of one component.

    Raises
    ------
    AssertionError
        Naming the worst item, its difference and the two quaternions.
    ValueError
        If an argument has the wrong shape, holds NaN or infinity, or the shapes do not
        broadcast; if ``atol`` is negative or NaN.

    Examples
    --------
    >>> import numpy as np
    >>> assert_quaternion_equal([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, -1.0])   # same rotation
    >>> assert_quaternion_equal([1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0])
    Traceback (most recent call last):
    ...
    AssertionError: the quaternions differ by 1 up to sign (atol 1e-12), 1 of 1 items:
    ...
    """
    _assert_equal_up_to_sign(actual, desired, atol, 4, "quaternion")


def assert_dual_quaternion_equal(actual, desired, *, atol=1e-12):
    r"""Fail unless each dual quaternion of ``actual`` is that of ``desired`` or its negative.

    Item by item over the leading axes (which broadcast), all eight numbers with one sign:
    :math:`\min(\lVert A - D\rVert_\infty, \lVert A + D\rVert_\infty) \le` ``atol``.

    Parameters
    ----------
    actual, desired : array_like, shape (..., 8)
        Dual quaternions ``(q_r, q_d)``.
    atol : float, optional
        Largest allowed difference of one component.

    Raises
    ------
    AssertionError
        Naming the worst item, its difference and the two dual quaternions.
    ValueError
        If an argument has the wrong shape, holds NaN or infinity, or the shapes do not
        broadcast; if ``atol`` is negative or NaN.

    Examples
    --------
    The UR3 at rest, by its chain and by its transform, is one rigid motion:

    >>> import numpy as np
    >>> from dqlab import dual_quaternion_from_transform
    >>> from dqlab.models import ur3
    >>> robot = ur3()
    >>> assert_dual_quaternion_equal(robot.fk_dq(np.zeros(6)),
    ...                              -dual_quaternion_from_transform(robot.fk(np.zeros(6))))
    """
    _assert_equal_up_to_sign(actual, desired, atol, 8, "dual quaternion")


@contextlib.contextmanager
def quiet_stdout():
    """Silence the C-level standard output for the duration of the block.

    ``ur_analytic_ik``, used as an independent oracle in the tests and benchmarks, prints a
    line to the C ``stdout`` (file descriptor 1) for every candidate its forward-kinematics
    filter rejects; ``contextlib.redirect_stdout`` cannot catch it, so descriptor 1 is
    pointed at ``os.devnull`` and restored afterwards.

    Examples
    --------
    >>> with quiet_stdout():
    ...     _ = os.write(1, b"not shown")
    """
    sys.stdout.flush()
    saved = os.dup(1)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    try:
        yield
    finally:
        os.dup2(saved, 1)
        os.close(devnull)
        os.close(saved)
