r"""Servo valve + symmetric double-acting cylinder (``[actuator] kind = "hydraulic"``, docs/drives.md).

Chambers: a (its pressure pulls the leg shorter) and b; piston area A on both sides (a rod through both
ends), piston position x = l - l_min + margin (:meth:`pressfit.description.machine.Machine.piston_position_m`),
volumes V_a = V_0a + A (s - x), V_b = V_0b + A x. The delivered tension is N = A (p_a - p_b). Flow continuity
with the bulk modulus beta and the leakage across the piston Q_L = C_L (p_a - p_b):

    dp_a/dt = beta / V_a (Q_a + A x_dot - Q_L),   dp_b/dt = beta / V_b (Q_b - A x_dot + Q_L).

Valve (critically lapped, spool x_v in [-1, 1]): x_v > 0 connects supply to a and b to tank, x_v < 0 the
reverse, each land an orifice Q = K_v x_v sqrt(dp) (signed, so that the flow reverses with the drop);
below dp_lam = ``LAMINAR_FRACTION`` (p_s - p_t) the orifice is laminar, Q = K_v x_v dp / sqrt(dp_lam) (the
usual regularisation: it keeps dQ/dp finite at a closed land; 0.1% of the supply drop). The spool follows
its command with a first-order lag of ``valve_bandwidth_hz``. Pressure (force) loop, analog in the valve
amplifier: x_v,cmd = sat(g (dp_cmd - (p_a - p_b)) - f_v A l_dot / K_q), dp_cmd = sat(N_cmd) / A, with N_cmd
saturated at the drive's force limit A (p_s - p_t); f_v = ``flow_feedforward`` feeds the leg's flow A l_dot
forward from the measured rate (without it the proportional loop must open the spool by a pressure error,
a drag of A^2 / (g K_q) N s/m per leg: = k_h / w_p, the oil column over the pressure loop's bandwidth).
Linearised about the null (p_a = p_b = (p_s + p_t) / 2, blocked piston),
with K_q = K_v sqrt((p_s - p_t) / 2) and c = beta (1/V_a + 1/V_b):

    dp / dp_cmd = g c K_q w_v / ((s + c C_L)(s + w_v) + g c K_q w_v),   w_v = 2 pi f_v,

a loop of bandwidth about c (g K_q + C_L) (rad/s) behind the valve.

Integration (the chambers are stiff: dQ/dp of an open land and beta / V make rates of 1e4-1e5 1/s):
each step of the caller is split into n = ceil(dt / ``SUBSTEP_S``) substeps; in each, the spool is updated
exactly (exponential of its lag under the held command), then the pressures by one linearly implicit
(Rosenbrock-Euler) step p' = p + h (I - h J)^-1 f(p) with the analytic 2x2 Jacobian J of each leg: stable for
any h (the linearised chamber dynamics have negative real eigenvalues), first-order accurate, so the substep
is set by accuracy only (0.1 ms against the loop's ~4 ms time scale and the valve's 1.6 ms). The leg length
moves at its held rate within the step. A step is refused (:class:`pressfit.errors.DriveStepError`) when
the piston would leave the stroke, a pressure leaves [-0.1 p_s, 10 p_s] (a load the cylinder cannot hold: a
relief valve or cavitation, which this model does not have) or is not finite, or when dt needs more than
``MAX_SUBSTEPS``. The oil column's stiffness against the moving mass (sqrt(k_h / m) / 2 pi, hundreds of Hz)
is the caller's to resolve: an explicit coupling (the rigid model) needs a step short against it
(:func:`oil_column_step_index`), an implicit one takes :meth:`HydraulicDrive.step_stiffness_n_per_m` as the
drive's tangent (the flexible model).

Measures: the leg length (a position transducer) and both chamber pressures (the force A (p_a - p_b)).
No reflected inertia: the piston and rod translate with the stem (``mass.actuator_moving_mass_kg``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pressfit.description.machine import HydraulicDrive as HydraulicTable
from pressfit.description.machine import Machine
from pressfit.dynamics import kernels
from pressfit.dynamics.drives.base import DrivePort, Rating, minus_3db_hz, require_step
from pressfit.errors import DriveStepError

SUBSTEP_S = 1e-4  # largest pressure substep, s (accuracy, not stability: module docstring)
MAX_SUBSTEPS = 100_000  # a step that needs more is refused (dt above 10 s)
LAMINAR_FRACTION = 1e-3  # laminar orifice below this fraction of the supply drop p_s - p_t


@dataclass(frozen=True, kw_only=True)
class HydraulicState:
    pressure_a_pa: np.ndarray  # chamber a (pulls the leg shorter), Pa
    pressure_b_pa: np.ndarray  # chamber b, Pa
    spool: np.ndarray  # valve opening x_v in [-1, 1]


@dataclass(frozen=True, kw_only=True)
class HydraulicSizing:
    """A hydraulic drive's supply figures (:meth:`HydraulicDrive.sizing`): flow m^3/s, power W, energy J."""

    kind = "hydraulic"
    peak_flow_m3_per_s: float
    peak_supply_power_w: float
    mean_supply_power_w: float
    supply_energy_j: float

    def loss_energy_j(self, net_work_j: float) -> float:
        """The valve's throttling, J: the supplied energy minus the net mechanical work ``net_work_j`` (J)."""
        return self.supply_energy_j - net_work_j


class HydraulicDrive:
    """Servo-hydraulic drive (module docstring)."""

    kind = "hydraulic"
    measures = ("leg_length_m", "pressure_a_pa", "pressure_b_pa")
    reflected_mass_kg = 0.0
    force_limit_key = HydraulicTable.force_limit_key
    follows_travel = True  # the oil column follows the travel: stepped inside the flexible step
    explicit_spring = True  # the rigid model's explicit coupling must resolve the oil column (refuse_step)
    speed_limit_m_per_s = None
    speed_limit_key = ""

    def __init__(self, machine: Machine) -> None:
        self.machine = machine
        self.table: HydraulicTable = machine.actuator.hydraulic
        t = self.table
        self.area_m2 = t.area_m2
        self.laminar_pa = LAMINAR_FRACTION * (t.supply_pressure_pa - t.tank_pressure_pa)
        self.valve_time_constant_s = 1.0 / (2.0 * math.pi * t.valve_bandwidth_hz)
        self.null_flow_gain = t.valve_flow_gain_m3_per_s_sqrt_pa * math.sqrt(0.5 * (t.supply_pressure_pa -
                                                                                   t.tank_pressure_pa))
        self.feedforward_per_rate = t.flow_feedforward * self.area_m2 / self.null_flow_gain  # spool per m/s
        lim = machine.limits
        self._params = np.array([t.pressure_loop_gain_per_pa, t.valve_flow_gain_m3_per_s_sqrt_pa, self.laminar_pa,
                                 t.supply_pressure_pa, t.tank_pressure_pa, t.leakage_m3_per_s_pa, t.bulk_modulus_pa,
                                 self.area_m2, t.dead_volume_a_m3, t.dead_volume_b_m3, t.stroke_m,
                                 lim.leg_length_min_m,  # and x(l_min), the stroke's margin
                                 float(machine.piston_position_m(lim.leg_length_min_m))])

    @classmethod
    def of(cls, machine: Machine) -> HydraulicDrive:
        return cls(machine)

    @property
    def force_limit_n(self) -> float:
        """A (p_s - p_t), N."""
        return self.table.force_limit_n

    @property
    def null_pressure_pa(self) -> float:
        """(p_s + p_t) / 2: both chambers at the null of a symmetric valve, Pa."""
        return 0.5 * (self.table.supply_pressure_pa + self.table.tank_pressure_pa)

    def volumes_m3(self, lengths_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t = self.table
        x = self.machine.piston_position_m(lengths_m)
        return t.dead_volume_a_m3 + self.area_m2 * (t.stroke_m - x), t.dead_volume_b_m3 + self.area_m2 * x

    def closed_loop(self, frequency_hz: np.ndarray, length_m: float | None = None) -> np.ndarray:
        """The linearised pressure loop dp / dp_cmd (module docstring) at a leg length (default mid-travel), complex."""
        t, lim = self.table, self.machine.limits
        length = 0.5 * (lim.leg_length_min_m + lim.leg_length_max_m) if length_m is None else length_m
        v_a, v_b = self.volumes_m3(np.array(length))
        c = t.bulk_modulus_pa * (1.0 / v_a + 1.0 / v_b)
        kq = t.valve_flow_gain_m3_per_s_sqrt_pa * math.sqrt(0.5 * (t.supply_pressure_pa - t.tank_pressure_pa))
        wv = 1.0 / self.valve_time_constant_s
        s = 2j * math.pi * np.asarray(frequency_hz, dtype=float)
        loop = t.pressure_loop_gain_per_pa * c * kq * wv
        return loop / ((s + c * t.leakage_m3_per_s_pa) * (s + wv) + loop)

    @property
    def bandwidth_hz(self) -> float:
        """-3 dB frequency of :meth:`closed_loop` at mid-travel, Hz."""
        return minus_3db_hz(self.closed_loop)

    def initial_state(self, force_n: np.ndarray, lengths_m: np.ndarray) -> HydraulicState:
        """Pressures delivering ``force_n`` (clipped at the limit) symmetric about the null, spool centred (with
        leakage the pressure loop then takes a few milliseconds to find its steady opening)."""
        dp = np.clip(np.asarray(force_n, dtype=float), -self.force_limit_n, self.force_limit_n) / self.area_m2
        p0 = self.null_pressure_pa
        return HydraulicState(pressure_a_pa=p0 + dp / 2, pressure_b_pa=p0 - dp / 2, spool=0 * dp)

    def step(self, state: HydraulicState, command_n: np.ndarray, lengths_m: np.ndarray, rates_m_per_s: np.ndarray,
             dt_s: float) -> tuple[HydraulicState, np.ndarray]:
        dt_s = require_step(dt_s)
        n = math.ceil(dt_s / SUBSTEP_S - 1e-9)
        if n > MAX_SUBSTEPS:
            raise DriveStepError(self.kind, 1, "time step dt_s", dt_s, f"at most {MAX_SUBSTEPS * SUBSTEP_S:g} s "
                                 f"({MAX_SUBSTEPS} pressure substeps of {SUBSTEP_S:g} s)")
        h = dt_s / n
        arrays = [np.array(a, dtype=float) for a in (state.pressure_a_pa, state.pressure_b_pa, state.spool,
                                                      command_n, lengths_m, rates_m_per_s)]  # copies: pa, pb, xv
        shape = arrays[0].shape
        if any(a.shape != shape for a in arrays) or arrays[0].ndim != 1:  # one leg, or per-leg values broadcast
            shape = np.broadcast_shapes(*(a.shape for a in arrays))
            arrays = [np.array(np.broadcast_to(a, shape), dtype=float).reshape(-1) for a in arrays]
        pa, pb, xv, command, length, rate = arrays
        dp_cmd = np.clip(command, -self.force_limit_n, self.force_limit_n) / self.area_m2
        decay = math.exp(-h / self.valve_time_constant_s)
        stroke_ok, pressures_ok = kernels.hydraulic_substeps(pa, pb, xv, dp_cmd, self.feedforward_per_rate * rate,
                                                             length, rate, h, n, decay, dt_s, self._params)
        if not stroke_ok:  # the piston leaves its stroke over the step: refused before the substeps' result is used
            self._check_stroke(length, rate, dt_s)
        if not pressures_ok:
            self._check_pressures(pa, pb)
        pa, pb, xv = pa.reshape(shape), pb.reshape(shape), xv.reshape(shape)
        return HydraulicState(pressure_a_pa=pa, pressure_b_pa=pb, spool=xv), self.area_m2 * (pa - pb)

    def _check_stroke(self, length: np.ndarray, rate: np.ndarray, dt_s: float) -> None:
        stroke = self.table.stroke_m
        for x in (self.machine.piston_position_m(length), self.machine.piston_position_m(length + rate * dt_s)):
            bad = np.flatnonzero(~((x >= 0.0) & (x <= stroke)))
            if bad.size:
                leg = int(bad[0])
                raise DriveStepError(self.kind, leg + 1, "piston position x_m", float(np.ravel(x)[leg]),
                                     f"the stroke [0, {stroke:g}] m")

    def _check_pressures(self, pa: np.ndarray, pb: np.ndarray) -> None:
        ps = self.table.supply_pressure_pa
        for name, p in (("pressure_a_pa", pa), ("pressure_b_pa", pb)):
            bad = np.flatnonzero(~((p >= -0.1 * ps) & (p <= 10.0 * ps)))
            if bad.size:
                leg = int(bad[0])
                raise DriveStepError(self.kind, leg + 1, name, float(np.ravel(p)[leg]),
                                     f"[{-0.1 * ps:g}, {10.0 * ps:g}] Pa (no relief valve or cavitation modelled)")

    def measure_lengths_m(self, lengths_m: np.ndarray) -> np.ndarray:
        """The leg lengths from its position transducer, exact, m."""
        return lengths_m

    def sizing(self, tension_n: np.ndarray, rate_m_per_s: np.ndarray, dt_s: float
               ) -> tuple[HydraulicSizing, list[Rating]]:
        """One valve's supply over a motion (:mod:`pressfit.dynamics.sizing`): Q = A |l_dot| + C_L |N| / A at p_s;
        rated: the peak flow against the valve's no-load flow K_v sqrt((p_s - p_t) / 2)."""
        t, n, v = self.table, tension_n, rate_m_per_s
        flow = t.area_m2 * np.abs(v) + t.leakage_m3_per_s_pa * np.abs(n) / t.area_m2
        power = t.supply_pressure_pa * flow
        sizing = HydraulicSizing(peak_flow_m3_per_s=float(flow.max()), peak_supply_power_w=float(power.max()),
                                 mean_supply_power_w=float(power.mean()), supply_energy_j=float(power.sum() * dt_s))
        rated = t.valve_flow_gain_m3_per_s_sqrt_pa * math.sqrt(0.5 * (t.supply_pressure_pa - t.tank_pressure_pa))
        return sizing, [Rating(figure="peak_flow_m3_per_s", value=sizing.peak_flow_m3_per_s, rating=rated,
                               key="[actuator.hydraulic] valve_flow_gain_m3_per_s_sqrt_pa sqrt((p_s - p_t) / 2)")]

    def saturated(self, command_n: np.ndarray) -> np.ndarray:
        return np.abs(command_n) > self.force_limit_n

    def axial_stiffness_n_per_m(self, lengths_m: np.ndarray) -> np.ndarray:
        """The oil column with the valve closed, beta A^2 (1/V_a + 1/V_b), N/m."""
        return self.machine.drive_stiffness_n_per_m(lengths_m)

    def step_stiffness_n_per_m(self, lengths_m: np.ndarray) -> np.ndarray:
        """The chambers compressed by the piston's travel within a step, the valve and leakage held: the oil
        column k_h (:meth:`axial_stiffness_n_per_m`), N/m."""
        return self.axial_stiffness_n_per_m(lengths_m)

    def linear_port(self, length_m: float, tension_n: float) -> DrivePort:
        r"""Chambers and valve linearised at rest delivering ``tension_n`` (p_a,b = null +- N / 2A), states
        (dp_a, dp_b, x_v), v = l_dot:

            dp_a' = beta / V_a (K_qa x_v - K_ca dp_a + A v - C_L (dp_a - dp_b)),
            dp_b' = beta / V_b (-K_qb x_v - K_cb dp_b - A v + C_L (dp_a - dp_b)),
            x_v' = w_v (g (dN_cmd / A - (dp_a - dp_b)) - f_v A v / K_q - x_v),   dN = A (dp_a - dp_b).

        K_q = dQ/dx_v of each chamber's pair of lands, the mean of the opening (x_v > 0) and closing side
        (the critically lapped spool rests near its null, x_v0 = C_L (p_a - p_b) / (K_v sqrt(drop)) ~ 1e-4,
        where the two sides meet; at p_a = p_b both are K_v sqrt((p_s - p_t) / 2), the docstring's K_q);
        K_c = -dQ/dp at x_v0 (the land's flow-pressure coefficient, K_v |x_v0| / (2 sqrt(drop))). Blocked
        (v = 0) at p_a = p_b this is :meth:`closed_loop`; with the spool held (x_v = 0) and no leakage, the
        chambers on a mass m ring at sqrt(k_h / m) (k_h = :meth:`axial_stiffness_n_per_m`)."""
        t, area = self.table, self.area_m2
        ps, pt, cl = t.supply_pressure_pa, t.tank_pressure_pa, t.leakage_m3_per_s_pa
        kv = t.valve_flow_gain_m3_per_s_sqrt_pa
        dp0 = float(np.clip(tension_n, -self.force_limit_n, self.force_limit_n)) / area
        pa, pb = self.null_pressure_pa + dp0 / 2, self.null_pressure_pa - dp0 / 2
        floor = self.laminar_pa
        drops_a = np.maximum([ps - pa, pa - pt], floor)  # opening side (supply to a), closing side (a to tank)
        drops_b = np.maximum([pb - pt, ps - pb], floor)
        kqa, kqb = kv * np.mean(np.sqrt(drops_a)), kv * np.mean(np.sqrt(drops_b))
        side = 0 if dp0 >= 0 else 1
        xv0 = abs(cl * dp0) / (kv * math.sqrt(drops_a[side]))
        kca, kcb = kv * xv0 / (2 * math.sqrt(drops_a[side])), kv * xv0 / (2 * math.sqrt(drops_b[side]))
        v_a, v_b = (float(v) for v in self.volumes_m3(np.array(length_m)))
        ga, gb = t.bulk_modulus_pa / v_a, t.bulk_modulus_pa / v_b
        wv, g = 1.0 / self.valve_time_constant_s, t.pressure_loop_gain_per_pa
        a = np.array([[-ga * (kca + cl), ga * cl, ga * kqa],
                      [gb * cl, -gb * (kcb + cl), -gb * kqb],
                      [-wv * g, wv * g, -wv]])
        return DrivePort(states=("pressure_a_pa", "pressure_b_pa", "spool"), a=a,
                         b_command=np.array([0.0, 0.0, wv * g / area]),
                         b_rate=np.array([ga * area, -gb * area, -wv * self.feedforward_per_rate]),
                         c=np.array([area, -area, 0.0]))


STEP_FRACTION = 0.5  # the multibody step is refused beyond this fraction of the oil column's stability limit


def oil_column_step_index(stiffness_n_per_m: np.ndarray, mass_kg: np.ndarray, dt_s: float) -> np.ndarray:
    r"""omega_h dt / 2 for the oil column k_h on a mass m, omega_h = sqrt(k_h / m): the step is stable below 1.

    Derived: the rigid model's simulation couples drive and mechanics explicitly (the flexible model takes the
    drive inside its implicit step, :mod:`pressfit.dynamics.machine.flexible`). Over a step the drive holds the leg
    rate v_n (its pressures then change the force by -k_h v_n dt: the chambers' A l_dot term through beta / V), and the
    mechanics then advance the velocity with the new force (semi-implicit Euler), so on the oil column alone
    F_{n+1} = F_n - k_h dt v_n, v_{n+1} = v_n + dt F_{n+1} / m: the update matrix [[1, -k_h dt], [dt / m,
    1 - a]], a = (omega_h dt)^2, has determinant 1 and trace 2 - a, so its eigenvalues stay on the unit circle
    iff a < 4, i.e. omega_h dt < 2 (beyond, one grows as |z| > 1 every step: the pressures run away)."""
    omega = np.sqrt(np.asarray(stiffness_n_per_m, dtype=float) / np.asarray(mass_kg, dtype=float))
    return 0.5 * omega * dt_s


def refuse_step(machine: Machine, lengths_m: np.ndarray, mass_kg: np.ndarray, dt_s: float) -> str | None:
    """The reason (one clause naming the key and the limit) a hydraulic machine's time step ``dt_s`` cannot
    integrate the oil column k_h(l) on the mass ``mass_kg`` (m, kg: per leg, at the lengths ``lengths_m`` (n, 4)
    of the planned poses), or None; refused beyond ``STEP_FRACTION`` of :func:`oil_column_step_index`."""
    lengths = np.atleast_2d(np.asarray(lengths_m, dtype=float))
    k_h = machine.drive_stiffness_n_per_m(lengths)
    index = oil_column_step_index(k_h, np.broadcast_to(mass_kg, k_h.shape), dt_s)
    pose, leg = np.unravel_index(int(np.argmax(index)), index.shape)
    worst = float(index[pose, leg])
    if worst <= STEP_FRACTION:
        return None
    mass = float(np.broadcast_to(mass_kg, k_h.shape)[pose, leg])
    f_h = math.sqrt(k_h[pose, leg] / mass) / (2 * math.pi)
    bound = 2.0 * STEP_FRACTION / (2 * math.pi * f_h)
    return (f"at most {bound:.3g} s against the hydraulic oil column of leg {leg + 1} (omega_h dt / 2 = "
            f"{worst:.3g} > {STEP_FRACTION:g}; the explicit drive-mechanics coupling is stable below 1): "
            f"k_h = {k_h[pose, leg]:.4g} N/m at leg length {lengths[pose, leg]:.4g} m on {mass:.4g} kg, "
            f"f_h = {f_h:.4g} Hz")
