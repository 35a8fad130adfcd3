r"""The paper's law (section 4.2: a force proportional to the interference) and the press fit on top of it:
F(d) = k d + f_fit(d) for d > 0, 0 otherwise; ``press_fit``: f_fit = k_fit d (``fit = "linear"``) or
F_fit tanh(d / d_fit) (``"saturating"``). k in N/m, d in m. The insertion kernels keep their own compiled codes
for it (``ELASTIC``, ``FIT_LINEAR``, ``FIT_TANH`` of :mod:`pressfit.dynamics.kernels`): the numbers of the paper's
cases are unchanged."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True, kw_only=True)
class ElasticLaw:
    """k d (+ the fit force): ``stiffness_n_per_m`` k, ``fit`` ("none", "linear" or "saturating"),
    ``fit_stiffness_n_per_m``, ``fit_force_n``, ``fit_depth_m``."""

    stiffness_n_per_m: float
    fit: str = "none"
    fit_stiffness_n_per_m: float = 0.0
    fit_force_n: float = 0.0
    fit_depth_m: float = 1e-3

    depth_range_m = (0.0, math.inf)
    plateau_force_n = None
    seat_depth_m = None
    reversible = True  # a spring: backing off follows the law down (the paper's contact)
    notes: tuple[str, ...] = ()

    def force_n(self, depth_m: np.ndarray) -> np.ndarray:
        return self.force_and_slope(depth_m)[0]

    def force_and_slope(self, depth_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """F(d) (N) and dF/dd (N/m): k (+ k_fit, or + F_fit / d_fit cosh^-2(d / d_fit)) where F > 0, else 0."""
        d = np.asarray(depth_m, dtype=float)
        f, slope = self.stiffness_n_per_m * d, self.stiffness_n_per_m + 0.0 * d
        if self.fit == "linear":
            f, slope = f + self.fit_stiffness_n_per_m * d, slope + self.fit_stiffness_n_per_m
        elif self.fit == "saturating":
            f = f + self.fit_force_n * np.tanh(d / self.fit_depth_m)
            slope = slope + self.fit_force_n / self.fit_depth_m / np.cosh(d / self.fit_depth_m) ** 2
        on = (d > 0.0) & (f > 0.0)
        return np.where(d > 0.0, np.maximum(f, 0.0), 0.0), np.where(on, slope, 0.0)


def from_keys(law: str, keys: Mapping[str, Any]) -> ElasticLaw:
    """``elastic`` (k only) or ``press_fit`` (k and the fit)."""
    if law == "elastic":
        return ElasticLaw(stiffness_n_per_m=float(keys["stiffness_n_per_m"]))
    return ElasticLaw(stiffness_n_per_m=float(keys["stiffness_n_per_m"]), fit=str(keys["fit"]),
                      fit_stiffness_n_per_m=float(keys["fit_stiffness_n_per_m"]),
                      fit_force_n=float(keys["fit_force_n"]),
                      fit_depth_m=float(keys["fit_depth_m"]))
