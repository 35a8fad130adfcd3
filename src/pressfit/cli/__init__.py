"""The ``pressfit`` command: thin; each command parses, calls the library, prints. Exit codes: 0 pass,
1 a checked limit is exceeded, 2 bad input (one line naming what is wrong), 70 an internal error (a bug:
one line naming the exception; ``PRESSFIT_TRACEBACK=1`` prints its traceback too), 130 / 143 Ctrl-C /
SIGTERM."""

from __future__ import annotations

import os
import signal
import sys
import threading
import traceback
from typing import Any

import click

from pressfit.cli import calibrate, check, compare, curve, curves, dynamics, listing, paper, pose, study, workspace
from pressfit.cli.common import close_progress_bars

INTERNAL_ERROR_EXIT = 70  # EX_SOFTWARE of sysexits.h: never 1, which CI reads as "a limit is exceeded"
TRACEBACK_VARIABLE = "PRESSFIT_TRACEBACK"


class _Group(click.Group):
    """Usage errors become one line on stderr (exit 2); SIGTERM unwinds like Ctrl-C, so temporary
    files are removed (exit 130 or 143); any other exception is an internal error: one line naming it,
    exit 70 (its traceback too when the environment variable PRESSFIT_TRACEBACK is set to a non-empty
    value other than 0)."""

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
        except Exception as exc:  # a bug, not bad input: its own exit code, one line
            close_progress_bars()
            if os.environ.get(TRACEBACK_VARIABLE, "") not in ("", "0"):
                traceback.print_exc(file=sys.stderr)
            message = " ".join(str(exc).split())
            click.echo(f"internal error: {type(exc).__name__}: {message} (please report; run with "
                       f"{TRACEBACK_VARIABLE}=1 for the traceback)", err=True)
            sys.exit(INTERNAL_ERROR_EXIT)
        finally:
            if main_thread:
                signal.signal(signal.SIGTERM, previous)
        sys.exit(code if isinstance(code, int) else 0)


def _terminate(signum: int, frame: object) -> None:
    raise SystemExit(128 + signum)


@click.group(cls=_Group)
@click.version_option(package_name="pressfit")
def main() -> None:
    """Structural load, compliance and dynamics analyzer for parallel-kinematic press-fit machines (UPU machines of
    any leg count; the paper's 4-UPU by default) and their Cartesian gantry (SI units)."""


for command in (pose.kinematics_cmd, listing.list_cmd, pose.solve_cmd, paper.tables_cmd, check.check_cmd,
                workspace.workspace_cmd, pose.stiffness_cmd, pose.interference_cmd, paper.report_cmd,
                study.study_group, dynamics.modes_cmd, dynamics.simulate_cmd,
                dynamics.export_mjcf_cmd, dynamics.response_cmd, dynamics.control_cmd, dynamics.cycle_cmd,
                compare.compare_cmd, calibrate.calibrate_cmd, curve.curve_cmd, curves.curves_group):
    main.add_command(command)
