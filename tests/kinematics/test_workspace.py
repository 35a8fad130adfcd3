"""Unit tests of pressfit.workspace: square sampling, plane maps, outputs and the CLI command."""

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pressfit import kinematics
from pressfit.cli import main
from pressfit.errors import WorkspaceError
from pressfit.kinematics import workspace


def test_square_points(machine):
    """Corners and edge midpoints are samples; no sample leaves the square; rotation keeps the set."""
    pts = workspace.square_points(machine)
    a = machine.workspace.x_half_width_m
    for must in ([a, a], [-a, -a], [a, 0.0], [0.0, -a]):
        assert np.min(np.linalg.norm(pts - must, axis=1)) < 1e-15
    assert np.all(np.abs(pts) <= a + 1e-15)
    rot = workspace.square_points(machine, 30.0)
    np.testing.assert_allclose(np.linalg.norm(rot, axis=1), np.linalg.norm(pts, axis=1), atol=1e-15)
    np.testing.assert_allclose(workspace.square_corners(machine, 45.0)[0], [a * np.sqrt(2), 0.0], atol=1e-15)


def test_square_too_large_is_an_error(machine):
    big = machine.with_overrides({"workspace": {"x_half_width_m": 0.6, "z_half_width_m": 0.6}})
    with pytest.raises(WorkspaceError, match="no height") as err:
        workspace.square_height_range(big)
    assert err.value.heights_m == [] and err.value.angle_deg == 0.0  # the data, not only the message


def test_plane_map(machine):
    pm = workspace.plane_map(machine, 0.6, half_extent_m=0.4, step_m=0.05)
    assert pm.x_m.shape == (17,) and pm.reachable.shape == (17, 17) and pm.leg_rates.shape == (17, 17, 4, 3)
    assert 0 < pm.reachable.sum() < pm.reachable.size
    assert np.array_equal(np.isfinite(pm.dexterity), pm.reachable)
    i, j = 5, 11  # z = -0.15, x = 0.15
    ix = kinematics.indices(machine, [pm.x_m[j], 0.6, pm.z_m[i]])
    assert pm.dexterity[i, j] == ix.dexterity
    np.testing.assert_array_equal(pm.force_indices[i, j], ix.force_indices)
    header, rows = workspace.map_rows(pm)
    assert rows.shape == (17 * 17, len(header))
    assert rows[i * 17 + j, :3].tolist() == [pm.x_m[j], 0.6, pm.z_m[i]]


@pytest.mark.slow
def test_cli_workspace(tmp_path):
    runner = CliRunner()
    res = runner.invoke(main, ["workspace", "--y", "0.55", "--out", str(tmp_path), "--json", "--no-progress"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert [r["angle_deg"] for r in out["height_range"]] == [0.0, 45.0, 90.0]
    assert (tmp_path / "maps_y0.550.png").exists()
    again = runner.invoke(main, ["workspace", "--y", "0.55", "--out", str(tmp_path), "--no-progress"])
    assert again.exit_code == 2 and "exists" in again.output
