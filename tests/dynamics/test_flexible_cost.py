"""What one step of the flexible machine (pressfit.dynamics.machine.flexible) costs in Pinocchio evaluations, and
that the shortcuts behind that count give the answers of the direct computations they replace."""

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from pressfit.dynamics.machine.base import DriveInput
from pressfit.dynamics.machine.flexible import FlexibleMachine, Rayleigh

OFF_CENTRE = np.array([0.05, 0.65, -0.08])
WRENCH = np.array([40.0, -250.0, 25.0, 6.0, -4.0, 3.0])
H = 1e-3


def _counting(monkeypatch, names):
    counts = dict.fromkeys(names, 0)
    for name in names:
        original = getattr(pin, name)

        def counted(*args, _original=original, _name=name, **kwargs):
            counts[_name] += 1
            return _original(*args, **kwargs)

        monkeypatch.setattr(pin, name, counted)
    return counts


def test_a_step_evaluates_the_closures_once_per_iteration_and_once_at_its_end(machine, monkeypatch):
    """Position drives ramping the lengths by 2 um per step (so the rigid velocity is needed every step and the
    stems are re-placed every few steps) under a plate wrench, with the insertion's per-step reads (closure error,
    section loads): the closure Jacobian (computeJointJacobians) is evaluated once per Newton iteration, once at
    each step's end state (shared by the closure error and the next step's rigid velocity) and once after each
    re-placement of the stems; the mass matrix (crba) only when the iteration matrix is refactored. The code
    before this count evaluated the Jacobian three more times per step and crba every step."""
    fm = FlexibleMachine(machine, OFF_CENTRE)
    s = fm.rest_state()
    placements = []
    place = fm.mm.place_stem
    monkeypatch.setattr(fm.mm, "place_stem", lambda *args: (placements.append(1), place(*args)))
    counts = _counting(monkeypatch, ["computeJointJacobians", "crba"])
    refreshes, iterations, steps = fm.refreshes, 0, 40
    lengths = s.drive.values.copy()
    for _ in range(steps):
        lengths = lengths + 2e-6
        s = fm.step(s, DriveInput.positions(lengths), WRENCH, H)
        iterations += s.iterations
        assert fm.closure_error(s)[0] < 1e-12
        fm.section_loads(s)
    assert len(placements) > 2  # the re-placement path is exercised
    assert counts["computeJointJacobians"] == iterations + steps + len(placements)
    assert counts["crba"] == fm.refreshes - refreshes


def _opened(fm, state, seed=0, size=1e-2):
    """``state`` moved off its closures by a random configuration change (m, rad) and given a velocity and an
    acceleration, the multipliers kept: a state the section-load shortcuts must handle exactly as well."""
    rng = np.random.default_rng(seed)
    q = pin.integrate(fm.model, state.q, size * rng.standard_normal(fm.nv))
    return dataclasses.replace(state, q=q, v=0.1 * rng.standard_normal(fm.nv), acceleration=rng.standard_normal(fm.nv),
                               iterations=0, damping_work_j=0.0)


def test_closure_wrenches_equal_the_least_squares_over_the_leg_twists(machine):
    """The closure wrench on leg i's last body is the constraint force lambda_i in the closure frame c1, carried to
    the world: it equals the direct answer, the world wrench W whose generalised forces S_k . W on the leg's joints
    are -(B^T lambda) there (least squares over the leg's twists S_k, Pinocchio's joint Jacobians), to 1e-12 of
    the largest component (achieved 5e-16), on a state whose closures are 1e-2 m / rad open."""
    fm = FlexibleMachine(machine, OFF_CENTRE)
    s = _opened(fm, fm.rest_state(WRENCH))
    model, data = fm.model, fm.model.createData()
    pin.computeJointJacobians(model, data, s.q)
    for cm, cd in zip(fm.cms, fm.cds):
        cm.calc(model, data, cd)
    b = np.array(pin.getConstraintsJacobian(model, data, fm.cms, fm.cds))
    assert np.abs(np.concatenate([cd.extract().constraint_position_error for cd in fm.cds])).max() > 1e-3
    gen = -(b.T @ s.multipliers)
    direct = np.array([np.linalg.lstsq(np.asarray(data.J)[:, lv].T, gen[lv], rcond=None)[0] for lv in fm.leg_v])
    got = fm.closure_wrenches(s)
    np.testing.assert_allclose(got, direct, rtol=0, atol=1e-12 * np.abs(direct).max())


def test_section_loads_do_not_depend_on_what_the_model_evaluated_before(machine):
    """Pinocchio's rnea leaves the joint placements (oMi) as they were: section_loads computes them itself, so the
    loads of a state are the same (bit for bit) on a fresh machine and after the machine stepped and evaluated
    other states (a version reading the placements left by an earlier call was off by 0.08 N of 143 N)."""
    fresh, used = FlexibleMachine(machine, OFF_CENTRE), FlexibleMachine(machine, OFF_CENTRE)
    s = _opened(fresh, fresh.rest_state(WRENCH), size=1e-3)
    expected = fresh.section_loads(s).values
    other = used.rest_state()
    for _ in range(3):
        other = used.step(other, other.drive, -WRENCH, H)
    used.closure_error(other)
    used._mass(other.q)
    got = used.section_loads(s).values
    assert np.array_equal(got, expected)
    assert np.abs(expected).max() > 100.0


@pytest.mark.parametrize("drive", ["position", "force"])
def test_batched_leg_frame_loads_equal_the_per_state_loads(machine, drive):
    """section_wrenches_from and leg_frame_loads over a stack of section_state arrays (the insertion converts its
    whole run at once) equal section_loads state by state, exactly."""
    from pressfit.dynamics.machine.flexible import leg_frame_loads

    fm = FlexibleMachine(machine, OFF_CENTRE)
    s = fm.rest_state(WRENCH)
    tension = fm.section_loads(s).axial_n("actuator")
    states = []
    for n in range(5):
        d = s.drive if drive == "position" else DriveInput.forces(tension * (1 + 0.01 * n))
        s = fm.step(s, d, WRENCH, H)
        states.append(s)
    placements, subtrees = (np.array(a) for a in zip(*(fm.section_state(x) for x in states)))
    batched = leg_frame_loads(fm.section_wrenches_from(placements, subtrees), machine.cardan_axes)
    for k, x in enumerate(states):
        loads = fm.section_loads(x)
        assert np.array_equal(batched[0][k], loads.values) and np.array_equal(batched[1][k], loads.frames)


def test_the_flexible_run_keeps_blas_on_one_thread(monkeypatch):
    """OpenBLAS starts one thread per core; on the flexible step's small matrices (146 x 146) they only spin
    (the shipped scenario took 3.6 times the CPU time with them on the shared 2-core machine). The flexible run
    holds every BLAS library to one thread, and gives the caller's setting back afterwards."""
    import scipy.linalg  # noqa: F401 (loads scipy's OpenBLAS beside numpy's)
    from threadpoolctl import threadpool_info, threadpool_limits

    from pressfit.description.cases import load_case
    from pressfit.dynamics.insertion import plan_scenario
    from pressfit.dynamics.machine import flexible_scenario
    from pressfit.dynamics.machine.flexible_scenario import FlexibleScenario
    from pressfit.dynamics.scenario import run_plan
    from pressfit.shipped import cases_dir

    def blas_threads():
        return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]

    seen = []

    class Probe:  # the flexible model's scenario class as the step loop sees it, recording the BLAS threads
        one_blas_thread = FlexibleScenario.one_blas_thread

        def __init__(self, *args):
            seen.append(set(blas_threads()))

        def rows(self):
            return np.zeros((0, 1)), None

    case = load_case(cases_dir() / "paper" / "insertion.toml")
    plan = dataclasses.replace(plan_scenario(case), steps=0,
                               simulation=case.simulation.model_copy(update={"model": "flexible"}))
    monkeypatch.setattr(flexible_scenario, "FlexibleScenario", Probe)  # what the registry's "flexible" names
    with threadpool_limits(limits=2, user_api="blas"):
        assert blas_threads() and set(blas_threads()) == {2}
        run_plan(case, None, plan, None, True, False)
        assert seen == [{1}]
        assert set(blas_threads()) == {2}


def test_the_closures_read_through_views_equal_pinocchios_calls(machine):
    """The closure Jacobian B (one closure at a time) and error Phi (numpy views of the constraint datas) on a state
    1e-2 m / rad open, after the machine evaluated another configuration: equal to getConstraintsJacobian and the
    constraint datas' own errors on a fresh Data, bit for bit."""
    fm = FlexibleMachine(machine, OFF_CENTRE)
    rest = fm.rest_state(WRENCH)
    fm._jacobian(rest.q)
    s = _opened(fm, rest)
    b, phi = fm._jacobian(s.q)
    model, data, cds = fm.model, fm.model.createData(), [cm.createData() for cm in fm.cms]
    pin.computeJointJacobians(model, data, s.q)
    for cm, cd in zip(fm.cms, cds):
        cm.calc(model, data, cd)
    assert np.array_equal(b, np.array(pin.getConstraintsJacobian(model, data, fm.cms, cds)))
    expected = np.concatenate([cd.extract().constraint_position_error for cd in cds])
    assert np.array_equal(phi, expected) and np.abs(expected).max() > 1e-3


def test_the_section_state_read_through_views_equals_pinocchios_objects(machine):
    """section_state (the closure forces written and the placements and subtree wrenches read through numpy views
    of the Data) on a state 1e-3 m / rad open, after the machine stepped and re-placed its stems (the views must
    follow): the direct computation on a fresh Data with Pinocchio's objects (c1.act of each closure force as an
    external force, forwardKinematics, rnea, oMi and f), to 1e-13 of the largest value (the dual action matrix's
    rounding against SE3.act)."""
    fm = FlexibleMachine(machine, OFF_CENTRE)
    s = fm.rest_state(WRENCH)
    lengths = s.drive.values.copy()
    for _ in range(3):
        lengths = lengths + 2e-5  # 20 um a step: the stems re-placed every step
        s = fm.step(s, DriveInput.positions(lengths), WRENCH, H)
        fm.section_state(s)
    s = _opened(fm, s, size=1e-3)
    placements, wrenches = fm.section_state(s)
    model, data = fm.model, fm.model.createData()
    fext = pin.StdVec_Force()
    for _ in range(model.njoints):
        fext.append(pin.Force.Zero())
    lam = s.multipliers.reshape(fm.legs, 6)
    for i, (j, c1) in enumerate(zip(fm.plate_end, fm._c1)):
        fext[j] = c1.act(pin.Force(lam[i]))
    pin.forwardKinematics(model, data, s.q)
    pin.rnea(model, data, s.q, s.v, s.acceleration, fext)
    joints, subs = fm._sec_joints
    expected_p = np.array([data.oMi[j].homogeneous[:3] for j in joints])
    expected_w = np.array([data.f[j].vector for j in subs])
    np.testing.assert_allclose(placements, expected_p, rtol=0, atol=1e-13 * np.abs(expected_p).max())
    np.testing.assert_allclose(wrenches, expected_w, rtol=0, atol=1e-13 * np.abs(expected_w).max())
    assert np.abs(expected_w).max() > 100.0


def test_re_placed_stems_are_the_placements_and_pieces_of_a_fresh_model(machine):
    """The stems re-placed through the held views of the placements and the stem inertias written once their
    constants are known: the joint placements and body inertias of a fresh copy of the model placed by
    MachineModel.place_stem (no views) and weighed by set_stem_inertias, bit for bit, at other stem lengths."""
    from pressfit.dynamics.inertia import inertial_model, set_stem_inertias

    fm = FlexibleMachine(machine, OFF_CENTRE)
    stems = fm._placed + np.array([0.012, -0.007, 0.003, 0.021])
    fm._place(stems)
    fresh = inertial_model(fm.mm)
    fm.mm.place_stem(fresh, stems)
    set_stem_inertias(fm.mm, fresh, stems)
    moved = [j for ids in fm.mm.stem_joint_ids() for j in ids]
    z = fm.mm.stem_placements_z(stems).ravel()
    for j, zj in zip(moved, z):
        assert fm.model.jointPlacements[j].translation[2] == zj
    for j in range(fm.model.njoints):
        assert np.array_equal(fm.model.jointPlacements[j].homogeneous, fresh.jointPlacements[j].homogeneous)
        assert np.array_equal(fm.model.inertias[j].toDynamicParameters(), fresh.inertias[j].toDynamicParameters())


def test_the_damping_force_is_the_rayleigh_force_of_the_mass_matrix(machine):
    """The damping force alpha M rel + beta K rel of a step's end (M rel by one rnea with the gravity off): equal to
    alpha crba(q) rel + beta K rel to 1e-12 of its largest component, and the model's gravity is back after it."""
    fm = FlexibleMachine(machine, OFF_CENTRE, damping=Rayleigh(alpha_per_s=3.0, beta_s=2e-4))
    s = _opened(fm, fm.rest_state(WRENCH), size=1e-3)
    rel = np.random.default_rng(1).standard_normal(fm.nv)
    rest, k = fm._rest(s.drive)
    gravity = fm.model.gravity.vector.copy()
    got = fm._damping_force(s.q, rel, rest, k, s.drive)
    expected = 3.0 * fm._mass(s.q) @ rel
    expected[fm.sv] += 2e-4 * k * rel[fm.sv]
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    assert np.array_equal(fm.model.gravity.vector, gravity) and gravity[1] < -9.0


def test_the_energies_kept_from_the_section_state_are_the_energy_pass(machine):
    """section_state keeps the state's energies from its own passes (forward kinematics at q, rnea at q, v): on a
    moving state after steps that re-placed the stems, energy() then equals Pinocchio's computeMechanicalEnergy on a
    fresh Data at the state's q and v, bit for bit; and the energy of another state asked next (another step's, or
    the same velocity, drive and stems at another q) is that state's, not the kept one."""
    fm = FlexibleMachine(machine, OFF_CENTRE)
    s = fm.rest_state(WRENCH)
    lengths = s.drive.values.copy()
    states = []
    for _ in range(3):
        lengths = lengths + 2e-5
        s = fm.step(s, DriveInput.positions(lengths), WRENCH, H)
        states.append(s)
    assert np.abs(s.v).max() > 1e-3  # moving: a kinetic energy to get right
    elsewhere = dataclasses.replace(states[-1], q=states[0].q)  # the same velocity, drive and stems at another q
    for state in (states[-1], states[0], elsewhere):
        fm.section_state(states[-1])
        got = fm.energy(state)
        fm._place(state.stem_lengths_m)
        data = fm.model.createData()
        pin.computeMechanicalEnergy(fm.model, data, state.q, state.v)
        assert got.kinetic_j == data.kinetic_energy and got.potential_j == data.potential_energy
        assert got.kinetic_j > 1e-6
