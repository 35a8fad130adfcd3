r"""Drive sizing from a motion: per drive the thermal and peak figures against its ratings, the preload's cost, and
the energy balance of a run (issue 20; docs/sizing.md).

Inputs are time series on one grid of step dt (s): the delivered leg tensions N_i(t) (N, > 0 tension, what acts
on the prismatic joints as -N_i) and the leg rates l_dot_i(t) (m/s); the leg count is the series' width. The
power a drive delivers to its leg is P_i = -N_i l_dot_i (W: > 0 while a tension shortens the leg, the drive
motoring; < 0 regenerating). Over the n samples, RMS x = sqrt(mean x^2), integrals are sums x dt (the series'
zero-order hold). Energies: positive E+ = sum max(P, 0) dt, regenerative E- = sum max(-P, 0) dt (J, both >= 0).

Electric drive (servo motor + ball screw, docs/drives.md): N = k_f i, k_f = 2 pi eta K_t / lead, so the
current is i = N / k_f, the motor torque T = K_t i = N lead / (2 pi eta) and the motor speed
omega = 2 pi |l_dot| / lead. The rotor and screw inertia J is the prismatic joint's armature in the multibody
models (:mod:`pressfit.dynamics.inertia`), so the delivered N already includes J alpha (2 pi / lead): adding it
again would count it twice. Copper loss R mean(i^2) = R (RMS i)^2 (W) where ``winding_resistance_ohm`` is given.
Hydraulic drive (servo valve + symmetric cylinder): the valve supplies the displacement and leakage flow
Q = A |l_dot| + C_L |N| / A (m^3/s; the compressibility flow, which averages out, is left out) at the supply
pressure: supplied power p_s Q (W, what the pump delivers: the difference to P is throttled in the valve).

Ratings (:class:`Rating`, ratio = figure / rating, exceeded when the ratio is above 1): the peak force against
the drive's force limit; for an electric drive the peak speed against ``speed_limit_rad_per_s`` lead / (2 pi), the
RMS torque against ``continuous_torque_nm`` and the peak power against ``rated_power_w`` (both optional); for a
hydraulic one the peak flow against the valve's no-load flow K_v sqrt((p_s - p_t) / 2).

Energy balance of a run (:func:`energy_balance`), between its first and last rows:

    W_drives = dK + dV_g + dV_el + W_pin + D + dV_play + P_play - E_replacement + L_series + residual,

W_drives = sum_i sum_k -N_i,k (l_i,k - l_i,k-1), the exact work of the tensions held over each step over the drives'
lengths (the sensors'); W_pin = sum_k F_k-1 (y_k-1 - y_k), the work of the tool on the pin (the contact force F, +y
on the tool, held over the step after it was computed; on the rigid model through the series compliance, whose
quasi-static spring is the pin's side), or sum_k F_k (y_k-1 - y_k) on a model whose contact is implicit (the
flexible one: the force at a step's end acts over it, ``contact_implicit``); K (armature and a drive side behind the
plays included) and V_g from Pinocchio; V_el the flexible model's springs and D its Rayleigh damping's work per step
(:class:`pressfit.dynamics.machine.flexible.FlexibleState`); V_play and P_play the cardan plays' stored energy and
dissipation (flexible model with clearance: :class:`.flexible_scenario.PlayLedger`, what the drives do on their side
of the plays minus what reaches the legs); E_replacement the stems' re-placement, a jump of the flexible machine's
energy no force works on (:meth:`FlexibleMachine.replacement_energy_j`, step-independent); L_series the loss of the
drives' sensor-side series springs (flexible model: the tension held over a step stepping into a massless spring,
:mod:`pressfit.dynamics.machine.flexible_scenario`). The drives' own losses (copper, valve throttling) are upstream
of the joints, so they are reported beside the balance, not in it. The relative residual is |residual| / the drives'
gross work sum_k |sum_i -N_i,k (l_i,k - l_i,k-1)| (the energy the drives move in and out of the machine; the
preload's circulating power, which sums to zero over the legs at every instant on a rigid machine, v_p . l_dot = 0,
does not inflate it). What is left is the integrators' own energy error, first order in dt on both models
(docs/sizing.md): semi-implicit Euler's sum 1/2 dv^T M dv per step (its velocity update is explicit) on the rigid
model, generalised-alpha's with its rectangle-rule damping work and numerical damping (rho_inf) on the flexible one.

Tolerance per model and drive kind (``ENERGY_BALANCE``, about 3x the largest relative residual measured
on the shipped insertions at 1 ms, with the limiter; ratio = residual(1 ms) / residual(0.5 ms)):

    model     drive         largest measured (case)              ratio  tolerance
    rigid     force         0.275% (insertion_fast; 1.00% the suite's 0.3 s moves)  2.00   3%
    rigid     electric      0.242% (insertion_electric)          2.00   0.75%
    rigid     hydraulic     0.178% (insertion_hydraulic)         2.00   0.55%
    rigid     linear_motor  0.208% (insertion_linear_motor)      2.00   0.65%
    flexible  force         0.291% (insertion_fast; 0.181% insertion with clearance;     2.03   3%
                            0.94% the suite's two-pin flexible board, test_cycle.py)
    flexible  electric      0.247% (insertion_electric)          2.00   0.75%
    flexible  hydraulic     about 0.18% (insertion_hydraulic)    ~2     0.55%
    flexible  linear_motor  about 0.21% (insertion_linear_motor) ~2     0.65%

(the last two from their runs before the re-placement term, 0.372 J and 0.375 J, less its 0.43 J). The rigid
force drives' tolerance is 3x the 1.00% of tests/dynamics/test_insertion.py's fast scenario (0.3 s moves, 1 ms):
semi-implicit Euler's error grows with the accelerations, so 3x the shipped 0.275% would refuse it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pressfit.dynamics import drives as drive_kinds
from pressfit.dynamics.drives.base import Rating, rms
from pressfit.dynamics.drives.electric import ElectricSizing
from pressfit.dynamics.drives.hydraulic import HydraulicSizing
from pressfit.dynamics.machine.flexible_scenario import FlexibleScenario
from pressfit.dynamics.machine.registry import model_kind
from pressfit.dynamics.machine.rigid import RigidScenario
from pressfit.errors import PressfitError, ResidualError

# the relative residual of the energy balance by (model, drive kind): about 3x the largest measured on the shipped
# insertions at 1 ms (module docstring's table, docs/sizing.md)
# (model, drive) -> (tolerance on the relative residual, residual(1 ms) / residual(0.5 ms) measured on the shipped
# insertions: first order is 2; None where not measured), the table of the module docstring; keyed by the registries'
# classes (a run's names reach them through model_kind and drives.by_kind only)
_R, _F = RigidScenario, FlexibleScenario
_FORCE, _ELECTRIC, _HYDRAULIC, _LINEAR = (drive_kinds.ForceDrive, drive_kinds.ElectricDrive, drive_kinds.HydraulicDrive,
                                          drive_kinds.LinearMotorDrive)
ENERGY_BALANCE: dict[tuple[type, type], tuple[float, float | None]] = {
    (_R, _FORCE): (0.03, 2.00), (_R, _ELECTRIC): (0.0075, 2.00), (_R, _HYDRAULIC): (0.0055, 2.00),
    (_R, _LINEAR): (0.0065, 2.00),
    (_F, _FORCE): (0.03, 2.00), (_F, _ELECTRIC): (0.0075, 2.00), (_F, _HYDRAULIC): (0.0055, 2.0),
    (_F, _LINEAR): (0.0065, 2.0),
}
FIRST_ORDER_RATIO = 1.6  # a residual that shrinks by at least this when the step halves: a smaller step reduces it
PRELOAD_FIGURES = ("rms_force_n", "copper_loss_w", "positive_energy_j", "regenerative_energy_j",
                   "supply_energy_j")  # given again with a4 = 0 (the preload's cost)


@dataclass(frozen=True, kw_only=True)
class DriveSizing:
    """One drive over a motion (module docstring). ``leg`` from 1; forces N, speed m/s, power W, energy J."""

    leg: int
    peak_force_n: float
    rms_force_n: float
    peak_speed_m_per_s: float
    peak_power_w: float
    peak_regenerative_power_w: float
    positive_energy_j: float
    regenerative_energy_j: float
    drive: Any | None  # the drive's own figures (its ``sizing``: ElectricSizing, HydraulicSizing, ...), or None
    ratings: tuple[Rating, ...]
    without_preload: DriveSizing | None = None
    rms_preload_share_n: float | None = None  # RMS of N(a4) - N(a4 = 0) on the same time grid, N

    def figures(self) -> dict[str, float | None]:
        """Every figure by its key (the drive-specific ones included)."""
        out = {k: getattr(self, k) for k in ("peak_force_n", "rms_force_n", "peak_speed_m_per_s", "peak_power_w",
                                             "peak_regenerative_power_w", "positive_energy_j",
                                             "regenerative_energy_j")}
        if self.drive is not None:
            out.update(vars(self.drive))
        return out

    @property
    def electric(self) -> ElectricSizing | None:
        """The electric drive's figures (None for another kind)."""
        return self.drive if isinstance(self.drive, ElectricSizing) else None

    @property
    def hydraulic(self) -> HydraulicSizing | None:
        """The hydraulic drive's figures (None for another kind)."""
        return self.drive if isinstance(self.drive, HydraulicSizing) else None

    def to_dict(self) -> dict[str, Any]:
        """JSON record: the figures, ``ratings`` by figure, and with a preload comparison each of
        ``PRELOAD_FIGURES`` again as ``<stem>_without_preload_<unit>`` and ``rms_preload_share_n``."""
        out: dict[str, Any] = {"leg": self.leg, **self.figures(),
                               "ratings": {r.figure: r.to_dict() for r in self.ratings}}
        if self.without_preload is not None:
            other = self.without_preload.figures()
            for key in PRELOAD_FIGURES:
                if key in other:
                    stem, unit = key.rsplit("_", 1)
                    out[f"{stem}_without_preload_{unit}"] = other[key]
            out["rms_preload_share_n"] = self.rms_preload_share_n
        return out


def _series(tensions_n: np.ndarray, rates_m_per_s: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    n, v = np.asarray(tensions_n, dtype=float), np.asarray(rates_m_per_s, dtype=float)
    if n.ndim != 2 or n.shape != v.shape or n.shape[0] == 0:
        raise PressfitError(f"drive sizing needs tensions and rates of one shape (samples, legs), got "
                            f"{n.shape} and {v.shape}")
    if not (np.all(np.isfinite(n)) and np.all(np.isfinite(v))):
        raise PressfitError("drive sizing needs finite tensions (N) and rates (m/s)")
    if not (math.isfinite(dt_s) and dt_s > 0):
        raise PressfitError(f"drive sizing needs a positive time step (s), got {dt_s!r}")
    return n, v


def drive_sizing(tensions_n: np.ndarray, rates_m_per_s: np.ndarray, dt_s: float, drive: drive_kinds.Drive
                 ) -> tuple[DriveSizing, ...]:
    """Per drive (column) the sizing figures and ratings (module docstring) of tensions (samples, legs) N and leg
    rates (samples, legs) m/s sampled every ``dt_s`` (s), for a drive model of :mod:`pressfit.dynamics.drives`."""
    n, v = _series(tensions_n, rates_m_per_s, dt_s)
    power = -n * v
    peak_force, rms_force = np.abs(n).max(axis=0), rms(n)
    speed = np.abs(v).max(axis=0)
    out = []
    for i in range(n.shape[1]):
        own, more = drive.sizing(n[:, i], v[:, i], dt_s)
        ratings = [Rating(figure="peak_force_n", value=float(peak_force[i]), rating=float(drive.force_limit_n),
                          key=drive.force_limit_key), *more]
        out.append(DriveSizing(
            leg=i + 1, peak_force_n=float(peak_force[i]), rms_force_n=float(rms_force[i]),
            peak_speed_m_per_s=float(speed[i]), peak_power_w=float(max(power[:, i].max(), 0.0)),
            peak_regenerative_power_w=float(max(-power[:, i].min(), 0.0)),
            positive_energy_j=float(np.maximum(power[:, i], 0.0).sum() * dt_s),
            regenerative_energy_j=float(np.maximum(-power[:, i], 0.0).sum() * dt_s),
            drive=own, ratings=tuple(ratings)))
    return tuple(out)


def with_preload_cost(sizing: tuple[DriveSizing, ...], tensions_n: np.ndarray, without: tuple[DriveSizing, ...],
                      tensions_without_n: np.ndarray) -> tuple[DriveSizing, ...]:
    """``sizing`` with the same figures of the run with a4 = 0 beside it and the preload's RMS share
    RMS(N - N_0) (N; the two runs on one time grid: the same scenario and step)."""
    a, b = np.asarray(tensions_n, dtype=float), np.asarray(tensions_without_n, dtype=float)
    if a.shape != b.shape or len(sizing) != len(without) or a.shape[1] != len(sizing):
        raise PressfitError(f"the preload's cost compares two runs on one time grid: got {a.shape} and {b.shape}")
    share = rms(a - b)
    return tuple(DriveSizing(**{**vars(s), "without_preload": w, "rms_preload_share_n": float(share[i])})
                 for i, (s, w) in enumerate(zip(sizing, without, strict=True)))


def _measured(model: str, drive_kind: str) -> tuple[float, float | None]:
    """The measured (tolerance, step ratio) of the model and drive kind named by a run (``ENERGY_BALANCE``)."""
    try:
        return ENERGY_BALANCE[(model_kind(model), drive_kinds.by_kind(drive_kind))]
    except KeyError:
        known = ", ".join(f"{m.__name__}/{d.kind}" for m, d in ENERGY_BALANCE)
        raise PressfitError(f"no energy-balance tolerance for the {model} model with {drive_kind} drives (known: "
                            f"{known})") from None


def energy_balance_tolerance(model: str, drive_kind: str) -> float:
    """The largest relative residual accepted for the model with drives of the kind (``ENERGY_BALANCE``; module
    docstring)."""
    return _measured(model, drive_kind)[0]


def converges_with_the_step(model: str, drive_kind: str) -> bool:
    """Whether the residual of the model with drives of the kind was measured to shrink at least in proportion to
    the step (``ENERGY_BALANCE``'s residual(dt) / residual(dt / 2) >= ``FIRST_ORDER_RATIO``)."""
    ratio = _measured(model, drive_kind)[1]
    return ratio is not None and ratio >= FIRST_ORDER_RATIO


@dataclass(frozen=True, kw_only=True)
class EnergyBalance:
    """The energy balance of a run (module docstring), J; ``relative_residual`` = |residual_j| /
    ``gross_drive_work_j``, held to ``tolerance`` (:func:`energy_balance_tolerance` of ``model`` and
    ``drive_kind``); ``drive_losses_j`` (copper, valve throttling) upstream of the joints, beside it;
    ``play_energy_change_j`` and ``play_dissipation_j`` the cardan plays' (flexible model with clearance,
    :class:`.flexible_scenario.PlayLedger`; 0 otherwise); ``step_convergent``: the residual of this
    model and drive kind shrinks with the step (:func:`converges_with_the_step`)."""

    drive_work_j: float
    kinetic_change_j: float
    potential_change_j: float
    elastic_change_j: float
    pin_work_j: float
    damping_j: float
    residual_j: float
    gross_drive_work_j: float
    relative_residual: float
    tolerance: float
    drive_losses_j: float
    play_energy_change_j: float = 0.0
    play_dissipation_j: float = 0.0
    stem_replacement_j: float = 0.0
    series_loss_j: float = 0.0
    model: str = "rigid"
    drive_kind: str = "force"
    step_convergent: bool = True

    def to_dict(self) -> dict[str, Any]:
        return dict(vars(self))

    def terms(self) -> str:
        """The balance written out, J."""
        plays = (f" + plays' stored {self.play_energy_change_j:.4g} + plays' dissipation {self.play_dissipation_j:.4g}"
                 if self.play_energy_change_j or self.play_dissipation_j else "")
        stems = f" - stem re-placement {self.stem_replacement_j:.4g}" if self.stem_replacement_j else ""
        series = f" + series springs' loss {self.series_loss_j:.4g}" if self.series_loss_j else ""
        return (f"drive work {self.drive_work_j:.4g} J = kinetic {self.kinetic_change_j:.4g} + potential "
                f"{self.potential_change_j:.4g} + elastic {self.elastic_change_j:.4g} + pin {self.pin_work_j:.4g} + "
                f"damping {self.damping_j:.4g}{plays}{stems}{series} + residual {self.residual_j:.4g} J")

    def require_closed(self, where: str = "", table: str = "simulation") -> EnergyBalance:
        """Itself, or ResidualError when ``relative_residual`` exceeds ``tolerance`` (the energies are not trusted).
        The message writes the balance out and names the term that is out, the residual: the integrator's energy
        error of the model; it suggests a smaller ``table``'s time step only where that residual was measured to
        shrink with the step (``step_convergent``), and says the step is not its cause otherwise."""
        if not self.relative_residual <= self.tolerance:
            integrator = model_kind(self.model).integrator_error
            if self.step_convergent:
                advice = (f"first order in [{table}] time_step_s on the {self.model} model with {self.drive_kind} "
                          "drives (measured, docs/sizing.md): a smaller time_step_s reduces it")
            else:
                advice = (f"it was not measured to shrink with [{table}] time_step_s on the {self.model} model with "
                          f"{self.drive_kind} drives (docs/sizing.md): a smaller step is not known to close it")
            raise ResidualError(f"the run's energy balance ({self.terms()}; the residual, {integrator}, is "
                                f"{self.residual_j:.4g} J of the drives' gross work {self.gross_drive_work_j:.4g} J, "
                                f"{advice})", f"relative energy residual ({self.model} model, {self.drive_kind} "
                                "drives)", self.relative_residual, self.tolerance, where)
        return self


def energy_balance(lengths_m: np.ndarray, tensions_n: np.ndarray, contact_force_n: np.ndarray,
                   contact_y_m: np.ndarray, kinetic_j: np.ndarray, potential_j: np.ndarray, elastic_j: np.ndarray,
                   damping_work_j: np.ndarray, drive_losses_j: float = 0.0, *, model: str, drive_kind: str,
                   play_energy_j: np.ndarray | None = None, play_dissipation_j: np.ndarray | None = None,
                   stem_replacement_j: np.ndarray | None = None,
                   series_loss_j: np.ndarray | None = None) -> EnergyBalance:
    """The balance between the first and the last of n rows (module docstring): the drives' lengths (n, legs) m, the
    tensions held over the step ending at each row (n, legs) N, the contact force at each row (n,) N (+y on the
    tool, held over the next step, or over its own on a model whose contact is implicit) and the y of the point it
    acts on (n,) m, the energies at each row (n,) J, the damping's work over the step ending at each row (n,) J and,
    with cardan plays, their stored energy at each row (n,) J and their dissipation over the step ending at it (n,)
    J, and the energy change of each step's stem re-placement (n,) J and the sensors' series springs' loss over the
    step ending at each row (n,) J (flexible model); held to the tolerance of ``model`` with drives of
    ``drive_kind`` (:func:`energy_balance_tolerance`)."""
    lengths, n = np.asarray(lengths_m, float), np.asarray(tensions_n, float)
    force, y = np.asarray(contact_force_n, float), np.asarray(contact_y_m, float)
    if lengths.shape != n.shape or lengths.shape[0] < 2:
        raise PressfitError(f"an energy balance needs at least two rows of lengths and tensions, got {lengths.shape}")
    step_work = np.sum(-n[1:] * np.diff(lengths, axis=0), axis=1)  # all drives, per step
    drive, gross = float(step_work.sum()), float(np.abs(step_work).sum())
    acting = force[1:] if model_kind(model).contact_implicit else force[:-1]  # the force over each step
    pin_work = float(np.sum(acting * -np.diff(y)))
    kin, pot, el = (float(np.asarray(e, float)[-1] - np.asarray(e, float)[0]) for e in (kinetic_j, potential_j,
                                                                                         elastic_j))
    damp = float(np.sum(np.asarray(damping_work_j, float)[1:]))
    stored = 0.0 if play_energy_j is None else float(np.asarray(play_energy_j, float)[-1]
                                                     - np.asarray(play_energy_j, float)[0])
    lost = 0.0 if play_dissipation_j is None else float(np.sum(np.asarray(play_dissipation_j, float)[1:]))
    replaced = 0.0 if stem_replacement_j is None else float(np.sum(np.asarray(stem_replacement_j, float)[1:]))
    series = 0.0 if series_loss_j is None else float(np.sum(np.asarray(series_loss_j, float)[1:]))
    residual = drive - kin - pot - el - pin_work - damp - stored - lost + replaced - series
    return EnergyBalance(drive_work_j=drive, kinetic_change_j=kin, potential_change_j=pot, elastic_change_j=el,
                         pin_work_j=pin_work, damping_j=damp, residual_j=residual,
                         gross_drive_work_j=gross, relative_residual=abs(residual) / gross if gross > 0 else 0.0,
                         tolerance=energy_balance_tolerance(model, drive_kind), drive_losses_j=float(drive_losses_j),
                         play_energy_change_j=stored, play_dissipation_j=lost, stem_replacement_j=replaced,
                         series_loss_j=series, model=model, drive_kind=drive_kind,
                         step_convergent=converges_with_the_step(model, drive_kind))


@dataclass(frozen=True)
class RunSizing:
    """The drive sizing of one simulated run (:func:`run_sizing`): per drive, and the run's energy balance."""

    drives: tuple[DriveSizing, ...]
    energy: EnergyBalance

    def to_dict(self) -> dict[str, Any]:
        """``drives`` (one record per drive, :meth:`DriveSizing.to_dict`), ``energy_balance`` and
        ``energy_balance_residual`` (its relative residual)."""
        return {"drives": [d.to_dict() for d in self.drives], "energy_balance": self.energy.to_dict(),
                "energy_balance_residual": self.energy.relative_residual}


def _columns(result: Any, prefix: str) -> np.ndarray:
    from pressfit.dynamics.series import leg_columns

    return result.series[:, leg_columns(result.columns, prefix)]


def drive_losses_j(sizing: tuple[DriveSizing, ...]) -> float:
    """The drives' losses upstream of the joints, J: copper R i^2 (electric, with the winding resistance), the valve's
    throttling p_s Q - P (hydraulic: supplied minus net mechanical work), 0 for the force kind: each drive's
    figures' ``loss_energy_j``."""
    total = 0.0
    for s in sizing:
        if s.drive is not None:
            total += s.drive.loss_energy_j(s.positive_energy_j - s.regenerative_energy_j)
    return total


def run_sizing(result: Any, drive: drive_kinds.Drive, dt_s: float, without_preload: Any | None = None, *,
               model: str) -> RunSizing:
    """Drive sizing and energy balance of an :class:`pressfit.dynamics.insertion.InsertionResult` stepped every
    ``dt_s`` (s) on ``model`` ("rigid", "flexible": the balance's tolerance); ``without_preload``: the same scenario
    run with a4 = 0 (the preload's cost, :func:`with_preload_cost`)."""
    def col(name: str) -> np.ndarray:
        return result.series[:, result.columns.index(name)]

    tensions, rates = _columns(result, "act_n"), _columns(result, "rate_m_per_s")
    sizing = drive_sizing(tensions, rates, dt_s, drive)
    if without_preload is not None:
        base = _columns(without_preload, "act_n")
        sizing = with_preload_cost(sizing, tensions, drive_sizing(base, _columns(without_preload, "rate_m_per_s"),
                                                                  dt_s, drive), base)
    balance = energy_balance(_columns(result, "length_m"), tensions, col("contact_force_n"), col("plate_y_m"),
                             col("kinetic_energy_j"), col("potential_energy_j"), col("elastic_energy_j"),
                             col("damping_work_j"), drive_losses_j(sizing), model=model, drive_kind=drive.kind,
                             play_energy_j=col("play_energy_j"), play_dissipation_j=col("play_dissipation_j"),
                             stem_replacement_j=col("stem_replacement_j"), series_loss_j=col("series_loss_j"))
    return RunSizing(sizing, balance)


def size_insertion(case: Any, result: Any, limiter: bool = True, progress: bool = False) -> RunSizing:
    """:func:`run_sizing` of a case's simulated insertion, the preload's cost from a second run of the same scenario
    with ``[preload] a4_n`` = 0 (``result`` itself when a4 is 0)."""
    from pressfit.dynamics.insertion import simulate_insertion
    from pressfit.dynamics.scenario import without_preload

    amplitudes = case.preload.amplitudes
    baseline = result
    if any(amplitudes):
        try:
            baseline = simulate_insertion(without_preload(case), limiter, progress)
        except PressfitError as exc:
            raise PressfitError(f"the preload's cost (the same scenario without the preload, instead of "
                                f"{', '.join(f'{a:g}' for a in amplitudes)} N) could not be simulated: {exc}") from None
    sizing = run_sizing(result, drive_kinds.of(case.machine()), case.simulation.time_step_s, baseline,
                        model=case.simulation.model)
    sizing.energy.require_closed(f"of {case.path}")
    return sizing
