"""Paper Table 2 (section 3): equation 1 for legs 2-4 follows from leg 1 by substitutions of (x_h, z_h).

Equation 1 as printed lost its inverse functions. Restored: tan(alpha_1) = y_h / (z_h + p - r),
tan(beta_1) = (x_h / y_h) sin(alpha_1) (equivalently sin(beta_1) = x_h / l_1; the beta-dot lines of
equation 3 are the derivative of this tan form), l_1 = y_h / (cos(beta_1) sin(alpha_1)).

Table 2: leg 2 = leg 1 with x_h -> z_h, z_h -> -x_h; leg 3: x_h -> -x_h, z_h -> -z_h;
leg 4: x_h -> -z_h, z_h -> x_h. Finding: for leg 4 the substitution gives beta_4 with the wrong sign.
Equation 1's own leg-4 line (beta_4 = +(z_h / y_h) sin(alpha_4)) and A_34 = sin(beta_4) in equation 5
need the positive sign; the substitution is right for alpha_4 and l_4. Asserted explicitly below.
Tolerance 1e-12 throughout: identical closed forms written differently, round-off only.
"""

import numpy as np
import pytest
from paper_equations import equation_1

from pressfit import kinematics

TOL = 1e-12


def leg1_equation_1(x, y, z, p, r):
    """Leg 1's line of equation 1: (alpha_1, beta_1, l_1) in rad, rad, m."""
    return [q[0] for q in equation_1(x, y, z, p, r)]


TABLE_2 = {  # leg -> (x, z) -> the leg-1 arguments
    2: lambda x, z: (z, -x),
    3: lambda x, z: (-x, -z),
    4: lambda x, z: (-z, x),
}


@pytest.fixture(scope="module")
def poses():
    """The required square (500 mm) at heights through the reachable range, and beyond it in x-z
    (up to 0.35 m < p - r = 0.36 m, where equation 1's atan of a quotient holds)."""
    g = np.linspace(-0.35, 0.35, 15)
    x, y, z = np.meshgrid(g, np.linspace(0.45, 0.8, 8), g, indexing="ij")
    return x.ravel(), y.ravel(), z.ravel()


def _pr(machine):
    return machine.geometry.base_half_side_m, machine.geometry.plate_half_side_m


def test_equation_1_matches_kinematics(machine, poses):
    """Equation 1 (all four legs, as printed, atan restored) = pressfit.kinematics.inverse_kinematics."""
    x, y, z = poses
    alpha, beta, l = equation_1(x, y, z, *_pr(machine))
    ik = kinematics.inverse_kinematics(machine, np.column_stack(poses))
    np.testing.assert_allclose(ik.alpha_rad, alpha.T, rtol=0, atol=TOL)
    np.testing.assert_allclose(ik.beta_rad, beta.T, rtol=0, atol=TOL)
    np.testing.assert_allclose(ik.lengths_m, l.T, rtol=0, atol=TOL)


@pytest.mark.parametrize("leg", [2, 3])
def test_table2_substitution(machine, poses, leg):
    """Legs 2 and 3: leg 1's relations under Table 2's substitution give alpha, beta and l."""
    x, y, z = poses
    xs, zs = TABLE_2[leg](x, z)
    alpha, beta, l = leg1_equation_1(xs, y, zs, *_pr(machine))
    ik = kinematics.inverse_kinematics(machine, np.column_stack(poses))
    np.testing.assert_allclose(ik.alpha_rad[:, leg - 1], alpha, rtol=0, atol=TOL)
    np.testing.assert_allclose(ik.beta_rad[:, leg - 1], beta, rtol=0, atol=TOL)
    np.testing.assert_allclose(ik.lengths_m[:, leg - 1], l, rtol=0, atol=TOL)


def test_table2_leg4_beta_sign_is_misprinted(machine, poses):
    """Leg 4: the substitution is right for alpha_4 and l_4 but gives -beta_4 (Table 2 misprint)."""
    x, y, z = poses
    xs, zs = TABLE_2[4](x, z)
    alpha, beta, l = leg1_equation_1(xs, y, zs, *_pr(machine))
    ik = kinematics.inverse_kinematics(machine, np.column_stack(poses))
    np.testing.assert_allclose(ik.alpha_rad[:, 3], alpha, rtol=0, atol=TOL)
    np.testing.assert_allclose(ik.lengths_m[:, 3], l, rtol=0, atol=TOL)
    np.testing.assert_allclose(ik.beta_rad[:, 3], -beta, rtol=0, atol=TOL)
    assert np.max(np.abs(ik.beta_rad[:, 3] - beta)) > 0.1  # not a sign convention lost in round-off
    # Equation 5's A_34 = sin(beta_4) is the z component of leg 4's unit vector: the positive sign.
    np.testing.assert_allclose(kinematics.static_matrix(machine, np.column_stack(poses))[:, 2, 3],
                               np.sin(ik.beta_rad[:, 3]), rtol=0, atol=TOL)
