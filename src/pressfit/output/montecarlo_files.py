"""Monte Carlo study on disk: one Parquet file per finished chunk (``samples/chunk-NNNNNN.parquet``, written
atomically as chunks finish, so a rerun resumes), then ``summary.json``, ``quantiles.csv`` and PNG plots.

``study.json`` records what defines the study (:meth:`MonteCarloPlan.fingerprint`); a rerun into the
same directory resumes only if it matches, and ``overwrite`` starts afresh (finished chunks removed).
"""

from __future__ import annotations

import json
import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from pressfit.description.cases import Case
from pressfit.errors import OutputExistsError
from pressfit.output import files as io
from pressfit.studies import distributed, montecarlo
from pressfit.studies.limit_check import LIMITS

CHUNK_DIR = "samples"


@dataclass(frozen=True)
class MonteCarloRun:
    """A finished study: its summary, the chunks run now (the rest were resumed), the files written."""

    summary: montecarlo.MonteCarloSummary
    chunks_run: int
    chunks_total: int
    written: list[Path]


def chunk_path(out_dir: Path, k: int) -> Path:
    return out_dir / CHUNK_DIR / f"chunk-{k:06d}.parquet"


def finished_chunks(out_dir: Path) -> frozenset[int]:
    """Chunk indices whose Parquet file exists (files appear only complete: atomic rename)."""
    return frozenset(int(p.stem.split("-")[1]) for p in (out_dir / CHUNK_DIR).glob("chunk-*.parquet"))


def read_samples(out_dir: Path | str) -> dict[str, np.ndarray]:
    """Every sample of the study directory as columns, ordered by sample index."""
    import pyarrow.parquet as pq

    table = pq.read_table(Path(out_dir) / CHUNK_DIR).sort_by("sample")
    return {name: table.column(name).to_numpy(zero_copy_only=False) for name in table.column_names}


def _prepare(out_dir: Path, fingerprint: dict[str, object], overwrite: bool) -> None:
    manifest = out_dir / "study.json"
    if overwrite and out_dir.exists():
        shutil.rmtree(out_dir / CHUNK_DIR, ignore_errors=True)
        manifest.unlink(missing_ok=True)
    if manifest.exists():
        if json.loads(manifest.read_text(encoding="utf-8")) != json.loads(io.to_json(fingerprint)):
            raise OutputExistsError(f"{out_dir} holds a different Monte Carlo study (study.json differs: case, "
                                    "samples, seed, chunk size or inputs); pass --overwrite or another --out")
    else:
        if (out_dir / CHUNK_DIR).exists() or (out_dir / "summary.json").exists():
            raise OutputExistsError(f"{out_dir} holds results without study.json; pass --overwrite")
        io.write_json(manifest, fingerprint)


def run_montecarlo(case: Case, out_dir: Path | str, *, samples: int | None = None, seed: int | None = None,
                   chunk_size: int | None = None, workers: int | None = None, scheduler: str | None = None,
                   overwrite: bool = False, progress: bool = True) -> MonteCarloRun:
    """Run (or resume) the case's Monte Carlo study on Dask and write the samples, summary and plots."""
    plan = montecarlo.plan_from_case(case, samples, seed, chunk_size)
    out = Path(out_dir)
    _prepare(out, plan.fingerprint(), overwrite)
    seeds = montecarlo.chunk_seeds(plan)
    sizes = [b - a for a, b in map(plan.chunk_range, range(plan.n_chunks))]
    run = distributed.run_chunks(montecarlo.evaluate_chunk, [(plan, k, seeds[k]) for k in range(plan.n_chunks)],
                                 sizes, lambda k, cols: io.write_parquet(chunk_path(out, k), cols),
                                 done=finished_chunks(out), workers=workers, scheduler=scheduler,
                                 progress=progress, name="montecarlo")
    columns = read_samples(out)
    envelope = {k: v for k, v in case.envelope.model_dump().items() if v is not None}
    summary = montecarlo.summarize(plan, columns, envelope)
    written = write_summary(summary, columns, envelope, out)
    return MonteCarloRun(summary, run, plan.n_chunks, written)


def write_summary(summary: montecarlo.MonteCarloSummary, columns: dict[str, np.ndarray], envelope: dict[str, float],
                  out: Path) -> list[Path]:
    """summary.json, quantiles.csv, histograms of the envelope outputs and the sensitivity ranking (PNG);
    these are derived from all the samples and are replaced on every (resumed) run."""
    paths = [io.write_json(out / "summary.json", summary.to_dict(), overwrite=True)]
    rows = [[k, *(q.get(f"q{p:g}", math.nan) for p in montecarlo.QUANTILES)] for k, q in summary.quantiles.items()]
    paths.append(io.write_csv(out / "quantiles.csv", ["output", *(f"q{p:g}" for p in montecarlo.QUANTILES)], rows,
                              overwrite=True))
    keys = [k for k in montecarlo.OUTPUTS if np.isfinite(columns[k]).any()]
    fig, axes = plt.subplots(math.ceil(len(keys) / 3), 3, figsize=(14, 3.2 * math.ceil(len(keys) / 3)),
                             squeeze=False, layout="constrained")
    try:
        for ax, key in zip(axes.flat, keys):
            v = columns[key][np.isfinite(columns[key])]
            ax.hist(v, bins=40, color="0.5")
            if key in envelope:
                ax.axvline(envelope[key], color="r", label="envelope limit")
                ax.legend(fontsize=7)
            ax.set(xlabel=f"{LIMITS[key].label} [{LIMITS[key].unit}]", ylabel="samples")
        for ax in axes.flat[len(keys):]:
            ax.set_visible(False)
        fig.suptitle(f"{summary.samples} samples: worst value per sample over poses, loads, legs")
        paths.append(io.save_figure(fig, out / "histograms.png", overwrite=True))
    finally:
        plt.close(fig)
    paths.append(_sensitivity_plot(summary, out))
    return paths


def _sensitivity_plot(summary: montecarlo.MonteCarloSummary, out: Path) -> Path:
    keys = list(summary.sensitivity)
    fig, axes = plt.subplots(math.ceil(len(keys) / 3), 3, figsize=(15, 3.4 * math.ceil(len(keys) / 3)),
                             squeeze=False, layout="constrained")
    try:
        for ax, key in zip(axes.flat, keys):
            top = summary.sensitivity[key][:8][::-1]
            ax.barh([n for n, _ in top], [r for _, r in top], color="0.4")
            ax.set(xlim=(-1, 1), title=key, xlabel="Spearman rank correlation")
            ax.tick_params(axis="y", labelsize=7)
        for ax in axes.flat[len(keys):]:
            ax.set_visible(False)
        return io.save_figure(fig, out / "sensitivity.png", overwrite=True)
    finally:
        plt.close(fig)
