"""Files of ``pressfit compare``: ``compare.json`` (every machine's figures and the two claims), ``compare.csv`` (one
row per machine) and ``compare.png`` (the figures side by side, one panel per figure)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pressfit.output import files as io
from pressfit.output.plots import plt

if TYPE_CHECKING:
    from pressfit.studies.compare import Comparison

PANELS = (("worst_drive_force_n", "worst drive force [N]", 1.0),
          ("worst_bending_nm", "worst member bending [N m]", 1.0),
          ("weakest_stiffness_worst_n_per_m", "weakest tool stiffness, worst [N/um]", 1e-6),
          ("vertical_stiffness_worst_n_per_m", "vertical tool stiffness, worst [N/um]", 1e-6),
          ("tilt_worst_rad", "tool tilt under 700 N, worst [mrad]", 1e3),
          ("first_frequency_lowest_hz", "first natural frequency, lowest [Hz]", 1.0),
          ("moving_mass_kg", "moving mass [kg]", 1.0),
          ("lost_motion_m", "lost motion, 20 um play, worst over the box [um]", 1e6))
CSV_COLUMNS = ("name", "kind", "legs", "source", "worst_drive_force_n", "worst_bending_nm", "worst_bending_member",
               "weakest_stiffness_worst_n_per_m", "weakest_stiffness_median_n_per_m",
               "vertical_stiffness_worst_n_per_m", "vertical_stiffness_median_n_per_m", "tilt_worst_rad",
               "tilt_median_rad", "first_frequency_lowest_hz", "first_frequency_median_hz", "moving_mass_kg",
               "lost_motion_m", "lost_motion_preloaded_m", "critical_preload_worst_n", "preloaded_drive_force_n",
               "max_relative_residual")


def compare_figure(result: Comparison) -> plt.Figure:
    """One bar panel per figure (``PANELS``), a bar per machine; the lost-motion panel adds the preloaded bar."""
    names = [m.name if [x.name for x in result.machines].count(m.name) == 1 else f"{m.name} ({i + 1})"
             for i, m in enumerate(result.machines)]  # bars by machine: two machines of one name stay apart
    fig, axes = plt.subplots(2, 4, figsize=(16, 7))
    for ax, (key, label, scale) in zip(axes.flat, PANELS, strict=True):
        values = np.array([getattr(m, key) for m in result.machines], dtype=float) * scale
        ax.bar(names, values, color="tab:blue")
        if key == "lost_motion_m":
            pre = np.array([np.nan if m.lost_motion_preloaded_m is None else max(m.lost_motion_preloaded_m, 0.0)
                            for m in result.machines]) * scale
            ax.bar(names, pre, color="tab:orange", width=0.4, label="with each pose's critical preload")
            ax.legend(fontsize=7)
        ax.set_title(label, fontsize=9)
        ax.tick_params(axis="x", labelrotation=20, labelsize=7)
    fig.suptitle("pressfit compare: the required workspace under the press load and its 5 degree cone")
    fig.tight_layout()
    return fig


def write_compare(result: Comparison, out_dir: Path | str, overwrite: bool = False) -> list[Path]:
    out = Path(out_dir)
    rows = [[m.to_dict()[k] for k in CSV_COLUMNS] for m in result.machines]
    paths = [io.write_json(out / "compare.json", result.to_dict(), overwrite),
             io.write_csv(out / "compare.csv", list(CSV_COLUMNS), rows, overwrite)]
    fig = compare_figure(result)
    try:
        paths.append(io.save_figure(fig, out / "compare.png", overwrite))
    finally:
        plt.close(fig)
    return paths
