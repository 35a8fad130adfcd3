"""Files of ``pressfit cycle``: the board's time series (``cycle.csv``), summary (``cycle.json``) and plots
(``cycle_path.png``: the tool's path over the board, top view and 3D; ``cycle_force.png``: the contact force of
every pin against the time since its descent started, with its limit)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pressfit.description.cases import load_case
from pressfit.dynamics.cycle import CYCLE_COLUMNS, CycleResult, simulate_cycle
from pressfit.output import files as io
from pressfit.output.plots import plt


def path_figure(result: CycleResult) -> plt.Figure:
    """The tool's path (x, z) over the board with the pins numbered, and the same in 3D (y up)."""
    x, y, z = (result.column(f"tool_{a}_m") for a in "xyz")
    pins = result.plan.pins
    fig = plt.figure(figsize=(14, 6), layout="constrained")
    top = fig.add_subplot(1, 2, 1)
    top.plot(x, z, lw=0.8, color="tab:blue", label="tool")
    top.plot([p.x_m for p in pins], [p.z_m for p in pins], "o", mfc="none", color="tab:red", label="pins")
    for p in pins:
        top.annotate(str(p.index), (p.x_m, p.z_m), textcoords="offset points", xytext=(4, 4), fontsize=8)
    top.set(xlabel="x [m]", ylabel="z [m]", aspect="equal", title="tool path over the board (top view)")
    top.grid(alpha=0.3)
    top.legend(fontsize=8)
    view = fig.add_subplot(1, 2, 2, projection="3d")
    view.plot(x, z, y, lw=0.8, color="tab:blue")
    board = result.plan.scenario.simulation.contact.board_height_m
    view.scatter([p.x_m for p in pins], [p.z_m for p in pins], [board] * len(pins), color="tab:red", s=12)
    view.set(xlabel="x [m]", ylabel="z [m]", zlabel="y [m]", title="tool path (3D, y up)")
    return fig


def force_figure(result: CycleResult) -> plt.Figure:
    """Every pin's contact force against the time since the start of its descent, with its force limit."""
    t, force, pin = result.column("time_s"), result.column("contact_force_n"), result.column("pin")
    fig, ax = plt.subplots(figsize=(10, 5), layout="constrained")
    for record in result.summary["pins"]:
        rows = np.flatnonzero(pin == record["index"])
        ax.plot(t[rows] - t[rows[0]], force[rows], lw=1, label=f"pin {record['index']}")
    for limit in sorted({p.force_limit_n for p in result.plan.pins}):
        ax.axhline(limit, color="k", ls=":", lw=1)
    ax.set(xlabel="time since the descent started [s]", ylabel="contact force [N]",
           title="contact force per pin (dotted: the pins' force limits)")
    ax.grid(alpha=0.3)
    if len(result.plan.pins) <= 30:
        ax.legend(fontsize=7, ncols=4)
    return fig


def write_cycle(result: CycleResult, out_dir: Path | str) -> list[Path]:
    """``cycle.csv`` (one row per time step, :data:`pressfit.dynamics.cycle.CYCLE_COLUMNS`), ``cycle.json``,
    ``cycle_path.png``, ``cycle_force.png`` into a fresh directory (through :func:`io.write_directory`)."""
    out = Path(out_dir)
    paths = [io.write_csv(out / "cycle.csv", CYCLE_COLUMNS, result.series),
             io.write_json(out / "cycle.json", result.summary)]
    for name, build in (("cycle_path.png", path_figure), ("cycle_force.png", force_figure)):
        fig = build(result)
        try:
            paths.append(io.save_figure(fig, out / name))
        finally:
            plt.close(fig)
    return paths


def run_cycle(case_path: Path | str, model: str | None, out_dir: Path | None, overwrite: bool = False,
              progress: bool = False) -> tuple[dict[str, Any], list[Path]]:
    """Simulate the case file's board (:func:`pressfit.dynamics.cycle.simulate_cycle`); the summary, and the
    files in ``out_dir`` if given (checked before the simulation, written through a temporary directory)."""
    if out_dir is not None:
        io.check_directory(out_dir, overwrite)  # before computing
    case = load_case(case_path)
    result = simulate_cycle(case, model, progress)
    source = case.machine().source
    paths = [] if out_dir is None else io.write_directory(
        out_dir, overwrite, lambda tmp: write_cycle(result, tmp),
        inputs=[Path(case_path), *([source] if source else [])])
    return result.summary, paths
