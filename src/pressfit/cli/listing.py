"""``pressfit list``: the shipped machine and case files."""

from __future__ import annotations

import click

from pressfit.cli.common import user_errors
from pressfit.description.cases import Case
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
        click.echo(f"  {path.relative_to(cases_dir())}  {c.name} [{', '.join(case_kinds(c))}]: "
                   f"{' '.join(c.description.split())[:90]}")


def case_kinds(case: Case) -> list[str]:
    """What a case holds beyond its poses and loads, by table name ("loads" when nothing else): the reference
    table, the envelope limits, the studies (preload, Monte Carlo, design), the simulation, the cycle."""
    kinds = [k for k, v in (("reference table", case.reference),
                            ("envelope", case.envelope.model_dump(exclude_none=True)),
                            ("study", case.study), ("montecarlo", case.montecarlo), ("design", case.design),
                            ("simulation", case.simulation), ("cycle", case.cycle)) if v]
    return kinds or ["loads"]
