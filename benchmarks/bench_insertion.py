"""Speed of the insertion simulation (pressfit.dynamics.insertion) on the shipped scenario, one core.

Run: ``python benchmarks/bench_insertion.py``. Prints simulated seconds per wall-clock second on each model,
one line per model naming it (``[simulation] model``; issue 19's goals: rigid at least 10, flexible at least 1),
with and without the limiter on the rigid model, and the bare closed-loop rigid-leg step
(:meth:`pressfit.dynamics.multibody.RigidLegModel.step`, passive, no controller or contact) in steps per
second, the rigid and flexible insertions' cost in passive steps per step (CPU time, the median of five and
their spread: a ratio that a loaded machine scales out of; issue 29's goals 2 and 6.5), the wall time of
``pressfit response`` (:func:`pressfit.dynamics.response.tool_response`, median of three), and the cardan
plays' cost on the flexible model (:func:`_plays_cost`). Steady state: the rigid model runs once untimed
first, its line reporting that first run (numba loading the compiled kernels of
:mod:`pressfit.dynamics.kernels` from its cache, or compiling them in a fresh install).
Not a test: timings depend on the machine.
"""

from __future__ import annotations

import os
import time

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from pressfit.description.cases import load_case
from pressfit.description.machine import load_machine
from pressfit.dynamics.insertion import simulate_insertion
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.dynamics.response import tool_response
from pressfit.shipped import cases_dir


def _timed(label: str, case: object, limiter: bool = True) -> float:
    """One insertion run: simulated seconds per wall-clock second and steps per second; the process's CPU time
    beside the wall time (on a shared machine the wall time also counts the other jobs); returns the wall time."""
    t0, c0 = time.perf_counter(), time.process_time()
    result = simulate_insertion(case, limiter)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    simulated = result.summary["simulated_time_s"]
    print(f"{label}: {simulated:g} s simulated in {wall:.2f} s wall ({cpu:.2f} s CPU), {simulated / wall:.2f} "
          f"simulated s per s, {len(result.series) / wall:.0f} steps/s")
    return wall


def _passive_cpu_s(rigid: object, steps: int) -> float:
    """CPU time (s) of ``steps`` passive closed-loop rigid-leg steps (no controller, drives or contact)."""
    q, tau = rigid.reference_q.copy(), np.zeros(rigid.model.nv)
    v = rigid.admissible_velocity(q, [0.2, 0.1, -0.2])
    start = time.process_time()
    for _ in range(steps):
        q, v = rigid.step(q, v, tau, 1e-4)
    return time.process_time() - start


def _passive_steps_per_step(case: object, repeats: int) -> tuple[float, float, float]:
    """An insertion's cost as a ratio that a loaded machine scales out of: CPU time of the whole run (planning,
    loop, summary) over that of as many passive rigid-leg steps measured just before it, ``repeats`` times:
    (least, median, largest). A shared host drifts within seconds (about +-30% between runs here, docs/benchmarks.md):
    the spread says how far one number can be trusted."""
    steps = len(simulate_insertion(case).series)
    rigid = rigid_leg_model(case.machine(), np.asarray(case.simulation.start_m, float))
    ratios = []
    for _ in range(repeats):
        passive = _passive_cpu_s(rigid, steps)
        start = time.process_time()
        simulate_insertion(case)
        ratios.append((time.process_time() - start) / passive)
    return min(ratios), float(np.median(ratios)), max(ratios)


def _plays_cost() -> None:
    """The flexible model with the cardan plays (``[simulation] clearance = true``) against without, on the
    shipped force and electric cases: CPU time, the two alternated three times in one run, medians and their
    ratio (the plays' cost: the force drive's sensors only, the electric drive's solve behind the plays)."""
    for name in ("insertion", "insertion_electric"):
        base = load_case(cases_dir() / "paper" / f"{name}.toml")
        cpu: dict[bool, list[float]] = {False: [], True: []}
        for _ in range(3):
            for clearance in (False, True):
                sim = base.simulation.model_copy(update={"model": "flexible", "clearance": clearance})
                start = time.process_time()
                simulate_insertion(base.model_copy(update={"simulation": sim}))
                cpu[clearance].append(time.process_time() - start)
        off, on = float(np.median(cpu[False])), float(np.median(cpu[True]))
        print(f"{name} flexible, plays off / on: {off:.2f} / {on:.2f} s CPU (median of 3, alternated), "
              f"ratio {on / off:.2f}")


def main() -> None:
    case = load_case(cases_dir() / "paper" / "insertion.toml")
    rigid_case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"model": "rigid"})})
    t0 = time.perf_counter()
    simulate_insertion(rigid_case)
    print(f"first rigid run in this process (the kernels loaded or compiled): {time.perf_counter() - t0:.2f} s wall")
    for model in ("rigid", "flexible"):
        _timed(model, case.model_copy(update={"simulation": case.simulation.model_copy(update={"model": model})}))
    for limiter in (True, False):
        _timed(f"limiter {'on ' if limiter else 'off'}", case, limiter)
    rigid = rigid_leg_model(load_machine(), np.array([0.05, 0.65, -0.05]))
    q, tau = rigid.reference_q.copy(), np.zeros(rigid.model.nv)
    v = rigid.admissible_velocity(q, [0.2, 0.1, -0.2])
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(2000):
            q, v = rigid.step(q, v, tau, 1e-4)
        times.append((time.perf_counter() - t0) / 2000)
    step = float(np.median(times))
    print(f"passive rigid-leg step: {step * 1e6:.0f} us/step, {1 / step:.0f} steps/s")
    flexible_case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"model": "flexible"})})
    for name, run, goal in (("rigid", rigid_case, 2.0), ("flexible", flexible_case, 6.5)):
        least, median, largest = _passive_steps_per_step(run, 5)
        print(f"{name} insertion: {median:.2f} passive closed-loop steps per step, median of 5 (least {least:.2f}, "
              f"largest {largest:.2f}; CPU time of the whole run over as many passive steps measured just before "
              f"it; goal {goal:g})")
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        tool_response(load_machine(), np.array([0.0, 0.6, 0.2]), np.array([0.0, -100.0, 0.0]))
        times.append(time.perf_counter() - t0)
    print(f"response (0, 0.6, 0.2), 100 N step, 0.5 s: {np.median(times):.2f} s wall")
    from pressfit.dynamics.linearise import control_design

    for model in ("rigid", "flexible"):
        t0 = time.perf_counter()
        control_design(case, model)
        print(f"control {model} (shipped case, 4 poses): {time.perf_counter() - t0:.1f} s wall")
    _plays_cost()


if __name__ == "__main__":
    main()
