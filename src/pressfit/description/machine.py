"""The machine as data: load and validate ``models/*.toml`` into frozen, typed objects.

Every quantity is SI and names its unit. A malformed file raises :class:`ModelFileError` naming the
file, the key and what was expected.
"""

from __future__ import annotations

import math
import stat
import tomllib
from functools import cached_property
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal

import numpy as np
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    ValidationInfo,
    create_model,
    field_validator,
    model_validator,
)

from pressfit.description import drive_stiffness
from pressfit.errors import LegCountError, ModelFileError, WrongFileKindError
from pressfit.shipped import default_model

DEFAULT_MODEL = default_model()  # the paper's machine, shipped inside the package

Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]
NonNegative = Annotated[float, Field(ge=0, allow_inf_nan=False)]
# Physical lower bounds of the inertia the time-domain dynamics need (``simulate``, ``control``, a gantry's
# figures): a body with inertia of its own (the plate, a cardan's spider, a tube through the density) lighter than
# a gram, or a material lighter than 100 kg/m^3 (below any structural one: wood is ~400), makes the mass matrix
# numerically singular. The modes and response accept lighter legs (the massless-leg closed forms of the tests)
MIN_BODY_MASS_KG = 1e-3
MIN_DENSITY_KG_PER_M3 = 100.0


def require_inertia(source: str, values: dict[str, float]) -> None:
    """Refuse inertial data below the physical bounds: ``values`` maps [mass] keys (``density_kg_per_m3`` or a
    ``*_mass_kg``) to their values; ModelFileError naming the file, the key and the bound."""
    for key, value in values.items():
        low, unit = (MIN_DENSITY_KG_PER_M3, "kg/m^3") if key == "density_kg_per_m3" else (MIN_BODY_MASS_KG, "kg")
        if not value >= low:
            raise ModelFileError(source or "<machine>", f"mass.{key}",
                                 f"at least {low:g} {unit} for the dynamics (the body carries inertia: a lighter one "
                                 f"makes the mass matrix singular), got {value:g}")
Finite = Annotated[float, Field(allow_inf_nan=False)]
Vector3 = Annotated[list[Finite], Field(min_length=3, max_length=3)]


RIGID_BULK_MODULUS_PA = 1e300  # Pa: an oil column made rigid (HydraulicDrive.rigid_overrides)


class StrictModel(BaseModel):
    """Base of every schema: unknown keys, type coercion and mutation are refused."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)


class Geometry(StrictModel):
    """Joint layout: p, r (Table 3) and optional heights of the cardan centres above the base plane (base)
    and above the plate centre (plate), the same for every leg; m."""

    base_half_side_m: Positive
    plate_half_side_m: Positive
    base_joint_height_m: Finite = 0.0
    plate_joint_height_m: Finite = 0.0

    @model_validator(mode="after")
    def _plate_inside_base(self) -> Geometry:
        if self.plate_half_side_m >= self.base_half_side_m:
            raise ValueError("plate_half_side_m must be smaller than base_half_side_m")
        return self


MAX_LEGS = 12  # a schema bound (a machine file is a few legs, not a data set)
MAX_CARDAN_TILT_RAD = 0.05  # largest accepted cardan misalignment (a manufacturing error, not a redesign)


class LegLayout(StrictModel):
    """One leg's direction and cardan axes. ``radial_direction``: the horizontal unit vector n_i from the base
    centre toward the leg's base cardan (a leg at angle theta about y: (cos theta, 0, sin theta)), so that
    B_i = p n_i and d_i = r n_i. ``cardan_axis``: the base cardan's first axis a_i, horizontal and normal to
    n_i (default n_i x y); ``plate_cardan_axis`` the plate cardan's first axis (default a_i), which Tsai's
    condition requires parallel to a_i (checked: a deviation is a misalignment, given as
    ``plate_cardan_tilt_rad``). ``beta_axis``: +-a_i, the direction s_i with sin(beta_i) = s_i . u_i / l_i
    (equation 1; default a_i; the paper's leg 4 uses +z against the default -z, docs/conventions.md).

    ``base_point_error_m`` and ``plate_point_error_m`` (m, world axes, default 0) move its base cardan centre
    B_i and its plate cardan centre d_i off the nominal layout (manufacturing errors; the leg lines then no
    longer meet at one point).

    ``base_cardan_tilt_rad`` and ``plate_cardan_tilt_rad`` (rad, default 0, norm at most
    MAX_CARDAN_TILT_RAD): misalignments of the base and plate cardans' axes, each a small rotation vector
    in the leg reference frame (X = +-a_i, Y = down, Z = inward w_i) turning that cardan's frame
    (R0_i -> R0_i Exp(theta)). Nonzero tilts break Tsai's condition (the plate cardan's axes no longer
    parallel to the base cardan's): the machine is then no longer a pure translator."""

    radial_direction: Vector3
    cardan_axis: Vector3 | None = None
    plate_cardan_axis: Vector3 | None = None
    beta_axis: Vector3 | None = None
    base_point_error_m: Vector3 = [0.0, 0.0, 0.0]
    plate_point_error_m: Vector3 = [0.0, 0.0, 0.0]
    base_cardan_tilt_rad: Vector3 = [0.0, 0.0, 0.0]
    plate_cardan_tilt_rad: Vector3 = [0.0, 0.0, 0.0]

    @field_validator("base_cardan_tilt_rad", "plate_cardan_tilt_rad")
    @classmethod
    def _small_tilt(cls, v: list[float]) -> list[float]:
        if math.sqrt(sum(c * c for c in v)) > MAX_CARDAN_TILT_RAD:
            raise ValueError(f"a cardan misalignment must have an angle of at most {MAX_CARDAN_TILT_RAD} rad")
        return v

    @field_validator("radial_direction", "cardan_axis", "plate_cardan_axis", "beta_axis")
    @classmethod
    def _unit(cls, v: list[float] | None) -> list[float] | None:
        if v is not None and abs(math.sqrt(sum(c * c for c in v)) - 1.0) > 1e-9:
            raise ValueError("must be a unit vector")
        return v

    @field_validator("radial_direction", "cardan_axis", "plate_cardan_axis")
    @classmethod
    def _horizontal(cls, v: list[float] | None) -> list[float] | None:
        if v is not None and abs(v[1]) > 1e-9:
            raise ValueError("must be horizontal (y component 0): the base and plate planes are y = const")
        return v

    @model_validator(mode="before")
    @classmethod
    def _default_axes(cls, data: Any) -> Any:
        if not isinstance(data, dict) or not isinstance(data.get("radial_direction"), list):
            return data
        data = {k: v for k, v in data.items() if v is not None}  # a dumped model lists absent keys as None
        n = data["radial_direction"]
        if len(n) == 3 and all(isinstance(c, int | float) and not isinstance(c, bool) for c in n):
            data.setdefault("cardan_axis", [-float(n[2]), 0.0, float(n[0])])  # n x y
        if isinstance(data.get("cardan_axis"), list):
            data.setdefault("plate_cardan_axis", data["cardan_axis"])
            data.setdefault("beta_axis", data["cardan_axis"])
        return data

    @model_validator(mode="after")
    def _axes_perpendicular(self) -> LegLayout:
        if abs(float(np.dot(self.radial_direction, self.cardan_axis))) > 1e-9:
            raise ValueError("cardan_axis must be perpendicular to radial_direction")
        if abs(abs(float(np.dot(self.beta_axis, self.cardan_axis))) - 1.0) > 1e-9:
            raise ValueError("beta_axis must be +/- cardan_axis")
        if abs(abs(float(np.dot(self.plate_cardan_axis, self.cardan_axis))) - 1.0) > 1e-9:
            raise ValueError("plate_cardan_axis must be parallel to cardan_axis (Tsai's condition: the plate "
                             "cardan's axes parallel to the base cardan's); give a small misalignment as "
                             f"plate_cardan_tilt_rad (at most {MAX_CARDAN_TILT_RAD} rad)")
        return self


class Limits(StrictModel):
    leg_length_min_m: Positive
    leg_length_max_m: Positive
    alpha_min_rad: Finite
    alpha_max_rad: Finite
    beta_min_rad: Finite
    beta_max_rad: Finite

    @model_validator(mode="after")
    def _ordered(self) -> Limits:
        for lo, hi in (("leg_length_min_m", "leg_length_max_m"), ("alpha_min_rad", "alpha_max_rad"),
                       ("beta_min_rad", "beta_max_rad")):
            if getattr(self, lo) >= getattr(self, hi):
                raise ValueError(f"{lo} must be smaller than {hi}")
        return self


class Workspace(StrictModel):
    x_half_width_m: Positive
    z_half_width_m: Positive
    height_min_m: Positive


class Material(StrictModel):
    youngs_modulus_pa: Positive
    shear_modulus_pa: Positive


class Cylinder(StrictModel):
    length_m: Positive
    outer_diameter_m: Positive
    wall_thickness_m: Positive

    @model_validator(mode="after")
    def _wall(self) -> Cylinder:
        if 2 * self.wall_thickness_m > self.outer_diameter_m:
            raise ValueError("wall_thickness_m must be at most half of outer_diameter_m")
        return self


class Stem(StrictModel):
    """The stem: a solid rod of ``diameter_m`` and fixed ``length_m`` (m) sliding in the cylinder; the part beyond
    the cylinder's end (l - L_c at leg length l) is exposed, the rest is inside the cylinder (its inner end, with
    the actuator's moving parts, at l - length_m from the base cardan). ``length_m`` must exceed the longest
    exposed stem the limits allow (l_max - L_c: the full stroke leaves rod in the cylinder), checked by
    :func:`load_machine` and :meth:`Machine.with_overrides` (:func:`require_rod_in_cylinder`)."""

    diameter_m: Positive
    length_m: Positive


class DriveTable(StrictModel):
    """A drive kind's schema table, owning the kind's statics (docs/drives.md): ``force_limit_n`` (N, the largest
    tension magnitude it delivers), ``force_limit_key`` (the machine-file keys that set it, for messages),
    :meth:`axial_stiffness_n_per_m` (its own axial stiffness in series with the leg), :meth:`reflected_mass_kg`
    (inertia along the leg carried as the prismatic joint's armature) and :meth:`check` (its constraints
    against the rest of the machine). ``inline``: its keys sit in ``[actuator]`` itself (the force kind), not
    in a table ``[actuator.<kind>]``. ``sensed_past_stiffness``: its position sensor reads the drive's output
    past its own axial stiffness, which is then inside the position loop and not between the sensor and the tool
    (a hydraulic cylinder's piston sensor, past the oil column; a servo motor's encoder sits before its ball
    screw, a linear motor's scale inside its mount). A new kind is one subclass and one line of
    :data:`DRIVE_TABLES`."""

    inline: ClassVar[bool] = False
    force_limit_key: ClassVar[str] = ""

    @property
    def force_limit_n(self) -> float:
        raise NotImplementedError

    def axial_stiffness_n_per_m(self, machine: Machine, leg_length_m: np.ndarray | float) -> np.ndarray:
        raise NotImplementedError

    def reflected_mass_kg(self, machine: Machine) -> float:
        """Inertia reflected along the leg, kg (0 unless the kind says otherwise)."""
        return 0.0

    def check(self, machine: Machine) -> None:
        """Refuse (ValueError naming the key) a table that does not fit the machine; nothing by default."""

    def rigid_overrides(self) -> dict[str, Any]:
        """The machine-file overrides that make the drive's own stiffness rigid (:attr:`Machine.sensed_view`), for a
        kind whose sensor reads past it; none by default."""
        return {}

    @property
    def sensed_past_stiffness(self) -> bool:
        """Whether the kind's position sensor reads past its own stiffness: it gives :meth:`rigid_overrides`."""
        return bool(self.rigid_overrides())


class ForceSource(DriveTable):
    """``kind = "force"``: an ideal first-order force source, its keys in ``[actuator]`` itself: axial stiffness
    (N/m, required), the force bandwidth (Hz; paper section 4.2: 40 Hz, feasible for servo-hydraulics) and its
    force saturation (N, magnitude; an estimate, see the machine file)."""

    inline: ClassVar[bool] = True
    force_limit_key: ClassVar[str] = "[actuator] force_limit_n"

    axial_stiffness_n_per_m_: Positive = Field(alias="axial_stiffness_n_per_m")
    force_bandwidth_hz: Positive = 40.0
    force_limit_n_: Positive = Field(1000.0, alias="force_limit_n")

    @property
    def force_limit_n(self) -> float:
        return self.force_limit_n_

    def axial_stiffness_n_per_m(self, machine: Machine, leg_length_m: np.ndarray | float) -> np.ndarray:
        """``axial_stiffness_n_per_m`` at every length, N/m."""
        return np.full_like(np.asarray(leg_length_m, dtype=float), self.axial_stiffness_n_per_m_)


class CurrentLoop(DriveTable):
    """The keys of a drive with a current loop (an electric motor: rotary or linear). The loop is given by its
    closed-loop bandwidth (``current_loop_bandwidth_hz``: a first-order loop) or by its PI gains on the winding
    (``current_loop_kp_v_per_a``, ``current_loop_ki_v_per_a_s``, ``winding_inductance_h``,
    ``winding_resistance_ohm``)."""

    current_limit_a: Positive
    current_loop_bandwidth_hz: Positive | None = None
    current_loop_kp_v_per_a: Positive | None = None
    current_loop_ki_v_per_a_s: Positive | None = None
    winding_inductance_h: Positive | None = None
    winding_resistance_ohm: Positive | None = None

    def _require_current_loop(self) -> None:
        gains = ("current_loop_kp_v_per_a", "current_loop_ki_v_per_a_s", "winding_inductance_h",
                 "winding_resistance_ohm")
        given = [getattr(self, k) is not None for k in gains]
        if self.current_loop_bandwidth_hz is not None and any(given[:3]):
            raise ValueError("give the current loop either as current_loop_bandwidth_hz or as its gains "
                             f"({', '.join(gains)}), not both")
        if self.current_loop_bandwidth_hz is None and not all(given):
            raise ValueError("give current_loop_bandwidth_hz or all of " + ", ".join(gains))

    @property
    def force_per_current_n_per_a(self) -> float:
        raise NotImplementedError

    @property
    def force_limit_n(self) -> float:
        """Largest axial force k_f i_max, N."""
        return self.force_per_current_n_per_a * self.current_limit_a


class ElectricDrive(CurrentLoop):
    """``[actuator.electric]``: servo motor + ball screw (docs/drives.md). The screw's root diameter gives its
    section (stiffness E A / L_free, and its inertia when ``screw_length_m`` is given instead of
    ``screw_inertia_kg_m2``); the free length between the fixed bearing and the nut is either constant
    (``screw_free_length_m``) or ``screw_free_length_at_min_leg_m`` at ``limits.leg_length_min_m``, growing one
    for one with the leg length. The current loop: :class:`CurrentLoop`."""

    force_limit_key: ClassVar[str] = "2 pi eta K_t [actuator.electric] current_limit_a / lead"

    lead_m: Positive
    screw_diameter_m: Positive
    screw_free_length_m: Positive | None = None
    screw_free_length_at_min_leg_m: Positive | None = None
    nut_stiffness_n_per_m: Positive
    bearing_stiffness_n_per_m: Positive
    rotor_inertia_kg_m2: Positive
    screw_inertia_kg_m2: Positive | None = None
    screw_length_m: Positive | None = None
    screw_efficiency: Annotated[float, Field(gt=0, le=1, allow_inf_nan=False)] = 0.9
    torque_constant_nm_per_a: Positive
    speed_limit_rad_per_s: Positive
    continuous_torque_nm: Positive | None = None  # the motor's rated (continuous, S1) torque: the RMS torque's rating
    rated_power_w: Positive | None = None  # the motor's rated power: the peak mechanical power's rating

    @model_validator(mode="after")
    def _one_of_each(self) -> ElectricDrive:
        _exactly_one(self, "screw_free_length_m", "screw_free_length_at_min_leg_m")
        _exactly_one(self, "screw_inertia_kg_m2", "screw_length_m")
        self._require_current_loop()
        return self

    @property
    def force_per_current_n_per_a(self) -> float:
        """Axial force per motor current, 2 pi eta K_t / lead, N/A."""
        return 2.0 * math.pi * self.screw_efficiency * self.torque_constant_nm_per_a / self.lead_m

    @property
    def force_limit_n(self) -> float:
        """Largest axial force, 2 pi eta K_t i_max / lead, N."""
        return self.force_per_current_n_per_a * self.current_limit_a

    def axial_stiffness_n_per_m(self, machine: Machine, leg_length_m: np.ndarray | float) -> np.ndarray:
        """The ball screw E A / L_free(l) in series with nut and bearing, N/m."""
        length = np.asarray(leg_length_m, dtype=float)
        free = (np.full_like(length, self.screw_free_length_m) if self.screw_free_length_m is not None
                else self.screw_free_length_at_min_leg_m + (length - machine.limits.leg_length_min_m))
        return drive_stiffness.screw_axial_stiffness_n_per_m(
            machine.material.youngs_modulus_pa, self.screw_diameter_m, free, self.nut_stiffness_n_per_m,
            self.bearing_stiffness_n_per_m)

    def screw_inertia(self, machine: Machine) -> float:
        """The ball screw's inertia about its axis, kg m^2: ``screw_inertia_kg_m2`` or a solid steel bar of the
        root diameter d and ``screw_length_m`` L, rho pi d^4 L / 32 (rho = ``mass.density_kg_per_m3``)."""
        if self.screw_inertia_kg_m2 is not None:
            return self.screw_inertia_kg_m2
        return machine.mass.density_kg_per_m3 * math.pi * self.screw_diameter_m**4 * self.screw_length_m / 32.0

    def reflected_mass_kg(self, machine: Machine) -> float:
        """(J_rotor + J_screw) (2 pi / lead)^2, kg (its kinetic energy J omega^2 / 2 with omega = 2 pi l_dot /
        lead)."""
        return (self.rotor_inertia_kg_m2 + self.screw_inertia(machine)) * (2.0 * math.pi / self.lead_m) ** 2


class HydraulicDrive(DriveTable):
    """``[actuator.hydraulic]``: symmetric double-acting cylinder with a servo valve (docs/drives.md). The
    annulus area is ``piston_area_m2`` or follows from ``bore_diameter_m`` and ``rod_diameter_m`` (a rod on
    both sides). The working leg travel sits centred in the stroke: piston position
    x = l - l_min + (s - (l_max - l_min)) / 2 from the base-side end. Chamber a's pressure pulls the leg
    shorter (tension), chamber b's pushes it longer. Valve: Q = K_v x_v sqrt(dp), spool x_v in [-1, 1]
    with a first-order response; pressure loop x_v,cmd = g (dp_cmd - dp) - f_v A l_dot / K_q, dp = p_a - p_b,
    f_v = ``flow_feedforward`` (0..1) the fraction of the leg's flow A l_dot fed forward from the measured leg
    rate through the null flow gain K_q = K_v sqrt((p_s - p_t) / 2). No reflected inertia: the piston and rod
    translate with the stem (``mass.actuator_moving_mass_kg``)."""

    force_limit_key: ClassVar[str] = "A ([actuator.hydraulic] supply_pressure_pa - tank_pressure_pa)"

    piston_area_m2: Positive | None = None
    bore_diameter_m: Positive | None = None
    rod_diameter_m: Positive | None = None
    stroke_m: Positive
    dead_volume_a_m3: Positive
    dead_volume_b_m3: Positive
    bulk_modulus_pa: Positive
    supply_pressure_pa: Positive
    tank_pressure_pa: NonNegative = 0.0
    valve_flow_gain_m3_per_s_sqrt_pa: Positive
    valve_bandwidth_hz: Positive
    leakage_m3_per_s_pa: NonNegative = 0.0
    pressure_loop_gain_per_pa: Positive
    flow_feedforward: Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)] = 0.0

    @model_validator(mode="after")
    def _area(self) -> HydraulicDrive:
        if self.piston_area_m2 is not None and (self.bore_diameter_m, self.rod_diameter_m) != (None, None):
            raise ValueError("give piston_area_m2 or bore_diameter_m and rod_diameter_m, not both")
        if self.piston_area_m2 is None:
            if self.bore_diameter_m is None or self.rod_diameter_m is None:
                raise ValueError("give piston_area_m2 or both bore_diameter_m and rod_diameter_m")
            if self.rod_diameter_m >= self.bore_diameter_m:
                raise ValueError("rod_diameter_m must be smaller than bore_diameter_m")
        if self.tank_pressure_pa >= self.supply_pressure_pa:
            raise ValueError("tank_pressure_pa must be below supply_pressure_pa")
        return self

    @property
    def area_m2(self) -> float:
        """Effective piston area A (annulus pi (D^2 - d^2) / 4 for a symmetric cylinder), m^2."""
        if self.piston_area_m2 is not None:
            return self.piston_area_m2
        return math.pi / 4.0 * (self.bore_diameter_m**2 - self.rod_diameter_m**2)

    @property
    def force_limit_n(self) -> float:
        """Largest axial force A (p_s - p_t), N (one chamber at supply, the other at tank)."""
        return self.area_m2 * (self.supply_pressure_pa - self.tank_pressure_pa)

    def axial_stiffness_n_per_m(self, machine: Machine, leg_length_m: np.ndarray | float) -> np.ndarray:
        """The oil column beta A^2 (1/V_a + 1/V_b) at the piston position of l (valve closed), N/m."""
        v_a, v_b = drive_stiffness.chamber_volumes_m3(self.area_m2, self.stroke_m, machine.piston_position_m(
            np.asarray(leg_length_m, dtype=float)), self.dead_volume_a_m3, self.dead_volume_b_m3)
        return drive_stiffness.oil_column_stiffness_n_per_m(self.bulk_modulus_pa, self.area_m2, v_a, v_b)

    def rigid_overrides(self) -> dict[str, Any]:
        """The oil column made rigid: a bulk modulus ``RIGID_BULK_MODULUS_PA`` (its compliance then vanishes against
        the tubes' in floating point)."""
        return {"actuator": {"hydraulic": {"bulk_modulus_pa": RIGID_BULK_MODULUS_PA}}}

    def check(self, machine: Machine) -> None:
        """The stroke must hold the leg travel l_max - l_min."""
        travel = machine.limits.leg_length_max_m - machine.limits.leg_length_min_m
        if self.stroke_m < travel:
            raise ValueError(f"actuator.hydraulic.stroke_m must be at least the leg travel leg_length_max_m - "
                             f"leg_length_min_m = {travel:g} m (got {self.stroke_m!r})")


class LinearMotorDrive(CurrentLoop):
    """``[actuator.linear_motor]``: a direct-drive linear motor on each leg (the drive the paper argues for;
    docs/drives.md): the forcer on the stem, the magnet track along the cylinder. Force N = K_f i (1 + ripple)
    + cogging, K_f = ``force_constant_n_per_a`` (N/A, = the back-EMF constant in V s/m); the peak force
    K_f i_max, the continuous (S1) force ``continuous_force_n`` (the RMS force's rating); ``speed_limit_m_per_s``
    (m/s) its largest leg speed; the current loop as :class:`CurrentLoop` (``winding_resistance_ohm`` is
    required: the copper loss R i^2 heats the winding). Statics: no screw, the mount (forcer bracket and track)
    ``mount_stiffness_n_per_m`` (N/m) is the drive's own axial stiffness; the forcer's ``moving_mass_kg`` (kg)
    is carried along the leg as the prismatic joint's armature (behind the mount in the linearised port).
    Thermal: winding-to-ambient ``thermal_resistance_k_per_w`` (K/W) and ``thermal_time_constant_s`` (s), the
    rise limited to ``max_winding_temperature_rise_k`` (K). Ripple (period ``pole_pitch_m`` / 3, the 6th
    electrical harmonic of a 3-phase motor): ``force_ripple_fraction`` of K_f i and ``cogging_force_n`` (N), of which
    the drive compensates the fraction ``ripple_compensation`` (0..1, a calibrated anti-cogging table; default 0).
    ``encoder_resolution_m``: the linear encoder's step (m), the leg length it measures is quantised on it."""

    force_limit_key: ClassVar[str] = "K_f i_max = [actuator.linear_motor] force_constant_n_per_a x current_limit_a"

    force_constant_n_per_a: Positive
    continuous_force_n: Positive
    speed_limit_m_per_s: Positive
    mount_stiffness_n_per_m: Positive
    moving_mass_kg: NonNegative
    thermal_resistance_k_per_w: Positive
    thermal_time_constant_s: Positive
    max_winding_temperature_rise_k: Positive
    pole_pitch_m: Positive
    force_ripple_fraction: Annotated[float, Field(ge=0, lt=1, allow_inf_nan=False)] = 0.0
    cogging_force_n: NonNegative = 0.0
    ripple_compensation: Annotated[float, Field(ge=0, le=1, allow_inf_nan=False)] = 0.0
    encoder_resolution_m: Positive

    @model_validator(mode="after")
    def _loop_and_ratings(self) -> LinearMotorDrive:
        self._require_current_loop()
        if self.winding_resistance_ohm is None:
            raise ValueError("winding_resistance_ohm is required (the copper loss R i^2 heats the winding)")
        if self.continuous_force_n > self.force_limit_n:
            raise ValueError(f"continuous_force_n must be at most the peak force force_constant_n_per_a x "
                             f"current_limit_a = {self.force_limit_n:g} N (got {self.continuous_force_n!r})")
        return self

    @property
    def force_per_current_n_per_a(self) -> float:
        """K_f, N/A."""
        return self.force_constant_n_per_a

    def axial_stiffness_n_per_m(self, machine: Machine, leg_length_m: np.ndarray | float) -> np.ndarray:
        """The mount's ``mount_stiffness_n_per_m`` at every length (no screw), N/m."""
        return np.full_like(np.asarray(leg_length_m, dtype=float), self.mount_stiffness_n_per_m)

    def reflected_mass_kg(self, machine: Machine) -> float:
        """The forcer's ``moving_mass_kg`` along the leg, kg."""
        return self.moving_mass_kg


def _exactly_one(table: BaseModel, a: str, b: str) -> None:
    if (getattr(table, a) is None) == (getattr(table, b) is None):
        raise ValueError(f"give exactly one of {a} and {b}")


# The drive kinds: ``[actuator] kind`` -> its schema table (the only list of kinds; a table that is not inline is
# ``[actuator.<kind>]``). Their dynamics: pressfit.dynamics.drives.DRIVES, keyed by these tables.
DRIVE_TABLES: dict[str, type[DriveTable]] = {
    "force": ForceSource,
    "electric": ElectricDrive,
    "hydraulic": HydraulicDrive,
    "linear_motor": LinearMotorDrive,
}
_INLINE = {name: table for name, table in DRIVE_TABLES.items() if table.inline}
_TABLES = {name: table for name, table in DRIVE_TABLES.items() if not table.inline}
_INLINE_KEYS = {field.alias or key: field for table in _INLINE.values() for key, field in table.model_fields.items()}


class _ActuatorKeys(StrictModel):
    """The linear actuators. ``kind`` (default "force") selects the drive (:data:`DRIVE_TABLES`, docs/drives.md):

    * "force": an ideal first-order force source, the keys of :class:`ForceSource` in ``[actuator]`` itself;
    * "electric": servo motor + ball screw, the table ``[actuator.electric]`` (:class:`ElectricDrive`);
    * "hydraulic": servo valve + symmetric cylinder, the table ``[actuator.hydraulic]`` (:class:`HydraulicDrive`);
    * "linear_motor": direct-drive linear motor, ``[actuator.linear_motor]`` (:class:`LinearMotorDrive`).

    A tabled drive's stiffness, bandwidth and force limit follow from its table, so the force kind's three keys
    are refused with it (one key means one thing)."""

    axial_stiffness_n_per_m: Positive | None = None
    force_bandwidth_hz: Positive | None = None
    force_limit_n: Positive | None = None

    @model_validator(mode="before")
    @classmethod
    def _kind_keys(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        data = {k: v for k, v in data.items() if v is not None}  # a dumped model lists absent keys as None
        kind = data.get("kind", "force")
        if kind not in DRIVE_TABLES:
            return data  # the kind's Literal names the known kinds, at actuator.kind
        if kind in _INLINE:
            for key, field in _INLINE_KEYS.items():
                if field.is_required() and key not in data:
                    raise ValueError(f"{key} is required for kind = \"{kind}\"")
                data.setdefault(key, field.default)
        elif kind in _TABLES:
            given = sorted(set(_INLINE_KEYS) & set(data))
            if given:
                raise ValueError(f"{given[0]} belongs to kind = \"force\"; the {kind} drive's stiffness, bandwidth "
                                 f"and force limit follow from [actuator.{kind}]")
            if kind not in data:
                raise ValueError(f"kind = \"{kind}\" needs the table [actuator.{kind}]")
        for table in _TABLES:
            if table in data and table != kind:
                raise ValueError(f"[actuator.{table}] is given but kind = \"{kind}\"")
        return data

    @cached_property
    def table(self) -> DriveTable:
        """The drive kind's table (:data:`DRIVE_TABLES`): ``[actuator.<kind>]``, or the inline keys' table."""
        kind = self.kind  # type: ignore[attr-defined]
        if kind in _INLINE:
            return _INLINE[kind].model_validate({key: getattr(self, key) for key in _INLINE_KEYS})
        return getattr(self, kind)

    @property
    def drive_force_limit_n(self) -> float:
        """The largest axial force the drive delivers (magnitude), N (:attr:`DriveTable.force_limit_n`): the
        force kind's ``force_limit_n``, 2 pi eta K_t i_max / lead (electric), A (p_s - p_t) (hydraulic),
        K_f i_max (linear motor)."""
        return self.table.force_limit_n


Actuator = create_model(
    "Actuator", __base__=_ActuatorKeys, __module__=__name__, __doc__=_ActuatorKeys.__doc__,
    kind=(Literal[tuple(DRIVE_TABLES)], "force"),
    **{name: (table | None, None) for name, table in _TABLES.items()})
Actuator.__qualname__ = "Actuator"


class Joints(StrictModel):
    """Cardan compliance. ``cardan_axial_clearance_m``: the play g of each cardan, m, in the shape
    ``cardan_clearance_geometry`` gives it: "axial" (default) +-g along the leg axis; "box" +-g on each of
    the joint's three translations in the cardan's axes (a, b, c = a x b); "sphere" a ball of radius g.
    Each enters as a dead zone in series with the leg of its effective axial gap at the pose (its support
    function along the leg: g, g (|cos beta| + |sin beta|), g; :mod:`pressfit.mechanics.clearance`)."""

    cardan_axial_clearance_m: NonNegative = 0.0
    cardan_clearance_geometry: Literal["axial", "box", "sphere"] = "axial"
    cardan_contact_stiffness_n_per_m: Positive = 1.0e9  # per cardan, along the leg (pressfit.clearance)
    cardan_rotational_stiffness_nm_per_rad: Positive | None = None

    @model_validator(mode="before")
    @classmethod
    def _renamed(cls, data: Any) -> Any:
        if isinstance(data, dict) and "cardan_radial_clearance_m" in data:
            raise ValueError("cardan_radial_clearance_m is renamed cardan_axial_clearance_m: the play is applied "
                             "along the leg axis (+-g per cardan), not radially")
        return data


class Mass(StrictModel):
    """Inertial data (kg, kg/m^3) for modes and dynamics; the defaults are estimates (see the machine file).

    The leg tubes' masses follow from ``density_kg_per_m3`` and the cylinder and stem sections and lengths
    (the stem is a rod of fixed length ``stem.length_m``: its mass is the same at every pose, its centre of mass
    moves with the extension). The tool is lumped at the plate centre with the plate (a
    uniform box of side 2 r and ``collision.plate_thickness_m``); the actuator housing is spread uniformly
    along the cylinder, its moving parts (nut, piston) ride on the rod at its inner end;
    each cardan is a small sphere at its centre (split between its spider and the next body).
    """

    density_kg_per_m3: Positive = 7850.0
    plate_mass_kg: Positive = 4.2
    tool_mass_kg: NonNegative = 2.0
    actuator_housing_mass_kg: NonNegative = 2.5
    actuator_moving_mass_kg: NonNegative = 0.8
    cardan_spider_mass_kg: NonNegative = 0.3

    def require_dynamics_inertia(self, source: str) -> None:
        """:func:`require_inertia` of the bodies that carry inertia of their own (the plate, the spiders, the
        tubes through the density) of the machine file ``source``."""
        require_inertia(source, {"density_kg_per_m3": self.density_kg_per_m3, "plate_mass_kg": self.plate_mass_kg,
                                 "cardan_spider_mass_kg": self.cardan_spider_mass_kg})


class Damping(StrictModel):
    """Structural damping of the flexible dynamics (:mod:`pressfit.dynamics.machine.flexible`): Rayleigh damping
    C = alpha M_e + beta K on the elastic coordinates, given as ``alpha_per_s`` (1/s) and ``beta_s`` (s) with
    ``kind = "rayleigh"``, or fitted to modal damping ratios ``ratios`` at two ``modes`` (numbered from 1 by
    increasing frequency, the modes of ``pressfit modes``) with ``kind = "modal"``. The default, 2% at modes 1
    and 3 (the rocking mode and the plate twist; modes 1 and 2 are a near-degenerate pair that cannot fix two
    coefficients), is an ESTIMATE: bolted steel frames show 1-5%."""

    kind: Literal["modal", "rayleigh"] = "modal"
    modes: Annotated[list[Annotated[int, Field(ge=1, le=60)]], Field(min_length=2, max_length=2)] | None = None
    ratios: Annotated[list[Annotated[float, Field(ge=0, lt=1, allow_inf_nan=False)]],
                      Field(min_length=2, max_length=2)] | None = None
    alpha_per_s: NonNegative | None = None
    beta_s: NonNegative | None = None

    @model_validator(mode="after")
    def _one_kind(self) -> Damping:
        modal, rayleigh = (self.modes, self.ratios), (self.alpha_per_s, self.beta_s)
        if self.kind == "modal":
            if any(v is not None for v in rayleigh):
                raise ValueError('alpha_per_s and beta_s belong to kind = "rayleigh", not "modal"')
            if self.modes is not None and self.modes[0] >= self.modes[1]:
                raise ValueError("modes must be two increasing mode numbers")
        elif any(v is not None for v in modal) or any(v is None for v in rayleigh):
            raise ValueError('kind = "rayleigh" takes alpha_per_s and beta_s (and not modes, ratios)')
        return self

    @property
    def fit_modes(self) -> list[int]:
        return self.modes or [1, 3]

    @property
    def fit_ratios(self) -> list[float]:
        return self.ratios or [0.02, 0.02]


class ModelOptions(StrictModel):
    springs_per_segment: Annotated[int, Field(ge=1, le=64)] = 4


class ExtraBody(StrictModel):
    """A body for interference checks: a mesh file (STL/OBJ/..., convex hull used) or a box.

    ``frame`` 'world' places it in the world frame, 'plate' relative to the plate centre h (it moves
    with the plate). Pose: x = R t + translation_m with R = Rz(yaw) Ry(pitch) Rx(roll) from
    ``rotation_rpy_rad``. Mesh coordinates are multiplied by ``mesh_scale`` (0.001 for files in mm);
    a relative ``mesh_path`` is resolved from the machine (or case) file's directory.
    """

    name: Annotated[str, Field(min_length=1, pattern=r"^[A-Za-z0-9_\-]+$")]
    frame: Literal["world", "plate"] = "world"
    mesh_path: str | None = None
    mesh_scale: Positive = 1.0
    box_size_m: Annotated[list[Positive], Field(min_length=3, max_length=3)] | None = None  # full sides
    translation_m: Vector3 = [0.0, 0.0, 0.0]
    rotation_rpy_rad: Vector3 = [0.0, 0.0, 0.0]

    @model_validator(mode="after")
    def _one_shape(self) -> ExtraBody:
        if (self.mesh_path is None) == (self.box_size_m is None):
            raise ValueError("give exactly one of mesh_path and box_size_m")
        return self


class Collision(StrictModel):
    """Interference shapes (capsules for the legs, boxes for plate and base) and pair overrides.

    Pairs are named 'body_a|body_b' with bodies leg1.cylinder ... leg<n>.stem, plate, base and the
    extra bodies' names (see :mod:`pressfit.interference`).
    """

    cylinder_radius_m: Positive
    stem_radius_m: Positive
    plate_thickness_m: Positive
    base_thickness_m: Positive
    safety_margin_m: NonNegative = 0.0
    base_half_extent_m: Positive | None = None  # half-side of the base box in x and z; default p
    leg_shape: Literal["capsule", "cylinder"] = "capsule"  # capsule: conservative by a radius at the ends
    extra_bodies: list[ExtraBody] = []
    include_pairs: list[str] = []  # checked in addition to the default pairs
    exclude_pairs: list[str] = []  # removed from the default pairs

    @model_validator(mode="after")
    def _stem_inside_cylinder(self) -> Collision:
        if self.stem_radius_m > self.cylinder_radius_m:
            raise ValueError("stem_radius_m must not exceed cylinder_radius_m (the rod slides inside)")
        names = [b.name for b in self.extra_bodies]
        if len(set(names)) != len(names):
            raise ValueError("extra_bodies names must be unique")
        return self


class Section(BaseModel):
    """Cross-section properties of a leg segment (SI)."""

    model_config = ConfigDict(frozen=True)
    area_m2: float
    second_moment_m4: float  # bending, about any diameter
    polar_moment_m4: float  # torsion constant (circular section: 2 I)


class Machine(StrictModel):
    """A validated n-UPU machine description (n >= 3 legs; the paper's machine has 4). Lengths m, angles rad,
    forces N, stiffness SI. Per-leg arrays have the leg count n = len(legs) as their first axis."""

    name: str
    description: str = ""
    geometry: Geometry
    legs: Annotated[list[LegLayout], Field(min_length=3, max_length=MAX_LEGS)]
    limits: Limits
    workspace: Workspace
    material: Material
    cylinder: Cylinder
    stem: Stem
    actuator: Actuator
    joints: Joints = Joints()
    mass: Mass = Mass()
    damping: Damping = Damping()
    model: ModelOptions = ModelOptions()
    collision: Collision
    source: str = ""

    @field_validator("legs")
    @classmethod
    def _distinct_legs(cls, legs: list[LegLayout]) -> list[LegLayout]:
        radial = np.array([leg.radial_direction for leg in legs])
        close = np.abs(radial @ radial.T - 1.0) < 1e-9
        np.fill_diagonal(close, False)
        if close.any():
            i, j = np.argwhere(close)[0]
            raise ValueError(f"legs {i + 1} and {j + 1} have the same radial_direction (one joint for two legs)")
        return legs

    @field_validator("stem")
    @classmethod
    def _stem_inside_bore(cls, stem: Stem, info: ValidationInfo) -> Stem:
        cyl = info.data.get("cylinder")
        if cyl is not None and stem.diameter_m >= cyl.outer_diameter_m - 2 * cyl.wall_thickness_m:
            bore = cyl.outer_diameter_m - 2 * cyl.wall_thickness_m
            raise ValueError(f"stem.diameter_m = {stem.diameter_m:g} m must be smaller than the cylinder bore "
                             f"{bore:g} m (cylinder.outer_diameter_m - 2 cylinder.wall_thickness_m): the stem "
                             "slides inside the cylinder")
        return stem

    @model_validator(mode="after")
    def _cylinder_shorter_than_legs(self) -> Machine:
        if self.cylinder.length_m >= self.limits.leg_length_min_m:
            raise ValueError("cylinder.length_m must be shorter than limits.leg_length_min_m")
        self.actuator.table.check(self)
        return self


    @property
    def redundancy(self) -> int:
        """Degree of actuation redundancy n - 3 (n legs, 3 translations): the dimension of the preload space."""
        return len(self.legs) - 3

    def require_legs(self, layer: str, *supported: int) -> None:
        """Refuse this machine up front in a layer that supports only ``supported`` leg counts
        (:class:`LegCountError` naming the layer)."""
        if len(self.legs) not in supported:
            raise LegCountError(self.name, len(self.legs), supported, layer)

    # --- derived geometry (arrays, SI) -------------------------------------------------------
    @cached_property
    def base_points_m(self) -> np.ndarray:
        """(n, 3) base cardan centres B_i = p n_i + h_b y + e_i in the world frame, m (n_i radial, h_b the
        joint height, e_i the leg's position error)."""
        radial = np.array([leg.radial_direction for leg in self.legs])
        return (self.geometry.base_half_side_m * radial + [0.0, self.geometry.base_joint_height_m, 0.0]
                + np.array([leg.base_point_error_m for leg in self.legs]))

    @cached_property
    def plate_offsets_m(self) -> np.ndarray:
        """(n, 3) plate cardan centres relative to the plate centre, d_i = r n_i + h_p y + e_i, m."""
        radial = np.array([leg.radial_direction for leg in self.legs])
        return (self.geometry.plate_half_side_m * radial + [0.0, self.geometry.plate_joint_height_m, 0.0]
                + np.array([leg.plate_point_error_m for leg in self.legs]))

    @cached_property
    def legs_concurrent(self) -> bool:
        """True when every leg line meets the others at one point P* for every pose h (see
        :func:`pressfit.kinematics.concurrency_point`), i.e. p (d_i - h_p y) = r (B_i - h_b y) for each leg (to
        1e-12 m): false once a joint position error breaks it."""
        g = self.geometry
        p, r = g.base_half_side_m, g.plate_half_side_m
        d = self.plate_offsets_m - [0.0, g.plate_joint_height_m, 0.0]
        b = self.base_points_m - [0.0, g.base_joint_height_m, 0.0]
        return bool(np.all(np.abs(p * d - r * b) <= 1e-12 * p))

    @cached_property
    def cardan_tilts_rad(self) -> np.ndarray:
        """(n, 2, 3) cardan misalignment rotation vectors per leg, (base, plate), in the leg reference frame, rad."""
        return np.array([[leg.base_cardan_tilt_rad, leg.plate_cardan_tilt_rad] for leg in self.legs], dtype=float)

    @cached_property
    def has_cardan_tilts(self) -> bool:
        """True when any cardan is misaligned (Tsai's condition broken: not a pure translator)."""
        return bool(np.any(self.cardan_tilts_rad != 0.0))

    @cached_property
    def cardan_axes(self) -> np.ndarray:
        """(n, 3) unit first axes a_i of the cardans."""
        return np.array([leg.cardan_axis for leg in self.legs], dtype=float)

    @cached_property
    def beta_axes(self) -> np.ndarray:
        """(n, 3) unit axes s_i with sin(beta_i) = s_i . u_i / l_i (equation 1)."""
        return np.array([leg.beta_axis for leg in self.legs], dtype=float)

    @cached_property
    def inward_directions(self) -> np.ndarray:
        """(n, 3) horizontal unit vectors from B_i toward the base centre."""
        return -np.array([leg.radial_direction for leg in self.legs], dtype=float)

    @cached_property
    def cylinder_section(self) -> Section:
        do, t = self.cylinder.outer_diameter_m, self.cylinder.wall_thickness_m
        di = do - 2 * t
        i = math.pi / 64 * (do**4 - di**4)
        return Section(area_m2=math.pi / 4 * (do**2 - di**2), second_moment_m4=i, polar_moment_m4=2 * i)

    @cached_property
    def stem_section(self) -> Section:
        d = self.stem.diameter_m
        i = math.pi / 64 * d**4
        return Section(area_m2=math.pi / 4 * d**2, second_moment_m4=i, polar_moment_m4=2 * i)

    def axial_compliance_m_per_n(self, leg_length_m: np.ndarray | float) -> np.ndarray:
        """Series axial compliance of a leg of length l: actuator (:meth:`drive_stiffness_n_per_m`) + cylinder
        + stem, m/N."""
        e = self.material.youngs_modulus_pa
        lc = self.cylinder.length_m
        drive = 1.0 / self.drive_stiffness_n_per_m(leg_length_m)
        return (drive + lc / (e * self.cylinder_section.area_m2)
                + (np.asarray(leg_length_m) - lc) / (e * self.stem_section.area_m2))

    def sensed_axial_compliance_m_per_n(self, leg_length_m: np.ndarray | float) -> np.ndarray:
        """The part of :meth:`axial_compliance_m_per_n` between the drive's position sensor and the leg's cardans,
        m/N: all of it, less the drive's own where the sensor reads past it (:attr:`sensed_view`'s)."""
        return self.sensed_view.axial_compliance_m_per_n(leg_length_m)

    @cached_property
    def sensed_view(self) -> Machine:
        """The machine as its drives' position sensors see it: itself, or, where a sensor reads past the drive's own
        stiffness (``DriveTable.sensed_past_stiffness``: the hydraulic cylinder's piston sensor, the oil column
        inside its position loop), a copy with that stiffness rigid (``DriveTable.rigid_overrides``). What a
        position loop closed on the sensors leaves of the machine's compliance: the controller's deflection
        compensation, the rigid model's hidden deflection and clearance, the press monitor's deflection."""
        table = self.actuator.table
        if not table.sensed_past_stiffness:
            return self
        return self.with_overrides(table.rigid_overrides(), f"{self.source} (as its position sensors see it)")

    def drive_stiffness_n_per_m(self, leg_length_m: np.ndarray | float) -> np.ndarray:
        """The drive's own axial stiffness at leg length l (m), N/m: its table's
        :meth:`DriveTable.axial_stiffness_n_per_m` (:mod:`pressfit.description.drive_stiffness`):
        ``axial_stiffness_n_per_m`` (force kind), the ball screw E A / L_free(l) in series with nut and bearing
        (electric), the oil column beta A^2 (1/V_a + 1/V_b) at the piston position of l (hydraulic), the mount
        (linear motor)."""
        return self.actuator.table.axial_stiffness_n_per_m(self, leg_length_m)

    def piston_position_m(self, leg_length_m: np.ndarray | float) -> np.ndarray:
        """Hydraulic piston position x (m from the base-side end of the stroke) at leg length l: the leg travel
        centred in the stroke, x = l - l_min + (s - (l_max - l_min)) / 2."""
        lim, stroke = self.limits, self.actuator.hydraulic.stroke_m
        margin = (stroke - (lim.leg_length_max_m - lim.leg_length_min_m)) / 2.0
        return np.asarray(leg_length_m, dtype=float) - lim.leg_length_min_m + margin

    @cached_property
    def screw_inertia_kg_m2(self) -> float:
        """The electric drive's ball screw inertia about its axis, kg m^2 (:meth:`ElectricDrive.screw_inertia`)."""
        return self.actuator.electric.screw_inertia(self)

    @cached_property
    def drive_reflected_mass_kg(self) -> float:
        """Inertia reflected along the leg, kg (:meth:`DriveTable.reflected_mass_kg`): (J_rotor + J_screw)
        (2 pi / lead)^2 for an electric drive, the forcer's mass for a linear motor, 0 otherwise (a hydraulic
        drive's piston and rod are translating masses: ``mass.actuator_moving_mass_kg``)."""
        return self.actuator.table.reflected_mass_kg(self)

    @cached_property
    def cylinder_tube_mass_kg(self) -> float:
        """Mass of one cylinder tube (without the actuator housing), kg."""
        return self.mass.density_kg_per_m3 * self.cylinder_section.area_m2 * self.cylinder.length_m

    @cached_property
    def stem_mass_kg(self) -> float:
        """Mass of one stem, a rod of fixed length: rho pi d^2 / 4 L_rod, kg (the same at every pose)."""
        return self.mass.density_kg_per_m3 * self.stem_section.area_m2 * self.stem.length_m

    def stem_centre_of_mass_m(self, leg_length_m: np.ndarray | float) -> np.ndarray:
        """Distance (m) from the base cardan, along the leg, of the stem's centre of mass at leg length l: the rod
        spans [l - L_rod, l] (its outer end at the plate cardan), so its centre l - L_rod / 2 moves with the
        extension."""
        return np.asarray(leg_length_m, dtype=float) - self.stem.length_m / 2.0

    def with_overrides(self, overrides: dict[str, Any], source: str = "<overrides>") -> Machine:
        """A copy with nested keys replaced (e.g. ``{"actuator": {"axial_stiffness_n_per_m": 1e8}}``)."""
        data = _merge(self.model_dump(exclude={"source"}), overrides)
        return _validate(data, source)


def _merge(base: dict[str, Any], new: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for k, v in new.items():
        out[k] = _merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def _validate(data: dict[str, Any], source: str) -> Machine:
    try:
        machine = Machine.model_validate({**data, "source": source})
    except ValidationError as exc:
        raise validation_error(source, exc) from None
    require_rod_in_cylinder(machine, source)
    return machine


def require_rod_in_cylinder(machine: Machine, source: str) -> None:
    """Refuse a stem rod no longer than the longest exposed stem the limits allow (l_max - L_c, m): at full
    extension no rod would be left in the cylinder. ModelFileError naming the file, ``stem.length_m`` and the
    limit."""
    longest = machine.limits.leg_length_max_m - machine.cylinder.length_m
    if not machine.stem.length_m > longest:
        raise ModelFileError(source or "<machine>", "stem.length_m",
                             f"the stem rod must be longer than the longest exposed stem, "
                             f"limits.leg_length_max_m - cylinder.length_m = {longest:.6g} m (the actuator's full "
                             f"stroke must leave rod in the cylinder), got "
                             f"{machine.stem.length_m:.6g} m")


def validation_error(path: Path | str, exc: ValidationError) -> ModelFileError:
    """Turn pydantic's first error into a :class:`ModelFileError` naming the key and expectation."""
    err = exc.errors()[0]
    key = ".".join(str(p) for p in err["loc"]) or "<top level>"
    got = err.get("input")
    expected = err["msg"] if err["type"] != "extra_forbidden" else "unknown key (not part of the schema)"
    if err["type"] != "missing" and not isinstance(got, dict):
        expected += f" (got {got!r})"
    return ModelFileError(path, key, expected)


MAX_INPUT_BYTES = 10_000_000  # a machine or case file is a few kB; anything larger is not one


CASE_TABLES = ("poses", "loads", "cycle", "simulation")  # a case file's tables (a machine file has none of them)


def file_kind(data: dict[str, Any]) -> str | None:
    """What a parsed TOML file is: "machine" (a UPU machine's [geometry] or a gantry's ``kind = "gantry"``),
    "case" (any of ``CASE_TABLES``), or None (neither: left to the schema's error)."""
    if "geometry" in data or data.get("kind") == "gantry":
        return "machine"
    return "case" if any(k in data for k in CASE_TABLES) else None


def refuse_wrong_kind(path: Path | str, data: dict[str, Any], expected: str) -> None:
    """:class:`WrongFileKindError` when ``data`` (parsed from ``path``) is a file of another kind than
    ``expected`` ("machine" or "case")."""
    kind = file_kind(data)
    if kind is not None and kind != expected:
        raise WrongFileKindError(path, kind, expected)


def read_toml(path: Path | str) -> dict[str, Any]:
    """Parse a TOML file; a missing, special (FIFO, device), oversized or malformed file becomes a
    :class:`ModelFileError` (checked with ``stat`` before opening, so nothing blocks or reads forever)."""
    path = Path(path)
    try:
        st = path.stat()
        if not stat.S_ISREG(st.st_mode):
            raise ModelFileError(path, "<file>", "a regular file (not a directory, FIFO or device)")
        if st.st_size > MAX_INPUT_BYTES:
            raise ModelFileError(path, "<file>", f"a TOML file of at most {MAX_INPUT_BYTES} bytes "
                                 f"(it has {st.st_size})")
        with path.open("rb") as f:
            return tomllib.loads(f.read(MAX_INPUT_BYTES + 1).decode("utf-8"))
    except FileNotFoundError:
        raise ModelFileError(path, "<file>", "file does not exist") from None
    except tomllib.TOMLDecodeError as exc:
        raise ModelFileError(path, "<syntax>", f"valid TOML ({exc})") from None
    except UnicodeDecodeError:
        raise ModelFileError(path, "<file>", "a UTF-8 text file") from None
    except (OSError, RecursionError) as exc:
        raise ModelFileError(path, "<file>", f"a readable file ({getattr(exc, 'strerror', None) or exc})") from None


def load_machine(path: Path | str = DEFAULT_MODEL, overrides: dict[str, Any] | None = None) -> Machine:
    """Load and validate a machine description, optionally with nested parameter overrides."""
    data = read_toml(path)
    refuse_wrong_kind(path, data, "machine")
    if overrides:
        data = _merge(data, overrides)
    return _validate(data, str(path))
