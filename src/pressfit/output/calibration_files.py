"""The calibration's files: results.json, residuals.csv, predicted_vs_measured.png, the calibrated machine file,
and its Markdown summary (:mod:`pressfit.studies.calibration` computes; this module formats and writes).

The calibrated machine file is the input file's own tables with the fitted keys replaced (every other key as the
owner wrote it; TOML comments are not kept) and its description extended by the calibration's source.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import tomli_w

from pressfit.description.machine import read_toml
from pressfit.errors import PressfitError
from pressfit.output import files as io

if TYPE_CHECKING:
    from pressfit.studies.calibration import Calibration
    from pressfit.studies.measurement_plan import MeasurementPlan

RESULTS = "results.json"
RESIDUALS = "residuals.csv"
PLOT = "predicted_vs_measured.png"


def to_dict(cal: Calibration) -> dict[str, Any]:
    """JSON-ready results (SI units of each key; residuals predicted - measured)."""
    d = cal.data.deflections
    return {
        "model": "condensed linear (pressfit.mechanics.condensed.solve_linear); first frequencies: "
                 "pressfit.dynamics.modes.natural_modes",
        "sigma": "stated: covariance (J^T W J)^-1, normal quantile" if cal.sigma_stated
                 else "not stated: covariance scaled by the reduced chi-square, Student's t quantile",
        "quantile_95": cal.quantile,
        "estimates": [{"key": e.key, "start": e.start, "value": e.value, "standard_error": e.standard_error,
                       "interval_95": [e.interval_low, e.interval_high],
                       "space": "log (interval from ln value, transformed back)" if e.log_space else "linear"}
                      for e in cal.estimates],
        "keys": [e.key for e in cal.estimates], "correlation": cal.correlation.tolist(),
        "condition_number": cal.condition_number,
        "not_separately_identifiable": cal.unidentifiable,
        "rows": cal.rows, "residuals": cal.residual_count, "degrees_of_freedom": cal.dof,
        "chi_square": cal.chi_square, "reduced_chi_square": cal.chi_square / cal.dof, "p_value": cal.p_value,
        "rms_residual_m": cal.rms_residual_m, "rms_sigma_m": cal.rms_sigma_m, "evaluations": cal.iterations,
        "measurements": d.path, "machine": cal.machine.source,
    }


def warnings(cal: Calibration) -> list[str]:
    """One line per pair of keys the data cannot separate, with the measurement that would."""
    out = []
    for u in cal.unidentifiable:
        s = u["separated_by"]
        pose = ", ".join(f"{v:.3f}" for v in s["pose_m"])
        direction = ", ".join(f"{v:.3f}" for v in s["load_direction"])
        out.append(f"warning: {u['keys'][0]} and {u['keys'][1]} are not separately identifiable from these data "
                   f"(correlation {u['correlation']:+.4f}, condition number {cal.condition_number:.3g}); a load "
                   f"of {s['load_n']:g} N along ({direction}) at pose ({pose}) m would bring it to "
                   f"{s['correlation_after']:+.3f}")
    return out


def to_markdown(cal: Calibration) -> str:
    """The calibration as a Markdown section (values, intervals, residuals, chi-square, warnings)."""
    r = to_dict(cal)
    lines = ["| key | start | fitted | standard error | 95% interval |", "|---|---|---|---|---|"]
    lines += [f"| `{e['key']}` | {e['start']:.6g} | {e['value']:.6g} | {e['standard_error']:.3g} | "
              f"[{e['interval_95'][0]:.6g}, {e['interval_95'][1]:.6g}] |" for e in r["estimates"]]
    sigma = "" if cal.rms_sigma_m is None else f" against a stated RMS sigma of {cal.rms_sigma_m:.3g} m"
    p = "" if cal.p_value is None else f", p-value {cal.p_value:.3g}"
    lines += ["", f"{cal.rows} rows, {cal.residual_count} residuals, {cal.dof} degrees of freedom; RMS translation "
              f"residual {cal.rms_residual_m:.3g} m{sigma}; chi-square {cal.chi_square:.4g} "
              f"(reduced {cal.chi_square / cal.dof:.3g}{p}). Sigma: {r['sigma']} ({cal.quantile:.4f}).",
              "", "Correlation: " + ("; ".join(f"{a} / {b} {cal.correlation[i, j]:+.3f}" for i, a in
                                               enumerate(r["keys"]) for j, b in enumerate(r["keys"]) if j > i)
                                     or "one key.")]
    return "\n".join(lines + [""] + warnings(cal)) + "\n"


def _residual_rows(cal: Calibration) -> tuple[list[str], list[list[Any]]]:
    d = cal.data.deflections
    pred = cal.predicted[: len(d.pose_m) * d.components].reshape(len(d.pose_m), d.components)
    header = ["line", "x_m", "y_m", "z_m", "fx_n", "fy_n", "fz_n", "pred_dx_m", "pred_dy_m", "pred_dz_m",
              "res_dx_m", "res_dy_m", "res_dz_m", "sigma_m"]
    rows = [[int(line), *h, *f, *p[:3], *res, "" if d.sigma_m is None else d.sigma_m[i]]
            for i, (line, h, f, p, res) in enumerate(zip(d.lines, d.pose_m, d.load_n, pred,
                                                         cal.deflection_residuals_m, strict=True))]
    return header, rows


def _plot(cal: Calibration, path: Path) -> Path:
    d = cal.data.deflections
    n = len(d.pose_m) * d.components
    meas = cal.measured[:n].reshape(len(d.pose_m), d.components)[:, :3]
    pred = cal.predicted[:n].reshape(len(d.pose_m), d.components)[:, :3]
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4.5), layout="constrained")
    try:
        for i, name in enumerate("xyz"):
            ax.scatter(meas[:, i] * 1e6, pred[:, i] * 1e6, s=12, label=f"d{name}")
            bx.scatter(np.arange(len(meas)) + 1, (pred[:, i] - meas[:, i]) * 1e6, s=12, label=f"d{name}")
        lim = np.abs(np.concatenate([meas, pred])).max() * 1e6 * 1.05
        ax.plot([-lim, lim], [-lim, lim], "k-", lw=0.8)
        ax.set(xlabel="measured translation (um)", ylabel="predicted translation (um)",
               title="calibrated model vs measurement", aspect="equal")
        if cal.rms_sigma_m is not None:
            bx.axhspan(-2e6 * cal.rms_sigma_m, 2e6 * cal.rms_sigma_m, color="0.9", zorder=0, label="+-2 sigma (RMS)")
        bx.set(xlabel="row", ylabel="residual, predicted - measured (um)", title="residuals")
        ax.legend()
        bx.legend()
        return io.save_figure(fig, path)
    finally:
        plt.close(fig)


def calibrated_machine_toml(cal: Calibration, machine_path: Path | str) -> str:
    """The input machine file with the fitted keys replaced (module doc), as TOML text."""
    data = read_toml(machine_path)
    for e in cal.estimates:
        node = data
        *tables, last = e.key.split(".")
        for t in tables:
            node = node.setdefault(t, {})
        node[last] = e.value
    note = (f"calibrated by pressfit calibrate from {cal.data.deflections.path}: "
            + ", ".join(f"{e.key} = {e.value:.6g} [{e.interval_low:.6g}, {e.interval_high:.6g}] (95%)"
                        for e in cal.estimates))
    data["description"] = f"{data.get('description', '')} ({note})".strip()
    return tomli_w.dumps(data)


def calibrated_name(machine_path: Path | str) -> str:
    return f"{Path(machine_path).stem}_calibrated.toml"


def write_calibration(cal: Calibration, machine_path: Path | str, out: Path) -> list[Path]:
    """Every file of a calibration into the directory ``out`` (fresh: :func:`pressfit.output.files.write_directory`)."""
    return [io.write_json(out / RESULTS, to_dict(cal)), io.write_csv(out / RESIDUALS, *_residual_rows(cal)),
            _plot(cal, out / PLOT), io.write_text(out / calibrated_name(machine_path),
                                                  calibrated_machine_toml(cal, machine_path)),
            io.write_text(out / "calibration.md", to_markdown(cal))]


def plan_markdown(plan: MeasurementPlan) -> str:
    """The measurement plan as a CSV block to fill in (the measurement file's columns) and the predicted errors."""
    d = plan.to_dict()
    lines = ["x_m,y_m,z_m,fx_n,fy_n,fz_n,dx_m,dy_m,dz_m,sigma_m"]
    lines += [f"{m['x_m']:.4f},{m['y_m']:.4f},{m['z_m']:.4f},{m['fx_n']:.1f},{m['fy_n']:.1f},{m['fz_n']:.1f},,,,"
              f"{plan.sigma_m:g}" for m in d["measurements"]]
    lines += ["", f"D-optimal over the required workspace (greedy log det); predicted standard errors with sigma "
              f"{plan.sigma_m:g} m per translation:"]
    lines += [f"  {s['key']}: " + (f"{100 * s['relative']:.3g}% (relative)" if "relative" in s
                                   else f"{s['absolute']:.3g} (absolute)") for s in d["predicted_standard_error"]]
    return "\n".join(lines) + "\n"


def read_calibration(directory: Path | str) -> dict[str, Any]:
    """The results.json of a ``pressfit calibrate --out`` directory, for the report; a missing or malformed one is
    a PressfitError naming the file."""
    path = Path(directory) / RESULTS
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(data, dict) or not all(k in data for k in ("estimates", "keys", "chi_square")):
            raise ValueError("no estimates, keys or chi_square")
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise PressfitError(f"{path}: not the results.json of a pressfit calibrate run ({exc})") from None
    return data


def report_section(results: dict[str, Any], directory: Path | str) -> list[str]:
    """The report's calibration section (``pressfit report --calibration DIR``) from a run's results.json."""
    md = ["## Calibration (issue 31: `pressfit calibrate`)", "",
          f"The machine fitted to the measurements `{results.get('measurements')}` (run directory `{directory}`); "
          f"model: {results.get('model')}. Sigma: {results.get('sigma')}.", "",
          "| key | start | fitted | standard error | 95% interval |", "|---|---|---|---|---|"]
    md += [f"| `{e['key']}` | {e['start']:.6g} | {e['value']:.6g} | {e['standard_error']:.3g} | "
           f"[{e['interval_95'][0]:.6g}, {e['interval_95'][1]:.6g}] |" for e in results["estimates"]]
    sigma = results.get("rms_sigma_m")
    p = results.get("p_value")
    md += ["", f"{results.get('rows')} rows, {results.get('degrees_of_freedom')} degrees of freedom; RMS translation "
           f"residual {results.get('rms_residual_m', float('nan')):.3g} m"
           + ("" if sigma is None else f" against a stated RMS sigma of {sigma:.3g} m")
           + f"; chi-square {results['chi_square']:.4g}" + ("" if p is None else f" (p-value {p:.3g})") + ". "
           f"Residuals per row: `{Path(directory) / RESIDUALS}`; predicted against measured: "
           f"`{Path(directory) / PLOT}`.", ""]
    md += [f"Not separately identifiable: {u['keys'][0]} and {u['keys'][1]} (correlation {u['correlation']:+.4f})."
           for u in results.get("not_separately_identifiable", [])]
    return md + [""]
