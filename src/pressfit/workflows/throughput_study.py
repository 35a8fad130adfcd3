"""``pressfit study cycle``: the board's throughput study (:func:`pressfit.studies.cycle_study.cycle_study`) on a
case file, the case file of its fastest setting within the limits, and its files (:mod:`pressfit.output.cycle_study`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import tomli_w

from pressfit.description.cases import Case, load_case
from pressfit.description.machine import read_toml
from pressfit.output import files as io
from pressfit.output.cycle_study import FASTEST_CASE, write_cycle_study
from pressfit.studies.cycle_study import FACTOR_LABELS, FACTORS, CycleStudyResult, cycle_study, judged_limits, variant


def fastest_case_toml(result: CycleStudyResult) -> str | None:
    """The fastest setting within the limits as a case file's text (None: no sample is within them)."""
    if result.fastest is None:
        return None
    case = result.case
    data: dict[str, Any] = read_toml(case.path)
    setting = tuple(float(result.columns[k][result.fastest]) for k in FACTORS)
    varied = variant(case, setting)
    cycle = data["cycle"]
    cycle.pop("study", None)
    cycle["motion"] = varied.cycle.motion.model_dump()
    cycle["descent"] = varied.cycle.descent.model_dump()
    cycle.setdefault("controller", {}).update({k: getattr(varied.cycle.controller, k) for k in
                                               ("kp_n_per_m", "kd_n_s_per_m", "ki_n_per_m_s")})
    if varied.preload.a4_n != case.preload.a4_n:
        data.setdefault("preload", {})["a4_n"] = varied.preload.a4_n
    if data.get("model"):
        data["model"] = str((Path(case.path).parent / data["model"]).resolve())
    data["name"] = f"{case.name}-fastest"
    time_s = result.columns["cycle_time_s"][result.fastest]
    data["description"] = (f"The fastest setting of `pressfit study cycle` on {case.path} within the limits judged ("
                           + "; ".join(judged_limits(case)) + "): "
                           + ", ".join(f"{FACTOR_LABELS[k]} {v:g}" for k, v in zip(FACTORS, setting, strict=True))
                           + f"; cycle time {time_s:.6g} s.")
    return tomli_w.dumps(data)


def run_cycle_study(case_path: Path | str, model: str | None, out_dir: Path, overwrite: bool = False,
                    workers: int | None = None, scheduler: str | None = None, progress: bool = True,
                    dashboard: bool = False) -> tuple[CycleStudyResult, list[Path]]:
    """Run the case file's ``[cycle.study]`` (:func:`pressfit.studies.cycle_study.cycle_study`) and write its files
    (the directory checked before the study, written through a temporary directory)."""
    io.check_directory(out_dir, overwrite)
    case: Case = load_case(case_path)
    source = case.machine().source
    inputs = [Path(case_path), *([source] if source else [])]
    io.check_distinct({"--out": Path(out_dir) / FASTEST_CASE}, inputs)  # the study's case file: before the study
    result = cycle_study(case, model, workers, scheduler, progress, dashboard)
    paths = io.write_directory(out_dir, overwrite,
                               lambda tmp: write_cycle_study(result, tmp, fastest_case_toml(result)), inputs=inputs)
    return result, paths


