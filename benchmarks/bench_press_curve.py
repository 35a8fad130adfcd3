"""Time per predicted press curve of ``pressfit study curve`` (the shipped compliant-pin case by default) on one core.

Run: ``python benchmarks/bench_press_curve.py [--case cases/paper/insertion_compliant_pin.toml] [--curves 300]
[--samples 0]``. Prints the median (and 10% / 90% quantiles) over ``--curves`` curves, each at one draw of the
case's ``[curve.tolerances]``, of: the whole sample (``CurveSample.__call__``: the perturbed contact, the pin field,
the compliance at the pose, the series Newton, the summary), the compliance at the pose alone and the series
solve alone, in CPU time of this process (``time.process_time``: on a shared machine the wall time also counts the
other processes' turns); with ``--samples N`` also a serial ``curve_band_study`` of N samples end to end (wall time,
samples/s). Medians, and the spread. Not a test.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

from pressfit.description.cases import load_case
from pressfit.mechanics.condensed import condensed_plate_compliance
from pressfit.mechanics.press_curve import PinField, pin_pose_m, solve_field
from pressfit.shipped import cases_dir
from pressfit.studies.curve_band import curve_band_study
from pressfit.studies.curve_study import CurveSample, perturbed_contact


def _timed(fn, draws) -> list[float]:
    out = []
    for values in draws:
        t0 = time.process_time()
        fn(values)
        out.append(time.process_time() - t0)
    return out


def _line(name: str, times: list[float]) -> str:
    q = np.quantile(times, [0.1, 0.9]) * 1e3
    return f"{name:34s} median {statistics.median(times) * 1e3:7.3f} ms  (10% {q[0]:.3f}, 90% {q[1]:.3f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default=str(cases_dir() / "paper" / "insertion_compliant_pin.toml"))
    parser.add_argument("--curves", type=int, default=300)
    parser.add_argument("--samples", type=int, default=0)
    args = parser.parse_args()
    case = load_case(args.case)
    machine = case.machine()
    sample = CurveSample.from_case(case, machine)
    rng = np.random.default_rng(0)
    tol = case.curve.tolerances
    draws = [{k: float(d.draw(rng, ())) for k, d in tol.items()} for _ in range(args.curves)]
    sample(draws[0])  # warm up (imports, caches)
    contacts = [perturbed_contact(sample.contact, v) for v in draws]
    poses = [pin_pose_m(c) for c in contacts]
    fields = [PinField.from_contact(c) for c in contacts]
    compliances = [condensed_plate_compliance(machine, p) for p in poses]
    depth = np.linspace(0.0, fields[0].laws[0].depth_range_m[1], sample.points)
    print(f"{args.case}: {len(fields[0].laws)} pins, {sample.points} depth samples per curve, {args.curves} curves")
    print(_line("whole sample (CurveSample)", _timed(sample, draws)))
    print(_line("compliance at the pose", _timed(lambda i: condensed_plate_compliance(machine, poses[i]),
                                                  range(args.curves))))
    print(_line("series solve (solve_field)", _timed(lambda i: solve_field(fields[i], compliances[i], depth),
                                                      range(args.curves))))
    if args.samples:
        t0 = time.perf_counter()
        curve_band_study(sample, tol, args.samples, serial=True)
        total = time.perf_counter() - t0
        print(f"curve_band_study serial: {args.samples} samples in {total:.1f} s, {args.samples / total:.0f} "
              "samples/s")


if __name__ == "__main__":
    main()
