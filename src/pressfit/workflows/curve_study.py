"""``pressfit study curve``'s workflow: the case's ``[curve.tolerances]`` Monte Carlo of predicted press curves
(:mod:`pressfit.studies.curve_study` on :func:`pressfit.studies.curve_band.curve_band_study`), the monitor's
windows derived from the band (:func:`pressfit.studies.curve_band.windows_from_band`), handed to
:func:`pressfit.output.curve_files.write_curve_study` (windows.json, band.csv, band.png)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pressfit.description.cases import MAX_CURVE_SAMPLES, load_case
from pressfit.description.monitor_windows import Windows
from pressfit.errors import ModelFileError, PressfitError
from pressfit.output import files as io
from pressfit.output.curve_files import write_curve_study
from pressfit.studies.curve_band import CurveBandStudy, curve_band_study, windows_from_band
from pressfit.studies.curve_study import CurveSample


@dataclass(frozen=True, kw_only=True)
class CurveStudyRun:
    """A finished ``study curve``: the Monte Carlo ``study``, the derived ``windows`` and the files ``written``."""

    study: CurveBandStudy
    windows: Windows
    written: list[Path]

    def summary(self) -> dict[str, Any]:
        b = self.study.band
        return {"samples": b.samples, "seed": self.study.seed, "chunks": self.study.chunks,
                "displacement": "sensed_depth_m (the drives' encoders: the press's deflection included)",
                "largest_force_n_min": float(self.study.peak_force_n.min()),
                "largest_force_n_max": float(self.study.peak_force_n.max()),
                "elements": [e.name for e in self.windows.elements], "outputs": [str(p) for p in self.written]}


def run_curve_study(case_path: Path | str, out_dir: Path | str, *, samples: int | None = None,
                    seed: int | None = None, workers: int | None = None, scheduler: str | None = None,
                    serial: bool = False, overwrite: bool = False, progress: bool = False) -> CurveStudyRun:
    """Run the case's curve study (``samples`` / ``seed`` default to its ``[curve]``) on Dask (``workers``,
    ``scheduler``) or ``serial``ly, and write its files into ``out_dir`` (checked before the computation)."""
    io.check_directory(out_dir, overwrite)
    case = load_case(case_path)
    if case.curve is None:
        raise ModelFileError(case_path, "curve.tolerances", "the case has no [curve.tolerances] table: name the "
                             "contact's keys to vary, each a Distribution table (docs/monitor.md)")
    n = case.curve.samples if samples is None else samples
    if not 1 <= n <= MAX_CURVE_SAMPLES:
        raise PressfitError(f"--samples: give 1 .. {MAX_CURVE_SAMPLES:.0e} samples, got {n}")
    machine = case.machine()
    sample = CurveSample.from_case(case, machine)
    study = curve_band_study(sample, case.curve.tolerances, n, seed=case.curve.seed if seed is None else seed,
                             workers=workers, scheduler=scheduler, serial=serial, progress=progress)
    source = {"case": str(case_path), "samples": n, "seed": study.seed, "points_per_curve": sample.points,
              "displacement": "sensed_depth_m: the drives' encoders, the press's deflection at the pin pose included",
              "tolerances": {k: d.model_dump() for k, d in case.curve.tolerances.items()}}
    windows = windows_from_band(study.band, name=f"{case.name}: predicted band", source=source)
    nominal = sample({})
    written = io.write_directory(out_dir, overwrite, lambda tmp: write_curve_study(tmp, windows, study.band, nominal),
                                 inputs=[Path(case_path), *([machine.source] if machine.source else [])])
    return CurveStudyRun(study=study, windows=windows, written=written)
