"""dqlab.testing: the assertions that know q and -q (Q and -Q) are one rotation (motion)."""

import numpy as np
import pytest
import pytransform3d.rotations as pr
import pytransform3d.transformations as pt
from _draws import random_unit_quaternions

from dqlab import dual_quaternion_from_rotation_translation
from dqlab.testing import assert_dual_quaternion_equal, assert_quaternion_equal


def _holds(assertion, *args, **kwargs):
    try:
        assertion(*args, **kwargs)
    except AssertionError:
        return False
    return True


def test_the_verdicts_are_pytransform3ds_item_by_item():
    """pytransform3d's assert_quaternion_equal and assert_unit_dual_quaternion_equal (decimal
    6: a difference below 1.5e-6) on pairs that differ by 1e-8 to 1e-4, with random signs."""
    rng = np.random.default_rng(41)
    n = 300
    q = random_unit_quaternions(rng, n)
    Q = dual_quaternion_from_rotation_translation(random_unit_quaternions(rng, n),
                                                  rng.normal(size=(n, 3)))
    sign = rng.choice([-1.0, 1.0], (n, 1))
    size = 10.0 ** rng.uniform(-8, -4, (n, 1))
    q_other = sign * q + size * rng.normal(size=(n, 4))
    Q_other = sign * Q + size * rng.normal(size=(n, 8))
    for ours, theirs, a, b in ((assert_quaternion_equal, pr.assert_quaternion_equal, q, q_other),
                               (assert_dual_quaternion_equal,
                                pt.assert_unit_dual_quaternion_equal, Q, Q_other)):
        pairs = list(zip(a, b, strict=True))
        verdicts = np.array([_holds(ours, x, y, atol=1.5e-6) for x, y in pairs])
        assert verdicts.tolist() == [_holds(theirs, x, y, decimal=6) for x, y in pairs]
        assert 0.2 < verdicts.mean() < 0.8                # both verdicts are exercised
        assert _holds(ours, a, b, atol=1.5e-6) == verdicts.all()            # one call, a batch
        assert _holds(ours, a[verdicts], b[verdicts], atol=1.5e-6)


def test_a_failure_names_the_worst_item_and_one_sign_serves_all_eight_numbers():
    rng = np.random.default_rng(42)
    q = random_unit_quaternions(rng, (2, 3))
    wrong = -q
    wrong[1, 2] = q[0, 0]
    with pytest.raises(AssertionError, match=r"at index \(1, 2\), 1 of 6 items") as info:
        assert_quaternion_equal(q, wrong)
    assert str(info.value).count("\n") == 2              # the two quaternions, one line each
    assert_quaternion_equal(np.tile(q[0, 0], (4, 1)), -q[0, 0])     # leading axes broadcast
    Q = dual_quaternion_from_rotation_translation(q[0, 0], [0.1, 0.2, 0.3])
    assert_dual_quaternion_equal(Q, -Q)
    mixed = np.concatenate([Q[:4], -Q[4:]])              # q_r with one sign, q_d with the other
    with pytest.raises(AssertionError, match="dual quaternions differ"):
        assert_dual_quaternion_equal(Q, mixed)


def test_bad_arguments_are_refused_by_name():
    with pytest.raises(ValueError, match=r"desired must have shape \(\.\.\., 4\)"):
        assert_quaternion_equal([1.0, 0, 0, 0], [1.0, 0, 0])
    with pytest.raises(ValueError, match="actual of shape .* do not broadcast"):
        assert_quaternion_equal(np.ones((2, 4)), np.ones((3, 4)))
    with pytest.raises(ValueError, match="atol"):
        assert_dual_quaternion_equal(np.ones(8), np.ones(8), atol=-1.0)
