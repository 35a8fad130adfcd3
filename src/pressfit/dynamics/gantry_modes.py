r"""Natural frequencies of the Cartesian gantry press, and the summary metrics that ``pressfit compare`` reads.

Modes (small vibrations about the unloaded geometry, as :mod:`pressfit.dynamics.modes` does for the 4-UPU):
on the VJM model of :mod:`pressfit.mechanics.gantry`, restricted to the elastic coordinates (compliance > 0)
and to the null space N of the portal's closure Jacobian J_c,

    K_r = N^T C^-1 N,   M_r = N^T M N,   K_r x = omega^2 M_r x   (scipy.linalg.eigh),

M Pinocchio's joint-space mass matrix (``pin.crba``, :func:`pressfit.dynamics.modes.mass_matrix`) of the
model with the gantry's masses (:func:`inertial_gantry_model`). Each member's mass is split at its stations as
:mod:`pressfit.dynamics.inertia` splits a leg: the piece between two stations rides on the body after the
first of them, with its own rotational inertia (Pinocchio's box and cylinder inertias, hollow sections as
outer minus inner). The parts of the Z beam that carry no load (beyond the Z carriage and on the far side of
the X carriage) and the ram above its guide are rigid masses on the carriage bodies; the carriages are point
masses at their carriage points with the rotational inertia of a cube of steel of the same mass (an ESTIMATE:
without it the Z carriage, between the Z guide's and the Y guide's collinear vertical rotations, would be
a massless body), the tool a point mass at the ram tip. The drives' rotor inertia is left out
(it adds to the axis modes only).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from scipy.linalg import eigh, null_space

from pressfit.description.gantry import GANTRY_AXES, BeamSection, Gantry
from pressfit.description.machine import require_inertia
from pressfit.dynamics.inertia import _add, joint_placements, total_mass_kg
from pressfit.dynamics.modes import mass_matrix
from pressfit.errors import PressfitError, ResidualError
from pressfit.mechanics import data_pool
from pressfit.mechanics.gantry import GantryModel, build_gantry_model

EIGEN_TOL = 1e-8  # relative residual |K_r x - omega^2 M_r x| / |K_r x| a mode is held to


def _piece_inertia(section: BeamSection, mass_per_m3: float, length_m: float) -> pin.Inertia:
    """Inertia of a straight piece of a member about its centre, member frame (x width, y height, z along)."""
    if section.kind == "tube":
        r, t = section.outer_diameter_m / 2, section.wall_thickness_m
        outer = pin.Inertia.FromCylinder(mass_per_m3 * math.pi * r**2 * length_m, r, length_m)
        if t >= r:
            return outer
        return outer - pin.Inertia.FromCylinder(mass_per_m3 * math.pi * (r - t) ** 2 * length_m, r - t, length_m)
    (b, h), (bi, hi) = section.rectangles_m()
    outer = pin.Inertia.FromBox(mass_per_m3 * b * h * length_m, b, h, length_m)
    if section.kind == "solid":
        return outer
    return outer - pin.Inertia.FromBox(mass_per_m3 * bi * hi * length_m, bi, hi, length_m)


def inertial_gantry_model(gm: GantryModel) -> pin.Model:
    """A copy of ``gm.model`` with the gantry's masses (module doc) and gravity along -y."""
    g = gm.gantry
    model = pin.Model(gm.model)
    model.gravity = pin.Motion(np.array([0.0, -9.81, 0.0, 0.0, 0.0, 0.0]))
    world = joint_placements(model, pin.neutral(model))
    rho = g.mass.density_kg_per_m3

    def piece(joint: int, section: BeamSection, rotation: np.ndarray, start: np.ndarray, length: float) -> None:
        if joint == 0 or length <= 0.0:
            return  # on the bed, or nothing
        inertia = _piece_inertia(section, rho, length)
        _add(model, world[joint], joint, inertia.mass, start + rotation[:, 2] * length / 2,
             rotation @ inertia.inertia @ rotation.T)

    for mb in gm.members:
        bounds = np.concatenate([[0.0], mb.station_s_m, [mb.length_m]])
        for j, s0, s1 in zip([mb.parent_joint, *mb.station_joints.tolist()], bounds[:-1], bounds[1:], strict=True):
            piece(j, mb.section, mb.rotation, mb.point_m(s0), float(s1 - s0))
        if mb.name == "z_beam":  # the unloaded parts: beyond the Z carriage, and on the far side of the X carriage
            half = g.frame.z_beam_half_length_m
            piece(int(mb.station_joints[-1]), mb.section, mb.rotation, mb.point_m(mb.length_m), half - mb.length_m)
            piece(gm.axis_joints["x"], mb.section, -mb.rotation, mb.root_m, half)
        if mb.name == "ram":  # above its guide, moving with it
            above = g.frame.ram_length_m - mb.length_m
            piece(gm.axis_joints["y"], mb.section, -mb.rotation, mb.root_m, above)
            tool = gm.model.frames[gm.tool_frame]
            _add(model, world[tool.parentJoint], tool.parentJoint, g.mass.tool_mass_kg,
                 mb.point_m(mb.length_m), np.zeros((3, 3)))
    for axis in GANTRY_AXES:  # a cube of the members' density: bodies between collinear joint axes need inertia
        j, m = gm.axis_joints[axis], getattr(g.axes, axis).carriage_mass_kg
        side = (m / rho) ** (1 / 3)
        _add(model, world[j], j, m, world[j].translation, pin.Inertia.FromBox(m, side, side, side).inertia)
    return model


@dataclass(frozen=True, kw_only=True)
class GantryModes:
    """The lowest natural modes of the gantry at a tool pose (SI), by increasing frequency."""

    pose_m: np.ndarray  # (3,) tool position
    frequencies_hz: np.ndarray  # (k,)
    tool_shapes: np.ndarray  # (k, 6) tool translation (m) and rotation (rad) per mass-normalised mode, world axes
    model_mass_kg: float  # total mass on the model's bodies (the columns below their first stations stand on the bed)
    closure_residual: float  # max |J_c phi| over the mass-normalised modes
    eigen_residual: float  # max |K_r x - omega^2 M_r x| / |K_r x| over the modes (on the closure null space)

    def to_dict(self) -> dict[str, Any]:
        return {"pose_m": self.pose_m.tolist(), "frequencies_hz": self.frequencies_hz.tolist(),
                "tool_shapes": self.tool_shapes.tolist(), "model_mass_kg": self.model_mass_kg,
                "closure_residual": self.closure_residual, "eigen_residual": self.eigen_residual}


def gantry_modes(gantry: Gantry, pose_m: np.ndarray, count: int = 6, **model_options: Any) -> GantryModes:
    """The ``count`` lowest modes with the tool at ``pose_m`` (m); ``model_options`` as
    :func:`pressfit.mechanics.gantry.build_gantry_model`. Raises ResidualError for a mode over EIGEN_TOL."""
    return model_modes(build_gantry_model(gantry, pose_m, **model_options), count)


def model_modes(gm: GantryModel, count: int = 6) -> GantryModes:
    """:func:`gantry_modes` of a built model."""
    model = inertial_gantry_model(gm)
    flex = gm.compliance > 0
    if not (isinstance(count, int) and 1 <= count <= int(flex.sum())):
        raise PressfitError(f"count of modes must be an integer in [1, {int(flex.sum())}], got {count!r}")
    with data_pool.borrowed(model) as data:
        full = mass_matrix(model, data, pin.neutral(model))
    basis = null_space(gm.closure_jacobian[:, flex])
    k_r = basis.T @ (basis / gm.compliance[flex][:, None])
    m_r = basis.T @ full[np.ix_(flex, flex)] @ basis
    omega2, x = eigh(k_r, m_r, subset_by_index=[0, count - 1])
    phi = np.zeros((gm.model.nv, count))
    phi[flex] = basis @ x
    kx = k_r @ x
    eig = float(np.max(np.linalg.norm(kx - m_r @ x * omega2, axis=0) / np.linalg.norm(kx, axis=0)))
    closure = float(np.max(np.abs(gm.closure_jacobian @ phi)))
    if not eig <= EIGEN_TOL:
        raise ResidualError("gantry modes", "eigen_residual", eig, EIGEN_TOL, f"at tool pose {tuple(gm.pose_m)} m")
    return GantryModes(pose_m=gm.pose_m.copy(), frequencies_hz=np.sqrt(omega2) / (2 * np.pi),
                       tool_shapes=(gm.tool_jacobian @ phi).T, model_mass_kg=total_mass_kg(model),
                       closure_residual=closure, eigen_residual=eig)


@dataclass(frozen=True, kw_only=True)
class GantryMetrics:
    """What ``pressfit compare`` reads of a gantry over a set of tool poses and loads (SI). "Worst" is over
    every pose and load; the medians are over the poses of each pose's worst value over the loads."""

    poses_m: np.ndarray  # (p, 3)
    tool_wrenches: np.ndarray  # (l, 6) tool wrenches, N and N m
    worst_drive_force_n: float  # largest |axial drive force| of any axis
    worst_drive_axis: str  # 'x', 'y' or 'z'
    worst_drive_pose_m: np.ndarray
    worst_bending_moment_nm: float  # largest bending moment in any structural member
    worst_bending_member: str  # one of pressfit.mechanics.gantry.MEMBERS
    worst_bending_pose_m: np.ndarray
    min_tool_stiffness_n_per_m: float  # smallest eigenvalue of the tool's 3x3 translational stiffness, worst pose
    median_tool_stiffness_n_per_m: float  # the same, median over the poses
    vertical_stiffness_n_per_m: np.ndarray  # (p,) 1 / C_yy per pose: the tool's compliance along y, rotation free
    max_tool_displacement_m: float  # |tool translation| under the loads, worst
    median_tool_displacement_m: float
    max_tool_tilt_rad: float  # |tool rotation vector| under the loads, worst
    median_tool_tilt_rad: float
    first_frequency_hz: float  # lowest first natural frequency over the poses
    first_frequency_pose_m: np.ndarray
    moving_mass_kg: float  # what the X axis moves (the largest moving mass)
    axis_moving_masses_kg: np.ndarray  # (3,) x, y, z axes
    worst_residual: float  # of the static solves (relative), each held to statics.RESIDUAL_TOL

    def to_dict(self) -> dict[str, Any]:
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.__dict__.items()}


def gantry_metrics(gantry: Gantry, poses_m: np.ndarray, load_n: float | np.ndarray, **model_options: Any
                   ) -> GantryMetrics:
    """Metrics of ``gantry`` over tool poses (p, 3) (m) under ``load_n``: a press force (N) on the tool along +y
    (the board's reaction), or tool wrenches (l, 6) (N, N m; e.g. a load cone), every one at every pose."""
    require_inertia(gantry.source, {"density_kg_per_m3": gantry.mass.density_kg_per_m3})
    poses = np.atleast_2d(np.asarray(poses_m, dtype=float))
    if poses.ndim != 2 or poses.shape[1] != 3 or len(poses) == 0 or not np.all(np.isfinite(poses)):
        raise PressfitError(f"poses_m must be a non-empty (p, 3) array of finite positions, got shape {poses.shape}")
    if np.ndim(load_n) == 0:
        wrenches = np.array([[0.0, float(load_n), 0.0, 0.0, 0.0, 0.0]])
    else:
        wrenches = np.atleast_2d(np.asarray(load_n, dtype=float))
    if wrenches.shape[1:] != (6,) or not np.all(np.isfinite(wrenches)):
        raise PressfitError(f"load_n must be a finite force (N) or (l, 6) tool wrenches, got {load_n!r}")
    drive = np.zeros((len(poses), 3))
    bending = np.zeros(len(poses))
    member: list[str] = []
    stiffness, vertical, disp, tilt, f1, residual = (np.zeros(len(poses)) for _ in range(6))
    for i, pose in enumerate(poses):
        gm = build_gantry_model(gantry, pose, **model_options)
        eqs = [gm.solve(w) for w in wrenches]
        drive[i] = np.max([np.abs(e.drive_forces_n) for e in eqs], axis=0)
        moments = [(m.bending_moment_nm, m.member) for e in eqs for m in e.members.values()]
        bending[i], name = max(moments)
        member.append(name)
        k = gm.tool_stiffness_n_per_m()
        stiffness[i] = float(np.linalg.eigvalsh(0.5 * (k + k.T))[0])
        vertical[i] = 1.0 / np.linalg.inv(k)[1, 1]
        disp[i] = max(float(np.linalg.norm(e.tool_displacement_m)) for e in eqs)
        tilt[i] = max(float(np.linalg.norm(e.tool_rotation_rad)) for e in eqs)
        residual[i] = max(e.residuals.worst() for e in eqs)
        f1[i] = model_modes(gm, count=1).frequencies_hz[0]
    i_d, i_b, i_f = np.unravel_index(np.argmax(drive), drive.shape), int(np.argmax(bending)), int(np.argmin(f1))
    return GantryMetrics(
        poses_m=poses, tool_wrenches=wrenches, worst_drive_force_n=float(drive[i_d]),
        worst_drive_axis=GANTRY_AXES[int(i_d[1])], worst_drive_pose_m=poses[i_d[0]].copy(),
        worst_bending_moment_nm=float(bending[i_b]), worst_bending_member=member[i_b],
        worst_bending_pose_m=poses[i_b].copy(), min_tool_stiffness_n_per_m=float(stiffness.min()),
        median_tool_stiffness_n_per_m=float(np.median(stiffness)), vertical_stiffness_n_per_m=vertical,
        max_tool_displacement_m=float(disp.max()),
        median_tool_displacement_m=float(np.median(disp)), max_tool_tilt_rad=float(tilt.max()),
        median_tool_tilt_rad=float(np.median(tilt)), first_frequency_hz=float(f1[i_f]),
        first_frequency_pose_m=poses[i_f].copy(), moving_mass_kg=gantry.axis_moving_masses_kg[0],
        axis_moving_masses_kg=np.array(gantry.axis_moving_masses_kg), worst_residual=float(residual.max()))

