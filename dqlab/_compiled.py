"""The one switch of dqlab's compiled paths: the environment variable ``DQLAB_COMPILED``.

Some speed machinery of dqlab runs compiled by numba when it is installed (the ``fast``
extra): the Newton steps of inverse kinematics on a calibrated UR
(``dqlab.ik._newton_compiled``), tested equal to the numpy path that runs without it.
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

import os

__all__ = ["VARIABLE", "compiled_allowed"]

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
