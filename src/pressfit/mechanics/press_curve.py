r"""The predicted press curve: the joint's law in series with the machine's 6x6 compliance at the pin pose,
quasi-statically (no time stepping): what a press monitor records, and how much of it is the press.

A component has n pins at offsets r_i = (dx_i, 0, dz_i) (m) from the tool axis (the tool tip is the plate
centre), each with its law f_i (:mod:`pressfit.mechanics.contact_laws`, force N against depth m). The pins push the
tool up (+y) with F_i; about the tool tip this is the wrench w = G F, G's column i = (0, 1, 0, -dz_i, 0, dx_i)
(force, moment r_i x F_i e_y). The tool moves by [u; theta] = C w, C the plate's compliance about its centre
(:func:`pressfit.mechanics.condensed.condensed_plate_compliance`, translation then rotation: m/N, rad/N,
rad/(N m); the legs and the drives' axial compliance between the drives' position sensors and the plate: all of
it but a hydraulic cylinder's oil column, which its piston sensor reads past and its position loop holds). With
the tool's true depth d (its tip below the board face, m), pin i is at the depth

.. math:: d_i = d - (\theta \times r_i)_y = d - (\theta_z dx_i - \theta_x dz_i) = d - (G_r^T \theta)_i,
          \qquad \theta = C_{r\cdot} G F,

so the pins' forces solve the series equation F = f(d 1 - A F), A = G_r^T C_{r\cdot} G (n x n, m/N), by Newton
at each sampled depth (batched over the depths; the pins' laws stacked over the pins,
:func:`pressfit.mechanics.contact_laws.stack_laws`; the Jacobian I + diag(f'(d_i)) A from the laws' slopes in
closed form; the worst residual max |F - f(d_i)|, N, is returned, and callers enforce it). The drives' encoders
(motor side: everything between them and the tool deflects) read the sensed depth d + u_y, u_y = (C G F)_y: the
sensed minus the true depth is the machine's deflection along the press at that pose. The weight's sag is a
constant offset between the two that a monitor zeroes at first contact; it is left out here. One pin on the axis
of a centred pose gives d_1 = d exactly.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from pressfit.description.cases import Case, Contact
from pressfit.description.machine import Machine
from pressfit.errors import PressCurveError
from pressfit.mechanics.condensed import condensed_plate_compliance
from pressfit.mechanics.contact_laws import ContactLawModel, build_law, stack_laws

DEFAULT_SAMPLES = 2001  # depth samples of a predicted curve
NEWTON_ITERATIONS = 50
NEWTON_TOLERANCE_N = 1e-9  # N: Newton stops when every pin's residual is below this
RESIDUAL_LIMIT_N = 1e-6  # N: a curve whose series residual exceeds this is refused by its callers


@dataclass(frozen=True, kw_only=True)
class PinField:
    """The component: its pins' laws, offsets (n, 2) = [dx, dz] (m) and where each is defined."""

    laws: tuple[ContactLawModel, ...]
    offsets_m: np.ndarray
    sources: tuple[str, ...]

    @classmethod
    def from_contact(cls, contact: Contact) -> PinField:
        pins = contact.resolved_pins()
        return cls(laws=tuple(build_law(p.law, p.keys) for p in pins),
                   offsets_m=np.array([p.offset_m for p in pins], dtype=float),
                   sources=tuple(p.source for p in pins))

    @property
    def wrench_map(self) -> np.ndarray:
        """G (6, n): the wrench about the tool tip (N, N m) per newton of each pin's force."""
        g = np.zeros((6, len(self.laws)))
        g[1] = 1.0
        g[3], g[5] = -self.offsets_m[:, 1], self.offsets_m[:, 0]
        return g

    @cached_property
    def _stacked(self) -> tuple[tuple[np.ndarray, ContactLawModel], ...]:
        return stack_laws(self.laws)

    def forces_and_slopes(self, depths_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """f_i(d_i) (N) and f_i'(d_i) (N/m) for depths (..., n) (m), one evaluation per kind of law."""
        if len(self._stacked) == 1:
            return self._stacked[0][1].force_and_slope(depths_m)
        forces, slopes = np.empty_like(depths_m), np.empty_like(depths_m)
        for idx, law in self._stacked:
            forces[..., idx], slopes[..., idx] = law.force_and_slope(depths_m[..., idx])
        return forces, slopes

    def forces_n(self, depths_m: np.ndarray) -> np.ndarray:
        """f_i(d_i) for depths (..., n), N."""
        return self.forces_and_slopes(depths_m)[0]


@dataclass(frozen=True, kw_only=True)
class FieldSolution:
    """The series equation solved at the tool depths ``depth_m`` (m): the pins' forces (m, n), N, and depths
    (m, n), m, the tool's displacement [u; theta] (m, 6) and the worst residual (N)."""

    depth_m: np.ndarray
    pin_forces_n: np.ndarray
    pin_depths_m: np.ndarray
    displacement: np.ndarray
    residual_n: float


def series_matrix(pins: PinField, compliance: np.ndarray) -> np.ndarray:
    """A = G_r^T C_r. G (n, n), m/N: pin i's depth lost to the tool's tilt per newton of pin j's force."""
    g = pins.wrench_map
    return g[3:].T @ compliance[3:] @ g


def field_stiffness(pins: PinField, compliance: np.ndarray, depth_m: float) -> tuple[float, float]:
    """The component's total force (N) and its local slope dF/dd (N/m) at the tool's true depth ``depth_m`` (m),
    the tilt by ``compliance`` included: differentiating F = f(d 1 - A F), (I + diag(f'(d_i)) A) dF = f'(d_i) dd,
    so dF/dd = 1^T (I + diag(f') A)^-1 f', each law's slope f' in closed form (``force_and_slope``) at the solved
    pin depths. One pin on the tool axis (A = 0): its law's own slope f'(d)."""
    sol = solve_field(pins, compliance, np.array([float(depth_m)]))
    slopes = pins.forces_and_slopes(sol.pin_depths_m)[1][0]
    jac = np.eye(slopes.size) + slopes[:, None] * series_matrix(pins, compliance)
    return float(sol.pin_forces_n.sum()), float(np.linalg.solve(jac, slopes).sum())


def operating_depth_m(pins: PinField, compliance: np.ndarray, interference_m: float, force_limit_n: float,
                      samples: int = 2001) -> float:
    """Where a force-limited insertion holds the tool (m): the first true depth at which the component's total force
    (tilt included) reaches ``force_limit_n`` (N), linear between ``samples`` depths from 0 to ``interference_m``
    (the commanded depth, m); the commanded depth if the force stays below the limit there."""
    depth = np.linspace(0.0, float(interference_m), samples)
    total = solve_field(pins, compliance, depth).pin_forces_n.sum(axis=1)
    over = np.flatnonzero(total >= force_limit_n)
    if not over.size:
        return float(interference_m)
    k = int(over[0])
    if k == 0:
        return 0.0
    return float(np.interp(force_limit_n, total[k - 1:k + 1], depth[k - 1:k + 1]))


def solve_field(pins: PinField, compliance: np.ndarray, depth_m: np.ndarray) -> FieldSolution:
    """F = f(d 1 - A F) at every tool depth (module docstring): Newton from F = 0 (whose first step is the untilted
    forces f(d 1) through the linearised tilt, (I + diag(f'(d 1)) A)^-1 f(d 1)), each depth iterated until its pins'
    residual is at most ``NEWTON_TOLERANCE_N`` (N) and then left alone."""
    d = np.asarray(depth_m, dtype=float)
    g = pins.wrench_map
    a = series_matrix(pins, compliance)  # (n, n), m/N
    n = g.shape[1]
    eye = np.eye(n)
    forces = np.zeros((d.size, n))
    depths = np.repeat(d[:, None], n, axis=1)
    law_forces, slopes = pins.forces_and_slopes(depths)
    residual = forces - law_forces
    rows = np.arange(d.size)  # the depths still iterating
    for _ in range(NEWTON_ITERATIONS):
        rows = rows[np.max(np.abs(residual[rows]), axis=1, initial=0.0) > NEWTON_TOLERANCE_N]
        if not rows.size:
            break
        jac = eye[None] + slopes[rows, :, None] * a[None]
        forces[rows] -= np.linalg.solve(jac, residual[rows, :, None])[..., 0]
        depths[rows] = d[rows, None] - forces[rows] @ a.T
        law_forces, slopes[rows] = pins.forces_and_slopes(depths[rows])
        residual[rows] = forces[rows] - law_forces
    return FieldSolution(depth_m=d, pin_forces_n=forces, pin_depths_m=depths,
                         displacement=forces @ (compliance @ g).T,
                         residual_n=float(np.max(np.abs(residual), initial=0.0)))


@dataclass(frozen=True, kw_only=True)
class PressCurve:
    """A predicted press curve (module docstring), sampled at the tool's true depths: ``depth_m`` (m, the tool tip
    below the board face), ``force_n`` (the total, N), ``pin_forces_n`` (samples, pins), N, ``pin_depths_m``
    (samples, pins), m, ``sensed_depth_m`` (m, what the drives' encoders read), ``tilt_rad`` (samples, 3) the
    tool's small rotation; the summary: ``peak_force_n`` (the insertion's peak: before the first shoulder touches
    the board, over the whole stroke without one), ``final_force_n`` (at the end of the stroke),
    ``plateau_force_n`` (the pins' plateaus summed; None
    when a law has none), ``seated`` (the component's shoulder on the board at every pin by the end of the
    stroke), ``seating_depth_m`` (the true tool depth where the last pin seats; None if never or no shoulder),
    ``sensed_minus_true_depth_at_peak_m``, ``machine_compliance_along_press_m_per_n`` (C_yy at the pose),
    ``tool_tilt_max_rad`` (the largest |theta|), ``max_pin_depth_spread_m`` (the largest spread of the pins'
    depths), ``all_pins_seated``, per pin ``pin_peak_force_n`` (before its shoulder touches),
    ``pin_final_depth_m``, ``pin_seated`` and ``pin_offsets_m``; ``series_residual_n`` (the series equation's
    worst residual, N: callers enforce it against ``RESIDUAL_LIMIT_N``), ``pose_m`` (the pin pose, m) and
    ``notes`` (what the laws say of themselves)."""

    depth_m: np.ndarray
    force_n: np.ndarray
    pin_forces_n: np.ndarray
    pin_depths_m: np.ndarray
    sensed_depth_m: np.ndarray
    tilt_rad: np.ndarray
    peak_force_n: float
    final_force_n: float
    plateau_force_n: float | None
    seated: bool
    seating_depth_m: float | None
    sensed_minus_true_depth_at_peak_m: float
    machine_compliance_along_press_m_per_n: float
    tool_tilt_max_rad: float
    max_pin_depth_spread_m: float
    all_pins_seated: bool
    pin_peak_force_n: tuple[float, ...]
    pin_final_depth_m: tuple[float, ...]
    pin_seated: tuple[bool, ...]
    pin_offsets_m: tuple[tuple[float, float], ...]
    series_residual_n: float
    pose_m: tuple[float, float, float]
    notes: tuple[str, ...] = field(default=())

    def summary(self) -> dict:
        """The scalar fields and the per-pin lists (JSON-ready)."""
        keys = ("peak_force_n", "final_force_n", "plateau_force_n", "seated", "seating_depth_m",
                "sensed_minus_true_depth_at_peak_m", "machine_compliance_along_press_m_per_n", "tool_tilt_max_rad",
                "max_pin_depth_spread_m", "all_pins_seated", "series_residual_n")
        out = {k: getattr(self, k) for k in keys}
        out["pose_m"] = list(self.pose_m)
        out["max_depth_m"] = float(self.depth_m[-1])
        out["pins"] = [{"offset_m": list(o), "peak_force_n": f, "final_depth_m": d, "seated": s}
                       for o, f, d, s in zip(self.pin_offsets_m, self.pin_peak_force_n, self.pin_final_depth_m,
                                             self.pin_seated, strict=True)]
        out["notes"] = list(self.notes)
        return out


@dataclass(frozen=True, kw_only=True)
class StrokeFigures:
    """A press stroke's monitor figures (:func:`stroke_figures`): the row of the insertion's peak and its force (N),
    the pins' plateaus summed (N; None when a law has none), whether every pin is seated at the end of the stroke,
    the true tool depth where the last pin seats (m; None if never or without a shoulder), the sensed minus the
    true depth at the peak (m), and per pin whether it is seated at the end and its peak before its shoulder (N)."""

    peak_row: int
    peak_force_n: float
    plateau_force_n: float | None
    seated: bool
    seating_depth_m: float | None
    sensed_minus_true_depth_at_peak_m: float
    pin_seated: tuple[bool, ...]
    pin_peak_force_n: tuple[float, ...]


def stroke_figures(pins: PinField, depth_m: np.ndarray, force_n: np.ndarray, pin_forces_n: np.ndarray,
                   pin_depths_m: np.ndarray, sensed_depth_m: np.ndarray, end_row: int = -1) -> StrokeFigures:
    """The monitor's figures of a stroke sampled in rows (the predicted curve's depths, or a simulation's time
    steps): true tool depth (m), total force (N), the pins' forces (rows, n), N, and depths (rows, n), m, the
    sensed depth (m); ``end_row`` the end of the stroke (the deepest point: the last depth of a predicted curve,
    the end of a simulated dwell). The peak is the insertion's: before the first shoulder touches the board, over
    the whole stroke without one."""
    seats = np.array([law.seat_depth_m if law.seat_depth_m is not None else np.inf for law in pins.laws])
    shoulder = bool(np.all(np.isfinite(seats)))
    touched = np.flatnonzero(np.any(pin_depths_m >= seats, axis=1))
    before = touched[0] if touched.size else force_n.size
    peak = int(np.argmax(force_n[:max(before, 1)]))
    pin_seated = tuple(bool(x >= s) and bool(np.isfinite(s)) for x, s in zip(pin_depths_m[end_row], seats,
                                                                           strict=True))
    seated_rows = np.flatnonzero(np.all(pin_depths_m >= seats, axis=1))
    plateaus = [law.plateau_force_n for law in pins.laws]
    return StrokeFigures(
        peak_row=peak, peak_force_n=float(force_n[peak]),
        plateau_force_n=None if any(p is None for p in plateaus) else float(sum(plateaus)),
        seated=bool(shoulder and all(pin_seated)),
        seating_depth_m=float(depth_m[seated_rows[0]]) if shoulder and seated_rows.size else None,
        sensed_minus_true_depth_at_peak_m=float(sensed_depth_m[peak] - depth_m[peak]), pin_seated=pin_seated,
        pin_peak_force_n=tuple(float(np.max(np.where(pin_depths_m[:, i] < s, pin_forces_n[:, i], 0.0)))
                               for i, s in enumerate(seats)))


def component_figures(pins: PinField, sol: FieldSolution, fig: StrokeFigures, end_row: int = -1) -> dict:
    """The component's figures of a stroke solved by :func:`solve_field` (its rows the stroke's) with its
    :func:`stroke_figures`: ``tool_tilt_max_rad`` (the largest |theta| of the tool, rad), ``max_pin_depth_spread_m``
    (the largest spread of the pins' depths, m), ``all_pins_seated`` and ``component_pins``: per pin its
    ``offset_m`` ([dx, dz], m), ``peak_force_n`` (before its shoulder touches, N), ``final_depth_m`` (at ``end_row``,
    the end of the stroke, m) and ``seated`` (JSON-ready)."""
    final = sol.pin_depths_m[end_row]
    return {"tool_tilt_max_rad": float(np.max(np.linalg.norm(sol.displacement[:, 3:], axis=1), initial=0.0)),
            "max_pin_depth_spread_m": float(np.max(np.ptp(sol.pin_depths_m, axis=1), initial=0.0)),
            "all_pins_seated": fig.seated,
            "component_pins": [{"offset_m": [float(o[0]), float(o[1])], "peak_force_n": f, "final_depth_m": float(d),
                                "seated": s} for o, f, d, s in zip(pins.offsets_m, fig.pin_peak_force_n, final,
                                                                    fig.pin_seated, strict=True)]}


def pin_pose_m(contact: Contact) -> np.ndarray:
    """The plate pose of the insertion: the tool tip (the plate centre) on the pin, at the board face (m)."""
    return np.array([contact.pin_position_m[0], contact.board_height_m, contact.pin_position_m[1]], dtype=float)


def _stroke_end(pins: PinField, max_depth_m: float | None, fallback_m: float | None, path: str) -> float:
    if max_depth_m is not None:
        return float(max_depth_m)
    end = max(law.depth_range_m[1] for law in pins.laws)
    if np.isfinite(end):
        return float(end)
    if fallback_m is not None:
        return float(fallback_m)
    raise PressCurveError(path, "max_depth_m", "the law has no depth range of its own (an elastic spring without "
                          "a shoulder): give max_depth_m or a case with [simulation] interference_m")


def predict_curve(machine: Machine, case_or_contact: Case | Contact, *, pose_m: Sequence[float] | None = None,
                  samples: int = DEFAULT_SAMPLES, max_depth_m: float | None = None,
                  stop_force_n: float | None = None) -> PressCurve:
    """The quasi-static press curve (module docstring) of a case's ``[simulation.contact]`` (or of a
    :class:`Contact`) at ``pose_m`` (m; default: the pin pose, :func:`pin_pose_m`), ``samples`` true tool depths
    from 0 to ``max_depth_m`` (m; default: the laws' depth range, which ends at the shoulder + 20 um with one, else
    the case's ``[simulation] interference_m``; with a shoulder the stroke is lengthened until every pin seats,
    at most twice, and then until the force reaches ``stop_force_n`` (N; a case's default: its
    ``[simulation.controller] force_limit_n``): the press seats a component up to its force limit and stops there,
    as the simulation does; a stroke whose force reaches ``stop_force_n`` earlier ends where it first does)."""
    if isinstance(case_or_contact, Case):
        if case_or_contact.simulation is None:
            raise PressCurveError(case_or_contact.path, "[simulation]", "the case has no [simulation] table (its "
                                  "contact is the joint)")
        contact, path = case_or_contact.simulation.contact, case_or_contact.path
        fallback = case_or_contact.simulation.interference_m
        stop = case_or_contact.simulation.controller.force_limit_n if stop_force_n is None else stop_force_n
    else:
        contact, path, fallback, stop = case_or_contact, "", None, stop_force_n
    if not 2 <= samples <= 10**6:
        raise PressCurveError(path, "samples", f"give 2 .. 1e6 samples, got {samples}")
    pins = PinField.from_contact(contact)
    pose = pin_pose_m(contact) if pose_m is None else np.asarray(pose_m, dtype=float)
    compliance = condensed_plate_compliance(machine.sensed_view, pose)
    end = _stroke_end(pins, max_depth_m, fallback, path)
    seats = [law.seat_depth_m for law in pins.laws]
    shoulder = all(s is not None for s in seats)
    for _ in range(3):
        depth = np.linspace(0.0, end, samples)
        sol = solve_field(pins, compliance, depth)
        pin_seated = tuple(bool(sol.pin_depths_m[-1, i] >= s) if s is not None else False for i, s in enumerate(seats))
        if max_depth_m is not None or not shoulder or all(pin_seated):
            break
        spread = float(np.max(np.ptp(sol.pin_depths_m, axis=1)))
        end += max(spread, 1e-6)
    for _ in range(SEATING_ITERATIONS if max_depth_m is None and shoulder and stop is not None else 0):
        force = sol.pin_forces_n.sum(axis=1)  # the seated rise is linear: a secant step lands on the limit
        if force[-1] >= stop * (1.0 - 1e-9):
            break
        end += (stop - force[-1]) / ((force[-1] - force[-2]) / (depth[-1] - depth[-2]))
        depth = np.linspace(0.0, end, samples)
        sol = solve_field(pins, compliance, depth)
    force = sol.pin_forces_n.sum(axis=1)
    hit = np.flatnonzero(force >= stop)[:1] if stop is not None else ()
    if len(hit) and hit[0] > 0 and force[-1] > stop * (1.0 + 1e-9):  # the press stops where it first reaches it
        k = int(hit[0])
        depth = np.linspace(0.0, float(np.interp(stop, force[k - 1:k + 1], depth[k - 1:k + 1])), samples)
        sol = solve_field(pins, compliance, depth)
        force = sol.pin_forces_n.sum(axis=1)
    sensed = depth + sol.displacement[:, 1]
    tilt = sol.displacement[:, 3:]
    fig = stroke_figures(pins, depth, force, sol.pin_forces_n, sol.pin_depths_m, sensed)
    component = component_figures(pins, sol, fig)
    notes = tuple(dict.fromkeys(n for law in pins.laws for n in law.notes))
    return PressCurve(
        depth_m=depth, force_n=force, pin_forces_n=sol.pin_forces_n, pin_depths_m=sol.pin_depths_m,
        sensed_depth_m=sensed, tilt_rad=tilt, peak_force_n=fig.peak_force_n, final_force_n=float(force[-1]),
        plateau_force_n=fig.plateau_force_n, seated=fig.seated, seating_depth_m=fig.seating_depth_m,
        sensed_minus_true_depth_at_peak_m=fig.sensed_minus_true_depth_at_peak_m,
        machine_compliance_along_press_m_per_n=float(compliance[1, 1]),
        tool_tilt_max_rad=component["tool_tilt_max_rad"], max_pin_depth_spread_m=component["max_pin_depth_spread_m"],
        all_pins_seated=fig.seated, pin_peak_force_n=fig.pin_peak_force_n,
        pin_final_depth_m=tuple(p["final_depth_m"] for p in component["component_pins"]), pin_seated=fig.pin_seated,
        pin_offsets_m=tuple((float(a), float(b)) for a, b in pins.offsets_m), series_residual_n=sol.residual_n,
        pose_m=(float(pose[0]), float(pose[1]), float(pose[2])), notes=notes)


@dataclass(frozen=True, kw_only=True)
class ForceTable:
    """The component's total force against the tool's true depth, for the insertion kernels' TABLE law: depths
    (m, uniform from 0), forces (N), the slope past the last depth (N/m), and the tabulation error bound (N):
    twice the largest |linear interpolation - the solve| at the midpoints of the grid (on a smooth law the midpoint
    error is the cell's largest; at a kink of slope jump s at a fraction a of a cell of width h the error is
    a (1 - a) h s, at most twice the midpoint's min(a, 1 - a) h s / 2)."""

    depth_m: np.ndarray
    force_n: np.ndarray
    slope_n_per_m: float
    error_n: float


SEATING_ITERATIONS = 4  # secant steps of the seated stroke's end onto the case's force limit
TABLE_SAMPLES = 4001  # rows of the insertion's force table
TABLE_EXTENSION = 1.25  # the table runs past the laws' range by this factor (the seating's rise included)
TABLE_DEPTH_M = 0.01  # m: the table's range for laws without one of their own (elastic pins, extrapolated past it)


def force_table(machine: Machine | None, contact: Contact, *, pose_m: Sequence[float] | None = None,
                max_depth_m: float | None = None, samples: int = TABLE_SAMPLES) -> ForceTable:
    """The total force of the contact's pins against the tool depth (m), tilt included when ``machine`` is given
    (its compliance at ``pose_m``, default the pin pose), else with the pins at the tool's depth: for the
    insertion's TABLE law (:func:`pressfit.dynamics.contact.contact_parameters`). Past the last row the kernels
    extrapolate with ``slope_n_per_m`` (the sum of the pins' slopes there: the seat stiffness of a seated
    component)."""
    pins = PinField.from_contact(contact)
    compliance = np.zeros((6, 6)) if machine is None else condensed_plate_compliance(
        machine, pin_pose_m(contact) if pose_m is None else np.asarray(pose_m, dtype=float))
    end = TABLE_EXTENSION * _stroke_end(pins, max_depth_m, TABLE_DEPTH_M, "")
    depth = np.linspace(0.0, end, samples)
    mid = 0.5 * (depth[1:] + depth[:-1])
    both = solve_field(pins, compliance, np.concatenate([depth, mid, [end, end + 1e-6]]))
    total = both.pin_forces_n.sum(axis=1)
    rows, between = total[:samples], total[samples:2 * samples - 1]
    error = 2.0 * float(np.max(np.abs(0.5 * (rows[1:] + rows[:-1]) - between), initial=0.0))
    slope = float((total[-1] - total[-2]) / 1e-6)
    return ForceTable(depth_m=depth, force_n=rows, slope_n_per_m=slope, error_n=error)
