"""The leg layout of a machine file (issue 21): n >= 3 UPU legs given by their radial directions, default
cardan and beta axes, Tsai's parallel-axes condition and the redundancy n - 3. References: the paper's layout
(docs/conventions.md, Table 2), the definitions of the schema (n x y, B_i = p n_i), and counting."""

import math

import numpy as np
import pytest

from pressfit import kinematics
from pressfit.description.machine import MAX_CARDAN_TILT_RAD
from pressfit.errors import LegCountError, ModelFileError


def ring(n: int, first_deg: float = -90.0) -> list[dict]:
    """n legs at 360/n degrees about y, leg 1 at angle first_deg from +x toward +z (-90: the paper's leg 1, -z)."""
    out = []
    for i in range(n):
        t = math.radians(first_deg + 360.0 * i / n)
        out.append({"radial_direction": [math.cos(t), 0.0, math.sin(t)]})
    return out


@pytest.mark.parametrize("n", [3, 4, 5, 6])
def test_n_legs_on_a_ring(machine, n):
    """A ring of n legs: redundancy n - 3 (n actuators, 3 translations), base cardans on the circle of radius p
    and plate cardans on the circle of radius r, one row per leg."""
    m = machine.with_overrides({"legs": ring(n)})
    g = m.geometry
    assert m.redundancy == n - 3 and len(m.legs) == n
    np.testing.assert_allclose(np.linalg.norm(m.base_points_m, axis=1), g.base_half_side_m, rtol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(m.plate_offsets_m, axis=1), g.plate_half_side_m, rtol=1e-15)
    assert m.legs_concurrent  # homothetic: d_i = (r / p) B_i


def test_fewer_than_three_legs_refused(machine):
    with pytest.raises(ModelFileError) as info:
        machine.with_overrides({"legs": ring(2)})
    assert info.value.key == "legs" and "at least 3" in str(info.value)


def test_default_axes(machine):
    """Without cardan_axis and beta_axis a leg takes a_i = s_i = n_i x y. On the paper's radial directions this
    is the paper's beta axis for legs 1-3 and the opposite for leg 4 (docs/conventions.md: "leg 4 uses +z"), so
    beta_4 changes sign and nothing else does; the cardan axes agree up to sign."""
    legs = [{"radial_direction": leg.radial_direction} for leg in machine.legs]
    plain = machine.with_overrides({"legs": legs})
    n = np.array([leg.radial_direction for leg in machine.legs])
    np.testing.assert_array_equal(plain.cardan_axes, np.cross(n, [0.0, 1.0, 0.0]) + 0.0)
    np.testing.assert_array_equal(plain.beta_axes, plain.cardan_axes)
    np.testing.assert_array_equal(np.abs(plain.cardan_axes), np.abs(machine.cardan_axes))
    np.testing.assert_array_equal(plain.beta_axes[:3], machine.beta_axes[:3])
    np.testing.assert_array_equal(plain.beta_axes[3], -machine.beta_axes[3])
    pose = np.array([0.12, 0.6, -0.2])
    a, b = kinematics.inverse_kinematics(machine, pose), kinematics.inverse_kinematics(plain, pose)
    np.testing.assert_array_equal(b.lengths_m, a.lengths_m)
    np.testing.assert_array_equal(b.alpha_rad, a.alpha_rad)
    np.testing.assert_array_equal(b.beta_rad, a.beta_rad * [1, 1, 1, -1])


def _with_leg1(machine, **keys):
    legs = machine.model_dump()["legs"]
    legs[0] = {**legs[0], **keys}
    return machine.with_overrides({"legs": legs})


def test_tsai_condition_checked(machine):
    """The plate cardan's first axis must be parallel (or antiparallel) to the base cardan's; a deviation is a
    misalignment and is refused with the pointer to plate_cardan_tilt_rad."""
    assert _with_leg1(machine, plate_cardan_axis=[-1.0, 0.0, 0.0]).legs[0].plate_cardan_axis == [-1.0, 0.0, 0.0]
    turned = [math.cos(0.01), 0.0, math.sin(0.01)]
    with pytest.raises(ModelFileError) as info:
        _with_leg1(machine, plate_cardan_axis=turned)
    assert info.value.key == "legs.0" and "Tsai's condition" in str(info.value)
    assert f"plate_cardan_tilt_rad (at most {MAX_CARDAN_TILT_RAD} rad)" in str(info.value)


@pytest.mark.parametrize("key, value", [("radial_direction", [0.0, 0.6, -0.8]), ("cardan_axis", [0.0, 1.0, 0.0])])
def test_axes_must_be_horizontal(machine, key, value):
    """The base and plate planes are y = const: a radial direction or cardan axis with a y component is refused."""
    with pytest.raises(ModelFileError) as info:
        _with_leg1(machine, **{key: value})
    assert info.value.key == f"legs.0.{key}" and "horizontal" in str(info.value)


def test_require_legs(machine):
    """A layer that supports only 4 legs refuses another count up front, with the data in the exception."""
    machine.require_legs("a 4-leg layer", 4)
    three = machine.with_overrides({"legs": ring(3)})
    with pytest.raises(LegCountError) as info:
        three.require_legs("the insertion simulation", 4)
    e = info.value
    assert (e.machine, e.legs, e.supported, e.layer) == (three.name, 3, (4,), "the insertion simulation")
    assert "the insertion simulation supports 4-leg machines only so far; this machine has 3 legs" in str(e)
