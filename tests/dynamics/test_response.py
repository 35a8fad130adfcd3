"""Tool-point response (pressfit.dynamics.response): the modal closed form against independent computations.

Sources: the condensed closed-form compliance (mechanics/condensed.py, exact for rigid cardans: docs/conventions.md)
for the static limit; a direct time integration of the reduced equations of motion (scipy's Radau, no modal
decomposition) for the step response; the machine's x -> -x mirror plane for symmetry."""

import json

import numpy as np
import pytest
from click.testing import CliRunner
from readme import assert_printed, readme_fragment
from scipy.integrate import solve_ivp
from scipy.linalg import eigh

from pressfit.cli import main
from pressfit.dynamics.modes import natural_modes, reduced_system
from pressfit.dynamics.response import tool_response
from pressfit.errors import PressfitError
from pressfit.mechanics.condensed import condensed_plate_compliance

OFF_CENTRE = np.array([0.0, 0.6, 0.2])
STEP_N = np.array([0.0, -100.0, 0.0])
NO_LOAD = np.zeros(6)


@pytest.mark.parametrize("pose", [[0.0, 0.72, 0.0], [0.0, 0.6, 0.2], [0.15, 0.55, -0.2]])
def test_static_limit_is_the_condensed_closed_form(machine, pose):
    """Unloaded (the reduced system about the nominal pose), the sum of the modal statics and the receptance at
    0.01 Hz equal the closed-form plate compliance times the force. Achieved 4e-11 (static) and 2e-7
    (receptance, the omega^2 / omega_1^2 ~ 1e-7 dynamic term at 0.01 Hz): tolerances 1e-9 and 1e-6; the
    receptance's imaginary part is the damping's 2 zeta omega / omega_k <= 2 zeta f / f_1 of it."""
    force = np.array([30.0, -100.0, 20.0])
    r = tool_response(machine, np.array(pose), force, duration_s=0.05, plate_wrench=NO_LOAD,
                      frequency_range_hz=(0.01, 100.0), frequency_count=10)
    c = condensed_plate_compliance(machine, np.array(pose))[:3, :3]
    ref = c @ force
    assert np.linalg.norm(r.static_m - ref) <= 1e-9 * np.linalg.norm(ref)
    h0 = r.receptance_m_per_n[0]
    assert np.abs(h0.real - c).max() <= 1e-6 * np.abs(c).max()
    assert np.abs(h0.imag).max() <= 2 * 0.02 * 0.01 / r.modes_hz[0] * np.abs(c).max()


def test_step_response_matches_a_direct_time_integration(machine):
    """The closed-form modal step response equals Radau integration of M_r z'' + C_r z' + K_r z = G^T F with
    C_r = M_r X diag(2 zeta omega) X^T M_r (the same modal damping, assembled as a matrix), at every 20th
    sample over 0.1 s. Achieved 2e-7 of the peak; tolerance 2e-6 (the integrator's rtol 1e-8 on a stiff
    196-state system)."""
    zeta = 0.02
    r = tool_response(machine, OFF_CENTRE, STEP_N, duration_s=0.1, damping_ratio=zeta)
    rs = reduced_system(machine, OFF_CENTRE)
    omega2, x = eigh(rs.stiffness, rs.mass_kg)
    m, k = rs.mass_kg, rs.stiffness
    c = m @ x @ np.diag(2 * zeta * np.sqrt(omega2)) @ x.T @ m
    g = rs.plate_map[:3]
    f = g.T @ STEP_N
    minv = np.linalg.inv(m)
    n = m.shape[0]

    def rhs(_t, s):
        return np.concatenate([s[n:], minv @ (f - c @ s[n:] - k @ s[:n])])

    jac = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ k, -minv @ c]])
    t = r.time_s[::20]
    sol = solve_ivp(rhs, (0.0, t[-1]), np.zeros(2 * n), method="Radau", t_eval=t, rtol=1e-8, atol=1e-14,
                    jac=jac)
    u = (g @ sol.y[:n]).T
    peak = np.abs(r.displacement_m).max()
    assert np.abs(u - r.displacement_m[::20]).max() <= 2e-6 * peak


def test_off_centre_vertical_step_rings_at_the_rocking_mode(machine):
    """Off-centre a vertical force tilts and sways the plate (docs/conventions.md): the dominant mode is the
    rocking mode of `pressfit modes` (its 2nd mode here, 26.2 Hz), the lateral response overshoots its static
    value (nearly 2x for light damping: a single mode's step peak is 1 + exp(-pi zeta / sqrt(1 - zeta^2)) =
    1.94 at zeta = 0.02, the other modes add ~1%), and the ringing's period measured from the zero crossings of
    u - u_static equals 1 / f_d of that mode to 0.5%."""
    r = tool_response(machine, OFF_CENTRE, STEP_N, duration_s=0.5)
    modes = natural_modes(machine, OFF_CENTRE, count=2)
    assert r.dominant_frequency_hz == pytest.approx(modes.frequencies_hz[1], rel=1e-9)
    s = r.summary()
    single = 1 + np.exp(-np.pi * 0.02 / np.sqrt(1 - 0.02**2))
    assert s["peak_lateral_m"] / s["static_lateral_m"] == pytest.approx(single, rel=0.02)
    dz = r.displacement_m[:, 2] - r.static_m[2]
    crossings = r.time_s[np.flatnonzero(np.sign(dz[1:]) != np.sign(dz[:-1]))]
    period = 2 * np.median(np.diff(crossings[2:]))
    assert 1 / period == pytest.approx(r.dominant_frequency_hz * np.sqrt(1 - 0.02**2), rel=5e-3)
    assert any(abs(p / r.dominant_frequency_hz - 1) < 5e-3 for p in s["receptance_peak_hz"])
    readme_fragment("A 100 N downward step at (0, 0.6, 0.2) deflects the tool 60.7 um sideways and 21.0 um down "
                    "statically, but the plate rocks: the lateral peak is 116.4 um, ringing at 26.2 Hz")
    for value, printed in ((s["static_lateral_m"] * 1e6, "60.7"), (-s["static_vertical_m"] * 1e6, "21.0"),
                           (s["peak_lateral_m"] * 1e6, "116.4"), (r.dominant_frequency_hz, "26.2")):
        assert_printed(value, printed)


def test_mirror_image_pose_and_force_give_the_mirror_image_response(machine):
    """The machine is symmetric in x -> -x (legs 2 and 4 swap): mirrored pose and force give the mirrored
    displacement history, to round-off of the largest displacement."""
    pose, force = np.array([0.12, 0.62, 0.05]), np.array([10.0, -80.0, 5.0])
    mirror = np.array([-1.0, 1.0, 1.0])
    a = tool_response(machine, pose, force, duration_s=0.05)
    b = tool_response(machine, pose * mirror, force * mirror, duration_s=0.05)
    assert np.abs(a.displacement_m * mirror - b.displacement_m).max() <= 1e-9 * np.abs(a.displacement_m).max()


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"force_n": np.zeros(3)}, "non-zero"),
    ({"force_n": np.array([0.0, np.nan, 0.0])}, "finite"),
    ({"duration_s": 0.0}, "duration"),
    ({"damping_ratio": 1.0}, "damping ratio"),
    ({"duration_s": 50.0}, "samples"),
])
def test_bad_requests_are_refused(machine, kwargs, message):
    args = {"force_n": STEP_N, "duration_s": 0.1} | kwargs
    with pytest.raises(PressfitError, match=message):
        tool_response(machine, OFF_CENTRE, **args)


def test_cli_json_files_and_refusals(tmp_path):
    runner = CliRunner()
    out = tmp_path / "resp"
    res = runner.invoke(main, ["response", "0", "0.6", "0.2", "--force", "0", "-100", "0", "--duration", "0.2",
                               "--out", str(out), "--json"])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    for key in ("static_lateral_m", "static_vertical_m", "peak_lateral_m", "peak_vertical_m",
                "dominant_frequency_hz"):
        assert np.isfinite(data[key])
    assert sorted(p.name for p in out.iterdir()) == ["receptance.csv", "response.csv", "response.json",
                                                       "response.png"]
    assert json.loads((out / "response.json").read_text())["static_vertical_m"] == data["static_vertical_m"]
    again = runner.invoke(main, ["response", "0", "0.6", "0.2", "--force", "0", "-100", "0", "--out", str(out)])
    assert again.exit_code == 2 and "not empty" in again.output
    for bad in (["--force", "0", "nan", "0"], ["--force", "0", "-100", "0", "--duration", "-1"],
                ["--force", "0", "0", "0"]):
        res = runner.invoke(main, ["response", "0", "0.6", "0.2", *bad])
        assert res.exit_code == 2, res.output
        assert len(res.output.strip().splitlines()) == 1
    res = runner.invoke(main, ["response", "0", "2.6", "0.2", "--force", "0", "-100", "0"])
    assert res.exit_code == 2 and "not reachable" in res.output
