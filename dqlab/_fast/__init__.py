"""The speed twins: the machinery that makes a readable path of dqlab fast, each module tested
equal to the path it speeds up and reached only through that path's module (its front).

- ``chain``: forward kinematics, Jacobian and screws of a chain from constant factors, for
  :class:`dqlab.robot.Robot`;
- ``ur_engine``: the UR closed form of :mod:`dqlab.ik.ur_steps`, on Python floats for one
  pose and in blocks for a batch, for :mod:`dqlab.ik.ur_closed_form`;
- ``calibrated_matrices``, ``calibrated_entries`` (numpy) and ``newton_compiled`` (over the
  generated ``newton_lanes``): the Newton kernels of :mod:`dqlab.ik.ur_calibrated`, whose
  readable path is :mod:`dqlab.ik.ur_calibrated_reference`;
- ``dynamics_floats``, ``dynamics_compiled``: the recursions of :mod:`dqlab.dynamics` on
  floats and compiled;
- ``compiled``: the switch of the compiled paths (the ``DQLAB_COMPILED`` environment
  variable) and their compiler.
"""
