r"""The cardans' clearance law: the smoothed dead zone, the play geometries and their effective axial gaps, and
:class:`Clearance` (every cardan's play; the solvers that use it are :mod:`pressfit.mechanics.clearance`). SI
units throughout.

Clearance law (:class:`DeadZone`)
--------------------------------
Each cardan gets a play along its leg (of the effective gap g of its geometry, below): a virtual
translation x (m, > 0 = the leg lengthens) between the cardan and the leg segment with the smoothed dead-zone force

    f(x) = k_c (s(x - g) - s(-x - g)),   s(u) = (u + sqrt(u^2 + w^2)) / 2,

g the clearance (m), k_c the contact stiffness (N/m), w the smoothing width (m); the energy
E(x) = k_c (S(x - g) + S(-x - g)), S(u) = u s(u) / 2 + w^2 asinh(u / w) / 4, and the tangent
f'(x) = k_c (s'(x - g) + s'(-x - g)) are consistent (tested against finite differences). As w -> 0 the
law tends to the sharp dead zone; the force at the contact edge x = g is k_c w / 2 (0.5 N with the
defaults), which bounds the smoothing error of every contact-state result. A joint is **closed** (in
contact) when |x| >= g.

Why only the play along the leg, and the three geometries (``Clearance.geometry``)
------------------------------------------------------------------------------------
A UPU leg carries its axial force and one couple along c_i = a_i x b_i, and no shear (docs/conventions.md,
"Mechanics facts"). A cardan's translational play t (a vector, m) changes the leg's length by e_i . t to first
order (e_i the unit leg direction); the components of t normal to e_i carry no load (no shear) and
change the length only by |t|^2 / l (nm): to first order the only play that produces lost motion is its
projection on the leg. Under an axial force the joint slides to the point of its play region furthest
along +-e_i, so each geometry enters as an **effective axial gap**, the support function of its play
region along the current leg direction (:meth:`Clearance.effective_gaps_m`):

* ``"axial"``: +-g along the leg axis: g_eff = g (the region is the segment [-g, g] e_i).
* ``"box"``: +-g on each of the joint's three translations, in the cardan's own axes a_i, b_i and
  c_i = a_i x b_i (a cube of half-side g): g_eff = g (|e.a| + |e.b| + |e.c|). With b_i normal to the
  leg and c_i in the plane of a_i and e_i, e.a = sin(beta_i), e.b = 0, e.c = cos(beta_i), so
  g_eff = g (|cos beta_i| + |sin beta_i|): g at beta = 0, up to sqrt(2) g at |beta| = 45 degrees. The
  plate cardan's axes are parallel to the base cardan's (Tsai's condition): the same factor at both ends.
* ``"sphere"``: a ball of radius g: g_eff = g in every direction, so to first order it equals ``"axial"``
  (they differ only in the second-order lateral slide, left out as above).

A leg of two cardans has 2 g_eff of play from the centred state (4 g_eff end to end); at pose A
(beta = 0, every geometry alike) the plate moves by 2g / sin(alpha) before the legs engage. The
effective gaps are taken at the solve's pose (the nonlinear solver keeps them through the deformation:
beta changes by mrad). The play of the rotation about c_i (``rotation_gaps_rad``) is optional: in
series with the leg's couple stiffness k_r, it lets the plate rock before torsion takes the moment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike

from pressfit import kinematics
from pressfit.compiled import compiled
from pressfit.description.machine import Machine
from pressfit.errors import ClearanceError, ConvergenceError

ENDS = ("base", "plate")
DEFAULT_SMOOTHING_M = 1e-9
_EPS = float(np.finfo(float).eps)
Geometry = Literal["axial", "box", "sphere"]
GEOMETRY_DESCRIPTIONS: dict[str, str] = {
    "axial": "axial: +-g along the leg axis at each cardan",
    "box": "box: +-g on the three translations of each cardan in its own axes (a, b, c = a x b); "
           "effective axial gap g (|cos beta| + |sin beta|)",
    "sphere": "sphere: a ball of radius g at each cardan; effective axial gap g (equal to axial to first order)",
}


# --- the law -----------------------------------------------------------------------------------------------
@compiled
def _ramp(u: float, w: float) -> tuple[float, float, float]:
    """s(u) = (u + sqrt(u^2 + w^2)) / 2 (without cancellation for u < 0), its derivative and its integral
    S(u) = u s / 2 + w^2 asinh(u / w) / 4 (S' = s)."""
    r = math.sqrt(u * u + w * w)
    if u >= 0:
        s, ds = 0.5 * (u + r), 0.5 * (1.0 + u / r)
    else:  # an underflowed r - u divides to inf (error_model numpy), as the branch it stands for needs
        s, ds = 0.5 * w * w / (r - u), 0.5 * w * w / (r * (r - u))
    return s, ds, 0.5 * u * s + 0.25 * w * w * math.asinh(u / w)


@compiled
def dead_zone(x: float, g: float, k: float, w: float) -> tuple[float, float, float]:
    """Energy (J), force (N) and tangent (N/m) of one dead zone (:func:`dead_zones`), compiled, for other kernels."""
    sa, dsa, big_a = _ramp(x - g, w)
    sb, dsb, big_b = _ramp(-x - g, w)
    return k * (big_a + big_b), k * (sa - sb), k * (dsa + dsb)


@compiled
def _dead_zone_kernel(x, g, k, w, energy, force, tangent):
    for i in range(x.shape[0]):
        energy[i], force[i], tangent[i] = dead_zone(x[i], g[i], k, w)


@dataclass(frozen=True, kw_only=True)
class DeadZone:
    """Smoothed dead zone of +-gap (m) with contact stiffness (N/m or N m/rad) and smoothing width (m or
    rad); a :class:`pressfit.mechanics.model.SpringLaw`, vectorised over numpy arrays. gap = 0 gives k x exactly."""

    gap: float
    stiffness: float
    width: float = DEFAULT_SMOOTHING_M

    def energy(self, x: ArrayLike) -> np.ndarray:
        return dead_zones(x, self.gap, self.stiffness, self.width)[0]

    def force(self, x: ArrayLike) -> np.ndarray:
        return dead_zones(x, self.gap, self.stiffness, self.width)[1]

    def tangent(self, x: ArrayLike) -> np.ndarray:
        return dead_zones(x, self.gap, self.stiffness, self.width)[2]


def dead_zones(x: ArrayLike, g: ArrayLike, k: float, w: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Energy (J), force (N) and tangent (N/m) of dead zones of stiffness k (N/m) and smoothing width w (m) at
    x (m), with per-entry gaps g (m, broadcast with x): k (S(x - g) + S(-x - g)), k (s(x - g) - s(-x - g)),
    k (s'(x - g) + s'(-x - g)) (:func:`_ramp`, compiled: the plays' solve calls it in every Newton iteration of
    every flexible step)."""
    x, g = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(g, dtype=float))
    out = np.empty((3, x.size))
    _dead_zone_kernel(np.ascontiguousarray(x).reshape(-1), np.ascontiguousarray(g).reshape(-1), float(k), float(w),
                      out[0], out[1], out[2])
    return out[0].reshape(x.shape), out[1].reshape(x.shape), out[2].reshape(x.shape)


def invert_law(force: np.ndarray, gap: np.ndarray, stiffness: float, width: float) -> np.ndarray:
    """The joint coordinate x (m) whose dead-zone force is ``force`` (N), elementwise (safeguarded Newton)."""
    f = np.asarray(force, dtype=float)
    g = np.broadcast_to(np.asarray(gap, dtype=float), f.shape)
    hi = g + np.abs(f) / stiffness + width + 1e-30  # f(hi) >= |f|, f(-hi) <= -|f|
    lo, hi = -hi, hi.copy()
    x = np.sign(f) * (g + np.abs(f) / stiffness)
    for _ in range(200):
        _, fx, tx = dead_zones(x, g, stiffness, width)
        r = fx - f
        # 1e-12 relative, or the force's float resolution at x (k eps |x|: 4e-12 N at 40 um on 5e8 N/m)
        if np.all(np.abs(r) <= 1e-12 * (np.abs(f) + stiffness * width) + 4 * _EPS * stiffness * np.abs(x)):
            return x
        lo, hi = np.where(r < 0, x, lo), np.where(r > 0, x, hi)
        step = x - r / tx
        x = np.where((step >= lo) & (step <= hi), step, 0.5 * (lo + hi))
    raise ConvergenceError("dead-zone inversion", float(np.max(np.abs(r))), 1e-12, 200)


# --- clearance description ---------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class Clearance:
    """Plays of the 2 n cardans (n legs) and their contact law (SI).

    ``gaps_m`` (n, 2): [leg 0..n-1, end 'base' | 'plate'], m: the play g of each cardan, in the shape
    ``geometry`` gives it (module doc: "axial" +-g along the leg, "box" of half-side g in the cardan's axes,
    "sphere" of radius g). ``rotation_gaps_rad`` (n, 2) (or one value for all) or None (rigid): the play of
    the rotation about c_i, rad, with ``rotation_stiffness_nm_per_rad``.
    """

    gaps_m: np.ndarray
    contact_stiffness_n_per_m: float
    smoothing_m: float = DEFAULT_SMOOTHING_M
    rotation_gaps_rad: np.ndarray | None = None
    rotation_stiffness_nm_per_rad: float = 1e7
    rotation_smoothing_rad: float = 1e-8
    geometry: Geometry = "axial"

    def __post_init__(self) -> None:
        if self.geometry not in get_args(Geometry):
            raise ClearanceError(f"clearance geometry must be one of {', '.join(get_args(Geometry))}, "
                                 f"got {self.geometry!r}")
        g = np.array(self.gaps_m, dtype=float)
        if g.ndim != 2 or g.shape[1] != 2 or len(g) < 3:
            raise ClearanceError(f"clearances are given per leg and end, shape (legs, 2) with at least 3 legs, "
                                 f"got shape {g.shape}")
        if not np.all(np.isfinite(g)) or np.any(g < 0) or np.any(g > 1e-2):
            raise ClearanceError(f"clearances must be in [0, 0.01] m, got {g.ravel().tolist()}")
        if not (self.contact_stiffness_n_per_m > 0 and self.smoothing_m > 0):
            raise ClearanceError("contact stiffness and smoothing width must be positive")
        object.__setattr__(self, "gaps_m", g)
        if self.rotation_gaps_rad is not None:
            r = np.broadcast_to(np.asarray(self.rotation_gaps_rad, dtype=float), g.shape).copy()
            if not np.all(np.isfinite(r)) or np.any(r < 0):
                raise ClearanceError("rotation clearances must be non-negative")
            object.__setattr__(self, "rotation_gaps_rad", r)

    @classmethod
    def uniform(cls, machine: Machine, gap_m: float | None = None, **kw: Any) -> Clearance:
        """Every cardan with the same play (default: the machine's ``joints.cardan_axial_clearance_m``)."""
        g = machine.joints.cardan_axial_clearance_m if gap_m is None else gap_m
        kw.setdefault("contact_stiffness_n_per_m", machine.joints.cardan_contact_stiffness_n_per_m)
        kw.setdefault("geometry", machine.joints.cardan_clearance_geometry)
        return cls(gaps_m=np.full((len(machine.legs), 2), float(g)), **kw)

    @classmethod
    def per_joint(cls, machine: Machine, gaps_m: list[float], **kw: Any) -> Clearance:
        """2 n plays (n legs) ordered leg 1 base, leg 1 plate, leg 2 base, ..., m."""
        if len(gaps_m) != 2 * len(machine.legs):
            raise ClearanceError(f"give {2 * len(machine.legs)} clearances (leg 1 base, leg 1 plate, ...) for "
                                 f"{machine.name}'s {len(machine.legs)} legs, got {len(gaps_m)}")
        kw.setdefault("contact_stiffness_n_per_m", machine.joints.cardan_contact_stiffness_n_per_m)
        kw.setdefault("geometry", machine.joints.cardan_clearance_geometry)
        return cls(gaps_m=np.asarray(gaps_m, dtype=float).reshape(-1, 2), **kw)

    @classmethod
    def random(cls, machine: Machine, low_m: float, high_m: float, seed: int, **kw: Any) -> Clearance:
        """Plays drawn uniformly from [low_m, high_m] (numpy default_rng(seed)), m."""
        if not 0 <= low_m <= high_m:
            raise ClearanceError(f"need 0 <= low_m <= high_m, got {low_m}, {high_m}")
        kw.setdefault("contact_stiffness_n_per_m", machine.joints.cardan_contact_stiffness_n_per_m)
        kw.setdefault("geometry", machine.joints.cardan_clearance_geometry)
        return cls(gaps_m=np.random.default_rng(seed).uniform(low_m, high_m, (len(machine.legs), 2)), **kw)

    def with_gap(self, gap_m: float) -> Clearance:
        """The same contact law and geometry with every cardan's play g = gap_m (m)."""
        return replace(self, gaps_m=np.full(self.gaps_m.shape, float(gap_m)))

    @property
    def description(self) -> str:
        """The geometry in words (for outputs)."""
        return GEOMETRY_DESCRIPTIONS[self.geometry]

    def effective_gaps_m(self, machine: Machine, pose_m: ArrayLike) -> np.ndarray:
        """(n, 2) effective axial gaps, m: the support function of each play region along the leg direction
        e_i at the pose (module doc): g (axial, sphere) or g (|e.a| + |e.b| + |e.c|) = g (|cos beta| +
        |sin beta|) (box; e.b = 0, e.c = sqrt(1 - (e.a)^2))."""
        if len(self.gaps_m) != len(machine.legs):
            raise ClearanceError(f"the clearance gives plays for {len(self.gaps_m)} legs; {machine.name} has "
                                 f"{len(machine.legs)}")
        if self.geometry != "box":
            return self.gaps_m.copy()
        u = kinematics.leg_vectors(machine, np.asarray(pose_m, dtype=float).reshape(3))
        ea = np.abs(np.sum(u / np.linalg.norm(u, axis=-1, keepdims=True) * machine.cardan_axes, -1))
        return self.gaps_m * (ea + np.sqrt(np.clip(1.0 - ea * ea, 0.0, 1.0)))[:, None]

    def at_pose(self, machine: Machine, pose_m: ArrayLike) -> Clearance:
        """The equivalent axial clearance at a pose (m): gaps = :meth:`effective_gaps_m`, geometry "axial"
        (idempotent: an axial clearance is returned unchanged). Every solver applies it at its entry."""
        if self.geometry == "axial":
            return self
        return replace(self, gaps_m=self.effective_gaps_m(machine, pose_m), geometry="axial")

    def law(self, leg: int, end: int) -> DeadZone:
        return DeadZone(gap=float(self.gaps_m[leg, end]), stiffness=self.contact_stiffness_n_per_m,
                        width=self.smoothing_m)

    def rotation_law(self, leg: int, end: int) -> DeadZone | None:
        if self.rotation_gaps_rad is None:
            return None
        return DeadZone(gap=float(self.rotation_gaps_rad[leg, end]), stiffness=self.rotation_stiffness_nm_per_rad,
                        width=self.rotation_smoothing_rad)

    def cardan_compliance(self) -> dict:
        """The ``cardan_compliance`` argument of :func:`pressfit.mechanics.model.build_model` (axial
        geometry; resolve a box or sphere at its pose with :meth:`at_pose` first)."""
        from pressfit.mechanics.model import CardanCompliance

        if self.geometry != "axial":
            raise ClearanceError(f"a {self.geometry} clearance depends on the pose: resolve it with "
                                 "Clearance.at_pose(machine, pose) before building a model")

        return {(i, e): CardanCompliance(axial=self.law(i, j), rotation=self.rotation_law(i, j))
                for i in range(len(self.gaps_m)) for j, e in enumerate(ENDS)}

    def play_extension_m(self, machine: Machine, pose_m: ArrayLike, axial_forces_n: np.ndarray) -> np.ndarray:
        """The summed extension (n,), m, of each leg's two plays (effective axial gaps at the pose, m) under
        its axial force (n,), N."""
        return invert_law(np.repeat(np.asarray(axial_forces_n, float)[:, None], 2, 1),
                          self.effective_gaps_m(machine, pose_m),
                          self.contact_stiffness_n_per_m, self.smoothing_m).sum(1)

    def to_dict(self) -> dict[str, Any]:
        return {"geometry": self.geometry, "gaps_m": self.gaps_m.tolist(),
                "contact_stiffness_n_per_m": self.contact_stiffness_n_per_m,
                "smoothing_m": self.smoothing_m,
                "rotation_gaps_rad": None if self.rotation_gaps_rad is None else self.rotation_gaps_rad.tolist()}
