"""``pressfit compare``: machines measured the same way, and the paper's two claims."""

from __future__ import annotations

import math
from pathlib import Path

import click

from pressfit.cli.common import OVERWRITE_OPTION, echo_written, user_errors
from pressfit.errors import PressfitError
from pressfit.output.files import to_json

ROWS = (("worst drive force [N]", "worst_drive_force_n", 1.0, ".4g"),
        ("worst member bending [N m]", "worst_bending_nm", 1.0, ".4g"),
        ("weakest tool stiffness, worst / median [N/um]", ("weakest_stiffness_worst_n_per_m",
                                                           "weakest_stiffness_median_n_per_m"), 1e-6, ".4g"),
        ("vertical tool stiffness, worst / median [N/um]", ("vertical_stiffness_worst_n_per_m",
                                                            "vertical_stiffness_median_n_per_m"), 1e-6, ".4g"),
        ("tool tilt under the press load, worst / median [mrad]", ("tilt_worst_rad", "tilt_median_rad"), 1e3, ".3g"),
        ("first natural frequency, lowest / median [Hz]", ("first_frequency_lowest_hz", "first_frequency_median_hz"),
         1.0, ".4g"),
        ("moving mass [kg]", "moving_mass_kg", 1.0, ".4g"),
        ("lost motion, 20 um play, worst: no preload / critical preload [um]",
         ("lost_motion_m", "lost_motion_preloaded_m"), 1e6, ".3g"),
        ("critical preload, worst pose [N]", "critical_preload_worst_n", 1.0, ".4g"),
        ("drive force with it, worst [N]", "preloaded_drive_force_n", 1.0, ".4g"))


def _cell(figures: dict, keys: str | tuple[str, str], scale: float, fmt: str) -> str:
    def one(v: object) -> str:
        if v is None or not math.isfinite(float(v)):
            return "-"
        return format((max(float(v), 0.0) if "lost" in str(keys) else float(v)) * scale, fmt)  # lost: round-off < 0
    return " / ".join(one(figures[k]) for k in (keys if isinstance(keys, tuple) else (keys,)))


@click.command("compare")
@click.argument("machine_files", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print the comparison as JSON.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=None,
              help="Directory for compare.json, compare.csv and compare.png.")
@OVERWRITE_OPTION
@click.option("--progress/--no-progress", default=True, help="Show a progress bar over the machines.")
@user_errors
def compare_cmd(machine_files: tuple[Path, ...], as_json: bool, out_dir: Path | None, overwrite: bool,
                progress: bool) -> None:
    """Machine files (UPU machines of any leg count) measured the same way over the required workspace under the
    700 N press load and its 5 degree cone: worst drive force, worst member bending, tool stiffness and tilt, first
    natural frequency, moving mass, lost motion with 20 um of cardan play without and with each pose's critical
    preload and the drive forces with it; and the paper's claims (against the gantry, against the 3-UPU) decided pose
    by pose over the box (confirmed, holds on X% of the box, refuted; SI units)."""
    from pressfit.workflows.machine_comparison import run_compare

    if len(set(machine_files)) != len(machine_files):
        raise PressfitError("the same machine file is given twice")
    result, written = run_compare(list(machine_files), out_dir, overwrite, progress)
    if as_json:
        click.echo(to_json(result.to_dict() | {"outputs": [str(p) for p in written]}))
        return
    figures = [m.to_dict() for m in result.machines]
    width = max(len(r[0]) for r in ROWS)
    click.echo(" " * width + "".join(f"  {f['name']:>26}" for f in figures))
    for label, keys, scale, fmt in ROWS:
        click.echo(f"{label:<{width}}" + "".join(f"  {_cell(f, keys, scale, fmt):>26}" for f in figures))
    for c in result.claims:
        click.echo(f"claim: {c.claim}\n  against {c.baseline}: {c.verdict.upper()}: {c.evidence}")
    echo_written(written)
