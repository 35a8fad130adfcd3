r"""The current (force) loop shared by the drives with an electric motor: the servo motor + ball screw
(:mod:`pressfit.dynamics.drives.electric`) and the direct-drive linear motor
(:mod:`pressfit.dynamics.drives.linear_motor`); their table is a
:class:`pressfit.description.machine.CurrentLoop`.

The delivered tension is N = k_f i (k_f the table's ``force_per_current_n_per_a``, N/A; a positive current pulls
the leg shorter) through :meth:`CurrentLoopDrive.force_n`, the hook a motor with force ripple overrides. The
force command is a current reference i_ref = sat(N_cmd / k_f), saturated at +-i_max; the force limit is k_f i_max.

Current loop, per leg, with the motor speed w (the subclass's :meth:`CurrentLoopDrive.motor_speed`, > 0 while
the leg shortens) and the back-EMF K_e w (K_e the subclass's ``emf_constant``, = K_t or K_f in SI):

* by its gains (PI on the winding, inductance L, resistance R):
  L di/dt = k_p (i_ref - i) + k_i z - R i - K_e w, dz/dt = i_ref - i; the closed loop
  i / i_ref = (k_p s + k_i) / (L s^2 + (R + k_p) s + k_i) (= k_p / (L s + k_p) when k_i / k_p = R / L);
* by its bandwidth f_c: di/dt = 2 pi f_c (i_ref - i) (an ideal first-order loop; back-EMF rejected).

Both are linear in (i, z) under inputs held over a step, so the step is their exact zero-order-hold
discretisation (matrix exponential, cached per step size): exact for any dt, however fast the loop.
The inverter limits the current to +-i_max. Speed limit: while |w| exceeds the subclass's ``speed_limit``,
a current reference that would accelerate the motor further is set to zero (the drive coasts back).
The drive measures the leg length (quantised on the encoder's ``encoder_resolution_m`` where the table gives
one: :meth:`CurrentLoopDrive.measure_lengths_m`) and its current (the force estimate k_f i).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import expm

from pressfit.description.machine import Machine
from pressfit.dynamics.drives.base import DrivePort, minus_3db_hz, require_step


@dataclass(frozen=True)
class CurrentLoopState:
    current_a: np.ndarray  # motor current i, A
    integral_a_s: np.ndarray  # PI integrator z = integral of (i_ref - i), A s (0 for the bandwidth form)


class CurrentLoopDrive:
    """A drive whose force is a motor current under a current loop (module docstring). A subclass sets
    ``kind``, ``table`` (in ``__init__``, before calling this one's), ``emf_constant`` and :meth:`motor_speed`,
    ``speed_limit``, and the leg-speed limit :attr:`speed_limit_m_per_s` with its key."""

    kind: str
    measures = ("leg_length_m", "current_a")
    follows_travel = True  # stepped inside the flexible step (its back-EMF follows the travel)
    explicit_spring = False  # nothing the rigid model's explicit coupling must resolve
    speed_limit_key = ""
    table: Any

    def __init__(self, machine: Machine) -> None:
        self.machine = machine
        t = self.table
        self.force_limit_key = t.force_limit_key
        self.force_per_current_n_per_a = t.force_per_current_n_per_a
        if t.current_loop_bandwidth_hz is not None:
            w = 2.0 * math.pi * t.current_loop_bandwidth_hz
            self._a = np.array([[-w, 0.0], [0.0, 0.0]])
            self._b = np.array([[w, 0.0], [0.0, 0.0]])  # inputs (i_ref, back-EMF V)
        else:
            inv_l = 1.0 / t.winding_inductance_h
            kp, ki, r = t.current_loop_kp_v_per_a, t.current_loop_ki_v_per_a_s, t.winding_resistance_ohm
            self._a = np.array([[-(kp + r) * inv_l, ki * inv_l], [-1.0, 0.0]])
            self._b = np.array([[kp * inv_l, -inv_l], [1.0, 0.0]])
        self._zoh: dict[float, tuple[float, ...]] = {}

    @classmethod
    def of(cls, machine: Machine) -> CurrentLoopDrive:
        return cls(machine)

    @property
    def emf_constant(self) -> float:
        raise NotImplementedError

    @property
    def speed_limit(self) -> float:
        raise NotImplementedError

    @property
    def speed_limit_m_per_s(self) -> float | None:
        raise NotImplementedError

    def motor_speed(self, rates_m_per_s: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def emf_per_rate(self) -> float:
        """d(back-EMF)/d(leg rate), V s/m."""
        raise NotImplementedError

    @property
    def force_limit_n(self) -> float:
        """k_f i_max, N."""
        return self.table.force_limit_n

    @property
    def reflected_mass_kg(self) -> float:
        return self.machine.drive_reflected_mass_kg

    def closed_loop(self, frequency_hz: np.ndarray) -> np.ndarray:
        """The current (= force) loop i / i_ref at frequencies (Hz), complex (blocked motor)."""
        s = 2j * math.pi * np.asarray(frequency_hz, dtype=float)
        t = self.table
        if t.current_loop_bandwidth_hz is not None:
            w = 2.0 * math.pi * t.current_loop_bandwidth_hz
            return w / (s + w)
        kp, ki = t.current_loop_kp_v_per_a, t.current_loop_ki_v_per_a_s
        return (kp * s + ki) / (t.winding_inductance_h * s**2 + (t.winding_resistance_ohm + kp) * s + ki)

    @property
    def bandwidth_hz(self) -> float:
        """The -3 dB frequency of :meth:`closed_loop` (its last crossing of 1/sqrt 2), Hz."""
        return minus_3db_hz(self.closed_loop)

    def discrete(self, dt_s: float) -> tuple[float, ...]:
        """The loop's zero-order-hold matrices at dt, Phi (2, 2) and Gamma (2, 2) on the inputs (i_ref, back-EMF), as
        floats row by row: (Phi_00, Phi_01, Gamma_00, Gamma_01, Phi_10, Phi_11, Gamma_10, Gamma_11) (the step's
        per-leg arithmetic reads them without indexing arrays per call)."""
        if dt_s not in self._zoh:
            aug = np.zeros((4, 4))
            aug[:2, :2], aug[:2, 2:] = self._a * dt_s, self._b * dt_s
            self._zoh[dt_s] = tuple(expm(aug)[:2, :].ravel().tolist())
        return self._zoh[dt_s]

    def current_for_force_a(self, force_n: np.ndarray, lengths_m: np.ndarray) -> np.ndarray:
        """The current delivering ``force_n`` at ``lengths_m`` (N / k_f; inverts :meth:`force_n`), A."""
        return np.asarray(force_n, dtype=float) / self.force_per_current_n_per_a

    def force_n(self, current_a: np.ndarray, lengths_m: np.ndarray) -> np.ndarray:
        """The tension the current delivers at the leg lengths, k_f i, N."""
        return self.force_per_current_n_per_a * current_a

    def initial_state(self, force_n: np.ndarray, lengths_m: np.ndarray) -> CurrentLoopState:
        """At rest delivering ``force_n`` (clipped at the force limit): i = N / k_f, z = R i / k_i (steady)."""
        i = np.clip(self.current_for_force_a(force_n, lengths_m), -self.table.current_limit_a,
                    self.table.current_limit_a)
        t = self.table
        z = i * t.winding_resistance_ohm / t.current_loop_ki_v_per_a_s if t.current_loop_bandwidth_hz is None else 0 * i
        return CurrentLoopState(i, z)

    def commanded_current_a(self, command_n: np.ndarray, lengths_m: np.ndarray | None) -> np.ndarray:
        """The current the drive commands for a tension N_cmd at the measured lengths, N_cmd / k_f, A (the hook of a
        motor that compensates its ripple)."""
        return np.asarray(command_n, dtype=float) / self.force_per_current_n_per_a

    def current_reference_a(self, command_n: np.ndarray, rates_m_per_s: np.ndarray,
                            lengths_m: np.ndarray | None = None) -> np.ndarray:
        """sat(N_cmd / k_f) (:meth:`commanded_current_a`) with the speed limit applied (module docstring), A."""
        return self._reference(command_n, self.motor_speed(rates_m_per_s), lengths_m)

    def _reference(self, command_n: np.ndarray, omega: np.ndarray, lengths_m: np.ndarray | None) -> np.ndarray:
        """:meth:`current_reference_a` at the motor speeds ``omega`` (the subclass's unit)."""
        limit, speed = self.table.current_limit_a, self.speed_limit
        i_ref = np.minimum(np.maximum(self.commanded_current_a(command_n, lengths_m), -limit), limit)
        i_ref = np.where(omega > speed, np.minimum(i_ref, 0.0), i_ref)
        return np.where(omega < -speed, np.maximum(i_ref, 0.0), i_ref)

    def step(self, state: CurrentLoopState, command_n: np.ndarray, lengths_m: np.ndarray, rates_m_per_s: np.ndarray,
             dt_s: float) -> tuple[CurrentLoopState, np.ndarray]:
        p00, p01, g00, g01, p10, p11, g10, g11 = self.discrete(require_step(dt_s))
        omega = self.motor_speed(rates_m_per_s)
        i_ref = self._reference(command_n, omega, lengths_m)
        emf = self.emf_constant * omega
        i, z = state.current_a, state.integral_a_s
        i_new = p00 * i + p01 * z + g00 * i_ref + g01 * emf
        z_new = p10 * i + p11 * z + g10 * i_ref + g11 * emf
        limit = self.table.current_limit_a
        i_new = np.minimum(np.maximum(i_new, -limit), limit)
        end = np.asarray(lengths_m, dtype=float) + np.asarray(rates_m_per_s, dtype=float) * dt_s
        return CurrentLoopState(i_new, z_new), self.force_n(i_new, end)

    def saturated(self, command_n: np.ndarray) -> np.ndarray:
        return np.abs(command_n) > self.force_limit_n

    def axial_stiffness_n_per_m(self, lengths_m: np.ndarray) -> np.ndarray:
        return self.machine.drive_stiffness_n_per_m(lengths_m)

    def measure_lengths_m(self, lengths_m: np.ndarray) -> np.ndarray:
        """The leg lengths its encoder reports, m: quantised on ``encoder_resolution_m`` (round to the nearest
        count) where the table gives one, else exact."""
        resolution = getattr(self.table, "encoder_resolution_m", None)
        if resolution is None:
            return lengths_m
        return np.round(np.asarray(lengths_m, dtype=float) / resolution) * resolution

    def copper_loss_w(self, state: CurrentLoopState) -> np.ndarray:
        """R i^2 per motor, W (0 without ``winding_resistance_ohm``)."""
        r = self.table.winding_resistance_ohm or 0.0
        return r * state.current_a**2

    def step_stiffness_n_per_m(self, lengths_m: np.ndarray) -> np.ndarray:
        """0, N/m: the current follows the travel only through the back-EMF, a rate term the iterations resolve."""
        return np.zeros_like(np.asarray(lengths_m, dtype=float))

    def linear_port(self, length_m: float, tension_n: float) -> DrivePort:
        r"""The current loop (module docstring) with i_ref = dN_cmd / k_f and the back-EMF K_e w (w the motor speed
        of v, the motor side's rate); dN = k_f i. The motor's reflected mass (``reflected_mass_kg``) sits on the
        motor side of the drive's own stiffness in series (``axial_stiffness_n_per_m`` at the length)."""
        n = 1 if self.table.current_loop_bandwidth_hz is not None else 2
        a, b = self._a[:n, :n], self._b[:n]
        c = np.zeros(n)
        c[0] = self.force_per_current_n_per_a
        return DrivePort(states=("current_a", "integral_a_s")[:n], a=a.copy(),
                         b_command=b[:, 0] / self.force_per_current_n_per_a, b_rate=b[:, 1] * self.emf_per_rate(),
                         c=c, reflected_mass_kg=self.reflected_mass_kg,
                         series_stiffness_n_per_m=float(self.axial_stiffness_n_per_m(np.array(length_m))))
