"""Monte Carlo study on disk: one Parquet file per finished chunk (``samples/chunk-NNNNNN.parquet``, written
atomically as chunks finish, so a rerun resumes), then ``summary.json``, ``quantiles.csv`` and PNG plots.

``study.json`` records what defines the study (:meth:`MonteCarloPlan.fingerprint`); a rerun into the
same directory resumes only if it matches, and ``overwrite`` starts afresh (finished chunks removed). Each
chunk carries the SHA-256 of that fingerprint and its index in its Parquet metadata: on resume a readable
chunk of another study (or index, or samples) is refused naming the file (it is someone's data: never
deleted), a damaged one (truncated, empty, not Parquet; impossible from the atomic writes, so nothing to keep)
is run again, and files not named ``chunk-NNNNNN.parquet`` are ignored.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from pressfit.errors import OutputExistsError
from pressfit.output import files as io
from pressfit.studies.limit_check import LIMITS
from pressfit.studies.montecarlo import OUTPUTS, QUANTILES

if TYPE_CHECKING:
    from pressfit.studies import montecarlo

CHUNK_DIR = "samples"
DERIVED = ("summary.json", "quantiles.csv", "histograms.png", "sensitivity.png")  # replaced on every run
_CHUNK_NAME = re.compile(r"chunk-(\d{6})\.parquet")
_STUDY_KEY, _CHUNK_KEY = "pressfit.study_sha256", "pressfit.chunk"


def study_hash(plan: montecarlo.MonteCarloPlan) -> str:
    """SHA-256 of the study's fingerprint (case content, seed, samples, chunking, pressfit version)."""
    return hashlib.sha256(io.to_json(plan.fingerprint()).encode()).hexdigest()


def chunk_path(out_dir: Path, k: int) -> Path:
    return out_dir / CHUNK_DIR / f"chunk-{k:06d}.parquet"


def write_chunk(out_dir: Path, plan: montecarlo.MonteCarloPlan, k: int, columns: dict[str, np.ndarray]) -> Path:
    """Chunk k atomically, its Parquet metadata naming the study (``study_hash``) and the chunk index."""
    return io.write_parquet(chunk_path(out_dir, k), columns,
                            metadata={_STUDY_KEY: study_hash(plan), _CHUNK_KEY: str(k)})


def _chunk_state(path: Path, plan: montecarlo.MonteCarloPlan, k: int, digest: str) -> str:
    """"ok", "damaged" (truncated, empty, not Parquet: run again) or why the file is foreign (refused)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        meta = pq.read_schema(path).metadata or {}
        samples = pq.read_table(path, columns=["sample"]).column("sample").to_numpy()
    except (OSError, ValueError, KeyError, pa.ArrowException):
        return "damaged"
    if meta.get(_STUDY_KEY.encode(), b"").decode() != digest:
        return "it belongs to another study (its fingerprint differs: case, seed, samples, chunking or version)"
    if meta.get(_CHUNK_KEY.encode(), b"").decode() != str(k) or k >= plan.n_chunks:
        return "its chunk index does not match its name"
    a, b = plan.chunk_range(k)
    if not np.array_equal(samples, np.arange(a, b)):
        return f"its sample indices are not {a}..{b - 1}"
    return "ok"


def finished_chunks(out_dir: Path, plan: montecarlo.MonteCarloPlan) -> tuple[frozenset[int], list[Path]]:
    """The chunks of this study already on disk, and the damaged chunk files (removed, to be run again: a
    chunk file appears only complete, by atomic rename, so a broken one holds nothing to keep). Only
    ``samples/chunk-NNNNNN.parquet`` names are considered (stray files are ignored); a readable chunk of
    another study, of another index or with other samples is refused (OutputExistsError naming the file)."""
    digest, done, damaged = study_hash(plan), set(), []
    for path in sorted((out_dir / CHUNK_DIR).glob("chunk-*.parquet")):
        m = _CHUNK_NAME.fullmatch(path.name)
        if m is None or not path.is_file():
            continue
        k = int(m.group(1))
        state = _chunk_state(path, plan, k, digest)
        if state == "damaged":
            path.unlink()
            damaged.append(path)
        elif state != "ok":
            raise OutputExistsError(f"{path} is not a chunk of this Monte Carlo study: {state}; remove it or pass "
                                    "--overwrite", path=path)
        else:
            done.add(k)
    return frozenset(done), damaged


def read_samples(out_dir: Path | str, plan: montecarlo.MonteCarloPlan | None = None) -> dict[str, np.ndarray]:
    """Every sample of the study directory as columns, ordered by sample index: the chunk files of ``plan``
    (all present), or every ``chunk-NNNNNN.parquet`` without a plan."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out = Path(out_dir)
    paths = [chunk_path(out, k) for k in range(plan.n_chunks)] if plan is not None else \
        sorted(p for p in (out / CHUNK_DIR).glob("chunk-*.parquet") if _CHUNK_NAME.fullmatch(p.name))
    table = pa.concat_tables([pq.read_table(p) for p in paths]).sort_by("sample")
    cols = {name: table.column(name).to_numpy(zero_copy_only=False) for name in table.column_names}
    if plan is not None and not np.array_equal(cols["sample"], np.arange(plan.samples)):
        raise OutputExistsError(f"{out / CHUNK_DIR}: the chunks do not hold samples 0..{plan.samples - 1} exactly "
                                "once", path=out / CHUNK_DIR)
    return cols


def prepare(out_dir: Path, fingerprint: dict[str, object], overwrite: bool) -> None:
    """Check (or start) the study directory. A directory holding nothing of a study but its ``study.json``
    (a first run that failed before its first chunk: scheduler unreachable, SIGTERM) is restarted."""
    manifest, samples = out_dir / "study.json", out_dir / CHUNK_DIR
    if overwrite and out_dir.exists():
        shutil.rmtree(samples, ignore_errors=True)
        for name in ("study.json", *DERIVED):
            (out_dir / name).unlink(missing_ok=True)
    started = samples.is_dir() and any(_CHUNK_NAME.fullmatch(p.name) for p in samples.iterdir())
    if manifest.exists() and (started or (out_dir / "summary.json").exists()):
        if json.loads(manifest.read_text(encoding="utf-8")) != json.loads(io.to_json(fingerprint)):
            raise OutputExistsError(f"{out_dir} holds a different Monte Carlo study (study.json differs: case, "
                                    "samples, seed, chunk size, inputs or pressfit version); pass --overwrite or "
                                    "another --out", path=out_dir)
        return
    if started or (out_dir / "summary.json").exists():
        raise OutputExistsError(f"{out_dir} holds results without study.json; pass --overwrite", path=out_dir)
    io.write_json(manifest, fingerprint, overwrite=True)  # fresh, or a start that wrote nothing else


def write_summary(summary: montecarlo.MonteCarloSummary, columns: dict[str, np.ndarray], envelope: dict[str, float],
                  out: Path) -> list[Path]:
    """summary.json, quantiles.csv, histograms of the envelope outputs and the sensitivity ranking (PNG);
    these are derived from all the samples and are replaced on every (resumed) run."""
    paths = [io.write_json(out / "summary.json", summary.to_dict(), overwrite=True)]
    rows = [[k, *(q.get(f"q{p:g}", math.nan) for p in QUANTILES)] for k, q in summary.quantiles.items()]
    paths.append(io.write_csv(out / "quantiles.csv", ["output", *(f"q{p:g}" for p in QUANTILES)], rows,
                              overwrite=True))
    keys = [k for k in OUTPUTS if np.isfinite(columns[k]).any()]
    if keys:  # none when every sample failed (the caller refuses that study before)
        paths.append(_histograms(summary, columns, envelope, keys, out))
    if summary.sensitivity:  # undefined below 3 solved samples (summary.notes says so): no plot
        paths.append(_sensitivity_plot(summary, out))
    else:
        (out / "sensitivity.png").unlink(missing_ok=True)  # a resumed run's plot is no longer valid
    return paths


def _histograms(summary: montecarlo.MonteCarloSummary, columns: dict[str, np.ndarray], envelope: dict[str, float],
                keys: list[str], out: Path) -> Path:
    fig, axes = plt.subplots(math.ceil(len(keys) / 3), 3, figsize=(14, 3.2 * math.ceil(len(keys) / 3)),
                             squeeze=False, layout="constrained")
    try:
        for ax, key in zip(axes.flat, keys):
            v = columns[key][np.isfinite(columns[key])]
            if np.ptp(v) > 1e-9 * np.abs(v).max():
                ax.hist(v, bins=40, color="0.5")
            else:  # one value (or all equal): one bar around it (40 bins of width ~0 are not representable)
                half = 1e-6 * abs(float(v[0])) or 0.5
                ax.hist(v, bins=1, range=(float(v[0]) - half, float(v[0]) + half), color="0.5")
            if key in envelope:
                ax.axvline(envelope[key], color="r", label="envelope limit")
                ax.legend(fontsize=7)
            ax.set(xlabel=f"{LIMITS[key].label} [{LIMITS[key].unit}]", ylabel="samples")
        for ax in axes.flat[len(keys):]:
            ax.set_visible(False)
        fig.suptitle(f"{summary.samples} samples: worst value per sample over poses, loads, legs")
        return io.save_figure(fig, out / "histograms.png", overwrite=True)
    finally:
        plt.close(fig)


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
