"""``pressfit modes``: the natural modes at a pose (:mod:`pressfit.dynamics.modes`) and their files
(:mod:`pressfit.output.modal`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pressfit.description.machine import Machine
from pressfit.dynamics.modes import Modes, natural_modes
from pressfit.output import files as io
from pressfit.output.modal import write_modes


def run_modes(machine: Machine, pose_m: np.ndarray, count: int, out_dir: Path | None,
              overwrite: bool = False) -> tuple[Modes, list[Path]]:
    """:func:`pressfit.dynamics.modes.natural_modes` at a pose, and its files in ``out_dir`` if given (checked
    before computing, written through a temporary directory: :func:`pressfit.output.files.write_directory`)."""
    if out_dir is not None:
        io.check_directory(out_dir, overwrite)
    modes = natural_modes(machine, pose_m, count)
    return modes, ([] if out_dir is None else io.write_directory(
        out_dir, overwrite, lambda tmp: write_modes(modes, tmp), inputs=[machine.source] if machine.source else []))
