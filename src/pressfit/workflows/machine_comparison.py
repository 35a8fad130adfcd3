"""``pressfit compare``: machine files loaded (UPU machines or the gantry), measured the same way
(:func:`pressfit.studies.compare.compare`) and written (:mod:`pressfit.output.compare`)."""

from __future__ import annotations

from pathlib import Path

from pressfit.description.gantry import is_gantry_file, load_gantry
from pressfit.description.machine import load_machine, read_toml
from pressfit.output import files as io
from pressfit.output.compare import write_compare
from pressfit.studies.compare import Comparison, compare


def run_compare(machine_paths: list[Path], out_dir: Path | None, overwrite: bool = False,
                progress: bool = True) -> tuple[Comparison, list[Path]]:
    """Load every machine file (refused before computing when one does not load), compare them
    (:func:`pressfit.studies.compare.compare`) and write the files into ``out_dir`` if given (checked first)."""
    if out_dir is not None:
        io.check_directory(out_dir, overwrite)
    machines = [load_gantry(p) if is_gantry_file(read_toml(p)) else load_machine(p) for p in machine_paths]
    result = compare(machines, progress)
    return result, ([] if out_dir is None else io.write_directory(
        out_dir, overwrite, lambda tmp: write_compare(result, tmp), inputs=machine_paths))
