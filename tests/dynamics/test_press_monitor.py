"""The press monitor's view of a board (dynamics/press_monitor.py, ``pressfit cycle``'s curves/pin_<nn>.csv): one
curve per pin, each with its own pose's compliance, and the tare of the sensed depth. The slow single insertion
against ``pressfit curve`` is in tests/mechanics/test_press_curve.py."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from pressfit.description.cases import load_case
from pressfit.description.measured_curves import read_curve
from pressfit.dynamics.cycle import simulate_cycle
from pressfit.dynamics.press_monitor import tare_row, tared_sensed_depth
from pressfit.mechanics.compliance import vjm_plate_compliance
from pressfit.output.curve import monitor_curve_columns
from pressfit.output.cycle import write_cycle
from tests.dynamics.test_cycle import BOARD
from tests.dynamics.test_simulation_trust import write_updated

PINS = [{"x_m": 0.10, "z_m": -0.05}, {"x_m": -0.20, "z_m": 0.15}]  # insertion.toml's pin and a corner of the board


@pytest.fixture(scope="module")
def board_run(tmp_path_factory):
    """The shipped board's [cycle] (elastic pins, 30 N limit, rigid model) on two pins at different poses, 0.5 s
    dwell, without the drive sizing: about 10 s."""
    data = tomllib.loads(BOARD.read_text())
    del data["cycle"]["grid"]
    path = write_updated(tmp_path_factory.mktemp("board") / "b.toml", data, "cycle",
                         {"pins": PINS, "dwell_s": 0.5, "settle_s": 0.1})
    case = load_case(path)
    return case, simulate_cycle(case, sizing=False)


@pytest.mark.slow
def test_each_pin_has_its_curve_with_its_own_poses_compliance(board_run, tmp_path):
    """Per pin, curves/pin_<nn>.csv with the monitor's columns, its rows the pin's stroke from the row before its
    first contact (readable by `pressfit curves check` with --displacement-column sensed_depth_m: the sensed depth
    never runs backwards before its maximum); the
    summary's machine_compliance_along_press_m_per_n the Pinocchio VJM compliance C_yy at the pin's pose to 1e-6
    (a second formulation of the condensed one), and sensed minus true depth at the peak that C_yy times the pin's
    peak force within 5% (achieved 1.5% and 1.0%: the board's 10 mm/s descent is not quasi-static, the rigid
    model's dynamics); the corner pin's deflection 5x the centre's (11.5 um against 2.2 um at 30 N)."""
    case, result = board_run
    paths = write_cycle(result, tmp_path)
    smt = []
    for k, (pin, record, curve) in enumerate(zip(PINS, result.summary["pins"], result.curves, strict=True)):
        csv = tmp_path / "curves" / f"pin_{k + 1:02d}.csv"
        assert csv in paths
        assert csv.read_text().splitlines()[0].split(",") == monitor_curve_columns(1)
        table = np.loadtxt(csv, delimiter=",", skiprows=1)
        assert table.shape == (curve.time_s.size, 6)
        assert np.array_equal(table[:, 3], table[:, 4])  # one pin: its force is the total
        assert table[0, 3] == 0.0 and table[1, 3] > 0.0 and table[0, 0] == 0.0
        measured = read_curve(csv, columns={"displacement": "sensed_depth_m"})
        assert measured.force_n.max() == pytest.approx(record["peak_contact_force_n"])
        c_yy = vjm_plate_compliance(case.machine(), np.array([pin["x_m"], 0.6, pin["z_m"]]))[1, 1]
        assert record["machine_compliance_along_press_m_per_n"] == pytest.approx(c_yy, rel=1e-6)
        assert record["peak_force_n"] == pytest.approx(record["peak_contact_force_n"])  # no shoulder: the peak
        assert record["sensed_minus_true_depth_at_peak_m"] == pytest.approx(c_yy * record["peak_force_n"], rel=5e-2)
        assert record["plateau_force_n"] is None and record["seated"] is False and record["seating_depth_m"] is None
        smt.append(record["sensed_minus_true_depth_at_peak_m"])
    assert smt[1] > 4.0 * smt[0]


def test_the_curve_starts_at_the_last_row_before_contact_where_the_sensed_depth_is_tared():
    """The monitor's start is the row before the first contact (0 if it never touches); there h_b - kinematic_y is
    shifted onto the true depth (the weight's sag out, as a monitor zeroes at its start), the deflection kept."""
    depth = np.array([-2e-3, -1e-3, 0.5e-3, 1e-3])
    kinematic_y = 0.6 - depth - np.array([7e-6, 7e-6, 9e-6, 1.1e-5])  # sag 7 um, then 2 and 4 um of deflection
    force = np.array([0.0, 0.0, 10.0, 20.0])
    assert tare_row(force) == 1 and tare_row(np.zeros(4)) == 0 and tare_row(np.ones(4)) == 0
    sensed = tared_sensed_depth(0.6, kinematic_y, depth, force)
    assert np.allclose(sensed - depth, [0.0, 0.0, 2e-6, 4e-6], atol=1e-15)
