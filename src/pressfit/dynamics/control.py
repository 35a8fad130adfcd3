r"""Figure 12's force-limited position control: pose estimate from the actuator lengths, a Cartesian PID
position loop, a force-limiting loop on the measured contact force, and the reference trajectory.

Estimate (forward kinematics of the redundant set): Gauss-Newton on the n leg lengths l_i(h) = |h + d_i - B_i|
(equation 1), h <- h - J^+ (l(h) - l_measured), J = dl/dh (rows e_i, equations 2-3), a few iterations from
the last estimate (least squares over the n lengths; exact for consistent lengths). The velocity
estimate is J^+ l_dot from the measured length rates.

Position loop: W = Kp e + Kd e_dot + Ki int(e) + G, e = h_ref - h_est (m), W the Cartesian force (N) that
the actuators are to exert on the plate (:func:`pressfit.dynamics.actuators.distribute`), G the gravity
feed-forward (the Cartesian force that holds the moving parts, legs included, at the estimated pose:
G = V^T g(q), g the generalised gravity of the rigid-leg model, V its closed-loop velocities per unit plate
velocity; by virtual work, since A tau_a = V^T g in static equilibrium; computed as minus the machine's weight as a
plate force in closed form, :func:`pressfit.dynamics.leg_weight.weight_force_n`). G is recomputed only when
the estimate has moved more than ``GRAVITY_UPDATE_M`` (1 mm) from the pose it was last computed at
(:class:`PoseCache`): |dG/dh| is at most 17 N/m per axis over the workspace (finite differences at 30 random
poses, measured 16.4 N/m with the stem as a rod of fixed length; 55 N/m with the old exposed-length stems), so the
feed-forward is off by at most sqrt(3) * 17 N/m * 1 mm = 0.03 N (0.02% of the 180-233 N weight it carries), a
fixed force error the integrator removes.

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

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from pressfit import kinematics
from pressfit.description.cases import Controller, Simulation
from pressfit.description.machine import Machine
from pressfit.dynamics import kernels
from pressfit.dynamics.actuators import singular_error
from pressfit.dynamics.leg_weight import weight_force_n, weight_sag_m
from pressfit.dynamics.multibody import PoseCache, RigidLegModel, path_nodes
from pressfit.errors import PreloadError
from pressfit.kinematics.profiles import quintic as _quintic
from pressfit.mechanics.condensed import condensed_plate_compliance


def _legs(machine: Machine, pose_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Leg lengths l_i (n,), m, and unit vectors e_i (n, 3) at one pose (equation 1)."""
    u = kinematics.leg_vectors(machine, pose_m)
    lengths = np.sqrt(np.einsum("ij,ij->i", u, u))
    return lengths, u / lengths[:, None]


def estimate_pose(machine: Machine, lengths_m: np.ndarray, guess_m: np.ndarray,
                  iterations: int = 2) -> tuple[np.ndarray, np.ndarray, float]:
    """Plate position (3,), m, whose leg lengths best fit ``lengths_m`` (n,), m (Gauss-Newton from
    ``guess_m``), the leg unit vectors there (n, 3) (rows of dl/dh) and the largest length residual (m)
    (:func:`pressfit.dynamics.kernels.gauss_newton`: the 3 x 3 normal equations by the adjugate; the normal
    matrix is well conditioned wherever A is, singular poses are refused by
    :func:`pressfit.dynamics.actuators.distribution`)."""
    pose, units = np.array(guess_m, dtype=float), np.empty((len(machine.legs), 3))
    residual = kernels.gauss_newton(_offsets(machine), np.asarray(lengths_m, dtype=float), pose, int(iterations),
                                    units)
    return pose, units, residual


def _offsets(machine: Machine) -> np.ndarray:
    """d_i - B_i (n, 3), m: u_i = h + d_i - B_i (equation 1)."""
    return np.ascontiguousarray(machine.plate_offsets_m - machine.base_points_m, dtype=float)


def gravity_feedforward_n(rigid: RigidLegModel, pose_m: np.ndarray, check_reach: bool = True) -> np.ndarray:
    """G (..., 3), N: the Cartesian force the actuators must exert to hold the moving parts at reachable poses
    ``pose_m`` (..., 3), m, under the rigid-leg model's gravity: minus the machine's weight as a plate force in closed
    form (:func:`pressfit.dynamics.leg_weight.weight_force_n`), which by virtual work is V^T g(q) of the model (module
    doc; equal to Pinocchio's generalised gravity projected on the plate translations to 1e-15 relative,
    tests/dynamics/test_leg_weight.py). ``check_reach`` False: the poses are not checked (a running controller's
    estimate, whose plate pose the run's guard checks)."""
    h = kinematics.require_all_reachable(rigid.machine, pose_m) if check_reach else np.asarray(pose_m, dtype=float)
    return -weight_force_n(rigid.machine, h, np.asarray(rigid.model.gravity.linear))


GRAVITY_UPDATE_M = 1e-3  # the gravity feed-forward is recomputed when the estimate moved more than this, m
# The static deflection's columns are recomputed with their pose gradient beyond this, m, and extrapolated to
# first order in between (DeflectionCache): over 40 random poses of the workspace, 2 mm away in the infinity
# norm, the extrapolation is off by at most 1.5e-4 of the compliance's largest entry (holding the value instead:
# 9e-4 at 0.1 mm, 1.9e-2 at 2 mm), tests/dynamics/test_static_deflection.py
DEFLECTION_UPDATE_M = 2e-3
DEFLECTION_GRADIENT_STEP_M = 1e-4  # central differences of the compliance (error ~ h^2: 1e-8 relative)
COLUMNS_BLOCK = 1024  # poses per batched call of linearised_columns (7168 closed-form poses: bounded work arrays)


def _gravity_on(rigid: RigidLegModel) -> bool:
    """Whether the rigid-leg model has gravity (a model without it has no weight to sag under)."""
    return bool(np.any(np.asarray(rigid.model.gravity.linear) != 0.0))


def static_deflection_columns(machine: Machine, rigid: RigidLegModel, pose_m: np.ndarray) -> np.ndarray:
    """The structure's quasi-static tool deflection at a pose, (3, 2), m: column 0 per newton of contact force
    along +y (the condensed compliance, :func:`pressfit.mechanics.condensed.condensed_plate_compliance`), column 1
    under the machine's own weight at that pose (:func:`pressfit.dynamics.leg_weight.weight_sag_m`: the condensed
    compliance times the weight as a plate wrench, the legs' cardan forces and their clamped bending between the
    cardans included; within 0.2% of the elastic model's static sag, tests/dynamics/test_leg_weight.py); zero when
    the model ``rigid`` has no gravity."""
    compliance = condensed_plate_compliance(machine.sensed_view, pose_m)
    sag = weight_sag_m(machine, pose_m, compliance) if _gravity_on(rigid) else np.zeros(3)
    return np.column_stack([compliance[:3, 1], sag])


def linearised_columns(machine: Machine, poses_m: np.ndarray, gravity: bool) -> tuple[np.ndarray, np.ndarray]:
    """The deflection rows (c0, c1) (k, 2, 3) at reachable poses (k, 3), m, and their gradient (k, 2, 3, 3) in the
    pose, per m (central differences: batched calls of the closed forms at seven poses each, ``COLUMNS_BLOCK`` poses
    at a time; the six about a pose need not be reachable: a pose within the step of a joint limit has its gradient
    too)."""
    h = DEFLECTION_GRADIENT_STEP_M * np.eye(3)
    centres = kinematics.require_all_reachable(machine, np.reshape(poses_m, (-1, 3)))
    rows, gradients = np.empty((len(centres), 2, 3)), np.empty((len(centres), 2, 3, 3))
    for start in range(0, len(centres), COLUMNS_BLOCK):
        block = slice(start, start + COLUMNS_BLOCK)
        flat = (centres[block, None, :] + np.vstack([np.zeros((1, 3)), h, -h])).reshape(-1, 3)  # 7 per pose
        compliance = condensed_plate_compliance(machine.sensed_view, flat)
        c0 = compliance[:, :3, 1]
        c1 = weight_sag_m(machine, flat, compliance, check_reach=False) if gravity else np.zeros_like(c0)
        seven = np.stack([c0, c1], axis=1).reshape(-1, 7, 2, 3)
        rows[block] = seven[:, 0]
        gradients[block] = np.moveaxis((seven[:, 1:4] - seven[:, 4:7]) / (2.0 * DEFLECTION_GRADIENT_STEP_M), 1, -1)
    return rows, gradients


@dataclass(kw_only=True)
class DeflectionCache:
    """The deflection columns as rows (c0, c1) (2, 3) at a pose (m) (:func:`static_deflection_columns`): ``rows``
    and their pose ``gradient`` (2, 3, 3), per m, computed at ``pose_m`` and refreshed (:meth:`refresh`) where the
    pose moved more than ``DEFLECTION_UPDATE_M`` (infinity norm) from it; a call extrapolates them to first order
    to the pose asked (:func:`pressfit.dynamics.kernels.extrapolated`, which the compiled controller and rigid step
    call themselves) and leaves them in ``value``. ``gravity`` False: no weight (c1 = 0). ``nodes_m`` (k, 3): poses
    where the rows and gradients are computed beforehand in one batched call (a planned path's,
    :func:`pressfit.dynamics.multibody.path_nodes`): a stale cache takes the nearest node within
    ``DEFLECTION_UPDATE_M`` (the same bound), and computes at the pose only where there is none."""

    machine: Machine
    gravity: bool = True
    nodes_m: np.ndarray | None = None
    pose_m: np.ndarray | None = None
    rows: np.ndarray | None = None
    gradient: np.ndarray | None = None
    value: np.ndarray | None = None
    _nodes: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False)  # rows, gradients at nodes_m
    _node: int = field(default=0, repr=False)  # the last node taken: where the next search starts

    def __post_init__(self) -> None:
        if self.nodes_m is not None:
            self.nodes_m = np.ascontiguousarray(self.nodes_m, dtype=float)
            self._nodes = linearised_columns(self.machine, self.nodes_m, self.gravity)

    def refresh(self, pose_m: np.ndarray) -> None:
        """Rows and gradient for ``pose_m`` (m): kept while it is within ``DEFLECTION_UPDATE_M`` of ``pose_m``."""
        if self.pose_m is not None and not kernels.moved(pose_m, self.pose_m, DEFLECTION_UPDATE_M):
            return
        node = -1 if self.nodes_m is None else kernels.nearest(self.nodes_m, pose_m, DEFLECTION_UPDATE_M, self._node)
        if node >= 0:
            self._node = node
            self.pose_m, self.rows, self.gradient = self.nodes_m[node], *(a[node] for a in self._nodes)
        else:
            self.pose_m = np.array(pose_m, dtype=float)
            rows, gradient = linearised_columns(self.machine, self.pose_m[None], self.gravity)
            self.rows, self.gradient = rows[0], gradient[0]

    def __call__(self, pose_m: np.ndarray) -> np.ndarray:
        self.refresh(pose_m)
        self.value = np.empty((2, 3))
        kernels.extrapolated(np.asarray(pose_m, dtype=float), self.pose_m, self.rows, self.gradient, self.value)
        return self.value


class Shape(Protocol):
    """The time law of one straight segment: the fraction of it covered at time t from its start and its
    rate (1/s), elementwise on an array of times, e.g. :class:`pressfit.kinematics.profiles.SCurve`."""

    def fraction(self, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...


@dataclass(frozen=True, kw_only=True)
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
        return cls(waypoints_m=points, durations_s=times,
                   phases=("approach", "descent", "dwell", "retract", "move", "settle"))

    @property
    def duration_s(self) -> float:
        return float(self.durations_s.sum())

    def segment(self, t_s: float) -> int:
        """Index of the segment running at time ``t_s`` (the last one after the end)."""
        return int(self.segments(np.array([t_s]))[0])

    def segments(self, times_s: np.ndarray) -> np.ndarray:
        """:meth:`segment` at each of ``times_s`` (n,), s."""
        return np.minimum(np.searchsorted(self.ends_s, times_s, side="right"), len(self.durations_s) - 1)

    def at(self, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Reference position (m) and velocity (m/s) at ``t_s`` (s)."""
        position, velocity = self.sample(np.array([t_s]))
        return position[0], velocity[0]

    def sample(self, times_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reference positions (n, 3), m, and velocities (n, 3), m/s, at ``times_s`` (n,), s: the quintic on
        each segment, or the segment's shape (its ``fraction`` at each time from the segment's start)."""
        times_s = np.asarray(times_s, dtype=float)
        k = self.segments(times_s)
        local = times_s - np.where(k > 0, self.ends_s[k - 1], 0.0)
        profile, rate = _quintic(local / self.durations_s[k])
        rate = rate / self.durations_s[k]
        for j, shape in enumerate(self.shapes or ()):
            on = k == j
            if shape is not None and on.any():  # one call per segment, over all its times
                profile[on], rate[on] = shape.fraction(local[on])
        delta = self.waypoints_m[k + 1] - self.waypoints_m[k]
        return self.waypoints_m[k] + profile[:, None] * delta, rate[:, None] * delta


@dataclass(kw_only=True)
class ForceLimitedController:
    """Figure 12's controller (module docstring); state: estimate, integral, reference lift delta. Each
    :meth:`command` also leaves A^+ and the preload basis V at the estimate (``pinv``, ``null``) and the tensions
    -A^+ W + V a (``tension_n``, N, a = ``preload_n`` the n - 3 preload amplitudes; a4 v_p on the 4-UPU) that
    distribute its force W."""

    machine: Machine
    rigid: RigidLegModel
    gains: Controller
    limiter: bool
    estimate_m: np.ndarray
    preload_n: np.ndarray | None = None  # a (n - 3,), N; None: no preload
    path_m: np.ndarray | None = None  # (k, 3), m: the planned path, whose deflection columns are computed beforehand
    # at nodes DEFLECTION_UPDATE_M apart (DeflectionCache; the rigid scenario's); None: at the estimate, on demand
    integral_m_s: np.ndarray = field(default_factory=lambda: np.zeros(3))
    lift_m: float = 0.0
    clamped: bool = False
    estimate_residual_m: float = 0.0
    pinv: np.ndarray = field(init=False)  # A^+ (n, 3) at the estimate (n legs)
    null: np.ndarray = field(init=False)  # V (n, n - 3) at the estimate (v_p on the 4-UPU)
    units: np.ndarray = field(init=False)  # e_i (n, 3) at the estimate
    tension_n: np.ndarray = field(init=False)  # -A^+ W + V a (n,), N
    gravity: PoseCache = field(init=False)
    deflection: DeflectionCache = field(init=False)  # (2, 3) rows c0 (m/N), c1 (m) at the last pose asked:
    # with deflection_compensation the error is taken against the estimate + c0 F + c1 (kernels.control)
    force_limit_n: float = field(init=False)  # the insertion limit in force (N): the gains' unless a run sets it
    offsets_m: np.ndarray = field(init=False)  # d_i - B_i (n, 3), m
    _params: np.ndarray = field(init=False, repr=False)
    _force: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.force_limit_n = self.gains.force_limit_n
        self.gravity = PoseCache(function=lambda pose: gravity_feedforward_n(self.rigid, pose, check_reach=False),
                                 tolerance_m=GRAVITY_UPDATE_M)
        self.deflection = DeflectionCache(machine=self.machine, gravity=_gravity_on(self.rigid),
                                          nodes_m=None if self.path_m is None else path_nodes(self.path_m,
                                                                                               DEFLECTION_UPDATE_M))
        self.estimate_m = np.array(self.estimate_m, dtype=float)
        self.offsets_m = _offsets(self.machine)
        legs = len(self.offsets_m)
        self.preload_n = np.zeros(legs - 3) if self.preload_n is None else np.array(self.preload_n, dtype=float)
        if self.preload_n.shape != (legs - 3,):
            raise PreloadError(f"the controller takes {legs - 3} preload amplitude(s) (n - 3), got "
                               f"{self.preload_n.size}", self.machine.name, legs - 3)
        self.units, self.pinv = np.zeros_like(self.offsets_m), np.zeros_like(self.offsets_m)
        self.null, self.tension_n = np.zeros((legs, legs - 3)), np.zeros(legs)
        g = self.gains
        params = np.zeros(len(_PARAMS))
        params[list(_PARAMS)] = (g.kp_n_per_m, g.kd_n_s_per_m, g.ki_n_per_m_s, g.force_limit_n, g.backoff_m_per_s_n,
                                 float(self.limiter), float(g.gravity_compensation), GRAVITY_UPDATE_M,
                                 float(g.deflection_compensation), DEFLECTION_UPDATE_M)
        self._params, self._force = params, np.zeros(3)

    def command(self, lengths_m: np.ndarray, rates_m_per_s: np.ndarray, reference: tuple[np.ndarray, np.ndarray],
                contact_force_n: float, dt_s: float) -> np.ndarray:
        """The Cartesian force W (3,), N, from the measured lengths (m) and rates (m/s), the reference
        (position m, velocity m/s) and the measured contact force (N); advances the loop states by dt_s."""
        self.observe(lengths_m)
        return self.command_at_estimate(rates_m_per_s, reference, contact_force_n, dt_s)

    def observe(self, lengths_m: np.ndarray) -> None:
        """The pose estimate from the measured lengths (m): ``estimate_m``, ``units``, ``estimate_residual_m``."""
        self.estimate_residual_m = kernels.gauss_newton(self.offsets_m, np.asarray(lengths_m, dtype=float),
                                                        self.estimate_m, self.gains.estimator_iterations, self.units)

    def command_at_estimate(self, rates_m_per_s: np.ndarray, reference: tuple[np.ndarray, np.ndarray],
                            contact_force_n: float, dt_s: float) -> np.ndarray:
        """:meth:`command` with the estimate (``estimate_m``, ``units``) already taken from the lengths
        (:meth:`observe`, or :func:`pressfit.dynamics.kernels.rigid_post_step`)."""
        self._params[kernels.FORCE_LIMIT] = self.force_limit_n  # a run may set it per segment
        gravity, deflection = self.gravity, self.deflection
        if self.gains.gravity_compensation and gravity.value is None:
            gravity(self.estimate_m)
        if self.gains.deflection_compensation and deflection.rows is None:
            deflection.refresh(self.estimate_m)  # then kept while the kernel finds it fresh, extrapolated by it
        while True:
            status, self.lift_m, self.clamped, sigma = kernels.control(
                self._params, self.estimate_m, self.units, rates_m_per_s, reference[0], reference[1],
                float(contact_force_n), float(dt_s), self.integral_m_s, float(self.lift_m),
                *((gravity.pose_m, gravity.value) if gravity.value is not None else (_ZERO3, _ZERO3)),
                *((deflection.pose_m, deflection.rows, deflection.gradient) if deflection.rows is not None else
                  (_ZERO3, _ZERO23, _ZERO233)),
                self.pinv, self.null, self._force, self.tension_n, self.preload_n)
            if status == 1:  # the estimate moved past GRAVITY_UPDATE_M: refresh the feed-forward
                gravity(self.estimate_m)
            elif status == 3:  # past DEFLECTION_UPDATE_M: refresh the static deflection
                deflection.refresh(self.estimate_m)
            else:
                break
        if status == 2:
            raise singular_error(sigma)
        return self._force.copy()


_PARAMS = (kernels.KP, kernels.KD, kernels.KI, kernels.FORCE_LIMIT, kernels.BACKOFF, kernels.LIMITER, kernels.GRAVITY,
           kernels.GRAVITY_TOL, kernels.DEFLECTION, kernels.DEFLECTION_TOL)
_ZERO3, _ZERO23, _ZERO233 = np.zeros(3), np.zeros((2, 3)), np.zeros((2, 3, 3))
