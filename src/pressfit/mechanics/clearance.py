r"""Cardan clearance and actuator preload: load-deflection curves, lost motion, the preload that keeps
every joint closed (paper section 4.1's promise, quantified). SI units throughout. The clearance law (the
smoothed dead zone, the effective gaps of the three play geometries, :class:`Clearance`) is
:mod:`pressfit.mechanics.clearance_law`.

Preload (:func:`pressfit.mechanics.preload.rest_length_offsets` with a :class:`Clearance`)
---------------------------------------------------------------------------------------------
Actuator rest-length offsets along v_p, applied before the load. ``force`` mode: a4 in N, offsets
o_i = -(a4 v_i / k_a,i + x_b,i + x_p,i) with x the joint coordinates that carry a4 v_i
(:meth:`Clearance.play_extension_m`), so that with no load the actuator forces are exactly a4 v_p
(tension > 0) and every joint with v_i != 0 is closed; the offsets are then held (position-held after
setting). ``length`` mode: a4 in m, offsets -a4 v_p.

Two solvers
-----------
``method="small"`` (default for curves and studies): small displacements, the clearance nonlinearity
kept, exact for this structure: each leg is its axial spring in series with its two axial plays (and its
couple spring in series with the optional rotational plays), and about the concurrency point P* the
plate's translation and rotation decouple (:mod:`pressfit.condensed`). Each load step is a damped Newton
on the convex energy, batched over many (clearance, preload) pairs. ``method="nonlinear"``: the Pinocchio
VJM model with the axial plays as virtual prismatic joints (:func:`pressfit.mechanics.model.build_model`),
geometrically nonlinear Newton (:class:`pressfit.mechanics.statics.EquilibriumSolver`), each load step started from
the previous solution. The two agree to the geometric nonlinearity (about 1e-3 at 700 N, tested).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from pressfit import kinematics
from pressfit.description.cases import Case
from pressfit.description.machine import Machine
from pressfit.errors import ClearanceError, ConvergenceError
from pressfit.mechanics import condensed
from pressfit.mechanics.clearance_law import DEFAULT_SMOOTHING_M, ENDS, Clearance, dead_zones
from pressfit.mechanics.preload import Amplitudes, along_first_vector, rest_length_offsets, self_stress_forces_n

NEWTON_TOL = 1e-10  # relative force residual of the small-displacement solve


# --- small-displacement solver, batched --------------------------------------------------------------------
def _newton_step(u: np.ndarray, k: np.ndarray, t: np.ndarray, grad: np.ndarray) -> np.ndarray:
    """The Newton step -H^-1 grad (B, 3 + 2 n) of :meth:`_Chain.solve`, the joint block eliminated leg by leg: leg
    i's two plays (tangents t_b, t_p) and its spring k_i form a 2 x 2 block [[k + t_b, k], [k, k + t_p]] coupled to
    the plate by -k u_i on both, so the Schur complement on the plate is sum_i k_s,i u_i u_i^T with k_s the three
    springs in series, k t_b t_p / det, det = k (t_b + t_p) + t_b t_p (no cancellation when a play is open)."""
    b, nl = k.shape
    gd, gx = grad[:, :3], grad[:, 3:].reshape(b, nl, 2)
    tb, tp = t[..., 0], t[..., 1]
    det = k * (tb + tp) + tb * tp
    m = (tp * gx[..., 0] + tb * gx[..., 1]) / det  # 1^T M g_i
    schur = np.einsum("bi,bij,bik->bjk", k * tb * tp / det, u, u)
    dd = np.linalg.solve(schur, (-gd - np.einsum("bi,bi,bij->bj", k, m, u))[:, :, None])[:, :, 0]
    c = k * np.einsum("bj,bij->bi", dd, u)  # dx_i = M_i (c 1 - g_i)
    dxb = (c * tp - (k + tp) * gx[..., 0] + k * gx[..., 1]) / det
    dxp = (c * tb + k * gx[..., 0] - (k + tb) * gx[..., 1]) / det
    return np.concatenate([dd, np.stack([dxb, dxp], -1).reshape(b, 2 * nl)], 1)


@dataclass(frozen=True, kw_only=True)
class _Chain:
    """One decoupled block: n legs with direction u_i (n, 3) and spring k_i (n,), or per batch member (B, n, 3)
    and (B, n) (many poses at once), in series with two plays."""

    u: np.ndarray
    k: np.ndarray
    gaps: np.ndarray | None  # (B, n, 2) or None (no play: linear block)
    kc: float
    w: float

    def solve(self, load: np.ndarray, offsets: np.ndarray, z0: np.ndarray | None,
              tol: float = NEWTON_TOL, max_iter: int = 200) -> tuple[np.ndarray, np.ndarray, float]:
        """Minimise sum k/2 (u.d - x_b - x_p - o)^2 + E(x) - load.d over (d (B, 3), x (B, n, 2)).

        Returns z = (d, x flattened) (B, 3 + 2 n), the spring forces (B, n) and the worst relative residual.
        """
        b, nl = load.shape[0], self.k.shape[-1]
        u = np.broadcast_to(self.u, (b, nl, 3))
        k = np.broadcast_to(self.k, (b, nl))
        nz = 3 + 2 * nl
        kuu = np.einsum("bi,bij,bik->bjk", k, u, u)
        if self.gaps is None:
            d = np.linalg.solve(kuu, (load + np.einsum("bi,bi,bij->bj", offsets, k, u))[:, :, None])[:, :, 0]
            return d, k * (np.einsum("bj,bij->bi", d, u) - offsets), 0.0
        z = np.zeros((b, nz)) if z0 is None else z0.copy()
        f_ref = np.maximum(np.linalg.norm(load, axis=1), (np.abs(offsets) * k).sum(1) / nl + 1.0)
        radius = max(0.5 * float(self.gaps.max()), 100 * self.w)

        def parts(zz: np.ndarray) -> tuple[np.ndarray, ...]:
            d, x = zz[:, :3], zz[:, 3:].reshape(b, nl, 2)
            stretch = np.einsum("bj,bij->bi", d, u) - x.sum(2) - offsets
            n = k * stretch
            e, f, t = dead_zones(x, self.gaps, self.kc, self.w)
            energy = 0.5 * (n * stretch).sum(1) + e.sum((1, 2)) - (load * d).sum(1)
            grad = np.concatenate([np.einsum("bi,bij->bj", n, u) - load, (f - n[:, :, None]).reshape(b, 2 * nl)], 1)
            return energy, grad, t.reshape(b, 2 * nl), n

        energy, grad, t, n = parts(z)
        for _ in range(max_iter):
            res = np.max(np.abs(grad), 1) / f_ref
            if np.all(res <= tol):
                return z, n, float(res.max())
            dz = _newton_step(u, k, t.reshape(b, nl, 2), grad)
            alpha = np.minimum(1.0, radius / np.maximum(np.max(np.abs(dz[:, 3:]), 1), 1e-300))
            slope = (grad * dz).sum(1)
            for _ in range(60):  # backtracking on the convex energy (Armijo), per batch member
                zt = z + alpha[:, None] * dz
                et, gt, tt, nt = parts(zt)
                ok = ((et <= energy + 1e-4 * alpha * slope) | (res <= tol)
                      | (np.max(np.abs(gt), 1) <= 0.5 * np.max(np.abs(grad), 1)))  # below energy round-off
                if np.all(ok):
                    break
                alpha = np.where(ok, alpha, 0.5 * alpha)
            z, energy, grad, t, n = zt, et, gt, tt, nt
        res = np.max(np.abs(grad), 1) / f_ref
        raise ConvergenceError("clearance equilibrium (small-displacement Newton)", float(res.max()), tol, max_iter)


@dataclass(frozen=True, kw_only=True)
class _SmallModel:
    """The condensed legs at one pose with B clearance/preload variants."""

    pose: np.ndarray
    trans: _Chain
    rot: _Chain
    rho: np.ndarray  # h - P*, m
    offsets: np.ndarray  # (B, n) actuator rest-length offsets, m

    @classmethod
    def build(cls, machine: Machine, pose: np.ndarray, clearances: list[Clearance], offsets: np.ndarray) -> _SmallModel:
        core = condensed._core(machine, pose[None])
        cl0 = clearances[0]
        for c in clearances[1:]:
            if (c.contact_stiffness_n_per_m, c.smoothing_m, c.rotation_gaps_rad is None) != \
                    (cl0.contact_stiffness_n_per_m, cl0.smoothing_m, cl0.rotation_gaps_rad is None):
                raise ClearanceError("a batch needs the same contact law for every clearance")
        gaps = np.array([c.effective_gaps_m(machine, pose) for c in clearances])
        trans = _Chain(u=core.e[:, :, 0].T, k=core.k_a[:, 0], gaps=gaps, kc=cl0.contact_stiffness_n_per_m,
                       w=cl0.smoothing_m)
        rg = None if cl0.rotation_gaps_rad is None else np.array([c.rotation_gaps_rad for c in clearances])
        rot = _Chain(u=core.c[:, :, 0].T, k=core.k_r[:, 0], gaps=rg, kc=cl0.rotation_stiffness_nm_per_rad,
                     w=cl0.rotation_smoothing_rad)
        return cls(pose=pose, trans=trans, rot=rot, rho=core.rho[:, 0], offsets=np.asarray(offsets, dtype=float))

    def solve(self, wrench: np.ndarray, state: tuple | None) -> tuple[dict[str, np.ndarray], tuple]:
        """wrench (B, 6) at the plate centre; returns per-member results and the state for the next step."""
        f, m = wrench[:, :3], wrench[:, 3:]
        zt, n, rt = self.trans.solve(f, self.offsets, None if state is None else state[0])
        zr, cpl, rr = self.rot.solve(m + np.cross(self.rho, f), np.zeros_like(self.offsets),
                                     None if state is None else state[1])
        phi = zr[:, :3]
        disp = zt[:, :3] - np.cross(self.rho, phi)
        nb, nz = len(wrench), 3 + 2 * len(n[0])
        out = {"displacement_m": disp, "rotation_rad": phi, "axial_forces_n": n, "couples_nm": cpl,
               "joint_axial_m": zt[:, 3:].reshape(nb, -1, 2), "residual": np.full(nb, max(rt, rr))}
        return out, (zt if zt.shape[1] == nz else None, zr if zr.shape[1] == nz else None)


# --- load-deflection ---------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class Branch:
    """States along one loading direction of a load-deflection curve (step k at ``loads_n[k]``)."""

    loads_n: np.ndarray  # (n,) load magnitude along the direction, N
    displacement_m: np.ndarray  # (n, 3) plate-centre translation, world
    rotation_rad: np.ndarray  # (n, 3) plate rotation vector
    axial_forces_n: np.ndarray  # (steps, legs) leg/actuator forces, > 0 tension
    joint_axial_m: np.ndarray  # (steps, legs, 2) axial play coordinates [leg, base|plate], m
    residual: np.ndarray  # (n,) relative residual of each solve


@dataclass(frozen=True, kw_only=True)
class LoadDeflection:
    """A load-deflection curve at one pose (SI). ``unloading`` is stored in the order of ``loading``
    (its state k is at loads_n[k], reached from above). Derived quantities are along ``direction``."""

    pose_m: np.ndarray
    direction: np.ndarray  # unit load direction, world
    preload: float  # a4: N (force mode) or m (length mode)
    preload_mode: str
    method: str  # 'small' | 'nonlinear'
    clearance: Clearance  # as given (its geometry named in the summary)
    effective_gaps_m: np.ndarray  # (n, 2) the effective axial gaps at the pose (Clearance.effective_gaps_m), m
    loading: Branch
    unloading: Branch | None

    @property
    def loads_n(self) -> np.ndarray:
        return self.loading.loads_n

    @property
    def deflection_m(self) -> np.ndarray:
        """(n,) plate-centre displacement along the load direction relative to the preloaded, unloaded state."""
        d = self.loading.displacement_m @ self.direction
        return d - d[0] if self.loads_n[0] == 0 else d

    def closed(self, branch: str = "loading") -> np.ndarray:
        """(steps, legs, 2) True where the joint is in contact (|x| >= effective gap)."""
        x = getattr(self, branch).joint_axial_m
        return np.abs(x) >= self.effective_gaps_m

    @property
    def lost_motion_m(self) -> float:
        """Intercept at zero load of the line through the first two loaded steps (m): the play taken up."""
        f, d = self.loads_n, self.deflection_m
        return float(d[1] - f[1] * (d[2] - d[1]) / (f[2] - f[1]))

    @property
    def small_load_stiffness_n_per_m(self) -> float:
        """Secant stiffness over the first load step, N/m."""
        return float((self.loads_n[1] - self.loads_n[0]) / (self.deflection_m[1] - self.deflection_m[0]))

    @property
    def press_stiffness_n_per_m(self) -> float:
        """Tangent stiffness at the largest load (backward difference over the last step), N/m."""
        return float((self.loads_n[-1] - self.loads_n[-2]) / (self.deflection_m[-1] - self.deflection_m[-2]))

    @property
    def press_secant_stiffness_n_per_m(self) -> float:
        """Largest load over the deflection it causes (includes lost motion), N/m."""
        return float((self.loads_n[-1] - self.loads_n[0]) / (self.deflection_m[-1] - self.deflection_m[0]))

    @property
    def opening_loads_n(self) -> np.ndarray:
        """(n, 2) load at which each joint first opens on loading (|x| < g), N: 0 if open without load, NaN
        if it stays closed. Between the last closed step and the first open one, the joint force (linear in
        the load while closed) is extrapolated from the closed steps to the contact-edge force k_c w / 2."""
        cl, g = self.clearance, self.effective_gaps_m
        x = self.loading.joint_axial_m
        f = np.abs(dead_zones(x, g, cl.contact_stiffness_n_per_m, cl.smoothing_m)[1])
        edge = np.abs(dead_zones(g, g, cl.contact_stiffness_n_per_m, cl.smoothing_m)[1])
        is_open, ld = ~self.closed(), self.loads_n
        out = np.full(g.shape, np.nan)
        for i, j in np.ndindex(*g.shape):
            k = np.flatnonzero(is_open[:, i, j])
            if not k.size:
                continue
            k0 = int(k[0])
            a = k0 - 2 if k0 >= 2 else k0 - 1  # two closed steps (or the last closed and the first open)
            if k0 == 0:
                out[i, j] = ld[0]
                continue
            fa, fb = f[a, i, j], f[k0 - 1 if k0 >= 2 else k0, i, j]
            la, lb = ld[a], ld[k0 - 1 if k0 >= 2 else k0]
            cross = la + (lb - la) * (fa - edge[i, j]) / (fa - fb) if fa != fb else lb
            out[i, j] = float(np.clip(cross, ld[k0 - 1], ld[k0]))
        return out

    def summary(self) -> dict[str, Any]:
        op = self.opening_loads_n
        return {"pose_m": self.pose_m.tolist(), "direction": self.direction.tolist(), "preload": self.preload,
                "preload_mode": self.preload_mode, "method": self.method, "clearance": self.clearance.to_dict(),
                "clearance_geometry": self.clearance.description,
                "effective_gaps_m": self.effective_gaps_m.tolist(),
                "load_max_n": float(self.loads_n[-1]), "lost_motion_m": self.lost_motion_m,
                "small_load_stiffness_n_per_m": self.small_load_stiffness_n_per_m,
                "press_stiffness_n_per_m": self.press_stiffness_n_per_m,
                "press_secant_stiffness_n_per_m": self.press_secant_stiffness_n_per_m,
                "deflection_at_max_m": float(self.deflection_m[-1]),
                "opening_loads_n": [[None if np.isnan(v) else float(v) for v in row] for row in op],
                "max_residual": float(np.max(self.loading.residual))}


def _direction(direction: ArrayLike) -> np.ndarray:
    d = np.asarray(direction, dtype=float).reshape(3)
    nd = np.linalg.norm(d)
    if not np.isfinite(nd) or nd == 0:
        raise ClearanceError(f"the load direction must be a finite non-zero vector, got {direction!r}")
    return d / nd


def _loads(loads: ArrayLike) -> np.ndarray:
    f = np.asarray(loads, dtype=float).reshape(-1)
    if f.size < 3 or not np.all(np.isfinite(f)) or f[0] != 0 or np.any(np.diff(f) <= 0):
        raise ClearanceError("loads must start at 0 N and increase strictly, with at least 3 values")
    return f


def _branch(loads: np.ndarray, states: list[dict[str, np.ndarray]], member: int) -> Branch:
    keys = ("displacement_m", "rotation_rad", "axial_forces_n", "joint_axial_m", "residual")
    return Branch(loads_n=loads, **{k: np.array([s[k][member] for s in states]) for k in keys})


def _sweep_small(machine: Machine, pose: np.ndarray, direction: np.ndarray, loads: np.ndarray,
                 clearances: list[Clearance], offsets: np.ndarray, unload: bool) -> tuple[list, list]:
    """Loading (and unloading) states of B variants at once; each step starts from the previous one."""
    model = _SmallModel.build(machine, pose, clearances, offsets)
    nb = len(clearances)
    state, up, down = None, [], []
    for f in loads:
        out, state = model.solve(np.tile(np.concatenate([f * direction, np.zeros(3)]), (nb, 1)), state)
        up.append(out)
    if unload:
        for f in loads[::-1]:
            out, state = model.solve(np.tile(np.concatenate([f * direction, np.zeros(3)]), (nb, 1)), state)
            down.append(out)
        down = down[::-1]
    return up, down


def _sweep_nonlinear(machine: Machine, pose: np.ndarray, direction: np.ndarray, loads: np.ndarray,
                     clearance: Clearance, offsets: np.ndarray, unload: bool) -> tuple[list, list]:
    from pressfit.mechanics.statics import EquilibriumSolver

    clearance = clearance.at_pose(machine, pose)
    solver = EquilibriumSolver(machine, cardan_compliance=clearance.cardan_compliance(), pose_m=pose)
    idx = np.zeros((len(machine.legs), 2), dtype=int)
    for s in solver.model.springs:
        if s.name.endswith("_cardan.axial"):
            idx[s.leg, ENDS.index(s.name.split("_")[0])] = s.idx_q
    radius = max(0.5 * float(clearance.gaps_m.max()), 100 * clearance.smoothing_m)
    v_idx = idx - 1  # joint coordinates of 1-DOF joints: idx_v = idx_q - 1 (the free flyer has nq = nv + 1)

    def limit(dv: np.ndarray) -> float:
        return min(1.0, radius / max(float(np.max(np.abs(dv[v_idx]))), 1e-300))

    prev = None

    def solve(f: float) -> dict[str, np.ndarray]:
        nonlocal prev
        eq = solver.solve(pose, np.concatenate([f * direction, np.zeros(3)]), preload_offsets_m=offsets, start=prev,
                          step_limit=limit, max_iter=200)
        prev = eq
        return {"displacement_m": eq.plate_displacement_m[None], "rotation_rad": eq.plate_rotation_rad[None],
                "axial_forces_n": eq.actuator_forces_n[None], "joint_axial_m": eq.q[idx][None],
                "residual": np.array([eq.residuals.worst()])}

    up = [solve(f) for f in loads]
    down = [solve(f) for f in loads[::-1]][::-1] if unload else []
    return up, down


def load_deflection(machine: Machine, pose_m: ArrayLike, direction: ArrayLike, loads_n: ArrayLike,
                    clearance: Clearance | None = None, preload: Amplitudes = 0.0, preload_mode: str = "force", *,
                    method: str = "small",
                    unload: bool = True) -> LoadDeflection:
    """Load-deflection curve of the plate at a reachable pose (m) under loads_n (N, from 0, increasing)
    along ``direction`` (world, at the plate centre), after the preload a4 (N, or m in length mode; the n - 3
    amplitudes on a machine with another redundancy than 1).

    ``clearance`` defaults to the machine's uniform clearance (:meth:`Clearance.uniform`); its geometry
    enters as the effective axial gaps at the pose. Loading, then (``unload``) unloading by continuation.
    ``method``: 'small' or 'nonlinear' (module doc).
    """
    pose = kinematics.require_reachable(machine, pose_m)
    d, loads = _direction(direction), _loads(loads_n)
    given = clearance or Clearance.uniform(machine)
    cl = given.at_pose(machine, pose)
    offsets = rest_length_offsets(machine, pose, preload, preload_mode, cl)
    if method == "small":
        up, down = _sweep_small(machine, pose, d, loads, [cl], offsets[None], unload)
    elif method == "nonlinear":
        up, down = _sweep_nonlinear(machine, pose, d, loads, cl, offsets, unload)
    else:
        raise ClearanceError(f"method must be 'small' or 'nonlinear', got {method!r}")
    return LoadDeflection(pose_m=pose, direction=d, preload=float(preload), preload_mode=preload_mode, method=method,
                          clearance=given, effective_gaps_m=cl.gaps_m, loading=_branch(loads, up, 0),
                          unloading=_branch(loads, down, 0) if unload else None)


# --- critical preload --------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class CriticalPreload:
    """Smallest preload keeping every joint closed (|x| >= g) at every load step up to the press load."""

    preload: float  # upper end of the final bracket (closed): N (force mode) or m (length mode)
    lower: float  # largest tried preload that lets a joint open
    tolerance: float  # bracket width reached
    preload_mode: str
    press_load_n: float
    evaluations: int


def _all_closed(machine: Machine, pose: np.ndarray, d: np.ndarray, loads: np.ndarray, cls: list[Clearance],
                a4: np.ndarray, mode: str) -> np.ndarray:
    offsets = np.array([rest_length_offsets(machine, pose, along_first_vector(machine, a), mode, c)
                        for c, a in zip(cls, a4)])
    up, _ = _sweep_small(machine, pose, d, loads, cls, offsets, unload=False)
    gaps = np.array([c.effective_gaps_m(machine, pose) for c in cls])
    return np.array([np.all(np.abs(s["joint_axial_m"]) >= gaps, axis=(1, 2)) for s in up]).all(0)


def _loads_every_leg(machine: Machine, pose: np.ndarray) -> bool:
    """Whether the studies' one-number preload (:func:`pressfit.mechanics.preload.along_first_vector`) puts a force
    on every leg at ``pose``: never on a 3-leg machine (no preload) nor on one of five or more legs (legs 5..n carry
    none), whose cardans then stay open at no load whatever the amplitude."""
    if machine.redundancy != 1:
        return False
    v = np.abs(self_stress_forces_n(machine, pose, 1.0))
    return bool(v.min() > 1e-9 * v.max())


def critical_preloads(machine: Machine, pose_m: ArrayLike, direction: ArrayLike, press_load_n: float,
                      clearances: list[Clearance], preload_mode: str = "force", steps: int = 50,
                      tol: float | None = None) -> list[CriticalPreload]:
    """:func:`critical_preload` for several clearances at once (batched bisections)."""
    pose = kinematics.require_reachable(machine, pose_m)
    d = _direction(direction)
    clearances = [c.at_pose(machine, pose) for c in clearances]
    loads = np.linspace(0.0, float(press_load_n), steps + 1)
    scale = float(press_load_n) if preload_mode == "force" else float(press_load_n) * float(
        machine.axial_compliance_m_per_n(kinematics.inverse_kinematics(machine, pose).lengths_m).max())
    tol = tol if tol is not None else 1e-4 * scale
    nb = len(clearances)
    lo, hi = np.zeros(nb), np.full(nb, scale)
    n_eval = 0
    closed0 = _all_closed(machine, pose, d, loads, clearances, lo, preload_mode)
    if not np.all(closed0) and not _loads_every_leg(machine, pose):
        nan = float("nan")  # no amplitude closes a leg the preload leaves without force: nothing to bisect
        return [CriticalPreload(preload=0.0 if c else nan, lower=0.0 if c else nan, tolerance=0.0 if c else nan,
                                preload_mode=preload_mode, press_load_n=float(press_load_n), evaluations=1)
                for c in closed0]
    for _ in range(30):  # grow the upper bound until every joint stays closed
        ok = _all_closed(machine, pose, d, loads, clearances, hi, preload_mode)
        n_eval += 1
        if np.all(ok):
            break
        lo, hi = np.where(ok, lo, hi), np.where(ok, hi, 2 * hi)
    else:
        raise ClearanceError("no preload up to 2^30 times the press load keeps every joint closed")
    while np.max(hi - lo) > tol:
        mid = 0.5 * (lo + hi)
        ok = _all_closed(machine, pose, d, loads, clearances, mid, preload_mode)
        n_eval += 1
        lo, hi = np.where(ok, lo, mid), np.where(ok, mid, hi)
    hi = np.where(closed0, 0.0, hi)
    return [CriticalPreload(preload=float(h), lower=float(lw), tolerance=float(h - lw), preload_mode=preload_mode,
                            press_load_n=float(press_load_n), evaluations=n_eval)
            for h, lw in zip(hi, lo)]


def critical_preload(machine: Machine, pose_m: ArrayLike, direction: ArrayLike, press_load_n: float,
                     clearance: Clearance | None = None, preload_mode: str = "force", steps: int = 50,
                     tol: float | None = None) -> CriticalPreload:
    """The smallest preload a4 (N in force mode, m in length mode) that keeps every cardan closed
    (|x| >= its effective gap) at each of ``steps`` load steps up to press_load_n (N) along ``direction``;
    on a machine of five or more legs a4 is the amplitude along the first preload basis vector
    (:func:`pressfit.mechanics.preload.along_first_vector`), which leaves legs 5..n without force, and a 3-leg
    machine has no preload: on both the answer is NaN (0 where the load alone keeps every cardan closed), never a
    bisection of ever larger preloads that the solver cannot follow (:mod:`pressfit.mechanics.closing_preload`
    finds the critical preload of such machines along a direction that loads every leg).

    Bisection on the small-displacement model; ``tol`` (default 1e-4 of the press load in N, or of the
    press load times the largest axial compliance in m) is the final bracket width. The smoothing adds a
    bias of about k_c w / |v_i| (the contact-edge force k_c w / 2 at each end of the worst leg).
    """
    cl = clearance or Clearance.uniform(machine)
    return critical_preloads(machine, pose_m, direction, press_load_n, [cl], preload_mode, steps, tol)[0]


def clearance_from_case(case: Case, machine: Machine) -> Clearance:
    """The cardan clearances a case's ``[clearance]`` table describes (default: the machine's uniform one)."""
    spec = case.clearance
    kw: dict[str, Any] = {"smoothing_m": spec.smoothing_m if spec else DEFAULT_SMOOTHING_M}
    if spec and spec.geometry:
        kw["geometry"] = spec.geometry
    if spec and spec.contact_stiffness_n_per_m:
        kw["contact_stiffness_n_per_m"] = spec.contact_stiffness_n_per_m
    if spec and spec.gaps_m:
        return Clearance.per_joint(machine, spec.gaps_m, **kw)
    if spec and spec.random_m:
        return Clearance.random(machine, *spec.random_m, seed=spec.seed, **kw)
    return Clearance.uniform(machine, **kw)

