r"""The rigid-leg model behind the dynamics-model interface (:class:`pressfit.dynamics.machine.base.DynamicsModel`)
and its scenario step.

:class:`RigidMachine` wraps :class:`pressfit.dynamics.multibody.RigidLegModel` (Pinocchio constraint dynamics,
semi-implicit Euler, Baumgarte-stabilised closures) in the interface's immutable states: force drives on the
prismatic joints (-N_i, N_i > 0 tension), a plate force at the plate centre; no elastic energy, no sections (the
rigid model's couples are not objective).

:class:`RigidScenario` is the model in a scenario (:mod:`pressfit.dynamics.scenario`): the compliance in series
at the tool, quasi-statically. Per step: the controller at the estimate, the drives, one Pinocchio step, the joints
against Table 3's limits (:func:`pressfit.dynamics.kernels.within_limits`: the guard names the plate pose's broken
limit where they leave), the deflection cache's rows for the new pose (computed beforehand along the planned path,
:class:`pressfit.dynamics.control.DeflectionCache`), then one compiled kernel
(:func:`pressfit.dynamics.kernels.rigid_post_step`) for the deflection extrapolated to the new pose, the contact, the
axial forces, the pose estimate of the new lengths (the next step's controller estimate and, continued to
``KINEMATIC_ITERATIONS``, the row's kinematic pose) and the row; the energies (``ENERGY_COLUMNS``) from the rigid
model.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pressfit.description.cases import Case, Simulation
from pressfit.description.machine import Machine
from pressfit.dynamics import drives as drive_kinds
from pressfit.dynamics import kernels
from pressfit.dynamics.contact import NO_TABLE, contact_force_n, contact_parameters
from pressfit.dynamics.control import ForceLimitedController
from pressfit.dynamics.machine.base import DriveInput, Energy, MachineState, SectionLoads
from pressfit.dynamics.multibody import RigidLegModel
from pressfit.dynamics.series import (
    ENERGY_COLUMNS,
    KINEMATIC_ITERATIONS,
    Guard,
    ScenarioPlan,
    Series,
    preload_amplitudes_n,
    series_columns,
)
from pressfit.errors import PressfitError
from pressfit.mechanics.clearance import clearance_from_case, load_deflection
from pressfit.mechanics.preload import ActuatorPreload

CURVE_POINTS = 41  # load steps of the clearance load-deflection curve


class RigidMachine:
    """:class:`pressfit.dynamics.machine.base.DynamicsModel` on the rigid-leg model (module docstring); force
    drives only."""

    def __init__(self, rigid: RigidLegModel) -> None:
        self.rigid = rigid

    def step(self, state: MachineState, drive_input: DriveInput, plate_wrench: np.ndarray,
             dt_s: float) -> MachineState:
        if drive_input.kind != "force":
            raise PressfitError("the rigid-leg model takes force drives only (its actuator joints carry no spring)")
        rigid, tau = self.rigid, np.zeros(self.rigid.model.nv)
        tau[rigid.actuator_v] = -drive_input.values
        rotation = pin.Quaternion(state.q[3:7]).matrix()
        wrench = np.asarray(plate_wrench, dtype=float)
        tau[0:3], tau[3:6] = rotation.T @ wrench[:3], rotation.T @ wrench[3:]  # the plate's local frame
        q, v = rigid.step(state.q, state.v, tau, dt_s)
        return MachineState(time_s=state.time_s + dt_s, q=q, v=v)

    def plate_pose(self, state: MachineState) -> tuple[np.ndarray, np.ndarray]:
        return state.q[0:3].copy(), pin.Quaternion(state.q[3:7]).matrix()

    def tool_point_m(self, state: MachineState) -> np.ndarray:
        return state.q[0:3].copy()  # the rigid tool point; a scenario adds the compliance in series

    def leg_lengths_m(self, state: MachineState) -> np.ndarray:
        return state.q[self.rigid.actuator_q].copy()

    def leg_rates_m_per_s(self, state: MachineState) -> np.ndarray:
        return state.v[self.rigid.actuator_v].copy()

    def section_loads(self, state: MachineState) -> SectionLoads:
        raise PressfitError("the rigid-leg model has no objective section loads (its couples are statically "
                            "indeterminate): use the flexible model")

    def closure_error(self, state: MachineState) -> tuple[float, float]:
        """The translation error of the closures at the last step (rad: not tracked, 0)."""
        return self.rigid.closure_error_m(), 0.0

    def energy(self, state: MachineState) -> Energy:
        kinetic, potential = self.rigid.energy_j(state.q, state.v)
        return Energy(kinetic_j=kinetic, elastic_j=0.0, potential_j=potential)


def _hidden_compliance(machine: Machine, case: Case, sim: Simulation, pin_pose: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    """How the tool's quasi-static deflection at the rigid pose enters
    :func:`pressfit.dynamics.kernels.solve_contact`: u = c0 F + c1 under the contact force F (N, +y) and the moving
    parts' weight (c0 m/N and the sag c1 m, the rows of the controller's cache ``ForceLimitedController.deflection``
    at the rigid pose, :func:`pressfit.dynamics.control.static_deflection_columns`; the estimate and the rigid pose
    differ by the closure drift, so one refresh serves both): no table; or, with ``clearance``, c1 + the clearance
    model's load-deflection table at the pin (loads (n,), N; displacements (n, 3), m) for the contact force, of the
    machine as its sensors see it (``Machine.sensed_view``: a hydraulic oil column rigid)."""
    if not sim.clearance:
        return NO_TABLE
    params = contact_parameters(sim.contact)
    law_force = (contact_force_n(params, sim.interference_m) if params[kernels.LAW] == kernels.TABLE
                 else sim.contact.stiffness_n_per_m * sim.interference_m)
    limit = max(4.0 * sim.controller.force_limit_n, law_force)
    curve = load_deflection(machine.sensed_view, pin_pose, [0.0, 1.0, 0.0], np.linspace(0.0, limit, CURVE_POINTS),
                            clearance_from_case(case, machine), ActuatorPreload.from_case(case.preload).a4,
                            unload=False)
    return (np.ascontiguousarray(curve.loads_n, dtype=float),
            np.ascontiguousarray(curve.loading.displacement_m - curve.loading.displacement_m[0], dtype=float))


class RigidScenario:
    """The rigid-leg model in a scenario (module docstring; :class:`pressfit.dynamics.series.ScenarioStep`)."""

    elastic = False
    integrator_error = "semi-implicit Euler's energy error sum 1/2 dv^T M dv"
    # the legs' couples are statically indeterminate here (a minimum-norm split, not mirror-objective): no torsion or
    # bending limits ([simulation.limits], scenario.check_limits_offered)
    objective_couples = False
    contact_implicit = False  # the contact force computed at a step's end acts over the next step

    def __init__(self, case: Case, machine: Machine, plan: ScenarioPlan, drives: drive_kinds.Drive, limiter: bool,
                 guard: Guard) -> None:
        sim, rigid = plan.simulation, plan.rigid
        self.case, self.machine, self.plan, self.drives, self.guard = case, machine, plan, drives, guard
        self.dt = sim.time_step_s
        self.q, self.v = rigid.reference_q.copy(), np.zeros(rigid.model.nv)
        self.ctrl = ctrl = ForceLimitedController(machine=machine, rigid=rigid, gains=sim.controller, limiter=limiter,
                                                  estimate_m=np.asarray(sim.start_m, float).copy(),
                                                  preload_n=preload_amplitudes_n(case, machine),
                                                  path_m=plan.path_m)
        self.table = _hidden_compliance(machine, case, sim, plan.trajectory.waypoints_m[2])
        act_q, act_v = rigid.actuator_q, rigid.actuator_v
        ctrl.command(self.q[act_q], self.v[act_v], plan.trajectory.at(0.0), 0.0, 0.0)
        self.drive = drives.initial_state(ctrl.tension_n.copy(), self.q[act_q])
        ctrl.observe(self.q[act_q])  # the first step's estimate (later ones: rigid_post_step's)
        self.params = contact_parameters(sim.contact, machine)
        columns = series_columns(len(machine.legs))
        self.post = np.array([columns.index(c) for c in ("plate_x_m", "tool_x_m", "contact_force_n", "depth_m",
                                                         "axial_n1", "kinematic_x_m", "length_m1", "rate_m_per_s1")])
        self.pre = np.array([columns.index(c) for c in ("time_s", "ref_x_m", "est_x_m", "cmd_n1", "act_n1",
                                                        "reference_lift_m")]
                            + [columns.index("axial_n1") + len(machine.legs)])  # the internal forces follow the axial
        self.drift_column = columns.index("closure_drift_m")
        self.kinetic = columns.index(ENERGY_COLUMNS[0])  # then the potential energy
        self.series = Series(machine, plan.steps, sim.start_m)
        lim = machine.limits
        self.limits = np.array([lim.leg_length_min_m, lim.leg_length_max_m, lim.alpha_min_rad, lim.alpha_max_rad,
                                lim.beta_min_rad, lim.beta_max_rad])  # kernels.within_limits'
        self.tau, self.contact_tau, self.u = np.zeros(rigid.model.nv), np.zeros(3), np.empty(3)
        column, sag = ctrl.deflection(self.q[0:3])
        self.force, self.depth = kernels.solve_contact(self.params, sim.contact.board_height_m - self.q[1], 0.0,
                                                       self.dt, column, sag, *self.table, self.u)
        self.contact_tau[:] = pin.Quaternion(self.q[3:7]).matrix().T @ np.array([0.0, self.force, 0.0])  # local frame
        self.lengths, self.rates = self.q[act_q], self.v[act_v]

    def step(self, k: int, t: float, reference: tuple[np.ndarray, np.ndarray], force_limit_n: float) -> None:
        ctrl, rigid, dt, guard = self.ctrl, self.plan.rigid, self.dt, self.guard
        ctrl.force_limit_n = force_limit_n
        ctrl.command_at_estimate(self.rates, reference, self.force, dt)
        command = ctrl.tension_n.copy()  # equation 5 at the estimate, plus the preload
        self.drive, tension = self.drives.step(self.drive, command, self.lengths, self.rates, dt)
        row = self.series.row(k)
        kernels.rigid_pre_step(row, t, reference[0], ctrl.lift_m, ctrl.estimate_m, command, tension, ctrl.null,
                               self.tau, rigid.actuator_v, self.contact_tau, self.pre)
        previous = self.q
        self.q, self.v = q, v = rigid.step(previous, self.v, self.tau, dt)
        if not kernels.within_limits(q, rigid.actuator_q, rigid.sigma, self.limits):  # its joints, every step
            guard.finite(kernels.all_finite(q, v), t)
            guard.pose(k, t, q[0:3], every=1)  # the plate pose's limits, named
        deflection = ctrl.deflection
        deflection.refresh(q[0:3])
        finite, self.force, self.depth, ctrl.estimate_residual_m = kernels.rigid_post_step(
            row, previous, q, v, rigid.data.lambda_c, rigid.actuator_q, rigid.actuator_v, self.params, self.depth,
            dt, deflection.pose_m, deflection.rows, deflection.gradient, *self.table, ctrl.offsets_m,
            ctrl.estimate_m, ctrl.units, ctrl.gains.estimator_iterations, KINEMATIC_ITERATIONS, self.contact_tau,
            self.post, self.lengths, self.rates)
        guard.finite(finite, t)
        guard.depth(self.depth, t)
        row[self.drift_column] = drift = rigid.closure_error_m()
        guard.drift(drift, t)
        row[self.kinetic], row[self.kinetic + 1] = rigid.energy_j(q, v)  # no elastic energies: the row's zeros

    def rows(self) -> tuple[np.ndarray, None]:
        return self.series.rows(), None
