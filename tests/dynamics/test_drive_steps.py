"""The time step against a hydraulic drive's oil column (issue 19, item 2): the explicit drive-mechanics
coupling's stability bound, derived in pressfit.dynamics.drives.hydraulic.oil_column_step_index, and the
refusal before a run."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from pressfit.description.cases import load_case
from pressfit.description.machine import load_machine
from pressfit.dynamics import drives, insertion
from pressfit.dynamics.drives.hydraulic import STEP_FRACTION
from pressfit.dynamics.drives.steps import leg_masses_kg
from pressfit.errors import DriveStepError, ModelFileError
from tests.dynamics.test_insertion_drives import SHORT, drive_case
from tests.test_simulation_trust import refused

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def hydraulic():
    return load_machine(ROOT / "models/pressfit_4upu_hydraulic.toml")


def _k_h(machine, length_m):
    """beta A^2 (1/V_a + 1/V_b) from the file (docs/drives.md), the piston centred in the stroke."""
    hy = machine.actuator.hydraulic
    x = length_m - 0.5 + 0.5 * (hy.stroke_m - 0.5)
    return hy.bulk_modulus_pa * hy.area_m2**2 * (1 / (hy.dead_volume_a_m3 + hy.area_m2 * (hy.stroke_m - x))
                                                 + 1 / (hy.dead_volume_b_m3 + hy.area_m2 * x))


@pytest.mark.parametrize(("omega_dt", "grows"), [(1.9, False), (2.1, True)])
def test_explicit_coupling_on_the_oil_column_is_stable_below_omega_dt_2(hydraulic, omega_dt, grows):
    """The drive (valve held closed, no leakage) on a 3 kg mass coupled as the simulation couples them: the drive
    steps with the rate held, then the mass takes the new force (semi-implicit Euler). omega_h dt = 1.9 stays
    bounded over 300 steps (symplectic: |z| = 1), 2.1 grows by orders of magnitude (|z| > 1) until a chamber
    pressure leaves the drive's range."""
    machine = hydraulic.with_overrides({"actuator": {"hydraulic": {"pressure_loop_gain_per_pa": 1e-300,
                                                                   "flow_feedforward": 0.0,
                                                                   "leakage_m3_per_s_pa": 0.0}}})
    drive, mass, l0 = drives.of(machine), 3.0, 0.75
    dt = omega_dt / math.sqrt(_k_h(machine, l0) / mass)
    state = drive.initial_state(np.zeros(1), np.full(1, l0))
    length, rate, peak = l0, 1e-4, 0.0
    first = 1e-4 * dt  # the first step's displacement
    try:
        for _ in range(300):
            state, tension = drive.step(state, np.zeros(1), np.full(1, length), np.full(1, rate), dt)
            rate -= dt * tension[0] / mass
            length += dt * rate
            peak = max(peak, abs(length - l0))
    except DriveStepError:
        peak = math.inf
    assert (peak > 1e3 * first) == grows, peak / first
    if not grows:
        assert peak < 3 * first / (omega_dt * math.sqrt(1 - omega_dt**2 / 4))  # the discrete oscillator's amplitude


def test_flexible_leg_mass_brackets_the_moving_parts(hydraulic):
    """The flexible model's actuator-joint mass lies between the moving parts at the cylinder end and those
    plus the whole stem (the stem tube moves with the joint when the other coordinates are held)."""
    m = leg_masses_kg(hydraulic, np.array([-0.15, 0.65, 0.1]), "flexible")
    moving = hydraulic.mass.actuator_moving_mass_kg
    stem = hydraulic.mass.density_kg_per_m3 * math.pi / 4 * hydraulic.stem.diameter_m**2 * 0.6
    assert np.all(m > moving) and np.all(m < moving + stem)


def test_hydraulic_flexible_at_1ms_is_refused_before_the_run(tmp_path):
    """The shipped hydraulic case on the flexible model at the 1 ms step: exit 2 before any step, one line
    naming the key, the leg, the oil column and the largest step."""
    path = drive_case(tmp_path, "hydraulic", {"model": "flexible", **SHORT})
    refused(path, "[simulation] time_step_s", "oil column of leg", "k_h = ", "f_h = ", "at most ")


def test_step_just_over_the_oil_column_bound_is_refused_and_just_under_is_not(tmp_path, hydraulic):
    """The bound dt* = 2 STEP_FRACTION / omega_h, omega_h = sqrt(k_h / m): k_h from the closed form at the leg
    length the refusal names (it must agree with the file's closed form), m the leg's mass; plan at 1.01 dt* is
    refused, at 0.99 dt* it is not."""
    path = drive_case(tmp_path, "hydraulic", {"model": "flexible", **SHORT})
    with pytest.raises(ModelFileError) as exc:
        insertion.plan_scenario(load_case(path))
    message = str(exc.value)
    k_h, length, mass = (float(x) for x in re.search(r"k_h = ([0-9.e+]+) N/m at leg length ([0-9.]+) m on "
                                                      r"([0-9.]+) kg", message).groups())
    assert k_h == pytest.approx(_k_h(hydraulic, length), rel=2e-3)  # the message prints 4 digits of the length
    bound = 2 * STEP_FRACTION / math.sqrt(_k_h(hydraulic, length) / mass)
    for factor, refused_ in ((1.01, True), (0.99, False)):
        case = load_case(drive_case(tmp_path, "hydraulic", {"model": "flexible", **SHORT,
                                                            "time_step_s": factor * bound}))
        if refused_:
            with pytest.raises(ModelFileError, match="oil column"):
                insertion.plan_scenario(case)
        else:
            insertion.plan_scenario(case)
