"""Tests of python/src/scene_bindings.cpp: crux.Scene's models and poses, batched rays and region
queries against the per-mesh answers, the overlapping pairs, and pickling."""

import numpy as np
import pytest

import crux
from conftest import evaluate_in_child, random_rays, torus, unit_cube


def quat_z(angle):
    return np.array([np.cos(angle / 2), 0, 0, np.sin(angle / 2)])


def scene_of_cubes():
    cube = unit_cube()
    s = crux.Scene()
    a = s.add(cube)
    b = s.add(cube, (quat_z(0), [1.0, 0, 0]))  # touches a along x = 1
    m = np.eye(4)
    m[:3, 3] = [5, 0, 0]
    c = s.add(cube, m)
    return s, cube, (a, b, c)


def test_models_and_poses():
    s, cube, (a, b, c) = scene_of_cubes()
    assert len(s) == 3 and s.ids().tolist() == [a, b, c]
    np.testing.assert_array_equal(s.world_pose(c)[:3, 3], [5, 0, 0])
    d = s.add(cube, np.r_[quat_z(0), [0, 2, 0]], parent=c)
    np.testing.assert_allclose(s.world_pose(d)[:3, 3], [5, 2, 0])
    assert s.parent(d) == c and s.parent(a) is None and s.mesh(d) is cube
    s.set_parent(d, None)
    np.testing.assert_allclose(s.world_pose(d)[:3, 3], [5, 2, 0])
    s.remove(d)
    assert len(s) == 3
    with pytest.raises(ValueError):
        s.pose(d)


def test_scene_rays_hit_the_nearest_model():
    s, cube, (a, b, c) = scene_of_cubes()
    rays = np.array([[-3, 0.5, 0.5, 1, 0, 0], [9, 0.5, 0.5, -1, 0, 0], [0.5, 0.5, 9, 0, 0, -1], [0, 9, 0, 0, 1, 0]])
    h = s.ray_closest(rays.reshape(2, 2, 6))
    assert h.model.shape == (2, 2)
    assert h.model.ravel().tolist() == [a, c, a, -1]
    np.testing.assert_array_equal(h.t.ravel()[:3], [3, 3, 8])
    assert np.isinf(h.t.ravel()[3])


def test_scene_rays_equal_each_models_own_answer():
    mesh = torus()
    s = crux.Scene()
    rng = np.random.default_rng(1)
    poses = []
    for i in range(6):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        t = rng.uniform(-6, 6, size=3)
        poses.append((q, t))
        s.add(mesh, (q, t))
    rays = crux.rays(rng.uniform(-12, 12, size=(3000, 3)), rng.normal(size=(3000, 3)))
    h = s.ray_closest(rays)
    assert (h.model >= 0).sum() > 100
    # each hit's model, seen alone, gives the same t
    for model in range(6):
        solo = crux.Scene()
        solo.add(mesh, poses[model])
        mine = h.model == model
        np.testing.assert_array_equal(solo.ray_closest(rays[mine]).t, h.t[mine])


def test_set_transforms_moves_many_models_at_once():
    s, cube, (a, b, c) = scene_of_cubes()
    poses = np.zeros((2, 7))
    poses[:, 0] = 1
    poses[0, 4:] = [0, 10, 0]
    poses[1, 4:] = [0, 20, 0]
    s.set_transforms([a, c], poses)
    np.testing.assert_array_equal(s.world_pose(c)[:3, 3], [0, 20, 0])
    mats = np.stack([np.eye(4), np.eye(4)])
    with pytest.raises(ValueError):
        s.set_transforms([a, 99], mats)  # unknown id: nothing moves
    np.testing.assert_array_equal(s.world_pose(a)[:3, 3], [0, 10, 0])
    s.set_transforms(np.array([a, c]), mats)
    np.testing.assert_array_equal(s.world_pose(a)[:3, 3], [0, 0, 0])


def test_region_queries_and_overlapping_pairs():
    s, cube, (a, b, c) = scene_of_cubes()
    spheres = np.array([[0.5, 0.5, 0.5, 0.1], [1.0, 0.5, 0.5, 0.1], [5.5, 0.5, 2.0, 1.0], [3, 3, 3, 0.1]])
    r = s.query_spheres(spheres)
    assert r.offsets.tolist() == [0, 0, 2, 3, 3]
    assert r.models.tolist() == [a, b, c]
    assert s.query_spheres(spheres, bounds_only=True).models.tolist() == [a, a, b, c]
    boxes = np.array([[0.9, 0, 0, 1.1, 1, 1]])
    assert s.query_aabbs(boxes).models.tolist() == [a, b]
    obbs = np.array([np.r_[[5.5, 0.5, 0.5], [0.1, 0.1, 0.1], np.eye(3).ravel()]])
    assert s.query_obbs(obbs).models.tolist() == []  # inside c: surfaces only
    pairs = s.overlapping_pairs()
    assert pairs.shape == (1, 2) and pairs.tolist() == [[a, b]]
    assert s.overlapping_pairs(bounds_only=True).tolist() == [[a, b]]


def test_scene_pickle_round_trip_in_a_child_process():
    s, cube, (a, b, c) = scene_of_cubes()
    d = s.add(torus(), (quat_z(0.3), [0, 0, 4]), parent=c)
    s.remove(b)  # a gap in the ids
    rays = random_rays(torus(), 1000, seed=2) * np.r_[3, 3, 3, 1, 1, 1].astype(crux.REAL)
    out = evaluate_in_child(s, rays, {
        "model": "obj.ray_closest(rays).model", "t": "obj.ray_closest(rays).t", "ids": "obj.ids()",
        "poses": "np.stack([obj.world_pose(i) for i in obj.ids()])", "pairs": "obj.overlapping_pairs()",
    })
    h = s.ray_closest(rays)
    np.testing.assert_array_equal(out["model"], h.model)
    np.testing.assert_array_equal(out["t"], h.t)
    np.testing.assert_array_equal(out["ids"], [a, c, d])
    np.testing.assert_array_equal(out["poses"], np.stack([s.world_pose(i) for i in s.ids()]))
    np.testing.assert_array_equal(out["pairs"], s.overlapping_pairs())
    assert (h.model == d).any()


def test_model_ids_of_the_wrong_type_raise_type_error():
    s, cube, (a, b, c) = scene_of_cubes()
    for bad in (1.0, "0", np.float64(1), True, [0]):
        with pytest.raises(TypeError):
            s.pose(bad)
        with pytest.raises(TypeError):
            s.remove(bad)
        with pytest.raises(TypeError):
            s.add(cube, parent=bad)
    with pytest.raises(ValueError):
        s.world_pose(2**64)  # an int, but no model
    assert s.pose(np.int64(a)).shape == (4, 4)  # numpy integers are ids
    with pytest.raises(TypeError):
        s.add(None)  # segfaulted
    assert len(s) == 3


def test_set_transforms_refuses_ids_that_are_not_integers():
    s, cube, (a, b, c) = scene_of_cubes()
    before = [s.world_pose(i) for i in (a, b, c)]
    pose = [[1.0, 0, 0, 0, 50, 0, 0]]
    for bad in ([0.9], np.array([True]), np.array(["0"])):
        with pytest.raises(ValueError, match="ids: expected a 1-D integer array"):
            s.set_transforms(bad, pose)
    for i, p in zip((a, b, c), before):
        np.testing.assert_array_equal(s.world_pose(i), p)


def test_a_malformed_scene_pickle_raises():
    s, cube, _ = scene_of_cubes()
    cls, (state,) = s.__reduce__()
    assert len(cls(state)) == len(s)
    pose = state[0][0][2]
    for bad in ([(0, None, pose, None)], [(0, "not a mesh", pose, None)], [(0, cube)], [[0, cube, pose, None]],
                [(-1, cube, pose, None)], [(2**32 - 1, cube, pose, None)], [(0, cube, pose, None)] * 2,
                [(0, cube, pose, 7)]):
        with pytest.raises(ValueError):
            cls((bad,))  # None as the mesh segfaulted; 2**32 - 1 never ended
    for bad in ([(0.5, cube, pose, None)], [(0, cube, pose, "0")]):
        with pytest.raises(TypeError):
            cls((bad,))
    with pytest.raises(ValueError):
        cls((tuple(state[0]),))  # models must be a list

