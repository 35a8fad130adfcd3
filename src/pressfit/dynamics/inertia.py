r"""Masses on the machine's Pinocchio model (the ``[mass]`` table of the machine file), for modes and dynamics.

:func:`pressfit.mechanics.model.build_model` builds a massless model (the statics needs none);
:func:`inertial_model` returns a copy of its ``pin.Model`` with body inertias and gravity (-9.81 m/s^2 along
world y) set. Along leg i (unit axis e_i from the base cardan B_i to the plate cardan, length l_i) each
body of the VJM chain carries the piece of tube it spans between the virtual springs:

* the cylinder, s in [0, L_c] from B_i, split at the cylinder springs (s = (k + 1/2) L_c / n): tube mass
  density * A_c per metre plus the actuator housing spread uniformly (``actuator_housing_mass_kg`` / L_c);
* the stem, a rod of fixed length L_r (``stem.length_m``) and mass density * A_s * L_r at every pose, spanning
  s in [l_i - L_r, l_i] (its outer end at the plate cardan, so its centre of mass l_i - L_r / 2 moves with the
  extension): its exposed part s in [L_c, l_i] is split at the stem springs; the part inside the cylinder,
  s in [l_i - L_r, L_c], rides on the body after the prismatic joint (the actuator), which also carries the
  actuator's moving parts (nut, piston) as a point mass at the rod's inner end s = l_i - L_r. The stem springs'
  placements follow the stem length, so these pieces are written per pose in the bodies' own frames
  (:func:`set_stem_inertias`; :class:`pressfit.dynamics.machine.flexible.FlexibleMachine` re-writes them with the
  placements, the rigid-leg model lumps them onto one body whatever the pose);
* each cardan, a solid sphere of the stem's radius at its centre, half of its mass on the spider (between the
  two revolutes) and half on the body after the cardan (every body then has rotational inertia about its
  joint axes, which keeps the mass matrix of the rigid-leg model positive definite);
* the plate (a uniform box 2 r x t x 2 r, t = ``collision.plate_thickness_m``) plus the tool as a point mass
  at the plate centre, on the plate joint;
* an electric drive's rotor and screw, J (2 pi / lead)^2 along the leg
  (:attr:`pressfit.description.machine.Machine.drive_reflected_mass_kg`), as the armature of the prismatic
  joint (``model.armature`` at its velocity index: ``crba`` and the constraint dynamics add it to the
  diagonal of the mass matrix), scaled like the other masses. It is the rotor's kinetic energy
  J omega^2 / 2 with omega = 2 pi l_dot / lead relative to the housing; the housing's own rotation about the
  leg axis adds a gyroscopic coupling of order J omega Omega that is left out.

A piece of length L and mass m is a thick-walled tube about its own centre: axial inertia m (r_o^2 + r_i^2) / 2,
transverse m ((r_o^2 + r_i^2) / 4 + L^2 / 12) (kg m^2). Inertias are body-fixed, so they are computed once
at the model's reference configuration ``mm.q0``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pressfit.description.machine import Machine
from pressfit.mechanics.model import MachineModel

GRAVITY_M_PER_S2 = 9.81  # standard gravity, along -y (world y is vertical, up)


def _tube(mass_kg: float, length_m: float, r_out_m: float, r_in_m: float, axis: np.ndarray) -> np.ndarray:
    """Rotational inertia (3, 3) about the centre of a tube piece, world axes (kg m^2)."""
    rr = r_out_m**2 + r_in_m**2
    ee = np.outer(axis, axis)
    return mass_kg * ((rr / 4 + length_m**2 / 12) * (np.eye(3) - ee) + rr / 2 * ee)


def _add(model: pin.Model, oMi: pin.SE3, joint: int, mass_kg: float, com_world: np.ndarray,
         inertia_world: np.ndarray) -> None:
    """Add a body piece given in world coordinates to joint ``joint``'s inertia (its frame is ``oMi``)."""
    if mass_kg <= 0.0:
        return
    rot = oMi.rotation
    piece = pin.Inertia(mass_kg, rot.T @ (com_world - oMi.translation), rot.T @ inertia_world @ rot)
    model.inertias[joint] = model.inertias[joint] + piece


def _chain(mm: MachineModel, leg: int, first: int, segment: str) -> list[int]:
    """Joint ids carrying a leg segment: ``first`` then the last revolute of each of its spring groups."""
    names = [f"leg{leg + 1}.{segment}[{k}].z" for k in range(mm.springs_per_segment)]
    return [first] + [mm.model.getJointId(name) for name in names]


def joint_placements(model: pin.Model, q: np.ndarray) -> list[pin.SE3]:
    """The joints' world placements at ``q`` (``data.oMi`` of ``pin.forwardKinematics``), walking the tree with
    each joint's own calc: creating a Data of the elastic model (122 velocities) costs 0.2 s, this 1.5 ms."""
    placements = [pin.SE3.Identity()]
    for j in range(1, model.njoints):
        joint = model.joints[j]
        jd = joint.createData()
        joint.calc(jd, q)
        placements.append(placements[model.parents[j]] * model.jointPlacements[j] * jd.M)
    return placements


def inertial_model(mm: MachineModel, mass_scale: float = 1.0) -> pin.Model:
    """A copy of ``mm.model`` with the machine's masses (all multiplied by ``mass_scale``) and gravity on."""
    machine, mass = mm.machine, mm.machine.mass
    model = pin.Model(mm.model)
    model.gravity = pin.Motion(np.array([0.0, -GRAVITY_M_PER_S2, 0.0, 0.0, 0.0, 0.0]))
    placements = joint_placements(model, mm.q0)
    n, lc = mm.springs_per_segment, machine.cylinder.length_m
    r_cyl = (machine.cylinder.outer_diameter_m / 2, machine.cylinder.outer_diameter_m / 2
             - machine.cylinder.wall_thickness_m)
    mu_cyl = mass_scale * (machine.cylinder_tube_mass_kg + mass.actuator_housing_mass_kg) / lc
    for i, ids in enumerate(mm.leg_joint_ids):
        base = machine.base_points_m[i]
        axis = mm.pose_m + machine.plate_offsets_m[i] - base
        length = float(np.linalg.norm(axis))
        axis = axis / length
        bounds = lc * np.concatenate([[0.0], (np.arange(n) + 0.5) / n, [1.0]])
        for j, s0, s1 in zip(_chain(mm, i, ids["cylinder"], "cylinder"), bounds[:-1], bounds[1:], strict=True):
            m = mu_cyl * (s1 - s0)
            _add(model, placements[j], j, m, base + axis * (s0 + s1) / 2, _tube(m, s1 - s0, *r_cyl, axis))
        m_half = mass_scale * mass.cardan_spider_mass_kg / 2
        sphere = 0.4 * m_half * (machine.stem.diameter_m / 2) ** 2 * np.eye(3)
        points = ((ids["base_cardan"], 0.0, m_half, sphere), (ids["cylinder"], 0.0, m_half, sphere),
                  (ids["plate_cardan"], length, m_half, sphere), (ids["plate_end"], length, m_half, sphere))
        for j, s, m, inertia in points:
            _add(model, placements[j], j, m, base + axis * s, inertia)
    set_stem_inertias(mm, model, mm.pose_values(mm.pose_m).stem_lengths_m, mass_scale)
    plate = mm.plate_joint_id
    side, t = 2 * machine.geometry.plate_half_side_m, machine.collision.plate_thickness_m
    m_plate = mass_scale * mass.plate_mass_kg
    box = m_plate / 12 * np.diag([side**2 + t**2, 2 * side**2, side**2 + t**2])
    _add(model, placements[plate], plate, m_plate, mm.pose_m, box)
    _add(model, placements[plate], plate, mass_scale * mass.tool_mass_kg, mm.pose_m, np.zeros((3, 3)))
    for ids in mm.leg_joint_ids:
        model.armature[model.joints[ids["actuator"]].idx_v] += mass_scale * machine.drive_reflected_mass_kg
    return model


def stem_pieces(machine: Machine, springs_per_segment: int, stem_length_m: float, mass_scale: float = 1.0
                ) -> list[pin.Inertia]:
    """The stem's pieces (module doc) as inertias in their bodies' own frames, in chain order: the actuator body
    (origin at the plate cardan, z along the leg: the rod z in [-L_r, -L_s (1 - 1/(2n))] and the moving parts at
    z = -L_r) and the body of each stem spring k (origin at the spring, L_c + (k + 1/2) L_s / n from the base
    cardan: the exposed rod up to the next spring or the plate cardan), for an exposed stem length L_s (m);
    kg, m, kg m^2. Their masses sum to the rod's and the moving parts' at every L_s."""
    return [pin.Inertia(piece) for piece in _StemRod(machine, springs_per_segment, mass_scale).pieces(
        float(stem_length_m))]  # copies: the rod's spring pieces share one object where they are equal


class _StemRod:
    """:func:`stem_pieces` with what does not depend on the stem length computed once (a flexible run re-writes
    the pieces on many of its steps)."""

    def __init__(self, machine: Machine, springs_per_segment: int, mass_scale: float) -> None:
        self.n, self.rod = springs_per_segment, machine.stem.length_m
        self.mu = mass_scale * machine.mass.density_kg_per_m3 * machine.stem_section.area_m2  # kg/m
        self.radius = machine.stem.diameter_m / 2
        moving = mass_scale * machine.mass.actuator_moving_mass_kg
        self.moving = pin.Inertia(moving, np.array([0.0, 0.0, -self.rod]), np.zeros((3, 3))) if moving > 0.0 else None

    def pieces(self, ls: float) -> list[pin.Inertia]:
        n = self.n
        inner, spring, last = (self._rod(z0, z1) for z0, z1 in ((-self.rod, -ls + ls / (2 * n)), (0.0, ls / n),
                                                                 (0.0, ls / (2 * n))))
        # the spring bodies' pieces, the same object where the same (written into a model, each is copied)
        return [inner if self.moving is None else inner + self.moving] + [spring] * (n - 1) + [last]

    def _rod(self, z0: float, z1: float) -> pin.Inertia:
        """A solid rod along z from z0 to z1 (m) about its centre (the tube of _tube without a bore), moved there."""
        piece = pin.Inertia.FromCylinder(self.mu * (z1 - z0), self.radius, z1 - z0)
        piece.lever = np.array([0.0, 0.0, (z0 + z1) / 2])
        return piece


class StemInertias:
    """Writes the stem pieces (:func:`stem_pieces`) of exposed stem lengths into a model's actuator and stem-spring
    bodies (a copy of ``mm.model`` with :meth:`MachineModel.place_stem` at the same lengths; those bodies carry
    nothing else), the bodies and the rod's constants found once."""

    def __init__(self, mm: MachineModel, mass_scale: float = 1.0) -> None:
        self.rod = _StemRod(mm.machine, mm.springs_per_segment, mass_scale)
        self.bodies = [_chain(mm, i, ids["actuator"], "stem") for i, ids in enumerate(mm.leg_joint_ids)]

    def write(self, model: pin.Model, stem_lengths_m: np.ndarray) -> None:
        """Write the pieces for exposed stem lengths (n,), m."""
        inertias = model.inertias
        for bodies, ls in zip(self.bodies, np.asarray(stem_lengths_m, dtype=float).tolist(), strict=True):
            for j, piece in zip(bodies, self.rod.pieces(ls), strict=True):
                inertias[j] = piece


def set_stem_inertias(mm: MachineModel, model: pin.Model, stem_lengths_m: np.ndarray, mass_scale: float = 1.0
                      ) -> None:
    """Write the stem pieces (:func:`stem_pieces`) of exposed stem lengths (n,) (m) into ``model``'s actuator and
    stem-spring bodies (:class:`StemInertias`, once)."""
    StemInertias(mm, mass_scale).write(model, stem_lengths_m)


def total_mass_kg(model: pin.Model) -> float:
    """Sum of the body masses of a model, kg."""
    return float(sum(inertia.mass for inertia in model.inertias))
