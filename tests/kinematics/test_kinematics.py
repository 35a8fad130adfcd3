"""Unit tests of pressfit.kinematics: IK at hand-computed poses, limits, the shared index core."""

import numpy as np
import pytest

from pressfit import kinematics
from pressfit.errors import SingularPoseError, UnreachablePoseError
from pressfit.kinematics import closed_form

D = 0.442 - 0.082  # p - r from Table 3, m: horizontal distance base cardan -> plate cardan at x = z = 0


def test_ik_centre(machine):
    """h = (0, 0.6, 0): every leg is (D, 0.6) in its vertical plane: l = sqrt(D^2 + 0.36), beta = 0."""
    ik = kinematics.inverse_kinematics(machine, [0.0, 0.6, 0.0])
    np.testing.assert_allclose(ik.lengths_m, np.sqrt(D**2 + 0.36), rtol=1e-15)
    np.testing.assert_allclose(ik.alpha_rad, np.arctan2(0.6, D), rtol=1e-15)
    np.testing.assert_allclose(ik.beta_rad, 0.0, atol=1e-15)
    np.testing.assert_allclose(ik.vectors_m[0], [0.0, 0.6, D], atol=1e-15)  # leg 1 from B_1 = (0, 0, -p)


def test_ik_offset_x(machine):
    """h = (0.1, 0.6, 0): legs 2 and 4 stay in the x-y plane (horizontal runs D - 0.1 and D + 0.1,
    beta = 0); legs 1 and 3 lean by sin(beta) = +-0.1 / l (leg 3's beta axis is -x)."""
    ik = kinematics.inverse_kinematics(machine, [0.1, 0.6, 0.0])
    l13 = np.sqrt(0.01 + 0.36 + D**2)
    np.testing.assert_allclose(ik.lengths_m, [l13, np.hypot(D - 0.1, 0.6), l13, np.hypot(D + 0.1, 0.6)],
                               rtol=1e-15)
    np.testing.assert_allclose(ik.alpha_rad, [np.arctan2(0.6, D), np.arctan2(0.6, D - 0.1),
                                              np.arctan2(0.6, D), np.arctan2(0.6, D + 0.1)], rtol=1e-15)
    np.testing.assert_allclose(ik.beta_rad, [np.arcsin(0.1 / l13), 0.0, -np.arcsin(0.1 / l13), 0.0],
                               atol=1e-15)


@pytest.mark.parametrize(("pose", "expected"), [
    ((0.25, 0.45, 0.0), {(2, "leg length l [m]", "minimum 0.5")}),
    ((0.4, 0.6, 0.0), {(2, "alpha [rad]", "maximum 1.5708")}),
    ((0.7, 0.5, 0.0), {(1, "beta [rad]", "maximum 0.785398"), (2, "alpha [rad]", "maximum 1.5708"),
                       (3, "beta [rad]", "minimum -0.785398"), (4, "leg length l [m]", "maximum 1")}),
])
def test_unreachable_pose_names_leg_and_limit(machine, pose, expected):
    """Each violated limit is reported once, with its leg and bound; the message names them."""
    with pytest.raises(UnreachablePoseError) as info:
        kinematics.require_reachable(machine, pose)
    assert {(leg, what, limit) for leg, what, _, limit in info.value.violations} == expected
    for leg, what, limit in expected:
        assert f"leg {leg}: {what}" in str(info.value) and limit in str(info.value)
    assert not kinematics.is_reachable(machine, pose)


def test_plate_below_base_is_unreachable(machine):
    with pytest.raises(UnreachablePoseError, match="plate above base"):
        kinematics.require_reachable(machine, [0.0, -0.1, 0.0])


def test_is_reachable_vectorised_agrees_with_violations(machine):
    g = np.linspace(-0.45, 0.45, 13)
    poses = np.stack(np.meshgrid(g, np.linspace(0.3, 0.95, 9), g, indexing="ij"), -1).reshape(-1, 3)
    mask = kinematics.is_reachable(machine, poses)
    assert mask.shape == (len(poses),) and 0 < mask.sum() < len(poses)
    assert mask.tolist() == [not kinematics.violations(machine, h) for h in poses]


@pytest.fixture(scope="module")
def poses():
    rng = np.random.default_rng(1)
    n = 2 * closed_form._CHUNK + 17  # spans several chunks of indices()
    return np.column_stack([rng.uniform(-0.3, 0.3, n), rng.uniform(0.45, 0.8, n), rng.uniform(-0.3, 0.3, n)])


def test_indices_against_numpy(machine, poses):
    """n (eq. 4) vs numpy's SVD of dl/dh (1e-7 relative: the closed-form eigenvalues use arccos, which
    keeps about half the digits near a repeated eigenvalue); F (eqs. 6-8) vs numpy's pinv (1e-12)."""
    ix = kinematics.indices(machine, poses)
    sv = np.linalg.svd(kinematics.jacobian(machine, poses), compute_uv=False)
    np.testing.assert_allclose(ix.dexterity, sv[:, -1] / sv[:, 0], rtol=1e-7)
    pinv = np.linalg.pinv(kinematics.static_matrix(machine, poses))
    np.testing.assert_allclose(ix.force_indices, np.abs(pinv).max(axis=1), rtol=0, atol=1e-12)
    assert not ix.singular.any()


def test_public_functions_share_the_core(machine, poses):
    ix = kinematics.indices(machine, poses)
    np.testing.assert_array_equal(kinematics.dexterity(machine, poses), ix.dexterity)
    np.testing.assert_array_equal(kinematics.force_indices(machine, poses), ix.force_indices)
    np.testing.assert_array_equal(kinematics.preload_vector(machine, poses), ix.preload_vector)


def test_indices_shapes(machine, poses):
    one = kinematics.indices(machine, poses[0])
    assert one.dexterity.shape == () and one.force_indices.shape == (3,) and one.preload_vector.shape == (4,)
    grid = kinematics.indices(machine, poses[:12].reshape(3, 4, 3))
    assert grid.force_indices.shape == (3, 4, 3) and grid.preload_vector.shape == (3, 4, 4)
    np.testing.assert_array_equal(grid.dexterity.ravel(), kinematics.indices(machine, poses[:12]).dexterity)


def test_singular_pose(machine):
    """h on the base plane: every leg horizontal, A has rank 2: NaN from indices, an error otherwise."""
    ix = kinematics.indices(machine, [[0.0, 0.0, 0.0], [0.0, 0.6, 0.0]])
    assert ix.singular.tolist() == [True, False]
    assert np.isnan(ix.force_indices[0]).all() and np.isnan(ix.preload_vector[0]).all()
    assert np.isfinite(ix.force_indices[1]).all()
    with pytest.raises(SingularPoseError) as exc:
        kinematics.force_indices(machine, [[0.0, 0.6, 0.0], [0.0, 0.0, 0.0]])
    assert exc.value.pose_m == (0.0, 0.0, 0.0)  # the error names the singular pose of the batch, not the first
    with pytest.raises(SingularPoseError) as exc:
        kinematics.pseudo_inverse(machine, [[0.0, 0.6, 0.0], [0.0, 0.0, 0.0]])
    # rank 2: det(A A^T) vanishes to round-off (its trace is n = 4 for unit leg vectors)
    assert exc.value.pose_m == (0.0, 0.0, 0.0) and abs(exc.value.determinant) < 1e-12


def test_pose_report(machine):
    out = kinematics.pose_report(machine, [0.1, 0.6, 0.0])
    assert out["reachable"] is True
    assert len(out["leg_lengths_m"]) == 4 and len(out["force_indices"]) == 3
    np.testing.assert_allclose(np.sum(np.square(out["preload_vector"])), 1.0, rtol=1e-15)
