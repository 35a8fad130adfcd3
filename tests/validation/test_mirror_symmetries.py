"""Mirror symmetries of the machine (paper Table 2, section 3), property-based (hypothesis, derandomized).

The machine (Table 3 geometry, four identical legs, cardan axes a_1 = a_3 = x, a_2 = a_4 = z) is symmetric
under the mirrors R_x: x -> -x (legs 1, 3 onto themselves, 2 <-> 4; Table 2's leg-3 substitution x_h -> -x_h
composed with z_h -> -z_h is the product of both mirrors) and R_z: z -> -z (legs 1 <-> 3, 2 and 4 onto
themselves). A mirrored pose under the mirrored load must give the mirrored answer. Derivation of the
signs (R = the mirror matrix, det R = -1): a force is a vector (F' = R F), a moment a pseudovector
(M' = -R M); the plate translation maps as R d, its rotation as -R phi. The image leg's frame is built from
its own cardan axis a' (e_z' = R e_z, e_x' = a' made normal to e_z'): when the mirror reverses a (R a = -a:
legs 1, 3 under R_x; legs 2, 4 under R_z) e_x' = -R e_x and e_y' = R e_y, so (N, V_x, V_y, M_x, M_y, T) map
to (N, -V_x, V_y, M_x, -M_y, -T); when it keeps a (R a = a) e_x' = R e_x, e_y' = -R e_y, and they map to
(N, V_x, -V_y, -M_x, M_y, -T). The condensed couple C_i (moment C_i c_i, c_i' = R c_i) changes sign.
Signed comparisons throughout (never abs()).

Tolerances, relative to the largest value of each kind (measured on 40 random pose/load pairs): the
condensed solve is closed-form 3x3 algebra (achieved 6e-16; 1e-14 asserted); the linear Pinocchio solve is a
KKT factorisation whose rows are not mirror images of each other (leg 1 carries the plate in the tree)
(achieved 1.5e-14; 1e-13). The linear solve has no shear (round-off, 1e-16 of N), so the shear signs are
checked by the geometrically nonlinear solve too, where shears reach 0.5% of N (a wrong shear sign errs by
7e-3): its Newton stops at a residual of 1e-9 (achieved 2.6e-11; 1e-9).
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from pressfit import kinematics
from pressfit.mechanics import condensed
from pressfit.mechanics.statics import EquilibriumSolver

TOL = {"condensed": 1e-14, "linear": 1e-13, "nonlinear": 1e-9}
SETTINGS = settings(max_examples=12, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])
MIRRORS = {  # name -> (R, leg image (0-based), the mirror reverses the leg's cardan axis a_i)
    "x": (np.diag([-1.0, 1.0, 1.0]), [0, 3, 2, 1], [True, False, True, False]),
    "z": (np.diag([1.0, 1.0, -1.0]), [2, 1, 0, 3], [False, True, False, True]),
}
FIELDS = ("N", "V_x", "V_y", "M_x", "M_y", "T")
SIGNS = {True: np.array([1, -1, 1, 1, -1, -1]), False: np.array([1, 1, -1, -1, 1, -1])}  # (module doc)

poses = st.tuples(st.floats(-0.25, 0.25), st.floats(0.5, 0.75), st.floats(-0.25, 0.25))
wrenches = st.tuples(*[st.floats(-1000.0, 1000.0)] * 3, *[st.floats(-100.0, 100.0)] * 3)


def mirrored(name, pose, wrench):
    r = MIRRORS[name][0]
    w = np.asarray(wrench, float)
    return r @ np.asarray(pose, float), np.concatenate([r @ w[:3], -r @ w[3:]])


@pytest.fixture(scope="module")
def solver(machine):
    return EquilibriumSolver(machine)


def test_the_machine_file_has_the_symmetry_these_tests_assume(machine):
    """Base and plate points and cardan axes map onto the image legs' (up to the axis sign): Table 3."""
    for r, image, reversed_ in MIRRORS.values():
        np.testing.assert_allclose(machine.base_points_m @ r, machine.base_points_m[image], atol=1e-15)
        np.testing.assert_allclose(machine.plate_offsets_m @ r, machine.plate_offsets_m[image], atol=1e-15)
        a = machine.cardan_axes
        np.testing.assert_allclose(a @ r, np.where(np.array(reversed_)[:, None], -1, 1) * a[image], atol=1e-15)


@pytest.mark.parametrize("name", sorted(MIRRORS))
@SETTINGS
@given(pose=poses, wrench=wrenches)
def test_condensed_linear_solve_is_mirror_symmetric(machine, name, pose, wrench):
    assume(kinematics.is_reachable(machine, np.array([pose]))[0])
    r, image, reversed_ = MIRRORS[name]
    a = condensed.solve_linear(machine, np.array(pose), np.array(wrench))
    b = condensed.solve_linear(machine, *mirrored(name, pose, wrench))
    scale_n, scale_m = np.abs(a.axial_forces_n).max(), np.abs(a.leg_moments_nm).max() + 1e-300
    np.testing.assert_allclose(b.axial_forces_n[image], a.axial_forces_n, rtol=0, atol=TOL["condensed"] * scale_n)
    np.testing.assert_allclose(b.couples_nm[image], -a.couples_nm, rtol=0, atol=TOL["condensed"] * scale_m)
    for i in range(4):  # (M_x, M_y, T) with the signs of the module doc
        np.testing.assert_allclose(b.leg_moments_nm[image[i]], SIGNS[reversed_[i]][3:] * a.leg_moments_nm[i],
                                   rtol=0, atol=TOL["condensed"] * scale_m)
    d = np.abs(a.plate_displacement_m).max()
    np.testing.assert_allclose(b.plate_displacement_m, r @ a.plate_displacement_m, rtol=0, atol=TOL["condensed"] * d)
    phi = np.abs(a.plate_rotation_rad).max() + 1e-300
    np.testing.assert_allclose(b.plate_rotation_rad, -r @ a.plate_rotation_rad, rtol=0, atol=TOL["condensed"] * phi)


@pytest.mark.parametrize("how", ["linear", "nonlinear"])
@pytest.mark.parametrize("name", sorted(MIRRORS))
@settings(SETTINGS, max_examples=8)
@given(pose=poses, wrench=wrenches)
def test_pinocchio_solve_is_mirror_symmetric(machine, solver, name, how, pose, wrench):
    assume(kinematics.is_reachable(machine, np.array([pose]))[0])
    r, image, reversed_ = MIRRORS[name]
    tol = TOL[how]
    a = solver.solve(np.array(pose), np.array(wrench), linear=how == "linear")
    b = solver.solve(*mirrored(name, pose, wrench), linear=how == "linear")
    values = np.array([[[getattr(s, f) for f in FIELDS] for s in leg.sections.values()] for leg in a.legs])
    images = np.array([[[getattr(s, f) for f in FIELDS] for s in leg.sections.values()] for leg in b.legs])
    assert [list(leg.sections) for leg in a.legs] == [list(leg.sections) for leg in b.legs]
    # round-off scales with the load (N, N m per 1 m), not with a section force that vanishes by symmetry
    load = np.abs(wrench).max()
    forces, moments = max(np.abs(values[..., :3]).max(), load), max(np.abs(values[..., 3:]).max(), load)
    for i in range(4):
        expect = SIGNS[reversed_[i]] * values[i]
        np.testing.assert_allclose(images[image[i]][..., :3], expect[..., :3], rtol=0, atol=tol * forces)
        np.testing.assert_allclose(images[image[i]][..., 3:], expect[..., 3:], rtol=0, atol=tol * moments)
    d = np.abs(a.plate_displacement_m).max()
    np.testing.assert_allclose(b.plate_displacement_m, r @ a.plate_displacement_m, rtol=0, atol=tol * d)
    phi = np.abs(a.plate_rotation_rad).max() + 1e-300
    np.testing.assert_allclose(b.plate_rotation_rad, -r @ a.plate_rotation_rad, rtol=0, atol=tol * phi)
