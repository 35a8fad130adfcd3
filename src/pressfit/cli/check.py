"""``pressfit check``: load-envelope assertions of case files, for CI."""

from __future__ import annotations

import sys
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
    """Check the load envelopes of case files (or directories of them): exit 0 pass, 1 fail, 2 bad input."""
    from dataclasses import asdict

    from pressfit.description.cases import discover, load_case
    from pressfit.output.files import write_json, write_text

    files = discover(list(paths))
    cases = [load_case(f) for f in files]  # validate every file before computing anything
    for c in cases:
        c.machine()
    from pressfit.output import check_report
    from pressfit.studies import limit_check as envelope
    checked = [c for c in cases if c.envelope.model_dump(exclude_none=True)]
    if not checked:
        raise PressfitError("no case among " + ", ".join(map(str, paths)) + " has an [envelope] to check")
    skipped = [c.path for c in cases if c not in checked]
    if skipped:
        click.echo(f"skipped (no [envelope]): {', '.join(skipped)}")
    results = [envelope.evaluate_case(c, progress=progress) for c in checked]
    click.echo(check_report.format_table(results))
    if junit_path:
        write_text(junit_path, check_report.junit_xml(results), overwrite)
    if json_path:
        write_json(json_path, [asdict(r) | {"passed": r.passed} for r in results], overwrite)
    failed = [r.case for r in results if not r.passed]
    click.echo(f"{len(results) - len(failed)} passed, {len(failed)} failed")
    sys.exit(1 if failed else 0)
