"""``pressfit study curve``'s sample and band (studies/curve_study.py on studies/curve_band.py): the references are
``predict_curve`` called directly on a contact built by hand (a second path through the schema), not the study's
own output."""

from __future__ import annotations

import numpy as np
import pytest

from pressfit.description.cases import Distribution, load_case
from pressfit.description.monitor_windows import Envelope
from pressfit.errors import ModelFileError, PressCurveError
from pressfit.mechanics.press_curve import pin_pose_m, predict_curve
from pressfit.shipped import cases_dir
from pressfit.studies.curve_band import curve_band_study, windows_from_band
from pressfit.studies.curve_check import check_curve
from pressfit.studies.curve_study import CurveSample, perturbed_contact

CASE = cases_dir() / "paper" / "insertion_compliant_pin.toml"
POINTS = 401


@pytest.fixture(scope="module")
def case():
    return load_case(CASE)


@pytest.fixture(scope="module")
def sample(case):
    return CurveSample.from_case(case, case.machine())


def test_the_nominal_sample_is_predict_curves_sensed_curve_exactly(case, sample):
    """Every tolerance at zero deviation (and no values at all) gives predict_curve's (sensed depth, force) of the
    case, bit for bit; a degenerate study (every Distribution of std 0) bands that one curve: its quantiles all
    equal the curve resampled on the grid (achieved 0 N)."""
    ref = predict_curve(case.machine(), case, samples=POINTS)
    for values in ({}, {k: 0.0 for k in case.curve.tolerances}):
        x, f = sample(values)
        np.testing.assert_array_equal(x, ref.sensed_depth_m)
        np.testing.assert_array_equal(f, ref.force_n)
    zero = {k: Distribution(distribution="normal", std=0.0) for k in case.curve.tolerances}
    band = curve_band_study(sample, zero, 6, seed=1, chunk_size=2, serial=True).band
    expected = np.interp(band.grid_m, np.maximum.accumulate(ref.sensed_depth_m), ref.force_n, right=np.nan)
    reached = np.isfinite(expected)
    for q in range(band.quantiles.size):
        np.testing.assert_array_equal(band.force_n[q, reached], expected[reached])


def test_a_law_deviation_is_the_hand_built_contacts_curve(case, sample):
    """+20 um of hole diameter and -0.02 of friction equal predict_curve of the contact with those values written
    in (hole 1.02 mm, friction 0.13, validated from its TOML keys), exactly."""
    contact = case.simulation.contact
    by_hand = type(contact).model_validate({**contact.model_dump(exclude_unset=True), "hole_diameter_m": 1.02e-3,
                                            "friction_coefficient": 0.13})
    ref = predict_curve(case.machine(), by_hand, samples=POINTS, stop_force_n=case.simulation.controller.force_limit_n)
    x, f = sample({"hole_diameter_m": 2.0e-5, "friction_coefficient": -0.02})
    np.testing.assert_allclose(f, ref.force_n, rtol=0, atol=1e-9)  # achieved 0 (1.02e-3 = 1e-3 + 2e-5 to 1 ulp)
    np.testing.assert_allclose(x, ref.sensed_depth_m, rtol=0, atol=1e-15)


def test_pin_position_moves_the_pose(case, sample):
    """pin_x_m / pin_z_m give predict_curve of the nominal contact at the pose moved by hand (its compliance
    there): identical; and 50 mm further out the sensed depth at the end differs by 18 um (another compliance)."""
    contact = case.simulation.contact
    pose = pin_pose_m(contact) + np.array([0.004, 0.0, -0.003])
    ref = predict_curve(case.machine(), contact, pose_m=pose, samples=POINTS,
                        stop_force_n=case.simulation.controller.force_limit_n)
    x, f = sample({"pin_x_m": 0.004, "pin_z_m": -0.003})
    np.testing.assert_array_equal(x, ref.sensed_depth_m)
    np.testing.assert_array_equal(f, ref.force_n)
    far, _ = sample({"pin_x_m": 0.05})
    assert abs(far[-1] - sample({})[0][-1]) > 1e-6  # achieved 1.8e-5 m


def test_a_draw_out_of_range_is_refused_naming_the_key(case):
    with pytest.raises(PressCurveError, match="curve.tolerances.hole_diameter_m"):
        perturbed_contact(case.simulation.contact, {"hole_diameter_m": -2e-3})
    with pytest.raises(PressCurveError, match="curve.tolerances.friction_coefficient"):
        perturbed_contact(case.simulation.contact, {"friction_coefficient": -0.2})


def test_a_wider_hole_tolerance_widens_the_band_at_the_plateau(sample):
    """Hole diameter uniform +-10 um against +-30 um (same seed, so the same unit draws scaled): the band's width
    (highest minus lowest quantile) on the plateau (sensed 1.25 .. 1.35 mm, past the zone's peak, before the
    shoulder) grows; the plateau force is monotone in the hole (a larger hole, less squeeze), so three times the
    deviation spreads the plateau at least twice as wide (achieved ~3x on this elastic-plastic zone)."""
    def width(half):
        tol = {"hole_diameter_m": Distribution(distribution="uniform", low=-half, high=half)}
        band = curve_band_study(sample, tol, 60, seed=3, chunk_size=30, serial=True).band
        on = (band.grid_m > 1.25e-3) & (band.grid_m < 1.35e-3)
        assert on.any()
        return float(np.min(band.force_n[-1, on] - band.force_n[0, on]))

    narrow, wide = width(1e-5), width(3e-5)
    assert narrow > 0
    assert wide > 2.0 * narrow


def test_the_derived_windows_pass_the_nominal_curve_and_not_one_far_above(case, sample):
    """The windows of the shipped tolerances (100 curves) pass the nominal curve (every element); the nominal
    forces times 1.6 (a pin far too thick) fail, and a curve just above the envelope's upper curve fails it while
    one just below it does not exceed it."""
    study = curve_band_study(sample, case.curve.tolerances, 100, seed=0, chunk_size=50, serial=True)
    windows = windows_from_band(study.band)
    x, f = sample({})
    results = check_curve(x, f, windows)
    assert all(r.passed for r in results), [r for r in results if not r.passed]
    assert not all(r.passed for r in check_curve(x, 1.6 * f, windows))
    env = next(e for e in windows.elements if isinstance(e, Envelope))
    ex, upper = np.array(env.displacement_m), np.array(env.upper_force_n)
    over = [r for r in check_curve(ex, upper + 0.5, windows) if r.element == "envelope"]
    under = [r for r in check_curve(ex, upper - 0.5, windows) if r.element == "envelope"]
    assert not over[0].passed and under[0].passed


def test_an_unknown_tolerance_key_is_refused_naming_it_and_the_file(tmp_path):
    text = CASE.read_text().replace("pin_z_m = {", "pin_diameter_m = { distribution = \"normal\", std = 1e-6 }\n"
                                    "pin_z_m = {", 1)
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    with pytest.raises(ModelFileError, match=r"bad\.toml: key 'curve\.tolerances\.pin_diameter_m'"):
        load_case(bad)


def test_two_dask_workers_agree_with_a_serial_run(case, sample, cluster):
    serial = curve_band_study(sample, case.curve.tolerances, 40, seed=7, chunk_size=10, serial=True)
    dask = curve_band_study(sample, case.curve.tolerances, 40, seed=7, chunk_size=10,
                            scheduler=cluster.scheduler_address)
    np.testing.assert_array_equal(serial.band.force_n, dask.band.force_n)
    for n in case.curve.tolerances:
        np.testing.assert_array_equal(serial.inputs[n], dask.inputs[n])
