r"""Figure 12's force-limited position control: pose estimate from the actuator lengths, a Cartesian PID
position loop, a force-limiting loop on the measured contact force, and the reference trajectory.

Estimate (forward kinematics of the redundant set): Gauss-Newton on the four lengths l_i(h) = |h + d_i - B_i|
(equation 1), h <- h - J^+ (l(h) - l_measured), J = dl/dh (rows e_i, equations 2-3), a few iterations from
the last estimate (least squares over the four lengths; exact for consistent lengths). The velocity
estimate is J^+ l_dot from the measured length rates.

Position loop: W = Kp e + Kd e_dot + Ki int(e) + G, e = h_ref - h_est (m), W the Cartesian force (N) that
the actuators are to exert on the plate (:func:`pressfit.dynamics.actuators.distribute`), G the gravity
feed-forward (the Cartesian force that holds the moving parts, legs included, at the estimated pose:
G = V^T g(q), g Pinocchio's generalised gravity of the rigid-leg model, V its closed-loop velocities per
unit plate velocity; by virtual work, since A tau_a = V^T g in static equilibrium). G is recomputed only when
the estimate has moved more than ``GRAVITY_UPDATE_M`` (1 mm) from the pose it was last computed at
(:class:`PoseCache`): |dG/dh| is at most 58 N/m per axis over the workspace (finite differences at 30 random
poses), so the feed-forward is off by at most sqrt(3) * 58 N/m * 1 mm = 0.1 N (0.06% of the ~180 N weight
it carries), a fixed force error the integrator removes.

Force limiter (on the measured contact force F_c along +y, limit F_lim: the gains' ``force_limit_n``, or the
running segment's pin limit that a board's run sets in ``ForceLimitedController.force_limit_n``), both parts of
Figure 12:
* force reference clamp: in contact (F_c > 0) the vertical push of the loop beyond the feed-forward is
  clamped, (Kp e + Kd dh_ref/dt + Ki int(e))_y >= -F_lim, so in a steady contact F_c <= F_lim (in free motion
  the loop keeps its full authority); the integrator holds
  while clamped (anti-windup) and the damping -Kd dh_est/dt acts after the clamp (a clamped tool on an
  elastic contact would otherwise ring undamped);
* reference modification: the vertical reference is lifted by delta >= 0,
  d delta/dt = c (F_c - F_lim) while F_c > F_lim or delta > 0 (c in m/(s N)): the reference stops advancing
  and backs off while the force is over the limit, and catches up once it is below.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import pinocchio as pin

from pressfit import kinematics
from pressfit.description.cases import Controller, Simulation
from pressfit.description.machine import Machine
from pressfit.dynamics.actuators import distribution
from pressfit.dynamics.multibody import PoseCache, RigidLegModel
from pressfit.kinematics.profiles import quintic as _quintic
from pressfit.mechanics.condensed import condensed_plate_compliance


def _legs(machine: Machine, pose_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Leg lengths l_i (4,), m, and unit vectors e_i (4, 3) at one pose (equation 1)."""
    u = kinematics.leg_vectors(machine, pose_m)
    lengths = np.sqrt(np.einsum("ij,ij->i", u, u))
    return lengths, u / lengths[:, None]


def estimate_pose(machine: Machine, lengths_m: np.ndarray, guess_m: np.ndarray,
                  iterations: int = 2) -> tuple[np.ndarray, np.ndarray, float]:
    """Plate position (3,), m, whose leg lengths best fit ``lengths_m`` (4,), m (Gauss-Newton from
    ``guess_m``), the leg unit vectors there (4, 3) (rows of dl/dh) and the largest length residual (m).
    In Python floats (the 3 x 3 normal equations by the adjugate): at this size numpy's per-call overhead
    costs more than the arithmetic; the normal matrix is well conditioned wherever A is (singular poses are
    refused by :func:`pressfit.dynamics.actuators.distribution`)."""
    offsets = (machine.plate_offsets_m - machine.base_points_m).tolist()  # u_i = h + d_i - B_i (equation 1)
    measured = [float(x) for x in lengths_m]
    hx, hy, hz = (float(x) for x in guess_m)

    def legs() -> tuple[list, list]:
        rows, residuals = [], []
        for (dx, dy, dz), lm in zip(offsets, measured, strict=True):
            ux, uy, uz = hx + dx, hy + dy, hz + dz
            n = math.sqrt(ux * ux + uy * uy + uz * uz)
            rows.append((ux / n, uy / n, uz / n))
            residuals.append(n - lm)
        return rows, residuals

    e, r = legs()
    for _ in range(iterations):
        a00 = a01 = a02 = a11 = a12 = a22 = b0 = b1 = b2 = 0.0
        for (ex, ey, ez), ri in zip(e, r, strict=True):  # e^T e and e^T r
            a00 += ex * ex
            a01 += ex * ey
            a02 += ex * ez
            a11 += ey * ey
            a12 += ey * ez
            a22 += ez * ez
            b0 += ex * ri
            b1 += ey * ri
            b2 += ez * ri
        c00, c01, c02 = a11 * a22 - a12 * a12, a02 * a12 - a01 * a22, a01 * a12 - a02 * a11
        c11, c12, c22 = a00 * a22 - a02 * a02, a02 * a01 - a00 * a12, a00 * a11 - a01 * a01
        det = a00 * c00 + a01 * c01 + a02 * c02
        hx -= (c00 * b0 + c01 * b1 + c02 * b2) / det
        hy -= (c01 * b0 + c11 * b1 + c12 * b2) / det
        hz -= (c02 * b0 + c12 * b1 + c22 * b2) / det
        e, r = legs()
    return np.array([hx, hy, hz]), np.array(e), max(abs(x) for x in r)


def gravity_feedforward_n(rigid: RigidLegModel, pose_m: np.ndarray) -> np.ndarray:
    """G (3,), N: the Cartesian force the actuators must exert to hold the moving parts at ``pose_m`` (m)."""
    q = rigid.configuration_at(pose_m)
    jac = rigid.closure_jacobian(q)
    basis = np.zeros((rigid.model.nv, 3))
    basis[:3] = np.eye(3)  # the plate is unrotated at configuration_at: local = world axes
    basis[6:] = -np.linalg.lstsq(jac[:, 6:], jac[:, :3], rcond=None)[0]
    return basis.T @ pin.computeGeneralizedGravity(rigid.model, rigid.data, q)


GRAVITY_UPDATE_M = 1e-3  # the gravity feed-forward is recomputed when the estimate moved more than this, m
DEFLECTION_UPDATE_M = 1e-4  # the static deflection's compliance is recomputed beyond this, m (3.4% over 5 mm)


def static_deflection_columns(machine: Machine, rigid: RigidLegModel, pose_m: np.ndarray) -> np.ndarray:
    """The structure's quasi-static tool deflection at a pose, (3, 2), m: column 0 per newton of contact force
    along +y, column 1 under the moving parts' weight (the condensed compliance,
    :func:`pressfit.mechanics.condensed.condensed_plate_compliance`, under -G, G the Cartesian force that holds
    them: :func:`gravity_feedforward_n`). The legs' own bending under their weight is not in a plate load: the
    weight column is 12-14% short of the elastic model's static sag at four poses over the workspace
    (tests/dynamics/test_static_deflection.py); zero when the model has no gravity."""
    compliance = condensed_plate_compliance(machine, pose_m)[:3, :3]
    return np.column_stack([compliance[:, 1], compliance @ -gravity_feedforward_n(rigid, pose_m)])


class Shape(Protocol):
    """The time law of one straight segment: the fraction of it covered at time t from its start and its
    rate (1/s), e.g. :class:`pressfit.kinematics.profiles.SCurve`."""

    def fraction(self, t_s: float) -> tuple[float, float]: ...


@dataclass(frozen=True)
class Trajectory:
    """Piecewise reference on straight segments through waypoints (m) with segment durations (s): each
    segment minimum-jerk (the quintic) unless ``shapes`` gives its time law (None: the quintic)."""

    waypoints_m: np.ndarray  # (k + 1, 3)
    durations_s: np.ndarray  # (k,)
    phases: tuple[str, ...]  # (k,) segment names
    shapes: tuple[Shape | None, ...] | None = None  # (k,) per segment, or None: all quintic
    ends_s: np.ndarray = field(init=False, repr=False, compare=False)  # (k,) cumulative durations, s

    def __post_init__(self) -> None:
        object.__setattr__(self, "ends_s", np.cumsum(self.durations_s))  # computed once: at() runs every step

    @classmethod
    def insertion(cls, sim: Simulation) -> Trajectory:
        """The scenario of Figures 13-14 (:class:`pressfit.description.cases.Simulation`)."""
        c = sim.contact
        above = np.array([c.pin_position_m[0], c.board_height_m + sim.approach_height_m, c.pin_position_m[1]])
        bottom = np.array([above[0], c.board_height_m - sim.interference_m, above[2]])
        points = np.array([sim.start_m, above, bottom, bottom, above, sim.end_m, sim.end_m])
        times = np.array([sim.move_time_s, sim.descent_time_s, sim.dwell_s, sim.descent_time_s, sim.move_time_s,
                          max(sim.settle_s, 1e-9)])
        return cls(points, times, ("approach", "descent", "dwell", "retract", "move", "settle"))

    @property
    def duration_s(self) -> float:
        return float(self.durations_s.sum())

    def segment(self, t_s: float) -> int:
        """Index of the segment running at time ``t_s`` (the last one after the end)."""
        return min(int(np.searchsorted(self.ends_s, t_s, side="right")), len(self.durations_s) - 1)

    def at(self, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Reference position (m) and velocity (m/s) at ``t_s`` (s)."""
        k = self.segment(t_s)
        t0 = float(self.ends_s[k - 1]) if k else 0.0
        delta = self.waypoints_m[k + 1] - self.waypoints_m[k]
        shape = self.shapes[k] if self.shapes is not None else None
        if shape is not None:
            s, rate = shape.fraction(t_s - t0)
            return self.waypoints_m[k] + s * delta, rate * delta
        s, ds = _quintic((t_s - t0) / self.durations_s[k])
        return self.waypoints_m[k] + s * delta, ds / self.durations_s[k] * delta


@dataclass
class ForceLimitedController:
    """Figure 12's controller (module docstring); state: estimate, integral, reference lift delta."""

    machine: Machine
    rigid: RigidLegModel
    gains: Controller
    limiter: bool
    estimate_m: np.ndarray
    integral_m_s: np.ndarray = field(default_factory=lambda: np.zeros(3))
    lift_m: float = 0.0
    clamped: bool = False
    estimate_residual_m: float = 0.0
    pinv: np.ndarray = field(default_factory=lambda: np.zeros((4, 3)))  # A^+ at the estimate
    null: np.ndarray = field(default_factory=lambda: np.zeros(4))  # v_p at the estimate
    gravity: PoseCache = field(init=False)
    deflection: PoseCache = field(init=False)
    force_limit_n: float = field(init=False)  # the insertion limit in force (N): the gains' unless a run sets it

    def __post_init__(self) -> None:
        self.force_limit_n = self.gains.force_limit_n
        self.gravity = PoseCache(lambda pose: gravity_feedforward_n(self.rigid, pose), GRAVITY_UPDATE_M)
        self.deflection = PoseCache(lambda pose: static_deflection_columns(self.machine, self.rigid, pose),
                                    DEFLECTION_UPDATE_M)

    def tool_estimate_m(self, contact_force_n: float) -> np.ndarray:
        """The position the loop acts on (3,), m: the pose estimate, plus with ``deflection_compensation`` the
        structure's predicted static deflection under the weight and the measured contact force (N, +y)."""
        if not self.gains.deflection_compensation:
            return self.estimate_m
        columns = self.deflection(self.estimate_m)
        return self.estimate_m + columns[:, 0] * contact_force_n + columns[:, 1]

    def command(self, lengths_m: np.ndarray, rates_m_per_s: np.ndarray, reference: tuple[np.ndarray, np.ndarray],
                contact_force_n: float, dt_s: float) -> np.ndarray:
        """The Cartesian force W (3,), N, from the measured lengths (m) and rates (m/s), the reference
        (position m, velocity m/s) and the measured contact force (N); advances the loop states by dt_s."""
        g = self.gains
        self.estimate_m, jac, self.estimate_residual_m = estimate_pose(self.machine, lengths_m, self.estimate_m,
                                                                       g.estimator_iterations)
        self.pinv, self.null = distribution(jac)
        velocity = self.pinv.T @ rates_m_per_s  # J^+ = (A^+)^T, J = dl/dh = A^T
        target, target_velocity = reference
        target = target + np.array([0.0, self.lift_m, 0.0])
        error = target - self.tool_estimate_m(contact_force_n)
        pid = g.kp_n_per_m * error + g.kd_n_s_per_m * target_velocity + g.ki_n_per_m_s * self.integral_m_s
        self.clamped = self.limiter and contact_force_n > 0.0 and pid[1] < -self.force_limit_n
        if self.clamped:
            pid[1] = -self.force_limit_n
            error[1] = 0.0  # anti-windup: the vertical integrator holds while clamped
        pid -= g.kd_n_s_per_m * velocity  # damping acts outside the clamp: a clamped contact stays damped
        self.integral_m_s = self.integral_m_s + dt_s * error
        if self.limiter and (contact_force_n > self.force_limit_n or self.lift_m > 0.0):
            self.lift_m = max(0.0, self.lift_m + dt_s * g.backoff_m_per_s_n * (contact_force_n - self.force_limit_n))
        if g.gravity_compensation:
            pid = pid + self.gravity(self.estimate_m)
        return pid
