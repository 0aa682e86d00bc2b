"""Tests of python/src/cast_bindings.cpp: shape casts in batches against a Mesh and a Scene, linear
(Mesh/Scene.cast_spheres / cast_capsules / cast_obbs) and rigid (cast_*_rigid), closest and any hit
(C++'s castClosest / castAny of mesh_cast.hpp and scene_cast.hpp): times of impact, contact data,
misses, leading dimensions, bad input, pickled meshes and scenes. Agreement with `crux batch` is in
test_world.py."""

import pickle

import numpy as np
import pytest

import crux
from conftest import unit_cube, torus

# The casts' tolerance in t is relative (kCastRelativeTolerance, cast.hpp); 1e-4 of a unit
# motion covers it in both precisions.
T_TOL = 1e-4


def test_a_sphere_falling_on_the_cube_meets_the_top_face_when_its_gap_is_covered():
    cube = unit_cube()
    # radius 0.25 centred 1 above the top face (z = 2), falling by 2: contact after 0.75 of 2
    spheres = np.array([[0.5, 0.5, 2.0, 0.25], [0.3, 0.6, 3.0, 0.5]])
    motions = np.array([[0.0, 0.0, -2.0], [0.0, 0.0, -4.0]])
    hits = cube.cast_spheres(spheres, motions)
    assert isinstance(hits, crux.CastHits)
    np.testing.assert_allclose(hits.t, [0.75 / 2, 1.5 / 4], atol=T_TOL)
    assert (hits.triangle >= 0).all()
    np.testing.assert_allclose(hits.point_mesh[:, 2], [1.0, 1.0], atol=1e-4)
    np.testing.assert_allclose(hits.normal, [[0, 0, 1], [0, 0, 1]], atol=1e-3)  # mesh -> shape
    assert not hits.starts_overlapping.any()


def test_misses_are_inf_minus_one_and_nan_and_leading_dimensions_are_kept():
    cube = unit_cube()
    spheres = np.zeros((2, 3, 4))
    spheres[..., :3] = [5.0, 5.0, 5.0]
    spheres[..., 3] = 0.5
    motions = np.zeros((2, 3, 3))
    motions[..., 0] = 1.0  # moving away from the cube
    motions[1, 2] = [-8.0, -8.0, -8.0]  # through the cube: a hit
    hits = cube.cast_spheres(spheres, motions)
    assert hits.t.shape == (2, 3) and hits.point_shape.shape == (2, 3, 3)
    miss = np.ones((2, 3), bool)
    miss[1, 2] = False
    assert np.isinf(hits.t[miss]).all() and (hits.triangle[miss] == -1).all()
    assert np.isnan(hits.normal[miss]).all()
    assert np.isfinite(hits.t[1, 2]) and 0 < hits.t[1, 2] < 1


def test_touching_at_the_start_gives_t_zero_and_the_flag():
    cube = unit_cube()
    hits = cube.cast_spheres([[0.5, 0.5, 1.25, 0.25]], [[0.0, 0.0, 1.0]])  # resting on the top face
    assert hits.t[0] == 0 and hits.starts_overlapping[0]


def test_capsule_and_box_casts_agree_with_the_gap_they_close():
    cube = unit_cube()
    # a horizontal capsule of radius 0.1 whose lowest point is 0.5 above the top face
    capsules = np.array([[0.2, 0.5, 1.6, 0.8, 0.5, 1.6, 0.1]])
    hits = cube.cast_capsules(capsules, [[0.0, 0.0, -1.0]])
    np.testing.assert_allclose(hits.t, [0.5], atol=T_TOL)
    # an axis-aligned box of half extent 0.1 whose bottom face is 0.3 beside the +x face
    obb = np.concatenate([[1.4, 0.5, 0.5], [0.1, 0.1, 0.1], np.eye(3).ravel()])
    hits = cube.cast_obbs([obb], [[-0.6, 0.0, 0.0]])
    np.testing.assert_allclose(hits.t, [0.3 / 0.6], atol=T_TOL)
    np.testing.assert_allclose(hits.normal[0], [1, 0, 0], atol=1e-3)


def test_a_sphere_cast_finds_the_ray_hit_of_its_centre_minus_the_radius(bunny):
    # a small sphere cast along a ray that hits the bunny head-on enough: its t is at most the
    # ray's (it touches no later than its centre would) and within its radius of it
    rng = np.random.default_rng(3)
    lo, hi = bunny.vertices.min(0), bunny.vertices.max(0)
    centre = (lo + hi) / 2
    size = np.linalg.norm(hi - lo)
    origins = centre + rng.normal(size=(40, 3)) * size
    motions = centre + (rng.random((40, 3)) - 0.5) * (hi - lo) * 0.5 - origins
    radius = 1e-3 * size
    rays = np.concatenate([origins, motions], axis=1)
    ray = bunny.ray_closest(rays)
    spheres = np.concatenate([origins, np.full((40, 1), radius)], axis=1)
    cast = bunny.cast_spheres(spheres, motions)
    length = np.linalg.norm(motions, axis=1)
    hit = np.isfinite(ray.t) & (ray.t < length)
    assert hit.sum() > 10
    assert np.isfinite(cast.t[hit]).all()
    assert (cast.t[hit] * length[hit] <= ray.t[hit] + 1e-4 * size).all()
    assert (cast.t[hit] * length[hit] >= ray.t[hit] - 50 * radius).all()


def test_threads_do_not_change_answers(bunny):
    rng = np.random.default_rng(5)
    lo, hi = bunny.vertices.min(0), bunny.vertices.max(0)
    spheres = np.concatenate([lo + rng.random((200, 3)) * (hi - lo), np.full((200, 1), 0.01)], axis=1)
    motions = (rng.random((200, 3)) - 0.5) * (hi - lo)
    one = bunny.cast_spheres(spheres, motions, threads=1)
    many = bunny.cast_spheres(spheres, motions, threads=2)
    for a, b in zip(one, many):
        np.testing.assert_array_equal(a, b)


def test_bad_input_names_the_row_and_the_field():
    cube = unit_cube()
    with pytest.raises(ValueError, match="motions"):
        cube.cast_spheres([[0, 0, 2, 0.1]], [[0.0, np.nan, 0.0]])
    with pytest.raises(ValueError, match="spheres"):
        cube.cast_spheres([[0, 0, 2, -0.1]], [[0.0, 0.0, -1.0]])
    with pytest.raises(ValueError, match="motions"):
        cube.cast_spheres([[0, 0, 2, 0.1], [0, 0, 3, 0.1]], [[0.0, 0.0, -1.0]])
    with pytest.raises(ValueError, match="obbs"):
        cube.cast_obbs([np.concatenate([[2, 2, 2], [0.1, 0.1, 0.1], 2 * np.eye(3).ravel()])], [[-1.0, 0, 0]])


# ---- rigid casts: shapes in their own frame, moved from a start pose to an end pose

IDENTITY = np.array([1.0, 0, 0, 0])


def quat_z(angle):
    return np.array([np.cos(angle / 2), 0, 0, np.sin(angle / 2)])


def pose_rows(quats, translations):
    """(..., 7) pose rows w, x, y, z, tx, ty, tz: one quaternion for all, or one per translation."""
    t = np.asarray(translations, float)
    q = np.broadcast_to(np.asarray(quats, float), t.shape[:-1] + (4,))
    return np.concatenate([q, t], axis=-1)


def matrix(quat, translation):
    w, x, y, z = quat
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                 [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                 [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = translation
    return m


def test_a_turning_bar_falling_on_the_cube_meets_the_top_face_at_its_gap():
    cube = unit_cube()
    # a box of half extents (0.4, 0.05, 0.05) in its own frame; starts 0.5 above the top face and
    # falls by 1 while turning a quarter turn about z (which keeps its lowest face at the same height)
    bar = np.concatenate([[0, 0, 0], [0.4, 0.05, 0.05], np.eye(3).ravel()])
    starts = pose_rows(IDENTITY, [[0.5, 0.5, 1.55]])
    ends = pose_rows(quat_z(np.pi / 2), [[0.5, 0.5, 0.55]])
    hits = cube.cast_obbs_rigid([bar], starts, ends)
    assert isinstance(hits, crux.CastHits)
    np.testing.assert_allclose(hits.t, [0.5], atol=T_TOL)
    np.testing.assert_allclose(hits.normal[0], [0, 0, 1], atol=1e-3)
    np.testing.assert_allclose(hits.point_mesh[0, 2], 1.0, atol=1e-4)
    assert not hits.starts_overlapping[0]


def test_a_pure_turn_sweeps_the_bar_into_the_cube_side():
    cube = unit_cube()
    # a bar beside the +x face, 0.2 away, long along y: turning by a quarter turn about its centre
    # swings its end into the cube
    bar = np.concatenate([[0, 0, 0], [0.05, 1.0, 0.05], np.eye(3).ravel()])
    centre = [1.6, 0.5, 0.5]
    hits = cube.cast_obbs_rigid([bar], pose_rows(IDENTITY, [centre]), pose_rows(quat_z(np.pi / 2), [centre]))
    assert 0 < hits.t[0] < 1 and hits.triangle[0] >= 0
    assert cube.cast_obbs_rigid([bar], pose_rows(IDENTITY, [centre]), pose_rows(IDENTITY, [centre])).triangle[0] == -1


def test_rigid_casts_without_rotation_agree_with_linear_casts(bunny):
    rng = np.random.default_rng(7)
    lo, hi = bunny.bounds.astype(np.float64)
    n = 100
    starts_t = lo + rng.uniform(-0.5, 1.5, size=(n, 3)) * (hi - lo)
    motions = lo + rng.random((n, 3)) * (hi - lo) - starts_t
    radius = 0.02 * np.linalg.norm(hi - lo)
    own = np.c_[np.zeros((n, 3)), np.full(n, radius)]
    rigid = bunny.cast_spheres_rigid(own, pose_rows(IDENTITY, starts_t), pose_rows(IDENTITY, starts_t + motions))
    linear = bunny.cast_spheres(np.c_[starts_t, np.full(n, radius)], motions)
    hit = np.isfinite(linear.t)
    assert 10 < hit.sum() < n
    np.testing.assert_array_equal(np.isfinite(rigid.t), hit)
    np.testing.assert_allclose(rigid.t[hit], linear.t[hit], atol=T_TOL)


def test_poses_as_matrices_and_as_rows_give_the_same_answers(bunny):
    rng = np.random.default_rng(8)
    lo, hi = bunny.bounds.astype(np.float64)
    n = 50
    q0, q1 = rng.normal(size=(n, 4)), rng.normal(size=(n, 4))
    q0 /= np.linalg.norm(q0, axis=1, keepdims=True)
    q1 /= np.linalg.norm(q1, axis=1, keepdims=True)
    t0 = lo + rng.uniform(-0.5, 1.5, size=(n, 3)) * (hi - lo)
    t1 = lo + rng.random((n, 3)) * (hi - lo)
    half = 0.05 * (hi - lo)
    boxes = np.c_[np.zeros((n, 3)), np.tile(half, (n, 1)), np.tile(np.eye(3).ravel(), (n, 1))]
    rows = bunny.cast_obbs_rigid(boxes, np.c_[q0, t0], np.c_[q1, t1])
    mats = bunny.cast_obbs_rigid(boxes, np.array([matrix(q, t) for q, t in zip(q0, t0)]),
                                 np.array([matrix(q, t) for q, t in zip(q1, t1)]))
    hit = np.isfinite(rows.t)
    assert 5 < hit.sum() < n
    # a matrix goes through its quaternion: equal up to that quaternion's rounding
    np.testing.assert_array_equal(np.isfinite(mats.t), hit)
    np.testing.assert_allclose(mats.t[hit], rows.t[hit], atol=1e-3)


def test_equal_start_and_end_poses_are_an_overlap_test():
    mesh = torus()
    rng = np.random.default_rng(9)
    n = 300
    centres = rng.uniform(-3, 3, size=(n, 3))
    radii = rng.uniform(0, 0.8, size=n)
    poses = pose_rows(IDENTITY, centres)
    hits = mesh.cast_spheres_rigid(np.c_[np.zeros((n, 3)), radii], poses, poses)
    touching = mesh.overlaps_spheres(np.c_[centres, radii])
    assert 20 < touching.sum() < n - 20
    np.testing.assert_array_equal(np.isfinite(hits.t), touching)
    assert (hits.t[touching] == 0).all() and hits.starts_overlapping[touching].all()
    assert not hits.starts_overlapping[~touching].any()


def test_leading_dimensions_and_any_hit(bunny):
    rng = np.random.default_rng(10)
    lo, hi = bunny.bounds.astype(np.float64)
    capsules = np.zeros((4, 5, 7))
    capsules[..., 0] = -0.05 * (hi - lo)[0]
    capsules[..., 3] = 0.05 * (hi - lo)[0]
    capsules[..., 6] = 0.01 * np.linalg.norm(hi - lo)
    q = rng.normal(size=(4, 5, 2, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    t = lo + rng.uniform(-0.3, 1.3, size=(4, 5, 2, 3)) * (hi - lo)
    starts, ends = np.concatenate([q, t], -1)[:, :, 0], np.concatenate([q, t], -1)[:, :, 1]
    hits = bunny.cast_capsules_rigid(capsules, starts, ends)
    assert hits.t.shape == (4, 5) and hits.normal.shape == (4, 5, 3)
    any_hit = bunny.cast_capsules_rigid(capsules, starts, ends, any=True)
    assert any_hit.dtype == bool and any_hit.shape == (4, 5)
    np.testing.assert_array_equal(any_hit, np.isfinite(hits.t))
    assert 0 < any_hit.sum() < 20
    placed = capsules.copy()  # the capsules at their start translations, moved linearly
    placed[..., 0:3] += t[:, :, 0]
    placed[..., 3:6] += t[:, :, 0]
    linear = bunny.cast_capsules(placed, t[:, :, 1] - t[:, :, 0])
    np.testing.assert_array_equal(bunny.cast_capsules(placed, t[:, :, 1] - t[:, :, 0], any=True), np.isfinite(linear.t))
    for i in range(4):
        for j in range(5):  # each row alone: the same answer
            one = bunny.cast_capsules_rigid(capsules[i, j], starts[i, j], ends[i, j])
            assert one.t.shape == ()
            np.testing.assert_array_equal(one.t, hits.t[i, j])
            np.testing.assert_array_equal(one.point_mesh, hits.point_mesh[i, j])


def test_bad_rigid_input_names_the_argument_and_the_row():
    cube = unit_cube()
    sphere = [[0, 0, 0, 0.1], [0, 0, 0, 0.1]]
    good = pose_rows(IDENTITY, [[0, 0, 2], [0, 0, 3]])
    with pytest.raises(ValueError, match=r"starts: expected shape \(2, 4, 4\) or \(2, 7\), got \(3, 7\)"):
        cube.cast_spheres_rigid(sphere, pose_rows(IDENTITY, np.zeros((3, 3))), good)
    bad = good.copy()
    bad[1, 5] = np.nan
    with pytest.raises(ValueError, match=r"ends\[1\]"):
        cube.cast_spheres_rigid(sphere, good, bad)
    skew = np.array([matrix(IDENTITY, [0, 0, 2])] * 2)
    skew[1, 0, 1] = 0.5
    with pytest.raises(ValueError, match=r"starts\[1\]: the 3x3 block of a 4x4 pose must be a rotation"):
        cube.cast_spheres_rigid(sphere, skew, good)
    with pytest.raises(ValueError, match="spheres"):
        cube.cast_spheres_rigid([[0, 0, 0, -1], [0, 0, 0, 1]], good, good)
    with pytest.raises(ValueError, match="ends: expected an array of poses, got None"):
        cube.cast_spheres_rigid(sphere, good, None)


# ---- casts against a Scene


def scene_of_two_cubes():
    cube = unit_cube()
    scene = crux.Scene()
    scene.add(cube)                                       # model 0: [0, 1]^3
    scene.add(cube, (quat_z(np.pi / 2), [4.0, 0, 0]))     # model 1: [3, 4] x [0, 1] x [0, 1]
    return scene, cube


def test_scene_casts_name_the_model_hit_first():
    scene, _ = scene_of_two_cubes()
    # spheres of radius 0.25 moving along +x at heights inside both cubes' range
    spheres = np.array([[-1.0, 0.5, 0.5, 0.25], [2.0, 0.5, 0.5, 0.25], [-1.0, 0.5, 3.0, 0.25], [0.5, 0.5, 1.05, 0.1]])
    motions = np.array([[6.0, 0, 0], [2.0, 0, 0], [6.0, 0, 0], [0.0, 0, 0]])
    hits = scene.cast_spheres(spheres, motions)
    assert isinstance(hits, crux.SceneCastHits)
    np.testing.assert_array_equal(hits.model, [0, 1, -1, 0])
    np.testing.assert_allclose(hits.t[:2], [0.75 / 6, 0.75 / 2], atol=T_TOL)
    np.testing.assert_allclose(hits.normal[:2], [[-1, 0, 0], [-1, 0, 0]], atol=1e-3)
    assert np.isinf(hits.t[2]) and hits.triangle[2] == -1 and np.isnan(hits.point_mesh[2]).all()
    assert hits.t[3] == 0 and hits.starts_overlapping.tolist() == [False, False, False, True]
    np.testing.assert_array_equal(scene.cast_spheres(spheres, motions, any=True), [True, True, False, True])


def test_scene_casts_agree_with_the_mesh_casts_of_each_model(bunny):
    # models at translations only: a cast against the scene is the earliest of the casts against
    # each mesh with the shape moved into that model's frame
    scene = crux.Scene()
    lo, hi = bunny.bounds.astype(np.float64)
    offsets = np.array([[0, 0, 0], [1.5, 0, 0], [0, 1.5, 0]]) * (hi - lo)
    for o in offsets:
        scene.add(bunny, (IDENTITY, o))
    rng = np.random.default_rng(11)
    n = 200
    half = 0.03 * (hi - lo)
    centres = lo + rng.uniform(-0.5, 2.5, size=(n, 3)) * (hi - lo)
    motions = (rng.random((n, 3)) - 0.5) * 2 * (hi - lo)
    boxes = np.c_[centres, np.tile(half, (n, 1)), np.tile(np.eye(3).ravel(), (n, 1))]
    hits = scene.cast_obbs(boxes, motions)
    per_model = []
    for o in offsets:
        moved = boxes.copy()
        moved[:, :3] -= o
        per_model.append(bunny.cast_obbs(moved, motions).t)
    per_model = np.array(per_model)
    best = np.min(per_model, axis=0)
    hit = np.isfinite(best)
    assert 20 < hit.sum() < n - 20
    np.testing.assert_array_equal(hits.model >= 0, hit)
    np.testing.assert_allclose(hits.t[hit], best[hit], atol=T_TOL)
    ahead = hit & (np.sort(per_model, axis=0)[1] > best + 1e-3)  # no near tie between two models
    np.testing.assert_array_equal(hits.model[ahead], np.argmin(per_model, axis=0)[ahead])
    np.testing.assert_array_equal(scene.cast_obbs(boxes, motions, any=True), hit)


def test_scene_rigid_casts_agree_with_the_mesh_rigid_casts_of_a_model_at_the_origin(bunny):
    scene = crux.Scene()
    scene.add(bunny)
    rng = np.random.default_rng(12)
    lo, hi = bunny.bounds.astype(np.float64)
    n = 60
    q = rng.normal(size=(n, 2, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    t = lo + rng.uniform(-0.5, 1.5, size=(n, 2, 3)) * (hi - lo)
    starts, ends = np.c_[q[:, 0], t[:, 0]], np.c_[q[:, 1], t[:, 1]]
    capsules = np.tile(np.r_[[-1, 0, 0], [1, 0, 0], [0.3]] * 0.05 * np.linalg.norm(hi - lo), (n, 1))
    hits = scene.cast_capsules_rigid(capsules, starts, ends)
    mesh = bunny.cast_capsules_rigid(capsules, starts, ends)
    hit = np.isfinite(mesh.t)
    assert 5 < hit.sum() < n
    np.testing.assert_array_equal(hits.model, np.where(hit, 0, -1))
    np.testing.assert_allclose(hits.t[hit], mesh.t[hit], atol=T_TOL)
    np.testing.assert_array_equal(scene.cast_capsules_rigid(capsules, starts, ends, any=True), hit)
    many = scene.cast_capsules_rigid(capsules, starts, ends, threads=2)
    for a, b in zip(hits, many):
        np.testing.assert_array_equal(a, b)


def test_scene_cast_bad_input_raises():
    scene, _ = scene_of_two_cubes()
    with pytest.raises(ValueError, match="motions"):
        scene.cast_spheres([[0, 0, 2, 0.1]], [[0.0, np.inf, 0.0]])
    with pytest.raises(ValueError, match=r"obbs\[0\]"):
        scene.cast_obbs([np.r_[[2, 2, 2], [0.1, 0.1, 0.1], 2 * np.eye(3).ravel()]], [[-1.0, 0, 0]])
    with pytest.raises(ValueError, match="starts"):
        scene.cast_capsules_rigid([[0, 0, 0, 1, 0, 0, 0.1]], np.eye(4)[None] * 2, np.eye(4)[None])
    with pytest.raises(ValueError, match="threads"):
        scene.cast_spheres([[0, 0, 2, 0.1]], [[0.0, 0, 0]], threads=-1)


def test_pickled_meshes_and_scenes_cast_the_same():
    scene, cube = scene_of_two_cubes()
    rng = np.random.default_rng(13)
    n = 100
    spheres = np.c_[rng.uniform(-2, 6, size=(n, 3)), rng.uniform(0.05, 0.3, size=n)]
    motions = rng.normal(size=(n, 3)) * 3
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    starts, ends = pose_rows(IDENTITY, spheres[:, :3]), np.c_[q, spheres[:, :3] + motions]
    own = np.c_[np.zeros((n, 3)), spheres[:, 3]]
    for obj, call in [(scene, lambda o: o.cast_spheres(spheres, motions)),
                      (scene, lambda o: o.cast_spheres_rigid(own, starts, ends)),
                      (cube, lambda o: o.cast_spheres_rigid(own, starts, ends))]:
        before, after = call(obj), call(pickle.loads(pickle.dumps(obj)))
        assert np.isfinite(before.t).any()
        for a, b in zip(before, after):
            np.testing.assert_array_equal(a, b)
        restored = pickle.loads(pickle.dumps(before))  # the answer tuples pickle too
        assert type(restored) is type(before) and restored._fields == before._fields
