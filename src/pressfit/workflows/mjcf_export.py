"""``pressfit export-mjcf``: the rigid-leg machine closed at a pose as MuJoCo's MJCF
(:mod:`pressfit.dynamics.mjcf`), printed or written atomically (:mod:`pressfit.output.files`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pressfit.description.machine import Machine
from pressfit.dynamics.mjcf import machine_mjcf
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.output.files import check_distinct, check_target, write_text


def export_mjcf(machine: Machine, pose_m: np.ndarray, timestep_s: float, out: Path | None,
                overwrite: bool = False) -> tuple[str, Path | None]:
    """The MJCF of the rigid-leg machine closed at a reachable pose (m), MuJoCo time step ``timestep_s`` (s),
    written atomically to ``out`` when given (an existing file only with ``overwrite``)."""
    if out is not None:
        check_distinct({"--out": out}, [machine.source] if machine.source else [])
        check_target(out, overwrite)
    text = machine_mjcf(rigid_leg_model(machine, pose_m), timestep_s)
    return text, (write_text(out, text, overwrite) if out is not None else None)
