"""Inverse kinematics: closed-form solvers and a numerical solver, one result type for all.

- :func:`ur` -- every closed-form solution of a UR-family arm, by dual quaternions;
- :func:`numerical` -- damped least squares, position-only or full pose;
- :func:`desk_arm` -- the 3-DOF desktop arm in closed form;
- :func:`scara` -- the SCARA RSM-5 in closed form.
"""

from .result import IKResult

__all__ = ["IKResult"]

try:  # each solver lives in its own module
    from .ur import ur  # noqa: F401
    __all__.append("ur")
except ImportError:  # pragma: no cover
    pass
try:
    from .numerical import numerical  # noqa: F401
    __all__.append("numerical")
except ImportError:  # pragma: no cover
    pass
try:
    from .arm3 import desk_arm  # noqa: F401
    __all__.append("desk_arm")
except ImportError:  # pragma: no cover
    pass
try:
    from .scara import scara  # noqa: F401
    __all__.append("scara")
except ImportError:  # pragma: no cover
    pass
