"""The critical preload over many poses and load directions (mechanics/closing_preload.py) against independent
references: a brute-force bisection on the public one-pose clearance solve (load_deflection's closed joints at
every load step), the closed-joint linear model (the condensed statics with the two contact springs in series with
each leg: with every cardan closed the leg forces are linear in the load, so the preload must give every leg whose
load share opposes its preload share a |v_i| >= F |n_i|), and the lost motion 2 g / sin(alpha) at pose A."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from pressfit.description.machine import load_machine
from pressfit.kinematics import preload_basis, preload_vector
from pressfit.mechanics import condensed
from pressfit.mechanics.clearance import critical_preload, load_deflection
from pressfit.mechanics.clearance_law import Clearance
from pressfit.mechanics.closing_preload import RELATIVE_TOL, closing_preload
from pressfit.mechanics.preload import closing_direction

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from n_legs import ring_machine_file

PLAY = 20e-6
LOW_CORNER = np.array([-0.25, 0.48775004, -0.25])  # the shipped 4-UPU's box: its lowest height, a corner
STEPS = np.linspace(0.0, 700.0, 51)


def _series(machine):
    """The machine with each leg's two closed contact springs k_c in series with its actuator (closed-joint model)."""
    kc, ka = machine.joints.cardan_contact_stiffness_n_per_m, machine.actuator.axial_stiffness_n_per_m
    return machine.with_overrides({"actuator": {"axial_stiffness_n_per_m": 1.0 / (1.0 / ka + 2.0 / kc)}})


def _linear_critical(machine, pose, direction, v, load=700.0):
    """The closed-joint linear model's critical preload along the unit leg forces v (n,), N, and its smoothing bias:
    the critical leg must keep the contact-edge force k_c w / 2 of the smoothed law (clearance_law)."""
    n = condensed.solve_linear(_series(machine), pose, load * np.asarray(direction, float)).axial_forces_n
    need = np.where(n * v < 0, np.abs(n) / np.abs(v), 0.0)
    i = int(np.argmax(need))
    edge = 0.5 * machine.joints.cardan_contact_stiffness_n_per_m * Clearance.uniform(machine).smoothing_m
    return float(need[i]), edge / abs(v[i]), n


def _all_closed(machine, pose, a, play):
    ld = load_deflection(machine, pose, [0.0, 1.0, 0.0], STEPS, play, a, unload=False)
    return bool(ld.closed().all()), ld


def test_the_critical_preload_is_a_brute_force_bisection_and_the_closed_joint_model():
    """At the box's low corner under the press load: the batched answer equals a bisection written here on
    load_deflection (every cardan closed at every one of the 50 steps) to the bisection's bracket, and the
    closed-joint linear model's critical preload plus the smoothing bias k_c w / (2 |v_i|) to 0.1 N (achieved
    0.02 N, the bisection's bracket being 0.07 N)."""
    machine = load_machine()
    play = Clearance.uniform(machine).with_gap(PLAY)
    got = closing_preload(machine, LOW_CORNER, [[0.0, 1.0, 0.0]], 700.0, play).critical_preload_n[0]
    lo, hi = 0.0, 2000.0
    assert _all_closed(machine, LOW_CORNER, hi, play)[0]
    while hi - lo > 0.05:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _all_closed(machine, LOW_CORNER, mid, play)[0] else (mid, hi)
    assert got == pytest.approx(hi, abs=0.05 + RELATIVE_TOL * 700.0)
    linear, bias, _ = _linear_critical(machine, LOW_CORNER, [0.0, 1.0, 0.0], preload_vector(machine, LOW_CORNER))
    assert linear > 1000.0  # the box centre's 422 N is far from enough here
    assert got == pytest.approx(linear + bias, abs=0.1)


def test_a_cardan_that_opens_mid_path_is_seen():
    """With the box centre's 422 N at the low corner a cardan opens at about 245 N of the 700 N path, while the
    first two load steps show no play (the old zero-load intercept: 0): the reported critical preload is above it,
    and 0.2 N below the reported value a cardan opens on the way while at it every cardan stays closed."""
    machine = load_machine()
    play = Clearance.uniform(machine).with_gap(PLAY)
    closed, ld = _all_closed(machine, LOW_CORNER, 422.2, play)
    opening = float(np.nanmin(ld.opening_loads_n))
    assert not closed and 100.0 < opening < 600.0 and abs(ld.lost_motion_m) < 1e-9
    got = closing_preload(machine, LOW_CORNER, [[0.0, 1.0, 0.0]], 700.0, play).critical_preload_n[0]
    assert got > 1000.0
    assert _all_closed(machine, LOW_CORNER, got, play)[0] and not _all_closed(machine, LOW_CORNER, got - 0.2, play)[0]


def test_drive_forces_with_the_preload_are_a_v_plus_the_load_share():
    """The drive forces reported with the pose's critical preload a: max over the path of |a v_i + N_i(F)|, with the
    load share N_i from the closed-joint linear statics (linear in F: the extremes are the path's ends), over the
    press load and one tilted direction; to 1e-6 of the force (achieved 4.4e-7)."""
    machine = load_machine()
    play = Clearance.uniform(machine).with_gap(PLAY)
    dirs = np.array([[0.0, 1.0, 0.0], [math.sin(0.0873), math.cos(0.0873), 0.0]])
    r = closing_preload(machine, LOW_CORNER, dirs, 700.0, play)
    a, v = r.critical_preload_n[0], preload_vector(machine, LOW_CORNER)
    expected = np.max([np.maximum(np.abs(a * v), np.abs(a * v + _linear_critical(machine, LOW_CORNER, d, v)[2]))
                       for d in dirs], axis=0)
    np.testing.assert_allclose(r.drive_forces_n[0], expected, rtol=1e-6)
    assert np.max(r.drive_forces_n[0]) < a  # the preload's share is a |v_i| <= a: adding the whole a over-bounds


def test_the_lost_motion_at_pose_a_is_two_gaps_over_sin_alpha():
    """Pose A (0, 0.72, 0) under the vertical press load, no preload: every leg's two cardans take up 2 g before
    the leg engages, the plate moving 2 g / sin(alpha) (tan(alpha) = 2: docs); with the critical preload nothing is
    left (below 1 nm: the smoothing)."""
    machine = load_machine()
    play = Clearance.uniform(machine).with_gap(PLAY)
    r = closing_preload(machine, [0.0, 0.72, 0.0], [[0.0, 1.0, 0.0]], 700.0, play)
    assert r.lost_motion_unpreloaded_m[0] == pytest.approx(2 * PLAY / (2 / math.sqrt(5)), rel=2e-7)  # achieved 6e-8
    assert abs(r.lost_motion_m[0]) < 1e-9


@pytest.mark.parametrize("legs", [5, 6, 12])
def test_machines_of_more_legs_get_a_preload_that_loads_every_leg(tmp_path, legs):
    """n = 5, 6, 12 legs on a ring: the closing direction is a unit self-stress (it loads the plate with nothing:
    sum v_i u_i = 0) in the preload space with a share on every leg, and the critical preload at an off-centre pose
    is the closed-joint linear model's plus the smoothing bias (to 0.15 N: achieved 0.01-0.08 N)."""
    machine = load_machine(ring_machine_file(tmp_path / f"ring{legs}.toml", legs))
    pose = np.array([0.15, 0.55, -0.1])
    v = closing_direction(machine, pose)
    u = machine.base_points_m - (pose + machine.plate_offsets_m)
    u /= np.linalg.norm(u, axis=1)[:, None]
    basis = preload_basis(machine, pose)
    assert np.linalg.norm(v) == pytest.approx(1.0) and np.abs(v @ u).max() < 1e-12
    assert np.abs(v - basis @ np.linalg.lstsq(basis, v, rcond=None)[0]).max() < 1e-12
    assert np.abs(v).min() > 0.1 / math.sqrt(legs)
    play = Clearance.uniform(machine).with_gap(PLAY)
    got = closing_preload(machine, pose, [[0.0, 1.0, 0.0]], 700.0, play).critical_preload_n[0]
    linear, bias, _ = _linear_critical(machine, pose, [0.0, 1.0, 0.0], v)
    assert got == pytest.approx(linear + bias, abs=0.15)


def test_the_studies_critical_preload_is_none_where_it_cannot_exist(tmp_path):
    """The studies' one-number preload leaves legs 5..n of a 5-leg machine without force, and a 3-leg machine has
    none: no amplitude closes those cardans, so the answer is NaN at once (it was a bisection doubling the preload
    until the clearance Newton failed: "did not converge")."""
    five = load_machine(ring_machine_file(tmp_path / "ring5.toml", 5))
    three = load_machine(Path(__file__).resolve().parents[2] / "models/tsai_3upu.toml")
    for machine in (five, three):
        play = Clearance.uniform(machine).with_gap(PLAY)
        got = critical_preload(machine, [0.0, 0.55, 0.0], [0.0, 1.0, 0.0], 700.0, play)
        assert math.isnan(got.preload) and got.evaluations == 1


def test_a_cardan_open_on_the_way_and_closed_at_the_end_is_open():
    """2 um of play at the low corner and half the critical preload: the critical leg's force a v_i + N_i(f) crosses
    zero at about 350 N, its cardans open there (the plate must move 2 g along the leg before they close on their
    other side) and close again in compression before 420 N: at 700 N every cardan is closed (load_deflection, the
    one-pose solve, says both). A decision from the last step alone would call the path closed; the batched sweep
    must not."""
    from pressfit.mechanics.closing_preload import _model, _sweep

    machine = load_machine()
    play = Clearance.uniform(machine).with_gap(2e-6)
    result = closing_preload(machine, LOW_CORNER, [[0.0, 1.0, 0.0]], 700.0, play)
    half = 0.5 * float(result.critical_preload_n[0])
    closed_each_step, ld = _all_closed(machine, LOW_CORNER, half, play)
    open_steps = np.flatnonzero(~ld.closed().all(axis=(1, 2)))
    assert not closed_each_step and ld.closed()[-1].all() and open_steps.min() > 0 and open_steps.max() < 50
    chain = _model(machine, LOW_CORNER[None], play, True)
    ok, _, _, residual = _sweep(chain, 1.0 / chain.k, half * result.preload_direction, STEPS,
                                np.array([[0.0, 1.0, 0.0]]))
    assert residual < 1e-8 and not ok[0]
