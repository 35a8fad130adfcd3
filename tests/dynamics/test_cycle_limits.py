"""``[cycle.limits]`` asserted by ``pressfit check``: every limit just over the figure recomputed here from
cycle.csv passes, just under fails (exit 1), one line each in the report, the JSON and the JUnit XML; a bad key is
exit 2 naming it."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner

from pressfit.cli import main
from tests.dynamics.test_cycle import board
from tests.dynamics.test_cycle_sizing import legs, read_csv

PINS = [{"x_m": 0.10, "z_m": -0.05}, {"x_m": 0.0, "z_m": 0.0}]
REL = 1e-6  # "just": the limits are the recomputed figure x (1 +- 1e-6) (the CSV holds full-precision floats)


def run(*args: object):
    return CliRunner().invoke(main, [str(a) for a in args])


def figures(tmp: Path, case: Path) -> dict[str, float]:
    """Each [cycle.limits] figure recomputed from ``pressfit cycle``'s CSV (and the case's pins)."""
    res = run("cycle", case, "--no-progress", "--out", tmp / "out")
    assert res.exit_code == 0, res.output
    c = read_csv(tmp / "out/cycle.csv")
    data = tomllib.loads(case.read_text())["cycle"]
    dt = data["time_step_s"]
    t, segment, pin, force = c["time_s"], c["segment"].astype(int), c["pin"].astype(int), c["contact_force_n"]
    # the cycle ends where the reference reaches end_m: the settle (the last segment) starts. The rows are at
    # t = k dt and a row's segment is the one its time falls in, so the first settle row is within dt after it
    settle = t[np.flatnonzero(segment == segment.max())[0]]
    overshoot, alignment = [], []
    for k, p in enumerate(data["pins"], start=1):
        rows = np.flatnonzero(pin == k)
        overshoot.append(max(force[rows].max() - data["controller"]["force_limit_n"], 0.0))
        first = rows[np.flatnonzero(force[rows] > 0.0)[0]]
        alignment.append(float(np.hypot(c["tool_x_m"][first] - p["x_m"], c["tool_z_m"][first] - p["z_m"])))
    n, v = legs(c, "act_n"), legs(c, "rate_m_per_s")
    return {"settle_start_s": settle, "dt_s": dt, "max_overshoot_n": max(overshoot),
            "worst_overshoot_pin": int(np.argmax(overshoot)) + 1, "max_alignment_error_m": max(alignment),
            "worst_alignment_pin": int(np.argmax(alignment)) + 1,
            "max_rms_drive_force_n": float(np.sqrt(np.mean(n**2, axis=0)).max()),
            "max_peak_drive_force_n": float(np.abs(n).max()),
            "max_energy_per_cycle_j": float(np.clip(-n * v, 0.0, None).sum() * dt)}


def with_limits(case: Path, name: str, limits: dict[str, float]) -> Path:
    data = tomllib.loads(case.read_text())
    data["cycle"]["limits"] = limits
    out = case.with_name(name)
    out.write_text(tomli_w.dumps(data))
    return out


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("limits")
    # a 2 mm/s descent (10 x the shipped board's): the force loop overshoots the 30 N limit
    case = board(tmp, pins=PINS, dwell_s=0.1, settle_s=0.1,
                 descent={"speed_m_per_s": 0.1, "acceleration_m_per_s2": 0.5, "jerk_m_per_s3": 5.0})
    return tmp, case, figures(tmp, case)


KEYS = ("max_overshoot_n", "max_alignment_error_m", "max_rms_drive_force_n", "max_peak_drive_force_n",
        "max_energy_per_cycle_j")


@pytest.mark.parametrize("side", ["over", "under"])
def test_limits_just_over_pass_and_just_under_fail(measured, side):
    """Every limit at the recomputed figure x (1 + 1e-6) passes (exit 0), x (1 - 1e-6) fails (exit 1); the cycle
    time, known from the CSV only to a step, at the first settle row + dt and - 2 dt. One line each, in the report,
    the JSON and the JUnit XML, the worst pin or drive named."""
    tmp, case, f = measured
    assert f["max_overshoot_n"] > 1.0  # the case is built to overshoot: its failing side can fail
    scale = 1 + REL if side == "over" else 1 - REL
    limits = {k: f[k] * scale for k in KEYS}
    limits["max_cycle_time_s"] = f["settle_start_s"] + (f["dt_s"] if side == "over" else -2 * f["dt_s"])
    path = with_limits(case, f"{side}.toml", limits)
    out = tmp / side
    out.mkdir()
    res = run("check", path, "--no-progress", "--json", out / "c.json", "--junit", out / "c.xml")
    assert res.exit_code == (0 if side == "over" else 1), res.output
    lines = json.loads((out / "c.json").read_text())["cases"][0]["limits"]
    cycle = {x["key"]: x for x in lines if x["key"].startswith("cycle.")}
    assert sorted(cycle) == sorted(f"cycle.{k}" for k in limits)
    for key, line in cycle.items():
        assert line["passed"] is (side == "over"), line
        assert res.output.count(key) == 1, (key, res.output)
    xml = (out / "c.xml").read_text()
    assert all(f'name="{k}"' in xml or k in xml for k in cycle)
    assert f"worst pin {f['worst_overshoot_pin']} " in cycle["cycle.max_overshoot_n"]["method"]
    assert f"worst pin {f['worst_alignment_pin']} " in cycle["cycle.max_alignment_error_m"]["method"]
    n = legs(read_csv(tmp / "out/cycle.csv"), "act_n")
    assert cycle["cycle.max_peak_drive_force_n"]["leg"] == int(np.abs(n).max(axis=0).argmax()) + 1


def test_bad_cycle_limit_key_is_exit_2(measured):
    """An unknown key and a negative limit: exit 2, the file and the key named (no board is simulated)."""
    tmp, case, _ = measured
    for name, limits, why in (("bad.toml", {"max_cycle_time": 5.0}, "unknown key"),
                              ("negative.toml", {"max_cycle_time_s": -5.0}, "greater than or equal to 0")):
        res = run("check", with_limits(case, name, limits), "--no-progress")
        assert res.exit_code == 2, res.output
        key = f"cycle.limits.{next(iter(limits))}'"
        assert key in res.output and name in res.output and why in res.output, res.output
        assert "Traceback" not in res.output
