r"""The model fitted to the built machine: stiffness keys calibrated from measured deflections (and frequencies).

Model. The measured tool translation (and rotation) under a load at a pose is predicted by the exact condensed
linear model (:func:`pressfit.mechanics.condensed.solve_linear`: rigid free cardans, linear elastic legs,
small displacements), the model ``pressfit stiffness`` reports, so the calibrated file predicts the data in
every command that uses it. It is exact for the keys it depends on (actuator, tube and stem sections, material);
keys it does not depend on (e.g. ``joints.cardan_contact_stiffness_n_per_m``, a clearance-study parameter) are
refused by name. A measured first natural frequency (``--modes``) is predicted by
:func:`pressfit.dynamics.modes.natural_modes` (the VJM model with the machine's masses).

Fit. Weighted nonlinear least squares (scipy.optimize.least_squares, trust-region reflective, bounded,
``x_scale="jac"``): residual r = (predicted - measured) / sigma per measured component. A key whose start
value and bounds are positive is fitted in log space, theta = ln(value) (the stiffnesses and dimensions are
positive and their uncertainty is relative); its interval is computed in theta and transformed back
(value exp(+-q se_theta), asymmetric), its standard error is the delta-method value se_theta * value.
Sensitivities are batched: a central difference of the closed form in theta, one batched solve over every row
per key and sign (about 100 us for 30 rows), never a solve per row.

Statistics at the optimum, J = dr/dtheta:

* covariance Cov = (J^T J)^-1 when sigma is given (stated noise: the scale is known), else
  s^2 (J^T J)^-1 with s^2 = chi^2 / (N - k) the reduced chi-square (the noise is estimated from the residuals);
* 95% intervals theta +- q se: q the normal quantile (1.960) with stated sigma, Student's t with N - k degrees
  of freedom otherwise;
* correlations Cov_ij / (se_i se_j); a pair with |rho| > 0.95, or an information matrix whose condition number
  (columns scaled to unit norm) exceeds 1e8, is reported as not separately identifiable, with the measurement
  (pose, load direction) of :mod:`pressfit.studies.measurement_plan`'s candidate set that best separates it;
* chi^2 = sum r^2 with stated sigma, its p-value P(X > chi^2) for N - k degrees of freedom (small: the model or
  the stated noise is wrong), the residuals per row (m) and their RMS against the stated RMS sigma.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats
from scipy.optimize import least_squares

from pressfit.description.machine import Machine, load_machine
from pressfit.errors import CalibrationError, MeasurementFileError, ModelFileError, PressfitError
from pressfit.studies.calibration_model import (
    Data,
    FitKey,
    machine_with,
    parse_fit_keys,
    predict,
    sensitivities,
    values_of,
)
from pressfit.studies.measurement_plan import separating_measurement
from pressfit.studies.measurements import read_deflections, read_frequencies

CORRELATION_LIMIT = 0.95  # |rho| above which two keys are reported as not separately identifiable
CONDITION_LIMIT = 1e8  # condition number of the column-scaled information matrix: near-singular above
LEVEL = 0.95


@dataclass(frozen=True, kw_only=True)
class KeyEstimate:
    """One fitted key (its SI unit is the key's): value, standard error (delta method), 95% interval, start."""

    key: str
    start: float
    value: float
    standard_error: float
    interval_low: float
    interval_high: float
    log_space: bool


@dataclass(frozen=True, kw_only=True)
class Calibration:
    """A finished fit (module doc): estimates, correlation (k, k), residuals, chi-square and warnings."""

    machine: Machine  # the calibrated machine
    estimates: list[KeyEstimate]
    correlation: np.ndarray
    condition_number: float  # of the column-scaled information matrix J^T J
    covariance_theta: np.ndarray  # (k, k) in theta (ln value for log keys)
    sigma_stated: bool  # True: Cov = (J^T J)^-1 and normal quantile; False: scaled by s^2, Student's t
    quantile: float
    rows: int
    residual_count: int
    dof: int
    chi_square: float  # sum of squared weighted residuals (with stated sigma), else sum r^2 in m^2 (and Hz^2)
    p_value: float | None  # P(chi2_dof > chi_square), None without stated sigma
    deflection_residuals_m: np.ndarray  # (m, 3) predicted - measured translation
    rotation_residuals_rad: np.ndarray | None
    frequency_residuals_hz: np.ndarray | None
    predicted: np.ndarray  # flattened prediction (m, rad, Hz)
    measured: np.ndarray
    rms_residual_m: float
    rms_sigma_m: float | None
    unidentifiable: list[dict[str, Any]] = field(default_factory=list)  # pairs and the measurement separating them
    iterations: int = 0
    data: Data | None = None


class _Evaluations:
    """The fit's predictions and sensitivities, each computed once per theta (a modal solve costs ~1 s: the
    identifiability check, the optimiser and the statistics share them). Owned by one calibrate call."""

    def __init__(self, machine: Machine, keys: list[FitKey], data: Data) -> None:
        self.machine, self.keys, self.data = machine, keys, data
        self._pred: dict[bytes, np.ndarray] = {}
        self._sens: dict[bytes, np.ndarray] = {}

    def prediction(self, theta: np.ndarray) -> np.ndarray:
        key = np.asarray(theta, dtype=float).tobytes()
        if key not in self._pred:
            self._pred[key] = predict(machine_with(self.machine, self.keys, values_of(self.keys, theta)), self.data)
        return self._pred[key]

    def sensitivities(self, theta: np.ndarray) -> np.ndarray:
        key = np.asarray(theta, dtype=float).tobytes()
        if key not in self._sens:
            self._sens[key] = sensitivities(self.machine, self.keys, np.asarray(theta, dtype=float), self.data)
        return self._sens[key]


def _fit(machine: Machine, keys: list[FitKey], data: Data, ev: _Evaluations) -> tuple[np.ndarray, Any]:
    w, y = data.weights(), data.measured()

    def residual(theta: np.ndarray) -> np.ndarray:
        return w * (ev.prediction(theta) - y)

    def jacobian(theta: np.ndarray) -> np.ndarray:
        return w[:, None] * ev.sensitivities(theta)

    lo = np.array([float(k.to_theta(k.low)) if not (k.log and k.low == 0) else -np.inf for k in keys])
    hi = np.array([float(k.to_theta(k.high)) for k in keys])
    x0 = np.array([float(k.to_theta(k.start)) for k in keys])
    try:
        with np.errstate(divide="ignore"):
            sol = least_squares(residual, x0, jac=jacobian, bounds=(lo, hi), x_scale="jac", method="trf",
                                xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=200)
    except PressfitError as exc:  # a trial value the schema or the model refuses
        raise CalibrationError(f"did not converge: a trial value was refused ({exc})",
                               residual=float("nan"), keys=[k.key for k in keys]) from None
    if sol.status <= 0 or not np.all(np.isfinite(sol.x)):
        raise CalibrationError(f"did not converge ({sol.message.rstrip('.')}, {sol.nfev} evaluations)",
                               residual=float(np.linalg.norm(sol.fun)), keys=[k.key for k in keys])
    return sol.x, sol


def calibrate(machine: Machine, keys: list[FitKey], data: Data) -> Calibration:
    """Fit ``keys`` of ``machine`` to ``data`` (module doc); raises CalibrationError when it does not converge,
    MeasurementFileError when there are fewer measured numbers than keys, ModelFileError for a key the model
    does not depend on."""
    n_res = data.measured().size
    if n_res <= len(keys):
        raise MeasurementFileError(data.deflections.path, None, None, f"{n_res} measured numbers for {len(keys)} "
                                   "fitted keys: give more rows than keys (at least one degree of freedom)")
    x0 = np.array([float(k.to_theta(k.start)) for k in keys])
    ev = _Evaluations(machine, keys, data)
    j0 = ev.sensitivities(x0)
    for k, col in zip(keys, j0.T, strict=True):
        if not np.any(np.abs(col) > 1e-12 * np.abs(j0).max()):
            raise ModelFileError(machine.source, k.key, "a key the static model's predictions depend on (the "
                                 "condensed model does not use it: it cannot be fitted from these data)")
    theta, sol = _fit(machine, keys, data, ev)
    return _statistics(machine, keys, data, theta, sol, ev)


def _statistics(machine: Machine, keys: list[FitKey], data: Data, theta: np.ndarray, sol: Any,
                ev: _Evaluations) -> Calibration:
    fitted = machine_with(machine, keys, values_of(keys, theta))
    w, y = data.weights(), data.measured()
    pred = ev.prediction(theta)
    r = w * (pred - y)
    jac = w[:, None] * ev.sensitivities(theta)
    n, k = r.size, len(keys)
    dof = n - k
    chi2 = float(r @ r)
    info = jac.T @ jac
    cov = np.linalg.pinv(info)
    stated = data.stated_sigma
    if not stated:
        cov = cov * chi2 / dof
    se = np.sqrt(np.diag(cov))
    q = float(stats.norm.ppf(0.5 + LEVEL / 2) if stated else stats.t.ppf(0.5 + LEVEL / 2, dof))
    corr = cov / np.outer(se, se)
    scale = np.linalg.norm(jac, axis=0)
    sv = np.linalg.svd(jac / scale, compute_uv=False)
    condition = float((sv[0] / sv[-1]) ** 2) if sv[-1] > 0 else math.inf
    values = values_of(keys, theta)
    estimates = [KeyEstimate(key=kk.key, start=kk.start, value=float(v),
                             standard_error=float(s * v if kk.log else s), interval_low=float(kk.from_theta(t - q * s)),
                             interval_high=float(kk.from_theta(t + q * s)), log_space=kk.log)
                 for kk, v, t, s in zip(keys, values, theta, se, strict=True)]
    return Calibration(machine=fitted, estimates=estimates, correlation=corr, condition_number=condition,
                       covariance_theta=cov, sigma_stated=stated, quantile=q, rows=len(data.deflections.pose_m),
                       residual_count=n, dof=dof, chi_square=chi2,
                       p_value=float(stats.chi2.sf(chi2, dof)) if stated else None,
                       **_residual_parts(data, pred - y), predicted=pred, measured=y,
                       unidentifiable=_unidentifiable(machine, keys, theta, corr, condition, info, data),
                       iterations=int(sol.nfev), data=data)


def _residual_parts(data: Data, diff: np.ndarray) -> dict[str, Any]:
    d = data.deflections
    m, c = len(d.pose_m), d.components
    per_row = diff[: m * c].reshape(m, c)
    trans = per_row[:, :3]
    return {"deflection_residuals_m": trans, "rotation_residuals_rad": None if c == 3 else per_row[:, 3:],
            "frequency_residuals_hz": None if data.frequencies is None else diff[m * c:],
            "rms_residual_m": float(np.sqrt(np.mean(trans**2))),
            "rms_sigma_m": None if d.sigma_m is None else float(np.sqrt(np.mean(d.sigma_m**2)))}


def _unidentifiable(machine: Machine, keys: list[FitKey], theta: np.ndarray, corr: np.ndarray, condition: float,
                    info: np.ndarray, data: Data) -> list[dict[str, Any]]:
    pairs = [(i, j) for i in range(len(keys)) for j in range(i + 1, len(keys)) if abs(corr[i, j]) > CORRELATION_LIMIT]
    if not pairs and condition > CONDITION_LIMIT and len(keys) > 1:
        i, j = np.unravel_index(np.argmax(np.abs(corr - np.eye(len(keys)))), corr.shape)
        pairs = [(int(min(i, j)), int(max(i, j)))]
    fitted = machine_with(machine, keys, values_of(keys, theta))
    sigma = data.deflections.sigma_m
    sigma_m = float(np.sqrt(np.mean(sigma**2))) if sigma is not None else 1.0  # info is in 1 / m^2 then
    return [{"keys": [keys[i].key, keys[j].key], "correlation": float(corr[i, j]),
             "separated_by": separating_measurement(fitted, [keys[i], keys[j]], info[np.ix_([i, j], [i, j])],
                                                    sigma_m)} for i, j in pairs]


def calibrate_files(machine_path: str | Path, measurements_path: str | Path, fit: list[str],
                    modes_path: str | Path | None = None) -> Calibration:
    """``pressfit calibrate``: load the machine, read and check the measurements (and modes), check the keys
    (:func:`pressfit.studies.calibration_model.parse_fit_keys`), fit. Every bad input is a PressfitError naming
    the file, the row and the column or key."""
    machine = load_machine(machine_path)
    keys = parse_fit_keys(machine, fit)
    deflections = read_deflections(machine, measurements_path)
    modes = None if modes_path is None else read_frequencies(machine, modes_path)
    return calibrate(machine, keys, Data(deflections=deflections, frequencies=modes))
