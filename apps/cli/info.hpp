#pragma once
/// @file info.hpp  `crux info MESH...`: loads mesh files and reports what they are made of
/// (MeshStats), how long loading and the BVH build took, and the shape and memory of the BVH.
/// Documented for users in docs/batch.md ("crux info").

#include <crux/mesh/bvh.hpp>

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

namespace crux::cli {

/// Shape of a mesh's 4-wide BVH, from one pass over its node array.
struct BvhShape {
  std::size_t nodes = 0;          ///< wide nodes
  std::size_t leaves = 0;         ///< leaf lanes
  double meanLanes = 0;           ///< mean used lanes per node (2 to 4)
  std::size_t depth = 0;          ///< wide nodes above the deepest leaf, the root's not counted
                                  ///< (leaves in the root's own lanes: 0)
  double meanLeafDepth = 0;       ///< mean over leaves of their depth
  double meanLeafSize = 0;        ///< mean primitives per leaf
  std::size_t maxLeafSize = 0;    ///< most primitives in one leaf
};

/// Walks the node array from the root with an explicit stack (no recursion).
BvhShape bvhShape(const WideBvh& bvh);

/// Options of one `crux info` run.
struct InfoOptions {
  /// One JSON object per file and line (JSON Lines) instead of the text report.
  bool json = false;
  /// The `crux` executable: when set, each file is imported in a `crux import-mesh` child
  /// (loadMeshFile), so a file that crashes assimp is reported like any other failure.
  std::string cruxExecutable;
};

/// Loads every file with loadMeshFile (timing the load, which includes the BVH build) and
/// writes its report to `out`, in argument order. A file that fails to load is reported on
/// `err` as "crux info: <loadMesh's message, which starts with the path>" (and, with json, as
/// {"path":…,"error":…} on `out`) and the remaining files are still reported.
/// Returns 0 when every file loaded, 1 otherwise.
int runInfo(const std::vector<std::string>& paths, const InfoOptions& options, std::ostream& out,
            std::ostream& err);

}  // namespace crux::cli
