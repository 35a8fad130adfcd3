"""Mechanics with n legs (issue 21): the Pinocchio statics, the condensed model, the fast solver, clearance and
buckling of Tsai's 3-UPU and of a 5-leg machine, and the 4-UPU's closed forms through the same general code.
References, derived in the tests: at the centred pose every leg carries F / (n sin(alpha)) and the vertical
stiffness is n k_a sin^2(alpha) (rigid cardans; docs/conventions.md for n = 4, the same argument for any n legs
on a circle: the force passes through P*, no couples), k_a from the sections; a cardan play g per joint adds
a lost motion 2 g / sin(alpha); a preload in force mode gives actuator forces V a at no load (its definition);
Euler loads scale as the leg compression."""

import math

import numpy as np
import pytest
from n_legs import centred

from pressfit import kinematics
from pressfit.errors import CondensedModelError, PreloadError
from pressfit.mechanics import buckling, clearance, condensed, fast_statics, preload, statics

F_N = 700.0  # the press load, +y at the plate centre


@pytest.mark.parametrize("which, y", [("tsai", 0.6), ("paper", 0.72)])
@pytest.mark.parametrize("method", ["condensed", "pinocchio linear", "fast linear", "pinocchio nonlinear"])
def test_centred_vertical_load(request, machine, which, y, method):
    """Leg tension F / (n sin(alpha)) and vertical stiffness n k_a sin^2(alpha), no plate rotation, for the
    3-UPU and (the same code, n = 4) the paper's pose A, where F / (4 sin(alpha)) = 195.66 N (Table 5). Linear
    solves to 1e-9 (exact models, round-off); the nonlinear one to 1e-4 (the plate moves ~1e-5 m on legs of
    ~0.7 m: the geometric nonlinearity is of that relative order)."""
    m = request.getfixturevalue("tsai") if which == "tsai" else machine
    n = len(m.legs)
    sa, ka = centred(m, y)
    pose, load = np.array([0.0, y, 0.0]), np.array([0.0, F_N, 0.0, 0.0, 0.0, 0.0])
    if method == "condensed":
        r = condensed.solve_linear(m, pose, load)
        forces, disp, rot = r.axial_forces_n, r.plate_displacement_m, r.plate_rotation_rad
    elif method == "fast linear":
        b = fast_statics.FastEquilibriumSolver(m, pose_m=pose).solve_batch(pose[None], load, linear=True)
        forces, disp, rot = b.actuator_forces_n[0], b.plate_displacement_m[0], b.plate_rotation_rad[0]
    else:
        eq = statics.solve_equilibrium(m, pose, load, linear=method == "pinocchio linear")
        assert eq.is_valid() and eq.stability.stable and eq.stability.constraints == 6 * n
        forces, disp, rot = eq.actuator_forces_n, eq.plate_displacement_m, eq.plate_rotation_rad
    rtol = 1e-4 if method.endswith("nonlinear") else 1e-9
    np.testing.assert_allclose(forces, F_N / (n * sa), rtol=rtol)
    assert disp[1] == pytest.approx(F_N / (n * ka * sa**2), rel=rtol)
    np.testing.assert_allclose(rot, 0.0, atol=1e-12)
    np.testing.assert_allclose(disp[[0, 2]], 0.0, atol=1e-12)
    if which == "paper":
        assert forces[0] == pytest.approx(195.66, abs=0.005)


def test_three_legs_refuse_a_preload(tsai):
    """No redundancy, no internal preload: refused with the machine's name and its redundancy; no preload is fine."""
    pose = np.array([0.0, 0.6, 0.0])
    with pytest.raises(PreloadError) as info:
        preload.rest_length_offsets(tsai, pose, 100.0)
    assert (info.value.machine, info.value.redundancy) == (tsai.name, 0)
    assert "a 3-leg machine has no redundant actuation: no internal preload" in str(info.value)
    with pytest.raises(PreloadError):
        statics.solve_equilibrium(tsai, pose, [0.0, F_N, 0.0], preload=100.0)
    np.testing.assert_array_equal(preload.rest_length_offsets(tsai, pose, 0.0), np.zeros(3))


def test_five_legs_preload_and_statics_close(five):
    """A 5-leg machine: a two-amplitude preload gives, unloaded, actuator forces V a (force mode, nonlinear
    solve; A V a = 0 so the plate does not move); under a general wrench after it the solve closes within the
    solver's tolerance (RESIDUAL_TOL) and is stable with 6 n closure rows; the fast solver agrees (1e-7 N
    relative, the two solvers' nonlinear agreement); one amplitude is refused."""
    pose, amp = np.array([0.08, 0.62, -0.05]), np.array([300.0, -150.0])
    wrench = np.array([30.0, F_N, -50.0, 5.0, 10.0, -7.0])
    v = kinematics.preload_basis(five, pose)
    unloaded = statics.solve_equilibrium(five, pose, np.zeros(6), preload=amp)
    np.testing.assert_allclose(unloaded.actuator_forces_n, v @ amp, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(unloaded.plate_displacement_m, 0.0, atol=1e-12)
    eq = statics.solve_equilibrium(five, pose, wrench, preload=amp)
    assert eq.residuals.worst() <= statics.RESIDUAL_TOL
    assert eq.stability.stable and eq.stability.constraints == 30
    added = eq.actuator_forces_n - unloaded.actuator_forces_n  # the plate's small motion turns the legs: ~1e-3
    np.testing.assert_allclose(kinematics.static_matrix(five, pose) @ added, wrench[:3], rtol=0.05)
    batch = fast_statics.FastEquilibriumSolver(five, pose_m=pose).solve_batch(pose[None], wrench, preload=amp)
    np.testing.assert_allclose(batch.actuator_forces_n[0], eq.actuator_forces_n, rtol=1e-7, atol=1e-7 * F_N)
    with pytest.raises(PreloadError, match="give 2 preload amplitudes, got 1"):
        preload.rest_length_offsets(five, pose, 300.0)


def test_three_leg_clearance_lost_motion(tsai):
    """Six cardans of play g each: under a vertical load every joint closes and the plate moves 2 g / sin(alpha)
    (two joints per leg along the leg) before the legs stretch."""
    y, g = 0.6, tsai.joints.cardan_axial_clearance_m
    sa, _ = centred(tsai, y)
    cl = clearance.Clearance.uniform(tsai)
    assert cl.gaps_m.shape == (3, 2)
    ld = clearance.load_deflection(tsai, [0.0, y, 0.0], [0.0, 1.0, 0.0], np.linspace(0.0, F_N, 8), cl)
    assert ld.lost_motion_m == pytest.approx(2 * g / sa, rel=5e-5)
    with pytest.raises(clearance.ClearanceError, match="give 6 clearances"):
        clearance.Clearance.per_joint(tsai, [g] * 8)


def test_three_leg_buckling_factors(tsai):
    """Under a downward load each leg is compressed by F / (3 sin(alpha)): its Euler factor is P_cr(l) 3 sin(alpha)
    / F; the mode's energy shares are per leg and sum to 1."""
    y = 0.6
    sa, _ = centred(tsai, y)
    res = buckling.machine_buckling(tsai, np.array([0.0, y, 0.0]), np.array([0.0, -F_N, 0.0, 0.0, 0.0, 0.0]))
    length = math.hypot(y, tsai.geometry.base_half_side_m - tsai.geometry.plate_half_side_m)
    np.testing.assert_allclose(res.leg_euler_factors, buckling.leg_critical_load_n(tsai, length) * 3 * sa / F_N,
                               rtol=1e-3)  # leg_critical_loads_n interpolates a table of P_cr(l) (log-linear)
    assert res.leg_energy_share.shape == (3,) and res.leg_energy_share.sum() == pytest.approx(1.0)
    assert 1 <= res.dominant_leg <= 3 and res.load_factor > 1.0


def test_condensed_refuses_legs_that_do_not_meet(tsai):
    """The condensed model assumes one concurrency point P*; a plate joint moved off d_i = (r/p) B_i breaks it."""
    legs = tsai.model_dump()["legs"]
    legs[1]["plate_point_error_m"] = [0.0, 0.0, 1e-3]
    off = tsai.with_overrides({"legs": legs})
    with pytest.raises(CondensedModelError, match="do not all meet at one point"):
        condensed.solve_linear(off, [0.0, 0.6, 0.0], [0.0, F_N, 0.0])
    eq = statics.solve_equilibrium(off, [0.0, 0.6, 0.0], [0.0, F_N, 0.0])  # the Pinocchio model has no such assumption
    assert eq.is_valid()
