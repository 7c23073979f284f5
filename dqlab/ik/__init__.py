"""Inverse kinematics: closed-form solvers and a numerical solver, one result type for all.

- :func:`dqlab.ik.ur.ur` -- every closed-form solution of a UR-family arm, by dual
  quaternions;
- :func:`dqlab.ik.numerical.numerical` -- damped least squares, position-only or full pose;
- :func:`dqlab.ik.arm3.desk_arm` -- the 3-DOF desktop arm in closed form;
- :func:`dqlab.ik.scara.scara` -- the SCARA RSM-5 in closed form.

Each returns an :class:`dqlab.ik.result.IKResult`. They are reached as ``dqlab.ik.ur``,
``dqlab.ik.numerical``, ``dqlab.ik.desk_arm`` and ``dqlab.ik.scara``, together with the
helpers for the UR solutions: ``SOLUTION_ORDER`` (the meaning of the eight rows),
``distinct_solutions``, ``equivalent_solutions`` (the 2 pi-equivalents within the joint
limits) and ``closest_solution``.
"""

from .arm3 import desk_arm
from .numerical import numerical
from .result import IKResult
from .scara import scara
from .ur import (
    SOLUTION_ORDER,
    closest_solution,
    distinct_solutions,
    equivalent_solutions,
    ur,
)

__all__ = [
    "IKResult", "SOLUTION_ORDER", "closest_solution", "desk_arm", "distinct_solutions",
    "equivalent_solutions", "numerical", "scara", "ur",
]
