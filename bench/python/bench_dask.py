#!/usr/bin/env python3
"""crux.dask's scaling with the number of Dask workers: crux.dask.ray_closest over the same rays
on a local cluster of 1 worker, then of 2 (processes, one thread each, as docs/python.md says to
run a cluster), and the speedup.

The rays (bench_rays.py's: from a sphere of 3 bounding radii towards random points of the mesh's
bounds) are made in this process and persisted on the workers before timing, as data already on
the cluster (da.from_zarr etc.) would be; the mesh is given by path, loaded once per worker during
a warm-up. Two computations are timed (median of --runs):
  - answers: dask.compute(*hits), all four answers gathered into this process (the packed blocks
    cost 64 bytes per ray of transfer);
  - hit count: the number of hits, reduced on the workers (the rays' work alone).
Prints the load average before and after: on a machine shared with other work the speedup
measures that work too.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/python/bench_dask.py [--mesh PATH]
       [--rays N] [--chunk N] [--runs N] [--workers 1,2]
"""

import argparse
import os
import statistics
import time

import numpy as np

import crux
import crux.dask as cd
import dask
import dask.array as da
import distributed

from bench_rays import bench_rays


def load():
    return " ".join(open("/proc/loadavg").read().split()[:3]) if os.path.exists("/proc/loadavg") else "?"


def median_seconds(call, runs):
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times), times


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--mesh", default=os.path.join(here, "..", "..", "data", "meshes", "bunny00.off"))
    p.add_argument("--rays", type=int, default=4_000_000)
    p.add_argument("--chunk", type=int, default=250_000)
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--workers", default="1,2")
    a = p.parse_args()
    path = os.path.abspath(a.mesh)

    mesh = crux.Mesh.load(path)
    rays = bench_rays(mesh, a.rays, 1)
    start = time.perf_counter()
    mesh.ray_closest(rays, threads=1)
    print("%s: %d triangles; %d rays in chunks of %d; in process, 1 thread: %.2f s; load average %s"
          % (os.path.basename(path), len(mesh), a.rays, a.chunk, time.perf_counter() - start, load()))
    results = {}
    for n in [int(x) for x in a.workers.split(",")]:
        with distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                                      dashboard_address=None, worker_dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            d = da.from_array(rays, chunks=(a.chunk, 6)).persist()
            distributed.wait(d)
            # each run its own graph (max_distance differs, beyond every hit): dask would otherwise
            # hand back results of the previous run still held by the workers
            runs = iter(range(1, 4 * a.runs + 2))
            fresh = lambda: cd.ray_closest(path, d, max_distance=1e30 * next(runs))  # noqa: E731
            da.isfinite(fresh().t).sum().compute()  # warm-up: every worker loads the mesh
            answers, answer_runs = median_seconds(lambda: dask.compute(*fresh()), a.runs)
            counted, count_runs = median_seconds(lambda: da.isfinite(fresh().t).sum().compute(), a.runs)
            results[n] = (answers, counted)
            print("%d worker%s: answers %.2f s (%s), hit count %.2f s (%s); load average %s"
                  % (n, "s" if n > 1 else " ", answers, " ".join("%.2f" % t for t in answer_runs), counted,
                     " ".join("%.2f" % t for t in count_runs), load()))
    if 1 in results:
        for n, (answers, counted) in results.items():
            if n != 1:
                print("speedup of %d workers over 1: answers %.2fx, hit count %.2fx"
                      % (n, results[1][0] / answers, results[1][1] / counted))


if __name__ == "__main__":
    main()
