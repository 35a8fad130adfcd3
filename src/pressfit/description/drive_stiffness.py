r"""Axial stiffness of a drive from its datasheet numbers (SI), for the statics (description level: the
mechanics uses it through :meth:`pressfit.description.machine.Machine.axial_compliance_m_per_n`; see
docs/drives.md).

* Ball screw (``[actuator.electric]``): the screw between its fixed bearing and the nut is a bar of
  stiffness E A / L_free, A = pi d^2 / 4 of the screw's root diameter d, L_free growing with the leg length
  when the nut travels away from the bearing; in series with the nut and the bearing:

      1 / k = L_free / (E A) + 1 / k_nut + 1 / k_bearing.

* Oil column (``[actuator.hydraulic]``, valve closed): chamber j of volume V_j (dead volume plus the
  swept volume at the current piston position) is a spring beta A^2 / V_j; both chambers act in parallel on
  the piston,

      k_h = beta A^2 (1 / V_a + 1 / V_b),

  smallest at mid-stroke for a symmetric cylinder with equal dead volumes.
"""

from __future__ import annotations

import numpy as np


def screw_axial_stiffness_n_per_m(youngs_modulus_pa: float, root_diameter_m: float,
                                  free_length_m: np.ndarray | float, nut_stiffness_n_per_m: float,
                                  bearing_stiffness_n_per_m: float) -> np.ndarray:
    """Ball screw E A / L_free (A from the root diameter, m) in series with nut and bearing stiffness, N/m."""
    area = np.pi / 4.0 * root_diameter_m**2
    compliance = (np.asarray(free_length_m, dtype=float) / (youngs_modulus_pa * area)
                  + 1.0 / nut_stiffness_n_per_m + 1.0 / bearing_stiffness_n_per_m)
    return 1.0 / compliance


def chamber_volumes_m3(piston_area_m2: float, stroke_m: float, piston_position_m: np.ndarray | float,
                       dead_volume_a_m3: float, dead_volume_b_m3: float) -> tuple[np.ndarray, np.ndarray]:
    """Oil volumes (m^3) of chamber a (its pressure pulls the leg shorter: V_a = V_0a + A (s - x)) and of
    chamber b (V_b = V_0b + A x) at the piston position x in [0, s] (m, from the base-side end)."""
    x = np.asarray(piston_position_m, dtype=float)
    return dead_volume_a_m3 + piston_area_m2 * (stroke_m - x), dead_volume_b_m3 + piston_area_m2 * x


def oil_column_stiffness_n_per_m(bulk_modulus_pa: float, piston_area_m2: float, volume_a_m3: np.ndarray | float,
                                 volume_b_m3: np.ndarray | float) -> np.ndarray:
    """k_h = beta A^2 (1 / V_a + 1 / V_b), N/m (module docstring)."""
    return bulk_modulus_pa * piston_area_m2**2 * (1.0 / np.asarray(volume_a_m3, dtype=float)
                                                  + 1.0 / np.asarray(volume_b_m3, dtype=float))
