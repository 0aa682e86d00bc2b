"""Tests of python/crux/dask.py on a LocalCluster of 2 worker processes on 127.0.0.1 (started and
stopped by the test): the answers equal the in-process answers bit for bit, with the mesh given by
path and by pickle, and also when a worker process is killed mid-run (its nanny restarts it and
the lost blocks are recomputed)."""

import os
import signal
import time

import numpy as np
import pytest

import crux
from conftest import mesh_path, random_points, random_rays, torus

da = pytest.importorskip("dask.array")
distributed = pytest.importorskip("distributed")
import crux.dask as cd  # noqa: E402
import dask  # noqa: E402


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None,
        worker_dashboard_address=None,
    )
    c = distributed.Client(cluster)
    try:
        yield c
    finally:
        c.close()
        cluster.close()


def equal(a, b):
    for x, y in zip(a, b):
        assert x.dtype == y.dtype and x.shape == y.shape
        assert x.tobytes() == y.tobytes()  # bit for bit (NaN payloads included)


def test_rays_by_pickled_mesh_equal_in_process(client):
    mesh = torus()
    rays = random_rays(mesh, 20000, seed=3).reshape(100, 200, 6)
    hits = cd.ray_closest(mesh, da.from_array(rays, chunks=(25, 200, 6)))
    equal(dask.compute(*hits), mesh.ray_closest(rays))
    one = rays[0, 0]  # a single ray, shape (6,): 0-d answers, (3,) points and normals
    equal(dask.compute(*cd.ray_closest(mesh, da.from_array(one, chunks=(6,)))), mesh.ray_closest(one))
    equal([cd.ray_any(mesh, da.from_array(rays, chunks=(10, 100, 6))).compute()], [mesh.ray_any(rays)])


def test_points_and_shapes_by_path_equal_in_process(client, bunny):
    path = mesh_path("bunny00.off")
    points = random_points(bunny, 6000, seed=8)
    dpoints = da.from_array(points, chunks=(1000, 3))
    equal(dask.compute(*cd.closest_point(path, dpoints)), bunny.closest_point(points))
    equal(dask.compute(*cd.closest_point(path, da.from_array(points[0], chunks=(3,)))), bunny.closest_point(points[0]))
    spheres = np.c_[points, np.full(len(points), 0.01, dtype=crux.REAL)]
    equal([cd.overlaps_spheres(path, da.from_array(spheres, chunks=(1500, 4))).compute()],
          [bunny.overlaps_spheres(spheres)])
    closed = torus()
    tp = random_points(closed, 3000)
    equal([cd.signed_distance(closed, da.from_array(tp, chunks=(700, 3))).compute()], [closed.signed_distance(tp)])
    equal([cd.contains(closed, da.from_array(tp, chunks=(700, 3))).compute()], [closed.contains(tp)])


def test_a_worker_killed_mid_run_is_restarted_and_the_answers_are_complete(client, bunny):
    rays = np.tile(random_rays(bunny, 20000, seed=12), (20, 1))
    expected = bunny.ray_closest(rays)
    hits = cd.ray_closest(bunny, da.from_array(rays, chunks=(10000, 6)))
    pids = client.run(os.getpid)  # worker address -> pid
    address, victim = sorted(pids.items())[0]
    futures = client.compute(list(hits))
    # kill one worker as soon as it is answering blocks, before the run ends
    deadline = time.time() + 60
    while not client.processing().get(address) and time.time() < deadline:
        time.sleep(0.005)
    assert not all(f.done() for f in futures), "the batch ended before the kill: make it longer"
    os.kill(victim, signal.SIGKILL)
    results = client.gather(futures)
    equal(results, expected)
    # the nanny brought a worker back: two workers again, the killed one not among them
    deadline = time.time() + 60
    while len(client.scheduler_info()["workers"]) < 2 and time.time() < deadline:
        time.sleep(0.1)
    now = client.run(os.getpid)
    assert len(now) == 2 and victim not in now.values()
