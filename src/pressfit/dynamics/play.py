r"""Cardan play on the flexible machine: each leg's two cardan plays lumped in series at its drive.

Model. A leg's base and plate cardans each have an axial play (the effective axial gaps g_b, g_p of
:meth:`pressfit.mechanics.clearance_law.Clearance.effective_gaps_m` at the plate's current pose, so a box
geometry follows the pose) with the contact stiffness k_c. In series they act as one dead zone of gap
G = g_b + g_p and stiffness k_c / 2 (:func:`pressfit.mechanics.clearance_law.dead_zones`; exact in the sharp
limit, the smoothed pair differs by the smoothing width w, 1 nm by default). The play is massless and sits
between the drive and the leg: the leg's length between the cardan centres (the flexible model's actuator
coordinate q_a) is the drive's length l_d plus the play's extension x,

    q_a = l_d + (x - x_0),   f(x) = N  (the leg's tension N through the play),

with x_0 the extension at the calibration state: the drives' length sensors are zeroed at the run's start
(gravity, the preload and the start tensions), so the run shows the lost motion -- the change of the plays with
the tensions -- as the rigid model's load-deflection curve does from zero contact load.

* An ideal force drive delivers N whatever the travel: the play changes only what its length sensor reads,
  l_d = q_a - (X(N) - x_0), X the dead zone's inverse (:meth:`LegPlay.sensed_lengths_m`).
* A drive whose tension follows its own travel (an oil column, a back-EMF) gets its length from the play, and
  a drive with a reflected mass m_d (an electric drive's rotor and screw, 15.5 kg on the shipped one) carries it
  on its own side of the plays, off the leg: m_d l_d'' = f(x) - D. Per leg the monotone equation

      r(x) = f(x) - D(l_d) - m_d a_d(l_d) = 0,   l_d = q_a - x + x_0,   r' = f'(x) + k_d + k_i > 0

  (D the drive over the step as a function of its end length, k_d its step stiffness, a_d the end acceleration
  of the generalised-alpha scheme with rho_inf = ``DRIVE_SIDE_RHO_INF``, k_i = m_d (1 - alpha_m) / ((1 - alpha_f)
  beta h^2)) is solved at every Newton iteration of the flexible step (:class:`PlayedDrive`: safeguarded Newton
  on a bracket, halving it where Newton leaves it or does not halve its last step, a secant step
  instead while the bracket has no second end, to ``PLAY_TOL``), which
  returns the play's force f(x) on the leg. The step's iteration matrix gets the series tangent
  k_e f' / (k_e + f'), k_e = k_d + k_i, where the last solve left it, or the chord of the last two solves where
  they straddle a contact edge (Newton cycles across a kink; the chord interpolates it). The sensors read the
  drive side's length and rate (:class:`DriveSide`).
  Why rho_inf = 0 there: the play's contact against the drive's mass, sqrt(k_c / 2 / m_d) = 904 Hz on the
  electric drive, is not resolved at 1 ms, and an unresolved impact on a stiff contact is where an implicit
  scheme's energy goes wrong: measured on a 15.5 kg drive side dropped across the gap by 5 N and bouncing
  (tests/dynamics/test_play.py), the energy after 25 ms changes by +49% of the impact's kinetic energy at
  h = 1 ms with the trapezoidal rule (rho_inf = 1), +51% with 0.8, +41% with 0.5, and by -58% with 0 (the
  contact mode annihilated in a step: an inelastic impact, never a gain); resolved (h = 10 us) every rho_inf
  keeps it to 0.03% (second order).
* Position drives (the flexible model's modes, Rayleigh fit and rest state) see the plays closed: the contact
  stiffness k_c / 2 in series with each actuator spring (``FlexibleMachine(actuator_series_n_per_m=)``).

Left out (stated): the leg's own axial inertia between the plays (its bodies move with the leg's length; an
ideal force drive is massless, so its sensor follows a play's crossing at once), the rotation plays (refused),
and the plays' lateral slide (second order, :mod:`pressfit.mechanics.clearance_law`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pressfit.description.machine import Machine
from pressfit.dynamics import kernels
from pressfit.dynamics.machine.flexible import generalized_alpha
from pressfit.errors import ConvergenceError, PressfitError
from pressfit.mechanics.clearance_law import Clearance, dead_zones, invert_law

PLAY_TOL = 1e-14  # m: the play solve's last correction (k_c / 2 = 5e8 N/m: 5e-6 N of tension)
PLAY_ITERATIONS = 80
DRIVE_SIDE_RHO_INF = 0.0  # the drive side's numerical damping (module doc: unresolved impacts on the play)


@dataclass(frozen=True, kw_only=True)
class DriveSide:
    """The drives' side of the plays (n,) each: the length the sensor reads (m), its rate (m/s), acceleration
    and the generalised-alpha pseudo-acceleration (m/s^2; equal to the acceleration at rest and by default)."""

    length_m: np.ndarray
    rate_m_per_s: np.ndarray
    acceleration_m_per_s2: np.ndarray
    pseudo_acceleration_m_per_s2: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.pseudo_acceleration_m_per_s2 is None:
            object.__setattr__(self, "pseudo_acceleration_m_per_s2", self.acceleration_m_per_s2.copy())


class LegPlay:
    """The lumped plays of a machine's legs (module doc), calibrated at a pose (m) under tensions (n,), N;
    ``drive_mass_kg`` the drives' reflected mass carried on their side of the plays, kg, integrated by the
    generalised-alpha scheme of spectral radius ``rho_inf`` (module doc)."""

    def __init__(self, machine: Machine, clearance: Clearance, pose_m: np.ndarray, tensions_n: np.ndarray,
                 drive_mass_kg: float = 0.0, rho_inf: float = DRIVE_SIDE_RHO_INF) -> None:
        if clearance.rotation_gaps_rad is not None:
            raise PressfitError("the flexible model's cardan play is axial only: rotation plays "
                                "(rotation_gaps_rad) are not modelled on it")
        if not (np.isfinite(drive_mass_kg) and drive_mass_kg >= 0):
            raise PressfitError(f"drive_mass_kg must be a mass >= 0, kg, got {drive_mass_kg!r}")
        if not 0.0 <= rho_inf <= 1.0:
            raise PressfitError(f"rho_inf must be a number in [0, 1], got {rho_inf!r}")
        self.machine, self.clearance, self.drive_mass_kg = machine, clearance, float(drive_mass_kg)
        self.scheme = generalized_alpha(rho_inf)  # (alpha_m, alpha_f, gamma, beta)
        self.stiffness_n_per_m = 0.5 * clearance.contact_stiffness_n_per_m
        self.width_m = clearance.smoothing_m
        self.zero_m = np.zeros(len(machine.legs))
        self.zero_m = self.extension_m(pose_m, tensions_n)

    def gaps_m(self, pose_m: np.ndarray) -> np.ndarray:
        """G = g_b + g_p per leg (n,), m, the effective axial gaps at the pose."""
        return self.clearance.effective_gaps_m(self.machine, pose_m).sum(1)

    def extension_m(self, pose_m: np.ndarray, tensions_n: np.ndarray) -> np.ndarray:
        """The plays' extension from the calibration state, X(N) - x_0 (n,), m, under tensions N (n,), N."""
        return invert_law(np.asarray(tensions_n, float), self.gaps_m(pose_m), self.stiffness_n_per_m,
                          self.width_m) - self.zero_m

    def stored_energy_j(self, pose_m: np.ndarray, extension_m: np.ndarray) -> np.ndarray:
        """The plays' elastic contact energy V(x) per leg (n,), J, at extensions X - x_0 (n,), m (as
        :meth:`extension_m` and :attr:`PlayedDrive.extension_m` give them) with the gaps at the pose (m): the
        closed form of the dead zone's law f (:func:`pressfit.mechanics.clearance_law.dead_zones`), its
        antiderivative: k/2 (|x| - G)^2 outside the gap of half-width G and 0 inside in the sharp limit (k = k_c / 2,
        x the extension from the middle of the gap); the smoothed law differs from it within the width w of the
        edges and by a constant of order k w^2 ln(G / w) (1e-9 J at the default 1 nm)."""
        x = np.asarray(extension_m, float) + self.zero_m
        return dead_zones(x, self.gaps_m(pose_m), self.stiffness_n_per_m, self.width_m)[0]

    def sensed_lengths_m(self, pose_m: np.ndarray, lengths_m: np.ndarray, tensions_n: np.ndarray) -> np.ndarray:
        """A massless drive's lengths l_d = q_a - (X(N) - x_0) (n,), m, for leg lengths q_a (n,), m."""
        return np.asarray(lengths_m, float) - self.extension_m(pose_m, tensions_n)

    def over_step(self, drive: Callable[[np.ndarray], np.ndarray], pose_m: np.ndarray, tensions_n: np.ndarray,
                  drive_stiffness_n_per_m: np.ndarray, side: DriveSide, dt_s: float) -> PlayedDrive:
        """``drive`` (a :class:`pressfit.dynamics.drives.base.DriveOverStep`, a function of the drive's end
        lengths) through the plays over a step of dt_s (s) from the drive side's state ``side``, as a function
        of the leg lengths q_a; warm-started at tensions (n,), N."""
        return PlayedDrive(play=self, drive=drive, gaps_m=self.gaps_m(pose_m),
                           start_m=self.extension_m(pose_m, tensions_n) + self.zero_m,
                           drive_stiffness_n_per_m=np.asarray(drive_stiffness_n_per_m, float), side=side,
                           dt_s=float(dt_s))


class PlayedDrive:
    """N(q_a) for a drive behind the plays (module doc): ``__call__`` solves r(x) = 0 per leg and returns the
    plays' force on the legs f(x) (n,), N (the drive's own tension D is the wrapped drive's); ``extension_m``
    the last solve's X - x_0 (n,), m; ``side`` the drive side at its end."""

    def __init__(self, *, play: LegPlay, drive: Callable[[np.ndarray], np.ndarray], gaps_m: np.ndarray,
                 start_m: np.ndarray, drive_stiffness_n_per_m: np.ndarray, side: DriveSide, dt_s: float) -> None:
        self.play, self.drive, self.gaps, self.x, self.start, self.h = play, drive, gaps_m, start_m.copy(), side, dt_s
        self.side = side
        am, af, _, beta = play.scheme
        self.inertia_n_per_m = play.drive_mass_kg * (1 - am) / ((1 - af) * beta * dt_s * dt_s)
        self.kd = drive_stiffness_n_per_m + self.inertia_n_per_m
        shape = np.shape(start_m)  # the solve's per-leg constants, as its compiled iteration takes them
        self._g, self._kd = (np.ascontiguousarray(np.broadcast_to(a, shape), dtype=float) for a in (gaps_m, self.kd))
        self._trust = 2.0 * self._g + 10.0 * play.width_m + 1e-6  # m: the largest step before a bracket is known
        self._last: tuple[np.ndarray, np.ndarray] | None = None  # the last solve's (q_a, f)
        self._previous: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # the one before, with its tangent

    def _point_tangent(self, x: np.ndarray) -> np.ndarray:
        kp = dead_zones(x, self.gaps, self.play.stiffness_n_per_m, self.play.width_m)[2]
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.kd + kp > 0, self.kd * kp / (self.kd + kp), 0.0)

    def tangent_n_per_m(self) -> np.ndarray:
        """dN/dq_a for the step's iteration matrix (n,), N/m: the series k_e f' / (k_e + f') at the last solve
        (the start before any); where the last two solves lie on either side of a contact edge (their tangents
        differ by more than half), the chord between them (a Newton iteration across a kink cycles; the chord
        interpolates the kink)."""
        point = self._point_tangent(self.x)
        if self._previous is None:
            return point
        (q0, f0, k0), (q1, f1) = self._previous, self._last
        dq = q1 - q0
        across = (np.abs(point - k0) > 0.5 * np.maximum(point, k0)) & (np.abs(dq) > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(across, (f1 - f0) / dq, point)  # in [0, max(point, k0)]: f(q_a) is monotone

    @property
    def extension_m(self) -> np.ndarray:
        return self.x - self.play.zero_m

    @property
    def force_n(self) -> np.ndarray:
        """The last solve's force of the plays on the legs f(x) (n,), N (the drive's tension at the start)."""
        if self._last is None:
            return dead_zones(self.x, self.gaps, self.play.stiffness_n_per_m, self.play.width_m)[1]
        return self._last[1]

    def stored_energy_j(self) -> np.ndarray:
        """The plays' elastic energy at the last solve (n,), J, with the gaps of this step
        (:meth:`LegPlay.stored_energy_j`)."""
        return dead_zones(self.x, self.gaps, self.play.stiffness_n_per_m, self.play.width_m)[0]

    def _accelerations(self, length_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The drive side's pseudo- and true acceleration at the step's end length (n,), m/s^2 (module doc)."""
        s, h = self.start, self.h
        am, af, _, beta = self.play.scheme
        a = (length_m - s.length_m - h * s.rate_m_per_s - h * h * (0.5 - beta) * s.pseudo_acceleration_m_per_s2
             ) / (beta * h * h)
        return a, ((1 - am) * a + am * s.pseudo_acceleration_m_per_s2 - af * s.acceleration_m_per_s2) / (1 - af)

    def _inertia_n(self, length_m: np.ndarray) -> np.ndarray:
        """m_d a_d at the drive's end length (n,), N."""
        if not self.play.drive_mass_kg:
            return np.zeros_like(length_m)
        return self.play.drive_mass_kg * self._accelerations(length_m)[1]

    def __call__(self, lengths_m: np.ndarray) -> np.ndarray:
        k, w, g, kd, trust = self.play.stiffness_n_per_m, self.play.width_m, self._g, self._kd, self._trust
        x, f = np.array(self.x, dtype=float), np.empty(np.shape(self.x))
        lo, hi = np.full(x.shape, -np.inf), np.full(x.shape, np.inf)
        previous = np.full(x.shape, np.inf)  # the last step's size: Newton must halve it, or the bracket is halved
        last = np.full((2, x.size), np.nan)  # the last iterate's x and r (the secant's other point)
        for _ in range(PLAY_ITERATIONS):
            end = lengths_m - x + self.play.zero_m
            tension = self.drive(end)
            if kernels.play_iteration(x, np.asarray(tension, dtype=float), self._inertia_n(end), g, k, w, kd, trust,
                                      lo, hi, previous, PLAY_TOL, f, last):
                if self._last is not None:
                    self._previous = (*self._last, self._point_tangent(self.x))
                self.x, self.side, self._last = x, self._side(end), (lengths_m.copy(), f)
                return f  # the play's force on the leg: the drive's tension plus its side's inertia
        raise ConvergenceError("cardan play in series with the drive (m)", float(np.max(previous)), PLAY_TOL,
                               PLAY_ITERATIONS)

    def _side(self, end: np.ndarray) -> DriveSide:
        """The drive side at the step's end: generalised-alpha with a mass, else the backward difference."""
        s, h = self.start, self.h
        if not self.play.drive_mass_kg:
            return DriveSide(length_m=end, rate_m_per_s=(end - s.length_m) / h,
                             acceleration_m_per_s2=np.zeros_like(end))
        gamma = self.play.scheme[2]
        a, acc = self._accelerations(end)
        return DriveSide(length_m=end, rate_m_per_s=s.rate_m_per_s + h * ((1 - gamma) * s.pseudo_acceleration_m_per_s2
                                                                          + gamma * a),
                         acceleration_m_per_s2=acc, pseudo_acceleration_m_per_s2=a)
