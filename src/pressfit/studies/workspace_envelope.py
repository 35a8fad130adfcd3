"""Workspace load envelope: the worst leg loads and plate motions over the required workspace box and a
set of plate loads, from the exact condensed linear model (:mod:`pressfit.mechanics.condensed`),
vectorised over poses. This is the design-load sweep shown in the report; the CI limit check of case
files is :mod:`pressfit.studies.limit_check`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from tqdm import tqdm

from pressfit.description.machine import Machine
from pressfit.errors import PressfitError
from pressfit.kinematics import is_reachable
from pressfit.kinematics.workspace import workspace_box, workspace_square
from pressfit.mechanics.condensed import _CHUNK, PRESS_LOAD_N, _as_wrench, _core, _solve_core
from pressfit.spatial import cone_directions


# --- workspace load envelope ---------------------------------------------------------------------
def press_loads(force_n: float = PRESS_LOAD_N, cone_half_angle_rad: float = 0.0, n_azimuth: int = 8) -> np.ndarray:
    """Load directions (L, 3), N: the press force along +y, plus n_azimuth forces of the same magnitude
    on a cone of the given half-angle about +y (when the angle is > 0)."""
    return force_n * cone_directions(np.array([0.0, 1.0, 0.0]), cone_half_angle_rad, n_azimuth)


LEG_QUANTITIES = {  # name -> (unit, description)
    "tension_n": ("N", "max axial force N (tension; negative if never in tension)"),
    "compression_n": ("N", "max -N (compression; negative if never in compression)"),
    "bending_x_nm": ("N m", "max |M_x|"),
    "bending_y_nm": ("N m", "max |M_y|"),
    "torsion_nm": ("N m", "max |T|"),
    "bending_nm": ("N m", "max bending magnitude hypot(M_x, M_y)"),
}


PLATE_QUANTITIES = {"tilt_rad": ("rad", "max plate tilt |rotation|"),
                    "deflection_m": ("m", "max plate-centre displacement |delta|")}


@dataclass(frozen=True, kw_only=True)
class EnvelopeEntry:
    """The worst value of one quantity: per leg (shape (n,), n legs) or for the plate (shape ()), with the pose
    (m) and the force (N, at the plate centre) where it happens (shapes (n, 3) or (3,))."""

    value: np.ndarray
    pose_m: np.ndarray
    load_n: np.ndarray


@dataclass(frozen=True, kw_only=True)
class LoadEnvelope:
    """Workspace load envelope of the condensed linear model (SI). ``entries`` holds every name of
    LEG_QUANTITIES and PLATE_QUANTITIES; ``maps`` the worst value over y, loads and legs on the x-z grid
    (indexed [i_z, i_x]; NaN where no pose of the column is reachable)."""

    x_m: np.ndarray
    z_m: np.ndarray
    y_m: np.ndarray
    loads: np.ndarray  # (L, 6) wrenches at the plate centre, N and N m
    n_evaluated: int  # reachable poses evaluated (each under every load)
    n_unreachable: int  # grid poses skipped (outside the joint limits)
    entries: dict[str, EnvelopeEntry] = field(default_factory=dict)
    maps: dict[str, np.ndarray] = field(default_factory=dict)


def _sweep(machine: Machine, h: np.ndarray, loads: np.ndarray) -> dict[str, np.ndarray]:
    """Every enveloped quantity for poses h (P, 3) under each load (L, 6): (L, P, n) (n legs) or (L, P)."""
    p = h.shape[0]
    out = {k: np.empty((len(loads), p, len(machine.legs))) for k in LEG_QUANTITIES}
    out.update({k: np.empty((len(loads), p)) for k in PLATE_QUANTITIES})
    for i in range(0, p, _CHUNK):
        core = _core(machine, h[i:i + _CHUNK])
        sl = slice(i, i + _CHUNK)
        for j, w in enumerate(loads):
            delta, phi, n, _, _, _, mom, _, _ = _solve_core(machine, core, w[:, None])
            mom = np.abs(mom)
            for k, v in (("tension_n", n), ("compression_n", -n), ("bending_x_nm", mom[0]),
                         ("bending_y_nm", mom[1]), ("torsion_nm", mom[2]), ("bending_nm", np.hypot(mom[0], mom[1]))):
                out[k][j, sl] = v.T
            out["tilt_rad"][j, sl] = np.sqrt((phi * phi).sum(0))
            out["deflection_m"][j, sl] = np.sqrt((delta * delta).sum(0))
    return out


def load_envelope(machine: Machine, y_m: np.ndarray, n_xz: int = 51, loads_n: np.ndarray | None = None,
                  chunk_poses: int = 50_000, progress: bool | None = None) -> LoadEnvelope:
    """Per-leg worst loads over the required workspace box and a set of plate loads (linear model).

    Args:
        machine: the machine.
        y_m: the heights of the grid (m); x and z run over the required square with n_xz points each.
        loads_n: forces (L, 3) or wrenches (L, 6) at the plate centre; default :func:`press_loads`.
        chunk_poses: about this many (pose, load) pairs per step (whole y-levels at a time).
        progress: show a tqdm bar (default: when there is more than one step).
    Unreachable poses are skipped and counted.
    """
    loads = _as_wrench(press_loads() if loads_n is None else np.atleast_2d(loads_n))
    x, z = workspace_square(machine, n_xz)
    y = np.atleast_1d(np.asarray(y_m, dtype=float))
    grid = (z.size, x.size)  # one height of the box, [i_z, i_x]
    levels = max(1, chunk_poses // (z.size * x.size * len(loads)))
    chunks = [y[i:i + levels] for i in range(0, y.size, levels)]
    names = list(LEG_QUANTITIES) + list(PLATE_QUANTITIES)
    best: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    maps = {k: np.full(grid, -np.inf) for k in names}
    n_bad = 0
    show = len(chunks) > 1 if progress is None else progress
    for ys in tqdm(chunks, desc="load envelope", unit="y-step", disable=not show):
        h = workspace_box(machine, ys, n_xz).reshape(-1, 3)
        ok = is_reachable(machine, h)
        n_bad += int(np.sum(~ok))
        if not np.any(ok):
            continue
        q = _sweep(machine, h[ok], loads)
        for k in names:
            v = q[k].reshape((-1,) + q[k].shape[2:])  # (L * P, n) or (L * P,)
            i = np.argmax(v, axis=0)
            val = v[i, np.arange(v.shape[1])] if v.ndim > 1 else v[i]
            pose, load = h[ok][i % ok.sum()], loads[i // ok.sum(), :3]
            old = best.get(k)
            if old is not None:
                better = val > old[0]
                val, pose, load = (np.where(better, val, old[0]), np.where(better[..., None], pose, old[1]),
                                   np.where(better[..., None], load, old[2]))
            best[k] = (val, pose, load)
            col = np.full(ok.shape, -np.inf)
            col[ok] = q[k].max(0).max(-1) if q[k].ndim > 2 else q[k].max(0)
            maps[k] = np.maximum(maps[k], col.reshape((-1,) + grid).max(0))
    if not best:
        raise PressfitError("no pose of the envelope grid is reachable")
    return LoadEnvelope(x_m=x, z_m=z, y_m=y, loads=loads, n_evaluated=int(y.size * z.size * x.size - n_bad),
                        n_unreachable=n_bad,
                        entries={k: EnvelopeEntry(value=v, pose_m=p, load_n=f) for k, (v, p, f) in best.items()},
                        maps={k: np.where(np.isfinite(m), m, np.nan) for k, m in maps.items()})


def envelope_rows(env: LoadEnvelope) -> tuple[list[str], list[list[object]]]:
    """The envelope as a table: header and rows (quantity, unit, leg or 'plate', value, pose, load)."""
    header = ["quantity", "unit", "leg", "value", "x_m", "y_m", "z_m", "load_x_n", "load_y_n", "load_z_n"]
    rows: list[list[object]] = []
    for k, e in env.entries.items():
        unit = {**LEG_QUANTITIES, **PLATE_QUANTITIES}[k][0]
        if e.value.ndim == 0:
            rows.append([k, unit, "plate", float(e.value), *e.pose_m.tolist(), *e.load_n.tolist()])
        else:
            rows += [[k, unit, i + 1, float(e.value[i]), *e.pose_m[i].tolist(), *e.load_n[i].tolist()]
                     for i in range(e.value.size)]
    return header, rows


def worst_axial(env: LoadEnvelope) -> tuple[str, int, np.ndarray, np.ndarray]:
    """The largest axial leg force of the envelope, tension or compression: the quantity ('tension_n' or
    'compression_n'), the leg (1-based), the pose (3,) in m and the force (3,) in N where it happens."""
    name = max(("tension_n", "compression_n"), key=lambda k: float(env.entries[k].value.max()))
    e = env.entries[name]
    leg = int(np.argmax(e.value))
    return name, leg + 1, e.pose_m[leg], e.load_n[leg]
