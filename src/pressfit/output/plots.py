"""Shared matplotlib helpers (Agg backend): x-z workspace maps and per-leg bar charts, written
atomically through :mod:`pressfit.io` (no silent overwrite)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib import ticker

from pressfit.output import files as io

Fields = dict[str, tuple[np.ndarray, str]]  # CSV column and panel title -> (values, colour-bar label, e.g. the unit)


def _grid(n: int) -> tuple[int, int]:
    cols = min(n, 3)
    return math.ceil(n / cols), cols


def xz_map_figure(x_m: np.ndarray, z_m: np.ndarray, fields: Fields, title: str) -> plt.Figure:
    """One filled-contour panel per field over the x-z plane; each field is indexed [i_z, i_x]
    (NaN = not reachable, left blank). ``fig.axes[k]`` is the panel of the k-th field."""
    rows, cols = _grid(len(fields))
    fig, axes = plt.subplots(rows, cols, figsize=(5.6 * cols, 4.4 * rows), squeeze=False, layout="constrained")
    fig.get_layout_engine().set(wspace=0.15)
    for ax, (name, (values, label)) in zip(axes.flat, fields.items(), strict=False):
        v = np.asarray(values, dtype=float)
        if np.any(np.isfinite(v)) and np.nanmax(v) > np.nanmin(v):
            wide = np.nanmin(v) > 0 and np.nanmax(v) > 100 * np.nanmin(v)  # > 2 decades: log colours
            cs = ax.contourf(x_m, z_m, v, levels=20, cmap="viridis", **({"locator": ticker.LogLocator(subs="all")}
                                                                        if wide else {}))
            ax.contour(cs, levels=cs.levels[::4], colors="k", linewidths=0.4)
            # an inset colour bar is a child of its panel: fig.axes stays the list of panels, in order
            fig.colorbar(cs, cax=ax.inset_axes((1.04, 0.0, 0.05, 1.0)), label=label, format="%.3g")
        else:
            ax.text(0.5, 0.5, f"constant {np.nanmax(v) if np.any(np.isfinite(v)) else 'NaN'}",
                    ha="center", transform=ax.transAxes)
        ax.set(title=name, xlabel="x [m]", ylabel="z [m]", aspect="equal")
    for ax in list(axes.flat)[len(fields):]:
        ax.set_visible(False)
    fig.suptitle(title)
    return fig


def write_xz_maps(out_dir: Path | str, stem: str, x_m: np.ndarray, z_m: np.ndarray, fields: Fields,
                  title: str, overwrite: bool = False, figures: bool = True) -> list[Path]:
    """``<stem>.png`` (one panel per field; not with ``figures=False``) and ``<stem>.csv`` (columns x_m, z_m,
    one per field)."""
    out = Path(out_dir)
    zz, xx = np.meshgrid(z_m, x_m, indexing="ij")
    cols = [np.asarray(v, dtype=float).ravel() for v, _ in fields.values()]
    rows = zip(xx.ravel(), zz.ravel(), *cols, strict=True)
    paths = [io.write_csv(out / f"{stem}.csv", ["x_m", "z_m", *fields], rows, overwrite)]
    if not figures:
        return paths
    fig = xz_map_figure(x_m, z_m, fields, title)
    try:
        paths.append(io.save_figure(fig, out / f"{stem}.png", overwrite))
    finally:
        plt.close(fig)
    return paths


def leg_bars_figure(fields: Fields, title: str) -> plt.Figure:
    """One bar chart panel per field, one bar per leg (values of shape (n_legs,)), each bar annotated."""
    rows, cols = _grid(len(fields))
    fig, axes = plt.subplots(rows, cols, figsize=(4.0 * cols, 3.2 * rows), squeeze=False)
    for ax, (name, (values, label)) in zip(axes.flat, fields.items(), strict=False):
        v = np.asarray(values, dtype=float)
        legs = np.arange(1, v.size + 1)
        ax.bar(legs, v, color="tab:blue")
        for i, val in zip(legs, v, strict=True):
            ax.annotate(f"{val:.4g}", (i, val), ha="center", va="bottom", fontsize=7)
        ax.set(title=name, xlabel="leg", ylabel=label, xticks=legs)
    for ax in list(axes.flat)[len(fields):]:
        ax.set_visible(False)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def write_leg_bars(path: Path | str, fields: Fields, title: str, overwrite: bool = False) -> Path:
    """:func:`leg_bars_figure` written to ``path``."""
    fig = leg_bars_figure(fields, title)
    try:
        return io.save_figure(fig, path, overwrite)
    finally:
        plt.close(fig)


def write_residual_bars(path: Path | str, labels: list[str], series: dict[str, np.ndarray], title: str,
                        overwrite: bool = False) -> Path:
    """Grouped horizontal bars of |residual| / sigma per entry (log scale), one colour per series."""
    fig, ax = plt.subplots(figsize=(7.0, 0.18 * len(labels) + 1.5))
    try:
        y = np.arange(len(labels))
        h = 0.8 / len(series)
        for k, (name, values) in enumerate(series.items()):
            ax.barh(y + k * h, np.maximum(np.abs(values), 1e-3), height=h, label=name)
        ax.set_xscale("log")
        ax.set(yticks=y + 0.4 - h / 2, title=title, xlabel="|residual| / sigma (printed rounding)")
        ax.set_yticklabels(labels, fontsize=6)
        ax.axvline(1.0, color="k", lw=0.6)
        ax.invert_yaxis()
        ax.legend(fontsize=7)
        fig.tight_layout()
        return io.save_figure(fig, path, overwrite)
    finally:
        plt.close(fig)
