r"""Pinocchio model of the n-UPU machine with elastic virtual joints (VJM: Pashkevich, Klimchik, Chablat).

Topology (why: every leg is built identically, so the machine's two mirror planes hold exactly in the
model, and the elastic problem splits into n independent leg chains coupled only through the plate):

* joint 1: the plate, a free flyer (``JointModelFreeFlyer``) at the plate centre, world-aligned when
  unrotated: ``q[0:3]`` = h (m), ``q[3:7]`` = quaternion (x, y, z, w);
* per leg i, a chain from the universe: base cardan (revolute about +-a_i, then about b_i), the cylinder
  split into n sub-segments with a 3-DOF rotational spring at each sub-segment midpoint (revolutes about
  the leg frame x, y, z), the actuated prismatic joint along the leg (spring = actuator stiffness in
  series with the axial compliance of cylinder and stem), the stem split likewise, the plate cardan
  (revolute about b_i, then about a_i: Tsai's condition), closed on the plate by a 6D
  ``pin.FrameAnchorConstraintModel`` between the last plate-cardan body and the plate.

Leg reference frame R0_i (columns X, Y, Z): Z = w_i (horizontal, inward), Y = -y (down), X = Y x Z = w_i x y
(= +-a_i). The rigid joint values at a pose with cardan angles (alpha_i, beta_i) and length l_i
(paper equation 1, :func:`pressfit.kinematics.inverse_kinematics`) are

    base cardan (alpha_i, sigma_i beta_i), prismatic l_i, plate cardan (-sigma_i beta_i, -alpha_i),

with sigma_i = X . s_i = +-1 (s_i the beta axis of equation 1); every spring coordinate is 0.
The prismatic coordinate is the leg length between the cardan centres in the rigid configuration (m).

Cylinder springs sit at (k + 1/2) L_c / n from the base cardan (bending n E I / L_c, torsion n G J / L_c,
N m/rad); stem springs at (k + 1/2) L_s / n from the cylinder end with L_s = l_i - L_c at the model's
pose (bending n E I_s / L_s, torsion n G J_s / L_s). Lumped springs carry the constant couples of a
rigid-cardan leg exactly; in the nonlinear state small shears appear and the error falls as 1/n^2.

Optional cardan compliance (clearance/stiffness hook, rigid by default): a :class:`CardanCompliance`
adds virtual joints for a cardan's constrained directions, three translations (in the leg reference
frame R0_i, at the cardan centre) and the rotation about c_i = a_i x b_i (between the cardan's two
revolutes), each with a spring law (:class:`LinearSpring`, or any object with ``energy``, ``force``,
``tangent`` of the joint coordinate). ``axial`` adds one translation along the leg (+z of the leg
segment frame, positive = the leg lengthens) between the cardan and its leg segment: the axial play that
:mod:`pressfit.mechanics.clearance` models. ``machine.joints.cardan_rotational_stiffness_nm_per_rad`` (if set)
puts a linear spring on the cardans' free revolutes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import pinocchio as pin

from pressfit import kinematics
from pressfit.description.machine import Machine
from pressfit.errors import ConvergenceError
from pressfit.mechanics import data_pool
from pressfit.spatial import cross

UP = np.array([0.0, 1.0, 0.0])
CARDAN_ENDS = ("base", "plate")


class SpringLaw(Protocol):
    """A one-dimensional elastic law of the joint coordinate offset x = q - rest (SI)."""

    def energy(self, x: float) -> float: ...

    def force(self, x: float) -> float: ...  # dE/dx (N or N m)

    def tangent(self, x: float) -> float: ...  # d2E/dx2 (N/m or N m/rad)


@dataclass(frozen=True)
class LinearSpring:
    """E = k x^2 / 2 with k in N/m (translations) or N m/rad (rotations)."""

    k: float

    def energy(self, x: float) -> float:
        return 0.5 * self.k * x * x

    def force(self, x: float) -> float:
        return self.k * x

    def tangent(self, x: float) -> float:
        return self.k


@dataclass(frozen=True, kw_only=True)
class CardanCompliance:
    """Virtual joints for one cardan's constrained directions; ``None`` keeps that direction rigid.

    ``translation`` applies to each of the 3 translations (m), ``rotation`` to the rotation about
    c_i = a_i x b_i (rad), ``axial`` to the translation along the leg between the cardan and the leg
    (base: after the cardan's second revolute; plate: before its first), m, positive = leg lengthens.
    """

    translation: SpringLaw | None = None
    rotation: SpringLaw | None = None
    axial: SpringLaw | None = None


@dataclass(kw_only=True)
class Spring:
    """An elastic virtual joint: energy law(q[idx_q] - rest)."""

    name: str  # e.g. "cylinder[2].x", "actuator", "base_cardan.tx"
    leg: int  # 0..n-1
    idx_q: int
    idx_v: int
    law: SpringLaw
    rest: float = 0.0


CardanComplianceSpec = CardanCompliance | dict[tuple[int, str], CardanCompliance | None] | None


@dataclass(frozen=True, kw_only=True)
class ModelPose:
    """The pose-dependent values of a :class:`MachineModel` at one reachable pose: a fresh value per pose
    (the model itself never changes after it is built).

    The stem springs sit at (k + 1/2) L_s / n from the cylinder end, so the stem joint placements depend
    on the stem length L_s = l_i - L_c (:meth:`MachineModel.place_stem` writes them into a Pinocchio
    model); the stem spring and actuator stiffnesses depend on it too."""

    pose_m: np.ndarray  # (3,) plate-centre pose h, m
    q0: np.ndarray  # (nq,) rigid reference (springs 0): closed form (equation 1), least-squares assembly if tilted
    stem_lengths_m: np.ndarray  # (n,) L_s per leg, m
    spring_k: np.ndarray  # per spring: linear stiffness (N/m or N m/rad), NaN for a nonlinear law
    spring_rest: np.ndarray  # per spring: rest value of its coordinate (m or rad)


@dataclass(kw_only=True)
class MachineModel:
    """The Pinocchio model of a machine, with its springs and loop closures, built at a reference pose.

    Body frames in the rigid configuration (all spring coordinates 0), per ``leg_joint_ids[i]``:

    * ``'base_cardan'``: the base cardan's spider (first revolute), origin B_i;
    * ``'cylinder'``: the body after the base cardan, origin B_i, +z along the leg toward the plate,
      x = +-(a_i made normal to the leg); the cylinder occupies z in [0, L_c];
    * ``'actuator'`` and ``'stem'``: the body after the prismatic joint, origin at the plate cardan
      centre h + d_i, axes as ``'cylinder'``; the stem occupies z in [-(l_i - L_c), 0];
    * ``'plate_cardan'``: the plate cardan's spider (first revolute), origin h + d_i;
    * ``'plate_end'``: the body after the plate cardan (anchored to the plate), origin h + d_i, axes R0_i.

    ``leg_v[i]`` lists leg i's velocity indices in chain order; the plate owns v[0:6]. ``sections[i]``
    gives, for 'base' (base cardan centre), 'actuator' (cylinder end, L_c from the base cardan) and
    'plate' (plate cardan centre), the joint carrying the section point and its z offset (m); the same
    points are Pinocchio frames named ``leg<i>.section.<name>`` (legs numbered from 1).

    ``pose_m``, ``q0``, ``spring_k``, ``spring_rest`` and the springs' laws are the values at the pose the
    model was built at (:class:`ModelPose`); nothing changes them afterwards. Other poses: take
    :meth:`pose_values` and :meth:`place_stem` on a copy of ``model`` (what the equilibrium solver does).
    :meth:`closure_error` and :meth:`assemble` create a Pinocchio Data per call: pin 4.1's Data holds
    second-order derivative tensors of nv^3 entries (123 MB at 4 springs per segment, ~4.5 GB at 16), so
    the model keeps none (the fast solver, :mod:`pressfit.mechanics.fast_statics`, needs none at all).
    """

    machine: Machine
    model: pin.Model
    constraint_models: list[pin.ConstraintModel]
    springs_per_segment: int
    pose_m: np.ndarray
    q0: np.ndarray
    plate_joint_id: int
    leg_joint_ids: list[dict[str, int]]
    leg_v: list[np.ndarray]
    springs: list[Spring]
    anchor_placements: list[pin.SE3]  # constraint frame on the plate (plate frame), per leg
    sigma: np.ndarray  # (n,) sign of the b-revolute against beta
    leg_frames0: np.ndarray  # (n, 3, 3) R0_i
    sections: list[dict[str, tuple[int, float]]]  # per leg: section -> (joint id, z offset in its frame, m)
    cardan_compliance: CardanComplianceSpec
    spring_k: np.ndarray  # per spring: linear k (N/m or N m/rad) at pose_m, NaN if nonlinear
    spring_rest: np.ndarray  # per spring: rest value at pose_m (m or rad)
    _rigid_idx: dict[str, np.ndarray] = field(repr=False)  # q indices of the rigid joints, by kind
    _stem_first: list[int] = field(repr=False)  # per leg: first stem joint
    _variable_springs: tuple[np.ndarray, ...] = field(repr=False)  # (spring index, kind 0 act/1 bend/2 tors, leg)

    # --- configurations ----------------------------------------------------------------------------
    def configuration_at(self, pose_m: np.ndarray) -> np.ndarray:
        """Rigid closed-form q (nq,) at a reachable pose (m): springs 0, joints from equation 1."""
        h = kinematics.require_reachable(self.machine, pose_m)
        return self._configuration(h, kinematics.inverse_kinematics(self.machine, h))

    def _configuration(self, h: np.ndarray, ik: kinematics.LegKinematics) -> np.ndarray:
        """q (..., nq) for poses h (..., 3) and their inverse kinematics (batched)."""
        q = np.zeros(h.shape[:-1] + (self.model.nq,))
        q[..., 0:3] = h
        q[..., 6] = 1.0
        r = self._rigid_idx
        q[..., r["base_a"]] = ik.alpha_rad
        q[..., r["base_b"]] = self.sigma * ik.beta_rad
        q[..., r["prismatic"]] = ik.lengths_m
        q[..., r["plate_b"]] = -self.sigma * ik.beta_rad
        q[..., r["plate_a"]] = -ik.alpha_rad
        return q

    def configurations(self, poses_m: np.ndarray, *, base_points_m: np.ndarray | None = None,
                       plate_offsets_m: np.ndarray | None = None) -> np.ndarray:
        """Rigid closed-form q (..., nq) at reachable poses (..., 3) (m), batched; raises
        :class:`UnreachablePoseError` naming the first pose outside the joint limits. ``base_points_m``,
        ``plate_offsets_m`` ((..., n, 3), m, per pose): joint positions other than the machine's (other joint
        position errors: :func:`pressfit.kinematics.leg_vectors`); the chain closes for any of them."""
        h = np.asarray(poses_m, dtype=float)
        ik = kinematics.inverse_kinematics(self.machine, h, base_points_m=base_points_m,
                                           plate_offsets_m=plate_offsets_m)
        bad = ~kinematics.is_reachable(self.machine, h, ik)
        if np.any(bad):
            first = tuple(np.argwhere(bad)[0])
            kinematics.require_reachable(self.machine, h[first], ik.at(first))
        return self._configuration(h, ik)

    def constraint_datas(self) -> list[pin.ConstraintData]:
        return [cm.createData() for cm in self.constraint_models]

    def closure_error(self, q: np.ndarray, data: pin.Data | None = None) -> tuple[float, float]:
        """Largest loop-closure error over the legs (m, rad), from Pinocchio's constraint placements."""
        if data is None:
            with data_pool.borrowed(self.model) as lent:
                return self.closure_error(q, lent)
        pin.forwardKinematics(self.model, data, q)
        em, er = 0.0, 0.0
        for cm, cd in zip(self.constraint_models, self.constraint_datas()):
            cm.calc(self.model, data, cd)
            d = cd.extract()
            err = d.oMc1.actInv(d.oMc2)  # c1 -> c2; identity when closed
            em = max(em, float(np.linalg.norm(err.translation)))
            er = max(er, float(np.linalg.norm(pin.log3(err.rotation))))
        return em, er

    def assemble(self, pose_m: np.ndarray, q_init: np.ndarray | None = None, tol: float = 1e-12,
                 max_iter: int = 50, least_squares: bool = False) -> np.ndarray:
        """Close the loops numerically at a pose (m): Gauss-Newton on Pinocchio's constraint Jacobian
        over the cardan, prismatic and plate-rotation coordinates, springs held at 0.

        Starts from ``q_init`` (default: the rigid closed form, which is already closed); returns q.
        ``least_squares``: stop at the configuration that minimises the closure error (the Gauss-Newton step
        below ``tol``) instead of requiring it to vanish: with misaligned cardans the rigid redundant machine
        generally cannot close (each of the n > 3 legs fixes one plate rotation; there are three), and what is left
        is closed elastically by the equilibrium solve (a self-stress).
        """
        h = kinematics.require_reachable(self.machine, pose_m)
        q = self.configuration_at(h) if q_init is None else np.array(q_init, dtype=float)
        q[0:3] = h
        r = self._rigid_idx
        free = np.concatenate([[3, 4, 5]] + [r[k] - 1 for k in _RIGID])
        with data_pool.borrowed(self.model) as data:
            return self._assembled(q, free, tol, max_iter, least_squares, data)

    def _assembled(self, q: np.ndarray, free: np.ndarray, tol: float, max_iter: int, least_squares: bool,
                   data: pin.Data) -> np.ndarray:
        """:meth:`assemble`'s Gauss-Newton from q over the coordinates ``free``, in ``data``."""
        cds = self.constraint_datas()
        for _ in range(max_iter):
            pin.computeJointJacobians(self.model, data, q)
            err = []
            for cm, cd in zip(self.constraint_models, cds):
                cm.calc(self.model, data, cd)
                d = cd.extract()
                err.append(np.array(d.constraint_position_error))  # log6(c1^-1 c2) in c1's frame
            e = np.concatenate(err)
            if np.max(np.abs(e)) < tol:
                return q
            jac = pin.getConstraintsJacobian(self.model, data, self.constraint_models, cds)[:, free]
            dv = np.zeros(self.model.nv)
            dv[free] = -np.linalg.lstsq(jac, e, rcond=None)[0]  # jac = d log6(c1^-1 c2) / dv at closure
            q = pin.integrate(self.model, q, dv)
            if least_squares and np.max(np.abs(dv)) < tol:
                return q
        raise ConvergenceError("loop-closure assembly", float(np.max(np.abs(e))), tol, max_iter)

    # --- pose-dependent values -------------------------------------------------------------------
    def pose_values(self, pose_m: np.ndarray) -> ModelPose:
        """The model's pose-dependent values at a reachable pose (m), computed afresh: stem lengths,
        actuator stiffness (actuator in series with the leg's axial compliance, N/m), stem bending
        n E I_s / L_s and torsion n G J_s / L_s (N m/rad), rest values and q0. Raises
        :class:`UnreachablePoseError` outside the joint limits.

        q0 is the rigid closed form (equation 1); with misaligned cardans (``machine.has_cardan_tilts``)
        it is the least-squares rigid assembly started from it (:meth:`assemble`, springs at 0, the plate
        free to rotate), which the elastic solve then closes. The rest values are the closed form's
        (springs relaxed, actuators at the commanded lengths l_i) either way."""
        m = self.machine
        h = np.asarray(pose_m, dtype=float).reshape(3)
        ik = kinematics.inverse_kinematics(m, h)
        h = kinematics.require_reachable(m, h, ik)
        q0 = self._configuration(h, ik)
        k = self.spring_stiffness(ik.lengths_m)
        rest = q0[[s.idx_q for s in self.springs]]
        if m.has_cardan_tilts:
            q0 = self.assemble(h, q0, tol=1e-13, least_squares=True)
        return ModelPose(pose_m=h, q0=q0, stem_lengths_m=ik.lengths_m - m.cylinder.length_m, spring_k=k,
                         spring_rest=rest)

    def place_stem(self, model: pin.Model, stem_lengths_m: np.ndarray,
                   translations: list[np.ndarray] | None = None) -> None:
        """Write the stem joint placements for stem lengths (n,) (m) into ``model``: this model's
        Pinocchio model or a copy of it (every pose-dependent placement is written), through ``translations``
        (:meth:`stem_translations` of that model, held by a caller that re-places often) or found here."""
        views = self.stem_translations(model) if translations is None else translations
        for view, z in zip(views, self.stem_placements_z(stem_lengths_m).ravel().tolist(), strict=True):
            view[2] = z

    def stem_translations(self, model: pin.Model) -> list[np.ndarray]:
        """Numpy views of the translations of ``model``'s :meth:`stem_joint_ids` placements, legs then joints (what
        :meth:`place_stem` writes; valid while the model lives)."""
        jp = model.jointPlacements
        return [jp[j].translation for ids in self.stem_joint_ids() for j in ids]

    def spring_stiffness(self, lengths_m: np.ndarray) -> np.ndarray:
        """Linear spring stiffnesses (..., n_springs) for leg lengths (..., n) (m), batched: the actuator
        in series with the leg's axial compliance (N/m), stem bending n E I_s / L_s and torsion
        n G J_s / L_s (N m/rad) with L_s = l - L_c, the other springs as built; NaN for a nonlinear law."""
        m, n, sec = self.machine, self.springs_per_segment, self.machine.stem_section
        lengths_m = np.asarray(lengths_m, dtype=float)
        ls = lengths_m - m.cylinder.length_m
        per_kind = np.empty(ls.shape[:-1] + (3, ls.shape[-1]))  # (..., 3, legs): actuator, stem bending, torsion
        per_kind[..., 0, :] = 1.0 / m.axial_compliance_m_per_n(lengths_m)
        per_kind[..., 1, :] = n * (m.material.youngs_modulus_pa * sec.second_moment_m4) / ls
        per_kind[..., 2, :] = n * (m.material.shear_modulus_pa * sec.polar_moment_m4) / ls
        var, kind, leg = self._variable_springs
        k = np.empty(lengths_m.shape[:-1] + self.spring_k.shape)
        k[...] = self.spring_k  # broadcast (np.broadcast_to's copy costs 4 us more a call)
        k[..., var] = per_kind[..., kind, leg]
        return k

    def stem_joint_ids(self) -> list[list[int]]:
        """Per leg, the n + 1 joints whose placements depend on the stem length: the stem springs' first
        revolutes and the joint after the stem (the plate cardan or its virtual axial joint)."""
        n = self.springs_per_segment
        return [[j0 + 3 * k for k in range(n + 1)] for j0 in self._stem_first]

    def stem_placements_z(self, stem_lengths_m: np.ndarray) -> np.ndarray:
        """z translations (..., legs, n + 1) (m) of the :meth:`stem_joint_ids` placements for stem lengths
        (..., legs): the stem springs at (k + 1/2) L_s / n from the cylinder end (module doc)."""
        n = self.springs_per_segment
        ls = np.asarray(stem_lengths_m, dtype=float)[..., None]
        z = np.broadcast_to(ls / n, ls.shape[:-1] + (n + 1,)).copy()
        z[..., :1] = -ls + ls / (2 * n)
        z[..., n:] = ls / (2 * n)
        return z


def _tz(z: float) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([0.0, 0.0, z]))


def _leg_frame0(machine: Machine, i: int) -> np.ndarray:
    w = machine.inward_directions[i]
    y = -UP
    return np.column_stack([cross(y, w), y, w])


_JOINT_MODELS = {"RX": pin.JointModelRX, "RY": pin.JointModelRY, "RZ": pin.JointModelRZ,
                 "PX": pin.JointModelPX, "PY": pin.JointModelPY, "PZ": pin.JointModelPZ}
_RIGID = ("base_a", "base_b", "prismatic", "plate_b", "plate_a")


class _ChainBuilder:
    """Adds the n leg chains to a Pinocchio model with the plate's free flyer (module doc): one joint
    at a time after ``parent``, placed by ``pending``; records springs, rigid joints and sections."""

    def __init__(self, machine: Machine, n: int, cardan_compliance: CardanComplianceSpec) -> None:
        self.machine, self.n, self.cc = machine, n, cardan_compliance
        self.model = pin.Model()
        self.model.name = machine.name
        self.model.gravity = pin.Motion.Zero()  # massless bodies: loads enter as wrenches only
        self.plate = self.model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "plate")
        self.springs: list[Spring] = []
        self.rigid: dict[str, list[int]] = {k: [] for k in _RIGID}
        self.ids: list[dict[str, int]] = []
        self.stem_first: list[int] = []
        self.sections: list[dict[str, tuple[int, float]]] = []
        self.leg, self.parent, self.pending = 0, 0, pin.SE3.Identity()
        k_card = machine.joints.cardan_rotational_stiffness_nm_per_rad
        self.card = LinearSpring(k_card) if k_card else None

    def compliance(self, end: str, leg: int | None = None) -> CardanCompliance | None:
        leg = self.leg if leg is None else leg
        return self.cc.get((leg, end)) if isinstance(self.cc, dict) else self.cc

    def add(self, kind: str, name: str, law: SpringLaw | None = None) -> int:
        j = self.model.addJoint(self.parent, _JOINT_MODELS[kind](), self.pending, f"leg{self.leg + 1}.{name}")
        self.parent, self.pending = j, pin.SE3.Identity()
        if law is not None:
            jm = self.model.joints[j]
            self.springs.append(Spring(name=name, leg=self.leg, idx_q=jm.idx_q, idx_v=jm.idx_v, law=law))
        return j

    def virtual(self, end: str, which: str) -> None:
        """The cardan's virtual joints of one kind ('translation', 'rotation', 'axial'), if compliant."""
        law = getattr(self.compliance(end) or CardanCompliance(), which)
        if law is None:
            return
        if which == "translation":
            for ax in "XYZ":
                self.add("P" + ax, f"{end}_cardan.t{ax.lower()}", law)
        else:
            self.add("RZ" if which == "rotation" else "PZ", f"{end}_cardan.{'rc' if which == 'rotation' else 'axial'}",
                     law)

    def add_leg(self, i: int) -> None:
        m = self.machine
        self.leg, self.parent = i, 0
        self.pending = pin.SE3(_leg_frame0(m, i) @ pin.exp3(m.cardan_tilts_rad[i, 0]), m.base_points_m[i].copy())
        jid: dict[str, int] = {}
        self.virtual("base", "translation")
        jid["base_cardan"] = self.add("RX", "base_cardan.a", self.card)
        self.virtual("base", "rotation")
        jid["cylinder"] = self.add("RY", "base_cardan.b", self.card)
        self.virtual("base", "axial")
        sec = {"base": (jid["cylinder"], 0.0), "actuator": self.cylinder()}
        jid["actuator"] = jid["stem"] = self.add("PZ", "actuator", LinearSpring(1.0))  # k set per pose
        self.stem()
        self.virtual("plate", "axial")  # placed per pose like the plate cardan (first joint after the stem)
        jid["plate_cardan"] = self.add("RY", "plate_cardan.b", self.card)
        self.virtual("plate", "rotation")
        sec["plate"] = (self.add("RX", "plate_cardan.a", self.card), 0.0)
        for name, (pj, z) in sec.items():
            self.model.addFrame(pin.Frame(f"leg{i + 1}.section.{name}", pj, _tz(z), pin.FrameType.OP_FRAME))
        self.virtual("plate", "translation")
        jid["plate_end"] = self.parent
        for kind, key in zip(_RIGID, ("base_cardan", "cylinder", "actuator", "plate_cardan")):
            self.rigid[kind].append(jid[key])
        self.rigid["plate_a"].append(sec["plate"][0])
        self.ids.append(jid)
        self.sections.append(sec)

    def cylinder(self) -> tuple[int, float]:
        """The cylinder's n springs (bending n E I / L_c, torsion n G J / L_c); returns the actuator section
        (joint, z offset); leaves ``pending`` at the prismatic frame (the virtual base point: q = l_i)."""
        m, n = self.machine, self.n
        lc, cyl = m.cylinder.length_m, m.cylinder_section
        bend, tors = n * m.material.youngs_modulus_pa * cyl.second_moment_m4 / lc, n * m.material.shear_modulus_pa * \
            cyl.polar_moment_m4 / lc
        for k in range(n):
            self.pending = _tz(lc / (2 * n) if k == 0 else lc / n)
            for ax, kk in zip("XYZ", (bend, bend, tors)):
                self.add("R" + ax, f"cylinder[{k}].{ax.lower()}", LinearSpring(kk))
        self.pending = _tz(-(lc - lc / (2 * n)))
        return self.parent, lc / (2 * n)

    def stem(self) -> None:
        """The stem's n springs (stiffness and placement set per pose: :meth:`MachineModel.place_stem`)."""
        for k in range(self.n):
            j = self.add("RX", f"stem[{k}].x", LinearSpring(1.0))
            if k == 0:
                self.stem_first.append(j)
            self.add("RY", f"stem[{k}].y", LinearSpring(1.0))
            self.add("RZ", f"stem[{k}].z", LinearSpring(1.0))

    def leg_velocities(self, i: int) -> np.ndarray:
        """Leg i's velocity indices in chain order (its first virtual translation to its plate end)."""
        c = self.compliance("base", i)
        virtual = 3 if c is not None and c.translation is not None else 0
        first = self.model.joints[self.ids[i]["base_cardan"]].idx_v - virtual
        return np.arange(first, self.model.joints[self.ids[i]["plate_end"]].idx_v + 1)


def build_model(machine: Machine, pose_m: np.ndarray, *, springs_per_segment: int | None = None,
                cardan_compliance: CardanComplianceSpec = None) -> MachineModel:
    """Build the VJM Pinocchio model of ``machine`` at the reachable pose ``pose_m`` (m).

    ``springs_per_segment`` defaults to ``machine.model.springs_per_segment``. ``cardan_compliance`` is
    ``None`` (rigid cardans), one :class:`CardanCompliance` for all 2 n cardans, or a dict keyed by
    ``(leg 0..n-1, 'base' | 'plate')``. Raises :class:`UnreachablePoseError` for a pose outside the limits.
    """
    h = kinematics.require_reachable(machine, pose_m)
    b = _ChainBuilder(machine, int(springs_per_segment or machine.model.springs_per_segment), cardan_compliance)
    legs = range(len(machine.legs))
    for i in legs:
        b.add_leg(i)
    model, springs = b.model, b.springs
    frames0 = np.array([_leg_frame0(machine, i) for i in legs])
    anchors = [pin.SE3(frames0[i] @ pin.exp3(machine.cardan_tilts_rad[i, 1]), machine.plate_offsets_m[i].copy())
               for i in legs]
    constraints = [pin.ConstraintModel(pin.FrameAnchorConstraintModel(model, b.ids[i]["plate_end"], pin.SE3.Identity(),
                                                                      b.plate, anchors[i])) for i in legs]
    var = [(k, 0 if sp.name == "actuator" else 2 if sp.name.endswith(".z") else 1, sp.leg)
           for k, sp in enumerate(springs) if sp.name == "actuator" or sp.name.startswith("stem[")]
    mm = MachineModel(machine=machine, model=model, constraint_models=constraints, springs_per_segment=b.n, pose_m=h,
                      q0=np.zeros(model.nq), plate_joint_id=b.plate, leg_joint_ids=b.ids,
                      leg_v=[b.leg_velocities(i) for i in legs], springs=springs, anchor_placements=anchors,
                      sigma=np.array([float(np.sign(frames0[i][:, 0] @ machine.beta_axes[i])) for i in legs]),
                      leg_frames0=frames0, sections=b.sections, cardan_compliance=cardan_compliance,
                      spring_k=np.array([sp.law.k if type(sp.law) is LinearSpring else np.nan for sp in springs]),
                      spring_rest=np.zeros(len(springs)),
                      _rigid_idx={k: np.array([model.joints[j].idx_q for j in v]) for k, v in b.rigid.items()},
                      _stem_first=b.stem_first, _variable_springs=tuple(np.array(c, dtype=int) for c in zip(*var)))
    at = mm.pose_values(h)
    mm.place_stem(model, at.stem_lengths_m)
    variable = set(mm._variable_springs[0].tolist())
    for k, sp in enumerate(springs):  # the laws and rest values at the build pose
        if k in variable:
            sp.law = LinearSpring(float(at.spring_k[k]))
        sp.rest = float(at.spring_rest[k])
    mm.q0, mm.spring_k, mm.spring_rest = at.q0, at.spring_k, at.spring_rest
    return mm
