"""Speed of the board cycle (pressfit.dynamics.cycle) on the shipped 20-pin board, one core.

Run: ``python benchmarks/bench_cycle.py [rigid|flexible|study ...]``. Prints, per model, the board's simulated time,
the wall and CPU time of one run with its drive sizing but without the preload-cost run (issue 20's goal: the
20-pin board on the flexible model in under 5 minutes on one core), and simulated seconds per CPU second; with
``study``, the throughput study's samples per second on 1 and 2 local Dask workers (``pressfit study cycle``,
:func:`pressfit.studies.cycle_study.cycle_study`) on the shipped board cut to its first 4 pins with an 8-sample
``[cycle.study]`` grid on the rigid model, end to end (the cluster's start included), beside the same samples run
one after the other in this process (:func:`pressfit.studies.cycle_study.run_sample`, no cluster). Not a test:
timings depend on the machine.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import tomli_w

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from pressfit.description.cases import load_case
from pressfit.dynamics.cycle import simulate_cycle
from pressfit.shipped import cases_dir
from pressfit.studies.cycle_study import cycle_study, grid, run_sample

STUDY = {"speed_scale": [1.0, 1.5], "acceleration_scale": [1.0, 2.0], "descent_scale": [1.0, 2.0]}


def study() -> None:
    """Samples per second of ``pressfit study cycle`` on 1 and 2 workers (module docstring)."""
    data = tomllib.loads((cases_dir() / "paper" / "board.toml").read_text())
    data["cycle"]["grid"] = {"x": {"min_m": -0.2, "max_m": -0.1, "count": 2}, "z": {"min_m": -0.15, "max_m": -0.05,
                                                                                   "count": 2}}
    data["cycle"]["study"] = STUDY
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "board4.toml"
        path.write_text(tomli_w.dumps(data))
        case = load_case(path)
        samples = case.cycle.study.sample_count
        wall = time.perf_counter()
        for factors in grid(case):
            run_sample(case, None, factors)
        print(f"study: {samples} samples in this process in {time.perf_counter() - wall:.1f} s: "
              f"{samples / (time.perf_counter() - wall):.2f} samples/s")
        for workers in (1, 2):
            wall = time.perf_counter()
            result = cycle_study(case, workers=workers, progress=False)
            wall = time.perf_counter() - wall
            print(f"study: {samples} samples (4-pin board, rigid) on {workers} worker(s) in {wall:.1f} s: "
                  f"{samples / wall:.2f} samples/s end to end; {int(result.columns['within_limits'].sum())} within "
                  "limits")


def main(models: list[str]) -> None:
    case = load_case(cases_dir() / "paper" / "board.toml")
    for model in models:
        if model == "study":
            study()
            continue
        wall, cpu = time.perf_counter(), time.process_time()
        result = simulate_cycle(case, model, sizing=True, preload_cost=False)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        simulated = result.summary["cycle_time_s"]
        passed = sum(p["passed"] for p in result.summary["pins"])
        print(f"{model}: {len(result.summary['pins'])}-pin board, {simulated:g} s simulated in {wall:.1f} s wall "
              f"({cpu:.1f} s CPU), {simulated / cpu:.2f} simulated s per CPU s; {passed} pins pass")


if __name__ == "__main__":
    main(sys.argv[1:] or ["rigid", "flexible"])
