"""``pressfit simulate`` (the case file's insertion, with and without the limiter, and its drive sizing) and
``pressfit study insertion`` (the insertion over preload and joint clearance): the physics of
:mod:`pressfit.dynamics.insertion`, :mod:`pressfit.dynamics.sizing` and :mod:`pressfit.studies.insertion_study`,
the files of :mod:`pressfit.output.simulation`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pressfit.description.cases import load_case
from pressfit.dynamics.insertion import simulate_insertion
from pressfit.dynamics.sizing import size_insertion
from pressfit.output import files as io
from pressfit.output.simulation import simulation_summary, write_insertion_study, write_simulation
from pressfit.studies.insertion_study import InsertionStudy, insertion_study


def run_simulation(case_path: Path | str, out_dir: Path | None, limiter: bool = True, overwrite: bool = False,
                   progress: bool = False) -> tuple[dict[str, Any], list[Path]]:
    """Simulate the case file's insertion (:func:`pressfit.dynamics.insertion.simulate_insertion`); with the
    limiter on, the same scenario also runs without it (the comparison of the contact-force plot and of the
    summary's ``"comparison"``) and, for the drive sizing's preload cost, with ``[preload] a4_n`` = 0
    (:func:`pressfit.dynamics.sizing.size_insertion`). The summary, and the files in ``out_dir`` if given (checked
    before the simulation, written through a temporary directory: :func:`pressfit.output.files.write_directory`)."""
    if out_dir is not None:
        io.check_directory(out_dir, overwrite)  # before computing
    case = load_case(case_path)
    result = simulate_insertion(case, limiter, progress)
    comparison = simulate_insertion(case, False, progress) if limiter else None
    sizing = size_insertion(case, result, limiter, progress)
    paths = [] if out_dir is None else io.write_directory(
        out_dir, overwrite, lambda tmp: write_simulation(result, tmp, comparison=comparison, sizing=sizing),
        inputs=[Path(case_path), *([case.machine().source] if case.machine().source else [])])
    return simulation_summary(result, comparison, sizing), paths


def run_insertion_study(case_path: Path | str, preloads_n: list[float] | None, clearances_m: list[float] | None,
                        out_dir: Path, overwrite: bool = False, progress: bool = False) -> tuple[InsertionStudy,
                                                                                                  list[Path]]:
    """The insertion study of a case file (:func:`pressfit.studies.insertion_study.insertion_study`; defaults:
    preloads 0 N and the case's a4, clearances 10 and 50 um) and its files in ``out_dir``."""
    io.check_directory(out_dir, overwrite)
    case = load_case(case_path)
    study = insertion_study(case, preloads_n or sorted({0.0, case.preload.a4_n}), clearances_m or [1e-5, 5e-5],
                            progress)
    source = case.machine().source
    return study, io.write_directory(out_dir, overwrite, lambda tmp: write_insertion_study(study, tmp),
                                     inputs=[p for p in (case_path, source) if p and Path(str(p)).is_file()])
