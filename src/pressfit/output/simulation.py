"""Files of ``pressfit simulate`` (the insertion's time series CSV, summary JSON, plots PNG) and of
``pressfit study insertion`` (table CSV/JSON, plot PNG)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pressfit.dynamics.series import section_columns
from pressfit.output import files as io
from pressfit.output.curve import write_monitor_curve
from pressfit.output.plots import plt
from pressfit.studies.insertion_study import COLUMNS

if TYPE_CHECKING:
    from pressfit.dynamics.insertion import InsertionResult
    from pressfit.dynamics.sizing import RunSizing
    from pressfit.studies.insertion_study import InsertionStudy


def simulation_figure(result: InsertionResult, comparison: InsertionResult | None = None) -> plt.Figure:
    """Five panels against time: plate positions (reference dashed, tool solid), the contact force with the
    limit (and ``comparison``'s, the run with the limiter the other way, on the same axes), actuator
    tensions (commanded dashed, delivered solid), leg axial forces at the plate cardans, the structure's
    deflection (tool minus the kinematic pose of the actuator lengths) with the summary's move peak."""
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
    for i in range(1, sum(c.startswith("cmd_n") for c in result.columns) + 1):
        line, = axes[2].plot(t, result.column(f"act_n{i}"), lw=1.5, label=f"leg {i}")
        axes[2].plot(t, result.column(f"cmd_n{i}"), "--", lw=0.8, color=line.get_color())
        axes[3].plot(t, result.column(f"axial_n{i}"), lw=1.5, color=line.get_color(), label=f"leg {i}")
    limiter = "on" if result.limiter else "off"
    axes[2].set(ylabel="tension [N]", title=f"actuator forces, limiter {limiter} (dashed: commanded)")
    axes[3].set(ylabel="axial force [N]",
                title=f"leg axial force at the plate cardan (> 0 tension), limiter {limiter}")
    for axis in "xyz":
        axes[4].plot(t, 1e6 * (result.column(f"tool_{axis}_m") - result.column(f"kinematic_{axis}_m")), lw=1,
                     label=f"{axis}")
    s = result.summary
    if s.get("max_move_deflection_m") is not None:
        axes[4].plot([s["max_move_deflection_time_s"]], [0.0], "kv",
                     label=f"move peak |u| {1e6 * s['max_move_deflection_m']:.2f} um")
    axes[4].set(xlabel="time [s]", ylabel="deflection [um]",
                title=f"structure deflection at the tool (tool - kinematic pose), model {s.get('model', '')}")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncols=3)
    return fig


def write_simulation(result: InsertionResult, out_dir: Path | str, overwrite: bool = False,
                     comparison: InsertionResult | None = None, sizing: RunSizing | None = None) -> list[Path]:
    """``simulation.csv`` (one row per time step of ``result``), ``simulation.json`` (its summary, with the
    comparison's under ``"comparison"`` and the drive sizing's records, :meth:`RunSizing.to_dict`),
    ``simulation.png``, ``curve.csv`` (the press monitor's view of the stroke, :func:`write_monitor_curve`); with
    the flexible model ``sections.csv`` (the leg section resultants per step, N and N m,
    :func:`pressfit.dynamics.series.section_columns`)."""
    out = Path(out_dir)
    summary = simulation_summary(result, comparison, sizing)
    paths = [io.write_csv(out / "simulation.csv", result.columns, result.series, overwrite),
             io.write_json(out / "simulation.json", summary, overwrite)]
    if result.monitor is not None:
        paths.append(write_monitor_curve(out / "curve.csv", result.monitor, overwrite))
    if result.sections is not None:
        table = np.column_stack([result.column("time_s"), result.sections.reshape(len(result.series), -1)])
        paths.append(io.write_csv(out / "sections.csv", section_columns(result.sections.shape[1]), table, overwrite))
    fig = simulation_figure(result, comparison)
    try:
        paths.append(io.save_figure(fig, out / "simulation.png", overwrite))
    finally:
        plt.close(fig)
    return paths


def simulation_summary(result: InsertionResult, comparison: InsertionResult | None, sizing: RunSizing | None = None
                       ) -> dict[str, Any]:
    """``simulation.json``: the run's summary, the comparison run's figures under ``"comparison"`` and the drive
    sizing's records."""
    extra = sizing.to_dict() if sizing is not None else {}
    if comparison is None:
        return {**result.summary, **extra}
    keys = ("limiter", "peak_contact_force_n", "overshoot_n", "steady_insertion_force_n", "steady_insertion_depth_m",
            "positioning_error_m", "settling_time_s", "insertion_completed", "release_time_s", "warnings")
    return {**result.summary, "comparison": {k: comparison.summary[k] for k in keys}, **extra}


def insertion_study_figure(study: InsertionStudy) -> plt.Figure:
    """The play's share of the tool error and the force overshoot against the preload, one line per clearance,
    with each clearance's critical preload marked."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), layout="constrained")
    for g in np.unique(study.column("clearance_m")):
        rows = study.column("clearance_m") == g
        p = study.column("preload_n")[rows]
        line, = axes[0].plot(p, study.column("play_error_m")[rows] * 1e6, "o-", label=f"g = {g * 1e6:g} um")
        axes[0].axvline(study.column("critical_preload_n")[rows][0], color=line.get_color(), ls=":", lw=1)
        axes[1].plot(p, study.column("overshoot_n")[rows], "o-", color=line.get_color(), label=f"g = {g * 1e6:g} um")
    axes[0].set(xlabel="preload a4 [N]", ylabel="tool error from the play [um]",
                title="tool offset hidden from the length-based estimate (dotted: critical preload)")
    axes[1].set(xlabel="preload a4 [N]", ylabel="overshoot [N]", title="contact force over the insertion limit")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    return fig


def write_insertion_study(study: InsertionStudy, out_dir: Path) -> list[Path]:
    """``insertion_study.csv`` (one row per preload x clearance), ``insertion_study.json``, ``insertion_study.png``
    into a fresh directory (used through :func:`pressfit.output.files.write_directory`)."""
    paths = [io.write_csv(out_dir / "insertion_study.csv", COLUMNS, study.rows),
             io.write_json(out_dir / "insertion_study.json", study.to_dict())]
    fig = insertion_study_figure(study)
    try:
        paths.append(io.save_figure(fig, out_dir / "insertion_study.png"))
    finally:
        plt.close(fig)
    return paths
