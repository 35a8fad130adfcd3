"""The rigid-leg model in a scenario (:mod:`pressfit.dynamics.machine.rigid`): what it puts in series at the tool."""

from __future__ import annotations

import numpy as np

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
    column_scale, (loads, table) = _hidden_compliance(machine, case, sim, pin)
    assert column_scale == 0.0  # the table replaces the compliance column (c0 F)

    def curve(m):
        c = load_deflection(m, pin, [0.0, 1.0, 0.0], loads, clearance_from_case(case, m),
                            ActuatorPreload.from_case(case.preload).a4, unload=False).loading.displacement_m
        return c - c[0]

    stiff = curve(machine.with_overrides({"actuator": {"hydraulic": {"bulk_modulus_pa": 1.2e15}}}))
    scale = np.abs(stiff).max()
    assert np.abs(table - stiff).max() < 1e-5 * scale
    full = curve(machine)
    assert full[-1, 1] > 1.3 * stiff[-1, 1]
