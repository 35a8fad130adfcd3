"""The VJM Pinocchio model (pressfit.model): assembly, closed-form configuration, body frames, springs.

References are independent of the model code: the machine's geometry (B_i, d_i from the TOML) and the
closed-form inverse kinematics of the paper's equation 1 (pressfit.kinematics); closure errors come from
Pinocchio's own FrameAnchor constraint data. Tolerances: 1e-9 m / rad as the issue asks (round-off is
~1e-15 here, so a real error cannot hide under them).
"""

import numpy as np
import pinocchio as pin
import pytest

from pressfit import kinematics
from pressfit.errors import UnreachablePoseError
from pressfit.mechanics.model import CardanCompliance, LinearSpring, build_model

POSES = [(0.0, 0.72, 0.0), (0.2765, 0.72, -0.2765), (0.1, 0.6, -0.15), (-0.25, 0.5, 0.25), (0.25, 0.75, 0.0)]


@pytest.fixture(scope="module")
def mm(machine):
    return build_model(machine, [0.1, 0.6, -0.15])


@pytest.mark.parametrize("pose", POSES)
def test_configuration_closes_loops_and_matches_closed_form(machine, mm, pose):
    q = mm.configuration_at(pose)
    em, er = mm.closure_error(q)
    assert em < 1e-9 and er < 1e-9
    data = mm.model.createData()
    pin.forwardKinematics(mm.model, data, q)
    ik = kinematics.inverse_kinematics(machine, pose)
    h = np.array(pose)
    for i in range(4):
        ids = mm.leg_joint_ids[i]
        b, top = machine.base_points_m[i], h + machine.plate_offsets_m[i]  # geometry straight from the TOML
        e = (top - b) / np.linalg.norm(top - b)
        cyl = data.oMi[ids["cylinder"]]
        assert np.allclose(cyl.translation, b, atol=1e-12)
        assert np.allclose(cyl.rotation[:, 2], e, atol=1e-12)  # cylinder body z along the leg
        assert abs(cyl.rotation[:, 0] @ machine.cardan_axes[i]) == pytest.approx(
            np.linalg.norm(np.cross(e, np.cross(machine.cardan_axes[i], e))), abs=1e-12)  # x = +-a_i made normal
        assert np.allclose(data.oMi[ids["actuator"]].translation, top, atol=1e-12)  # stem body at plate cardan
        assert np.allclose(data.oMi[ids["plate_end"]].translation, top, atol=1e-12)
        assert q[mm.model.joints[ids["actuator"]].idx_q] == pytest.approx(ik.lengths_m[i], abs=1e-15)
    for s in mm.springs:  # rigid configuration: every spring unloaded
        if s.name != "actuator":
            assert q[s.idx_q] == 0.0


def test_assembly_from_a_perturbed_guess_recovers_the_closed_form(mm):
    pose = [0.2, 0.55, 0.1]
    q_ref = mm.configuration_at(pose)
    guess = q_ref.copy()
    rng = np.random.default_rng(1)
    for idx in mm._rigid_idx.values():
        guess[idx] += rng.uniform(-0.05, 0.05, idx.shape)
    q = mm.assemble(pose, guess)
    assert np.max(np.abs(q - q_ref)) < 1e-9
    em, er = mm.closure_error(q)
    assert em < 1e-9 and er < 1e-9


def test_random_reachable_poses_close(machine, mm):
    rng = np.random.default_rng(2)
    poses = np.column_stack([rng.uniform(-0.25, 0.25, 50), rng.uniform(0.5, 0.75, 50), rng.uniform(-0.25, 0.25, 50)])
    for h in poses:
        em, er = mm.closure_error(mm.configuration_at(h))
        assert em < 1e-12 and er < 1e-12


def test_section_points_sit_where_the_docstring_says(machine, mm):
    pose = np.array([0.1, 0.6, -0.15])
    data = mm.model.createData()
    pin.forwardKinematics(mm.model, data, mm.q0)
    pin.updateFramePlacements(mm.model, data)
    for i in range(4):
        b, top = machine.base_points_m[i], pose + machine.plate_offsets_m[i]
        e = (top - b) / np.linalg.norm(top - b)
        want = {"base": b, "actuator": b + machine.cylinder.length_m * e, "plate": top}
        for name, p in want.items():
            fid = mm.model.getFrameId(f"leg{i + 1}.section.{name}")
            assert np.allclose(data.oMf[fid].translation, p, atol=1e-12)


def test_segment_springs_add_up_to_the_beam_compliances(machine):
    # n springs of n E I / L in series = L / (E I): the lumped model carries a constant couple exactly
    for n in (1, 4, 7):
        mm = build_model(machine, [0.0, 0.7, 0.0], springs_per_segment=n)
        leg0 = [s for s in mm.springs if s.leg == 0]
        cyl_x = sum(1 / s.law.k for s in leg0 if s.name.startswith("cylinder") and s.name.endswith(".x"))
        stem_z = sum(1 / s.law.k for s in leg0 if s.name.startswith("stem") and s.name.endswith(".z"))
        lc = machine.cylinder.length_m
        ls = kinematics.inverse_kinematics(machine, [0.0, 0.7, 0.0]).lengths_m[0] - lc
        assert cyl_x == pytest.approx(
            lc / (machine.material.youngs_modulus_pa * machine.cylinder_section.second_moment_m4)
        )
        assert stem_z == pytest.approx(ls / (machine.material.shear_modulus_pa * machine.stem_section.polar_moment_m4))
        act = [s for s in leg0 if s.name == "actuator"][0]
        assert 1 / act.law.k == pytest.approx(float(machine.axial_compliance_m_per_n(ls + lc)))
        assert mm.model.nv == 6 + 4 * (5 + 6 * n)


def test_unreachable_pose_names_leg_and_limit(machine):
    with pytest.raises(UnreachablePoseError, match=r"leg 3: leg length l \[m\] = 1.0182"):
        build_model(machine, [0.0, 0.72, -0.36])


def test_cardan_compliance_hook_adds_virtual_joints(machine):
    law = LinearSpring(1e8)
    mm = build_model(machine, [0.05, 0.65, 0.02], springs_per_segment=2,
                     cardan_compliance={(0, "base"): CardanCompliance(translation=law, rotation=law)})
    assert mm.model.nv == 6 + 4 * (5 + 12) + 4
    names = {s.name for s in mm.springs if s.leg == 0}
    assert {"base_cardan.tx", "base_cardan.ty", "base_cardan.tz", "base_cardan.rc"} <= names
    em, er = mm.closure_error(mm.q0)
    assert em < 1e-12 and er < 1e-12
