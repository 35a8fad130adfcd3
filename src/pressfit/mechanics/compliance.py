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
from pressfit.mechanics.statics import Equilibrium, EquilibriumSolver


def _response(eq: Equilibrium) -> np.ndarray:
    return np.concatenate([eq.plate_displacement_m, eq.plate_rotation_rad])


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
    """
    solver = EquilibriumSolver(machine, pose_m=pose_m)
    cols = []
    for j in range(6):
        if load is None:
            e = np.zeros(6)
            e[j] = 1.0
            cols.append(_response(solver.solve(pose_m, e, linear=True)))
        else:
            d = np.zeros(6)
            d[j] = step[0] if j < 3 else step[1]
            base = np.asarray(load, dtype=float)
            plus = _response(solver.solve(pose_m, base + d, preload=preload))
            minus = _response(solver.solve(pose_m, base - d, preload=preload))
            cols.append((plus - minus) / (2 * d[j]))
    return np.stack(cols, axis=1)


def pose_stiffness_report(machine: Machine, pose_m: np.ndarray, press_load_n: float = PRESS_LOAD_N) -> dict[str, object]:
    """Everything ``pressfit stiffness`` reports at one reachable pose (m), JSON-ready and SI: the condensed
    model's report (:func:`pressfit.mechanics.condensed.stiffness_report`), the same compliance from the
    Pinocchio model with their largest difference relative to its largest entry (an independent
    cross-check, ~1e-9), and the tangent compliance of the nonlinear equilibrium under the press load (+y)."""
    h = kinematics.require_reachable(machine, pose_m)
    out = condensed.stiffness_report(machine, h, press_load_n)
    c_pin = vjm_plate_compliance(machine, h)
    c_tan = vjm_plate_compliance(machine, h, load=np.array([0.0, press_load_n, 0.0, 0.0, 0.0, 0.0]))
    difference = np.abs(np.asarray(out["compliance_6x6"]) - c_pin).max() / np.abs(c_pin).max()
    return out | {"pinocchio_linear_compliance_6x6": c_pin.tolist(),
                  "condensed_vs_pinocchio_max_difference_relative": float(difference),
                  "tangent_compliance_6x6_under_press_load": c_tan.tolist(),
                  "tangent_vertical_stiffness_under_press_load_n_per_m": float(1.0 / c_tan[1, 1])}
