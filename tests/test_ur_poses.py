"""UR pose vectors: rotation vectors checked against scipy and pyquaternion, incl. near 0 and pi."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from pyquaternion import Quaternion as PyQuaternion
from scipy.spatial.transform import Rotation

import dqlab
from dqlab.ur import poses as P

RNG = np.random.default_rng(13)


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _random_transforms(rng, n):
    R = Rotation.random(n, random_state=rng).as_matrix()
    T = np.zeros((n, 4, 4))
    T[:, :3, :3] = R
    T[:, :3, 3] = rng.uniform(-0.5, 0.5, (n, 3))
    T[:, 3, 3] = 1.0
    return T


def test_round_trip_transform_pose_transform():
    T = _random_transforms(RNG, 500)
    p = P.pose_from_transform(T)
    assert p.shape == (500, 6)
    np.testing.assert_allclose(P.transform_from_pose(p), T, atol=1e-14)
    assert np.all(np.linalg.norm(p[:, 3:], axis=-1) <= np.pi + 1e-12)


def test_rotation_vector_matches_scipy_as_rotvec():
    R = Rotation.random(1000, random_state=RNG)
    ours = P.rotation_vector_from_matrix(R.as_matrix())
    np.testing.assert_allclose(ours, R.as_rotvec(), atol=1e-12)


@pytest.mark.parametrize("angle", [0.0, 1e-300, 1e-16, 1e-12, 1e-8, 1e-4, 0.5])
def test_small_angles_are_exact(angle):
    axis = _unit([0.3, -0.5, 0.8])
    r = angle * axis
    q = P.quaternion_from_rotation_vector(r)
    back = P.rotation_vector_from_quaternion(q)
    np.testing.assert_allclose(back, r, rtol=1e-14, atol=1e-300)
    np.testing.assert_allclose(back, Rotation.from_rotvec(r).as_rotvec(), rtol=1e-13, atol=1e-300)


@pytest.mark.parametrize("delta", [0.0, 1e-16, 1e-15, 1e-14, 1e-13, 1e-12, 1e-11, 1e-9])
@pytest.mark.parametrize("axis", [[0.3, -0.5, -0.8], [1.0, -1.0, 0.0], [-1.0, 0.0, 0.0],
                                  [0.2, 0.9, 0.1]])
def test_within_1e12_of_pi_agrees_with_scipy_and_pyquaternion(axis, delta):
    n = _unit(axis)
    theta = np.pi - delta
    R = Rotation.from_rotvec(theta * n)
    r = P.rotation_vector_from_matrix(R.as_matrix())
    # the same rotation as scipy's rotation vector, to rounding
    np.testing.assert_allclose(P.matrix_from_rotation_vector(r), R.as_matrix(), atol=1e-14)
    np.testing.assert_allclose(P.matrix_from_rotation_vector(R.as_rotvec()), R.as_matrix(),
                               atol=1e-14)
    ref = R.as_rotvec()
    if delta > 1e-12:           # unique vector: equal to scipy's
        np.testing.assert_allclose(r, ref, atol=1e-12)
    else:                        # half turn: scipy's or its mirror 2 pi - theta about -n
        assert np.allclose(r, ref, atol=1e-12) or np.allclose(
            r, -(2 * np.pi - np.linalg.norm(ref)) * _unit(ref), atol=1e-12)
    # the quaternion agrees with pyquaternion's (up to sign)
    q = P.quaternion_from_rotation_vector(r)
    pq = PyQuaternion(axis=n, angle=theta)
    assert min(np.abs(q - pq.elements).max(), np.abs(q + pq.elements).max()) < 1e-12


def test_half_turn_sign_is_stable_under_rounding():
    rng = np.random.default_rng(3)
    axes = _unit(rng.normal(size=(200, 3)))
    for n in axes:
        Rs = [Rotation.from_rotvec(a * n).as_matrix() for a in (np.pi, np.pi - 1e-14)]
        Rs.append(Rs[0] + 1e-16 * rng.normal(size=(3, 3)))  # a rounding-sized perturbation
        rs = [P.rotation_vector_from_matrix(R) for R in Rs]
        for r in rs:
            assert np.abs(r - rs[0]).max() < 1e-12
        # and the chosen vector points into the upper half-space
        assert rs[0][2] > 0 or (abs(rs[0][2]) < 1e-9 and rs[0][1] > 0)


def test_half_turn_rule_on_axes():
    cases = {(1, 0, 0): (1, 0, 0), (-1, 0, 0): (1, 0, 0), (0, -1, 0): (0, 1, 0),
             (0, 0, -1): (0, 0, 1), (1, -1, 0): (-1, 1, 0), (1, 0, -1): (-1, 0, 1)}
    for axis, want in cases.items():
        r = P.rotation_vector_from_quaternion(np.r_[0.0, _unit(axis)])
        np.testing.assert_allclose(r, np.pi * _unit(want), atol=1e-15)


def test_quaternion_from_rotation_vector_matches_pyquaternion():
    rvecs = RNG.normal(size=(300, 3)) * 1.5
    q = P.quaternion_from_rotation_vector(rvecs)
    for r, qi in zip(rvecs, q, strict=True):
        angle = np.linalg.norm(r)
        ref = PyQuaternion(axis=r / angle, angle=angle).elements
        np.testing.assert_allclose(qi, ref, atol=1e-14)


def test_long_rotation_vectors_are_accepted():
    r = np.array([0.0, 0.0, 1.5 * np.pi])          # same as -pi/2 about z
    np.testing.assert_allclose(P.matrix_from_rotation_vector(r), dqlab.rot_z(-np.pi / 2),
                               atol=1e-15)
    np.testing.assert_allclose(P.rotation_vector_from_matrix(P.matrix_from_rotation_vector(r)),
                               [0, 0, -np.pi / 2], atol=1e-15)


@pytest.mark.parametrize("lead", [(), (4,), (2, 3)])
def test_batches_match_single_items(lead):
    rng = np.random.default_rng(5)
    T = _random_transforms(rng, int(np.prod(lead, dtype=int))).reshape(lead + (4, 4))
    p = P.pose_from_transform(T)
    Q = P.dual_quaternion_from_pose(p)
    assert p.shape == lead + (6,) and Q.shape == lead + (8,)
    # the same formulas on a batch and on one item; numpy's vectorised transcendental
    # functions may round the last bit differently by array length, hence a few ulps
    for idx in np.ndindex(*lead):
        np.testing.assert_array_max_ulp(p[idx], P.pose_from_transform(T[idx]), maxulp=4)
        np.testing.assert_array_max_ulp(Q[idx], P.dual_quaternion_from_pose(p[idx]), maxulp=4)


def test_dual_quaternion_round_trips():
    T = _random_transforms(RNG, 200)
    Q = dqlab.dual_quaternion_from_transform(T)
    p = P.pose_from_dual_quaternion(Q)
    np.testing.assert_allclose(p, P.pose_from_transform(T), atol=1e-14)
    Q2 = P.dual_quaternion_from_pose(p)
    np.testing.assert_allclose(dqlab.transform_from_dual_quaternion(Q2), T, atol=1e-14)


def test_thesis_pose_at_home_joints():
    X_WF = dqlab.models.ur3().fk([0, -np.pi / 2, 0, -np.pi / 2, 0, 0])
    p = P.pose_from_transform(X_WF)
    np.testing.assert_allclose(p[:3], [0.0, -0.19425, 0.69415], atol=1e-12)
    np.testing.assert_allclose(p[3:], np.pi * _unit([0, -1, 1]), atol=1e-12)


def test_rpy_matches_scipy_extrinsic_xyz():
    rpy = RNG.uniform([-np.pi, -1.5, -np.pi], [np.pi, 1.5, np.pi], (300, 3))
    r = P.rotation_vector_from_rpy(rpy)
    ref = Rotation.from_euler("xyz", rpy).as_rotvec()
    np.testing.assert_allclose(P.matrix_from_rotation_vector(r),
                               Rotation.from_rotvec(ref).as_matrix(), atol=1e-13)
    np.testing.assert_allclose(P.rpy_from_rotation_vector(r), rpy, atol=1e-12)


@pytest.mark.parametrize("bad, match", [
    ([0, 0, 0, 0, 0, np.nan], "p contains NaN"),
    ([0, 0, 0, 0, 0], r"p must have shape \(\.\.\., 6\)"),
    ([0, 0, np.inf, 0, 0, 0], "p contains NaN"),
])
def test_bad_poses_are_refused(bad, match):
    with pytest.raises(ValueError, match=match):
        P.transform_from_pose(bad)


def test_non_unit_quaternion_and_non_rigid_transform_are_refused():
    with pytest.raises(ValueError, match="unit quaternion"):
        P.rotation_vector_from_quaternion([1.0, 0.1, 0, 0])
    T = np.eye(4)
    T[0, 0] = 1.1
    with pytest.raises(ValueError):
        P.pose_from_transform(T)


@given(st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(
           lambda v: np.linalg.norm(v) > 1e-3),
       st.lists(st.floats(-1, 1), min_size=3, max_size=3),
       st.sampled_from([0.0, 1e-14, 1e-9, 1e-4]))
def test_property_pose_round_trip_including_near_half_turns(quat, position, squash):
    q = np.array(quat) / np.linalg.norm(quat)
    q[0] *= squash if squash else 1.0            # squash w: angles near pi
    q /= np.linalg.norm(q)
    T = np.eye(4)
    T[:3, :3] = dqlab.matrix_from_quaternion(q)
    T[:3, 3] = position
    p = P.pose_from_transform(T)
    assert np.linalg.norm(p[3:]) <= np.pi + 1e-12
    np.testing.assert_allclose(P.transform_from_pose(p), T, atol=1e-14)
    # pyquaternion's view of the same rotation
    pq = PyQuaternion(matrix=T[:3, :3])
    np.testing.assert_allclose(P.matrix_from_rotation_vector(pq.axis * pq.angle),
                               T[:3, :3], atol=1e-12)
