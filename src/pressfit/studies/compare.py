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
* with ``PLAY_M`` (20 um) of play in every cardan (the machine's clearance law and geometry), at the box's centre
  under the press load: the lost motion without preload and, for a redundant machine, with the best preload (the
  critical preload that keeps every cardan closed up to the press load, :func:`pressfit.mechanics.clearance.
  critical_preloads`), from :func:`pressfit.studies.preload_study.preload_study`; a machine with n = 3 legs has no
  preload (None, with the reason).
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
    lost_motion_m: float  # with PLAY_M of play, no preload, at the box's centre under the press load
    lost_motion_preloaded_m: float | None  # the same with the best preload (None: no redundant actuation)
    best_preload_n: float | None
    preload_note: str  # why there is no preload, or how the best one was found
    max_relative_residual: float  # the worst equilibrium residual of the solves behind these figures

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
    tilt_rad: np.ndarray  # (k,) |phi| under the press load (+y)
    max_relative_residual: float


def pose_figures(machine: Machine, poses_m: np.ndarray) -> PoseFigures:
    """:class:`PoseFigures` at ``poses_m`` (k, 3), m, from the condensed model (its residual enforced)."""
    poses = np.atleast_2d(np.asarray(poses_m, dtype=float))
    loads = press_loads(PRESS_LOAD_N, CONE_HALF_ANGLE_RAD, CONE_DIRECTIONS)  # the first: the press load alone
    forces, bending, tilt, residual = [], [], None, 0.0
    for load in loads:
        res = condensed.solve_linear(machine, poses, np.broadcast_to(load, poses.shape))
        residual = max(residual, float(res.relative_residual().max()))
        forces.append(np.abs(res.axial_forces_n))
        bending.append(res.bending_nm)
        tilt = res.tilt_rad if tilt is None else tilt
    if residual > CONDENSED_RESIDUAL_TOL:
        raise ResidualError("compare: condensed solve", "relative equilibrium residual", residual,
                            CONDENSED_RESIDUAL_TOL)
    compliance = condensed.condensed_plate_compliance(machine, poses)[:, :3, :3]
    return PoseFigures(poses_m=poses, drive_force_n=np.max(forces, axis=0), bending_nm=np.max(bending, axis=0),
                       weakest_stiffness_n_per_m=np.linalg.eigvalsh(np.linalg.inv(compliance))[:, 0],
                       vertical_stiffness_n_per_m=1.0 / compliance[:, 1, 1], tilt_rad=tilt,
                       max_relative_residual=residual)


def upu_figures(machine: Machine, heights: int = COMPARE_HEIGHTS, grid: int = COMPARE_GRID,
                modes: bool = True, play: bool = True) -> MachineFigures:
    """The comparison figures of a UPU machine (module docstring) over :func:`compare_box`; ``modes``/``play``
    False leave those figures NaN (a quick look)."""
    from pressfit.dynamics.modes import natural_modes
    from pressfit.studies.preload_study import preload_study

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
    lost, lost_pre, best, note = float("nan"), None, None, "not computed"
    if play:
        lost, lost_pre, best, note = _lost_motion(machine, centre, preload_study)
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
        moving_mass_kg=mass, lost_motion_m=lost, lost_motion_preloaded_m=lost_pre, best_preload_n=best,
        preload_note=note, max_relative_residual=f.max_relative_residual)


def _lost_motion(machine: Machine, pose: np.ndarray, study: Any) -> tuple[float, float | None, float | None, str]:
    """Lost motion (m) with PLAY_M of cardan play at ``pose`` under the press load: without preload, with the
    critical preload (N), the preload, and a note."""
    from pressfit.mechanics.clearance import Clearance, critical_preloads

    play = Clearance.uniform(machine).with_gap(PLAY_M)
    if len(machine.legs) <= 3:
        s = study(machine, pose, [play], [0.0], PRESS_LOAD_N, progress=False)
        return float(s.lost_motion_m[0, 0]), None, None, (f"{len(machine.legs)} legs: no redundant actuation, no "
                                                          "internal preload")
    crit = critical_preloads(machine, pose, [0.0, 1.0, 0.0], PRESS_LOAD_N, [play])[0].preload
    s = study(machine, pose, [play], [crit], PRESS_LOAD_N, progress=False)
    k = int(np.flatnonzero(s.preloads == crit)[0])
    return (float(s.lost_motion_m[0, 0]), float(s.lost_motion_m[0, k]), float(crit),
            "the critical preload: the smallest that keeps every cardan closed up to the press load")


@dataclass(frozen=True, kw_only=True)
class Claim:
    """One of the paper's two claims against its baseline: ``verdict`` "confirmed", "refuted" or "not measured"
    (the baseline is not among the machines compared), with the numbers that decide it."""

    claim: str  # the paper's words
    baseline: str  # what it is measured against
    verdict: str
    evidence: str


PRECISION_CLAIM = ("against the Cartesian press, the 4-UPU \"could improve the precision of the positioning "
                   "movements\": the tool's stiffness and tilt under the press load")
MEMBER_CLAIM = ("against the Cartesian press, the 4-UPU \"could improve ... the stiffness of the structural "
                "elements\" (the gantry's X and Z beams carry large bending moments): the worst bending moment in any "
                "member")
PRELOAD_CLAIM = ("\"thanks to the additional leg, the proposed solution allows a preload that is capable of "
                 "compensating the backlash of joints\" (against Tsai's non-redundant 3-UPU)")
BACKLASH_COMPENSATED = 0.01  # the preload compensates the backlash when it leaves < 1% of the 3-UPU's lost motion


def claims(figures: list[MachineFigures]) -> list[Claim]:
    """The paper's claims decided from the compared machines, the redundant 4-UPU being the first UPU machine with 4
    legs: against the first gantry, precision (confirmed when the 4-UPU's weakest and vertical tool stiffness, worst
    over the box, are both higher and its worst tilt lower) and the members (confirmed when its worst member bending
    moment is lower); against the first 3-leg UPU, the backlash (confirmed when the 4-UPU's lost motion with its
    best preload is below ``BACKLASH_COMPENSATED`` of the 3-UPU's, which no preload can change, and the drives
    carry that preload on top of their worst press force: a4 + the worst drive force within the drive force limit,
    a4 bounding each leg's share |a4 v_i|). "not measured" when the baseline is not among the machines."""
    upu4 = next((f for f in figures if f.kind == "upu" and f.legs == 4), None)
    gantry = next((f for f in figures if f.kind == "gantry"), None)
    upu3 = next((f for f in figures if f.kind == "upu" and f.legs == 3), None)
    out = []
    if upu4 is None or gantry is None:
        out += [Claim(claim=c, baseline="a Cartesian gantry", verdict="not measured",
                      evidence="compare a 4-leg UPU machine and a gantry machine file")
                for c in (PRECISION_CLAIM, MEMBER_CLAIM)]
    else:
        better = (upu4.weakest_stiffness_worst_n_per_m > gantry.weakest_stiffness_worst_n_per_m
                  and upu4.vertical_stiffness_worst_n_per_m > gantry.vertical_stiffness_worst_n_per_m
                  and upu4.tilt_worst_rad < gantry.tilt_worst_rad)
        out.append(Claim(
            claim=PRECISION_CLAIM, baseline=gantry.name, verdict="confirmed" if better else "refuted",
            evidence=(f"weakest tool stiffness (worst over the box) {upu4.weakest_stiffness_worst_n_per_m:.4g} N/m "
                      f"({upu4.name}) against {gantry.weakest_stiffness_worst_n_per_m:.4g} N/m ({gantry.name}); "
                      f"vertical {upu4.vertical_stiffness_worst_n_per_m:.4g} against "
                      f"{gantry.vertical_stiffness_worst_n_per_m:.4g} N/m; tool tilt under the press load (worst) "
                      f"{upu4.tilt_worst_rad:.3g} against {gantry.tilt_worst_rad:.3g} rad; moving mass "
                      f"{upu4.moving_mass_kg:.4g} against {gantry.moving_mass_kg:.4g} kg")))
        out.append(Claim(
            claim=MEMBER_CLAIM, baseline=gantry.name,
            verdict="confirmed" if upu4.worst_bending_nm < gantry.worst_bending_nm else "refuted",
            evidence=(f"worst member bending moment {upu4.worst_bending_nm:.4g} N m ({upu4.name}, "
                      f"{upu4.worst_bending_member}) against {gantry.worst_bending_nm:.4g} N m ({gantry.name}, "
                      f"{gantry.worst_bending_member})")))
    if upu4 is None or upu3 is None or upu4.lost_motion_preloaded_m is None or not np.isfinite(upu3.lost_motion_m):
        out.append(Claim(claim=PRELOAD_CLAIM, baseline="a 3-leg UPU", verdict="not measured",
                         evidence="compare a 4-leg and a 3-leg UPU machine file with the play figures"))
    else:
        left = max(upu4.lost_motion_preloaded_m, 0.0)
        carried = upu4.best_preload_n + upu4.worst_drive_force_n
        ok = left < BACKLASH_COMPENSATED * upu3.lost_motion_m and carried <= upu4.drive_force_limit_n
        out.append(Claim(
            claim=PRELOAD_CLAIM, baseline=upu3.name, verdict="confirmed" if ok else "refuted",
            evidence=(f"with {PLAY_M * 1e6:g} um of play in every cardan, at the box's centre under the press load: "
                      f"lost motion {upu3.lost_motion_m * 1e6:.3g} um ({upu3.name}: {upu3.preload_note}) against "
                      f"{upu4.lost_motion_m * 1e6:.3g} um without preload and {left * 1e6:.3g} um with a preload of "
                      f"{upu4.best_preload_n:.4g} N ({upu4.name}); with it the drives carry up to {carried:.4g} N "
                      f"({upu4.best_preload_n:.4g} N of preload on their {upu4.worst_drive_force_n:.4g} N worst press "
                      f"force) against their {upu4.drive_force_limit_n:.4g} N limit")))
    return out


@dataclass(frozen=True, kw_only=True)
class Comparison:
    """The machines' figures and the two claims (:func:`claims`)."""

    machines: list[MachineFigures]
    claims: list[Claim]

    def to_dict(self) -> dict[str, Any]:
        return {"machines": [m.to_dict() for m in self.machines], "claims": [c.__dict__ for c in self.claims],
                "play_m": PLAY_M, "press_load_n": PRESS_LOAD_N, "cone_half_angle_rad": CONE_HALF_ANGLE_RAD}


def gantry_figures(gantry: Gantry, heights: int = COMPARE_HEIGHTS, grid: int = COMPARE_GRID) -> MachineFigures:
    """The comparison figures of a gantry (module docstring)."""
    from pressfit.dynamics.gantry_modes import gantry_metrics
    from pressfit.mechanics.gantry import build_gantry_model

    ws = gantry.workspace
    x, z = np.linspace(-ws.x_half_width_m, ws.x_half_width_m, grid), np.linspace(-ws.z_half_width_m,
                                                                               ws.z_half_width_m, grid)
    y = np.linspace(ws.tool_height_min_m, ws.tool_height_min_m + REQUIRED_HEIGHT_M, heights)
    yy, zz, xx = np.meshgrid(y, z, x, indexing="ij")
    poses = np.stack([xx, yy, zz], -1).reshape(-1, 3)
    loads = press_loads(PRESS_LOAD_N, CONE_HALF_ANGLE_RAD, CONE_DIRECTIONS)
    m = gantry_metrics(gantry, poses, np.column_stack([loads, np.zeros_like(loads)]))
    vertical = np.array([1.0 / np.linalg.inv(build_gantry_model(gantry, p).tool_stiffness_n_per_m())[1, 1]
                         for p in poses])
    tilt = np.array([np.linalg.norm(build_gantry_model(gantry, p).solve(np.array([0.0, PRESS_LOAD_N, 0.0, 0.0, 0.0,
                                                                                   0.0])).tool_rotation_rad)
                     for p in poses])
    return MachineFigures(
        name=gantry.name, source=str(gantry.source or gantry.name), kind="gantry", legs=None,
        heights_m=(float(y[0]), float(y[-1])), poses=len(poses), worst_drive_force_n=m.worst_drive_force_n,
        drive_force_limit_n=float("nan"),
        worst_drive_force_pose_m=m.worst_drive_pose_m, worst_bending_nm=m.worst_bending_moment_nm,
        worst_bending_member=m.worst_bending_member, weakest_stiffness_worst_n_per_m=m.min_tool_stiffness_n_per_m,
        weakest_stiffness_median_n_per_m=m.median_tool_stiffness_n_per_m,
        vertical_stiffness_worst_n_per_m=float(vertical.min()),
        vertical_stiffness_median_n_per_m=float(np.median(vertical)), tilt_worst_rad=float(tilt.max()),
        tilt_median_rad=float(np.median(tilt)), first_frequency_lowest_hz=m.first_frequency_hz,
        first_frequency_median_hz=float("nan"), moving_mass_kg=m.moving_mass_kg, lost_motion_m=float("nan"),
        lost_motion_preloaded_m=None, best_preload_n=None,
        preload_note="the gantry's guides and screws have no play model", max_relative_residual=m.worst_residual)


def compare(machines: list[Machine | Gantry], progress: bool = True, heights: int = COMPARE_HEIGHTS,
            grid: int = COMPARE_GRID) -> Comparison:
    """Every machine's figures (:func:`upu_figures`, :func:`gantry_figures`, on ``heights`` x ``grid`` x ``grid``
    box poses) and the claims."""
    from tqdm import tqdm

    figures = [gantry_figures(m, heights, grid) if isinstance(m, Gantry) else upu_figures(m, heights, grid)
               for m in tqdm(machines, desc="compare", unit="machine", disable=not progress)]
    return Comparison(machines=figures, claims=claims(figures))
