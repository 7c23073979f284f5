"""The result type shared by every inverse-kinematics solver in :mod:`dqlab.ik`."""

from dataclasses import dataclass, field

import numpy as np

from .._checks import check_tolerance, short_repr


@dataclass(repr=False)
class IKResult:
    """Solutions of an inverse-kinematics problem, for one target or a batch.

    Attributes
    ----------
    solutions : ndarray, shape (..., k, n)
        Joint vectors in radians (metres for prismatic joints). Rows where ``valid`` is
        False hold zeros, never NaN.
    valid : ndarray of bool, shape (..., k)
        Which rows are solutions that reproduce the target within the solver's tolerance.
    position_error : ndarray, shape (..., k)
        Distance in metres between the forward kinematics of each row and the target.
    rotation_error : ndarray, shape (..., k)
        Rotation angle in radians between the forward kinematics of each row and the target.
    flags : dict of str to ndarray of bool, shape (...)
        Solver-specific conditions, for example ``"wrist_singular"`` or ``"unreachable"``.
    reason : ndarray of str, shape (...)
        Why a target has no valid solution (empty string when it has one).
    history : dict of str to ndarray, optional
        What an iterative solver records per iteration when asked (see
        :func:`dqlab.ik.damped_least_squares.numerical`); None otherwise.
    row_names : tuple of str, optional
        What each of the ``k`` rows stands for (for :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`, the
        branches of :data:`~dqlab.ik.ur_closed_form.SOLUTION_ORDER`, such as
        ``"left up noflip"``); printed by ``repr``.

    Notes
    -----
    ``repr`` (and ``print``) give a short summary, not the arrays: for one target a line
    per row (its name, whether it is valid, its errors and its joint values in degrees),
    for a batch the counts of valid rows, the targets without a solution by reason, the
    flags that are set and the largest error of a valid row. The solutions a target has
    beyond its rows (a calibrated UR near a singularity) are in :attr:`more`.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur5e
    >>> from dqlab.ik import ur
    >>> robot = ur5e().with_tool(z=0.15)
    >>> print(ur(robot, robot.fk([0.3, -1.2, 1.1, -0.4, 0.9, 0.2])))
    IKResult: one target, 8 of 8 rows valid; flags: none
      row  name               valid  err [m]  err [rad]  q [deg]
      0    left up noflip     yes    0        0          -137.4 170 67.2 -34.3 105.5 179.1
      1    left up flip       yes    0        0          -137.4 -170.4 60.4 132.9 -105.5 -0.9
      2    left down noflip   yes    0        0          -137.4 -125.8 -67.2 36 105.5 179.1
      3    left down flip     yes    0        0          -137.4 -112.7 -60.4 -164 -105.5 -0.9
      4    right up noflip    yes    0        0          17.2 -68.8 63 -22.9 51.6 11.5
      5    right up flip      yes    0        0          17.2 -53 64.7 139.7 -51.6 -168.5
      6    right down noflip  yes    0        0          17.2 -8.5 -63 42.9 51.6 11.5
      7    right down flip    yes    0        0          17.2 8.7 -64.7 -152.7 -51.6 -168.5
    """

    solutions: np.ndarray
    valid: np.ndarray
    position_error: np.ndarray
    rotation_error: np.ndarray
    flags: dict = field(default_factory=dict)
    reason: np.ndarray = None
    history: dict = None
    row_names: tuple = None

    _more: "IKResult | None" = field(default=None, repr=False)

    def __post_init__(self):
        if self.reason is None:
            self.reason = np.full(np.shape(self.valid)[:-1], "", dtype=object)

    @property
    def more(self) -> "IKResult":
        """The solutions of each target beyond its ``k`` rows, shape (..., m, n), valid where
        there is one: an :class:`IKResult` with m = 0 rows when the solver has no more.

        A calibrated UR within about its gap of a singularity of its nearest exact arm may
        reach a pose in ten or twelve ways (a general 6R arm has up to 16), while its rows
        are the exact arm's eight branches: :func:`dqlab.ik.ur <dqlab.ik.ur_solver.ur>`
        gives the others here, in eight rows. :attr:`count` counts the rows only;
        :func:`~dqlab.ik.solutions.closest_solution` and :meth:`best` choose among both.
        """
        if self._more is None:
            batch, n = np.shape(self.valid)[:-1], np.shape(self.solutions)[-1]
            return IKResult(np.zeros(batch + (0, n)), np.zeros(batch + (0,), dtype=bool),
                            np.zeros(batch + (0,)), np.zeros(batch + (0,)))
        return self._more

    @property
    def count(self):
        """Number of valid solutions per target, shape (...)."""
        return np.count_nonzero(self.valid, axis=-1)

    @property
    def success(self):
        """True where at least one valid solution exists, shape (...)."""
        return self.count > 0

    def best(self, q_ref) -> np.ndarray:
        """The valid solution closest to ``q_ref`` (shape (..., n)) for each target.

        Distance is measured joint-wise with angle wrapping, and the row is returned as the
        solver gives it: :func:`dqlab.ik.solutions.closest_solution` with ``wrapped=True``
        (without it, the row comes as the equivalent nearest ``q_ref``, within joint limits
        if given). Raises ``ValueError`` if some target has no valid solution.
        """
        from .solutions import closest_solution

        return closest_solution(self, q_ref, wrapped=True)

    def __repr__(self):
        return summary(self)


def _short(x):
    """A number in a few significant digits (0 for an exact zero)."""
    return "0" if x == 0.0 else f"{x:.2g}"


def summary(result: IKResult) -> str:
    """The text of ``repr(result)``: a short summary of an :class:`IKResult`.

    Parameters
    ----------
    result : IKResult

    Returns
    -------
    str
        For one target, a title line (valid rows, solutions beyond them, flags set) and one
        line per row: its name (``row_names``, else its index), whether it is valid, its
        position and rotation errors and its joints in degrees (rounded to 0.1), then one
        line per solution beyond the rows (:attr:`IKResult.more`). For a batch, the title
        line, the number of targets by count of valid rows, the targets with solutions
        beyond the rows, the targets without a solution grouped by reason, the flags set
        (on how many targets) and the largest error of a valid row.

    Examples
    --------
    >>> import numpy as np
    >>> from dqlab.models import ur3
    >>> from dqlab.ik import ur
    >>> robot = ur3()
    >>> X = robot.fk([[0.3, -1.2, 1.1, -0.4, 0.9, 0.2], [0, -np.pi / 2, 0, -np.pi / 2, 0, 0]])
    >>> X[1, 2, 3] += 1.0                  # out of reach
    >>> print(summary(ur(robot, X)))              # doctest: +ELLIPSIS
    IKResult: 2 targets (shape (2,)), rows of 8 branches x 6 joints
      targets with 8 valid rows: 1
      targets with 0 valid rows: 1
      no solution: 1 target: elbow: the wrist-1 point is farther from the shoulder than ...
      flags: unreachable on 1 target
      largest error of a valid row: 0 m, 0 rad
    """
    valid = np.asarray(result.valid)
    k, n = np.shape(result.solutions)[-2:]
    names = (tuple(result.row_names) if result.row_names is not None
             else tuple(str(i) for i in range(k)))
    flags = {name: np.asarray(f) for name, f in (result.flags or {}).items()}
    more = result.more if isinstance(result, IKResult) else None
    more_count = (np.zeros(valid.shape[:-1], dtype=int) if more is None
                  else np.count_nonzero(more.valid, axis=-1))
    if valid.ndim == 1:
        set_ = [name for name, f in flags.items() if bool(f)]
        beyond = f", {int(more_count)} more beyond them" if more_count else ""
        lines = [f"IKResult: one target, {int(valid.sum())} of {k} rows valid{beyond}; flags: "
                 f"{', '.join(set_) or 'none'}"]
        if result.reason is not None and str(result.reason):
            lines.append(f"  no solution: {result.reason}")
        pe, re = np.asarray(result.position_error), np.asarray(result.rotation_error)
        table = [("row", "name", "valid", "err [m]", "err [rad]", "q [deg]")]
        for i in range(k):
            q = " ".join("0" if abs(v) < 0.05 else f"{v:.1f}".rstrip("0").rstrip(".")
                         for v in np.degrees(result.solutions[i]))
            table.append((str(i), names[i], "yes" if valid[i] else "no", _short(pe[i]),
                          _short(re[i]), q if valid[i] else "-"))
        for j, i in enumerate(np.flatnonzero(more.valid) if more_count else ()):
            q = " ".join("0" if abs(v) < 0.05 else f"{v:.1f}".rstrip("0").rstrip(".")
                         for v in np.degrees(more.solutions[i]))
            table.append((f"+{j + 1}", "(more)", "yes", _short(more.position_error[i]),
                          _short(more.rotation_error[i]), q))
        widths = [max(len(r[c]) for r in table) for c in range(5)]
        lines += ["  " + "  ".join(c.ljust(w) for c, w in zip(r, widths + [0], strict=True))
                  .rstrip() for r in table]
        return "\n".join(lines)
    batch = valid.shape[:-1]
    count = valid.sum(axis=-1)
    label = "branches" if result.row_names is not None else "rows"
    lines = [f"IKResult: {int(np.prod(batch))} targets (shape {batch}), rows of {k} {label} "
             f"x {n} joints"]
    for c in sorted(set(count.ravel().tolist()), reverse=True):
        lines.append(f"  targets with {c} valid rows: {int(np.sum(count == c))}")
    if np.any(more_count):
        lines.append(f"  targets with solutions beyond the rows (result.more): "
                     f"{int(np.count_nonzero(more_count))}, {int(more_count.sum())} solutions")
    if result.reason is not None:
        reasons = np.asarray(result.reason, dtype=object)[count == 0]
        for why in sorted(set(str(r) for r in reasons)):
            m = int(sum(str(r) == why for r in reasons))
            lines.append(f"  no solution: {m} target{'s' * (m != 1)}: {why or '(no reason given)'}")
    set_ = [(name, int(np.sum(f))) for name, f in flags.items() if np.any(f)]
    lines.append("  flags: " + (", ".join(f"{name} on {m} target{'s' * (m != 1)}"
                                          for name, m in set_) or "none"))
    if valid.any():
        pe = np.asarray(result.position_error)[valid].max()
        re = np.asarray(result.rotation_error)[valid].max()
        lines.append(f"  largest error of a valid row: {_short(pe)} m, {_short(re)} rad")
    return "\n".join(lines)


def finish(solutions: np.ndarray, valid: np.ndarray, position_error: np.ndarray,
           rotation_error: np.ndarray, flags: dict, reason: np.ndarray | None = None,
           more: IKResult | None = None) -> IKResult:
    """The :class:`IKResult` of a solver, with the rows that are not valid set to zero.

    Every solver ends here, so that an invalid row never carries a NaN or a half-computed
    angle a caller could mistake for a solution. ``solutions`` is the solver's own array
    and is zeroed in place.

    Parameters
    ----------
    solutions : ndarray, shape (..., k, n)
    valid : ndarray of bool, shape (..., k)
    position_error, rotation_error : ndarray, shape (..., k)
    flags : dict of str to ndarray of bool, shape (...)
    reason : ndarray of str, shape (...), optional
    more : IKResult, optional
        The solutions beyond the rows (:attr:`IKResult.more`), already finished.

    Returns
    -------
    IKResult

    Examples
    --------
    >>> import numpy as np
    >>> result = finish(np.full((2, 3), np.nan), np.array([False, False]), np.ones(2),
    ...                 np.zeros(2), {})
    >>> result.solutions
    array([[0., 0., 0.],
           [0., 0., 0.]])
    """
    if not valid.all():                       # by row numbers, faster than a 2-d mask
        if solutions.flags.c_contiguous:
            rows = solutions.reshape(-1, solutions.shape[-1])
            rows[np.flatnonzero(~valid.ravel())] = 0.0
        elif solutions.flags.f_contiguous:    # targets last in memory: rows are columns
            invalid = np.flatnonzero(~valid.T.ravel())
            for column in solutions.T.reshape(solutions.shape[-1], -1):   # joint by joint
                column[invalid] = 0.0
        else:
            solutions[~valid] = 0.0
    return IKResult(solutions=solutions, valid=valid, position_error=position_error,
                    rotation_error=rotation_error, flags=flags, reason=reason, _more=more)


def check_ur_options(tol, singular_tol, near_tol, pose_tol, residuals) -> tuple:
    """The options of the UR solvers (``dqlab.ik.ur``, and ``calibrated_ur`` called
    directly), checked: the four tolerances as floats >= 0, ``residuals`` one of
    ``"equations"``, ``"fk"``.

    Returns
    -------
    tuple
        ``(tol, singular_tol, near_tol, pose_tol)``.

    Examples
    --------
    >>> check_ur_options(1e-9, 5e-7, 0.01, 1e-9, "equations")
    (1e-09, 5e-07, 0.01, 1e-09)
    >>> check_ur_options(1e-9, 5e-7, 0.01, 1e-9, "eqs")
    Traceback (most recent call last):
    ...
    ValueError: residuals must be 'fk' or 'equations', got 'eqs'
    """
    checked = (check_tolerance(tol, "tol"), check_tolerance(singular_tol, "singular_tol"),
               check_tolerance(near_tol, "near_tol"), check_tolerance(pose_tol, "pose_tol"))
    if not (isinstance(residuals, str) and residuals in ("fk", "equations")):
        raise ValueError(f"residuals must be 'fk' or 'equations', got {short_repr(residuals)}")
    return checked


def target_reasons(failed: np.ndarray, explain) -> np.ndarray:
    """Why each target without a solution failed: ``explain(index)`` for those, ``""`` else.

    Parameters
    ----------
    failed : ndarray of bool, shape (...)
        The targets without a valid solution.
    explain : callable
        ``explain(index)`` returns the text for the target at ``index`` (a tuple).

    Returns
    -------
    ndarray of str (object), shape (...)

    Examples
    --------
    >>> import numpy as np
    >>> target_reasons(np.array([False, True]), lambda i: f"target {i[0]} is out of reach")
    array(['', 'target 1 is out of reach'], dtype=object)
    """
    reason = np.full(np.shape(failed), "", dtype=object)
    if not np.any(failed):
        return reason
    for index in np.argwhere(failed):
        reason[tuple(index)] = explain(tuple(int(i) for i in index))
    return reason
