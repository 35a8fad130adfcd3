"""The generic figures of pressfit.output.plots: what the leg bars show (issue 28: not a PNG's size)."""

from __future__ import annotations

import numpy as np

from pressfit.output.plots import leg_bars_figure, plt


def test_leg_bars_show_each_legs_value_and_label_it():
    """Two fields over four legs: per panel a bar per leg at x = 1..4 whose height is the leg's value, the value
    printed on it (4 digits), the panel titled and its y axis labelled by the field; the third cell hidden."""
    fields = {"N [N]": (np.array([-195.7, 130.3, 130.3, -478.2]), "N"),
              "T [N m]": (np.array([0.5, -1.25, 2.0, 0.0]), "N m")}
    fig = leg_bars_figure(fields, "leg loads")
    try:
        panels = [ax for ax in fig.axes if ax.get_visible()]
        assert len(panels) == 2 and fig._suptitle.get_text() == "leg loads"
        for ax, (name, (values, unit)) in zip(panels, fields.items(), strict=True):
            assert (ax.get_title(), ax.get_ylabel()) == (name, unit)
            np.testing.assert_array_equal([p.get_height() for p in ax.patches], values)
            np.testing.assert_array_equal([p.get_x() + p.get_width() / 2 for p in ax.patches], [1, 2, 3, 4])
            assert [t.get_text() for t in ax.texts] == [f"{v:.4g}" for v in values]
    finally:
        plt.close(fig)
