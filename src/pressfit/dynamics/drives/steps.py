r"""Whether a simulation's time step can integrate a hydraulic drive's oil column (plan time, before a run).

Only the rigid model needs the check: it steps the drive explicitly (the drive at the rate of the start of the
step, then one semi-implicit Euler step of the mechanics), stable while omega_h dt < 2
(:func:`pressfit.dynamics.drives.hydraulic.oil_column_step_index`). The mass each oil column k_h(l) acts on, per
leg at a pose, is the plate's apparent mass along the leg, m_i = 1 / (a_i^T M_h^-1 a_i) (M_h the apparent
Cartesian mass, Pinocchio's constraint dynamics at rest, gravity off; a_i the leg's unit vector): a Rayleigh
quotient of the coupled system, so sqrt(k_h / m_i) is a lower bound of its fastest oil-column frequency and a
step refused on it cannot be stable. The flexible model takes the drive inside its implicit step (the oil
column like the legs' springs: :mod:`pressfit.dynamics.machine.flexible`, "Drives in the step"), stable at any
step: nothing to check there.
"""

from __future__ import annotations

import numpy as np

from pressfit import kinematics
from pressfit.description.machine import Machine
from pressfit.dynamics import drives
from pressfit.dynamics.drives.hydraulic import refuse_step
from pressfit.dynamics.multibody import inverse_apparent_mass


def leg_masses_kg(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """The plate's apparent mass (per leg, kg) along each leg at ``pose_m`` (m) on the rigid model (module doc)."""
    inverse = inverse_apparent_mass(machine, np.asarray(pose_m, dtype=float))
    a = kinematics.inverse_kinematics(machine, pose_m).unit_vectors  # (legs, 3)
    return 1.0 / np.einsum("ij,jk,ik->i", a, inverse, a)


def hydraulic_step_refusal(machine: Machine, waypoints_m: np.ndarray, path_m: np.ndarray, elastic: bool,
                           dt_s: float) -> str | None:
    """None when ``dt_s`` integrates the oil columns over the planned ``path_m`` (n, 3), else the
    reason (:func:`pressfit.dynamics.drives.hydraulic.refuse_step`): per leg the stiffest column over the path
    (k_h is largest at the ends of the stroke) on the lightest of the masses at the ``waypoints_m`` (the mass
    changes slowly with the pose). A drive without an ``explicit_spring`` (not hydraulic), or an ``elastic`` model
    (the flexible machine steps the column implicitly, module doc): None."""
    if not drives.drive_type(machine).explicit_spring or elastic:
        return None
    lengths = np.array([kinematics.inverse_kinematics(machine, p).lengths_m for p in np.atleast_2d(path_m)])
    legs = np.arange(lengths.shape[1])
    stiffest = lengths[np.argmax(machine.drive_stiffness_n_per_m(lengths), axis=0), legs]
    masses = np.min([leg_masses_kg(machine, p) for p in np.atleast_2d(waypoints_m)], axis=0)
    return refuse_step(machine, stiffest[None, :], masses[None, :], dt_s)
