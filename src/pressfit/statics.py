r"""Compliant static equilibrium of the 4-UPU machine (VJM model of :mod:`pressfit.model`).

Equilibrium = stationarity of  E(q) - W_load(q)  subject to the four 6D loop closures c_i(q) = 0:

    g(q) + J_c(q)^T lambda = 0,   c(q) = 0,     g = dE/dq - Q_load,

solved by Newton on the KKT system  [H J_c^T; J_c 0] [dq; lambda+] = [-g; -c]  (DESIGN.md "Physics
approach"). Closure i is written world-aligned at the plate cardan: c_i = (p_E - p_D, log3(R_E R_D^T)),
with J_c built from the joint twists of ``pin.computeJointJacobians`` (it equals Pinocchio's
``FrameAnchorConstraintModel`` Jacobian up to the rotation of its frame, checked in the tests); lambda_i
= (force, couple) that leg i exerts on the plate, world axes, at the plate cardan centre.

Geometric stiffness, analytic: for a dead wrench W = (f, m_O) (world, about the origin) applied at a
point p of a body, the generalised force Q_k = S_k . W over the supporting joint twists S_k (world,
Pinocchio order (v, omega)) has, along the retraction q (+) dq,

    dQ_k/dq_j = [S_j, S_k] . W   (j strictly before k in the chain; every pair inside the free flyer)
              + omega_k . (u_j x f),   u_j = v_j + omega_j x p   (the point's velocity),

and [S_j, S_k] . W = -S_k . (S_j x* W). Applied to the load on the plate and to every multiplier (a dead
wrench on the leg end and its opposite on the plate), this gives the exact tangent
H = K_springs - dQ_load/dq + d(J_c^T lambda)/dq, block-diagonal over the four legs and the plate. The KKT
system is solved by eliminating each leg's own KKT block (batched) and a 6x6 Schur complement on the
plate.

Linear solve (``linear=True``): one KKT solve at the assembled pose with the elastic stiffness only
(small displacements; equilibrium written on the undeformed geometry).

Section resultants: there are no loads along a leg, so the wrench that the plate-side part exerts on the
base-side part at any section is the plate's wrench on the leg end (-lambda_i) carried to the section
point: N, V_x, V_y (N) and M_x, M_y, T (N m) in the deformed leg frame (e_z from the base cardan to the
current plate cardan, e_x = a_i made normal to e_z, e_y = e_z x e_x; N > 0 tension).

Residuals are relative to F_ref = max(|F_load|, |M_load| / L_ref, max |preload force|) (N; 1 N if all
vanish) and the characteristic length L_ref = p, the base half-side (m): forces / F_ref, moments /
(F_ref L_ref), closure in m / L_ref and in rad as is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dgetrf as _getrf
from scipy.linalg.lapack import dgetrs as _getrs

from . import kinematics
from .errors import ConvergenceError, SingularPoseError
from .machine import Machine
from .model import LinearSpring, MachineModel, build_model

SECTIONS = ("base", "actuator", "plate")
NEWTON_TOL = 1e-10  # stopping tolerance (relative, module doc); the round-off floor is about 3e-12


# --- results -----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SectionWrench:
    """Wrench of the plate-side part on the base-side part, about the section point, deformed leg frame."""

    N: float  # axial force, N, > 0 tension
    V_x: float  # shear, N
    V_y: float
    M_x: float  # bending, N m
    M_y: float
    T: float  # torsion, N m

    def as_dict(self) -> dict[str, float]:
        return {"N": self.N, "V_x": self.V_x, "V_y": self.V_y, "M_x": self.M_x, "M_y": self.M_y, "T": self.T}


@dataclass(frozen=True)
class LegLoads:
    sections: dict[str, SectionWrench]  # 'base', 'actuator', 'plate'
    frame: np.ndarray  # (3, 3) columns e_x, e_y, e_z of the (deformed) leg frame
    actuator_force_n: float  # prismatic spring force, N, > 0 tension


@dataclass(frozen=True)
class Residuals:
    """Equilibrium and closure residuals of a solution (relative, see module doc; closure also in m, rad)."""

    plate_force: float  # |F_load + sum leg forces on the plate| / F_ref
    plate_moment: float  # |M_load + sum leg moments about the plate centre| / (F_ref L_ref)
    machine_force: float  # |sum base reactions + F_load| / F_ref  (base reactions by Pinocchio's RNEA)
    machine_moment: float  # same for moments about the world origin / (F_ref L_ref)
    closure_m: float  # largest loop-closure translation error (Pinocchio constraint data), m
    closure_rad: float  # largest loop-closure rotation error, rad
    stationarity: float  # max |g + J^T lambda| / F_ref (moment rows / (F_ref L_ref))
    force_scale_n: float  # F_ref, N
    length_scale_m: float  # L_ref, m

    def worst(self) -> float:
        return max(self.plate_force, self.plate_moment, self.machine_force, self.machine_moment,
                   self.closure_m / self.length_scale_m, self.closure_rad, self.stationarity)

    def is_valid(self, tol: float = 1e-9) -> bool:
        return bool(self.worst() <= tol)

    def to_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in self.__dataclass_fields__}


@dataclass(frozen=True)
class Equilibrium:
    """A static equilibrium of the machine (SI). Legs in kinematic order."""

    pose_m: np.ndarray  # (3,) nominal plate-centre pose h
    load: np.ndarray  # (6,) plate wrench: force N then moment N m, world axes, at the plate centre
    legs: tuple[LegLoads, ...]
    actuator_forces_n: np.ndarray  # (4,), > 0 tension
    plate_displacement_m: np.ndarray  # (3,) plate-centre translation from the nominal pose
    plate_rotation_rad: np.ndarray  # (3,) plate rotation vector (world axes)
    q: np.ndarray
    multipliers: np.ndarray  # (4, 6) per leg: force (N) and couple (N m) the leg exerts on the plate, world
    iterations: int
    linear: bool
    residuals: Residuals
    preload_offsets_m: np.ndarray = field(default_factory=lambda: np.zeros(4))  # actuator rest-length offsets

    def is_valid(self, tol: float = 1e-9) -> bool:
        return self.residuals.is_valid(tol)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: legs (sections N, V_x, V_y, M_x, M_y, T), actuator forces, plate, residuals."""
        return {
            "pose_m": self.pose_m.tolist(), "load": self.load.tolist(), "linear": self.linear,
            "legs": [{"sections": {k: s.as_dict() for k, s in leg.sections.items()},
                      "actuator_force_n": leg.actuator_force_n} for leg in self.legs],
            "actuator_forces_n": self.actuator_forces_n.tolist(),
            "plate": {"displacement_m": self.plate_displacement_m.tolist(),
                      "rotation_rad": self.plate_rotation_rad.tolist()},
            "residuals": self.residuals.to_dict(), "iterations": self.iterations,
        }


# --- small spatial-algebra helpers (batched; few numpy calls, since each call costs ~1 us) -------------
_LEVI = np.zeros((3, 3, 3))
_LEVI[0, 1, 2] = _LEVI[1, 2, 0] = _LEVI[2, 0, 1] = 1.0
_LEVI[0, 2, 1] = _LEVI[2, 1, 0] = _LEVI[1, 0, 2] = -1.0
_SKEW = _LEVI.transpose(1, 0, 2).reshape(3, 9)  # p @ _SKEW -> skew(p) flattened: skew(p)_ik = eps_ijk p_j


def _skew(p: np.ndarray) -> np.ndarray:
    """(..., 3) -> (..., 3, 3) with skew(p) x = p x x."""
    return (p @ _SKEW).reshape(p.shape[:-1] + (3, 3))


def _phi_psi(f: np.ndarray, mo: np.ndarray, fp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """6x6 operators of the geometric stiffness (module doc), batched over a leading axis:
    Phi S_j = S_j x* W for W = (f, mo), and Psi with omega_k . (u_j x f) = S_k^T Psi S_j, given
    fp = skew(f) skew(p) (p the point of application)."""
    n = f.shape[0]
    sf, sm = _skew(f), _skew(mo)
    phi, psi = np.zeros((n, 6, 6)), np.zeros((n, 6, 6))
    phi[:, :3, 3:] = phi[:, 3:, :3] = psi[:, 3:, :3] = -sf
    phi[:, 3:, 3:] = -sm
    psi[:, 3:, 3:] = fp
    return phi, psi


@dataclass
class _Problem:
    """Everything a solve needs that does not change during the iterations."""

    mm: MachineModel
    load: np.ndarray
    k: np.ndarray  # (L, m) diagonal spring stiffness of the linear springs per leg coordinate
    rest_rel: np.ndarray  # (L, m) rest values minus q0 (preload offsets on the actuators), m or rad
    lin_mask: np.ndarray  # (L, m) bool: coordinate carries a linear spring
    other: list  # nonlinear springs: (leg, col, law)
    legq: np.ndarray  # (L, m) q indices of leg coordinates
    offsets: np.ndarray  # (4,) actuator rest-length offsets, m
    f_ref: float
    l_ref: float
    legv: np.ndarray  # (L, m) v indices of leg coordinates
    act_col: np.ndarray  # (L,) column of the actuator in each leg
    is_force: np.ndarray  # (L, m) translation coordinate (stationarity row in N)
    sc: _Static | None = None


@dataclass
class _Static:
    """Per-model data of the solver (rebuilt when the model is retargeted)."""

    legv: np.ndarray
    k: np.ndarray
    rest_rel: np.ndarray
    lin_mask: np.ndarray
    other: list
    act_col: np.ndarray
    is_force: np.ndarray
    plate_end: list[int]
    first: list[int]
    anchors: np.ndarray  # (3, 4) anchor points in the plate frame
    frames0: np.ndarray  # (4, 3, 3)
    fext: list  # RNEA external forces (zeros; 4 entries set and reset per call)
    cds: list  # constraint datas
    eye6: np.ndarray  # (4, 6, 6) identities
    spring_cols: tuple = ()  # (leg, column) of each of mm.springs


def _static(mm: MachineModel) -> _Static:
    """Solver data of a model: structure cached per model, spring arrays refreshed per retarget."""
    hit = getattr(mm, "_statics_cache", None)
    if hit is not None and hit[0] == (id(mm), mm.version):
        return hit[1]
    if hit is None or hit[0][0] != id(mm):
        try:
            legv = np.array(mm.leg_v, dtype=int)
        except ValueError:
            raise NotImplementedError("legs with different numbers of virtual joints are not supported yet") from None
        col = {int(v): (i, c) for i in range(4) for c, v in enumerate(legv[i])}
        first = [next(j for j in range(1, mm.model.njoints) if mm.model.joints[j].idx_v == legv[i, 0]) for i in range(4)]
        st = _Static(legv, np.zeros(legv.shape), np.zeros(legv.shape), np.zeros(legv.shape, bool), [],
                     np.array([col[s.idx_v][1] for s in mm.springs if s.name == "actuator"]), _force_rows(mm),
                     [mm.leg_joint_ids[i]["plate_end"] for i in range(4)], first,
                     np.array([a.translation for a in mm.anchor_placements]).T, np.array(mm.leg_frames0),
                     [pin.Force.Zero() for _ in range(mm.model.njoints)], mm.constraint_datas(),
                     np.tile(np.eye(6), (4, 1, 1)))
        st.spring_cols = tuple(col[s.idx_v] for s in mm.springs)
    else:
        st = hit[1]
    k, rest, mask = np.zeros(st.legv.shape), np.zeros(st.legv.shape), np.zeros(st.legv.shape, bool)
    other = []
    for (i, c), s in zip(st.spring_cols, mm.springs):
        rest[i, c] = s.rest
        if type(s.law) is LinearSpring:
            k[i, c], mask[i, c] = s.law.k, True
        else:
            other.append((i, c, s.law))
    st.k, st.rest_rel, st.lin_mask, st.other = k, rest - mm.q0[st.legv + 1], mask, other
    mm._statics_cache = ((id(mm), mm.version), st)
    return st


def _problem(mm: MachineModel, load: np.ndarray, offsets: np.ndarray, f_pre: float) -> _Problem:
    sc = _static(mm)
    rest_rel = sc.rest_rel.copy()
    rest_rel[np.arange(4), sc.act_col] += offsets
    l_ref = mm.machine.geometry.base_half_side_m
    f_ref = max(float(np.linalg.norm(load[:3])), float(np.linalg.norm(load[3:])) / l_ref, f_pre)
    return _Problem(mm, load, sc.k, rest_rel, sc.lin_mask, sc.other, sc.legv + 1, offsets, f_ref if f_ref > 0 else 1.0,
                    l_ref, sc.legv, sc.act_col, sc.is_force, sc)


@dataclass
class _State:
    q: np.ndarray
    s: np.ndarray  # (4, 6, m) leg twists
    sp: np.ndarray  # (6, 6) plate twists
    pe: np.ndarray  # (4, 3) leg end points
    pd: np.ndarray  # (4, 3) plate anchor points
    pc: np.ndarray  # (3,) plate centre
    rp: np.ndarray  # (3, 3) plate rotation
    c: np.ndarray  # (4, 6) closure residual (world)
    a: np.ndarray  # (4, 6, m) closure Jacobian, leg part
    p: np.ndarray  # (4, 6, 6) closure Jacobian, plate part
    g_leg: np.ndarray  # (4, m) spring forces
    g_plate: np.ndarray  # (6,) -Q_load
    ktan: np.ndarray  # (4, m) spring tangent stiffness


def _evaluate(pb: _Problem, q: np.ndarray, data: pin.Data, d_leg: np.ndarray | None = None) -> _State:
    """Kinematics, closure, spring forces at q; ``d_leg`` = q - q0 on the leg coordinates (kept apart so
    that spring forces keep full relative precision however stiff the springs: q ~ 1 m, q - rest ~ 1e-6 m)."""
    mm, sc = pb.mm, pb.sc
    if d_leg is None:
        d_leg = q[pb.legq] - mm.q0[pb.legq]
    pin.computeJointJacobians(mm.model, data, q)
    jac = data.J
    s = jac[:, pb.legv].transpose(1, 0, 2)  # (L, 6, m) leg twists (v, omega), world, about the origin
    sp = jac[:, :6]
    op = data.oMi[mm.plate_joint_id]
    rp, pc = op.rotation, op.translation.copy()
    pe, c = np.empty((4, 3)), np.empty((4, 6))
    pd = pc + sc.anchors.T @ rp.T  # (4, 3)
    rd = rp @ sc.frames0  # (4, 3, 3) anchor orientations
    for i, j in enumerate(sc.plate_end):
        oe = data.oMi[j]
        pe[i] = oe.translation
        c[i, 3:] = pin.log3(oe.rotation @ rd[i].T)
    c[:, :3] = pe - pd
    lam_e, lam_d = sc.eye6.copy(), sc.eye6.copy()  # twist about O -> (velocity of the point, omega)
    lam_e[:, :3, 3:] = -_skew(pe)  # v + omega x p = v - skew(p) omega
    lam_d[:, :3, 3:] = -_skew(pd)
    a = lam_e @ s  # closure Jacobian, leg part (L, 6, m)
    p = -(lam_d @ sp)  # plate part (L, 6, 6)
    x = d_leg - pb.rest_rel
    g_leg = pb.k * x
    ktan = pb.k
    if pb.other:
        ktan = ktan.copy()
        for i, cc, law in pb.other:
            g_leg[i, cc] = law.force(x[i, cc])
            ktan[i, cc] = law.tangent(x[i, cc])
    f, m = pb.load[:3], pb.load[3:]
    g_plate = -(sp.T @ np.concatenate([f, _cross3(pc, f) + m]))
    return _State(q, s, sp, pe, pd, pc, rp, c, a, p, g_leg, g_plate, ktan)


@dataclass
class _Factor:
    """The KKT matrix [H J^T; J 0] factored by per-leg elimination and a 6x6 plate Schur complement."""

    lu: list  # per leg: LAPACK LU (lu, piv) of the leg's own KKT block [H_i A_i^T; A_i 0], (m+6)^2
    zz: np.ndarray  # (L, m+6, 6): leg solution per unit plate displacement
    pt: np.ndarray  # (L, 6, 6) plate part of the closure Jacobian, transposed
    schur: tuple  # LAPACK LU of the 6x6 plate Schur complement
    m: int


def _kkt_factor(st: _State, h_leg: np.ndarray, h_plate: np.ndarray, check: bool = True) -> _Factor:
    nl, m = h_leg.shape[:2]
    kkt = np.zeros((nl, m + 6, m + 6))
    kkt[:, :m, :m] = h_leg
    kkt[:, :m, m:] = st.a.transpose(0, 2, 1)
    kkt[:, m:, :m] = st.a
    rhs = np.zeros((m + 6, 6))
    zz = np.empty((nl, m + 6, 6))
    lus = []
    for i in range(nl):  # direct LAPACK: numpy's batched linalg costs ~5x more on 35x35 blocks
        lu, piv, info = _getrf(kkt[i])
        if info != 0:
            raise SingularPoseError(f"leg {i + 1}'s elastic KKT block is singular (a leg mechanism has no stiffness)")
        rhs[m:] = -st.p[i]
        zz[i] = _getrs(lu, piv, rhs)[0]
        lus.append((lu, piv))
    pt = st.p.transpose(0, 2, 1)
    schur = h_plate + (pt @ zz[:, m:]).sum(0)
    if check:
        sv = np.linalg.svd(schur, compute_uv=False)
        if not np.all(np.isfinite(sv)) or sv[-1] <= 1e-13 * sv[0]:
            raise SingularPoseError("the plate stiffness is singular at this pose "
                                    f"(condition {sv[0] / max(sv[-1], 1e-300):.3g})")
    lu, piv, info = _getrf(schur)
    if info != 0:
        raise SingularPoseError("the plate stiffness is singular at this pose")
    return _Factor(lus, zz, pt, (lu, piv), m)


def _kkt_apply(fa: _Factor, r_leg: np.ndarray, r_plate: np.ndarray, rhs_c: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Solve [H J^T; J 0][dq; lam] = [r; rhs_c] with a factored KKT matrix: (dq_leg, dq_plate, lam)."""
    m = fa.m
    rhs = np.concatenate([r_leg, rhs_c], 1)
    z = np.array([_getrs(lu, piv, rhs[i])[0] for i, (lu, piv) in enumerate(fa.lu)])  # (L, m+6)
    dp = _getrs(*fa.schur, r_plate - (fa.pt @ z[:, m:, None]).sum(0)[:, 0])[0]
    sol = z + fa.zz @ dp
    return sol[:, :m], dp, sol[:, m:]


def _kkt_solve(st: _State, h_leg: np.ndarray, h_plate: np.ndarray, r_leg: np.ndarray, r_plate: np.ndarray,
               rhs_c: np.ndarray, check: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return _kkt_apply(_kkt_factor(st, h_leg, h_plate, check), r_leg, r_plate, rhs_c)


def _stationarity(pb: _Problem, st: _State, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r_leg = st.g_leg + (lam[:, None, :] @ st.a)[:, 0]
    r_plate = st.g_plate + (lam[:, None, :] @ st.p).sum(0)[0]
    return r_leg, r_plate


def _scaled_stationarity(pb: _Problem, mm: MachineModel, r_leg: np.ndarray, r_plate: np.ndarray) -> float:
    # leg rows: N m for revolutes, N for prismatics; plate rows: (N, N m)
    scale = np.where(pb.is_force, pb.f_ref, pb.f_ref * pb.l_ref)
    return float(max(np.max(np.abs(r_leg) / scale),
                     np.max(np.abs(r_plate[:3])) / pb.f_ref, np.max(np.abs(r_plate[3:])) / (pb.f_ref * pb.l_ref)))


def _dq(mm: MachineModel, dq_leg: np.ndarray, dp: np.ndarray) -> np.ndarray:
    dv = np.empty(mm.model.nv)
    dv[:6] = dp
    dv[_static(mm).legv] = dq_leg
    return dv


# --- public API ----------------------------------------------------------------------------------------
_CACHE: dict[tuple, tuple[Machine, MachineModel]] = {}


def _model_for(machine_or_model: Machine | MachineModel, pose: np.ndarray) -> MachineModel:
    if isinstance(machine_or_model, MachineModel):
        mm = machine_or_model
    else:
        key = (id(machine_or_model), machine_or_model.model.springs_per_segment)
        hit = _CACHE.get(key)
        if hit is None or hit[0] is not machine_or_model:
            if len(_CACHE) > 16:
                _CACHE.clear()
            hit = (machine_or_model, build_model(machine_or_model, pose))
            _CACHE[key] = hit
        mm = hit[1]
    if not np.array_equal(mm.pose_m, pose):
        mm.retarget(pose)
    return mm


def preload_offsets(machine: Machine, pose_m: np.ndarray, a4: float, mode: str = "force") -> np.ndarray:
    """Actuator rest-length offsets (4,) in m for a preload along v_p (paper eqs. 9-10, Table 4).

    ``force``: a4 in N; offsets -a4 v_p,i c_axial,i, so that with no load the actuator forces are exactly
    a4 v_p (tension positive). ``length``: a4 in m; offsets -a4 v_p,i (position-held drives shortened by
    a4 v_p,i, so a4 > 0 pulls the legs with v_p,i > 0 like the force mode).
    """
    vp = kinematics.preload_vector(machine, pose_m)
    if mode == "force":
        return -a4 * vp * machine.axial_compliance_m_per_n(kinematics.inverse_kinematics(machine, pose_m).lengths_m)
    if mode == "length":
        return -a4 * vp
    raise ValueError(f"preload mode must be 'force' or 'length', got {mode!r}")


def solve_equilibrium(machine_or_model: Machine | MachineModel, pose_m: np.ndarray, plate_wrench: np.ndarray, *,
                      preload: float | Any | None = None, preload_mode: str | None = None, linear: bool = False,
                      tol: float = NEWTON_TOL, max_iter: int = 25, start: Equilibrium | None = None,
                      preload_offsets_m: np.ndarray | None = None, step_limit: Any = None) -> Equilibrium:
    """Static equilibrium at a reachable pose (m) under a dead plate wrench (6,) (N, N m; world axes, at
    the plate centre), after an optional actuator preload along v_p.

    ``preload``: a4 (a float; N in force mode, m in length mode, see :func:`preload_offsets`) or an
    object with ``a4_n`` and ``mode`` (a case file's ``[preload]``). Preload first, then load.
    Geometrically nonlinear Newton by default (``tol``: relative stationarity and closure, module doc);
    ``linear=True``: small-displacement solve at the assembled pose. A :class:`MachineModel` argument is
    retargeted in place to ``pose_m`` if needed. Raises UnreachablePoseError, SingularPoseError,
    ConvergenceError.

    Continuation hooks (nonlinear solve; used by :mod:`pressfit.clearance`): ``start``, a previous solution of
    the same model and pose, to start Newton from (its q and multipliers); ``preload_offsets_m``, explicit
    actuator rest-length offsets (4,) in m instead of ``preload``; ``step_limit(dv) -> factor in (0, 1]``,
    scales each Newton step (dv over the model's velocity coordinates).
    """
    if isinstance(machine_or_model, MachineModel):
        machine = machine_or_model.machine
    else:
        machine = machine_or_model
    pose = kinematics.require_reachable(machine, pose_m)
    load = np.asarray(plate_wrench, dtype=float).reshape(-1)
    if load.shape == (3,):
        load = np.concatenate([load, np.zeros(3)])
    if load.shape != (6,) or not np.all(np.isfinite(load)):
        raise ValueError(f"plate_wrench must be 6 finite numbers (F then M), got {plate_wrench!r}")
    mm = _model_for(machine_or_model, pose)
    a4, mode = 0.0, preload_mode or "force"
    if preload is not None:
        if hasattr(preload, "a4_n"):
            a4, mode = float(preload.a4_n), preload_mode or preload.mode
        else:
            a4 = float(preload)
    offsets = preload_offsets(machine, pose, a4, mode) if a4 else np.zeros(4)
    if preload_offsets_m is not None:
        offsets = np.asarray(preload_offsets_m, dtype=float).reshape(4)
    kax = np.array([s.law.k for s in mm.springs if s.name == "actuator"])
    pb = _problem(mm, load, offsets, float(np.max(np.abs(kax * offsets))))
    data = mm.data
    if linear:
        return _solve_linear(pb, data)
    return _solve_nonlinear(pb, data, tol, max_iter, start, step_limit)


def _force_rows(mm: MachineModel) -> np.ndarray:
    """(4, m) True where the leg coordinate is a translation (its stationarity row is a force, N)."""
    prism = {int(mm.model.joints[j].idx_v) for j in range(1, mm.model.njoints)
             if mm.model.joints[j].shortname().startswith("JointModelP")}
    return np.array([[int(v) in prism for v in legv] for legv in mm.leg_v])


def _solve_linear(pb: _Problem, data: pin.Data) -> Equilibrium:
    mm = pb.mm
    st = _evaluate(pb, mm.q0, data)
    k = st.ktan
    fa = _kkt_factor(st, _diag(k), np.zeros((6, 6)))
    r_leg, r_plate = -st.g_leg, -st.g_plate
    dq_leg, dp, lam = _kkt_apply(fa, r_leg, r_plate, -st.c)

    def errors():  # residual of the linear KKT system
        r_l, r_p = _stationarity(pb, st, lam)  # g + J^T lam (g = -r)
        e_c = -st.c - (st.a @ dq_leg[:, :, None])[:, :, 0] - st.p @ dp
        return r_leg - k * dq_leg - (r_l - st.g_leg), r_plate - (r_p - st.g_plate), e_c

    for _ in range(2):  # iterative refinement (keeps the residuals at round-off)
        d1, d2, d3 = _kkt_apply(fa, *errors())
        dq_leg, dp, lam = dq_leg + d1, dp + d2, lam + d3
    e_leg, e_plate, _ = errors()
    stat = _scaled_stationarity(pb, mm, e_leg, e_plate)
    dv = _dq(mm, dq_leg, dp)
    return _result(pb, st, lam, pin.integrate(mm.model, mm.q0, dv), dq_leg, stat, 1, linear=True, data=data, dv=dv)


def _diag(k: np.ndarray) -> np.ndarray:
    out = np.zeros(k.shape + (k.shape[-1],))
    idx = np.arange(k.shape[-1])
    out[:, idx, idx] = k
    return out


def _tangent(pb: _Problem, st: _State, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact tangent blocks: legs (4, m, m) and plate (6, 6) (module doc)."""
    lf, lm = lam[:, :3], lam[:, 3:]
    sf = _skew(lf)
    # legs: the multiplier as a dead wrench (lf, pe x lf + lm) at the leg end pe
    phi, psi = _phi_psi(lf, _cross3(st.pe, lf) + lm, sf @ _skew(st.pe))
    st_ = st.s.transpose(0, 2, 1)
    h_leg = -np.tril(st_ @ phi @ st.s, -1) + st_ @ psi @ st.s
    idx = np.arange(h_leg.shape[1])
    h_leg[:, idx, idx] += st.ktan
    # plate: minus the load at pc, and -(lf, pd x lf + lm) at pd per leg (Phi linear in W, Psi summed)
    f, m = pb.load[:3], pb.load[3:]
    f_tot = -f - lf.sum(0)
    mo_tot = -(_cross3(st.pc, f) + m) - (_cross3(st.pd, lf) + lm).sum(0)
    fp = -_skew(f) @ _skew(st.pc) - (sf @ _skew(st.pd)).sum(0)
    phi, psi = _phi_psi(f_tot[None], mo_tot[None], fp[None])
    h_plate = st.sp.T @ (psi[0] - phi[0]) @ st.sp
    return h_leg, h_plate


def _solve_nonlinear(pb: _Problem, data: pin.Data, tol: float, max_iter: int, start: Equilibrium | None = None,
                     step_limit: Any = None) -> Equilibrium:
    mm = pb.mm
    q = mm.q0.copy() if start is None else start.q.copy()
    d_leg = np.zeros(pb.legq.shape) if start is None else start.q[pb.legq] - mm.q0[pb.legq]
    lam = np.zeros((4, 6)) if start is None else start.multipliers.copy()
    stat = np.inf
    for it in range(max_iter + 1):
        st = _evaluate(pb, q, data, d_leg)
        r_leg, r_plate = _stationarity(pb, st, lam)
        stat = _scaled_stationarity(pb, mm, r_leg, r_plate)
        clos = max(np.max(np.abs(st.c[:, :3])) / pb.l_ref, np.max(np.abs(st.c[:, 3:])))
        if stat <= tol and clos <= tol:
            return _result(pb, st, lam, q, d_leg, stat, it, linear=False, data=data)
        if it == max_iter:
            break
        h_leg, h_plate = _tangent(pb, st, lam)
        dq_leg, dp, lam_new = _kkt_solve(st, h_leg, h_plate, -st.g_leg, -st.g_plate, -st.c, check=it == 0)
        a = 1.0 if step_limit is None else float(step_limit(_dq(mm, dq_leg, dp)))
        dq_leg, dp, lam = a * dq_leg, a * dp, lam + a * (lam_new - lam)
        d_leg = d_leg + dq_leg
        q = pin.integrate(mm.model, q, _dq(mm, dq_leg, dp))
        q[pb.legq] = mm.q0[pb.legq] + d_leg
    raise ConvergenceError("nonlinear equilibrium (Newton on the KKT system)", max(stat, clos), tol, max_iter)


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of 3-vectors along the last axis (np.cross costs ~20 us a call)."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1], a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], -1)


def _result(pb: _Problem, st: _State, lam: np.ndarray, q: np.ndarray, d_leg: np.ndarray, stat: float,
            iterations: int, linear: bool, data: pin.Data, dv: np.ndarray | None = None) -> Equilibrium:
    """Section resultants, plate motion and residuals. Linear: on the reference geometry (st at q0)."""
    mm, sc = pb.mm, pb.sc
    model = mm.model
    geo_q = mm.q0 if linear else q
    pin.forwardKinematics(model, data, geo_q)
    f_load, m_load = pb.load[:3], pb.load[3:]
    lf, lm = lam[:, :3], lam[:, 3:]
    # section points (4 legs, 3 sections, xyz) and deformed leg frames
    pts = np.empty((4, 3, 3))
    for i in range(4):
        for k, name in enumerate(SECTIONS):
            j, z = mm.sections[i][name]
            oj = data.oMi[j]
            pts[i, k] = oj.translation + oj.rotation[:, 2] * z if z else oj.translation
    pe = st.pe if linear else np.array([data.oMi[j].translation for j in sc.plate_end])
    ez = pts[:, 2] - pts[:, 0]
    ez /= np.linalg.norm(ez, axis=1, keepdims=True)
    ax = mm.machine.cardan_axes
    ex = ax - np.sum(ax * ez, 1, keepdims=True) * ez
    ex /= np.linalg.norm(ex, axis=1, keepdims=True)
    frames = np.stack([ex, _cross3(ez, ex), ez], -1)  # (4, 3, 3), columns e_x, e_y, e_z
    force = -lf  # the plate's wrench on each leg end, carried to the sections (no loads along the leg)
    mom = _cross3(pe[:, None, :] - pts, force[:, None, :]) - lm[:, None, :]  # (4, 3, 3)
    fl = (force[:, None, :] @ frames)[:, 0]  # (4, 3) leg-frame components
    ml = mom @ frames  # (4, 3 sections, 3)
    act = np.array([float(pb.k[i, pb.act_col[i]] * (d_leg[i, pb.act_col[i]] - pb.rest_rel[i, pb.act_col[i]]))
                    if pb.lin_mask[i, pb.act_col[i]] else 0.0 for i in range(4)])
    legs = tuple(LegLoads({name: SectionWrench(fl[i, 2], fl[i, 0], fl[i, 1], ml[i, k, 0], ml[i, k, 1], ml[i, k, 2])
                           for k, name in enumerate(SECTIONS)}, frames[i], float(act[i])) for i in range(4))
    plate = data.oMi[mm.plate_joint_id]
    pc = st.pc if linear else plate.translation
    # residuals -----------------------------------------------------------------------------------
    pd = st.pd if linear else (plate.translation[:, None] + plate.rotation @ sc.anchors).T
    pf = np.linalg.norm(f_load + lf.sum(0)) / pb.f_ref
    pm = np.linalg.norm(m_load + (_cross3(pd - pc, lf) + lm).sum(0)) / (pb.f_ref * pb.l_ref)
    fext = sc.fext
    for i, j in enumerate(sc.plate_end):
        oj = data.oMi[j]
        fext[j] = oj.actInv(pin.Force(force[i], _cross3(oj.translation, force[i]) - lm[i]))  # world, about O
    zero = np.zeros(model.nv)
    pin.rnea(model, data, geo_q, zero, zero, fext)
    for j in sc.plate_end:
        fext[j] = pin.Force.Zero()
    react = np.zeros(6)
    for first in sc.first:
        react += data.oMi[first].act(data.f[first]).vector
    mf = np.linalg.norm(react[:3] + f_load) / pb.f_ref
    mmom = np.linalg.norm(react[3:] + _cross3(pc, f_load) + m_load) / (pb.f_ref * pb.l_ref)
    cds = sc.cds
    if linear:  # linearised closure: Pinocchio's constraint Jacobian at q0 times the displacement
        pin.computeJointJacobians(model, data, mm.q0)
        for cm, cd in zip(mm.constraint_models, cds):
            cm.calc(model, data, cd)
        e = (pin.getConstraintsJacobian(model, data, mm.constraint_models, cds) @ dv).reshape(4, 6)
    else:
        for cm, cd in zip(mm.constraint_models, cds):
            cm.calc(model, data, cd)
        e = np.array([cd.extract().constraint_position_error for cd in cds])
    res = Residuals(float(pf), float(pm), float(mf), float(mmom), float(np.max(np.linalg.norm(e[:, :3], axis=1))),
                    float(np.max(np.linalg.norm(e[:, 3:], axis=1))), float(stat), pb.f_ref, pb.l_ref)
    if linear:  # the free flyer's v is in its local frame; at q0 the plate is world-aligned
        disp, rot = dv[:3].copy(), dv[3:6].copy()
    else:
        disp, rot = plate.translation - mm.pose_m, pin.log3(plate.rotation)
    return Equilibrium(mm.pose_m.copy(), pb.load.copy(), legs, act, disp, rot, q, lam.copy(),
                       iterations, linear, res, pb.offsets.copy())
