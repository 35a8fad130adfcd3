"""The Cartesian gantry press of the paper's Figure 2 as data: load and validate ``models/gantry_cartesian.toml``.

Layout (world frame of the 4-UPU: origin on the bed at the centre of the workspace, y vertical, up): two
columns stand on the bed at x = -span/2 and +span/2 (z = 0), built in at their feet and rigidly joined at
their tops to the X beam (a portal frame) whose axis runs along x at y = ``column_height_m``. The X carriage
runs on the X beam; a Z beam, fixed at its middle to the X carriage ``x_to_z_beam_drop_m`` below the X beam's
axis, reaches z = +-``z_beam_half_length_m``; the Z carriage runs on it and holds the Y guide
``z_beam_to_ram_guide_drop_m`` lower, through which the vertical ram slides; the tool is at the ram's lower
end. The tool pose (x, y, z) is the ram tip's position: x the X carriage's, z the Z carriage's, y the height
of the tool, so that the ram's free length below its guide is y_guide - y.

Sections (:class:`BeamSection`) have local axes x (``width_m``), y (``height_m``) and z along the member:
for the X and Z beams the height is vertical, for the columns and the ram it is along world x. Every
quantity is SI and names its unit; a malformed file raises :class:`ModelFileError` naming the file and key.
"""

from __future__ import annotations

import math
from functools import cached_property
from pathlib import Path
from typing import Any, Literal

from pydantic import ValidationError, model_validator

from pressfit.description import drive_stiffness
from pressfit.description.machine import (
    Material,
    ModelOptions,
    NonNegative,
    Positive,
    StrictModel,
    _merge,
    read_toml,
    refuse_wrong_kind,
    validation_error,
)
from pressfit.errors import UnreachablePoseError

GANTRY_AXES = ("x", "y", "z")  # world-axis order of every per-axis array


class BeamSection(StrictModel):
    """A member's cross-section: ``kind`` "tube" (``outer_diameter_m``, ``wall_thickness_m``; a wall of half
    the diameter is a solid round bar), "box" (rectangular hollow section: ``width_m``, ``height_m``,
    ``wall_thickness_m``) or "solid" (rectangular bar: ``width_m``, ``height_m``). Local axes: x along the
    width, y along the height (module doc)."""

    kind: Literal["tube", "box", "solid"]
    outer_diameter_m: Positive | None = None
    width_m: Positive | None = None
    height_m: Positive | None = None
    wall_thickness_m: Positive | None = None

    @model_validator(mode="after")
    def _keys_of_kind(self) -> BeamSection:
        needed = {"tube": ("outer_diameter_m", "wall_thickness_m"), "box": ("width_m", "height_m", "wall_thickness_m"),
                  "solid": ("width_m", "height_m")}[self.kind]
        for key in ("outer_diameter_m", "width_m", "height_m", "wall_thickness_m"):
            if (getattr(self, key) is not None) != (key in needed):
                raise ValueError(f'kind = "{self.kind}" takes {", ".join(needed)}'
                                 f'{" (not " + key + ")" if key not in needed else " (" + key + " is missing)"}')
        if self.kind == "tube" and 2 * self.wall_thickness_m > self.outer_diameter_m:
            raise ValueError("wall_thickness_m must be at most half of outer_diameter_m")
        if self.kind == "box" and 2 * self.wall_thickness_m >= min(self.width_m, self.height_m):
            raise ValueError("wall_thickness_m must be less than half of the smaller of width_m and height_m")
        return self

    def rectangles_m(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """(width, height) of the outer and the inner (hole) rectangle, m."""
        b, h = self.width_m, self.height_m
        t = self.wall_thickness_m if self.kind == "box" else 0.0
        inner = (b - 2 * t, h - 2 * t) if self.kind == "box" else (0.0, 0.0)
        return (b, h), inner

    @cached_property
    def area_m2(self) -> float:
        if self.kind == "tube":
            d = self.outer_diameter_m
            return math.pi / 4 * (d**2 - (d - 2 * self.wall_thickness_m) ** 2)
        (b, h), (bi, hi) = self.rectangles_m()
        return b * h - bi * hi

    @cached_property
    def second_moments_m4(self) -> tuple[float, float]:
        """(I_x, I_y): about the local x axis (bending in the height direction) and about y, m^4."""
        if self.kind == "tube":
            d = self.outer_diameter_m
            i = math.pi / 64 * (d**4 - (d - 2 * self.wall_thickness_m) ** 4)
            return i, i
        (b, h), (bi, hi) = self.rectangles_m()
        return (b * h**3 - bi * hi**3) / 12, (h * b**3 - hi * bi**3) / 12

    @cached_property
    def torsion_constant_m4(self) -> float:
        """Saint-Venant torsion constant J, m^4: tube 2 I (exact); box, Bredt's thin-walled closed section
        4 A_m^2 t / s_m = 2 t (b - t)^2 (h - t)^2 / (b + h - 2 t); solid rectangle a x c (a >= c), Roark's
        J = a c^3 (1/3 - 0.21 (c/a) (1 - c^4 / (12 a^4)))."""
        if self.kind == "tube":
            return 2 * self.second_moments_m4[0]
        b, h = self.width_m, self.height_m
        if self.kind == "box":
            t = self.wall_thickness_m
            return 2 * t * (b - t) ** 2 * (h - t) ** 2 / (b + h - 2 * t)
        a, c = max(b, h), min(b, h)
        return a * c**3 * (1 / 3 - 0.21 * (c / a) * (1 - c**4 / (12 * a**4)))

    @cached_property
    def shear_areas_m2(self) -> tuple[float, float]:
        """(A_s,x, A_s,y): shear areas for shear along the local x and y axes (Timoshenko), m^2: tube A / 2
        (thin-walled circular tube), box A b / (b + h) and A h / (b + h) (Eurocode 3, EN 1993-1-1 6.2.6 for a
        rectangular hollow section), solid rectangle 5 A / 6."""
        a = self.area_m2
        if self.kind == "tube":
            return a / 2, a / 2
        if self.kind == "box":
            b, h = self.width_m, self.height_m
            return a * b / (b + h), a * h / (b + h)
        return 5 * a / 6, 5 * a / 6

    @cached_property
    def outer_size_m(self) -> tuple[float, float]:
        """(width, height) of the outer contour, m (a tube: its diameter twice)."""
        if self.kind == "tube":
            return self.outer_diameter_m, self.outer_diameter_m
        return self.width_m, self.height_m


class Sections(StrictModel):
    column: BeamSection
    x_beam: BeamSection
    z_beam: BeamSection
    ram: BeamSection


class GantryFrame(StrictModel):
    """The portal and the carriages' offsets (module doc), m."""

    span_m: Positive  # between the column axes (x = +-span/2)
    column_height_m: Positive  # bed (y = 0) to the X beam's axis
    x_to_z_beam_drop_m: Positive  # X beam axis to the Z beam axis, vertical
    z_beam_to_ram_guide_drop_m: Positive  # Z beam axis to the ram's (lowest) guide point, vertical
    z_beam_half_length_m: Positive  # the Z beam reaches z = +-this from the X carriage
    ram_length_m: Positive  # whole ram (tool end to top)


class Guide(StrictModel):
    """A carriage's linear guide, lumped at the carriage point: translational stiffness normal to the axis
    (both normal directions, N/m), rotational stiffness about the two normals (pitch and yaw) and about the
    axis (roll), N m/rad."""

    normal_stiffness_n_per_m: Positive
    tilt_stiffness_nm_per_rad: Positive
    roll_stiffness_nm_per_rad: Positive


class ScrewDrive(StrictModel):
    """A ball-screw drive along the axis: the screw's root diameter and its free length between the fixed
    bearing and the nut (the longest over the travel: the softest position), nut and bearing stiffness."""

    screw_root_diameter_m: Positive
    screw_free_length_m: Positive
    nut_stiffness_n_per_m: Positive
    bearing_stiffness_n_per_m: Positive


class GantryAxis(StrictModel):
    guide: Guide
    drive: ScrewDrive
    carriage_mass_kg: NonNegative  # what this axis's carriage adds to the moving mass (tubes counted apart)


class Axes(StrictModel):
    x: GantryAxis
    y: GantryAxis
    z: GantryAxis


class GantryWorkspace(StrictModel):
    """The required tool workspace: a box x in +-x_half_width_m, z in +-z_half_width_m, tool height y in
    [tool_height_min_m, tool_height_max_m], m; the axes' travel."""

    x_half_width_m: Positive
    z_half_width_m: Positive
    tool_height_min_m: Positive
    tool_height_max_m: Positive


class GantryMass(StrictModel):
    density_kg_per_m3: Positive = 7850.0  # of every member (the tubes' masses follow from their sections)
    tool_mass_kg: NonNegative = 2.0  # tool and force sensor, a point mass at the ram tip


class Gantry(StrictModel):
    """A validated Cartesian gantry press (module doc). Lengths m, forces N, stiffness SI."""

    kind: Literal["gantry"]
    name: str
    description: str = ""
    material: Material
    frame: GantryFrame
    sections: Sections
    axes: Axes
    workspace: GantryWorkspace
    mass: GantryMass = GantryMass()
    model: ModelOptions = ModelOptions()
    source: str = ""

    @model_validator(mode="after")
    def _workspace_fits(self) -> Gantry:
        f, w = self.frame, self.workspace
        if w.tool_height_min_m >= w.tool_height_max_m:
            raise ValueError("workspace.tool_height_min_m must be smaller than workspace.tool_height_max_m")
        if w.x_half_width_m >= f.span_m / 2:
            raise ValueError(f"workspace.x_half_width_m = {w.x_half_width_m:g} m must be less than half of "
                             f"frame.span_m = {f.span_m:g} m (the X carriage runs between the columns)")
        if w.z_half_width_m > f.z_beam_half_length_m:
            raise ValueError(f"workspace.z_half_width_m = {w.z_half_width_m:g} m exceeds "
                             f"frame.z_beam_half_length_m = {f.z_beam_half_length_m:g} m")
        if self.ram_guide_height_m <= w.tool_height_max_m:
            raise ValueError(f"the ram guide at y = {self.ram_guide_height_m:g} m (frame.column_height_m - "
                             "x_to_z_beam_drop_m - z_beam_to_ram_guide_drop_m) must be above "
                             f"workspace.tool_height_max_m = {w.tool_height_max_m:g} m")
        if f.ram_length_m <= self.ram_guide_height_m - w.tool_height_min_m:
            raise ValueError(f"frame.ram_length_m = {f.ram_length_m:g} m must exceed the longest free length "
                             f"below the guide, {self.ram_guide_height_m - w.tool_height_min_m:g} m")
        return self

    @property
    def ram_guide_height_m(self) -> float:
        """Height of the ram's guide point (y), m."""
        f = self.frame
        return f.column_height_m - f.x_to_z_beam_drop_m - f.z_beam_to_ram_guide_drop_m

    def drive_stiffness_n_per_m(self, axis: str) -> float:
        """The ball-screw drive's axial stiffness of an axis ('x', 'y', 'z'): E A / L_free in series with
        nut and bearing (:func:`pressfit.description.drive_stiffness.screw_axial_stiffness_n_per_m`), N/m."""
        d = getattr(self.axes, axis).drive
        return float(drive_stiffness.screw_axial_stiffness_n_per_m(
            self.material.youngs_modulus_pa, d.screw_root_diameter_m, d.screw_free_length_m,
            d.nut_stiffness_n_per_m, d.bearing_stiffness_n_per_m))

    def member_mass_kg(self, member: str, length_m: float) -> float:
        """Mass of a length of a member ('column', 'x_beam', 'z_beam', 'ram'), kg."""
        return self.mass.density_kg_per_m3 * getattr(self.sections, member).area_m2 * length_m

    @cached_property
    def axis_moving_masses_kg(self) -> tuple[float, float, float]:
        """Mass moved by each axis (x, y, z order), kg: the ram axis moves the ram, its carriage and the tool;
        the Z axis adds its carriage; the X axis adds the Z beam and its own carriage."""
        f, a = self.frame, self.axes
        y = self.member_mass_kg("ram", f.ram_length_m) + a.y.carriage_mass_kg + self.mass.tool_mass_kg
        z = y + a.z.carriage_mass_kg
        x = z + self.member_mass_kg("z_beam", 2 * f.z_beam_half_length_m) + a.x.carriage_mass_kg
        return x, y, z

    def require_in_workspace(self, pose_m: Any) -> tuple[float, float, float]:
        """The pose (x, y, z) of the tool (m) as floats; :class:`UnreachablePoseError` outside the workspace."""
        x, y, z = (float(c) for c in pose_m)
        w, bad = self.workspace, []
        for name, value, lo, hi in (("x [m]", x, -w.x_half_width_m, w.x_half_width_m),
                                    ("y [m]", y, w.tool_height_min_m, w.tool_height_max_m),
                                    ("z [m]", z, -w.z_half_width_m, w.z_half_width_m)):
            if not value >= lo:
                bad.append((0, name, value, f"minimum {lo:g} (gantry workspace)"))
            elif not value <= hi:
                bad.append((0, name, value, f"maximum {hi:g} (gantry workspace)"))
        if bad:
            raise UnreachablePoseError((x, y, z), bad)
        return x, y, z

    def with_overrides(self, overrides: dict[str, Any], source: str = "<overrides>") -> Gantry:
        """A copy with nested keys replaced (e.g. ``{"sections": {"ram": {"width_m": 0.1}}}``)."""
        return _validate(_merge(self.model_dump(exclude={"source"}, exclude_none=True), overrides), source)


def _validate(data: dict[str, Any], source: str) -> Gantry:
    try:
        return Gantry.model_validate({**data, "source": source})
    except ValidationError as exc:
        raise validation_error(source, exc) from None


def is_gantry_file(data: dict[str, Any]) -> bool:
    """True for the parsed TOML of a gantry description (its top-level ``kind = "gantry"``)."""
    return data.get("kind") == "gantry"


def load_gantry(path: Path | str, overrides: dict[str, Any] | None = None) -> Gantry:
    """Load and validate a gantry description, optionally with nested parameter overrides."""
    data = read_toml(path)
    refuse_wrong_kind(path, data, "machine")
    if overrides:
        data = _merge(data, overrides)
    return _validate(data, str(path))
