"""`pressfit curve`: its files and summary, exit 2 with one line on bad input, no overwrite without --overwrite."""

from __future__ import annotations

import csv
import json

from click.testing import CliRunner

from pressfit.cli import main
from pressfit.shipped import cases_dir

CASE = cases_dir() / "paper" / "insertion_compliant_pin.toml"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_curve_writes_depth_sampled_rows_and_the_summary(tmp_path):
    """curve.csv: true and sensed depth, total and per-pin forces (4 pins), the total the pins' sum (to 1e-9 N);
    curve.json and --json: the summary keys the issue names; the sensed minus true depth at the peak is C_yy times
    the peak force (the same summary's numbers, 1e-9 relative)."""
    result = run("curve", CASE, "--out", tmp_path / "out", "--samples", "501")
    assert result.exit_code == 0, result.output
    with (tmp_path / "out" / "curve.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 501
    assert list(rows[0])[:4] == ["depth_m", "sensed_depth_m", "force_n", "pin_force_n1"]
    for row in rows[::50]:
        total = sum(float(row[f"pin_force_n{i}"]) for i in range(1, 5))
        assert abs(total - float(row["force_n"])) < 1e-9
    summary = json.loads((tmp_path / "out" / "curve.json").read_text())
    for key in ("peak_force_n", "plateau_force_n", "seated", "seating_depth_m", "sensed_minus_true_depth_at_peak_m",
                "machine_compliance_along_press_m_per_n", "tool_tilt_max_rad", "max_pin_depth_spread_m",
                "all_pins_seated", "series_residual_n"):
        assert key in summary
    assert summary["seated"] and summary["all_pins_seated"] and len(summary["pins"]) == 4
    printed = json.loads(run("curve", CASE, "--json", "--samples", "501").output)
    assert printed["peak_force_n"] == summary["peak_force_n"]
    again = run("curve", CASE, "--out", tmp_path / "out")
    assert again.exit_code == 2 and "--overwrite" in again.output


def test_curve_bad_input_exits_2_with_one_line(tmp_path):
    """A missing file, a case without [simulation], a foreign law key: exit 2, one `error:` line naming it."""
    bad = tmp_path / "bad.toml"
    bad.write_text(CASE.read_text().replace('law = "compliant_pin"', 'law = "compliant_pin"\npin_diameter_m = 1e-3'))
    for path, word in ((tmp_path / "missing.toml", "does not exist"), (cases_dir() / "paper" / "A.toml",
                                                                        "[simulation]"), (bad, "pin_diameter_m")):
        result = run("curve", path)
        assert result.exit_code == 2, result.output
        lines = result.output.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error:") and word in lines[0]
