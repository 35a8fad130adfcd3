"""Files of ``pressfit cycle``: the board's time series (``cycle.csv``), summary (``cycle.json``) and plots
(``cycle_path.png``: the tool's path over the board, top view and 3D; ``cycle_force.png``: the contact force of
every pin against the time since its descent started, with its limit; with the drive sizing ``cycle_drives.png``:
each drive's force and speed against the time with their limits, and ``cycle_operating_points.png``: each
drive's speed-force operating points over the cycle inside its limits)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pressfit.output import files as io
from pressfit.output.curve import write_monitor_curve
from pressfit.output.plots import plt

if TYPE_CHECKING:
    from pressfit.dynamics.cycle import CycleResult


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


def _legs(result: CycleResult) -> list[int]:
    return [d["leg"] for d in result.summary.get("drives", [])]


def _limits(record: dict[str, Any]) -> tuple[float, float | None]:
    """A drive's force limit (N) and speed limit (m/s, None: the drive model has none) from its ratings."""
    ratings = record["ratings"]
    speed = ratings.get("peak_speed_m_per_s")
    return ratings["peak_force_n"]["rating"], None if speed is None else speed["rating"]


def drives_figure(result: CycleResult) -> plt.Figure:
    """Every drive's delivered force (N) and speed (m/s) against the time, with the drives' limits (dashed)."""
    t = result.column("time_s")
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(12, 7), sharex=True, layout="constrained")
    for record in result.summary["drives"]:
        i = record["leg"]
        top.plot(t, result.column(f"act_n{i}"), lw=0.8, label=f"drive {i}")
        bottom.plot(t, result.column(f"rate_m_per_s{i}"), lw=0.8, label=f"drive {i}")
    force_limit, speed_limit = _limits(result.summary["drives"][0])
    for sign in (-1.0, 1.0):
        top.axhline(sign * force_limit, color="k", ls="--", lw=1)
        if speed_limit is not None:
            bottom.axhline(sign * speed_limit, color="k", ls="--", lw=1)
    top.set(ylabel="drive force (tension) [N]", title="drive force and speed over the cycle (dashed: the limits"
            + ("" if speed_limit is not None else "; the drive model has no speed limit") + ")")
    bottom.set(xlabel="time [s]", ylabel="leg speed [m/s]")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncols=len(_legs(result)))
    return fig


def operating_points_figure(result: CycleResult) -> plt.Figure:
    """Per drive its (speed, force) at every step of the cycle, inside the rectangle of its limits (dashed)."""
    records = result.summary["drives"]
    cols = min(len(records), 4)
    rows = -(-len(records) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3.6 * rows), squeeze=False, layout="constrained")
    for ax, record in zip(axes.flat, records, strict=False):
        i = record["leg"]
        speed, force = result.column(f"rate_m_per_s{i}"), result.column(f"act_n{i}")
        ax.plot(speed, force, ".", ms=1, alpha=0.4)
        force_limit, speed_limit = _limits(record)
        for sign in (-1.0, 1.0):
            ax.axhline(sign * force_limit, color="k", ls="--", lw=1)
            if speed_limit is not None:
                ax.axvline(sign * speed_limit, color="k", ls="--", lw=1)
        ax.set(xlabel="leg speed [m/s]", ylabel="drive force [N]", title=f"drive {i}: operating points")
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(records):]:
        ax.set_visible(False)
    return fig


def write_cycle(result: CycleResult, out_dir: Path | str, overwrite: bool = False) -> list[Path]:
    """``cycle.csv`` (one row per time step, :func:`pressfit.dynamics.cycle.cycle_columns`), ``cycle.json``,
    ``curves/pin_<nn>.csv`` (each pin's press monitor view, :func:`pressfit.output.curve.write_monitor_curve`),
    ``cycle_path.png``, ``cycle_force.png`` (and with the drive sizing ``cycle_drives.png``,
    ``cycle_operating_points.png``) into a fresh directory (through :func:`io.write_directory`)."""
    out = Path(out_dir)
    paths = [io.write_csv(out / "cycle.csv", result.columns, result.series, overwrite),
             io.write_json(out / "cycle.json", result.summary, overwrite)]
    width = max(2, len(str(len(result.curves))))
    paths += [write_monitor_curve(out / "curves" / f"pin_{pin.index:0{width}d}.csv", curve, overwrite)
              for pin, curve in zip(result.plan.pins, result.curves, strict=True)]
    figures = [("cycle_path.png", path_figure), ("cycle_force.png", force_figure)]
    if "drives" in result.summary:
        figures += [("cycle_drives.png", drives_figure), ("cycle_operating_points.png", operating_points_figure)]
    for name, build in figures:
        fig = build(result)
        try:
            paths.append(io.save_figure(fig, out / name, overwrite))
        finally:
            plt.close(fig)
    return paths
