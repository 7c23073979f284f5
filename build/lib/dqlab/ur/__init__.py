"""Programming a Universal Robots arm: UR pose vectors, pose files, URScript, a client.

Layers (each uses only those above it): :mod:`~dqlab.ur.poses` (UR pose vectors and
rotation vectors), :mod:`~dqlab.ur.files` (pose files), :mod:`~dqlab.ur.script` (URScript
with safety checks), :mod:`~dqlab.ur.rtde` (the RTDE state protocol),
:mod:`~dqlab.ur.client` (a client with interchangeable back ends) and
:mod:`~dqlab.ur.standin` (a local stand-in for a UR controller, for tests and the book).
"""

from .client import (
    HOME,
    ROBOT_MODE_RUNNING,
    Backend,
    KinematicBackend,
    RTDEBackend,
    SecondaryInterfaceBackend,
    StepClock,
    URClient,
    URState,
)
from .files import PoseFile, PoseFileError, append_pose, read_poses, write_poses
from .poses import (
    check_pose,
    dual_quaternion_from_pose,
    matrix_from_rotation_vector,
    pose_from_dual_quaternion,
    pose_from_transform,
    quaternion_from_rotation_vector,
    rotation_vector_from_matrix,
    rotation_vector_from_quaternion,
    rotation_vector_from_rpy,
    rpy_from_rotation_vector,
    transform_from_pose,
)
from .script import (
    SafetyLimits,
    UnsafeTargetError,
    movej,
    movel,
    program_from_trajectory,
    servoj,
    stopj,
)
from .standin import ControllerStandIn

__all__ = [
    "check_pose", "dual_quaternion_from_pose", "matrix_from_rotation_vector",
    "pose_from_dual_quaternion", "pose_from_transform", "quaternion_from_rotation_vector",
    "rotation_vector_from_matrix", "rotation_vector_from_quaternion",
    "rotation_vector_from_rpy", "rpy_from_rotation_vector", "transform_from_pose",
    "PoseFile", "PoseFileError", "append_pose", "read_poses", "write_poses",
    "SafetyLimits", "UnsafeTargetError", "movej", "movel", "program_from_trajectory",
    "servoj", "stopj",
    "Backend", "HOME", "ROBOT_MODE_RUNNING", "URState", "URClient", "KinematicBackend",
    "StepClock", "SecondaryInterfaceBackend", "RTDEBackend", "ControllerStandIn",
]
