"""Files of ``pressfit simulate``: the insertion's time series (CSV), its summary (JSON) and plots (PNG)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pressfit.description.cases import load_case
from pressfit.dynamics.insertion import SERIES_COLUMNS, InsertionResult, simulate_insertion
from pressfit.output import files as io
from pressfit.output.plots import plt


def simulation_figure(result: InsertionResult) -> plt.Figure:
    """Three panels against time: plate positions (reference, estimate, tool), contact force with the
    limit, actuator tensions (commanded dashed, delivered solid)."""
    t = result.column("time_s")
    fig, axes = plt.subplots(3, 1, figsize=(10, 10), sharex=True, layout="constrained")
    for axis, colour in zip("xyz", ("tab:blue", "tab:orange", "tab:green"), strict=True):
        axes[0].plot(t, result.column(f"ref_{axis}_m"), "--", color=colour, lw=1, label=f"{axis} reference")
        axes[0].plot(t, result.column(f"tool_{axis}_m"), color=colour, lw=1.5, label=f"{axis} tool")
    axes[0].set(ylabel="position [m]", title="plate centre (tool tip)")
    axes[1].plot(t, result.column("contact_force_n"), color="tab:red", label="contact force")
    axes[1].axhline(result.summary["force_limit_n"], color="k", ls=":", label="insertion limit")
    axes[1].set(ylabel="force [N]", title="contact force, limiter " + ("on" if result.limiter else "off"))
    for i in range(1, 5):
        line, = axes[2].plot(t, result.column(f"act_n{i}"), lw=1.5, label=f"leg {i}")
        axes[2].plot(t, result.column(f"cmd_n{i}"), "--", lw=0.8, color=line.get_color())
    axes[2].set(xlabel="time [s]", ylabel="tension [N]", title="actuator forces (dashed: commanded)")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncols=3)
    return fig


def write_simulation(result: InsertionResult, out_dir: Path | str, overwrite: bool = False) -> list[Path]:
    """``simulation.csv`` (one row per time step), ``simulation.json`` (summary), ``simulation.png``."""
    out = Path(out_dir)
    paths = [io.write_csv(out / "simulation.csv", SERIES_COLUMNS, result.series, overwrite),
             io.write_json(out / "simulation.json", result.summary, overwrite)]
    fig = simulation_figure(result)
    try:
        paths.append(io.save_figure(fig, out / "simulation.png", overwrite))
    finally:
        plt.close(fig)
    return paths


def run_simulation(case_path: Path | str, out_dir: Path | None, limiter: bool = True, overwrite: bool = False,
                   progress: bool = False) -> tuple[dict[str, Any], list[Path]]:
    """Simulate the case file's insertion (:func:`pressfit.dynamics.insertion.simulate_insertion`); its
    summary, and its files in ``out_dir`` if given."""
    result = simulate_insertion(load_case(case_path), limiter, progress)
    return result.summary, (write_simulation(result, out_dir, overwrite) if out_dir is not None else [])
