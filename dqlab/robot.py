r"""Serial kinematic chains: links in standard or modified Denavit--Hartenberg form.

A :class:`Robot` is a list of :class:`Link` objects plus a base and a tool transform. It
computes the forward kinematics (MGD in the French course notes) as homogeneous matrices
(:meth:`Robot.fk`) and as unit dual quaternions, in the two ways of the thesis: a product of
per-link dual quaternions (:meth:`Robot.fk_dq`) and a product of base-frame screw motions
about the joint axes of the zero pose (:meth:`Robot.fk_dq_screw`).

Conventions
-----------
Both Denavit--Hartenberg conventions are first-class. For link :math:`i`:

- standard DH (``convention="dh"``, as Universal Robots publish their arms)

  .. math::

     X_{i-1,i} = R_z(\theta_i)\, T_z(d_i)\, T_x(a_i)\, R_x(\alpha_i)

- modified DH (``convention="mdh"``, Khalil--Kleinfinger, the French course notes), where the
  link stores :math:`a_{i-1}` in ``a``, :math:`\alpha_{i-1}` in ``alpha`` and :math:`r_i` in
  ``d``:

  .. math::

     X_{i-1,i} = R_x(\alpha_{i-1})\, T_x(a_{i-1})\, R_z(\theta_i)\, T_z(r_i)

The joint variable :math:`q_i` enters as :math:`\theta_i = q_i + \theta^0_i` for a revolute
joint (``theta_offset`` holds :math:`\theta^0_i`, the "q_fig" row of a published table) and
as :math:`d_i = q_i + d^0_i` for a prismatic joint (``d`` holds :math:`d^0_i`, and
``theta_offset`` is then the constant :math:`\theta_i`). The whole chain is

.. math::

   X_{WT}(q) = X_{W0}\, X_{01}(q_1) \cdots X_{n-1,n}(q_n)\, X_{nT}

with the base :math:`X_{W0}` and the tool :math:`X_{nT}` (both identity by default).
Units are metres and radians.
"""

import copy
import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import as_float_array, check_scalar, check_text, real_array, short_repr
from ._fast.chain import CompiledChain
from .dualquat import dual_quaternion_from_transform
from .inertia import LinkInertia
from .transforms import check_transform

__all__ = ["Link", "Robot", "REVOLUTE", "PRISMATIC"]

class _Offset:
    """with_tool's default: the tool is given by its offset x, y, z."""

    def __repr__(self):
        return "<offset x, y, z>"


_OFFSET = _Offset()


class _TurnEachWay:
    """from_dh_table's default limits: one full turn each way for a revolute joint."""

    def __repr__(self):
        return "<±2π for revolute joints>"


_TURN_EACH_WAY = _TurnEachWay()

REVOLUTE = "revolute"
PRISMATIC = "prismatic"


def _bound(value, name):
    """A joint limit: a finite number (:func:`dqlab._checks.check_scalar`), or an infinite
    float for no limit on that side."""
    if isinstance(value, (float, np.floating)) and math.isinf(value):
        return float(value)
    return check_scalar(value, name)


def _rot_x_h(alpha):
    """4x4 rotation about x (plain numpy; used for the constant parts of a link)."""
    c, s = math.cos(alpha), math.sin(alpha)
    return np.array([[1.0, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _trans_x_h(a):
    T = np.eye(4)
    T[0, 3] = a
    return T


class Link:
    r"""One link of a serial chain: its Denavit--Hartenberg parameters and its joint.

    Parameters
    ----------
    a : float
        Link length in metres: :math:`a_i` (standard DH) or :math:`a_{i-1}` (modified DH).
    alpha : float
        Link twist in radians: :math:`\alpha_i` (standard DH) or :math:`\alpha_{i-1}`
        (modified DH).
    d : float
        Link offset in metres along the joint axis: :math:`d_i` (standard DH) or :math:`r_i`
        (modified DH). For a prismatic joint this is the constant added to the joint
        variable.
    theta_offset : float, optional
        For a revolute joint, the constant added to the joint variable,
        :math:`\theta_i = q_i + \theta^0_i` (the "q_fig" row of a table). For a prismatic
        joint, the constant joint angle :math:`\theta_i`.
    joint : {"revolute", "prismatic"}, optional
        Joint type, :math:`\sigma_i = 0` or :math:`1` in the course notes.
    limits : (float, float), optional
        Lowest and highest joint value (radians or metres). Default: no limit.
    name : str, optional
        A label printed in :meth:`Robot.dh_table`.
    inertia : LinkInertia, optional
        The link's mass, centre of mass and inertia tensor in the link's own frame (see
        :mod:`dqlab.inertia`), for :mod:`dqlab.dynamics` and the simulators. None (the
        default): the link has no inertial parameters.
    max_speed : float, optional
        The joint's rated speed limit, rad/s (m/s for a prismatic joint), > 0; ``None`` (the
        default) when not known. Read by :meth:`dqlab.ur.script.SafetyLimits.for_robot`.
    max_torque : float, optional
        The joint's rated torque, N m (N for a prismatic joint), > 0; ``None`` (the default)
        when not known. Read by :meth:`dqlab.ur.script.SafetyLimits.for_robot`.

    Raises
    ------
    ValueError
        If a parameter is not a finite number, the joint type is unknown, the limits are
        not ordered or ``max_speed`` or ``max_torque`` is not a positive number.

    Notes
    -----
    A link is immutable: a :class:`Robot` precomputes the constant parts of its chain.

    The parameters come in the order ``a, alpha, d``; makers' tables print ``d, a, alpha``.
    Pass them by name, as below, or build the whole robot from the table's columns with
    :meth:`Robot.from_dh_table` (which also gives revolute joints the :math:`\pm 2\pi`
    limits of a UR joint by default; a bare ``Link`` has no limits).

    Examples
    --------
    >>> import numpy as np
    >>> link = Link(a=0.0, alpha=np.pi / 2, d=0.1519)
    >>> link.joint, link.sigma
    ('revolute', 0)
    >>> Link(a=0.0, alpha=0.0, d=0.0, joint="prismatic", limits=(0.0, 0.15)).sigma
    1
    """

    def __init__(self, a, alpha, d, theta_offset=0.0, joint=REVOLUTE, limits=None, name="",
                 inertia=None, max_speed=None, max_torque=None):
        values = {key: check_scalar(value, f"Link {key}") for key, value in
                  (("a", a), ("alpha", alpha), ("d", d), ("theta_offset", theta_offset))}
        if isinstance(joint, (bool, np.bool_)) or joint not in (
                REVOLUTE, PRISMATIC, 0, 1, "R", "r", "P", "p"):
            raise ValueError("Link joint must be 'revolute' or 'prismatic' (or 0, 1, 'R', "
                             f"'P'), got {short_repr(joint)}")
        joint = REVOLUTE if joint in (REVOLUTE, 0, "R", "r") else PRISMATIC
        if limits is None:
            limits = (-math.inf, math.inf)
        try:
            pair = not isinstance(limits, (str, bytes)) and np.shape(limits) == (2,)
        except ValueError:                                  # a ragged sequence
            pair = False
        if not pair:
            raise ValueError(f"Link limits must be a pair (lo, hi), got {short_repr(limits)}")
        lo, hi = _bound(limits[0], "Link limits (lo)"), _bound(limits[1], "Link limits (hi)")
        if not lo <= hi or lo == math.inf or hi == -math.inf:
            raise ValueError(f"Link limits must satisfy lo <= hi, lo < inf and hi > -inf, got "
                             f"{short_repr(limits)}")
        set_ = object.__setattr__       # a Link is immutable once built
        set_(self, "a", values["a"])
        set_(self, "alpha", values["alpha"])
        set_(self, "d", values["d"])
        set_(self, "theta_offset", values["theta_offset"])
        set_(self, "joint", joint)
        set_(self, "limits", (lo, hi))
        if not isinstance(name, str):
            raise TypeError(f"Link name must be text, got {short_repr(name)}")
        set_(self, "name", check_text(name, "Link name") if name else name)
        if max_speed is not None:
            max_speed = check_scalar(max_speed, "Link max_speed", minimum=0.0, strict=True)
        set_(self, "max_speed", max_speed)
        if max_torque is not None:
            max_torque = check_scalar(max_torque, "Link max_torque", minimum=0.0, strict=True)
        set_(self, "max_torque", max_torque)
        if inertia is not None and not isinstance(inertia, LinkInertia):
            raise ValueError("Link inertia must be a dqlab.inertia.LinkInertia or None, got "
                             f"{type(inertia).__name__}")
        set_(self, "inertia", inertia)

    def with_inertia(self, inertia):
        """A copy of this link (every other parameter kept) with other inertial parameters.

        Examples
        --------
        >>> from dqlab.inertia import LinkInertia
        >>> link = Link(a=0.3, alpha=0.0, d=0.0)
        >>> link.with_inertia(LinkInertia.sphere(1.0, [-0.15, 0, 0])).inertia.mass
        1.0
        """
        if inertia is not None and not isinstance(inertia, LinkInertia):
            raise ValueError("inertia must be a dqlab.inertia.LinkInertia or None, got "
                             f"{type(inertia).__name__}")
        new = copy.copy(self)
        object.__setattr__(new, "inertia", inertia)
        return new

    def __setattr__(self, key, value):
        raise AttributeError("Link is immutable (a Robot precomputes its constant parts); "
                             "build a new Link and Robot instead")

    @property
    def sigma(self):
        """Joint type as in the course notes: 0 revolute, 1 prismatic."""
        return int(self.joint == PRISMATIC)

    @property
    def is_revolute(self):
        return self.joint == REVOLUTE

    def __repr__(self):
        return (f"Link(a={self.a!r}, alpha={self.alpha!r}, d={self.d!r}, "
                f"theta_offset={self.theta_offset!r}, joint={self.joint!r}, "
                f"limits={self.limits!r})")


def _link_constants(links, convention):
    """The constant factors L_i, R_i (n, 4, 4) of the links X_{i-1,i} = L_i J_i R_i, with
    the joint motion J = Rz(theta) Tz(d) between them: L = I, R = Tx(a) Rx(alpha) in
    standard DH; L = Rx(alpha) Tx(a), R = I in modified DH."""
    L = np.empty((len(links), 4, 4))
    R = np.empty((len(links), 4, 4))
    for i, lk in enumerate(links):
        if convention == "dh":
            L[i] = np.eye(4)
            R[i] = _trans_x_h(lk.a) @ _rot_x_h(lk.alpha)
        else:
            L[i] = _rot_x_h(lk.alpha) @ _trans_x_h(lk.a)
            R[i] = np.eye(4)
    return L, R


# How far from orthonormal the rotation block of a base or tool may be: the largest entry of
# |R^T R - I|, an absolute tolerance (that of every check of dqlab's transforms).
_RIGID_TOL = 1e-9


def _check_transform_like(T, name):
    r"""A base or tool transform, checked once where it enters: one rigid 4x4 transform
    (:func:`dqlab.transforms.check_transform` with an absolute tolerance of 1e-9 on
    :math:`R^\top R - I`), the error naming the argument."""
    if T is None:
        return np.eye(4)
    T = as_float_array(T, name, (4, 4))
    if T.shape != (4, 4):
        raise ValueError(f"{name} must be one 4x4 transform, got shape {T.shape}")
    try:
        return check_transform(T, _RIGID_TOL, name).copy()
    except ValueError as exc:
        raise ValueError(f"{name} must be a rigid transform: {exc}") from None


def _check_name(name):
    """A robot's name: text, empty or one line of printable text (it is written into files:
    :func:`dqlab._checks.check_text`)."""
    if not isinstance(name, str):
        raise TypeError(f"name must be text (the robot's name), got {short_repr(name)}")
    return check_text(name, "name") if name else name


def _transform_attribute(name, doc):
    """A rigid transform of the chain (base or tool): read as a copy; assigning checks it
    and recomputes the chain's constant parts."""
    private = "_" + name

    def get(self):
        return getattr(self, private).copy()

    def set_(self, value):
        setattr(self, private, _check_transform_like(value, name))
        self._prepare()

    return property(get, set_, doc=doc)


class Robot:
    r"""A serial kinematic chain with forward kinematics and Jacobian.

    Parameters
    ----------
    links : sequence of Link
        The links from the base to the flange.
    convention : {"dh", "mdh"}, optional
        Standard (``"dh"``) or modified (``"mdh"``, Khalil--Kleinfinger) Denavit--Hartenberg.
    base : array_like, shape (4, 4), optional
        :math:`X_{W0}`, the pose of the chain's frame 0 in the world frame W. Identity by
        default.
    tool : array_like, shape (4, 4), optional
        :math:`X_{nT}`, the pose of the tool centre point (TCP) in the flange frame n.
        Identity by default.
    name : str, optional
        Printed in :meth:`dh_table` and ``repr``.

    Attributes
    ----------
    n : int
        Number of joints.
    links : tuple of Link
    convention : str
    base, tool : ndarray, shape (4, 4)
    name : str
        Empty, or one line of printable text (checked when assigned: it is written into
        the URDF and MJCF exports).

    Examples
    --------
    A planar two-link arm in standard DH (lengths 1 and 0.5):

    >>> import numpy as np
    >>> arm = Robot([Link(1.0, 0.0, 0.0), Link(0.5, 0.0, 0.0)], name="planar 2R")
    >>> arm.n
    2
    >>> X_WT = arm.fk([0.0, np.pi / 2])
    >>> X_WT[:3, 3].round(12)
    array([1. , 0.5, 0. ])
    >>> arm.fk([[0.0, 0.0], [np.pi / 2, 0.0]])[:, :3, 3].round(12)
    array([[1.5, 0. , 0. ],
           [0. , 1.5, 0. ]])
    """

    def __init__(self, links, convention="dh", base=None, tool=None, name=""):
        links = tuple(links)
        if not links:
            raise ValueError("Robot needs at least one link")
        for i, link in enumerate(links):
            if not isinstance(link, Link):
                raise ValueError(f"links[{i}] must be a Link, got {type(link).__name__}")
        if convention not in ("dh", "mdh"):
            raise ValueError(f"convention must be 'dh' or 'mdh', got {convention!r}")
        self._links = links
        self._convention = convention
        self.name = name
        self._base = _check_transform_like(base, "base")
        self._tool = _check_transform_like(tool, "tool")
        self._prepare()

    @classmethod
    def from_dh_table(cls, *, d: ArrayLike, a: ArrayLike, alpha: ArrayLike,
                      theta_offset: ArrayLike | None = None, joint: str | tuple = REVOLUTE,
                      limits: ArrayLike | None = _TURN_EACH_WAY,
                      max_speed: ArrayLike | None = None, convention: str = "dh",
                      base: ArrayLike | None = None, tool: ArrayLike | None = None,
                      name: str = "") -> "Robot":
        r"""A robot from a maker's parameter table, column by column, by name.

        Makers print their tables in the order :math:`d, a, \alpha` (Universal Robots:
        :math:`d_i, a_i, \alpha_i`), :class:`Link` takes ``Link(a, alpha, d)``: every column
        here is a keyword, so the order cannot be mixed up, and every column must have one
        entry per joint.

        Parameters
        ----------
        d, a, alpha : array_like, shape (n,)
            The columns of the table: offsets :math:`d_i` (m), lengths :math:`a_i` (m) and
            twists :math:`\alpha_i` (radians; ``np.radians`` converts a table in degrees).
            In modified DH (``convention="mdh"``) they are :math:`r_i, a_{i-1},
            \alpha_{i-1}`, as :class:`Link` reads them.
        theta_offset : array_like, shape (n,), optional
            :math:`\theta^0_i` (radians), :math:`\theta_i = q_i + \theta^0_i` (for a
            prismatic joint the constant :math:`\theta_i`); zeros by default.
        joint : str or sequence of str, optional
            ``"revolute"`` (default) or ``"prismatic"``, for all joints or one per joint.
        limits : array_like, shape (2,) or (n, 2), or None, optional
            Joint limits (radians for a revolute joint, metres for a prismatic one), for
            all joints or per joint; ``None``: no limits. By default a revolute joint gets
            :math:`\pm 2\pi`, the range of a UR joint (one full turn each way); a
            prismatic joint has no such common range, so a table with a prismatic joint
            must give its limits (its travel in metres) or ``None``.
        max_speed : array_like, shape (n,), optional
            The joints' rated speeds (rad/s), see :class:`Link`.
        convention : {"dh", "mdh"}, optional
        base, tool : array_like, shape (4, 4), optional
            As for :class:`Robot`; :meth:`with_tool` sets a tool afterwards.
        name : str, optional

        Returns
        -------
        Robot

        Raises
        ------
        ValueError
            If a column is not a list of n finite numbers (the message names it), the
            columns have different lengths, a twist or an angle offset exceeds :math:`2\pi`
            in magnitude (a table in degrees?), a prismatic joint is given no limits, or a
            limit or joint type is invalid.

        Examples
        --------
        The UR5e as Universal Robots print it (d, a, alpha):

        >>> import numpy as np
        >>> robot = Robot.from_dh_table(
        ...     d=[0.1625, 0, 0, 0.1333, 0.0997, 0.0996],
        ...     a=[0, -0.425, -0.3922, 0, 0, 0],
        ...     alpha=[np.pi / 2, 0, 0, np.pi / 2, -np.pi / 2, 0], name="my UR5e")
        >>> from dqlab.models import ur5e
        >>> bool(np.allclose(robot.fk([0.1] * 6), ur5e().fk([0.1] * 6), atol=1e-15))
        True
        >>> robot.limits[0]
        array([-6.28318531,  6.28318531])
        """
        columns = {"d": d, "a": a, "alpha": alpha}
        if theta_offset is not None:
            columns["theta_offset"] = theta_offset
        if max_speed is not None:
            columns["max_speed"] = max_speed
        values = {}
        for key, column in columns.items():
            v = as_float_array(column, key)
            if v.ndim != 1 or v.size == 0:
                raise ValueError(f"{key} must be a column of the table, one number per joint "
                                 f"(shape (n,)), got shape {v.shape}")
            values[key] = v
        n = values["d"].size
        for key, v in values.items():
            if v.size != n:
                sizes = ", ".join(f"{k}: {w.size}" for k, w in values.items())
                raise ValueError(f"the columns of the table must have one entry per joint; "
                                 f"got {sizes} ({key} differs from d)")
        for key, what in (("alpha", "twists"), ("theta_offset", "angle offsets")):
            big = np.abs(values.get(key, np.zeros(n))) > 2 * math.pi
            if big.any():
                i = int(np.flatnonzero(big)[0])
                raise ValueError(f"{key}[{i}] = {values[key][i]:g} is more than 2 pi: {what} "
                                 "are in radians (a table in degrees? convert with np.radians)")
        theta0 = values.get("theta_offset", np.zeros(n))
        if isinstance(joint, (str, int)):
            joints = (joint,) * n
        else:
            try:
                joints = tuple(joint)
            except TypeError:
                raise ValueError(f"joint must be one type or one per joint ({n}), got "
                                 f"{short_repr(joint)}") from None
        if len(joints) != n:
            raise ValueError(f"joint must be one type or one per joint ({n}), got "
                             f"{short_repr(joint)}")
        if limits is _TURN_EACH_WAY:
            prismatic = [i for i, j in enumerate(joints) if Link(0, 0, 0, joint=j).sigma]
            if prismatic:
                raise ValueError(f"limits: joint {prismatic[0] + 1} is prismatic and has no "
                                 "default range: give the joints' limits (metres for a "
                                 "prismatic joint, radians for a revolute one), or None for "
                                 "no limits")
            limits = (-2 * math.pi, 2 * math.pi)
        if limits is None:
            lims = [None] * n
        else:
            lim = real_array(limits, "limits")
            if lim.shape not in ((2,), (n, 2)):
                raise ValueError(f"limits must have shape (2,) or ({n}, 2), got {lim.shape}")
            lims = [tuple(row) for row in np.broadcast_to(lim, (n, 2)).tolist()]
            for i, (lo, hi) in enumerate(lims):
                turns = max([abs(v) for v in (lo, hi) if math.isfinite(v)] + [0.0]) / (2 * math.pi)
                if joints[i] in (REVOLUTE, 0, "R", "r") and turns > 2:
                    raise ValueError(f"limits of joint {i + 1} = ({lo:g}, {hi:g}) are more than "
                                     "two turns: a revolute joint's limits are in radians (a "
                                     "table in degrees? convert with np.radians; inf for no "
                                     "limit)")
        speeds = values.get("max_speed", [None] * n)
        links = [Link(a=values["a"][i], alpha=values["alpha"][i], d=values["d"][i],
                      theta_offset=theta0[i], joint=joints[i], limits=lims[i],
                      max_speed=None if speeds[i] is None else float(speeds[i]))
                 for i in range(n)]
        return cls(links, convention=convention, base=base, tool=tool, name=name)

    def with_tool(self, X_nT: ArrayLike = _OFFSET, *, x: float = 0.0, y: float = 0.0,
                  z: float = 0.0) -> "Robot":
        r"""The same robot with another tool: a transform :math:`X_{nT}`, or an offset of
        the tool centre point along the flange's axes.

        ``robot.with_tool(z=0.15)`` is a gripper whose TCP lies 0.15 m along the flange's z
        axis, :math:`X_{nT} = T(x, y, z)` with the flange's orientation. The tool replaces
        the robot's own (it is not composed with it); the links and the base are kept, and
        the robot itself is not changed.

        Parameters
        ----------
        X_nT : array_like, shape (4, 4), optional
            The pose of the TCP in the flange frame (a rigid transform). Not together with
            ``x``, ``y``, ``z``; ``robot.with_tool()`` removes the tool.
        x, y, z : float, optional
            The TCP's position in the flange frame, metres (rotation: none).

        Returns
        -------
        Robot

        Raises
        ------
        ValueError
            If ``X_nT`` is not a rigid 4x4 transform, an offset is not a finite number, or
            both a transform and an offset are given.

        Examples
        --------
        >>> import numpy as np
        >>> from dqlab.models import ur5e
        >>> robot = ur5e().with_tool(z=0.15)
        >>> q = [0.3, -1.2, 1.1, -0.4, 0.9, 0.2]
        >>> X_WF, X_WT = ur5e().fk(q), robot.fk(q)
        >>> bool(np.allclose(X_WT[:3, 3], X_WF[:3, 3] + 0.15 * X_WF[:3, 2]))
        True
        >>> robot.name, ur5e().bare, robot.bare
        ('UR5e', True, False)
        """
        offset = [check_scalar(v, k) for k, v in (("x", x), ("y", y), ("z", z))]
        if X_nT is _OFFSET:
            X_nT = np.eye(4)
            X_nT[:3, 3] = offset
        elif any(offset):
            raise ValueError("give the tool as X_nT or as the offset x, y, z, not both")
        if X_nT is None:
            raise TypeError("X_nT must be a 4x4 transform, got None (robot.with_tool() "
                            "without arguments removes the tool)")
        X_nT = _check_transform_like(X_nT, "X_nT")
        return type(self)(self._links, convention=self._convention, base=self._base,
                          tool=X_nT, name=self.name)

    # -- read-only description -------------------------------------------------------------
    @property
    def links(self):
        return self._links

    @property
    def convention(self):
        return self._convention

    @property
    def n(self):
        return len(self._links)

    @property
    def name(self):  # documented in the class's Attributes: text, empty or one printable line
        return self._name

    @name.setter
    def name(self, value):
        self._name = _check_name(value)

    base = _transform_attribute(
        "base", ":math:`X_{W0}`, shape (4, 4) (a copy; assign a new transform to change it).")
    tool = _transform_attribute(
        "tool", ":math:`X_{nT}`, shape (4, 4) (a copy; assign a new transform to change it).")

    @property
    def joint_types(self):
        """Tuple of ``"revolute"`` / ``"prismatic"``, one per joint."""
        return tuple(link.joint for link in self._links)

    @property
    def bare(self):
        """True when the robot has neither a base transform nor a tool: its world frame is
        frame 0 and its TCP is the flange (the frames of a published DH table)."""
        return self._bare

    @property
    def base_dq(self):
        """:math:`X_{W0}` as a unit dual quaternion ``(q_r, q_d)``, shape (8,) (a copy)."""
        return self._base_dq.copy()

    @property
    def tool_dq(self):
        """:math:`X_{nT}` as a unit dual quaternion ``(q_r, q_d)``, shape (8,) (a copy).

        Examples
        --------
        >>> from dqlab.models import ur5e
        >>> ur5e().with_tool(z=0.15).tool_dq
        array([1.   , 0.   , 0.   , 0.   , 0.   , 0.   , 0.   , 0.075])
        """
        return self._tool_dq.copy()

    @property
    def limits(self):
        """Joint limits as an array of shape (n, 2): lowest, highest."""
        return np.array([link.limits for link in self._links], dtype=float)

    # -- constant parts, precomputed once ------------------------------------------------
    def _prepare(self):
        """Compute everything derived from the links, the base and the tool.

        The one cache rule of a robot: this runs when the robot is built and whenever its
        base or tool is assigned (links are immutable), and nothing else is cached.
        """
        self._revolute = np.array([lk.is_revolute for lk in self._links])
        self._lo = np.array([lk.limits[0] for lk in self._links])
        self._hi = np.array([lk.limits[1] for lk in self._links])
        self._prismatic_idx = np.flatnonzero(~self._revolute)
        self._bare = bool(np.array_equal(self._base, np.eye(4))
                          and np.array_equal(self._tool, np.eye(4)))
        # the base and the tool as unit dual quaternions (8,), for the solvers' fast paths
        self._base_dq = dual_quaternion_from_transform(self._base)
        self._tool_dq = dual_quaternion_from_transform(self._tool)
        # (theta_i offset, d_i offset, revolute?) of every link
        self._joint_constants = [(lk.theta_offset, lk.d, lk.is_revolute) for lk in self._links]
        self._L, self._R = _link_constants(self._links, self._convention)
        # the products that fk, fk_dq, fk_dq_screw and jacobian run (speed machinery)
        self._chain = CompiledChain(self._joint_constants, self._L, self._R, self._base,
                                    self._tool, self.check_joints)

    # -- joint vectors -----------------------------------------------------------------------
    def check_joints(self, q: ArrayLike, *, limits: str = "prismatic", name: str = "q"
                     ) -> NDArray[np.float64]:
        """Validate joint vectors and return them as a float array.

        Parameters
        ----------
        q : array_like, shape (..., n)
            Joint values: radians for revolute joints, metres for prismatic joints.
        limits : {"prismatic", "all", "none"}, optional
            Which joint limits to enforce. The default enforces only the prismatic ones (a
            prismatic joint beyond its travel has no physical meaning, while a revolute angle
            outside its software limits still describes a pose).

        Returns
        -------
        ndarray, shape (..., n)

        Raises
        ------
        ValueError
            On a wrong last dimension, NaN or infinity, or a value beyond the enforced
            limits (the message names the joint and the limit).

        Examples
        --------
        >>> from dqlab.models import scara_rsm5
        >>> scara = scara_rsm5()
        >>> scara.check_joints([0.1, 0.2, 0.05, 0.0])
        array([0.1 , 0.2 , 0.05, 0.  ])
        >>> scara.check_joints([0.1, 0.2, 0.5, 0.0])
        Traceback (most recent call last):
        ...
        ValueError: joint 3 (prismatic) = 0.5 is beyond its limits [0, 0.15]
        """
        q = real_array(q, name)
        if q.ndim == 0 or q.shape[-1] != self.n:
            raise ValueError(
                f"{name} must have shape (..., {self.n}) for this {self.n}-joint robot, "
                f"got shape {q.shape}")
        if not np.isfinite(q).all():
            raise ValueError(f"{name} contains NaN or infinity")
        if limits == "none":
            return q
        if limits == "prismatic":
            idx = self._prismatic_idx
            if idx.size == 0:
                return q
        elif limits == "all":
            idx = np.arange(self.n)
        else:
            raise ValueError(f"limits must be 'prismatic', 'all' or 'none', got {limits!r}")
        sub = q[..., idx]
        bad = (sub < self._lo[idx]) | (sub > self._hi[idx])
        if bad.any():
            where = np.argwhere(bad)[0]
            j = idx[where[-1]]
            value = sub[tuple(where)]
            lk = self._links[j]
            # beyond two turns no joint angle is plausible in radians: degrees, probably
            hint = ("; joint angles are in radians (degrees? convert with np.radians)"
                    if lk.is_revolute and abs(value) > 4 * math.pi else "")
            raise ValueError(
                f"joint {j + 1} ({lk.joint}) = {value:.6g} is beyond its limits "
                f"[{lk.limits[0]:.6g}, {lk.limits[1]:.6g}]{hint}")
        return q

    def _link_parameters(self, q):
        """Joint angles theta and offsets d of every link, shape (..., n) each."""
        theta = np.array([c[0] for c in self._joint_constants]) + q * self._revolute
        d = np.array([c[1] for c in self._joint_constants]) + q * ~self._revolute
        return theta, d

    def _joint_motions(self, q):
        """J_i = Rz(theta_i) Tz(d_i) for every link, shape (..., n, 4, 4)."""
        theta, d = self._link_parameters(q)
        c, s = np.cos(theta), np.sin(theta)
        J = np.zeros(q.shape + (4, 4))
        J[..., 0, 0] = c
        J[..., 0, 1] = -s
        J[..., 1, 0] = s
        J[..., 1, 1] = c
        J[..., 2, 2] = 1.0
        J[..., 2, 3] = d
        J[..., 3, 3] = 1.0
        return J

    def link_transforms(self, q: ArrayLike) -> NDArray[np.float64]:
        r"""The link transforms :math:`X_{i-1,i}(q_i)`, without base and tool: the readable
        definition of the chain.

        Each link is the product of its constant factors and its joint motion,
        :math:`X_{i-1,i} = L_i\, R_z(\theta_i) T_z(d_i)\, R_i` (:math:`L_i = I`,
        :math:`R_i = T_x(a_i) R_x(\alpha_i)` in standard DH; :math:`L_i = R_x(\alpha_{i-1})
        T_x(a_{i-1})`, :math:`R_i = I` in modified DH), as 4x4 matrices. :meth:`fk` is
        defined as :math:`X_{W0}\, X_{01} \cdots X_{n-1,n}\, X_{nT}` of these; it is
        computed another way, and tested equal to this product.

        Parameters
        ----------
        q : array_like, shape (..., n)

        Returns
        -------
        ndarray, shape (..., n, 4, 4)
            Entry ``i`` is the pose of frame ``i + 1`` in frame ``i``.

        Examples
        --------
        >>> from dqlab.models import ur3_mdh
        >>> X_01 = ur3_mdh().link_transforms([0.1, 0, 0, 0, 0, 0])[0]
        >>> X_01.round(8)
        array([[-0.09983342, -0.99500417,  0.        ,  0.        ],
               [ 0.99500417, -0.09983342,  0.        ,  0.        ],
               [ 0.        ,  0.        ,  1.        ,  0.152     ],
               [ 0.        ,  0.        ,  0.        ,  1.        ]])
        """
        q = self.check_joints(q)
        return self._L @ self._joint_motions(q) @ self._R

    # -- forward kinematics, matrices ---------------------------------------------------
    def fk(self, q: ArrayLike, all_frames: bool = False) -> NDArray[np.float64]:
        r"""Forward kinematics as homogeneous transforms.

        .. math::

           X_{WT}(q) = X_{W0} \prod_{i=1}^{n} X_{i-1,i}(q_i)\; X_{nT}

        The definition is this product of the :meth:`link_transforms`. It is computed by
        the robot's compiled chain (``dqlab._fast.chain``: the constant factors of
        neighbouring links multiplied once, the product unrolled on the entries, one joint
        vector on Python floats), which the tests hold to the product of
        :meth:`link_transforms` with the base and the tool.

        Parameters
        ----------
        q : array_like, shape (..., n)
            Joint vectors (radians, metres for prismatic joints).
        all_frames : bool, optional
            If True, also return the intermediate frames.

        Returns
        -------
        ndarray, shape (..., 4, 4) or (..., n + 1, 4, 4)
            :math:`X_{WT}`, the pose of the tool (the flange when there is no tool) in the
            world frame. With ``all_frames``, the poses of frames 0 (the base), 1, ...,
            n in W, where the last one is the TCP (frame n composed with the tool).

        Raises
        ------
        ValueError
            See :meth:`check_joints`.

        Examples
        --------
        >>> import numpy as np
        >>> from dqlab.models import ur3
        >>> X_WF = ur3().fk(np.zeros(6))
        >>> X_WF.round(5)
        array([[ 1.     ,  0.     ,  0.     , -0.4569 ],
               [ 0.     ,  0.     , -1.     , -0.19425],
               [ 0.     ,  1.     ,  0.     ,  0.06655],
               [ 0.     ,  0.     ,  0.     ,  1.     ]])
        >>> ur3().fk(np.zeros((5, 6)), all_frames=True).shape
        (5, 7, 4, 4)
        """
        if all_frames:
            return self._chain.frames(self.check_joints(q))
        return self._chain.pose(q)

    def joint_axes(self, q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        r"""Points on the joint axes and their unit directions, in the world frame.

        The joint :math:`i` moves along or about the z axis of the frame
        :math:`X_{W0} X_{01} \cdots X_{i-2,i-1} L_i` (frame :math:`i-1` in standard DH,
        frame :math:`i` in modified DH).

        Parameters
        ----------
        q : array_like, shape (..., n)

        Returns
        -------
        points : ndarray, shape (..., n, 3)
        axes : ndarray, shape (..., n, 3)

        Examples
        --------
        >>> import numpy as np
        >>> from dqlab.models import ur3
        >>> points, axes = ur3().joint_axes(np.zeros(6))
        >>> axes[:3].round(12)
        array([[ 0.,  0.,  1.],
               [ 0., -1.,  0.],
               [ 0., -1.,  0.]])
        """
        points, axes, _ = self._chain.axes_and_tcp_position(self.check_joints(q))
        return points, axes

    # -- forward kinematics, dual quaternions --------------------------------------------
    def fk_dq(self, q: ArrayLike) -> NDArray[np.float64]:
        r"""Forward kinematics as a unit dual quaternion, link by link.

        Each link is written as a product of three dual quaternions, the constant parts and
        the joint's screw about its own z axis (a turn by :math:`\theta_i` and a shift by
        :math:`d_i`, which commute),

        .. math::

           \hat Q_{i-1,i} = \hat L_i\; \hat J_i(q_i)\; \hat R_i, \qquad
           \hat J_i = r_i + \varepsilon\,\tfrac12\, d_i k\, r_i, \quad
           r_i = \cos\tfrac{\theta_i}{2} + \sin\tfrac{\theta_i}{2}\,k,

        that is :math:`\hat J_i = \bigl(\cos\tfrac{\theta_i}{2}, 0, 0,
        \sin\tfrac{\theta_i}{2}\bigr) + \varepsilon\,\tfrac12\bigl(-d_i
        \sin\tfrac{\theta_i}{2}, 0, 0, d_i \cos\tfrac{\theta_i}{2}\bigr)`, and multiplied
        from the base to the tool,
        :math:`\hat Q_{WT} = \hat Q_{W0} \hat Q_{01} \cdots \hat Q_{n-1,n} \hat Q_{nT}`
        (thesis section 4.2, first construction). The constant factors of neighbouring
        links are multiplied once in advance, :math:`\hat K_0 = \hat Q_{W0} \hat L_1`,
        :math:`\hat K_i = \hat R_i \hat L_{i+1}`, :math:`\hat K_n = \hat R_n \hat Q_{nT}`, so
        that

        .. math::

           \hat Q_{WT} = \hat K_0\, \hat J_1 \hat K_1\, \hat J_2 \hat K_2 \cdots
           \hat J_n \hat K_n .

        Parameters
        ----------
        q : array_like, shape (..., n)

        Returns
        -------
        ndarray, shape (..., 8)
            :math:`(q_r, q_d)` of the pose :math:`X_{WT}`. Its sign is that of the product
            (``-Q`` is the same pose).

        Raises
        ------
        ValueError
            See :meth:`check_joints`.

        Examples
        --------
        >>> import numpy as np
        >>> from dqlab import dualquat
        >>> from dqlab.models import ur3
        >>> robot = ur3()
        >>> q = [0.1, -0.5, 0.8, -0.2, 0.5, 0.1]
        >>> Q = robot.fk_dq(q)
        >>> np.allclose(dualquat.transform_from_dual_quaternion(Q), robot.fk(q))
        True
        """
        return self._chain.dual_quaternion(q)

    def zero_pose_screws(self
                         ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        r"""The joint axes at :math:`q = 0` in the world frame and the zero-pose TCP.

        Returns
        -------
        points : ndarray, shape (n, 3)
            A point on each joint axis.
        axes : ndarray, shape (n, 3)
            Unit direction of each joint axis.
        X_WT0 : ndarray, shape (4, 4)
            The pose of the tool at :math:`q = 0`.

        Examples
        --------
        >>> from dqlab.models import ur3
        >>> points, axes, X_WT0 = ur3().zero_pose_screws()
        >>> points[1].round(4), axes[1].round(4)
        (array([0.    , 0.    , 0.1519]), array([ 0., -1.,  0.]))
        """
        points, axes, X_WT0 = self._chain.zero_pose
        return points.copy(), axes.copy(), X_WT0.copy()

    def fk_dq_screw(self, q: ArrayLike) -> NDArray[np.float64]:
        r"""Forward kinematics as a product of base-frame screw motions (thesis, second way).

        Joint :math:`i` turns the rest of the arm about its axis at the zero pose, the line
        through :math:`p_i` with unit direction :math:`\omega_i` in the world frame. As a dual
        quaternion that motion is the rotation :math:`r_i = \cos\frac{q_i}{2} +
        \sin\frac{q_i}{2}\,\omega_i` followed by the translation :math:`p_i - r_i p_i r_i^*`
        (a translation :math:`q_i \omega_i` for a prismatic joint). In closed form, with the
        moment :math:`\mathbf m_i = p_i \times \omega_i` of the axis (see
        :func:`dqlab.dualquat.dual_quaternion_from_screw`),

        .. math::

           \hat S_i = \Bigl(\cos\tfrac{q_i}{2},\; \sin\tfrac{q_i}{2}\,\omega_i\Bigr)
           + \varepsilon\,\Bigl(0,\; \sin\tfrac{q_i}{2}\,\mathbf m_i\Bigr)
           \quad\text{(revolute)}, \qquad
           \hat S_i = 1 + \varepsilon\,\Bigl(0,\; \tfrac{q_i}{2}\,\omega_i\Bigr)
           \quad\text{(prismatic)}.

        Then

        .. math::

           \hat Q_{WT}(q) = \hat S_1(q_1)\, \hat S_2(q_2) \cdots \hat S_n(q_n)\;
           \hat Q_{WT}(0),

        the dual-quaternion form of the product-of-exponentials formula.

        Parameters
        ----------
        q : array_like, shape (..., n)

        Returns
        -------
        ndarray, shape (..., 8)
            The same pose as :meth:`fk_dq` (possibly with the opposite sign).

        Examples
        --------
        >>> import numpy as np
        >>> from dqlab import dualquat
        >>> from dqlab.models import ur3
        >>> robot = ur3()
        >>> q = [0, -np.pi / 2, 0, -np.pi / 2, 0, 0]
        >>> Q = robot.fk_dq_screw(q)
        >>> tcp = dualquat.dual_quaternion_apply(Q, [0.0, 0.0, 0.2])   # 0.2 m along flange z
        >>> tcp.round(5) + 0.0
        array([ 0.     , -0.39425,  0.69415])
        """
        return self._chain.screw_dual_quaternion(self.check_joints(q))

    # -- differential kinematics ----------------------------------------------------------
    def jacobian(self, q: ArrayLike) -> NDArray[np.float64]:
        r"""Geometric Jacobian at the tool centre point, in the world frame, linear rows first.

        Column :math:`i` for a revolute joint about the unit axis :math:`z_i` through
        :math:`o_i`, and for a prismatic joint along :math:`z_i`:

        .. math::

           J_i = \begin{pmatrix} z_i \times (p_T - o_i) \\ z_i \end{pmatrix}
           \quad\text{(revolute)},\qquad
           J_i = \begin{pmatrix} z_i \\ 0 \end{pmatrix}
           \quad\text{(prismatic)},

        where :math:`p_T` is the TCP position (see :meth:`joint_axes`). Then
        :math:`(\dot p_T, \omega) = J(q)\, \dot q` with :math:`\omega` the tool's angular
        velocity in the world frame. For standard DH the axis of joint :math:`i` is the z
        axis of frame :math:`i-1`; for modified DH it is the z axis of frame :math:`i`.
        This is the package's one geometric Jacobian (:mod:`dqlab.jacobian` builds on it).

        Parameters
        ----------
        q : array_like, shape (..., n)

        Returns
        -------
        ndarray, shape (..., 6, n)

        Examples
        --------
        The UR3 report's Jacobian (modified DH) at its joint angles, first column:

        >>> import numpy as np
        >>> from dqlab.models import ur3_mdh
        >>> J = ur3_mdh().jacobian([0.1, -0.5, 0.8, -0.2, 0.5, 0.1])
        >>> J[:, 0].round(8)
        array([-0.49781088, -0.08817691,  0.        ,  0.        ,  0.        ,  1.        ])
        """
        return self._chain.jacobian(q)

    def fk_with_jacobian(self, q: ArrayLike
                         ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        r""":meth:`fk` and :meth:`jacobian` at the same joint vectors, from one product.

        The running product of the forward kinematics passes through every joint's frame,
        which is all the Jacobian needs; a Newton-type solver that wants both at each
        iterate computes the chain once.

        Parameters
        ----------
        q : array_like, shape (..., n)

        Returns
        -------
        X : ndarray, shape (..., 4, 4)
            As :meth:`fk`.
        J : ndarray, shape (..., 6, n)
            As :meth:`jacobian`.

        Examples
        --------
        >>> import numpy as np
        >>> from dqlab.models import ur3
        >>> robot = ur3()
        >>> q = np.array([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])
        >>> X, J = robot.fk_with_jacobian(q)
        >>> bool(np.array_equal(X, robot.fk(q)) and np.array_equal(J, robot.jacobian(q)))
        True
        """
        return self._chain.pose_and_jacobian(q)

    # -- printing -------------------------------------------------------------------------
    def dh_table(self) -> str:
        """The parameter table as text, in the robot's own convention.

        Angles are printed in degrees, lengths in metres. For modified DH the columns are
        the course notes' :math:`\\sigma_i, \\alpha_{i-1}, a_{i-1}, \\theta_i, r_i`. The
        title names the convention unless the robot's name already does.

        Returns
        -------
        str

        Examples
        --------
        >>> from dqlab.models import ur3
        >>> print(ur3().dh_table())
        UR3 (standard DH, 6 joints)
          i  joint  theta_i [deg]  d_i [m]  a_i [m]   alpha_i [deg]  limits
          1  R      q1             0.1519   0         90             [-360, 360] deg
          2  R      q2             0        -0.24365  0              [-360, 360] deg
          3  R      q3             0        -0.21325  0              [-360, 360] deg
          4  R      q4             0.11235  0         90             [-360, 360] deg
          5  R      q5             0.08535  0         -90            [-360, 360] deg
          6  R      q6             0.0819   0         0              -
        """
        rows = []
        for i, lk in enumerate(self._links, start=1):
            if lk.is_revolute:
                theta = _var("q", i, lk.theta_offset, degrees=True)
                d = _num(lk.d)
                lim = _limits(lk.limits, degrees=True)
            else:
                theta = _num(math.degrees(lk.theta_offset))
                d = _var("q", i, lk.d, degrees=False)
                lim = _limits(lk.limits, degrees=False)
            rows.append((str(i), "R" if lk.is_revolute else "P", theta, d, _num(lk.a),
                         _num(math.degrees(lk.alpha)), lim))
        if self._convention == "dh":
            convention = "standard DH"
            header = ("i", "joint", "theta_i [deg]", "d_i [m]", "a_i [m]", "alpha_i [deg]",
                      "limits")
        else:
            convention = "modified DH"
            header = ("i", "sigma", "alpha_i-1 [deg]", "a_i-1 [m]", "theta_i [deg]",
                      "r_i [m]", "limits")
            rows = [(r[0], str(int(r[1] == "P")), r[5], r[4], r[2], r[3], r[6]) for r in rows]
        name = self.name or "robot"
        notes = [f"{self.n} joints"]
        if convention.lower() not in name.lower():      # unless the name already says it
            notes.insert(0, convention)
        if name.endswith(")"):                          # no second pair of parentheses
            title = ", ".join([name] + notes)
        else:
            title = f"{name} ({', '.join(notes)})"
        widths = [max(len(header[k]), *(len(r[k]) for r in rows)) for k in range(7)]

        def fmt(cells):
            return "  " + "  ".join(c.ljust(w) for c, w in zip(cells, widths, strict=True)).rstrip()

        lines = [title, fmt(header)] + [fmt(r) for r in rows]
        extra = []
        if not np.allclose(self._base, np.eye(4)):
            extra.append("base X_W0 =\n" + _matrix_text(self._base))
        if not np.allclose(self._tool, np.eye(4)):
            extra.append("tool X_nT =\n" + _matrix_text(self._tool))
        return "\n".join(lines + extra)

    def __repr__(self):
        return f"Robot({self.name!r}, convention={self._convention!r}, n={self.n})"


def _num(x):
    """Short number text: up to 6 significant digits, no trailing zeros."""
    if abs(x) < 1e-12:
        return "0"
    return f"{x:.6g}"


def _var(symbol, i, offset, degrees):
    name = f"{symbol}{i}"
    if abs(offset) < 1e-12:
        return name
    value = math.degrees(offset) if degrees else offset
    sign = "+" if value > 0 else "-"
    return f"{name} {sign} {_num(abs(value))}"


def _limits(limits, degrees):
    lo, hi = limits
    if math.isinf(lo) and math.isinf(hi):
        return "-"
    if degrees:
        return f"[{_num(math.degrees(lo))}, {_num(math.degrees(hi))}] deg"
    return f"[{_num(lo)}, {_num(hi)}] m"


def _matrix_text(T):
    return "\n".join("  " + " ".join(f"{v:9.5f}" for v in row) for row in T)
