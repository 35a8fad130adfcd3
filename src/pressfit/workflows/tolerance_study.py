"""``pressfit study montecarlo``: the case's Monte Carlo tolerance study (:mod:`pressfit.studies.montecarlo`) run
or resumed chunk by chunk on Dask (:mod:`pressfit.studies.distributed`), its chunks, summary and plots written by
:mod:`pressfit.output.montecarlo_files` (which owns the directory's layout and its resume rules)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from pressfit.description.cases import Case
from pressfit.errors import StudyFailedError
from pressfit.output.montecarlo_files import finished_chunks, prepare, read_samples, write_chunk, write_summary
from pressfit.studies import distributed, montecarlo


@dataclass(frozen=True, kw_only=True)
class MonteCarloRun:
    """A finished study: its summary, the chunks run now (the rest were resumed), the files written, and the
    damaged chunk files found and run again."""

    summary: montecarlo.MonteCarloSummary
    chunks_run: int
    chunks_total: int
    written: list[Path]
    rerun: list[Path] = field(default_factory=list)


class _Lazy(Sequence):  # type: ignore[type-arg]
    """The values f(0) .. f(n - 1), made when asked (a study of 1e7 chunks keeps no list of them)."""

    def __init__(self, n: int, f: Callable[[int], object]) -> None:
        self.n, self.f = n, f

    def __len__(self) -> int:
        return self.n

    def __getitem__(self, k):  # type: ignore[no-untyped-def]
        if not 0 <= k < self.n:
            raise IndexError(k)
        return self.f(k)


def run_montecarlo(case: Case, out_dir: Path | str, *, samples: int | None = None, seed: int | None = None,
                   chunk_size: int | None = None, workers: int | None = None, scheduler: str | None = None,
                   overwrite: bool = False, progress: bool = True, dashboard: bool = False) -> MonteCarloRun:
    """Run (or resume) the case's Monte Carlo study on Dask and write the samples, summary and plots.
    Raises StudyFailedError (after keeping the chunks) when every sample failed."""
    plan = montecarlo.plan_from_case(case, samples, seed, chunk_size)
    out = Path(out_dir)
    prepare(out, plan.fingerprint(), overwrite)
    done, damaged = finished_chunks(out, plan)
    run = distributed.run_chunks(montecarlo.evaluate_chunk,
                                 _Lazy(plan.n_chunks, lambda k: (k, montecarlo.chunk_seed(plan, k))),
                                 _Lazy(plan.n_chunks, lambda k: plan.chunk_range(k)[1] - plan.chunk_range(k)[0]),
                                 lambda k, cols: write_chunk(out, plan, k, cols), shared=plan, done=done,
                                 workers=workers, scheduler=scheduler, progress=progress, name="montecarlo",
                                 dashboard=dashboard, total=plan.samples)
    columns = read_samples(out, plan)
    envelope = {k: v for k, v in case.envelope.model_dump().items() if v is not None}
    summary = montecarlo.summarize(plan, columns, envelope)
    if summary.failed and sum(summary.failed.values()) == summary.samples:
        raise StudyFailedError(f"{case.path}: Monte Carlo study in {out}", summary.failed)
    written = write_summary(summary, columns, envelope, out)
    return MonteCarloRun(summary=summary, chunks_run=run, chunks_total=plan.n_chunks, written=written, rerun=damaged)
