"""The ``pressfit`` command: thin; each command parses, calls the library, prints. Exit codes: 0 pass,
1 a checked limit is exceeded, 2 bad input (one line naming what is wrong)."""

from __future__ import annotations

import click

from pressfit.cli import check, dynamics, listing, paper, pose, study, workspace


@click.group()
@click.version_option(package_name="pressfit")
def main() -> None:
    """Structural load and compliance analyzer for the 4-UPU press-fit manipulator (SI units)."""


for command in (pose.kinematics_cmd, listing.list_cmd, pose.solve_cmd, paper.tables_cmd, check.check_cmd,
                workspace.workspace_cmd, pose.stiffness_cmd, pose.interference_cmd, paper.report_cmd,
                study.study_group, dynamics.modes_cmd, dynamics.simulate_cmd):
    main.add_command(command)
