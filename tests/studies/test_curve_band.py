"""The tolerance band, the windows derived from it and the Dask study: quantiles against numpy.quantile on a
hand-built sample, the closed-form pin against its formula written here, every curve of a band passing the
windows derived from it, the missing / bent pin and the oversized / undersized hole each NOK for its element, and
2 Dask workers against a serial run (same seed, bit for bit)."""

from dataclasses import replace

import numpy as np
import pytest

from pressfit.studies.curve_band import AnalyticPin, band_from_curves, curve_band_study, windows_from_band
from pressfit.studies.curve_check import check_curve

TOLERANCES = {"plateau_force_n": {"distribution": "normal", "mean": 120.0, "std": 6.0},
              "approach_m": {"distribution": "uniform", "low": 0.45e-3, "high": 0.55e-3},
              "seat_depth_m": {"distribution": "uniform", "low": 1.55e-3, "high": 1.65e-3}}


def test_band_quantiles_are_numpys_on_a_hand_built_sample():
    rng = np.random.default_rng(7)
    grid = np.linspace(0.0, 1e-3, 11)
    forces = rng.uniform(0.0, 100.0, (9, grid.size))
    q = (0.1, 0.5, 0.9)
    band = band_from_curves([(grid, f) for f in forces], quantiles=q, grid_m=grid)
    np.testing.assert_array_equal(band.force_n, np.quantile(forces, q, axis=0))
    np.testing.assert_array_equal(band.count, 9)


def test_band_interpolates_and_counts_the_curves_that_reach():
    """Two straight curves, 0 -> 10 N over 1 mm and 0 -> 30 N over 2 mm (then a return stroke, dropped): at 0.5 mm
    5 and 7.5 N (linear), beyond 1 mm only the second curve."""
    a = (np.array([0.0, 1e-3]), np.array([0.0, 10.0]))
    b = (np.array([0.0, 2e-3, 1e-3]), np.array([0.0, 30.0, 0.0]))
    band = band_from_curves([a, b], quantiles=(0.0, 0.5, 1.0), grid_m=np.array([0.5e-3, 1.5e-3]))
    np.testing.assert_allclose(band.force_n[:, 0], [5.0, 6.25, 7.5], rtol=1e-12)
    np.testing.assert_allclose(band.force_n[:, 1], [22.5, 22.5, 22.5], rtol=1e-12)
    np.testing.assert_array_equal(band.count, [2, 1])


def test_analytic_pin_against_its_closed_form():
    pin = AnalyticPin(approach_m=0.5e-3, lead_in_m=0.4e-3, plateau_force_n=120.0, seat_depth_m=1.6e-3,
                      seat_stiffness_n_per_m=2e6, stop_force_n=400.0)
    x, f = pin()
    hand = np.where(x < 0.5e-3, 0.0, np.where(x < 0.9e-3, 120.0 * (x - 0.5e-3) / 0.4e-3,
                                              120.0 + 2e6 * np.maximum(x - 2.1e-3, 0.0)))
    np.testing.assert_allclose(f, hand, atol=1e-9)
    assert x[-1] == pytest.approx(2.1e-3 + 280.0 / 2e6, rel=1e-12) and f[-1] == pytest.approx(400.0)


@pytest.fixture(scope="module")
def derived():
    study = curve_band_study(AnalyticPin(), TOLERANCES, 400, seed=3, chunk_size=100, serial=True)
    return study, windows_from_band(study.band, press_in_end_m=1.9e-3)


def test_every_curve_of_the_band_passes_its_windows(derived):
    """Every 20th of the 400 sampled curves (the band's quantiles are +-3 sigma, the margin 5% of the peak)."""
    study, windows = derived
    names = [e.name for e in windows.elements]
    assert names == ["max_force", "no_early_force", "press_in", "seated", "envelope"]
    for k in range(0, 400, 20):
        values = {n: float(v[k]) for n, v in study.inputs.items()}
        x, f = AnalyticPin()(values)
        assert all(r.passed for r in check_curve(x, f, windows)), values


@pytest.mark.parametrize(("label", "pin", "element"), [
    ("missing pin", replace(AnalyticPin(), plateau_force_n=2.0), "press_in"),
    ("oversized hole", replace(AnalyticPin(), plateau_force_n=85.0), "press_in"),
    ("undersized hole", replace(AnalyticPin(), plateau_force_n=160.0), "press_in"),
])
def test_bad_parts_fail_the_right_element(derived, label, pin, element):
    _, windows = derived
    x, f = pin()
    failed = [r for r in check_curve(x, f, windows) if not r.passed]
    assert failed and failed[0].element == element, (label, failed)
    assert ("below" if pin.plateau_force_n < 120 else "above") in failed[0].reason


def test_a_bent_pin_fails_the_early_force_threshold(derived):
    _, windows = derived
    x, f = AnalyticPin()()
    f = f + np.where((x > 0.15e-3) & (x < 0.4e-3), 30.0, 0.0)  # the tip rides on the board before the hole
    failed = [r for r in check_curve(x, f, windows) if not r.passed]
    assert failed[0].element == "no_early_force" and failed[0].x_m < 0.45e-3


def test_a_part_that_never_seats_fails_the_seated_threshold(derived):
    _, windows = derived
    pin = replace(AnalyticPin(), seat_depth_m=4e-3, stop_force_n=121.0, seat_stiffness_n_per_m=1e3)
    x, f = pin()
    x, f = x[x < 2.6e-3], f[x < 2.6e-3]
    failed = [r.element for r in check_curve(x, f, windows) if not r.passed]
    assert failed == ["seated"]


def test_two_dask_workers_agree_with_a_serial_run(cluster):
    serial = curve_band_study(AnalyticPin(), TOLERANCES, 300, seed=5, chunk_size=40, serial=True)
    dask = curve_band_study(AnalyticPin(), TOLERANCES, 300, seed=5, chunk_size=40, scheduler=cluster.scheduler_address)
    assert serial.chunks == dask.chunks == 8
    np.testing.assert_array_equal(serial.band.force_n, dask.band.force_n)
    for n in TOLERANCES:
        np.testing.assert_array_equal(serial.inputs[n], dask.inputs[n])
    other = curve_band_study(AnalyticPin(), TOLERANCES, 300, seed=6, chunk_size=40, serial=True)
    assert not np.array_equal(other.inputs["plateau_force_n"], serial.inputs["plateau_force_n"])
