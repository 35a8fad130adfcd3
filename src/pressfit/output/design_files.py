"""Design study on disk: ``trials.parquet`` (every design), ``pareto.parquet`` (the front), ``summary.json``,
``pareto.png`` and the best designs as machine files ``designs/design-NNN.toml`` (``load_machine`` reads them)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import tomli_w

from pressfit.output import files as io
from pressfit.studies.design import METRICS

if TYPE_CHECKING:
    from pressfit.description.machine import Machine
    from pressfit.studies import design


def summary(result: design.DesignResult) -> dict[str, object]:
    """JSON-ready: counts, the front (parameters and metrics per trial) and the best designs written."""
    c = result.columns
    row = lambda i: {k: (c[k][i].item() if np.isfinite(c[k][i]) else None)
                     for k in (*result.plan.parameters(), *METRICS)}
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


def write_design(result: design.DesignResult, out: Path, best: dict[int, Machine]) -> list[Path]:
    """Every file of a design study into directory ``out`` (fresh: see
    :func:`pressfit.workflows.design_study.run_design_study`); ``best``: the machine of each best trial
    (:meth:`DesignResult.best`), written as ``designs/design-NNNNNN.toml``."""
    c = result.columns
    paths = [io.write_parquet(out / "trials.parquet", c),
             io.write_parquet(out / "pareto.parquet", {k: v[result.pareto] for k, v in c.items()}),
             io.write_json(out / "summary.json", summary(result)), _plot(result, out / "pareto.png")]
    for i, m in best.items():
        data = m.model_dump(exclude={"source"}, exclude_none=True)
        data["description"] = f"design study {result.plan.name}, trial {i}: {m.source}"
        paths.append(io.write_text(out / "designs" / f"design-{i:06d}.toml", tomli_w.dumps(data)))
    return paths
