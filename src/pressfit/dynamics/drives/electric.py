r"""Servo motor + ball screw (``[actuator] kind = "electric"``, docs/drives.md).

Force from current: the screw turns the motor torque T = K_t i into the axial force F = 2 pi eta T / lead
(eta the screw efficiency), so the delivered tension is N = k_f i, k_f = 2 pi eta K_t / lead (N/A): a
positive current pulls the leg shorter. The force command is a current reference
i_ref = sat(N_cmd / k_f), saturated at +-i_max; the drive's force limit is k_f i_max.

Current loop (:mod:`pressfit.dynamics.drives.current_loop`, shared with the linear motor), per leg, with the
motor speed omega = -2 pi l_dot / lead (rad/s, > 0 while the leg shortens) and the back-EMF constant K_e = K_t:

* by its gains (PI on the winding, inductance L, resistance R, back-EMF K_e omega with K_e = K_t in SI):
  L di/dt = k_p (i_ref - i) + k_i z - R i - K_t omega, dz/dt = i_ref - i; the closed loop
  i / i_ref = (k_p s + k_i) / (L s^2 + (R + k_p) s + k_i) (= k_p / (L s + k_p) when k_i / k_p = R / L);
* by its bandwidth f_c: di/dt = 2 pi f_c (i_ref - i) (an ideal first-order loop; back-EMF rejected).

Both are linear in (i, z) under inputs held over a step, so the step is their exact zero-order-hold
discretisation (matrix exponential, cached per step size): exact for any dt, however fast the loop.
The inverter limits the current to +-i_max. Speed limit: while |omega| exceeds ``speed_limit_rad_per_s``,
a current reference that would accelerate the motor further is set to zero (the drive coasts back).

Reflected inertia: the rotor and the screw, m = J (2 pi / lead)^2 along the leg, are in the multibody model
as the prismatic joint's armature (:mod:`pressfit.dynamics.inertia`); the delivered tension k_f i is applied
to that joint, so the rotor's inertial force comes from the mass matrix, not from this module. The drive
measures the leg length (motor encoder through the lead) and its motor current (the force estimate k_f i).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pressfit.description.machine import ElectricDrive as ElectricTable
from pressfit.description.machine import Machine
from pressfit.dynamics.drives.base import Rating, rms
from pressfit.dynamics.drives.current_loop import CurrentLoopDrive, CurrentLoopState

ElectricState = CurrentLoopState  # motor current i (A) and the PI integrator z (A s)


@dataclass(frozen=True, kw_only=True)
class ElectricSizing:
    """An electric drive's motor figures (:meth:`ElectricDrive.sizing`): torque N m, current A, speed rad/s, loss W,
    energy J (the copper figures None without ``winding_resistance_ohm``)."""

    kind = "electric"
    rms_torque_nm: float
    peak_torque_nm: float
    rms_current_a: float
    peak_current_a: float
    peak_motor_speed_rad_per_s: float
    copper_loss_w: float | None
    copper_energy_j: float | None

    def loss_energy_j(self, net_work_j: float) -> float:
        """Its losses upstream of the joint, J: the copper energy (0 without the winding resistance)."""
        return 0.0 if self.copper_energy_j is None else self.copper_energy_j


class ElectricDrive(CurrentLoopDrive):
    """Servo motor + ball screw drive (module docstring)."""

    kind = "electric"
    speed_limit_key = "[actuator.electric] speed_limit_rad_per_s x lead_m / 2 pi"

    def __init__(self, machine: Machine) -> None:
        self.table: ElectricTable = machine.actuator.electric
        super().__init__(machine)

    @property
    def emf_constant(self) -> float:
        """K_e = K_t, V s/rad."""
        return self.table.torque_constant_nm_per_a

    @property
    def speed_limit(self) -> float:
        """The motor's ``speed_limit_rad_per_s``, rad/s."""
        return self.table.speed_limit_rad_per_s

    @property
    def speed_limit_m_per_s(self) -> float:
        """The leg speed of the motor's speed limit, speed_limit_rad_per_s lead / 2 pi, m/s."""
        return self.table.speed_limit_rad_per_s * self.table.lead_m / (2.0 * math.pi)

    def motor_speed(self, rates_m_per_s: np.ndarray) -> np.ndarray:
        return self.motor_speed_rad_per_s(rates_m_per_s)

    def motor_speed_rad_per_s(self, rates_m_per_s: np.ndarray) -> np.ndarray:
        """omega = -2 pi l_dot / lead, rad/s (> 0 while the leg shortens, the direction a positive current drives)."""
        return -2.0 * math.pi * np.asarray(rates_m_per_s, dtype=float) / self.table.lead_m

    def emf_per_rate(self) -> float:
        """-K_t 2 pi / lead, V s/m."""
        return -self.table.torque_constant_nm_per_a * 2.0 * math.pi / self.table.lead_m

    def sizing(self, tension_n: np.ndarray, rate_m_per_s: np.ndarray, dt_s: float) -> tuple[Any, list[Rating]]:
        """One motor's figures over a motion (:mod:`pressfit.dynamics.sizing`): current i = N / k_f, torque
        K_t i, motor speed 2 pi |l_dot| / lead, copper loss R RMS(i)^2; rated: the peak leg speed, the RMS torque
        (``continuous_torque_nm``) and the peak power (``rated_power_w``)."""
        t, n, v = self.table, tension_n, rate_m_per_s
        peak_speed, peak_power_w = float(np.abs(v).max()), float((-n * v).max())
        current = n / t.force_per_current_n_per_a
        torque = t.torque_constant_nm_per_a * current
        rms_i = float(rms(current))
        loss = None if t.winding_resistance_ohm is None else t.winding_resistance_ohm * rms_i**2
        sizing = ElectricSizing(
            rms_torque_nm=float(rms(torque)), peak_torque_nm=float(np.abs(torque).max()), rms_current_a=rms_i,
            peak_current_a=float(np.abs(current).max()),
            peak_motor_speed_rad_per_s=2.0 * math.pi * peak_speed / t.lead_m,
            copper_loss_w=loss, copper_energy_j=None if loss is None else loss * n.size * dt_s)
        ratings = [Rating(figure="peak_speed_m_per_s", value=peak_speed, rating=self.speed_limit_m_per_s,
                          key="[actuator.electric] speed_limit_rad_per_s lead / (2 pi)")]
        if t.continuous_torque_nm is not None:
            ratings.append(Rating(figure="rms_torque_nm", value=sizing.rms_torque_nm, rating=t.continuous_torque_nm,
                                  key="[actuator.electric] continuous_torque_nm"))
        if t.rated_power_w is not None:
            ratings.append(Rating(figure="peak_power_w", value=max(peak_power_w, 0.0), rating=t.rated_power_w,
                                  key="[actuator.electric] rated_power_w"))
        return sizing, ratings
