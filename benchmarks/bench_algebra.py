"""Speed of dqlab's algebra next to pyquaternion and pytransform3d.

Run with ``python benchmarks/bench_algebra.py`` (add ``--quick`` for a short run). It prints
two tables: single values (microseconds per call) and batches of 100,000 (microseconds per
element), with the ratio of each peer's time to dqlab's (above 1: dqlab is faster).

Goals: every single-value dqlab operation at least as fast as one pyquaternion quaternion
product, and every batch operation under 0.2 microseconds per element.

pyquaternion has no dual quaternions and no batches: its column shows what a program
written with it does (the thesis's style): a dual-quaternion product as three quaternion
products, a dual quaternion from a 4x4 via ``Quaternion(matrix=R)``, and batches as a
Python loop (timed on 2,000 elements). Times are CPU times, the methods timed in turn in
rounds (``timing.interleaved_best``). This is not a test; timings vary between machines.
"""

import argparse
import os

import numpy as np
import pytransform3d.batch_rotations as pbr
import pytransform3d.rotations as pr
import pytransform3d.trajectories as ptr
import pytransform3d.transformations as pt
from pyquaternion import Quaternion as PyQuaternion
from timing import interleaved_best

import dqlab

N_BATCH = 100_000
N_LOOP = 2_000  # elements for the pyquaternion Python loops


def unit(rng, shape=()):
    q = rng.normal(size=tuple(shape) + (4,))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


# pyquaternion, written the way a program using it would
def pyq_dq_product(A, B):
    ar, ad = A
    br, bd = B
    return ar * br, ar * bd + ad * br


def pyq_dq_from_transform(T):
    qr = PyQuaternion(matrix=T[:3, :3])
    return qr, 0.5 * PyQuaternion(0.0, *T[:3, 3]) * qr


def main(quick=False):
    rng = np.random.default_rng(0)
    number, repeat = (2_000, 3) if quick else (20_000, 7)
    bnumber, brepeat = (2, 3) if quick else (5, 5)

    a, b = unit(rng, (2,))
    v = rng.normal(size=3)
    T = dqlab.transform_from(dqlab.matrix_from_quaternion(a), rng.normal(size=3))
    A = dqlab.dual_quaternion_from_transform(T)
    B = dqlab.dual_quaternion_from_rotation_translation(b, rng.normal(size=3))
    pa, pb = PyQuaternion(a), PyQuaternion(b)
    pA = (PyQuaternion(A[:4]), PyQuaternion(A[4:]))
    pB = (PyQuaternion(B[:4]), PyQuaternion(B[4:]))

    single = {
        "quaternion product": (
            lambda: dqlab.quaternion_product(a, b),
            lambda: pa * pb,
            lambda: pr.concatenate_quaternions(a, b)),
        "rotate a vector": (
            lambda: dqlab.rotate_vector(a, v),
            lambda: pa.rotate(v),
            lambda: pr.q_prod_vector(a, v)),
        "dual quaternion product": (
            lambda: dqlab.dual_quaternion_product(A, B),
            lambda: pyq_dq_product(pA, pB),
            lambda: pt.concatenate_dual_quaternions(A, B)),
        "dual quaternion from 4x4": (
            lambda: dqlab.dual_quaternion_from_transform(T),
            lambda: pyq_dq_from_transform(T),
            lambda: pt.dual_quaternion_from_transform(T)),
    }

    n = N_BATCH
    qa, qb = unit(rng, (2, n))
    vs = rng.normal(size=(n, 3))
    Ts = dqlab.transform_from(dqlab.matrix_from_quaternion(qa), rng.normal(size=(n, 3)))
    As = dqlab.dual_quaternion_from_transform(Ts)
    Bs = dqlab.dual_quaternion_from_rotation_translation(qb, rng.normal(size=(n, 3)))
    m = N_LOOP
    pqa = [PyQuaternion(q) for q in qa[:m]]
    pqb = [PyQuaternion(q) for q in qb[:m]]
    pAs = [(PyQuaternion(x[:4]), PyQuaternion(x[4:])) for x in As[:m]]
    pBs = [(PyQuaternion(x[:4]), PyQuaternion(x[4:])) for x in Bs[:m]]

    def pt_rotate_batch():
        return np.einsum("nij,nj->ni", pbr.matrices_from_quaternions(qa), vs)

    batch = {
        "quaternion product": (
            lambda: dqlab.quaternion_product(qa, qb),
            lambda: [x * y for x, y in zip(pqa, pqb, strict=True)],
            lambda: pbr.batch_concatenate_quaternions(qa, qb)),
        "rotate a vector": (
            lambda: dqlab.rotate_vector(qa, vs),
            lambda: [x.rotate(y) for x, y in zip(pqa, vs[:m], strict=True)],
            pt_rotate_batch),
        "dual quaternion product": (
            lambda: dqlab.dual_quaternion_product(As, Bs),
            lambda: [pyq_dq_product(x, y) for x, y in zip(pAs, pBs, strict=True)],
            lambda: ptr.batch_concatenate_dual_quaternions(As, Bs)),
        "dual quaternion from 4x4": (
            lambda: dqlab.dual_quaternion_from_transform(Ts),
            lambda: [pyq_dq_from_transform(X) for X in Ts[:m]],
            lambda: ptr.dual_quaternions_from_transforms(Ts)),
    }

    # the results agree (up to the sign of q) before anything is timed
    for name, (f_dq, _, f_pt) in {**single, **batch}.items():
        x, y = np.asarray(f_dq()), np.asarray(f_pt())
        if x.shape[-1] in (4, 8):  # q and -q are the same rotation
            y = y * np.sign(np.sum(x[..., :4] * y[..., :4], axis=-1, keepdims=True))
        ok = np.allclose(x, y, atol=1e-12)
        assert ok, f"dqlab and pytransform3d disagree on {name}"

    results = {}
    if hasattr(os, "getloadavg"):
        print(f"Load average at start: {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs "
              "(timings grow with it; the ratios much less)\n")
    print(f"Single values: microseconds per call (best of {repeat} x {number})")
    print(f"{'operation':26s} {'dqlab':>8s} {'pyquaternion':>13s} {'pytransform3d':>14s}"
          f" {'pyq/dqlab':>10s} {'pt3d/dqlab':>11s}")
    for name, (f_dq, f_pq, f_pt) in single.items():
        best = interleaved_best({"dqlab": (f_dq, number, 1), "pyquaternion": (f_pq, number, 1),
                                 "pytransform3d": (f_pt, number, 1)}, repeat)
        t = [x * 1e6 for x in best.values()]
        results[("single", name)] = t
        print(f"{name:26s} {t[0]:8.2f} {t[1]:13.2f} {t[2]:14.2f} {t[1] / t[0]:10.1f}"
              f" {t[2] / t[0]:11.1f}")

    print(f"\nBatches of {n:,}: microseconds per element (pyquaternion: Python loop over "
          f"{m:,})")
    print(f"{'operation':26s} {'dqlab':>8s} {'pyquaternion':>13s} {'pytransform3d':>14s}"
          f" {'pyq/dqlab':>10s} {'pt3d/dqlab':>11s}")
    for name, (f_dq, f_pq, f_pt) in batch.items():
        best = interleaved_best({"dqlab": (f_dq, bnumber, n), "pyquaternion": (f_pq, 1, m),
                                 "pytransform3d": (f_pt, bnumber, n)}, brepeat)
        t = [x * 1e6 for x in best.values()]
        results[("batch", name)] = t
        print(f"{name:26s} {t[0]:8.3f} {t[1]:13.3f} {t[2]:14.3f} {t[1] / t[0]:10.1f}"
              f" {t[2] / t[0]:11.1f}")

    reference = results[("single", "quaternion product")][1]
    print("\nGoals")
    for (kind, name), t in results.items():
        if kind == "single":
            ok = t[0] <= reference
            print(f"  [{'ok' if ok else 'MISSED'}] single {name}: {t[0]:.2f} us "
                  f"<= pyquaternion product {reference:.2f} us")
        else:
            ok = t[0] < 0.2
            print(f"  [{'ok' if ok else 'MISSED'}] batch {name}: {t[0]:.3f} us/element < 0.2")
    return results


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats")
    main(parser.parse_args().quick)
