#!/usr/bin/env python3
"""crux.dask's scaling with the number of Dask workers: crux.dask.ray_closest over the same rays
on a local cluster of 1 worker, then of 2 (processes, one thread each, as docs/python.md says to
run a cluster), and the speedup.

The rays (bench_rays.py's: from a sphere of 3 bounding radii towards random points of the mesh's
bounds) are made in this process and scattered over the workers before timing, as data already on
the cluster (da.from_zarr etc.) would be; the mesh is given by path, loaded once per worker during
a warm-up. Two computations are timed (median and best of --runs):
  - answers: dask.compute(*hits), all four answers gathered into this process (36 bytes per ray
    of transfer: t, triangle as int64, point, normal);
  - hit count: the number of hits, reduced on the workers (the rays' work alone).
The control: the same rays in this process on crux's own 1 and 2 threads. On a machine shared
with other work, the workers' speedup cannot exceed that one; the load average is printed too.

The workers start without Dask's default MALLOC_TRIM_THRESHOLD_=65536 (its nanny's
pre-spawn-environ), as docs/python.md advises for crux workers: any explicit malloc threshold turns
off glibc's adaptive mmap threshold, so every answer array becomes fresh pages to fault in, which
made each crux call ~45 % slower in a worker than in this process. --dask-malloc-trim keeps
Dask's default, to measure that.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/python/bench_dask.py [--mesh PATH]
       [--rays N] [--chunk N] [--runs N] [--workers 1,2] [--dask-malloc-trim]
"""

import argparse
import os
import statistics
import time


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
    p.add_argument("--dask-malloc-trim", action="store_true", help="keep Dask's MALLOC_TRIM_THRESHOLD_ for the workers")
    a = p.parse_args()
    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ"))
    if not a.dask_malloc_trim:
        environ.pop("MALLOC_TRIM_THRESHOLD_", None)
    dask.config.set({"distributed.nanny.pre-spawn-environ": environ})
    path = os.path.abspath(a.mesh)

    mesh = crux.Mesh.load(path)
    rays = bench_rays(mesh, a.rays, 1)
    # the control: crux's own threads in this process, 1 then 2 (what 2 cores give right now)
    one, _ = median_seconds(lambda: mesh.ray_closest(rays, threads=1), 1)
    two, _ = median_seconds(lambda: mesh.ray_closest(rays, threads=2), 1)
    print("%s: %d triangles; %d rays in chunks of %d; in process: 1 thread %.2f s, 2 threads %.2f s (%.2fx);"
          " load average %s" % (os.path.basename(path), len(mesh), a.rays, a.chunk, one, two, one / two, load()))
    print("workers' MALLOC_TRIM_THRESHOLD_: %s" % environ.get("MALLOC_TRIM_THRESHOLD_", "unset (glibc's adaptive thresholds)"))
    results = {}
    for n in [int(x) for x in a.workers.split(",")]:
        with distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                                      dashboard_address=None, worker_dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            # the chunks scattered round robin over the workers (persisting da.from_array would leave
            # them all on the worker that held the whole array, and locality would keep the work there)
            pieces = [rays[i:i + a.chunk] for i in range(0, a.rays, a.chunk)]
            futures = client.scatter(pieces)
            d = da.concatenate([da.from_delayed(dask.delayed(f), shape=c.shape, dtype=c.dtype)
                                for f, c in zip(futures, pieces)])
            held = client.who_has(futures)
            per_worker = {w: sum(1 for ws in held.values() if w in ws) for w in client.scheduler_info()["workers"]}
            # each run its own graph (max_distance differs, beyond every hit): dask would otherwise
            # hand back results of the previous run still held by the workers
            runs = iter(range(1, 4 * a.runs + 2))
            fresh = lambda: cd.ray_closest(path, d, max_distance=1e30 * next(runs))  # noqa: E731
            da.isfinite(fresh().t).sum().compute()  # warm-up: every worker loads the mesh
            answers, answer_runs = median_seconds(lambda: dask.compute(*fresh()), a.runs)
            counted, count_runs = median_seconds(lambda: da.isfinite(fresh().t).sum().compute(), a.runs)
            results[n] = (answers, counted, min(answer_runs), min(count_runs))
            print("%d worker%s (chunks per worker %s): answers %.2f s (%s), hit count %.2f s (%s); load average %s"
                  % (n, "s" if n > 1 else " ", sorted(per_worker.values()), answers, " ".join("%.2f" % t for t in answer_runs), counted,
                     " ".join("%.2f" % t for t in count_runs), load()))
    if 1 in results:
        for n, (answers, counted, best_answers, best_count) in results.items():
            if n != 1:
                print("speedup of %d workers over 1: answers %.2fx, hit count %.2fx (medians);"
                      " %.2fx, %.2fx (best runs)" % (n, results[1][0] / answers, results[1][1] / counted,
                                                     results[1][2] / best_answers, results[1][3] / best_count))

if __name__ == "__main__":
    main()
