"""Tests of python/crux/world.py, and of the module against `crux batch`: the same inputs give
the same answers through the batch protocol (native backend: bit for bit), and the inside/outside
sign of contains() and signed_distance() equals the exact (CGAL) backend's on a grid around
closed meshes."""

import os

import numpy as np
import pytest

import crux
from conftest import random_points, random_rays, torus, unit_cube


def world_or_skip(backend):
    """A World of `backend`, or a skip when that backend is not built (its peer library missing)."""
    try:
        world = crux.World(backend)
        world.request("mesh", name="probe", vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles=[[0, 1, 2]])
    except (crux.WorldError, ValueError) as e:
        pytest.skip("the %s backend is not built: %s" % (backend, e))
    return world


@pytest.fixture(scope="module")
def native():
    with world_or_skip("native") as w:
        yield w


def test_mesh_rays_equal_crux_batch_bit_for_bit(native, bunny):
    native.add_mesh("bunny", bunny)
    rays = random_rays(bunny, 400, seed=21)
    answers = native.requests(
        [{"op": "mesh_ray", "mesh": "bunny", "ray": {"origin": r[:3], "dir": r[3:]}} for r in rays]
    )
    hits = bunny.ray_closest(rays)
    assert any(a["hit"] for a in answers) and not all(a["hit"] for a in answers)
    for i, a in enumerate(answers):
        assert a["hit"] == bool(np.isfinite(hits.t[i]))
        if a["hit"]:
            assert a["t"] == float(hits.t[i]) and a["triangle"] == hits.triangle[i]
            assert a["point"] == hits.point[i].astype(float).tolist()
            assert a["normal"] == hits.normal[i].astype(float).tolist()


def test_shape_overlaps_and_mesh_mesh_equal_crux_batch(native):
    mesh = torus()
    native.add_mesh("torus", mesh)
    rng = np.random.default_rng(4)
    spheres = np.c_[rng.uniform(-3, 3, size=(300, 3)), rng.uniform(0, 0.8, size=300)].astype(crux.REAL)
    answers = native.requests(
        [{"op": "mesh_sphere", "mesh": "torus", "sphere": {"center": s[:3], "radius": s[3]}} for s in spheres]
    )
    np.testing.assert_array_equal([a["hit"] for a in answers], mesh.overlaps_spheres(spheres))
    native.add_mesh("cube", unit_cube())
    for x in [0.5, 1.4, 1.9, 2.6, 3.0]:
        pose = (np.array([1.0, 0, 0, 0]), np.array([x, 0, 0]))
        batch = native.request("mesh_mesh", a="torus", b="cube", transform_b={"translation": [x, 0, 0]})
        assert batch["hit"] == crux.mesh_overlap(mesh, unit_cube(), pose_b=pose)


def test_rigid_and_linear_casts_equal_crux_batch(native, bunny):
    native.add_mesh("bunny", bunny)
    rng = np.random.default_rng(22)
    lo, hi = bunny.bounds.astype(np.float64)
    n = 80
    q = rng.normal(size=(n, 2, 4))
    q = (q / np.linalg.norm(q, axis=-1, keepdims=True)).astype(crux.REAL)
    t = (lo + rng.uniform(-0.5, 1.5, size=(n, 2, 3)) * (hi - lo)).astype(crux.REAL)
    half = (0.04 * (hi - lo)).astype(crux.REAL)
    box = np.r_[[0, 0, 0], half, np.eye(3).ravel()].astype(crux.REAL)
    starts, ends = np.c_[q[:, 0], t[:, 0]], np.c_[q[:, 1], t[:, 1]]
    rigid = bunny.cast_obbs_rigid(np.tile(box, (n, 1)), starts, ends)
    obb = {"box": {"center": [0, 0, 0], "half": half, "axes": np.eye(3)}}
    answers = native.requests(
        [{"op": "cast", "a": dict(obb, transform={"rotation": s[:4], "translation": s[4:]}),
          "end": {"rotation": e[:4], "translation": e[4:]}, "b": {"mesh": "bunny"}} for s, e in zip(starts, ends)]
    )
    spheres = np.c_[t[:, 0], np.full(n, half[0])].astype(crux.REAL)
    motions = (t[:, 1] - t[:, 0]).astype(crux.REAL)
    linear = bunny.cast_spheres(spheres, motions)
    answers += native.requests(
        [{"op": "cast", "a": {"sphere": {"center": s[:3], "radius": s[3]}}, "motion": m, "b": {"mesh": "bunny"}}
         for s, m in zip(spheres, motions)]
    )
    for hits, batch in [(rigid, answers[:n]), (linear, answers[n:])]:
        hit = np.array([a["hit"] for a in batch])
        assert 5 < hit.sum() < n
        np.testing.assert_array_equal(np.isfinite(hits.t), hit)
        for i, a in enumerate(batch):
            if a["hit"]:
                assert a["t"] == float(hits.t[i]) and a["triangle"] == hits.triangle[i]
                assert a["normal"] == hits.normal[i].astype(float).tolist()
                assert a["starts_overlapping"] == bool(hits.starts_overlapping[i])


def test_point_inside_sign_equals_the_exact_backend():
    with world_or_skip("exact") as exact:
        for name, mesh in [("cube", unit_cube(2.0)), ("torus", torus(16, 12))]:
            exact.add_mesh(name, mesh)
            lo, hi = mesh.bounds.astype(np.float64)
            axes = [np.linspace(l - 0.25 * (h - l), h + 0.25 * (h - l), 9) for l, h in zip(lo, hi)]
            grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3).astype(crux.REAL)
            grid = np.concatenate([grid, mesh.vertices, random_points(mesh, 100)])
            answers = exact.requests([{"op": "point_inside", "mesh": name, "point": p} for p in grid])
            inside = np.array([a["inside"] for a in answers])
            assert inside.any() and not inside.all()
            np.testing.assert_array_equal(mesh.contains(grid), inside)
            sd = mesh.signed_distance(grid)
            np.testing.assert_array_equal(np.signbit(sd), inside)


def test_error_answers_raise_and_unknown_backends_are_refused(native):
    with pytest.raises(ValueError, match="mesh"):
        native.request("mesh_ray", mesh="no such mesh", ray={"origin": [0, 0, 0], "dir": [1, 0, 0]})
    with pytest.raises(ValueError, match="dir"):
        native.request("ray_triangle", triangle=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], ray={"origin": [0, 0, 0], "dir": [0, 0, 0]})
    with pytest.raises(ValueError, match="backend"):
        crux.World("havok")


def test_unsupported_ops_raise_not_implemented():
    with world_or_skip("fcl") as fcl:
        with pytest.raises(NotImplementedError, match="unsupported: mesh_ray on fcl"):
            fcl.request("mesh_ray", mesh="probe", ray={"origin": [0, 0, 1], "dir": [0, 0, -1]})
        assert fcl.request("mesh_sphere", mesh="probe", sphere={"center": [0.2, 0.2, 0.5], "radius": 0.5})["hit"]


def test_scene_casts_equal_crux_batch_scene_cast(native, bunny):
    # three placed copies of bunny00 (one turned a quarter about z); linear and rigid box casts,
    # closest and any, against the same models added to crux batch
    lo, hi = bunny.bounds.astype(np.float64)
    native.add_mesh("bunny", bunny)
    scene = crux.Scene()
    h = np.sqrt(0.5)
    poses = [([1.0, 0, 0, 0], [0.0, 0, 0]), ([h, 0, 0, h], 1.5 * (hi - lo) * [1, 0, 0]),
             ([1.0, 0, 0, 0], 1.5 * (hi - lo) * [0, 1, 0])]
    for i, (q, t) in enumerate(poses):
        model = scene.add(bunny, (np.array(q), np.array(t)))
        native.request("add_model", name=f"m{model}", mesh="bunny",
                       transform={"rotation": list(q), "translation": list(map(float, t))})
    rng = np.random.default_rng(23)
    n = 60
    q = rng.normal(size=(n, 2, 4))
    q = (q / np.linalg.norm(q, axis=-1, keepdims=True)).astype(crux.REAL)
    t = (lo + rng.uniform(-0.5, 2.5, size=(n, 2, 3)) * (hi - lo)).astype(crux.REAL)
    half = (0.04 * (hi - lo)).astype(crux.REAL)
    box = np.tile(np.r_[[0, 0, 0], half, np.eye(3).ravel()].astype(crux.REAL), (n, 1))
    starts, ends = np.c_[q[:, 0], t[:, 0]], np.c_[q[:, 1], t[:, 1]]
    obb = {"box": {"center": [0, 0, 0], "half": half, "axes": np.eye(3)}}
    rigid = scene.cast_obbs_rigid(box, starts, ends)
    rigid_any = scene.cast_obbs_rigid(box, starts, ends, any=True)
    world_box = box.copy()
    world_box[:, :3] = t[:, 0]
    motions = (t[:, 1] - t[:, 0]).astype(crux.REAL)
    linear = scene.cast_obbs(world_box, motions)
    for end_field, hits, any_hits in [(True, rigid, rigid_any), (False, linear, None)]:
        requests = []
        for i in range(n):
            if end_field:
                requests.append({"op": "scene_cast", "a": dict(obb, transform={"rotation": starts[i, :4],
                                                                              "translation": starts[i, 4:]}),
                                 "end": {"rotation": ends[i, :4], "translation": ends[i, 4:]}})
            else:
                requests.append({"op": "scene_cast", "a": {"box": dict(obb["box"], center=world_box[i, :3])},
                                 "motion": motions[i]})
        answers = native.requests(requests)
        hit = np.array([a["hit"] for a in answers])
        assert 5 < hit.sum() < n
        np.testing.assert_array_equal(hits.model >= 0, hit)
        for i, a in enumerate(answers):
            if a["hit"]:
                assert a["model"] == f"m{hits.model[i]}"
                assert a["t"] == float(hits.t[i]) and a["triangle"] == hits.triangle[i]
        if any_hits is not None:
            answers = native.requests([dict(r, any=True) for r in requests])
            np.testing.assert_array_equal(any_hits, [a["hit"] for a in answers])
