"""The one switch of dqlab's compiled paths: the environment variable ``DQLAB_COMPILED``.

Some speed machinery of dqlab runs compiled by numba when it is installed (the ``fast``
extra): the Newton steps of inverse kinematics on a calibrated UR
(``dqlab._fast.newton_compiled``) and the recursions of the dynamics
(``dqlab._fast.dynamics_compiled``), each tested equal to the numpy path that runs without it;
:func:`compile_in_place` compiles them, once per process.
``DQLAB_COMPILED=0`` switches every compiled path off (the numpy paths run, as in a browser
or without numba); unset, ``1`` or empty: on wherever numba imports. It is read here only,
by :func:`compiled_allowed`, which a compiled path's public entry calls at each call
(``dqlab.ik.ur`` on a calibrated UR does): a process may switch it between calls, as the
tests and benchmarks do.

>>> import os
>>> os.environ["DQLAB_COMPILED"] = "0"
>>> compiled_allowed()
False
>>> del os.environ["DQLAB_COMPILED"]
>>> compiled_allowed()
True
"""

import importlib.util
import os

__all__ = ["VARIABLE", "compiled_allowed", "compile_in_place"]

#: The name of the environment variable.
VARIABLE = "DQLAB_COMPILED"

_ON = ("", "1", "true", "yes", "on")
_OFF = ("0", "false", "no", "off")


def compiled_allowed() -> bool:
    """Whether ``DQLAB_COMPILED`` allows the compiled paths (they also need numba).

    Raises
    ------
    ValueError
        If the variable holds anything but 0 or 1 (or true/false, yes/no, on/off).
    """
    value = os.environ.get(VARIABLE)
    if value is None:
        return True
    value = value.strip().lower()
    if value in _ON:
        return True
    if value in _OFF:
        return False
    raise ValueError(f"the environment variable {VARIABLE} must be 0 (compiled paths off) or "
                     f"1 (on), got {value[:40]!r}")


def compile_in_place(namespace, names) -> bool:
    """Compile the functions ``names`` of a module's ``namespace`` (its ``globals()``) with
    numba, in place, and say whether it could: False without numba, or with a numba that does
    not import (e.g. one that does not support the installed numpy). The compiled code is
    cached on disk for the next processes."""
    if importlib.util.find_spec("numba") is None:
        return False
    try:
        import numba
    except ImportError:
        return False
    jit = numba.njit(cache=True, nogil=True, error_model="numpy")
    for name in names:
        namespace[name] = jit(namespace[name])
    return True
