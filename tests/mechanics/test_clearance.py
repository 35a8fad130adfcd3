"""Clearance, preload, load-deflection and the preload study (pressfit.clearance).

Each test names its independent reference and tolerance. Pose A = (0, 0.72, 0):
tan(alpha) = y_h / (p - r) = 0.72 / 0.36 = 2 for every leg, so sin(alpha) = 2 / sqrt(5), and
v_p = (-1, 1, -1, 1) / 2 (Table 4's centre row).
"""

import math

import numpy as np
import pytest
from click.testing import CliRunner

from pressfit import kinematics
from pressfit.cli import main
from pressfit.description.cases import load_case
from pressfit.mechanics import clearance as C
from pressfit.mechanics import clearance_law as L
from pressfit.mechanics import statics
from pressfit.mechanics.model import build_model
from pressfit.mechanics.preload import PreloadError, rest_length_offsets
from pressfit.output import maps
from pressfit.studies import preload_study

POSE_A = np.array([0.0, 0.72, 0.0])
OFF = np.array([0.2, 0.6, -0.2])
SIN_A = 2 / math.sqrt(5)
UP = np.array([0.0, 1.0, 0.0])
G = 20e-6


def k_axial(machine, pose=POSE_A):
    return 1.0 / machine.axial_compliance_m_per_n(kinematics.inverse_kinematics(machine, pose).lengths_m)


@pytest.mark.parametrize("w", [1e-7, 1e-9])
def test_law_energy_force_tangent_consistent(w):
    """Reference: central finite differences of the law's own energy and force (calculus); rel. 1e-6."""
    law = L.DeadZone(gap=G, stiffness=1e9, width=w)
    h = w / 1000  # truncation h^2 f''' / 6 ~ 1e-7 k w; energy round-off ~ 1e-16 k g^2 / h
    for x in [-3e-5, -G - w, -G, -1e-5, 0.0, 7e-6, G - 2 * w, G, G + w, 2.5e-5]:
        fd_f = (law.energy(x + h) - law.energy(x - h)) / (2 * h)
        fd_t = (law.force(x + h) - law.force(x - h)) / (2 * h)
        assert law.force(x) == pytest.approx(fd_f, rel=1e-6, abs=1e-6 * law.stiffness * w)
        assert law.tangent(x) == pytest.approx(fd_t, rel=1e-6, abs=1e-6 * law.stiffness)
    # the sharp limit (reference: the dead-zone definition): 0 inside, k (|x| - g) sign(x) outside
    assert abs(law.force(0.5 * G)) <= law.stiffness * w * w / (2 * 0.5 * G)  # inside: k w^2 / (4 |u|) per side
    assert law.force(G + 1e-6) == pytest.approx(law.stiffness * 1e-6, rel=1e-3 if w < 1e-8 else 1e-1)
    linear = L.DeadZone(gap=0.0, stiffness=1e9, width=w)
    assert linear.force(3e-6) == pytest.approx(1e9 * 3e-6, rel=1e-12)  # g = 0: linear
    f = np.array([-300.0, -0.1, 0.0, 0.1, 300.0])
    assert np.allclose(law.force(L.invert_law(f, G, 1e9, w)), f, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("method", ["small", "nonlinear"])
def test_lost_motion_at_pose_A(machine, method):
    """Reference: each leg's axial play from the centred state is 2g (+-g at each of its two cardans), and
    the plate must move 2g / sin(alpha) upward to take it up; at 10 N the closed-form elastic part
    10 N / (4 k sin^2(alpha)) (k: axial spring and two contact springs in series) adds 1.9e-3 of it.
    Tolerance 5e-5: the smoothing bias (k_c w / 2 per joint) and, nonlinear, the geometry (achieved 7e-6
    small, 1.3e-5 nonlinear)."""
    cl = C.Clearance.uniform(machine, G)
    ld = C.load_deflection(machine, POSE_A, UP, [0.0, 10.0, 20.0], cl, method=method, unload=False)
    expect = 2 * G / SIN_A
    k = 1 / (1 / k_axial(machine)[0] + 2 / cl.contact_stiffness_n_per_m)
    assert ld.deflection_m[1] == pytest.approx(expect + 10.0 / (4 * k * SIN_A**2), rel=5e-5)
    assert ld.lost_motion_m == pytest.approx(expect, rel=5e-5)
    assert np.max(ld.loading.residual) < 1e-9


def test_preload_restores_no_clearance_stiffness(machine):
    """References: (a) closed form at pose A, K = 4 k sin^2(alpha) with the leg k = axial spring in series
    with the two contact springs, k = 1 / (1 / k_a + 2 / k_c) (achieved 2e-7 and 9e-7; 3e-6); (b) with
    stiff contacts (k_c = 1e12 N/m) the same closed form, which tends to the rigid-cardan value
    4 k_a sin^2(alpha) (1e-4) that the Pinocchio solver without clearance gives (3e-6); here the smoothing's
    edge force k_c w / 2 = 500 N is no longer small, so 1e-3 (achieved 2.2e-4)."""
    ka = k_axial(machine)[0]
    loads = np.linspace(0.0, 700.0, 51)
    cl = C.Clearance.uniform(machine, G)
    ld = C.load_deflection(machine, POSE_A, UP, loads, cl, preload=600.0, unload=False)
    k_series = 1 / (1 / ka + 2 / cl.contact_stiffness_n_per_m)
    assert ld.small_load_stiffness_n_per_m == pytest.approx(4 * k_series * SIN_A**2, rel=3e-6)
    assert ld.press_stiffness_n_per_m == pytest.approx(4 * k_series * SIN_A**2, rel=3e-6)
    no_pre = C.load_deflection(machine, POSE_A, UP, loads, cl, unload=False)
    assert no_pre.small_load_stiffness_n_per_m < 0.01 * ld.small_load_stiffness_n_per_m  # the dead zone
    stiff = C.Clearance.uniform(machine, G, contact_stiffness_n_per_m=1e12)
    ld = C.load_deflection(machine, POSE_A, UP, loads, stiff, preload=600.0, unload=False)
    rigid = statics.solve_equilibrium(machine, POSE_A, [0, 14.0, 0, 0, 0, 0])
    stiff_series = 4 / (1 / ka + 2 / 1e12) * SIN_A**2
    assert ld.small_load_stiffness_n_per_m == pytest.approx(stiff_series, rel=1e-3)  # achieved 2.2e-4 (below)
    assert 14.0 / rigid.plate_displacement_m[1] == pytest.approx(4 * ka * SIN_A**2, rel=3e-6)
    assert stiff_series == pytest.approx(4 * ka * SIN_A**2, rel=1e-4)


def test_critical_preload_pose_A(machine):
    """Reference (closed form): each leg gets 700 / (4 sin alpha) of tension, legs 1 and 3 start at -a4/2,
    so they stay closed while a4 > 700 / (2 sin alpha) = 391.31 N. Tolerance 0.5%: bisection bracket
    1e-4 x 700 N plus the smoothing bias k_c w / |v_i| = 1 N (the contact-edge force k_c w / 2 per joint)."""
    expect = 700.0 / (2 * SIN_A)
    assert expect == pytest.approx(391.31, abs=0.01)
    cp = C.critical_preload(machine, POSE_A, UP, 700.0, C.Clearance.uniform(machine, G))
    assert cp.preload == pytest.approx(expect, rel=5e-3)
    assert cp.tolerance <= 0.07 and cp.lower < cp.preload
    below = C.load_deflection(machine, POSE_A, UP, np.linspace(0, 700, 51), preload=0.97 * expect, unload=False)
    op = below.opening_loads_n  # legs 1, 3 (index 0, 2) open near 2 a4 sin(alpha), legs 2, 4 stay closed
    assert np.all(np.isnan(op[[1, 3]]))
    assert op[0, 0] == pytest.approx(2 * 0.97 * expect * SIN_A, rel=5e-3)


def test_preload_alone_is_along_vp_without_bending(machine):
    """Reference: v_p spans the null space of A (paper eq. 9-10), so a preload with no load is
    self-equilibrated: actuator forces a4 v_p (rel. 1e-6, the gap shifts move the legs by ~1e-5 rad),
    and no bending or torsion (|M| < 1e-6 N m) in the geometrically nonlinear Pinocchio model."""
    cl = C.Clearance.uniform(machine, G)
    a4 = 500.0
    vp = kinematics.preload_vector(machine, OFF)
    mm = build_model(machine, OFF, cardan_compliance=cl.cardan_compliance())
    offsets = rest_length_offsets(machine, OFF, a4, "force", cl)
    eq = statics.solve_equilibrium(mm, OFF, np.zeros(6), preload_offsets_m=offsets)
    assert np.allclose(eq.actuator_forces_n, a4 * vp, rtol=1e-6, atol=1e-6 * a4)
    for leg in eq.legs:
        for s in leg.sections.values():
            assert max(abs(s.M_x), abs(s.M_y), abs(s.T)) < 1e-6
            assert math.hypot(s.V_x, s.V_y) < 1e-6 * a4
    assert np.linalg.norm(eq.plate_displacement_m) < 1e-9
    small = C.load_deflection(machine, OFF, UP, [0.0, 1.0, 2.0], cl, preload=a4, unload=False)
    assert np.allclose(small.loading.axial_forces_n[0], a4 * vp, rtol=1e-10, atol=1e-9)


@pytest.mark.slow
def test_results_converge_as_smoothing_shrinks(machine):
    """Reference: the sharp dead zone (w -> 0): the critical preload tends to 391.31 N and the lost motion
    to 2g / sin(alpha); the error falls with w (about linearly, the edge force being k_c w / 2)."""
    expect_cp, expect_lm = 700.0 / (2 * SIN_A), 2 * G / SIN_A
    err_cp, err_lm = [], []
    for w in (1e-7, 1e-8, 1e-9):
        cl = C.Clearance.uniform(machine, G, smoothing_m=w)
        err_cp.append(abs(C.critical_preload(machine, POSE_A, UP, 700.0, cl, tol=1e-3).preload - expect_cp))
        ld = C.load_deflection(machine, POSE_A, UP, [0.0, 10.0, 20.0], cl, unload=False)
        err_lm.append(abs(ld.lost_motion_m - expect_lm))
    assert err_cp[0] > 5 * err_cp[1] > 25 * err_cp[2]
    assert err_cp[2] < 1.5  # N, the 1 N smoothing bias at w = 1e-9 m
    assert err_lm[2] <= err_lm[0] and err_lm[2] < 1e-3 * expect_lm


@pytest.mark.parametrize("pose", [POSE_A, OFF])
def test_unloading_retraces_loading(machine, pose):
    """Reference: with every joint closed the structure is elastic (energy-conserving), so the unloading
    branch equals the loading one (abs. 1e-10 m); the geometrically nonlinear solver, continuation."""
    loads = np.linspace(0.0, 700.0, 8)
    a4 = 1500.0 if pose is OFF else 600.0
    ld = C.load_deflection(machine, pose, UP, loads, preload=a4, method="nonlinear")
    assert np.all(ld.closed("loading")) and np.all(ld.closed("unloading"))
    assert np.allclose(ld.loading.displacement_m, ld.unloading.displacement_m, atol=1e-10)
    assert np.allclose(ld.loading.rotation_rad, ld.unloading.rotation_rad, atol=1e-10)


def test_small_and_nonlinear_agree_off_centre(machine):
    """Reference: the geometrically nonlinear Pinocchio model; the small-displacement solver must agree to
    the geometric nonlinearity at 700 N (achieved 8.5e-4 in deflection, 1.5 N in the leg forces; asserted
    3e-3 and 4 N) and exactly in the contact pattern."""
    loads = np.linspace(0.0, 700.0, 11)
    kw = dict(preload=400.0, unload=False)
    a = C.load_deflection(machine, OFF, UP, loads, **kw)
    b = C.load_deflection(machine, OFF, UP, loads, method="nonlinear", **kw)
    assert np.allclose(a.deflection_m, b.deflection_m, rtol=3e-3, atol=1e-9)
    assert np.abs(a.loading.axial_forces_n - b.loading.axial_forces_n).max() < 4.0
    assert np.array_equal(a.closed(), b.closed())


def test_clearance_variants_and_errors(machine):
    """Per-joint and seeded random clearances (reproducible, within bounds); bad inputs raise."""
    r1, r2 = C.Clearance.random(machine, 1e-5, 3e-5, seed=3), C.Clearance.random(machine, 1e-5, 3e-5, seed=3)
    assert np.array_equal(r1.gaps_m, r2.gaps_m) and np.all((r1.gaps_m >= 1e-5) & (r1.gaps_m <= 3e-5))
    pj = C.Clearance.per_joint(machine, [1e-5, 2e-5, 1e-5, 2e-5, 1e-5, 2e-5, 1e-5, 2e-5])
    ld = C.load_deflection(machine, POSE_A, UP, [0.0, 10.0, 20.0], pj, unload=False)
    assert ld.lost_motion_m == pytest.approx(3e-5 / SIN_A, rel=5e-5)  # play 1e-5 + 2e-5 in every leg (as above)
    with pytest.raises(C.ClearanceError):
        C.Clearance.uniform(machine, -1e-6)
    with pytest.raises(C.ClearanceError):
        C.load_deflection(machine, POSE_A, UP, [0.0, 5.0, 1.0])
    with pytest.raises(PreloadError):
        C.load_deflection(machine, POSE_A, UP, [0.0, 1.0, 2.0], preload_mode="torque")
    cp = C.critical_preload(machine, POSE_A, UP, 700.0, preload_mode="length")
    assert cp.preload > 0  # a4 in m in length mode


@pytest.mark.slow
def test_study_case_and_cli(machine, tmp_path):
    """The one-command answer: the case-file form and the option form write CSV, JSON and two PNGs,
    refuse to overwrite, and report the critical preload of the closed form at pose A (0.5%)."""
    case = load_case("cases/studies/preload_pose_A.toml")
    kw = preload_study.study_from_case(case)
    kw["preloads"], kw["clearances_m"], kw["steps"] = [0.0, 400.0], [G], 50
    study = preload_study.preload_study(**kw, progress=False)
    assert study.critical_preload[0] == pytest.approx(700 / (2 * SIN_A), rel=5e-3)
    # secant at 70 N: the play costs a factor 1 + (2 g / sin(alpha)) K / 70 N = 77 (test_preload_study.py)
    assert study.small_load_secant_stiffness_n_per_m[0, 1] > 50 * study.small_load_secant_stiffness_n_per_m[0, 0]
    paths = maps.write_preload_study(study, tmp_path / "a")
    assert sorted(p.name for p in paths) == ["load_deflection.png", "preload_stiffness.png",
                                             "preload_study.csv", "preload_study.json"]
    runner = CliRunner()
    args = ["study", "preload", "--pose", "0.2", "0.6", "-0.2", "--clearance", "1e-5,2e-5", "--preload", "0,1000",
            "--steps", "5", "--out", str(tmp_path / "b"), "--no-progress"]
    res = runner.invoke(main, args)
    assert res.exit_code == 0, res.output
    assert "critical preload" in res.output
    assert runner.invoke(main, args).exit_code == 2  # exists: no silent overwrite
    assert runner.invoke(main, args + ["--overwrite", "--json"]).exit_code == 0
    bad = runner.invoke(main, ["study", "preload", "--pose", "0", "0.72", "0", "--preload", "a,b"])
    assert bad.exit_code == 2


def test_the_dead_zone_far_from_its_edges_warns_nothing_at_a_tiny_smoothing():
    """With w = 1e-15 m the branch np.where drops divides by an underflowed r - u (0) far from an edge: no
    RuntimeWarning reaches the user, and the force and tangent are the sharp law's there (k (x - g), k)."""
    import warnings

    from pressfit.mechanics.clearance_law import DeadZone

    law = DeadZone(gap=2e-5, stiffness=5e8, width=1e-15)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert float(law.force(1e-3)) == pytest.approx(5e8 * (1e-3 - 2e-5), rel=1e-12)
        assert float(law.tangent(1e-3)) == pytest.approx(5e8, rel=1e-12)
