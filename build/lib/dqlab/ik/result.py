"""The result type shared by every inverse-kinematics solver in :mod:`dqlab.ik`."""

from dataclasses import dataclass, field

import numpy as np

from .._checks import as_float_array
from ..rotations import wrap_angle


@dataclass
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
    """

    solutions: np.ndarray
    valid: np.ndarray
    position_error: np.ndarray
    rotation_error: np.ndarray
    flags: dict = field(default_factory=dict)
    reason: np.ndarray = None
    history: dict = None

    def __post_init__(self):
        if self.reason is None:
            self.reason = np.full(np.shape(self.valid)[:-1], "", dtype=object)

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

        Distance is measured joint-wise with angle wrapping for revolute joints. Raises
        ``ValueError`` if some target has no valid solution.
        """
        n = np.shape(self.solutions)[-1]
        q_ref = as_float_array(q_ref, "q_ref", (n,))[..., None, :]
        if not np.all(self.success):
            raise ValueError("some targets have no valid solution; check result.reason")
        diff = wrap_angle(self.solutions - q_ref)
        dist = np.where(self.valid, np.linalg.norm(diff, axis=-1), np.inf)
        index = np.argmin(dist, axis=-1)
        return np.take_along_axis(self.solutions, index[..., None, None], axis=-2)[..., 0, :]


def finish(solutions: np.ndarray, valid: np.ndarray, position_error: np.ndarray,
           rotation_error: np.ndarray, flags: dict, reason: np.ndarray | None = None
           ) -> IKResult:
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
                    rotation_error=rotation_error, flags=flags, reason=reason)


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
