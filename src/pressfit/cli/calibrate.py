"""``pressfit calibrate``: the machine file fitted to the built machine's measurements, and the measurement plan."""

from __future__ import annotations

from pathlib import Path

import click

from pressfit.cli.common import OVERWRITE_OPTION, FiniteFloat, echo_written, user_errors
from pressfit.output.files import check_directory, check_distinct, to_json, write_directory


@click.command("calibrate")
@click.argument("machine_path", metavar="MACHINE.toml", type=click.Path(path_type=Path))
@click.argument("measurements_path", metavar="MEASUREMENTS.csv", type=click.Path(path_type=Path), required=False)
@click.option("--fit", "fit", multiple=True, required=True, metavar="KEY[=LO:HI]",
              help="A numeric key of the machine file to fit, table.key (e.g. actuator.axial_stiffness_n_per_m), "
                   "optionally with bounds; repeat for several keys.")
@click.option("--modes", "modes_path", type=click.Path(path_type=Path),
              help="Measured first natural frequencies: x_m,y_m,z_m,frequency_hz[,sigma_hz].")
@click.option("--plan", is_flag=True, help="Plan the measurements instead (no MEASUREMENTS.csv): D-optimal poses "
              "and load directions over the required workspace.")
@click.option("--poses", type=click.IntRange(1), default=12, show_default=True, help="Measurements to plan.")
@click.option("--load", "load_n", type=FiniteFloat(0.0, 1e6, open_low=True), default=700.0, show_default=True,
              help="Planned load magnitude, N.")
@click.option("--sigma", "sigma_m", type=FiniteFloat(0.0, 1.0, open_low=True), default=1e-6, show_default=True,
              help="Planned measurement noise per translation component, m.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON (results.json's content).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path),
              help="Write results.json, residuals.csv, predicted_vs_measured.png, calibration.md and the calibrated "
                   "machine file MACHINE_calibrated.toml here.")
@OVERWRITE_OPTION
@user_errors
def calibrate_cmd(machine_path: Path, measurements_path: Path | None, fit: tuple[str, ...], modes_path: Path | None,
                  plan: bool, poses: int, load_n: float, sigma_m: float, as_json: bool, out_dir: Path | None,
                  overwrite: bool) -> None:
    """Fit keys of MACHINE.toml to measured tool deflections (and frequencies): values, 95% intervals,
    correlations, residuals, chi-square; exit 2 on bad input or a fit that does not converge."""
    from pressfit.output import calibration_files as cf

    if plan:
        if measurements_path is not None:
            raise click.UsageError("--plan takes MACHINE.toml only (it proposes where to measure)")
        from pressfit.studies.measurement_plan import plan_from_file

        result = plan_from_file(machine_path, list(fit), poses, load_n, sigma_m)
        click.echo(to_json(result.to_dict()) if as_json else cf.plan_markdown(result))
        return
    if measurements_path is None:
        raise click.UsageError("give MEASUREMENTS.csv (or --plan)")
    from pressfit.studies.calibration import calibrate_files

    if out_dir is not None:
        check_directory(out_dir, overwrite)
        check_distinct({"--out": out_dir / cf.calibrated_name(machine_path)}, [machine_path, measurements_path])
    cal = calibrate_files(machine_path, measurements_path, list(fit), modes_path)
    click.echo(to_json(cf.to_dict(cal)) if as_json else cf.to_markdown(cal))
    for line in cf.warnings(cal) if as_json else ():
        click.echo(line, err=True)
    if out_dir is not None:
        inputs = [machine_path, measurements_path] + ([modes_path] if modes_path else [])
        echo_written(write_directory(out_dir, overwrite, lambda tmp: cf.write_calibration(cal, machine_path, tmp),
                                     inputs=inputs))
