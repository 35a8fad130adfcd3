"""The joint and its press curve, for the report (issue 30 item 7): a case's predicted curve (true and sensed depth),
its tolerance band from a small serial Monte Carlo and the monitor's windows derived from it, and a board's per-pin
predicted curves (each pin's pose sees another machine compliance, so each sensed curve is skewed differently).

All quasi-static (:func:`pressfit.mechanics.press_curve.predict_curve`: the joint's law in series with the machine's
6x6 compliance at the pose), each curve's series residual enforced. A board pin is its ``[cycle.contact]`` law on the
tool axis at the pose (x, board face, z), pressed from the face until the force first reaches the pin's force limit
(where the force-limited press stops: ``predict_curve``'s ``stop_force_n``, the tilt included) or to its commanded
``interference_m``, whichever comes first. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pressfit.description.cases import Case, Contact
from pressfit.description.machine import Machine
from pressfit.description.monitor_windows import Windows
from pressfit.errors import PressCurveError, ResidualError
from pressfit.mechanics.press_curve import RESIDUAL_LIMIT_N, PressCurve, predict_curve
from pressfit.studies.curve_band import CurveBandStudy, curve_band_study, windows_from_band
from pressfit.studies.curve_study import CurveSample

REPORT_BAND_SAMPLES = 300  # the report's Monte Carlo: a few hundred serial samples (a preview, not a design band)
BOARD_CURVE_POINTS = 201  # depth samples of a board pin's curve


@dataclass(frozen=True, kw_only=True)
class BoardPinCurve:
    """One board pin's predicted curve: its cycle ``index`` (from 1), place ``x_m``, ``z_m`` (m), ``force_limit_n``
    (N) and the ``curve`` at its pose."""

    index: int
    x_m: float
    z_m: float
    force_limit_n: float
    curve: PressCurve

    def summary(self) -> dict[str, Any]:
        c = self.curve
        return {"index": self.index, "x_m": self.x_m, "z_m": self.z_m, "force_limit_n": self.force_limit_n,
                "machine_compliance_along_press_m_per_n": c.machine_compliance_along_press_m_per_n,
                "peak_force_n": c.peak_force_n, "max_depth_m": float(c.depth_m[-1]),
                "sensed_minus_true_depth_at_peak_m": c.sensed_minus_true_depth_at_peak_m}


@dataclass(frozen=True, kw_only=True)
class JointCurves:
    """The report's joint section: the pin case (``case_name``) nominal ``curve``, its band ``study`` and derived
    ``windows``, and the board case's (``board_name``) per-pin curves ``board``."""

    case_name: str
    curve: PressCurve
    study: CurveBandStudy
    windows: Windows
    board_name: str
    board: list[BoardPinCurve]


def _checked(curve: PressCurve, where: str) -> PressCurve:
    if not curve.series_residual_n <= RESIDUAL_LIMIT_N:
        raise ResidualError("the press curve's series equation", "max |F - f(d)| (N)", curve.series_residual_n,
                            RESIDUAL_LIMIT_N, where=where)
    return curve


def board_pin_curves(case: Case, machine: Machine | None = None,
                     points: int = BOARD_CURVE_POINTS) -> list[BoardPinCurve]:
    """Each pin of the case's ``[cycle]`` (module docstring), on ``machine`` (default the case's), ``points`` depths
    from the board face to where the press stops (module docstring)."""
    if case.cycle is None:
        raise PressCurveError(case.path, "[cycle]", "the case has no [cycle] table (a board of pins)")
    machine = case.machine() if machine is None else machine
    law = case.cycle.contact.model_dump(exclude_unset=True)
    out = []
    for pin in case.cycle.resolved_pins():
        contact = Contact.model_validate({**law, "board_height_m": case.cycle.board_height_m,
                                          "pin_position_m": [pin.x_m, pin.z_m]})
        curve = predict_curve(machine, contact, samples=points, max_depth_m=pin.interference_m,
                              stop_force_n=pin.force_limit_n)
        out.append(BoardPinCurve(index=pin.index, x_m=pin.x_m, z_m=pin.z_m, force_limit_n=pin.force_limit_n,
                                 curve=_checked(curve, f"{case.path} pin {pin.index}")))
    return out


def joint_curves(pin_case: Case, board_case: Case, samples: int = REPORT_BAND_SAMPLES) -> JointCurves:
    """The pin case's nominal curve (its ``[curve] points`` depths), its band over ``[curve.tolerances]`` from
    ``samples`` serial samples (seed: its ``[curve] seed``) with the windows derived from it
    (:func:`pressfit.studies.curve_band.windows_from_band`, the rules of ``pressfit study curve``), and the board
    case's per-pin curves (:func:`board_pin_curves`)."""
    if pin_case.curve is None:
        raise PressCurveError(pin_case.path, "[curve]", "the case has no [curve.tolerances] table")
    machine = pin_case.machine()
    sample = CurveSample.from_case(pin_case, machine)
    curve = _checked(predict_curve(machine, pin_case, samples=sample.points), pin_case.path)
    study = curve_band_study(sample, pin_case.curve.tolerances, samples, seed=pin_case.curve.seed, serial=True)
    windows = windows_from_band(study.band, name=f"{pin_case.name}: predicted band ({samples} samples)",
                                source={"case": pin_case.path, "samples": samples, "seed": study.seed,
                                        "points_per_curve": sample.points,
                                        "displacement": "sensed_depth_m: the drives' encoders, the press's "
                                                        "deflection at the pin pose included"})
    return JointCurves(case_name=pin_case.name, curve=curve, study=study, windows=windows, board_name=board_case.name,
                       board=board_pin_curves(board_case))
