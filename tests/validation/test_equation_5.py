"""Paper equation 5 (section 4.1): the static matrix A, with A F = (X, Y, Z) for actuator forces F.

A's columns are the leg unit vectors (A = J^T). The printed A lacks A_14; the complete one has
A_14 = cos(beta_4) cos(alpha_4). The Moore-Penrose forces of equations 6-8 must reproduce the load, and
the preload vector v_p of equations 9-10 must produce no plate force (A v_p = 0).
"""

import numpy as np
import pytest
from paper_equations import equation_5

from pressfit import kinematics


@pytest.fixture(scope="module")
def poses():
    """Random poses over the required square at heights 0.45-0.8 m (|x|, |z| < p - r)."""
    rng = np.random.default_rng(5)
    return np.column_stack([rng.uniform(-0.3, 0.3, 300), rng.uniform(0.45, 0.8, 300),
                            rng.uniform(-0.3, 0.3, 300)])


def _printed(machine, poses, a14=True):
    p, r = machine.geometry.base_half_side_m, machine.geometry.plate_half_side_m
    return np.moveaxis(equation_5(*poses.T, p, r, a14=a14), -1, 0)


def test_equation_5_complete_matrix(machine, poses):
    """The printed entries plus A_14 = cos(beta_4) cos(alpha_4) = kinematics.static_matrix (1e-12,
    round-off). The omission is not harmless: A_14 = (x_h + p - r) / l_4 > 0 wherever x_h > -(p - r),
    so the printed A (A_14 = 0) would not have v_p as its null vector."""
    a = kinematics.static_matrix(machine, poses)
    np.testing.assert_allclose(_printed(machine, poses), a, rtol=0, atol=1e-12)
    assert np.all(a[:, 0, 3] > 0)
    assert np.all(np.abs(np.einsum("nj,nj->n", _printed(machine, poses, a14=False)[:, 0],
                                   kinematics.preload_vector(machine, poses))) > 1e-3)


def test_moore_penrose_forces_reproduce_the_load(machine, poses):
    """A F = W for F = A^+ W (1e-9 N on a 1 kN load: relative 1e-12, round-off), F is orthogonal to
    v_p (the minimum-norm property, 1e-9 N), and A^+ equals numpy's SVD pseudo-inverse (1e-12)."""
    rng = np.random.default_rng(7)
    w = rng.uniform(-1000.0, 1000.0, (len(poses), 3))
    f = kinematics.actuator_forces_min_norm(machine, poses, w)
    a = kinematics.static_matrix(machine, poses)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", a, f), w, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.sum(f * kinematics.preload_vector(machine, poses), -1), 0, atol=1e-9)
    np.testing.assert_allclose(kinematics.pseudo_inverse(machine, poses), np.linalg.pinv(a), rtol=0, atol=1e-12)


def test_preload_vector_is_null_vector(machine, poses):
    """A v_p = 0 (1e-14: unit vectors and a unit v_p, round-off only)."""
    a = kinematics.static_matrix(machine, poses)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", a, kinematics.preload_vector(machine, poses)), 0,
                               atol=1e-14)
