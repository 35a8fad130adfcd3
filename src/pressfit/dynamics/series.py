r"""A scenario run's record, shared by the step loop (:mod:`pressfit.dynamics.scenario`) and the models that
step (:mod:`pressfit.dynamics.machine`): the plan the loop runs (:class:`ScenarioPlan`), the series' columns and
rows (:class:`Series`), the run's stop conditions and their messages (:class:`Guard`) and what a model's scenario
step is (:class:`ScenarioStep`).

A run stops with one line naming the time and the likely keys when the state is not finite, the plate leaves the
reachable set (its pose's inverse kinematics checked every ``REACH_CHECK_STEPS`` steps and at the last; the rigid
model checks its joints every step and the pose where they leave, :func:`pressfit.dynamics.kernels.within_limits`),
the loop-closure drift exceeds
``MAX_CLOSURE_DRIFT_M``, the tool goes deeper than the plan's depth limit (``MAX_DEPTH_FACTOR`` times the
commanded interference) or a drive cannot take its step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from pressfit import kinematics
from pressfit.description.cases import Case, Simulation
from pressfit.description.machine import Machine
from pressfit.dynamics.control import Trajectory, estimate_pose
from pressfit.dynamics.machine.base import SECTION_COMPONENTS, SECTIONS
from pressfit.dynamics.multibody import RigidLegModel
from pressfit.errors import DriveStepError, PressfitError, format_violation

# the machine's energies after the step and the Rayleigh damping's work over it (flexible model; 0 on the rigid one,
# which has no elastic energy either), the cardan plays' stored energy after the step and their dissipation over it
# (flexible model with clearance, :class:`PlayLedger`; 0 otherwise), the energy change of the step's stem
# re-placement (flexible model, :meth:`FlexibleMachine.replacement_energy_j`; 0 on the rigid one), the loss of the
# drives' sensor-side series springs over the step (flexible model, :meth:`FlexibleScenario._sense`; 0 on the rigid
# one), J: the energy balance of :mod:`pressfit.dynamics.sizing`
ENERGY_COLUMNS = ("kinetic_energy_j", "potential_energy_j", "elastic_energy_j", "damping_work_j", "play_energy_j",
                  "play_dissipation_j", "stem_replacement_j", "series_loss_j")


def internal_columns(legs: int) -> tuple[str, ...]:
    """The internal force columns of an n-leg run: the preload amplitudes the delivered tensions carry
    (:func:`pressfit.dynamics.kernels.internal_forces`): ``internal_force_n`` (v_p . N) with one redundant leg,
    ``internal_force_n<3 + k>`` for amplitude k (of leg 3 + k) with more, none on 3 legs."""
    if legs - 3 == 1:
        return ("internal_force_n",)
    return tuple(f"internal_force_n{j + 1}" for j in range(3, legs))


def series_columns(legs: int) -> tuple[str, ...]:
    """The columns of an n-leg run's series (:class:`InsertionResult`), per-leg columns numbered 1 .. n."""
    names = [str(i + 1) for i in range(legs)]
    return ("time_s", "ref_x_m", "ref_y_m", "ref_z_m", "est_x_m", "est_y_m", "est_z_m", "plate_x_m", "plate_y_m",
            "plate_z_m", "tool_x_m", "tool_y_m", "tool_z_m", "contact_force_n", "depth_m",
            *(f"cmd_n{i}" for i in names), *(f"act_n{i}" for i in names), "reference_lift_m", "closure_drift_m",
            *(f"axial_n{i}" for i in names), *internal_columns(legs), "kinematic_x_m", "kinematic_y_m",
            "kinematic_z_m", *(f"length_m{i}" for i in names), *(f"rate_m_per_s{i}" for i in names), *ENERGY_COLUMNS)


def section_columns(legs: int) -> tuple[str, ...]:
    """The columns of an n-leg flexible run's section resultants (``sections.csv``)."""
    return ("time_s", *(f"leg{i + 1}_{s}_{c}" for i in range(legs) for s in SECTIONS for c in SECTION_COMPONENTS))


def leg_columns(columns: tuple[str, ...], prefix: str) -> list[int]:
    """The indices of the per-leg columns ``<prefix>1 .. <prefix>n`` in ``columns``, in leg order."""
    legs = sum(c.startswith("cmd_n") for c in columns)
    return [columns.index(f"{prefix}{i + 1}") for i in range(legs)]



KINEMATIC_ITERATIONS = 3  # Gauss-Newton iterations of the kinematic pose from the last row's
MAX_CLOSURE_DRIFT_M = 2e-5  # the run stops when the loop closures open more than this (m; module docstring)
# the run stops when the tool goes deeper below the board face than this many times the commanded interference
# (the reference's deepest point): the contact law models the pin-board stack down to it, the board face is solid
MAX_DEPTH_FACTOR = 2.0
CHUNK_ROWS = 4096  # the series grows by this many rows at a time
REACH_CHECK_STEPS = 10  # the plate's joint limits are checked every this many steps (and at the last)


@dataclass(frozen=True, kw_only=True)
class ScenarioPlan:
    """A validated scenario (:func:`pressfit.dynamics.insertion.plan_scenario`, or a board's
    :func:`pressfit.dynamics.cycle.plan_cycle`): its reference, the number of steps, the planned path samples
    (n, 3), m, the warnings to show before the run, the run's settings (``simulation``: time step, model, contact
    law, controller gains, start pose) and the insertion force limit of each segment of the reference (N; the
    controller's limiter uses the running segment's)."""

    trajectory: Trajectory
    steps: int
    path_m: np.ndarray
    warnings: tuple[str, ...]
    rigid: RigidLegModel
    simulation: Simulation
    force_limits_n: np.ndarray
    depth_limit_m: float = math.inf  # the run stops beyond this depth below the board face (MAX_DEPTH_FACTOR)
    table: str = "simulation"  # the case table whose keys the run's errors name: [simulation], a board's [cycle]
    contact_params: tuple[np.ndarray, ...] = ()  # per segment, the contact as the kernels take it (a board's joint
    # at each board position: dynamics.cycle.segment_contacts); empty: the models' own of simulation.contact


def preload_amplitudes_n(case: Case, machine: Machine) -> np.ndarray:
    """The case's preload amplitudes a (n - 3,), N, along the machine's preload basis (a4 on the 4-UPU; zeros when
    the case has no preload; :func:`pressfit.dynamics.scenario.check_preload` refuses a preload the machine cannot
    take)."""
    amplitudes = np.asarray(case.preload.amplitudes, dtype=float)
    return amplitudes if amplitudes.any() else np.zeros(machine.redundancy)


class Series:
    """The series' rows, grown in chunks; :meth:`add` appends a row with the kinematic pose (forward kinematics of
    the actuator lengths, Gauss-Newton from the last row's, :func:`pressfit.dynamics.control.estimate_pose`; the
    rigid model's step fills :meth:`row` in place, its kinematic pose from its controller's estimate)."""

    def __init__(self, machine: Machine, steps: int, start_m: np.ndarray) -> None:
        self.machine, self.steps, self.kinematic = machine, steps, np.asarray(start_m, float).copy()
        self.width = len(series_columns(len(machine.legs)))
        self.chunks = [np.zeros((min(steps, CHUNK_ROWS), self.width))]

    def add(self, k: int, row: tuple, lengths: np.ndarray, rates: np.ndarray, energy: tuple) -> None:
        self.kinematic = estimate_pose(self.machine, lengths, self.kinematic, KINEMATIC_ITERATIONS)[0]
        self.row(k)[:] = (*row, *self.kinematic.tolist(), *np.asarray(lengths, dtype=float).tolist(),
                          *np.asarray(rates, dtype=float).tolist(), *energy)

    def row(self, k: int) -> np.ndarray:
        """Row k (the rows are filled in order) to fill in place, zeros where the caller writes nothing; the kinematic
        pose is the caller's."""
        if k // CHUNK_ROWS == len(self.chunks):
            self.chunks.append(np.zeros((min(self.steps - k, CHUNK_ROWS), self.width)))
        return self.chunks[-1][k % CHUNK_ROWS]

    def rows(self) -> np.ndarray:
        return np.concatenate(self.chunks)


class Guard:
    """A run's stop conditions (module docstring), each raising one PressfitError that names the time and the
    case table's keys (``plan.table``: [simulation], a board's [cycle])."""

    def __init__(self, case: Case, machine: Machine, plan: ScenarioPlan) -> None:
        self.case, self.machine, self.plan, self.table = case, machine, plan, plan.table

    def diverged(self, t: float, what: str) -> PressfitError:
        return PressfitError(f"{self.case.path}: the simulation diverged at t = {t:.4g} s ({what}); the planned path "
                             f"is reachable, so the likely keys are [{self.table}] time_step_s, the "
                             f"[{self.table}.controller] gains (kp_n_per_m, kd_n_s_per_m, ki_n_per_m_s, "
                             f"backoff_m_per_s_n) or [{self.table}] baumgarte_rad_per_s")

    def finite(self, ok: bool, t: float) -> None:
        if not ok:
            raise self.diverged(t, "the state is not finite")

    def pose(self, k: int, t: float, pose: np.ndarray, every: int = REACH_CHECK_STEPS) -> None:
        """The plate (or tool) pose (m) within the joint limits, every ``every`` steps and at the last."""
        bad = [] if k % every and k != self.plan.steps - 1 else kinematics.violations(self.machine, pose) \
            if pose[1] > 0 else [(0, "y_h [m]", pose[1], "minimum 0")]
        if bad:
            raise self.diverged(t, f"the plate left the reachable set at ({', '.join(f'{c:.4g}' for c in pose)})"
                                f" m: {format_violation(*bad[0])}")

    def depth(self, depth_m: float, t: float) -> None:
        """A tool deeper below the board face than ``plan.depth_limit_m`` stops the run: never a result."""
        if depth_m > self.plan.depth_limit_m:
            raise PressfitError(f"{self.case.path}: the tool went {1e3 * depth_m:.4g} mm below the board face at "
                                f"t = {t:.4g} s, beyond the tolerance of {1e3 * self.plan.depth_limit_m:.4g} mm "
                                f"({MAX_DEPTH_FACTOR:g} x the commanded interference_m): the board face is solid and "
                                "the contact law models the pin-board stack only down to the commanded interference, "
                                f"so the run is refused; the likely keys are the [{self.table}.controller] gains, the "
                                "segment times or the drives")

    def drift(self, drift_m: float, t: float) -> None:
        if drift_m > MAX_CLOSURE_DRIFT_M:
            sim = self.case.simulation
            raise PressfitError(f"{self.case.path}: the loop closures drifted open by {drift_m:.3g} m at t = {t:.4g} "
                                f"s, over the tolerance of {MAX_CLOSURE_DRIFT_M:g} m (the tool position is only as "
                                f"good as the closures): raise [{self.table}] baumgarte_rad_per_s (now "
                                f"{sim.baumgarte_rad_per_s:g} rad/s) or reduce time_step_s; if the motion itself "
                                f"diverged, the [{self.table}.controller] gains")

    def drive_failed(self, t: float, exc: DriveStepError) -> PressfitError:
        return PressfitError(f"{self.case.path}: the {exc} at t = {t:.4g} s (the machine file's "
                             f"[actuator.{exc.kind}] table, or the scenario's speed and forces)")


class ScenarioStep(Protocol):
    """A dynamics model driven through a scenario (one class per model,
    :data:`pressfit.dynamics.machine.registry.MODELS`): built from the run's case, machine, plan, drives, limiter
    flag and guard at the start state, stepped once per time step by the step loop
    (:func:`pressfit.dynamics.scenario.run_plan`), its rows read at the end.
    Capabilities the planning and the summaries ask of the class: ``elastic`` (the structure's modes in the
    equations of motion: the step is bounded by the first mode, the leg sections are objective, the cardan plays
    are modelled between the drives and the legs, a hydraulic oil column is stepped implicitly) and
    ``integrator_error`` (what the energy balance's residual is made of). ``params``: the contact as the kernels
    take it (:func:`pressfit.dynamics.contact.contact_parameters`), which the step loop replaces per segment when
    the plan gives ``contact_params`` (a board's joint at each board position, with its own state)."""

    elastic: bool
    integrator_error: str
    params: np.ndarray

    def step(self, k: int, t: float, reference: tuple[np.ndarray, np.ndarray], force_limit_n: float) -> None:
        """Advance time step k (ending at ``t``, s) towards the reference (position m, velocity m/s) under the
        running segment's insertion force limit (N), writing row k; raises through the guard to stop the run."""
        ...

    def rows(self) -> tuple[np.ndarray, np.ndarray | None]:
        """The series (one row per step, :func:`series_columns`) and the section resultants (elastic models)."""
        ...
