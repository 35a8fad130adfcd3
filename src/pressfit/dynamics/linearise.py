r"""The insertion's control loop linearised at a pose: plant, drives and Figure 12's controller as state space.

Plant (``model = "flexible"``, the default): the elastic VJM machine of :func:`pressfit.dynamics.modes.reduced_system`
(static equilibrium under the plate's and tool's weight, motions restricted to the linearised closures,
dq = basis z) with FORCE drives, as :mod:`pressfit.dynamics.machine.flexible` runs them: the actuator joints
carry no spring and drive i puts -F_i (F_i > 0 tension) on its actuator joint,

    M_r z'' + C_r z' + K_r z = -S^T F + p_y^T f,     S = basis[actuator rows] (n, r),  p_y = plate_map[1],

K_r = basis^T K basis with the actuator springs removed (three rigid-body modes remain: the plate's
translations, held by the controller only), C_r the machine file's Rayleigh damping on the elastic motion
(alpha M (v - v_r) + beta K v, v_r the rigid machine's velocity at the actuator rates, as the simulation damps)
and f the contact force on the tool (N, +y). ``model = "rigid"``: the rigid-leg machine, z = h (3,) the plate
position, M_h h'' = -A F + e_y f, M_h the apparent Cartesian mass (Pinocchio's constraint dynamics, unit plate
forces, gravity off), S = A^T (equation 2: dl = A^T dh). In contact (the pin pose) the case's contact spring
k_c (and damping b_c) acts at the tool: K += k_c p_y^T p_y, C += b_c p_y^T p_y, contact force = -k_c y - b_c y'.
Drives (``[actuator] kind``, :class:`pressfit.dynamics.drives.base.DrivePort`): each leg's drive linearised at
its operating tension (:func:`static_tensions_n`: gravity feed-forward and preload), x_d' = a x_d + b N_cmd +
r v, N = c x_d, v the rate of the coordinate it pushes: force, tau N' = N_cmd - N; electric, the PI current
loop with the back-EMF (whose integral makes it an added mass k_f K_t (2 pi / lead) / k_i below k_i / k_p),
the rotor's reflected mass on its own coordinate u joined to the leg by the screw, nut and bearing in series
(k (l - u)), the encoder reading u; hydraulic, the spool's lag, the chambers with K_q, K_c, leakage and the
oil column (beta / V_a,b, A l_dot), the pressure loop and the flow feed-forward. Outputs: the n
measured lengths l = S z (the actuator joint coordinates), their rates, the tool position (3) and the contact
force.

Controller (:mod:`pressfit.dynamics.control`), unclamped (limiter inactive, the contact force below the limit):
the Gauss-Newton estimate is linear near the pose, dh_est = J^+ dl = (A^+)^T dl, likewise its rate;
W = K_p (r - h_est) + K_d (r' - h_est') + K_i int(r - h_est); F_cmd = -A^+ W (the preload V a and the
gravity feed-forward are constants of the equilibrium). Left out, stated: the pose dependence of A^+, v_p
(distribution) and of A (the legs' static tensions turning with the legs): in statics they cancel exactly
(-A(h) N(h) = W for every h), dynamically they differ by the drive lag; the gravity feed-forward's
|dG/dh| <= 17 N/m (``control`` module) against K_p = 2e4 N/m.

Results: open loop broken at the force commands per Cartesian axis (the other two closed), margins from
python-control's ``stability_margins``; closed-loop poles (frequency |s| / 2 pi, damping -Re s / |s|); the
-3 dB bandwidth of reference -> tool (``control.bandwidth``) vertical and lateral (x); the structural modes
(:func:`pressfit.dynamics.modes.natural_modes`, drives holding) with how much the drives see and move each: the
drive forces act on, and the encoders measure, the actuator coordinates S phi_k (collocated: the controllability
and the observability are the same vector), and the share of the mode's strain energy stored in the actuator
springs, sum_i k_i (S phi_k)_i^2 / phi_k^T K phi_k (= / omega_k^2, phi mass-normalised), is that measure normalised
by the mode itself: most of it for the axial leg modes (75% at pose A's 386 Hz mode: the legs' swing bends
them, tests/dynamics/test_linearise.py), 1-2% for the rocking pair (the plate sways and tilts about the legs'
concurrency point, where a rigid rotation changes no leg length; what is left is the legs' bending),
exactly 0 for the plate twist; one warning line per (pose, mode) when a loop pole (a
closed-loop pole the feedback moved by more than ``MOVED_RELATIVE`` from every open-loop pole) lies within
``WARNING_RATIO`` of a structural mode's frequency and the drives hold at least ``DRIVE_SHARE_THRESHOLD`` of that
mode's strain energy (below it the loop neither excites nor damps the mode).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import control as ct
import numpy as np
from scipy.optimize import brentq

from pressfit import kinematics
from pressfit.description.cases import Case, Contact, Controller
from pressfit.description.machine import Machine
from pressfit.dynamics import drives as drive_kinds
from pressfit.dynamics.actuators import distribution
from pressfit.dynamics.control import gravity_feedforward_n
from pressfit.dynamics.drives.base import DrivePort
from pressfit.dynamics.machine.flexible import FlexibleMachine
from pressfit.dynamics.machine.registry import model_kind, require_model
from pressfit.dynamics.modes import closure_jacobian, elastic_stiffness, mass_matrix, natural_modes, reduced_system
from pressfit.dynamics.multibody import inverse_apparent_mass, rigid_leg_model
from pressfit.errors import PressfitError
from pressfit.mechanics.condensed import condensed_plate_compliance
from pressfit.mechanics.contact_laws.elastic import ElasticLaw
from pressfit.mechanics.preload import ActuatorPreload, self_stress_forces_n
from pressfit.mechanics.press_curve import PinField, field_stiffness, operating_depth_m, pin_pose_m

WARNING_RATIO = 0.2  # a loop pole within 20% of a structural mode's frequency is reported ...
DRIVE_SHARE_THRESHOLD = 0.1  # ... when the drives hold at least this share of the mode's strain energy
MOVED_RELATIVE = 1e-3  # a closed-loop pole farther than this (relative) from every open-loop pole is a loop pole
MODE_COUNT = 6
FREQUENCY_POINTS = 300  # log-spaced over 0.01-1000 Hz: Bode data and margins (~30 ms a point at 200 states)
AXES = ("x", "y", "z")


@dataclass(frozen=True, kw_only=True)
class Plant:
    """The linear plant at a pose (module doc): state x = [z, z', F]; inputs the force commands (N, one per leg)
    and the contact force (N, +y on the tool); ``c_lengths``, ``c_rates``, ``c_tool`` (legs / legs / 3, n) the
    outputs, m and m/s; ``c_contact`` (n,) the contact force (N, zero out of contact). A^+ (legs, 3) at the pose."""

    model: str
    pose_m: np.ndarray
    in_contact: bool
    a: np.ndarray
    b_command: np.ndarray  # (n, legs)
    b_contact: np.ndarray  # (n,)
    c_lengths: np.ndarray
    c_rates: np.ndarray
    c_tool: np.ndarray
    c_contact: np.ndarray
    pinv: np.ndarray
    vertical_mass_kg: float  # 1 / (e_y^T M_h^-1 e_y) of the rigid model: the apparent vertical mass
    drive_kind: str = "force"
    tensions_n: np.ndarray | None = None  # (legs,) the drives' operating tensions, N
    contact_stiffness_n_per_m: float = 0.0  # k_c: the contact law's local slope (0 out of contact), N/m
    contact_depth_m: float | None = None  # the tool depth it is taken at (None: a law of constant slope), m

    def system(self) -> ct.StateSpace:
        """python-control state space, inputs n_cmd1..n, f_contact; outputs l1..n, tool_x..z, f_contact."""
        c = np.vstack([self.c_lengths, self.c_tool, self.c_contact])
        b = np.column_stack([self.b_command, self.b_contact])
        legs = range(1, self.b_command.shape[1] + 1)
        return ct.ss(self.a, b, c, np.zeros((c.shape[0], b.shape[1])),
                     inputs=[f"n_cmd{i}" for i in legs] + ["f_contact"],
                     outputs=[f"l{i}" for i in legs] + ["tool_x", "tool_y", "tool_z", "f_contact"])


def _assemble(mass: np.ndarray, damping: np.ndarray, stiffness: np.ndarray, drive_on: np.ndarray,
              contact_on: np.ndarray, ports: list[DrivePort]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """State matrix and input matrices (commands (n, legs), contact (n,)) over x = [q, q', drive states] of
    M q'' + C q' + K q = -drive_on^T N + contact_on f, N_i = c_i x_i, x_i' = a_i x_i + b_i N_cmd,i + r_i v_i with
    v = drive_on q' (the rate of the coordinate each drive pushes on)."""
    r = mass.shape[0]
    sizes = [p.a.shape[0] for p in ports]
    nd = sum(sizes)
    n = 2 * r + nd
    a = np.zeros((n, n))
    b = np.zeros((n, len(ports)))
    c_force = np.zeros((len(ports), nd))
    off = 2 * r
    for i, p in enumerate(ports):
        sl = slice(off, off + sizes[i])
        a[sl, sl] = p.a
        b[sl, i] = p.b_command
        a[sl, r:2 * r] = np.outer(p.b_rate, drive_on[i])
        c_force[i, sl.start - 2 * r:sl.stop - 2 * r] = p.c
        off += sizes[i]
    minv = np.linalg.solve(mass, np.column_stack([stiffness, damping, -drive_on.T @ c_force, contact_on]))
    a[:r, r:2 * r] = np.eye(r)
    a[r:2 * r, :r], a[r:2 * r, r:2 * r] = -minv[:, :r], -minv[:, r:2 * r]
    a[r:2 * r, 2 * r:] = minv[:, 2 * r:2 * r + nd]
    bf = np.zeros(n)
    bf[r:2 * r] = minv[:, -1]
    return a, b, bf


def _with_series(mass: np.ndarray, damping: np.ndarray, stiffness: np.ndarray, s: np.ndarray, plate: np.ndarray,
                 ports: list[DrivePort]) -> tuple[np.ndarray, ...]:
    """Add each drive's own coordinate u_i (its reflected mass, joined to the leg length l_i = s_i q by the
    series spring k_i) where the port has one: the reflected mass moves off the leg (it was its armature),
    K gains k_i (s_i q - u_i)^2 / 2; returns mass, damping, stiffness, drive_on (legs, n) (where the drives push),
    the measured lengths (legs, n) (the drive's own coordinate: a motor encoder reads u through the lead) and the
    tool rows (3, n)."""
    k = np.array([p.series_stiffness_n_per_m for p in ports])
    if np.all(np.isinf(k)):
        return mass, damping, stiffness, s, s, plate
    m_r = np.array([p.reflected_mass_kg for p in ports])
    r, legs = mass.shape[0], len(ports)
    big_m = np.zeros((r + legs, r + legs))
    big_m[:r, :r] = mass - s.T @ np.diag(m_r) @ s
    big_m[r:, r:] = np.diag(m_r)
    big_c = np.zeros((r + legs, r + legs))
    big_c[:r, :r] = damping
    coupling = np.hstack([s, -np.eye(legs)])  # l - u, (legs, r + legs)
    big_k = np.zeros((r + legs, r + legs))
    big_k[:r, :r] = stiffness
    big_k += coupling.T @ np.diag(k) @ coupling
    drive_on = np.hstack([np.zeros((legs, r)), np.eye(legs)])
    return big_m, big_c, big_k, drive_on, drive_on, np.hstack([plate, np.zeros((plate.shape[0], legs))])


def _apparent_vertical_mass(machine: Machine, pose_m: np.ndarray) -> tuple[np.ndarray, float]:
    """M_h (3, 3), kg, of the rigid-leg model at rest, gravity off (Pinocchio constraint dynamics), and
    1 / (M_h^-1)_yy."""
    inv = inverse_apparent_mass(machine, pose_m)
    return np.linalg.inv(inv), 1.0 / inv[1, 1]


def static_tensions_n(machine: Machine, pose_m: np.ndarray, preload_n: float | np.ndarray = 0.0) -> np.ndarray:
    """The drives' tensions (n,), N, holding the pose at rest as the controller commands them: -A^+ G + V a
    (G the gravity feed-forward, a = ``preload_n`` the n - 3 preload amplitudes, N: a4 v_p on the 4-UPU; a zero
    preload on any machine; PreloadError for a preload the machine cannot take,
    :func:`pressfit.mechanics.preload.self_stress_forces_n`)."""
    pose = np.asarray(pose_m, dtype=float)
    pinv, _ = distribution(kinematics.inverse_kinematics(machine, pose).unit_vectors)
    gravity = gravity_feedforward_n(rigid_leg_model(machine, pose), pose)
    return -pinv @ gravity + self_stress_forces_n(machine, pose, preload_n)


def contact_stiffness_n_per_m(machine: Machine, pose_m: np.ndarray, contact: Contact,
                              depth_m: float | None = None) -> float:
    """The contact's linearised stiffness k_c (N/m) at the tool depth ``depth_m`` (m): the local slope of the
    component's total force against the depth, its pins' laws' closed-form slopes with the tilt by the machine's
    compliance at ``pose_m`` (:func:`pressfit.mechanics.press_curve.field_stiffness`; the elastic law's k exactly).
    Without a depth only a law of constant slope (one pin on the axis, ``elastic`` or a linear ``press_fit``, no
    shoulder) is linearised; any other is refused (PressfitError)."""
    pins = PinField.from_contact(contact)
    constant = (len(pins.laws) == 1 and not pins.offsets_m.any() and isinstance(pins.laws[0], ElasticLaw)
                and pins.laws[0].fit != "saturating")
    if depth_m is None:
        if not constant:
            raise PressfitError(f"the contact law {contact.law!r} (a shoulder, a pin field or a nonlinear law) has "
                                "no single stiffness: linearise it at an operating depth (contact_depth_m)")
        depth_m = 1.0
    return field_stiffness(pins, condensed_plate_compliance(machine, np.asarray(pose_m, dtype=float)), depth_m)[1]


def linear_plant(machine: Machine, pose_m: np.ndarray, contact: Contact | None = None,
                 model: str = "flexible", tensions_n: np.ndarray | None = None,
                 contact_depth_m: float | None = None) -> Plant:
    """:class:`Plant` at the reachable pose ``pose_m`` (m); ``contact``: the contact spring engaged at the tool,
    its stiffness the law's local slope at the tool depth ``contact_depth_m`` (m; :func:`contact_stiffness_n_per_m`);
    ``tensions_n`` (n,), N: the drives' operating point (default :func:`static_tensions_n` without preload)."""
    elastic = model_kind(model).elastic
    pose = kinematics.require_reachable(machine, np.asarray(pose_m, dtype=float))
    k_c = 0.0 if contact is None else contact_stiffness_n_per_m(machine, pose, contact, contact_depth_m)
    legs = kinematics.inverse_kinematics(machine, pose)
    pinv, _ = distribution(legs.unit_vectors)
    tensions = static_tensions_n(machine, pose) if tensions_n is None else np.asarray(tensions_n, dtype=float)
    drive = drive_kinds.of(machine)
    ports = [drive.linear_port(float(length), float(n)) for length, n in zip(legs.lengths_m, tensions, strict=True)]
    m_h, m_y = _apparent_vertical_mass(machine, pose)
    if not elastic:
        s = legs.unit_vectors  # (n, 3): dl = A^T dh
        mass, damping, stiffness = m_h, np.zeros((3, 3)), np.zeros((3, 3))
        plate = np.eye(3)
    else:
        rs = reduced_system(machine, pose)
        act = np.array([sp.idx_v for sp in rs.mm.springs if sp.name == "actuator"])
        k_full = elastic_stiffness(rs.mm, rs.q)
        k_full[act, act] = 0.0  # the drives' own stiffness is their port (and an electric drive's series spring)
        basis = rs.basis
        stiffness = basis.T @ k_full @ basis
        s = basis[act]  # (n, r)
        plate = rs.plate_map[:3]
        ray = FlexibleMachine(machine, pose).damping
        damping = ray.beta_s * stiffness
        if ray.alpha_per_s:
            jac = closure_jacobian(rs.mm, rs.model, rs.data, rs.q)
            rigid = np.setdiff1d(np.arange(rs.model.nv), [sp.idx_v for sp in rs.mm.springs])
            br = jac[:, rigid]
            v_r = np.zeros((rs.model.nv, len(act)))  # rigid machine velocity per unit actuator rate (flexible module)
            v_r[act] = np.eye(len(act))
            v_r[rigid] = -np.linalg.solve(br.T @ br, br.T @ jac[:, act])
            full_mass = mass_matrix(rs.model, rs.data, rs.q)
            damping = damping + ray.alpha_per_s * basis.T @ full_mass @ (basis - v_r @ s)
        mass = rs.mass_kg
    if contact is not None:
        py = plate[1]
        stiffness = stiffness + k_c * np.outer(py, py)
        damping = damping + contact.damping_n_s_per_m * np.outer(py, py)
    mass, damping, stiffness, drive_on, s, plate = _with_series(mass, damping, stiffness, s, plate, ports)
    c_contact_z = np.zeros((2, mass.shape[0]))
    if contact is not None:
        c_contact_z = np.vstack([-k_c * plate[1], -contact.damping_n_s_per_m * plate[1]])
    a, b, bf = _assemble(mass, damping, stiffness, drive_on, plate[1], ports)
    r = mass.shape[0]
    n = a.shape[0]

    def pad(rows: np.ndarray, offset: int) -> np.ndarray:
        out = np.zeros((rows.shape[0], n))
        out[:, offset:offset + r] = rows
        return out

    c_contact = (pad(c_contact_z[:1], 0) + pad(c_contact_z[1:], r))[0]
    return Plant(model=model, pose_m=pose, in_contact=contact is not None, a=a, b_command=b, b_contact=bf,
                 c_lengths=pad(s, 0), c_rates=pad(s, r), c_tool=pad(plate, 0), c_contact=c_contact, pinv=pinv,
                 vertical_mass_kg=float(m_y), drive_kind=getattr(drive, "kind", "force"), tensions_n=tensions,
                 contact_stiffness_n_per_m=k_c, contact_depth_m=contact_depth_m)


@dataclass(frozen=True, kw_only=True)
class Loop:
    """The linearised closed loop (module doc): plant ``plant``, closed-loop state matrix ``a`` over
    [plant state, integral of the error (3)], the Cartesian loop transfer ``open_loop`` (inputs the Cartesian
    force commands W, N; outputs the PID's W, N: loop broken at the force commands, F_cmd = -A^+ W) and
    ``reference`` (reference position r (3), m -> tool position (3), m, the reference velocity fed forward)."""

    plant: Plant
    a: np.ndarray
    open_loop: ct.StateSpace
    reference: ct.StateSpace


def close_loop(plant: Plant, gains: Controller) -> Loop:
    """Figure 12's controller (unclamped) around ``plant`` (module doc)."""
    kp, kd, ki = gains.kp_n_per_m, gains.kd_n_s_per_m, gains.ki_n_per_m_s
    est = plant.pinv.T  # (3, legs): dh_est = J^+ dl
    bw = plant.b_command @ (-plant.pinv)  # (n, 3): plant input per Cartesian command
    n = plant.a.shape[0]
    h, hd = est @ plant.c_lengths, est @ plant.c_rates  # (3, n) estimate and its rate
    # open loop: state [x, int(h_est)], input W_in (3), output y = Kp h_est + Kd h_est' + Ki int(h_est); W = -y
    a_ol = np.block([[plant.a, np.zeros((n, 3))], [h, np.zeros((3, 3))]])
    b_ol = np.vstack([bw, np.zeros((3, 3))])
    c_ol = np.hstack([kp * h + kd * hd, ki * np.eye(3)])
    open_loop = ct.ss(a_ol, b_ol, c_ol, np.zeros((3, 3)), inputs=[f"w_{x}" for x in AXES],
                      outputs=[f"pid_{x}" for x in AXES])
    # closed loop: state [x, xi], xi' = r - h_est; W = Kp (r - h_est) + Kd (r' - h_est') + Ki xi
    a_cl = np.block([[plant.a - bw @ (kp * h + kd * hd), ki * bw], [-h, np.zeros((3, 3))]])
    b_r = np.vstack([kp * bw, np.eye(3)])
    b_rd = np.vstack([kd * bw, np.zeros((3, 3))])
    c_tool = np.hstack([plant.c_tool, np.zeros((3, 3))])
    # r' = s r: s C (sI - A)^-1 B_rd = C A (sI - A)^-1 B_rd + C B_rd
    reference = ct.ss(a_cl, b_r + a_cl @ b_rd, c_tool, c_tool @ b_rd, inputs=[f"r_{x}" for x in AXES],
                      outputs=[f"tool_{x}" for x in AXES])
    return Loop(plant=plant, a=a_cl, open_loop=open_loop, reference=reference)


def axis_loop(loop: Loop, axis: int) -> ct.StateSpace:
    """The SISO loop transfer of one Cartesian axis broken at its force command, the other two closed."""
    ol = loop.open_loop
    a, b, c = ol.A, ol.B, ol.C
    others = [k for k in range(3) if k != axis]
    return ct.ss(a - b[:, others] @ c[others], b[:, [axis]], c[[axis]], np.zeros((1, 1)))


@dataclass(frozen=True, kw_only=True)
class Margins:
    """Stability margins of one axis loop: gain margin (ratio; inf if none) at its phase crossover (Hz), phase
    margin (deg) at the gain crossover (Hz); ``stable``: the closed loop's poles all in the left half plane."""

    axis: str
    gain_margin: float
    phase_crossover_hz: float
    phase_margin_deg: float
    gain_crossover_hz: float


@dataclass(frozen=True)
class StructuralMode:
    """A mode of the machine with the drives holding (``pressfit modes``): frequency (Hz) and the share of its
    strain energy in the actuator springs (0..1: how much the drives move it and the encoders see it; module
    doc)."""

    frequency_hz: float
    drive_energy_fraction: float


@dataclass(frozen=True, kw_only=True)
class PoseDesign:
    """What ``pressfit control`` reports at one pose (SI; module doc)."""

    name: str
    pose_m: np.ndarray
    in_contact: bool
    model: str
    margins: tuple[Margins, ...]
    poles: np.ndarray  # (n,) closed-loop poles, 1/s (complex)
    loop_poles: np.ndarray  # (k,) bool: moved by the feedback
    bandwidth_vertical_hz: float
    bandwidth_lateral_hz: float
    stable: bool
    modes: tuple[StructuralMode, ...]
    warnings: tuple[str, ...]
    vertical_mass_kg: float
    bode_frequency_hz: np.ndarray
    bode_open_loop: np.ndarray  # (2, f) complex: vertical and lateral axis loops
    bode_reference: np.ndarray  # (2, f) complex: r_y -> tool_y, r_x -> tool_x
    contact_stiffness_n_per_m: float = 0.0  # the linearised contact's stiffness (0 out of contact), N/m
    contact_depth_m: float | None = None  # the tool depth it is taken at, m

    @property
    def pole_frequencies_hz(self) -> np.ndarray:
        return np.abs(self.poles) / (2 * math.pi)

    @property
    def pole_damping(self) -> np.ndarray:
        mag = np.abs(self.poles)
        return np.where(mag > 0, -self.poles.real / np.where(mag > 0, mag, 1.0), 1.0)

    def to_dict(self) -> dict[str, Any]:
        loop = self.loop_poles & (self.poles.imag >= 0)
        order = np.argsort(self.pole_frequencies_hz[loop])
        return {"name": self.name, "pose_m": self.pose_m, "in_contact": self.in_contact, "model": self.model,
                "stable": self.stable, "vertical_mass_kg": self.vertical_mass_kg,
                "contact_stiffness_n_per_m": self.contact_stiffness_n_per_m, "contact_depth_m": self.contact_depth_m,
                "bandwidth_vertical_hz": _finite(self.bandwidth_vertical_hz),
                "bandwidth_lateral_hz": _finite(self.bandwidth_lateral_hz),
                "margins": [{k: _finite(v) if isinstance(v, float) else v for k, v in m.__dict__.items()}
                            for m in self.margins],
                "loop_poles": [{"real_per_s": p.real, "imag_rad_per_s": p.imag, "frequency_hz": f, "damping": z}
                               for p, f, z in zip(self.poles[loop][order], self.pole_frequencies_hz[loop][order],
                                                  self.pole_damping[loop][order], strict=True)],
                "structural_modes": [m.__dict__ for m in self.modes], "warnings": list(self.warnings)}


def _finite(value: float) -> float | None:
    """JSON: a margin that does not exist (no crossover: inf or nan) is null."""
    return value if math.isfinite(value) else None


def _margins(response: ct.FrequencyResponseData, axis: str) -> Margins:
    """From the loop's frequency response (python-control interpolates the crossings; its polynomial route is
    ill-conditioned at a hundred states)."""
    gm, pm, _, wpc, wgc, _ = ct.stability_margins(response)
    return Margins(axis=axis, gain_margin=float(gm), phase_crossover_hz=float(wpc) / (2 * math.pi),
                   phase_margin_deg=float(pm), gain_crossover_hz=float(wgc) / (2 * math.pi))


def _bandwidth_hz(sys: ct.StateSpace, drop_db: float = -3.0) -> float:
    """The first frequency (Hz) where the SISO ``sys``'s gain falls ``drop_db`` below its DC gain; inf if it never
    does (or the DC gain is infinite). python-control's ``bandwidth`` to its tolerance (2e-12 rad/s; of a negative
    DC gain's magnitude, which ``bandwidth`` never finds dropped): the same
    frequency grid brackets the first crossing, then Brent's method refines it where ``bandwidth`` bisects (about
    10 evaluations instead of 40; each is a Hessenberg reduction of A by Laub's method, about 30 ms on a flexible
    loop of a few hundred states)."""
    from control.freqplot import _default_frequency_range  # the grid ct.bandwidth brackets on (version pinned)

    dc = sys.dcgain()
    if np.isinf(dc):
        return math.inf
    omega = _default_frequency_range(sys)
    mag = sys.frequency_response(omega).magnitude.reshape(-1)
    level = abs(dc) * 10 ** (drop_db / 20)
    dropped = np.flatnonzero(mag < level)  # |dc|: ct.bandwidth compares with dc, so a negative DC gain never drops
    if dropped.size == 0:
        return math.inf
    first = dropped[0]  # bracketed by the grid point before it, or by w = 0 (where the gain is |dc|)
    root = brentq(lambda w: abs(sys(w * 1j)) - level, omega[first - 1] if first else 0.0, omega[first], xtol=2e-12)
    return abs(float(root)) / (2 * math.pi)


def structural_modes(machine: Machine, pose_m: np.ndarray, count: int = MODE_COUNT) -> tuple[StructuralMode, ...]:
    """The ``count`` lowest modes, drives holding, with the modal measures of the module doc."""
    modes = natural_modes(machine, pose_m, count)
    rs = reduced_system(machine, pose_m)
    k = np.diag(elastic_stiffness(rs.mm, rs.q))
    act = np.array([sp.idx_v for sp in rs.mm.springs if sp.name == "actuator"])
    drive = np.sum(k[act] * modes.shapes[:, act] ** 2, axis=1)
    total = np.einsum("kv,v,kv->k", modes.shapes, k, modes.shapes)
    return tuple(StructuralMode(frequency_hz=float(f), drive_energy_fraction=float(d / t))
                 for f, d, t in zip(modes.frequencies_hz, drive, total, strict=True))


def proximity_warnings(poles: np.ndarray, loop_poles: np.ndarray, modes: tuple[StructuralMode, ...],
                       pose: str) -> tuple[str, ...]:
    """One line per structural mode that a loop pole (``loop_poles``: moved by the feedback) comes within
    ``WARNING_RATIO`` of in frequency, reported only when the drives see and move that mode: their share of its
    strain energy at least ``DRIVE_SHARE_THRESHOLD`` (below it the loop can neither excite nor damp the mode:
    the rocking pair's 1-2%, the twist's 0)."""
    freq = np.abs(poles) / (2 * math.pi)
    near = loop_poles & (poles.imag >= 0)
    lines = []
    for k, m in enumerate(modes):
        if m.drive_energy_fraction < DRIVE_SHARE_THRESHOLD:
            continue
        close = np.flatnonzero(near & (np.abs(freq - m.frequency_hz) <= WARNING_RATIO * m.frequency_hz))
        if close.size:
            p = close[np.argmin(np.abs(freq[close] - m.frequency_hz))]
            lines.append(f"{pose}: structural mode {k + 1} at {m.frequency_hz:.4g} Hz (drive energy share "
                         f"{m.drive_energy_fraction:.2g} >= {DRIVE_SHARE_THRESHOLD:g}) has {close.size} loop "
                         f"pole(s) within {100 * WARNING_RATIO:g}%, nearest {freq[p]:.4g} Hz (damping "
                         f"{-poles[p].real / abs(poles[p]):.3g})")
    return tuple(lines)


def design_at(machine: Machine, gains: Controller, pose_m: np.ndarray, name: str, contact: Contact | None,
              model: str = "flexible", frequencies_hz: np.ndarray | None = None,
              tensions_n: np.ndarray | None = None, contact_depth_m: float | None = None) -> PoseDesign:
    """The loop at one pose (module doc); ``tensions_n``: the drives' operating point, ``contact_depth_m`` the
    contact's (:func:`linear_plant`)."""
    plant = linear_plant(machine, pose_m, contact, model, tensions_n, contact_depth_m)
    loop = close_loop(plant, gains)
    poles = np.linalg.eigvals(loop.a)
    open_poles = np.concatenate([np.linalg.eigvals(plant.a), np.zeros(3)])
    scale = np.maximum(np.abs(poles), 1.0)
    moved = np.min(np.abs(poles[:, None] - open_poles[None, :]), axis=1) > MOVED_RELATIVE * scale
    stable = bool(np.all(poles.real < 0))
    f = np.logspace(-2, 3, FREQUENCY_POINTS) if frequencies_hz is None else frequencies_hz
    w = 2 * math.pi * f
    responses = [ct.frequency_response(axis_loop(loop, k), w) for k in (1, 0)]
    margins = (_margins(responses[0], "y"), _margins(responses[1], "x"))
    ref_y, ref_x = loop.reference[1, 1], loop.reference[0, 0]
    bode_ol = np.array([np.asarray(r.complex).reshape(-1) for r in responses])
    bode_ref = np.array([np.asarray(ct.frequency_response(s, w).complex).reshape(-1) for s in (ref_y, ref_x)])
    modes = structural_modes(machine, pose_m)
    warnings = list(proximity_warnings(poles, moved, modes, name))
    if not stable:
        worst = poles[np.argmax(poles.real)]
        warnings.insert(0, f"the closed loop is UNSTABLE: pole {worst.real:.4g} {worst.imag:+.4g}j 1/s "
                           f"({abs(worst) / (2 * math.pi):.4g} Hz)")
    return PoseDesign(name=name, pose_m=plant.pose_m, in_contact=plant.in_contact, model=model, margins=margins,
                      poles=poles, loop_poles=moved, bandwidth_vertical_hz=_bandwidth_hz(ref_y) if stable else math.nan,
                      bandwidth_lateral_hz=_bandwidth_hz(ref_x) if stable else math.nan, stable=stable, modes=modes,
                      warnings=tuple(warnings), vertical_mass_kg=plant.vertical_mass_kg, bode_frequency_hz=f,
                      bode_open_loop=bode_ol, bode_reference=bode_ref,
                      contact_stiffness_n_per_m=plant.contact_stiffness_n_per_m, contact_depth_m=plant.contact_depth_m)


@dataclass(frozen=True, kw_only=True)
class ControlDesign:
    """``pressfit control``: the loop at the pin pose (in contact) and at the case's waypoints."""

    case: str
    model: str
    poses: tuple[PoseDesign, ...]

    def to_dict(self) -> dict[str, Any]:
        return {"case": self.case, "model": self.model, "warning_ratio": WARNING_RATIO,
                "warning_drive_share": DRIVE_SHARE_THRESHOLD,
                "poses": [p.to_dict() for p in self.poses]}


def control_design(case: Case, model: str | None = None) -> ControlDesign:
    """The case's loop (``[simulation]``, ``[simulation.controller]``) linearised at the pin (contact engaged)
    and at the waypoints start, approach (above the pin) and end, on ``model`` (default: ``[simulation] model``).
    The contact is linearised where the insertion holds the tool
    (:func:`pressfit.mechanics.press_curve.operating_depth_m`: the depth where the component's force reaches the
    force limit, else the commanded interference)."""
    sim = case.simulation
    if sim is None:
        raise PressfitError(f"{case.path}: no [simulation] table: pressfit control needs the insertion scenario")
    require_model(case.path, "--model" if model else "[simulation] model", model or sim.model)
    model = model or sim.model
    machine = case.machine()
    machine.mass.require_dynamics_inertia(machine.source)
    c = sim.contact
    pin_pose = np.array([c.pin_position_m[0], c.board_height_m, c.pin_position_m[1]])
    approach = pin_pose + np.array([0.0, sim.approach_height_m, 0.0])
    poses = [("pin", pin_pose, c), ("start", np.array(sim.start_m), None), ("approach", approach, None),
             ("end", np.array(sim.end_m), None)]
    preload = ActuatorPreload.from_case(case.preload).a4
    depth = operating_depth_m(PinField.from_contact(c), condensed_plate_compliance(machine, pin_pose_m(c)),
                              sim.interference_m, sim.controller.force_limit_n)
    designs = [design_at(machine, sim.controller, p, n, con, model, tensions_n=static_tensions_n(machine, p, preload),
                         contact_depth_m=depth if con is not None else None) for n, p, con in poses]
    if sim.clearance:  # a dead zone has no linearisation at its edge: say what the loop leaves out
        designs[0] = dataclasses.replace(designs[0], warnings=(
            "linearised without the cardan plays of [simulation] clearance = true (a dead zone has no linearisation "
            "at its edge): where the preload keeps a leg in one sign its closed plays add k_c / 2 in series with it; "
            "a leg changing sign loses 2 G of position (`pressfit simulate` shows it)", *designs[0].warnings))
    return ControlDesign(case=case.name, model=model, poses=tuple(designs))
