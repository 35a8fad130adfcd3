r"""Tool-board contact with the machine's compliance in series (quasi-static), for the insertion simulation.

Contact law (case ``[simulation.contact]``): for an interference d > 0 (m) of the tool tip below the board
face, F(d) = k d + f_fit(d) + b d_dot (N, pushing the tool up, +y), F = 0 out of contact and never negative
(no adhesion). ``elastic``: f_fit = 0 (paper section 4.2: a force proportional to the interference);
``press_fit``: f_fit(d) = k_fit d (linear) or F_fit tanh(d / d_fit) (saturating); every other law
(:mod:`pressfit.mechanics.contact_laws`: solid and compliant pins, tables, the shoulder, a field of pins) as a
table of the component's force against the depth (:func:`contact_parameters`), plus b d_dot. A pin law is not a
spring: friction and the board's yield set the joint, so where the tool backs off from the deepest depth d_max it
reached (a snap past a compliant pin's peak pulled back by the loop, the retract) the joint unloads elastically,
F(d_max) - k_u (d_max - d), k_u the table's steepest slope (:func:`steepest_slope_n_per_m`), to 0 within
micrometres, and leaves the pin at d_max; the tool reloads it along the same line (``kernels.contact_law``; the
state d_max lives in the parameter vector, moved on after each step by ``kernels.contact_advance``, fresh for
every run and every board position). The elastic law is the paper's spring and follows itself back.

The tool sees the machine's compliance: the rigid-leg multibody model (:mod:`pressfit.dynamics.multibody`)
gives the rigid tool position r, the structure adds the deflection u(F) under the contact force and the moving
parts' weight, applied quasi-statically (in series, no inertia of its own). This holds below the first structural mode
(``pressfit modes``: 18 Hz plate rocking at pose A, above the force loop's bandwidth of a few Hz). u(F) is
either C F y + s (C the condensed plate compliance at the current pose, translation block,
:func:`pressfit.mechanics.condensed.condensed_plate_compliance`, s the sag under the weight,
:func:`pressfit.dynamics.control.static_deflection_columns`) or, plus s, with the cardans' clearance on, the
load-deflection curve of :func:`pressfit.mechanics.clearance.load_deflection` at the insertion pose (lost
motion, preload and compliance together, interpolated in the load).

Each step solves the scalar equation F = F(d(F)), d(F) = h_b - r_y - u_y(F), with the damping term taken
backward in time (d_dot = (d - d_prev) / dt): the residual is increasing in F (u_y grows with F), so
bisection on [0, F(d(0))] always converges (to 1e-9 of the bracket); d(0) includes the sag, which can press
the tool below the rigid depth.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pressfit.description.cases import Contact
from pressfit.description.machine import Machine
from pressfit.dynamics import kernels
from pressfit.mechanics.contact_laws import build_law
from pressfit.mechanics.contact_laws.elastic import ElasticLaw
from pressfit.mechanics.press_curve import ForceTable, PinField, force_table

_FITS = {"none": kernels.ELASTIC, "linear": kernels.FIT_LINEAR, "saturating": kernels.FIT_TANH}


def contact_parameters(contact: Contact, machine: Machine | None = None) -> np.ndarray:
    """The contact as the compiled kernels take it (:func:`pressfit.dynamics.kernels.solve_contact`). One pin on
    the tool axis with the elastic or press-fit law and no shoulder: the kernels' own codes (the paper's numbers).
    Any other law, a shoulder or a pin field: the component's total force against the tool's depth tabulated
    (:func:`pressfit.mechanics.press_curve.force_table`: ``TABLE_SAMPLES`` rows, linear interpolation, its error
    ``ForceTable.error_n``; 0.06 N on the shipped compliant pin, at the peak's and the shoulder's kinks), with the
    field's tilt by the machine's compliance at the pin pose when ``machine`` is given (the insertion's), and the
    damping b d_dot added on top: the one path of every law in the rigid and the flexible models."""
    pins = contact.resolved_pins()
    law = build_law(pins[0].law, pins[0].keys)
    values = np.zeros(7)
    values[[kernels.BOARD, kernels.DAMPING]] = contact.board_height_m, contact.damping_n_s_per_m
    if len(pins) == 1 and pins[0].offset_m == (0.0, 0.0) and isinstance(law, ElasticLaw):
        values[[kernels.STIFFNESS, kernels.LAW]] = law.stiffness_n_per_m, _FITS[law.fit]
        if law.fit != "none":
            values[[kernels.FIT_STIFFNESS, kernels.FIT_FORCE, kernels.FIT_DEPTH]] = (
                law.fit_stiffness_n_per_m, law.fit_force_n, law.fit_depth_m)
        return values
    table = force_table(machine, contact)
    values[kernels.LAW] = kernels.TABLE
    sets = not all(law.reversible for law in PinField.from_contact(contact).laws)
    head = np.array([table.force_n.max(), table.slope_n_per_m, table.depth_m.size,
                     steepest_slope_n_per_m(table) if sets else 0.0, 0.0], dtype=float)
    return np.concatenate([values, head, table.depth_m, table.force_n])


def steepest_slope_n_per_m(table: ForceTable) -> float:
    """The steepest slope of a force table and past its end (N/m): the contact's stiffest for the step check, and
    the stiffness with which a set joint unloads as the tool backs off (its shoulder's once seated; the unloading
    line then stays below the table: the joint is at least as stiff elastically as it ever was while loading)."""
    return float(max(np.max(np.diff(table.force_n) / np.diff(table.depth_m), initial=0.0), table.slope_n_per_m))


def contact_stiffness_bound_n_per_m(contact: Contact) -> float:
    """The steepest slope of the contact's force against the tool depth (N/m), for the explicit step's stability
    check (:func:`pressfit.dynamics.scenario.check_steps`). One pin on the tool axis with the elastic or press-fit
    law and no shoulder: k + k_fit (linear fit) or k + F_fit / d_fit (the saturating fit's slope at 0). Any other
    law, a shoulder or a pin field: the largest slope of the component's total force over its table
    (:func:`pressfit.mechanics.press_curve.force_table`, the pins at the tool's depth: every pin's slope summed, the
    seated shoulders' included) and past its end."""
    pins = contact.resolved_pins()
    law = build_law(pins[0].law, pins[0].keys)
    if len(pins) == 1 and pins[0].offset_m == (0.0, 0.0) and isinstance(law, ElasticLaw):
        fit = {"none": 0.0, "linear": law.fit_stiffness_n_per_m}.get(law.fit, law.fit_force_n / law.fit_depth_m)
        return float(law.stiffness_n_per_m + fit)
    return steepest_slope_n_per_m(force_table(None, contact))


def contact_force_n(contact: Contact | np.ndarray, depth_m: float, depth_rate_m_per_s: float = 0.0) -> float:
    """The contact law F(d, d_dot) (N, >= 0) at interference ``depth_m`` (m) and its rate (m/s); ``contact``: the
    case's contact or its :func:`contact_parameters` (computed once: a tabulated law's table costs a solve)."""
    params = contact if isinstance(contact, np.ndarray) else contact_parameters(contact)
    return float(kernels.contact_law(params, float(depth_m), float(depth_rate_m_per_s)))


@dataclass(frozen=True, kw_only=True)
class ContactState:
    """The contact at one instant: force (N, +y on the tool), interference (m), tool deflection (3,), m."""

    force_n: float
    depth_m: float
    deflection_m: np.ndarray


NO_TABLE = (np.zeros(0), np.zeros((0, 3)))  # kernels.solve_contact's (loads, disp) for a linear compliance


def solve_contact(contact: Contact, rigid_tip_m: np.ndarray, deflection: Callable[[float], np.ndarray],
                  previous_depth_m: float, dt_s: float) -> ContactState:
    """The contact force with the structure's deflection ``deflection(F)`` (m, (3,)) in series (module doc), for
    any deflection function; the insertion loop's linear or tabulated compliance takes the compiled
    :func:`pressfit.dynamics.kernels.solve_contact`, the same bisection (tested against this one)."""
    rigid_depth = contact.board_height_m - float(rigid_tip_m[1])
    params = contact_parameters(contact)

    def residual(force: float) -> tuple[float, float, np.ndarray]:
        u = deflection(force)
        d = rigid_depth - float(u[1])
        return force - contact_force_n(params, d, (d - previous_depth_m) / dt_s), d, u

    r0, d0, u0 = residual(0.0)
    if r0 >= 0.0:
        return ContactState(force_n=0.0, depth_m=d0, deflection_m=u0)
    # the deflection grows with the force (compliance >= 0), so the depth at zero force bounds the force
    lo, hi = 0.0, contact_force_n(params, d0, max(d0 - previous_depth_m, 0.0) / dt_s)
    if params[kernels.LAW] == kernels.TABLE:  # a law that falls after its peak (kernels.solve_contact)
        hi = max(hi, params[kernels.TABLE_MAX] + params[kernels.DAMPING] * max(d0 - previous_depth_m, 0.0) / dt_s)
    for _ in range(kernels.BISECTIONS):
        mid = 0.5 * (lo + hi)
        if residual(mid)[0] < 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-9 * hi:
            break
    _, d, u = residual(hi)
    return ContactState(force_n=hi, depth_m=d, deflection_m=u)
