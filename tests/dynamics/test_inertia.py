"""The moving parts' inertias (:mod:`pressfit.dynamics.inertia`) against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from pressfit.dynamics.inertia import stem_pieces


@pytest.mark.parametrize("exposed_m", [0.12, 0.31])
def test_the_stem_pieces_are_solid_rods_of_the_rods_mass(machine, exposed_m):
    """Each piece of the stem (:func:`stem_pieces`, n = 4 springs: the inner part on the actuator body, then the
    exposed rod over the springs' bodies) is a solid rod of length L and radius r along z: mass mu L, centre at its
    span's middle, inertia about its centre m (3 r^2 + L^2) / 12 across and m r^2 / 2 along (the textbook's); the
    moving parts sit on the actuator piece at -L_rod; the masses sum to the rod's and the moving parts'."""
    n, rod, r = 4, machine.stem.length_m, machine.stem.diameter_m / 2
    mu = machine.mass.density_kg_per_m3 * machine.stem_section.area_m2
    spans = [(-rod, -exposed_m + exposed_m / (2 * n))] + [(0.0, exposed_m / n)] * (n - 1) + [(0.0, exposed_m / (2 * n))]
    pieces = stem_pieces(machine, n, exposed_m)
    moving = machine.mass.actuator_moving_mass_kg
    for k, (piece, (z0, z1)) in enumerate(zip(pieces, spans, strict=True)):
        length, m = z1 - z0, mu * (z1 - z0)
        rod_inertia = np.diag([m * (3 * r**2 + length**2) / 12] * 2 + [m * r**2 / 2])
        centre = (z0 + z1) / 2
        if k == 0 and moving > 0:  # the moving parts at -L_rod: the combined body's centre and parallel axes
            total = m + moving
            c = (m * centre - moving * rod) / total
            shift = m * (centre - c) ** 2 + moving * (rod + c) ** 2
            rod_inertia = rod_inertia + np.diag([shift, shift, 0.0])
            m, centre = total, c
        assert piece.mass == pytest.approx(m, rel=1e-12)
        np.testing.assert_allclose(piece.lever, [0.0, 0.0, centre], rtol=0, atol=1e-15)
        np.testing.assert_allclose(piece.inertia, rod_inertia, rtol=1e-12, atol=1e-18)
    assert sum(p.mass for p in pieces) == pytest.approx(mu * rod + moving, rel=1e-12)


def test_the_stem_pieces_are_distinct_objects(machine):
    """The spring bodies' equal pieces are built once (the re-placement writes the same piece into several bodies,
    each a copy): :func:`stem_pieces` hands out distinct objects, so a caller changing one changes no other."""
    pieces = stem_pieces(machine, 4, 0.2)
    assert len({id(p) for p in pieces}) == len(pieces)
    before = pieces[2].mass
    pieces[1].mass = 2 * pieces[1].mass
    assert pieces[2].mass == before
