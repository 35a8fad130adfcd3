r"""The contact laws of the pin-board joint as data: one module per law behind one interface
(:class:`ContactLawModel`: the force against the depth, vectorised, N against m; its depth range; its plateau if
it has one), and the one registry from ``[simulation.contact] law = "..."`` to its module (:data:`LAWS`; nothing
else reads the name). The shoulder (``seat_depth_m``, ``seat_stiffness_n_per_m``) is added to any law by
:mod:`pressfit.mechanics.contact_laws.seating`. Equations and units: docs/joint.md.

A module of a law offers ``from_keys(keys) -> ContactLawModel`` (``keys``: the law's keys of
:data:`pressfit.description.cases.CONTACT_LAW_KEYS`, SI, already validated by the schema).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, Protocol, runtime_checkable

import numpy as np

from pressfit.mechanics.contact_laws import compliant_pin, elastic, seating, solid_pin, tabulated


@runtime_checkable
class ContactLawModel(Protocol):
    """A pin's contact law: ``force_n(depth_m)`` (N, >= 0, 0 at depth <= 0; vectorised over an array of depths in
    m, the interference of the pin's tip below the board face), ``depth_range_m`` (m: where the law's shape lies;
    the end is ``inf`` for a law without one, e.g. the elastic spring), ``plateau_force_n`` (N, the friction
    plateau of a pin law, or None), ``seat_depth_m`` (m, the shoulder's depth, or None) and ``notes`` (what the
    law says of itself: a capped pressure, ...)."""

    @property
    def depth_range_m(self) -> tuple[float, float]: ...

    @property
    def plateau_force_n(self) -> float | None: ...

    @property
    def seat_depth_m(self) -> float | None: ...

    @property
    def notes(self) -> tuple[str, ...]: ...

    def force_n(self, depth_m: np.ndarray) -> np.ndarray: ...


# the registry: [simulation.contact] law -> the module that builds it
LAWS: Mapping[str, Any] = MappingProxyType({
    "elastic": elastic, "press_fit": elastic, "solid_pin": solid_pin, "compliant_pin": compliant_pin,
    "tabulated": tabulated,
})


def build_law(law: str, keys: Mapping[str, Any]) -> ContactLawModel:
    """The law named ``law`` with its ``keys`` (SI), with the shoulder when ``keys`` has ``seat_depth_m``."""
    model = LAWS[law].from_keys(law, keys)
    if keys.get("seat_depth_m") is not None:
        model = seating.Seated(law=model, seat_depth_m=float(keys["seat_depth_m"]),
                               seat_stiffness_n_per_m=float(keys["seat_stiffness_n_per_m"]))
    return model
