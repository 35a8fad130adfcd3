"""``pressfit curves check``: the shipped examples (docs/examples/curves, made by its generate.py from closed-form
pin curves whose verdicts are known by construction), exit codes 0 / 1 / 2, the JUnit file parsed with
xml.etree, JSON, no overwrite without --overwrite, and --compensate moving a curve across a window's edge by
exactly compliance x force."""

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from click.testing import CliRunner

from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.studies.curve_check import press_compliance_m_per_n

ROOT = Path(__file__).resolve().parents[2]
EX = ROOT / "docs/examples/curves"
WINDOWS = str(EX / "windows.json")
CASE = str(ROOT / "cases/paper/insertion.toml")
EXPECTED = {"ok_part.csv": None, "ok_protocol.csv": None, "nok_missing_pin.csv": "press_in",
            "nok_bent_pin.csv": "no_early_force", "nok_oversized_hole.csv": "press_in",
            "nok_undersized_hole.csv": "press_in"}


def _run(*args):
    return CliRunner().invoke(main, ["curves", "check", *map(str, args)])


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_each_shipped_example_gets_its_verdict(name):
    for extra in ([], ["--case", CASE, "--compensate"]):
        r = _run(EX / name, "--windows", WINDOWS, *extra)
        element = EXPECTED[name]
        assert r.exit_code == (0 if element is None else 1), r.output
        line = next(s for s in r.output.splitlines() if name in s)
        assert line.startswith("OK ") if element is None else f"element '{element}'" in line, line


def test_all_examples_junit_json_and_figure(tmp_path):
    junit, js, png = tmp_path / "j.xml", tmp_path / "r.json", tmp_path / "c.png"
    files = [EX / n for n in sorted(EXPECTED)]
    r = _run(*files, "--windows", WINDOWS, "--junit", junit, "--json", js, "--png", png)
    assert r.exit_code == 1 and "2 OK, 4 NOK of 6 curves" in r.output
    suite = ET.parse(junit).getroot().find("testsuite")
    cases = suite.findall("testcase")
    assert len(cases) == 6 and int(suite.get("failures")) == 4
    assert sum(tc.find("failure") is not None for tc in cases) == 4
    data = json.loads(js.read_text())
    assert data["nok"] == 4 and {Path(x["path"]).name: x["ok"] for x in data["results"]} == \
        {n: e is None for n, e in EXPECTED.items()}
    assert png.stat().st_size > 10_000
    again = _run(EX / "ok_part.csv", "--windows", WINDOWS, "--json", js)
    assert again.exit_code == 2 and "--overwrite" in again.output
    assert _run(EX / "ok_part.csv", "--windows", WINDOWS, "--json", js, "--overwrite").exit_code == 0


def test_bad_input_exits_2_naming_file_row_and_column(tmp_path):
    cases = {"nan.csv": ("x_mm,force_n\n0,0\n1,NaN\n", "row 3, column 'force_n'"),
             "one.csv": ("x_mm,force_n\n0,0\n", "row 2, column 'x_mm'"),
             "back.csv": ("x_mm,force_n\n0,0\n2,1\n1,1\n3,3\n", "row 4, column 'x_mm'"),
             "unit.csv": ("x [inch],force_n\n0,0\n1,1\n", "row 1, column 'x [inch]'")}
    for name, (text, where) in cases.items():
        p = tmp_path / name
        p.write_text(text)
        r = _run(EX / "ok_part.csv", p, "--windows", WINDOWS)
        assert r.exit_code == 2, r.output
        err = [s for s in r.output.splitlines() if s.startswith("error:")]
        assert len(err) == 1 and str(p) in err[0] and where in err[0], r.output
    big = tmp_path / "big.csv"
    big.write_bytes(b"x_mm,force_n\n" + b"0" * 10_000_000)
    r = _run(big, "--windows", WINDOWS)
    assert r.exit_code == 2 and "must be smaller than 10000000 bytes" in r.output
    assert _run(EX / "ok_part.csv", "--windows", WINDOWS, "--compensate").exit_code == 2  # no --case
    bad = tmp_path / "w.json"
    bad.write_text('{"schema_version": 1, "elements": []}')
    r = _run(EX / "ok_part.csv", "--windows", bad)
    assert r.exit_code == 2 and "elements" in r.output


def test_compensation_moves_the_curve_by_compliance_times_force(tmp_path):
    """A step to 400 N at a sensed 1 mm; the true depth under 400 N is 1 mm - C 400 N (C ~ 6.9e-8 m/N: 27.7 um
    less). A must-not-cross threshold of 200 N ending 1 um beyond that depth fails the compensated curve, one ending
    1 um before it passes; uncompensated (the rise at 1 mm) both pass."""
    c = press_compliance_m_per_n(load_case(CASE))
    true_x = 1e-3 - c * 400.0
    p = tmp_path / "step.csv"
    p.write_text("x_m,force_n\n0,0\n0.001,0\n0.001000000001,400\n0.003,400\n")
    for edge, ok in ((true_x + 1e-6, False), (true_x - 1e-6, True)):
        w = tmp_path / f"w{ok}.json"
        w.write_text(json.dumps({"schema_version": 1, "elements": [
            {"type": "threshold", "name": "early", "force_n": 200.0, "x_min_m": 0.0, "x_max_m": edge,
             "mode": "must_not_cross"}]}))
        assert _run(p, "--windows", w).exit_code == 0
        r = _run(p, "--windows", w, "--case", CASE, "--compensate")
        assert r.exit_code == (0 if ok else 1), r.output


def test_a_limiter_backoff_is_one_stroke_only_within_the_reversal_tolerance(tmp_path):
    """A press curve whose displacement steps back 2 um before its maximum (a force limiter backing the tool off):
    bad input at the default 1 um jitter tolerance (exit 2, naming the row), one forward stroke judged at
    --reversal-tolerance-m 2.5e-6 and refused again at 1.5e-6 (just under the 2 um step); a negative or NaN tolerance
    is a usage error (exit 2)."""
    rows = ["x_mm,force_n", "0,0", "0.5,0", "1.0,100", "1.2,120", "1.198,119", "1.4,140", "2.2,200", "2.25,300"]
    curve = tmp_path / "backoff.csv"
    curve.write_text("\n".join(rows) + "\n")
    r = _run(curve, "--windows", WINDOWS)
    assert r.exit_code == 2 and "runs backwards by 2e-06 m" in r.output and "row 6, column 'x_mm'" in r.output, r.output
    assert "(row 5 to this one, the force 120 N to 119 N)" in r.output and "reversal tolerance 1e-06 m" in r.output
    r = _run(curve, "--windows", WINDOWS, "--reversal-tolerance-m", "2.5e-6")
    assert r.exit_code in (0, 1) and "backoff.csv" in r.output and "runs backwards" not in r.output, r.output
    assert _run(curve, "--windows", WINDOWS, "--reversal-tolerance-m", "1.5e-6").exit_code == 2
    for bad in ("-1e-6", "nan"):
        r = _run(curve, "--windows", WINDOWS, "--reversal-tolerance-m", bad)
        assert r.exit_code == 2 and "--reversal-tolerance-m" in r.output, r.output
