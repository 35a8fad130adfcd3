r"""A whole board in one run (``pressfit cycle``): the case's ``[cycle]`` (:class:`pressfit.description.cases.Cycle`)
as one reference of straight S-curve moves (:mod:`pressfit.kinematics.profiles`) through the approach heights,
simulated by the scenario engine (:func:`pressfit.dynamics.scenario.run_plan`, on any model of
:mod:`pressfit.dynamics.machine.registry`) with each segment's insertion force limit the pin's, and per pin and
per cycle figures.

The reference: from ``start_m`` to the first pin's approach point (x, h_b + approach, z) ("approach"), per pin
"descent" to (x, h_b - interference, z), "dwell", "retract" to the approach point, then "traverse" to the next
pin's approach point; after the last pin "move" to ``end_m`` and "settle". Each move is the minimum-time
rest-to-rest S-curve under ``[cycle.motion]`` (approach, traverse, move) or ``[cycle.descent]`` (descent,
retract), with the speed and acceleration scaled down where the drives would bind along the segment (the speed
every ``PATH_SAMPLE_M``, the force at ``FORCE_SAMPLES`` points: the weight and the inertia vary smoothly along a
straight move):

* drive speed: |l_dot_i| = |e_i . u| v must stay within the drive kind's speed limit (electric: the motor's
  ``speed_limit_rad_per_s`` x lead / 2 pi; the force and hydraulic models have none of their own);
* drive force: the rigid-model inverse dynamics at rest, N = -A^+ (G(h) + M(h) a u) + a4 v_p (G the gravity
  feed-forward, M = the plate's apparent mass matrix, the inverse of
  :func:`pressfit.dynamics.scenario.plate_mobility`, reflected drive inertia included), must stay within the
  drives' force limit for |a| up to the acceleration limit; the velocity-product terms (about m v^2 / l, a few
  N at 0.5 m/s) and the force loop's lag are left out of this bound (the simulation has them; its saturation
  time is reported).

Each segment reports the limit that binds it: "speed", "acceleration" or "jerk" (the profile's
:attr:`pressfit.kinematics.profiles.SCurve.binding_limit`, the limit whose relaxation saves the most time; the quintic's
largest of its three times), "drive speed" or "drive force" when that limit is the drives' scaled one, "dwell"
or "settle" for a hold.

Before the run the board is refused (one line naming the pin by its number and (x, z), its key and the file)
when a pin's approach point or the bottom of its insertion is unreachable, start or end is not above the board
face or unreachable, any point of the path (every ``PATH_SAMPLE_M``) breaks a joint limit, a dwell spans fewer
than ``MIN_SEGMENT_STEPS`` steps, the run exceeds ``MAX_STEPS`` steps, the preload alone saturates a drive, the
drives cannot hold a segment even at rest, or the explicit step is unstable (as ``[simulation]``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pressfit import kinematics
from pressfit.description.cases import Case, Contact, Cycle, MotionLimits, ResolvedPin, Simulation
from pressfit.description.machine import Machine
from pressfit.dynamics import drives as drive_kinds
from pressfit.dynamics.actuators import distribution
from pressfit.dynamics.contact import contact_force_n, contact_parameters
from pressfit.dynamics.control import Trajectory, gravity_feedforward_n
from pressfit.dynamics.machine.registry import require_model
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.dynamics.press_monitor import SUMMARY_KEYS, MonitorCurve, monitor_curve
from pressfit.dynamics.scenario import (
    MAX_STEPS,
    MIN_SEGMENT_STEPS,
    PATH_SAMPLE_M,
    WARN_STEPS,
    check_model_step,
    check_oil_column,
    check_preload,
    check_steps,
    drive_limit,
    pin_figures,
    planned_path,
    plate_mobility,
    require_force_preload,
    require_reachable_pose,
    run_plan,
    run_time_warning,
    without_preload,
)
from pressfit.dynamics.series import (
    MAX_DEPTH_FACTOR,
    ScenarioPlan,
    leg_columns,
    preload_amplitudes_n,
    series_columns,
)
from pressfit.dynamics.sizing import RunSizing, run_sizing
from pressfit.errors import ModelFileError, PressfitError
from pressfit.kinematics.profiles import Quintic, SCurve, quintic_move, s_curve

FORCE_SAMPLES = 11  # points per segment where the drive speed and force bounds are evaluated
PIN_PHASES = ("descent", "dwell", "retract")  # a pin's window: its figures are computed on these rows


@dataclass(frozen=True, kw_only=True)
class Segment:
    """One segment of the reference: its phase, the pin it serves (from 1; the traverse and the approach: the pin
    they lead to, the final move and settle: the last pin), its end points (m), duration (s), the limits it ran
    under (m/s, m/s^2, m/s^3; None for a hold), its profile and the limit that binds it (module docstring)."""

    index: int
    phase: str
    pin: int
    start_m: np.ndarray
    end_m: np.ndarray
    duration_s: float
    limits: tuple[float, float, float] | None
    profile: SCurve | Quintic | None
    binding_limit: str

    def to_dict(self) -> dict[str, Any]:
        p = self.profile
        return {"index": self.index, "phase": self.phase, "pin": self.pin, "start_m": self.start_m,
                "end_m": self.end_m, "distance_m": float(np.linalg.norm(self.end_m - self.start_m)),
                "duration_s": self.duration_s, "binding_limit": self.binding_limit,
                "speed_limit_m_per_s": self.limits[0] if self.limits else None,
                "acceleration_limit_m_per_s2": self.limits[1] if self.limits else None,
                "jerk_limit_m_per_s3": self.limits[2] if self.limits else None,
                "peak_speed_m_per_s": p.peak_speed_m_per_s if p else 0.0,
                "peak_acceleration_m_per_s2": p.peak_acceleration_m_per_s2 if p else 0.0}


@dataclass(frozen=True, kw_only=True)
class CyclePlan:
    """A validated board (:func:`plan_cycle`): the scenario plan the step loops run, the resolved pins, the
    segments and the run case (the case with ``simulation`` = the cycle's settings)."""

    scenario: ScenarioPlan
    pins: tuple[ResolvedPin, ...]
    segments: tuple[Segment, ...]
    run_case: Case

    @property
    def cycle_time_s(self) -> float:
        """From the start until the reference reaches ``end_m`` (the settle hold excluded), s."""
        return float(sum(s.duration_s for s in self.segments if s.phase != "settle"))


def drive_speed_limit_m_per_s(drives: drive_kinds.Drive) -> tuple[float | None, str]:
    """The leg speed (m/s) the drive kind cannot exceed and the key that sets it (None: the model has none)."""
    return getattr(drives, "speed_limit_m_per_s", None), getattr(drives, "speed_limit_key", "")


def _pin_label(pin: ResolvedPin) -> str:
    return f"pin {pin.index} (x = {pin.x_m:g} m, z = {pin.z_m:g} m)"


def _unit_legs(machine: Machine, a: np.ndarray, b: np.ndarray, count: int) -> np.ndarray:
    """Leg unit vectors e_i (count, legs, 3) at ``count`` points evenly spaced from a to b (m)."""
    legs = kinematics.leg_vectors(machine, a + np.linspace(0.0, 1.0, count)[:, None] * (b - a))
    return legs / np.linalg.norm(legs, axis=-1, keepdims=True)


def _profile(limits: MotionLimits, distance_m: float, speed_m_per_s: float | None = None,
             acceleration_m_per_s2: float | None = None) -> SCurve | Quintic:
    """The move of ``limits.profile`` over a distance (m) under ``limits`` (or the speed and acceleration given)."""
    move = quintic_move if limits.profile == "quintic" else s_curve
    v = limits.speed_m_per_s if speed_m_per_s is None else speed_m_per_s
    a = limits.acceleration_m_per_s2 if acceleration_m_per_s2 is None else acceleration_m_per_s2
    return move(distance_m, v, a, limits.jerk_m_per_s3)


def _check_length(case: Case, duration_s: float, dt_s: float, pins: int) -> int:
    """The number of steps of a run of ``duration_s``; refused above ``MAX_STEPS``."""
    steps = int(np.ceil(duration_s / dt_s))
    if steps > MAX_STEPS:
        raise ModelFileError(case.path, "[cycle] time_step_s", f"a run of at most {MAX_STEPS} steps: time_step_s = "
                             f"{dt_s:g} s over the board's {duration_s:g} s ({pins} pins) makes {steps} steps or more "
                             "(use a larger time step, fewer pins or faster motion limits)")
    return steps


def _scaled(case: Case, rigid: Any, machine: Machine, drives: drive_kinds.Drive, a: np.ndarray, b: np.ndarray,
            limits: MotionLimits, key: str, label: str) -> tuple[float, float, float, SCurve | Quintic, str]:
    """The segment a -> b (m) under ``limits`` scaled down for the drives (module docstring): v, a, j, the
    profile and the binding limit."""
    v, acc, jerk = limits.speed_m_per_s, limits.acceleration_m_per_s2, limits.jerk_m_per_s3
    distance = float(np.linalg.norm(b - a))
    if distance == 0.0:
        return v, acc, jerk, _profile(limits, 0.0), ""
    u = (b - a) / distance
    speed_limit, _ = drive_speed_limit_m_per_s(drives)
    dense = max(2, math.ceil(distance / PATH_SAMPLE_M) + 1)
    v_drive = speed_limit / np.abs(_unit_legs(machine, a, b, dense) @ u).max() if speed_limit is not None else math.inf
    samples = a + np.linspace(0.0, 1.0, FORCE_SAMPLES)[:, None] * (b - a)
    a_drive = math.inf
    for p, ep in zip(samples, _unit_legs(machine, a, b, FORCE_SAMPLES), strict=True):
        pinv, null = distribution(ep)
        static = -pinv @ gravity_feedforward_n(rigid, p) + null @ preload_amplitudes_n(case, machine)
        per_acc = np.abs(pinv @ np.linalg.solve(plate_mobility(rigid, p), u))
        margin = drives.force_limit_n - np.abs(static)
        if np.any(margin <= 0.0):
            raise ModelFileError(case.path, key, f"{label}: a segment the drives can hold: at "
                                 f"({', '.join(f'{c:.4g}' for c in p)}) m the weight and the preload alone need "
                                 f"{np.abs(static).max():.4g} N, beyond {drive_limit(drives)}")
        a_drive = min(a_drive, float(np.min(margin / np.maximum(per_acc, 1e-300))))
    v_used, a_used = float(min(v, v_drive)), float(min(acc, a_drive))
    profile = _profile(limits, distance, v_used, a_used)
    binding = {"speed": "drive speed" if v_used < v else "speed",
               "acceleration": "drive force" if a_used < acc else "acceleration"}.get(profile.binding_limit, "jerk")
    return v_used, a_used, jerk, profile, binding


def cycle_simulation(cycle: Cycle, first: ResolvedPin, model: str) -> Simulation:
    """The cycle's run settings as the insertion's :class:`Simulation` (the keys mean the same in both; the
    contact's pin pose the first pin's, its pin field ``[[cycle.contact.pins]]``'s)."""
    return Simulation(start_m=cycle.start_m, end_m=cycle.end_m, settle_s=cycle.settle_s,
                      time_step_s=cycle.time_step_s, baumgarte_rad_per_s=cycle.baumgarte_rad_per_s, model=model,
                      contact=Contact(board_height_m=cycle.board_height_m, pin_position_m=[first.x_m, first.z_m],
                                      pins=list(cycle.contact.pins),
                                      **cycle.contact.model_dump(exclude_unset=True, exclude={"pins"})),
                      controller=cycle.controller)


def pin_contact(contact: Contact, pin: ResolvedPin) -> Contact:
    """The board's contact at one board position: the tool axis (``pin_position_m``) on the pin's (x, z), m."""
    return contact.model_copy(update={"pin_position_m": [pin.x_m, pin.z_m]})


def segment_contacts(contact: Contact, machine: Machine, pins: tuple[ResolvedPin, ...],
                     segments: tuple[Segment, ...]) -> tuple[np.ndarray, ...]:
    """Per segment, the contact as the kernels take it (:func:`pressfit.dynamics.contact.contact_parameters`) at
    the board position of the segment's pin, one array per position that its segments share: a pin law's joint has
    a state (the deepest depth it reached: it sets), fresh at every position (the scenario copies the array there).
    With a pin field (``[[cycle.contact.pins]]``) each position has its own table: the component's total force
    against the tool depth carries the tilt by the machine's compliance at that position; one pin on the tool axis
    has its law's at every position (it does not depend on the pose)."""
    if contact.pins:
        tables = [contact_parameters(pin_contact(contact, pin), machine) for pin in pins]
    else:
        law = contact_parameters(pin_contact(contact, pins[0]), machine)
        tables = [law.copy() for _ in pins]
    return tuple(tables[s.pin - 1] for s in segments)


def _check_poses(case: Case, machine: Machine, pins: tuple[ResolvedPin, ...]) -> None:
    """Start and end above the board face and reachable; every pin's dwell at least ``MIN_SEGMENT_STEPS`` steps,
    its approach point and the bottom of its insertion reachable (ModelFileError naming the pin and the key)."""
    cycle = case.cycle
    dt, board = cycle.time_step_s, cycle.board_height_m
    for key, pose in (("start_m", cycle.start_m), ("end_m", cycle.end_m)):
        if not pose[1] > board:
            raise ModelFileError(case.path, f"[cycle] {key}", f"a pose above the board face (the plane y = "
                                 f"[cycle] board_height_m = {board:g} m), got y = {pose[1]:g} m")
        require_reachable_pose(case, machine, np.asarray(pose, float), f"[cycle] {key}", f"the {key[:-2]} pose")
    for pin in pins:
        if pin.dwell_s < MIN_SEGMENT_STEPS * dt * (1 - 1e-9):
            raise ModelFileError(case.path, f"{pin.source} dwell_s", f"{_pin_label(pin)}: a dwell of at least "
                                 f"{MIN_SEGMENT_STEPS} time steps ({MIN_SEGMENT_STEPS * dt:g} s at time_step_s = "
                                 f"{dt:g} s), got {pin.dwell_s:g} s")
        for height, what in ((pin.approach_height_m, f"its approach point {pin.approach_height_m:g} m above the "
                              "board face"), (-pin.interference_m, f"the bottom of its insertion "
                                              f"{pin.interference_m:g} m below the board face")):
            require_reachable_pose(case, machine, np.array([pin.x_m, board + height, pin.z_m]),
                                   f"{pin.source} (x_m, z_m)", f"{_pin_label(pin)}: {what}")


def plan_cycle(case: Case, machine: Machine | None = None, model: str | None = None) -> CyclePlan:
    """Validate the case's ``[cycle]`` (module docstring; ModelFileError naming the pin, the key and the file)
    and plan it. ``model`` overrides ``[cycle] model``."""
    cycle = case.cycle
    if cycle is None:
        raise PressfitError(f"{case.path}: the case has no [cycle] table")
    require_model(case.path, "--model" if model else "[cycle] model", model or cycle.model)
    require_force_preload(case)
    machine = machine or case.machine()
    drives = drive_kinds.of(machine)
    pins = tuple(cycle.resolved_pins())
    dt, board = cycle.time_step_s, cycle.board_height_m
    _check_poses(case, machine, pins)
    descent = cycle.descent or cycle.motion
    bound, previous = cycle.settle_s, np.asarray(cycle.start_m, float)  # the run without the drives' scaling
    for pin in pins:  # (which only lengthens the moves): refused at once if that is already too long
        above = np.array([pin.x_m, board + pin.approach_height_m, pin.z_m])
        bound += (_profile(cycle.motion, float(np.linalg.norm(above - previous))).duration_s + pin.dwell_s
                  + 2.0 * _profile(descent, pin.approach_height_m + pin.interference_m).duration_s)
        previous = above
    _check_length(case, bound + _profile(cycle.motion, float(np.linalg.norm(cycle.end_m - previous))).duration_s,
                  dt, len(pins))
    rigid = rigid_leg_model(machine, np.asarray(cycle.start_m, float), cycle.baumgarte_rad_per_s)
    points, segments = [np.asarray(cycle.start_m, float)], []

    def add(phase: str, pin: ResolvedPin, target: np.ndarray, hold_s: float | None = None) -> None:
        a, index = points[-1], len(segments)
        if hold_s is not None:
            segments.append(Segment(index=index, phase=phase, pin=pin.index, start_m=a, end_m=target,
                                    duration_s=hold_s, limits=None, profile=None, binding_limit=phase))
        else:
            limits, key = (descent, "[cycle.descent]") if phase in ("descent", "retract") else \
                (cycle.motion, "[cycle.motion]")
            v, acc, jerk, profile, binding = _scaled(case, rigid, machine, drives, a, target, limits, key,
                                                     f"{_pin_label(pin)}, its {phase}")
            segments.append(Segment(index=index, phase=phase, pin=pin.index, start_m=a, end_m=target,
                                    duration_s=profile.duration_s, limits=(v, acc, jerk), profile=profile,
                                    binding_limit=binding))
        points.append(target)

    for k, pin in enumerate(pins):
        above = np.array([pin.x_m, board + pin.approach_height_m, pin.z_m])
        bottom = np.array([pin.x_m, board - pin.interference_m, pin.z_m])
        add("approach" if k == 0 else "traverse", pin, above)
        add("descent", pin, bottom)
        add("dwell", pin, bottom, pin.dwell_s)
        add("retract", pin, above)
    add("move", pins[-1], np.asarray(cycle.end_m, float))
    add("settle", pins[-1], points[-1], max(cycle.settle_s, 1e-9))
    trajectory = Trajectory(waypoints_m=np.array(points), durations_s=np.array([s.duration_s for s in segments]),
                            phases=tuple(s.phase for s in segments), shapes=tuple(s.profile for s in segments))
    steps = _check_length(case, trajectory.duration_s, dt, len(pins))
    path, index = planned_path(trajectory)
    ok = kinematics.is_reachable(machine, path)
    if not ok.all():
        first = int(np.flatnonzero(~ok)[0])
        seg = segments[index[first]]
        pin = pins[seg.pin - 1]
        require_reachable_pose(case, machine, path[first], f"{pin.source} (x_m, z_m)" if seg.phase != "move" else
                               "[cycle] end_m", f"{_pin_label(pin)}: the planned path ({seg.phase} segment)")
    check_preload(case, machine, drives, path, "[preload] a4_n")
    sim = cycle_simulation(cycle, pins[0], model or cycle.model)
    check_steps(case, sim, rigid, np.array([cycle.start_m, *points[1::4], cycle.end_m]), "cycle")  # start,
    # every approach point and the end
    check_oil_column(case, machine, sim, np.array([cycle.start_m, *points[1::4], cycle.end_m]), path,
                     "[cycle] time_step_s")
    check_model_step(case, machine, sim, np.array(points), "[cycle] time_step_s")
    limits = np.array([pins[s.pin - 1].force_limit_n for s in segments])
    warnings = (run_time_warning(steps, dt, trajectory.duration_s),) if steps > WARN_STEPS else ()
    scenario = ScenarioPlan(trajectory=trajectory, steps=steps, path_m=path, warnings=warnings, rigid=rigid,
                            simulation=sim, force_limits_n=limits,
                            depth_limit_m=MAX_DEPTH_FACTOR * max(pin.interference_m for pin in pins), table="cycle",
                            contact_params=segment_contacts(sim.contact, machine, pins, tuple(segments)))
    return CyclePlan(scenario=scenario, pins=pins, segments=tuple(segments),
                     run_case=case.model_copy(update={"simulation": sim}))


@dataclass(frozen=True, kw_only=True)
class CycleResult:
    """A simulated board: ``series`` (n, len(columns)), one row per step (``columns``: :func:`cycle_columns`, the
    simulate columns, the pin and the segment of the row), the plan, and ``summary`` (:func:`summarise_cycle`,
    JSON-ready)."""

    series: np.ndarray
    columns: tuple[str, ...]
    plan: CyclePlan
    summary: dict[str, Any]
    sections: np.ndarray | None = None
    sizing: RunSizing | None = None
    curves: tuple[MonitorCurve, ...] = ()  # per pin, the press monitor's view of its stroke (cycle_monitor_curves)

    def column(self, name: str) -> np.ndarray:
        return self.series[:, self.columns.index(name)]


def simulate_cycle(case: Case, model: str | None = None, progress: bool = False, sizing: bool = True,
                   preload_cost: bool = True) -> CycleResult:
    """Plan (:func:`plan_cycle`) and run the board with the force limiter on, and summarise it. With ``sizing``
    the drive sizing over the cycle (:func:`pressfit.dynamics.sizing.run_sizing`: ``drives``, ``energy_balance``,
    ``energy_balance_residual`` in the summary), the preload's cost from a second run of the same plan (the same
    reference and time grid) with ``[preload] a4_n`` = 0, and the energy balance enforced (ResidualError over
    its tolerance); ``preload_cost`` False skips the second run (no ``*_without_preload_*`` figures)."""
    machine = case.machine()
    plan = plan_cycle(case, machine, model)
    drives = drive_kinds.of(machine)

    def run(run_case: Case) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        return run_plan(run_case, machine, plan.scenario, drives, True, progress)  # its errors name [cycle]'s keys

    rows, phases, sections = run(plan.run_case)
    pin = np.array([plan.segments[k].pin if plan.segments[k].phase in PIN_PHASES else 0 for k in phases])
    series = np.column_stack([rows, pin, phases])
    summary = summarise_cycle(series, plan, drives)
    curves = cycle_monitor_curves(series, plan, machine)
    for record, curve in zip(summary["pins"], curves, strict=True):
        record.update({k: curve.summary[k] for k in SUMMARY_KEYS})
    sized = None
    if sizing:
        amplitudes, columns = case.preload.amplitudes, series_columns(len(machine.legs))
        baseline = _Rows(series=series, columns=columns)
        if any(amplitudes) and preload_cost:
            try:
                baseline = _Rows(series=run(without_preload(plan.run_case))[0], columns=columns)
            except PressfitError as exc:
                raise PressfitError(f"the preload's cost (the same board without the preload, instead of "
                                    f"{', '.join(f'{a:g}' for a in amplitudes)} N) could not be simulated: {exc}"
                                    ) from None
        sized = run_sizing(_Rows(series=series, columns=columns), drives, plan.scenario.simulation.time_step_s,
                           baseline if preload_cost else None, model=plan.scenario.simulation.model)
        sized.energy.require_closed(f"of the board of {case.path}", "cycle")
        summary.update(sized.to_dict())
    return CycleResult(series=series, columns=cycle_columns(len(machine.legs)), plan=plan, summary=summary,
                       sections=sections, sizing=sized, curves=curves)


def cycle_monitor_curves(series: np.ndarray, plan: CyclePlan, machine: Machine) -> tuple[MonitorCurve, ...]:
    """Per pin, the press monitor's view of its stroke (its descent, dwell and retract rows,
    :func:`pressfit.dynamics.press_monitor.monitor_curve`) at that pin's pose: the board's contact with
    ``pin_position_m`` the pin's (x, z), so each pin's curve carries the compliance of its own pose."""
    col = {name: k for k, name in enumerate(cycle_columns(len(machine.legs)))}
    segment = series[:, col["segment"]].astype(int)
    contact = plan.scenario.simulation.contact
    curves = []
    for pin in plan.pins:
        mine = [s.index for s in plan.segments if s.pin == pin.index and s.phase in PIN_PHASES]
        rows = np.flatnonzero(np.isin(segment, mine))
        dwell = np.flatnonzero(segment[rows] == mine[1])
        curves.append(monitor_curve(machine, pin_contact(contact, pin),
                                    *(series[rows, col[c]] for c in ("time_s", "depth_m", "kinematic_y_m",
                                                                     "contact_force_n")),
                                    int(dwell[-1]), where=f"{plan.run_case.path}: {_pin_label(pin)}"))
    return tuple(curves)


@dataclass(frozen=True, kw_only=True)
class _Rows:
    """Rows whose first columns are ``columns`` (:func:`pressfit.dynamics.series.series_columns`: what run_sizing
    reads)."""

    series: np.ndarray
    columns: tuple[str, ...]


def cycle_columns(legs: int) -> tuple[str, ...]:
    """The columns of an n-leg board's series: the simulate columns, the pin (0: none) and the segment."""
    return (*series_columns(legs), "pin", "segment")


def summarise_cycle(series: np.ndarray, plan: CyclePlan, drives: drive_kinds.Drive | None = None) -> dict[str, Any]:
    """Per pin (``pins``), on the rows of its descent, dwell and retract: ``first_contact_time_s``,
    ``peak_contact_force_n`` (and its time), ``steady_insertion_force_n`` (at the end of the dwell),
    ``overshoot_n`` over the pin's ``force_limit_n``, ``tool_lateral_error_at_first_contact_m`` (the tool's
    (x, z) against the pin's), ``settling_time_s``, ``insertion_completed`` (the figures of
    :func:`pressfit.dynamics.scenario.pin_figures`, computed there once for a pin and a board: settled at
    ``COMPLETION_FRACTION`` of the target: the contact law at the pin's
    interference or its force limit if lower), ``checks`` (each given pin limit: ``max_overshoot_n`` on
    ``overshoot_n``, ``max_alignment_error_m`` on the lateral error) and ``passed`` (completed and every check
    holds). The cycle: ``cycle_time_s`` (:attr:`CyclePlan.cycle_time_s`), ``pins_per_minute``, ``segments``,
    ``slowest_segment`` (the longest segment but the settle, and its binding limit), the drives' saturation."""
    columns = cycle_columns(len(plan.scenario.rigid.machine.legs))
    col = {name: k for k, name in enumerate(columns)}
    t, force = series[:, col["time_s"]], series[:, col["contact_force_n"]]
    tool = series[:, [col["tool_x_m"], col["tool_z_m"]]]
    segment = series[:, col["segment"]].astype(int)
    contact = plan.scenario.simulation.contact
    pins, warnings = [], []
    for pin in plan.pins:
        mine = [s.index for s in plan.segments if s.pin == pin.index and s.phase in PIN_PHASES]
        rows = np.flatnonzero(np.isin(segment, mine))
        law = plan.scenario.contact_params[mine[0]] if plan.scenario.contact_params else contact
        fig = pin_figures(t[rows], force[rows], tool[rows], np.flatnonzero(segment[rows] == mine[1]),
                          np.array([pin.x_m, pin.z_m]), min(contact_force_n(law, pin.interference_m),
                                                            pin.force_limit_n), pin.force_limit_n)
        checks = _checks(pin, fig.overshoot_n, fig.lateral_m)
        if not fig.completed:
            warnings.append(f"{_pin_label(pin)}: the insertion did not complete: {fig.note}")
        first = fig.first_contact
        pins.append({
            "index": pin.index, "x_m": pin.x_m, "z_m": pin.z_m, "source": pin.source,
            "force_limit_n": pin.force_limit_n, "interference_m": pin.interference_m, "dwell_s": pin.dwell_s,
            "first_contact_time_s": float(t[rows[first]]) if first is not None else None,
            "peak_contact_force_n": fig.peak_n, "peak_contact_force_time_s": float(t[rows[fig.peak]]),
            "steady_insertion_force_n": fig.steady_n, "overshoot_n": fig.overshoot_n,
            "tool_lateral_error_at_first_contact_m": fig.lateral_m,
            "settling_time_s": fig.settling_s, "insertion_completed": fig.completed,
            "insertion_target_force_n": fig.target_n, "insertion_note": fig.note,
            "checks": checks, "passed": bool(fig.completed and all(c["passed"] for c in checks))})
    records = [s.to_dict() for s in plan.segments]
    slowest = max((r for r in records if r["phase"] != "settle"), key=lambda r: r["duration_s"])
    cycle_time = plan.cycle_time_s
    summary: dict[str, Any] = {
        "case": plan.run_case.name, "model": plan.scenario.simulation.model,
        "time_step_s": plan.scenario.simulation.time_step_s, "simulated_time_s": float(t[-1]),
        "pin_count": len(pins), "pins": pins, "pins_passed": sum(p["passed"] for p in pins),
        "cycle_time_s": cycle_time, "pins_per_minute": 60.0 * len(pins) / cycle_time,
        "slowest_segment": {k: slowest[k] for k in ("index", "phase", "pin", "duration_s", "binding_limit")},
        "segments": records,
    }
    if drives is not None:
        commands = series[:, leg_columns(columns, "cmd_n")]
        saturated = drives.saturated(commands).any(axis=1)
        summary["actuator_saturation_time_s"] = float(saturated.sum() * plan.scenario.simulation.time_step_s)
        if saturated.any():
            warnings.append(f"the drives saturated (a command beyond {drive_limit(drives)}) for "
                            f"{summary['actuator_saturation_time_s']:g} s")
    summary["warnings"] = [*plan.scenario.warnings, *warnings]
    return summary


def _checks(pin: ResolvedPin, overshoot_n: float, lateral_m: float | None) -> list[dict[str, Any]]:
    """Each limit the pin gives (``max_overshoot_n`` on the overshoot, ``max_alignment_error_m`` on the lateral
    error at first contact, None without contact) with its value and whether it holds."""
    checks = []
    if pin.max_overshoot_n is not None:
        checks.append({"key": "max_overshoot_n", "value_n": overshoot_n, "limit_n": pin.max_overshoot_n,
                       "passed": overshoot_n <= pin.max_overshoot_n})
    if pin.max_alignment_error_m is not None:
        checks.append({"key": "max_alignment_error_m", "value_m": lateral_m, "limit_m": pin.max_alignment_error_m,
                       "passed": lateral_m is not None and lateral_m <= pin.max_alignment_error_m})
    return checks
