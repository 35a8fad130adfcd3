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


if __name__ == "__main__":
    main()
