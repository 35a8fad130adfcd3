"""The fast batched solver with per-solve joint positions (pressfit.mechanics.fast_statics, ``base_points_m`` and
``plate_offsets_m``) against a machine built per sample with those joint position errors and solved by the
reference Pinocchio solver (pressfit.mechanics.statics), an independent implementation of the same equations on
that machine's own model.

Tolerances: those of the fast-vs-reference tests (tests/mechanics/test_fast_statics.py, the issue's accuracy
targets), 1e-9 (linear) and 1e-7 (nonlinear) of the largest force and moment; both solvers stop at 1e-10 relative
stationarity.
"""

import numpy as np
import pytest
from test_fast_statics import random_cases, worst_difference

from pressfit import kinematics
from pressfit.errors import FastSolverError, PressfitError, UnreachablePoseError
from pressfit.mechanics.fast_statics import FastEquilibriumSolver
from pressfit.mechanics.model import build_model
from pressfit.mechanics.statics import EquilibriumSolver


def with_errors(machine, base_m, plate_m):
    """The machine with joint position errors (n, 3) on its base and plate cardan centres (its own file's way)."""
    legs = [leg.model_dump() for leg in machine.legs]
    for leg, eb, ed in zip(legs, base_m, plate_m):
        leg["base_point_error_m"], leg["plate_point_error_m"] = eb.tolist(), ed.tolist()
    return machine.with_overrides({"legs": legs})


@pytest.mark.parametrize("linear, tol", [(True, 1e-9), (False, 1e-7)])
def test_per_sample_joint_positions_equal_a_machine_per_sample(machine, linear, tol):
    """Three samples with uniform joint errors up to 1 mm per component at four poses each, one batched call on the
    nominal model; each sample's machine solved on its own model by the reference solver, with per-sample actuator
    rest-length offsets (position-held drives, a self-stress)."""
    rng = np.random.default_rng(11)
    n, samples = len(machine.legs), 3
    poses, loads = random_cases(machine, 4, seed=2)
    errors = rng.uniform(-1e-3, 1e-3, (samples, 2, n, 3))
    offsets = rng.normal(0.0, 5e-6, (samples, len(poses), n))
    machines = [with_errors(machine, *e) for e in errors]
    fast = FastEquilibriumSolver(machine, pose_m=poses[0])
    batch = fast.solve_batch(np.tile(poses, (samples, 1)), np.tile(loads, (samples, 1)),
                             preload_offsets_m=offsets.reshape(-1, n),
                             base_points_m=np.repeat([m.base_points_m for m in machines], len(poses), axis=0),
                             plate_offsets_m=np.repeat([m.plate_offsets_m for m in machines], len(poses), axis=0),
                             linear=linear)
    assert batch.residuals.max() < 1e-9
    for s, m in enumerate(machines):
        ref = EquilibriumSolver(m, pose_m=poses[0])
        assert not np.allclose(m.base_points_m, machine.base_points_m)
        for p in range(len(poses)):
            i = s * len(poses) + p
            eq = ref.solve(poses[p], loads[p], preload_offsets_m=offsets[s, p], linear=linear)
            got = batch.equilibrium(i, eq.stability)  # the sample's stability is the reference's (own model)
            assert worst_difference(eq, got) < tol, (s, p)
            np.testing.assert_allclose(batch.q[i, 7:], eq.q[7:], atol=1e-9)  # leg coordinates (m, rad)


def test_a_base_point_error_along_the_leg_lengthens_it_and_moves_its_stem_springs(machine):
    """Leg 1's base cardan moved 1 mm back along its leg at a pose: that leg is 1 mm longer there (closed form:
    u -> u + 1 mm e), so its stem is 1 mm longer, its stem springs sit further apart and its stem and actuator
    stiffnesses change: the fast solver's per-solve placements and stiffnesses must be the sample model's own
    (:meth:`MachineModel.pose_values` of a model built on that machine), not the nominal ones."""
    n = len(machine.legs)
    pose = np.array([0.1, 0.62, -0.05])
    e = kinematics.inverse_kinematics(machine, pose).unit_vectors[0]
    base = machine.base_points_m.copy()
    base[0] -= 1e-3 * e
    own = build_model(with_errors(machine, base - machine.base_points_m, np.zeros((n, 3))), pose)
    at = own.pose_values(pose)
    fast = FastEquilibriumSolver(machine, pose_m=pose)
    ch = fast._chain
    block, nominal = (fast._block(pose[None], np.zeros((1, 6)), np.zeros((1, n)), b[None],
                                  machine.plate_offsets_m[None]) for b in (base, machine.base_points_m))
    stem = kinematics.inverse_kinematics(machine, pose).lengths_m - machine.cylinder.length_m
    np.testing.assert_allclose(at.stem_lengths_m - stem, [1e-3] + [0.0] * (n - 1), atol=1e-12)
    np.testing.assert_allclose(block.q0leg[0], at.q0[fast._legq], atol=1e-15)  # prismatic: the 1 mm longer leg
    np.testing.assert_allclose(block.z[0][:, ch.stem_cols], own.stem_placements_z(at.stem_lengths_m), rtol=1e-14)
    np.testing.assert_allclose(block.ks[0], at.spring_k[ch.spring_index], rtol=1e-14)
    changed = ~np.isclose(block.ks[0], nominal.ks[0], rtol=1e-6, atol=0)
    assert changed[0].sum() == 1 + 3 * own.springs_per_segment and not changed[1:].any()  # leg 1: actuator, stem
    assert np.abs(block.z[0, 0, ch.stem_cols] - nominal.z[0, 0, ch.stem_cols]).min() > 1e-4


def test_joint_positions_make_a_pose_unreachable_by_their_own_limits(machine):
    """Leg 3's base cardan moved back along its leg by more than half the stroke at the reference pose (legs at
    (l_min + l_max) / 2): that leg passes l_max, which the layout's own inverse kinematics must find, as for a
    machine built with that error."""
    h = kinematics.reference_pose_m(machine)
    lim = machine.limits
    base = machine.base_points_m.copy()
    base[2] -= (0.5 * (lim.leg_length_max_m - lim.leg_length_min_m) + 0.01) * \
        kinematics.inverse_kinematics(machine, h).unit_vectors[2]
    fast = FastEquilibriumSolver(machine, pose_m=h)
    with pytest.raises(UnreachablePoseError, match="leg length") as err:
        fast.solve_batch(h, np.zeros(6), base_points_m=base)
    assert [v[0] for v in err.value.violations] == [3]  # leg 3 (1-based) only


def test_layout_input_is_checked(machine):
    h = kinematics.reference_pose_m(machine)
    n = len(machine.legs)
    fast = FastEquilibriumSolver(machine, pose_m=h)
    with pytest.raises(PressfitError, match=r"base_points_m: joint positions \(m\) of shape \(1, 4, 3\)"):
        fast.solve_batch(h, np.zeros(6), base_points_m=np.zeros((n + 1, 3)))
    bad = machine.plate_offsets_m.copy()
    bad[1, 2] = np.nan
    with pytest.raises(PressfitError, match="plate_offsets_m: joint positions must be finite"):
        fast.solve_batch(h, np.zeros(6), plate_offsets_m=bad)
    with pytest.raises(PressfitError, match="give the rest-length offsets"):
        fast.solve_batch(h, np.zeros(6), preload=300.0, base_points_m=machine.base_points_m)
    batch = fast.solve_batch(h, np.zeros(6), base_points_m=machine.base_points_m + 1e-5)
    with pytest.raises(FastSolverError, match="joint positions other than the model's"):
        fast.equilibrium(batch, 0)
