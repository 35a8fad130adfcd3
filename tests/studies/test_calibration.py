"""Calibration (issue 31): keys recovered from measurements made by another engine, honest intervals, keys the
data cannot separate reported as such.

The measurements are made by the Pinocchio-chain VJM model (:class:`pressfit.mechanics.fast_statics.
FastEquilibriumSolver`, linear solve: lumped springs per leg segment, loop closures solved numerically), a
formulation independent of the condensed closed form that the fit uses; the two agree to ~1e-9 relative
(docs/architecture.md, tests/mechanics), far below the 1e-6 m noise on ~1e-4 m deflections.
"""

import numpy as np
import pytest

from pressfit.errors import CalibrationError, MeasurementFileError, ModelFileError
from pressfit.mechanics.fast_statics import FastEquilibriumSolver
from pressfit.studies import calibration as cal_mod
from pressfit.studies.calibration import calibrate
from pressfit.studies.calibration_model import Data, machine_with, parse_fit_keys
from pressfit.studies.measurement_plan import candidate_poses, load_directions
from pressfit.studies.measurements import Deflections

KEYS = ["actuator.axial_stiffness_n_per_m", "stem.diameter_m"]
TRUTH = [4.2e7, 0.0315]  # the "built machine": a softer drive, a thicker stem than the shipped 5e7 N/m, 30 mm
SIGMA_M = 1e-6


def vjm_deflections(machine, pose, load):
    """Tool translations (m) of ``machine`` at poses (m, 3) under loads (m, 3), by the VJM chain."""
    batch = FastEquilibriumSolver(machine).solve_batch(pose, np.concatenate([load, np.zeros_like(load)], 1),
                                                       linear=True)
    return batch.plate_displacement_m


def deflections(pose, load, measured, sigma=SIGMA_M):
    s = None if sigma is None else np.full(len(pose), sigma)
    return Deflections(path="<test>", pose_m=pose, load_n=load, translation_m=measured, rotation_rad=None,
                       sigma_m=s, sigma_rad=None, lines=np.arange(len(pose)) + 2)


@pytest.fixture(scope="module")
def layout(machine):
    """14 poses of the required workspace (every other candidate) x loads of 700 N along x, y, z."""
    poses = candidate_poses(machine)[::2]
    return np.repeat(poses, 3, 0), np.tile(load_directions()[:3], (len(poses), 1)) * 700.0


@pytest.fixture(scope="module")
def perturbed(machine, layout):
    keys = parse_fit_keys(machine, KEYS)
    truth = machine_with(machine, keys, TRUTH)
    return keys, vjm_deflections(truth, *layout)


def test_perturbed_values_recovered_within_their_intervals(machine, layout, perturbed):
    keys, exact = perturbed
    noisy = exact + np.random.default_rng(3).normal(0.0, SIGMA_M, exact.shape)
    c = calibrate(machine, keys, Data(deflections=deflections(*layout, noisy)))
    for e, t in zip(c.estimates, TRUTH, strict=True):
        assert e.interval_low < t < e.interval_high, e
        assert abs(e.value - t) < 3 * e.standard_error  # a 3-sigma bound: fails about 3 times in 1000
    assert c.sigma_stated and c.quantile == pytest.approx(1.959964, abs=1e-6)  # the normal quantile
    assert 0.001 < c.p_value < 0.999  # chi-square consistent with the stated noise
    assert c.rms_residual_m == pytest.approx(SIGMA_M, rel=0.2)  # 126 residuals: the RMS scatters ~6%
    assert not c.unidentifiable
    # the calibrated machine predicts the measured translations at the noise level
    assert np.abs(c.deflection_residuals_m).max() < 5 * SIGMA_M


def test_shipped_values_recovered_from_data_of_the_shipped_machine(machine, layout):
    """Data of the shipped machine (VJM), fit started from a wrong machine file: noise-free, the shipped 5e7 N/m
    and 30 mm come back to the engines' ~1e-9 agreement; with noise and sigma unstated (noise estimated from the
    residuals, Student's t), within their intervals."""
    keys = parse_fit_keys(machine, KEYS)
    exact = vjm_deflections(machine, *layout)
    start = machine_with(machine, keys, [8e7, 0.026])
    c = calibrate(start, parse_fit_keys(start, KEYS), Data(deflections=deflections(*layout, exact, sigma=None)))
    assert [e.value for e in c.estimates] == pytest.approx([5e7, 0.030], rel=3e-8)
    noisy = exact + np.random.default_rng(5).normal(0.0, SIGMA_M, exact.shape)
    c = calibrate(start, parse_fit_keys(start, KEYS), Data(deflections=deflections(*layout, noisy, sigma=None)))
    for e, t in zip(c.estimates, [5e7, 0.030], strict=True):
        assert e.interval_low < t < e.interval_high, e
    assert not c.sigma_stated and c.p_value is None and c.quantile > 1.96  # t with 124 degrees of freedom


def test_axial_keys_from_one_vertical_load_at_the_centre_are_not_separately_identifiable(machine):
    """At x = z = 0 under a vertical load every leg is purely axial (docs: 700 / (4 sin alpha) each), so the
    tool moves by F / (4 k_leg sin^2 alpha) with 1 / k_leg = 1 / k_act + L_cyl / (E A_cyl) + L_stem / (E A_stem):
    the drive's stiffness and the stem's diameter enter only through this one combination. The data (three
    loads at one pose) cannot separate them; the warning names the pair and a measurement that would."""
    keys = parse_fit_keys(machine, KEYS)
    pose = np.tile([0.0, 0.7, 0.0], (3, 1))
    load = np.array([[0, 300.0, 0], [0, 500.0, 0], [0, 700.0, 0]])
    exact = vjm_deflections(machine, pose, load)
    c = calibrate(machine, keys, Data(deflections=deflections(pose, load, exact)))
    assert len(c.unidentifiable) == 1
    pair = c.unidentifiable[0]
    assert pair["keys"] == KEYS and abs(pair["correlation"]) > 0.9999  # exactly 1 in exact arithmetic
    sep = pair["separated_by"]
    # the proposed measurement is not another centred vertical load, and it breaks the degeneracy
    assert np.hypot(sep["pose_m"][0], sep["pose_m"][2]) > 0.1 or abs(sep["load_direction"][1]) < 0.9
    assert abs(sep["correlation_after"]) < 0.99 and sep["log_det_gain"] > 5
    assert c.condition_number > 1e8


@pytest.mark.slow  # 200 full fits, ~8 s of CPU
def test_intervals_cover_the_truth_about_95_percent(machine, layout, perturbed):
    """Coverage over 200 noisy data sets (the same VJM data, fresh noise each): each key's 95% interval holds
    the truth in 95% +- 1.5% (binomial sd) of them; the bounds [0.90, 0.99] are 3.3 sd. Cheap: 9 rows."""
    keys, exact = perturbed
    pose, load = layout
    rows = slice(0, 27, 3)
    rng = np.random.default_rng(11)
    hits = np.zeros(2)
    reps = 200
    for _ in range(reps):
        noisy = exact[rows] + rng.normal(0.0, SIGMA_M, exact[rows].shape)
        c = calibrate(machine, keys, Data(deflections=deflections(pose[rows], load[rows], noisy)))
        hits += [e.interval_low < t < e.interval_high for e, t in zip(c.estimates, TRUTH, strict=True)]
    assert np.all((hits / reps >= 0.90) & (hits / reps <= 0.99)), hits / reps


@pytest.mark.parametrize(("spec", "words"), [
    ("actuator.no_such_key_n", ["actuator.no_such_key_n", "no such key"]),
    ("joints.cardan_clearance_geometry", ["joints.cardan_clearance_geometry", "numeric"]),
    ("actuator", ["'actuator'", "numeric"]),
    ("actuator.axial_stiffness_n_per_m=1e8:2e8", ["actuator.axial_stiffness_n_per_m", "exclude the start value 5e+07"]),
    ("stem.diameter_m=0.04", ["stem.diameter_m", "LO:HI"]),
    ("stem.diameter_m=0.04:0.02", ["stem.diameter_m", "LO < HIGH"]),
])
def test_a_bad_key_names_the_machine_file_and_the_key(machine, spec, words):
    with pytest.raises(ModelFileError) as err:
        parse_fit_keys(machine, [spec])
    assert machine.source in str(err.value)
    for w in words:
        assert w in str(err.value)


def test_a_key_the_static_model_does_not_use_is_refused(machine, layout, perturbed):
    """The cardans' contact stiffness acts only in the clearance solvers: the condensed model's prediction
    does not depend on it, so the fit cannot determine it."""
    keys = parse_fit_keys(machine, ["joints.cardan_contact_stiffness_n_per_m"])
    with pytest.raises(ModelFileError, match="cardan_contact_stiffness_n_per_m.*depend"):
        calibrate(machine, keys, Data(deflections=deflections(*layout, perturbed[1])))


def test_fewer_measured_numbers_than_keys_is_refused(machine):
    keys = parse_fit_keys(machine, [*KEYS, "cylinder.wall_thickness_m"])
    pose, load = np.array([[0.0, 0.7, 0.0]]), np.array([[0.0, 700.0, 0.0]])
    with pytest.raises(MeasurementFileError, match="3 measured numbers for 3 fitted keys"):
        calibrate(machine, keys, Data(deflections=deflections(pose, load, vjm_deflections(machine, pose, load))))


def test_a_fit_that_does_not_converge_says_so_with_its_last_residual(machine, layout, perturbed, monkeypatch):
    real = cal_mod.least_squares
    monkeypatch.setattr(cal_mod, "least_squares", lambda *a, **k: real(*a, **{**k, "max_nfev": 1}))
    with pytest.raises(CalibrationError) as err:
        calibrate(machine, parse_fit_keys(machine, KEYS), Data(deflections=deflections(*layout, perturbed[1])))
    assert "did not converge" in str(err.value) and np.isfinite(err.value.residual) and err.value.residual > 0


def test_rotation_columns_are_fitted_with_their_own_sigma(machine, layout):
    """Measured plate rotations (VJM) with sigma_rad join the translations: the built values are recovered
    within their intervals and the residual count doubles."""
    keys = parse_fit_keys(machine, KEYS)
    pose, load = layout[0][::3], layout[1][::3]
    wrench = np.concatenate([load, np.zeros_like(load)], 1)
    batch = FastEquilibriumSolver(machine_with(machine, keys, TRUTH)).solve_batch(pose, wrench, linear=True)
    rng = np.random.default_rng(7)
    d = Deflections(path="<test>", pose_m=pose, load_n=load,
                    translation_m=batch.plate_displacement_m + rng.normal(0, SIGMA_M, pose.shape),
                    rotation_rad=batch.plate_rotation_rad + rng.normal(0, 1e-6, pose.shape),
                    sigma_m=np.full(len(pose), SIGMA_M), sigma_rad=np.full(len(pose), 1e-6), lines=np.arange(len(pose)))
    c = calibrate(machine, keys, Data(deflections=d))
    assert c.residual_count == 6 * len(pose) and c.rotation_residuals_rad.shape == (len(pose), 3)
    for e, t in zip(c.estimates, TRUTH, strict=True):
        assert e.interval_low < t < e.interval_high, e


@pytest.mark.slow  # about a dozen modal solves of the VJM model, ~1 s each
def test_a_measured_first_frequency_joins_the_fit(machine):
    """The tube's wall thickness from three deflections (VJM) and the first frequency at pose A (the rocking pair,
    held by the legs' torsion: sensitive to the wall) of the built machine: recovered within its interval, the
    frequency residual at the noise level."""
    from pressfit.dynamics.modes import natural_modes
    from pressfit.studies.measurements import Frequencies

    keys = parse_fit_keys(machine, ["cylinder.wall_thickness_m"])
    built = machine_with(machine, keys, [0.0046])
    pose = np.array([[0.2, 0.6, -0.2]] * 3)
    load = np.eye(3) * 150.0
    f1 = natural_modes(built, [0.0, 0.72, 0.0], count=1).frequencies_hz
    freq = Frequencies(path="<modes>", pose_m=np.array([[0.0, 0.72, 0.0]]), frequency_hz=f1 + 0.01,
                       sigma_hz=np.array([0.05]), lines=np.array([2]))
    data = Data(deflections=deflections(pose, load, vjm_deflections(built, pose, load)), frequencies=freq)
    c = calibrate(machine, keys, data)
    (e,) = c.estimates
    assert e.interval_low < 0.0046 < e.interval_high
    assert abs(c.frequency_residuals_hz[0]) < 0.05
