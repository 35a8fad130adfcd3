"""Throughput of the condensed linear statics (pressfit.condensed), one core.

Run: ``python benchmarks/bench_condensed.py [n_poses]``. Prints the median of several repeats per
stage and the poses per second. Not a test: timings depend on the machine.
"""

from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

from pressfit.description.machine import load_machine
from pressfit.mechanics import condensed
from pressfit.studies import workspace_envelope


def _median_s(fn, repeats: int = 7) -> float:
    fn()  # warm up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def main(n: int = 1_000_000) -> None:
    machine = load_machine()
    rng = np.random.default_rng(0)
    poses = np.column_stack([rng.uniform(-0.25, 0.25, n), rng.uniform(0.5, 0.75, n), rng.uniform(-0.25, 0.25, n)])
    press = np.array([0.0, condensed.PRESS_LOAD_N, 0.0, 0.0, 0.0, 0.0])
    wrenches = rng.normal(size=(n, 6)) * [700, 700, 700, 50, 50, 50]
    stages = {
        "solve_linear, vertical press load (stiffness + solve + residuals)":
            (lambda: condensed.solve_linear(machine, poses, press), n),
        "solve_linear, one wrench per pose": (lambda: condensed.solve_linear(machine, poses, wrenches), n),
        "condensed_plate_compliance about the centre (6x6)": (
            lambda: condensed.condensed_plate_compliance(machine, poses), n),
        "plate_stiffness about the centre (6x6)": (lambda: condensed.plate_stiffness(machine, poses), n),
        "stiffness_maps, 51 x 51": (lambda: condensed.stiffness_maps(machine, 0.6, 51), 2601),
        "load_envelope, 51 x 51 x 11 levels x 9 loads (cone 10 deg)": (
            lambda: workspace_envelope.load_envelope(machine, np.linspace(0.5, 0.74, 11), 51,
                                            workspace_envelope.press_loads(cone_half_angle_rad=np.radians(10)),
                                            progress=False), 2601 * 11 * 9),
    }
    print(f"{n} poses, median of 7 runs, one core")
    for name, (fn, count) in stages.items():
        t = _median_s(fn)
        print(f"  {name:<68s} {t * 1e3:9.2f} ms  {t / count * 1e6:7.3f} us/pose  {count / t:12,.0f} poses/s")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000)
