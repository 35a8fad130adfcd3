"""The shared spatial helpers against numpy's cross product and the cone's stated geometry."""

import math

import numpy as np
import pytest

from pressfit.errors import format_violation
from pressfit.spatial import cone_directions, cross, skew


def test_skew_and_cross_match_numpy():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(5, 4, 3)), rng.normal(size=(5, 4, 3))
    np.testing.assert_allclose(cross(a, b), np.cross(a, b), rtol=0, atol=1e-15)  # a few ulps of O(1) values
    np.testing.assert_allclose(skew(a) @ b[..., None], np.cross(a, b)[..., None], rtol=0, atol=1e-15)
    soa = cross(np.moveaxis(a, -1, 0), np.moveaxis(b, -1, 0), axis=0)  # structure of arrays: exact formula
    np.testing.assert_array_equal(np.moveaxis(soa, 0, -1), np.cross(a, b))


@pytest.mark.parametrize("axis", [[0.0, 1.0, 0.0], [1.0, 0.1, 0.0], [0.3, -0.5, 0.8]])
def test_cone_directions_are_unit_at_the_half_angle_and_evenly_spaced(axis):
    d = np.asarray(axis) / np.linalg.norm(axis)
    dirs = cone_directions(np.asarray(axis), 0.1, 6)
    assert dirs.shape == (7, 3) and np.allclose(dirs[0], d)
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=1e-15)
    np.testing.assert_allclose(np.arccos(np.clip(dirs[1:] @ d, -1, 1)), 0.1, atol=1e-7)
    ring = dirs[1:] - np.cos(0.1) * d  # the ring's radial parts: consecutive ones 60 degrees apart
    cosines = np.einsum("ij,ij->i", ring, np.roll(ring, -1, 0)) / np.sin(0.1) ** 2
    np.testing.assert_allclose(cosines, 0.5, atol=1e-12)


def test_cone_about_y_starts_at_x_and_turns_toward_z():
    """The convention the load envelope documents: cos(c) y + sin(c) (cos(phi) x + sin(phi) z)."""
    c = math.radians(10)
    dirs = cone_directions(np.array([0.0, 2.0, 0.0]), c, 4)
    expected = [[0, 1, 0]] + [[math.sin(c) * math.cos(p), math.cos(c), math.sin(c) * math.sin(p)]
                              for p in (0, math.pi / 2, math.pi, 3 * math.pi / 2)]
    np.testing.assert_allclose(dirs, expected, atol=1e-15)
    assert cone_directions(np.array([0.0, 1.0, 0.0]), 0.0, 8).shape == (1, 3)


def test_a_value_just_past_a_limit_never_prints_as_the_limit():
    """1.5708 rounds both pi/2 and pi/2 + 1e-9: the printed value must still break the printed bound."""
    text = format_violation(2, "alpha [rad]", math.pi / 2 + 1e-9, "maximum 1.5707963268")
    value = float(text.split(" = ")[1].split()[0])
    assert value > 1.5707963268 and text.startswith("leg 2: alpha [rad] = ")
