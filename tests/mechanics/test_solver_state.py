"""The equilibrium solver holds no state between poses, pickles, and is safe from several threads.

References: bit-identity with a fresh solver (nothing may leak from a previous pose into the stem
placements, stiffnesses, rest values or q0), and the sequential answers of the same solver.
"""

import pickle
import threading

import numpy as np

from pressfit.mechanics.statics import EquilibriumSolver

POSE_A, POSE_B = np.array([0.1, 0.6, -0.15]), np.array([-0.2, 0.72, 0.1])  # stem lengths differ by ~0.1 m
WRENCH = np.array([30.0, 700.0, -20.0, 5.0, -3.0, 2.0])


def _same(a, b):
    return (np.array_equal(a.q, b.q) and np.array_equal(a.multipliers, b.multipliers)
            and np.array_equal(a.actuator_forces_n, b.actuator_forces_n))


def test_pose_b_then_a_is_bit_identical_to_a_on_a_fresh_solver(machine):
    for linear in (True, False):
        used = EquilibriumSolver(machine, pose_m=POSE_A)
        used.solve(POSE_B, WRENCH, linear=linear, preload=300.0)
        after_b = used.solve(POSE_A, WRENCH, linear=linear)
        fresh = EquilibriumSolver(machine, pose_m=POSE_A).solve(POSE_A, WRENCH, linear=linear)
        assert _same(after_b, fresh)
    # and the model the solver owns is never modified
    assert np.array_equal(used.model.pose_m, POSE_A)


def test_pickled_solver_gives_the_same_answers(machine):
    solver = EquilibriumSolver(machine, pose_m=POSE_A)
    ref = solver.solve(POSE_B, WRENCH)
    clone = pickle.loads(pickle.dumps(solver))
    assert _same(clone.solve(POSE_B, WRENCH), ref)


def test_threads_sharing_a_solver_match_sequential_solves(machine):
    solver = EquilibriumSolver(machine, pose_m=POSE_A)
    poses = [POSE_A, POSE_B, np.array([0.0, 0.65, 0.2]), np.array([0.15, 0.55, 0.0])] * 3
    sequential = [solver.solve(h, WRENCH) for h in poses]
    out = [None] * len(poses)

    def work(k0):
        for k in range(k0, len(poses), 2):
            out[k] = solver.solve(poses[k], WRENCH)

    threads = [threading.Thread(target=work, args=(k,)) for k in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all(_same(a, b) for a, b in zip(out, sequential))
