"""The insertion simulation (issue 11 items 4-7): actuators, force distribution, length-based pose estimate,
contact with series compliance, and the scenario of Figures 13-14 with and without the force limiter."""

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner

from pressfit import kinematics
from pressfit.cli import main
from pressfit.description.cases import Contact, load_case
from pressfit.dynamics.actuators import ForceActuators, distribute
from pressfit.dynamics.contact import contact_force_n, solve_contact
from pressfit.dynamics.control import estimate_pose
from pressfit.dynamics.insertion import simulate_insertion
from pressfit.errors import ModelFileError
from pressfit.mechanics.condensed import condensed_plate_compliance

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "cases/paper/insertion.toml"
RNG_POSES = np.random.default_rng(7).uniform([-0.2, 0.5, -0.2], [0.2, 0.72, 0.2], (20, 3))


def test_actuator_step_response_time_constant():
    """First-order lag (definition): a step reaches 1 - 1/e of its value after tau = 1 / (2 pi f_bw). Measured
    from a simulated step (dt = 1e-5 s, linear interpolation between samples): within 1% (achieved 1e-9)."""
    drives = ForceActuators(40.0, 1000.0)
    dt, force, t, trace = 1e-5, np.zeros(4), [0.0], [0.0]
    for k in range(2000):
        force = drives.step(force, np.full(4, 100.0), dt)
        t.append((k + 1) * dt)
        trace.append(force[0])
    tau = np.interp(100.0 * (1 - math.exp(-1)), trace, t)
    assert tau == pytest.approx(1 / (2 * math.pi * 40.0), rel=0.01)


def test_actuator_bandwidth_is_minus_3_db():
    """At the 40 Hz bandwidth the steady response to a sinusoidal command has amplitude 1/sqrt(2) (first-order
    |H(j omega_bw)|); measured over the last two periods of a 0.5 s run at dt = 1e-5 s: within 2% (achieved
    1e-4, the sampling of the peak)."""
    drives = ForceActuators(40.0, 1000.0)
    dt, force, trace = 1e-5, np.zeros(1), []
    for k in range(50_000):
        force = drives.step(force, np.array([100.0 * math.sin(2 * math.pi * 40.0 * k * dt)]), dt)
        trace.append(force[0])
    assert max(trace[-5000:]) / 100.0 == pytest.approx(1 / math.sqrt(2), rel=0.02)


def test_actuator_saturates_at_its_limit():
    """A command above the limit is delivered at the limit, never above (the drive's saturation)."""
    drives = ForceActuators(40.0, 500.0)
    force = np.zeros(4)
    for _ in range(2000):
        force = drives.step(force, np.array([2000.0, -2000.0, 100.0, 0.0]), 1e-4)
        assert np.all(np.abs(force) <= 500.0)
    np.testing.assert_allclose(force, [500.0, -500.0, 100.0, 0.0], atol=1e-6)
    assert drives.saturated(np.array([501.0, 0.0])).tolist() == [True, False]


def test_distribution_reproduces_the_cartesian_force_and_preload_is_internal(machine):
    """Equation 5: the actuators exert -A N on the plate (tension positive); N = -A^+ W + a4 v_p gives -A N = W
    to round-off, and the preload part alone gives A N = 0 (v_p in A's null space, equations 9-10)."""
    w = np.array([12.0, -30.0, 7.0])
    for pose in RNG_POSES:
        a = kinematics.static_matrix(machine, pose)
        np.testing.assert_allclose(-a @ distribute(machine, pose, w, 150.0), w, atol=1e-12 * 150)
        preload = distribute(machine, pose, np.zeros(3), 150.0)
        assert np.linalg.norm(preload) == pytest.approx(150.0, rel=1e-12)
        np.testing.assert_allclose(a @ preload, 0.0, atol=1e-12 * 150)


def test_pose_estimate_inverts_the_closed_form_lengths(machine):
    """Round trip through equation 1: the lengths of a pose, estimated from a guess 1 cm off by Gauss-Newton,
    give the pose back within 1e-10 m (quadratic convergence: 4 iterations reach round-off)."""
    for pose in RNG_POSES:
        lengths = kinematics.inverse_kinematics(machine, pose).lengths_m
        estimate, units, residual = estimate_pose(machine, lengths, pose + [0.01, -0.01, 0.01], iterations=4)
        np.testing.assert_allclose(estimate, pose, atol=1e-10)
        np.testing.assert_allclose(units, kinematics.inverse_kinematics(machine, pose).unit_vectors, atol=1e-10)
        assert residual < 1e-12


def test_contact_in_series_with_a_spring_is_the_series_stiffness():
    """Two springs in series (closed form): a rigid interference d_r against contact stiffness k in series with
    a structure compliance c gives F = k d_r / (1 + k c); the saturating press-fit law adds F_fit tanh(d/d_fit)."""
    contact = Contact(board_height_m=0.6, pin_position_m=[0.0, 0.0], stiffness_n_per_m=5e4)
    c = 2e-5
    state = solve_contact(contact, np.array([0.0, 0.599, 0.0]), lambda f: np.array([0.0, c * f, 0.0]), 0.0, 1e-3)
    assert state.force_n == pytest.approx(5e4 * 1e-3 / (1 + 5e4 * c), rel=1e-8)
    assert state.force_n == pytest.approx(contact_force_n(contact, state.depth_m), rel=1e-8)
    assert solve_contact(contact, np.array([0.0, 0.601, 0.0]), lambda f: np.zeros(3), 0.0, 1e-3).force_n == 0.0
    fit = Contact(board_height_m=0.6, pin_position_m=[0.0, 0.0], stiffness_n_per_m=1e4, law="press_fit",
                  fit="saturating", fit_force_n=20.0, fit_depth_m=1e-3)
    assert contact_force_n(fit, 2e-3) == pytest.approx(1e4 * 2e-3 + 20.0 * math.tanh(2.0), rel=1e-12)


def short_case(tmp_path, **simulation):
    """The shipped scenario, shortened for the test suite (same contact, gains and step)."""
    data = tomllib.loads(SHIPPED.read_text())
    data["simulation"].update({"move_time_s": 0.5, "descent_time_s": 0.6, "dwell_s": 1.5,
                               **simulation})
    path = tmp_path / "insertion.toml"
    path.write_text(tomli_w.dumps(data))
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    case = load_case(short_case(tmp_path_factory.mktemp("insertion")))
    return case, simulate_insertion(case, limiter=True), simulate_insertion(case, limiter=False)


def test_limiter_keeps_the_contact_force_under_the_limit(runs):
    """Figure 14: with the limiter the peak contact force stays within 30 N plus 2 N (the overshoot measured
    at dt = 1e-3 s is 0.5-0.6 N: the tool meets the board at under 10 mm/s and the loop's damping acts through
    the clamp) and the steady force is the limit (the reference back-off integrates the force error: 0.1%);
    without the limiter the force exceeds the limit three times."""
    case, limited, free = runs
    limit = case.simulation.controller.force_limit_n
    assert limited.summary["peak_contact_force_n"] <= limit + 2.0
    assert limited.summary["steady_insertion_force_n"] == pytest.approx(limit, rel=1e-3)
    assert free.summary["peak_contact_force_n"] > 3 * limit


def test_without_limiter_the_steady_force_is_the_series_stiffness_times_interference(runs):
    """The PID drives the length-based estimate, i.e. the rigid plate, to the reference 2 mm below the board;
    the structure (vertical compliance C_yy of the condensed model) is in series with the contact, so the
    steady force is k i / (1 + k C_yy) (closed form, within 1%: the integrator's residual error after the dwell, 0.5% here)
    and equals the contact law at the depth reached (the solver's consistency, 1e-6)."""
    case, _, free = runs
    sim, s = case.simulation, free.summary
    c_yy = condensed_plate_compliance(case.machine(), np.array([0.10, 0.60, -0.05]))[1, 1]
    k = sim.contact.stiffness_n_per_m
    assert s["steady_insertion_force_n"] == pytest.approx(k * sim.interference_m / (1 + k * c_yy), rel=0.01)
    assert s["steady_insertion_force_n"] == pytest.approx(s["contact_law_at_steady_depth_n"], rel=1e-6)


def test_scenario_tracks_and_keeps_the_loops_closed(runs):
    """The tool ends within 0.1 mm of end_m (PID with an exact gravity feed-forward; achieved 5 um), the loop
    closures drift less than 3e-5 m (Baumgarte stabilisation at dt = 1e-3 s; achieved 1.1e-5 m in this faster
    copy, 2.4e-6 m in the shipped scenario) and no actuator saturates (peak tensions ~210 N against the
    1000 N limit)."""
    for result in runs[1:]:
        s = result.summary
        assert s["tool_final_error_m"] < 1e-4
        assert s["max_closure_drift_m"] < 3e-5
        assert s["actuator_saturation_time_s"] == 0.0 and max(s["peak_actuator_tension_n"]) < 1000.0


def test_simulate_cli_json_files_and_bad_input(tmp_path):
    path = short_case(tmp_path, dwell_s=0.3)
    args = ["simulate", str(path), "--json", "--no-progress", "--out", str(tmp_path / "o")]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert {"peak_contact_force_n", "overshoot_n", "max_insertion_depth_m", "tool_final_error_m",
            "tool_lateral_error_at_insertion_m", "max_closure_drift_m", "actuator_saturation_time_s",
            "steady_insertion_force_n", "limiter"} <= set(out)
    assert {p.name for p in (tmp_path / "o").iterdir()} == {"simulation.csv", "simulation.json", "simulation.png"}
    again = CliRunner().invoke(main, ["simulate", str(path), "--no-progress", "--out", str(tmp_path / "o")])
    assert again.exit_code == 2 and "exists" in again.output
    for bad in (tmp_path / "missing.toml", ROOT / "cases/paper/A.toml", short_case(tmp_path, time_step_s=-1.0)):
        res = CliRunner().invoke(main, ["simulate", str(bad), "--no-progress"])
        assert res.exit_code == 2 and res.output.startswith("error:"), res.output


def test_simulation_table_is_strict(tmp_path):
    with pytest.raises(ModelFileError, match="simulation.contact.stiffnes"):
        load_case(short_case(tmp_path, contact={"board_height_m": 0.6, "pin_position_m": [0.0, 0.0],
                                                "stiffnes_n_per_m": 1.0}))


def test_contact_damping_in_series_is_the_backward_difference_closed_form():
    """F = k d + b d_dot with the rate taken backward (d_dot = (d - d_prev) / dt) in series with a compliance
    c (closed form): F = ((k + b/dt) d_r - b d_prev / dt) / (1 + c (k + b/dt)); a damped contact pushes harder
    while the tool enters (b d_dot > 0) and never pulls while it leaves fast (no adhesion: F = 0 although the
    interference is positive)."""
    k, b, c, dt = 5e4, 400.0, 2e-5, 1e-3
    contact = Contact(board_height_m=0.6, pin_position_m=[0.0, 0.0], stiffness_n_per_m=k, damping_n_s_per_m=b)
    rigid_depth, previous = 1e-3, 0.3e-3  # the tool enters: d = 0.34 mm after the step
    state = solve_contact(contact, np.array([0.0, 0.6 - rigid_depth, 0.0]), lambda f: np.array([0.0, c * f, 0.0]),
                          previous, dt)
    keff = k + b / dt
    assert state.force_n == pytest.approx((keff * rigid_depth - b * previous / dt) / (1 + c * keff), rel=1e-8)
    undamped = Contact(board_height_m=0.6, pin_position_m=[0.0, 0.0], stiffness_n_per_m=k)
    assert state.force_n > solve_contact(undamped, np.array([0.0, 0.6 - rigid_depth, 0.0]),
                                         lambda f: np.array([0.0, c * f, 0.0]), previous, dt).force_n
    leaving = solve_contact(contact, np.array([0.0, 0.6 - 0.1e-3, 0.0]), lambda f: np.zeros(3), 0.5e-3, dt)
    assert leaving.force_n == 0.0 and leaving.depth_m > 0.0
