"""Cartesian compliance of the plate from the Pinocchio model (the reference for ``condensed``).

The plate's 6x6 compliance C maps a wrench at the plate centre (force N, moment N m, world axes) to
the plate-centre translation (m) and rotation (rad): rows/columns (x, y, z, rx, ry, rz).
"""

from __future__ import annotations

import numpy as np

from pressfit import kinematics
from pressfit.description.machine import Machine
from pressfit.mechanics import condensed
from pressfit.mechanics.condensed import PRESS_LOAD_N
from pressfit.mechanics.fast_statics import FastEquilibriumSolver


def vjm_plate_compliance(machine: Machine, pose_m: np.ndarray, load: np.ndarray | None = None,
                         preload: float | None = None, step: tuple[float, float] = (1.0, 0.1)) -> np.ndarray:
    """6x6 plate compliance at a pose, from the closed-loop Pinocchio VJM model (the closed form of the
    condensed model is :func:`pressfit.mechanics.condensed.condensed_plate_compliance`).

    Without ``load``: the small-displacement compliance, column j = the linear response to the unit
    wrench e_j (exact: the linear solve is linear). With ``load`` (6,) (and ``preload`` a4, N): the
    tangent compliance of the geometrically nonlinear equilibrium under that load, by central
    differences of nonlinear solves with steps ``step`` = (N, N m); the solver converges to ~1e-12
    relative, so the difference error is ~1e-12 * |load| / step (negligible), and the curvature error
    O(step^2) is below 1e-6 relative for the default steps.

    The 6 (12) solves and the base state (unloaded, or under ``load``) are one batch of
    :mod:`pressfit.mechanics.fast_statics` (equal to the Pinocchio solve to 1e-9 linear, 1e-7 nonlinear);
    the base state's stability is checked as the Pinocchio solve checks it (raises UnstableEquilibriumError;
    the steps are small perturbations of it).
    """
    solver = FastEquilibriumSolver(machine, pose_m=pose_m)
    pose = np.asarray(pose_m, dtype=float)
    if load is None:  # column j: the response to the unit wrench e_j
        base, d, preload = np.zeros(6), np.eye(6), None
        wrenches = np.concatenate([d, base[None]])
    else:
        base, d = np.asarray(load, dtype=float), np.diag([step[0]] * 3 + [step[1]] * 3)
        wrenches = np.concatenate([base + d, base - d, base[None]])
    batch = solver.solve_batch(np.broadcast_to(pose, (len(wrenches), 3)), wrenches, preload=preload,
                               linear=load is None)
    solver.equilibrium(batch, len(wrenches) - 1)  # the stability check of the base state
    resp = np.concatenate([batch.plate_displacement_m, batch.plate_rotation_rad], 1).T[:, :-1]
    return resp if load is None else (resp[:, :6] - resp[:, 6:]) / (2 * np.diag(d))


def pose_stiffness_report(
    machine: Machine, pose_m: np.ndarray, press_load_n: float = PRESS_LOAD_N
) -> dict[str, object]:
    """Everything ``pressfit stiffness`` reports at one reachable pose (m), JSON-ready and SI: the condensed model's
    report (:func:`pressfit.mechanics.condensed.stiffness_report`), the same compliance from the Pinocchio model
    with their largest difference relative to its largest entry (an independent cross-check, ~1e-9), the tangent
    compliance of the nonlinear equilibrium under the press load (+y), and the compliance along the press as the
    drives' position sensors see it (``sensed_vertical_compliance_m_per_n``,
    :func:`pressfit.mechanics.condensed.condensed_plate_compliance` of ``machine.sensed_view``: less a hydraulic
    cylinder's oil column, which its piston sensor reads past; the number ``simulate``, ``curve`` and ``curves check
    --compensate`` use)."""
    h = kinematics.require_reachable(machine, pose_m)
    out = condensed.stiffness_report(machine, h, press_load_n)
    c_pin = vjm_plate_compliance(machine, h)
    c_tan = vjm_plate_compliance(machine, h, load=np.array([0.0, press_load_n, 0.0, 0.0, 0.0, 0.0]))
    difference = np.abs(np.asarray(out["compliance_6x6"]) - c_pin).max() / np.abs(c_pin).max()
    return out | {"pinocchio_linear_compliance_6x6": c_pin.tolist(),
                  "condensed_vs_pinocchio_max_difference_relative": float(difference),
                  "tangent_compliance_6x6_under_press_load": c_tan.tolist(),
                  "tangent_vertical_stiffness_under_press_load_n_per_m": float(1.0 / c_tan[1, 1]),
                  "sensed_vertical_compliance_m_per_n":
                      float(condensed.condensed_plate_compliance(machine.sensed_view, h)[1, 1])}
