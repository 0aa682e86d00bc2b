#pragma once
/// @file mesh_ops.hpp  Handlers of the batch protocol's mesh ops (see docs/batch.md): defining
/// meshes by name in the batch's crux::CollisionWorld and querying them through it.

#include "cli/batch.hpp"

namespace crux::cli {

/// Adds `mesh` and `load_mesh` (build a crux::Mesh, then CollisionWorld::addMesh under a name;
/// redefining a name replaces it) and `mesh_ray`, `mesh_segment`, `mesh_sphere`, `mesh_aabb`,
/// `mesh_obb`, `mesh_plane`, `mesh_triangle`, `mesh_mesh`, answered by the world's raycast
/// (closest or all-hits collector), intersects / overlaps, and the touchingTriangles /
/// touchingTrianglePairs extensions (for native: the BVH queries of
/// include/crux/mesh/mesh_query.hpp).
void addMeshOps(OpTable& table);

}  // namespace crux::cli
