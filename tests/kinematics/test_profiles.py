"""The S-curve rest-to-rest move (pressfit.kinematics.profiles) against closed forms derived here, and its
properties under hypothesis."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pressfit.kinematics.profiles import s_curve, s_curve_time_s

V, A, J = 0.5, 2.0, 40.0  # a typical cell: v j = 20 >= a^2 = 4, so a is reached on the way to v


def test_long_move_time_is_distance_over_speed_plus_v_over_a_plus_a_over_j():
    # D >= v (v/a + a/j): cruise; the speed-up takes v/a + a/j and covers half of v (v/a + a/j) twice
    d = 1.0
    assert s_curve_time_s(d, V, A, J) == pytest.approx(d / V + V / A + A / J, rel=1e-14)
    profile = s_curve(d, V, A, J)
    assert profile.limits_reached == ("speed", "acceleration", "jerk")
    # the cruise takes D/v - v/a - a/j = 1.65 s of the 2.35 s: the speed holds it longest
    assert profile.cruise_time_s == pytest.approx(d / V - V / A - A / J, rel=1e-13) and profile.binding_limit == "speed"


def test_speed_not_reached_but_acceleration_reached():
    # 2 a^3/j^2 = 0.01 m <= D = 0.1 m < v (v/a + a/j) = 0.15 m: peak speed from v_p^2 + v_p a^2/j - a D = 0
    d = 0.1
    vp = (-A * A / J + math.sqrt((A * A / J) ** 2 + 4 * A * d)) / 2
    profile = s_curve(d, V, A, J)
    assert profile.duration_s == pytest.approx(2 * (vp / A + A / J), rel=1e-13)
    assert profile.peak_speed_m_per_s == pytest.approx(vp, rel=1e-13)
    # constant acceleration 2 T_c = 2 (v_p/a - a/j) = 0.258 s against 4 T_j = 4 a/j = 0.2 s of jerk phases
    assert 2 * (vp / A - A / J) > 4 * A / J and profile.binding_limit == "acceleration"
    # the distance check: the speed-up covers v_p (v_p/a + a/j) / 2, the move twice that
    assert vp * (vp / A + A / J) == pytest.approx(d, rel=1e-13)


def test_triangular_jerk_only_move():
    # D < 2 a^3/j^2 = 0.01 m: +j, -j, -j, +j phases of equal length T_j, D = 2 j T_j^3
    d = 0.004
    tj = (d / (2 * J)) ** (1 / 3)
    profile = s_curve(d, V, A, J)
    assert profile.duration_s == pytest.approx(4 * tj, rel=1e-13)
    assert profile.peak_acceleration_m_per_s2 == pytest.approx(J * tj, rel=1e-13) and J * tj < A
    assert profile.binding_limit == "jerk"


def test_acceleration_never_reached_when_v_j_below_a_squared():
    # v j = 0.5 * 2 = 1 < a^2 = 4: T_j = sqrt(v/j), the speed-up 2 sqrt(v/j) covers v sqrt(v/j)
    v, a, j = 0.5, 2.0, 2.0
    d = 2.0
    assert s_curve_time_s(d, v, a, j) == pytest.approx(d / v + 2 * math.sqrt(v / j), rel=1e-14)
    assert s_curve(d, v, a, j).limits_reached == ("speed", "jerk")
    short = 0.1  # below v 2 sqrt(v/j) = 0.5 m: triangular
    assert s_curve_time_s(short, v, a, j) == pytest.approx(4 * (short / (2 * j)) ** (1 / 3), rel=1e-13)


def test_time_is_continuous_across_the_case_boundaries():
    for d in (2 * A**3 / J**2, V * (V / A + A / J)):  # where a, then v, start to be reached
        below, above = s_curve_time_s(d * (1 - 1e-9), V, A, J), s_curve_time_s(d * (1 + 1e-9), V, A, J)
        assert abs(above - below) < 1e-8


def test_profile_integrates_its_own_speed():
    # an independent check of the piecewise polynomials: x(T) by trapezoidal integration of v(t)
    profile = s_curve(0.3, V, A, J)
    t = np.linspace(0.0, profile.duration_s, 200001)
    x, v, a = profile.at(t)
    assert np.trapezoid(v, t) == pytest.approx(0.3, rel=1e-9)
    assert np.max(np.abs(np.gradient(v, t) - a)) < 1e-3 * A


def test_zero_distance_and_bad_limits():
    assert s_curve_time_s(0.0, V, A, J) == 0.0
    assert s_curve(0.0, V, A, J).fraction(0.5) == (0.0, 0.0)
    with pytest.raises(ValueError, match="positive limits"):
        s_curve(1.0, 0.0, A, J)
    with pytest.raises(ValueError, match="distance"):
        s_curve(math.nan, V, A, J)


positive = st.floats(1e-3, 1e3)


@settings(max_examples=200, deadline=None)
@given(d=st.just(0.0) | st.floats(1e-9, 2.0), v=positive, a=positive, j=positive)  # nm and up
def test_properties(d, v, a, j):
    profile = s_curve(d, v, a, j)
    t = np.linspace(0.0, profile.duration_s, 2001)
    x, speed, acc = profile.at(t)
    assert x[0] == 0.0 and x[-1] == d and speed[-1] == 0.0 and acc[-1] == 0.0  # endpoints exact
    assert np.all(np.diff(x) >= -1e-12 * max(d, 1e-300))  # monotone
    assert np.all(speed >= 0.0) and speed.max() <= v * (1 + 1e-12)
    assert np.abs(acc).max() <= a * (1 + 1e-12)
    if d > 0:
        jerk = np.abs(np.diff(acc) / np.diff(t))
        assert jerk.max() <= j * (1 + 1e-6)


def closed_form_time_s(d, v, a, j):
    """The S-curve's minimum time, written here from the textbook cases (the module docstring's derivation)."""
    if v * j >= a * a:
        t_a = v / a + a / j
    else:
        t_a = 2 * math.sqrt(v / j)
    if d >= v * t_a:
        return d / v + t_a
    if d >= 2 * a**3 / j**2:
        vp = (math.sqrt(a**4 / j**2 + 4 * a * d) - a * a / j) / 2
        if vp * j >= a * a:
            return 2 * (vp / a + a / j)
    return 4 * (d / (2 * j)) ** (1 / 3)


@pytest.mark.parametrize(("d", "v", "a", "j", "binding"), [
    (0.26, 0.5, 2.0, 20.0, "speed"),       # the board's approach: a 0.17 s cruise, 0.4 s of jerk phases
    (2.0, 0.5, 2.0, 20.0, "speed"),        # a long cruise
    (0.51125, 0.5, 0.5, 40.0, "acceleration"),  # a 0.01 s cruise, 2 T_c = 1.975 s at constant acceleration
    (0.1, 0.5, 2.0, 40.0, "acceleration"),  # no cruise, a reached for most of the move
    (0.1, 0.5, 2.0, 20.0, "jerk"),          # the board's traverse: no cruise, a reached only briefly
    (0.004, 0.5, 2.0, 40.0, "jerk"),        # jerk only: a never reached
])
def test_the_binding_limit_is_the_one_whose_relaxation_saves_the_most_time(d, v, a, j, binding):
    """issue 28 item 8: the time saved per relative relaxation of each limit, -dT/dln(limit), against a central
    difference (1e-6) of the closed-form time written above (agreement ~1e-9 s: tolerance 1e-7 s), and the binding
    label is the largest; the board's approach cruises at the speed limit and is "speed" (it read "jerk")."""
    profile = s_curve(d, v, a, j)
    assert profile.duration_s == pytest.approx(closed_form_time_s(d, v, a, j), rel=1e-12)
    h = 1e-6
    limits = {"speed": 0, "acceleration": 1, "jerk": 2}
    for name, k in limits.items():
        up, down = [v, a, j], [v, a, j]
        up[k] *= math.exp(h)
        down[k] *= math.exp(-h)
        expected = -(closed_form_time_s(d, *up) - closed_form_time_s(d, *down)) / (2 * h)
        assert profile.time_saved_s[name] == pytest.approx(expected, abs=1e-7), name
    assert profile.binding_limit == binding
