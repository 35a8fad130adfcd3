"""The n-leg layers from the command line (issue 21): ``pressfit modes``, ``interference``, ``solve`` and
``study preload`` with ``--model models/tsai_3upu.toml`` exit 0 and report three legs (names leg1..leg3, no
leg 4). The numbers behind them are tested in tests/dynamics/test_n_leg_modes.py, tests/geometry/test_interference.py,
tests/mechanics/test_n_leg_mechanics.py and tests/studies/test_n_leg_studies.py; here the closed form
F / (3 sin(alpha)) of the centred press load checks the printed actuator forces (tests/n_legs.py)."""

import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from n_legs import centred

from pressfit.cli import main

TSAI = str(Path(__file__).resolve().parents[2] / "models" / "tsai_3upu.toml")
POSE = ["0", "0.6", "0"]


def run(*args: str):
    res = CliRunner().invoke(main, [*args])
    assert res.exit_code == 0, res.output
    return res.output


def test_modes():
    out = run("modes", "--model", TSAI, *POSE, "--count", "3")
    assert out.startswith("tsai-3upu, 3 legs:")
    data = json.loads(run("modes", "--model", TSAI, *POSE, "--count", "3", "--json"))
    assert data["legs"] == 3 and data["frequencies_hz"][1] == pytest.approx(data["frequencies_hz"][0], rel=1e-6)


def test_interference():
    data = json.loads(run("interference", "--model", TSAI, *POSE, "--json"))
    legs = {b.split(".")[0] for p in data["pairs"] for b in p["pair"].split("|") if b.startswith("leg")}
    assert legs == {"leg1", "leg2", "leg3"} and data["passed"]


def test_solve(tsai):
    out = run("solve", "--model", TSAI, *POSE, "--load", "0", "700", "0")
    forces = [float(f) for f in out.split("actuator forces [N]:")[1].splitlines()[0].split(",")]
    sa, _ = centred(tsai, 0.6)
    assert forces == pytest.approx([700.0 / (3 * sa)] * 3, rel=1e-4)  # nonlinear solve, 4-decimal print


def test_study_preload(tmp_path):
    out = run("study", "preload", "--model", TSAI, "--pose", *POSE, "--preload", "0", "--out", str(tmp_path / "s"),
              "--no-progress")
    assert "no redundant actuation" in out and "lost motion 46.6 um" in out
    bad = CliRunner().invoke(main, ["study", "preload", "--model", TSAI, "--pose", *POSE, "--preload", "100",
                                    "--out", str(tmp_path / "t"), "--no-progress"])
    assert bad.exit_code == 2 and "no redundant actuation" in bad.output and len(bad.output.splitlines()) == 1


def _tsai_insertion(tmp_path, preload: str) -> str:
    text = (Path(__file__).resolve().parents[2] / "cases" / "paper" / "insertion.toml").read_text()
    path = tmp_path / "tsai_insertion.toml"
    path.write_text(f'model = "{TSAI}"\n' + text.replace("a4_n = 100.0", preload))
    return str(path)


@pytest.mark.slow
def test_simulate(tmp_path):
    """`pressfit simulate` on the 3-UPU: exit 0, the series' per-leg columns 1..3 (no leg 4, no internal force
    column), the printed line names no preload; with a preload the case is refused up front (exit 2, one line)."""
    out = run("simulate", _tsai_insertion(tmp_path, "a4_n = 0.0"), "--out", str(tmp_path / "s"), "--no-progress")
    assert "commanded none: no preload space" in out
    header = (tmp_path / "s" / "simulation.csv").read_text().splitlines()[0].split(",")
    assert "act_n3" in header and "act_n4" not in header and not [c for c in header if c.startswith("internal")]
    bad = CliRunner().invoke(main, ["simulate", _tsai_insertion(tmp_path, "a4_n = 50.0"), "--no-progress"])
    assert bad.exit_code == 2 and "no redundant actuation" in bad.output and len(bad.output.splitlines()) == 1
