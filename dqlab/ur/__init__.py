"""Programming a Universal Robots arm: UR pose vectors, pose files, URScript, a client."""

from .client import ROBOT_MODE_RUNNING, Backend, URState

__all__ = ["Backend", "ROBOT_MODE_RUNNING", "URState"]
