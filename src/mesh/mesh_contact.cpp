// Mesh vs convex shape: BVH candidate search, per-triangle convex contacts / distance,
// internal-edge correction with a caller-kept adjacency, reduction to 4 points.

#include <crux/mesh/mesh_contact.hpp>

#include <crux/geometry/closest_point.hpp>
#include <crux/error.hpp>

#include <algorithm>
#include <array>
#include <cmath>
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
}

Real MeshContactManifold::depth() const {
  Real d = 0;
  for (int i = 0; i < count; ++i) d = std::max(d, -points[i].separation);
  return d;
}

namespace {

/// The shape's AABB in the mesh frame (rel maps shape-local to mesh-local), by six supports.
Aabb shapeBoundsIn(const ConvexShape& shape, const Transform& rel) {
  Aabb box = Aabb::empty();
  const Quat inv = rel.rotation.conjugate();
  for (int k = 0; k < 3; ++k) {
    Vec3 e = Vec3::Zero();
    e[k] = 1;
    box.grow(rel.apply(support(shape, inv * e)));
    box.grow(rel.apply(support(shape, inv * (-e))));
  }
  return box;
}

bool boxesOverlap(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

/// Distance between two boxes (0 when they overlap): a lower bound of the distance of anything
/// inside them.
Real boxDistance(const Aabb& a, const Aabb& b) {
  const Vec3 gap = (a.min - b.max).cwiseMax(b.min - a.max).cwiseMax(Vec3::Zero());
  return gap.norm();
}

/// Conservative slack added to computed boxes so rounding never prunes a triangle the
/// per-triangle routine would report: 1000 ulps of Real × the coordinates' magnitude.
Real boxSlack(const Aabb& box) {
  const Real scale = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff()) +
                     (box.max - box.min).maxCoeff();
  return kMeshFeatureRelativeTolerance * scale;
}

struct Collector {
  const Mesh& mesh;
  const Transform& meshPose;
  const ConvexShape& shape;
  const Transform& shapePose;
  Real margin;
  const MeshAdjacency* adjacency;
  Real mergeTol2;
  MeshContactPoint buf[kMeshContactBuffer];
  int n = 0;

  void add(const MeshContactPoint& p) {
    for (int i = 0; i < n; ++i) {
      MeshContactPoint& q = buf[i];
      if ((q.pointA - p.pointA).squaredNorm() <= mergeTol2 && q.normal.dot(p.normal) >= kContactFaceAngleCos) {
        if (p.separation < q.separation || (p.separation == q.separation && p.triangle < q.triangle)) q = p;
        return;
      }
    }
    if (n < kMeshContactBuffer) {
      buf[n++] = p;
      return;
    }
    int worst = 0;  // full: replace the shallowest when p is deeper
    for (int i = 1; i < n; ++i)
      if (buf[i].separation > buf[worst].separation) worst = i;
    if (p.separation < buf[worst].separation) buf[worst] = p;
  }

  /// Internal-edge correction of one point (see the header). Returns false to drop it.
  bool correct(std::uint32_t t, MeshContactPoint& p) const {
    const Triangle tri = mesh.triangle(t);
    const Vec3 e0 = tri.b - tri.a, e1 = tri.c - tri.b, e2 = tri.a - tri.c;
    Vec3 face = e0.cross(tri.c - tri.a);
    const Real len = face.norm();
    if (!(len > 0)) return true;  // degenerate triangle: no face cone
    face /= len;
    const Vec3 nLocal = meshPose.rotation.conjugate() * p.normal;  // shape -> mesh
    if (std::abs(face.dot(nLocal)) >= kMeshFaceConeCos) return true;  // within the face cone
    const Real scale = std::max({e0.norm(), e1.norm(), e2.norm()}) +
                       std::max({tri.a.cwiseAbs().maxCoeff(), tri.b.cwiseAbs().maxCoeff(),
                                 tri.c.cwiseAbs().maxCoeff()});
    const Real tol = kMeshFeatureRelativeTolerance * scale;
    const Vec3 pa = meshPose.inverse().apply(p.pointA);
    bool onEdge[3];
    int edges = 0;
    for (int i = 0; i < 3; ++i) {
      const Vec3 u = tri[i], v = tri[(i + 1) % 3];
      const Segment s{u, v};
      const Vec3 c = closestPoint(s, pa);
      onEdge[i] = (c - pa).squaredNorm() <= tol * tol;
      edges += onEdge[i];
    }
    if (edges == 0) return true;  // face interior: the convex routine's normal stands
    {
      // The side of the (two-sided) triangle the shape is on: the one it reaches farther into
      // (the contact normal may be nearly parallel to the plane, so its sign says nothing).
      const Transform rel = meshPose.inverse() * shapePose;
      const Quat inv = rel.rotation.conjugate();
      const Real up = face.dot(rel.apply(support(shape, inv * face)) - tri.a);
      const Real down = -face.dot(rel.apply(support(shape, inv * (-face))) - tri.a);
      if (down > up) face = -face;
    }
    auto active = [&](int i) {
      const std::uint32_t nb = adjacency->neighbor(t, i);
      if (nb == MeshAdjacency::kNone) return true;
      const auto& own = mesh.triangles()[t];
      const auto& other = mesh.triangles()[nb];
      const std::uint32_t u = own[i], v = own[(i + 1) % 3];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t w = other[k];
        if (w == u || w == v) continue;
        const Real d = face.dot(mesh.vertices()[w] - tri[i]);
        return d < -tol;  // convex: the neighbour falls away from the shape's side
      }
      return true;  // neighbour without a third vertex (degenerate): treat as boundary
    };
    bool isActive = false;
    for (int i = 0; i < 3; ++i)
      if (onEdge[i] && active(i)) isActive = true;
    if (isActive) return true;
    // Inactive (flat or concave) edge or vertex: use the face normal.
    const Vec3 fW = meshPose.rotation * face;  // mesh outward, towards the shape
    const Vec3 n = -fW;                        // B -> A
    const Vec3 dirLocal = shapePose.rotation.conjugate() * n;
    const Vec3 pb = shapePose.apply(support(shape, dirLocal));
    const Real sep = fW.dot(pb - meshPose.apply(tri.a));
    if (sep > margin) return false;
    const Vec3 pa2 = pb - sep * fW;
    // The projection must lie on this triangle: otherwise the triangle beyond the inactive
    // feature (or another one) holds that point and reports it with its own face.
    if ((closestPoint(tri, meshPose.inverse().apply(pa2)) - meshPose.inverse().apply(pa2)).squaredNorm() > tol * tol)
      return false;
    p.normal = n;
    p.pointB = pb;
    p.separation = sep;
    p.pointA = pa2;
    return true;
  }

  /// Cheap conservative reject: the triangle's plane separates it from the shape by more than
  /// the margin (plus rounding slack), so the convex routine would report nothing.
  bool planeSeparates(const Triangle& tri) const {
    const Vec3 nl = (tri.b - tri.a).cross(tri.c - tri.a);
    const Real len = nl.norm();
    if (!(len > 0)) return false;
    const Vec3 face = meshPose.rotation * (nl / len);
    const Vec3 a = meshPose.apply(tri.a);
    const Quat inv = shapePose.rotation.conjugate();
    const Real up = face.dot(shapePose.apply(support(shape, inv * (-face))) - a);  // shape's lowest above
    const Real down = -face.dot(shapePose.apply(support(shape, inv * face)) - a);  // shape's highest below
    const Real slack = kMeshFeatureRelativeTolerance *
                       (a.cwiseAbs().maxCoeff() + shapePose.translation.cwiseAbs().maxCoeff() + shape.size() +
                        (tri.b - tri.a).norm() + (tri.c - tri.a).norm());
    return up > margin + slack || down > margin + slack;
  }

  void triangle(std::uint32_t t, const Triangle& tri) {
    if (planeSeparates(tri)) return;
    ContactManifold m;
    if (!contacts(ConvexShape(tri), meshPose, shape, shapePose, margin, m)) return;
    for (int i = 0; i < m.count; ++i) {
      MeshContactPoint p;
      p.pointA = m.points[i].pointA;
      p.pointB = m.points[i].pointB;
      p.normal = m.normal;
      p.separation = m.points[i].separation;
      p.triangle = t;
      p.featureB = m.points[i].featureB;
      if (adjacency && !correct(t, p)) continue;
      add(p);
    }
  }

  /// Deepest, then the farthest from it, then the point of largest |area| with those two, then
  /// the one adding most area to that triangle (about the deepest normal); stops early when the
  /// next point adds nothing (coincident or collinear within the merge tolerance).
  void reduce(MeshContactManifold& out, Real mergeTol) {
    out.count = 0;
    if (n == 0) return;
    int sel[4] = {0, -1, -1, -1};
    for (int i = 1; i < n; ++i)
      if (buf[i].separation < buf[sel[0]].separation ||
          (buf[i].separation == buf[sel[0]].separation && buf[i].triangle < buf[sel[0]].triangle))
        sel[0] = i;
    out.points[out.count++] = buf[sel[0]];
    auto P = [&](int i) { return buf[i].pointA.template cast<double>(); };
    const Eigen::Vector3d u = buf[sel[0]].normal.template cast<double>();
    const double tol = double(mergeTol);
    double best = tol * tol;
    for (int i = 0; i < n; ++i)
      if ((P(i) - P(sel[0])).squaredNorm() > best) {
        best = (P(i) - P(sel[0])).squaredNorm();
        sel[1] = i;
      }
    if (sel[1] < 0) return;
    out.points[out.count++] = buf[sel[1]];
    const double areaTol = tol * (P(sel[1]) - P(sel[0])).norm();
    auto area = [&](int i) { return (P(sel[1]) - P(sel[0])).cross(P(i) - P(sel[0])).dot(u); };
    double a2 = areaTol;
    for (int i = 0; i < n; ++i)
      if (std::abs(area(i)) > a2) {
        a2 = std::abs(area(i));
        sel[2] = i;
      }
    if (sel[2] < 0) return;
    out.points[out.count++] = buf[sel[2]];
    const double orient = area(sel[2]) > 0 ? 1 : -1;
    double g3 = areaTol;
    for (int i = 0; i < n; ++i) {
      double gain = 0;  // area outside the triangle's edges
      for (int e = 0; e < 3; ++e) {
        const Eigen::Vector3d a = P(sel[e]), b = P(sel[(e + 1) % 3]);
        gain = std::max(gain, -orient * (b - a).cross(P(i) - a).dot(u));
      }
      if (gain > g3) {
        g3 = gain;
        sel[3] = i;
      }
    }
    if (sel[3] >= 0) out.points[out.count++] = buf[sel[3]];
  }
};

}  // namespace

bool contacts(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape, const Transform& shapePose,
              Real margin, MeshContactManifold& out, const MeshAdjacency* adjacency, QueryPath path) {
  out.count = 0;
  validateContactMargin(margin);
  if (adjacency && adjacency->triangleCount() != mesh.triangleCount())
    throw InvalidInput("adjacency: built for a mesh of " + std::to_string(adjacency->triangleCount()) +
                       " triangles, this mesh has " + std::to_string(mesh.triangleCount()));
  const Real size = shape.size();
  const Real mergeTol = kMeshContactMergeRelativeTolerance * (size > 0 ? size : Real(1));
  Collector c{mesh, meshPose, shape, shapePose, margin, adjacency, mergeTol * mergeTol, {}, 0};
  if (path == QueryPath::BruteForce) {
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) c.triangle(t, mesh.triangle(t));
  } else {
    const Transform rel = meshPose.inverse() * shapePose;
    Aabb query = shapeBoundsIn(shape, rel);
    const Real grow = margin + boxSlack(query);
    query.min.array() -= grow;
    query.max.array() += grow;
    struct Visitor {
      const Mesh& mesh;
      const Aabb& query;
      Collector& c;
      bool enter(const BvhNode& node, Real& key) {
        key = 0;
        return boxesOverlap(node.bounds, query);
      }
      bool keep(Real) { return true; }
      bool slot(std::uint32_t k) {
        const Triangle tri = mesh.slotTriangle(k);
        if (boxesOverlap(bounds(tri), query)) c.triangle(mesh.bvh().primIndices[k], tri);
        return true;
      }
    } v{mesh, query, c};
    traverseBvhSlots(mesh.bvh(), v);
  }
  c.reduce(out, mergeTol);
  return out.count > 0;
}

MeshDistanceResult distance(const Mesh& mesh, const Transform& meshPose, const ConvexShape& shape,
                            const Transform& shapePose, Real maxDistance, QueryPath path) {
  if (std::isnan(maxDistance)) throw InvalidInput("maxDistance: expected a number (or +inf for no limit), got NaN");
  MeshDistanceResult r;
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
  struct Visitor {
    const Mesh& mesh;
    const Aabb& sb;
    Real& best;
    decltype(consider)& f;
    // Signed distances can be negative: boxes that overlap bound nothing from below.
    Real lowerBound(const Aabb& b) const {
      const Real gap = boxDistance(b, sb);
      return gap > 0 ? gap : -kNoLimit;
    }
    bool enter(const BvhNode& node, Real& key) {
      key = lowerBound(node.bounds);
      return key <= best;
    }
    bool keep(Real key) { return key <= best; }
    bool slot(std::uint32_t k) {
      const Triangle tri = mesh.slotTriangle(k);
      if (lowerBound(bounds(tri)) <= best) f(mesh.bvh().primIndices[k], tri);
      return true;
    }
  } v{mesh, sb, best, consider};
  traverseBvhSlots(mesh.bvh(), v);
  return r;
}

}  // namespace crux
