"""Closed-loop rigid-leg multibody dynamics (pressfit.dynamics.multibody) with Pinocchio's constraint dynamics."""

import numpy as np
import pinocchio as pin
import pytest
from readme import readme_fragment

from pressfit import kinematics
from pressfit.dynamics.inertia import inertial_model, total_mass_kg
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.errors import PressfitError
from pressfit.mechanics.model import build_model

POSE = np.array([0.05, 0.65, -0.05])


@pytest.fixture(scope="module")
def rigid(machine):
    return rigid_leg_model(machine, POSE)


def test_masses_are_those_of_the_elastic_model(machine, rigid):
    """Lumping the VJM bodies onto the rigid bodies keeps total mass and centre of mass (to round-off)."""
    mm = build_model(machine, POSE)
    full = inertial_model(mm)
    assert pin.computeTotalMass(rigid.model) == pytest.approx(total_mass_kg(full), rel=1e-13)
    np.testing.assert_allclose(pin.centerOfMass(rigid.model, rigid.model.createData(), rigid.reference_q),
                               pin.centerOfMass(full, full.createData(), mm.q0), atol=1e-13)


def test_reference_configuration_is_closed(machine, rigid):
    """Equation 1's joint values close the four loops (closure error at round-off) and the actuator
    coordinates are the closed-form leg lengths."""
    q = rigid.reference_q
    rigid.accelerations(q, np.zeros(rigid.model.nv), np.zeros(rigid.model.nv))
    assert rigid.closure_error_m() < 1e-14
    np.testing.assert_allclose(q[rigid.actuator_q], kinematics.inverse_kinematics(machine, POSE).lengths_m,
                               rtol=1e-15)


def _passive_run(rigid, dt_s: float, duration_s: float = 0.1) -> tuple[float, float, float]:
    q = rigid.reference_q.copy()
    v = rigid.admissible_velocity(q, [0.2, 0.1, -0.2])
    tau = np.zeros(rigid.model.nv)
    e0 = sum(rigid.energy_j(q, v))
    worst_energy, worst_drift = 0.0, 0.0
    for _ in range(round(duration_s / dt_s)):
        q, v = rigid.step(q, v, tau, dt_s)
        worst_drift = max(worst_drift, rigid.closure_error_m())
        worst_energy = max(worst_energy, abs(sum(rigid.energy_j(q, v)) - e0))
    return worst_energy, worst_drift, rigid.energy_j(q, v)[0]


def test_passive_undamped_motion_conserves_energy(rigid):
    """No actuator force, no damping, gravity on, 0.1 s from an admissible velocity (the plate falls and
    gains ~8.5 J of kinetic energy): kinetic + potential energy is conserved up to the first-order error of
    semi-implicit Euler, 1.2e-3 of the kinetic energy at dt = 1e-4 s (tolerance 3e-3) and halving with dt
    (a conservation bug would not scale with dt); the closure drift stays below 1e-6 m (achieved 6e-7)."""
    readme_fragment("(closure drift below 1e-6 m, energy conserved to first order in the time step;")
    e1, drift1, kinetic = _passive_run(rigid, 1e-4)
    e2, drift2, _ = _passive_run(rigid, 5e-5)
    assert kinetic > 5.0  # the run did exchange energy
    assert e1 < 3e-3 * kinetic
    assert e2 == pytest.approx(e1 / 2, rel=0.1)
    assert max(drift1, drift2) < 1e-6


def test_energies_are_the_mass_matrix_quadratic_form_and_the_centre_of_masss_height(rigid):
    """``energy_j`` at a moving state against two other Pinocchio algorithms: kinetic 1/2 v^T M(q) v (the
    composite-rigid-body mass matrix, armature included) and potential -m g . c(q) (the total mass at the centre of
    mass), to 1e-12 relative."""
    q = rigid.reference_q.copy()
    v = rigid.admissible_velocity(q, [0.2, 0.1, -0.2])
    for _ in range(20):
        q, v = rigid.step(q, v, np.zeros(rigid.model.nv), 1e-3)
    kinetic, potential = rigid.energy_j(q, v)
    data = rigid.model.createData()
    mass = pin.crba(rigid.model, data, q)
    mass = np.triu(mass) + np.triu(mass, 1).T
    assert kinetic == pytest.approx(0.5 * v @ mass @ v, rel=1e-12) and kinetic > 0.01
    com = pin.centerOfMass(rigid.model, data, q)
    expected = -pin.computeTotalMass(rigid.model) * float(np.asarray(rigid.model.gravity.linear) @ com)
    assert potential == pytest.approx(expected, rel=1e-12) and potential != pytest.approx(kinetic, rel=0.5)


def test_bad_baumgarte_rate(machine):
    with pytest.raises(PressfitError, match="baumgarte"):
        rigid_leg_model(machine, POSE, baumgarte_rad_per_s=0.0)


def test_holding_a_pose_under_a_constant_load_gives_the_static_actuator_forces(machine):
    """A constant plate force W (N) at pose POSE, gravity off. Reference: the linear elastic statics
    (mechanics.statics, the VJM model with its leg and cardan springs). Its axial forces balance W alone (a
    UPU leg carries no shear at linear order, so A N = W exactly) and split the redundancy by the legs'
    stiffnesses: N_static = A^+ W + (v_p . N_static) v_p. Commanding the drives with equation 5's
    Moore-Penrose inverse plus that same preload a4 = v_p . N_static (the same redundancy resolution) must
    then give N_static to the statics' residual (1e-9 relative), the rigid-leg dynamics (Pinocchio's
    constraint dynamics, which knows nothing of equation 5) must stay at rest (accelerations at round-off,
    1e-9 of W / m) and the closure forces must carry the tensions to the plate (axial force at the plate
    cardan = tension: massless legs without gravity). With gravity on, the feed-forward G added to the
    command holds the pose as well."""
    from pressfit.dynamics.actuators import distribute
    from pressfit.dynamics.control import gravity_feedforward_n
    from pressfit.mechanics.statics import solve_equilibrium

    w = np.array([25.0, -300.0, 40.0])
    eq = solve_equilibrium(machine, POSE, np.concatenate([w, np.zeros(3)]), linear=True)
    a4 = float(kinematics.preload_vector(machine, POSE) @ eq.actuator_forces_n)
    tension = distribute(machine, POSE, -w, a4)  # the drives push back against W
    np.testing.assert_allclose(tension, eq.actuator_forces_n, rtol=0, atol=1e-9 * np.abs(w).max())
    rigid = rigid_leg_model(machine, POSE)
    mass = pin.computeTotalMass(rigid.model)
    q, v, tau = rigid.reference_q.copy(), np.zeros(rigid.model.nv), np.zeros(rigid.model.nv)
    tau[rigid.actuator_v], tau[0:3] = -tension, w  # the plate is unrotated: local = world axes
    weight = rigid.model.gravity
    rigid.model.gravity = pin.Motion.Zero()
    try:
        assert np.abs(rigid.accelerations(q, v, tau)).max() < 1e-9 * np.abs(w).max() / mass
        np.testing.assert_allclose(rigid.leg_loads()[:, 0], tension, rtol=1e-9)
        for _ in range(100):
            q, v = rigid.step(q, v, tau, 1e-3)
        assert np.abs(q[0:3] - POSE).max() < 1e-10
    finally:
        rigid.model.gravity = weight
    q = rigid.reference_q.copy()
    tau[rigid.actuator_v] = -distribute(machine, POSE, -w + gravity_feedforward_n(rigid, POSE), a4)
    assert np.abs(rigid.accelerations(q, np.zeros(rigid.model.nv), tau)).max() < 1e-8 * np.abs(w).max() / mass


def test_a_machine_with_cardan_tilts_is_refused(machine):
    """Rigid legs close the loops only with parallel cardan axes (Tsai's condition): a tilted machine is refused
    with a named error, not simulated with its tilts silently dropped."""
    from pressfit.dynamics.multibody import rigid_leg_model
    from pressfit.errors import PressfitError

    legs = [leg.model_dump() for leg in machine.legs]
    legs[1]["base_cardan_tilt_rad"] = [0.0, 0.01, 0.0]
    tilted = machine.with_overrides({"legs": legs})
    with pytest.raises(PressfitError, match="cardan tilts"):
        rigid_leg_model(tilted, [0.0, 0.72, 0.0])


def test_path_nodes_are_at_most_the_spacing_apart_and_every_sample_is_near_one():
    """``path_nodes`` of a sampled path (0.5 mm samples on straight segments, with a dwell's repeated points): the
    first and last samples kept, consecutive nodes at most the spacing apart (infinity norm), every sample within
    half the spacing of one, and no more than twice the nodes the path's length needs."""
    from pressfit.dynamics.multibody import path_nodes

    waypoints = np.array([[0.0, 0.7, 0.0], [0.1, 0.62, -0.05], [0.1, 0.6, -0.05], [0.1, 0.6, -0.05], [0.2, 0.7, 0.1]])
    samples = []
    for a, b in zip(waypoints[:-1], waypoints[1:], strict=True):
        n = max(2, int(np.ceil(np.linalg.norm(b - a) / 5e-4)) + 1)
        samples.append(a + np.linspace(0.0, 1.0, n)[:, None] * (b - a))
    path = np.concatenate(samples)
    for spacing in (1e-3, 2e-3, 7e-3):
        nodes = path_nodes(path, spacing)
        assert np.array_equal(nodes[0], path[0]) and np.array_equal(nodes[-1], path[-1])
        assert np.abs(np.diff(nodes, axis=0)).max() <= spacing * (1 + 1e-12)
        nearest = np.abs(path[:, None, :] - nodes[None]).max(axis=2).min(axis=1)
        assert nearest.max() <= 0.5 * spacing * (1 + 1e-12)
        length = np.abs(np.diff(waypoints, axis=0)).max(axis=1).sum()
        assert len(nodes) <= 2 * (length / spacing + len(waypoints))
    assert len(path_nodes(path[:1].repeat(3, axis=0), 2e-3)) == 2  # a path that does not move: its point, twice


def test_the_closure_error_is_the_largest_leg_gap_of_the_last_dynamics_call(rigid):
    """closure_error_m (the constraint datas' errors read through held views) after constraintDynamics at a
    configuration opened by a random change (every leg's closure open by a different amount), then again after a
    second call at another one (the views follow): the largest distance between each closure's two anchor points,
    from forwardKinematics and the constraint models' joint placements, to 1e-6 relative (Pinocchio's error is the
    linear part of the relative placement's log, which differs from the gap at second order in the rotation:
    1e-12 relative here)."""
    rng = np.random.default_rng(3)
    tau, v = np.zeros(rigid.model.nv), np.zeros(rigid.model.nv)
    data = rigid.model.createData()
    for size in (1e-4, 3e-5):
        q = pin.integrate(rigid.model, rigid.reference_q, size * rng.standard_normal(rigid.model.nv))
        rigid.accelerations(q, v, tau)
        pin.forwardKinematics(rigid.model, data, q)
        gaps = [np.linalg.norm(data.oMi[cm.joint1_id].act(cm.joint1_placement.translation)
                               - data.oMi[cm.joint2_id].act(cm.joint2_placement.translation))
                for cm in rigid.constraint_models]
        assert max(gaps) > 1.5 * min(gaps) > 0.0  # the legs open differently
        assert rigid.closure_error_m() == pytest.approx(max(gaps), rel=1e-6)
