"""The linearised insertion loop (pressfit.dynamics.linearise, pressfit control): closed forms derived here."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.dynamics.actuators import ForceActuators
from pressfit.dynamics.linearise import (
    _apparent_vertical_mass,
    _bandwidth_hz,
    close_loop,
    linear_plant,
    structural_modes,
)
from pressfit.dynamics.modes import elastic_stiffness, natural_modes, reduced_system

SHIPPED = Path(__file__).resolve().parents[2] / "cases" / "paper" / "insertion.toml"


def test_rigid_closed_loop_poles_match_the_closed_form():
    """Rigid legs, no contact, at the scenario's start pose. With A A^+ = I the Cartesian loop is
    M_h h'' = D(s) C(s) (r - h), D = 1 / (tau s + 1) the drives, C = K_d s + K_p + K_i / s; in the eigenbasis of
    the apparent mass M_h (eigenvalues m_k) each axis has the characteristic polynomial
    m_k tau s^4 + m_k s^3 + K_d s^2 + K_p s + K_i, and the fourth drive (along v_p, which moves nothing) keeps
    its pole -1 / tau: 3 x 4 + 1 = 13 poles."""
    case = load_case(SHIPPED)
    machine, gains = case.machine(), case.simulation.controller
    pose = np.array(case.simulation.start_m)
    loop = close_loop(linear_plant(machine, pose, None, "rigid"), gains)
    tau = ForceActuators.of(machine).time_constant_s
    m_h, _ = _apparent_vertical_mass(machine, pose)
    expected = [-1.0 / tau]
    for m in np.linalg.eigvalsh(m_h):
        expected.extend(np.roots([m * tau, m, gains.kd_n_s_per_m, gains.kp_n_per_m, gains.ki_n_per_m_s]))
    poles = np.sort_complex(np.linalg.eigvals(loop.a))
    expected = np.sort_complex(np.array(expected))
    assert poles.shape == expected.shape == (13,)
    assert np.max(np.abs(poles - expected) / np.abs(expected)) < 1e-6


def test_contact_spring_adds_its_stiffness_at_the_pin():
    """Rigid legs in contact, drives and controller left out: the vertical plant is M_h h'' + k_c e_y e_y^T h = 0
    with the other two axes free; its nonzero eigenvalue is omega^2 = k_c (M_h^-1)_yy."""
    case = load_case(SHIPPED)
    machine, c = case.machine(), case.simulation.contact
    pin_pose = np.array([c.pin_position_m[0], c.board_height_m, c.pin_position_m[1]])
    plant = linear_plant(machine, pin_pose, c, "rigid")
    ev = np.linalg.eigvals(plant.a[:6, :6])
    omega = np.max(np.abs(ev))
    assert omega == pytest.approx(np.sqrt(c.stiffness_n_per_m / plant.vertical_mass_kg), rel=1e-9)


def test_control_without_simulation_table_exits_2(tmp_path):
    case = tmp_path / "nosim.toml"
    case.write_text('name = "x"\n[poses]\npoints_m = [[0.0, 0.65, 0.0]]\n[loads]\nforce_n = [0.0, 10.0, 0.0]\n')
    r = CliRunner().invoke(main, ["control", str(case), "--model", "rigid"])
    assert r.exit_code == 2
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and "[simulation]" in lines[0] and "nosim.toml" in lines[0]


def test_control_missing_file_exits_2(tmp_path):
    r = CliRunner().invoke(main, ["control", str(tmp_path / "none.toml"), "--model", "rigid"])
    assert r.exit_code == 2 and len(r.output.strip().splitlines()) == 1


@pytest.mark.slow
def test_unstable_controller_is_reported_not_refused(tmp_path):
    """K_d = 0 with the integrator: per axis m tau s^4 + m s^3 + K_p s + K_i has no s^2 term, so by Routh it
    has right-half-plane roots: reported as UNSTABLE, exit 0."""
    text = SHIPPED.read_text().replace("kd_n_s_per_m = 1.0e3", "kd_n_s_per_m = 0.0")
    case = tmp_path / "unstable.toml"
    case.write_text(text)
    r = CliRunner().invoke(main, ["control", str(case), "--model", "rigid"])
    assert r.exit_code == 0, r.output
    assert "UNSTABLE" in r.output


@pytest.mark.slow
def test_control_writes_its_files(tmp_path):
    """What the files hold, against closed forms: each pole s = sigma + j omega_d in poles.csv has
    frequency |s| / (2 pi) and damping -sigma / |s|; one pole of each conjugate pair is listed (a real system);
    a pose called stable in control.json has every pole in the open left half-plane; control.json's poles are
    the CSV's; bode.png is an image. A second run into the same directory is refused (exit 2), the files kept."""
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["control", str(SHIPPED), "--model", "rigid", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in out.iterdir()) == ["bode.png", "control.json", "poles.csv"]
    rows = list(csv.DictReader((out / "poles.csv").open()))
    summary = json.loads((out / "control.json").read_text())
    assert {row["pose"] for row in rows} == {p["name"] for p in summary["poses"]}
    for pose in summary["poses"]:
        mine = [row for row in rows if row["pose"] == pose["name"]]
        s = np.array([float(row["real_per_s"]) + 1j * float(row["imag_rad_per_s"]) for row in mine])
        np.testing.assert_allclose([float(row["frequency_hz"]) for row in mine], np.abs(s) / (2 * np.pi), rtol=1e-12)
        np.testing.assert_allclose([float(row["damping"]) for row in mine], -s.real / np.abs(s), rtol=1e-12)
        assert np.all(s.imag >= 0)  # a real system: one pole of each conjugate pair is listed
        assert pose["stable"] == bool(np.all(s.real < 0)), pose["name"]
        loop = [row for row in mine if row["loop_pole"] == "1"]
        np.testing.assert_allclose(sorted(float(row["real_per_s"]) for row in loop),
                                   sorted(p["real_per_s"] for p in pose["loop_poles"]), rtol=1e-12)
    assert (out / "bode.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    before = (out / "control.json").read_bytes()
    again = CliRunner().invoke(main, ["control", str(SHIPPED), "--model", "rigid", "--out", str(out)])
    assert again.exit_code == 2 and "error:" in again.output and "--overwrite" in again.output, again.output
    assert (out / "control.json").read_bytes() == before


def test_drives_hold_most_of_the_axial_mode_and_little_of_the_rocking_pair(machine):
    """The drives' share of each mode's strain energy (module doc), at pose A: the plate twist (80 Hz) stretches no
    leg, so the share is 0 to round-off (by the machine's symmetry: the twist turns every plate cardan
    perpendicular to its leg); the rocking pair sways and tilts about the legs' concurrency point, where a rigid
    rotation changes no leg length, so only the legs' bending is left (measured 0.0117); the vertical mode
    (386 Hz) is the plate and the stems moving along the legs on the actuator springs, but the inclined legs
    (26.6 degrees from vertical at A: 0.45 of the plate's vertical motion is across each leg) also
    swing, and the swinging mass loads the legs in bending. Why the share is 0.748, not the 0.970 of the old
    masses: the stem is now the 0.60 m rod it is, 0.245 m of it inside the cylinder at A with the actuator's
    moving parts (0.8 kg) at its inner end, and in the VJM chain that part rides on the actuator body, a rigid
    extension of the cylinder's last segment: its transverse inertia acts 0.19 m behind the last cylinder spring
    and bends the cylinder (measured: cylinder springs 0.189, stem springs 0.063 of the mode's strain energy; with
    the moving parts removed the share is 0.952, with the inner rod and the moving parts lumped at the gland 0.986).
    A rod guided in the bore passes that load into the cylinder where the piston sits; the chain cannot (one
    prismatic joint between the cylinder's springs and the stem's), so the bending share is an upper bound and the
    claim asserted is the one that holds for both: the drives hold most of the mode's strain energy (> 0.6, the
    other modes < 0.03) and it is the mode with the largest share. An independent share: the energy fraction
    from the model's own stiffness matrix restricted to the actuator coordinates, phi^T K_act phi / phi^T K phi,
    with omega^2 (mass-normalised shapes) as the denominator instead: equal to 1e-9."""
    modes = structural_modes(machine, np.array([0.0, 0.72, 0.0]), count=12)
    share = np.array([m.drive_energy_fraction for m in modes])
    f = np.array([m.frequency_hz for m in modes])
    assert f[0] == pytest.approx(f[1], rel=1e-9)  # the rocking pair
    assert 0.005 < share[0] < 0.03 and share[1] == pytest.approx(share[0], rel=1e-6)
    assert share[2] < 1e-12  # the twist
    axial = int(np.argmax(share))
    assert share[axial] > 0.6 and 350 < f[axial] < 450
    assert np.all(np.delete(share, axial) < 0.03)
    ref = natural_modes(machine, np.array([0.0, 0.72, 0.0]), count=12)
    omega2 = (2 * np.pi * ref.frequencies_hz) ** 2
    rs = reduced_system(machine, np.array([0.0, 0.72, 0.0]))
    k = np.diag(elastic_stiffness(rs.mm, rs.q))
    act = [sp.idx_v for sp in rs.mm.springs if sp.name == "actuator"]
    by_omega = np.sum(k[act] * ref.shapes[:, act] ** 2, axis=1) / omega2
    np.testing.assert_allclose(share, by_omega, rtol=1e-9, atol=1e-15)


def test_frequency_responses_by_laubs_method_hold_against_a_refined_solve():
    """python-control evaluates a state-space frequency response by Laub's method when Slycot is installed (one
    Hessenberg reduction, then O(n^2) per frequency: ``pressfit control`` on the flexible model 4x faster); it must
    be installed (a silent fallback would only be slower), and its answer is held against the definition
    C (j w I - A)^-1 B + D solved here densely with three steps of iterative refinement (residuals in extended
    precision: converged to ~1e-11), on the flexible loop at the pin (a few hundred states, cond(j w I - A) up to
    1e14): measured within 1e-5 relative (Laub's method loses what the condition costs; the margins and bandwidths
    are printed to 4 digits), asserted to 1e-4."""
    import control as ct

    from pressfit.dynamics.linearise import axis_loop

    assert ct.exception.slycot_check()
    case = load_case(SHIPPED)
    c = case.simulation.contact
    pin = np.array([c.pin_position_m[0], c.board_height_m, c.pin_position_m[1]])
    sys = axis_loop(close_loop(linear_plant(case.machine(), pin, c, "flexible"), case.simulation.controller), 1)
    assert sys.nstates > 200
    w = 2 * np.pi * np.array([0.3, 5.0, 27.0, 140.0])
    laub = np.asarray(ct.frequency_response(sys, w).complex).reshape(-1)
    for x, value in zip(w, laub, strict=True):
        m = 1j * x * np.eye(sys.nstates) - sys.A
        sol = np.linalg.solve(m, sys.B)
        for _ in range(3):
            residual = sys.B.astype(np.clongdouble) - m.astype(np.clongdouble) @ sol.astype(np.clongdouble)
            sol = sol + np.linalg.solve(m, residual.astype(complex))
        exact = (sys.C @ sol + sys.D)[0, 0]
        assert abs(value - exact) <= 1e-4 * abs(exact), (x, value, exact)


@pytest.mark.slow
def test_control_with_the_plays_on_says_it_linearises_without_them(tmp_path):
    """[simulation] clearance = true: the linearised loop has no dead zone in it, and says so (a warning at the
    pin pose); without clearance no such line (the rest of the design is the same either way)."""
    text = SHIPPED.read_text().replace("clearance = false", "clearance = true")
    assert text != SHIPPED.read_text()
    case = tmp_path / "plays.toml"
    case.write_text(text)
    r = CliRunner().invoke(main, ["control", str(case), "--model", "rigid"])
    assert r.exit_code == 0, r.output
    assert "linearised without the cardan plays" in r.output
    plain = CliRunner().invoke(main, ["control", str(SHIPPED), "--model", "rigid"])
    assert "linearised without the cardan plays" not in plain.output


@pytest.mark.parametrize(("name", "expected"), [("insertion.toml", "rigid"), ("insertion_fast.toml", "flexible")])
def test_control_defaults_to_the_cases_model(monkeypatch, name, expected):
    """issue 28 item 8: without --model, `pressfit control` linearises the case's [simulation] model (insertion.toml:
    rigid, insertion_fast.toml: flexible, as their files say), at every pose; the design says which."""
    import types

    from pressfit.dynamics import linearise

    seen = []
    monkeypatch.setattr(linearise, "design_at", lambda *a, **k: seen.append(a[5]) or types.SimpleNamespace())
    case = load_case(SHIPPED.parent / name)
    design = linearise.control_design(case)
    assert case.simulation.model == expected and design.model == expected and seen == [expected] * 4
    assert linearise.control_design(case, "rigid").model == "rigid" and seen[-1] == "rigid"
    assert "default: the case's [simulation] model" in CliRunner().invoke(main, ["control", "--help"]).output


def test_the_bandwidth_is_the_first_3_db_drop_below_the_dc_gain():
    """``_bandwidth_hz`` (python-control's grid, Brent's refinement): a first-order lag 1 / (1 + s / w0) drops 3 dB at
    w0 sqrt(10^0.3 - 1) (closed form), to 1e-10; a lightly damped second-order system with a resonant peak (its
    first crossing beyond the peak) agrees with python-control's own ``bandwidth`` (bisection) to 1e-9; an all-pass
    (s - a) / (s + a) never drops: inf, nor does an integrator's infinite DC gain; a negative DC gain: the drop of its
    magnitude."""
    import math

    import control as ct

    w0 = 2 * math.pi * 3.0
    lag = ct.ss(ct.tf([1.0], [1.0 / w0, 1.0]))
    assert _bandwidth_hz(lag) == pytest.approx(w0 * math.sqrt(10**0.3 - 1) / (2 * math.pi), rel=1e-10)
    resonant = ct.ss(ct.tf([w0**2], [1.0, 0.1 * w0, w0**2]))
    assert _bandwidth_hz(resonant) == pytest.approx(ct.bandwidth(resonant) / (2 * math.pi), rel=1e-9)
    assert _bandwidth_hz(resonant) > w0 / (2 * math.pi)  # past the peak, not at the first frequency below it
    assert _bandwidth_hz(ct.ss(ct.tf([1.0, -5.0], [1.0, 5.0]))) == math.inf
    assert _bandwidth_hz(ct.ss(ct.tf([1.0], [1.0, 0.0]))) == math.inf  # an integrator: infinite DC gain
    assert _bandwidth_hz(ct.ss(ct.tf([-1.0], [1.0 / w0, 1.0]))) == pytest.approx(_bandwidth_hz(lag), rel=1e-10)


def test_a_bandwidth_below_the_grids_first_frequency_is_bracketed_from_zero(monkeypatch):
    """A grid starting above the crossing (python-control's frequency range made to start at 10 w0): the drop is
    bracketed by w = 0, where the gain is the DC gain (ct.bandwidth would index the grid at -1), and found at the
    first-order lag's closed form w0 sqrt(10^0.3 - 1)."""
    import math

    import control as ct
    import control.freqplot

    w0 = 2 * math.pi * 3.0
    monkeypatch.setattr(control.freqplot, "_default_frequency_range", lambda sys: np.logspace(1, 3, 50) * w0)
    lag = ct.ss(ct.tf([1.0], [1.0 / w0, 1.0]))
    assert _bandwidth_hz(lag) == pytest.approx(w0 * math.sqrt(10**0.3 - 1) / (2 * math.pi), rel=1e-10)
