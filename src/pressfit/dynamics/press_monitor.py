r"""The press monitor's view of a simulated insertion (``pressfit simulate``, each pin of ``pressfit cycle``): the
force-displacement curve a process monitor records, with the columns of ``pressfit curve``'s ``curve.csv``
(:func:`pressfit.output.curve.curve_columns`) after a time column.

The window is the pin's press stroke as its monitor records it: of its ``MONITOR_PHASES`` rows (descent, dwell,
retract) from the last row before the first contact (:func:`tare_row`, where a monitor zeroes its displacement
and starts the curve; the whole stroke if it never touches) to the end of the retract, ``time_s`` from that row.
Per row:

* ``depth_m``: the tool's true depth below the board face (the series' ``depth_m``: h_b - tool_y);
* ``sensed_depth_m``: the depth the press measures from its drives' encoders: the forward kinematics of the leg
  lengths the drives measure (the series' ``kinematic_y_m``), h_b - kinematic_y, tared to the true depth on the
  curve's first row (the weight's sag, a constant offset at one pose, is then out, as in the predicted curve).
  Everything between the encoders and the tool deflects (the legs, the cardans, the drives' axial stiffness: the
  condensed compliance the rigid model carries in series, the elastic legs of the flexible model), so sensed -
  true is the machine's deflection along the press at that pose (C_yy F on the rigid model, C the compliance at
  the pin pose, :func:`pressfit.mechanics.condensed.condensed_plate_compliance`);
* ``force_n``: the simulated total contact force (N);
* ``pin_force_n<i>``, ``pin_depth_m<i>``: the simulation carries a pin field through its quasi-static total-force
  table (:func:`pressfit.mechanics.press_curve.force_table`), so each pin's share is taken from the same
  quasi-static pin-field solve (:func:`pressfit.mechanics.press_curve.solve_field`, the pin pose's compliance) at
  the simulated true depth: pin i's force is the simulated total times f_i / sum f (an equal share where the
  quasi-static total is 0: a damping force or the table's interpolation error out of the pins' contact), so the
  pins' forces sum to the total; the pins' depths are the solve's. A time-stepped per-pin model is not built.

The summary (:func:`pressfit.mechanics.press_curve.stroke_figures`, the predicted curve's figures on the simulated
rows, the end of the stroke the end of the dwell): ``peak_force_n`` (the insertion's peak, before the first
shoulder touches the board), ``plateau_force_n`` (the laws' plateaus summed: solid and compliant pins; None for
the others), ``seated``, ``seating_depth_m``, ``sensed_minus_true_depth_at_peak_m``,
``machine_compliance_along_press_m_per_n`` (C_yy at the pin pose), the component's figures
(:func:`pressfit.mechanics.press_curve.component_figures`, as ``pressfit curve``'s: ``tool_tilt_max_rad``,
``max_pin_depth_spread_m``, ``all_pins_seated`` and per pin ``component_pins``: its peak force, its depth at the
end of the dwell and whether it is seated; the tilt and the pins' depths those of the quasi-static solve at the
simulated true depth), ``pin_count``, ``curve_start_time_s`` (the run's
time of the first row) and ``series_residual_n`` (the pin-field solve's worst residual, refused over
``RESIDUAL_LIMIT_N``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pressfit.description.cases import Contact
from pressfit.description.machine import Machine
from pressfit.errors import ResidualError
from pressfit.mechanics.condensed import condensed_plate_compliance
from pressfit.mechanics.press_curve import (
    RESIDUAL_LIMIT_N,
    PinField,
    component_figures,
    pin_pose_m,
    solve_field,
    stroke_figures,
)

MONITOR_PHASES = ("descent", "dwell", "retract")  # a pin's press stroke: the rows its monitor records
SUMMARY_KEYS = ("peak_force_n", "plateau_force_n", "seated", "seating_depth_m", "sensed_minus_true_depth_at_peak_m",
                "machine_compliance_along_press_m_per_n", "tool_tilt_max_rad", "max_pin_depth_spread_m",
                "all_pins_seated", "component_pins")


@dataclass(frozen=True, kw_only=True)
class MonitorCurve:
    """One pin's press stroke as its monitor records it (module docstring): ``time_s`` (since the curve's first
    row), ``depth_m`` (true), ``sensed_depth_m`` (encoders, tared), ``force_n``, ``pin_forces_n`` and
    ``pin_depths_m`` (rows, pins); ``summary`` (JSON-ready)."""

    time_s: np.ndarray
    depth_m: np.ndarray
    sensed_depth_m: np.ndarray
    force_n: np.ndarray
    pin_forces_n: np.ndarray
    pin_depths_m: np.ndarray
    summary: dict[str, Any]


def tare_row(force_n: np.ndarray) -> int:
    """The monitor's start: the last row before the first contact (0 if the stroke starts in contact or never
    touches)."""
    touching = np.flatnonzero(np.asarray(force_n) > 0.0)
    return max(int(touching[0]) - 1, 0) if touching.size else 0


def tared_sensed_depth(board_m: float, kinematic_y_m: np.ndarray, depth_m: np.ndarray,
                       force_n: np.ndarray) -> np.ndarray:
    """h_b - kinematic_y (m), minus its offset from the true depth at :func:`tare_row`."""
    sensed = board_m - np.asarray(kinematic_y_m, dtype=float)
    tare = tare_row(force_n)
    return sensed - (sensed[tare] - depth_m[tare])


def monitor_curve(machine: Machine, contact: Contact, time_s: np.ndarray, depth_m: np.ndarray,
                  kinematic_y_m: np.ndarray, force_n: np.ndarray, end_row: int, where: str = "") -> MonitorCurve:
    """The monitor's view (module docstring) of a stroke's rows (time s, true depth m, the kinematic pose's y m,
    the total contact force N; ``end_row`` the last dwell row, in the stroke's rows) of ``contact``'s pin field at
    its pin pose (``contact.pin_position_m``), from :func:`tare_row` on. ResidualError (naming ``where``) if the
    pin-field solve's residual exceeds ``RESIDUAL_LIMIT_N``."""
    pins = PinField.from_contact(contact)
    compliance = condensed_plate_compliance(machine.sensed_view, pin_pose_m(contact))
    start = tare_row(force_n)
    time, depth, force = (np.asarray(a, dtype=float)[start:] for a in (time_s, depth_m, force_n))
    sensed = tared_sensed_depth(contact.board_height_m, np.asarray(kinematic_y_m, dtype=float)[start:], depth, force)
    sol = solve_field(pins, compliance, depth)
    if not sol.residual_n <= RESIDUAL_LIMIT_N:
        raise ResidualError("the monitor curve's pin-field solve", "max |F - f(d)| (N)", sol.residual_n,
                            RESIDUAL_LIMIT_N, where=where)
    n = len(pins.laws)
    total = sol.pin_forces_n.sum(axis=1, keepdims=True)
    share = np.divide(sol.pin_forces_n, total, out=np.full_like(sol.pin_forces_n, 1.0 / n), where=total > 0.0)
    pin_forces = force[:, None] * share
    end = max(end_row - start, 0)
    fig = stroke_figures(pins, depth, force, pin_forces, sol.pin_depths_m, sensed, end)
    summary = {**component_figures(pins, sol, fig, end),
               "peak_force_n": fig.peak_force_n, "plateau_force_n": fig.plateau_force_n, "seated": fig.seated,
               "seating_depth_m": fig.seating_depth_m,
               "sensed_minus_true_depth_at_peak_m": fig.sensed_minus_true_depth_at_peak_m,
               "machine_compliance_along_press_m_per_n": float(compliance[1, 1]), "pin_count": n,
               "curve_start_time_s": float(time[0]), "series_residual_n": sol.residual_n}
    return MonitorCurve(time_s=time - time[0], depth_m=depth, sensed_depth_m=sensed, force_n=force,
                        pin_forces_n=pin_forces, pin_depths_m=sol.pin_depths_m, summary=summary)


def stroke_rows(phases: np.ndarray, phase_names: tuple[str, ...]) -> tuple[np.ndarray, int]:
    """An insertion's rows of the ``MONITOR_PHASES`` and the index in them of the last dwell row (the end of the
    stroke)."""
    codes = [phase_names.index(p) for p in MONITOR_PHASES]
    rows = np.flatnonzero(np.isin(phases, codes))
    dwell = np.flatnonzero(phases[rows] == codes[1])
    return rows, int(dwell[-1]) if dwell.size else rows.size - 1
