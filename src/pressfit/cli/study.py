"""``pressfit study``: parameter studies (clearance vs preload)."""

from __future__ import annotations

from pathlib import Path

import click

from pressfit.cli.common import (
    COORDINATE,
    FORCE,
    MODEL_OPTION,
    OVERWRITE_OPTION,
    PROGRESS_OPTION,
    FiniteFloat,
    FloatList,
    cluster_options,
    echo_written,
    user_errors,
)
from pressfit.description.cases import MAX_CHUNK_SIZE, MAX_CURVE_SAMPLES, MAX_FORCE_N, MAX_SAMPLES
from pressfit.description.machine import load_machine
from pressfit.dynamics.machine.registry import model_names
from pressfit.errors import PressfitError
from pressfit.output.files import check_directory, to_json, write_directory


@click.group("study")
def study_group() -> None:
    """Parameter studies: ``pressfit study preload``, ``montecarlo``, ``design``, ``insertion``, ``cycle``,
    ``curve``."""


@study_group.command("preload", context_settings={"ignore_unknown_options": True})  # negative numbers
@click.argument("case_file", required=False, type=click.Path(path_type=Path))
@click.option("--pose", nargs=3, type=COORDINATE, help="Plate pose X Y Z, m (without CASE_FILE).")
@click.option("--clearance", "clearances", type=FloatList(0.0, 1e-2),
              help="Cardan clearances g, m, comma-separated (default: the model's).")
@click.option("--clearance-geometry", "geometry", type=click.Choice(["axial", "box", "sphere"]),
              help="Play of each cardan: +-g along the leg (axial), +-g on its three translations (box) or a ball "
                   "of radius g (sphere) (default: the model's [joints] cardan_clearance_geometry).")
@click.option("--preload", "preloads", type=FloatList(-MAX_FORCE_N, MAX_FORCE_N),
              help="Preloads a4 along v_p, comma-separated: N (force mode) or m (length).")
@click.option("--mode", "preload_mode", type=click.Choice(["force", "length"]), default="force", show_default=True)
@click.option("--load-max", "load_max", type=FiniteFloat(0.0, MAX_FORCE_N, open_low=True), default=700.0,
              show_default=True, help="Largest load, N.")
@click.option("--steps", type=click.IntRange(2, 10000), default=50, show_default=True, help="Load steps.")
@click.option("--direction", nargs=3, type=FORCE, default=(0.0, 1.0, 0.0), show_default=True, help="Load direction.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/study_preload"), show_default=True,
              help="Directory for preload_study.csv/.json and the PNG plots.")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the study as JSON.")
@PROGRESS_OPTION
@MODEL_OPTION
@user_errors
def study_preload_cmd(case_file: Path | None, pose: tuple[float, ...] | None, clearances: list[float] | None,
                      geometry: str | None, preloads: list[float] | None, preload_mode: str, load_max: float,
                      steps: int,
                      direction: tuple[float, ...], out_dir: Path, overwrite: bool, as_json: bool, progress: bool,
                      model_path: Path) -> None:
    """How much preload keeps every cardan closed up to the load, and what stiffness it buys (SI)."""
    from pressfit.output import maps as map_files
    from pressfit.studies import preload_study

    check_directory(out_dir, overwrite)
    if case_file is not None:
        if pose or clearances or preloads or geometry:
            raise PressfitError("give either CASE_FILE or --pose/--clearance/--clearance-geometry/--preload")
        from pressfit.description.cases import load_case

        kw = preload_study.study_from_case(load_case(case_file))
    else:
        if not pose or not preloads:
            raise PressfitError("give CASE_FILE, or --pose X Y Z and --preload P1,P2,...")
        machine = load_machine(model_path)
        kw = {"machine": machine, "geometry": geometry, "pose_m": list(pose), "clearances_m": clearances or [],
              "preloads": preloads, "load_max_n": load_max, "steps": steps,
              "direction": direction, "preload_mode": preload_mode}
    study = preload_study.preload_study(**kw, progress=progress)
    inputs = [case_file] if case_file is not None else [model_path]
    written = write_directory(out_dir, overwrite, lambda tmp: map_files.write_preload_study(study, tmp), inputs=inputs)
    if as_json:
        click.echo(to_json(study.to_dict() | {"outputs": [str(p) for p in written]}))
        return
    click.echo(preload_study.format_answers(study))
    echo_written(written)


@study_group.command("montecarlo")
@click.argument("case_file", type=click.Path(path_type=Path))
@click.option("--samples", type=click.IntRange(1, MAX_SAMPLES),
              help="Number of samples (default: the case's [montecarlo]).")
@click.option("--seed", type=click.IntRange(0), help="Seed (default: the case's).")
@click.option("--chunk-size", type=click.IntRange(1, MAX_CHUNK_SIZE), help="Samples per task (default: the case's).")
@cluster_options
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/montecarlo"), show_default=True,
              help="Study directory: samples/*.parquet, summary.json, quantiles.csv, PNG plots; rerun to resume.")
@click.option("--overwrite", is_flag=True, help="Discard an earlier study in --out and start afresh.")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar over samples.")
@user_errors
def study_montecarlo_cmd(case_file: Path, samples: int | None, seed: int | None, chunk_size: int | None,
                         workers: int | None, scheduler: str | None, dashboard: bool, out_dir: Path, overwrite: bool,
                         as_json: bool, progress: bool) -> None:
    """Monte Carlo tolerances: exceedance probability of each envelope limit (Wilson 95% interval) and a
    sensitivity ranking, on a Dask cluster (SI units)."""
    from pressfit.description.cases import load_case
    from pressfit.workflows.tolerance_study import run_montecarlo

    run = run_montecarlo(load_case(case_file), out_dir, samples=samples, seed=seed, chunk_size=chunk_size,
                         workers=workers, scheduler=scheduler, overwrite=overwrite, progress=progress,
                         dashboard=dashboard)
    for path in run.rerun:
        click.echo(f"warning: {path} was damaged (not a complete Parquet file); its chunk was run again", err=True)
    if as_json:
        click.echo(to_json(run.summary.to_dict() | {"outputs": [str(p) for p in run.written]}))
        return
    s = run.summary
    click.echo(f"{s.samples} samples ({run.chunks_run} of {run.chunks_total} chunks run now, the rest resumed); "
               f"failed solves: {s.failed or 'none'}")
    for e in s.exceedance:
        click.echo(f"P({e.key} beyond {e.limit:g}) = {e.probability:.4g}  (95% Wilson {e.ci95[0]:.4g} .. "
                   f"{e.ci95[1]:.4g}; {e.count}/{e.samples})")
    for note in s.notes:
        click.echo(note)
    echo_written(run.written)


@study_group.command("insertion")
@click.argument("case_file", type=click.Path(path_type=Path))
@click.option("--preload", "preloads", type=FloatList(0.0, MAX_FORCE_N),
              help="Preloads a4 along v_p, N, comma-separated (default: 0 and the case's).")
@click.option("--clearance", "clearances", type=FloatList(0.0, 1e-2),
              help="Cardan axial clearances g, m, comma-separated (default: 1e-5,5e-5).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/study_insertion"),
              show_default=True, help="Directory for insertion_study.csv/.json/.png.")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the table as JSON.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar over the runs.")
@user_errors
def study_insertion_cmd(case_file: Path, preloads: list[float] | None, clearances: list[float] | None, out_dir: Path,
                        overwrite: bool, as_json: bool, progress: bool) -> None:
    """The insertion scenario over preload and joint clearance: the tool error the play hides from the
    length-based estimate, and the overshoot (SI)."""
    from pressfit.workflows.insertion_simulation import run_insertion_study

    study, written = run_insertion_study(case_file, preloads, clearances, out_dir, overwrite, progress)
    if as_json:
        click.echo(to_json(study.to_dict() | {"outputs": [str(p) for p in written]}))
        return
    click.echo("preload [N]  clearance [um]  critical [N]  play error [um]  lateral [um]  peak [N]  overshoot [N]")
    for r in study.rows:
        click.echo(f"{r[0]:>11.4g}  {r[1] * 1e6:>14.4g}  {r[2]:>12.4g}  {r[4] * 1e6:>15.3f}  {r[5] * 1e6:>12.3f}  "
                   f"{r[6]:>8.3f}  {r[7]:>13.3f}")
    if any(c != c for c in study.column("critical_preload_n")):  # NaN
        from pressfit.studies.preload_study import NO_CRITICAL_PRELOAD

        click.echo(f"critical nan: {NO_CRITICAL_PRELOAD}")
    echo_written(written)


@study_group.command("design")
@click.argument("case_file", type=click.Path(path_type=Path))
@click.option("--trials", type=click.IntRange(1), help="Designs to evaluate (NSGA-II; default: the case's [design]).")
@cluster_options
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/design"), show_default=True,
              help="Directory for trials.parquet, pareto.parquet, summary.json, pareto.png, designs/*.toml.")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar over designs.")
@user_errors
def study_design_cmd(case_file: Path, trials: int | None, workers: int | None, scheduler: str | None,
                     dashboard: bool, out_dir: Path, overwrite: bool, as_json: bool, progress: bool) -> None:
    """Design search: the Pareto front of the case's objectives under its constraints over the workspace,
    and the best designs as machine files, on a Dask cluster (SI units)."""
    from pressfit.description.cases import load_case
    from pressfit.output.design_files import summary
    from pressfit.workflows.design_study import run_design_study

    run = run_design_study(load_case(case_file), out_dir, trials=trials, workers=workers, scheduler=scheduler,
                           overwrite=overwrite, progress=progress, dashboard=dashboard)
    s = summary(run.result)
    if as_json:
        click.echo(to_json(s | {"outputs": [str(p) for p in run.written]}))
        return
    click.echo(f"{s['trials']} designs ({s['feasible']} feasible, {s['failed']} failed); Pareto front of "
               f"{', '.join(s['objectives'])}: {len(s['pareto'])} designs")  # type: ignore[arg-type]
    echo_written(run.written)


@study_group.command("cycle")
@click.argument("case_file", type=click.Path(path_type=Path))
@click.option("--model", "plant_model", type=click.Choice(model_names()), default=None,
              help="The machine simulated (default: the case's [cycle] model).")
@cluster_options
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/study_cycle"), show_default=True,
              help="Directory for samples.parquet, summary.json, front.png and fastest.toml.")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar over the board runs.")
@user_errors
def study_cycle_cmd(case_file: Path, plant_model: str | None, workers: int | None, scheduler: str | None,
                    dashboard: bool, out_dir: Path, overwrite: bool, as_json: bool, progress: bool) -> None:
    """Throughput: the board's motion limits (and optionally its controller gains and preload) swept over the case's
    [cycle.study] grid on a Dask cluster (one board run per sample); the Pareto front of cycle time against the
    worst alignment error and the worst overshoot, and the fastest setting within the pins' limits (the force limit,
    the overshoot and alignment limits where given; the limits judged are printed), written as a case file (SI
    units)."""
    from pressfit.studies.cycle_study import FACTOR_LABELS, FACTORS
    from pressfit.workflows.throughput_study import run_cycle_study

    if dashboard and scheduler is not None:
        raise PressfitError("--dashboard starts the local cluster's dashboard: not with --scheduler")
    result, written = run_cycle_study(case_file, plant_model, out_dir, overwrite, workers, scheduler, progress,
                                      dashboard)
    s = result.summary()
    if as_json:
        click.echo(to_json(s | {"outputs": [str(p) for p in written]}))
        return
    click.echo(f"{s['case']}: {s['samples']} samples (model {s['model']}), {s['failed']} refused or failed, "
               f"{s['within_limits']} within the limits; Pareto front of cycle time, worst alignment error, "
               f"worst overshoot: {len(s['front'])} samples")
    click.echo("limits judged: " + "; ".join(s["limits_judged"]))
    varied = [k for k in FACTORS if len({r[k] for r in s["front"]}) > 1] or list(FACTORS[:1])  # the ones that vary
    click.echo("".join(f"{FACTOR_LABELS[k]:>15}" for k in varied)
               + "  cycle [s]  alignment [um]  overshoot [N]  within")
    for r in s["front"]:
        error = r["worst_alignment_error_m"]
        alignment = "never touched" if error is None else f"{error * 1e6:.3f}"
        click.echo("".join(f"{r[k]:>15.4g}" for k in varied) + f" {r['cycle_time_s']:>10.3f} {alignment:>15}"
                   f" {r['worst_overshoot_n']:>14.3f}  {'yes' if r['within_limits'] else 'no'}")
    f = s["fastest_within_limits"]
    click.echo("fastest within the limits: " + ("none" if f is None else
               f"sample {f['sample']}, cycle time {f['cycle_time_s']:.3f} s (written as fastest.toml)"))
    echo_written(written)


@study_group.command("curve")
@click.argument("case_file", type=click.Path(path_type=Path))
@click.option("--samples", type=click.IntRange(1, MAX_CURVE_SAMPLES),
              help=f"Predicted curves (default: the case's [curve]; at most {MAX_CURVE_SAMPLES:.0e}).")
@click.option("--seed", type=click.IntRange(0), help="Seed (default: the case's [curve]).")
@cluster_options
@click.option("--serial", is_flag=True, help="Run in this process, without a Dask cluster.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/study_curve"), show_default=True,
              help="Directory for windows.json (with the band), band.csv and band.png.")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar over samples.")
@user_errors
def study_curve_cmd(case_file: Path, samples: int | None, seed: int | None, workers: int | None,
                    scheduler: str | None, dashboard: bool, serial: bool, out_dir: Path, overwrite: bool,
                    as_json: bool, progress: bool) -> None:
    """The predicted press curve's tolerance band over the case's [curve.tolerances] (Monte Carlo on a Dask
    cluster) and the monitor's windows derived from it (windows.json; displacement: the sensed depth, SI)."""
    from pressfit.workflows.curve_study import run_curve_study

    if dashboard:
        raise PressfitError("--dashboard is not offered by study curve")
    if serial and (workers is not None or scheduler is not None):
        raise PressfitError("give --serial or --workers/--scheduler, not both")
    run = run_curve_study(case_file, out_dir, samples=samples, seed=seed, workers=workers, scheduler=scheduler,
                          serial=serial, overwrite=overwrite, progress=progress and not as_json)
    s = run.summary()
    if as_json:
        click.echo(to_json(s))
        return
    click.echo(f"{s['samples']} predicted curves (seed {s['seed']}); largest force of a curve "
               f"{s['largest_force_n_min']:.4g} .. {s['largest_force_n_max']:.4g} N; displacement: the sensed depth")
    click.echo("windows: " + ", ".join(s["elements"]))
    echo_written(run.written)
