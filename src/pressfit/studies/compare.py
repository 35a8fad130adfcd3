r"""Machines measured the same way (``pressfit compare``, issue 21 item 4): the figures a press builder compares
over the required workspace under the press load and its load cone, and the paper's two claims with the numbers.

The box: the machine's required square (``[workspace]``, 500 x 500 mm for the shipped machines) at
``COMPARE_HEIGHTS`` heights from the lowest height where the whole square is reachable
(:func:`pressfit.kinematics.workspace.square_height_range`) up ``[workspace] height_min_m`` (100 mm); a machine that
does not reach the whole box is refused by name. The loads: the press force (700 N, +y on the tool) and
``CONE_DIRECTIONS`` forces of the same magnitude on a cone of ``CONE_HALF_ANGLE_RAD`` (5 degrees of misalignment)
about it (:func:`pressfit.studies.workspace_envelope.press_loads`).

A Cartesian gantry (:mod:`pressfit.description.gantry`, a serial chain of prismatic axes with elastic beams,
:mod:`pressfit.mechanics.gantry`) is measured over its own required box (``[workspace]``'s square at
``COMPARE_HEIGHTS`` tool heights over the 100 mm from ``tool_height_min_m``) under the same loads by
:func:`pressfit.dynamics.gantry_modes.gantry_metrics` (drive forces per axis, member bending moments, the tool's
stiffness, tilt and first natural frequency at every pose; the moving mass is what the X axis moves); its guides
and screws have no play model, so it has no lost-motion figure.

Per UPU machine (any number of legs; the condensed linear model, :mod:`pressfit.mechanics.condensed`, its
residual enforced):
* worst drive force: max |N_i| over the box, the loads and the legs (each actuator carries its leg's axial force);
* worst bending moment in any structural member: the legs' section bending hypot(M_x, M_y) (constant along a
  leg in this model), N m;
* the tool's translational stiffness (the tool at the plate centre, the plate free to tilt: the inverse of the
  compliance's translational block): its weakest direction (smallest eigenvalue) and the vertical 1 / C_yy,
  worst and median over the box, N/m; the tilt |phi| under the press load, worst and median, rad;
* the first natural frequency (:func:`pressfit.dynamics.modes.natural_modes`, the drives holding their lengths)
  at the box's centre and its four corners at mid height, lowest and median, Hz; the moving mass (every body of
  the inertial model: the plate, the tool, the legs, which swing), kg;
* with ``PLAY_M`` (20 um) of play in every cardan (the machine's clearance law and geometry), at every pose of the
  box and every load direction of the cone, from the whole load path (:mod:`pressfit.mechanics.closing_preload`):
  the lost motion without preload (the deflection the play adds at the press load, wherever along the path it is
  taken up) and, for a redundant machine, the pose's critical preload (the smallest that keeps every cardan closed
  along the whole path for every direction), the drive forces computed with it and the lost motion left; a machine
  with n = 3 legs has no preload (None, with the reason).

The claims (:func:`claims`) are decided pose by pose over the 4-UPU's box and cone: the verdict is "confirmed"
only where the claim holds at every pose, "holds on X% of the box" where it holds at some, "refuted" where at none,
with the worst pose and its figures.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pressfit.description.gantry import Gantry
from pressfit.description.machine import Machine
from pressfit.errors import PressfitError, ResidualError
from pressfit.kinematics import is_reachable
from pressfit.kinematics.workspace import square_height_range, workspace_box
from pressfit.mechanics import condensed
from pressfit.mechanics.condensed import CONDENSED_RESIDUAL_TOL, PRESS_LOAD_N
from pressfit.studies.workspace_envelope import press_loads

COMPARE_GRID = 5  # x-z points per side of the required square
COMPARE_HEIGHTS = 3  # heights over the required 100 mm
CONE_HALF_ANGLE_RAD = 0.0873  # 5 degrees: the load cone of cases/envelope/press_workspace.toml
CONE_DIRECTIONS = 8
REQUIRED_HEIGHT_M = 0.1  # the gantry's box height (the 4-UPU's: [workspace] height_min_m), m
PLAY_M = 20e-6  # cardan play of the lost-motion figures, m (the shipped machine's cardan_axial_clearance_m)


@dataclass(frozen=True, kw_only=True)
class MachineFigures:
    """One machine's comparison figures (module docstring), SI units; ``*_pose_m`` where the worst happens."""

    name: str
    source: str
    kind: str  # "upu" or "gantry"
    legs: int | None  # UPU legs (None: a gantry)
    heights_m: tuple[float, float]  # the box's lowest and highest plate height
    poses: int  # box poses evaluated (each under every load)
    worst_drive_force_n: float
    worst_drive_force_pose_m: np.ndarray
    drive_force_limit_n: float  # what one drive delivers (magnitude), N
    worst_bending_nm: float
    worst_bending_member: str  # e.g. "leg 2"
    weakest_stiffness_worst_n_per_m: float
    weakest_stiffness_median_n_per_m: float
    vertical_stiffness_worst_n_per_m: float
    vertical_stiffness_median_n_per_m: float
    tilt_worst_rad: float
    tilt_median_rad: float
    first_frequency_lowest_hz: float
    first_frequency_median_hz: float
    moving_mass_kg: float
    lost_motion_m: float  # with PLAY_M of play, no preload: worst over the box and the cone, m
    lost_motion_preloaded_m: float | None  # the same with each pose's critical preload (None: no redundant actuation)
    critical_preload_worst_n: float | None  # the largest pose-wise critical preload over the box (NaN: none at a pose)
    critical_preload_worst_pose_m: np.ndarray | None
    preloaded_drive_force_n: float | None  # max |N_i| over the box, cone and path with each pose's critical preload
    preload_note: str  # why there is no preload, or how it was found
    max_relative_residual: float  # the worst equilibrium residual of the solves behind these figures
    poses_m: np.ndarray  # (k, 3) the box; the per-pose figures below decide the claims
    pose_weakest_stiffness_n_per_m: np.ndarray  # (k,)
    pose_vertical_stiffness_n_per_m: np.ndarray  # (k,)
    pose_tilt_rad: np.ndarray  # (k,) worst over the cone
    pose_bending_nm: np.ndarray  # (k,) worst member, over the cone
    pose_lost_motion_m: np.ndarray  # (k,) no preload, worst over the cone (NaN: not computed)
    pose_critical_preload_n: np.ndarray  # (k,) NaN: none (or no redundant actuation)
    pose_preloaded_drive_force_n: np.ndarray  # (k,) the worst drive with the pose's critical preload
    pose_preloaded_lost_motion_m: np.ndarray  # (k,)

    def to_dict(self) -> dict[str, Any]:
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.__dict__.items()}


def compare_box(machine: Machine, heights: int = COMPARE_HEIGHTS, grid: int = COMPARE_GRID) -> np.ndarray:
    """The box's poses (k, 3), m (module docstring); PressfitError naming the machine when it is not reachable."""
    span = square_height_range(machine)
    need = machine.workspace.height_min_m
    lo = span.y_min_m + span.tolerance_m  # inside the bisection's bracket: reachable
    if span.y_max_m - lo < need:
        raise PressfitError(f"{machine.name} ({machine.source}): the required square is reachable over "
                            f"{span.y_max_m - lo:.4g} m of height ({lo:.4g}..{span.y_max_m:.4g} m), less than "
                            f"[workspace] height_min_m = {need:g} m: the machine does not cover the required box")
    poses = workspace_box(machine, np.linspace(lo, lo + need, heights), grid).reshape(-1, 3)
    if not np.all(is_reachable(machine, poses)):
        raise PressfitError(f"{machine.name} ({machine.source}): a pose of the required box is unreachable")
    return poses


@dataclass(frozen=True, kw_only=True)
class PoseFigures:
    """The per-pose figures of a UPU machine at poses (k, 3), m (module docstring): over the loads and legs."""

    poses_m: np.ndarray  # (k, 3)
    drive_force_n: np.ndarray  # (k, n) max |N_i| over the loads
    bending_nm: np.ndarray  # (k, n) max leg bending over the loads
    weakest_stiffness_n_per_m: np.ndarray  # (k,) smallest eigenvalue of the tool's translational stiffness
    vertical_stiffness_n_per_m: np.ndarray  # (k,) 1 / C_yy
    tilt_rad: np.ndarray  # (k,) |phi|, worst over the press load and its cone
    max_relative_residual: float


def pose_figures(machine: Machine, poses_m: np.ndarray) -> PoseFigures:
    """:class:`PoseFigures` at ``poses_m`` (k, 3), m, from the condensed model (its residual enforced)."""
    poses = np.atleast_2d(np.asarray(poses_m, dtype=float))
    loads = press_loads(PRESS_LOAD_N, CONE_HALF_ANGLE_RAD, CONE_DIRECTIONS)  # the first: the press load alone
    forces, bending, tilt, residual = [], [], [], 0.0
    for load in loads:
        res = condensed.solve_linear(machine, poses, np.broadcast_to(load, poses.shape))
        residual = max(residual, float(res.relative_residual().max()))
        forces.append(np.abs(res.axial_forces_n))
        bending.append(res.bending_nm)
        tilt.append(res.tilt_rad)
    if residual > CONDENSED_RESIDUAL_TOL:
        raise ResidualError("compare: condensed solve", "relative equilibrium residual", residual,
                            CONDENSED_RESIDUAL_TOL)
    compliance = condensed.condensed_plate_compliance(machine, poses)[:, :3, :3]
    return PoseFigures(poses_m=poses, drive_force_n=np.max(forces, axis=0), bending_nm=np.max(bending, axis=0),
                       weakest_stiffness_n_per_m=np.linalg.eigvalsh(np.linalg.inv(compliance))[:, 0],
                       vertical_stiffness_n_per_m=1.0 / compliance[:, 1, 1], tilt_rad=np.max(tilt, axis=0),
                       max_relative_residual=residual)


def upu_figures(machine: Machine, heights: int = COMPARE_HEIGHTS, grid: int = COMPARE_GRID,
                modes: bool = True, play: bool = True) -> MachineFigures:
    """The comparison figures of a UPU machine (module docstring) over :func:`compare_box`; ``modes``/``play``
    False leave those figures NaN (a quick look)."""
    from pressfit.dynamics.modes import natural_modes

    poses = compare_box(machine, heights, grid)
    f = pose_figures(machine, poses)
    i_force = np.unravel_index(np.argmax(f.drive_force_n), f.drive_force_n.shape)
    i_bend = np.unravel_index(np.argmax(f.bending_nm), f.bending_nm.shape)
    box = poses.reshape(heights, grid, grid, 3)
    centre = box[heights // 2, grid // 2, grid // 2]
    frequencies, mass = np.full(1, np.nan), float("nan")
    if modes:
        corners = box[heights // 2][[0, 0, -1, -1], [0, -1, 0, -1]]
        found = [natural_modes(machine, p, count=1) for p in (centre, *corners)]
        frequencies, mass = np.array([m.frequencies_hz[0] for m in found]), found[0].total_mass_kg
    backlash = _backlash(machine, poses) if play else None
    nan = np.full(len(poses), np.nan)
    redundant = machine.redundancy > 0 and backlash is not None
    crit = backlash.critical_preload_n if backlash is not None else nan
    worst = int(np.argmax(np.where(np.isnan(crit), np.inf, crit))) if redundant else None
    return MachineFigures(
        name=machine.name, source=str(machine.source or machine.name), kind="upu", legs=len(machine.legs),
        heights_m=(float(poses[0, 1]), float(poses[-1, 1])), poses=len(poses),
        worst_drive_force_n=float(f.drive_force_n[i_force]), worst_drive_force_pose_m=poses[i_force[0]],
        drive_force_limit_n=machine.actuator.drive_force_limit_n,
        worst_bending_nm=float(f.bending_nm[i_bend]), worst_bending_member=f"leg {i_bend[1] + 1}",
        weakest_stiffness_worst_n_per_m=float(f.weakest_stiffness_n_per_m.min()),
        weakest_stiffness_median_n_per_m=float(np.median(f.weakest_stiffness_n_per_m)),
        vertical_stiffness_worst_n_per_m=float(f.vertical_stiffness_n_per_m.min()),
        vertical_stiffness_median_n_per_m=float(np.median(f.vertical_stiffness_n_per_m)),
        tilt_worst_rad=float(f.tilt_rad.max()), tilt_median_rad=float(np.median(f.tilt_rad)),
        first_frequency_lowest_hz=float(frequencies.min()), first_frequency_median_hz=float(np.median(frequencies)),
        moving_mass_kg=mass,
        lost_motion_m=float("nan") if backlash is None else float(backlash.lost_motion_unpreloaded_m.max()),
        lost_motion_preloaded_m=float(np.max(backlash.lost_motion_m)) if redundant else None,
        critical_preload_worst_n=float(crit[worst]) if redundant else None,
        critical_preload_worst_pose_m=poses[worst] if redundant else None,
        preloaded_drive_force_n=float(np.max(backlash.drive_forces_n)) if redundant else None,
        preload_note=_preload_note(machine, play), max_relative_residual=max(
            f.max_relative_residual, 0.0 if backlash is None else backlash.max_relative_residual),
        poses_m=poses, pose_weakest_stiffness_n_per_m=f.weakest_stiffness_n_per_m,
        pose_vertical_stiffness_n_per_m=f.vertical_stiffness_n_per_m, pose_tilt_rad=f.tilt_rad,
        pose_bending_nm=f.bending_nm.max(1),
        pose_lost_motion_m=nan if backlash is None else backlash.lost_motion_unpreloaded_m,
        pose_critical_preload_n=crit,
        pose_preloaded_drive_force_n=backlash.drive_forces_n.max(1) if redundant else nan,
        pose_preloaded_lost_motion_m=backlash.lost_motion_m if redundant else nan)


def _backlash(machine: Machine, poses: np.ndarray) -> Any:
    """:func:`pressfit.mechanics.closing_preload.closing_preload` over the box and the cone, PLAY_M of play."""
    from pressfit.mechanics.clearance import Clearance
    from pressfit.mechanics.closing_preload import closing_preload

    return closing_preload(machine, poses, press_loads(1.0, CONE_HALF_ANGLE_RAD, CONE_DIRECTIONS), PRESS_LOAD_N,
                           Clearance.uniform(machine).with_gap(PLAY_M))


def _preload_note(machine: Machine, play: bool) -> str:
    if not play:
        return "not computed"
    if machine.redundancy == 0:
        return f"{len(machine.legs)} legs: no redundant actuation, no internal preload"
    return ("each pose's critical preload: the smallest along " + ("v_p" if machine.redundancy == 1 else
            "the preload space's direction that loads every leg most evenly") + " that keeps every cardan closed "
            "along the whole load path for every direction of the cone")


@dataclass(frozen=True, kw_only=True)
class Claim:
    """One of the paper's claims against its baseline, decided pose by pose over the 4-UPU's box (:func:`verdict`):
    ``verdict`` "confirmed", "holds on X% of the box", "refuted" or "not measured" (the baseline is not among the
    machines compared), the fraction of the box where it holds, the worst pose (m) and the numbers that decide it."""

    claim: str  # the paper's words
    baseline: str  # what it is measured against
    verdict: str
    holds_fraction: float | None  # of the box's poses (None: not measured)
    worst_pose_m: tuple[float, float, float] | None
    evidence: str


PRECISION_CLAIM = ("against the Cartesian press, the 4-UPU \"could improve the precision of the positioning "
                   "movements\": the tool's stiffness and tilt under the press load")
MEMBER_CLAIM = ("against the Cartesian press, the 4-UPU \"could improve ... the stiffness of the structural "
                "elements\" (the gantry's X and Z beams carry large bending moments): the worst bending moment in any "
                "member")
PRELOAD_CLAIM = ("\"thanks to the additional leg, the proposed solution allows a preload that is capable of "
                 "compensating the backlash of joints\" (against Tsai's non-redundant 3-UPU)")
BACKLASH_COMPENSATED = 0.01  # the preload compensates the backlash when it leaves < 1% of the 3-UPU's lost motion


def verdict(holds: np.ndarray) -> tuple[str, float]:
    """The verdict of a claim that holds at the poses where ``holds`` (k,) is True, and the fraction: "confirmed"
    at every pose, "refuted" at none, else "holds on X% of the box"."""
    fraction = float(np.mean(holds))
    if fraction == 1.0:
        return "confirmed", fraction
    return ("refuted", fraction) if fraction == 0.0 else (f"holds on {100 * fraction:.3g}% of the box", fraction)


def _pose(h: np.ndarray) -> str:
    return "(" + ", ".join(f"{c:.4g}" for c in h) + ") m"


def _span(values: np.ndarray, scale: float, fmt: str) -> str:
    """min..max of the finite values times scale, or "none"."""
    ok = values[np.isfinite(values)] * scale
    return "none" if ok.size == 0 else f"{format(ok.min(), fmt)}..{format(ok.max(), fmt)}"


def _not_measured(claim: str, baseline: str, evidence: str) -> Claim:
    return Claim(claim=claim, baseline=baseline, verdict="not measured", holds_fraction=None, worst_pose_m=None,
                 evidence=evidence)


def _decided(claim: str, baseline: str, holds: np.ndarray, worst: int, poses: np.ndarray, evidence: str) -> Claim:
    v, fraction = verdict(holds)
    return Claim(claim=claim, baseline=baseline, verdict=v, holds_fraction=fraction,
                 worst_pose_m=tuple(float(c) for c in poses[worst]),
                 evidence=f"holds at {int(np.sum(holds))} of {len(holds)} poses of the box; " + evidence)


def precision_claim(upu: MachineFigures, gantry: MachineFigures) -> Claim:
    """Precision at a pose of the UPU's box: its weakest and vertical tool stiffness higher than the gantry's worst
    over its own box, and its tilt (worst over the cone) lower than the gantry's worst."""
    w, v, t = upu.pose_weakest_stiffness_n_per_m, upu.pose_vertical_stiffness_n_per_m, upu.pose_tilt_rad
    holds = ((w > gantry.weakest_stiffness_worst_n_per_m) & (v > gantry.vertical_stiffness_worst_n_per_m)
             & (t < gantry.tilt_worst_rad))
    margin = np.minimum(np.minimum(w / gantry.weakest_stiffness_worst_n_per_m,
                                   v / gantry.vertical_stiffness_worst_n_per_m), gantry.tilt_worst_rad / t)
    i = int(np.argmin(margin))
    return _decided(PRECISION_CLAIM, gantry.name, holds, i, upu.poses_m, (
        f"worst pose {_pose(upu.poses_m[i])}: weakest tool stiffness {w[i]:.4g} N/m, vertical {v[i]:.4g} N/m, tilt "
        f"{t[i]:.3g} rad ({upu.name}) against the gantry's worst {gantry.weakest_stiffness_worst_n_per_m:.4g} N/m, "
        f"{gantry.vertical_stiffness_worst_n_per_m:.4g} N/m, {gantry.tilt_worst_rad:.3g} rad ({gantry.name}); "
        f"over the box {upu.weakest_stiffness_worst_n_per_m:.4g}..{w.max():.4g} N/m weakest; moving mass "
        f"{upu.moving_mass_kg:.4g} against {gantry.moving_mass_kg:.4g} kg"))


def member_claim(upu: MachineFigures, gantry: MachineFigures) -> Claim:
    """The members at a pose of the UPU's box: its worst member bending (over the cone) below the gantry's worst."""
    holds = upu.pose_bending_nm < gantry.worst_bending_nm
    i = int(np.argmax(upu.pose_bending_nm))
    return _decided(MEMBER_CLAIM, gantry.name, holds, i, upu.poses_m, (
        f"worst member bending moment {upu.pose_bending_nm[i]:.4g} N m at {_pose(upu.poses_m[i])} ({upu.name}, "
        f"{upu.worst_bending_member}) against {gantry.worst_bending_nm:.4g} N m ({gantry.name}, "
        f"{gantry.worst_bending_member})"))


def preload_claim(upu: MachineFigures, upu3: MachineFigures) -> Claim:
    """The backlash at a pose of the 4-UPU's box: a critical preload exists there (every cardan closed along the
    whole load path for every direction of the cone), it leaves less than ``BACKLASH_COMPENSATED`` of the 3-UPU's
    smallest lost motion over its own box (which no preload can change), and the drive forces computed with it stay
    within the drive force limit."""
    crit, drive = upu.pose_critical_preload_n, upu.pose_preloaded_drive_force_n
    left = np.maximum(upu.pose_preloaded_lost_motion_m, 0.0)
    base = float(np.nanmin(upu3.pose_lost_motion_m))
    with np.errstate(invalid="ignore"):
        holds = np.isfinite(crit) & (left < BACKLASH_COMPENSATED * base) & (drive <= upu.drive_force_limit_n)
    i = int(np.argmax(np.where(np.isfinite(crit), drive, np.inf)))
    at = ("no preload up to the bracket's closes every cardan" if not np.isfinite(crit[i]) else
          f"critical preload {crit[i]:.4g} N, the drives carry up to {drive[i]:.4g} N with it, lost motion "
          f"{left[i] * 1e6:.3g} um")
    return _decided(PRELOAD_CLAIM, upu3.name, holds, i, upu.poses_m, (
        f"with {PLAY_M * 1e6:g} um of play in every cardan, along the whole load path to {PRESS_LOAD_N:g} N and "
        f"over the cone: lost motion {base * 1e6:.3g}..{np.nanmax(upu3.pose_lost_motion_m) * 1e6:.3g} um "
        f"({upu3.name}: {upu3.preload_note}) against {np.nanmin(upu.pose_lost_motion_m) * 1e6:.3g}.."
        f"{upu.lost_motion_m * 1e6:.3g} um without preload ({upu.name}); its pose-wise critical preload "
        f"{_span(crit, 1.0, '.4g')} N; worst pose {_pose(upu.poses_m[i])}: {at}, against the "
        f"drives' {upu.drive_force_limit_n:.4g} N limit"))


def claims(figures: list[MachineFigures]) -> list[Claim]:
    """The paper's claims decided from the compared machines, the redundant 4-UPU being the first UPU machine with 4
    legs, pose by pose over its box (:func:`precision_claim` and :func:`member_claim` against the first gantry,
    :func:`preload_claim` against the first 3-leg UPU); "not measured" when the baseline is not among the
    machines."""
    upu4 = next((f for f in figures if f.kind == "upu" and f.legs == 4), None)
    gantry = next((f for f in figures if f.kind == "gantry"), None)
    upu3 = next((f for f in figures if f.kind == "upu" and f.legs == 3), None)
    out = []
    if upu4 is None or gantry is None:
        out += [_not_measured(c, "a Cartesian gantry", "compare a 4-leg UPU machine and a gantry machine file")
                for c in (PRECISION_CLAIM, MEMBER_CLAIM)]
    else:
        out += [precision_claim(upu4, gantry), member_claim(upu4, gantry)]
    if upu4 is None or upu3 is None or upu4.lost_motion_preloaded_m is None or not np.isfinite(upu3.lost_motion_m):
        out.append(_not_measured(PRELOAD_CLAIM, "a 3-leg UPU",
                                 "compare a 4-leg and a 3-leg UPU machine file with the play figures"))
    else:
        out.append(preload_claim(upu4, upu3))
    return out


@dataclass(frozen=True, kw_only=True)
class Comparison:
    """The machines' figures and the two claims (:func:`claims`)."""

    machines: list[MachineFigures]
    claims: list[Claim]

    def to_dict(self) -> dict[str, Any]:
        return {"machines": [m.to_dict() for m in self.machines], "claims": [dict(c.__dict__) for c in self.claims],
                "play_m": PLAY_M, "press_load_n": PRESS_LOAD_N, "cone_half_angle_rad": CONE_HALF_ANGLE_RAD}


def gantry_figures(gantry: Gantry, heights: int = COMPARE_HEIGHTS, grid: int = COMPARE_GRID) -> MachineFigures:
    """The comparison figures of a gantry (module docstring)."""
    from pressfit.dynamics.gantry_modes import gantry_metrics

    ws = gantry.workspace
    x, z = np.linspace(-ws.x_half_width_m, ws.x_half_width_m, grid), np.linspace(-ws.z_half_width_m,
                                                                               ws.z_half_width_m, grid)
    y = np.linspace(ws.tool_height_min_m, ws.tool_height_min_m + REQUIRED_HEIGHT_M, heights)
    yy, zz, xx = np.meshgrid(y, z, x, indexing="ij")
    poses = np.stack([xx, yy, zz], -1).reshape(-1, 3)
    loads = press_loads(PRESS_LOAD_N, CONE_HALF_ANGLE_RAD, CONE_DIRECTIONS)
    m = gantry_metrics(gantry, poses, np.column_stack([loads, np.zeros_like(loads)]))
    vertical = m.vertical_stiffness_n_per_m  # from the same model per pose (not built twice)
    nan = np.full(len(poses), np.nan)
    return MachineFigures(
        name=gantry.name, source=str(gantry.source or gantry.name), kind="gantry", legs=None,
        heights_m=(float(y[0]), float(y[-1])), poses=len(poses), worst_drive_force_n=m.worst_drive_force_n,
        drive_force_limit_n=float("nan"),
        worst_drive_force_pose_m=m.worst_drive_pose_m, worst_bending_nm=m.worst_bending_moment_nm,
        worst_bending_member=m.worst_bending_member, weakest_stiffness_worst_n_per_m=m.min_tool_stiffness_n_per_m,
        weakest_stiffness_median_n_per_m=m.median_tool_stiffness_n_per_m,
        vertical_stiffness_worst_n_per_m=float(vertical.min()),
        vertical_stiffness_median_n_per_m=float(np.median(vertical)), tilt_worst_rad=m.max_tool_tilt_rad,
        tilt_median_rad=m.median_tool_tilt_rad, first_frequency_lowest_hz=m.first_frequency_hz,
        first_frequency_median_hz=float("nan"), moving_mass_kg=m.moving_mass_kg, lost_motion_m=float("nan"),
        lost_motion_preloaded_m=None, critical_preload_worst_n=None, critical_preload_worst_pose_m=None,
        preloaded_drive_force_n=None, preload_note="the gantry's guides and screws have no play model",
        max_relative_residual=m.worst_residual, poses_m=poses, pose_weakest_stiffness_n_per_m=nan,
        pose_vertical_stiffness_n_per_m=vertical, pose_tilt_rad=nan, pose_bending_nm=nan, pose_lost_motion_m=nan,
        pose_critical_preload_n=nan, pose_preloaded_drive_force_n=nan, pose_preloaded_lost_motion_m=nan)


def compare(machines: list[Machine | Gantry], progress: bool = True, heights: int = COMPARE_HEIGHTS,
            grid: int = COMPARE_GRID) -> Comparison:
    """Every machine's figures (:func:`upu_figures`, :func:`gantry_figures`, on ``heights`` x ``grid`` x ``grid``
    box poses) and the claims."""
    from tqdm import tqdm

    figures = [gantry_figures(m, heights, grid) if isinstance(m, Gantry) else upu_figures(m, heights, grid)
               for m in tqdm(machines, desc="compare", unit="machine", disable=not progress)]
    return Comparison(machines=figures, claims=claims(figures))
