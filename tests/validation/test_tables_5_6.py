"""Paper Tables 5 and 6 (Fiorineschi, Pugi, Rotini, section 4.3): leg loads for cases A, B and C.

The paper's CAD model numbers legs differently (CAD 1, 2, 3, 4 = kinematic 1, 3, 4, 2) and prints the
axial force compression-positive; ``pressfit.tables`` applies that map explicitly (never abs()).
The paper's model is rigid with locked actuators; it is compared with pressfit's linear solution.
Tolerances: case A 0.1% (the paper prints 4 digits; 195.6-195.8 N spread is its own asymmetry of
0.1%), case B axial forces 1.5% (docs/conventions.md: the pose (0.2765, 0.72, -0.2765) is fitted to the axial
forces, not given). B and C moments and the C axial split are reported, not asserted (see README).
"""

import math

import numpy as np
import pytest

from pressfit import kinematics
from pressfit.description.cases import load_case
from pressfit.studies.paper_tables import PAPER_CASES, compare_case


@pytest.fixture(scope="module")
def entries():
    return {name: compare_case(load_case(PAPER_CASES / f"{name}.toml")) for name in "ABC"}


def _by(entries, quantity):
    return {e.kinematic_leg: e for e in entries if e.quantity == quantity}


def test_table5_case_A_axial_forces_within_0p1_percent(entries):
    # closed form: every leg carries 700 / (4 sin(alpha)) in tension, tan(alpha) = 2 at y_h = 0.72
    closed = 700.0 / (4 * math.sin(math.atan(2.0)))
    assert closed == pytest.approx(195.66, abs=5e-3)
    for e in _by(entries["A"], "F_z").values():
        assert e.linear == pytest.approx(-closed, rel=1e-9)  # paper axes: compression positive
        assert e.linear == pytest.approx(e.paper, rel=1e-3)


def test_table6_case_A_moments_vanish(entries):
    # symmetry of pose A: no couples (paper: |M| < 2e-4 N m, numerical noise of its solver)
    for q in ("M_x", "M_y", "M_z", "F_x", "F_y"):
        for e in _by(entries["A"], q).values():
            assert abs(e.linear) < 1e-6 and abs(e.nonlinear) < 1e-6


def test_table5_case_B_axial_forces_within_1p5_percent(entries):
    for e in _by(entries["B"], "F_z").values():
        assert e.linear == pytest.approx(e.paper, rel=0.015), e


def test_table5_case_C_leg1_sign_is_inconsistent_with_vertical_equilibrium(machine):
    """The paper's case C forces (CAD order, compression-positive) cannot balance +700 N vertically;
    flipping leg 1's sign makes the vertical balance close to 0.12% (so leg 1 is misprinted)."""
    case = load_case(PAPER_CASES / "C.toml")
    ref = case.reference
    tension = np.zeros(4)
    for cad, kin in enumerate(ref.leg_order):
        tension[kin - 1] = ref.axial_sign * ref.values["F_z"][cad]
    ey = kinematics.static_matrix(case.machine(), case.poses.array()[0])[1]
    assert abs(ey @ tension - 700.0) > 0.5 * 700.0
    tension[0] *= -1
    assert ey @ tension == pytest.approx(700.0, rel=2e-3)


def test_case_C_pose_breaks_table3_leg_length(machine):
    # documented in cases/paper/C.toml: leg 3 is 1.0182 m > l_max = 1.0 m
    bad = kinematics.violations(machine, [0.0, 0.72, -0.36])
    assert [(leg, what) for leg, what, _, _ in bad] == [(3, "leg length l [m]")]
    assert bad[0][2] == pytest.approx(math.hypot(0.72, 0.36 + 0.442 - 0.082), rel=1e-12)


def test_table6_large_B_and_C_moments_are_26_to_39_percent_below_print(entries):
    """Documented disagreement (README "Tables 5 and 6"): with Table 3's geometry the large moments of
    cases B (CAD legs 2, 3) and C (CAD legs 3, 4) come out 26-39% below the printed values (docs/conventions.md,
    "Where the printed paper is wrong"; asserted as that band). Torsion keeps the paper's sign under the map."""
    for name, cad_legs in (("B", (2, 3)), ("C", (3, 4))):
        for e in entries[name]:
            if e.cad_leg in cad_legs and e.quantity in ("M_z", "M_bend"):
                assert -0.39 <= abs(e.linear) / abs(e.paper) - 1 <= -0.26, e
                assert np.sign(e.linear) == np.sign(e.paper), e


def test_case_C_paper_split_is_mostly_a_preload_along_v_p(entries, machine):
    """README "Tables 5 and 6": the printed case C forces (leg 1 flipped) leave 15 N unbalanced along z
    (paper data and Table 3 geometry only), and differ from pressfit's linear split mostly (> 90%) by a
    self-stress along v_p; its coordinate is about 333 N (printed to 4 digits: 1 N)."""
    case = load_case(PAPER_CASES / "C.toml")
    h = case.poses.array()[0]
    paper = np.zeros(4)
    ours = np.zeros(4)
    for e in entries["C"]:
        if e.quantity == "F_z":
            paper[e.kinematic_leg - 1] = case.reference.axial_sign * e.paper
            ours[e.kinematic_leg - 1] = case.reference.axial_sign * e.linear
    paper[0] *= -1
    a = kinematics.static_matrix(case.machine(), h)
    assert (a @ paper)[2] == pytest.approx(15.36, abs=0.05)
    d, vp = paper - ours, kinematics.preload_vector(case.machine(), h)
    assert d @ vp == pytest.approx(333.0, abs=1.0)
    assert np.linalg.norm(d - (d @ vp) * vp) / np.linalg.norm(d) < 0.1
