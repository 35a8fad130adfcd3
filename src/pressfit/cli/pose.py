"""Commands about one pose: kinematics, solve, stiffness, interference."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from pressfit import kinematics
from pressfit.cli.common import (
    COORDINATE,
    FORCE,
    MODEL_OPTION,
    OVERWRITE_OPTION,
    PROGRESS_OPTION,
    FiniteFloat,
    echo_written,
    increasing_pair,
    parse_numbers,
    user_errors,
)
from pressfit.description.machine import load_machine
from pressfit.errors import PressfitError
from pressfit.mechanics.statics import Equilibrium
from pressfit.output.files import check_directory, to_json, write_directory


@click.command("kinematics", context_settings={"ignore_unknown_options": True})  # negative coordinates
@click.argument("x", type=COORDINATE)
@click.argument("y", type=COORDINATE)
@click.argument("z", type=COORDINATE)
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
    vp = out["preload_vector"]  # None unless the machine has one redundant leg (kinematics.pose_report)
    click.echo("leg   l [m]     alpha [rad]  beta [rad]" + ("  v_p" if vp is not None else ""))
    for i in range(len(out["leg_lengths_m"])):
        click.echo(f"{i + 1:>3}  {out['leg_lengths_m'][i]:.6f}  {out['alpha_rad'][i]:+.6f}    "
                   f"{out['beta_rad'][i]:+.6f}" + (f"   {vp[i]:+.4f}" if vp is not None else ""))
    click.echo(f"dexterity n = {out['dexterity']:.4f}; force indices F_x, F_y, F_z = "
               + ", ".join(f"{v:.4f}" for v in out["force_indices"]))


@click.command("solve", context_settings={"ignore_unknown_options": True})  # negative numbers
@click.argument("values", nargs=-1)
@click.option("--load", "has_load", is_flag=True,
              help="Followed by FX FY FZ [MX MY MZ]: plate wrench at the plate centre, world axes (N, N m).")
@click.option("--preload", "a4", type=FORCE, default=None, help="Actuator preload a4 along v_p (N; m in length mode).")
@click.option("--preload-mode", type=click.Choice(["force", "length"]), default=None,
              help="force (default): offsets giving actuator forces a4 v_p at no load; length: offsets -a4 v_p (m).")
@click.option("--linear", is_flag=True, help="Small-displacement (linear) solve instead of the nonlinear default.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON (keys documented in README).")
@MODEL_OPTION
@user_errors
def solve_cmd(values: tuple[str, ...], has_load: bool, a4: float | None, preload_mode: str | None, linear: bool,
              as_json: bool, model_path: Path) -> None:
    """Static equilibrium: pressfit solve X Y Z --load FX FY FZ [MX MY MZ], or pressfit solve CASE.toml."""
    from pressfit.mechanics.statics import solve_case, solve_equilibrium

    if len(values) == 1 and values[0].endswith(".toml"):
        from pressfit.description.cases import load_case

        if a4 is not None or preload_mode is not None:
            raise PressfitError(f"--preload/--preload-mode cannot be combined with a case file: edit the [preload] "
                                f"table of {values[0]}")
        results = solve_case(load_case(values[0]), linear)
    else:
        numbers = parse_numbers(values, "expected X Y Z --load FX FY FZ [MX MY MZ] (finite numbers) or CASE.toml")
        if not has_load or len(numbers) not in (6, 9):
            raise click.UsageError("expected X Y Z --load FX FY FZ [MX MY MZ]")
        wrench = numbers[3:] + [0.0] * (9 - len(numbers))
        results = [solve_equilibrium(load_machine(model_path), numbers[:3], wrench, preload=a4,
                                     preload_mode=preload_mode or "force", linear=linear)]
    if as_json:
        click.echo(to_json(results[0].to_dict() if len(results) == 1 else [r.to_dict() for r in results]))
        return
    for eq in results:
        _print_equilibrium(eq)


def _print_equilibrium(eq: Equilibrium) -> None:
    from pressfit.mechanics.statics import SECTIONS

    kind = "linear (small displacements)" if eq.linear else f"nonlinear, {eq.iterations} Newton iterations"
    fmt = lambda v: "(" + ", ".join(f"{c:g}" for c in v) + ")"
    click.echo(f"pose h = {fmt(eq.pose_m)} m, load F = {fmt(eq.load[:3])} N, M = {fmt(eq.load[3:])} N m; {kind}")
    click.echo("leg  section       N [N]      V_x [N]    V_y [N]    M_x [N m]  M_y [N m]  T [N m]")
    for i, leg in enumerate(eq.legs):
        for name in SECTIONS:
            s = leg.sections[name]
            click.echo(
                f"{i + 1:>3}  {name:<9} " + " ".join(f"{v:+10.4f}" for v in (s.N, s.V_x, s.V_y, s.M_x, s.M_y, s.T))
            )
    click.echo("actuator forces [N]: " + ", ".join(f"{v:+.4f}" for v in eq.actuator_forces_n))
    click.echo("plate displacement [m]: " + ", ".join(f"{v:+.4e}" for v in eq.plate_displacement_m)
               + "; rotation [rad]: " + ", ".join(f"{v:+.4e}" for v in eq.plate_rotation_rad))
    r = eq.residuals
    click.echo(f"residuals (relative): plate F {r.plate_force:.1e} M {r.plate_moment:.1e}; machine F "
               f"{r.machine_force:.1e} M {r.machine_moment:.1e}; closure {r.closure_m:.1e} m {r.closure_rad:.1e} rad; "
               f"stationarity {r.stationarity:.1e}\n")


@click.command("stiffness", context_settings={"ignore_unknown_options": True})  # negative coordinates
@click.argument("x", type=COORDINATE)
@click.argument("y", type=COORDINATE)
@click.argument("z", type=COORDINATE)
@click.option("--json", "as_json", is_flag=True, help="Print JSON (SI units, keys name their units).")
@click.option("--maps", is_flag=True, help="Instead: maps over the x-z required square at height Y (X, Z unused).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/stiffness"), show_default=True,
              help="Directory for the maps (PNG, CSV).")
@click.option(
    "--n", "n_grid", type=click.IntRange(3, 1001), default=51, show_default=True, help="Map grid points per side."
)
@OVERWRITE_OPTION
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
        check_directory(out_dir, overwrite)
        m = condensed.stiffness_maps(machine, y, n_grid)
        for p in write_directory(out_dir, overwrite, lambda tmp: map_files.write_stiffness_maps(m, tmp)):
            click.echo(f"wrote {p}")
        return
    out = compliance.pose_stiffness_report(machine, [x, y, z])
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
    if machine.actuator.table.sensed_past_stiffness:
        click.echo(f"as the drives' position sensors see it (they read past the drives' own stiffness, which their "
                   f"position loop holds): vertical compliance {out['sensed_vertical_compliance_m_per_n']:.4e} m/N "
                   f"(the press monitor's deflection: simulate, curve, curves check --compensate)")


@click.command("interference", context_settings={"ignore_unknown_options": True})  # negative coordinates
@click.argument("pose", nargs=-1, type=COORDINATE)
@click.option("--workspace", "over_workspace", is_flag=True, help="Sweep the required workspace instead of one pose.")
@click.option("--margin", "margin_m", type=FiniteFloat(0.0, 1.0),
              help="Safety margin, m, in [0, 1] (default: collision.safety_margin_m).")
@click.option("--points", type=click.IntRange(2, 1001), default=41, show_default=True,
              help="Grid points per x and z axis (--workspace).")
@click.option("--heights", type=click.IntRange(1, 1001), default=7, show_default=True,
              help="Grid heights (--workspace).")
@click.option("--y-range", "y_range", type=COORDINATE, nargs=2, callback=increasing_pair,
              help="y_h range LOW HIGH, m (default: heights where the whole "
              "required square is reachable).")
@click.option("--include", multiple=True, help="Also check pair 'a|b' (repeatable).")
@click.option("--exclude", multiple=True, help="Do not check pair 'a|b' (repeatable).")
@click.option("--rig", type=click.Choice(["auto", "model", "closed-form"]), default="auto", show_default=True,
              help="Pinocchio model that places the shapes.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON (SI units; keys name their units).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), help="Write CSV and a PNG map here (--workspace).")
@OVERWRITE_OPTION
@PROGRESS_OPTION
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
    if out_dir is not None:
        check_directory(out_dir, overwrite)
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
    written = [] if out_dir is None else write_directory(
        out_dir, overwrite, lambda tmp: map_files.write_interference_sweep(res, tmp))
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
        echo_written(written)
    sys.exit(0 if res.passed else 1)
