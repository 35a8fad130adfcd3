"""The rigid-leg model in a scenario (:mod:`pressfit.dynamics.machine.rigid`): what it puts in series at the tool."""

from __future__ import annotations

import numpy as np
import pytest

from pressfit.description.cases import load_case
from pressfit.dynamics.machine.rigid import _hidden_compliance
from pressfit.mechanics.clearance import clearance_from_case, load_deflection
from pressfit.mechanics.preload import ActuatorPreload
from pressfit.shipped import cases_dir


def test_the_clearance_table_of_a_hydraulic_machine_leaves_out_the_oil_column():
    """With ``clearance = true`` the rigid model's series deflection is the clearance model's load-deflection table
    at the pin, of the machine as its sensors see it: for the hydraulic case the table of a second machine, the same
    file with the oil 1e6 times stiffer, to 1e-5 of its largest displacement (the piston sensor reads past the oil
    column, which the drive's pressures already carry); the full machine's, with the oil column, moves the tool 30%
    and more further at the largest load."""
    case = load_case(cases_dir() / "paper" / "insertion_hydraulic.toml")
    sim = case.simulation.model_copy(update={"clearance": True})
    case = case.model_copy(update={"simulation": sim})
    machine = case.machine()
    pin = np.array([sim.contact.pin_position_m[0], sim.contact.board_height_m, sim.contact.pin_position_m[1]])
    loads, table = _hidden_compliance(machine, case, sim, pin)

    def curve(m):
        c = load_deflection(m, pin, [0.0, 1.0, 0.0], loads, clearance_from_case(case, m),
                            ActuatorPreload.from_case(case.preload).a4, unload=False).loading.displacement_m
        return c - c[0]

    stiff = curve(machine.with_overrides({"actuator": {"hydraulic": {"bulk_modulus_pa": 1.2e15}}}))
    scale = np.abs(stiff).max()
    assert np.abs(table - stiff).max() < 1e-5 * scale
    full = curve(machine)
    assert full[-1, 1] > 1.3 * stiff[-1, 1]


def test_a_plate_that_leaves_the_joint_limits_stops_the_run_naming_the_leg_and_limit(monkeypatch):
    """The guard of the rigid step (compiled on the joints every step, named from the plate pose's inverse
    kinematics): the shipped scenario's state put 1e-5 m beyond the pose where a leg reaches its maximum length
    (straight up from the start pose; bisected on ``kinematics.violations``) stops at the next step with the
    divergence's line naming that leg's limit; 1e-5 m inside it, the step runs (one step at rest moves the plate
    by about a dt^2 = 1e-7 m)."""
    from pressfit import kinematics
    from pressfit.dynamics import drives as drive_kinds
    from pressfit.dynamics.insertion import plan_scenario
    from pressfit.dynamics.machine.rigid import RigidScenario
    from pressfit.dynamics.series import Guard
    from pressfit.errors import PressfitError

    case = load_case(cases_dir() / "paper" / "insertion.toml")
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"model": "rigid"})})
    machine = case.machine()
    plan = plan_scenario(case, machine)
    start = np.asarray(case.simulation.start_m, float)
    lo, hi = 0.0, 0.5
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if not kinematics.violations(machine, start + [0.0, mid, 0.0]) else (lo, mid)
    leg, name, _, bound = kinematics.violations(machine, start + [0.0, hi + 1e-5, 0.0])[0]
    assert name == "leg length l [m]" and bound.startswith("maximum")
    reference = plan.trajectory.at(4e-4)  # step 3 (the guard's inverse kinematics runs every 10 steps only)
    for offset, refused in ((-1e-5, False), (1e-5, True)):
        scenario = RigidScenario(case, machine, plan, drive_kinds.of(machine), True, Guard(case, machine, plan))
        with monkeypatch.context() as m:  # a closed configuration past the limit (configuration_at refuses one)
            m.setattr("pressfit.dynamics.multibody.kinematics.require_reachable", lambda machine, h, ik=None: h)
            scenario.q = plan.rigid.configuration_at(start + [0.0, hi + offset, 0.0])
        if not refused:
            scenario.step(3, 4e-4, reference, 30.0)
            continue
        with pytest.raises(PressfitError) as info:
            scenario.step(3, 4e-4, reference, 30.0)
        line = str(info.value)
        assert "left the reachable set" in line and f"leg {leg}" in line and "leg length" in line, line
        assert "at t = 0.0004 s" in line and "[simulation.controller]" in line


def test_with_clearance_the_tools_deflection_is_the_sag_plus_the_load_deflection_table():
    """The shipped rigid insertion with ``clearance = true``: through the dwell, the tool's deflection from the rigid
    pose (tool - plate) is the weight's sag at the plate pose (the columns computed afresh: the run extrapolates
    them, 1.5e-4 of them) plus the clearance model's load-deflection table (at the descent's end) at the recorded
    contact force, linearly interpolated, to 1e-9 m plus 2e-4 of the sag; the compliance column c0 F is not added on
    top (it is 30 N x c0, microns, here)."""
    from pressfit.dynamics.control import Trajectory, static_deflection_columns
    from pressfit.dynamics.insertion import simulate_insertion
    from pressfit.dynamics.multibody import rigid_leg_model

    case = load_case(cases_dir() / "paper" / "insertion.toml")
    sim = case.simulation.model_copy(update={"model": "rigid", "clearance": True})
    case = case.model_copy(update={"simulation": sim})
    machine = case.machine()
    result = simulate_insertion(case)
    bottom = Trajectory.insertion(sim).waypoints_m[2]  # the table's pose: the descent's end at the interference
    loads, table = _hidden_compliance(machine, case, sim, bottom)
    col = {name: k for k, name in enumerate(result.columns)}
    rows = result.series[result.phases == result.phase_names.index("dwell")][::50]
    rigid = rigid_leg_model(machine, bottom)
    worst_c0 = 0.0
    for row in rows:
        plate = row[[col["plate_x_m"], col["plate_y_m"], col["plate_z_m"]]]
        tool = row[[col["tool_x_m"], col["tool_y_m"], col["tool_z_m"]]]
        force = row[col["contact_force_n"]]
        columns = static_deflection_columns(machine, rigid, plate)
        expected = columns[:, 1] + np.array([np.interp(force, loads, table[:, k]) for k in range(3)])
        assert np.abs((tool - plate) - expected).max() <= 1e-9 + 2e-4 * np.abs(columns[:, 1]).max()
        worst_c0 = max(worst_c0, float(np.abs(columns[:, 0] * force).max()))
    assert force > 20.0 and worst_c0 > 1e-6  # a column term that the tolerance would catch


def test_a_state_that_is_not_finite_is_named_so_not_as_an_unreachable_pose():
    """A NaN in the rigid state (a diverged step) fails the joints' reach check too (NaN compares false): the guard
    names it as a state that is not finite at its time, not as a plate that left the reachable set at (nan, ...)."""
    from pressfit.dynamics import drives as drive_kinds
    from pressfit.dynamics.insertion import plan_scenario
    from pressfit.dynamics.machine.rigid import RigidScenario
    from pressfit.dynamics.series import Guard
    from pressfit.errors import PressfitError

    case = load_case(cases_dir() / "paper" / "insertion.toml")
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"model": "rigid"})})
    machine = case.machine()
    plan = plan_scenario(case, machine)
    scenario = RigidScenario(case, machine, plan, drive_kinds.of(machine), True, Guard(case, machine, plan))
    scenario.v = scenario.v.copy()
    scenario.v[scenario.plan.rigid.actuator_v[1]] = np.nan
    with pytest.raises(PressfitError, match=r"diverged at t = 0.0004 s \(the state is not finite\)"):
        scenario.step(3, 4e-4, plan.trajectory.at(4e-4), 30.0)
