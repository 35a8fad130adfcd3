r"""An eye-of-needle (compliant) press-fit zone: an elastic-plastic radial spring pushed through a lead-in.

The zone of width w (``zone_width_m``) across a hole of diameter d_h (``hole_diameter_m``) is squeezed by
delta = w - d_h (m, diametral). Its radial spring (the force N across the zone, N, against its diametral
compression x, m) is elastic-plastic: N(x) = k x up to the yield force F_y (x_y = F_y / k), then
N(x) = F_y + k_p (x - x_y) (``radial_stiffness_n_per_m`` k, ``radial_yield_force_n`` F_y,
``post_yield_stiffness_n_per_m`` k_p). The depth z (m) is the travel of the zone's leading end into the hole:

* over the lead-in (0 <= z <= L_l, ``lead_in_length_m``) the squeeze rises linearly, x = delta z / L_l, on a taper
  of slope t = (delta / 2) / L_l against the hole's edge: both flanks are wedged in with friction mu
  (``friction_coefficient``), F = 2 N(x) (mu + t) / (1 - mu t) (the rise);
* after the lead-in the wedge's share falls linearly to 0 over ``FADE_FRACTION`` L_l (the taper's crest moving
  into the hole; a modelling choice): the peak at z = L_l;
* then the zone slides with the full squeeze, F = 2 mu N(delta): the plateau, over ``zone_length_m`` L_z;
* then the zone's trailing end leaves the hole over L_l, the squeeze unloading elastically from its plastic set:
  N = max(0, N(delta) - k (delta - x)), F = 2 mu N.

The retention (push-out) force estimate after insertion is the static friction on the normal force the zone holds,
2 mu N(delta), without the wedge (an upper estimate: the board's relaxation, which lowers it over time, is not
modelled). Forces in N, lengths in m.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

FADE_FRACTION = 1.0  # the wedge's share fades over this fraction of the lead-in's length after the peak


@dataclass(frozen=True, kw_only=True)
class CompliantPinLaw:
    """The compliant zone's law (module docstring)."""

    squeeze_m: float
    radial_stiffness_n_per_m: float
    radial_yield_force_n: float
    post_yield_stiffness_n_per_m: float
    zone_length_m: float
    lead_in_length_m: float
    friction_coefficient: float
    notes: tuple[str, ...] = ()
    reversible = False  # friction sets the joint: backing off unloads it elastically (contact_laws docstring)

    seat_depth_m = None

    def radial_force_n(self, compression_m: np.ndarray) -> np.ndarray:
        """N(x), N, on the loading branch (module docstring)."""
        return self._radial(compression_m)[0]

    def _radial(self, compression_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """N(x) (N) and dN/dx (N/m: k, then k_p past the yield; k at x <= 0, the loading side)."""
        x = np.maximum(np.asarray(compression_m, dtype=float), 0.0)
        k, fy = self.radial_stiffness_n_per_m, self.radial_yield_force_n
        kx = k * x
        elastic = kx <= fy
        return (np.where(elastic, kx, fy + self.post_yield_stiffness_n_per_m * (x - fy / k)),
                np.where(elastic, k, self.post_yield_stiffness_n_per_m))

    @property
    def taper(self) -> float:
        """t = (delta / 2) / L_l, the lead-in's slope (-)."""
        return 0.5 * self.squeeze_m / self.lead_in_length_m

    @property
    def held_normal_force_n(self) -> float:
        """N(delta), N: the force across the zone once fully in the hole (an array for stacked laws)."""
        held = self.radial_force_n(self.squeeze_m)
        return float(held) if held.ndim == 0 else held

    @property
    def plastic_set_m(self) -> float:
        """The zone's permanent diametral set after it is pushed out (m): delta - N(delta) / k."""
        return max(0.0, self.squeeze_m - self.held_normal_force_n / self.radial_stiffness_n_per_m)

    @property
    def peak_force_n(self) -> float:
        """The force at the end of the lead-in, 2 N(delta) (mu + t) / (1 - mu t), N."""
        mu, t = self.friction_coefficient, self.taper
        return 2.0 * self.held_normal_force_n * (mu + t) / (1.0 - mu * t)

    @property
    def plateau_force_n(self) -> float:
        return 2.0 * self.friction_coefficient * self.held_normal_force_n

    @property
    def retention_force_n(self) -> float:
        """The push-out force estimate, 2 mu N(delta), N (module docstring)."""
        return self.plateau_force_n

    @property
    def depth_range_m(self) -> tuple[float, float]:
        return 0.0, 2.0 * self.lead_in_length_m + self.zone_length_m

    def force_n(self, depth_m: np.ndarray) -> np.ndarray:
        return self.force_and_slope(depth_m)[0]

    def force_and_slope(self, depth_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """F(z) (N, module docstring) and dF/dz (N/m) in closed form: with g(w) = (mu + w) / (1 - mu w),
        F = 2 N g(w) and dF/dz = 2 (N' g + N g'(w) w'), g'(w) = (1 + mu^2) / (1 - mu w)^2; at a kink (the lead-in's
        end, the yield, the fade's end, the exit's start) the slope of one of its sides. The fields may be arrays
        (n,) (a stacked field of pins, :func:`pressfit.mechanics.contact_laws.stack_laws`) against depths (..., n)."""
        z = np.asarray(depth_m, dtype=float)
        mu, t, ll = self.friction_coefficient, self.taper, self.lead_in_length_m
        fade = FADE_FRACTION * ll
        s, k = self.squeeze_m, self.radial_stiffness_n_per_m
        past = (z - ll) / fade  # the fade's progress: <= 0 over the lead-in (the full wedge t)
        wedge = t * np.clip(1.0 - past, 0.0, 1.0)
        exit_start = ll + self.zone_length_m
        radial, d_radial = self._radial(s * np.clip(z / ll, 0.0, 1.0))
        unloaded = self.radial_force_n(s) - k * s * np.clip((z - exit_start) / ll, 0.0, 1.0)
        inside = z <= exit_start
        normal = np.where(inside, radial, np.maximum(0.0, unloaded))
        exiting = ~inside & (z < exit_start + ll) & (unloaded > 0.0)
        d_normal = np.where(z < ll, d_radial * (s / ll), exiting * (-k * s / ll))
        d_wedge = ((past > 0.0) & (past < 1.0)) * (-t / fade)
        denominator = 1.0 - mu * wedge
        f = 2.0 * normal * (mu + wedge) / denominator  # 0 at z <= 0 (no squeeze)
        slope = 2.0 * (d_normal * (mu + wedge) / denominator + normal * (1.0 + mu * mu) / denominator**2 * d_wedge)
        return f, slope * (z > 0.0)


def from_keys(law: str, keys: Mapping[str, Any]) -> CompliantPinLaw:
    return CompliantPinLaw(squeeze_m=float(keys["zone_width_m"]) - float(keys["hole_diameter_m"]),
                           radial_stiffness_n_per_m=float(keys["radial_stiffness_n_per_m"]),
                           radial_yield_force_n=float(keys["radial_yield_force_n"]),
                           post_yield_stiffness_n_per_m=float(keys["post_yield_stiffness_n_per_m"]),
                           zone_length_m=float(keys["zone_length_m"]), lead_in_length_m=float(keys["lead_in_length_m"]),
                           friction_coefficient=float(keys["friction_coefficient"]))
