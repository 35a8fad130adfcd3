"""Euler buckling of the stepped leg column against closed forms (Euler 1744; Timoshenko & Gere,
Theory of Elastic Stability, 2nd ed., section 2.10, stepped pinned-pinned column)."""

import math

import pytest

from pressfit.mechanics.buckling import leg_critical_load_n, leg_critical_loads_n, stepped_column_critical_load_n


def test_uniform_column_is_euler():
    # equal segments: the stepped column is a uniform one, P_cr = pi^2 EI / L^2 (exact up to root tol)
    assert stepped_column_critical_load_n(2.0e4, 0.3, 2.0e4, 0.5) == pytest.approx(math.pi**2 * 2e4 / 0.8**2, rel=1e-10)


def test_symmetric_stepped_column_transcendental_root():
    # Symmetric column: stiff middle replaced by two halves -> with segments EI1 (length a) and EI2
    # (length b) the condition k2 tan(k1 a) = -k1 tan(k2 b); check the returned root satisfies it
    # and lies between the Euler loads of the weakest and the stiffest uniform column.
    ei1, a, ei2, b = 6.9e4, 0.45, 8.3e3, 0.3
    p = stepped_column_critical_load_n(ei1, a, ei2, b)
    k1, k2 = math.sqrt(p / ei1), math.sqrt(p / ei2)
    assert k2 * math.tan(k1 * a) + k1 * math.tan(k2 * b) == pytest.approx(0.0, abs=1e-6 * (k1 + k2))
    assert math.pi**2 * ei2 / (a + b) ** 2 < p < math.pi**2 * ei1 / (a + b) ** 2


def test_order_of_segments_does_not_matter():
    # mirror symmetry of a pinned-pinned column
    assert stepped_column_critical_load_n(5e4, 0.45, 8e3, 0.3) == pytest.approx(
        stepped_column_critical_load_n(8e3, 0.3, 5e4, 0.45), rel=1e-10)


def test_vectorised_table_matches_direct_root(machine):
    for length in (0.5, 0.73, 1.0):
        assert leg_critical_loads_n(machine, [length])[0] == pytest.approx(leg_critical_load_n(machine, length), rel=1e-6)
