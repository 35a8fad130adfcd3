"""Workspace of the n-UPU (paper section 4.1, Table 3, Figures 6-11): reachable set, the height range of
the required square, maps of n, F_x, F_y, F_z and dl_i/dh on x-z planes, and their statistics.

Lengths in m, angles of the square in degrees (about the vertical y axis), indices dimensionless (N/N).
The reachable set is :func:`pressfit.kinematics.is_reachable` (Table 3's limits on l, alpha, beta).

Definitions used in every output:
- *required square*: the x-z rectangle of half-widths ``machine.workspace`` (500 x 500 mm), centred on
  the y axis, rotated by ``angle_deg`` about y; sampled by its boundary (``BOUNDARY_STEP_M``) and an
  interior grid (``INTERIOR_POINTS`` per side). Corners and edge midpoints are always samples.
- *variation* of n over the square: (max - min) / max.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict, dataclass

import numpy as np

from pressfit import kinematics
from pressfit.description.machine import Machine
from pressfit.errors import WorkspaceError

BOUNDARY_STEP_M = 5e-4
INTERIOR_POINTS = 41
HEIGHT_TOLERANCE_M = 1e-7
MAP_HALF_EXTENT_M = 0.4
MAP_STEP_M = 0.005
DEFAULT_HEIGHTS_M = (0.6,)  # the paper's Figures 7-11 and Table 4
DEFAULT_ANGLES_DEG = (0.0, 45.0, 90.0)
VARIATION_DEFINITION = "(max - min) / max over the required square (boundary + interior grid)"


def square_corners(machine: Machine, angle_deg: float = 0.0) -> np.ndarray:
    """x-z corners (4, 2) of the required square rotated by ``angle_deg`` about y, m."""
    a, b = machine.workspace.x_half_width_m, machine.workspace.z_half_width_m
    return _rotate(np.array([[a, b], [-a, b], [-a, -b], [a, -b]]), angle_deg)


def square_points(machine: Machine, angle_deg: float = 0.0, boundary_step_m: float = BOUNDARY_STEP_M,
                  interior: int = INTERIOR_POINTS) -> np.ndarray:
    """x-z samples (k, 2) of the rotated required square: its boundary and an interior grid, m."""
    corners = square_corners(machine, 0.0)
    edges = []
    for c0, c1 in zip(corners, np.roll(corners, -1, axis=0), strict=True):
        k = 2 * int(np.ceil(np.linalg.norm(c1 - c0) / boundary_step_m / 2))  # even: midpoint included
        edges.append(c0 + np.linspace(0.0, 1.0, k, endpoint=False)[:, None] * (c1 - c0))
    a, b = machine.workspace.x_half_width_m, machine.workspace.z_half_width_m
    gx, gz = np.meshgrid(np.linspace(-a, a, interior), np.linspace(-b, b, interior))
    return _rotate(np.vstack(edges + [np.column_stack([gx.ravel(), gz.ravel()])]), angle_deg)


def _rotate(xz: np.ndarray, angle_deg: float) -> np.ndarray:
    """Rotate x-z points about y by ``angle_deg`` (right-handed about +y: z -> x)."""
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    return np.column_stack([c * xz[:, 0] + s * xz[:, 1], -s * xz[:, 0] + c * xz[:, 1]])


def _poses(xz: np.ndarray, y_m: float) -> np.ndarray:
    return np.column_stack([xz[:, 0], np.full(len(xz), y_m), xz[:, 1]])


@dataclass(frozen=True, kw_only=True)
class HeightRange:
    """Heights y_h (m) at which every sample of the rotated required square is reachable."""

    angle_deg: float
    y_min_m: float
    y_max_m: float
    tolerance_m: float  # bisection bracket width (the sampling of the square adds < 1e-6 m, see tests)
    limit_below: str  # the limit the worst sample breaks just below y_min
    limit_above: str  # ... and just above y_max


def square_height_range(machine: Machine, angle_deg: float = 0.0, tolerance_m: float = HEIGHT_TOLERANCE_M,
                        scan_step_m: float = 1e-2) -> HeightRange:
    """Bisect on the worst sample of the square for the lowest and highest height where all is reachable.

    A scan of y in steps of ``scan_step_m`` up to l_max brackets both ends and checks that the feasible
    heights form one interval (else :class:`WorkspaceError`).
    """
    xz = square_points(machine, angle_deg)

    def ok(y: float) -> bool:
        return bool(np.all(kinematics.is_reachable(machine, _poses(xz, y))))

    ys = np.arange(scan_step_m, machine.limits.leg_length_max_m + scan_step_m, scan_step_m)
    feasible = np.flatnonzero([ok(y) for y in ys])
    if feasible.size == 0:
        raise WorkspaceError(float(angle_deg), [], scan_step_m)
    if feasible[-1] - feasible[0] + 1 != feasible.size:
        raise WorkspaceError(float(angle_deg), ys[feasible].round(4).tolist(), scan_step_m)

    def bisect(good: float, bad: float) -> tuple[float, float]:
        while abs(good - bad) > tolerance_m:
            mid = 0.5 * (good + bad)
            good, bad = (mid, bad) if ok(mid) else (good, mid)
        return good, bad

    lo = bisect(ys[feasible[0]], ys[feasible[0] - 1] if feasible[0] > 0 else 0.0)
    hi = bisect(ys[feasible[-1]], ys[feasible[-1]] + scan_step_m)
    return HeightRange(angle_deg=float(angle_deg), y_min_m=float(lo[0]), y_max_m=float(hi[0]), tolerance_m=tolerance_m,
                       limit_below=_first_violation(machine, xz, lo[1]),
                       limit_above=_first_violation(machine, xz, hi[1]))


def _first_violation(machine: Machine, xz: np.ndarray, y_m: float) -> str:
    poses = _poses(xz, y_m)
    bad = np.flatnonzero(~kinematics.is_reachable(machine, poses))
    if bad.size == 0:
        return "none"
    h = poses[bad[0]]
    return f"at (x, y, z) = ({h[0]:.4f}, {h[1]:.6f}, {h[2]:.4f}) m: {kinematics.unreachable_reason(machine, h)}"


@dataclass(frozen=True, kw_only=True)
class SquareStats:
    """Dexterity and force indices over the rotated required square at one height (N/N, -)."""

    y_m: float
    angle_deg: float
    all_reachable: bool
    dexterity_min: float
    dexterity_max: float
    dexterity_variation: float  # VARIATION_DEFINITION
    force_index_min: tuple[float, float, float]  # (F_x, F_y, F_z), eqs. 6-8
    force_index_max: tuple[float, float, float]


def square_statistics(machine: Machine, y_m: float, angle_deg: float = 0.0,
                      half_width_m: float | None = None) -> SquareStats:
    """Min/max of n (eq. 4) and of F_x, F_y, F_z (eqs. 6-8) over the required square at height y_m.

    ``half_width_m`` replaces the required square by a centred square of that half-side (m).
    """
    if half_width_m is not None:
        machine = machine.with_overrides({"workspace": {"x_half_width_m": half_width_m,
                                                        "z_half_width_m": half_width_m}})
    poses = _poses(square_points(machine, angle_deg), y_m)
    ix = kinematics.indices(machine, poses)
    n_min, n_max = float(ix.dexterity.min()), float(ix.dexterity.max())
    return SquareStats(y_m=float(y_m), angle_deg=float(angle_deg),
                       all_reachable=bool(np.all(kinematics.is_reachable(machine, poses))), dexterity_min=n_min,
                       dexterity_max=n_max, dexterity_variation=(n_max - n_min) / n_max,
                       force_index_min=tuple(ix.force_indices.min(axis=0).tolist()),
                       force_index_max=tuple(ix.force_indices.max(axis=0).tolist()))


def dexterity_half_width(machine: Machine, y_m: float, variation: float = 0.15,
                         tolerance_m: float = 1e-5) -> float:
    """Largest half-side s (m) of a centred axis-aligned square over which n varies <= ``variation``.

    Bisection on s in (0, the required half-width]; returns the required half-width if it already holds.
    """
    hi = max(machine.workspace.x_half_width_m, machine.workspace.z_half_width_m)
    if square_statistics(machine, y_m, half_width_m=hi).dexterity_variation <= variation:
        return hi
    lo = 0.0
    while hi - lo > tolerance_m:
        mid = 0.5 * (lo + hi)
        if square_statistics(machine, y_m, half_width_m=mid).dexterity_variation <= variation:
            lo = mid
        else:
            hi = mid
    return lo


@dataclass(frozen=True, kw_only=True)
class PlaneMap:
    """Maps on the x-z plane at height y_m (the paper's Figures 7-11); NaN where not reachable."""

    y_m: float
    x_m: np.ndarray  # (nx,)
    z_m: np.ndarray  # (nz,)
    reachable: np.ndarray  # (nz, nx) bool
    dexterity: np.ndarray  # n, eq. 4, (nz, nx)
    force_indices: np.ndarray  # F_x, F_y, F_z, eqs. 6-8, (nz, nx, 3)
    leg_rates: np.ndarray  # dl_i/dh (eqs. 2-3), (nz, nx, n, 3), m/m


def plane_map(machine: Machine, y_m: float, half_extent_m: float = MAP_HALF_EXTENT_M,
              step_m: float = MAP_STEP_M) -> PlaneMap:
    """Evaluate n, F and dl/dh on a square x-z grid of half-side ``half_extent_m`` at height ``y_m``."""
    k = int(round(2 * half_extent_m / step_m)) + 1
    x = z = np.linspace(-half_extent_m, half_extent_m, k)
    gx, gz = np.meshgrid(x, z)
    poses = np.stack([gx, np.full_like(gx, y_m), gz], axis=-1)
    ok = kinematics.is_reachable(machine, poses)
    ix = kinematics.indices(machine, poses)
    rates = kinematics.jacobian(machine, poses)
    mask = np.where(ok, 1.0, np.nan)
    return PlaneMap(y_m=float(y_m), x_m=x, z_m=z, reachable=ok, dexterity=ix.dexterity * mask,
                    force_indices=ix.force_indices * mask[..., None], leg_rates=rates * mask[..., None, None])


_AXES = "xyz"


def map_rows(pm: PlaneMap) -> tuple[list[str], np.ndarray]:
    """CSV header and rows of a plane map: one row per grid point (x varies fastest)."""
    legs = pm.leg_rates.shape[-2]
    header = ["x_m", "y_m", "z_m", "reachable", "dexterity", "F_x", "F_y", "F_z"] + [
        f"dl{i + 1}_d{a}" for i in range(legs) for a in _AXES]
    gx, gz = np.meshgrid(pm.x_m, pm.z_m)
    cols = [gx.ravel(), np.full(gx.size, pm.y_m), gz.ravel(), pm.reachable.ravel().astype(float),
            pm.dexterity.ravel()] + [pm.force_indices[..., j].ravel() for j in range(3)] + [
        pm.leg_rates[..., i, j].ravel() for i in range(legs) for j in range(3)]
    return header, np.column_stack(cols)


def summary(machine: Machine, heights_m: Iterable[float] = DEFAULT_HEIGHTS_M,
            angles_deg: Iterable[float] = DEFAULT_ANGLES_DEG, workspace_heights: int = 27) -> dict[str, object]:
    """JSON-ready summary: height range per square orientation, statistics per height and orientation,
    the worst force indices over the whole reachable-square height range, and the half-side within
    which n varies at most 15 % (the paper's claim)."""
    angles, heights = list(angles_deg), [float(y) for y in heights_m]
    ranges = {a: square_height_range(machine, a) for a in angles}
    stats = [asdict(square_statistics(machine, y, a)) for y in heights for a in angles]
    over = {}
    for a, r in ranges.items():
        ys = np.linspace(r.y_min_m, r.y_max_m, workspace_heights)
        worst = np.max([square_statistics(machine, y, a).force_index_max for y in ys], axis=0)
        over[f"{a:g}"] = {"y_from_m": r.y_min_m, "y_to_m": r.y_max_m, "heights": workspace_heights,
                          "force_index_max": worst.tolist()}
    return {
        "definitions": {
            "required_square_half_widths_m": [machine.workspace.x_half_width_m,
                                              machine.workspace.z_half_width_m],
            "square_sampling": f"boundary every {BOUNDARY_STEP_M} m + {INTERIOR_POINTS}^2 interior grid",
            "angle_deg": "rotation of the square about +y",
            "dexterity_variation": VARIATION_DEFINITION,
            "force_indices": "max_i |F_i| per unit plate force along x, y, z (Moore-Penrose, eqs. 5-8)",
        },
        "height_range": [asdict(r) for r in ranges.values()],
        "squares": stats,
        "workspace_force_index_max": over,
        "dexterity_variation_15pct_half_width_m": {
            f"{y:g}": dexterity_half_width(machine, y, 0.15) for y in heights},
    }


# --- stiffness maps over the x-z workspace square ------------------------------------------------
def workspace_square(machine: Machine, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(x, z) grid coordinates, n points each over the required workspace square, m."""
    ws = machine.workspace
    return np.linspace(-ws.x_half_width_m, ws.x_half_width_m, n), np.linspace(-ws.z_half_width_m, ws.z_half_width_m, n)


def workspace_box(machine: Machine, y_m: np.ndarray, n_xz: int) -> np.ndarray:
    """Poses (len(y_m), n_xz, n_xz, 3), m, indexed [i_y, i_z, i_x]: the :func:`workspace_square` grid at
    each height y_m (m). The one workspace grid of the sweeps (load envelope, interference)."""
    x, z = workspace_square(machine, n_xz)
    yy, zz, xx = np.meshgrid(np.atleast_1d(np.asarray(y_m, dtype=float)), z, x, indexing="ij")
    return np.stack([xx, yy, zz], -1)
