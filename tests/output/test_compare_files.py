"""compare.png's figure (pressfit.output.compare.compare_figure): what the bars show (issue 28: not its size)."""

from __future__ import annotations

import types

import numpy as np

from pressfit.output.compare import PANELS, compare_figure
from pressfit.output.plots import plt


def test_each_panel_shows_each_machines_figure_in_the_panels_unit():
    """Three machines (two of one name, kept apart): per panel one bar per machine whose height is the figure
    times the panel's unit (N/um, mrad, um: the factors written here), titled as the panel; the lost-motion panel
    adds the preloaded bars (None: no bar)."""
    units = {"weakest_stiffness_worst_n_per_m": 1e-6, "vertical_stiffness_worst_n_per_m": 1e-6,
             "tilt_worst_rad": 1e3, "lost_motion_m": 1e6}
    keys = [k for k, _, _ in PANELS]
    machines = [types.SimpleNamespace(name=n, lost_motion_preloaded_m=pre,
                                      **{k: (i + 1) * (j + 2) * 1.5 for j, k in enumerate(keys)})
                for i, (n, pre) in enumerate((("upu", 2e-6), ("upu", None), ("gantry", 0.0)))]
    fig = compare_figure(types.SimpleNamespace(machines=machines))
    try:
        for ax, (key, label, _) in zip(fig.axes, PANELS, strict=True):
            assert ax.get_title() == label
            heights = [p.get_height() for p in ax.patches]
            expected = [getattr(m, key) * units.get(key, 1.0) for m in machines]
            np.testing.assert_allclose(heights[:3], expected, rtol=1e-15)
            assert [t.get_text() for t in ax.get_xticklabels()] == ["upu (1)", "upu (2)", "gantry"]
            if key == "lost_motion_m":
                np.testing.assert_allclose(heights[3:], [2.0, np.nan, 0.0], rtol=1e-15)
            assert ax.get_ylim()[1] >= max(expected)
    finally:
        plt.close(fig)
