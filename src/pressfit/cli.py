"""The ``pressfit`` command: thin; parses, calls the library, prints. Exit 2 on bad input."""

from __future__ import annotations

import functools
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click
import numpy as np

from . import kinematics
from .errors import PressfitError
from .io import to_json
from .machine import DEFAULT_MODEL, load_machine

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


@main.command("kinematics")
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


@main.command("tables")
@click.option("--json", "as_json", is_flag=True, help="Print the entries as JSON.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), help="Write tables.md and tables.csv here.")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@user_errors
def tables_cmd(as_json: bool, out_dir: Path | None, overwrite: bool) -> None:
    """Reproduce the paper's Tables 5 and 6 (cases/paper/A, B, C) beside pressfit's solution."""
    from dataclasses import asdict

    from . import tables
    from .io import write_csv, write_text

    entries = tables.paper_tables()
    if as_json:
        click.echo(to_json([asdict(e) for e in entries]))
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

    from .cases import discover, load_case
    from .io import write_json, write_text

    files = discover(list(paths))
    cases = [load_case(f) for f in files]  # validate every file before computing anything
    for c in cases:
        c.machine()
    from . import envelope
    checked = [c for c in cases if c.envelope.model_dump(exclude_none=True)]
    if not checked:
        raise PressfitError("no case among " + ", ".join(map(str, paths)) + " has an [envelope] to check")
    results = [envelope.evaluate_case(c, progress=progress) for c in checked]
    click.echo(envelope.format_table(results))
    if junit_path:
        write_text(junit_path, envelope.junit_xml(results), overwrite)
    if json_path:
        write_json(json_path, [asdict(r) | {"passed": r.passed} for r in results], overwrite)
    failed = [r.case for r in results if not r.passed]
    click.echo(f"{len(results) - len(failed)} passed, {len(failed)} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
