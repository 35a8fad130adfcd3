"""The ``pressfit`` command: thin; parses, calls the library, prints. Exit 2 on bad input."""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click
import numpy as np

from pressfit import kinematics
from pressfit.description.machine import DEFAULT_MODEL, load_machine
from pressfit.errors import PressfitError
from pressfit.output.files import to_json

MODEL_OPTION = click.option("--model", "model_path", type=click.Path(path_type=Path), default=DEFAULT_MODEL,
                            show_default=True, help="Machine description (TOML).")


def user_errors(func: Callable[..., Any]) -> Callable[..., Any]:
    """Turn a :class:`PressfitError` into a one-line message and exit code 2 (never a traceback)."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except PressfitError as exc:
            click.echo(f"error: {exc}", err=True)
            sys.exit(2)

    return wrapper


@click.group()
@click.version_option(package_name="pressfit")
def main() -> None:
    """Structural load and compliance analyzer for the 4-UPU press-fit manipulator (SI units)."""


@main.command("kinematics", context_settings={"ignore_unknown_options": True})  # negative coordinates
@click.argument("x", type=float)
@click.argument("y", type=float)
@click.argument("z", type=float)
@click.option("--json", "as_json", is_flag=True, help="Print JSON (keys documented in README).")
@MODEL_OPTION
@user_errors
def kinematics_cmd(x: float, y: float, z: float, as_json: bool, model_path: Path) -> None:
    """Closed-form kinematics of the plate pose X Y Z (m): lengths, angles, v_p, n, force indices."""
    machine = load_machine(model_path)
    h = kinematics.require_reachable(machine, [x, y, z])
    out = kinematics.pose_report(machine, h)
    if as_json:
        click.echo(to_json(out))
        return
    click.echo(f"pose h = ({x:g}, {y:g}, {z:g}) m: reachable")
    click.echo("leg   l [m]     alpha [rad]  beta [rad]  v_p")
    for i in range(4):
        click.echo(f"{i + 1:>3}  {out['leg_lengths_m'][i]:.6f}  {out['alpha_rad'][i]:+.6f}    "
                   f"{out['beta_rad'][i]:+.6f}   {out['preload_vector'][i]:+.4f}")
    click.echo(f"dexterity n = {out['dexterity']:.4f}; force indices F_x, F_y, F_z = "
               + ", ".join(f"{v:.4f}" for v in out["force_indices"]))


@main.command("list")
@user_errors
def list_cmd() -> None:
    """The shipped machine descriptions (models/) and case files (cases/), with what each case holds."""
    from pressfit.description.cases import discover, load_case
    from pressfit.shipped import cases_dir, models_dir

    click.echo(f"models ({models_dir()}):")
    for path in sorted(models_dir().glob("*.toml")):
        m = load_machine(path)
        click.echo(f"  {path.name}  {m.name}: {m.description}")
    click.echo(f"cases ({cases_dir()}):")
    for path in discover([cases_dir()]):
        c = load_case(path)
        kinds = [k for k, v in (("reference table", c.reference), ("envelope", c.envelope.model_dump(exclude_none=True)),
                                ("study", getattr(c, "study", None))) if v]
        click.echo(f"  {path.relative_to(cases_dir())}  {c.name} [{', '.join(kinds) or 'loads'}]: "
                   f"{' '.join(c.description.split())[:90]}")


@main.command("solve", context_settings={"ignore_unknown_options": True})  # negative numbers
@click.argument("values", nargs=-1)
@click.option("--load", "has_load", is_flag=True,
              help="Followed by FX FY FZ [MX MY MZ]: plate wrench at the plate centre, world axes (N, N m).")
@click.option("--preload", "a4", type=float, default=None, help="Actuator preload a4 along v_p (N; m in length mode).")
@click.option("--preload-mode", type=click.Choice(["force", "length"]), default="force", show_default=True,
              help="force: offsets giving actuator forces a4 v_p at no load; length: offsets -a4 v_p (m).")
@click.option("--linear", is_flag=True, help="Small-displacement (linear) solve instead of the nonlinear default.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON (keys documented in README).")
@MODEL_OPTION
@user_errors
def solve_cmd(values: tuple[str, ...], has_load: bool, a4: float | None, preload_mode: str, linear: bool,
              as_json: bool, model_path: Path) -> None:
    """Static equilibrium: pressfit solve X Y Z --load FX FY FZ [MX MY MZ], or pressfit solve CASE.toml."""
    from pressfit.mechanics.statics import solve_equilibrium

    if len(values) == 1 and values[0].endswith(".toml"):
        from pressfit.description.cases import load_case

        case = load_case(values[0])
        machine = case.machine()
        a4, preload_mode = (case.preload.a4 or None), case.preload.mode
        linear = linear or case.solver.linear
        jobs = [(h, w) for h in case.poses.array() for w in case.loads.wrenches()]
    else:
        try:
            numbers = [float(v) for v in values]
        except ValueError:
            raise click.UsageError("expected X Y Z --load FX FY FZ [MX MY MZ] (numbers) or CASE.toml") from None
        if not has_load or len(numbers) not in (6, 9):
            raise click.UsageError("expected X Y Z --load FX FY FZ [MX MY MZ]")
        wrench = np.zeros(6)
        wrench[:len(numbers) - 3] = numbers[3:]
        machine = load_machine(model_path)
        jobs = [(np.array(numbers[:3]), wrench)]
    results = [solve_equilibrium(machine, h, w, preload=a4, preload_mode=preload_mode, linear=linear)
               for h, w in jobs]
    if as_json:
        click.echo(to_json(results[0].to_dict() if len(results) == 1 else [r.to_dict() for r in results]))
        return
    for eq in results:
        _print_equilibrium(eq)


def _print_equilibrium(eq: Any) -> None:
    from pressfit.mechanics.statics import SECTIONS

    kind = "linear (small displacements)" if eq.linear else f"nonlinear, {eq.iterations} Newton iterations"
    fmt = lambda v: "(" + ", ".join(f"{c:g}" for c in v) + ")"  # noqa: E731
    click.echo(f"pose h = {fmt(eq.pose_m)} m, load F = {fmt(eq.load[:3])} N, M = {fmt(eq.load[3:])} N m; {kind}")
    click.echo("leg  section       N [N]      V_x [N]    V_y [N]    M_x [N m]  M_y [N m]  T [N m]")
    for i, leg in enumerate(eq.legs):
        for name in SECTIONS:
            s = leg.sections[name]
            click.echo(f"{i + 1:>3}  {name:<9} " + " ".join(f"{v:+10.4f}" for v in (s.N, s.V_x, s.V_y, s.M_x, s.M_y, s.T)))
    click.echo("actuator forces [N]: " + ", ".join(f"{v:+.4f}" for v in eq.actuator_forces_n))
    click.echo("plate displacement [m]: " + ", ".join(f"{v:+.4e}" for v in eq.plate_displacement_m)
               + "; rotation [rad]: " + ", ".join(f"{v:+.4e}" for v in eq.plate_rotation_rad))
    r = eq.residuals
    click.echo(f"residuals (relative): plate F {r.plate_force:.1e} M {r.plate_moment:.1e}; machine F "
               f"{r.machine_force:.1e} M {r.machine_moment:.1e}; closure {r.closure_m:.1e} m {r.closure_rad:.1e} rad; "
               f"stationarity {r.stationarity:.1e}\n")


@main.command("tables")
@click.option("--json", "as_json", is_flag=True, help="Print the entries as JSON.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), help="Write tables.md and tables.csv here.")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@user_errors
def tables_cmd(as_json: bool, out_dir: Path | None, overwrite: bool) -> None:
    """Reproduce the paper's Tables 5 and 6 (cases/paper/A, B, C) beside pressfit's solution."""
    from pressfit.output.files import write_csv, write_text
    from pressfit.studies import paper_tables as tables

    entries = tables.paper_tables()
    if as_json:
        click.echo(to_json([e.as_dict() for e in entries]))
    else:
        click.echo(tables.to_markdown(entries))
    if out_dir is not None:
        write_text(out_dir / "tables.md", tables.to_markdown(entries), overwrite)
        write_csv(out_dir / "tables.csv", *tables.to_rows(entries), overwrite=overwrite)


@main.command("check")
@click.argument("paths", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--junit", "junit_path", type=click.Path(path_type=Path), help="Write JUnit XML here.")
@click.option("--json", "json_path", type=click.Path(path_type=Path), help="Write JSON results here.")
@click.option("--overwrite", is_flag=True, help="Replace existing result files.")
@click.option("--progress/--no-progress", default=True, help="Show progress bars.")
@user_errors
def check_cmd(paths: tuple[Path, ...], junit_path: Path | None, json_path: Path | None,
              overwrite: bool, progress: bool) -> None:
    """Check the load envelopes of case files (or directories of them): exit 0 pass, 1 fail, 2 bad input."""
    from dataclasses import asdict

    from pressfit.description.cases import discover, load_case
    from pressfit.output.files import write_json, write_text

    files = discover(list(paths))
    cases = [load_case(f) for f in files]  # validate every file before computing anything
    for c in cases:
        c.machine()
    from pressfit.output import check_report
    from pressfit.studies import limit_check as envelope
    checked = [c for c in cases if c.envelope.model_dump(exclude_none=True)]
    if not checked:
        raise PressfitError("no case among " + ", ".join(map(str, paths)) + " has an [envelope] to check")
    skipped = [c.path for c in cases if c not in checked]
    if skipped:
        click.echo(f"skipped (no [envelope]): {', '.join(skipped)}")
    results = [envelope.evaluate_case(c, progress=progress) for c in checked]
    click.echo(check_report.format_table(results))
    if junit_path:
        write_text(junit_path, check_report.junit_xml(results), overwrite)
    if json_path:
        write_json(json_path, [asdict(r) | {"passed": r.passed} for r in results], overwrite)
    failed = [r.case for r in results if not r.passed]
    click.echo(f"{len(results) - len(failed)} passed, {len(failed)} failed")
    sys.exit(1 if failed else 0)


@main.command("workspace")
@click.option("--y", "heights", type=float, multiple=True, help="Plate height y_h of a map, m (repeatable; "
              "default 0.6, the paper's Figures 7-11).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/workspace"),
              show_default=True, help="Directory for the maps (CSV, PNG) and summary.json.")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
@MODEL_OPTION
@user_errors
def workspace_cmd(heights: tuple[float, ...], out_dir: Path, overwrite: bool, as_json: bool, progress: bool,
                  model_path: Path) -> None:
    """Reachable heights of the required square (0, 45, 90 deg), maps of n, F and dl/dh, statistics."""
    from pressfit.kinematics import workspace
    from pressfit.output import maps as map_files

    machine = load_machine(model_path)
    rng = workspace.square_height_range(machine)
    for y in heights:
        if not (np.isfinite(y) and rng.y_min_m <= y <= rng.y_max_m):
            raise PressfitError(f"--y {y:g}: the required square is reachable only for y_h in "
                                f"[{rng.y_min_m:.5f}, {rng.y_max_m:.5f}] m")
    summary, _ = map_files.write_kinematic_maps(machine, out_dir, heights or workspace.DEFAULT_HEIGHTS_M,
                                         overwrite, progress)
    if as_json:
        click.echo(to_json(summary))
        return
    for r in summary["height_range"]:
        click.echo(f"square at {r['angle_deg']:g} deg reachable for y_h in [{r['y_min_m']:.5f}, "
                   f"{r['y_max_m']:.5f}] m (+-{r['tolerance_m']:g} m)")
    for s in summary["squares"]:
        click.echo(f"y_h = {s['y_m']:g} m, {s['angle_deg']:g} deg: n in [{s['dexterity_min']:.4f}, "
                   f"{s['dexterity_max']:.4f}] (variation {s['dexterity_variation']:.1%}), max F_x, F_y, F_z = "
                   + ", ".join(f"{v:.4f}" for v in s["force_index_max"]))
    click.echo(f"maps and summary.json written to {out_dir}")


@main.command("stiffness", context_settings={"ignore_unknown_options": True})  # negative coordinates
@click.argument("x", type=float)
@click.argument("y", type=float)
@click.argument("z", type=float)
@click.option("--json", "as_json", is_flag=True, help="Print JSON (SI units, keys name their units).")
@click.option("--maps", is_flag=True, help="Instead: maps over the x-z required square at height Y (X, Z unused).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/stiffness"), show_default=True,
              help="Directory for the maps (PNG, CSV).")
@click.option("--n", "n_grid", type=click.IntRange(3, 1001), default=51, show_default=True, help="Map grid points per side.")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@MODEL_OPTION
@user_errors
def stiffness_cmd(x: float, y: float, z: float, as_json: bool, maps: bool, out_dir: Path, n_grid: int,
                  overwrite: bool, model_path: Path) -> None:
    """Plate compliance and stiffness at pose X Y Z (m): condensed linear model, cross-checked against the
    Pinocchio model, plus the tangent compliance of the nonlinear equilibrium under the press load."""
    from pressfit.mechanics import compliance, condensed
    from pressfit.output import maps as map_files

    machine = load_machine(model_path)
    if maps:
        m = condensed.stiffness_maps(machine, y, n_grid)
        for p in map_files.write_stiffness_maps(m, out_dir, overwrite):
            click.echo(f"wrote {p}")
        return
    h = kinematics.require_reachable(machine, [x, y, z])
    out = condensed.stiffness_report(machine, h)
    c_pin = compliance.plate_compliance(machine, h)
    c_tan = compliance.plate_compliance(machine, h, load=np.array([0.0, out["press_load_n"], 0, 0, 0, 0]))
    scale = np.abs(c_pin).max()
    out["pinocchio_linear_compliance_6x6"] = c_pin.tolist()
    out["condensed_vs_pinocchio_max_difference_relative"] = float(
        np.abs(np.array(out["compliance_6x6"]) - c_pin).max() / scale)
    out["tangent_compliance_6x6_under_press_load"] = c_tan.tolist()
    out["tangent_vertical_stiffness_under_press_load_n_per_m"] = float(1 / c_tan[1, 1])
    if as_json:
        click.echo(to_json(out))
        return
    click.echo(f"pose h = ({x:g}, {y:g}, {z:g}) m; plate-centre compliance ({out['compliance_units']}):")
    for row in out["compliance_6x6"]:
        click.echo("  " + " ".join(f"{v:+.4e}" for v in row))
    click.echo("translational stiffness at the centre, plate free to tilt [N/m]:")
    for row in out["translational_stiffness_n_per_m"]:
        click.echo("  " + " ".join(f"{v:+.4e}" for v in row))
    click.echo(f"vertical {out['vertical_stiffness_n_per_m']:.4e} N/m, lateral (weakest horizontal) "
               f"{out['lateral_stiffness_n_per_m']:.4e} N/m, ratio {out['lateral_to_vertical']:.4f}")
    click.echo(f"under {out['press_load_n']:g} N (+y): tilt {out['press_tilt_rad']:.4e} rad, displacement "
               + ", ".join(f"{v:+.4e}" for v in out["press_displacement_m"]) + " m")
    click.echo(f"Pinocchio model: compliance agrees with the condensed one to "
               f"{out['condensed_vs_pinocchio_max_difference_relative']:.1e} (relative to its largest entry); "
               f"tangent vertical stiffness under the press load (nonlinear) "
               f"{out['tangent_vertical_stiffness_under_press_load_n_per_m']:.4e} N/m")


@main.command("interference", context_settings={"ignore_unknown_options": True})  # negative coordinates
@click.argument("pose", nargs=-1, type=float)
@click.option("--workspace", "over_workspace", is_flag=True, help="Sweep the required workspace instead of one pose.")
@click.option("--margin", "margin_m", type=float, help="Safety margin, m (default: collision.safety_margin_m).")
@click.option("--points", type=click.IntRange(2, 1001), default=41, show_default=True,
              help="Grid points per x and z axis (--workspace).")
@click.option("--heights", type=click.IntRange(1, 1001), default=7, show_default=True,
              help="Grid heights (--workspace).")
@click.option("--y-range", "y_range", type=float, nargs=2, help="y_h range, m (default: heights where the whole "
              "required square is reachable).")
@click.option("--include", multiple=True, help="Also check pair 'a|b' (repeatable).")
@click.option("--exclude", multiple=True, help="Do not check pair 'a|b' (repeatable).")
@click.option("--rig", type=click.Choice(["auto", "model", "closed-form"]), default="auto", show_default=True,
              help="Pinocchio model that places the shapes.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON (SI units; keys name their units).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), help="Write CSV and a PNG map here (--workspace).")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
@MODEL_OPTION
@user_errors
def interference_cmd(pose: tuple[float, ...], over_workspace: bool, margin_m: float | None, points: int, heights: int,
                     y_range: tuple[float, float] | None, include: tuple[str, ...], exclude: tuple[str, ...], rig: str,
                     as_json: bool, out_dir: Path | None, overwrite: bool, progress: bool, model_path: Path) -> None:
    """Signed clearance (m) of legs, plate, base and extra bodies at pose X Y Z or over --workspace.

    Exit 0 when every checked pair keeps the safety margin, 1 when one does not, 2 on bad input.
    """
    from pressfit.geometry import interference
    from pressfit.output import maps as map_files

    if over_workspace == (len(pose) == 3) or len(pose) not in (0, 3):
        raise PressfitError("give either a pose X Y Z (m) or --workspace")
    machine = load_machine(model_path)
    im = interference.build_interference(machine, rig, include, exclude)
    if not over_workspace:
        pc = interference.clearance_at(im, kinematics.require_reachable(machine, pose), margin_m)
        if as_json:
            click.echo(to_json(pc.to_dict() | {"kinematics": im.kinematics, "notes": list(im.notes)}))
        else:
            click.echo(f"pose h = ({pose[0]:g}, {pose[1]:g}, {pose[2]:g}) m; margin {pc.margin_m * 1e3:g} mm")
            for p in sorted(pc.pairs, key=lambda p: p.distance_m):
                click.echo(f"  {p.distance_m * 1e3:+9.2f} mm  {p.kind:<10} {p.pair}")
            click.echo(f"excluded (touch by design or overridden): {', '.join(pc.excluded)}")
            click.echo(f"{'PASS' if pc.passed else 'FAIL'}: worst {pc.worst.pair} {pc.worst.distance_m * 1e3:+.2f} mm")
        sys.exit(0 if pc.passed else 1)
    res = interference.workspace_sweep(im, points, heights, y_range, margin_m, progress)
    summary = res.to_dict() | {"kinematics": im.kinematics, "notes": list(im.notes),
                               "y_range_m": [float(res.grid_axes_m[1][0]), float(res.grid_axes_m[1][-1])]}
    written = map_files.write_interference_sweep(res, out_dir, overwrite) if out_dir is not None else []
    if as_json:
        click.echo(to_json(summary | {"outputs": [str(p) for p in written]}))
    else:
        y0, y1 = summary["y_range_m"]
        click.echo(f"{len(res.poses_m)} poses (x, z in the required square, y_h in [{y0:.4f}, {y1:.4f}] m), "
                   f"{res.n_skipped} unreachable skipped; margin {res.margin_m * 1e3:g} mm")
        for kind, v in summary["by_kind"].items():
            click.echo(f"  {kind:<10} min {v['distance_m'] * 1e3:+9.2f} mm  {v['pair']:<28} at "
                       + "(" + ", ".join(f"{c:.4f}" for c in v["pose_m"]) + ") m")
        w = summary["worst"]
        click.echo(f"{'PASS' if res.passed else 'FAIL'}: worst {w['pair']} {w['distance_m'] * 1e3:+.2f} mm")
        for p in written:
            click.echo(f"wrote {p}")
    sys.exit(0 if res.passed else 1)


@main.command("report")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("report"), show_default=True,
              help="Output directory.")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--quick", is_flag=True, help="Coarse grids (a preview in seconds).")
@MODEL_OPTION
@user_errors
def report_cmd(out_dir: Path, overwrite: bool, quick: bool, model_path: Path) -> None:
    """Reproduce Tables 5 and 6 and write the full Markdown report (maps, envelope, stiffness, ...)."""
    from pressfit.output.report import write_report

    path = write_report(load_machine(model_path), out_dir, overwrite=overwrite, quick=quick)
    click.echo((path.parent / "tables.md").read_text())  # the Tables 5-6 comparison the report just wrote
    click.echo(f"report written to {path}")


@main.group("study")
def study_group() -> None:
    """Parameter studies: ``pressfit study preload``."""


def _floats(text: str | None, what: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",") if v.strip()] if text else []
    except ValueError:
        raise PressfitError(f"{what} must be comma-separated numbers, got {text!r}") from None


@study_group.command("preload", context_settings={"ignore_unknown_options": True})  # negative numbers
@click.argument("case_file", required=False, type=click.Path(path_type=Path))
@click.option("--pose", nargs=3, type=float, help="Plate pose X Y Z, m (without CASE_FILE).")
@click.option("--clearance", "clearances", help="Cardan axial clearances g, m, comma-separated (default: the model's).")
@click.option("--preload", "preloads", help="Preloads a4 along v_p, comma-separated: N (force mode) or m (length).")
@click.option("--mode", "preload_mode", type=click.Choice(["force", "length"]), default="force", show_default=True)
@click.option("--load-max", "load_max", type=float, default=700.0, show_default=True, help="Largest load, N.")
@click.option("--steps", type=click.IntRange(2, 10000), default=50, show_default=True, help="Load steps.")
@click.option("--direction", nargs=3, type=float, default=(0.0, 1.0, 0.0), show_default=True, help="Load direction.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/study_preload"), show_default=True,
              help="Directory for preload_study.csv/.json and the PNG plots.")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--json", "as_json", is_flag=True, help="Print the study as JSON.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
@MODEL_OPTION
@user_errors
def study_preload_cmd(case_file: Path | None, pose: tuple[float, ...] | None, clearances: str | None,
                      preloads: str | None, preload_mode: str, load_max: float, steps: int,
                      direction: tuple[float, ...], out_dir: Path, overwrite: bool, as_json: bool, progress: bool,
                      model_path: Path) -> None:
    """How much preload keeps every cardan closed up to the load, and what stiffness it buys (SI)."""
    from pressfit.output import maps as map_files
    from pressfit.studies import preload_study

    if case_file is not None:
        if pose or clearances or preloads:
            raise PressfitError("give either CASE_FILE or --pose/--clearance/--preload")
        from pressfit.description.cases import load_case

        kw = preload_study.study_from_case(load_case(case_file))
    else:
        if not pose or not preloads:
            raise PressfitError("give CASE_FILE, or --pose X Y Z and --preload P1,P2,...")
        machine = load_machine(model_path)
        kw = {"machine": machine, "pose_m": list(pose), "clearances_m": _floats(clearances, "--clearance"),
              "preloads": _floats(preloads, "--preload"), "load_max_n": load_max, "steps": steps,
              "direction": direction, "preload_mode": preload_mode}
    study = preload_study.preload_study(**kw, progress=progress)
    written = map_files.write_preload_study(study, out_dir, overwrite)
    if as_json:
        click.echo(to_json(study.to_dict() | {"outputs": [str(p) for p in written]}))
        return
    click.echo(preload_study.format_answers(study))
    for p in written:
        click.echo(f"wrote {p}")


if __name__ == "__main__":
    main()
