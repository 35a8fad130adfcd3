"""Monte Carlo samples with joint position errors on the batched fast solver (pressfit.studies.montecarlo: each
sample's joint positions B_i + e_B, d_i + e_d passed to one batched solve on the nominal model) against the path
it replaced: a machine, a Pinocchio model and a fast solver built per sample with its errors (the sample's own
joint positions, leg lengths and length offsets from that machine's inverse kinematics)."""

import dataclasses
import math

import numpy as np

from pressfit import kinematics
from pressfit.description.cases import load_case
from pressfit.errors import UnreachablePoseError, UnstableEquilibriumError
from pressfit.mechanics.fast_statics import FastEquilibriumSolver
from pressfit.shipped import cases_dir
from pressfit.studies import montecarlo as mc


def model_per_sample(plan, xj, azimuth):
    """One sample's row the previous way: its machine (joint errors in the machine file's keys), its own model and
    fast solver, its leg lengths from its own inverse kinematics (the drives held at the nominal lengths)."""
    nominal = mc._nominal(plan)
    machine = mc._perturbed(plan.machine, xj)
    lengths = kinematics.inverse_kinematics(machine, plan.poses_m).lengths_m
    s = dataclasses.replace(mc._sample_loads(plan, nominal, {"load_tilt_rad": xj["load_tilt_rad"]}, azimuth),
                            base_points_m=machine.base_points_m, plate_offsets_m=machine.plate_offsets_m,
                            lengths_m=lengths, critical_n=plan.critical_loads_n(lengths),
                            offsets_m=nominal.lengths_m - lengths + xj["actuator_length_offset_m"]
                            + nominal.preload_offsets_m)
    return mc._fast_rows(plan, nominal, [s], FastEquilibriumSolver(machine, pose_m=plan.poses_m[0]))[0]


def shipped_plan(samples):
    return mc.plan_from_case(load_case(cases_dir() / "studies" / "montecarlo_tolerances.toml"), samples=samples,
                             chunk_size=samples)


def test_joint_errors_through_the_batch_equal_a_model_per_sample():
    """The shipped 3-pose case (joint errors +-10 um, drive offsets, load tilt), 6 samples in one chunk: every column
    equal to round-off (rtol 1e-12, measured bit-identical: the same equations and operations on the same numbers,
    the batch only longer), the inputs exactly."""
    plan = shipped_plan(6)
    assert "one model per chunk (joint position errors as per-sample joint positions)" in mc.solver_path(plan)
    seed = mc.chunk_seeds(plan)[0]
    cols, x = mc.evaluate_chunk(plan, 0, seed), mc.draw_inputs(plan, 0, seed)
    assert np.all(cols["status"] == "ok")
    assert np.all(np.minimum(cols["min_buckling_safety_factor"], cols["min_leg_euler_factor"])
                  >= mc.STABILITY_RECHECK_FACTOR)  # no sample re-solved by the reference solver: the fast rows alone
    np.testing.assert_array_equal(cols["base_point_error_m.leg2.y"], x["base_point_error_m"][:, 4])
    for j in range(6):
        old = model_per_sample(plan, {n: v[j] for n, v in x.items()}, float(x["load_azimuth_rad"][j]))
        for k in (*mc.OUTPUTS, *mc.EXTRA_OUTPUTS):
            assert math.isfinite(old[k])
            np.testing.assert_allclose(cols[k][j], old[k], rtol=1e-12, atol=0, err_msg=k)


def test_a_sample_whose_joint_errors_make_a_pose_unreachable_fails_alone():
    """Three samples, the middle one's base cardan of leg 1 moved 0.3 m back along its leg at the first pose (past
    l_max): its solve fails alone (unreachable pose) and, its drives held 0.3 m short, the whole machine's buckling
    factor is 0, so it is stored as unstable (what building its own model, which refuses the pose, gave); the other
    two keep the values they have in a batch without it (exactly)."""
    plan = shipped_plan(3)
    n = len(plan.machine.legs)
    e = kinematics.inverse_kinematics(plan.machine, plan.poses_m[0]).unit_vectors[0]
    assert kinematics.inverse_kinematics(plan.machine, plan.poses_m[0]).lengths_m[0] + 0.3 > \
        plan.machine.limits.leg_length_max_m
    rng = np.random.default_rng(4)
    x = [{"base_point_error_m": rng.uniform(-1e-5, 1e-5, 3 * n), "plate_point_error_m": rng.uniform(-1e-5, 1e-5, 3 * n),
          "actuator_length_offset_m": rng.normal(0, 2e-6, n), "load_tilt_rad": np.array([0.01])} for _ in range(3)]
    x[1]["base_point_error_m"][:3] = -0.3 * e
    rows = mc._evaluate_fast(plan, x, np.array([0.1, 0.2, 0.3]))
    nominal = mc._nominal(plan)
    solve = mc._fast_rows(plan, nominal, [mc._sample_loads(plan, nominal, x[1], 0.2)],
                          FastEquilibriumSolver(plan.machine, pose_m=plan.poses_m[0]))[0]
    assert isinstance(solve, UnreachablePoseError) and solve.violations[0][:2] == (1, "leg length l [m]")
    assert isinstance(rows[1], UnstableEquilibriumError) and "buckling factor 0 < 1" in str(rows[1])
    alone = mc._evaluate_fast(plan, [x[0], x[2]], np.array([0.1, 0.3]))
    assert rows[0] == alone[0] and rows[2] == alone[1]
