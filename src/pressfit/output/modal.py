"""Files of ``pressfit modes``: the natural modes at a pose as JSON, CSV and a PNG of the first mode shapes."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pressfit.output import files as io
from pressfit.output.plots import plt

if TYPE_CHECKING:
    from pressfit.dynamics.modes import Modes

PLOTTED_MODES = 6
SHAPE_AMPLITUDE_M = 0.08  # largest drawn displacement of a mode shape (the shapes are scaled to it)


def modes_figure(modes: Modes) -> plt.Figure:
    """One 3D panel per mode (at most six): legs and plate at equilibrium (grey) and displaced (blue)."""
    count = min(PLOTTED_MODES, modes.frequencies_hz.size)
    cols = min(count, 3)
    rows = -(-count // cols)
    fig = plt.figure(figsize=(4.6 * cols, 4.4 * rows))
    for k in range(count):
        ax = fig.add_subplot(rows, cols, k + 1, projection="3d")
        shape = modes.leg_point_shapes[k]
        moved = modes.leg_points_m + shape * (SHAPE_AMPLITUDE_M / max(float(np.max(np.abs(shape))), 1e-300))
        for pts, colour in ((modes.leg_points_m, "0.6"), (moved, "tab:blue")):
            for leg in pts:  # world y is up: draw (x, z, y)
                ax.plot(leg[:, 0], leg[:, 2], leg[:, 1], color=colour, lw=1.5)
            plate = pts[[0, 1, 2, 3, 0], -1]
            ax.plot(plate[:, 0], plate[:, 2], plate[:, 1], color=colour, lw=2.5)
        ax.set(title=f"mode {k + 1}: {modes.frequencies_hz[k]:.4g} Hz", xlabel="x [m]", ylabel="z [m]",
               zlabel="y [m]")
        ax.set_box_aspect((1, 1, 1))
    pose = ", ".join(f"{c:g}" for c in modes.pose_m)
    fig.suptitle(f"natural modes at h = ({pose}) m (shapes scaled to {SHAPE_AMPLITUDE_M * 1e3:g} mm)")
    fig.tight_layout()
    return fig


def write_modes(modes: Modes, out_dir: Path | str, overwrite: bool = False) -> list[Path]:
    """``modes.json`` (summary), ``modes.csv`` (frequency and plate shape per mode), ``modes.png``."""
    out = Path(out_dir)
    rows = [[k + 1, f, *s] for k, (f, s) in enumerate(zip(modes.frequencies_hz, modes.plate_shapes, strict=True))]
    header = ["mode", "frequency_hz", "plate_ux_m", "plate_uy_m", "plate_uz_m", "plate_rx_rad", "plate_ry_rad",
              "plate_rz_rad"]
    paths = [io.write_json(out / "modes.json", modes.to_dict(), overwrite),
             io.write_csv(out / "modes.csv", header, rows, overwrite)]
    fig = modes_figure(modes)
    try:
        paths.append(io.save_figure(fig, out / "modes.png", overwrite))
    finally:
        plt.close(fig)
    return paths

