/// @file mesh_point_query.cpp  Closest surface point of a mesh to a point (mesh_point_query.hpp).

#include <crux/mesh/mesh_point_query.hpp>
#include <crux/precondition.hpp>

#include <crux/geometry/closest_point.hpp>

#include "geometry/unchecked.hpp"
#include "mesh_walk.hpp"
#include "node_tests.hpp"

#include <cmath>
#include <cstring>

namespace crux {
namespace {

/// Keeps the best (squared distance, triangle) and prunes boxes farther than it: the lanes of a
/// wide node four at a time (entry4), and a leaf's triangles by their own boxes before the
/// closest point on each is formed (bunny00, points uniform in its bounds: a third of a leaf's
/// triangles are skipped so). Every box key is mesh_detail::boxSquaredDistance in Real: a
/// triangle's rounded closest point lies in its box and in every enclosing node's, and rounding
/// is monotone, so a key never exceeds the triangle's computed squared distance by more than the
/// summation order's ulp, far inside kMeshPointPruneSlack: the walk skips only triangles that
/// the brute-force loop would not keep.
struct ClosestPointVisitor {
  const Mesh& mesh;
  const Vec3& p;
  Real best2;  // squared distance bound: maxDistance², lowered to the best triangle's
  MeshClosestPoint best{};

  bool within(Real key) const { return key <= best2 + best2 * kMeshPointPruneSlack; }
  // (the walk's visitor: mesh_detail::walkOrdered, nearest box first)
  bool entry(const Aabb& box, Real& key) const {
    key = mesh_detail::boxSquaredDistance(box, p);
    return within(key);
  }
  // The same keys on four lanes; unused lanes (empty boxes) are never entered, even without a
  // distance limit.
  unsigned entry4(const WideBvhNode& n, Real (&keys)[4]) const {
    using namespace mesh_detail;
    const Lanes key = boxSquaredDistances4(n, p);
    std::memcpy(keys, &key, sizeof keys);
    const Real limit = best2 + best2 * kMeshPointPruneSlack;
    return laneMask((key <= limit) & usedLanes(n));
  }
  bool keep(Real key) const { return within(key); }
  bool leaf(std::uint32_t first, std::uint32_t count) {
    for (std::uint32_t k = first; k < first + count; ++k) {
      const Triangle t = mesh.slotTriangle(k);
      if (within(mesh_detail::boxSquaredDistance(bounds(t), p))) visit(t, mesh.bvh().primIndices[k]);
    }
    return true;
  }
  void visit(const Triangle& t, std::uint32_t tri) {
    const Vec3 q = unchecked::closestPoint(t, p);
    const Real d2 = (q - p).squaredNorm();
    if (d2 > best2) return;
    if (best.found && (d2 > best.distance || (d2 == best.distance && tri > best.triangle))) return;
    best.found = true;
    best.distance = d2;  // squared until the end
    best.point = q;
    best.triangle = tri;
    best2 = d2;
  }
};

}  // namespace

MeshClosestPoint closestPoint(const Mesh& mesh, const Vec3& p, Real maxDistance, QueryPath path) {
  if (!detail::entryPreconditions("closestPoint(Mesh, point)", detail::rule::kPoint, p))
    return {};
  ClosestPointVisitor v{mesh, p, maxDistance * maxDistance};
  if (path == QueryPath::BruteForce) {
    for (std::uint32_t i = 0, n = std::uint32_t(mesh.triangleCount()); i < n; ++i) v.visit(mesh.triangle(i), i);
  } else {
    mesh_detail::walkOrdered(mesh, v);
  }
  if (v.best.found) v.best.distance = std::sqrt(v.best.distance);
  return v.best;
}

}  // namespace crux
