"""What the paper's CAD model was: a weighted least-squares identification from Tables 5 and 6.

A hypothesis, not a replacement for Table 3 (which stays the default geometry). The paper computed its
Tables 5-6 on a rigid multibody model of a CAD geometry that it says "should not be considered
necessarily similar" to the final machine, and it does not print case B's pose. This module asks which
undisclosed quantities make pressfit's rigid-limit (linear, :func:`pressfit.mechanics.condensed.solve_linear`)
solution reproduce every printed entry, and how well the printed entries determine them.

Parameters (SI):

* ``base_half_side_m`` p and ``plate_half_side_m`` r: radial joint offsets (Table 3: 0.442 m, 0.082 m);
* ``base_joint_height_m`` h_b and ``plate_joint_height_m`` h_p: heights of the base cardan centres above
  the base plane and of the plate cardan centres above the plate centre (the load point), Table 3: 0;
* case B's pose ``B_x_m``, ``B_y_m``, ``B_z_m`` (not printed; start: the axial-force fit (0.2765, 0.72, -0.2765));
* case C's pose ``C_x_m``, ``C_y_m`` and ``C_dz_m``: C is "leg 1 vertical", z_h = -(p - r) + C_dz (start 0,
  0.72, 0), so C_x = C_dz = 0 means the pose is exactly as stated;
* per case a self-stress ``<case>_self_stress_n`` a (N): the axial forces become N + a v_p (v_p the unit null
  vector of equation 5, v_1 < 0). A rigid model with locked actuators is statically indeterminate along
  v_p; any a balances the load, so a is whatever the paper's solver left there (0 = the elastic split).

Case A's pose stays (0, 0.72, 0) (its y only sets the leg angle together with h_p - h_b).

Data: every printed axial force F_z, torsion M_z and bending magnitude hypot(M_x, M_y) of Tables 5-6
(36 entries; the shears F_x, F_y are ~1e-4 N in the paper and exactly 0 in a rigid model: they carry no
information). The map from the paper's CAD legs, signs and axes is :mod:`pressfit.studies.paper_tables`'s.
Each entry is weighted by 1 / sigma with sigma = hypot(half a unit of its last printed digit, floor);
the floor (1e-3 N or N m) is five times the largest entry that vanishes by symmetry in case A (2e-4),
i.e. the paper solver's own noise. Case C's printed F_z of CAD leg 1 breaks vertical equilibrium; the
fit is run with it as printed and with its leg frame reversed (F_z and M_z negated) and both costs are
reported.

Uncertainties: the covariance (J^T J)^+ of the weighted Jacobian J at the optimum, multiplied by the
reduced chi-square when it exceeds 1 (the model then misses the data by more than the rounding, and the
scatter of the residuals is the honest noise level). Identifiability: singular values of J with its
columns scaled to unit norm (unit-free; a zero singular value is an exact degeneracy), the physical
parameter combinations along the null directions (not determined by the tables), and correlations.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from decimal import Decimal
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from pressfit.description.cases import Case, load_case
from pressfit.description.machine import Machine
from pressfit.errors import PressfitError
from pressfit.kinematics import actuator_forces_min_norm, preload_vector
from pressfit.mechanics.condensed import solve_linear
from pressfit.studies.paper_tables import PAPER_CASES

CASES = ("A", "B", "C")
QUANTITIES = ("F_z", "M_z", "M_bend")  # the frame-independent printed entries (paper_tables.COMPARED)
FLOOR = 1e-3  # N or N m: the paper solver's noise level, see the module docstring


@dataclass(frozen=True, kw_only=True)
class Parameter:
    """One quantity of the CAD model: name (with unit suffix), starting value (Table 3 / case files), and
    whether the fit adjusts it (the joint heights are held: the tables cannot determine them)."""

    name: str
    initial: float
    meaning: str
    fitted: bool = True


def parameters(cases: dict[str, Case]) -> tuple[Parameter, ...]:
    """The CAD model's parameters and their starting values, read from the paper case files (SI)."""
    g = cases["A"].machine().geometry
    a, b, c = (cases[n].poses.array()[0] for n in CASES)
    return (Parameter(name="base_half_side_m", initial=g.base_half_side_m,
                      meaning="p, radial base joint offset (sets the scale)", fitted=False),
            Parameter(name="plate_half_side_m", initial=g.plate_half_side_m, meaning="r, radial plate joint offset"),
            Parameter(name="base_joint_height_m", initial=g.base_joint_height_m,
                      meaning="h_b, base cardans above the base", fitted=False),
            Parameter(name="plate_joint_height_m", initial=g.plate_joint_height_m,
                      meaning="h_p, plate cardans above the load", fitted=False),
            Parameter(name="A_y_m", initial=float(a[1]), meaning="case A pose y_h (x_h = z_h = 0)"),
            Parameter(name="B_x_m", initial=float(b[0]), meaning="case B pose x_h"),
            Parameter(name="B_y_m", initial=float(b[1]), meaning="case B pose y_h"),
            Parameter(name="B_z_m", initial=float(b[2]), meaning="case B pose z_h"),
            Parameter(name="C_x_m", initial=float(c[0]), meaning="case C pose x_h"),
            Parameter(name="C_y_m", initial=float(c[1]), meaning="case C pose y_h"),
            Parameter(name="C_dz_m", initial=0.0, meaning="case C: z_h + (p - r), 0 when leg 1 is vertical"),
            *(Parameter(name=f"{n}_self_stress_n", initial=0.0, meaning=f"case {n}: axial self-stress a along v_p")
              for n in CASES),
            *(Parameter(name=f"{n}_couple_self_stress_nm", initial=0.0,
                        meaning=f"case {n}: couple self-stress b along w_c") for n in CASES))


@dataclass(frozen=True, kw_only=True)
class PrintedTables:
    """The fitted data: values and sigmas (N, N m) of shape (case A..C, quantity F_z/M_z/M_bend, CAD leg 1..4)."""

    values: np.ndarray
    sigma: np.ndarray
    c_leg1_reversed: bool  # case C's CAD leg 1 read with its leg frame reversed (F_z, M_z negated)


def _half_unit(printed: float) -> float:
    """Half a unit of the last digit of a printed number (its shortest decimal representation)."""
    return 0.5 * 10.0 ** Decimal(repr(abs(float(printed)))).as_tuple().exponent


def printed_tables(cases: dict[str, Case], c_leg1_reversed: bool = True, floor: float = FLOOR) -> PrintedTables:
    """Tables 5-6's frame-independent entries of the paper cases, with their rounding sigmas."""
    values, sigma = np.empty((3, 3, 4)), np.empty((3, 3, 4))
    for i, name in enumerate(CASES):
        ref = cases[name].reference
        if ref is None:
            raise PressfitError(f"{cases[name].path}: case {name} has no [reference] table to fit")
        v = ref.values
        half = {q: np.array([_half_unit(x) for x in v[q]]) for q in ("F_z", "M_x", "M_y", "M_z")}
        values[i] = [v["F_z"], v["M_z"], np.hypot(v["M_x"], v["M_y"])]
        sigma[i] = np.hypot([half["F_z"], half["M_z"], np.hypot(half["M_x"], half["M_y"])], floor)
    if c_leg1_reversed:
        values[2, :2, 0] *= -1
    return PrintedTables(values=values, sigma=sigma, c_leg1_reversed=c_leg1_reversed)


def configure(cases: dict[str, Case], theta: np.ndarray) -> list[tuple[Machine, np.ndarray, float]]:
    """(machine, pose m, self-stress N) of cases A, B, C for parameter values ``theta`` (order of
    :func:`parameters`)."""
    p, r, hb, hp, ay, bx, by, bz, cx, cy, cdz, sa, sb, sc, ta, tb, tc = (float(t) for t in theta)
    geometry = {"geometry": {"base_half_side_m": p, "plate_half_side_m": r, "base_joint_height_m": hb,
                             "plate_joint_height_m": hp}}
    poses = {"A": np.array([0.0, ay, 0.0]), "B": np.array([bx, by, bz]), "C": np.array([cx, cy, r - p + cdz])}
    stress = {"A": (sa, ta), "B": (sb, tb), "C": (sc, tc)}
    return [(cases[n].machine().with_overrides(geometry, f"cad-fit {n}"), poses[n], *stress[n]) for n in CASES]


def couple_null_vector(couple_directions: np.ndarray) -> np.ndarray:
    """w_c: the unit self-equilibrated set of leg couples, sum_i w_i c_i = 0 (4,), with w_1 >= 0 (like v_p's
    v_1 < 0 convention: a fixed sign, so that the couple self-stress is a smooth parameter)."""
    w = np.linalg.svd(np.asarray(couple_directions).T)[2][-1]
    return w if w[0] >= 0 else -w


def predict(cases: dict[str, Case], theta: np.ndarray) -> np.ndarray:
    """pressfit's rigid-limit entries (3, 3, 4) in the paper's legs, axes and signs for ``theta``."""
    out = np.empty((3, 3, 4))
    for i, (machine, pose, stress, couple_stress) in enumerate(configure(cases, theta)):
        ref = cases[CASES[i]].reference
        res = solve_linear(machine, pose, cases[CASES[i]].loads.wrenches()[0])
        n = res.axial_forces_n + stress * preload_vector(machine, pose)
        cpl = res.couples_nm + couple_stress * couple_null_vector(res.couple_directions)
        cos_beta = np.sum(res.couple_directions * res.leg_unit_vectors, -1)  # c_i . e_i (condensed module)
        kin = np.array(ref.leg_order) - 1
        torsion, bending = cpl * cos_beta, np.abs(cpl) * np.sqrt(np.maximum(1.0 - cos_beta**2, 0.0))
        out[i] = [ref.axial_sign * n[kin], ref.axial_sign * torsion[kin], bending[kin]]
    return out


# --- the fit -------------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class FittedParameter:
    """A parameter at the optimum; ``std`` is inf when the tables do not determine it (or it is held)."""

    name: str
    meaning: str
    initial: float
    value: float
    std: float
    fitted: bool
    determined: bool


@dataclass(frozen=True, kw_only=True)
class EntryResidual:
    """One printed entry (N or N m, the paper's axes and signs) beside the Table 3 model and the fitted one."""

    case: str
    quantity: str
    cad_leg: int
    printed: float  # as fitted (case C CAD leg 1 F_z and M_z negated when its frame is read reversed)
    sigma: float  # rounding sigma
    table3: float  # pressfit with Table 3's geometry, the case files' poses, no self-stress
    fitted: float  # pressfit with the fitted CAD model

    @property
    def table3_residual(self) -> float:
        return self.table3 - self.printed

    @property
    def fit_residual(self) -> float:
        return self.fitted - self.printed


@dataclass(frozen=True, kw_only=True)
class Identifiability:
    """What the tables determine. ``singular_values``: of the weighted Jacobian over all parameters (held ones
    included) with unit-norm columns (unit-free; exact degeneracies show as ~1e-9 or less). For each held
    parameter, ``held_directions`` gives the first-order change of the fitted parameters that compensates a
    unit change of it, and ``held_sensitivity`` the weighted residual change that is left (0: the tables
    cannot see that parameter at all). ``correlations`` are those of the fitted parameters."""

    singular_values: tuple[float, ...]  # descending
    held_directions: dict[str, dict[str, float]]
    held_sensitivity: dict[str, float]  # |J d| per unit (1 m) of the held parameter, in sigmas
    fitted_names: tuple[str, ...]
    correlations: np.ndarray  # (n_fitted, n_fitted)

    def strongest_correlations(self, threshold: float = 0.9) -> list[tuple[str, str, float]]:
        """Pairs of fitted parameters with |correlation| >= threshold, strongest first."""
        n = len(self.fitted_names)
        pairs = [(self.fitted_names[i], self.fitted_names[j], float(self.correlations[i, j]))
                 for i in range(n) for j in range(i + 1, n) if abs(self.correlations[i, j]) >= threshold]
        return sorted(pairs, key=lambda t: -abs(t[2]))


@dataclass(frozen=True, kw_only=True)
class SplitVerdict:
    """Case C's axial split: the fitted self-stress beside what the physical rules would give (N)."""

    self_stress_n: float  # fitted a_C (0 = pressfit's elastic split)
    self_stress_std_n: float
    min_norm_self_stress_n: float  # a that turns the elastic split into the minimum-norm one (eq. 5)
    vertical_balance_printed_n: float  # sum of the printed axial forces' vertical components, as printed
    vertical_balance_reversed_n: float  # the same with CAD leg 1 read reversed (the load is 700 N)
    verdict: str


@dataclass(frozen=True, kw_only=True)
class CadFit:
    """The identified CAD model, its residuals, uncertainties and identifiability (SI units)."""

    parameters: tuple[FittedParameter, ...]
    entries: tuple[EntryResidual, ...]
    chi_square: float  # sum of squared weighted residuals at the optimum
    chi_square_table3: float
    dof: int  # entries - rank of the fitted Jacobian
    covariance_scale: float  # reduced chi-square when > 1, else 1
    chi_square_without_couple_stress: float  # the same fit with the couple self-stresses held at 0
    identifiability: Identifiability
    split: SplitVerdict

    @property
    def reduced_chi_square(self) -> float:
        return self.chi_square / max(self.dof, 1)

    def value(self, name: str) -> float:
        return next(p.value for p in self.parameters if p.name == name)


def _residuals(cases: dict[str, Case], tables: PrintedTables, theta: np.ndarray) -> np.ndarray:
    return ((predict(cases, theta) - tables.values) / tables.sigma).ravel()


def _optimise(cases: dict[str, Case], tables: PrintedTables, theta0: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Weighted least squares over the free parameters (trust region, Jacobian-scaled variables)."""
    def fun(x: np.ndarray) -> np.ndarray:
        theta = theta0.copy()
        theta[free] = x
        return _residuals(cases, tables, theta)

    try:
        sol = least_squares(fun, theta0[free], x_scale="jac", xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=400)
    except PressfitError as exc:
        raise PressfitError(f"the CAD fit left the range where the model can be solved: {exc}") from None
    theta = theta0.copy()
    theta[free] = sol.x
    return theta


def _jacobian(cases: dict[str, Case], tables: PrintedTables, theta: np.ndarray) -> np.ndarray:
    """Central-difference weighted Jacobian (entries, parameters); steps 1e-6 m or 1e-4 N (N m)."""
    steps = np.array([1e-4 if n.endswith(("_n", "_nm")) else 1e-6 for n in _names(cases)])
    cols = []
    for k, h in enumerate(steps):
        d = np.zeros_like(theta)
        d[k] = h
        cols.append((_residuals(cases, tables, theta + d) - _residuals(cases, tables, theta - d)) / (2 * h))
    return np.stack(cols, -1)


def _names(cases: dict[str, Case]) -> tuple[str, ...]:
    return tuple(p.name for p in parameters(cases))


_RANK_TOL = 1e-7  # singular values below this fraction of the largest count as zero (exact degeneracies)


def _covariance(jac: np.ndarray, free: np.ndarray, chi_square: float) -> tuple[np.ndarray, np.ndarray, int, float]:
    """(covariance of the free parameters, their 'determined' mask, dof, scale) from the weighted Jacobian."""
    jf = jac[:, free]
    norms = np.where(np.linalg.norm(jf, axis=0) > 0, np.linalg.norm(jf, axis=0), 1.0)
    _, s, vt = np.linalg.svd(jf / norms, full_matrices=False)
    keep = s > _RANK_TOL * s[0]
    cov = (vt[keep].T / s[keep] ** 2) @ vt[keep] / np.outer(norms, norms)
    determined = np.all(np.abs(vt[~keep]) < 1e-6, axis=0)
    dof = jac.shape[0] - int(keep.sum())
    scale = max(1.0, chi_square / max(dof, 1))
    return cov * scale, determined, dof, scale


def _identifiability(jac: np.ndarray, names: tuple[str, ...], free: np.ndarray, cov: np.ndarray) -> Identifiability:
    norms = np.where(np.linalg.norm(jac, axis=0) > 0, np.linalg.norm(jac, axis=0), 1.0)
    s = np.linalg.svd(jac / norms, compute_uv=False)
    jf, fitted = jac[:, free], tuple(n for n, f in zip(names, free, strict=True) if f)
    directions, sensitivity = {}, {}
    for k in np.flatnonzero(~free):
        d = -np.linalg.lstsq(jf, jac[:, k], rcond=None)[0]
        directions[names[k]] = {n: float(c) for n, c in zip(fitted, d, strict=True) if abs(c) > 1e-9}
        sensitivity[names[k]] = float(np.linalg.norm(jac[:, k] + jf @ d))
    sd = np.sqrt(np.diag(cov))
    corr = cov / np.outer(np.where(sd > 0, sd, 1.0), np.where(sd > 0, sd, 1.0))
    return Identifiability(singular_values=tuple(float(x) for x in s), held_directions=directions,
                           held_sensitivity=sensitivity, fitted_names=fitted, correlations=corr)


def _split_verdict(cases: dict[str, Case], theta: np.ndarray, a_std: float) -> SplitVerdict:
    """Case C: the fitted self-stress against the physical rules, and the vertical balance of the printed
    axial forces at the fitted pose (as printed and with CAD leg 1 reversed)."""
    machine, pose, a, _ = configure(cases, theta)[2]
    case = cases["C"]
    force = case.loads.wrenches()[0][:3]
    res = solve_linear(machine, pose, force)
    v_p = preload_vector(machine, pose)
    a_mn = float(v_p @ (actuator_forces_min_norm(machine, pose, force) - res.axial_forces_n))
    ref = case.reference
    tension = np.empty(4)
    tension[np.array(ref.leg_order) - 1] = ref.axial_sign * np.array(ref.values["F_z"])
    vertical = tension * res.leg_unit_vectors[:, 1]
    printed, reversed_ = float(vertical.sum()), float(vertical.sum() - 2 * vertical[ref.leg_order[0] - 1])
    if abs(a) <= 3 * a_std:
        verdict = "physical: the printed split is the elastic (compliance) split within 3 sigma"
    elif abs(a - a_mn) <= 3 * a_std:
        verdict = "a rule of the paper's rigid solver: the minimum-norm (equal axial stiffness) split, eq. 5"
    else:
        verdict = (f"an artefact of the paper's solver: the printed split is the elastic one plus a self-stress "
                   f"a = {a:.1f} +- {a_std:.1f} N along v_p that no load produces and no physical rule gives "
                   f"(elastic: 0 N, minimum norm: {a_mn:.1f} N)")
    return SplitVerdict(self_stress_n=float(a), self_stress_std_n=float(a_std), min_norm_self_stress_n=a_mn,
                        vertical_balance_printed_n=printed, vertical_balance_reversed_n=reversed_, verdict=verdict)


def load_paper_cases(directory: Path = PAPER_CASES) -> dict[str, Case]:
    """The paper cases A, B, C (case files with ``[reference]`` tables)."""
    return {n: load_case(Path(directory) / f"{n}.toml") for n in CASES}


def fit_cad_model(cases: dict[str, Case] | None = None, tables: PrintedTables | None = None, *,
                  compare_without_couple_stress: bool = True) -> CadFit:
    """Identify the CAD model from Tables 5-6 (module docstring): the weighted least-squares optimum from
    Table 3's start, its residuals, covariance, identifiability and the case C split verdict.

    ``tables`` defaults to the printed tables with case C's CAD leg 1 read reversed (it then balances the
    load; see :class:`SplitVerdict`); pass synthetic tables to test the identification.
    """
    cases = load_paper_cases() if cases is None else cases
    tables = printed_tables(cases) if tables is None else tables
    params = parameters(cases)
    names = tuple(p.name for p in params)
    theta0 = np.array([p.initial for p in params])
    free = np.array([p.fitted for p in params])
    theta = _optimise(cases, tables, theta0, free)
    chi2 = float(np.sum(_residuals(cases, tables, theta) ** 2))
    jac = _jacobian(cases, tables, theta)
    cov, determined, dof, scale = _covariance(jac, free, chi2)
    std = np.full(len(params), np.inf)
    std[free] = np.where(determined, np.sqrt(np.diag(cov)), np.inf)
    chi2_no_couple = np.nan
    if compare_without_couple_stress:
        held = free & ~np.array([n.endswith("_couple_self_stress_nm") for n in names])
        chi2_no_couple = float(np.sum(_residuals(cases, tables, _optimise(cases, tables, theta0, held)) ** 2))
    fitted = tuple(FittedParameter(name=p.name, meaning=p.meaning, initial=p.initial, value=float(v), std=float(s),
                                   fitted=p.fitted, determined=bool(p.fitted and np.isfinite(s)))
                   for p, v, s in zip(params, theta, std, strict=True))
    before, after = predict(cases, theta0), predict(cases, theta)
    entries = tuple(EntryResidual(case=n, quantity=q, cad_leg=leg + 1, printed=float(tables.values[i, j, leg]),
                                  sigma=float(tables.sigma[i, j, leg]), table3=float(before[i, j, leg]),
                                  fitted=float(after[i, j, leg]))
                    for i, n in enumerate(CASES) for j, q in enumerate(QUANTITIES) for leg in range(4))
    return CadFit(parameters=fitted, entries=entries, chi_square=chi2,
                  chi_square_table3=float(np.sum(((before - tables.values) / tables.sigma) ** 2)), dof=dof,
                  covariance_scale=scale, chi_square_without_couple_stress=chi2_no_couple,
                  identifiability=_identifiability(jac, names, free, cov),
                  split=_split_verdict(cases, theta, float(std[names.index("C_self_stress_n")])))


def to_dict(fit: CadFit) -> dict[str, object]:
    """JSON-ready (SI; std null where a parameter is held or not determined)."""
    ident = fit.identifiability
    finite = lambda x: x if np.isfinite(x) else None
    return {"parameters": [{**asdict(p), "std": finite(p.std)} for p in fit.parameters],
            "entries": [{**asdict(e), "table3_residual": e.table3_residual, "fit_residual": e.fit_residual}
                        for e in fit.entries],
            "chi_square": fit.chi_square, "chi_square_table3": fit.chi_square_table3, "dof": fit.dof,
            "reduced_chi_square": fit.reduced_chi_square, "covariance_scale": fit.covariance_scale,
            "chi_square_without_couple_stress": finite(fit.chi_square_without_couple_stress),
            "identifiability": {"singular_values": list(ident.singular_values),
                                "held_directions": ident.held_directions, "held_sensitivity": ident.held_sensitivity,
                                "fitted_names": list(ident.fitted_names), "correlations": ident.correlations.tolist()},
            "c_split": asdict(fit.split)}


def to_markdown(fit: CadFit) -> str:
    """The fitted CAD model, every entry's residual beside Table 3's, identifiability and the C verdict."""
    ident, sp = fit.identifiability, fit.split
    lines = ["| parameter | meaning | Table 3 / case file | fitted | std |", "|---|---|---|---|---|"]
    lines += [f"| {p.name} | {p.meaning} | {p.initial:.5g} | {p.value:.5g} | "
              f"{f'{p.std:.2g}' if p.determined else ('held' if not p.fitted else 'not determined')} |"
              for p in fit.parameters]
    lines += ["", f"chi-square {fit.chi_square:.4g} with {fit.dof} degrees of freedom (Table 3 model: "
              f"{fit.chi_square_table3:.4g}; without the couple self-stresses: "
              f"{fit.chi_square_without_couple_stress:.4g});"
              f" uncertainties scaled by {fit.covariance_scale:.3g} (the reduced chi-square, when above 1).", "",
              "Held parameters, the compensating change of the fitted ones per unit change, and the weighted "
              "residual change that is left (in sigmas; ~0 = the tables cannot see it):", ""]
    for name, d in ident.held_directions.items():
        combo = ", ".join(f"{k} {v:+.3g}" for k, v in d.items() if abs(v) > 1e-6)
        lines.append(f"- {name} +1: {combo or 'nothing'}; left {ident.held_sensitivity[name]:.2g}")
    corr = ", ".join(f"{a}/{b} {c:+.2f}" for a, b, c in ident.strongest_correlations(0.95))
    lines += ["", f"Singular values of the column-normalised weighted Jacobian: "
              f"{', '.join(f'{s:.2g}' for s in ident.singular_values)}. Correlations above 0.95: {corr or 'none'}.",
              "", f"Case C axial split: as printed the axial forces carry {sp.vertical_balance_printed_n:.1f} N of the "
              f"700 N load vertically, with CAD leg 1 reversed {sp.vertical_balance_reversed_n:.1f} N (the fit uses "
              f"the reversed reading). Verdict: {sp.verdict}.", "",
              "| case | entry | CAD leg | printed | sigma | Table 3 model | residual | fitted model | residual |",
              "|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {e.case} | {e.quantity} | {e.cad_leg} | {e.printed:.4g} | {e.sigma:.2g} | {e.table3:.4g} | "
              f"{e.table3_residual:+.3g} | {e.fitted:.4g} | {e.fit_residual:+.3g} |" for e in fit.entries]
    return "\n".join(lines) + "\n"
