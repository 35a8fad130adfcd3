"""The exact condensed linear statics (pressfit.condensed) against independent references.

References, each named in its test: closed forms at pose A (derived in the test; docs/conventions.md,
"Closed forms at x = z = 0"); the compliance-weighted truss solution of A N = F (Maxwell/Castigliano:
the elastic bar forces minimise sum N^2 / k_a); the machine's mirror and 90-degree symmetries; a finite-difference
Hessian of the potential energy of 4 axial springs + 4 couple springs written directly here (section properties from
docs/conventions.md's defaults, not from the package); the leg frames of pressfit.kinematics.
"""

import json
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pressfit import kinematics
from pressfit.errors import CondensedModelError, OutputExistsError, PressfitError
from pressfit.kinematics.workspace import workspace_square
from pressfit.mechanics import condensed
from pressfit.mechanics.preload import with_axial_preload
from pressfit.output import maps as map_files
from pressfit.studies import workspace_envelope

P, R = 0.442, 0.082  # Table 3
E, G = 210e9, 81e9
L_CYL, D_CYL, T_CYL, D_STEM, K_ACT = 0.45, 0.060, 0.005, 0.030, 5e7  # docs/conventions.md defaults
A_CYL = math.pi / 4 * (D_CYL**2 - (D_CYL - 2 * T_CYL) ** 2)
I_CYL = math.pi / 64 * (D_CYL**4 - (D_CYL - 2 * T_CYL) ** 4)
A_STEM, I_STEM = math.pi / 4 * D_STEM**2, math.pi / 64 * D_STEM**4
BASE = P * np.array([[0, 0, -1], [1, 0, 0], [0, 0, 1], [-1, 0, 0]], float)
OFFS = BASE * (R / P)
AXES = np.array([[1, 0, 0], [0, 0, 1], [1, 0, 0], [0, 0, 1]], float)


def k_axial(length):
    """Actuator + tube + rod in series, N/m."""
    return 1 / (1 / K_ACT + L_CYL / (E * A_CYL) + (length - L_CYL) / (E * A_STEM))


def random_poses(n, seed=0):
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-0.25, 0.25, n), rng.uniform(0.49, 0.75, n), rng.uniform(-0.25, 0.25, n)])


# --- pose A: closed forms -------------------------------------------------------------------------
@pytest.mark.parametrize("y", [0.55, 0.72])
def test_pose_a_press_load_closed_form(machine, y):
    # vertical equilibrium of 4 equal legs at x = z = 0: N_i = 700 / (4 sin alpha), zero couples; vertical
    # stiffness = sum k_a sin^2(alpha) (docs/conventions.md). rel 1e-12
    length = math.hypot(y, P - R)
    sin_a = y / length
    res = condensed.solve_linear(machine, [0, y, 0], [0, 700, 0, 0, 0, 0])
    np.testing.assert_allclose(res.axial_forces_n, 700 / (4 * sin_a), rtol=1e-12)
    np.testing.assert_allclose(res.couples_nm, 0, atol=1e-9)
    np.testing.assert_allclose(res.plate_rotation_rad, 0, atol=1e-15)
    k_vert = 4 * k_axial(length) * sin_a**2
    assert 1 / condensed.condensed_plate_compliance(machine, [0, y, 0])[1, 1] == pytest.approx(k_vert, rel=1e-12)
    assert res.plate_displacement_m[1] == pytest.approx(700 / k_vert, rel=1e-12)


def test_pose_a_fits_table_5():
    # y_h = 0.72 m gives tan(alpha) = 0.72 / (p - r) = 2 and 195.66 N per leg (Table 5 prints 195.6-195.8 N)
    assert 700 / (4 * math.sin(math.atan(2))) == pytest.approx(195.66, abs=0.005)


# --- the concurrent truss and equilibrium -----------------------------------------------------------
def test_load_through_p_star_is_the_elastic_truss(machine):
    # A force whose line passes through P* loads no couple; then N is the elastic truss answer:
    # A N = F with N minimising sum N^2 / k_a (weighted pseudo-inverse, numpy lstsq). rel 1e-9
    rng = np.random.default_rng(1)
    for h in random_poses(20, 1):
        f = rng.normal(size=3) * 500
        w = np.r_[f, np.cross(kinematics.concurrency_point(machine, h) - h, f)]
        res = condensed.solve_linear(machine, h, w)
        assert np.max(np.abs(res.couples_nm)) < 1e-9 * np.linalg.norm(f) * 1.0  # N m per N of load
        a = kinematics.static_matrix(machine, h)
        sq = np.sqrt(k_axial(kinematics.inverse_kinematics(machine, h).lengths_m))
        ref = sq * np.linalg.lstsq(a * sq, f, rcond=None)[0]
        np.testing.assert_allclose(res.axial_forces_n, ref, rtol=1e-9, atol=1e-9 * np.linalg.norm(f))


def test_vertical_load_off_axis_needs_couples(machine):
    # P* lies on the line through the origin and h: a vertical force at h misses it unless x = z = 0
    res = condensed.solve_linear(machine, [0.2, 0.6, -0.1], [0, 700, 0])
    assert np.max(np.abs(res.couples_nm)) > 1.0
    a = kinematics.static_matrix(machine, [0.2, 0.6, -0.1])
    np.testing.assert_allclose(a @ res.axial_forces_n, [0, 700, 0], atol=1e-9 * 700)  # couples carry no force


def test_equilibrium_residuals_random_wrenches(machine):
    # plate force and moment balance about the plate centre, with moment arms d_i (not P*): < 1e-9 rel
    h = random_poses(500, 2)
    w = np.random.default_rng(3).normal(size=(500, 6)) * [700, 700, 700, 60, 60, 60]
    res = condensed.solve_linear(machine, h, w)
    assert res.plate_displacement_m.shape == (500, 3) and res.leg_moments_nm.shape == (500, 4, 3)
    assert np.max(res.relative_residual()) < 1e-9


def test_solve_matches_compliance_and_stiffness(machine):
    # delta = C w and K C = I, for the centre and the concurrency-point forms. rel 1e-9
    h = random_poses(30, 4)
    w = np.random.default_rng(5).normal(size=(30, 6)) * [700, 700, 700, 60, 60, 60]
    res = condensed.solve_linear(machine, h, w)
    c = condensed.condensed_plate_compliance(machine, h)
    x = np.einsum("pij,pj->pi", c, w)
    np.testing.assert_allclose(x[:, :3], res.plate_displacement_m, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(x[:, 3:], res.plate_rotation_rad, rtol=1e-9, atol=1e-15)
    for about in ("centre", "concurrency"):
        kc = condensed.plate_stiffness(machine, h, about) @ condensed.condensed_plate_compliance(machine, h, about)
        np.testing.assert_allclose(kc, np.broadcast_to(np.eye(6), kc.shape), atol=1e-9)
    kp = condensed.plate_stiffness(machine, h, "concurrency")
    np.testing.assert_array_equal(kp[:, :3, 3:], 0)


def test_leg_moments_in_the_leg_frame(machine):
    # project the world couple vectors on kinematics.leg_frames; M_y = 0, c normal to a_i, in plane (a_i, e_i)
    h = random_poses(50, 6)
    res = condensed.solve_linear(machine, h, [30, 700, -50, 5, 0, 8])
    frames = kinematics.leg_frames(machine, h)
    ref = np.einsum("plji,plj->pli", frames, res.couple_vectors_nm)
    np.testing.assert_allclose(res.leg_moments_nm, ref, atol=1e-12 * np.abs(ref).max())
    np.testing.assert_allclose(res.leg_moments_nm[..., 1], 0, atol=1e-12)
    c = res.couple_directions
    np.testing.assert_allclose(np.einsum("plj,lj->pl", c, AXES), 0, atol=1e-15)
    np.testing.assert_allclose(np.einsum("plj,plj->pl", np.cross(AXES, res.leg_unit_vectors), c), 0, atol=1e-15)


# --- symmetry -------------------------------------------------------------------------------------
SYMMETRIES = {  # name: (proper or improper orthogonal map, leg permutation: leg i goes to perm[i])
    "mirror x": (np.diag([-1.0, 1, 1]), [0, 3, 2, 1]),
    "mirror z": (np.diag([1.0, 1, -1]), [2, 1, 0, 3]),
    "rotation 90 deg about y": (Rotation.from_euler("y", 90, degrees=True).as_matrix(), [3, 0, 1, 2]),
}


@pytest.mark.parametrize("name", list(SYMMETRIES))
def test_symmetry_maps_leg_loads(machine, name):
    # the machine maps onto itself: a mapped pose and load give the same leg loads on the mapped legs;
    # moments and rotations are pseudo-vectors (times det S). rel 1e-10
    s, perm = SYMMETRIES[name]
    det = np.linalg.det(s)
    h = random_poses(40, 7)
    w = np.random.default_rng(8).normal(size=(40, 6)) * [700, 700, 700, 60, 60, 60]
    a = condensed.solve_linear(machine, h, w)
    b = condensed.solve_linear(machine, h @ s.T, np.c_[w[:, :3] @ s.T, det * w[:, 3:] @ s.T])
    np.testing.assert_allclose(b.axial_forces_n[:, perm], a.axial_forces_n, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(b.couple_vectors_nm[:, perm], det * a.couple_vectors_nm @ s.T, atol=1e-9)
    np.testing.assert_allclose(np.abs(b.leg_moments_nm[:, perm]), np.abs(a.leg_moments_nm), atol=1e-9)
    np.testing.assert_allclose(b.plate_displacement_m, a.plate_displacement_m @ s.T, atol=1e-15)
    np.testing.assert_allclose(b.plate_rotation_rad, det * a.plate_rotation_rad @ s.T, atol=1e-15)


# --- finite-difference stiffness from an energy written here ------------------------------------------
def _energy_hessian(h):
    """Central-difference Hessian of U(delta, phi) = sum 1/2 k_a dl^2 + 1/2 k_r (c . phi)^2 about h."""
    u0 = h + OFFS - BASE
    l0 = np.linalg.norm(u0, axis=1)
    e = u0 / l0[:, None]
    k_r = np.empty(4)
    c = np.empty((4, 3))
    for i in range(4):
        b = np.cross(AXES[i], e[i])
        b /= np.linalg.norm(b)  # second cardan axis: normal to a_i and the leg
        c[i] = np.cross(AXES[i], b)  # the only couple both cardans transmit
        ex = AXES[i] - AXES[i] @ e[i] * e[i]
        ex /= np.linalg.norm(ex)
        cl = np.array([c[i] @ ex, c[i] @ np.cross(e[i], ex), c[i] @ e[i]])  # in the leg frame
        seg = [(L_CYL, I_CYL), (l0[i] - L_CYL, I_STEM)]
        k_r[i] = 1 / sum(ln * ((cl[0] ** 2 + cl[1] ** 2) / (E * i2) + cl[2] ** 2 / (G * 2 * i2)) for ln, i2 in seg)

    def energy(x):
        rot = Rotation.from_rotvec(x[3:]).as_matrix()
        u = h + x[:3] + OFFS @ rot.T - BASE
        dl = (np.sum(u * u, 1) - l0**2) / (np.linalg.norm(u, axis=1) + l0)
        return 0.5 * np.sum(k_axial(l0) * dl**2) + 0.5 * np.sum(k_r * (c @ x[3:]) ** 2)

    steps = np.array([1e-6] * 3 + [1e-5] * 3)
    hess = np.empty((6, 6))
    for i in range(6):
        for j in range(6):
            def f(si, sj, i=i, j=j):
                x = np.zeros(6)
                x[i] += si * steps[i]
                x[j] += sj * steps[j]
                return energy(x)
            hess[i, j] = (f(1, 1) - f(1, -1) - f(-1, 1) + f(-1, -1)) / (4 * steps[i] * steps[j])
    return hess


@pytest.mark.parametrize("h", [[0.0, 0.6, 0.0], [0.2, 0.55, -0.15], [-0.25, 0.74, 0.25], [0.1, 0.5, 0.22]])
def test_stiffness_is_the_energy_hessian(machine, h):
    # entries agree to 1e-6 of sqrt(K_ii K_jj) (central differences, steps 1 um and 10 urad)
    k_fd = _energy_hessian(np.array(h))
    k = condensed.plate_stiffness(machine, h)
    scale = np.sqrt(np.outer(np.diag(k), np.diag(k)))
    assert np.max(np.abs(k - k_fd) / scale) < 1e-6


# --- maps, envelope, preload, errors --------------------------------------------------------------------
@pytest.mark.slow
def test_stiffness_maps(machine, tmp_path):
    maps = condensed.stiffness_maps(machine, 0.72, n=5)
    assert maps.vertical_n_per_m.shape == (5, 5) and np.all(maps.reachable)
    length = math.hypot(0.72, P - R)
    assert maps.vertical_n_per_m[2, 2] == pytest.approx(4 * k_axial(length) * (0.72 / length) ** 2, rel=1e-12)
    assert maps.tilt_rad[2, 2] == pytest.approx(0, abs=1e-15)  # pose A does not tilt
    # pose A, lateral force along x: legs 2 and 4 resist translation of P* (2 k_a cos^2 alpha); the moment
    # of the force about P*, F y r / (p - r), tilts the plate about z against the torsion of legs 1 and 3
    # (beta = 0: c_i = e_i, 2 k_T cos^2 alpha), and the tilt moves the centre by y r / (p - r) per rad
    cos_a, arm = (P - R) / length, 0.72 * R / (P - R)
    k_t = 1 / (L_CYL / (G * 2 * I_CYL) + (length - L_CYL) / (G * 2 * I_STEM))
    k_lat = 1 / (1 / (2 * k_axial(length) * cos_a**2) + arm**2 / (2 * k_t * cos_a**2))
    assert maps.lateral_x_n_per_m[2, 2] == pytest.approx(k_lat, rel=1e-12)
    assert maps.lateral_n_per_m[2, 2] == pytest.approx(k_lat, rel=1e-12)  # x and z are alike at pose A
    assert maps.lateral_to_vertical[2, 2] < 0.01  # rocking is held by leg torsion only
    assert np.all(maps.lateral_to_vertical < 1)
    assert np.all(maps.lateral_n_per_m <= np.minimum(maps.lateral_x_n_per_m, maps.lateral_z_n_per_m) * (1 + 1e-12))
    np.testing.assert_allclose(maps.tilt_rad, maps.tilt_rad.T, rtol=1e-9)  # x <-> z symmetry of the square
    paths = map_files.write_stiffness_maps(maps, tmp_path)
    assert {p.suffix for p in paths} == {".png", ".csv"} and all(p.stat().st_size > 0 for p in paths)
    with pytest.raises(OutputExistsError):
        map_files.write_stiffness_maps(maps, tmp_path)


@pytest.mark.slow
def test_load_envelope_matches_brute_force(machine, tmp_path):
    ys = np.array([0.5, 0.62, 0.74])
    loads = workspace_envelope.press_loads(cone_half_angle_rad=math.radians(10), n_azimuth=4)
    env = workspace_envelope.load_envelope(machine, ys, n_xz=7, loads_n=loads, chunk_poses=100, progress=False)
    assert env.n_evaluated == 3 * 49 and env.n_unreachable == 0
    x, z = workspace_square(machine, 7)
    h = np.stack(np.meshgrid(x, ys, z, indexing="ij"), -1).reshape(-1, 3)
    res = condensed.solve_linear(machine, h[None], np.c_[loads, np.zeros_like(loads)][:, None])  # (L, P, ...)
    np.testing.assert_allclose(env.entries["tension_n"].value, res.axial_forces_n.max((0, 1)), rtol=1e-12)
    np.testing.assert_allclose(env.entries["compression_n"].value, (-res.axial_forces_n).max((0, 1)), rtol=1e-12)
    np.testing.assert_allclose(env.entries["torsion_nm"].value, np.abs(res.leg_moments_nm[..., 2]).max((0, 1)),
                               rtol=1e-12)
    assert float(env.entries["tilt_rad"].value) == pytest.approx(res.tilt_rad.max(), rel=1e-12)
    # the reported pose and load reproduce the reported value
    e = env.entries["bending_nm"]
    for leg in range(4):
        again = condensed.solve_linear(machine, e.pose_m[leg], e.load_n[leg])
        assert again.bending_nm[leg] == pytest.approx(e.value[leg], rel=1e-12)
    # 90-degree symmetry of machine, grid and load set: every leg has the same envelope
    np.testing.assert_allclose(env.entries["torsion_nm"].value, env.entries["torsion_nm"].value[0], rtol=1e-9)
    assert env.maps["tilt_rad"].shape == (7, 7)
    paths = map_files.write_load_envelope(env, tmp_path)
    assert len(paths) == 5 and (tmp_path / "load_envelope.csv").read_text().count("\n") == 6 * 4 + 2 + 1
    records = json.loads((tmp_path / "load_envelope.json").read_text())  # the same rows, keyed by the CSV header
    assert [list(r.values()) for r in records] == workspace_envelope.envelope_rows(env)[1]


def test_envelope_counts_unreachable_poses(machine):
    env = workspace_envelope.load_envelope(machine, [0.3, 0.6], n_xz=5, progress=False)
    assert env.n_unreachable > 0 and env.n_evaluated == 25


def test_axial_preload_superposes(machine):
    h = random_poses(10, 9)
    res = condensed.solve_linear(machine, h, [0, 700, 0])
    vp = kinematics.preload_vector(machine, h)
    pre = with_axial_preload(res, 300 * vp)
    np.testing.assert_allclose(pre.axial_forces_n - res.axial_forces_n, 300 * vp, rtol=1e-14)
    assert np.max(pre.relative_residual()) < 1e-9
    bad = with_axial_preload(res, np.full((10, 4), 100.0))  # not self-equilibrated: shows
    assert np.min(bad.relative_residual()) > 0.1


def test_bad_input_is_a_pressfit_error(machine):
    with pytest.raises(PressfitError):
        condensed.solve_linear(machine, [0, 0.6], [0, 700, 0])
    with pytest.raises(PressfitError):
        condensed.solve_linear(machine, [0, 0.6, 0], [0, 700])
    with pytest.raises(PressfitError):
        condensed.plate_stiffness(machine, [0, 0.6, 0], about="P")
    elastic = machine.with_overrides({"joints": {"cardan_rotational_stiffness_nm_per_rad": 1e5}})
    with pytest.raises(CondensedModelError):
        condensed.solve_linear(elastic, [0, 0.6, 0], [0, 700, 0])


@pytest.mark.slow
def test_cli_stiffness(tmp_path):
    import json

    from click.testing import CliRunner

    from pressfit.cli import main

    out = CliRunner().invoke(main, ["stiffness", "0", "0.72", "0", "--json"])
    assert out.exit_code == 0, out.output
    data = json.loads(out.output)
    length = math.hypot(0.72, P - R)
    assert data["vertical_stiffness_n_per_m"] == pytest.approx(4 * k_axial(length) * (0.72 / length) ** 2, rel=1e-12)
    assert np.shape(data["compliance_6x6"]) == (6, 6)
    maps = CliRunner().invoke(main, ["stiffness", "0", "0.6", "0", "--maps", "--out", str(tmp_path), "--n", "5"])
    assert maps.exit_code == 0 and (tmp_path / "stiffness_maps_y600mm.png").exists()
    assert CliRunner().invoke(main, ["stiffness", "0", "0.3", "0"]).exit_code == 2  # unreachable: a clear error


# --- the singular-pose guard ------------------------------------------------------------------------
# Near y = 0 the shipped legs (l = 0.36 m) are shorter than their 0.45 m cylinder, which gives negative
# springs; a 0.2 m cylinder keeps every spring positive there, so only the geometry is singular.
@pytest.fixture(scope="module")
def short_cylinder(machine):
    # the stem rod must outlast the longer stroke (l_max - L_c = 0.8 m); its length does not enter the statics
    return machine.with_overrides({"cylinder": {"length_m": 0.2}, "stem": {"length_m": 0.85}}, source="test")


def singular_height_m() -> float:
    """The height y* below which the guard refuses h = (0, y, 0), from a closed form derived here.

    At x = z = 0 every leg has sin(beta) = 0, so c_i = e_i, and with equal legs K_t / k_a = K_r / k_r =
    sum e_i e_i^T = diag(2 cos^2 a, 4 sin^2 a, 2 cos^2 a) (tan a = y / (p - r)): both determinants are
    16 cos^4(a) sin^2(a) times the cube of the leg spring. condensed.py refuses a block whose determinant is
    below 1e-12 times the cube of its largest spring, i.e. below 16 cos^4 sin^2 = 1e-12 (y* = 9.0e-8 m). At
    y = 0 the plate lies in the base plane, every leg is horizontal and nothing holds it vertically."""
    from scipy.optimize import brentq

    def margin(y):
        a = math.atan2(y, P - R)
        return 16 * math.cos(a) ** 4 * math.sin(a) ** 2 - 1e-12

    return brentq(margin, 1e-12, 1e-3, xtol=1e-20, rtol=1e-14)


@pytest.mark.parametrize("y", [0.0, "half"])
def test_singular_pose_is_refused(short_cylinder, y):
    """The stiffness is singular (y = 0) or numerically so (y*/2): a SingularPoseError naming the pose, never
    NaN or inf compliances, and no RuntimeWarning of the division that the guard then refuses (a user sees one
    line)."""
    import warnings

    h = [0.0, singular_height_m() / 2 if y == "half" else y, 0.0]
    from pressfit.errors import SingularPoseError

    for call in (lambda: condensed.solve_linear(short_cylinder, h, [0, 700, 0]),
                 lambda: condensed.condensed_plate_compliance(short_cylinder, h),
                 lambda: condensed.plate_stiffness(short_cylinder, [[0, 0.72, 0], h])):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with pytest.raises(SingularPoseError, match=r"singular at 1 pose\(s\), e\.g\. h = \[0\.0, ") as exc:
                call()
            assert exc.value.pose_m == tuple(h)


def test_pose_just_clear_of_the_guard_is_solved(short_cylinder):
    """At 2 y* the guard lets the pose through and the (huge) vertical compliance is the closed form
    1 / (4 k_a sin^2 a) (condition number 1e12: to 1e-6)."""
    y = 2 * singular_height_m()
    length = math.hypot(y, P - R)
    k_a = 1 / float(short_cylinder.axial_compliance_m_per_n(length))
    k_vert = 4 * k_a * (y / length) ** 2
    res = condensed.solve_linear(short_cylinder, [0, y, 0], [0, 700, 0])
    assert res.plate_displacement_m[1] == pytest.approx(700 / k_vert, rel=1e-6)
    assert condensed.condensed_plate_compliance(short_cylinder, [0, y, 0])[1, 1] == pytest.approx(1 / k_vert, rel=1e-6)


def test_stiffness_report_off_centre_against_the_vjm_model(machine):
    """Every stiffness of ``stiffness_report`` at an asymmetric pose (where x and z, and the couplings, all
    differ: at pose A symmetry hides a wrong index) against the second formulation: the Pinocchio VJM
    compliance and its linear solve under the press load (they agree with the condensed model to ~1e-11;
    asserted to 1e-8)."""
    from pressfit.mechanics.compliance import vjm_plate_compliance
    from pressfit.mechanics.statics import solve_equilibrium

    pose = [0.2, 0.6, -0.15]
    rep, c = condensed.stiffness_report(machine, pose), vjm_plate_compliance(machine, pose)
    horizontal = c[np.ix_([0, 2], [0, 2])]
    assert abs(c[0, 0] - c[2, 2]) > 0.05 * c[0, 0] and abs(horizontal[0, 1]) > 1e-3 * c[0, 0]  # no symmetry here
    lam = np.linalg.eigvalsh(horizontal)[-1]
    expected = {"vertical_stiffness_n_per_m": 1 / c[1, 1], "lateral_stiffness_n_per_m": 1 / lam,
                "lateral_x_stiffness_n_per_m": 1 / c[0, 0], "lateral_z_stiffness_n_per_m": 1 / c[2, 2],
                "lateral_to_vertical": c[1, 1] / lam}
    for key, value in expected.items():
        assert rep[key] == pytest.approx(value, rel=1e-8), key
    np.testing.assert_allclose(rep["compliance_6x6"], c, rtol=0, atol=1e-8 * np.abs(c).max())
    # the inverse of the ill-conditioned 3x3 block amplifies the 1e-11 difference: 1.2e-8 measured
    np.testing.assert_allclose(rep["translational_stiffness_n_per_m"], np.linalg.inv(c[:3, :3]), rtol=5e-8)
    eq = solve_equilibrium(machine, pose, [0, 700, 0, 0, 0, 0], linear=True)
    np.testing.assert_allclose(rep["press_displacement_m"], eq.plate_displacement_m, rtol=1e-8, atol=1e-15)
    np.testing.assert_allclose(rep["press_rotation_rad"], eq.plate_rotation_rad, rtol=1e-8, atol=1e-15)
    assert rep["press_tilt_rad"] == pytest.approx(np.linalg.norm(eq.plate_rotation_rad), rel=1e-8)
    np.testing.assert_allclose(rep["press_axial_forces_n"], eq.actuator_forces_n, rtol=1e-8)
    assert rep["pose_m"] == pose and rep["press_load_n"] == 700.0
    assert condensed.stiffness_report(machine, np.array([pose])) == rep  # a (1, 3) pose is the same pose
    # leg moments (M_x, M_y, T), constant along a leg in the condensed model: the Pinocchio actuator section
    moments = np.array([[leg.sections["actuator"].as_dict()[k] for k in ("M_x", "M_y", "T")] for leg in eq.legs])
    np.testing.assert_allclose(rep["press_leg_moments_nm"], moments, rtol=0, atol=1e-8 * np.abs(moments).max())
    assert rep["compliance_units"] == "rows/columns (x, y, z, rx, ry, rz): m/N, rad/N, rad/(N m)"
    # about P* the translation block is sum k_a e e^T (docs/conventions.md), from the leg vectors here
    u = np.asarray(pose) + OFFS - BASE
    length = np.linalg.norm(u, axis=1)
    e = u / length[:, None]
    k_t = sum(k_axial(li) * np.outer(ei, ei) for li, ei in zip(length, e))
    np.testing.assert_allclose(rep["translational_stiffness_about_p_star_n_per_m"], k_t, rtol=0,
                               atol=1e-12 * np.abs(k_t).max())


def test_condensed_model_error_carries_the_broken_assumption(machine):
    """Callers read the machine and the assumption from the exception, not from its message."""
    elastic = machine.with_overrides({"joints": {"cardan_rotational_stiffness_nm_per_rad": 1e5}})
    with pytest.raises(CondensedModelError) as err:
        condensed.plate_stiffness(elastic, [0.0, 0.6, 0.0])
    assert (err.value.machine, err.value.assumption) == (machine.name, "free cardans")
