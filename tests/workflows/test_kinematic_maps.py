"""The kinematic maps' workflow (pressfit.workflows.kinematic_maps): outputs checked before computing, the files
written and the summary returned as written."""

import json

import pytest

from pressfit.errors import OutputExistsError
from pressfit.workflows import kinematic_maps as maps


@pytest.mark.slow
def test_write_outputs_and_no_silent_overwrite(machine, tmp_path):
    (tmp_path / "summary.json").write_text("keep")
    with pytest.raises(OutputExistsError):  # checked before anything is computed or written
        maps.write_kinematic_maps(machine, tmp_path, [0.6])
    assert (tmp_path / "summary.json").read_text() == "keep" and not (tmp_path / "maps_y0.600.csv").exists()
    summary, paths, _ = maps.write_kinematic_maps(machine, tmp_path, [0.6], overwrite=True)
    assert sorted(p.name for p in paths) == ["maps_y0.600.csv", "maps_y0.600.png", "summary.json"]
    assert json.loads((tmp_path / "summary.json").read_text()) == json.loads(json.dumps(summary))
