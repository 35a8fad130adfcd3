"""The direct-drive linear motor (pressfit.dynamics.drives.linear_motor) against closed forms, and the drive
registry it was added through (pressfit.description.machine.DRIVE_TABLES, pressfit.dynamics.drives.DRIVES).

Reference values: the step response of the PI current loop's transfer function (kp s + ki) / (L s^2 + (R + kp) s
+ ki) computed by scipy.signal (an independent integration of the continuous loop; the drive's ZOH update is exact
at the samples), the first-order thermal model's closed forms (1 - 1/e at t = tau; the periodic steady state of a
square loss wave solved by hand from the geometric series), the ripple's formula evaluated at chosen phases, and
the machine file's numbers for the ratings."""

import json
import math
import tomllib
import typing
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner
from scipy import signal

from pressfit.cli import main
from pressfit.description.machine import DRIVE_TABLES, Actuator, load_machine
from pressfit.dynamics import drives
from pressfit.dynamics.drives.linear_motor import (
    RIPPLE_HARMONIC,
    LinearMotorDrive,
    periodic_winding_rise_k,
    winding_rise_k,
)
from pressfit.dynamics.sizing import drive_sizing

ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / "models/pressfit_4upu_linear_motor.toml"
CASE = ROOT / "cases/paper/insertion_linear_motor.toml"
NO_RIPPLE = {"actuator": {"linear_motor": {"force_ripple_fraction": 0.0, "cogging_force_n": 0.0}}}


@pytest.fixture(scope="module")
def machine():
    return load_machine(MODEL)


@pytest.fixture(scope="module")
def smooth():
    return drives.of(load_machine(MODEL, NO_RIPPLE))


def test_registry_keys_are_the_schema_tables():
    kinds = typing.get_args(Actuator.model_fields["kind"].annotation)
    assert set(kinds) == set(DRIVE_TABLES)
    assert set(drives.DRIVES) == set(DRIVE_TABLES.values())
    tabled = {name for name, table in DRIVE_TABLES.items() if not table.inline}
    assert tabled <= set(Actuator.model_fields)
    assert "linear_motor" in DRIVE_TABLES


def test_the_machine_file_selects_the_linear_motor_and_its_statics(machine):
    t = machine.actuator.linear_motor
    assert isinstance(drives.of(machine), LinearMotorDrive)
    assert machine.actuator.drive_force_limit_n == pytest.approx(100.0 * 10.0, rel=1e-15)  # K_f i_max
    assert machine.drive_reflected_mass_kg == 2.0  # the forcer, as the joint's armature
    np.testing.assert_array_equal(machine.drive_stiffness_n_per_m(np.array([0.5, 0.9])), [2e8, 2e8])
    e = machine.material.youngs_modulus_pa  # series: mount + cylinder + stem
    l, lc = 0.7, machine.cylinder.length_m
    expected = 1 / 2e8 + lc / (e * machine.cylinder_section.area_m2) + (l - lc) / (e * machine.stem_section.area_m2)
    assert machine.axial_compliance_m_per_n(l) == pytest.approx(expected, rel=1e-14)
    assert t.thermal_resistance_k_per_w * t.winding_resistance_ohm * (t.continuous_force_n / 100.0) ** 2 \
        == pytest.approx(89.6)  # the continuous force is the thermal limit (the file's comment)


@pytest.mark.parametrize("gains", ["cancelling", "not cancelling"])
def test_the_force_loop_step_is_the_pi_loops_closed_form(gains):
    """Blocked leg, a force step of 500 N: N(t) = K_f i(t), i(t) the step response of the PI loop."""
    over = {"current_loop_ki_v_per_a_s": 90000.0} if gains == "not cancelling" else {}
    m = load_machine(MODEL, {"actuator": {"linear_motor": {**NO_RIPPLE["actuator"]["linear_motor"], **over}}})
    t = m.actuator.linear_motor
    drive = drives.of(m)
    dt, steps, command = 2e-5, 100, 500.0
    state = drive.initial_state(np.zeros(1), np.full(1, 0.7))
    forces = []
    for _ in range(steps):
        state, f = drive.step(state, np.full(1, command), np.full(1, 0.7), np.zeros(1), dt)
        forces.append(f[0])
    loop = signal.lti([t.current_loop_kp_v_per_a, t.current_loop_ki_v_per_a_s],
                      [t.winding_inductance_h, t.winding_resistance_ohm + t.current_loop_kp_v_per_a,
                       t.current_loop_ki_v_per_a_s])
    times = dt * np.arange(1, steps + 1)
    _, unit = signal.step(loop, T=np.concatenate([[0.0], times]))
    expected = command * unit[1:]
    np.testing.assert_allclose(forces, expected, rtol=0, atol=3e-6 * command)
    if gains == "cancelling":  # first order, k_p / (L s + k_p): 1 - 1/e at t = L / k_p
        tau = t.winding_inductance_h / t.current_loop_kp_v_per_a
        assert drive.bandwidth_hz == pytest.approx(1 / (2 * math.pi * tau), rel=1e-6)


def test_the_thermal_time_constant():
    """A constant current: the rise reaches (1 - 1/e) R_th R i^2 at t = tau (exact ZOH of tau T' = R_th P - T)."""
    r_th, tau, power = 1.4, 300.0, 4.0 * 5.0**2
    rise = winding_rise_k(np.full(3000, power), 0.1, r_th, tau)
    assert rise[-1] == pytest.approx((1 - math.exp(-1)) * r_th * power, rel=1e-12)
    assert rise[-1] / (r_th * power) == pytest.approx(0.632, abs=5e-4)


def test_the_periodic_steady_state_is_the_geometric_series():
    """A square loss wave P0 for T1, 0 for T2: T_s = R_th P0 (1 - e^-T1/tau) e^-T2/tau / (1 - e^-(T1+T2)/tau) at the
    start of a period, peak T_s e^-T1/tau + R_th P0 (1 - e^-T1/tau) at the end of the on-time."""
    r_th, tau, p0, dt, n1, n2 = 1.4, 300.0, 64.0, 0.5, 40, 80
    t1, t2 = n1 * dt, n2 * dt
    power = np.concatenate([np.full(n1, p0), np.zeros(n2)])
    rise = periodic_winding_rise_k(power, dt, r_th, tau)
    start = r_th * p0 * (1 - math.exp(-t1 / tau)) * math.exp(-t2 / tau) / (1 - math.exp(-(t1 + t2) / tau))
    peak = start * math.exp(-t1 / tau) + r_th * p0 * (1 - math.exp(-t1 / tau))
    assert rise.max() == pytest.approx(peak, rel=1e-12)
    assert rise[-1] == pytest.approx(start, rel=1e-12)  # it ends where it started: periodic
    cold = winding_rise_k(power, dt, r_th, tau)
    assert cold.max() < rise.max()


def test_the_force_ripple_formula(machine):
    """N = K_f i (1 + eps cos(k l)) + F_cog sin(k l), k = 2 pi 3 / tau_p: at k l = 0 and pi/2, and period tau_p / 3."""
    drive, t = drives.of(machine), machine.actuator.linear_motor
    k = 2 * math.pi * RIPPLE_HARMONIC / t.pole_pitch_m
    i = np.array([5.0])
    assert drive.force_n(i, np.array([0.0]))[0] == pytest.approx(100.0 * 5.0 * 1.01, rel=1e-14)
    quarter = np.array([math.pi / 2 / k])
    assert drive.force_n(i, quarter)[0] == pytest.approx(500.0 + 8.0, rel=1e-12)
    lengths = np.linspace(0.5, 0.52, 7)
    np.testing.assert_allclose(drive.force_n(i, lengths + t.pole_pitch_m / 3), drive.force_n(i, lengths), atol=1e-9)
    ripple = drive.force_n(np.full(2001, 5.0), np.linspace(0.5, 0.53, 2001)) - 500.0
    assert np.ptp(ripple) / 2 == pytest.approx(math.hypot(5.0, 8.0), rel=1e-4)  # amplitude of a cos + b sin
    state = drive.initial_state(np.array([300.0]), quarter)  # at rest delivering 300 N: the inverse
    assert drive.force_n(state.current_a, quarter)[0] == pytest.approx(300.0, rel=1e-14)


def test_a_step_delivers_the_ripple_at_the_end_of_its_travel(machine):
    """A step of dt from length l at rate v returns the force of its new current at l + v dt, the pole's phase the
    leg reaches (the flexible step evaluates the drive at its end lengths): a quarter ripple period of travel in one
    step moves the phase by pi / 2, so the force at the start's phase is another (by 3.9 N at this length)."""
    drive, t = drives.of(machine), machine.actuator.linear_motor
    k = 2 * math.pi * RIPPLE_HARMONIC / t.pole_pitch_m
    start, dt = np.array([0.6]), 1e-3
    rate = np.array([math.pi / 2 / k / dt])  # a quarter period in the step
    state, tension = drive.step(drive.initial_state(np.array([300.0]), start), np.array([300.0]), start, rate, dt)
    end = start + rate * dt
    np.testing.assert_allclose(tension, drive.force_n(state.current_a, end), rtol=0, atol=1e-12)
    assert abs(tension[0] - drive.force_n(state.current_a, start)[0]) > 1.0  # the start's phase: 3.9 N off here


def test_the_encoder_quantises_the_measured_length(machine):
    drive = drives.of(machine)
    lengths = np.random.default_rng(3).uniform(0.5, 1.0, 1000)
    measured = drive.measure_lengths_m(lengths)
    assert np.max(np.abs(measured - lengths)) <= 0.5e-6 + 1e-15
    np.testing.assert_allclose(measured / 1e-6, np.round(measured / 1e-6), atol=1e-6)
    assert drive.measure_lengths_m(np.array([0.7000004]))[0] == pytest.approx(0.7, abs=1e-15)
    assert drives.of(load_machine(ROOT / "models/pressfit_4upu_electric.toml")).measure_lengths_m(lengths) is lengths


def test_the_sizing_tables_rate_the_motor(machine):
    """N = N0 (constant) at v0: i = N0 / K_f, copper R i^2, rise R_th R i^2 (1 - e^-T/tau) cold, R_th R i^2 periodic
    (a constant loss repeated is steady), RMS force against the continuous force."""
    t, dt, n = machine.actuator.linear_motor, 0.01, 6000
    n0, v0 = 300.0, -0.25
    sizing = drive_sizing(np.full((n, 4), n0), np.full((n, 4), v0), dt, drives.of(machine))
    d = sizing[0]
    loss = t.winding_resistance_ohm * (n0 / 100.0) ** 2
    assert d.drive.rms_current_a == pytest.approx(3.0, rel=1e-12)
    assert d.drive.copper_loss_w == pytest.approx(loss, rel=1e-12)
    assert d.drive.peak_winding_rise_k == pytest.approx(1.4 * loss * (1 - math.exp(-n * dt / 300.0)), rel=1e-10)
    assert d.drive.periodic_winding_rise_k == pytest.approx(1.4 * loss, rel=1e-10)
    ratings = {r.figure: r for r in d.ratings}
    assert ratings["rms_force_n"].ratio == pytest.approx(300.0 / 400.0, rel=1e-12)
    assert ratings["peak_force_n"].rating == pytest.approx(1000.0)
    assert ratings["peak_speed_m_per_s"].ratio == pytest.approx(0.25 / 2.0, rel=1e-12)
    assert ratings["periodic_winding_rise_k"].ratio == pytest.approx(1.4 * loss / 90.0, rel=1e-10)
    record = d.to_dict()
    assert record["periodic_winding_rise_k"] == d.drive.periodic_winding_rise_k
    assert d.electric is None and d.hydraulic is None


def test_an_unknown_drive_kind_is_one_error_line_naming_the_key_and_the_file(tmp_path):
    text = MODEL.read_text().replace('kind = "linear_motor"', 'kind = "stepper"')
    bad = tmp_path / "machine.toml"
    bad.write_text(text)
    case = tmp_path / "case.toml"
    case.write_text(CASE.read_text().replace('"../../models/pressfit_4upu_linear_motor.toml"', f'"{bad}"'))
    res = CliRunner().invoke(main, ["simulate", str(case)])
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert "actuator.kind" in lines[0] and str(bad) in lines[0] and "linear_motor" in lines[0]


@pytest.mark.slow
def test_control_linearises_the_linear_motor_case():
    """The shipped gains (x1.5 the force case's) keep every pose stable; the vertical mass carries the four forcers
    (2 kg each, as armature) above the force drive's (no reflected mass) at the pin."""
    res = CliRunner().invoke(main, ["control", str(CASE), "--model", "rigid", "--json"])
    assert res.exit_code == 0, res.output
    poses = json.loads(res.output)["poses"]
    assert poses and all(p["stable"] for p in poses)
    force = CliRunner().invoke(main, ["control", str(ROOT / "cases/paper/insertion.toml"), "--model", "rigid",
                                      "--json"])
    pin = next(p for p in json.loads(force.output)["poses"] if p["name"] == "pin")
    assert poses[0]["name"] == "pin" and poses[0]["vertical_mass_kg"] > pin["vertical_mass_kg"] + 2.0


def _board(tmp_path: Path) -> Path:
    text = (ROOT / "cases/paper/board.toml").read_text()
    text = text.replace('name = "paper-board"', f'name = "lm-board"\nmodel = "{MODEL}"')
    text = text.replace("x = { min_m = -0.20, max_m = 0.20, count = 5 }\nz = { min_m = -0.15, max_m = 0.15, "
                        "count = 4 }\n\n[cycle.motion]",
                        "x = { min_m = -0.10, max_m = 0.10, count = 2 }\nz = { min_m = 0.0, max_m = 0.0, "
                        "count = 1 }\n\n[cycle.motion]")
    path = tmp_path / "board.toml"
    path.write_text(text)
    return path


@pytest.mark.slow
def test_cycle_sizes_the_linear_motor(tmp_path):
    res = CliRunner().invoke(main, ["cycle", str(_board(tmp_path)), "--no-progress", "--json"])
    assert res.exit_code in (0, 1), res.output
    assert "periodic_winding_rise_k" in res.output


@pytest.mark.slow
def test_simulate_prints_the_linear_motors_winding_and_sizing(tmp_path):
    """`pressfit simulate` on the shipped linear-motor case, shortened (0.5 s moves, 0.3 s dwell) and on the rigid
    model (what is asserted is what the command prints, which both models print alike): the winding and the drive
    sizing reported. The shipped case itself, whole, on its own model, is simulated against its limits by
    `pressfit check` (tests/studies/test_envelope.py::test_shipped_cases_pass_and_example_fails)."""
    data = tomllib.loads(CASE.read_text())
    data["model"] = str(MODEL)
    data["simulation"].update({"move_time_s": 0.5, "descent_time_s": 0.5, "dwell_s": 0.3, "settle_s": 0.2,
                               "model": "rigid"})
    path = tmp_path / "linear_motor.toml"
    path.write_text(tomli_w.dumps(data))
    res = CliRunner().invoke(main, ["simulate", str(path), "--no-progress"])
    assert res.exit_code == 0, res.output
    assert "winding" in res.output and "drive sizing" in res.output


@pytest.mark.parametrize("compensation", [0.0, 0.5, 1.0])
def test_the_ripple_compensation_leaves_its_complement(compensation):
    """Blocked at a length where sin(k l) = cos(k l) = 1/sqrt 2, held at N_cmd until the loop settles: the delivered
    tension is (N_cmd - c F s) (1 + eps s) / (1 + c eps s) + F s, s = 1/sqrt 2 (N_cmd exactly at c = 1)."""
    m = load_machine(MODEL, {"actuator": {"linear_motor": {"ripple_compensation": compensation}}})
    t, drive = m.actuator.linear_motor, drives.of(m)
    length = np.array([0.5 + (math.pi / 4) / drive.wavenumber_per_m])  # k l = pi/4 (mod 2 pi: 0.5 m = 50 periods)
    length = np.array([round(length[0] / 1e-6) * 1e-6])  # on an encoder count, so that it measures it exactly
    s, c = math.sin(drive.wavenumber_per_m * length[0]), math.cos(drive.wavenumber_per_m * length[0])
    state, command = drive.initial_state(np.zeros(1), length), 300.0
    for _ in range(200):
        state, force = drive.step(state, np.full(1, command), length, np.zeros(1), 1e-4)
    eps, cog = t.force_ripple_fraction, t.cogging_force_n
    expected = (command - compensation * cog * s) * (1 + eps * c) / (1 + compensation * eps * c) + cog * s
    assert force[0] == pytest.approx(expected, rel=1e-9)
    assert abs(s - math.sqrt(0.5)) < 1e-3
