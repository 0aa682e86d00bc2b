#!/usr/bin/env python3
"""crux's Python batch rays against crux's C++ batch API, in one process, on the same mesh and
rays: closest hits on one thread (Mesh.ray_closest(rays, threads=1) against C++'s
raycastClosest(mesh, Span<const Ray>, Span<std::optional<MeshRayHit>>) into a reused vector,
timed inside the extension: crux._crux._ray_closest_reference_seconds).

The rays are bench_parallel's: from a sphere of 3 bounding radii towards random points of the
mesh's bounds, float32 (crux.REAL) rows read in place. The two are timed alternately, run by run;
the figure is the Python/C++ ratio of the median times per ray (1.00: no overhead). Answers are
checked first (Python's equal the single queries bit for bit: the same function per ray).

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/python/bench_rays.py [--mesh PATH]
       [--rays N] [--runs N] [--seed N]
"""

import argparse
import os
import statistics
import time

import numpy as np

import crux
from crux import _crux


def bench_rays(mesh, n, seed):
    """bench_parallel's rays (bench/bench_parallel.cpp) with numpy's generator."""
    rng = np.random.default_rng(seed)
    lo, hi = mesh.bounds.astype(np.float64)
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    d = rng.normal(size=(n, 3))
    origins = centre + 3 * radius * d / np.linalg.norm(d, axis=1, keepdims=True)
    targets = lo + (hi - lo) * rng.random((n, 3))
    return crux.rays(origins, targets - origins)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--mesh", default=os.path.join(here, "..", "..", "data", "meshes", "bunny00.off"))
    p.add_argument("--rays", type=int, default=1_000_000)
    p.add_argument("--runs", type=int, default=7)
    p.add_argument("--seed", type=int, default=1)
    a = p.parse_args()

    mesh = crux.Mesh.load(a.mesh)
    rays = bench_rays(mesh, a.rays, a.seed)
    assert rays.dtype == crux.REAL and rays.flags.c_contiguous
    hits = mesh.ray_closest(rays, threads=1)  # also the warm-up
    check = np.random.default_rng(a.seed).integers(0, a.rays, 1000)
    for i in check:
        one = mesh.ray_closest(rays[i], threads=1)
        assert one.t == hits.t[i] and one.triangle == hits.triangle[i]
    _crux._ray_closest_reference_seconds(mesh, rays, 1)  # warm-up

    python, cpp = [], []
    for _ in range(a.runs):
        start = time.perf_counter()
        mesh.ray_closest(rays, threads=1)
        python.append(time.perf_counter() - start)
        cpp.extend(_crux._ray_closest_reference_seconds(mesh, rays, 1))
    ns = lambda s: 1e9 * statistics.median(s) / a.rays  # noqa: E731
    load = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else ["?"]
    print("mesh %s: %d triangles; %d rays, hit rate %.1f%%; %d runs; load average %s"
          % (os.path.basename(a.mesh), len(mesh), a.rays, 100 * np.isfinite(hits.t).mean(), a.runs, " ".join(load)))
    print("%-34s %8.1f ns/ray  (runs: %s)" % ("Python Mesh.ray_closest", ns(python),
                                               " ".join("%.0f" % (1e9 * s / a.rays) for s in python)))
    print("%-34s %8.1f ns/ray  (runs: %s)" % ("C++ batch raycastClosest", ns(cpp),
                                               " ".join("%.0f" % (1e9 * s / a.rays) for s in cpp)))
    print("Python / C++: %.3f" % (statistics.median(python) / statistics.median(cpp)))


if __name__ == "__main__":
    main()
