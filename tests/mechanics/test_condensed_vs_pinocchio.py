"""Cross-check: the exact condensed linear statics (pressfit.condensed) against the Pinocchio VJM
solver (pressfit.statics.solve_equilibrium, linear=True), an independent assembly of the same physics
(per-leg spring chains, 6D loop closures, KKT solve). Measured: they agree to ~1e-11; asserted to 1e-9
relative (forces to max |N|, moments to max |M|, motions to their norm) at sampled poses and loads."""

import numpy as np
import pytest

from pressfit.mechanics import condensed
from pressfit.mechanics.statics import solve_equilibrium

POSES = [(0.0, 0.72, 0.0), (0.2, 0.6, -0.15), (-0.25, 0.74, 0.25), (0.1, 0.5, 0.22), (0.25, 0.55, -0.25)]
LOADS = [(0.0, 700.0, 0.0, 0.0, 0.0, 0.0), (120.0, 650.0, -80.0, 10.0, -5.0, 15.0)]
REL = 1e-9


@pytest.mark.parametrize("load", LOADS)
@pytest.mark.parametrize("pose", POSES)
def test_condensed_equals_pinocchio_linear(machine, pose, load):
    eq = solve_equilibrium(machine, pose, load, linear=True)
    assert eq.is_valid(1e-9)
    res = condensed.solve_linear(machine, pose, load)
    n_scale = np.abs(res.axial_forces_n).max()
    np.testing.assert_allclose(eq.actuator_forces_n, res.axial_forces_n, atol=REL * n_scale)
    for name in ("plate_displacement_m", "plate_rotation_rad"):
        ref = getattr(eq, name)
        np.testing.assert_allclose(getattr(res, name), ref, atol=REL * np.linalg.norm(ref) + 1e-18)
    m_scale = max(np.abs(res.leg_moments_nm).max(), 1e-3 * n_scale * machine.geometry.plate_half_side_m)
    for i, leg in enumerate(eq.legs):
        for section in leg.sections.values():  # base cardan, actuator, plate cardan: constant, no shear
            assert pytest.approx(res.axial_forces_n[i], abs=REL * n_scale) == section.N
            assert abs(section.V_x) < REL * n_scale and abs(section.V_y) < REL * n_scale
            np.testing.assert_allclose([section.M_x, section.M_y, section.T], res.leg_moments_nm[i],
                                       atol=REL * m_scale)
