"""``pressfit study design``: the case's design study on Dask (:mod:`pressfit.studies.design`), its best designs
built as machines, and its directory written atomically (:mod:`pressfit.output.design_files`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pressfit.description.cases import Case
from pressfit.description.machine import Machine
from pressfit.output import files as io
from pressfit.output.design_files import write_design
from pressfit.studies import design


@dataclass(frozen=True)
class DesignRun:
    result: design.DesignResult
    written: list[Path]


def best_machines(result: design.DesignResult) -> dict[int, Machine]:
    """The machine of every best trial (:meth:`pressfit.studies.design.DesignResult.best`), by trial."""
    c, params = result.columns, list(result.plan.parameters())
    return {i: design.design_machine(result.plan, {k: float(c[k][i]) for k in params}) for i in result.best()}


def run_design_study(case: Case, out_dir: Path | str, *, trials: int | None = None, workers: int | None = None,
                     scheduler: str | None = None, overwrite: bool = False, progress: bool = True,
                     dashboard: bool = False) -> DesignRun:
    """Run the case's design study on Dask and write its directory atomically (nothing existing is
    replaced without ``overwrite``)."""
    plan = design.plan_from_case(case, trials)
    io.check_directory(out_dir, overwrite)
    source = case.machine().source
    inputs = [p for p in (case.path, source) if p and Path(str(p)).is_file()]  # a designs/*.toml never replaces them
    io.check_inputs_outside(out_dir, inputs)
    result = design.run_design(plan, workers=workers, scheduler=scheduler, progress=progress, dashboard=dashboard)
    return DesignRun(result, io.write_directory(out_dir, overwrite,
                                                lambda tmp: write_design(result, tmp, best_machines(result)),
                                                inputs=inputs))
