"""The paper's results: ``pressfit tables`` and the full ``pressfit report``."""

from __future__ import annotations

from pathlib import Path

import click

from pressfit.cli.common import MODEL_OPTION, OVERWRITE_OPTION, user_errors
from pressfit.description.machine import load_machine
from pressfit.output.files import to_json


@click.command("tables")
@click.option("--json", "as_json", is_flag=True, help="Print the entries as JSON.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), help="Write tables.md and tables.csv here.")
@OVERWRITE_OPTION
@click.option("--cad-fit", "cad", is_flag=True,
              help="Instead: identify the paper's CAD model from the tables (least squares; a hypothesis).")
@user_errors
def tables_cmd(as_json: bool, out_dir: Path | None, overwrite: bool, cad: bool) -> None:
    """Reproduce the paper's Tables 5 and 6 (cases/paper/A, B, C) beside pressfit's solution."""
    from pressfit.output.files import check_directory, write_csv, write_directory, write_json, write_text
    from pressfit.studies import cad_fit
    from pressfit.studies import paper_tables as tables

    if out_dir is not None:
        check_directory(out_dir, overwrite)
    if cad:
        fit = cad_fit.fit_cad_model()
        click.echo(to_json(cad_fit.to_dict(fit)) if as_json else cad_fit.to_markdown(fit))
        if out_dir is not None:
            write_directory(out_dir, overwrite, lambda tmp: [write_text(tmp / "cad_fit.md", cad_fit.to_markdown(fit)),
                                                             write_json(tmp / "cad_fit.json", cad_fit.to_dict(fit))])
        return
    entries = tables.paper_tables()
    if as_json:
        click.echo(to_json([e.as_dict() for e in entries]))
    else:
        click.echo(tables.to_markdown(entries))
    if out_dir is not None:
        write_directory(out_dir, overwrite, lambda tmp: [write_text(tmp / "tables.md", tables.to_markdown(entries)),
                                                         write_csv(tmp / "tables.csv", *tables.to_rows(entries))])


@click.command("report")
@click.option("--out", "out_dir", type=click.Path(path_type=Path), default=Path("report"), show_default=True,
              help="Output directory.")
@OVERWRITE_OPTION
@click.option("--quick", is_flag=True,
              help="A preview: coarse grids, no static PNG maps (report.html has them, interactive).")
@click.option("--full", is_flag=True,
              help="Full resolution: the insertion and the board cycle at the cases' own 1 ms step (default: 2 ms).")
@click.option("--cycle-study", "cycle_study", type=click.Path(path_type=Path, exists=True, file_okay=False),
              help="The --out directory of a `pressfit study cycle` run: its Pareto front in the board's section.")
@click.option("--calibration", "calibration", type=click.Path(path_type=Path, exists=True, file_okay=False),
              help="The --out directory of a `pressfit calibrate` run: its values, intervals and residuals.")
@MODEL_OPTION
@user_errors
def report_cmd(out_dir: Path, overwrite: bool, quick: bool, full: bool, cycle_study: Path | None,
               calibration: Path | None, model_path: Path) -> None:
    """Reproduce Tables 5 and 6 and write the full report (maps, envelope, stiffness, ...) as report.md and .html."""
    from pressfit.output.files import check_directory, write_directory
    from pressfit.workflows.report import write_report

    check_directory(out_dir, overwrite)
    machine = load_machine(model_path)
    path, = write_directory(out_dir, overwrite, lambda tmp: [write_report(machine, tmp, quick=quick, full=full,
                                                                                 cycle_study=cycle_study,
                                                                                 calibration=calibration)])
    click.echo((path.parent / "tables.md").read_text())  # the Tables 5-6 comparison the report just wrote
    click.echo(f"report written to {path} and {path.with_suffix('.html')}")
