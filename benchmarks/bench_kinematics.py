"""Throughput of ``kinematics.indices`` (n, F_x, F_y, F_z, v_p; equations 4-10) on one core.

Run: ``python benchmarks/bench_kinematics.py [--poses 1000000] [--repeat 7]``. Prints the median
wall time per call over the poses and the throughput (goal: >= 1e6 poses/s). Not a test. Pin BLAS to
one thread (numpy elementwise code is single-threaded anyway): OMP_NUM_THREADS=1.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

from pressfit import kinematics, load_machine


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    machine = load_machine()
    rng = np.random.default_rng(0)
    # Poses over the required square and the reachable heights (paper section 4.1), m.
    poses = np.column_stack([rng.uniform(-0.25, 0.25, args.poses), rng.uniform(0.49, 0.75, args.poses),
                             rng.uniform(-0.25, 0.25, args.poses)])
    kinematics.indices(machine, poses[:1000])  # warm-up
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        kinematics.indices(machine, poses)
        times.append(time.perf_counter() - t0)
    med = statistics.median(times)
    print(f"kinematics.indices: {args.poses} poses, median {med * 1e3:.1f} ms per call "
          f"({med / args.poses * 1e9:.0f} ns/pose), throughput {args.poses / med:.3g} poses/s "
          f"(min {min(times) * 1e3:.1f} ms, max {max(times) * 1e3:.1f} ms, {args.repeat} calls)")


if __name__ == "__main__":
    main()
