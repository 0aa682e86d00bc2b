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
normal) come from one task per block: compute them together, ``dask.compute(*hits)``.

Dask's nanny starts workers with ``MALLOC_TRIM_THRESHOLD_=65536``, which turns off glibc's adaptive
mmap threshold: every answer array is then fresh memory to fault in, and a crux call in such a
worker took ~45 % longer than in the client. docs/python.md ("crux.dask") shows how to start
crux's workers without it.
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


def _apply(block, source, method, kwargs):
    return getattr(_mesh(source), method)(block, threads=1, **kwargs)


# Calls with several answers (t, triangle, point, normal): one task per block answers the call and
# keeps the answers as they are, a tuple of arrays; each answer array is then taken out of it by a
# small task of its own on the same worker, so each crosses to the client in its own dtype and no
# packed copy is made.
def _answers(block, source, method, kwargs):
    return tuple(_apply(block, source, method, kwargs))


def _field(answers, i):
    return answers[i]


def _split(rows, source, method, fields, **kwargs):
    """The answers of ``method`` over ``rows``, one lazy array per (dtype, trailing width) of fields
    (width None: the rows' leading shape; an int: one more axis of that length)."""
    lead = rows.ndim - 1
    # meta given: dask must not call the function on an empty block with the delayed mesh to find it
    blocks = da.map_blocks(
        _answers, rows, source, method, kwargs, dtype=object, drop_axis=lead, meta=np.empty((0,) * lead, object)
    )
    out = []
    for i, (dtype, width) in enumerate(fields):
        if width is None:
            out.append(blocks.map_blocks(_field, i, dtype=dtype, meta=np.empty((0,) * lead, dtype)))
        else:
            chunks = blocks.chunks + ((width,),)
            meta = np.empty((0,) * (lead + 1), dtype)
            out.append(blocks.map_blocks(_field, i, dtype=dtype, new_axis=lead, chunks=chunks, meta=meta))
    return out


def _reduced(rows, source, method, dtype, **kwargs):
    meta = np.empty((0,) * (rows.ndim - 1), dtype)
    return da.map_blocks(_apply, rows, source, method, kwargs, dtype=dtype, drop_axis=rows.ndim - 1, meta=meta)


def ray_closest(mesh, rays, max_distance=np.inf, cull_back_faces=False):
    """Mesh.ray_closest over a dask array of rays (..., 6): crux.RayHits of lazy dask arrays."""
    rows = _rows(rays, 6, "rays")
    fields = [(_crux.REAL, None), (np.int64, None), (_crux.REAL, 3), (_crux.REAL, 3)]
    return _crux.RayHits(
        *_split(rows, _source(mesh), "ray_closest", fields, max_distance=max_distance, cull_back_faces=cull_back_faces)
    )


def ray_any(mesh, rays, max_distance=np.inf, cull_back_faces=False):
    """Mesh.ray_any over a dask array of rays (..., 6): a lazy bool dask array (...)."""
    rows = _rows(rays, 6, "rays")
    return _reduced(rows, _source(mesh), "ray_any", bool, max_distance=max_distance, cull_back_faces=cull_back_faces)


def closest_point(mesh, points, max_distance=np.inf):
    """Mesh.closest_point over a dask array of points (..., 3): crux.ClosestPoints of lazy arrays."""
    rows = _rows(points, 3, "points")
    fields = [(_crux.REAL, 3), (_crux.REAL, None), (np.int64, None)]
    return _crux.ClosestPoints(*_split(rows, _source(mesh), "closest_point", fields, max_distance=max_distance))


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
