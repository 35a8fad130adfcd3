"""A whole board (pressfit.dynamics.cycle, ``pressfit cycle``): a one-pin board reproduces ``pressfit simulate``,
boards that cannot run are refused naming the pin, the drives' limits scale the moves, and a pin's pass/fail
turns at its limit, recomputed here from the CSV."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pressfit import kinematics
from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.dynamics import cycle, series
from pressfit.dynamics import drives as drive_kinds
from pressfit.dynamics.actuators import distribution
from pressfit.dynamics.control import gravity_feedforward_n
from pressfit.dynamics.cycle import cycle_columns, plan_cycle, simulate_cycle, summarise_cycle
from pressfit.dynamics.insertion import series_columns, simulate_insertion
from pressfit.kinematics.profiles import s_curve_time_s
from tests.dynamics.test_simulation_trust import write_updated
from tests.readme import assert_printed, readme_fragment

ROOT = Path(__file__).resolve().parents[2]
BOARD = ROOT / "cases/paper/board.toml"
INSERTION = ROOT / "cases/paper/insertion.toml"
ELECTRIC = ROOT / "models/pressfit_4upu_electric.toml"
START, ABOVE = np.array([-0.15, 0.65, 0.10]), np.array([0.10, 0.605, -0.05])  # insertion.toml's start, waypoint
PIN = {"x_m": 0.10, "z_m": -0.05}  # insertion.toml's pin
FIGURES = ("first_contact_time_s", "peak_contact_force_n", "steady_insertion_force_n", "overshoot_n",
           "tool_lateral_error_at_first_contact_m", "settling_time_s")


def board(tmp_path: Path, name: str = "board.toml", top: dict | None = None, **cycle) -> Path:
    """The shipped board with its grid replaced by insertion.toml's pin (2 s dwell, as insertion.toml) unless
    ``cycle`` gives pins or a grid; [cycle] keys and sub-tables updated from ``cycle``; ``top``: other tables."""
    data = tomllib.loads(BOARD.read_text())
    c = data["cycle"]
    del c["grid"]
    c.update({"pins": [dict(PIN)], "dwell_s": 2.0})
    return write_updated(tmp_path / name, data, "cycle", cycle, top, whole=("grid",))


def run(*args: object):
    return CliRunner().invoke(main, [str(a) for a in args])


def refused(path: Path, *fragments: str) -> str:
    """``pressfit cycle`` exits 2 with one error line holding every fragment."""
    res = run("cycle", path, "--no-progress")
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and "Traceback" not in res.output, res.output
    for f in fragments:
        assert f in lines[0], (f, lines[0])
    return lines[0]


@pytest.fixture(scope="module")
def simulated():
    """``pressfit simulate``'s run of insertion.toml (rigid model, limiter on)."""
    return simulate_insertion(load_case(INSERTION))


# --- a one-pin board against pressfit simulate -------------------------------------------------------------
def test_one_pin_quintic_board_reproduces_simulate(tmp_path, simulated):
    """insertion.toml's scenario as a board: quintic moves whose speed limit 15 D / (8 T) makes every segment
    1 s (T = 15 D / (8 v) for the quintic's peak speed; acceleration and jerk limits far from binding), the
    same pin, dwell, gains and contact. The reference is then the same, so the step loop must give the same
    series up to the end of the retract and the same figures, to 1e-9 (the segment times come out of the
    limits with a round-off of an ulp, which shifts the reference by ~1e-16 s)."""
    d_move, d_descent = float(np.linalg.norm(ABOVE - START)), 0.005 + 0.002
    quintic = {"acceleration_m_per_s2": 1000.0, "jerk_m_per_s3": 1e6, "profile": "quintic"}
    path = board(tmp_path, motion={"speed_m_per_s": 15 * d_move / 8, **quintic},
                 descent={"speed_m_per_s": 15 * d_descent / 8, **quintic})
    result = simulate_cycle(load_case(path))
    durations = [s.duration_s for s in result.plan.segments]
    assert durations[:4] == pytest.approx([1.0, 1.0, 2.0, 1.0], abs=1e-12)
    assert [s.binding_limit for s in result.plan.segments[:2]] == ["speed", "speed"]
    rows = int(round(5.0 / 1e-3)) - 5  # approach, descent, dwell, retract: 5 s at 1 ms
    np.testing.assert_allclose(result.series[:rows, :len(series_columns(4))], simulated.series[:rows],
                               rtol=1e-9, atol=1e-9)
    pin = result.summary["pins"][0]
    for key in FIGURES:
        assert pin[key] == pytest.approx(simulated.summary[key], rel=1e-9, abs=1e-12), key
    assert pin["passed"] and pin["insertion_completed"]


def test_one_pin_s_curve_board_at_the_papers_speeds_agrees_with_simulate(tmp_path, simulated):
    """The same pin with S-curves of the same durations: the approach (D = 0.295 m) with T_j = 0.1 s and
    T_c = 0.3 s, a = D / ((T_j + T_c)(2 T_j + T_c)), j = a / T_j, the speed out of reach (v_p = 0.4 a < 1 m/s):
    T = 4 T_j + 2 T_c = 1 s; the descent (7 mm) at v = 10 mm/s, a = 0.05, j = 0.5: T = D/v + v/a + a/j = 1 s.
    The shapes differ (the S-curve cruises into the board at 10 mm/s, the quintic passes 5 mm of 7 at 8.7 mm/s),
    so the figures agree to what the shape changes: measured 0.28% on the peak force, 1e-4% on the steady one
    (the limiter sets both: 30 N plus the overshoot; asserted 0.5%, 0.02%), 2 ms on the settling, 34 ms on
    the first contact; the lateral error at first contact is the approach move's residual, which the profile's
    shape sets: 0.56 um after the S-curve, 1.78 um after the quintic (with the stem rods, the apparent mass 21.6 kg;
    0.58 and 0.88 um with the exposed-length stems' 16.0 kg, when the two were within a factor 2: no longer
    asserted), both under 2 um."""
    d = float(np.linalg.norm(ABOVE - START))
    a = d / ((0.1 + 0.3) * (2 * 0.1 + 0.3))
    assert s_curve_time_s(d, 1.0, a, a / 0.1) == pytest.approx(1.0, rel=1e-12)
    assert s_curve_time_s(0.007, 0.01, 0.05, 0.5) == pytest.approx(1.0, rel=1e-12)
    path = board(tmp_path, motion={"speed_m_per_s": 1.0, "acceleration_m_per_s2": a, "jerk_m_per_s3": a / 0.1})
    pin = simulate_cycle(load_case(path)).summary["pins"][0]
    s = simulated.summary
    assert pin["peak_contact_force_n"] == pytest.approx(s["peak_contact_force_n"], rel=5e-3)
    assert pin["steady_insertion_force_n"] == pytest.approx(s["steady_insertion_force_n"], rel=2e-4)
    assert pin["settling_time_s"] == pytest.approx(s["settling_time_s"], abs=0.01)
    assert pin["first_contact_time_s"] == pytest.approx(s["first_contact_time_s"], abs=0.1)
    assert max(pin["tool_lateral_error_at_first_contact_m"], s["tool_lateral_error_at_first_contact_m"]) < 2e-6


# --- refused before a run ---------------------------------------------------------------------------------
def test_a_pin_outside_the_workspace_is_refused_naming_it(tmp_path):
    path = board(tmp_path, pins=[dict(PIN), {"x_m": 0.45, "z_m": 0.0}])
    line = refused(path, "pin 2 (x = 0.45 m, z = 0 m)", "[cycle] pins[1]", str(path), "approach point", "breaks")
    assert "leg" in line
    grid = board(tmp_path, "g.toml", pins=[], grid={"x": {"min_m": 0.0, "max_m": 0.6, "count": 2},
                                                    "z": {"min_m": 0.0, "max_m": 0.0, "count": 1}})
    refused(grid, "pin 2 (x = 0.6 m, z = 0 m)", "[cycle.grid]")


def test_the_bottom_of_an_insertion_below_the_workspace_is_refused(tmp_path):
    # at the corner (0.25, 0.25) the plate reaches down to y = 0.4189 m (leg length limits; checked here): the
    # board face at 0.42 m puts the approach point (0.425 m) inside and the bottom (0.418 m) outside
    machine = load_case(INSERTION).machine()
    assert kinematics.is_reachable(machine, np.array([0.25, 0.425, 0.25]))
    assert not kinematics.is_reachable(machine, np.array([0.25, 0.418, 0.25]))
    low = board(tmp_path, board_height_m=0.42, pins=[{"x_m": 0.25, "z_m": 0.25}])
    refused(low, "pin 1 (x = 0.25 m, z = 0.25 m)", "the bottom of its insertion 0.002 m below the board face",
            "[cycle] pins[0] (x_m, z_m)")


def test_start_below_the_board_huge_boards_short_dwells_and_unknown_keys_are_refused(tmp_path):
    refused(board(tmp_path, "s.toml", start_m=[-0.15, 0.59, 0.10]), "[cycle] start_m", "board_height_m = 0.6")
    huge = board(tmp_path, "h.toml", grid={"x": {"min_m": -0.2, "max_m": 0.2, "count": 40},
                                           "z": {"min_m": -0.2, "max_m": 0.2, "count": 40}})
    refused(huge, "1601 pins, above the cap of 1000")
    # 999 pins of 2 s dwell are 2e6 steps at 1 ms before any move: refused before the drives' scaling is computed
    long = board(tmp_path, "l.toml", grid={"x": {"min_m": -0.2, "max_m": 0.2, "count": 37},
                                           "z": {"min_m": -0.2, "max_m": 0.2, "count": 27}})
    refused(long, "[cycle] time_step_s", "a run of at most 1000000 steps", "(1000 pins)")
    short = board(tmp_path, "d.toml", pins=[{**PIN, "dwell_s": 0.005}])
    refused(short, "[cycle] pins[0] dwell_s", "pin 1 (x = 0.1 m, z = -0.05 m)", "at least 10 time steps")
    refused(board(tmp_path, "k.toml", pins=[{**PIN, "force_limit": 3.0}]), "force_limit")
    refused(board(tmp_path, "m.toml", motion={"jerk_m_per_s3": -1.0}), "jerk_m_per_s3")


def test_per_pin_values_override_the_boards_and_the_grid_snakes(tmp_path):
    case = load_case(board(tmp_path, pins=[{**PIN, "force_limit_n": 25.0, "dwell_s": 0.7}],
                           grid={"x": {"min_m": -0.1, "max_m": 0.1, "count": 3},
                                 "z": {"min_m": 0.0, "max_m": 0.1, "count": 2}}))
    pins = case.cycle.resolved_pins()
    assert (pins[0].force_limit_n, pins[0].dwell_s, pins[0].interference_m) == (25.0, 0.7, 0.002)
    assert (pins[1].force_limit_n, pins[1].dwell_s) == (30.0, 2.0)  # [cycle.controller]'s limit, [cycle]'s dwell
    assert [(p.x_m, p.z_m) for p in pins[1:]] == [(-0.1, 0.0), (0.0, 0.0), (0.1, 0.0), (0.1, 0.1), (0.0, 0.1),
                                                 (-0.1, 0.1)]
    assert [p.index for p in pins] == list(range(1, 8))


# --- the drives' limits along a segment ---------------------------------------------------------------------
def test_the_electric_drives_speed_limit_scales_a_fast_move(tmp_path):
    """With 1 m/s of leg speed (3000 rpm on a 20 mm lead) and a 2 m/s tool speed asked (50 m/s^2, 5000 m/s^3: the
    cruise holds the move longest), the approach runs at the speed where the fastest leg reaches 1 m/s;
    recomputed here on a 20x denser sampling from the leg unit vectors of equation 1 (the scaled speed holds to
    the sampling's 1e-3)."""
    path = board(tmp_path, top={"model": str(ELECTRIC)}, motion={"speed_m_per_s": 2.0, "acceleration_m_per_s2": 50.0,
                                                                 "jerk_m_per_s3": 5000.0})
    case = load_case(path)
    plan = plan_cycle(case)
    approach = plan.segments[0]
    assert approach.binding_limit == "drive speed"
    v = approach.limits[0]
    assert v < 2.0 and approach.profile.peak_speed_m_per_s == pytest.approx(v, rel=1e-12)
    u = (approach.end_m - approach.start_m) / np.linalg.norm(approach.end_m - approach.start_m)
    points = approach.start_m + np.linspace(0, 1, 12001)[:, None] * (approach.end_m - approach.start_m)
    legs = kinematics.leg_vectors(case.machine(), points)
    rates = np.abs(legs / np.linalg.norm(legs, axis=-1, keepdims=True) @ u) * v
    table = case.machine().actuator.electric
    limit = table.speed_limit_rad_per_s * table.lead_m / (2 * math.pi)
    assert limit == pytest.approx(1.0, rel=1e-4)
    assert limit * (1 - 1e-3) <= rates.max() <= limit * (1 + 1e-3)
    assert plan.segments[1].binding_limit == "speed"  # the descent: 10 mm/s, far from 1 m/s


def test_the_drive_force_limit_scales_a_hard_acceleration(tmp_path):
    """A 300 N drive limit and 50 m/s^2 asked: the approach's acceleration comes down until the worst leg
    needs 300 N (weight + preload + inertia); the inertia term is checked by forward constraint dynamics of the
    rigid model: the scaled tensions accelerate the plate by exactly a u."""
    path = board(tmp_path, top={"model_overrides": {"actuator": {"force_limit_n": 300.0}}},
                 motion={"speed_m_per_s": 2.0, "acceleration_m_per_s2": 50.0, "jerk_m_per_s3": 5000.0})
    case = load_case(path)
    plan = plan_cycle(case)
    approach = plan.segments[0]
    assert approach.binding_limit == "drive force"
    acc = approach.limits[1]
    assert acc < 50.0
    rigid, machine = plan.scenario.rigid, case.machine()
    u = (approach.end_m - approach.start_m) / np.linalg.norm(approach.end_m - approach.start_m)
    worst = 0.0
    for p in approach.start_m + np.linspace(0, 1, 11)[:, None] * (approach.end_m - approach.start_m):
        legs = kinematics.leg_vectors(machine, p)
        pinv, null = distribution(legs / np.linalg.norm(legs, axis=1, keepdims=True))
        q = rigid.configuration_at(p)
        for sign in (1.0, -1.0):
            tau = np.zeros(rigid.model.nv)
            rest = rigid.accelerations(q, np.zeros(rigid.model.nv), tau)[:3]  # gravity alone
            probe = np.zeros(rigid.model.nv)
            inverse = np.empty((3, 3))
            for k in range(3):  # the plate's mobility, unit forces on the plate
                probe[:] = 0.0
                probe[k] = 1.0
                inverse[:, k] = rigid.accelerations(q, np.zeros(rigid.model.nv), probe)[:3] - rest
            tension = -pinv @ (gravity_feedforward_n(rigid, p) + np.linalg.solve(inverse, sign * acc * u)) \
                + case.preload.a4_n * null[:, 0]
            tau[rigid.actuator_v] = -tension
            moved = rigid.accelerations(q, np.zeros(rigid.model.nv), tau)[:3]
            np.testing.assert_allclose(moved, sign * acc * u, atol=1e-6 * acc)
            worst = max(worst, float(np.abs(tension).max()))
    assert worst == pytest.approx(300.0, rel=1e-6)
    assert drive_kinds.of(machine).force_limit_n == 300.0


# --- pass/fail at a pin's limits, recomputed from the CSV -----------------------------------------------------
@pytest.mark.slow
def test_pin_pass_fail_turns_at_its_limits_recomputed_from_the_csv(tmp_path):
    """A pin whose limits cannot hold (0 N of overshoot, 1 nm of alignment) fails: exit 1, files written. The
    overshoot (peak contact force over the pin's rows minus its 30 N limit) and the lateral error at the first
    row in contact are recomputed from cycle.csv; a limit 1e-6 above each figure passes, 1e-6 below fails."""
    path = board(tmp_path, pins=[{**PIN, "max_overshoot_n": 0.0, "max_alignment_error_m": 1e-9}], dwell_s=0.5,
                 settle_s=0.1)
    out = tmp_path / "out"
    res = run("cycle", path, "--out", out, "--no-progress")
    assert res.exit_code == 1, res.output
    assert "FAIL" in res.output
    assert sorted(p.name for p in out.iterdir()) == ["curves", "cycle.csv", "cycle.json", "cycle_drives.png",
                                                     "cycle_force.png", "cycle_operating_points.png", "cycle_path.png"]
    assert sorted(p.name for p in (out / "curves").iterdir()) == ["pin_01.csv"]
    header = (out / "cycle.csv").read_text().splitlines()[0].split(",")
    assert tuple(header) == cycle_columns(4)
    series = np.loadtxt(out / "cycle.csv", delimiter=",", skiprows=1)
    col = {c: k for k, c in enumerate(header)}
    rows = np.flatnonzero(series[:, col["pin"]] == 1)
    force = series[rows, col["contact_force_n"]]
    overshoot = force.max() - 30.0
    first = rows[np.flatnonzero(force > 0)[0]]
    lateral = math.hypot(series[first, col["tool_x_m"]] - PIN["x_m"], series[first, col["tool_z_m"]] - PIN["z_m"])
    assert overshoot > 0.1 and 0 < lateral < 1e-5
    summary = json.loads((out / "cycle.json").read_text())
    assert {"pins", "cycle_time_s", "pins_per_minute", "segments"} <= set(summary)
    assert summary["pins"][0]["overshoot_n"] == pytest.approx(overshoot, rel=1e-12)
    assert summary["pins"][0]["tool_lateral_error_at_first_contact_m"] == pytest.approx(lateral, rel=1e-12)
    assert not summary["pins"][0]["passed"]
    for factor, passes in ((1 + 1e-6, True), (1 - 1e-6, False)):
        for limits in ({"max_overshoot_n": overshoot * factor, "max_alignment_error_m": 1.0},
                       {"max_overshoot_n": 100.0, "max_alignment_error_m": lateral * factor}):
            variant = load_case(board(tmp_path, "v.toml", pins=[{**PIN, **limits}], dwell_s=0.5, settle_s=0.1))
            pin = summarise_cycle(series, plan_cycle(variant))["pins"][0]
            assert pin["passed"] is passes, (limits, pin["checks"])
    figures = summarise_cycle(series, plan_cycle(load_case(path)))["pins"][0]  # the same series, summarised again
    lateral_figure = figures["tool_lateral_error_at_first_contact_m"]
    for limits in ({"max_overshoot_n": figures["overshoot_n"], "max_alignment_error_m": 1.0},
                   {"max_overshoot_n": 100.0, "max_alignment_error_m": lateral_figure}):
        variant = load_case(board(tmp_path, "v.toml", pins=[{**PIN, **limits}], dwell_s=0.5, settle_s=0.1))
        assert summarise_cycle(series, plan_cycle(variant))["pins"][0]["passed"], limits  # a limit met exactly holds


@pytest.mark.slow
def test_each_pin_is_pressed_at_its_own_force_limit(tmp_path):
    """Two pins, the second with a 20 N limit: the limiter of each pin's segments uses that pin's limit (the
    contact law reaches 100 N at the 2 mm commanded, so the limit sets the steady force: within the 2% settling
    band of it)."""
    path = board(tmp_path, pins=[dict(PIN), {"x_m": 0.0, "z_m": -0.05, "force_limit_n": 20.0}], dwell_s=0.5,
                 settle_s=0.1)
    pins = simulate_cycle(load_case(path)).summary["pins"]
    assert [p["force_limit_n"] for p in pins] == [30.0, 20.0]
    assert pins[0]["steady_insertion_force_n"] == pytest.approx(30.0, rel=0.02)
    assert pins[1]["steady_insertion_force_n"] == pytest.approx(20.0, rel=0.02)
    assert all(p["insertion_completed"] for p in pins)


def test_an_unstable_step_names_the_cycles_keys(tmp_path):
    """The explicit-step check is [simulation]'s; on a board it names [cycle]'s keys (the same meaning)."""
    refused(board(tmp_path, controller={"kp_n_per_m": 1e8}), "[cycle] time_step_s", "[cycle.controller] gains")


def test_shipped_board_cycle_time_in_closed_form():
    """cases/paper/board.toml: 20 pins at a 100 mm pitch. Every move is a rest-to-rest S-curve in closed form
    (v = 0.5, a = 2, j = 20: the speed-up takes v/a + a/j = 0.35 s over v (v/a + a/j) / 2 = 87.5 mm):
    the approach (0.259 m) and the final move (0.214 m) cruise: T = D/v + v/a + a/j; the 19 traverses of 0.1 m
    do not: T = 2 (v_p/a + a/j), v_p^2 + v_p a^2/j - a D = 0; the descents and retracts (7 mm at v = 0.01,
    a = 0.05, j = 0.5) cruise: 0.7 + 0.2 + 0.1 = 1 s; the dwells 0.5 s. None is held by the drives."""
    v, a, j = 0.5, 2.0, 20.0
    start, end = np.array([-0.15, 0.65, 0.10]), np.array([0.0, 0.68, 0.15])
    first, last = np.array([-0.2, 0.605, -0.15]), np.array([-0.2, 0.605, 0.15])  # snaking: row 4 ends at x min
    cruise = [float(np.linalg.norm(first - start)), float(np.linalg.norm(end - last))]
    assert min(cruise) > v * (v / a + a / j)
    vp = (math.sqrt(a**4 / j**2 + 4 * a * 0.1) - a * a / j) / 2
    expected = sum(d / v + v / a + a / j for d in cruise) + 19 * 2 * (vp / a + a / j) + 20 * (1.0 + 0.5 + 1.0)
    plan = plan_cycle(load_case(BOARD))
    assert len(plan.pins) == 20 and plan.cycle_time_s == pytest.approx(expected, rel=1e-12)
    assert not any(s.binding_limit.startswith("drive") for s in plan.segments)
    # a traverse: 2 T_c = 2 (v_p/a - a/j) = 0.158 s at constant acceleration, 4 T_j = 4 a/j = 0.4 s of jerk phases
    assert 2 * (vp / a - a / j) < 4 * a / j
    assert {s.binding_limit for s in plan.segments if s.phase == "traverse"} == {"jerk"}
    assert {s.binding_limit for s in plan.segments if s.phase in ("descent", "retract")} == {"speed"}
    text = readme_fragment("the shipped board (20 pins) plans to a 62.25 s cycle, 19.28 pins per minute, its "
                           "traverses held by the jerk")
    assert_printed(plan.cycle_time_s, "62.25")
    assert_printed(60 * 20 / plan.cycle_time_s, "19.28")
    assert "62.25" in text


@pytest.mark.slow
def test_cli_runs_the_flexible_model_and_refuses_an_existing_output_before_computing(tmp_path):
    """``--model flexible`` overrides the case's rigid model: the same step loop as ``simulate``'s flexible runs
    (elastic legs, contact on the elastic tool point); a short fast board (2.6 s at 1.75 ms steps: 2 ms is over the
    flexible step bound at the pin, 1.81 ms) presses its pin. A non-empty --out is refused before any computation
    (exit 2, nothing written)."""
    fast = {"motion": {"speed_m_per_s": 1.0, "acceleration_m_per_s2": 5.0, "jerk_m_per_s3": 50.0},
            "descent": {"speed_m_per_s": 0.02, "acceleration_m_per_s2": 0.2, "jerk_m_per_s3": 2.0}}
    path = board(tmp_path, dwell_s=0.3, settle_s=0.0, time_step_s=1.75e-3, **fast)
    res = run("cycle", path, "--model", "flexible", "--json", "--no-progress")
    assert res.exit_code == 0, res.output
    summary = json.loads(res.output)
    assert summary["model"] == "flexible" and summary["pins"][0]["insertion_completed"]
    assert summary["pins_per_minute"] == pytest.approx(60 / summary["cycle_time_s"], rel=1e-12)
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("x")
    res = run("cycle", path, "--out", out, "--no-progress")
    assert res.exit_code == 2 and "--overwrite" in res.output and sorted(p.name for p in out.iterdir()) == ["keep.txt"]


def test_a_run_time_error_names_the_cycles_keys(tmp_path, monkeypatch):
    """An error raised inside the step loop of a board names [cycle]'s keys (the board has no [simulation] table):
    with the closure-drift tolerance set to zero the first step's drift stops the run; the one error line names
    [cycle] baumgarte_rad_per_s and [cycle.controller], never [simulation]."""
    monkeypatch.setattr(series, "MAX_CLOSURE_DRIFT_M", 0.0)
    line = refused(board(tmp_path), "drifted open", "[cycle] baumgarte_rad_per_s", "[cycle.controller] gains")
    assert "[simulation" not in line


def test_a_flexible_board_over_the_paths_step_bound_is_refused(tmp_path):
    """The flexible step bound holds over the board's path, not only at its start: 2 ms is over the bound at the
    pin (1.81 ms; 1.75 ms runs, the CLI test above), so the board is refused before the run naming [cycle]'s key."""
    path = board(tmp_path, time_step_s=2e-3, model="flexible")
    refused(path, "[cycle] time_step_s")


@pytest.mark.slow
def test_a_tool_deeper_than_the_boards_depth_limit_stops_the_run(tmp_path, monkeypatch):
    """A board's run stops when the tool goes deeper below the face than MAX_DEPTH_FACTOR x its deepest pin's
    interference: with the factor cut to 1e-3 (2 um) the first press stops the run with one line naming the depth,
    never a result."""
    monkeypatch.setattr(cycle, "MAX_DEPTH_FACTOR", 1e-3)
    refused(board(tmp_path), "below the board face", "[cycle.controller] gains")
