r"""The flexible machine: the elastic VJM legs of the statics in the closed-loop equations of motion.

Model. The Pinocchio model of :mod:`pressfit.mechanics.model` (plate free flyer; per leg the base cardan, the
cylinder and stem rotational springs, springs_per_segment from the machine file, the actuator joint, the plate
cardan; one 6D frame-anchor loop closure per leg) with the ``[mass]`` table's masses and inertias
(:mod:`pressfit.dynamics.inertia`; gravity -9.81 m/s^2 along y, optional). Equations of motion (index 3):

    M(q) vdot + h(q, v) + f_s(q) + C (v_e - r_dot) - tau_d - J_p^T W + B(q)^T lambda = 0,    Phi(q) = 0,

with M vdot + h = ``pin.rnea(q, v, vdot)`` (Coriolis, centrifugal and gravity terms included), f_s the virtual
springs' forces (each spring law's ``force`` of its deflection q - rest), B the (6n, nv) Jacobian of the
closures Phi (Pinocchio's ``constraint_position_error``, log6 of the closure placement), lambda their forces,
W the plate wrench (world, at the plate centre; J_p^T W = (R^T f, R^T m) on the free flyer) and tau_d the
drives: a force drive puts -F_i (F_i > 0 tension) on actuator joint i, which then carries no spring; a position
drive sets the rest length r_i of the actuator spring (the actuator stiffness in series with the segments'
axial compliance, ``MachineModel.spring_stiffness``). The stem springs' placements and stiffnesses follow the
leg length (re-placed when a stem changed by STEM_UPDATE_M: the stiffness n E I_s / L_s then moves by at most
2e-4 relative at the shortest 50 mm stem), and so does the stem's mass: a rod of fixed length whose exposed part
is spread over the stem springs' bodies and whose inner part rides on the actuator body
(:class:`pressfit.dynamics.inertia.StemInertias`, re-written with the placements), so a state sees the weight
and inertia of the pose it stands at, not the build pose's.
Cardan contacts: ``cardan_compliance`` (:class:`pressfit.mechanics.model.CardanCompliance`, e.g. the laws of
:meth:`pressfit.mechanics.clearance.Clearance.cardan_compliance`) adds its virtual joints and laws. They are massless,
so a law must be stiff at its rest: an open play's dead zone (no stiffness there) would make the step's iteration
matrix singular and is refused (open plays belong to the scenario's ``clearance``, on the drives' side,
:mod:`pressfit.dynamics.play`).

Damping: Rayleigh, f_d = alpha M (v - v_r) + beta K (v - v_r), acting on the elastic motion only: v_r is the
velocity of the rigid machine (springs frozen) at the commanded leg rates (a position drive's rest-length
rate, a force drive's actual actuator rate at the start of the step), from the closure Jacobian's rigid
columns (least squares; the rigid closures are redundant, rank 6n - (n - 3) of 6n), so a commanded motion of the
machine is not damped; M at the end of the step, where the other forces are evaluated (one ``rnea`` gives
M (vdot + alpha (v - v_r)) + h), K the springs' tangents (zero on the cardans and the plate, and on the
actuators of force drives). With the drives holding (v_r = 0) this is classical Rayleigh
damping, zeta_k = alpha / (2 omega_k) + beta omega_k / 2, which ``kind = "modal"`` solves for (alpha, beta)
at the two named modes (the drives holding their lengths, at the build pose).

Integrator: generalised-alpha (Chung & Hulbert 1993) for index-3 constrained systems (Arnold & Bruls 2007,
"Convergence of the generalized-alpha scheme for constrained mechanical systems"), on the Lie group of the
configuration (q_{n+1} = q_n (+) dq, ``pin.integrate``). Why: the VJM springs put modes in the kHz range
(axial leg modes), far above what an explicit scheme can hold at the scenario's 1 ms step, while the modes
that matter (13-100 Hz) need second-order accuracy; generalised-alpha is unconditionally stable, second
order, and damps the unresolved high modes by a stated spectral radius ``rho_inf`` (1: trapezoidal, no
numerical damping, energy conserving for a linear system; 0.8 default: modes with omega h >> 1 lose 20%
amplitude per step, those at omega h = 0.17, the rocking mode at 1 ms, about 1e-5 per period). Parameters
alpha_m = (2 rho - 1) / (rho + 1), alpha_f = rho / (rho + 1), gamma = 1/2 + alpha_f - alpha_m,
beta = (gamma + 1/2)^2 / 4. A reduced modal basis was not chosen: over large motion the basis would have
to follow the pose, and the closures are nonlinear in the plate rotation.

Newton: the unknowns are vdot_{n+1} and lambda; the iteration matrix, in position increments dx,

    S = [ M / (beta' h^2) + gamma / (beta h) C + K,  B^T ;  B,  0 ],   beta' = beta (1 - alpha_f) / (1 - alpha_m),

is factored at a configuration and kept (modified Newton; the geometric and inertial tangents are left out:
with spring stiffnesses of 1e4-1e7 they slow convergence by a factor of about 1e-3 per iteration); it is
refactored when an iteration contracts by less than REFRESH_RATIO (once per step, or again while a drive tangent
given as a function moves by more than TANGENT_REFRESH: a cardan play crossing its contact edge,
:mod:`pressfit.dynamics.play`), and a step whose freshly factored Newton does not reach NEWTON_TOL (m and rad, the
largest position correction) in MAX_ITERATIONS since its last factoring is refused (ConvergenceError). Per
iteration one ``computeJointJacobians`` (B and Phi) and one ``rnea``; B and Phi at the end state are kept for the
closure error and the next step's rigid velocity; ``crba`` only when refactoring; the factor is applied by LAPACK
``getrs`` directly (scipy's checks cost more than the solve). A step longer than MAX_STEP_FRACTION of the first
mode's period (at the build pose, the drives holding) is refused too: the rocking mode then has fewer than 20
steps per period, its period error (omega h)^2 / 12 passes 0.8%. No finite differences: M (``crba``), the spring
tangents and B (``getConstraintsJacobian``) are Pinocchio's or analytic.

Drives in the step: a force drive model (:mod:`pressfit.dynamics.drives`) is not a held force. Its
delivered tension depends on the leg's motion over the step (a hydraulic drive's chambers compress by the
piston's travel: the oil column k_h = beta A^2 (1/V_a + 1/V_b), 3-12e6 N/m, is a spring in series with the
leg). Stepped explicitly (its tension from the rate at the start of the step, then held while the mechanics
take the step), that spring lags by a step: on a generalised-alpha step this adds negative damping of the
order of omega h / 8 to the oil-column modes, whatever the step (measured: with the valve closed, a 129 Hz
mode grows 1.9x in 0.15 s at h = 50 us, 4x at 0.1 ms, 41x at 0.25 ms; rho_inf 0.8 does not change it; the
bound omega_h dt < 2 of :func:`pressfit.dynamics.drives.hydraulic.oil_column_step_index` holds for the rigid
model's semi-implicit Euler, not here). So ``step(..., drive=)`` takes the drive as a function of the end
lengths (the drive stepped at the mean rate (l - l_n) / h, consistent with the step's own kinematics) and
evaluates it in every Newton iteration, with the drive's tangent -dN/dl (``Drive.step_stiffness_n_per_m``:
k_h for the hydraulic drive) in the iteration matrix: the oil column is then integrated like the legs'
springs, unconditionally stable (tests/dynamics/test_drive_steps.py: the closed valve's free response
reproduces the oil-column modes of the linearised machine).

Section resultants (objective, mirror-exact): ``pin.rnea`` with the closure forces as external forces on the
legs' last bodies gives the wrench each joint transmits to its subtree; the section's wrench (plate side on
base side) is its opposite, carried to the section point and written in the deformed leg frame
(:mod:`.base`; :func:`leg_frame_loads`, batched over a run). The closure force of leg i is its constraint
force lambda_i (6,) in the closure frame c1 on the leg's last body (the world wrench W_i whose generalised
forces S_k . W_i on the leg's joints are -(B^T lambda) there: tests/dynamics/test_flexible_cost.py checks it
against that least squares over the leg's twists S_k).

Initial state: :meth:`FlexibleMachine.rest_state` is the static equilibrium under gravity and a plate
wrench with the drives holding their rest lengths (Newton on [K B^T; B 0]); a state with a velocity gets
the consistent acceleration of [M B^T; B 0] with the term dB/dt v left out (exact at rest, O(|v|^2) else).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.linalg import eigh, lu_factor, null_space
from scipy.linalg.lapack import dgetrs as _getrs
from scipy.linalg.lapack import dposv as _posv

from pressfit.description.machine import Damping, Machine
from pressfit.dynamics import kernels
from pressfit.dynamics.inertia import StemInertias, inertial_model
from pressfit.dynamics.machine.base import SECTIONS, DriveInput, Energy, MachineState, SectionLoads
from pressfit.errors import ConvergenceError, PressfitError
from pressfit.mechanics import data_pool
from pressfit.mechanics.model import CardanComplianceSpec, LinearSpring, Spring, build_model

NEWTON_TOL = 1e-12  # m or rad: largest position correction of the last Newton iteration
MAX_ITERATIONS = 12  # with a freshly factored iteration matrix
REFRESH_RATIO = 0.1  # refactor when one iteration shrinks the correction by less than 10x
TANGENT_REFRESH = 0.05  # and again when a drive's tangent (a function) moved by more than this since the factoring
MAX_STEP_FRACTION = 0.05  # dt at most 1/20 of the first mode's period
DEAD_ZONE_RATIO = 1e-6  # a nonlinear spring this much softer at its rest than out of it is an open play
STEM_UPDATE_M = 1e-5  # stem placements and stiffnesses follow the leg length to this, m
RHO_INF = 0.8  # default spectral radius at infinite frequency (numerical damping)
_NO_GRAVITY = pin.Motion.Zero()
_NONE = np.empty(0)  # the linear springs' force and tangent in the Newton residual (computed there)


@dataclass(frozen=True, kw_only=True)
class Rayleigh:
    """Rayleigh coefficients of C = alpha M_e + beta K (module doc): alpha 1/s, beta s."""

    alpha_per_s: float
    beta_s: float


@dataclass(frozen=True, kw_only=True)
class FlexibleState(MachineState):
    """A state of :class:`FlexibleMachine`: besides (q, v), the true and the generalised-alpha accelerations
    (nv,), the closure forces lambda (6n,) (Pinocchio's constraint frames, N and N m), the drive input of the
    last step, the stem lengths (n,) (m) the model was placed at, and the Newton iterations of the last step."""

    acceleration: np.ndarray
    pseudo_acceleration: np.ndarray
    multipliers: np.ndarray
    drive: DriveInput
    stem_lengths_m: np.ndarray
    iterations: int = 0
    damping_work_j: float = 0.0  # the Rayleigh forces' dissipation over the last step, f_d . (q_n+1 - q_n), J


@dataclass(frozen=True, kw_only=True)
class _SectionViews:
    """Numpy views into a FlexibleMachine's Pinocchio Data and external forces (they follow every pass): the
    external forces (zero but on the plate ends) and the plate ends' entries, the closure frames' dual action
    matrices (n, 6, 6) (c1.act of a force), the section joints' rotations and translations and the subtrees'
    wrenches."""

    fext: pin.StdVec_Force
    closures: list[np.ndarray]
    closure_dual: np.ndarray
    rotations: list[np.ndarray]
    translations: list[np.ndarray]
    forces: list[np.ndarray]


@dataclass(frozen=True, kw_only=True)
class _Modes:
    frequencies_hz: np.ndarray
    shapes: np.ndarray  # (k, nv) mass-normalised


class FlexibleMachine:
    """The elastic machine's dynamics (module doc), built at a reachable start pose (m).

    ``damping``: the machine file's ``[damping]`` (default) or explicit :class:`Rayleigh` coefficients;
    ``rho_inf`` in [0, 1] the integrator's numerical damping; ``gravity`` on by default;
    ``actuator_series_n_per_m`` a stiffness in series with every actuator spring (N/m; the closed cardan plays
    of :mod:`pressfit.dynamics.play`, k_c / 2: position drives, the modes and the Rayleigh fit see it);
    ``drive_mass_on_legs`` False takes the drives' reflected mass (``drive_mass_kg``) off the actuator joints after
    the modes and the fit (which keep it: plays closed), for a caller that carries it behind the plays. Owns
    its Pinocchio
    model (stems placed per state) and data: one instance per thread.
    """

    def __init__(self, machine: Machine, pose_m: np.ndarray, *, springs_per_segment: int | None = None,
                 cardan_compliance: CardanComplianceSpec = None, damping: Damping | Rayleigh | None = None,
                 rho_inf: float = RHO_INF, gravity: bool = True, actuator_series_n_per_m: float | None = None,
                 drive_mass_on_legs: bool = True) -> None:
        if actuator_series_n_per_m is not None and not (math.isfinite(actuator_series_n_per_m)
                                                        and actuator_series_n_per_m > 0):
            raise PressfitError(f"actuator_series_n_per_m must be a positive stiffness, N/m, got "
                                f"{actuator_series_n_per_m!r}")
        self._series = actuator_series_n_per_m
        if not (isinstance(rho_inf, int | float) and 0.0 <= rho_inf <= 1.0):
            raise PressfitError(f"rho_inf must be a number in [0, 1], got {rho_inf!r}")
        self.machine, self.legs = machine, len(machine.legs)
        self.mm = mm = build_model(machine, pose_m, springs_per_segment=springs_per_segment,
                                   cardan_compliance=cardan_compliance)
        self.model = inertial_model(mm)
        if not gravity:
            self.model.gravity = pin.Motion.Zero()
        self.data = data_pool.lend(self.model)
        self._gravity = pin.Motion(self.model.gravity)  # kept (the damping force turns it off for a pass)
        self.cms = mm.constraint_models
        self.cds = mm.constraint_datas()
        self._phi = [cd.extract().constraint_position_error for cd in self.cds]  # views: follow each calc
        self.nv = self.model.nv
        sp = mm.springs
        self.sq = np.array([s.idx_q for s in sp])
        self.sv = np.array([s.idx_v for s in sp])
        self.rest0 = mm.spring_rest.copy()
        self.nonlinear = [(k, s.law) for k, s in enumerate(sp) if type(s.law) is not LinearSpring]
        _refuse_dead_zones(sp[k] for k, _ in self.nonlinear)
        self.act = np.array([k for k, s in enumerate(sp) if s.name == "actuator"])  # spring index per leg
        self.act_q, self.act_v = self.sq[self.act], self.sv[self.act]
        self.rigid = np.setdiff1d(np.arange(self.nv), self.sv)  # plate and cardan coordinates
        ids = mm.leg_joint_ids
        self.plate_end = [d["plate_end"] for d in ids]
        if [cm.extract().joint1_id for cm in self.cms] != self.plate_end:
            raise PressfitError("the loop closures must act on the legs' plate-end joints (joint1), in leg order")
        self._c1 = [cm.extract().joint1_placement for cm in self.cms]  # closure frames in the plate-end joints
        self.leg_v = [np.asarray(v) for v in mm.leg_v]
        # (joint whose subtree is the plate side, joint carrying the point, z offset) per leg and section
        sec = [(j if z == 0.0 else j + 1, j, z) for i in range(self.legs)
               for j, z in (mm.sections[i][s] for s in SECTIONS)]
        joints = sorted({j for t in sec for j in t[:2]})
        self._sec_joints = (joints, [t[0] for t in sec])
        self._sec_sub = np.array([joints.index(t[0]) for t in sec])
        self._sec_j = np.array([joints.index(t[1]) for t in sec])
        self._sec_z = np.array([t[2] for t in sec])
        self.alpha_m, self.alpha_f, self.gamma, self.beta = generalized_alpha(rho_inf)
        self.rho_inf = float(rho_inf)
        self._placed = np.full(self.legs, np.nan)
        self._stems = StemInertias(mm)
        self._stem_translations = mm.stem_translations(self.model)
        self._placed_key = b""
        self._closure_key: bytes | None = None  # the q (bytes) of ``_closure`` (B, Phi), None: stale
        self._closure: tuple = ()
        self._lower = np.tri(self.nv, k=-1, dtype=bool)
        self._k = np.zeros(len(sp))
        stem0 = mm.pose_values(mm.pose_m).stem_lengths_m
        self._place(stem0)
        self.q0 = mm.q0.copy()
        damping = machine.damping if damping is None else damping
        count = max(damping.fit_modes) if isinstance(damping, Damping) else 1
        self.modes = self._modes(self.q0, count)
        self.first_period_s = 1.0 / float(self.modes.frequencies_hz[0])
        self.damping = damping if isinstance(damping, Rayleigh) else self._fit(damping)
        self.drive_mass_kg = 0.0  # the drives' reflected mass taken off the legs, kg (carried by the caller)
        if not drive_mass_on_legs:  # after the modes and the fit, which see it on the legs (plays closed)
            self.drive_mass_kg = float(machine.drive_reflected_mass_kg)
            armature = np.array(self.model.armature)
            armature[self.act_v] -= self.drive_mass_kg
            self.model.armature = armature
        self.refreshes = 0  # iteration-matrix factorisations so far (a diagnostic)
        self._factor: tuple | None = None
        self._factor_key: tuple | None = None
        self._views: _SectionViews | None = None  # section_state's, made at its first call
        self._drive_k = np.zeros(len(self.act))  # implicit force drives' tangent -dN/dl in the iteration matrix, N/m
        self._drive_tangent: Callable[[], np.ndarray] | None = None
        self._contact_k, self._contact_dir = 0.0, np.zeros(3)  # an implicit contact's tangent (N/m) and R^T e_y
        self._energy: tuple | None = None  # (the last state's key, its Energy)

    # --- model -----------------------------------------------------------------------------------
    def _place(self, stem_lengths_m: np.ndarray) -> None:
        """Stem placements and the pose-dependent stiffnesses (actuator, stem) for stem lengths (n,), m."""
        key = np.asarray(stem_lengths_m, dtype=float).tobytes()
        if key == self._placed_key:
            return
        self._placed_key = key
        self.mm.place_stem(self.model, stem_lengths_m, self._stem_translations)
        self._stems.write(self.model, stem_lengths_m)
        self._closure_key = None
        self._k = self.mm.spring_stiffness(stem_lengths_m + self.machine.cylinder.length_m)
        if self._series is not None:  # a stiffness in series with each actuator spring (closed cardan plays)
            self._k[self.act] = 1.0 / (1.0 / self._k[self.act] + 1.0 / self._series)
        self._placed = np.array(stem_lengths_m, dtype=float)

    def _rest(self, drive: DriveInput) -> tuple[np.ndarray, np.ndarray]:
        """Rest values of the springs and their stiffness (0 on the actuators of force drives)."""
        if drive.values.shape != (self.legs,):
            raise PressfitError(f"drive input ({drive.kind}) must be one value per leg ({self.legs}), got "
                                f"{drive.values.size}")
        rest, k = self.rest0.copy(), self._k.copy()
        if drive.kind == "position":
            rest[self.act] = drive.values
        else:
            k[self.act] = 0.0
        return rest, k

    def _springs(self, q: np.ndarray, rest: np.ndarray, k: np.ndarray,
                 drive: DriveInput) -> tuple[np.ndarray, np.ndarray]:
        """Spring forces and tangents (n_springs,) at q."""
        x = q[self.sq] - rest
        f, kt = k * x, k.copy()
        for j, law in self.nonlinear:
            f[j], kt[j] = float(law.force(x[j])), float(law.tangent(x[j]))
        if drive.kind == "force":
            f[self.act], kt[self.act] = 0.0, 0.0
        return f, kt

    def _jacobian(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closure Jacobian B (6n, nv) and error Phi (6n,) at q; the last q's are kept (a step's end state is
        asked for them again by the closure error, the section loads and the next step's rigid velocity)."""
        key = q.tobytes()
        if key == self._closure_key:
            return self._closure
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        b = np.empty((6 * self.legs, self.nv))  # a new array: a caller may still hold the last one
        for i, (cm, cd) in enumerate(zip(self.cms, self.cds)):  # one closure at a time: 1.6x getConstraintsJacobian
            cm.calc(model, data, cd)
            b[6 * i:6 * i + 6] = pin.getConstraintJacobian(model, data, cm, cd)
        phi = np.concatenate(self._phi)
        self._closure, self._closure_key = (b, phi), key
        return b, phi

    def _mass(self, q: np.ndarray) -> np.ndarray:
        """M(q) (nv, nv), kg and kg m^2 (``crba`` fills the upper triangle)."""
        m = np.array(pin.crba(self.model, self.data, q, pin.Convention.WORLD))
        np.copyto(m, m.T, where=self._lower)
        return m

    def _modes(self, q: np.ndarray, count: int) -> _Modes:
        """The lowest modes at q with the drives holding their lengths (the model's actuator springs)."""
        b, _ = self._jacobian(q)
        basis = null_space(b)
        kd = np.zeros(self.nv)
        np.add.at(kd, self.sv, self._springs(q, self.rest0, self._k, DriveInput.positions(q[self.act_q]))[1])
        mass = self._mass(q)
        w2, x = eigh(basis.T @ (kd[:, None] * basis), basis.T @ mass @ basis, subset_by_index=[0, count - 1])
        if w2[0] <= 0:
            raise PressfitError(f"the flexible machine has a mechanism at pose {tuple(self.mm.pose_m.tolist())} m "
                                f"(lowest eigenvalue {w2[0]:.3g} s^-2)")
        return _Modes(frequencies_hz=np.sqrt(w2) / (2 * np.pi), shapes=(basis @ x).T)

    def _fit(self, damping: Damping) -> Rayleigh:
        """Rayleigh coefficients for modal ratios at two modes (module doc); refused if one comes out negative."""
        if damping.kind == "rayleigh":
            return Rayleigh(alpha_per_s=float(damping.alpha_per_s), beta_s=float(damping.beta_s))
        k = [m - 1 for m in damping.fit_modes]
        w = 2 * np.pi * self.modes.frequencies_hz[k]
        a = np.column_stack([1 / (2 * w), w / 2])
        alpha, beta = np.linalg.solve(a, np.asarray(damping.fit_ratios, dtype=float))
        if alpha < 0 or beta < 0 or not (math.isfinite(alpha) and math.isfinite(beta)):
            raise PressfitError(f"damping ratios {damping.fit_ratios} at modes {damping.fit_modes} "
                                f"({w[0] / 2 / np.pi:.4g} and {w[1] / 2 / np.pi:.4g} Hz) need a negative Rayleigh "
                                f"coefficient (alpha {alpha:.3g} 1/s, beta {beta:.3g} s): choose other modes or ratios")
        return Rayleigh(alpha_per_s=float(alpha), beta_s=float(beta))

    def modal_damping_ratios(self) -> np.ndarray:
        """The Rayleigh damping's ratio at each computed mode (module doc), dimensionless."""
        w = 2 * np.pi * self.modes.frequencies_hz
        return self.damping.alpha_per_s / (2 * w) + self.damping.beta_s * w / 2

    # --- states ------------------------------------------------------------------------------------
    def rest_state(self, plate_wrench: np.ndarray | None = None, drive: DriveInput | None = None,
                   tol: float = NEWTON_TOL, max_iter: int = 30, pose_m: np.ndarray | None = None) -> FlexibleState:
        """Static equilibrium at the build pose (or at the reachable ``pose_m``, m: the stems placed, stiffened and
        weighed there) under gravity and a plate wrench (6,) (N, N m; default none) with position drives at
        ``drive`` (default: the rigid leg lengths of the pose); v = 0."""
        q_start = self.q0 if pose_m is None else self.mm.pose_values(pose_m).q0
        drive = DriveInput.positions(q_start[self.act_q]) if drive is None else drive
        if drive.kind != "position":
            raise PressfitError("a rest state needs position drives: force drives hold no pose")
        self._place(q_start[self.act_q] - self.machine.cylinder.length_m)
        wrench = _wrench(plate_wrench)
        rest, k = self._rest(drive)
        q, lam, nv, nc = q_start.copy(), np.zeros(6 * self.legs), self.nv, 6 * self.legs
        zero = np.zeros(nv)
        for it in range(1, max_iter + 1):  # noqa: B007 (the count is reported)
            b, phi = self._jacobian(q)
            f, kt = self._springs(q, rest, k, drive)
            r = np.array(pin.rnea(self.model, self.data, q, zero, zero)) + b.T @ lam - self._external(q, wrench, drive)
            r[self.sv] += f
            kkt = np.zeros((nv + nc, nv + nc))
            kkt[self.sv, self.sv] = kt
            kkt[:nv, nv:], kkt[nv:, :nv] = b.T, b
            dx = np.linalg.solve(kkt, -np.concatenate([r, phi]))
            q = pin.integrate(self.model, q, dx[:nv])
            lam = lam + dx[nv:]
            if np.max(np.abs(dx[:nv])) <= tol:
                break
        else:
            raise ConvergenceError("flexible rest state (Newton)", float(np.max(np.abs(dx[:nv]))), tol, max_iter)
        return self._consistent(FlexibleState(time_s=0.0, q=q, v=zero.copy(), acceleration=zero.copy(),
                                              pseudo_acceleration=zero.copy(), multipliers=lam, drive=drive,
                                              stem_lengths_m=self._placed.copy(), iterations=it), wrench)

    def with_velocity(self, state: FlexibleState, v: np.ndarray, plate_wrench: np.ndarray | None = None
                      ) -> FlexibleState:
        """``state`` with velocity v (nv,) and the consistent acceleration (module doc)."""
        v = np.asarray(v, dtype=float)
        if v.shape != (self.nv,) or not np.all(np.isfinite(v)):
            raise PressfitError(f"velocity must be {self.nv} finite numbers")
        s = dataclasses.replace(state, v=v, damping_work_j=0.0)
        return self._consistent(s, _wrench(plate_wrench))

    def _consistent(self, s: FlexibleState, wrench: np.ndarray) -> FlexibleState:
        self._place(s.stem_lengths_m)
        rest, k = self._rest(s.drive)
        b, _ = self._jacobian(s.q)
        f, kt = self._springs(s.q, rest, k, s.drive)
        nv, mass = self.nv, self._mass(s.q)
        rhs = self._external(s.q, wrench, s.drive) - np.array(pin.nonLinearEffects(self.model, self.data, s.q, s.v))
        rhs[self.sv] -= f
        rhs -= self._damping_terms(s.v, np.zeros(nv), kt, mass if self.damping.alpha_per_s else None)
        nc = 6 * self.legs
        kkt = np.zeros((nv + nc, nv + nc))
        kkt[:nv, :nv], kkt[:nv, nv:], kkt[nv:, :nv] = mass, b.T, b
        sol = np.linalg.lstsq(kkt, np.concatenate([rhs, np.zeros(nc)]), rcond=None)[0]
        acc = sol[:nv]
        return FlexibleState(time_s=s.time_s, q=s.q, v=s.v, acceleration=acc, pseudo_acceleration=acc.copy(),
                             multipliers=sol[nv:], drive=s.drive, stem_lengths_m=s.stem_lengths_m,
                             iterations=s.iterations)

    def _external(self, q: np.ndarray, wrench: np.ndarray, drive: DriveInput) -> np.ndarray:
        """Generalised forces (nv,) of the plate wrench and of force drives."""
        tau = np.zeros(self.nv)
        if wrench.any():
            rot = pin.Quaternion(q[3:7]).matrix()
            tau[0:3], tau[3:6] = rot.T @ wrench[:3], rot.T @ wrench[3:]
        if drive.kind == "force":
            tau[self.act_v] -= drive.values
        return tau

    # --- the step ------------------------------------------------------------------------------------
    def step(self, state: FlexibleState, drive_input: DriveInput, plate_wrench: np.ndarray | None, dt_s: float,
             drive: Callable[[np.ndarray], np.ndarray] | None = None,
             drive_stiffness_n_per_m: np.ndarray | Callable[[], np.ndarray] | None = None,
             contact: Callable[[float], tuple[float, float]] | None = None) -> FlexibleState:
        """One generalised-alpha step of ``dt_s`` (s) (module doc); the drive input and the plate wrench (6,) (N, N m,
        world, plate centre; None: none) are held over the step. With force drives, ``drive`` (optional) gives the
        delivered tensions (n,), N, as a function of the actuator lengths (n,), m, at the step's end (a drive model
        stepped over the step at the mean rate they make): it is evaluated at every Newton iteration, so the drive's own
        stiffness (an oil column) is implicit in the step like the legs' springs (module doc, "Drives in the step");
        ``drive_stiffness_n_per_m`` (n,) its tangent -dN/dl for the iteration matrix (default 0; an approximate tangent
        only slows the modified Newton), or a function giving it where ``drive``'s last call left it (asked again at
        each refactoring: a cardan play's tangent changes across its contact edge). ``contact`` (optional): the force on
        the tool along world +y (N) and its stiffness -dF/dy (N/m) at the plate centre's world y (m), evaluated at every
        iteration like ``drive`` (implicit; added to the plate wrench at the start's orientation). The state records the
        tensions of the last iterate (``drive``'s last call). Refuses (PressfitError) a step longer than
        MAX_STEP_FRACTION of the first mode's period or one whose Newton does not converge."""
        h = self._step_length(dt_s)
        wrench = _wrench(plate_wrench)
        stem = self.stems_for(state)
        self._place(stem)
        rest, k = self._rest(drive_input)
        rest_prev, _ = self._rest(state.drive) if state.drive.kind == drive_input.kind else (rest, k)
        rates = (rest - rest_prev)[self.act] / h if drive_input.kind == "position" else state.v[self.act_v]
        am, af, g, b = self.alpha_m, self.alpha_f, self.gamma, self.beta
        ca = (1 - af) / (1 - am)
        q_n, v_n, acc_n, a_n = state.q, state.v, state.acceleration, state.pseudo_acceleration
        base_dq = h * v_n + h * h * (0.5 - b) * a_n
        base_v = v_n + h * (1 - g) * a_n
        v_r = self._rigid_velocity(q_n, rates) if rates.any() else np.zeros(self.nv)
        key = (h, drive_input.kind, self._placed.tobytes())
        implicit = drive is not None and drive_input.kind == "force"
        self._set_drive_tangent(drive_stiffness_n_per_m if implicit else None)
        tau_ext = self._external(q_n, wrench, drive_input)
        tension, held = drive_input.values, tau_ext[self.act_v] + drive_input.values  # without the drives
        plate, k_contact = tau_ext[0:3].copy(), self._start_contact(contact, q_n)  # the wrench without the contact
        fresh = self._factor is None or self._factor_key[:2] != key[:2]
        if fresh:
            self._contact_k = k_contact
            self._refresh(q_n, k, drive_input, rest, h)
        acc, lam = acc_n.copy(), state.multipliers.copy()
        nv, sv, last, it, since = self.nv, self.sv, np.inf, 0, 0  # since: iterations since the last factoring
        scale, c_acc, c_old = 1.0 / (h * h * b * ca), (1 - af) / (1 - am), (af * acc_n - am * a_n) / (1 - am)
        rhs, (dq, v, rel, acc_eff) = np.empty(nv + 6 * self.legs), np.empty((4, nv))
        alpha, beta, hhb, hg = self.damping.alpha_per_s, self.damping.beta_s, h * h * b, h * g
        while True:  # rnea at acc + alpha (v - v_r): the inertia and the mass-proportional damping in one pass
            kernels.newton_predict(acc, c_acc, c_old, base_dq, hhb, base_v, hg, v_r, alpha, dq, v, rel, acc_eff)
            q = pin.integrate(self.model, q_n, dq)
            bj, phi = self._jacobian(q)
            if implicit:
                tension = drive(q[self.act_q])
                tau_ext[self.act_v] = held - tension
            if contact is not None:
                force_c, k_contact = contact(float(q[1]))
                tau_ext[0:3] = plate + self._contact_dir * force_c
            f, kt = self._springs(q, rest, k, drive_input) if self.nonlinear else (_NONE, _NONE)
            kernels.newton_residual(pin.rnea(self.model, self.data, q, v, acc_eff), bj.T @ lam, tau_ext, q, self.sq,
                                    sv, rest, k, f, kt, not self.nonlinear, rel, beta, phi, rhs)
            size = kernels.newton_update(self._solve(rhs), nv, scale, acc, lam)  # |dq|_inf, m or rad
            it += 1
            if size <= NEWTON_TOL:
                break
            if size > REFRESH_RATIO * last and (not fresh or self._tangents_moved(k_contact)):
                if self._drive_tangent is not None:  # the drive's tangent where its last call left it
                    self._drive_k = np.asarray(self._drive_tangent(), dtype=float)
                self._contact_k = k_contact
                self._refresh(q, k, drive_input, rest, h)
                fresh, last, since = True, np.inf, 0
                continue
            since += 1
            _refuse_iteration(state.time_s + h, size, it, since, fresh)
            last = size
        # the drive at the last iterate: within drive_stiffness * NEWTON_TOL (~1e-5 N) of the end's
        held = DriveInput.forces(tension) if implicit else drive_input
        return self._end_state(state, h, acc, lam, (base_dq, base_v, v_r), rest, k, drive_input, held, it)

    def _end_state(self, state: FlexibleState, h: float, acc: np.ndarray, lam: np.ndarray, base: tuple,
                   rest: np.ndarray, k: np.ndarray, drive: DriveInput, held: DriveInput,
                   iterations: int) -> FlexibleState:
        """The state at the end of :meth:`step` from its converged accelerations ``acc`` and multipliers ``lam``
        (``base``: the step's predictor of the position increment and the velocity, and the rigid velocity v_r);
        the damping's work over the step under the drive input ``drive``; ``held``: the input the state records."""
        base_dq, base_v, v_r = base
        a_ps, dq, v = np.empty((3, self.nv))
        kernels.newton_end(acc, state.acceleration, state.pseudo_acceleration, self.alpha_f, self.alpha_m, base_dq,
                           h * h * self.beta, base_v, h * self.gamma, a_ps, dq, v)
        q = pin.integrate(self.model, state.q, dq)
        work = float(self._damping_force(q, v - v_r, rest, k, drive) @ pin.difference(self.model, state.q, q))
        return FlexibleState(time_s=state.time_s + h, q=q, v=v, acceleration=acc, pseudo_acceleration=a_ps,
                             multipliers=lam, drive=held, stem_lengths_m=self._placed.copy(), iterations=iterations,
                             damping_work_j=work)

    def _step_length(self, dt_s: float) -> float:
        """``dt_s`` as a float, refused (PressfitError) outside (0, MAX_STEP_FRACTION of the first period]."""
        h = float(dt_s)
        if not (math.isfinite(h) and 0.0 < h <= MAX_STEP_FRACTION * self.first_period_s):
            bound = MAX_STEP_FRACTION * self.first_period_s
            raise PressfitError(f"time step {dt_s!r} s is outside (0, {bound:.4g}] s: at most {MAX_STEP_FRACTION:g} "
                                f"of the first mode's period ({1e3 * self.first_period_s:.4g} ms, "
                                f"{self.modes.frequencies_hz[0]:.4g} Hz)")
        return h

    def _set_drive_tangent(self, stiffness: np.ndarray | Callable[[], np.ndarray] | None) -> None:
        """The implicit drives' tangent -dN/dl (n,) for the iteration matrix: 0 without (None), or a function asked
        again at each refactoring (:meth:`step`'s ``drive_stiffness_n_per_m``)."""
        self._drive_tangent = stiffness if callable(stiffness) else None
        self._drive_k = np.zeros(len(self.act)) if stiffness is None else \
            np.asarray(stiffness() if self._drive_tangent else stiffness, dtype=float)

    def _start_contact(self, contact: Callable[[float], tuple[float, float]] | None, q_n: np.ndarray) -> float:
        """An implicit contact's direction R^T e_y at the step's start (a world +y force on the free flyer's local
        translation) and its stiffness there (N/m; 0 without a contact; ``_contact_k`` stays the factored one)."""
        if contact is None:
            return 0.0
        self._contact_dir = pin.Quaternion(q_n[3:7]).matrix()[1].copy()
        return contact(float(q_n[1]))[1]

    def _tangents_moved(self, contact_k: float) -> bool:
        """Whether the contact's tangent ``contact_k`` (N/m) or a drive's moved by more than TANGENT_REFRESH of the
        factored one."""
        scale = max(abs(contact_k), abs(self._contact_k))
        return abs(contact_k - self._contact_k) > TANGENT_REFRESH * scale or self._drive_tangent_moved()

    def _drive_tangent_moved(self) -> bool:
        """Whether a drive tangent given as a function moved by more than TANGENT_REFRESH of the factored one
        (a play crossed its contact edge within the step: the factored matrix then converges too slowly)."""
        if self._drive_tangent is None:
            return False
        now = np.asarray(self._drive_tangent(), dtype=float)
        scale = np.maximum(np.abs(now), np.abs(self._drive_k))
        return bool(np.any(np.abs(now - self._drive_k) > TANGENT_REFRESH * scale))

    def _damping_force(self, q: np.ndarray, rel: np.ndarray, rest: np.ndarray, k: np.ndarray,
                       drive_input: DriveInput) -> np.ndarray:
        """The Rayleigh force alpha M (v - v_r) + beta K (v - v_r) (nv,) at the end of a step (``rel`` = v - v_r),
        for the damping's work over the step: M rel by Pinocchio's rnea at zero velocity with the gravity off."""
        alpha, beta = self.damping.alpha_per_s, self.damping.beta_s
        force = np.zeros(self.nv)
        if alpha:  # M rel: rnea at zero velocity with the gravity off
            model, gravity = self.model, self._gravity
            model.gravity = _NO_GRAVITY
            try:
                force += alpha * pin.rnea(model, self.data, q, np.zeros(self.nv), rel)
            finally:
                model.gravity = gravity
        if beta:
            kt = self._springs(q, rest, k, drive_input)[1] if self.nonlinear else k
            force[self.sv] += beta * kt * rel[self.sv]
        return force

    def _solve(self, rhs: np.ndarray) -> np.ndarray:
        """The iteration matrix's factor applied to rhs (LAPACK getrs, without scipy's per-call checks)."""
        x, info = _getrs(*self._factor, rhs)
        if info:
            raise PressfitError(f"iteration-matrix solve failed (LAPACK getrs info {info})")
        return x

    def _damping_terms(self, v: np.ndarray, v_r: np.ndarray, kt: np.ndarray, mass: np.ndarray | None
                       ) -> np.ndarray:
        """Rayleigh forces (nv,) on the elastic motion v - v_r (module doc); ``mass`` None when alpha = 0."""
        d, rel = self.damping, v - v_r
        out = np.zeros(self.nv)
        out[self.sv] = d.beta_s * kt * rel[self.sv]
        if mass is not None:
            out += d.alpha_per_s * (mass @ rel)
        return out

    def _rigid_velocity(self, q: np.ndarray, rates: np.ndarray) -> np.ndarray:
        """Velocity (nv,) of the rigid machine (springs frozen) at q with actuator rates (n,) (m/s)."""
        b, _ = self._jacobian(q)
        br = b[:, self.rigid]  # full column rank: with fixed lengths the rigid machine has no mechanism
        v = np.zeros(self.nv)
        v[self.act_v] = rates
        c, x, info = _posv(br.T @ br, br.T @ (b[:, self.act_v] @ rates))
        if info:
            raise PressfitError(f"the rigid machine's closure Jacobian is rank deficient (LAPACK posv info {info})")
        v[self.rigid] = -x
        return v

    def _refresh(self, q: np.ndarray, k: np.ndarray, drive: DriveInput, rest: np.ndarray, h: float) -> None:
        """Factor the iteration matrix (module doc) at q."""
        nv, b, g = self.nv, self.beta, self.gamma
        ca = (1 - self.alpha_f) / (1 - self.alpha_m)
        bj, _ = self._jacobian(q)
        _, kt = self._springs(q, rest, k, drive)
        s = np.zeros((nv + 6 * self.legs, nv + 6 * self.legs))
        s[:nv, :nv] = (1 / (b * ca * h * h) + g / (b * h) * self.damping.alpha_per_s) * self._mass(q)
        s[self.sv, self.sv] += (1 + g / (b * h) * self.damping.beta_s) * kt
        s[self.act_v, self.act_v] += self._drive_k  # an implicit force drive's tangent (step)
        s[:3, :3] += self._contact_k * np.outer(self._contact_dir, self._contact_dir)  # an implicit contact's
        s[:nv, nv:], s[nv:, :nv] = bj.T, bj
        self._factor = lu_factor(s, check_finite=False, overwrite_a=True)
        self.refreshes += 1
        self._factor_key = (h, drive.kind, self._placed.tobytes())

    # --- what a designer reads -------------------------------------------------------------------------
    def plate_pose(self, state: MachineState) -> tuple[np.ndarray, np.ndarray]:
        return state.q[0:3].copy(), pin.Quaternion(state.q[3:7]).matrix()

    def tool_point_m(self, state: MachineState) -> np.ndarray:
        """The tool tip: the plate centre (the ``[mass]`` table lumps the tool there), m."""
        return state.q[0:3].copy()

    def leg_lengths_m(self, state: MachineState) -> np.ndarray:
        return state.q[self.act_q].copy()

    def leg_rates_m_per_s(self, state: MachineState) -> np.ndarray:
        return state.v[self.act_v].copy()

    def closure_error(self, state: MachineState) -> tuple[float, float]:
        self._place(getattr(state, "stem_lengths_m", self._placed))
        return kernels.closure_gaps(self._jacobian(state.q)[1])

    def stems_for(self, state: FlexibleState) -> np.ndarray:
        """The stem lengths (n,), m, the next step from ``state`` places the stems at: the state's, or its leg
        lengths less the cylinders' where a stem changed by more than STEM_UPDATE_M (module doc)."""
        stem = state.stem_lengths_m
        exposed = state.q[self.act_q] - self.machine.cylinder.length_m
        return exposed if kernels.moved(exposed, stem, STEM_UPDATE_M) else stem

    def replacement_energy_j(self, state: FlexibleState) -> float:
        """The change of the machine's energy (kinetic + elastic + potential, J) when the next step from ``state``
        re-places the stems (:meth:`stems_for`) at the state's q and v: the stems' bodies and spring stiffnesses
        move to the new lengths in one jump that no force works on (0 without a re-placement). The energy
        balance (:func:`pressfit.dynamics.sizing.energy_balance`) gives it back: a step-independent term of the
        model's stem placement, not integrator error. A stem is a rod of fixed mass, so only the exposed stem's
        stiffness jumps: 8.3e-5 J on the shipped clearance insertion (33.8 J gross drive work)."""
        stem = self.stems_for(state)
        if stem is state.stem_lengths_m:
            return 0.0
        before = self.energy(state).total_j
        return self.energy(dataclasses.replace(state, stem_lengths_m=stem)).total_j - before

    def energy(self, state: FlexibleState) -> Energy:
        key = _energy_key(state)
        if self._energy is not None and self._energy[0] == key:  # a state asked again (the series, the re-placement)
            return self._energy[1]
        self._energy = (key, self._energy_of(state))
        return self._energy[1]

    def _energy_of(self, state: FlexibleState, kinematics: bool = False) -> Energy:
        """The state's energies; ``kinematics``: the Data already holds its placements and joint velocities (a
        forward kinematics at q and an rnea at (q, v) just made: the same arithmetic as the energy's own pass)."""
        self._place(state.stem_lengths_m)
        rest, k = self._rest(state.drive)
        x = state.q[self.sq] - rest
        e = 0.5 * k * x * x
        for j, law in self.nonlinear:
            e[j] = float(law.energy(x[j]))
        if state.drive.kind == "force":
            e[self.act] = 0.0
        if kinematics:
            pin.computeMechanicalEnergy(self.model, self.data)
        else:
            pin.computeMechanicalEnergy(self.model, self.data, state.q, state.v)  # one pass for both
        return Energy(kinetic_j=float(self.data.kinetic_energy), elastic_j=float(e.sum()),
                      potential_j=float(self.data.potential_energy))

    def closure_wrenches(self, state: FlexibleState) -> np.ndarray:
        """(n, 6) the world wrench (force N, moment about the world origin N m) the plate exerts on each leg's
        last body through its closure (module doc)."""
        self._place(state.stem_lengths_m)
        self._jacobian(state.q)  # the closure frames c1 at q
        lam = state.multipliers.reshape(self.legs, 6)
        return np.array([cd.extract().oMc1.act(pin.Force(lam[i])).vector for i, cd in enumerate(self.cds)])

    def section_state(self, state: FlexibleState) -> tuple[np.ndarray, np.ndarray]:
        """What the section resultants need of a state (the Pinocchio part; :meth:`section_wrenches_from` the
        rest, batched): the placements (n, 3, 4) (rotation | translation, m) of the joints involved and the
        wrench (3n, 6) (force N, moment N m; local) each section's plate-side subtree receives from its parent.
        The state's energies (:meth:`energy`) are kept from the same passes."""
        self._place(state.stem_lengths_m)
        views = self._views if self._views is not None else self._section_views()
        loads = np.einsum("lij,lj->li", views.closure_dual, state.multipliers.reshape(self.legs, 6))  # c1.act(lambda)
        for view, load in zip(views.closures, loads):  # the closure forces, in the plate-end joints' frames
            view[:] = load
        pin.forwardKinematics(self.model, self.data, state.q)  # oMi: Pinocchio's rnea leaves them as they were
        pin.rnea(self.model, self.data, state.q, state.v, state.acceleration, views.fext)
        self._energy = (_energy_key(state), self._energy_of(state, kinematics=True))  # the placements, rnea's v
        placements = np.empty((len(views.rotations), 3, 4))
        placements[:, :, :3], placements[:, :, 3] = np.array(views.rotations), np.array(views.translations)
        return placements, np.array(views.forces)

    def _section_views(self) -> _SectionViews:
        """:meth:`section_state`'s views into the Data (read, or written, in place: no Pinocchio object a step)."""
        fext = pin.StdVec_Force()
        for _ in range(self.model.njoints):
            fext.append(pin.Force.Zero())
        omi, f_sub = self.data.oMi, self.data.f
        joints, subs = self._sec_joints
        self._views = _SectionViews(fext=fext, closures=[fext[j].vector for j in self.plate_end],
                                    closure_dual=np.array([c1.toDualActionMatrix() for c1 in self._c1]),
                                    rotations=[omi[j].rotation for j in joints],
                                    translations=[omi[j].translation for j in joints],
                                    forces=[f_sub[j].vector for j in subs])
        return self._views

    def section_wrenches_from(self, placements: np.ndarray, wrenches: np.ndarray) -> np.ndarray:
        """(..., n, 3, 9) per leg and section (module doc): the section point (m), the force (N) and the moment
        about the point (N m) of the plate side on the base side, world axes, from :meth:`section_state`'s
        arrays (..., m, 3, 4) and (..., 3n, 6); batched."""
        hj, hs = placements[..., self._sec_j, :, :], placements[..., self._sec_sub, :, :]
        pts = hj[..., :, 3] + hj[..., :, 2] * self._sec_z[:, None]  # the section points
        force = -np.einsum("...sij,...sj->...si", hs[..., :3], wrenches[..., :3])  # plate side on base side
        moment = _cross(hs[..., :, 3] - pts, force) - np.einsum("...sij,...sj->...si", hs[..., :3], wrenches[..., 3:])
        out = np.concatenate([pts, force, moment], axis=-1)
        return out.reshape(*out.shape[:-2], self.legs, 3, 9)

    def section_wrenches(self, state: FlexibleState) -> np.ndarray:
        """(n, 3, 9) the section wrenches of one state (:meth:`section_wrenches_from`); :func:`leg_frame_loads`
        writes them in the leg frames."""
        return self.section_wrenches_from(*self.section_state(state))

    def section_loads(self, state: FlexibleState) -> SectionLoads:
        """Leg section resultants at the three sections (module doc, :mod:`.base`)."""
        values, frames = leg_frame_loads(self.section_wrenches(state), self.machine.cardan_axes)
        return SectionLoads(values, frames)


def _energy_key(state: FlexibleState) -> tuple:
    """What a state's energies depend on (:meth:`FlexibleMachine.energy`'s cache)."""
    return (state.q.tobytes(), state.v.tobytes(), state.stem_lengths_m.tobytes(), state.drive.kind,
            state.drive.values.tobytes())


def _refuse_dead_zones(springs: Iterable[Spring]) -> None:
    """PressfitError for a nonlinear spring with no stiffness at its rest (a cardan play's open dead zone: its tangent
    there below DEAD_ZONE_RATIO of its largest within 1e-7..1e-2 of it): the play joints are massless, so the step's
    iteration matrix would be singular there (each step refused as diverged)."""
    probe = np.concatenate([-np.logspace(-7, -2, 11), np.logspace(-7, -2, 11)])
    for spring in springs:
        at_rest, out = float(spring.law.tangent(0.0)), max(float(spring.law.tangent(x)) for x in probe)
        if not at_rest > DEAD_ZONE_RATIO * out:
            raise PressfitError(
                f"cardan_compliance: leg {spring.leg + 1}'s {spring.name} law has no stiffness at its rest (tangent "
                f"{at_rest:.3g} against {out:.3g} out of it: an open play's dead zone); the flexible machine's play "
                "joints are massless, so its step cannot integrate them -- model open cardan plays with the "
                "scenario's [simulation] clearance (on the drives' side), or give the law its contact closed")


def _refuse_iteration(time_s: float, size: float, iterations: int, since: int, fresh: bool) -> None:
    """ConvergenceError for the step ending at ``time_s`` (s) when its Newton diverged (a correction ``size`` that
    is not finite), when a freshly factored Newton has not converged in MAX_ITERATIONS (``since`` the factoring) or
    after 3 MAX_ITERATIONS in all."""
    if not math.isfinite(size):
        raise ConvergenceError(f"flexible step at t = {time_s:.6g} s (Newton diverged)", size, NEWTON_TOL, iterations)
    if since >= MAX_ITERATIONS and fresh:
        raise ConvergenceError(f"flexible step at t = {time_s:.6g} s (Newton, position correction in m or rad)", size,
                               NEWTON_TOL, iterations)
    if iterations >= 3 * MAX_ITERATIONS:
        raise ConvergenceError(f"flexible step at t = {time_s:.6g} s", size, NEWTON_TOL, iterations)


def generalized_alpha(rho_inf: float) -> tuple[float, float, float, float]:
    """(alpha_m, alpha_f, gamma, beta) of the generalised-alpha scheme for the spectral radius rho_inf in [0, 1]
    (module doc; Chung & Hulbert 1993)."""
    alpha_m, alpha_f = (2 * rho_inf - 1) / (rho_inf + 1), rho_inf / (rho_inf + 1)
    gamma = 0.5 + alpha_f - alpha_m
    return alpha_m, alpha_f, gamma, 0.25 * (gamma + 0.5) ** 2


def first_mode_hz(machine: Machine, poses_m: np.ndarray) -> np.ndarray:
    """The first mode (Hz) (k,) of the flexible machine at reachable poses (k, 3) (m), the drives holding their
    lengths: the mode whose period MAX_STEP_FRACTION bounds the step by (module doc). One model, built at the first
    pose, its stems placed, stiffened and weighed at each (as a state there sees them): within 5e-11 of a model
    built at each pose."""
    poses = np.atleast_2d(np.asarray(poses_m, dtype=float))
    fm = FlexibleMachine(machine, poses[0], damping=Rayleigh(alpha_per_s=0.0, beta_s=0.0))
    out = [float(fm.modes.frequencies_hz[0])]
    for pose in poses[1:]:
        q = fm.mm.pose_values(pose).q0
        fm._place(q[fm.act_q] - machine.cylinder.length_m)
        out.append(float(fm._modes(q, 1).frequencies_hz[0]))
    return np.array(out)


def leg_frame_loads(wrenches: np.ndarray, cardan_axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Section resultants (..., n, 3, 6) (N, V_x, V_y in N; M_x, M_y, T in N m) in the deformed leg frames,
    and the frames (..., n, 3, 3) (columns e_x, e_y, e_z; :mod:`.base`), from the world section wrenches
    (..., n, 3, 9) of :meth:`FlexibleMachine.section_wrenches` and the cardan axes a_i (n, 3); batched."""
    pts, force, moment = wrenches[..., :3], wrenches[..., 3:6], wrenches[..., 6:]
    ez = pts[..., 2, :] - pts[..., 0, :]
    ez = ez / np.sqrt((ez * ez).sum(axis=-1))[..., None]
    ex = cardan_axes - (cardan_axes * ez).sum(axis=-1)[..., None] * ez
    ex = ex / np.sqrt((ex * ex).sum(axis=-1))[..., None]
    frames = np.stack([ex, _cross(ez, ex), ez], axis=-1)  # (..., leg, xyz, column)
    fl = np.einsum("...lji,...lsj->...lsi", frames, force)  # in the leg frames
    ml = np.einsum("...lji,...lsj->...lsi", frames, moment)
    return np.concatenate([fl[..., 2:3], fl[..., 0:2], ml], axis=-1), frames


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b over the last axis (3,) (np.cross's overhead dominates at this size)."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1], a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def _wrench(plate_wrench: np.ndarray | None) -> np.ndarray:
    if plate_wrench is None:
        return np.zeros(6)
    w = np.asarray(plate_wrench, dtype=float).reshape(-1)
    if w.shape == (3,):
        w = np.concatenate([w, np.zeros(3)])
    if w.shape != (6,) or not np.all(np.isfinite(w)):
        raise PressfitError(f"plate_wrench must be 3 or 6 finite numbers (F in N, then M in N m), got {plate_wrench!r}")
    return w
