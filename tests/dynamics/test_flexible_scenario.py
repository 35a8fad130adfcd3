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


def test_the_elastic_column_carries_the_series_springs_and_the_length_columns_the_sensors():
    """Five steps of the shipped insertion on the flexible model, its scenario stepped directly: each row's
    ``elastic_energy_j`` is the machine's elastic energy plus the series springs' N^2 c / 2 (from the row's tensions
    ``act_n`` and the machine's sensed compliance at the actuator joints' lengths), its ``length_m`` columns are those
    lengths less N c and its ``rate_m_per_s`` columns their rates less the stretch's change over the step / dt (the
    first step's from the start state's stretch)."""
    from pressfit.description.cases import load_case
    from pressfit.dynamics import drives
    from pressfit.dynamics.insertion import plan_scenario
    from pressfit.dynamics.series import Guard, series_columns
    from pressfit.shipped import cases_dir

    case = load_case(cases_dir() / "paper" / "insertion.toml")
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"model": "flexible"})})
    machine, plan = case.machine(), plan_scenario(case)
    scenario = FlexibleScenario(case, machine, plan, drives.of(machine), True, Guard(case, machine, plan))
    columns = series_columns(len(machine.legs))
    dt = plan.simulation.time_step_s
    stretch = machine.sensed_axial_compliance_m_per_n(scenario.fm.leg_lengths_m(scenario.state)) * scenario.tension
    for k in range(5):
        scenario.step(k, (k + 1) * dt, plan.trajectory.at((k + 1) * dt), 30.0)
        row = scenario.series.row(k)
        legs = scenario.fm.leg_lengths_m(scenario.state)
        tension = row[[columns.index(f"act_n{i}") for i in "1234"]]
        c = machine.sensed_axial_compliance_m_per_n(legs)
        assert row[columns.index("elastic_energy_j")] == pytest.approx(
            scenario.fm.energy(scenario.state).elastic_j + 0.5 * float(tension @ (c * tension)), rel=1e-12)
        np.testing.assert_allclose(row[[columns.index(f"length_m{i}") for i in "1234"]], legs - c * tension,
                                   rtol=0, atol=1e-15)
        previous, stretch = stretch, c * tension
        np.testing.assert_allclose(row[[columns.index(f"rate_m_per_s{i}") for i in "1234"]],
                                   scenario.fm.leg_rates_m_per_s(scenario.state) - (stretch - previous) / dt,
                                   rtol=0, atol=1e-12)


def test_a_state_that_is_not_finite_is_named_so():
    """A step that leaves the flexible machine's velocity not finite (its configuration finite) stops the run at that
    step, named as a state that is not finite at its time (the guard reads q and v)."""
    from pressfit.description.cases import load_case
    from pressfit.dynamics import drives as drive_kinds
    from pressfit.dynamics.insertion import plan_scenario
    from pressfit.dynamics.series import Guard
    from pressfit.errors import PressfitError
    from pressfit.shipped import cases_dir

    case = load_case(cases_dir() / "paper" / "insertion.toml")
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"model": "flexible"})})
    machine = case.machine()
    plan = plan_scenario(case, machine)
    scenario = FlexibleScenario(case, machine, plan, drive_kinds.of(machine), True, Guard(case, machine, plan))
    step = scenario.fm.step

    def nan_velocity(*args, **kwargs):
        state = step(*args, **kwargs)
        v = state.v.copy()
        v[7] = np.nan
        return type(state)(**{**state.__dict__, "v": v})

    scenario.fm.step = nan_velocity
    with pytest.raises(PressfitError, match=r"diverged at t = 0.001 s \(the state is not finite\)"):
        scenario.step(0, 1e-3, plan.trajectory.at(1e-3), 30.0)


@pytest.mark.slow  # a flexible run, 3 s
def test_the_reference_columns_are_the_planned_path_plus_the_limiters_lift():
    """The flexible run's reference columns (ref_x/y/z_m) are the planned trajectory at each row's time plus the
    force limiter's lift along +y (the reference_lift_m column), to 1e-12 m, on the shipped scenario shortened: the
    lift is non-zero while the limiter holds the force."""
    from pressfit.description.cases import load_case
    from pressfit.dynamics.insertion import plan_scenario, simulate_insertion
    from pressfit.dynamics.series import series_columns
    from pressfit.shipped import cases_dir

    case = load_case(cases_dir() / "paper" / "insertion.toml")
    short = {"model": "flexible", "move_time_s": 0.25, "descent_time_s": 0.25, "dwell_s": 0.3, "settle_s": 0.25}
    case = case.model_copy(update={"simulation": case.simulation.model_copy(update=short)})
    rows = np.asarray(simulate_insertion(case).series, float)
    col = {c: k for k, c in enumerate(series_columns(4))}
    plan = plan_scenario(case, case.machine())
    planned = np.array([plan.trajectory.at(t)[0] for t in rows[:, col["time_s"]]])
    ref = rows[:, [col["ref_x_m"], col["ref_y_m"], col["ref_z_m"]]]
    lift = rows[:, col["reference_lift_m"]]
    np.testing.assert_allclose(ref - np.column_stack([0 * lift, lift, 0 * lift]), planned, rtol=0, atol=1e-12)
    assert lift.max() > 1e-6
