"""Compliant statics (pressfit.statics) against independent references.

* the exact condensation of docs/conventions.md (written here from scratch: per leg k_a w1 w1^T + k_r w2 w2^T
  about P*), for the linear solve, to 1e-9 (both sides are exact; round-off is ~1e-13);
* energy stationarity on the constraint manifold, evaluated with forward kinematics only;
* global equilibrium (sum of base reactions = load), machine symmetry, preload, rigid limit,
  segment-count convergence, finite differences of the analytic tangent and of the plate compliance.
"""

import math

import numpy as np
import pinocchio as pin
import pytest

from pressfit import kinematics
from pressfit.errors import ConvergenceError, SingularPoseError, UnreachablePoseError
from pressfit.mechanics import statics
from pressfit.mechanics.model import CardanCompliance, LinearSpring, build_model
from pressfit.mechanics.statics import solve_equilibrium

POSE = np.array([0.1, 0.6, -0.15])
WRENCH = np.array([30.0, 700.0, -50.0, 5.0, 10.0, -7.0])


def condensed(machine, pose, wrench):
    """Independent exact linear condensation (docs/conventions.md): axial forces, couple vectors (world) and plate
    displacement / rotation at the plate centre."""
    h = np.asarray(pose, float)
    p, r = machine.geometry.base_half_side_m, machine.geometry.plate_half_side_m
    star = h * p / (p - r)
    E, G = machine.material.youngs_modulus_pa, machine.material.shear_modulus_pa
    cs, ss, lc = machine.cylinder_section, machine.stem_section, machine.cylinder.length_m
    kt, kr = np.zeros((3, 3)), np.zeros((3, 3))
    legs = []
    for i in range(4):
        u = h + machine.plate_offsets_m[i] - machine.base_points_m[i]
        l = np.linalg.norm(u)
        e = u / l
        a = machine.cardan_axes[i]
        b = np.cross(e, a)
        b /= np.linalg.norm(b)
        c = np.cross(a, b)
        cos_b = abs(c @ e)  # c = cos(beta) e + sin(beta) (normal): torsion and bending shares
        ct = lc / (G * cs.polar_moment_m4) + (l - lc) / (G * ss.polar_moment_m4)
        cm = lc / (E * cs.second_moment_m4) + (l - lc) / (E * ss.second_moment_m4)
        ka = 1.0 / (1 / machine.actuator.axial_stiffness_n_per_m + lc / (E * cs.area_m2) + (l - lc) / (E * ss.area_m2))
        k_r = 1.0 / (cos_b**2 * ct + (1 - cos_b**2) * cm)
        kt += ka * np.outer(e, e)
        kr += k_r * np.outer(c, c)
        legs.append((e, c, ka, k_r))
    f, m = wrench[:3], wrench[3:]
    m_star = m + np.cross(h - star, f)
    dp, dth = np.linalg.solve(kt, f), np.linalg.solve(kr, m_star)
    n = np.array([ka * e @ dp for e, c, ka, k_r in legs])
    couples = np.array([k_r * (c @ dth) * c for e, c, ka, k_r in legs])
    return n, couples, dp + np.cross(dth, h - star), dth


def world_vectors(leg, name):
    s = leg.sections[name]
    return leg.frame @ np.array([s.V_x, s.V_y, s.N]), leg.frame @ np.array([s.M_x, s.M_y, s.T])


@pytest.mark.parametrize("pose,wrench", [(POSE, WRENCH), ((0.2765, 0.72, -0.2765), (0, 700, 0, 0, 0, 0)),
                                         ((-0.2, 0.52, 0.22), (-80, -300, 40, -12, 3, 20))])
def test_linear_solve_equals_exact_condensation(machine, pose, wrench):
    eq = solve_equilibrium(machine, pose, wrench, linear=True)
    n, couples, disp, rot = condensed(machine, np.array(pose), np.array(wrench, float))
    fs = np.abs(n).max()
    assert np.allclose(eq.actuator_forces_n, n, rtol=0, atol=1e-9 * fs)
    for i, leg in enumerate(eq.legs):
        for name in statics.SECTIONS:
            force, moment = world_vectors(leg, name)
            assert pytest.approx(n[i], abs=1e-9 * fs) == leg.sections[name].N
            assert abs(leg.sections[name].V_x) < 1e-9 * fs and abs(leg.sections[name].V_y) < 1e-9 * fs  # no shear
            assert np.allclose(moment, couples[i], rtol=0, atol=1e-9 * fs * 0.442)
    assert np.allclose(eq.plate_displacement_m, disp, rtol=0, atol=1e-9 * np.abs(disp).max())
    assert np.allclose(eq.plate_rotation_rad, rot, rtol=0, atol=1e-9 * max(np.abs(rot).max(), 1e-12))
    assert eq.is_valid(1e-9) and eq.linear


def test_pose_A_every_leg_carries_700_over_4_sin_alpha(machine):
    closed = 700.0 / (4 * math.sin(math.atan(2.0)))  # tan(alpha) = 0.72 / (0.442 - 0.082) = 2
    lin = solve_equilibrium(machine, [0, 0.72, 0], [0, 700, 0, 0, 0, 0], linear=True)
    non = solve_equilibrium(machine, [0, 0.72, 0], [0, 700, 0, 0, 0, 0])
    for eq, tol in ((lin, 1e-12), (non, 1e-5)):  # nonlinear: the legs shorten by ~5 um of 0.8 m (~1e-5)
        for leg in eq.legs:
            for s in leg.sections.values():
                assert pytest.approx(closed, rel=tol) == s.N
                assert max(abs(s.V_x), abs(s.V_y), abs(s.M_x), abs(s.M_y), abs(s.T)) < 1e-9
    assert closed == pytest.approx(195.66, abs=5e-3)


def _energy(mm, q, offsets):
    e = 0.0
    for s in mm.springs:
        e += s.law.energy(q[s.idx_q] - s.rest - (offsets[s.leg] if s.name == "actuator" else 0.0))
    return e


def _closure(mm, q, data):
    pin.forwardKinematics(mm.model, data, q)
    out = []
    for i in range(4):
        a = data.oMi[mm.leg_joint_ids[i]["plate_end"]]
        b = data.oMi[mm.plate_joint_id] * mm.anchor_placements[i]
        out.append(pin.log6(a.actInv(b)).vector)
    return np.concatenate(out)


def test_nonlinear_solution_is_energy_stationary_on_the_constraint_manifold(machine):
    """Forward kinematics only: tangent directions = null space of a finite-difference closure Jacobian;
    along each, d(E - W)/d eps by central differences (dead load: work F . dp + M . dtheta) must vanish.
    Tolerance: 1e-6 of the typical term |dE/d eps| (central differences with eps = 1e-6 give ~1e-9)."""
    mm = build_model(machine, POSE, springs_per_segment=2)
    eq = solve_equilibrium(mm, POSE, WRENCH, preload=300.0)
    q, data, nv = eq.q, mm.model.createData(), mm.model.nv
    eps = 1e-6
    jac = np.array([(_closure(mm, pin.integrate(mm.model, q, eps * d), data)
                     - _closure(mm, pin.integrate(mm.model, q, -eps * d), data)) / (2 * eps) for d in np.eye(nv)]).T
    tangent = np.linalg.svd(jac)[2][24:].T  # (nv, nv - 24)
    rng = np.random.default_rng(3)
    worst, scale = 0.0, 0.0
    for d in (tangent @ rng.normal(size=(tangent.shape[1], 8))).T:
        def plate(t, d=d):
            qq = pin.integrate(mm.model, q, t * d)
            pin.forwardKinematics(mm.model, data, qq)
            return qq, data.oMi[mm.plate_joint_id].copy()
        qp, mp = plate(eps)
        qm, mm_ = plate(-eps)
        de = (_energy(mm, qp, eq.preload_offsets_m) - _energy(mm, qm, eq.preload_offsets_m)) / (2 * eps)
        dwork = (WRENCH[:3] @ (mp.translation - mm_.translation)
                 + WRENCH[3:] @ pin.log3(mp.rotation @ mm_.rotation.T)) / (2 * eps)
        worst, scale = max(worst, abs(de - dwork)), max(scale, abs(de))
    assert scale > 1.0
    assert worst < 1e-6 * scale


@pytest.mark.parametrize("linear", [True, False])
def test_base_reactions_balance_the_load(machine, linear):
    """Sum over legs of the base-section wrench (what each leg pushes into the base) = the load, about the
    world origin, to 1e-9 relative (the reactions and load are O(700 N), moments O(700 N x 0.442 m))."""
    eq = solve_equilibrium(machine, POSE, WRENCH, linear=linear)
    mm = build_model(machine, POSE)
    data = mm.model.createData()
    pin.forwardKinematics(mm.model, data, mm.q0 if linear else eq.q)
    f_sum, m_sum = np.zeros(3), np.zeros(3)
    for i, leg in enumerate(eq.legs):
        force, moment = world_vectors(leg, "base")
        b = data.oMi[mm.leg_joint_ids[i]["cylinder"]].translation
        f_sum += force
        m_sum += moment + np.cross(b, force)
    pc = POSE + (0 if linear else eq.plate_displacement_m)
    assert np.linalg.norm(f_sum - WRENCH[:3]) < 1e-9 * 700
    assert np.linalg.norm(m_sum - (WRENCH[3:] + np.cross(pc, WRENCH[:3]))) < 1e-9 * 700 * 0.442
    assert eq.residuals.machine_force < 1e-9 and eq.residuals.machine_moment < 1e-9 and eq.is_valid(1e-9)


def test_axial_forces_are_the_concurrent_truss_about_p_star(machine):
    """Linear: the axial forces satisfy sum N_i e_i = F with compatible elongations N_i / k_a = e_i . dp*
    (the leg lines meet at P*, so M about P* goes to the couples only), whatever the load moment."""
    for m in ([0, 0, 0], [40, -20, 15]):
        w = np.concatenate([WRENCH[:3], m])
        eq = solve_equilibrium(machine, POSE, w, linear=True)
        ik = kinematics.inverse_kinematics(machine, POSE)
        ka = 1 / machine.axial_compliance_m_per_n(ik.lengths_m)
        kt = sum(ka[i] * np.outer(ik.unit_vectors[i], ik.unit_vectors[i]) for i in range(4))
        n = ka * (ik.unit_vectors @ np.linalg.solve(kt, w[:3]))
        assert np.allclose(eq.actuator_forces_n, n, rtol=0, atol=1e-9 * 700)


def test_stiff_limit_nonlinear_tends_to_the_linear_rigid_limit(machine):
    """Scaling every stiffness by s leaves the linear forces unchanged (they depend on stiffness ratios)
    and shrinks displacements as 1/s, so the nonlinear - linear gap must fall ~ 1/s (achieved within 0.8%,
    the next order 1/s^2; 2%)."""
    gaps = []
    for s in (1.0, 1e1, 1e2):
        mach = machine.with_overrides({"material": {"youngs_modulus_pa": 210e9 * s, "shear_modulus_pa": 81e9 * s},
                                       "actuator": {"axial_stiffness_n_per_m": 5e7 * s}})
        lin = solve_equilibrium(mach, POSE, WRENCH, linear=True)
        non = solve_equilibrium(mach, POSE, WRENCH)
        if s == 1.0:
            ref = lin.actuator_forces_n
        assert np.allclose(lin.actuator_forces_n, ref, rtol=1e-8)  # LU round-off grows ~ s (unscaled KKT)
        gaps.append(np.abs(non.actuator_forces_n - lin.actuator_forces_n).max())
    assert gaps[0] > 0.1  # the nonlinearity is real at nominal stiffness (~1 N of 300 N)
    assert gaps[1] == pytest.approx(gaps[0] / 1e1, rel=0.02)
    assert gaps[2] == pytest.approx(gaps[0] / 1e2, rel=0.02)


MIRRORS = {  # reflection S, leg permutation (leg i -> image leg)
    "x": (np.diag([-1.0, 1, 1]), [0, 3, 2, 1]),
    "z": (np.diag([1.0, 1, -1]), [2, 1, 0, 3]),
}


@pytest.mark.parametrize("plane", ["x", "z"])
def test_mirror_poses_give_mirrored_loads(machine, plane):
    """Reflection S: forces map as S F, moments (pseudo-vectors) as -S M (det S = -1). 1e-9 relative."""
    s, perm = MIRRORS[plane]
    w2 = np.concatenate([s @ WRENCH[:3], -s @ WRENCH[3:]])
    a = solve_equilibrium(machine, POSE, WRENCH)
    b = solve_equilibrium(machine, s @ POSE, w2)
    tol = 1e-9 * 700
    for i in range(4):
        j = perm[i]
        for name in statics.SECTIONS:
            fa, ma = world_vectors(a.legs[i], name)
            fb, mb = world_vectors(b.legs[j], name)
            assert np.allclose(s @ fa, fb, atol=tol) and np.allclose(-s @ ma, mb, atol=tol * 0.442)
    assert np.allclose(s @ a.plate_displacement_m, b.plate_displacement_m, atol=1e-12)
    assert np.allclose(-s @ a.plate_rotation_rad, b.plate_rotation_rad, atol=1e-12)


@pytest.mark.parametrize("linear", [True, False])
def test_preload_alone_acts_along_v_p_without_bending(machine, linear):
    a4 = 1000.0
    eq = solve_equilibrium(machine, POSE, np.zeros(6), preload=a4, linear=linear)
    vp = kinematics.preload_vector(machine, POSE)
    assert np.allclose(eq.actuator_forces_n, a4 * vp, rtol=0, atol=1e-9 * a4)
    for i, leg in enumerate(eq.legs):
        for s in leg.sections.values():
            assert pytest.approx(a4 * vp[i], abs=1e-9 * a4) == s.N
            assert max(abs(s.V_x), abs(s.V_y), abs(s.M_x), abs(s.M_y), abs(s.T)) < 1e-9 * a4
    assert np.abs(eq.plate_displacement_m).max() < 1e-15 and eq.is_valid(1e-9)


def test_length_mode_preload_shortens_the_actuators(machine):
    vp = kinematics.preload_vector(machine, POSE)
    eq = solve_equilibrium(machine, POSE, np.zeros(6), preload=1e-5, preload_mode="length")
    assert np.allclose(eq.preload_offsets_m, -1e-5 * vp)
    assert eq.is_valid(1e-9)
    assert np.sign(eq.actuator_forces_n) @ np.sign(vp) == 4  # a4 > 0 pulls where v_p > 0


def test_force_mode_preload_then_load(machine):
    """Linear: preload and load superpose exactly (N += a4 v_p). Nonlinear: close to it (geometric terms)."""
    base = solve_equilibrium(machine, POSE, WRENCH, linear=True)
    pre = solve_equilibrium(machine, POSE, WRENCH, preload=800.0, linear=True)
    vp = kinematics.preload_vector(machine, POSE)
    assert np.allclose(pre.actuator_forces_n, base.actuator_forces_n + 800 * vp, atol=1e-9 * 800)
    non = solve_equilibrium(machine, POSE, WRENCH, preload=800.0)
    assert np.allclose(non.actuator_forces_n, pre.actuator_forces_n, rtol=0.05) and non.is_valid(1e-9)


def test_analytic_tangent_matches_finite_differences_of_the_gradient(machine):
    """The KKT tangent (springs + load + multiplier geometric stiffness) vs central differences of the
    stationarity residual along pin.integrate, at a non-equilibrium point with arbitrary multipliers.
    Tolerance 1e-6 relative to the largest entry (differences with step 1e-7 are good to ~1e-8)."""
    mm = build_model(machine, POSE, springs_per_segment=2)
    pb, _ = statics.EquilibriumSolver(mm)._problem(mm.pose_values(POSE), WRENCH, np.zeros(4))
    rng = np.random.default_rng(4)
    q = pin.integrate(mm.model, mm.q0, 1e-3 * rng.normal(size=mm.model.nv))
    lam = rng.normal(size=(4, 6)) * np.array([300, 300, 300, 20, 20, 20])
    data = mm.model.createData()

    d0 = q[pb.legq] - mm.q0[pb.legq]

    def residual(qq, dv):  # spring offsets from the exact step (q ~ 1 m would cost k * 1e-16 m of noise)
        st = statics._evaluate(pb, qq, data, d0 + dv[pb.legv])
        r_leg, r_plate = statics._stationarity(pb, st, lam)
        return statics._dq(pb.mm, r_leg, r_plate)

    st = statics._evaluate(pb, q, data)
    h_leg, h_plate = statics._tangent(pb, st, lam)
    h = np.zeros((mm.model.nv, mm.model.nv))
    h[:6, :6] = h_plate
    for i, v in enumerate(mm.leg_v):
        h[np.ix_(v, v)] = h_leg[i]
    eps = 1e-7
    fd = np.array(
        [
            (
                residual(pin.integrate(mm.model, q, eps * d), eps * d)
                - residual(pin.integrate(mm.model, q, -eps * d), -eps * d)
            )
            / (2 * eps)
            for d in np.eye(mm.model.nv)
        ]
    ).T
    geo = h  # the whole tangent: springs + geometric stiffness
    assert np.abs(fd - geo).max() < 1e-6 * np.abs(geo).max()
    # the geometric part alone (without springs) is also matched to 1e-5 of its own size
    springs = np.zeros(mm.model.nv)
    for s in mm.springs:
        springs[s.idx_v] = s.law.k
    assert (
        np.abs((fd - np.diag(springs)) - (geo - np.diag(springs))).max() < 1e-5 * np.abs(geo - np.diag(springs)).max()
    )


def test_constraint_jacobian_equals_pinocchios_frame_anchor_jacobian(machine):
    """Our world-aligned closure Jacobian (motion of the leg end relative to the plate anchor) equals minus
    Pinocchio's FrameAnchor Jacobian (c2 relative to c1, in c1's frame) rotated to world axes, 1e-9."""
    mm = build_model(machine, POSE, springs_per_segment=2)
    eq = solve_equilibrium(mm, POSE, WRENCH)
    pb, _ = statics.EquilibriumSolver(mm)._problem(mm.pose_values(POSE), WRENCH, np.zeros(4))
    data = mm.model.createData()
    st = statics._evaluate(pb, eq.q, data)
    cds = mm.constraint_datas()
    pin.computeJointJacobians(mm.model, data, eq.q)
    for cm, cd in zip(mm.constraint_models, cds):
        cm.calc(mm.model, data, cd)
    jp = pin.getConstraintsJacobian(mm.model, data, mm.constraint_models, cds)
    for i in range(4):
        r = data.oMi[mm.leg_joint_ids[i]["plate_end"]].rotation
        mine = np.zeros((6, mm.model.nv))
        mine[:, mm.leg_v[i]] = st.a[i]
        mine[:, :6] = st.p[i]
        rot = np.kron(np.eye(2), r)
        assert np.allclose(-rot @ jp[6 * i:6 * i + 6], mine, atol=1e-9)  # Pinocchio: d log6(c1^-1 c2), c2 rel. c1


@pytest.mark.slow
def test_plate_compliance_by_finite_differences(machine):
    """Nonlinear solves at +-1 N (each component): d(displacement)/d(load) by central differences equals
    the exact linear compliance of the condensation; what remains is O((1 N / 700 N)^2 x 3%) ~ 1e-8."""
    for k in range(6):
        dw = np.zeros(6)
        dw[k] = 1.0
        base = np.zeros(6)  # central differences about zero load: the quadratic (nonlinear) part cancels
        a = solve_equilibrium(machine, POSE, base + dw)
        b = solve_equilibrium(machine, POSE, base - dw)
        fd_t = (a.plate_displacement_m - b.plate_displacement_m) / 2
        fd_r = (a.plate_rotation_rad - b.plate_rotation_rad) / 2
        _, _, dt, dr = condensed(machine, POSE, dw)
        assert np.allclose(fd_t, dt, rtol=0, atol=1e-6 * np.abs(dt).max())
        assert np.allclose(fd_r, dr, rtol=0, atol=1e-6 * np.abs(dr).max())


@pytest.mark.slow
def test_segment_spring_error_falls_as_one_over_n_squared(machine):
    """Nonlinear axial forces with n = 1, 2, 4, 8 springs per segment against the Richardson limit
    (4 N_8 - N_4) / 3 (error model C / n^2). Measured at this corner pose (case B + 40 N m): relative errors
    1.4e-3, 3.4e-4, 8.5e-5, 2.1e-5, ratios 4.00 (achieved within 1.6e-3; 5e-3). n = 4 (the default) errs
    < 1e-4 of max |N|.
    (Pinocchio 4.1's Data grows steeply with nv: n = 16 needs ~4.5 GB, so the test stops at 8.)"""
    pose, w = (0.2765, 0.72, -0.2765), np.array([0, 700, 0, 40, 0, 0])
    n = {k: solve_equilibrium(build_model(machine, pose, springs_per_segment=k), pose, w).actuator_forces_n
         for k in (1, 2, 4, 8)}
    limit = (4 * n[8] - n[4]) / 3
    err = {k: np.abs(n[k] - limit).max() for k in (1, 2, 4)}
    scale = np.abs(limit).max()
    assert err[1] / err[2] == pytest.approx(4, rel=5e-3)
    assert err[2] / err[4] == pytest.approx(4, rel=5e-3)
    assert err[4] < 1e-4 * scale


def test_unreachable_pose_raises_named_error(machine):
    with pytest.raises(UnreachablePoseError, match="leg 3"):
        solve_equilibrium(machine, [0.0, 0.72, -0.36], WRENCH)


def test_non_convergence_reports_the_residual(machine):
    with pytest.raises(ConvergenceError, match=r"residual \d\.\d+e[-+]\d+ > tolerance") as exc:
        solve_equilibrium(machine, POSE, WRENCH, max_iter=1)
    assert exc.value.residual > exc.value.tolerance


def test_leg_mechanism_is_reported_as_singular(machine):
    # a cardan whose translations have no stiffness lets the leg move with the plate held: no equilibrium
    mm = build_model(
        machine, POSE, springs_per_segment=1, cardan_compliance=CardanCompliance(translation=LinearSpring(0.0))
    )
    with pytest.raises(SingularPoseError) as exc:
        solve_equilibrium(mm, POSE, WRENCH)
    assert exc.value.pose_m == pytest.approx(tuple(POSE), abs=1e-9)  # found at the first Newton step, at the pose


def test_to_dict_has_the_documented_keys(machine):
    d = solve_equilibrium(machine, POSE, WRENCH).to_dict()
    assert len(d["legs"]) == 4
    assert set(d["legs"][0]["sections"]) == {"base", "actuator", "plate"}
    assert set(d["legs"][0]["sections"]["base"]) == {"N", "V_x", "V_y", "M_x", "M_y", "T"}
    assert set(d["plate"]) == {"displacement_m", "rotation_rad"}
    for k in ("actuator_forces_n", "residuals", "pose_m", "load", "linear"):
        assert k in d
    import json
    json.dumps(d)
