"""``pressfit study insertion`` (issue 11 item 8): joint play becomes a tool error the length-based estimate
cannot see, and a preload above the critical one removes it (paper section 4.1's claim, in time domain)."""

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner
from readme import assert_printed, readme_fragment

from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.mechanics.clearance import Clearance, load_deflection
from pressfit.studies.insertion_study import insertion_study

ROOT = Path(__file__).resolve().parents[1]
GAP = 2e-5


def short_case(tmp_path: Path) -> Path:
    data = tomllib.loads((ROOT / "cases/paper/insertion.toml").read_text())
    data["simulation"].update({"move_time_s": 0.4, "descent_time_s": 0.5, "dwell_s": 1.0, "settle_s": 0.0})
    path = tmp_path / "insertion.toml"
    path.write_text(tomli_w.dumps(data))
    return path


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    return insertion_study(load_case(short_case(tmp_path_factory.mktemp("istudy"))), [0.0, 60.0], [GAP])


def test_play_shows_as_hidden_tool_error_without_preload(machine, study):
    """Without preload the tool sits off the length-based estimate by the lost motion of the cardans' play
    (the plate's free travel before the joints engage under an upward load): the reference is the
    small-displacement clearance model's lost motion at the insertion pose (mechanics.clearance, checked
    against 2g / sin(alpha) at pose A in test_clearance). Within 3% (achieved 1%: the clearance curve is
    interpolated over 41 load steps and the difference of the two runs also holds the integrator's residual)."""
    row = study.rows[0]
    assert row[0] == 0.0 and row[1] == GAP
    ld = load_deflection(machine, study.pose_m, [0.0, 1.0, 0.0], np.linspace(0.0, 30.0, 31),
                         Clearance.uniform(machine, GAP), 0.0, unload=False)
    assert study.column("play_error_m")[0] == pytest.approx(ld.lost_motion_m, rel=0.03)


def test_preload_above_critical_removes_the_play(study):
    """With a4 = 60 N above the critical preload (every cardan closed up to the peak contact force, ~23 N
    here) the tool error is the elastic one of g = 0: the play's share is below 1e-8 m (the dead zone's
    smoothing width is 1e-9 m; achieved 1e-11 m), against ~46 um without preload."""
    critical = study.column("critical_preload_n")[1]
    assert 0.0 < critical < 60.0
    assert study.column("play_error_m")[1] < 1e-8
    assert study.column("play_error_m")[0] > 1e3 * 1e-8


def test_study_cli_files_and_json(tmp_path):
    out = tmp_path / "o"
    args = ["study", "insertion", str(short_case(tmp_path)), "--preload", "0", "--clearance", "1e-5", "--out",
            str(out), "--json", "--no-progress"]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    assert len(data["rows"]) == 1 and data["columns"][4] == "play_error_m"
    assert {p.name for p in out.iterdir()} == {"insertion_study.csv", "insertion_study.json", "insertion_study.png"}
    again = CliRunner().invoke(main, args)
    assert again.exit_code == 2 and "error:" in again.output


def test_readme_numbers_of_the_preload_against_play(machine, study):
    """The README's "Preload against play" numbers (tests/readme.py), from this module's study: the shipped
    scenario with shorter moves and dwell, i.e. the same insertion pose, contact, gains and 30 N limit (the lost
    motion depends on the pose and the gap only, the critical preload on the peak contact force, 30.4 N here)."""
    readme_fragment("At g = 20 um and no preload the play hides 46 um of tool error (the clearance model's lost "
                    "motion at the insertion pose); any preload above the critical one (23 N at the 30 N limit) "
                    "removes it (below 1e-10 m).")
    assert GAP == 20e-6 and study.column("preload_n").tolist() == [0.0, 60.0]
    assert_printed(study.column("play_error_m")[0] * 1e6, "46")
    ld = load_deflection(machine, study.pose_m, [0.0, 1.0, 0.0], np.linspace(0.0, 30.0, 31),
                         Clearance.uniform(machine, GAP), 0.0, unload=False)
    assert_printed(ld.lost_motion_m * 1e6, "46")
    assert_printed(study.column("critical_preload_n")[1], "23")
    assert study.column("play_error_m")[1] < 1e-10
