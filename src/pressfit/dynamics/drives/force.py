r"""The ideal force drive (``[actuator] kind = "force"``): today's first-order force source.

tau dN/dt = sat(N_cmd) - N, tau = 1 / (2 pi f_bw), the command saturated at +-``force_limit_n``; the step is
the exact zero-order-hold update N' = s + (N - s) exp(-dt / tau) of the saturated command s, the very
arithmetic of :class:`pressfit.dynamics.actuators.ForceActuators` (bit-identical results, tested). It
measures its delivered force (a load cell) and the leg length; its axial stiffness is
``axial_stiffness_n_per_m``; it has no reflected inertia.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pressfit.description.machine import ForceSource, Machine
from pressfit.dynamics.actuators import ForceActuators
from pressfit.dynamics.drives.base import DrivePort, Rating


@dataclass(frozen=True)
class ForceState:
    force_n: np.ndarray  # delivered tension, N


class ForceDrive:
    """The first-order force source (module docstring)."""

    kind = "force"
    measures = ("leg_length_m", "force_n")
    reflected_mass_kg = 0.0
    force_limit_key = ForceSource.force_limit_key
    follows_travel = False  # an ideal force source: stepped once per step, its tension held over it
    explicit_spring = False
    speed_limit_m_per_s = None
    speed_limit_key = ""

    def __init__(self, bandwidth_hz: float, force_limit_n: float, axial_stiffness_n_per_m: float) -> None:
        self._first_order = ForceActuators(bandwidth_hz, force_limit_n)  # validates both numbers
        self._stiffness = float(axial_stiffness_n_per_m)

    @classmethod
    def of(cls, machine: Machine) -> ForceDrive:
        t = machine.actuator.table
        return cls(t.force_bandwidth_hz, t.force_limit_n, t.axial_stiffness_n_per_m_)

    @property
    def bandwidth_hz(self) -> float:
        return self._first_order.bandwidth_hz

    @property
    def force_limit_n(self) -> float:
        return self._first_order.force_limit_n

    @property
    def time_constant_s(self) -> float:
        """tau = 1 / (2 pi f_bw), s."""
        return self._first_order.time_constant_s

    def initial_state(self, force_n: np.ndarray, lengths_m: np.ndarray) -> ForceState:
        return ForceState(np.array(force_n, dtype=float))

    def step(self, state: ForceState, command_n: np.ndarray, lengths_m: np.ndarray, rates_m_per_s: np.ndarray,
             dt_s: float) -> tuple[ForceState, np.ndarray]:
        force = self._first_order.step(state.force_n, command_n, dt_s)
        return ForceState(force), force

    def saturated(self, command_n: np.ndarray) -> np.ndarray:
        return self._first_order.saturated(command_n)

    def axial_stiffness_n_per_m(self, lengths_m: np.ndarray) -> np.ndarray:
        return np.full_like(np.asarray(lengths_m, dtype=float), self._stiffness)

    def step_stiffness_n_per_m(self, lengths_m: np.ndarray) -> np.ndarray:
        """0 (an ideal force source: the travel does not change its tension), N/m."""
        return np.zeros_like(np.asarray(lengths_m, dtype=float))

    def linear_port(self, length_m: float, tension_n: float) -> DrivePort:
        """tau dN' = dN_cmd - dN (the same at every length and tension)."""
        w = 1.0 / self.time_constant_s
        return DrivePort(states=("force_n",), a=np.array([[-w]]), b_command=np.array([w]), b_rate=np.zeros(1),
                         c=np.ones(1))

    def measure_lengths_m(self, lengths_m: np.ndarray) -> np.ndarray:
        """The leg lengths, exact (an ideal sensor), m."""
        return lengths_m

    def sizing(self, tension_n: np.ndarray, rate_m_per_s: np.ndarray, dt_s: float) -> tuple[None, list[Rating]]:
        """No figures of its own beyond the common ones (:mod:`pressfit.dynamics.sizing`)."""
        return None, []
