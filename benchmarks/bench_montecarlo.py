"""Monte Carlo throughput on Dask (pressfit.studies.montecarlo): samples per second in process and with 1 and 2
worker processes, scaling efficiency, output volume per sample, and the projection to 1e5 and 1e8 samples.

Run: ``python benchmarks/bench_montecarlo.py [SAMPLES]`` (default 400) on the shipped 3-pose case
cases/studies/montecarlo_tolerances.toml, in two variants, both in chunks of 500 with one model and one batched
fast solve per chunk: lengths + load tilt only, and the full input set (plus joint position errors, which the
batched solve takes as per-sample joint positions). In process: CPU and wall ms per sample of one chunk and the
CPU-time ratio of the two variants (the number that survives a loaded machine). Goal of issue 12: 1e5 samples of
a 3-pose case in at most 5 minutes on 2 cores; of issue 21 item 5: the same throughput for both variants. Not a
test: timings depend on the machine.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from pressfit.description.cases import load_case
from pressfit.output.montecarlo_files import CHUNK_DIR
from pressfit.shipped import cases_dir
from pressfit.studies import montecarlo
from pressfit.workflows.tolerance_study import run_montecarlo

CASE = cases_dir() / "studies" / "montecarlo_tolerances.toml"


def _in_process(case, chunk: int) -> tuple[float, float]:
    """CPU and wall seconds per sample of one chunk evaluated in this process (no cluster; plan built before)."""
    plan = montecarlo.plan_from_case(case, samples=chunk, chunk_size=chunk)
    c, t = time.process_time(), time.perf_counter()
    montecarlo.evaluate_chunk(plan, 0, montecarlo.chunk_seeds(plan)[0])
    return (time.process_time() - c) / chunk, (time.perf_counter() - t) / chunk


def _run(case, samples: int, workers: int, out: Path, chunk: int) -> tuple[float, int]:
    t = time.perf_counter()
    run_montecarlo(case, out, samples=samples, chunk_size=chunk, workers=workers, progress=False)
    dt = time.perf_counter() - t
    return dt, sum(p.stat().st_size for p in (out / CHUNK_DIR).iterdir())


def main() -> None:
    samples = int(sys.argv[1]) if len(sys.argv) > 1 else 400
    full = load_case(CASE)
    light = full.model_copy(update={"montecarlo": full.montecarlo.model_copy(update={  # type: ignore[union-attr]
        "inputs": full.montecarlo.inputs.model_copy(update={"base_point_error_m": None,  # type: ignore[union-attr]
                                                            "plate_point_error_m": None})})})
    chunk = 500
    cpu = {}
    with tempfile.TemporaryDirectory() as tmp:
        for label, case in (("lengths + load tilt", light), ("all inputs (with joint position errors)", full)):
            cpu[label], wall = _in_process(case, chunk)
            print(f"{label}: {cpu[label] * 1e3:.2f} ms/sample CPU, {wall * 1e3:.2f} ms wall in process (chunk of "
                  f"{chunk})")
            rate = {}
            for workers in (1, 2):
                dt, size = _run(case, samples, workers, Path(tmp) / f"{label[:3]}{workers}", chunk)
                rate[workers] = samples / dt
                print(f"{label}, {workers} worker(s): {samples} samples in {dt:.1f} s = {rate[workers]:.1f} "
                      f"samples/s (cluster start included); {size / samples:.0f} bytes/sample on disk")
            # the projection: the marginal cost per sample of a second 2-worker run ten times larger (chunk writes
            # and transfers included, the cluster start and the summary's plots not), plus the small run's time; a
            # small run's rate alone is mostly its fixed cost (issue 12's 1e5 samples measured 3.1 min on 2 workers,
            # 2.6 min projected this way, 2.2 min from the in-process cost: what a large run adds beyond its chunks, its
            # summary over all samples among it, is not in the projection)
            big, _ = _run(case, 10 * samples, 2, Path(tmp) / f"{label[:3]}big", chunk)
            marginal = (big - samples / rate[2]) / (9 * samples)
            projected = (samples / rate[2] + (1e5 - samples) * marginal) / 60
            print(f"  scaling efficiency 2 vs 1 workers: {rate[2] / (2 * rate[1]):.0%} (fixed costs included); "
                  f"{10 * samples} samples on 2 workers in {big:.1f} s, {marginal * 1e3:.2f} ms a sample at the "
                  f"margin; projected: 1e5 samples on 2 workers {projected:.1f} min, 1e8 on 256 workers "
                  f"{1e8 * marginal * 2 / 256 / 3600:.1f} h")
    light_cpu, full_cpu = cpu.values()
    print(f"CPU time per sample, all inputs / lengths + load tilt: {full_cpu / light_cpu:.2f}")


if __name__ == "__main__":
    main()
