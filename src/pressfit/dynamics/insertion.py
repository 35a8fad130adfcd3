r"""The insertion simulation of Figures 13-14: the closed-loop rigid-leg machine (Pinocchio constraint
dynamics, :mod:`pressfit.dynamics.multibody`) driven by four force-controlled actuators
(:mod:`pressfit.dynamics.actuators`) under Figure 12's force-limited position control
(:mod:`pressfit.dynamics.control`), pressing a pin into a board (:mod:`pressfit.dynamics.contact`, the
machine's compliance in series at the tool, quasi-statically).

One time step dt (the controller runs every step, an ideal sampled controller at 1/dt):
measure the actuator lengths and rates and the contact force of the last step -> controller -> Cartesian force
W -> tensions N_cmd = -A^+ W + a4 v_p -> first-order saturated drives -> joint forces (-N_i on the prismatic
joints, the contact force on the plate) -> one semi-implicit Euler step -> contact at the new position.
The contact force acts on the plate centre (the tool tip), +y.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from tqdm import tqdm

from pressfit.description.cases import Case, Simulation
from pressfit.description.machine import Machine
from pressfit.dynamics.actuators import ForceActuators
from pressfit.dynamics.contact import ContactState, contact_force_n, solve_contact
from pressfit.dynamics.control import ForceLimitedController, PoseCache, Trajectory
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.errors import PressfitError
from pressfit.mechanics.clearance import clearance_from_case, load_deflection
from pressfit.mechanics.condensed import condensed_plate_compliance

LEGS = ("1", "2", "3", "4")
SERIES_COLUMNS = ("time_s", "ref_x_m", "ref_y_m", "ref_z_m", "est_x_m", "est_y_m", "est_z_m", "plate_x_m",
                  "plate_y_m", "plate_z_m", "tool_x_m", "tool_y_m", "tool_z_m", "contact_force_n", "depth_m",
                  *(f"cmd_n{i}" for i in LEGS), *(f"act_n{i}" for i in LEGS), "reference_lift_m", "closure_drift_m",
                  *(f"axial_n{i}" for i in LEGS), *(f"torsion_nm{i}" for i in LEGS), *(f"bending_nm{i}" for i in LEGS),
                  "internal_force_n")
SETTLING_BAND = 0.02  # settling: the contact force within 2% of its value at the end of the dwell
COMPLIANCE_UPDATE_M = 1e-4  # the plate compliance is recomputed when the rigid pose moved more than this, m
_CURVE_POINTS = 41  # load steps of the clearance load-deflection curve


@dataclass(frozen=True)
class InsertionResult:
    """A simulated insertion (SI). ``series`` (n, len(SERIES_COLUMNS)) holds one row per time step:
    reference, estimated and rigid plate positions, tool tip (rigid + series deflection), contact force
    (+y on the tool) and interference, commanded and delivered actuator tensions, reference lift, closure
    drift, the legs' axial force, torsion and bending at the plate cardan
    (:meth:`pressfit.dynamics.multibody.RigidLegModel.leg_loads`) and the internal force along v_p,
    v_p . N (N) of the delivered tensions. ``summary`` is the JSON-ready digest (:func:`summarise`)."""

    limiter: bool
    series: np.ndarray
    phases: np.ndarray  # (n,) segment index of each row (see ``phase_names``)
    phase_names: tuple[str, ...]
    summary: dict[str, Any] = field(default_factory=dict)

    def column(self, name: str) -> np.ndarray:
        return self.series[:, SERIES_COLUMNS.index(name)]


def _deflection(machine: Machine, case: Case, sim: Simulation, pin_pose: np.ndarray) -> Callable[
        [np.ndarray], Callable[[float], np.ndarray]]:
    """pose -> (F -> u): the tool's deflection u (3,), m, under the contact force F (N, +y) at the rigid pose."""
    if not sim.clearance:  # C varies by 3.4% over 5 mm at the pin: 0.07% error at the 0.1 mm update distance
        compliance = PoseCache(lambda pose: condensed_plate_compliance(machine, pose)[:3, 1], COMPLIANCE_UPDATE_M)
        return lambda pose: (lambda force, column=compliance(pose): column * force)  # noqa: B008 (bound per pose)
    limit = max(4.0 * sim.controller.force_limit_n, sim.contact.stiffness_n_per_m * sim.interference_m)
    curve = load_deflection(machine, pin_pose, [0.0, 1.0, 0.0], np.linspace(0.0, limit, _CURVE_POINTS),
                            clearance_from_case(case, machine), case.preload.a4_n, unload=False)
    loads, disp = curve.loads_n, curve.loading.displacement_m - curve.loading.displacement_m[0]
    return lambda pose: lambda force: np.array([np.interp(force, loads, disp[:, k]) for k in range(3)])


def simulate_insertion(case: Case, limiter: bool = True, progress: bool = False) -> InsertionResult:
    """Run the case's ``[simulation]`` scenario, with or without the force limiter (module docstring)."""
    sim = case.simulation
    if sim is None:
        raise PressfitError(f"{case.path}: the case has no [simulation] table")
    if case.preload.mode != "force":
        raise PressfitError(f"{case.path}: [preload] mode must be \"force\" (a4_n, N) for the force-controlled "
                            f"drives of the simulation, got \"{case.preload.mode}\"")
    machine = case.machine()
    trajectory = Trajectory.insertion(sim)
    rigid = rigid_leg_model(machine, np.asarray(sim.start_m, float), sim.baumgarte_rad_per_s)
    deflection = _deflection(machine, case, sim, trajectory.waypoints_m[2])
    drives = ForceActuators.of(machine)
    ctrl = ForceLimitedController(machine, rigid, sim.controller, limiter, np.asarray(sim.start_m, float).copy())
    q, v, dt, a4 = rigid.reference_q.copy(), np.zeros(rigid.model.nv), sim.time_step_s, case.preload.a4_n
    steps = int(np.ceil(trajectory.duration_s / dt))
    force = ctrl.command(q[rigid.actuator_q], v[rigid.actuator_v], trajectory.at(0.0), 0.0, 0.0)
    tension = -ctrl.pinv @ force + a4 * ctrl.null
    contact = ContactState(0.0, sim.contact.board_height_m - q[1], np.zeros(3))
    rows, phases = np.empty((steps, len(SERIES_COLUMNS))), np.empty(steps, dtype=int)
    tau = np.zeros(rigid.model.nv)
    for k in tqdm(range(steps), desc="simulate", unit="step", disable=not progress, mininterval=0.5):
        t = (k + 1) * dt
        reference = trajectory.at(t)
        force = ctrl.command(q[rigid.actuator_q], v[rigid.actuator_v], reference, contact.force_n, dt)
        command = -ctrl.pinv @ force + a4 * ctrl.null  # equation 5 at the estimate, plus the preload
        tension = drives.step(tension, command, dt)
        tau[rigid.actuator_v] = -tension
        tau[0:3] = pin.Quaternion(q[3:7]).matrix().T @ np.array([0.0, contact.force_n, 0.0])  # local frame
        q, v = rigid.step(q, v, tau, dt)
        loads = rigid.leg_loads()  # at the start of the step, where the accelerations were computed
        pose = q[0:3].copy()
        depth = sim.contact.board_height_m - pose[1]
        contact = (solve_contact(sim.contact, pose, deflection(pose), contact.depth_m, dt) if depth > 0.0
                   else ContactState(0.0, depth, np.zeros(3)))
        rows[k] = (t, *reference[0] + [0.0, ctrl.lift_m, 0.0], *ctrl.estimate_m, *pose,
                   *(pose + contact.deflection_m), contact.force_n, contact.depth_m, *command, *tension, ctrl.lift_m,
                   rigid.closure_error_m(), *loads.T.ravel(), ctrl.null @ tension)
        phases[k] = trajectory.segment(t - 1e-12)
        if not np.all(np.isfinite(q)):
            raise PressfitError(f"{case.path}: the simulation diverged at t = {t:.4g} s (reduce time_step_s)")
    result = InsertionResult(limiter, rows, phases, trajectory.phases)
    return InsertionResult(limiter, rows, phases, trajectory.phases, summarise(result, case, drives))


def settling_time_s(time_s: np.ndarray, force_n: np.ndarray, end: int) -> float | None:
    """Time (s) from the first contact (force > 0) until the contact force enters, and stays in until sample
    ``end`` (the end of the dwell), the band of +-``SETTLING_BAND`` around its value there; None if the tool
    never touches the board before ``end``."""
    touching = np.flatnonzero(force_n[:end + 1] > 0.0)
    if not touching.size:
        return None
    outside = np.flatnonzero(np.abs(force_n[:end + 1] - force_n[end]) > SETTLING_BAND * abs(force_n[end]))
    settled = outside[-1] + 1 if outside.size else touching[0]
    return float(time_s[max(settled, touching[0])] - time_s[touching[0]])


def _columns(result: InsertionResult, prefix: str) -> np.ndarray:
    return result.series[:, [SERIES_COLUMNS.index(f"{prefix}{i}") for i in LEGS]]


def summarise(result: InsertionResult, case: Case, drives: ForceActuators) -> dict[str, Any]:
    """Peak contact force and overshoot over the limit, insertion depth, the steady insertion force at the
    end of the dwell against the contact law at the depth reached, its settling time (:func:`settling_time_s`),
    tool positioning errors (lateral against the pin at the end of the dwell, 3D against ``end_m`` at the end;
    ``positioning_error_m`` is the larger), closure drift, actuator saturation time and peak tensions, the
    peak |axial force|, |torsion| and bending of each leg over the run, the internal force v_p . N."""
    sim = case.simulation
    force, depth, t = result.column("contact_force_n"), result.column("depth_m"), result.column("time_s")
    last = np.flatnonzero(result.phases == result.phase_names.index("dwell"))[-1]
    tool = result.series[:, [SERIES_COLUMNS.index(c) for c in ("tool_x_m", "tool_y_m", "tool_z_m")]]
    lateral = float(np.linalg.norm(tool[last, [0, 2]] - np.array(sim.contact.pin_position_m)))
    final = float(np.linalg.norm(tool[-1] - sim.end_m))
    internal, limit = result.column("internal_force_n"), sim.controller.force_limit_n
    return {
        "case": case.name, "limiter": result.limiter, "force_limit_n": limit,
        "simulated_time_s": float(t[-1]), "time_step_s": sim.time_step_s,
        "peak_contact_force_n": float(force.max()), "overshoot_n": float(max(force.max() - limit, 0.0)),
        "max_insertion_depth_m": float(depth.max()), "steady_insertion_force_n": float(force[last]),
        "steady_insertion_depth_m": float(depth[last]),
        "contact_law_at_steady_depth_n": contact_force_n(sim.contact, float(depth[last])),
        "settling_time_s": settling_time_s(t, force, last), "settling_band": SETTLING_BAND,
        "tool_lateral_error_at_insertion_m": lateral, "tool_final_error_m": final,
        "positioning_error_m": max(lateral, final),
        "max_closure_drift_m": float(result.column("closure_drift_m").max()),
        "actuator_saturation_time_s": float(drives.saturated(_columns(result, "cmd_n")).any(axis=1).sum()
                                            * sim.time_step_s),
        "peak_actuator_tension_n": np.abs(_columns(result, "act_n")).max(axis=0),
        "actuator_force_limit_n": drives.force_limit_n, "actuator_bandwidth_hz": drives.bandwidth_hz,
        "peak_leg_axial_force_n": np.abs(_columns(result, "axial_n")).max(axis=0),
        "peak_leg_torsion_nm": np.abs(_columns(result, "torsion_nm")).max(axis=0),
        "peak_leg_bending_nm": _columns(result, "bending_nm").max(axis=0),
        "commanded_preload_n": case.preload.a4_n,
        "internal_force_range_n": [float(internal.min()), float(internal.max())],
    }
