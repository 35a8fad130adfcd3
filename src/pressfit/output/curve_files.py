"""Files of the press-fit curve monitor: ``windows.json``, the verdicts as text, JSON and JUnit XML, and the
figure of the curves over the band and the evaluation objects (all written atomically, :mod:`.files`)."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pressfit.description.monitor_windows import Envelope, MaxForce, Threshold, Window, Windows
from pressfit.output import files as io
from pressfit.output.curve import curve_columns

if TYPE_CHECKING:
    from pressfit.studies.curve_check import CurveVerdict
    from pressfit.studies.joint_curves import JointCurves


def windows_document(windows: Windows) -> dict[str, Any]:
    """The JSON-ready ``windows.json`` content (NaN of the band as null)."""
    return json.loads(io.to_json(windows.model_dump(mode="python")))


def write_windows(path: Path | str, windows: Windows, overwrite: bool = False) -> Path:
    return io.write_json(path, windows_document(windows), overwrite)


def _where(x_m: float | None, y_n: float | None) -> str:
    return "" if x_m is None else f" at x = {x_m:.6g} m, y = {y_n:.6g} N"


def verdict_line(v: CurveVerdict) -> str:
    """``OK  path (name)`` or ``NOK path (name): element 'press_in' (window): <reason> at x = .. m, y = .. N``
    (and how many more elements failed)."""
    head = f"{v.path} ({v.name})"
    if v.passed:
        return f"OK  {head}"
    first, more = v.failures[0], len(v.failures) - 1
    return (f"NOK {head}: element '{first.element}' ({first.kind}): {first.reason}{_where(first.x_m, first.y_n)}"
            + (f" (+{more} more element{'s' if more > 1 else ''} failed: "
               + ", ".join(r.element for r in v.failures[1:]) + ")" if more else ""))


def verdicts_json(verdicts: Sequence[CurveVerdict], windows_path: str) -> dict[str, Any]:
    return {"windows": windows_path, "curves": len(verdicts), "nok": sum(not v.passed for v in verdicts),
            "results": [{"path": v.path, "name": v.name, "ok": v.passed,
                         "compliance_m_per_n": v.compliance_m_per_n,
                         "elements": [{"element": r.element, "kind": r.kind, "ok": r.passed, "reason": r.reason,
                                       "x_m": r.x_m, "y_n": r.y_n} for r in v.results]} for v in verdicts]}


def junit_xml(verdicts: Sequence[CurveVerdict], windows_path: str) -> str:
    """JUnit XML: one test suite, one test case per curve (a failure for a NOK curve, its message the first failed
    element, its text every failed element)."""
    import xml.etree.ElementTree as ET

    root = ET.Element("testsuites", name="pressfit curves check")
    suite = ET.SubElement(root, "testsuite", name=windows_path, tests=str(len(verdicts)),
                          failures=str(sum(not v.passed for v in verdicts)), errors="0")
    for v in verdicts:
        tc = ET.SubElement(suite, "testcase", classname=windows_path, name=f"{v.path} ({v.name})", file=v.path)
        if not v.passed:
            text = "\n".join(f"{r.element} ({r.kind}): {r.reason}{_where(r.x_m, r.y_n)}" for r in v.failures)
            ET.SubElement(tc, "failure", message=verdict_line(v)).text = text
    return ET.tostring(root, encoding="unicode", xml_declaration=True)


def curves_figure(curves: Sequence[tuple[str, np.ndarray, np.ndarray, bool]], windows: Windows,
                  ax: Any = None) -> Any:
    """The curves ((label, displacement m, force N, ok)) over the band and the evaluation objects, in mm and N (on
    the matplotlib axes ``ax`` if given, else a new figure); returns the figure."""
    from pressfit.output import plots  # noqa: F401, I001  (the Agg backend, before pyplot)
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    if ax is None:
        fig, ax = plt.subplots(figsize=(8, 5), layout="constrained")
    fig = ax.figure
    mm = 1e3
    if windows.band is not None:
        g, f = np.array(windows.band.grid_m) * mm, np.array(windows.band.force_n, dtype=float)
        ax.fill_between(g, f[0], f[-1], color="0.85", label=f"band q{windows.band.quantiles[0]:g}-"
                        f"q{windows.band.quantiles[-1]:g} ({windows.band.samples} curves)")
        ax.plot(g, f[len(f) // 2], color="0.5", lw=0.8, ls="--", label=f"q{windows.band.quantiles[len(f) // 2]:g}")
    for el in windows.elements:
        if isinstance(el, Envelope):
            x = np.array(el.displacement_m) * mm
            ax.plot(x, el.lower_force_n, color="tab:blue", lw=0.8)
            ax.plot(x, el.upper_force_n, color="tab:blue", lw=0.8, label=f"envelope '{el.name}'")
        elif isinstance(el, Window):
            ax.add_patch(Rectangle((el.x_min_m * mm, el.y_min_n), (el.x_max_m - el.x_min_m) * mm,
                                   el.y_max_n - el.y_min_n, fill=False, ec="tab:green", lw=1.5,
                                   label=f"window '{el.name}' ({el.entry} -> {el.exit})"))
        elif isinstance(el, Threshold):
            ax.plot([el.x_min_m * mm, el.x_max_m * mm], [el.force_n] * 2, lw=1.5,
                    color="tab:purple" if el.mode == "must_cross" else "tab:orange",
                    label=f"threshold '{el.name}' ({el.mode.replace('_', ' ')})")
        elif isinstance(el, MaxForce):
            ax.axhline(el.force_n, color="tab:red", lw=0.8, ls=":", label=f"max_force '{el.name}'")
    for label, x, f, ok in curves:
        ax.plot(np.asarray(x) * mm, f, lw=1.2, color="k" if ok else "tab:red",
                label=f"{label}: {'OK' if ok else 'NOK'}")
    ax.set(xlabel="displacement [mm]", ylabel="force [N]", title=windows.name or "press-fit curves")
    if not math.isclose(ax.get_ylim()[0], 0.0):
        ax.set_ylim(bottom=min(0.0, ax.get_ylim()[0]))
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(alpha=0.3)
    return fig


def write_check_outputs(verdicts: Sequence[CurveVerdict],
                        strokes: Sequence[tuple[str, np.ndarray, np.ndarray, bool]], windows: Windows,
                        windows_path: str, *, json_path: Path | None = None, junit_path: Path | None = None,
                        png_path: Path | None = None, overwrite: bool = False) -> list[Path]:
    """Write the outputs asked for (each atomically, refusing to replace a file without ``overwrite``); the
    figure shows each curve's forward stroke as judged (``strokes``: name, displacement m, force N, passed;
    :func:`pressfit.studies.curve_check.judged_strokes`)."""
    out: list[Path] = []
    if json_path is not None:
        out.append(io.write_json(json_path, verdicts_json(verdicts, windows_path), overwrite))
    if junit_path is not None:
        out.append(io.write_text(junit_path, junit_xml(verdicts, windows_path) + "\n", overwrite))
    if png_path is not None:
        import matplotlib.pyplot as plt

        fig = curves_figure(strokes, windows)
        try:
            out.append(io.save_figure(fig, png_path, overwrite))
        finally:
            plt.close(fig)
    return out


def write_band_csv(path: Path | str, band: Any, overwrite: bool = False) -> Path:
    """``band.csv``: per grid displacement ``displacement_m`` (m) the curves reaching it (``count``) and one force
    column per quantile ``force_q<q>_n`` (N; empty where no curve reaches). ``band``: a
    :class:`pressfit.studies.curve_band.CurveBand`."""
    header = ["displacement_m", "count", *[f"force_q{q:g}_n" for q in band.quantiles]]
    rows = ([float(x), int(c), *[("" if not math.isfinite(v) else float(v)) for v in band.force_n[:, j]]]
            for j, (x, c) in enumerate(zip(band.grid_m, band.count, strict=True)))
    return io.write_csv(path, header, rows, overwrite)


def write_curve_study(directory: Path, windows: Windows, band: Any,
                      nominal: tuple[np.ndarray, np.ndarray] | None = None) -> list[Path]:
    """``pressfit study curve``'s files in ``directory``: windows.json (the evaluation objects and the band),
    band.csv (:func:`write_band_csv`) and band.png (the band, the windows and the ``nominal`` curve, sensed
    displacement m and force N, if given)."""
    import matplotlib.pyplot as plt

    out = [write_windows(directory / "windows.json", windows), write_band_csv(directory / "band.csv", band)]
    fig = curves_figure([] if nominal is None else [("nominal", nominal[0], nominal[1], True)], windows)
    try:
        out.append(io.save_figure(fig, directory / "band.png"))
    finally:
        plt.close(fig)
    return out


BOARD_PIN_COLUMNS = ("index", "x_m", "z_m", "machine_compliance_along_press_m_per_n", "peak_force_n",
                     "sensed_minus_true_depth_at_peak_m", "max_depth_m", "force_limit_n")  # board_pins.csv
JOINT_CURVE_KEYS = ("peak_force_n", "plateau_force_n", "final_force_n", "seating_depth_m",
                    "sensed_minus_true_depth_at_peak_m", "machine_compliance_along_press_m_per_n", "tool_tilt_max_rad",
                    "max_pin_depth_spread_m", "all_pins_seated")  # the pin case's figures the report shows


def joint_figure(joint: JointCurves) -> Any:
    """The report's joint figure: left, the pin case's nominal curve against the true and the sensed depth over its
    band and windows (sensed), mm and N; right, each board pin's force (N) against its sensed minus true depth (um:
    the skew of its sensed curve, whose true curve is every pin's), coloured by the machine's compliance along the
    press at its pose."""
    from pressfit.output import plots  # noqa: F401, I001  (the Agg backend, before pyplot)
    import matplotlib.pyplot as plt
    from matplotlib import cm, colors

    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 5), layout="constrained")
    c, mm = joint.curve, 1e3
    curves_figure([], joint.windows, ax=left)
    left.plot(c.depth_m * mm, c.force_n, color="tab:blue", ls="--", lw=1.2, label="nominal, true depth")
    left.plot(c.sensed_depth_m * mm, c.force_n, color="k", lw=1.2, label="nominal, sensed depth (encoders)")
    left.legend(fontsize=7, loc="upper left")
    left.set(xlabel="depth [mm] (band and windows: sensed)", title=f"{joint.case_name}: predicted curve, band of "
             f"{joint.study.band.samples} samples, windows")
    compliance = np.array([p.curve.machine_compliance_along_press_m_per_n for p in joint.board])
    norm = colors.Normalize(float(compliance.min()), float(compliance.max()) * (1 + 1e-12))
    named = {int(np.argmin(compliance)): "stiffest", int(np.argmax(compliance)): "most compliant"}
    for i, (p, k) in enumerate(zip(joint.board, compliance, strict=True)):
        right.plot((p.curve.sensed_depth_m - p.curve.depth_m) * 1e6, p.curve.force_n, color=cm.viridis(norm(k)),
                   lw=1.2, label=f"pin {p.index} ({p.x_m:g}, {p.z_m:g}) m: {named[i]}" if i in named else None)
    fig.colorbar(cm.ScalarMappable(norm=norm, cmap="viridis"), ax=right,
                 label="compliance along the press at the pin [m/N]")
    right.set(xlabel="sensed minus true depth [um] (the press's deflection)", ylabel="force [N]",
              title=f"{joint.board_name}: {len(joint.board)} pins, each at its pose (one true curve)")
    right.legend(fontsize=7, loc="upper left")
    right.grid(alpha=0.3)
    return fig


def write_joint_files(joint: JointCurves, directory: Path, overwrite: bool = False) -> list[Path]:
    """The report's joint files in ``directory``: curve.csv (the pin case's nominal curve, :func:`curve_columns`),
    windows.json and band.csv (:func:`write_band_csv`), board_pins.csv (``BOARD_PIN_COLUMNS``), board_curves.csv
    (per pin and depth: true depth m, sensed depth m, force N), joint.json (the summaries) and joint.png
    (:func:`joint_figure`)."""
    import matplotlib.pyplot as plt

    c = joint.curve
    rows = ([d, x, f, *pf, *pd] for d, x, f, pf, pd in zip(c.depth_m, c.sensed_depth_m, c.force_n, c.pin_forces_n,
                                                             c.pin_depths_m, strict=True))
    pins = [p.summary() for p in joint.board]
    board_rows = ([p.index, d, x, f] for p in joint.board
                  for d, x, f in zip(p.curve.depth_m, p.curve.sensed_depth_m, p.curve.force_n, strict=True))
    out = [io.write_csv(directory / "curve.csv", curve_columns(c.pin_forces_n.shape[1]), rows, overwrite),
           write_windows(directory / "windows.json", joint.windows, overwrite),
           write_band_csv(directory / "band.csv", joint.study.band, overwrite),
           io.write_csv(directory / "board_pins.csv", BOARD_PIN_COLUMNS,
                        ([p[k] for k in BOARD_PIN_COLUMNS] for p in pins), overwrite),
           io.write_csv(directory / "board_curves.csv", ["index", "depth_m", "sensed_depth_m", "force_n"], board_rows,
                        overwrite),
           io.write_json(directory / "joint.json", {"case": joint.case_name, "curve": c.summary(),
                                                    "band_samples": joint.study.band.samples,
                                                    "board": joint.board_name, "board_pins": pins}, overwrite)]
    fig = joint_figure(joint)
    try:
        out.append(io.save_figure(fig, directory / "joint.png", overwrite))
    finally:
        plt.close(fig)
    return out
