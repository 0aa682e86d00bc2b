"""crux: exact collision detection and ray casting on triangle meshes, with numpy in and out.

Every batch method takes arrays of rows with any leading dimensions and keeps them: rays of shape
(H, W, 6) give answers of shape (H, W). Rows of crux's real dtype (``crux.REAL``: float32, or
float64 in a double-precision build) in C order are read in place; any other array is converted
once. The GIL is released while a batch runs, on ``threads=`` TBB threads (0 = all cores).
Bad input raises ValueError with crux's message. See docs/python.md.
"""

from ._crux import (
    DOUBLE_PRECISION,
    REAL,
    CastHits,
    ClosestPoints,
    Contacts,
    Mesh,
    MeshDistance,
    RayHits,
    RayHitsAll,
    RegionHits,
    Scene,
    SceneCastHits,
    SceneRayHits,
    contacts,
    mesh_distance,
    mesh_overlap,
    touching_pairs,
)
from .world import World, WorldError

__all__ = [
    "DOUBLE_PRECISION",
    "REAL",
    "CastHits",
    "ClosestPoints",
    "Contacts",
    "Mesh",
    "MeshDistance",
    "RayHits",
    "RayHitsAll",
    "RegionHits",
    "Scene",
    "SceneCastHits",
    "SceneRayHits",
    "World",
    "WorldError",
    "contacts",
    "mesh_distance",
    "mesh_overlap",
    "rays",
    "touching_pairs",
]


def rays(origins, directions):
    """Stacks origins (..., 3) and directions (..., 3) into rays (..., 6) of dtype REAL."""
    import numpy as np

    o = np.asarray(origins, dtype=REAL)
    d = np.asarray(directions, dtype=REAL)
    o, d = np.broadcast_arrays(o, d)
    return np.concatenate([o, d], axis=-1)
