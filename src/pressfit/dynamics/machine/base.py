r"""The dynamics-model interface that the simulation drives: one state, one step, and what a designer reads off it.

A model is stepped by ``step(state, drive_input, plate_wrench, dt_s) -> state``; the state is immutable (a new
value per step), so a run is reproducible from any of its states. Conventions (those of
:mod:`pressfit.mechanics.statics`): world frame with y up, SI units; legs in kinematic order; an axial force
N > 0 is tension; a plate wrench is (force N, moment N m) in world axes at the plate centre.

Drive input (:class:`DriveInput`), per leg:

* ``kind = "force"``: the drive's force, N, tension > 0, acting through the actuator joint (an ideal force
  source: the actuator joint carries no spring);
* ``kind = "position"``: the drive position, m: the rest length of the actuator spring (the actuator stiffness
  in series with the leg's axial compliance), so a position drive holds the leg through that spring.

Section resultants (:class:`SectionLoads`): the wrench of the plate-side part on the base-side part at the
sections 'base' (base cardan centre), 'actuator' (cylinder end) and 'plate' (plate cardan centre), about the
section point, in the deformed leg frame (e_z from the base cardan to the plate cardan, e_x = a_i made normal
to e_z, e_y = e_z x e_x): columns N, V_x, V_y (N), M_x, M_y, T (N m), as in
:class:`pressfit.mechanics.statics.SectionWrench`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

from pressfit.errors import PressfitError
from pressfit.mechanics.statics import SECTION_COMPONENTS, SECTIONS

DRIVE_KINDS = ("force", "position")


@dataclass(frozen=True)
class DriveInput:
    """What the drives (one per leg) impose during one step: forces (N, tension > 0) or positions (m, actuator
    spring rest lengths). ``values`` (n,) are held over the step (zero-order hold)."""

    kind: Literal["force", "position"]
    values: np.ndarray

    def __post_init__(self) -> None:
        values = np.asarray(self.values, dtype=float)
        if self.kind not in DRIVE_KINDS:
            raise PressfitError(f"drive input kind must be one of {DRIVE_KINDS}, got {self.kind!r}")
        if values.ndim != 1 or values.size < 3 or not np.all(np.isfinite(values)):
            unit = "N" if self.kind == "force" else "m"
            raise PressfitError(f"drive input ({self.kind}) must be one finite number in {unit} per leg (3 or more), "
                                f"got {self.values!r}")
        if self.kind == "position" and np.any(values <= 0):
            raise PressfitError(f"drive positions must be positive lengths (m), got {values.tolist()}")
        object.__setattr__(self, "values", values)

    @classmethod
    def forces(cls, forces_n: np.ndarray) -> DriveInput:
        return cls("force", forces_n)

    @classmethod
    def positions(cls, lengths_m: np.ndarray) -> DriveInput:
        return cls("position", lengths_m)


@dataclass(frozen=True, kw_only=True)
class MachineState:
    """The state of a dynamics model at ``time_s`` (s): configuration q (nq,) and velocity v (nv,) in the
    model's Pinocchio coordinates (plate free flyer first: q[0:3] the plate centre, m)."""

    time_s: float
    q: np.ndarray
    v: np.ndarray


@dataclass(frozen=True)
class SectionLoads:
    """Leg section resultants at one instant (module doc): ``values`` (4 legs, 3 sections, 6 components
    N, V_x, V_y, M_x, M_y, T in N and N m), ``frames`` (4, 3, 3) the deformed leg frames (columns e_x, e_y, e_z)."""

    values: np.ndarray
    frames: np.ndarray

    def axial_n(self, section: str = "plate") -> np.ndarray:
        """(n,) axial force N at a section, N, > 0 tension (n legs)."""
        return self.values[:, SECTIONS.index(section), 0]

    def as_dicts(self) -> list[dict[str, dict[str, float]]]:
        """Per leg: section -> component -> value (JSON-ready)."""
        return [{s: dict(zip(SECTION_COMPONENTS, self.values[i, k].tolist())) for k, s in enumerate(SECTIONS)}
                for i in range(len(self.values))]


@dataclass(frozen=True, kw_only=True)
class Energy:
    """Mechanical energy at one instant, J: kinetic, elastic (the virtual springs, including the actuator
    springs of position drives) and gravitational potential (zero at y = 0)."""

    kinetic_j: float
    elastic_j: float
    potential_j: float

    @property
    def total_j(self) -> float:
        return self.kinetic_j + self.elastic_j + self.potential_j


class DynamicsModel(Protocol):
    """What the insertion simulation, the control design and the tool-point response need of a machine model."""

    def step(self, state: MachineState, drive_input: DriveInput, plate_wrench: np.ndarray,
             dt_s: float) -> MachineState:
        """Advance ``dt_s`` (s) under the drive input and a plate wrench (6,) (N, N m; world, plate centre),
        both held over the step; raises a PressfitError for a step it cannot integrate."""
        ...

    def plate_pose(self, state: MachineState) -> tuple[np.ndarray, np.ndarray]:
        """Plate centre (3,) (m) and rotation matrix (3, 3) (world)."""
        ...

    def tool_point_m(self, state: MachineState) -> np.ndarray:
        """The tool tip (3,), m, world."""
        ...

    def leg_lengths_m(self, state: MachineState) -> np.ndarray:
        """(n,) what the drives measure: the actuator joint coordinates, m (n legs)."""
        ...

    def leg_rates_m_per_s(self, state: MachineState) -> np.ndarray:
        """(n,) their rates, m/s."""
        ...

    def section_loads(self, state: MachineState) -> SectionLoads:
        """Leg section resultants (module doc)."""
        ...

    def closure_error(self, state: MachineState) -> tuple[float, float]:
        """Largest loop-closure error over the legs, (m, rad)."""
        ...

    def energy(self, state: MachineState) -> Energy:
        """Kinetic, elastic and potential energy, J."""
        ...
