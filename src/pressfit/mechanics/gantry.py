r"""Compliance and static loads of the Cartesian gantry press (:mod:`pressfit.description.gantry`): a Pinocchio
serial chain with elastic virtual joints (VJM), the machinery of :mod:`pressfit.mechanics.model`.

Topology, built afresh at each tool pose (x, y, z) (every member length depends on it):

* branch A from the bed: the left column (root (-span/2, 0, 0), up), then the left part of the X beam from
  the column's top to the X carriage point C = (x, H, 0); branch B likewise with the right column and the
  right part of the X beam (from x = +span/2 toward -x). The portal corners and the column feet are rigid
  (built in); the two branches are welded at C by a 6D closure (the X beam is one continuous beam);
* from branch A's end, the X axis at C, the Z beam (from (x, H - d_xz, 0) to the Z carriage at z), the Z axis
  at the Z carriage, the Y axis at the ram's guide point G = (x, y_G, z) and the ram from G down to the tool
  at (x, y, z). Carriage plates and offsets are rigid.

Each axis is six virtual joints at its carriage point, world-aligned: the prismatic joint along the axis with
the ball-screw drive's axial stiffness, two translations normal to the axis with the guide's normal stiffness,
two rotations about the normals (guide tilt stiffness) and one about the axis (guide roll stiffness).

Each member of length L is split into n = ``springs_per_segment`` sub-segments of length h = L / n with, at
each sub-segment's midpoint (k + 1/2) h from the root (model.py's placement), six virtual joints in the
member frame (x = section width, y = section height, z along the member): rotations with model.py's laws,
bending E I_x / h and E I_y / h, torsion G J / h (N m/rad), the axial spring E A / h (N/m), and one
transverse spring per bending plane (N/m) of compliance

    h^3 / (12 E I) + h / (G A_s)        ("timoshenko", default; A_s the shear area)
    h^3 / (12 E I)                      ("euler_bernoulli")
    none                                ("none": model.py's law, rotational springs only).

Why: model.py's legs carry constant couples, for which midpoint rotational springs are exact; a gantry
member carries shear, and a midpoint spring then misses h^3 / (12 E I) of each sub-segment's tip compliance
(a cantilever's tip deflection comes out F L^3 / (3 E I) (1 - 1 / (4 n^2))). With the transverse spring a
sub-segment reproduces the Euler-Bernoulli (or Timoshenko) beam's end flexibility exactly, so the statics
under loads at the member ends is exact for every n; n only matters for the mass distribution (modes).

Static solve, linear (small displacements about the unloaded geometry): with C the diagonal joint
compliance (0 for a rigid joint), J_t the tool's and J_c = J_A - J_B the closure's LOCAL_WORLD_ALIGNED
Jacobians (``pin.getFrameJacobian``), a tool wrench W gives Q = J_t^T W and

    (J_c C J_c^T) lambda = J_c C Q,   tau = Q - J_c^T lambda,   dq = C tau,

tau being the generalised force each joint transmits (the spring force for an elastic one). The six
joints of a station transmit the wrench of everything beyond it (forces along, moments about their axes):
the section wrench there, as the tip-side part acting on the root-side part in the member frame (N > 0
tension). Members carry no loads between stations (self-weight is left out: the press load alone), so the
bending moment is linear between stations and largest at a member end.

Residuals (relative to F_ref = max(|F|, |M| / L_ref, 1 N), L_ref = the span): the closure J_c dq (m, rad),
the bed reactions (the wrenches through each column's first station, from the joint forces) against the
tool wrench, and the work balance W . u = tau . C tau (Clapeyron). A solution over RESIDUAL_TOL is refused.
The linear solve leaves out P-delta terms of relative size N / N_E (N_E = pi^2 E I / (4 L^2), a cantilever's
Euler load): ``axial_load_ratio``; above MAX_AXIAL_LOAD_RATIO the solve is refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pressfit.description.gantry import GANTRY_AXES, BeamSection, Gantry
from pressfit.errors import PressfitError, ResidualError, UnstableEquilibriumError
from pressfit.mechanics import data_pool
from pressfit.mechanics.model import _JOINT_MODELS
from pressfit.mechanics.statics import RESIDUAL_TOL, SectionWrench
from pressfit.spatial import cross

COMPONENTS = ("column", "x_beam", "z_beam", "ram", "x_axis", "y_axis", "z_axis")  # what ``rigid`` may name
TRANSVERSE_LAWS = ("timoshenko", "euler_bernoulli", "none")
MEMBERS = ("column_left", "column_right", "x_beam", "z_beam", "ram")  # the reported structural members
STATION_JOINTS = ("PX", "PY", "PZ", "RX", "RY", "RZ")  # member frame: transverse x, y, axial, bending x, y, torsion
# per axis, world-aligned: the drive along the axis, the guide's two normal translations, its two tilts, its roll
AXIS_JOINTS = {"x": ("PX", "PY", "PZ", "RY", "RZ", "RX"), "y": ("PY", "PX", "PZ", "RX", "RZ", "RY"),
               "z": ("PZ", "PX", "PY", "RX", "RY", "RZ")}
MAX_AXIAL_LOAD_RATIO = 0.01  # compressive force / Euler load above which the linear solve is refused
_UP, _X, _Z = np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])


def _frame(y_axis: np.ndarray, z_axis: np.ndarray) -> np.ndarray:
    """Member frame (3, 3), columns x = y cross z, y, z (world)."""
    return np.column_stack([cross(y_axis, z_axis), y_axis, z_axis])


@dataclass(frozen=True, kw_only=True)
class Member:
    """One straight elastic member of the model at its pose: ``rotation`` columns are the local x (width),
    y (height) and z (root to tip) axes in the world; ``station_v`` (n, 6) the velocity indices of each
    station's joints (STATION_JOINTS order); ``station_joints`` (n,) each station's last joint (its body
    carries the member from that station on), ``parent_joint`` the body the member is fixed to."""

    name: str  # column_left, column_right, x_beam_left, x_beam_right, z_beam, ram
    component: str  # column, x_beam, z_beam, ram
    section: BeamSection
    root_m: np.ndarray
    rotation: np.ndarray
    length_m: float
    station_v: np.ndarray
    station_joints: np.ndarray
    parent_joint: int

    @property
    def station_s_m(self) -> np.ndarray:
        """(n,) distance of each station from the root, m."""
        n = len(self.station_joints)
        return (np.arange(n) + 0.5) * self.length_m / n

    def point_m(self, s_m: np.ndarray | float) -> np.ndarray:
        """World point(s) at distance s from the root, m."""
        return self.root_m + np.multiply.outer(s_m, self.rotation[:, 2])


@dataclass(frozen=True, kw_only=True)
class MemberMoment:
    """The largest bending moment in a member under one load: its magnitude sqrt(M_x^2 + M_y^2) (N m), where
    (world point, m; distance from the member's root, m: for the X beam from the left column's top), and the
    whole section wrench there (tip-side part on the root-side part, member frame, N > 0 tension)."""

    member: str
    bending_moment_nm: float
    at_m: np.ndarray
    distance_from_root_m: float
    section: SectionWrench


@dataclass(frozen=True, kw_only=True)
class GantryResiduals:
    """Residuals of a gantry solve (module doc): closure in m and rad, the rest relative."""

    closure_m: float
    closure_rad: float
    bed_force: float  # |bed reactions - tool force| / F_ref
    bed_moment: float  # |... moments about the origin| / (F_ref L_ref)
    work: float  # |W . u - tau . C tau| / (F_ref (|u_t| + L_ref |u_r|)), Clapeyron's theorem
    force_scale_n: float
    length_scale_m: float

    def worst(self) -> float:
        return max(self.closure_m / self.length_scale_m, self.closure_rad, self.bed_force, self.bed_moment, self.work)

    def to_dict(self) -> dict[str, float]:
        return {k: float(getattr(self, k)) for k in self.__dataclass_fields__}


@dataclass(frozen=True, kw_only=True)
class GantryEquilibrium:
    """The linear static response of the gantry to a tool wrench at a pose (SI, world axes)."""

    pose_m: np.ndarray  # (3,) tool position (x, y, z)
    tool_wrench: np.ndarray  # (6,) force (N) and moment (N m) on the tool, at the tool point
    tool_displacement_m: np.ndarray  # (3,)
    tool_rotation_rad: np.ndarray  # (3,) rotation vector: the tool's tilt
    drive_forces_n: np.ndarray  # (3,) axial force in the x, y, z drives, > 0 when the load pushes along +axis
    members: dict[str, MemberMoment]  # MEMBERS
    axial_load_ratio: float  # largest compressive member force / its cantilever Euler load
    residuals: GantryResiduals
    joint_displacements: np.ndarray  # (nv,) dq, m or rad
    joint_forces: np.ndarray  # (nv,) tau, the force (N) or moment (N m) each joint transmits

    def to_dict(self) -> dict[str, Any]:
        return {"pose_m": self.pose_m.tolist(), "tool_wrench": self.tool_wrench.tolist(),
                "tool_displacement_m": self.tool_displacement_m.tolist(),
                "tool_rotation_rad": self.tool_rotation_rad.tolist(),
                "drive_forces_n": dict(zip(GANTRY_AXES, self.drive_forces_n.tolist())),
                "members": {k: {"bending_moment_nm": m.bending_moment_nm, "at_m": m.at_m.tolist(),
                                "distance_from_root_m": m.distance_from_root_m, "section": m.section.as_dict()}
                            for k, m in self.members.items()},
                "axial_load_ratio": self.axial_load_ratio, "residuals": self.residuals.to_dict()}


@dataclass(kw_only=True)
class GantryModel:
    """The VJM Pinocchio model of a gantry at one tool pose (module doc); never changed after it is built.

    ``compliance`` (nv,) per joint (m/N or rad/(N m); 0 = rigid); ``axis_v[a]`` the velocity indices of axis
    a's six joints (AXIS_JOINTS order, the drive first) and ``axis_joints[a]`` its carriage body;
    ``tool_jacobian`` (6, nv) and ``closure_jacobian`` (6, nv) are LOCAL_WORLD_ALIGNED (translation first) at
    the tool and at the X carriage point."""

    gantry: Gantry
    pose_m: np.ndarray
    model: pin.Model
    springs_per_segment: int
    transverse: str
    compliance: np.ndarray
    coordinate_names: tuple[str, ...]
    members: tuple[Member, ...]
    axis_v: dict[str, np.ndarray]
    axis_joints: dict[str, int]
    tool_frame: int
    tool_jacobian: np.ndarray
    closure_jacobian: np.ndarray

    @property
    def length_scale_m(self) -> float:
        return self.gantry.frame.span_m

    def _closure_forces(self, q_load: np.ndarray) -> np.ndarray:
        """lambda (6,) of the closure for generalised loads Q (nv,) (minimum norm if the loop is rigid)."""
        jc, c = self.closure_jacobian, self.compliance
        return np.linalg.lstsq((jc * c) @ jc.T, jc @ (c * q_load), rcond=None)[0]

    def tool_compliance(self) -> np.ndarray:
        """6x6 compliance of the tool point: wrench (N, N m) -> translation (m) and rotation (rad), world axes:
        J_t C J_t^T - J_t C J_c^T (J_c C J_c^T)^+ J_c C J_t^T."""
        jt, jc, c = self.tool_jacobian, self.closure_jacobian, self.compliance
        a, b = (jt * c) @ jt.T, (jt * c) @ jc.T
        return a - b @ np.linalg.pinv((jc * c) @ jc.T) @ b.T

    def tool_stiffness_n_per_m(self) -> np.ndarray:
        """The tool's 3x3 translational stiffness (N/m): the inverse of the compliance's force-to-translation
        block (a force on the tool, the tool free to tilt)."""
        return np.linalg.inv(self.tool_compliance()[:3, :3])

    def solve(self, tool_wrench: np.ndarray, tol: float = RESIDUAL_TOL) -> GantryEquilibrium:
        """The linear static response to a tool wrench (6,) (N, N m; world axes, at the tool point), module doc;
        raises ResidualError over ``tol`` and UnstableEquilibriumError beyond MAX_AXIAL_LOAD_RATIO."""
        w = np.asarray(tool_wrench, dtype=float).reshape(6)
        if not np.all(np.isfinite(w)):
            raise PressfitError(f"tool wrench must be finite, got {w.tolist()}")
        q_load = self.tool_jacobian.T @ w
        lam = self._closure_forces(q_load)
        tau = q_load - self.closure_jacobian.T @ lam
        dq = self.compliance * tau
        u = self.tool_jacobian @ dq
        members, ratio, bed = self._member_loads(tau)
        res = self._residuals(w, u, tau, dq, bed)
        eq = GantryEquilibrium(pose_m=self.pose_m.copy(), tool_wrench=w, tool_displacement_m=u[:3],
                               tool_rotation_rad=u[3:], members=members, axial_load_ratio=ratio, residuals=res,
                               drive_forces_n=np.array([tau[self.axis_v[a][0]] for a in GANTRY_AXES]),
                               joint_displacements=dq, joint_forces=tau)
        where = f"at tool pose {tuple(self.pose_m.tolist())} m under the tool wrench {tuple(w.tolist())} (N, N m)"
        if not res.worst() <= tol:
            names = ("closure_m", "closure_rad", "bed_force", "bed_moment", "work")
            values = (res.closure_m / res.length_scale_m, res.closure_rad, res.bed_force, res.bed_moment, res.work)
            k = int(np.argmax(np.where(np.isnan(values), np.inf, values)))
            raise ResidualError("gantry linear solve", names[k], float(values[k]), tol, where)
        if ratio > MAX_AXIAL_LOAD_RATIO:
            raise UnstableEquilibriumError(f"a gantry member {where} carries {100 * ratio:.3g}% of its Euler load, "
                                           f"beyond the {100 * MAX_AXIAL_LOAD_RATIO:g}% this linear solve accepts",
                                           pose_m=self.pose_m, load=w)
        return eq

    def member(self, name: str) -> Member:
        """The model member of that name (Member.name)."""
        return next(mb for mb in self.members if mb.name == name)

    def sections(self, member: Member, joint_forces: np.ndarray, s_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Section force (k, 3) (N) and moment about the section point (k, 3) (N m), member frame, at distances
        ``s_m`` (k,) from the member's root: the tip-side part on the root-side part, from the forces its
        stations transmit (``joint_forces`` tau, (nv,)), carried to the section from the nearest station on
        its tip side (the root end from the first station; nothing loads a member between its stations)."""
        t = joint_forces[member.station_v]
        f, m = t[:, :3] @ member.rotation.T, t[:, 3:] @ member.rotation.T  # world, about the station points
        s_m = np.atleast_1d(np.asarray(s_m, dtype=float))
        k = np.minimum(np.searchsorted(member.station_s_m, s_m - 1e-12 * max(member.length_m, 1.0)), len(t) - 1)
        arm = member.point_m(member.station_s_m[k]) - member.point_m(s_m)
        return f[k] @ member.rotation, (m[k] + cross(arm, f[k])) @ member.rotation

    def section_wrench(self, eq: GantryEquilibrium, member: str, s_m: float) -> SectionWrench:
        """The section wrench of a solution ``eq`` in member ``member`` (Member.name) at s (m) from its root."""
        (f,), (m,) = self.sections(self.member(member), eq.joint_forces, np.array([s_m]))
        return SectionWrench(N=float(f[2]), V_x=float(f[0]), V_y=float(f[1]), M_x=float(m[0]), M_y=float(m[1]),
                             T=float(m[2]))

    def _member_loads(self, tau: np.ndarray) -> tuple[dict[str, MemberMoment], float, np.ndarray]:
        """Largest bending moment per reported member (at its ends and stations), the axial-load ratio, and the
        bed reaction (6,) about the origin (through the columns' first stations)."""
        best: dict[str, MemberMoment] = {}
        ratio, bed = 0.0, np.zeros(6)
        e = self.gantry.material.youngs_modulus_pa
        for mb in self.members:
            s_all = np.concatenate([[0.0], mb.station_s_m, [mb.length_m]])
            local_f, local_m = self.sections(mb, tau, s_all)
            if mb.component == "column":
                p, f = mb.point_m(mb.station_s_m[0]), mb.rotation @ local_f[1]
                bed += np.concatenate([f, mb.rotation @ local_m[1] + cross(p, f)])
            bending = np.hypot(local_m[:, 0], local_m[:, 1])
            k = int(np.argmax(bending))
            if mb.length_m > 0:
                euler = math.pi**2 * e * min(mb.section.second_moments_m4) / (4 * mb.length_m**2)
                ratio = max(ratio, float(np.max(-local_f[:, 2])) / euler)
            name = "x_beam" if mb.component == "x_beam" else mb.name
            dist = float(s_all[k]) if mb.name != "x_beam_right" else self.gantry.frame.span_m - float(s_all[k])
            cand = MemberMoment(member=name, bending_moment_nm=float(bending[k]), at_m=mb.point_m(s_all[k]),
                                distance_from_root_m=dist,
                                section=SectionWrench(N=float(local_f[k, 2]), V_x=float(local_f[k, 0]),
                                                      V_y=float(local_f[k, 1]), M_x=float(local_m[k, 0]),
                                                      M_y=float(local_m[k, 1]), T=float(local_m[k, 2])))
            if name not in best or cand.bending_moment_nm > best[name].bending_moment_nm:
                best[name] = cand
        return best, max(ratio, 0.0), bed

    def _residuals(self, w: np.ndarray, u: np.ndarray, tau: np.ndarray, dq: np.ndarray,
                   bed: np.ndarray) -> GantryResiduals:
        l_ref = self.length_scale_m
        f_ref = max(float(np.linalg.norm(w[:3])), float(np.linalg.norm(w[3:])) / l_ref, 1.0)
        e = self.closure_jacobian @ dq
        tool_o = np.concatenate([w[:3], w[3:] + cross(self.pose_m, w[:3])])  # the tool wrench about the origin
        d = bed - tool_o
        scale = f_ref * (float(np.linalg.norm(u[:3])) + l_ref * float(np.linalg.norm(u[3:]))) + 1e-300
        return GantryResiduals(closure_m=float(np.linalg.norm(e[:3])), closure_rad=float(np.linalg.norm(e[3:])),
                               bed_force=float(np.linalg.norm(d[:3])) / f_ref,
                               bed_moment=float(np.linalg.norm(d[3:])) / (f_ref * l_ref),
                               work=abs(float(w @ u) - float(tau @ dq)) / scale, force_scale_n=f_ref,
                               length_scale_m=l_ref)


class _Builder:
    """Adds joints with their compliance, keeping each body's world placement at q = 0."""

    def __init__(self, gantry: Gantry, n: int, transverse: str, rigid: frozenset[str]) -> None:
        self.gantry, self.n, self.transverse, self.rigid = gantry, n, transverse, rigid
        self.model = pin.Model()
        self.model.name = gantry.name
        self.model.gravity = pin.Motion.Zero()  # the press load alone (module doc)
        self.world = [pin.SE3.Identity()]
        self.compliance: list[float] = []
        self.names: list[str] = []
        self.members: list[Member] = []

    def joint(self, parent: int, kind: str, placement: pin.SE3, name: str, compliance: float) -> int:
        j = self.model.addJoint(parent, _JOINT_MODELS[kind](), self.world[parent].actInv(placement), name)
        self.world.append(placement)
        self.compliance.append(compliance)
        self.names.append(name)
        return j

    def frame(self, joint: int, point: np.ndarray, name: str) -> int:
        placement = self.world[joint].actInv(pin.SE3(np.eye(3), point))
        return self.model.addFrame(pin.Frame(name, joint, placement, pin.FrameType.OP_FRAME))

    def station_compliance(self, component: str, h: float) -> list[float]:
        """Compliances of one station's six joints (STATION_JOINTS order) for a sub-segment of length h (module
        doc): transverse x, y, axial (m/N), bending x, y, torsion (rad/(N m))."""
        if component in self.rigid:
            return [0.0] * 6
        mat, sec = self.gantry.material, getattr(self.gantry.sections, component)
        e, g = mat.youngs_modulus_pa, mat.shear_modulus_pa
        ix, iy = sec.second_moments_m4
        asx, asy = sec.shear_areas_m2

        def transverse(i_bend: float, a_shear: float) -> float:
            if self.transverse == "none":
                return 0.0
            return h**3 / (12 * e * i_bend) + (h / (g * a_shear) if self.transverse == "timoshenko" else 0.0)

        return [transverse(iy, asx), transverse(ix, asy), h / (e * sec.area_m2), h / (e * ix), h / (e * iy),
                h / (g * sec.torsion_constant_m4)]

    def member(self, parent: int, name: str, component: str, root: np.ndarray, rotation: np.ndarray,
               length: float) -> int:
        n, first = self.n, parent
        h = length / n
        comp = self.station_compliance(component, h)
        ids, vs = [], []
        for k in range(n):
            placement = pin.SE3(rotation, root + rotation[:, 2] * (k + 0.5) * h)
            for kind, c in zip(STATION_JOINTS, comp):
                parent = self.joint(parent, kind, placement, f"{name}[{k}].{kind.lower()}", c)
            ids.append(parent)
            vs.append(np.arange(self.model.joints[parent].idx_v - 5, self.model.joints[parent].idx_v + 1))
        self.members.append(Member(name=name, component=component, section=getattr(self.gantry.sections, component),
                                   root_m=np.asarray(root, dtype=float), rotation=rotation, length_m=float(length),
                                   station_v=np.array(vs), station_joints=np.array(ids), parent_joint=first))
        return parent

    def axis(self, parent: int, axis: str, point: np.ndarray) -> tuple[int, np.ndarray]:
        ax = getattr(self.gantry.axes, axis)
        k_n, k_t, k_r = ax.guide.normal_stiffness_n_per_m, ax.guide.tilt_stiffness_nm_per_rad, \
            ax.guide.roll_stiffness_nm_per_rad
        stiff = [self.gantry.drive_stiffness_n_per_m(axis), k_n, k_n, k_t, k_t, k_r]
        rigid = f"{axis}_axis" in self.rigid
        placement = pin.SE3(np.eye(3), point)
        for kind, k, role in zip(AXIS_JOINTS[axis], stiff, ("drive", "guide_n1", "guide_n2", "guide_tilt1",
                                                              "guide_tilt2", "guide_roll")):
            parent = self.joint(parent, kind, placement, f"{axis}_axis.{role}", 0.0 if rigid else 1.0 / k)
        v = self.model.joints[parent].idx_v
        return parent, np.arange(v - 5, v + 1)


def build_gantry_model(gantry: Gantry, pose_m: np.ndarray, *, springs_per_segment: int | None = None,
                       rigid: tuple[str, ...] | frozenset[str] = (), transverse: str = "timoshenko") -> GantryModel:
    """The VJM model of ``gantry`` with the tool at ``pose_m`` (x, y, z) (m; inside the gantry's workspace, else
    UnreachablePoseError). ``springs_per_segment`` defaults to ``gantry.model.springs_per_segment``;
    ``rigid`` names COMPONENTS to make rigid (a closed-form check isolates one of them); ``transverse`` one of
    TRANSVERSE_LAWS (module doc)."""
    x, y, z = gantry.require_in_workspace(pose_m)
    rigid = frozenset(rigid)
    if not rigid <= set(COMPONENTS):
        raise PressfitError(f"rigid: unknown component(s) {sorted(rigid - set(COMPONENTS))}; known: {COMPONENTS}")
    if transverse not in TRANSVERSE_LAWS:
        raise PressfitError(f"transverse must be one of {TRANSVERSE_LAWS}, got {transverse!r}")
    n = int(springs_per_segment or gantry.model.springs_per_segment)
    if n < 1:
        raise PressfitError(f"springs_per_segment must be at least 1, got {n}")
    f = gantry.frame
    s2, top = f.span_m / 2, f.column_height_m
    b = _Builder(gantry, n, transverse, rigid)
    column = _frame(_X, _UP)
    # depth first (Pinocchio's algorithms need each subtree's velocities contiguous): branch A and the
    # carriage chain it carries, then branch B
    a_end = b.member(0, "column_left", "column", np.array([-s2, 0.0, 0.0]), column, top)
    a_end = b.member(a_end, "x_beam_left", "x_beam", np.array([-s2, top, 0.0]), _frame(_UP, _X), x + s2)
    carriage = np.array([x, top, 0.0])
    axis_v, axis_joints = {}, {}
    j, axis_v["x"] = b.axis(a_end, "x", carriage)
    axis_joints["x"] = j
    y_z = top - f.x_to_z_beam_drop_m
    j = b.member(j, "z_beam", "z_beam", np.array([x, y_z, 0.0]), _frame(_UP, _Z if z >= 0 else -_Z), abs(z))
    j, axis_v["z"] = b.axis(j, "z", np.array([x, y_z, z]))
    axis_joints["z"] = j
    guide = np.array([x, gantry.ram_guide_height_m, z])
    j, axis_v["y"] = b.axis(j, "y", guide)
    axis_joints["y"] = j
    j = b.member(j, "ram", "ram", guide, _frame(_X, -_UP), gantry.ram_guide_height_m - y)
    tool = b.frame(j, np.array([x, y, z]), "tool")
    b_end = b.member(0, "column_right", "column", np.array([s2, 0.0, 0.0]), column, top)
    b_end = b.member(b_end, "x_beam_right", "x_beam", np.array([s2, top, 0.0]), _frame(_UP, -_X), s2 - x)
    closure = (b.frame(a_end, carriage, "x_carriage.a"), b.frame(b_end, carriage, "x_carriage.b"))
    model = b.model
    with data_pool.borrowed(model) as data:
        pin.computeJointJacobians(model, data, pin.neutral(model))
        pin.updateFramePlacements(model, data)
        jac = [np.array(pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)) for fid in (tool, *closure)]
    return GantryModel(gantry=gantry, pose_m=np.array([x, y, z]), model=model, springs_per_segment=n,
                       transverse=transverse, compliance=np.array(b.compliance),
                       coordinate_names=tuple(b.names), members=tuple(b.members), axis_v=axis_v,
                       axis_joints=axis_joints, tool_frame=tool, tool_jacobian=jac[0], closure_jacobian=jac[1] - jac[2])


def gantry_equilibrium(gantry: Gantry, pose_m: np.ndarray, tool_wrench: np.ndarray, **model_options: Any
                       ) -> GantryEquilibrium:
    """Build the model at ``pose_m`` (m) and solve it under ``tool_wrench`` (6,) (N, N m), :meth:`GantryModel.solve`."""
    return build_gantry_model(gantry, pose_m, **model_options).solve(tool_wrench)
