"""Trajectories: time laws, joint-space motions, Cartesian paths and path following.

- :mod:`~dqlab.trajectory.time_laws` -- cubic, quintic, trapezoidal and the UR3 report's
  three-phase law, as :class:`TimeLaw` objects (chapter 10);
- :mod:`~dqlab.trajectory.joint` -- the :class:`Trajectory` type with CSV files,
  synchronised point-to-point motions and via-points (chapter 10);
- :mod:`~dqlab.trajectory.cartesian` -- straight line + SLERP, screw motions (ScLERP) and
  the report's circle, as :class:`CartesianPath` objects (chapter 11);
- :mod:`~dqlab.trajectory.follow` -- following a path with the closed-form UR solver and
  branch tracking, or with the report's warm-started numerical IK (chapter 11).
"""

from .cartesian import CartesianPath, circle_three_phase, line_slerp, screw_path
from .follow import (
    BranchSwitch,
    FollowReport,
    SingularPass,
    follow_path_numerical,
    follow_path_ur,
    joint_velocities,
    singular_passes,
    track_branches,
    ur_singularity_margins,
)
from .joint import Trajectory, joint_trajectory, via_points
from .time_laws import TimeLaw, cubic, quintic, three_phase, time_grid, trapezoidal

__all__ = [
    "TimeLaw", "cubic", "quintic", "trapezoidal", "three_phase", "time_grid",
    "Trajectory", "joint_trajectory", "via_points",
    "CartesianPath", "line_slerp", "screw_path", "circle_three_phase",
    "BranchSwitch", "FollowReport", "SingularPass", "follow_path_ur", "follow_path_numerical",
    "joint_velocities", "singular_passes", "track_branches", "ur_singularity_margins",
]
