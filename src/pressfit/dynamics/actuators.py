r"""The force-controlled actuators (one per leg) and the redundant force distribution (paper section 4.2,
equation 5).

Forces are leg tensions N_i (N, positive = tension, the project's convention): leg i pulls the plate with
-N_i e_i, so the actuators exert the Cartesian force -A N on the plate (A of equation 5, columns e_i).

Distribution: a commanded Cartesian force W (N, on the plate) and commanded preload amplitudes a (n - 3,), N,
give

    N = -A^+ W + V a      (on the 4-UPU: -A^+ W + a4 v_p),

A^+ = A^T (A A^T)^-1 the Moore-Penrose inverse and V the preload basis (:func:`pressfit.kinematics.preload_basis`:
n - 3 unit null vectors of A, amplitude k belonging to leg 3 + k; the 4-UPU's one vector is v_p with v_1 < 0,
equations 9-10; none on 3 legs): -A N = W exactly and the preload changes no plate force. At one pose both come in
closed form from the 3 x 3 normal matrix A A^T (:func:`distribution`, compiled: about a microsecond; accurate to
cond(A)^2 eps, and cond(A) <= 3.6 over the reachable workspace; the batched closed forms of
:mod:`pressfit.kinematics` and numpy's SVD are the independent references of the tests).

Drive: each actuator tracks its command with a first-order force response of bandwidth f_bw (Hz),
tau dN/dt = sat(N_cmd) - N, tau = 1 / (2 pi f_bw), the command saturated at +-``force_limit_n`` (the drive
cannot deliver more, so neither its output). The step is the exact zero-order-hold discretisation
N' = s + (N - s) exp(-dt / tau) of the saturated command s, exact for any dt.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pressfit import kinematics
from pressfit.description.machine import Machine
from pressfit.dynamics import kernels
from pressfit.errors import PressfitError, SingularPoseError

SINGULAR_SIGMA = kernels.SINGULAR_SIGMA  # smallest singular value of A (entries O(1)) below which A is singular


def distribution(unit_vectors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A^+ (n, 3) and the preload basis V (n, n - 3) (v_p as its one column on the 4-UPU) at one pose from the leg
    unit vectors e_i (n, 3) (rows of dl/dh, columns of A), in closed form
    (:func:`pressfit.dynamics.kernels.distribution`); SingularPoseError when A's smallest singular value is below
    ``SINGULAR_SIGMA``."""
    legs = len(unit_vectors)
    pinv, null = np.empty((legs, 3)), np.empty((legs, legs - 3))
    sigma = kernels.distribution(np.ascontiguousarray(unit_vectors, dtype=float), pinv, null)
    if sigma < SINGULAR_SIGMA:
        raise singular_error(sigma)
    return pinv, null


def singular_error(sigma: float) -> SingularPoseError:
    """The refusal of a singular A (smallest singular value ``sigma`` below ``SINGULAR_SIGMA``)."""
    return SingularPoseError(f"the static matrix A is singular (smallest singular value {sigma:.2e})",
                             smallest_singular_value=float(sigma))


def distribute(machine: Machine, pose_m: np.ndarray, plate_force_n: np.ndarray,
               preload_n: float | np.ndarray) -> np.ndarray:
    """Actuator tensions (n,), N, that exert the Cartesian force ``plate_force_n`` (3,), N, on the plate at
    ``pose_m`` (m) with the preload amplitudes ``preload_n`` (n - 3,), N (a4 along v_p on the 4-UPU; module
    docstring)."""
    pinv, null = distribution(kinematics.inverse_kinematics(machine, np.asarray(pose_m, float)).unit_vectors)
    return -pinv @ np.asarray(plate_force_n, dtype=float) + null @ np.atleast_1d(np.asarray(preload_n, float))


@dataclass(frozen=True)
class ForceActuators:
    """First-order force response with saturation (module docstring); bandwidth Hz, limit N."""

    bandwidth_hz: float
    force_limit_n: float

    def __post_init__(self) -> None:
        for name in ("bandwidth_hz", "force_limit_n"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise PressfitError(f"actuator {name} must be a positive number, got {value!r}")

    @classmethod
    def of(cls, machine: Machine) -> ForceActuators:
        """The machine's drives (``[actuator] force_bandwidth_hz``, ``force_limit_n``); an electric or hydraulic
        drive is refused here (its model is :mod:`pressfit.dynamics.drives`, ``drives.of(machine)``)."""
        if machine.actuator.kind != "force":
            raise PressfitError(f"{machine.source or machine.name}: key 'actuator.kind': the first-order force drive "
                                f"needs kind = \"force\", got \"{machine.actuator.kind}\" (see drives.of)")
        return cls(machine.actuator.force_bandwidth_hz, machine.actuator.force_limit_n)

    @property
    def time_constant_s(self) -> float:
        """tau = 1 / (2 pi f_bw), s."""
        return 1.0 / (2.0 * math.pi * self.bandwidth_hz)

    def saturated(self, command_n: np.ndarray) -> np.ndarray:
        """True where a command exceeds the force limit."""
        return np.abs(command_n) > self.force_limit_n

    def step(self, force_n: np.ndarray, command_n: np.ndarray, dt_s: float) -> np.ndarray:
        """The actuator forces (N) after ``dt_s`` (s) from ``force_n`` under the held command ``command_n`` (N)."""
        force, command, shape = force_n, command_n, None  # a run's step: two float vectors of one length
        if not (type(force) is np.ndarray and type(command) is np.ndarray and force.ndim == 1
                and force.shape == command.shape and force.dtype == command.dtype == np.float64):
            shape = np.broadcast_shapes(np.shape(force_n), np.shape(command_n))  # anything else, as the kernel takes it
            force, command = (np.ascontiguousarray(x, dtype=float).ravel() for x in np.broadcast_arrays(force, command))
        out = np.empty(force.size)
        kernels.first_order(force, command, float(self.force_limit_n), math.exp(-dt_s / self.time_constant_s), out)
        return out if shape is None else out.reshape(shape)
