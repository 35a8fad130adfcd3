"""Interference (Coal shapes in a Pinocchio GeometryModel) against independent references.

References: a closed-form segment-segment distance (below; no Coal, no Pinocchio) minus the capsule
radii; leg end points from :mod:`pressfit.kinematics` or from explicit cardan angles; a coal.Box
primitive for a mesh body. Tolerances are stated per test.
"""

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from pressfit import kinematics
from pressfit.cli import main
from pressfit.errors import InterferenceError
from pressfit.geometry import interference as I


def segment_distance(p0, p1, q0, q1):
    """Distance between segments [p0, p1] and [q0, q1] (closed form): |P(s) - Q(t)|^2 is a convex
    quadratic on the unit square, so its minimum is the interior stationary point (if inside) or the
    best of the four edges, each minimised by a clamped projection."""
    p0, p1, q0, q1 = (np.asarray(v, float) for v in (p0, p1, q0, q1))
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e, b, c, f = d1 @ d1, d2 @ d2, d1 @ d2, d1 @ r, d2 @ r

    def dist(s, t):
        return np.linalg.norm(p0 + s * d1 - q0 - t * d2)

    cand = []
    den = a * e - b * b
    if den > 1e-14 * a * e:
        s, t = (b * f - c * e) / den, (a * f - b * c) / den
        if 0 <= s <= 1 and 0 <= t <= 1:
            cand.append(dist(s, t))
    for s in (0.0, 1.0):
        cand.append(dist(s, np.clip((f + s * b) / e, 0, 1) if e > 0 else 0.0))
    for t in (0.0, 1.0):
        cand.append(dist(np.clip((t * b - c) / a, 0, 1) if a > 0 else 0.0, t))
    return min(cand)


def test_segment_distance_reference_sanity():
    assert segment_distance([0, 0, 0], [1, 0, 0], [0.5, 1, -1], [0.5, 1, 1]) == pytest.approx(1.0, abs=1e-15)
    assert segment_distance([0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]) == pytest.approx(1.0, abs=1e-15)
    assert segment_distance([0, 0, 0], [1, 0, 0], [0.5, 2, 0], [0.7, 2, 0]) == pytest.approx(2.0, abs=1e-15)
    assert segment_distance([0, 0, 0], [0, 0, 0], [1, 1, 0], [1, -1, 0]) == pytest.approx(1.0, abs=1e-15)


def leg_segments(machine, b, e, length):
    """Per leg body, its capsule segments (module docstring of interference): (radius, [(p0, p1)])."""
    lc, lmin, lmax = machine.cylinder.length_m, machine.limits.leg_length_min_m, machine.limits.leg_length_max_m
    s_end = min(lmin, max(lc, lmax - lmin))
    c = machine.collision
    return {"cylinder": (c.cylinder_radius_m, [(b, b + lc * e)]),
            "stem": (c.stem_radius_m, [(b + lc * e, b + s_end * e), (b + (length - lmin) * e, b + length * e)])}


def reference_leg_leg(machine, bases, units, lengths):
    """'legi.part|legj.part' -> min over segment pairs of (segment distance - radii), m."""
    n = len(bases)
    segs = [leg_segments(machine, bases[i], units[i], lengths[i]) for i in range(n)]
    out = {}
    for i in range(n):
        for j in range(i + 1, n):
            for pa, (ra, sa) in segs[i].items():
                for pb, (rb, sb) in segs[j].items():
                    out[f"leg{i + 1}.{pa}|leg{j + 1}.{pb}"] = min(
                        segment_distance(*u, *v) for u in sa for v in sb) - ra - rb
    return out


def check_against_reference(im, pc, ref, tol):
    got = {p.pair: p.distance_m for p in pc.pairs if p.kind == "leg-leg"}
    assert set(got) == set(ref)
    err = max(abs(got[k] - ref[k]) for k in ref)
    assert err < tol, err


@pytest.mark.slow
@pytest.mark.parametrize("rig", ["closed-form", "auto"])
def test_capsules_match_segment_distance_at_random_poses(machine, rig):
    """Leg-leg capsule distances = closed-form segment distance - radii, 1e-9 m (random poses in a box
    larger than the workspace, reachable or not; end points from kinematics.py)."""
    im = I.build_interference(machine, rig=rig)
    rng = np.random.default_rng(3)
    n = 0
    for h in np.column_stack([rng.uniform(-.35, .35, 60), rng.uniform(.45, .8, 60), rng.uniform(-.35, .35, 60)]):
        if rig != "closed-form" and not kinematics.is_reachable(machine, h):
            continue  # pressfit.model's configuration_at only takes reachable poses
        ik = kinematics.inverse_kinematics(machine, h)
        ref = reference_leg_leg(machine, machine.base_points_m, ik.unit_vectors, ik.lengths_m)
        check_against_reference(im, I.clearance_at(im, h, check_reachable=False), ref, 1e-9)
        n += 1
    assert n >= 20


def unit_from_angles(machine, i, phi, psi):
    """Leg direction after cardan angles phi (about a_i, from the inward horizontal w_i toward a_i x w_i)
    and psi (toward a_i): e = cos(psi) (cos(phi) w + sin(phi) a x w) + sin(psi) a."""
    a, w = machine.cardan_axes[i], machine.inward_directions[i]
    return np.cos(psi) * (np.cos(phi) * w + np.sin(phi) * np.cross(a, w)) + np.sin(psi) * a


def configuration(im, phis, psis, lengths, h):
    q = np.zeros(im.rig.model.nq)
    for i, ids in enumerate(im.rig.leg_joint_ids):
        for k, v in (("base_cardan", phis[i]), ("cylinder", psis[i]), ("actuator", lengths[i])):
            q[im.rig.model.joints[ids[k]].idx_q] = v
    q[im.rig.model.joints[im.rig.plate_joint_id].idx_q:][:3] = h
    return q


def test_capsules_match_segment_distance_random_configurations(machine):
    """Random leg configurations (independent legs, loops not closed, penetrations included):
    capsule distance = segment distance - radii to 1e-9 m."""
    im = I.build_interference(machine, rig="closed-form")
    rng = np.random.default_rng(7)
    negative = 0
    for _ in range(60):
        phis, psis = rng.uniform(-0.2, 1.8, 4), rng.uniform(-0.9, 0.9, 4)
        lengths = rng.uniform(0.5, 1.0, 4)
        units = np.array([unit_from_angles(machine, i, phis[i], psis[i]) for i in range(4)])
        pc = I.clearance_at_configuration(im, configuration(im, phis, psis, lengths, [0, .6, 0]))
        ref = reference_leg_leg(machine, machine.base_points_m, units, lengths)
        check_against_reference(im, pc, ref, 1e-9)
        negative += sum(v < 0 for v in ref.values())
    assert negative > 0  # penetrating configurations were exercised


def test_crossing_legs_are_a_collision(machine):
    """Cylinder axes of legs 1 and 2 aimed at one point: signed distance -2 r_c (1e-9 m), pose fails."""
    im = I.build_interference(machine, rig="closed-form")
    x = np.array([0.2, 0.3, -0.2])  # 0.434 m from B_1 and B_2, inside both cylinders (0.45 m)
    phis, psis = np.full(4, 1.0), np.zeros(4)
    for i in (0, 1):
        e = (x - machine.base_points_m[i]) / np.linalg.norm(x - machine.base_points_m[i])
        a, w = machine.cardan_axes[i], machine.inward_directions[i]
        phis[i], psis[i] = np.arctan2(e @ np.cross(a, w), e @ w), np.arcsin(e @ a)
    pc = I.clearance_at_configuration(im, configuration(im, phis, psis, np.full(4, 0.75), [0, .6, 0]))
    d = {p.pair: p for p in pc.pairs}["leg1.cylinder|leg2.cylinder"]
    assert d.distance_m == pytest.approx(-2 * machine.collision.cylinder_radius_m, abs=1e-9)
    assert pc.worst.distance_m < 0 and not pc.passed


def test_fat_stems_touch_at_a_reachable_pose(machine):
    """Stem radius set to half the closed-form rod-rod distance of legs 1-2 (+1 mm, then exactly):
    the pair reads -2 mm, then 0 (1e-9 m), and the pose fails the margin."""
    h = np.array([0.1, 0.6, -0.05])
    ik = kinematics.inverse_kinematics(machine, h)
    ref = reference_leg_leg(machine, machine.base_points_m, ik.unit_vectors, ik.lengths_m)
    gap = ref["leg1.stem|leg2.stem"] + 2 * machine.collision.stem_radius_m  # axis-to-axis distance
    for extra, expected in ((1e-3, -2e-3), (0.0, 0.0)):
        r = gap / 2 + extra
        fat = machine.with_overrides({"collision": {"stem_radius_m": r, "cylinder_radius_m": max(r, 0.03)}})
        pc = I.clearance_at(I.build_interference(fat), h)
        d = {p.pair: p.distance_m for p in pc.pairs}["leg1.stem|leg2.stem"]
        assert d == pytest.approx(expected, abs=1e-9)
        assert not pc.passed


def test_witness_points_are_on_the_bodies_and_realise_the_distance(machine):
    im = I.build_interference(machine)
    pc = I.clearance_at(im, [0.15, 0.55, 0.2])
    for p in pc.pairs:
        assert np.linalg.norm(np.subtract(p.point_a_m, p.point_b_m)) == pytest.approx(p.distance_m, abs=1e-8)
    p = {q.pair: q for q in pc.pairs}["leg1.stem|base"]
    assert p.point_b_m[1] == pytest.approx(0.0, abs=1e-9)  # on the base's top face (y = 0)


def names_of_geometry_pairs(im):
    objs = im.geometry_model.geometryObjects
    return {(objs[cp.first].name, objs[cp.second].name) for cp in im.geometry_model.collisionPairs}


def test_excluded_pairs_are_not_evaluated(machine):
    im = I.build_interference(machine)
    by_design = {f"leg{i}.cylinder|leg{i}.stem" for i in range(1, 5)} | {f"leg{i}.cylinder|base" for i in range(1, 5)} \
        | {f"leg{i}.stem|plate" for i in range(1, 5)}
    assert set(im.excluded) == by_design and not by_design & set(im.pairs)
    assert len(im.pairs) == 24 + 4 + 4
    for a, b in names_of_geometry_pairs(im):
        body = lambda n: n if n in ("plate", "base") else ".".join(n.split(".")[:2])
        assert f"{body(a)}|{body(b)}" in im.pairs
        assert not (a.split(".")[0] == b.split(".")[0] and a.startswith("leg"))  # no shape pair within a leg
    pc = I.clearance_at(im, [0, 0.6, 0])
    assert {p.pair for p in pc.pairs} == set(im.pairs)

    over = I.build_interference(machine, exclude=["leg2.stem|leg1.stem"], include=["leg1.stem|plate"])
    assert "leg1.stem|leg2.stem" not in over.pairs and "leg1.stem|leg2.stem" in over.excluded
    assert "leg1.stem|plate" in over.pairs and "leg1.stem|plate" not in over.excluded
    assert not any({a, b} <= {"leg1.stem.stub", "leg1.stem.rod", "leg2.stem.stub", "leg2.stem.rod"}
                   and a[:4] != b[:4] for a, b in names_of_geometry_pairs(over))
    touching = {p.pair: p.distance_m for p in I.clearance_at(over, [0, 0.6, 0]).pairs}["leg1.stem|plate"]
    assert touching < 0  # the stem ends at its plate cardan, on the plate's side face: why it is excluded
    with pytest.raises(InterferenceError) as refused:
        I.build_interference(machine, exclude=["leg1.stem|nothing"])
    assert refused.value.key == "pair" and refused.value.value == "leg1.stem|nothing"  # the data, not the text
    assert "leg1.stem" in refused.value.allowed and "nothing" not in refused.value.allowed


def test_mesh_body_matches_box_primitive(machine, tmp_path):
    """A trimesh box exported to STL (in mm, scale 0.001) gives the box primitive's distances, on the
    plate and in the world, penetrating or not: 1e-6 m (both through GJK/EPA at Coal's default 1e-6
    tolerance; the STL stores float32 vertices, 1e-8 m here)."""
    size = [0.3, 0.12, 0.2]
    trimesh.creation.box(extents=np.array(size) * 1e3).export(tmp_path / "fixture.stl")
    pose = {"translation_m": [0.05, -0.25, 0.02], "rotation_rpy_rad": [0.1, 0.4, -0.2]}
    wpose = {"translation_m": [0.3, 0.25, -0.25], "rotation_rpy_rad": [0.0, 0.3, 0.0]}
    extras = [
        {"name": "mesh", "frame": "plate", "mesh_path": str(tmp_path / "fixture.stl"), "mesh_scale": 1e-3, **pose},
        {"name": "box", "frame": "plate", "box_size_m": size, **pose},
        {"name": "wmesh", "mesh_path": "fixture.stl", "mesh_scale": 1e-3, **wpose},
        {"name": "wbox", "box_size_m": size, **wpose},
    ]
    m = machine.with_overrides({"collision": {"extra_bodies": extras}}, source=str(tmp_path / "machine.toml"))
    (tmp_path / "machine.toml").write_text("")  # relative mesh paths resolve from the machine file's directory
    im = I.build_interference(m)
    assert sum(k == "leg-extra" for k in im.kinds) == 8 * 4
    signs = set()
    for h in ([0, 0.6, 0], [0.2, 0.5, -0.2], [-0.25, 0.7, 0.25]):
        d = {p.pair: p.distance_m for p in I.clearance_at(im, h).pairs}
        for leg in range(1, 5):
            for part in ("cylinder", "stem"):
                body = f"leg{leg}.{part}"
                for a, b in (("mesh", "box"), ("wmesh", "wbox")):
                    assert d[f"{body}|{a}"] == pytest.approx(d[f"{body}|{b}"], abs=1e-6)
                    signs.add(np.sign(d[f"{body}|{b}"]))
    assert signs == {-1.0, 1.0}


def test_sweep_skips_and_counts_unreachable_poses(machine):
    im = I.build_interference(machine)
    poses = np.array([[0, 0.6, 0], [0, 2.0, 0], [0.25, 0.5, 0.25], [0, 0.1, 0]])
    res = I.sweep(im, poses)
    assert res.n_skipped == 2 and list(res.reachable) == [True, False, True, False]
    assert np.isnan(res.min_distance_m[[1, 3]]).all() and (res.worst_pair[[1, 3]] == -1).all()
    for k in (0, 2):
        pc = I.clearance_at(im, poses[k])
        assert res.min_distance_m[k] == pytest.approx(pc.worst.distance_m, abs=1e-12)
        assert res.pairs[res.worst_pair[k]] == pc.worst.pair or \
            abs(pc.worst.distance_m - {p.pair: p.distance_m for p in pc.pairs}[res.pairs[res.worst_pair[k]]]) < 1e-12
    assert set(res.kind_minima()) == {"leg-leg", "leg-plate", "leg-base"}


def test_model_rig_matches_closed_form_rig(machine):
    """Shapes on pressfit.model's VJM model (rigid configuration) and on the closed-form rig: 1e-12 m."""
    rng = np.random.default_rng(11)
    poses = np.column_stack([rng.uniform(-.25, .25, 300), rng.uniform(.49, .75, 300), rng.uniform(-.25, .25, 300)])
    a = I.sweep(I.build_interference(machine, rig="model"), poses)
    b = I.sweep(I.build_interference(machine, rig="closed-form"), poses)
    assert a.reachable.sum() > 200
    np.testing.assert_allclose(a.min_distance_m, b.min_distance_m, atol=1e-12)
    np.testing.assert_allclose(a.pair_min_m, b.pair_min_m, atol=1e-12)


@pytest.mark.slow
def test_cli_pose_and_workspace(tmp_path):
    r = CliRunner().invoke(main, ["interference", "0.1", "0.6", "-0.2", "--json"])
    assert r.exit_code == 0, r.output
    assert CliRunner().invoke(main, ["interference", "0.1", "0.6", "-0.2", "--margin", "0.5"]).exit_code == 1
    assert CliRunner().invoke(main, ["interference", "0", "2", "0"]).exit_code == 2
    assert CliRunner().invoke(main, ["interference", "0", "0.6"]).exit_code == 2
    assert CliRunner().invoke(main, ["interference", "0", "0.6", "0", "--exclude", "a|b"]).exit_code == 2
    args = ["interference", "--workspace", "--points", "5", "--heights", "2", "--out", str(tmp_path), "--no-progress"]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    assert {p.name for p in tmp_path.iterdir()} >= {"interference_poses.csv", "interference_pairs.csv",
                                                   "interference_map.png"}
    assert CliRunner().invoke(main, args).exit_code == 2  # never overwrite without --overwrite
    assert CliRunner().invoke(main, args + ["--overwrite", "--margin", "0.05"]).exit_code == 1


def test_flat_cylinders_are_contained_in_the_capsules(machine):
    """leg_shape = 'cylinder': every distance >= the capsule one (a capsule contains its cylinder), and
    the leg 1 cylinder-plate distance equals a direct coal.Cylinder / coal.Box query (1e-6 m, GJK)."""
    import coal

    flat = machine.with_overrides({"collision": {"leg_shape": "cylinder"}})
    h = np.array([0.0, 0.48775, -0.25])  # shortest leg 1: its cylinder end near the plate
    cap = {p.pair: p.distance_m for p in I.clearance_at(I.build_interference(machine), h).pairs}
    cyl = {p.pair: p.distance_m for p in I.clearance_at(I.build_interference(flat), h).pairs}
    assert all(cyl[k] >= cap[k] - 1e-6 for k in cap)
    f, b = kinematics.leg_frames(machine, h)[0], machine.base_points_m[0]
    lc, c = machine.cylinder.length_m, machine.collision
    direct = coal.distance(coal.Cylinder(c.cylinder_radius_m, lc), coal.Transform3s(f, b + lc / 2 * f[:, 2]),
                           coal.Box(2 * machine.geometry.plate_half_side_m, c.plate_thickness_m,
                                    2 * machine.geometry.plate_half_side_m), coal.Transform3s(np.eye(3), h),
                           coal.DistanceRequest(), coal.DistanceResult())
    assert cyl["leg1.cylinder|plate"] == pytest.approx(direct, abs=1e-6)
    assert cyl["leg1.cylinder|plate"] > cap["leg1.cylinder|plate"] + 0.02


@pytest.mark.slow
@pytest.mark.parametrize("which", ["tsai", "five"])
def test_n_legs_capsules_match_segment_distance(request, which):
    """Issue 21: n legs' bodies leg1..legn, every leg-leg pair (n (n - 1) / 2 leg pairs of 4 body pairs),
    n leg-plate and n leg-base pairs; the leg-leg distances = closed-form segment distance - radii to 1e-9 m at
    reachable poses of the required workspace."""
    m = request.getfixturevalue(which)
    n = len(m.legs)
    im = I.build_interference(m)
    assert im.kinds.count("leg-leg") == 4 * n * (n - 1) // 2
    assert im.kinds.count("leg-plate") == im.kinds.count("leg-base") == n
    assert {p.split("|")[0].split(".")[0] for p in im.pairs} == {f"leg{i + 1}" for i in range(n)}
    rng = np.random.default_rng(5)
    poses = np.column_stack([rng.uniform(-.25, .25, 20), rng.uniform(.5, .7, 20), rng.uniform(-.25, .25, 20)])
    poses = poses[kinematics.is_reachable(m, poses)]
    assert len(poses) >= 10
    for h in poses:
        ik = kinematics.inverse_kinematics(m, h)
        ref = reference_leg_leg(m, m.base_points_m, ik.unit_vectors, ik.lengths_m)
        check_against_reference(im, I.clearance_at(im, h), ref, 1e-9)


def test_tsai_distances_follow_the_120_degree_rotation(tsai):
    """Rotating the pose by 120 degrees about y maps the 3-UPU onto itself with legs relabelled (R n_i = n_s(i),
    found from the radial directions): every leg-leg and leg-base distance at R h equals its relabelled pair's
    at h, and at the centred pose all three of a kind are equal (1e-9 m: capsule distances are closed form in
    Coal). The plate pairs are left out here: the plate is a 2r square box (the 4-UPU's), not 120-degree
    symmetric; the mirror x -> -x (legs 2 and 3 swap) maps it onto itself, and with it the leg-plate pairs."""
    from n_legs import rotation_about_y

    im = I.build_interference(tsai)
    radial = np.array([leg.radial_direction for leg in tsai.legs])

    def relabel(matrix):
        return [int(np.argmin(np.linalg.norm(radial - matrix @ r, axis=1))) + 1 for r in radial]

    def mapped(pair, s):
        names = [f"leg{s[int(b[3]) - 1]}{b[4:]}" if b.startswith("leg") else b for b in pair.split("|")]
        return "|".join(sorted(names, key=lambda b: (not b.startswith("leg"), b)))

    rot, mirror = rotation_about_y(2 * np.pi / 3), np.diag([-1.0, 1.0, 1.0])
    for h in ([0.0, 0.6, 0.0], [0.12, 0.62, -0.07]):
        h = np.array(h)
        for matrix, kinds in ((rot, ("leg-leg", "leg-base")), (mirror, ("leg-leg", "leg-base", "leg-plate"))):
            s = relabel(matrix)
            assert sorted(s) == [1, 2, 3] and s != [1, 2, 3]
            a = {p.pair: p.distance_m for p in I.clearance_at(im, h).pairs if p.kind in kinds}
            b = {p.pair: p.distance_m for p in I.clearance_at(im, matrix @ h).pairs}
            assert max(abs(b[mapped(k, s)] - v) for k, v in a.items()) < 1e-9
    centre = I.clearance_at(im, [0.0, 0.6, 0.0])
    for kind in ("leg-base", "leg-plate"):
        d = [p.distance_m for p in centre.pairs if p.kind == kind]
        assert max(d) - min(d) < 1e-9 if kind == "leg-base" else d[1] == pytest.approx(d[2], abs=1e-9)
