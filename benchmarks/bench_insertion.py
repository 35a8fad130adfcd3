"""Speed of the insertion simulation (pressfit.dynamics.insertion) on the shipped scenario, one core.

Run: ``python benchmarks/bench_insertion.py``. Prints simulated seconds per wall-clock second with and
without the limiter (issue 11's goal: at least 1, ideally 10). Not a test: timings depend on the machine.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from pressfit.description.cases import load_case
from pressfit.dynamics.insertion import simulate_insertion
from pressfit.shipped import cases_dir


def main() -> None:
    case = load_case(cases_dir() / "paper" / "insertion.toml")
    for limiter in (True, False):
        t0 = time.perf_counter()
        result = simulate_insertion(case, limiter)
        wall = time.perf_counter() - t0
        simulated = result.summary["simulated_time_s"]
        print(f"limiter {'on ' if limiter else 'off'}: {simulated:g} s simulated in {wall:.2f} s wall, "
              f"{simulated / wall:.2f} simulated s per s, {len(result.series) / wall:.0f} steps/s")


if __name__ == "__main__":
    main()
