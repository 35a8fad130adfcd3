"""Kinematics with n legs (issue 21): Tsai's 3-UPU (models/tsai_3upu.toml) reaches the required workspace, the
preload basis is the null space of the static matrix (equation 5) of dimension n - 3, and equals the paper's
v_p on the 4-UPU. References: closed forms derived here (distances in the x-z plane, the centred pose's
A A^T), the paper's v_p proportional to (-l_1, l_2, -l_3, l_4) (docs/conventions.md), an SVD null space."""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import null_space

from pressfit import kinematics
from pressfit.description.machine import load_machine
from pressfit.errors import PreloadError
from pressfit.kinematics import workspace

TSAI = Path(__file__).resolve().parents[2] / "models" / "tsai_3upu.toml"


def ring(n: int) -> list[dict]:
    """n legs at 360/n degrees about y, leg 1 at -z."""
    return [{"radial_direction": [math.cos(t), 0.0, math.sin(t)]}
            for t in (math.radians(-90.0 + 360.0 * i / n) for i in range(n))]


@pytest.fixture(scope="module")
def tsai():
    return load_machine(TSAI)


def _square_range(m) -> tuple[float, float]:
    """Heights where the whole x-z square is reachable, from the leg length limits alone: the horizontal part of
    leg i is h_xz - (p - r) n_i, so its length over the square runs from the distance of (p - r) n_i to the
    square (clip to the square) to the distance to the farthest corner; l_min <= l <= l_max bounds y_h."""
    g, lim, ws = m.geometry, m.limits, m.workspace
    half = np.array([ws.x_half_width_m, ws.z_half_width_m])
    corners = np.array([[sx, sz] for sx in (-1, 1) for sz in (-1, 1)]) * half
    lo, hi = 0.0, math.inf
    for leg in m.legs:
        c = (g.base_half_side_m - g.plate_half_side_m) * np.array(leg.radial_direction)[[0, 2]]
        near = np.linalg.norm(c - np.clip(c, -half, half))
        far = np.linalg.norm(corners - c, axis=1).max()
        lo = max(lo, math.sqrt(lim.leg_length_min_m**2 - near**2))
        hi = min(hi, math.sqrt(lim.leg_length_max_m**2 - far**2))
    return lo, hi


def test_tsai_reaches_the_required_workspace(tsai):
    """The 500 x 500 mm square is reachable over at least 100 mm of height: the corners and the centre on a grid
    of heights inside the leg-length range derived above, the alpha limit held by p - r >= 0.25 (cos 30 + sin 30)
    (the legs at +-30 degrees from x), and the bisection of the whole sampled square agrees with the closed form."""
    lo, hi = _square_range(tsai)
    assert hi - lo >= tsai.workspace.height_min_m
    g = tsai.geometry
    assert g.base_half_side_m - g.plate_half_side_m >= 0.25 * (math.cos(math.pi / 6) + math.sin(math.pi / 6))
    a, b = tsai.workspace.x_half_width_m, tsai.workspace.z_half_width_m
    xz = np.array([[a, b], [-a, b], [-a, -b], [a, -b], [0.0, 0.0]])
    for y in np.linspace(lo + 1e-6, hi - 1e-6, 9):
        poses = np.column_stack([xz[:, 0], np.full(5, y), xz[:, 1]])
        assert kinematics.is_reachable(tsai, poses).all(), y
    r = workspace.square_height_range(tsai)
    assert r.y_min_m == pytest.approx(lo, abs=1e-6) and r.y_max_m == pytest.approx(hi, abs=1e-6)


def test_tsai_indices_at_the_centred_pose(tsai):
    """At x = z = 0 every leg has sin(alpha) = y / l with l = sqrt(y^2 + (p - r)^2), and for three legs at 120
    degrees sum n_i n_i^T = 3/2 (horizontal identity), so A A^T = diag(3/2 cos^2, 3 sin^2, 3/2 cos^2): dexterity
    sqrt(min / max) (eq. 4) and F_y = 1 / (3 sin(alpha)) (eq. 7, A^+ = A^T (A A^T)^-1)."""
    y, pr = 0.6, tsai.geometry.base_half_side_m - tsai.geometry.plate_half_side_m
    s2 = y * y / (y * y + pr * pr)
    ix = kinematics.indices(tsai, [0.0, y, 0.0])
    eig = sorted([1.5 * (1 - s2), 3 * s2])
    assert float(ix.dexterity) == pytest.approx(math.sqrt(eig[0] / eig[1]), rel=1e-8)
    assert ix.force_indices[1] == pytest.approx(1 / (3 * math.sqrt(s2)), rel=1e-12)


def test_three_legs_have_no_preload_space(tsai):
    """Three legs for three forces: A is square and regular, its null space empty; a preload vector is refused."""
    assert kinematics.preload_basis(tsai, [0.0, 0.6, 0.0]).shape == (3, 0)
    with pytest.raises(PreloadError) as info:
        kinematics.preload_vector(tsai, [0.0, 0.6, 0.0])
    assert info.value.redundancy == 0 and info.value.machine == tsai.name
    assert "a 3-leg machine has no redundant actuation: no internal preload" in str(info.value)


def test_4upu_preload_basis_is_the_papers_v_p(machine):
    """On the paper's machine the general null-space basis (cofactors of columns 1, 2, 3, 4) is v_p proportional
    to (-l_1, l_2, -l_3, l_4) with v_1 < 0 (Table 4), to round-off."""
    rng = np.random.default_rng(21)
    poses = np.column_stack([rng.uniform(-0.25, 0.25, 200), rng.uniform(0.5, 0.75, 200), rng.uniform(-0.25, 0.25, 200)])
    lengths = kinematics.inverse_kinematics(machine, poses).lengths_m
    paper = lengths * [-1, 1, -1, 1]
    paper /= np.linalg.norm(paper, axis=1, keepdims=True)
    basis = kinematics.preload_basis(machine, poses)
    assert basis.shape == (200, 4, 1)
    np.testing.assert_allclose(basis[..., 0], paper, rtol=0, atol=1e-15)


def test_five_legs_have_a_two_dimensional_preload_space(machine):
    """Legs at 72 degrees: V (5 x 2) has A V = 0 and rank 2, spans the SVD null space of A (equal projectors),
    and vector k pulls leg 3 + k and leaves the other redundant leg unloaded (the basis's definition)."""
    five = machine.with_overrides({"legs": ring(5)})
    rng = np.random.default_rng(5)
    poses = np.column_stack([rng.uniform(-0.2, 0.2, 50), rng.uniform(0.55, 0.7, 50), rng.uniform(-0.2, 0.2, 50)])
    assert kinematics.is_reachable(five, poses).all()
    v = kinematics.preload_basis(five, poses)
    a = kinematics.static_matrix(five, poses)
    assert v.shape == (50, 5, 2)
    np.testing.assert_allclose(a @ v, 0.0, atol=1e-15)
    for vi, ai in zip(v, a):
        assert np.linalg.svd(vi, compute_uv=False).min() > 0.1
        z = null_space(ai)
        np.testing.assert_allclose(vi @ np.linalg.pinv(vi), z @ z.T, atol=1e-13)
    assert (v[:, 3, 0] > 0).all() and (v[:, 4, 1] > 0).all()
    np.testing.assert_array_equal(v[:, 4, 0], 0.0)
    np.testing.assert_array_equal(v[:, 3, 1], 0.0)
    with pytest.raises(PreloadError, match="2-dimensional preload space"):
        kinematics.preload_vector(five, poses)
