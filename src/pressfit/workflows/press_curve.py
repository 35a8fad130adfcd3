"""``pressfit curve``'s workflow: the case's predicted press curve, its residual enforced, handed to
:mod:`pressfit.output.curve` for curve.csv and curve.json."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pressfit.description.cases import load_case
from pressfit.errors import ResidualError
from pressfit.mechanics.press_curve import RESIDUAL_LIMIT_N, predict_curve
from pressfit.output import files as io
from pressfit.output.curve import write_curve


def run_curve(case_path: Path | str, out_dir: Path | None, overwrite: bool = False,
              samples: int | None = None) -> tuple[dict[str, Any], list[Path]]:
    """The case's predicted press curve (:func:`pressfit.mechanics.press_curve.predict_curve`), its residual
    enforced (:class:`pressfit.errors.ResidualError` above ``RESIDUAL_LIMIT_N``); the summary and the files in
    ``out_dir`` if given (checked before the computation)."""
    if out_dir is not None:
        io.check_directory(out_dir, overwrite)
    case = load_case(case_path)
    machine = case.machine()
    curve = predict_curve(machine, case) if samples is None else predict_curve(machine, case, samples=samples)
    if not curve.series_residual_n <= RESIDUAL_LIMIT_N:
        raise ResidualError("the press curve's series equation", "max |F - f(d)| (N)", curve.series_residual_n,
                            RESIDUAL_LIMIT_N, where=str(case_path))
    paths = [] if out_dir is None else io.write_directory(
        out_dir, overwrite, lambda tmp: write_curve(curve, tmp, case.name),
        inputs=[Path(case_path), *([machine.source] if machine.source else [])])
    return {"case": case.name, **curve.summary()}, paths
