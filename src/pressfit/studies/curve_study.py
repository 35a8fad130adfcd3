"""``pressfit study curve``'s sample: one predicted press curve (:func:`pressfit.mechanics.press_curve.predict_curve`)
of a case's ``[simulation.contact]`` with a draw of its ``[curve.tolerances]`` applied, as the (displacement m,
force N) pair :func:`pressfit.studies.curve_band.curve_band_study` bands.

The displacement is the SENSED depth (``PressCurve.sensed_depth_m``: what the drives' encoders read, the press's
own deflection at the pin pose included), the one a press monitor records and judges its windows against; the
force is the pins' total. Each tolerance is a deviation added to the case's value: a law key moves the contact's
value and every pin's own override of it by the same draw (one component's lot), ``pin_x_m`` / ``pin_z_m`` move
``pin_position_m`` (the pose, hence the machine's compliance there).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from pressfit.description.cases import CURVE_POSE_KEYS, Case, Contact
from pressfit.description.machine import Machine
from pressfit.errors import PressCurveError, ResidualError
from pressfit.mechanics.press_curve import RESIDUAL_LIMIT_N, PinField, predict_curve

DEFAULT_POINTS = 401  # depth samples per curve: ~3 ms of CPU a curve for the shipped 4-pin component


def perturbed_contact(contact: Contact, values: Mapping[str, float]) -> Contact:
    """``contact`` with each deviation of ``values`` (key -> deviation, SI) added (module docstring); a law value
    that leaves its range (a diameter or stiffness <= 0, a friction < 0) is refused naming the key."""
    update: dict[str, object] = {}
    pins = list(contact.pins)
    dx, dz = float(values.get("pin_x_m", 0.0)), float(values.get("pin_z_m", 0.0))
    if dx or dz:
        update["pin_position_m"] = [contact.pin_position_m[0] + dx, contact.pin_position_m[1] + dz]
    for key, dv in values.items():
        if key in CURVE_POSE_KEYS or not dv:
            continue
        base = getattr(contact, key)
        if base is not None:
            update[key] = _moved(key, base, dv)
        pins = [p.model_copy(update={key: _moved(key, getattr(p, key), dv)}) if getattr(p, key, None) is not None
                else p for p in pins]
    if pins != list(contact.pins):
        update["pins"] = pins
    return contact.model_copy(update=update) if update else contact


def _moved(key: str, base: float, deviation: float) -> float:
    value = float(base) + float(deviation)
    if value < 0.0 or (value == 0.0 and key != "friction_coefficient"):
        raise PressCurveError("", f"curve.tolerances.{key}", f"a draw {deviation:g} moves the value {base:g} to "
                              f"{value:g}, out of its range: bound the tolerance (truncnormal or uniform)")
    return value


@dataclass(frozen=True, kw_only=True)
class CurveSample:
    """The picklable curve function of the study: ``machine``, the nominal ``contact``, ``points`` depth samples
    per curve and ``max_depth_m`` (m; None: the laws' own stroke, lengthened until every pin seats). Called with
    a dict of deviations it returns (sensed depth m, total force N); a curve whose series residual exceeds
    ``RESIDUAL_LIMIT_N`` raises ResidualError."""

    machine: Machine
    contact: Contact
    points: int = DEFAULT_POINTS
    max_depth_m: float | None = None
    stop_force_n: float | None = None  # the press stops a seated component at its force limit (predict_curve)

    @classmethod
    def from_case(cls, case: Case, machine: Machine, points: int | None = None) -> CurveSample:
        """The case's sample: its ``[curve] points`` (or ``points``); the stroke the laws' own, or the case's
        ``[simulation] interference_m`` for a law without a depth range (an elastic spring without a shoulder); a
        seated component pressed on to the case's force limit."""
        if case.simulation is None:
            raise PressCurveError(case.path, "[simulation]", "the case has no [simulation] table (its contact is "
                                  "the joint)")
        contact = case.simulation.contact
        finite = all(np.isfinite(law.depth_range_m[1]) for law in PinField.from_contact(contact).laws)
        n = points if points is not None else case.curve.points if case.curve is not None else DEFAULT_POINTS
        return cls(machine=machine, contact=contact, points=n,
                   max_depth_m=None if finite else case.simulation.interference_m,
                   stop_force_n=case.simulation.controller.force_limit_n)

    def __call__(self, values: Mapping[str, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
        curve = predict_curve(self.machine, perturbed_contact(self.contact, values or {}), samples=self.points,
                              max_depth_m=self.max_depth_m, stop_force_n=self.stop_force_n)
        if not curve.series_residual_n <= RESIDUAL_LIMIT_N:
            raise ResidualError("the press curve's series equation", "max |F - f(d)| (N)", curve.series_residual_n,
                                RESIDUAL_LIMIT_N, where=f"curve sample {dict(values or {})}")
        return curve.sensed_depth_m, curve.force_n
