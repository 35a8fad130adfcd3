"""Verdicts of the monitor's evaluation objects, each at its boundary: a curve just inside and just outside
every element (hand-built polylines whose verdict is read off the geometry), and the compensation's compliance
against the Pinocchio VJM model (a second formulation; agreement 6e-11 relative, asserted to 1e-9)."""

import numpy as np
import pytest

from pressfit.description.cases import load_case
from pressfit.description.monitor_windows import Envelope, MaxForce, Threshold, Window, Windows
from pressfit.mechanics.compliance import vjm_plate_compliance
from pressfit.studies.curve_check import (
    check_curve,
    compensated_displacement,
    pin_pose_m,
    press_compliance_m_per_n,
)

EPS = 1e-9
BOX = dict(name="w", x_min_m=1.0, x_max_m=2.0, y_min_n=10.0, y_max_n=20.0)


def _one(element, x, y):
    (r,) = check_curve(np.asarray(x, float), np.asarray(y, float), Windows(schema_version=1, elements=[element]))
    return r


def _window(entry="left", exit="right"):
    return Window(**BOX, entry=entry, exit=exit)


@pytest.mark.parametrize(("level", "ok"), [(20.0 - EPS, True), (20.0, True), (20.0 + EPS, False),
                                           (10.0 + EPS, True), (10.0, True), (10.0 - EPS, False)])
def test_window_a_level_line_just_inside_and_outside(level, ok):
    r = _one(_window(), [0.0, 3.0], [level, level])
    assert r.passed is ok
    if not ok:
        assert ("above" if level > 15 else "below") in r.reason
        assert r.element == "w" and r.kind == "window"


@pytest.mark.parametrize(("y0", "ok"), [(10.0 + 1e-6, True), (10.0 - 1e-6, False)])
def test_window_entry_side_turns_at_the_corner(y0, ok):
    """(0, y0) -> (1, y0) -> (1.5, 15) -> (3, 15): at x = 1 the curve is on the left edge just above the corner
    (enters left) or just below it (then it crosses the bottom edge)."""
    r = _one(_window(), [0.0, 1.0, 1.5, 3.0], [y0, y0, 15.0, 15.0])
    assert r.passed is ok
    if not ok:
        assert "enters through the bottom side" in r.reason
        assert r.y_n == pytest.approx(10.0) and 1.0 < r.x_m < 1.5


@pytest.mark.parametrize(("y_exit", "ok"), [(20.0 - 1e-6, True), (20.0 + 1e-6, False)])
def test_window_exit_side_turns_at_the_corner(y_exit, ok):
    """(0, 15) -> (2, y_exit) -> (3, 30): leaves through the right edge just under the top corner, or through the
    top just before it."""
    r = _one(_window(), [0.0, 2.0, 3.0], [15.0, y_exit, 30.0])
    assert r.passed is ok
    if not ok:
        assert "leaves through the top side" in r.reason and r.y_n == pytest.approx(20.0)


def test_window_other_sides_start_inside_and_end_inside():
    assert _one(_window("bottom", "top"), [1.5, 1.5], [0.0, 30.0]).passed
    assert not _one(_window("bottom", "top"), [0.0, 3.0], [15.0, 15.0]).passed  # left -> right instead
    r = _one(_window(), [1.5, 3.0], [15.0, 15.0])
    assert not r.passed and "starts inside" in r.reason and (r.x_m, r.y_n) == (1.5, 15.0)
    r = _one(_window(), [0.0, 1.5], [15.0, 15.0])
    assert not r.passed and "ends inside" in r.reason
    assert _one(_window("left", "none"), [0.0, 1.5], [15.0, 15.0]).passed  # a block window at the end
    r = _one(_window("left", "none"), [0.0, 3.0], [15.0, 15.0])
    assert not r.passed and "must end inside" in r.reason and r.x_m == pytest.approx(2.0)
    r = _one(_window(), [0.0, 0.5], [15.0, 15.0])
    assert not r.passed and "before the window" in r.reason


def test_window_touch_of_the_top_edge_is_an_entry_and_exit_through_it():
    r = _one(_window(), [0.0, 1.5, 3.0], [30.0, 20.0, 30.0])
    assert not r.passed and "enters through the top side" in r.reason and r.y_n == pytest.approx(20.0)


@pytest.mark.parametrize(("peak", "ok"), [(100.0 + EPS, True), (100.0, True), (100.0 - EPS, False)])
def test_threshold_must_cross_at_its_level(peak, ok):
    t = Threshold(name="seat", force_n=100.0, x_min_m=1.0, x_max_m=2.0, mode="must_cross")
    r = _one(t, [0.0, 1.5, 3.0], [0.0, peak, 0.0])
    assert r.passed is ok
    if not ok:
        assert r.x_m == pytest.approx(1.5) and r.y_n == pytest.approx(peak)


@pytest.mark.parametrize(("peak", "ok"), [(100.0 - EPS, True), (100.0, True), (100.0 + EPS, False)])
def test_threshold_must_not_cross_at_its_level(peak, ok):
    t = Threshold(name="early", force_n=100.0, x_min_m=1.0, x_max_m=2.0, mode="must_not_cross")
    assert _one(t, [0.0, 1.5, 3.0], [0.0, peak, 0.0]).passed is ok


def test_threshold_range_and_crossing_point():
    t = Threshold(name="early", force_n=100.0, x_min_m=1.0, x_max_m=2.0, mode="must_not_cross")
    assert _one(t, [0.0, 2.5, 3.0], [0.0, 0.0, 500.0]).passed  # the force rises beyond the range only
    r = _one(t, [0.0, 1.0, 2.0], [0.0, 0.0, 200.0])  # crosses 100 N at x = 1.5 (linear segment)
    assert not r.passed and r.x_m == pytest.approx(1.5) and r.y_n == pytest.approx(100.0)
    r = _one(Threshold(name="seat", force_n=1.0, x_min_m=1.0, x_max_m=2.0, mode="must_cross"), [0, 0.5], [0, 5])
    assert not r.passed and "does not reach the range" in r.reason


@pytest.mark.parametrize(("dy", "ok"), [(-EPS, True), (0.0, True), (EPS, False)])
def test_envelope_upper_and_lower_bounds(dy, ok):
    e = Envelope(name="env", displacement_m=[0.0, 1.0, 2.0], lower_force_n=[0.0, 5.0, 0.0],
                 upper_force_n=[10.0, 15.0, 10.0])
    assert _one(e, [0.0, 1.0, 2.0], [10.0 + dy, 15.0 + dy, 10.0 + dy]).passed is ok
    r = _one(e, [0.0, 1.0, 2.0], [0.0 - dy, 5.0 - dy, 0.0 - dy])
    assert r.passed is ok
    if not ok:
        assert "below the lower" in r.reason and r.x_m == pytest.approx(0.0)


def test_envelope_violation_between_the_curves_samples_is_found_at_the_breakpoint():
    e = Envelope(name="env", displacement_m=[0.0, 1.0, 2.0], lower_force_n=[0.0, 0.0, 0.0],
                 upper_force_n=[10.0, 5.0, 10.0])
    r = _one(e, [0.0, 2.0], [8.0, 8.0])  # no sample at x = 1, where the bound dips to 5 N
    assert not r.passed and r.x_m == pytest.approx(1.0) and r.y_n == pytest.approx(8.0)
    assert _one(e, [-1.0, 3.0], [4.0, 4.0]).passed  # beyond the span: not judged


@pytest.mark.parametrize(("peak", "ok"), [(400.0 - EPS, True), (400.0, True), (400.0 + EPS, False)])
def test_max_force_at_its_limit(peak, ok):
    r = _one(MaxForce(name="max", force_n=400.0), [0.0, 1.0, 2.0], [0.0, peak, 0.0])
    assert r.passed is ok
    if not ok:
        assert (r.x_m, r.y_n) == (1.0, peak)


def test_compensation_and_the_press_compliance_against_the_vjm_model():
    x, f = np.array([0.0, 1e-3, 2e-3]), np.array([0.0, 100.0, 400.0])
    np.testing.assert_array_equal(compensated_displacement(x, f, 1e-7), [0.0, 1e-3 - 1e-5, 2e-3 - 4e-5])
    case = load_case("cases/paper/insertion.toml")
    np.testing.assert_array_equal(pin_pose_m(case), [0.10, 0.60, -0.05])  # the case file's pin on the board
    c = press_compliance_m_per_n(case)
    assert c == pytest.approx(vjm_plate_compliance(case.machine(), pin_pose_m(case))[1, 1], rel=1e-9)
    board = load_case("cases/paper/board.toml")
    pin = board.cycle.resolved_pins()[0]
    np.testing.assert_array_equal(pin_pose_m(board), [pin.x_m, board.cycle.board_height_m, pin.z_m])
