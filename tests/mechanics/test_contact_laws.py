"""The contact laws (mechanics/contact_laws): each against a closed form derived here, the registry, the
kernels' TABLE law against the law it tabulates, and the schema's refusals naming the key."""

from __future__ import annotations

import math
import typing

import numpy as np
import pytest

from pressfit.description.cases import CONTACT_LAW_KEYS, Contact, load_case
from pressfit.dynamics import kernels
from pressfit.dynamics.contact import contact_force_n, contact_parameters
from pressfit.errors import ModelFileError
from pressfit.mechanics.contact_laws import LAWS, ContactLawModel, build_law

SOLID = dict(pin_diameter_m=1.008e-3, hole_diameter_m=1.0e-3, pin_youngs_modulus_pa=1.2e11, pin_poisson_ratio=0.34,
             board_youngs_modulus_pa=2.0e10, board_poisson_ratio=0.13, friction_coefficient=0.15,
             engaged_length_m=1.6e-3, chamfer_length_m=0.2e-3)
COMPLIANT = dict(hole_diameter_m=1.0e-3, zone_width_m=1.15e-3, radial_stiffness_n_per_m=1.6e6,
                 radial_yield_force_n=80.0, post_yield_stiffness_n_per_m=3.7e5, zone_length_m=1.0e-3,
                 lead_in_length_m=0.6e-3, friction_coefficient=0.15)


def lame_by_stress_functions(delta, d, e_p, nu_p, e_b, nu_b, outer):
    """The contact pressure from the Lame stress functions themselves (plane stress): in the hub (inner radius
    b = d/2, outer c) under the bore pressure p, sigma_r = A - B / r^2, sigma_t = A + B / r^2 with sigma_r(b) = -p,
    sigma_r(c) = 0: A = p b^2 / (c^2 - b^2), B = p b^2 c^2 / (c^2 - b^2); the bore's radial displacement
    u = r eps_t = (r / E)(sigma_t - nu sigma_r). The solid pin under -p all round: u = -p b (1 - nu) / E. The
    fit closes delta / 2 = u_hub(b) - u_pin(b), linear in p."""
    b, c = d / 2.0, outer / 2.0
    a_per_p, b_per_p = b * b / (c * c - b * b), b * b * c * c / (c * c - b * b)
    sigma_t, sigma_r = a_per_p + b_per_p / b**2, -1.0
    u_hub = b / e_b * (sigma_t - nu_b * sigma_r)
    u_pin = -b * (1.0 - nu_p) / e_p
    return 0.5 * delta / (u_hub - u_pin)


@pytest.mark.parametrize("outer", [3.0e-3, 10.0e-3])
def test_solid_pin_pressure_of_a_thick_hub_is_lames(outer):
    """The law's pressure for a hub of outer diameter D against the Lame stress functions solved here (achieved
    ~1e-16 relative: the same algebra in two forms), and the plateau mu p pi d L_b against its closed form."""
    law = build_law("solid_pin", {**SOLID, "board_outer_diameter_m": outer})
    p = lame_by_stress_functions(8e-6, 1e-3, 1.2e11, 0.34, 2.0e10, 0.13, outer)
    assert law.pressure_pa == pytest.approx(p, rel=1e-12)
    assert law.plateau_force_n == pytest.approx(0.15 * p * math.pi * 1e-3 * 1.6e-3, rel=1e-12)
    assert float(law.force_n(np.array([5e-3]))[0]) == pytest.approx(law.plateau_force_n, rel=1e-12)


def test_solid_pin_in_an_infinite_plate_is_the_limit_of_a_wide_hub():
    """No board_outer_diameter_m: the hub's pressure as D -> infinity (the stress functions at D = 1e4 d, whose
    (D^2 + d^2)/(D^2 - d^2) = 1 + 2e-8: achieved 1.4e-8 relative)."""
    law = build_law("solid_pin", SOLID)
    wide = lame_by_stress_functions(8e-6, 1e-3, 1.2e11, 0.34, 2.0e10, 0.13, 10.0)
    assert law.pressure_pa == pytest.approx(wide, rel=1e-7)
    # the closed form of the infinite plate: p = delta / (d [(1 + nu_b)/E_b + (1 - nu_p)/E_p])
    assert law.pressure_pa == pytest.approx(8e-6 / (1e-3 * (1.13 / 2e10 + 0.66 / 1.2e11)), rel=1e-12)


def test_two_cylinders_of_one_material_are_the_textbook_fit():
    """Shaft and hub of one material (E, nu): the Lame pressure's nu terms cancel,
    p = E delta / (d [(D^2 + d^2)/(D^2 - d^2) + 1]) = E delta / (2 d) (1 - (d / D)^2) (the textbook's
    interference fit of a solid shaft); achieved 1e-16 relative."""
    e, nu, d, big, delta = 2.1e11, 0.3, 1e-3, 4e-3, 5e-6
    keys = {**SOLID, "pin_diameter_m": d + delta, "hole_diameter_m": d, "pin_youngs_modulus_pa": e,
            "board_youngs_modulus_pa": e, "pin_poisson_ratio": nu, "board_poisson_ratio": nu,
            "board_outer_diameter_m": big}
    assert build_law("solid_pin", keys).pressure_pa == pytest.approx(e * delta / (2 * d) * (1 - (d / big) ** 2),
                                                                     rel=1e-12)


def test_solid_pin_chamfer_lead_in_rises_quadratically_to_half_its_length():
    """With the pressure proportional to the local interference, the chamfer (interference 0 -> delta over L_c)
    at depth z <= L_c carries mu p pi d z^2 / (2 L_c); at z = L_c + L_b the full plateau (closed forms)."""
    law = build_law("solid_pin", SOLID)
    unit = 0.15 * law.pressure_pa * math.pi * 1e-3
    z = np.array([0.05e-3, 0.2e-3, 1.0e-3, 1.8e-3])
    expected = unit * np.array([0.05e-3**2 / 0.4e-3, 0.1e-3, 1.0e-3 - 0.1e-3, 1.6e-3])
    assert law.force_n(z) == pytest.approx(expected, rel=1e-12)
    assert law.force_n(np.array([0.0, -1e-3])).tolist() == [0.0, 0.0]


@pytest.mark.parametrize("factor, capped", [(1.0 - 1e-9, True), (1.0 + 1e-9, False)])
def test_board_yield_caps_the_pressure_just_over_and_not_just_under(factor, capped):
    """board_yield_strength_pa just under the Lame pressure caps it (and says so in notes); just over, it does
    not."""
    p = build_law("solid_pin", SOLID).pressure_pa
    law = build_law("solid_pin", {**SOLID, "board_yield_strength_pa": factor * p})
    assert law.capped is capped
    assert law.pressure_pa == pytest.approx(factor * p if capped else p, rel=1e-15)
    assert bool(law.notes) is capped and (not capped or "board_yield_strength_pa" in law.notes[0])


def test_compliant_pin_rise_peak_plateau_and_retention_by_hand():
    """The zone of the shipped case: squeeze 0.15 mm, yield at 50 um (80 N), N(delta) = 80 + 3.7e5 x 1e-4 =
    117 N; plateau and retention 2 mu N = 35.1 N; taper t = 0.075 / 0.6 = 0.125, peak
    2 N (mu + t)/(1 - mu t) = 65.58 N; in the elastic range (z = 0.1 mm: x = 25 um, N = 40 N) 2 x 40 x 0.275 /
    0.98125; the plastic set 0.15 mm - 117 / 1.6e6 = 76.9 um (hand numbers)."""
    law = build_law("compliant_pin", COMPLIANT)
    assert law.held_normal_force_n == pytest.approx(117.0, rel=1e-12)
    assert law.plateau_force_n == pytest.approx(35.1, rel=1e-12)
    assert law.retention_force_n == pytest.approx(35.1, rel=1e-12)
    assert law.peak_force_n == pytest.approx(2 * 117 * 0.275 / (1 - 0.15 * 0.125), rel=1e-12)
    f = law.force_n(np.array([0.1e-3, 0.6e-3, 1.5e-3]))
    assert f == pytest.approx([2 * 40 * 0.275 / (1 - 0.15 * 0.125), law.peak_force_n, 35.1], rel=1e-12)
    assert law.plastic_set_m == pytest.approx(0.15e-3 - 117 / 1.6e6, rel=1e-12)
    grid = np.linspace(0, 2.2e-3, 2201)  # a grid through the peak's depth 0.6 mm
    assert law.force_n(grid).max() == pytest.approx(law.peak_force_n, rel=1e-12)


def test_seating_adds_the_shoulders_rise():
    """seat_depth_m d_s, seat_stiffness_n_per_m k_s: + k_s (d - d_s) past the shoulder, nothing before, and the
    stroke ends 20 um past it."""
    plain = build_law("compliant_pin", COMPLIANT)
    seated = build_law("compliant_pin", {**COMPLIANT, "seat_depth_m": 1.4e-3, "seat_stiffness_n_per_m": 2e6})
    z = np.array([1.0e-3, 1.4e-3, 1.41e-3])
    assert seated.force_n(z) - plain.force_n(z) == pytest.approx([0.0, 0.0, 2e6 * 1e-5], abs=1e-9)
    assert seated.depth_range_m == pytest.approx((0.0, 1.42e-3)) and seated.seat_depth_m == 1.4e-3
    assert seated.retention_force_n == plain.retention_force_n


def test_tabulated_law_reads_its_csv_relative_to_the_case(tmp_path):
    """A tabulated law's CSV next to the case file: linear interpolation between its rows (hand values)."""
    (tmp_path / "curves").mkdir()
    (tmp_path / "curves" / "pin.csv").write_text("depth_m,force_n\n0,0\n0.001,50\n0.002,30\n")
    case = tmp_path / "case.toml"
    case.write_text(_case_text('law = "tabulated"\ntable_path = "curves/pin.csv"'))
    contact = load_case(case).simulation.contact
    law = build_law(contact.law, contact.law_keys())
    assert law.force_n(np.array([0.0005, 0.0015, 0.003])) == pytest.approx([25.0, 40.0, 30.0])
    (tmp_path / "curves" / "pin.csv").write_text("depth_m,force_n\n0,0\n0.001,nan\n")
    with pytest.raises(ModelFileError, match="row 3 column force_n"):
        load_case(case)


def test_every_law_of_the_schema_is_in_the_registry_and_keeps_the_interface():
    """The registry maps every law name the schema takes to a module whose law is a ContactLawModel; the schema's
    ``law`` takes the names its keys table declares (one list, not spelled again)."""
    assert set(LAWS) == set(CONTACT_LAW_KEYS)
    assert typing.get_args(Contact.model_fields["law"].annotation) == tuple(CONTACT_LAW_KEYS)
    for law, keys in (("elastic", {"stiffness_n_per_m": 1e4}), ("solid_pin", SOLID), ("compliant_pin", COMPLIANT)):
        assert isinstance(build_law(law, keys), ContactLawModel)


def test_the_paper_law_keeps_its_kernel_code_and_numbers():
    """elastic on one pin: the kernels' ELASTIC code and its 7 numbers, F = k d exactly (the paper's cases)."""
    params = contact_parameters(Contact(board_height_m=0.6, pin_position_m=[0.1, -0.05], stiffness_n_per_m=5e4))
    assert params.size == 7 and params[kernels.LAW] == kernels.ELASTIC
    assert contact_force_n(params, 6e-4) == 5e4 * 6e-4


def test_the_table_law_is_the_law_within_its_tabulation_error():
    """A compliant pin with a shoulder through the kernels' TABLE: within the tabulation error the table reports
    (0.0625 N here, from the peak's and the shoulder's kinks; achieved 0.045 N) at 500 random depths, and the
    shoulder's slope past the table's end."""
    keys = {**COMPLIANT, "seat_depth_m": 1.4e-3, "seat_stiffness_n_per_m": 2e6}
    contact = Contact(board_height_m=0.6, pin_position_m=[0.0, 0.0], law="compliant_pin", **keys)
    params = contact_parameters(contact)
    law = build_law("compliant_pin", keys)
    depths = np.random.default_rng(1).uniform(0.0, 1.75e-3, 500)
    got = np.array([contact_force_n(params, d) for d in depths])
    from pressfit.mechanics.press_curve import force_table
    error = force_table(None, contact).error_n
    assert error < 0.1
    assert np.max(np.abs(got - law.force_n(depths))) <= error + 1e-9
    assert contact_force_n(params, 1.85e-3) == pytest.approx(float(law.force_n(np.array([1.85e-3]))[0]), rel=1e-9)


def _case_text(contact_lines: str, pins: str = "") -> str:
    return f"""name = "t"
[poses]
points_m = [[0.0, 0.6, 0.0]]
[loads]
force_n = [0.0, 30.0, 0.0]
[simulation]
start_m = [0.0, 0.65, 0.0]
end_m = [0.0, 0.65, 0.0]
[simulation.contact]
board_height_m = 0.6
pin_position_m = [0.0, 0.0]
{contact_lines}
{pins}"""


SOLID_LINES = "\n".join(f"{k} = {v!r}" for k, v in SOLID.items())


@pytest.mark.parametrize("lines, pins, match", [
    ('law = "elastic"\npin_diameter_m = 1e-3', "", r"pin_diameter_m is not a key of law = \"elastic\""),
    ('law = "solid_pin"\n' + SOLID_LINES.replace("engaged_length_m = 0.0016", ""), "",
     "engaged_length_m is required"),
    ('law = "solid_pin"\n' + SOLID_LINES.replace("pin_diameter_m = 0.001008", "pin_diameter_m = 0.001"), "",
     "pin_diameter_m = 0.001 m must be larger than hole_diameter_m"),
    ('law = "solid_pin"\nstiffness_n_per_m = 1e4\n' + SOLID_LINES, "", "stiffness_n_per_m is not a key"),
    ('law = "solid_pin"\nseat_depth_m = 1e-3\n' + SOLID_LINES, "", "seat_depth_m and seat_stiffness_n_per_m"),
    ('law = "solid_pin"\n' + SOLID_LINES, "[[simulation.contact.pins]]\noffset_m = [0.01, 0.0]\nzone_width_m = 1e-3",
     r"pins\[0\]\.zone_width_m is not a key of law = \"solid_pin\""),
    ('law = "solid_pin"\n' + SOLID_LINES, "[[simulation.contact.pins]]\noffset_m = [0.01, 0.0]\n"
     "hole_diameter_m = 0.0011", r"pins\[0\]\.pin_diameter_m = 0.001008 m must be larger"),
    ('law = "solid_pin"\n' + SOLID_LINES.replace("board_poisson_ratio = 0.13", "board_poisson_ratio = 0.5"), "",
     "board_poisson_ratio"),
    ('law = "tabulated"\ntable_path = "missing.csv"', "", "cannot read"),
])
def test_bad_contact_keys_are_refused_naming_the_key(tmp_path, lines, pins, match):
    """Each malformed contact is refused with a ModelFileError naming the key (and the pin)."""
    path = tmp_path / "bad.toml"
    path.write_text(_case_text(lines, pins))
    with pytest.raises(ModelFileError, match=match):
        load_case(path)


SLOPE_LAWS = {
    "elastic": ("elastic", {"stiffness_n_per_m": 5e4}),
    "press_fit linear": ("press_fit", {"stiffness_n_per_m": 5e4, "fit": "linear", "fit_stiffness_n_per_m": 2e4,
                                       "fit_force_n": 0.0, "fit_depth_m": 1e-3}),
    "press_fit saturating": ("press_fit", {"stiffness_n_per_m": 5e4, "fit": "saturating", "fit_stiffness_n_per_m": 0.0,
                                           "fit_force_n": 20.0, "fit_depth_m": 3e-4}),
    "solid_pin": ("solid_pin", SOLID),
    "solid_pin without chamfer": ("solid_pin", {**SOLID, "chamfer_length_m": 0.0}),
    "compliant_pin": ("compliant_pin", COMPLIANT),
    "compliant_pin seated": ("compliant_pin", {**COMPLIANT, "seat_depth_m": 1.4e-3, "seat_stiffness_n_per_m": 2e6}),
}


@pytest.mark.parametrize("name", SLOPE_LAWS)
def test_each_laws_closed_form_slope_is_its_central_difference(name):
    """force_and_slope's dF/dd against (F(d + h) - F(d - h)) / 2h, h = 1 nm, at 400 random depths over and past
    the law's shape (none within h of a kink at this seed): exact on the linear and quadratic pieces, O(h^2) on
    the wedge's rational and the tanh pieces, the difference's round-off ~1e-16 F / h ~ 1e-5 N/m; achieved 4.2e-10
    relative (2.7e-4 N/m at the 2e6 N/m shoulder), asserted at 1.5e-9 relative + 1e-3 N/m. The force is force_n's."""
    law = build_law(*SLOPE_LAWS[name])
    d = np.random.default_rng(7).uniform(-2e-4, 2.5e-3, 400)
    f, slope = law.force_and_slope(d)
    h = 1e-9
    central = (law.force_n(d + h) - law.force_n(d - h)) / (2 * h)
    assert np.array_equal(f, law.force_n(d))
    assert slope == pytest.approx(central, rel=1.5e-9, abs=1e-3)
    assert np.all(slope[d < 0] == 0.0) and np.any(slope > 0)


def test_the_tabulated_slope_is_the_rows_interval_slope():
    """A table (0, 0), (1 mm, 50 N), (2 mm, 30 N): slope 5e4 N/m, then -2e4 N/m, 0 before and past the rows (hand)."""
    from pressfit.mechanics.contact_laws.tabulated import TabulatedLaw

    law = TabulatedLaw(depth_m=np.array([0.0, 1e-3, 2e-3]), table_force_n=np.array([0.0, 50.0, 30.0]), path="")
    f, slope = law.force_and_slope(np.array([-1e-4, 0.5e-3, 1.5e-3, 2.5e-3]))
    assert f == pytest.approx([0.0, 25.0, 40.0, 30.0]) and slope == pytest.approx([0.0, 5e4, -2e4, 0.0])


def test_a_stacked_field_gives_each_pins_own_numbers():
    """stack_laws on a field of compliant pins with per-pin overrides (three different zones, one without a
    shoulder) and two solid pins: each group's one evaluation over depths (m, n) equals each pin's own law
    evaluated alone, bit for bit (the same arithmetic per element), and the groups cover every pin once."""
    from pressfit.mechanics.contact_laws import stack_laws

    seat = {"seat_depth_m": 1.4e-3, "seat_stiffness_n_per_m": 2e6}
    laws = [build_law("compliant_pin", {**COMPLIANT, **seat}),
            build_law("solid_pin", SOLID),
            build_law("compliant_pin", {**COMPLIANT, **seat, "zone_width_m": 1.17e-3, "friction_coefficient": 0.1}),
            build_law("compliant_pin", COMPLIANT),
            build_law("compliant_pin", {**COMPLIANT, "seat_depth_m": 1.3e-3, "seat_stiffness_n_per_m": 3e6}),
            build_law("solid_pin", {**SOLID, "pin_diameter_m": 1.01e-3})]
    depths = np.random.default_rng(3).uniform(-1e-4, 2.4e-3, (50, len(laws)))
    groups = stack_laws(laws)
    assert sorted(i for idx, _ in groups for i in idx) == list(range(len(laws))) and len(groups) == 3
    for idx, stacked in groups:
        f, slope = stacked.force_and_slope(depths[:, idx])
        for column, i in enumerate(idx):
            own_f, own_slope = laws[i].force_and_slope(depths[:, i])
            assert np.array_equal(f[:, column], own_f) and np.array_equal(slope[:, column], own_slope)
