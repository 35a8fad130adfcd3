"""Envelope checks: every kind of limit passes when loose and fails when tight; exit codes; JUnit.

References: pose A (0, 0.72, 0) under +700 N has closed forms (each leg 700/(4 sin alpha) in tension,
no couples, plate deflection 700/(4 k_a sin^2 alpha), no tilt). For the other quantities the limits
bracket the worst value the check itself reports on a small off-centre grid: those tests check the
comparison logic and the reporting, not the numbers (the numbers are tested in test_statics.py,
test_condensed.py and test_interference.py).
"""

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import tomli_w
from click.testing import CliRunner

from pressfit import kinematics
from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.studies.limit_check import LIMITS, evaluate_case

ROOT = Path(__file__).resolve().parents[2]

GRID = {"x": {"min_m": -0.25, "max_m": 0.25, "count": 3}, "y": {"min_m": 0.6, "max_m": 0.7, "count": 2},
        "z": {"min_m": -0.25, "max_m": 0.25, "count": 3}}
LOOSE = {"max_tension_n": 1e6, "max_compression_n": 1e6, "max_shear_n": 1e6, "max_bending_nm": 1e6,
         "max_torsion_nm": 1e6, "max_actuator_force_n": 1e6, "max_plate_deflection_m": 1.0,
         "max_plate_tilt_rad": 1.0, "min_buckling_safety_factor": 1e-6, "min_leg_length_margin_m": 0.0,
         "min_angle_margin_rad": 0.0, "min_interference_distance_m": -1.0}


def case_file(tmp_path, envelope, poses=GRID, name="c.toml", **extra):
    path = tmp_path / name
    path.write_text(tomli_w.dumps({"name": name[:-5], "poses": poses, "loads": {"press_force_n": 700.0},
                                   "envelope": envelope, **extra}))
    return path


@pytest.fixture(scope="module")
def loose_result(tmp_path_factory):
    return evaluate_case(load_case(case_file(tmp_path_factory.mktemp("env"), LOOSE)))


def test_every_limit_kind_is_evaluated_and_passes_when_loose(loose_result):
    assert {r.key for r in loose_result.limits} == set(LIMITS)
    assert loose_result.passed
    for r in loose_result.limits:
        assert math.isfinite(r.worst) and r.pose_m


@pytest.mark.parametrize("key", sorted(LIMITS))
def test_each_limit_fails_when_tighter_than_the_worst_value(tmp_path, loose_result, key):
    worst = next(r.worst for r in loose_result.limits if r.key == key)
    sense = LIMITS[key].sense
    tight = worst * (0.99 if sense == "max" else 1.01) if worst else (-1e-9 if sense == "max" else 1e-9)
    if sense == "max" and tight < 0:
        pytest.fail(f"{key}: worst value {worst} is not positive; cannot build a failing max limit")
    res = evaluate_case(load_case(case_file(tmp_path, {key: tight})))
    (line,) = res.limits
    assert not line.passed and not res.passed
    looser = worst * (1.01 if sense == "max" else 0.99) if worst > 0 else worst - 1e-9
    assert evaluate_case(load_case(case_file(tmp_path, {key: looser}, name="d.toml"))).passed


def test_pose_A_closed_forms(tmp_path, machine):
    """Tension, actuator force and deflection at pose A against closed forms (rel. 1e-9)."""
    env = {"max_tension_n": 1e6, "max_actuator_force_n": 1e6, "max_plate_deflection_m": 1.0,
           "max_plate_tilt_rad": 1.0, "max_torsion_nm": 1e6}
    res = evaluate_case(load_case(case_file(tmp_path, env, poses={"points_m": [[0.0, 0.72, 0.0]]})))
    worst = {r.key: r.worst for r in res.limits}
    alpha = math.atan(2.0)
    k_a = 1.0 / float(
        machine.axial_compliance_m_per_n(kinematics.inverse_kinematics(machine, [0, 0.72, 0]).lengths_m[0])
    )
    assert worst["max_tension_n"] == pytest.approx(700 / (4 * math.sin(alpha)), rel=1e-9)
    assert worst["max_actuator_force_n"] == pytest.approx(700 / (4 * math.sin(alpha)), rel=1e-9)
    # small-displacement deflection; the nonlinear refinement differs by O(strain) ~ 1e-5
    assert worst["max_plate_deflection_m"] == pytest.approx(700 / (4 * k_a * math.sin(alpha) ** 2), rel=1e-4)
    assert worst["max_plate_tilt_rad"] < 1e-12 and worst["max_torsion_nm"] < 1e-9


def test_unreachable_pose_fails_with_leg_and_limit(tmp_path):
    res = evaluate_case(load_case(case_file(tmp_path, {"max_tension_n": 1e6},
                                            poses={"points_m": [[0.0, 0.72, 0.0], [0.0, 0.95, 0.3]]})))
    assert not res.passed and len(res.unreachable) == 1
    assert "leg 1: leg length l [m]" in res.unreachable[0]["reason"]


def test_cli_exit_codes_junit_and_json(tmp_path):
    good = case_file(tmp_path, {"max_tension_n": 1e6}, name="good.toml")
    bad = case_file(tmp_path, {"max_plate_tilt_rad": 1e-4}, name="bad.toml")
    runner = CliRunner()
    ok = runner.invoke(main, ["check", str(good), "--no-progress"])
    assert ok.exit_code == 0, ok.output
    junit, js = tmp_path / "r.xml", tmp_path / "r.json"
    fail = runner.invoke(
        main, ["check", str(good), str(bad), "--junit", str(junit), "--json", str(js), "--no-progress"]
    )
    assert fail.exit_code == 1 and "FAIL plate tilt" in fail.output and "EXCEEDS limit" in fail.output
    root = ET.parse(junit).getroot()  # well-formed XML
    suites = {s.get("name"): s for s in root.iter("testsuite")}
    assert suites["bad"].get("failures") == "1" and suites["good"].get("failures") == "0"
    assert suites["bad"].find("testcase/failure") is not None
    # results are never overwritten without being asked
    again = runner.invoke(main, ["check", str(good), "--json", str(js), "--no-progress"])
    assert again.exit_code == 2 and "exists" in again.output
    assert runner.invoke(main, ["check", str(tmp_path / "nope.toml")]).exit_code == 2


@pytest.mark.slow
def test_shipped_cases_pass_and_example_fails():
    """Every shipped case passes `pressfit check` (its envelope statically and, with a [simulation], the run against
    its limits), each insertion case by name with its static plate-deflection line; a too tight example fails."""
    runner = CliRunner()
    res = runner.invoke(main, ["check", str(ROOT / "cases"), "--no-progress"])
    assert res.exit_code == 0, res.output
    blocks = {b.split()[0]: b for b in re.split(r"^PASS  ", res.output, flags=re.M)[1:]}
    for name in ("paper-insertion", "paper-insertion-electric", "paper-insertion-hydraulic",
                 "paper-insertion-linear-motor"):
        assert "insertion simulation, limiter on" in blocks[name], res.output
        assert ("max_plate_deflection_m" in blocks[name]) == (name != "paper-insertion"), blocks[name]
    res = runner.invoke(main, ["check", str(ROOT / "docs/examples/too_tight.toml"), "--no-progress"])
    assert res.exit_code == 1 and "FAIL plate tilt" in res.output


def test_clearance_case_sheds_load_from_opened_legs(tmp_path):
    """Pose A, preload a4 = 200 N along v_p = (-1, 1, -1, 1)/2, 20 um axial plays, 700 N up: legs 1 and 3
    (compressed by the preload) open at 2 a4 sin(alpha) = 358 N < 700 N, after which legs 2 and 4 carry
    everything: N = 700 / (2 sin(alpha)) = 391.3 N (closed form; 0.5% covers the smoothing and the
    contact law). Without [clearance] the linear superposition gives 100 + 700 / (4 sin(alpha)) N."""
    env, pose_a, preload = {"max_tension_n": 1e6}, {"points_m": [[0.0, 0.72, 0.0]]}, {"a4_n": 200.0}
    s = math.sin(math.atan(2.0))
    plain = evaluate_case(load_case(case_file(tmp_path, env, pose_a, "p.toml", preload=preload)))
    assert plain.limits[0].worst == pytest.approx(100 + 700 / (4 * s), rel=1e-9)
    res = evaluate_case(load_case(case_file(tmp_path, env, pose_a, "c.toml", preload=preload,
                                            clearance={"gaps_m": [20e-6] * 8})))
    assert res.limits[0].worst == pytest.approx(700 / (2 * s), rel=5e-3)
    assert "clearance" in res.limits[0].method


def test_buckling_limit_uses_the_whole_machine_factor(tmp_path):
    """A downward press at pose A: the refined buckling line is the machine's linearised factor
    (pressfit.mechanics.buckling.machine_buckling, a plate-rotation mode, 143), not the per-leg Euler factor
    (1197, what the check reported before): a limit of 200 fails; the Euler check alone passed it."""
    from pressfit.mechanics.buckling import machine_buckling

    one = {k: {"min_m": v, "max_m": v, "count": 1} for k, v in (("x", 0.0), ("y", 0.72), ("z", 0.0))}
    path = tmp_path / "b.toml"
    path.write_text(tomli_w.dumps({"name": "b", "poses": one, "loads": {"press_force_n": 700.0,
                                                                        "direction": [0.0, -1.0, 0.0]},
                                   "envelope": {"min_buckling_safety_factor": 200.0}}))
    line = evaluate_case(load_case(path)).limits[0]
    ref = machine_buckling(load_case(path).machine(), [0, 0.72, 0], [0, -700, 0, 0, 0, 0])
    assert line.worst == pytest.approx(ref.load_factor, rel=1e-9) and line.worst < 0.2 * ref.leg_euler_factors.min()
    assert not line.passed and "whole-machine linearised buckling" in line.method
