"""Files of ``pressfit response``: the tool's step response (CSV, PNG), its receptance (CSV) and the summary."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pressfit.output import files as io
from pressfit.output.plots import plt

if TYPE_CHECKING:
    from pressfit.dynamics.response import ToolResponse


def response_figure(r: ToolResponse) -> plt.Figure:
    """Left: the tool displacement after the force step (um, world axes). Right: the direct receptance
    d^T H d along the force direction, magnitude (m/N, log) and phase (deg), with the natural frequencies."""
    fig, (ax, mag) = plt.subplots(1, 2, figsize=(12, 4.4), layout="constrained")
    for k, name in enumerate("xyz"):
        ax.plot(r.time_s, r.displacement_m[:, k] * 1e6, label=f"u_{name}")
    ax.set(xlabel="time [s]", ylabel="tool displacement [um]",
           title=f"step {np.array2string(r.force_n, precision=4)} N, zeta = {r.damping_ratio:g}")
    ax.legend()
    direct = r.direct_receptance_m_per_n
    mag.loglog(r.frequencies_hz, np.abs(direct), color="tab:blue")
    mag.set(xlabel="frequency [Hz]", ylabel="|receptance| along the force [m/N]", title="tool-point receptance")
    for f in r.modes_hz[(r.modes_hz >= r.frequencies_hz[0]) & (r.modes_hz <= r.frequencies_hz[-1])][:12]:
        mag.axvline(f, color="0.85", lw=0.8, zorder=0)
    phase = mag.twinx()
    phase.semilogx(r.frequencies_hz, np.degrees(np.angle(direct)), color="tab:orange", lw=0.8)
    phase.set_ylabel("phase [deg]", color="tab:orange")
    return fig


def write_response(r: ToolResponse, out: Path) -> list[Path]:
    """``response.json``, ``response.csv`` (time, displacement), ``receptance.csv``, ``response.png`` in ``out``."""
    direct = r.direct_receptance_m_per_n
    column = np.einsum("fij,j->fi", r.receptance_m_per_n, r.direction)  # tool motion per N along the force
    rec_rows = [[f, abs(d), np.degrees(np.angle(d)), *np.abs(c)]
                for f, d, c in zip(r.frequencies_hz, direct, column, strict=True)]
    paths = [io.write_json(out / "response.json", r.summary()),
             io.write_csv(out / "response.csv", ["time_s", "tool_ux_m", "tool_uy_m", "tool_uz_m"],
                          np.column_stack([r.time_s, r.displacement_m])),
             io.write_csv(out / "receptance.csv", ["frequency_hz", "direct_m_per_n", "direct_phase_deg",
                                                   "abs_hx_m_per_n", "abs_hy_m_per_n", "abs_hz_m_per_n"], rec_rows)]
    fig = response_figure(r)
    try:
        paths.append(io.save_figure(fig, out / "response.png"))
    finally:
        plt.close(fig)
    return paths
