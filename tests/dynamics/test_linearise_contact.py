"""The controller's linearisation of the contact (dynamics/linearise.py: ``contact_stiffness_n_per_m``): the contact
law's local slope at the operating depth, against a central difference of the law (an independent evaluation of
the same law: its force only, not its closed-form slope); the paper's elastic spring unchanged."""

from __future__ import annotations

import numpy as np
import pytest

from pressfit.description.cases import Contact, load_case
from pressfit.description.machine import DEFAULT_MODEL, load_machine
from pressfit.dynamics.linearise import contact_stiffness_n_per_m, control_design, linear_plant
from pressfit.errors import PressfitError
from pressfit.mechanics.condensed import condensed_plate_compliance
from pressfit.mechanics.contact_laws import build_law
from pressfit.mechanics.press_curve import PinField, solve_field
from pressfit.shipped import cases_dir

PIN_POSE = np.array([0.10, 0.60, -0.05])  # insertion.toml's pin pose, m
COMPLIANT = dict(law="compliant_pin", hole_diameter_m=1.0e-3, zone_width_m=1.15e-3, radial_stiffness_n_per_m=1.6e6,
                 radial_yield_force_n=80.0, post_yield_stiffness_n_per_m=3.7e5, zone_length_m=1.0e-3,
                 lead_in_length_m=0.6e-3, friction_coefficient=0.15, seat_depth_m=1.4e-3, seat_stiffness_n_per_m=2e6)
H_M = 1e-9  # central-difference step, m: the law's curvature error k'' h^2 / 6 is far below 1e-6 relative


@pytest.fixture(scope="module")
def machine():
    return load_machine(DEFAULT_MODEL)


@pytest.mark.slow
def test_the_elastic_spring_is_linearised_as_before(machine):
    """The paper's elastic law: k_c = stiffness_n_per_m exactly at any depth and without one (the numbers of
    ``pressfit control`` unchanged), the rigid plant's contact output -k_c per metre of tool travel; the shipped
    insertion's control design reports it."""
    case = load_case(cases_dir() / "paper" / "insertion.toml")
    contact = case.simulation.contact
    for depth in (None, 1e-4, 6e-4, 2e-3):
        assert contact_stiffness_n_per_m(machine, PIN_POSE, contact, depth) == 5.0e4
    plant = linear_plant(machine, PIN_POSE, contact, "rigid")
    assert plant.c_contact[1] == -5.0e4 and plant.contact_stiffness_n_per_m == 5.0e4
    assert np.array_equal(plant.a, linear_plant(machine, PIN_POSE, contact, "rigid", contact_depth_m=6e-4).a)
    design = control_design(case, "rigid").poses[0]
    assert design.in_contact and design.contact_stiffness_n_per_m == 5.0e4
    assert design.contact_depth_m == pytest.approx(30.0 / 5.0e4, rel=1e-9)  # 30 N limit on the 5e4 N/m spring


@pytest.mark.parametrize("depth_m", [0.3e-3, 0.8e-3, 1.3e-3, 1.45e-3])
def test_a_compliant_pin_is_linearised_at_its_local_slope(machine, depth_m):
    """One compliant pin on the tool axis: k_c at the lead-in (0.3 mm: 51847 N/m), the wedge's fade (0.8 mm:
    -51117 N/m, a falling curve), the plateau (1.3 mm: 0) and on the shoulder (1.45 mm: 2e6 N/m) is the central
    difference of the law's force (h = 1 nm) to 1e-6 relative (achieved 3e-12 .. 1.2e-10, the plateau exactly), and
    the rigid plant's contact output is -k_c; none is the ContactLaw's default 5e4 N/m the linearisation used
    before."""
    contact = Contact(board_height_m=0.6, pin_position_m=[0.1, -0.05], **COMPLIANT)
    law = build_law("compliant_pin", contact.law_keys())
    forces = law.force_n(np.array([depth_m - H_M, depth_m + H_M]))
    central = (forces[1] - forces[0]) / (2 * H_M)
    k_c = contact_stiffness_n_per_m(machine, PIN_POSE, contact, depth_m)
    assert k_c == pytest.approx(central, rel=1e-6)
    assert abs(k_c - 5.0e4) > 1e3  # not the ContactLaw's default stiffness_n_per_m
    plant = linear_plant(machine, PIN_POSE, contact, "rigid", contact_depth_m=depth_m)
    assert plant.c_contact[1] == pytest.approx(-k_c, rel=1e-12)


def test_a_pin_field_is_linearised_at_its_total_forces_slope_with_the_tilt(machine):
    """The shipped four-pin compliant component at the pin pose: k_c is the slope of the component's total force
    (the pins' laws in series with the tilt) against the tool depth, checked by a central difference of the solved
    total force (h = 1 nm) at the lead-in (0.3 mm) and in the wedge's fade (0.9 mm), to 1e-6 relative (achieved
    3e-12 and 1e-11; away from the fade's end at 1.2 mm, a kink where a central difference straddles two slopes)."""
    case = load_case(cases_dir() / "paper" / "insertion_compliant_pin.toml")
    contact = case.simulation.contact
    pins = PinField.from_contact(contact)
    compliance = condensed_plate_compliance(machine, PIN_POSE)
    for depth in (0.3e-3, 0.9e-3):
        total = solve_field(pins, compliance, np.array([depth - H_M, depth + H_M])).pin_forces_n.sum(axis=1)
        assert contact_stiffness_n_per_m(machine, PIN_POSE, contact, depth) == pytest.approx(
            (total[1] - total[0]) / (2 * H_M), rel=1e-6)


@pytest.mark.slow
def test_the_shipped_compliant_pin_is_linearised_where_the_press_holds_it(machine):
    """``pressfit control`` on the shipped compliant-pin case linearises the contact where the component's force
    reaches the 400 N limit (on the shoulders: four seat springs of 2e6 N/m in parallel, 8e6 N/m to 1e-6; achieved
    3e-16), not at the ContactLaw's default 5e4 N/m it used before; without a depth such a law is refused."""
    case = load_case(cases_dir() / "paper" / "insertion_compliant_pin.toml")
    design = control_design(case, "rigid").poses[0]
    pins = PinField.from_contact(case.simulation.contact)
    total = solve_field(pins, condensed_plate_compliance(machine, PIN_POSE),
                        np.array([design.contact_depth_m])).pin_forces_n.sum()
    assert total == pytest.approx(400.0, rel=1e-3)
    assert design.contact_depth_m > 1.4e-3
    assert design.contact_stiffness_n_per_m == pytest.approx(4 * 2.0e6, rel=1e-6)
    with pytest.raises(PressfitError, match="operating depth"):
        contact_stiffness_n_per_m(machine, PIN_POSE, case.simulation.contact)
