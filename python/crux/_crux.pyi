"""Type stubs of the extension module crux._crux (re-exported by the package crux)."""

from typing import Any, List, Literal, NamedTuple, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

REAL: np.dtype
DOUBLE_PRECISION: bool

ArrayLike = npt.ArrayLike
Pose = Union[None, npt.ArrayLike, Tuple[npt.ArrayLike, npt.ArrayLike]]

class RayHits(NamedTuple):
    t: np.ndarray
    triangle: np.ndarray
    point: np.ndarray
    normal: np.ndarray

class RayHitsAll(NamedTuple):
    offsets: np.ndarray
    ray: np.ndarray
    triangle: np.ndarray
    t: np.ndarray

class ClosestPoints(NamedTuple):
    point: np.ndarray
    distance: np.ndarray
    triangle: np.ndarray

class MeshDistance(NamedTuple):
    distance: float
    point_a: np.ndarray
    point_b: np.ndarray
    triangle_a: int
    triangle_b: int

class Contacts(NamedTuple):
    point_a: np.ndarray
    point_b: np.ndarray
    normal: np.ndarray
    separation: np.ndarray
    triangle: np.ndarray

class SceneRayHits(NamedTuple):
    model: np.ndarray
    t: np.ndarray
    triangle: np.ndarray
    point: np.ndarray
    normal: np.ndarray

class CastHits(NamedTuple):
    t: np.ndarray
    triangle: np.ndarray
    point_shape: np.ndarray
    point_mesh: np.ndarray
    normal: np.ndarray
    starts_overlapping: np.ndarray

class SceneCastHits(NamedTuple):
    model: np.ndarray
    t: np.ndarray
    triangle: np.ndarray
    point_shape: np.ndarray
    point_mesh: np.ndarray
    normal: np.ndarray
    starts_overlapping: np.ndarray

class RegionHits(NamedTuple):
    offsets: np.ndarray
    models: np.ndarray

class Mesh:
    def __init__(self, vertices: ArrayLike, triangles: ArrayLike, name: str = "mesh") -> None: ...
    @staticmethod
    def load(path: str, import_command: Optional[List[str]] = None) -> "Mesh": ...
    @property
    def vertices(self) -> np.ndarray: ...
    @property
    def triangles(self) -> np.ndarray: ...
    @property
    def name(self) -> str: ...
    @property
    def closed(self) -> bool: ...
    @property
    def bounds(self) -> np.ndarray: ...
    def stats(self) -> dict: ...
    def __len__(self) -> int: ...
    def ray_closest(
        self, rays: ArrayLike, max_distance: float = ..., cull_back_faces: bool = False, threads: int = 0
    ) -> RayHits: ...
    def ray_any(
        self, rays: ArrayLike, max_distance: float = ..., cull_back_faces: bool = False, threads: int = 0
    ) -> np.ndarray: ...
    def ray_all(
        self, rays: ArrayLike, max_distance: float = ..., cull_back_faces: bool = False, threads: int = 0
    ) -> RayHitsAll: ...
    def closest_point(self, points: ArrayLike, max_distance: float = ..., threads: int = 0) -> ClosestPoints: ...
    def contains(self, points: ArrayLike, threads: int = 0) -> np.ndarray: ...
    def signed_distance(self, points: ArrayLike, threads: int = 0) -> np.ndarray: ...
    def overlaps_spheres(self, spheres: ArrayLike, volume: bool = False, threads: int = 0) -> np.ndarray: ...
    @overload
    def cast_spheres(
        self, spheres: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> CastHits: ...
    @overload
    def cast_spheres(
        self, spheres: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    @overload
    def cast_spheres_rigid(
        self, spheres: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> CastHits: ...
    @overload
    def cast_spheres_rigid(
        self, spheres: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    @overload
    def cast_capsules(
        self, capsules: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> CastHits: ...
    @overload
    def cast_capsules(
        self, capsules: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    @overload
    def cast_capsules_rigid(
        self, capsules: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> CastHits: ...
    @overload
    def cast_capsules_rigid(
        self, capsules: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    @overload
    def cast_obbs(
        self, obbs: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> CastHits: ...
    @overload
    def cast_obbs(
        self, obbs: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    @overload
    def cast_obbs_rigid(
        self, obbs: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> CastHits: ...
    @overload
    def cast_obbs_rigid(
        self, obbs: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    def overlaps_aabbs(self, aabbs: ArrayLike, volume: bool = False, threads: int = 0) -> np.ndarray: ...
    def overlaps_obbs(self, obbs: ArrayLike, volume: bool = False, threads: int = 0) -> np.ndarray: ...

class Scene:
    @overload
    def __init__(self) -> None: ...
    @overload
    def __init__(self, state: tuple) -> None: ...  # a pickled Scene's state (__reduce__)
    def add(self, mesh: Mesh, pose: Pose = None, parent: Optional[int] = None) -> int: ...
    def remove(self, id: int) -> None: ...
    def set_transform(self, id: int, pose: Pose) -> None: ...
    def set_transforms(self, ids: ArrayLike, poses: ArrayLike) -> None: ...
    def set_parent(self, id: int, parent: Optional[int]) -> None: ...
    def pose(self, id: int) -> np.ndarray: ...
    def world_pose(self, id: int) -> np.ndarray: ...
    def parent(self, id: int) -> Optional[int]: ...
    def mesh(self, id: int) -> Mesh: ...
    def ids(self) -> np.ndarray: ...
    def __len__(self) -> int: ...
    def ray_closest(
        self, rays: ArrayLike, max_distance: float = ..., cull_back_faces: bool = False, threads: int = 0
    ) -> SceneRayHits: ...
    def query_spheres(self, spheres: ArrayLike, bounds_only: bool = False, threads: int = 0) -> RegionHits: ...
    def query_aabbs(self, aabbs: ArrayLike, bounds_only: bool = False, threads: int = 0) -> RegionHits: ...
    def query_obbs(self, obbs: ArrayLike, bounds_only: bool = False, threads: int = 0) -> RegionHits: ...
    def overlapping_pairs(self, bounds_only: bool = False) -> np.ndarray: ...
    @overload
    def cast_spheres(
        self, spheres: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> SceneCastHits: ...
    @overload
    def cast_spheres(
        self, spheres: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    @overload
    def cast_spheres_rigid(
        self, spheres: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> SceneCastHits: ...
    @overload
    def cast_spheres_rigid(
        self, spheres: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    @overload
    def cast_capsules(
        self, capsules: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> SceneCastHits: ...
    @overload
    def cast_capsules(
        self, capsules: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    @overload
    def cast_capsules_rigid(
        self, capsules: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> SceneCastHits: ...
    @overload
    def cast_capsules_rigid(
        self, capsules: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    @overload
    def cast_obbs(
        self, obbs: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> SceneCastHits: ...
    @overload
    def cast_obbs(
        self, obbs: ArrayLike, motions: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...
    @overload
    def cast_obbs_rigid(
        self, obbs: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[False] = False
    ) -> SceneCastHits: ...
    @overload
    def cast_obbs_rigid(
        self, obbs: ArrayLike, starts: ArrayLike, ends: ArrayLike, threads: int = 0, *, any: Literal[True]
    ) -> np.ndarray: ...

def mesh_overlap(a: Mesh, b: Mesh, pose_a: Pose = None, pose_b: Pose = None, volume: bool = False) -> bool: ...
def touching_pairs(a: Mesh, b: Mesh, pose_a: Pose = None, pose_b: Pose = None) -> np.ndarray: ...
def mesh_distance(
    a: Mesh, b: Mesh, pose_a: Pose = None, pose_b: Pose = None, max_distance: float = ...
) -> MeshDistance: ...
def contacts(
    mesh: Mesh, kind: str, shape: ArrayLike, mesh_pose: Pose = None, shape_pose: Pose = None, margin: float = 0.0
) -> Contacts: ...
def _read_rows(array: Any, width: int) -> np.ndarray: ...
def _ray_closest_reference_seconds(mesh: Mesh, rays: ArrayLike, runs: int) -> List[float]: ...
