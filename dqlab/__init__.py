"""dqlab: quaternions and dual quaternions for robot kinematics.

The companion package of the course book *Quaternions and dual quaternions for robot
kinematics*. Conventions: quaternions are scalar-first ``(w, x, y, z)`` with the Hamilton
product and active rotations ``p' = q p q*``; dual quaternions are ``q_r + eps q_d`` with
``q_d = t q_r / 2``, stored as 8 numbers; units are metres and radians. Every function takes
array-likes and works on the last axis, broadcasting over leading axes.
"""

import importlib

__version__ = "0.1.11"

# The math core the chapters use, re-exported at the top level (``dqlab.quaternion_product``,
# the public contract of ../shared/DESIGN.md among them); every other function is reached
# through its module (``dqlab.rotations.skew``, ``dqlab.complex.planar_arm_joints``).
from .dualquat import (  # noqa: E402
    DualQuaternion,
    dual_quaternion_apply,
    dual_quaternion_apply_line,
    dual_quaternion_combined_conjugate,
    dual_quaternion_conjugate,
    dual_quaternion_dual_conjugate,
    dual_quaternion_from_pair,
    dual_quaternion_from_rotation_translation,
    dual_quaternion_from_screw,
    dual_quaternion_from_transform,
    dual_quaternion_identity,
    dual_quaternion_inverse,
    dual_quaternion_norm,
    dual_quaternion_normalize,
    dual_quaternion_power,
    dual_quaternion_product,
    pair_from_dual_quaternion,
    pair_product,
    rotation_translation_from_dual_quaternion,
    sclerp,
    screw_from_dual_quaternion,
    transform_from_dual_quaternion,
)
from .quaternion import (  # noqa: E402
    Quaternion,
    axis_angle_from_quaternion,
    matrix_from_quaternion,
    pyquaternion_from_quaternion,
    quaternion_conjugate,
    quaternion_distance,
    quaternion_exp,
    quaternion_from_axis_angle,
    quaternion_from_matrix,
    quaternion_from_pyquaternion,
    quaternion_inverse,
    quaternion_log,
    quaternion_norm,
    quaternion_normalize,
    quaternion_power,
    quaternion_product,
    rotate_vector,
    slerp,
)
from .rotations import (  # noqa: E402
    matrix_from_axis_angle,
    matrix_from_rpy,
    rot_x,
    rot_y,
    rot_z,
)
from .transforms import (  # noqa: E402
    apply_to_vectors,
    apply_transform,
    compose,
    transform_from,
    transform_inverse,
)

__all__ = [
    # quaternion.py
    "Quaternion", "axis_angle_from_quaternion", "matrix_from_quaternion",
    "pyquaternion_from_quaternion", "quaternion_conjugate", "quaternion_distance",
    "quaternion_exp", "quaternion_from_axis_angle", "quaternion_from_matrix",
    "quaternion_from_pyquaternion", "quaternion_inverse", "quaternion_log", "quaternion_norm",
    "quaternion_normalize", "quaternion_power", "quaternion_product", "rotate_vector", "slerp",
    # rotations.py
    "matrix_from_axis_angle", "matrix_from_rpy", "rot_x", "rot_y", "rot_z",
    # transforms.py
    "apply_to_vectors", "apply_transform", "compose", "transform_from", "transform_inverse",
    # dualquat.py
    "DualQuaternion", "dual_quaternion_apply", "dual_quaternion_apply_line",
    "dual_quaternion_combined_conjugate", "dual_quaternion_conjugate",
    "dual_quaternion_dual_conjugate", "dual_quaternion_from_pair",
    "dual_quaternion_from_rotation_translation", "dual_quaternion_from_screw",
    "dual_quaternion_from_transform", "dual_quaternion_identity", "dual_quaternion_inverse",
    "dual_quaternion_norm", "dual_quaternion_normalize", "dual_quaternion_power",
    "dual_quaternion_product", "pair_from_dual_quaternion", "pair_product",
    "rotation_translation_from_dual_quaternion", "sclerp", "screw_from_dual_quaternion",
    "transform_from_dual_quaternion",
]

# Sub-packages reached as attributes (``dqlab.models.ur3()``) are imported on first use, so
# that ``import dqlab`` stays light.
_SUBMODULES = {
    "complex", "rotations", "quaternion", "transforms", "dualquat", "robot", "models",
    "jacobian", "ik", "trajectory", "identify", "pick_place", "viz", "ur", "sim",
    "inertia", "dynamics",
}


def __getattr__(name):
    if name in _SUBMODULES:
        try:
            return importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":   # the module exists, a dependency is absent
                raise
    raise AttributeError(f"module 'dqlab' has no attribute {name!r}")
