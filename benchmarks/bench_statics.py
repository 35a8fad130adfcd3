"""Per-pose time of the Pinocchio equilibrium solve (``statics.EquilibriumSolver.solve``), one core.

Run: ``python benchmarks/bench_statics.py [--poses 1000] [--springs 4]``. Random reachable poses in the
required workspace (x, z in +-0.25 m, y in [0.5, 0.75] m), a 700 N press load plus a small off-axis
wrench; one solver is built once and reused over the poses (as a sweep would; each solve takes the
pose-dependent values afresh), and the same loads are also solved at one fixed pose. Also times the
convenience ``solve_equilibrium(machine, ...)``, which builds a solver per call. Prints the median time per
pose and the throughput for the linear and the nonlinear solve, the batched fast path beside the reference
with the ratio, the end-to-end wall times of the pressfit commands (``--no-end-to-end`` skips them), then an
instrumented run that splits the time into Pinocchio calls, LAPACK / numpy.linalg calls and the rest
(Python and small numpy operations, including the per-pose values and the result objects). Not a test.
Goals (issue 14): linear <= 25 us, nonlinear <= 250 us.

Before/after: the script only uses the public API (the breakdown wraps whichever LAPACK entry points
``pressfit.statics`` imports), so ``PYTHONPATH=<older checkout>/src python benchmarks/bench_statics.py``
times an older version under the same conditions.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import pinocchio as pin

from pressfit import kinematics, load_machine
from pressfit.mechanics import statics
from pressfit.mechanics.fast_statics import FastEquilibriumSolver
from pressfit.mechanics.model import build_model

PIN_CALLS = ("computeJointJacobians", "forwardKinematics", "rnea", "integrate", "log3", "getConstraintsJacobian")


def poses_and_loads(machine, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    out = []
    while len(out) < n:
        h = np.array([rng.uniform(-0.25, 0.25), rng.uniform(0.5, 0.75), rng.uniform(-0.25, 0.25)])
        if kinematics.is_reachable(machine, h):
            out.append(h)
    loads = np.column_stack([rng.normal(0, 30, n), np.full(n, 700.0), rng.normal(0, 30, n), rng.normal(0, 5, (n, 3))])
    return np.array(out), loads


LAPACK = ("_getrf", "_getrs", "_gesv", "_gesdd")


def run(solver, poses, loads, linear: bool, fixed: bool = False) -> tuple[list[float], list[int]]:
    times, iters = [], []
    for h, w in zip(poses, loads):
        h = poses[0] if fixed else h
        t0 = time.perf_counter()
        eq = solver.solve(h, w, linear=linear)
        times.append(time.perf_counter() - t0)
        iters.append(eq.iterations)
        assert eq.is_valid(1e-9), eq.residuals
    return times, iters


class Clock:
    """Accumulates the time spent inside wrapped functions."""

    def __init__(self) -> None:
        self.total = 0.0

    def wrap(self, f):
        def g(*a, **k):
            t0 = time.perf_counter()
            try:
                return f(*a, **k)
            finally:
                self.total += time.perf_counter() - t0
        return g


def breakdown(solver, poses, loads, linear: bool) -> dict[str, float]:
    pin_clock, la_clock = Clock(), Clock()
    saved = {name: getattr(pin, name) for name in PIN_CALLS}
    saved_la = {name: getattr(statics, name) for name in LAPACK if hasattr(statics, name)}
    saved_svd = np.linalg.svd
    try:
        for name in PIN_CALLS:
            setattr(pin, name, pin_clock.wrap(saved[name]))
        for name, f in saved_la.items():
            setattr(statics, name, la_clock.wrap(f))
        np.linalg.svd = la_clock.wrap(saved_svd)
        t0 = time.perf_counter()
        run(solver, poses, loads, linear)
        total = time.perf_counter() - t0
    finally:
        for name, f in saved.items():
            setattr(pin, name, f)
        for name, f in saved_la.items():
            setattr(statics, name, f)
        np.linalg.svd = saved_svd
    n = len(poses)
    return {"total": total / n, "pinocchio": pin_clock.total / n, "linalg": la_clock.total / n,
            "python+numpy": (total - pin_clock.total - la_clock.total) / n}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=1000)
    parser.add_argument("--springs", type=int, default=None, help="springs per segment (default: the model's)")
    parser.add_argument("--end-to-end", action=argparse.BooleanOptionalAction, default=True,
                        help="also time the pressfit commands (report --quick, report, check, study preload)")
    args = parser.parse_args()
    machine = load_machine()
    rng = np.random.default_rng(0)
    poses, loads = poses_and_loads(machine, args.poses, rng)
    solver = statics.EquilibriumSolver(machine, springs_per_segment=args.springs, pose_m=poses[0])
    mm = solver.model
    print(f"model: nq = {mm.model.nq}, nv = {mm.model.nv}, {mm.springs_per_segment} springs per segment, "
          f"{len(poses)} poses")
    run(solver, poses[:20], loads[:20], True)  # warm-up
    for fixed in (False, True):
        print("one fixed pose:" if fixed else "a new pose per solve:")
        for linear in (True, False):
            times, iters = run(solver, poses, loads, linear, fixed)
            med = statistics.median(times)
            name = "linear   " if linear else "nonlinear"
            print(f"  {name}: median {med * 1e6:8.1f} us/pose, throughput {1 / med:8.0f} poses/s "
                  f"(p10 {np.percentile(times, 10) * 1e6:.1f}, p90 {np.percentile(times, 90) * 1e6:.1f} us; "
                  f"Newton iterations median {statistics.median(iters):g}, max {max(iters)})")
    print("fast batched path (fast_statics.FastEquilibriumSolver.solve_batch, all poses in one call) vs reference:")
    fast = FastEquilibriumSolver(mm)
    for linear in (True, False):
        ref = statistics.median(run(solver, poses[:200], loads[:200], linear)[0])
        t = min(timed_batch(fast, poses, loads, linear) for _ in range(3))
        print(f"  {'linear   ' if linear else 'nonlinear'}: fast {t * 1e6:8.1f} us/pose, reference {ref * 1e6:8.1f} "
              f"us/pose, ratio {ref / t:6.1f}")
    print("instrumented breakdown, new pose per solve (mean per pose; the wrappers add ~1 us per call):")
    for linear in (True, False):
        b = breakdown(solver, poses[:300], loads[:300], linear)
        print(f"  {'linear   ' if linear else 'nonlinear'}: total {b['total'] * 1e6:7.1f} us = Pinocchio "
              f"{b['pinocchio'] * 1e6:6.1f} + LAPACK {b['linalg'] * 1e6:6.1f} + Python/numpy "
              f"{b['python+numpy'] * 1e6:6.1f} us")
    print("convenience function (a solver built per call):")
    convenience_cost(machine, poses[:50], loads[:50])
    if args.end_to_end:
        end_to_end()


def timed_batch(fast, poses, loads, linear: bool) -> float:
    t0 = time.perf_counter()
    out = fast.solve_batch(poses, loads, linear=linear)
    t = (time.perf_counter() - t0) / len(poses)
    assert out.residuals.max() <= 1e-9, out.residuals.max()
    return t


def convenience_cost(machine, poses, loads) -> None:
    """solve_equilibrium(machine, ...) and (model, ...) build a solver per call: the extra cost."""
    mm = build_model(machine, poses[0])
    for what, system in (("machine", machine), ("built model", mm)):
        times = []
        for h, w in zip(poses, loads):
            t0 = time.perf_counter()
            statics.solve_equilibrium(system, h, w, linear=True)
            times.append(time.perf_counter() - t0)
        print(f"  solve_equilibrium({what}, ..., linear=True): median {statistics.median(times) * 1e3:.2f} ms per call")


ROOT = Path(__file__).resolve().parents[1]
COMMANDS = (("report --quick", ["report", "--quick", "--out", "r"]), ("report", ["report", "--out", "r"]),
            ("check envelope", ["check", str(ROOT / "cases/envelope/press_workspace.toml"), "--no-progress"]),
            ("study preload", ["study", "preload", str(ROOT / "cases/studies/preload_pose_A.toml"), "--no-progress"]))


def end_to_end() -> None:
    """Wall time of each command as a fresh subprocess (imports included) in its own temporary directory."""
    print("end to end (wall time of one run each, a subprocess in a temporary directory; the machine is shared):")
    times = {}
    for name, argv in COMMANDS:
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            run_ = subprocess.run([sys.executable, "-m", "pressfit", *argv], cwd=tmp, capture_output=True, text=True)
            times[name] = time.perf_counter() - t0
        status = "ok" if run_.returncode == 0 else f"exit {run_.returncode}: {run_.stderr.strip()[-200:]}"
        print(f"  pressfit {name:16s} {times[name]:7.2f} s  ({status})")
    print(f"  report --quick / report: {times['report --quick'] / times['report']:.2f}")


if __name__ == "__main__":
    main()
