"""The figures of pressfit.output.maps: what the kinematic maps show (issue 28: titles per machine, axes and data)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pressfit.description.machine import load_machine
from pressfit.kinematics.workspace import plane_map, square_corners
from pressfit.output.maps import kinematic_fields, plane_map_figure
from pressfit.output.plots import plt

TSAI = Path(__file__).resolve().parents[2] / "models" / "tsai_3upu.toml"


def test_a_3upu_plane_map_is_titled_for_its_machine_and_shows_its_fields():
    """The 3-UPU's maps at y = 0.62 m: the title names the machine and 3-UPU (never 4-UPU); one panel per field,
    its axes spanning the plane's x and z grid; each panel's filled contours cover the field's finite range (the
    first and last contour levels bracket the finite min and max of the plane map's dexterity, force indices and
    leg 1's rates, in the panels' order); the required square drawn on every panel is its corners, closed."""
    machine = load_machine(TSAI)
    pm = plane_map(machine, 0.62)
    fields = kinematic_fields(pm)
    square = square_corners(machine, 0.0)
    fig = plane_map_figure(machine, pm, fields, [np.vstack([square, square[:1]])] * 2)
    try:
        title = fig._suptitle.get_text()
        assert "tsai-3upu (3-UPU)" in title and "4-UPU" not in title and "y_h = 0.62 m" in title
        assert [ax.get_title() for ax in fig.axes[:len(fields)]] == list(fields)
        shown = [pm.dexterity, *np.moveaxis(pm.force_indices, -1, 0), *np.moveaxis(pm.leg_rates[..., 0, :], -1, 0)]
        assert len(shown) == len(fields)
        closed = np.vstack([square, square[:1]])
        for ax, v in zip(fig.axes, shown, strict=False):
            assert ax.get_xlim() == (pm.x_m.min(), pm.x_m.max()) and ax.get_ylim() == (pm.z_m.min(), pm.z_m.max())
            if np.nanmax(v) > np.nanmin(v):
                levels = ax.collections[0].levels
                assert levels[0] <= np.nanmin(v) and levels[-1] >= np.nanmax(v)
            assert np.count_nonzero(np.isfinite(v)) > v.size // 4  # the plane is largely reachable
            np.testing.assert_array_equal(ax.lines[0].get_xydata(), closed)
    finally:
        plt.close(fig)
