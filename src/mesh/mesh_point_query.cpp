/// @file mesh_point_query.cpp  Closest surface point of a mesh to a point (mesh_point_query.hpp).

#include <crux/mesh/mesh_point_query.hpp>
#include <crux/precondition.hpp>

#include <crux/geometry/closest_point.hpp>

#include "mesh_walk.hpp"

#include <cmath>

namespace crux {
namespace {

/// Keeps the best (squared distance, triangle) and prunes boxes farther than it.
struct ClosestPointVisitor {
  const Mesh& mesh;
  const Vec3& p;
  Real best2;  // squared distance bound: maxDistance², lowered to the best triangle's
  MeshClosestPoint best{};

  bool within(Real key) const { return key <= best2 + best2 * kMeshPointPruneSlack; }
  // (the walk's visitor: mesh_detail::walkOrdered, nearest box first)
  bool entry(const Aabb& box, Real& key) const {
    key = squaredDistance(box, p);
    return within(key);
  }
  bool keep(Real key) const { return within(key); }
  bool leaf(std::uint32_t first, std::uint32_t count) {
    for (std::uint32_t k = first; k < first + count; ++k) visit(mesh.slotTriangle(k), mesh.bvh().primIndices[k]);
    return true;
  }
  void visit(const Triangle& t, std::uint32_t tri) {
    const Vec3 q = closestPoint(t, p);
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
