r"""Force against depth from a CSV file (a datasheet's or a measured curve; ``table_path``, relative to the case
file; header ``depth_m,force_n``, read by :func:`pressfit.description.cases.read_force_table`): linear
interpolation between the rows, 0 at depth <= 0 and before the first row's depth, the last row's force held past
the last row. N against m."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pressfit.description.cases import read_force_table


@dataclass(frozen=True, kw_only=True)
class TabulatedLaw:
    """The table (depths m, forces N) and where it came from."""

    depth_m: np.ndarray
    table_force_n: np.ndarray
    path: str
    notes: tuple[str, ...] = ()
    reversible = False  # friction sets the joint: backing off unloads it elastically (contact_laws docstring)

    plateau_force_n = None
    seat_depth_m = None

    @property
    def depth_range_m(self) -> tuple[float, float]:
        return float(self.depth_m[0]), float(self.depth_m[-1])

    def force_n(self, depth_m: np.ndarray) -> np.ndarray:
        return self.force_and_slope(depth_m)[0]

    def force_and_slope(self, depth_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The interpolated force (N) and its slope (N/m): the row interval's, 0 before the first row and past
        the last (at a row, the interval above it)."""
        z = np.asarray(depth_m, dtype=float)
        f = np.interp(z, self.depth_m, self.table_force_n, left=0.0)
        k = np.searchsorted(self.depth_m, z, side="right")  # the row interval [k - 1, k] holding z
        inside = (k > 0) & (k < self.depth_m.size) & (z > 0.0)
        k = np.clip(k, 1, self.depth_m.size - 1)
        slope = np.diff(self.table_force_n)[k - 1] / np.diff(self.depth_m)[k - 1]
        return np.where(z > 0.0, f, 0.0), np.where(inside, slope, 0.0)


def from_keys(law: str, keys: Mapping[str, Any]) -> TabulatedLaw:
    depth, force = read_force_table(keys["table_path"])
    return TabulatedLaw(depth_m=depth, table_force_n=force, path=str(keys["table_path"]))
