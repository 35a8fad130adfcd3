"""``pressfit check``: load-envelope assertions of case files, for CI."""

from __future__ import annotations

import sys
from dataclasses import asdict
from pathlib import Path

import click

from pressfit.cli.common import user_errors
from pressfit.errors import PressfitError


@click.command("check")
@click.argument("paths", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--junit", "junit_path", type=click.Path(path_type=Path), help="Write JUnit XML here.")
@click.option("--json", "json_path", type=click.Path(path_type=Path), help="Write JSON results here.")
@click.option("--overwrite", is_flag=True, help="Replace existing result files.")
@click.option("--progress/--no-progress", default=True, help="Show progress bars.")
@user_errors
def check_cmd(paths: tuple[Path, ...], junit_path: Path | None, json_path: Path | None,
              overwrite: bool, progress: bool) -> None:
    """Check the load envelopes of case files (or directories of them): exit 0 pass, 1 a limit is exceeded,
    2 bad input (a malformed file is reported and the others are still checked)."""
    from pressfit.output import check_report
    from pressfit.output.files import check_distinct, check_target, write_json, write_text
    from pressfit.studies.limit_check import check_files

    check_distinct({"--junit": junit_path, "--json": json_path}, _input_files(paths))  # before any computation
    for target in (junit_path, json_path):
        if target is not None:
            check_target(target, overwrite)
    run = check_files(list(paths), progress=progress)
    click.echo(check_report.format_run(run))
    if junit_path:
        write_text(junit_path, check_report.junit_xml(run), overwrite)
    if json_path:
        write_json(json_path, {"exit_code": run.exit_code, "cases": [asdict(r) | {"passed": r.passed}
                                                                      for r in run.results],
                               "errors": [asdict(e) for e in run.errors], "skipped": run.skipped}, overwrite)
    if run.errors:
        first = " ".join(run.errors[0].message.split())
        more = f" ({len(run.errors) - 1} more listed above)" if len(run.errors) > 1 else ""
        click.echo(f"error: {first}{more}", err=True)
    sys.exit(run.exit_code)


def _input_files(paths: tuple[Path, ...]) -> list[Path]:
    """The files ``check`` reads: the case files named or found in the directories, and the machine file each
    names with ``model`` or the default one (an unreadable case is left to the check, which reports it)."""
    from pressfit.description.cases import discover
    from pressfit.description.machine import DEFAULT_MODEL, read_toml

    files = [Path(DEFAULT_MODEL)]
    for f in discover([p for p in paths if p.exists()]):
        files.append(f)
        try:
            model = read_toml(f).get("model")
        except PressfitError:
            continue
        if isinstance(model, str):
            files.append(f.parent / model)
    return files
