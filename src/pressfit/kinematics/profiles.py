r"""Jerk-limited (S-curve) rest-to-rest moves: the time-optimal seven-phase profile of a distance D >= 0 (m)
under a speed, acceleration and jerk limit (v, a, j: m/s, m/s^2, m/s^3), in closed form.

The phases are [T_j, T_c, T_j, T_v, T_j, T_c, T_j] with jerk +j, 0, -j, 0, -j, 0, +j: the peak acceleration
a_p = j T_j, the peak speed v_p = a_p (T_j + T_c), the distance v_p (2 T_j + T_c + T_v). Derivation of the
minimum time (the rest-to-rest move with both limits active is the textbook case; the others follow from it):

* the acceleration limit is reached on the way to v iff v j >= a^2: then T_j = a / j, T_c = v / a - a / j,
  else T_j = sqrt(v / j), T_c = 0; either way the speed-up takes T_a = 2 T_j + T_c and covers v T_a / 2;
* if D >= v T_a (speed reached): T_v = (D - v T_a) / v, T = D / v + T_a (= D / v + v / a + a / j when a is
  reached);
* else the peak speed v_p < v: with a reached (D >= 2 a^3 / j^2), v_p^2 + v_p a^2 / j - a D = 0,
  v_p = (sqrt(a^4 / j^2 + 4 a D) - a^2 / j) / 2, T_c = v_p / a - a / j, T = 2 (v_p / a + a / j);
  without (D < 2 a^3 / j^2): D = 2 j T_j^3, T_j = (D / (2 j))^(1/3), T = 4 T_j.

Position, speed and acceleration are exact polynomials per phase; the second half is the mirror of the first
(x(t) = D - x(T - t)), so the end point is D exactly and the profile is symmetric to round-off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

LIMITS = ("speed", "acceleration", "jerk")


@dataclass(frozen=True, kw_only=True)
class SCurve:
    """The minimum-time S-curve of ``distance_m`` (m) under ``speed_m_per_s``, ``acceleration_m_per_s2`` and
    ``jerk_m_per_s3`` (:func:`s_curve`). ``jerk_time_s`` T_j, ``constant_acceleration_time_s`` T_c,
    ``cruise_time_s`` T_v, ``duration_s`` T; ``peak_speed_m_per_s``, ``peak_acceleration_m_per_s2``."""

    distance_m: float
    speed_m_per_s: float
    acceleration_m_per_s2: float
    jerk_m_per_s3: float
    jerk_time_s: float
    constant_acceleration_time_s: float
    cruise_time_s: float
    _knots: tuple[tuple[float, float, float, float], ...] = field(repr=False, compare=False, default=())

    @property
    def duration_s(self) -> float:
        return 4.0 * self.jerk_time_s + 2.0 * self.constant_acceleration_time_s + self.cruise_time_s

    @property
    def peak_acceleration_m_per_s2(self) -> float:
        return self.jerk_m_per_s3 * self.jerk_time_s

    @property
    def peak_speed_m_per_s(self) -> float:
        return self.peak_acceleration_m_per_s2 * (self.jerk_time_s + self.constant_acceleration_time_s)

    @property
    def limits_reached(self) -> tuple[str, ...]:
        """Which limits the profile reaches ("speed": a cruise; "acceleration": a constant-acceleration phase;
        "jerk": always, for D > 0)."""
        if self.distance_m <= 0.0:
            return ()
        return tuple(k for k, on in zip(LIMITS, (self.cruise_time_s > 0.0, self.constant_acceleration_time_s > 0.0,
                                                 True), strict=True) if on)

    @property
    def time_saved_s(self) -> dict[str, float]:
        """Per limit, the time the move saves per relative relaxation of it, -dT/d(ln limit) (s): with a cruise
        (T = D/v + v/a + a/j, or D/v + 2 sqrt(v/j) when a is not reached) speed T_v + T_j, acceleration T_c,
        jerk T_j; without a cruise but with a reached (T = 2 (v_p/a + a/j)) speed 0, acceleration (3 e - 1) T
        and jerk (1 - 2 e) T, e = dlnT/dlnD = 2 D / (T (2 v_p + a^2/j)) (from the scalings T(kD, ka, kj) = T
        and T(D, a/k^2, j/k^3) = k T); jerk only (T = 4 (D / 2j)^(1/3)): jerk T/3. All 0 for D = 0."""
        t, tj, tc, tv = self.duration_s, self.jerk_time_s, self.constant_acceleration_time_s, self.cruise_time_s
        if self.distance_m <= 0.0:
            return dict.fromkeys(LIMITS, 0.0)
        if tv > 0.0:
            return {"speed": tv + tj, "acceleration": tc, "jerk": tj}
        if tc > 0.0:
            a, j = self.acceleration_m_per_s2, self.jerk_m_per_s3
            e = 2.0 * self.distance_m / (t * (2.0 * self.peak_speed_m_per_s + a * a / j))
            return {"speed": 0.0, "acceleration": (3.0 * e - 1.0) * t, "jerk": (1.0 - 2.0 * e) * t}
        return {"speed": 0.0, "acceleration": 0.0, "jerk": t / 3.0}

    @property
    def binding_limit(self) -> str:
        """The limit that binds the move most: the one whose relaxation saves the most time
        (:attr:`time_saved_s`; "speed" on a move that cruises long enough, "acceleration" or "jerk" otherwise);
        "" for D = 0."""
        if self.distance_m <= 0.0:
            return ""
        saved = self.time_saved_s
        return max(LIMITS, key=saved.__getitem__)

    def at(self, t_s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position (m, from 0 to D), speed (m/s) and acceleration (m/s^2) at ``t_s`` (s; clamped to [0, T])."""
        t = np.clip(np.asarray(t_s, dtype=float), 0.0, self.duration_s)
        half = 0.5 * self.duration_s
        mirrored = t > half
        tau = np.where(mirrored, self.duration_s - t, t)
        x, v, a = self._first_half(tau)
        return np.where(mirrored, self.distance_m - x, x), v, np.where(mirrored, -a, a)

    def fraction(self, t_s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """The fraction of the distance covered at ``t_s`` (s; elementwise on an array) and its rate (1/s): the
        shape of a straight segment (:class:`pressfit.dynamics.control.Trajectory`); (0, 0) for D = 0."""
        if self.distance_m <= 0.0:
            zero = np.zeros_like(np.asarray(t_s, dtype=float))
            return zero, zero
        x, v, _ = self.at(t_s)
        return x / self.distance_m, v / self.distance_m

    def _first_half(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The first half (jerk +j, 0, -j, then the cruise up to T/2), integrated exactly from the knots."""
        x, v, a = np.zeros_like(tau), np.zeros_like(tau), np.zeros_like(tau)
        for (t0, x0, v0, a0), jerk, end in zip(self._knots, (self.jerk_m_per_s3, 0.0, -self.jerk_m_per_s3, 0.0),
                                              (*(k[0] for k in self._knots[1:]), math.inf), strict=True):
            on = (tau >= t0) & (tau < end) if math.isfinite(end) else tau >= t0
            s = tau[on] - t0
            x[on] = x0 + v0 * s + a0 * s**2 / 2 + jerk * s**3 / 6
            v[on] = v0 + a0 * s + jerk * s**2 / 2
            a[on] = a0 + jerk * s
        return x, v, a


def s_curve(distance_m: float, speed_m_per_s: float, acceleration_m_per_s2: float, jerk_m_per_s3: float) -> SCurve:
    """The minimum-time rest-to-rest S-curve of a distance (m) under the three limits (module docstring)."""
    d, v, a, j = (float(x) for x in (distance_m, speed_m_per_s, acceleration_m_per_s2, jerk_m_per_s3))
    if not (math.isfinite(d) and d >= 0.0) or not all(math.isfinite(x) and x > 0.0 for x in (v, a, j)):
        raise ValueError(f"an S-curve needs a finite distance >= 0 and finite positive limits, got D = {d!r}, "
                         f"v = {v!r}, a = {a!r}, j = {j!r}")
    if v * j >= a * a:
        tj, tc = a / j, v / a - a / j
    else:
        tj, tc = math.sqrt(v / j), 0.0
    speed_up = 2.0 * tj + tc
    if d >= v * speed_up:
        tv = d / v - speed_up
    elif d >= 2.0 * a**3 / j**2 and v * j >= a * a:
        peak = 0.5 * (math.sqrt(a**4 / j**2 + 4.0 * a * d) - a * a / j)
        tj, tc, tv = a / j, max(peak / a - a / j, 0.0), 0.0
    else:
        tj, tc, tv = (d / (2.0 * j)) ** (1.0 / 3.0), 0.0, 0.0
    knots = [(0.0, 0.0, 0.0, 0.0)]
    for duration, jerk in ((tj, j), (tc, 0.0), (tj, -j)):
        t0, x0, v0, a0 = knots[-1]
        knots.append((t0 + duration, x0 + v0 * duration + a0 * duration**2 / 2 + jerk * duration**3 / 6,
                      v0 + a0 * duration + jerk * duration**2 / 2, a0 + jerk * duration))
    _, x3, v3, _ = knots[-1]
    knots[-1] = (knots[-1][0], x3, v3, 0.0)  # the acceleration is zero at the end of the speed-up (round-off)
    return SCurve(distance_m=d, speed_m_per_s=v, acceleration_m_per_s2=a, jerk_m_per_s3=j, jerk_time_s=tj,
                  constant_acceleration_time_s=tc, cruise_time_s=tv, _knots=tuple(knots))


def quintic(s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """The minimum-jerk (quintic) profile 10 s^3 - 15 s^4 + 6 s^5 and its derivative on s in [0, 1] (clamped;
    elementwise on an array)."""
    s = np.clip(s, 0.0, 1.0)
    return s**3 * (10 - 15 * s + 6 * s * s), 30 * s * s * (1 - s) ** 2


@dataclass(frozen=True, kw_only=True)
class Quintic:
    """The minimum-jerk rest-to-rest move of ``distance_m`` (m) in the least time ``duration_s`` (s) its peak
    speed 15 D / (8 T) (at s = 1/2), acceleration 10 D / (sqrt(3) T^2) (at s = (3 - sqrt(3)) / 6) and jerk
    60 D / T^3 (at both ends) allow under the three limits (:func:`quintic_move`)."""

    distance_m: float
    duration_s: float
    binding_limit: str

    @property
    def peak_speed_m_per_s(self) -> float:
        return 15.0 * self.distance_m / (8.0 * self.duration_s) if self.duration_s > 0 else 0.0

    @property
    def peak_acceleration_m_per_s2(self) -> float:
        return 10.0 * self.distance_m / (math.sqrt(3.0) * self.duration_s**2) if self.duration_s > 0 else 0.0

    @property
    def limits_reached(self) -> tuple[str, ...]:
        return (self.binding_limit,) if self.binding_limit else ()

    def fraction(self, t_s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """The fraction covered at ``t_s`` (s; elementwise on an array) and its rate (1/s), as the insertion's
        reference computes it."""
        if self.duration_s <= 0.0:
            zero = np.zeros_like(np.asarray(t_s, dtype=float))
            return zero, zero
        s, ds = quintic(np.asarray(t_s, dtype=float) / self.duration_s)
        return s, ds / self.duration_s


def quintic_move(distance_m: float, speed_m_per_s: float, acceleration_m_per_s2: float,
                 jerk_m_per_s3: float) -> Quintic:
    """The least-time quintic of a distance (m) under the three limits (:class:`Quintic`)."""
    d = float(distance_m)
    times = (15.0 * d / (8.0 * speed_m_per_s), math.sqrt(10.0 * d / (math.sqrt(3.0) * acceleration_m_per_s2)),
             (60.0 * d / jerk_m_per_s3) ** (1.0 / 3.0))
    k = int(np.argmax(times))
    return Quintic(distance_m=d, duration_s=float(times[k]), binding_limit=LIMITS[k] if d > 0 else "")


def s_curve_time_s(distance_m: float, speed_m_per_s: float, acceleration_m_per_s2: float,
                   jerk_m_per_s3: float) -> float:
    """The minimum time (s) of a rest-to-rest move of ``distance_m`` under the three limits."""
    return s_curve(distance_m, speed_m_per_s, acceleration_m_per_s2, jerk_m_per_s3).duration_s
