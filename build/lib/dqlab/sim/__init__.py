"""Physics simulation of a dqlab robot with MuJoCo (the optional extra ``sim``).

- :func:`~dqlab.sim.mjcf.mjcf_from_robot` writes a MuJoCo model of any
  :class:`~dqlab.robot.Robot` (standard or modified DH, base and tool); its flange site's
  pose is ``robot.fk(q)``.
- :func:`~dqlab.sim.urdf.urdf_from_robot` writes the same chain as URDF, for simulators
  that read it.
- :class:`~dqlab.sim.simulation.ArmSimulation` loads the model and steps it under joint
  torques; :class:`~dqlab.sim.simulation.JointPD` and
  :class:`~dqlab.sim.simulation.ComputedTorque` compute those torques;
  :func:`~dqlab.sim.simulation.track` runs one of them along a joint trajectory and
  returns a :class:`~dqlab.sim.simulation.TrackingResult` of arrays.
- :class:`~dqlab.sim.backend.MujocoBackend` is the simulated arm behind the UR client:
  ``movej``, ``movel``, ``servoj`` and ``stop`` executed in physics.

Generating the models needs only numpy; simulating them needs ``mujoco``
(``pip install 'dqlab[sim]'``).
"""

from .backend import UR3_HOME, MujocoBackend
from .mjcf import (
    UR3_BASE_MASS,
    UR3_LINK_MASSES,
    UR3_PAYLOAD,
    default_masses,
    link_placements,
    mjcf_from_robot,
    robot_inertias,
)
from .simulation import (
    ArmSimulation,
    ComputedTorque,
    DynamicsModel,
    JointPD,
    TrackingResult,
    check_trajectory,
    require_mujoco,
    track,
)
from .urdf import urdf_from_robot

__all__ = [
    "mjcf_from_robot", "urdf_from_robot", "link_placements", "default_masses", "robot_inertias",
    "UR3_LINK_MASSES", "UR3_PAYLOAD", "UR3_BASE_MASS",
    "ArmSimulation", "JointPD", "ComputedTorque", "DynamicsModel", "TrackingResult", "track",
    "check_trajectory", "require_mujoco", "MujocoBackend", "UR3_HOME",
]
