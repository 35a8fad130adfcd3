"""Report sections on a machine other than the paper's: the clearance-and-preload section on Tsai's 3-UPU (no
redundant actuation) runs the clearance alone and says why, instead of refusing the report."""

from __future__ import annotations

import numpy as np
import pytest

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


@pytest.mark.slow
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


def test_each_kind_states_the_grids_steps_and_samples_it_runs():
    """report.md's first paragraph (:func:`report.resolution_note`) states each kind's grids, sample counts and
    steps as the sections are handed them; the default is the full report's grids (the design ones) with only the
    insertion and the board cycle at 2 ms; --full runs them at the cases' own 1 ms step."""
    full, default = report.FULL, report.DEFAULT
    assert {k: v for k, v in vars(default).items() if getattr(full, k) != v} == {"name": "default",
                                                                               "time_step_s": 2e-3}
    assert (full.envelope_grid, full.stiffness_grid, full.interference_points, full.band_samples) == (41, 51, 41, 300)
    for res in (report.QUICK, default, full):
        text = report.resolution_note(res)
        heights, grid = res.compare_box or (3, 5)
        step = "the cases' own (1 ms)" if res.time_step_s is None else f"{res.time_step_s * 1e3:g} ms"
        for fragment in (f"y_h = {', '.join(f'{y:g}' for y in res.kinematic_heights_m)} m",
                         f"envelope {res.envelope_heights} heights x {res.envelope_grid} x {res.envelope_grid} poses",
                         f"stiffness maps {res.stiffness_grid} x {res.stiffness_grid} at "
                         f"{len(res.stiffness_heights_m)} heights",
                         f"{len(res.preloads_n)} preloads x {res.preload_load_steps} load steps at "
                         f"{res.preload_poses} poses",
                         f"interference {res.interference_heights} heights x {res.interference_points} x "
                         f"{res.interference_points}", f"board cycle time step {step}",
                         f"a {heights} x {grid} x {grid} box", f"joint band {res.band_samples} samples"):
            assert fragment in text, (res.name, fragment)


@pytest.mark.slow
def test_the_default_insertion_runs_at_the_step_its_section_states(tmp_path, machine):
    """The default report's insertion section: both runs at 2 ms (the series' time column), stated in its text."""
    parts: dict[str, object] = {}
    md = report._insertion_section(machine, tmp_path, False, report.DEFAULT, parts)
    assert "at a 2 ms step" in md[2]
    for run in parts["insertion"]:
        assert np.allclose(np.diff(run.series[:, run.columns.index("time_s")]), 2e-3, rtol=1e-9, atol=0)


def test_quick_and_full_together_are_refused_before_computing(tmp_path):
    """`pressfit report --quick --full`: one error line naming both, exit 2, no directory left."""
    from click.testing import CliRunner

    from pressfit.cli import main

    res = CliRunner().invoke(main, ["report", "--out", str(tmp_path / "rep"), "--quick", "--full"])
    assert res.exit_code == 2 and "--quick and --full exclude each other" in res.output, res.output
    assert not (tmp_path / "rep").exists()
