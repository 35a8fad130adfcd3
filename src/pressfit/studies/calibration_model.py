"""The calibration's model: fitted keys of the machine file, the measured data, the prediction and its sensitivities.

Shared by :mod:`pressfit.studies.calibration` (the fit) and :mod:`pressfit.studies.measurement_plan` (the
planner). The prediction is the exact condensed linear model (:func:`pressfit.mechanics.condensed.solve_linear`)
for deflections and :func:`pressfit.dynamics.modes.natural_modes` for first frequencies; keys are fitted in
theta = ln(value) when positive (``FitKey.log``), else in value. Sensitivities d prediction / d theta are
central differences of the batched closed form: one batched solve over every row per key and sign.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pressfit.description.machine import Machine
from pressfit.dynamics.modes import natural_modes
from pressfit.errors import ModelFileError, PressfitError
from pressfit.mechanics.condensed import solve_linear
from pressfit.studies.measurements import Deflections, Frequencies

STEP = 1e-5  # central-difference step in theta (relative for log keys): truncation ~STEP^2, round-off ~1e-16/STEP


@dataclass(frozen=True, kw_only=True)
class FitKey:
    """One fitted key of the machine file: dotted ``table.key`` path, start value, bounds (SI units of the key),
    ``log`` = fitted in log space."""

    key: str
    start: float
    low: float
    high: float
    log: bool

    def to_theta(self, value: float | np.ndarray) -> np.ndarray:
        return np.log(value) if self.log else np.asarray(value, dtype=float)

    def from_theta(self, theta: float | np.ndarray) -> np.ndarray:
        return np.exp(theta) if self.log else np.asarray(theta, dtype=float)


def _lookup(data: dict[str, Any], key: str) -> Any:
    node: Any = data
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def _bounds(source: str, key: str, text: str | None, start: float) -> tuple[float, float]:
    if text is None:
        return (0.0, math.inf) if start > 0 else (-math.inf, math.inf)
    lo_text, sep, hi_text = text.partition(":")
    try:
        if not sep:
            raise ValueError
        lo, hi = float(lo_text), float(hi_text)
    except ValueError:
        raise ModelFileError(source, key, f"bounds as KEY=LO:HI with two numbers (got {text!r})") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ModelFileError(source, key, f"bounds LO < HIGH, both finite (got {text!r})")
    if not lo <= start <= hi:
        raise ModelFileError(source, key, f"bounds [{lo:g}, {hi:g}] exclude the start value {start:g} of the "
                             "machine file")
    return lo, hi


def parse_fit_keys(machine: Machine, specs: list[str]) -> list[FitKey]:
    """``--fit`` arguments ``table.key`` or ``table.key=LO:HI`` -> FitKey list, checked against the machine file:
    the key must exist, hold a number (not a boolean, a list or a table) and lie within its bounds; each key once.
    Raises ModelFileError naming the machine file and the key."""
    data, source = machine.model_dump(exclude={"source"}), machine.source
    keys: list[FitKey] = []
    for spec in specs:
        key, sep, bounds = spec.partition("=")
        key = key.strip()
        value = _lookup(data, key)
        if value is None:
            raise ModelFileError(source, key, "no such key in the machine file (give table.key, e.g. "
                                 "actuator.axial_stiffness_n_per_m)")
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ModelFileError(source, key, f"a numeric key to fit (it holds {value!r})")
        if any(k.key == key for k in keys):
            raise ModelFileError(source, key, "given twice to --fit")
        lo, hi = _bounds(source, key, bounds if sep else None, float(value))
        keys.append(FitKey(key=key, start=float(value), low=lo, high=hi, log=float(value) > 0 and lo >= 0))
    if not keys:
        raise PressfitError("give at least one --fit KEY")
    return keys


def machine_with(machine: Machine, keys: list[FitKey], values: np.ndarray) -> Machine:
    """A copy of the machine with the keys set to ``values`` (validated by the schema, as a file would be)."""
    overrides: dict[str, Any] = {}
    for k, v in zip(keys, values, strict=True):
        node = overrides
        *tables, last = k.key.split(".")
        for t in tables:
            node = node.setdefault(t, {})
        node[last] = float(v)
    return machine.with_overrides(overrides, source=machine.source)


@dataclass(frozen=True, kw_only=True)
class Data:
    """What is fitted: deflections and optional frequencies."""

    deflections: Deflections
    frequencies: Frequencies | None = None

    @property
    def stated_sigma(self) -> bool:
        f = self.frequencies
        return self.deflections.sigma_m is not None and (f is None or f.sigma_hz is not None)

    def weights(self) -> np.ndarray:
        """1 / sigma per residual (1 where no sigma is stated: residuals in m and Hz)."""
        d = self.deflections
        w = np.ones((len(d.pose_m), d.components))
        if d.sigma_m is not None:
            w[:, :3] = 1.0 / d.sigma_m[:, None]
        if d.rotation_rad is not None:
            w[:, 3:] = 1.0 / d.sigma_rad[:, None]
        parts = [w.reshape(-1)]
        if self.frequencies is not None:
            s = self.frequencies.sigma_hz
            parts.append(np.ones(len(self.frequencies.pose_m)) if s is None else 1.0 / s)
        return np.concatenate(parts)

    def measured(self) -> np.ndarray:
        d = self.deflections
        parts = [d.translation_m if d.rotation_rad is None else np.concatenate([d.translation_m, d.rotation_rad], 1)]
        out = [parts[0].reshape(-1)]
        if self.frequencies is not None:
            out.append(self.frequencies.frequency_hz)
        return np.concatenate(out)


def predict(machine: Machine, data: Data) -> np.ndarray:
    """The model's prediction of :meth:`Data.measured` (m, rad, Hz), flattened in the same order."""
    d = data.deflections
    res = solve_linear(machine, d.pose_m, d.load_n)
    out = [res.plate_displacement_m if d.rotation_rad is None
           else np.concatenate([res.plate_displacement_m, res.plate_rotation_rad], 1)]
    flat = [out[0].reshape(-1)]
    if data.frequencies is not None:
        flat.append(np.array([natural_modes(machine, h, count=1).frequencies_hz[0]
                              for h in data.frequencies.pose_m]))
    return np.concatenate(flat)


def sensitivities(machine: Machine, keys: list[FitKey], theta: np.ndarray, data: Data) -> np.ndarray:
    """d prediction / d theta (N, k) by central differences of the batched model (module doc)."""
    cols = []
    for j in range(len(keys)):
        step = np.zeros(len(keys))
        step[j] = STEP * (1.0 if keys[j].log else max(abs(theta[j]), 1e-12))
        plus, minus = (machine_with(machine, keys, values_of(keys, theta + s)) for s in (step, -step))
        cols.append((predict(plus, data) - predict(minus, data)) / (2 * step[j]))
    return np.stack(cols, 1)


def values_of(keys: list[FitKey], theta: np.ndarray) -> np.ndarray:
    return np.array([float(k.from_theta(t)) for k, t in zip(keys, theta, strict=True)])


