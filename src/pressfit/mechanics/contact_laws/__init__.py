r"""The contact laws of the pin-board joint as data: one module per law behind one interface
(:class:`ContactLawModel`: the force against the depth, vectorised, N against m; its depth range; its plateau if
it has one), and the one registry from ``[simulation.contact] law = "..."`` to its module (:data:`LAWS`; nothing
else reads the name). The shoulder (``seat_depth_m``, ``seat_stiffness_n_per_m``) is added to any law by
:mod:`pressfit.mechanics.contact_laws.seating`. Equations and units: docs/joint.md.

A module of a law offers ``from_keys(keys) -> ContactLawModel`` (``keys``: the law's keys of
:data:`pressfit.description.cases.CONTACT_LAW_KEYS`, SI, already validated by the schema). Each law also gives its
slope dF/dd in closed form (``force_and_slope``), and :func:`stack_laws` turns a field of pins of one kind into one
law whose numeric fields are arrays over the pins, evaluated on depths (..., n) at once (the press curve's series
Newton: one numpy pass per iteration for the whole field).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Any, Protocol, runtime_checkable

import numpy as np

from pressfit.mechanics.contact_laws import compliant_pin, elastic, seating, solid_pin, tabulated


@runtime_checkable
class ContactLawModel(Protocol):
    """A pin's contact law: ``force_n(depth_m)`` (N, >= 0, 0 at depth <= 0; vectorised over an array of depths in
    m, the interference of the pin's tip below the board face), ``depth_range_m`` (m: where the law's shape lies;
    the end is ``inf`` for a law without one, e.g. the elastic spring), ``plateau_force_n`` (N, the friction
    plateau of a pin law, or None), ``seat_depth_m`` (m, the shoulder's depth, or None), ``reversible`` (a spring,
    whose force follows the law back as the tool backs off: the elastic law; a pin law is set by its friction and
    the board's yield, so a tool backing off unloads the joint elastically from the deepest point it reached and
    leaves the pin there: :func:`pressfit.dynamics.contact.contact_parameters`) and ``notes`` (what the law says of
    itself: a capped pressure, ...)."""

    @property
    def depth_range_m(self) -> tuple[float, float]: ...

    @property
    def plateau_force_n(self) -> float | None: ...

    @property
    def seat_depth_m(self) -> float | None: ...

    @property
    def reversible(self) -> bool: ...

    @property
    def notes(self) -> tuple[str, ...]: ...

    def force_n(self, depth_m: np.ndarray) -> np.ndarray: ...

    def force_and_slope(self, depth_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...


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


def _kind(law: Any) -> tuple:
    """What must be equal for two laws to stack: the class, the non-numeric fields (by identity for arrays) and,
    for a shoulder, the inner law's kind."""
    if isinstance(law, seating.Seated):
        return seating.Seated, _kind(law.law)
    return (type(law),) + tuple(
        id(v) if isinstance(v, np.ndarray) else v for f in dataclasses.fields(law) if f.name != "notes"
        for v in [getattr(law, f.name)] if isinstance(v, bool) or not isinstance(v, (int, float)))


def _stack(laws: Sequence[Any]) -> Any:
    first = laws[0]
    if isinstance(first, seating.Seated):
        return seating.Seated(law=_stack([x.law for x in laws]),
                              seat_depth_m=np.array([x.seat_depth_m for x in laws]),
                              seat_stiffness_n_per_m=np.array([x.seat_stiffness_n_per_m for x in laws]))
    numeric = {f.name: np.array([getattr(x, f.name) for x in laws]) for f in dataclasses.fields(first)
               if f.name != "notes" and isinstance(getattr(first, f.name), (int, float))
               and not isinstance(getattr(first, f.name), bool)}
    return dataclasses.replace(first, **numeric)


def stack_laws(laws: Sequence[ContactLawModel]) -> tuple[tuple[np.ndarray, Any], ...]:
    """The pins' laws grouped by kind (:func:`_kind`: a class and its non-numeric fields): per group the pins'
    indices and one law whose numeric fields are arrays over them, ``force_and_slope`` of depths (..., len(group))
    giving each pin's own force and slope (N, N/m), the same numbers as the pin's law."""
    groups: dict[tuple, list[int]] = {}
    for i, law in enumerate(laws):
        groups.setdefault(_kind(law), []).append(i)
    return tuple((np.array(idx), _stack([laws[i] for i in idx])) for idx in groups.values())
