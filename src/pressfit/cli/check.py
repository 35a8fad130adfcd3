"""``pressfit check``: load-envelope assertions of case files, for CI."""

from __future__ import annotations

import sys
from dataclasses import asdict
from pathlib import Path

import click

from pressfit.cli.common import user_errors


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
    from pressfit.output.files import check_target, write_json, write_text
    from pressfit.studies.limit_check import check_files

    for target in (junit_path, json_path):  # before any computation
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
