"""The drives of ``[actuator] kind`` (pressfit.dynamics.drives, docs/drives.md) against closed forms derived
here: reflected inertia J (2 pi / lead)^2, ball-screw stiffness E A / L in series with nut and bearing, the oil
column's k_h = beta A^2 (1/V_a + 1/V_b) and its natural frequency against a simulated free oscillation, the
force loops' -3 dB points from simulated sines against the bandwidth their gains give, saturation at the
current and pressure limits, the force kind's first-order lag in closed form, and the statics using the drive's
stiffness (vertical stiffness at pose A against 4 k_leg sin^2 alpha)."""

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import tomli_w
from click.testing import CliRunner
from readme import assert_printed, readme_fragment

from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.description.machine import Machine, load_machine, read_toml
from pressfit.dynamics import drives
from pressfit.dynamics.actuators import ForceActuators
from pressfit.dynamics.inertia import inertial_model
from pressfit.errors import DriveStepError, ModelFileError
from pressfit.kinematics.closed_form import leg_vectors
from pressfit.mechanics import condensed
from pressfit.mechanics.fast_statics import FastEquilibriumSolver
from pressfit.mechanics.model import build_model
from pressfit.mechanics.statics import solve_equilibrium
from pressfit.shipped import cases_dir, models_dir

ELECTRIC = models_dir() / "pressfit_4upu_electric.toml"
HYDRAULIC = models_dir() / "pressfit_4upu_hydraulic.toml"
POSE_A = (0.0, 0.72, 0.0)


@pytest.fixture(scope="module")
def electric():
    return load_machine(ELECTRIC)


@pytest.fixture(scope="module")
def hydraulic():
    return load_machine(HYDRAULIC)


def _with_force_drive(path, stiffness_n_per_m=5.0e7):
    """The same machine file with the ideal force drive in place of its [actuator] table."""
    data = read_toml(path)
    data["actuator"] = {"axial_stiffness_n_per_m": stiffness_n_per_m}
    return Machine.model_validate({**data, "source": str(path)})


def _sine_gain(drive, frequency_hz, amplitude_n, length_m, periods=15, per_period=100):
    """|delivered / commanded| at each frequency (array; one leg per frequency) from a simulated sine command
    (blocked leg), least-squares fit of sin and cos over the last third of the run (the transient has decayed
    by then). One dt for all: ``per_period`` steps per period of the highest frequency, held at mid-step values."""
    f = np.asarray(frequency_hz, dtype=float)
    dt = 1.0 / (f.max() * per_period)
    n = int(periods / (f.min() * dt))
    lengths = np.full(f.shape, length_m)
    state = drive.initial_state(np.zeros(f.shape), lengths)
    out = np.empty((n, f.size))
    for k in range(n):
        state, out[k] = drive.step(state, amplitude_n * np.sin(2 * math.pi * f * (k + 0.5) * dt), lengths,
                                   np.zeros(f.shape), dt)
    t = (np.arange(n) + 1.0) * dt
    keep = slice(2 * n // 3, n)
    gains = []
    for j in range(f.size):
        w = 2 * math.pi * f[j] * t[keep]
        basis = np.column_stack([np.sin(w), np.cos(w), np.ones_like(w)])
        coef = np.linalg.lstsq(basis, out[keep, j], rcond=None)[0]
        gains.append(math.hypot(coef[0], coef[1]) / amplitude_n)
    return np.array(gains)


def _crossing(gain_of, f_lo, f_hi):
    """Frequency (Hz) where gain_of(f) falls through 1/sqrt 2, by log-linear interpolation on 9 points."""
    grid = np.geomspace(f_lo, f_hi, 9)
    g = gain_of(grid) - math.sqrt(0.5)
    k = np.flatnonzero((g[:-1] >= 0) & (g[1:] < 0))[-1]
    s = g[k] / (g[k] - g[k + 1])
    return float(np.exp(np.log(grid[k]) + s * (np.log(grid[k + 1]) - np.log(grid[k])))), grid


def _closed_form_crossing(magnitude):
    """The last 1/sqrt 2 crossing of a closed-form |T(f)| (bisection on a fine grid), Hz."""
    grid = np.geomspace(1e-2, 1e6, 200001)
    g = magnitude(grid) - math.sqrt(0.5)
    k = np.flatnonzero((g[:-1] >= 0) & (g[1:] < 0))[-1]
    lo, hi = grid[k], grid[k + 1]
    for _ in range(80):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if magnitude(np.array([mid]))[0] >= math.sqrt(0.5) else (lo, mid)
    return lo


# --- reflected inertia -----------------------------------------------------------------------------------
def test_reflected_inertia_is_the_prismatic_armature(electric):
    """M_electric - M_force = J (2 pi / lead)^2 on each actuator's diagonal entry and nothing else, with
    J = J_rotor + rho pi d^4 L / 32 (the screw a solid steel bar of the root diameter)."""
    el = electric.actuator.electric
    j_total = el.rotor_inertia_kg_m2 + electric.mass.density_kg_per_m3 * math.pi * el.screw_diameter_m**4 \
        * el.screw_length_m / 32
    expected = j_total * (2 * math.pi / el.lead_m) ** 2
    assert expected == pytest.approx(15.49, abs=0.01)  # kg per leg: 1.57e-4 kg m^2 through a 20 mm lead
    mm_e, mm_f = build_model(electric, POSE_A), build_model(_with_force_drive(ELECTRIC), POSE_A)
    me, mf = inertial_model(mm_e), inertial_model(mm_f)
    m_e = pin.crba(me, me.createData(), mm_e.q0)
    m_f = pin.crba(mf, mf.createData(), mm_f.q0)
    diff = np.triu(m_e - m_f)
    idx = [mm_e.model.joints[ids["actuator"]].idx_v for ids in mm_e.leg_joint_ids]
    np.testing.assert_allclose(np.diag(diff)[idx], expected, rtol=1e-12)
    diff[idx, idx] = 0.0
    assert np.abs(diff).max() < 1e-12 * np.abs(m_f).max()


def test_force_and_hydraulic_drives_reflect_no_inertia(machine, hydraulic):
    assert machine.drive_reflected_mass_kg == 0.0 and hydraulic.drive_reflected_mass_kg == 0.0
    assert np.all(inertial_model(build_model(hydraulic, POSE_A)).armature == 0.0)


# --- stiffness in the statics ------------------------------------------------------------------------------
def test_screw_stiffness_in_series_with_nut_and_bearing(electric):
    el, e = electric.actuator.electric, electric.material.youngs_modulus_pa
    lengths = np.array([0.5, 0.75, 1.0])
    free = 0.08 + (lengths - 0.5)  # the file's free length at the shortest leg, growing with the leg
    screw = e * math.pi * el.screw_diameter_m**2 / 4 / free
    expected = 1 / (1 / screw + 1 / el.nut_stiffness_n_per_m + 1 / el.bearing_stiffness_n_per_m)
    np.testing.assert_allclose(electric.drive_stiffness_n_per_m(lengths), expected, rtol=1e-14)
    assert expected[0] > 2.4 * expected[-1]  # 1.44e8 N/m at the shortest leg, 5.9e7 N/m at the longest
    segments = 0.45 / (e * electric.cylinder_section.area_m2) + (lengths - 0.45) / (e * electric.stem_section.area_m2)
    np.testing.assert_allclose(electric.axial_compliance_m_per_n(lengths), 1 / expected + segments, rtol=1e-14)


def test_the_sensors_see_the_tubes_and_the_drive_unless_they_read_past_it(machine, electric, hydraulic):
    """The axial compliance between a drive's position sensor and the cardans: the whole leg's for the force kind and
    the electric drive (its motor encoder sits before the ball screw), the tubes' alone, lc / (E A_c) + (l - lc) /
    (E A_s) in closed form, for the hydraulic cylinder (its piston sensor reads past the oil column)."""
    lengths = np.array([0.55, 0.75, 0.95])
    for m in (machine, electric):
        np.testing.assert_array_equal(m.sensed_axial_compliance_m_per_n(lengths), m.axial_compliance_m_per_n(lengths))
    e, lc = hydraulic.material.youngs_modulus_pa, hydraulic.cylinder.length_m
    tubes = lc / (e * hydraulic.cylinder_section.area_m2) + (lengths - lc) / (e * hydraulic.stem_section.area_m2)
    np.testing.assert_allclose(hydraulic.sensed_axial_compliance_m_per_n(lengths), tubes, rtol=1e-12)
    assert np.all(hydraulic.axial_compliance_m_per_n(lengths) > 20 * tubes)  # the oil column dominates the leg


def test_the_condensed_compliance_from_the_sensors_is_the_machine_with_a_rigid_oil_column(machine, hydraulic):
    """``condensed_plate_compliance`` of the hydraulic machine's ``sensed_view`` against a second machine: the same
    file with the oil's bulk modulus 1e6 times larger (the oil column 1e6 times stiffer), its full condensed
    compliance (to 1e-5); the sensed C_yy is 41% below the full one at the shipped end pose (the oil column's share);
    the force-kind machine's is its full compliance exactly."""
    poses = np.array([[0.0, 0.68, 0.15], [0.10, 0.60, -0.05], [-0.15, 0.65, 0.10]])
    stiff = hydraulic.with_overrides({"actuator": {"hydraulic": {"bulk_modulus_pa": 1.2e15}}})
    sensed = condensed.condensed_plate_compliance(hydraulic.sensed_view, poses)
    np.testing.assert_allclose(sensed, condensed.condensed_plate_compliance(stiff, poses), rtol=1e-5,
                               atol=1e-5 * np.abs(sensed).max())
    full = condensed.condensed_plate_compliance(hydraulic, poses)
    assert sensed[0, 1, 1] < 0.65 * full[0, 1, 1]
    assert machine.sensed_view is machine
    np.testing.assert_array_equal(condensed.condensed_plate_compliance(machine.sensed_view, poses),
                                  condensed.condensed_plate_compliance(machine, poses))


def test_oil_column_stiffness_lowest_at_mid_stroke(hydraulic):
    hy = hydraulic.actuator.hydraulic
    area = math.pi / 4 * (0.032**2 - 0.022**2)
    lengths = np.linspace(0.5, 1.0, 101)
    x = lengths - 0.5 + (0.52 - 0.5) / 2
    expected = hy.bulk_modulus_pa * area**2 * (1 / (1.5e-5 + area * (0.52 - x)) + 1 / (1.5e-5 + area * x))
    k = hydraulic.drive_stiffness_n_per_m(lengths)
    np.testing.assert_allclose(k, expected, rtol=1e-13)
    assert np.argmin(k) == 50 and k[50] == pytest.approx(3.446e6, rel=1e-3)


@pytest.mark.parametrize("path", [ELECTRIC, HYDRAULIC], ids=["electric", "hydraulic"])
def test_vertical_stiffness_at_pose_a_uses_the_drive(path):
    """At pose A a vertical force passes through P* and only stretches the legs: with rigid cardans the vertical
    stiffness is 4 k_leg sin^2 alpha, sin alpha = h / l the legs' elevation, k_leg the drive in series with the
    cylinder and stem tubes. Pinocchio's linear solve reproduces it to 1e-9 (the solver's 1e-11 accuracy)."""
    machine = load_machine(path)
    e, p, r, h = machine.material.youngs_modulus_pa, 0.442, 0.082, 0.72
    length = math.hypot(p - r, h)
    k_drive = float(machine.drive_stiffness_n_per_m(length))
    k_leg = 1 / (1 / k_drive + 0.45 / (e * machine.cylinder_section.area_m2)
                 + (length - 0.45) / (e * machine.stem_section.area_m2))
    k_vertical = 4 * k_leg * (h / length) ** 2
    eq = solve_equilibrium(machine, POSE_A, (0.0, 700.0, 0.0, 0.0, 0.0, 0.0), linear=True)
    assert eq.is_valid(1e-9)
    assert eq.plate_displacement_m[1] == pytest.approx(700.0 / k_vertical, rel=1e-9)
    # and the drive changes the answer: the force kind's 5e7 N/m gives another deflection
    force_kind = solve_equilibrium(_with_force_drive(path), POSE_A, (0.0, 700.0, 0.0, 0.0, 0.0, 0.0), linear=True)
    assert abs(force_kind.plate_displacement_m[1] / eq.plate_displacement_m[1] - 1) > 0.2


@pytest.mark.parametrize("path", [ELECTRIC, HYDRAULIC], ids=["electric", "hydraulic"])
@pytest.mark.parametrize("pose", [(0.2, 0.6, -0.15), (-0.25, 0.74, 0.25), (0.1, 0.5, 0.22)])
def test_condensed_and_fast_paths_use_the_drive_stiffness(path, pose):
    """The condensed closed form and the batched fast solver against the Pinocchio linear solve (the
    tests/mechanics/test_condensed_vs_pinocchio.py cross-check) on a machine whose drive stiffness varies with the
    stroke."""
    machine = load_machine(path)
    load = (120.0, 650.0, -80.0, 10.0, -5.0, 15.0)
    eq = solve_equilibrium(machine, pose, load, linear=True)
    assert eq.is_valid(1e-9)
    res = condensed.solve_linear(machine, pose, load)
    fast = FastEquilibriumSolver(machine, pose_m=pose).solve(pose, load, linear=True)
    scale = np.abs(res.axial_forces_n).max()
    np.testing.assert_allclose(res.axial_forces_n, eq.actuator_forces_n, atol=1e-9 * scale)
    np.testing.assert_allclose(fast.actuator_forces_n, eq.actuator_forces_n, atol=1e-9 * scale)
    for name in ("plate_displacement_m", "plate_rotation_rad"):
        ref = getattr(eq, name)
        np.testing.assert_allclose(getattr(res, name), ref, atol=1e-9 * np.linalg.norm(ref))
        np.testing.assert_allclose(getattr(fast, name), ref, atol=1e-9 * np.linalg.norm(ref))


def test_force_kind_leg_compliance_is_the_integral_along_the_leg(machine):
    """A force-kind leg's axial compliance against a second formulation: the actuator's spring in series with
    int_0^l ds / (E A(s)), integrated numerically over the stepped section (the cylinder tube from the base
    cardan for its length, the stem beyond it), at lengths on both sides of the tube's end."""
    e, lc = machine.material.youngs_modulus_pa, machine.cylinder.length_m
    area = lambda s: np.where(s < lc, machine.cylinder_section.area_m2, machine.stem_section.area_m2)
    for length in (0.55, 0.7, 1.0):
        s = np.linspace(0.0, length, 400001)
        integral = float(np.sum(0.5 * (1 / area(s[1:]) + 1 / area(s[:-1])) * np.diff(s))) / e
        expected = 1.0 / machine.actuator.axial_stiffness_n_per_m + integral
        assert machine.axial_compliance_m_per_n(np.array([length]))[0] == pytest.approx(expected, rel=1e-5)


# --- the force kind ------------------------------------------------------------------------------------------
def test_force_kind_is_the_first_order_lag_in_closed_form(machine):
    """tau dN/dt = sat(N_cmd) - N held over a step (zero-order hold) has the exact solution
    N(t) = s + (N0 - s) exp(-t / tau) with tau = 1 / (2 pi f_bw) and s the command clipped at +-force_limit_n:
    after k steps of dt, N0 relaxes by exp(-k dt / tau), whatever the split of the time into steps."""
    drive = drives.of(machine)
    assert isinstance(drive, drives.ForceDrive)
    a = machine.actuator
    tau = 1.0 / (2 * math.pi * a.force_bandwidth_hz)
    limit = a.force_limit_n
    n0 = np.array([-200.0, 0.0, 150.0, 400.0])
    command = np.array([0.5 * limit, -3.0 * limit, 2.0 * limit, -0.25 * limit])  # two inside, two clipped
    target = np.clip(command, -limit, limit)
    state, lengths, rates = drive.initial_state(n0, np.full(4, 0.7)), np.full(4, 0.7), np.zeros(4)
    elapsed = 0.0
    for dt in (1e-4, 3e-4, 2e-3, 5e-4, 1e-3) * 4:
        state, force = drive.step(state, command, lengths, rates, dt)
        elapsed += dt
        np.testing.assert_allclose(force, target + (n0 - target) * math.exp(-elapsed / tau), rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(drive.saturated(command), np.abs(command) > limit)
    lag = ForceActuators.of(machine)  # any shapes the closed form broadcasts over: its shape, the same values
    decay = math.exp(-1e-3 / tau)
    grid = np.array([[-200.0, 0.0, 150.0], [400.0, -50.0, 10.0]])
    for force, cmd in ((grid, 3.0 * limit), (np.float64(-200.0), np.array(0.5 * limit)), ([1.0, 2.0], [3.0, 4.0])):
        expected = np.clip(cmd, -limit, limit) + (np.asarray(force) - np.clip(cmd, -limit, limit)) * decay
        out = lag.step(force, cmd, 1e-3)
        assert out.shape == np.broadcast_shapes(np.shape(force), np.shape(cmd))
        np.testing.assert_allclose(out, expected, rtol=1e-14)


# --- electric --------------------------------------------------------------------------------------------------
def _pi_loop_magnitude(el):
    kp, ki, ind, res = (el.current_loop_kp_v_per_a, el.current_loop_ki_v_per_a_s, el.winding_inductance_h,
                        el.winding_resistance_ohm)

    def magnitude(f):  # i / i_ref = (kp s + ki) / (L s^2 + (R + kp) s + ki), derived in docs/drives.md
        s = 2j * math.pi * f
        return np.abs((kp * s + ki) / (ind * s**2 + (res + kp) * s + ki))
    return magnitude


@pytest.mark.parametrize("ki_factor", [1.0, 6.0], ids=["pole-zero-cancelled", "integral-heavy"])
def test_electric_force_loop_minus_3db(electric, ki_factor):
    """The delivered force's -3 dB point from simulated sine commands (blocked motor) against the closed loop of
    the PI gains on the winding: for k_i / k_p = R / L it is k_p / (2 pi L) = 1000 Hz."""
    el = electric.actuator.electric
    machine = electric.with_overrides({"actuator": {"electric": {
        "current_loop_ki_v_per_a_s": el.current_loop_ki_v_per_a_s * ki_factor}}})
    drive = drives.of(machine)
    expected = _closed_form_crossing(_pi_loop_magnitude(machine.actuator.electric))
    if ki_factor == 1.0:
        assert expected == pytest.approx(el.current_loop_kp_v_per_a / (2 * math.pi * el.winding_inductance_h),
                                         rel=1e-3)
    measured, _ = _crossing(lambda f: _sine_gain(drive, f, 100.0, 0.75), 0.7 * expected, 1.4 * expected)
    assert measured == pytest.approx(expected, rel=5e-4)  # 1.4e-5 and 1.6e-4 achieved (the 9-point interpolation)
    assert drive.bandwidth_hz == pytest.approx(expected, rel=1e-9)


def test_electric_bandwidth_form_is_first_order(electric):
    machine = electric.with_overrides({"actuator": {"electric": {
        "current_loop_kp_v_per_a": None, "current_loop_ki_v_per_a_s": None, "winding_inductance_h": None,
        "current_loop_bandwidth_hz": 250.0}}})
    drive = drives.of(machine)
    state = drive.initial_state(np.zeros(1), np.full(1, 0.7))
    state, force = drive.step(state, np.full(1, 400.0), np.full(1, 0.7), np.zeros(1), 1e-3)
    assert force[0] == pytest.approx(400.0 * (1 - math.exp(-2 * math.pi * 250.0 * 1e-3)), rel=1e-12)


def test_electric_current_limit_saturates(electric):
    """A command beyond the limit delivers at most k_f i_max = 2 pi eta K_t i_max / lead and reaches it."""
    el = electric.actuator.electric
    bound = 2 * math.pi * el.screw_efficiency * el.torque_constant_nm_per_a * el.current_limit_a / el.lead_m
    drive = drives.of(electric)
    assert drive.force_limit_n == pytest.approx(bound, rel=1e-14)
    assert bound == pytest.approx(1000.0, rel=1e-3)
    command = np.array([3.0 * bound, -3.0 * bound, 0.999 * bound, 1.001 * bound])
    np.testing.assert_array_equal(drive.saturated(command), [True, True, False, True])
    state, peak = drive.initial_state(np.zeros(4), np.full(4, 0.7)), np.zeros(4)
    for _ in range(200):
        state, force = drive.step(state, command, np.full(4, 0.7), np.zeros(4), 1e-4)
        peak = np.maximum(peak, np.abs(force))
    assert np.all(peak <= bound * (1 + 1e-12))
    np.testing.assert_allclose(force, [bound, -bound, 0.999 * bound, bound], rtol=1e-6)


def test_electric_speed_limit_stops_accelerating_torque(electric):
    """Beyond the speed limit, either way, a current that drives the motor faster is cut; one that brakes it is
    kept."""
    el = electric.actuator.electric
    drive = drives.of(electric)
    v_limit = el.speed_limit_rad_per_s * el.lead_m / (2 * math.pi)  # m/s along the leg (1.0)
    shortening = np.full(2, -1.01 * v_limit)  # omega > limit: a positive current (tension) accelerates it
    i_ref = drive.current_reference_a(np.array([500.0, -500.0]), shortening)
    assert i_ref[0] == 0.0 and i_ref[1] == pytest.approx(-500.0 / drive.force_per_current_n_per_a)
    i_ref = drive.current_reference_a(np.array([500.0, -500.0]), np.full(2, -0.99 * v_limit))
    assert i_ref[0] > 0.0
    # the mirror image: lengthening beyond the limit (omega < -limit), a negative current (compression) is cut
    i_ref = drive.current_reference_a(np.array([500.0, -500.0]), -shortening)
    assert i_ref[1] == 0.0 and i_ref[0] == pytest.approx(500.0 / drive.force_per_current_n_per_a)
    assert drive.current_reference_a(np.array([-500.0]), np.array([0.99 * v_limit]))[0] < 0.0


# --- hydraulic --------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_oil_column_natural_frequency_against_free_oscillation(hydraulic):
    """A mass m on the leg, valve closed (no loop gain, no leakage), kicked at 1 mm/s: it rings at
    sqrt(k_h / m) / (2 pi) with k_h = beta A^2 (1/V_a + 1/V_b). The run: the drive stepped with the mass by
    symplectic Euler at dt = 10 us (frequency error (omega dt)^2 / 24 ~ 5e-6); zero crossings over 10 periods."""
    machine = hydraulic.with_overrides({"actuator": {"hydraulic": {"pressure_loop_gain_per_pa": 1e-300,
                                                                   "flow_feedforward": 0.0,
                                                                   "leakage_m3_per_s_pa": 0.0}}})
    drive, mass, l0 = drives.of(machine), 3.0, 0.62
    area, hy = machine.actuator.hydraulic.area_m2, machine.actuator.hydraulic
    x = l0 - 0.5 + 0.01
    k_h = hy.bulk_modulus_pa * area**2 * (1 / (hy.dead_volume_a_m3 + area * (0.52 - x))
                                          + 1 / (hy.dead_volume_b_m3 + area * x))
    expected = math.sqrt(k_h / mass) / (2 * math.pi)
    state = drive.initial_state(np.zeros(1), np.full(1, l0))
    length, rate, dt = l0, 1e-3, 1e-5  # a 1 mm/s kick: 1 um amplitude
    times, signs = [], []
    for k in range(int(10 / expected / dt)):
        state, tension = drive.step(state, np.zeros(1), np.full(1, length), np.full(1, rate), dt)
        rate += dt * (-tension[0]) / mass  # the tension pulls the mass back toward the base
        length += dt * rate
        signs.append(length > l0)
        times.append((k + 1) * dt)
    signs = np.array(signs)
    flips = np.flatnonzero(signs[1:] != signs[:-1])
    t = np.array(times)[flips]
    measured = (len(t) - 1) / (2 * (t[-1] - t[0]))
    assert measured == pytest.approx(expected, rel=5e-4)  # 1.3e-4 achieved: crossings quantised at dt, 10 periods
    assert expected == pytest.approx(190.0, abs=0.1)  # Hz: 4.27e6 N/m at l = 0.62 m against 3 kg


def _pressure_loop_magnitude(machine, length_m):
    hy = machine.actuator.hydraulic
    area = hy.area_m2
    x = length_m - 0.5 + 0.01
    c = hy.bulk_modulus_pa * (1 / (hy.dead_volume_a_m3 + area * (0.52 - x)) + 1 / (hy.dead_volume_b_m3 + area * x))
    kq = hy.valve_flow_gain_m3_per_s_sqrt_pa * math.sqrt((hy.supply_pressure_pa - hy.tank_pressure_pa) / 2)
    wv, g, cl = 2 * math.pi * hy.valve_bandwidth_hz, hy.pressure_loop_gain_per_pa, hy.leakage_m3_per_s_pa

    def magnitude(f):  # linearised about the null, blocked piston (docs/drives.md)
        s = 2j * math.pi * f
        return np.abs(g * c * kq * wv / ((s + c * cl) * (s + wv) + g * c * kq * wv))
    return magnitude


def test_hydraulic_force_loop_minus_3db(hydraulic):
    """The delivered force's -3 dB point from small simulated sines (2 N about 0, blocked piston at mid-travel,
    the drive's own 1 ms-class substeps) against the linearised loop of valve, chambers and gain."""
    expected = _closed_form_crossing(_pressure_loop_magnitude(hydraulic, 0.75))
    assert 300.0 < expected < 400.0  # the file's 200 Hz valve and gain: a 355 Hz pressure loop at mid-stroke
    drive = drives.of(hydraulic)
    measured, _ = _crossing(lambda f: _sine_gain(drive, f, 2.0, 0.75, periods=10, per_period=40),
                            0.7 * expected, 1.4 * expected)
    assert measured == pytest.approx(expected, rel=5e-3)  # 1.2e-3 achieved: the 2 N sine is not quite linear
    assert drive.bandwidth_hz == pytest.approx(expected, rel=1e-9)


def test_hydraulic_pressure_limit_saturates(hydraulic):
    """A command beyond A (p_s - p_t) drives one chamber to supply and the other to tank: the delivered force is
    bounded by A (p_s - p_t) and (without leakage) approaches it."""
    machine = hydraulic.with_overrides({"actuator": {"hydraulic": {"leakage_m3_per_s_pa": 0.0}}})
    drive = drives.of(machine)
    hy = machine.actuator.hydraulic
    bound = math.pi / 4 * (0.032**2 - 0.022**2) * (hy.supply_pressure_pa - hy.tank_pressure_pa)
    assert drive.force_limit_n == pytest.approx(bound, rel=1e-14)
    command = np.array([5 * bound, -5 * bound])
    state, peak = drive.initial_state(np.zeros(2), np.full(2, 0.75)), np.zeros(2)
    for _ in range(500):
        state, force = drive.step(state, command, np.full(2, 0.75), np.zeros(2), 1e-3)
        peak = np.maximum(peak, np.abs(force))
    assert np.all(peak <= bound * (1 + 1e-9))
    np.testing.assert_allclose(force, [bound, -bound], rtol=1e-3)


def test_a_hydraulic_command_beyond_the_force_limit_is_the_limit(hydraulic):
    """The pressure loop takes a command beyond A (p_s - p_t) as A (p_s - p_t) (the controller cannot ask for more
    than the drive has): 3 times the limit and the limit itself, each held 5 ms on a blocked and on a moving leg,
    give the same drive states and tensions, bit for bit; a command under the limit does not."""
    drive = drives.of(hydraulic)
    limit = drive.force_limit_n
    lengths, rates = np.full(4, 0.75), np.array([0.0, 0.01, -0.01, 0.0])

    def run(command):
        state = drive.initial_state(np.zeros(4), lengths)
        for _ in range(5):
            state, force = drive.step(state, np.full(4, command), lengths, rates, 1e-3)
        return state.pressure_a_pa, state.pressure_b_pa, state.spool, force

    at, over, under = run(limit), run(3.0 * limit), run(0.9 * limit)
    for a, b in zip(at, over, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.array_equal(at[3], under[3])


def test_hydraulic_refuses_leaving_the_stroke(hydraulic):
    drive = drives.of(hydraulic)
    state = drive.initial_state(np.zeros(4), np.full(4, 0.75))
    rates = np.array([0.0, 0.0, 20.0, 0.0])  # leg 3 would run 20 mm in 1 ms from 1.0 m (10 mm of margin)
    lengths = np.array([0.75, 0.75, 1.0, 0.75])
    with pytest.raises(DriveStepError, match="leg 3: piston position x_m = 0.53 breaks the stroke"):
        drive.step(state, np.zeros(4), lengths, rates, 1e-3)


def test_closed_valve_chambers_follow_the_piston_by_the_log_law(hydraulic):
    """Valve closed (no loop gain, no feed-forward, no leakage), the piston driven out at 10 mm/s for 10 ms: each
    chamber's oil is compressed or expanded by the moving piston alone, beta dV / V, so exactly
    p_a(t) = p_a(0) + beta ln(V_a(0) / V_a(t)) and p_b(t) = p_b(0) - beta ln(V_b(t) / V_b(0)). The drive's substeps
    evaluate the volumes at each substep's midpoint (a midpoint rule on this integral): 1.3e-12 of the pressure
    change achieved; at the substep's start (a mutation, stop 36) it is 1.4e-6."""
    machine = hydraulic.with_overrides({"actuator": {"hydraulic": {"pressure_loop_gain_per_pa": 1e-300,
                                                                   "flow_feedforward": 0.0,
                                                                   "leakage_m3_per_s_pa": 0.0}}})
    hy, drive = machine.actuator.hydraulic, drives.of(machine)
    l0, rate, dt, steps = 0.7, 0.01, 1e-3, 10
    state = start = drive.initial_state(np.full(1, 200.0), np.full(1, l0))
    for k in range(steps):
        state, tension = drive.step(state, np.full(1, 200.0), np.full(1, l0 + rate * k * dt), np.full(1, rate), dt)
    x0 = float(machine.piston_position_m(l0))
    x1 = x0 + rate * steps * dt
    v_a = [hy.dead_volume_a_m3 + hy.area_m2 * (hy.stroke_m - x) for x in (x0, x1)]
    v_b = [hy.dead_volume_b_m3 + hy.area_m2 * x for x in (x0, x1)]
    dp_a, dp_b = hy.bulk_modulus_pa * math.log(v_a[0] / v_a[1]), -hy.bulk_modulus_pa * math.log(v_b[1] / v_b[0])
    assert state.pressure_a_pa[0] - start.pressure_a_pa[0] == pytest.approx(dp_a, rel=1e-9)
    assert state.pressure_b_pa[0] - start.pressure_b_pa[0] == pytest.approx(dp_b, rel=1e-9)
    assert tension[0] == pytest.approx(hy.area_m2 * (state.pressure_a_pa[0] - state.pressure_b_pa[0]), rel=1e-12)
    assert dp_a > 1e5 and dp_b < -1e5  # a real compression over the 0.1 mm travel


@pytest.mark.parametrize(("chamber", "sign"), [("a", 1.0), ("b", -1.0)])
@pytest.mark.parametrize("margin", [-1e-4, 1e-4], ids=["just under", "just over"])
def test_a_chamber_compressed_past_ten_times_supply_is_refused(hydraulic, chamber, sign, margin):
    """Both chambers at 9.9 p_s, valve closed, the piston moved in one 1 ms step by the travel that takes one chamber
    exactly to 10 p_s by the log law of the closed chambers (p = p_0 + beta ln(V_0 / V_1), the drive's substeps to
    1.3e-12): 1e-4 of that travel less passes, 1e-4 more (30 Pa over, printed with ten digits) is refused naming
    the chamber and the bound; the other chamber expands and stays far inside its own."""
    machine = hydraulic.with_overrides({"actuator": {"hydraulic": {"pressure_loop_gain_per_pa": 1e-300,
                                                                   "flow_feedforward": 0.0,
                                                                   "leakage_m3_per_s_pa": 0.0}}})
    hy, drive = machine.actuator.hydraulic, drives.of(machine)
    l0, ps = 0.7, hy.supply_pressure_pa
    x0 = float(machine.piston_position_m(l0))
    v0 = (hy.dead_volume_a_m3 + hy.area_m2 * (hy.stroke_m - x0) if chamber == "a"
          else hy.dead_volume_b_m3 + hy.area_m2 * x0)
    travel = v0 * (1.0 - math.exp(-0.1 * ps / hy.bulk_modulus_pa)) / hy.area_m2 * (1.0 + margin)  # m, + for a
    state = type(drive.initial_state(np.zeros(1), np.full(1, l0)))(
        pressure_a_pa=np.full(1, 9.9 * ps), pressure_b_pa=np.full(1, 9.9 * ps), spool=np.zeros(1))
    step = (state, np.zeros(1), np.full(1, l0), np.full(1, sign * travel / 1e-3), 1e-3)
    if margin < 0:
        after, _ = drive.step(*step)
        assert getattr(after, f"pressure_{chamber}_pa")[0] == pytest.approx(10.0 * ps, rel=2e-5)
        return
    with pytest.raises(DriveStepError, match=rf"leg 1: pressure_{chamber}_pa = 3000003\d\.?\d* breaks "
                                             r"\[-300000, 3e\+07\] Pa"):
        drive.step(*step)


@pytest.mark.parametrize("feedforward", [0.0, 1.0])
def test_the_flow_feedforward_takes_the_moving_legs_pressure_drag_away(hydraulic, feedforward):
    """Commanded zero force while the leg extends at 50 mm/s, no leakage: without feed-forward the pressure loop
    opens the valve for the leg's flow A v only through a pressure error D = p_a - p_b, a drag force A D. Steady
    state: the spool x = g D (g the loop gain), each land passing A v = K_v |x| sqrt(drop) with the chambers
    symmetric about the null (drops p_a - p_t = p_s - p_b), so D^3 + (p_s - p_t) D^2 = 2 (A v / (g K_v))^2: 80.65 N
    here (3% under the small-D estimate A^2 v / (g K_v sqrt((p_s - p_t) / 2)) = 83.3 N), matched to 1e-4. With the
    full feed-forward (``flow_feedforward = 1``) the spool opens for that flow from the measured rate and the force
    left is under 1e-4 of it."""
    machine = hydraulic.with_overrides({"actuator": {"hydraulic": {"leakage_m3_per_s_pa": 0.0,
                                                                   "flow_feedforward": feedforward}}})
    hy, drive = machine.actuator.hydraulic, drives.of(machine)
    rate, l0 = 0.05, 0.7
    state = drive.initial_state(np.zeros(1), np.full(1, l0))
    for k in range(100):  # 0.1 s: the loop settles in milliseconds
        state, force = drive.step(state, np.zeros(1), np.full(1, l0 + rate * k * 1e-3), np.full(1, rate), 1e-3)
    roots = np.roots([1.0, hy.supply_pressure_pa - hy.tank_pressure_pa, 0.0,
                      -2.0 * (hy.area_m2 * rate / (hy.pressure_loop_gain_per_pa * hy.valve_flow_gain_m3_per_s_sqrt_pa))
                      ** 2])
    drag = hy.area_m2 * float(max(r.real for r in roots if abs(r.imag) < 1e-9 * abs(r)))
    assert 50.0 < drag < 150.0
    if feedforward:
        assert abs(force[0]) < 1e-4 * drag
    else:
        assert abs(force[0]) == pytest.approx(drag, rel=1e-4)


def test_hydraulic_step_converges_at_one_millisecond(hydraulic):
    """The 1 ms caller step (10 implicit substeps) against the same run at 10 us (one substep each), 30 ms of a
    command step while the leg extends at 50 mm/s."""
    drive = drives.of(hydraulic)
    command, lengths, rates = np.full(1, 600.0), np.full(1, 0.7), np.full(1, 0.05)
    coarse = drive.initial_state(np.zeros(1), lengths)
    fine = coarse
    for k in range(30):
        coarse, f_coarse = drive.step(coarse, command, lengths + rates * k * 1e-3, rates, 1e-3)
    for k in range(30 * 100):
        fine, f_fine = drive.step(fine, command, lengths + rates * k * 1e-5, rates, 1e-5)
    assert abs(f_coarse[0] - f_fine[0]) < 2e-5 * 600.0  # 4.3e-6 achieved


# --- schema ----------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("change", "key"), [
    ({"electric": {"lead_mm": 20.0}}, "actuator.electric.lead_mm"),
    ({"electric": {"lead_m": float("nan")}}, "actuator.electric.lead_m"),
    ({"electric": {"screw_efficiency": 1.2}}, "actuator.electric.screw_efficiency"),
    ({"electric": {"screw_free_length_m": 0.3}}, "screw_free_length_m and screw_free_length_at_min_leg_m"),
    ({"electric": {"current_loop_bandwidth_hz": 800.0}}, "current_loop_bandwidth_hz"),
    ({"axial_stiffness_n_per_m": 5e7}, "axial_stiffness_n_per_m belongs to kind = \"force\""),
    ({"force_limit_n": 900.0}, "force_limit_n belongs to kind = \"force\""),
    ({"kind": "hydraulic"}, "needs the table [actuator.hydraulic]"),
])
def test_electric_table_is_strict(electric, change, key):
    with pytest.raises(ModelFileError, match=key.replace("[", r"\[").replace("]", r"\]").replace(".", r"\.")):
        electric.with_overrides({"actuator": change})


@pytest.mark.parametrize(("change", "key"), [
    ({"stroke_m": 0.45}, "stroke_m must be at least the leg travel"),
    ({"piston_area_m2": 4e-4}, "piston_area_m2 or bore_diameter_m and rod_diameter_m, not both"),
    ({"rod_diameter_m": 0.04}, "rod_diameter_m must be smaller than bore_diameter_m"),
    ({"tank_pressure_pa": 3.5e6}, "tank_pressure_pa must be below supply_pressure_pa"),
    ({"bulk_modulus_pa": -1.0}, "actuator.hydraulic.bulk_modulus_pa"),
])
def test_hydraulic_table_is_strict(hydraulic, change, key):
    with pytest.raises(ModelFileError, match=key):
        hydraulic.with_overrides({"actuator": {"hydraulic": change}})


def test_force_kind_refuses_a_drive_table(machine, electric, tmp_path):
    with pytest.raises(ModelFileError, match=r"\[actuator\.electric\] is given but kind = \"force\""):
        machine.with_overrides({"actuator": {"electric": electric.actuator.electric.model_dump()}})
    text = (models_dir() / "pressfit_4upu.toml").read_text()
    path = tmp_path / "no_stiffness.toml"
    path.write_text(text.replace("axial_stiffness_n_per_m = 5.0e7\n", ""))
    with pytest.raises(ModelFileError, match="no_stiffness.toml: key 'actuator'.*axial_stiffness_n_per_m is required"):
        load_machine(path)


def test_registry_picks_the_kind(machine, electric, hydraulic):
    assert [drives.of(m).kind for m in (machine, electric, hydraulic)] == ["force", "electric", "hydraulic"]
    for m in (machine, electric, hydraulic):
        d = drives.of(m)
        np.testing.assert_array_equal(d.axial_stiffness_n_per_m(np.array([0.6, 0.9])),
                                      m.drive_stiffness_n_per_m(np.array([0.6, 0.9])))


# --- shipped files ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["electric", "hydraulic"])
def test_shipped_insertion_cases_load_their_drive(kind):
    """The shipped drive cases load with their drive kind; `pressfit check` passes them (their waypoints statically
    and their simulation against its limits): tests/studies/test_envelope.py::test_shipped_cases_pass_and_example_fails;
    simulate runs them on the drive seam: tests/dynamics/test_insertion_drives.py."""
    case = load_case(cases_dir() / "paper" / f"insertion_{kind}.toml")
    assert case.machine().actuator.kind == kind


def _modes_json(path_or_machine, tmp_path=None):
    if tmp_path is not None:  # a machine object: through its file, as a user would
        path_or_machine = tmp_path / "machine.toml"
    result = CliRunner().invoke(main, ["modes", "0", "0.72", "0", "--model", str(path_or_machine), "--json",
                                       "--count", "12"])
    assert result.exit_code == 0, result.output
    return np.array(json.loads(result.output)["frequencies_hz"])


def _as_force_kind(path, tmp_path, stiffness_n_per_m):
    """The machine file with its drive table replaced by the force kind's spring of the given stiffness."""
    data = tomllib.loads(Path(path).read_text())
    data["actuator"] = {"kind": "force", "axial_stiffness_n_per_m": float(stiffness_n_per_m)}
    (tmp_path / "machine.toml").write_text(tomli_w.dumps(data))


def test_modes_of_a_hydraulic_machine_are_those_of_its_equivalent_spring(hydraulic, tmp_path):
    """A second formulation of the hydraulic machine's modes: at the centre pose every leg has one length, so the
    oil column is one spring k_h(l) (no reflected mass: the piston's mass is in [mass]); the force kind with
    axial_stiffness_n_per_m = k_h(l) is the same linear system and must give the same frequencies."""
    length = float(np.linalg.norm(leg_vectors(hydraulic, np.array([0.0, 0.72, 0.0]))[0]))
    _as_force_kind(HYDRAULIC, tmp_path, hydraulic.drive_stiffness_n_per_m(np.array([length]))[0])
    np.testing.assert_allclose(_modes_json(HYDRAULIC), _modes_json(None, tmp_path), rtol=1e-6)


def test_an_electric_drives_reflected_mass_lowers_every_mode(electric, tmp_path):
    """The electric drive is its screw's spring plus a reflected mass on each leg's prismatic joint. The same
    spring without the mass (the force kind) has a mass matrix smaller by a positive semi-definite term and the
    same stiffness, so by Courant-Fischer every natural frequency of the electric machine is lower or equal,
    and the plunge mode (the prismatic joints move) strictly lower."""
    length = float(np.linalg.norm(leg_vectors(electric, np.array([0.0, 0.72, 0.0]))[0]))
    _as_force_kind(ELECTRIC, tmp_path, electric.drive_stiffness_n_per_m(np.array([length]))[0])
    with_mass, without = _modes_json(ELECTRIC), _modes_json(None, tmp_path)
    assert np.all(with_mass <= without * (1 + 1e-9)), (with_mass, without)
    assert np.min(with_mass / without) < 0.95, (with_mass, without)


def test_readme_drive_numbers(electric, hydraulic):
    """The README's drive paragraph, computed (closed forms above; the bandwidths from the drives' loops)."""
    readme_fragment("(15.5 kg reflected per leg, 1000 N, a 1 kHz current loop)")
    assert_printed(electric.drive_reflected_mass_kg, "15.5")
    assert_printed(electric.actuator.drive_force_limit_n, "1000")
    assert_printed(drives.of(electric).bandwidth_hz / 1e3, "1")
    readme_fragment("(3.45e6 N/m at mid-stroke, 1188 N, a 355 Hz force loop)")
    assert_printed(float(hydraulic.drive_stiffness_n_per_m(0.75)), "3.45e6")
    assert_printed(hydraulic.actuator.drive_force_limit_n, "1188")
    assert_printed(_closed_form_crossing(_pressure_loop_magnitude(hydraulic, 0.75)), "355")


@pytest.mark.slow
def test_electric_back_emf_is_rejected_by_the_current_loop_integral(electric):
    """A leg moving at a constant rate with no force commanded: the motor's back-EMF e = K_t omega is a voltage
    step on the winding, L di/dt = v - R i - e with v = k_p (i_ref - i) + k_i z, z' = i_ref - i. From
    I(s) = -(e / s) s / (L s^2 + (R + k_p) s + k_i) the current returns to zero (integral action) after a
    transient whose charge is int i dt = I(s)|_{s -> 0} = -e / k_i (derived here). Without the EMF term the
    current would stay 0: the drive would deliver no force transient at all while the leg moves."""
    el = electric.actuator.electric
    drive = drives.of(electric)
    rate = np.array([-0.05, -0.02, 0.02, 0.05])  # m/s, well inside the speed limit
    omega = drive.motor_speed_rad_per_s(rate)
    assert np.all(np.abs(omega) < el.speed_limit_rad_per_s)
    dt, steps = 1e-6, 30000  # 30 ms: ~190 time constants of the 1 kHz loop
    state, charge, previous = drive.initial_state(np.zeros(4), np.full(4, 0.7)), np.zeros(4), np.zeros(4)
    peak = np.zeros(4)
    for _ in range(steps):
        state, _ = drive.step(state, np.zeros(4), np.full(4, 0.7), rate, dt)
        charge += 0.5 * (previous + state.current_a) * dt
        previous = state.current_a
        peak = np.maximum(peak, np.abs(state.current_a))
    expected = -el.torque_constant_nm_per_a * omega / el.current_loop_ki_v_per_a_s
    np.testing.assert_allclose(charge, expected, rtol=1e-3)
    assert np.all(peak > 0) and np.all(np.abs(state.current_a) < 1e-3 * peak)  # the transient has died out
