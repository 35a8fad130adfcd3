"""The calibration's files and report section (issue 31)."""

import json

import pytest

from pressfit.errors import PressfitError
from pressfit.output.calibration_files import read_calibration, report_section


def results():
    return {"estimates": [{"key": "actuator.axial_stiffness_n_per_m", "start": 5e7, "value": 4.2e7,
                           "standard_error": 1e6, "interval_95": [4.0e7, 4.4e7]}],
            "keys": ["actuator.axial_stiffness_n_per_m"], "chi_square": 40.0, "p_value": 0.5, "rows": 16,
            "degrees_of_freedom": 47, "rms_residual_m": 1.9e-6, "rms_sigma_m": 2e-6, "measurements": "m.csv",
            "not_separately_identifiable": [{"keys": ["a.b", "c.d"], "correlation": 0.99}]}


def test_the_report_section_shows_values_intervals_and_residuals(tmp_path):
    (tmp_path / "results.json").write_text(json.dumps(results()))
    text = "\n".join(report_section(read_calibration(tmp_path), tmp_path))
    for w in ["| `actuator.axial_stiffness_n_per_m` | 5e+07 | 4.2e+07 | 1e+06 | [4e+07, 4.4e+07] |",
              "chi-square 40 (p-value 0.5)", "1.9e-06 m against a stated RMS sigma of 2e-06 m", "residuals.csv",
              "a.b and c.d (correlation +0.9900)"]:
        assert w in text, w


def test_a_directory_without_results_is_refused_by_name(tmp_path):
    with pytest.raises(PressfitError, match="results.json: not the results.json of a pressfit calibrate run"):
        read_calibration(tmp_path)
    (tmp_path / "results.json").write_text(json.dumps({"keys": []}))
    with pytest.raises(PressfitError, match="no estimates"):
        read_calibration(tmp_path)
