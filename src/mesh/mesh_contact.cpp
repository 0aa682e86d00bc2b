// Mesh vs convex shape. Contacts: a per-shape collider against each candidate triangle the BVH
// walk keeps (contact/triangle_colliders.hpp), then the stages internal-edge filter → merge →
// reduce (contact/contact_stages.hpp). Also the caller-kept adjacency of the internal-edge rule
// and the mesh–shape distance.

#include <crux/mesh/mesh_contact.hpp>
#include <crux/mesh/mesh_query_data.hpp>
#include <crux/precondition.hpp>

#include <crux/error.hpp>

#include "mesh/contact/contact_stages.hpp"
#include "mesh/contact/local_shape.hpp"
#include "mesh/contact/triangle_colliders.hpp"
#include "mesh/mesh_walk.hpp"
#include "mesh/shape_bounds.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>

namespace crux {

MeshAdjacency::MeshAdjacency(const Mesh& mesh) {
  const auto& tris = mesh.triangles();
  neighbors_.assign(tris.size() * 3, kNone);
  struct EdgeRef {
    std::uint32_t lo, hi, tri;
    int edge;
  };
  std::vector<EdgeRef> edges;
  edges.reserve(tris.size() * 3);
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t u = tris[t][e], v = tris[t][(e + 1) % 3];
      if (u == v) continue;  // collapsed edge of a degenerate triangle: no neighbour
      edges.push_back({std::min(u, v), std::max(u, v), t, e});
    }
  std::sort(edges.begin(), edges.end(), [](const EdgeRef& a, const EdgeRef& b) {
    return std::tie(a.lo, a.hi, a.tri, a.edge) < std::tie(b.lo, b.hi, b.tri, b.edge);
  });
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    if (j - i == 2 && edges[i].tri != edges[i + 1].tri) {
      neighbors_[3 * std::size_t(edges[i].tri) + edges[i].edge] = edges[i + 1].tri;
      neighbors_[3 * std::size_t(edges[i + 1].tri) + edges[i + 1].edge] = edges[i].tri;
    }
    i = j;
  }
  opposite_.assign(tris.size() * 3, kNone);
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t nb = neighbors_[3 * std::size_t(t) + e];
      if (nb == kNone) continue;
      const std::uint32_t u = tris[t][e], v = tris[t][(e + 1) % 3];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t w = tris[nb][k];
        if (w != u && w != v) {
          opposite_[3 * std::size_t(t) + e] = w;
          break;
        }
      }
    }
  activity_.assign(tris.size(), 0);
  std::vector<Real> tolerances(tris.size());  // meshFeatureTolerance by triangle (for bySlot_)
  for (std::uint32_t t = 0; t < tris.size(); ++t) {
    const Triangle tri = mesh.triangle(t);
    const Real tol = tolerances[t] = meshFeatureTolerance(tri);
    // the unit face normal as the internal-edge filter (contact/contact_stages.hpp) computes it
    // in the mesh frame (a box's points are filtered in the box frame: the same normal rotated,
    // to rounding)
    Vec3 face = (tri.b - tri.a).cross(tri.c - tri.a);
    const Real len = face.norm();
    if (!(len > 0)) {
      activity_[t] = 0x3f;
      continue;
    }
    face /= len;
    std::uint8_t bits = 0;
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t w = opposite_[3 * std::size_t(t) + e];
      if (w == kNone) {
        bits |= std::uint8_t(3u << (2 * e));
        continue;
      }
      // the neighbour's vertex falls away from the front side (d < -tol) or from the back side
      // (-face·(w − corner) = -d exactly, so the back test is d > tol)
      const Real d = face.dot(mesh.vertices()[w] - tri[e]);
      bits |= std::uint8_t((d < -tol ? 1u : 0u) << (2 * e)) | std::uint8_t((d > tol ? 1u : 0u) << (2 * e + 1));
    }
    activity_[t] = bits;
  }
  const auto& prims = mesh.bvh().primIndices;
  bySlot_.resize(prims.size());
  for (std::size_t k = 0; k < prims.size(); ++k)
    bySlot_[k] = {tolerances[prims[k]], activity_[prims[k]]};
}

std::size_t MeshAdjacency::memoryBytes() const {
  return neighbors_.capacity() * sizeof(std::uint32_t) + opposite_.capacity() * sizeof(std::uint32_t) +
         activity_.capacity() + bySlot_.capacity() * sizeof(SlotData);
}

Real meshFeatureTolerance(const Triangle& tri) {
  const Real longest = std::sqrt(std::max(
      {(tri.b - tri.a).squaredNorm(), (tri.c - tri.b).squaredNorm(), (tri.a - tri.c).squaredNorm()}));
  return kMeshFeatureRelativeTolerance *
         (longest + std::max({tri.a.cwiseAbs().maxCoeff(), tri.b.cwiseAbs().maxCoeff(), tri.c.cwiseAbs().maxCoeff()}));
}

Real MeshContactManifold::depth() const {
  Real d = 0;
  for (int i = 0; i < count; ++i) d = std::max(d, -points[i].separation);
  return d;
}

namespace {

using mesh_detail::boxSlack;
using mesh_detail::CandidateTriangle;
using mesh_detail::ContactBuffer;
using mesh_detail::InternalEdgeFilter;
using mesh_detail::kNoSlot;
using mesh_detail::LocalShape;
using mesh_detail::shapeBoundsIn;

/// Distance between two boxes (0 when they overlap): a lower bound of the distance of anything
/// inside them.
Real boxDistance(const Aabb& a, const Aabb& b) {
  const Vec3 gap = (a.min - b.max).cwiseMax(b.min - a.max).cwiseMax(Vec3::Zero());
  return gap.norm();
}

/// Hands every candidate triangle of the mesh to the collider: all of them in index order on
/// the brute-force path, else those the collider's pruning keeps, in the BVH's slot order.
template <class Collider>
void collideTriangles(const Mesh& mesh, const Collider& collider, QueryPath path, InternalEdgeFilter& out) {
  if (path == QueryPath::BruteForce) {
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
      const Triangle tri = mesh.triangle(t);
      collider.collide(CandidateTriangle{t, kNoSlot, tri}, out);
    }
    return;
  }
  struct Visitor {
    const Mesh& mesh;
    const Collider& collider;
    InternalEdgeFilter& out;
    unsigned touches4(const WideBvhNode& node) const {
      if constexpr (mesh_detail::HasTouches4<Collider>::value) return collider.touches4(node);
      else return mesh_detail::eachLane(node, [&](const Aabb& b) { return collider.touches(b); });
    }
    bool touches(const Aabb& bounds) const { return collider.touches(bounds); }
    bool slot(std::uint32_t k) {
      const Triangle tri = mesh.slotTriangle(k);
      if (collider.leafTouches(tri)) collider.collide(CandidateTriangle{mesh.bvh().primIndices[k], k, tri}, out);
      return true;
    }
  } v{mesh, collider, out};
  mesh_detail::walkSlots(mesh, v);
}

/// One contact query through its stages: the collider's points on each candidate triangle →
/// internal-edge filter → merge (buffer) → reduce, in the collider's frame; out gets the
/// reduced points in the mesh frame.
template <class Collider>
void collideMesh(const Mesh& mesh, const Collider& collider, Real margin, Real mergeTol,
                 const MeshAdjacency* adjacency, QueryPath path, MeshContactManifold& out) {
  ContactBuffer merged(mergeTol);
  InternalEdgeFilter filter(adjacency, collider.frame(), collider.mirrored(), margin, merged);
  collideTriangles(mesh, collider, path, filter);
  filter.finish();
  merged.reduce(out);
  collider.toMeshFrame(out);
}

}  // namespace

bool contacts(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape, const Transform& shapePose,
              Real margin, MeshContactManifold& out, const MeshQueryData* data, QueryPath path) {
  out.count = 0;
  validateContactMargin(margin);
  if (!detail::entryPreconditions("contacts(Mesh, ConvexShape)", detail::rule::kShapesAtPoses, meshPose, shape, shapePose))
    return false;
  const MeshAdjacency* adjacency = data ? &data->adjacencyFor(mesh) : nullptr;
  const Real size = shape.size();
  const Real mergeTol = kMeshContactMergeRelativeTolerance * (size > 0 ? size : Real(1));
  const LocalShape ls(shape, meshPose, shapePose);
  // the one dispatch on the shape's kind: its collider (triangle_colliders.hpp)
  switch (shape.kind) {
    case ConvexKind::Sphere:
      collideMesh(mesh, mesh_detail::SphereCollider(ls, margin), margin, mergeTol, adjacency, path, out);
      break;
    case ConvexKind::Capsule:
      collideMesh(mesh, mesh_detail::CapsuleCollider(ls, margin), margin, mergeTol, adjacency, path, out);
      break;
    case ConvexKind::Box: {
      const mesh_detail::BoxCollider box(ls, margin);
      collideMesh(mesh, box, margin, mergeTol, adjacency, path, out);
      break;
    }
    default:
      collideMesh(mesh, mesh_detail::ConvexCollider(ls, margin), margin, mergeTol, adjacency, path, out);
      break;
  }
  // Mesh frame -> world: only the reduced points.
  const Eigen::Matrix3d R = meshPose.rotation.cast<double>().toRotationMatrix();
  const Eigen::Vector3d tw = meshPose.translation.cast<double>();
  for (int i = 0; i < out.count; ++i) {
    MeshContactPoint& p = out.points[i];
    p.pointA = (R * p.pointA.cast<double>() + tw).cast<Real>();
    p.pointB = (R * p.pointB.cast<double>() + tw).cast<Real>();
    p.normal = (R * p.normal.cast<double>()).normalized().cast<Real>();
  }
  return out.count > 0;
}

MeshDistanceResult distance(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                            const Transform& shapePose, Real maxDistance, QueryPath path) {
  if (std::isnan(maxDistance)) throw InvalidInput("maxDistance: expected a number (or +inf for no limit), got NaN");
  MeshDistanceResult r;
  if (!detail::entryPreconditions("distance(Mesh, ConvexShape)", detail::rule::kShapesAtPoses, meshPose, shape, shapePose)) return r;
  Real best = maxDistance;
  auto consider = [&](std::uint32_t t, const Triangle& tri) {
    const DistanceResult d = distance(ConvexShape(tri), meshPose, shape, shapePose);
    if (d.distance < best || (d.distance == best && (!r.found || t < r.triangle))) {
      best = d.distance;
      r.found = true;
      r.distance = d.distance;
      r.pointA = d.pointA;
      r.pointB = d.pointB;
      r.normal = d.normal;
      r.triangle = t;
    }
  };
  if (path == QueryPath::BruteForce) {
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) consider(t, mesh.triangle(t));
    return r;
  }
  const Transform rel = meshPose.inverse() * shapePose;
  Aabb sb = shapeBoundsIn(shape, rel);
  const Real slack = boxSlack(sb);
  sb.min.array() -= slack;
  sb.max.array() += slack;
  // A triangle whose box overlaps the shape's is still skipped when a separating-axis lower
  // bound on its signed distance (the triangle's plane; for a box also the box's face axes: the
  // separation along any axis is <= the signed distance, penetrating or not) exceeds the best
  // distance by more than the slack covering the bound's rounding and GJK/EPA's error (1e-6
  // relative, narrowphase.md): such a triangle's computed distance would exceed best too, so the
  // result is the one without this test. Penetrating queries no longer run EPA on every
  // triangle the shape overlaps.
  const LocalShape ls(shape, meshPose, shapePose);
  const Real pairScale = meshPose.translation.norm() + shapePose.translation.norm() + shape.size() +
                         sb.min.cwiseAbs().maxCoeff() + sb.max.cwiseAbs().maxCoeff();
  const Real pruneSlack = kMeshDistancePruneRelativeTolerance * pairScale;
  struct Visitor {
    const Mesh& mesh;
    const Aabb& sb;
    Real& best;
    decltype(consider)& f;
    const LocalShape& ls;
    Real pruneSlack;
    /// Lower bound on the triangle's signed distance to the shape from separating axes.
    Real axisLowerBound(const Triangle& tri) const {
      Real bound = -kNoLimit;
      const Vec3 nl = (tri.b - tri.a).cross(tri.c - tri.a);
      const Real len = nl.norm();
      if (len > 0) {
        const Vec3 face = nl / len;
        Real lo = 0, hi = 0;
        ls.project(face, lo, hi);
        const Real base = face.dot(tri.a);
        bound = std::max(lo - base, base - hi);
      }
      if (ls.shape.kind == ConvexKind::Box) {
        for (int k = 0; k < 3; ++k) {
          const Vec3 u = ls.axes.col(k);
          const Real c = u.dot(ls.p[0]);
          const Real p0 = u.dot(tri.a) - c, p1 = u.dot(tri.b) - c, p2 = u.dot(tri.c) - c;
          const Real h = ls.half[k];
          bound = std::max(bound, std::max(std::min({p0, p1, p2}) - h, -h - std::max({p0, p1, p2})));
        }
      }
      return bound;
    }
    // Signed distances can be negative: boxes that overlap bound nothing from below.
    Real lowerBound(const Aabb& b) const {
      const Real gap = boxDistance(b, sb);
      return gap > 0 ? gap : -kNoLimit;
    }
    bool entry(const Aabb& b, Real& key) const {
      key = lowerBound(b);
      return key <= best;
    }
    bool keep(Real key) const { return key <= best; }
    bool leaf(std::uint32_t first, std::uint32_t count) {
      for (std::uint32_t k = first; k < first + count; ++k) {
        const Triangle tri = mesh.slotTriangle(k);
        if (lowerBound(bounds(tri)) <= best && !(axisLowerBound(tri) - pruneSlack > best))
          f(mesh.bvh().primIndices[k], tri);
      }
      return true;
    }
  } v{mesh, sb, best, consider, ls, pruneSlack};
  mesh_detail::walkOrdered(mesh, v);
  return r;
}

}  // namespace crux
