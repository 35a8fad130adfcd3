"""CPU and wall time of ``pressfit report`` per section (pressfit.workflows.report), one process.

Run: ``python benchmarks/bench_report.py [quick|default|full ...]`` (default: ``default``). Writes each report into a
temporary directory and prints, per section, the CPU seconds (``time.process_time``, all threads) and wall seconds,
then the totals. The first run in a fresh ``NUMBA_CACHE_DIR`` includes the numba compilation; run twice for a warm
cache. Not a test: timings depend on the machine and its load (state the load beside any number you quote).
"""

from __future__ import annotations

import os
import sys
import tempfile
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from pressfit.description.machine import load_machine
from pressfit.output import html_report
from pressfit.shipped import default_model
from pressfit.workflows import report

SECTIONS = [name for name in dir(report) if name.startswith("_") and name.endswith("_section")]


def timed(times: dict[str, list[float]], name: str, fn):
    def wrapper(*args, **kwargs):
        c, w = time.process_time(), time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            times[name] = [time.process_time() - c, time.perf_counter() - w]
    return wrapper


def run(mode: str) -> None:
    times: dict[str, list[float]] = {}
    originals = {name: getattr(report, name) for name in SECTIONS}
    for name, fn in originals.items():
        setattr(report, name, timed(times, name.strip("_"), fn))
    report.write_html_report = timed(times, "html", html_report.write_html_report)
    c, w = time.process_time(), time.perf_counter()
    try:
        with tempfile.TemporaryDirectory() as tmp:
            report.write_report(load_machine(default_model()), tmp, quick=mode == "quick", full=mode == "full",
                                progress=False)
    finally:
        for name, fn in originals.items():
            setattr(report, name, fn)
        report.write_html_report = html_report.write_html_report
    total = [time.process_time() - c, time.perf_counter() - w]
    print(f"\n{mode}: section, CPU s, wall s (load {os.getloadavg()[0]:.1f})")
    for name, (cpu, wall) in sorted(times.items(), key=lambda kv: -kv[1][0]):
        print(f"  {name:24s} {cpu:7.1f} {wall:7.1f}")
    print(f"  {'total':24s} {total[0]:7.1f} {total[1]:7.1f}")


if __name__ == "__main__":
    for mode in sys.argv[1:] or ["default"]:
        run(mode)
