"""Closed-form kinematics of the 4-UPU manipulator (paper equations 1-10), vectorised over poses.

A pose is the plate-centre position h = (x_h, y_h, z_h) in m; arrays of poses have shape (..., 3).
Leg i runs from its base cardan B_i to its plate cardan h + d_i; u_i = h + d_i - B_i, l_i = |u_i|.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import SingularPoseError, UnreachablePoseError
from .machine import Machine

Y_AXIS = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class LegKinematics:
    """Inverse kinematics of every leg at an array of poses (shapes (..., 4) and (..., 4, 3))."""

    vectors_m: np.ndarray  # u_i, base cardan -> plate cardan, m
    lengths_m: np.ndarray  # l_i, m
    unit_vectors: np.ndarray  # e_i = u_i / l_i
    alpha_rad: np.ndarray  # equation 1: tan(alpha_i) = (u_i . y) / (u_i . w_i), w_i inward
    beta_rad: np.ndarray  # equation 1: sin(beta_i) = (u_i . s_i) / l_i


def leg_vectors(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """u_i = h + d_i - B_i, shape (..., 4, 3), m."""
    h = np.asarray(pose_m, dtype=float)
    return h[..., None, :] + (machine.plate_offsets_m - machine.base_points_m)


def inverse_kinematics(machine: Machine, pose_m: np.ndarray) -> LegKinematics:
    """Leg lengths and cardan angles (equation 1 with its atan/asin restored, DESIGN.md)."""
    u = leg_vectors(machine, pose_m)
    length = np.linalg.norm(u, axis=-1)
    alpha = np.arctan2(u[..., 1], np.einsum("...ij,ij->...i", u, machine.inward_directions))
    sin_beta = np.einsum("...ij,ij->...i", u, machine.beta_axes) / length
    return LegKinematics(u, length, u / length[..., None], alpha, np.arcsin(np.clip(sin_beta, -1, 1)))


def violations(machine: Machine, pose_m: np.ndarray) -> list[tuple[int, str, float, str]]:
    """Joint-limit violations of one pose as (leg 1..4, quantity, value, broken limit)."""
    ik = inverse_kinematics(machine, np.asarray(pose_m, dtype=float).reshape(3))
    lim = machine.limits
    out: list[tuple[int, str, float, str]] = []
    checks = (("leg length l [m]", ik.lengths_m, lim.leg_length_min_m, lim.leg_length_max_m),
              ("alpha [rad]", ik.alpha_rad, lim.alpha_min_rad, lim.alpha_max_rad),
              ("beta [rad]", ik.beta_rad, lim.beta_min_rad, lim.beta_max_rad))
    for name, values, lo, hi in checks:
        for i, v in enumerate(values):
            if v < lo:
                out.append((i + 1, name, float(v), f"minimum {lo:.6g}"))
            elif v > hi:
                out.append((i + 1, name, float(v), f"maximum {hi:.6g}"))
    return out


def limit_margins(machine: Machine, pose_m: np.ndarray) -> dict[str, np.ndarray]:
    """Distance to the nearest limit per leg, shape (..., 4); negative = violated (m and rad)."""
    ik = inverse_kinematics(machine, pose_m)
    lim = machine.limits
    return {
        "leg_length_m": np.minimum(ik.lengths_m - lim.leg_length_min_m, lim.leg_length_max_m - ik.lengths_m),
        "alpha_rad": np.minimum(ik.alpha_rad - lim.alpha_min_rad, lim.alpha_max_rad - ik.alpha_rad),
        "beta_rad": np.minimum(ik.beta_rad - lim.beta_min_rad, lim.beta_max_rad - ik.beta_rad),
    }


def is_reachable(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Boolean mask (...,): every leg within Table 3's limits (and the plate above the base)."""
    m = limit_margins(machine, pose_m)
    ok = np.all((m["leg_length_m"] >= 0) & (m["alpha_rad"] >= 0) & (m["beta_rad"] >= 0), axis=-1)
    return ok & (np.asarray(pose_m)[..., 1] > 0)


def require_reachable(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Return the pose as a float array (3,) or raise :class:`UnreachablePoseError` naming leg and limit."""
    h = np.asarray(pose_m, dtype=float).reshape(3)
    if not np.all(np.isfinite(h)):
        raise UnreachablePoseError(tuple(h), [(0, "pose", float("nan"), "finite coordinates")])
    if h[1] <= 0:
        raise UnreachablePoseError(tuple(h), [(0, "y_h [m]", float(h[1]), "minimum 0 (plate above base)")])
    bad = violations(machine, h)
    if bad:
        raise UnreachablePoseError(tuple(float(c) for c in h), bad)
    return h


def static_matrix(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Equation 5's A, shape (..., 3, 4): columns are the leg unit vectors e_i (A = J^T).

    With N_i the leg tension (N, positive = tension), the plate is in equilibrium under an external
    force W (N) when A N = W. The printed A lacks A_14 = cos(beta_4) cos(alpha_4); this one is complete.
    """
    return np.swapaxes(inverse_kinematics(machine, pose_m).unit_vectors, -1, -2)


def jacobian(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Velocity Jacobian dl/dh (equations 2-3 in closed form), shape (..., 4, 3), dimensionless."""
    return inverse_kinematics(machine, pose_m).unit_vectors


def _det3(m: np.ndarray) -> np.ndarray:
    """Determinant of stacked 3x3 matrices, explicit (much faster than batched LAPACK)."""
    return (m[..., 0, 0] * (m[..., 1, 1] * m[..., 2, 2] - m[..., 1, 2] * m[..., 2, 1])
            - m[..., 0, 1] * (m[..., 1, 0] * m[..., 2, 2] - m[..., 1, 2] * m[..., 2, 0])
            + m[..., 0, 2] * (m[..., 1, 0] * m[..., 2, 1] - m[..., 1, 1] * m[..., 2, 0]))


def _inv_sym3(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse and determinant of stacked symmetric 3x3 matrices by cofactors."""
    a, b, c = m[..., 0, 0], m[..., 0, 1], m[..., 0, 2]
    d, e, f = m[..., 1, 1], m[..., 1, 2], m[..., 2, 2]
    c00, c01, c02 = d * f - e * e, c * e - b * f, b * e - c * d
    c11, c12, c22 = a * f - c * c, b * c - a * e, a * d - b * b
    det = a * c00 + b * c01 + c * c02
    inv = np.stack([np.stack([c00, c01, c02], -1), np.stack([c01, c11, c12], -1),
                    np.stack([c02, c12, c22], -1)], -2) / det[..., None, None]
    return inv, det


def _eig_sym3(m: np.ndarray) -> np.ndarray:
    """Eigenvalues (ascending) of stacked symmetric 3x3 matrices, closed form (trigonometric)."""
    q = np.trace(m, axis1=-2, axis2=-1) / 3.0
    off = m[..., 0, 1] ** 2 + m[..., 0, 2] ** 2 + m[..., 1, 2] ** 2
    p2 = (m[..., 0, 0] - q) ** 2 + (m[..., 1, 1] - q) ** 2 + (m[..., 2, 2] - q) ** 2 + 2 * off
    p = np.sqrt(p2 / 6.0)
    safe_p = np.where(p > 0, p, 1.0)
    bm = (m - q[..., None, None] * np.eye(3)) / safe_p[..., None, None]
    r = np.clip(_det3(bm) / 2.0, -1.0, 1.0)
    phi = np.arccos(r) / 3.0
    e_max = q + 2 * p * np.cos(phi)
    e_min = q + 2 * p * np.cos(phi + 2 * np.pi / 3)
    return np.stack([e_min, 3 * q - e_max - e_min, e_max], -1)


def dexterity(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Equation 4: n = sigma_min / sigma_max of the Jacobian dl/dh (dimensionless, (...,))."""
    a = static_matrix(machine, pose_m)
    ev = np.clip(_eig_sym3(a @ np.swapaxes(a, -1, -2)), 0.0, None)
    return np.sqrt(ev[..., 0] / ev[..., 2])


def pseudo_inverse(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Moore-Penrose inverse A^+ = A^T (A A^T)^-1 of equation 5, shape (..., 4, 3)."""
    a = static_matrix(machine, pose_m)
    inv, det = _inv_sym3(a @ np.swapaxes(a, -1, -2))
    if np.any(np.abs(det) < 1e-12):
        raise SingularPoseError("the static matrix A is singular (legs cannot balance every force)")
    return np.swapaxes(a, -1, -2) @ inv


def actuator_forces_min_norm(machine: Machine, pose_m: np.ndarray, plate_force_n: np.ndarray) -> np.ndarray:
    """Minimum-norm (Moore-Penrose) leg tensions N for an external plate force W (paper eq. 5), N.

    This is the paper's rigid answer; the physical split needs compliance (see ``pressfit.statics``).
    """
    return np.einsum("...ij,...j->...i", pseudo_inverse(machine, pose_m), np.asarray(plate_force_n, float))


def force_indices(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Equations 6-8: (F_x, F_y, F_z) = max_i |F_i| per unit plate force along x, y, z, shape (..., 3)."""
    return np.max(np.abs(pseudo_inverse(machine, pose_m)), axis=-2)


def preload_vector(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """v_p (equations 9-10, Table 4): unit null vector of A with v_1 < 0, shape (..., 4).

    Computed as the generalised cross product of A's rows (cofactors); for this machine it is
    proportional to (-l_1, l_2, -l_3, l_4).
    """
    a = static_matrix(machine, pose_m)
    v = np.stack([(-1) ** k * _det3(a[..., [j for j in range(4) if j != k]]) for k in range(4)], -1)
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(v[..., :1] > 0, -v, v)


def leg_frames(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Leg frames (..., 4, 3, 3), columns (e_x, e_y, e_z): e_z along the leg base -> plate,
    e_x = the base cardan axis a_i made normal to e_z, e_y = e_z x e_x (DESIGN.md conventions)."""
    ez = inverse_kinematics(machine, pose_m).unit_vectors
    a = np.broadcast_to(machine.cardan_axes, ez.shape)
    ex = a - np.sum(a * ez, -1, keepdims=True) * ez
    ex /= np.linalg.norm(ex, axis=-1, keepdims=True)
    return np.stack([ex, np.cross(ez, ex), ez], -1)


def concurrency_point(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """P* = h p / (p - r): the point where all four leg lines meet, m."""
    p, r = machine.geometry.base_half_side_m, machine.geometry.plate_half_side_m
    return np.asarray(pose_m, dtype=float) * p / (p - r)


def pose_report(machine: Machine, pose_m: np.ndarray) -> dict[str, object]:
    """Everything the closed-form kinematics says about one pose, as JSON-ready lists (SI)."""
    h = np.asarray(pose_m, dtype=float).reshape(3)
    ik = inverse_kinematics(machine, h)
    return {
        "pose_m": h.tolist(),
        "reachable": bool(is_reachable(machine, h)),
        "leg_lengths_m": ik.lengths_m.tolist(),
        "alpha_rad": ik.alpha_rad.tolist(),
        "beta_rad": ik.beta_rad.tolist(),
        "leg_unit_vectors": ik.unit_vectors.tolist(),
        "preload_vector": preload_vector(machine, h).tolist(),
        "dexterity": float(dexterity(machine, h)),
        "force_indices": force_indices(machine, h).tolist(),
        "concurrency_point_m": concurrency_point(machine, h).tolist(),
    }
