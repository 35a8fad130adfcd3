"""A case's preload on machines of any redundancy (issue 21): n - 3 amplitudes (``amplitudes_n`` / ``_m``), the
4-UPU's scalar a4 unchanged, and the case solved end to end on a 5-leg machine file, where the unloaded
actuator forces are V a (the force mode's definition, :mod:`pressfit.mechanics.preload`)."""

import math
from pathlib import Path

import numpy as np
import pytest

from pressfit import kinematics
from pressfit.description.cases import Preload, load_case
from pressfit.mechanics import statics

TSAI = Path(__file__).resolve().parents[2] / "models" / "tsai_3upu.toml"


def test_amplitudes():
    assert Preload(amplitudes_n=[300.0, -150.0]).amplitudes == (300.0, -150.0)
    assert Preload(amplitudes_n=[300.0, -150.0]).a4 == 0.0  # the 4-leg layers' scalar: none here
    one = Preload.model_validate({"amplitudes_n": [250.0]})
    assert (one.a4_n, one.amplitudes_n, one.amplitudes) == (250.0, None, (250.0,))  # one amplitude is a4
    assert Preload(a4_n=120.0).amplitudes == (120.0,)
    assert Preload(mode="length", amplitudes_m=[1e-5, 2e-5]).amplitudes == (1e-5, 2e-5)
    for bad in ({"a4_n": 1.0, "amplitudes_n": [1.0, 2.0]}, {"amplitudes_m": [1e-5, 1e-5]},
                {"mode": "length", "amplitudes_n": [1.0, 2.0]}):
        with pytest.raises(ValueError):
            Preload.model_validate(bad)


def test_five_leg_case_solved(tmp_path):
    """A machine file with five legs at 72 degrees (the 3-UPU file's legs replaced) and a case on it with two
    preload amplitudes and no load: solve_case returns actuator forces V a."""
    text = TSAI.read_text()
    head, tail = text.split("[[legs]]", 1)[0], "[limits]" + text.split("[limits]", 1)[1]
    legs = "".join(f"[[legs]]\nradial_direction = [{math.cos(t)!r}, 0.0, {math.sin(t)!r}]\n\n"
                   for t in (math.radians(-90.0 + 72.0 * i) for i in range(5)))
    (tmp_path / "five.toml").write_text(head + legs + tail)
    case_text = ('name = "five"\nmodel = "five.toml"\n[poses]\npoints_m = [[0.05, 0.62, -0.05]]\n'
                 "[loads]\nforce_n = [0.0, 0.0, 0.0]\n[preload]\namplitudes_n = [300.0, -150.0]\n")
    (tmp_path / "case.toml").write_text(case_text)
    case = load_case(tmp_path / "case.toml")
    (eq,) = statics.solve_case(case)
    v = kinematics.preload_basis(case.machine(), [0.05, 0.62, -0.05])
    np.testing.assert_allclose(eq.actuator_forces_n, v @ [300.0, -150.0], rtol=1e-6)


@pytest.mark.parametrize(("model", "preload", "fragments"), [
    (TSAI, "a4_n = 100.0", ("key '[preload] a4_n'", "3-leg machine tsai-3upu", "tsai_3upu.toml",
                            "no redundant actuation", "got 1: 100")),
    (TSAI.parent / "pressfit_4upu.toml", "amplitudes_n = [100.0, 50.0]",
     ("key '[preload] amplitudes_n'", "give 1 preload amplitude (n - 3)", "4-leg machine", "got 2: 100, 50")),
])
def test_a_preload_against_the_leg_count_names_the_case_file_and_the_key(tmp_path, model, preload, fragments):
    """issue 28 item 8: a case whose [preload] does not fit its machine's leg count: one `error:` line (exit 2)
    naming the case file, the [preload] key, the machine's file and its leg count."""
    from click.testing import CliRunner

    from pressfit.cli import main

    path = tmp_path / "wrong_preload.toml"
    path.write_text(f'name = "x"\nmodel = "{model}"\n[poses]\npoints_m = [[0.0, 0.62, 0.0]]\n[loads]\n'
                    f'force_n = [0.0, 30.0, 0.0]\n[preload]\n{preload}\n')
    res = CliRunner().invoke(main, ["solve", str(path)])
    assert res.exit_code == 2 and len(res.output.strip().splitlines()) == 1, res.output
    line = res.output.strip()
    assert line.startswith(f"error: {path}: ") and all(f in line for f in fragments), line
