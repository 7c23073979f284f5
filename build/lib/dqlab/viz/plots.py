"""matplotlib figures with one look: frames, vectors, planar and spatial arms, complex numbers.

Every function draws into a matplotlib ``Axes`` it is given (or creates one) and returns
that ``Axes``, so that a chapter can combine several drawings in one figure. Frames are
drawn with x red, y green, z blue, as in the 3D scenes of :mod:`dqlab.viz.scene`; axes get
labels in metres and an equal aspect ratio, so that right angles look right.
"""

import matplotlib.pyplot as plt
import numpy as np

__all__ = ["axes_3d", "set_axes_equal", "plot_frame", "plot_frames", "plot_vector",
           "plot_planar_arm", "plot_arm", "plot_complex"]

AXIS_COLORS = ("#d62728", "#2ca02c", "#1f77b4")  # x, y, z
ARM_COLOR = "#3a3f44"
JOINT_FACE = "#ffffff"
TIP_COLOR = "#e67e22"
VECTOR_COLOR = "#8e44ad"


def _is_3d(ax):
    return getattr(ax, "name", "") == "3d"


def axes_3d(ax=None, *, figsize=(5.0, 5.0), title=None):
    """Return 3D axes labelled in metres (creating a figure when ``ax`` is None).

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D, optional
        Axes to prepare; a new figure and axes when omitted.
    figsize : tuple of float
        Size in inches of a new figure.
    title : str, optional
        Title of the axes.

    Returns
    -------
    mpl_toolkits.mplot3d.axes3d.Axes3D

    Examples
    --------
    >>> ax = axes_3d(title="world frame")
    >>> ax.get_xlabel()
    'x (m)'
    >>> plt.close(ax.figure)
    """
    if ax is None:
        fig = plt.figure(figsize=figsize)
        ax = fig.add_subplot(projection="3d")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    if title is not None:
        ax.set_title(title)
    return ax


def _axes_2d(ax, figsize=(5.0, 5.0)):
    if ax is None:
        _, ax = plt.subplots(figsize=figsize)
    return ax


def set_axes_equal(ax, points=None, *, margin=0.1):
    """Give ``ax`` equal scales on every axis, framing ``points`` (or what is drawn).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        2D or 3D axes.
    points : array_like, shape (k, 2) or (k, 3), optional
        Points that must be visible; the current data limits when omitted.
    margin : float
        Extra room around the points, as a fraction of their extent.

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> ax = axes_3d()
    >>> ax = set_axes_equal(ax, [[0, 0, 0], [1, 2, 0.5]])
    >>> [round(float(hi - lo), 6) for lo, hi in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())]
    [2.4, 2.4, 2.4]
    >>> plt.close(ax.figure)
    """
    dims = 3 if _is_3d(ax) else 2
    if points is None:
        if dims == 3:
            lims = np.array([ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d()])
        else:
            lims = np.array([ax.get_xlim(), ax.get_ylim()])
        lo, hi = lims[:, 0], lims[:, 1]
    else:
        P = np.asarray(points, dtype=float).reshape(-1, dims)
        lo, hi = P.min(axis=0), P.max(axis=0)
    center = (lo + hi) / 2
    half = max(float(np.max(hi - lo)) / 2, 1e-9) * (1 + 2 * margin)
    if dims == 3:
        ax.set_xlim3d(center[0] - half, center[0] + half)
        ax.set_ylim3d(center[1] - half, center[1] + half)
        ax.set_zlim3d(center[2] - half, center[2] + half)
        ax.set_box_aspect((1, 1, 1))
    else:
        ax.set_xlim(center[0] - half, center[0] + half)
        ax.set_ylim(center[1] - half, center[1] + half)
        ax.set_aspect("equal", adjustable="box")
    return ax


def plot_frame(ax, X, *, label=None, length=0.1, linewidth=2.0):
    """Draw the frame ``X`` as three arrows: x red, y green, z blue.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
        3D axes (see :func:`axes_3d`).
    X : array_like, shape (4, 4)
        Pose ``X_WF`` of the frame F in the axes' frame W.
    label : str, optional
        Name written at the origin, e.g. ``"{E}"``.
    length : float
        Length of each axis arrow, metres.
    linewidth : float
        Width of the arrows, points.

    Returns
    -------
    mpl_toolkits.mplot3d.axes3d.Axes3D

    Examples
    --------
    >>> ax = plot_frame(axes_3d(), np.eye(4), label="{W}")
    >>> len(ax.collections)
    3
    >>> plt.close(ax.figure)
    """
    X = np.asarray(X, dtype=float)
    if X.shape != (4, 4):
        raise ValueError(f"X must have shape (4, 4), got shape {X.shape}")
    p, R = X[:3, 3], X[:3, :3]
    for k in range(3):
        d = R[:, k] * length
        ax.quiver(p[0], p[1], p[2], d[0], d[1], d[2], color=AXIS_COLORS[k],
                  linewidth=linewidth, arrow_length_ratio=0.2)
    if label:
        ax.text(p[0], p[1], p[2], f"  {label}", fontsize=10)
    return ax


def plot_frames(ax, frames, *, labels=None, length=0.1, linewidth=2.0):
    """Draw several frames (e.g. the FK frames of a robot) with :func:`plot_frame`.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
        3D axes.
    frames : array_like, shape (k, 4, 4)
        Poses of the frames.
    labels : sequence of str, optional
        One label per frame; ``"{0}", "{1}", ...`` when omitted, none when ``False``.
    length, linewidth : float
        As in :func:`plot_frame`.

    Returns
    -------
    mpl_toolkits.mplot3d.axes3d.Axes3D

    Examples
    --------
    >>> X = np.tile(np.eye(4), (2, 1, 1)); X[1, :3, 3] = [0.3, 0, 0]
    >>> ax = plot_frames(axes_3d(), X)
    >>> [t.get_text().strip() for t in ax.texts]
    ['{0}', '{1}']
    >>> plt.close(ax.figure)
    """
    F = np.asarray(frames, dtype=float).reshape(-1, 4, 4)
    if labels is None:
        labels = [f"{{{i}}}" for i in range(len(F))]
    elif labels is False:
        labels = [None] * len(F)
    for X, label in zip(F, labels, strict=True):
        plot_frame(ax, X, label=label, length=length, linewidth=linewidth)
    return ax


def plot_vector(ax, v, origin=None, *, color=VECTOR_COLOR, label=None, linewidth=2.0):
    """Draw the vector ``v`` as an arrow from ``origin`` (2D or 3D axes).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        2D axes for a 2-vector, 3D axes for a 3-vector.
    v : array_like, shape (2,) or (3,)
        The vector.
    origin : array_like, optional
        Start of the arrow; the origin by default.
    color : str
        Colour of the arrow.
    label : str, optional
        Text written at the arrow's tip.
    linewidth : float
        Width, points.

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> fig, ax = plt.subplots()
    >>> ax = plot_vector(ax, [1, 2], label="v")
    >>> ax.texts[-1].get_text()
    ' v'
    >>> plt.close(fig)
    """
    v = np.asarray(v, dtype=float)
    o = np.zeros_like(v) if origin is None else np.asarray(origin, dtype=float)
    if _is_3d(ax):
        if v.shape != (3,):
            raise ValueError(f"v must have shape (3,) on 3D axes, got shape {v.shape}")
        ax.quiver(o[0], o[1], o[2], v[0], v[1], v[2], color=color, linewidth=linewidth,
                  arrow_length_ratio=0.12)
        if label:
            tip = o + v
            ax.text(tip[0], tip[1], tip[2], f" {label}", color=color, fontsize=10)
    else:
        if v.shape != (2,):
            raise ValueError(f"v must have shape (2,) on 2D axes, got shape {v.shape}")
        ax.annotate("", xy=tuple(o + v), xytext=tuple(o),
                    arrowprops=dict(arrowstyle="-|>", color=color, lw=linewidth,
                                    shrinkA=0, shrinkB=0))
        ax.update_datalim(np.array([o, o + v]))
        ax.autoscale_view()
        if label:
            ax.text(*(o + v), f" {label}", color=color, fontsize=10)
    return ax


def plot_planar_arm(ax, joints, *, label=None, color=ARM_COLOR, show_tip=True):
    """Draw a planar arm from the positions of its joints (complex numbers or xy pairs).

    Parameters
    ----------
    ax : matplotlib.axes.Axes or None
        2D axes; a new figure when None.
    joints : array_like, complex shape (k,) or real shape (k, 2)
        Base, every joint and the tip, in order (e.g. from
        ``dqlab.complex.planar_arm_joints``).
    label : str, optional
        Legend entry of the arm.
    color : str
        Colour of the links.
    show_tip : bool
        Mark the tip with an orange dot.

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> z = np.cumsum([0, 1.0, 0.8 * np.exp(0.5j)])
    >>> ax = plot_planar_arm(None, z)
    >>> ax.get_xlabel(), ax.get_aspect()
    ('x (m)', 1.0)
    >>> plt.close(ax.figure)
    """
    ax = _axes_2d(ax)
    J = np.asarray(joints)
    if np.iscomplexobj(J):
        xy = np.column_stack([J.real, J.imag]).astype(float)
    else:
        xy = np.asarray(J, dtype=float)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f"joints must be complex (k,) or real (k, 2), got {xy.shape}")
    ax.plot(xy[:, 0], xy[:, 1], "-", color=color, linewidth=4, solid_capstyle="round",
            label=label, zorder=2)
    ax.plot(xy[:-1, 0], xy[:-1, 1], "o", markersize=8, markerfacecolor=JOINT_FACE,
            markeredgecolor=color, markeredgewidth=2, zorder=3)
    ax.plot(xy[0, 0], xy[0, 1], "s", markersize=11, color=color, zorder=3)
    if show_tip:
        ax.plot(xy[-1, 0], xy[-1, 1], "o", markersize=7, color=TIP_COLOR, zorder=4)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, alpha=0.3)
    ax.set_aspect("equal", adjustable="datalim")
    return ax


def plot_arm(ax, frames, *, label=None, color=ARM_COLOR, frame_length=None,
             show_frames=True):
    """Draw a serial arm as a 3D stick figure through the origins of its FK frames.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D or None
        3D axes; a new figure when None.
    frames : array_like, shape (n + 1, 4, 4)
        Base and body frames, as ``robot.fk(q, all_frames=True)`` returns them.
    label : str, optional
        Legend entry.
    color : str
        Colour of the links.
    frame_length : float, optional
        Length of the drawn frame axes; 15 % of the arm's extent by default.
    show_frames : bool
        Draw the base and flange frames.

    Returns
    -------
    mpl_toolkits.mplot3d.axes3d.Axes3D

    Examples
    --------
    >>> F = np.tile(np.eye(4), (3, 1, 1))
    >>> F[1, :3, 3] = [0, 0, 0.15]; F[2, :3, 3] = [0.25, 0, 0.15]
    >>> ax = plot_arm(None, F)
    >>> [round(float(hi - lo), 3) for lo, hi in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())]
    [0.3, 0.3, 0.3]
    >>> plt.close(ax.figure)
    """
    F = np.asarray(frames, dtype=float)
    if F.ndim != 3 or F.shape[1:] != (4, 4):
        raise ValueError(f"frames must have shape (n + 1, 4, 4), got shape {F.shape}")
    if ax is None:
        ax = axes_3d()
    P = F[:, :3, 3]
    ax.plot(P[:, 0], P[:, 1], P[:, 2], "-", color=color, linewidth=4, label=label)
    ax.scatter(P[1:-1, 0], P[1:-1, 1], P[1:-1, 2], s=45, facecolor=JOINT_FACE,
               edgecolor=color, linewidths=1.5, depthshade=False)
    ax.scatter(*P[-1], s=40, color=TIP_COLOR, depthshade=False)
    extent = max(float(np.ptp(P, axis=0).max()), 1e-3)
    if show_frames:
        length = 0.15 * extent if frame_length is None else frame_length
        plot_frame(ax, F[0], length=length)
        plot_frame(ax, F[-1], length=length)
    set_axes_equal(ax, np.vstack([P, P[:1] * 0]))
    return ax


def plot_complex(ax, z, *, labels=None, arrows=True, unit_circle=False, color=VECTOR_COLOR):
    """Plot complex numbers as points (or arrows from 0) in the complex plane.

    Parameters
    ----------
    ax : matplotlib.axes.Axes or None
        2D axes; a new figure when None.
    z : complex or array_like of complex
        The numbers.
    labels : sequence of str, optional
        One label per number.
    arrows : bool
        Draw arrows from the origin (otherwise dots).
    unit_circle : bool
        Draw the unit circle (where rotations live).
    color : str
        Colour of the arrows or dots.

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> ax = plot_complex(None, [1 + 1j, np.exp(1j * np.pi / 3)], labels=["z", "w"],
    ...                   unit_circle=True)
    >>> ax.get_xlabel(), ax.get_ylabel()
    ('Re', 'Im')
    >>> plt.close(ax.figure)
    """
    ax = _axes_2d(ax)
    Z = np.atleast_1d(np.asarray(z, dtype=complex))
    if unit_circle:
        t = np.linspace(0, 2 * np.pi, 200)
        ax.plot(np.cos(t), np.sin(t), ":", color="0.5", linewidth=1)
    ax.axhline(0, color="0.6", linewidth=0.8, zorder=0)
    ax.axvline(0, color="0.6", linewidth=0.8, zorder=0)
    labels = [None] * len(Z) if labels is None else list(labels)
    for w, label in zip(Z, labels, strict=True):
        if arrows:
            plot_vector(ax, [w.real, w.imag], color=color, label=label)
        else:
            ax.plot(w.real, w.imag, "o", color=color)
            if label:
                ax.text(w.real, w.imag, f" {label}", color=color, fontsize=10)
    pts = np.column_stack([Z.real, Z.imag, ])
    if unit_circle:
        pts = np.vstack([pts, [[-1, -1], [1, 1]]])
    set_axes_equal(ax, np.vstack([pts, [[0, 0]]]))
    ax.set_xlabel("Re")
    ax.set_ylabel("Im")
    ax.grid(True, alpha=0.3)
    return ax
