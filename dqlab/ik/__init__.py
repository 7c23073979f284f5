r"""Inverse kinematics: closed-form solvers and a numerical solver, one contract for all.

Every solver is called ``solver(robot, target, *, tol, ...)`` and returns an
:class:`~dqlab.ik.result.IKResult` (the numerical solver also takes its start ``q0``):

- ``dqlab.ik.ur`` (:func:`dqlab.ik.ur_solver.ur`) -- every solution of a UR-family arm:
  of the exact UR shape in closed form, by dual quaternions
  (:func:`dqlab.ik.ur_closed_form.exact_ur`; its steps, and their assembly into the eight
  rows as chapter 8 derives them, are :mod:`dqlab.ik.ur_steps`), of a calibrated UR from
  the closed form of its nearest exact arm (:func:`dqlab.ik.ur_calibrated.calibrated_ur`);
- ``dqlab.ik.desk_arm`` (:func:`dqlab.ik.desk_arm_closed_form.desk_arm`) -- the 3-DOF
  desktop arm in closed form (the robot itself is :func:`dqlab.models.desk_arm`);
- ``dqlab.ik.scara`` (:func:`dqlab.ik.scara_closed_form.scara`) -- the SCARA RSM-5 in
  closed form;
- ``dqlab.ik.numerical`` (:func:`dqlab.ik.damped_least_squares.numerical`) -- damped least
  squares, position-only or full pose, for any chain.

What they share lives in a few small modules: :mod:`dqlab.ik.targets` parses and checks
the targets once (:func:`~dqlab.ik.targets.parse_targets`) and measures the errors of a pose
(:func:`~dqlab.ik.targets.pose_errors`); :mod:`dqlab.ik.result` holds the result type and
how a solver finishes it (:func:`~dqlab.ik.result.finish`,
:func:`~dqlab.ik.result.target_reasons`; the UR solvers' options are checked by
:func:`~dqlab.ik.result.check_ur_options`); :mod:`dqlab.ik.two_link` solves the planar
two-link arm. A closed-form solver checks the robot against its
:class:`dqlab.models.ChainShape`. A new closed-form solver is one new module built from
these pieces.

Helpers for the UR solutions: ``SOLUTION_ORDER`` (the meaning of the eight rows),
``ur_branch`` (the row of a joint vector), ``ur_parameters`` and ``distinct_solutions``.
For any solver, :mod:`dqlab.ik.solutions` picks
the solution to send a robot: ``closest_solution`` (the valid solution nearest a
configuration, as its :math:`2\pi`-equivalent within the joint limits) and
``equivalent_solutions`` (every such equivalent). ``closest_ur_solution`` answers the
common question in one call: the joints to send a UR (with its tool, within its limits) to
reach a pose from where it stands.
"""

from .damped_least_squares import numerical
from .desk_arm_closed_form import desk_arm
from .result import IKResult
from .scara_closed_form import scara
from .solutions import closest_solution, equivalent_solutions
from .targets import pose_errors
from .ur_closed_form import SOLUTION_ORDER, distinct_solutions, ur_parameters
from .ur_solver import closest_ur_solution, ur, ur_branch

__all__ = [
    "IKResult", "SOLUTION_ORDER", "closest_solution", "closest_ur_solution", "desk_arm",
    "distinct_solutions", "equivalent_solutions", "numerical", "pose_errors", "scara", "ur",
    "ur_branch", "ur_parameters",
]
