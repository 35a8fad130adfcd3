"""``pressfit workspace``: reachable heights and kinematic maps (Figures 6-11)."""

from __future__ import annotations

from pathlib import Path

import click

from pressfit.cli.common import COORDINATE, MODEL_OPTION, OVERWRITE_OPTION, PROGRESS_OPTION, user_errors
from pressfit.description.machine import load_machine
from pressfit.errors import PressfitError
from pressfit.output.files import check_directory, to_json, write_directory


@click.command("workspace")
@click.option("--y", "heights", type=COORDINATE, multiple=True, help="Plate height y_h of a map, m (repeatable; "
              "default 0.6, the paper's Figures 7-11).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("out/workspace"),
              show_default=True, help="Directory for the maps (CSV, PNG) and summary.json.")
@OVERWRITE_OPTION
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@PROGRESS_OPTION
@MODEL_OPTION
@user_errors
def workspace_cmd(heights: tuple[float, ...], out_dir: Path, overwrite: bool, as_json: bool, progress: bool,
                  model_path: Path) -> None:
    """Reachable heights of the required square (0, 45, 90 deg), maps of n, F and dl/dh, statistics."""
    from pressfit.kinematics import workspace
    from pressfit.workflows.kinematic_maps import write_kinematic_maps

    check_directory(out_dir, overwrite)
    machine = load_machine(model_path)
    rng = workspace.square_height_range(machine)
    for y in heights:
        if not (rng.y_min_m <= y <= rng.y_max_m):
            raise PressfitError(f"--y {y:g}: the required square is reachable only for y_h in "
                                f"[{rng.y_min_m:.5f}, {rng.y_max_m:.5f}] m")
    box: dict[str, dict] = {}

    def write(tmp: Path) -> list[Path]:
        box["summary"], paths, _ = write_kinematic_maps(machine, tmp, heights or workspace.DEFAULT_HEIGHTS_M,
                                                        progress=progress)
        return paths

    write_directory(out_dir, overwrite, write)
    summary = box["summary"]
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
