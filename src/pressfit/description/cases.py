"""Case files (``cases/**/*.toml``): a machine, poses, loads, preload, clearances and an envelope.

A case is validated strictly into frozen objects; unknown keys, wrong types, NaN and non-physical
values raise :class:`ModelFileError` naming the file, the key and the expectation. All values SI.
The schema is documented with a complete example in README.md ("Case files").
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, ValidationError, model_validator

from pressfit.description.machine import (
    DEFAULT_MODEL,
    MAX_CARDAN_TILT_RAD,
    MAX_LEGS,
    Finite,
    Machine,
    NonNegative,
    Positive,
    StrictModel,
    Vector3,
    load_machine,
    read_toml,
    refuse_wrong_kind,
    validation_error,
)
from pressfit.errors import CasePreloadError, ModelFileError
from pressfit.spatial import cone_directions

MAX_FORCE_N = 1e7  # a press-fit machine load above 10 MN is a typo, not a load case
MAX_POSES = 2_000_000
MAX_SAMPLES, MAX_CHUNK_SIZE = 10**9, 100_000  # [montecarlo] (and --samples, --chunk-size)
MAX_LOAD_TILT_RAD = math.pi / 2  # a load turned beyond 90 degrees off its direction is another load case
MAX_GRID_DESIGNS = 100_000  # [design] search = "grid": grid_points ** parameters designs at most


class Axis(StrictModel):
    """A range of one coordinate: ``count`` points from ``min_m`` to ``max_m`` (m); one point (``count`` = 1)
    needs ``min_m`` = ``max_m`` (a range with one point would silently be its ``min_m``)."""

    min_m: Finite
    max_m: Finite
    count: Annotated[int, Field(ge=1, le=2000)]

    @model_validator(mode="after")
    def _order(self) -> Axis:
        if self.count == 1 and self.max_m > self.min_m:
            raise ValueError(f"count = 1 places one point, but min_m = {self.min_m:g} m < max_m = {self.max_m:g} m: "
                             "give count >= 2 for a range or min_m = max_m for one point")
        if self.max_m < self.min_m or (self.count > 1 and self.max_m == self.min_m):
            raise ValueError("max_m must be larger than min_m (or count = 1 with min_m = max_m)")
        return self

    def values(self) -> np.ndarray:
        return np.linspace(self.min_m, self.max_m, self.count)


class Poses(StrictModel):
    """Plate-centre poses (m): an explicit list and/or a grid ``x`` x ``y`` x ``z``."""

    points_m: list[Vector3] = []
    x: Axis | None = None
    y: Axis | None = None
    z: Axis | None = None

    @model_validator(mode="after")
    def _some(self) -> Poses:
        grid = [self.x, self.y, self.z]
        if any(a is not None for a in grid) and not all(a is not None for a in grid):
            raise ValueError("a grid needs all three axes x, y and z")
        if not self.points_m and self.x is None:
            raise ValueError("give points_m or a grid (x, y, z)")
        if self.x is not None and self.x.count * self.y.count * self.z.count > MAX_POSES:  # type: ignore[union-attr]
            raise ValueError(f"the grid has more than {MAX_POSES} poses")
        return self

    def array(self) -> np.ndarray:
        """All poses, shape (n, 3), m."""
        pts = [np.asarray(self.points_m, dtype=float).reshape(-1, 3)]
        if self.x is not None:
            g = np.meshgrid(self.x.values(), self.y.values(), self.z.values(), indexing="ij")  # type: ignore[union-attr]
            pts.append(np.stack([a.ravel() for a in g], -1))
        return np.concatenate(pts)


class Loads(StrictModel):
    """Dead wrenches at the plate centre, world axes.

    ``force_n``/``moment_nm`` give one wrench. A press load is ``press_force_n`` (N, magnitude; or
    ``press_force_range_n`` = [min, max, count]) along ``direction`` (default +y, the press reaction),
    optionally spread over a cone of half-angle ``cone_half_angle_rad`` sampled by ``cone_directions``.
    """

    force_n: Vector3 | None = None
    moment_nm: Vector3 = [0.0, 0.0, 0.0]
    press_force_n: Annotated[float, Field(ge=0, le=MAX_FORCE_N, allow_inf_nan=False)] | None = None
    direction: Vector3 = [0.0, 1.0, 0.0]
    cone_half_angle_rad: Annotated[float, Field(ge=0, le=math.pi / 2, allow_inf_nan=False)] = 0.0
    cone_directions: Annotated[int, Field(ge=1, le=360)] = 8

    @model_validator(mode="after")
    def _one(self) -> Loads:
        if (self.force_n is None) == (self.press_force_n is None):
            raise ValueError("give exactly one of force_n or press_force_n")
        if self.force_n is not None and max(abs(c) for c in self.force_n) > MAX_FORCE_N:
            raise ValueError(f"force components must be at most {MAX_FORCE_N:g} N")
        if np.linalg.norm(self.direction) < 1e-12:
            raise ValueError("direction must be a non-zero vector")
        return self

    def wrenches(self) -> np.ndarray:
        """All load wrenches (n, 6): force N then moment N m."""
        m = np.asarray(self.moment_nm, dtype=float)
        if self.force_n is not None:
            return np.concatenate([np.asarray(self.force_n, float), m])[None]
        dirs = cone_directions(np.asarray(self.direction, float), self.cone_half_angle_rad, self.cone_directions)
        return np.array([np.concatenate([self.press_force_n * u, m]) for u in dirs])


class Preload(StrictModel):
    """Actuator preload in the preload space (the null space of the static matrix, dimension n - 3 for n legs;
    :mod:`pressfit.mechanics.preload`), applied before the load.

    ``mode = "force"`` (force-controlled drives): ``a4_n`` (N), the actuator forces at no load are a4 v_p.
    ``mode = "length"`` (position-held drives): ``a4_m`` (m), actuator rest-length offsets -a4 v_p.
    A machine with n - 3 != 1 takes the amplitudes as a list, ``amplitudes_n`` (N) or ``amplitudes_m`` (m),
    one per preload basis vector (:func:`pressfit.kinematics.preload_basis`: amplitude k belongs to leg 3 + k);
    a one-entry list is the same as a4 (and is stored as a4). Their count is checked against the machine
    when the preload is applied.
    """

    a4_n: Annotated[float, Field(le=MAX_FORCE_N, ge=-MAX_FORCE_N, allow_inf_nan=False)] = 0.0
    a4_m: Annotated[float, Field(le=0.01, ge=-0.01, allow_inf_nan=False)] | None = None
    amplitudes_n: Annotated[list[Annotated[float, Field(le=MAX_FORCE_N, ge=-MAX_FORCE_N, allow_inf_nan=False)]],
                            Field(min_length=2, max_length=9)] | None = None
    amplitudes_m: Annotated[list[Annotated[float, Field(le=0.01, ge=-0.01, allow_inf_nan=False)]],
                            Field(min_length=2, max_length=9)] | None = None
    mode: Literal["force", "length"] = "force"

    @model_validator(mode="before")
    @classmethod
    def _one_amplitude_is_a4(cls, data: Any) -> Any:
        if isinstance(data, dict):
            data = {k: v for k, v in data.items() if v is not None}  # a dumped model lists absent keys as None
            for unit in ("n", "m"):
                amp = data.get(f"amplitudes_{unit}")
                if isinstance(amp, list) and len(amp) == 1 and f"a4_{unit}" not in data:
                    data[f"a4_{unit}"] = data.pop(f"amplitudes_{unit}")[0]
        return data

    @model_validator(mode="after")
    def _unit_matches_mode(self) -> Preload:
        if (self.amplitudes_n is not None and self.a4_n != 0.0) or (self.amplitudes_m is not None
                                                                     and self.a4_m is not None):
            raise ValueError("give the preload as a4 or as amplitudes, not both")
        length = self.a4_m is not None or self.amplitudes_m is not None
        force = self.a4_n != 0.0 or self.amplitudes_n is not None
        if self.mode == "length" and (not length or force):
            raise ValueError('mode = "length" takes a4_m or amplitudes_m (m), not a4_n')
        if self.mode == "force" and length:
            raise ValueError('mode = "force" takes a4_n or amplitudes_n (N), not a4_m')
        return self

    @property
    def a4(self) -> float:
        """The preload coordinate in the mode's unit (N or m) of a redundancy-1 machine (0 when the preload
        is given as two or more amplitudes: layers that read it support 4-leg machines only)."""
        if self.mode == "length":
            return self.a4_m if self.a4_m is not None else 0.0
        return self.a4_n

    @property
    def amplitudes(self) -> tuple[float, ...]:
        """Every preload amplitude in the mode's unit (N or m): (a4,) or the given list."""
        amp = self.amplitudes_m if self.mode == "length" else self.amplitudes_n
        return tuple(amp) if amp is not None else (self.a4,)


class Solver(StrictModel):
    linear: bool = False
    refine_worst: Annotated[int, Field(ge=0, le=100)] = 3


class Envelope(StrictModel):
    """Limits a case asserts (all optional; SI). Each becomes one line of the check report."""

    max_tension_n: NonNegative | None = None
    max_compression_n: NonNegative | None = None
    max_shear_n: NonNegative | None = None
    max_bending_nm: NonNegative | None = None
    max_torsion_nm: NonNegative | None = None
    max_actuator_force_n: NonNegative | None = None
    max_plate_deflection_m: NonNegative | None = None
    max_plate_tilt_rad: NonNegative | None = None
    min_interference_distance_m: Finite | None = None
    min_leg_length_margin_m: NonNegative | None = None
    min_angle_margin_rad: NonNegative | None = None
    min_buckling_safety_factor: Positive | None = None


class Reference(StrictModel):
    """A published table to compare with: values as printed, in the publication's leg order."""

    source: str
    leg_order: Annotated[list[Annotated[int, Field(ge=1, le=MAX_LEGS)]], Field(min_length=3, max_length=MAX_LEGS)]
    axial_sign: Literal[1, -1] = 1
    values: dict[str, Annotated[list[Finite], Field(min_length=3, max_length=MAX_LEGS)]]

    @model_validator(mode="after")
    def _one_value_per_leg(self) -> Reference:
        if sorted(self.leg_order) != list(range(1, len(self.leg_order) + 1)):
            raise ValueError(f"leg_order must list each leg 1..{len(self.leg_order)} once")
        for key, v in self.values.items():
            if len(v) != len(self.leg_order):
                raise ValueError(f"values.{key} has {len(v)} entries for {len(self.leg_order)} legs")
        return self
    note: str = ""


class ClearanceSpec(StrictModel):
    """Axial plays of the 2 n cardans (:mod:`pressfit.clearance`): ``gaps_m`` (2 n values for n legs, checked
    against the machine: leg 1 base, leg 1 plate, leg 2 base, ...) or ``random_m`` = [low, high] with ``seed``;
    default: the machine's uniform clearance. ``geometry`` ("axial": +-g along the leg; "box": +-g on the joint's
    three translations in the cardan's axes; "sphere": radius g) defaults to the machine's
    ``[joints] cardan_clearance_geometry``.
    Contact stiffness N/m and smoothing width m default to the machine's and 1e-9 m."""

    gaps_m: Annotated[list[Annotated[float, Field(ge=0, le=1e-2, allow_inf_nan=False)]],
                      Field(min_length=6, max_length=2 * MAX_LEGS)] | None = None
    random_m: Annotated[list[Annotated[float, Field(ge=0, le=1e-2, allow_inf_nan=False)]],
                        Field(min_length=2, max_length=2)] | None = None
    seed: int = 0
    geometry: Literal["axial", "box", "sphere"] | None = None
    contact_stiffness_n_per_m: Positive | None = None
    smoothing_m: Annotated[float, Field(gt=0, le=1e-5, allow_inf_nan=False)] = 1e-9

    @model_validator(mode="after")
    def _one(self) -> ClearanceSpec:
        if self.gaps_m is not None and self.random_m is not None:
            raise ValueError("give at most one of gaps_m and random_m")
        if self.random_m is not None and self.random_m[0] > self.random_m[1]:
            raise ValueError("random_m must be [low, high] with low <= high")
        return self


class Study(StrictModel):
    """A preload study (``pressfit study preload CASE.toml``): the first pose of [poses], the load
    ``[loads] press_force_n`` (N, the largest load) along ``[loads] direction``, ``[preload] mode``.
    ``clearances_m``: uniform plays to compare (default: the one of [clearance] or the machine)."""

    kind: Literal["preload"] = "preload"
    clearances_m: list[Annotated[float, Field(ge=0, le=1e-2, allow_inf_nan=False)]] = []
    preloads: Annotated[list[Annotated[float, Field(ge=-MAX_FORCE_N, le=MAX_FORCE_N, allow_inf_nan=False)]],
                        Field(min_length=1, max_length=1000)]  # N (force mode) or m (length mode)
    steps: Annotated[int, Field(ge=2, le=10000)] = 50


class Distribution(StrictModel):
    """One random input (SI, the unit of the input it drives): ``normal`` (``mean``, ``std``), ``uniform``
    (``low``, ``high``) or ``truncnormal`` (a normal ``mean``, ``std`` cut to [``low``, ``high``])."""

    distribution: Literal["normal", "uniform", "truncnormal"]
    mean: Finite = 0.0
    std: NonNegative | None = None
    low: Finite | None = None
    high: Finite | None = None

    @model_validator(mode="after")
    def _parameters(self) -> Distribution:
        needs_std, needs_bounds = self.distribution != "uniform", self.distribution != "normal"
        if needs_std != (self.std is not None):
            raise ValueError(f"{self.distribution} {'needs' if needs_std else 'takes no'} std")
        if needs_bounds != (self.low is not None and self.high is not None) or (
                not needs_bounds and (self.low is not None or self.high is not None)):
            raise ValueError(f"{self.distribution} {'needs' if needs_bounds else 'takes no'} low and high")
        if needs_bounds and not self.low < self.high:  # type: ignore[operator]
            raise ValueError("low must be smaller than high")
        if self.distribution == "truncnormal" and not (self.std > 0 and self.low <= self.mean + 8 * self.std  # type: ignore
                                                       and self.high >= self.mean - 8 * self.std):  # type: ignore
            raise ValueError("truncnormal needs std > 0 and [low, high] within 8 std of the mean")
        return self

    def draw(self, rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
        """Values of this distribution of the given shape from ``rng`` (the one sampler of a Distribution:
        the Monte Carlo studies draw through it)."""
        from scipy import special

        if self.distribution == "normal":
            return self.mean + self.std * rng.standard_normal(shape)  # type: ignore[operator]
        if self.distribution == "uniform":
            return rng.uniform(self.low, self.high, shape)  # type: ignore[arg-type]
        lo, hi = special.ndtr((self.low - self.mean) / self.std), special.ndtr((self.high - self.mean) / self.std)  # type: ignore
        return np.clip(self.mean + self.std * special.ndtri(lo + (hi - lo) * rng.uniform(size=shape)),  # type: ignore
                       self.low, self.high)


class MonteCarloInputs(StrictModel):
    """The random inputs of a Monte Carlo study; each is drawn independently for every leg (and joint, and
    axis) it applies to. Lengths m, angles rad."""

    actuator_length_offset_m: Distribution | None = None  # per leg: held length minus commanded length
    base_point_error_m: Distribution | None = None  # per leg and world axis: base cardan centre error
    plate_point_error_m: Distribution | None = None  # per leg and world axis: plate cardan centre error
    load_tilt_rad: Distribution | None = None  # angle of the load force off its nominal direction (azimuth uniform)
    cardan_clearance_m: Distribution | None = None  # per cardan (2 n): axial play, m (values must stay in [0, 1e-2])
    # per cardan (2 n) and axis of its leg reference frame (x = +-a_i, y down, z inward): misalignment rotation, rad
    cardan_misalignment_rad: Distribution | None = None

    @model_validator(mode="after")
    def _some(self) -> MonteCarloInputs:
        if all(getattr(self, k) is None for k in type(self).model_fields):
            raise ValueError("name at least one random input")
        c = self.cardan_clearance_m
        if c is not None and (c.distribution == "normal" or c.low < 0 or c.high > 1e-2):  # type: ignore[operator]
            raise ValueError("cardan_clearance_m must be uniform or truncnormal within [0, 0.01] m")
        t = self.load_tilt_rad
        if t is not None and (t.distribution == "normal" or t.low < -MAX_LOAD_TILT_RAD  # type: ignore[operator]
                              or t.high > MAX_LOAD_TILT_RAD):  # type: ignore[operator]
            raise ValueError(f"load_tilt_rad must be uniform or truncnormal within [-{MAX_LOAD_TILT_RAD:.6g}, "
                             f"{MAX_LOAD_TILT_RAD:.6g}] rad (pi/2: a load turned further is another load case)")
        t, bound = self.cardan_misalignment_rad, MAX_CARDAN_TILT_RAD / math.sqrt(3.0)
        if t is not None and (t.distribution == "normal" or t.low < -bound or t.high > bound):  # type: ignore[operator]
            raise ValueError(f"cardan_misalignment_rad must be uniform or truncnormal within [-{bound:.6g}, "
                             f"{bound:.6g}] rad per axis (a cardan's tilt is at most {MAX_CARDAN_TILT_RAD} rad)")
        return self


class MonteCarlo(StrictModel):
    """``pressfit study montecarlo``: ``samples`` draws of ``inputs``, seeded by ``seed``, run in chunks of
    ``chunk_size`` samples; every sample solves every pose and load of the case."""

    samples: Annotated[int, Field(ge=1, le=MAX_SAMPLES)] = 1000
    seed: Annotated[int, Field(ge=0)] = 0
    chunk_size: Annotated[int, Field(ge=1, le=MAX_CHUNK_SIZE)] = 50
    inputs: MonteCarloInputs


Range = Annotated[list[Positive], Field(min_length=2, max_length=2)]
DESIGN_PARAMETERS = {  # [design.parameters] key -> the machine file key it sets (SI)
    "base_half_side_m": "geometry.base_half_side_m", "plate_half_side_m": "geometry.plate_half_side_m",
    "cylinder_outer_diameter_m": "cylinder.outer_diameter_m", "cylinder_wall_thickness_m": "cylinder.wall_thickness_m",
    "stem_diameter_m": "stem.diameter_m", "actuator_axial_stiffness_n_per_m": "actuator.axial_stiffness_n_per_m"}
DESIGN_OBJECTIVES = ("peak_torsion_nm", "peak_bending_nm", "peak_axial_force_n", "moving_mass_kg",
                     "max_vertical_compliance_m_per_n")  # all minimised


class DesignParameters(StrictModel):
    """Design variables, each a range [min, max] in the unit of its name (DESIGN_PARAMETERS: the machine key)."""

    base_half_side_m: Range | None = None
    plate_half_side_m: Range | None = None
    cylinder_outer_diameter_m: Range | None = None
    cylinder_wall_thickness_m: Range | None = None
    stem_diameter_m: Range | None = None
    actuator_axial_stiffness_n_per_m: Range | None = None

    @model_validator(mode="after")
    def _ranges(self) -> DesignParameters:
        given = self.ranges()
        if not given:
            raise ValueError("name at least one design parameter range")
        for k, (lo, hi) in given.items():
            if not lo < hi:
                raise ValueError(f"{k} must be [min, max] with min < max")
        return self

    def ranges(self) -> dict[str, tuple[float, float]]:
        return {k: tuple(v) for k in DESIGN_PARAMETERS if (v := getattr(self, k)) is not None}  # type: ignore[misc]


class DesignConstraints(StrictModel):
    """Limits every accepted design meets (SI), over the workspace of the design study."""

    max_peak_torsion_nm: Positive | None = None
    max_peak_bending_nm: Positive | None = None
    max_peak_axial_force_n: Positive | None = None
    max_moving_mass_kg: Positive | None = None
    min_vertical_stiffness_n_per_m: Positive | None = None  # 1 / vertical compliance at every workspace pose


class Design(StrictModel):
    """``pressfit study design``: search the ``parameters`` ranges for designs that minimise ``objectives``
    (DESIGN_OBJECTIVES) under ``constraints`` and the ``[loads]``, over the required square at
    ``height_levels`` heights spanning ``heights_m`` (m), which every design must reach entirely (the
    height-range constraint). ``search = "nsga2"``: Optuna's NSGA-II, ``trials`` designs in generations of
    ``population``, seeded by ``seed``; ``"grid"``: ``grid_points`` values per parameter. ``best``: machine
    files written from the Pareto front; ``grid_xz``: workspace grid points per side."""

    search: Literal["nsga2", "grid"] = "nsga2"
    trials: Annotated[int, Field(ge=1, le=1_000_000)] = 64
    population: Annotated[int, Field(ge=2, le=10_000)] = 16
    grid_points: Annotated[int, Field(ge=2, le=1000)] = 5
    seed: Annotated[int, Field(ge=0)] = 0
    objectives: Annotated[list[Literal[DESIGN_OBJECTIVES]],  # type: ignore[valid-type]
                          Field(min_length=1, max_length=5)]
    heights_m: Range
    height_levels: Annotated[int, Field(ge=1, le=100)] = 3
    grid_xz: Annotated[int, Field(ge=2, le=201)] = 11
    best: Annotated[int, Field(ge=1, le=100)] = 3
    parameters: DesignParameters
    constraints: DesignConstraints = DesignConstraints()

    @model_validator(mode="after")
    def _checks(self) -> Design:
        if len(set(self.objectives)) != len(self.objectives):
            raise ValueError("objectives must be distinct")
        if self.heights_m[0] > self.heights_m[1]:
            raise ValueError("heights_m must be [low, high] with low <= high")
        n = len(self.parameters.ranges())
        if self.search == "grid" and (total := self.grid_points**n) > MAX_GRID_DESIGNS:
            raise ValueError(f"grid_points = {self.grid_points} over {n} parameters is {self.grid_points}^{n} = "
                             f"{total if total < 10**12 else f'{float(total):.3g}'} designs, above the cap of "
                             f"{MAX_GRID_DESIGNS} "
                             "designs of a grid search; lower grid_points or use search = \"nsga2\"")
        return self


# keys of each contact law in [simulation.contact] (and [cycle.contact], and per pin in [[simulation.contact.pins]]):
# (required, optional); the keys every law takes are CONTACT_COMMON_KEYS. docs/joint.md gives the equations.
CONTACT_LAW_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "elastic": ((), ("stiffness_n_per_m",)),
    "press_fit": ((), ("stiffness_n_per_m", "fit", "fit_stiffness_n_per_m", "fit_force_n", "fit_depth_m")),
    "solid_pin": (("pin_diameter_m", "hole_diameter_m", "pin_youngs_modulus_pa", "pin_poisson_ratio",
                   "board_youngs_modulus_pa", "board_poisson_ratio", "friction_coefficient", "engaged_length_m"),
                  ("board_outer_diameter_m", "chamfer_length_m", "board_yield_strength_pa")),
    "compliant_pin": (("hole_diameter_m", "zone_width_m", "radial_stiffness_n_per_m", "radial_yield_force_n",
                       "post_yield_stiffness_n_per_m", "zone_length_m", "lead_in_length_m",
                       "friction_coefficient"), ()),
    "tabulated": (("table_path",), ()),
}
CONTACT_COMMON_KEYS = ("seat_depth_m", "seat_stiffness_n_per_m")  # the shoulder (seating), with any law
MAX_CONTACT_PINS = 200  # a component of more pins in one press stroke is a typo
PoissonRatio = Annotated[float, Field(ge=0.0, lt=0.5, allow_inf_nan=False)]
Friction = Annotated[float, Field(ge=0.0, le=2.0, allow_inf_nan=False)]


class LawKeys(StrictModel):
    """The keys of the pin laws (``CONTACT_LAW_KEYS``) and of the seating, all optional here; which are
    required, allowed or refused depends on ``law`` (:func:`check_law_keys`). SI units: m, Pa, N/m, N;
    ``table_path``: a CSV file (header ``depth_m,force_n``), relative to the case file."""

    pin_diameter_m: Positive | None = None
    hole_diameter_m: Positive | None = None
    pin_youngs_modulus_pa: Positive | None = None
    pin_poisson_ratio: PoissonRatio | None = None
    board_youngs_modulus_pa: Positive | None = None
    board_poisson_ratio: PoissonRatio | None = None
    board_outer_diameter_m: Positive | None = None
    friction_coefficient: Friction | None = None
    engaged_length_m: Positive | None = None
    chamfer_length_m: NonNegative | None = None
    board_yield_strength_pa: Positive | None = None
    zone_width_m: Positive | None = None
    radial_stiffness_n_per_m: Positive | None = None
    radial_yield_force_n: Positive | None = None
    post_yield_stiffness_n_per_m: NonNegative | None = None
    zone_length_m: Positive | None = None
    lead_in_length_m: Positive | None = None
    table_path: str | None = None
    seat_depth_m: Positive | None = None
    seat_stiffness_n_per_m: Positive | None = None


LEGACY_LAW_KEYS = ("stiffness_n_per_m", "fit", "fit_stiffness_n_per_m", "fit_force_n", "fit_depth_m")
LAW_KEY_NAMES = LEGACY_LAW_KEYS + tuple(LawKeys.model_fields)


def check_law_keys(law: str, given: dict[str, Any], where: str, *, complete: bool) -> None:
    """Refuse a key of another law than ``law`` in ``given`` (the keys set, with their values), naming the key
    and ``where``; with ``complete``, also a missing required key, and the pair rules (seating keys together, an
    interference that is positive: pin/zone wider than the hole, hole inside the board's outer diameter)."""
    required, optional = CONTACT_LAW_KEYS[law]
    allowed = set(required) | set(optional) | set(CONTACT_COMMON_KEYS)
    for key, value in given.items():
        if value is not None and key not in allowed:
            owners = [name for name, (r, o) in CONTACT_LAW_KEYS.items() if key in r or key in o]
            raise ValueError(f"{where}{key} is not a key of law = \"{law}\" (it belongs to law = "
                             + " or ".join(f'"{o}"' for o in owners) + ")")
    if not complete:
        return
    for key in required:
        if given.get(key) is None:
            raise ValueError(f"{where}{key} is required with law = \"{law}\"")
    if (given.get("seat_depth_m") is None) != (given.get("seat_stiffness_n_per_m") is None):
        raise ValueError(f"{where}seat_depth_m and seat_stiffness_n_per_m go together (the shoulder's depth and "
                         "stiffness): give both or neither")
    hole = given.get("hole_diameter_m")
    for key in ("pin_diameter_m", "zone_width_m"):
        if key in required and not given[key] > hole:
            raise ValueError(f"{where}{key} = {given[key]:g} m must be larger than hole_diameter_m = {hole:g} m "
                             "(an interference fit needs an interference)")
    outer = given.get("board_outer_diameter_m")
    if law == "solid_pin" and outer is not None and not outer > hole:
        raise ValueError(f"{where}board_outer_diameter_m = {outer:g} m must be larger than hole_diameter_m = "
                         f"{hole:g} m")
    if law == "compliant_pin":
        taper = 0.5 * (given["zone_width_m"] - hole) / given["lead_in_length_m"]
        if given["friction_coefficient"] * taper >= 1.0:
            raise ValueError(f"{where}friction_coefficient x the lead-in's taper {taper:.3g} >= 1: the zone "
                             "self-locks in the lead-in; lengthen lead_in_length_m")


class ContactPin(LawKeys):
    """One pin of the component in ``[[simulation.contact.pins]]``: its ``offset_m`` = [dx, dz] (m) from the tool
    axis in the board plane, and overrides of the contact law's keys (``CONTACT_LAW_KEYS`` of the contact's law;
    the others are refused)."""

    stiffness_n_per_m: Positive | None = None
    fit_stiffness_n_per_m: NonNegative | None = None
    fit_force_n: NonNegative | None = None
    fit_depth_m: Positive | None = None
    offset_m: Annotated[list[Finite], Field(min_length=2, max_length=2)] = [0.0, 0.0]


class ResolvedContactPin(StrictModel):
    """A pin with its law's keys resolved (its own, else the contact's): ``offset_m`` = [dx, dz] (m), ``law``,
    ``keys`` (the law's keys set, SI) and ``source`` (where it is defined)."""

    offset_m: tuple[float, float]
    law: str
    keys: dict[str, Any]
    source: str


class ContactLaw(LawKeys):
    """The pin-board contact law of the insertion (:mod:`pressfit.dynamics.contact`; the laws:
    :mod:`pressfit.mechanics.contact_laws`, equations in docs/joint.md), for an interference (depth) d > 0 of the
    tool tip below the board face: ``law = "elastic"``: F = k d + b d_dot (paper section 4.2: force proportional
    to the interference); ``"press_fit"`` adds f_fit(d): ``fit = "linear"`` (``fit_stiffness_n_per_m`` d) or
    ``"saturating"`` (``fit_force_n`` tanh(d / ``fit_depth_m``)); ``"solid_pin"`` (a cylindrical interference fit,
    Lame), ``"compliant_pin"`` (an eye-of-needle zone), ``"tabulated"`` (a CSV of force against depth), each with
    its keys (``CONTACT_LAW_KEYS``; a key of another law is refused), and on any law the shoulder
    (``seat_depth_m``, ``seat_stiffness_n_per_m``). ``damping_n_s_per_m``: b d_dot on every law. Defaults: an
    estimate of a compliant pin-board stack, 30 N at 0.6 mm, no damping."""

    stiffness_n_per_m: Positive = 5.0e4
    damping_n_s_per_m: NonNegative = 0.0
    law: Literal[tuple(CONTACT_LAW_KEYS)] = "elastic"  # type: ignore[valid-type]  (the laws' keys declare them)
    fit: Literal["linear", "saturating"] = "linear"
    fit_stiffness_n_per_m: NonNegative = 0.0
    fit_force_n: NonNegative = 0.0
    fit_depth_m: Positive = 1e-3

    def law_keys(self) -> dict[str, Any]:
        """The law's keys as given (the legacy keys of ``elastic`` / ``press_fit`` with their defaults)."""
        required, optional = CONTACT_LAW_KEYS[self.law]
        legacy = {k: getattr(self, k) for k in LEGACY_LAW_KEYS if k in required + optional}
        return {**legacy, **{k: getattr(self, k) for k in LawKeys.model_fields if getattr(self, k) is not None}}

    @model_validator(mode="after")
    def _law_keys(self) -> ContactLaw:
        given = {k: getattr(self, k) for k in LawKeys.model_fields}
        given |= {k: getattr(self, k) for k in LEGACY_LAW_KEYS if k in self.model_fields_set}
        check_law_keys(self.law, given, "", complete=True)
        if self.table_path is not None:
            read_force_table(self.table_path)  # refused here, naming the file, when it is not a table
        return self


def read_force_table(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """The tabulated law's CSV (a header with ``depth_m`` and ``force_n`` columns, comma-separated): depths
    (strictly increasing, >= 0, m) and forces (>= 0, N), at least 2 rows; ValueError naming the file, the row and
    the column otherwise."""
    path = Path(path)
    try:
        lines = [line for line in path.read_text().splitlines() if line.strip()]
    except OSError as exc:
        raise ValueError(f"table_path: cannot read {path}: {exc.strerror}") from None
    if not lines:
        raise ValueError(f"table_path: {path} is empty")
    header = [h.strip() for h in lines[0].split(",")]
    if "depth_m" not in header or "force_n" not in header:
        raise ValueError(f"table_path: {path}: the header needs the columns depth_m and force_n, got {header}")
    i, j = header.index("depth_m"), header.index("force_n")
    depth, force = [], []
    for row, line in enumerate(lines[1:], start=2):
        cells = line.split(",")
        for name, k, out in (("depth_m", i, depth), ("force_n", j, force)):
            try:
                value = float(cells[k])
            except (IndexError, ValueError):
                raise ValueError(f"table_path: {path} row {row} column {name}: not a number") from None
            if not math.isfinite(value) or value < 0.0:
                raise ValueError(f"table_path: {path} row {row} column {name}: {value!r} is not a finite number >= 0")
            out.append(value)
    d, f = np.array(depth), np.array(force)
    if d.size < 2:
        raise ValueError(f"table_path: {path}: give at least 2 rows, got {d.size}")
    bad = np.flatnonzero(np.diff(d) <= 0.0)
    if bad.size:
        raise ValueError(f"table_path: {path} row {bad[0] + 3} column depth_m: the depths must increase strictly")
    return d, f


class PinFieldLaw(ContactLaw):
    """A contact law with its component's pin field: ``pins``, a component of several pins pressed at once (each at
    its ``offset_m`` = [dx, dz] (m) from the tool axis, with overrides of the law's keys); without it one pin on
    the axis. ``[cycle.contact]`` (every board position presses the component) and the base of :class:`Contact`."""

    pins: Annotated[list[ContactPin], Field(max_length=MAX_CONTACT_PINS)] = []

    @model_validator(mode="after")
    def _pin_keys(self) -> PinFieldLaw:
        base = self.law_keys()
        for k, pin in enumerate(self.pins):
            own = {key: getattr(pin, key) for key in LAW_KEY_NAMES if key in type(pin).model_fields}
            check_law_keys(self.law, own, f"pins[{k}].", complete=False)
            merged = {**base, **{key: v for key, v in own.items() if v is not None}}
            check_law_keys(self.law, merged, f"pins[{k}].", complete=True)
            if pin.table_path is not None:
                read_force_table(pin.table_path)
        return self

    def resolved_pins(self) -> list[ResolvedContactPin]:
        """Every pin of the component with its law's keys resolved (one on the axis without ``pins``)."""
        base = self.law_keys()
        if not self.pins:
            return [ResolvedContactPin(offset_m=(0.0, 0.0), law=self.law, keys=base, source="[simulation.contact]")]
        out = []
        for k, pin in enumerate(self.pins):
            own = {key: getattr(pin, key) for key in LAW_KEY_NAMES
                   if key in type(pin).model_fields and getattr(pin, key) is not None}
            out.append(ResolvedContactPin(offset_m=(float(pin.offset_m[0]), float(pin.offset_m[1])), law=self.law,
                                          keys={**base, **own}, source=f"[simulation.contact] pins[{k}]"))
        return out


class Contact(PinFieldLaw):
    """Tool-board contact of ``[simulation]``: the law (:class:`ContactLaw`) on the board's top face, the plane
    y = ``board_height_m``, with the pin to insert on it at (x, z) = ``pin_position_m`` (the tool axis). ``pins``:
    a component of several pins pressed at once (``[[simulation.contact.pins]]``, :class:`PinFieldLaw`); without
    it one pin on the axis."""

    board_height_m: Positive
    pin_position_m: Annotated[list[Finite], Field(min_length=2, max_length=2)]


class Controller(StrictModel):
    """Figure 12's force-limited position control (:mod:`pressfit.dynamics.control`). PID gains of the
    Cartesian position loop on the plate position estimated from the actuator lengths (N/m, N s/m, N/(m s));
    the insertion force limit (N, paper: 30 N) and the limiter's reference back-off rate per newton over the
    limit (m/(s N)); the gravity feed-forward (weight of the moving parts, Cartesian); ``deflection_compensation``:
    the loop acts on the tool estimated as the pose of the measured lengths plus the structure's predicted static
    deflection under the weight and the measured contact force (the condensed compliance; on a real machine a
    calibrated sag map), which the lengths cannot see (off: the paper's controller). Defaults: a ~5 Hz
    position loop for the ~25 kg moving machine, well below the 40 Hz actuators."""

    kp_n_per_m: Positive = 2.0e4
    kd_n_s_per_m: NonNegative = 1.0e3
    ki_n_per_m_s: NonNegative = 5.0e4
    force_limit_n: Positive = 30.0
    backoff_m_per_s_n: NonNegative = 1.0e-3
    gravity_compensation: bool = True
    deflection_compensation: bool = False
    estimator_iterations: Annotated[int, Field(ge=1, le=20)] = 2


TimeStep = Annotated[float, Field(gt=0, le=2e-3, allow_inf_nan=False)]  # s
# Baumgarte rate omega_b of the loop closures: at least 10 rad/s (a drift correction time 1/omega_b of at
# most 0.1 s, the scale of the scenario's motions; slower lets the closures open, 0.48 mm at 1e-9 rad/s),
# at most 1e4 rad/s (the explicit corrector needs omega_b dt < 0.83, checked against time_step_s before a
# run: dt <= 45 us at the cap). The run also refuses a closure drift over its tolerance (dynamics.insertion).
BaumgarteRate = Annotated[float, Field(ge=10.0, le=1e4, allow_inf_nan=False)]
NOT_OBJECTIVE_LIMITS = ("max_torsion_nm", "max_bending_nm")  # offered by a model with objective leg couples only


class SimulationLimits(StrictModel):
    """Limits ``pressfit check`` asserts on the simulated insertion (all optional; SI), one report line each:
    peak contact force and its overshoot over the insertion limit (N), tool positioning error (the larger of
    the lateral error at the pin and the final 3D error, m), settling time of the contact force (s; a force
    that does not settle fails), peak actuator tension |N| (N), peak per-leg axial force |N| at the plate
    cardans (N), and with ``[simulation] model = "flexible"`` only the peak leg torsion |T| and bending
    |M_b| over the three sections (N m; refused with the rigid-leg model, whose couples are statically
    indeterminate: a minimum-norm split that depends on the frames' handedness). ``limiter``: whether the
    checked run uses the insertion force limiter."""

    limiter: bool = True
    max_contact_force_n: NonNegative | None = None
    max_overshoot_n: NonNegative | None = None
    max_positioning_error_m: NonNegative | None = None
    max_settling_time_s: NonNegative | None = None
    max_actuator_force_n: NonNegative | None = None
    max_axial_force_n: NonNegative | None = None
    max_torsion_nm: NonNegative | None = None
    max_bending_nm: NonNegative | None = None


class Simulation(StrictModel):
    """The insertion scenario of Figures 13-14 (``pressfit simulate``; :mod:`pressfit.dynamics.insertion`).

    The tool tip is the plate centre. The reference moves (minimum-jerk segments) from ``start_m`` to
    ``approach_height_m`` above the pin in ``move_time_s``, down to ``interference_m`` below the board face
    in ``descent_time_s``, holds ``dwell_s``, rises back above the pin in ``descent_time_s``, moves to
    ``end_m`` in ``move_time_s`` and holds ``settle_s``. The commanded preload is ``[preload] a4_n`` (force
    mode). ``clearance``: the cardans' lost motion (``[clearance]`` or the machine's plays) in series at the
    tool. Time step (s) and the loop closures' Baumgarte rate (rad/s) of the multibody model. ``limits``:
    what ``pressfit check`` asserts on the run (:class:`SimulationLimits`). ``model``: ``"flexible"`` (the
    default: the elastic legs in the equations of motion, :mod:`pressfit.dynamics.machine.flexible`, the contact
    on the elastic tool point, no series compliance added) or ``"rigid"`` (the fast rigid-leg model with the
    structure's compliance in series at the tool, quasi-statically): a name of the dynamics models' registry
    (:mod:`pressfit.dynamics.machine.registry`), checked when the scenario is planned."""

    start_m: Vector3
    end_m: Vector3
    approach_height_m: Positive = 0.005
    interference_m: Positive = 0.002
    move_time_s: Positive = 1.0
    descent_time_s: Positive = 1.0
    dwell_s: Positive = 1.0
    settle_s: NonNegative = 0.5
    time_step_s: TimeStep = 5e-4
    baumgarte_rad_per_s: BaumgarteRate = 200.0
    clearance: bool = False
    contact: Contact
    controller: Controller = Controller()
    limits: SimulationLimits = SimulationLimits()
    model: str = "flexible"  # a name of pressfit.dynamics.machine.registry.MODELS, checked by the plan



CURVE_POSE_KEYS = ("pin_x_m", "pin_z_m")  # [curve.tolerances]: the pin's position on the board (the pose)
MAX_CURVE_SAMPLES = 10**6  # [curve] samples and ``pressfit study curve --samples``: 1e6 curves take hours serially
MAX_CURVE_POINTS = 10001


def curve_tolerance_keys(law: str) -> tuple[str, ...]:
    """The keys ``[curve.tolerances]`` may vary for a contact ``law``: its numeric keys (``CONTACT_LAW_KEYS``), the
    shoulder's (``CONTACT_COMMON_KEYS``) and the pin's position on the board (``CURVE_POSE_KEYS``)."""
    required, optional = CONTACT_LAW_KEYS[law]
    numeric = tuple(k for k in required + optional if k not in ("table_path", "fit"))
    return numeric + CONTACT_COMMON_KEYS + CURVE_POSE_KEYS


class CurveStudy(StrictModel):
    """``pressfit study curve`` (:mod:`pressfit.studies.curve_study`): ``samples`` predicted press curves, seeded by
    ``seed``, each of ``points`` depth samples; ``tolerances``: key -> Distribution of the DEVIATION added to the
    case's value (so ``mean`` defaults to 0; SI, the key's unit), the keys from :func:`curve_tolerance_keys` of
    the ``[simulation.contact]`` law (a law key moves every pin's value by the same draw: one component's lot;
    ``pin_x_m`` / ``pin_z_m`` move the pin position, so the pose and the machine's compliance there)."""

    samples: Annotated[int, Field(ge=1, le=MAX_CURVE_SAMPLES)] = 1000
    seed: Annotated[int, Field(ge=0)] = 0
    points: Annotated[int, Field(ge=2, le=MAX_CURVE_POINTS)] = 401
    tolerances: dict[str, Distribution] = {}


MAX_PINS = 1000  # [cycle]: a board of more pins is refused (the run is also capped at MAX_STEPS time steps)
PIN_KEYS = ("force_limit_n", "approach_height_m", "interference_m", "dwell_s", "max_overshoot_n",
            "max_alignment_error_m")  # per pin, defaulting to [cycle]'s (force_limit_n: [cycle.controller]'s)


class Pin(StrictModel):
    """One pin of a board at (``x_m``, ``z_m``) on the board face (m), with optional overrides of the board's
    defaults (``PIN_KEYS``; meanings as in :class:`Cycle`)."""

    x_m: Finite
    z_m: Finite
    force_limit_n: Positive | None = None
    approach_height_m: Positive | None = None
    interference_m: Positive | None = None
    dwell_s: Positive | None = None
    max_overshoot_n: NonNegative | None = None
    max_alignment_error_m: NonNegative | None = None


class PinGrid(StrictModel):
    """A rectangular grid of pins: ``x`` and ``z`` ranges (m) with their counts."""

    x: Axis
    z: Axis


class MotionLimits(StrictModel):
    """The tool's Cartesian limits on a straight move: speed (m/s), acceleration (m/s^2), jerk (m/s^3), and the
    profile of each move: ``"s_curve"`` (the minimum-time jerk-limited move) or ``"quintic"`` (the minimum-jerk
    move of ``[simulation]``, in the least time the three limits allow)."""

    speed_m_per_s: Annotated[float, Field(gt=0, le=10.0, allow_inf_nan=False)]
    acceleration_m_per_s2: Annotated[float, Field(gt=0, le=1000.0, allow_inf_nan=False)]
    jerk_m_per_s3: Annotated[float, Field(gt=0, le=1e6, allow_inf_nan=False)]
    profile: Literal["s_curve", "quintic"] = "s_curve"


class ResolvedPin(StrictModel):
    """A pin with every value resolved (its own, else the board's): ``index`` is its place in the cycle (from 1)."""

    index: int
    x_m: float
    z_m: float
    force_limit_n: float
    approach_height_m: float
    interference_m: float
    dwell_s: float
    max_overshoot_n: float | None
    max_alignment_error_m: float | None
    source: str  # where it is defined: "[cycle] pins[k]" or "[cycle.grid]"


class CycleLimits(StrictModel):
    """Limits ``pressfit check`` asserts on the simulated board (all optional; SI), one report line each: the
    cycle time (s), every pin's overshoot over its insertion limit (N) and lateral alignment error at first
    contact (m; a pin never touched fails), the worst pin named, the worst drive's RMS and peak force over the
    cycle (N), the energy per cycle: the drives' positive (motoring) mechanical energy summed over the
    drives, regeneration not credited (J), and ``max_pin_depth_spread_m``: at the worst board position, the
    largest spread of the depths of the component's pins (``[[cycle.contact.pins]]``, tilted by the machine's
    compliance there) over its stroke (m; the uneven seating of a multi-pin component)."""

    max_cycle_time_s: NonNegative | None = None
    max_overshoot_n: NonNegative | None = None
    max_alignment_error_m: NonNegative | None = None
    max_pin_depth_spread_m: NonNegative | None = None
    max_rms_drive_force_n: NonNegative | None = None
    max_peak_drive_force_n: NonNegative | None = None
    max_energy_per_cycle_j: NonNegative | None = None


MAX_CYCLE_STUDY_SAMPLES = 400  # board runs in one `pressfit study cycle` (each a whole board: minutes at most)
ScaleFactors = Annotated[list[Annotated[float, Field(gt=0, le=100.0, allow_inf_nan=False)]],
                         Field(min_length=1, max_length=50)]


class CycleStudy(StrictModel):
    """The grid of ``pressfit study cycle`` (:mod:`pressfit.studies.cycle_study`): scale factors (-) on
    ``[cycle.motion]``'s speed, acceleration and jerk, ``descent`` on all three of ``[cycle.descent]`` (or of
    ``[cycle.motion]`` when the board has no descent table), ``kp_scale``, ``kd_scale``, ``ki_scale`` on
    ``[cycle.controller]``'s gains, and ``a4_n``: the commanded preloads (N, force mode; default the case's
    ``[preload] a4_n``); every combination is one board run, at most ``MAX_CYCLE_STUDY_SAMPLES``. Each scaled
    limit must stay within :class:`MotionLimits`' bounds."""

    speed_scale: ScaleFactors = [1.0]
    acceleration_scale: ScaleFactors = [1.0]
    jerk_scale: ScaleFactors = [1.0]
    descent_scale: ScaleFactors = [1.0]
    kp_scale: ScaleFactors = [1.0]
    kd_scale: ScaleFactors = [1.0]
    ki_scale: ScaleFactors = [1.0]
    a4_n: Annotated[list[Annotated[float, Field(le=MAX_FORCE_N, ge=-MAX_FORCE_N, allow_inf_nan=False)]],
                    Field(min_length=1, max_length=50)] | None = None

    @model_validator(mode="after")
    def _grid(self) -> CycleStudy:
        for key in type(self).model_fields:
            values = getattr(self, key)
            if values is not None and len(set(values)) != len(values):
                raise ValueError(f"{key}: the values must be distinct, got {values}")
        count = self.sample_count
        if count > MAX_CYCLE_STUDY_SAMPLES:
            raise ValueError(f"the grid has {count} samples (board runs), above the cap of "
                             f"{MAX_CYCLE_STUDY_SAMPLES}")
        return self

    @property
    def sample_count(self) -> int:
        return math.prod(len(getattr(self, key) or [None]) for key in type(self).model_fields)


class Cycle(StrictModel):
    """A whole board (``pressfit cycle``; :mod:`pressfit.dynamics.cycle`): the board face is the plane
    y = ``board_height_m``; the pins are ``pins`` (in their order) then the ``grid`` (row by row in z, each row
    in alternating x direction). Per pin (``PIN_KEYS``, overriding the defaults here): the insertion force limit
    (N; default ``[cycle.controller] force_limit_n``), ``approach_height_m`` above the face where the descent
    starts, the commanded ``interference_m`` below it, ``dwell_s`` at the bottom, and the pass/fail limits
    ``max_overshoot_n`` (peak contact force over the pin's limit, N) and ``max_alignment_error_m`` (the tool's
    lateral distance from the pin at first contact, m), unchecked when not given. The tool moves from
    ``start_m`` above the first pin, descends, dwells, retracts to the approach height, traverses above the next
    pin, ..., and after the last to ``end_m``, where it holds ``settle_s``; each move is the minimum-time S-curve
    under ``motion`` (lift and traverse) or ``descent`` (descent and retract; default ``motion``), scaled down
    where the drives' speed or force limit would bind. ``time_step_s``, ``baumgarte_rad_per_s``, ``model``,
    ``contact`` (the law, and with ``[[cycle.contact.pins]]`` a component of several pins pressed at every board
    position: :class:`PinFieldLaw`) and ``controller`` mean what they mean in ``[simulation]``. ``limits``: what
    ``pressfit check`` asserts on the board (:class:`CycleLimits`); ``study``: the grid of ``pressfit study
    cycle`` (:class:`CycleStudy`)."""

    board_height_m: Positive
    start_m: Vector3
    end_m: Vector3
    pins: list[Pin] = []
    grid: PinGrid | None = None
    approach_height_m: Positive = 0.005
    interference_m: Positive = 0.002
    dwell_s: Positive = 0.5
    max_overshoot_n: NonNegative | None = None
    max_alignment_error_m: NonNegative | None = None
    settle_s: NonNegative = 0.5
    motion: MotionLimits
    descent: MotionLimits | None = None
    time_step_s: TimeStep = 5e-4
    baumgarte_rad_per_s: BaumgarteRate = 200.0
    model: str = "flexible"  # a name of pressfit.dynamics.machine.registry.MODELS, checked by the plan
    contact: PinFieldLaw = PinFieldLaw()
    controller: Controller = Controller()
    limits: CycleLimits = CycleLimits()
    study: CycleStudy | None = None

    @model_validator(mode="after")
    def _some_pins(self) -> Cycle:
        count = len(self.pins) + (self.grid.x.count * self.grid.z.count if self.grid is not None else 0)
        if count == 0:
            raise ValueError("give pins (a list of {x_m, z_m}) and/or a grid (x and z ranges with counts)")
        if count > MAX_PINS:
            raise ValueError(f"the board has {count} pins, above the cap of {MAX_PINS} pins per cycle")
        return self

    def resolved_pins(self) -> list[ResolvedPin]:
        """Every pin in cycle order with its values resolved (class docstring)."""
        defaults = {k: getattr(self, k) for k in PIN_KEYS if k != "force_limit_n"}
        defaults["force_limit_n"] = self.controller.force_limit_n
        places = [(p, f"[cycle] pins[{k}]") for k, p in enumerate(self.pins)]
        if self.grid is not None:
            for row, z in enumerate(self.grid.z.values()):
                xs = self.grid.x.values() if row % 2 == 0 else self.grid.x.values()[::-1]
                places += [(Pin(x_m=float(x), z_m=float(z)), "[cycle.grid]") for x in xs]
        out = []
        for k, (pin, source) in enumerate(places):
            values = {key: getattr(pin, key) if getattr(pin, key) is not None else defaults[key] for key in PIN_KEYS}
            out.append(ResolvedPin(index=k + 1, x_m=pin.x_m, z_m=pin.z_m, source=source, **values))
        return out


class Case(StrictModel):
    """A validated case file."""

    name: str
    description: str = ""
    model: str = ""  # path of the machine file, relative to the case file; default: the shipped model
    model_overrides: dict[str, Any] = {}
    poses: Poses
    loads: Loads
    preload: Preload = Preload()
    solver: Solver = Solver()
    envelope: Envelope = Envelope()
    reference: Reference | None = None
    clearance: ClearanceSpec | None = None
    study: Study | None = None
    montecarlo: MonteCarlo | None = None
    design: Design | None = None
    simulation: Simulation | None = None
    cycle: Cycle | None = None
    curve: CurveStudy | None = None
    path: str = ""

    @model_validator(mode="before")
    @classmethod
    def _table_paths(cls, data: Any) -> Any:
        """A tabulated law's ``table_path`` is relative to the case file: made absolute before validation."""
        if not isinstance(data, dict) or not data.get("path"):
            return data
        base = Path(data["path"]).parent

        def resolve(table: Any) -> Any:
            if isinstance(table, dict) and isinstance(table.get("table_path"), str):
                return {**table, "table_path": str(base / table["table_path"])}
            return table

        out = dict(data)
        for name in ("simulation", "cycle"):
            section = out.get(name)
            if isinstance(section, dict) and isinstance(section.get("contact"), dict):
                contact = resolve(section["contact"])
                if isinstance(contact.get("pins"), list):
                    contact = {**contact, "pins": [resolve(p) for p in contact["pins"]]}
                out[name] = {**section, "contact": contact}
        return out

    def machine(self) -> Machine:
        """The case's machine, with its overrides applied (errors name the case file)."""
        base = (Path(self.path).parent / self.model) if self.model else DEFAULT_MODEL
        machine = load_machine(base)
        machine = machine.with_overrides(self.model_overrides, source=f"{self.path} [model_overrides]") \
            if self.model_overrides else machine
        self._preload_fits(machine)
        return machine

    def _preload_fits(self, machine: Machine) -> None:
        """A non-zero ``[preload]`` must have the machine's redundancy n - 3 of amplitudes: CasePreloadError
        naming the case file, the key and the machine's leg count otherwise."""
        p = self.preload
        amplitudes, k, n = p.amplitudes, machine.redundancy, len(machine.legs)
        if not any(amplitudes) or len(amplitudes) == k:
            return
        unit = "m" if p.mode == "length" else "n"
        key = f"[preload] {'a4' if len(amplitudes) == 1 else 'amplitudes'}_{unit}"
        got = f"got {len(amplitudes)}: " + ", ".join(f"{a:g}" for a in amplitudes)
        where = f"the {n}-leg machine {machine.name} ({machine.source})"
        message = (f"{where} has no redundant actuation: no internal preload; {got}" if k == 0 else
                   f"give {k} preload amplitude{'s' if k > 1 else ''} (n - 3) for {where}; {got}")
        raise CasePreloadError(self.path, key, message, machine.name, k)


def load_case(path: Path | str) -> Case:
    """Read and validate one case file."""
    data = read_toml(path)
    refuse_wrong_kind(path, data, "case")
    try:
        case = Case.model_validate({**data, "path": str(path)})
    except ValidationError as exc:
        raise validation_error(path, exc) from None
    except (TypeError, ValueError) as exc:  # e.g. numbers too large for numpy
        raise ModelFileError(path, "<values>", str(exc)) from None
    check_curve_tolerances(case)
    return case


def check_curve_tolerances(case: Case) -> None:
    """``[curve]`` needs ``[simulation.contact]`` and its tolerances' keys must be the law's
    (:func:`curve_tolerance_keys`): ModelFileError naming the case file and the key otherwise."""
    if case.curve is None:
        return
    if case.simulation is None:
        raise ModelFileError(case.path, "curve", "[curve] needs a [simulation.contact] table (the joint it varies)")
    contact = case.simulation.contact
    allowed = curve_tolerance_keys(contact.law)
    have = {k for p in contact.resolved_pins() for k, v in p.keys.items() if v is not None}
    for key in case.curve.tolerances:
        if key not in allowed:
            raise ModelFileError(case.path, f"curve.tolerances.{key}", f"unknown tolerance for law "
                                 f"\"{contact.law}\"; give one of {', '.join(allowed)}")
        if key not in CURVE_POSE_KEYS and key not in have:
            raise ModelFileError(case.path, f"curve.tolerances.{key}", "the contact has no value of this key to "
                                 "vary (give it in [simulation.contact])")


def discover(paths: list[Path | str]) -> list[Path]:
    """Case files named directly or found recursively (``*.toml``) under directories, sorted."""
    out: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            out.extend(sorted(p.rglob("*.toml")))
        elif p.exists():
            out.append(p)
        else:
            raise ModelFileError(p, "<file>", "file or directory does not exist")
    return out
