"""Issue 19's rigid-model speed, as a ratio that a loaded machine scales out of: the whole shipped rigid
insertion (planning, loop, summary) against the bare passive closed-loop step it is built on, CPU time of one
process, alternately measured."""

import time

import numpy as np

from pressfit.description.cases import load_case
from pressfit.dynamics.insertion import simulate_insertion
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.shipped import cases_dir

# The goal of 10 simulated s per s is 100 us per step: 3.2 passive steps at a quiet core's 31 us per passive step
# (docs/benchmarks.md; achieved 2.0-3.2, 10.0-16.6 before the compiled kernels).
MAX_PASSIVE_STEPS_PER_STEP = 3.2


def _passive_cpu_s(rigid, steps: int) -> float:
    q, tau = rigid.reference_q.copy(), np.zeros(rigid.model.nv)
    v = rigid.admissible_velocity(q, [0.2, 0.1, -0.2])
    start = time.process_time()
    for _ in range(steps):
        q, v = rigid.step(q, v, tau, 1e-4)
    return time.process_time() - start


def test_rigid_insertion_costs_a_few_passive_steps_per_step():
    """The best of three ratios (run CPU time / CPU time of as many passive steps, measured just before it):
    at most MAX_PASSIVE_STEPS_PER_STEP (achieved 2.0-3.2 under a load average of 5-11; the code before the
    kernels: 10.0-16.6, and 11.9 in this test: refused)."""
    case = load_case(cases_dir() / "paper" / "insertion.toml")
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"model": "rigid"})})
    first = simulate_insertion(case)  # the kernels loaded (or compiled) outside the timing
    steps = len(first.series)
    rigid = rigid_leg_model(case.machine(), np.asarray(case.simulation.start_m, float))
    ratios = []
    for _ in range(3):
        passive = _passive_cpu_s(rigid, steps)
        start = time.process_time()
        simulate_insertion(case)
        ratios.append((time.process_time() - start) / passive)
    assert min(ratios) <= MAX_PASSIVE_STEPS_PER_STEP, ratios
