"""Files of ``pressfit study cycle``: ``samples.parquet`` (every sample: the factors, the figures, ``within_limits``,
``on_front``, ``error``), ``summary.json``, ``front.png`` (cycle time against the worst alignment error and the worst
overshoot, the front marked) and ``fastest.toml``: the case with the fastest setting within the limits (a case file
that loads: its ``[cycle.motion]`` and ``[cycle.descent]`` scaled, the gains of ``[cycle.controller]`` and
``[preload] a4_n`` set, ``[cycle.study]`` removed, ``model`` made absolute)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import tomli_w

from pressfit.description.cases import Case, load_case
from pressfit.description.machine import read_toml
from pressfit.output import files as io
from pressfit.output.plots import plt
from pressfit.studies.cycle_study import FACTOR_LABELS, FACTORS, CycleStudyResult, cycle_study, judged_limits, variant


def front_figure(result: CycleStudyResult) -> plt.Figure:
    """Cycle time against the worst alignment error and against the worst overshoot; the front in red, the
    samples within the limits filled, the fastest of them circled."""
    c = result.columns
    t = c["cycle_time_s"]
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), layout="constrained")
    for ax, key, scale, label in ((axes[0], "worst_alignment_error_m", 1e6, "worst alignment error [um]"),
                                  (axes[1], "worst_overshoot_n", 1.0, "worst overshoot [N]")):
        y = c[key] * scale
        ok = c["within_limits"]
        ax.plot(t[~ok], y[~ok], "o", mfc="none", color="tab:gray", label="outside the limits")
        ax.plot(t[ok], y[ok], "o", color="tab:blue", label="within the limits")
        ax.plot(t[result.front], y[result.front], "x", color="tab:red", ms=9, label="Pareto front")
        if result.fastest is not None:
            ax.plot(t[result.fastest], y[result.fastest], "o", ms=14, mfc="none", color="k",
                    label="fastest within the limits")
        ax.set(xlabel="cycle time [s]", ylabel=label)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{result.case.name}: throughput study ({len(t)} samples, model {result.model})")
    return fig


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


def write_cycle_study(result: CycleStudyResult, out_dir: Path | str) -> list[Path]:
    out = Path(out_dir)
    c = {k: (v.astype(str) if v.dtype == object else v) for k, v in result.columns.items()}
    paths = [io.write_parquet(out / "samples.parquet", c), io.write_json(out / "summary.json", result.summary())]
    fig = front_figure(result)
    try:
        paths.append(io.save_figure(fig, out / "front.png"))
    finally:
        plt.close(fig)
    text = fastest_case_toml(result)
    if text is not None:
        paths.append(io.write_text(out / "fastest.toml", text))
    return paths


def run_cycle_study(case_path: Path | str, model: str | None, out_dir: Path, overwrite: bool = False,
                    workers: int | None = None, scheduler: str | None = None, progress: bool = True,
                    dashboard: bool = False) -> tuple[CycleStudyResult, list[Path]]:
    """Run the case file's ``[cycle.study]`` (:func:`pressfit.studies.cycle_study.cycle_study`) and write its files
    (the directory checked before the study, written through a temporary directory)."""
    io.check_directory(out_dir, overwrite)
    case: Case = load_case(case_path)
    result = cycle_study(case, model, workers, scheduler, progress, dashboard)
    source = case.machine().source
    paths = io.write_directory(out_dir, overwrite, lambda tmp: write_cycle_study(result, tmp),
                               inputs=[Path(case_path), *([source] if source else [])])
    return result, paths


