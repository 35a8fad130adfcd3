r"""The drive interface: what the insertion loop (or any simulation) asks of an actuator drive.

A drive turns a commanded leg tension N_cmd (N, > 0 tension, the project's convention: leg i pulls the plate
with -N_i e_i) into a delivered tension, given the leg's length l (m) and rate l_dot (m/s) from the multibody
model, both held over the step. All arrays have the legs' shape ((n,) for n legs; any shape broadcasts). A drive
object holds only constants (and per-step-size caches); its state is a separate frozen value, so one drive
serves several runs.

* ``initial_state(force_n, lengths_m)``: a state at rest delivering ``force_n``;
* ``step(state, command_n, lengths_m, rates_m_per_s, dt_s) -> (state, force_n)``: advance by dt, return the
  new state and the tension delivered at its end (what goes on the prismatic joints, -N);
* ``force_limit_n``: the largest tension magnitude it can deliver; ``saturated(command_n)``: where a command
  exceeds it;
* ``measures``: the quantities its own sensors give (names of the state's fields and of the leg length);
* ``axial_stiffness_n_per_m(lengths_m)``: its axial stiffness in the statics (the same function as
  :meth:`pressfit.description.machine.Machine.drive_stiffness_n_per_m`);
* ``step_stiffness_n_per_m(lengths_m)``: -dN/dl of the tension at a step's end in the leg's travel over the step
  (its loops held within the step): the tangent with which an implicit multibody step takes the drive
  (:meth:`pressfit.dynamics.machine.flexible.FlexibleMachine.step`); 0 for a drive whose tension does not follow
  the travel within a step;
* ``reflected_mass_kg``: rotating inertia reflected along the leg, which the multibody model carries as the
  prismatic joint's armature (:mod:`pressfit.dynamics.inertia`); the delivered force is therefore the drive's
  force before that inertia, never minus it (no double count);
* ``bandwidth_hz``: the -3 dB frequency of its force loop (small signal, blocked leg);
* ``linear_port(length_m, tension_n)``: the drive linearised about rest at one leg's length and tension
  (:class:`DrivePort`), for the control design (:mod:`pressfit.dynamics.linearise`);
* ``measure_lengths_m(lengths_m)``: the leg lengths its sensor reports (an encoder quantises them);
* ``sizing(tension_n, rate_m_per_s, dt_s)``: one drive's own figures over a motion (a frozen dataclass, or None)
  and their :class:`Rating`\ s, for :mod:`pressfit.dynamics.sizing` (which adds the peak force against
  ``force_limit_n``, named by ``force_limit_key``);
* flags read instead of the kind's name: ``follows_travel`` (its tension follows the leg's travel within a step,
  so an implicit step takes it inside its iterations), ``explicit_spring`` (a stiff spring, the oil column, that
  the rigid model's explicit coupling must resolve: :mod:`pressfit.dynamics.drives.steps`),
  ``speed_limit_m_per_s`` and ``speed_limit_key`` (the leg speed it cannot exceed, None without one).

The kinds are registered in :data:`pressfit.dynamics.drives.DRIVES` (schema table -> drive), the tables in
:data:`pressfit.description.machine.DRIVE_TABLES` (name -> table).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from scipy.optimize import brentq

from pressfit.errors import PressfitError


@dataclass(frozen=True, kw_only=True)
class DrivePort:
    r"""One leg's drive linearised about rest (deviations): x' = a x + b_command dN_cmd + b_rate v,
    dN = c x (N, tension), v (m/s) the rate of the coordinate the drive pushes on (the leg length, or for an
    electric drive the motor side of the screw). ``series_stiffness_n_per_m``: a spring between the drive's own
    coordinate (carrying ``reflected_mass_kg``) and the leg length (inf: the drive acts on the leg directly);
    ``states``: the names of x."""

    states: tuple[str, ...]
    a: np.ndarray  # (n, n)
    b_command: np.ndarray  # (n,) per N of command
    b_rate: np.ndarray  # (n,) per m/s
    c: np.ndarray  # (n,) N per unit state
    reflected_mass_kg: float = 0.0
    series_stiffness_n_per_m: float = math.inf

    def force_response(self, frequency_hz: np.ndarray) -> np.ndarray:
        """dN / dN_cmd with the coordinate held (v = 0) at frequencies (Hz), complex."""
        s = 2j * math.pi * np.atleast_1d(np.asarray(frequency_hz, dtype=float))
        eye = np.eye(self.a.shape[0])
        return np.array([self.c @ np.linalg.solve(w * eye - self.a, self.b_command) for w in s])


@dataclass(frozen=True, kw_only=True)
class Rating:
    """A sizing figure beside its rating: ``value`` and ``rating`` in the figure's unit, ``key`` the machine-file
    key the rating comes from."""

    figure: str
    value: float
    rating: float
    key: str

    @property
    def ratio(self) -> float:
        return self.value / self.rating

    @property
    def exceeded(self) -> bool:
        return self.ratio > 1.0

    def to_dict(self) -> dict[str, Any]:
        return {"value": self.value, "rating": self.rating, "ratio": self.ratio, "exceeded": self.exceeded,
                "key": self.key}


def rms(x: np.ndarray) -> np.ndarray:
    """sqrt(mean x^2) over the first axis (samples), in x's unit."""
    return np.sqrt(np.mean(x * x, axis=0))


class Drive(Protocol):
    """An actuator drive (module docstring)."""

    kind: str
    measures: tuple[str, ...]
    force_limit_key: str
    follows_travel: bool
    explicit_spring: bool
    speed_limit_key: str

    @property
    def force_limit_n(self) -> float: ...

    @property
    def bandwidth_hz(self) -> float: ...

    @property
    def reflected_mass_kg(self) -> float: ...

    def initial_state(self, force_n: np.ndarray, lengths_m: np.ndarray) -> Any: ...

    def step(self, state: Any, command_n: np.ndarray, lengths_m: np.ndarray, rates_m_per_s: np.ndarray,
             dt_s: float) -> tuple[Any, np.ndarray]: ...

    def saturated(self, command_n: np.ndarray) -> np.ndarray: ...

    def axial_stiffness_n_per_m(self, lengths_m: np.ndarray) -> np.ndarray: ...

    def step_stiffness_n_per_m(self, lengths_m: np.ndarray) -> np.ndarray: ...

    def linear_port(self, length_m: float, tension_n: float) -> DrivePort: ...

    @property
    def speed_limit_m_per_s(self) -> float | None: ...

    def measure_lengths_m(self, lengths_m: np.ndarray) -> np.ndarray: ...

    def sizing(self, tension_n: np.ndarray, rate_m_per_s: np.ndarray, dt_s: float) -> tuple[Any, list[Rating]]: ...


class DriveOverStep:
    """One drive step from ``state`` as a function of the leg lengths at the step's end (the drive at the mean rate
    (l - l_n) / dt), for an implicit multibody step that evaluates it per iteration
    (:meth:`pressfit.dynamics.machine.flexible.FlexibleMachine.step`'s ``drive``); ``result``: the last call's
    (state, tension N)."""

    def __init__(self, drive: Drive, state: Any, command_n: np.ndarray, lengths_m: np.ndarray, dt_s: float) -> None:
        self.drive, self.state, self.command_n, self.lengths_m, self.dt_s = drive, state, command_n, lengths_m, dt_s
        self.result: tuple[Any, np.ndarray] | None = None

    def __call__(self, end_m: np.ndarray) -> np.ndarray:
        self.result = self.drive.step(self.state, self.command_n, self.lengths_m, (end_m - self.lengths_m) / self.dt_s,
                                      self.dt_s)
        return self.result[1]


def require_step(dt_s: float) -> float:
    """A time step must be a positive finite number of seconds."""
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise PressfitError(f"a drive time step must be a positive number of seconds, got {dt_s!r}")
    return float(dt_s)


def minus_3db_hz(response: Callable[[np.ndarray], np.ndarray]) -> float:
    """The highest frequency (Hz) where |response(f)| falls through 1/sqrt(2) (scanned on 1 mHz-1 MHz)."""
    grid = np.logspace(-3, 6, 1801)
    gain = np.abs(response(grid)) - math.sqrt(0.5)
    above = np.flatnonzero(gain >= 0.0)
    if not above.size or above[-1] == grid.size - 1:
        return math.nan
    k = above[-1]
    return float(brentq(lambda f: abs(response(np.array([f]))[0]) - math.sqrt(0.5), grid[k], grid[k + 1],
                        xtol=1e-12, rtol=1e-12))
