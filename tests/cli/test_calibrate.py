"""`pressfit calibrate` (issue 31): every bad input of item 2 exits 2 with one line naming the file, the row and
the column or key; the calibrated machine file is accepted by `solve` and `stiffness`; --plan; the outputs never
replace an input."""

import json
from pathlib import Path

import pytest
from click.testing import CliRunner
from readme import assert_printed, readme_fragment

from pressfit.cli import main
from pressfit.studies import calibration as cal_mod

ROOT = Path(__file__).resolve().parents[2]
MACHINE = ROOT / "models" / "pressfit_4upu.toml"
EXAMPLE = ROOT / "docs" / "examples" / "calibration" / "measurements.csv"
FIT = ["--fit", "actuator.axial_stiffness_n_per_m", "--fit", "cylinder.wall_thickness_m"]
HEADER = "x_m,y_m,z_m,fx_n,fy_n,fz_n,dx_m,dy_m,dz_m,sigma_m"
ROW = "0.1,0.7,-0.1,0,700,0,1e-5,2e-5,3e-6,1e-6"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def assert_one_line_exit_2(res, *words):
    assert res.exit_code == 2, (res.output, res.exception)
    assert isinstance(res.exception, SystemExit) and "Traceback" not in res.output
    lines = [x for x in res.stderr.splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])


def csv_file(tmp_path, *rows, header=HEADER):
    p = tmp_path / "m.csv"
    p.write_text("\n".join([header, *rows]) + "\n")
    return p


@pytest.mark.parametrize(("rows", "words"), [
    ([ROW, "0.1,0.2,-0.1,0,700,0,1e-5,2e-5,3e-6,1e-6"], ["row 3", "x_m,y_m,z_m", "out of reach", "leg"]),
    ([ROW, "0.1,0.7,-0.1,0,nan,0,1e-5,2e-5,3e-6,1e-6"], ["row 3", "'fy_n'", "finite"]),
    ([ROW, "0.1,0.7,-0.1,0,700,0,abc,2e-5,3e-6,1e-6"], ["row 3", "'dx_m'", "not a number"]),
    ([ROW, "0.1,0.7,-0.1,0,700,0,1e-5,2e-5,3e-6,0"], ["row 3", "'sigma_m'", "positive"]),
    ([ROW, "0.1,0.7,-0.1,0,700,0,1e-5"], ["row 3", "7 values for 10 columns"]),
    (["0.1,0.7,-0.1,0,0,0,1e-5,2e-5,3e-6,1e-6"] * 2, ["fx_n,fy_n,fz_n", "zero on every row"]),
    ([], ["no measurement rows"]),
])
def test_a_bad_measurement_file_names_the_file_row_and_column(tmp_path, rows, words):
    path = csv_file(tmp_path, *rows)
    assert_one_line_exit_2(run("calibrate", MACHINE, path, *FIT), str(path), *words)


def test_a_missing_column_is_named(tmp_path):
    path = csv_file(tmp_path, ROW.rsplit(",", 2)[0] + ",1e-6", header=HEADER.replace(",dz_m", ""))
    assert_one_line_exit_2(run("calibrate", MACHINE, path, *FIT), str(path), "row 1", "'dz_m'", "missing column")


def test_fewer_rows_than_keys_is_refused(tmp_path):
    path = csv_file(tmp_path, ROW)
    keys = [*FIT, "--fit", "stem.diameter_m"]
    assert_one_line_exit_2(run("calibrate", MACHINE, path, *keys), str(path), "3 measured numbers for 3 fitted keys")


@pytest.mark.parametrize(("key", "words"), [
    ("actuator.no_such_n", ["actuator.no_such_n", "no such key"]),
    ("name", ["'name'", "numeric"]),
    ("stem.diameter_m=0.031:0.04", ["stem.diameter_m", "exclude the start value 0.03"]),
])
def test_a_bad_key_names_the_machine_file_and_the_key(key, words):
    assert_one_line_exit_2(run("calibrate", MACHINE, EXAMPLE, "--fit", key), str(MACHINE), *words)


def test_a_fit_that_does_not_converge_exits_2_with_its_last_residual(monkeypatch):
    real = cal_mod.least_squares
    monkeypatch.setattr(cal_mod, "least_squares", lambda *a, **k: real(*a, **{**k, "max_nfev": 1}))
    assert_one_line_exit_2(run("calibrate", MACHINE, EXAMPLE, *FIT), "did not converge", "last residual norm")


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    out = tmp_path_factory.mktemp("cal") / "run"
    res = run("calibrate", MACHINE, EXAMPLE, *FIT, "--out", out)
    assert res.exit_code == 0, res.output
    return out, res


def test_the_example_is_fitted_and_every_file_written(calibrated):
    """The shipped example was made by the VJM chain from 4.2e7 N/m and 4.6 mm walls with 2 um noise
    (docs/examples/calibration/generate.py): both inside the printed 95% intervals."""
    out, res = calibrated
    assert {p.name for p in out.iterdir()} == {"results.json", "residuals.csv", "predicted_vs_measured.png",
                                               "pressfit_4upu_calibrated.toml", "calibration.md"}
    results = json.loads((out / "results.json").read_text())
    for e, truth in zip(results["estimates"], [4.2e7, 0.0046], strict=True):
        assert e["interval_95"][0] < truth < e["interval_95"][1], e
    assert len((out / "residuals.csv").read_text().splitlines()) == 1 + 16
    assert "95% interval" in res.output


@pytest.mark.parametrize("command", [["solve", "0.1", "0.7", "-0.1", "--load", "0", "700", "0"],
                                     ["stiffness", "0.1", "0.7", "-0.1"]])
def test_the_calibrated_file_is_accepted_by_solve_and_stiffness(calibrated, command):
    out, _ = calibrated
    res = run(*command, "--model", out / "pressfit_4upu_calibrated.toml")
    assert res.exit_code == 0, res.output


def test_the_output_never_replaces_an_existing_run_or_an_input(calibrated, tmp_path):
    out, _ = calibrated
    assert_one_line_exit_2(run("calibrate", MACHINE, EXAMPLE, *FIT, "--out", out), "--overwrite")
    measurements = tmp_path / "residuals.csv"  # the input has the name of an output, in the output directory
    measurements.write_text(EXAMPLE.read_text())
    res = run("calibrate", MACHINE, measurements, *FIT, "--out", tmp_path, "--overwrite")
    assert_one_line_exit_2(res, "residuals.csv", "input")
    assert measurements.read_text() == EXAMPLE.read_text()


def test_the_plan_proposes_distinct_measurements_in_the_measurement_file_format():
    res = run("calibrate", "--plan", MACHINE, *FIT, "--poses", "5", "--json")
    assert res.exit_code == 0, res.output
    plan = json.loads(res.output)
    rows = [tuple(m.values()) for m in plan["measurements"]]
    assert len(rows) == 5 == len(set(rows))
    text = run("calibrate", "--plan", MACHINE, *FIT, "--poses", "5").output
    assert text.splitlines()[0] == HEADER


def test_plan_takes_no_measurement_file():
    assert_one_line_exit_2(run("calibrate", "--plan", MACHINE, EXAMPLE, *FIT), "--plan takes MACHINE.toml only")


@pytest.mark.parametrize(("rows", "words"), [
    (["0,0.72,0,-3"], ["row 2", "'frequency_hz'", "positive"]),
    (["0,5.0,0,18"], ["row 2", "x_m,y_m,z_m", "out of reach"]),
])
def test_a_bad_modes_file_names_the_file_row_and_column(tmp_path, rows, words):
    modes = tmp_path / "modes.csv"
    modes.write_text("\n".join(["x_m,y_m,z_m,frequency_hz", *rows]) + "\n")
    assert_one_line_exit_2(run("calibrate", MACHINE, EXAMPLE, *FIT, "--modes", modes), str(modes), *words)


def test_rotation_columns_without_sigma_rad_are_refused(tmp_path):
    path = csv_file(tmp_path, ROW + ",1e-6,0,0", header=HEADER + ",rx_rad,ry_rad,rz_rad")
    assert_one_line_exit_2(run("calibrate", MACHINE, path, *FIT), str(path), "'sigma_rad'")


def test_report_refuses_a_calibration_directory_without_results_before_computing(tmp_path):
    empty = tmp_path / "not-a-run"
    empty.mkdir()
    res = run("report", "--calibration", empty, "--out", tmp_path / "report", "--quick")
    assert_one_line_exit_2(res, "results.json", "not the results.json of a pressfit calibrate run")


def test_the_readme_calibration_table_is_this_run_and_holds_the_built_machine(calibrated):
    """Drift protection: the README's table is what the run prints (each cell at its printed digits). The
    independent source: the built machine's values (4.2e7 N/m, 4.6 mm: docs/examples/calibration/generate.py,
    from which the VJM chain made the data) lie inside the README's printed 95% intervals, and its chi-square's
    degrees of freedom are 3 x 16 rows - 2 keys = 46."""
    out, _ = calibrated
    results = json.loads((out / "results.json").read_text())
    for e, truth in zip(results["estimates"], [4.2e7, 0.0046], strict=True):
        low, high = (f"{v:.6g}" for v in e["interval_95"])
        row = readme_fragment(f"| `{e['key']}` | {e['start']:g} | {e['value']:.6g} |")
        assert row and readme_fragment(f"[{low}, {high}] |")
        assert float(low) < truth < float(high)
    readme_fragment("16 rows, 48 residuals, 46 degrees of freedom")
    assert_printed(results["chi_square"], readme_fragment("chi-square 36.09").split()[-1])
