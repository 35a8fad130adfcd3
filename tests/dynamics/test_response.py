"""Tool-point response (pressfit.dynamics.response): the modal closed form against independent computations.

Sources: the condensed closed-form compliance (mechanics/condensed.py, exact for rigid cardans: docs/conventions.md)
for the static limit; the exact discretisation of the reduced equations of motion (a matrix exponential, no modal
decomposition) for the step response; the machine's x -> -x mirror plane for symmetry."""

import json

import numpy as np
import pytest
from click.testing import CliRunner
from readme import assert_printed, readme_fragment
from scipy.linalg import eigh, expm

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


def test_step_response_matches_an_exact_discretisation(machine):
    """The closed-form modal step response equals the exact zero-order-hold discretisation of
    M_r z'' + C_r z' + K_r z = G^T F (a step: the force is constant) as a first-order system, with
    C_r = M_r X diag(2 zeta omega) X^T M_r (the same modal damping, assembled as a matrix): one matrix exponential
    of the augmented matrix [[A, b], [0, 0]] (Van Loan) over the sample spacing, marched over 0.1 s at every 20th
    sample; no modal decomposition of the motion. Achieved 1.1e-10 of the peak; tolerance 3e-10. (It replaced
    Radau integration of the same system, 2e-7 of the peak in 230-445 s; this takes about 1 s.)"""
    zeta = 0.02
    r = tool_response(machine, OFF_CENTRE, STEP_N, duration_s=0.1, damping_ratio=zeta)
    rs = reduced_system(machine, OFF_CENTRE)
    omega2, x = eigh(rs.stiffness, rs.mass_kg)
    m, k = rs.mass_kg, rs.stiffness
    c = m @ x @ np.diag(2 * zeta * np.sqrt(omega2)) @ x.T @ m
    g = rs.plate_map[:3]
    n = m.shape[0]
    a = np.zeros((2 * n + 1, 2 * n + 1))  # state (z, z', 1)
    a[:n, n:2 * n] = np.eye(n)
    a[n:2 * n, :n] = -np.linalg.solve(m, k)
    a[n:2 * n, n:2 * n] = -np.linalg.solve(m, c)
    a[n:2 * n, 2 * n] = np.linalg.solve(m, g.T @ STEP_N)
    t = r.time_s[::20]
    assert np.ptp(np.diff(t)) <= 1e-12 * t[-1]  # uniform samples: one transition matrix
    transition = expm(a * (t[1] - t[0]))
    state = np.zeros(2 * n + 1)
    state[-1] = 1.0
    u = np.empty((t.size, 3))
    for i in range(t.size):
        u[i] = g @ state[:n]
        state = transition @ state
    peak = np.abs(r.displacement_m).max()
    assert np.abs(u - r.displacement_m[::20]).max() <= 3e-10 * peak


@pytest.mark.slow
def test_off_centre_vertical_step_rings_at_the_rocking_mode(machine):
    """Off-centre a vertical force tilts and sways the plate (docs/conventions.md): the dominant mode is the
    rocking mode of `pressfit modes` (its 2nd mode here, 26.0 Hz), the lateral response overshoots its static
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
                    "statically, but the plate rocks: the lateral peak is 116.5 um, ringing at 26.0 Hz")
    for value, printed in ((s["static_lateral_m"] * 1e6, "60.7"), (-s["static_vertical_m"] * 1e6, "21.0"),
                           (s["peak_lateral_m"] * 1e6, "116.5"), (r.dominant_frequency_hz, "26.0")):
        assert_printed(value, printed)


@pytest.mark.slow
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
    ({"damping_ratio": 1.5}, "damping ratio"),
    ({"damping_ratio": -0.01}, "damping ratio"),
    ({"damping_ratio": np.nan}, "damping ratio"),
    ({"duration_s": 50.0}, "samples"),
])
def test_bad_requests_are_refused(machine, kwargs, message):
    args = {"force_n": STEP_N, "duration_s": 0.1} | kwargs
    with pytest.raises(PressfitError, match=message):
        tool_response(machine, OFF_CENTRE, **args)


@pytest.mark.slow
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


@pytest.mark.parametrize(("zeta", "unit_step"), [
    (0.0, lambda w, t: 1 - np.cos(w * t)),  # undamped
    (1.0, lambda w, t: 1 - np.exp(-w * t) * (1 + w * t)),  # critically damped
])
def test_undamped_and_critical_steps_are_the_textbook_forms(machine, zeta, unit_step):
    """At zeta = 0 and 1 each mode's step response is the textbook closed form (written here, not the module's
    sinc expression): the history is sum_k s_k f(omega_k t) with s_k the modal statics, to round-off."""
    r = tool_response(machine, OFF_CENTRE, STEP_N, duration_s=0.05, damping_ratio=zeta)
    rs = reduced_system(machine, OFF_CENTRE)
    omega2, x = eigh(rs.stiffness, rs.mass_kg)
    shapes = rs.plate_map[:3] @ x
    statics = shapes * ((shapes.T @ STEP_N) / omega2)
    ref = unit_step(np.sqrt(omega2)[None, :], r.time_s[:, None]) @ statics.T
    assert np.abs(ref - r.displacement_m).max() <= 1e-9 * np.abs(ref).max()


@pytest.mark.slow
def test_undamped_step_peaks_at_twice_the_static_deflection(machine):
    """zeta = 0: each mode's step response is s_k (1 - cos omega_k t), so one mode alone peaks at exactly twice its
    static share, and the vertical step's peak is twice the static deflection only as far as one mode carries it.
    At the centre pose the stem rods (3.33 kg each; their inner part and the moving parts ride on the actuator
    body) bring a leg-bending mode next to the heave: the vertical static deflection is carried by the 386 Hz mode
    (share 0.748) and the 421 Hz mode (0.247) (scipy's eigh of the reduced system here, not the module), and the
    two crest together only where both cosines are -1 at once: within 0.2 s those two alone reach 1.9845 of 1.9899,
    all modes 1.99185. So 1.9918 is mode coupling, not sampling: the history has 105 samples per dominant period,
    and its peak equals the closed form's maximum on a grid 250 times finer to 1.1e-6 (asserted 4e-6). Before the
    rod the heave mode alone carried 0.970 and the peak was 1.9990. The response does not decay: the last
    period's peak is the peak to the modes' beating (measured 0.998)."""
    pose = np.array([0.0, 0.72, 0.0])
    r = tool_response(machine, pose, STEP_N, duration_s=0.2, damping_ratio=0.0)
    s = r.summary()
    ratio = s["peak_vertical_m"] / s["static_vertical_m"]
    rs = reduced_system(machine, pose)
    omega2, x = eigh(rs.stiffness, rs.mass_kg)
    shapes = rs.plate_map[:3] @ x
    vertical = (shapes * ((shapes.T @ STEP_N) / omega2))[1]
    share = vertical / vertical.sum()
    top = np.argsort(-np.abs(share))[:2]
    assert share[top].sum() > 0.99 and share[top[1]] > 0.2  # two modes carry it, neither alone
    t = np.linspace(0.0, r.time_s[-1], 250 * r.time_s.size)
    dense = np.zeros_like(t)
    for k in np.argsort(-np.abs(share))[:20]:
        dense += share[k] * (1.0 - np.cos(np.sqrt(omega2[k]) * t))
    assert ratio == pytest.approx(np.abs(dense).max(), abs=4e-6)
    assert 1.99 < ratio < 2.0
    period = 1 / r.dominant_frequency_hz
    last = np.abs(r.displacement_m[r.time_s >= r.time_s[-1] - period, 1]).max()
    assert last / abs(s["peak_vertical_m"]) >= 0.99  # achieved 0.998 (the modes beat); 2% damping: < 1e-3
    assert np.all(np.isfinite(r.receptance_m_per_n))


@pytest.mark.slow
def test_the_weight_loaded_static_limit_against_stiffness(machine):
    """What `pressfit response` prints is linearised about the weight-loaded equilibrium: its static limit differs
    from the condensed closed form of `pressfit stiffness` (the unloaded pose) by at most 2e-3 at the poses of
    the docstring (achieved 1.8e-3 at (0.2, 0.8, 0.2)), and the difference is the weight's: linear in it
    (half the weight, half the difference, to 1%)."""
    force = np.array([30.0, -100.0, 20.0])
    for pose in ([0.0, 0.72, 0.0], [0.0, 0.6, 0.2], [0.15, 0.55, -0.2], [0.2, 0.8, 0.2], [-0.2, 0.5, 0.0]):
        ref = condensed_plate_compliance(machine, np.array(pose))[:3, :3] @ force
        r = tool_response(machine, np.array(pose), force, duration_s=0.01, frequency_count=10)
        assert np.linalg.norm(r.static_m - ref) <= 2e-3 * np.linalg.norm(ref), pose
    pose = np.array([0.2, 0.8, 0.2])
    ref = condensed_plate_compliance(machine, pose)[:3, :3] @ force
    full = tool_response(machine, pose, force, duration_s=0.01, frequency_count=10)
    half = tool_response(machine, pose, force, duration_s=0.01, frequency_count=10,
                         plate_wrench=0.5 * reduced_system(machine, pose).plate_wrench)
    ratio = np.linalg.norm(half.static_m - ref) / np.linalg.norm(full.static_m - ref)
    assert ratio == pytest.approx(0.5, rel=1e-2)
    assert np.linalg.norm(full.static_m - ref) >= 1e-3 * np.linalg.norm(ref)  # the stated state, not the unloaded


@pytest.mark.parametrize("force", [["0", "-2e5", "0"], ["1e7", "0", "0"]])
def test_a_step_beyond_buckling_is_refused_as_solve_refuses_it(force):
    """`pressfit solve --linear` (an independent check: the KKT tangent of the statics loses definiteness, no
    eigenvalue buckling) finds no stable equilibrium under these loads; `response` refuses them too, with the
    buckling factor and the limit."""
    runner = CliRunner()
    solved = runner.invoke(main, ["solve", "0", "0.72", "0", "--load", *force, "--linear"])
    assert solved.exit_code == 2 and "beyond the machine's buckling load" in solved.output
    res = runner.invoke(main, ["response", "0", "0.72", "0", "--force", *force])
    assert res.exit_code == 2, res.output
    assert len(res.output.strip().splitlines()) == 1
    factor = float(res.output.split("buckling load factor of ")[1].split()[0])
    assert factor < 1 and "at least 10" in res.output


@pytest.mark.slow
def test_a_step_near_buckling_is_refused_below_the_stated_factor(machine):
    """20 kN down at the centre has a buckling factor of 5 (10x the 0.5 of 200 kN: the factor is inverse in the
    load, the weight being 1e-4 of it), below the 10 a linear response needs; 5 kN (factor 20) is answered."""
    with pytest.raises(PressfitError, match=r"buckling load factor of 4\.99"):
        tool_response(machine, np.array([0.0, 0.72, 0.0]), np.array([0.0, -2e4, 0.0]), duration_s=0.01)
    r = tool_response(machine, np.array([0.0, 0.72, 0.0]), np.array([0.0, -5e3, 0.0]), duration_s=0.01)
    assert r.static_m[1] == pytest.approx(50 * tool_response(machine, np.array([0.0, 0.72, 0.0]), STEP_N,
                                                             duration_s=0.01).static_m[1], rel=1e-12)


@pytest.mark.slow
def test_a_large_rotation_or_translation_is_refused(machine, monkeypatch):
    """A lateral step high in the workspace rocks the plate (the soft 18 Hz mode): 260 N at (0, 0.8, 0) turns it
    beyond 0.01 rad at the peak (0.109 rad static under 2.7 kN, linear in the force, about twice at the peak);
    100 N at (0, 0.72, 0) stays inside. A translation cap set below the 100 N response refuses that one."""
    from pressfit.dynamics import response

    with pytest.raises(PressfitError, match=r"rotates the plate by .* beyond the small-angle range of 0\.01 rad"):
        tool_response(machine, np.array([0.0, 0.8, 0.0]), np.array([260.0, 0.0, 0.0]), duration_s=0.2)
    r = tool_response(machine, np.array([0.0, 0.72, 0.0]), np.array([100.0, 0.0, 0.0]), duration_s=0.2)
    monkeypatch.setattr(response, "MAX_TRANSLATION_FRACTION", 0.5 * np.abs(r.displacement_m).max() / 0.6)
    with pytest.raises(PressfitError, match="beyond the small-displacement range"):
        tool_response(machine, np.array([0.0, 0.72, 0.0]), np.array([100.0, 0.0, 0.0]), duration_s=0.2)


def test_the_duration_cap_is_named_and_holds():
    """A duration beyond the sample cap is refused with the pose's longest duration, which itself fits the cap."""
    from pressfit.dynamics.response import MAX_SAMPLES, _time_samples

    fastest = 2 * np.pi * 1024.0
    with pytest.raises(PressfitError, match="the longest duration at this pose is") as exc:
        _time_samples(60.0, fastest)
    longest = float(str(exc.value).split("is ")[-1].split()[0])
    assert len(_time_samples(longest, fastest)) <= MAX_SAMPLES
    res = CliRunner().invoke(main, ["response", "0", "0.72", "0", "--force", "0", "-100", "0", "--duration", "60"])
    assert res.exit_code == 2 and "the longest duration at this pose is" in res.output


@pytest.mark.parametrize("zeta", ["0", "1"])
def test_cli_accepts_the_whole_declared_damping_range(zeta):
    res = CliRunner().invoke(main, ["response", "0", "0.72", "0", "--force", "0", "-100", "0", "--duration", "0.05",
                                    "--damping-ratio", zeta])
    assert res.exit_code == 0, res.output
