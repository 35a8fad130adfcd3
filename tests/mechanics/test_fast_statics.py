"""The fast batched solver (pressfit.mechanics.fast_statics) against the reference Pinocchio solve.

Reference: :class:`pressfit.mechanics.statics.EquilibriumSolver` on the same model (Pinocchio kinematics,
exact-tangent Newton, per-leg KKT elimination), an independent implementation of the same equations.
Tolerances: the issue's accuracy targets, 1e-9 (linear) and 1e-7 (nonlinear) of the largest force and
moment; achieved about 1e-11 (both solvers stop at 1e-10 relative stationarity, round-off ~1e-12).
"""

import numpy as np
import pytest

from pressfit import kinematics
from pressfit.errors import FastSolverError
from pressfit.mechanics.fast_statics import FastEquilibriumSolver
from pressfit.mechanics.model import CardanCompliance, LinearSpring, build_model
from pressfit.mechanics.statics import SECTIONS, EquilibriumSolver


def random_cases(machine, n, seed):
    rng = np.random.default_rng(seed)
    poses = []
    while len(poses) < n:
        h = np.array([rng.uniform(-0.25, 0.25), rng.uniform(0.5, 0.75), rng.uniform(-0.25, 0.25)])
        if kinematics.is_reachable(machine, h):
            poses.append(h)
    loads = np.column_stack([rng.normal(0, 60, n), rng.uniform(-700, 700, n), rng.normal(0, 60, n),
                             rng.normal(0, 10, (n, 3))])
    return np.array(poses), loads


def worst_difference(ref, fast):
    """Largest difference of actuator forces and section wrenches (relative to the largest force / the
    largest moment of the reference) and of the plate motion (relative to its largest component)."""
    def sec(eq):
        return np.array([[list(leg.sections[s].as_dict().values()) for s in SECTIONS] for leg in eq.legs])
    a, b = sec(ref), sec(fast)
    f_scale = max(np.abs(a[..., :3]).max(), np.abs(ref.actuator_forces_n).max())
    m_scale = np.abs(a[..., 3:]).max()
    motion = np.concatenate([ref.plate_displacement_m, ref.plate_rotation_rad])
    motion_fast = np.concatenate([fast.plate_displacement_m, fast.plate_rotation_rad])
    return max(np.abs(ref.actuator_forces_n - fast.actuator_forces_n).max() / f_scale,
               np.abs(a[..., :3] - b[..., :3]).max() / f_scale, np.abs(a[..., 3:] - b[..., 3:]).max() / m_scale,
               np.abs(motion - motion_fast).max() / np.abs(motion).max(),
               np.abs(ref.multipliers - fast.multipliers).max() / f_scale)


@pytest.mark.parametrize("linear, tol", [(True, 1e-9), (False, 1e-7)])
@pytest.mark.parametrize("preload", [None, 400.0])
def test_fast_equals_reference(machine, linear, tol, preload):
    poses, loads = random_cases(machine, 12, seed=7)
    ref = EquilibriumSolver(machine, pose_m=poses[0])
    solver = FastEquilibriumSolver(ref.model)
    batch = solver.solve_batch(poses, loads, preload=preload, linear=linear)
    for i in range(len(poses)):
        eq = ref.solve(poses[i], loads[i], preload=preload, linear=linear)
        fast = solver.equilibrium(batch, i)
        assert worst_difference(eq, fast) < tol, i
        assert fast.is_valid(1e-9), fast.residuals
        np.testing.assert_allclose(fast.q[7:], eq.q[7:], atol=1e-9)  # leg coordinates (m, rad)
        # the stability report at the fast solution is the reference's (same tangent, states equal to ~1e-11)
        assert fast.stability.stable and eq.stability.stable
        assert fast.stability.min_eigenvalue_nm == pytest.approx(eq.stability.min_eigenvalue_nm, rel=1e-6)


@pytest.mark.parametrize("linear, tol", [(True, 1e-9), (False, 1e-7)])
def test_linear_cardan_springs_match_reference(machine, linear, tol):
    """Linear-spring cardan compliance (all eight cardans, translations and the c rotation): the general
    condensed step (the closed-form linear solve needs rigid cardans; the default model's linear solves
    above are the closed form)."""
    cc = CardanCompliance(translation=LinearSpring(2e8), rotation=LinearSpring(5e4))
    poses, loads = random_cases(machine, 4, seed=3)
    mm = build_model(machine, poses[0], cardan_compliance=cc)
    solver = FastEquilibriumSolver(mm)
    batch = solver.solve_batch(poses, loads, preload=300.0, linear=linear)
    ref = EquilibriumSolver(mm)
    for i in range(len(poses)):
        assert worst_difference(ref.solve(poses[i], loads[i], preload=300.0, linear=linear),
                                solver.equilibrium(batch, i)) < tol


def test_nonlinear_spring_laws_refused(machine):
    class Dead:  # a nonlinear law (as the clearance dead zone)
        def energy(self, x): return x ** 4
        def force(self, x): return 4 * x ** 3
        def tangent(self, x): return 12 * x ** 2
    mm = build_model(machine, kinematics.reference_pose_m(machine), cardan_compliance=CardanCompliance(axial=Dead()))
    with pytest.raises(FastSolverError, match="nonlinear laws"):
        FastEquilibriumSolver(mm)


def current_rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


def test_memory_flat_in_spring_count(machine):
    """n = 32 springs per segment (nv = 794): model and fast solves within 150 MB of resident memory (the
    Pinocchio Data of this model would take ~16 GB: pin 4.1 allocates nv^3 derivative tensors)."""
    before = current_rss_bytes()
    poses, loads = random_cases(machine, 8, seed=5)
    solver = FastEquilibriumSolver(machine, springs_per_segment=32, pose_m=poses[0])
    out = solver.solve_batch(poses, loads)
    assert solver.model.model.nv == 794
    assert np.all(out.residuals.max(1) < 1e-9)
    assert current_rss_bytes() - before < 150e6


def test_spring_count_convergence_to_32(machine):
    """Nonlinear axial forces converge as 1/n^2 toward the smooth beam (a bent segment's chord shortens by
    L phi^2/8 with one kink against L phi^2/24 smooth; docs/conventions.md): with N_32 as the reference, the error
    ratio e_4 / e_8 is (1/16 - 1/1024) / (1/64 - 1/1024) = 4.2 for a pure 1/n^2 law (accepted 3.5-5), and
    the default count (4) is within 1e-4 of the largest force."""
    pose, load = np.array([[0.2, 0.6, -0.2]]), np.array([60.0, 700.0, -60.0, 8.0, 12.0, -6.0])
    forces = {n: FastEquilibriumSolver(machine, springs_per_segment=n, pose_m=pose[0]).solve_batch(pose, load)
              .actuator_forces_n[0] for n in (4, 8, 32)}
    e4, e8 = (np.abs(forces[n] - forces[32]).max() for n in (4, 8))
    assert 3.5 < e4 / e8 < 5.0
    assert e4 < 1e-4 * np.abs(forces[32]).max()


def test_compliance_and_check_refinement_equal_reference(machine):
    """The wired fast paths: vjm_plate_compliance (linear: exact, 1e-9; tangent: central differences of
    nonlinear solves, whose 1e-7 agreement is amplified by |load| / step ~ 10^3 at most) and the limit
    check's batched refinement, against the Pinocchio solve of the same pairs."""
    from pressfit.mechanics.compliance import vjm_plate_compliance
    from pressfit.studies.limit_check import _refine, equilibrium_quantities

    pose, load = np.array([0.2, 0.6, -0.15]), np.array([30.0, 700.0, -20.0, 1.0, 2.0, 3.0])
    ref = EquilibriumSolver(machine, pose_m=pose)
    for wrench, tol in ((None, 1e-9), (load, 1e-6)):
        d = np.diag([1.0] * 3 + [0.1] * 3)
        cols = [np.concatenate([ref.solve(pose, e, linear=True).plate_displacement_m,
                                ref.solve(pose, e, linear=True).plate_rotation_rad]) for e in np.eye(6)] \
            if wrench is None else \
            [(np.concatenate([(a := ref.solve(pose, wrench + e)).plate_displacement_m, a.plate_rotation_rad])
              - np.concatenate([(b := ref.solve(pose, wrench - e)).plate_displacement_m, b.plate_rotation_rad]))
             / (2 * e.max()) for e in d]
        expected = np.stack(cols, 1)
        got = vjm_plate_compliance(machine, pose, wrench)
        assert np.abs(got - expected).max() < tol * np.abs(expected).max()
    poses, loads = random_cases(machine, 3, seed=5)
    pairs = [(0, 0), (1, 2), (2, 1)]
    critical = np.full((1, 4), 1e5)
    for linear, tol in ((True, 1e-9), (False, 1e-7)):
        refined = _refine(machine, poses, loads, pairs, linear, 300.0)
        for j, p in pairs:
            eq = ref.solve(poses[p], loads[j], linear=linear, preload=300.0)
            a, b = equilibrium_quantities(eq, critical), equilibrium_quantities(refined[(j, p)], critical)
            for key in set(a) - {"min_buckling_safety_factor"}:  # that one is critical / N of the forces compared
                scale = np.abs(eq.actuator_forces_n).max() if key == "max_shear_n" else np.abs(a[key]).max()
                assert np.abs(a[key] - b[key]).max() <= tol * scale, key  # shear: 0 in the linear model
            stab = refined[(j, p)].stability
            assert stab.stable and eq.stability.stable
            assert stab.min_eigenvalue_nm == pytest.approx(eq.stability.min_eigenvalue_nm, rel=1e-6)
