"""``pressfit list`` (pressfit.cli.listing): every shipped case labelled by the tables it holds."""

from __future__ import annotations

import re

from click.testing import CliRunner

from pressfit.cli import main


def test_list_labels_simulation_and_cycle_cases_by_their_tables():
    """issue 28 item 9: insertion.toml holds [simulation] (it read [loads]), board.toml [envelope] and [cycle],
    the Monte Carlo and design studies their tables, the paper's cases their reference table."""
    res = CliRunner().invoke(main, ["list"])
    assert res.exit_code == 0, res.output
    labels = dict(re.findall(r"^  (\S+\.toml)  \S+ \[([^]]*)\]", res.output, flags=re.M))
    assert labels["paper/insertion.toml"] == "simulation"
    assert labels["paper/insertion_fast.toml"] == "simulation"
    assert labels["paper/insertion_electric.toml"] == "envelope, simulation"
    assert labels["paper/board.toml"] == "envelope, cycle"
    assert labels["studies/montecarlo_tolerances.toml"] == "envelope, montecarlo"
    assert labels["studies/design_sections.toml"] == "design"
    assert labels["paper/A.toml"] == "reference table"


def test_the_top_level_help_is_generic():
    """issue 28 item 9: `pressfit --help` speaks of parallel-kinematic press-fit machines, not only the 4-UPU."""
    out = " ".join(CliRunner().invoke(main, ["--help"]).output.split())
    assert "parallel-kinematic press-fit machines" in out
    assert "analyzer for the 4-UPU" not in out
