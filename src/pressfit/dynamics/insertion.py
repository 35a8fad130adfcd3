r"""The insertion simulation of Figures 13-14: the closed-loop rigid-leg machine (Pinocchio constraint
dynamics, :mod:`pressfit.dynamics.multibody`) driven by one force-controlled actuator per leg
(:mod:`pressfit.dynamics.actuators`) under Figure 12's force-limited position control
(:mod:`pressfit.dynamics.control`), pressing a pin into a board (:mod:`pressfit.dynamics.contact`, the
machine's compliance in series at the tool, quasi-statically).

One time step dt (the controller runs every step, an ideal sampled controller at 1/dt):
measure the actuator lengths and rates and the contact force of the last step -> controller -> Cartesian force
W -> tensions N_cmd = -A^+ W + V a (a4 v_p on the 4-UPU; V the preload basis at the estimate, a the case's n - 3
preload amplitudes, none on 3 legs) -> first-order saturated drives -> joint forces (-N_i on the prismatic
joints, the contact force on the plate) -> one semi-implicit Euler step -> contact at the new position.
The contact force acts on the plate centre (the tool tip), +y.

Before a run (:func:`plan_scenario`) the case is refused (one line naming the key) when: a segment spans fewer
than ``MIN_SEGMENT_STEPS`` steps; the run would take more than ``MAX_STEPS`` steps; start, end, the approach
waypoint above the pin or the bottom of the descent is unreachable, or any point of the planned path (sampled
every ``PATH_SAMPLE_M``; the minimum-jerk reference moves on straight segments) breaks a joint limit (closed-form
inverse kinematics); start or end is not above the board face (the contact is the infinite plane y = h_b);
the preload alone saturates a drive (max |V a| over the path > the drives' limit; a preload on a 3-leg machine or
with another number of amplitudes than n - 3: PreloadError); the explicit step is
unstable for the position loop or the closures' Baumgarte corrector (:func:`step_stability`). During the run it
stops with one line naming the time and the likely keys when the state is not finite, the plate leaves the
reachable set, or the loop-closure drift exceeds ``MAX_CLOSURE_DRIFT_M``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from threadpoolctl import threadpool_limits
from tqdm import tqdm

from pressfit import kinematics
from pressfit.description.cases import Case, Simulation
from pressfit.description.machine import ForceSource, Machine
from pressfit.dynamics import drives as drive_kinds
from pressfit.dynamics import kernels
from pressfit.dynamics.contact import NO_TABLE, contact_force_n, contact_parameters
from pressfit.dynamics.control import (
    ForceLimitedController,
    PoseCache,
    Trajectory,
    estimate_pose,
)
from pressfit.dynamics.drives.base import DriveOverStep
from pressfit.dynamics.drives.steps import hydraulic_step_refusal
from pressfit.dynamics.machine.base import SECTION_COMPONENTS, SECTIONS, DriveInput, Energy
from pressfit.dynamics.machine.flexible import MAX_STEP_FRACTION, FlexibleMachine, first_mode_hz, leg_frame_loads
from pressfit.dynamics.multibody import RigidLegModel, rigid_leg_model
from pressfit.dynamics.play import DriveSide, LegPlay
from pressfit.errors import (
    ConvergenceError,
    DriveStepError,
    ModelFileError,
    PressfitError,
    UnreachablePoseError,
    format_violation,
)
from pressfit.mechanics.clearance import clearance_from_case, load_deflection
from pressfit.mechanics.preload import ActuatorPreload, self_stress_forces_n

# the machine's energies after the step and the Rayleigh damping's work over it (flexible model; 0 on the rigid one,
# which has no elastic energy either), the cardan plays' stored energy after the step and their dissipation over it
# (flexible model with clearance, :class:`PlayLedger`; 0 otherwise), the energy change of the step's stem
# re-placement (flexible model, :meth:`FlexibleMachine.replacement_energy_j`; 0 on the rigid one), J: the energy
# balance of :mod:`pressfit.dynamics.sizing`
ENERGY_COLUMNS = ("kinetic_energy_j", "potential_energy_j", "elastic_energy_j", "damping_work_j", "play_energy_j",
                  "play_dissipation_j", "stem_replacement_j")


def internal_columns(legs: int) -> tuple[str, ...]:
    """The internal force columns of an n-leg run: the preload amplitudes the delivered tensions carry
    (:func:`pressfit.dynamics.kernels.internal_forces`): ``internal_force_n`` (v_p . N) with one redundant leg,
    ``internal_force_n<3 + k>`` for amplitude k (of leg 3 + k) with more, none on 3 legs."""
    if legs - 3 == 1:
        return ("internal_force_n",)
    return tuple(f"internal_force_n{j + 1}" for j in range(3, legs))


def series_columns(legs: int) -> tuple[str, ...]:
    """The columns of an n-leg run's series (:class:`InsertionResult`), per-leg columns numbered 1 .. n."""
    names = [str(i + 1) for i in range(legs)]
    return ("time_s", "ref_x_m", "ref_y_m", "ref_z_m", "est_x_m", "est_y_m", "est_z_m", "plate_x_m", "plate_y_m",
            "plate_z_m", "tool_x_m", "tool_y_m", "tool_z_m", "contact_force_n", "depth_m",
            *(f"cmd_n{i}" for i in names), *(f"act_n{i}" for i in names), "reference_lift_m", "closure_drift_m",
            *(f"axial_n{i}" for i in names), *internal_columns(legs), "kinematic_x_m", "kinematic_y_m",
            "kinematic_z_m", *(f"length_m{i}" for i in names), *(f"rate_m_per_s{i}" for i in names), *ENERGY_COLUMNS)


def section_columns(legs: int) -> tuple[str, ...]:
    """The columns of an n-leg flexible run's section resultants (``sections.csv``)."""
    return ("time_s", *(f"leg{i + 1}_{s}_{c}" for i in range(legs) for s in SECTIONS for c in SECTION_COMPONENTS))


def leg_columns(columns: tuple[str, ...], prefix: str) -> list[int]:
    """The indices of the per-leg columns ``<prefix>1 .. <prefix>n`` in ``columns``, in leg order."""
    legs = sum(c.startswith("cmd_n") for c in columns)
    return [columns.index(f"{prefix}{i + 1}") for i in range(legs)]


MOVE_PHASES = ("approach", "move")  # the structure's deflection during the moves: these phases (summarise)
VIBRATION_WINDOW_S = 0.2  # residual vibration: the tool's peak-to-peak over the last 0.2 s of the final settle
KINEMATIC_ITERATIONS = 3  # Gauss-Newton iterations of the kinematic pose from the last row's
SETTLING_BAND = 0.02  # settling: the contact force within 2% of its value at the end of the dwell
SETTLING_HOLD = 0.25  # ... and inside that band over at least the last quarter of the dwell, else "did not settle"
COMPLETION_FRACTION = 0.9  # pressed: the settled force reaches 90% of the target force (summarise)
MAX_STEPS = 1_000_000  # refused above: ~15 min per run at ~0.8 ms per step, a 250 MB series
WARN_STEPS = 100_000  # warned above: more than a minute or two per run
MIN_SEGMENT_STEPS = 10  # every segment of the reference spans at least this many steps
PATH_SAMPLE_M = 5e-4  # spacing of the planned-path samples checked against the joint limits, m
MAX_CLOSURE_DRIFT_M = 2e-5  # the run stops when the loop closures open more than this (m; module docstring)
STABILITY_FRACTION = 0.5  # the explicit step is refused beyond this fraction of the stability limit
# the run stops when the tool goes deeper below the board face than this many times the commanded interference
# (the reference's deepest point): the contact law models the pin-board stack down to it, the board face is solid
MAX_DEPTH_FACTOR = 2.0
_CHUNK_ROWS = 4096  # the series grows by this many rows at a time
_REACH_CHECK_STEPS = 10  # the plate's joint limits are checked every this many steps (and at the last)
_CURVE_POINTS = 41  # load steps of the clearance load-deflection curve


@dataclass(frozen=True, kw_only=True)
class InsertionResult:
    """A simulated insertion (SI). ``series`` (n, len(columns)) holds one row per time step (``columns``:
    :func:`series_columns` of the machine's leg count):
    reference, estimated and rigid plate positions, tool tip (rigid + series deflection), contact force
    (+y on the tool) and interference, commanded and delivered actuator tensions, reference lift, closure
    drift, the legs' axial force at the plate cardan (:meth:`pressfit.dynamics.multibody.RigidLegModel.leg_loads`;
    its torsion and bending are left out: the rigid model's couples are not objective) and the internal force
    (the preload amplitudes, N, :func:`internal_columns`) of the delivered tensions, the kinematic pose, leg
    lengths and rates, and the energies
    (``ENERGY_COLUMNS``, J). ``summary`` is the JSON-ready digest (:func:`summarise`)."""

    limiter: bool
    series: np.ndarray
    columns: tuple[str, ...]
    phases: np.ndarray  # (n,) segment index of each row (see ``phase_names``)
    phase_names: tuple[str, ...]
    summary: dict[str, Any] = field(default_factory=dict)
    sections: np.ndarray | None = None  # (n, legs, 3, 6) flexible model: section resultants (section_columns)

    def column(self, name: str) -> np.ndarray:
        return self.series[:, self.columns.index(name)]


def _deflection(machine: Machine, case: Case, sim: Simulation, pin_pose: np.ndarray, columns: PoseCache
                ) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray]]]:
    """pose -> the tool's quasi-static deflection at the rigid pose as
    :func:`pressfit.dynamics.kernels.solve_contact` takes it: u = column F + sag under the contact force F (N, +y)
    and the moving parts' weight (column m/N and sag m, (3,) each:
    :func:`pressfit.dynamics.control.static_deflection_columns`), or, with ``clearance``, sag + the clearance
    model's load-deflection table at the pin (loads (n,), N; displacements (n, 3), m) for the contact force.
    ``columns``: the controller's cache of the columns (``ForceLimitedController.deflection``, rows c0, c1,
    extrapolated to first order from the pose where they were last computed, within ``DEFLECTION_UPDATE_M``),
    shared: the estimate and the rigid pose differ by the closure drift, so one update serves both."""
    if not sim.clearance:
        return lambda pose: (*columns(pose), NO_TABLE)
    params = contact_parameters(sim.contact)
    law_force = (contact_force_n(params, sim.interference_m) if params[kernels.LAW] == kernels.TABLE
                 else sim.contact.stiffness_n_per_m * sim.interference_m)
    limit = max(4.0 * sim.controller.force_limit_n, law_force)
    curve = load_deflection(machine, pin_pose, [0.0, 1.0, 0.0], np.linspace(0.0, limit, _CURVE_POINTS),
                            clearance_from_case(case, machine), ActuatorPreload.from_case(case.preload).a4,
                            unload=False)
    table = (np.ascontiguousarray(curve.loads_n, dtype=float),
             np.ascontiguousarray(curve.loading.displacement_m - curve.loading.displacement_m[0], dtype=float))
    zero = np.zeros(3)
    return lambda pose: (zero, columns(pose)[1], table)


@dataclass(frozen=True, kw_only=True)
class ScenarioPlan:
    """A validated scenario (:func:`plan_scenario`, or a board's :func:`pressfit.dynamics.cycle.plan_cycle`): its
    reference, the number of steps, the planned path samples (n, 3), m, the warnings to show before the run, the
    run's settings (``simulation``: time step, model, contact law, controller gains, start pose) and the insertion
    force limit of each segment of the reference (N; the controller's limiter uses the running segment's)."""

    trajectory: Trajectory
    steps: int
    path_m: np.ndarray
    warnings: tuple[str, ...]
    rigid: RigidLegModel
    simulation: Simulation
    force_limits_n: np.ndarray
    depth_limit_m: float = math.inf  # the run stops beyond this depth below the board face (MAX_DEPTH_FACTOR)
    table: str = "simulation"  # the case table whose keys the run's errors name: [simulation], a board's [cycle]


def _refuse(case: Case, key: str, expected: str) -> ModelFileError:
    return ModelFileError(case.path, key, expected)


def _path(trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Points of the planned path every ``PATH_SAMPLE_M`` along each straight segment (n, 3), m, and the index of
    the segment of each point (the minimum-jerk reference moves on the segment between its waypoints)."""
    points, segments = [], []
    for k in range(len(trajectory.durations_s)):
        a, b = trajectory.waypoints_m[k], trajectory.waypoints_m[k + 1]
        n = max(2, int(np.ceil(np.linalg.norm(b - a) / PATH_SAMPLE_M)) + 1)
        points.append(a + np.linspace(0.0, 1.0, n)[:, None] * (b - a))
        segments.append(np.full(n, k))
    return np.concatenate(points), np.concatenate(segments)


# the key that places each segment of the planned path (Trajectory.insertion's phases)
_SEGMENT_KEYS = ("[simulation] start_m", "[simulation] interference_m", "[simulation] interference_m",
                 "[simulation] interference_m", "[simulation] end_m", "[simulation] end_m")


def apparent_mass_kg(rigid: RigidLegModel, pose_m: np.ndarray) -> float:
    """The plate's smallest apparent translational mass (kg) at a pose: 1 / the largest eigenvalue of
    :func:`plate_mobility`."""
    return float(1.0 / np.linalg.eigvalsh(plate_mobility(rigid, pose_m)).max())


def plate_mobility(rigid: RigidLegModel, pose_m: np.ndarray) -> np.ndarray:
    """The plate's acceleration per unit plate force (3, 3), 1/kg, world axes, at a pose (constraint dynamics at
    rest, three unit forces, gravity's share removed; symmetrised): the inverse of its apparent mass matrix."""
    q, v = rigid.configuration_at(pose_m), np.zeros(rigid.model.nv)
    tau = np.zeros(rigid.model.nv)
    saved = rigid.data, rigid.constraint_datas  # scratch datas: the run's solver state stays untouched
    rigid.data, rigid.constraint_datas = rigid.model.createData(), pin.StdVec_RigidConstraintData()
    for cm in rigid.constraint_models:
        rigid.constraint_datas.append(cm.createData())
    pin.initConstraintDynamics(rigid.model, rigid.data, rigid.constraint_models, rigid.constraint_datas)
    try:
        rest = rigid.accelerations(q, v, tau)[:3]
        inverse = np.empty((3, 3))
        for j in range(3):
            tau[:] = 0.0
            tau[j] = 1.0  # N on the unrotated plate: world axes
            inverse[:, j] = rigid.accelerations(q, v, tau)[:3] - rest
    finally:
        rigid.data, rigid.constraint_datas = saved
    return 0.5 * (inverse + inverse.T)


def step_stability(mass_kg: float, stiffness_n_per_m: float, damping_n_s_per_m: float, dt_s: float) -> float:
    r"""Stability index of the semi-implicit Euler step for m x'' = -k x - c x' (derived: with a = k dt^2 / m,
    b = c dt / m the step's characteristic polynomial is z^2 - (2 - a - b) z + (1 - b), whose roots lie in the
    unit circle iff a > 0, 0 < b < 2 and a + 2 b < 4): returns (a + 2 b) / 4, stable below 1."""
    return (stiffness_n_per_m * dt_s**2 / mass_kg + 2.0 * damping_n_s_per_m * dt_s / mass_kg) / 4.0


def plan_scenario(case: Case, machine: Machine | None = None, preload_key: str = "[preload] a4_n") -> ScenarioPlan:
    """Validate the case's ``[simulation]`` before a run (module docstring; ModelFileError naming the key, the
    file and the limit) and return its plan. ``preload_key`` names where the preload came from."""
    sim = case.simulation
    if sim is None:
        raise PressfitError(f"{case.path}: the case has no [simulation] table")
    require_force_preload(case)
    machine = machine or case.machine()
    dt, board = sim.time_step_s, sim.contact.board_height_m
    for key in ("move_time_s", "descent_time_s", "dwell_s", "settle_s"):
        value = getattr(sim, key)
        if (value > 0 or key != "settle_s") and value < MIN_SEGMENT_STEPS * dt * (1 - 1e-9):
            raise _refuse(case, f"[simulation] {key}", f"at least {MIN_SEGMENT_STEPS} time steps "
                          f"({MIN_SEGMENT_STEPS * dt:g} s at time_step_s = {dt:g} s){' or 0' * (key == 'settle_s')}, "
                          f"got {value:g} s")
    trajectory = Trajectory.insertion(sim)
    steps = int(np.ceil(trajectory.duration_s / dt))
    if steps > MAX_STEPS:
        raise _refuse(case, "[simulation] time_step_s", f"a run of at most {MAX_STEPS} steps: time_step_s = {dt:g} s "
                      f"over the {trajectory.duration_s:g} s of move_time_s, descent_time_s, dwell_s and settle_s "
                      f"makes {steps} steps (use a larger time step or shorter segments)")
    for key, pose in (("start_m", sim.start_m), ("end_m", sim.end_m)):
        if not pose[1] > board:
            raise _refuse(case, f"[simulation] {key}", f"a pose above the board face (the contact is the plane y = "
                          f"[simulation.contact] board_height_m = {board:g} m), got y = {pose[1]:g} m")
    names = {1: ("[simulation] approach_height_m", "the approach waypoint above the pin"),
             2: ("[simulation] interference_m", "the bottom of the descent")}
    for k, pose in enumerate(trajectory.waypoints_m[:3]):
        key, what = names.get(k, ("[simulation] start_m", "the start pose"))
        _require_reachable(case, machine, pose, key, what)
    _require_reachable(case, machine, np.asarray(sim.end_m, float), "[simulation] end_m", "the end pose")
    path, segment = _path(trajectory)
    ok = kinematics.is_reachable(machine, path)
    if not ok.all():
        first = int(np.flatnonzero(~ok)[0])
        _require_reachable(case, machine, path[first], _SEGMENT_KEYS[segment[first]],
                           f"the planned path ({trajectory.phases[segment[first]]} segment)")
    free = np.isin(segment, [0, 4, 5])  # approach, move, settle: out of contact by design
    if np.any(path[free, 1] <= board):
        raise _refuse(case, "[simulation] start_m", "a planned approach and move above the board face")
    warnings = []
    check_preload(case, machine, drive_kinds.of(machine), path, preload_key)
    rigid = rigid_leg_model(machine, np.asarray(sim.start_m, float), sim.baumgarte_rad_per_s)
    _check_steps(case, sim, rigid, trajectory.waypoints_m[[0, 1, 5]])
    check_oil_column(case, machine, sim, trajectory.waypoints_m, path, "[simulation] time_step_s")
    check_flexible_step(case, machine, sim, trajectory.waypoints_m, "[simulation] time_step_s")
    if steps > WARN_STEPS:
        warnings.append(run_time_warning(steps, dt, trajectory.duration_s))
    return ScenarioPlan(trajectory=trajectory, steps=steps, path_m=path, warnings=tuple(warnings), rigid=rigid,
                        simulation=sim,
                        force_limits_n=np.full(len(trajectory.durations_s), sim.controller.force_limit_n),
                        depth_limit_m=MAX_DEPTH_FACTOR * sim.interference_m)


def run_time_warning(steps: int, dt_s: float, duration_s: float) -> str:
    return (f"{steps} time steps (time_step_s = {dt_s:g} s over {duration_s:g} s): expect about "
            f"{steps * 8e-4 / 60:.0f} min per run")


def require_force_preload(case: Case) -> None:
    """The simulated drives are force-controlled: the case's preload must be in force mode (a4_n, N)."""
    if case.preload.mode != "force":
        raise PressfitError(f"{case.path}: [preload] mode must be \"force\" (a4_n, N) for the force-controlled "
                            f"drives of the simulation, got \"{case.preload.mode}\"")


def check_oil_column(case: Case, machine: Machine, sim: Simulation, waypoints_m: np.ndarray, path_m: np.ndarray,
                     key: str) -> None:
    """A hydraulic drive's oil column must be integrable at the time step over the planned path
    (:func:`pressfit.dynamics.drives.steps.hydraulic_step_refusal`; nothing to check for other drives)."""
    reason = hydraulic_step_refusal(machine, waypoints_m, path_m, sim.model, sim.time_step_s)
    if reason:
        raise _refuse(case, key, reason)


def check_flexible_step(case: Case, machine: Machine, sim: Simulation, waypoints_m: np.ndarray, key: str) -> None:
    """On the flexible model the step must be at most ``MAX_STEP_FRACTION`` of the first mode's period
    (:mod:`pressfit.dynamics.machine.flexible`) at every pose the scenario visits, not only at the start pose the
    model is built at: the first mode spans 13-46 Hz over the workspace. Checked at the waypoints ``waypoints_m``
    (n, 3), m, and the midpoints of the segments between them (the stiffest pose of the shipped path lies inside
    its first segment, 0.06% above its end). Nothing to check on the rigid model."""
    if sim.model != "flexible":
        return
    points = np.unique(np.asarray(waypoints_m, dtype=float), axis=0)
    poses = np.concatenate([points, 0.5 * (waypoints_m[1:] + waypoints_m[:-1])])
    frequencies = np.array([first_mode_hz(machine, p) for p in poses])
    worst = int(np.argmax(frequencies))
    bound = MAX_STEP_FRACTION / frequencies[worst]
    if sim.time_step_s > bound:
        where = ", ".join(f"{c:.4g}" for c in poses[worst])
        raise _refuse(case, key, f"at most {MAX_STEP_FRACTION:g} of the flexible machine's first period on the "
                      f"planned path: {bound:.4g} s ({frequencies[worst]:.4g} Hz at ({where}) m, "
                      f"{frequencies.min():.4g} Hz at the softest pose), got {sim.time_step_s:g} s")


def preload_amplitudes_n(case: Case, machine: Machine) -> np.ndarray:
    """The case's preload amplitudes a (n - 3,), N, along the machine's preload basis (a4 on the 4-UPU; zeros when
    the case has no preload; :func:`check_preload` refuses a preload the machine cannot take)."""
    amplitudes = np.asarray(case.preload.amplitudes, dtype=float)
    return amplitudes if amplitudes.any() else np.zeros(machine.redundancy)


def without_preload(case: Case) -> Case:
    """The case with no preload (the preload's cost: the same scenario with a = 0)."""
    return case.model_copy(update={"preload": case.preload.model_copy(update={"a4_n": 0.0, "amplitudes_n": None})})


def check_preload(case: Case, machine: Machine, drives: drive_kinds.Drive, path_m: np.ndarray, key: str) -> None:
    """The preload alone must not saturate a drive anywhere on the planned path (n, 3), m: max |V a| at most the
    drives' limit (|a4| max |v_p| on the 4-UPU); a preload on a 3-leg machine, or with another number of
    amplitudes than n - 3, raises :class:`pressfit.errors.PreloadError`
    (:func:`pressfit.mechanics.preload.self_stress_forces_n`)."""
    amplitudes = np.asarray(case.preload.amplitudes, dtype=float)
    forces = self_stress_forces_n(machine, path_m, amplitudes[0] if amplitudes.size == 1 else amplitudes)
    peak = float(np.abs(forces).max())
    if peak <= drives.force_limit_n:
        return
    if machine.redundancy == 1:
        a4, vp = float(amplitudes[0]), float(np.abs(kinematics.preload_vector(machine, path_m)).max())
        raise _refuse(case, key, f"|a4| max|v_p| at most {drive_limit(drives)}: a4 = {a4:g} N with "
                      f"max|v_p| = {vp:.4g} over the planned path commands {peak:.4g} N from the preload alone")
    raise _refuse(case, key, f"max |V a| at most {drive_limit(drives)}: the amplitudes "
                  f"({', '.join(f'{a:g}' for a in amplitudes)}) N command {peak:.4g} N over the planned path from "
                  "the preload alone")


def drive_limit(drives: drive_kinds.Drive) -> str:
    """The drives' force limit and the key that sets it, for messages ("the drives' [actuator] force_limit_n =
    1000 N")."""
    key = getattr(drives, "force_limit_key", ForceSource.force_limit_key)
    return f"the drives' {key} = {drives.force_limit_n:g} N"


def _require_reachable(case: Case, machine: Machine, pose: np.ndarray, key: str, what: str) -> None:
    try:
        kinematics.require_reachable(machine, pose)
    except UnreachablePoseError as exc:
        reasons = "; ".join(format_violation(*v) for v in exc.violations)
        raise _refuse(case, key, f"{what} within the joint limits: pose ({', '.join(f'{c:.6g}' for c in pose)}) m "
                      f"breaks {reasons}") from None


def _check_steps(case: Case, sim: Simulation, rigid: RigidLegModel, poses_m: np.ndarray,
                 table: str = "simulation") -> None:
    """The explicit step against the position loop (PD gains plus the contact's stiffness and damping on the
    plate's lightest apparent mass at the poses ``poses_m`` (n, 3), m, the waypoints) and the Baumgarte corrector
    (m = 1, k = omega_b^2, c = 2 omega_b): refused beyond ``STABILITY_FRACTION`` of the stability limit
    (:func:`step_stability`), the margin left for the drives' lag and the sampled estimator the index does not see;
    the errors name ``table``'s keys."""
    dt, g, c = sim.time_step_s, sim.controller, sim.contact
    omega = sim.baumgarte_rad_per_s
    if step_stability(1.0, omega**2, 2.0 * omega, dt) > STABILITY_FRACTION:
        bound = math.sqrt(4 + 4 * STABILITY_FRACTION) - 2  # (omega dt)^2 + 4 omega dt = 4 STABILITY_FRACTION
        raise _refuse(case, f"[{table}] baumgarte_rad_per_s", f"omega_b dt at most {bound:.3g} (the explicit "
                      f"corrector is stable below 2 sqrt(2) - 2 = 0.83), got {omega:g} rad/s x time_step_s "
                      f"{dt:g} s = {omega * dt:.3g}")
    mass = min(apparent_mass_kg(rigid, p) for p in poses_m)
    fit = (c.fit_stiffness_n_per_m if c.fit == "linear" else c.fit_force_n / c.fit_depth_m) if c.law == "press_fit" \
        else 0.0
    stiffness, damping = g.kp_n_per_m + c.stiffness_n_per_m + fit, g.kd_n_s_per_m + c.damping_n_s_per_m
    index = step_stability(mass, stiffness, damping, dt)
    if index > STABILITY_FRACTION:
        raise _refuse(case, f"[{table}] time_step_s", f"a step the position loop is stable with: (k dt^2 / m + "
                      f"2 c dt / m) / 4 = {index:.3g} > {STABILITY_FRACTION:g} (semi-implicit Euler is stable below 1) "
                      f"with k = kp_n_per_m + the contact stiffness = {stiffness:.4g} N/m, c = kd_n_s_per_m + the "
                      f"contact damping = {damping:.4g} N s/m, m = {mass:.4g} kg the plate's lightest apparent mass, "
                      f"dt = {dt:g} s: reduce time_step_s or the [{table}.controller] gains")


def _diverged(case: Case, t: float, what: str, table: str) -> PressfitError:
    return PressfitError(f"{case.path}: the simulation diverged at t = {t:.4g} s ({what}); the planned path is "
                         f"reachable, so the likely keys are [{table}] time_step_s, the [{table}.controller] "
                         f"gains (kp_n_per_m, kd_n_s_per_m, ki_n_per_m_s, backoff_m_per_s_n) or [{table}] "
                         "baumgarte_rad_per_s")


def simulate_insertion(case: Case, limiter: bool = True, progress: bool = False) -> InsertionResult:
    """Run the case's ``[simulation]`` scenario, with or without the force limiter, on the case's model
    (``[simulation] model``: the rigid-leg model with the compliance in series, or the flexible machine)."""
    machine = case.machine()
    machine.mass.require_dynamics_inertia(machine.source)
    plan = plan_scenario(case, machine)
    drives = drive_kinds.of(machine)
    rows, phases, sections = run_plan(case, machine, plan, drives, limiter, progress)
    result = InsertionResult(limiter=limiter, series=rows, columns=series_columns(len(machine.legs)), phases=phases,
                             phase_names=plan.trajectory.phases, sections=sections)
    summary = summarise(result, case, drives)
    summary["warnings"] = [*plan.warnings, *summary["warnings"]]
    return dataclasses.replace(result, summary=summary)


def run_plan(case: Case, machine: Machine, plan: ScenarioPlan, drives: drive_kinds.Drive, limiter: bool,
             progress: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Run a validated plan on its model (``plan.simulation.model``): the series (one row per step,
    :func:`series_columns`), the segment index of each row and, with the flexible model, the section resultants."""
    run = _run_flexible if plan.simulation.model == "flexible" else _run_rigid
    return run(case, machine, plan, drives, limiter, progress)


class _Series:
    """The series' rows, grown in chunks; :meth:`add` appends a row with the kinematic pose (forward kinematics of
    the actuator lengths, Gauss-Newton from the last row's, :func:`pressfit.dynamics.control.estimate_pose`; the
    rigid loop fills :meth:`row` in place, its kinematic pose from its controller's estimate)."""

    def __init__(self, machine: Machine, steps: int, start_m: np.ndarray) -> None:
        self.machine, self.steps, self.kinematic = machine, steps, np.asarray(start_m, float).copy()
        self.width = len(series_columns(len(machine.legs)))
        self.chunks = [np.empty((min(steps, _CHUNK_ROWS), self.width))]

    def add(self, k: int, row: tuple, lengths: np.ndarray, rates: np.ndarray, energy: tuple) -> None:
        self.kinematic = estimate_pose(self.machine, lengths, self.kinematic, KINEMATIC_ITERATIONS)[0]
        if k // _CHUNK_ROWS == len(self.chunks):
            self.chunks.append(np.empty((min(self.steps - k, _CHUNK_ROWS), self.width)))
        self.chunks[-1][k % _CHUNK_ROWS] = (*row, *self.kinematic, *lengths, *rates, *energy)

    def row(self, k: int) -> np.ndarray:
        """Row k (the rows are filled in order) to fill in place; the kinematic pose is the caller's."""
        if k // _CHUNK_ROWS == len(self.chunks):
            self.chunks.append(np.empty((min(self.steps - k, _CHUNK_ROWS), self.width)))
        return self.chunks[-1][k % _CHUNK_ROWS]

    def rows(self) -> np.ndarray:
        return np.concatenate(self.chunks)


def _check_pose(case: Case, machine: Machine, k: int, steps: int, t: float, pose: np.ndarray, table: str) -> None:
    bad = [] if k % _REACH_CHECK_STEPS and k != steps - 1 else kinematics.violations(machine, pose) \
        if pose[1] > 0 else [(0, "y_h [m]", pose[1], "minimum 0")]
    if bad:
        raise _diverged(case, t, f"the plate left the reachable set at ({', '.join(f'{c:.4g}' for c in pose)})"
                        f" m: {format_violation(*bad[0])}", table)


def _drive_failed(case: Case, t: float, exc: DriveStepError) -> PressfitError:
    return PressfitError(f"{case.path}: the {exc} at t = {t:.4g} s (the machine file's [actuator.{exc.kind}] "
                         "table, or the scenario's speed and forces)")


def _check_depth(case: Case, plan: ScenarioPlan, depth_m: float, t: float) -> None:
    """A tool deeper below the board face than ``plan.depth_limit_m`` stops the run: never a result."""
    if depth_m > plan.depth_limit_m:
        raise PressfitError(f"{case.path}: the tool went {1e3 * depth_m:.4g} mm below the board face at t = {t:.4g} s, "
                            f"beyond the tolerance of {1e3 * plan.depth_limit_m:.4g} mm ({MAX_DEPTH_FACTOR:g} x the "
                            f"commanded interference_m): the board face is solid and the contact law models "
                            "the pin-board stack only down to the commanded interference, so the run is refused; "
                            f"the likely keys are the [{plan.table}.controller] gains, the segment times or the "
                            "drives")


def _drift_error(case: Case, drift: float, t: float, table: str) -> PressfitError:
    sim = case.simulation
    return PressfitError(f"{case.path}: the loop closures drifted open by {drift:.3g} m at t = {t:.4g} s, "
                         f"over the tolerance of {MAX_CLOSURE_DRIFT_M:g} m (the tool position is only as "
                         f"good as the closures): raise [{table}] baumgarte_rad_per_s (now "
                         f"{sim.baumgarte_rad_per_s:g} rad/s) or reduce time_step_s; if the motion itself "
                         f"diverged, the [{table}.controller] gains")


def _run_rigid(case: Case, machine: Machine, plan: ScenarioPlan, drives: drive_kinds.Drive, limiter: bool,
               progress: bool) -> tuple[np.ndarray, np.ndarray, None]:
    """The rigid-leg model, the compliance in series at the tool (module docstring). Per step: the controller at
    the estimate, the drives, one Pinocchio step, then one compiled kernel
    (:func:`pressfit.dynamics.kernels.rigid_post_step`) for the contact, the axial forces, the pose estimate of the
    new lengths (the next step's controller estimate and, continued to ``KINEMATIC_ITERATIONS``, the row's
    kinematic pose) and the row; the energies (``ENERGY_COLUMNS``) from the rigid model."""
    sim, trajectory, steps, rigid = plan.simulation, plan.trajectory, plan.steps, plan.rigid
    q, v, dt = rigid.reference_q.copy(), np.zeros(rigid.model.nv), sim.time_step_s
    ctrl = ForceLimitedController(machine=machine, rigid=rigid, gains=sim.controller, limiter=limiter,
                                  estimate_m=np.asarray(sim.start_m, float).copy(),
                                  preload_n=preload_amplitudes_n(case, machine))
    deflection = _deflection(machine, case, sim, trajectory.waypoints_m[2], ctrl.deflection)
    act_q, act_v = rigid.actuator_q, rigid.actuator_v
    ctrl.command(q[act_q], v[act_v], trajectory.at(0.0), 0.0, 0.0)
    drive = drives.initial_state(ctrl.tension_n.copy(), q[act_q])
    ctrl.observe(q[act_q])  # the first step's estimate (later ones: rigid_post_step's)
    times = dt * np.arange(1, steps + 1)
    ref_position, ref_velocity = trajectory.sample(times)
    limits = plan.force_limits_n[trajectory.segments(times)]  # the running segment's insertion limit
    phases = trajectory.segments(times - 1e-12)
    params = contact_parameters(sim.contact, machine)
    iterations = ctrl.gains.estimator_iterations
    columns = series_columns(len(machine.legs))
    post = np.array([columns.index(c) for c in ("plate_x_m", "tool_x_m", "contact_force_n", "depth_m",
                                                       "axial_n1", "kinematic_x_m", "length_m1", "rate_m_per_s1")])
    pre = np.array([columns.index(c) for c in ("time_s", "ref_x_m", "est_x_m", "cmd_n1", "act_n1",
                                               "reference_lift_m")]
                   + [columns.index("axial_n1") + len(machine.legs)])  # the internal forces follow the axial ones
    drift_column = columns.index("closure_drift_m")
    energy = slice(columns.index(ENERGY_COLUMNS[0]), columns.index(ENERGY_COLUMNS[-1]) + 1)
    series = _Series(machine, steps, sim.start_m)
    tau, contact_tau, u = np.zeros(rigid.model.nv), np.zeros(3), np.empty(3)
    column, sag, table = deflection(q[0:3])
    force, depth = kernels.solve_contact(params, sim.contact.board_height_m - q[1], 0.0, dt, column, sag, *table, u)
    contact_tau[:] = pin.Quaternion(q[3:7]).matrix().T @ np.array([0.0, force, 0.0])  # the plate's local frame
    lengths, rates = q[act_q], v[act_v]
    for k in tqdm(range(steps), desc="simulate", unit="step", disable=not progress, mininterval=0.5):
        t = float(times[k])
        ctrl.force_limit_n = float(limits[k])
        try:
            ctrl.command_at_estimate(rates, (ref_position[k], ref_velocity[k]), force, dt)
            command = ctrl.tension_n.copy()  # equation 5 at the estimate, plus the preload
            drive, tension = drives.step(drive, command, lengths, rates, dt)
            row = series.row(k)
            kernels.rigid_pre_step(row, t, ref_position[k], ctrl.lift_m, ctrl.estimate_m, command, tension, ctrl.null,
                                   tau, act_v, contact_tau, pre)
            previous = q
            q, v = rigid.step(q, v, tau, dt)
            column, sag, table = deflection(q[0:3])
            finite, force, depth, ctrl.estimate_residual_m = kernels.rigid_post_step(
                row, previous, q, v, rigid.data.lambda_c, act_q, act_v, params, depth, dt, column, sag, *table,
                ctrl.offsets_m, ctrl.estimate_m, ctrl.units, iterations, KINEMATIC_ITERATIONS, contact_tau, post,
                lengths, rates)
            if not finite:
                raise _diverged(case, t, "the state is not finite", plan.table)
            _check_depth(case, plan, depth, t)
            row[drift_column] = drift = rigid.closure_error_m()
            if drift > MAX_CLOSURE_DRIFT_M:
                raise _drift_error(case, drift, t, plan.table)
            _check_pose(case, machine, k, steps, t, q[0:3], plan.table)
            row[energy] = (*rigid.energy_j(q, v), 0.0, 0.0, 0.0, 0.0, 0.0)
        except UnreachablePoseError as exc:  # the estimate (feed-forward, compliance) left the workspace
            raise _diverged(case, t, f"the pose estimate left the reachable set: {exc}", plan.table) from None
        except DriveStepError as exc:
            raise _drive_failed(case, t, exc) from None
    return series.rows(), phases, None


def _run_flexible(case: Case, machine: Machine, plan: ScenarioPlan, drives: drive_kinds.Drive, limiter: bool,
                  progress: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_flexible_steps` with BLAS on one thread: its matrices are small (nv + 24 = 146), and OpenBLAS's
    default threads (one per core) cost 3.6 times the CPU time of the run on the shared 2-core machine
    (docs/benchmarks.md)."""
    with threadpool_limits(limits=1, user_api="blas"):
        return _flexible_steps(case, machine, plan, drives, limiter, progress)


def _flexible_steps(case: Case, machine: Machine, plan: ScenarioPlan, drives: drive_kinds.Drive, limiter: bool,
                    progress: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The flexible machine (:class:`pressfit.dynamics.machine.flexible.FlexibleMachine`, the machine file's
    ``[damping]``; with ``clearance`` the cardan plays between the drives and the legs,
    :mod:`pressfit.dynamics.play`, the drives' sensors zeroed at the start): the machine's drives on the actuator
    joints, stepped
    inside the flexible step's Newton at the mean rate of the step (implicit, so that an oil column is stable:
    ``FlexibleMachine.step``'s ``drive``; the ideal force drive, which ignores the travel, once per step), the
    contact force on the elastic tool point (the plate centre), evaluated
    at the end of each step and held over the next (as in the rigid model); no series compliance (it is in the
    model).
    Starts from the static equilibrium under gravity with the drives holding the start pose's lengths."""
    sim, trajectory, steps, rigid = plan.simulation, plan.trajectory, plan.steps, plan.rigid
    dt, preload = sim.time_step_s, preload_amplitudes_n(case, machine)
    params = contact_parameters(sim.contact, machine)  # once: a tabulated law's table costs a solve
    start = np.asarray(sim.start_m, float)
    plays = clearance_from_case(case, machine) if sim.clearance else None
    implicit = drives.follows_travel  # a drive whose tension follows its travel, stepped inside the step
    fm = FlexibleMachine(machine, start,  # its step: check_flexible_step
                         actuator_series_n_per_m=None if plays is None else 0.5 * plays.contact_stiffness_n_per_m,
                         drive_mass_on_legs=plays is None or not implicit)  # behind the plays: on the drive side
    try:
        state = fm.rest_state()
    except ConvergenceError as exc:
        series = ", with the plays' [clearance] contact_stiffness_n_per_m in series" if plays is not None else ""
        raise PressfitError(f"{case.path}: the flexible machine's rest state at [{plan.table}] start_m under gravity "
                            f"failed ({exc}): its legs{series} do not hold the weight") from None
    ctrl = ForceLimitedController(machine=machine, rigid=rigid, gains=sim.controller, limiter=limiter,
                                  estimate_m=start.copy())
    lengths, rates = fm.leg_lengths_m(state), fm.leg_rates_m_per_s(state)  # what the drives measure
    force = ctrl.command(lengths, rates, trajectory.at(0.0), 0.0, 0.0)
    tension = -ctrl.pinv @ force + ctrl.null @ preload
    play = None if plays is None else LegPlay(machine, plays, start, tension, fm.drive_mass_kg)  # zeroed here
    extension = np.zeros(len(machine.legs))
    side = DriveSide(length_m=lengths.copy(), rate_m_per_s=rates.copy(), acceleration_m_per_s2=np.zeros_like(rates))
    tool = fm.tool_point_m(state)
    ledger = None if play is None else PlayLedger(fm.leg_lengths_m(state), lengths, _side_kinetic_j(fm, side),
                                                  float(play.stored_energy_j(tool, extension).sum()))
    drive = drives.initial_state(tension, lengths)
    board, contact_force = sim.contact.board_height_m, 0.0
    depth = board - tool[1]
    series, phases = _Series(machine, steps, sim.start_m), np.empty(steps, dtype=int)
    placement, subtree = fm.section_state(state)  # per step; the section loads from them after the run (batched)
    placements, wrenches = np.empty((steps, *placement.shape)), np.empty((steps, *subtree.shape))
    wrench, no_axial, internal = np.zeros(6), (0.0,) * len(machine.legs), np.empty(machine.redundancy)
    for k in tqdm(range(steps), desc="simulate", unit="step", disable=not progress, mininterval=0.5):
        t = (k + 1) * dt
        reference = trajectory.at(t)
        ctrl.force_limit_n = plan.force_limits_n[trajectory.segment(t)]
        try:
            force = ctrl.command(drives.measure_lengths_m(lengths), rates, reference, contact_force, dt)
            command = -ctrl.pinv @ force + ctrl.null @ preload
            wrench[1] = contact_force
            replaced = fm.replacement_energy_j(state)  # the step re-places the stems first
            if not drives.follows_travel:  # its tension does not follow the travel: stepped once, held over the step
                drive, tension = drives.step(drive, command, lengths, rates, dt)
                state = fm.step(state, DriveInput.forces(tension), wrench, dt)
            else:
                stepped = DriveOverStep(drives, drive, command, lengths, dt)
                through, k_step = stepped, drives.step_stiffness_n_per_m(lengths)
                if play is not None:
                    through = play.over_step(stepped, tool, tension, k_step, side, dt)
                    k_step = through.tangent_n_per_m
                state = fm.step(state, DriveInput.forces(tension), wrench, dt, through, k_step)
                drive, tension = stepped.result
                if play is not None:
                    side = through.side
            if not (np.all(np.isfinite(state.q)) and np.all(np.isfinite(state.v))):
                raise _diverged(case, t, "the state is not finite", plan.table)
            drift = fm.closure_error(state)[0]
            if drift > MAX_CLOSURE_DRIFT_M:
                raise _drift_error(case, drift, t, plan.table)
            placements[k], wrenches[k] = fm.section_state(state)
            tool = fm.tool_point_m(state)
            _check_pose(case, machine, k, steps, t, tool, plan.table)
            previous, depth = depth, board - tool[1]
            _check_depth(case, plan, depth, t)
            contact_force = contact_force_n(params, depth, (depth - previous) / dt)
            legs_m = lengths = fm.leg_lengths_m(state)
            rates = fm.leg_rates_m_per_s(state)
            plays_j = (0.0, 0.0)
            if play is not None and implicit:  # the drives measure their own side of the plays
                lengths, rates = side.length_m, side.rate_m_per_s
                plays_j = ledger.step(tension, through.force_n, legs_m, lengths, _side_kinetic_j(fm, side),
                                      float(through.stored_energy_j().sum()))
            elif play is not None:  # a massless force drive: the legs' lengths less the plays' extension
                before, extension = extension, play.extension_m(tool, tension)
                lengths, rates = lengths - extension, rates - (extension - before) / dt
                plays_j = ledger.step(tension, tension, legs_m, lengths, _side_kinetic_j(fm, side),
                                      float(play.stored_energy_j(tool, extension).sum()))
            kernels.internal_forces(ctrl.null, tension, internal)
            series.add(k, (t, *reference[0] + [0.0, ctrl.lift_m, 0.0], *ctrl.estimate_m, *tool, *tool,
                           contact_force, depth, *command, *tension, ctrl.lift_m, drift, *no_axial,
                           *internal), lengths, rates,
                       (*_energies(fm.energy(state), state.damping_work_j, _side_kinetic_j(fm, side)), *plays_j,
                        replaced))
        except UnreachablePoseError as exc:
            raise _diverged(case, t, f"the pose estimate left the reachable set: {exc}", plan.table) from None
        except ConvergenceError as exc:
            raise _diverged(case, t, f"the flexible model's step failed: {exc}", plan.table) from None
        except DriveStepError as exc:
            raise _drive_failed(case, t, exc) from None
        phases[k] = trajectory.segment(t - 1e-12)
    sections = leg_frame_loads(fm.section_wrenches_from(placements, wrenches), machine.cardan_axes)[0]
    rows = series.rows()
    rows[:, leg_columns(series_columns(len(machine.legs)), "axial_n")] = sections[:, :, 2, 0]  # plate
    return rows, phases, sections


def _side_kinetic_j(fm: FlexibleMachine, side: DriveSide) -> float:
    """The kinetic energy of the drives' reflected masses behind the plays, 1/2 m_d |l_d'|^2, J (constant without
    the plays: ``side`` keeps its start there)."""
    return 0.5 * fm.drive_mass_kg * float(side.rate_m_per_s @ side.rate_m_per_s)


class PlayLedger:
    r"""The cardan plays' energy account over a flexible run's steps (the ``play_energy_j`` and
    ``play_dissipation_j`` columns, J): what the drives do on their side of the plays minus what reaches the legs.

    Over step k the drives' tensions D_k (the ``act_n`` columns, held over the step) do -D_k . dl_d on their side,
    l_d the drives' lengths (the ``length_m`` columns: what the sensors read); the plays' forces f_k (the tension
    the legs carry at the step's end, where the flexible step evaluates them) do -f_k . dq_a on the legs, q_a the
    legs' lengths between the cardan centres. Between the two sit the plays, of stored energy V
    (:meth:`pressfit.dynamics.play.LegPlay.stored_energy_j`), and the drives' reflected masses m_d (an electric
    drive behind the plays), of kinetic energy K_side = 1/2 m_d |l_d'|^2 (in the ``kinetic_energy_j`` column).
    The plays' dissipation over the step is what is left of the drives' work after the legs, the masses and the
    plays have taken theirs:

        P_k = -D_k . dl_d + f_k . dq_a - dK_side - dV
            = [f_k . dx - dV]  +  [(f_k - D_k) . dl_d - dK_side]     (x = q_a - l_d + x_0, the plays' extension)

    The first bracket is the plays' own: with the force held at its end value, sum_k f(x_k) (x_k - x_k-1) - dV
    = sum_k int_{x_k-1}^{x_k} (f(x_k) - f(x)) dx >= 0 for the monotone law, O(k dx^2) per step inside a contact
    (first order in the step), and on a crossing of the dead zone (a tension changing sign) about |f_k| 2 G: the
    massless drive side (an ideal force drive) crosses the gap 2 G at once under the drive's force and meets the
    contact with the work it did on the way -- the inelastic impact of a vanishing mass, a loss of the model
    whatever the step. The second bracket is the drive side's: the work of its net force on its mass minus its
    kinetic energy, generalised-alpha's energy error at rho_inf = ``DRIVE_SIDE_RHO_INF`` (0: the unresolved
    contact mode annihilated in a step, an inelastic impact, :mod:`pressfit.dynamics.play`); zero without a mass.
    The machine's own balance (:func:`pressfit.dynamics.sizing.energy_balance`) starts from -f_k . dq_a."""

    def __init__(self, legs_m: np.ndarray, drives_m: np.ndarray, side_j: float, stored_j: float) -> None:
        self.legs, self.drives = np.array(legs_m, float), np.array(drives_m, float)
        self.side_j, self.stored_j = float(side_j), float(stored_j)

    def step(self, drive_n: np.ndarray, play_n: np.ndarray, legs_m: np.ndarray, drives_m: np.ndarray,
             side_j: float, stored_j: float) -> tuple[float, float]:
        """The step to the legs' lengths q_a (n,), m, and the drives' l_d (n,), m, under the drives' tensions D
        (n,), N, and the plays' forces f (n,), N, to the drive side's kinetic energy and the plays' stored energy
        (J): (the stored energy, the step's dissipation P_k), J."""
        legs, drives = np.asarray(legs_m, float), np.asarray(drives_m, float)
        dissipation = (float(-np.asarray(drive_n, float) @ (drives - self.drives))
                       + float(np.asarray(play_n, float) @ (legs - self.legs))
                       - (side_j - self.side_j) - (stored_j - self.stored_j))
        self.legs, self.drives, self.side_j, self.stored_j = legs.copy(), drives.copy(), float(side_j), float(stored_j)
        return float(stored_j), dissipation


def _energies(energy: Energy, damping_work_j: float, drive_side_j: float = 0.0) -> tuple[float, float, float, float]:
    """Kinetic (plus ``drive_side_j``, the drives' reflected masses behind the plays), potential and elastic
    energy and the damping work, J."""
    kinetic = energy.kinetic_j + drive_side_j
    return kinetic, energy.potential_j, energy.elastic_j, damping_work_j


def settling_time_s(time_s: np.ndarray, force_n: np.ndarray, dwell: np.ndarray) -> tuple[float | None, int | None, str]:
    """The contact force's settling over the dwell (rows ``dwell``): the time (s) from the first contact
    (force > 0) until it enters, and stays in up to the end of the dwell, the band of +-``SETTLING_BAND`` around
    its value there; the row where it entered; and "" -- or (None, None, the reason) if it did not settle: no
    contact at the end of the dwell, or the force outside the band within the last ``SETTLING_HOLD`` of the dwell
    (a limit cycle, a contact lost and regained)."""
    end = int(dwell[-1])
    final = float(force_n[end])
    if not final > 0.0:
        return None, None, "no contact at the end of the dwell"
    touching = np.flatnonzero(force_n[:end + 1] > 0.0)
    outside = np.flatnonzero(np.abs(force_n[:end + 1] - final) > SETTLING_BAND * final)
    settled = max(int(outside[-1]) + 1 if outside.size else 0, int(touching[0]))
    hold = int(dwell[0]) + int(np.floor((1.0 - SETTLING_HOLD) * (dwell.size - 1)))
    if settled > hold:
        window = force_n[hold:end + 1]
        return None, None, (f"the contact force did not settle: {window.min():.4g} .. {window.max():.4g} N over the "
                            f"last {100 * SETTLING_HOLD:g}% of the dwell, outside +-{100 * SETTLING_BAND:g}% of "
                            f"{final:.4g} N")
    return float(time_s[settled] - time_s[touching[0]]), settled, ""


def _reversals_unseen(time_s: np.ndarray, tensions_n: np.ndarray) -> list[str]:
    """The rigid model's clearance is the load-deflection curve at the pin under the contact force: a leg whose
    tension changes sign during the run crosses its plays' gaps unseen (docs/dynamics.md, "Cardan play"). One
    warning naming the legs and the first time of each."""
    signs = np.sign(tensions_n)
    crossed = signs[1:] * signs[:-1] < 0  # (rows - 1, legs)
    flips = [(i, int(crossed[:, i].argmax()) + 1) for i in np.flatnonzero(crossed.any(0))]
    if not flips:
        return []
    legs = ", ".join(f"{i + 1} (first at t = {time_s[k]:.4g} s)" for i, k in flips)
    many = len(flips) > 1
    return [f"with clearance = true the tension of leg{'s' * many} {legs} change{'' if many else 's'} sign: the "
            "rigid model's clearance is the load-deflection curve at the pin under the contact force, so the lost "
            f"motion across {'their' if many else 'its'} cardan plays is not in this run (model = \"flexible\" has it)"]


def _columns(result: InsertionResult, prefix: str) -> np.ndarray:
    return result.series[:, leg_columns(result.columns, prefix)]


def _xyz(result: InsertionResult, prefix: str) -> np.ndarray:
    return result.series[:, [result.columns.index(f"{prefix}_{a}_m") for a in "xyz"]]


def summarise(result: InsertionResult, case: Case, drives: drive_kinds.Drive) -> dict[str, Any]:
    """Peak contact force and overshoot over the limit, insertion depth, the steady insertion force at the
    end of the dwell against the contact law at the depth reached, its settling time (:func:`settling_time_s`;
    None if it did not settle), whether the insertion completed (the force settled in contact at the end of the
    dwell at ``COMPLETION_FRACTION`` of the target force or more: the contact law at the commanded interference,
    or the force limit if lower with the limiter), tool positioning errors (lateral against the pin at the end of
    the dwell, 3D against ``end_m`` at the end; ``positioning_error_m`` is the larger), what happens after the
    dwell (``release_time_s``: from the end of the dwell until the contact force is zero, None if it never is;
    ``retract_tool_error_m``: the tool's 3D distance from the reference at the end of the retract, where the
    reference comes to rest above the pin), closure drift, actuator saturation time and fraction of the run,
    peak tensions, the peak |axial force| of each leg, the range of the internal forces (the preload amplitudes the
    delivered tensions carry, v_p . N on the 4-UPU, 0 on 3 legs). Every peak carries its time
    and plate pose (``<stem>_time_s``, ``<stem>_pose_m``; per leg for per-leg peaks). ``warnings``: saturation,
    an insertion that did not complete, a tool never released."""
    sim = case.simulation
    force, depth, t = result.column("contact_force_n"), result.column("depth_m"), result.column("time_s")
    dwell = np.flatnonzero(result.phases == result.phase_names.index("dwell"))
    last = int(dwell[-1])
    tool, plate, ref = _xyz(result, "tool"), _xyz(result, "plate"), _xyz(result, "ref")
    lateral = float(np.linalg.norm(tool[last, [0, 2]] - np.array(sim.contact.pin_position_m)))
    final = float(np.linalg.norm(tool[-1] - sim.end_m))
    legs = len(leg_columns(result.columns, "cmd_n"))
    internal = result.series[:, [result.columns.index(c) for c in internal_columns(legs)]]
    limit = sim.controller.force_limit_n
    settling, settled_row, why = settling_time_s(t, force, dwell)
    target = contact_force_n(sim.contact, sim.interference_m)
    target = min(target, limit) if result.limiter else target
    completed = settling is not None and force[last] >= COMPLETION_FRACTION * target
    if settling is not None and not completed:
        why = (f"the steady contact force {force[last]:.4g} N is below {100 * COMPLETION_FRACTION:g}% of the target "
               f"{target:.4g} N")
    released = np.flatnonzero(force[last + 1:] <= 0.0)
    release = int(released[0]) + last + 1 if released.size else None
    retract = np.flatnonzero(result.phases == result.phase_names.index("retract"))
    saturated = drives.saturated(_columns(result, "cmd_n")).any(axis=1)
    peak = int(np.argmax(force))
    tensions, axial = np.abs(_columns(result, "act_n")), np.abs(_columns(result, "axial_n"))
    warnings = []
    if saturated.any():
        warnings.append(f"the drives saturated (a command beyond {drive_limit(drives)})"
                        f" for {saturated.sum() * sim.time_step_s:g} s, {100 * saturated.mean():.3g}% of the run")
    if not completed:
        warnings.append(f"the insertion did not complete (the pin is not pressed): {why}")
    if release is None:
        warnings.append("the contact force never returned to zero after the dwell (the tool was not released)")
    if sim.clearance and sim.model == "rigid":
        warnings += _reversals_unseen(t, _columns(result, "act_n"))

    def where(stem: str, rows: Any) -> dict[str, Any]:
        return {f"{stem}_time_s": t[rows], f"{stem}_pose_m": plate[rows]}

    positioning_row = last if lateral >= final else len(t) - 1
    pin_xz = np.array(sim.contact.pin_position_m)
    touching = np.flatnonzero(force > 0.0)
    first = int(touching[0]) if touching.size else None
    dwell_lateral = np.linalg.norm(tool[dwell][:, [0, 2]] - pin_xz, axis=1)
    deflection = np.linalg.norm(tool - _xyz(result, "kinematic"), axis=1)
    moves = np.flatnonzero(np.isin(result.phases, [result.phase_names.index(p) for p in MOVE_PHASES]))
    move_row = int(moves[np.argmax(deflection[moves])]) if moves.size else None
    settle = np.flatnonzero(result.phases == result.phase_names.index("settle"))
    window = settle[t[settle] >= t[-1] - VIBRATION_WINDOW_S + 0.5 * sim.time_step_s] if sim.settle_s > 0 else settle[:0]
    tension_columns, rates = _columns(result, "act_n"), np.abs(_columns(result, "rate_m_per_s"))
    production = {
        "model": sim.model,
        "tool_lateral_error_at_first_contact_m": float(np.linalg.norm(tool[first, [0, 2]] - pin_xz))
        if first is not None else None,
        "first_contact_time_s": float(t[first]) if first is not None else None,
        "tool_lateral_error_dwell_max_m": float(dwell_lateral.max()),
        **where("tool_lateral_error_dwell_max", int(dwell[np.argmax(dwell_lateral)])),
        "max_move_deflection_m": float(deflection[move_row]) if move_row is not None else None,
        **(where("max_move_deflection", move_row) if move_row is not None else
           {"max_move_deflection_time_s": None, "max_move_deflection_pose_m": None}),
        "residual_vibration_m": float(np.ptp(tool[window], axis=0).max()) if window.size else None,
        "residual_vibration_window_s": float(t[-1] - t[window[0]] + sim.time_step_s) if window.size else None,
        "rms_actuator_tension_n": np.sqrt(np.mean(tension_columns**2, axis=0)),
        "peak_actuator_speed_m_per_s": rates.max(axis=0), **where("peak_actuator_speed", rates.argmax(axis=0)),
    }
    if result.sections is not None:  # the elastic model's objective couples (the rigid model has none)
        sec = result.sections
        torsion = np.abs(sec[..., 5])  # (n, leg, section)
        bending = np.hypot(sec[..., 3], sec[..., 4])
        peak_t, peak_b = torsion.max(axis=(0, 2)), bending.max(axis=(0, 2))
        production.update({
            "peak_leg_torsion_nm": peak_t, **where("peak_leg_torsion", torsion.max(axis=2).argmax(axis=0)),
            "peak_leg_bending_nm": peak_b, **where("peak_leg_bending", bending.max(axis=2).argmax(axis=0)),
            "peak_section_loads": [{s: {"axial_n": float(np.abs(sec[:, i, k, 0]).max()),
                                        "torsion_nm": float(torsion[:, i, k].max()),
                                        "bending_nm": float(bending[:, i, k].max())}
                                    for k, s in enumerate(SECTIONS)} for i in range(sec.shape[1])],
        })
    return {
        "case": case.name, "limiter": result.limiter, "force_limit_n": limit,
        "simulated_time_s": float(t[-1]), "time_step_s": sim.time_step_s,
        "peak_contact_force_n": float(force.max()), **where("peak_contact_force", peak),
        "overshoot_n": float(max(force.max() - limit, 0.0)), **where("overshoot", peak),
        "max_insertion_depth_m": float(depth.max()), "steady_insertion_force_n": float(force[last]),
        "steady_insertion_depth_m": float(depth[last]),
        "contact_law_at_steady_depth_n": contact_force_n(sim.contact, float(depth[last])),
        "settling_time_s": settling, "settling_band": SETTLING_BAND,
        **(where("settled", settled_row) if settled_row is not None else {"settled_time_s": None,
                                                                          "settled_pose_m": None}),
        "insertion_completed": bool(completed), "insertion_target_force_n": target,
        "insertion_note": why if not completed else "",
        "release_time_s": float(t[release] - t[last]) if release is not None else None,
        "retract_tool_error_m": float(np.linalg.norm(tool[retract[-1]] - ref[retract[-1]])) if retract.size else None,
        "tool_lateral_error_at_insertion_m": lateral, "tool_final_error_m": final,
        "positioning_error_m": max(lateral, final), **where("positioning_error", positioning_row),
        "max_closure_drift_m": float(result.column("closure_drift_m").max()),
        "closure_drift_tolerance_m": MAX_CLOSURE_DRIFT_M,
        "actuator_saturation_time_s": float(saturated.sum() * sim.time_step_s),
        "actuator_saturation_fraction": float(saturated.mean()),
        "peak_actuator_tension_n": tensions.max(axis=0), **where("peak_actuator_tension", tensions.argmax(axis=0)),
        "actuator_force_limit_n": drives.force_limit_n, "actuator_bandwidth_hz": drives.bandwidth_hz,
        "peak_leg_axial_force_n": axial.max(axis=0), **where("peak_leg_axial_force", axial.argmax(axis=0)),
        "commanded_preload_n": case.preload.a4_n,
        "commanded_preload_amplitudes_n": list(case.preload.amplitudes) if internal.size else [],
        "internal_force_range_n": [float(internal.min()), float(internal.max())] if internal.size else [0.0, 0.0],
        **production,
        "warnings": warnings,
    }
