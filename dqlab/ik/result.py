"""The result type shared by every inverse-kinematics solver in :mod:`dqlab.ik`."""

from dataclasses import dataclass, field

import numpy as np

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
    """

    solutions: np.ndarray
    valid: np.ndarray
    position_error: np.ndarray
    rotation_error: np.ndarray
    flags: dict = field(default_factory=dict)
    reason: np.ndarray = None

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

    def best(self, q_ref):
        """The valid solution closest to ``q_ref`` (shape (..., n)) for each target.

        Distance is measured joint-wise with angle wrapping for revolute joints. Raises
        ``ValueError`` if some target has no valid solution.
        """
        if not np.all(self.success):
            raise ValueError("some targets have no valid solution; check result.reason")
        q_ref = np.asarray(q_ref, dtype=float)[..., None, :]
        diff = wrap_angle(self.solutions - q_ref)
        dist = np.where(self.valid, np.linalg.norm(diff, axis=-1), np.inf)
        index = np.argmin(dist, axis=-1)
        return np.take_along_axis(self.solutions, index[..., None, None], axis=-2)[..., 0, :]
