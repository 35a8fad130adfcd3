"""Layers above mechanics still assume the paper's four legs: each refuses another leg count up front with a
LegCountError naming the layer (issue 21 item 7), instead of arrays of the wrong shape. The machine is Tsai's
3-UPU (models/tsai_3upu.toml); the case files are the shipped ones pointed at it. Modes, interference, the 3D
scene, the load envelope, the preload and Monte Carlo studies, the simulation, pressfit check and the design
study take n legs (tests/*/test_n_leg_*.py)."""

from pathlib import Path

import pytest

from pressfit.description.cases import load_case
from pressfit.errors import LegCountError
from pressfit.studies import paper_tables

ROOT = Path(__file__).resolve().parents[1]
TSAI = ROOT / "models" / "tsai_3upu.toml"

CASE_CALLS = {
    "the paper's tables": ("paper/A.toml", paper_tables.solve_case),
}


@pytest.mark.parametrize("layer", CASE_CALLS)
def test_case_layers_refuse_three_legs(tmp_path, layer):
    name, call = CASE_CALLS[layer]
    text = (ROOT / "cases" / name).read_text()
    path = tmp_path / "case.toml"
    path.write_text(f'model = "{TSAI}"\n' + text)
    with pytest.raises(LegCountError) as info:
        call(load_case(path))
    assert info.value.legs == 3 and layer in info.value.layer
