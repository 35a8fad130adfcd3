r"""The insertion simulation of Figures 13-14: one pin pressed by the machine (the case's ``[simulation]``
model, :mod:`pressfit.dynamics.machine.registry`: the closed-loop rigid-leg machine with the compliance in series
at the tool, or the flexible machine) driven by one force-controlled actuator per leg
(:mod:`pressfit.dynamics.actuators`) under Figure 12's force-limited position control
(:mod:`pressfit.dynamics.control`), pressing a pin into a board (:mod:`pressfit.dynamics.contact`), on the
scenario engine (:mod:`pressfit.dynamics.scenario`).

One time step dt (the controller runs every step, an ideal sampled controller at 1/dt):
measure the actuator lengths and rates and the contact force of the last step -> controller -> Cartesian force
W -> tensions N_cmd = -A^+ W + V a (a4 v_p on the 4-UPU; V the preload basis at the estimate, a the case's n - 3
preload amplitudes, none on 3 legs) -> the drives -> joint forces (-N_i on the prismatic joints, the contact
force on the plate) -> one model step -> contact at the new position. The contact force acts on the plate centre
(the tool tip), +y.

Before a run (:func:`plan_scenario`) the case is refused (one line naming the key) when: a segment spans fewer
than ``MIN_SEGMENT_STEPS`` steps; the run would take more than ``MAX_STEPS`` steps; start, end, the approach
waypoint above the pin or the bottom of the descent is unreachable, or any point of the planned path (sampled
every ``PATH_SAMPLE_M``; the minimum-jerk reference moves on straight segments) breaks a joint limit (closed-form
inverse kinematics); start or end is not above the board face (the contact is the infinite plane y = h_b);
the preload alone saturates a drive (max |V a| over the path > the drives' limit; a preload on a 3-leg machine or
with another number of amplitudes than n - 3: PreloadError); the explicit step is
unstable for the position loop or the closures' Baumgarte corrector
(:func:`pressfit.dynamics.scenario.step_stability`). During the run it stops with one line naming the time and
the likely keys (:class:`pressfit.dynamics.series.Guard`) when the state is not finite, the plate leaves the
reachable set, or the loop-closure drift exceeds ``MAX_CLOSURE_DRIFT_M``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pressfit import kinematics
from pressfit.description.cases import Case
from pressfit.description.machine import Machine
from pressfit.dynamics import drives as drive_kinds
from pressfit.dynamics.contact import contact_force_n
from pressfit.dynamics.control import Trajectory
from pressfit.dynamics.machine.base import SECTIONS
from pressfit.dynamics.machine.registry import model_kind, require_model
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.dynamics.press_monitor import SUMMARY_KEYS, MonitorCurve, monitor_curve, stroke_rows
from pressfit.dynamics.scenario import (
    MAX_STEPS,
    MIN_SEGMENT_STEPS,
    SETTLING_BAND,
    WARN_STEPS,
    check_limits_offered,
    check_model_step,
    check_oil_column,
    check_preload,
    check_steps,
    drive_limit,
    pin_figures,
    planned_path,
    refuse,
    require_force_preload,
    require_reachable_pose,
    run_plan,
    run_time_warning,
)
from pressfit.dynamics.series import (
    MAX_CLOSURE_DRIFT_M,
    MAX_DEPTH_FACTOR,
    ScenarioPlan,
    internal_columns,
    leg_columns,
    series_columns,
)
from pressfit.errors import PressfitError

MOVE_PHASES = ("approach", "move")  # the structure's deflection during the moves: these phases (summarise)
VIBRATION_WINDOW_S = 0.2  # residual vibration: the tool's peak-to-peak over the last 0.2 s of the final settle


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
    monitor: MonitorCurve | None = None  # the press monitor's view of the stroke (:func:`insertion_monitor_curve`)

    def column(self, name: str) -> np.ndarray:
        return self.series[:, self.columns.index(name)]


# the key that places each segment of the planned path (Trajectory.insertion's phases)
_SEGMENT_KEYS = ("[simulation] start_m", "[simulation] interference_m", "[simulation] interference_m",
                 "[simulation] interference_m", "[simulation] end_m", "[simulation] end_m")


def plan_scenario(case: Case, machine: Machine | None = None, preload_key: str = "[preload] a4_n") -> ScenarioPlan:
    """Validate the case's ``[simulation]`` before a run (module docstring; ModelFileError naming the key, the
    file and the limit) and return its plan. ``preload_key`` names where the preload came from."""
    sim = case.simulation
    if sim is None:
        raise PressfitError(f"{case.path}: the case has no [simulation] table")
    require_model(case.path, "[simulation] model", sim.model)
    require_force_preload(case)
    check_limits_offered(case, sim)
    machine = machine or case.machine()
    dt, board = sim.time_step_s, sim.contact.board_height_m
    for key in ("move_time_s", "descent_time_s", "dwell_s", "settle_s"):
        value = getattr(sim, key)
        if (value > 0 or key != "settle_s") and value < MIN_SEGMENT_STEPS * dt * (1 - 1e-9):
            raise refuse(case, f"[simulation] {key}", f"at least {MIN_SEGMENT_STEPS} time steps "
                         f"({MIN_SEGMENT_STEPS * dt:g} s at time_step_s = {dt:g} s){' or 0' * (key == 'settle_s')}, "
                         f"got {value:g} s")
    trajectory = Trajectory.insertion(sim)
    steps = int(np.ceil(trajectory.duration_s / dt))
    if steps > MAX_STEPS:
        raise refuse(case, "[simulation] time_step_s", f"a run of at most {MAX_STEPS} steps: time_step_s = {dt:g} s "
                     f"over the {trajectory.duration_s:g} s of move_time_s, descent_time_s, dwell_s and settle_s "
                     f"makes {steps} steps (use a larger time step or shorter segments)")
    for key, pose in (("start_m", sim.start_m), ("end_m", sim.end_m)):
        if not pose[1] > board:
            raise refuse(case, f"[simulation] {key}", f"a pose above the board face (the contact is the plane y = "
                         f"[simulation.contact] board_height_m = {board:g} m), got y = {pose[1]:g} m")
    names = {1: ("[simulation] approach_height_m", "the approach waypoint above the pin"),
             2: ("[simulation] interference_m", "the bottom of the descent")}
    for k, pose in enumerate(trajectory.waypoints_m[:3]):
        key, what = names.get(k, ("[simulation] start_m", "the start pose"))
        require_reachable_pose(case, machine, pose, key, what)
    require_reachable_pose(case, machine, np.asarray(sim.end_m, float), "[simulation] end_m", "the end pose")
    path, segment = planned_path(trajectory)
    ok = kinematics.is_reachable(machine, path)
    if not ok.all():
        first = int(np.flatnonzero(~ok)[0])
        require_reachable_pose(case, machine, path[first], _SEGMENT_KEYS[segment[first]],
                               f"the planned path ({trajectory.phases[segment[first]]} segment)")
    free = np.isin(segment, [0, 4, 5])  # approach, move, settle: out of contact by design
    if np.any(path[free, 1] <= board):
        raise refuse(case, "[simulation] start_m", "a planned approach and move above the board face")
    warnings = []
    check_preload(case, machine, drive_kinds.of(machine), path, preload_key)
    rigid = rigid_leg_model(machine, np.asarray(sim.start_m, float), sim.baumgarte_rad_per_s)
    check_steps(case, sim, rigid, trajectory.waypoints_m[[0, 1, 5]])
    check_oil_column(case, machine, sim, trajectory.waypoints_m, path, "[simulation] time_step_s")
    check_model_step(case, machine, sim, trajectory.waypoints_m, "[simulation] time_step_s")
    if steps > WARN_STEPS:
        warnings.append(run_time_warning(steps, dt, trajectory.duration_s))
    return ScenarioPlan(trajectory=trajectory, steps=steps, path_m=path, warnings=tuple(warnings), rigid=rigid,
                        simulation=sim,
                        force_limits_n=np.full(len(trajectory.durations_s), sim.controller.force_limit_n),
                        depth_limit_m=MAX_DEPTH_FACTOR * sim.interference_m)


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
    monitor = insertion_monitor_curve(result, case, machine)
    summary.update({k: monitor.summary[k] for k in SUMMARY_KEYS})
    return dataclasses.replace(result, summary=summary, monitor=monitor)


def insertion_monitor_curve(result: InsertionResult, case: Case, machine: Machine) -> MonitorCurve:
    """The press monitor's view of the insertion's stroke (descent, dwell, retract:
    :func:`pressfit.dynamics.press_monitor.monitor_curve`) at the case's pin pose."""
    rows, end = stroke_rows(result.phases, result.phase_names)
    return monitor_curve(machine, case.simulation.contact, result.column("time_s")[rows],
                         result.column("depth_m")[rows], result.column("kinematic_y_m")[rows],
                         result.column("contact_force_n")[rows], end, where=str(case.path))


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


def _where(result: InsertionResult) -> Any:
    """(stem, rows) -> the time and plate pose of the rows as ``<stem>_time_s``, ``<stem>_pose_m``."""
    t, plate = result.column("time_s"), _xyz(result, "plate")

    def where(stem: str, rows: Any) -> dict[str, Any]:
        return {f"{stem}_time_s": t[rows], f"{stem}_pose_m": plate[rows]}

    return where


def summarise(result: InsertionResult, case: Case, drives: drive_kinds.Drive) -> dict[str, Any]:
    """Peak contact force and overshoot over the limit, insertion depth, the steady insertion force at the
    end of the dwell against the contact law at the depth reached, its settling time
    (:func:`pressfit.dynamics.scenario.settling_time_s`; None if it did not settle), whether the insertion completed
    (:func:`pressfit.dynamics.scenario.pin_figures`: the force settled in contact at the end of the
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
    tool, ref = _xyz(result, "tool"), _xyz(result, "ref")
    lateral = float(np.linalg.norm(tool[last, [0, 2]] - np.array(sim.contact.pin_position_m)))
    final = float(np.linalg.norm(tool[-1] - sim.end_m))
    legs = len(leg_columns(result.columns, "cmd_n"))
    internal = result.series[:, [result.columns.index(c) for c in internal_columns(legs)]]
    limit = sim.controller.force_limit_n
    target = contact_force_n(sim.contact, sim.interference_m)
    pin = pin_figures(t, force, tool[:, [0, 2]], dwell, np.array(sim.contact.pin_position_m),
                      min(target, limit) if result.limiter else target, limit)
    released = np.flatnonzero(force[last + 1:] <= 0.0)
    release = int(released[0]) + last + 1 if released.size else None
    retract = np.flatnonzero(result.phases == result.phase_names.index("retract"))
    saturated = drives.saturated(_columns(result, "cmd_n")).any(axis=1)
    tensions, axial = np.abs(_columns(result, "act_n")), np.abs(_columns(result, "axial_n"))
    where = _where(result)
    return {
        "case": case.name, "limiter": result.limiter, "force_limit_n": limit,
        "simulated_time_s": float(t[-1]), "time_step_s": sim.time_step_s,
        "peak_contact_force_n": pin.peak_n, **where("peak_contact_force", pin.peak),
        "overshoot_n": pin.overshoot_n, **where("overshoot", pin.peak),
        "max_insertion_depth_m": float(depth.max()), "steady_insertion_force_n": pin.steady_n,
        "steady_insertion_depth_m": float(depth[last]),
        "contact_law_at_steady_depth_n": contact_force_n(sim.contact, float(depth[last])),
        "settling_time_s": pin.settling_s, "settling_band": SETTLING_BAND,
        **(where("settled", pin.settled_row) if pin.settled_row is not None else {"settled_time_s": None,
                                                                                  "settled_pose_m": None}),
        "insertion_completed": pin.completed, "insertion_target_force_n": pin.target_n,
        "insertion_note": pin.note,
        "release_time_s": float(t[release] - t[last]) if release is not None else None,
        "retract_tool_error_m": float(np.linalg.norm(tool[retract[-1]] - ref[retract[-1]])) if retract.size else None,
        "tool_lateral_error_at_insertion_m": lateral, "tool_final_error_m": final,
        "positioning_error_m": max(lateral, final),
        **where("positioning_error", last if lateral >= final else len(t) - 1),
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
        **_production(result, sim, pin, dwell),
        "warnings": _warnings(result, sim, drives, saturated, pin, release),
    }


def _warnings(result: InsertionResult, sim: Any, drives: drive_kinds.Drive, saturated: np.ndarray, pin: Any,
              release: int | None) -> list[str]:
    """Saturation, an insertion that did not complete, a tool never released, and on a model without the plays
    (not elastic) with clearance, the legs whose tension changed sign (:func:`_reversals_unseen`)."""
    warnings = []
    if saturated.any():
        warnings.append(f"the drives saturated (a command beyond {drive_limit(drives)})"
                        f" for {saturated.sum() * sim.time_step_s:g} s, {100 * saturated.mean():.3g}% of the run")
    if not pin.completed:
        warnings.append(f"the insertion did not complete (the pin is not pressed): {pin.note}")
    if release is None:
        warnings.append("the contact force never returned to zero after the dwell (the tool was not released)")
    if sim.clearance and not model_kind(sim.model).elastic:
        warnings += _reversals_unseen(result.column("time_s"), _columns(result, "act_n"))
    return warnings


def _production(result: InsertionResult, sim: Any, pin: Any, dwell: np.ndarray) -> dict[str, Any]:
    """The production figures: the model, the tool's lateral error at first contact and over the dwell, the
    structure's largest deflection during the moves (tool - kinematic pose), the residual vibration over the last
    ``VIBRATION_WINDOW_S`` of the settle, the drives' RMS tension and peak speed and, on an elastic model, the
    legs' peak torsion and bending and the section loads."""
    t, tool, where = result.column("time_s"), _xyz(result, "tool"), _where(result)
    pin_xz = np.array(sim.contact.pin_position_m)
    first = pin.first_contact
    dwell_lateral = np.linalg.norm(tool[dwell][:, [0, 2]] - pin_xz, axis=1)
    deflection = np.linalg.norm(tool - _xyz(result, "kinematic"), axis=1)
    moves = np.flatnonzero(np.isin(result.phases, [result.phase_names.index(p) for p in MOVE_PHASES]))
    move_row = int(moves[np.argmax(deflection[moves])]) if moves.size else None
    settle = np.flatnonzero(result.phases == result.phase_names.index("settle"))
    window = settle[t[settle] >= t[-1] - VIBRATION_WINDOW_S + 0.5 * sim.time_step_s] if sim.settle_s > 0 else settle[:0]
    tension_columns, rates = _columns(result, "act_n"), np.abs(_columns(result, "rate_m_per_s"))
    production = {
        "model": sim.model,
        "tool_lateral_error_at_first_contact_m": pin.lateral_m,
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
    return production
