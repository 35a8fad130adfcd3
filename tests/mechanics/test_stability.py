"""Stability of every solve, independent residuals, exact closure Jacobian, proportionality (issue 10).

References: the second-order optimality condition of a constrained minimum (the KKT matrix of a stable
minimum has exactly as many negative eigenvalues as constraints; Gould 1985), evaluated here on a DENSE
matrix with numpy's eigvalsh, independently of the blockwise (Haynsworth) algorithm of stability.py; the
machine's linearised buckling factor (tests/mechanics/test_buckling.py checks it against Euler); central finite
differences of the closure residual; the linearity of the small-displacement model (exact superposition).
"""

import numpy as np
import pinocchio as pin
import pytest

from pressfit.errors import UnstableEquilibriumError
from pressfit.mechanics import statics
from pressfit.mechanics.buckling import machine_buckling
from pressfit.mechanics.model import build_model
from pressfit.mechanics.stability import reduced_stability
from pressfit.mechanics.statics import solve_equilibrium

POSE_A = np.array([0.0, 0.72, 0.0])
POSE = np.array([0.1, 0.6, -0.15])
WRENCH = np.array([30.0, 700.0, -50.0, 5.0, 10.0, -7.0])


@pytest.mark.parametrize("pose,load", [(POSE_A, [0, 700, 0, 0, 0, 0]), (POSE_A, [0, -700, 0, 0, 0, 0]),
                                       (POSE, WRENCH), ((0.25, 0.5, -0.25), [0, 7000, 0, 0, 0, 0])])
@pytest.mark.parametrize("linear", [False, True])
def test_press_loads_are_stable(machine, pose, load, linear):
    s = solve_equilibrium(machine, pose, load, linear=linear).stability
    assert s.stable and s.kkt_negative_eigenvalues == s.constraints == 24
    assert 0 < s.min_eigenvalue_nm < s.max_eigenvalue_nm


def test_the_1e12_n_tensile_load_is_refused(machine):
    """Newton converged to a branch with a leg at -4e6 N (issue 10): the stability check refuses it."""
    with pytest.raises(UnstableEquilibriumError, match=r"no stable equilibrium at pose \(0, 0.72, 0\) m under the "
                                                       r"load \(0, 1e\+12, 0, 0, 0, 0\).*smallest eigenvalue -") as exc:
        solve_equilibrium(machine, POSE_A, [0, 1e12, 0])
    assert exc.value.leg is None and exc.value.pose_m == (0.0, 0.72, 0.0) and exc.value.load == (0, 1e12, 0, 0, 0, 0)


@pytest.mark.parametrize("linear", [False, True])
def test_compression_beyond_the_machine_buckling_load_is_refused(machine, linear):
    """The machine's linearised buckling factor under -700 N at pose A (143, a plate rotation mode) bounds the
    stable range of both solvers: 0.97 of it is stable, 1.03 of it is refused. The band is +-3%: the
    pre-buckling state at pose A is a pure vertical compression (the nonlinear factor differs from the
    linearised one by the shortening of the legs, ~1e-3), so the crossing must fall inside it."""
    lam = machine_buckling(machine, POSE_A, [0, -700, 0, 0, 0, 0]).load_factor
    assert solve_equilibrium(machine, POSE_A, [0, -700 * 0.97 * lam, 0], linear=linear).stability.stable
    with pytest.raises(UnstableEquilibriumError, match="beyond the machine's buckling load"):
        solve_equilibrium(machine, POSE_A, [0, -700 * 1.03 * lam, 0], linear=linear)


def _dense_kkt(tangent, scale):
    """The full KKT matrix of a linear reference, geometric stiffness scaled by ``scale``, in coordinates made
    angle-like (translations times L_ref) as stability.py does; rows of J scaled to H's size."""
    h = tangent.elastic + scale * tangent.geometric
    j = tangent.jacobian
    n = h.shape[0]
    kkt = np.zeros((n + 24, n + 24))
    kkt[:n, :n], kkt[:n, n:], kkt[n:, :n] = h, 1e6 * j.T, 1e6 * j
    return kkt


def _problem(solver, pose, wrench):
    """The solver's per-pose problem (pose values, problem, the thread's Pinocchio data) without preload."""
    pv = solver.model.pose_values(pose)
    pb, data = solver._problem(pv, np.asarray(wrench, dtype=float), np.zeros(4))
    return pv, pb, data


@pytest.mark.parametrize("scale,expect_stable", [(0.9, True), (1.1, False), (3.0, False)])
def test_blockwise_inertia_equals_the_dense_kkt_inertia(machine, scale, expect_stable):
    """Count of negative eigenvalues from the blockwise algorithm = the dense KKT matrix's (numpy eigvalsh on
    the whole 146 x 146 matrix), below and beyond buckling (scale = multiple of the buckling load)."""
    solver = statics.EquilibriumSolver(build_model(machine, POSE_A))
    lam = machine_buckling(solver, POSE_A, [0, -700, 0, 0, 0, 0]).load_factor
    ref = statics.reference_tangent(solver, POSE_A, np.array([0, -700.0 * lam, 0, 0, 0, 0]), None)
    dense = np.linalg.eigvalsh(_dense_kkt(ref, scale))
    n_dense = int((dense < -1e-9 * np.abs(dense).max()).sum())
    pv, pb, data = _problem(solver, POSE_A, np.array([0, -700.0 * lam * scale, 0, 0, 0, 0]))
    eq = statics._solve_linear(pb, data)
    st = statics._evaluate(pb, pv.q0, data)
    s = reduced_stability(*statics._tangent(pb, st, eq.multipliers), st.ja, st.jp, pb.is_force, pb.l_ref)
    assert s.kkt_negative_eigenvalues == n_dense
    assert s.stable is expect_stable and (n_dense == 24) is expect_stable


def test_machine_residual_is_independent_of_the_multipliers(machine):
    """The whole-machine residual comes from the spring forces alone: ~1e-16 for a converged solution; a
    corrupted deformation (one actuator spring off by 1e-9 m, 0.05 N at 5e7 N/m) shows in it at ~7e-5 of
    the 700 N load, and corrupted multipliers leave it unchanged while the plate residual flags them."""
    eq = solve_equilibrium(machine, POSE, WRENCH)
    assert eq.residuals.machine_force < 1e-12 and eq.residuals.machine_moment < 1e-12
    pv, pb, data = _problem(statics.EquilibriumSolver(machine, pose_m=POSE), POSE, WRENCH)
    d_leg = eq.q[pb.legq] - pv.q0[pb.legq]
    st = statics._evaluate(pb, eq.q, data, d_leg)
    good = statics._machine_residual(pb, st, st.g_leg)  # d_leg from q - q0 here: 1e-16 m x 5e7 N/m = 5e-9 N
    assert np.abs(good[:3]).max() < 2e-11 * 700  # of noise (achieved 4.5e-12 of the load)
    bad_d = d_leg.copy()
    bad_d[0, pb.act_col[0]] += 1e-9
    st_bad = statics._evaluate(pb, eq.q, data, bad_d)
    bad = statics._machine_residual(pb, st_bad, st_bad.g_leg)
    k = pb.k[0, pb.act_col[0]]
    assert np.linalg.norm(bad[:3]) == pytest.approx(k * 1e-9, rel=1e-3)  # the extra spring force, N
    lam_bad = eq.multipliers + 1.0
    res_bad = statics._result(pb, st, lam_bad, eq.q, d_leg, 0.0, 1, linear=False, data=data).residuals
    assert res_bad.machine_force == pytest.approx(np.linalg.norm(good[:3]) / pb.f_ref, rel=1e-12)
    assert res_bad.plate_force > 1e-3


def test_exact_closure_jacobian_by_finite_differences_off_the_manifold(machine):
    """dc/dq (rotation rows with Jlog3) vs central differences of c along pin.integrate at a configuration 1e-2
    rad / m off closure, to 1e-7 of the largest entry (step 1e-6: truncation ~1e-12, round-off ~1e-10). The
    twist-only rows (no Jlog3) miss it by ~|c| = 1e-2: the check would fail on them."""
    mm = build_model(machine, POSE, springs_per_segment=2)
    pv, pb, data = _problem(statics.EquilibriumSolver(mm), POSE, WRENCH)
    q = pin.integrate(pb.mm.model, pv.q0, 1e-2 * np.random.default_rng(7).normal(size=mm.model.nv))
    st = statics._evaluate(pb, q, data)
    assert np.abs(st.c).max() > 1e-3  # far off the manifold
    exact = np.zeros((4, 6, mm.model.nv))
    twist = np.zeros_like(exact)
    for i, v in enumerate(mm.leg_v):
        exact[i][:, v], exact[i][:, :6] = st.ja[i], st.jp[i]
        twist[i][:, v], twist[i][:, :6] = st.a[i], st.p[i]
    eps = 1e-6
    fd = np.stack([(statics._evaluate(pb, pin.integrate(pb.mm.model, q, eps * d), data).c
                    - statics._evaluate(pb, pin.integrate(pb.mm.model, q, -eps * d), data).c) / (2 * eps)
                   for d in np.eye(mm.model.nv)], -1)
    scale = np.abs(exact).max()
    assert np.abs(fd - exact).max() < 1e-9 * scale  # achieved 1.5e-10
    assert np.abs(fd - twist).max() > 1e-4 * scale


def test_linear_leg_forces_and_motion_are_proportional_to_the_load_at_any_scale(machine):
    """Linear solve, 1e-12 N to 1e4 N: actuator forces, multipliers and plate motion per newton agree to 1e-9
    (exact superposition: the reference is stress-free; achieved ~1e-14). Before, the reference's closure
    round-off (~1e-16 m x 5e7 N/m) acted as a 5e-9 N self-stress and dominated a 1e-12 N load."""
    ref = solve_equilibrium(machine, POSE, WRENCH / 700.0, linear=True)
    for f in (1e-12, 1e-6, 1.0, 1e4):
        eq = solve_equilibrium(machine, POSE, WRENCH / 700.0 * f, linear=True)
        assert np.allclose(eq.actuator_forces_n / f, ref.actuator_forces_n, rtol=1e-9, atol=0)
        assert np.allclose(eq.multipliers / f, ref.multipliers, rtol=1e-9, atol=1e-12)
        assert np.allclose(eq.plate_displacement_m / f, ref.plate_displacement_m, rtol=1e-9, atol=1e-18)
        assert np.allclose(eq.plate_rotation_rad / f, ref.plate_rotation_rad, rtol=1e-9, atol=1e-18)


def test_nonlinear_solution_tends_to_the_linear_one_at_small_loads(machine):
    """Nonlinear solve, 1e-12 N to 1e-3 N: actuator forces per newton differ from the linear ones by the
    geometric nonlinearity only, first order in the plate rotation theta (measured 6 theta); bound 10 theta
    + 1e-12 (round-off). At 1e-12 N the difference is 2e-14 (it was a sign change before)."""
    ref = solve_equilibrium(machine, POSE, WRENCH / 700.0, linear=True).actuator_forces_n
    for f in (1e-12, 1e-9, 1e-6, 1e-3):
        eq = solve_equilibrium(machine, POSE, WRENCH / 700.0 * f)
        theta = float(np.linalg.norm(eq.plate_rotation_rad))
        assert np.abs(eq.actuator_forces_n / f / ref - 1).max() < 10 * theta + 1e-12


def test_small_strain_range_is_a_leg_strain_not_a_plate_displacement(machine):
    """1e7 N of tension at pose A stretches each leg by about 1e7 / (4 sin a) x c_axial / l ~ 9% (stable, but
    far beyond small strains): refused. At (0, 0.8, 0) a 2.7 kN lateral force rotates the plate (the soft
    plate-rotation mode) and moves it 17 mm with leg strains below 1e-4: accepted (a 20 mm displacement cap
    refused its linear solve, 20.0 mm)."""
    with pytest.raises(UnstableEquilibriumError, match=r"changes length by [89]\.\d+% .* 1% small-strain range") as exc:
        solve_equilibrium(machine, POSE_A, [0, 1e7, 0])
    assert exc.value.leg in range(1, 5) and str(exc.value).startswith(f"leg {exc.value.leg} at pose (0, 0.72, 0) m")
    assert exc.value.pose_m == (0.0, 0.72, 0.0) and exc.value.load == (0, 1e7, 0, 0, 0, 0)
    eq = solve_equilibrium(machine, [0, 0.8, 0], [0, 4775.36, 2686.14], linear=True)
    assert np.linalg.norm(eq.plate_displacement_m) > 0.02 and eq.stability.stable
