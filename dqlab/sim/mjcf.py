r"""An MJCF model (MuJoCo's XML) generated from a :class:`~dqlab.robot.Robot`.

A link of either Denavit--Hartenberg convention is a constant transform, the joint's motion
along or about its own z axis, and another constant transform (see :mod:`dqlab.robot`):

.. math::

   X_{i-1,i}(q_i) = L_i\, R_z(\theta^0_i)\, T_z(d^0_i)\; J_i(q_i)\; R_i,
   \qquad J_i(q_i) = R_z(q_i) \text{ (revolute) or } T_z(q_i) \text{ (prismatic)},

with :math:`L_i = I,\ R_i = T_x(a_i) R_x(\alpha_i)` in standard DH and
:math:`L_i = R_x(\alpha_{i-1}) T_x(a_{i-1}),\ R_i = I` in modified DH. (The constant turn
:math:`R_z(\theta^0_i)` and shift :math:`T_z(d^0_i)` commute with :math:`J_i`, so they can be
taken out of it.) MuJoCo places a body in its parent by a constant position and unit
quaternion and then applies the body's joint *after* that placement, about or along an axis
through the body's origin. So body :math:`i` sits in body :math:`i-1` at

.. math::

   X_{B_{i-1} B_i} = R_{i-1}\, L_i\, R_z(\theta^0_i)\, T_z(d^0_i),

where body 0 is the fixed base, placed at :math:`X_{W0}` in the world (and :math:`R_0 = I`).
Each body carries a hinge (revolute) or slide (prismatic) joint along its own z axis, with
``qpos`` equal to dqlab's joint value :math:`q_i` (the offsets are in the placement). The
flange site sits in the last body at :math:`R_n X_{nT}` (the tool, when the robot has one).
Then the site's pose is :math:`X_{WT}(q)` of :meth:`~dqlab.robot.Robot.fk` exactly, up to
rounding: the tests check 1,000 random configurations of three robots to 1e-9.

The bodies are drawn as a joint housing (a short cylinder about the joint axis) and capsules
along the path to the next joint. They are weighed by the robot's own inertial parameters
(``Link.inertia``, :class:`~dqlab.inertia.LinkInertia`, the one source of them that
:mod:`dqlab.dynamics` reads too): link :math:`i`'s centre of mass :math:`\mathbf c` and
inertia tensor :math:`I_c`, given in its DH frame :math:`i = B_i R_i`, are written into body
:math:`i` as an ``<inertial>`` element at :math:`R_i \mathbf c` with the tensor
:math:`R\, I_c R^\top` (:math:`R` the rotation of :math:`R_i`). A link without inertial
parameters gets :func:`dqlab.models.rod_link_inertias`' plausible ones. Collisions are off
(the simulation is about tracking, not contact). This module only writes text: MuJoCo is
needed to load the model, not to generate it.
"""

import math
from xml.sax.saxutils import quoteattr

import numpy as np

from .._checks import check_instance, check_scalar, check_text
from ..models import UR_DYNAMICS, rod_link_inertias
from ..quaternion import quaternion_from_matrix
from ..robot import Robot
from ._checks import per_joint

__all__ = ["mjcf_from_robot", "link_placements", "default_masses", "robot_inertias",
           "UR3_LINK_MASSES", "UR3_PAYLOAD", "UR3_BASE_MASS", "MIN_MASS", "MIN_INERTIA",
           "MIN_RADIUS", "MAX_RADIUS", "MIN_TIMESTEP", "MAX_TIMESTEP"]

#: Masses of the UR3's six moving links in kg, from Universal Robots' table of dynamic
#: parameters (the ``ur_dh`` reference; :data:`dqlab.models.UR_DYNAMICS`, which
#: :func:`dqlab.models.ur3` gives its links). Their sum, 8.63 kg, plus the base housing and
#: the cable make the data sheet's 11 kg.
UR3_LINK_MASSES = tuple(UR_DYNAMICS["UR3"]["mass"])
#: The UR3's rated payload in kg (thesis, annex A: the maker's data sheet).
UR3_PAYLOAD = 3.0
#: Mass of the fixed base housing in kg: the data sheet's 11 kg minus the moving links (it
#: carries the cable's share too). Fixed to the world, it never enters the dynamics.
UR3_BASE_MASS = 11.0 - sum(UR3_LINK_MASSES)

#: The lightest link mass accepted, kg (MuJoCo refuses a moving body whose mass or inertia
#: is below its ``mjMINVAL``, 1e-15).
MIN_MASS = 1e-6
#: The smallest principal moment of inertia of a link accepted, kg m^2: MuJoCo refuses an
#: inertia tensor whose smallest eigenvalue is below its ``mjEPS``, 1e-14 ("inertia must
#: have positive eigenvalues"); the factor 100 covers the rounding of its own eigenvalue
#: computation. A point mass (:meth:`~dqlab.inertia.LinkInertia.sphere` of radius 0) or a
#: thin rod has a zero moment and is refused: a body MuJoCo moves must have extent.
MIN_INERTIA = 1e-12
#: The smallest radius of the drawn links, metres.
MIN_RADIUS = 1e-3
#: The largest radius of the drawn links, metres.
MAX_RADIUS = 1.0
#: The shortest simulation time step, seconds.
MIN_TIMESTEP = 1e-9
#: The longest simulation time step, seconds.
MAX_TIMESTEP = 1.0

_LINK_COLOR = "0.62 0.66 0.72 1"
_HOUSING_COLOR = "0.20 0.45 0.75 1"
_PAYLOAD_COLOR = "0.85 0.45 0.15 1"


def _rot_z(theta):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _rot_x(alpha):
    c, s = math.cos(alpha), math.sin(alpha)
    return np.array([[1.0, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]])


def _shift(axis, length):
    X = np.eye(4)
    X[axis, 3] = length
    return X


def link_placements(robot):
    r"""The constant parts of a chain, as a MuJoCo body tree needs them.

    Parameters
    ----------
    robot : Robot

    Returns
    -------
    placements : ndarray, shape (n, 4, 4)
        :math:`X_{B_{i-1} B_i} = R_{i-1} L_i R_z(\theta^0_i) T_z(d^0_i)`, the pose of body
        :math:`i` in body :math:`i-1`; body 0 is the fixed base, placed at :math:`X_{W0}` in
        the world (so :math:`R_0 = I` here).
    X_BnT : ndarray, shape (4, 4)
        :math:`R_n X_{nT}`, the pose of the tool centre point in the last body.
    corners : list of ndarray, shape (n + 1, 4, 4)
        :math:`R_{i}` for body :math:`i` (:math:`R_0 = I`): where the link's own constant
        motion ends, a corner of the drawn path.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> placements, X_BnT, _ = link_placements(ur3())
    >>> placements[0][:3, 3]                 # body 1 at the shoulder height d1
    array([0.    , 0.    , 0.1519])
    >>> np.allclose(X_BnT, np.eye(4))       # no tool: the TCP is body 6's origin
    True
    """
    check_instance(robot, Robot, "robot")
    corners = [np.eye(4)]
    lefts = []
    for link in robot.links:
        if robot.convention == "dh":
            lefts.append(np.eye(4))
            corners.append(_shift(0, link.a) @ _rot_x(link.alpha))
        else:
            lefts.append(_rot_x(link.alpha) @ _shift(0, link.a))
            corners.append(np.eye(4))
    # theta_offset and d are the constant turn and shift for both joint types (a prismatic
    # link's theta_offset is its fixed angle, its d the constant added to q)
    placements = np.array([corners[i] @ lefts[i] @ _rot_z(link.theta_offset)
                           @ _shift(2, link.d) for i, link in enumerate(robot.links)])
    return placements, corners[-1] @ robot.tool, corners


def xml_number(x):
    """A float as MJCF text: the shortest repr that reads back exactly; rounding noise of
    the constant products below 1e-15 (for instance 5e-18 m left by a quarter turn) is
    written as 0."""
    x = float(x)
    return "0" if abs(x) < 1e-15 else repr(x)


def xml_vector(v):
    """A vector as MJCF/URDF text: its entries written by :func:`xml_number`, space-separated."""
    return " ".join(xml_number(x) for x in v)


def _pos_quat(X):
    """MJCF ``pos`` and ``quat`` (MuJoCo's order is also w, x, y, z) of a 4x4 transform."""
    quat = quaternion_from_matrix(X[:3, :3])
    return f'pos="{xml_vector(X[:3, 3])}" quat="{xml_vector(quat)}"'


def _segments(points, eps=1e-4):
    """Consecutive pairs of points along a polyline, without the pieces shorter than
    ``eps`` metres (too short to draw; MuJoCo refuses a capsule of a few micrometres)."""
    out = []
    for a, b in zip(points[:-1], points[1:], strict=True):
        if np.linalg.norm(b - a) > eps:
            out.append((a, b))
    return out


def _is_ur3(robot):
    return robot.n == 6 and robot.name.upper().startswith("UR3")


def _link_paths(placements, X_BnT, corners):
    """The drawn path of body i: its origin -> its corner R_i -> the next body's origin."""
    n = len(placements)
    paths = []
    for i in range(n):
        nxt = placements[i + 1] if i + 1 < n else X_BnT
        paths.append(_segments([np.zeros(3), corners[i + 1][:3, 3], nxt[:3, 3]]))
    return paths


def robot_inertias(robot):
    """The robot's link inertias (``Link.inertia``); a link without them gets the plausible
    ones of :func:`dqlab.models.rod_link_inertias` (0.5 kg plus 4 kg per metre of its path,
    a uniform rod).

    Returns
    -------
    tuple of LinkInertia
        In the links' DH frames.

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> robot_inertias(ur3())[1].mass
    3.42
    """
    if not isinstance(robot, Robot):
        raise TypeError(f"robot must be a dqlab Robot, got {type(robot).__name__}")
    guessed = None
    inertias = []
    for i, link in enumerate(robot.links):
        if link.inertia is None:
            guessed = rod_link_inertias(robot) if guessed is None else guessed
            inertias.append(guessed[i])
        else:
            inertias.append(link.inertia)
    return tuple(inertias)


def default_masses(robot):
    """Link masses in kg when none are given: those of :func:`robot_inertias`.

    Examples
    --------
    >>> from dqlab.models import desk_arm, ur3
    >>> default_masses(desk_arm()).round(3)
    array([0.768, 1.076, 1.148])
    >>> default_masses(ur3())
    array([2.  , 3.42, 1.26, 0.8 , 0.8 , 0.35])
    """
    check_instance(robot, Robot, "robot")
    return np.array([inertia.mass for inertia in robot_inertias(robot)])


def mjcf_from_robot(robot, *, masses=None, payload=0.0, radius=None, damping=0.1,
                    armature=0.01, timestep=0.001, integrator="implicitfast", gravity=9.81,
                    base_mass=None, name=None):
    r"""The MJCF text of a MuJoCo model of ``robot``: one body and one joint per link.

    Body :math:`i` is placed in body :math:`i-1` at
    :math:`X_{B_{i-1}B_i} = R_{i-1} L_i R_z(\theta^0_i) T_z(d^0_i)` (see the module
    docstring), carries a ``hinge`` (revolute) or ``slide`` (prismatic) joint ``joint{i}``
    along its z axis with ``qpos`` :math:`= q_i`, and a torque (or force) motor
    ``motor{i}``. A site named ``flange`` marks the robot's TCP, :math:`R_n X_{nT}` in the
    last body, so that its pose in the world is :math:`X_{WT}(q)` of
    :meth:`~dqlab.robot.Robot.fk`. A second body ``payload`` (no joint, welded to the last
    link at the TCP) carries the payload, so that a simulation can change it.

    Parameters
    ----------
    robot : Robot
        Standard or modified DH, with its base and tool.
    masses : array_like, shape (n,), optional
        Link masses in kg, to override the robot's: each link's inertia
        (:func:`robot_inertias`) is scaled to the given mass, its centre of mass kept.
        Default: the robot's own (UR's values for the UR3).
    payload : float, optional
        Mass in kg of a sphere at the TCP (0 by default; the UR3 is rated for 3 kg).
    radius : float, optional
        Radius of the drawn links in metres. Default: 5 % of the sum of the link lengths,
        between 0.01 and 0.05 m.
    damping, armature : float or array_like, shape (n,), optional
        Joint viscous damping (N m s/rad) and armature, the reflected rotor inertia that
        MuJoCo adds to the diagonal of the mass matrix (kg m^2).
    timestep : float, optional
        Simulation step in seconds, written exactly.
    integrator : {"implicitfast", "implicit", "RK4", "Euler"}, optional
        ``implicitfast`` (default) treats damping implicitly, the choice for stiff joints.
    gravity : float, optional
        Acceleration of gravity along the world's -z in m/s^2 (0 to switch it off).
    base_mass : float, optional
        Mass of the fixed base housing (drawn only; it does not move). Default:
        :data:`UR3_BASE_MASS` for the UR3, otherwise 1 kg.
    name : str, optional
        The model's name (default: the robot's).

    Returns
    -------
    str
        The MJCF document.

    Raises
    ------
    TypeError
        If ``robot`` is not a :class:`~dqlab.robot.Robot`.
    ValueError
        If a mass, radius, damping, armature or time step is negative, not finite, of the
        wrong length or outside its range (a link mass below :data:`MIN_MASS`, a radius
        outside [:data:`MIN_RADIUS`, :data:`MAX_RADIUS`], a time step outside
        [:data:`MIN_TIMESTEP`, :data:`MAX_TIMESTEP`]: MuJoCo refuses bodies too light for
        it, and a step it would write as 0 or take as the whole motion simulates nothing),
        a link's inertia has a mass below :data:`MIN_MASS` or a principal moment below
        :data:`MIN_INERTIA` (a point mass: MuJoCo refuses it), the model's name is not one
        line of text (XML cannot hold a control character), or the integrator is unknown.

    See Also
    --------
    dqlab.sim.simulation.ArmSimulation : loads the model and steps it.

    Examples
    --------
    >>> from dqlab.models import ur3
    >>> xml = mjcf_from_robot(ur3())
    >>> xml.count("<joint "), xml.count('<site name="flange"')
    (6, 1)
    >>> 'type="hinge"' in xml and 'integrator="implicitfast"' in xml
    True
    """
    placements, X_BnT, corners = link_placements(robot)
    n = robot.n
    links = robot.links
    paths = _link_paths(placements, X_BnT, corners)
    base_path = _segments([np.zeros(3), placements[0][:3, 3]])
    total_length = sum(np.linalg.norm(b - a) for path in paths for a, b in path)
    total_length += sum(np.linalg.norm(b - a) for a, b in base_path)
    is_ur3 = _is_ur3(robot)
    if radius is None:
        radius = min(max(0.05 * total_length, 0.01), 0.05)
    radius = check_scalar(radius, "radius", minimum=MIN_RADIUS, maximum=MAX_RADIUS)
    inertias = robot_inertias(robot)
    if masses is not None:
        masses = per_joint(masses, n, "masses", positive=True, minimum=MIN_MASS)
        inertias = [inertia.scaled(m / inertia.mass) if inertia.mass > 0
                    else type(inertia).sphere(m, inertia.com)
                    for inertia, m in zip(inertias, masses, strict=True)]
    for i, inertia in enumerate(inertias):
        _check_moving_body(inertia, corners[i + 1], i, masses is not None)
    damping = per_joint(damping, n, "damping", positive=False)
    armature = per_joint(armature, n, "armature", positive=False)
    payload = check_scalar(payload, "payload", minimum=0)
    timestep = check_scalar(timestep, "timestep", minimum=MIN_TIMESTEP, maximum=MAX_TIMESTEP)
    gravity = check_scalar(gravity, "gravity", minimum=0)
    if base_mass is None:
        base_mass = UR3_BASE_MASS if is_ur3 else 1.0
    base_mass = check_scalar(base_mass, "base_mass", minimum=0, strict=True)
    if not isinstance(integrator, str) or integrator not in (
            "implicitfast", "implicit", "RK4", "Euler"):
        raise ValueError("integrator must be 'implicitfast', 'implicit', 'RK4' or 'Euler', "
                         f"got {integrator!r}")
    model_name = quoteattr(model_name_of(robot, name))

    lines = [
        f"<mujoco model={model_name}>",
        '  <compiler angle="radian" autolimits="true"/>',
        f'  <option timestep="{timestep!r}" integrator="{integrator}" '
        f'gravity="0 0 {xml_number(-gravity)}"/>',
        "  <default>",
        '    <geom contype="0" conaffinity="0"/>',
        "  </default>",
        "  <worldbody>",
        '    <light pos="0 0 3" dir="0 0 -1" directional="true"/>',
    ]
    indent = "    "
    # the fixed base housing, at the base frame X_W0
    lines.append(f'{indent}<body name="base" {_pos_quat(robot.base)}>')
    lines += _housing_and_path(indent + "  ", "base", base_mass, radius, base_path,
                               _HOUSING_COLOR)
    # body i+1 is nested in body i, body 1 in the base body
    depth = indent + "  "
    for i, link in enumerate(links):
        lines.append(f'{depth}<body name="link{i + 1}" {_pos_quat(placements[i])}>')
        inner = depth + "  "
        kind = "hinge" if link.is_revolute else "slide"
        lo, hi = link.limits
        limit = ""
        if math.isfinite(lo) and math.isfinite(hi):
            limit = f' range="{xml_number(lo)} {xml_number(hi)}"'
        lines.append(f'{inner}<joint name="joint{i + 1}" type="{kind}" axis="0 0 1"{limit} '
                     f'damping="{xml_number(damping[i])}" armature="{xml_number(armature[i])}"/>')
        lines.append(inner + _inertial(inertias[i], corners[i + 1]))
        lines += _housing_and_path(inner, f"link{i + 1}", None, radius, paths[i],
                                   _LINK_COLOR)
        depth = inner
    lines.append(f'{depth}<site name="flange" {_pos_quat(X_BnT)} size="{xml_number(radius / 4)}"/>')
    r_payload = radius * 0.8
    lines.append(f'{depth}<body name="payload" {_pos_quat(X_BnT)}>')
    # The payload is a solid sphere of radius r_payload, of mass 0 when there is none (a body
    # without a joint of its own may weigh nothing), set by ArmSimulation.payload.
    lines.append(f'{depth}  <geom name="payload" type="sphere" size="{xml_number(r_payload)}" '
                 f'mass="{xml_number(payload)}" rgba="{_PAYLOAD_COLOR}"/>')
    lines.append(f"{depth}</body>")
    for i in range(n, 0, -1):
        lines.append(indent + "  " * i + "</body>")
    lines.append(f"{indent}</body>")
    lines += ["  </worldbody>", "  <actuator>"]
    for i in range(n):
        lines.append(f'    <motor name="motor{i + 1}" joint="joint{i + 1}" gear="1"/>')
    lines += ["  </actuator>", "</mujoco>", ""]
    return "\n".join(lines)


def _full_inertia(inertia, X_BF):
    r"""The ``pos``, ``mass`` and ``fullinertia`` (ixx iyy izz ixy ixz iyz) texts of a link
    whose frame F sits at ``X_BF`` in its body: :math:`X_{BF}\,\mathbf c` and
    :math:`R I_c R^\top`."""
    R = X_BF[:3, :3]
    com = R @ inertia.com + X_BF[:3, 3]
    I = R @ inertia.tensor @ R.T
    full = (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])
    return xml_vector(com), xml_number(inertia.mass), xml_vector(full)


def _check_moving_body(inertia, X_BF, i, scaled):
    """Refuse, naming the link, an inertia MuJoCo would refuse for a moving body: a mass
    below MIN_MASS, or a principal moment of the tensor as written below MIN_INERTIA."""
    where = f"link {i + 1}'s inertia (robot.links[{i}].inertia"
    where += f", scaled to masses[{i}])" if scaled else ")"
    if not inertia.mass >= MIN_MASS:
        raise ValueError(f"{where} has mass {inertia.mass:g} kg, below {MIN_MASS:g} kg: "
                         "MuJoCo cannot move a body without mass")
    full = [float(x) for x in _full_inertia(inertia, X_BF)[2].split()]
    tensor = np.array([[full[0], full[3], full[4]], [full[3], full[1], full[5]],
                       [full[4], full[5], full[2]]])
    smallest = float(np.linalg.eigvalsh(tensor)[0])
    if not smallest >= MIN_INERTIA:
        raise ValueError(f"{where} has a principal moment of {smallest:.3g} kg m^2, below "
                         f"{MIN_INERTIA:g} kg m^2, which MuJoCo refuses (a point mass or a "
                         "thin rod: give the link a body, e.g. LinkInertia.sphere(m, c, "
                         "radius=0.02))")


def _inertial(inertia, X_BF):
    r"""The ``<inertial>`` element of a body whose link frame F sits at ``X_BF`` in it: the
    centre of mass :math:`X_{BF}\,\mathbf c` and the tensor :math:`R I_c R^\top`, written
    as MuJoCo's ``fullinertia`` (ixx iyy izz ixy ixz iyz)."""
    com, mass, full = _full_inertia(inertia, X_BF)
    return f'<inertial pos="{com}" mass="{mass}" fullinertia="{full}"/>'


def model_name_of(robot, name):
    """The name a generated model takes: ``name``, else the robot's (``"robot"`` if it has
    none), checked as one line of text that XML can hold (``dqlab._checks.check_text``;
    the writers escape ``&``, ``<``, ``>`` and quotes)."""
    if name is None:
        return check_text(robot.name, "robot.name") if robot.name else "robot"
    return check_text(name, "name")


def _housing_and_path(indent, name, mass, radius, path, color):
    """Geoms of one body: a joint housing about z and capsules along the path. With a
    ``mass``, they share it (housing 30 %, capsules 70 % in proportion to their lengths)
    and MuJoCo computes the body's inertia from them; without (None), they are drawn only
    (the body has its ``<inertial>``)."""
    lengths = [float(np.linalg.norm(b - a)) for a, b in path]
    total = sum(lengths)

    def weight(share):
        return "" if mass is None else f'mass="{xml_number(share)}" '

    housing_mass = None if mass is None else (mass if total == 0 else 0.3 * mass)
    out = [f'{indent}<geom name="{name}_housing" type="cylinder" '
           f'size="{xml_number(radius * 1.1)} {xml_number(radius)}" '
           f'{weight(housing_mass)}'
           f'rgba="{_HOUSING_COLOR}"/>']
    for k, ((a, b), length) in enumerate(zip(path, lengths, strict=True)):
        share = None if mass is None else 0.7 * mass * length / total
        out.append(f'{indent}<geom name="{name}_segment{k + 1}" type="capsule" '
                   f'fromto="{xml_vector(a)} {xml_vector(b)}" size="{xml_number(radius)}" '
                   f'{weight(share)}rgba="{color}"/>')
    return out
