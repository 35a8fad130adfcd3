r"""Actuator preload along the self-stress vector v_p (paper equations 9-10, Table 4): the one home of
the preload modes, the actuator rest-length offsets, and the self-stress superposition. SI units.

The 4-UPU plate has four legs for three force directions, so the static matrix A (equation 5) has a
one-dimensional null space spanned by v_p (:func:`pressfit.kinematics.preload_vector`, v_1 < 0): leg
forces a4 v_p load the plate with nothing. A preload a4 is applied before the load, in one of two modes:

* ``force`` (force-controlled drives): a4 in N; with no load the actuator forces are exactly a4 v_p
  (tension > 0). As actuator rest-length offsets: o_i = -(a4 v_i c_axial,i + x_i), c_axial the leg's
  axial compliance (m/N) and x_i the extension (m) of the leg's cardan plays (if any) under a4 v_i,
  which closes every play with v_i != 0 (:class:`pressfit.mechanics.clearance.Clearance`).
* ``length`` (position-held drives): a4 in m; offsets o_i = -a4 v_i (legs shortened by a4 v_i, so that
  a4 > 0 pulls the legs with v_i > 0 like the force mode).

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
from pressfit.errors import PressfitError
from pressfit.mechanics.condensed import CondensedResult
from pressfit.spatial import cross

if TYPE_CHECKING:
    from pressfit.mechanics.clearance import Clearance

PreloadMode = Literal["force", "length"]
PRELOAD_MODES = ("force", "length")


class PreloadError(PressfitError):
    """A preload that cannot be applied (unknown mode, non-finite a4)."""


@dataclass(frozen=True)
class ActuatorPreload:
    """A preload a4 along v_p: N in ``force`` mode, m in ``length`` mode (module doc)."""

    a4: float
    mode: PreloadMode = "force"

    def __post_init__(self) -> None:
        if self.mode not in PRELOAD_MODES:
            raise PreloadError(f"preload mode must be 'force' or 'length', got {self.mode!r}")
        if not math.isfinite(self.a4):
            raise PreloadError(f"preload a4 must be finite, got {self.a4!r}")

    @classmethod
    def from_case(cls, spec: CasePreload) -> ActuatorPreload:
        """A case file's ``[preload]`` table (a4_n in force mode, a4_m in length mode)."""
        return cls(float(spec.a4), spec.mode)


def rest_length_offsets(machine: Machine, pose_m: np.ndarray, a4: float, mode: str = "force",
                        clearance: Clearance | None = None) -> np.ndarray:
    """Actuator rest-length offsets (4,), m, for a preload a4 along v_p at one pose (m) (module doc).

    ``clearance``: the cardans' plays (effective axial gaps at the pose), closed by the preload in force mode
    (None: rigid cardans).
    """
    pre = ActuatorPreload(float(a4), mode)  # type: ignore[arg-type]
    vp = kinematics.preload_vector(machine, pose_m)
    if pre.mode == "length":
        return -pre.a4 * vp
    n = pre.a4 * vp
    offsets = -n * machine.axial_compliance_m_per_n(kinematics.inverse_kinematics(machine, pose_m).lengths_m)
    return offsets if clearance is None else offsets - clearance.play_extension_m(machine, pose_m, n)


def self_stress_forces_n(machine: Machine, poses_m: np.ndarray, a4_n: float) -> np.ndarray:
    """Leg forces a4 v_p (..., 4), N (tension > 0): a force-mode preload at each pose (m)."""
    return a4_n * kinematics.preload_vector(machine, poses_m)


def with_axial_preload(result: CondensedResult, extra_forces_n: np.ndarray) -> CondensedResult:
    """Superpose leg forces that are self-equilibrated on the plate (a multiple of v_p, e.g. a
    force-mode actuator preload): N += extra, (..., 4) N. Exact in the linear model: displacements and
    couples are unchanged; the residuals are updated, so an extra set that is not self-equilibrated shows.
    """
    extra_forces_n = np.asarray(extra_forces_n, dtype=float)
    extra = extra_forces_n[..., None] * result.leg_unit_vectors
    return replace(
        result, axial_forces_n=result.axial_forces_n + extra_forces_n,
        force_residual_n=result.force_residual_n - extra.sum(-2),
        moment_residual_nm=result.moment_residual_nm - cross(result.plate_offsets_m, extra).sum(-2))
