"""The flexible machine (pressfit.dynamics.machine.flexible) against independent answers: the natural modes of
pressfit.dynamics.modes, energy conservation, the static solver, the machine's mirror symmetries and the exact
frequency and damping maps of the trapezoidal rule (Newmark's average acceleration, docs/dynamics.md)."""

import numpy as np
import pinocchio as pin
import pytest

from pressfit import kinematics
from pressfit.description.machine import Damping
from pressfit.dynamics.machine.base import SECTIONS, DriveInput
from pressfit.dynamics.machine.flexible import MAX_STEP_FRACTION, FlexibleMachine, Rayleigh
from pressfit.dynamics.modes import natural_modes
from pressfit.errors import ConvergenceError, ModelFileError, PressfitError
from pressfit.mechanics.statics import solve_equilibrium

POSE_A = np.array([0.0, 0.72, 0.0])
OFF_CENTRE = np.array([0.05, 0.65, -0.08])
UNDAMPED = Rayleigh(alpha_per_s=0.0, beta_s=0.0)
H = 1e-3


def _modal_history(fm, state, phi, steps, h=H):
    """Modal coordinate z_n = phi^T M (q_n - q_0) (q_0 the start) over ``steps`` steps, drives holding."""
    m0 = fm._mass(state.q)
    z, s = [0.0], state
    for _ in range(steps):
        s = fm.step(s, s.drive, np.zeros(6), h)
        z.append(phi @ m0 @ pin.difference(fm.model, state.q, s.q))
    return np.array(z)


def _tustin_pole(z, h):
    """Continuous pole s of a sampled free response: z_{n+1} = c1 z_n + c2 z_{n-1} fitted by least squares gives
    the discrete pole p; the trapezoidal rule maps s to p = (1 + s h/2) / (1 - s h/2) exactly (for a linear
    mode), so s = (2/h) (p - 1) / (p + 1)."""
    a = np.column_stack([z[1:-1], z[:-2]])
    c1, c2 = np.linalg.lstsq(a, z[2:], rcond=None)[0]
    p = np.roots([1.0, -c1, -c2])[0]
    return 2 / h * (p - 1) / (p + 1)


@pytest.mark.parametrize("mode", [0, 2, 3])
def test_free_vibration_reproduces_the_natural_modes(machine, mode):
    """Small free vibration at pose A started on a mode shape (mass-normalised phi_k of natural_modes, no load,
    no gravity, undamped, rho_inf = 1): the frequency of the response projected on phi_k, through the
    trapezoidal rule's exact map tan(w_num h / 2) = w h / 2, equals the mode's to 1e-8 (achieved 1e-9; the
    issue asks 1e-3). Unmapped, the sampled frequency is off by (w h)^2 / 12: 0.1% at mode 1, 2% at mode 3."""
    modes = natural_modes(machine, POSE_A, count=4, plate_wrench=np.zeros(6))
    fm = FlexibleMachine(machine, POSE_A, gravity=False, damping=UNDAMPED, rho_inf=1.0)
    rest = fm.rest_state()
    phi = modes.shapes[mode]
    z = _modal_history(fm, fm.with_velocity(rest, 1e-4 * phi), phi, 300)
    s = _tustin_pole(z, H)
    assert abs(s.real) < 1e-6 * abs(s)  # undamped
    f = abs(s) / (2 * np.pi)
    assert f == pytest.approx(modes.frequencies_hz[mode], rel=1e-8)


def test_modal_damping_ratios_are_those_fitted(machine):
    """[damping] kind = "modal", 2% at modes 1 and 3 (the machine file's default): the free decay of mode 3 at
    pose A (the drives holding, rho_inf = 1) has, through the trapezoidal rule's exact map, damping ratio
    0.02 and the mode's undamped frequency (both to 1e-10, achieved 6e-13 and 9e-13)."""
    modes = natural_modes(machine, POSE_A, count=3, plate_wrench=np.zeros(6))
    fm = FlexibleMachine(machine, POSE_A, gravity=False, damping=Damping(modes=[1, 3], ratios=[0.02, 0.02]),
                         rho_inf=1.0)
    np.testing.assert_allclose(fm.modal_damping_ratios()[[0, 2]], [0.02, 0.02], rtol=1e-12)
    z = _modal_history(fm, fm.with_velocity(fm.rest_state(), 1e-4 * modes.shapes[2]), modes.shapes[2], 200)
    s = _tustin_pole(z, H)
    assert -s.real / abs(s) == pytest.approx(0.02, rel=1e-10)
    assert abs(s) / (2 * np.pi) == pytest.approx(modes.frequencies_hz[2], rel=1e-10)


def test_a_modal_fit_needing_a_negative_coefficient_is_refused(machine):
    """beta = 2 (z2 w2 - z1 w1) / (w2^2 - w1^2) is negative just below z2 / z1 = w1 / w2: refused there, fitted
    just above it (alpha, beta >= 0)."""
    fm = FlexibleMachine(machine, POSE_A, gravity=False)
    w1, w3 = fm.modes.frequencies_hz[[0, 2]]
    edge = 0.02 * w1 / w3
    fit = FlexibleMachine(machine, POSE_A, damping=Damping(ratios=[0.02, edge * (1 + 1e-6)]))
    assert fit.damping.beta_s >= 0 and fit.damping.alpha_per_s > 0
    with pytest.raises(PressfitError, match="negative Rayleigh coefficient"):
        FlexibleMachine(machine, POSE_A, damping=Damping(ratios=[0.02, edge * (1 - 1e-6)]))


def test_damping_table_is_strict(machine):
    with pytest.raises(ModelFileError, match="damping"):
        machine.with_overrides({"damping": {"kind": "rayleigh", "alpha_per_s": 1.0}})
    with pytest.raises(ModelFileError, match="damping"):
        machine.with_overrides({"damping": {"modes": [1, 3], "beta_s": 1e-4}})
    m = machine.with_overrides({"damping": {"kind": "rayleigh", "alpha_per_s": 1.0, "beta_s": 1e-4}})
    assert FlexibleMachine(m, POSE_A).damping == Rayleigh(alpha_per_s=1.0, beta_s=1e-4)


def _energy_drift(machine, h, rho_inf=1.0, duration=0.3):
    fm = FlexibleMachine(machine, OFF_CENTRE, damping=UNDAMPED, rho_inf=rho_inf)
    rest = fm.rest_state()
    phi = fm._modes(rest.q, 6).shapes
    s = fm.with_velocity(rest, 3e-3 * phi.sum(0))
    e0 = fm.energy(s)
    dev = 0.0
    for _ in range(round(duration / h)):
        s = fm.step(s, s.drive, np.zeros(6), h)
        dev = max(dev, abs(fm.energy(s).total_j - e0.total_j))
    return dev / e0.kinetic_j


def test_passive_undamped_run_conserves_energy(machine):
    """Gravity on, drives holding, no damping, rho_inf = 1: the six lowest modes excited together at an off-centre
    pose (plate amplitude ~3 um); over 0.3 s the total energy (kinetic + elastic + gravitational) stays within
    4e-6 of the initial kinetic energy at h = 1 ms (measured 1.3e-6), and the error falls as about h^2 (measured
    3.2x from 1 ms to 0.5 ms). With rho_inf = 0.8 the scheme's numerical damping removes far more."""
    d1, d2 = _energy_drift(machine, 1e-3), _energy_drift(machine, 5e-4)
    assert d1 < 4e-6
    assert d1 / d2 > 2.5
    assert _energy_drift(machine, 1e-3, rho_inf=0.8) > 100 * d1


def test_energies_are_the_mass_matrix_quadratic_form_and_the_centre_of_masss_height(machine):
    """``energy`` of a moving state against other Pinocchio algorithms: kinetic 1/2 v^T M(q) v (``crba``, armature
    included) and potential -m g . c(q) (the total mass at the centre of mass), to 1e-12 relative (the energy
    balance sums the two, so only a test of each tells them apart)."""
    fm = FlexibleMachine(machine, POSE_A, springs_per_segment=2)
    s = fm.rest_state()
    s = fm.with_velocity(s, 1e-3 * np.random.default_rng(2).normal(size=fm.nv))
    for _ in range(5):
        s = fm.step(s, s.drive, np.zeros(6), 1e-3)
    e = fm.energy(s)
    data = fm.model.createData()
    mass = pin.crba(fm.model, data, s.q)
    mass = np.triu(mass) + np.triu(mass, 1).T
    assert e.kinetic_j == pytest.approx(0.5 * s.v @ mass @ s.v, rel=1e-12) and e.kinetic_j > 1e-9
    com = pin.centerOfMass(fm.model, data, s.q)
    expected = -pin.computeTotalMass(fm.model) * float(np.asarray(fm.model.gravity.linear) @ com)
    assert e.potential_j == pytest.approx(expected, rel=1e-12)
    assert abs(e.potential_j - e.kinetic_j) > 0.5 * abs(e.potential_j)


def _section_array(eq):
    return np.array([[[sw.N, sw.V_x, sw.V_y, sw.M_x, sw.M_y, sw.T] for sw in (leg.sections[k] for k in SECTIONS)]
                     for leg in eq.legs])


def test_holding_a_pose_under_a_wrench_reproduces_the_static_solver(machine):
    """No gravity (the statics' legs are massless), the drives holding the rigid lengths, a constant plate wrench
    applied at t = 0 from the unloaded state, heavily damped (70% at modes 1 and 3, rho_inf = 0.5) for 0.4 s: the
    leg section resultants at all three sections and the plate displacement equal solve_equilibrium's (the
    geometrically nonlinear Newton KKT solve) to 1e-9 of the largest resultant (achieved 1.5e-10) and 1e-12 m."""
    wrench = np.array([40.0, -250.0, 25.0, 6.0, -4.0, 3.0])
    eq = solve_equilibrium(machine, OFF_CENTRE, wrench)
    ref = _section_array(eq)
    fm = FlexibleMachine(machine, OFF_CENTRE, gravity=False, rho_inf=0.5,
                         damping=Damping(modes=[1, 3], ratios=[0.7, 0.7]))
    s = fm.rest_state()
    for _ in range(400):
        s = fm.step(s, s.drive, wrench, H)
    loads = fm.section_loads(s)
    scale = np.abs(ref).max()
    np.testing.assert_allclose(loads.values, ref, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(fm.tool_point_m(s) - OFF_CENTRE, eq.plate_displacement_m, rtol=0, atol=1e-12)
    # the plate-section N (deformed leg frame) is not exactly the actuator spring's force: in the nonlinear state
    # the stem's small shear projects on the leg axis (measured up to 1.3e-7 N here, 1e-9 of the largest)
    np.testing.assert_allclose(loads.axial_n("plate"), eq.actuator_forces_n, rtol=0, atol=1e-8 * scale)
    static = fm.section_loads(fm.rest_state(wrench)).values  # the model's own static Newton: same answer
    np.testing.assert_allclose(static, ref, rtol=0, atol=1e-9 * scale)


def test_a_pure_plate_moment_is_held_as_the_static_solver_holds_it(machine):
    """A plate wrench of moments only (no force) at rest, no gravity: the flexible machine's static equilibrium
    (rest_state, the step's generalised forces of the wrench) gives solve_equilibrium's leg section resultants (a
    wrench whose force part is zero must still turn the moment into the plate's generalised forces). Achieved
    2.4e-8 N on the axial forces of 0.18 N (the static solvers' round-off on loads this small): held to 1e-6 of the
    largest resultant, against the moment's whole effect."""
    moment = np.array([0.0, 0.0, 0.0, 6.0, -4.0, 3.0])
    ref = _section_array(solve_equilibrium(machine, OFF_CENTRE, moment))
    fm = FlexibleMachine(machine, OFF_CENTRE, gravity=False)
    got = fm.section_loads(fm.rest_state(moment)).values
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-6 * np.abs(ref).max())
    assert np.abs(ref).max() > 1.0


def test_the_newton_stops_on_the_largest_correction_of_either_sign(machine, monkeypatch):
    """Every step ends on an iteration whose largest position correction, of either sign, is within NEWTON_TOL
    (module doc): the corrections of the last iteration of each of 30 steps under a changing wrench, read from the
    iteration-matrix solves."""
    from pressfit.dynamics.machine.flexible import NEWTON_TOL

    fm = FlexibleMachine(machine, OFF_CENTRE)
    last = []
    solve = fm._solve
    monkeypatch.setattr(fm, "_solve", lambda rhs: last.append(solve(rhs)) or last[-1])
    s = fm.rest_state()
    ends = []
    for n in range(30):
        s = fm.step(s, s.drive, (n % 7) * np.array([30.0, -60.0, 20.0, 2.0, -1.0, 1.0]), H)
        ends.append(np.abs(last[-1][:fm.nv]).max())
    assert max(ends) <= NEWTON_TOL
    assert any(np.abs(x[:fm.nv]).max() > 1e-9 for x in last)  # the steps did iterate


def test_a_commanded_motion_is_not_damped_where_a_leg_stands_still(machine):
    """Position drives commanding the plate along a direction square to leg 1 (its rate zero, the others' not: the
    rates e_i . v of the rigid kinematics, equations 2-3, by central differences of the inverse kinematics), 10 mm/s,
    stiffness-proportional damping only (beta 1e-4 s), no gravity: the damping acts on the elastic motion v - v_r
    only (v_r the rigid machine's velocity at the commanded rates, a zero rate among them), so its work over 60
    steps is below a tenth of what it would do on the commanded motion, beta sum k_a rate^2 T (k_a the actuator
    springs: the ramp seen as an elastic rate). Achieved 2.3% (the start's transient: the springs accelerating the
    machine); damping the commanded motion (v_r left zero) does 102%."""
    fm = FlexibleMachine(machine, OFF_CENTRE, gravity=False, damping=Rayleigh(alpha_per_s=0.0, beta_s=1e-4))
    step = 1e-7
    jac = np.array([(kinematics.inverse_kinematics(machine, OFF_CENTRE + step * e).lengths_m
                     - kinematics.inverse_kinematics(machine, OFF_CENTRE - step * e).lengths_m) / (2 * step)
                    for e in np.eye(3)]).T  # dl/dh (n, 3)
    direction = np.cross(jac[0], [0.0, 1.0, 0.0])
    rates = jac @ (1e-2 * direction / np.linalg.norm(direction))
    rates[0] = 0.0  # square to leg 1 (1e-17 m/s of round-off)
    s = fm.rest_state()
    lengths, steps, work = s.drive.values.copy(), 60, 0.0
    for _ in range(steps):
        lengths = lengths + rates * H
        s = fm.step(s, DriveInput.positions(lengths), np.zeros(6), H)
        work += s.damping_work_j
    naive = 1e-4 * float(fm._k[fm.act] @ rates**2) * steps * H
    assert naive > 1e-4 and np.abs(rates[1:]).min() > 1e-3
    assert abs(work) < 0.1 * naive


def test_the_cardan_contacts_nonlinear_springs_settle_where_the_static_newton_holds(machine):
    """The cardans' contacts as nonlinear virtual springs in the flexible machine (``cardan_compliance`` of
    Clearance.uniform with no clearance: the contact stiffness at every cardan, a nonlinear law whose dead zone is
    closed), no gravity, the drives holding, the plate wrench applied at t = 0 and held for 0.4 s heavily damped:
    the step (the laws' force and tangent in its Newton residual and iteration matrix) settles where the machine's
    own static Newton (rest_state: the KKT of the springs, a second formulation) holds the wrench, section
    resultants to 1e-6 of the largest, and the plate moves more than on the machine without the contacts."""
    from pressfit.mechanics.clearance import Clearance

    plays = Clearance.uniform(machine, 0.0).cardan_compliance()
    wrench = np.array([40.0, -250.0, 25.0, 6.0, -4.0, 3.0])
    fm = FlexibleMachine(machine, OFF_CENTRE, gravity=False, rho_inf=0.5, cardan_compliance=plays,
                         damping=Damping(modes=[1, 3], ratios=[0.7, 0.7]))
    assert fm.nonlinear  # the contacts' laws are the nonlinear springs
    s = fm.rest_state()
    for _ in range(400):
        s = fm.step(s, s.drive, wrench, H)
    static = fm.rest_state(wrench)
    ref = fm.section_loads(static).values
    np.testing.assert_allclose(fm.section_loads(s).values, ref, rtol=0, atol=1e-6 * np.abs(ref).max())
    stiff = FlexibleMachine(machine, OFF_CENTRE, gravity=False)
    moved, elastic = (np.linalg.norm(m.tool_point_m(x) - OFF_CENTRE) for m, x in
                      ((fm, static), (stiff, stiff.rest_state(wrench))))
    assert moved - elastic > 1e-7  # 0.23 um more (the contact stiffness in series)


def test_open_cardan_plays_are_refused_naming_the_law(machine):
    """Open plays (20 um of clearance at every cardan) as the flexible machine's virtual springs: their joints are
    massless and their dead zones have no stiffness, so every step would be refused as diverged; the machine refuses
    them when built, naming the leg and the law (1 um of clearance too; with none, the contact laws alone, it builds:
    test_the_cardan_contacts_...)."""
    from pressfit.mechanics.clearance import Clearance

    for gap in (20e-6, 1e-6):
        with pytest.raises(PressfitError, match=r"leg 1's .* no stiffness at its rest .* \[simulation\] clearance"):
            FlexibleMachine(machine, OFF_CENTRE, cardan_compliance=Clearance.uniform(machine, gap).cardan_compliance())


MIRRORS = {"x": (np.array([-1.0, 1.0, 1.0]), [0, 3, 2, 1]), "z": (np.array([1.0, 1.0, -1.0]), [2, 1, 0, 3])}


def _dynamic_loads(machine, pose, wrench, steps=60):
    fm = FlexibleMachine(machine, pose)
    s = fm.rest_state()
    out = []
    for n in range(steps):
        s = fm.step(s, s.drive, wrench if n >= 5 else np.zeros(6), H)
        out.append(fm.section_loads(s).values)
    return np.array(out)


@pytest.mark.parametrize("axis", ["x", "z"])
def test_mirror_scenarios_give_mirror_leg_loads(machine, axis):
    """A reflection of the machine (x -> -x swaps legs 2 and 4; z -> -z swaps legs 1 and 3) maps the pose, the
    force (polar vector) and the moment (axial vector: m -> -R m) of a wrench step applied at 5 ms, with gravity,
    the drives holding: over 60 ms of the transient the mirrored legs carry the same axial force N, shear and
    bending magnitudes and the opposite torsion T (a reflection flips an axial moment about an axis it maps to its
    image) to 2e-9 of the largest load (255 N; measured 4e-10: the floor is the actuator spring's 5e7 N/m times
    the ulp of a 0.8 m leg coordinate, 5.5e-9 N, times the few ulps the Newton solution ends at)."""
    r, perm = MIRRORS[axis]
    pose = np.array([0.06, 0.66, -0.09])
    wrench = np.array([30.0, -150.0, 20.0, 4.0, -3.0, 2.0])
    mirrored = np.concatenate([r * wrench[:3], -r * wrench[3:]])
    a = _dynamic_loads(machine, pose, wrench)
    b = _dynamic_loads(machine, r * pose, mirrored)[:, perm]
    tol = 2e-9 * np.abs(a).max()
    assert np.abs(a[..., 0]).max() > 50.0  # the transient is not trivial
    np.testing.assert_allclose(b[..., 0], a[..., 0], rtol=0, atol=tol)
    np.testing.assert_allclose(b[..., 5], -a[..., 5], rtol=0, atol=tol)
    for cols in ([1, 2], [3, 4]):
        np.testing.assert_allclose(np.hypot(*b[..., cols].transpose(3, 0, 1, 2)),
                                   np.hypot(*a[..., cols].transpose(3, 0, 1, 2)), rtol=0, atol=tol)


def test_closure_stays_closed_over_a_large_move(machine):
    """The insertion case's first move (from (-0.15, 0.65, 0.10) to above the pin at (0.10, 0.605, -0.05) m: 0.3 m)
    as a quintic in 0.4 s, position drives on the inverse kinematics, gravity and the default damping: every
    step's loop-closure error stays below 1e-13 m and 1e-13 rad (measured ~5e-15), the tool stays within 1 mm of
    the reference (elastic deflection under the machine's own inertia and weight), and the leg lengths the drives
    measure stay within 0.1 mm of the commanded rest lengths (the actuator springs' stretch)."""
    start, end = np.array([-0.15, 0.65, 0.10]), np.array([0.10, 0.605, -0.05])
    fm = FlexibleMachine(machine, start)
    s = fm.rest_state()
    n = 400
    u = np.minimum(np.arange(1, n + 51) / n, 1.0)
    poses = start + np.outer(10 * u**3 - 15 * u**4 + 6 * u**5, end - start)
    worst = np.zeros(4)
    for pose, lengths in zip(poses, kinematics.inverse_kinematics(machine, poses).lengths_m):
        s = fm.step(s, DriveInput.positions(lengths), np.zeros(6), H)
        worst = np.maximum(worst, [*fm.closure_error(s), np.linalg.norm(fm.tool_point_m(s) - pose),
                                   np.abs(fm.leg_lengths_m(s) - lengths).max()])
    assert worst[0] < 1e-13 and worst[1] < 1e-13
    assert 1e-6 < worst[2] < 1e-3
    assert worst[3] < 1e-4


def test_a_step_longer_than_the_bound_is_refused(machine):
    """The bound is MAX_STEP_FRACTION of the first mode's period at the build pose: just below it the step runs,
    just above it is refused with one line naming the bound and the mode."""
    fm = FlexibleMachine(machine, POSE_A)
    bound = MAX_STEP_FRACTION * fm.first_period_s
    assert fm.first_period_s == pytest.approx(1 / natural_modes(machine, POSE_A, count=1).frequencies_hz[0], rel=1e-5)
    s = fm.rest_state()
    fm.step(s, s.drive, np.zeros(6), bound * (1 - 1e-9))
    with pytest.raises(PressfitError, match=r"time step .* first mode's period") as err:
        fm.step(s, s.drive, np.zeros(6), bound * (1 + 1e-9))
    assert "\n" not in str(err.value)
    for bad in (0.0, -1e-3, float("nan")):
        with pytest.raises(PressfitError, match="time step"):
            fm.step(s, s.drive, np.zeros(6), bad)


def test_a_step_newton_cannot_integrate_is_refused(machine):
    """Force drives jumping from the holding forces to 1e7 N of tension in one step would pull the plate through
    the base within the step: Newton cannot converge and the step is refused (ConvergenceError, one line naming
    the time); a 100 N jump on the same state integrates."""
    fm = FlexibleMachine(machine, POSE_A)
    s = fm.rest_state()
    held = fm.section_loads(s).axial_n("plate")
    s1 = fm.step(s, DriveInput.forces(held + 100.0), np.zeros(6), H)
    assert np.isfinite(s1.q).all()
    with pytest.raises(ConvergenceError, match="flexible step at t = 0.001 s") as err:
        fm.step(s, DriveInput.forces(held + 1e7), np.zeros(6), H)
    assert "\n" not in str(err.value)


def test_bad_inputs_are_refused(machine):
    fm = FlexibleMachine(machine, POSE_A)
    s = fm.rest_state()
    with pytest.raises(PressfitError, match="drive input"):
        fm.step(s, DriveInput("force", np.zeros(3)), np.zeros(6), H)
    with pytest.raises(PressfitError, match="plate_wrench"):
        fm.step(s, s.drive, np.array([np.nan, 0, 0]), H)
    with pytest.raises(PressfitError, match="rho_inf"):
        FlexibleMachine(machine, POSE_A, rho_inf=1.5)
    with pytest.raises(PressfitError, match="force drives hold no pose"):
        fm.rest_state(drive=DriveInput.forces(np.zeros(4)))


def test_a_stiffness_in_series_with_the_actuators_softens_the_vertical_press_by_the_closed_form(machine):
    """``actuator_series_n_per_m`` k_s (the closed cardan plays, k_c / 2) in series with every actuator spring: at
    pose A a vertical press F loads the four legs alike, N = F / (4 sin alpha), each leg lengthens by N / k_s more,
    and the plate moves down by that over sin alpha: du_y = F / (4 k_s sin^2 alpha), sin^2 alpha = 0.8 (tan alpha
    = 2 at pose A). With F = 700 N, k_s = 5e7 N/m: 4.375 um, the two rest states (no gravity) to 1e-3 of it."""
    force, ks = 700.0, 5e7
    wrench = np.array([0.0, -force, 0.0, 0.0, 0.0, 0.0])
    tools = [FlexibleMachine(machine, POSE_A, gravity=False, actuator_series_n_per_m=series) for series in (None, ks)]
    y = [fm.tool_point_m(fm.rest_state(wrench))[1] for fm in tools]
    assert y[0] - y[1] == pytest.approx(force / (4 * ks * 0.8), rel=1e-3)
    with pytest.raises(PressfitError, match="actuator_series_n_per_m"):
        FlexibleMachine(machine, POSE_A, actuator_series_n_per_m=-1.0)


def test_a_constant_contact_in_the_step_is_the_same_force_as_a_held_wrench(machine):
    """The implicit contact (``step``'s ``contact``, a world +y force on the plate centre) against the held plate
    wrench path (``_external``: R^T f on the free flyer): with a contact that does not depend on the plate's y
    (100 N, stiffness 0) three steps from a tilted rest state (an off-centre pose, the plate turned by the weight)
    give the same states to 1e-13 m and rad."""
    pose = np.array([0.15, 0.62, -0.1])
    fm = FlexibleMachine(machine, pose)
    state = fm.rest_state()
    assert np.abs(state.q[3:6]).max() > 1e-5  # the premise: the plate is turned, R differs from R^T
    tensions = DriveInput.forces(np.full(len(machine.legs), 60.0))
    held, implicit = state, state
    for _ in range(3):
        held = fm.step(held, tensions, np.array([0.0, 100.0, 0.0, 0.0, 0.0, 0.0]), 1e-3)
        implicit = fm.step(implicit, tensions, np.zeros(6), 1e-3, contact=lambda y: (100.0, 0.0))
        assert np.abs(fm.tool_point_m(held) - fm.tool_point_m(implicit)).max() < 1e-13
        assert np.abs(pin.difference(fm.model, held.q, implicit.q)).max() < 1e-13
