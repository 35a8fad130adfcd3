r"""The preload that keeps every cardan closed along the whole load path, over many poses and load directions at
once (the backlash claim of paper section 4.1, decided over the required box: ``pressfit compare``). SI units.

Per pose h and load direction u, the press load is swept from 0 to F in ``steps`` equal steps (each solve started
from the previous one) on the small-displacement clearance model (:mod:`pressfit.mechanics.clearance`: each leg its
axial spring in series with its two cardans' plays, batched here over poses x directions); a preload of amplitude
a (N) along the unit leg-force direction v (:func:`pressfit.mechanics.preload.closing_direction`: v_p on the
4-UPU) puts a v_i on leg i before the load, the play extensions included (so every cardan with v_i != 0 starts
closed). A cardan is closed when |x| >= its effective gap; the **critical preload** of (h, u) is the smallest a
that keeps every cardan closed at every step (bisection to ``1e-4 F``), so a cardan that opens in the middle of the
path and closes again on its other side is seen. The pose's critical preload is the largest over the directions
(the press does not know the misalignment); NaN where no preload up to ``2^GROWTH`` F closes every cardan (a leg
with no share of the preload).

With the pose's critical preload applied the sweep is run once more over every direction: the **drive forces** are
the legs' spring forces max |a v_i + N_i(load)| over the path and the directions (computed, not bounded), and the
**lost motion** is the deflection along the load at F minus that of the same machine and preload with no play
(g = 0, the contact springs kept): the play the load path takes up, wherever along the path it happens. The same
without preload gives the lost motion the play costs an unpreloaded machine (a 3-leg machine has only this one).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pressfit.description.machine import Machine
from pressfit.errors import ResidualError
from pressfit.mechanics import condensed
from pressfit.mechanics.clearance import _Chain
from pressfit.mechanics.clearance_law import Clearance, invert_law
from pressfit.mechanics.preload import closing_direction

STEPS = 50  # load steps from 0 to the press load
GROWTH = 12  # the bracket grows up to 2^GROWTH times the press load
RELATIVE_TOL = 1e-4  # the bisection's bracket, a fraction of the press load
RESIDUAL_TOL = 1e-8  # the relative equilibrium residual every solve must reach


@dataclass(frozen=True, kw_only=True)
class ClosingPreload:
    """Per pose (k poses, n legs, d load directions) the critical preload and what it costs (module doc)."""

    poses_m: np.ndarray  # (k, 3)
    directions: np.ndarray  # (d, 3) unit load directions
    press_load_n: float
    preload_direction: np.ndarray  # (k, n) unit leg forces of the preload (v_p on the 4-UPU); NaN: no preload
    critical_preload_n: np.ndarray  # (k,) the largest over the directions; NaN: none closes every cardan
    critical_preload_by_direction_n: np.ndarray  # (k, d)
    drive_forces_n: np.ndarray  # (k, n) max |N_i| over the path and directions with the pose's critical preload
    lost_motion_m: np.ndarray  # (k,) worst over the directions with the pose's critical preload
    lost_motion_unpreloaded_m: np.ndarray  # (k,) worst over the directions without preload
    max_relative_residual: float


def _model(machine: Machine, poses: np.ndarray, clearance: Clearance, gaps: bool) -> _Chain:
    core = condensed._core(machine, poses)
    g = np.array([clearance.effective_gaps_m(machine, h) for h in poses]) if gaps else np.zeros((len(poses),
                                                                                                 len(machine.legs), 2))
    return _Chain(u=core.e.transpose(2, 1, 0), k=core.k_a.T, gaps=g, kc=clearance.contact_stiffness_n_per_m,
                  w=clearance.smoothing_m)


def _preloaded_start(chain: _Chain, compliance: np.ndarray, forces_n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rest-length offsets (B, n), m, that put ``forces_n`` (B, n) on the legs at no load with the plate where it
    is (the play extensions included: :func:`pressfit.mechanics.preload.rest_length_offsets`), and that state."""
    x = invert_law(np.repeat(forces_n[:, :, None], 2, 2), chain.gaps, chain.kc, chain.w)
    offsets = -(forces_n * compliance + x.sum(2))
    return offsets, np.concatenate([np.zeros((len(forces_n), 3)), x.reshape(len(forces_n), -1)], 1)


def _sweep(chain: _Chain, compliance: np.ndarray, forces_n: np.ndarray, loads: np.ndarray,
           directions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Every member's loading path: (closed at every step (B,), max |N_i| (B, n), deflection along the load at the
    last step (B,), m, worst residual)."""
    offsets, z = _preloaded_start(chain, compliance, forces_n)
    closed, peak, worst = np.ones(len(z), bool), np.abs(forces_n), 0.0
    for f in loads[1:]:
        z, n, res = chain.solve(f * directions, offsets, z)
        worst = max(worst, res)
        closed &= np.all(np.abs(z[:, 3:].reshape(n.shape + (2,))) >= chain.gaps, axis=(1, 2))
        peak = np.maximum(peak, np.abs(n))
    return closed, peak, (z[:, :3] * directions).sum(1), worst


def closing_preload(machine: Machine, poses_m: np.ndarray, directions: np.ndarray, press_load_n: float,
                    clearance: Clearance, steps: int = STEPS) -> ClosingPreload:
    """:class:`ClosingPreload` at poses (k, 3), m, for unit load directions (d, 3) of magnitude press_load_n (N),
    with the cardans' plays ``clearance`` (module doc). A 3-leg machine: no preload (NaN), the lost motion
    without preload only."""
    poses, dirs = np.atleast_2d(np.asarray(poses_m, float)), np.atleast_2d(np.asarray(directions, float))
    k, d, n = len(poses), len(dirs), len(machine.legs)
    member_poses, member_dirs = np.repeat(poses, d, 0), np.tile(dirs, (k, 1))
    chain, free = _model(machine, member_poses, clearance, True), _model(machine, member_poses, clearance, False)
    compliance = 1.0 / chain.k
    loads = np.linspace(0.0, float(press_load_n), int(steps) + 1)
    v = closing_direction(machine, poses) if machine.redundancy else np.full((k, n), np.nan)
    vm = np.repeat(v, d, 0)
    residual = 0.0

    def closed(a: np.ndarray) -> np.ndarray:
        nonlocal residual
        ok, _, _, res = _sweep(chain, compliance, np.nan_to_num(a[:, None] * vm), loads, member_dirs)
        residual = max(residual, res)
        return ok

    crit = np.full(k * d, np.nan)
    if machine.redundancy:
        _, load_only, res = free.solve(float(press_load_n) * member_dirs, np.zeros((k * d, n)), None)
        residual = max(residual, res)
        with np.errstate(divide="ignore", invalid="ignore"):  # a leg without a share: no bracket (NaN)
            guess = np.where(load_only * vm < 0, np.abs(load_only) / np.abs(vm), 0.0).max(1)
        crit = _bisect(closed, guess, float(press_load_n))
    pose_crit = crit.reshape(k, d).max(1)
    forces = np.nan_to_num(np.repeat(pose_crit, d)[:, None] * vm)
    _, peak, bent, res_pre = _sweep(chain, compliance, forces, loads, member_dirs)
    _, _, bent_free, res_free = _sweep(free, compliance, forces, loads[[0, -1]], member_dirs)
    _, _, bent0, res0 = _sweep(chain, compliance, np.zeros((k * d, n)), loads, member_dirs)
    _, _, bent0_free, res0_free = _sweep(free, compliance, np.zeros((k * d, n)), loads[[0, -1]], member_dirs)
    residual = max(residual, res_pre, res_free, res0, res0_free)
    if residual > RESIDUAL_TOL:
        raise ResidualError("closing preload: clearance solve", "relative equilibrium residual", residual,
                            RESIDUAL_TOL)
    has = np.isfinite(pose_crit)
    return ClosingPreload(
        poses_m=poses, directions=dirs, press_load_n=float(press_load_n), preload_direction=v,
        critical_preload_n=pose_crit, critical_preload_by_direction_n=crit.reshape(k, d),
        drive_forces_n=np.where(has[:, None], peak.reshape(k, d, n).max(1), np.nan),
        lost_motion_m=np.where(has, (bent - bent_free).reshape(k, d).max(1), np.nan),
        lost_motion_unpreloaded_m=(bent0 - bent0_free).reshape(k, d).max(1), max_relative_residual=residual)


def _bisect(closed: Callable[[np.ndarray], np.ndarray], guess: np.ndarray, scale: float) -> np.ndarray:
    """The smallest a >= 0 with closed(a) for each member (NaN: none up to 2^GROWTH scale), to RELATIVE_TOL scale;
    ``closed`` maps amplitudes (B,) to booleans and is monotone in a. The bracket starts about ``guess`` (B,) (the
    preload that a closed-joint, linear model would need: every leg's preload share a |v_i| at least its load
    share) and is checked by ``closed`` at both ends before it is bisected: widened upwards (doubled) where its top
    lets a cardan open, down to 0 where its bottom keeps every cardan closed; the answer is the sweeps'."""
    width = np.nan_to_num(0.02 * guess, nan=0.0) + 1e-2 * scale
    lo = np.clip(np.nan_to_num(guess, nan=0.0) - width, 0.0, None)
    hi = np.where(np.isfinite(guess), guess + width, scale)
    ok = closed(hi)
    for _ in range(GROWTH):
        if ok.all():
            break
        lo, hi = np.where(ok, lo, hi), np.where(ok, hi, 2 * hi)
        ok = ok | closed(hi)
    found = ok & (hi <= 2.0**GROWTH * scale)
    low_closed = closed(np.where(found, lo, 0.0)) & (lo > 0)
    hi, lo = np.where(low_closed, lo, hi), np.where(low_closed, 0.0, lo)
    while np.max(np.where(found, hi - lo, 0.0)) > RELATIVE_TOL * scale:
        mid = 0.5 * (lo + hi)
        now = closed(np.where(found, mid, 0.0))
        lo, hi = np.where(now, lo, mid), np.where(now, mid, hi)
    return np.where(found, hi, np.nan)
