"""Speed of the board cycle (pressfit.dynamics.cycle) on the shipped 20-pin board, one core.

Run: ``python benchmarks/bench_cycle.py [rigid|flexible ...]``. Prints, per model, the board's simulated time, the
wall and CPU time of one run with its drive sizing but without the preload-cost run (issue 20's goal: the
20-pin board on the flexible model in under 5 minutes on one core), and simulated seconds per CPU second. Not a
test: timings depend on the machine.
"""

from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from pressfit.description.cases import load_case
from pressfit.dynamics.cycle import simulate_cycle
from pressfit.shipped import cases_dir


def main(models: list[str]) -> None:
    case = load_case(cases_dir() / "paper" / "board.toml")
    for model in models:
        wall, cpu = time.perf_counter(), time.process_time()
        result = simulate_cycle(case, model, sizing=True, preload_cost=False)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        simulated = result.summary["cycle_time_s"]
        passed = sum(p["passed"] for p in result.summary["pins"])
        print(f"{model}: {len(result.summary['pins'])}-pin board, {simulated:g} s simulated in {wall:.1f} s wall "
              f"({cpu:.1f} s CPU), {simulated / cpu:.2f} simulated s per CPU s; {passed} pins pass")


if __name__ == "__main__":
    main(sys.argv[1:] or ["rigid", "flexible"])
