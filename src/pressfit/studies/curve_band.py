"""The tolerance band of press-fit curves and the monitor's windows derived from it (docs/monitor.md).

Generic in the curve: a curve is a pair of arrays (displacement m, force N) in stroke order, from a
measurement, a model or :class:`AnalyticPin` (a closed-form linear-then-plateau pin with a seating rise, the
stand-in until the joint model provides its predicted curve).

* :func:`band_from_curves`: each curve's forward stroke (to its largest displacement) interpolated linearly onto a
  common displacement grid (NaN beyond the curve's range); per grid point the force quantiles (numpy's default
  ``linear`` method) over the curves that reach it, and their count.
* :func:`windows_from_band`: the evaluation objects (``max_force``, ``no_early_force``, ``press_in``, ``seated``,
  ``envelope``), by the rules of docs/monitor.md, "Windows from a band".
* :func:`curve_band_study`: a Monte Carlo over tolerances (each a :class:`~pressfit.description.cases.Distribution`)
  on the Dask runner (:mod:`pressfit.studies.distributed`: a local cluster by default, ``workers``, ``scheduler``)
  or serially; the draws of a sample depend on its chunk only (``SeedSequence(seed, spawn_key=(k,))``), so a run
  on any number of workers, or serially, gives the same band.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pressfit.description.cases import Distribution
from pressfit.description.monitor_windows import SCHEMA_VERSION, Band, Envelope, MaxForce, Threshold, Window, Windows
from pressfit.errors import PressfitError

DEFAULT_QUANTILES = (0.00135, 0.5, 0.99865)  # the normal distribution's +-3 sigma and its median
GRID_POINTS = 201
GRID_EXTENSION = 0.25  # the study's default grid reaches 25% beyond the nominal curve's stroke
CurveFunction = Callable[[dict[str, float]], tuple[np.ndarray, np.ndarray]]


@dataclass(frozen=True, kw_only=True)
class CurveBand:
    """Force quantiles over a displacement grid: ``grid_m`` (G,) m, ``quantiles`` (Q,), ``force_n`` (Q, G) N
    (NaN where no curve reaches the grid point), ``count`` (G,) the curves that reach each point, ``samples`` the
    number of curves."""

    grid_m: np.ndarray
    quantiles: np.ndarray
    force_n: np.ndarray
    count: np.ndarray
    samples: int

    def quantile(self, q: float) -> np.ndarray:
        """The force curve (G,) N of quantile ``q`` (one of ``quantiles``)."""
        k = np.flatnonzero(np.isclose(self.quantiles, q, rtol=0, atol=1e-12))
        if not k.size:
            have = ", ".join(f"{v:g}" for v in self.quantiles)
            raise PressfitError(f"the band has no quantile {q:g} (it has {have})")
        return self.force_n[int(k[0])]

    def to_schema(self) -> Band:
        return Band(grid_m=self.grid_m.tolist(), quantiles=self.quantiles.tolist(), force_n=self.force_n.tolist(),
                    samples=self.samples)


def forward_stroke(displacement_m: np.ndarray, force_n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The samples up to the largest displacement (m, N); the return stroke after it is dropped."""
    x, f = np.asarray(displacement_m, dtype=float), np.asarray(force_n, dtype=float)
    if x.ndim != 1 or x.shape != f.shape or x.size < 2:
        raise PressfitError(f"a curve needs matching 1-D displacement and force arrays of at least 2 points, got "
                            f"shapes {x.shape} and {f.shape}")
    k = int(np.argmax(x)) + 1
    return x[:k], f[:k]


def resample(displacement_m: np.ndarray, force_n: np.ndarray, grid_m: np.ndarray) -> np.ndarray:
    """The forward stroke's force (N) at the grid's displacements (m), linear in between, NaN outside its range
    (a jitter backwards before the maximum is read as a pause: the displacement's running maximum)."""
    x, f = forward_stroke(displacement_m, force_n)
    x = np.maximum.accumulate(x)
    return np.interp(grid_m, x, f, left=math.nan, right=math.nan)


def band_from_forces(forces_n: np.ndarray, grid_m: np.ndarray,
                     quantiles: Sequence[float] = DEFAULT_QUANTILES) -> CurveBand:
    """The band of curves already on a grid: ``forces_n`` (n, G) N, NaN where a curve does not reach."""
    f = np.asarray(forces_n, dtype=float)
    q = np.asarray(quantiles, dtype=float)
    if q.ndim != 1 or not q.size or np.any((q < 0) | (q > 1)) or np.any(np.diff(q) <= 0):
        raise PressfitError(f"quantiles must be increasing numbers in [0, 1], got {list(quantiles)}")
    count = np.sum(np.isfinite(f), axis=0)
    out = np.full((q.size, f.shape[1]), math.nan)
    full = count == f.shape[0]
    if full.any():
        out[:, full] = np.quantile(f[:, full], q, axis=0)
    for j in np.flatnonzero(~full & (count > 0)):
        out[:, j] = np.quantile(f[np.isfinite(f[:, j]), j], q)
    return CurveBand(grid_m=np.asarray(grid_m, dtype=float), quantiles=q, force_n=out, count=count,
                     samples=f.shape[0])


def band_from_curves(curves: Sequence[tuple[np.ndarray, np.ndarray]], quantiles: Sequence[float] = DEFAULT_QUANTILES,
                     grid_m: np.ndarray | None = None, points: int = GRID_POINTS) -> CurveBand:
    """The band of ``curves`` ((displacement m, force N) pairs): quantiles per displacement of the grid
    ``grid_m`` (default ``points`` points from the smallest to the largest displacement of any curve)."""
    if not curves:
        raise PressfitError("a band needs at least one curve")
    strokes = [forward_stroke(x, f) for x, f in curves]
    if grid_m is None:
        lo, hi = min(float(x.min()) for x, _ in strokes), max(float(x.max()) for x, _ in strokes)
        grid_m = np.linspace(lo, hi, points)
    grid = np.asarray(grid_m, dtype=float)
    if grid.ndim != 1 or grid.size < 2 or np.any(np.diff(grid) <= 0):
        raise PressfitError("grid_m must be a strictly increasing array of at least 2 displacements (m)")
    return band_from_forces(np.stack([resample(x, f, grid) for x, f in strokes]), grid, quantiles)


# --- windows from a band ---------------------------------------------------------------------------------------
def _run_around(mask: np.ndarray, k: int) -> tuple[int, int]:
    """The first and last index of the run of True in ``mask`` that contains index k."""
    a = k
    while a > 0 and mask[a - 1]:
        a -= 1
    b = k
    while b < mask.size - 1 and mask[b + 1]:
        b += 1
    return a, b


def windows_from_band(band: CurveBand, *, lower_quantile: float | None = None, upper_quantile: float | None = None,
                      force_margin_fraction: float = 0.05, force_margin_n: float = 0.0, x_margin_m: float = 0.0,
                      peak_level: float = 0.97, press_in_end_m: float | None = None, seat_force_n: float | None = None,
                      name: str = "", source: Mapping[str, Any] | None = None) -> Windows:
    """The evaluation objects derived from ``band`` (docs/monitor.md, "Windows from a band"): lo, mid, hi the
    band's lowest (``lower_quantile``), middle (nearest 0.5) and highest (``upper_quantile``) quantile curves;
    the press-in zone the grid points every curve reaches up to ``press_in_end_m`` (m; default all); the force
    margin m = max(``force_margin_n``, ``force_margin_fraction`` x the press-in peak of mid) (N); ``x_margin_m``
    widens the thresholds' ranges; ``peak_level`` the fraction of lo's press-in peak that bounds the press-in
    window (where even the lowest curves are at their peak or plateau);
    ``seat_force_n`` the seated threshold's level (default: the press-in zone's highest hi plus m)."""
    if not 0 < peak_level < 1:
        raise PressfitError(f"peak_level must be in (0, 1), got {peak_level}")
    if force_margin_fraction < 0 or force_margin_n < 0 or x_margin_m < 0:
        raise PressfitError("the margins must be >= 0")
    x = band.grid_m
    lo = band.force_n[0] if lower_quantile is None else band.quantile(lower_quantile)
    hi = band.force_n[-1] if upper_quantile is None else band.quantile(upper_quantile)
    mid = band.force_n[int(np.argmin(np.abs(band.quantiles - 0.5)))]
    full = band.count == band.samples
    if not full.any():
        raise PressfitError("no grid point is reached by every curve of the band: give a grid within their strokes")
    zone = full & (x <= press_in_end_m) if press_in_end_m is not None else full.copy()
    if not zone.any():
        raise PressfitError(f"press_in_end_m = {press_in_end_m:g} m is before the band's first complete grid point "
                            f"({x[full][0]:g} m)")
    k_peak = int(np.flatnonzero(zone)[np.argmax(mid[zone])])
    peak = float(mid[k_peak])
    if not peak > 0:
        raise PressfitError("the band's median force is not positive in the press-in zone: no peak to window")
    m = max(force_margin_n, force_margin_fraction * peak)
    elements: list[Any] = [MaxForce(name="max_force", force_n=float(np.nanmax(hi)) + m)]
    rise = np.flatnonzero(np.isfinite(hi) & (hi > m))
    if rise.size and rise[0] > 0 and x[rise[0] - 1] - x_margin_m > x[0]:  # the last grid point before any rise
        elements.append(Threshold(name="no_early_force", force_n=m, x_min_m=float(x[0]),
                                  x_max_m=float(x[rise[0] - 1] - x_margin_m), mode="must_not_cross"))
    k_low = int(np.flatnonzero(zone)[np.argmax(lo[zone])])  # where the lowest curves are at their peak
    a, b = _run_around(zone & (lo >= peak_level * float(lo[k_low])), k_low)
    if a == b:
        a, b = max(a - 1, 0), min(b + 1, x.size - 1)
    elements.append(Window(name="press_in", x_min_m=float(x[a]), x_max_m=float(x[b]),
                           y_min_n=float(np.min(lo[a:b + 1])) - m, y_max_n=float(np.max(hi[a:b + 1])) + m,
                           entry="left", exit="right"))
    seat = float(np.max(hi[zone])) + m if seat_force_n is None else seat_force_n
    last_zone = int(np.flatnonzero(zone)[-1])
    seated = np.flatnonzero(np.isfinite(hi) & (hi >= seat) & (np.arange(x.size) > last_zone))
    if seated.size:
        elements.append(Threshold(name="seated", force_n=seat, x_min_m=float(x[seated[0]] - x_margin_m),
                                  x_max_m=float(x[-1] + max(x_margin_m, 1e-9)), mode="must_cross"))
    elements.append(Envelope(name="envelope", displacement_m=x[full].tolist(),
                             lower_force_n=(lo[full] - m).tolist(), upper_force_n=(hi[full] + m).tolist()))
    rules = {"lower_quantile": float(band.quantiles[0] if lower_quantile is None else lower_quantile),
             "upper_quantile": float(band.quantiles[-1] if upper_quantile is None else upper_quantile),
             "force_margin_n": m, "x_margin_m": x_margin_m, "peak_level": peak_level,
             "press_in_end_m": press_in_end_m, "peak_force_n": peak, "peak_displacement_m": float(x[k_peak])}
    return Windows(schema_version=SCHEMA_VERSION, name=name, elements=elements, band=band.to_schema(),
                   source={**(source or {}), "derivation": rules})


# --- a closed-form pin -----------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class AnalyticPin:
    """A closed-form press-fit curve (a picklable curve function): free travel ``approach_m``, then the force
    rising linearly over the lead-in ``lead_in_m`` to the plateau ``plateau_force_n`` (N, held while the pin
    slides), the component's shoulder reaching the board at ``seat_depth_m`` past the first contact, then the
    seating rise of ``seat_stiffness_n_per_m`` (N/m) until the press stops at ``stop_force_n`` (N); optionally
    the return stroke (``return_stroke``: back to the start, force falling linearly). ``points`` samples of the
    forward stroke. Calling it with a dict of values (keys: any field) overrides those fields."""

    approach_m: float = 0.5e-3
    lead_in_m: float = 0.4e-3
    plateau_force_n: float = 120.0
    seat_depth_m: float = 1.6e-3
    seat_stiffness_n_per_m: float = 2.0e6
    stop_force_n: float = 400.0
    points: int = 241
    return_stroke: bool = False

    def __call__(self, values: Mapping[str, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
        pin = replace(self, **dict(values or {})) if values else self
        return pin.curve()

    def force_n(self, displacement_m: np.ndarray) -> np.ndarray:
        """The forward stroke's force (N) at displacements (m) before the stop."""
        d = np.asarray(displacement_m, dtype=float) - self.approach_m
        press = self.plateau_force_n * np.clip(d / self.lead_in_m, 0.0, 1.0)
        return press + self.seat_stiffness_n_per_m * np.maximum(d - self.seat_depth_m, 0.0)

    @property
    def stop_m(self) -> float:
        """The displacement (m) where the press stops (the force reaches ``stop_force_n``)."""
        if self.stop_force_n <= self.plateau_force_n:
            raise PressfitError("stop_force_n must exceed plateau_force_n (the press stops on the seating rise)")
        return self.approach_m + self.seat_depth_m + (self.stop_force_n - self.plateau_force_n) / \
            self.seat_stiffness_n_per_m

    def curve(self) -> tuple[np.ndarray, np.ndarray]:
        if not (self.lead_in_m > 0 and self.seat_depth_m >= self.lead_in_m and self.seat_stiffness_n_per_m > 0):
            raise PressfitError("AnalyticPin needs lead_in_m > 0, seat_depth_m >= lead_in_m, seat_stiffness > 0")
        knots = [0.0, self.approach_m, self.approach_m + self.lead_in_m, self.approach_m + self.seat_depth_m,
                 self.stop_m]
        x = np.unique(np.concatenate([np.linspace(0.0, self.stop_m, self.points), knots]))
        f = self.force_n(x)
        if self.return_stroke:
            back = np.linspace(self.stop_m, 0.0, self.points // 4 + 2)[1:]
            x, f = np.concatenate([x, back]), np.concatenate([f, np.linspace(self.stop_force_n, 0.0, back.size)])
        return x, f


# --- the Monte Carlo study -------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class _BandSetup:
    curve: CurveFunction
    tolerances: tuple[tuple[str, Distribution], ...]
    grid_m: np.ndarray
    seed: int
    chunk_size: int
    samples: int


def _chunk_range(s: _BandSetup, k: int) -> tuple[int, int]:
    return k * s.chunk_size, min((k + 1) * s.chunk_size, s.samples)


def evaluate_band_chunk(setup: _BandSetup, k: int) -> dict[str, np.ndarray]:
    """Chunk k of the study: its inputs (n, T), its curves on the grid (n, G) N, each curve's peak force (N) and
    largest displacement (m). Runs on a Dask worker (or serially)."""
    start, stop = _chunk_range(setup, k)
    rng = np.random.default_rng(np.random.SeedSequence(setup.seed, spawn_key=(k,)))
    inputs = np.stack([d.draw(rng, (stop - start,)) for _, d in setup.tolerances], -1) if setup.tolerances \
        else np.zeros((stop - start, 0))
    names = [n for n, _ in setup.tolerances]
    forces = np.empty((stop - start, setup.grid_m.size))
    peak, reach = np.empty(stop - start), np.empty(stop - start)
    for i, row in enumerate(inputs):
        x, f = setup.curve({n: float(v) for n, v in zip(names, row, strict=True)})
        xs, fs = forward_stroke(x, f)
        forces[i] = resample(xs, fs, setup.grid_m)
        peak[i], reach[i] = float(np.max(fs)), float(np.max(xs))
    return {"inputs": inputs, "forces_n": forces, "peak_force_n": peak, "max_displacement_m": reach}


@dataclass(frozen=True, kw_only=True)
class CurveBandStudy:
    """The study's result: ``band``, the drawn ``inputs`` (name -> (samples,)), each sample's ``peak_force_n`` (N)
    and ``max_displacement_m`` (m), the ``seed`` and the chunks run."""

    band: CurveBand
    inputs: dict[str, np.ndarray]
    peak_force_n: np.ndarray
    max_displacement_m: np.ndarray
    seed: int
    chunks: int


def _nominal(d: Distribution) -> float:
    return float(d.mean if d.distribution != "uniform" else 0.5 * (d.low + d.high))  # type: ignore[operator]


def curve_band_study(sample_curve: CurveFunction, tolerances: Mapping[str, Distribution | Mapping[str, Any]],
                     samples: int, *, seed: int = 0, chunk_size: int = 500, grid_m: np.ndarray | None = None,
                     points: int = GRID_POINTS, quantiles: Sequence[float] = DEFAULT_QUANTILES,
                     workers: int | None = None, scheduler: str | None = None, client: Any = None,
                     serial: bool = False, progress: bool = False) -> CurveBandStudy:
    """A Monte Carlo of ``samples`` curves ``sample_curve(values)`` (a picklable function of a dict name -> value,
    returning (displacement m, force N)), each value drawn from its tolerance (a Distribution, or its table), and
    the band of the curves. ``grid_m`` default: ``points`` points from the nominal curve's first displacement
    (every tolerance at its mean, a uniform one at its middle) to ``GRID_EXTENSION`` beyond its last. On Dask
    (:func:`pressfit.studies.distributed.run_chunks`: ``workers`` local processes, ``scheduler`` a running
    cluster, or an open ``client``) unless ``serial``; the same seed gives the same band either way."""
    from pressfit.studies import distributed

    if samples < 1 or chunk_size < 1:
        raise PressfitError(f"samples and chunk_size must be at least 1, got {samples} and {chunk_size}")
    tol = tuple(sorted((n, d if isinstance(d, Distribution) else Distribution.model_validate(dict(d)))
                       for n, d in tolerances.items()))
    if grid_m is None:
        x0, _ = forward_stroke(*sample_curve({n: _nominal(d) for n, d in tol}))
        lo, hi = float(x0.min()), float(x0.max())
        grid_m = np.linspace(lo, lo + (hi - lo) * (1 + GRID_EXTENSION), points)
    setup = _BandSetup(curve=sample_curve, tolerances=tol, grid_m=np.asarray(grid_m, dtype=float), seed=seed,
                       chunk_size=chunk_size, samples=samples)
    n_chunks = -(-samples // chunk_size)
    parts: dict[int, dict[str, np.ndarray]] = {}
    if serial:
        for k in range(n_chunks):
            parts[k] = evaluate_band_chunk(setup, k)
    else:
        sizes = [_chunk_range(setup, k)[1] - _chunk_range(setup, k)[0] for k in range(n_chunks)]
        distributed.run_chunks(evaluate_band_chunk, [(k,) for k in range(n_chunks)], sizes,
                               lambda k, r: parts.__setitem__(k, r), workers=workers, scheduler=scheduler,
                               client=client, shared=setup, progress=progress, name="curve band")
    cat = {key: np.concatenate([parts[k][key] for k in range(n_chunks)]) for key in parts[0]}
    band = band_from_forces(cat["forces_n"], setup.grid_m, quantiles)
    return CurveBandStudy(band=band, inputs={n: cat["inputs"][:, j] for j, (n, _) in enumerate(tol)},
                          peak_force_n=cat["peak_force_n"], max_displacement_m=cat["max_displacement_m"], seed=seed,
                          chunks=n_chunks)
