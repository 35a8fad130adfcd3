"""The second engine (pressfit.dynamics.mjcf): the rigid-leg machine exported to MJCF and run in MuJoCo against
Pinocchio's constraint dynamics (pressfit.dynamics.multibody)."""

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner
from readme import assert_printed, readme_fragment

from pressfit.cli import main
from pressfit.dynamics.mjcf import machine_mjcf, mujoco_state, passive_motion
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.errors import PressfitError

POSE = np.array([0.05, 0.65, -0.05])
THROW_M_PER_S = np.array([0.2, 2.0, -0.2])  # the plate rises ~0.19 m and falls back to y ~ 0.34 m in 0.5 s


@pytest.fixture(scope="module")
def rigid(machine):
    return rigid_leg_model(machine, POSE)


@pytest.fixture(scope="module")
def exported(rigid):
    model = mujoco.MjModel.from_xml_string(machine_mjcf(rigid))
    return model, mujoco.MjData(model)


@pytest.fixture(scope="module")
def runs(machine):
    return {h: passive_motion(machine, POSE, THROW_M_PER_S, duration_s=0.5, timestep_s=h) for h in (1e-4, 5e-5)}


def test_exported_bodies_carry_the_pinocchio_inertias(rigid, exported):
    """Every MuJoCo body has its Pinocchio body's mass, centre of mass and inertia about it (MuJoCo stores the
    principal inertia and its frame; rebuilt here), to round-off of the 17-digit MJCF numbers."""
    model, _ = exported
    assert model.nbody == rigid.model.njoints  # the world plus one body per joint
    for joint in range(1, rigid.model.njoints):
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, rigid.model.names[joint])
        inertia = rigid.model.inertias[joint]
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, model.body_iquat[body])
        rot = rot.reshape(3, 3)
        assert model.body_mass[body] == pytest.approx(inertia.mass, rel=1e-15)
        np.testing.assert_allclose(model.body_ipos[body], inertia.lever, atol=1e-15)
        np.testing.assert_allclose(rot @ np.diag(model.body_inertia[body]) @ rot.T, inertia.inertia, atol=1e-15)
    assert mujoco.mj_getTotalmass(model) == pytest.approx(pin.computeTotalMass(rigid.model), rel=1e-14)
    np.testing.assert_allclose(model.opt.gravity, rigid.model.gravity.linear, rtol=0)


def test_mass_matrices_agree_at_the_reference_configuration(rigid, exported):
    """MuJoCo's joint-space mass matrix (its CRB) equals Pinocchio's CRBA at the closed reference configuration
    (plate unrotated, so both free-joint velocity conventions coincide): the kinematic tree, joint axes, body
    placements and inertias are exported consistently. Round-off 1e-15 of entries up to ~1 (tolerance 1e-13)."""
    mass, reference = _mass_matrices(rigid, exported)
    np.testing.assert_allclose(mass, reference, atol=1e-13)


def _mass_matrices(rigid, exported):
    """MuJoCo's and Pinocchio's joint-space mass matrices at the keyframe (the closed reference configuration)."""
    model, data = exported
    mujoco.mj_resetDataKeyframe(model, data, 0)
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, mass)
    reference = pin.crba(rigid.model, rigid.model.createData(), rigid.reference_q)
    return mass, np.triu(reference) + np.triu(reference, 1).T


def test_state_map_keeps_the_plate_pose_and_twist(rigid, exported):
    """With the plate rotated (a state off the closures: only the plate's own kinematics matter here) the mapped
    MuJoCo state puts the plate body at Pinocchio's placement and gives it Pinocchio's body-frame twist
    (mj_objectVelocity, local frame): the two free-joint conventions (quaternion order, world vs plate-frame
    linear velocity) are mapped correctly. Round-off tolerance."""
    model, data = exported
    rng = np.random.default_rng(7)
    q, v = rigid.reference_q.copy(), rng.normal(size=rigid.model.nv)
    q[3:7] = pin.Quaternion(pin.rpy.rpyToMatrix(0.3, -0.2, 0.5)).coeffs()
    data.qpos[:], data.qvel[:] = mujoco_state(rigid, q, v)
    mujoco.mj_forward(model, data)
    plate = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "plate")
    twist = np.zeros(6)  # MuJoCo's order: angular, linear
    mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_XBODY, plate, twist, 1)  # body frame
    placement = pin.XYZQUATToSE3(q[:7])
    np.testing.assert_allclose(data.xpos[plate], placement.translation, atol=1e-15)
    np.testing.assert_allclose(data.xmat[plate].reshape(3, 3), placement.rotation, atol=1e-15)
    np.testing.assert_allclose(np.concatenate([twist[3:], twist[:3]]), v[:6], atol=1e-14)


def test_initial_state_satisfies_the_closures_in_mujoco(rigid, exported):
    """At the exported keyframe (equation 1's closed configuration) the 24 weld rows' violations (efc_pos) are at
    round-off, and the admissible velocity of the throw (J v = 0 in Pinocchio) gives zero weld velocities
    (efc_vel) in MuJoCo's own Jacobian, after mapping the free joint's velocity convention."""
    model, data = exported
    mujoco.mj_resetDataKeyframe(model, data, 0)
    q, v = rigid.reference_q, rigid.admissible_velocity(rigid.reference_q, THROW_M_PER_S)
    data.qpos[:], data.qvel[:] = mujoco_state(rigid, q, v)
    mujoco.mj_forward(model, data)
    rows = data.efc_type[:data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
    assert rows.sum() == 24
    assert np.abs(data.efc_pos[:data.nefc][rows]).max() < 1e-14
    assert np.abs(data.efc_vel[:data.nefc][rows]).max() < 1e-12  # of velocities ~2 m/s


def test_passive_plate_trajectories_agree(runs):
    """Gravity on, no actuator force, the plate thrown upward (admissible velocity), 0.5 s in both engines.

    Both integrate with semi-implicit Euler; their difference comes from the closure treatment and is first
    order in the step h: Pinocchio's Baumgarte-corrected drift (largest 1.3e-5 m at h = 1e-4 s) falls as h,
    MuJoCo's soft-weld violation (measured 6.6e-7 m) as h^2. Measured deviation of the plate positions:
    3.0e-6 m at h = 1e-4 s over a 0.75 m path (tolerance 8e-6 m), halving with h (ratio 1.97; 2 within 10%,
    the signature of a first-order integrator error, not of a modelling difference, which would not scale).
    Richardson-extrapolated to h -> 0 (2 D(h/2) - D(h)) the engines agree to 5.3e-8 m (tolerance 1.7e-7 m)."""
    coarse, fine = runs[1e-4], runs[5e-5]
    assert coarse.time_s[-1] == pytest.approx(0.5)
    assert np.ptp(coarse.pinocchio_plate_m[:, 1]) > 0.4  # the run did move the plate
    assert coarse.deviation_m.max() < 8e-6
    assert coarse.deviation_m.max() / fine.deviation_m.max() == pytest.approx(2.0, rel=0.1)
    d_coarse = coarse.pinocchio_plate_m - coarse.mujoco_plate_m
    d_fine = (fine.pinocchio_plate_m - fine.mujoco_plate_m)[::2]
    assert np.linalg.norm(2 * d_fine - d_coarse, axis=1).max() < 1.7e-7


def test_closures_and_plate_orientation_hold_in_both_engines(runs):
    """The 4-UPU plate only translates: its rotation stays below 5e-6 rad in both engines (MuJoCo's soft welds
    give 1.8e-6 rad at h = 1e-4 s). MuJoCo's weld violation follows the h^2 law of its stiffest safe solref
    (time constant 2 h): 6.6e-7 m at h = 1e-4 s (tolerance 1.7e-6 m), 4x less at h / 2 (ratio 3.98, 4 within
    10%); Pinocchio's drift stays below 3e-5 m (1.3e-5 m) and halves with h (first-order Baumgarte drift)."""
    coarse, fine = runs[1e-4], runs[5e-5]
    for run in (coarse, fine):
        assert max(run.pinocchio_rotation_rad.max(), run.mujoco_rotation_rad.max()) < 5e-6
    assert coarse.mujoco_closure_error_m < 1.7e-6
    assert coarse.mujoco_closure_error_m / fine.mujoco_closure_error_m == pytest.approx(4.0, rel=0.1)
    assert coarse.pinocchio_closure_error_m < 3e-5
    assert coarse.pinocchio_closure_error_m / fine.pinocchio_closure_error_m == pytest.approx(2.0, rel=0.1)


@pytest.mark.parametrize(("duration", "step"), [(0.5, 0.0), (0.5, -1e-4), (1e-5, 1e-4), (float("nan"), 1e-4)])
def test_bad_run_parameters(machine, duration, step):
    with pytest.raises(PressfitError, match="timestep_s"):
        passive_motion(machine, POSE, duration_s=duration, timestep_s=step)


def test_bad_export_timestep(rigid):
    with pytest.raises(PressfitError, match="timestep_s"):
        machine_mjcf(rigid, timestep_s=0.0)


def test_export_mjcf_cli(rigid, tmp_path):
    """``pressfit export-mjcf`` prints the library's MJCF, writes it atomically with --out (MuJoCo loads the
    file) and refuses to overwrite without --overwrite (exit 2, one line)."""
    runner, pose = CliRunner(), [str(c) for c in POSE]
    printed = runner.invoke(main, ["export-mjcf", *pose])
    assert printed.exit_code == 0, printed.output
    assert printed.output.strip() == machine_mjcf(rigid).strip()
    out = tmp_path / "machine.xml"
    written = runner.invoke(main, ["export-mjcf", *pose, "--timestep", "5e-5", "--out", str(out)])
    assert written.exit_code == 0, written.output
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.opt.timestep == 5e-5 and model.neq == 4
    again = runner.invoke(main, ["export-mjcf", *pose, "--out", str(out)])
    assert again.exit_code == 2 and "--overwrite" in again.output


def test_readme_numbers_of_the_second_engine(rigid, exported, runs):
    """Every number of the README's "Second engine (MuJoCo)" paragraph (tests/readme.py): the pinned MuJoCo, the
    weld parameters as exported, and the measured agreement of the two engines rounded to the printed digits.
    What makes the agreement meaningful (first order in h, h^2 for the welds) is asserted above."""
    readme_fragment("(`pressfit export-mjcf`; MuJoCo 4.0.0)")
    assert mujoco.__version__ == "4.0.0"
    readme_fragment("(the joint-space mass matrices agree to round-off, within 2e-15)")
    mass, reference = _mass_matrices(rigid, exported)
    assert np.abs(mass - reference).max() < 2e-15
    model = exported[0]
    readme_fragment("impedance 0.9999, time constant twice the time step, critically damped, which leaves a closure "
                    "violation falling as h^2 (6.6e-7 m at h = 0.1 ms)")
    np.testing.assert_array_equal(model.eq_solimp[:, :2], 0.9999)
    np.testing.assert_allclose(model.eq_solref, [[2 * model.opt.timestep, 1.0]] * 4, rtol=1e-15)
    coarse, fine = runs[1e-4], runs[5e-5]
    assert_printed(coarse.mujoco_closure_error_m, "6.6e-7")
    readme_fragment("For the plate thrown up at (0.2, 2.0, -0.2) m/s from (0.05, 0.65, -0.05) m (0.75 m of path "
                    "in 0.5 s) the plate trajectories agree to 3.0 um at h = 0.1 ms and 1.51 um at 0.05 ms")
    assert THROW_M_PER_S.tolist() == [0.2, 2.0, -0.2] and POSE.tolist() == [0.05, 0.65, -0.05]
    assert coarse.time_s[-1] == pytest.approx(0.5, abs=1e-12)
    assert_printed(np.linalg.norm(np.diff(coarse.pinocchio_plate_m, axis=0), axis=1).sum(), "0.75")
    assert_printed(coarse.deviation_m.max() * 1e6, "3.0")
    assert_printed(fine.deviation_m.max() * 1e6, "1.51")
    readme_fragment("(Pinocchio's Baumgarte-corrected drift, 1.3e-5 m at 0.1 ms), and extrapolated to h -> 0 the "
                    "two engines agree to 0.05 um")
    assert_printed(coarse.pinocchio_closure_error_m, "1.3e-5")
    d_coarse = coarse.pinocchio_plate_m - coarse.mujoco_plate_m
    d_fine = (fine.pinocchio_plate_m - fine.mujoco_plate_m)[::2]
    assert_printed(np.linalg.norm(2 * d_fine - d_coarse, axis=1).max() * 1e6, "0.05")
