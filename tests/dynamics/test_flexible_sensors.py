"""The flexible scenario's position sensors (:meth:`FlexibleScenario._sense`) against their closed forms: a sensor
reads l - N c on its side of the series compliance c, its rate the actuator rate less the stretch's change over the
step, the series springs hold N^2 c / 2 and a tension stepping from N_0 to N_1 into them loses c (N_1 - N_0)^2 / 2
(a force step into a massless spring, the ``series_loss_j`` column)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from pressfit.dynamics.machine.flexible_scenario import FlexibleScenario


def test_a_sensor_reads_its_side_of_the_series_spring_and_the_step_loses_the_closed_form():
    c, dt = 2.5e-8, 1e-3  # m/N, s
    n0, n1 = np.array([100.0, -50.0, 20.0, 0.0]), np.array([130.0, -80.0, 20.0, 40.0])  # N
    lengths, rates = np.array([0.70, 0.72, 0.74, 0.76]), np.array([0.01, -0.02, 0.0, 0.03])
    scenario = SimpleNamespace(series_compliance=lambda l: np.full_like(l, c), dt=dt, tension=n1, lengths=lengths,
                               rates=rates, stretch=n0 * c, series_j=0.5 * c * float(n0 @ n0))
    energy, loss = FlexibleScenario._sense(scenario)
    np.testing.assert_allclose(scenario.sensed, lengths - c * n1, rtol=0, atol=1e-18)
    np.testing.assert_allclose(scenario.sensed_rates, rates - c * (n1 - n0) / dt, rtol=0, atol=1e-15)
    assert energy == pytest.approx(0.5 * c * float(n1 @ n1), rel=1e-12)
    assert loss == pytest.approx(0.5 * c * float((n1 - n0) @ (n1 - n0)), rel=1e-9)
    assert loss > 0.0
