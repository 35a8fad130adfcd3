"""A component with a pin field pressed at every board position (``[[cycle.contact.pins]]`` in ``pressfit cycle``):
one board position against ``pressfit simulate`` of the same component at the same pose, the pins' final depths
against the linear pins' series equation solved by hand with the Pinocchio VJM compliance (a second formulation of
the condensed compliance the program uses), the symmetry of a centred symmetric field, a mirrored board, the
per-pin curve files and ``[cycle.limits] max_pin_depth_spread_m``.

The runs are tiny (rigid model, 2 board positions, 2 elastic pins of 5e4 N/m at (+-10 mm, 0), 0.4 mm commanded
interference with the force limit out of reach: about 40 N of quasi-static contact, short moves)."""

from __future__ import annotations

import copy
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner

from pressfit.cli import main
from pressfit.cli.dynamics import _echo_components
from pressfit.description.cases import load_case
from pressfit.dynamics.contact import contact_force_n
from pressfit.dynamics.cycle import plan_cycle, simulate_cycle
from pressfit.dynamics.insertion import simulate_insertion
from pressfit.dynamics.scenario import apparent_mass_kg, step_stability
from pressfit.errors import ModelFileError
from pressfit.mechanics.compliance import vjm_plate_compliance
from pressfit.output.curve import monitor_curve_columns
from pressfit.output.cycle import write_cycle
from pressfit.studies.limit_check import cycle_lines, evaluate_cycle

K_N_PER_M = 5.0e4  # each pin's elastic stiffness
OFFSETS = [[0.01, 0.0], [-0.01, 0.0]]  # the component: two pins mirror-symmetric about the tool axis, m
FACE_M, CENTRE, OFF = 0.60, (0.0, 0.0), (0.15, 0.10)  # board face; the centred and an off-centre board position
CONTROLLER = {"force_limit_n": 100.0, "kp_n_per_m": 2.0e4, "kd_n_s_per_m": 1.0e3, "ki_n_per_m_s": 2.0e5,
              "backoff_m_per_s_n": 1.0e-3, "gravity_compensation": True, "deflection_compensation": True}
CONTACT = {"law": "elastic", "stiffness_n_per_m": K_N_PER_M, "pins": [{"offset_m": o} for o in OFFSETS]}
BASE = {"name": "pin-field-board", "poses": {"points_m": [[0.0, 0.605, 0.0]]}, "loads": {"force_n": [0.0, 40.0, 0.0]},
        "preload": {"a4_n": 100.0}}


def board_case(path: Path, mirror: bool = False, offsets: list | None = None, **limits: float) -> Path:
    """The two-position board (the centred position first, then (0.15, 0.10); ``mirror``: x -> -x everywhere,
    the board positions, the start and the end; the field is its own mirror image with its pins' order swapped;
    ``offsets``: another field, m)."""
    s = -1.0 if mirror else 1.0
    cycle = {"board_height_m": FACE_M, "start_m": [0.0, 0.602, 0.0], "end_m": [s * 0.15, 0.602, 0.10],
             "approach_height_m": 0.001, "interference_m": 4e-4, "dwell_s": 1.0, "settle_s": 0.01,
             "time_step_s": 1e-3, "model": "rigid",
             "pins": [{"x_m": s * CENTRE[0], "z_m": CENTRE[1]}, {"x_m": s * OFF[0], "z_m": OFF[1]}],
             "motion": {"speed_m_per_s": 0.5, "acceleration_m_per_s2": 4.0, "jerk_m_per_s3": 80.0},
             "descent": {"speed_m_per_s": 0.01, "acceleration_m_per_s2": 0.2, "jerk_m_per_s3": 10.0},
             "contact": {**copy.deepcopy(CONTACT), "pins": [{"offset_m": o} for o in offsets or OFFSETS]},
             "controller": CONTROLLER, "limits": limits}
    path.write_text(tomli_w.dumps({**BASE, "cycle": cycle}))
    return path


def insertion_case(path: Path) -> Path:
    """``pressfit simulate`` of the same component at the off-centre board position, the same controller and
    commanded interference, descending from the same approach height."""
    sim = {"start_m": [OFF[0], 0.602, OFF[1]], "end_m": [OFF[0], 0.602, OFF[1]], "approach_height_m": 0.001,
           "interference_m": 4e-4, "move_time_s": 0.1, "descent_time_s": 0.3, "dwell_s": 1.0, "settle_s": 0.0,
           "time_step_s": 1e-3, "model": "rigid",
           "contact": {"board_height_m": FACE_M, "pin_position_m": list(OFF), **copy.deepcopy(CONTACT)},
           "controller": CONTROLLER}
    path.write_text(tomli_w.dumps({**BASE, "simulation": sim}))
    return path


@pytest.fixture(scope="module")
def field_runs(tmp_path_factory):
    """The board, its mirror image and the single insertion: about 10 s together."""
    tmp = tmp_path_factory.mktemp("field")
    board = load_case(board_case(tmp / "board.toml"))
    mirrored = load_case(board_case(tmp / "mirrored.toml", mirror=True))
    single = load_case(insertion_case(tmp / "single.toml"))
    return (board, simulate_cycle(board, sizing=False), simulate_cycle(mirrored, sizing=False),
            simulate_insertion(single))


def hand_pin_depths(machine, pose_m, depth_m: float, offsets: list | None = None) -> np.ndarray:
    """The linear pins' series equation solved by hand: F = k (d 1 - A F), A = G_r^T C_rr G_r (the tilt only, the
    pins' moments about the tool tip through the rotation block of the Pinocchio VJM compliance C at the pose),
    so F = (I + k A)^-1 k d 1 and d_i = F_i / k (``offsets``: the field, default ``OFFSETS``, m)."""
    r = np.array(offsets or OFFSETS, dtype=float)
    c = vjm_plate_compliance(machine, np.asarray(pose_m, dtype=float))
    g = np.zeros((6, len(r)))
    g[1] = 1.0
    g[3], g[5] = -r[:, 1], r[:, 0]
    a = g[3:].T @ c[3:] @ g
    forces = np.linalg.solve(np.eye(len(r)) + K_N_PER_M * a, K_N_PER_M * depth_m * np.ones(len(r)))
    return forces / K_N_PER_M


@pytest.mark.slow
def test_a_board_position_presses_the_component_as_simulate_does(field_runs):
    """The off-centre board position's component figures against ``pressfit simulate`` of the same component at the
    same pose (independent runs: another reference path, another start; the same quasi-static end of the dwell):
    each pin's peak force and final depth within 1% (achieved 0.19% and 0.08%: the 1 s dwell has not quite settled,
    the two runs' force still rising by a few tenths of a percent), the tilt and the depth spread within 2%
    (achieved 0.19%); the pins' final depths against the linear pins' series equation solved by hand with the VJM
    compliance at the board position's pose and the simulated tool depth at the end of the dwell, to 1e-9 (achieved
    2e-16: the two compliances agree to 2e-12 and the tilt moves the pins by about 1% of their depth); the first
    pin is deeper than the second there (the tilt is that pose's, not the first board position's, where the field
    does not tilt)."""
    case, board, _, single = field_runs
    record, sim = board.summary["pins"][1], single.summary
    for mine, theirs in zip(record["component_pins"], sim["component_pins"], strict=True):
        assert mine["offset_m"] == theirs["offset_m"]
        assert mine["peak_force_n"] == pytest.approx(theirs["peak_force_n"], rel=1e-2)
        assert mine["final_depth_m"] == pytest.approx(theirs["final_depth_m"], rel=1e-2)
        assert mine["seated"] is theirs["seated"] is False
    for key in ("tool_tilt_max_rad", "max_pin_depth_spread_m"):
        assert record[key] == pytest.approx(sim[key], rel=2e-2)
    curve = board.curves[1]
    final = [p["final_depth_m"] for p in record["component_pins"]]
    row = int(np.flatnonzero(curve.pin_depths_m[:, 0] == final[0])[0])  # the end of the dwell: its true depth
    hand = hand_pin_depths(case.machine(), [OFF[0], FACE_M, OFF[1]], float(curve.depth_m[row]))
    assert np.allclose(final, hand, rtol=1e-9, atol=0.0)
    assert final[0] - final[1] > 1e-7


@pytest.mark.slow
def test_a_centred_symmetric_field_does_not_tilt_the_tool(field_runs):
    """At the centred board position the symmetric field does not tilt the tool (the 4-UPU's mirror symmetry; achieved
    4e-21 rad and 0 m) and its two pins share the force equally (achieved exactly, asserted to 1e-12 relative, 17.2 N
    each); at the off-centre position the same field tilts it (achieved 142 urad, 2.3 um of spread): the check can
    fail."""
    _, board, _, _ = field_runs
    centre, off = board.summary["pins"]
    assert centre["tool_tilt_max_rad"] < 1e-15 and centre["max_pin_depth_spread_m"] < 1e-15
    one, two = centre["component_pins"]
    assert one["peak_force_n"] == pytest.approx(two["peak_force_n"], rel=1e-12)
    assert one["peak_force_n"] > 15.0
    assert off["tool_tilt_max_rad"] > 1e-5 and off["max_pin_depth_spread_m"] > 1e-7


@pytest.mark.slow
def test_a_mirrored_board_gives_mirrored_figures(field_runs):
    """The board mirrored x -> -x (positions, start, end): the 4-UPU is mirror-symmetric in x, so at each board
    position the tilt and the spread are the same and each pin's figures are its mirror pin's (the field's pins
    swap: (+10 mm, 0) <-> (-10 mm, 0)); to 1e-6 relative (achieved 3e-16: the two runs' round-off)."""
    _, board, mirrored, _ = field_runs
    for one, two in zip(board.summary["pins"], mirrored.summary["pins"], strict=True):
        assert two["x_m"] == -one["x_m"]
        for key in ("tool_tilt_max_rad", "max_pin_depth_spread_m", "peak_force_n"):
            assert two[key] == pytest.approx(one[key], rel=1e-6, abs=1e-15)
        for mine, theirs in zip(two["component_pins"], one["component_pins"][::-1], strict=True):
            assert mine["offset_m"] == [-theirs["offset_m"][0], theirs["offset_m"][1]]
            for key in ("peak_force_n", "final_depth_m"):
                assert mine[key] == pytest.approx(theirs[key], rel=1e-6)
    off, off_mirrored = board.summary["pins"][1]["component_pins"], mirrored.summary["pins"][1]["component_pins"]
    assert abs(off[0]["final_depth_m"] - off[1]["final_depth_m"]) > 1e-7  # the swap is not of equal pins
    assert off_mirrored[1]["final_depth_m"] > off_mirrored[0]["final_depth_m"]


@pytest.mark.slow
def test_each_board_position_writes_its_pins_force_columns(field_runs, tmp_path, capsys):
    """curves/pin_NN.csv per board position with simulate's curve.csv columns for a two-pin component: the pins'
    forces sum to the total (to 1e-9 N) and at the centred position are equal; cycle.json's pins carry the
    component's figures, and ``pressfit cycle`` prints them per board position (tilt in mrad, spread in um)."""
    _, board, _, _ = field_runs
    _echo_components(board.summary)
    lines = capsys.readouterr().out.splitlines()
    off = board.summary["pins"][1]
    assert lines[0].split()[:3] == ["pin", "tilt", "[mrad]"] and len(lines) == 3
    assert lines[2].split()[:4] == ["2", f"{off['tool_tilt_max_rad'] * 1e3:.4f}",
                                    f"{off['max_pin_depth_spread_m'] * 1e6:.3f}", "no"]
    write_cycle(board, tmp_path)
    for k in (1, 2):
        csv = tmp_path / "curves" / f"pin_{k:02d}.csv"
        assert csv.read_text().splitlines()[0].split(",") == monitor_curve_columns(2)
        table = np.loadtxt(csv, delimiter=",", skiprows=1)
        assert np.allclose(table[:, 4] + table[:, 5], table[:, 3], rtol=0.0, atol=1e-9)
        assert table[:, 3].max() > 30.0
    centre = np.loadtxt(tmp_path / "curves" / "pin_01.csv", delimiter=",", skiprows=1)
    assert np.allclose(centre[:, 4], centre[:, 5], rtol=1e-12, atol=1e-12)
    saved = json.loads((tmp_path / "cycle.json").read_text())["pins"]
    assert [len(p["component_pins"]) for p in saved] == [2, 2]
    assert {"tool_tilt_max_rad", "max_pin_depth_spread_m", "all_pins_seated"} <= set(saved[1])


@pytest.mark.slow
def test_each_board_position_runs_the_component_at_its_own_compliance(tmp_path):
    """The run's contact (the component's total force against the tool depth, the kernels' table) is the board
    position's: for a field off the tool axis ((20, 10) and (30, 10) mm) linear pins give the total
    sum((I + k A)^-1 k d 1) solved by hand with the VJM compliance at each position (at 0.1 .. 0.4 mm, to 1e-9
    relative; achieved 6e-15), and the two positions' totals differ (0.64% below 2 k d at the centre, 0.36% above it
    off it: the first position's table at the second would be wrong by 1%)."""
    offsets = [[0.02, 0.01], [0.03, 0.01]]
    case = load_case(board_case(tmp_path / "board.toml", offsets=offsets))
    plan = plan_cycle(case)
    machine = case.machine()
    descent = {s.pin: s.index for s in plan.segments if s.phase == "descent"}
    depths = np.array([1e-4, 2e-4, 4e-4])
    totals = {}
    for index, (x, z) in ((1, CENTRE), (2, OFF)):
        totals[index] = np.array([contact_force_n(plan.scenario.contact_params[descent[index]], d) for d in depths])
        hand = [K_N_PER_M * hand_pin_depths(machine, [x, FACE_M, z], d, offsets).sum() for d in depths]
        assert totals[index] == pytest.approx(hand, rel=1e-9)
    assert np.all(np.abs(totals[2] / totals[1] - 1.0) > 5e-3)


@pytest.mark.slow
def test_the_pin_depth_spread_limit_turns_at_the_spread_solved_by_hand(field_runs, tmp_path):
    """``[cycle.limits] max_pin_depth_spread_m``: the true worst spread is the off-centre position's, for linear pins
    proportional to the tool depth, so its deepest row's true depth times the spread of the hand solve at 1 m
    (VJM compliance); the limit at that x (1 + 1e-6) passes, x (1 - 1e-6) fails, naming the worst board position
    (achieved agreement 2e-14); ``pressfit check``'s evaluation of the case with the lower limit fails the line."""
    case, board, _, _ = field_runs
    machine = case.machine()
    depth = float(board.curves[1].depth_m.max())
    spread = depth * float(np.ptp(hand_pin_depths(machine, [OFF[0], FACE_M, OFF[1]], 1.0)))
    for factor, passed in ((1 + 1e-6, True), (1 - 1e-6, False)):
        (line,) = cycle_lines({"max_pin_depth_spread_m": spread * factor}, board.summary, case.cycle.start_m, FACE_M)
        assert line.passed is passed and line.key == "cycle.max_pin_depth_spread_m"
        assert line.pose_m == [OFF[0], FACE_M, OFF[1]] and "worst pin 2 (x = 0.15 m, z = 0.1 m)" in line.method
    lower = load_case(board_case(tmp_path / "limited.toml", max_pin_depth_spread_m=spread * (1 - 1e-6)))
    (line,) = evaluate_cycle(lower)
    assert line.passed is False and line.worst == pytest.approx(spread, rel=1e-6)


def test_a_pin_of_the_board_component_with_another_laws_key_is_refused_naming_it(tmp_path):
    """``[[cycle.contact.pins]]`` is validated as ``[[simulation.contact.pins]]``: a key of another law is exit 2,
    one line naming the file, the table and the pin's key."""
    path = board_case(tmp_path / "bad.toml")
    data = tomllib.loads(path.read_text())
    data["cycle"]["contact"]["pins"][0]["zone_width_m"] = 0.002
    path.write_text(tomli_w.dumps(data))
    res = CliRunner().invoke(main, ["cycle", str(path), "--no-progress"])
    assert res.exit_code == 2, res.output
    (line,) = res.output.strip().splitlines()
    assert str(path) in line and "cycle.contact" in line and "pins[0].zone_width_m" in line and "compliant_pin" in line


def test_the_explicit_step_check_sums_the_component_pins_stiffness(tmp_path):
    """The position loop's step check (``check_steps``: (k dt^2 / m + 2 c dt / m) / 4 at most 0.5, semi-implicit
    Euler stable below 1) takes the contact's steepest slope, for a pin field the pins' stiffnesses summed (before,
    one pin's ``stiffness_n_per_m``, so a two-pin board at twice the stiffness passed unchecked). With K the total
    contact stiffness at index 0.5 (solved here from the index, m the plate's lightest apparent mass at the
    waypoints), two pins of K / 2 x (1 + 1e-3) are refused naming [cycle] time_step_s, x (1 - 1e-3) plan."""
    case = load_case(board_case(tmp_path / "probe.toml"))
    plan = plan_cycle(case)
    cycle = case.cycle
    points = np.array([cycle.start_m, *plan.scenario.trajectory.waypoints_m[1::4], cycle.end_m])
    mass = min(apparent_mass_kg(plan.scenario.rigid, p) for p in points)
    dt, gains = cycle.time_step_s, cycle.controller
    total = (2.0 - 2.0 * gains.kd_n_s_per_m * dt / mass) * mass / dt**2 - gains.kp_n_per_m
    assert step_stability(mass, gains.kp_n_per_m + total, gains.kd_n_s_per_m, dt) == pytest.approx(0.5, rel=1e-12)
    for factor, refused in ((1 + 1e-3, True), (1 - 1e-3, False)):
        path = board_case(tmp_path / f"k{factor}.toml")
        data = tomllib.loads(path.read_text())
        data["cycle"]["contact"]["stiffness_n_per_m"] = 0.5 * total * factor
        path.write_text(tomli_w.dumps(data))
        if refused:
            with pytest.raises(ModelFileError, match=r"\[cycle\] time_step_s"):
                plan_cycle(load_case(path))
        else:
            plan_cycle(load_case(path))


@pytest.mark.parametrize(("fit", "expected"), [("linear", 5e4 + 2e5), ("saturating", 5e4 + 40.0 / 2e-4)])
def test_the_step_checks_contact_slope_of_a_press_fit_pin_in_closed_form(fit, expected):
    """The stability check's contact slope for one pin on the axis with the press-fit law: k + k_fit (linear fit),
    k + F_fit / d_fit (the saturating fit's slope at 0, its steepest); the same law as a two-pin field (each pin at
    half the keys) goes through the force table and gives the same slope (its largest secant, 1e-6)."""
    from pressfit.description.cases import Contact
    from pressfit.dynamics.contact import contact_stiffness_bound_n_per_m

    keys = {"law": "press_fit", "stiffness_n_per_m": 5e4, "fit": fit, "fit_stiffness_n_per_m": 2e5,
            "fit_force_n": 40.0, "fit_depth_m": 2e-4}
    one = Contact(board_height_m=0.6, pin_position_m=[0.1, -0.05], **keys)
    assert contact_stiffness_bound_n_per_m(one) == pytest.approx(expected, rel=1e-12)
    half = {k: v / 2 for k, v in keys.items() if k in ("stiffness_n_per_m", "fit_stiffness_n_per_m", "fit_force_n")}
    two = Contact(board_height_m=0.6, pin_position_m=[0.1, -0.05], **{**keys, **half},
                  pins=[{"offset_m": [0.0, 0.0]}, {"offset_m": [0.0, 0.0]}])
    assert contact_stiffness_bound_n_per_m(two) == pytest.approx(expected, rel=1e-6 if fit == "linear" else 2e-2)
