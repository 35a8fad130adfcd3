r"""Actuator preload in the preload space (paper equations 9-10, Table 4): the one home of the preload modes,
the actuator rest-length offsets, and the self-stress superposition. SI units.

A plate with n legs for three force directions has a static matrix A (equation 5, 3 x n) whose null space,
of dimension n - 3 (the machine's redundancy), is spanned by the basis V = [v_1 ... v_{n-3}]
(:func:`pressfit.kinematics.preload_basis`; for the paper's 4-UPU the one vector v_p, v_1 < 0): leg forces
V a load the plate with nothing. A preload is a vector of n - 3 amplitudes a (the 4-UPU's scalar a4; a 3-leg
machine has none and is refused), applied before the load in one of two modes:

* ``force`` (force-controlled drives): a in N; with no load the actuator forces are exactly V a
  (tension > 0). As actuator rest-length offsets: o_i = -((V a)_i c_axial,i + x_i), c_axial the leg's
  axial compliance (m/N) and x_i the extension (m) of the leg's cardan plays (if any) under (V a)_i,
  which closes every play with (V a)_i != 0 (:class:`pressfit.mechanics.clearance_law.Clearance`).
* ``length`` (position-held drives): a in m; offsets o = -V a (legs shortened by (V a)_i, so that
  a > 0 pulls the legs with v_i > 0 like the force mode).

In the condensed linear model (:mod:`pressfit.mechanics.condensed`) a force-mode preload is a
self-stress with no couples and no plate motion; it superposes exactly (:func:`with_axial_preload`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Literal

import numpy as np

from pressfit import kinematics
from pressfit.description.cases import Preload as CasePreload
from pressfit.description.machine import Machine
from pressfit.errors import PreloadError
from pressfit.mechanics.condensed import CondensedResult
from pressfit.spatial import cross

if TYPE_CHECKING:
    from pressfit.mechanics.clearance_law import Clearance

PreloadMode = Literal["force", "length"]
PRELOAD_MODES = ("force", "length")
Amplitudes = float | tuple[float, ...] | list[float] | np.ndarray


@dataclass(frozen=True)
class ActuatorPreload:
    """A preload along the preload space: ``a4`` the amplitude (a redundancy-1 machine, the 4-UPU) or the
    n - 3 amplitudes (a tuple), N in ``force`` mode, m in ``length`` mode (module doc)."""

    a4: float | tuple[float, ...]
    mode: PreloadMode = "force"

    def __post_init__(self) -> None:
        if self.mode not in PRELOAD_MODES:
            raise PreloadError(f"preload mode must be 'force' or 'length', got {self.mode!r}")
        if not all(math.isfinite(a) for a in self.amplitudes.tolist()):
            raise PreloadError(f"preload a4 must be finite, got {self.a4!r}")

    @property
    def amplitudes(self) -> np.ndarray:
        """The amplitudes as an array (k,), N or m (k = 1 for a scalar a4)."""
        return np.atleast_1d(np.asarray(self.a4, dtype=float)).reshape(-1)

    @classmethod
    def from_case(cls, spec: CasePreload) -> ActuatorPreload:
        """A case file's ``[preload]`` table (a4_n or amplitudes_n in force mode, a4_m or amplitudes_m in length
        mode)."""
        amp = spec.amplitudes
        return cls(amp[0] if len(amp) == 1 else tuple(amp), spec.mode)


def _preload(a4: Amplitudes, mode: str = "force") -> ActuatorPreload:
    """The checked preload of a scalar a4 or an array of amplitudes."""
    amp = float(a4) if np.ndim(a4) == 0 else tuple(np.asarray(a4, dtype=float).ravel().tolist())
    return ActuatorPreload(amp, mode)  # type: ignore[arg-type]


def self_stress_forces_n(machine: Machine, poses_m: np.ndarray, a4: Amplitudes) -> np.ndarray:
    """Leg forces V a (..., n) of the preload amplitudes a (scalar for a redundancy-1 machine, else (n - 3,); N
    in force mode, tension > 0) at poses (..., 3) (m). A zero preload is zero on any machine; otherwise
    :class:`PreloadError` for a 3-leg machine ("no redundant actuation") or a number of amplitudes other than
    its redundancy n - 3."""
    amp = _preload(a4).amplitudes
    h = np.asarray(poses_m, dtype=float)
    if not amp.any():
        return np.zeros(h.shape[:-1] + (len(machine.legs),))
    k = machine.redundancy
    if k == 0:
        raise PreloadError("a 3-leg machine has no redundant actuation: no internal preload", machine.name, k)
    if amp.size != k:
        raise PreloadError(f"a {k + 3}-leg machine's preload space has dimension {k}: give {k} preload "
                           f"amplitude{'s' if k > 1 else ''}, got {amp.size}", machine.name, k)
    return kinematics.preload_basis(machine, h) @ amp


def along_first_vector(machine: Machine, a: float) -> Amplitudes:
    """The amplitudes of a one-number preload a (N or m) of the preload studies: a itself on a machine with at
    most one preload vector (a 3-leg machine accepts only a = 0 downstream), a along the first basis vector
    (leg 4 pulls, the legs beyond it carry nothing) and 0 along the others on a machine with more."""
    return float(a) if machine.redundancy <= 1 else (float(a),) + (0.0,) * (machine.redundancy - 1)


def rest_length_offsets(machine: Machine, pose_m: np.ndarray, a4: Amplitudes, mode: str = "force",
                        clearance: Clearance | None = None) -> np.ndarray:
    """Actuator rest-length offsets (n,), m, for a preload of amplitudes a4 (scalar for a redundancy-1
    machine, else (n - 3,); N in force mode, m in length mode) at one pose (m) (module doc).

    ``clearance``: the cardans' plays (effective axial gaps at the pose), closed by the preload in force mode
    (None: rigid cardans).
    """
    pre = _preload(a4, mode)
    v = self_stress_forces_n(machine, pose_m, pre.amplitudes)
    if pre.mode == "length":
        return -v
    offsets = -v * machine.axial_compliance_m_per_n(kinematics.inverse_kinematics(machine, pose_m).lengths_m)
    return offsets if clearance is None else offsets - clearance.play_extension_m(machine, pose_m, v)


def with_axial_preload(result: CondensedResult, extra_forces_n: np.ndarray) -> CondensedResult:
    """Superpose leg forces that are self-equilibrated on the plate (in the preload space, e.g. a
    force-mode actuator preload): N += extra, (..., n) N. Exact in the linear model: displacements and
    couples are unchanged; the residuals are updated, so an extra set that is not self-equilibrated shows.
    """
    extra_forces_n = np.asarray(extra_forces_n, dtype=float)
    extra = extra_forces_n[..., None] * result.leg_unit_vectors
    return replace(
        result, axial_forces_n=result.axial_forces_n + extra_forces_n,
        force_residual_n=result.force_residual_n - extra.sum(-2),
        moment_residual_nm=result.moment_residual_nm - cross(result.plate_offsets_m, extra).sum(-2))


def closing_direction(machine: Machine, poses_m: np.ndarray) -> np.ndarray:
    """The unit leg-force direction (..., n) of the preload that closes every leg's cardans, at poses (..., 3), m.

    Redundancy 1 (the 4-UPU): v_p itself (Table 4, v_1 < 0). Redundancy >= 2: of the preload space's projections of
    the 2^(n-1) leg sign patterns (s_1 = -1), the unit vector whose smallest leg share min_i |v_i| is largest, so
    every leg carries a share (the studies' :func:`along_first_vector` leaves legs 5..n without any); v_1 < 0. NaN
    where the basis is. PreloadError on a 3-leg machine (no redundant actuation)."""
    k = machine.redundancy
    if k == 0:
        raise PreloadError("a 3-leg machine has no redundant actuation: no internal preload", machine.name, k)
    basis = kinematics.preload_basis(machine, np.asarray(poses_m, dtype=float))
    if k == 1:
        return basis[..., 0]
    n = len(machine.legs)
    signs = np.array(np.meshgrid(*([[-1.0]] + [[-1.0, 1.0]] * (n - 1)), indexing="ij")).reshape(n, -1)  # (n, P)
    q, _ = np.linalg.qr(np.nan_to_num(basis))  # (..., n, k) orthonormal
    proj = q @ (np.swapaxes(q, -1, -2) @ signs)  # (..., n, P)
    proj /= np.maximum(np.linalg.norm(proj, axis=-2, keepdims=True), 1e-300)
    best = np.argmax(np.abs(proj).min(axis=-2), axis=-1)  # (...,)
    v = np.take_along_axis(proj, best[..., None, None], axis=-1)[..., 0]
    v = np.where(v[..., :1] > 0, -v, v)
    return np.where(np.isnan(basis).any(axis=(-1, -2))[..., None], np.nan, v)
