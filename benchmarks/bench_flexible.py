"""Speed of the flexible machine (pressfit.dynamics.machine.flexible), one core.

Run: ``python benchmarks/bench_flexible.py``. The shipped insertion case's first move (from ``start_m`` to
above the pin, a quintic in 1 s) and 0.5 s of holding, at h = 1 ms, position drives following the inverse
kinematics of the reference (issue 19's target: at least 1 simulated s per wall-clock s). Prints simulated
seconds per wall second, the Newton iterations per step and the iteration-matrix factorisations. Not a
test: timings depend on the machine (and on what else runs on it).
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

from pressfit import kinematics
from pressfit.description.cases import load_case
from pressfit.dynamics.machine.base import DriveInput
from pressfit.dynamics.machine.flexible import FlexibleMachine
from pressfit.shipped import cases_dir

H_S = 1e-3


def main() -> None:
    case = load_case(cases_dir() / "paper" / "insertion.toml")
    machine, sim = case.machine(), case.simulation
    start, above = np.array(sim.start_m), np.array(case.poses.points_m[1])
    n_move, n_hold = round(sim.move_time_s / H_S), round(0.5 / H_S)
    u = np.minimum(np.arange(1, n_move + n_hold + 1) / n_move, 1.0)
    poses = start + np.outer(10 * u**3 - 15 * u**4 + 6 * u**5, above - start)
    lengths = kinematics.inverse_kinematics(machine, poses).lengths_m
    t0 = time.perf_counter()
    fm = FlexibleMachine(machine, start)
    state = fm.rest_state()
    build = time.perf_counter() - t0
    iterations = []
    t0 = time.perf_counter()
    for row in lengths:
        state = fm.step(state, DriveInput.positions(row), np.zeros(6), H_S)
        iterations.append(state.iterations)
    wall = time.perf_counter() - t0
    simulated = len(lengths) * H_S
    deflection = np.linalg.norm(fm.tool_point_m(state) - poses[-1])
    print(f"flexible: {simulated / wall:.2f} simulated s per s (h = {1e3 * H_S:g} ms, {simulated:g} s simulated in "
          f"{wall:.2f} s; {1e3 * wall / len(lengths):.3f} ms per step, {np.mean(iterations):.2f} Newton iterations "
          f"per step, {fm.refreshes} factorisations; model and rest state {build:.2f} s)")
    print(f"tool against the reference at the end of the hold: {1e6 * deflection:.1f} um (gravity sag and residual "
          f"vibration); closure error {fm.closure_error(state)[0]:.2e} m")


if __name__ == "__main__":
    main()
