"""crux.dask: batches of crux queries over a Dask array, on a Dask cluster.

Each function maps a dask array of rows (rays (..., 6), points (..., 3), spheres (..., 4), AABBs
(..., 6) or OBBs (..., 15)) block by block over the workers and returns lazy dask arrays with the
rows' leading shape, equal bit for bit to the in-process answers (each block is answered by the
same crux call). The mesh reaches the workers once per worker process:

- ``mesh="path/to/file.off"``: each worker process loads the file itself (crux.Mesh.load, cached
  per process), so the file must exist at that path on every worker machine;
- ``mesh=crux.Mesh(...)``: the mesh is one task of the graph (``dask.delayed``), pickled to each
  worker that needs it and kept in worker memory; its BVH is rebuilt there once per transfer.

Every block runs crux with ``threads=1``: a Dask worker process runs one task per worker thread,
so parallelism comes from the worker processes (``LocalCluster(n_workers=N,
threads_per_worker=1)`` or ``dask-worker --nthreads 1``). Blocks are recomputed when a worker
dies, so the result is complete and identical. Several answers of one call (t, triangle, point,
normal) come from one packed block each: compute them together, ``dask.compute(*hits)``.
"""

import functools

import dask
import dask.array as da
import numpy as np

from . import _crux

__all__ = [
    "ray_closest",
    "ray_any",
    "closest_point",
    "contains",
    "signed_distance",
    "overlaps_spheres",
    "overlaps_aabbs",
    "overlaps_obbs",
]


@functools.lru_cache(maxsize=8)
def _load(path):
    return _crux.Mesh.load(path)


def _mesh(source):
    return _load(source) if isinstance(source, str) else source


def _source(mesh):
    if isinstance(mesh, str):
        return mesh
    if isinstance(mesh, _crux.Mesh):
        return dask.delayed(mesh, pure=False)
    raise TypeError("mesh: expected a crux.Mesh or the path of a mesh file, got %r" % type(mesh).__name__)


def _rows(array, width, name):
    a = da.asarray(array)
    if a.ndim == 0 or a.shape[-1] != width:
        raise ValueError("%s: expected shape (..., %d), got %s" % (name, width, a.shape))
    return a.rechunk({a.ndim - 1: width})


# Packed blocks: every answer of a row as float64 (exact for crux's Real and for triangle indices).
def _pack_closest(block, source, max_distance, cull_back_faces):
    h = _mesh(source).ray_closest(block, max_distance=max_distance, cull_back_faces=cull_back_faces, threads=1)
    return np.concatenate(
        [h.t[..., None], h.triangle[..., None].astype(np.float64), h.point, h.normal], axis=-1, dtype=np.float64
    )


def _pack_closest_point(block, source, max_distance):
    c = _mesh(source).closest_point(block, max_distance=max_distance, threads=1)
    return np.concatenate(
        [c.point, c.distance[..., None], c.triangle[..., None].astype(np.float64)], axis=-1, dtype=np.float64
    )


def _apply(block, source, method, kwargs):
    return getattr(_mesh(source), method)(block, threads=1, **kwargs)


def _packed(rows, source, func, width, *args):
    chunks = rows.chunks[:-1] + ((width,),)
    # meta given: dask must not call func on an empty block with the delayed mesh to find it
    meta = np.empty((0,) * rows.ndim, np.float64)
    return da.map_blocks(func, rows, source, *args, dtype=np.float64, chunks=chunks, meta=meta)


def _reduced(rows, source, method, dtype, **kwargs):
    meta = np.empty((0,) * (rows.ndim - 1), dtype)
    return da.map_blocks(_apply, rows, source, method, kwargs, dtype=dtype, drop_axis=rows.ndim - 1, meta=meta)


def ray_closest(mesh, rays, max_distance=np.inf, cull_back_faces=False):
    """Mesh.ray_closest over a dask array of rays (..., 6): crux.RayHits of lazy dask arrays."""
    rows = _rows(rays, 6, "rays")
    p = _packed(rows, _source(mesh), _pack_closest, 8, max_distance, cull_back_faces)
    return _crux.RayHits(
        p[..., 0].astype(_crux.REAL), p[..., 1].astype(np.int64), p[..., 2:5].astype(_crux.REAL), p[..., 5:8].astype(_crux.REAL)
    )


def ray_any(mesh, rays, max_distance=np.inf, cull_back_faces=False):
    """Mesh.ray_any over a dask array of rays (..., 6): a lazy bool dask array (...)."""
    rows = _rows(rays, 6, "rays")
    return _reduced(rows, _source(mesh), "ray_any", bool, max_distance=max_distance, cull_back_faces=cull_back_faces)


def closest_point(mesh, points, max_distance=np.inf):
    """Mesh.closest_point over a dask array of points (..., 3): crux.ClosestPoints of lazy arrays."""
    rows = _rows(points, 3, "points")
    p = _packed(rows, _source(mesh), _pack_closest_point, 5, max_distance)
    return _crux.ClosestPoints(p[..., 0:3].astype(_crux.REAL), p[..., 3].astype(_crux.REAL), p[..., 4].astype(np.int64))


def contains(mesh, points):
    """Mesh.contains over a dask array of points (..., 3): a lazy bool dask array (...)."""
    return _reduced(_rows(points, 3, "points"), _source(mesh), "contains", bool)


def signed_distance(mesh, points):
    """Mesh.signed_distance over a dask array of points (..., 3): a lazy REAL dask array (...)."""
    return _reduced(_rows(points, 3, "points"), _source(mesh), "signed_distance", _crux.REAL)


def overlaps_spheres(mesh, spheres, volume=False):
    """Mesh.overlaps_spheres over a dask array of spheres (..., 4): a lazy bool dask array."""
    return _reduced(_rows(spheres, 4, "spheres"), _source(mesh), "overlaps_spheres", bool, volume=volume)


def overlaps_aabbs(mesh, aabbs, volume=False):
    """Mesh.overlaps_aabbs over a dask array of boxes (..., 6): a lazy bool dask array."""
    return _reduced(_rows(aabbs, 6, "aabbs"), _source(mesh), "overlaps_aabbs", bool, volume=volume)


def overlaps_obbs(mesh, obbs, volume=False):
    """Mesh.overlaps_obbs over a dask array of oriented boxes (..., 15): a lazy bool dask array."""
    return _reduced(_rows(obbs, 15, "obbs"), _source(mesh), "overlaps_obbs", bool, volume=volume)
