"""Cardan-axis misalignment (``LegLayout.base_cardan_tilt_rad`` / ``plate_cardan_tilt_rad``): the model, the
reference solver's assembled start, the solvers that refuse it, and the Monte Carlo input."""

from pathlib import Path

import numpy as np
import pytest

from pressfit import kinematics
from pressfit.description.cases import load_case
from pressfit.description.machine import Machine
from pressfit.errors import CondensedModelError, ModelFileError, PressfitError
from pressfit.mechanics import condensed
from pressfit.mechanics.fast_statics import FastEquilibriumSolver
from pressfit.mechanics.model import build_model
from pressfit.mechanics.statics import EquilibriumSolver
from pressfit.studies import montecarlo as mc

POSE_A = np.array([0.0, 0.72, 0.0])  # x = z = 0: beta_i = 0, the cardans pass couples along the leg axes only
PRESS_N = np.array([0.0, 700.0, 0.0, 0.0, 0.0, 0.0])


def tilted(machine: Machine, leg: int, end: str, tilt_rad: np.ndarray) -> Machine:
    legs = [lg.model_dump() for lg in machine.legs]
    legs[leg][f"{end}_cardan_tilt_rad"] = [float(t) for t in tilt_rad]
    return machine.with_overrides({"legs": legs})


def leg_axis_tilt(machine: Machine, theta_rad: float) -> np.ndarray:
    """Leg 1's base-cardan tilt turning it by theta about the leg's own axis u_1 at POSE_A (a rotation vector in
    the leg reference frame R0_1)."""
    u = kinematics.inverse_kinematics(machine, POSE_A).unit_vectors[0]
    return theta_rad * build_model(machine, POSE_A).leg_frames0[0].T @ u


def torsion_stiffness_nm_per_rad(machine: Machine) -> float:
    """Series torsion stiffness of a leg at POSE_A: cylinder G J_c / L_c and stem G J_s / (l - L_c), N m/rad."""
    g, lc = machine.material.shear_modulus_pa, machine.cylinder.length_m
    ls = kinematics.inverse_kinematics(machine, POSE_A).lengths_m[0] - lc
    return 1.0 / (lc / (g * machine.cylinder_section.polar_moment_m4) + ls / (g * machine.stem_section.polar_moment_m4))


def peak_torsions_nm(eq) -> np.ndarray:
    return np.array([max(abs(s.T) for s in leg.sections.values()) for leg in eq.legs])


def test_zero_tilts_keep_the_closed_form_path_bit_identical(machine):
    """Explicit zero tilts: the cardan frames are exactly R0_i = [w_i x y_down, y_down, w_i] (module doc of
    pressfit.mechanics.model), the reference is exactly the closed form, and a solve equals the default
    machine's bit for bit."""
    zero = tilted(machine, 0, "base", np.zeros(3))
    mm = build_model(zero, POSE_A)
    down = np.array([0.0, -1.0, 0.0])
    for i, w in enumerate(machine.inward_directions):
        r0 = np.column_stack([np.cross(down, w), down, w])
        first = mm.model.joints[mm.leg_joint_ids[i]["base_cardan"]].id
        np.testing.assert_array_equal(mm.model.jointPlacements[first].rotation, r0)
        np.testing.assert_array_equal(mm.anchor_placements[i].rotation, r0)
    assert not zero.has_cardan_tilts
    np.testing.assert_array_equal(mm.pose_values(POSE_A).q0, mm.configuration_at(POSE_A))
    a, b = EquilibriumSolver(machine, pose_m=POSE_A).solve(POSE_A, PRESS_N), \
        EquilibriumSolver(zero, pose_m=POSE_A).solve(POSE_A, PRESS_N)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.multipliers, b.multipliers)


def test_tilt_about_the_cardans_own_axis_is_absorbed_without_stress(machine):
    """A tilt about a cardan's first axis a_i (x of R0_i) only shifts that revolute's angle: the rigid machine
    assembles exactly (closure to 1e-12), the plate does not turn and nothing is stressed (to round-off)."""
    for end in ("base", "plate"):
        m = tilted(machine, 1, end, [0.02, 0.0, 0.0])
        sv = EquilibriumSolver(m, pose_m=POSE_A)
        q = sv.model.assemble(POSE_A)
        assert max(sv.model.closure_error(q)) < 1e-12
        eq = sv.solve(POSE_A, np.zeros(6))
        assert eq.is_valid(1e-9)
        assert np.abs(eq.plate_rotation_rad).max() < 1e-12
        assert np.abs(eq.multipliers).max() < 1e-6  # N, N m: round-off of ~1 m positions times 5e7 N/m


def test_misaligned_machine_has_a_rotated_self_stressed_reference(machine):
    """A tilt about the vertical (y of R0_i) breaks Tsai's condition: four legs each fix one plate rotation
    and there are three, so the rigid machine cannot close (the least-squares assembly keeps an error of the
    order of the tilt); the elastic solve closes it (residuals and closure at 1e-9) with the plate turned at
    zero load by an angle of the order of the misfit."""
    theta = 0.01
    sv = EquilibriumSolver(tilted(machine, 0, "base", [0.0, theta, 0.0]), pose_m=POSE_A)
    q_ref = sv.model.pose_values(POSE_A).q0
    rigid_gap_m, rigid_gap_rad = sv.model.closure_error(q_ref)
    assert rigid_gap_rad > 0.01 * theta
    eq = sv.solve(POSE_A, np.zeros(6))
    assert eq.is_valid(1e-9)
    assert max(sv.model.closure_error(eq.q)) < 1e-9
    assert 0.1 * theta < np.linalg.norm(eq.plate_rotation_rad) < 2 * theta
    assert peak_torsions_nm(eq).max() > 0.01 * torsion_stiffness_nm_per_rad(machine) * theta


@pytest.mark.parametrize(("load", "rtol"), [(np.zeros(6), 0.02), (PRESS_N, 0.05)])
def test_leg_axis_tilt_twists_every_leg_by_a_quarter_of_the_misfit(machine, load, rtol):
    """Closed form at POSE_A (beta_i = 0: each cardan pair passes only a couple T_i along the leg axis u_i).
    Plate moments about P* (where the axial forces meet): sum T_i u_i = 0, whose only solution is
    T = t (1, -1, 1, -1) (u_1 - u_2 + u_3 - u_4 = 0). Compatibility of the plate rotation w with leg twists
    T_i / k_t plus the misfit theta on leg 1: w . u_i = T_i / k_t + theta d_i1, dotted with (1, -1, 1, -1):
    0 = 4 t / k_t + theta, so |T_i| = k_t theta / 4 in every leg. At theta = 2 mrad, unloaded: measured within
    0.65% (nonlinear terms of order theta), tolerance 2%. Under the press load the closed form leaves out the
    geometric stiffness of the leg forces (~190 N tension): measured 1.5% off, 2.9% at twice the load, so
    proportional to the load; tolerance 5%."""
    theta = 0.002
    eq = EquilibriumSolver(tilted(machine, 0, "base", leg_axis_tilt(machine, theta)), pose_m=POSE_A).solve(POSE_A, load)
    assert eq.is_valid(1e-9)
    np.testing.assert_allclose(peak_torsions_nm(eq), torsion_stiffness_nm_per_rad(machine) * theta / 4, rtol=rtol)


def test_torsion_from_a_tilt_is_linear_in_the_tilt(machine):
    """The self-stress vanishes with the misfit, linearly to first order: T(theta) / T(theta / 2) = 2 within 5%."""
    t = [peak_torsions_nm(EquilibriumSolver(tilted(machine, 0, "base", leg_axis_tilt(machine, th)), pose_m=POSE_A)
                          .solve(POSE_A, PRESS_N)).max() for th in (0.02, 0.01)]
    assert t[0] / t[1] == pytest.approx(2.0, rel=0.05)


def test_solvers_that_need_parallel_axes_refuse_a_tilted_machine(machine):
    m = tilted(machine, 2, "plate", [0.0, 0.0, 0.01])
    with pytest.raises(PressfitError, match="misaligned cardans"):
        FastEquilibriumSolver(m, pose_m=POSE_A)
    with pytest.raises(PressfitError, match="misaligned cardans"):
        EquilibriumSolver(m, pose_m=POSE_A).solve(POSE_A, PRESS_N, linear=True)
    with pytest.raises(CondensedModelError, match="misaligned cardans"):
        condensed.solve_linear(m, POSE_A[None], PRESS_N)


def test_a_tilt_beyond_the_limit_is_a_named_error(machine):
    with pytest.raises(ModelFileError, match="legs.0.base_cardan_tilt_rad"):
        tilted(machine, 0, "base", [0.0, 0.06, 0.0])


def misalignment_case(tmp_path: Path, bound: float = 0.01) -> Path:
    p = tmp_path / "misalign.toml"
    p.write_text(f"""name = "misalign"
[poses]
points_m = [{POSE_A.tolist()}]
[loads]
force_n = [0.0, 700.0, 0.0]
[envelope]
max_torsion_nm = 30.0
[montecarlo]
samples = 2
chunk_size = 2
[montecarlo.inputs.cardan_misalignment_rad]
distribution = "uniform"
low = {-bound}
high = {bound}
""")
    return p


def test_monte_carlo_misalignment_input_drives_the_peak_torsion(machine, tmp_path):
    """Through evaluate_sample: no misalignment gives no torsion; leg 1's base cardan turned about its leg axis
    by 0.004 rad gives the closed form k_t theta / 4 above (under the press load: 5%). A chunk of random draws
    runs on the reference solver."""
    plan = mc.plan_from_case(load_case(misalignment_case(tmp_path)))
    assert "reference solver (cardan misalignments)" in mc.solver_path(plan)
    assert len(plan.input_columns()) == 24 and plan.input_columns()[0] == "cardan_misalignment_rad.leg1.base.x"
    x = np.zeros(24)
    assert mc.evaluate_sample(plan, {"cardan_misalignment_rad": x}, 0.0)["max_torsion_nm"] < 1e-6
    x[:3] = leg_axis_tilt(machine, 0.004)
    row = mc.evaluate_sample(plan, {"cardan_misalignment_rad": x}, 0.0)
    assert row["max_torsion_nm"] == pytest.approx(torsion_stiffness_nm_per_rad(machine) * 0.004 / 4, rel=0.05)
    cols = mc.evaluate_chunk(plan, 0, mc.chunk_seeds(plan)[0])
    assert np.all(cols["status"] == "ok") and np.all(cols["max_torsion_nm"] > 1.0)


def test_monte_carlo_misalignment_must_stay_within_the_machine_limit(tmp_path):
    with pytest.raises(ModelFileError, match="cardan_misalignment_rad must be uniform or truncnormal"):
        load_case(misalignment_case(tmp_path, bound=0.04))
