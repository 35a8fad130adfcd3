"""Unit tests of pressfit.machine: the shipped model, derived geometry, and malformed model files."""

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.description.machine import DEFAULT_MODEL, load_machine
from pressfit.errors import ModelFileError


def test_default_model(machine):
    """Table 3's geometry and limits, and the legs of docs/conventions.md's table."""
    assert machine.geometry.base_half_side_m == 0.442 and machine.geometry.plate_half_side_m == 0.082
    assert (machine.limits.leg_length_min_m, machine.limits.leg_length_max_m) == (0.5, 1.0)
    assert machine.limits.beta_max_rad == pytest.approx(np.pi / 4, rel=1e-15)
    np.testing.assert_allclose(machine.base_points_m, 0.442 * np.array(
        [[0, 0, -1], [1, 0, 0], [0, 0, 1], [-1, 0, 0]]), atol=0)
    np.testing.assert_allclose(machine.plate_offsets_m, machine.base_points_m * 0.082 / 0.442, rtol=1e-15)


def test_leg_tube_masses(machine):
    """Tube masses from the sections by hand: steel 7850 kg/m^3, cylinder tube 60 x 5 mm over 0.45 m, the stem a
    30 mm rod of 0.60 m whatever the pose (3.329 kg: it slides in the cylinder, it does not grow); its centre of
    mass at l - 0.30 m from the base cardan (its outer end at the plate cardan); exact up to round-off."""
    rho = 7850.0
    assert machine.mass.density_kg_per_m3 == rho
    assert machine.stem.length_m == 0.60
    assert machine.cylinder_tube_mass_kg == pytest.approx(rho * np.pi / 4 * (0.06**2 - 0.05**2) * 0.45, rel=1e-13)
    assert machine.stem_mass_kg == pytest.approx(rho * np.pi / 4 * 0.03**2 * 0.60, rel=1e-13)
    np.testing.assert_allclose(machine.stem_centre_of_mass_m(np.array([0.5, 0.8, 1.0])), [0.2, 0.5, 0.7],
                               rtol=1e-13)


@pytest.mark.parametrize(("length", "accepted"), [(0.55 * (1 + 1e-9), True), (0.55 * (1 - 1e-9), False),
                                                  (0.55, False)])
def test_a_stem_rod_must_outlast_the_stroke(tmp_path, length, accepted):
    """The rod must be longer than the longest exposed stem the limits allow, l_max - L_c = 1.0 - 0.45 = 0.55 m
    (the full stroke leaves rod in the cylinder): just over is accepted, just under and equal refused by a
    ModelFileError naming the file, the key stem.length_m and the limit; the same through an override."""
    path = _write(tmp_path, "length_m = 0.60 ", f"length_m = {length!r} ")
    if accepted:
        assert load_machine(path).stem.length_m == length
        return
    with pytest.raises(ModelFileError) as info:
        load_machine(path)
    assert info.value.key == "stem.length_m" and str(path) in str(info.value) and "0.55 m" in str(info.value)
    with pytest.raises(ModelFileError, match="stem.length_m"):
        load_machine().with_overrides({"stem": {"length_m": length}})


def test_a_machine_file_without_the_stem_length_is_refused_naming_the_key(tmp_path):
    """A machine file written before the stem became a rod of its own length (no ``[stem] length_m``) is refused:
    exit 2, one ``error:`` line naming the file and the key (its mass cannot be guessed from the pose)."""
    text = DEFAULT_MODEL.read_text(encoding="utf-8")
    path = tmp_path / "old.toml"
    path.write_text("\n".join(x for x in text.splitlines() if not x.startswith("length_m = 0.60")), encoding="utf-8")
    res = CliRunner().invoke(main, ["kinematics", "--model", str(path), "0", "0.65", "0"])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and str(path) in lines[0] and "stem.length_m" in lines[0]


def test_raising_l_max_needs_a_longer_rod(tmp_path):
    """Case C raises l_max to 1.05 m: with the shipped 0.60 m rod it is refused (the longest exposed stem is then
    0.60 m), the case's 0.65 m rod is accepted; the CLI says so in one error line (exit 2)."""
    with pytest.raises(ModelFileError, match="stem.length_m"):
        load_machine().with_overrides({"limits": {"leg_length_max_m": 1.05}})
    case = load_case(DEFAULT_MODEL.parents[1] / "cases" / "paper" / "C.toml").machine()
    assert case.stem.length_m == 0.65
    path = _write(tmp_path, "length_m = 0.60 ", "length_m = 0.50 ")
    res = CliRunner().invoke(main, ["kinematics", "--model", str(path), "0", "0.65", "0"])
    assert res.exit_code == 2, res.output
    assert len(res.output.strip().splitlines()) == 1 and "stem.length_m" in res.output and "error:" in res.output
    assert str(path) in res.output and "0.55 m" in res.output


def test_overrides_are_validated(machine):
    m = machine.with_overrides({"actuator": {"axial_stiffness_n_per_m": 1e8}})
    assert m.actuator.axial_stiffness_n_per_m == 1e8
    with pytest.raises(ModelFileError, match="actuator.axial_stiffness_n_per_m"):
        machine.with_overrides({"actuator": {"axial_stiffness_n_per_m": -1.0}})


def _write(tmp_path, old, new):
    text = DEFAULT_MODEL.read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    return path


BAD_FILES = {  # id: (replace, by, expected key, words in the expectation)
    "missing key": ("base_half_side_m = 0.442", "", "geometry.base_half_side_m", "required"),
    "unknown key": ("[geometry]", "[geometry]\nbase_radius_m = 0.4", "geometry.base_radius_m", "unknown key"),
    "wrong type": ("base_half_side_m = 0.442", 'base_half_side_m = "wide"', "geometry.base_half_side_m",
                   "valid number"),
    "table for number": ("leg_length_max_m = 1.0", "leg_length_max_m = {value = 1.0}",
                         "limits.leg_length_max_m", "valid number"),
    "negative length": ("base_half_side_m = 0.442", "base_half_side_m = -0.442", "geometry.base_half_side_m",
                        "greater than 0"),
    "l_min >= l_max": ("leg_length_min_m = 0.5", "leg_length_min_m = 1.0", "limits",
                       "leg_length_min_m must be smaller than leg_length_max_m"),
    "two legs on one radial direction": ("radial_direction = [-1.0", "radial_direction = [1.0", "legs",
                                         "legs 2 and 4 have the same radial_direction"),
    "negative density": ("density_kg_per_m3 = 7850.0", "density_kg_per_m3 = -7850.0", "mass.density_kg_per_m3",
                         "greater than 0"),
    "unknown mass key": ("[mass]", "[mass]\nleg_mass_kg = 3.0", "mass.leg_mass_kg", "unknown key"),
    "bad TOML syntax": ("[geometry]", "[geometry", "<syntax>", "valid TOML"),
}


@pytest.mark.parametrize("case", BAD_FILES, ids=list(BAD_FILES))
def test_bad_model_file(tmp_path, case):
    """Every malformed file raises ModelFileError naming the file, the key and the expectation."""
    old, new, key, words = BAD_FILES[case]
    path = _write(tmp_path, old, new)
    with pytest.raises(ModelFileError) as info:
        load_machine(path)
    assert info.value.key == key
    assert str(path) in str(info.value) and f"'{key}'" in str(info.value) and words in str(info.value)


def test_missing_file(tmp_path):
    with pytest.raises(ModelFileError, match="does not exist"):
        load_machine(tmp_path / "nope.toml")


@pytest.mark.parametrize("value", ["true", '"0.442"'])
def test_wrong_scalar_type_is_rejected(tmp_path, value):
    with pytest.raises(ModelFileError, match="base_half_side_m"):
        load_machine(_write(tmp_path, "base_half_side_m = 0.442", f"base_half_side_m = {value}"))


_ROOT = DEFAULT_MODEL.parents[1]


@pytest.mark.parametrize(("args", "what"), [
    (["check", "models/pressfit_4upu.toml"], "models/pressfit_4upu.toml is a machine file, not a case file"),
    (["simulate", "models/tsai_3upu.toml"], "models/tsai_3upu.toml is a machine file, not a case file"),
    (["cycle", "models/gantry_cartesian.toml"], "models/gantry_cartesian.toml is a machine file, not a case file"),
    (["solve", "--model", "cases/paper/A.toml", "0", "0.65", "0", "--load", "0", "30", "0"],
     "cases/paper/A.toml is a case file, not a machine file"),
    (["compare", "cases/paper/board.toml"], "cases/paper/board.toml is a case file, not a machine file"),
])
def test_the_wrong_kind_of_file_gets_a_plain_refusal(monkeypatch, args, what):
    """issue 28 item 8: a machine file given as a case, or a case as a machine: one `error:` line saying what the
    file is and where it goes, exit 2; not the schema's first complaint ("key 'model': Input should be ...")."""
    monkeypatch.chdir(_ROOT)
    res = CliRunner().invoke(main, args)
    lines = [line for line in res.output.strip().splitlines() if line.startswith("error:")]
    assert res.exit_code == 2 and len(lines) == 1 and what in lines[0], res.output
    assert "key '" not in res.output and "Traceback" not in res.output


def _with_mass(tmp_path, source, name, table):
    """A copy of ``source`` (a TOML file) with [mass] keys replaced (tomllib + tomli_w)."""
    import tomllib

    import tomli_w

    data = tomllib.loads(Path(source).read_text())
    data.setdefault("mass", {}).update(table)
    path = tmp_path / name
    path.write_text(tomli_w.dumps(data))
    return path


@pytest.mark.parametrize(("key", "value"), [("cardan_spider_mass_kg", 1e-12), ("density_kg_per_m3", 1e-9),
                                            ("plate_mass_kg", 1e-12)])
@pytest.mark.parametrize("command", ["simulate", "control"])
def test_near_zero_masses_are_refused_by_the_dynamics_naming_the_key(tmp_path, command, key, value):
    """A near-zero [mass] value the schema accepts made the mass matrix singular (exit 70, LinAlgError, in
    simulate and control): refused before computing, one line naming the file and the key (exit 2)."""
    root = Path(__file__).resolve().parents[2]
    case = tmp_path / "case.toml"
    case.write_text((root / "cases" / "paper" / "insertion.toml").read_text()
                    + f"\n[model_overrides.mass]\n{key} = {value!r}\n")
    res = CliRunner().invoke(main, [command, str(case)])
    assert res.exit_code == 2, res.output
    assert len(res.output.strip().splitlines()) == 1 and f"mass.{key}" in res.output


@pytest.mark.slow
def test_a_massless_gantry_is_refused_by_compare_naming_the_key(tmp_path):

    root = Path(__file__).resolve().parents[2]
    gantry = _with_mass(tmp_path, root / "models" / "gantry_cartesian.toml", "massless.toml",
                        {"density_kg_per_m3": 1e-9, "tool_mass_kg": 0.0})
    res = CliRunner().invoke(main, ["compare", "--no-progress", str(root / "models" / "pressfit_4upu.toml"),
                                    str(gantry)])
    assert res.exit_code == 2, res.output
    assert len(res.output.strip().splitlines()) == 1 and "mass.density_kg_per_m3" in res.output

