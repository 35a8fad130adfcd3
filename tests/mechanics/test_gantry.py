"""The Cartesian gantry's VJM model (pressfit.mechanics.gantry) against closed-form beam and spring mechanics.

Each expected value is derived here from the shipped file's inputs (sections, stiffnesses), never from the
program's output. Beam formulas: Euler-Bernoulli with Timoshenko's shear term added where the model's
default law includes it (Timoshenko & Gere, Mechanics of Materials: cantilever and fixed-fixed beams)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pressfit.description.gantry import load_gantry
from pressfit.errors import ResidualError, UnreachablePoseError, UnstableEquilibriumError
from pressfit.mechanics.gantry import COMPONENTS, build_gantry_model
from pressfit.shipped import models_dir

GANTRY = load_gantry(models_dir() / "gantry_cartesian.toml")
E, G = GANTRY.material.youngs_modulus_pa, GANTRY.material.shear_modulus_pa
F = 700.0  # the press load, N
UP = np.array([0.0, F, 0.0, 0.0, 0.0, 0.0])
RTOL = 1e-9  # the lumped model is exact for end-loaded members (module doc): round-off only


def only(*flexible: str) -> tuple[str, ...]:
    """The ``rigid`` argument that leaves only these components elastic."""
    return tuple(c for c in COMPONENTS if c not in flexible)


def screw_stiffness(axis: str) -> float:
    """Ball screw in series with nut and bearing: 1/k = L / (E pi d^2 / 4) + 1/k_nut + 1/k_bearing."""
    d = getattr(GANTRY.axes, axis).drive
    return 1.0 / (d.screw_free_length_m / (E * math.pi * d.screw_root_diameter_m**2 / 4)
                  + 1 / d.nut_stiffness_n_per_m + 1 / d.bearing_stiffness_n_per_m)


def box(b: float, h: float, t: float) -> tuple[float, float, float]:
    """Area, I about the width axis (b h^3 / 12 minus the hole's) and the EN 1993-1-1 shear area A h / (b + h)
    of a rectangular hollow section (height h along the shear)."""
    area = b * h - (b - 2 * t) * (h - 2 * t)
    return area, (b * h**3 - (b - 2 * t) * (h - 2 * t) ** 3) / 12, area * h / (b + h)


def test_x_beam_built_in_at_both_columns_under_a_mid_span_load():
    """Rigid columns: the X beam is a fixed-fixed beam of span L with the load at mid-span, delta = F L^3 / (192 E I)
    + F L / (4 G A_s) (each half carries F/2 in shear over L/2), and the moment is F L / 8 at both ends and at
    mid-span (the slope vanishes at the ends and, by symmetry, at mid-span)."""
    s = GANTRY.sections.x_beam
    area, i, shear = box(s.width_m, s.height_m, s.wall_thickness_m)
    span = GANTRY.frame.span_m
    gm = build_gantry_model(GANTRY, (0.0, 0.6, 0.0), rigid=only("x_beam"))
    eq = gm.solve(UP)
    expected = F * span**3 / (192 * E * i) + F * span / (4 * G * shear)
    assert eq.tool_displacement_m[1] == pytest.approx(expected, rel=RTOL)
    assert eq.members["x_beam"].bending_moment_nm == pytest.approx(F * span / 8, rel=RTOL)
    for name, s_m in (("x_beam_left", 0.0), ("x_beam_left", span / 2), ("x_beam_right", 0.0)):
        assert abs(gm.section_wrench(eq, name, s_m).M_x) == pytest.approx(F * span / 8, rel=RTOL)
    assert gm.section_wrench(eq, "x_beam_left", span / 4).M_x == pytest.approx(0.0, abs=1e-9 * F * span)  # inflexion
    assert gm.section_wrench(eq, "x_beam_left", span / 4).V_y == pytest.approx(F / 2, rel=RTOL)


def test_portal_frame_by_slope_deflection():
    """Flexible columns (Euler-Bernoulli law, slender solid sections so that axial strain barely couples):
    symmetric fixed-base portal of height h, span L, central load P, no sway. Slope-deflection with corner
    rotation theta: column M = 4 E I_c theta / h, beam M = 2 E I_b theta / L - P L / 8; joint balance gives
    theta = (P L / 8) / (4 E I_c / h + 2 E I_b / L); the mid-span moment is P L / 4 - M_corner and the mid-span
    deflection P L^3 / (48 E I_b) - M_corner L^2 / (8 E I_b) plus each column's shortening (P / 2) h / (E A_c)."""
    g = GANTRY.with_overrides({"sections": {"column": {"kind": "solid", "width_m": 0.02, "height_m": 0.02,
                                                       "wall_thickness_m": None},
                                            "x_beam": {"kind": "solid", "width_m": 0.02, "height_m": 0.02,
                                                       "wall_thickness_m": None}}})
    p, h, span = 50.0, g.frame.column_height_m, g.frame.span_m
    i, a = 0.02**4 / 12, 0.02**2
    gm = build_gantry_model(g, (0.0, 0.6, 0.0), rigid=only("column", "x_beam"), transverse="euler_bernoulli")
    eq = gm.solve([0.0, p, 0.0, 0.0, 0.0, 0.0])
    theta = (p * span / 8) / (4 * E * i / h + 2 * E * i / span)
    corner = 4 * E * i * theta / h
    deflection = p * span**3 / (48 * E * i) - corner * span**2 / (8 * E * i) + (p / 2) * h / (E * a)
    # axial strain of the beam (its thrust) changes the frame by O(I / (A L^2)) = 3e-5 here
    assert eq.tool_displacement_m[1] == pytest.approx(deflection, rel=2e-4)
    assert abs(gm.section_wrench(eq, "x_beam_left", 0.0).M_x) == pytest.approx(corner, rel=2e-4)
    assert abs(gm.section_wrench(eq, "x_beam_left", span / 2).M_x) == pytest.approx(p * span / 4 - corner, rel=2e-4)


@pytest.mark.parametrize("pose", [(0.0, 0.5, 0.0), (0.2, 0.75, -0.1)])
def test_ram_is_a_cantilever(pose):
    """Only the ram elastic: a cantilever of free length L = y_guide - y. A tip force F along x (the section's
    height direction) gives delta = F L^3 / (3 E I) + F L / (G A_s) and slope F L^2 / (2 E I); along the ram,
    F L / (E A)."""
    s = GANTRY.sections.ram
    area, i, shear = box(s.width_m, s.height_m, s.wall_thickness_m)
    length = GANTRY.ram_guide_height_m - pose[1]
    gm = build_gantry_model(GANTRY, pose, rigid=only("ram"))
    lateral = gm.solve([F, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert lateral.tool_displacement_m[0] == pytest.approx(F * length**3 / (3 * E * i) + F * length / (G * shear),
                                                           rel=RTOL)
    # the ram hangs down (-y): a tip force +x turns its tip about +z
    assert lateral.tool_rotation_rad[2] == pytest.approx(F * length**2 / (2 * E * i), rel=RTOL)
    assert lateral.members["ram"].bending_moment_nm == pytest.approx(F * length, rel=RTOL)  # at the guide
    assert lateral.members["ram"].distance_from_root_m == 0.0
    axial = gm.solve(UP)
    assert axial.tool_displacement_m[1] == pytest.approx(F * length / (E * area), rel=RTOL)


@pytest.mark.slow
@pytest.mark.parametrize("n", [1, 2, 4, 8])
def test_springs_per_segment_convergence(n):
    """With model.py's law alone (midpoint rotational springs, transverse='none') a cantilever's tip deflection is
    the midpoint rule of integral_0^L F (L - s)^2 / (E I) ds: F L^3 / (3 E I) (1 - 1 / (4 n^2)), an error falling
    as 1/n^2; with the transverse springs (the default law) it is exact for every n."""
    s = GANTRY.sections.ram
    _, i, shear = box(s.width_m, s.height_m, s.wall_thickness_m)
    pose = (0.0, 0.5, 0.0)
    length = GANTRY.ram_guide_height_m - pose[1]
    exact = F * length**3 / (3 * E * i)
    lumped = build_gantry_model(GANTRY, pose, rigid=only("ram"), springs_per_segment=n, transverse="none")
    assert lumped.solve([F, 0, 0, 0, 0, 0]).tool_displacement_m[0] == pytest.approx(exact * (1 - 1 / (4 * n**2)),
                                                                                     rel=RTOL)
    eb = build_gantry_model(GANTRY, pose, rigid=only("ram"), springs_per_segment=n, transverse="euler_bernoulli")
    assert eb.solve([F, 0, 0, 0, 0, 0]).tool_displacement_m[0] == pytest.approx(exact, rel=RTOL)


def test_vertical_springs_in_series_at_the_centre():
    """Rigid columns, tool at (0, y, 0) (the Z beam's loaded arm has zero length): the vertical load passes in series
    through the ram (axial L / (E A)), the Y drive, the Z guide and the X guide (normal) and the fixed-fixed X beam,
    so the compliances add."""
    y = 0.55
    ram, xb = GANTRY.sections.ram, GANTRY.sections.x_beam
    a_ram = box(ram.width_m, ram.height_m, ram.wall_thickness_m)[0]
    _, i_b, shear_b = box(xb.width_m, xb.height_m, xb.wall_thickness_m)
    span = GANTRY.frame.span_m
    compliance = ((GANTRY.ram_guide_height_m - y) / (E * a_ram) + 1 / screw_stiffness("y")
                  + 1 / GANTRY.axes.z.guide.normal_stiffness_n_per_m + 1 / GANTRY.axes.x.guide.normal_stiffness_n_per_m
                  + span**3 / (192 * E * i_b) + span / (4 * G * shear_b))
    gm = build_gantry_model(GANTRY, (0.0, y, 0.0), rigid=("column",))
    assert gm.solve(UP).tool_displacement_m[1] == pytest.approx(F * compliance, rel=RTOL)
    assert 1 / np.linalg.inv(gm.tool_stiffness_n_per_m())[1, 1] == pytest.approx(1 / compliance, rel=RTOL)


def test_lateral_springs_in_series_with_their_lever_arms():
    """Rigid members: a tool force F_x passes through the X drive (axial), the Z guide and the Y guide (normal) and
    turns the X carriage (guide tilts about z, lever top - y, and about y, lever |z|: the X carriage sits at z = 0),
    the Z carriage (roll about its axis z) and the ram guide (tilt about z), each rotation moving the tool by its
    lever arm d: u = F (sum 1/k + sum d^2 / k_theta)."""
    x, y, z = 0.1, 0.6, -0.2
    a = GANTRY.axes
    top = GANTRY.frame.column_height_m
    y_z = top - GANTRY.frame.x_to_z_beam_drop_m
    compliance = (1 / screw_stiffness("x") + 1 / a.z.guide.normal_stiffness_n_per_m
                  + 1 / a.y.guide.normal_stiffness_n_per_m
                  + ((top - y) ** 2 + z**2) / a.x.guide.tilt_stiffness_nm_per_rad
                  + (y_z - y) ** 2 / a.z.guide.roll_stiffness_nm_per_rad
                  + (GANTRY.ram_guide_height_m - y) ** 2 / a.y.guide.tilt_stiffness_nm_per_rad)
    eq = build_gantry_model(GANTRY, (x, y, z), rigid=("column", "x_beam", "z_beam", "ram")).solve([F, 0, 0, 0, 0, 0])
    assert eq.tool_displacement_m[0] == pytest.approx(F * compliance, rel=RTOL)
    assert eq.drive_forces_n == pytest.approx([F, 0.0, 0.0], abs=1e-9 * F)


def test_statics_of_the_determinate_parts():
    """Whatever the compliances: the Y drive carries the whole press load, the Z beam's root moment is F |z|, and
    the bed reactions balance the load (the residuals)."""
    pose = (-0.25, 0.5, 0.25)
    eq = build_gantry_model(GANTRY, pose).solve(UP)
    assert eq.drive_forces_n == pytest.approx([0.0, F, 0.0], abs=1e-9 * F)
    assert eq.members["z_beam"].bending_moment_nm == pytest.approx(F * 0.25, rel=RTOL)
    assert eq.members["z_beam"].distance_from_root_m == 0.0
    assert eq.members["ram"].bending_moment_nm == pytest.approx(0.0, abs=1e-9 * F)
    assert eq.residuals.worst() < 1e-12


def _mirror(v: np.ndarray, axis: int) -> np.ndarray:
    """A vector reflected in the plane normal to ``axis``."""
    out = np.array(v, dtype=float)
    out[axis] = -out[axis]
    return out


@pytest.mark.parametrize("axis", [0, 2])
def test_mirror_image_pose_gives_the_mirror_image_result(axis):
    """The gantry is symmetric in x = 0 and z = 0: reflecting the pose and the load's force reflects the tool's
    displacement; moments and rotations are pseudo-vectors (reflected and negated); the drive forces follow their
    axes; in x, the two columns exchange their moments."""
    pose = np.array([0.17, 0.62, -0.21])
    wrench = np.array([40.0, F, -30.0, 5.0, -7.0, 3.0])
    eq = build_gantry_model(GANTRY, pose).solve(wrench)
    mirrored = np.concatenate([_mirror(wrench[:3], axis), -_mirror(wrench[3:], axis)])
    eq_m = build_gantry_model(GANTRY, _mirror(pose, axis)).solve(mirrored)
    scale = np.abs(eq.tool_displacement_m).max()
    assert eq_m.tool_displacement_m == pytest.approx(_mirror(eq.tool_displacement_m, axis), abs=1e-10 * scale)
    rot = np.abs(eq.tool_rotation_rad).max()
    assert eq_m.tool_rotation_rad == pytest.approx(-_mirror(eq.tool_rotation_rad, axis), abs=1e-10 * rot)
    drives = np.array(eq.drive_forces_n)
    drives[axis] = -drives[axis]
    assert eq_m.drive_forces_n == pytest.approx(drives, abs=1e-9 * F)
    pairs = {"column_left": "column_right", "column_right": "column_left"} if axis == 0 else {}
    for name, m in eq.members.items():
        assert eq_m.members[pairs.get(name, name)].bending_moment_nm == pytest.approx(m.bending_moment_nm, rel=1e-9)


def test_tool_compliance_is_symmetric_and_inverts_the_solve():
    """Maxwell-Betti reciprocity: the tool compliance is symmetric; its stiffness applied to a pure-force solve's
    displacement gives the force back."""
    gm = build_gantry_model(GANTRY, (0.25, 0.7, 0.25))
    c = gm.tool_compliance()
    assert c == pytest.approx(c.T, abs=1e-12 * np.abs(c).max())
    force = np.array([30.0, F, -20.0])
    u = gm.solve(np.concatenate([force, np.zeros(3)])).tool_displacement_m
    assert gm.tool_stiffness_n_per_m() @ u == pytest.approx(force, rel=1e-9)


def test_a_solution_over_its_tolerance_is_refused():
    """The residual check is wired: with a tolerance no solution can meet, the solve raises and names the residual."""
    with pytest.raises(ResidualError, match="gantry linear solve at tool pose"):
        build_gantry_model(GANTRY, (0.1, 0.6, 0.1)).solve(UP, tol=-1.0)


def test_the_linear_solve_refuses_loads_near_buckling():
    """N / N_E of the ram (cantilever Euler load pi^2 E I / (4 L^2)) above 1%: the linear solve is refused."""
    s = GANTRY.sections.ram
    _, i, _ = box(s.width_m, s.height_m, s.wall_thickness_m)
    length = GANTRY.ram_guide_height_m - 0.5
    euler = math.pi**2 * E * i / (4 * length**2)
    gm = build_gantry_model(GANTRY, (0.0, 0.5, 0.0))
    assert gm.solve([0, 0.009 * euler, 0, 0, 0, 0]).axial_load_ratio == pytest.approx(0.009, rel=1e-9)
    with pytest.raises(UnstableEquilibriumError, match="Euler load") as exc:
        gm.solve([0, 0.011 * euler, 0, 0, 0, 0])
    assert exc.value.leg is None and exc.value.pose_m == (0.0, 0.5, 0.0)
    assert exc.value.load == (0, 0.011 * euler, 0, 0, 0, 0)


@pytest.mark.parametrize(("pose", "text"), [((0.3, 0.6, 0.0), "x [m] = 0.3 breaks maximum 0.25"),
                                             ((0.0, 0.45, 0.0), "y [m] = 0.45 breaks minimum 0.5"),
                                             ((0.0, 0.6, float("nan")), "z [m] = nan breaks minimum -0.25")])
def test_a_pose_outside_the_workspace_is_refused(pose, text):
    with pytest.raises(UnreachablePoseError, match=text.replace("[", r"\[").replace("]", r"\]")):
        build_gantry_model(GANTRY, pose)
