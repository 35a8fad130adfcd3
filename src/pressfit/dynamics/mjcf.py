r"""A second engine: the rigid-leg machine exported to MuJoCo (MJCF) and a passive motion run in both engines.

:func:`machine_mjcf` writes the rigid-leg closed-loop model of :mod:`pressfit.dynamics.multibody` as an MJCF
string (nothing is written to disk here): the plate a free body, each leg a chain of four bodies from the
world (base cardan about a_i then b_i, the actuator's slide along the leg, plate cardan about b_i then a_i),
every body with the Pinocchio model's mass, centre of mass and inertia (``<inertial fullinertia>``), gravity
-9.81 m/s^2 along world y, no geoms (so no contacts), no joint damping, no actuators.

Loop closures: one ``<weld>`` per leg between the plate (body1) and the leg's last body (body2, the plate
cardan's outer body), ``relpose`` = the closure's anchor placement in the plate frame, so the weld holds the
same 6D relative pose as Pinocchio's CONTACT_6D closure. A ``<connect>`` (3D, point-on-point) would leave the
leg's last body free to spin relative to the plate: a spherical joint in place of the weld, a different
mechanism with a spurious spin of each leg about its axis, so welds are used. The n welds are redundant on
n >= 4 legs (6n rows, rank 6n - (n - 3): 24 rows, rank 23 on the 4-UPU), which MuJoCo's regularised solver
accepts.

MuJoCo's equality constraints are soft: the solver drives each constraint row's acceleration towards the
reference a_ref = -k r - b r_dot (r the violation) with impedance d, a_c = (1 - d) a_free + d a_ref, so that
the rows behave as a stiff spring-damper rather than a rigid link. The export makes them as stiff as MuJoCo
allows: impedance at its maximum, ``solimp = 0.9999 0.9999 ...`` (mjMAXIMP, constant), and ``solref = (2 h, 1)``
(time constant twice the time step h, the smallest MuJoCo's ``refsafe`` accepts with the Euler integrator,
critically damped: k = 1 / (d (2 h))^2, b = 2 / (d 2 h)). The violation left is r ~ R f / k, with
R = (1 - d) / d * A_ii the regulariser (A = J M^-1 J^T), so it falls as h^2: measured 5.6e-7 m at h = 1e-4 s
and 1.4e-7 m at h = 5e-5 s over a 0.5 s passive throw (the light cardan spiders make A_ii, hence R, large). Pinocchio's
closures are exact in the accelerations and stabilised by Baumgarte's law; its drift falls as h.

Integration: MuJoCo's ``Euler`` integrator is semi-implicit Euler (v += a h, q += v h; with no joint damping
its implicit-damping term is absent), the same scheme as :meth:`RigidLegModel.step`; the Newton solver runs
to a 1e-12 tolerance. State maps between the engines: MuJoCo's free joint stores (x, y, z, qw, qx, qy, qz)
and a world-frame linear velocity where Pinocchio stores (x, y, z, qx, qy, qz, qw) and a plate-frame one;
every other coordinate is the same joint value (rad or m).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import mujoco
import numpy as np
import pinocchio as pin

from pressfit.description.machine import Machine
from pressfit.dynamics.inertia import GRAVITY_M_PER_S2
from pressfit.dynamics.multibody import RigidLegModel, rigid_leg_model
from pressfit.errors import PressfitError

SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)  # constant impedance at MuJoCo's maximum (mjMAXIMP)
_AXES = {"RX": ("hinge", "1 0 0"), "RY": ("hinge", "0 1 0"), "RZ": ("hinge", "0 0 1"),
         "PX": ("slide", "1 0 0"), "PY": ("slide", "0 1 0"), "PZ": ("slide", "0 0 1")}


def _num(values: np.ndarray | list[float] | tuple[float, ...]) -> str:
    """Numbers at full double precision, space separated (MJCF vectors)."""
    return " ".join(f"{float(x):.17g}" for x in np.ravel(values))


def _wxyz(rotation: np.ndarray) -> np.ndarray:
    """MuJoCo's quaternion (w, x, y, z) of a rotation matrix."""
    xyzw = pin.Quaternion(rotation).coeffs()
    return np.array([xyzw[3], xyzw[0], xyzw[1], xyzw[2]])


def _inertial(parent: ET.Element, inertia: pin.Inertia) -> None:
    """``<inertial>`` of a Pinocchio body inertia (mass kg, centre m, inertia about the centre kg m^2)."""
    rot = inertia.inertia
    ET.SubElement(parent, "inertial", pos=_num(inertia.lever), mass=_num([inertia.mass]),
                  fullinertia=_num([rot[0, 0], rot[1, 1], rot[2, 2], rot[0, 1], rot[0, 2], rot[1, 2]]))


def _body(parent: ET.Element, model: pin.Model, joint: int) -> ET.Element:
    """The body carried by Pinocchio joint ``joint``: its placement in the parent body, joint, inertia."""
    placement, name = model.jointPlacements[joint], model.names[joint]
    body = ET.SubElement(parent, "body", name=name, pos=_num(placement.translation),
                         quat=_num(_wxyz(placement.rotation)))
    kind = model.joints[joint].shortname().removeprefix("JointModel")
    if kind == "FreeFlyer":
        ET.SubElement(body, "freejoint", name=name)
    elif kind in _AXES:
        ET.SubElement(body, "joint", name=name, type=_AXES[kind][0], axis=_AXES[kind][1])
    else:
        raise PressfitError(f"joint '{name}': type {kind} has no MJCF export (free flyer, RX-RZ, PX-PZ only)")
    _inertial(body, model.inertias[joint])
    return body


def machine_mjcf(rigid: RigidLegModel, timestep_s: float = 1e-4) -> str:
    """The rigid-leg model as an MJCF string (time step ``timestep_s``, s), with a keyframe ``reference`` at
    its closed reference configuration (the model's pose, at rest). Units SI (m, kg, kg m^2, rad, s)."""
    if not (np.isfinite(timestep_s) and timestep_s > 0):
        raise PressfitError(f"MJCF export: timestep_s must be positive, got {timestep_s!r}")
    model = rigid.model
    root = ET.Element("mujoco", model=f"pressfit {len(rigid.constraint_models)}-UPU rigid legs")
    ET.SubElement(root, "compiler", angle="radian", inertiafromgeom="false")
    option = ET.SubElement(root, "option", timestep=_num([timestep_s]), gravity=_num([0.0, -GRAVITY_M_PER_S2, 0.0]),
                           integrator="Euler", solver="Newton", iterations="200", tolerance="1e-12")
    ET.SubElement(option, "flag", contact="disable")
    bodies = {0: ET.SubElement(root, "worldbody")}
    for joint in range(1, model.njoints):  # parents come first in Pinocchio's depth-first order, as in MJCF
        bodies[joint] = _body(bodies[model.parents[joint]], model, joint)
    equality = ET.SubElement(root, "equality")
    for i, cm in enumerate(rigid.constraint_models):
        anchor = cm.joint2_placement  # the leg end's closure frame in the plate frame
        ET.SubElement(equality, "weld", name=f"leg{i + 1}.closure", body1=model.names[cm.joint2_id],
                      body2=model.names[cm.joint1_id],
                      relpose=_num(np.concatenate([anchor.translation, _wxyz(anchor.rotation)])),
                      solref=_num([2 * timestep_s, 1.0]), solimp=_num(SOLIMP))
    keyframe = ET.SubElement(root, "keyframe")
    ET.SubElement(keyframe, "key", name="reference", qpos=_num(mujoco_state(rigid, rigid.reference_q,
                                                                             np.zeros(model.nv))[0]))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode")


def mujoco_state(rigid: RigidLegModel, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's (qpos, qvel) of a Pinocchio state (q, v) of ``rigid`` (free flyer first, then the legs)."""
    qpos, qvel = np.array(q, dtype=float), np.array(v, dtype=float)
    qpos[3], qpos[4:7] = q[6], q[3:6]
    qvel[0:3] = pin.Quaternion(q[6], *q[3:6]).toRotationMatrix() @ v[0:3]
    return qpos, qvel


@dataclass(frozen=True, kw_only=True)
class PassiveMotion:
    """One passive run (no actuator force, gravity on) of the rigid-leg machine in Pinocchio and in MuJoCo from
    the same state, sampled every time step (row 0 the initial state). Plate positions (m, world), plate
    rotation angles (rad, from the unrotated plate), closure errors: the largest translation error of the
    loop closures over the run (m), Pinocchio's Baumgarte-corrected drift and MuJoCo's soft-weld violation."""

    time_s: np.ndarray  # (n + 1,)
    pinocchio_plate_m: np.ndarray  # (n + 1, 3)
    mujoco_plate_m: np.ndarray  # (n + 1, 3)
    pinocchio_rotation_rad: np.ndarray  # (n + 1,)
    mujoco_rotation_rad: np.ndarray  # (n + 1,)
    pinocchio_closure_error_m: float
    mujoco_closure_error_m: float
    timestep_s: float

    @property
    def deviation_m(self) -> np.ndarray:
        """Distance between the two engines' plate positions at each sample (m)."""
        return np.linalg.norm(self.pinocchio_plate_m - self.mujoco_plate_m, axis=1)


def _weld_error_m(model: mujoco.MjModel, data: mujoco.MjData) -> float:
    """Largest translation error (m) of the welds: the leg end's origin against its anchor on the plate."""
    worst = 0.0
    for eq in range(model.neq):
        plate, end = model.eq_obj1id[eq], model.eq_obj2id[eq]
        anchor = data.xpos[plate] + data.xmat[plate].reshape(3, 3) @ model.eq_data[eq, 3:6]
        worst = max(worst, float(np.linalg.norm(data.xpos[end] - anchor)))
    return worst


def passive_motion(machine: Machine, pose_m: np.ndarray,
                   plate_velocity_m_per_s: np.ndarray | tuple[float, float, float] = (0.0, 0.0, 0.0),
                   duration_s: float = 0.5, timestep_s: float = 1e-4,
                   baumgarte_rad_per_s: float = 200.0) -> PassiveMotion:
    """Run the rigid-leg machine passively for ``duration_s`` (s) at ``timestep_s`` (s) in both engines, from the
    closed configuration at a reachable pose (m) with the plate translating at ``plate_velocity_m_per_s`` (m/s,
    the joint velocities completed to satisfy the closures, :meth:`RigidLegModel.admissible_velocity`)."""
    if not (np.isfinite(timestep_s) and timestep_s > 0 and np.isfinite(duration_s) and duration_s >= timestep_s):
        raise PressfitError(f"need 0 < timestep_s <= duration_s, got timestep_s={timestep_s!r}, "
                            f"duration_s={duration_s!r}")
    rigid = rigid_leg_model(machine, pose_m, baumgarte_rad_per_s)
    steps = round(duration_s / timestep_s)
    q = rigid.configuration_at(pose_m)
    v = rigid.admissible_velocity(q, np.asarray(plate_velocity_m_per_s, dtype=float))
    mj_model = mujoco.MjModel.from_xml_string(machine_mjcf(rigid, timestep_s))
    mj_data = mujoco.MjData(mj_model)
    mj_data.qpos[:], mj_data.qvel[:] = mujoco_state(rigid, q, v)
    plates, angles = np.zeros((2, steps + 1, 3)), np.zeros((2, steps + 1))
    plates[:, 0], errors = q[:3], [0.0, 0.0]
    tau = np.zeros(rigid.model.nv)
    for k in range(1, steps + 1):
        q, v = rigid.step(q, v, tau, timestep_s)
        mujoco.mj_step(mj_model, mj_data)
        plates[0, k], plates[1, k] = q[:3], mj_data.qpos[:3]
        angles[0, k] = 2 * np.arctan2(np.linalg.norm(q[3:6]), abs(q[6]))
        angles[1, k] = 2 * np.arctan2(np.linalg.norm(mj_data.qpos[4:7]), abs(mj_data.qpos[3]))
        errors = [max(errors[0], rigid.closure_error_m()), max(errors[1], _weld_error_m(mj_model, mj_data))]
    if not (np.all(np.isfinite(plates)) and np.all(np.isfinite(errors))):
        raise PressfitError(f"passive motion diverged (non-finite state) at time step {timestep_s} s: reduce it")
    return PassiveMotion(time_s=np.arange(steps + 1) * timestep_s, pinocchio_plate_m=plates[0],
                         mujoco_plate_m=plates[1], pinocchio_rotation_rad=angles[0], mujoco_rotation_rad=angles[1],
                         pinocchio_closure_error_m=errors[0], mujoco_closure_error_m=errors[1],
                         timestep_s=timestep_s)
