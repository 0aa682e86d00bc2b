#!/usr/bin/env python3
"""crux.dask's scaling with the number of Dask workers: crux.dask.ray_closest over the same rays
on a local cluster of 1 worker and on one of 2 (processes, one thread each, as docs/python.md says
to run a cluster), and the speedup. Both clusters are started first and the rounds alternate
between them, so the machine's drift (up to ±40 % within minutes on the VMs measured) falls on
both alike; each speedup is the median over rounds of that round's ratio.

The rays (bench_rays.py's: from a sphere of 3 bounding radii towards random points of the mesh's
bounds) are made in this process and scattered over the workers before timing, as data already on
the cluster (da.from_zarr etc.) would be; the mesh is given by path, loaded once per worker during
a warm-up. Two computations are timed in each of --runs rounds:
  - answers: all four answers computed together and gathered into this process (36 bytes per ray
    of transfer: t, triangle as int64, point, normal);
  - hit count: the number of hits, reduced on the workers (the rays' work alone).
The control, in every round: the same rays in this process on crux's own 1 and 2 threads. The
workers' speedup cannot exceed that one; the load average is printed too.

The workers start without Dask's default MALLOC_TRIM_THRESHOLD_=65536 (its nanny's
pre-spawn-environ), as docs/python.md advises for crux workers: any explicit malloc threshold turns
off glibc's adaptive mmap threshold, so every answer array becomes fresh pages to fault in, which
made each crux call ~45 % slower in a worker than in this process. --dask-malloc-trim keeps
Dask's default, to measure that.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/python/bench_dask.py [--mesh PATH]
       [--rays N] [--chunk N] [--runs N] [--workers 1,2] [--dask-malloc-trim]
"""

import argparse
import contextlib
import itertools
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


def seconds(call):
    start = time.perf_counter()
    call()
    return time.perf_counter() - start


def fresh_graphs(path, rays):
    """A function giving a new crux.dask.ray_closest graph over `rays` at each call: each run its
    own graph (max_distance differs, beyond every hit), else dask would hand back the results of
    the previous run still held by the workers."""
    runs = itertools.count(1)
    return lambda: cd.ray_closest(path, rays, max_distance=1e30 * next(runs))


def paired(before, after):
    """The median over rounds of before / after (each round's two figures measured minutes apart
    at most, so the machine's drift between rounds cancels)."""
    return statistics.median(b / a for b, a in zip(before, after))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--mesh", default=os.path.join(here, "..", "..", "data", "meshes", "bunny00.off"))
    p.add_argument("--rays", type=int, default=4_000_000)
    p.add_argument("--chunk", type=int, default=250_000)
    p.add_argument("--runs", type=int, default=5, help="rounds (each: the control, then every cluster)")
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
    counts = [int(x) for x in a.workers.split(",")]
    print("%s: %d triangles; %d rays in chunks of %d; %d rounds; load average %s"
          % (os.path.basename(path), len(mesh), a.rays, a.chunk, a.runs, load()))
    print("workers' MALLOC_TRIM_THRESHOLD_: %s" % environ.get("MALLOC_TRIM_THRESHOLD_", "unset (glibc's adaptive thresholds)"))
    # Every cluster is started first and the rounds alternate between them (and the in-process
    # control): the same work on these VMs drifts by up to ±40 % within minutes, which one cluster
    # after the other would read as a speedup or a loss. Idle clusters only exchange heartbeats.
    with contextlib.ExitStack() as stack:
        setups = {}
        for n in counts:
            cluster = stack.enter_context(distributed.LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=":0",
                worker_dashboard_address=None))
            client = stack.enter_context(distributed.Client(cluster, set_as_default=False))
            # the chunks scattered round robin over the workers (persisting da.from_array would leave
            # them all on the worker that held the whole array, and locality would keep the work there)
            pieces = [rays[i:i + a.chunk] for i in range(0, a.rays, a.chunk)]
            futures = client.scatter(pieces)
            d = da.concatenate([da.from_delayed(dask.delayed(f), shape=c.shape, dtype=c.dtype)
                                for f, c in zip(futures, pieces)])
            held = client.who_has(futures)
            per_worker = sorted(sum(1 for ws in held.values() if w in ws) for w in client.scheduler_info()["workers"])
            fresh = fresh_graphs(path, d)
            client.compute(da.isfinite(fresh().t).sum(), sync=True)  # warm-up: every worker loads the mesh
            setups[n] = (client, fresh, per_worker)
        times = {("control", 1): [], ("control", 2): []}
        for n in counts:
            times[("answers", n)], times[("count", n)] = [], []
        for _ in range(a.runs):
            # the control: crux's own threads in this process, 1 then 2 (what 2 cores give right now)
            times[("control", 1)].append(seconds(lambda: mesh.ray_closest(rays, threads=1)))
            times[("control", 2)].append(seconds(lambda: mesh.ray_closest(rays, threads=2)))
            for n in counts:
                client, fresh, _ = setups[n]
                times[("answers", n)].append(seconds(lambda: client.compute(list(fresh()), sync=True)))
                times[("count", n)].append(seconds(lambda: client.compute(da.isfinite(fresh().t).sum(), sync=True)))
    med = {k: statistics.median(v) for k, v in times.items()}
    print("in process (control): 1 thread %.2f s (%s), 2 threads %.2f s (%s): %.2fx (median of the rounds' ratios)"
          % (med[("control", 1)], " ".join("%.2f" % t for t in times[("control", 1)]), med[("control", 2)],
             " ".join("%.2f" % t for t in times[("control", 2)]), paired(times[("control", 1)], times[("control", 2)])))
    for n in counts:
        print("%d worker%s (chunks per worker %s): answers %.2f s (%s), hit count %.2f s (%s)"
              % (n, "s" if n > 1 else " ", setups[n][2], med[("answers", n)], " ".join("%.2f" % t for t in times[("answers", n)]),
                 med[("count", n)], " ".join("%.2f" % t for t in times[("count", n)])))
    if 1 in counts:
        for n in counts:
            if n != 1:
                print("speedup of %d workers over 1 (median of the rounds' ratios): answers %.2fx, hit count %.2fx;"
                      " load average %s" % (n, paired(times[("answers", 1)], times[("answers", n)]),
                                            paired(times[("count", 1)], times[("count", n)]), load()))


if __name__ == "__main__":
    main()
