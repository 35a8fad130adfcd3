"""``pressfit curve``: the predicted press curve of a case's joint (quasi-static)."""

from __future__ import annotations

from pathlib import Path

import click

from pressfit.cli.common import OVERWRITE_OPTION, echo_written, user_errors
from pressfit.output.files import to_json


@click.command("curve")
@click.argument("case_path", type=click.Path(path_type=Path))
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=None,
              help="Directory for curve.csv and curve.json (nothing written without it).")
@click.option("--samples", type=click.IntRange(2, 1_000_000), default=None,
              help="Depth samples of the curve (default 2001).")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@user_errors
def curve_cmd(case_path: Path, out_dir: Path | None, samples: int | None, overwrite: bool, as_json: bool) -> None:
    """The press curve a monitor would record for the case's [simulation.contact] (its pins' laws in series with
    the machine's 6x6 compliance at the pin pose, the tool's tilt included; no time stepping), SI units."""
    from pressfit.workflows.press_curve import run_curve

    s, paths = run_curve(case_path, out_dir, overwrite, samples)
    if as_json:
        click.echo(to_json(s))
        return
    plateau = "none" if s["plateau_force_n"] is None else f"{s['plateau_force_n']:.2f} N"
    seat = "not seated" if not s["seated"] else f"seated at {s['seating_depth_m'] * 1e3:.4f} mm"
    click.echo(f"{s['case']}: {len(s['pins'])} pin(s) at pose ({', '.join(f'{x:g}' for x in s['pose_m'])}) m; "
               f"peak {s['peak_force_n']:.2f} N, plateau {plateau}, {seat}, "
               f"final {s['final_force_n']:.2f} N at {s['max_depth_m'] * 1e3:.4f} mm")
    click.echo(f"machine compliance along the press {s['machine_compliance_along_press_m_per_n']:.4g} m/N: sensed "
               f"minus true depth at the peak {s['sensed_minus_true_depth_at_peak_m'] * 1e6:.2f} um; tool tilt up to "
               f"{s['tool_tilt_max_rad'] * 1e3:.4f} mrad, pin depths spread up to "
               f"{s['max_pin_depth_spread_m'] * 1e6:.2f} um; series residual {s['series_residual_n']:.1e} N")
    for k, p in enumerate(s["pins"]):
        click.echo(f"  pin {k + 1} at ({p['offset_m'][0]:+g}, {p['offset_m'][1]:+g}) m: "
                   f"peak {p['peak_force_n']:.2f} N, final depth {p['final_depth_m'] * 1e3:.4f} mm, "
                   + ("seated" if p["seated"] else "not seated"))
    for note in s["notes"]:
        click.echo(f"note: {note}")
    echo_written(paths)
