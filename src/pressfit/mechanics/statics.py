r"""Compliant static equilibrium of the n-UPU machine (VJM model of :mod:`pressfit.mechanics.model`).

Equilibrium = stationarity of  E(q) - W_load(q)  subject to the n 6D loop closures c_i(q) = 0 (one per leg):

    g(q) + J_c(q)^T lambda = 0,   c(q) = 0,     g = dE/dq - Q_load,

solved by Newton on the KKT system  [H J_c^T; J_c 0] [dq; lambda+] = [-g; -c]  (docs/conventions.md,
"Mechanics facts"). Closure i is written world-aligned at the plate cardan: c_i = (p_E - p_D, log3(R_E R_D^T)),
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
H = K_springs - dQ_load/dq + d(J_c^T lambda)/dq, block-diagonal over the n legs and the plate. The KKT
system is solved by eliminating each leg's own KKT block (batched) and a 6x6 Schur complement on the
plate.

Closure Jacobian: the constraint rows of the KKT matrix are the exact derivative of c, with
d log3(R_E R_D^T) = Jlog3^T omega_E - Jlog3 omega_D (``pin.Jlog3``), so Newton is exact off the manifold;
the stationarity rows keep J^T lambda with the twist map (lambda is the physical dead wrench; the two
Jacobians agree on the manifold). Closure components below CLOSURE_FLOOR (64 ulp of 1 m) are set to 0: they
are the round-off of positions of ~1 m and, left in, a 5e7 N/m actuator turns them into a ~1e-9 N
self-stress that swamps tiny loads. Every solve reports its stability (:mod:`pressfit.mechanics.stability`):
at convergence for the nonlinear solve, and for the linear solve the tangent at the reference with the
geometric stiffness of its own multipliers (stable exactly when the machine's linearised buckling factor
exceeds 1). Unstable solutions raise UnstableEquilibriumError; a solution whose relative residuals (below)
exceed RESIDUAL_TOL raises ResidualError naming the residual (the fast path is held to the same).

Linear solve (``linear=True``): one KKT solve at the assembled pose with the elastic stiffness only
(small displacements; equilibrium written on the undeformed geometry), about a stress-free reference:
the closed form of equation 1 is closed in exact arithmetic, so its round-off closure residual is taken
as zero and the answer is exactly proportional to the load.

Section resultants: there are no loads along a leg, so the wrench that the plate-side part exerts on the
base-side part at any section is the plate's wrench on the leg end (-lambda_i) carried to the section
point: N, V_x, V_y (N) and M_x, M_y, T (N m) in the deformed leg frame (e_z from the base cardan to the
current plate cardan, e_x = a_i made normal to e_z, e_y = e_z x e_x; N > 0 tension).

Residuals are relative to F_ref = max(|F_load|, |M_load| / L_ref, max |preload force|) (N; 1 N if all
vanish) and the characteristic length L_ref = p, the base half-side (m): forces / F_ref, moments /
(F_ref L_ref), closure in m / L_ref and in rad as is.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.linalg.lapack import dgesdd as _gesdd
from scipy.linalg.lapack import dgesv as _gesv
from scipy.linalg.lapack import dgetrf as _getrf
from scipy.linalg.lapack import dgetrs as _getrs

from pressfit import kinematics
from pressfit.description.cases import Case
from pressfit.description.machine import Machine
from pressfit.errors import (
    ConvergenceError,
    PressfitError,
    ResidualError,
    SingularPoseError,
    UnstableEquilibriumError,
)
from pressfit.mechanics import data_pool
from pressfit.mechanics.model import CardanComplianceSpec, MachineModel, ModelPose, SpringLaw, build_model
from pressfit.mechanics.preload import ActuatorPreload, Amplitudes, rest_length_offsets
from pressfit.mechanics.stability import Stability, reduced_stability
from pressfit.spatial import cross, skew

SECTIONS = ("base", "actuator", "plate")
SECTION_COMPONENTS = ("N", "V_x", "V_y", "M_x", "M_y", "T")  # SectionWrench's fields
CLOSURE_FLOOR = 64 * np.finfo(float).eps  # m or rad: closure components below it are round-off (module doc)
NEWTON_TOL = 1e-10  # stopping tolerance (relative, module doc); the round-off floor is about 3e-12
# Relative tolerance every returned solution is held to (Residuals.is_valid's default and the README's validity
# criterion); a solve above it raises ResidualError. Newton stops at NEWTON_TOL on stationarity and closure: over
# 40 random reachable poses x 6 loads, with and without a 400 N preload, the worst residual of this solver and
# of the fast one was 9.9e-11 (nonlinear; the balances derived from it 3.7e-11) and 1.1e-13 (linear).
RESIDUAL_TOL = 1e-9
RESIDUAL_NAMES = ("plate_force", "plate_moment", "machine_force", "machine_moment", "closure_m", "closure_rad",
                  "stationarity")  # the relative residuals, in Residuals.relative() order


# --- results -----------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
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


@dataclass(frozen=True, kw_only=True)
class LegLoads:
    sections: dict[str, SectionWrench]  # 'base', 'actuator', 'plate'
    frame: np.ndarray  # (3, 3) columns e_x, e_y, e_z of the (deformed) leg frame
    actuator_force_n: float  # prismatic spring force, N, > 0 tension


@dataclass(frozen=True, kw_only=True)
class Residuals:
    """Equilibrium and closure residuals of a solution (relative, see module doc; closure also in m, rad)."""

    plate_force: float  # |F_load + sum leg forces on the plate| / F_ref
    plate_moment: float  # |M_load + sum leg moments about the plate centre| / (F_ref L_ref)
    machine_force: float  # |sum base reactions + F_load| / F_ref, reactions from the spring forces alone
    machine_moment: float  # same for moments about the world origin / (F_ref L_ref)
    closure_m: float  # largest loop-closure translation error (Pinocchio constraint data), m
    closure_rad: float  # largest loop-closure rotation error, rad
    stationarity: float  # max |g + J^T lambda| / F_ref (moment rows / (F_ref L_ref))
    force_scale_n: float  # F_ref, N
    length_scale_m: float  # L_ref, m

    def worst(self) -> float:
        return max(self.plate_force, self.plate_moment, self.machine_force, self.machine_moment,
                   self.closure_m / self.length_scale_m, self.closure_rad, self.stationarity)

    def is_valid(self, tol: float = RESIDUAL_TOL) -> bool:
        return bool(self.worst() <= tol)

    def relative(self) -> np.ndarray:
        """The seven relative residuals (RESIDUAL_NAMES order; the closure in m divided by L_ref)."""
        return np.array([self.plate_force, self.plate_moment, self.machine_force, self.machine_moment,
                         self.closure_m / self.length_scale_m, self.closure_rad, self.stationarity])

    def to_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in self.__dataclass_fields__}


@dataclass(frozen=True, kw_only=True)
class Equilibrium:
    """A static equilibrium of the machine (SI). Legs in kinematic order."""

    pose_m: np.ndarray  # (3,) nominal plate-centre pose h
    load: np.ndarray  # (6,) plate wrench: force N then moment N m, world axes, at the plate centre
    legs: tuple[LegLoads, ...]
    actuator_forces_n: np.ndarray  # (n,), > 0 tension
    plate_displacement_m: np.ndarray  # (3,) plate-centre translation from the nominal pose
    plate_rotation_rad: np.ndarray  # (3,) plate rotation vector (world axes)
    q: np.ndarray
    multipliers: np.ndarray  # (n, 6) per leg: force (N) and couple (N m) the leg exerts on the plate, world
    iterations: int
    linear: bool
    residuals: Residuals
    stability: Stability  # of the tangent stiffness on the closure manifold (pressfit.mechanics.stability)
    preload_offsets_m: np.ndarray | None = None  # (n,) actuator rest-length offsets, m (None: zeros)

    def __post_init__(self) -> None:
        if self.preload_offsets_m is None:
            object.__setattr__(self, "preload_offsets_m", np.zeros(len(self.actuator_forces_n)))

    def is_valid(self, tol: float = RESIDUAL_TOL) -> bool:
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
            "residuals": self.residuals.to_dict(), "stability": self.stability.to_dict(),
            "iterations": self.iterations,
        }


# --- spatial algebra: pressfit.spatial (batched; few numpy calls, since each call costs ~1 us) -------------
_skew, _cross3 = skew, cross


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


@dataclass(kw_only=True)
class _Static:
    """Pose-independent index structure of the solver for one model, with one thread's constraint datas."""

    legv: np.ndarray  # (n, m) v indices of the leg coordinates
    act_col: np.ndarray  # (n,) column of the actuator in each leg
    act_spring: np.ndarray  # (n,) index of each leg's actuator in mm.springs
    is_force: np.ndarray  # (n, m) translation coordinate (stationarity row in N)
    plate_end: list[int]
    anchors: np.ndarray  # (3, n) anchor points in the plate frame
    frames0: np.ndarray  # (n, 3, 3) anchor orientations in the plate frame (R0_i, turned by a plate cardan tilt)
    cds: list[pin.ConstraintData]  # constraint datas (one set per thread)
    spring_at: tuple[np.ndarray, np.ndarray]  # (legs, columns) of mm.springs
    sec_joints: list[int]  # 3 n joints carrying the section points, leg-major
    sec_z: list[tuple[int, int, float]]  # (leg, section, z) for section points off their joint origin
    lower: np.ndarray  # (m, m) 1.0 strictly below the diagonal
    lin: np.ndarray  # per spring: linear law
    lin_mask: np.ndarray  # (n, m) coordinate carries a linear spring
    other: list[tuple[int, int, SpringLaw]]  # (leg, column, law) of the springs with a nonlinear law


def _static(mm: MachineModel) -> _Static:
    """The solver's index structure of a model (pose-independent)."""
    try:
        legv = np.array(mm.leg_v, dtype=int)
    except ValueError:
        raise PressfitError("cardan compliance on only some legs (legs with different numbers of virtual "
                            "joints) is not supported by the solver yet; give it to every leg") from None
    legs = range(len(legv))
    col = {int(v): (i, c) for i in legs for c, v in enumerate(legv[i])}
    at = np.array([col[s.idx_v] for s in mm.springs], dtype=int).T
    act = np.array([k for k, s in enumerate(mm.springs) if s.name == "actuator"])
    sec = [mm.sections[i][name] for i in legs for name in SECTIONS]
    m = legv.shape[1]
    lin = ~np.isnan(mm.spring_k)
    lin_mask = np.zeros(legv.shape, bool)
    lin_mask[at[0, lin], at[1, lin]] = True
    return _Static(legv=legv, act_col=at[1, act], act_spring=act, is_force=_force_rows(mm),
                   plate_end=[mm.leg_joint_ids[i]["plate_end"] for i in legs],
                   anchors=np.array([a.translation for a in mm.anchor_placements]).T,
                   frames0=np.array([a.rotation for a in mm.anchor_placements]), cds=mm.constraint_datas(),
                   spring_at=(at[0], at[1]), sec_joints=[j for j, _ in sec],
                   sec_z=[(n // 3, n % 3, z) for n, (_, z) in enumerate(sec) if z], lower=np.tril(np.ones((m, m)), -1),
                   lin=lin, lin_mask=lin_mask,
                   other=[(int(at[0, k]), int(at[1, k]), mm.springs[k].law) for k in np.flatnonzero(~lin)])


@dataclass(frozen=True, kw_only=True)
class _PoseModel:
    """What the Newton loop and the results read of the model at one pose: a fresh value per solve, with
    the calling thread's Pinocchio model (its stem placed for this pose)."""

    machine: Machine
    model: pin.Model
    constraint_models: list[pin.ConstraintModel]
    plate_joint_id: int
    pose_m: np.ndarray  # (3,), m
    q0: np.ndarray  # (nq,) rigid configuration at pose_m
    legv: np.ndarray  # (n, m) v indices of the leg coordinates


@dataclass(kw_only=True)
class _Problem:
    """Everything a solve needs that does not change during the iterations."""

    mm: _PoseModel
    load: np.ndarray
    k: np.ndarray  # (L, m) diagonal spring stiffness of the linear springs per leg coordinate
    rest_rel: np.ndarray  # (L, m) rest values minus q0 (preload offsets on the actuators), m or rad
    lin_mask: np.ndarray  # (L, m) bool: coordinate carries a linear spring
    other: list[tuple[int, int, SpringLaw]]  # nonlinear springs: (leg, col, law)
    legq: np.ndarray  # (L, m) q indices of leg coordinates
    offsets: np.ndarray  # (n,) actuator rest-length offsets, m
    f_ref: float
    l_ref: float
    legv: np.ndarray  # (L, m) v indices of leg coordinates
    act_col: np.ndarray  # (L,) column of the actuator in each leg
    is_force: np.ndarray  # (L, m) translation coordinate (stationarity row in N)
    sc: _Static
    inv_scale: np.ndarray  # (L, m) 1 / (F_ref or F_ref L_ref) per leg stationarity row


def _problem(mm: _PoseModel, sc: _Static, pv: ModelPose, load: np.ndarray, offsets: np.ndarray) -> _Problem:
    """The spring arrays of one pose (fresh; nothing shared with other poses) and the residual scales."""
    rows, cols = sc.spring_at
    k, rest_rel = np.zeros(sc.legv.shape), np.zeros(sc.legv.shape)
    k[rows[sc.lin], cols[sc.lin]] = pv.spring_k[sc.lin]
    rest_rel[rows, cols] = pv.spring_rest
    rest_rel -= pv.q0[sc.legv + 1]
    rest_rel[np.arange(len(sc.act_col)), sc.act_col] += offsets
    f_pre = float(np.max(np.abs(pv.spring_k[sc.act_spring] * offsets)))
    l_ref = mm.machine.geometry.base_half_side_m
    f, m = load[:3].tolist(), load[3:].tolist()
    f_ref = max(math.hypot(*f), math.hypot(*m) / l_ref, f_pre)
    f_ref = f_ref if f_ref > 0 else 1.0
    return _Problem(mm=mm, load=load, k=k, rest_rel=rest_rel, lin_mask=sc.lin_mask, other=sc.other, legq=sc.legv + 1,
                    offsets=offsets, f_ref=f_ref, l_ref=l_ref, legv=sc.legv, act_col=sc.act_col, is_force=sc.is_force,
                    sc=sc, inv_scale=np.where(sc.is_force, 1.0 / f_ref, 1.0 / (f_ref * l_ref)))


@dataclass(kw_only=True)
class _State:
    q: np.ndarray
    s: np.ndarray  # (n, 6, m) leg twists
    sp: np.ndarray  # (6, 6) plate twists
    pe: np.ndarray  # (n, 3) leg end points
    pd: np.ndarray  # (n, 3) plate anchor points
    pc: np.ndarray  # (3,) plate centre
    rp: np.ndarray  # (3, 3) plate rotation
    c: np.ndarray  # (n, 6) closure residual (world)
    a: np.ndarray  # (n, 6, m) wrench map (closure Jacobian on the manifold), leg part
    p: np.ndarray  # (n, 6, 6) wrench map, plate part
    ja: np.ndarray  # (n, 6, m) exact closure Jacobian dc/dq, leg part (rotation rows with Jlog3)
    jp: np.ndarray  # (n, 6, 6) exact closure Jacobian, plate part
    g_leg: np.ndarray  # (n, m) spring forces
    g_plate: np.ndarray  # (6,) -Q_load
    ktan: np.ndarray  # (n, m) spring tangent stiffness


def _evaluate(pb: _Problem, q: np.ndarray, data: pin.Data, d_leg: np.ndarray | None = None) -> _State:
    """Kinematics, closure, spring forces at q; ``d_leg`` = q - q0 on the leg coordinates (kept apart so
    that spring forces keep full relative precision however stiff the springs: q ~ 1 m, q - rest ~ 1e-6 m).
    One Pinocchio pass (``computeJointJacobians``: placements and joint twists); ``data`` keeps the
    placements at q for :func:`_result`."""
    mm, sc = pb.mm, pb.sc
    if d_leg is None:
        d_leg = q[pb.legq] - mm.q0[pb.legq]
    pin.computeJointJacobians(mm.model, data, q)
    jac, oMi = data.J, data.oMi
    s = jac[:, pb.legv].transpose(1, 0, 2)  # (L, 6, m) leg twists (v, omega), world, about the origin
    sp = jac[:, :6]
    op = oMi[mm.plate_joint_id]
    rp, pc = op.rotation.copy(), op.translation.copy()
    ends = [oMi[j] for j in sc.plate_end]
    pe = np.array([oe.translation for oe in ends])
    pd = pc + sc.anchors.T @ rp.T  # (n, 3)
    rd = rp @ sc.frames0  # (n, 3, 3) anchor orientations
    rel = [oe.rotation @ rd[i].T for i, oe in enumerate(ends)]  # R_E R_D^T
    c = np.empty((len(ends), 6))
    c[:, :3] = pe - pd
    c[:, 3:] = [pin.log3(r) for r in rel]
    c[np.abs(c) < CLOSURE_FLOOR] = 0.0  # round-off of ~1 m positions: no information (module doc)
    a = s.copy()  # wrench map, leg part (L, 6, m): twist about O -> (velocity of the point, omega)
    a[:, :3] -= _skew(pe) @ s[:, 3:]  # v + omega x p = v - skew(p) omega
    p = np.empty((len(ends), 6, 6))  # plate part (L, 6, 6)
    p[:, :3] = _skew(pd) @ sp[3:] - sp[:3]
    p[:, 3:] = -sp[3:]
    # d log3(R) for R = R_E R_D^T, world angular velocities: exp(w_E) R = R exp(R^T w_E) and R exp(-w_D), so
    # dc = Jlog3(R) (R^T w_E - w_D) = Jlog3(R)^T w_E - Jlog3(R) w_D  (Jlog3 R^T = Jlog3^T, its left form)
    jl = np.array([pin.Jlog3(r) for r in rel])
    ja, jp = a.copy(), p.copy()
    ja[:, 3:], jp[:, 3:] = jl.transpose(0, 2, 1) @ a[:, 3:], jl @ p[:, 3:]
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
    return _State(q=q, s=s, sp=sp, pe=pe, pd=pd, pc=pc, rp=rp, c=c, a=a, p=p, ja=ja, jp=jp, g_leg=g_leg,
                  g_plate=g_plate, ktan=ktan)


@dataclass(kw_only=True)
class _Factor:
    """The KKT matrix [H J^T; J 0] factored by per-leg elimination and a 6x6 plate Schur complement."""

    lu: list  # per leg: LAPACK LU (lu, piv) of the leg's own KKT block [H_i A_i^T; A_i 0], (m+6)^2
    zz: np.ndarray  # (L, m+6, 6): leg solution per unit plate displacement
    pt: np.ndarray  # (L, 6, 6) plate part of the closure Jacobian, transposed
    schur: tuple  # LAPACK LU of the 6x6 plate Schur complement
    m: int


def _kkt_solve(st: _State, h_leg: np.ndarray, h_plate: np.ndarray, r_leg: np.ndarray, r_plate: np.ndarray,
               rhs_c: np.ndarray, check: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray, _Factor]:
    """Solve [H J^T; J 0][dq; lam] = [r; rhs_c]: (dq_leg, dq_plate, lam) and the factorisation (for
    :func:`_kkt_apply`). Per leg one LAPACK gesv of the leg's KKT block with 7 right-hand sides (the 6
    plate-displacement columns and the load), then the 6x6 plate Schur complement."""
    nl, m = h_leg.shape[:2]
    kkt = np.zeros((nl, m + 6, m + 6))
    kkt[:, :m, :m] = h_leg
    kkt[:, :m, m:] = st.a.transpose(0, 2, 1)
    kkt[:, m:, :m] = st.ja
    rhs = np.zeros((nl, m + 6, 7))
    rhs[:, m:, :6] = -st.jp
    rhs[:, :m, 6] = r_leg
    rhs[:, m:, 6] = rhs_c
    sol = np.empty((nl, m + 6, 7))
    lus = []
    for i in range(nl):  # direct LAPACK: numpy's batched linalg costs more on 35x35 blocks
        lu, piv, sol[i], info = _gesv(kkt[i], rhs[i])
        if info != 0:
            raise SingularPoseError(f"leg {i + 1}'s elastic KKT block is singular (a leg mechanism has no stiffness)",
                                    pose_m=st.pc)
        lus.append((lu, piv))
    zz, z = sol[:, :, :6], sol[:, :, 6]
    pt = st.p.transpose(0, 2, 1)
    schur = h_plate + (pt @ zz[:, m:]).sum(0)
    if check:
        sv = _gesdd(schur, compute_uv=0)[1].tolist()
        if not all(map(math.isfinite, sv)) or sv[-1] <= 1e-13 * sv[0]:
            raise SingularPoseError("the plate stiffness is singular at this pose "
                                    f"(condition {sv[0] / max(sv[-1], 1e-300):.3g})", pose_m=st.pc,
                                    smallest_singular_value=sv[-1])
    lu, piv, info = _getrf(schur)
    if info != 0:
        raise SingularPoseError("the plate stiffness is singular at this pose", pose_m=st.pc)
    fa = _Factor(lu=lus, zz=zz, pt=pt, schur=(lu, piv), m=m)
    dp = _getrs(lu, piv, r_plate - (pt @ z[:, m:, None]).sum(0)[:, 0])[0]
    sol = z + zz @ dp
    return sol[:, :m], dp, sol[:, m:], fa


def _kkt_apply(fa: _Factor, r_leg: np.ndarray, r_plate: np.ndarray, rhs_c: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Solve [H J^T; J 0][dq; lam] = [r; rhs_c] with a factored KKT matrix: (dq_leg, dq_plate, lam)."""
    m = fa.m
    rhs = np.concatenate([r_leg, rhs_c], 1)
    z = np.array([_getrs(lu, piv, rhs[i])[0] for i, (lu, piv) in enumerate(fa.lu)])  # (L, m+6)
    dp = _getrs(*fa.schur, r_plate - (fa.pt @ z[:, m:, None]).sum(0)[:, 0])[0]
    sol = z + fa.zz @ dp
    return sol[:, :m], dp, sol[:, m:]


def _stationarity(pb: _Problem, st: _State, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r_leg = st.g_leg + (lam[:, None, :] @ st.a)[:, 0]
    r_plate = st.g_plate + (lam[:, None, :] @ st.p).sum(0)[0]
    return r_leg, r_plate


def _scaled_stationarity(pb: _Problem, mm: _PoseModel, r_leg: np.ndarray, r_plate: np.ndarray) -> float:
    # leg rows: N m for revolutes, N for prismatics; plate rows: (N, N m)
    rp = np.abs(r_plate)
    return max(float(np.max(np.abs(r_leg) * pb.inv_scale)), float(rp[:3].max()) / pb.f_ref,
               float(rp[3:].max()) / (pb.f_ref * pb.l_ref))


def _dq(mm: _PoseModel, dq_leg: np.ndarray, dp: np.ndarray) -> np.ndarray:
    dv = np.empty(mm.model.nv)
    dv[:6] = dp
    dv[mm.legv] = dq_leg
    return dv


# --- public API ----------------------------------------------------------------------------------------
StepLimit = Callable[[np.ndarray], float]  # dv (model velocity coordinates) -> step factor in (0, 1]


@dataclass(kw_only=True)
class _Worker:
    """One thread's own Pinocchio model (stem placed per solve), data and constraint datas."""

    model: pin.Model
    data: pin.Data
    sc: _Static


class EquilibriumSolver:
    """The static equilibrium solver of one machine model, built once and reused over poses and loads.

    It owns its :class:`MachineModel` (never modified) and, per thread, a copy of the Pinocchio model
    with its data. Every :meth:`solve` takes the pose-dependent values afresh
    (:meth:`MachineModel.pose_values`) and writes the pose's stem placements into the calling thread's
    copy before anything reads it, so no state carries over from one pose or call to the next.

    Threads: one solver may be shared; each thread uses its own model copy and data (created on its
    first solve). Processes: picklable; the pickle holds the model's description (machine, springs per
    segment, cardan compliance, build pose) and the model is rebuilt on unpickling.
    """

    def __init__(self, machine_or_model: Machine | MachineModel, *, springs_per_segment: int | None = None,
                 cardan_compliance: CardanComplianceSpec = None, pose_m: np.ndarray | None = None) -> None:
        """A solver for a built :class:`MachineModel`, or for a machine: its model is built at ``pose_m``
        (m; default: x = z = 0, mid-range leg length) with ``springs_per_segment`` and
        ``cardan_compliance`` (see :func:`pressfit.mechanics.model.build_model`)."""
        if isinstance(machine_or_model, MachineModel):
            if springs_per_segment is not None or cardan_compliance is not None:
                raise PressfitError("springs_per_segment and cardan_compliance are fixed by a built model")
            self.model = machine_or_model
        else:
            pose = kinematics.reference_pose_m(machine_or_model) if pose_m is None else pose_m
            self.model = build_model(machine_or_model, pose, springs_per_segment=springs_per_segment,
                                     cardan_compliance=cardan_compliance)
        self._structure = _static(self.model)  # checks the model's legs once
        self._local = threading.local()

    @property
    def machine(self) -> Machine:
        return self.model.machine

    def __getstate__(self) -> dict[str, Machine | int | CardanComplianceSpec | np.ndarray]:
        mm = self.model
        return {"machine": mm.machine, "springs_per_segment": mm.springs_per_segment,
                "cardan_compliance": mm.cardan_compliance, "pose_m": mm.pose_m}

    def __setstate__(self, state: dict) -> None:
        self.__init__(build_model(state["machine"], state["pose_m"], springs_per_segment=state["springs_per_segment"],
                                  cardan_compliance=state["cardan_compliance"]))

    def _worker(self) -> _Worker:
        w = getattr(self._local, "worker", None)
        if w is None:
            model = self.model.model.copy()
            w = self._local.worker = _Worker(model=model, data=data_pool.lend(model), sc=_static(self.model))
        return w

    def solve(self, pose_m: np.ndarray, plate_wrench: np.ndarray, *,
              preload: Amplitudes | ActuatorPreload | None = None, preload_mode: str | None = None,
              linear: bool = False, tol: float = NEWTON_TOL, max_iter: int = 25,
              start: Equilibrium | None = None, preload_offsets_m: np.ndarray | None = None,
              step_limit: StepLimit | None = None) -> Equilibrium:
        """Static equilibrium at a reachable pose (m) under a dead plate wrench (6,) (N, N m; world axes, at
        the plate centre; a force (3,) alone is accepted), after an optional actuator preload along v_p.

        ``preload``: a4 (N in force mode, m in length mode; :mod:`pressfit.mechanics.preload`; the n - 3
        amplitudes of a machine whose redundancy is not 1) or an
        :class:`ActuatorPreload`; ``preload_mode`` overrides its mode. Preload first, then load.
        Geometrically nonlinear Newton by default (``tol``: relative stationarity and closure, module doc);
        ``linear=True``: small-displacement solve at the assembled pose. Raises UnreachablePoseError,
        SingularPoseError, ConvergenceError, UnstableEquilibriumError, and ResidualError when a relative
        residual exceeds :func:`residual_tolerance` (``tol``).

        Continuation hooks (nonlinear solve; used by :mod:`pressfit.mechanics.clearance`): ``start``, a
        previous solution at the same pose, to start Newton from (its q and multipliers);
        ``preload_offsets_m``, explicit actuator rest-length offsets (n,) in m instead of ``preload``;
        ``step_limit(dv)``, a factor in (0, 1] scaling each Newton step (dv over the velocity coordinates).
        """
        load = _wrench(plate_wrench)
        pv = self.model.pose_values(pose_m)  # checks reachability
        offsets = _offsets(self.machine, pv.pose_m, preload, preload_mode, preload_offsets_m)
        pb, data = self._problem(pv, load, offsets)
        eq = _solve_linear(pb, data) if linear else _solve_nonlinear(pb, data, tol, max_iter, start, step_limit)
        _check_physical(self.machine, eq)  # first: a branch beyond buckling is named as such
        enforce_residuals(eq.residuals.relative()[None], residual_tolerance(tol),
                          f"{'linear' if linear else 'nonlinear'} equilibrium", lambda i: _where(eq))
        return eq

    def stability_at(self, pose_m: np.ndarray, plate_wrench: np.ndarray, q: np.ndarray, multipliers: np.ndarray,
                     *, linear: bool, preload_offsets_m: np.ndarray) -> Stability:
        """The stability report every solve here carries, for an equilibrium of this model found elsewhere
        (the batched :mod:`pressfit.mechanics.fast_statics`): the exact tangent at configuration q (the
        assembled one if ``linear``, as :func:`_solve_linear` takes it) with the multipliers (n, 6) (N, N m),
        under the plate wrench (N, N m) after the actuator rest-length offsets (n,) (m)."""
        pv = self.model.pose_values(pose_m)
        pb, data = self._problem(pv, _wrench(plate_wrench),
                                 np.asarray(preload_offsets_m, dtype=float).reshape(len(self.machine.legs)))
        q = np.asarray(q, dtype=float)
        st = _evaluate(pb, pb.mm.q0, data) if linear else _evaluate(pb, q, data, q[pb.legq] - pb.mm.q0[pb.legq])
        return reduced_stability(*_tangent(pb, st, np.asarray(multipliers, dtype=float)), st.ja, st.jp, pb.is_force,
                                 pb.l_ref)

    def _problem(self, pv: ModelPose, load: np.ndarray, offsets: np.ndarray) -> tuple[_Problem, pin.Data]:
        """The problem at one pose on this thread's model copy, its stem placed for the pose first."""
        w = self._worker()
        self.model.place_stem(w.model, pv.stem_lengths_m)
        mm = _PoseModel(machine=self.machine, model=w.model, constraint_models=self.model.constraint_models,
                        plate_joint_id=self.model.plate_joint_id, pose_m=pv.pose_m, q0=pv.q0, legv=w.sc.legv)
        return _problem(mm, w.sc, pv, load, offsets), w.data


def _wrench(plate_wrench: np.ndarray) -> np.ndarray:
    load = np.asarray(plate_wrench, dtype=float).reshape(-1)
    if load.shape == (3,):
        load = np.concatenate([load, np.zeros(3)])
    if load.shape != (6,) or not np.all(np.isfinite(load)):
        raise PressfitError(f"plate_wrench must be 3 or 6 finite numbers (F in N, then M in N m), got {plate_wrench!r}")
    return load


def _offsets(machine: Machine, pose: np.ndarray, preload: Amplitudes | ActuatorPreload | None, preload_mode: str | None,
             preload_offsets_m: np.ndarray | None) -> np.ndarray:
    """Actuator rest-length offsets (n,), m: explicit, or from the preload (:mod:`pressfit.mechanics.preload`)."""
    if preload_offsets_m is not None:
        return np.asarray(preload_offsets_m, dtype=float).reshape(len(machine.legs))
    if isinstance(preload, ActuatorPreload):
        a4, mode = preload.a4, preload_mode or preload.mode
    else:
        a4, mode = (0.0 if preload is None else preload), preload_mode or "force"
    return rest_length_offsets(machine, pose, a4, mode)


def solve_equilibrium(
    system: Machine | MachineModel | EquilibriumSolver,
    pose_m: np.ndarray,
    plate_wrench: np.ndarray,
    *,
    preload: Amplitudes | ActuatorPreload | None = None,
    preload_mode: str | None = None,
    linear: bool = False,
    tol: float = NEWTON_TOL,
    max_iter: int = 25,
    start: Equilibrium | None = None,
    preload_offsets_m: np.ndarray | None = None,
    step_limit: StepLimit | None = None,
) -> Equilibrium:
    """One equilibrium (:meth:`EquilibriumSolver.solve`, same keywords) of a machine, a built model or a
    solver. Convenience: for a machine it builds the model and a solver each call (~0.1 s; a built model:
    ~5 ms for the solver's index structure and model copy; ``benchmarks/bench_statics.py`` measures both);
    a loop over poses or loads builds one :class:`EquilibriumSolver` and reuses it.
    """
    if isinstance(system, EquilibriumSolver):
        solver = system
    elif isinstance(system, MachineModel):
        solver = EquilibriumSolver(system)
    else:
        solver = EquilibriumSolver(system, pose_m=pose_m)
    return solver.solve(pose_m, plate_wrench, preload=preload, preload_mode=preload_mode, linear=linear, tol=tol,
                        max_iter=max_iter, start=start, preload_offsets_m=preload_offsets_m, step_limit=step_limit)


# Range of validity (not stability): a leg whose length changes by more than 1% is outside the model's small
# strains. It takes an axial force of at least 0.01 l / c_axial ~ 2.5e5 N (c_axial ~ 2e-8 m/N, l >= 0.5 m), a
# stress above 350 MPa in the 30 mm stem, beyond structural steel's yield. (A cap on the plate displacement
# is not a strain limit: at (0, 0.8, 0) a 2.7 kN lateral force rotates the plate by 0.1 rad and moves it
# 17 mm with every strain small.)
MAX_AXIAL_STRAIN = 0.01


def _check_physical(machine: Machine, eq: Equilibrium) -> None:
    """Refuse an unstable equilibrium: the tangent stiffness on the closure manifold is not positive definite
    (the load is beyond the machine's buckling load; the branch Newton found is meaningless); and a leg
    strained beyond the model's small-strain range (MAX_AXIAL_STRAIN)."""
    s = eq.stability
    if not s.stable:
        raise UnstableEquilibriumError(
            f"no stable equilibrium {_where(eq)}: the tangent stiffness on the closure manifold has smallest "
            f"eigenvalue {s.min_eigenvalue_nm:.4g} N m (largest {s.max_eigenvalue_nm:.4g} N m) and the KKT matrix "
            f"{s.kkt_negative_eigenvalues} negative eigenvalues for {s.constraints} constraints: the load is "
            "beyond the machine's buckling load", pose_m=eq.pose_m, load=eq.load)
    lengths = kinematics.inverse_kinematics(machine, eq.pose_m).lengths_m
    strain = np.abs(eq.actuator_forces_n) * machine.axial_compliance_m_per_n(lengths) / lengths
    if strain.max() > MAX_AXIAL_STRAIN:
        i = int(np.argmax(strain))
        raise UnstableEquilibriumError(f"leg {i + 1} {_where(eq)} changes length by {100 * strain[i]:.3g}% "
                                       f"(axial force {eq.actuator_forces_n[i]:.4g} N), beyond the "
                                       f"{100 * MAX_AXIAL_STRAIN:g}% small-strain range of this linear-elastic model",
                                       leg=i + 1, pose_m=eq.pose_m, load=eq.load)


def residual_tolerance(tol: float = NEWTON_TOL) -> float:
    """The tolerance a solve with Newton tolerance ``tol`` is held to: RESIDUAL_TOL, or 10 tol if looser."""
    return max(RESIDUAL_TOL, 10.0 * float(tol))


def enforce_residuals(relative: np.ndarray, tolerance: float, what: str, where: Callable[[int], str]) -> None:
    """Refuse solutions whose relative residuals (b, 7) (RESIDUAL_NAMES order) exceed ``tolerance`` (NaN
    included): ResidualError naming the worst residual of the first such solution, located by ``where(i)``."""
    bad = ~(relative <= tolerance)
    if not bad.any():
        return
    i = int(np.argmax(bad.any(1)))
    k = int(np.argmax(np.where(np.isnan(relative[i]), np.inf, relative[i])))
    raise ResidualError(what, RESIDUAL_NAMES[k], float(relative[i, k]), tolerance, where(i))


def _where(eq: Equilibrium) -> str:
    pose = ", ".join(f"{x:.6g}" for x in eq.pose_m.tolist())
    load = ", ".join(f"{x:.6g}" for x in eq.load.tolist())
    return f"at pose ({pose}) m under the load ({load}) (N, N m)"


def _force_rows(mm: MachineModel) -> np.ndarray:
    """(n, m) True where the leg coordinate is a translation (its stationarity row is a force, N)."""
    prism = {int(mm.model.joints[j].idx_v) for j in range(1, mm.model.njoints)
             if mm.model.joints[j].shortname().startswith("JointModelP")}
    return np.array([[int(v) in prism for v in legv] for legv in mm.leg_v])


def _solve_linear(pb: _Problem, data: pin.Data) -> Equilibrium:
    mm = pb.mm
    if mm.machine.has_cardan_tilts:
        raise PressfitError(f"{mm.machine.source or mm.machine.name}: the linear solve needs a stress-free closed "
                            "reference, which misaligned cardans (base/plate_cardan_tilt_rad) do not have; use the "
                            "nonlinear solve")
    st = _evaluate(pb, mm.q0, data)
    k = st.ktan
    r_leg, r_plate = -st.g_leg, -st.g_plate
    # the reference is closed in exact arithmetic (equation 1): its closure residual, round-off, is taken as 0
    dq_leg, dp, lam, fa = _kkt_solve(st, _diag(k), np.zeros((6, 6)), r_leg, r_plate, np.zeros(st.c.shape))

    def errors():  # residual of the linear KKT system
        r_l, r_p = _stationarity(pb, st, lam)  # g + J^T lam (g = -r)
        e_c = -(st.ja @ dq_leg[:, :, None])[:, :, 0] - st.jp @ dp
        return r_leg - k * dq_leg - (r_l - st.g_leg), r_plate - (r_p - st.g_plate), e_c

    d1, d2, d3 = _kkt_apply(fa, *errors())  # one step of iterative refinement: residuals ~3e-16 (1e-14 without;
    dq_leg, dp, lam = dq_leg + d1, dp + d2, lam + d3  # a second step changes nothing measurable)
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
    """Exact tangent blocks: legs (n, m, m) and plate (6, 6) (module doc). The n + 1 dead wrenches (the
    multipliers at the leg ends; their opposites plus minus the load on the plate) in one batch."""
    nl = len(lam)
    lf, lm = lam[:, :3], lam[:, 3:]
    f, m = pb.load[:3], pb.load[3:]
    sk = _skew(np.concatenate([lf, f[None], st.pe, st.pd, st.pc[None]]))  # skew of lf (n), f, pe (n), pd (n), pc
    sf, sp = sk[:nl + 1], sk[nl + 1:]
    fp = sf[np.r_[0:nl, 0:nl, nl]] @ sp  # (2 n + 1, 3, 3): lf x pe (n), lf x pd (n), f x pc
    xs = (sp @ np.concatenate([lf, lf, f[None]])[:, :, None])[:, :, 0]  # pe x lf (n), pd x lf (n), pc x f
    w = np.empty((nl + 1, 15))  # per wrench: f, moment about O, skew(f) skew(p) flattened
    w[:nl, :3], w[:nl, 3:6], w[:nl, 6:] = lf, xs[:nl] + lm, fp[:nl].reshape(nl, 9)
    w[nl, :3] = -f - lf.sum(0)  # on the plate: minus the load at pc, and -(lf, pd x lf + lm) at pd per leg
    w[nl, 3:6] = -(xs[2 * nl] + m) - (xs[nl:2 * nl] + lm).sum(0)
    w[nl, 6:] = (-fp[2 * nl] - fp[nl:2 * nl].sum(0)).reshape(9)
    phi, psi = _phi_psi(w[:, :3], w[:, 3:6], w[:, 6:].reshape(nl + 1, 3, 3))
    st_ = st.s.transpose(0, 2, 1)
    g = st_[:, None] @ np.stack([phi[:nl], psi[:nl]], 1) @ st.s[:, None]  # (n, 2, m, m)
    h_leg = g[:, 1] - g[:, 0] * pb.sc.lower
    nc = h_leg.shape[1]
    h_leg.reshape(nl, nc * nc)[:, ::nc + 1] += st.ktan
    h_plate = st.sp.T @ (psi[nl] - phi[nl]) @ st.sp
    return h_leg, h_plate


def _solve_nonlinear(pb: _Problem, data: pin.Data, tol: float, max_iter: int, start: Equilibrium | None = None,
                     step_limit: StepLimit | None = None) -> Equilibrium:
    mm = pb.mm
    q = mm.q0.copy() if start is None else start.q.copy()
    d_leg = np.zeros(pb.legq.shape) if start is None else start.q[pb.legq] - mm.q0[pb.legq]
    lam = np.zeros(pb.legq.shape[:1] + (6,)) if start is None else start.multipliers.copy()
    stat = np.inf
    for it in range(max_iter + 1):
        st = _evaluate(pb, q, data, d_leg)
        r_leg, r_plate = _stationarity(pb, st, lam)
        stat = _scaled_stationarity(pb, mm, r_leg, r_plate)
        ac = np.abs(st.c)
        clos = max(float(ac[:, :3].max()) / pb.l_ref, float(ac[:, 3:].max()))
        if stat <= tol and clos <= tol:
            return _result(pb, st, lam, q, d_leg, stat, it, linear=False, data=data)
        if it == max_iter:
            break
        h_leg, h_plate = _tangent(pb, st, lam)
        dq_leg, dp, lam_new, _ = _kkt_solve(st, h_leg, h_plate, -st.g_leg, -st.g_plate, -st.c, check=it == 0)
        a = 1.0 if step_limit is None else float(step_limit(_dq(mm, dq_leg, dp)))
        dq_leg, dp, lam = a * dq_leg, a * dp, lam + a * (lam_new - lam)
        d_leg = d_leg + dq_leg
        q = pin.integrate(mm.model, q, _dq(mm, dq_leg, dp))
        q[pb.legq] = mm.q0[pb.legq] + d_leg
    raise ConvergenceError("nonlinear equilibrium (Newton on the KKT system)", max(stat, clos), tol, max_iter)


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of 3-vectors along the last axis, broadcast (np.cross costs ~20 us a call)."""
    return (_skew(a) @ b[..., None])[..., 0]


def _result(pb: _Problem, st: _State, lam: np.ndarray, q: np.ndarray, d_leg: np.ndarray, stat: float,
            iterations: int, linear: bool, data: pin.Data, dv: np.ndarray | None = None) -> Equilibrium:
    """Section resultants, plate motion and residuals from the state st (at q0 if linear, else at q), whose
    evaluation left ``data`` with the placements at that configuration."""
    mm, sc = pb.mm, pb.sc
    model = mm.model
    f_load, m_load = pb.load[:3], pb.load[3:]
    lf, lm = lam[:, :3], lam[:, 3:]
    oMi = data.oMi
    # section points (n legs, 3 sections, xyz) and deformed leg frames
    nl = len(lam)
    pts = np.array([oMi[j].translation for j in sc.sec_joints]).reshape(nl, 3, 3)
    for i, k, z in sc.sec_z:
        pts[i, k] += oMi[sc.sec_joints[3 * i + k]].rotation[:, 2] * z
    ez = pts[:, 2] - pts[:, 0]
    ez /= np.sqrt((ez * ez).sum(1))[:, None]
    ax = mm.machine.cardan_axes
    ex = ax - (ax * ez).sum(1)[:, None] * ez
    ex /= np.sqrt((ex * ex).sum(1))[:, None]
    frames = np.stack([ex, _cross3(ez, ex), ez], -1)  # (n, 3, 3), columns e_x, e_y, e_z
    force = -lf  # the plate's wrench on each leg end, carried to the sections (no loads along the leg)
    mom = _cross3(st.pe[:, None, :] - pts, force[:, None, :]) - lm[:, None, :]  # (n, 3, 3), world
    fl = (force[:, None, :] @ frames)[:, 0].tolist()  # (n, 3) leg-frame components
    ml = (mom @ frames).tolist()  # (n, 3 sections, 3)
    ac = pb.act_col
    legs = np.arange(nl)
    act = np.where(pb.lin_mask[legs, ac], pb.k[legs, ac] * (d_leg[legs, ac] - pb.rest_rel[legs, ac]), 0.0)
    legs = tuple(LegLoads(sections={name: SectionWrench(N=fl[i][2], V_x=fl[i][0], V_y=fl[i][1],
                                                           M_x=ml[i][k][0], M_y=ml[i][k][1], T=ml[i][k][2])
                                             for k, name in enumerate(SECTIONS)}, frame=frames[i], actuator_force_n=a)
                 for i, a in enumerate(act.tolist()))
    # residuals: the plate (from the multipliers), and the whole machine from the spring forces alone
    pc = st.pc
    plate = np.concatenate([f_load + lf.sum(0), m_load + (_cross3(st.pd - pc, lf) + lm).sum(0)])
    machine = _machine_residual(pb, st, st.g_leg + st.ktan * d_leg if linear else st.g_leg)
    cds = sc.cds
    for cm, cd in zip(mm.constraint_models, cds):
        cm.calc(model, data, cd)
    if linear:  # linearised closure: Pinocchio's constraint Jacobian at q0 times the displacement
        e = (pin.getConstraintsJacobian(model, data, mm.constraint_models, cds) @ dv).reshape(nl, 6)
    else:
        e = np.array([cd.extract().constraint_position_error for cd in cds])
    fm = np.sqrt(np.array([plate[:3] @ plate[:3], plate[3:] @ plate[3:], machine[:3] @ machine[:3],
                           machine[3:] @ machine[3:]])) / (pb.f_ref * np.array([1, pb.l_ref, 1, pb.l_ref]))
    en = np.sqrt((e * e).reshape(nl, 2, 3).sum(2)).max(0)
    res = Residuals(**dict(zip(RESIDUAL_NAMES, [*fm.tolist(), *en.tolist(), float(stat)], strict=True)),
                    force_scale_n=pb.f_ref, length_scale_m=pb.l_ref)
    if linear:  # the free flyer's v is in its local frame; at q0 the plate is world-aligned
        disp, rot = dv[:3].copy(), dv[3:6].copy()
    else:
        disp, rot = pc - mm.pose_m, pin.log3(st.rp)
    stab = reduced_stability(*_tangent(pb, st, lam), st.ja, st.jp, pb.is_force, pb.l_ref)
    return Equilibrium(pose_m=mm.pose_m.copy(), load=pb.load.copy(), legs=legs, actuator_forces_n=act,
                       plate_displacement_m=disp, plate_rotation_rad=rot, q=q, multipliers=lam.copy(),
                       iterations=iterations, linear=linear, residuals=res, stability=stab,
                       preload_offsets_m=pb.offsets.copy())


@dataclass(frozen=True, kw_only=True)
class ReferenceTangent:
    """Dense tangent data of the linear reference state (for :func:`pressfit.mechanics.buckling.machine_buckling`),
    in the model's velocity coordinates (rad, m; plate: translation, rotation)."""

    elastic: np.ndarray  # (nv, nv) spring stiffness K_e (N m/rad, N/m)
    geometric: np.ndarray  # (nv, nv) geometric stiffness of the linear multipliers and the load
    jacobian: np.ndarray  # (6 n, nv) closure Jacobian at the reference
    leg_v: np.ndarray  # (n, m) velocity indices of each leg's coordinates
    axial_forces_n: np.ndarray  # (n,) linear actuator forces, N, > 0 tension


def reference_tangent(solver: EquilibriumSolver, pose_m: np.ndarray, plate_wrench: np.ndarray,
                      offsets_m: np.ndarray | None) -> ReferenceTangent:
    """Linear solve at a pose (m) under a plate wrench (6,) (N, N m) with actuator offsets (n,) (m), and the
    tangent there split into K_e and the geometric part (linear in the wrench and the offsets)."""
    offsets = np.zeros(len(solver.machine.legs)) if offsets_m is None else np.asarray(offsets_m, dtype=float)
    pv = solver.model.pose_values(pose_m)
    pb, data = solver._problem(pv, np.asarray(plate_wrench, dtype=float), offsets)
    eq = _solve_linear(pb, data)
    st = _evaluate(pb, pv.q0, data)
    h_leg, h_plate = _tangent(pb, st, eq.multipliers)
    nv = pb.mm.model.nv
    full, jac = np.zeros((nv, nv)), np.zeros((6 * len(pb.legv), nv))
    full[:6, :6] = h_plate
    for i, v in enumerate(pb.legv):
        full[np.ix_(v, v)] = h_leg[i]
        jac[6 * i:6 * i + 6, v], jac[6 * i:6 * i + 6, :6] = st.ja[i], st.jp[i]
    k_e = np.zeros((nv, nv))
    k_e[pb.legv, pb.legv] = st.ktan
    return ReferenceTangent(elastic=k_e, geometric=full - k_e, jacobian=jac, leg_v=pb.legv,
                            axial_forces_n=eq.actuator_forces_n)


def _machine_residual(pb: _Problem, st: _State, g_leg: np.ndarray) -> np.ndarray:
    """Sum of the base reactions plus the load (6,), (N, N m about the world origin), independent of the
    multipliers: the wrench W_i (about O) that leg i carries is the one whose generalised forces on the
    leg's joints balance its spring forces g_i (m equations for 6 unknowns: the cardans give S_k . W = 0,
    the springs S_k . W = -g_k), solved by least squares over the joint twists S (from Pinocchio). At
    equilibrium sum_i W_i + (F, M + p_c x F) = 0 (the legs are massless and unloaded along their length)."""
    s = st.s  # (L, 6, m) twists about O
    w = np.linalg.solve(s @ s.transpose(0, 2, 1), -(s @ g_leg[:, :, None]))[:, :, 0]  # (L, 6)
    f = pb.load[:3]
    return w.sum(0) + np.concatenate([f, pb.load[3:] + _cross3(st.pc, f)])


def solve_case(case: Case, linear: bool = False) -> list[Equilibrium]:
    """Every (pose, load) pair of a case file (poses outer, loads inner), after the case's preload, with one
    solver; ``linear`` or the case's ``[solver] linear`` selects the small-displacement solve. A case with
    ``[clearance]`` is refused: this solver has rigid cardans (:mod:`pressfit.mechanics.clearance` models the play)."""
    if case.clearance is not None:
        raise PressfitError(f"{case.path} has a [clearance] table, which this solve does not model (rigid cardans): "
                            "use 'pressfit study preload' or 'pressfit check' for cardan clearance")
    poses, loads = case.poses.array(), case.loads.wrenches()
    solver = EquilibriumSolver(case.machine(), pose_m=poses[0])
    preload = ActuatorPreload.from_case(case.preload) if any(case.preload.amplitudes) else None
    return [solver.solve(h, w, preload=preload, linear=linear or case.solver.linear) for h in poses for w in loads]
