r"""Exact condensed linear-elastic statics of the n-UPU plate, batched over poses (the fast path).

Model: rigid, clearance-free cardans (free about their two axes), linear elastic legs, small
displacements. A pose is the plate-centre position h (m), arrays of poses have shape (..., 3). Loads
are a wrench at the plate centre in world axes, ordered (F_x, F_y, F_z, M_x, M_y, M_z) in N and N m;
displacements are ordered (translation of the plate centre in m, small rotation vector in rad).

What a leg transmits
--------------------
Leg i has a base cardan with first axis a_i (fixed in the base) and second axis b_i normal to a_i and
to the leg, and a plate cardan with the same two axes (Tsai's condition). A cardan transmits a force
and only the couple normal to both of its axes, i.e. along

.. math:: c_i = \frac{e_i - s_i a_i}{\cos\beta_i}, \qquad s_i = \sin\beta_i = e_i \cdot a_i,

the unit vector in the plane of a_i and the leg direction e_i, normal to a_i (sign chosen so that
c_i . e_i = cos(beta_i) > 0; c_i = +-a_i x b_i). The leg carries no load of its own, so the couples at
its two ends are equal and opposite (their e_i components must cancel, and c_i . e_i != 0), hence
u_i x F = 0: the end force is axial (N_i, positive = tension) and there is **no shear**; the moment
C_i c_i is **constant along the leg**.

Why k_r = 1 / (cos^2(beta) c_T + sin^2(beta) c_M)
-------------------------------------------------
In the leg frame (e_z = e_i, e_x = a_i made normal to e_z, e_y = e_z x e_x) one finds
c_i = -sin(beta_i) e_x + cos(beta_i) e_z: the couple C_i c_i is a torsion T = C_i cos(beta_i) plus a
bending moment M_x = -C_i sin(beta_i) (M_y = 0). With constant moments the strain energy of the leg
(cylinder of length L_cyl, stem of length L_stem = l - L_cyl) is

.. math:: U = \tfrac12 C^2 \left[\cos^2\beta\, c_T + \sin^2\beta\, c_M\right], \quad
          c_T = \frac{L_{cyl}}{G J_{cyl}} + \frac{L_{stem}}{G J_{stem}}, \quad
          c_M = \frac{L_{cyl}}{E I_{cyl}} + \frac{L_{stem}}{E I_{stem}},

so by Castigliano the rotation of the plate end relative to the base end along c_i is
dU/dC = C (cos^2 c_T + sin^2 c_M). The other two relative rotations (about a_i, b_i) and the lateral
end deflections are taken up freely by the cardans, so the only elastic couple constraint is
C_i = k_r (c_i . phi). Check: at beta = 0 the couple is pure torsion (k_r = 1/c_T); a leg lying along
a_i would take it in pure bending (k_r = 1/c_M). The axial spring is k_a = 1 / c_axial(l) (actuator,
cylinder and stem in series, :meth:`pressfit.machine.Machine.axial_compliance_m_per_n`).

The plate stiffness
-------------------
With w1_i = (e_i, r x e_i) (the leg's Plücker line, r a point of the line, moments about the reference
point) and w2_i = (0, c_i), leg i adds k_a w1 w1^T + k_r w2 w2^T to the plate's 6x6 stiffness. On the
homothetic layouts d_i = (r / p) B_i (any number and placement of legs, :attr:`Machine.legs_concurrent`) all
leg lines meet at P* = h p / (p - r) (:func:`pressfit.kinematics.concurrency_point`); about P* the
stiffness is block diagonal, K_t = sum k_a e e^T (translation) and K_r = sum k_r c c^T (rotation),
so every solve is two closed-form 3x3 inverses. A layout without one concurrency point is refused
(:class:`CondensedModelError`). With rho = h - P*, a wrench (F, M) at h gives

    delta_P = K_t^-1 F,  phi = K_r^-1 (M + rho x F),  delta_h = delta_P - rho x phi,
    N_i = k_a e_i . delta_P,  C_i = k_r c_i . phi.

A load whose line passes through P* (a vertical force at h only when x_h = z_h = 0) is carried by the
axial forces alone; any moment about P* only by the couples. Clearance is ignored here (the default
model's clearance matters only to :mod:`pressfit.mechanics.clearance`); elastic cardans break the rank-2
structure and are refused. The Pinocchio solver (:mod:`pressfit.mechanics.statics`) is the reference for
everything beyond this model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pressfit.description.machine import Machine
from pressfit.errors import CondensedModelError, PressfitError, ResidualError, SingularPoseError
from pressfit.kinematics import concurrency_point, is_reachable, leg_vectors
from pressfit.kinematics.workspace import workspace_square
from pressfit.spatial import cross, skew

PRESS_LOAD_N = 700.0  # the press reaction on the tool, +y (paper section 4)
# Relative plate-equilibrium residual a solve is held to (CondensedResult.relative_residual): the closed form
# reaches 2.5e-15 over the 168,480 reachable poses of an 81 x 71 x 81 grid of the default machine under four
# wrenches; the residual grows as round-off times the condition of the 3x3 blocks, so 1e-13 leaves a design
# variant 40 times that and refuses one that has lost three more digits
CONDENSED_RESIDUAL_TOL = 1e-13
_CHUNK = 16384  # poses per vectorised block: the working set stays in the CPU cache


def rotational_compliances(machine: Machine, leg_length_m: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """(c_T, c_M): torsional and bending compliance of a leg of length l under a constant moment,
    cylinder and stem in series, rad/(N m)."""
    g, e, lc = machine.material.shear_modulus_pa, machine.material.youngs_modulus_pa, machine.cylinder.length_m
    cyl, stem = machine.cylinder_section, machine.stem_section
    ls = np.asarray(leg_length_m, dtype=float) - lc
    c_t = lc / (g * cyl.polar_moment_m4) + ls / (g * stem.polar_moment_m4)
    c_m = lc / (e * cyl.second_moment_m4) + ls / (e * stem.second_moment_m4)
    return c_t, c_m


# --- the per-pose core, "structure of arrays": a vector is (3, m), a per-leg vector (3, n, m), a ----
# symmetric 3x3 matrix the tuple (s00, s01, s02, s11, s12, s22) of (m,) arrays.
Sym = tuple[np.ndarray, ...]


def _sym_outer(k: np.ndarray, v: np.ndarray) -> Sym:
    """sum_i k_i v_i v_i^T over the legs."""
    kv = k * v
    return tuple((kv[i] * v[j]).sum(0) for i, j in ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)))


def _sym_inv(s: Sym) -> tuple[Sym, np.ndarray]:
    """Inverse and determinant by cofactors."""
    a, b, c, d, e, f = s
    c00, c01, c02 = d * f - e * e, c * e - b * f, b * e - c * d
    c11, c12, c22 = a * f - c * c, b * c - a * e, a * d - b * b
    det = a * c00 + b * c01 + c * c02
    inv = 1.0 / det
    return (c00 * inv, c01 * inv, c02 * inv, c11 * inv, c12 * inv, c22 * inv), det


def _sym_mv(s: Sym, x: np.ndarray) -> np.ndarray:
    a, b, c, d, e, f = s
    return np.stack([a * x[0] + b * x[1] + c * x[2], b * x[0] + d * x[1] + e * x[2], c * x[0] + e * x[1] + f * x[2]])


def _sym_full(s: Sym) -> np.ndarray:
    """(m, 3, 3) from the tuple."""
    a, b, c, d, e, f = s
    return np.stack([a, b, c, b, d, e, c, e, f], -1).reshape(-1, 3, 3)


@dataclass(frozen=True, kw_only=True)
class _Core:
    e: np.ndarray  # (3, n, m) leg unit vectors, base -> plate
    sin_beta: np.ndarray  # (n, m) e_i . a_i
    c: np.ndarray  # (3, n, m) couple directions
    k_a: np.ndarray  # (n, m) axial stiffness, N/m
    k_r: np.ndarray  # (n, m) couple stiffness along c, N m/rad
    rho: np.ndarray  # (3, m) h - P*, m
    kt: Sym  # translational stiffness about P*, N/m
    kr: Sym  # rotational stiffness about P*, N m/rad
    ct: Sym  # K_t^-1, m/N
    cr: Sym  # K_r^-1, rad/(N m)


def _core(machine: Machine, h: np.ndarray) -> _Core:
    """Condensed springs and the two 3x3 blocks for poses h of shape (m, 3)."""
    if not machine.legs_concurrent:
        raise CondensedModelError(machine.name, "concurrent legs", "the leg lines do not all meet at one point "
                                  "(joint position errors d_i != (r/p) B_i)")
    if machine.has_cardan_tilts:
        raise CondensedModelError(machine.name, "parallel cardan axes", "misaligned cardans "
                                  "(base/plate_cardan_tilt_rad)")
    u = np.ascontiguousarray(np.moveaxis(leg_vectors(machine, h), (0, 1, 2), (2, 1, 0)))
    length = np.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    e = u / length
    a = machine.cardan_axes.T[:, :, None]
    s = e[0] * a[0] + e[1] * a[1] + e[2] * a[2]
    cos2 = 1.0 - s * s
    with np.errstate(divide="ignore", invalid="ignore"):  # a singular pose is refused just below, by name
        c = (e - s * a) / np.sqrt(cos2)
        c_t, c_m = rotational_compliances(machine, length)
        k_a = 1.0 / machine.axial_compliance_m_per_n(length)
        k_r = 1.0 / (cos2 * c_t + s * s * c_m)
        kt, kr = _sym_outer(k_a, e), _sym_outer(k_r, c)
        (ct, det_t), (cr, det_r) = _sym_inv(kt), _sym_inv(kr)
    # a block is singular when its determinant vanishes against the cube of its largest spring
    bad = ~((det_t > 1e-12 * k_a.max(0) ** 3) & (det_r > 1e-12 * k_r.max(0) ** 3))
    if np.any(bad):
        raise SingularPoseError(f"the condensed plate stiffness is singular at {int(bad.sum())} pose(s), "
                                f"e.g. h = {h[np.argmax(bad)].tolist()} m", pose_m=h[np.argmax(bad)])
    rho = np.ascontiguousarray((h - concurrency_point(machine, h)).T)
    return _Core(e=e, sin_beta=s, c=c, k_a=k_a, k_r=k_r, rho=rho, kt=kt, kr=kr, ct=ct, cr=cr)


def _poses(machine: Machine, poses_m: np.ndarray) -> np.ndarray:
    if machine.joints.cardan_rotational_stiffness_nm_per_rad is not None:
        raise CondensedModelError(machine.name, "free cardans", "the cardans have a rotational stiffness "
                                  "(joints.cardan_rotational_stiffness_nm_per_rad)")
    h = np.asarray(poses_m, dtype=float)
    if h.shape[-1:] != (3,) or not np.all(np.isfinite(h)):
        raise PressfitError(f"poses must be finite with shape (..., 3), got shape {h.shape}")
    return h


def _blocks(tl: np.ndarray, tr: np.ndarray, bl: np.ndarray, br: np.ndarray) -> np.ndarray:
    return np.concatenate([np.concatenate([tl, tr], -1), np.concatenate([bl, br], -1)], -2)


def _six_by_six(machine: Machine, poses_m: np.ndarray, about: str, compliance: bool) -> np.ndarray:
    if about not in ("centre", "concurrency"):
        raise PressfitError(f"about must be 'centre' or 'concurrency', got {about!r}")
    h = _poses(machine, poses_m)
    core = _core(machine, h.reshape(-1, 3))
    t, r = (core.ct, core.cr) if compliance else (core.kt, core.kr)
    t, r = _sym_full(t), _sym_full(r)
    if about == "concurrency":
        z = np.zeros_like(t)
        return _blocks(t, z, z, r).reshape(h.shape[:-1] + (6, 6))
    x = skew(core.rho.T)  # x_P = S x_h with S = [[I, [rho]], [0, I]]
    if compliance:  # C_h = S^-1 C_P S^-T
        x_r = x @ r
        out = _blocks(t - x_r @ x, -x_r, r @ x, r)
    else:  # K_h = S^T K_P S
        t_x = t @ x
        out = _blocks(t, t_x, -x @ t, r - x @ t_x)
    return out.reshape(h.shape[:-1] + (6, 6))


def plate_stiffness(machine: Machine, poses_m: np.ndarray, about: str = "centre") -> np.ndarray:
    """The plate's 6x6 stiffness (..., 6, 6), world axes, order (translation, rotation).

    ``about="centre"``: wrench and translation at the plate centre h; ``about="concurrency"``: at P*,
    where it is block diagonal (K_t in N/m, K_r in N m/rad). Units: N/m, N/rad, N m/rad.
    """
    return _six_by_six(machine, poses_m, about, compliance=False)


def condensed_plate_compliance(machine: Machine, poses_m: np.ndarray, about: str = "centre") -> np.ndarray:
    """The inverse of :func:`plate_stiffness`, (..., 6, 6): m/N, rad/N, rad/(N m); closed form. Of
    ``machine.sensed_view``: the compliance a position loop closed on the drives' sensors leaves (a hydraulic
    cylinder's oil column, which its piston sensor reads past, rigid)."""
    return _six_by_six(machine, poses_m, about, compliance=True)


# --- the linear solve ----------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class CondensedResult:
    """Linear elastic equilibrium at an array of poses (leading shape ``...``), SI units.

    Section resultants are the wrench that the plate-side part of a leg exerts on the base-side part,
    in the leg frame of :func:`pressfit.kinematics.leg_frames`. In this model they are the same at every
    section (base cardan, actuator, plate cardan): shear is zero and the moment is constant.
    """

    pose_m: np.ndarray  # (..., 3)
    plate_wrench: np.ndarray  # (..., 6) applied (F [N], M [N m]) at the plate centre
    plate_displacement_m: np.ndarray  # (..., 3) plate-centre translation
    plate_rotation_rad: np.ndarray  # (..., 3) plate small-rotation vector
    axial_forces_n: np.ndarray  # (..., n) N_i, positive = tension; the actuator carries the same force
    couples_nm: np.ndarray  # (..., n) C_i: the section moment is C_i c_i
    couple_directions: np.ndarray  # (..., n, 3) unit c_i (normal to a_i, c_i . e_i = cos(beta_i) > 0)
    leg_unit_vectors: np.ndarray  # (..., n, 3) e_i, base -> plate
    leg_moments_nm: np.ndarray  # (..., n, 3) (M_x, M_y, T) in the leg frame
    force_residual_n: np.ndarray  # (..., 3) applied force + sum of the legs' forces on the plate
    moment_residual_nm: np.ndarray  # (..., 3) same for moments about the plate centre
    plate_offsets_m: np.ndarray  # (n, 3) plate cardan centres relative to the plate centre, d_i

    @property
    def actuator_forces_n(self) -> np.ndarray:
        """Actuator forces (..., n), N, positive = tension (each actuator is in series with its leg)."""
        return self.axial_forces_n

    @property
    def couple_vectors_nm(self) -> np.ndarray:
        """Section moments in world axes (..., n, 3), N m."""
        return self.couples_nm[..., None] * self.couple_directions

    @property
    def bending_nm(self) -> np.ndarray:
        """Bending moment magnitude hypot(M_x, M_y), (..., n), N m."""
        return np.hypot(self.leg_moments_nm[..., 0], self.leg_moments_nm[..., 1])

    @property
    def tilt_rad(self) -> np.ndarray:
        """Plate tilt |rotation|, (...,), rad."""
        return np.linalg.norm(self.plate_rotation_rad, axis=-1)

    def relative_residual(self) -> np.ndarray:
        """Per pose: max(|force residual|, |moment residual| / 1 m) / (|F| + |M| / 1 m), (or / 1 N for a
        zero load); about 1e-16 for a sound solve."""
        w = self.plate_wrench
        scale = np.linalg.norm(w[..., :3], axis=-1) + np.linalg.norm(w[..., 3:], axis=-1)
        return np.maximum(np.linalg.norm(self.force_residual_n, axis=-1),
                          np.linalg.norm(self.moment_residual_nm, axis=-1)) / np.where(scale > 0, scale, 1.0)


def _as_wrench(w: np.ndarray) -> np.ndarray:
    w = np.asarray(w, dtype=float)
    if w.shape[-1:] == (3,):
        w = np.concatenate([w, np.zeros_like(w)], -1)
    if w.shape[-1:] != (6,) or not np.all(np.isfinite(w)):
        raise PressfitError(f"a plate wrench must be finite with shape (..., 6) (or a force (..., 3)), "
                            f"got shape {w.shape}")
    return w


def _solve_core(machine: Machine, core: _Core, w: np.ndarray) -> tuple[np.ndarray, ...]:
    """Solve with w of shape (6, m) or (6, 1); returns SoA arrays (see :func:`solve_linear`)."""
    f, m = w[:3], w[3:]
    d_p = _sym_mv(core.ct, f)
    phi = _sym_mv(core.cr, m + cross(core.rho, f, axis=0))
    delta = d_p - cross(core.rho, phi, axis=0)
    e, c = core.e, core.c
    n = core.k_a * (e[0] * d_p[0] + e[1] * d_p[1] + e[2] * d_p[2])
    cpl = core.k_r * (c[0] * phi[0] + c[1] * phi[1] + c[2] * phi[2])
    # leg frame: c = -sin(beta) e_x + cos(beta) e_z (module docstring)
    moments = np.stack([-cpl * core.sin_beta, np.zeros_like(cpl), cpl * np.sqrt(1.0 - core.sin_beta**2)])
    # plate equilibrium about h: leg i pulls the plate with -N_i e_i at h + d_i and a couple -C_i c_i
    leg_f = n * e
    d = machine.plate_offsets_m.T[:, :, None]
    res_f = f - leg_f.sum(1)
    res_m = m - (cross(d, leg_f, axis=0) + cpl * c).sum(1)
    return delta, phi, n, cpl, c, e, moments, res_f, res_m


def solve_linear(machine: Machine, poses_m: np.ndarray, plate_wrench: np.ndarray) -> CondensedResult:
    """Small-displacement equilibrium under a wrench at the plate centre, batched over poses.

    Args:
        machine: the machine (cardans must be free: no rotational stiffness; clearance is ignored).
        poses_m: plate-centre positions h, (..., 3), m.
        plate_wrench: (F, M) at the plate centre in world axes, (..., 6) or (6,), N and N m; a force
            (..., 3) means zero moment. Broadcast against the poses.

    Geometrically linear (the docs/conventions.md default, nonlinear, solve is :mod:`pressfit.mechanics.statics`). Poses
    are processed in cache-sized blocks; no Python loop runs over single poses. Raises ResidualError when a
    pose's relative plate-equilibrium residual exceeds CONDENSED_RESIDUAL_TOL.
    """
    h, w = _poses(machine, poses_m), _as_wrench(plate_wrench)
    shape = np.broadcast_shapes(h.shape[:-1], w.shape[:-1])
    hf = np.broadcast_to(h, shape + (3,)).reshape(-1, 3)
    wf = None if w.ndim == 1 else np.broadcast_to(w, shape + (6,)).reshape(-1, 6)
    m, nl = hf.shape[0], len(machine.legs)
    # outputs in their final (pose, ...) layout: delta, phi, N, C, c, e, leg moments, residuals
    out = [np.empty((m,) + t) for t in ((3,), (3,), (nl,), (nl,), (nl, 3), (nl, 3), (nl, 3), (3,), (3,))]
    for i in range(0, m, _CHUNK):
        wc = w[:, None] if wf is None else np.ascontiguousarray(wf[i:i + _CHUNK].T)
        for o, x in zip(out, _solve_core(machine, _core(machine, hf[i:i + _CHUNK]), wc), strict=True):
            o[i:i + _CHUNK] = x.T  # (3, m) -> (m, 3); (n, m) -> (m, n); (3, n, m) -> (m, n, 3)
    delta, phi, n, cpl, c, e, moments, res_f, res_m = (x.reshape(shape + x.shape[1:]) for x in out)
    result = CondensedResult(pose_m=np.broadcast_to(h, shape + (3,)), plate_wrench=np.broadcast_to(w, shape + (6,)),
                             plate_displacement_m=delta, plate_rotation_rad=phi, axial_forces_n=n, couples_nm=cpl,
                             couple_directions=c, leg_unit_vectors=e, leg_moments_nm=moments, force_residual_n=res_f,
                             moment_residual_nm=res_m, plate_offsets_m=machine.plate_offsets_m)
    relative = result.relative_residual().reshape(-1)
    bad = ~(relative <= CONDENSED_RESIDUAL_TOL)
    if bad.any():
        i = int(np.argmax(bad))
        raise ResidualError("condensed linear equilibrium", "plate equilibrium (relative)", float(relative[i]),
                            CONDENSED_RESIDUAL_TOL, f"at pose {tuple(result.pose_m.reshape(-1, 3)[i].tolist())} m "
                            f"under the load {tuple(result.plate_wrench.reshape(-1, 6)[i].tolist())} (N, N m)")
    return result


@dataclass(frozen=True, kw_only=True)
class StiffnessMaps:
    """Maps over the x-z square at height y; arrays are indexed [i_z, i_x], SI units.

    Stiffnesses are for a force at the plate centre with the plate free to tilt (inverse compliance):
    vertical = 1 / C_yy; lateral_x = 1 / C_xx, lateral_z = 1 / C_zz; lateral = the stiffness along the
    weakest horizontal direction, 1 / (largest eigenvalue of the 2x2 horizontal block of the compliance).
    Tilt, drift (horizontal displacement magnitude) and deflection come from the press load (+y at the
    plate centre).
    """

    x_m: np.ndarray
    z_m: np.ndarray
    y_m: float
    press_load_n: float
    reachable: np.ndarray
    vertical_n_per_m: np.ndarray
    lateral_n_per_m: np.ndarray
    lateral_x_n_per_m: np.ndarray
    lateral_z_n_per_m: np.ndarray
    tilt_rad: np.ndarray
    drift_m: np.ndarray

    @property
    def lateral_to_vertical(self) -> np.ndarray:
        """lateral / vertical stiffness (dimensionless)."""
        return self.lateral_n_per_m / self.vertical_n_per_m

    def fields(self) -> dict[str, tuple[np.ndarray, str]]:
        """Every map: CSV column / panel title -> (values, unit)."""
        return {"vertical_stiffness_n_per_m": (self.vertical_n_per_m, "N/m"),
                "lateral_stiffness_n_per_m": (self.lateral_n_per_m, "N/m, weakest horizontal direction"),
                "lateral_x_stiffness_n_per_m": (self.lateral_x_n_per_m, "N/m"),
                "lateral_z_stiffness_n_per_m": (self.lateral_z_n_per_m, "N/m"),
                "lateral_to_vertical": (self.lateral_to_vertical, "-"),
                "tilt_rad": (self.tilt_rad, f"rad, under {self.press_load_n:g} N"),
                "drift_m": (self.drift_m, f"m, under {self.press_load_n:g} N")}


def stiffness_maps(machine: Machine, y_m: float, n: int = 51, press_load_n: float = PRESS_LOAD_N) -> StiffnessMaps:
    """Stiffness, tilt and drift maps over the required workspace square at height y_m (n x n grid).

    Poses outside the joint limits are NaN (``reachable`` is False there).
    """
    x, z = workspace_square(machine, n)
    zz, xx = np.meshgrid(z, x, indexing="ij")
    h = np.stack([xx, np.full_like(xx, y_m), zz], -1)
    ok = is_reachable(machine, h)
    comp = condensed_plate_compliance(machine, h)
    res = solve_linear(machine, h, np.array([0.0, press_load_n, 0.0]))
    hor = comp[..., [0, 2]][..., [0, 2], :]
    tr, det = hor[..., 0, 0] + hor[..., 1, 1], hor[..., 0, 0] * hor[..., 1, 1] - hor[..., 0, 1] ** 2
    lam_max = tr / 2 + np.sqrt(np.maximum(tr**2 / 4 - det, 0.0))

    def masked(v: np.ndarray) -> np.ndarray:
        return np.where(ok, v, np.nan)

    return StiffnessMaps(x_m=x, z_m=z, y_m=float(y_m), press_load_n=float(press_load_n), reachable=ok,
                         vertical_n_per_m=masked(1 / comp[..., 1, 1]), lateral_n_per_m=masked(1 / lam_max),
                         lateral_x_n_per_m=masked(1 / comp[..., 0, 0]), lateral_z_n_per_m=masked(1 / comp[..., 2, 2]),
                         tilt_rad=masked(res.tilt_rad),
                         drift_m=masked(np.hypot(res.plate_displacement_m[..., 0], res.plate_displacement_m[..., 2])))


def stiffness_report(machine: Machine, pose_m: np.ndarray, press_load_n: float = PRESS_LOAD_N) -> dict[str, object]:
    """Stiffness of one pose as JSON-ready lists (SI): the 6x6 compliance at the plate centre, the 3x3
    translational stiffness there with the plate free to tilt (inverse of the compliance's translational
    block) and about P* (rotation-free, K_t), the scalar stiffnesses of :class:`StiffnessMaps`, and the
    response to the press load (+y at the plate centre)."""
    h = np.asarray(pose_m, dtype=float).reshape(3)
    comp = condensed_plate_compliance(machine, h)
    maps_like = np.linalg.eigvalsh(comp[[0, 2]][:, [0, 2]])
    res = solve_linear(machine, h, [0.0, press_load_n, 0.0])
    return {
        "pose_m": h.tolist(),
        "compliance_6x6": comp.tolist(),
        "compliance_units": "rows/columns (x, y, z, rx, ry, rz): m/N, rad/N, rad/(N m)",
        "translational_stiffness_n_per_m": np.linalg.inv(comp[:3, :3]).tolist(),
        "translational_stiffness_about_p_star_n_per_m": plate_stiffness(machine, h, "concurrency")[:3, :3].tolist(),
        "vertical_stiffness_n_per_m": float(1 / comp[1, 1]),
        "lateral_stiffness_n_per_m": float(1 / maps_like[-1]),
        "lateral_x_stiffness_n_per_m": float(1 / comp[0, 0]),
        "lateral_z_stiffness_n_per_m": float(1 / comp[2, 2]),
        "lateral_to_vertical": float(comp[1, 1] / maps_like[-1]),
        "press_load_n": press_load_n,
        "press_displacement_m": res.plate_displacement_m.tolist(),
        "press_rotation_rad": res.plate_rotation_rad.tolist(),
        "press_tilt_rad": float(res.tilt_rad),
        "press_axial_forces_n": res.axial_forces_n.tolist(),
        "press_leg_moments_nm": res.leg_moments_nm.tolist(),
    }
