"""Leg interference: Coal shapes in a Pinocchio ``GeometryModel``, signed distances per body pair (m).

Bodies (world frame of docs/conventions.md, y up; every length in m):

- ``leg{i}.cylinder``: a capsule of radius ``collision.cylinder_radius_m`` on the segment from the base
  cardan B_i to B_i + L_cyl e_i (L_cyl = ``cylinder.length_m``, e_i the leg's unit vector).
- ``leg{i}.stem``: the exposed rod from the cylinder end to the plate cardan C_i = h + d_i, radius
  ``collision.stem_radius_m``. Its length l_i - L_cyl changes with the pose but a Coal shape is rigid, so
  the stem is the union of two rigid capsules: a *stub* fixed to the cylinder over [L_cyl, S] along the
  leg, S = min(l_min, max(L_cyl, l_max - l_min)), and the sliding *rod* over the last l_min of the leg,
  [l_i - l_min, l_i]. Their union is the exposed stem (exactly, when l_max <= 2 l_min as in the default
  machine) plus a part hidden inside the cylinder capsule (stem radius <= cylinder radius). The hidden part
  is never closer to a body than the cylinder is, so the minimum over a leg's bodies (and over each pair
  kind) is exact, while a single stem pair may read low where its cylinder is closer still. The base is
  the exception (the cylinder-base pair is excluded): the stem-base pair uses the stub alone, the
  stem's lowest part (a leg rises from its base cardan, so the distance to the base grows along it).
- ``plate``: a box 2r x t x 2r centred on h: the plate cardans lie on its mid-plane, on its side faces.
- ``base``: a box 2e x t x 2e whose top face is the plane y = 0 (the base cardans lie on it); e is
  ``collision.base_half_extent_m`` (default p).
- extra bodies (``collision.extra_bodies``): the convex hull of a mesh file (trimesh loads STL/OBJ/...;
  split a non-convex part into convex pieces) or a box, in the world or on the plate.

Capsules by default (``collision.leg_shape = "capsule"``): a capsule contains its cylinder (conservative
by at most one radius beyond each end), Coal computes capsule-capsule distances in closed form (no GJK
tolerance), the distance is smooth in the pose, and "segment distance minus radii" is an independent
check (tests). ``leg_shape = "cylinder"`` uses flat-ended cylinders (GJK, tolerance 1e-6 m) where the
end caps matter: the leg-plate clearance at the shortest legs is about 10 mm with capsules and 40 mm
with cylinders for the default machine.

Pairs (named ``'a|b'``): leg-leg (all bodies of different legs), leg-plate (cylinders), leg-base (stems)
and leg-extra (every leg body). Excluded because they touch by design: a leg's cylinder and stem, a
leg's cylinder and the base (its base cardan), a leg's stem and the plate (its plate cardan). The lists
are explicit (:attr:`InterferenceModel.pairs`, ``excluded``) and overridable (``include_pairs`` /
``exclude_pairs`` in the machine's ``[collision]`` table or as arguments).

Kinematics: the shapes are attached to the joints of a Pinocchio model and placed by forward kinematics
of its rigid configuration. That model is ``pressfit.model.build_model`` when available (``rig="model"``),
else :class:`ClosedFormRig`, a small rigid tree (per leg: cardan RX, RY, actuator PZ; plate translation)
whose configuration comes in closed form from :mod:`pressfit.kinematics`, vectorised over poses.
``pin.computeDistances`` evaluates every pair in C++; Python only gathers the results.
"""

from __future__ import annotations

import operator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from pressfit import kinematics
from pressfit.description.machine import ExtraBody, Machine
from pressfit.errors import InterferenceError
from pressfit.kinematics import reference_pose_m
from pressfit.kinematics.workspace import square_height_range, workspace_box, workspace_square
from pressfit.mechanics import data_pool
from pressfit.spatial import cross

PART_NAMES = ("cylinder", "stem")
KIND_ORDER = ("leg", "plate", "base", "extra")
_MIN_DISTANCE = operator.attrgetter("min_distance")
_CHUNK = 1024  # poses per block of the sweep
RIGS = ("auto", "closed-form", "model")  # make_rig's names


class Rig(Protocol):
    """A Pinocchio model whose joints carry the leg parts and the plate
    (:class:`pressfit.mechanics.model.MachineModel` satisfies it)."""

    model: pin.Model
    leg_joint_ids: list[dict[str, int]]
    plate_joint_id: int

    def configuration_at(self, pose_m: np.ndarray) -> np.ndarray: ...


# --- the closed-form rig --------------------------------------------------------------------------
class ClosedFormRig:
    """Rigid kinematic tree: per leg RX (about a_i) and RY at B_i (the base cardan, carrying the
    cylinder), PZ along the leg (the actuator, q = l_i, carrying the stem); the plate on a translation
    joint (q = h). Joint frames: at B_i the axes (a_i, w_i x a_i, w_i) with w_i inward horizontal; after
    the cardan they are the docs/conventions.md leg frame. Configurations in closed form, vectorised."""

    def __init__(self, machine: Machine) -> None:
        self.machine = machine
        self.model = pin.Model()
        self.leg_joint_ids: list[dict[str, int]] = []
        a, w = machine.cardan_axes, machine.inward_directions
        self._a, self._aw, self._w = a, cross(a, w), w
        for i in range(len(machine.legs)):
            frame = np.column_stack([a[i], cross(w[i], a[i]), w[i]])
            j1 = self.model.addJoint(0, pin.JointModelRX(), pin.SE3(frame, machine.base_points_m[i]),
                                     f"leg{i + 1}_cardan_a")
            j2 = self.model.addJoint(j1, pin.JointModelRY(), pin.SE3.Identity(), f"leg{i + 1}_cardan_b")
            j3 = self.model.addJoint(j2, pin.JointModelPZ(), pin.SE3.Identity(), f"leg{i + 1}_actuator")
            self.leg_joint_ids.append({"base_cardan": j1, "cylinder": j2, "actuator": j3, "stem": j3,
                                       "plate_cardan": j3})
        self.plate_joint_id = self.model.addJoint(0, pin.JointModelTranslation(), pin.SE3.Identity(), "plate")
        self._idx = np.array([[self.model.joints[self.leg_joint_ids[i][k]].idx_q
                               for k in ("base_cardan", "cylinder", "actuator")] for i in range(len(machine.legs))])
        self._plate_idx = self.model.joints[self.plate_joint_id].idx_q

    def configurations(self, poses_m: np.ndarray) -> np.ndarray:
        """Rigid configurations (n, nq) for poses (n, 3) in m: cardan angles (rad), leg lengths (m), h (m)."""
        h = np.asarray(poses_m, dtype=float).reshape(-1, 3)
        ik = kinematics.inverse_kinematics(self.machine, h)
        e = ik.unit_vectors
        q = np.empty((len(h), self.model.nq))
        q[:, self._idx[:, 0]] = np.arctan2(np.einsum("nij,ij->ni", e, self._aw), np.einsum("nij,ij->ni", e, self._w))
        q[:, self._idx[:, 1]] = np.arcsin(np.clip(np.einsum("nij,ij->ni", e, self._a), -1.0, 1.0))
        q[:, self._idx[:, 2]] = ik.lengths_m
        q[:, self._plate_idx:self._plate_idx + 3] = h
        return q

    def configuration_at(self, pose_m: np.ndarray) -> np.ndarray:
        return self.configurations(np.asarray(pose_m, dtype=float).reshape(1, 3))[0]


def make_rig(machine: Machine, rig: str = "auto") -> Rig:
    """'closed-form' (:class:`ClosedFormRig`), 'model' (:func:`pressfit.mechanics.model.build_model`) or 'auto' (the
    latter when importable, else the former)."""
    if rig not in RIGS:
        raise InterferenceError(f"rig must be 'auto', 'closed-form' or 'model' (got {rig!r})", key="rig", value=rig,
                                allowed=RIGS)
    if rig != "closed-form":
        try:
            from pressfit.mechanics.model import build_model
        except ImportError:
            if rig == "model":
                raise InterferenceError("pressfit.mechanics.model is not available", key="rig", value=rig,
                                        allowed=("closed-form",)) from None
        else:
            return build_model(machine, reference_pose_m(machine))
    return ClosedFormRig(machine)


# --- shapes ---------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class Shape:
    """One Coal shape of a body, its carrying joint ('cylinder', 'stem', 'plate', 'world') and its
    world placement as a function of the pose (closed form; used once, to attach it to the joint)."""

    body: str
    name: str
    geometry: coal.CollisionGeometry
    carrier: tuple[str, int]  # ('cylinder'|'stem', leg index 0..n-1) or ('plate'|'world', -1)
    local: pin.SE3 = field(default_factory=pin.SE3.Identity)  # in the leg frame / plate / world frame


def _source_dir(machine: Machine) -> Path:
    src = Path(machine.source.split(" [")[0])
    return src.parent if src.is_file() else Path.cwd()


def load_mesh_convex(path: Path | str, scale: float = 1.0) -> coal.ConvexBase:
    """The convex hull (Coal, qhull) of a mesh file read by trimesh, coordinates times ``scale`` (m)."""
    import trimesh

    try:
        mesh = trimesh.load(str(path), force="mesh")
        vertices = np.ascontiguousarray(mesh.vertices, dtype=float) * scale
        faces = np.ascontiguousarray(mesh.faces, dtype=np.int64)
        if len(faces) == 0:
            raise ValueError("no triangles")
    except Exception as exc:  # trimesh raises many types for bad files
        raise InterferenceError(f"cannot load mesh {path}: {exc}", key="mesh", value=str(path)) from None
    bvh = coal.BVHModelOBBRSS()
    bvh.beginModel(len(faces), len(vertices))
    bvh.addVertices(vertices)
    bvh.addTriangles(faces)
    bvh.endModel()
    bvh.buildConvexHull(True, "Qt")
    return bvh.convex


def _extra_shape(machine: Machine, body: ExtraBody) -> Shape:
    if body.box_size_m is not None:
        geom = coal.Box(*body.box_size_m)
    else:
        path = Path(body.mesh_path)  # type: ignore[arg-type]
        geom = load_mesh_convex(path if path.is_absolute() else _source_dir(machine) / path, body.mesh_scale)
    local = pin.SE3(pin.rpy.rpyToMatrix(np.asarray(body.rotation_rpy_rad)), np.asarray(body.translation_m))
    return Shape(body=body.name, name=body.name, geometry=geom, carrier=(body.frame, -1), local=local)


def machine_shapes(machine: Machine) -> tuple[list[Shape], list[str]]:
    """Every shape of the machine (module docstring) and notes on approximations."""
    c, lim = machine.collision, machine.limits
    lc, lmin, lmax = machine.cylinder.length_m, lim.leg_length_min_m, lim.leg_length_max_m
    stub_end = min(lmin, max(lc, lmax - lmin))
    notes = []
    if lmax > 2 * lmin:
        notes.append(f"the stem capsules miss [{lmin:.4g}, {lmax - lmin:.4g}] m along legs longer than "
                     f"{2 * lmin:.4g} m (l_max > 2 l_min)")
    solid = coal.Capsule if c.leg_shape == "capsule" else coal.Cylinder  # both (radius, length)
    shapes = []
    along = lambda s: pin.SE3(np.eye(3), np.array([0.0, 0.0, s]))
    for i in range(len(machine.legs)):
        leg = f"leg{i + 1}"
        shapes.append(Shape(body=f"{leg}.cylinder", name=f"{leg}.cylinder",
                            geometry=solid(c.cylinder_radius_m, lc), carrier=("cylinder", i), local=along(lc / 2)))
        stub = solid if stub_end > lc else coal.Capsule  # a zero-length stub: a sphere
        shapes.append(Shape(body=f"{leg}.stem", name=f"{leg}.stem.stub",
                            geometry=stub(c.stem_radius_m, stub_end - lc), carrier=("cylinder", i),
                            local=along((lc + stub_end) / 2)))
        # the rod: placed from the plate cardan backwards (the 'stem' frame is the leg frame at C_i)
        shapes.append(Shape(body=f"{leg}.stem", name=f"{leg}.stem.rod", geometry=solid(c.stem_radius_m, lmin),
                            carrier=("stem", i), local=along(-lmin / 2)))
    r, e = machine.geometry.plate_half_side_m, c.base_half_extent_m or machine.geometry.base_half_side_m
    shapes.append(Shape(body="plate", name="plate", geometry=coal.Box(2 * r, c.plate_thickness_m, 2 * r),
                        carrier=("plate", -1)))
    shapes.append(Shape(body="base", name="base", geometry=coal.Box(2 * e, c.base_thickness_m, 2 * e),
                        carrier=("world", -1), local=pin.SE3(np.eye(3), np.array([0.0, -c.base_thickness_m / 2, 0.0]))))
    shapes += [_extra_shape(machine, b) for b in c.extra_bodies]
    return shapes, notes


def carrier_placements(machine: Machine, pose_m: np.ndarray) -> dict[tuple[str, int], pin.SE3]:
    """World placements of the carrier frames at a pose (closed form): leg frame at B_i ('cylinder'),
    leg frame at C_i ('stem'), translation h ('plate'), identity ('world')."""
    h = np.asarray(pose_m, dtype=float).reshape(3)
    frames = kinematics.leg_frames(machine, h)
    out = {("world", -1): pin.SE3.Identity(), ("plate", -1): pin.SE3(np.eye(3), h)}
    for i in range(len(machine.legs)):
        out[("cylinder", i)] = pin.SE3(frames[i], machine.base_points_m[i])
        out[("stem", i)] = pin.SE3(frames[i], h + machine.plate_offsets_m[i])
    return out


# --- pairs ----------------------------------------------------------------------------------------
def _kind(body: str) -> str:
    return "leg" if body.startswith("leg") else body if body in ("plate", "base") else "extra"


def pair_kind(pair: str) -> str:
    """'leg-leg', 'leg-plate', 'leg-base', 'leg-extra', or e.g. 'plate-extra' for an included pair."""
    a, b = sorted((_kind(x) for x in pair.split("|")), key=KIND_ORDER.index)
    return f"{a}-{b}"


def default_pairs(extras: list[str], n_legs: int) -> tuple[list[str], list[str]]:
    """(checked pairs, pairs excluded because they touch by design) as 'a|b' names, legs leg1..leg{n_legs}."""
    legs = [[f"leg{i + 1}.{p}" for p in PART_NAMES] for i in range(n_legs)]
    pairs = [f"{a}|{b}" for i in range(n_legs) for j in range(i + 1, n_legs) for a in legs[i] for b in legs[j]]
    pairs += [f"leg{i + 1}.cylinder|plate" for i in range(n_legs)] + [f"leg{i + 1}.stem|base" for i in range(n_legs)]
    pairs += [f"{a}|{x}" for x in extras for leg in legs for a in leg]
    excluded = [f"leg{i + 1}.{a}|{b}" for i in range(n_legs)
                for a, b in (("cylinder", f"leg{i + 1}.stem"), ("cylinder", "base"), ("stem", "plate"))]
    return pairs, excluded


def _canonical(pair: str, bodies: list[str]) -> str:
    parts = [p.strip() for p in pair.split("|")]
    if len(parts) != 2 or parts[0] == parts[1] or any(p not in bodies for p in parts):
        raise InterferenceError(f"pair {pair!r}: expected 'a|b' with two different bodies among {bodies}",
                                key="pair", value=pair, allowed=tuple(bodies))
    return "|".join(sorted(parts, key=bodies.index))


# --- the model ------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, kw_only=True)
class InterferenceModel:
    """Coal shapes attached to a rig's joints, the checked body pairs and their geometry pairs."""

    machine: Machine
    rig: Rig
    geometry_model: pin.GeometryModel
    pairs: tuple[str, ...]  # checked body pairs 'a|b'
    kinds: tuple[str, ...]  # pair_kind of each
    excluded: tuple[str, ...]  # default pairs not checked (by design or by override)
    group_starts: np.ndarray  # first geometry collision pair of each body pair (they are grouped)
    notes: tuple[str, ...]
    kinematics: str  # which rig places the shapes

    batch: Any = None  # vectorised configurations: the rig's own, or a verified affine fit, or None

    def configurations(self, poses_m: np.ndarray) -> np.ndarray:
        """Rigid configurations (n, nq) of the rig for reachable poses (n, 3), m."""
        h = np.asarray(poses_m, dtype=float).reshape(-1, 3)
        if self.batch is not None:
            return self.batch(h)
        return np.array([self.rig.configuration_at(p) for p in h])


class AffineConfigurations:
    """q(h) = F(h) W with features F = (1, alpha_i, beta_i, l_i, h) of equation 1, W fitted by least
    squares on reachable probe poses of a rig's ``configuration_at`` and verified to 1e-12 on others.
    Rigid configurations built from equation 1 are affine in these (``pressfit.model``'s are); a rig
    for which the check fails keeps its per-pose ``configuration_at``."""

    def __init__(self, machine: Machine, rig: Rig, probes: int = 48, seed: int = 0) -> None:
        self.machine = machine
        ws, y_ref = machine.workspace, reference_pose_m(machine)[1]
        rng = np.random.default_rng(seed)
        h = np.column_stack([rng.uniform(-ws.x_half_width_m, ws.x_half_width_m, 4 * probes),
                             y_ref + rng.uniform(-0.15, 0.1, 4 * probes) * y_ref,
                             rng.uniform(-ws.z_half_width_m, ws.z_half_width_m, 4 * probes)])
        h = h[kinematics.is_reachable(machine, h)][:probes]
        if len(h) < probes:
            raise InterferenceError("too few reachable probe poses to vectorise the rig's configurations",
                                    key="probe_poses", value=len(h))
        q = np.array([rig.configuration_at(p) for p in h])
        fit, check = slice(0, probes // 2), slice(probes // 2, probes)
        self.weights = np.linalg.lstsq(self.features(h[fit]), q[fit], rcond=None)[0]
        self.error = float(np.abs(self(h[check]) - q[check]).max())

    def features(self, h: np.ndarray) -> np.ndarray:
        ik = kinematics.inverse_kinematics(self.machine, h)
        return np.column_stack([np.ones(len(h)), ik.alpha_rad, ik.beta_rad, ik.lengths_m, h])

    def __call__(self, h: np.ndarray) -> np.ndarray:
        return self.features(h) @ self.weights


def build_interference(machine: Machine, rig: str | Rig = "auto", include: list[str] | tuple[str, ...] = (),
                       exclude: list[str] | tuple[str, ...] = ()) -> InterferenceModel:
    """Shapes, pairs and a ``pin.GeometryModel`` attached to ``rig`` (a :class:`Rig` or a name for
    :func:`make_rig`). ``include``/``exclude`` add to the machine's ``include_pairs``/``exclude_pairs``."""
    rig_obj = make_rig(machine, rig) if isinstance(rig, str) else rig
    shapes, notes = machine_shapes(machine)
    bodies = list(dict.fromkeys(s.body for s in shapes))
    extras = [b.name for b in machine.collision.extra_bodies]
    clash = [x for x in extras if x in ("plate", "base") or x.startswith("leg")]
    if clash:
        raise InterferenceError(f"extra body names {clash} clash with built-in bodies (plate, base, leg*)",
                                key="extra_bodies", value=tuple(clash))
    pairs, excluded = default_pairs(extras, len(machine.legs))
    drop = {_canonical(p, bodies) for p in [*machine.collision.exclude_pairs, *exclude]}
    add = [_canonical(p, bodies) for p in [*machine.collision.include_pairs, *include]]
    excluded = [p for p in excluded if p not in add] + [p for p in pairs if p in drop]
    pairs = [p for p in dict.fromkeys(pairs + add) if p not in drop]

    # attach: joint-relative placement = oMi(ref)^-1 * oMg(ref), so any rig convention works
    h_ref = reference_pose_m(machine)
    world = carrier_placements(machine, h_ref)
    joint = {("world", -1): 0, ("plate", -1): rig_obj.plate_joint_id}
    for i, ids in enumerate(rig_obj.leg_joint_ids):
        joint[("cylinder", i)], joint[("stem", i)] = ids["cylinder"], ids["stem"]
    with data_pool.borrowed(rig_obj.model) as data:
        pin.forwardKinematics(rig_obj.model, data, rig_obj.configuration_at(h_ref))
        o_m_i = {j: data.oMi[j].copy() for j in set(joint.values())}  # the carriers' joints at the reference
    gm = pin.GeometryModel()
    index: dict[str, list[int]] = {}
    for s in shapes:
        j = joint[s.carrier]
        placement = o_m_i[j].actInv(world[s.carrier] * s.local)
        index.setdefault(s.body, []).append(gm.addGeometryObject(pin.GeometryObject(s.name, j, placement, s.geometry)))
    starts = []
    for p in pairs:
        a, b = p.split("|")
        starts.append(len(gm.collisionPairs))
        for ga in index[a]:
            for gb in index[b]:
                if b == "base" and gm.geometryObjects[ga].name.endswith(".rod"):
                    continue  # stem-base: the stub only (module docstring)
                gm.addCollisionPair(pin.CollisionPair(ga, gb))
    kin = "closed-form rig" if isinstance(rig_obj, ClosedFormRig) else type(rig_obj).__module__
    batch = getattr(rig_obj, "configurations", None)
    if batch is None:
        fit = AffineConfigurations(machine, rig_obj)
        batch = fit if fit.error < 1e-12 else None
        notes.append(f"{kin}: configurations vectorised by a verified affine fit (max error {fit.error:.1e})"
                     if batch else f"{kin}: configurations per pose (the affine fit errs by {fit.error:.1e})")
    return InterferenceModel(machine=machine, rig=rig_obj, geometry_model=gm, pairs=tuple(pairs),
                             kinds=tuple(pair_kind(p) for p in pairs), excluded=tuple(excluded),
                             group_starts=np.array(starts, dtype=np.intp), notes=tuple(notes), kinematics=kin,
                             batch=batch)


# --- queries --------------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class PairDistance:
    """Signed minimum distance of one body pair (m; negative = penetration) and the witness points
    on each body (world frame, m)."""

    pair: str
    kind: str
    distance_m: float
    point_a_m: tuple[float, float, float]
    point_b_m: tuple[float, float, float]


@dataclass(frozen=True, kw_only=True)
class PoseClearance:
    """Every checked pair at one pose, against a safety margin (m)."""

    pose_m: tuple[float, ...]
    margin_m: float
    pairs: tuple[PairDistance, ...]
    excluded: tuple[str, ...]

    @property
    def worst(self) -> PairDistance:
        return min(self.pairs, key=lambda p: p.distance_m)

    @property
    def passed(self) -> bool:
        return self.worst.distance_m >= self.margin_m

    def to_dict(self) -> dict[str, Any]:
        from dataclasses import asdict

        return {"pose_m": list(self.pose_m), "margin_m": self.margin_m, "passed": self.passed,
                "worst": asdict(self.worst), "pairs": [asdict(p) for p in self.pairs],
                "excluded_pairs": list(self.excluded)}


class _Evaluator:
    """pin Data + GeometryData with live references to the distance results (read without copies)."""

    def __init__(self, im: InterferenceModel) -> None:
        self.im = im
        self.data = data_pool.lend(im.rig.model, self)
        self.gdata = pin.GeometryData(im.geometry_model)
        self.results = list(self.gdata.distanceResults)
        self.n = len(self.results)

    def distances(self, q: np.ndarray) -> np.ndarray:
        pin.computeDistances(self.im.rig.model, self.data, self.im.geometry_model, self.gdata, q)
        return np.fromiter(map(_MIN_DISTANCE, self.results), float, self.n)


def clearance_at_configuration(im: InterferenceModel, q: np.ndarray, margin_m: float | None = None,
                               pose_m: ArrayLike = ()) -> PoseClearance:
    """Every checked pair at a rig configuration ``q`` (need not close the loops)."""
    ev = _Evaluator(im)
    d = ev.distances(np.asarray(q, dtype=float))
    out = []
    bounds = list(im.group_starts) + [ev.n]
    for k, pair in enumerate(im.pairs):  # geometry pairs were added (shape of body a, shape of body b)
        g = bounds[k] + int(np.argmin(d[bounds[k]:bounds[k + 1]]))
        pa, pb = ev.results[g].getNearestPoint1(), ev.results[g].getNearestPoint2()
        out.append(PairDistance(pair=pair, kind=im.kinds[k], distance_m=float(d[g]), point_a_m=tuple(map(float, pa)),
                                point_b_m=tuple(map(float, pb))))
    margin = im.machine.collision.safety_margin_m if margin_m is None else float(margin_m)
    return PoseClearance(pose_m=tuple(map(float, pose_m)), margin_m=margin, pairs=tuple(out), excluded=im.excluded)


def clearance_at(im: InterferenceModel, pose_m: ArrayLike, margin_m: float | None = None,
                 check_reachable: bool = True) -> PoseClearance:
    """Every checked pair at the plate pose h (m); raises UnreachablePoseError unless reachable."""
    h = kinematics.require_reachable(im.machine, pose_m) if check_reachable else np.asarray(pose_m, float).reshape(3)
    return clearance_at_configuration(im, im.rig.configuration_at(h), margin_m, h)


@dataclass(frozen=True, eq=False, kw_only=True)
class SweepResult:
    """Clearance over poses. Per pose: the minimum over pairs and the worst pair (NaN / -1 where the
    pose is unreachable and skipped). Per pair: the minimum over poses and where."""

    poses_m: np.ndarray  # (n, 3)
    reachable: np.ndarray  # (n,) bool
    min_distance_m: np.ndarray  # (n,)
    worst_pair: np.ndarray  # (n,) index into pairs
    pairs: tuple[str, ...]
    kinds: tuple[str, ...]
    excluded: tuple[str, ...]
    pair_min_m: np.ndarray  # (P,)
    pair_argmin: np.ndarray  # (P,) index into poses
    margin_m: float
    grid_axes_m: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # x, y, z axes of a grid

    @property
    def n_skipped(self) -> int:
        return int((~self.reachable).sum())

    @property
    def passed(self) -> bool:
        return bool(np.all(self.pair_min_m >= self.margin_m))

    @property
    def worst(self) -> int:
        """Index of the pair with the smallest distance over all poses."""
        return int(np.argmin(self.pair_min_m))

    def kind_minima(self) -> dict[str, dict[str, Any]]:
        """Per pair kind: the minimum distance (m), its pair and pose (m)."""
        out: dict[str, dict[str, Any]] = {}
        for k in dict.fromkeys(self.kinds):
            idx = [i for i, kk in enumerate(self.kinds) if kk == k]
            i = idx[int(np.argmin(self.pair_min_m[idx]))]
            out[k] = {"distance_m": float(self.pair_min_m[i]), "pair": self.pairs[i],
                      "pose_m": self.poses_m[self.pair_argmin[i]].tolist()}
        return out

    def to_dict(self) -> dict[str, Any]:
        w = self.worst
        return {
            "n_poses": len(self.poses_m), "n_evaluated": int(self.reachable.sum()), "n_skipped_unreachable":
            self.n_skipped, "margin_m": self.margin_m, "passed": self.passed,
            "worst": {"pair": self.pairs[w], "kind": self.kinds[w], "distance_m": float(self.pair_min_m[w]),
                      "pose_m": self.poses_m[self.pair_argmin[w]].tolist()},
            "by_kind": self.kind_minima(),
            "pairs": [{"pair": p, "kind": k, "distance_m": float(d), "pose_m": self.poses_m[i].tolist()}
                      for p, k, d, i in zip(self.pairs, self.kinds, self.pair_min_m, self.pair_argmin)],
            "excluded_pairs": list(self.excluded),
        }


def sweep(im: InterferenceModel, poses_m: np.ndarray, margin_m: float | None = None, progress: bool = False,
          grid_axes_m: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> SweepResult:
    """Distances of every checked pair at poses (n, 3) in m; unreachable poses are skipped and counted."""
    from tqdm import tqdm

    poses = np.asarray(poses_m, dtype=float).reshape(-1, 3)
    n, npairs = len(poses), len(im.pairs)
    ok = kinematics.is_reachable(im.machine, poses) & np.all(np.isfinite(poses), axis=1)
    dmin, worst = np.full(n, np.nan), np.full(n, -1, dtype=np.intp)
    pmin, parg = np.full(npairs, np.inf), np.zeros(npairs, dtype=np.intp)
    ev = _Evaluator(im)
    todo = np.flatnonzero(ok)
    with tqdm(total=len(todo), desc="interference", unit="pose", disable=not progress) as bar:
        for s in range(0, len(todo), _CHUNK):
            idx = todo[s:s + _CHUNK]
            qs = im.configurations(poses[idx])
            g = np.array([ev.distances(q) for q in qs]).reshape(len(idx), ev.n)
            body = np.minimum.reduceat(g, im.group_starts, axis=1)  # (chunk, P)
            worst[idx] = np.argmin(body, axis=1)
            dmin[idx] = body[np.arange(len(idx)), worst[idx]]
            k = np.argmin(body, axis=0)
            better = body[k, np.arange(npairs)] < pmin
            pmin[better], parg[better] = body[k, np.arange(npairs)][better], idx[k][better]
            bar.update(len(idx))
    margin = im.machine.collision.safety_margin_m if margin_m is None else float(margin_m)
    if not len(todo):
        raise InterferenceError(f"none of the {n} poses is reachable", key="poses", value=n)
    return SweepResult(poses_m=poses, reachable=ok, min_distance_m=dmin, worst_pair=worst, pairs=im.pairs,
                       kinds=im.kinds, excluded=im.excluded, pair_min_m=pmin, pair_argmin=parg, margin_m=margin,
                       grid_axes_m=grid_axes_m)


def workspace_sweep(im: InterferenceModel, points: int = 41, heights: int = 7,
                    y_range_m: tuple[float, float] | None = None, margin_m: float | None = None,
                    progress: bool = False) -> SweepResult:
    """:func:`sweep` over the required workspace (:func:`pressfit.kinematics.workspace.workspace_box`,
    poses ordered (y, z, x)): ``points`` per side, ``heights`` levels spanning ``y_range_m`` (m), by default
    the heights where the whole required square is reachable (``square_height_range``)."""
    if y_range_m is None:
        hr = square_height_range(im.machine)
        y_range_m = (hr.y_min_m, hr.y_max_m)
    ys = np.linspace(*y_range_m, heights)
    xs, zs = workspace_square(im.machine, points)
    poses = workspace_box(im.machine, ys, points).reshape(-1, 3)
    return sweep(im, poses, margin_m, progress, (xs, ys, zs))


def min_distance_over_poses(machine: Machine, poses_m: np.ndarray, progress: bool = False) -> np.ndarray:
    """Minimum signed distance over every checked pair at each pose (n,), m; NaN where unreachable."""
    return sweep(build_interference(machine), poses_m, progress=progress).min_distance_m
