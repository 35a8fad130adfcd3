"""Monte Carlo study physics and statistics (in process, no cluster; the Dask runner is in test_distributed)."""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import special

from pressfit import kinematics
from pressfit.description.cases import load_case
from pressfit.errors import CondensedModelError, ModelFileError
from pressfit.mechanics import condensed
from pressfit.studies import montecarlo as mc

POSE_A = [0.0, 0.72, 0.0]  # tan(alpha) = y_h / (p - r) = 0.72 / 0.36 = 2
SIGMA_M = 5e-6


def synthetic_case(tmp_path: Path, samples: int = 200, extra: str = "") -> Path:
    """Pose A, 700 N vertical, only the actuator lengths random (normal, 5 um): closed form below."""
    p = tmp_path / "synthetic.toml"
    p.write_text(f"""name = "synthetic"
[poses]
points_m = [{POSE_A}]
[loads]
force_n = [0.0, 700.0, 0.0]
[envelope]
max_tension_n = 300.0
[montecarlo]
samples = {samples}
seed = 3
chunk_size = 25
[montecarlo.inputs.actuator_length_offset_m]
distribution = "normal"
mean = 0.0
std = {SIGMA_M}
{extra}""")
    return p


def closed_form_peak_tension(machine, offsets_m: np.ndarray) -> np.ndarray:
    """Linear closed form at pose A: N = N_F - k (v_p . o) v_p (the offsets' part outside the range of A^T
    is a self-stress), N_F = 700 / (4 sin alpha) per leg, |v_p,i| = 1/2, so max_i N_i = N_F + k |v_p . o| / 2
    with k = 1 / (series axial compliance) (actuator, cylinder, stem)."""
    ik = kinematics.inverse_kinematics(machine, np.array(POSE_A))
    n_f = 700.0 / (4 * math.sin(ik.alpha_rad[0]))
    k = 1.0 / machine.axial_compliance_m_per_n(ik.lengths_m[0])
    vp = kinematics.preload_vector(machine, np.array(POSE_A))
    return n_f + k * np.abs(offsets_m @ vp) / 2


def test_peak_tension_matches_closed_form_per_sample(tmp_path):
    """Each sample's worst tension against the linear closed form; the geometrically nonlinear solve differs
    by its small-rotation terms (measured 5.7e-5 relative here): tolerance 2e-4 of the value."""
    plan = mc.plan_from_case(load_case(synthetic_case(tmp_path)), samples=25)
    cols = mc.evaluate_chunk(plan, 0, mc.chunk_seeds(plan)[0])
    offsets = np.column_stack([cols[f"actuator_length_offset_m.leg{i}"] for i in range(1, 5)])
    expected = closed_form_peak_tension(plan.machine, offsets)
    assert np.all(cols["status"] == "ok")
    np.testing.assert_allclose(cols["max_tension_n"], expected, rtol=2e-4)
    assert np.ptp(expected) > 50  # the offsets really spread the answer


def test_exceedance_probability_within_wilson_interval(tmp_path):
    """P(max N > L) = P(|v_p . o| > 2 (L - N_F) / k) = 2 (1 - Phi(2 (L - N_F) / (k sigma))), v_p . o ~ N(0,
    sigma^2) for a unit v_p and iid offsets: the sampled estimate's 95% Wilson interval must contain it."""
    case = load_case(synthetic_case(tmp_path))
    plan = mc.plan_from_case(case)
    seeds = mc.chunk_seeds(plan)
    chunks = [mc.evaluate_chunk(plan, k, seeds[k]) for k in range(plan.n_chunks)]
    cols = {key: np.concatenate([c[key] for c in chunks]) for key in chunks[0]}
    summary = mc.summarize(plan, cols, {"max_tension_n": 300.0})
    (e,) = summary.exceedance
    ik = kinematics.inverse_kinematics(plan.machine, np.array(POSE_A))
    n_f = 700.0 / (4 * math.sin(ik.alpha_rad[0]))
    k = 1.0 / plan.machine.axial_compliance_m_per_n(ik.lengths_m[0])
    p = 2 * (1 - special.ndtr(2 * (300.0 - n_f) / (k * SIGMA_M)))
    assert 0.1 < p < 0.9  # a probability the 200 samples can resolve
    assert e.ci95[0] <= p <= e.ci95[1], (p, e)
    assert e.samples == 200 and summary.failed == {}


def test_wilson_interval_closed_form():
    """Wilson score interval: for 0 successes the upper end is z^2 / (n + z^2) (z = 1.96: 0.2775 at n = 10);
    for k = n/2 it is symmetric about 1/2 with half-width z sqrt(n/4 + z^2/4) / (n + z^2)."""
    z = 1.959963984540054
    assert mc.wilson_interval(0, 10) == pytest.approx((0.0, z * z / (10 + z * z)), abs=1e-15)
    lo, hi = mc.wilson_interval(50, 100)
    half = z * math.sqrt(100 / 4 + z * z / 4) / (100 + z * z)
    assert (lo, hi) == pytest.approx((0.5 - half, 0.5 + half), abs=1e-14)


def test_seeds_do_not_depend_on_chunking_order(tmp_path):
    """Chunk k's inputs come from SeedSequence(seed).spawn(n)[k]: drawing chunk 3 alone gives the same
    numbers as drawing every chunk in reverse order."""
    plan = mc.plan_from_case(load_case(synthetic_case(tmp_path)))
    seeds = mc.chunk_seeds(plan)
    alone = mc.draw_inputs(plan, 3, np.random.SeedSequence(plan.seed).spawn(plan.n_chunks)[3])
    in_reverse = [mc.draw_inputs(plan, k, seeds[k]) for k in reversed(range(plan.n_chunks))]
    np.testing.assert_array_equal(alone["actuator_length_offset_m"], in_reverse[-4]["actuator_length_offset_m"])


def test_truncated_normal_stays_in_bounds_and_has_its_mean(tmp_path):
    """Truncated normal N(0, 0.02) on [0, 0.06] rad: mean sigma / sqrt(2 pi) (1 - e^{-4.5}) / (Phi(3) - 1/2)
    (closed form of the half-normal cut at 3 sigma); 4000 draws: standard error 1.9e-4, tolerance 1e-3."""
    extra = """[montecarlo.inputs.load_tilt_rad]
distribution = "truncnormal"
mean = 0.0
std = 0.02
low = 0.0
high = 0.06
"""
    plan = mc.plan_from_case(load_case(synthetic_case(tmp_path, 4000, extra)), chunk_size=4000)
    t = mc.draw_inputs(plan, 0, mc.chunk_seeds(plan)[0])["load_tilt_rad"]
    assert t.min() >= 0 and t.max() <= 0.06
    mean = 0.02 / math.sqrt(2 * math.pi) * (1 - math.exp(-4.5)) / (special.ndtr(3) - 0.5)
    assert t.mean() == pytest.approx(mean, abs=1e-3)


@pytest.mark.parametrize(("table", "message"), [
    ('distribution = "normal"\nmean = 0.0', "normal needs std"),
    ('distribution = "uniform"\nlow = 1.0\nhigh = 0.0', "low must be smaller than high"),
    ('distribution = "gamma"\nstd = 1.0', "distribution"),
])
def test_bad_distribution_is_a_named_error(tmp_path, table, message):
    p = tmp_path / "bad.toml"
    text = synthetic_case(tmp_path).read_text().split("[montecarlo.inputs.actuator_length_offset_m]")[0]
    p.write_text(text + "[montecarlo.inputs.actuator_length_offset_m]\n" + table + "\n")
    with pytest.raises(ModelFileError, match=message) as err:
        load_case(p)
    assert "montecarlo.inputs.actuator_length_offset_m" in str(err.value)


def test_joint_position_errors_move_the_cardans_and_the_condensed_model_refuses_them(machine):
    """An error on leg 2's base cardan adds to B_2; the leg lines then miss P*, which the condensed model
    assumes: it must refuse the machine rather than answer for the nominal one."""
    legs = [leg.model_dump() for leg in machine.legs]
    legs[1]["base_point_error_m"] = [0.0, 1e-4, 0.0]
    perturbed = machine.with_overrides({"legs": legs})
    np.testing.assert_array_equal(perturbed.base_points_m - machine.base_points_m,
                                  [[0, 0, 0], [0, 1e-4, 0], [0, 0, 0], [0, 0, 0]])
    assert machine.legs_concurrent and not perturbed.legs_concurrent
    with pytest.raises(CondensedModelError, match="do not all meet"):
        condensed.solve_linear(perturbed, np.array([POSE_A]), np.array([0, 700.0, 0, 0, 0, 0]))


def test_joint_position_error_acts_as_a_length_offset(machine, tmp_path):
    """Raising leg 1's plate cardan by e (m) with the drives held at the nominal lengths is, to first order,
    a length offset of -e . u_1 / l_1 on leg 1: the self-stress of the two must agree (linear closed form
    above, tolerance 2e-3: the geometry changes by e / l ~ 1e-4 and the solve is nonlinear)."""
    plan = mc.plan_from_case(load_case(synthetic_case(tmp_path)))
    e = np.zeros(12)
    e[1] = 2e-5  # leg 1, y
    x = {"plate_point_error_m": e, "actuator_length_offset_m": np.zeros(4)}
    worst = mc.evaluate_sample(plan, x, 0.0)
    ik = kinematics.inverse_kinematics(machine, np.array(POSE_A))
    offset = np.array([-(ik.unit_vectors[0] @ e[:3]), 0, 0, 0])
    assert worst["max_tension_n"] == pytest.approx(closed_form_peak_tension(machine, offset), rel=2e-3)


def test_fast_path_matches_the_reference_solver_per_sample():
    """evaluate_chunk (the batched fast solver; the shipped case's joint position errors as per-sample joint
    positions on the nominal model) against evaluate_sample (the Pinocchio reference solver on each sample's
    machine, stability checked) on the same draws: both solve the same equations to the Newton tolerance 1e-10
    (measured 1.3e-8 relative on the smallest outputs, the torsion of a leg near zero): tolerance 1e-6 relative,
    1e-9 of the largest value absolute."""
    from pressfit.shipped import cases_dir

    plan = mc.plan_from_case(load_case(cases_dir() / "studies" / "montecarlo_tolerances.toml"), samples=4,
                             chunk_size=4)
    assert "one model per chunk (joint position errors as per-sample joint positions)" in mc.solver_path(plan)
    seed = mc.chunk_seeds(plan)[0]
    cols, x = mc.evaluate_chunk(plan, 0, seed), mc.draw_inputs(plan, 0, seed)
    assert np.all(cols["status"] == "ok")
    for j in range(4):
        ref = mc.evaluate_sample(plan, {n: v[j] for n, v in x.items()}, float(x["load_azimuth_rad"][j]))
        for k in mc.OUTPUTS:
            if math.isfinite(ref[k]):
                np.testing.assert_allclose(cols[k][j], ref[k], rtol=1e-6, atol=1e-9 * abs(ref[k]), err_msg=k)
            else:
                assert cols[k][j] == ref[k]
