r"""Time laws: how far along a path a motion is at each instant.

A time law :math:`s(t)` takes a path parameter from 0 to a distance :math:`\Delta` in a
duration :math:`T`, starting and ending at rest. Every law here is a piecewise polynomial
of degree at most 5, held in one :class:`TimeLaw` object that evaluates position
:math:`s`, speed :math:`\dot s`, acceleration :math:`\ddot s` and jerk :math:`\dddot s`
on any time grid. The constructors are:

- :func:`cubic` -- :math:`s = \Delta (3\tau^2 - 2\tau^3)`, :math:`\tau = t / T`;
- :func:`quintic` -- :math:`s = \Delta (10\tau^3 - 15\tau^4 + 6\tau^5)` (zero acceleration
  at both ends);
- :func:`trapezoidal` -- constant acceleration, cruise, constant deceleration, from a speed
  and an acceleration limit (the shortest such motion) or from a duration;
- :func:`three_phase` -- the UR3 report's law: accelerate over a fraction of the distance,
  cruise over a second fraction, decelerate over the rest, peak speed given.

Chapter 10 of the book derives them.
"""

from dataclasses import dataclass

import numpy as np

from .._checks import as_float_array
from ._args import finite as _finite
from ._args import positive as _positive

__all__ = ["TimeLaw", "cubic", "quintic", "trapezoidal", "three_phase", "time_grid"]


def time_grid(duration, dt, *, endpoint=True):
    r"""Sampling instants :math:`0, \delta t, 2\delta t, \ldots` up to ``duration``.

    Parameters
    ----------
    duration : float
        Length of the motion in seconds (>= 0).
    dt : float
        Sampling period in seconds (> 0).
    endpoint : bool
        With True, ``duration`` itself is appended when the regular grid stops short of it
        (the last step is then shorter than ``dt``). With False the grid is
        ``numpy.arange(0, duration, dt)``, as in the UR3 report (its last instant lies less
        than ``dt`` before the end).

    Returns
    -------
    ndarray, shape (N,)

    Examples
    --------
    >>> time_grid(0.02, 0.008)
    array([0.   , 0.008, 0.016, 0.02 ])
    >>> time_grid(0.02, 0.008, endpoint=False)
    array([0.   , 0.008, 0.016])
    """
    dt = _positive(dt, "dt")
    duration = _finite(duration, "duration")
    if duration < 0.0:
        raise ValueError(f"duration must be >= 0, got {duration!r}")
    t = np.arange(0.0, duration, dt)
    if not endpoint:
        return t if t.size else np.zeros(1)
    if t.size and duration - t[-1] <= 1e-9 * dt:
        t[-1] = duration
    else:
        t = np.append(t, duration)
    return t


@dataclass(frozen=True)
class TimeLaw:
    r"""A rest-to-rest time law :math:`s(t)`, piecewise polynomial.

    On segment :math:`k`, :math:`t_k \le t \le t_{k+1}`,
    :math:`s(t) = \sum_j c_{kj} (t - t_k)^j`. Before 0 the law holds :math:`s = 0`, after
    :attr:`duration` it holds :math:`s = \Delta`, both at rest.

    Attributes
    ----------
    breaks : ndarray, shape (m + 1,)
        Segment boundaries :math:`0 = t_0 < t_1 < \dots < t_m = T` in seconds.
    coefficients : ndarray, shape (m, 6)
        :math:`c_{kj}`, ascending powers of the local time :math:`t - t_k`.
    name : str
        What law it is (for printing).
    """

    breaks: np.ndarray
    coefficients: np.ndarray
    name: str = "time law"

    def __post_init__(self):
        breaks = as_float_array(self.breaks, "breaks")
        coefficients = as_float_array(self.coefficients, "coefficients", (6,))
        if breaks.ndim != 1 or breaks.size < 2 or coefficients.shape != (breaks.size - 1, 6):
            raise ValueError(
                f"breaks (m + 1,) and coefficients (m, 6) do not match: shapes "
                f"{breaks.shape} and {coefficients.shape}")
        if breaks[0] != 0.0 or np.any(np.diff(breaks) <= 0.0):
            raise ValueError("breaks must start at 0 and increase strictly")
        object.__setattr__(self, "breaks", breaks)
        object.__setattr__(self, "coefficients", coefficients)

    @property
    def duration(self):
        """:math:`T`, seconds."""
        return float(self.breaks[-1])

    @property
    def distance(self):
        r""":math:`\Delta = s(T)`."""
        return self._end_position()

    @property
    def switch_times(self):
        """The interior segment boundaries (where the acceleration may jump), seconds."""
        return self.breaks[1:-1].copy()

    def _evaluate(self, t, order):
        t = as_float_array(t, "t")
        T = self.duration
        tc = np.clip(t, 0.0, T)
        k = np.clip(np.searchsorted(self.breaks, tc, side="right") - 1, 0,
                    len(self.coefficients) - 1)
        tau = tc - self.breaks[k]
        c = self.coefficients[k]                                   # (..., 6)
        powers = np.arange(6)
        # d^order/dtau^order of sum c_j tau^j = sum c_j j!/(j-order)! tau^(j-order)
        factor = np.ones(6)
        for i in range(order):
            factor = factor * np.maximum(powers - i, 0)
        exponent = np.maximum(powers - order, 0)
        value = np.sum(c * factor * tau[..., None] ** exponent, axis=-1)
        # from T on the law holds its end at rest (exactly, whatever the rounding)
        end = self._end_position() if order == 0 else 0.0
        value = np.where(t >= T, end, value)
        if order > 0:
            value = np.where(t < 0.0, 0.0, value)
        return value

    def _end_position(self):
        c = self.coefficients[-1]
        h = self.breaks[-1] - self.breaks[-2]
        return float(np.polynomial.polynomial.polyval(h, c))

    def position(self, t):
        """:math:`s(t)`, same shape as ``t``."""
        return self._evaluate(t, 0)

    def speed(self, t):
        r""":math:`\dot s(t)`."""
        return self._evaluate(t, 1)

    def acceleration(self, t):
        r""":math:`\ddot s(t)`."""
        return self._evaluate(t, 2)

    def jerk(self, t):
        r""":math:`\dddot s(t)` inside the segments (the impulses where the acceleration
        jumps are not represented)."""
        return self._evaluate(t, 3)

    def __call__(self, t):
        r"""``(s, s_dot, s_ddot)`` at the instants ``t`` (array_like, any shape)."""
        return self.position(t), self.speed(t), self.acceleration(t)

    def sample(self, dt, *, endpoint=True):
        """``(t, s, s_dot, s_ddot)`` on :func:`time_grid` ``(self.duration, dt, endpoint)``."""
        t = time_grid(self.duration, dt, endpoint=endpoint)
        return (t,) + self(t)

    def _extremes(self, order):
        """Largest absolute value of the ``order``-th derivative (exact, from the roots)."""
        best = 0.0
        for k, c in enumerate(self.coefficients):
            h = self.breaks[k + 1] - self.breaks[k]
            poly = np.polynomial.Polynomial(c).deriv(order)
            candidates = [0.0, h]
            if poly.degree() >= 1:
                roots = poly.deriv().roots()
                roots = roots[np.abs(roots.imag) < 1e-12].real
                candidates += [r for r in roots if 0.0 <= r <= h]
            best = max(best, float(np.max(np.abs(poly(np.array(candidates))))))
        return best

    @property
    def peak_speed(self):
        r""":math:`\max |\dot s|`, from the roots of :math:`\ddot s` on each segment."""
        return self._extremes(1)

    @property
    def peak_acceleration(self):
        r""":math:`\max |\ddot s|`, from the roots of :math:`\dddot s` on each segment."""
        return self._extremes(2)

    def __repr__(self):
        return (f"TimeLaw({self.name}: distance {self.distance:.6g}, duration "
                f"{self.duration:.6g} s, switches at {np.round(self.switch_times, 6).tolist()})")


def _polynomial_law(duration, distance, unit_coefficients, name):
    T = _positive(duration, "duration")
    D = _finite(distance, "distance")
    scale = D / T ** np.arange(6)
    return TimeLaw(np.array([0.0, T]), (np.asarray(unit_coefficients) * scale)[None], name)


def cubic(duration, distance=1.0):
    r"""Cubic rest-to-rest law :math:`s = \Delta (3\tau^2 - 2\tau^3)`, :math:`\tau = t/T`.

    Speed :math:`\dot s = \frac{6\Delta}{T}\tau(1-\tau)`, peak :math:`1.5\,\Delta/T` at
    :math:`\tau = \frac12`; acceleration :math:`\frac{6\Delta}{T^2}(1 - 2\tau)`, which jumps
    from 0 to :math:`6\Delta/T^2` at the start (infinite jerk).

    Parameters
    ----------
    duration : float
        :math:`T` in seconds (> 0).
    distance : float
        :math:`\Delta` (any sign; 1 gives the normalised law).

    Returns
    -------
    TimeLaw

    Examples
    --------
    >>> law = cubic(2.0, 1.0)
    >>> law.peak_speed, law.peak_acceleration
    (0.75, 1.5)
    >>> [float(x) for x in law(1.0)]
    [0.5, 0.75, 0.0]
    """
    return _polynomial_law(duration, distance, [0, 0, 3, -2, 0, 0], "cubic")


def quintic(duration, distance=1.0):
    r"""Quintic rest-to-rest law :math:`s = \Delta (10\tau^3 - 15\tau^4 + 6\tau^5)`.

    Zero speed and acceleration at both ends. Speed
    :math:`\dot s = \frac{30\Delta}{T}\tau^2(1-\tau)^2`, peak :math:`\frac{15}{8}\Delta/T =
    1.875\,\Delta/T` at :math:`\tau = \frac12`; acceleration peak
    :math:`\frac{10}{\sqrt3}\Delta/T^2` at :math:`\tau = \frac12 \mp \frac{\sqrt3}{6}`.

    Parameters
    ----------
    duration : float
        :math:`T` in seconds (> 0).
    distance : float
        :math:`\Delta`.

    Returns
    -------
    TimeLaw

    Examples
    --------
    >>> law = quintic(1.0)
    >>> law.peak_speed
    1.875
    >>> round(law.peak_acceleration, 6) == round(10 / 3 ** 0.5, 6)
    True
    """
    return _polynomial_law(duration, distance, [0, 0, 0, 10, -15, 6], "quintic")


def _three_segments(t_acc, t_cruise, t_dec, v, name, sign=1.0):
    """Accelerate to ``v`` in ``t_acc``, cruise ``t_cruise``, stop in ``t_dec`` (>0 each)."""
    a, d = v / t_acc, v / t_dec
    s1 = 0.5 * v * t_acc
    s2 = s1 + v * t_cruise
    rows = [[0.0, 0.0, 0.5 * a, 0, 0, 0]]
    lengths = [t_acc]
    if t_cruise > 0.0:
        rows.append([s1, v, 0.0, 0, 0, 0])
        lengths.append(t_cruise)
    rows.append([s2, v, -0.5 * d, 0, 0, 0])
    lengths.append(t_dec)
    breaks = np.concatenate([[0.0], np.cumsum(lengths)])
    keep = np.diff(breaks) > 0.0          # a cruise too short to move the sum is dropped
    return TimeLaw(np.concatenate([[0.0], breaks[1:][keep]]), sign * np.array(rows)[keep],
                   name)


def trapezoidal(distance=1.0, *, v_max=None, a_max=None, duration=None, accel_fraction=None):
    r"""Trapezoidal speed law: constant acceleration, cruise, constant deceleration.

    With :math:`t_a` the acceleration time, :math:`v` the cruise speed and
    :math:`a = v / t_a`, the duration is :math:`T = \Delta / v + t_a`. Give either

    - ``v_max`` and ``a_max``: the shortest motion within both limits,
      :math:`t_a = v_{max}/a_{max}` and :math:`T = \Delta/v_{max} + v_{max}/a_{max}`; when
      :math:`\Delta < v_{max}^2/a_{max}` the cruise vanishes (triangular law,
      :math:`T = 2\sqrt{\Delta/a_{max}}`);
    - ``duration`` and ``accel_fraction`` :math:`f = t_a/T \in (0, \frac12]` (default
      :math:`\frac13`): :math:`v = \frac{\Delta}{(1-f)T}`, so :math:`v = 1.5\,\Delta/T` for
      a third;
    - ``duration`` and ``a_max``: :math:`t_a = \frac T2 - \sqrt{\frac{T^2}{4} -
      \frac{\Delta}{a_{max}}}`, which needs :math:`a_{max} \ge 4\Delta/T^2`;
    - ``duration`` and ``v_max``: :math:`t_a = T - \Delta/v_{max}`, which needs
      :math:`\Delta/T < v_{max}`; above :math:`2\Delta/T` the law is triangular.

    With ``duration``, ``a_max`` and ``v_max`` together, the law is built from ``a_max``
    and its cruise speed must not exceed ``v_max``.

    Parameters
    ----------
    distance : float
        :math:`\Delta` (any sign, not zero).
    v_max, a_max : float, optional
        Limits on :math:`|\dot s|` and :math:`|\ddot s|` (> 0).
    duration : float, optional
        :math:`T` in seconds (> 0).
    accel_fraction : float, optional
        :math:`t_a / T`, in :math:`(0, \frac12]`.

    Returns
    -------
    TimeLaw

    Raises
    ------
    ValueError
        On a zero, NaN or infinite distance, non-positive limits or duration, a missing
        pair of arguments, or limits that cannot reach the distance in the duration.

    Examples
    --------
    >>> law = trapezoidal(0.9, duration=3.0)          # accelerates for a third of the time
    >>> law.peak_speed, law.switch_times
    (0.45, array([1., 2.]))
    >>> law = trapezoidal(1.0, v_max=0.5, a_max=1.0)   # the shortest motion within limits
    >>> law.duration
    2.5
    >>> trapezoidal(1.0, duration=1.0, a_max=3.0)
    Traceback (most recent call last):
    ...
    ValueError: a_max = 3 cannot cover the distance 1 in 1 s: it needs a_max >= ... = 4
    """
    D = _finite(distance, "distance")
    if D == 0.0:
        raise ValueError("distance must not be 0 (a law that does not move has no timing)")
    sign, D = np.sign(D), abs(D)
    v = None if v_max is None else _positive(v_max, "v_max")
    a = None if a_max is None else _positive(a_max, "a_max")
    if duration is None:
        if accel_fraction is not None:
            raise ValueError("accel_fraction needs a duration")
        if v is None or a is None:
            raise ValueError("give v_max and a_max, or a duration")
        if D <= v * v / a:                       # triangular: the cruise speed is not reached
            t_a = np.sqrt(D / a)
            return _three_segments(t_a, 0.0, t_a, a * t_a, "trapezoidal (triangular)", sign)
        return _three_segments(v / a, D / v - v / a, v / a, v, "trapezoidal", sign)
    T = _positive(duration, "duration")
    if a is not None:
        if accel_fraction is not None:
            raise ValueError("give a_max or accel_fraction with a duration, not both")
        if a < 4.0 * D / T ** 2 * (1 - 1e-12):
            raise ValueError(
                f"a_max = {a:g} cannot cover the distance {D:g} in {T:g} s: it needs "
                f"a_max >= 4 |distance| / duration^2 = {4.0 * D / T ** 2:g}")
        t_a = T / 2 - np.sqrt(max(T * T / 4 - D / a, 0.0))
        cruise = D / (T - t_a)
        if v is not None and cruise > v * (1 + 1e-12):
            raise ValueError(
                f"with a_max = {a:g} the cruise speed {cruise:g} exceeds v_max = {v:g}; "
                f"a longer duration or a larger a_max is needed")
    elif v is not None:
        if accel_fraction is not None:
            raise ValueError("give v_max or accel_fraction with a duration, not both")
        if v <= D / T:
            raise ValueError(
                f"v_max = {v:g} cannot cover the distance {D:g} in {T:g} s: it needs "
                f"v_max > |distance| / duration = {D / T:g}")
        t_a = T - D / min(v, 2.0 * D / T)
    else:
        f = 1.0 / 3.0 if accel_fraction is None else _positive(accel_fraction,
                                                                 "accel_fraction")
        if f > 0.5:
            raise ValueError(f"accel_fraction must be in (0, 0.5], got {accel_fraction!r}")
        t_a = f * T
    t_a = min(t_a, T / 2)
    cruise_time = max(T - 2 * t_a, 0.0)
    if cruise_time < 1e-12 * T:
        cruise_time = 0.0
    v_peak = D / (T - t_a)
    return _three_segments(t_a, cruise_time, T - t_a - cruise_time, v_peak, "trapezoidal",
                           sign)


def three_phase(distance, speed, fractions=(0.25, 0.25, 0.5)):
    r"""The UR3 report's law: accelerate, cruise and decelerate over given fractions of the
    distance.

    With :math:`d_1, d_2, d_3 = f_1\Delta, f_2\Delta, f_3\Delta` and the peak speed
    :math:`V`:

    .. math::

        a = \frac{V^2}{2 d_1},\quad t_1 = \frac{2 d_1}{V},\qquad
        t_2 = t_1 + \frac{d_2}{V},\qquad
        d = \frac{V^2}{2 d_3},\quad t_f = t_2 + \frac{2 d_3}{V},

    so :math:`t_f = (2 f_1 + f_2 + 2 f_3)\,\Delta / V`. The report's circle uses a quarter
    turn, a quarter turn and a half turn of :math:`\Delta = 2\pi R`, hence
    :math:`t_f = 3.5\pi R / V`.

    Parameters
    ----------
    distance : float
        :math:`\Delta > 0` (an arc length, metres).
    speed : float
        Peak speed :math:`V > 0`.
    fractions : sequence of 3 floats
        :math:`(f_1, f_2, f_3)`, each >= 0, :math:`f_1, f_3 > 0`, summing to 1.

    Returns
    -------
    TimeLaw

    Examples
    --------
    >>> import numpy as np
    >>> law = three_phase(2 * np.pi * 0.1, 0.05)
    >>> round(law.duration, 4), round(3.5 * np.pi * 0.1 / 0.05, 4)
    (21.9911, 21.9911)
    >>> law.switch_times.round(4)
    array([6.2832, 9.4248])
    """
    D = _positive(distance, "distance")
    V = _positive(speed, "speed")
    f = as_float_array(fractions, "fractions")
    if f.shape != (3,):
        raise ValueError(f"fractions must hold 3 numbers, got shape {f.shape}")
    if np.any(f < 0) or f[0] <= 0 or f[2] <= 0:
        raise ValueError(f"fractions must be >= 0 with the first and last > 0, got {f}")
    if abs(f.sum() - 1.0) > 1e-12:
        raise ValueError(f"fractions must sum to 1, got {f} (sum {f.sum():.15g})")
    d1, d2, d3 = f * D
    return _three_segments(2 * d1 / V, d2 / V, 2 * d3 / V, V, "three-phase")
