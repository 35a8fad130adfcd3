"""``pressfit workspace`` and the report's kinematics: the kinematic maps of the paper's Figures 7-11 per height
(:func:`pressfit.kinematics.workspace.plane_map`) and the workspace summary, written by :mod:`pressfit.output.maps`."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pressfit.description.machine import Machine
from pressfit.kinematics.workspace import DEFAULT_HEIGHTS_M, PlaneMap, map_rows, plane_map, square_corners, summary
from pressfit.output import files as io
from pressfit.output.maps import check_kinematic_maps, write_plane_map


def write_kinematic_maps(machine: Machine, out_dir: Path | str, heights_m: Iterable[float] = DEFAULT_HEIGHTS_M,
                         overwrite: bool = False, progress: bool = False, figures: bool = True
                         ) -> tuple[dict[str, object], list[Path], list[PlaneMap]]:
    """Write per height ``maps_y<y>.csv`` (every field, every leg) and ``maps_y<y>.png`` (panels, the
    required square dashed magenta, also at 45 deg on the F panels), then ``summary.json``; returns the
    summary, the paths and the maps.
    Refuses to overwrite unless asked (checked for every file before anything is written)."""
    out = Path(out_dir)
    heights = [float(y) for y in heights_m]
    check_kinematic_maps(out, heights, overwrite)
    squares = [np.vstack([c, c[:1]]) for c in (square_corners(machine, 0.0), square_corners(machine, 45.0))]
    written, plane_maps = [], []
    with tqdm(total=len(heights) + 1, desc="workspace", unit="step", disable=not progress) as bar:
        for y in heights:
            pm = plane_map(machine, y)
            plane_maps.append(pm)
            written += write_plane_map(machine, pm, map_rows(pm), squares, out, overwrite, figures)
            bar.update()
        result = summary(machine, heights)
        written.append(io.write_json(out / "summary.json", result, overwrite))
        bar.update()
    return result, written, plane_maps
