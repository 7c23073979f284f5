"""Programming a Universal Robots arm: UR pose vectors, pose files, URScript, a client.

In :mod:`dqlab.ur` a **pose** is always UR's 6-vector ``[x, y, z, rx, ry, rz]``: the position
of the TCP in metres and its orientation as a rotation vector (axis times angle) in radians,
in the controller's base frame -- DH frame 0 of the robot, which ``robot.base`` places in the
world (see :mod:`dqlab.ur.motion` for the frames, and ROS's ``base`` and ``base_link``).
Transforms, quaternions and dual quaternions convert to and from it
(:mod:`dqlab.ur.poses`).

Layers (each uses only those above it): :mod:`~dqlab.ur.poses` (UR pose vectors and
rotation vectors), :mod:`~dqlab.ur.files` (pose files), :mod:`~dqlab.ur.motion` (how the
controller executes each command: the one planner), :mod:`~dqlab.ur.script` (URScript with
safety checks on the planned motions), :mod:`~dqlab.ur.rtde` (the RTDE state protocol),
:mod:`~dqlab.ur.state` (what a controller reports, checked), :mod:`~dqlab.ur.client` (a
client with interchangeable back ends), the back ends :mod:`~dqlab.ur.kinematic_arm` (an arm
in this process), :mod:`~dqlab.ur.secondary` (a controller's secondary interface) and
:mod:`~dqlab.ur.rtde_backend` (``ur_rtde``), and :mod:`~dqlab.ur.standin` (a local stand-in
for a UR controller, for tests and the book).
"""

from .client import Backend, URClient
from .files import PoseFile, PoseFileError, append_pose, read_poses, write_poses
from .kinematic_arm import KinematicBackend, StepClock
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
from .rtde_backend import RTDEBackend
from .script import (
    SafetyLimits,
    UnsafeTargetError,
    movej,
    movel,
    program_from_trajectory,
    servoj,
    stopj,
)
from .secondary import SecondaryInterfaceBackend
from .standin import ControllerStandIn
from .state import HOME, ROBOT_MODE_RUNNING, ControllerError, URState

__all__ = [
    "check_pose", "dual_quaternion_from_pose", "matrix_from_rotation_vector",
    "pose_from_dual_quaternion", "pose_from_transform", "quaternion_from_rotation_vector",
    "rotation_vector_from_matrix", "rotation_vector_from_quaternion",
    "rotation_vector_from_rpy", "rpy_from_rotation_vector", "transform_from_pose",
    "PoseFile", "PoseFileError", "append_pose", "read_poses", "write_poses",
    "SafetyLimits", "UnsafeTargetError", "movej", "movel", "program_from_trajectory",
    "servoj", "stopj",
    "Backend", "HOME", "ROBOT_MODE_RUNNING", "URState", "ControllerError", "URClient",
    "KinematicBackend", "StepClock", "SecondaryInterfaceBackend", "RTDEBackend",
    "ControllerStandIn",
]
