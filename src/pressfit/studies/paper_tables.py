"""The paper's Tables 5 and 6 beside pressfit's solution, entry by entry.

The paper's multibody model (rigid legs, locked actuators) reports, per CAD leg, the force and moment
components at the fixed joint that stands for the locked actuator (our ``actuator`` section), in a
leg frame whose figure is lost. The comparison uses an explicit map, stated once here:

* legs: CAD legs (1, 2, 3, 4) = kinematic legs ``reference.leg_order`` = (1, 3, 4, 2);
* axial force: ``F_z(paper) = axial_sign * N`` with ``axial_sign = -1`` (the paper prints compression
  positive, i.e. its z axis runs from the plate to the base);
* torsion: ``M_z(paper) = axial_sign * T`` (the same reversed z axis);
* bending is compared by its magnitude M_bend = sqrt(M_x^2 + M_y^2), which does not depend on how the leg's
  x and y axes are turned about the leg axis. The paper's x/y axes cannot be recovered: in case B its
  CAD legs 2 and 3, mirror images of each other, carry their bending in M_y and in M_x respectively, so
  each CAD leg frame was oriented on its own. The printed M_x, M_y (and the shears F_x, F_y) are listed
  beside ours (our M_x, M_y, V_x, V_y with y reversed like z), without a relative error.

The paper's model was rigid, so it is compared with the linear solution (the rigid limit where the
case's symmetry fixes the answer); the geometrically nonlinear solution is shown beside it.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from pressfit.description.cases import Case, load_case
from pressfit.errors import PressfitError
from pressfit.mechanics.statics import Equilibrium, EquilibriumSolver
from pressfit.shipped import cases_dir

QUANTITIES = ("F_x", "F_y", "F_z", "M_x", "M_y", "M_bend", "M_z")
COMPARED = {"F_z", "M_bend", "M_z"}  # frame-independent entries; the others are listed, not compared
PAPER_CASES = cases_dir() / "paper"
NEGLIGIBLE = {"F": 1e-3, "M": 1e-3}  # N, N m: entries below this on both sides count as "~0"


@dataclass(frozen=True, kw_only=True)
class TableEntry:
    """One printed entry of Table 5 (forces, N) or Table 6 (moments, N m) and ours beside it."""

    case: str
    quantity: str  # F_x ... M_z in the paper's axes
    cad_leg: int
    kinematic_leg: int
    paper: float
    linear: float  # ours, linear (rigid-limit) solve, mapped to the paper's axes and signs
    nonlinear: float  # ours, geometrically nonlinear solve, same map
    relative_error: float  # (linear - paper) / |paper|; nan when both are negligible or not compared
    compared: bool  # False for the frame-dependent entries (F_x, F_y, M_x, M_y): listed only

    @property
    def table(self) -> str:
        return "Table 5" if self.quantity.startswith("F") else "Table 6"

    def as_dict(self) -> dict[str, object]:
        """JSON-ready; ``relative_error`` is null where it is not defined (negligible or not compared)."""
        d = asdict(self)
        d["relative_error"] = None if np.isnan(self.relative_error) else self.relative_error
        return d

    @property
    def verdict(self) -> str:
        if not self.compared:
            return "listed (frame)"
        return "~0 both" if np.isnan(self.relative_error) else f"{100 * self.relative_error:+.1f}%"


def paper_components(eq: Equilibrium, leg: int, axial_sign: int) -> dict[str, float]:
    """Our actuator-section resultants of kinematic ``leg`` (1-based) in the paper's axes (module doc)."""
    s = eq.legs[leg - 1].sections["actuator"]
    flip = axial_sign  # -1: the paper's z axis is reversed, so y is reversed too
    return {"F_x": s.V_x, "F_y": flip * s.V_y, "F_z": flip * s.N,
            "M_x": s.M_x, "M_y": flip * s.M_y, "M_bend": float(np.hypot(s.M_x, s.M_y)), "M_z": flip * s.T}


@dataclass(frozen=True, kw_only=True)
class CaseSolution:
    """A paper case and its two solutions: linear (the rigid-limit comparison) and geometrically nonlinear."""

    case: Case
    linear: Equilibrium
    nonlinear: Equilibrium


def solve_case(case: Case) -> CaseSolution:
    """Solve a paper case (its first pose and load) linearly and nonlinearly."""
    if case.reference is None:
        raise PressfitError(f"{case.path}: case {case.name} has no [reference] table to compare with")
    machine = case.machine()
    machine.require_legs("the paper's tables (a 4-UPU)", 4)
    pose, wrench = case.poses.array()[0], case.loads.wrenches()[0]
    solver = EquilibriumSolver(machine, pose_m=pose)
    return CaseSolution(case=case, linear=solver.solve(pose, wrench, linear=True),
                        nonlinear=solver.solve(pose, wrench, linear=False))


def compare_solution(solution: CaseSolution) -> list[TableEntry]:
    """Line up a solved paper case with its printed reference."""
    lin, nonlin, ref = solution.linear, solution.nonlinear, solution.case.reference
    out = []
    for q in QUANTITIES:
        for cad, kin in enumerate(ref.leg_order, start=1):
            paper = (float(np.hypot(ref.values["M_x"][cad - 1], ref.values["M_y"][cad - 1])) if q == "M_bend"
                     else ref.values[q][cad - 1])
            a = paper_components(lin, kin, ref.axial_sign)[q]
            b = paper_components(nonlin, kin, ref.axial_sign)[q]
            tiny = NEGLIGIBLE[q[0]]
            compared = q in COMPARED
            err = np.nan if not compared or max(abs(paper), abs(a)) < tiny else (a - paper) / abs(paper)
            out.append(TableEntry(case=solution.case.name, quantity=q, cad_leg=cad, kinematic_leg=kin, paper=paper,
                                  linear=a, nonlinear=b, relative_error=float(err), compared=compared))
    return out


def compare_case(case: Case) -> list[TableEntry]:
    """Solve a paper case (linear and nonlinear) and line it up with its printed reference."""
    return compare_solution(solve_case(case))


def solve_paper_cases(directory: Path = PAPER_CASES) -> list[CaseSolution]:
    """The paper's cases A, B and C, solved."""
    return [solve_case(load_case(directory / f"{name}.toml")) for name in "ABC"]


def paper_tables(directory: Path = PAPER_CASES, solutions: list[CaseSolution] | None = None) -> list[TableEntry]:
    """Every entry of Tables 5 and 6 for the paper's cases A, B and C (from ``solutions`` when given)."""
    return [e for s in (solve_paper_cases(directory) if solutions is None else solutions) for e in compare_solution(s)]


ROUND_OFF = 1e-9  # an entry below this fraction of its table's scale (the case's largest |value|) is printed 0
TABLES = (("Table 5", "forces (N)"), ("Table 6", "moments (N m)"))


def shown_value(x: float, scale: float) -> str:
    """An entry as printed: 4 significant digits; round-off (|x| at most ``ROUND_OFF`` x ``scale``, the table's
    largest |value|) and anything that would print as -0 are "0"."""
    if abs(x) <= ROUND_OFF * scale:
        return "0"
    text = f"{x:.4g}"
    return "0" if float(text) == 0.0 else text


def case_table(entries: list[TableEntry], case: str, table: str) -> tuple[list[str], list[list[str]]]:
    """One case's part of Table 5 or 6 as the paper prints it: a row per CAD leg (its kinematic leg beside it),
    per component the paper's value beside pressfit's linear one, and the relative error of the compared
    components (:attr:`TableEntry.verdict`); every value printed with :func:`shown_value` at the case's scale."""
    mine = [e for e in entries if e.case == case and e.table == table]
    scale = max((max(abs(e.paper), abs(e.linear)) for e in mine), default=0.0)
    quantities = [q for q in QUANTITIES if any(e.quantity == q for e in mine)]
    header = ["CAD leg (kin.)"]
    for q in quantities:
        header += [f"{q} paper", f"{q} pressfit"] + ([f"{q} rel. error"] if q in COMPARED else [])
    rows = []
    for cad in sorted({e.cad_leg for e in mine}):
        by = {e.quantity: e for e in mine if e.cad_leg == cad}
        row = [f"{cad} ({by[quantities[0]].kinematic_leg})"]
        for q in quantities:
            e = by[q]
            row += [shown_value(e.paper, scale), shown_value(e.linear, scale)] + ([e.verdict] if e.compared else [])
        rows.append(row)
    return header, rows


def to_markdown(entries: list[TableEntry]) -> str:
    """Tables 5 and 6 as the paper prints them (:func:`case_table`: per case, components by leg), the paper
    beside pressfit's linear solution with the relative errors; the nonlinear solution is in tables.csv."""
    cases = list(dict.fromkeys(e.case for e in entries))
    lines = []
    for table, title in TABLES:
        lines += [f"### {table}: {title}, paper vs pressfit (actuator section, paper's axes and signs)", "",
                  "rel. error = (pressfit linear - paper) / |paper|, signed in the paper's axes; '~0 both' when "
                  "both are below 1e-3; round-off (below 1e-9 of the case's largest entry) printed 0; the "
                  "nonlinear solution is in tables.csv and tables.json.", ""]
        for case in cases:
            header, rows = case_table(entries, case, table)
            lines += [f"**{case}**", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
            lines += ["| " + " | ".join(r) + " |" for r in rows]
            lines.append("")
    return "\n".join(lines)


def to_rows(entries: list[TableEntry]) -> tuple[list[str], list[list[object]]]:
    header = list(asdict(entries[0]).keys())
    return header, [list(asdict(e).values()) for e in entries]
