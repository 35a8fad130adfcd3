r"""Design study: which base and plate size, leg sections and actuator stiffness minimise the case's objectives
under its constraints (``[design]`` of a case file, :class:`pressfit.description.cases.Design`).

Each design is the case's machine with the parameters set (:data:`DESIGN_PARAMETERS`; the collision radii
of cylinder and stem follow the diameters). It is evaluated over the required square at ``height_levels``
heights spanning ``heights_m`` on a ``grid_xz`` x ``grid_xz`` grid, under every ``[loads]`` wrench, with the
exact condensed linear model (:mod:`pressfit.mechanics.condensed`; rigid, clearance-free cardans, which is
what a design comparison needs), batched over poses (:func:`pressfit.studies.workspace_envelope.load_envelope`):

* ``peak_torsion_nm``, ``peak_bending_nm``, ``peak_axial_force_n``: the worst |T|, hypot(M_x, M_y) and |N|
  over poses, loads and legs (N m, N);
* ``max_vertical_compliance_m_per_n``: the largest C_yy of the plate compliance at the plate centre
  (vertical displacement per vertical force, rotations free; m/N); its inverse is the minimum vertical
  stiffness ``min_vertical_stiffness_n_per_m``;
* ``moving_mass_kg``: every body the machine moves (legs, cardans, plate and tool) from the machine's
  ``[mass]`` data (:func:`pressfit.dynamics.inertia.inertial_model` at the reference pose, kg);
* ``height_min_m``, ``height_max_m``: the heights where the whole required square is reachable
  (:func:`pressfit.kinematics.workspace.square_height_range`); the design must cover ``heights_m``.

Constraint violations are relative (violation / limit, summed; 0 = feasible); a design whose square is
reachable at no height, or whose parameters make an invalid machine (e.g. plate not smaller than base),
fails (``status``). The Pareto front: the feasible designs no other feasible design dominates (every
objective <=, one <). Search: Optuna's NSGA-II (seeded; generations of ``population`` designs asked
together, evaluated on Dask and told in trial order, so the result does not depend on the number of
workers) or a full grid.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from pressfit import kinematics
from pressfit.description.cases import DESIGN_PARAMETERS, Case, Design
from pressfit.description.machine import Machine
from pressfit.dynamics.inertia import inertial_model, total_mass_kg
from pressfit.errors import PressfitError
from pressfit.kinematics.workspace import square_height_range, workspace_box
from pressfit.mechanics.condensed import condensed_plate_compliance
from pressfit.mechanics.model import build_model
from pressfit.studies import distributed
from pressfit.studies.workspace_envelope import load_envelope

METRICS = ("peak_torsion_nm", "peak_bending_nm", "peak_axial_force_n", "moving_mass_kg",
           "max_vertical_compliance_m_per_n", "height_min_m", "height_max_m")
CONSTRAINTS = {  # [design.constraints] key -> (metric, sense): the metric must stay below (max) / above (min)
    "max_peak_torsion_nm": ("peak_torsion_nm", "max"), "max_peak_bending_nm": ("peak_bending_nm", "max"),
    "max_peak_axial_force_n": ("peak_axial_force_n", "max"), "max_moving_mass_kg": ("moving_mass_kg", "max"),
    "min_vertical_stiffness_n_per_m": ("max_vertical_compliance_m_per_n", "inverse")}


@dataclass(frozen=True, kw_only=True)
class DesignPlan:
    """Everything a worker needs (picklable): the case's machine, its load wrenches (W, 6) (N, N m) and
    ``[design]`` table."""

    name: str
    machine: Machine
    wrenches: np.ndarray
    design: Design

    def parameters(self) -> dict[str, tuple[float, float]]:
        return self.design.parameters.ranges()

    def columns(self) -> list[str]:
        return ["trial", "status", *self.parameters(), *METRICS, "violation", "feasible"]


def plan_from_case(case: Case, trials: int | None = None) -> DesignPlan:
    """The design study of a case with a ``[design]`` table (``trials`` overrides its number of trials)."""
    if case.design is None:
        raise PressfitError(f"{case.path}: a design study needs a [design] table with [design.parameters]")
    if trials is not None and trials < 1:
        raise PressfitError(f"the number of trials must be at least 1, got {trials}")
    design = case.design if trials is None else case.design.model_copy(update={"trials": trials})
    return DesignPlan(name=case.name, machine=case.machine(), wrenches=case.loads.wrenches(), design=design)


def design_machine(plan: DesignPlan, params: dict[str, float]) -> Machine:
    """The machine of one design: the parameters (SI) set on the case's machine; the collision radii of
    cylinder and stem follow their diameters. Raises ModelFileError for an invalid machine."""
    over: dict[str, dict[str, float]] = {}
    for name, value in params.items():
        table, key = DESIGN_PARAMETERS[name].split(".")
        over.setdefault(table, {})[key] = float(value)
    col = {}
    if "cylinder_outer_diameter_m" in params:
        col["cylinder_radius_m"] = 0.5 * float(params["cylinder_outer_diameter_m"])
    if "stem_diameter_m" in params:
        col["stem_radius_m"] = 0.5 * float(params["stem_diameter_m"])
    if col:
        over["collision"] = col
    text = ", ".join(f"{k} = {v:.6g}" for k, v in params.items())
    return plan.machine.with_overrides(over, source=f"{plan.machine.source} [design: {text}]")


def evaluate_design(plan: DesignPlan, params: dict[str, float]) -> dict[str, float]:
    """The :data:`METRICS` of one design (module doc), SI. Raises PressfitError for a design that fails."""
    d = plan.design
    machine = design_machine(plan, params)
    hr = square_height_range(machine)
    ys = np.linspace(d.heights_m[0], d.heights_m[1], d.height_levels)
    env = load_envelope(machine, ys, n_xz=d.grid_xz, loads_n=plan.wrenches, progress=False)
    poses = workspace_box(machine, ys, d.grid_xz).reshape(-1, 3)
    poses = poses[kinematics.is_reachable(machine, poses)]
    compliance = condensed_plate_compliance(machine, poses)[:, 1, 1]
    axial = max(float(env.entries["tension_n"].value.max()), float(env.entries["compression_n"].value.max()))
    mass = total_mass_kg(inertial_model(build_model(machine, kinematics.reference_pose_m(machine),
                                                    springs_per_segment=1)))
    return {"peak_torsion_nm": float(env.entries["torsion_nm"].value.max()),
            "peak_bending_nm": float(env.entries["bending_nm"].value.max()), "peak_axial_force_n": axial,
            "moving_mass_kg": mass, "max_vertical_compliance_m_per_n": float(compliance.max()),
            "height_min_m": hr.y_min_m, "height_max_m": hr.y_max_m}


def violation(plan: DesignPlan, metrics: dict[str, float]) -> float:
    """Sum of the relative constraint violations (0: feasible), the required heights included."""
    d = plan.design
    span = max(d.heights_m[1] - d.heights_m[0], 1e-3)
    lo, hi = d.heights_m
    total = (max(0.0, metrics["height_min_m"] - lo) + max(0.0, hi - metrics["height_max_m"])) / span
    for key, limit in d.constraints.model_dump().items():
        if limit is None:
            continue
        metric, sense = CONSTRAINTS[key]
        value = metrics[metric] if sense == "max" else 1.0 / metrics[metric]
        total += max(0.0, (value - limit) / limit if sense == "max" else (limit - value) / limit)
    return total


def evaluate_designs(plan: DesignPlan, first_trial: int, params: list[dict[str, float]]) -> dict[str, np.ndarray]:
    """A chunk of designs (the task a worker runs): parameters, metrics, violation and status, as columns."""
    rows, status = [], []
    for p in params:
        try:
            m = evaluate_design(plan, p)
            rows.append(m | {"violation": violation(plan, m)})
            status.append("ok")
        except PressfitError as exc:
            rows.append(dict.fromkeys((*METRICS, "violation"), math.nan))
            status.append(type(exc).__name__)
    cols: dict[str, np.ndarray] = {"trial": np.arange(first_trial, first_trial + len(params), dtype=np.int64),
                                   "status": np.array(status)}
    cols.update({k: np.array([p[k] for p in params], dtype=float) for k in plan.parameters()})
    cols.update({k: np.array([r[k] for r in rows]) for k in (*METRICS, "violation")})
    cols["feasible"] = (cols["status"] == "ok") & (cols["violation"] == 0.0)
    return cols


def pareto_mask(objectives: np.ndarray, feasible: np.ndarray) -> np.ndarray:
    """(n,) True for the feasible rows of ``objectives`` (n, k) (minimised) that no feasible row dominates."""
    f = objectives[feasible]
    le = (f[:, None, :] <= f[None, :, :]).all(-1)
    lt = (f[:, None, :] < f[None, :, :]).any(-1)
    dominated = (le & lt).any(0)  # row j dominated by some row i
    out = np.zeros(len(objectives), dtype=bool)
    out[np.flatnonzero(feasible)[~dominated]] = True
    return out


@dataclass(frozen=True, kw_only=True)
class DesignResult:
    """Every trial as columns (:meth:`DesignPlan.columns` plus ``pareto``), and the Pareto rows by the
    first objective."""

    plan: DesignPlan
    columns: dict[str, np.ndarray]
    pareto: np.ndarray  # trial indices on the front, sorted by the first objective

    def best(self) -> list[int]:
        """Up to ``[design] best`` trials spread evenly along the front (its two ends first)."""
        n, k = len(self.pareto), self.plan.design.best
        return [int(self.pareto[i]) for i in sorted({round(j * (n - 1) / max(k - 1, 1)) for j in range(min(k, n))})]


def _grid(plan: DesignPlan) -> list[dict[str, float]]:
    axes = {k: np.linspace(lo, hi, plan.design.grid_points) for k, (lo, hi) in plan.parameters().items()}
    return [dict(zip(axes, map(float, v))) for v in itertools.product(*axes.values())]


def _chunks(params: list[dict[str, float]], first: int, size: int) -> list[tuple[int, list[dict[str, float]]]]:
    return [(first + i, params[i:i + size]) for i in range(0, len(params), size)]


def _evaluate(plan: DesignPlan, client: object, params: list[dict[str, float]], first: int,
              progress: bool) -> dict[str, np.ndarray]:
    size = max(1, math.ceil(len(params) / 32))
    chunks = _chunks(params, first, size)
    out: dict[int, dict[str, np.ndarray]] = {}
    distributed.run_chunks(evaluate_designs, [(plan, a, p) for a, p in chunks], [len(p) for _, p in chunks],
                           out.__setitem__, client=client, progress=progress, name="design")  # type: ignore[arg-type]
    return {k: np.concatenate([out[i][k] for i in range(len(chunks))]) for k in out[0]}


def _nsga2(plan: DesignPlan, client: object, progress: bool) -> dict[str, np.ndarray]:
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    d = plan.design
    sampler = optuna.samplers.NSGAIISampler(population_size=d.population, seed=d.seed)
    study = optuna.create_study(directions=["minimize"] * len(d.objectives), sampler=sampler)
    space = {k: optuna.distributions.FloatDistribution(lo, hi) for k, (lo, hi) in plan.parameters().items()}
    parts: list[dict[str, np.ndarray]] = []
    while (done := sum(len(p["trial"]) for p in parts)) < d.trials:
        trials = [study.ask(space) for _ in range(min(d.population, d.trials - done))]
        cols = _evaluate(plan, client, [t.params for t in trials], done, progress)
        for j, t in enumerate(trials):
            if cols["status"][j] != "ok":
                study.tell(t, state=optuna.trial.TrialState.FAIL)
                continue
            t.set_constraint("violation", float(cols["violation"][j]))
            study.tell(t, [float(cols[k][j]) for k in d.objectives])
        parts.append(cols)
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def run_design(plan: DesignPlan, *, workers: int | None = None, scheduler: str | None = None,
               progress: bool = True, dashboard: bool = False) -> DesignResult:
    """Search the design space on Dask (module doc) and return every trial with the Pareto front."""
    with distributed.connect(workers, scheduler, dashboard) as client:
        cols = _nsga2(plan, client, progress) if plan.design.search == "nsga2" else \
            _evaluate(plan, client, _grid(plan), 0, progress)
    objectives = np.column_stack([cols[k] for k in plan.design.objectives])
    cols["pareto"] = pareto_mask(objectives, cols["feasible"])
    front = np.flatnonzero(cols["pareto"])
    return DesignResult(plan=plan, columns=cols, pareto=front[np.argsort(objectives[front, 0], kind="stable")])
