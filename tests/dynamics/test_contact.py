"""The insertion's contact (:mod:`pressfit.dynamics.contact`, ``kernels.contact_law``): a pin law's joint sets. Backing
off from the deepest depth d_max it reached, the tool unloads it elastically, F(d_max) - k_u (d_max - d), down to 0,
and reloads it along the same line; k_u is the force table's steepest slope; the elastic law (the paper's spring)
and a field of elastic pins follow their law back. Closed forms on the tables themselves."""

from __future__ import annotations

import numpy as np
import pytest

from pressfit.description.cases import Contact
from pressfit.dynamics import kernels
from pressfit.dynamics.contact import contact_force_n, contact_parameters, steepest_slope_n_per_m
from pressfit.mechanics.press_curve import force_table

SOLID = dict(law="solid_pin", pin_diameter_m=1.008e-3, hole_diameter_m=1.0e-3, pin_youngs_modulus_pa=1.2e11,
             pin_poisson_ratio=0.34, board_youngs_modulus_pa=2.2e10, board_poisson_ratio=0.28,
             friction_coefficient=0.2, engaged_length_m=1.6e-3, chamfer_length_m=2e-4, seat_depth_m=1.5e-3,
             seat_stiffness_n_per_m=3e6)


def _contact(**keys):
    return Contact(board_height_m=0.6, pin_position_m=[0.1, -0.05], **keys)


def test_a_pin_joint_unloads_from_its_deepest_depth_and_reloads_along_the_same_line():
    """Solid pin with a shoulder: pressed to 1.2 mm (``contact_advance``), the force at 1.2 mm - delta is
    F(1.2 mm) - k_u delta (k_u the table's steepest slope: the seat's 3e6 N/m past the shoulder), zero below
    1.2 mm - F / k_u (no adhesion), the same line on the way back in, and the table again past 1.2 mm; a fresh
    parameter vector starts at d_max = 0 (the law itself). k_u past the shoulder: the seat's 3e6 N/m plus the pin's
    own slope there (its engaged length still growing: mu p pi d = 7.9e4 N/m)."""
    params = contact_parameters(_contact(**SOLID))
    table = force_table(None, _contact(**SOLID))
    k_u = params[kernels.TABLE_UNLOAD]
    from pressfit.mechanics.contact_laws import build_law

    pin = build_law("solid_pin", {k: v for k, v in SOLID.items() if k not in ("law", "seat_depth_m",
                                                                              "seat_stiffness_n_per_m")})
    own = float(pin.force_and_slope(np.array([1.55e-3]))[1][0])
    assert k_u == steepest_slope_n_per_m(table) == pytest.approx(3e6 + own, rel=1e-6)
    law = lambda d: float(np.interp(d, table.depth_m, table.force_n))
    d_max = 1.2e-3
    assert contact_force_n(params, 0.6e-3) == pytest.approx(law(0.6e-3), rel=1e-12)  # fresh: loading
    kernels.contact_advance(params, d_max)
    kernels.contact_advance(params, 0.5e-3)  # a shallower step does not move the state
    assert params[kernels.TABLE_DEEPEST] == d_max
    top = law(d_max)
    for delta in (1e-6, 5e-6, 0.5 * top / k_u):
        assert contact_force_n(params, d_max - delta) == pytest.approx(top - k_u * delta, rel=1e-9)
    assert contact_force_n(params, d_max - 1.01 * top / k_u) == 0.0
    assert contact_force_n(params, 0.6e-3) == 0.0  # backed off: not the law's force at 0.6 mm
    assert contact_force_n(params, d_max + 2e-5) == pytest.approx(law(d_max + 2e-5), rel=1e-12)
    assert contact_parameters(_contact(**SOLID))[kernels.TABLE_DEEPEST] == 0.0


def test_springs_follow_their_law_back():
    """The elastic law on the axis (the kernels' own code, the paper's) and a field of elastic pins (a table): no
    unloading branch (k_u = 0), so after a deeper step the force at a shallower depth is the law's, k d."""
    for contact in (_contact(stiffness_n_per_m=5e4),
                    _contact(stiffness_n_per_m=5e4, pins=[{"offset_m": [0.01, 0.0]}, {"offset_m": [-0.01, 0.0]}])):
        params = contact_parameters(contact)
        kernels.contact_advance(params, 2e-3)
        pins = max(len(contact.pins), 1)
        assert contact_force_n(params, 1e-3) == pytest.approx(pins * 5e4 * 1e-3, rel=1e-9)
        if params[kernels.LAW] == kernels.TABLE:
            assert params[kernels.TABLE_UNLOAD] == 0.0


def test_every_board_position_has_its_own_fresh_joint():
    """``cycle.segment_contacts``: one parameter vector per board position, shared by that position's segments
    (the joint's state carries through its descent, dwell and retract) and distinct between positions (a new hole),
    for one pin on the axis too; the step loop copies it at each position, so a plan runs twice alike."""
    from pressfit.description.cases import load_case
    from pressfit.dynamics.cycle import plan_cycle
    from pressfit.shipped import cases_dir

    case = load_case(cases_dir() / "paper" / "board.toml")
    plan = plan_cycle(case)
    contacts, segments = plan.scenario.contact_params, plan.segments
    assert len(contacts) == len(segments)
    for a, sa in zip(contacts, segments):
        for b, sb in zip(contacts, segments):
            assert (a is b) == (sa.pin == sb.pin)


def test_past_its_table_the_law_runs_on_at_its_last_slope():
    """Beyond the force table's last depth (1.25 times the law's range) the kernels extrapolate with the table's
    slope there: against the solid pin's own law with its shoulder (linear past the seat), evaluated directly, at
    0.1 and 0.5 mm beyond the end, to 1e-6 (a fresh joint: the loading curve)."""
    from pressfit.mechanics.contact_laws import build_law

    keys = {k: v for k, v in SOLID.items() if k != "law"}
    law = build_law("solid_pin", keys)
    params = contact_parameters(_contact(**SOLID))
    end = float(force_table(None, _contact(**SOLID)).depth_m[-1])
    for beyond in (1e-4, 5e-4):
        expected = float(law.force_n(np.array([end + beyond]))[0])
        assert contact_force_n(params, end + beyond) == pytest.approx(expected, rel=1e-6)
