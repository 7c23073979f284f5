"""dqlab: quaternions and dual quaternions for robot kinematics.

The companion package of the course book *Quaternions and dual quaternions for robot
kinematics*. Conventions: quaternions are scalar-first ``(w, x, y, z)`` with the Hamilton
product and active rotations ``p' = q p q*``; dual quaternions are ``q_r + eps q_d`` with
``q_d = t q_r / 2``, stored as 8 numbers; units are metres and radians. Every function takes
array-likes and works on the last axis, broadcasting over leading axes.
"""

import importlib

__version__ = "0.1.0"

# Sub-packages reached as attributes (``dqlab.models.ur3()``) are imported on first use, so
# that ``import dqlab`` stays light.
_SUBMODULES = {
    "complex", "rotations", "quaternion", "transforms", "dualquat", "robot", "models",
    "jacobian", "ik", "trajectory", "identify", "viz", "ur",
}


def __getattr__(name):
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module 'dqlab' has no attribute {name!r}")
