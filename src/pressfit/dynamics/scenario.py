r"""The one scenario engine: the checks a plan passes before a run, the step loop that runs it on any dynamics
model, and the figures of a pin's insertion. :mod:`pressfit.dynamics.insertion` (one pin, ``[simulation]``) and
:mod:`pressfit.dynamics.cycle` (a board, ``[cycle]``) plan their scenario with these checks and run it here.

Plan (refused with one line naming the key, :class:`pressfit.errors.ModelFileError`): the preload in force mode;
start, end and the planned path within the joint limits (closed-form inverse kinematics, the path sampled every
``PATH_SAMPLE_M``); the preload alone within the drives' limit (max |V a| over the path); the explicit step stable
for the position loop and the closures' Baumgarte corrector (:func:`step_stability`); a hydraulic oil column
integrable at the step on a model that steps it explicitly; on an elastic model the step at most
``MAX_STEP_FRACTION`` of the first mode's period on the path.

Run (:func:`run_plan`): the model named by the plan's settings (:func:`pressfit.dynamics.machine.registry.model_kind`)
is built at the start state and stepped once per time step towards the reference under the running segment's
insertion force limit; the run stops through :class:`pressfit.dynamics.series.Guard`.
"""

from __future__ import annotations

import math
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from threadpoolctl import threadpool_limits
from tqdm import tqdm

from pressfit import kinematics
from pressfit.description.cases import NOT_OBJECTIVE_LIMITS, Case, Simulation
from pressfit.description.machine import ForceSource, Machine
from pressfit.dynamics import drives as drive_kinds
from pressfit.dynamics.contact import contact_stiffness_bound_n_per_m
from pressfit.dynamics.control import Trajectory
from pressfit.dynamics.drives.steps import hydraulic_step_refusal
from pressfit.dynamics.machine.flexible import MAX_STEP_FRACTION, first_mode_hz
from pressfit.dynamics.machine.registry import model_kind
from pressfit.dynamics.multibody import RigidLegModel
from pressfit.dynamics.series import Guard, ScenarioPlan
from pressfit.errors import (
    ConvergenceError,
    DriveStepError,
    ModelFileError,
    PressfitError,
    UnreachablePoseError,
    format_violation,
)
from pressfit.mechanics.preload import self_stress_forces_n

SETTLING_BAND = 0.02  # settling: the contact force within 2% of its value at the end of the dwell
SETTLING_HOLD = 0.25  # ... and inside that band over at least the last quarter of the dwell, else "did not settle"
COMPLETION_FRACTION = 0.9  # pressed: the settled force reaches 90% of the target force (pin_figures)
MAX_STEPS = 1_000_000  # refused above: ~15 min per run at ~0.8 ms per step, a 250 MB series
WARN_STEPS = 100_000  # warned above: more than a minute or two per run
MIN_SEGMENT_STEPS = 10  # every segment of the reference spans at least this many steps
PATH_SAMPLE_M = 5e-4  # spacing of the planned-path samples checked against the joint limits, m
STABILITY_FRACTION = 0.5  # the explicit step is refused beyond this fraction of the stability limit


def refuse(case: Case, key: str, expected: str) -> ModelFileError:
    return ModelFileError(case.path, key, expected)


def planned_path(trajectory: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Points of the planned path every ``PATH_SAMPLE_M`` along each straight segment (n, 3), m, and the index of
    the segment of each point (the minimum-jerk reference moves on the segment between its waypoints)."""
    points, segments = [], []
    for k in range(len(trajectory.durations_s)):
        a, b = trajectory.waypoints_m[k], trajectory.waypoints_m[k + 1]
        n = max(2, int(np.ceil(np.linalg.norm(b - a) / PATH_SAMPLE_M)) + 1)
        points.append(a + np.linspace(0.0, 1.0, n)[:, None] * (b - a))
        segments.append(np.full(n, k))
    return np.concatenate(points), np.concatenate(segments)


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
    (:func:`pressfit.dynamics.drives.steps.hydraulic_step_refusal`; nothing to check for other drives, or on an
    elastic model, which steps the column implicitly)."""
    reason = hydraulic_step_refusal(machine, waypoints_m, path_m, model_kind(sim.model).elastic, sim.time_step_s)
    if reason:
        raise refuse(case, key, reason)


def check_limits_offered(case: Case, sim: Simulation) -> None:
    """Torsion and bending limits (``NOT_OBJECTIVE_LIMITS`` of ``[simulation.limits]``) only on a model whose leg
    couples are objective (its class's ``objective_couples``: the elastic model's sections; the rigid-leg model's
    couples are a statically indeterminate minimum-norm split that is not mirror-objective)."""
    bad = [k for k in NOT_OBJECTIVE_LIMITS if getattr(sim.limits, k) is not None]
    if bad and not model_kind(sim.model).objective_couples:
        raise refuse(case, f"[simulation.limits] {bad[0]}", f"no {bad[0]} limit with model = \"{sim.model}\" (the "
                     "rigid-leg model's leg couples are statically indeterminate: a minimum-norm split that is not "
                     "mirror-objective); use model = \"flexible\" (the elastic model's sections) or check them "
                     "statically in [envelope]")


def check_model_step(case: Case, machine: Machine, sim: Simulation, waypoints_m: np.ndarray, key: str) -> None:
    """On an elastic model (the flexible machine) the step must be at most ``MAX_STEP_FRACTION`` of the first
    mode's period (:mod:`pressfit.dynamics.machine.flexible`) at every pose the scenario visits, not only at the
    start pose the model is built at: the first mode spans 13-46 Hz over the workspace. Checked at the waypoints
    ``waypoints_m`` (n, 3), m, and the midpoints of the segments between them (the stiffest pose of the shipped
    path lies inside its first segment, 0.06% above its end). Nothing to check on the rigid model."""
    if not model_kind(sim.model).elastic:
        return
    points = np.unique(np.asarray(waypoints_m, dtype=float), axis=0)
    poses = np.concatenate([points, 0.5 * (waypoints_m[1:] + waypoints_m[:-1])])
    frequencies = first_mode_hz(machine, poses)
    worst = int(np.argmax(frequencies))
    bound = MAX_STEP_FRACTION / frequencies[worst]
    if sim.time_step_s > bound:
        where = ", ".join(f"{c:.4g}" for c in poses[worst])
        raise refuse(case, key, f"at most {MAX_STEP_FRACTION:g} of the flexible machine's first period on the "
                     f"planned path: {bound:.4g} s ({frequencies[worst]:.4g} Hz at ({where}) m, "
                     f"{frequencies.min():.4g} Hz at the softest pose), got {sim.time_step_s:g} s")



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
        raise refuse(case, key, f"|a4| max|v_p| at most {drive_limit(drives)}: a4 = {a4:g} N with "
                     f"max|v_p| = {vp:.4g} over the planned path commands {peak:.4g} N from the preload alone")
    raise refuse(case, key, f"max |V a| at most {drive_limit(drives)}: the amplitudes "
                 f"({', '.join(f'{a:g}' for a in amplitudes)}) N command {peak:.4g} N over the planned path from "
                 "the preload alone")


def drive_limit(drives: drive_kinds.Drive) -> str:
    """The drives' force limit and the key that sets it, for messages ("the drives' [actuator] force_limit_n =
    1000 N")."""
    key = getattr(drives, "force_limit_key", ForceSource.force_limit_key)
    return f"the drives' {key} = {drives.force_limit_n:g} N"




def require_reachable_pose(case: Case, machine: Machine, pose: np.ndarray, key: str, what: str) -> None:
    try:
        kinematics.require_reachable(machine, pose)
    except UnreachablePoseError as exc:
        reasons = "; ".join(format_violation(*v) for v in exc.violations)
        raise refuse(case, key, f"{what} within the joint limits: pose ({', '.join(f'{c:.6g}' for c in pose)}) m "
                     f"breaks {reasons}") from None



def check_steps(case: Case, sim: Simulation, rigid: RigidLegModel, poses_m: np.ndarray,
                 table: str = "simulation") -> None:
    """The explicit step against the position loop (PD gains plus the contact's steepest slope,
    :func:`pressfit.dynamics.contact.contact_stiffness_bound_n_per_m`, and its damping on the
    plate's lightest apparent mass at the poses ``poses_m`` (n, 3), m, the waypoints) and the Baumgarte corrector
    (m = 1, k = omega_b^2, c = 2 omega_b): refused beyond ``STABILITY_FRACTION`` of the stability limit
    (:func:`step_stability`), the margin left for the drives' lag and the sampled estimator the index does not see;
    the errors name ``table``'s keys."""
    dt, g, c = sim.time_step_s, sim.controller, sim.contact
    omega = sim.baumgarte_rad_per_s
    if step_stability(1.0, omega**2, 2.0 * omega, dt) > STABILITY_FRACTION:
        bound = math.sqrt(4 + 4 * STABILITY_FRACTION) - 2  # (omega dt)^2 + 4 omega dt = 4 STABILITY_FRACTION
        raise refuse(case, f"[{table}] baumgarte_rad_per_s", f"omega_b dt at most {bound:.3g} (the explicit "
                     f"corrector is stable below 2 sqrt(2) - 2 = 0.83), got {omega:g} rad/s x time_step_s "
                     f"{dt:g} s = {omega * dt:.3g}")
    mass = min(apparent_mass_kg(rigid, p) for p in poses_m)
    stiffness = g.kp_n_per_m + contact_stiffness_bound_n_per_m(c)
    damping = g.kd_n_s_per_m + c.damping_n_s_per_m
    index = step_stability(mass, stiffness, damping, dt)
    if index > STABILITY_FRACTION:
        raise refuse(case, f"[{table}] time_step_s", f"a step the position loop is stable with: (k dt^2 / m + "
                     f"2 c dt / m) / 4 = {index:.3g} > {STABILITY_FRACTION:g} (semi-implicit Euler is stable below 1) "
                     f"with k = kp_n_per_m + the contact's steepest slope (its pins summed) = {stiffness:.4g} N/m, "
                     f"c = kd_n_s_per_m + the "
                     f"contact damping = {damping:.4g} N s/m, m = {mass:.4g} kg the plate's lightest apparent mass, "
                     f"dt = {dt:g} s: reduce time_step_s or the [{table}.controller] gains")


def run_plan(case: Case, machine: Machine, plan: ScenarioPlan, drives: drive_kinds.Drive, limiter: bool,
             progress: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Run a validated plan on its model (``plan.simulation.model``, :func:`model_kind`): the series (one row per
    step, :func:`pressfit.dynamics.series.series_columns`), the segment index of each row and, on an elastic model,
    the section resultants. The step loop: per step k (ending at t = (k + 1) dt) the reference and the running
    segment's force limit (and, with ``plan.contact_params``, its contact: the model's ``params``, a fresh copy at
    each board position, whose segments share it: the joint's state, ``kernels.contact_advance``), one model step;
    the model's failures become the guard's one-line errors."""
    kind, trajectory, guard = model_kind(plan.simulation.model), plan.trajectory, Guard(case, machine, plan)
    times = plan.simulation.time_step_s * np.arange(1, plan.steps + 1)
    ref_position, ref_velocity = trajectory.sample(times)
    running = trajectory.segments(times)
    limits = plan.force_limits_n[running]  # the running segment's insertion limit
    contacts = plan.contact_params
    one_thread = getattr(kind, "one_blas_thread", False)
    with threadpool_limits(limits=1, user_api="blas") if one_thread else nullcontext():
        model = kind(case, machine, plan, drives, limiter, guard)
        for k in tqdm(range(plan.steps), desc="simulate", unit="step", disable=not progress, mininterval=0.5):
            t = float(times[k])
            if contacts and (k == 0 or contacts[running[k]] is not contacts[running[k - 1]]):
                model.params = contacts[running[k]].copy()  # a board position's own joint, fresh: its state
            try:
                model.step(k, t, (ref_position[k], ref_velocity[k]), float(limits[k]))
            except UnreachablePoseError as exc:  # the estimate (feed-forward, compliance) left the workspace
                raise guard.diverged(t, f"the pose estimate left the reachable set: {exc}") from None
            except ConvergenceError as exc:
                raise guard.diverged(t, f"the {plan.simulation.model} model's step failed: {exc}") from None
            except DriveStepError as exc:
                raise guard.drive_failed(t, exc) from None
        rows, sections = model.rows()
    return rows, trajectory.segments(times - 1e-12), sections


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


@dataclass(frozen=True, kw_only=True)
class PinFigures:
    """The figures of one pin's insertion (:func:`pin_figures`), rows counted in the window it was given."""

    first_contact: int | None  # the first row in contact (force > 0), None without contact
    peak: int  # the row of the peak contact force
    peak_n: float
    overshoot_n: float  # over the force limit, >= 0
    steady_n: float  # at the end of the dwell
    settling_s: float | None  # settling_time_s; None: it did not settle (note)
    settled_row: int | None
    target_n: float
    completed: bool
    note: str  # why it did not complete, "" when it did
    lateral_m: float | None  # the tool's (x, z) against the pin's at the first contact, m


def pin_figures(time_s: np.ndarray, force_n: np.ndarray, tool_xz_m: np.ndarray, dwell: np.ndarray,
                pin_xz_m: np.ndarray, target_n: float, limit_n: float) -> PinFigures:
    """One pin's insertion over a window of rows (time s, contact force N, the tool's (x, z) (n, 2), m), its dwell
    ``dwell`` (row indices in the window): the first contact, the peak and its overshoot over ``limit_n``, the
    steady force at the end of the dwell, the settling (:func:`settling_time_s`) and whether the insertion
    completed (settled at ``COMPLETION_FRACTION`` of ``target_n`` or more), and the lateral error at first contact."""
    touching = np.flatnonzero(force_n > 0.0)
    first = int(touching[0]) if touching.size else None
    peak, steady = int(np.argmax(force_n)), float(force_n[dwell[-1]])
    settling, settled_row, why = settling_time_s(time_s, force_n, dwell)
    completed = settling is not None and steady >= COMPLETION_FRACTION * target_n
    if settling is not None and not completed:
        why = (f"the steady contact force {steady:.4g} N is below {100 * COMPLETION_FRACTION:g}% of the target "
               f"{target_n:.4g} N")
    return PinFigures(first_contact=first, peak=peak, peak_n=float(force_n[peak]),
                      overshoot_n=float(max(force_n[peak] - limit_n, 0.0)), steady_n=steady, settling_s=settling,
                      settled_row=settled_row, target_n=target_n, completed=bool(completed),
                      note=why if not completed else "",
                      lateral_m=float(np.linalg.norm(tool_xz_m[first] - pin_xz_m)) if first is not None else None)
