"""Plate compliance from the Pinocchio model against independent references."""

import math

import numpy as np
import pytest

from pressfit import kinematics
from pressfit.mechanics import condensed
from pressfit.mechanics.compliance import vjm_plate_compliance
from pressfit.mechanics.statics import EquilibriumSolver


def test_linear_compliance_equals_condensation(machine):
    # exact condensation (docs/conventions.md, per-leg rank-2 stiffness), an independent formulation, to 1e-9
    for pose in ([0.0, 0.72, 0.0], [0.2, 0.6, -0.15]):
        c_pin = vjm_plate_compliance(machine, pose)
        c_cond = condensed.condensed_plate_compliance(machine, np.array(pose))
        assert np.allclose(c_pin, c_cond, rtol=1e-9, atol=1e-9 * np.abs(c_cond).max())


def test_compliance_is_symmetric_positive_definite(machine):
    # Maxwell-Betti reciprocity of a conservative elastic structure
    c = vjm_plate_compliance(machine, [0.1, 0.65, 0.2])
    assert np.allclose(c, c.T, rtol=0, atol=1e-9 * np.abs(c).max())
    assert np.all(np.linalg.eigvalsh(c) > 0)


def test_vertical_compliance_at_pose_A_closed_form(machine):
    # four legs of axial stiffness k_a at angle alpha: C_yy = 1 / (4 k_a sin^2(alpha)), tan(alpha) = 2
    ik = kinematics.inverse_kinematics(machine, [0.0, 0.72, 0.0])
    k_a = 1.0 / float(machine.axial_compliance_m_per_n(ik.lengths_m[0]))
    c = vjm_plate_compliance(machine, [0.0, 0.72, 0.0])
    assert c[1, 1] == pytest.approx(1.0 / (4 * k_a * math.sin(math.atan(2.0)) ** 2), rel=1e-9)


def test_tangent_compliance_under_load_tends_to_linear_at_zero_load(machine):
    pose = [0.2, 0.6, -0.15]
    lin = vjm_plate_compliance(machine, pose)
    tan0 = vjm_plate_compliance(machine, pose, load=np.zeros(6))
    assert np.allclose(tan0, lin, rtol=1e-5, atol=1e-6 * np.abs(lin).max())


def test_tangent_compliance_under_load_equals_the_reference_solvers_difference_quotient(machine):
    """Under the press load the geometric stiffness moves the compliance by 0.19% of its largest entry here.
    Independent reference: central differences of the Pinocchio reference solver's nonlinear equilibria
    (EquilibriumSolver, not the batched fast path vjm_plate_compliance uses) with twice the step, (2 N, 0.2 N m).
    Measured: the two agree to 2.0e-9 of the largest entry (the O(step^2) curvature error of the larger step),
    and their geometric terms (tangent - linear) to 1.0e-6 of that term; asserted to 1e-8 and 5e-6."""
    pose, load = np.array([0.2, 0.6, -0.15]), np.array([0.0, 700.0, 0.0, 0.0, 0.0, 0.0])
    lin = vjm_plate_compliance(machine, pose)
    tan = vjm_plate_compliance(machine, pose, load=load)
    solver = EquilibriumSolver(machine, pose_m=pose)

    def response(w):
        eq = solver.solve(pose, w)
        return np.concatenate([eq.plate_displacement_m, eq.plate_rotation_rad])

    steps = np.diag([2.0] * 3 + [0.2] * 3)
    ref = np.column_stack([(response(load + s) - response(load - s)) / (2 * s[k]) for k, s in enumerate(steps)])
    assert np.abs(tan - ref).max() < 1e-8 * np.abs(ref).max()
    assert np.abs((tan - lin) - (ref - lin)).max() < 5e-6 * np.abs(ref - lin).max()
    assert 1e-3 < np.abs(ref - lin).max() / np.abs(lin).max() < 3e-3  # the geometric term is resolved: 1.9e-3


def test_stiffness_reports_the_compliance_the_sensors_see(machine):
    """``pressfit stiffness``'s ``sensed_vertical_compliance_m_per_n``: for the hydraulic machine the Pinocchio VJM
    C_yy of the same file with the oil 1e6 times stiffer (an independent model: the oil column is what the piston
    sensor reads past), to 1e-5, 41% below its full C_yy; for the force-kind machine its full C_yy (the drive's
    stiffness is between its sensor and the tool); the CLI prints the line only where the two differ."""
    from click.testing import CliRunner

    from pressfit.cli import main
    from pressfit.description.machine import load_machine
    from pressfit.mechanics.compliance import pose_stiffness_report
    from pressfit.shipped import models_dir

    pose = [0.0, 0.68, 0.15]
    hydraulic = load_machine(models_dir() / "pressfit_4upu_hydraulic.toml")
    stiff = hydraulic.with_overrides({"actuator": {"hydraulic": {"bulk_modulus_pa": 1.2e15}}})
    report = pose_stiffness_report(hydraulic, pose)
    sensed = report["sensed_vertical_compliance_m_per_n"]
    assert sensed == pytest.approx(vjm_plate_compliance(stiff, np.array(pose))[1, 1], rel=1e-5)
    assert sensed < 0.65 * report["compliance_6x6"][1][1]
    plain = pose_stiffness_report(machine, pose)
    assert plain["sensed_vertical_compliance_m_per_n"] == plain["compliance_6x6"][1][1]
    lines = [CliRunner().invoke(main, ["stiffness", *map(str, pose), *extra]).output
             for extra in (["--model", str(models_dir() / "pressfit_4upu_hydraulic.toml")], [])]
    assert f"vertical compliance {sensed:.4e} m/N" in lines[0]
    assert "position sensors" not in lines[1]
