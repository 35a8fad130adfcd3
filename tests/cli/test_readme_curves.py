"""The README's press-curve section is what the commands print (drift protection), and its numbers hold against
their independent sources: the sensed-minus-true depth is the Pinocchio VJM model's compliance along the press
(a second formulation of the condensed one the curve uses) times the peak force, to 0.3% (the pin field's moments
add the coupling terms: 0.1% here); the judged curves' verdicts are the ones their construction gives
(docs/examples/curves/generate.py: an oversized hole's plateau below the window, a good part inside every
element)."""

import re
import shlex
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from readme import README

from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.mechanics.compliance import vjm_plate_compliance

ROOT = Path(__file__).resolve().parents[2]


def _example(command: str) -> tuple[list[str], str]:
    """The README's ``$ pressfit ...`` command and the lines printed after it, up to the next blank line."""
    text = (ROOT / "README.md").read_text()
    block = text.split(f"$ pressfit {command}", 1)[1].split("```", 1)[0]
    first, *lines = block.strip("\n").splitlines()
    return shlex.split(command + first), lines


def test_the_readme_curve_is_what_pressfit_curve_prints_and_its_deflection_the_compliance_times_the_force():
    args, lines = _example("curve ")
    run = CliRunner().invoke(main, args)
    assert run.exit_code == 0, run.output
    assert run.output.splitlines()[:2] == lines
    case = load_case(ROOT / args[1])
    pose = [case.simulation.contact.pin_position_m[0], case.simulation.contact.board_height_m,
            case.simulation.contact.pin_position_m[1]]
    peak = float(re.search(r"peak ([\d.]+) N", lines[0]).group(1))
    c_yy = vjm_plate_compliance(case.machine(), np.array(pose))[1, 1]
    printed = float(re.search(r"at the peak ([\d.]+) um", lines[1]).group(1))
    assert printed == pytest.approx(1e6 * c_yy * peak, rel=3e-3)  # the pins' moments tilt the tool: 0.1% here
    assert "sensed minus true depth at the peak 18.09 um" in README
    final = float(re.search(r"final ([\d.]+) N", lines[0]).group(1))  # the press stops at the case's force limit
    assert final == pytest.approx(case.simulation.controller.force_limit_n, abs=5e-3)


def test_the_readme_judged_curves_are_what_curves_check_prints():
    args, lines = _example("curves check ")
    run = CliRunner().invoke(main, args)
    assert run.exit_code == 1, run.output  # one NOK: exit 1
    assert run.output.splitlines() == lines
    assert lines[0].startswith("NOK") and "element 'press_in'" in lines[0] and "passes below" in lines[0]
    assert lines[1].startswith("OK ")
