#pragma once
/// @file mesh_ops.hpp  Handlers of the batch protocol's mesh ops (see docs/batch.md): defining
/// meshes by name in BatchState and querying them through the crux mesh layer.

#include "cli/batch.hpp"

namespace crux::cli {

/// Adds `mesh` and `load_mesh` (store a crux::Mesh under a name; redefining a name replaces
/// it) and `mesh_ray`, `mesh_segment`, `mesh_sphere`, `mesh_aabb`, `mesh_obb`, `mesh_plane`,
/// `mesh_triangle`, `mesh_mesh`, answered by crux::raycastClosest / raycastAll,
/// crux::intersects / overlaps / touchingTriangles and the BVH-vs-BVH crux::overlaps /
/// touchingTrianglePairs of include/crux/mesh/mesh_query.hpp.
void addMeshOps(OpTable& table);

}  // namespace crux::cli
