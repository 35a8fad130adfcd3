"""Property-based checks (hypothesis, derandomized) over random reachable poses and press loads.

References: equilibrium and closure residuals (definition, tolerance 1e-9 as Residuals.is_valid), the
second-order condition of a stable minimum (Stability), linearity of the small-displacement model
(superposition and proportionality hold exactly; 1e-9 relative is ~1e5 times the round-off achieved).
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from pressfit import kinematics
from pressfit.mechanics.statics import solve_equilibrium

SETTINGS = settings(max_examples=15, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.filter_too_much])

poses = st.tuples(st.floats(-0.25, 0.25), st.floats(0.45, 0.8), st.floats(-0.25, 0.25))
press = st.tuples(st.floats(-0.3, 0.3), st.floats(0.5, 1.0), st.floats(-0.3, 0.3), st.floats(10.0, 5000.0))


def _load(p):  # a press force (N) within ~17 degrees of +y
    d = np.array(p[:3])
    return np.concatenate([p[3] * d / np.linalg.norm(d), np.zeros(3)])


@pytest.mark.slow
@SETTINGS
@given(pose=poses, p=press)
def test_nonlinear_press_solutions_are_stable_equilibria(machine, pose, p):
    assume(kinematics.is_reachable(machine, np.array([pose]))[0])  # an unreachable draw is not a pass
    eq = solve_equilibrium(machine, pose, _load(p))
    assert eq.is_valid(1e-9)
    assert eq.stability.stable and eq.stability.kkt_negative_eigenvalues == 24


@pytest.mark.slow
@SETTINGS
@given(pose=poses, p=press, q=press, a=st.floats(-2.0, 2.0))
def test_linear_solve_superposes_and_scales(machine, pose, p, q, a):
    """a w1 + w2 (|a| <= 2, below every buckling load: the linear solve checks stability too)."""
    assume(kinematics.is_reachable(machine, np.array([pose]))[0])  # an unreachable draw is not a pass
    w1, w2 = _load(p), _load(q)
    s1, s2 = (solve_equilibrium(machine, pose, w, linear=True) for w in (w1, w2))
    s = solve_equilibrium(machine, pose, a * w1 + w2, linear=True)
    scale = np.abs(a * s1.multipliers).max() + np.abs(s2.multipliers).max()
    assert np.abs(s.multipliers - (a * s1.multipliers + s2.multipliers)).max() < 1e-9 * scale
    u = np.abs(a * s1.plate_displacement_m).max() + np.abs(s2.plate_displacement_m).max()
    assert np.abs(s.plate_displacement_m - (a * s1.plate_displacement_m + s2.plate_displacement_m)).max() < 1e-9 * u
