"""Closed forms of n equal legs on a circle at the centred pose (0, y, 0), shared by the n-leg tests (issue 21).

Every leg has length l = hypot(y, p - r) and elevation sin(alpha) = y / l; its axial stiffness k_a is the
actuator, the cylinder tube and the stem rod in series (sections from the machine file, E A / L each). A vertical
force F through the plate centre passes through P*: each leg carries F / (n sin(alpha)), and with rigid cardans
the vertical stiffness is n k_a sin^2(alpha) (docs/conventions.md, for n = 4)."""

import math

import numpy as np


def centred(machine, y: float) -> tuple[float, float]:
    """sin(alpha) and the axial stiffness k_a (N/m) of every leg at (0, y, 0) (module doc)."""
    g, e = machine.geometry, machine.material.youngs_modulus_pa
    length = math.hypot(y, g.base_half_side_m - g.plate_half_side_m)
    cyl = machine.cylinder
    do, di = cyl.outer_diameter_m, cyl.outer_diameter_m - 2 * cyl.wall_thickness_m
    tube, rod = math.pi / 4 * (do**2 - di**2), math.pi / 4 * machine.stem.diameter_m**2
    lc = machine.cylinder.length_m
    c = 1 / machine.actuator.axial_stiffness_n_per_m + lc / (e * tube) + (length - lc) / (e * rod)
    return y / length, 1 / c


def ring(n: int) -> list[dict]:
    """The ``[[legs]]`` of n legs at 360/n degrees about y, leg 1 at -z."""
    return [{"radial_direction": [math.cos(t), 0.0, math.sin(t)]}
            for t in (math.radians(-90.0 + 360.0 * i / n) for i in range(n))]


def rotation_about_y(angle_rad: float):
    """The (3, 3) rotation by ``angle_rad`` about world y (a leg at theta, (cos theta, 0, sin theta), goes to
    theta - angle_rad)."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def ring_machine_file(path, n: int):
    """Write Tsai's machine file with its legs replaced by :func:`ring` (n) to ``path``; returns the path."""
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "models" / "tsai_3upu.toml").read_text()
    head, tail = text.split("[[legs]]", 1)[0], "[limits]" + text.split("[limits]", 1)[1]
    legs = "".join(f"[[legs]]\nradial_direction = {leg['radial_direction']!r}\n\n" for leg in ring(n))
    path.write_text(head + legs + tail)
    return path
