r"""Stability of a constrained equilibrium: the tangent stiffness on the loop-closure manifold.

A state q with multipliers lambda is a stable equilibrium (a strict local minimum of the energy on the
manifold c(q) = 0) when the tangent H (springs plus geometric stiffness, :func:`pressfit.mechanics.statics`)
restricted to the tangent space of the manifold, Z^T H Z with J_c Z = 0, is positive definite. Equivalently
(Chabrillac & Crouzeix 1984; Gould 1985), the KKT matrix K = [H J_c^T; J_c 0] with J_c of full row rank r
has exactly r negative eigenvalues; each further one is a direction of lost stability.

Both are computed here blockwise, as the solver factors the KKT matrix: H is block-diagonal over the n
legs and the plate, and each leg's closure rows J_i = [A_i (leg), P_i (plate)] touch only that leg.

* Inertia (Haynsworth's additivity): In(K) = sum_i In(K_i) + In(S), where K_i = [H_i A_i^T; A_i 0] is leg
  i's own KKT block (35 x 35 with 4 springs per segment) and S = H_plate - sum_i [0 P_i^T] K_i^-1 [0; P_i]
  is the 6 x 6 plate Schur complement (the machine's condensed tangent stiffness at the plate).
* Reduced stiffness: in the null-space basis Z made of (a) each leg's internal motions with the plate held
  (an orthonormal null-space basis Z_i of A_i) and (b) the six plate motions with every leg following at
  least energy, Z^T H Z is block-diagonal: diag(Z_1^T H_1 Z_1, ..., Z_n^T H_n Z_n, S). Its smallest
  eigenvalue is reported (Sylvester: its sign, and the count of negative ones, do not depend on the basis).

Units: the coordinates are scaled to be all angle-like before the eigenvalues are taken: translations
(prismatic and plate) divided by the length scale L_ref = p (m), rotations in rad; the reduced stiffness
is then in N m (energy per unit squared coordinate), comparable across all its blocks. Cost: one batched
symmetric eigen-decomposition of the n leg KKT blocks and of their reduced stiffnesses, ~0.3 ms.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

NEUTRAL_TOL = 1e-10  # eigenvalues within this fraction of the largest count as zero (round-off is ~1e-15)


@dataclass(frozen=True, kw_only=True)
class Stability:
    """Stability of an equilibrium (module doc). ``stable``: the reduced tangent stiffness is positive
    definite (no eigenvalue below -NEUTRAL_TOL times its largest) and the KKT matrix has exactly as many
    negative eigenvalues as there are constraints. A zero-stiffness direction (an open clearance) is
    neutral, not unstable."""

    stable: bool
    min_eigenvalue_nm: float  # smallest eigenvalue of the reduced tangent stiffness, N m (module doc)
    max_eigenvalue_nm: float  # largest, N m (the scale of min_eigenvalue_nm)
    kkt_negative_eigenvalues: int  # negative eigenvalues of the KKT matrix (beyond the neutral band)
    constraints: int  # rows of the closure Jacobian (6 n): the count a stable minimum has

    def to_dict(self) -> dict[str, float | int | bool]:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def _sym(a: np.ndarray) -> np.ndarray:
    return 0.5 * (a + np.swapaxes(a, -1, -2))


def reduced_stability(h_leg: np.ndarray, h_plate: np.ndarray, a: np.ndarray, p: np.ndarray, is_force: np.ndarray,
                      l_ref: float) -> Stability:
    """Stability from the tangent blocks (module doc): h_leg (L, m, m), h_plate (6, 6) (N/m, N, N m/rad
    per coordinate pair), closure Jacobian blocks a (L, 6, m) and p (L, 6, 6) (rows: m then rad),
    ``is_force`` (L, m) marking translation coordinates, ``l_ref`` the length scale (m)."""
    nl, m = h_leg.shape[:2]
    d_leg = np.where(is_force, l_ref, 1.0)
    d_plate = np.array([l_ref] * 3 + [1.0] * 3)
    rows = np.array([1.0 / l_ref] * 3 + [1.0] * 3)  # closure rows made dimensionless (inertia, S unchanged)
    hs = _sym(d_leg[:, :, None] * h_leg * d_leg[:, None, :])
    big = np.abs(hs).max((1, 2))[:, None, None]  # rows scaled to H's size: the KKT's negative eigenvalues ~ -big
    as_ = big * rows[None, :, None] * a * d_leg[:, None, :]
    ps = big * rows[None, :, None] * p * d_plate[None, None, :]
    kkt = np.zeros((nl, m + 6, m + 6))
    kkt[:, :m, :m] = hs
    kkt[:, :m, m:] = np.swapaxes(as_, 1, 2)
    kkt[:, m:, :m] = as_
    w, v = np.linalg.eigh(kkt)
    rhs = np.zeros((nl, m + 6, 6))
    rhs[:, m:] = -ps
    zz = v @ ((np.swapaxes(v, 1, 2) @ rhs) / w[:, :, None])  # leg response to unit plate motions
    schur = _sym(d_plate[:, None] * h_plate * d_plate[None, :] + (np.swapaxes(ps, 1, 2) @ zz[:, m:]).sum(0))
    ws = np.linalg.eigvalsh(schur)
    z = np.linalg.svd(as_)[2][:, 6:].swapaxes(1, 2)  # (L, m, m-6) orthonormal null-space bases of A_i
    wk = np.linalg.eigvalsh(np.swapaxes(z, 1, 2) @ hs @ z)
    reduced = np.concatenate([wk.ravel(), ws])
    top = float(np.max(np.abs(reduced)))
    neg = int((w < -NEUTRAL_TOL * np.abs(w).max(1, keepdims=True)).sum() + (ws < -NEUTRAL_TOL * top).sum())
    lo = float(reduced.min())
    return Stability(stable=bool(lo >= -NEUTRAL_TOL * top and neg == 6 * nl), min_eigenvalue_nm=lo,
                     max_eigenvalue_nm=float(reduced.max()), kkt_negative_eigenvalues=neg, constraints=6 * nl)
