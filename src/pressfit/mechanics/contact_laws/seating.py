r"""The component's shoulder reaching the board: F_seat(d) = k_s max(0, d - d_s) added to the pin's law
(``seat_depth_m`` d_s, m; ``seat_stiffness_n_per_m`` k_s, N/m, per pin): the sharp rise a press monitor uses to
detect "seated". The law's depth range ends at d_s + ``SEAT_OVERTRAVEL_M`` (the shoulder stops the stroke)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

SEAT_OVERTRAVEL_M = 20e-6  # m: how far past the seat a predicted curve runs (k_s x 20 um: the seating rise)


@dataclass(frozen=True, kw_only=True)
class Seated:
    """``law`` plus the shoulder (module docstring)."""

    law: Any  # a ContactLawModel
    seat_depth_m: float
    seat_stiffness_n_per_m: float

    @property
    def depth_range_m(self) -> tuple[float, float]:
        return self.law.depth_range_m[0], self.seat_depth_m + SEAT_OVERTRAVEL_M  # the shoulder stops the stroke

    @property
    def plateau_force_n(self) -> float | None:
        return self.law.plateau_force_n

    @property
    def notes(self) -> tuple[str, ...]:
        return self.law.notes

    @property
    def reversible(self) -> bool:
        return self.law.reversible

    def __getattr__(self, name: str) -> Any:  # the law's own figures (retention, pressure, ...)
        if name == "law":
            raise AttributeError(name)
        return getattr(self.law, name)

    def force_n(self, depth_m: np.ndarray) -> np.ndarray:
        return self.force_and_slope(depth_m)[0]

    def force_and_slope(self, depth_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The force (N) and its slope (N/m): the law's plus k_s past the shoulder (k_s at d > d_s)."""
        d = np.asarray(depth_m, dtype=float)
        f, slope = self.law.force_and_slope(d)
        return (f + self.seat_stiffness_n_per_m * np.maximum(d - self.seat_depth_m, 0.0),
                slope + np.where(d > self.seat_depth_m, self.seat_stiffness_n_per_m, 0.0))
