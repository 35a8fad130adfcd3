r"""Closed-loop rigid-leg multibody dynamics of the n-UPU with Pinocchio's constraint dynamics.

The model (:func:`rigid_leg_model`) is the VJM model of :mod:`pressfit.mechanics.model` with its elastic
virtual joints frozen: plate free flyer, per leg base cardan (2 revolutes), the actuated prismatic joint
(coordinate = leg length l_i, m), plate cardan (2 revolutes), closed on the plate by one 6D loop closure per leg
(``pin.RigidConstraintModel`` CONTACT_6D, the same anchor frames as the elastic model). Body inertias are
those of :func:`pressfit.dynamics.inertia.inertial_model` lumped onto the rigid bodies (the stem, a rod of fixed
length, is one body after the prismatic joint: its mass and its place on that body are the same at every pose,
so the model is the same wherever it is built), and the
prismatic joints carry its armature (an electric drive's reflected rotor and screw inertia); gravity
-9.81 m/s^2 along y. The elastic structure is left out because its modes (from 20 Hz for the plate's
rocking up to kHz for the legs' axial modes, ``pressfit modes``) would need time steps of microseconds.

Why the rigid model is right for motion and forces below the first structural mode: there the structure
responds quasi-statically, so its deflection under a tool force F is C F, C the plate compliance of
:mod:`pressfit.mechanics.condensed` at the current pose, which a contact model can put in series with the
rigid motion (the tool sees the rigid position plus C F).

Accelerations: ``pin.constraintDynamics`` (proximal KKT; on n legs the closures are redundant, rank
6n - (n - 3) of 6n: 23 of 24 on the 4-UPU, none redundant on the 3-UPU; the proximal iterations handle it) with
Baumgarte stabilisation a_c = -Kp e - Kd e_dot of the closure error e, Kp = omega_b^2, Kd = 2 omega_b. Time
stepping: semi-implicit (symplectic) Euler, v += a dt, q = q (+) v dt. The closure drift (largest translation
error of the closures, m) is reported per step.

Leg loads (:meth:`RigidLegModel.leg_loads`): the closure force of leg i (``data.lambda_c``, 6 per closure,
in the frame of the leg's last body at the plate cardan centre) is the wrench the plate exerts on the leg
there: the plate section of :mod:`pressfit.mechanics.statics` with its conventions (leg frame e_z base ->
plate; the bending magnitude needs no e_x): axial force N = f . e_z (> 0 tension), torsion T = m . e_z,
bending |M_b| = |m - T e_z|. N differs from the actuator tension by the weight and inertia of
the stem. The couples are statically indeterminate in the rigid model (the n - 3 self-stresses of the closures,
one on the 4-UPU, are sets of couples along the legs' free couple axes, S the left null space of the closure
Jacobian); Pinocchio's proximal solver leaves an arbitrary, step-to-step varying amount of it in lambda, so
the loads are taken from the minimum-norm closure force lambda - S S^T lambda, the split of legs equally
stiff in torsion. S is recomputed when the plate moved 1 mm (``SELF_STRESS_UPDATE_M``): it turns by about
1 mm / l (2e-3 rad, l ~ 0.5 m), which bounds the error of the couples at 0.2%.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pressfit import kinematics
from pressfit.description.machine import Machine
from pressfit.dynamics import kernels
from pressfit.dynamics.inertia import inertial_model, joint_placements
from pressfit.errors import PressfitError
from pressfit.mechanics.model import build_model

RIGID_JOINTS = (("RX", "base_cardan.a"), ("RY", "base_cardan.b"), ("PZ", "actuator"), ("RY", "plate_cardan.b"),
                ("RX", "plate_cardan.a"))
_JOINT_TYPES = {"RX": pin.JointModelRX, "RY": pin.JointModelRY, "PZ": pin.JointModelPZ}
SELF_STRESS_UPDATE_M = 1e-3  # the closures' self-stress direction is recomputed when the plate moved this far, m


@dataclass(kw_only=True)
class PoseCache:
    """``function(pose)`` recomputed only when the pose (m) moved more than ``tolerance_m`` from the pose of
    the cached value (infinity norm); the caller states the error bound (|d function / d pose| tolerance)."""

    function: Callable[[np.ndarray], np.ndarray]
    tolerance_m: float
    pose_m: np.ndarray | None = None
    value: np.ndarray | None = None

    def __call__(self, pose_m: np.ndarray) -> np.ndarray:
        if self.value is None or kernels.moved(pose_m, self.pose_m, self.tolerance_m):
            self.pose_m, self.value = np.array(pose_m, dtype=float), self.function(pose_m)
        return self.value


def path_nodes(path_m: np.ndarray, spacing_m: float) -> np.ndarray:
    """Poses (k, 3), m, along a sampled path (n, 3), m: every s-th sample and the last, s the most samples that
    span at most ``spacing_m`` (infinity norm) at the path's largest sample step, so a pose on the path is within
    half the spacing of one, in the path's order (the deflection cache's nodes,
    :class:`pressfit.dynamics.control.DeflectionCache`)."""
    path = np.asarray(path_m, dtype=float)
    step = float(np.abs(np.diff(path, axis=0)).max(initial=0.0))
    stride = max(1, int(spacing_m // step)) if step > 0.0 else len(path)
    return np.ascontiguousarray(np.vstack([path[::stride], path[-1:]]))


@dataclass(kw_only=True)
class RigidLegModel:
    """The rigid-leg closed-loop model and its solver workspace (Pinocchio data, constraint datas)."""

    machine: Machine
    model: pin.Model
    data: pin.Data
    constraint_models: pin.StdVec_RigidConstraintModel
    constraint_datas: pin.StdVec_RigidConstraintData
    prox: pin.ProximalSettings
    actuator_v: np.ndarray  # (n,) velocity indices of the prismatic (actuator) joints
    actuator_q: np.ndarray  # (n,) their configuration indices: q[actuator_q] = leg lengths l_i (m)
    sigma: np.ndarray  # (n,) sign of the b-revolutes against beta (as in the elastic model)
    reference_q: np.ndarray  # rigid configuration at the model's pose
    baumgarte_rad_per_s: float
    end_joints: tuple[int, ...] = ()  # the last joint of each leg (plate cardan a): joint1 of its closure
    self_stress: PoseCache = field(init=False)
    _datas: tuple | None = field(default=None, init=False, repr=False)  # (constraint_datas, its error views)

    def __post_init__(self) -> None:
        self.self_stress = PoseCache(function=self._self_stress, tolerance_m=SELF_STRESS_UPDATE_M)

    def _self_stress(self, pose_m: np.ndarray) -> np.ndarray:
        """Orthonormal left null space (6n, n - 3) of the closure Jacobian at the closed configuration of ``pose_m``
        (the closures' n - 3 self-stresses, one per redundant leg: none on 3 legs)."""
        u = np.linalg.svd(self.closure_jacobian(self.configuration_at(pose_m), scratch=True))[0]
        return u[:, u.shape[0] - (len(self.machine.legs) - 3):]

    def configuration_at(self, pose_m: np.ndarray) -> np.ndarray:
        """Closed rigid configuration (nq,) at a reachable pose (m), from equation 1 (closed form)."""
        h = np.asarray(pose_m, dtype=float).reshape(3)
        ik = kinematics.inverse_kinematics(self.machine, h)
        h = kinematics.require_reachable(self.machine, h, ik)
        sigma = self.sigma
        q = np.zeros(self.model.nq)
        q[0:3], q[6] = h, 1.0
        values = np.array([ik.alpha_rad, sigma * ik.beta_rad, ik.lengths_m, -sigma * ik.beta_rad, -ik.alpha_rad])
        for i in range(len(self.actuator_q)):
            q[self.actuator_q[i] - 2:self.actuator_q[i] + 3] = values[:, i]
        return q

    def accelerations(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Joint accelerations (nv,) under joint forces ``tau`` (N on the actuators, > 0 extends the leg)."""
        return pin.constraintDynamics(self.model, self.data, q, v, tau, self.constraint_models,
                                      self.constraint_datas, self.prox)

    def closure_error_m(self) -> float:
        """Largest loop-closure translation error (m) at the last :meth:`accelerations` call."""
        datas = self.constraint_datas
        if self._datas is None or self._datas[0] is not datas:  # held views of the errors (they follow each call)
            self._datas = (datas, [datas[i].contact_placement_error.linear for i in range(len(datas))])
        errors = [e.tolist() for e in self._datas[1]]
        return math.sqrt(max([x * x + y * y + z * z for x, y, z in errors]))

    def leg_loads(self) -> np.ndarray:
        """(n, 3): axial force N (N, > 0 tension), torsion T (N m) and bending |M_b| (N m) of each leg at its
        plate cardan, from the closure forces of the last :meth:`accelerations` call (module docstring)."""
        lam = np.asarray(self.data.lambda_c)
        s = self.self_stress(np.array(self.data.oMi[1].translation))
        lam = (lam - s @ (s.T @ lam)).reshape(len(self.actuator_q), 2, 3)  # the minimum-norm split of the couples
        placements = [self.data.oMi[j] for j in self.end_joints]
        world = np.einsum("lij,lkj->lki", np.array([m.rotation for m in placements]), lam)  # (leg, f|m, xyz)
        axes = np.array([m.translation for m in placements]) - self.machine.base_points_m
        axes /= np.sqrt(np.einsum("li,li->l", axes, axes))[:, None]
        axial = np.einsum("lki,li->lk", world, axes)  # N, T
        bent = world[:, 1] - axial[:, 1:] * axes
        return np.column_stack([axial, np.sqrt(np.einsum("li,li->l", bent, bent))])

    def axial_forces_n(self, q: np.ndarray) -> np.ndarray:
        """(n,): the axial force N (N, > 0 tension) of each leg at its plate cardan from the closure forces of the
        last :meth:`accelerations` call, made at ``q`` (the first column of :meth:`leg_loads`, without the couples'
        split: the self-stress is made of couples and leaves the forces alone; closed form from the plate cardan
        angles, :func:`pressfit.dynamics.kernels.axial_forces`)."""
        out = np.empty(len(self.actuator_q))
        kernels.axial_forces(np.asarray(self.data.lambda_c), np.asarray(q, dtype=float), self.actuator_q, out)
        return out

    def energy_j(self, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
        """Kinetic and gravitational potential energy (J) at (q, v) (one Pinocchio pass for both)."""
        pin.computeMechanicalEnergy(self.model, self.data, q, v)
        return float(self.data.kinetic_energy), float(self.data.potential_energy)

    def closure_jacobian(self, q: np.ndarray, scratch: bool = False) -> np.ndarray:
        """The (6n, nv) Jacobian of the n loop closures at q (``scratch``: in fresh Pinocchio datas, leaving
        those of the last :meth:`accelerations` call intact)."""
        data = self.model.createData() if scratch else self.data
        datas = [cm.createData() for cm in self.constraint_models] if scratch else self.constraint_datas
        pin.computeJointJacobians(self.model, data, q)
        return np.vstack([pin.getConstraintJacobian(self.model, data, cm, cd)
                          for cm, cd in zip(self.constraint_models, datas, strict=True)])

    def admissible_velocity(self, q: np.ndarray, plate_velocity_m_per_s: np.ndarray) -> np.ndarray:
        """Joint velocities (nv,) with the plate translating at the given velocity (m/s, world axes; the plate
        unrotated) that satisfy the linearised closures J v = 0 (least squares over the leg joints)."""
        v = np.zeros(self.model.nv)
        v[0:3] = np.asarray(plate_velocity_m_per_s, dtype=float)
        jac = self.closure_jacobian(q)
        v[6:] = -np.linalg.lstsq(jac[:, 6:], jac[:, :6] @ v[:6], rcond=None)[0]
        return v

    def step(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
        """One semi-implicit Euler step of ``dt_s`` (s)."""
        v = v + dt_s * self.accelerations(q, v, tau)
        return pin.integrate(self.model, q, v * dt_s), v


def rigid_leg_model(machine: Machine, pose_m: np.ndarray, baumgarte_rad_per_s: float = 200.0) -> RigidLegModel:
    """The rigid-leg model with the machine's masses at a reachable pose (m); Baumgarte rate omega_b (rad/s)."""
    if not (np.isfinite(baumgarte_rad_per_s) and baumgarte_rad_per_s > 0):
        raise PressfitError(f"baumgarte_rad_per_s must be positive, got {baumgarte_rad_per_s!r}")
    if machine.has_cardan_tilts:
        raise PressfitError("the rigid-leg dynamics needs parallel cardan axes (Tsai's condition): this machine has "
                            "cardan tilts (legs.*_cardan_tilt_rad), with which rigid legs cannot close the loops")
    mm = build_model(machine, pose_m)
    full = inertial_model(mm)
    full_placements = joint_placements(full, mm.q0)
    model = pin.Model()
    model.gravity = full.gravity
    plate = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "plate")
    owner = {mm.plate_joint_id: plate}
    for i, ids in enumerate(mm.leg_joint_ids):
        parent, placement = 0, pin.SE3(mm.leg_frames0[i], machine.base_points_m[i].copy())
        for kind, name in RIGID_JOINTS:
            parent = model.addJoint(parent, _JOINT_TYPES[kind](), placement, f"leg{i + 1}.{name}")
            placement = pin.SE3.Identity()
        for j in range(ids["base_cardan"], ids["plate_end"] + 1):  # full-model bodies -> rigid body carrying them
            if model.existJointName(full.names[j]):
                current = model.getJointId(full.names[j])
            owner[j] = current
    actuators = [model.joints[model.getJointId(f"leg{i + 1}.actuator")] for i in range(len(machine.legs))]
    rigid = RigidLegModel(machine=machine, model=model, data=model.createData(),
                          constraint_models=pin.StdVec_RigidConstraintModel(),
                          constraint_datas=pin.StdVec_RigidConstraintData(),
                          prox=pin.ProximalSettings(1e-12, 1e-10, 10),
                          actuator_v=np.array([j.idx_v for j in actuators]),
                          actuator_q=np.array([j.idx_q for j in actuators]),
                          sigma=mm.sigma.copy(), reference_q=np.zeros(model.nq),
                          baumgarte_rad_per_s=baumgarte_rad_per_s)
    rigid.reference_q = rigid.configuration_at(mm.pose_m)
    rigid.end_joints = tuple(model.getJointId(f"leg{i + 1}.plate_cardan.a") for i in range(len(machine.legs)))
    data = model.createData()
    pin.forwardKinematics(model, data, rigid.reference_q)
    for j, body in owner.items():
        model.inertias[body] = model.inertias[body] + data.oMi[body].actInv(full_placements[j].act(full.inertias[j]))
    for i, ids in enumerate(mm.leg_joint_ids):  # an electric drive's reflected inertia (dynamics/inertia.py)
        model.armature[rigid.actuator_v[i]] = full.armature[full.joints[ids["actuator"]].idx_v]
    gains = pin.BaumgarteCorrectorParameters(baumgarte_rad_per_s**2, 2 * baumgarte_rad_per_s)
    for i in range(len(machine.legs)):
        end = model.getJointId(f"leg{i + 1}.plate_cardan.a")
        cm = pin.RigidConstraintModel(pin.ContactType.CONTACT_6D, model, end, pin.SE3.Identity(), plate,
                                      mm.anchor_placements[i], pin.ReferenceFrame.LOCAL)
        cm.setBaumgarteCorrectorParameters(gains)
        rigid.constraint_models.append(cm)
        rigid.constraint_datas.append(cm.createData())
    rigid.data = model.createData()
    pin.initConstraintDynamics(model, rigid.data, rigid.constraint_models, rigid.constraint_datas)
    return rigid


def inverse_apparent_mass(machine: Machine, pose_m: np.ndarray) -> np.ndarray:
    """M_h^-1 (3, 3), 1/kg: the plate's acceleration (world axes) per unit plate force at rest at a reachable pose,
    gravity off (the rigid-leg model's constraint dynamics, three unit forces; symmetrised)."""
    rigid = rigid_leg_model(machine, pose_m)
    rigid.model.gravity = pin.Motion.Zero()
    q, rest = rigid.configuration_at(pose_m), np.zeros(rigid.model.nv)
    inverse = np.empty((3, 3))
    for k in range(3):
        tau = np.zeros(rigid.model.nv)
        tau[k] = 1.0  # N along the unrotated plate's axes = world axes
        inverse[:, k] = rigid.accelerations(q, rest, tau)[:3]
    return 0.5 * (inverse + inverse.T)
