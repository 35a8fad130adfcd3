"""The scenario engine's seams (pressfit.dynamics.scenario, .series, .machine.registry, .machine.rigid): the one
registry of dynamics models and the names the schema and the CLI accept, the rigid-leg model behind the
dynamics-model interface, and a pin's figures (computed once for an insertion and for each pin of a board)."""

from __future__ import annotations

import re

import click
import numpy as np
import pytest

from pressfit.cli.dynamics import control_cmd, cycle_cmd
from pressfit.cli.study import study_cycle_cmd
from pressfit.description.cases import Cycle, Simulation, load_case
from pressfit.description.machine import load_machine
from pressfit.dynamics.cycle import plan_cycle
from pressfit.dynamics.insertion import plan_scenario
from pressfit.dynamics.linearise import control_design
from pressfit.dynamics.machine.base import DriveInput, DynamicsModel, MachineState
from pressfit.dynamics.machine.registry import MODELS, model_kind, model_names
from pressfit.dynamics.machine.rigid import RigidMachine
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.dynamics.scenario import COMPLETION_FRACTION, pin_figures
from pressfit.errors import ModelFileError, PressfitError


def _choices(command: click.Command) -> set[str]:
    return {c for p in command.params if p.name == "plant_model" for c in p.type.choices}


def test_the_registry_names_every_model_the_schema_and_the_cli_accept():
    """A model is one registry line: the CLI's ``--model`` offers exactly the registry's names (read from it, not
    spelled again), the schema's defaults are registered names; each class states its capabilities; an unknown name
    is refused naming the known ones."""
    assert model_names() == tuple(MODELS) == ("flexible", "rigid")
    assert _choices(cycle_cmd) == _choices(control_cmd) == _choices(study_cycle_cmd) == set(MODELS)
    assert {Simulation.model_fields["model"].default, Cycle.model_fields["model"].default} <= set(MODELS)
    assert {name: model_kind(name).elastic for name in MODELS} == {"flexible": True, "rigid": False}
    assert all(model_kind(name).integrator_error for name in MODELS)
    with pytest.raises(PressfitError, match="model must be 'flexible' or 'rigid', got 'stiff'"):
        model_kind("stiff")


@pytest.mark.parametrize("table", ["simulation", "cycle"])
def test_an_unregistered_model_in_a_case_is_refused_before_anything_is_computed(tmp_path, table):
    """``model = "stiff"`` in ``[simulation]`` or ``[cycle]``: the plan (and ``pressfit simulate`` / ``cycle`` /
    ``control``) refuse it with exit 2 and one line naming the file, the key and the registered names, before any
    physics runs (the schema takes any name: the registry is the one list)."""
    from click.testing import CliRunner

    from pressfit.cli import main
    from pressfit.shipped import cases_dir

    source = cases_dir() / "paper" / ("insertion.toml" if table == "simulation" else "board.toml")
    text, count = re.subn(r'^model = "\w+"', 'model = "stiff"', source.read_text(), flags=re.MULTILINE)
    assert count == 1
    path = tmp_path / "stiff.toml"
    path.write_text(text)
    expected = f"{path}: key '[{table}] model': a dynamics model, 'flexible' or 'rigid', got 'stiff'"
    case = load_case(path)
    with pytest.raises(ModelFileError) as refused:
        plan_scenario(case) if table == "simulation" else plan_cycle(case)
    assert str(refused.value) == expected
    commands = [["simulate" if table == "simulation" else "cycle"]] + ([["control"]] if table == "simulation" else [])
    for command in commands:
        result = CliRunner().invoke(main, [*command, str(path), "--out", str(tmp_path / "out")])
        assert result.exit_code == 2, (command, result.output)
        assert result.output.strip() == f"error: {expected}", (command, result.output)
        assert not (tmp_path / "out").exists()
    plan = plan_scenario if table == "simulation" else plan_cycle
    plan(load_case(source))  # the shipped case's own model plans
    override = r"key '--model': a dynamics model, 'flexible' or 'rigid', got 'stiff'"  # named as such
    with pytest.raises(ModelFileError, match=override):
        plan_cycle(load_case(source), model="stiff") if table == "cycle" else control_design(load_case(source), "stiff")


def test_the_rigid_model_implements_the_dynamics_interface():
    """RigidMachine is a DynamicsModel: every method of the protocol, and its step is the rigid-leg model's
    semi-implicit Euler step under -N on the actuator joints and the plate force in the plate's frame."""
    assert all(callable(getattr(RigidMachine, m)) for m in DynamicsModel.__dict__ if not m.startswith("_")
               and callable(DynamicsModel.__dict__[m]))
    machine = load_machine()
    rigid = rigid_leg_model(machine, np.array([0.0, 0.65, 0.0]))
    body = RigidMachine(rigid)
    state = MachineState(time_s=0.0, q=rigid.reference_q.copy(), v=np.zeros(rigid.model.nv))
    tension = np.full(len(machine.legs), -150.0)
    after = body.step(state, DriveInput.forces(tension), np.array([0.0, 20.0, 0.0, 0.0, 0.0, 0.0]), 1e-3)
    tau = np.zeros(rigid.model.nv)
    tau[rigid.actuator_v], tau[1] = 150.0, 20.0  # the unrotated plate: its frame is the world's
    q, v = rigid.step(state.q, state.v, tau, 1e-3)
    np.testing.assert_array_equal(after.q, q)
    np.testing.assert_array_equal(after.v, v)
    assert after.time_s == 1e-3
    np.testing.assert_array_equal(body.leg_lengths_m(after), q[rigid.actuator_q])
    np.testing.assert_array_equal(body.tool_point_m(after), q[0:3])
    energy = body.energy(after)
    assert energy.elastic_j == 0.0 and energy.kinetic_j > 0.0
    assert body.closure_error(after)[0] < 1e-6
    with pytest.raises(PressfitError, match="force drives only"):
        body.step(state, DriveInput.positions(np.full(len(machine.legs), 0.5)), np.zeros(6), 1e-3)


def test_pin_figures_of_a_settled_insertion():
    """A force ramping to 100 N at row 10 and held over the dwell (rows 20-39): first contact at row 1, peak 100 N
    (overshoot 70 N over a 30 N limit), steady 100 N, settled at row 10 (0.009 s after the first contact), completed
    against a target of 100 N; the lateral error at first contact is the tool's (x, z) distance from the pin."""
    t = 1e-3 * np.arange(40)
    force = np.minimum(np.arange(40) * 10.0, 100.0)
    tool = np.column_stack([np.full(40, 3e-6), np.full(40, -4e-6)])
    fig = pin_figures(t, force, tool, np.arange(20, 40), np.zeros(2), 100.0, 30.0)
    assert (fig.first_contact, fig.peak, fig.peak_n, fig.overshoot_n, fig.steady_n) == (1, 10, 100.0, 70.0, 100.0)
    assert fig.settled_row == 10 and fig.settling_s == pytest.approx(0.009)
    assert fig.completed and fig.note == "" and fig.lateral_m == pytest.approx(5e-6)
    short = pin_figures(t, force, tool, np.arange(20, 40), np.zeros(2), 100.0 / (0.99 * COMPLETION_FRACTION), 30.0)
    assert not short.completed and "below 90% of the target" in short.note
    none = pin_figures(t, np.zeros(40), tool, np.arange(20, 40), np.zeros(2), 100.0, 30.0)
    assert none.first_contact is None and none.lateral_m is None and none.note == "no contact at the end of the dwell"
