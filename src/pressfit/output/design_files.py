"""Design study on disk: ``trials.parquet`` (every design), ``pareto.parquet`` (the front), ``summary.json``,
``pareto.png`` and the best designs as machine files ``designs/design-NNN.toml`` (``load_machine`` reads them)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import tomli_w

from pressfit.description.cases import Case
from pressfit.output import files as io
from pressfit.studies import design


@dataclass(frozen=True)
class DesignRun:
    result: design.DesignResult
    written: list[Path]


def summary(result: design.DesignResult) -> dict[str, object]:
    """JSON-ready: counts, the front (parameters and metrics per trial) and the best designs written."""
    c = result.columns
    row = lambda i: {k: (c[k][i].item() if np.isfinite(c[k][i]) else None)
                     for k in (*result.plan.parameters(), *design.METRICS)}
    return {"trials": len(c["trial"]), "failed": int((c["status"] != "ok").sum()), "feasible": int(c["feasible"].sum()),
            "objectives": list(result.plan.design.objectives), "search": result.plan.design.search,
            "pareto": [{"trial": int(i)} | row(i) for i in result.pareto], "best": result.best()}


def pareto_figure(result: design.DesignResult) -> plt.Figure:
    """pareto.png: the trials in the plane of the first two objectives (or the first parameter and the one
    objective), infeasible in light grey, feasible in grey, the Pareto front in red."""
    c, obj = result.columns, result.plan.design.objectives
    x, y = (obj[0], obj[1]) if len(obj) > 1 else (next(iter(result.plan.parameters())), obj[0])
    fig, ax = plt.subplots(figsize=(7, 5), layout="constrained")
    ok = c["status"] == "ok"
    ax.scatter(c[x][ok & ~c["feasible"]], c[y][ok & ~c["feasible"]], s=10, c="0.75", label="infeasible")
    ax.scatter(c[x][c["feasible"]], c[y][c["feasible"]], s=12, c="0.4", label="feasible")
    ax.plot(c[x][result.pareto], c[y][result.pareto], "o-", c="r", ms=5, label="Pareto front")
    ax.set(xlabel=x, ylabel=y, title=f"{result.plan.name}: {len(c['trial'])} designs")
    ax.legend()
    return fig


def _plot(result: design.DesignResult, path: Path) -> Path:
    fig = pareto_figure(result)
    try:
        return io.save_figure(fig, path)
    finally:
        plt.close(fig)


def write_design(result: design.DesignResult, out: Path) -> list[Path]:
    """Every file of a design study into directory ``out`` (fresh: see :func:`run_design_study`)."""
    c = result.columns
    paths = [io.write_parquet(out / "trials.parquet", c),
             io.write_parquet(out / "pareto.parquet", {k: v[result.pareto] for k, v in c.items()}),
             io.write_json(out / "summary.json", summary(result)), _plot(result, out / "pareto.png")]
    params = list(result.plan.parameters())
    for i in result.best():
        m = design.design_machine(result.plan, {k: float(c[k][i]) for k in params})
        data = m.model_dump(exclude={"source"}, exclude_none=True)
        data["description"] = f"design study {result.plan.name}, trial {i}: {m.source}"
        paths.append(io.write_text(out / "designs" / f"design-{i:06d}.toml", tomli_w.dumps(data)))
    return paths


def run_design_study(case: Case, out_dir: Path | str, *, trials: int | None = None, workers: int | None = None,
                     scheduler: str | None = None, overwrite: bool = False, progress: bool = True,
                     dashboard: bool = False) -> DesignRun:
    """Run the case's design study on Dask and write its directory atomically (nothing existing is
    replaced without ``overwrite``)."""
    plan = design.plan_from_case(case, trials)
    io.check_directory(out_dir, overwrite)
    result = design.run_design(plan, workers=workers, scheduler=scheduler, progress=progress, dashboard=dashboard)
    source = case.machine().source
    inputs = [p for p in (case.path, source) if p and Path(str(p)).is_file()]  # a designs/*.toml never replaces them
    return DesignRun(result, io.write_directory(out_dir, overwrite, lambda tmp: write_design(result, tmp),
                                                inputs=inputs))
