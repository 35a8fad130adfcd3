"""Files of ``pressfit study cycle``: ``samples.parquet`` (every sample: the factors, the figures, ``within_limits``,
``on_front``, ``error``), ``summary.json``, ``front.png`` (cycle time against the worst alignment error and the worst
overshoot, the front marked) and ``fastest.toml``: the case with the fastest setting within the limits (a case file
that loads: its ``[cycle.motion]`` and ``[cycle.descent]`` scaled, the gains of ``[cycle.controller]`` and
``[preload] a4_n`` set, ``[cycle.study]`` removed, ``model`` made absolute)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from pressfit.output import files as io
from pressfit.output.plots import plt

if TYPE_CHECKING:
    from pressfit.studies.cycle_study import CycleStudyResult


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


FASTEST_CASE = "fastest.toml"  # the fastest setting's case file in the study's directory


def write_cycle_study(result: CycleStudyResult, out_dir: Path | str, fastest_toml: str | None = None) -> list[Path]:
    """``samples.parquet``, ``summary.json``, ``front.png`` and, when given, ``fastest_toml`` as ``fastest.toml``
    (the case file of the fastest setting within the limits:
    :func:`pressfit.workflows.throughput_study.fastest_case_toml`)."""
    out = Path(out_dir)
    c = {k: (v.astype(str) if v.dtype == object else v) for k, v in result.columns.items()}
    paths = [io.write_parquet(out / "samples.parquet", c), io.write_json(out / "summary.json", result.summary())]
    fig = front_figure(result)
    try:
        paths.append(io.save_figure(fig, out / "front.png"))
    finally:
        plt.close(fig)
    if fastest_toml is not None:
        paths.append(io.write_text(out / FASTEST_CASE, fastest_toml))
    return paths
