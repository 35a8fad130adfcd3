"""``pressfit cycle``: a whole board simulated (:func:`pressfit.dynamics.cycle.simulate_cycle`) and its files
(:mod:`pressfit.output.cycle`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pressfit.description.cases import load_case
from pressfit.dynamics.cycle import simulate_cycle
from pressfit.output import files as io
from pressfit.output.cycle import write_cycle


def run_cycle(case_path: Path | str, model: str | None, out_dir: Path | None, overwrite: bool = False,
              progress: bool = False) -> tuple[dict[str, Any], list[Path]]:
    """Simulate the case file's board (:func:`pressfit.dynamics.cycle.simulate_cycle`); the summary, and the
    files in ``out_dir`` if given (checked before the simulation, written through a temporary directory)."""
    if out_dir is not None:
        io.check_directory(out_dir, overwrite)  # before computing
    case = load_case(case_path)
    result = simulate_cycle(case, model, progress)
    source = case.machine().source
    paths = [] if out_dir is None else io.write_directory(
        out_dir, overwrite, lambda tmp: write_cycle(result, tmp),
        inputs=[Path(case_path), *([source] if source else [])])
    return result.summary, paths
