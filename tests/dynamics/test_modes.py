"""Natural modes (pressfit.dynamics.modes) and the masses on the Pinocchio model (pressfit.dynamics.inertia)."""

import json

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner
from readme import assert_printed, readme_fragment
from scipy.linalg import eigh

from pressfit import kinematics
from pressfit.cli import main
from pressfit.dynamics.inertia import inertial_model, total_mass_kg
from pressfit.dynamics.modes import natural_modes
from pressfit.errors import PressfitError
from pressfit.mechanics import condensed
from pressfit.mechanics.model import build_model

POSE_A = np.array([0.0, 0.72, 0.0])
OFF_CENTRE = np.array([0.1, 0.6, -0.15])
# Legs almost massless (1e-6 of the plate's mass): only the plate (plate + tool, 6.2 kg) vibrates.
LIGHT_LEGS = {"mass": {"density_kg_per_m3": 0.01, "actuator_housing_mass_kg": 0.0, "actuator_moving_mass_kg": 0.0,
                       "cardan_spider_mass_kg": 0.0}}


def test_total_mass_is_the_sum_of_the_parts(machine):
    """Hand sum of the [mass] table and the tube masses (density x section x length; the stem a 30 mm rod of
    0.60 m at every pose) at an off-centre pose."""
    mm = build_model(machine, OFF_CENTRE)
    ms = machine.mass
    rod = ms.density_kg_per_m3 * np.pi * 0.03**2 / 4 * 0.60
    per_leg = machine.cylinder_tube_mass_kg + ms.actuator_housing_mass_kg + ms.actuator_moving_mass_kg \
        + 2 * ms.cardan_spider_mass_kg + rod
    expected = 4 * per_leg + ms.plate_mass_kg + ms.tool_mass_kg
    model = inertial_model(mm)
    assert total_mass_kg(model) == pytest.approx(expected, rel=1e-13)
    assert pin.computeTotalMass(model) == pytest.approx(expected, rel=1e-13)
    assert total_mass_kg(mm.model) == 0.0  # the statics' model is left massless


def test_leg_centre_of_mass_by_hand(machine):
    """Centre of mass of the whole machine at pose A from a hand sum of the parts (tube pieces at their
    middles, point masses at their places: the 0.60 m rod over [l - 0.60, l], the moving parts at its inner end);
    agreement to round-off."""
    mm = build_model(machine, POSE_A)
    model = inertial_model(mm)
    com = pin.centerOfMass(model, model.createData(), mm.q0)
    ms, lc = machine.mass, machine.cylinder.length_m
    length = float(kinematics.inverse_kinematics(machine, POSE_A).lengths_m[0])
    sin_a = 0.72 / length  # leg elevation: every leg rises 0.72 m over its length
    m_cyl = machine.cylinder_tube_mass_kg + ms.actuator_housing_mass_kg
    rod = 0.60
    m_stem = ms.density_kg_per_m3 * np.pi * 0.03**2 / 4 * rod
    y_leg = (m_cyl * lc / 2 + m_stem * (length - rod / 2) + ms.actuator_moving_mass_kg * (length - rod)
             + ms.cardan_spider_mass_kg * length) * sin_a
    m_leg = m_cyl + m_stem + ms.actuator_moving_mass_kg + 2 * ms.cardan_spider_mass_kg
    m_plate = ms.plate_mass_kg + ms.tool_mass_kg
    expected_y = (4 * y_leg + m_plate * 0.72) / (4 * m_leg + m_plate)
    np.testing.assert_allclose(com, [0.0, expected_y, 0.0], atol=1e-14)


def test_frequencies_scale_as_one_over_sqrt_mass(machine):
    """omega^2 = k / m: scaling every mass by 4 halves every frequency (same static load, so same K)."""
    load = np.array([0.0, -60.0, 0.0, 0.0, 0.0, 0.0])
    ref = natural_modes(machine, OFF_CENTRE, count=8, plate_wrench=load)
    heavy = natural_modes(machine, OFF_CENTRE, count=8, plate_wrench=load, mass_scale=4.0)
    assert heavy.total_mass_kg == pytest.approx(4 * ref.total_mass_kg, rel=1e-14)
    np.testing.assert_allclose(heavy.frequencies_hz, ref.frequencies_hz / 2, rtol=1e-9)  # eigh round-off ~1e-12


def test_vertical_mode_at_pose_A_is_a_single_spring_mass(machine):
    """Legs massless, pose A: the vertical plate mode decouples (mirror symmetry), f = sqrt(k_y / m) / (2 pi)
    with k_y = sum_i k_axial,i sin^2(alpha_i) (rigid cardans: vertical translation only stretches the legs)
    and m = plate + tool. Leg mass 1e-6 of the plate's shifts f by about 1e-6: tolerance 1e-5."""
    light = machine.with_overrides(LIGHT_LEGS)
    modes = natural_modes(light, POSE_A, count=6, plate_wrench=np.zeros(6))
    ik = kinematics.inverse_kinematics(light, POSE_A)
    k_y = float(np.sum(np.sin(ik.alpha_rad) ** 2 / light.axial_compliance_m_per_n(ik.lengths_m)))
    mass = light.mass.plate_mass_kg + light.mass.tool_mass_kg
    vertical = int(np.argmax(np.abs(modes.plate_shapes[:, 1]) / np.linalg.norm(modes.plate_shapes, axis=1)))
    assert np.linalg.norm(modes.plate_shapes[vertical, [0, 2, 3, 4, 5]]) < 1e-6 * abs(modes.plate_shapes[vertical, 1])
    assert modes.frequencies_hz[vertical] == pytest.approx(np.sqrt(k_y / mass) / (2 * np.pi), rel=1e-5)


@pytest.mark.parametrize("pose", [POSE_A, OFF_CENTRE], ids=["A", "off-centre"])
def test_plate_modes_match_the_condensed_rigid_body_problem(machine, pose):
    """Legs massless: the six modes are those of a rigid plate (mass 6.2 kg, uniform box inertia about its
    centre) on the condensed 6x6 stiffness (pressfit.mechanics.condensed, an independent closed-form
    condensation of the legs). Achieved 3e-6; tolerance 2e-5, the README's."""
    readme_fragment("With massless legs the six plate modes equal those of a rigid plate on the condensed 6x6 "
                    "stiffness (tested to 2e-5).")
    light = machine.with_overrides(LIGHT_LEGS)
    modes = natural_modes(light, pose, count=6, plate_wrench=np.zeros(6))
    ms, side, t = light.mass, 2 * light.geometry.plate_half_side_m, light.collision.plate_thickness_m
    m6 = np.zeros((6, 6))
    m6[:3, :3] = (ms.plate_mass_kg + ms.tool_mass_kg) * np.eye(3)
    m6[3:, 3:] = ms.plate_mass_kg / 12 * np.diag([side**2 + t**2, 2 * side**2, side**2 + t**2])
    omega2 = eigh(condensed.plate_stiffness(light, pose), m6, eigvals_only=True)
    np.testing.assert_allclose(modes.frequencies_hz, np.sqrt(omega2) / (2 * np.pi), rtol=2e-5)


def test_mode_shapes_satisfy_the_loop_closures(machine):
    """J_c phi = 0 to round-off, and moving along a shape by eps opens Pinocchio's closures only at second
    order (a first-order error would grow like eps, not eps^2)."""
    modes = natural_modes(machine, OFF_CENTRE, count=4)
    assert modes.closure_residual < 1e-12
    mm = build_model(machine, OFF_CENTRE)
    from pressfit.mechanics.statics import solve_equilibrium

    q = solve_equilibrium(mm, OFF_CENTRE, modes.plate_wrench).q
    phi = modes.shapes[0] / np.max(np.abs(modes.shapes[0]))
    errors = [mm.closure_error(pin.integrate(mm.model, q, eps * phi))[0] for eps in (1e-3, 1e-4)]
    assert errors[1] < errors[0] / 50  # eps^2: ratio 100; eps: ratio 10


def test_bad_arguments(machine):
    with pytest.raises(PressfitError, match="count of modes"):
        natural_modes(machine, POSE_A, count=0)
    with pytest.raises(PressfitError, match="mass_scale"):
        natural_modes(machine, POSE_A, mass_scale=float("nan"))


def test_modes_cli(tmp_path):
    out = tmp_path / "m"
    res = CliRunner().invoke(main, ["modes", "0.1", "0.6", "-0.15", "--count", "3", "--json", "--out", str(out)])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    assert len(data["frequencies_hz"]) == 3 and data["frequencies_hz"][0] > 0
    assert {p.name for p in out.iterdir()} == {"modes.json", "modes.csv", "modes.png"}
    again = CliRunner().invoke(main, ["modes", "0.1", "0.6", "-0.15", "--out", str(out)])
    assert again.exit_code == 2 and "--overwrite" in again.output
    bad = CliRunner().invoke(main, ["modes", "0", "0.3", "0"])
    assert bad.exit_code == 2 and "not reachable" in bad.output


def test_readme_numbers_of_the_modes(machine):
    """Every number of the README's modes paragraph and the insertion section's first mode (tests/readme.py),
    with the shipped mass estimates under the plate's weight. The mode kinds are checked on the shapes: the
    rocking pair (equal by the fourfold symmetry at pose A) moves the plate sideways and tilts it about a
    horizontal axis; the twist turns it about y alone; from the fourth mode on the plate moves less than 5% of the
    largest leg-point displacement (the legs' own bending; the rocking pair and the twist move it 45-110%). The
    rocking pair's frequencies against a second formulation (:func:`_rigid_leg_rocking_hz`): 0.8-2.7% above."""
    readme_fragment("held by the legs' bending and torsion) at 18.2 Hz at pose A (0, 0.72, 0); it is stiffer low in "
                    "the workspace and softer high and off-centre: 45.7 Hz at (0, 0.49, 0), 28.5 Hz at (0, 0.6, 0), "
                    "14.5 Hz at the corner (0.25, 0.72, 0.25), 13.4 Hz at (0.25, 0.75, 0.25); so it lies below the "
                    "paper's 40 Hz actuator bandwidth except near the bottom of the workspace. At pose A the plate "
                    "twist is at 80 Hz and the legs' own bending starts at 93 Hz.")
    readme_fragment("structural mode (`pressfit modes`: 27.3 Hz at the pin, 18.2 Hz at pose A)")
    modes = natural_modes(machine, POSE_A, count=8)
    f, plate = modes.frequencies_hz, modes.plate_shapes
    legs = np.abs(modes.leg_point_shapes).max(axis=(1, 2, 3))
    plate_motion = np.maximum(np.linalg.norm(plate[:, :3], axis=1),
                              machine.geometry.plate_half_side_m * np.linalg.norm(plate[:, 3:], axis=1))
    for k in (0, 1):
        assert_printed(f[k], "18.2")
        assert abs(plate[k, 1]) + abs(plate[k, 4]) < 1e-6 * np.linalg.norm(plate[k])  # no heave, no twist
        assert min(np.linalg.norm(plate[k, [0, 2]]), np.linalg.norm(plate[k, [3, 5]])) > 0.1 * np.linalg.norm(plate[k])
    assert_printed(f[2], "80")
    assert np.linalg.norm(plate[2, [0, 1, 2, 3, 5]]) < 1e-6 * abs(plate[2, 4])
    assert_printed(f[3], "93")
    assert np.all(plate_motion[3:] < 0.05 * legs[3:]) and np.all(plate_motion[:3] > 0.3 * legs[:3])
    assert machine.actuator.force_bandwidth_hz == 40.0
    poses = ((0.0, 0.49, 0.0), (0.0, 0.6, 0.0), (0.25, 0.72, 0.25), (0.25, 0.75, 0.25), (0.1, 0.6, -0.05))  # last: pin
    lowest = {pose: natural_modes(machine, np.array(pose), count=1).frequencies_hz[0] for pose in poses}
    for pose, printed in zip(lowest, ("45.7", "28.5", "14.5", "13.4", "27.3"), strict=True):
        assert_printed(lowest[pose], printed)
    assert lowest[0.0, 0.6, 0.0] < 40.0 < lowest[0.0, 0.49, 0.0]
    lowest[tuple(POSE_A)] = f[0]
    for pose, frequency in lowest.items():  # independent: rigid legs on the condensed stiffness (docstring below)
        estimate = _rigid_leg_rocking_hz(machine, np.array(pose))
        assert estimate == pytest.approx(frequency, rel=0.05), (pose, frequency, estimate)


def _rigid_leg_rocking_hz(machine, pose):
    """The lowest plate mode (Hz) of a second formulation: the condensed 6 x 6 plate stiffness (closed form, exact
    for rigid cardans) against a 6 x 6 plate mass written by hand from the machine file, the legs moving as rigid
    bodies with their plate cardans (the plate box and tool; per leg, moving with the plate cardan's velocity
    v_P = v + omega x d_i: the leg's transverse mass (sum of m s^2 + the tubes' own transverse inertias) / l^2 across
    e and its rod body (the 0.60 m rod, the moving parts, the plate cardan, the reflected drive mass) along e; the
    legs' spin about e and the cardan spheres' inertia left out). Its legs do not bend (a constraint the VJM does
    not have: it raises the estimate) and its stiffness is the unloaded one (the VJM's modes are about the
    weight-loaded state: either sign): measured 0.8% (pose A) to 2.7% (the corner (0.25, 0.72, 0.25)) above the
    VJM's rocking pair at the README's poses, -1.1% to +4.3% on the compared machines
    (tests/studies/test_compare.py); asserted 5%."""
    ms, lc, rod = machine.mass, machine.cylinder.length_m, machine.stem.length_m
    ro = machine.cylinder.outer_diameter_m / 2
    ri = ro - machine.cylinder.wall_thickness_m
    rr = machine.stem.diameter_m / 2
    mu_c = ms.density_kg_per_m3 * np.pi * (ro**2 - ri**2) + ms.actuator_housing_mass_kg / lc
    mu_r = ms.density_kg_per_m3 * np.pi * rr**2
    side, t, mp = 2 * machine.geometry.plate_half_side_m, machine.collision.plate_thickness_m, ms.plate_mass_kg
    mass = np.zeros((6, 6))
    mass[:3, :3] = (mp + ms.tool_mass_kg) * np.eye(3)
    mass[3:, 3:] = np.diag([mp * (side**2 + t**2), 2 * mp * side**2, mp * (side**2 + t**2)]) / 12
    for i in range(len(machine.legs)):
        d = machine.plate_offsets_m[i]
        u = pose + d - machine.base_points_m[i]
        length = np.linalg.norm(u)
        e = u / length
        to_cardan = np.hstack([np.eye(3), -pin.skew(d)])  # v_P = v + omega x d = v - [d]x omega
        inner = length - rod
        second = (mu_c * lc**3 / 3 + mu_r * (length**3 - inner**3) / 3 + ms.actuator_moving_mass_kg * inner**2
                  + ms.cardan_spider_mass_kg * length**2 + mu_c * lc * (ro**2 + ri**2) / 4 + mu_r * rod * rr**2 / 4)
        leg = second / length**2 * (np.eye(3) - np.outer(e, e)) + (
            mu_r * rod + ms.actuator_moving_mass_kg + ms.cardan_spider_mass_kg
            + machine.drive_reflected_mass_kg) * np.outer(e, e)
        mass += to_cardan.T @ leg @ to_cardan
    stiffness = np.linalg.inv(condensed.condensed_plate_compliance(machine, pose))
    return float(np.sqrt(eigh(stiffness, mass, eigvals_only=True)[0]) / (2 * np.pi))
