"""Files of ``pressfit control``: Bode plots of the open and closed loops (PNG), the closed-loop poles (CSV) and
the summary (JSON)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pressfit.output import files as io
from pressfit.output.plots import plt

if TYPE_CHECKING:
    from pressfit.dynamics.linearise import ControlDesign


def bode_figure(design: ControlDesign) -> plt.Figure:
    """Per pose: magnitude and phase of the vertical and lateral (x) axis loops broken at the force commands,
    and of reference -> tool; the structural modes as grey lines."""
    fig, axes = plt.subplots(2, len(design.poses), figsize=(5 * len(design.poses), 7), layout="constrained",
                             squeeze=False)
    for k, p in enumerate(design.poses):
        f = p.bode_frequency_hz
        mag, ph = axes[0, k], axes[1, k]
        for data, label in ((p.bode_open_loop[0], "loop y"), (p.bode_open_loop[1], "loop x"),
                            (p.bode_reference[0], "r_y -> tool_y"), (p.bode_reference[1], "r_x -> tool_x")):
            mag.loglog(f, np.abs(data), label=label)
            ph.semilogx(f, np.degrees(np.unwrap(np.angle(data))), label=label)
        for m in p.modes:
            mag.axvline(m.frequency_hz, color="0.8", lw=0.8, zorder=0)
        mag.axhline(1.0, color="k", lw=0.5)
        mag.set(title=f"{p.name} {np.round(p.pose_m, 3).tolist()} m ({design.model})", ylabel="|G|")
        ph.set(xlabel="frequency [Hz]", ylabel="phase [deg]")
        mag.legend(fontsize=7)
    return fig


POLE_COLUMNS = ("pose", "real_per_s", "imag_rad_per_s", "frequency_hz", "damping", "loop_pole")


def write_control(design: ControlDesign, out: Path) -> list[Path]:
    """``control.json``, ``poles.csv`` (every closed-loop pole, upper half plane), ``bode.png`` in ``out``."""
    rows = [[p.name, z.real, z.imag, f, d, int(m)]
            for p in design.poses
            for z, f, d, m in zip(p.poles, p.pole_frequencies_hz, p.pole_damping, p.loop_poles, strict=True)
            if z.imag >= 0]
    paths = [io.write_json(out / "control.json", design.to_dict()), io.write_csv(out / "poles.csv", POLE_COLUMNS, rows)]
    fig = bode_figure(design)
    try:
        paths.append(io.save_figure(fig, out / "bode.png"))
    finally:
        plt.close(fig)
    return paths
