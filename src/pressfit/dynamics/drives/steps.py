r"""Whether a simulation's time step can integrate a hydraulic drive's oil column (plan time, before a run).

The mass each oil column k_h(l) acts on, per leg at a pose: on the rigid model the plate's apparent mass along
the leg, m_i = 1 / (a_i^T M_h^-1 a_i) (M_h the apparent Cartesian mass, Pinocchio's constraint dynamics at
rest, gravity off; a_i the leg's unit vector); on the flexible model the actuator joint's own entry of the
mass matrix (the piston, rod and what the joint carries, the other coordinates held). Both are Rayleigh
quotients of the coupled system, so sqrt(k_h / m_i) is a lower bound of its fastest oil-column frequency: a
step refused on it cannot be stable (:func:`pressfit.dynamics.drives.hydraulic.oil_column_step_index`).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pressfit import kinematics
from pressfit.description.machine import Machine
from pressfit.dynamics.drives.hydraulic import refuse_step
from pressfit.dynamics.inertia import inertial_model
from pressfit.dynamics.multibody import inverse_apparent_mass
from pressfit.mechanics.model import build_model


def leg_masses_kg(machine: Machine, pose_m: np.ndarray, model: str) -> np.ndarray:
    """The mass (4,), kg, each actuator pushes at ``pose_m`` (m) on ``model`` ("rigid" or "flexible") (module doc)."""
    pose = np.asarray(pose_m, dtype=float)
    if model == "flexible":
        mm = build_model(machine, pose)
        inertial = inertial_model(mm)
        mass = pin.crba(inertial, inertial.createData(), mm.q0)
        act = [inertial.joints[ids["actuator"]].idx_v for ids in mm.leg_joint_ids]
        return np.array([mass[k, k] for k in act])
    inverse = inverse_apparent_mass(machine, pose)
    a = kinematics.inverse_kinematics(machine, pose).unit_vectors  # (4, 3)
    return 1.0 / np.einsum("ij,jk,ik->i", a, inverse, a)


def hydraulic_step_refusal(machine: Machine, waypoints_m: np.ndarray, path_m: np.ndarray, model: str,
                           dt_s: float) -> str | None:
    """None when ``dt_s`` integrates the oil columns over the planned ``path_m`` (n, 3) on ``model``, else the
    reason (:func:`pressfit.dynamics.drives.hydraulic.refuse_step`): per leg the stiffest column over the path
    (k_h is largest at the ends of the stroke) on the lightest of the masses at the ``waypoints_m`` (the mass
    changes slowly with the pose). Not hydraulic: None."""
    if machine.actuator.kind != "hydraulic":
        return None
    lengths = np.array([kinematics.inverse_kinematics(machine, p).lengths_m for p in np.atleast_2d(path_m)])
    stiffest = lengths[np.argmax(machine.drive_stiffness_n_per_m(lengths), axis=0), np.arange(4)]
    masses = np.min([leg_masses_kg(machine, p, model) for p in np.atleast_2d(waypoints_m)], axis=0)
    return refuse_step(machine, stiffest[None, :], masses[None, :], dt_s)
