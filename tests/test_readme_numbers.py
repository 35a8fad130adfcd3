"""Every number the README states in its statics sections is computed here and compared at the printed
precision (scikit-fem style: the README is a test). Each test first asserts that the README still contains
the exact fragment, so the text and the code cannot drift apart. Tolerance: half a unit of the last printed
digit, unless the README states a bound ("within", "about"). The insertion, MuJoCo, modes and CAD-fit
numbers are asserted in their own test modules, where they are computed anyway.

A snapshot of a printed number only protects against drift. Where the number has an independent source, it is
asserted against that too, and the comment says which: a closed form derived here from Table 3's geometry and
docs/conventions.md's section properties ("closed form"), or a second formulation (the Pinocchio VJM model
against the condensed one, "second formulation").
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from pressfit import kinematics
from pressfit.description.cases import load_case
from pressfit.geometry import interference
from pressfit.kinematics import workspace
from pressfit.mechanics import buckling, condensed
from pressfit.mechanics.clearance import Clearance, critical_preload, load_deflection
from pressfit.mechanics.compliance import vjm_plate_compliance
from pressfit.mechanics.statics import solve_equilibrium
from pressfit.studies import preload_study
from pressfit.studies.paper_tables import PAPER_CASES, paper_tables

README = (Path(__file__).resolve().parents[1] / "README.md").read_text()
POSE_A, OFF = [0.0, 0.72, 0.0], [0.2, 0.6, -0.2]
SIN_A = 2 / math.sqrt(5)  # pose A: tan(alpha) = 0.72 / (p - r) = 2
P, R = 0.442, 0.082  # Table 3
E = 210e9  # docs/conventions.md: steel; tube 60 x 5 mm, 0.45 m; rod 30 mm; actuator 5e7 N/m
L_CYL, A_CYL, A_STEM, K_ACT = 0.45, math.pi / 4 * (0.060**2 - 0.050**2), math.pi / 4 * 0.030**2, 5e7
I_CYL, I_STEM = math.pi / 64 * (0.060**4 - 0.050**4), math.pi / 64 * 0.030**4
L_A = math.hypot(0.72, P - R)  # every leg at pose A
K_A = 1 / (1 / K_ACT + L_CYL / (E * A_CYL) + (L_A - L_CYL) / (E * A_STEM))  # actuator, tube, rod in series


def says(fragment: str) -> None:
    assert fragment in " ".join(README.split()), f"README no longer says {fragment!r}"


def printed(value: float, text: str) -> None:
    """value rounds to ``text`` (its last printed digit), e.g. printed(0.06542, "0.065")."""
    mantissa = text.split("e")[0]
    digits = len(mantissa.split(".")[1]) if "." in mantissa else 0
    unit = 10.0 ** (-digits) * (10.0 ** int(text.split("e")[1]) if "e" in text else 1.0)
    assert abs(value - float(text)) <= 0.5 * unit * (1 + 1e-9), f"{value} does not print as {text}"


@pytest.fixture(scope="module")
def tables():
    out: dict[tuple[str, str], dict[int, object]] = {}
    for e in paper_tables():
        out.setdefault((e.case.removeprefix("paper-"), e.quantity), {})[e.cad_leg] = e
    return out


def test_tables_case_a(tables):
    says("every leg carries 700 / (4 sin alpha) = 195.66 N in tension (tan alpha = 2); the paper prints "
         "195.6-195.8 N: within 0.1%")
    printed(700 / (4 * SIN_A), "195.66")
    for e in tables["A", "F_z"].values():
        printed(-e.linear, "195.66")  # the paper's axis: compression-positive
        assert abs(e.relative_error) < 1e-3


def test_tables_case_b(tables):
    says("axial forces within 1.5% of the paper (-0.4%, -0.9%, +1.2%, +0.2%)")
    errors = [tables["B", "F_z"][cad].relative_error for cad in (1, 2, 3, 4)]
    assert [f"{100 * e:+.1f}%" for e in errors] == ["-0.4%", "-0.9%", "+1.2%", "+0.2%"]
    says("CAD legs 1 and 4 (kinematic 1 and 2, the two nearly vertical legs) within 4.5%; CAD legs 2 and 3 "
         "(kinematic 3 and 4) come out 27% lower than printed")
    for q in ("M_z", "M_bend"):
        ratios = {cad: abs(e.linear) / abs(e.paper) - 1 for cad, e in tables["B", q].items()}
        assert max(abs(ratios[1]), abs(ratios[4])) < 0.045
        printed(-100 * ratios[2], "27")
        printed(-100 * ratios[3], "27")


def test_tables_case_c(tables, machine):
    says("(leg 3 is 1.018 m long)")
    printed(kinematics.inverse_kinematics(machine, [0.0, 0.72, -0.36]).lengths_m[2], "1.018")
    printed(math.hypot(0.72, -0.36 + R - P), "1.018")  # closed form: |h + d_3 - B_3|, d_3 = (0, 0, r), B_3 = (0, 0, p)
    says("Torsion 29% and bending 32% lower than printed")
    for q, text in (("M_z", "29"), ("M_bend", "32")):
        for cad in (3, 4):
            e = tables["C", q][cad]
            printed(100 * (1 - abs(e.linear) / abs(e.paper)), text)
    says("vertical equilibrium closes to 0.12%")
    case = load_case(PAPER_CASES / "C.toml")
    h = case.poses.array()[0]
    paper, ours = np.zeros(4), np.zeros(4)
    for e in tables["C", "F_z"].values():
        paper[e.kinematic_leg - 1] = case.reference.axial_sign * e.paper
        ours[e.kinematic_leg - 1] = case.reference.axial_sign * e.linear
    paper[0] *= -1
    a = kinematics.static_matrix(case.machine(), h)
    printed(100 * abs(a[1] @ paper / 700.0 - 1), "0.12")
    says("the paper has (471, 300, -368, 300) N with leg 1 flipped, ours is (589, 136, -157, 136) N")
    assert np.round(paper).tolist() == [471, 300, -368, 300] and np.round(ours).tolist() == [589, 136, -157, 136]
    says(
        "The difference is mostly (99.4% of its squared norm) a self-stress a4 = 333 N along v_p, and the rest "
        "leaves 15 N unbalanced along z"
    )
    d, vp = paper - ours, kinematics.preload_vector(case.machine(), h)
    printed(100 * (d @ vp) ** 2 / (d @ d), "99.4")
    printed(d @ vp, "333")
    printed((a @ paper)[2], "15")


def test_section_4_1(machine):
    says("the full 500 x 500 mm square is reachable for y_h in [0.48775, 0.75193] m; n varies by 23.4%")
    r = workspace.square_height_range(machine)
    printed(r.y_min_m, "0.48775")
    printed(r.y_max_m, "0.75193")
    s = workspace.square_statistics(machine, 0.6)
    printed(100 * (s.dexterity_max - s.dexterity_min) / s.dexterity_max, "23.4")
    says("(that holds within +-0.19 m); F_y < 1 holds (max 0.665 at y_h = 0.6 m)")
    printed(workspace.dexterity_half_width(machine, 0.6, 0.15), "0.19")
    printed(s.force_index_max[1], "0.665")
    says("by 45 degrees makes F_y 27% worse and the height range smaller")
    s45 = workspace.square_statistics(machine, 0.6, 45.0)
    printed(100 * (s45.force_index_max[1] / s.force_index_max[1] - 1), "27")
    r45 = workspace.square_height_range(machine, 45.0)
    assert r45.y_max_m - r45.y_min_m < r.y_max_m - r.y_min_m


def test_stiffness(machine):
    says("at pose A (0, 0.72, 0) the plate is 1.29e8 N/m stiff vertically but only 2.3e5 N/m laterally "
         "(ratio 0.0018)")
    rep = condensed.stiffness_report(machine, POSE_A)
    printed(rep["vertical_stiffness_n_per_m"], "1.29e8")
    # closed form (rigid cardans, four equal legs): 4 k_a sin^2(alpha)
    assert rep["vertical_stiffness_n_per_m"] == pytest.approx(4 * K_A * SIN_A**2, rel=1e-9)
    printed(rep["lateral_stiffness_n_per_m"], "2.3e5")
    # second formulation: the Pinocchio VJM compliance (agrees with the condensed one to ~1e-11)
    c_pin = vjm_plate_compliance(machine, POSE_A)
    assert rep["lateral_stiffness_n_per_m"] == pytest.approx(1 / np.linalg.eigvalsh(c_pin[::2, ::2][:2, :2])[-1],
                                                             rel=1e-8)
    printed(rep["lateral_to_vertical"], "0.0018")
    says("Off-centre the vertical stiffness itself falls about 170 times (7.7e5 N/m at the corners of the square at "
         "y_h = 0.72 m)")
    corner = condensed.stiffness_report(machine, [0.25, 0.72, 0.25])
    printed(corner["vertical_stiffness_n_per_m"], "7.7e5")
    assert corner["vertical_stiffness_n_per_m"] == pytest.approx(  # second formulation
        1 / vjm_plate_compliance(machine, [0.25, 0.72, 0.25])[1, 1], rel=1e-8)
    assert 160 < rep["vertical_stiffness_n_per_m"] / corner["vertical_stiffness_n_per_m"] < 180  # "about 170"
    says("11 mrad and 1.8 mm of lateral drift under 700 N there")
    printed(corner["press_tilt_rad"] * 1e3, "11")
    printed(math.hypot(corner["press_displacement_m"][0], corner["press_displacement_m"][2]) * 1e3, "1.8")
    pin_eq = solve_equilibrium(machine, [0.25, 0.72, 0.25], [0, 700, 0, 0, 0, 0], linear=True)  # second formulation
    assert np.linalg.norm(pin_eq.plate_rotation_rad) == pytest.approx(corner["press_tilt_rad"], rel=1e-8)
    assert np.hypot(*pin_eq.plate_displacement_m[::2]) == pytest.approx(
        math.hypot(corner["press_displacement_m"][0], corner["press_displacement_m"][2]), rel=1e-8)


def test_concurrency_point():
    """Closed form: every leg line, from B_i to h + d_i with d_i = (r / p) B_i, passes through P* = h p / (p - r)
    (h + d_i - B_i = h - (1 - r/p) B_i, so B_i + p / (p - r) (h + d_i - B_i) = h p / (p - r))."""
    says("about the point P* = h p / (p - r) where all leg lines meet")
    base = P * np.array([[0, 0, -1], [1, 0, 0], [0, 0, 1], [-1, 0, 0]], float)
    for h in (np.array(POSE_A), np.array(OFF), np.array([-0.25, 0.5, 0.13])):
        star = h * P / (P - R)
        for b in base:
            leg, to_star = h + b * R / P - b, star - b
            assert np.linalg.norm(np.cross(leg, to_star)) < 1e-15 * np.linalg.norm(to_star)
        np.testing.assert_allclose(kinematics.concurrency_point(load_case(PAPER_CASES / "A.toml").machine(), h),
                                   star, rtol=0, atol=1e-15)


def test_clearance_and_preload(machine):
    says("at pose A with g = 20 um and no preload the first newtons move the plate 44.7 um (2g / sin(alpha)) and "
         "the secant stiffness at 70 N")
    study = preload_study.preload_study(machine, POSE_A, [20e-6], [0.0, 400.0], 700.0, 50, progress=False)
    printed(study.lost_motion_m[0, 0] * 1e6, "44.7")
    printed(2 * 20 / SIN_A, "44.7")
    says("is 1.54e6 N/m")
    printed(study.small_load_secant_stiffness_n_per_m[0, 0], "1.54e6")
    # closed form: the dead zone 2 g / sin(alpha) in series with the no-clearance stiffness K (below):
    # F / (zone + F / K); the smoothed dead zone's edge takes up a little less play: 0.4% here, asserted to 1%
    k_contact = 4 * SIN_A**2 / (1 / K_A + 2 / machine.joints.cardan_contact_stiffness_n_per_m)
    secant = lambda f: f / (2 * 20e-6 / SIN_A + f / k_contact)
    assert study.small_load_secant_stiffness_n_per_m[0, 0] == pytest.approx(secant(70.0), rel=0.01)
    says("a preload a4 >= 392 N along v_p (closed form 700 / (2 sin(alpha)) = 391.3 N; the smoothing adds 1 N)")
    printed(700 / (2 * SIN_A), "391.3")
    crit = float(study.critical_preload[0])
    printed(crit, "392")
    printed(crit - 700 / (2 * SIN_A), "1")
    says("restores 1.19e8 N/m (the secant at 700 N without preload is 1.4e7 N/m)")
    printed(study.press_secant_stiffness_n_per_m[0, 1], "1.19e8")
    printed(study.press_secant_stiffness_n_per_m[0, 0], "1.4e7")
    assert study.press_secant_stiffness_n_per_m[0, 0] == pytest.approx(secant(700.0), rel=0.01)  # closed form
    says("reference, 1.19e8 N/m): 8% apart")
    printed(study.no_clearance_contact_stiffness_n_per_m, "1.19e8")
    # closed form: each leg's axial spring in series with its two cardans' contact springs, 4 k sin^2(alpha)
    assert study.no_clearance_contact_stiffness_n_per_m == pytest.approx(k_contact, rel=1e-6)
    assert study.press_secant_stiffness_n_per_m[0, 1] == pytest.approx(k_contact, rel=0.01)  # preload closes the play
    assert study.rigid_cardan_stiffness_n_per_m == pytest.approx(4 * K_A * SIN_A**2, rel=1e-9)  # closed form
    printed(100 * (study.rigid_cardan_stiffness_n_per_m / study.no_clearance_contact_stiffness_n_per_m - 1), "8")
    says("Off-centre at (0.2, 0.6, -0.2) the critical preload is 931 N")
    printed(critical_preload(machine, OFF, (0, 1, 0), 700.0).preload, "931")


def test_clearance_geometries(machine):
    says("at (0.2, 0.6, -0.2) the box adds 26% of lost motion and 3.1% of deflection at 700 N")
    loads = np.linspace(0.0, 700.0, 51)
    curves = {g: load_deflection(machine, OFF, (0, 1, 0), loads, Clearance.uniform(machine, 20e-6, geometry=g),
                                 unload=False) for g in ("axial", "box")}
    printed(100 * (curves["box"].lost_motion_m / curves["axial"].lost_motion_m - 1), "26")
    printed(100 * (curves["box"].deflection_m[-1] / curves["axial"].deflection_m[-1] - 1), "3.1")


@pytest.mark.slow
def test_interference(machine):
    says("the tightest pair is a leg's cylinder and the plate, 10.3 mm at the lowest height (a capsule's rounded "
         "end; 39 mm with flat-ended cylinders), neighbouring stems 84 mm, legs and base 253 mm")
    minima = interference.workspace_sweep(interference.build_interference(machine)).kind_minima()
    printed(minima["leg-plate"]["distance_m"] * 1e3, "10.3")
    assert "cylinder" in minima["leg-plate"]["pair"]
    printed(minima["leg-leg"]["distance_m"] * 1e3, "84")
    printed(minima["leg-base"]["distance_m"] * 1e3, "253")
    flat = machine.with_overrides({"collision": {"leg_shape": "cylinder"}})
    printed(interference.workspace_sweep(interference.build_interference(flat)).kind_minima()["leg-plate"]["distance_m"]
            * 1e3, "39")


def test_stability_and_buckling(machine):
    says("At pose A under +-700 N it is stable (smallest eigenvalue 5.6e3 N m)")
    for f in (700.0, -700.0):
        st = solve_equilibrium(machine, POSE_A, [0, f, 0, 0, 0, 0]).stability
        assert st.stable and st.kkt_negative_eigenvalues == st.constraints == 24
        if f > 0:
            printed(st.min_eigenvalue_nm, "5.6e3")
    says("under a 700 N downward press it is 143 at pose A, where each leg's pinned-pinned Euler factor is 1197, "
         "and 52.5 at (0.2765, 0.72, -0.2765) (legs: 561 and more)")
    a = buckling.machine_buckling(machine, POSE_A, [0, -700, 0, 0, 0, 0])
    printed(a.load_factor, "143")
    for f in a.leg_euler_factors:
        printed(f, "1197")
    # closed form: the pinned-pinned stepped column (tube EI_1 over L_CYL, rod EI_2 over the rest) buckles at the
    # first root of k_2 sin(k_1 a) cos(k_2 b) + k_1 sin(k_2 b) cos(k_1 a) = 0, k_j = sqrt(P / EI_j), solved here;
    # each leg carries 700 / (4 sin(alpha)) of compression
    ei_1, ei_2, b_len = E * I_CYL, E * I_STEM, L_A - L_CYL
    def g(p):
        k1, k2 = math.sqrt(p / ei_1), math.sqrt(p / ei_2)
        return k2 * math.sin(k1 * L_CYL) * math.cos(k2 * b_len) + k1 * math.sin(k2 * b_len) * math.cos(k1 * L_CYL)

    lo, hi = math.pi**2 * ei_2 / L_A**2, math.pi**2 * ei_1 / L_A**2  # the rod's and the tube's Euler loads
    p_cr = brentq(g, lo, hi, xtol=1e-9, rtol=1e-14)
    for f in a.leg_euler_factors:
        assert f == pytest.approx(p_cr / (700 / (4 * SIN_A)), rel=1e-6)  # the package interpolates a table: 1e-6
    b = buckling.machine_buckling(machine, [0.2765, 0.72, -0.2765], [0, -700, 0, 0, 0, 0])
    printed(b.load_factor, "52.5")
    printed(min(b.leg_euler_factors), "561")
    says("so per-leg Euler overstates the safety about 8 times")
    assert 7.5 < min(a.leg_euler_factors) / a.load_factor < 8.5
