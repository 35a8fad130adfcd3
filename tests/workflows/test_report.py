"""Report sections on a machine other than the paper's: the clearance-and-preload section on Tsai's 3-UPU (no
redundant actuation) runs the clearance alone and says why, instead of refusing the report."""

from __future__ import annotations

import numpy as np

from pressfit.workflows import report


def test_the_preload_section_on_a_3_leg_machine_shows_the_clearance_alone(tmp_path, tsai):
    """3 legs: preload 0 only, stated; the lost motion with play is positive (the play is not taken up) and the
    critical preload does not exist (NaN)."""
    parts: dict[str, object] = {}
    md = report._preload_section(tsai, tmp_path, False, report.QUICK, parts)
    assert any("no redundant actuation, so no internal preload" in line for line in md)
    (name, study), = parts["studies"]
    assert study.preloads.tolist() == [0.0]
    assert np.all(study.lost_motion_m[1:, 0] > 0) and np.all(np.isnan(study.critical_preload))


def test_a_report_on_a_baseline_compares_it_once_and_bars_keep_machines_apart(tmp_path, tsai):
    """The report's comparison on Tsai's 3-UPU lists it once (the shipped baselines minus itself); two machines of
    one name get one bar each in compare.png (labelled by position), not one merged bar."""
    import dataclasses

    from pressfit.output.compare import compare_figure
    from pressfit.output.plots import plt
    from pressfit.studies.compare import Comparison

    parts: dict[str, object] = {}
    report._compare_section(tsai, tmp_path, False, report.QUICK, parts)
    names = [m.name for m in parts["comparison"].machines]
    assert names == ["tsai-3upu", "gantry-cartesian", "pressfit-4upu-rotated45"]
    first = parts["comparison"].machines[0]
    twins = Comparison(machines=[first, dataclasses.replace(first, worst_drive_force_n=1.0)], claims=[])
    fig = compare_figure(twins)
    try:
        ax = fig.axes[0]
        assert len(ax.patches) == 2 and [t.get_text() for t in ax.get_xticklabels()] == ["tsai-3upu (1)",
                                                                                          "tsai-3upu (2)"]
    finally:
        plt.close(fig)
