"""The ``pressfit`` command: thin; each command parses, calls the library, prints. Exit codes: 0 pass,
1 a checked limit is exceeded, 2 bad input (one line naming what is wrong)."""

from __future__ import annotations

import signal
import sys
import threading
from typing import Any

import click

from pressfit.cli import check, dynamics, listing, paper, pose, study, workspace
from pressfit.cli.common import close_progress_bars


class _Group(click.Group):
    """Usage errors become one line on stderr (exit 2); SIGTERM unwinds like Ctrl-C, so temporary
    files are removed (exit 130 or 143)."""

    def main(self, *args: Any, **kwargs: Any) -> Any:  # type: ignore[override]
        kwargs["standalone_mode"] = False
        main_thread = threading.current_thread() is threading.main_thread()
        previous = signal.signal(signal.SIGTERM, _terminate) if main_thread else None
        try:
            code = super().main(*args, **kwargs)
        except click.ClickException as exc:
            close_progress_bars()
            click.echo(f"error: {exc.format_message()}", err=True)
            sys.exit(exc.exit_code)
        except click.Abort:
            close_progress_bars()
            click.echo("error: interrupted", err=True)
            sys.exit(130)
        finally:
            if main_thread:
                signal.signal(signal.SIGTERM, previous)
        sys.exit(code if isinstance(code, int) else 0)


def _terminate(signum: int, frame: object) -> None:
    raise SystemExit(128 + signum)


@click.group(cls=_Group)
@click.version_option(package_name="pressfit")
def main() -> None:
    """Structural load and compliance analyzer for the 4-UPU press-fit manipulator (SI units)."""


for command in (pose.kinematics_cmd, listing.list_cmd, pose.solve_cmd, paper.tables_cmd, check.check_cmd,
                workspace.workspace_cmd, pose.stiffness_cmd, pose.interference_cmd, paper.report_cmd,
                study.study_group, dynamics.modes_cmd, dynamics.simulate_cmd,
                dynamics.export_mjcf_cmd, dynamics.response_cmd, dynamics.control_cmd):
    main.add_command(command)
