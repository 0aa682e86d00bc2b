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

/// loadMesh for a file a user names (`load_mesh`, `crux info`): with `cruxExecutable` (the
/// `crux` executable) assimp runs in a `crux import-mesh` child process
/// (MeshImportIsolation::Subprocess), so a file that crashes or hangs assimp costs an
/// InvalidInput for that file only; without it, in this process.
Mesh loadMeshFile(const std::string& path, const std::string& cruxExecutable);

/// `crux import-mesh BUDGET PATH`, the import command of MeshImportIsolation::Subprocess:
/// crux::runMeshImport(PATH, BUDGET, standard output). Returns its exit status (2: bad
/// arguments, with the reason on `err`).
int runImportMesh(const std::string& budget, const std::string& path, std::ostream& err);

}  // namespace crux::cli
