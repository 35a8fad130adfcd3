"""`pressfit study curve`: its files, no overwrite without --overwrite, exit 2 with one line naming the key on bad
input (an unknown tolerance, a case without [curve], --samples beyond the cap)."""

from __future__ import annotations

import csv
import json

from click.testing import CliRunner

from pressfit.cli import main
from pressfit.description.cases import MAX_CURVE_SAMPLES
from pressfit.shipped import cases_dir

CASE = cases_dir() / "paper" / "insertion_compliant_pin.toml"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_study_curve_writes_windows_band_and_figure(tmp_path):
    """windows.json holds the band (30 curves, its quantiles) and the elements; band.csv one row per grid point
    with a column per quantile; band.png a PNG; the --json summary says what the displacement is."""
    out = tmp_path / "out"
    result = run("study", "curve", CASE, "--samples", "30", "--serial", "--out", out, "--json")
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert summary["samples"] == 30 and summary["displacement"].startswith("sensed_depth_m")
    doc = json.loads((out / "windows.json").read_text())
    assert doc["band"]["samples"] == 30
    assert {e["name"] for e in doc["elements"]} >= {"max_force", "press_in", "envelope"}
    assert doc["source"]["samples"] == 30 and "hole_diameter_m" in doc["source"]["tolerances"]
    with (out / "band.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["displacement_m", "count"] + [f"force_q{q:g}_n" for q in doc["band"]["quantiles"]]
    assert len(rows) == len(doc["band"]["grid_m"])
    assert (out / "band.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_study_curve_refuses_an_existing_output_before_computing(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "windows.json").write_text("{}")
    result = run("study", "curve", CASE, "--samples", "5", "--serial", "--out", out)
    assert result.exit_code == 2 and result.output.startswith("error:"), result.output
    assert (out / "windows.json").read_text() == "{}"
    assert run("study", "curve", CASE, "--samples", "5", "--serial", "--out", out, "--overwrite").exit_code == 0


def test_an_unknown_tolerance_exits_2_naming_the_key_and_the_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(CASE.read_text().replace("pin_x_m = {", "board_thickness_m = { distribution = \"normal\", "
                                            "std = 1e-5 }\npin_x_m = {", 1))
    result = run("study", "curve", bad, "--samples", "5", "--serial", "--out", tmp_path / "out")
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:")
    assert "bad.toml" in lines[0] and "curve.tolerances.board_thickness_m" in lines[0]
    assert not (tmp_path / "out").exists()


def test_a_case_without_curve_and_too_many_samples_exit_2(tmp_path):
    plain = tmp_path / "plain.toml"
    plain.write_text(CASE.read_text().split("\n[curve]")[0] + "\n")
    result = run("study", "curve", plain, "--serial", "--out", tmp_path / "a")
    assert result.exit_code == 2 and "curve.tolerances" in result.output and "plain.toml" in result.output
    just_under = run("study", "curve", CASE, "--samples", MAX_CURVE_SAMPLES, "--serial", "--out", tmp_path / "x",
                     "--seed", "-1")  # the cap itself is accepted by --samples (the seed is what is refused here)
    assert just_under.exit_code == 2 and "--samples" not in just_under.output
    over = run("study", "curve", CASE, "--samples", MAX_CURVE_SAMPLES + 1, "--serial", "--out", tmp_path / "b")
    assert over.exit_code == 2 and "--samples" in over.output
