r"""Natural frequencies and mode shapes of the loaded machine at a pose (small vibrations about equilibrium).

The VJM model (:mod:`pressfit.mechanics.model`) is first brought to its static equilibrium under the plate
wrench (default: the weight of plate and tool; :func:`pressfit.mechanics.statics.solve_equilibrium`,
geometrically nonlinear). About that configuration q*, admissible motions dq = N z satisfy the linearised
loop closures J_c(q*) dq = 0, N an orthonormal basis of the null space of the (6 n x nv) closure Jacobian
(n legs, one plate-cardan closure each). Restricted to it,

    K_r = N^T K N,   M_r = N^T M(q*) N,   K_r x = omega^2 M_r x   (scipy.linalg.eigh),

with K the elastic tangent stiffness (each virtual spring's tangent at q*, N/m or N m/rad, zero on the
cardans and the plate's free flyer) and M(q*) Pinocchio's joint-space mass matrix (``pin.crba``) of the
model with the machine's masses (:mod:`pressfit.dynamics.inertia`). Mode shapes phi = N x are
mass-normalised (phi^T M phi = 1 kg m^2 in mixed units). The geometric stiffness of the static load is left
out: its terms are of order F L (N m/rad) against leg spring stiffnesses of order E I / L; at the plate's own
weight the ratio is about 1e-6, at the 700 N press load about 1e-3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.linalg import eigh, null_space

from pressfit.description.machine import Machine
from pressfit.dynamics.inertia import GRAVITY_M_PER_S2, inertial_model, total_mass_kg
from pressfit.errors import PressfitError
from pressfit.mechanics import data_pool
from pressfit.mechanics.model import MachineModel, build_model
from pressfit.mechanics.statics import solve_equilibrium


@dataclass(frozen=True, kw_only=True)
class Modes:
    """The lowest natural modes at a pose (SI). Legs in kinematic order, modes by increasing frequency."""

    pose_m: np.ndarray  # (3,) nominal plate-centre pose h
    plate_wrench: np.ndarray  # (6,) static plate wrench of the equilibrium (N, N m), world axes at h
    frequencies_hz: np.ndarray  # (k,)
    shapes: np.ndarray  # (k, nv) mass-normalised generalised velocities phi of the VJM model
    plate_shapes: np.ndarray  # (k, 6) plate-centre translation (m) and rotation (rad) per phi, world axes
    leg_points_m: np.ndarray  # (n, p, 3) joint centres along each of the n legs, base to plate, at equilibrium
    leg_point_shapes: np.ndarray  # (k, n, p, 3) their displacement per phi (m)
    closure_residual: float  # max |J_c phi| over the modes (phi mass-normalised): linearised loop closure
    total_mass_kg: float
    equilibrium_residual: float  # worst relative residual of the static equilibrium (statics module)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: frequencies and the plate part of each mass-normalised shape (per unit modal
        coordinate, kg^-1/2: translation in m, rotation in rad, world axes)."""
        return {"pose_m": self.pose_m, "legs": len(self.leg_points_m), "plate_wrench": self.plate_wrench,
                "total_mass_kg": self.total_mass_kg,
                "frequencies_hz": self.frequencies_hz,
                "plate_shapes": [{"translation_m": s[:3], "rotation_rad": s[3:]} for s in self.plate_shapes],
                "closure_residual": self.closure_residual, "equilibrium_residual": self.equilibrium_residual}


def closure_jacobian(mm: MachineModel, model: pin.Model, data: pin.Data, q: np.ndarray) -> np.ndarray:
    """The (6 n, nv) loop-closure Jacobian of Pinocchio's frame-anchor constraints at q (n legs)."""
    pin.computeJointJacobians(model, data, q)
    cds = [cm.createData() for cm in mm.constraint_models]
    for cm, cd in zip(mm.constraint_models, cds, strict=True):
        cm.calc(model, data, cd)
    return np.array(pin.getConstraintsJacobian(model, data, mm.constraint_models, cds))


def elastic_stiffness(mm: MachineModel, q: np.ndarray) -> np.ndarray:
    """Diagonal (nv, nv) tangent stiffness of the virtual springs at q (N/m, N m/rad)."""
    k = np.zeros(mm.model.nv)
    for s in mm.springs:
        k[s.idx_v] += s.law.tangent(float(q[s.idx_q] - s.rest))
    return np.diag(k)


def mass_matrix(model: pin.Model, data: pin.Data, q: np.ndarray) -> np.ndarray:
    """Pinocchio's joint-space mass matrix (crba fills the upper triangle), symmetrised."""
    m = np.array(pin.crba(model, data, q))
    return np.triu(m) + np.triu(m, 1).T


@dataclass(frozen=True, kw_only=True)
class ReducedSystem:
    """Small vibrations about the static equilibrium at a pose, restricted to the linearised loop closures
    (module docstring): ``mass_kg`` M_r and ``stiffness`` K_r (r, r) on the orthonormal closure null-space
    ``basis`` (nv, r), so that M_r z'' + K_r z = basis^T tau. ``plate_map`` (6, r) maps z to the plate
    centre's translation (m) and rotation (rad), world axes: a world force F (N) and moment C (N m) at the
    plate centre are the reduced force ``plate_map.T @ [F, C]`` (the same map, by virtual work)."""

    mm: MachineModel
    model: pin.Model  # with the machine's masses (``inertial_model``)
    data: pin.Data
    q: np.ndarray  # (nq,) the static equilibrium configuration q*
    basis: np.ndarray  # (nv, r)
    stiffness: np.ndarray  # (r, r) K_r, SI (N/m, N m/rad in the joint coordinates)
    mass_kg: np.ndarray  # (r, r) M_r, SI (kg, kg m^2)
    plate_map: np.ndarray  # (6, r)
    plate_wrench: np.ndarray  # (6,) the static plate wrench (N, N m)
    equilibrium_residual: float


def reduced_system(machine: Machine, pose_m: np.ndarray, plate_wrench: np.ndarray | None = None,
                   mass_scale: float = 1.0) -> ReducedSystem:
    """:class:`ReducedSystem` at the reachable pose ``pose_m`` (m), loaded by ``plate_wrench`` (6,) (N, N m,
    world axes at the plate centre; default the weight of plate and tool), masses times ``mass_scale``; the
    actuator springs keep the rest lengths of the static solve (the drives hold their lengths)."""
    if not (math.isfinite(mass_scale) and mass_scale > 0):
        raise PressfitError(f"mass_scale must be a positive number, got {mass_scale!r}")
    mm = build_model(machine, pose_m)
    if plate_wrench is None:
        weight = mass_scale * (machine.mass.plate_mass_kg + machine.mass.tool_mass_kg) * GRAVITY_M_PER_S2
        plate_wrench = np.array([0.0, -weight, 0.0, 0.0, 0.0, 0.0])
    eq = solve_equilibrium(mm, mm.pose_m, plate_wrench)
    model = inertial_model(mm, mass_scale)
    data = data_pool.lend(model)
    q = eq.q
    basis = null_space(closure_jacobian(mm, model, data, q))
    rot = pin.Quaternion(q[3:7]).matrix()  # free-flyer velocity is in the plate frame
    plate_map = np.vstack([rot @ basis[0:3], rot @ basis[3:6]])
    return ReducedSystem(mm=mm, model=model, data=data, q=q, basis=basis,
                         stiffness=basis.T @ elastic_stiffness(mm, q) @ basis,
                         mass_kg=basis.T @ mass_matrix(model, data, q) @ basis, plate_map=plate_map,
                         plate_wrench=np.asarray(plate_wrench, dtype=float).reshape(6),
                         equilibrium_residual=eq.residuals.worst())


def natural_modes(machine: Machine, pose_m: np.ndarray, count: int = 6, plate_wrench: np.ndarray | None = None,
                  mass_scale: float = 1.0) -> Modes:
    """The ``count`` lowest modes at the reachable pose ``pose_m`` (m), loaded by ``plate_wrench`` (6,) (N, N m,
    world axes at the plate centre; default the weight of plate and tool), masses times ``mass_scale``."""
    if not (isinstance(count, int) and 1 <= count <= 60):
        raise PressfitError(f"count of modes must be an integer in [1, 60], got {count!r}")
    rs = reduced_system(machine, pose_m, plate_wrench, mass_scale)
    omega2, x = eigh(rs.stiffness, rs.mass_kg, subset_by_index=[0, count - 1])
    if omega2[0] <= 0:
        raise PressfitError(f"the restricted stiffness is not positive definite at pose {tuple(rs.mm.pose_m)} m "
                            f"(lowest eigenvalue {omega2[0]:.3g} s^-2): a mechanism, not a structure")
    phi = (rs.basis @ x).T
    closure = float(np.max(np.abs(closure_jacobian(rs.mm, rs.model, rs.data, rs.q) @ phi.T)))
    points, shapes = _leg_motion(rs.mm, rs.model, rs.data, rs.q, phi)
    return Modes(pose_m=rs.mm.pose_m.copy(), plate_wrench=rs.plate_wrench, frequencies_hz=np.sqrt(omega2) / (2 * np.pi),
                 shapes=phi, plate_shapes=(rs.plate_map @ x).T, leg_points_m=points, leg_point_shapes=shapes,
                 closure_residual=closure, total_mass_kg=total_mass_kg(rs.model),
                 equilibrium_residual=rs.equilibrium_residual)


def _leg_motion(mm: MachineModel, model: pin.Model, data: pin.Data, q: np.ndarray,
                phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint centres along each leg (spatially ordered, the actuator joint left out as it sits at the plate
    cardan) and their linear displacement per mode (LOCAL_WORLD_ALIGNED joint Jacobians; kinematics of
    ``closure_jacobian`` already computed at q)."""
    points, shapes = [], []
    for ids in mm.leg_joint_ids:
        joints = [j for j in range(ids["base_cardan"], ids["plate_end"] + 1) if j != ids["actuator"]]
        points.append([data.oMi[j].translation.copy() for j in joints])
        shapes.append([(pin.getJointJacobian(model, data, j, pin.LOCAL_WORLD_ALIGNED)[:3] @ phi.T).T
                       for j in joints])
    return np.array(points), np.array(shapes).transpose(2, 0, 1, 3)
