"""Speed of the clearance/preload study (pressfit.clearance), one core.

Run: ``python benchmarks/bench_clearance.py``. A 13 preload x 11 clearance study with 50 load steps at an
off-centre pose (goal <= 60 s), with the small-displacement solver (clearance nonlinearity kept; batched
over the 13 preloads of a clearance) and, for comparison, per-step timings of the geometrically
nonlinear Pinocchio solver on one curve. Not a test: timings depend on the machine.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

from pressfit.description.machine import load_machine
from pressfit.mechanics import clearance as C
from pressfit.mechanics import statics
from pressfit.mechanics.model import build_model
from pressfit.mechanics.preload import rest_length_offsets
from pressfit.studies import preload_study

POSE = np.array([0.2, 0.6, -0.2])
UP = np.array([0.0, 1.0, 0.0])


def main() -> None:
    machine = load_machine()
    preloads = np.linspace(0.0, 1200.0, 13)
    gaps = np.linspace(0.0, 50e-6, 11)
    steps = 50
    t0 = time.perf_counter()
    study = preload_study.preload_study(machine, POSE, gaps, preloads, 700.0, steps, progress=False)
    total = time.perf_counter() - t0
    n_solves = len(gaps) * len(preloads) * (steps + 1)
    print(f"study 13 preloads x 11 clearances x {steps} steps (+ critical preload per clearance): "
          f"{total:.2f} s total, {total / n_solves * 1e6:.1f} us per curve point (amortised)")

    # per-step medians of the batched small-displacement step (13 preloads at once) and of one solve
    cl = C.Clearance.uniform(machine, 20e-6)
    offsets = np.array([rest_length_offsets(machine, POSE, float(a), "force", cl) for a in preloads])
    for batch, offs in (("13 preloads", offsets), ("1 preload", offsets[6:7])):
        model = C._SmallModel.build(machine, POSE, [cl] * len(offs), offs)
        state, times = None, []
        for f in np.linspace(0.0, 700.0, steps + 1):
            w = np.tile(np.concatenate([f * UP, np.zeros(3)]), (len(offs), 1))
            t = time.perf_counter()
            _, state = model.solve(w, state)
            times.append(time.perf_counter() - t)
        print(f"small-displacement step, batch of {batch}: median {np.median(times) * 1e6:.0f} us")
    t = time.perf_counter()
    C.critical_preload(machine, POSE, UP, 700.0, cl)
    print(f"critical preload (bisection, tol 0.07 N, {steps} steps): {time.perf_counter() - t:.3f} s")

    mm = build_model(machine, POSE, cardan_compliance=cl.cardan_compliance())
    prev, times = None, []
    for f in np.linspace(0.0, 700.0, steps + 1):
        t = time.perf_counter()
        prev = statics.solve_equilibrium(mm, POSE, np.concatenate([f * UP, np.zeros(3)]), start=prev,
                                         preload_offsets_m=offsets[6])
        times.append(time.perf_counter() - t)
    print(f"nonlinear Pinocchio step (continuation, a4 = {preloads[6]:g} N): median {np.median(times) * 1e3:.2f} ms, "
          f"a full 13 x 11 x {steps} study would take about {np.median(times) * n_solves:.0f} s")
    print(f"study max residual {study.max_residual:.1e}; critical preloads [N]: "
          + ", ".join(f"{v:.1f}" for v in study.critical_preload))


if __name__ == "__main__":
    main()
