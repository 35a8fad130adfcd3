"""The simulation with n legs (issue 21 item 1, phase 3): the compiled distribution against the kinematics' preload
basis, Tsai's 3-UPU holding a pose and pressing a pin, a 5-leg machine carrying a two-dimensional preload; the
linearised loop (`pressfit control`) and the MJCF export on the 3-UPU."""

import json
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner
from n_legs import centred, ring_machine_file

from pressfit import kinematics
from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.dynamics import kernels
from pressfit.dynamics.actuators import ForceActuators, distribute, distribution
from pressfit.dynamics.control import ForceLimitedController
from pressfit.dynamics.cycle import cycle_columns, simulate_cycle
from pressfit.dynamics.insertion import plan_scenario, series_columns, simulate_insertion
from pressfit.dynamics.linearise import _apparent_vertical_mass, close_loop, linear_plant
from pressfit.dynamics.mjcf import passive_motion
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.errors import PreloadError
from pressfit.mechanics.statics import solve_equilibrium

ROOT = Path(__file__).resolve().parents[2]
TSAI = ROOT / "models" / "tsai_3upu.toml"
POSES = np.array([[0.0, 0.62, 0.0], [0.12, 0.58, -0.1], [-0.2, 0.7, 0.15]])


@pytest.mark.parametrize("legs", ["tsai", "machine", "five"])
def test_compiled_distribution_is_the_kinematics_pseudo_inverse_and_preload_basis(legs, request):
    """kernels.distribution (cofactors of legs 1, 2, 3, 3 + k, compiled) against the batched closed forms of
    pressfit.kinematics (pseudo_inverse, preload_basis): equal to round-off (1e-13; entries O(1)) on 3, 4 and 5
    legs; the basis spans A's null space (A V = 0) and its vectors are unit."""
    machine = request.getfixturevalue(legs)
    for pose in POSES:
        units = kinematics.inverse_kinematics(machine, pose).unit_vectors
        pinv, null = distribution(units)
        assert null.shape == (len(machine.legs), len(machine.legs) - 3)
        np.testing.assert_allclose(pinv, kinematics.pseudo_inverse(machine, pose), atol=1e-13)
        np.testing.assert_allclose(null, kinematics.preload_basis(machine, pose), atol=1e-13)
        np.testing.assert_allclose(units.T @ null, 0.0, atol=1e-13)
        np.testing.assert_allclose(np.linalg.norm(null, axis=0), 1.0, rtol=1e-14)


def test_tsai_holds_its_centred_pose_with_the_statics_leg_forces(tsai):
    """Tsai's 3-UPU at its centred pose (0, y, 0) under a vertical plate load F, gravity off: each leg carries
    F / (3 sin alpha) in compression (closed form, tests/n_legs.py: the load passes through P*), which the
    distribution N = -A^+ W (no preload space) commands and the elastic statics (mechanics.statics) computes; the
    rigid-leg dynamics (Pinocchio's constraint dynamics, three closures) stays at rest under it (accelerations at
    round-off, 1e-9 of F / m) and carries the tensions to the plate (axial forces at the plate cardans)."""
    pose, f = np.array([0.0, 0.62, 0.0]), 300.0
    sin_alpha, _ = centred(tsai, pose[1])
    w = np.array([0.0, -f, 0.0])  # the load on the plate (the press pushing down)
    tension = distribute(tsai, pose, -w, np.zeros(0))  # the drives push back against it
    np.testing.assert_allclose(tension, -f / (3 * sin_alpha), rtol=1e-12)
    statics = solve_equilibrium(tsai, pose, np.concatenate([w, np.zeros(3)]), linear=True).actuator_forces_n
    np.testing.assert_allclose(statics, tension, rtol=1e-9)
    rigid = rigid_leg_model(tsai, pose)
    q, v, tau = rigid.reference_q.copy(), np.zeros(rigid.model.nv), np.zeros(rigid.model.nv)
    tau[rigid.actuator_v], tau[0:3] = -tension, w
    rigid.model.gravity = pin.Motion.Zero()
    assert np.abs(rigid.accelerations(q, v, tau)).max() < 1e-9 * f / pin.computeTotalMass(rigid.model)
    np.testing.assert_allclose(rigid.leg_loads()[:, 0], tension, rtol=1e-9)


def test_five_legs_hold_a_n_equal_w_while_carrying_a_two_dimensional_preload(five):
    """A 5-leg machine (two preload vectors, amplitudes a = (60, -35) N): the controller's tensions
    N = -A^+ W + V a at its estimate balance its force W, -A N = W, to round-off (1e-12 of |W|), carry V a
    (N + A^+ W = V a) and give back a (kernels.internal_forces: (V^T V)^-1 V^T N); the rigid-leg model (five
    closures, two self-stresses) stays at rest under them with gravity off, against the same W on the plate."""
    pose, a = POSES[1], np.array([60.0, -35.0])
    rigid = rigid_leg_model(five, pose)
    rigid.model.gravity = pin.Motion.Zero()
    case = load_case(ROOT / "cases" / "paper" / "insertion.toml")
    gains = case.simulation.controller.model_copy(update={"gravity_compensation": False,
                                                            "deflection_compensation": False})
    ctrl = ForceLimitedController(machine=five, rigid=rigid, gains=gains, limiter=False, estimate_m=pose.copy(),
                                  preload_n=a)
    lengths = kinematics.inverse_kinematics(five, pose).lengths_m
    w = ctrl.command(lengths, np.zeros(5), (pose + [0.002, -0.001, 0.003], np.zeros(3)), 0.0, 1e-3)
    tension, units = ctrl.tension_n, kinematics.inverse_kinematics(five, pose).unit_vectors
    np.testing.assert_allclose(-units.T @ tension, w, atol=1e-12 * np.abs(w).max())
    basis = kinematics.preload_basis(five, pose)
    np.testing.assert_allclose(tension + kinematics.pseudo_inverse(five, pose) @ w, basis @ a, atol=1e-11)
    carried = np.empty(2)
    kernels.internal_forces(ctrl.null, tension, carried)
    np.testing.assert_allclose(carried, a, rtol=1e-12)
    q, v, tau = rigid.reference_q.copy(), np.zeros(rigid.model.nv), np.zeros(rigid.model.nv)
    tau[rigid.actuator_v], tau[0:3] = -tension, -w  # the plate loaded against the drives' force
    scale = np.abs(w).max() / pin.computeTotalMass(rigid.model)
    assert np.abs(rigid.accelerations(q, v, tau)).max() < 1e-9 * scale


def _tsai_case(tmp_path, preload: str = "a4_n = 0.0"):
    text = (ROOT / "cases" / "paper" / "insertion.toml").read_text().replace("a4_n = 100.0", preload)
    path = tmp_path / "tsai_insertion.toml"
    path.write_text(f'model = "{TSAI}"\n' + text)
    return load_case(path)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["rigid", "flexible"])
def test_tsai_presses_the_paper_pin_with_its_contact_force_settling_at_the_limit(tmp_path, model):
    """The paper's scenario (cases/paper/insertion.toml: 30 N limit, 2 mm commanded interference, ~100 N of
    elastic contact unlimited) on Tsai's 3-UPU, rigid legs and elastic legs: the run completes, the steady contact
    force settles within 2% of the 30 N limit (the limiter's steady state, paper section 4.2), the series has the
    3-leg columns and no internal force (no preload space); the flexible run's section loads are three legs'."""
    case = _tsai_case(tmp_path)
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"model": model})})
    result = simulate_insertion(case)
    assert (result.sections is None) if model == "rigid" else result.sections.shape[1:] == (3, 3, 6)
    s = result.summary
    assert result.columns == series_columns(3) and result.series.shape[1] == len(series_columns(3))
    assert "cmd_n3" in result.columns and "cmd_n4" not in result.columns and "internal_force_n" not in result.columns
    assert s["insertion_completed"] and s["settling_time_s"] is not None
    assert s["steady_insertion_force_n"] == pytest.approx(30.0, rel=0.02)
    assert s["internal_force_range_n"] == [0.0, 0.0] and len(s["peak_actuator_tension_n"]) == 3


def test_a_preload_on_tsai_is_refused_up_front(tmp_path):
    """A 3-leg machine has no preload space: a case's a4_n on it is refused before any run (PreloadError)."""
    with pytest.raises(PreloadError, match="no redundant actuation"):
        plan_scenario(_tsai_case(tmp_path, "a4_n = 50.0"))


def test_tsai_rigid_closed_loop_poles_are_the_closed_form(tsai):
    """pressfit control's rigid plant on the 3-UPU at a pose: as for the 4-UPU (tests/dynamics/test_linearise.py),
    with A A^+ = I each eigen-axis k of the apparent mass M_h has m_k tau s^4 + m_k s^3 + K_d s^2 + K_p s + K_i for
    any apparent mass; three drives and no preload direction: 3 x 4 = 12 poles (relative 1e-6)."""
    case = load_case(ROOT / "cases" / "paper" / "insertion.toml")
    gains, pose = case.simulation.controller, np.array(case.simulation.start_m)
    loop = close_loop(linear_plant(tsai, pose, None, "rigid"), gains)
    tau = ForceActuators.of(tsai).time_constant_s
    m_h, _ = _apparent_vertical_mass(tsai, pose)
    expected = np.sort_complex(np.concatenate([
        np.roots([m * tau, m, gains.kd_n_s_per_m, gains.kp_n_per_m, gains.ki_n_per_m_s])
        for m in np.linalg.eigvalsh(m_h)]))
    poles = np.sort_complex(np.linalg.eigvals(loop.a))
    assert poles.shape == expected.shape == (12,)
    assert np.max(np.abs(poles - expected) / np.abs(expected)) < 1e-6


@pytest.mark.slow
def test_control_and_export_mjcf_run_on_tsai(tmp_path):
    """`pressfit control` (flexible plant, --model flexible) and `pressfit export-mjcf` on the 3-UPU case: exit 0, the
    plant's inputs and outputs are the three drives and lengths, the loop stable, the MJCF has three welds."""
    case = _tsai_case(tmp_path)
    out = tmp_path / "control"
    result = CliRunner().invoke(main, ["control", str(case.path), "--model", "flexible", "--out", str(out)])
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "control.json").read_text())
    assert all(pose["stable"] for pose in summary["poses"])
    system = linear_plant(case.machine(), np.array(case.simulation.start_m)).system()
    assert system.ninputs == 4 and system.noutputs == 7  # n_cmd1..3, f_contact; l1..3, tool_x..z, f_contact
    mjcf = tmp_path / "tsai.xml"
    result = CliRunner().invoke(main, ["export-mjcf", "--model", str(TSAI), "--out", str(mjcf), "0", "0.62", "0"])
    assert result.exit_code == 0, result.output
    model = mujoco.MjModel.from_xml_path(str(mjcf))
    assert model.neq == 3


def test_tsai_passive_motion_agrees_in_pinocchio_and_mujoco(tsai):
    """The 3-UPU thrown upwards, passive, 0.2 s in both engines (Pinocchio's constraint dynamics and the exported
    MJCF in MuJoCo): the plate trajectories differ by the integrators' first-order errors, which halve with the time
    step (ratio 2 within 15%), and stay below 10 um (the 4-UPU's: 8 um over 0.5 s, tests/dynamics/test_mjcf.py)."""
    runs = [passive_motion(tsai, np.array([0.05, 0.62, -0.05]), (0.2, 2.0, -0.2), duration_s=0.2, timestep_s=h)
            for h in (1e-4, 5e-5)]
    coarse, fine = (run.deviation_m.max() for run in runs)
    assert np.ptp(runs[0].pinocchio_plate_m[:, 1]) > 0.1
    assert coarse < 1e-5 and coarse / fine == pytest.approx(2.0, rel=0.15)


@pytest.mark.slow
def test_five_leg_insertion_carries_its_two_amplitudes(tmp_path):
    """The paper's scenario on a 5-leg machine (Tsai's file with five legs at 72 degrees, tests/n_legs.py) with
    the 2-D preload a = (60, -35) N (`amplitudes_n`): the run completes at the 30 N limit and its internal force
    columns (leg 4's and leg 5's amplitudes, kernels.internal_forces of the delivered tensions) are a at the end of
    the dwell (1e-6: the first-order drives have converged onto the constant command there), within 0.5% all run
    (the drives' lag while V turns with the pose)."""
    machine = ring_machine_file(tmp_path / "five.toml", 5)
    text = (ROOT / "cases" / "paper" / "insertion.toml").read_text().replace("a4_n = 100.0",
                                                                              "amplitudes_n = [60.0, -35.0]")
    path = tmp_path / "five_insertion.toml"
    path.write_text(f'model = "{machine}"\n' + text)
    result = simulate_insertion(load_case(path))
    s = result.summary
    assert s["insertion_completed"] and s["steady_insertion_force_n"] == pytest.approx(30.0, rel=0.02)
    dwell = np.flatnonzero(result.phases == result.phase_names.index("dwell"))[-1]
    internal = result.series[:, [result.columns.index(c) for c in ("internal_force_n4", "internal_force_n5")]]
    np.testing.assert_allclose(internal[dwell], [60.0, -35.0], rtol=1e-6)
    np.testing.assert_allclose(internal, np.broadcast_to([60.0, -35.0], internal.shape), rtol=5e-3)
    assert s["commanded_preload_amplitudes_n"] == [60.0, -35.0] and len(s["peak_leg_axial_force_n"]) == 5


@pytest.mark.slow
def test_tsai_board_passes_its_pins_with_three_drives_sized(tmp_path):
    """Two pins of the paper's board (cases/paper/board.toml, its grid cut to 2 x 1) on the 3-UPU: both pins pass,
    the drive sizing has three drives (legs 1..3) and the energy balance closes within its tolerance (simulate_cycle
    enforces it: ResidualError otherwise)."""
    text = (ROOT / "cases" / "paper" / "board.toml").read_text()
    grid = "x = { min_m = -0.20, max_m = 0.20, count = 5 }\nz = { min_m = -0.15, max_m = 0.15, count = 4 }"
    two = "x = { min_m = -0.10, max_m = 0.10, count = 2 }\nz = { min_m = 0.0, max_m = 0.0, count = 1 }"
    text = text.replace(grid, two)
    text = text.replace("a4_n = 100.0", "a4_n = 0.0")
    path = tmp_path / "tsai_board.toml"
    path.write_text(f'model = "{TSAI}"\n' + text)
    result = simulate_cycle(load_case(path))
    s = result.summary
    assert s["pin_count"] == s["pins_passed"] == 2
    assert [d["leg"] for d in s["drives"]] == [1, 2, 3] and result.columns == cycle_columns(3)
    assert s["energy_balance_residual"] < s["energy_balance"]["tolerance"]
