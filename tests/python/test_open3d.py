"""crux against Open3D's RaycastingScene (Embree inside) on small closed meshes, in one process:
cast rays, occlusion, distance, signed distance, occupancy (bench/python/bench_open3d.py times the
same queries on bunny00).

Skipped when Open3D is not importable (python3-open3d is opt-in: CRUX_SETUP_OPEN3D=1
scripts/setup). Open3D is imported through bench/python/open3d_peer.py, which loads crux's Embree
ray-mask shim first when this Open3D and Embree need it (Open3D < 0.19 gives rays mask 0); without
the shim such a build hits nothing, and the ray tests skip saying so.

Tolerances, with eps = float32's machine epsilon (Open3D computes in float32 whatever crux.REAL
is). Ray distances: Open3D's t_hit is in units of the direction as given, so t_hit * |d| is
compared with crux's t, within 32 eps (|o|_inf + t): the rounding of a float32 hit point at that
distance from an origin of that size, with room for the arithmetic of both (measured: 6.5 eps on
the torus, 0.9 on the cube). Point distances: within 8 eps (|p|_inf + d) (measured: 1.2).
Hit/miss, occlusion and triangle ids must be equal on every ray: a random ray passes within
rounding of an edge with probability ~1e-7. Inside/outside must be equal for points farther than
1e-4 of the mesh's extent from the surface: Open3D decides by ray parity in float32, crux exactly,
and only nearer points may legitimately differ.
"""

import os
import sys

import numpy as np
import pytest

from conftest import SOURCE_DIR, random_points, random_rays, torus, unit_cube

sys.path.insert(0, os.path.join(SOURCE_DIR, "bench", "python"))
from open3d_peer import import_open3d  # noqa: E402

# Without Open3D every test is collected and skipped (a module-level skip collects nothing, and
# pytest's exit status for that, 5, fails the CTest test).
try:
    o3d, SHIM = import_open3d()
except ImportError:
    o3d, SHIM = None, "absent"
pytestmark = pytest.mark.skipif(
    o3d is None, reason="open3d is not importable (python3-open3d: CRUX_SETUP_OPEN3D=1 scripts/setup)")

EPS = float(np.finfo(np.float32).eps)
RAY_TOLERANCE = 32   # in eps (|o|_inf + t)
POINT_TOLERANCE = 8  # in eps (|p|_inf + d)
SURFACE_MARGIN = 1e-4  # of the mesh's extent

needs_rays = pytest.mark.skipif(
    SHIM in ("missing", "too late"),
    reason="Open3D %s gives Embree rays mask 0 and this Embree honours ray masks, so its ray queries "
           "hit nothing; crux's shim for that (bench/python/open3d_embree_mask.c, built when "
           "libembree-dev is installed) is %s"
           % (getattr(o3d, "__version__", "?"), "not built" if SHIM == "missing" else "loaded too late"))

MESHES = {"torus": torus, "cube": unit_cube}


@pytest.fixture(scope="module", params=sorted(MESHES))
def pair(request):
    """A crux mesh and an Open3D scene of the same float32 vertices and triangles."""
    mesh = MESHES[request.param]()
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(np.asarray(mesh.vertices, np.float32)),
                        o3d.core.Tensor(np.asarray(mesh.triangles, np.uint32)))
    return mesh, scene


def rays_of(mesh, n=20000):
    """Seeded rays from around the mesh to points of its bounds; directions not unit."""
    return random_rays(mesh, n).astype(np.float32)


def points_of(mesh, n=20000):
    return random_points(mesh, n).astype(np.float32)


@needs_rays
def test_cast_rays_hit_the_same_triangles_at_the_same_distances(pair):
    mesh, scene = pair
    rays = rays_of(mesh)
    hits = mesh.ray_closest(rays)
    answer = scene.cast_rays(o3d.core.Tensor(rays))
    t = answer["t_hit"].numpy() * np.linalg.norm(rays[:, 3:].astype(np.float64), axis=1)
    hit = np.isfinite(hits.t)
    assert 0.2 < hit.mean() < 0.9  # both hits and misses are tested
    np.testing.assert_array_equal(np.isfinite(t), hit)
    np.testing.assert_array_equal(answer["primitive_ids"].numpy()[hit].astype(np.int64), hits.triangle[hit])
    scale = np.abs(rays[hit, :3]).max(axis=1) + hits.t[hit]
    assert (np.abs(t[hit] - hits.t[hit]) <= RAY_TOLERANCE * EPS * scale).all()


@needs_rays
def test_occlusion_is_ray_any(pair):
    mesh, scene = pair
    rays = rays_of(mesh)
    np.testing.assert_array_equal(scene.test_occlusions(o3d.core.Tensor(rays)).numpy().astype(bool),
                                  mesh.ray_any(rays))


def test_distance_is_the_closest_point_distance(pair):
    mesh, scene = pair
    points = points_of(mesh)
    d = mesh.closest_point(points).distance
    o3d_d = scene.compute_distance(o3d.core.Tensor(points)).numpy()
    scale = np.abs(points).max(axis=1) + d
    assert (np.abs(o3d_d - d) <= POINT_TOLERANCE * EPS * scale).all()


def away_from_surface(mesh, points):
    """The points farther than SURFACE_MARGIN of the mesh's extent from its surface."""
    lo, hi = mesh.bounds.astype(np.float64)
    away = mesh.closest_point(points).distance > SURFACE_MARGIN * np.linalg.norm(hi - lo)
    assert away.mean() > 0.99
    return away


@needs_rays
def test_signed_distance_has_the_same_sign_and_magnitude(pair):
    mesh, scene = pair
    points = points_of(mesh)
    sd = mesh.signed_distance(points)
    o3d_sd = scene.compute_signed_distance(o3d.core.Tensor(points)).numpy()
    away = away_from_surface(mesh, points)
    assert 0.05 < (sd < 0).mean() < 0.95  # negative inside in both: both signs are tested
    np.testing.assert_array_equal(np.signbit(o3d_sd[away]), np.signbit(sd[away]))
    scale = np.abs(points).max(axis=1) + np.abs(sd)
    assert (np.abs(np.abs(o3d_sd) - np.abs(sd)) <= POINT_TOLERANCE * EPS * scale).all()


@needs_rays
def test_occupancy_is_contains(pair):
    mesh, scene = pair
    points = points_of(mesh)
    inside = mesh.contains(points)
    occupancy = scene.compute_occupancy(o3d.core.Tensor(points)).numpy()
    assert set(np.unique(occupancy)) <= {0.0, 1.0}
    away = away_from_surface(mesh, points)
    np.testing.assert_array_equal(occupancy[away] == 1.0, inside[away])
