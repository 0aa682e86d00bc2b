#!/usr/bin/env python3
"""crux's Python module against Open3D's RaycastingScene (Embree inside), in one process, on the
same mesh, rays and points: cast rays, occlusion, distance, signed distance, occupancy.

Answers are checked first (counts of disagreements, with the cause where known) and each row gets
a verdict: "agree", "O3D wrong" (inside/outside only: Open3D's crossing count along its own
parity ray differs from crux's exact one at every point that differs) or "DIFFER". Then each row
is timed (median of --runs runs, both libraries on all cores) and the Open3D/crux time ratio is
printed (> 1: crux is faster). Needs Debian's python3-open3d (0.16; `CRUX_SETUP_OPEN3D=1
scripts/setup` installs it), which is too heavy for CI: this bench is not part of CI
(tests/python/test_open3d.py checks the same agreement on small meshes where Open3D is installed).

Open3D < 0.19 over an Embree built with ray masks (Debian's) hits nothing; open3d_peer.py loads
crux's shim for that before importing Open3D (bench/python/open3d_embree_mask.c), and the first
line of the output says whether it did.

Units: Open3D's t_hit is in units of the ray's direction as given (the rays here are not unit),
crux's t is the distance along the ray; the check compares t_hit * |direction| with crux's t.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/python/bench_open3d.py [--mesh PATH]
       [--rays N] [--points N] [--runs N] [--seed N]
"""

import argparse
import os
import statistics
import sys
import time

import numpy as np

import crux
from open3d_peer import import_open3d

try:
    o3d, SHIM = import_open3d()
except ImportError:
    sys.exit("bench_open3d: needs python3-open3d (CRUX_SETUP_OPEN3D=1 scripts/setup)")


def median_seconds(call, runs):
    call()  # warm up
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def verdict_inside(mesh, scene, points, differ):
    """"agree" when no point differs; "O3D wrong" when at every differing point Open3D's crossing
    count along its own parity ray, (1, 1, 1) from the point, differs from crux's exact count along
    that ray (a crossing through a shared edge counted twice or not at all); else "DIFFER"."""
    if not differ.any():
        return "agree"
    p = points[differ][:1000].astype(np.float32)
    parity_rays = np.hstack([p, np.ones_like(p)]).astype(np.float32)
    o3d_count = scene.count_intersections(o3d.core.Tensor(parity_rays)).numpy()
    crux_count = np.diff(mesh.ray_all(parity_rays).offsets)
    distance = mesh.closest_point(p).distance
    for i in range(min(len(p), 5)):
        print("  point %s, %.3g from the surface: along (1, 1, 1) Open3D counts %d crossings, crux %d"
              % (p[i].tolist(), distance[i], o3d_count[i], crux_count[i]))
    explained = (o3d_count != crux_count) & ((crux_count % 2 == 1) == mesh.contains(p))
    return "O3D wrong" if explained.all() and differ.sum() <= len(p) else "DIFFER"


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--mesh", default=os.path.join(here, "..", "..", "data", "meshes", "bunny00.off"))
    p.add_argument("--rays", type=int, default=1_000_000)
    p.add_argument("--points", type=int, default=200_000)
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--seed", type=int, default=1)
    a = p.parse_args()

    mesh = crux.Mesh.load(a.mesh)
    v, f = mesh.vertices.astype(np.float32), mesh.triangles.astype(np.uint32)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(v), o3d.core.Tensor(f))

    rng = np.random.default_rng(a.seed)
    lo, hi = mesh.bounds.astype(np.float64)
    center, radius = (lo + hi) / 2, np.linalg.norm(hi - lo)
    d = rng.normal(size=(a.rays, 3))
    origins = center + radius * d / np.linalg.norm(d, axis=1, keepdims=True)
    targets = lo + (hi - lo) * rng.uniform(-0.1, 1.1, size=(a.rays, 3))
    rays = crux.rays(origins, targets - origins).astype(np.float32)
    points = (lo + (hi - lo) * rng.uniform(-0.2, 1.2, size=(a.points, 3))).astype(np.float32)
    o3d_rays, o3d_points = o3d.core.Tensor(rays), o3d.core.Tensor(points)

    print("Open3D %s; Embree ray-mask shim: %s" % (o3d.__version__, SHIM))
    print("mesh %s: %d triangles, closed %s; %d rays, %d points; crux REAL %s; load average %.2f"
          % (a.mesh, len(mesh), mesh.closed, a.rays, a.points, crux.REAL, os.getloadavg()[0]))

    # ---- answers first: a verdict per row (the ratio of a row whose answers differ means little)
    scale = float(np.abs(mesh.bounds).max())
    verdict = {}
    hits = mesh.ray_closest(rays)
    # Open3D's t_hit counts lengths of the direction as given; as a distance it is t_hit * |d|
    # (|d| in float64 of the float32 rows both libraries read).
    t_o3d = scene.cast_rays(o3d_rays)["t_hit"].numpy() * np.linalg.norm(rays[:, 3:].astype(np.float64), axis=1)
    hit_crux, hit_o3d = np.isfinite(hits.t), np.isfinite(t_o3d)
    both = hit_crux & hit_o3d
    rel = np.abs(t_o3d[both] - hits.t[both]) / np.maximum(hits.t[both], 1e-30)
    print("cast rays: %d hits by crux, %d by Open3D; hit/miss differ on %d rays; distance relative difference max %.2e"
          % (hit_crux.sum(), hit_o3d.sum(), (hit_crux != hit_o3d).sum(), rel.max() if rel.size else np.nan))
    verdict["cast rays"] = (hit_crux == hit_o3d).all() and (rel.size == 0 or rel.max() <= 1e-5)
    if hit_crux.any() and not hit_o3d.any():
        print("  Open3D hit nothing at all (shim: %s): its ray queries are broken in this build (Embree"
              " with ray masks, Open3D < 0.19 giving rays mask 0: open3d_embree_mask.c); the ray rows,"
              " the signed distance's sign and occupancy below compare against that" % SHIM)
    occl = scene.test_occlusions(o3d_rays).numpy().astype(bool)
    verdict["occlusion"] = (occl == mesh.ray_any(rays)).all()
    print("occlusion: differs on %d rays" % (occl != mesh.ray_any(rays)).sum())
    dist = mesh.closest_point(points).distance
    o3d_dist = scene.compute_distance(o3d_points).numpy()
    err = np.abs(dist - o3d_dist).max()
    verdict["distance"] = err <= 1e-5 * scale
    print("distance: max |difference| %.2e" % err)
    if mesh.closed:
        # Open3D decides inside by the parity of count_intersections along one ray per point, of
        # direction (1, 1, 1), in float (RaycastingScene::ComputeOccupancy / ComputeSignedDistance).
        inside = mesh.contains(points)
        sd = mesh.signed_distance(points)
        o3d_sd = scene.compute_signed_distance(o3d_points).numpy()
        sign = np.signbit(sd) != np.signbit(o3d_sd)
        magnitude = np.abs(np.abs(sd) - np.abs(o3d_sd)).max()
        print("signed distance: sign differs on %d points, max |difference| %.2e" % (sign.sum(), magnitude))
        verdict["signed distance"] = verdict_inside(mesh, scene, points, sign) if magnitude <= 1e-5 * scale else False
        occ = scene.compute_occupancy(o3d_points).numpy().astype(bool)
        print("occupancy: differs on %d points (crux: exact ray parity)" % (occ != inside).sum())
        verdict["occupancy"] = verdict_inside(mesh, scene, points, occ != inside)

    # ---- then time
    rows = [
        ("cast rays", lambda: mesh.ray_closest(rays), lambda: scene.cast_rays(o3d_rays), a.rays),
        ("occlusion", lambda: mesh.ray_any(rays), lambda: scene.test_occlusions(o3d_rays), a.rays),
        ("distance", lambda: mesh.closest_point(points), lambda: scene.compute_distance(o3d_points), a.points),
    ]
    if mesh.closed:
        rows += [
            ("signed distance", lambda: mesh.signed_distance(points),
             lambda: scene.compute_signed_distance(o3d_points), a.points),
            ("occupancy", lambda: mesh.contains(points), lambda: scene.compute_occupancy(o3d_points), a.points),
        ]
    print("%-16s %14s %14s %10s  %s" % ("row", "crux ns/query", "Open3D ns/q", "O3D/crux", "answers"))
    for name, crux_call, o3d_call, n in rows:
        tc, to = median_seconds(crux_call, a.runs), median_seconds(o3d_call, a.runs)
        print("%-16s %14.1f %14.1f %10.2f  %s"
              % (name, 1e9 * tc / n, 1e9 * to / n, to / tc, verdict[name] if isinstance(verdict[name], str) else "agree" if verdict[name] else "DIFFER"))


if __name__ == "__main__":
    main()
