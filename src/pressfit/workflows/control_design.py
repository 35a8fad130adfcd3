"""``pressfit control``: the control loop of a case file linearised (:func:`pressfit.dynamics.linearise.control_design`)
and its files (:mod:`pressfit.output.control`)."""

from __future__ import annotations

from pathlib import Path

from pressfit.description.cases import load_case
from pressfit.dynamics.linearise import ControlDesign, control_design
from pressfit.output import files as io
from pressfit.output.control import write_control


def run_control(case_path: Path | str, model: str | None, out_dir: Path | None,
                overwrite: bool = False) -> tuple[ControlDesign, list[Path]]:
    """:func:`pressfit.dynamics.linearise.control_design` of a case file and, with ``out_dir``, its files
    (checked before computing, written atomically)."""
    if out_dir is not None:
        io.check_directory(out_dir, overwrite)
    design = control_design(load_case(case_path), model)
    paths = io.write_directory(out_dir, overwrite, lambda tmp: write_control(design, tmp)) if out_dir else []
    return design, paths
