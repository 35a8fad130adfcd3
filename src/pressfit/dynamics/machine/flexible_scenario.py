r"""The flexible machine (:class:`pressfit.dynamics.machine.flexible.FlexibleMachine`) in a scenario
(:mod:`pressfit.dynamics.scenario`), and the cardan plays' energy account (:class:`PlayLedger`).

The machine file's ``[damping]``; with ``clearance`` the cardan plays between the drives and the legs
(:mod:`pressfit.dynamics.play`, the drives' sensors zeroed at the start): the machine's drives on the actuator
joints, stepped inside the flexible step's Newton at the mean rate of the step (implicit, so that an oil column is
stable: ``FlexibleMachine.step``'s ``drive``; the ideal force drive, which ignores the travel, once per step), the
contact force on the elastic tool point (the plate centre) inside the step's Newton too, at the step's end with its
stiffness in the iteration matrix (implicit: a pin law's stiff unloading line held over a step as an explicit
coupling rattles; ``contact_implicit``, which the energy balance's pin work reads). The drives' position sensors
read their own side of the leg's axial compliance the model does not carry
(:meth:`pressfit.description.machine.Machine.sensed_axial_compliance_m_per_n`: the tubes, and the drive's own
stiffness unless its sensor reads past it; the force drives act on the actuator joint, which carries no spring):
quasi-statically, a sensor reads l - N c(l) (l the actuator joint's length, or its drive side of the plays; N the
drive's tension, c that compliance), its rate differenced over the step, so the controller sees the press's
deflection as on the machine (``sensed_depth_m``, the deflection compensation). The massless series spring's energy
N^2 c / 2 is in the ``elastic_energy_j`` column; the tension held over a step (it steps at the step's start)
stretches it by s_k - s_k-1 = N_k c_k - N_k-1 c_k-1 under N_k, which is more than its energy change by c (N_k -
N_k-1)^2 / 2 (a force step into a massless spring: first order in the step where the tension is smooth, not where
cardan plays make it chatter; plus N_k^2 dc / 2 as the stem's exposed length changes): the ``series_loss_j`` column,
so that the energy balance is held to the integrator's error alone. Starts from the static equilibrium under gravity
with the drives holding the start pose's lengths. The step runs with BLAS on one thread (``one_blas_thread``): its
matrices are small (nv + 24 = 146), and OpenBLAS's default threads (one per core) cost 3.6 times the CPU time of the
run on the shared 2-core machine (docs/benchmarks.md).
"""

from __future__ import annotations

import numpy as np

from pressfit.description.cases import Case
from pressfit.description.machine import Machine
from pressfit.dynamics import drives as drive_kinds
from pressfit.dynamics import kernels
from pressfit.dynamics.contact import contact_force_n, contact_parameters
from pressfit.dynamics.control import ForceLimitedController
from pressfit.dynamics.drives.base import DriveOverStep
from pressfit.dynamics.machine.base import DriveInput, Energy
from pressfit.dynamics.machine.flexible import FlexibleMachine, leg_frame_loads
from pressfit.dynamics.play import DriveSide, LegPlay
from pressfit.dynamics.series import Guard, ScenarioPlan, Series, leg_columns, preload_amplitudes_n, series_columns
from pressfit.errors import ConvergenceError, PressfitError
from pressfit.mechanics.clearance import clearance_from_case

CONTACT_TANGENT_STEP_M = 1e-8  # the contact's stiffness in the step by central differences over this, m


class FlexibleScenario:
    """The flexible machine in a scenario (module docstring; :class:`pressfit.dynamics.series.ScenarioStep`)."""

    elastic = True
    integrator_error = "generalised-alpha's energy error (the damping's rectangle rule, the numerical damping)"
    objective_couples = True  # the elastic legs' section resultants: torsion and bending limits are offered
    one_blas_thread = True
    contact_implicit = True  # the contact force acts over a step at its end value (the series' row of the step)

    def __init__(self, case: Case, machine: Machine, plan: ScenarioPlan, drives: drive_kinds.Drive, limiter: bool,
                 guard: Guard) -> None:
        sim, steps = plan.simulation, plan.steps
        self.machine, self.plan, self.drives, self.guard = machine, plan, drives, guard
        self.dt, self.preload = sim.time_step_s, preload_amplitudes_n(case, machine)
        self.params = contact_parameters(sim.contact, machine)  # once: a tabulated law's table costs a solve
        start = np.asarray(sim.start_m, float)
        plays = clearance_from_case(case, machine) if sim.clearance else None
        self.implicit = implicit = drives.follows_travel  # a drive whose tension follows its travel: in the step
        self.fm = fm = FlexibleMachine(machine, start,  # its step: scenario.check_model_step
                                       actuator_series_n_per_m=None if plays is None
                                       else 0.5 * plays.contact_stiffness_n_per_m,
                                       drive_mass_on_legs=plays is None or not implicit)  # behind the plays: drive side
        try:
            self.state = state = fm.rest_state()
        except ConvergenceError as exc:
            series = ", with the plays' [clearance] contact_stiffness_n_per_m in series" if plays is not None else ""
            raise PressfitError(f"{case.path}: the flexible machine's rest state at [{plan.table}] start_m under "
                                f"gravity failed ({exc}): its legs{series} do not hold the weight") from None
        self.ctrl = ctrl = ForceLimitedController(machine=machine, rigid=plan.rigid, gains=sim.controller,
                                                  limiter=limiter, estimate_m=start.copy())
        self.lengths, self.rates = lengths, rates = fm.leg_lengths_m(state), fm.leg_rates_m_per_s(state)  # measured
        force = ctrl.command(lengths, rates, plan.trajectory.at(0.0), 0.0, 0.0)
        self.tension = tension = -ctrl.pinv @ force + ctrl.null @ self.preload
        self.series_compliance = machine.sensed_axial_compliance_m_per_n
        self.stretch = tension * self.series_compliance(lengths)  # the series spring's, N c, m
        self.sensed, self.sensed_rates = lengths - self.stretch, rates.copy()
        self.series_j = 0.5 * float(tension @ self.stretch)  # the series springs' energy, J
        self.play = play = None if plays is None else LegPlay(machine, plays, start, tension, fm.drive_mass_kg)
        self.extension = np.zeros(len(machine.legs))
        self.side = DriveSide(length_m=lengths.copy(), rate_m_per_s=rates.copy(),
                              acceleration_m_per_s2=np.zeros_like(rates))
        self.tool = tool = fm.tool_point_m(state)
        self.ledger = None if play is None else PlayLedger(fm.leg_lengths_m(state), lengths, self._side_kinetic_j(),
                                                           float(play.stored_energy_j(tool, self.extension).sum()))
        self.drive = drives.initial_state(tension, lengths)
        self.board, self.contact_force = sim.contact.board_height_m, 0.0
        self.depth = self.board - tool[1]
        self.series = Series(machine, steps, sim.start_m)
        placement, subtree = fm.section_state(state)  # per step; the section loads from them after the run (batched)
        self.placements, self.wrenches = np.empty((steps, *placement.shape)), np.empty((steps, *subtree.shape))
        self.no_axial = (0.0,) * len(machine.legs)
        self.internal = np.empty(machine.redundancy)

    def _side_kinetic_j(self) -> float:
        """The kinetic energy of the drives' reflected masses behind the plays, 1/2 m_d |l_d'|^2, J (constant
        without the plays: ``side`` keeps its start there)."""
        return 0.5 * self.fm.drive_mass_kg * float(self.side.rate_m_per_s @ self.side.rate_m_per_s)

    def _advance(self, command: np.ndarray) -> object:
        """One step of the machine and its drives under ``command`` (N): the drive stepped once and held (a force
        drive), or inside the step's Newton, behind the plays if any; returns what the drives act through."""
        fm, drives, dt, play = self.fm, self.drives, self.dt, self.play
        # no plate wrench (None): the contact acts inside the step (``contact``)
        if not drives.follows_travel:  # its tension does not follow the travel: stepped once, held over the step
            self.drive, self.tension = drives.step(self.drive, command, self.lengths, self.rates, dt)
            self.state = fm.step(self.state, DriveInput.forces(self.tension), None, dt, contact=self._contact)
            return None
        stepped = DriveOverStep(drives, self.drive, command, self.lengths, dt)
        through, k_step = stepped, drives.step_stiffness_n_per_m(self.lengths)
        if play is not None:
            through = play.over_step(stepped, self.tool, self.tension, k_step, self.side, dt)
            k_step = through.tangent_n_per_m
        self.state = fm.step(self.state, DriveInput.forces(self.tension), None, dt, through, k_step,
                             contact=self._contact)
        self.drive, self.tension = stepped.result
        if play is not None:
            self.side = through.side
        return through

    def _measure(self, through: object, legs_m: np.ndarray) -> tuple[float, float]:
        """What the drives measure after the step (their own side of the plays, if any) and the plays' energy
        account (stored, dissipated; J)."""
        play, tension = self.play, self.tension
        if play is not None and self.implicit:  # the drives measure their own side of the plays
            self.lengths, self.rates = self.side.length_m, self.side.rate_m_per_s
            return self.ledger.step(tension, through.force_n, legs_m, self.lengths, self._side_kinetic_j(),
                                    float(through.stored_energy_j().sum()))
        if play is not None:  # a massless force drive: the legs' lengths less the plays' extension
            before, self.extension = self.extension, play.extension_m(self.tool, tension)
            self.lengths, self.rates = self.lengths - self.extension, self.rates - (self.extension - before) / self.dt
            return self.ledger.step(tension, tension, legs_m, self.lengths, self._side_kinetic_j(),
                                    float(play.stored_energy_j(self.tool, self.extension).sum()))
        return 0.0, 0.0

    def step(self, k: int, t: float, reference: tuple[np.ndarray, np.ndarray], force_limit_n: float) -> None:
        fm, ctrl, guard, dt = self.fm, self.ctrl, self.guard, self.dt
        ctrl.force_limit_n = force_limit_n
        force = ctrl.command(self.drives.measure_lengths_m(self.sensed), self.sensed_rates, reference,
                             self.contact_force, dt)
        command = -ctrl.pinv @ force + ctrl.null @ self.preload
        replaced = fm.replacement_energy_j(self.state)  # the step re-places the stems first
        through = self._advance(command)
        state = self.state
        guard.finite(kernels.all_finite(state.q, state.v), t)
        drift = fm.closure_error(state)[0]
        guard.drift(drift, t)
        self.placements[k], self.wrenches[k] = fm.section_state(state)
        self.tool = tool = fm.tool_point_m(state)
        guard.pose(k, t, tool)
        previous, self.depth = self.depth, self.board - tool[1]
        guard.depth(self.depth, t)
        self.contact_force = contact_force_n(self.params, self.depth, (self.depth - previous) / dt)
        kernels.contact_advance(self.params, self.depth)
        legs_m = self.lengths = fm.leg_lengths_m(state)
        self.rates = fm.leg_rates_m_per_s(state)
        plays_j = self._measure(through, legs_m)
        series = self._sense()
        kernels.internal_forces(ctrl.null, self.tension, self.internal)
        tool_xyz = tool.tolist()  # Python floats: a row of them fills faster than of numpy scalars
        self.series.add(k, (t, *(reference[0] + [0.0, ctrl.lift_m, 0.0]).tolist(), *ctrl.estimate_m.tolist(),
                            *tool_xyz, *tool_xyz, self.contact_force, self.depth, *command.tolist(),
                            *self.tension.tolist(), ctrl.lift_m, drift, *self.no_axial, *self.internal.tolist()),
                        self.sensed, self.sensed_rates,
                        (*_energies(fm.energy(state), state.damping_work_j, self._side_kinetic_j(), series[0]),
                         *plays_j, replaced, series[1]))

    def _contact(self, plate_y_m: float) -> tuple[float, float]:
        """The contact in the step (:meth:`FlexibleMachine.step`'s ``contact``): at the tool's end-of-step y (m, the
        plate centre), the force on the tool (N, +y; its damping on the depth's rate over the step) and its stiffness
        -dF/dy (N/m, central differences over ``CONTACT_TANGENT_STEP_M``)."""
        depth, h, dt, law = self.board - plate_y_m, CONTACT_TANGENT_STEP_M, self.dt, kernels.contact_law
        if depth <= -h:  # clear of the board: no force, no stiffness
            return 0.0, 0.0
        force = law(self.params, depth, (depth - self.depth) / dt)
        return force, (law(self.params, depth + h, (depth + h - self.depth) / dt)
                       - law(self.params, depth - h, (depth - h - self.depth) / dt)) / (2.0 * h)

    def _sense(self) -> tuple[float, float]:
        """What the drives' sensors read after the step (module docstring): l - N c(l) and its differenced rate;
        returns the series springs' energy sum N^2 c / 2 and their loss over the step, N . ds - dE, J."""
        previous, self.stretch = self.stretch, self.tension * self.series_compliance(self.lengths)
        self.sensed = self.lengths - self.stretch
        self.sensed_rates = self.rates - (self.stretch - previous) / self.dt
        before, self.series_j = self.series_j, 0.5 * float(self.tension @ self.stretch)
        return self.series_j, float(self.tension @ (self.stretch - previous)) - (self.series_j - before)

    def rows(self) -> tuple[np.ndarray, np.ndarray]:
        machine = self.machine
        sections = leg_frame_loads(self.fm.section_wrenches_from(self.placements, self.wrenches),
                                   machine.cardan_axes)[0]
        rows = self.series.rows()
        rows[:, leg_columns(series_columns(len(machine.legs)), "axial_n")] = sections[:, :, 2, 0]  # plate
        return rows, sections


class PlayLedger:
    r"""The cardan plays' energy account over a flexible run's steps (the ``play_energy_j`` and
    ``play_dissipation_j`` columns, J): what the drives do on their side of the plays minus what reaches the legs.

    Over step k the drives' tensions D_k (the ``act_n`` columns, held over the step) do -D_k . dl_d on their side,
    l_d the drives' lengths (the ``length_m`` columns: what the sensors read); the plays' forces f_k (the tension
    the legs carry at the step's end, where the flexible step evaluates them) do -f_k . dq_a on the legs, q_a the
    legs' lengths between the cardan centres. Between the two sit the plays, of stored energy V
    (:meth:`pressfit.dynamics.play.LegPlay.stored_energy_j`), and the drives' reflected masses m_d (an electric
    drive behind the plays), of kinetic energy K_side = 1/2 m_d |l_d'|^2 (in the ``kinetic_energy_j`` column).
    The plays' dissipation over the step is what is left of the drives' work after the legs, the masses and the
    plays have taken theirs:

        P_k = -D_k . dl_d + f_k . dq_a - dK_side - dV
            = [f_k . dx - dV]  +  [(f_k - D_k) . dl_d - dK_side]     (x = q_a - l_d + x_0, the plays' extension)

    The first bracket is the plays' own: with the force held at its end value, sum_k f(x_k) (x_k - x_k-1) - dV
    = sum_k int_{x_k-1}^{x_k} (f(x_k) - f(x)) dx >= 0 for the monotone law, O(k dx^2) per step inside a contact
    (first order in the step), and on a crossing of the dead zone (a tension changing sign) about |f_k| 2 G: the
    massless drive side (an ideal force drive) crosses the gap 2 G at once under the drive's force and meets the
    contact with the work it did on the way -- the inelastic impact of a vanishing mass, a loss of the model
    whatever the step. The second bracket is the drive side's: the work of its net force on its mass minus its
    kinetic energy, generalised-alpha's energy error at rho_inf = ``DRIVE_SIDE_RHO_INF`` (0: the unresolved
    contact mode annihilated in a step, an inelastic impact, :mod:`pressfit.dynamics.play`); zero without a mass.
    The machine's own balance (:func:`pressfit.dynamics.sizing.energy_balance`) starts from -f_k . dq_a."""

    def __init__(self, legs_m: np.ndarray, drives_m: np.ndarray, side_j: float, stored_j: float) -> None:
        self.legs, self.drives = np.array(legs_m, float), np.array(drives_m, float)
        self.side_j, self.stored_j = float(side_j), float(stored_j)

    def step(self, drive_n: np.ndarray, play_n: np.ndarray, legs_m: np.ndarray, drives_m: np.ndarray,
             side_j: float, stored_j: float) -> tuple[float, float]:
        """The step to the legs' lengths q_a (n,), m, and the drives' l_d (n,), m, under the drives' tensions D
        (n,), N, and the plays' forces f (n,), N, to the drive side's kinetic energy and the plays' stored energy
        (J): (the stored energy, the step's dissipation P_k), J."""
        legs, drives = np.asarray(legs_m, float), np.asarray(drives_m, float)
        dissipation = (float(-np.asarray(drive_n, float) @ (drives - self.drives))
                       + float(np.asarray(play_n, float) @ (legs - self.legs))
                       - (side_j - self.side_j) - (stored_j - self.stored_j))
        self.legs, self.drives, self.side_j, self.stored_j = legs.copy(), drives.copy(), float(side_j), float(stored_j)
        return float(stored_j), dissipation


def _energies(energy: Energy, damping_work_j: float, drive_side_j: float = 0.0,
              series_j: float = 0.0) -> tuple[float, float, float, float]:
    """Kinetic (plus ``drive_side_j``, the drives' reflected masses behind the plays), potential and elastic
    (plus ``series_j``, the sensors' series springs) energy and the damping work, J."""
    kinetic = energy.kinetic_j + drive_side_j
    return kinetic, energy.potential_j, energy.elastic_j + series_j, damping_work_j
