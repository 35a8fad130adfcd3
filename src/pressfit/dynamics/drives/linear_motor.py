r"""Direct-drive linear motor (``[actuator] kind = "linear_motor"``, docs/drives.md): the drive the paper argues
for, a forcer on each leg's stem over a magnet track along its cylinder, with no screw between the motor and
the leg (table :class:`pressfit.description.machine.LinearMotorDrive`).

Force: N = K_f i (1 + eps cos(k l)) + F_cog sin(k l), K_f = ``force_constant_n_per_a`` (N/A), l the leg length
(m: the forcer's position on its track, origin at l = 0, an arbitrary phase), k = 2 pi / (tau_p / 3) with
tau_p = ``pole_pitch_m``: a 3-phase motor commutated sinusoidally has its force ripple (eps =
``force_ripple_fraction`` of K_f i) and, for the usual slot/pole combinations, its cogging (F_cog =
``cogging_force_n``, independent of the current) at the 6th harmonic of the electrical period 2 tau_p, i.e. of
period tau_p / 3 (our choice of the one dominant harmonic; the back-EMF is taken ripple-free). The drive
compensates a fraction c = ``ripple_compensation`` of both (a calibrated anti-cogging table: the current
reference (N_cmd - c F_cog sin(k l_m)) / (K_f (1 + c eps cos(k l_m))) at the encoder's length l_m), leaving
(1 - c) of them, plus the travel within the step, as a force disturbance. The delivered
tension is evaluated at the step's end length l + l_dot dt. The current loop (ZOH, exact for any dt), the
current limit and the speed limit (``speed_limit_m_per_s`` on the leg speed, the motor speed w = -l_dot > 0 while
the leg shortens, back-EMF K_f w) are :mod:`pressfit.dynamics.drives.current_loop`'s. The linear encoder
quantises the leg length the controller sees on ``encoder_resolution_m`` (round to the nearest count).

Statics: the mount's ``mount_stiffness_n_per_m`` is the drive's axial stiffness; the forcer's
``moving_mass_kg`` rides along the leg as the prismatic joint's armature (behind the mount in the linear port).

Thermal (copper loss P = R i^2, R = ``winding_resistance_ohm``; a first-order winding-to-ambient model,
R_th = ``thermal_resistance_k_per_w``, tau = ``thermal_time_constant_s``): tau dT/dt = R_th P - T for the rise T
over ambient. With P held over each sample (zero-order hold) it is integrated exactly:

    T_{k+1} = a T_k + (1 - a) R_th P_k,   a = exp(-dt / tau)

(:func:`winding_rise_k`; a constant current reaches 1 - 1/e = 63.2% of R_th R i^2 at t = tau). A motion
repeated back to back with period T_p = n dt settles to the periodic steady state whose start is the geometric
series T_0 = T_c(T_p) (1 + a^n + a^2n + ...) = T_c(T_p) / (1 - a^n), T_c the cold-start rise
(:func:`periodic_winding_rise_k`). The sizing (:meth:`LinearMotorDrive.sizing`) rates the periodic peak
against ``max_winding_temperature_rise_k`` and the RMS force against ``continuous_force_n``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from pressfit.description.machine import LinearMotorDrive as LinearMotorTable
from pressfit.description.machine import Machine
from pressfit.dynamics.drives.base import Rating, rms
from pressfit.dynamics.drives.current_loop import CurrentLoopDrive

RIPPLE_HARMONIC = 3  # ripple periods per pole pitch (6 per electrical period 2 tau_p of a 3-phase motor)


@dataclass(frozen=True, kw_only=True)
class LinearMotorSizing:
    """A linear motor's figures over a motion (:meth:`LinearMotorDrive.sizing`): current A, copper loss W (mean
    R i^2) and energy J, winding temperature rises K (the peak from a cold start, the peak in the periodic steady
    state of the motion repeated back to back, and R_th times the mean loss: the rise it averages to)."""

    kind = "linear_motor"
    rms_current_a: float
    peak_current_a: float
    copper_loss_w: float
    copper_energy_j: float
    peak_winding_rise_k: float
    periodic_winding_rise_k: float
    mean_winding_rise_k: float

    def loss_energy_j(self, net_work_j: float) -> float:
        """Its losses upstream of the joint, J: the copper energy."""
        return self.copper_energy_j


def winding_rise_k(power_w: np.ndarray, dt_s: float, thermal_resistance_k_per_w: float,
                   time_constant_s: float, start_k: float = 0.0) -> np.ndarray:
    """The winding's temperature rise (K) at the end of each sample of the copper loss ``power_w`` (n,) W held
    over dt (s): T_{k+1} = a T_k + (1 - a) R_th P_k, a = exp(-dt / tau), from T_0 = ``start_k`` (module doc)."""
    a = math.exp(-dt_s / time_constant_s)
    p = np.asarray(power_w, dtype=float)
    out, _ = lfilter([(1.0 - a) * thermal_resistance_k_per_w], [1.0, -a], p, zi=[a * start_k])
    return out


def periodic_winding_rise_k(power_w: np.ndarray, dt_s: float, thermal_resistance_k_per_w: float,
                            time_constant_s: float) -> np.ndarray:
    """The rise (K) over one period of ``power_w`` (n,) W repeated back to back, in its periodic steady state:
    from T_0 = T_c(end) / (1 - a^n) (module doc), T_c the cold-start rise."""
    cold = winding_rise_k(power_w, dt_s, thermal_resistance_k_per_w, time_constant_s)
    decay = math.exp(-cold.size * dt_s / time_constant_s)
    start = float(cold[-1]) / (1.0 - decay)
    return winding_rise_k(power_w, dt_s, thermal_resistance_k_per_w, time_constant_s, start)


class LinearMotorDrive(CurrentLoopDrive):
    """Direct-drive linear motor (module docstring)."""

    kind = "linear_motor"
    speed_limit_key = "[actuator.linear_motor] speed_limit_m_per_s"

    def __init__(self, machine: Machine) -> None:
        self.table: LinearMotorTable = machine.actuator.linear_motor
        super().__init__(machine)
        self.wavenumber_per_m = 2.0 * math.pi * RIPPLE_HARMONIC / self.table.pole_pitch_m

    @property
    def emf_constant(self) -> float:
        """K_e = K_f, V s/m."""
        return self.table.force_constant_n_per_a

    @property
    def speed_limit(self) -> float:
        return self.table.speed_limit_m_per_s

    @property
    def speed_limit_m_per_s(self) -> float:
        """``speed_limit_m_per_s``, m/s."""
        return self.table.speed_limit_m_per_s

    def motor_speed(self, rates_m_per_s: np.ndarray) -> np.ndarray:
        """w = -l_dot, m/s (> 0 while the leg shortens)."""
        return -np.asarray(rates_m_per_s, dtype=float)

    def emf_per_rate(self) -> float:
        """-K_f, V s/m."""
        return -self.table.force_constant_n_per_a

    def _harmonics(self, lengths_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        phase = self.wavenumber_per_m * np.asarray(lengths_m, dtype=float)
        return np.cos(phase), np.sin(phase)

    def force_n(self, current_a: np.ndarray, lengths_m: np.ndarray) -> np.ndarray:
        """N = K_f i (1 + eps cos(k l)) + F_cog sin(k l), N (module docstring)."""
        t = self.table
        cos, sin = self._harmonics(lengths_m)
        return t.force_constant_n_per_a * current_a * (1.0 + t.force_ripple_fraction * cos) + t.cogging_force_n * sin

    def current_for_force_a(self, force_n: np.ndarray, lengths_m: np.ndarray) -> np.ndarray:
        """i = (N - F_cog sin(k l)) / (K_f (1 + eps cos(k l))), A (inverts :meth:`force_n`)."""
        t = self.table
        cos, sin = self._harmonics(lengths_m)
        return ((np.asarray(force_n, dtype=float) - t.cogging_force_n * sin)
                / (t.force_constant_n_per_a * (1.0 + t.force_ripple_fraction * cos)))

    def commanded_current_a(self, command_n: np.ndarray, lengths_m: np.ndarray | None) -> np.ndarray:
        """The current reference with the drive's calibrated ripple compensation c = ``ripple_compensation``:
        i = (N_cmd - c F_cog sin(k l_m)) / (K_f (1 + c eps cos(k l_m))) at the encoder's lengths l_m (c = 0: N_cmd /
        K_f, no compensation; c = 1: the modelled ripple and cogging cancelled at the step's start), A."""
        t, c = self.table, self.table.ripple_compensation
        if lengths_m is None or c == 0.0:
            return np.asarray(command_n, dtype=float) / t.force_constant_n_per_a
        cos, sin = self._harmonics(self.measure_lengths_m(lengths_m))
        return ((np.asarray(command_n, dtype=float) - c * t.cogging_force_n * sin)
                / (t.force_constant_n_per_a * (1.0 + c * t.force_ripple_fraction * cos)))

    def sizing(self, tension_n: np.ndarray, rate_m_per_s: np.ndarray, dt_s: float
               ) -> tuple[LinearMotorSizing, list[Rating]]:
        """One motor over a motion (samples of tension N and leg rate m/s every dt s): the current i = N / K_f (the
        ripple's share, at most eps, left out), the copper loss R i^2, the winding rises (module docstring);
        rated: the peak leg speed (``speed_limit_m_per_s``), the RMS force (``continuous_force_n``) and the
        periodic peak rise (``max_winding_temperature_rise_k``)."""
        t, n, v = self.table, tension_n, rate_m_per_s
        current = n / t.force_constant_n_per_a
        loss = t.winding_resistance_ohm * current**2
        thermal = (dt_s, t.thermal_resistance_k_per_w, t.thermal_time_constant_s)
        periodic = float(periodic_winding_rise_k(loss, *thermal).max())
        sizing = LinearMotorSizing(
            rms_current_a=float(rms(current)), peak_current_a=float(np.abs(current).max()),
            copper_loss_w=float(loss.mean()), copper_energy_j=float(loss.sum() * dt_s),
            peak_winding_rise_k=float(winding_rise_k(loss, *thermal).max()), periodic_winding_rise_k=periodic,
            mean_winding_rise_k=float(t.thermal_resistance_k_per_w * loss.mean()))
        key = "[actuator.linear_motor] "
        return sizing, [
            Rating(figure="peak_speed_m_per_s", value=float(np.abs(v).max()), rating=t.speed_limit_m_per_s,
                   key=key + "speed_limit_m_per_s"),
            Rating(figure="rms_force_n", value=float(rms(n)), rating=t.continuous_force_n,
                   key=key + "continuous_force_n"),
            Rating(figure="periodic_winding_rise_k", value=periodic, rating=t.max_winding_temperature_rise_k,
                   key=key + "max_winding_temperature_rise_k")]
