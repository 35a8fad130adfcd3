"""Files of ``pressfit curve``: the predicted press curve as ``curve.csv`` (one row per sampled depth: true depth,
sensed depth, total force, per-pin forces and depths) and ``curve.json`` (the summary)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pressfit.description.cases import load_case
from pressfit.errors import ResidualError
from pressfit.mechanics.press_curve import RESIDUAL_LIMIT_N, PressCurve, predict_curve
from pressfit.output import files as io


def curve_columns(pins: int) -> list[str]:
    """curve.csv's header for ``pins`` pins (time is not meaningful quasi-statically: rows are depth samples)."""
    return (["depth_m", "sensed_depth_m", "force_n"] + [f"pin_force_n{i + 1}" for i in range(pins)]
            + [f"pin_depth_m{i + 1}" for i in range(pins)])


def write_curve(curve: PressCurve, out_dir: Path, case_name: str) -> list[Path]:
    """curve.csv and curve.json into a fresh directory (through :func:`pressfit.output.files.write_directory`)."""
    pins = curve.pin_forces_n.shape[1]
    rows = ([d, s, f, *pf, *pd] for d, s, f, pf, pd in zip(curve.depth_m, curve.sensed_depth_m, curve.force_n,
                                                             curve.pin_forces_n, curve.pin_depths_m, strict=True))
    return [io.write_csv(out_dir / "curve.csv", curve_columns(pins), rows),
            io.write_json(out_dir / "curve.json", {"case": case_name, **curve.summary()})]


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
