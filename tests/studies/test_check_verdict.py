"""``pressfit check`` verdicts that must not pass by accident (issue 10, "The CI check can pass when it
should fail"): the whole linear sweep decides (refine_worst = 0), a load beyond buckling is a failed limit,
malformed files are errors while the others are still checked, unreachable poses are summarised."""

import json
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner

from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.mechanics.statics import solve_equilibrium
from pressfit.studies.limit_check import evaluate_case

POSES = [[0.25, 0.6, 0.25], [-0.25, 0.55, 0.25], [0.0, 0.72, 0.0], [0.2, 0.7, -0.2]]
CONE = {"press_force_n": 700.0, "cone_half_angle_rad": 0.5, "cone_directions": 8}  # 9 load directions


def write_case(path, envelope, poses=POSES, loads=CONE, **extra):
    path.write_text(tomli_w.dumps({"name": path.stem, "poses": {"points_m": poses}, "loads": loads,
                                   "envelope": envelope, **extra}))
    return path


def check(*args):
    return CliRunner().invoke(main, ["check", *map(str, args), "--no-progress"])


@pytest.mark.slow
def test_refine_worst_0_takes_the_worst_of_every_pose_and_load(tmp_path, machine):
    """Reference: the linear Pinocchio solve (independent of the condensed sweep) at all 4 x 9 pairs. Its
    largest tension (760 N) is far above the largest at the first load (467 N, what the old code looked at),
    so a 600 N limit must fail. Tolerance 1e-9: the two linear models agree to round-off (1e-14 seen)."""
    case = load_case(write_case(tmp_path / "rw.toml", {"max_tension_n": 600.0},
                                solver={"refine_worst": 0, "linear": True}))
    tension = np.array([[solve_equilibrium(machine, h, w, linear=True).actuator_forces_n
                         for w in case.loads.wrenches()] for h in POSES])
    assert tension[:, 0].max() < 600.0 < tension.max()  # the case discriminates the bug
    (line,) = evaluate_case(case).limits
    assert line.worst == pytest.approx(tension.max(), rel=1e-9) and not line.passed
    assert check(tmp_path / "rw.toml").exit_code == 1


@pytest.mark.parametrize("envelope, key", [({"max_tension_n": 1e7}, "stable_equilibrium"),
                                           ({"min_buckling_safety_factor": 2.0}, "min_buckling_safety_factor")])
def test_load_beyond_buckling_is_a_failed_limit_with_case_pose_and_load(tmp_path, envelope, key):
    """A 2 MN downward press at pose A compresses each leg by 2e6 / (4 sin(atan 2)) = 559 kN, above the
    legs' Euler load (tens of kN): no stable equilibrium. That is a FAIL (exit 1) naming the pose and load."""
    path = write_case(tmp_path / "press.toml", envelope, poses=[[0.0, 0.72, 0.0]],
                      loads={"press_force_n": 2e6, "direction": [0.0, -1.0, 0.0]})
    res = check(path)
    assert res.exit_code == 1, res.output
    line = next(x for x in res.output.splitlines() if key in x)
    assert line.lstrip().startswith("FAIL") and "pose (0, 0.72, 0)" in line and "-2e+06" in line
    assert "FAIL  press" in res.output
    if key == "stable_equilibrium":
        assert "no stable equilibrium" in line
    else:  # the whole machine's linearised buckling factor; it scales as 1 / load (linear reference state)
        from pressfit.mechanics.buckling import machine_buckling

        at_700 = machine_buckling(load_case(path).machine(), [0.0, 0.72, 0.0], [0.0, -700.0, 0, 0, 0, 0]).load_factor
        shown = float(line.split("worst ")[1].split()[0])
        assert shown == pytest.approx(at_700 * 700 / 2e6, rel=1e-5) and shown < 1


def test_unstable_refinement_without_a_buckling_limit_is_a_stable_equilibrium_line(tmp_path):
    """The same press with only a tension limit: a separate stable_equilibrium line (limit 1 = stable, value
    0 = none found) with the pose and the load."""
    path = write_case(tmp_path / "t.toml", {"max_tension_n": 1e7}, poses=[[0.0, 0.72, 0.0]],
                      loads={"press_force_n": 2e6, "direction": [0.0, -1.0, 0.0]})
    lines = {x.key: x for x in evaluate_case(load_case(path)).limits}
    assert set(lines) == {"max_tension_n", "stable_equilibrium"}
    line = lines["stable_equilibrium"]
    assert (line.worst, line.limit, line.passed, line.sense) == (0.0, 1.0, False, "min")
    assert line.pose_m == [0.0, 0.72, 0.0] and line.load == [0.0, -2e6, 0.0, 0.0, 0.0, 0.0]


@pytest.mark.parametrize("poses", [[[0.0, 0.72, 0.0]], [[0.0, 0.72, 0.0], [0.1, 0.7, 0.1]]])
def test_unstable_refinement_fails_the_buckling_line_of_a_case_that_has_one(tmp_path, poses):
    """The tension refinement under a 2 MN downward press (every leg far beyond Euler at both poses) finds no
    stable equilibrium. With a buckling limit in the case that is its line, reported as factor 0 with the pose
    and load and how many more pairs are likewise unstable (none with one pose, 1 with two); there is no
    separate stable_equilibrium line, and the tension line stays."""
    path = write_case(tmp_path / "both.toml", {"max_tension_n": 1e7, "min_buckling_safety_factor": 2.0},
                      poses=poses, loads={"press_force_n": 2e6, "direction": [0.0, -1.0, 0.0]})
    lines = {x.key: x for x in evaluate_case(load_case(path)).limits}
    assert set(lines) == {"max_tension_n", "min_buckling_safety_factor"}
    line = lines["min_buckling_safety_factor"]
    assert line.worst == 0.0 and not line.passed and line.sense == "min" and line.limit == 2.0
    assert line.load == [0.0, -2e6, 0.0, 0.0, 0.0, 0.0] and line.pose_m in poses
    assert line.method.startswith("no stable equilibrium under this load in the nonlinear solve")
    more = "; 1 more (pose, load) pairs likewise"
    assert line.method.endswith(more) if len(poses) == 2 else "more (pose, load)" not in line.method


def test_malformed_files_are_errors_and_the_others_are_still_checked(tmp_path):
    good = write_case(tmp_path / "good.toml", {"max_tension_n": 1e6}, poses=[[0.0, 0.72, 0.0]])
    (tmp_path / "broken.toml").write_text("name = ")
    (tmp_path / "wrong.toml").write_text("name = 'w'\n[poses]\npoints_m = [[0, 0.72, 0]]\n[loads]\nforce_n = 1\n")
    junit, js = tmp_path / "out" / "r.xml", tmp_path / "out" / "r.json"
    res = CliRunner().invoke(main, ["check", str(tmp_path), "--junit", str(junit), "--json", str(js),
                                    "--no-progress"])
    assert res.exit_code == 2
    assert "PASS  good" in res.output and "1 passed, 0 failed, 2 in error" in res.output
    assert "ERROR" in res.output and "broken.toml" in res.output and "wrong.toml" in res.output
    suites = {s.get("name"): s for s in ET.parse(junit).getroot().iter("testsuite")}
    assert suites["good"].get("failures") == "0"
    errors = [s for name, s in suites.items() if name.endswith(("broken.toml", "wrong.toml"))]
    assert len(errors) == 2 and all(s.find("testcase/error") is not None for s in errors)
    out = json.loads(js.read_text())
    assert out["exit_code"] == 2 and len(out["errors"]) == 2 and out["cases"][0]["case"] == "good"
    assert good.exists()


def test_unreachable_poses_are_summarised_with_the_worst_and_listed_in_full(tmp_path, machine):
    """121 poses of which the far ones break the leg-length limit: one summary line, not one per pose; the
    worst excess is the largest leg length of the grid minus l_max (closed-form inverse kinematics)."""
    from pressfit import kinematics

    poses = [[x, 0.85, z] for x in np.linspace(-0.3, 0.3, 11) for z in np.linspace(-0.3, 0.3, 11)]
    path = write_case(tmp_path / "far.toml", {"max_tension_n": 1e6}, poses=poses, loads={"press_force_n": 700.0})
    ok = kinematics.is_reachable(machine, np.array(poses))
    lengths = kinematics.inverse_kinematics(machine, np.array(poses)).lengths_m
    excess = lengths.max() - machine.limits.leg_length_max_m
    assert 0 < ok.sum() < len(poses) and excess > 0
    res = check(path, "--json", tmp_path / "r.json")
    assert res.exit_code == 1
    lines = [x for x in res.output.splitlines() if "poses unreachable" in x]
    assert len(lines) == 1 and f"{(~ok).sum()} of {len(poses)} poses unreachable" in lines[0]
    assert f"worst leg-length excess {excess:.4g} m" in lines[0]
    out = json.loads((tmp_path / "r.json").read_text())
    assert len(out["cases"][0]["unreachable"]) == (~ok).sum()
    assert max(u["leg_length_excess_m"] for u in out["cases"][0]["unreachable"]) == pytest.approx(excess, rel=1e-12)
    assert not math.isnan(excess)


def test_output_targets_are_refused_before_any_computation(tmp_path):
    path = write_case(tmp_path / "c.toml", {"max_tension_n": 1e6}, poses=[[0.0, 0.72, 0.0]])
    (tmp_path / "dir").mkdir()
    (tmp_path / "file").write_text("x")
    for args in (["--junit", tmp_path / "dir"], ["--json", tmp_path / "file"],
                 ["--json", tmp_path / "file" / "r.json"]):
        res = CliRunner().invoke(main, ["check", str(path), *map(str, args), "--no-progress"])
        assert res.exit_code == 2 and res.exception is None or isinstance(res.exception, SystemExit)
        assert "PASS" not in res.output and res.output.count("\n") == 1, res.output  # refused before the sweep


def test_clearance_limits_and_geometry_limits_in_one_case(tmp_path):
    """Regression: the clearance refinement used to rebind the name of the geometry-limit table, so a case with
    [clearance], a clearance-sensitive limit and a joint-limit margin crashed. Reference for the deflection:
    at pose A the cardans' play adds the lost motion 2 g / sin(alpha) = 44.7 um (g = 20 um, tan alpha = 2) to the
    elastic deflection, so the worst deflection is above it; the leg-length margin is exact (closed form:
    l = |(0, 0.72, 0.36)| = 0.805 m, 0.195 m from l_max = 1 m)."""
    path = write_case(tmp_path / "cl.toml", {"max_plate_deflection_m": 1e-3, "min_leg_length_margin_m": 0.0},
                      poses=[[0.0, 0.72, 0.0]], loads={"press_force_n": 700.0},
                      clearance={"gaps_m": [20e-6] * 8})
    (deflection, margin) = evaluate_case(load_case(path)).limits
    assert deflection.key == "max_plate_deflection_m" and deflection.worst > 2 * 20e-6 / (2 / 5**0.5)
    assert margin.worst == pytest.approx(1.0 - math.hypot(0.72, 0.36), rel=1e-12) and margin.passed
