/// @file mesh_query.cpp  Ray, shape and mesh–mesh queries against a triangle mesh.
///
/// Every query has one per-triangle decision (the geometry layer's exact test) shared by the
/// BVH path and the brute-force path; the BVH path only adds node culling, which is
/// conservative (node_tests.hpp), so both paths give identical answers. Ray queries traverse
/// front to back (traverseBvh with the entry distance as key) and prune subtrees that start
/// beyond the best hit. Closest, any and boolean queries allocate nothing.

#include <crux/mesh/mesh_query.hpp>

#include <crux/geometry/axis_aligned.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/predicates.hpp>

#include "node_tests.hpp"
#include "ray_kernel.hpp"
#include "relative_frame.hpp"

#include <algorithm>
#include <cmath>

namespace crux {
namespace {

using mesh_detail::kNodeBoxPad;
using mesh_detail::maxAbs;

Real meshScale(const Mesh& mesh) { return mesh.bvh().empty() ? Real(0) : maxAbs(mesh.bvh().nodes[0].bounds); }

// ---- rays ------------------------------------------------------------------------------------

/// Back-face test of RayQueryOptions::cullBackFaces: ((b-a)×(c-a))·dir > 0, in Wide. Zero for
/// degenerate and edge-on triangles, which are therefore never culled.
bool backFacing(const Triangle& t, const Vec3& dir) {
  const WVec3 a = wide(t.a);
  return (wide(t.b) - a).cross(wide(t.c) - a).dot(wide(dir)) > 0;
}

/// The one per-triangle ray decision of every ray query (BVH and brute force).
class TriangleRayTest {
 public:
  TriangleRayTest(const Ray& ray, const RayQueryOptions& options) : ray_(ray), options_(options), filter_(ray) {}

  std::optional<RayHit> operator()(const Triangle& t) const {
    if (filter_.certainlyMisses(t)) return std::nullopt;
    if (options_.cullBackFaces && backFacing(t, ray_.dir)) return std::nullopt;
    return raycast(ray_, t, options_.maxDistance);
  }

 private:
  const Ray& ray_;
  const RayQueryOptions& options_;
  mesh_detail::RayTriangleFilter filter_;
};

/// Orders hits by t, then by triangle index.
bool before(Real t, std::uint32_t tri, const MeshRayHit& best) {
  return t < best.t || (t == best.t && tri < best.triangle);
}

MeshRayHit meshHit(const RayHit& h, std::uint32_t tri) { return {h.t, h.point, h.normal, tri}; }

mesh_detail::RayBoxTest rayBoxTest(const Mesh& mesh, const Ray& ray) {
  const Real scale = std::max(meshScale(mesh), ray.origin.cwiseAbs().maxCoeff());
  return mesh_detail::RayBoxTest(ray.origin, ray.dir, scale);
}

/// Visitor for closest / any hit: keeps the best (t, index), prunes beyond it.
struct RayVisitor {
  const Mesh& mesh;
  const mesh_detail::RayBoxTest& box;
  const TriangleRayTest& test;
  bool stopAtFirst;
  Real sLimit;  // parameter limit: max distance, lowered to the best hit's t
  MeshRayHit best{};
  bool found = false;

  bool enter(const BvhNode& node, Real& key) const { return box.enter(node.bounds, sLimit, key); }
  bool keep(Real key) const { return box.keep(key, sLimit); }
  bool slot(std::uint32_t k) { return hit(mesh.slotTriangle(k), mesh.bvh().primIndices[k]); }
  bool hit(const Triangle& t, std::uint32_t tri) {
    const std::optional<RayHit> h = test(t);
    if (!h) return true;
    if (!found || before(h->t, tri, best)) {
      best = meshHit(*h, tri);
      found = true;
      sLimit = std::min(sLimit, box.parameterLimit(h->t));
    }
    return !stopAtFirst;
  }
};

/// Visitor collecting every hit.
struct RayAllVisitor {
  const Mesh& mesh;
  const mesh_detail::RayBoxTest& box;
  const TriangleRayTest& test;
  Real sLimit;
  std::vector<MeshRayHit>& hits;

  bool enter(const BvhNode& node, Real& key) const { return box.enter(node.bounds, sLimit, key); }
  bool keep(Real) const { return true; }
  bool slot(std::uint32_t k) {
    if (const std::optional<RayHit> h = test(mesh.slotTriangle(k))) hits.push_back(meshHit(*h, mesh.bvh().primIndices[k]));
    return true;
  }
};

std::optional<MeshRayHit> raycastBest(const Mesh& mesh, const Ray& ray, const RayQueryOptions& options,
                                      QueryPath path, bool stopAtFirst) {
  const TriangleRayTest test(ray, options);
  const mesh_detail::RayBoxTest box = rayBoxTest(mesh, ray);
  RayVisitor v{mesh, box, test, stopAtFirst, box.parameterLimit(options.maxDistance)};
  if (path == QueryPath::BruteForce) {
    for (std::uint32_t i = 0, n = std::uint32_t(mesh.triangleCount()); i < n; ++i)
      if (!v.hit(mesh.triangle(i), i)) break;
  } else {
    traverseBvhSlots(mesh.bvh(), v);
  }
  if (!v.found) return std::nullopt;
  return v.best;
}

// ---- shapes ----------------------------------------------------------------------------------

/// Runs a shape query: `nodeTest(bounds)` culls subtrees conservatively, `triTest(triangle)` is
/// the exact per-triangle decision. With `out == nullptr` it stops at the first touching
/// triangle and reports whether there was one; otherwise it appends every touching index
/// (ascending).
template <class NodeTest, class TriTest>
bool shapeQuery(const Mesh& mesh, QueryPath path, const NodeTest& nodeTest, const TriTest& triTest,
                std::vector<std::uint32_t>* out) {
  if (path == QueryPath::BruteForce) {
    bool any = false;
    for (std::uint32_t i = 0, n = std::uint32_t(mesh.triangleCount()); i < n; ++i) {
      if (!triTest(mesh.triangle(i))) continue;
      any = true;
      if (!out) return true;
      out->push_back(i);
    }
    return any;
  }
  struct Visitor {
    const Mesh& mesh;
    const NodeTest& nodeTest;
    const TriTest& triTest;
    std::vector<std::uint32_t>* out;
    bool any = false;
    bool enter(const BvhNode& node, Real&) const { return nodeTest(node.bounds); }
    bool keep(Real) const { return true; }
    bool slot(std::uint32_t k) {
      if (!triTest(mesh.slotTriangle(k))) return true;
      any = true;
      if (!out) return false;
      out->push_back(mesh.bvh().primIndices[k]);
      return true;
    }
  } v{mesh, nodeTest, triTest, out};
  traverseBvhSlots(mesh.bvh(), v);
  if (out) std::sort(out->begin(), out->end());
  return v.any;
}

/// Coordinate scale of a query (the node pads scale with it): the largest magnitude among the
/// mesh bounds and the query shape's coordinates.
Real shapeScale(const Mesh& mesh, std::initializer_list<Real> magnitudes) {
  Real s = meshScale(mesh);
  for (Real m : magnitudes) s = std::max(s, m);
  return s;
}

Real absMax(const Vec3& v) { return v.cwiseAbs().maxCoeff(); }

bool segmentQuery(const Mesh& mesh, const Segment& s, QueryPath path, std::vector<std::uint32_t>* out) {
  const Real scale = shapeScale(mesh, {absMax(s.start), absMax(s.end)});
  const Vec3 d = s.end - s.start;
  const mesh_detail::RayBoxTest box(s.start, d, scale);
  // The segment is the ray from start through end up to world distance |end - start|.
  const Real sLimit = box.parameterLimit(d.norm());
  auto node = [&](const Aabb& b) {
    Real key;
    return box.enter(b, sLimit, key);
  };
  auto tri = [&](const Triangle& t) { return intersects(s, t); };
  return shapeQuery(mesh, path, node, tri, out);
}

bool sphereQuery(const Mesh& mesh, const Sphere& s, QueryPath path, std::vector<std::uint32_t>* out) {
  const Real pad = kNodeBoxPad * shapeScale(mesh, {absMax(s.center), s.radius});
  auto node = [&](const Aabb& b) { return mesh_detail::sphereTouchesBox(s.center, s.radius, b, pad); };
  auto tri = [&](const Triangle& t) { return overlaps(t, s); };
  return shapeQuery(mesh, path, node, tri, out);
}

bool aabbQuery(const Mesh& mesh, const Aabb& q, QueryPath path, std::vector<std::uint32_t>* out) {
  const Real pad = kNodeBoxPad * shapeScale(mesh, {maxAbs(q)});
  auto node = [&](const Aabb& b) { return mesh_detail::boxTouchesBox(q, b, pad); };
  auto tri = [&](const Triangle& t) { return overlaps(t, q); };
  return shapeQuery(mesh, path, node, tri, out);
}

bool obbQuery(const Mesh& mesh, const Obb& q, QueryPath path, std::vector<std::uint32_t>* out) {
  const Real pad = kNodeBoxPad * shapeScale(mesh, {absMax(q.center) + q.half.sum()});
  const mesh_detail::ObbBoxTest box(q.axes, pad);
  const mesh_detail::ObbBoxTest::Placed placed = box.place(q.center, q.half);
  auto node = [&](const Aabb& b) { return box.touches(placed, b); };
  auto tri = [&](const Triangle& t) { return overlaps(t, q); };
  return shapeQuery(mesh, path, node, tri, out);
}

bool planeQuery(const Mesh& mesh, const Plane& p, QueryPath path, std::vector<std::uint32_t>* out) {
  const Real scale = meshScale(mesh);
  auto node = [&](const Aabb& b) { return mesh_detail::planeTouchesBox(p.normal, p.d, b, kNodeBoxPad, scale); };
  auto tri = [&](const Triangle& t) { return overlaps(t, p); };
  return shapeQuery(mesh, path, node, tri, out);
}

bool triangleQuery(const Mesh& mesh, const Triangle& q, QueryPath path, std::vector<std::uint32_t>* out) {
  const Aabb qb = bounds(q);
  const Real scale = shapeScale(mesh, {maxAbs(qb)});
  const Real pad = kNodeBoxPad * scale;
  // Node test: the query's bounding box, then its plane (normal in Wide; the pad covers the
  // rounding of the normal, which is relative to |e1||e2|).
  const WVec3 a = wide(q.a), e1 = wide(q.b) - a, e2 = wide(q.c) - a;
  const WVec3 n = e1.cross(e2);
  const Wide normalError = 8 * std::numeric_limits<Wide>::epsilon() * e1.cwiseAbs().maxCoeff() * e2.cwiseAbs().maxCoeff();
  auto node = [&](const Aabb& b) {
    if (!mesh_detail::boxTouchesBox(qb, b, pad)) return false;
    const WVec3 c = wide(b.center()) - a, h = wide(b.half()).array() + Wide(pad);
    const Wide s = std::fabs(n.dot(c));
    const Wide r = h.dot(n.cwiseAbs());
    const Wide slack = normalError * 3 * (c.cwiseAbs().sum() + h.sum()) + Wide(pad) * n.cwiseAbs().sum() +
                       4 * std::numeric_limits<Wide>::epsilon() * (s + r);
    return s <= r + slack;
  };
  auto tri = [&](const Triangle& t) { return overlaps(t, q); };
  return shapeQuery(mesh, path, node, tri, out);
}

// ---- mesh vs mesh ----------------------------------------------------------------------------

using mesh_detail::RelativeFrame;

/// Triangle pair decision (BVH and brute force): exact bounding-box rejection, then the exact
/// triangle–triangle test.
bool trianglePair(const Triangle& ta, const Aabb& boxA, const Triangle& tbMapped, const Aabb& boxB) {
  if ((boxA.min.array() > boxB.max.array()).any() || (boxB.min.array() > boxA.max.array()).any()) return false;
  return overlaps(ta, tbMapped);
}

using PairList = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

bool meshMeshBrute(const Mesh& a, const Mesh& b, const RelativeFrame& frame, PairList* out) {
  std::vector<Triangle> mapped(b.triangleCount());
  std::vector<Aabb> mappedBox(b.triangleCount());
  for (std::uint32_t j = 0; j < mapped.size(); ++j) {
    mapped[j] = frame.map(b.triangle(j));
    mappedBox[j] = bounds(mapped[j]);
  }
  bool any = false;
  for (std::uint32_t i = 0, n = std::uint32_t(a.triangleCount()); i < n; ++i) {
    const Triangle ta = a.triangle(i);
    const Aabb boxA = bounds(ta);
    for (std::uint32_t j = 0; j < mapped.size(); ++j) {
      if (!trianglePair(ta, boxA, mapped[j], mappedBox[j])) continue;
      any = true;
      if (!out) return true;
      out->emplace_back(i, j);
    }
  }
  return any;
}

/// Simultaneous descent of both BVHs (RTCD 6.3.2: descend the larger node; node pairs as an
/// AABB of a against b's node box mapped into a's frame, an OBB, RTCD 4.4.1). Leaf pairs map b's
/// triangles in chunks into a fixed buffer. Explicit fixed stack: each step pushes at most one
/// deferred pair per level of either tree.
bool meshMeshBvh(const Mesh& a, const Mesh& b, const RelativeFrame& frame, PairList* out) {
  const Bvh& ba = a.bvh();
  const Bvh& bb = b.bvh();
  if (ba.empty() || bb.empty()) return false;
  const Real scale =
      std::max(maxAbs(ba.nodes[0].bounds), maxAbs(bb.nodes[0].bounds) + frame.transform().translation.cwiseAbs().maxCoeff());
  const Real pad = kNodeBoxPad * scale;

  const mesh_detail::ObbBoxTest obb(frame.rotation(), pad);
  // b's node box placed in a's frame: an OBB.
  using Placed = mesh_detail::ObbBoxTest::Placed;
  auto place = [&](const BvhNode& nb) { return obb.place(frame.mapPoint(nb.bounds.center()), nb.bounds.half()); };
  auto nodesTouch = [&](const BvhNode& na, const BvhNode& nb, const Placed& pb) {
    if (frame.identity()) return mesh_detail::boxTouchesBox(na.bounds, nb.bounds, 0);
    return obb.touches(pb, na.bounds);
  };
  // Which node to descend: the larger (sum of extents; nodes are never empty).
  auto size = [](const BvhNode& n) { return (n.bounds.max - n.bounds.min).sum(); };

  constexpr std::uint32_t kChunk = 16;
  Triangle mapped[kChunk];
  Aabb mappedBox[kChunk];
  auto leafPair = [&](const BvhNode& na, const BvhNode& nb) {
    bool any = false;
    for (std::uint32_t j0 = nb.first, je = nb.first + nb.count; j0 < je; j0 += kChunk) {
      const std::uint32_t m = std::min(kChunk, je - j0);
      for (std::uint32_t k = 0; k < m; ++k) {
        mapped[k] = frame.map(b.slotTriangle(j0 + k));
        mappedBox[k] = bounds(mapped[k]);
      }
      for (std::uint32_t i = na.first, ie = na.first + na.count; i < ie; ++i) {
        const Triangle ta = a.slotTriangle(i);
        const Aabb boxA = bounds(ta);
        for (std::uint32_t k = 0; k < m; ++k) {
          if (!trianglePair(ta, boxA, mapped[k], mappedBox[k])) continue;
          any = true;
          if (!out) return true;
          out->emplace_back(ba.primIndices[i], bb.primIndices[j0 + k]);
        }
      }
    }
    return any;
  };

  struct Pair {
    std::uint32_t a, b;
  };
  Pair stack[2 * kBvhMaxDepth + 2];
  int top = 0;
  bool any = false;
  if (!nodesTouch(ba.nodes[0], bb.nodes[0], frame.identity() ? Placed{} : place(bb.nodes[0]))) return false;
  stack[top++] = {0, 0};
  while (top > 0) {
    const Pair p = stack[--top];
    const BvhNode& na = ba.nodes[p.a];
    const BvhNode& nb = bb.nodes[p.b];
    if (na.isLeaf() && nb.isLeaf()) {
      if (leafPair(na, nb)) {
        any = true;
        if (!out) return true;
      }
      continue;
    }
    // Push the second child first so the first child is visited first.
    if (nb.isLeaf() || (!na.isLeaf() && size(na) >= size(nb))) {
      const Placed pb = frame.identity() ? Placed{} : place(nb);  // once for both children of a
      for (std::uint32_t c = 2; c-- > 0;)
        if (nodesTouch(ba.nodes[na.first + c], nb, pb)) stack[top++] = {na.first + c, p.b};
    } else {
      for (std::uint32_t c = 2; c-- > 0;) {
        const BvhNode& child = bb.nodes[nb.first + c];
        if (nodesTouch(na, child, frame.identity() ? Placed{} : place(child))) stack[top++] = {p.a, nb.first + c};
      }
    }
  }
  if (out) std::sort(out->begin(), out->end());
  return any;
}

}  // namespace

// ---- public API --------------------------------------------------------------------------------

std::optional<MeshRayHit> raycastClosest(const Mesh& mesh, const Ray& ray, const RayQueryOptions& options,
                                         QueryPath path) {
  return raycastBest(mesh, ray, options, path, false);
}

bool raycastAny(const Mesh& mesh, const Ray& ray, const RayQueryOptions& options, QueryPath path) {
  return raycastBest(mesh, ray, options, path, true).has_value();
}

std::vector<MeshRayHit> raycastAll(const Mesh& mesh, const Ray& ray, const RayQueryOptions& options,
                                   QueryPath path) {
  std::vector<MeshRayHit> hits;
  const TriangleRayTest test(ray, options);
  if (path == QueryPath::BruteForce) {
    for (std::uint32_t i = 0, n = std::uint32_t(mesh.triangleCount()); i < n; ++i)
      if (const std::optional<RayHit> h = test(mesh.triangle(i))) hits.push_back(meshHit(*h, i));
  } else {
    const mesh_detail::RayBoxTest box = rayBoxTest(mesh, ray);
    RayAllVisitor v{mesh, box, test, box.parameterLimit(options.maxDistance), hits};
    traverseBvhSlots(mesh.bvh(), v);
  }
  std::sort(hits.begin(), hits.end(), [](const MeshRayHit& x, const MeshRayHit& y) {
    return x.t < y.t || (x.t == y.t && x.triangle < y.triangle);
  });
  return hits;
}

bool intersects(const Mesh& mesh, const Segment& s, QueryPath path) { return segmentQuery(mesh, s, path, nullptr); }
bool overlaps(const Mesh& mesh, const Sphere& s, QueryPath path) { return sphereQuery(mesh, s, path, nullptr); }
bool overlaps(const Mesh& mesh, const Aabb& b, QueryPath path) { return aabbQuery(mesh, b, path, nullptr); }
bool overlaps(const Mesh& mesh, const Obb& b, QueryPath path) { return obbQuery(mesh, b, path, nullptr); }
bool overlaps(const Mesh& mesh, const Plane& p, QueryPath path) { return planeQuery(mesh, p, path, nullptr); }
bool overlaps(const Mesh& mesh, const Triangle& t, QueryPath path) { return triangleQuery(mesh, t, path, nullptr); }

std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Segment& s, QueryPath path) {
  std::vector<std::uint32_t> out;
  segmentQuery(mesh, s, path, &out);
  return out;
}
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Sphere& s, QueryPath path) {
  std::vector<std::uint32_t> out;
  sphereQuery(mesh, s, path, &out);
  return out;
}
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Aabb& b, QueryPath path) {
  std::vector<std::uint32_t> out;
  aabbQuery(mesh, b, path, &out);
  return out;
}
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Obb& b, QueryPath path) {
  std::vector<std::uint32_t> out;
  obbQuery(mesh, b, path, &out);
  return out;
}
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Plane& p, QueryPath path) {
  std::vector<std::uint32_t> out;
  planeQuery(mesh, p, path, &out);
  return out;
}
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Triangle& t, QueryPath path) {
  std::vector<std::uint32_t> out;
  triangleQuery(mesh, t, path, &out);
  return out;
}

bool overlaps(const Mesh& a, const Transform& ta, const Mesh& b, const Transform& tb, QueryPath path) {
  const RelativeFrame frame(ta, tb);
  return path == QueryPath::BruteForce ? meshMeshBrute(a, b, frame, nullptr) : meshMeshBvh(a, b, frame, nullptr);
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> touchingTrianglePairs(const Mesh& a, const Transform& ta,
                                                                           const Mesh& b, const Transform& tb,
                                                                           QueryPath path) {
  const RelativeFrame frame(ta, tb);
  PairList out;
  if (path == QueryPath::BruteForce) meshMeshBrute(a, b, frame, &out);
  else meshMeshBvh(a, b, frame, &out);
  return out;
}

}  // namespace crux
