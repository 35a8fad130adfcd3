"""The floor of the flexible insertion's step: what its compiled arithmetic alone costs, in passive rigid steps.

Run: ``python benchmarks/bench_flexible_floor.py``. Runs the shipped insertion on the flexible model once with
every Pinocchio pass and LAPACK call of the flexible machine counted (rnea, the joint Jacobians, the closures'
Jacobians, crba, forward kinematics, the energies, integrate and difference, the iteration matrix's factorisation
and solves, the rigid velocity's solve), times each of them alone in a tight loop on the same model (the cache
warm: a lower bound of what it costs inside the run), and prints their sum per step -- the arithmetic a step
cannot shed whatever language drives it, since the counts and the operations fix the numbers -- over the passive
rigid-leg step that ``bench_insertion`` divides by, measured in the same process. The stems' re-placement is
counted at its Python cost apart (its compiled equivalent, a few writes into the model, is small). What is left
between this floor and ``bench_insertion``'s flexible ratio is the step's Python and the scenario around it
(controller, drives, contact law, sensing, the series row). Not a test: timings depend on the machine.
"""

from __future__ import annotations

import os
import time
from collections import Counter

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np
import pinocchio as pin
from scipy.linalg import lu_factor

from pressfit.description.cases import load_case
from pressfit.dynamics.insertion import simulate_insertion
from pressfit.dynamics.machine import flexible
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.shipped import cases_dir

PINOCCHIO = ("rnea", "computeJointJacobians", "getConstraintJacobian", "crba", "forwardKinematics",
             "computeMechanicalEnergy", "integrate", "difference")
LAPACK = ("lu_factor", "_getrs", "_posv")


def _counted_run(case: object) -> tuple[Counter, int, int]:
    """The run with the flexible machine's Pinocchio and LAPACK calls counted: (counts, steps, re-placements)."""
    counts: Counter = Counter()
    saved = {name: getattr(pin, name) for name in PINOCCHIO} | {name: getattr(flexible, name) for name in LAPACK}

    def counting(name: str, call: object) -> object:
        def counted(*args: object, **kwargs: object) -> object:
            kept = name == "computeMechanicalEnergy" and len(args) == 2  # on the kinematics a pass left
            counts[name + (" (kept)" if kept else "")] += 1
            return call(*args, **kwargs)
        return counted

    write = flexible.StemInertias.write
    replaced = []
    try:
        for name in PINOCCHIO:
            setattr(pin, name, counting(name, saved[name]))
        for name in LAPACK:
            setattr(flexible, name, counting(name, saved[name]))
        flexible.StemInertias.write = lambda self, model, stems: (replaced.append(1), write(self, model, stems))[1]
        steps = len(simulate_insertion(case).series)
    finally:
        for name in PINOCCHIO:
            setattr(pin, name, saved[name])
        for name in LAPACK:
            setattr(flexible, name, saved[name])
        flexible.StemInertias.write = write
    return counts, steps, len(replaced)


def _median_us(call: object, n: int = 300, rounds: int = 7) -> float:
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        for _ in range(n):
            call()
        times.append((time.perf_counter() - start) / n)
    return 1e6 * float(np.median(times))


def _pass_times(fm: flexible.FlexibleMachine, state: object) -> dict[str, float]:
    """Each counted operation alone on the flexible model at ``state`` (us; a closure's Jacobian with its calc)."""
    model, data, q, rng = fm.model, fm.data, state.q, np.random.default_rng(0)
    v, a, dq = 0.01 * rng.standard_normal(fm.nv), rng.standard_normal(fm.nv), 1e-4 * rng.standard_normal(fm.nv)
    cm, cd = fm.cms[0], fm.cds[0]
    pin.computeJointJacobians(model, data, q)
    matrix = np.eye(fm.nv + 6 * fm.legs) + 1e-3 * rng.standard_normal((fm.nv + 6 * fm.legs,) * 2)
    lu, piv = lu_factor(matrix)
    rhs = rng.standard_normal(matrix.shape[0])
    rigid = rng.standard_normal((6 * fm.legs, fm.nv - len(fm.sv)))
    normal, right = rigid.T @ rigid, rigid.T @ rng.standard_normal(6 * fm.legs)
    q1 = pin.integrate(model, q, dq)
    stems = state.stem_lengths_m
    return {
        "rnea": _median_us(lambda: pin.rnea(model, data, q, v, a)),
        "computeJointJacobians": _median_us(lambda: pin.computeJointJacobians(model, data, q)),
        "getConstraintJacobian": _median_us(lambda: (cm.calc(model, data, cd),
                                                     pin.getConstraintJacobian(model, data, cm, cd))),
        "crba": _median_us(lambda: pin.crba(model, data, q, pin.Convention.WORLD), n=100),
        "forwardKinematics": _median_us(lambda: pin.forwardKinematics(model, data, q)),
        "computeMechanicalEnergy": _median_us(lambda: pin.computeMechanicalEnergy(model, data, q, v)),
        "computeMechanicalEnergy (kept)": _median_us(lambda: pin.computeMechanicalEnergy(model, data)),
        "integrate": _median_us(lambda: pin.integrate(model, q, dq)),
        "difference": _median_us(lambda: pin.difference(model, q, q1)),
        "lu_factor": _median_us(lambda: lu_factor(matrix, check_finite=False), n=30),
        "_getrs": _median_us(lambda: flexible._getrs(lu, piv, rhs)),
        "_posv": _median_us(lambda: flexible._posv(normal, right)),
        "re-placement (Python)": _median_us(lambda: (setattr(fm, "_placed_key", b""), fm._place(stems + 1e-4),
                                                     setattr(fm, "_placed_key", b""), fm._place(stems)), n=100) / 2,
    }


def _passive_us(case: object) -> float:
    rigid = rigid_leg_model(case.machine(), np.asarray(case.simulation.start_m, float))
    q, v, tau = rigid.reference_q.copy(), None, np.zeros(rigid.model.nv)
    v = rigid.admissible_velocity(q, [0.2, 0.1, -0.2])

    def steps() -> None:
        nonlocal q, v
        for _ in range(300):
            q, v = rigid.step(q, v, tau, 1e-4)

    return _median_us(steps, n=1) / 300


def main() -> None:
    case = load_case(cases_dir() / "paper" / "insertion.toml")
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"model": "flexible"})})
    simulate_insertion(case)  # the kernels loaded
    counts, steps, replaced = _counted_run(case)
    counts["re-placement (Python)"] = replaced
    fm = flexible.FlexibleMachine(case.machine(), np.asarray(case.simulation.start_m, float))
    times = _pass_times(fm, fm.rest_state())
    passive = _passive_us(case)
    print(f"shipped insertion, flexible: {steps} steps; the passive rigid-leg step {passive:.1f} us")
    print(f"{'operation':31s} {'per step':>9s} {'us each':>9s} {'us / step':>10s} {'passive steps':>14s}")
    floor = 0.0
    for name, per_call in times.items():
        per_step = counts[name] / steps
        cost = per_step * per_call
        floor += cost if name != "re-placement (Python)" else 0.0
        print(f"{name:31s} {per_step:9.3f} {per_call:9.1f} {cost:10.1f} {cost / passive:14.2f}")
    print(f"compiled arithmetic per step (without the re-placement): {floor:.0f} us = {floor / passive:.2f} passive "
          "steps (issue 29's flexible goal: 6.5 for the whole step)")


if __name__ == "__main__":
    main()
