r"""Where to measure: a D-optimal plan of poses and load directions for the keys to calibrate.

Candidates: the poses of a 3 x 3 x 3 grid of the required workspace (the x-z square of ``[workspace]`` at the
lowest, middle and highest height where the whole square is reachable,
:func:`pressfit.kinematics.workspace.square_height_range`) times 9 load directions (the three axes and the six
two-axis diagonals; the sign of a load does not change the information of a linear model), each load of
``load_n`` (default the 700 N press load) with the tool translation measured with noise ``sigma_m``.

Each candidate c contributes G_c^T G_c to the information matrix of theta (G_c = d translation / d theta /
sigma, 3 x k, :func:`pressfit.studies.calibration_model.sensitivities`). The plan is built greedily: start
from a small ridge (1e-9 of the largest candidate information's trace), repeatedly add the candidate that
maximises log det of the information (D-optimality: the smallest volume of the keys' confidence ellipsoid;
with the matrix determinant lemma each step is one k x k solve per candidate). A candidate is used once.
The predicted standard errors are sqrt(diag(I^-1)) in theta (relative, for log keys), I the chosen measurements'
information without the ridge (a pseudo-inverse if they do not determine every key).

:func:`separating_measurement`: for two keys that the data cannot tell apart, the one candidate that adds the
most log det to their (2 x 2) information from the data (the same criterion), and their correlation after it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pressfit.description.machine import Machine, load_machine
from pressfit.errors import PressfitError
from pressfit.kinematics.workspace import square_height_range, workspace_square
from pressfit.mechanics.condensed import PRESS_LOAD_N
from pressfit.studies.calibration_model import Data, FitKey, parse_fit_keys, sensitivities
from pressfit.studies.measurements import Deflections

DEFAULT_SIGMA_M = 1e-6  # a dial gauge's or a laser tracker's repeatability, order of magnitude
HEIGHT_MARGIN_M = 1e-3  # inside the reachable height range


def load_directions() -> np.ndarray:
    """(9, 3) unit directions: x, y, z and the six diagonals x+-y, x+-z, y+-z."""
    d = [np.eye(3)[i] for i in range(3)]
    for i, j in ((0, 1), (0, 2), (1, 2)):
        for s in (1.0, -1.0):
            v = np.zeros(3)
            v[i], v[j] = 1.0, s
            d.append(v / np.sqrt(2.0))
    return np.array(d)


def candidate_poses(machine: Machine) -> np.ndarray:
    """(27, 3) poses, m: the required square at three heights (module doc)."""
    rng = square_height_range(machine)
    ys = np.linspace(rng.y_min_m + HEIGHT_MARGIN_M, rng.y_max_m - HEIGHT_MARGIN_M, 3)
    x, z = workspace_square(machine, 3)
    return np.array([(xi, yi, zi) for yi in ys for zi in z for xi in x])


def _candidates(machine: Machine, keys: list[FitKey], load_n: float, sigma_m: float
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    poses, dirs = candidate_poses(machine), load_directions()
    pose = np.repeat(poses, len(dirs), 0)
    load = np.tile(dirs, (len(poses), 1)) * load_n
    zeros = np.zeros_like(pose)
    data = Data(deflections=Deflections(path="<plan>", pose_m=pose, load_n=load, translation_m=zeros,
                                        rotation_rad=None, sigma_m=None, sigma_rad=None, lines=np.arange(len(pose))))
    theta = np.array([float(k.to_theta(k.start)) for k in keys])
    g = sensitivities(machine, keys, theta, data).reshape(len(pose), 3, len(keys)) / sigma_m
    return pose, load, g


@dataclass(frozen=True, kw_only=True)
class MeasurementPlan:
    """The planned measurements: ``pose_m`` (N, 3), ``load_n`` (N, 3) at the tool, the predicted standard error
    of each key in theta (``relative`` for log keys), and the plan's log det information."""

    keys: list[str]
    log_space: list[bool]
    pose_m: np.ndarray
    load_n: np.ndarray
    sigma_m: float
    standard_error_theta: np.ndarray
    correlation: np.ndarray
    log_det_information: float

    def to_dict(self) -> dict[str, Any]:
        return {"keys": self.keys, "sigma_m": self.sigma_m, "criterion": "D-optimal (greedy, log det information)",
                "measurements": [{"x_m": p[0], "y_m": p[1], "z_m": p[2], "fx_n": f[0], "fy_n": f[1], "fz_n": f[2]}
                                 for p, f in zip(self.pose_m.tolist(), self.load_n.tolist(), strict=True)],
                "predicted_standard_error": [{"key": k, "relative" if lg else "absolute": float(s)} for k, lg, s
                                             in zip(self.keys, self.log_space, self.standard_error_theta, strict=True)],
                "predicted_correlation": self.correlation.tolist(), "log_det_information": self.log_det_information}


def plan_measurements(machine: Machine, keys: list[FitKey], poses: int = 12, load_n: float = PRESS_LOAD_N,
                      sigma_m: float = DEFAULT_SIGMA_M) -> MeasurementPlan:
    """Greedy D-optimal choice of ``poses`` measurements (pose and load) from the candidates (module doc)."""
    pose, load, g = _candidates(machine, keys, load_n, sigma_m)
    if not 1 <= poses <= len(pose):
        raise PressfitError(f"--poses must be in [1, {len(pose)}] (the candidate measurements), got {poses}")
    per = np.einsum("cik,cil->ckl", g, g)  # each candidate's information, (c, k, k)
    k = len(keys)
    ridge = 1e-9 * np.trace(per, axis1=1, axis2=2).max() * np.eye(k)
    info = ridge
    chosen: list[int] = []
    for _ in range(poses):
        inv = np.linalg.inv(info)
        # det(I + G^T G) / det(I) = det(1_3 + G I^-1 G^T), the matrix determinant lemma
        gain = np.linalg.slogdet(np.eye(3) + np.einsum("cik,kl,cjl->cij", g, inv, g))[1]
        gain[chosen] = -np.inf
        best = int(np.argmax(gain))
        chosen.append(best)
        info = info + per[best]
    info = info - ridge  # the ridge only starts the selection; the plan's own information
    cov = np.linalg.pinv(info)
    se = np.sqrt(np.diag(cov))
    return MeasurementPlan(keys=[kk.key for kk in keys], log_space=[kk.log for kk in keys], pose_m=pose[chosen],
                           load_n=load[chosen], sigma_m=sigma_m, standard_error_theta=se,
                           correlation=cov / np.outer(se, se), log_det_information=float(np.linalg.slogdet(info)[1]))


def separating_measurement(machine: Machine, keys: list[FitKey], information: np.ndarray, sigma_m: float,
                           load_n: float = PRESS_LOAD_N) -> dict[str, Any]:
    """The one candidate measurement (pose, load direction) that best separates two keys (module doc): the
    planner's criterion, the largest gain of log det of the pair's (2, 2) ``information`` in theta (from the
    data already fitted), with the candidate's noise ``sigma_m``; returns it with the keys' correlation after
    adding it (``correlation_after``)."""
    pose, load, g = _candidates(machine, keys, load_n, sigma_m)
    per = np.einsum("cik,cil->ckl", g, g)
    after = information[None] + per
    gain = np.linalg.slogdet(after)[1] - np.linalg.slogdet(information)[1]
    best = int(np.argmax(gain))
    cov = np.linalg.inv(after[best])
    return {"pose_m": pose[best].tolist(), "load_direction": (load[best] / np.linalg.norm(load[best])).tolist(),
            "load_n": float(load_n), "log_det_gain": float(gain[best]),
            "correlation_after": float(cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1]))}


def plan_from_file(machine_path: str | Path, fit: list[str], poses: int = 12, load_n: float = PRESS_LOAD_N,
                   sigma_m: float = DEFAULT_SIGMA_M) -> MeasurementPlan:
    """``pressfit calibrate --plan``: the machine file's keys checked, then :func:`plan_measurements`."""
    machine = load_machine(machine_path)
    return plan_measurements(machine, parse_fit_keys(machine, fit), poses, load_n, sigma_m)
