"""Paper equations 2-3 (section 3): leg-length rates dl_i/dh from the joint-angle rates.

Transcribed literally in ``paper_equations`` with two corrections: "y_i" in equation 2 is y_h, and the
beta-dot lines of equation 3 need y_h^2 in the denominator (they are the time derivative of
tan(beta_1) = (x_h / y_h) sin(alpha_1)). Compared with pressfit's closed-form Jacobian (rows = leg unit
vectors) and with central finite differences of the leg lengths; the printed y_h is shown to be wrong.
"""

import numpy as np
import pytest
from paper_equations import equation_2

from pressfit import kinematics

STEP_M = 1e-6  # finite-difference step


@pytest.fixture(scope="module")
def poses():
    """Random poses over the required square (500 mm) at heights 0.45-0.8 m (|x|, |z| < p - r)."""
    rng = np.random.default_rng(23)
    return np.column_stack([rng.uniform(-0.3, 0.3, 300), rng.uniform(0.45, 0.8, 300),
                            rng.uniform(-0.3, 0.3, 300)])


def _paper_jacobian(machine, poses, power=2):
    """dl/dh (n, 4, 3) from equations 2-3: column k is l_dot for a unit plate velocity along axis k."""
    p, r = machine.geometry.base_half_side_m, machine.geometry.plate_half_side_m
    x, y, z = poses.T
    cols = [equation_2(x, y, z, p, r, *np.eye(3)[k], beta_denominator_power=power) for k in range(3)]
    return np.stack(cols, -1).transpose(1, 0, 2)


def test_equations_2_3_match_jacobian(machine, poses):
    """Equations 2-3 (corrected) = kinematics.jacobian to 1e-12 (exact algebra, round-off only)."""
    np.testing.assert_allclose(_paper_jacobian(machine, poses), kinematics.jacobian(machine, poses),
                               rtol=0, atol=1e-12)


def test_jacobian_matches_finite_differences(machine, poses):
    """Central differences of l_i (step 1e-6 m): truncation ~ step^2 * l''' ~ 1e-12, round-off
    ~ eps * l / step ~ 1e-10; tolerance 1e-8 leaves a factor 100 for both."""
    fd = np.stack([(kinematics.inverse_kinematics(machine, poses + STEP_M * e).lengths_m
                    - kinematics.inverse_kinematics(machine, poses - STEP_M * e).lengths_m) / (2 * STEP_M)
                   for e in np.eye(3)], -1)
    np.testing.assert_allclose(kinematics.jacobian(machine, poses), fd, rtol=0, atol=1e-8)
    np.testing.assert_allclose(_paper_jacobian(machine, poses), fd, rtol=0, atol=1e-8)


def test_printed_beta_dot_denominator_is_wrong(machine, poses):
    """With the printed y_h (not y_h^2) in equation 3's beta-dot lines, dl/dh is off by far more than
    any round-off (> 1e-2 somewhere): the printed form is a misprint, not an equivalent form."""
    wrong = _paper_jacobian(machine, poses, power=1)
    assert np.max(np.abs(wrong - kinematics.jacobian(machine, poses))) > 1e-2
