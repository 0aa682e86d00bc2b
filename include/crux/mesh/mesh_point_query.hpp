#pragma once
/// @file mesh_point_query.hpp  The point of a mesh's surface closest to a query point.
///
/// Best-first descent of the mesh's 4-wide BVH (nearest lane first, keyed by the squared
/// distance from the point to the lane's box; a subtree is pruned when its box is farther
/// than the best triangle found so far), exact per triangle as closestPoint(Triangle, p)
/// (closest_point.hpp, Ericson RTCD 5.1.5). The BVH path and the brute-force path
/// (QueryPath::BruteForce, every triangle) give identical answers.

#include <crux/geometry/raycast.hpp>
#include <crux/mesh/mesh.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <cstdint>
#include <limits>

namespace crux {

/// Relative slack of the node pruning of closestPoint(Mesh, p): a box is skipped only when its
/// squared distance exceeds the best squared distance by more than this fraction (16 ulps of
/// Real), so the rounding of the box distance never hides a triangle at the same distance.
/// Only which nodes are visited depends on it, never the answer.
inline constexpr Real kMeshPointPruneSlack = Real(16) * std::numeric_limits<Real>::epsilon();

/// The closest surface point of a mesh to a query point.
struct MeshClosestPoint {
  bool found = false;          ///< a triangle within maxDistance exists
  Real distance = kNoLimit;    ///< |point − query| (0 on the surface)
  Vec3 point = Vec3::Zero();   ///< closest point on the surface
  std::uint32_t triangle = 0;  ///< triangle realising it (lowest index among equal distances)
};

/// Closest point of the mesh's surface to p among triangles at distance <= maxDistance
/// (found == false when there is none). Ties in squared distance go to the lowest triangle
/// index. Preconditions: p finite, maxDistance >= 0 (not NaN); never throws, never allocates.
MeshClosestPoint closestPoint(const Mesh& mesh, const Vec3& p, Real maxDistance = kNoLimit,
                              QueryPath path = QueryPath::Bvh);

}  // namespace crux
