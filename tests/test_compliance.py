"""Plate compliance from the Pinocchio model against independent references."""

import math

import numpy as np
import pytest

from pressfit import kinematics
from pressfit.mechanics import condensed
from pressfit.mechanics.compliance import vjm_plate_compliance


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
    # under the press load the geometric stiffness changes the compliance, by a small amount
    tan = vjm_plate_compliance(machine, pose, load=np.array([0.0, 700.0, 0.0, 0.0, 0.0, 0.0]))
    rel = np.abs(tan - lin).max() / np.abs(lin).max()
    assert 1e-6 < rel < 0.1
