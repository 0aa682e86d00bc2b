"""Shape casts against a mesh from Python (Mesh.cast_spheres / cast_capsules / cast_obbs: C++'s
castClosest of mesh_cast.hpp in batches): times of impact, contact data, misses, leading
dimensions, bad input."""

import numpy as np
import pytest

import crux
from conftest import unit_cube

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
