"""The load envelope, the preload study and the Monte Carlo study with n legs (issue 21), on Tsai's 3-UPU and a
5-leg machine. References, derived in the tests (tests/n_legs.py): at the centred pose a vertical force F gives
every leg F / (n sin(alpha)); without preload each leg's two cardan plays g let the plate drop by
2 g / sin(alpha) (lost motion, any n); the mirror x -> -x maps the 3-UPU onto itself with legs 2 and 3 swapped; a
3-leg machine is statically determinate, so actuator length errors stress nothing and the self-stress (the
forces' projection on the preload space) is zero."""

import math
from pathlib import Path

import numpy as np
import pytest
from n_legs import centred, ring_machine_file

from pressfit.description.cases import load_case
from pressfit.errors import PreloadError
from pressfit.mechanics.preload import along_first_vector, self_stress_forces_n
from pressfit.studies import montecarlo, preload_study, workspace_envelope

ROOT = Path(__file__).resolve().parents[2]
F_N, Y, G = 700.0, 0.6, 20e-6


@pytest.mark.parametrize("which", ["tsai", "five"])
def test_envelope_tension_at_the_centre_is_the_closed_form(request, which):
    """The press load alone: the worst tension over the legs at the grid's centre column (x = z = 0) is
    F / (n sin(alpha)) (1e-9: the condensed model is exact there); per-leg entries are n wide."""
    m = request.getfixturevalue(which)
    n = len(m.legs)
    env = workspace_envelope.load_envelope(m, [Y], n_xz=5, loads_n=np.array([[0.0, F_N, 0.0]]))
    sa, _ = centred(m, Y)
    assert env.maps["tension_n"][2, 2] == pytest.approx(F_N / (n * sa), rel=1e-9)
    assert env.entries["tension_n"].value.shape == (n,) and env.entries["tension_n"].pose_m.shape == (n, 3)
    header, rows = workspace_envelope.envelope_rows(env)
    assert sorted({r[2] for r in rows if r[0] == "tension_n"}) == list(range(1, n + 1))


def test_tsai_envelope_is_mirror_symmetric(tsai):
    """x -> -x maps the square and the 3-UPU onto themselves, legs 2 and 3 swapped: equal worst tensions and
    bending, at mirrored poses (1e-9 relative)."""
    env = workspace_envelope.load_envelope(tsai, [0.55, 0.65], n_xz=9)
    for k in ("tension_n", "bending_nm", "torsion_nm"):
        e = env.entries[k]
        assert e.value[1] == pytest.approx(e.value[2], rel=1e-9)
        np.testing.assert_allclose(e.pose_m[2] * [-1, 1, 1], e.pose_m[1], atol=1e-12)


def test_tsai_preload_study_lost_motion_and_no_preload(tsai):
    """The 3-UPU with 20 um of play: lost motion 2 g / sin(alpha) = 46.6 um at (0, 0.6, 0) (rel 1e-4: the
    smoothing width), no critical preload (stated), and any preload other than 0 refused (PreloadError)."""
    s = preload_study.preload_study(tsai, [0.0, Y, 0.0], [G], [0.0], F_N, 50, progress=False)
    sa, _ = centred(tsai, Y)
    (answer,) = s.answers()
    assert answer["lost_motion_without_preload_m"] == pytest.approx(2 * G / sa, rel=1e-4) and 2 * G / sa > 0
    assert math.isnan(answer["critical_preload"]) and answer["first_sufficient_preload"] is None
    assert preload_study.NO_CRITICAL_PRELOAD in preload_study.format_answers(s)
    with pytest.raises(PreloadError, match="no redundant actuation") as info:
        preload_study.preload_study(tsai, [0.0, Y, 0.0], [G], [100.0], F_N, 50, progress=False)
    assert info.value.redundancy == 0


def test_five_leg_preload_study_runs_along_the_first_basis_vector(five):
    """A 5-leg machine: the study's one preload number a is the amplitude along the first basis vector
    (a unit self-stress times a in which leg 4 pulls and leg 5 carries nothing: the basis's definition); its lost
    motion without preload is 2 g / sin(alpha) (rel 1e-4), and a preload stiffens the small-load secant (legs
    1-4 closed)."""
    a = along_first_vector(five, 300.0)
    forces = self_stress_forces_n(five, np.array([0.0, Y, 0.0]), a)
    assert a == (300.0, 0.0) and np.linalg.norm(forces) == pytest.approx(300.0, rel=1e-12)
    assert forces[3] > 0 and forces[4] == 0.0
    s = preload_study.preload_study(five, [0.0, Y, 0.0], [G], [300.0], F_N, 50, progress=False)
    sa, _ = centred(five, Y)
    assert s.lost_motion_m[0, 0] == pytest.approx(2 * G / sa, rel=1e-4)
    assert s.small_load_secant_stiffness_n_per_m[0, 1] > 1.5 * s.small_load_secant_stiffness_n_per_m[0, 0]


def _plan(tmp_path, machine_file: Path, preload: str = ""):
    text = (ROOT / "cases" / "studies" / "montecarlo_tolerances.toml").read_text()
    path = tmp_path / "case.toml"
    path.write_text(f'model = "{machine_file}"\n' + preload + text)
    return montecarlo.plan_from_case(load_case(path), samples=6, chunk_size=6)


def test_tsai_monte_carlo_columns_and_no_self_stress(tmp_path, tsai):
    """The 3-UPU: input columns leg1..leg3 (3 offsets, 9 + 9 joint errors, the tilt), zero self-stress in every
    sample, and length errors alone leave the tensions of the nominal machine (statically determinate: the
    geometry moves by ~1e-5 m on 0.7 m legs, tolerance 1e-4 relative)."""
    plan = _plan(tmp_path, ROOT / "models" / "tsai_3upu.toml")
    columns = plan.input_columns()
    assert len(columns) == 3 + 9 + 9 + 1 and "actuator_length_offset_m.leg3" in columns
    assert not any(".leg4" in c for c in columns)
    out = montecarlo.evaluate_chunk(plan, 0, montecarlo.chunk_seed(plan, 0))
    assert list(out["status"]) == ["ok"] * 6
    np.testing.assert_allclose(out["internal_force_n"], 0.0, atol=1e-9)
    only_lengths = {"actuator_length_offset_m": np.array([2e-5, -3e-5, 1e-5])}
    nominal = montecarlo.evaluate_sample(plan, {"actuator_length_offset_m": np.zeros(3)}, 0.0)
    offset = montecarlo.evaluate_sample(plan, only_lengths, 0.0)
    assert offset["max_tension_n"] == pytest.approx(nominal["max_tension_n"], rel=1e-4)
    assert offset["internal_force_n"] == nominal["internal_force_n"] == 0.0


def test_five_leg_monte_carlo_preload_amplitudes(tmp_path):
    """A 5-leg machine file: the Monte Carlo case takes two preload amplitudes a (one is refused up front,
    PreloadError); input columns are 5 wide; at the centred pose under a vertical press load the self-stress
    |P N| is |V a| (the load's leg forces, all F / (5 sin(alpha)), lie in the range of A^T, orthogonal to the
    preload space; the nonlinear solve moves the geometry by ~1e-5: tolerance 1e-4 relative)."""
    machine_file = ring_machine_file(tmp_path / "five.toml", 5)
    case = ('name = "five-mc"\n[poses]\npoints_m = [[0.0, 0.6, 0.0]]\n[loads]\npress_force_n = 700.0\n'
            'direction = [0.0, 1.0, 0.0]\n[montecarlo]\nsamples = 3\nseed = 1\nchunk_size = 3\n'
            '[montecarlo.inputs.actuator_length_offset_m]\ndistribution = "normal"\nmean = 0.0\nstd = 1e-12\n')
    path = tmp_path / "case.toml"
    path.write_text(f'model = "{machine_file}"\n' + case + "[preload]\namplitudes_n = [300.0, -150.0]\n")
    plan = montecarlo.plan_from_case(load_case(path))
    assert plan.input_columns() == [f"actuator_length_offset_m.leg{i}" for i in range(1, 6)]
    out = montecarlo.evaluate_chunk(plan, 0, montecarlo.chunk_seed(plan, 0))
    assert list(out["status"]) == ["ok"] * 3
    v_a = self_stress_forces_n(plan.machine, np.array([0.0, 0.6, 0.0]), (300.0, -150.0))
    np.testing.assert_allclose(out["internal_force_n"], np.linalg.norm(v_a), rtol=1e-4)
    path.write_text(f'model = "{machine_file}"\n' + case + "[preload]\na4_n = 300.0\n")
    with pytest.raises(PreloadError, match="give 2 preload amplitudes"):
        montecarlo.plan_from_case(load_case(path))
