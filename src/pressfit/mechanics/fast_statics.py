r"""Fast equilibrium of the VJM model (:mod:`pressfit.mechanics.model`), batched over poses, numpy only.

Same model, same equations and same answers as :class:`pressfit.mechanics.statics.EquilibriumSolver`
(the reference, which every result here is tested against); different algorithm and data layout:

* Kinematics without Pinocchio: each leg is a serial chain of one-axis joints whose placements are
  translations along the parent's z (the first one (R0_i, B_i)). The chain is walked once per Newton
  iteration for every pose and leg at once (arrays (poses, n legs, ...)): rotating two columns of the
  frame per revolute, so each numpy call works on the whole batch. Pose-dependent stem placements and
  spring stiffnesses come from :meth:`MachineModel.stem_placements_z` and
  :meth:`MachineModel.spring_stiffness` (batched).
* Static condensation of each leg to its tip: with spring coordinates s (stiffness k_s > 0) and free
  coordinates f (the cardans' revolutes), the leg's stationarity k_s dq_s + A_s^T lambda = -g_s and
  A_f^T lambda = 0 eliminate dq_s = -x_s - k_s^-1 A_s^T lambda (x_s the spring extension), so closure
  A dq + P dp = -c becomes, per leg, the (6 + n_f) system

      [-C  A_f; A_f^T  0] [lambda; dq_f] = [-c + A_s x_s - P dp; 0],   C = A_s k_s^-1 A_s^T (tip compliance),

  and the plate's 6x6 system  sum_i P_i^T lambda_i = (F, M)  closes it. One batched solve per iteration.
* Modified Newton: the iteration matrix is the elastic one at the current configuration (closure
  Jacobians A, P re-evaluated, geometric stiffness left out). It converges linearly at the ratio of
  geometric to elastic stiffness (about 1e-3 here, so 1e-10 in 4-5 iterations) to the same fixed point:
  the residual tested is the exact one (stationarity g + J^T lambda and closure c at the current q, the
  reference's residuals and scales, :mod:`pressfit.mechanics.statics`).

``linear=True``: one step from the assembled pose (the small-displacement KKT solve of the reference),
sections on the undeformed geometry. With rigid cardans (the default model) this step is closed form
(:func:`_straight`): at the assembled pose every leg is straight, so all the joints between the two
cardans share the leg frame R and lie on the leg axis (p_c = B + s_c e_z), and a spring column's twist
in the leg frame is (e_a x e_z u_c, e_a) (revolute about e_a, lever u_c = L - s_c to the tip) or
(e_a, 0) (prismatic). The four free cardan revolutes (two at B, two at the tip) leave a leg two
transmitted wrenches, N = [(e_z, 0), (f, n)]: the axial force and the couple n = w_3 x w_4 normal to
both plate cardan axes with the force f (normal to e_z) that makes it do no work on the base cardan
axes w_1, w_2 ((w_k x L e_z) . f = -w_k . n). With lambda = N mu each leg reduces to the 2x2
S = N^T C N (C the tip compliance), the plate to K = sum_i Q_i S_i^-1 Q_i^T (Q_i = P_i^T N_i): one 6x6
solve per pose, the free joint motions from the closure in the dual bases of the cardan axes.
Plate coordinates: centre translation (world) and a world rotation
vector applied on the left (R <- exp(dtheta) R); closure rotation error log3(R_E R_D^T) as the reference.

Joint positions as data: ``solve_batch(base_points_m=..., plate_offsets_m=...)`` gives every solve its own base
and plate cardan centres B_i, d_i (a Monte Carlo sample's joint position errors). Only the chain's first
placement and its anchor on the plate depend on them (the cardan axes and leg frames R0_i do not); the leg
lengths, which set the stem placements and the stem and actuator stiffnesses, come from each solve's inverse
kinematics. So one model serves every layout, with the answers of a machine built with those errors (tested
against the reference solver on that machine). Cardan misalignments do not fit this path: their rigid
configuration is a least-squares assembly (Pinocchio, per pose) and their legs are not straight.

Supported: rigid or linear-spring cardans (``cardan_compliance`` with :class:`LinearSpring` laws, a
cardan rotational stiffness), actuator preload (offsets). Refused: springs with nonlinear laws (the
clearance dead zones; :mod:`pressfit.mechanics.clearance` keeps using the reference solver).
Memory: no Pinocchio Data (whose size grows as nv^3 in pin 4.1), so it serves any spring count.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pressfit.description.machine import Machine
from pressfit.errors import ConvergenceError, FastSolverError, PressfitError, SingularPoseError
from pressfit.mechanics.model import MachineModel, build_model
from pressfit.mechanics.preload import Amplitudes, rest_length_offsets
from pressfit.mechanics.stability import Stability
from pressfit.mechanics.statics import (
    NEWTON_TOL,
    RESIDUAL_NAMES,
    SECTION_COMPONENTS,
    SECTIONS,
    Equilibrium,
    EquilibriumSolver,
    LegLoads,
    Residuals,
    SectionWrench,
    _check_physical,
    _wrench,
    enforce_residuals,
    residual_tolerance,
)
from pressfit.spatial import cross, skew

_CHUNK = 1024  # poses per block: the per-leg arrays of a block stay in the CPU cache


@dataclass(frozen=True, kw_only=True)
class _Chain:
    """Pose-independent structure of the n (identical) leg chains, columns in chain order."""

    axis: np.ndarray  # (m,) local joint axis 0 x, 1 y, 2 z
    prismatic: np.ndarray  # (m,) bool
    z: np.ndarray  # (n, m) placement translation along the parent's z, m (stem columns set per pose)
    stem_cols: np.ndarray  # (n + 1,) columns whose placement depends on the stem length
    r0: np.ndarray  # (n, 3, 3) first placement's rotation
    b: np.ndarray  # (n, 3) first placement's translation (base cardan centre), m
    spring_cols: np.ndarray  # (m_s,) columns carrying a spring
    free_cols: np.ndarray  # (m_f,) columns without one
    spring_index: np.ndarray  # (n, m_s) index in mm.springs
    rigid_cols: np.ndarray  # (5,) columns of base a, base b, prismatic, plate b, plate a
    act_col: int
    sec: tuple[tuple[int, float], ...]  # per section: (column, z offset along that body's z), m
    anchors: np.ndarray  # (n, 3) plate cardan centres in the plate frame, m
    frames0: np.ndarray  # (n, 3, 3) anchor orientations in the plate frame
    force_rows: np.ndarray  # (m,) translation coordinate


def _chain(mm: MachineModel) -> _Chain:
    """The chain structure, checking that the legs are identical serial chains of one-axis joints placed
    along z, with linear springs only (module doc)."""
    model = mm.model
    legv = np.array(mm.leg_v)
    if np.isnan(mm.spring_k).any():
        raise FastSolverError("the fast solver supports linear springs only; this model has nonlinear laws "
                              "(cardan clearance): use pressfit.mechanics.statics.EquilibriumSolver")
    jid = {int(model.joints[j].idx_v): j for j in range(1, model.njoints)}
    joints = [[jid[int(v)] for v in row] for row in legv]
    kinds = [[model.joints[j].shortname()[-2:] for j in row] for row in joints]
    if any(k != kinds[0] for k in kinds):
        raise FastSolverError("the fast solver needs identical leg chains (same virtual joints on every leg)")
    pl = model.jointPlacements
    z = np.array([[pl[j].translation[2] for j in row] for row in joints])
    z[:, 0] = 0.0
    for row in joints:
        for j in row[1:]:
            if not (np.allclose(pl[j].rotation, np.eye(3)) and np.allclose(pl[j].translation[:2], 0)):
                raise FastSolverError(f"joint {model.names[j]}: placement is not a translation along z")
    col = {int(v): c for row in legv for c, v in enumerate(row)}
    legs = range(len(legv))
    spring_at = np.array([[col[s.idx_v] for s in mm.springs if s.leg == i] for i in legs])
    spring_idx = np.array([[k for k, s in enumerate(mm.springs) if s.leg == i] for i in legs])
    if np.any(spring_at != spring_at[0]):
        raise FastSolverError("the fast solver needs the springs at the same place on every leg")
    order = np.argsort(spring_at[0])
    scols = spring_at[0][order]
    col_q = {int(v) + 1: c for c, v in enumerate(legv[0])}
    rigid = np.array([col_q[int(mm._rigid_idx[k][0])] for k in ("base_a", "base_b", "prismatic", "plate_b",
                                                                "plate_a")])
    jcol = {j: c for c, j in enumerate(joints[0])}
    act = int(scols[[mm.springs[k].name == "actuator" for k in spring_idx[0][order]]][0])
    return _Chain(
        axis=np.array(["XYZ".index(k[1]) for k in kinds[0]]),
        prismatic=np.array([k[0] == "P" for k in kinds[0]]),
        z=z,
        stem_cols=np.array([jcol[j] for j in mm.stem_joint_ids()[0]]),
        r0=np.array([pl[r[0]].rotation for r in joints]),
        b=np.array([pl[r[0]].translation for r in joints]),
        spring_cols=scols,
        free_cols=np.setdiff1d(np.arange(legv.shape[1]), scols),
        spring_index=spring_idx[:, order],
        rigid_cols=rigid,
        act_col=act,
        sec=tuple((jcol[mm.sections[0][s][0]], mm.sections[0][s][1]) for s in SECTIONS),
        anchors=np.array([a.translation for a in mm.anchor_placements]),
        frames0=np.array(mm.leg_frames0),
        force_rows=np.array([k[0] == "P" for k in kinds[0]]),
    )


@dataclass(frozen=True)
class _Straight:
    """Constants of the closed-form linear solve (module doc), per spring column in chain order."""

    base: np.ndarray  # (m_s, 6) local twist part independent of the lever: (e_a, 0) prismatic, (0, e_a) revolute
    lever: np.ndarray  # (m_s, 6) part per metre of lever to the tip: (e_a x e_z, 0) revolute, 0 prismatic


def _straight(ch: _Chain) -> _Straight | None:
    """The closed-form constants when the chain is cardan (2 free revolutes at B), springs and prismatic
    joints along z, cardan (2 free revolutes at the tip), with the sections on the straight part or at the
    tip; None otherwise (cardan springs: the general condensed step)."""
    m = len(ch.axis)
    free = [0, 1, m - 2, m - 1]
    if (list(ch.free_cols) != free or ch.prismatic[free].any() or np.any(ch.axis[ch.prismatic] != 2)
            or np.any(ch.z[:, [1, m - 1]] != 0) or np.isin([1, m - 1], ch.stem_cols).any()
            or any(not (1 <= c <= m - 3 or (c == m - 1 and off == 0)) for c, off in ch.sec)):
        return None
    e = np.eye(3)[ch.axis[ch.spring_cols]]
    prism = ch.prismatic[ch.spring_cols, None]
    zero = np.zeros_like(e)
    return _Straight(np.concatenate([np.where(prism, e, 0.0), np.where(prism, 0.0, e)], -1),
                     np.concatenate([np.where(prism, 0.0, np.cross(e, [0.0, 0.0, 1.0])), zero], -1))


def _turn(frame: np.ndarray, axis: int, q: np.ndarray) -> np.ndarray:
    """Frames (..., 3, 3) (columns) turned by the angles q (...) about their own axis 0 x, 1 y, 2 z."""
    i, j = (axis + 1) % 3, (axis + 2) % 3
    c, s = np.cos(q)[..., None], np.sin(q)[..., None]
    out = frame.copy()
    out[..., :, i] = frame[..., :, i] * c + frame[..., :, j] * s
    out[..., :, j] = frame[..., :, j] * c - frame[..., :, i] * s
    return out


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return (a * b).sum(-1)


@dataclass(kw_only=True)
class _Kin:
    """Kinematics of a block of poses (b poses, n legs, m columns)."""

    w: np.ndarray  # (b, n, m, 3) joint axes, world
    p: np.ndarray  # (b, n, m, 3) joint origins, world, m
    sec: np.ndarray  # (b, n, 3 sections, 3) section points, m
    pe: np.ndarray  # (b, n, 3) leg end (plate cardan centre), m
    re: np.ndarray  # (b, n, 3, 3) leg end orientation


def _kinematics(ch: _Chain, q: np.ndarray, z: np.ndarray, base: np.ndarray) -> _Kin:
    """Walk the chains for leg coordinates q (b, n, m), placements z (b, n, m) and base cardan centres
    base (b, n, 3) (m)."""
    nb, nl, m = q.shape
    cols = [np.broadcast_to(ch.r0[:, :, k], (nb, nl, 3)).copy() for k in range(3)]
    pos = base.copy()
    cq, sq = np.cos(q)[..., None], np.sin(q)[..., None]
    w, p = np.empty((nb, nl, m, 3)), np.empty((nb, nl, m, 3))
    sec_col = {c: k for k, (c, _) in enumerate(ch.sec)}
    sec = np.empty((nb, nl, 3, 3))
    for c in range(m):
        if c:
            pos = pos + cols[2] * z[:, :, c, None]
        a = int(ch.axis[c])
        w[:, :, c], p[:, :, c] = cols[a], pos
        if ch.prismatic[c]:
            pos = pos + cols[a] * q[:, :, c, None]
        else:
            i, j = (a + 1) % 3, (a + 2) % 3
            ci, cj, cc, ss = cols[i], cols[j], cq[:, :, c], sq[:, :, c]
            cols[i], cols[j] = ci * cc + cj * ss, cj * cc - ci * ss
        if c in sec_col:
            k = sec_col[c]
            sec[:, :, k] = pos + cols[2] * ch.sec[k][1]
    return _Kin(w=w, p=p, sec=sec, pe=pos, re=np.stack(cols, -1))


def _log3(r: np.ndarray) -> np.ndarray:
    """Rotation vectors (..., 3) of rotation matrices (..., 3, 3) near the identity (|angle| < pi/2)."""
    v = np.stack([r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]], -1) / 2
    s = np.sqrt((v * v).sum(-1))
    c = (np.trace(r, axis1=-2, axis2=-1) - 1) / 2
    ang = np.arctan2(s, c)
    return v * np.where(s > 1e-300, ang / np.where(s > 1e-300, s, 1.0), 1.0)[..., None]


def _exp3(v: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of rotation vectors (..., 3) (Rodrigues)."""
    t = np.sqrt((v * v).sum(-1))[..., None, None]
    k = skew(v)
    small = t < 1e-8
    a = np.where(small, 1 - t * t / 6, np.sin(t) / np.where(small, 1, t))
    b = np.where(small, 0.5 - t * t / 24, (1 - np.cos(t)) / np.where(small, 1, t * t))
    return np.eye(3) + a * k + b * (k @ k)


@dataclass(frozen=True, kw_only=True)
class BatchEquilibrium:
    """Equilibria at b poses (SI; legs in kinematic order; conventions of :class:`Equilibrium`)."""

    pose_m: np.ndarray  # (b, 3) nominal plate-centre poses
    load: np.ndarray  # (b, 6) plate wrench (N, N m), world, at the plate centre
    actuator_forces_n: np.ndarray  # (b, n), > 0 tension
    sections: np.ndarray  # (b, n, 3, 6) per leg and section (base, actuator, plate): N, V_x, V_y, M_x, M_y, T
    frames: np.ndarray  # (b, n, 3, 3) deformed leg frames (columns e_x, e_y, e_z)
    plate_displacement_m: np.ndarray  # (b, 3)
    plate_rotation_rad: np.ndarray  # (b, 3) rotation vector, world
    multipliers: np.ndarray  # (b, n, 6) force (N), couple (N m) each leg exerts on the plate, world
    q: np.ndarray  # (b, nq) Pinocchio configuration of the reference model
    iterations: np.ndarray  # (b,) Newton iterations to convergence
    residuals: np.ndarray  # (b, 7) plate force, plate moment, machine force, machine moment, closure m, rad,
    #                        stationarity (relative, :class:`Residuals`)
    force_scale_n: np.ndarray  # (b,) F_ref
    length_scale_m: float
    preload_offsets_m: np.ndarray  # (b, n) actuator rest-length offsets
    linear: bool
    base_points_m: np.ndarray  # (b, n, 3) base cardan centres B_i of each solve, world
    plate_offsets_m: np.ndarray  # (b, n, 3) plate cardan centres d_i of each solve, plate frame

    def equilibrium(self, i: int, stability: Stability) -> Equilibrium:
        """Pose i as the reference solver's :class:`Equilibrium`, with its stability report (computed by
        :meth:`FastEquilibriumSolver.equilibrium`)."""
        s = self.sections[i].tolist()
        legs = tuple(LegLoads(sections={name: SectionWrench(**dict(zip(SECTION_COMPONENTS, s[leg][k], strict=True)))
                                        for k, name in enumerate(SECTIONS)},
                              frame=self.frames[i, leg], actuator_force_n=float(self.actuator_forces_n[i, leg]))
                     for leg in range(self.actuator_forces_n.shape[1]))
        res = Residuals(**dict(zip(RESIDUAL_NAMES, self.residuals[i].tolist(), strict=True)),
                        force_scale_n=float(self.force_scale_n[i]), length_scale_m=self.length_scale_m)
        return Equilibrium(pose_m=self.pose_m[i].copy(), load=self.load[i].copy(), legs=legs,
                           actuator_forces_n=self.actuator_forces_n[i].copy(),
                           plate_displacement_m=self.plate_displacement_m[i].copy(),
                           plate_rotation_rad=self.plate_rotation_rad[i].copy(), q=self.q[i].copy(),
                           multipliers=self.multipliers[i].copy(), iterations=int(self.iterations[i]),
                           linear=self.linear, residuals=res, stability=stability,
                           preload_offsets_m=self.preload_offsets_m[i].copy())


@dataclass(kw_only=True)
class _Block:
    """The pose-dependent constants of a block of poses."""

    pose: np.ndarray  # (b, 3), m
    load: np.ndarray  # (b, 6)
    q0: np.ndarray  # (b, nq)
    q0leg: np.ndarray  # (b, n, m)
    z: np.ndarray  # (b, n, m) placements, m
    ks: np.ndarray  # (b, n, m_s) spring stiffnesses
    rest: np.ndarray  # (b, n, m_s) spring rest offsets from q0 (the actuator preload offsets)
    offsets: np.ndarray  # (b, n), m
    base: np.ndarray  # (b, n, 3) base cardan centres B_i, m
    anchors: np.ndarray  # (b, n, 3) plate cardan centres d_i in the plate frame, m
    f_ref: np.ndarray  # (b,), N
    row_scale: np.ndarray  # (b, 1, m) 1 / (F_ref or F_ref L_ref) per leg stationarity row


def _plate_jacobian(r: np.ndarray) -> np.ndarray:
    """P (b, n, 6, 6): closure rows of the plate coordinates (centre translation, world rotation) for
    anchor arms r = p_D - p_C (b, n, 3)."""
    p = np.zeros(r.shape[:-1] + (6, 6))
    p[..., :3, :3] = p[..., 3:, 3:] = -np.eye(3)
    p[..., :3, 3:] = skew(r)
    return p


class FastEquilibriumSolver:
    """Batched equilibrium of one machine model (module doc), tested against the reference solver.

    Built like :class:`pressfit.mechanics.statics.EquilibriumSolver` (a built model, or a machine with
    ``springs_per_segment``, ``cardan_compliance`` and the build pose). Holds no per-call state: thread-safe
    and picklable (the model is rebuilt on unpickling only through the reference solver's pickling
    contract; here the built model itself is pickled by description).
    """

    def __init__(self, machine_or_model: Machine | MachineModel, *, springs_per_segment: int | None = None,
                 cardan_compliance: object = None, pose_m: np.ndarray | None = None) -> None:
        if isinstance(machine_or_model, MachineModel):
            self.model = machine_or_model
        else:
            from pressfit.kinematics import reference_pose_m

            pose = reference_pose_m(machine_or_model) if pose_m is None else pose_m
            self.model = build_model(machine_or_model, pose, springs_per_segment=springs_per_segment,
                                     cardan_compliance=cardan_compliance)
        if self.model.machine.has_cardan_tilts:
            raise PressfitError(f"{self.machine.source or self.machine.name}: the fast solver assumes parallel "
                                "cardan axes (its reference is the closed form); misaligned cardans "
                                "(base/plate_cardan_tilt_rad) need the reference solver (statics.EquilibriumSolver)")
        self._chain = _chain(self.model)
        self._reference = EquilibriumSolver(self.model)  # stability reports (Pinocchio Data made on first use)
        self._straight = _straight(self._chain)
        self._legq = np.array(self.model.leg_v) + 1

    @property
    def machine(self) -> Machine:
        return self.model.machine

    def solve(self, pose_m: np.ndarray, plate_wrench: np.ndarray, *, preload: Amplitudes | None = None,
              preload_mode: str = "force", linear: bool = False, tol: float = NEWTON_TOL,
              max_iter: int = 25) -> Equilibrium:
        """One pose (convenience over :meth:`solve_batch`; batches are where the speed is), with the
        reference's physical-range check."""
        batch = self.solve_batch(np.asarray(pose_m, dtype=float).reshape(1, 3), _wrench(plate_wrench)[None],
                                 preload=preload, preload_mode=preload_mode, linear=linear, tol=tol, max_iter=max_iter)
        return self.equilibrium(batch, 0)

    def equilibrium(self, batch: BatchEquilibrium, i: int) -> Equilibrium:
        """Pose i of a batch as the reference solve reports it: with its stability (the reference's exact
        tangent at this solution, :meth:`EquilibriumSolver.stability_at`, ~1 ms) and the same physical
        checks (raises UnstableEquilibriumError for an unstable or over-strained solution). Refuses a pose solved
        with joint positions other than the model's (its stability needs that layout's own model)."""
        if not (np.array_equal(batch.base_points_m[i], self._chain.b)
                and np.array_equal(batch.plate_offsets_m[i], self._chain.anchors)):
            raise FastSolverError(f"pose {i} of the batch was solved with joint positions other than the model's: its "
                                  "stability report needs the reference solver on that machine "
                                  "(statics.EquilibriumSolver)")
        stab = self._reference.stability_at(batch.pose_m[i], batch.load[i], batch.q[i], batch.multipliers[i],
                                            linear=batch.linear, preload_offsets_m=batch.preload_offsets_m[i])
        eq = batch.equilibrium(i, stab)
        _check_physical(self.machine, eq)
        return eq

    def solve_batch(self, poses_m: np.ndarray, plate_wrenches: np.ndarray, *, preload: Amplitudes | None = None,
                    preload_mode: str = "force", preload_offsets_m: np.ndarray | None = None,
                    base_points_m: np.ndarray | None = None, plate_offsets_m: np.ndarray | None = None,
                    linear: bool = False, tol: float = NEWTON_TOL, max_iter: int = 25) -> BatchEquilibrium:
        """Equilibria at reachable poses (b, 3) (m) under plate wrenches (b, 6) or (6,) (N, N m; world, at
        the plate centre), after an actuator preload a4 along v_p (N in force mode, m in length mode;
        :mod:`pressfit.mechanics.preload`; n - 3 amplitudes unless the redundancy is 1) or explicit
        rest-length offsets (b, n) (m). ``base_points_m`` B_i (world) and ``plate_offsets_m`` d_i (plate frame),
        (b, n, 3) or (n, 3), m: each solve's joint positions (default the model's): the same equilibrium as a
        machine with those joint position errors and its own model (leg lengths, hence stem placements and
        stiffnesses, from its inverse kinematics; the cardan axes are the model's); they take explicit
        ``preload_offsets_m``. Geometrically
        nonlinear by default (``tol``: the reference's relative stationarity and closure); ``linear=True``:
        the small-displacement solve. Raises UnreachablePoseError, SingularPoseError, ConvergenceError, and
        ResidualError when a solution's relative residuals exceed statics.residual_tolerance(tol)."""
        h = np.asarray(poses_m, dtype=float).reshape(-1, 3)
        w = np.asarray(plate_wrenches, dtype=float)
        w = np.broadcast_to(_wrench(w) if w.ndim == 1 else w, (len(h), 6))
        if not np.all(np.isfinite(w)):
            raise PressfitError("plate wrenches must be finite (F in N, then M in N m)")
        nl = len(self.machine.legs)
        base, anchors = (self._layout(name, a, default, len(h)) for name, a, default in (
            ("base_points_m", base_points_m, self._chain.b), ("plate_offsets_m", plate_offsets_m, self._chain.anchors)))
        if preload_offsets_m is not None:
            offsets = np.broadcast_to(np.asarray(preload_offsets_m, dtype=float), (len(h), nl))
        elif preload is not None and np.any(preload):
            if base_points_m is not None or plate_offsets_m is not None:
                raise PressfitError("a preload amplitude is defined on the model's joint positions; with other joint "
                                    "positions give the rest-length offsets (preload_offsets_m, m)")
            offsets = rest_length_offsets(self.machine, h, preload, preload_mode)
        else:
            offsets = np.zeros((len(h), nl))
        blocks = (slice(i, i + _CHUNK) for i in range(0, len(h), _CHUNK))
        parts = [self._solve_block(self._block(h[k], w[k], offsets[k], base[k], anchors[k]), linear, tol, max_iter)
                 for k in blocks]
        batch = BatchEquilibrium(**{k: np.concatenate([p[k] for p in parts]) for k in parts[0]},
                                 length_scale_m=self.machine.geometry.base_half_side_m,
                                 preload_offsets_m=np.array(offsets, dtype=float), linear=linear,
                                 base_points_m=np.array(base), plate_offsets_m=np.array(anchors))
        relative = batch.residuals.copy()
        relative[:, 4] /= batch.length_scale_m  # closure in m -> relative, as Residuals.relative
        enforce_residuals(relative, residual_tolerance(tol), f"{'linear' if linear else 'nonlinear'} equilibrium "
                          "(fast solver)", lambda i: f"at pose {tuple(batch.pose_m[i].tolist())} m under the load "
                          f"{tuple(batch.load[i].tolist())} (N, N m)")
        return batch

    def _layout(self, name: str, points: np.ndarray | None, default: np.ndarray, b: int) -> np.ndarray:
        """Joint positions (b, n, 3) (m) of the solves: ``points`` ((b, n, 3) or (n, 3)) or the model's."""
        shape = (b,) + default.shape
        a = default if points is None else np.asarray(points, dtype=float)
        if a.shape not in (shape, shape[1:]):
            raise PressfitError(f"{name}: joint positions (m) of shape {shape} or {shape[1:]} (one per leg), got "
                                f"{a.shape}")
        if not np.all(np.isfinite(a)):
            raise PressfitError(f"{name}: joint positions must be finite (m)")
        return np.broadcast_to(a, shape)

    def _block(self, h: np.ndarray, w: np.ndarray, offsets: np.ndarray, base: np.ndarray,
               anchors: np.ndarray) -> _Block:
        mm, ch = self.model, self._chain
        q0 = mm.configurations(h, base_points_m=base, plate_offsets_m=anchors)
        q0leg = q0[:, self._legq]
        lengths = q0leg[:, :, ch.rigid_cols[2]]
        z = np.broadcast_to(ch.z, q0leg.shape).copy()
        z[:, :, ch.stem_cols] = mm.stem_placements_z(lengths - self.machine.cylinder.length_m)
        ks = mm.spring_stiffness(lengths)[:, ch.spring_index]
        rest = np.zeros(ks.shape)
        act = int(np.flatnonzero(ch.spring_cols == ch.act_col)[0])
        rest[:, :, act] = offsets
        l_ref = self.machine.geometry.base_half_side_m
        f_ref = np.maximum.reduce([np.linalg.norm(w[:, :3], axis=1), np.linalg.norm(w[:, 3:], axis=1) / l_ref,
                                   np.abs(ks[:, :, act] * offsets).max(1)])
        f_ref = np.where(f_ref > 0, f_ref, 1.0)
        row = np.where(ch.force_rows, 1.0, l_ref)[None, None] * f_ref[:, None, None]
        return _Block(pose=h, load=w, q0=q0, q0leg=q0leg, z=z, ks=ks, rest=rest, offsets=offsets, base=base,
                      anchors=anchors, f_ref=f_ref, row_scale=1.0 / row)

    def _evaluate(self, bk: _Block, d: np.ndarray, pc: np.ndarray, rp: np.ndarray
                  ) -> tuple[_Kin, np.ndarray, np.ndarray, np.ndarray]:
        """Kinematics, closure residual c (b, n, 6), leg Jacobian transposed A^T (b, n, m, 6) and anchor
        arms r = p_D - p_C (b, n, 3) at leg offsets d from q0 and plate (pc, rp)."""
        ch = self._chain
        kin = _kinematics(ch, bk.q0leg + d, bk.z, bk.base)
        r = np.einsum("bij,blj->bli", rp, bk.anchors)
        rd = rp[:, None] @ ch.frames0
        c = np.concatenate([kin.pe - pc[:, None] - r, _log3(kin.re @ rd.swapaxes(-1, -2))], -1)
        prism = ch.prismatic[:, None]
        lin = np.where(prism, kin.w, cross(kin.w, kin.pe[:, :, None] - kin.p))
        at = np.concatenate([lin, np.where(prism, 0.0, kin.w)], -1)
        return kin, c, at, r

    def _residuals(self, bk: _Block, c: np.ndarray, at: np.ndarray, r: np.ndarray, lam: np.ndarray,
                   x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Relative stationarity and closure (b,) (the reference's scales, :mod:`pressfit.mechanics.statics`)."""
        r_leg = (at @ lam[..., None])[..., 0]
        r_leg[:, :, self._chain.spring_cols] += bk.ks * x
        return self._stationarity(bk, r_leg, r, lam), self._closure(c)

    def _stationarity(self, bk: _Block, r_leg: np.ndarray, r: np.ndarray, lam: np.ndarray) -> np.ndarray:
        """Relative stationarity (b,) of leg rows r_leg (b, n, m) (N or N m) and the plate."""
        l_ref = self.machine.geometry.base_half_side_m
        lf = lam[..., :3]
        r_plate = np.concatenate(
            [-bk.load[:, :3] - lf.sum(1), -bk.load[:, 3:] - (cross(r, lf) + lam[..., 3:]).sum(1)], 1
        )
        return np.maximum(np.abs(r_leg * bk.row_scale).max((1, 2)),
                          np.maximum(np.abs(r_plate[:, :3]).max(1), np.abs(r_plate[:, 3:]).max(1) / l_ref) / bk.f_ref)

    def _closure(self, c: np.ndarray) -> np.ndarray:
        """Relative closure (b,) of c (b, n, 6) (m, rad)."""
        return np.maximum(np.abs(c[..., :3]).max((1, 2)) / self.machine.geometry.base_half_side_m,
                          np.abs(c[..., 3:]).max((1, 2)))

    def _step(self, bk: _Block, c: np.ndarray, at: np.ndarray, r: np.ndarray, x: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The condensed elastic KKT solve (module doc): (dq_f, dq_s, dp, lambda)."""
        ch = self._chain
        ast, aft = at[:, :, ch.spring_cols], at[:, :, ch.free_cols]
        nf = aft.shape[2]
        kkt = np.zeros(c.shape[:2] + (6 + nf, 6 + nf))
        kkt[..., :6, :6] = -((ast / bk.ks[..., None]).swapaxes(-1, -2) @ ast)
        kkt[..., :6, 6:] = aft.swapaxes(-1, -2)
        kkt[..., 6:, :6] = aft
        pj = _plate_jacobian(r)
        rhs = np.zeros(c.shape[:2] + (6 + nf, 7))
        rhs[..., :6, :6] = -pj
        rhs[..., :6, 6] = -c + (ast.swapaxes(-1, -2) @ x[..., None])[..., 0]
        try:
            sol = np.linalg.solve(kkt, rhs)
            pt = pj.swapaxes(-1, -2)
            schur = (pt @ sol[..., :6, :6]).sum(1)
            dp = np.linalg.solve(schur, (bk.load - (pt @ sol[..., :6, 6:]).sum(1)[..., 0])[..., None])[..., 0]
        except np.linalg.LinAlgError:
            raise SingularPoseError("the condensed elastic KKT system is singular at a pose of the batch "
                                    f"(poses {bk.pose.tolist()})") from None
        z = sol[..., 6] + (sol[..., :6] @ dp[:, None, :, None])[..., 0]
        lam = z[..., :6]
        dqs = -x - (ast @ lam[..., None])[..., 0] / bk.ks
        return z[..., 6:], dqs, dp, lam

    def _solve_block(self, bk: _Block, linear: bool, tol: float, max_iter: int) -> dict[str, np.ndarray]:
        if linear and self._straight is not None:
            return self._solve_straight(bk)
        ch = self._chain
        nb = len(bk.pose)
        d, lam = np.zeros(bk.q0leg.shape), np.zeros(bk.q0leg.shape[:2] + (6,))
        pc, rp = bk.pose.copy(), np.broadcast_to(np.eye(3), (nb, 3, 3)).copy()
        iters = np.full(nb, -1)
        for it in range(max_iter + 1):
            kin, c, at, r = self._evaluate(bk, d, pc, rp)
            x = d[:, :, ch.spring_cols] - bk.rest
            stat, clos = self._residuals(bk, c, at, r, lam, x)
            iters[(iters < 0) & (stat <= tol) & (clos <= tol)] = it
            if not linear and np.all(iters >= 0):
                break
            if it == max_iter:
                raise ConvergenceError("nonlinear equilibrium (condensed modified Newton)",
                                       float(np.max(np.maximum(stat, clos))), tol, max_iter)
            dqf, dqs, dp, lam = self._step(bk, c, at, r, x)
            d[:, :, ch.free_cols] += dqf
            d[:, :, ch.spring_cols] += dqs
            if linear:  # the linear KKT residual, and the linearised closure (as the reference reports them)
                stat, _ = self._residuals(bk, np.zeros_like(c), at, r, lam, d[:, :, ch.spring_cols] - bk.rest)
                dq = np.zeros_like(d)
                dq[:, :, ch.free_cols], dq[:, :, ch.spring_cols] = dqf, dqs
                c = (
                    c
                    + (at.swapaxes(-1, -2) @ dq[..., None])[..., 0]
                    + (_plate_jacobian(r) @ dp[:, None, :, None])[..., 0]
                )
                return self._results(bk, kin.sec, kin.pe, c, r, lam, d, pc + dp[:, :3], _exp3(dp[:, 3:]) @ rp, stat,
                                     np.ones(nb, int), dp)
            pc, rp = pc + dp[:, :3], _exp3(dp[:, 3:]) @ rp
        return self._results(bk, kin.sec, kin.pe, c, r, lam, d, pc, rp, stat, iters, None)

    def _straight_legs(self, bk: _Block) -> dict[str, np.ndarray]:
        """Closed-form geometry of the straight legs at the assembled pose (module doc): leg frame rl, tip
        frame re, joint abscissae s (m) along e_z, free axes w (b, n, 4, 3) (the four cardan revolutes), closure c,
        transmitted wrenches n_w (b, n, 6, 2) (world) and n_l (leg frame), and the dual-basis helpers of the cardan
        axes."""
        ch, q = self._chain, bk.q0leg
        a = ch.axis
        f0 = np.broadcast_to(ch.r0, q.shape[:2] + (3, 3))
        f1 = _turn(f0, a[0], q[..., 0])
        rl = _turn(f1, a[1], q[..., 1])
        f3 = _turn(rl, a[-2], q[..., -2])
        re = _turn(f3, a[-1], q[..., -1])
        inc = bk.z.copy()
        inc[..., 1:] += np.where(ch.prismatic, q, 0.0)[..., :-1]
        s = np.cumsum(inc, -1)
        ln = s[..., -1]
        ez = rl[..., :, 2]
        pe = bk.base + ez * ln[..., None]
        c = np.concatenate([pe - bk.pose[:, None] - bk.anchors, _log3(re @ ch.frames0.swapaxes(-1, -2))], -1)
        w = np.stack([f0[..., :, a[0]], rl[..., :, a[1]], rl[..., :, a[-2]], f3[..., :, a[-1]]], -2)
        u = cross(w[..., :2, :], ez[..., None, :])  # base cardan axes x e_z
        v = cross(u, ez[..., None, :])
        det = _dot(u[..., 0, :], v[..., 1, :])
        n = cross(w[..., 2, :], w[..., 3, :])
        nn = _dot(n, n)
        if np.any(np.abs(det) < 1e-9) or np.any(nn < 1e-9):
            bad = np.flatnonzero((np.abs(det) < 1e-9).any(1) | (nn < 1e-9).any(1))[0]
            raise SingularPoseError(f"pose {bk.pose[bad].tolist()} m: a cardan axis is along its leg or the plate "
                                    "cardan axes are parallel (the leg's transmitted wrenches degenerate)",
                                    pose_m=bk.pose[bad])
        b = -_dot(w[..., :2, :], n[..., None, :]) / ln[..., None]
        f = (b[..., :1] * v[..., 1, :] - b[..., 1:] * v[..., 0, :]) / det[..., None]
        n_w = np.zeros(q.shape[:2] + (6, 2))
        n_w[..., :3, 0], n_w[..., :3, 1], n_w[..., 3:, 1] = ez, f, n
        n_l = np.concatenate([rl.swapaxes(-1, -2) @ n_w[..., :3, :], rl.swapaxes(-1, -2) @ n_w[..., 3:, :]], -2)
        return {"rl": rl, "s": s, "ln": ln, "ez": ez, "pe": pe, "c": c, "w": w, "u": u, "v": v, "det": det, "n": n,
                "nn": nn, "n_w": n_w, "n_l": n_l}

    def _solve_straight(self, bk: _Block) -> dict[str, np.ndarray]:
        """The linear solve in closed form for straight legs (module doc), by BatchEquilibrium field."""
        ch = self._chain
        g = self._straight_legs(bk)
        ln, n_w = g["ln"], g["n_w"]
        lever = ln[..., None] - g["s"][..., ch.spring_cols]  # (b, n, m_s), m
        gm = self._spring_rows(g["n_l"].swapaxes(-1, -2), lever)  # (b, n, 2, m_s): the two transmitted wrenches
        comp = 1.0 / bk.ks
        gc = gm * comp[..., None, :]
        sm = np.stack([_dot(gc[..., 0, :], gm[..., 0, :]), _dot(gc[..., 0, :], gm[..., 1, :]),
                       _dot(gc[..., 1, :], gm[..., 1, :])], -1)[..., [0, 1, 1, 2]].reshape(gm.shape[:2] + (2, 2))
        sinv = np.stack([sm[..., 1, 1], -sm[..., 0, 1], -sm[..., 1, 0], sm[..., 0, 0]], -1).reshape(sm.shape)
        sinv /= (sm[..., 0, 0] * sm[..., 1, 1] - sm[..., 0, 1] * sm[..., 1, 0])[..., None, None]
        x = -bk.rest
        r = bk.anchors
        pj = _plate_jacobian(r)
        qm = pj.swapaxes(-1, -2) @ n_w  # (b, n, 6, 2)
        nr0 = -(n_w.swapaxes(-1, -2) @ g["c"][..., None])[..., 0] + _dot(gm, x[..., None, :])
        qs = qm @ sinv
        try:
            dp = np.linalg.solve((qs @ qm.swapaxes(-1, -2)).sum(1),
                                 (bk.load + (qs @ nr0[..., None])[..., 0].sum(1))[..., None])[..., 0]
        except np.linalg.LinAlgError:
            raise SingularPoseError(f"the plate stiffness is singular at a pose of the batch (poses {bk.pose.tolist()})"
                                    ) from None
        mu = (sinv @ ((qm.swapaxes(-1, -2) @ dp[:, None, :, None])[..., 0] - nr0)[..., None])[..., 0]
        lam = (n_w @ mu[..., None])[..., 0]
        dqs = -x - comp * (gm * mu[..., None]).sum(-2)
        return self._straight_finish(bk, g, lever, pj, dp, lam, dqs)

    def _spring_rows(self, wrench_l: np.ndarray, lever: np.ndarray) -> np.ndarray:
        """A_s^T lambda (b, n, [k,] m_s) for leg-frame wrenches (b, n, [k,] 6) (N, N m at the tip) and the springs'
        levers (b, n, m_s) (m): each spring column's twist is base + lever * per-metre part (module doc)."""
        st = self._straight
        lever = lever.reshape(lever.shape[:2] + (1,) * (wrench_l.ndim - 3) + lever.shape[2:])
        return np.tensordot(wrench_l, st.base, ([-1], [1])) + lever * np.tensordot(wrench_l, st.lever, ([-1], [1]))

    def _straight_finish(self, bk: _Block, g: dict[str, np.ndarray], lever: np.ndarray, pj: np.ndarray,
                         dp: np.ndarray, lam: np.ndarray, dqs: np.ndarray) -> dict[str, np.ndarray]:
        """Free joint motions from the linearised closure A_f dq_f = t (dual bases of the cardan axes), the
        residuals (free-joint stationarity A_f^T lambda, spring rows, plate; the closure left by dq_f) and
        the results."""
        ch, st, rl, ln, w, u, v, n = self._chain, self._straight, g["rl"], g["ln"], g["w"], g["u"], g["v"], g["n"]
        tl = (dqs @ st.base + (lever * dqs) @ st.lever)[..., None]  # A_s dq_s in the leg frame
        t = -g["c"] - (pj @ dp[:, None, :, None])[..., 0] - np.concatenate([rl @ tl[..., :3, :], rl @ tl[..., 3:, :]],
                                                                         -2)[..., 0]
        scale = ln * g["det"]
        dq = np.empty(w.shape[:3])
        dq[..., 0], dq[..., 1] = _dot(t[..., :3], v[..., 1, :]) / scale, -_dot(t[..., :3], v[..., 0, :]) / scale
        om = t[..., 3:] - dq[..., 0, None] * w[..., 0, :] - dq[..., 1, None] * w[..., 1, :]
        dq[..., 2] = _dot(om, cross(w[..., 3, :], n)) / g["nn"]
        dq[..., 3] = _dot(om, cross(n, w[..., 2, :])) / g["nn"]
        fit = np.concatenate([ln[..., None] * (dq[..., :2, None] * u).sum(-2), (dq[..., None] * w).sum(-2)], -1)
        lf, lm = lam[..., :3], lam[..., 3:]
        d = np.zeros(bk.q0leg.shape)
        d[..., ch.free_cols], d[..., ch.spring_cols] = dq, dqs
        r_leg = np.zeros(d.shape)
        r_leg[..., ch.free_cols[:2]] = ln[..., None] * _dot(u, lf[..., None, :]) + _dot(w[..., :2, :], lm[..., None, :])
        r_leg[..., ch.free_cols[2:]] = _dot(w[..., 2:, :], lm[..., None, :])
        lam_l = np.concatenate([(lf[..., None, :] @ rl)[..., 0, :], (lm[..., None, :] @ rl)[..., 0, :]], -1)
        r_leg[..., ch.spring_cols] = self._spring_rows(lam_l, lever) + bk.ks * (dqs - bk.rest)
        r = bk.anchors
        stat = self._stationarity(bk, r_leg, r, lam)
        s, ez = g["s"], g["ez"]
        pts = np.stack([g["pe"] if col == len(ch.axis) - 1 else bk.base + ez * (s[..., col, None] + off)
                        for col, off in ch.sec], -2)
        return self._results(bk, pts, g["pe"], fit - t, r, lam, d, bk.pose + dp[:, :3], _exp3(dp[:, 3:]), stat,
                             np.ones(len(dp), int), dp)

    def _results(
        self,
        bk: _Block,
        pts: np.ndarray,
        pe: np.ndarray,
        c: np.ndarray,
        r: np.ndarray,
        lam: np.ndarray,
        d: np.ndarray,
        pc: np.ndarray,
        rp: np.ndarray,
        stat: np.ndarray,
        iters: np.ndarray,
        dp_linear: np.ndarray | None,
    ) -> dict[str, np.ndarray]:
        """Sections, plate motion and residuals (statics._result's definitions), by BatchEquilibrium field."""
        ch, l_ref = self._chain, self.machine.geometry.base_half_side_m
        f_load, m_load = bk.load[:, :3], bk.load[:, 3:]
        lf, lm = lam[..., :3], lam[..., 3:]
        ez = pts[:, :, 2] - pts[:, :, 0]
        ez /= np.linalg.norm(ez, axis=-1, keepdims=True)
        ax = self.machine.cardan_axes
        ex = ax - (ax * ez).sum(-1, keepdims=True) * ez
        ex /= np.linalg.norm(ex, axis=-1, keepdims=True)
        frames = np.stack([ex, cross(ez, ex), ez], -1)
        force = -lf
        mom = cross(pe[:, :, None] - pts, force[:, :, None]) - lm[:, :, None]
        fl = (force[:, :, None] @ frames)[:, :, 0]
        ml = mom @ frames
        sections = np.concatenate([np.broadcast_to(fl[:, :, None, [2, 0, 1]], ml.shape), ml], -1)
        act = np.flatnonzero(ch.spring_cols == ch.act_col)[0]
        act_force = bk.ks[:, :, act] * (d[:, :, ch.act_col] - bk.rest[:, :, act])
        pg = pc if dp_linear is None else bk.pose  # the plate centre of the equilibrium geometry
        plate = np.concatenate([f_load + lf.sum(1), m_load + (cross(r, lf) + lm).sum(1)], 1)
        base_m = mom[:, :, 0] + cross(pts[:, :, 0], force)
        mach = np.concatenate([f_load - force.sum(1), m_load + cross(pg, f_load) - base_m.sum(1)], 1)
        scale = np.array([1.0, l_ref])
        fm = np.linalg.norm(np.stack([plate, mach], 1).reshape(-1, 2, 2, 3), axis=-1).reshape(-1, 4)  # 4 balances
        fm /= bk.f_ref[:, None] * np.tile(scale, 2)
        closure = np.linalg.norm(c.reshape(len(c), -1, 2, 3), axis=-1).max(1)
        res = np.concatenate([fm, closure, stat[:, None]], 1)
        q = bk.q0.copy()
        q[:, self._legq] = bk.q0leg + d
        rot = _log3(rp)
        q[:, :3] = pc
        t = np.linalg.norm(rot, axis=-1, keepdims=True)
        q[:, 3:6] = rot * np.where(t > 0, np.sin(t / 2) / np.where(t > 0, t, 1.0), 0.5)
        q[:, 6] = np.cos(t[:, 0] / 2)
        disp, rot = (pc - bk.pose, rot) if dp_linear is None else (dp_linear[:, :3], dp_linear[:, 3:])
        return dict(pose_m=bk.pose, load=bk.load, actuator_forces_n=act_force, sections=sections, frames=frames,
                    plate_displacement_m=disp, plate_rotation_rad=rot, multipliers=lam, q=q, iterations=iters,
                    residuals=res, force_scale_n=bk.f_ref)
