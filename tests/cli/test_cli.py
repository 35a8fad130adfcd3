"""The CLI end to end: solve (pose and case-file forms), tables, report. Numbers are checked in the
module tests; here the documented JSON structure, exit codes and files."""

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from pressfit.cli import main

ROOT = Path(__file__).resolve().parents[2]
SECTION_KEYS = {"N", "V_x", "V_y", "M_x", "M_y", "T"}


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_solve_json_structure_as_documented():
    res = run("solve", 0.1, 0.6, -0.1, "--load", 0, 700, 0, "--json")
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert len(out["legs"]) == 4 and out["linear"] is False
    for leg in out["legs"]:
        assert set(leg["sections"]) == {"base", "actuator", "plate"}
        assert all(set(s) == SECTION_KEYS for s in leg["sections"].values())
    assert set(out["plate"]) == {"displacement_m", "rotation_rad"} and "residuals" in out
    # the documented validity criterion: every relative residual <= 1e-9
    r = out["residuals"]
    assert max(r[k] for k in ("plate_force", "plate_moment", "machine_force", "machine_moment",
                              "closure_rad", "stationarity")) <= 1e-9


def test_solve_case_file_pose_A_closed_form():
    res = run("solve", ROOT / "cases/paper/A.toml", "--json")
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["linear"] is True  # the case asks for the paper's rigid comparison
    for leg in out["legs"]:  # 700 / (4 sin(atan 2)), tension positive
        assert leg["sections"]["actuator"]["N"] == pytest.approx(700 / (4 * math.sin(math.atan(2))), rel=1e-9)


def test_solve_bad_input_exit_2():
    assert run("solve", 0.9, 0.6, 0, "--load", 0, 700, 0).exit_code == 2
    assert run("solve", "abc", "--load").exit_code == 2
    assert run("solve", ROOT / "nope.toml").exit_code == 2


def test_tables_json_and_files(tmp_path):
    res = run("tables", "--json", "--out", tmp_path)
    assert res.exit_code == 0, res.output
    entries = json.loads(res.output)
    assert {e["case"] for e in entries} == {"paper-A", "paper-B", "paper-C"}
    assert (tmp_path / "tables.md").exists() and (tmp_path / "tables.csv").exists()
    assert run("tables", "--out", tmp_path).exit_code == 2  # no silent overwrite


def test_list_shows_models_and_every_shipped_case():
    res = run("list")
    assert res.exit_code == 0, res.output
    for name in ("pressfit_4upu.toml", "paper/A.toml", "paper/B.toml", "paper/C.toml", "press_workspace.toml"):
        assert name in res.output


def test_unreadable_inputs_and_outputs_exit_2(tmp_path):
    (tmp_path / "bin.toml").write_bytes(b"\xff\xfe\x00name")
    assert run("check", tmp_path / "bin.toml").exit_code == 2
    assert run("kinematics", 0, 0.6, 0, "--model", tmp_path).exit_code == 2
    (tmp_path / "afile").write_text("x")
    res = run("tables", "--out", tmp_path / "afile")
    assert res.exit_code == 2 and "cannot write" in res.output
    assert run("workspace", "--y", "2", "--out", tmp_path / "ws").exit_code == 2


@pytest.mark.slow
def test_tables_cad_fit_json():
    """`tables --cad-fit --json`: the identified CAD model as JSON (values are tested in test_cad_fit.py)."""
    res = run("tables", "--cad-fit", "--json")
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    assert {"parameters", "entries", "identifiability", "c_split"} <= set(data)
    assert len(data["entries"]) == 36
