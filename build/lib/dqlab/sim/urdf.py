r"""A URDF description generated from a :class:`~dqlab.robot.Robot`, for other simulators.

The same body placements as the MJCF model (:func:`~dqlab.sim.mjcf.link_placements`):
joint ``joint{i}`` has its parent link ``link{i-1}`` (``base`` for the first) and its child
``link{i}`` at the origin :math:`X_{B_{i-1}B_i}`, written as URDF's ``xyz`` and ``rpy``
(roll, pitch, yaw about fixed axes, :math:`R = R_z(\text{yaw})\,R_y(\text{pitch})\,
R_x(\text{roll})`, Craig's convention of :func:`dqlab.rotations.rpy_from_matrix`), and its
axis along the child's z. A root link ``world`` holds the base at :math:`X_{W0}` and a link
``flange`` sits at the TCP. URDF carries the kinematics and the robot's link inertias here (no
shapes): enough for forward kinematics and dynamics in a simulator that reads URDF, such as
PyBullet.
"""

import math
from xml.sax.saxutils import quoteattr

import numpy as np

from ..rotations import rpy_from_matrix
from .mjcf import default_masses, link_placements, robot_inertias, xml_number, xml_vector

__all__ = ["urdf_from_robot"]


def _origin(X):
    return f'<origin xyz="{xml_vector(X[:3, 3])}" rpy="{xml_vector(rpy_from_matrix(X[:3, :3]))}"/>'


def urdf_from_robot(robot, *, masses=None, name=None):
    r"""The URDF text of ``robot``: one link and one joint per DH link, and a ``flange`` link.

    Parameters
    ----------
    robot : Robot
        Standard or modified DH, with its base and tool.
    masses : array_like, shape (n,), optional
        Link masses in kg, to override the robot's (as in
        :func:`~dqlab.sim.mjcf.mjcf_from_robot`: each link's inertia scaled to its mass).
        Each link's ``<inertial>`` is the robot's (:func:`~dqlab.sim.mjcf.robot_inertias`),
        moved from its DH frame into the URDF link frame.
    name : str, optional
        The robot's name in the file (default: the robot's).

    Returns
    -------
    str

    Examples
    --------
    >>> from dqlab.models import scara_rsm5
    >>> urdf = urdf_from_robot(scara_rsm5())
    >>> urdf.count('<joint name="joint'), 'type="prismatic"' in urdf
    (4, True)
    """
    placements, X_BnT, corners = link_placements(robot)
    masses = default_masses(robot) if masses is None else np.asarray(masses, dtype=float)
    if masses.shape != (robot.n,) or not np.isfinite(masses).all() or (masses <= 0).any():
        raise ValueError(f"masses must be {robot.n} positive finite numbers, got {masses!r}")
    inertias = [inertia.scaled(m / inertia.mass) if inertia.mass > 0 else inertia
                for inertia, m in zip(robot_inertias(robot), masses, strict=True)]
    label = quoteattr(name if name is not None else (robot.name or "robot"))
    lines = ['<?xml version="1.0"?>', f"<robot name={label}>", '  <link name="world"/>',
             '  <link name="base"/>',
             '  <joint name="base_joint" type="fixed">',
             f"    {_origin(robot.base)}",
             '    <parent link="world"/>', '    <child link="base"/>', "  </joint>"]
    parent = "base"
    for i, (link, X) in enumerate(zip(robot.links, placements, strict=True), start=1):
        body = inertias[i - 1].moved(corners[i])        # from DH frame i to the link frame
        I = body.tensor
        lines += [f'  <link name="link{i}">', "    <inertial>",
                  f'      <origin xyz="{xml_vector(body.com)}" rpy="0 0 0"/>',
                  f'      <mass value="{xml_number(body.mass)}"/>',
                  f'      <inertia ixx="{xml_number(I[0, 0])}" ixy="{xml_number(I[0, 1])}" '
                  f'ixz="{xml_number(I[0, 2])}" iyy="{xml_number(I[1, 1])}" '
                  f'iyz="{xml_number(I[1, 2])}" izz="{xml_number(I[2, 2])}"/>',
                  "    </inertial>", "  </link>"]
        lo, hi = link.limits
        bounded = math.isfinite(lo) and math.isfinite(hi)
        kind = "prismatic" if not link.is_revolute else ("revolute" if bounded
                                                         else "continuous")
        lines += [f'  <joint name="joint{i}" type="{kind}">', f"    {_origin(X)}",
                  f'    <parent link="{parent}"/>', f'    <child link="link{i}"/>',
                  '    <axis xyz="0 0 1"/>']
        if kind != "continuous":
            lo, hi = (lo, hi) if bounded else (-1e3, 1e3)
            lines.append(f'    <limit lower="{xml_number(lo)}" upper="{xml_number(hi)}" '
                         'effort="1000" velocity="10"/>')
        lines.append("  </joint>")
        parent = f"link{i}"
    lines += ['  <link name="flange"/>', '  <joint name="flange_joint" type="fixed">',
              f"    {_origin(X_BnT)}", f'    <parent link="{parent}"/>',
              '    <child link="flange"/>', "  </joint>", "</robot>", ""]
    return "\n".join(lines)
