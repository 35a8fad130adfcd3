r"""The per-step arithmetic of the insertion loop, compiled (numba ``njit``): at the loop's sizes (3- and
n-vectors) numpy's per-call overhead of about a microsecond costs more than the arithmetic, and the rigid-leg
step itself (Pinocchio's constraint dynamics) takes about 30 us. Each kernel is the one implementation of its
quantity; the Python functions of :mod:`pressfit.dynamics.control`, :mod:`pressfit.dynamics.actuators`,
:mod:`pressfit.dynamics.contact` and :mod:`pressfit.dynamics.multibody` call them.

* :func:`gauss_newton`: the pose estimate (equation 1, Gauss-Newton on the n lengths, the 3 x 3 normal
  equations by the adjugate);
* :func:`distribution`: A^+ = E N^-1 and the preload basis V of A = E^T (n legs: n - 3 unit null vectors by
  cofactors, v_p of equations 9-10 on the 4-UPU; equation 5) in closed form from the normal matrix
  N = E^T E = A A^T, and A's smallest singular value sqrt(lambda_min(N)) (the closed-form eigenvalues of a
  symmetric 3 x 3 matrix); :func:`internal_forces`: the preload amplitudes a set of tensions carries;
* :func:`control`: Figure 12's PID with the force limiter (:mod:`pressfit.dynamics.control`);
* :func:`moved`: the pose caches' test (:class:`pressfit.dynamics.multibody.PoseCache`,
  :class:`pressfit.dynamics.control.DeflectionCache`); :func:`nearest`: the deflection cache's search of the nodes
  computed beforehand along the planned path; :func:`extrapolated`: its rows extrapolated to a pose;
* :func:`first_order`: the ideal force drive's step (:mod:`pressfit.dynamics.actuators`);
* :func:`contact_law`, :func:`solve_contact`: the contact law and the bisection of the series compliance
  (:mod:`pressfit.dynamics.contact`);
* :func:`axial_forces`: the legs' axial forces from the closure forces and the plate cardan angles;
* :func:`rigid_post_step`: after one rigid-leg step, all of the above that the step's row needs;
  :func:`within_limits`: its joints against Table 3's limits, every step (the run's guard);
* :func:`hydraulic_substeps`: the servo-valve cylinders' pressure substeps (:mod:`pressfit.dynamics.drives.hydraulic`),
  called in every Newton iteration of a flexible step with a hydraulic drive;
* :func:`newton_predict`, :func:`newton_residual`, :func:`newton_update`: the vector arithmetic around Pinocchio's
  calls in each Newton iteration of the flexible step (:meth:`pressfit.dynamics.machine.flexible.FlexibleMachine.step`:
  the generalised-alpha update, the residual and its springs, the correction);
* :func:`play_iteration`: one iteration of the cardan plays' safeguarded Newton (:mod:`pressfit.dynamics.play`), on
  the compiled dead zone of :mod:`pressfit.mechanics.clearance_law`.

Compiled by :func:`pressfit.compiled.compiled` (``error_model="numpy"``, the cache in the user's cache directory,
:func:`cache_directory`): the first call in a fresh install compiles (about 10 s of CPU, once).
"""

from __future__ import annotations

import math

import numpy as np

from pressfit.compiled import cache_directory, compiled  # noqa: F401 (cache_directory: where the kernels live)
from pressfit.mechanics.clearance_law import dead_zone

# contact laws (contact_law's ``law``): elastic, press fit with a linear or a saturating (tanh) fit force, and any
# other law tabulated on a depth grid (TABLE: :func:`pressfit.dynamics.contact.contact_parameters`)
ELASTIC, FIT_LINEAR, FIT_TANH, TABLE = 0, 1, 2, 3
# the controller's parameter vector (control's ``params``)
KP, KD, KI, FORCE_LIMIT, BACKOFF, LIMITER, GRAVITY, GRAVITY_TOL, DEFLECTION, DEFLECTION_TOL = range(10)
SINGULAR_SIGMA = 1e-6  # A is singular below this smallest singular value (entries O(1))
SINGULAR_DET = 1e-12  # legs 1-3 do not span space below this |det(e_1, e_2, e_3)| (the preload basis' test)
BISECTIONS = 60  # bisection steps of the contact solve (to 1e-9 of the bracket, module docstring of contact)
# the contact's parameter vector (solve_contact's ``contact``)
BOARD, STIFFNESS, DAMPING, LAW, FIT_STIFFNESS, FIT_FORCE, FIT_DEPTH = range(7)
# a TABLE law appends: the table's largest force (N), the slope past its last depth (N/m), its row count n, the
# unloading stiffness (N/m; 0: a reversible law, the force follows the table back), the deepest depth reached so far
# (m: the joint's state, which contact_advance moves on), then n depths (m, increasing) and n forces (N)
TABLE_MAX, TABLE_SLOPE, TABLE_COUNT, TABLE_UNLOAD, TABLE_DEEPEST, TABLE_START = 7, 8, 9, 10, 11, 12
# rigid_post_step's ``layout``: the first column of each quantity it writes into the row
ROW_PLATE, ROW_TOOL, ROW_FORCE, ROW_DEPTH, ROW_AXIAL, ROW_KINEMATIC, ROW_LENGTHS, ROW_RATES = range(8)
# rigid_pre_step's ``layout``
ROW_TIME, ROW_REFERENCE, ROW_ESTIMATE, ROW_COMMAND, ROW_TENSION, ROW_LIFT, ROW_INTERNAL = range(7)


@compiled
def _legs(offsets, lengths, hx, hy, hz, units, residuals):
    """Unit vectors e_i (n, 3) and length residuals l_i(h) - l_i (n,) at h (equation 1: u_i = h + d_i - B_i)."""
    for i in range(offsets.shape[0]):
        ux, uy, uz = hx + offsets[i, 0], hy + offsets[i, 1], hz + offsets[i, 2]
        n = math.sqrt(ux * ux + uy * uy + uz * uz)
        units[i, 0], units[i, 1], units[i, 2] = ux / n, uy / n, uz / n
        residuals[i] = n - lengths[i]


@compiled
def gauss_newton(offsets, lengths, pose, iterations, units):
    """Gauss-Newton on the n leg lengths (m) from ``pose`` (3,), m, updated in place; fills ``units`` (n, 3) with
    the leg unit vectors at the result and returns the largest |length residual| there (m)."""
    hx, hy, hz = pose[0], pose[1], pose[2]
    legs = offsets.shape[0]
    r = np.empty(legs)
    _legs(offsets, lengths, hx, hy, hz, units, r)
    for _ in range(iterations):
        a00 = a01 = a02 = a11 = a12 = a22 = b0 = b1 = b2 = 0.0
        for i in range(legs):  # e^T e and e^T r
            ex, ey, ez, ri = units[i, 0], units[i, 1], units[i, 2], r[i]
            a00 += ex * ex
            a01 += ex * ey
            a02 += ex * ez
            a11 += ey * ey
            a12 += ey * ez
            a22 += ez * ez
            b0 += ex * ri
            b1 += ey * ri
            b2 += ez * ri
        c00, c01, c02 = a11 * a22 - a12 * a12, a02 * a12 - a01 * a22, a01 * a12 - a02 * a11
        c11, c12, c22 = a00 * a22 - a02 * a02, a02 * a01 - a00 * a12, a00 * a11 - a01 * a01
        det = a00 * c00 + a01 * c01 + a02 * c02
        hx -= (c00 * b0 + c01 * b1 + c02 * b2) / det
        hy -= (c01 * b0 + c11 * b1 + c12 * b2) / det
        hz -= (c02 * b0 + c12 * b1 + c22 * b2) / det
        _legs(offsets, lengths, hx, hy, hz, units, r)
    pose[0], pose[1], pose[2] = hx, hy, hz
    return np.max(np.abs(r))


@compiled
def _triple(units, i, j, k):
    """det(e_i, e_j, e_k) of rows i, j, k of ``units``."""
    return (units[i, 0] * (units[j, 1] * units[k, 2] - units[j, 2] * units[k, 1])
            - units[i, 1] * (units[j, 0] * units[k, 2] - units[j, 2] * units[k, 0])
            + units[i, 2] * (units[j, 0] * units[k, 1] - units[j, 1] * units[k, 0]))


@compiled
def distribution(units, pinv, null):
    """A^+ (n, 3) into ``pinv`` and the preload basis V (n, n - 3) into ``null`` from the leg unit vectors
    ``units`` (n, 3) (rows e_i: A = E^T); returns A's smallest singular value (0 where, on n >= 5 legs, legs 1-3
    do not span space and V is undefined). A^+ = A^T (A A^T)^-1 = E N^-1, N = E^T E by the adjugate; vector k of
    V is the generalised cross product of the legs 1, 2, 3 and j = 3 + k (equations 9-10 on the 4-UPU, where it
    is v_p, v_1 < 0): (-det(e_j, e_2, e_3), -det(e_1, e_j, e_3), -det(e_1, e_2, e_j), 0 ..., D at j, 0 ...),
    D = det(e_1, e_2, e_3), made unit with component j > 0, as :func:`pressfit.kinematics.preload_basis`;
    lambda_min(N) by the trigonometric closed form of a symmetric 3 x 3 eigenproblem (accurate to ~1e-16 absolute
    near a singular A, where lambda_min is far from the others; to ~1e-11 where two eigenvalues nearly coincide,
    far from the 1e-12 of the singularity test)."""
    legs = units.shape[0]
    a00 = a01 = a02 = a11 = a12 = a22 = 0.0
    for i in range(legs):
        ex, ey, ez = units[i, 0], units[i, 1], units[i, 2]
        a00 += ex * ex
        a01 += ex * ey
        a02 += ex * ez
        a11 += ey * ey
        a12 += ey * ez
        a22 += ez * ez
    c00, c01, c02 = a11 * a22 - a12 * a12, a02 * a12 - a01 * a22, a01 * a12 - a02 * a11
    c11, c12, c22 = a00 * a22 - a02 * a02, a02 * a01 - a00 * a12, a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    for i in range(legs):
        ex, ey, ez = units[i, 0], units[i, 1], units[i, 2]
        pinv[i, 0] = (ex * c00 + ey * c01 + ez * c02) / det
        pinv[i, 1] = (ex * c01 + ey * c11 + ez * c12) / det
        pinv[i, 2] = (ex * c02 + ey * c12 + ez * c22) / det
    d = _triple(units, 0, 1, 2)
    for k in range(legs - 3):
        j = 3 + k
        for i in range(legs):
            null[i, k] = 0.0
        null[0, k], null[1, k], null[2, k] = -_triple(units, j, 1, 2), -_triple(units, 0, j, 2), \
            -_triple(units, 0, 1, j)
        null[j, k] = d
        norm = 0.0
        for i in range(legs):
            norm += null[i, k] * null[i, k]
        scale = (-1.0 if d < 0.0 else 1.0) / math.sqrt(norm)
        for i in range(legs):
            null[i, k] *= scale
    if legs - 3 > 1 and abs(d) < SINGULAR_DET:  # two or more vectors need legs 1-3 to span space
        return 0.0
    q = (a00 + a11 + a22) / 3.0
    off = a01 * a01 + a02 * a02 + a12 * a12
    p = math.sqrt(((a00 - q) ** 2 + (a11 - q) ** 2 + (a22 - q) ** 2 + 2.0 * off) / 6.0)
    if p == 0.0:
        return math.sqrt(q)
    b00, b11, b22 = (a00 - q) / p, (a11 - q) / p, (a22 - q) / p
    b01, b02, b12 = a01 / p, a02 / p, a12 / p
    half_det = 0.5 * (b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) + b02 * (b01 * b12 - b11 * b02))
    phi = math.acos(min(1.0, max(-1.0, half_det))) / 3.0
    smallest = q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)
    return math.sqrt(max(smallest, 0.0))


@compiled
def moved(pose, reference, tolerance):
    """True when ``pose`` moved more than ``tolerance`` from ``reference`` (infinity norm; same units)."""
    for k in range(pose.size):  # noqa: SIM110 (numba compiles the loop, not a generator in any())
        if abs(pose[k] - reference[k]) > tolerance:
            return True
    return False


NEAREST_WINDOW = 64  # nodes searched either side of the hint before the whole list


@compiled
def _nearest_in(nodes, pose, tolerance, lo, hi):
    best, index = tolerance, -1
    for i in range(lo, hi):
        d = max(abs(nodes[i, 0] - pose[0]), abs(nodes[i, 1] - pose[1]), abs(nodes[i, 2] - pose[2]))
        if d <= best:
            best, index = d, i
    return index


@compiled
def nearest(nodes, pose, tolerance, hint):
    """The index of the row of ``nodes`` (k, 3) nearest to ``pose`` (3,) in the infinity norm among those within
    ``tolerance`` of it (same units), else -1: the nearest within ``NEAREST_WINDOW`` rows of ``hint`` (the last
    node taken: a path's nodes are in its order and the pose moves along it), followed row by row while a neighbour
    is nearer, or, where none of those rows is within the tolerance, the nearest of all rows (a pose that came back
    to an earlier part of the path)."""
    k = nodes.shape[0]
    index = _nearest_in(nodes, pose, tolerance, max(hint - NEAREST_WINDOW, 0), min(hint + NEAREST_WINDOW + 1, k))
    if index < 0:
        return _nearest_in(nodes, pose, tolerance, 0, k)
    while True:  # on along the path while a neighbour is nearer (the window's best may sit at its edge)
        best = _nearest_in(nodes, pose, tolerance, max(index - 1, 0), min(index + 2, k))
        if best == index:
            return index
        index = best


# within_limits' ``limits``: Table 3's (leg length m, alpha rad, beta rad), each min then max
LENGTH_MIN, LENGTH_MAX, ALPHA_MIN, ALPHA_MAX, BETA_MIN, BETA_MAX = range(6)


@compiled
def within_limits(q, actuator_q, sigma, limits):
    """Whether the rigid-leg configuration ``q`` (:class:`pressfit.dynamics.multibody.RigidLegModel`: per leg
    alpha, sigma beta, l at actuator_q - 2, - 1 and actuator_q, sigma (n,) the b-revolutes' signs) has every leg's
    length and base cardan angles within ``limits`` and the plate above the base (y_h > 0): Table 3's check on the
    joints the model integrates, which :func:`pressfit.kinematics.violations` makes on the plate pose's inverse
    kinematics (the two agree to the closures' drift)."""
    for i in range(actuator_q.shape[0]):
        j = actuator_q[i]
        length, alpha, beta = q[j], q[j - 2], sigma[i] * q[j - 1]
        if not (limits[LENGTH_MIN] <= length <= limits[LENGTH_MAX] and limits[ALPHA_MIN] <= alpha <= limits[ALPHA_MAX]
                and limits[BETA_MIN] <= beta <= limits[BETA_MAX]):
            return False
    return q[1] > 0.0


@compiled
def extrapolated(pose, at, rows, gradient, out):
    """``rows`` (r, 3) computed at the pose ``at`` (3,), m, extrapolated to first order to ``pose`` (3,) with their
    ``gradient`` (r, 3, 3), per m, into ``out`` (r, 3): the deflection caches' columns
    (:class:`pressfit.dynamics.control.DeflectionCache`)."""
    d0, d1, d2 = pose[0] - at[0], pose[1] - at[1], pose[2] - at[2]
    for a in range(rows.shape[0]):
        for j in range(3):
            out[a, j] = rows[a, j] + (gradient[a, j, 0] * d0 + gradient[a, j, 1] * d1 + gradient[a, j, 2] * d2)


@compiled
def control(params, estimate, units, rates, target, target_velocity, contact_force, dt, integral, lift,
            gravity_pose, gravity, deflection_pose, deflection_rows, deflection_gradient, pinv, null, force, tension,
            preload):
    """Figure 12's loop at the estimate (m) with leg unit vectors ``units`` (:mod:`pressfit.dynamics.control`):
    fills ``pinv``, ``null`` (:func:`distribution`), the Cartesian force W (3,), N, into ``force`` and the tensions
    -A^+ W + V a (n,), N, into ``tension`` (a = ``preload`` (n - 3,), N: a4 v_p on the 4-UPU); updates
    ``integral`` (m s) in place. With params[DEFLECTION] the error is taken against the estimate plus the
    predicted static deflection (2, 3): row 0 per newton of ``contact_force`` (m/N), row 1 the weight's sag (m),
    ``deflection_rows`` computed at ``deflection_pose`` and extrapolated to the estimate with their
    ``deflection_gradient`` (:func:`extrapolated`). Returns
    (status, lift m, clamped, smallest singular value of A): status 1 when the gravity feed-forward ``gravity``
    (computed at ``gravity_pose``) is stale (the estimate moved more than params[GRAVITY_TOL] from it; nothing else
    is done, the caller refreshes it and calls again), 3 when the deflection is stale (params[DEFLECTION_TOL]:
    likewise), 2 when A is singular (below SINGULAR_SIGMA: nothing else done)."""
    if params[GRAVITY] != 0.0 and moved(estimate, gravity_pose, params[GRAVITY_TOL]):
        return 1, lift, False, 0.0
    compensate = params[DEFLECTION] != 0.0
    if compensate and moved(estimate, deflection_pose, params[DEFLECTION_TOL]):
        return 3, lift, False, 0.0
    sigma = distribution(units, pinv, null)
    if sigma < SINGULAR_SIGMA:
        return 2, lift, False, sigma
    deflection = np.zeros((2, 3))
    if compensate:
        extrapolated(estimate, deflection_pose, deflection_rows, deflection_gradient, deflection)
    kp, kd, ki, limit = params[KP], params[KD], params[KI], params[FORCE_LIMIT]
    limiter = params[LIMITER] != 0.0
    error = np.empty(3)
    for j in range(3):
        velocity = 0.0
        for i in range(units.shape[0]):
            velocity += pinv[i, j] * rates[i]
        tool = estimate[j] + deflection[0, j] * contact_force + deflection[1, j] if compensate else estimate[j]
        error[j] = (target[j] + (lift if j == 1 else 0.0)) - tool
        force[j] = kp * error[j] + kd * target_velocity[j] + ki * integral[j]
        if j == 1:
            clamped = limiter and contact_force > 0.0 and force[1] < -limit
            if clamped:
                force[1] = -limit
                error[1] = 0.0  # anti-windup: the vertical integrator holds while clamped
        force[j] -= kd * velocity  # damping acts outside the clamp
        integral[j] = integral[j] + dt * error[j]
    if limiter and (contact_force > limit or lift > 0.0):
        lift = max(0.0, lift + dt * params[BACKOFF] * (contact_force - limit))
    if params[GRAVITY] != 0.0:
        for j in range(3):
            force[j] = force[j] + gravity[j]
    for i in range(units.shape[0]):
        tension[i] = -(pinv[i, 0] * force[0] + pinv[i, 1] * force[1] + pinv[i, 2] * force[2])
        for k in range(preload.shape[0]):
            tension[i] += preload[k] * null[i, k]
    return 0, lift, clamped, sigma


@compiled
def first_order(force, command, limit, decay, out):
    """The saturated first-order drive's zero-order-hold step (:class:`pressfit.dynamics.actuators.ForceActuators`):
    out = s + (force - s) decay, s = the command clipped to +-limit (N), decay = exp(-dt / tau)."""
    for i in range(force.size):
        target = min(max(command[i], -limit), limit)
        out[i] = target + (force[i] - target) * decay


@compiled
def _table_force(contact, depth):
    """A TABLE law's loading force at ``depth`` (m): np.interp between the rows, the given slope past the last."""
    n = int(contact[TABLE_COUNT])
    depths, forces = contact[TABLE_START:TABLE_START + n], contact[TABLE_START + n:TABLE_START + 2 * n]
    if depth > depths[n - 1]:
        return forces[n - 1] + contact[TABLE_SLOPE] * (depth - depths[n - 1])
    return np.interp(depth, depths, forces)


@compiled
def contact_law(contact, depth, rate):
    """F(d, d_dot) (N, >= 0) of :func:`pressfit.dynamics.contact.contact_force_n` (``contact`` as in
    :func:`solve_contact`). A TABLE law that sets (``TABLE_UNLOAD`` > 0) below the deepest depth it reached, d_max:
    the joint unloads elastically from there, F(d_max) - k_u (d_max - d), down to 0 where the tool leaves the
    component (no adhesion), and reloads along the same line up to d_max, where the table resumes."""
    if depth <= 0.0:
        return 0.0
    if contact[LAW] == TABLE:
        deepest = contact[TABLE_DEEPEST]
        if contact[TABLE_UNLOAD] > 0.0 and depth < deepest:
            force = _table_force(contact, deepest) - contact[TABLE_UNLOAD] * (deepest - depth)
        else:
            force = _table_force(contact, depth)
        return max(force + contact[DAMPING] * rate, 0.0)
    force = contact[STIFFNESS] * depth + contact[DAMPING] * rate
    if contact[LAW] == FIT_LINEAR:
        force += contact[FIT_STIFFNESS] * depth
    elif contact[LAW] == FIT_TANH:
        force += contact[FIT_FORCE] * math.tanh(depth / contact[FIT_DEPTH])
    return max(force, 0.0)


@compiled
def contact_advance(contact, depth):
    """The joint's state after a step that ended at ``depth`` (m): a TABLE law's deepest depth reached
    (``TABLE_DEEPEST``), in place; nothing for the other laws, which have none."""
    if contact[LAW] == TABLE and depth > contact[TABLE_DEEPEST]:
        contact[TABLE_DEEPEST] = depth


@compiled
def _deflect(force, column, sag, loads, disp, u):
    if loads.size == 0:
        for k in range(3):
            u[k] = column[k] * force + sag[k]
    else:
        for k in range(3):
            u[k] = sag[k] + np.interp(force, loads, disp[:, k])


@compiled
def solve_contact(contact, rigid_depth, previous_depth, dt, column, sag, loads, disp, u):
    """The contact force F (N) with the structure's deflection u(F) in series (:mod:`pressfit.dynamics.contact`):
    u = ``column`` F + ``sag``, or, when ``loads`` is not empty, ``sag`` + the table ``loads`` (n,), N -> ``disp``
    (n, 3), m, interpolated (m/N, m). ``contact`` = (board height m, k N/m, b N s/m, law, fit stiffness N/m, fit
    force N, fit depth m; a TABLE law appends its table from TABLE_MAX on). Writes u (3,), m, into ``u``; returns
    (F, interference m). The bracket's upper end is the law at the depth at zero force d(0), which includes the sag
    (the deflection grows with the force), or for a TABLE law the larger of it and the table's largest force (a
    law that falls after its peak is not monotone: the bracket still holds a root, which the bisection finds)."""
    _deflect(0.0, column, sag, loads, disp, u)
    d0 = rigid_depth - u[1]
    if 0.0 - contact_law(contact, d0, (d0 - previous_depth) / dt) >= 0.0:
        return 0.0, d0
    lo, hi = 0.0, contact_law(contact, d0, max(d0 - previous_depth, 0.0) / dt)
    if contact[LAW] == TABLE:  # a law that falls after a peak: the force at d(0) need not bound it
        hi = max(hi, contact[TABLE_MAX] + contact[DAMPING] * max(d0 - previous_depth, 0.0) / dt)
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        _deflect(mid, column, sag, loads, disp, u)
        d = rigid_depth - u[1]
        if mid - contact_law(contact, d, (d - previous_depth) / dt) < 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-9 * hi:
            break
    _deflect(hi, column, sag, loads, disp, u)
    return hi, rigid_depth - u[1]


@compiled
def axial_forces(closure_forces, q, actuator_q, out):
    """Axial force N_i (N, > 0 tension) of each leg at its plate cardan into ``out`` (n,): the closure force f
    (the first three of each leg's six in ``closure_forces``, in the frame of the leg's last body) along the leg
    axis. The last body's frame is R_0 Rx(a) Ry(b) Ry(c) Rx(d) (base cardan a, b, plate cardan c, d: q at
    ``actuator_q`` - 2, - 1, + 1, + 2) and the axis R_0 Rx(a) Ry(b) e_z, so N = f . (Ry(c) Rx(d))^T e_z =
    -f_x sin c + f_y sin d cos c + f_z cos d cos c."""
    for i in range(actuator_q.shape[0]):
        c, d = q[actuator_q[i] + 1], q[actuator_q[i] + 2]
        fx, fy, fz = closure_forces[6 * i], closure_forces[6 * i + 1], closure_forces[6 * i + 2]
        out[i] = -fx * math.sin(c) + (fy * math.sin(d) + fz * math.cos(d)) * math.cos(c)


@compiled
def internal_forces(null, tension, out):
    """The preload amplitudes a (n - 3,), N, that the tensions N (n,) carry, into ``out``: the coordinates of N's
    projection on the preload space in the basis V (n, n - 3), (V^T V)^-1 V^T N (v_p . N on the 4-UPU, V's one
    unit vector; nothing on 3 legs). For N = -A^+ W + V a it is a (A^+'s columns are orthogonal to V)."""
    r = null.shape[1]
    if r == 0:
        return
    gram, projection = np.empty((r, r)), np.empty(r)
    for k in range(r):
        projection[k] = 0.0
        for i in range(tension.shape[0]):
            projection[k] += null[i, k] * tension[i]
        for m in range(r):
            gram[k, m] = 0.0
            for i in range(tension.shape[0]):
                gram[k, m] += null[i, k] * null[i, m]
    out[:] = np.linalg.solve(gram, projection)


@compiled
def rigid_pre_step(row, t, reference, lift, estimate, command, tension, null, tau, actuator_v, contact_tau, layout):
    """Before one rigid-leg step: the step's row at the columns ``layout`` names (ROW_TIME ...): time (s), the
    reference with its lift (m), the estimate (m), the commanded and delivered tensions (N), the lift (m) and the
    internal forces (N, :func:`internal_forces`); and the joint forces ``tau``: -N on the actuators,
    ``contact_tau`` (N, the last
    step's contact force in the plate's local frame) on the plate."""
    row[layout[ROW_TIME]], row[layout[ROW_LIFT]] = t, lift
    for k in range(3):
        row[layout[ROW_REFERENCE] + k] = reference[k] + (lift if k == 1 else 0.0)
        row[layout[ROW_ESTIMATE] + k] = estimate[k]
        tau[k] = contact_tau[k]
    for i in range(actuator_v.shape[0]):
        row[layout[ROW_COMMAND] + i], row[layout[ROW_TENSION] + i] = command[i], tension[i]
        tau[actuator_v[i]] = -tension[i]
    r = null.shape[1]
    internal = np.empty(r)
    internal_forces(null, tension, internal)
    for k in range(r):
        row[layout[ROW_INTERNAL] + k] = internal[k]


@compiled
def all_finite(q, v):
    """Whether every entry of the configuration ``q`` and the velocity ``v`` is finite."""
    for x in q:
        if not math.isfinite(x):
            return False
    for x in v:  # noqa: SIM110 (numba compiles no generator into all())
        if not math.isfinite(x):
            return False
    return True


@compiled
def rigid_post_step(row, previous_q, q, v, closure_forces, actuator_q, actuator_v, contact, previous_depth, dt,
                    deflection_pose, deflection_rows, deflection_gradient, loads, disp, offsets, estimate, units,
                    iterations, kinematic_iterations, tau, layout, lengths, rates):
    """After one rigid-leg step from ``previous_q`` to (q, v): returns (False, ...) and does nothing else if the
    state is not finite. Else fills the step's row at the columns ``layout`` names (ROW_*: the caller fills the
    rest): the rigid pose and the tool tip (rigid + deflection) (m), the contact force (N) and interference (m) at
    the new rigid tool position (:func:`solve_contact`, at every step: the sag can press the tool below the
    board with the rigid tip above it), the axial forces (N) at ``previous_q``, where the
    accelerations were computed (:func:`axial_forces`), the kinematic pose (m: the forward kinematics of the new
    lengths, Gauss-Newton from ``estimate`` over ``iterations``, which becomes the next step's estimate, in
    place, with its unit vectors in ``units``, then continued to ``kinematic_iterations`` in all), the lengths
    (m) and rates (m/s), also into ``lengths`` and ``rates``; and the contact force for the next step into
    ``tau`` (the plate's local frame, R^T (0, F, 0)). Returns (True, F, interference, the estimate's largest
    length residual m). The tool's deflection at the new rigid pose: the rows (c0 m/N, c1 m) ``deflection_rows``
    computed at ``deflection_pose`` extrapolated there (:func:`extrapolated`), c0 F + c1, or c1 + the load-deflection
    table ``loads``, ``disp`` where it is not empty (:func:`solve_contact`)."""
    if not all_finite(q, v):
        return False, 0.0, 0.0, 0.0
    u, deflection = np.empty(3), np.empty((2, 3))
    extrapolated(q, deflection_pose, deflection_rows, deflection_gradient, deflection)
    force, depth = solve_contact(contact, contact[BOARD] - q[1], previous_depth, dt, deflection[0], deflection[1],
                                 loads, disp, u)
    contact_advance(contact, depth)
    for k in range(3):
        row[layout[ROW_PLATE] + k] = q[k]
        row[layout[ROW_TOOL] + k] = q[k] + u[k]
    row[layout[ROW_FORCE]], row[layout[ROW_DEPTH]] = force, depth
    legs = actuator_q.shape[0]
    axial = np.empty(legs)
    axial_forces(closure_forces, previous_q, actuator_q, axial)
    for i in range(legs):
        row[layout[ROW_AXIAL] + i] = axial[i]
        lengths[i], rates[i] = q[actuator_q[i]], v[actuator_v[i]]
        row[layout[ROW_LENGTHS] + i], row[layout[ROW_RATES] + i] = lengths[i], rates[i]
    residual = gauss_newton(offsets, lengths, estimate, iterations, units)
    kinematic = estimate.copy()
    if kinematic_iterations > iterations:
        gauss_newton(offsets, lengths, kinematic, kinematic_iterations - iterations, np.empty((legs, 3)))
    for k in range(3):
        row[layout[ROW_KINEMATIC] + k] = kinematic[k]
    x, y, z, w = q[3], q[4], q[5], q[6]  # R^T e_y F: the second row of R(quaternion)
    tau[0], tau[1], tau[2] = 2.0 * (x * y + z * w) * force, (1.0 - 2.0 * (x * x + z * z)) * force, \
        2.0 * (y * z - x * w) * force
    return True, force, depth, residual


# hydraulic_substeps' ``params``: the valve, the oil and the cylinder (:mod:`pressfit.dynamics.drives.hydraulic`)
(HYD_GAIN, HYD_FLOW_GAIN, HYD_LAMINAR, HYD_SUPPLY, HYD_TANK, HYD_LEAKAGE, HYD_BULK, HYD_AREA, HYD_DEAD_A, HYD_DEAD_B,
 HYD_STROKE, HYD_LENGTH_MIN, HYD_MARGIN) = range(13)


@compiled
def _orifice(kv, lam, opening, drop):
    """Q = K_v x sqrt(dp) (laminar below dp_lam) and dQ/d(dp) of one orifice, m^3/s and m^3/(s Pa)."""
    mag = abs(drop)
    root = math.sqrt(max(mag, lam))
    if mag >= lam:
        sign = 1.0 if drop > 0.0 else (-1.0 if drop < 0.0 else 0.0)
        return kv * opening * (sign * root), kv * opening * (0.5 / root)
    return kv * opening * (drop / math.sqrt(lam)), kv * opening * (1.0 / math.sqrt(lam))


@compiled
def hydraulic_substeps(pa, pb, xv, dp_cmd, feedforward, length, rate, h, n, decay, dt, params):
    """The servo-valve cylinders' n pressure substeps of h (s) per leg, in place on the chamber pressures pa, pb
    (Pa) and the spools xv (:meth:`pressfit.dynamics.drives.hydraulic.HydraulicDrive.step`): the spool's first-order
    lag toward the pressure loop's command (``dp_cmd`` Pa, ``feedforward`` per leg), the chambers' volumes at the
    mid-substep length, linearly implicit Euler on the two pressures. Returns whether every piston stays in its
    stroke over the step of dt (s) at its rate, and every pressure in [-0.1 p_s, 10 p_s] at its end (the drive's
    refusals)."""
    gain, kv, lam, ps, pt = params[HYD_GAIN], params[HYD_FLOW_GAIN], params[HYD_LAMINAR], params[HYD_SUPPLY], \
        params[HYD_TANK]
    cl, beta, area = params[HYD_LEAKAGE], params[HYD_BULK], params[HYD_AREA]
    stroke_ok, pressures_ok = True, True
    for i in range(pa.shape[0]):
        for end in (length[i], length[i] + rate[i] * dt):
            piston = end - params[HYD_LENGTH_MIN] + params[HYD_MARGIN]
            stroke_ok = stroke_ok and piston >= 0.0 and piston <= params[HYD_STROKE]
        a, b, x = pa[i], pb[i], xv[i]
        for k in range(n):
            x_cmd = min(max(gain * (dp_cmd[i] - (a - b)) - feedforward[i], -1.0), 1.0)
            x = x_cmd + (x - x_cmd) * decay
            piston = length[i] + rate[i] * (k + 0.5) * h - params[HYD_LENGTH_MIN] + params[HYD_MARGIN]
            v_a = params[HYD_DEAD_A] + area * (params[HYD_STROKE] - piston)
            v_b = params[HYD_DEAD_B] + area * piston
            up, down = max(x, 0.0), min(x, 0.0)
            qa1, da1 = _orifice(kv, lam, up, ps - a)
            qa2, da2 = _orifice(kv, lam, down, a - pt)
            qb1, db1 = _orifice(kv, lam, up, b - pt)
            qb2, db2 = _orifice(kv, lam, down, ps - b)
            leak = cl * (a - b)
            ga, gb = beta / v_a, beta / v_b
            fa = ga * (qa1 + qa2 + area * rate[i] - leak)
            fb = gb * (-qb1 - qb2 - area * rate[i] + leak)
            jaa, jab, jba, jbb = ga * (-da1 + da2 - cl), ga * cl, gb * cl, gb * (-db1 + db2 - cl)
            m00, m01, m10, m11 = 1.0 - h * jaa, -h * jab, -h * jba, 1.0 - h * jbb
            det = m00 * m11 - m01 * m10
            a, b = a + h * (m11 * fa - m01 * fb) / det, b + h * (m00 * fb - m10 * fa) / det
        pa[i], pb[i], xv[i] = a, b, x
        pressures_ok = pressures_ok and a >= -0.1 * ps and a <= 10.0 * ps and b >= -0.1 * ps and b <= 10.0 * ps
    return stroke_ok, pressures_ok


@compiled
def play_iteration(x, tension, inertia, g, k, w, kd, trust, lo, hi, previous, tol, f, last):
    """One iteration of the plays' safeguarded Newton (:meth:`pressfit.dynamics.play.PlayedDrive.__call__`) per leg
    at extensions x (m) under the drive's tensions (N) and its side's inertia forces (N) at the step's end: the
    residual r = f(x) - tension - inertia of the dead zones (gaps g m, stiffness k N/m, width w m), the bracket
    [lo, hi] it tightens, a Newton step on r' = f' + kd (N/m) within +-trust (m). Where Newton leaves the bracket or
    does not halve its last step (``previous``, m): the bracket's midpoint once both ends are known, else a secant
    step through the last iterate (``last`` (2, n): its x and r; nan before one), so a tangent hint kd that
    overestimates the drive's stiffness (inside a gap, where the drive alone resists) converges superlinearly, not at
    the rate 1 - r' / (f' + kd). Writes f(x) (N) into ``f``; returns True when every step is within tol (m), x then
    unchanged, else advances x, lo, hi, ``previous`` and ``last`` in place."""
    done = True
    step = np.empty(x.shape[0])
    for i in range(x.shape[0]):
        _, f[i], tangent = dead_zone(x[i], g[i], k, w)
        r = f[i] - tension[i] - inertia[i]
        if r <= 0:
            lo[i] = max(lo[i], x[i])
        if r >= 0:
            hi[i] = min(hi[i], x[i])
        newton = min(max(x[i] - r / max(tangent + kd[i], 1e-300), x[i] - trust[i]), x[i] + trust[i])
        slow = newton < lo[i] or newton > hi[i] or abs(newton - x[i]) > 0.5 * previous[i]
        if slow and math.isfinite(lo[i]) and math.isfinite(hi[i]):
            step[i] = 0.5 * (lo[i] + hi[i]) - x[i]
        elif slow and last[0, i] != x[i] and (r - last[1, i]) * (x[i] - last[0, i]) > 0:  # r is increasing in x
            secant = x[i] - r * (x[i] - last[0, i]) / (r - last[1, i])
            step[i] = min(max(secant, x[i] - trust[i]), x[i] + trust[i]) - x[i]
        else:
            step[i] = newton - x[i]
        last[0, i], last[1, i] = x[i], r
        previous[i] = abs(step[i])
        done = done and previous[i] <= tol
    if not done:
        for i in range(x.shape[0]):
            x[i] += step[i]
    return done


@compiled
def newton_predict(acc, c_acc, c_old, base_dq, hhb, base_v, hg, v_r, alpha, dq, v, rel, acc_eff):
    """The flexible step's iterate from the accelerations ``acc`` (nv,): the generalised-alpha pseudo-acceleration
    a = c_acc acc + c_old, the configuration increment dq = base_dq + hhb a (m, rad), the velocity v = base_v + hg a,
    the elastic velocity rel = v - v_r and the accelerations rnea takes, acc + alpha rel (the mass-proportional
    damping folded in); written into dq, v, rel, acc_eff (nv,)."""
    for i in range(acc.size):
        a = c_acc * acc[i] + c_old[i]
        dq[i] = base_dq[i] + hhb * a
        v[i] = base_v[i] + hg * a
        rel[i] = v[i] - v_r[i]
        acc_eff[i] = acc[i] + alpha * rel[i]


@compiled
def closure_gaps(phi):
    """The largest translation (m) and rotation (rad) error over the loop closures of errors ``phi`` (6n,): per
    closure the norms of its (translation, rotation) triples; NaN if one is."""
    translation = rotation = 0.0
    for i in range(0, phi.size, 6):
        t = math.sqrt(phi[i] * phi[i] + phi[i + 1] * phi[i + 1] + phi[i + 2] * phi[i + 2])
        r = math.sqrt(phi[i + 3] * phi[i + 3] + phi[i + 4] * phi[i + 4] + phi[i + 5] * phi[i + 5])
        if translation == translation and not t <= translation:  # a NaN kept, as numpy's max keeps it
            translation = t
        if rotation == rotation and not r <= rotation:
            rotation = r
    return translation, rotation


@compiled
def newton_end(acc, acc_n, a_n, af, am, base_dq, hhb, base_v, hg, a_ps, dq, v):
    """The flexible step's end from its converged accelerations ``acc`` (nv,) and the start's ``acc_n`` and
    pseudo-accelerations ``a_n``: the pseudo-acceleration a_ps = ((1 - af) acc + af acc_n - am a_n) / (1 - am), the
    configuration increment dq = base_dq + hhb a_ps (m, rad) and the velocity v = base_v + hg a_ps; written into
    a_ps, dq, v (nv,)."""
    for i in range(acc.size):
        a = ((1 - af) * acc[i] + af * acc_n[i] - am * a_n[i]) / (1 - am)
        a_ps[i] = a
        dq[i] = base_dq[i] + hhb * a
        v[i] = base_v[i] + hg * a


@compiled
def newton_residual(inertial, closures, external, q, spring_q, spring_v, rest, k, force, tangent, linear, rel, beta,
                    phi, rhs):
    """The flexible step's Newton residual into rhs (nv + 6n,): inertial (rnea's M acc_eff + h) + closures (B^T lambda)
    - external on every velocity, plus on the spring joints their forces and stiffness-proportional damping, k (x +
    beta rel) for linear springs (x = q - rest) or force + beta tangent rel; then the closure errors phi (6n,)."""
    nv = inertial.size
    for i in range(nv):
        rhs[i] = inertial[i] + closures[i] - external[i]
    for j in range(spring_q.size):
        sv = spring_v[j]
        if linear:
            rhs[sv] += k[j] * (q[spring_q[j]] - rest[j] + beta * rel[sv])
        else:
            rhs[sv] += force[j] + beta * tangent[j] * rel[sv]
    for i in range(phi.size):
        rhs[nv + i] = phi[i]


@compiled
def newton_update(dx, nv, scale, acc, lam):
    """The correction dx (nv + 6n,) applied: acc -= scale dx[:nv], lam -= dx[nv:]; returns |dx[:nv]|_inf (m, rad),
    NaN if a correction is."""
    size, finite = 0.0, True
    for i in range(nv):
        a = abs(dx[i])
        if a > size:
            size = a
        elif not a <= size:  # NaN
            finite = False
        acc[i] -= scale * dx[i]
    for i in range(lam.size):
        lam[i] -= dx[nv + i]
    return size if finite else math.nan
