r"""Insertion over preload and joint clearance (issue 11 item 8): does the commanded preload remove, in the
time domain, the tool error that the cardans' play causes?

Each (preload a4, clearance g) pair runs the case's insertion scenario (:func:`pressfit.dynamics.insertion.
simulate_insertion`, with the limiter) with every cardan given the axial play g and the clearance in the loop
(``[simulation] clearance = true``: the load-deflection curve of :mod:`pressfit.mechanics.clearance` at the
insertion pose, in series at the tool). The controller estimates the plate from the actuator lengths, so the
play is invisible to it: it shows as the offset of the tool from the estimate, ``hidden_error_m`` (3D, at the
end of the dwell, under the steady insertion force). Without preload the joints sit centred and the first
newtons of contact force take up the play: the plate moves by the lost motion (2g / sin(alpha) at pose A).
With a4 above the critical preload (:func:`pressfit.mechanics.clearance.critical_preload`, every joint kept
closed by the press load up to the insertion force limit, ``[simulation.controller] force_limit_n``: a property
of the clearance, the pose and the limit, never of the other preloads asked for; the overshoot above the limit
is reported per run) the offset is the elastic deflection alone, as with g = 0. The study
reports, per pair, that offset, its difference from the same preload with g = 0 (the play's share, ``play_error_m``,
the norm of the vector difference), the lateral
tool error at the pin, the peak contact force and its overshoot over the limit. The weight of the moving parts
is not in the clearance curve (it starts from the unloaded, preloaded state), so the lost motion is that from
centred joints: an upper bound on the closed-joint case, half the end-to-end play. On the flexible model
(``[simulation] model = "flexible"``) the plays sit between the drives and the legs instead
(:mod:`pressfit.dynamics.play`, the sensors zeroed at the start), so the play's share also counts the legs whose
tension changes sign along the path (gravity, inertia), which the rigid model's curve does not see.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from tqdm import tqdm

from pressfit.description.cases import Case, ClearanceSpec, Preload
from pressfit.dynamics.insertion import InsertionResult, plan_scenario, simulate_insertion
from pressfit.errors import PressfitError
from pressfit.mechanics.clearance import clearance_from_case, critical_preload

COLUMNS = ("preload_n", "clearance_m", "critical_preload_n", "hidden_error_m", "play_error_m",
           "lateral_error_m", "peak_contact_force_n", "overshoot_n", "steady_insertion_force_n")


@dataclass(frozen=True, kw_only=True)
class InsertionStudy:
    """Rows (one per preload x clearance, preload varying fastest) of ``COLUMNS`` (SI), the insertion pose."""

    case: str
    pose_m: np.ndarray
    rows: np.ndarray

    def column(self, name: str) -> np.ndarray:
        return self.rows[:, COLUMNS.index(name)]

    def to_dict(self) -> dict[str, Any]:
        return {"case": self.case, "insertion_pose_m": self.pose_m, "columns": list(COLUMNS), "rows": self.rows}


def _hidden_error_m(result: InsertionResult) -> np.ndarray:
    """tool - length-based estimate (3,), m, at the end of the dwell."""
    last = np.flatnonzero(result.phases == result.phase_names.index("dwell"))[-1]
    tool = result.series[last, [result.columns.index(f"tool_{a}_m") for a in "xyz"]]
    estimate = result.series[last, [result.columns.index(f"est_{a}_m") for a in "xyz"]]
    return tool - estimate


def _variant(case: Case, preload_n: float, gap_m: float, legs: int) -> Case:
    """The case with every one of its machine's 2 ``legs`` cardans given the play gap_m (m) and the preload (N)."""
    sim = case.simulation.model_copy(update={"clearance": True})
    spec = (case.clearance or ClearanceSpec()).model_copy(update={"gaps_m": [gap_m] * (2 * legs), "random_m": None})
    return case.model_copy(update={"simulation": sim, "clearance": spec,
                                   "preload": Preload(mode="force", a4_n=preload_n)})


def insertion_study(case: Case, preloads_n: list[float], clearances_m: list[float],
                    progress: bool = False) -> InsertionStudy:
    """Run the grid (module docstring); preloads in N (force mode), clearances in m."""
    if case.simulation is None:
        raise PressfitError(f"{case.path}: the case has no [simulation] table")
    if not preloads_n or not clearances_m:
        raise PressfitError("give at least one preload and one clearance")
    machine = case.machine()
    pose = np.array([*case.simulation.contact.pin_position_m[:1], case.simulation.contact.board_height_m
                     - case.simulation.interference_m, case.simulation.contact.pin_position_m[1]])
    grid = [(p, g) for g in [0.0, *clearances_m] for p in preloads_n]
    legs = len(machine.legs)
    for p in preloads_n:  # refused up front (a preload that saturates the drives, ...), not as a failed run
        plan_scenario(_variant(case, p, 0.0, legs), machine,
                      preload_key=f"the study's preload {p:g} N ([preload] a4_n)")
    results = {}
    for p, g in tqdm(grid, desc="insertion study", unit="run", disable=not progress):
        variant = _variant(case, p, g, legs)
        results[p, g] = simulate_insertion(variant, limiter=True)
    rows = []
    limit_n = case.simulation.controller.force_limit_n
    for g in clearances_m:
        clearance = clearance_from_case(_variant(case, 0.0, g, legs), machine)
        critical = critical_preload(machine, pose, [0.0, 1.0, 0.0], limit_n, clearance).preload if g > 0 else 0.0
        for p in preloads_n:
            s, hidden = results[p, g].summary, _hidden_error_m(results[p, g])
            play = np.linalg.norm(hidden - _hidden_error_m(results[p, 0.0]))
            rows.append((p, g, critical, np.linalg.norm(hidden), play,
                         s["tool_lateral_error_at_insertion_m"], s["peak_contact_force_n"], s["overshoot_n"],
                         s["steady_insertion_force_n"]))
    return InsertionStudy(case=case.name, pose_m=pose, rows=np.array(rows, dtype=float))
