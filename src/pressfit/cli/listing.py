"""``pressfit list``: the shipped machine and case files."""

from __future__ import annotations

import click

from pressfit.cli.common import user_errors
from pressfit.description.gantry import is_gantry_file, load_gantry
from pressfit.description.machine import load_machine, read_toml


@click.command("list")
@user_errors
def list_cmd() -> None:
    """The shipped machine descriptions (models/) and case files (cases/), with what each case holds."""
    from pressfit.description.cases import discover, load_case
    from pressfit.shipped import cases_dir, models_dir

    click.echo(f"models ({models_dir()}):")
    for path in sorted(models_dir().glob("*.toml")):
        m = load_gantry(path) if is_gantry_file(read_toml(path)) else load_machine(path)
        click.echo(f"  {path.name}  {m.name}: {m.description}")
    click.echo(f"cases ({cases_dir()}):")
    for path in discover([cases_dir()]):
        c = load_case(path)
        kinds = [
            k
            for k, v in (
                ("reference table", c.reference),
                ("envelope", c.envelope.model_dump(exclude_none=True)),
                ("study", getattr(c, "study", None)),
                ("cycle", c.cycle),
            )
            if v
        ]
        click.echo(f"  {path.relative_to(cases_dir())}  {c.name} [{', '.join(kinds) or 'loads'}]: "
                   f"{' '.join(c.description.split())[:90]}")
