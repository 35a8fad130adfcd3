"""Measured press-fit curves judged against a monitor's evaluation objects (``windows.json``, docs/monitor.md).

A curve is judged on its forward stroke (up to its largest displacement; the return stroke is ignored), as the
polyline through its samples (x the displacement, m; y the force, N), every element in file order; the curve
is OK when every element passes. Each element's rule (docs/monitor.md, "Verdicts"):

* ``window``: the box is closed (a point on its edge is inside). Walking the polyline, every crossing of the
  box's boundary is an entry or an exit (Liang-Barsky clipping of each segment); every entry must be through the
  ``entry`` side and every exit through the ``exit`` side; the curve must enter at least once (a curve that
  starts inside never entered), and must end outside (``exit = "none"``: must end inside, never leaving). A touch
  of an edge from outside is an entry and an exit through that edge.
* ``threshold``: over the polyline clipped to [x_min, x_max]: ``must_cross`` passes when the largest force
  there reaches the level (>=); ``must_not_cross`` fails at the first point where it exceeds it (>).
* ``envelope``: the polyline clipped to the envelope's span, at its samples and at the envelope's breakpoints,
  must satisfy lower <= y <= upper (both bounds linear between breakpoints, so no violation hides between).
* ``max_force``: the largest force of the forward stroke must not exceed the limit.

A failure names the element and the point (x, y) where it failed. ``--compensate``:
:func:`compensated_displacement` (the press's own deflection removed, compliance from
:func:`press_compliance_m_per_n`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pressfit.description.cases import Case
from pressfit.description.measured_curves import MeasuredCurve
from pressfit.description.monitor_windows import Envelope, MaxForce, Threshold, Window, Windows
from pressfit.errors import PressfitError

_SIDES = ("left", "right", "bottom", "top")


@dataclass(frozen=True, kw_only=True)
class ElementResult:
    """One element's verdict on one curve: ``element`` its name, ``kind`` its type, ``passed``, ``reason`` (""
    when passed) and the point where it failed, ``x_m`` (m) and ``y_n`` (N) (None when passed)."""

    element: str
    kind: str
    passed: bool
    reason: str = ""
    x_m: float | None = None
    y_n: float | None = None


@dataclass(frozen=True, kw_only=True)
class CurveVerdict:
    """The verdict on one measured curve: OK when every element passed; ``compliance_m_per_n`` the press
    compliance removed from its displacement (None: not compensated)."""

    path: str
    name: str
    results: tuple[ElementResult, ...]
    compliance_m_per_n: float | None = None

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.results)

    @property
    def failures(self) -> list[ElementResult]:
        return [r for r in self.results if not r.passed]


def compensated_displacement(displacement_m: np.ndarray, force_n: np.ndarray,
                             compliance_m_per_n: float) -> np.ndarray:
    """The displacement of the tool into the part (m): the measured one (the press's, m) less the press's own
    deflection, ``compliance_m_per_n`` (m/N, along the press direction) times the force (N)."""
    return np.asarray(displacement_m, dtype=float) - compliance_m_per_n * np.asarray(force_n, dtype=float)


def pin_pose_m(case: Case) -> np.ndarray:
    """The plate-centre pose (m) at the case's pin: ``[simulation.contact]``'s pin on the board face, else the
    first pin of ``[cycle]``."""
    if case.simulation is not None:
        c = case.simulation.contact
        return np.array([c.pin_position_m[0], c.board_height_m, c.pin_position_m[1]])
    if case.cycle is not None:
        pin = case.cycle.resolved_pins()[0]
        return np.array([pin.x_m, case.cycle.board_height_m, pin.z_m])
    raise PressfitError(f"{case.path}: --compensate needs the pin's pose: a [simulation.contact] or a [cycle] "
                        "table")


def press_compliance_m_per_n(case: Case) -> float:
    """The machine's compliance along the press direction (m/N) at the case's pin pose, as the drives' position
    sensors see it: C_yy of the condensed plate-centre compliance from the sensors
    (:func:`pressfit.mechanics.condensed.condensed_plate_compliance` of ``sensed_view``; the number ``pressfit
    stiffness`` prints as 1 / vertical stiffness, less a hydraulic cylinder's oil column, which its piston sensor
    reads past), the plate free to tilt. The one place the compensation's number comes from (the predicted curve's
    ``machine_compliance_along_press_m_per_n``)."""
    from pressfit.mechanics.condensed import condensed_plate_compliance

    return float(condensed_plate_compliance(case.machine().sensed_view, pin_pose_m(case))[1, 1])


# --- geometry of the polyline ----------------------------------------------------------------------------------
def _clip_segment(p0: np.ndarray, p1: np.ndarray, w: Window) -> tuple[float, float, str, str] | None:
    """Liang-Barsky: the parameter interval [t_in, t_out] of segment p0 -> p1 inside the closed box, and the
    sides through which it enters (at t_in > 0) and leaves (at t_out < 1); None if it misses the box."""
    d = p1 - p0
    t_in, t_out, side_in, side_out = 0.0, 1.0, "", ""
    for p, q, side in ((-d[0], p0[0] - w.x_min_m, "left"), (d[0], w.x_max_m - p0[0], "right"),
                       (-d[1], p0[1] - w.y_min_n, "bottom"), (d[1], w.y_max_n - p0[1], "top")):
        if p == 0.0:
            if q < 0.0:
                return None
            continue
        t = q / p
        if p < 0.0 and t > t_in:
            t_in, side_in = t, side
        elif p > 0.0 and t < t_out:
            t_out, side_out = t, side
    if t_in > t_out:
        return None
    return t_in, t_out, side_in, side_out


def _inside(p: np.ndarray, w: Window) -> bool:
    return bool(w.x_min_m <= p[0] <= w.x_max_m and w.y_min_n <= p[1] <= w.y_max_n)


def _point(p0: np.ndarray, p1: np.ndarray, t: float) -> tuple[float, float]:
    q = p0 + t * (p1 - p0)
    return float(q[0]), float(q[1])


def _clip_x(x: np.ndarray, y: np.ndarray, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
    """The points of the polyline within lo <= x <= hi, in order, with the points where it crosses lo and hi."""
    xs, ys = [], []
    for k in range(len(x) - 1):
        x0, x1, y0, y1 = x[k], x[k + 1], y[k], y[k + 1]
        a, b = 0.0, 1.0
        dx = x1 - x0
        if dx == 0.0:
            if not lo <= x0 <= hi:
                continue
        else:
            ta, tb = (lo - x0) / dx, (hi - x0) / dx
            a, b = max(a, min(ta, tb)), min(b, max(ta, tb))
            if a > b:
                continue
        for t in (a, b):
            xs.append(x0 + t * dx)
            ys.append(y0 + t * (y1 - y0))
    if len(x) == 1 and lo <= x[0] <= hi:
        xs, ys = [x[0]], [y[0]]
    return np.array(xs), np.array(ys)


def _nearest_description(x: np.ndarray, y: np.ndarray, w: Window) -> tuple[str, float, float]:
    """Why a curve that never enters the window missed it, and the point that shows it."""
    cx, cy = _clip_x(x, y, w.x_min_m, w.x_max_m)
    if cx.size == 0:
        if x.max() < w.x_min_m:
            return f"ends at x = {x[-1]:.6g} m, before the window (x >= {w.x_min_m:.6g} m)", float(x[-1]), float(y[-1])
        k = int(np.argmin(x))
        return f"starts at x = {x[k]:.6g} m, beyond the window (x <= {w.x_max_m:.6g} m)", float(x[k]), float(y[k])
    if cy.max() < w.y_min_n:
        k = int(np.argmax(cy))
        return (f"passes below the window: at most {cy[k]:.6g} N over its x range, under y_min {w.y_min_n:.6g} N",
                float(cx[k]), float(cy[k]))
    k = int(np.argmin(cy))
    return (f"passes above the window: at least {cy[k]:.6g} N over its x range, over y_max {w.y_max_n:.6g} N",
            float(cx[k]), float(cy[k]))


def check_window(x: np.ndarray, y: np.ndarray, w: Window) -> ElementResult:
    """The window's verdict on the polyline (x m, y N) (module doc)."""
    fail = lambda reason, px, py: ElementResult(element=w.name, kind="window", passed=False, reason=reason,
                                                x_m=float(px), y_n=float(py))
    pts = np.stack([x, y], -1)
    if _inside(pts[0], w):
        return fail(f"starts inside the window: it must enter through the {w.entry} side", *pts[0])
    entered = False
    for k in range(len(pts) - 1):
        clip = _clip_segment(pts[k], pts[k + 1], w)
        if clip is None:
            continue
        t_in, t_out, side_in, side_out = clip
        if t_in > 0.0:  # the segment comes from outside (t_in = 0: it starts inside)
            entered = True
            if side_in != w.entry:
                return fail(f"enters through the {side_in} side (must enter through the {w.entry})",
                            *_point(pts[k], pts[k + 1], t_in))
        if t_out < 1.0:
            if w.exit == "none":
                return fail(f"leaves through the {side_out} side (must end inside the window)",
                            *_point(pts[k], pts[k + 1], t_out))
            if side_out != w.exit:
                return fail(f"leaves through the {side_out} side (must leave through the {w.exit})",
                            *_point(pts[k], pts[k + 1], t_out))
    if not entered:
        return fail(*_nearest_description(x, y, w))
    if w.exit != "none" and _inside(pts[-1], w):
        return fail(f"ends inside the window (must leave through the {w.exit} side)", *pts[-1])
    return ElementResult(element=w.name, kind="window", passed=True)


def check_threshold(x: np.ndarray, y: np.ndarray, t: Threshold) -> ElementResult:
    """The threshold's verdict on the polyline (x m, y N) (module doc)."""
    cx, cy = _clip_x(x, y, t.x_min_m, t.x_max_m)
    ok = ElementResult(element=t.name, kind="threshold", passed=True)
    if t.mode == "must_cross":
        if cx.size == 0:
            return ElementResult(element=t.name, kind="threshold", passed=False, x_m=float(x[-1]), y_n=float(y[-1]),
                                 reason=f"never reaches {t.force_n:.6g} N: the curve does not reach the range "
                                        f"[{t.x_min_m:.6g}, {t.x_max_m:.6g}] m (ends at x = {x[-1]:.6g} m)")
        if cy.max() >= t.force_n:
            return ok
        k = int(np.argmax(cy))
        return ElementResult(element=t.name, kind="threshold", passed=False, x_m=float(cx[k]), y_n=float(cy[k]),
                             reason=f"never reaches {t.force_n:.6g} N over [{t.x_min_m:.6g}, {t.x_max_m:.6g}] m "
                                    f"(at most {cy[k]:.6g} N)")
    over = np.flatnonzero(cy > t.force_n)
    if over.size == 0:
        return ok
    k = int(over[0])
    px, py = float(cx[k]), float(cy[k])
    if k > 0 and cy[k - 1] <= t.force_n and cy[k] != cy[k - 1]:  # where the segment crosses the level
        s = (t.force_n - cy[k - 1]) / (cy[k] - cy[k - 1])
        px, py = float(cx[k - 1] + s * (cx[k] - cx[k - 1])), float(t.force_n)
    return ElementResult(element=t.name, kind="threshold", passed=False, x_m=px, y_n=py,
                         reason=f"exceeds {t.force_n:.6g} N within [{t.x_min_m:.6g}, {t.x_max_m:.6g}] m "
                                f"(up to {cy.max():.6g} N)")


def check_envelope(x: np.ndarray, y: np.ndarray, e: Envelope) -> ElementResult:
    """The envelope's verdict on the polyline (x m, y N) (module doc)."""
    ex, lo, hi = np.array(e.displacement_m), np.array(e.lower_force_n), np.array(e.upper_force_n)
    xs, ys = [], []
    for k in range(len(x) - 1):
        cx, cy = _clip_x(x[k:k + 2], y[k:k + 2], ex[0], ex[-1])
        if cx.size == 0:
            continue
        a, b = sorted((cx[0], cx[-1]))
        inner = ex[(ex > a) & (ex < b)]
        if cx[-1] < cx[0]:
            inner = inner[::-1]
        ts = (inner - cx[0]) / (cx[-1] - cx[0]) if inner.size else inner
        xs.extend([cx[0], *(cx[0] + ts * (cx[-1] - cx[0])), cx[-1]])
        ys.extend([cy[0], *(cy[0] + ts * (cy[-1] - cy[0])), cy[-1]])
    xs_a, ys_a = np.array(xs), np.array(ys)
    if xs_a.size:
        low, up = np.interp(xs_a, ex, lo), np.interp(xs_a, ex, hi)
        bad = np.flatnonzero((ys_a > up) | (ys_a < low))
        if bad.size:
            k = int(bad[0])
            side = ("above the upper", up[k]) if ys_a[k] > up[k] else ("below the lower", low[k])
            return ElementResult(element=e.name, kind="envelope", passed=False, x_m=float(xs_a[k]), y_n=float(ys_a[k]),
                                 reason=f"{side[0]} bound ({ys_a[k]:.6g} N against {side[1]:.6g} N)")
    return ElementResult(element=e.name, kind="envelope", passed=True)


def check_max_force(x: np.ndarray, y: np.ndarray, m: MaxForce) -> ElementResult:
    """The max_force verdict: the largest force must not exceed the limit."""
    k = int(np.argmax(y))
    if y[k] > m.force_n:
        return ElementResult(element=m.name, kind="max_force", passed=False, x_m=float(x[k]), y_n=float(y[k]),
                             reason=f"peak force {y[k]:.6g} N exceeds {m.force_n:.6g} N")
    return ElementResult(element=m.name, kind="max_force", passed=True)


def check_curve(displacement_m: np.ndarray, force_n: np.ndarray, windows: Windows) -> tuple[ElementResult, ...]:
    """Every element of ``windows`` on one forward stroke (m, N), in file order."""
    x, y = np.asarray(displacement_m, dtype=float), np.asarray(force_n, dtype=float)
    out = []
    for el in windows.elements:
        if isinstance(el, Window):
            out.append(check_window(x, y, el))
        elif isinstance(el, Threshold):
            out.append(check_threshold(x, y, el))
        elif isinstance(el, Envelope):
            out.append(check_envelope(x, y, el))
        else:
            out.append(check_max_force(x, y, el))
    return tuple(out)


def judge_curves(curves: Sequence[MeasuredCurve], windows: Windows,
                 compliance_m_per_n: float | None = None) -> list[CurveVerdict]:
    """The verdict on each measured curve (its forward stroke; with ``compliance_m_per_n`` (m/N) the press's
    deflection removed from the displacement first)."""
    out = []
    for c in curves:
        x, y = c.forward()
        if compliance_m_per_n is not None:
            if not math.isfinite(compliance_m_per_n) or compliance_m_per_n < 0:
                raise PressfitError(f"the press compliance must be a finite number >= 0 m/N, got {compliance_m_per_n}")
            x = compensated_displacement(x, y, compliance_m_per_n)
        out.append(CurveVerdict(path=c.path, name=c.name, results=check_curve(x, y, windows),
                                compliance_m_per_n=compliance_m_per_n))
    return out


def judged_strokes(curves: Sequence[MeasuredCurve], verdicts: Sequence[CurveVerdict]
                   ) -> list[tuple[str, np.ndarray, np.ndarray, bool]]:
    """Each curve's forward stroke as it was judged: (name, displacement m -- compensated where its verdict was --,
    force N, passed), for the figure of ``pressfit curves check``."""
    drawn = []
    for c, v in zip(curves, verdicts, strict=True):
        x, f = c.forward()
        if v.compliance_m_per_n is not None:
            x = compensated_displacement(x, f, v.compliance_m_per_n)
        drawn.append((c.name, x, f, v.passed))
    return drawn
