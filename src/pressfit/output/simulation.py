"""Files of ``pressfit simulate``: the insertion's time series (CSV), its summary (JSON) and plots (PNG)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pressfit.description.cases import load_case
from pressfit.dynamics.insertion import LEGS, SERIES_COLUMNS, InsertionResult, simulate_insertion
from pressfit.output import files as io
from pressfit.output.plots import plt


def simulation_figure(result: InsertionResult, comparison: InsertionResult | None = None) -> plt.Figure:
    """Five panels against time: plate positions (reference dashed, tool solid), the contact force with the
    limit (and ``comparison``'s, the run with the limiter the other way, on the same axes), actuator
    tensions (commanded dashed, delivered solid), leg axial forces, leg torsion (solid) and bending (dashed)
    at the plate cardans."""
    t = result.column("time_s")
    fig, axes = plt.subplots(5, 1, figsize=(10, 15), sharex=True, layout="constrained")
    for axis, colour in zip("xyz", ("tab:blue", "tab:orange", "tab:green"), strict=True):
        axes[0].plot(t, result.column(f"ref_{axis}_m"), "--", color=colour, lw=1, label=f"{axis} reference")
        axes[0].plot(t, result.column(f"tool_{axis}_m"), color=colour, lw=1.5, label=f"{axis} tool")
    axes[0].set(ylabel="position [m]", title="plate centre (tool tip)")
    runs = [result] if comparison is None else [result, comparison]
    for run, colour in zip(runs, ("tab:red", "tab:gray"), strict=False):
        axes[1].plot(run.column("time_s"), run.column("contact_force_n"), color=colour,
                     label="with limiter" if run.limiter else "without limiter")
    axes[1].axhline(result.summary["force_limit_n"], color="k", ls=":", label="insertion limit")
    axes[1].set(ylabel="force [N]", title="contact force")
    for i in LEGS:
        line, = axes[2].plot(t, result.column(f"act_n{i}"), lw=1.5, label=f"leg {i}")
        axes[2].plot(t, result.column(f"cmd_n{i}"), "--", lw=0.8, color=line.get_color())
        axes[3].plot(t, result.column(f"axial_n{i}"), lw=1.5, color=line.get_color(), label=f"leg {i}")
        axes[4].plot(t, result.column(f"torsion_nm{i}"), lw=1.5, color=line.get_color(), label=f"leg {i} torsion")
        axes[4].plot(t, result.column(f"bending_nm{i}"), "--", lw=1, color=line.get_color())
    limiter = "on" if result.limiter else "off"
    axes[2].set(ylabel="tension [N]", title=f"actuator forces, limiter {limiter} (dashed: commanded)")
    axes[3].set(ylabel="axial force [N]", title=f"leg axial force at the plate cardan (> 0 tension), limiter {limiter}")
    axes[4].set(xlabel="time [s]", ylabel="moment [N m]",
                title=f"leg torsion (solid) and bending |M_b| (dashed) at the plate cardan, limiter {limiter}")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncols=3)
    return fig


def write_simulation(result: InsertionResult, out_dir: Path | str, overwrite: bool = False,
                     comparison: InsertionResult | None = None) -> list[Path]:
    """``simulation.csv`` (one row per time step of ``result``), ``simulation.json`` (its summary, with the
    comparison's under ``"comparison"``), ``simulation.png``."""
    out = Path(out_dir)
    summary = _summary(result, comparison)
    paths = [io.write_csv(out / "simulation.csv", SERIES_COLUMNS, result.series, overwrite),
             io.write_json(out / "simulation.json", summary, overwrite)]
    fig = simulation_figure(result, comparison)
    try:
        paths.append(io.save_figure(fig, out / "simulation.png", overwrite))
    finally:
        plt.close(fig)
    return paths


def _summary(result: InsertionResult, comparison: InsertionResult | None) -> dict[str, Any]:
    if comparison is None:
        return result.summary
    keys = ("limiter", "peak_contact_force_n", "overshoot_n", "steady_insertion_force_n", "steady_insertion_depth_m",
            "positioning_error_m", "settling_time_s")
    return {**result.summary, "comparison": {k: comparison.summary[k] for k in keys}}


def run_simulation(case_path: Path | str, out_dir: Path | None, limiter: bool = True, overwrite: bool = False,
                   progress: bool = False) -> tuple[dict[str, Any], list[Path]]:
    """Simulate the case file's insertion (:func:`pressfit.dynamics.insertion.simulate_insertion`); with the
    limiter on, the same scenario also runs without it (the comparison of the contact-force plot and of the
    summary's ``"comparison"``). The summary, and the files in ``out_dir`` if given."""
    case = load_case(case_path)
    result = simulate_insertion(case, limiter, progress)
    comparison = simulate_insertion(case, False, progress) if limiter else None
    paths = write_simulation(result, out_dir, overwrite, comparison) if out_dir is not None else []
    return _summary(result, comparison), paths
