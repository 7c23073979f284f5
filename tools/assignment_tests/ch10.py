"""Hidden tests of chapter 10, trajectories in joint space."""

import numpy as np
from dqlab_grading import agrees, hidden

from dqlab import trajectory as tr


def _quintic_sample(rng):
    T = rng.uniform(0.1, 20.0)
    return rng.uniform(0.0, T, 30), T, rng.normal(0, 5)


def _trapezoid(f, T, D):
    law = tr.trapezoidal(D, duration=T, accel_fraction=f)
    return law.peak_speed, law.peak_acceleration


def _report(R, V):
    law = tr.three_phase(2 * np.pi * R, V)
    return (*law.switch_times, law.duration)


@hidden("ch10-ex1")
def my_quintic_on_new_laws(my_quintic):
    """my_quintic follows new quintic laws, long and short, either direction"""
    agrees(my_quintic, lambda t, T, D: tr.quintic(T, D).position(t), _quintic_sample, n=100,
           seed=1001, atol=1e-10)


@hidden("ch10-ex1")
def my_quintic_is_own_code(my_quintic):
    """my_quintic evaluates 10 tau^3 - 15 tau^4 + 6 tau^5 itself, not with dqlab.trajectory"""
    agrees(my_quintic, lambda t, T, D: tr.quintic(T, D).position(t), _quintic_sample, n=5,
           seed=1002, atol=1e-10, forbid=("dqlab",))


@hidden("ch10-ex2")
def trapezoid_peaks_on_new_laws(trapezoid_peaks):
    """trapezoid_peaks gives the peak speed and acceleration of new trapezoids"""
    agrees(trapezoid_peaks, _trapezoid,
           lambda rng: (rng.uniform(0.02, 0.5), rng.uniform(0.1, 20.0), rng.uniform(0.01, 10)),
           n=100, seed=1003, atol=1e-8)


@hidden("ch10-ex2")
def trapezoid_peaks_is_own_code(trapezoid_peaks):
    """trapezoid_peaks uses the formulas in f, T and D, not dqlab.trajectory"""
    agrees(trapezoid_peaks, _trapezoid,
           lambda rng: (rng.uniform(0.05, 0.5), rng.uniform(0.5, 5.0), rng.uniform(0.1, 3)),
           n=5, seed=1004, atol=1e-8, forbid=("dqlab",))


@hidden("ch10-ex3")
def report_times_on_new_circles(report_times):
    """report_times gives t1, t2 and tf of new circles and speeds"""
    agrees(report_times, _report, lambda rng: (rng.uniform(0.005, 2.0), rng.uniform(0.005, 2.0)),
           n=100, seed=1005, atol=1e-8)


@hidden("ch10-ex3")
def report_times_is_own_code(report_times):
    """report_times uses pi R / V and its multiples, not dqlab.trajectory"""
    agrees(report_times, _report, lambda rng: (rng.uniform(0.02, 0.5), rng.uniform(0.01, 0.5)),
           n=5, seed=1006, atol=1e-8, forbid=("dqlab",))


@hidden("ch10-ex4")
def quintic_segment_is_the_quintic(quintic_segment):
    """quintic_segment is the one quintic through the six conditions, for vectors of joints"""
    rng = np.random.default_rng(1007)
    for _ in range(20):
        h = rng.uniform(0.2, 5.0)
        start, end = rng.normal(size=(3, 2)), rng.normal(size=(3, 2))
        t = np.linspace(0.0, h, 11)
        q, qd, qdd = (np.asarray(x, dtype=float) for x in quintic_segment(t, h, start, end))
        assert q.shape == qd.shape == qdd.shape == (11, 2), (
            f"shapes {q.shape}, {qd.shape}, {qdd.shape} for 11 instants of 2 joints")
        for j in range(2):                       # the coefficients of joint j, by a 6x6 solve
            A = np.array([[1, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 2, 0, 0, 0],
                          [1, h, h**2, h**3, h**4, h**5],
                          [0, 1, 2 * h, 3 * h**2, 4 * h**3, 5 * h**4],
                          [0, 0, 2, 6 * h, 12 * h**2, 20 * h**3]])
            c = np.linalg.solve(A, np.r_[start[:, j], end[:, j]])
            want = np.polyval(c[::-1], t)
            assert np.allclose(q[:, j], want, atol=1e-9), f"q of joint {j} off the quintic"
            assert np.allclose(qd[:, j], np.polyval(np.polyder(c[::-1]), t), atol=1e-8), (
                f"qd of joint {j} is not the derivative of q")
            assert np.allclose(qdd[:, j], np.polyval(np.polyder(c[::-1], 2), t), atol=1e-7), (
                f"qdd of joint {j} is not the second derivative of q")
