"""The compiled per-step kernels of the insertion loop (pressfit.dynamics.kernels) against independent
computations: numpy's SVD for the force distribution, Pinocchio's joint placements for the axial forces, the
general (any deflection function) contact bisection, and a numpy transcription of Figure 12's controller as
the module docstring of pressfit.dynamics.control states it."""

import math

import numpy as np
import pinocchio as pin
import pytest

from pressfit import kinematics
from pressfit.description.cases import Contact, Controller
from pressfit.description.machine import load_machine
from pressfit.dynamics import kernels
from pressfit.dynamics.actuators import distribution
from pressfit.dynamics.contact import contact_parameters, solve_contact
from pressfit.dynamics.control import (
    DEFLECTION_UPDATE_M,
    GRAVITY_UPDATE_M,
    ForceLimitedController,
    gravity_feedforward_n,
    static_deflection_columns,
)
from pressfit.dynamics.multibody import rigid_leg_model
from pressfit.errors import SingularPoseError

RNG = np.random.default_rng(19)
POSES = RNG.uniform([-0.2, 0.5, -0.2], [0.2, 0.72, 0.2], (40, 3))


@pytest.fixture(scope="module")
def machine():
    return load_machine()


@pytest.fixture(scope="module")
def rigid(machine):
    return rigid_leg_model(machine, np.array([0.05, 0.65, -0.05]))


def test_distribution_is_the_svd_pseudo_inverse_and_null_vector(machine):
    """A^+ and v_p in closed form from the 3 x 3 normal matrix equal numpy's pinv and SVD null vector (sign: v_1
    < 0) to 1e-13 (achieved: a few 1e-16 on entries of order 1), and A's smallest singular value to 3e-11 (the
    trigonometric eigenvalue loses digits where two eigenvalues of A A^T nearly coincide: at most 8.5e-12 over
    these poses and 2000 others, median 3e-15; it only decides the 1e-6 singularity test)."""
    poses = POSES[kinematics.is_reachable(machine, POSES)]
    assert len(poses) >= 20
    for pose in poses:
        units = kinematics.inverse_kinematics(machine, pose).unit_vectors
        pinv, basis = distribution(units)
        null = basis[:, 0]  # v_p, the 4-UPU's one preload vector
        a = units.T
        _, s, vt = np.linalg.svd(a)
        reference = vt[3] if vt[3, 0] < 0 else -vt[3]
        assert np.abs(pinv - np.linalg.pinv(a)).max() < 1e-13
        assert np.abs(null - reference).max() < 1e-13
        assert np.abs(a @ null).max() < 1e-14 and null[0] < 0
        assert kernels.distribution(units, np.empty((4, 3)), np.empty((4, 1))) == pytest.approx(s[-1], abs=3e-11)


@pytest.mark.parametrize(("sigma", "singular"), [(1.02e-6, False), (0.98e-6, True)])
def test_distribution_refuses_a_singular_a_just_below_the_limit(sigma, singular):
    """A built with singular values (1, 0.7, sigma): refused (SingularPoseError) just below 1e-6, accepted just
    above (the closed-form lambda_min is accurate to ~1e-16 absolute: 1e-4 relative at sigma = 1e-6). Accepted,
    A^+ from the normal matrix is as accurate as cond(A)^2 eps allows (1e12 x 2.2e-16 here; over the reachable
    workspace cond(A) <= 3.6, so 3e-15: the first test)."""
    u, _ = np.linalg.qr(RNG.normal(size=(3, 3)))
    v, _ = np.linalg.qr(RNG.normal(size=(4, 4)))
    a = u @ np.diag([1.0, 0.7, sigma]) @ v[:3]
    if singular:
        with pytest.raises(SingularPoseError, match="smallest singular value 9.8") as exc:
            distribution(a.T)
        assert exc.value.smallest_singular_value == pytest.approx(sigma, rel=1e-4)
    else:
        pinv, null = distribution(a.T)
        null = null[:, 0]
        bound = 10 * (1.0 / sigma) ** 2 * np.finfo(float).eps
        assert np.abs(a @ pinv - np.eye(3)).max() < bound
        assert np.abs(a @ null).max() < 1e-11  # achieved 2.7e-12: the cofactors cancel to ~ sigma_1 sigma_2 sigma


def test_axial_forces_are_the_closure_forces_along_the_leg_axes(rigid):
    """The closed form N_i = f . (Ry(c) Rx(d))^T e_z from the plate cardan angles equals the closure force
    rotated to the world by Pinocchio's placement of the leg's last body, along the leg axis (its placement
    minus the base point), at moving, off-closure states: to 1e-14 of the largest force (achieved 2.3e-15:
    1.25e-12 N on 546 N; the forces are hundreds of N since the stems are rods of fixed mass)."""
    machine = rigid.machine
    for pose in POSES[kinematics.is_reachable(machine, POSES)][:10]:
        q = pin.integrate(rigid.model, rigid.configuration_at(pose), RNG.normal(scale=1e-3, size=rigid.model.nv))
        v = RNG.normal(scale=0.2, size=rigid.model.nv)
        tau = RNG.normal(scale=50.0, size=rigid.model.nv)
        rigid.accelerations(q, v, tau)
        lam = np.asarray(rigid.data.lambda_c).reshape(4, 2, 3)[:, 0]
        expected = []
        for i, j in enumerate(rigid.end_joints):
            placement = rigid.data.oMi[j]
            axis = placement.translation - machine.base_points_m[i]
            expected.append(placement.rotation @ lam[i] @ axis / np.linalg.norm(axis))
        assert np.abs(np.abs(expected)).max() > 1.0
        assert np.abs(rigid.axial_forces_n(q) - expected).max() <= 1e-14 * np.abs(expected).max()


@pytest.mark.parametrize("law", ["elastic", "linear", "saturating"])
def test_compiled_contact_solve_is_the_general_bisection(law):
    """The loop's compiled contact (linear compliance column, or a load-deflection table, each plus a sag) gives
    the force, interference and deflection of the general bisection with the same deflection as a Python
    function, to 1e-12 relative (the same arithmetic: achieved round-off), including a rigid tip above the board
    that the sag presses below it (the bracket's upper end is the law at the depth at zero force)."""
    fit = {} if law == "elastic" else {"law": "press_fit", "fit": law, "fit_stiffness_n_per_m": 3e4,
                                       "fit_force_n": 20.0, "fit_depth_m": 1e-3}
    contact = Contact(board_height_m=0.6, pin_position_m=[0.0, 0.0], stiffness_n_per_m=5e4,
                      damping_n_s_per_m=40.0, **fit)
    params = contact_parameters(contact)
    loads = np.linspace(0.0, 500.0, 41)
    disp = np.column_stack([1e-7 * loads, 3e-5 * np.sqrt(loads) + 1e-6 * loads, -2e-7 * loads])
    above = 0
    for _ in range(40):
        tip = np.array([0.0, 0.6 - RNG.uniform(-3e-4, 1e-3), 0.0])
        previous, column = RNG.uniform(-1e-3, 2e-3), np.array([1e-7, RNG.uniform(0.0, 4e-5), -3e-7])
        sag = np.array([2e-6, -RNG.uniform(0.0, 4e-4), -1e-6])
        tabulated = lambda f, s=sag: s + np.array([np.interp(f, loads, disp[:, k]) for k in range(3)])
        linear = lambda f, c=column, s=sag: c * f + s
        for table, function in (((np.zeros(0), np.zeros((0, 3))), linear), ((loads, disp), tabulated)):
            reference = solve_contact(contact, tip, function, previous, 1e-3)
            u = np.zeros(3)
            force, depth = kernels.solve_contact(params, 0.6 - tip[1], previous, 1e-3, column, sag, *table, u)
            above += tip[1] > 0.6 and force > 0.0
            assert force == pytest.approx(reference.force_n, rel=1e-12, abs=1e-12)
            assert depth == pytest.approx(reference.depth_m, rel=1e-12, abs=1e-15)
            assert np.abs(u - reference.deflection_m).max() <= 1e-12 * max(1e-6, np.abs(u).max())
    assert above > 2  # the sag pressed a tool whose rigid tip is above the board into it


def _figure_12(gains, limit, limiter, state, estimate, units, rates, target, target_velocity, contact_force, dt,
               gravity, deflection):
    """A numpy transcription of the module docstring of pressfit.dynamics.control (W and the next state) with the
    force limit ``limit`` (N) and the error against the estimate plus ``deflection`` (3, 2) @ (F, 1)."""
    integral, lift = state
    pinv = np.linalg.pinv(units.T)
    velocity = pinv.T @ rates
    error = target + [0.0, lift, 0.0] - (estimate + deflection @ [contact_force, 1.0])
    pid = gains.kp_n_per_m * error + gains.kd_n_s_per_m * target_velocity + gains.ki_n_per_m_s * integral
    clamped = limiter and contact_force > 0.0 and pid[1] < -limit
    if clamped:
        pid[1], error[1] = -limit, 0.0
    pid = pid - gains.kd_n_s_per_m * velocity
    if limiter and (contact_force > limit or lift > 0.0):
        lift = max(0.0, lift + dt * gains.backoff_m_per_s_n * (contact_force - limit))
    return pid + gravity, (integral + dt * error, lift), clamped


@pytest.mark.parametrize(("limiter", "compensation"), [(True, False), (False, False), (True, True)])
def test_compiled_controller_is_figure_12(machine, rigid, limiter, compensation):
    """400 random steps of the compiled controller (estimate, distribution, PID, clamp, anti-windup, lift,
    gravity feed-forward, tensions -A^+ W + a4 v_p; with ``deflection_compensation`` the error against the
    estimate plus the predicted static deflection; the force limit a run sets per segment, changed every 40
    steps) against the numpy transcription: W, the integral, the lift, the clamp and the tensions to 1e-9
    (relative to forces of hundreds of N; achieved ~1e-13)."""
    gains = Controller(deflection_compensation=compensation)
    pose0 = np.array([0.1, 0.62, -0.05])
    ctrl = ForceLimitedController(machine=machine, rigid=rigid, gains=gains, limiter=limiter, estimate_m=pose0.copy(),
                                  preload_n=np.array([40.0]))
    state, clamps, lifted = (np.zeros(3), 0.0), 0, 0
    for k in range(400):
        pose = pose0 + RNG.normal(scale=2e-4, size=3) + [0.0, -1e-5 * k, 1e-5 * k]  # 5.6 mm: 5 feed-forward updates
        lengths = kinematics.inverse_kinematics(machine, pose).lengths_m
        rates = RNG.normal(scale=0.05, size=4)
        target = pose + RNG.normal(scale=1e-3, size=3) - [0.0, 3e-3 * (k > 50), 0.0]  # pressing: clamps
        target_velocity = RNG.normal(scale=0.05, size=3)
        contact_force = max(0.0, RNG.normal(150.0, 60.0)) if k > 50 else 0.0
        ctrl.force_limit_n = gains.force_limit_n * (1.0 + 0.5 * ((k // 40) % 3 - 1))  # a segment's limit
        force = ctrl.command(lengths, rates, (target, target_velocity), contact_force, 1e-3)
        assert np.abs(ctrl.estimate_m - pose).max() < 1e-12
        assert np.abs(ctrl.gravity.pose_m - ctrl.estimate_m).max() <= GRAVITY_UPDATE_M
        gravity = gravity_feedforward_n(rigid, ctrl.gravity.pose_m)
        deflection = np.zeros((3, 2))
        if compensation:
            assert np.abs(ctrl.deflection.pose_m - ctrl.estimate_m).max() <= DEFLECTION_UPDATE_M
            cache = ctrl.deflection  # the rows the kernel was given, extrapolated to the estimate here in numpy
            deflection = (cache.rows + cache.gradient @ (ctrl.estimate_m - cache.pose_m)).T  # (3, 2)
            exact = static_deflection_columns(machine, rigid, ctrl.estimate_m)  # G at the estimate
            # extrapolated over <= DEFLECTION_UPDATE_M (1.5e-4 of C) with G from the controller's gravity cache
            # (within GRAVITY_UPDATE_M: 0.06% of each column)
            assert np.all(np.abs(deflection - exact).max(axis=0) <= 1e-3 * np.abs(exact).max(axis=0))
            assert np.abs(deflection[:, 1]).max() > 1e-5  # the sag counts (tens of um)
        expected, state, clamped = _figure_12(gains, ctrl.force_limit_n, limiter, state, ctrl.estimate_m, ctrl.units,
                                              rates, target, target_velocity, contact_force, 1e-3, gravity,
                                              deflection)
        assert np.abs(force - expected).max() < 1e-9
        assert np.abs(ctrl.integral_m_s - state[0]).max() < 1e-12 and ctrl.lift_m == pytest.approx(state[1], abs=1e-15)
        assert ctrl.clamped == clamped
        pinv, null = distribution(ctrl.units)
        assert np.abs(ctrl.tension_n - (-pinv @ expected + 40.0 * null[:, 0])).max() < 1e-9
        clamps, lifted = clamps + clamped, lifted + (state[1] > 0.0)
    assert (clamps > 10 and lifted > 100) if limiter else (clamps == 0 and lifted == 0)


def test_first_order_drive_step_is_the_closed_form():
    """The compiled drive step: s + (N - s) exp(-dt / tau), s the command clipped to +-limit."""
    force, command, out = np.array([0.0, 10.0, -5.0, 300.0]), np.array([500.0, -20.0, -900.0, 100.0]), np.empty(4)
    kernels.first_order(force, command, 300.0, math.exp(-0.25), out)
    target = np.array([300.0, -20.0, -300.0, 100.0])
    assert np.array_equal(out, target + (force - target) * math.exp(-0.25))


def test_nearest_node_is_numpys_argmin_of_the_infinity_norm_within_the_tolerance():
    """``nearest``: among nodes all within the hint's window, the row nearest to the pose in the infinity norm
    (numpy's argmin), -1 when even that one is beyond the tolerance; a node at 0.999 of the tolerance is taken, one at
    1.001 is not. Along a path's nodes (1 mm apart on a line) the nearest from any hint: in the window, just past
    its edge (followed from the window's best, which is within the tolerance too) and far beyond it (the whole
    list)."""
    nodes = RNG.uniform(-0.1, 0.1, (2 * kernels.NEAREST_WINDOW, 3))
    for pose in RNG.uniform(-0.12, 0.12, (50, 3)):
        distances = np.abs(nodes - pose).max(axis=1)
        best = int(np.argmin(distances))
        hint = kernels.NEAREST_WINDOW
        assert kernels.nearest(nodes, pose, 1.0, hint) == best
        assert kernels.nearest(nodes, pose, 0.999 * distances[best], hint) == -1
        assert kernels.nearest(nodes, pose, 1.001 * distances[best], hint) == best
    line = np.linspace(0.0, 1.0, 1001)[:, None] * np.array([1.0, 0.0, 0.0])
    edge = 480 + kernels.NEAREST_WINDOW
    for x, expected in ((0.5003, 500), ((edge + 1.2) / 1000, edge + 1), (0.9003, 900), (0.0004, 0)):
        assert kernels.nearest(line, np.array([x, 0.0, 0.0]), 2e-3, 480) == expected, x
    assert kernels.nearest(line, np.array([0.5, 0.0025, 0.0]), 2e-3, 480) == -1


def test_extrapolated_rows_are_the_first_order_taylor_series():
    """``extrapolated``: rows + gradient (pose - at), numpy's matmul, to 1e-15 relative."""
    rows, gradient = RNG.normal(size=(2, 3)), RNG.normal(size=(2, 3, 3))
    at, pose, out = RNG.normal(size=3), RNG.normal(size=3), np.empty((2, 3))
    kernels.extrapolated(pose, at, rows, gradient, out)
    assert np.abs(out - (rows + gradient @ (pose - at))).max() < 1e-15 * np.abs(out).max() * 10


def _configuration(rigid, pose, monkeypatch):
    """The rigid model's closed configuration at any pose, inside the joint limits or not (configuration_at's own
    reach check lifted: the loops close geometrically beyond the limits too)."""
    with monkeypatch.context() as m:
        m.setattr("pressfit.dynamics.multibody.kinematics.require_reachable", lambda machine, h, ik=None: h)
        return rigid.configuration_at(pose)


def _limits(machine):
    lim = machine.limits
    return np.array([lim.leg_length_min_m, lim.leg_length_max_m, lim.alpha_min_rad, lim.alpha_max_rad,
                     lim.beta_min_rad, lim.beta_max_rad])


def test_within_limits_on_the_joints_is_the_inverse_kinematics_check(machine, monkeypatch):
    """The run's reach guard on the rigid configuration's joints (``within_limits``) against Table 3's check on the
    plate pose's inverse kinematics (``kinematics.violations``): the same verdict at 300 poses around and beyond the
    workspace, and at poses just (1e-7 m) either side of the limit a leg meets first on lines through the workspace
    (both verdicts flip there), on the shipped machine (its lengths and alpha bind first) and on one with
    beta within [-0.3, 0.2] rad (beta binds first, at both bounds, on legs whose b-revolutes turn either way)."""
    narrow = machine.with_overrides({"limits": {"beta_min_rad": -0.3, "beta_max_rad": 0.2}})  # asymmetric: the sign
    crossings = set()
    for m in (machine, narrow):
        rigid, limits = rigid_leg_model(m, np.array([0.0, 0.62, 0.0])), _limits(m)
        for pose in RNG.uniform([-0.35, 0.35, -0.35], [0.35, 0.85, 0.35], (150, 3)):
            q = _configuration(rigid, pose, monkeypatch)
            inside = not kinematics.violations(m, pose)
            assert kernels.within_limits(q, rigid.actuator_q, rigid.sigma, limits) == inside
        for direction in ([0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [1.0, -0.3, 1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0],
                          [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]):
            inside, step = np.array([0.0, 0.62, 0.0]), np.asarray(direction) / np.linalg.norm(direction)
            lo, hi = 0.0, 1.0
            for _ in range(60):  # the distance along the line where the pose leaves the limits
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if not kinematics.violations(m, inside + mid * step) else (lo, mid)
            for offset, ok in ((-1e-7, True), (1e-7, False)):
                pose = inside + (hi + offset) * step
                assert (not kinematics.violations(m, pose)) == ok
                q = _configuration(rigid, pose, monkeypatch)
                assert kernels.within_limits(q, rigid.actuator_q, rigid.sigma, limits) == ok, (direction, offset)
            _, name, _, bound = kinematics.violations(m, inside + (hi + 1e-7) * step)[0]
            crossings.add((name, bound.split()[0]))
    assert {name for name, _ in crossings} == {"leg length l [m]", "alpha [rad]", "beta [rad]"}
    assert {("beta [rad]", "minimum"), ("beta [rad]", "maximum")} <= crossings
    q = _configuration(rigid, np.array([0.0, 0.62, 0.0]), monkeypatch)
    assert kernels.within_limits(q, rigid.actuator_q, rigid.sigma, limits)
    q[1] = -1e-9  # the plate below the base, its legs' joints left within their limits: refused (y_h > 0)
    assert not kernels.within_limits(q, rigid.actuator_q, rigid.sigma, limits)


def test_rigid_post_step_fills_the_row_from_the_new_pose(machine, rigid):
    """``rigid_post_step`` after a step from a pose to one 5 mm away, the deflection rows computed 1.5 mm from the
    new pose: the row's plate is the new pose, its tool the new pose plus c0 F + c1 with the rows extrapolated to
    the new pose in numpy (not the previous one: the column moves by 4e-4 of itself over the 5 mm), F the elastic
    law at the interference that deflection leaves, the lengths and rates the new state's, the estimate the
    Gauss-Newton fit of the new lengths, and the next step's plate force R^T (0, F, 0). A NaN configuration or an
    infinite velocity is refused (False) before anything is written."""
    from pressfit.dynamics.control import linearised_columns
    from pressfit.dynamics.series import KINEMATIC_ITERATIONS, series_columns

    new, old = np.array([0.05, 0.6001, -0.05]), np.array([0.053, 0.604, -0.05])
    q, previous = rigid.configuration_at(new), rigid.configuration_at(old)
    v = rigid.admissible_velocity(q, [0.0, -0.01, 0.0])
    at = new + [1.5e-3, 0.0, -1e-3]
    rows, gradient = linearised_columns(machine, at[None], True)
    contact = contact_parameters(Contact(board_height_m=0.6003, pin_position_m=[0.05, -0.05], stiffness_n_per_m=2e5,
                                         damping_n_s_per_m=0.0))
    columns = series_columns(len(machine.legs))
    layout = np.array([columns.index(c) for c in ("plate_x_m", "tool_x_m", "contact_force_n", "depth_m", "axial_n1",
                                                  "kinematic_x_m", "length_m1", "rate_m_per_s1")])
    row, estimate, units = np.zeros(len(columns)), old.copy(), np.empty((4, 3))
    lengths, rates, tau = np.empty(4), np.empty(4), np.empty(3)

    def post(row, q, v):
        return kernels.rigid_post_step(
            row, previous, q, v, np.zeros(24), rigid.actuator_q, rigid.actuator_v, contact, 0.0, 1e-3, at, rows[0],
            gradient[0], np.empty(0), np.empty((0, 3)), np.ascontiguousarray(machine.plate_offsets_m -
                                                                            machine.base_points_m), estimate, units,
            3, KINEMATIC_ITERATIONS, tau, layout, lengths, rates)

    ok, force, depth, _ = post(row, q, v)
    c0, c1 = rows[0] + gradient[0] @ (new - at)
    deflection = c0 * force + c1
    assert ok and force > 1.0 and depth == pytest.approx(0.6003 - new[1] - deflection[1], abs=1e-15)
    assert force == pytest.approx(2e5 * depth, rel=1e-8)
    assert np.abs(row[layout[1]:layout[1] + 3] - (new + deflection)).max() < 1e-15
    assert np.array_equal(row[layout[0]:layout[0] + 3], q[0:3])
    stale = rows[0] + gradient[0] @ (old - at)  # the columns at the previous pose: off by far more
    assert np.abs(stale[0] * force + stale[1] - deflection).max() > 1e3 * 1e-15
    assert np.array_equal(lengths, q[rigid.actuator_q]) and np.array_equal(rates, v[rigid.actuator_v])
    assert np.abs(estimate - new).max() < 1e-12
    rotation = pin.Quaternion(q[3:7]).matrix()
    assert np.abs(tau - rotation.T @ [0.0, force, 0.0]).max() < 1e-12
    for which, bad in ((0, np.nan), (1, np.inf)):  # a state that is not finite: refused, the row left alone
        state = [q.copy(), v.copy()]
        state[which][-1] = bad
        untouched = row.copy()
        assert post(row, *state) == (False, 0.0, 0.0, 0.0) and np.array_equal(row, untouched)


def test_the_flexible_newton_kernels_are_the_generalised_alpha_formulas():
    """newton_predict, newton_residual and newton_update (the vector arithmetic of a flexible step's Newton
    iteration) against a numpy transcription of the formulas of pressfit.dynamics.machine.flexible's module doc on
    random inputs, bit for bit (the same operations in the same order): the pseudo-acceleration a = c_acc acc +
    c_old, dq = base_dq + h^2 beta a, v = base_v + h gamma a, rel = v - v_r, rnea's acc + alpha rel; the residual
    inertial + B^T lambda - external plus the springs' k (x + beta rel) (linear) or f + beta k_t rel, then phi; the
    update acc -= scale dx, lambda -= dx and |dx[:nv]|_inf, NaN when a correction is."""
    rng = np.random.default_rng(7)
    nv, nc, ns = 20, 6, 8
    acc, c_old, base_dq, base_v, v_r = (rng.standard_normal(nv) for _ in range(5))
    out = np.empty((4, nv))
    kernels.newton_predict(acc, 0.7, c_old, base_dq, 1e-6, base_v, 2e-3, v_r, 3.0, *out)
    a = 0.7 * acc + c_old
    v = base_v + 2e-3 * a
    for got, expected in zip(out, (base_dq + 1e-6 * a, v, v - v_r, acc + 3.0 * (v - v_r)), strict=True):
        assert np.array_equal(got, expected)
    inertial, closures, external, q, rel = (rng.standard_normal(nv) for _ in range(5))
    sq, sv = rng.choice(nv, ns, replace=False), rng.choice(nv, ns, replace=False)
    rest, k, f, kt, phi = (rng.standard_normal(n) for n in (ns, ns, ns, ns, nc))
    for linear in (True, False):
        rhs = np.empty(nv + nc)
        kernels.newton_residual(inertial, closures, external, q, sq, sv, rest, k, f, kt, linear, rel, 0.3, phi, rhs)
        r = inertial + closures - external
        r[sv] += k * (q[sq] - rest + 0.3 * rel[sv]) if linear else f + 0.3 * kt * rel[sv]
        assert np.array_equal(rhs, np.concatenate([r, phi]))
    dx, acc1, lam1 = rng.standard_normal(nv + nc), rng.standard_normal(nv), rng.standard_normal(nc)
    acc2, lam2 = acc1.copy(), lam1.copy()
    size = kernels.newton_update(dx, nv, 5.0, acc2, lam2)
    assert size == np.abs(dx[:nv]).max() and size > 0
    assert np.array_equal(acc2, acc1 - 5.0 * dx[:nv]) and np.array_equal(lam2, lam1 - dx[nv:])
    for where in (0, nv // 2, nv - 1):
        bad = dx.copy()
        bad[where] = np.nan
        assert math.isnan(kernels.newton_update(bad, nv, 5.0, acc1.copy(), lam1.copy()))


def test_the_flexible_step_end_is_the_generalised_alpha_update():
    """newton_end (a flexible step's end state from its converged accelerations) against the numpy expressions of
    the update (Chung and Hulbert's generalised-alpha: a_ps = ((1 - af) acc + af acc_n - am a_n) / (1 - am),
    dq = base_dq + h^2 beta a_ps, v = base_v + h gamma a_ps), bit for bit, at rho_inf = 0.8's coefficients."""
    from pressfit.dynamics.machine.flexible import generalized_alpha

    am, af, gamma, beta = generalized_alpha(0.8)
    rng = np.random.default_rng(11)
    acc, acc_n, a_n, base_dq, base_v = (rng.standard_normal(30) for _ in range(5))
    h = 2e-4
    out = np.empty((3, 30))
    kernels.newton_end(acc, acc_n, a_n, af, am, base_dq, h * h * beta, base_v, h * gamma, *out)
    a_ps = ((1 - af) * acc + af * acc_n - am * a_n) / (1 - am)
    for got, expected in zip(out, (a_ps, base_dq + h * h * beta * a_ps, base_v + h * gamma * a_ps), strict=True):
        assert np.array_equal(got, expected)


def test_the_closure_gaps_are_the_largest_norms_of_the_error_triples():
    """closure_gaps: the largest translation and rotation error norm over the closures (each closure's six errors
    a translation then a rotation triple), against numpy's norms of the reshaped errors bit for bit; a NaN error
    anywhere is the answer for its part (numpy's max keeps it), never skipped."""
    rng = np.random.default_rng(5)
    for _ in range(50):
        phi = rng.standard_normal(24) * 10.0 ** rng.integers(-12, 0)
        norms = np.sqrt((phi.reshape(4, 2, 3) ** 2).sum(2)).max(0)
        assert kernels.closure_gaps(phi) == (norms[0], norms[1])
    phi = np.zeros(24)
    phi[13] = 3e-6  # the third closure's translation: the largest wherever it sits
    assert kernels.closure_gaps(phi) == (3e-6, 0.0)
    for where, part in ((0, 0), (4, 1), (19, 0), (23, 1)):
        bad = phi.copy()
        bad[where] = np.nan
        gaps = kernels.closure_gaps(bad)
        assert math.isnan(gaps[part]) and not math.isnan(gaps[1 - part])


def test_all_finite_is_numpys_isfinite_of_both_vectors():
    """all_finite(q, v) (the flexible scenario's guard) is np.isfinite(q).all() and np.isfinite(v).all(): false for a
    NaN, +inf or -inf anywhere in either vector, true otherwise."""
    q, v = np.linspace(-1.0, 1.0, 13), np.linspace(-2.0, 3.0, 12)
    assert kernels.all_finite(q, v)
    for bad in (np.nan, np.inf, -np.inf):
        for which in (0, 1):
            for where in (0, 5, -1):
                x = (q.copy(), v.copy())
                x[which][where] = bad
                assert not kernels.all_finite(*x)
