"""Files of ``pressfit curve``: the predicted press curve as ``curve.csv`` (one row per sampled depth: true depth,
sensed depth, total force, per-pin forces and depths) and ``curve.json`` (the summary); and the simulated
insertion's monitor view in the same columns after a time column (:func:`write_monitor_curve`: ``pressfit
simulate``'s curve.csv, ``pressfit cycle``'s curves/pin_<nn>.csv)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pressfit.output import files as io

if TYPE_CHECKING:
    from pressfit.dynamics.press_monitor import MonitorCurve
    from pressfit.mechanics.press_curve import PressCurve


def curve_columns(pins: int) -> list[str]:
    """curve.csv's header for ``pins`` pins (time is not meaningful quasi-statically: rows are depth samples)."""
    return (["depth_m", "sensed_depth_m", "force_n"] + [f"pin_force_n{i + 1}" for i in range(pins)]
            + [f"pin_depth_m{i + 1}" for i in range(pins)])


def write_curve(curve: PressCurve, out_dir: Path, case_name: str) -> list[Path]:
    """curve.csv and curve.json into a fresh directory (through :func:`pressfit.output.files.write_directory`)."""
    pins = curve.pin_forces_n.shape[1]
    rows = ([d, s, f, *pf, *pd] for d, s, f, pf, pd in zip(curve.depth_m, curve.sensed_depth_m, curve.force_n,
                                                             curve.pin_forces_n, curve.pin_depths_m, strict=True))
    return [io.write_csv(out_dir / "curve.csv", curve_columns(pins), rows),
            io.write_json(out_dir / "curve.json", {"case": case_name, **curve.summary()})]


def monitor_curve_columns(pins: int) -> list[str]:
    """A simulated stroke's curve.csv header: ``time_s`` (since the descent started), then :func:`curve_columns`."""
    return ["time_s", *curve_columns(pins)]


def write_monitor_curve(path: Path, curve: MonitorCurve, overwrite: bool = False) -> Path:
    """A simulated stroke's monitor view (:class:`pressfit.dynamics.press_monitor.MonitorCurve`) as a curve.csv,
    one row per time step (:func:`monitor_curve_columns`)."""
    table = np.column_stack([curve.time_s, curve.depth_m, curve.sensed_depth_m, curve.force_n, curve.pin_forces_n,
                             curve.pin_depths_m])
    return io.write_csv(path, monitor_curve_columns(curve.pin_forces_n.shape[1]), table, overwrite)
