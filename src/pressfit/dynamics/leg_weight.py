r"""The machine's own weight as a plate load, in closed form: what the rigid-leg model's quasi-static sag needs.

The condensed model (:mod:`pressfit.mechanics.condensed`) takes loads at the plate. The weight of plate and tool is
one; the legs' own weight is carried by the legs, and reaches the plate in two ways:

* **the cardan forces.** Leg i (base cardan B_i, plate cardan P_i = h + d_i, length l, unit axis e from B_i) carries
  masses along s in [0, l] from B_i (the ``[mass]`` table, as :mod:`pressfit.dynamics.inertia` places them): the
  cylinder tube and the actuator housing spread over [0, L_c]; the stem, a rod of fixed length L_r spanning
  [l - L_r, l] (its inner end may lie behind the base cardan, s < 0) with the actuator's moving parts at its inner
  end; the cardan spiders at s = 0 and s = l. The leg is a prismatic pair between two cardans, so along e the
  weight of the rod body (rod, moving parts, plate spider) reaches the plate and that of the cylinder the base;
  across e the cardans carry it as a simply supported beam: the plate's share is Q g_perp / l with
  Q = sum s m the first moment of the leg's masses about B_i (the couples at the two ends are equal and opposite,
  so they take no part in the leg's force balance). The plate then sees that force at P_i, i.e. the force and its
  moment d_i x F about the plate centre: together with the plate and the tool this is exactly the weight the
  rigid-leg model's virtual work gives (tests/dynamics/test_leg_weight.py checks it against Pinocchio's
  generalised gravity);
* **the legs' bending between the cardans.** A cardan transmits the couple along c_i (normal to both its axes), so
  each leg is clamped about c_i to the base at one end and to the plate at the other: the bending under its own
  transverse weight, which the cardans leave free about their two axes, would turn the plate end relative to the
  base end by

  .. math:: \Delta\varphi_0 = c \cdot (e \times g) \int_0^l \frac{m(s)}{EI(s)}\, ds, \qquad
            m(s) = q(s) - (l - s) \frac{Q}{l},

  where q(s) = sum over the plate side of section s of (x - s) m_x is the first moment about s of the masses the
  section carries toward the plate (for a cylinder section the whole rod is on that side: it rides on the actuator)
  and (e x g) m(s) is the simply supported bending moment of the plate side on the base side (zero at both ends).
  EI is the cylinder's over [0, L_c] and the stem's over [L_c, l], as in the VJM springs and in the condensed
  couple stiffness k_r = 1 / (cos^2(beta) c_T + sin^2(beta) c_M). The couple spring is thus pre-strained:
  C = k_r (c . phi - Delta phi_0), which is the plate moment k_r Delta phi_0 c (the fixed-end moment that a
  plate-equivalent force leaves out).

The tool's sag at rest is the condensed compliance (6 x 6, at the plate centre) times that wrench:
:func:`weight_sag_m`. It agrees with the elastic VJM model's static equilibrium under the same masses
(:meth:`pressfit.dynamics.machine.flexible.FlexibleMachine.rest_state`) to a few 1e-3 (the VJM lumps the
distributed weight on springs_per_segment springs: an error O(1/n^2)). Left out: the axial weight's distribution
along the leg's axial compliance (the actuator spring takes the leg's whole axial compliance, as in the VJM).
Assumed, as in the VJM chain: the rod's part inside the cylinder and the moving parts ride on the cylinder's end
(the actuator body), so a cylinder section carries them whichever side of it they sit; carried instead by the bore
where they sit (the piston's guide), the sag moves by 0.04-0.32% at the poses of tests/dynamics/test_leg_weight.py.
Units: SI (m, kg, N, N m, rad).
"""

from __future__ import annotations

import numpy as np

from pressfit.description.machine import Machine
from pressfit.dynamics.inertia import GRAVITY_M_PER_S2
from pressfit.kinematics import leg_vectors, require_all_reachable
from pressfit.mechanics.condensed import condensed_plate_compliance, rotational_compliances
from pressfit.spatial import cross

_GAUSS = np.polynomial.legendre.leggauss(3)  # exact for m(s), piecewise quadratic in s
_IN_CYLINDER = np.array([True, True, False, False])  # leg_weight_loads' four pieces: the first two in the cylinder


def _first_moment(pieces: list, points: list, s: np.ndarray, lower: np.ndarray) -> np.ndarray:
    """sum over the masses at x > lower of (x - s) m_x, kg m, at sections s (..., k) (``lower`` per section;
    a piece (kg/m, s0, s1) and a point (kg, s) give their bounds as numbers or arrays (..., 1))."""
    q = np.zeros_like(s)
    for mu, a, b in pieces:
        lo = np.maximum(a, lower)
        q += np.where(b > lo, mu * ((b - s) ** 2 - (lo - s) ** 2) / 2, 0.0)
    for m, x in points:
        q += np.where(x > lower, m * (x - s), 0.0)
    return q


def leg_weight_loads(machine: Machine, pose_m: np.ndarray, check_reach: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Per leg at reachable poses (..., 3) (m): the force (..., n, 3), N, the leg's weight puts on the plate at its
    plate cardan (module doc: axial share of the rod body, simply supported transverse share) and the plate moment
    (..., n, 3), N m, of its clamped bending k_r Delta phi_0 c_i (world axes). Batched over poses and legs: the leg's
    masses along s (``[mass]``) are the cylinder tube and housing over [0, L_c], the rod over [l - L_r, l], the
    moving parts at l - L_r and the spiders at 0 and l; the integral of m(s) / EI(s) is 3-point Gauss on each
    piece between the breaks 0, L_c, l and l - L_r (a piece of zero length adds nothing). ``check_reach`` False:
    the poses are not checked against the joint limits (a difference stencil about a reachable pose: the closed
    forms hold beyond Table 3's limits)."""
    h = require_all_reachable(machine, pose_m) if check_reach else np.asarray(pose_m, dtype=float)
    g = np.array([0.0, -GRAVITY_M_PER_S2, 0.0])
    forces, lengths, e, q0 = _cardan_forces(machine, h, g)
    mass, lc, rod = machine.mass, machine.cylinder.length_m, machine.stem.length_m
    e_mod, spider = machine.material.youngs_modulus_pa, mass.cardan_spider_mass_kg
    mu_cyl, mu_rod = _line_masses(machine)
    cylinder = (mu_cyl, 0.0, lc)
    # the four pieces between the breaks 0, L_c, l and l - L_r on axis -1: cylinder (0, split), (split, L_c) and stem
    # (L_c, split'), (split', l); s (..., n, 4, 3) the Gauss nodes on each
    ends = lengths[..., 0]
    inner = ends - rod  # the rod's inner end and the moving parts, s
    split_c, split_s = np.clip(inner, 0.0, lc), np.clip(inner, lc, ends)
    a = np.stack([np.zeros_like(ends), split_c, np.full_like(ends, lc), split_s], -1)
    b = np.stack([split_c, np.full_like(ends, lc), split_s, ends], -1)
    nodes, weights = _GAUSS
    s = ((a + b) / 2)[..., None] + ((b - a) / 2)[..., None] * nodes
    # a cylinder section carries the whole rod (it rides on the actuator) and the cylinder beyond s
    lower = np.where(_IN_CYLINDER[:, None], -np.inf, s)
    at = (lengths[..., None], inner[..., None, None], q0[..., None])  # (..., n, 1, 1): broadcast over pieces and nodes
    q = (_first_moment([cylinder], [], s, s)
         + _first_moment([(mu_rod, at[1], at[0])], [(mass.actuator_moving_mass_kg, at[1]), (spider, at[0])], s, lower))
    stiffness = e_mod * np.array([machine.cylinder_section.second_moment_m4] * 2
                                 + [machine.stem_section.second_moment_m4] * 2)
    integral = ((b - a) / 2 * ((q - (at[0] - s) * at[2] / at[0]) @ weights) / stiffness).sum(-1)[..., None]
    sin_beta = (e * machine.cardan_axes).sum(-1, keepdims=True)
    c = (e - sin_beta * machine.cardan_axes) / np.sqrt(1.0 - sin_beta**2)
    c_t, c_m = rotational_compliances(machine, lengths)
    k_r = 1.0 / ((1.0 - sin_beta**2) * c_t + sin_beta**2 * c_m)
    moments = k_r * (c * cross(e, g)).sum(-1, keepdims=True) * integral * c
    return forces, moments


def _line_masses(machine: Machine) -> tuple[float, float]:
    """Mass per length (kg/m) of the cylinder (tube and housing over L_c) and of the stem rod."""
    mass = machine.mass
    return ((machine.cylinder_tube_mass_kg + mass.actuator_housing_mass_kg) / machine.cylinder.length_m,
            mass.density_kg_per_m3 * machine.stem_section.area_m2)


def _cardan_forces(machine: Machine, pose_m: np.ndarray, gravity_m_per_s2: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The force (..., n, 3), N, each leg's weight puts on the plate at its plate cardan under the gravity vector
    (3,), m/s^2 (module doc: the rod body's axial share m_r (g . e) e, the simply supported transverse share
    Q (g - (g . e) e) / l), with the legs' lengths l and first moments Q (..., n, 1), m and kg m, and axes e (..., n,
    3), at poses (..., 3), m (not checked for reach)."""
    mass, lc, rod = machine.mass, machine.cylinder.length_m, machine.stem.length_m
    u = leg_vectors(machine, pose_m)
    lengths = np.sqrt((u * u).sum(-1))[..., None]  # (..., n, 1)
    e = u / lengths
    inner = lengths - rod  # the rod's inner end and the moving parts, s
    mu_cyl, mu_rod = _line_masses(machine)
    q0 = (mu_cyl * lc * lc / 2
          + mu_rod * (lengths**2 - inner**2) / 2 + mass.actuator_moving_mass_kg * inner
          + mass.cardan_spider_mass_kg * lengths)
    ge = (e @ gravity_m_per_s2)[..., None]
    axial = machine.stem_mass_kg + mass.actuator_moving_mass_kg + mass.cardan_spider_mass_kg
    return axial * ge * e + q0 / lengths * (gravity_m_per_s2 - ge * e), lengths, e, q0


def weight_force_n(machine: Machine, pose_m: np.ndarray, gravity_m_per_s2: np.ndarray | None = None) -> np.ndarray:
    """The force part (..., 3), N, of :func:`weight_wrench_n` at poses (..., 3), m (plate, tool and the legs' cardan
    forces; the legs' clamped bending puts only couples on the plate) under the gravity vector (3,), m/s^2 (default
    g = 9.81 along -y): closed form, the poses not checked for reach. By virtual work it is minus the
    rigid-leg model's generalised gravity projected on the plate translations (the controller's feed-forward
    :func:`pressfit.dynamics.control.gravity_feedforward_n`; tests/dynamics/test_leg_weight.py checks it against
    Pinocchio's)."""
    g = np.array([0.0, -GRAVITY_M_PER_S2, 0.0]) if gravity_m_per_s2 is None else np.asarray(gravity_m_per_s2, float)
    forces = _cardan_forces(machine, np.asarray(pose_m, dtype=float), g)[0]
    return (machine.mass.plate_mass_kg + machine.mass.tool_mass_kg) * g + forces.sum(-2)


def weight_wrench_n(machine: Machine, pose_m: np.ndarray, check_reach: bool = True) -> np.ndarray:
    """The machine's weight as a plate wrench (..., 6) at reachable poses (..., 3) (m): force N, moment N m about the
    plate centre, world axes (plate and tool at the centre, the legs' cardan forces and clamped bending: module
    doc; ``check_reach``: as :func:`leg_weight_loads`)."""
    forces, moments = leg_weight_loads(machine, pose_m, check_reach)
    plate = (machine.mass.plate_mass_kg + machine.mass.tool_mass_kg) * np.array([0.0, -GRAVITY_M_PER_S2, 0.0])
    return np.concatenate([plate + forces.sum(-2),
                           cross(machine.plate_offsets_m, forces).sum(-2) + moments.sum(-2)], axis=-1)


def weight_sag_m(machine: Machine, poses_m: np.ndarray, compliance: np.ndarray | None = None,
                 check_reach: bool = True) -> np.ndarray:
    """The tool's static deflection (..., 3), m, under the machine's own weight at reachable poses (..., 3), m: the
    condensed plate compliance times :func:`weight_wrench_n` (module doc); ``compliance`` (..., 6, 6): the condensed
    compliance at those poses where the caller has it already; ``check_reach``: as :func:`leg_weight_loads`."""
    h = np.asarray(poses_m, dtype=float)
    flat = h.reshape(-1, 3)
    wrenches = weight_wrench_n(machine, flat, check_reach)
    compliance = (condensed_plate_compliance(machine, flat) if compliance is None else compliance).reshape(-1, 6, 6)
    return np.einsum("kij,kj->ki", compliance[:, :3], wrenches).reshape(h.shape)
