"""Every bad input exits 2 with one line on stderr naming what is wrong, never a traceback (issue 10,
"Bad input" and the CLI fuzz test): non-finite, out-of-range and reversed option values, malformed lists,
a case file combined with options it would ignore, and random invalid case files (hypothesis)."""

from pathlib import Path

import numpy as np
import pytest
import tomli_w
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pressfit.cli import main

ROOT = Path(__file__).resolve().parents[2]
FUZZ = settings(derandomize=True, max_examples=60, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture])


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def assert_one_line_exit_2(res, *words):
    assert res.exit_code == 2, (res.output, res.exception)
    assert isinstance(res.exception, SystemExit) and "Traceback" not in res.output
    lines = [x for x in res.stderr.splitlines() if x.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    for w in words:
        assert w in lines[0], (w, lines[0])
    assert "array(" not in res.output and "overwrite=True" not in res.output and "Warning" not in res.stderr


# (command arguments with {} for the bad value, the option name the message must carry)
SLOTS = [
    (["solve", "0", "0.72", "0", "--load", "0", "700", "0", "--preload", "{}"], "--preload"),
    (["solve", "0", "0.72", "0", "--load", "0", "{}", "0"], "FX FY FZ"),
    (["solve", "{}", "0.72", "0", "--load", "0", "700", "0"], "FX FY FZ"),
    (["kinematics", "0", "{}", "0"], "'Y'"),
    (["stiffness", "{}", "0.72", "0"], "'X'"),
    (["interference", "0", "0.72", "0", "--margin", "{}"], "--margin"),
    (["interference", "--workspace", "--y-range", "{}", "0.6"], "--y-range"),
    (["workspace", "--y", "{}"], "--y"),
    (["study", "preload", "--pose", "0", "0.72", "0", "--preload", "{}"], "--preload"),
    (["study", "preload", "--pose", "0", "0.72", "0", "--preload", "100", "--clearance", "{}"], "--clearance"),
    (["study", "preload", "--pose", "0", "0.72", "0", "--preload", "100", "--load-max", "{}"], "--load-max"),
    (["study", "preload", "--pose", "{}", "0.72", "0", "--preload", "100"], "--pose"),
    (["modes", "0", "{}", "0"], "'Y'"),
    (["export-mjcf", "{}", "0.72", "0"], "'X'"),
    (["export-mjcf", "0", "0.72", "0", "--timestep", "{}"], "--timestep"),
]
BAD = ["nan", "inf", "-inf", "1e300", "1e400", "abc", "", "1,,2", ","]


@pytest.mark.parametrize("bad", BAD)
@pytest.mark.parametrize("slot", range(len(SLOTS)))
def test_every_bad_option_value_names_the_option(slot, bad, tmp_path):
    args, name = SLOTS[slot]
    res = run(*[a.replace("{}", bad) for a in args], "--no-progress" if args[0] in ("workspace", "study") else "",
              *(["--out", tmp_path / "o"] if args[0] in ("workspace", "study") else []))
    assert_one_line_exit_2(res, name)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("args, words", [
    (["interference", "--workspace", "--y-range", "0.6", "0.5"], ["--y-range", "LOW < HIGH"]),
    (["interference", "0", "0.72", "0", "--margin", "-1"], ["--margin"]),
    (["study", "preload", "--pose", "0", "0.72", "0", "--preload", "100", "--clearance", "1e-5,,2e-5"],
     ["--clearance", "empty"]),
    (["study", "preload", "--pose", "0", "0.72", "0", "--preload", "100", "--load-max", "0"], ["--load-max"]),
    (["solve", "0", "0.72", "0", "--load", "0", "1e300", "0"], ["outside"]),
    (["solve", "cases/paper/A.toml", "--preload", "400"], ["--preload", "[preload]"]),
    (["solve", "cases/studies/preload_pose_A.toml"], ["[clearance]"]),
])
def test_named_bad_inputs(args, words):
    assert_one_line_exit_2(run(*[str(ROOT / a) if a.startswith("cases/") else a for a in args]), *words)


VALID_CASE = {"name": "c", "poses": {"points_m": [[0.0, 0.72, 0.0]]}, "loads": {"press_force_n": 700.0},
              "envelope": {"max_tension_n": 1e6}}
NUMERIC_LEAVES = [("poses", "points_m"), ("loads", "press_force_n"), ("envelope", "max_tension_n")]
INVALID = st.one_of(st.sampled_from([float("nan"), float("inf"), -1.0, -1e9, True]),
                    st.text(max_size=5), st.lists(st.integers(), max_size=2), st.dictionaries(st.text(max_size=3),
                                                                                             st.integers(), max_size=1))


@pytest.mark.slow
@FUZZ
@given(leaf=st.sampled_from(NUMERIC_LEAVES), value=INVALID, command=st.sampled_from(["check", "solve"]))
def test_fuzz_invalid_case_values(tmp_path, leaf, value, command):
    """A numeric leaf of a valid case replaced by a value of the wrong type, non-finite or out of range."""
    data = {k: dict(v) if isinstance(v, dict) else v for k, v in VALID_CASE.items()}
    data[leaf[0]][leaf[1]] = value
    path = tmp_path / "fuzz.toml"
    path.write_text(tomli_w.dumps(data))
    assert_one_line_exit_2(run(command, path, *(["--no-progress"] if command == "check" else [])))


@FUZZ
@given(junk=st.binary(max_size=200), key=st.text(alphabet="abcxyz_", min_size=1, max_size=8))
def test_fuzz_garbage_and_unknown_keys(tmp_path, junk, key):
    """Random bytes appended to a case, or an unknown top-level key: exit 2, one line."""
    path = tmp_path / "g.toml"
    path.write_bytes(tomli_w.dumps(VALID_CASE | {f"x_{key}": 1}).encode())
    assert_one_line_exit_2(run("check", path, "--no-progress"), "x_" + key)
    path.write_bytes(b"name = " + junk)
    res = run("check", path, "--no-progress")
    if res.exit_code != 2:  # only a junk that parses as a valid name and nothing else could be valid: it is not
        pytest.fail(res.output)
    assert_one_line_exit_2(res)


@FUZZ
@given(slot=st.sampled_from(SLOTS), value=st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).filter(lambda x: x != x or abs(x) > 1e7),
    st.text(alphabet="abcxyz,;. ", max_size=6)))
def test_fuzz_option_values(slot, value):
    args, name = slot
    value = repr(value) if isinstance(value, float) else value
    res = run(*[a.replace("{}", value) for a in args])
    assert_one_line_exit_2(res, name)


def test_old_clearance_key_is_refused_with_its_new_name(tmp_path):
    """The play is applied along the leg, so the key says so; the old 'radial' name is refused, not ignored."""
    text = (ROOT / "models/pressfit_4upu.toml").read_text().replace("cardan_axial_clearance_m",
                                                                     "cardan_radial_clearance_m")
    (tmp_path / "m.toml").write_text(text)
    assert_one_line_exit_2(run("kinematics", 0, 0.72, 0, "--model", tmp_path / "m.toml"),
                           "renamed cardan_axial_clearance_m", "along the leg axis")


def test_a_value_just_beyond_a_limit_does_not_print_like_the_limit(machine):
    """alpha_2 = pi/2 at x = 0.36 m, y = 0.6 m (tan(alpha_2) = 0.6 / (D - x) with D = 0.36 m): 1e-9 m further
    the message must show the limit with enough digits and the excess, not '1.5708 breaks maximum 1.5708'."""
    from pressfit import kinematics
    from pressfit.errors import format_violation

    ((leg, what, value, limit),) = kinematics.violations(machine, [0.36 + 1e-9, 0.6, 0.0])
    assert (leg, what) == (2, "alpha [rad]") and value > np.pi / 2
    text = format_violation(leg, what, value, limit)  # "leg 2: alpha [rad] = <v> breaks maximum <limit>"
    shown_value, shown_limit = text.split(" = ")[1].split(" breaks maximum ")
    assert float(shown_value) > float(shown_limit) and float(shown_limit) == pytest.approx(np.pi / 2, abs=1e-9)
