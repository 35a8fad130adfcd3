"""``pressfit curves ...``: measured press-fit curves judged against a monitor's windows (docs/monitor.md)."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from pressfit.cli.common import OVERWRITE_OPTION, user_errors

UNIT_CHOICES = {"time": ("s", "ms"), "displacement": ("m", "mm", "um"), "force": ("N", "kN")}


def _finite(param: click.Parameter, value: float | None) -> float | None:
    if value is not None and value != value:  # NaN passes FloatRange's comparisons
        raise click.BadParameter("must be a finite length in m", param=param)
    return value


@click.group("curves")
def curves_group() -> None:
    """Measured force-displacement curves of a press monitor."""


@curves_group.command("check")
@click.argument("paths", metavar="MEASURED.csv...", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--windows", "windows_path", required=True, type=click.Path(path_type=Path),
              help="The evaluation objects (windows.json, docs/monitor.md).")
@click.option("--case", "case_path", type=click.Path(path_type=Path),
              help="The case of the insertion (its pin pose gives the press compliance for --compensate).")
@click.option("--compensate", is_flag=True, help="Remove the press's own deflection from the displacement: "
              "displacement - compliance x force, the compliance along the press direction at the case's pin pose.")
@click.option("--junit", "junit_path", type=click.Path(path_type=Path), help="Write JUnit XML here (one test case "
              "per curve).")
@click.option("--json", "json_path", type=click.Path(path_type=Path), help="Write the verdicts as JSON here.")
@click.option("--png", "png_path", type=click.Path(path_type=Path), help="Write a figure of the curves over the "
              "band and the evaluation objects here.")
@click.option("--time-unit", type=click.Choice(UNIT_CHOICES["time"], case_sensitive=False),
              help="Unit of a time column whose header names none.")
@click.option("--displacement-unit", type=click.Choice(UNIT_CHOICES["displacement"], case_sensitive=False),
              help="Unit of a displacement column whose header names none.")
@click.option("--force-unit", type=click.Choice(UNIT_CHOICES["force"], case_sensitive=False),
              help="Unit of a force column whose header names none.")
@click.option("--displacement-column", help="The displacement column's name (where the header is ambiguous).")
@click.option("--force-column", help="The force column's name (where the header is ambiguous).")
@click.option("--reversal-tolerance-m", type=click.FloatRange(min=0.0, max=1e-3), default=None,
              callback=lambda ctx, param, v: _finite(param, v),
              help="How far (m) the displacement may step back before its maximum and still be one forward stroke "
                   "(default 1e-6: encoder jitter; a force limiter backing the tool off needs more).")
@OVERWRITE_OPTION
@user_errors
def check_cmd(paths: tuple[Path, ...], windows_path: Path, case_path: Path | None, compensate: bool,
              junit_path: Path | None, json_path: Path | None, png_path: Path | None, time_unit: str | None,
              displacement_unit: str | None, force_unit: str | None, displacement_column: str | None,
              force_column: str | None, reversal_tolerance_m: float | None, overwrite: bool) -> None:
    """Judge each measured curve against the windows: one OK or NOK line per curve, naming the element that
    failed and where (x, y). Exit 0 all OK, 1 any NOK, 2 bad input (the file, row and column named)."""
    from pressfit.description.cases import load_case
    from pressfit.description.measured_curves import read_curve
    from pressfit.description.monitor_windows import load_windows
    from pressfit.output import curve_files
    from pressfit.output.files import check_distinct, check_target
    from pressfit.studies.curve_check import judge_curves, judged_strokes, press_compliance_m_per_n

    if compensate and case_path is None:
        raise click.UsageError("--compensate needs --case CASE (the pin pose whose press compliance is removed)")
    outputs = {"--junit": junit_path, "--json": json_path, "--png": png_path}
    check_distinct(outputs, [*paths, windows_path, *([case_path] if case_path else [])])
    for target in outputs.values():
        if target is not None:
            check_target(target, overwrite)
    windows = load_windows(windows_path)
    units = {k: v for k, v in (("time", time_unit), ("displacement", displacement_unit), ("force", force_unit)) if v}
    columns = {k: v for k, v in (("displacement", displacement_column), ("force", force_column)) if v}
    tolerance = {} if reversal_tolerance_m is None else {"reversal_tolerance_m": reversal_tolerance_m}
    curves = [read_curve(p, units=units, columns=columns, **tolerance) for p in paths]
    case = load_case(case_path) if case_path is not None else None
    compliance = press_compliance_m_per_n(case) if compensate and case is not None else None
    verdicts = judge_curves(curves, windows, compliance)
    if compliance is not None:
        click.echo(f"compensated: displacement - {compliance:.6g} m/N x force (press compliance at the pin of "
                   f"{case_path})")
    for v in verdicts:
        click.echo(curve_files.verdict_line(v))
    nok = sum(not v.passed for v in verdicts)
    click.echo(f"{len(verdicts) - nok} OK, {nok} NOK of {len(verdicts)} curves")
    strokes = judged_strokes(curves, verdicts)
    for p in curve_files.write_check_outputs(verdicts, strokes, windows, str(windows_path), json_path=json_path,
                                             junit_path=junit_path, png_path=png_path, overwrite=overwrite):
        click.echo(f"wrote {p}")
    sys.exit(1 if nok else 0)
