r"""Pinocchio model of the 4-UPU machine with elastic virtual joints (VJM: Pashkevich, Klimchik, Chablat).

Topology (why: every leg is built identically, so the machine's two mirror planes hold exactly in the
model, and the elastic problem splits into four independent leg chains coupled only through the plate):

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
:mod:`pressfit.clearance` models. ``machine.joints.cardan_rotational_stiffness_nm_per_rad`` (if set)
puts a linear spring on the cardans' free revolutes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import pinocchio as pin

from pressfit import kinematics
from pressfit.description.machine import Machine

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


@dataclass(frozen=True)
class CardanCompliance:
    """Virtual joints for one cardan's constrained directions; ``None`` keeps that direction rigid.

    ``translation`` applies to each of the 3 translations (m), ``rotation`` to the rotation about
    c_i = a_i x b_i (rad), ``axial`` to the translation along the leg between the cardan and the leg
    (base: after the cardan's second revolute; plate: before its first), m, positive = leg lengthens.
    """

    translation: SpringLaw | None = None
    rotation: SpringLaw | None = None
    axial: SpringLaw | None = None


@dataclass
class Spring:
    """An elastic virtual joint: energy law(q[idx_q] - rest)."""

    name: str  # e.g. "cylinder[2].x", "actuator", "base_cardan.tx"
    leg: int  # 0..3
    idx_q: int
    idx_v: int
    law: SpringLaw
    rest: float = 0.0


@dataclass
class MachineModel:
    """The Pinocchio model of a machine at a reference pose, with its springs and loop closures.

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
    """

    machine: Machine
    model: pin.Model
    data: pin.Data
    constraint_models: list
    springs_per_segment: int
    pose_m: np.ndarray
    q0: np.ndarray
    plate_joint_id: int
    leg_joint_ids: list[dict[str, int]]
    leg_v: list[np.ndarray]
    springs: list[Spring]
    anchor_placements: list[pin.SE3]  # constraint frame on the plate (plate frame), per leg
    sigma: np.ndarray  # (4,) sign of the b-revolute against beta
    leg_frames0: np.ndarray  # (4, 3, 3) R0_i
    sections: list[dict[str, tuple[int, float]]]  # per leg: section -> (joint id, z offset in its frame, m)
    _rigid_idx: dict[str, np.ndarray] = field(repr=False, default_factory=dict)
    _stem_first: list[int] = field(repr=False, default_factory=list)
    cardan_compliance: object = None
    spring_k: np.ndarray = field(default_factory=lambda: np.zeros(0))  # per spring: linear k, NaN if nonlinear
    spring_rest: np.ndarray = field(default_factory=lambda: np.zeros(0))  # per spring: rest value
    _spring_q: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0, int))  # idx_q per spring
    _variable_springs: tuple = field(repr=False, default=())  # (spring index, kind 0 act / 1 bend / 2 tors, leg)
    _stem_springs: list = field(repr=False, default_factory=list)  # per leg: [(Spring, is torsion)]
    _actuator_springs: list = field(repr=False, default_factory=list)  # per leg
    _rest_springs: list = field(repr=False, default_factory=list)  # springs on coordinates with q0 != 0
    version: int = 0  # bumped by retarget(); solvers cache per-model data under (id, version)

    # --- configurations ----------------------------------------------------------------------------
    def configuration_at(self, pose_m: np.ndarray) -> np.ndarray:
        """Rigid closed-form q (nq,) at a reachable pose (m): springs 0, joints from equation 1."""
        h = kinematics.require_reachable(self.machine, pose_m)
        return self._configuration(h, kinematics.inverse_kinematics(self.machine, h))

    def _configuration(self, h: np.ndarray, ik: kinematics.LegKinematics) -> np.ndarray:
        q = np.zeros(self.model.nq)
        q[0:3] = h
        q[6] = 1.0
        r = self._rigid_idx
        q[r["base_a"]] = ik.alpha_rad
        q[r["base_b"]] = self.sigma * ik.beta_rad
        q[r["prismatic"]] = ik.lengths_m
        q[r["plate_b"]] = -self.sigma * ik.beta_rad
        q[r["plate_a"]] = -ik.alpha_rad
        return q

    def constraint_datas(self) -> list:
        return [cm.createData() for cm in self.constraint_models]

    def closure_error(self, q: np.ndarray, data: pin.Data | None = None) -> tuple[float, float]:
        """Largest loop-closure error over the legs (m, rad), from Pinocchio's constraint placements."""
        data = data or self.data
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
                 max_iter: int = 50) -> np.ndarray:
        """Close the loops numerically at a pose (m): Gauss-Newton on Pinocchio's constraint Jacobian
        over the cardan, prismatic and plate-rotation coordinates, springs held at 0.

        Starts from ``q_init`` (default: the rigid closed form, which is already closed); returns q.
        """
        from pressfit.errors import ConvergenceError

        h = kinematics.require_reachable(self.machine, pose_m)
        q = self.configuration_at(h) if q_init is None else np.array(q_init, dtype=float)
        q[0:3] = h
        r = self._rigid_idx
        free = np.concatenate([[3, 4, 5]] + [r[k] - 1 for k in ("base_a", "base_b", "prismatic", "plate_b",
                                                                    "plate_a")])
        data, cds = self.data, self.constraint_datas()
        for it in range(max_iter):
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
        raise ConvergenceError("loop-closure assembly", float(np.max(np.abs(e))), tol, max_iter)

    # --- pose-dependent data ---------------------------------------------------------------------
    def retarget(self, pose_m: np.ndarray) -> MachineModel:
        """Move the model's reference pose in place (stem spring positions and stiffnesses, actuator
        stiffness, rest values, q0); returns self. Rigid kinematics is unchanged by this.

        Spring laws are re-read from ``springs`` only at build; afterwards retarget replaces the stem and
        actuator laws (shared :class:`LinearSpring` objects per leg) and keeps ``spring_k`` (N/m or N m/rad,
        NaN for a nonlinear law) and ``spring_rest`` (m or rad), aligned with ``springs``, up to date."""
        m = self.machine
        h = np.asarray(pose_m, dtype=float).reshape(3)
        ik = kinematics.inverse_kinematics(m, h)
        lim = m.limits
        if not (h[1] > 0 and np.all((ik.lengths_m >= lim.leg_length_min_m) & (ik.lengths_m <= lim.leg_length_max_m)
                                    & (ik.alpha_rad >= lim.alpha_min_rad) & (ik.alpha_rad <= lim.alpha_max_rad)
                                    & (ik.beta_rad >= lim.beta_min_rad) & (ik.beta_rad <= lim.beta_max_rad))):
            h = kinematics.require_reachable(m, h)  # raises the named error (fast path above: same limits)
        n, lc = self.springs_per_segment, m.cylinder.length_m
        e, g, sec = m.material.youngs_modulus_pa, m.material.shear_modulus_pa, m.stem_section
        lengths = ik.lengths_m.tolist()
        kax = (1.0 / m.axial_compliance_m_per_n(ik.lengths_m)).tolist()
        q0 = self._configuration(h, ik)
        ls = [length - lc for length in lengths]
        per_kind = [kax, [n * (e * sec.second_moment_m4) / x for x in ls],  # actuator, stem bending, torsion
                    [n * (g * sec.polar_moment_m4) / x for x in ls]]
        jp = self.model.jointPlacements
        for i in range(4):
            j0 = self._stem_first[i]
            jp[j0].translation[2] = -ls[i] + ls[i] / (2 * n)
            for k in range(1, n):
                jp[j0 + 3 * k].translation[2] = ls[i] / n
            jp[j0 + 3 * n].translation[2] = ls[i] / (2 * n)  # plate cardan (or its virtual joints)
            bend, tors = LinearSpring(per_kind[1][i]), LinearSpring(per_kind[2][i])
            for s, torsion in self._stem_springs[i]:
                s.law = tors if torsion else bend
            self._actuator_springs[i].law = LinearSpring(kax[i])
        for s in self._rest_springs:
            s.rest = float(q0[s.idx_q])
        var, kind, leg = self._variable_springs
        self.spring_k[var] = np.array(per_kind)[kind, leg]
        self.spring_rest[:] = q0[self._spring_q]
        self.pose_m, self.q0 = h, q0
        self.version += 1
        return self


def _tz(z: float) -> pin.SE3:
    return pin.SE3(np.eye(3), np.array([0.0, 0.0, z]))


def _leg_frame0(machine: Machine, i: int) -> np.ndarray:
    w = machine.inward_directions[i]
    y = -UP
    return np.column_stack([np.cross(y, w), y, w])


def build_model(machine: Machine, pose_m: np.ndarray, *, springs_per_segment: int | None = None,
                cardan_compliance: CardanCompliance | dict | None = None) -> MachineModel:
    """Build the VJM Pinocchio model of ``machine`` at the reachable pose ``pose_m`` (m).

    ``springs_per_segment`` defaults to ``machine.model.springs_per_segment``. ``cardan_compliance`` is
    ``None`` (rigid cardans), one :class:`CardanCompliance` for all eight cardans, or a dict keyed by
    ``(leg 0..3, 'base' | 'plate')``. Raises :class:`UnreachablePoseError` for a pose outside the limits.
    """
    h = kinematics.require_reachable(machine, pose_m)
    n = int(springs_per_segment or machine.model.springs_per_segment)
    lc = machine.cylinder.length_m
    e, g = machine.material.youngs_modulus_pa, machine.material.shear_modulus_pa
    cyl = machine.cylinder_section
    k_cyl = (n * e * cyl.second_moment_m4 / lc, n * e * cyl.second_moment_m4 / lc, n * g * cyl.polar_moment_m4 / lc)
    k_card = machine.joints.cardan_rotational_stiffness_nm_per_rad

    def compliance(i: int, end: str) -> CardanCompliance | None:
        if isinstance(cardan_compliance, dict):
            return cardan_compliance.get((i, end))
        return cardan_compliance

    model = pin.Model()
    model.name = machine.name
    model.gravity = pin.Motion.Zero()  # massless bodies: loads enter as wrenches only
    plate = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "plate")
    springs: list[Spring] = []
    ids: list[dict[str, int]] = []
    rigid: dict[str, list[int]] = {k: [] for k in ("base_a", "base_b", "prismatic", "plate_b", "plate_a")}
    stem_first: list[int] = []
    sections: list[dict[str, tuple[int, float]]] = []
    anchors, frames0, sigma = [], [], []

    for i in range(4):
        r0 = _leg_frame0(machine, i)
        frames0.append(r0)
        sigma.append(float(np.sign(r0[:, 0] @ machine.beta_axes[i])))
        parent = 0
        pending = pin.SE3(r0, machine.base_points_m[i].copy())  # placement of the next joint
        jid: dict[str, int] = {}

        def add(kind: str, name: str, law: SpringLaw | None = None, rest: float = 0.0) -> int:
            nonlocal parent, pending
            jm = {"RX": pin.JointModelRX, "RY": pin.JointModelRY, "RZ": pin.JointModelRZ,
                  "PX": pin.JointModelPX, "PY": pin.JointModelPY, "PZ": pin.JointModelPZ}[kind]()
            j = model.addJoint(parent, jm, pending, f"leg{i + 1}.{name}")
            parent, pending = j, pin.SE3.Identity()
            if law is not None:
                springs.append(Spring(name, i, model.joints[j].idx_q, model.joints[j].idx_v, law, rest))
            return j

        def virtual_translations(end: str) -> None:
            c = compliance(i, end)
            if c is not None and c.translation is not None:
                for ax in "XYZ":
                    add("P" + ax, f"{end}_cardan.t{ax.lower()}", c.translation)

        def virtual_rotation(end: str) -> None:
            c = compliance(i, end)
            if c is not None and c.rotation is not None:
                add("RZ", f"{end}_cardan.rc", c.rotation)

        def virtual_axial(end: str) -> None:
            c = compliance(i, end)
            if c is not None and c.axial is not None:
                add("PZ", f"{end}_cardan.axial", c.axial)

        card = LinearSpring(k_card) if k_card else None
        virtual_translations("base")
        jid["base_cardan"] = add("RX", "base_cardan.a", card)
        rigid["base_a"].append(jid["base_cardan"])
        virtual_rotation("base")
        jid["cylinder"] = add("RY", "base_cardan.b", card)
        rigid["base_b"].append(jid["cylinder"])
        virtual_axial("base")
        for k in range(n):
            pending = _tz(lc / (2 * n) if k == 0 else lc / n)
            for ax, kk in zip("XYZ", k_cyl):
                add("R" + ax, f"cylinder[{k}].{ax.lower()}", LinearSpring(kk))
        sec = {"base": (jid["cylinder"], 0.0), "actuator": (parent, lc / (2 * n))}
        pending = _tz(-(lc - lc / (2 * n)))  # prismatic frame at the (virtual) base point: q = leg length
        jid["actuator"] = jid["stem"] = add("PZ", "actuator", LinearSpring(1.0))
        rigid["prismatic"].append(jid["actuator"])
        for k in range(n):
            pending = _tz(0.0)  # set by retarget (depends on the stem length)
            j = add("RX", f"stem[{k}].x", LinearSpring(1.0))
            if k == 0:
                stem_first.append(j)
            add("RY", f"stem[{k}].y", LinearSpring(1.0))
            add("RZ", f"stem[{k}].z", LinearSpring(1.0))
        virtual_axial("plate")  # placed by retarget like the plate cardan (first joint after the stem)
        jid["plate_cardan"] = add("RY", "plate_cardan.b", card)
        rigid["plate_b"].append(jid["plate_cardan"])
        virtual_rotation("plate")
        j = add("RX", "plate_cardan.a", card)
        rigid["plate_a"].append(j)
        sec["plate"] = (j, 0.0)
        sections.append(sec)
        for name, (pj, z) in sec.items():
            model.addFrame(pin.Frame(f"leg{i + 1}.section.{name}", pj, _tz(z), pin.FrameType.OP_FRAME))
        virtual_translations("plate")
        jid["plate_end"] = parent
        ids.append(jid)
        anchors.append(pin.SE3(r0, machine.plate_offsets_m[i].copy()))

    constraints = [pin.ConstraintModel(pin.FrameAnchorConstraintModel(model, ids[i]["plate_end"], pin.SE3.Identity(),
                                                                      plate, anchors[i])) for i in range(4)]
    leg_v = []
    for i in range(4):
        first = model.joints[ids[i]["base_cardan"]].idx_v - (3 if _has_t(compliance(i, "base")) else 0)
        last = model.joints[ids[i]["plate_end"]].idx_v
        leg_v.append(np.arange(first, last + 1))
    mm = MachineModel(machine, model, model.createData(), constraints, n, h, np.zeros(model.nq), plate, ids, leg_v,
                      springs, anchors, np.array(sigma), np.array(frames0),
                      sections, {k: np.array([model.joints[j].idx_q for j in v]) for k, v in rigid.items()},
                      stem_first, cardan_compliance)
    var = [(k, 0 if sp.name == "actuator" else 2 if sp.name.endswith(".z") else 1, sp.leg)
           for k, sp in enumerate(springs) if sp.name == "actuator" or sp.name.startswith("stem[")]
    mm._variable_springs = tuple(np.array(c, dtype=int) for c in zip(*var))
    mm._stem_springs = [[(sp, sp.name.endswith(".z")) for sp in springs if sp.leg == i and sp.name.startswith("stem[")]
                        for i in range(4)]
    mm._actuator_springs = [next(sp for sp in springs if sp.leg == i and sp.name == "actuator") for i in range(4)]
    rigid_q = set(np.concatenate(list(mm._rigid_idx.values())).tolist())
    mm._rest_springs = [sp for sp in springs if sp.idx_q in rigid_q]
    mm._spring_q = np.array([sp.idx_q for sp in springs], dtype=int)
    mm.spring_k = np.array([sp.law.k if type(sp.law) is LinearSpring else np.nan for sp in springs])
    mm.spring_rest = np.zeros(len(springs))
    return mm.retarget(h)


def _has_t(c: CardanCompliance | None) -> bool:
    return c is not None and c.translation is not None
