"""Case files: the shipped cases load; malformed files give a clear error naming file and key."""

import copy
import math
import random
from pathlib import Path

import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner

from pressfit.cli import main
from pressfit.description.cases import discover, load_case
from pressfit.errors import ModelFileError

ROOT = Path(__file__).resolve().parents[2]
VALID = {
    "name": "fuzz",
    "poses": {"points_m": [[0.0, 0.6, 0.0]], "x": {"min_m": -0.1, "max_m": 0.1, "count": 3},
              "y": {"min_m": 0.6, "max_m": 0.6, "count": 1}, "z": {"min_m": -0.1, "max_m": 0.1, "count": 2}},
    "loads": {"press_force_n": 700.0, "cone_half_angle_rad": 0.1, "cone_directions": 4},
    "preload": {"a4_n": 50.0, "mode": "force"},
    "envelope": {"max_tension_n": 500.0, "max_torsion_nm": 90.0, "max_plate_tilt_rad": 1e-3},
}


def write(tmp_path, data, name="case.toml"):
    path = tmp_path / name
    path.write_text(tomli_w.dumps(data))
    return path


def test_shipped_cases_validate():
    files = discover([ROOT / "cases"])
    assert len(files) >= 3
    for f in files:
        load_case(f)


def test_grid_and_cone(tmp_path):
    case = load_case(write(tmp_path, VALID))
    assert case.poses.array().shape == (1 + 3 * 1 * 2, 3)
    w = case.loads.wrenches()
    assert w.shape == (5, 6)
    # every cone direction makes the stated half-angle with the axis (+y) and carries 700 N
    assert np.allclose(np.linalg.norm(w[:, :3], axis=1), 700.0)
    assert np.allclose(np.degrees(np.arccos(w[1:, 1] / 700.0)), np.degrees(0.1))


@pytest.mark.parametrize(("mutate", "key"), [
    (lambda d: d.pop("poses"), "poses"),
    (lambda d: d.update(extra=1), "extra"),
    (lambda d: d["loads"].update(press_force_n="700 N"), "loads.press_force_n"),
    (lambda d: d["loads"].update(press_force_n=math.nan), "loads.press_force_n"),
    (lambda d: d["loads"].update(press_force_n=1e30), "loads.press_force_n"),
    (lambda d: d["poses"]["x"].update(count=0), "poses.x.count"),
    (lambda d: d["poses"]["x"].update(count=1), "poses.x"),  # one point over a range: was silently min_m
    (lambda d: d["envelope"].update(max_tension_n=-1.0), "envelope.max_tension_n"),
    (lambda d: d["preload"].update(mode="torque"), "preload.mode"),
    (lambda d: d.update(model_overrides={"limits": {"leg_length_min_m": 2.0}}), "limits"),
])
def test_malformed_case_names_file_and_key(tmp_path, mutate, key):
    data = copy.deepcopy(VALID)
    mutate(data)
    path = write(tmp_path, data)
    with pytest.raises(ModelFileError) as exc:
        load_case(path).machine()
    assert key in str(exc.value) and str(tmp_path) in str(exc.value)


def _numeric_leaves(d, prefix=()):
    for k, v in d.items():
        if isinstance(v, dict):
            yield from _numeric_leaves(v, (*prefix, k))
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            yield (*prefix, k)


def test_fuzz_malformed_cases_never_traceback(tmp_path):
    """Random always-invalid mutations (deleted required keys, type swaps, NaN, huge forces) through
    the CLI: every one exits 2 with 'error: <file>: key ...', never a traceback."""
    rng = random.Random(20261122)
    leaves = list(_numeric_leaves(VALID))
    runner = CliRunner()
    for i in range(60):
        data = copy.deepcopy(VALID)
        kind = rng.choice(["delete", "string", "nan", "list", "huge"])
        if kind == "delete":
            data.pop(rng.choice(["name", "poses", "loads"]))
        elif kind == "huge":
            data["loads"]["press_force_n"] = 10 ** rng.randint(8, 300) * 1.0
        else:
            *path, leaf = rng.choice(leaves)
            node = data
            for k in path:
                node = node[k]
            node[leaf] = {"string": "abc", "nan": math.nan, "list": [1.0, 2.0]}[kind]
        f = write(tmp_path, data, f"fuzz{i}.toml")
        result = runner.invoke(main, ["check", str(f), "--no-progress"])
        assert result.exit_code == 2, (kind, result.output)
        assert result.exception is None or isinstance(result.exception, SystemExit)
        assert "Traceback" not in result.output and f"fuzz{i}.toml: key '" in result.output


def test_bad_toml_and_missing_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("name = [unclosed")
    with pytest.raises(ModelFileError, match="bad.toml: key '<syntax>'"):
        load_case(bad)
    with pytest.raises(ModelFileError, match="does not exist"):
        discover([tmp_path / "missing.toml"])


def test_a_shipped_case_that_promises_pressfit_check_has_limits_to_check():
    """issue 28 item 8: a shipped case whose description says `pressfit check` verifies it has limits the check
    evaluates (a non-empty [envelope], [simulation.limits] or [cycle.limits]); cases/paper/board.toml says so."""
    promising = []
    for path in discover([ROOT / "cases"]):
        case = load_case(path)
        if "pressfit check" not in " ".join(case.description.split()):
            continue
        promising.append(path.name)
        limits = case.envelope.model_dump(exclude_none=True) or (
            case.simulation is not None and case.simulation.limits.model_dump(exclude_none=True)) or (
            case.cycle is not None and case.cycle.limits.model_dump(exclude_none=True))
        assert limits, f"{path} promises `pressfit check` but has no limits to check"
    assert "board.toml" in promising


def test_a_one_pin_grid_axis_over_a_range_is_refused(tmp_path):
    """[cycle.grid] with count = 1 and min_m < max_m would place its one pin at min_m: refused, naming the key."""
    text = (ROOT / "cases" / "paper" / "board.toml").read_text()
    head, grid = text.split("[cycle.grid]", 1)
    body, rest = grid.split("\n[", 1)
    x_line = next(line for line in body.splitlines() if line.strip().startswith("x ="))
    bad = head + "[cycle.grid]" + body.replace(x_line, 'x = { min_m = -0.1, max_m = 0.1, count = 1 }') + "\n[" + rest
    tmp = tmp_path / "one_pin_grid.toml"
    tmp.write_text(bad)
    with pytest.raises(ModelFileError, match=r"cycle\.grid\.x.*count = 1 places one point"):
        load_case(tmp)
    res = CliRunner().invoke(main, ["cycle", str(tmp)])
    assert res.exit_code == 2 and len(res.output.strip().splitlines()) == 1 and "cycle.grid.x" in res.output
