r"""The tool-point response at a pose: a force step at the tool and the receptance (frequency response).

The machine vibrates about its static equilibrium under the weight, with the drives holding their lengths
(the actuator springs keep their rest lengths): the linearised, closure-restricted system of
:func:`pressfit.dynamics.modes.reduced_system`,

    M_r z'' + C_r z' + K_r z = G^T F(t),   u = G z,

with G (3, r) the plate centre's (= the tool tip's) world translation per reduced coordinate and F the world
force at the tool (N). Damping is modal: every mode k gets the ratio zeta (``damping_ratio``, an estimate:
bolted steel frames with cardan joints are typically 1-5%). In the mass-normalised modes X (X^T M_r X = I,
X^T K_r X = diag(omega_k^2)) the modal coordinates decouple, eta_k'' + 2 zeta omega_k eta_k' +
omega_k^2 eta_k = g_k, g = X^T G^T F, and a step F H(t) has the closed-form answer

    eta_k(t) = g_k / omega_k^2 [1 - e^{-zeta omega_k t} (cos omega_dk t + zeta omega_k t sinc(omega_dk t))],

omega_dk = omega_k sqrt(1 - zeta^2), sinc(x) = sin(x) / x (= 1 at x = 0): one expression for every zeta in
[0, 1], the undamped (zeta = 0: the modes ring for ever, so the history is only over the finite duration) and
the critically damped (zeta = 1: omega_dk = 0, eta_k = g_k / omega_k^2 [1 - e^{-omega_k t} (1 + omega_k t)])
included. Every mode of the reduced model is kept (no truncation), so u(infinity) = G K_r^{-1} G^T F is the
static compliance at the tool. The receptance is the 3x3 complex matrix

    H(omega) = sum_k (G x_k)(G x_k)^T / (omega_k^2 - omega^2 + 2 i zeta omega_k omega)   (m/N),

whose peaks sit at the modes the tool point sees. The first modes are the plate's rocking about the legs'
concurrency point: they change no leg length, so the drives holding their lengths do not stop them.

The state linearised about: ``K_r`` is the elastic stiffness at the equilibrium under ``plate_wrench`` (the
command: the plate's and tool's weight), the configuration deformed by that weight (its geometric stiffness left
out, as in :mod:`pressfit.dynamics.modes`). Unloaded (``plate_wrench`` = 0, the assembled pose) the static limit
is the condensed closed form of ``pressfit stiffness`` to 1e-9. About the weight-loaded equilibrium (what
``pressfit response`` prints) it differs from ``pressfit stiffness`` x force by a term linear in the weight:
2e-7 to 1.8e-3 of it at the poses tested (1.8e-3 at (0.2, 0.8, 0.2); halving the weight halves it to 1e-3),
tests/dynamics/test_response.py.

Range of validity (refused, naming the figure and the limit): the response is linear, so it leaves out the
geometric stiffness of the step load and the change of geometry under it. The step is refused when the whole
machine's linearised buckling factor on the loaded state (weight + step, :func:`pressfit.mechanics.buckling.
machine_buckling`) is below :data:`MIN_BUCKLING_FACTOR` (the softening the linear answer leaves out reaches
1 / (lambda - 1) of the deflection, 11% at lambda = 10), when the tool's peak translation exceeds
:data:`MAX_TRANSLATION_FRACTION` of the shortest leg or the plate's peak rotation :data:`MAX_ROTATION_RAD`
(the linearisation's error is of the order of that rotation: 0.11 rad linear against 0.10 rad nonlinear under a
2.7 kN lateral force at (0, 0.8, 0)), and when a leg is strained beyond the statics' small-strain range
(:data:`pressfit.mechanics.statics.MAX_AXIAL_STRAIN`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import eigh

from pressfit import kinematics
from pressfit.description.machine import Machine
from pressfit.dynamics.modes import ReducedSystem, reduced_system
from pressfit.errors import PressfitError, UnstableEquilibriumError
from pressfit.mechanics.buckling import machine_buckling

MAX_SAMPLES = 200_000  # time samples of the step response (a longer --duration is refused)
MAX_FREQUENCIES = 20_000
SAMPLES_PER_PERIOD = 40  # of the fastest mode that contributes at least CONTRIBUTION_FLOOR of the response
CONTRIBUTION_FLOOR = 1e-3
STATIC_TOL = 1e-9  # relative: u(infinity) of the modal sum against the direct static solve K_r^-1 G^T F
MIN_BUCKLING_FACTOR = 10.0  # the loaded state's linearised buckling factor a linear response needs (docstring)
MAX_TRANSLATION_FRACTION = 0.01  # peak tool translation / shortest leg length (small displacements)
MAX_ROTATION_RAD = 0.01  # peak plate rotation (small angles)


@dataclass(frozen=True, kw_only=True)
class ToolResponse:
    """Step response and receptance at the tool (SI). ``time_s`` (n,), ``displacement_m`` (n, 3) world axes
    from the loaded equilibrium; ``frequencies_hz`` (m,), ``receptance_m_per_n`` (m, 3, 3) complex;
    ``modes_hz`` (k,) every natural frequency of the reduced model, ``contribution_m`` (k,) each mode's
    static share |G x_k g_k| / omega_k^2 of the tool displacement."""

    pose_m: np.ndarray
    force_n: np.ndarray
    damping_ratio: float
    time_s: np.ndarray
    displacement_m: np.ndarray
    static_m: np.ndarray  # (3,) u(infinity)
    frequencies_hz: np.ndarray
    receptance_m_per_n: np.ndarray
    modes_hz: np.ndarray
    contribution_m: np.ndarray
    static_residual: float  # |sum of modal statics - direct solve| / |direct solve|

    @property
    def direction(self) -> np.ndarray:
        return self.force_n / np.linalg.norm(self.force_n)

    def split(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(along the force, perpendicular to it) magnitudes of displacements u (..., 3), m."""
        along = u @ self.direction
        return np.abs(along), np.linalg.norm(u - along[..., None] * self.direction, axis=-1)

    @property
    def direct_receptance_m_per_n(self) -> np.ndarray:
        """d^T H d (m,) complex, m/N: the tool's motion along the force per newton along it."""
        return np.einsum("i,fij,j->f", self.direction, self.receptance_m_per_n, self.direction)

    @property
    def dominant_frequency_hz(self) -> float:
        """The natural frequency of the mode with the largest share of the tool displacement."""
        return float(self.modes_hz[int(np.argmax(self.contribution_m))])

    def summary(self) -> dict[str, Any]:
        """JSON-ready digest. 'vertical' is along world y, 'lateral' the horizontal (x, z) magnitude."""
        lateral = np.hypot(self.displacement_m[:, 0], self.displacement_m[:, 2])
        return {
            "pose_m": self.pose_m, "force_n": self.force_n, "damping_ratio": self.damping_ratio,
            "duration_s": float(self.time_s[-1]),
            "static_lateral_m": float(math.hypot(self.static_m[0], self.static_m[2])),
            "static_vertical_m": float(self.static_m[1]),
            "peak_lateral_m": float(lateral.max()),
            "peak_vertical_m": float(self.displacement_m[np.argmax(np.abs(self.displacement_m[:, 1])), 1]),
            "static_displacement_m": self.static_m,
            "dominant_frequency_hz": self.dominant_frequency_hz,
            "lowest_modes_hz": self.modes_hz[:6],
            "receptance_peak_hz": self.receptance_peaks_hz(),
            "static_residual": self.static_residual,
        }

    def receptance_peaks_hz(self, count: int = 4) -> list[float]:
        """Frequencies of the ``count`` highest local maxima of the direct receptance |d^T H d| (d the force
        direction), lowest frequency first."""
        mag = np.abs(self.direct_receptance_m_per_n)
        inner = np.flatnonzero((mag[1:-1] > mag[:-2]) & (mag[1:-1] >= mag[2:])) + 1
        best = inner[np.argsort(mag[inner])[::-1][:count]]
        return sorted(float(self.frequencies_hz[i]) for i in best)


def tool_response(machine: Machine, pose_m: np.ndarray, force_n: np.ndarray, duration_s: float = 0.5,
                  damping_ratio: float = 0.02, frequency_range_hz: tuple[float, float] | None = None,
                  frequency_count: int = 2000, plate_wrench: np.ndarray | None = None) -> ToolResponse:
    """The step response and receptance at the tool, pose ``pose_m`` (m), step force ``force_n`` (3,) (N,
    world axes), about the equilibrium under ``plate_wrench`` (default the weight); module docstring.
    Refuses a non-positive duration, a damping ratio outside [0, 1], a zero force, a request of more than
    :data:`MAX_SAMPLES` time samples (naming the longest duration the pose allows, before the history is
    computed) and a step outside the linear range (module docstring)."""
    force = _check_request(force_n, duration_s, damping_ratio, frequency_count)
    rs = reduced_system(machine, pose_m, plate_wrench)
    omega2, x = eigh(rs.stiffness, rs.mass_kg)
    if omega2[0] <= 0:
        raise PressfitError(f"the restricted stiffness is not positive definite at pose {tuple(rs.mm.pose_m)} m")
    omega = np.sqrt(omega2)
    g = rs.plate_map[:3]  # (3, r)
    shapes = g @ x  # (3, k): tool translation per mass-normalised modal coordinate
    gk = shapes.T @ force  # modal forces
    modal_static = shapes * (gk / omega2)  # (3, k)
    static = modal_static.sum(axis=1)
    direct = g @ np.linalg.solve(rs.stiffness, g.T @ force)
    residual = float(np.linalg.norm(static - direct) / np.linalg.norm(direct))
    if not residual <= STATIC_TOL:
        raise PressfitError(f"modal static deflection residual {residual:.2e} exceeds {STATIC_TOL:.0e}")
    contribution = np.linalg.norm(modal_static, axis=0)
    relevant = omega[contribution >= CONTRIBUTION_FLOOR * contribution.max()]
    t = _time_samples(duration_s, relevant.max())
    _check_buckling(rs, force)
    eta_unit = _unit_step(t, omega, damping_ratio)  # (n, k)
    displacement = eta_unit @ modal_static.T  # (n, 3)
    rotation = eta_unit @ ((rs.plate_map[3:] @ x) * (gk / omega2)).T  # (n, 3) plate rotation, rad
    _check_small_displacement(machine, rs, displacement, rotation)
    lo, hi = frequency_range_hz or (max(0.1, 0.2 * omega[0] / 2 / math.pi), 3.0 * relevant.max() / 2 / math.pi)
    if not (0 < lo < hi):
        raise PressfitError(f"frequency range must be 0 < LOW < HIGH Hz, got {lo!r} {hi!r}")
    freqs = np.geomspace(lo, hi, frequency_count)
    w = 2 * math.pi * freqs
    denom = omega2[None, :] - w[:, None] ** 2 + 2j * damping_ratio * omega[None, :] * w[:, None]
    if not np.all(denom != 0):  # undamped, a sampled frequency exactly at a mode
        f = float(freqs[np.flatnonzero((denom == 0).any(axis=1))[0]])
        raise PressfitError(f"the undamped receptance is infinite at {f:.6g} Hz, a natural frequency: give a "
                            "damping ratio > 0 or another frequency range")
    receptance = np.einsum("ik,fk,jk->fij", shapes, 1.0 / denom, shapes)
    return ToolResponse(pose_m=rs.mm.pose_m.copy(), force_n=force, damping_ratio=float(damping_ratio), time_s=t,
                        displacement_m=displacement, static_m=static, frequencies_hz=freqs,
                        receptance_m_per_n=receptance, modes_hz=omega / (2 * math.pi), contribution_m=contribution,
                        static_residual=residual)


def _check_request(force_n: np.ndarray, duration_s: float, damping_ratio: float, frequency_count: int) -> np.ndarray:
    """The step force (3,) (N) of a valid request; PressfitError naming the bad argument otherwise."""
    force = np.asarray(force_n, dtype=float).reshape(3)
    if not np.all(np.isfinite(force)) or not np.linalg.norm(force) > 0:
        raise PressfitError(f"force must be a finite, non-zero vector (N), got {force.tolist()}")
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise PressfitError(f"duration must be a positive number of seconds, got {duration_s!r}")
    if not (math.isfinite(damping_ratio) and 0 <= damping_ratio <= 1):
        raise PressfitError(f"damping ratio must be in [0, 1], got {damping_ratio!r}")
    if not (isinstance(frequency_count, int) and 10 <= frequency_count <= MAX_FREQUENCIES):
        raise PressfitError(f"frequency count must be an integer in [10, {MAX_FREQUENCIES}], got {frequency_count!r}")
    return force


def _time_samples(duration_s: float, fastest_rad_s: float) -> np.ndarray:
    """Sample times (s) over the duration, :data:`SAMPLES_PER_PERIOD` per period of the fastest contributing
    mode (rad/s); a duration needing more than :data:`MAX_SAMPLES` is refused with the longest one allowed."""
    dt = 2 * math.pi / fastest_rad_s / SAMPLES_PER_PERIOD
    n = int(math.ceil(duration_s / dt)) + 1
    if n > MAX_SAMPLES:
        raise PressfitError(f"duration {duration_s:g} s needs {n} samples at {dt:.2e} s (the fastest contributing "
                            f"mode is {fastest_rad_s / 2 / math.pi:.4g} Hz); at most {MAX_SAMPLES}: the longest "
                            f"duration at this pose is {(MAX_SAMPLES - 2) * dt:.6g} s")
    return np.linspace(0.0, duration_s, n)


def _unit_step(t: np.ndarray, omega: np.ndarray, zeta: float) -> np.ndarray:
    """(n, k) each mode's step response per unit static deflection (module docstring), zeta in [0, 1]."""
    wd = omega * math.sqrt(1 - zeta**2)
    decay = np.exp(-zeta * np.outer(t, omega))
    tw = np.outer(t, wd)
    return 1.0 - decay * (np.cos(tw) + zeta * np.outer(t, omega) * np.sinc(tw / math.pi))


def _check_buckling(rs: ReducedSystem, force: np.ndarray) -> None:
    """Refuse a step whose loaded state (plate wrench + step) has a buckling factor below MIN_BUCKLING_FACTOR."""
    wrench = rs.plate_wrench + np.concatenate([force, np.zeros(3)])
    factor = machine_buckling(rs.mm, rs.mm.pose_m, wrench).load_factor
    if not factor >= MIN_BUCKLING_FACTOR:
        raise UnstableEquilibriumError(
            f"the step {force.tolist()} N at pose {tuple(rs.mm.pose_m.tolist())} m with the weight has a buckling "
            f"load factor of {factor:.4g}{' (beyond the buckling load)' if factor < 1 else ''}; a linear response "
            f"needs at least {MIN_BUCKLING_FACTOR:g} (it leaves out the load's geometric softening)",
            pose_m=rs.mm.pose_m, load=wrench)


def _check_small_displacement(machine: Machine, rs: ReducedSystem, displacement_m: np.ndarray,
                              rotation_rad: np.ndarray) -> None:
    """Refuse a history whose peak tool translation or plate rotation is beyond the linear range, or whose
    static leg strain is beyond the statics' small-strain range (module docstring)."""
    legs = kinematics.inverse_kinematics(machine, rs.mm.pose_m).lengths_m
    translation, rotation = np.linalg.norm(displacement_m, axis=1).max(), np.linalg.norm(rotation_rad, axis=1).max()
    where = f"at pose {tuple(rs.mm.pose_m.tolist())} m"
    if not translation <= MAX_TRANSLATION_FRACTION * legs.min():
        raise UnstableEquilibriumError(
            f"the linear response {where} moves the tool by {translation:.4g} m, beyond the small-displacement "
            f"range of {MAX_TRANSLATION_FRACTION:g} x the shortest leg ({MAX_TRANSLATION_FRACTION * legs.min():.4g} "
            "m): use pressfit solve for the nonlinear static answer", pose_m=rs.mm.pose_m)
    if not rotation <= MAX_ROTATION_RAD:
        raise UnstableEquilibriumError(
            f"the linear response {where} rotates the plate by {rotation:.4g} rad, beyond the small-angle range "
            f"of {MAX_ROTATION_RAD:g} rad: use pressfit solve for the nonlinear static answer", pose_m=rs.mm.pose_m)
