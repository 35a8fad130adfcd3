r"""A cylindrical interference fit (a solid pin pressed into a plated hole), the thick-wall (Lame) equations.

The diametral interference delta = d_pin - d_hole (m) over the nominal diameter d = d_hole gives the contact
pressure of a solid shaft (pin: E_p, nu_p) in a hub (board: E_b, nu_b, outer diameter D; Shigley, the press and
shrink fit):

.. math:: p = \frac{\delta}{d\left[\frac{1}{E_b}\left(\frac{D^2 + d^2}{D^2 - d^2} + \nu_b\right)
          + \frac{1 - \nu_p}{E_p}\right]}

and, for the infinite plate (no ``board_outer_diameter_m``: D -> inf, the factor (D^2 + d^2)/(D^2 - d^2) -> 1),
p = delta / (d [(1 + nu_b)/E_b + (1 - nu_p)/E_p]) (Pa). ``board_yield_strength_pa`` sigma_y caps p at sigma_y
(the hole wall yields; the law says so in ``notes``). Press-in force (N) at the depth z of the pin's tip below the
board face (m):

.. math:: F(z) = \mu\, p\, \pi d\, L_{eng}(z), \qquad
          L_{eng}(z) = G(z) - G(\max(0, z - L_b)), \quad
          G(s) = \int_0^s \min(t / L_c, 1)\, dt

(the chamfer of length L_c at the tip carries an interference rising linearly from 0 to delta, the pressure
proportional to the local interference; L_b = ``engaged_length_m``, the board thickness): quadratic over the
chamfer, linear to the plateau F_p = mu p pi d L_b once the pin's full diameter has crossed the board, from
z = L_b + L_c on.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np


def lame_pressure_pa(*, interference_m: float, diameter_m: float, pin_youngs_modulus_pa: float,
                     pin_poisson_ratio: float, board_youngs_modulus_pa: float, board_poisson_ratio: float,
                     board_outer_diameter_m: float | None = None) -> float:
    """The elastic contact pressure p (Pa) of a solid pin in a hub of outer diameter D (None: an infinite plate)
    for a diametral interference (m) at the nominal diameter (m) (module docstring)."""
    d = diameter_m
    ratio = 1.0 if board_outer_diameter_m is None else (
        (board_outer_diameter_m**2 + d**2) / (board_outer_diameter_m**2 - d**2))
    return interference_m / (d * ((ratio + board_poisson_ratio) / board_youngs_modulus_pa
                                  + (1.0 - pin_poisson_ratio) / pin_youngs_modulus_pa))


@dataclass(frozen=True, kw_only=True)
class SolidPinLaw:
    """The solid pin's law (module docstring): its elastic pressure, the pressure it uses (capped), the plateau."""

    diameter_m: float
    interference_m: float
    elastic_pressure_pa: float
    pressure_pa: float
    friction_coefficient: float
    engaged_length_m: float
    chamfer_length_m: float
    capped: bool
    notes: tuple[str, ...] = ()
    reversible = False  # friction sets the joint: backing off unloads it elastically (contact_laws docstring)

    seat_depth_m = None

    @property
    def depth_range_m(self) -> tuple[float, float]:
        return 0.0, self.engaged_length_m + self.chamfer_length_m

    @property
    def plateau_force_n(self) -> float:
        return self.friction_coefficient * self.pressure_pa * math.pi * self.diameter_m * self.engaged_length_m

    def engaged_length(self, depth_m: np.ndarray) -> np.ndarray:
        """L_eng(z) (m), the chamfer's share weighted by its interference (module docstring)."""
        return self._engaged(depth_m)[0]

    def _engaged(self, depth_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """L_eng(z) (m) and dL_eng/dz (-) = G'(z) - G'(z - L_b), G'(s) = min(s / L_c, 1) for s > 0, else 0."""
        z = np.asarray(depth_m, dtype=float)
        c = self.chamfer_length_m
        c_or_1 = np.where(c > 0.0, c, 1.0)  # no chamfer: only s <= c = 0, i.e. s = 0, takes the quadratic branch

        def g(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            s = np.maximum(s, 0.0)
            chamfer = s <= c
            return (np.where(chamfer, s * s / (2.0 * c_or_1), s - 0.5 * c),
                    np.where(chamfer, s / c_or_1, np.where(s > 0.0, 1.0, 0.0)))

        (g0, s0), (g1, s1) = g(z), g(z - self.engaged_length_m)
        return g0 - g1, s0 - s1

    def force_n(self, depth_m: np.ndarray) -> np.ndarray:
        return self.force_and_slope(depth_m)[0]

    def force_and_slope(self, depth_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """F(z) (N, module docstring) and dF/dz = mu p pi d dL_eng/dz (N/m); the fields may be arrays (n,) against
        depths (..., n) (a stacked field of pins)."""
        z = np.asarray(depth_m, dtype=float)
        unit = self.friction_coefficient * self.pressure_pa * math.pi * self.diameter_m
        length, d_length = self._engaged(z)
        positive = z > 0.0
        return np.where(positive, unit * length, 0.0), np.where(positive, unit * d_length, 0.0)


def from_keys(law: str, keys: Mapping[str, Any]) -> SolidPinLaw:
    d = float(keys["hole_diameter_m"])
    delta = float(keys["pin_diameter_m"]) - d
    p = lame_pressure_pa(interference_m=delta, diameter_m=d, pin_youngs_modulus_pa=keys["pin_youngs_modulus_pa"],
                         pin_poisson_ratio=keys["pin_poisson_ratio"],
                         board_youngs_modulus_pa=keys["board_youngs_modulus_pa"],
                         board_poisson_ratio=keys["board_poisson_ratio"],
                         board_outer_diameter_m=keys.get("board_outer_diameter_m"))
    cap = keys.get("board_yield_strength_pa")
    capped = cap is not None and p > cap
    notes = (f"the Lame pressure {p:.4g} Pa exceeds board_yield_strength_pa = {cap:.4g} Pa: capped at the yield "
             "strength (the hole wall yields)",) if capped else ()
    return SolidPinLaw(diameter_m=d, interference_m=delta, elastic_pressure_pa=p,
                       pressure_pa=float(cap) if capped else p,
                       friction_coefficient=float(keys["friction_coefficient"]),
                       engaged_length_m=float(keys["engaged_length_m"]),
                       chamfer_length_m=float(keys.get("chamfer_length_m") or 0.0), capped=capped, notes=notes)
