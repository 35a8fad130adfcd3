"""Small spatial-algebra helpers shared by every layer: the skew (cross-product) matrix, the cross
product, and the cone of load directions. SI units; vectors are world-axis 3-vectors.

Lowest layer: imports only numpy.
"""

from __future__ import annotations

import math

import numpy as np

_LEVI = np.zeros((3, 3, 3))
_LEVI[0, 1, 2] = _LEVI[1, 2, 0] = _LEVI[2, 0, 1] = 1.0
_LEVI[0, 2, 1] = _LEVI[2, 1, 0] = _LEVI[1, 0, 2] = -1.0
_SKEW = _LEVI.transpose(1, 0, 2).reshape(3, 9)  # p @ _SKEW -> skew(p) flattened: skew(p)_ik = eps_ijk p_j


def skew(p: np.ndarray) -> np.ndarray:
    """(..., 3) -> (..., 3, 3), the matrix with skew(p) x = p x x (one matmul: cheap on small batches)."""
    return (p @ _SKEW).reshape(p.shape[:-1] + (3, 3))


def cross(a: np.ndarray, b: np.ndarray, axis: int = -1) -> np.ndarray:
    """a x b along ``axis``, broadcast. Last axis (default): skew(a) @ b, a few numpy calls however many
    vectors (np.cross costs ~20 us a call). Another axis (structure-of-arrays data such as (3, 4, m)):
    component formulas on that axis, no copies of the large operands."""
    if axis == -1:
        return (skew(a) @ b[..., None])[..., 0]
    a0, a1, a2 = np.moveaxis(a, axis, 0)
    b0, b1, b2 = np.moveaxis(b, axis, 0)
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis)


def cone_directions(axis: np.ndarray, half_angle_rad: float, count: int) -> np.ndarray:
    """Unit load directions (1 + count, 3), or (1, 3) for a zero half-angle: the axis first, then
    ``count`` directions at the half-angle (rad) around it at equal azimuth steps.

    Azimuth 0 is t, the world x axis made normal to the axis (z when the axis is almost along x); the
    azimuth phi turns from t toward s = t x axis. About +y: cos(c) y + sin(c) (cos(phi) x + sin(phi) z)."""
    d = np.asarray(axis, dtype=float).reshape(3)
    d = d / np.linalg.norm(d)
    ref = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    t = ref - (ref @ d) * d
    t /= np.linalg.norm(t)
    if half_angle_rad <= 0:
        return d[None]
    s = cross(t, d)
    phi = np.linspace(0.0, 2.0 * np.pi, count, endpoint=False)[:, None]
    ring = math.cos(half_angle_rad) * d + math.sin(half_angle_rad) * (np.cos(phi) * t + np.sin(phi) * s)
    return np.concatenate([d[None], ring])
