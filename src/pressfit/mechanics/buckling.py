"""Euler buckling of a leg: a stepped column (cylinder tube + stem rod), pinned at both cardans.

End conditions: both ends pinned (the cardans carry no bending moment about their own axes; the
couple a UPU leg carries along c_i is a load, not a clamp), no lateral sway, load along the leg line.
With EI_1 over the cylinder length a and EI_2 over the stem length b, k_j = sqrt(P / EI_j), the
buckled shapes sin(k_1 x) and sin(k_2 (L - x)) match in deflection and slope at the step when

    k_2 sin(k_1 a) cos(k_2 b) + k_1 sin(k_2 b) cos(k_1 a) = 0,

whose smallest root P > 0 is the critical load. For EI_1 = EI_2 it reduces to pi^2 EI / L^2.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from pressfit.description.machine import Machine


def stepped_column_critical_load_n(ei_1_nm2: float, length_1_m: float, ei_2_nm2: float,
                                   length_2_m: float) -> float:
    """Smallest Euler load (N) of a pinned-pinned column of two prismatic segments."""
    def g(p: float) -> float:
        k1, k2 = np.sqrt(p / ei_1_nm2), np.sqrt(p / ei_2_nm2)
        return k2 * np.sin(k1 * length_1_m) * np.cos(k2 * length_2_m) \
            + k1 * np.sin(k2 * length_2_m) * np.cos(k1 * length_1_m)

    total = length_1_m + length_2_m
    lo = 0.999 * np.pi**2 * min(ei_1_nm2, ei_2_nm2) / total**2  # bounds of the stepped column
    hi = 1.001 * np.pi**2 * max(ei_1_nm2, ei_2_nm2) / total**2
    grid = np.linspace(lo, hi, 64)
    vals = [g(p) for p in grid]
    i = next(i for i in range(63) if np.sign(vals[i]) != np.sign(vals[i + 1]))
    return float(brentq(g, grid[i], grid[i + 1], xtol=1e-10, rtol=1e-13))


def leg_critical_load_n(machine: Machine, leg_length_m: float) -> float:
    """Euler critical compression (N) of a leg of length l (cylinder from the base, stem above)."""
    e = machine.material.youngs_modulus_pa
    lc = machine.cylinder.length_m
    return stepped_column_critical_load_n(e * machine.cylinder_section.second_moment_m4, lc,
                                          e * machine.stem_section.second_moment_m4, leg_length_m - lc)


def leg_critical_loads_n(machine: Machine, leg_lengths_m: np.ndarray) -> np.ndarray:
    """Vectorised over leg lengths by interpolation on a fine table (error < 1e-6 relative)."""
    lengths = np.asarray(leg_lengths_m, dtype=float)
    lo = machine.cylinder.length_m * 1.0001
    hi = max(float(lengths.max(initial=lo)), machine.limits.leg_length_max_m) * 1.0001
    table_l = np.linspace(lo, hi, 2049)
    table_p = np.log([leg_critical_load_n(machine, x) for x in table_l])
    return np.exp(np.interp(lengths, table_l, table_p))
