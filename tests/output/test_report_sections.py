"""Report sections on a machine other than the paper's: the clearance-and-preload section on Tsai's 3-UPU (no
redundant actuation) runs the clearance alone and says why, instead of refusing the report."""

from __future__ import annotations

import numpy as np

from pressfit.output import report


def test_the_preload_section_on_a_3_leg_machine_shows_the_clearance_alone(tmp_path, tsai):
    """3 legs: preload 0 only, stated; the lost motion with play is positive (the play is not taken up) and the
    critical preload does not exist (NaN)."""
    parts: dict[str, object] = {}
    md = report._preload_section(tsai, tmp_path, False, True, parts)
    assert any("no redundant actuation, so no internal preload" in line for line in md)
    (name, study), = parts["studies"]
    assert study.preloads.tolist() == [0.0]
    assert np.all(study.lost_motion_m[1:, 0] > 0) and np.all(np.isnan(study.critical_preload))
