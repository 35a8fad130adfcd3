"""Throughput study (``pressfit study cycle``, issue 20 item 5): the board's motion limits swept on Dask, the Pareto
front of cycle time against the worst alignment error and the worst force overshoot, and the fastest setting that
keeps every pin within its limits.

The grid is the case's ``[cycle.study]`` (:class:`pressfit.description.cases.CycleStudy`): every combination of the
scale factors on ``[cycle.motion]``'s speed, acceleration and jerk, on the descent's three limits and on the
controller's three gains, and of the commanded preloads. Each sample is
one board run (:func:`pressfit.dynamics.cycle.simulate_cycle`, the case's model, without the drive sizing) and
reports the planned cycle time (s), the worst pin's lateral alignment error at first contact (m; infinite for a
pin never touched) and the worst overshoot over its insertion limit (N). A setting keeps every pin within its
limits (:func:`pin_within_limits`) when every pin completes its insertion, its peak contact force stays within its
force limit plus the overshoot allowed (the pin's or ``[cycle.limits]``' ``max_overshoot_n``; none when not
given: a pin's force limit is a limit), and its alignment error within the pin's or ``[cycle.limits]``'
``max_alignment_error_m`` where one is given; :func:`judged_limits` says which limits a board is judged on. A
sample the planner refuses (a scaled move the drives cannot follow, ...) or whose run fails is recorded with its
reason, not on the front. Every variant is validated before the cluster starts (the scaled limits must satisfy
:class:`pressfit.description.cases.MotionLimits`; an error names ``[cycle.study]``, the factor and the file).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import ValidationError

from pressfit.description.cases import Case, MotionLimits, ResolvedPin
from pressfit.errors import ModelFileError, PressfitError

FACTORS = ("speed_scale", "acceleration_scale", "jerk_scale", "descent_scale", "kp_scale", "kd_scale", "ki_scale",
           "a4_n")  # a sample's setting, in this order
FACTOR_LABELS = {"speed_scale": "speed x", "acceleration_scale": "acceleration x", "jerk_scale": "jerk x",
                 "descent_scale": "descent x", "kp_scale": "kp x", "kd_scale": "kd x", "ki_scale": "ki x",
                 "a4_n": "a4 [N]"}
FIGURES = ("cycle_time_s", "worst_alignment_error_m", "worst_overshoot_n", "pins_passed")
FRONT_FIGURES = ("cycle_time_s", "worst_alignment_error_m", "worst_overshoot_n", "within_limits")  # front tables
Setting = tuple[float, ...]  # the values of FACTORS


def grid(case: Case) -> list[Setting]:
    """The study's samples (the values of ``FACTORS``), the last varying fastest."""
    if case.cycle is None or case.cycle.study is None:
        raise PressfitError(f"{case.path}: the case has no [cycle.study] table (the grid of scale factors)")
    s = case.cycle.study
    values = [getattr(s, k) for k in FACTORS[:-1]] + [s.a4_n or [case.preload.a4_n]]
    return list(itertools.product(*values))


def _scaled(case: Case, table: MotionLimits, factors: tuple[float, float, float], keys: str) -> MotionLimits:
    """``table`` with its speed, acceleration and jerk scaled; ModelFileError naming ``keys`` otherwise."""
    try:
        return MotionLimits(speed_m_per_s=table.speed_m_per_s * factors[0], profile=table.profile,
                            acceleration_m_per_s2=table.acceleration_m_per_s2 * factors[1],
                            jerk_m_per_s3=table.jerk_m_per_s3 * factors[2])
    except ValidationError as exc:
        raise ModelFileError(case.path, f"[cycle.study] {keys}", "factors that keep the limits within their bounds: "
                             f"({', '.join(f'{f:g}' for f in factors)}) gives {exc.errors()[0]['loc'][0]}: "
                             f"{exc.errors()[0]['msg']}") from None


def variant(case: Case, setting: Setting) -> Case:
    """The case with the sample's setting (``FACTORS``: motion and descent limits and gains scaled, the preload
    set; a simulation's preload is in force mode), validated; ModelFileError naming the factor otherwise."""
    cycle = case.cycle
    speed, acc, jerk, descent, kp, kd, ki, a4 = setting
    motion = _scaled(case, cycle.motion, (speed, acc, jerk), "speed_scale, acceleration_scale, jerk_scale")
    down = _scaled(case, cycle.descent or cycle.motion, (descent,) * 3, "descent_scale")
    g = cycle.controller
    gains = g.model_copy(update={"kp_n_per_m": g.kp_n_per_m * kp, "kd_n_s_per_m": g.kd_n_s_per_m * kd,
                                 "ki_n_per_m_s": g.ki_n_per_m_s * ki})
    return case.model_copy(update={"cycle": cycle.model_copy(update={"motion": motion, "descent": down,
                                                                     "controller": gains}),
                                   "preload": case.preload.model_copy(update={"a4_n": float(a4)})})


def within_limits(case: Case, summary: dict[str, Any]) -> bool:
    """Every pin completes its insertion and holds its limits (:func:`pin_within_limits`)."""
    pins = {p.index: p for p in case.cycle.resolved_pins()}
    return all(pin_within_limits(case, pins[p["index"]], p) for p in summary["pins"])


def pin_within_limits(case: Case, pin: ResolvedPin, result: dict[str, Any]) -> bool:
    """One pin of a run (``result``: its entry of the cycle summary's ``pins``) within its limits: the insertion
    completed; its force limit is a limit: the peak contact force at most ``force_limit_n`` plus the overshoot
    allowed (the pin's ``max_overshoot_n``, ``[cycle.limits]``' if lower; 0 N when neither is given); and the
    lateral alignment error at first contact at most the pin's or ``[cycle.limits]``' ``max_alignment_error_m``
    (the lower; a pin never touched fails), unjudged when neither is given (:func:`judged_limits` says so)."""
    allowed = [x for x in (pin.max_overshoot_n, case.cycle.limits.max_overshoot_n) if x is not None]
    if not result["insertion_completed"] or result["overshoot_n"] > min(allowed, default=0.0):
        return False
    alignment = [x for x in (pin.max_alignment_error_m, case.cycle.limits.max_alignment_error_m) if x is not None]
    lateral = result["tool_lateral_error_at_first_contact_m"]
    return not alignment or (lateral is not None and lateral <= min(alignment))


def judged_limits(case: Case) -> list[str]:
    """What :func:`within_limits` judges on this board, in words (printed and written with the study)."""
    limits = case.cycle.limits
    pins = case.cycle.resolved_pins()
    overshoot = [p.index for p in pins if p.max_overshoot_n is not None or limits.max_overshoot_n is not None]
    aligned = [p.index for p in pins if p.max_alignment_error_m is not None or limits.max_alignment_error_m is not None]
    out = ["insertion completed on every pin",
           "peak contact force at most the pin's force_limit_n" + (
               " plus its max_overshoot_n" if len(overshoot) == len(pins) else
               " (no max_overshoot_n: none allowed over it)" if not overshoot else
               f" plus its max_overshoot_n on pins {_pin_list(overshoot)}, none allowed on the others")]
    if not aligned:
        out.append("alignment error not judged (no max_alignment_error_m on the pins or in [cycle.limits])")
    else:
        out.append("alignment error at most max_alignment_error_m" + (
            "" if len(aligned) == len(pins) else f" on pins {_pin_list(aligned)} (the others not judged)"))
    return out


def _pin_list(indices: list[int]) -> str:
    return ", ".join(str(k) for k in indices)


def _worst(summary: dict[str, Any]) -> dict[str, float]:
    pins = summary["pins"]
    align = [math.inf if p["tool_lateral_error_at_first_contact_m"] is None else
             p["tool_lateral_error_at_first_contact_m"] for p in pins]
    return {"worst_alignment_error_m": float(max(align)),
            "worst_overshoot_n": float(max(p["overshoot_n"] for p in pins))}


def run_sample(case: Case, model: str | None, factors: Setting) -> dict[str, Any]:
    """One board run (a Dask task): the figures (``FIGURES``), ``within_limits`` and ``error`` ("" when it ran)."""
    from pressfit.dynamics.cycle import simulate_cycle

    try:
        varied = variant(case, factors)
        s = simulate_cycle(varied, model, sizing=False).summary
    except PressfitError as exc:
        return {"cycle_time_s": math.nan, "worst_alignment_error_m": math.nan, "worst_overshoot_n": math.nan,
                "pins_passed": 0, "within_limits": False, "error": " ".join(str(exc).split())}
    return {"cycle_time_s": s["cycle_time_s"], **_worst(s), "pins_passed": s["pins_passed"],
            "within_limits": within_limits(varied, s), "error": ""}


def pareto_front(objectives: np.ndarray) -> np.ndarray:
    """Indices of the non-dominated rows of (n, k) objectives, all minimised (a row with a NaN is never on it)."""
    ok = np.flatnonzero(~np.any(np.isnan(objectives), axis=1))
    front = []
    for i in ok:
        o = objectives[i]
        dominated = np.any(np.all(objectives[ok] <= o, axis=1) & np.any(objectives[ok] < o, axis=1))
        if not dominated:
            front.append(int(i))
    return np.array(front, dtype=int)


@dataclass(frozen=True, kw_only=True)
class CycleStudyResult:
    """Every sample (``columns``: the factors, ``FIGURES``, ``within_limits``, ``on_front``, ``error``), the front
    (indices, by cycle time), and the fastest sample within the limits (None: none is)."""

    case: Case
    columns: dict[str, np.ndarray]
    front: np.ndarray
    fastest: int | None
    model: str

    def summary(self) -> dict[str, Any]:
        """JSON-ready: counts, the front's rows and the fastest row (non-finite figures as None)."""
        c = self.columns

        def value(x: Any) -> Any:  # JSON: a NaN (refused sample) or an infinite alignment (a pin never touched)
            x = x.item() if hasattr(x, "item") else x  # is null, as cycle.json's error of a pin never touched
            return None if isinstance(x, float) and not math.isfinite(x) else x

        def row(i: int) -> dict[str, Any]:
            return {"sample": i, **{k: value(v[i]) for k, v in c.items()}}

        return {"case": self.case.name, "model": self.model, "samples": len(c["cycle_time_s"]),
                "failed": int(sum(bool(e) for e in c["error"])), "within_limits": int(c["within_limits"].sum()),
                "limits_judged": judged_limits(self.case), "front": [row(int(i)) for i in self.front],
                "fastest_within_limits": None if self.fastest is None else row(self.fastest)}


def cycle_study(case: Case, model: str | None = None, workers: int | None = None, scheduler: str | None = None,
                progress: bool = True, dashboard: bool = False) -> CycleStudyResult:
    """Run the grid on Dask (:func:`pressfit.studies.distributed.run_chunks`, one board per task) and rank it
    (module docstring). Every variant is validated first."""
    from pressfit.dynamics.cycle import plan_cycle
    from pressfit.studies.distributed import run_chunks

    samples = grid(case)
    plan_cycle(variant(case, samples[0]), model=model)  # the board itself is valid (refused at once, not n times)
    for f in samples:
        variant(case, f)
    results: dict[int, dict[str, Any]] = {}
    run_chunks(run_sample, [(model, f) for f in samples], [1] * len(samples), results.__setitem__,
               workers=workers, scheduler=scheduler, progress=progress, name="cycle study", shared=case,
               dashboard=dashboard)
    rows = [results[k] for k in range(len(samples))]
    columns: dict[str, np.ndarray] = {k: np.array([f[j] for f in samples]) for j, k in enumerate(FACTORS)}
    for k in FIGURES:
        columns[k] = np.array([r[k] for r in rows], dtype=int if k == "pins_passed" else float)
    columns["within_limits"] = np.array([r["within_limits"] for r in rows], dtype=bool)
    columns["error"] = np.array([r["error"] for r in rows], dtype=object)
    objectives = np.column_stack([columns[k] for k in FIGURES[:3]])
    front = pareto_front(objectives)
    front = front[np.argsort(columns["cycle_time_s"][front], kind="stable")]
    on = np.zeros(len(samples), dtype=bool)
    on[front] = True
    columns["on_front"] = on
    ok = np.flatnonzero(columns["within_limits"])
    fastest = int(ok[np.argmin(columns["cycle_time_s"][ok])]) if ok.size else None
    return CycleStudyResult(case=case, columns=columns, front=front, fastest=fastest, model=model or case.cycle.model)
