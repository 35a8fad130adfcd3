"""Files of the maps and sweeps: stiffness maps, the workspace load envelope, kinematic maps,
interference sweeps and the preload study (CSV, JSON and PNG, written atomically)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pressfit.errors import OutputError, OutputExistsError
from pressfit.output import files as io
from pressfit.output import plots
from pressfit.output.files import save_figure, write_csv
from pressfit.output.plots import plt, write_leg_bars, write_xz_maps
from pressfit.studies.workspace_envelope import LEG_QUANTITIES, PLATE_QUANTITIES, envelope_rows

if TYPE_CHECKING:
    from pressfit.description.machine import Machine
    from pressfit.geometry.interference import SweepResult
    from pressfit.kinematics.workspace import PlaneMap
    from pressfit.mechanics.condensed import StiffnessMaps
    from pressfit.studies.preload_study import PreloadStudy
    from pressfit.studies.workspace_envelope import LoadEnvelope

_AXES = "xyz"  # the world axes, as the kinematic maps' field names spell them


def write_load_envelope(env: LoadEnvelope, out_dir: Path | str, overwrite: bool = False,
                        figures: bool = True) -> list[Path]:
    """``load_envelope.csv`` and ``.json`` (the table), ``load_envelope.png`` (per-leg bars) and x-z maps of the worst
    values (``load_envelope_maps*``) into out_dir; returns the paths. ``figures=False``: no PNG."""
    header, rows = envelope_rows(env)
    out = Path(out_dir)
    paths = [io.write_csv(out / "load_envelope.csv", header, rows, overwrite),
             io.write_json(out / "load_envelope.json", [dict(zip(header, r)) for r in rows], overwrite)]
    legs = {k: (env.entries[k].value, f"[{u}]") for k, (u, _) in LEG_QUANTITIES.items()}
    if figures:
        paths.append(write_leg_bars(out / "load_envelope.png", legs,
                                    "workspace load envelope (condensed linear model)", overwrite))
    units = {**LEG_QUANTITIES, **PLATE_QUANTITIES}
    fields = {f"worst_{k}": (m, units[k][0]) for k, m in env.maps.items()}  # over y, loads and legs
    title = f"y in [{env.y_m.min():g}, {env.y_m.max():g}] m, {len(env.loads)} load(s)"
    return paths + write_xz_maps(out, "load_envelope_maps", env.x_m, env.z_m, fields, title, overwrite, figures)


def write_stiffness_maps(maps: StiffnessMaps, out_dir: Path | str, overwrite: bool = False,
                         figures: bool = True) -> list[Path]:
    """PNG per map (not with ``figures=False``) and one CSV (``stiffness_maps_y<mm>.csv``) into out_dir."""
    stem = f"stiffness_maps_y{round(maps.y_m * 1000):d}mm"
    return write_xz_maps(out_dir, stem, maps.x_m, maps.z_m, maps.fields(),
                         f"condensed linear model, y = {maps.y_m:g} m", overwrite, figures)


def kinematic_fields(pm: PlaneMap) -> plots.Fields:
    """The paper's Figures 7-11 as panels: n, F_x, F_y, F_z and leg 1's dl_1/dh (legs 2-4 follow by
    Table 2's symmetries; every leg is in the CSV)."""
    fields = {"n (eq. 4)": (pm.dexterity, "-")}
    fields |= {f"F_{a} (eq. {6 + j})": (pm.force_indices[..., j], "N/N") for j, a in enumerate(_AXES)}
    fields |= {f"dl_1/d{a}_h (eqs. 2-3)": (pm.leg_rates[..., 0, j], "m/m") for j, a in enumerate(_AXES)}
    return fields


def check_kinematic_maps(out_dir: Path | str, heights_m: list[float], overwrite: bool) -> None:
    """Refuse, before anything is computed, heights that would write the same ``maps_y<y>.*`` (OutputError) and
    existing output files without ``overwrite`` (OutputExistsError, checked for every file)."""
    out = Path(out_dir)
    heights = [float(y) for y in heights_m]
    names = [out / f"maps_y{y:.3f}.{ext}" for y in heights for ext in ("csv", "png")] + [out / "summary.json"]
    stems = [f"maps_y{y:.3f}" for y in heights]
    if len(set(stems)) != len(stems):
        y0, y1 = next((a, b) for i, a in enumerate(heights) for b in heights[i + 1:] if f"{a:.3f}" == f"{b:.3f}")
        raise OutputError(f"heights {y0:g} m and {y1:g} m would write the same files maps_y{y0:.3f}.*: "
                          "give heights that differ by at least 1 mm", path=out / f"maps_y{y0:.3f}.csv")
    clash = [p for p in names if p.exists()]
    if clash and not overwrite:
        raise OutputExistsError(f"{clash[0]} exists ({len(clash)} output files do); pass --overwrite "
                                "to replace them", path=clash[0])


def write_plane_map(machine: Machine, pm: PlaneMap, rows: tuple[list[str], np.ndarray], squares: list[np.ndarray],
                    out_dir: Path | str, overwrite: bool = False, figures: bool = True) -> list[Path]:
    """One height's ``maps_y<y>.csv`` (``rows``: header and rows, every field, every leg:
    :func:`pressfit.kinematics.workspace.map_rows`) and ``maps_y<y>.png`` (panels, ``squares``: the required square
    closed, at 0 and 45 degrees, m); ``figures=False``: no PNG."""
    out = Path(out_dir)
    y = pm.y_m
    written = [io.write_csv(out / f"maps_y{y:.3f}.csv", *rows, overwrite=overwrite)]
    fields = kinematic_fields(pm)
    if not figures:
        return written
    fig = plane_map_figure(machine, pm, fields, squares)
    try:
        written.append(io.save_figure(fig, out / f"maps_y{y:.3f}.png", overwrite))
    finally:
        plots.plt.close(fig)
    return written


def plane_map_figure(machine: Machine, pm: PlaneMap, fields: dict[str, np.ndarray], squares: list[np.ndarray]
                     ) -> plt.Figure:
    """The kinematic maps of one plane (:func:`pressfit.output.plots.xz_map_figure`), titled with the machine's
    name and leg count, the required square (m; and at 45 degrees on the force maps) drawn on each."""
    fig = plots.xz_map_figure(pm.x_m, pm.z_m, fields, f"{machine.name} ({len(machine.legs)}-UPU) maps at y_h = "
                              f"{pm.y_m:g} m (magenta: required square, also at 45 deg)")
    for ax, name in zip(fig.axes, fields, strict=False):
        for sq in squares if name.startswith("F_") else squares[:1]:
            ax.plot(sq[:, 0], sq[:, 1], "m--", linewidth=1.2)
    return fig


# --- output ---------------------------------------------------------------------------------------
def write_interference_sweep(result: SweepResult, out_dir: Path | str, overwrite: bool = False,
                             figures: bool = True) -> list[Path]:
    """``interference_poses.csv`` (per pose), ``interference_pairs.csv`` (per pair) and, for a grid,
    ``interference_map.png`` (minimum distance over x-z at up to four heights)."""

    out = Path(out_dir)
    names = np.array(result.pairs + ("",))
    rows = zip(*result.poses_m.T, result.reachable.astype(int), result.min_distance_m, names[result.worst_pair])
    paths = [write_csv(out / "interference_poses.csv", ["x_m", "y_m", "z_m", "reachable", "min_distance_m",
                                                         "worst_pair"], rows, overwrite)]
    prow = [(p, k, d, *result.poses_m[i]) for p, k, d, i in
            zip(result.pairs, result.kinds, result.pair_min_m, result.pair_argmin)]
    paths.append(write_csv(out / "interference_pairs.csv", ["pair", "kind", "min_distance_m", "x_m", "y_m", "z_m"],
                           prow, overwrite))
    if figures and result.grid_axes_m is not None:
        paths.append(plot_interference_sweep(result, out / "interference_map.png", overwrite))
    return paths


def plot_interference_sweep(result: SweepResult, path: Path | str, overwrite: bool = False) -> Path:
    """Filled contours of the minimum distance (mm) over x-z at up to four heights; the margin dashed."""
    if result.grid_axes_m is None:
        raise OutputError("an interference map needs a sweep over a grid (workspace_sweep), not a list of poses")
    xs, ys, zs = result.grid_axes_m
    d = result.min_distance_m.reshape(len(ys), len(zs), len(xs)) * 1e3
    pick = sorted(set(np.linspace(0, len(ys) - 1, min(4, len(ys))).round().astype(int)))
    fig, axes = plt.subplots(1, len(pick), figsize=(4.2 * len(pick), 3.8), squeeze=False, constrained_layout=True)
    levels = np.linspace(np.nanmin(d), np.nanmax(d), 21)
    for ax, k in zip(axes[0], pick):
        cs = ax.contourf(xs * 1e3, zs * 1e3, d[k], levels=levels, cmap="viridis")
        if np.nanmin(d[k]) < result.margin_m * 1e3 < np.nanmax(d[k]):
            ax.contour(xs * 1e3, zs * 1e3, d[k], levels=[result.margin_m * 1e3], colors="r", linestyles="--")
        ax.set(title=f"y_h = {ys[k] * 1e3:.1f} mm", xlabel="x_h [mm]", ylabel="z_h [mm]", aspect="equal")
    fig.colorbar(cs, ax=axes[0].tolist(), label="minimum clearance over pairs [mm]")
    try:
        return save_figure(fig, path, overwrite)
    finally:
        plt.close(fig)


def write_preload_study(study: PreloadStudy, out_dir: Path | str, overwrite: bool = False,
                        figures: bool = True) -> list[Path]:
    """preload_study.csv, preload_study.json and two PNGs (stiffness vs preload, curves; not with
    ``figures=False``) in out_dir."""
    out = Path(out_dir)
    header, rows = study.rows()
    paths = [io.write_csv(out / "preload_study.csv", header, rows, overwrite),
             io.write_json(out / "preload_study.json", study.to_dict(), overwrite)]
    if not figures:
        return paths
    unit = "N" if study.preload_mode == "force" else "m"
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    try:
        for g, gap in enumerate(study.clearances_m):
            lab = f"g = {gap * 1e6:g} um"
            line, = axes[0].plot(study.preloads, study.small_load_secant_stiffness_n_per_m[g], "o-", ms=3, label=lab)
            axes[1].plot(study.preloads, study.press_secant_stiffness_n_per_m[g], "o-", ms=3, color=line.get_color(),
                         label=lab)
            axes[1].plot(study.preloads, study.press_stiffness_n_per_m[g], "x:", ms=3, color=line.get_color())
            for ax in axes:
                ax.axvline(study.critical_preload[g], color=line.get_color(), lw=0.6, ls="--")
        for ax in axes:
            ax.axhline(study.no_clearance_contact_stiffness_n_per_m, color="k", lw=0.8,
                       label="no clearance, contact springs")
            ax.axhline(study.rigid_cardan_stiffness_n_per_m, color="k", lw=0.8, ls=":", label="rigid cardans")
            ax.set(xlabel=f"preload a4 [{unit}] (dashed: critical preload)", ylabel="stiffness [N/m]", yscale="log")
        axes[0].set_title(f"small-load secant stiffness at {study.small_load_n:g} N")
        axes[1].set_title(f"at {study.loads_n[-1]:g} N: secant (o-) and tangent (x:)")
        axes[0].legend(fontsize=7)
        fig.suptitle(f"pose {study.pose_m.tolist()} m, load along {np.round(study.direction, 3).tolist()}")
        paths.append(io.save_figure(fig, out / "preload_stiffness.png", overwrite))
    finally:
        plt.close(fig)
    fig, axes = plt.subplots(1, len(study.clearances_m), figsize=(4.2 * len(study.clearances_m), 3.8),
                             squeeze=False, layout="constrained")
    try:
        for g, ax in enumerate(axes[0]):
            for p, a in enumerate(study.preloads):
                ax.plot(study.deflection_m[g, p] * 1e6, study.loads_n, lw=1, label=f"a4 = {a:g} {unit}")
            ax.set(title=f"g = {study.clearances_m[g] * 1e6:g} um", xlabel="deflection along the load [um]",
                   ylabel="load [N]")
        axes[0][0].legend(fontsize=6)
        paths.append(io.save_figure(fig, out / "load_deflection.png", overwrite))
    finally:
        plt.close(fig)
    return paths
