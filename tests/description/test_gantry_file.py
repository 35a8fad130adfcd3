"""The gantry description (pressfit.description.gantry): section properties against their closed forms, and clear
errors for malformed files."""

from __future__ import annotations

import math

import pytest

from pressfit.description.gantry import BeamSection, load_gantry
from pressfit.errors import ModelFileError
from pressfit.shipped import models_dir

SHIPPED = models_dir() / "gantry_cartesian.toml"


def test_tube_section():
    """Circular tube: A = pi (D^2 - d^2) / 4, I = pi (D^4 - d^4) / 64, J = 2 I, shear area A / 2."""
    s = BeamSection(kind="tube", outer_diameter_m=0.1, wall_thickness_m=0.01)
    assert s.area_m2 == pytest.approx(math.pi * (0.1**2 - 0.08**2) / 4, rel=1e-14)
    assert s.second_moments_m4 == pytest.approx((math.pi * (0.1**4 - 0.08**4) / 64,) * 2, rel=1e-14)
    assert s.torsion_constant_m4 == pytest.approx(math.pi * (0.1**4 - 0.08**4) / 32, rel=1e-14)
    assert s.shear_areas_m2 == pytest.approx((s.area_m2 / 2,) * 2, rel=1e-14)


def test_square_sections_torsion():
    """A solid square's torsion constant is 0.1406 a^4 (Saint-Venant's series; Roark's formula gives 0.1408 a^4);
    a thin square tube's, Bredt's 4 A_m^2 t / s_m = t (b - t)^3."""
    assert BeamSection(kind="solid", width_m=0.05, height_m=0.05).torsion_constant_m4 == \
        pytest.approx(0.1406 * 0.05**4, rel=2e-3)
    assert BeamSection(kind="box", width_m=0.2, height_m=0.2, wall_thickness_m=0.008).torsion_constant_m4 == \
        pytest.approx(0.008 * 0.192**3, rel=1e-14)


def test_rectangular_box_bends_more_easily_about_its_short_side():
    """I_x (height direction) = (b h^3 - b_i h_i^3) / 12 and I_y with b and h exchanged."""
    s = BeamSection(kind="box", width_m=0.25, height_m=0.2, wall_thickness_m=0.008)
    assert s.second_moments_m4 == pytest.approx(((0.25 * 0.2**3 - 0.234 * 0.184**3) / 12,
                                                 (0.2 * 0.25**3 - 0.184 * 0.234**3) / 12), rel=1e-14)


def _write(tmp_path, old: str, new: str):
    path = tmp_path / "gantry.toml"
    text = SHIPPED.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(("old", "new", "key", "text"), [
    ("span_m = 1.0", "span_m = 0.4", "<top level>", "x_half_width_m = 0.25 m must be less than half"),
    ("ram_length_m = 0.6", "ram_length_m = 0.3", "<top level>", "ram_length_m = 0.3 m must exceed"),
    ("wall_thickness_m = 0.008", "wall_thickness_m = 0.2", "sections.column", "less than half"),
    ("kind = \"box\"", "kind = \"tube\"", "sections.column", 'kind = "tube" takes outer_diameter_m'),
    ("span_m = 1.0", "span_m = -1.0", "frame.span_m", "greater than 0"),
    ("tool_mass_kg = 2.0", "tool_mass_kg = 2.0\ncolour = 1", "mass.colour", "unknown key"),
    ("kind = \"gantry\"", "kind = \"4upu\"", "kind", "gantry"),
])
def test_malformed_files_name_the_key(tmp_path, old, new, key, text):
    with pytest.raises(ModelFileError) as err:
        load_gantry(_write(tmp_path, old, new))
    assert err.value.key == key and text in err.value.expected, str(err.value)
    assert str(tmp_path / "gantry.toml") in str(err.value)
