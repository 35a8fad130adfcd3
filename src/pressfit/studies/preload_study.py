"""Clearance vs preload: over a grid of cardan clearances and preloads at one pose, the load-deflection
curves, lost motion, stiffness and the critical preload that keeps every cardan closed (paper section
4.1's promise, quantified). The physics is :mod:`pressfit.mechanics.clearance`. SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from tqdm import tqdm

from pressfit import kinematics
from pressfit.description.machine import Machine
from pressfit.mechanics import condensed
from pressfit.mechanics.clearance import (
    Clearance,
    ClearanceError,
    LoadDeflection,
    _branch,
    _direction,
    _sweep_small,
    clearance_from_case,
    critical_preloads,
    load_deflection,
)
from pressfit.mechanics.clearance_law import GEOMETRY_DESCRIPTIONS
from pressfit.mechanics.preload import along_first_vector, rest_length_offsets

NO_CRITICAL_PRELOAD = ("no critical preload (3 legs: no redundant actuation; 5 or more: the study's preload, along "
                       "the first basis vector, leaves the plays of legs 5..n open at no load)")
SMALL_LOAD_FRACTION = 0.1  # the small load of the small-load secant stiffness, as a fraction of the largest load


# --- the preload study -------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class PreloadStudy:
    """Stiffness and lost motion over a (clearance x preload) grid at one pose; arrays (G, P) (SI)."""

    pose_m: np.ndarray
    direction: np.ndarray
    preload_mode: str
    clearances_m: np.ndarray  # (G,) mean play g of each clearance variant, m (in the shape clearance_geometry names)
    clearance_geometry: str  # the variants' Clearance.geometry: "axial", "box" or "sphere"
    preloads: np.ndarray  # (P,) N (force) or m (length)
    loads_n: np.ndarray  # (n,)
    deflection_m: np.ndarray  # (G, P, n) along the direction, loading
    small_load_n: float  # the stated small load, N (SMALL_LOAD_FRACTION of the largest load)
    small_load_secant_stiffness_n_per_m: np.ndarray  # small_load_n over the deflection it causes (own solve)
    press_stiffness_n_per_m: np.ndarray
    press_secant_stiffness_n_per_m: np.ndarray
    lost_motion_m: np.ndarray
    first_opening_load_n: np.ndarray  # lowest load at which some joint is open (NaN: none opens)
    critical_preload: np.ndarray  # (G,); NaN unless the machine has 4 legs (NO_CRITICAL_PRELOAD)
    no_clearance_contact_stiffness_n_per_m: float  # g = 0 with the contact springs k_c in series with each leg
    rigid_cardan_stiffness_n_per_m: float  # g = 0 and rigid cardans: the stiffness that ``pressfit stiffness`` gives
    max_residual: float
    contact_stiffness_n_per_m: float
    smoothing_m: float

    @property
    def baseline(self) -> int:
        """Index of the "without preload" column (a4 = 0, always computed)."""
        return int(np.flatnonzero(self.preloads == 0.0)[0])

    def rows(self) -> tuple[list[str], list[list[Any]]]:
        header = ["clearance_m", "clearance_geometry", f"preload_{'n' if self.preload_mode == 'force' else 'm'}",
                  "small_load_secant_stiffness_n_per_m", "press_stiffness_n_per_m", "press_secant_stiffness_n_per_m",
                  "lost_motion_m", "deflection_at_max_m", "first_opening_load_n", "critical_preload",
                  "stiffness_gain_vs_no_preload"]
        rows, b = [], self.baseline
        for g, p in np.ndindex(len(self.clearances_m), len(self.preloads)):
            rows.append([float(self.clearances_m[g]), self.clearance_geometry, float(self.preloads[p]),
                         float(self.small_load_secant_stiffness_n_per_m[g, p]),
                         float(self.press_stiffness_n_per_m[g, p]),
                         float(self.press_secant_stiffness_n_per_m[g, p]), float(self.lost_motion_m[g, p]),
                         float(self.deflection_m[g, p, -1]), _opt(self.first_opening_load_n[g, p]),
                         _opt(self.critical_preload[g]), float(self.small_load_secant_stiffness_n_per_m[g, p]
                                                               / self.small_load_secant_stiffness_n_per_m[g, b])])
        return header, rows

    def to_dict(self) -> dict[str, Any]:
        header, rows = self.rows()
        return {"pose_m": self.pose_m.tolist(), "direction": self.direction.tolist(),
                "preload_mode": self.preload_mode, "load_max_n": float(self.loads_n[-1]),
                "clearance_geometry": self.clearance_geometry,
                "clearance_geometry_description": GEOMETRY_DESCRIPTIONS[self.clearance_geometry],
                "steps": len(self.loads_n) - 1, "contact_stiffness_n_per_m": self.contact_stiffness_n_per_m,
                "smoothing_m": self.smoothing_m, "small_load_n": self.small_load_n,
                "no_clearance_contact_stiffness_n_per_m": self.no_clearance_contact_stiffness_n_per_m,
                "rigid_cardan_stiffness_n_per_m": self.rigid_cardan_stiffness_n_per_m,
                "max_residual": self.max_residual, "answers": self.answers(),
                "table": [dict(zip(header, r)) for r in rows]}

    def answers(self) -> list[dict[str, Any]]:
        """Per clearance: the critical preload, and the small-load and press-load stiffness it buys."""
        out, b = [], self.baseline
        for g, gap in enumerate(self.clearances_m):
            ok = np.flatnonzero(self.preloads >= self.critical_preload[g])
            best = int(ok[0]) if ok.size else None
            out.append({
                "clearance_m": float(gap), "critical_preload": float(self.critical_preload[g]),
                "lost_motion_without_preload_m": float(self.lost_motion_m[g, b]),
                "small_load_secant_without_preload_n_per_m": float(self.small_load_secant_stiffness_n_per_m[g, b]),
                "press_secant_without_preload_n_per_m": float(self.press_secant_stiffness_n_per_m[g, b]),
                "first_sufficient_preload": None if best is None else float(self.preloads[best]),
                "small_load_secant_with_it_n_per_m": None if best is None
                else float(self.small_load_secant_stiffness_n_per_m[g, best]),
                "press_secant_with_it_n_per_m": None if best is None
                else float(self.press_secant_stiffness_n_per_m[g, best]),
            })
        return out


def _opt(v: float) -> float | str:
    return "" if np.isnan(v) else float(v)


def preload_study(machine: Machine, pose_m: Any, clearances_m: Any, preloads: Any, load_max_n: float = 700.0,
                  steps: int = 50, *, direction: Any = (0.0, 1.0, 0.0), preload_mode: str = "force",
                  template: Clearance | None = None, geometry: str | None = None,
                  progress: bool = True) -> PreloadStudy:
    """Load-deflection curves (loading, small-displacement solver) for every clearance (a number: m, uniform
    on the eight cardans with the contact law and geometry of ``template`` or the machine, ``geometry``
    overriding it; or a :class:`Clearance`; an empty list: ``template`` itself; all of one geometry) and
    preload (N, or m in length mode), 0..load_max_n (N) in ``steps`` steps along ``direction``; plus the
    critical preload per clearance.

    With n legs the preload is the amplitude along the first basis vector of the preload space
    (:func:`pressfit.mechanics.preload.along_first_vector`: leg 4 pulls, legs 5..n carry nothing); a 3-leg
    machine has no preload and takes the preload 0 only (any other: PreloadError). The critical preload is NaN
    on both (:data:`NO_CRITICAL_PRELOAD`). The preload a4 = 0 (the baseline "without preload") is always part of
    the grid; preloads are sorted. The small-load stiffness is the secant at the stated load
    ``SMALL_LOAD_FRACTION * load_max_n`` from its own solve (independent of ``steps``); it includes the lost
    motion a joint's play allows."""
    pose = kinematics.require_reachable(machine, pose_m)
    d = _direction(direction)
    pre = np.unique(np.append(np.atleast_1d(np.asarray(preloads, float)), 0.0))
    base = template or Clearance.uniform(machine)
    base = base if geometry is None else replace(base, geometry=geometry)
    variants = [c if isinstance(c, Clearance) else base.with_gap(float(c)) for c in clearances_m] or [base]
    gaps = np.array([float(c.gaps_m.mean()) for c in variants])
    if len({c.geometry for c in variants}) != 1:
        raise ClearanceError("a preload study compares clearances of one geometry, got "
                             f"{sorted({c.geometry for c in variants})}", key="clearances_m")
    if pre.size == 0 or not np.all(np.isfinite(pre)):
        raise ClearanceError("give at least one finite preload", key="preloads")
    if not (load_max_n > 0 and steps >= 2):
        raise ClearanceError("load_max_n must be positive and steps >= 2",
                             key="steps" if load_max_n > 0 else "load_max_n")
    loads = np.linspace(0.0, float(load_max_n), int(steps) + 1)
    small = np.array([0.0, SMALL_LOAD_FRACTION * float(load_max_n)])
    curves, secants, res = [], [], 0.0
    for var in tqdm(variants, desc="preload study", unit="clearance", disable=not progress):
        cls = [var] * len(pre)
        offsets = np.array([rest_length_offsets(machine, pose, along_first_vector(machine, a), preload_mode, var)
                            for a in pre])
        up, _ = _sweep_small(machine, pose, d, loads, cls, offsets, unload=False)
        eff = var.effective_gaps_m(machine, pose)
        curves.append([LoadDeflection(pose_m=pose, direction=d, preload=float(a), preload_mode=preload_mode,
                                      method="small", clearance=var, effective_gaps_m=eff,
                                      loading=_branch(loads, up, p), unloading=None)
                       for p, a in enumerate(pre)])
        at, _ = _sweep_small(machine, pose, d, small, cls, offsets, unload=False)
        secants.append(small[1] / ((at[1]["displacement_m"] - at[0]["displacement_m"]) @ d))
        res = max(res, max(float(s["residual"].max()) for s in up + at))
    crit = [c.preload for c in critical_preloads(machine, pose, d, load_max_n, variants, preload_mode, steps)] \
        if machine.redundancy == 1 else [np.nan] * len(variants)
    contact = load_deflection(machine, pose, d, np.array([0.0, 0.5, 1.0]) * small[1], base.with_gap(0.0), unload=False)
    rigid = 1.0 / float(d @ condensed.condensed_plate_compliance(machine, pose[None])[0, :3, :3] @ d)

    def grid(f: Any) -> np.ndarray:
        return np.array([[f(c) for c in row] for row in curves])

    return PreloadStudy(
        pose_m=pose, direction=d, preload_mode=preload_mode, clearances_m=gaps,
        clearance_geometry=variants[0].geometry, preloads=pre, loads_n=loads,
        deflection_m=grid(lambda c: c.deflection_m), small_load_n=float(small[1]),
        small_load_secant_stiffness_n_per_m=np.array(secants),
        press_stiffness_n_per_m=grid(lambda c: c.press_stiffness_n_per_m),
        press_secant_stiffness_n_per_m=grid(lambda c: c.press_secant_stiffness_n_per_m),
        lost_motion_m=grid(lambda c: c.lost_motion_m),
        first_opening_load_n=grid(lambda c: np.nanmin(c.opening_loads_n) if np.any(~np.isnan(c.opening_loads_n))
                                  else np.nan),
        critical_preload=np.array(crit),
        no_clearance_contact_stiffness_n_per_m=contact.press_secant_stiffness_n_per_m,
        rigid_cardan_stiffness_n_per_m=rigid, max_residual=res,
        contact_stiffness_n_per_m=base.contact_stiffness_n_per_m, smoothing_m=base.smoothing_m)


def study_from_case(case: Any) -> dict[str, Any]:
    """Keyword arguments of :func:`preload_study` (plus ``machine``) from a case with a ``[study]`` table."""
    if case.study is None:
        raise ClearanceError(f"{case.path}: no [study] table", key="study", path=case.path)
    if case.loads.press_force_n is None or len(case.poses.array()) != 1:
        raise ClearanceError(f"{case.path}: a preload study needs one pose in [poses] and [loads] press_force_n",
                             key="loads.press_force_n" if case.loads.press_force_n is None else "poses",
                             path=case.path)
    machine = case.machine()
    return {"machine": machine, "pose_m": case.poses.array()[0], "clearances_m": list(case.study.clearances_m),
            "preloads": list(case.study.preloads), "load_max_n": case.loads.press_force_n,
            "steps": case.study.steps, "direction": case.loads.direction, "preload_mode": case.preload.mode,
            "template": clearance_from_case(case, machine)}


def format_answers(study: PreloadStudy) -> str:
    """The user's question answered per clearance, one line each (SI)."""
    unit = "N" if study.preload_mode == "force" else "m"
    pose, direction = (", ".join(f"{c:.4g}" for c in v) for v in (study.pose_m, study.direction))
    lines = [f"pose ({pose}) m, load 0..{study.loads_n[-1]:g} N along ({direction}); stiffness without clearance: "
             f"{study.no_clearance_contact_stiffness_n_per_m:.4g} N/m with the cardan contact springs "
             f"({study.contact_stiffness_n_per_m:.3g} N/m each) in series, {study.rigid_cardan_stiffness_n_per_m:.4g}"
             f" N/m with rigid cardans (as 'pressfit stiffness'); small-load secant at {study.small_load_n:g} N; "
             f"clearance geometry {GEOMETRY_DESCRIPTIONS[study.clearance_geometry]}"]
    for a in study.answers():
        crit = NO_CRITICAL_PRELOAD if math.isnan(a["critical_preload"]) else \
            f"critical preload {a['critical_preload']:.4g} {unit}"
        s = (f"g = {a['clearance_m'] * 1e6:g} um: {crit}; without "
             f"preload lost motion {a['lost_motion_without_preload_m'] * 1e6:.3g} um, small-load secant "
             f"{a['small_load_secant_without_preload_n_per_m']:.3g} N/m, secant at the load "
             f"{a['press_secant_without_preload_n_per_m']:.3g} N/m")
        if a["first_sufficient_preload"] is not None:
            s += (f"; with a4 = {a['first_sufficient_preload']:g} {unit}: {a['small_load_secant_with_it_n_per_m']:.3g}"
                  f" N/m and {a['press_secant_with_it_n_per_m']:.3g} N/m")
        elif not math.isnan(a["critical_preload"]):
            s += "; no preload in the list is sufficient"
        lines.append(s)
    return "\n".join(lines)
