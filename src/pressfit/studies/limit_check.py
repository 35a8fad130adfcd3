"""Load envelopes: evaluate a case over its poses and loads and check its ``[envelope]`` limits.

Method: the exact condensed linear-elastic formulation (``pressfit.condensed``) sweeps every pose and
load (vectorised); the geometrically nonlinear Pinocchio solve (``pressfit.statics``) then refines the
``solver.refine_worst`` worst (pose, load) pairs of each load quantity; the reported worst value is the
worse of the two. Shear is zero in the linear rigid-cardan model, so the shear limit is checked on the
refined nonlinear solutions only (stated in the report). Geometry-only quantities (joint-limit
margins, interference distance) are exact at every pose. A case with a ``[clearance]`` table also
re-evaluates the axial quantities, deflection and tilt at the refined poses with its cardan clearances
(lost motion adds to the deflection; a leg whose joints open sheds load to the others).

A case whose ``[simulation]`` has ``[simulation.limits]`` also gets one line per simulation limit, from one
run of its insertion scenario (:func:`evaluate_simulation`, lines keyed ``simulation.<limit>``), and a case
whose ``[cycle]`` has ``[cycle.limits]`` one per cycle limit from one run of its board (:func:`evaluate_cycle`,
lines keyed ``cycle.<limit>``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from pressfit import kinematics
from pressfit.description.cases import Case, SimulationLimits, discover, load_case
from pressfit.description.machine import Machine
from pressfit.errors import ConvergenceError, PressfitError, SingularPoseError, UnstableEquilibriumError
from pressfit.mechanics import buckling, condensed, preload
from pressfit.mechanics.clearance import clearance_from_case, load_deflection
from pressfit.mechanics.fast_statics import FastEquilibriumSolver
from pressfit.mechanics.statics import Equilibrium, EquilibriumSolver

SECTIONS = ("base", "actuator", "plate")


@dataclass(frozen=True, kw_only=True)
class Limit:
    """How one ``[envelope]`` key is evaluated: a per-(pose, leg) quantity and its sense."""

    label: str
    unit: str
    sense: str  # "max": value must stay <= limit; "min": value must stay >= limit
    load_dependent: bool = True


LIMITS: dict[str, Limit] = {
    "max_tension_n": Limit(label="leg axial tension", unit="N", sense="max"),
    "max_compression_n": Limit(label="leg axial compression", unit="N", sense="max"),
    "max_shear_n": Limit(label="leg shear |V|", unit="N", sense="max"),
    "max_bending_nm": Limit(label="leg bending |M_b|", unit="N m", sense="max"),
    "max_torsion_nm": Limit(label="leg torsion |T|", unit="N m", sense="max"),
    "max_actuator_force_n": Limit(label="actuator force |F|", unit="N", sense="max"),
    "max_plate_deflection_m": Limit(label="plate deflection |u|", unit="m", sense="max"),
    "max_plate_tilt_rad": Limit(label="plate tilt |theta|", unit="rad", sense="max"),
    "min_buckling_safety_factor": Limit(label="buckling safety factor", unit="-", sense="min"),
    "min_leg_length_margin_m": Limit(label="leg-length limit margin", unit="m", sense="min", load_dependent=False),
    "min_angle_margin_rad": Limit(label="cardan-angle limit margin", unit="rad", sense="min", load_dependent=False),
    "min_interference_distance_m": Limit(label="minimum interference distance", unit="m", sense="min",
                                         load_dependent=False),
}


@dataclass(frozen=True, kw_only=True)
class LimitResult:
    """One envelope line: the worst value over the case, where it happens, and the verdict."""

    key: str
    label: str
    unit: str
    limit: float
    worst: float
    leg: int | None  # 1..n, None for plate or machine quantities
    pose_m: list[float]
    load: list[float]
    method: str
    passed: bool
    sense: str = "max"  # "max": worst <= limit passes; "min": worst >= limit passes


@dataclass(frozen=True, kw_only=True)
class CaseResult:
    """Every envelope line of one case, plus the poses that could not be evaluated."""

    case: str
    path: str
    n_poses: int
    n_loads: int
    unreachable: list[dict[str, object]] = field(default_factory=list)  # every one: pose_m, reason, excess
    limits: list[LimitResult] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return not self.unreachable and all(r.passed for r in self.limits)


@dataclass(frozen=True)
class FileError:
    """A case file that could not be checked (malformed, or its evaluation refused): an error, not a verdict."""

    path: str
    message: str


@dataclass(frozen=True, kw_only=True)
class CheckRun:
    """``pressfit check``: the verdict of every checkable case, the files that could not be checked, and the
    cases without an ``[envelope]``. Exit code: 2 if any file is in error, else 1 if any case fails, else 0."""

    results: list[CaseResult]
    errors: list[FileError]
    skipped: list[str]

    @property
    def exit_code(self) -> int:
        return 2 if self.errors else 1 if any(not r.passed for r in self.results) else 0


def check_files(paths: list[Path | str], progress: bool = False) -> CheckRun:
    """Check every case file named or found under the directories in ``paths``: a malformed file (or one
    whose evaluation is refused) is recorded as an error and the others are still checked."""
    cases, errors = [], []
    for f in discover(paths):
        try:
            case = load_case(f)
            case.machine()
            cases.append(case)
        except PressfitError as exc:
            errors.append(FileError(str(f), str(exc)))
    checked = [c for c in cases if c.envelope.model_dump(exclude_none=True) or _simulation_limits(c)
               or _cycle_limits(c)]
    if not checked and not errors:
        raise PressfitError("no case among " + ", ".join(map(str, paths)) + " has an [envelope], "
                            "[simulation.limits] or [cycle.limits] to check")
    results = []
    for case in checked:
        try:
            results.append(evaluate_case(case, progress=progress))
        except PressfitError as exc:
            errors.append(FileError(case.path, str(exc)))
    return CheckRun(results=results, errors=errors, skipped=[c.path for c in cases if c not in checked])


def _axial_quantities(n: np.ndarray, critical: np.ndarray) -> dict[str, np.ndarray]:
    comp = np.maximum(-n, 0.0)
    return {"max_tension_n": np.maximum(n, 0.0), "max_compression_n": comp,
            "max_actuator_force_n": np.abs(n),
            "min_buckling_safety_factor": np.where(comp > 0, critical / np.where(comp > 0, comp, 1), np.inf)}


def condensed_quantities(res: condensed.CondensedResult, critical: np.ndarray) -> dict[str, np.ndarray]:
    """Per (pose, leg) arrays (P, n), or (P,) for plate quantities, from the linear condensed solve."""
    m = res.leg_moments_nm  # (P, 4, 3): M_x, M_y, T in the leg frame
    out = _axial_quantities(res.axial_forces_n, critical)
    out.update({"max_bending_nm": np.hypot(m[..., 0], m[..., 1]), "max_torsion_nm": np.abs(m[..., 2]),
                "max_plate_deflection_m": np.linalg.norm(res.plate_displacement_m, axis=-1),
                "max_plate_tilt_rad": np.linalg.norm(res.plate_rotation_rad, axis=-1)})
    return out


def section_quantities(forces_n: np.ndarray, sections: np.ndarray, displacement_m: np.ndarray,
                       rotation_rad: np.ndarray, critical: np.ndarray) -> dict[str, np.ndarray]:
    """The limit quantities of a batch of solves (leading shape b): actuator forces (b, n) (N, > 0 tension),
    section wrenches (b, n, sections, 6) (N, V_x, V_y in N; M_x, M_y, T in N m), plate displacement (b, 3), m,
    and rotation (b, 3), rad, Euler loads ``critical`` (N, broadcast to (b, n)). Per (solve, leg) arrays
    (b, n), worst over the sections, or (b,) for the plate quantities."""
    out = _axial_quantities(forces_n, critical)
    out.update({"max_shear_n": np.hypot(sections[..., 1], sections[..., 2]).max(-1),
                "max_bending_nm": np.hypot(sections[..., 3], sections[..., 4]).max(-1),
                "max_torsion_nm": np.abs(sections[..., 5]).max(-1),
                "max_plate_deflection_m": np.linalg.norm(displacement_m, axis=-1),
                "max_plate_tilt_rad": np.linalg.norm(rotation_rad, axis=-1)})
    return out


def equilibrium_quantities(eq: Equilibrium, critical: np.ndarray) -> dict[str, np.ndarray]:
    """The same quantities from a Pinocchio solve, worst over the base, actuator and plate sections."""
    s = np.array([[list(leg.sections[k].as_dict().values()) for k in SECTIONS] for leg in eq.legs])
    return section_quantities(np.asarray(eq.actuator_forces_n, float)[None], s[None], eq.plate_displacement_m[None],
                              eq.plate_rotation_rad[None], critical)


def _worst(values: np.ndarray, sense: str) -> tuple[float, int, int | None]:
    """Worst value, its pose index, and its leg (1-based) for (P, n) arrays."""
    v = values if sense == "max" else -values
    flat = int(np.argmax(v))
    if values.ndim == 1:
        return float(values[flat]), flat, None
    p, leg = np.unravel_index(flat, values.shape)
    return float(values[p, leg]), int(p), int(leg) + 1


def evaluate_case(case: Case, progress: bool = False) -> CaseResult:
    """Evaluate every ``[envelope]``, ``[simulation.limits]`` and ``[cycle.limits]`` limit of a case (module
    docstring)."""
    result = evaluate_envelope(case, progress)
    return replace(result, limits=[*result.limits, *evaluate_simulation(case, progress),
                                   *evaluate_cycle(case, progress)])


def evaluate_envelope(case: Case, progress: bool = False) -> CaseResult:
    """Evaluate every ``[envelope]`` limit of a case (module docstring for the method)."""
    machine = case.machine()
    poses_all, loads = case.poses.array(), case.loads.wrenches()
    ok = kinematics.is_reachable(machine, poses_all)
    unreachable = _unreachable(machine, poses_all[~ok])
    poses = poses_all[ok]
    wanted = {k: v for k, v in case.envelope.model_dump().items() if v is not None}
    if not len(poses):
        return CaseResult(case=case.name, path=case.path, n_poses=len(poses_all), n_loads=len(loads),
                          unreachable=unreachable)
    if case.preload.mode == "length" and case.preload.a4:
        raise PressfitError(f"{case.path}: [preload] mode = \"length\" is not supported by the envelope check "
                            "(its linear sweep superposes force-mode preload only); give a4_n with mode = \"force\"")
    critical = buckling.leg_critical_loads_n(machine, kinematics.inverse_kinematics(machine, poses).lengths_m)
    stacked = _linear_sweep(case, machine, poses, loads, critical, progress)
    lines = [_geometry_line(key, limit, machine, poses, progress) for key, limit in wanted.items()
             if not LIMITS[key].load_dependent]
    plans = {key: _candidates(LIMITS[key].sense, stacked.get(key), stacked, len(loads), len(poses),
                              case.solver.refine_worst) for key in wanted if LIMITS[key].load_dependent}
    refined = _refine(machine, poses, loads, sorted({c for key, (cands, _) in plans.items()
                                                      if key != "min_buckling_safety_factor" for c in cands}),
                      case.solver.linear, _case_preload(case))
    unstable: dict[tuple[int, int], str] = {}  # (load, pose) -> why no stable equilibrium was found
    for key, (candidates, best) in plans.items():
        best = _refined_best(case, machine, key, candidates, best, refined, poses, loads, critical, unstable)
        if best is not None:  # None: shear with every refined solve unstable (the stability line reports it)
            lines.append(_line(key, LIMITS[key], wanted[key], best[0], best[3], poses[best[2]], loads[best[1]],
                               best[4]))
    lines.sort(key=lambda x: list(wanted).index(x.key))
    if unstable:
        lines = _instability_line(lines, unstable, poses, loads, wanted.get("min_buckling_safety_factor"))
    return CaseResult(case=case.name, path=case.path, n_poses=len(poses_all), n_loads=len(loads),
                      unreachable=unreachable, limits=lines)


def _case_preload(case: Case) -> preload.Amplitudes:
    """The case's force-mode preload as the statics take it: a4 (N) on a redundancy-1 machine, else the n - 3
    amplitudes (checked against the machine where applied: PreloadError)."""
    return preload.ActuatorPreload.from_case(case.preload).a4


def _linear_sweep(case: Case, machine: Machine, poses: np.ndarray, loads: np.ndarray, critical: np.ndarray,
                  progress: bool) -> dict[str, np.ndarray]:
    """Every load-dependent quantity over every (load, pose) from the condensed linear model: (L, P, ...)."""
    a4 = _case_preload(case)
    self_stress = preload.self_stress_forces_n(machine, poses, a4) if np.any(a4) else None
    sweep: dict[str, list[np.ndarray]] = {}
    for w in tqdm(loads, desc=f"{case.name}: linear sweep", disable=not progress, unit="load"):
        res = condensed.solve_linear(machine, poses, w)
        if self_stress is not None:  # a force-mode preload is a self-stress along v_p with no couples and
            # no plate motion: it superposes exactly in the linear model (length mode: see README)
            res = preload.with_axial_preload(res, self_stress)
        for k, v in condensed_quantities(res, critical).items():
            sweep.setdefault(k, []).append(v)
    return {k: np.stack(v) for k, v in sweep.items()}


def _geometry_line(key: str, limit: float, machine: Machine, poses: np.ndarray, progress: bool) -> LimitResult:
    """A load-independent limit (joint-limit margins, interference distance), exact at every pose."""
    if key == "min_interference_distance_m":
        values = _interference(machine, poses, progress)
    else:
        margins = kinematics.limit_margins(machine, poses)
        values = margins["leg_length_m"] if key == "min_leg_length_margin_m" else \
            np.minimum(margins["alpha_rad"], margins["beta_rad"])
    spec = LIMITS[key]
    worst, p, leg = _worst(values, spec.sense)
    return _line(key, spec, limit, worst, leg, poses[p], None, "exact at every pose")


Best = tuple[float, int, int, int | None, str]  # worst value, load index, pose index, leg (1..n), method


def _refined_best(case: Case, machine: Machine, key: str, candidates: list[tuple[int, int]], best: Best | None,
                  refined: dict[tuple[int, int], Equilibrium | str], poses: np.ndarray, loads: np.ndarray,
                  critical: np.ndarray,
                  unstable: dict[tuple[int, int], str]) -> Best | None:
    """The worse of the sweep's worst and the refined solves at ``candidates`` (with the case's clearances for
    the clearance-sensitive quantities); a refined pair without a stable equilibrium goes to ``unstable``."""
    sense, a4, n = LIMITS[key].sense, _case_preload(case), len(candidates)
    solver = EquilibriumSolver(machine, pose_m=poses[candidates[0][1]]) \
        if key == "min_buckling_safety_factor" and candidates else None
    for j, p in candidates:
        if solver is not None:  # refined: the whole machine's linearised buckling factor
            w, leg = machine_buckling_factor(solver, poses[p], loads[j], a4)
            if worse(w, best, sense):
                best = (w, int(j), int(p), leg, f"whole-machine linearised buckling at the {n} worst poses "
                        "(per-leg Euler in the sweep)")
            continue
        eq = refined[(j, p)]
        if isinstance(eq, str):
            unstable.setdefault((int(j), int(p)), eq)
            continue
        w, _, leg = _worst(equilibrium_quantities(eq, critical[p:p + 1])[key], sense)
        if worse(w, best, sense):
            best = (w, int(j), int(p), leg, f"{'linear' if case.solver.linear else 'nonlinear'} solve at the {n} "
                    "worst poses")
        if case.clearance is None or key not in CLEARANCE_SENSITIVE:
            continue
        try:
            w, leg = _with_clearance(case, machine, poses[p], loads[j], a4, critical[p:p + 1], key, sense)
        except UnstableEquilibriumError as exc:
            unstable.setdefault((int(j), int(p)), str(exc))
            continue
        if worse(w, best, sense):
            best = (w, int(j), int(p), leg, f"with the case's cardan clearances "
                    f"({clearance_from_case(case, machine).description}; small-displacement clearance solver, "
                    f"20 load steps) at the {n} worst poses")
    return best


def _candidates(sense: str, lin: np.ndarray | None, stacked: dict[str, np.ndarray], n_loads: int, n_poses: int,
                refine_worst: int) -> tuple[list[tuple[int, int]], tuple[float, int, int, int | None, str] | None]:
    """The (load, pose) pairs to refine for one quantity (its linear sweep ``lin`` (L, P, ...), or None for
    shear: the worst bending pairs) and the sweep's worst as the starting best."""
    if lin is None:  # shear: only the refined nonlinear solutions carry it; refine the worst bending poses
        b = stacked["max_bending_nm"].reshape(n_loads, n_poses, -1).max(-1)
        order = np.argsort(-b, axis=None)
        return [tuple(int(k) for k in np.unravel_index(i, b.shape)) for i in order[:max(1, refine_worst)]], None
    flat = lin.reshape(n_loads, n_poses, -1)
    flat = flat.max(-1) if sense == "max" else flat.min(-1)
    order = np.argsort(-flat if sense == "max" else flat, axis=None)
    candidates = [tuple(int(k) for k in np.unravel_index(i, flat.shape)) for i in order[:refine_worst]]
    j, p = np.unravel_index(order[0], flat.shape)  # the worst of the whole sweep, refined or not
    w, _, leg = _worst(lin[j], sense)
    return candidates, (w, int(j), int(p), leg, f"linear condensed over {n_poses} poses x {n_loads} loads")


def _refine(machine: Machine, poses: np.ndarray, loads: np.ndarray, pairs: list[tuple[int, int]], linear: bool,
            a4: preload.Amplitudes) -> dict[tuple[int, int], Equilibrium | str]:
    """The refined solves of every (load, pose) pair in one batch (:mod:`pressfit.mechanics.fast_statics`,
    equal to the Pinocchio solve to 1e-9 linear, 1e-7 nonlinear), each with the reference's stability report;
    an unstable one maps to the reason. A batch the fast solver cannot finish (Newton diverging beyond
    buckling, a singular pose) is solved pose by pose with the Pinocchio solver instead, as before."""
    if not pairs:
        return {}
    fast = FastEquilibriumSolver(machine, pose_m=poses[0])
    idx = np.array(pairs)
    out: dict[tuple[int, int], Equilibrium | str] = {}
    try:
        batch = fast.solve_batch(poses[idx[:, 1]], loads[idx[:, 0]], preload=a4 if np.any(a4) else None, linear=linear)
        solve = lambda k, j, p: fast.equilibrium(batch, k)
    except (ConvergenceError, SingularPoseError):
        ref = EquilibriumSolver(fast.model)
        solve = lambda k, j, p: ref.solve(poses[p], loads[j], linear=linear, preload=a4 if np.any(a4) else None)
    for k, (j, p) in enumerate(pairs):
        try:
            out[(j, p)] = solve(k, j, p)
        except UnstableEquilibriumError as exc:
            out[(j, p)] = str(exc)
    return out


STABILITY = Limit(label="stable equilibrium under the full load (1 = stable, 0 = none found)", unit="-", sense="min")


def _instability_line(lines: list[LimitResult], unstable: dict[tuple[int, int], str], poses: np.ndarray,
                      loads: np.ndarray, buckling_limit: float | None) -> list[LimitResult]:
    """A refined solve found no stable equilibrium (a leg beyond buckling, a runaway displacement): a failed
    limit, not bad input. It fails ``min_buckling_safety_factor`` (reported as factor 0 at that pose and
    load) or, without a buckling limit, a ``stable_equilibrium`` line."""
    (j, p), why = next(iter(unstable.items()))
    method = f"no stable equilibrium under this load in the nonlinear solve ({why})"
    if len(unstable) > 1:
        method += f"; {len(unstable) - 1} more (pose, load) pairs likewise"
    if buckling_limit is None:
        return [*lines, _line("stable_equilibrium", STABILITY, 1.0, 0.0, None, poses[p], loads[j], method)]
    spec = LIMITS["min_buckling_safety_factor"]
    line = _line("min_buckling_safety_factor", spec, buckling_limit, 0.0, None, poses[p], loads[j], method)
    return [line if x.key == line.key else x for x in lines]


def _unreachable(machine: Machine, poses: np.ndarray) -> list[dict[str, object]]:
    """Every unreachable pose with the limits it breaks and by how much (m for leg lengths, rad for angles)."""
    if not len(poses):
        return []
    m = kinematics.limit_margins(machine, poses)
    length = np.maximum(-m["leg_length_m"].min(-1), 0.0)
    angle = np.maximum(-np.minimum(m["alpha_rad"], m["beta_rad"]).min(-1), 0.0)
    return [
        {
            "pose_m": h.tolist(),
            "reason": kinematics.unreachable_reason(machine, h),
            "leg_length_excess_m": float(dl),
            "angle_excess_rad": float(da),
        }
        for h, dl, da in zip(poses, length, angle)
    ]


def machine_buckling_factor(solver: EquilibriumSolver, pose: np.ndarray, load: np.ndarray,
                            a4: preload.Amplitudes) -> tuple[float, int]:
    """The machine's linearised buckling load factor on ``load`` (force-mode preload a4 in N held fixed) and
    the leg (1..n) holding most of the mode's energy (:func:`pressfit.mechanics.buckling.machine_buckling`),
    on a solver reused over the refined poses (building its model costs more than the eigenproblem)."""
    offsets = preload.rest_length_offsets(solver.machine, pose, a4, "force") if np.any(a4) else None
    res = buckling.machine_buckling(solver, pose, load, preload_offsets_m=offsets)
    return res.load_factor, res.dominant_leg


CLEARANCE_SENSITIVE = {"max_tension_n", "max_compression_n", "max_actuator_force_n", "max_plate_deflection_m",
                       "max_plate_tilt_rad", "min_buckling_safety_factor"}


def worse(value: float, best: tuple | None, sense: str) -> bool:
    return best is None or (value > best[0] if sense == "max" else value < best[0])


def _with_clearance(case: Case, machine: Machine, pose: np.ndarray, load: np.ndarray, a4: preload.Amplitudes,
                    critical: np.ndarray, key: str, sense: str) -> tuple[float, int | None]:
    """A quantity at the full load with the case's cardan clearances: the preload, then the load in 20
    steps along its direction (lost motion and joints that open both change it). Play along the leg does not
    change the leg couples (they follow the plate rotation about P*), so moments are not re-evaluated."""
    f = float(np.linalg.norm(load[:3]))
    if f == 0 or np.any(load[3:]):
        raise PressfitError(f"{case.path}: [clearance] in an envelope check needs pure force loads")
    ld = load_deflection(machine, pose, load[:3] / f, np.linspace(0.0, f, 21), clearance_from_case(case, machine), a4,
                         "force", unload=False)
    last = ld.loading
    n = last.axial_forces_n[-1][None]
    q = _axial_quantities(n, critical)
    q["max_plate_deflection_m"] = np.array([np.linalg.norm(last.displacement_m[-1])])
    q["max_plate_tilt_rad"] = np.array([np.linalg.norm(last.rotation_rad[-1])])
    w, _, leg = _worst(q[key], sense)
    return w, leg


def _line(key: str, spec: Limit, limit: float, worst: float, leg: int | None, pose: np.ndarray,
          load: np.ndarray | None, method: str) -> LimitResult:
    passed = worst <= limit if spec.sense == "max" else worst >= limit
    return LimitResult(key=key, label=spec.label, unit=spec.unit, limit=float(limit), worst=float(worst), leg=leg,
                       pose_m=[float(c) for c in pose], load=[] if load is None else [float(c) for c in load],
                       method=method, passed=bool(passed), sense=spec.sense)


def _interference(machine: object, poses: np.ndarray, progress: bool) -> np.ndarray:
    from pressfit.geometry import (
        interference,  # Coal is only needed when a case limits interference
    )

    return interference.min_distance_over_poses(machine, poses, progress=progress)


# --- simulation limits ---------------------------------------------------------------------------------------
SIMULATION_LIMITS: dict[str, tuple[Limit, str, str]] = {  # [simulation.limits] key -> (line, summary key, where)
    "max_contact_force_n": (Limit(label="peak contact force", unit="N", sense="max"), "peak_contact_force_n",
                            "peak_contact_force"),
    "max_overshoot_n": (Limit(label="contact force overshoot over the insertion limit", unit="N", sense="max"),
                        "overshoot_n", "overshoot"),
    "max_positioning_error_m": (Limit(label="tool positioning error", unit="m", sense="max"), "positioning_error_m",
                                "positioning_error"),
    "max_settling_time_s": (Limit(label="settling time of the contact force", unit="s", sense="max"),
                            "settling_time_s", "settled"),
    "max_actuator_force_n": (Limit(label="peak actuator tension |N|", unit="N", sense="max"), "peak_actuator_tension_n",
                             "peak_actuator_tension"),
    "max_axial_force_n": (Limit(label="peak leg axial force |N| at the plate cardan", unit="N", sense="max"),
                          "peak_leg_axial_force_n", "peak_leg_axial_force"),
    "max_torsion_nm": (Limit(label="peak leg torsion |T| over the three sections (flexible model)", unit="N m",
                             sense="max"),
                       "peak_leg_torsion_nm", "peak_leg_torsion"),
    "max_bending_nm": (Limit(label="peak leg bending |M_b| over the three sections (flexible model)", unit="N m",
                             sense="max"),
                       "peak_leg_bending_nm", "peak_leg_bending"),
}


def _simulation_limits(case: Case) -> dict[str, float]:
    limits = case.simulation.limits if case.simulation is not None else SimulationLimits()
    return limits.model_dump(exclude_none=True, exclude={"limiter"})


def evaluate_simulation(case: Case, progress: bool = False) -> list[LimitResult]:
    """Run the case's insertion scenario once (with or without the limiter, ``[simulation.limits] limiter``)
    and evaluate its ``[simulation.limits]`` (:func:`simulation_lines`); no lines without limits."""
    from pressfit.dynamics.insertion import simulate_insertion

    wanted = _simulation_limits(case)
    if not wanted:
        return []
    result = simulate_insertion(case, case.simulation.limits.limiter, progress)
    return simulation_lines(wanted, result.summary, case.simulation.contact.pin_position_m,
                            case.simulation.contact.board_height_m)


def simulation_lines(wanted: dict[str, float], summary: dict[str, Any], pin_xz_m: list[float],
                     board_height_m: float) -> list[LimitResult]:
    """One line per simulation limit from a run's summary (:func:`pressfit.dynamics.insertion.summarise`):
    per-leg peaks report their worst leg; each line's pose is the plate pose at the time of its peak (the
    summary's ``<where>_pose_m``; the method names the time), the pin on the board face where the summary has
    none; a settling time of a force that did not settle fails (reported as infinite, with the reason)."""
    pin_pose = np.array([pin_xz_m[0], board_height_m, pin_xz_m[1]])
    how = "insertion simulation, limiter " + ("on" if summary["limiter"] else "off")
    lines = []
    for key, limit in wanted.items():
        spec, name, where = SIMULATION_LIMITS[key]
        value, leg, method = summary[name], None, how
        time, pose = summary.get(f"{where}_time_s"), summary.get(f"{where}_pose_m")
        if value is None:
            value, time, pose = float("inf"), None, None
            method = how + ": " + (summary.get("insertion_note") or "the contact force did not settle")
        elif np.ndim(value):
            leg = int(np.argmax(value)) + 1
            value = float(np.max(value))
            time, pose = np.asarray(time)[leg - 1], np.asarray(pose)[leg - 1]
        if time is not None:
            method += f", at t = {float(time):.4g} s"
        lines.append(_line(f"simulation.{key}", spec, limit, value, leg, pin_pose if pose is None else
                           np.asarray(pose, float), None, method))
    return lines


# --- cycle limits --------------------------------------------------------------------------------------------
CYCLE_LIMITS: dict[str, Limit] = {  # [cycle.limits] key -> its line (description.cases.CycleLimits)
    "max_cycle_time_s": Limit(label="cycle time of the board", unit="s", sense="max"),
    "max_overshoot_n": Limit(label="worst pin's contact force overshoot over its insertion limit", unit="N",
                             sense="max"),
    "max_alignment_error_m": Limit(label="worst pin's lateral alignment error at first contact", unit="m", sense="max"),
    "max_pin_depth_spread_m": Limit(label="worst board position's spread of its component's pin depths", unit="m",
                                    sense="max"),
    "max_rms_drive_force_n": Limit(label="worst drive's RMS force over the cycle", unit="N", sense="max"),
    "max_peak_drive_force_n": Limit(label="worst drive's peak force over the cycle", unit="N", sense="max"),
    "max_energy_per_cycle_j": Limit(label="drives' positive mechanical energy per cycle (regeneration not credited)",
                                    unit="J", sense="max"),
}
CYCLE_DRIVE_LIMITS = ("max_rms_drive_force_n", "max_peak_drive_force_n", "max_energy_per_cycle_j")
PIN_LIMIT_FIGURES = {"max_overshoot_n": "overshoot_n", "max_alignment_error_m": "tool_lateral_error_at_first_contact_m",
                     "max_pin_depth_spread_m": "max_pin_depth_spread_m"}  # a per-pin limit: its figure in cycle.json


def _cycle_limits(case: Case) -> dict[str, float]:
    return {} if case.cycle is None else case.cycle.limits.model_dump(exclude_none=True)


def evaluate_cycle(case: Case, progress: bool = False) -> list[LimitResult]:
    """Run the case's board once (:func:`pressfit.dynamics.cycle.simulate_cycle`; the drive sizing, its energy
    balance enforced, only when a drive limit is asked; no preload-cost run) and evaluate its ``[cycle.limits]``
    (:func:`cycle_lines`); no lines without limits."""
    from pressfit.dynamics.cycle import simulate_cycle

    wanted = _cycle_limits(case)
    if not wanted:
        return []
    result = simulate_cycle(case, progress=progress, sizing=any(k in wanted for k in CYCLE_DRIVE_LIMITS),
                            preload_cost=False)
    return cycle_lines(wanted, result.summary, case.cycle.start_m, case.cycle.board_height_m)


def cycle_lines(wanted: dict[str, float], summary: dict[str, Any], start_m: list[float], board_height_m: float
                ) -> list[LimitResult]:
    """One line per cycle limit from a board's summary (:func:`pressfit.dynamics.cycle.summarise_cycle`, with the
    drive sizing for the drive limits): a pin limit names the worst pin (the line's pose: the pin on the board
    face), a drive limit the worst leg; the other lines' pose is the start pose."""
    how = f"board simulation ({summary['pin_count']} pins, model {summary['model']})"
    lines = []
    for key, limit in wanted.items():
        spec, leg, pose, method = CYCLE_LIMITS[key], None, np.asarray(start_m, float), how
        if key == "max_cycle_time_s":
            value = summary["cycle_time_s"]
        elif key in PIN_LIMIT_FIGURES:
            name = PIN_LIMIT_FIGURES[key]
            values = [math.inf if p[name] is None else p[name] for p in summary["pins"]]
            worst = int(np.argmax(values))
            pin = summary["pins"][worst]
            value, pose = values[worst], np.array([pin["x_m"], board_height_m, pin["z_m"]])
            method += f", worst pin {pin['index']} (x = {pin['x_m']:g} m, z = {pin['z_m']:g} m)" + \
                (": it never touched" if values[worst] == math.inf else "")
        elif key == "max_energy_per_cycle_j":
            value = float(sum(d["positive_energy_j"] for d in summary["drives"]))
        else:
            values = [d["rms_force_n" if key == "max_rms_drive_force_n" else "peak_force_n"] for d in summary["drives"]]
            leg = int(np.argmax(values)) + 1
            value = float(values[leg - 1])
        lines.append(_line(f"cycle.{key}", spec, limit, value, leg, pose, None, method))
    return lines
