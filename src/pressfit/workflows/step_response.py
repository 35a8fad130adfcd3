"""``pressfit response``: the tool's step response and receptance at a pose
(:func:`pressfit.dynamics.response.tool_response`) and their files (:mod:`pressfit.output.response`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pressfit.description.machine import Machine
from pressfit.dynamics.response import ToolResponse, tool_response
from pressfit.output import files as io
from pressfit.output.response import write_response


def run_response(machine: Machine, pose_m: np.ndarray, force_n: np.ndarray, duration_s: float,
                 damping_ratio: float, out_dir: Path | None,
                 overwrite: bool = False) -> tuple[ToolResponse, list[Path]]:
    """:func:`pressfit.dynamics.response.tool_response` and, with ``out_dir``, its files (the directory is
    checked before computing and written atomically)."""
    if out_dir is not None:
        io.check_directory(out_dir, overwrite)
    r = tool_response(machine, pose_m, force_n, duration_s, damping_ratio)
    paths = io.write_directory(out_dir, overwrite, lambda tmp: write_response(r, tmp)) if out_dir is not None else []
    return r, paths
