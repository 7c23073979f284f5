r"""Inertial parameters of a rigid link: mass, centre of mass and inertia tensor.

Each :class:`~dqlab.robot.Link` may carry a :class:`LinkInertia` (``Link(..., inertia=...)``),
expressed in the link's own frame :math:`i` of its Denavit--Hartenberg convention (standard DH:
the frame at the far end of the link, on the next joint's axis; modified DH: the frame on the
link's own joint axis). Both frames are attached to the link, so the numbers are constants.

A link of mass :math:`m` whose centre of mass is at :math:`\mathbf c` (in frame :math:`i`)
and whose inertia tensor about the centre of mass, in the axes of frame :math:`i`, is
:math:`I_c`, moving with the twist :math:`\hat\xi = \omega + \varepsilon\,\mathbf v` (the
angular velocity and the velocity of the body point at the frame's origin, chapter
"Differential kinematics"), has the momentum

.. math::

   \hat h = \mathbf p + \varepsilon\,\mathbf L,\qquad
   \mathbf p = m\,(\mathbf v + \omega \times \mathbf c),\qquad
   \mathbf L = I_c\,\omega + \mathbf c \times \mathbf p,

linear momentum and angular momentum about the frame's origin: a dual vector of the same kind
as a wrench (force :math:`+\ \varepsilon` moment). :meth:`LinkInertia.momentum` is this linear
map, :math:`\hat h = \mathcal M\hat\xi`, and :func:`dqlab.dynamics.inverse_dynamics` builds
on it. The kinetic energy is :math:`T = \tfrac12\,(\omega\cdot\mathbf L + \mathbf v\cdot
\mathbf p)`.

Units are kilograms, metres and kg m^2.
"""

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._checks import as_float_array, check_scalar
from ._formulas import momentum
from .transforms import check_transform

__all__ = ["LinkInertia"]


def _mass(value, name="mass"):
    """A mass, radius or factor: a finite number >= 0 (text and booleans refused by name)."""
    return check_scalar(value, name, minimum=0.0)


def _check_moment_at_origin(mass, point, names):
    r"""A ValueError naming ``names`` (the arguments that placed the body) unless a float
    holds :math:`m\,\lVert\mathbf c\rVert^2`, the size of the parallel-axis term of a
    body of mass ``mass`` whose centre of mass is ``point``."""
    with np.errstate(over="ignore", invalid="ignore"):
        moment = mass * float(point @ point)
    if not math.isfinite(moment):
        raise ValueError(f"{names} are too large: the inertia about the frame's origin, "
                         "m |c|^2, overflows")


def _finite_tensor(tensor, what):
    """``tensor`` if every entry is finite, else a ValueError saying which inputs overflow."""
    if not np.all(np.isfinite(tensor)):
        raise ValueError(f"the inertia tensor of {what} overflows (no finite float holds it)")
    return tensor


class LinkInertia:
    r"""Mass, centre of mass and inertia tensor of one rigid link, in the link's frame.

    Parameters
    ----------
    mass : float
        :math:`m` in kg, :math:`\ge 0`.
    com : array_like, shape (3,)
        :math:`\mathbf c`, the centre of mass in the link's frame, m.
    tensor : array_like, shape (3, 3) or (6,), optional
        :math:`I_c`, the inertia tensor about the centre of mass in the axes of the link's
        frame, kg m^2: a symmetric matrix or its six entries ``(ixx, iyy, izz, ixy, ixz,
        iyz)`` (URDF's order). Zero by default (a point mass).

    Raises
    ------
    ValueError
        If the mass is negative or not finite, the centre of mass is not three finite
        numbers, or the tensor is not symmetric, has a negative principal moment or violates
        the triangle inequality :math:`I_1 + I_2 \ge I_3` of its principal moments (no rigid
        body has such a tensor).

    Notes
    -----
    A :class:`LinkInertia` is immutable; :meth:`scaled`, ``+`` (two bodies welded
    together) and :meth:`moved` return new ones.

    Examples
    --------
    A 2 kg solid sphere of radius 0.05 m centred 0.1 m along x:

    >>> I = LinkInertia.sphere(2.0, [0.1, 0.0, 0.0], radius=0.05)
    >>> I.mass, I.com, I.tensor.diagonal()
    (2.0, array([0.1, 0. , 0. ]), array([0.002, 0.002, 0.002]))
    >>> p, L = I.momentum([0.0, 0.0, 1.0], [0.0, 0.0, 0.0])  # turning about z at 1 rad/s
    >>> p, L                                                # p = m w x c, L = I_O w
    (array([0. , 0.2, 0. ]), array([0.   , 0.   , 0.022]))
    """

    __slots__ = ("mass", "com", "tensor")

    def __init__(self, mass: float, com: ArrayLike, tensor: ArrayLike | None = None):
        mass = _mass(mass)
        com = as_float_array(com, "com", (3,)).copy()
        if com.shape != (3,):
            raise ValueError(f"com must have shape (3,), got shape {com.shape}")
        if tensor is None:
            tensor = np.zeros((3, 3))
        else:
            tensor = as_float_array(tensor, "tensor")
            if tensor.shape == (6,):
                ixx, iyy, izz, ixy, ixz, iyz = tensor
                tensor = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
            if tensor.shape != (3, 3):
                raise ValueError(f"tensor must have shape (3, 3) or (6,), got shape "
                                 f"{tensor.shape}")
        scale = max(float(np.abs(tensor).max()), 1e-300)
        unit = tensor / scale                   # the checks on entries of at most 1: no overflow
        if not np.allclose(unit, unit.T, rtol=0.0, atol=1e-12):
            raise ValueError("tensor must be symmetric")
        tensor = 0.5 * tensor + 0.5 * tensor.T
        moments = np.linalg.eigvalsh(0.5 * (unit + unit.T))
        if moments[0] < -1e-9:
            raise ValueError(f"tensor must be positive semidefinite, got principal moments "
                             f"{(moments * scale).tolist()}")
        if moments[0] + moments[1] < moments[2] - 1e-9:
            raise ValueError(f"tensor violates the triangle inequality I1 + I2 >= I3 of a "
                             f"rigid body: principal moments {(moments * scale).tolist()}")
        with np.errstate(over="ignore", invalid="ignore"):
            at_origin = tensor + mass * (np.dot(com, com) * np.eye(3) - np.outer(com, com))
        if not np.all(np.isfinite(at_origin)):
            raise ValueError("mass, com and tensor are too large: the inertia about the frame's "
                             "origin, I_c + m (|c|^2 I - c c^T), overflows")
        com.flags.writeable = False
        tensor.flags.writeable = False
        set_ = object.__setattr__
        set_(self, "mass", mass)
        set_(self, "com", com)
        set_(self, "tensor", tensor)

    def __setattr__(self, key, value):
        raise AttributeError("LinkInertia is immutable; build a new one")

    def __reduce__(self):       # pickled (for instance by dask) as a call to the constructor
        return LinkInertia, (self.mass, self.com.copy(), self.tensor.copy())

    def __repr__(self):
        return (f"LinkInertia(mass={self.mass!r}, com={self.com.tolist()!r}, "
                f"tensor={self.tensor.tolist()!r})")

    def __eq__(self, other):
        if not isinstance(other, LinkInertia):
            return NotImplemented
        return (self.mass == other.mass and np.array_equal(self.com, other.com)
                and np.array_equal(self.tensor, other.tensor))

    __hash__ = None

    # -- constructors of simple shapes -------------------------------------------------------
    @classmethod
    def sphere(cls, mass: float, centre: ArrayLike, radius: float = 0.0) -> "LinkInertia":
        r"""A solid sphere (a point mass for ``radius = 0``): :math:`I_c = \tfrac25 m r^2 I`.

        Examples
        --------
        >>> float(LinkInertia.sphere(3.0, [0, 0, 0.1]).tensor.max())      # a point mass
        0.0
        """
        mass = _mass(mass)
        radius = _mass(radius, "radius")
        centre = as_float_array(centre, "centre", (3,))
        if centre.shape != (3,):
            raise ValueError(f"centre must be one point of shape (3,), got shape {centre.shape}")
        _check_moment_at_origin(mass, centre, "mass and centre")
        with np.errstate(over="ignore", invalid="ignore"):
            tensor = 0.4 * mass * (radius * radius) * np.eye(3)
        return cls(mass, centre, _finite_tensor(
            tensor, f"a sphere of mass {mass:g} kg and radius {radius:g} m"))

    @classmethod
    def rod(cls, mass: float, start: ArrayLike, end: ArrayLike, radius: float
            ) -> "LinkInertia":
        r"""A solid cylinder of radius :math:`r` from ``start`` to ``end`` (length :math:`\ell`).

        About its centre, along the unit axis :math:`\mathbf u`:

        .. math::

           I_c = \tfrac12 m r^2\,\mathbf u\mathbf u^\top
           + \tfrac1{12} m\,(3r^2 + \ell^2)\,(I - \mathbf u\mathbf u^\top).

        Examples
        --------
        >>> rod = LinkInertia.rod(1.2, [0, 0, 0], [0.3, 0, 0], radius=0.02)
        >>> rod.com, rod.tensor.diagonal().round(6)
        (array([0.15, 0.  , 0.  ]), array([0.00024, 0.00912, 0.00912]))
        """
        mass = _mass(mass)
        radius = _mass(radius, "radius")
        start = as_float_array(start, "start", (3,))
        end = as_float_array(end, "end", (3,))
        if start.shape != (3,) or end.shape != (3,):
            raise ValueError(f"start and end must be points of shape (3,), got shapes "
                             f"{start.shape} and {end.shape}")
        with np.errstate(over="ignore", invalid="ignore"):
            axis = end - start
            size = float(np.abs(axis).max())
        if not math.isfinite(size):
            raise ValueError("start and end are too far apart: their distance overflows")
        with np.errstate(over="ignore", invalid="ignore"):
            unit = axis / size if size > 0 else np.array([0.0, 0.0, 1.0])   # |l| <= 1
            norm = float(np.linalg.norm(unit))
            length = size * norm
            u = unit / norm
            along = np.outer(u, u)
            r2, l2 = radius * radius, length * length
            tensor = (0.5 * mass * r2 * along
                      + mass * (3 * r2 + l2) / 12.0 * (np.eye(3) - along))
        what = f"a rod of mass {mass:g} kg, length {length:g} m and radius {radius:g} m"
        tensor = _finite_tensor(tensor, what)
        centre = 0.5 * start + 0.5 * end
        _check_moment_at_origin(mass, centre, "mass, start and end")
        return cls(mass, centre, tensor)

    # -- derived quantities -------------------------------------------------------------------
    @property
    def tensor_at_origin(self) -> NDArray[np.float64]:
        r""":math:`I_O = I_c + m\,(\lVert\mathbf c\rVert^2 I - \mathbf c\mathbf c^\top)`, the
        inertia tensor about the frame's origin (parallel-axis theorem), shape (3, 3)."""
        c = self.com
        return self.tensor + self.mass * (np.dot(c, c) * np.eye(3) - np.outer(c, c))

    def spatial_matrix(self) -> NDArray[np.float64]:
        r"""The 6x6 matrix of :meth:`momentum` for twists ordered :math:`(\mathbf v, \omega)`
        and momenta ordered :math:`(\mathbf p, \mathbf L)`, as the rows of a geometric
        Jacobian:

        .. math::

           \begin{pmatrix} \mathbf p \\ \mathbf L \end{pmatrix} =
           \begin{pmatrix} m I & -m[\mathbf c]_\times \\ m[\mathbf c]_\times & I_O
           \end{pmatrix}
           \begin{pmatrix} \mathbf v \\ \omega \end{pmatrix}.

        Examples
        --------
        >>> import numpy as np
        >>> G = LinkInertia.sphere(2.0, [0.1, 0.0, 0.0], 0.05).spatial_matrix()
        >>> bool(np.allclose(G, G.T)), G.shape
        (True, (6, 6))
        """
        m, (x, y, z) = self.mass, self.com
        cx = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
        return np.block([[m * np.eye(3), -m * cx], [m * cx, self.tensor_at_origin]])

    def momentum(self, omega: ArrayLike, v: ArrayLike
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        r"""The momentum :math:`\hat h = \mathbf p + \varepsilon\mathbf L` of the link moving
        with the twist :math:`\omega + \varepsilon\mathbf v` (both in the link's frame).

        .. math::

           \mathbf p = m\,(\mathbf v + \omega \times \mathbf c), \qquad
           \mathbf L = I_c\,\omega + \mathbf c \times \mathbf p .

        Parameters
        ----------
        omega, v : array_like, shape (..., 3)
            Angular velocity and velocity of the body point at the frame's origin.

        Returns
        -------
        p, L : ndarray, shape (..., 3)
            Linear momentum and angular momentum about the frame's origin.

        Raises
        ------
        ValueError
            Naming ``omega`` or ``v``: not real vectors of shape (..., 3), NaN or infinity,
            shapes that do not broadcast; or a momentum that overflows.
        """
        omega = as_float_array(omega, "omega", (3,))
        v = as_float_array(v, "v", (3,))
        try:
            np.broadcast_shapes(omega.shape, v.shape)
        except ValueError:
            raise ValueError(f"omega and v must broadcast, got shapes {omega.shape} and "
                             f"{v.shape}") from None
        with np.errstate(over="ignore", invalid="ignore"):
            p, L = momentum(self.mass, self.com, self.tensor, omega, v)
        if not (np.isfinite(p).all() and np.isfinite(L).all()):
            raise ValueError("omega and v are too large: the momentum overflows")
        return p, L

    # -- new inertias from this one ---------------------------------------------------------
    def scaled(self, factor: float) -> "LinkInertia":
        """The same shape with every mass multiplied by ``factor`` (mass and tensor scale,
        the centre of mass stays).

        Examples
        --------
        >>> LinkInertia.sphere(2.0, [0, 0, 0], 0.1).scaled(1.1).mass
        2.2
        """
        factor = _mass(factor, "factor")
        with np.errstate(over="ignore"):
            mass, tensor = self.mass * factor, self.tensor * factor
        if not (math.isfinite(mass) and np.all(np.isfinite(tensor))):
            raise ValueError(f"factor = {factor!r} makes the mass or the tensor overflow")
        return LinkInertia(mass, self.com, tensor)

    def __add__(self, other: "LinkInertia") -> "LinkInertia":
        r"""Two bodies in the same frame welded into one: masses add, the centre of mass is
        the weighted mean, and each tensor moves to it by the parallel-axis theorem.

        Examples
        --------
        >>> a = LinkInertia.sphere(1.0, [0.0, 0, 0])
        >>> b = LinkInertia.sphere(1.0, [0.2, 0, 0])
        >>> (a + b).com, (a + b).tensor.diagonal()
        (array([0.1, 0. , 0. ]), array([0.  , 0.02, 0.02]))
        """
        if not isinstance(other, LinkInertia):
            return NotImplemented
        mass = self.mass + other.mass
        if mass == 0.0:
            return LinkInertia(0.0, self.com)
        with np.errstate(over="ignore", invalid="ignore"):
            com = (self.mass * self.com + other.mass * other.com) / mass
            tensor = np.zeros((3, 3))
            for part in (self, other):
                d = part.com - com
                tensor += part.tensor + part.mass * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
        if not (math.isfinite(mass) and np.all(np.isfinite(com))):
            raise ValueError("the welded body's mass or centre of mass overflows")
        return LinkInertia(mass, com, _finite_tensor(
            tensor, "the welded body (the parts are too heavy or too far apart)"))

    def moved(self, X_AB: ArrayLike) -> "LinkInertia":
        r"""The same body described in frame A, when ``self`` describes it in frame B and
        ``X_AB`` is the pose of B in A: :math:`\mathbf c_A = R\,\mathbf c_B + \mathbf t`,
        :math:`I_A = R\, I_B R^\top`.

        Parameters
        ----------
        X_AB : array_like, shape (4, 4)
            A rigid transform (orthonormal rotation block of determinant +1 within 1e-9, last
            row ``(0, 0, 0, 1)``): a scaled or sheared block would change the body, not the
            frame it is seen from.

        Raises
        ------
        ValueError
            If ``X_AB`` is not one rigid 4x4 transform (the message names ``X_AB``).

        Examples
        --------
        >>> import numpy as np
        >>> X = np.eye(4); X[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]; X[0, 3] = 1.0
        >>> LinkInertia.rod(1.0, [0, 0, 0], [0.2, 0, 0], 0.0).moved(X).com
        array([1. , 0.1, 0. ])
        """
        X = as_float_array(X_AB, "X_AB", (4, 4))
        if X.shape != (4, 4):
            raise ValueError(f"X_AB must be one 4x4 transform, got shape {X.shape}")
        X = check_transform(X, 1e-9, "X_AB")
        R = X[:3, :3]
        return LinkInertia(self.mass, R @ self.com + X[:3, 3], R @ self.tensor @ R.T)
