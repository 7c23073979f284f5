"""Physics simulation of a dqlab robot with MuJoCo (the optional extra ``sim``)."""

from .mjcf import UR3_BASE_MASS, UR3_LINK_MASSES, UR3_PAYLOAD, link_placements, mjcf_from_robot

__all__ = ["mjcf_from_robot", "link_placements", "UR3_LINK_MASSES", "UR3_PAYLOAD",
           "UR3_BASE_MASS"]
