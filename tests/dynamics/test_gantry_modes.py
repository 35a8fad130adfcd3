"""Modes and summary metrics of the Cartesian gantry (pressfit.dynamics.gantry_modes), against closed forms and
independent computations written here."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import brentq

from pressfit.description.gantry import load_gantry
from pressfit.dynamics.gantry_modes import gantry_metrics, gantry_modes, inertial_gantry_model
from pressfit.dynamics.modes import mass_matrix
from pressfit.errors import PressfitError
from pressfit.mechanics.gantry import COMPONENTS, build_gantry_model
from pressfit.shipped import models_dir

GANTRY = load_gantry(models_dir() / "gantry_cartesian.toml")
E, RHO = GANTRY.material.youngs_modulus_pa, GANTRY.mass.density_kg_per_m3
SLENDER_RAM = GANTRY.with_overrides({"sections": {"ram": {"kind": "solid", "width_m": 0.02, "height_m": 0.02,
                                                          "wall_thickness_m": None}}})
ONLY_RAM = tuple(c for c in COMPONENTS if c != "ram")


def tip_mass_cantilever_hz(ei: float, length: float, beam_mass: float, tip_mass: float) -> float:
    """First frequency of an Euler-Bernoulli cantilever (mass m) with a tip point mass M, from the boundary
    conditions w(0) = w'(0) = 0, w''(L) = 0, E I w'''(L) = -M omega^2 w(L) on w = A (cosh - cos) + B (sinh - sin)
    of beta x / L: 1 + cos(b) cosh(b) + (M/m) b (cos(b) sinh(b) - sin(b) cosh(b)) = 0, omega = b^2 sqrt(E I / (m L^3))
    (the root below 1.875, the bare cantilever's)."""
    mu = tip_mass / beam_mass
    b = brentq(lambda b: 1 + math.cos(b) * math.cosh(b) + mu * b * (math.cos(b) * math.sinh(b)
                                                                   - math.sin(b) * math.cosh(b)), 0.1, 1.8751)
    return b**2 * math.sqrt(ei / (beam_mass * length**3)) / (2 * math.pi)


def test_cantilever_ram_with_the_tool_as_tip_mass():
    """Only the (slender, 20 mm square) ram elastic, Euler-Bernoulli law: its first frequency against the exact root
    and against Rayleigh's sqrt(3 E I / (L^3 (M + 0.2357 m))) / (2 pi) (33/140 of the beam's mass at the tip). With
    4 stations the lumped masses err by 3.4e-4, the Rayleigh quotient by 2.5e-4 here (mu = M / m = 1.6): 1e-3."""
    y = 0.5
    length = SLENDER_RAM.ram_guide_height_m - y
    ei, m, tip = E * 0.02**4 / 12, RHO * 0.02**2 * length, SLENDER_RAM.mass.tool_mass_kg
    exact = tip_mass_cantilever_hz(ei, length, m, tip)
    rayleigh = math.sqrt(3 * ei / (length**3 * (tip + 0.2357 * m))) / (2 * math.pi)
    modes = gantry_modes(SLENDER_RAM, (0.0, y, 0.0), count=2, springs_per_segment=4, rigid=ONLY_RAM,
                         transverse="euler_bernoulli")
    assert modes.frequencies_hz[0] == pytest.approx(exact, rel=1e-3)
    assert modes.frequencies_hz[0] == pytest.approx(rayleigh, rel=1e-3)
    assert modes.frequencies_hz[1] == pytest.approx(modes.frequencies_hz[0], rel=1e-9)  # square section: a pair
    assert modes.closure_residual < 1e-12 and modes.eigen_residual < 1e-9


def test_lumped_mass_error_falls_as_one_over_n_squared():
    """The frequency error of the lumped masses against the exact root: halving the stations' spacing divides it by
    about 4 (3.0 and 4.3 measured from 1 to 4 stations; beyond 8 the sections' rotary inertia, ~(r/L)^2, takes over)."""
    y = 0.5
    length = SLENDER_RAM.ram_guide_height_m - y
    exact = tip_mass_cantilever_hz(E * 0.02**4 / 12, length, RHO * 0.02**2 * length, SLENDER_RAM.mass.tool_mass_kg)
    err = [gantry_modes(SLENDER_RAM, (0.0, y, 0.0), count=1, springs_per_segment=n, rigid=ONLY_RAM,
                        transverse="euler_bernoulli").frequencies_hz[0] / exact - 1 for n in (1, 2, 4)]
    assert 0 < err[2] < err[1] < err[0]
    assert 2.8 < err[0] / err[1] < 4.5 and 2.8 < err[1] / err[2] < 4.5


def test_mass_matrix_is_the_sum_over_bodies():
    """Pinocchio's crba against sum_i J_i^T I_i J_i over the bodies (local joint Jacobians): equal only when the
    model is built depth first (each subtree's velocities contiguous)."""
    gm = build_gantry_model(GANTRY, (0.1, 0.6, -0.2))
    model = inertial_gantry_model(gm)
    data, q = model.createData(), pin.neutral(model)
    pin.computeJointJacobians(model, data, q)
    summed = sum(pin.getJointJacobian(model, data, j, pin.LOCAL).T @ model.inertias[j].matrix()
                 @ pin.getJointJacobian(model, data, j, pin.LOCAL) for j in range(1, model.njoints))
    crba = mass_matrix(model, model.createData(), q)
    assert crba == pytest.approx(summed, abs=1e-12 * np.abs(summed).max())


def test_every_mass_is_on_the_model():
    """The model carries the members (density x area x length; the columns from their first station up, the part
    below it stands on the bed), the carriages and the tool, each once."""
    n = GANTRY.model.springs_per_segment
    f, s, a = GANTRY.frame, GANTRY.sections, GANTRY.axes
    members = (2 * s.column.area_m2 * (f.column_height_m - f.column_height_m / (2 * n)) + s.x_beam.area_m2 * f.span_m
               + s.z_beam.area_m2 * 2 * f.z_beam_half_length_m + s.ram.area_m2 * f.ram_length_m)
    expected = RHO * members + a.x.carriage_mass_kg + a.y.carriage_mass_kg + a.z.carriage_mass_kg + \
        GANTRY.mass.tool_mass_kg
    for pose in ((0.0, 0.5, 0.0), (0.25, 0.75, -0.25)):
        assert gantry_modes(GANTRY, pose, count=1).model_mass_kg == pytest.approx(expected, rel=1e-12)


def test_metrics_at_one_pose():
    """gantry_metrics over a single corner pose, recomputed: the Y drive carries the press force; the largest moment
    is the Z beam's root moment F |z| (the portal's, from the model, are smaller); the moving mass of the X axis is
    the ram, the Z beam, three carriages and the tool."""
    pose = np.array([[0.25, 0.5, -0.25]])
    m = gantry_metrics(GANTRY, pose, 700.0)
    assert m.worst_drive_force_n == pytest.approx(700.0, rel=1e-9) and m.worst_drive_axis == "y"
    eq = build_gantry_model(GANTRY, pose[0]).solve([0, 700.0, 0, 0, 0, 0])
    assert max(v.bending_moment_nm for k, v in eq.members.items() if k != "z_beam") < 700.0 * 0.25
    assert m.worst_bending_moment_nm == pytest.approx(700.0 * 0.25, rel=1e-9) and m.worst_bending_member == "z_beam"
    assert m.max_tool_displacement_m == pytest.approx(np.linalg.norm(eq.tool_displacement_m), rel=1e-12)
    assert m.max_tool_tilt_rad == pytest.approx(np.linalg.norm(eq.tool_rotation_rad), rel=1e-12)
    assert m.first_frequency_hz == pytest.approx(gantry_modes(GANTRY, pose[0], count=1).frequencies_hz[0], rel=1e-12)
    f, s, a = GANTRY.frame, GANTRY.sections, GANTRY.axes
    moving = (RHO * (s.ram.area_m2 * f.ram_length_m + s.z_beam.area_m2 * 2 * f.z_beam_half_length_m)
              + a.x.carriage_mass_kg + a.y.carriage_mass_kg + a.z.carriage_mass_kg + GANTRY.mass.tool_mass_kg)
    assert m.moving_mass_kg == pytest.approx(moving, rel=1e-12)


def test_shipped_gantry_meets_its_sizing_criterion():
    """The criterion the machine file states: at most 25 um and 0.1 mrad at the tool under 700 N over the workspace
    (its corners and centre at both heights)."""
    xs = (-0.25, 0.0, 0.25)
    poses = [(x, y, z) for x in xs for y in (0.5, 0.75) for z in xs]
    m = gantry_metrics(GANTRY, poses, 700.0)
    assert m.max_tool_displacement_m <= 25e-6 and m.max_tool_tilt_rad <= 1e-4
    assert m.worst_residual < 1e-12


@pytest.mark.parametrize(("poses", "load"), [(np.zeros((0, 3)), 700.0), ([[0.0, 0.6, 0.0]], float("nan")),
                                              ([[0.0, 0.6]], 700.0), ([[0.0, 0.6, 0.0]], np.ones((2, 5)))])
def test_metrics_refuse_bad_input(poses, load):
    with pytest.raises(PressfitError, match="must be"):
        gantry_metrics(GANTRY, poses, load)


def test_an_eigen_residual_over_its_tolerance_is_refused(monkeypatch):
    """The modes' relative eigen-residual |K_r x - w^2 M_r x| / |K_r x| is held to EIGEN_TOL (1e-8; achieved 5e-13
    at the shipped gantry's pose): with the tolerance 0.1% under what is achieved the modes are refused
    (ResidualError naming the check), 0.1% over they are returned."""
    from pressfit.dynamics import gantry_modes as gm_module
    from pressfit.errors import ResidualError

    pose = np.array([0.0, 0.6, 0.0])
    achieved = gantry_modes(GANTRY, pose).eigen_residual
    assert 0 < achieved < 1e-10
    monkeypatch.setattr(gm_module, "EIGEN_TOL", 1.001 * achieved)
    assert gantry_modes(GANTRY, pose).eigen_residual == achieved
    monkeypatch.setattr(gm_module, "EIGEN_TOL", 0.999 * achieved)
    with pytest.raises(ResidualError, match="gantry modes"):
        gantry_modes(GANTRY, pose)
