"""Throughput of ``interference.sweep`` (every checked pair, signed distances) on one core.

Run: ``python benchmarks/bench_interference.py [--poses 100000] [--rig auto|model|closed-form]``.
Prints the total wall time (goal: 1e5 poses <= 5 s), the median time per pose over blocks of 1024
poses, the throughput, and a breakdown (configurations in numpy; ``pin.computeDistances``, which does
forward kinematics, shape placements and every pair in C++; gathering the distances). Not a test.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import pinocchio as pin

from pressfit import load_machine
from pressfit.geometry import interference


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=100_000)
    parser.add_argument("--rig", default="auto", choices=["auto", "model", "closed-form"])
    args = parser.parse_args()
    machine = load_machine()
    im = interference.build_interference(machine, rig=args.rig)
    ws = machine.workspace
    rng = np.random.default_rng(0)
    # the required square at the heights where it is reachable (docs/conventions.md: y_h in about [0.4877, 0.7519] m)
    poses = np.column_stack([rng.uniform(-ws.x_half_width_m, ws.x_half_width_m, args.poses),
                             rng.uniform(0.488, 0.751, args.poses),
                             rng.uniform(-ws.z_half_width_m, ws.z_half_width_m, args.poses)])
    print(f"rig: {im.kinematics} (nq = {im.rig.model.nq}); {len(im.pairs)} body pairs = "
          f"{len(im.geometry_model.collisionPairs)} Coal shape pairs; notes: {'; '.join(im.notes) or '-'}")

    t0 = time.perf_counter()
    res = interference.sweep(im, poses)
    total = time.perf_counter() - t0
    print(f"sweep: {args.poses} poses in {total:.3f} s ({args.poses / total:,.0f} poses/s), "
          f"{res.n_skipped} unreachable skipped; min clearance {res.pair_min_m.min() * 1e3:.3f} mm "
          f"({res.pairs[res.worst]})")

    # per-block timings and breakdown
    ev = interference._Evaluator(im)
    block, per_pose, t_conf, t_dist, t_read = 1024, [], 0.0, 0.0, 0.0
    for s in range(0, min(args.poses, 20 * block), block):
        t = time.perf_counter()
        qs = im.configurations(poses[s:s + block])
        t1 = time.perf_counter()
        for q in qs:
            pin.computeDistances(im.rig.model, ev.data, im.geometry_model, ev.gdata, q)
        t2 = time.perf_counter()
        for q in qs:
            np.fromiter(map(interference._MIN_DISTANCE, ev.results), float, ev.n)
        t3 = time.perf_counter()
        t_conf, t_dist, t_read = t_conf + t1 - t, t_dist + t2 - t1, t_read + t3 - t2
        per_pose.append((t3 - t) / len(qs))
    n = sum(min(block, args.poses - s) for s in range(0, min(args.poses, 20 * block), block))
    print(f"median per pose over blocks of {block}: {statistics.median(per_pose) * 1e6:.2f} us "
          f"(configurations {t_conf / n * 1e6:.2f} us, computeDistances {t_dist / n * 1e6:.2f} us, "
          f"gathering {t_read / n * 1e6:.2f} us)")
    print(f"goal 1e5 poses <= 5 s: {'met' if total / args.poses * 1e5 <= 5 else 'NOT met'} "
          f"({total / args.poses * 1e5:.2f} s per 1e5)")


if __name__ == "__main__":
    main()
