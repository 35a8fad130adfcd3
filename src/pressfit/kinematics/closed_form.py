"""Closed-form kinematics of an n-UPU translational manipulator (paper equations 1-10 for its 4-UPU),
vectorised over poses.

A pose is the plate-centre position h = (x_h, y_h, z_h) in m; arrays of poses have shape (..., 3).
Leg i (of n = len(machine.legs)) runs from its base cardan B_i to its plate cardan h + d_i;
u_i = h + d_i - B_i, l_i = |u_i|. Equation 1 holds leg by leg for any layout (alpha_i about the cardan axis,
from the inward direction w_i; beta_i from the beta axis s_i), so the paper's formulas are the general
UPU inverse kinematics written for its four legs. The static matrix A (equation 5) is 3 x n; its null space,
of dimension n - 3 (the machine's redundancy), is the preload space (:func:`preload_basis`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pressfit.description.machine import Machine
from pressfit.errors import PreloadError, SingularPoseError, UnreachablePoseError, format_violation
from pressfit.spatial import cross

Y_AXIS = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True, kw_only=True)
class LegKinematics:
    """Inverse kinematics of every leg at an array of poses (shapes (..., n) and (..., n, 3))."""

    vectors_m: np.ndarray  # u_i, base cardan -> plate cardan, m
    lengths_m: np.ndarray  # l_i, m
    unit_vectors: np.ndarray  # e_i = u_i / l_i
    alpha_rad: np.ndarray  # equation 1: tan(alpha_i) = (u_i . y) / (u_i . w_i), w_i inward
    beta_rad: np.ndarray  # equation 1: sin(beta_i) = (u_i . s_i) / l_i

    def at(self, index: int | tuple[int, ...]) -> LegKinematics:
        """The legs' kinematics at one pose of the array (``index`` into the pose dimensions)."""
        return LegKinematics(**{k: v[index] for k, v in vars(self).items()})


def reference_pose_m(machine: Machine) -> np.ndarray:
    """A reachable pose (3,), m, where models are built and shapes attached: x = z = 0, leg length
    (l_min + l_max) / 2."""
    lim, g = machine.limits, machine.geometry
    lm = 0.5 * (lim.leg_length_min_m + lim.leg_length_max_m)
    rise = np.sqrt(lm**2 - (g.base_half_side_m - g.plate_half_side_m) ** 2)
    return np.array([0.0, rise + g.base_joint_height_m - g.plate_joint_height_m, 0.0])


def leg_vectors(machine: Machine, pose_m: np.ndarray, *, base_points_m: np.ndarray | None = None,
                plate_offsets_m: np.ndarray | None = None) -> np.ndarray:
    """u_i = h + d_i - B_i, shape (..., n, 3), m. ``base_points_m`` B_i and ``plate_offsets_m`` d_i ((..., n, 3),
    m, per pose): joint positions other than the machine's (its layout with other joint position errors)."""
    h = np.asarray(pose_m, dtype=float)
    b = machine.base_points_m if base_points_m is None else base_points_m
    d = machine.plate_offsets_m if plate_offsets_m is None else plate_offsets_m
    return h[..., None, :] + (d - b)


def inverse_kinematics(machine: Machine, pose_m: np.ndarray, *, base_points_m: np.ndarray | None = None,
                       plate_offsets_m: np.ndarray | None = None) -> LegKinematics:
    """Leg lengths and cardan angles (equation 1 with its atan/asin restored, docs/conventions.md); joint
    positions other than the machine's as in :func:`leg_vectors`."""
    u = leg_vectors(machine, pose_m, base_points_m=base_points_m, plate_offsets_m=plate_offsets_m)
    length = np.linalg.norm(u, axis=-1)
    alpha = np.arctan2(u[..., 1], np.einsum("...ij,ij->...i", u, machine.inward_directions))
    sin_beta = np.einsum("...ij,ij->...i", u, machine.beta_axes) / length
    return LegKinematics(vectors_m=u, lengths_m=length, unit_vectors=u / length[..., None], alpha_rad=alpha,
                         beta_rad=np.arcsin(np.clip(sin_beta, -1, 1)))


def _bound_text(value: float, bound: float) -> str:
    """The bound with 6 significant digits, or as many more as it takes to differ from the value."""
    for digits in range(6, 18):
        if f"{value:.{digits}g}" != f"{bound:.{digits}g}":
            break
    return f"{bound:.{digits}g}"


def violations(machine: Machine, pose_m: np.ndarray, ik: LegKinematics | None = None
               ) -> list[tuple[int, str, float, str]]:
    """Joint-limit violations of one pose (m) as (leg 1..n, quantity, value, broken limit), the one check
    of Table 3's limits (``ik``: the pose's inverse kinematics, if already computed). The texts are
    printed by :func:`pressfit.errors.format_violation`."""
    ik = ik or inverse_kinematics(machine, np.asarray(pose_m, dtype=float).reshape(3))
    lim = machine.limits
    checks = (("leg length l [m]", ik.lengths_m, lim.leg_length_min_m, lim.leg_length_max_m),
              ("alpha [rad]", ik.alpha_rad, lim.alpha_min_rad, lim.alpha_max_rad),
              ("beta [rad]", ik.beta_rad, lim.beta_min_rad, lim.beta_max_rad))
    if all(np.all((values >= lo) & (values <= hi)) for _, values, lo, hi in checks):
        return []
    out: list[tuple[int, str, float, str]] = []
    for name, values, lo, hi in checks:
        for i, v in enumerate(values.tolist()):
            if v < lo:
                out.append((i + 1, name, v, f"minimum {_bound_text(v, lo)}"))
            elif v > hi:
                out.append((i + 1, name, v, f"maximum {_bound_text(v, hi)}"))
    return out


def unreachable_reason(machine: Machine, pose_m: np.ndarray) -> str:
    """Why a pose (m) is unreachable, one line (every broken limit), or "" if it is reachable."""
    try:
        require_reachable(machine, pose_m)
    except UnreachablePoseError as exc:
        return "; ".join(format_violation(*v) for v in exc.violations)
    return ""


def limit_margins(machine: Machine, pose_m: np.ndarray, ik: LegKinematics | None = None) -> dict[str, np.ndarray]:
    """Distance to the nearest limit per leg, shape (..., n); negative = violated (m and rad) (``ik``: the
    poses' inverse kinematics, if already computed)."""
    ik = ik or inverse_kinematics(machine, pose_m)
    lim = machine.limits
    return {
        "leg_length_m": np.minimum(ik.lengths_m - lim.leg_length_min_m, lim.leg_length_max_m - ik.lengths_m),
        "alpha_rad": np.minimum(ik.alpha_rad - lim.alpha_min_rad, lim.alpha_max_rad - ik.alpha_rad),
        "beta_rad": np.minimum(ik.beta_rad - lim.beta_min_rad, lim.beta_max_rad - ik.beta_rad),
    }


def is_reachable(machine: Machine, pose_m: np.ndarray, ik: LegKinematics | None = None) -> np.ndarray:
    """Boolean mask (...,): every leg within Table 3's limits (and the plate above the base) (``ik``: the
    poses' inverse kinematics, if already computed)."""
    m = limit_margins(machine, pose_m, ik)
    ok = np.all((m["leg_length_m"] >= 0) & (m["alpha_rad"] >= 0) & (m["beta_rad"] >= 0), axis=-1)
    return ok & (np.asarray(pose_m)[..., 1] > 0)


def require_reachable(machine: Machine, pose_m: np.ndarray, ik: LegKinematics | None = None) -> np.ndarray:
    """Return the pose as a float array (3,) or raise :class:`UnreachablePoseError` naming leg and limit
    (``ik``: the pose's inverse kinematics, if already computed)."""
    h = np.asarray(pose_m, dtype=float).reshape(3)
    if not np.all(np.isfinite(h)):
        bad = float(next(c for c in h if not np.isfinite(c)))
        raise UnreachablePoseError(tuple(h), [(0, "pose coordinate", bad, "finite coordinates")])
    if h[1] <= 0:
        raise UnreachablePoseError(tuple(h), [(0, "y_h [m]", float(h[1]), "minimum 0 (plate above base)")])
    bad = violations(machine, h, ik)
    if bad:
        raise UnreachablePoseError(tuple(float(c) for c in h), bad)
    return h


def require_all_reachable(machine: Machine, poses_m: np.ndarray) -> np.ndarray:
    """The poses (..., 3) as floats, or the first unreachable one refused as :func:`require_reachable` refuses it
    (:class:`UnreachablePoseError` naming leg and limit)."""
    h = np.asarray(poses_m, dtype=float)
    flat = h.reshape(-1, 3)
    ok = np.all(np.isfinite(flat), axis=-1)
    ok[ok] = is_reachable(machine, flat[ok])
    if not np.all(ok):
        require_reachable(machine, flat[np.argmin(ok)])
    return h


def static_matrix(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Equation 5's A, shape (..., 3, n): columns are the leg unit vectors e_i (A = J^T).

    With N_i the leg tension (N, positive = tension), the plate is in equilibrium under an external
    force W (N) when A N = W. The printed A lacks A_14 = cos(beta_4) cos(alpha_4); this one is complete.
    """
    return np.swapaxes(inverse_kinematics(machine, pose_m).unit_vectors, -1, -2)


def jacobian(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Velocity Jacobian dl/dh (equations 2-3 in closed form), shape (..., n, 3), dimensionless."""
    return inverse_kinematics(machine, pose_m).unit_vectors


# --- shared core of equations 4-10: one pass computes A, (A A^T)^-1 and everything built on them ----
# Quantities are kept per component ("structure of arrays"): e[k] has shape (n, m) for the world axis k,
# so every step is an elementwise numpy operation on contiguous rows (this is what makes >1e6 poses/s).

_SINGULAR_DET = 1e-12  # det(A A^T) below this: A has rank < 3 (A A^T has trace n, entries O(1))
_CHUNK = 4096  # poses per block: the working set stays in the CPU cache


@dataclass(frozen=True, kw_only=True)
class Indices:
    """Equations 4-10 at an array of poses (NaN where A is singular, see ``singular``)."""

    dexterity: np.ndarray  # n = sigma_min / sigma_max of dl/dh (eq. 4), (...,)
    force_indices: np.ndarray  # (F_x, F_y, F_z) (eqs. 6-8), N per N, (..., 3)
    preload_basis: np.ndarray  # the null space of A (:func:`preload_basis`), (..., n, n - 3)
    singular: np.ndarray  # det(A A^T) < 1e-12, (...,)

    @property
    def preload_vector(self) -> np.ndarray:
        """v_p (eqs. 9-10, Table 4), (..., n): the one preload basis vector of a machine with redundancy 1."""
        if self.preload_basis.shape[-1] != 1:
            raise PreloadError(_no_single_vector(self.preload_basis.shape[-1]), redundancy=self.preload_basis.shape[-1])
        return self.preload_basis[..., 0]


@dataclass(frozen=True, kw_only=True)
class _Core:
    e: np.ndarray  # leg unit vectors = columns of A = rows of dl/dh, (3, n, m)
    det: np.ndarray  # det(A A^T), (m,)
    pinv: np.ndarray  # A^+ = A^T (A A^T)^-1 per plate-force axis j: pinv[j] = column j, (3, n, m)
    gram: tuple[np.ndarray, ...]  # A A^T as (g00, g01, g02, g11, g12, g22), each (m,)


def _core(machine: Machine, poses: np.ndarray) -> _Core:
    """A (eq. 5), G = A A^T, its cofactor inverse and A^+ for poses of shape (m, 3)."""
    u = np.ascontiguousarray(np.moveaxis(leg_vectors(machine, poses), (0, 1, 2), (2, 1, 0)))
    e = u / np.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    g00, g01, g02 = [(e[0] * e[k]).sum(0) for k in range(3)]
    g11, g12, g22 = (e[1] * e[1]).sum(0), (e[1] * e[2]).sum(0), (e[2] * e[2]).sum(0)
    c00, c01, c02 = g11 * g22 - g12 * g12, g02 * g12 - g01 * g22, g01 * g12 - g02 * g11
    c11, c12, c22 = g00 * g22 - g02 * g02, g01 * g02 - g00 * g12, g00 * g11 - g01 * g01
    det = g00 * c00 + g01 * c01 + g02 * c02
    inv_det = 1.0 / np.where(det < _SINGULAR_DET, np.nan, det)
    pinv = np.stack([e[0] * (c * inv_det) + e[1] * (d * inv_det) + e[2] * (f * inv_det)
                     for c, d, f in ((c00, c01, c02), (c01, c11, c12), (c02, c12, c22))])
    return _Core(e=e, det=det, pinv=pinv, gram=(g00, g01, g02, g11, g12, g22))


def _dexterity(gram: tuple[np.ndarray, ...]) -> np.ndarray:
    """sqrt(lambda_min / lambda_max) of the symmetric 3x3 G (closed-form trigonometric eigenvalues).

    Near a repeated eigenvalue arccos loses half the digits: n is good to about 1e-8 relative.
    """
    g00, g01, g02, g11, g12, g22 = gram
    q = (g00 + g11 + g22) / 3.0
    a, d, f = g00 - q, g11 - q, g22 - q
    p = np.sqrt((a * a + d * d + f * f + 2.0 * (g01 * g01 + g02 * g02 + g12 * g12)) / 6.0)
    det_shifted = a * (d * f - g12 * g12) - g01 * (g01 * f - g12 * g02) + g02 * (g01 * g12 - d * g02)
    safe_p = np.where(p > 0, p, 1.0)
    phi = np.arccos(np.clip(det_shifted / (2.0 * safe_p**3), -1.0, 1.0)) / 3.0
    lam_max = q + 2.0 * p * np.cos(phi)
    lam_min = q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    return np.sqrt(np.clip(lam_min, 0.0, None) / lam_max)


def _triple(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """det(x, y, z) = x . (y x z) of SoA vectors (3, ...)."""
    return (x[0] * (y[1] * z[2] - y[2] * z[1]) + x[1] * (y[2] * z[0] - y[0] * z[2])
            + x[2] * (y[0] * z[1] - y[1] * z[0]))


def _null_basis(e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The preload basis (n, n - 3, m) of A = [e_1 ... e_n] (:func:`preload_basis`) by cofactors, and
    D = det(e_1, e_2, e_3) (m,). Vector k is the generalised cross product of the columns 1, 2, 3 and 3 + k,
    (-det(e_j, e_2, e_3), -det(e_1, e_j, e_3), -det(e_1, e_2, e_j), 0 ..., D at j, 0 ...) with j = 3 + k
    (Cramer's rule for A_123 x = -e_j, times D), made unit with its component j positive. For the paper's
    4-UPU it is proportional to (-l_1, l_2, -l_3, l_4) (Table 4's v_p, v_1 < 0)."""
    n, m = e.shape[1], e.shape[2]
    e1, e2, e3 = e[:, 0], e[:, 1], e[:, 2]
    d = _triple(e1, e2, e3)
    v = np.zeros((n, n - 3, m))
    for k, j in enumerate(range(3, n)):
        ej = e[:, j]
        v[0, k], v[1, k], v[2, k] = -_triple(ej, e2, e3), -_triple(e1, ej, e3), -_triple(e1, e2, ej)
        v[j, k] = d
    with np.errstate(invalid="ignore", divide="ignore"):  # singular A: 0/0 -> NaN, flagged by the caller
        v /= np.where(d < 0, -1.0, 1.0) * np.sqrt((v * v).sum(0))
    return v, d


def _no_single_vector(redundancy: int) -> str:
    if redundancy == 0:
        return "a 3-leg machine has no redundant actuation: no internal preload"
    return (f"a {redundancy + 3}-leg machine has a {redundancy}-dimensional preload space: give {redundancy} "
            "preload amplitudes (kinematics.preload_basis), not one preload vector")


def indices(machine: Machine, pose_m: np.ndarray) -> Indices:
    """Dexterity n (eq. 4), force indices F_x, F_y, F_z (eqs. 6-8) and v_p (eqs. 9-10) in one pass.

    A (eq. 5) and (A A^T)^-1 are computed once per pose and shared; poses (..., 3) in m.
    Where A is singular, F and v_p are NaN and ``singular`` is True (no exception: maps keep going).
    """
    h = np.asarray(pose_m, dtype=float)
    flat = h.reshape(-1, 3)
    m, nl = flat.shape[0], len(machine.legs)
    n, f, sing = np.empty(m), np.empty((3, m)), np.empty(m, dtype=bool)
    v = np.empty((nl, nl - 3, m))
    for s in range(0, m, _CHUNK):
        c = _core(machine, flat[s:s + _CHUNK])
        t = slice(s, s + _CHUNK)
        basis, d123 = _null_basis(c.e)
        n[t], sing[t] = _dexterity(c.gram), c.det < _SINGULAR_DET
        if nl > 4:  # several basis vectors need legs 1-3 to span (module doc of _null_basis)
            sing[t] |= np.abs(d123) < _SINGULAR_DET
        f[:, t] = np.abs(c.pinv).max(axis=1)
        v[:, :, t] = basis
        v[:, :, t][:, :, sing[t]] = np.nan
    shape = h.shape[:-1]
    return Indices(dexterity=n.reshape(shape), force_indices=f.T.reshape(*shape, 3),
                   preload_basis=np.moveaxis(v, -1, 0).reshape(*shape, nl, nl - 3), singular=sing.reshape(shape))


def dexterity(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Equation 4: n = sigma_min / sigma_max of the Jacobian dl/dh (dimensionless, (...,))."""
    return indices(machine, pose_m).dexterity


def pseudo_inverse(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Moore-Penrose inverse A^+ = A^T (A A^T)^-1 of equation 5, shape (..., n, 3), 1/1 (N per N)."""
    h = np.asarray(pose_m, dtype=float)
    c = _core(machine, h.reshape(-1, 3))
    if np.any(c.det < _SINGULAR_DET):
        i = int(np.argmax(c.det < _SINGULAR_DET))
        raise SingularPoseError("the static matrix A is singular (legs cannot balance every force)",
                                pose_m=h.reshape(-1, 3)[i], determinant=float(c.det[i]))
    return np.moveaxis(c.pinv, (0, 1, 2), (2, 1, 0)).reshape(*h.shape[:-1], len(machine.legs), 3)


def actuator_forces_min_norm(machine: Machine, pose_m: np.ndarray, plate_force_n: np.ndarray) -> np.ndarray:
    """Minimum-norm (Moore-Penrose) leg tensions N for an external plate force W (paper eq. 5), N.

    This is the paper's rigid answer; the physical split needs compliance (see ``pressfit.statics``).
    """
    return np.einsum("...ij,...j->...i", pseudo_inverse(machine, pose_m), np.asarray(plate_force_n, float))


def force_indices(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Equations 6-8: (F_x, F_y, F_z) = max_i |F_i| per unit plate force along x, y, z, shape (..., 3).

    Raises :class:`SingularPoseError` where A is singular (use :func:`indices` for NaN instead).
    """
    out = indices(machine, pose_m)
    if np.any(out.singular):
        raise SingularPoseError("the static matrix A is singular (legs cannot balance every force)",
                                pose_m=np.asarray(pose_m, dtype=float).reshape(-1, 3)[np.argmax(out.singular)])
    return out.force_indices


def preload_basis(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """The preload space, shape (..., n, n - 3): a basis of the null space of A (equation 5), whose leg
    forces load the plate with nothing. Basis vector k (k = 1 .. n - 3) is the unit self-stress in which leg
    3 + k pulls (component > 0), the other legs beyond the third carry nothing and legs 1-3 balance it
    (cofactors, :func:`_null_basis`); so a preload amplitude a_k belongs to leg 3 + k. For the paper's 4-UPU
    the one vector is v_p (Table 4). Empty (n - 3 = 0 columns) for a 3-leg machine. NaN where A is singular
    (or, with two or more vectors, where legs 1-3 do not span space)."""
    return indices(machine, pose_m).preload_basis


def preload_vector(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """v_p (equations 9-10, Table 4): unit null vector of A, shape (..., n), for a machine with redundancy 1
    (:func:`preload_basis`'s one vector; for the paper's machine proportional to (-l_1, l_2, -l_3, l_4),
    v_1 < 0). NaN where A is singular. Raises :class:`PreloadError` for any other redundancy."""
    if machine.redundancy != 1:
        raise PreloadError(_no_single_vector(machine.redundancy), machine.name, machine.redundancy)
    return indices(machine, pose_m).preload_basis[..., 0]


def leg_frames(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """Leg frames (..., n, 3, 3), columns (e_x, e_y, e_z): e_z along the leg base -> plate,
    e_x = the base cardan axis a_i made normal to e_z, e_y = e_z x e_x (docs/conventions.md conventions)."""
    return frames_along(machine, inverse_kinematics(machine, pose_m).unit_vectors)


def frames_along(machine: Machine, ez: np.ndarray) -> np.ndarray:
    """Leg frames (..., n, 3, 3) for given unit leg directions ez (..., n, 3) (e.g. of a displaced plate):
    columns (e_x, e_y, e_z) with e_x = a_i made normal to e_z, e_y = e_z x e_x."""
    a = np.broadcast_to(machine.cardan_axes, ez.shape)
    ex = a - np.sum(a * ez, -1, keepdims=True) * ez
    ex /= np.linalg.norm(ex, axis=-1, keepdims=True)
    return np.stack([ex, cross(ez, ex), ez], -1)


def concurrency_point(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """The point where every leg line meets (on a layout with d_i = (r / p) B_i, :attr:`Machine.legs_concurrent`),
    m: P* = (t x_h, h_b + t (y_h + h_p - h_b), t z_h) with
    t = p / (p - r), h_b and h_p the base and plate joint heights (P* = t h when both are zero)."""
    g = machine.geometry
    t = g.base_half_side_m / (g.base_half_side_m - g.plate_half_side_m)
    h = np.asarray(pose_m, dtype=float)
    shift = np.array([0.0, g.plate_joint_height_m - g.base_joint_height_m, 0.0])
    return t * (h + shift) + np.array([0.0, g.base_joint_height_m, 0.0])


def pose_report(machine: Machine, pose_m: np.ndarray) -> dict[str, object]:
    """Everything the closed-form kinematics says about one pose, as JSON-ready lists (SI)."""
    h = np.asarray(pose_m, dtype=float).reshape(3)
    ik, ix = inverse_kinematics(machine, h), indices(machine, h)
    return {
        "pose_m": h.tolist(),
        "reachable": bool(is_reachable(machine, h)),
        "leg_lengths_m": ik.lengths_m.tolist(),
        "alpha_rad": ik.alpha_rad.tolist(),
        "beta_rad": ik.beta_rad.tolist(),
        "leg_unit_vectors": ik.unit_vectors.tolist(),
        "preload_basis": ix.preload_basis.tolist(),
        "preload_vector": ix.preload_basis[..., 0].tolist() if machine.redundancy == 1 else None,
        "dexterity": float(dexterity(machine, h)),
        "force_indices": force_indices(machine, h).tolist(),
        "concurrency_point_m": concurrency_point(machine, h).tolist(),
    }
