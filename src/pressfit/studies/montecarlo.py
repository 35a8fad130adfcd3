r"""Monte Carlo tolerance study: how likely is a leg to leave its envelope, and which input drives it.

Each sample draws the case's ``[montecarlo.inputs]`` (SI) and solves the geometrically nonlinear
equilibrium (:func:`pressfit.mechanics.statics.solve_equilibrium`) at every pose and load of the case:

* ``base_point_error_m``, ``plate_point_error_m``: the real cardan centres B_i + e_B, d_i + e_d (world
  axes, per leg); the leg lines then miss P*, so the condensed model refuses them. The fast solver takes
  them as each solve's joint positions (one nominal model per chunk, the same equilibrium as a model built
  on the real geometry); the reference solver builds the sample's machine.
* ``actuator_length_offset_m``: held length minus commanded length, per leg. The drives are position-held
  at the lengths the controller computes from the **nominal** geometry (plus the case's ``[preload]``
  offsets on the nominal machine), so a joint position error also acts as a length offset
  l_nominal - l_real: the redundant leg turns both into a self-stress.
* ``load_tilt_rad``: every load force of the case turned by this angle off its direction, about an axis
  at a uniform random azimuth (magnitude and moments kept).
* ``cardan_clearance_m``: the axial play of each of the 2n cardans (n legs) (+-g along the leg, geometry "axial"
  whatever the machine's ``cardan_clearance_geometry``: one model serves every pose, and a box's effective
  gap changes with the pose; :mod:`pressfit.mechanics.clearance`, dead-zone springs in the Pinocchio model,
  the load applied in ``CLEARANCE_STEPS`` continuation steps).
* ``cardan_misalignment_rad``: per cardan (2n) and axis (x = +-a_i, y down, z inward, the leg reference
  frame), the components of the cardan's misalignment rotation vector (``LegLayout.base_cardan_tilt_rad``,
  ``plate_cardan_tilt_rad``). The rigid redundant machine then generally cannot assemble (Tsai's condition
  broken): the reference solver starts from the least-squares rigid assembly and closes the rest
  elastically, a self-stress (mostly leg torsion); the fast solver refuses such machines.

Per sample the worst value over poses, loads, legs and sections of every ``[envelope]`` load quantity
(:data:`pressfit.studies.limit_check.LIMITS`, same names and definitions), the internal force
|P N| (N, the actuator forces' orthogonal projection on the nominal preload space, equations 9-10: |v_p . N| on
the 4-UPU, 0 on a 3-leg machine) and the
largest relative residual are recorded. ``min_buckling_safety_factor`` is, as in ``pressfit check``, the
whole machine's linearised buckling load factor (:func:`pressfit.mechanics.buckling.machine_buckling`: the
sample's actuator offsets held, its load scaled), computed exactly at **every** pose and load of every
sample (:class:`BucklingBasis`); the per-leg Euler factor (leg Euler load / compression) is the extra
column ``min_leg_euler_factor``. A sample whose machine factor is below 1 is unstable (status
``UnstableEquilibriumError``, whatever its solve did); one below ``STABILITY_RECHECK_FACTOR`` (or with a
leg Euler factor below it) on the fast path gets the reference solve, whose stability check can refuse it.
A sample whose solve fails (unreachable pose, no convergence, unstable) gets NaN values and a non-"ok"
``status``; it counts as an exceedance of every limit (conservative) and is reported separately.

Exceedance probability: the fraction of samples beyond the limit with the **Wilson score** 95%
interval (it keeps its coverage near 0 and 1, where the normal approximation fails). Sensitivity: the
Spearman rank correlation (scipy) between each input and each output, ranked by its magnitude: random
sampling does not fit the structured designs that variance-based methods (SALib's Sobol) need, and rank
correlation is robust to monotone nonlinear responses. It does not see a response that is even in an
input (the self-stress grows with |v_p . offset| whatever its sign): read it with the histograms.
Quantiles are sample quantiles (``inverted_cdf``: an observed value, so an infinite buckling factor
stays infinite instead of becoming NaN).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import stats
from scipy.linalg import eigh, null_space

from pressfit import kinematics
from pressfit.description.cases import Case, Distribution
from pressfit.description.machine import Machine
from pressfit.errors import PressfitError, UnstableEquilibriumError
from pressfit.mechanics import buckling, statics
from pressfit.mechanics.clearance import Clearance
from pressfit.mechanics.fast_statics import FastEquilibriumSolver
from pressfit.mechanics.preload import ActuatorPreload, rest_length_offsets, self_stress_forces_n
from pressfit.studies.limit_check import LIMITS, equilibrium_quantities, section_quantities

OUTPUTS = ("max_tension_n", "max_compression_n", "max_shear_n", "max_bending_nm", "max_torsion_nm",
           "max_actuator_force_n", "max_plate_deflection_m", "max_plate_tilt_rad", "min_buckling_safety_factor")
EXTRA_OUTPUTS = ("internal_force_n", "residual", "min_leg_euler_factor")
STABILITY_RECHECK_FACTOR = 2.0  # fast path: a machine (or leg Euler) factor below 2 gets the reference solve
MAX_POSES = 64  # poses of a Monte Carlo case: the buckling basis keeps 11 (r, r) matrices per pose (~0.85 MB)
_DL = 1e-5  # m, step of the central difference of the Euler load against the leg length
CLEARANCE_STEPS = 8  # load continuation steps with cardan clearances (the dead zone needs a path)
_AXES = "xyz"


def input_shapes(legs: int) -> dict[str, list[str]]:
    """The column suffixes of every random input of a machine with ``legs`` legs (leg1..leg{legs})."""
    names = [f"leg{i}" for i in range(1, legs + 1)]
    return {"actuator_length_offset_m": names, "base_point_error_m": [f"{g}.{a}" for g in names for a in _AXES],
            "plate_point_error_m": [f"{g}.{a}" for g in names for a in _AXES], "load_tilt_rad": [""],
            "cardan_clearance_m": [f"{g}.{e}" for g in names for e in ("base", "plate")],
            "cardan_misalignment_rad": [f"{g}.{e}.{a}" for g in names for e in ("base", "plate") for a in _AXES]}


_REFERENCE_ONLY = {"cardan_clearance_m": "cardan clearances",  # inputs the fast solver does not model
                   "cardan_misalignment_rad": "cardan misalignments"}


@dataclass(frozen=True, kw_only=True)
class MonteCarloPlan:
    """Everything a worker needs (picklable): the nominal machine, the case's poses (m) and load
    wrenches (N, N m), the preload, the random inputs and the sampling plan."""

    name: str
    machine: Machine
    poses_m: np.ndarray  # (P, 3)
    wrenches: np.ndarray  # (W, 6)
    preload_a4: float | tuple[float, ...]  # N (force mode) or m (length mode); n - 3 amplitudes unless n = 4
    preload_mode: str
    inputs: tuple[tuple[str, Distribution], ...]
    samples: int
    seed: int
    chunk_size: int
    critical_n: np.ndarray  # (P, n) Euler loads of the nominal legs at the poses, N
    critical_slope_n_per_m: np.ndarray  # (P, n) their derivative with the leg length, N/m
    buckling: BucklingBasis  # the whole machine's linearised buckling problem per pose

    def critical_loads_n(self, lengths_m: np.ndarray) -> np.ndarray:
        """Euler loads (P, n), N, of legs of lengths (P, n), m, near the nominal ones: first order about them
        (relative error ~3 (dl / l)^2, below 1e-7 for joint errors under 0.1 mm at l >= 0.5 m; the exact
        stepped-column solve costs ~10 ms per leg)."""
        return self.critical_n + self.critical_slope_n_per_m * (lengths_m - self.nominal_lengths_m)

    @property
    def nominal_lengths_m(self) -> np.ndarray:
        return kinematics.inverse_kinematics(self.machine, self.poses_m).lengths_m

    @property
    def n_chunks(self) -> int:
        return -(-self.samples // self.chunk_size)

    def chunk_range(self, k: int) -> tuple[int, int]:
        """Sample indices [start, stop) of chunk k."""
        return k * self.chunk_size, min((k + 1) * self.chunk_size, self.samples)

    def input_columns(self) -> list[str]:
        shapes = input_shapes(len(self.machine.legs))
        return [f"{name}.{s}" if s else name for name, _ in self.inputs for s in shapes[name]]

    def output_columns(self) -> list[str]:
        return ["sample", "status", *self.input_columns(), *OUTPUTS, *EXTRA_OUTPUTS]

    def fingerprint(self) -> dict[str, object]:
        """What must match for a rerun to resume an earlier one (JSON-ready): the case content that defines
        the samples, the sampling plan and the pressfit version."""
        from pressfit import __version__

        return {"pressfit": __version__, "name": self.name, "samples": self.samples, "seed": self.seed,
                "chunk_size": self.chunk_size,
                "machine": self.machine.model_dump(exclude={"source"}), "poses_m": self.poses_m.tolist(),
                "wrenches": self.wrenches.tolist(), "preload": [self.preload_a4, self.preload_mode],
                "inputs": {n: d.model_dump() for n, d in self.inputs}}


@dataclass(frozen=True, kw_only=True)
class BucklingBasis:
    r"""The whole machine's linearised buckling problem (:func:`pressfit.mechanics.buckling.machine_buckling`)
    at each pose of a plan, split by its linearity: on the tangent space of the loop closures (Z orthonormal,
    J_c Z = 0, the nominal machine's reference state) ``elastic`` = Z^T K_e Z (P, r, r), ``per_offset`` the
    geometric stiffness Z^T K_g0 Z per metre of each actuator's rest-length offset (P, n, r, r) and
    ``per_wrench`` Z^T K_g Z per unit plate wrench component (P, 6, r, r) (per N, per N m). K_g0 and K_g
    are linear in the offsets and the wrench (the reference state is a linear solve; tested), so a sample's
    factor is one symmetric eigenproblem: the smallest lambda > 0 with
    (elastic + sum_i o_i per_offset_i + lambda sum_j w_j per_wrench_j) phi = 0. Joint position errors enter
    through their length offsets (l_nominal - l_real) on the nominal geometry (first order: the geometry
    change e / l ~ 1e-5 is dropped; tested against the perturbed machine)."""

    elastic: np.ndarray
    per_offset: np.ndarray
    per_wrench: np.ndarray

    @classmethod
    def of(cls, machine: Machine, poses_m: np.ndarray) -> BucklingBasis:
        """The basis on ``machine`` at ``poses_m`` (P, 3), m: 11 reference tangents per pose (~0.1-0.3 s)."""
        solver = statics.EquilibriumSolver(machine, pose_m=poses_m[0])
        el, off, wr = [], [], []
        for pose in poses_m:
            ref = statics.reference_tangent(solver, pose, np.zeros(6), None)
            z = null_space(ref.jacobian)
            sym = lambda a, z=z: 0.5 * (z.T @ a @ z + (z.T @ a @ z).T)
            el.append(sym(ref.elastic) + sym(ref.geometric))
            off.append([sym(statics.reference_tangent(solver, pose, np.zeros(6), e * _DL).geometric) / _DL
                        for e in np.eye(len(machine.legs))])
            wr.append([sym(statics.reference_tangent(solver, pose, e, None).geometric) for e in np.eye(6)])
        return cls(elastic=np.array(el), per_offset=np.array(off), per_wrench=np.array(wr))

    def load_factors(self, p: int, offsets_m: np.ndarray, wrenches: np.ndarray) -> np.ndarray:
        """Load factors (n,) at pose ``p`` for actuator offsets (n, legs), m, and plate wrenches (n, 6) (N, N m):
        inf when no positive factor exists (the load only stiffens), 0 when the offsets alone make the machine
        unstable (the stiffness is not positive definite before any load). One generalised symmetric eigenproblem
        for the smallest eigenvalue each (LAPACK sygvx, ~1 ms for r = 98)."""
        out = np.empty(len(offsets_m))
        for j, (o, w) in enumerate(zip(offsets_m, wrenches)):
            k = self.elastic[p] + np.tensordot(o, self.per_offset[p], 1)
            g = np.tensordot(w, self.per_wrench[p], 1)
            try:  # G phi = mu K phi <=> lambda = -1 / mu: the smallest lambda > 0 is the most negative mu
                mu = float(eigh(g, k, eigvals_only=True, subset_by_index=[0, 0])[0])
            except np.linalg.LinAlgError:  # K not positive definite
                out[j] = 0.0
                continue
            out[j] = -1.0 / mu if mu < -1.0 / buckling.NO_BUCKLING_BEYOND else math.inf  # beyond: round-off
        return out


def plan_from_case(case: Case, samples: int | None = None, seed: int | None = None,
                   chunk_size: int | None = None) -> MonteCarloPlan:
    """The study of a case with a ``[montecarlo]`` table (``samples``/``seed``/``chunk_size`` override it)."""
    mc = case.montecarlo
    if mc is None:
        raise PressfitError(f"{case.path}: a Monte Carlo study needs a [montecarlo] table with [montecarlo.inputs]")
    if case.solver.linear:
        raise PressfitError(f"{case.path}: the Monte Carlo study solves the nonlinear equilibrium; remove "
                            "[solver] linear = true")
    machine, poses = case.machine(), case.poses.array()
    inputs = tuple((k, d) for k in input_shapes(len(machine.legs)) if (d := getattr(mc.inputs, k)) is not None)
    n = samples if samples is not None else mc.samples
    if n < 1:
        raise PressfitError(f"the number of samples must be at least 1, got {n}")
    if len(poses) > MAX_POSES:
        raise PressfitError(f"{case.path}: key 'poses': a Monte Carlo study takes at most {MAX_POSES} poses, got "
                            f"{len(poses)} (each sample solves every pose)")
    bad = ~kinematics.is_reachable(machine, poses)
    if bad.any():
        h = poses[bad][0]
        raise PressfitError(f"{case.path}: key 'poses': pose {tuple(float(c) for c in h)} m is not reachable (every "
                            f"sample would fail): {kinematics.unreachable_reason(machine, h)}")
    a4 = ActuatorPreload.from_case(case.preload).a4
    self_stress_forces_n(machine, poses, a4)  # a preload the machine cannot take is refused here (PreloadError)
    lengths = kinematics.inverse_kinematics(machine, poses).lengths_m
    crit = lambda d: np.vectorize(lambda v: buckling.leg_critical_load_n(machine, v))(lengths + d)
    return MonteCarloPlan(name=case.name, machine=machine, poses_m=poses, wrenches=case.loads.wrenches(),
                          preload_a4=a4, preload_mode=case.preload.mode, inputs=inputs, samples=n,
                          seed=mc.seed if seed is None else seed, chunk_size=chunk_size or mc.chunk_size,
                          critical_n=crit(0.0), critical_slope_n_per_m=(crit(_DL) - crit(-_DL)) / (2 * _DL),
                          buckling=BucklingBasis.of(machine, poses))


def chunk_seed(plan: MonteCarloPlan, k: int) -> np.random.SeedSequence:
    """Chunk k's seed, ``SeedSequence(seed).spawn(n_chunks)[k]`` made alone (the k-th child of a spawn has
    ``spawn_key = (k,)``): the draws of a sample depend on its chunk only, never on the number of workers or
    the order in which chunks finish, and a study of 1e7 chunks needs no list of seeds."""
    return np.random.SeedSequence(plan.seed, spawn_key=(k,))


def chunk_seeds(plan: MonteCarloPlan) -> list[np.random.SeedSequence]:
    """Every chunk's seed (:func:`chunk_seed`), ``SeedSequence(seed).spawn(n_chunks)``."""
    return np.random.SeedSequence(plan.seed).spawn(plan.n_chunks)


def _draw(d: Distribution, rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    return d.draw(rng, shape)


def draw_inputs(plan: MonteCarloPlan, k: int, seed: np.random.SeedSequence) -> dict[str, np.ndarray]:
    """The random inputs of chunk k, (n, columns) per input name, plus the load azimuths (n,), rad."""
    rng = np.random.default_rng(seed)
    start, stop = plan.chunk_range(k)
    shapes = input_shapes(len(plan.machine.legs))
    out = {name: _draw(d, rng, (stop - start, len(shapes[name]))) for name, d in plan.inputs}
    out["load_azimuth_rad"] = rng.uniform(0.0, 2 * np.pi, stop - start)
    return out


def _tilted(wrenches: np.ndarray, tilt: float, azimuth: float) -> np.ndarray:
    """The wrenches with each force turned by ``tilt`` (rad) off its direction at ``azimuth`` (rad)."""
    out = wrenches.copy()
    for w in out:
        f = np.linalg.norm(w[:3])
        if f == 0:
            continue
        d = w[:3] / f
        t = np.cross(d, [1.0, 0, 0] if abs(d[0]) < 0.9 else [0, 0, 1.0])
        t /= np.linalg.norm(t)
        s = np.cross(d, t)
        w[:3] = f * (math.cos(tilt) * d + math.sin(tilt) * (math.cos(azimuth) * t + math.sin(azimuth) * s))
    return out


def _perturbed(machine: Machine, x: dict[str, np.ndarray]) -> Machine:
    """The sample's machine: joint position errors (m) of ``x`` added to the machine's (the joint positions of
    :func:`_sample_loads`), cardan misalignments (rad) applied."""
    base, plate, tilt = (x.get(k) for k in ("base_point_error_m", "plate_point_error_m", "cardan_misalignment_rad"))
    if base is None and plate is None and tilt is None:
        return machine
    legs = [leg.model_dump() for leg in machine.legs]
    for i, leg in enumerate(legs):
        for key, e in (("base_point_error_m", base), ("plate_point_error_m", plate)):
            if e is not None:
                leg[key] = (np.array(leg[key]) + e[3 * i:3 * i + 3]).tolist()
        if tilt is not None:
            leg["base_cardan_tilt_rad"], leg["plate_cardan_tilt_rad"] = tilt[6 * i:6 * i + 6].reshape(2, 3).tolist()
    return machine.with_overrides({"legs": legs}, source=f"{machine.source} [montecarlo joint errors]")


def _solver_for(machine: Machine, clearance: Clearance | None, pose_m: np.ndarray) -> statics.EquilibriumSolver:
    """The reference solver of a sample's machine (Pinocchio model built at a pose, retargeted by the solve
    to the others); the only path for cardan clearances and the stability re-check of the fast path."""
    return statics.EquilibriumSolver(machine, pose_m=pose_m,
                                     cardan_compliance=None if clearance is None else clearance.cardan_compliance())


def _solve(mm: statics.EquilibriumSolver, pose: np.ndarray, load: np.ndarray, offsets: np.ndarray,
           clearance: Clearance | None) -> statics.Equilibrium:
    if clearance is None:
        return statics.solve_equilibrium(mm, pose, load, preload_offsets_m=offsets)
    radius = max(0.5 * float(clearance.gaps_m.max()), 100 * clearance.smoothing_m)
    eq = None
    for f in np.linspace(0.0, 1.0, CLEARANCE_STEPS + 1):  # continuation: start each step from the last
        eq = statics.solve_equilibrium(mm, pose, f * load, preload_offsets_m=offsets, start=eq, max_iter=200,
                                       step_limit=lambda dv: min(1.0, radius / max(float(np.abs(dv).max()), 1e-300)))
    return eq  # type: ignore[return-value]


@dataclass(frozen=True, kw_only=True)
class _Nominal:
    """Per pose of the plan, on the nominal machine (n legs): leg lengths (P, n), m (the commanded lengths),
    preload rest-length offsets (P, n), m, and the orthogonal projectors on the preload space (P, n, n) (v_p v_p^T
    on the 4-UPU, zero on a 3-leg machine): the internal force is the norm of the actuator forces' projection."""

    lengths_m: np.ndarray
    preload_offsets_m: np.ndarray
    preload_projectors: np.ndarray


def _nominal(plan: MonteCarloPlan) -> _Nominal:
    m, poses = plan.machine, plan.poses_m
    lengths = kinematics.inverse_kinematics(m, poses).lengths_m
    pre = np.array([rest_length_offsets(m, h, plan.preload_a4, plan.preload_mode) for h in poses])
    basis = kinematics.preload_basis(m, poses)  # (P, n, n - 3)
    return _Nominal(lengths_m=lengths, preload_offsets_m=pre, preload_projectors=basis @ np.linalg.pinv(basis))


@dataclass(frozen=True, kw_only=True)
class _SampleLoads:
    """What one sample solves: its joint positions B_i (world) and d_i (plate frame), (n, 3) each, m (the
    nominal machine's plus the sample's joint position errors), wrenches (W, 6) (N, N m), actuator rest-length
    offsets per pose (P, n), m, its leg lengths (P, n), m, and their Euler loads (P, n), N (n legs)."""

    base_points_m: np.ndarray
    plate_offsets_m: np.ndarray
    wrenches: np.ndarray
    offsets_m: np.ndarray
    lengths_m: np.ndarray
    critical_n: np.ndarray


def _sample_loads(plan: MonteCarloPlan, nominal: _Nominal, x: dict[str, np.ndarray], azimuth: float) -> _SampleLoads:
    m = plan.machine
    base, plate = (getattr(m, a) + x[k].reshape(-1, 3) if k in x else getattr(m, a) for k, a in (
        ("base_point_error_m", "base_points_m"), ("plate_point_error_m", "plate_offsets_m")))
    lengths = nominal.lengths_m if base is m.base_points_m and plate is m.plate_offsets_m else \
        kinematics.inverse_kinematics(m, plan.poses_m, base_points_m=base, plate_offsets_m=plate).lengths_m
    offsets = nominal.lengths_m - lengths + x.get("actuator_length_offset_m", 0.0) + nominal.preload_offsets_m
    wrenches = _tilted(plan.wrenches, float(x["load_tilt_rad"][0]), azimuth) if "load_tilt_rad" in x else plan.wrenches
    return _SampleLoads(base_points_m=base, plate_offsets_m=plate, wrenches=wrenches, offsets_m=offsets,
                        lengths_m=lengths, critical_n=plan.critical_loads_n(lengths))


def _sample_row(q: dict[str, np.ndarray], internal_n: np.ndarray, residual: np.ndarray,
                machine_factor: float) -> dict[str, float]:
    """The worst of every output over one sample's m solves (arrays with m leading); the buckling key is the
    sample's whole-machine factor, the per-leg Euler factor goes to ``min_leg_euler_factor``."""
    row = {k: float(q[k].min() if LIMITS[k].sense == "min" else q[k].max()) for k in OUTPUTS}
    row["min_leg_euler_factor"] = row["min_buckling_safety_factor"]
    row["min_buckling_safety_factor"] = machine_factor
    return row | {"internal_force_n": float(np.abs(internal_n).max()), "residual": float(residual.max())}


def machine_factors(plan: MonteCarloPlan, setups: list[_SampleLoads]) -> np.ndarray:
    """Each sample's whole-machine linearised buckling factor (n,): the smallest over every pose and load
    (one batched eigenproblem per pose over the samples x loads)."""
    w = len(plan.wrenches)
    out = np.full(len(setups), math.inf)
    for p in range(len(plan.poses_m)):
        offsets = np.repeat(np.array([s.offsets_m[p] for s in setups]), w, axis=0)
        f = plan.buckling.load_factors(p, offsets, np.concatenate([s.wrenches for s in setups]))
        out = np.minimum(out, f.reshape(len(setups), w).min(1))
    return out


def machine_factor(plan: MonteCarloPlan, s: _SampleLoads) -> float:
    """One sample's whole-machine linearised buckling factor (:func:`machine_factors`)."""
    return float(machine_factors(plan, [s])[0])


def _unstable(factor: float) -> UnstableEquilibriumError:
    return UnstableEquilibriumError(f"the whole machine buckles below the full load (linearised buckling factor "
                                    f"{factor:.4g} < 1)")


def evaluate_sample(plan: MonteCarloPlan, x: dict[str, np.ndarray], azimuth: float,
                    model: statics.EquilibriumSolver | None = None) -> dict[str, float]:
    """Worst outputs over the case's poses and loads for one sample's inputs ``x`` (name -> values), by the
    reference solver (stability checked with every solve). ``model``: the nominal machine's solver, reused
    when the sample changes neither geometry nor joints."""
    nominal = _nominal(plan)
    s = _sample_loads(plan, nominal, x, azimuth)
    factor = machine_factor(plan, s)
    if factor < 1:
        raise _unstable(factor)
    machine = _perturbed(plan.machine, x)
    g = x.get("cardan_clearance_m")
    clearance = None if g is None else Clearance.per_joint(machine, g.tolist(), geometry="axial")
    solver = model if machine is plan.machine and clearance is None and model is not None else \
        _solver_for(machine, clearance, plan.poses_m[0])
    eqs = [(p, _solve(solver, pose, load, s.offsets_m[p], clearance)) for p, pose in enumerate(plan.poses_m)
           for load in s.wrenches]
    qs = [equilibrium_quantities(eq, s.critical_n[p]) for p, eq in eqs]
    return _sample_row({k: np.stack([q[k] for q in qs]) for k in OUTPUTS},
                       np.array([np.linalg.norm(nominal.preload_projectors[p] @ eq.actuator_forces_n)
                                 for p, eq in eqs]),
                       np.array([eq.residuals.worst() for _, eq in eqs]), factor)


def solver_path(plan: MonteCarloPlan) -> str:
    """Which solver the plan's samples take: the reference solver with cardan clearances (dead-zone springs,
    which the fast solver refuses) or cardan misalignments (a model per sample, the solve started from the
    least-squares rigid assembly: the fast solver's closed-form reference needs parallel cardan axes); else
    the batched fast solver, one model per chunk (joint position errors as each solve's joint positions)."""
    names = {n for n, _ in plan.inputs}
    if names & _REFERENCE_ONLY.keys():
        why = " and ".join(label for n, label in _REFERENCE_ONLY.items() if n in names)
        return f"reference solver ({why}), one model per sample, stability checked with every solve"
    joints = " (joint position errors as per-sample joint positions)" if names & {
        "base_point_error_m", "plate_point_error_m"} else ""
    return (f"fast batched solver, one model per chunk{joints}; samples with a whole-machine buckling factor (or a "
            f"leg's Euler factor) below {STABILITY_RECHECK_FACTOR:g} re-solved by the reference solver "
            "(stability check)")


def _fast_rows(plan: MonteCarloPlan, nominal: _Nominal, setups: list[_SampleLoads],
               solver: FastEquilibriumSolver) -> list[dict[str, float] | PressfitError]:
    """The samples of ``setups`` (on ``solver``'s model, each with its joint positions) in one batched solve over
    samples x poses x loads; a failing batch is split to find the failing samples. Checks the small-strain range
    per solve."""
    n, p, w, legs = len(setups), len(plan.poses_m), len(plan.wrenches), len(plan.machine.legs)
    per_solve = lambda a: np.stack(
        [np.broadcast_to(a(s)[:, None], (p, w) + a(s).shape[1:]) for s in setups])
    layout = lambda a: np.repeat(np.stack([a(s) for s in setups]), p * w, axis=0)
    try:
        be = solver.solve_batch(np.broadcast_to(plan.poses_m[None, :, None], (n, p, w, 3)).reshape(-1, 3),
                                np.stack([np.broadcast_to(s.wrenches, (p, w, 6)) for s in setups]).reshape(-1, 6),
                                preload_offsets_m=per_solve(lambda s: s.offsets_m).reshape(-1, legs),
                                base_points_m=layout(lambda s: s.base_points_m),
                                plate_offsets_m=layout(lambda s: s.plate_offsets_m))
    except PressfitError as exc:
        return [exc] if n == 1 else [r for s in setups for r in _fast_rows(plan, nominal, [s], solver)]
    crit, lengths = (per_solve(lambda s: s.critical_n).reshape(-1, legs),
                     per_solve(lambda s: s.lengths_m).reshape(-1, legs))
    q = section_quantities(be.actuator_forces_n, be.sections, be.plate_displacement_m, be.plate_rotation_rad, crit)
    projectors = np.broadcast_to(nominal.preload_projectors[None, :, None], (n, p, w, legs, legs))
    internal = np.linalg.norm(np.einsum("kij,kj->ki", projectors.reshape(-1, legs, legs), be.actuator_forces_n), axis=1)
    res = be.residuals.copy()
    res[:, 4] /= be.length_scale_m
    strain = np.abs(be.actuator_forces_n) * plan.machine.axial_compliance_m_per_n(lengths) / lengths
    m = p * w
    factors = machine_factors(plan, setups)
    rows: list[dict[str, float] | PressfitError] = []
    for j in range(n):
        sl = slice(j * m, (j + 1) * m)
        if strain[sl].max() > statics.MAX_AXIAL_STRAIN:
            solve, leg = np.unravel_index(np.argmax(strain[sl]), strain[sl].shape)
            rows.append(UnstableEquilibriumError(f"a leg strains beyond {statics.MAX_AXIAL_STRAIN:g}", leg=int(leg) + 1,
                                                 pose_m=be.pose_m[sl][solve], load=be.load[sl][solve]))
            continue
        rows.append(_sample_row({k: v[sl] for k, v in q.items()}, internal[sl], res[sl].max(1), float(factors[j])))
    return rows


def _evaluate_fast(plan: MonteCarloPlan, x: list[dict[str, np.ndarray]], azimuths: np.ndarray
                   ) -> list[dict[str, float] | PressfitError]:
    """The fast path (:func:`solver_path`): batched solves, then the stability re-check of the samples that
    come within STABILITY_RECHECK_FACTOR of a leg's Euler load by the reference solver."""
    nominal = _nominal(plan)
    setups = [_sample_loads(plan, nominal, xj, float(a)) for xj, a in zip(x, azimuths)]
    rows = _fast_rows(plan, nominal, setups, FastEquilibriumSolver(plan.machine, pose_m=plan.poses_m[0]))
    for j, r in enumerate(rows):
        if not isinstance(r, dict):  # a failed fast solve: unstable if the machine buckles below the load
            factor = machine_factor(plan, setups[j])
            rows[j] = _unstable(factor) if factor < 1 else r
        elif r["min_buckling_safety_factor"] < 1:
            rows[j] = _unstable(r["min_buckling_safety_factor"])
        elif min(r["min_buckling_safety_factor"], r["min_leg_euler_factor"]) < STABILITY_RECHECK_FACTOR:
            try:
                rows[j] = evaluate_sample(plan, x[j], float(azimuths[j]))
            except PressfitError as exc:
                rows[j] = exc
    return rows


def evaluate_chunk(plan: MonteCarloPlan, k: int, seed: np.random.SeedSequence) -> dict[str, np.ndarray]:
    """Chunk k of the study (the task a worker runs): inputs, outputs and status per sample, as columns.
    The solver path is :func:`solver_path`; the columns do not depend on which worker runs the chunk."""
    x = draw_inputs(plan, k, seed)
    start, stop = plan.chunk_range(k)
    samples = [{name: v[j] for name, v in x.items()} for j in range(stop - start)]
    azimuths = x["load_azimuth_rad"]
    if any(name in x for name in _REFERENCE_ONLY):
        rows: list[dict[str, float] | PressfitError] = []
        for xj, a in zip(samples, azimuths):
            try:
                rows.append(evaluate_sample(plan, xj, float(a)))
            except PressfitError as exc:
                rows.append(exc)
    else:
        rows = _evaluate_fast(plan, samples, azimuths)
    failed = dict.fromkeys(OUTPUTS + EXTRA_OUTPUTS, math.nan)
    status = ["ok" if isinstance(r, dict) else type(r).__name__ for r in rows]
    cols: dict[str, np.ndarray] = {"sample": np.arange(start, stop, dtype=np.int64), "status": np.array(status)}
    names = plan.input_columns()
    cols.update(zip(names, np.concatenate([x[name] for name, _ in plan.inputs], axis=1).T))
    cols.update({key: np.array([(r if isinstance(r, dict) else failed)[key] for r in rows])
                 for key in OUTPUTS + EXTRA_OUTPUTS})
    return cols


# --- summary ---------------------------------------------------------------------------------------------
QUANTILES = (0.01, 0.05, 0.5, 0.95, 0.99)
MIN_SENSITIVITY_SAMPLES = 3  # Spearman's rho of 2 points is +-1 whatever the data


def wilson_interval(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion k / n (default 95%, z = Phi^-1(0.975))."""
    if n <= 0:
        return 0.0, 1.0
    p = k / n
    centre, half = (p + z * z / (2 * n)), z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return max(0.0, (centre - half) / (1 + z * z / n)), min(1.0, (centre + half) / (1 + z * z / n))


@dataclass(frozen=True, kw_only=True)
class Exceedance:
    """P(the worst value of a sample breaks the ``[envelope]`` limit), failed samples counted as breaking."""

    key: str
    limit: float
    count: int
    samples: int
    probability: float
    ci95: tuple[float, float]  # Wilson score interval


@dataclass(frozen=True, kw_only=True)
class MonteCarloSummary:
    samples: int
    failed: dict[str, int]  # status -> count of samples whose solve failed
    quantiles: dict[str, dict[str, float]]  # output -> {"q0.05": value, ...} over the samples that solved
    exceedance: list[Exceedance]
    sensitivity: dict[str, list[tuple[str, float]]]  # output -> [(input, Spearman rho)], by |rho|
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready; non-finite values (no compression: an infinite buckling factor) become None."""
        return _finite(
            {
                "samples": self.samples,
                "failed": self.failed,
                "quantiles": self.quantiles,
                "exceedance": [e.__dict__ for e in self.exceedance],
                "sensitivity": {
                    k: [{"input": i, "spearman_rho": r} for i, r in v] for k, v in self.sensitivity.items()
                },
                "notes": self.notes,
            }
        )


def _finite(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return None if isinstance(obj, float) and not math.isfinite(obj) else obj


def _spearman(x: np.ndarray, y: np.ndarray) -> float:
    if np.unique(x).size < 2 or np.unique(y).size < 2:  # a constant carries no ranking
        return 0.0
    return float(stats.spearmanr(x, y).statistic)


def summarize(plan: MonteCarloPlan, columns: dict[str, np.ndarray], envelope: dict[str, float]) -> MonteCarloSummary:
    """Quantiles, exceedance probabilities of the ``envelope`` limits (key -> limit, SI) with Wilson 95%
    intervals, and the Spearman sensitivity ranking, from the per-sample columns of the whole study."""
    n = len(columns["sample"])
    ok = columns["status"] == "ok"
    failed = {str(s): int(c) for s, c in zip(*np.unique(columns["status"][~ok], return_counts=True))}
    outputs = [*OUTPUTS, *EXTRA_OUTPUTS]
    quantiles = {
        k: {f"q{q:g}": float(np.quantile(columns[k][ok], q, method="inverted_cdf")) for q in QUANTILES}
        if ok.any()
        else {}
        for k in outputs
    }
    exceed, notes = [], [f"solver: {solver_path(plan)}"]
    for key, limit in envelope.items():
        if key not in OUTPUTS:
            notes.append(f"{key}: geometric limit, not sampled (check it with pressfit check)")
            continue
        v = columns[key]
        bad = ~ok | ((v > limit) if LIMITS[key].sense == "max" else (v < limit))
        count = int(bad.sum())
        exceed.append(Exceedance(key=key, limit=float(limit), count=count, samples=n, probability=count / n,
                                 ci95=wilson_interval(count, n)))
    names = plan.input_columns()
    sens = {}
    if ok.sum() < MIN_SENSITIVITY_SAMPLES:
        notes.append(f"sensitivity: undefined with {int(ok.sum())} solved sample(s) (a rank correlation needs at "
                     f"least {MIN_SENSITIVITY_SAMPLES}); none computed")
    else:
        for key in (k for k in outputs if k != "residual"):
            rho = [(name, _spearman(columns[name][ok], columns[key][ok])) for name in names]
            sens[key] = sorted(rho, key=lambda t: -abs(t[1]))
    return MonteCarloSummary(samples=n, failed=failed, quantiles=quantiles, exceedance=exceed, sensitivity=sens,
                             notes=notes)
