"""Modes and the tool response with n legs (issue 21): Tsai's 3-UPU and a 5-leg machine at the centred pose.

References, derived here: with rigid cardans a vertical plate translation only stretches the legs, so the
vertical stiffness is k_v = n k_a sin^2(alpha) (tests/n_legs.py); with massless legs the vertical mode is the
single spring-mass sqrt(k_v / m) of plate and tool. With the real leg masses a rigid-leg vertical motion
gives the Rayleigh quotient k_v / m_eff with plate + tool <= m_eff <= the total mass (no point of a rigid leg
moves faster than the plate: a point at s from the base cardan moves at sqrt(sin^2 alpha + (s cos alpha / l)^2)
<= 1 per unit plate speed), so the vertical mode lies between sqrt(k_v / m_total) and sqrt(k_v / m_plate+tool);
the legs' own flexibility moves it inside that bracket, not out of it (437 Hz against 413 Hz for the rigid-leg
quotient on the 3-UPU). The n-fold rotational symmetry about y (n >= 3) makes the lateral modes pairs of equal
frequency. The 4-UPU's frequencies are tests/dynamics/test_modes.py's (unchanged)."""

import math

import numpy as np
import pytest
from n_legs import centred

from pressfit.dynamics.modes import natural_modes
from pressfit.dynamics.response import tool_response

Y = 0.6
POSE = np.array([0.0, Y, 0.0])
LIGHT_LEGS = {"mass": {"density_kg_per_m3": 0.01, "actuator_housing_mass_kg": 0.0, "actuator_moving_mass_kg": 0.0,
                       "cardan_spider_mass_kg": 0.0}}


def _vertical(modes) -> int:
    """The mode with the largest plate vertical translation per unit modal mass."""
    return int(np.argmax(np.abs(modes.plate_shapes[:, 1])))


@pytest.mark.parametrize("which", ["tsai", "five"])
def test_light_legs_vertical_mode_is_the_spring_mass_closed_form(request, which):
    """Legs 1e-6 of the plate's mass: the vertical mode is sqrt(n k_a sin^2(alpha) / (plate + tool)) / (2 pi), a pure
    vertical plate translation (tolerance 1e-5: the leg masses shift it by ~1e-6)."""
    light = request.getfixturevalue(which).with_overrides(LIGHT_LEGS)
    modes = natural_modes(light, POSE, count=6, plate_wrench=np.zeros(6))
    sa, ka = centred(light, Y)
    k_v = len(light.legs) * ka * sa**2
    k = _vertical(modes)
    assert np.linalg.norm(modes.plate_shapes[k, [0, 2, 3, 4, 5]]) < 1e-6 * abs(modes.plate_shapes[k, 1])
    mass = light.mass.plate_mass_kg + light.mass.tool_mass_kg
    assert modes.frequencies_hz[k] == pytest.approx(math.sqrt(k_v / mass) / (2 * math.pi), rel=1e-5)


def test_tsai_vertical_mode_within_the_rayleigh_bracket(tsai):
    """The shipped masses: the vertical translation mode of the 3-UPU lies in [sqrt(k_v / m_total),
    sqrt(k_v / (plate + tool))] (module doc), the plate moving vertically only."""
    modes = natural_modes(tsai, POSE, count=12)
    sa, ka = centred(tsai, Y)
    k_v = 3 * ka * sa**2
    k = _vertical(modes)
    assert np.linalg.norm(modes.plate_shapes[k, [0, 2, 3, 4, 5]]) < 1e-6 * abs(modes.plate_shapes[k, 1])
    low = math.sqrt(k_v / modes.total_mass_kg) / (2 * math.pi)
    high = math.sqrt(k_v / (tsai.mass.plate_mass_kg + tsai.mass.tool_mass_kg)) / (2 * math.pi)
    assert low < modes.frequencies_hz[k] < high
    assert modes.leg_points_m.shape[0] == modes.leg_point_shapes.shape[1] == 3


@pytest.mark.parametrize("which", ["tsai", "five"])
def test_lateral_modes_are_degenerate_pairs(request, which):
    """The n-fold symmetry: the two lowest modes (the plate's sway and rock, no heave, no twist) have equal
    frequencies to 1e-6 relative."""
    m = request.getfixturevalue(which)
    modes = natural_modes(m, POSE, count=3)
    f, plate = modes.frequencies_hz, modes.plate_shapes
    assert f[1] == pytest.approx(f[0], rel=1e-6) and f[2] > 1.5 * f[1]
    for k in (0, 1):
        assert abs(plate[k, 1]) + abs(plate[k, 4]) < 1e-6 * np.linalg.norm(plate[k])
    assert modes.closure_residual < 1e-12


def test_tsai_static_tool_response_is_the_closed_form_stiffness(tsai):
    """A vertical step at the tool settles at F / (3 k_a sin^2(alpha)) (the modal sum is complete; the
    equilibrium under the weight moves the geometry by ~1e-7 relative: tolerance 1e-5), with no lateral motion."""
    force = np.array([0.0, 100.0, 0.0])
    r = tool_response(tsai, POSE, force, duration_s=0.01, frequency_count=50)
    sa, ka = centred(tsai, Y)
    assert r.static_m[1] == pytest.approx(100.0 / (3 * ka * sa**2), rel=1e-5)
    np.testing.assert_allclose(r.static_m[[0, 2]], 0.0, atol=1e-9 * abs(r.static_m[1]))
