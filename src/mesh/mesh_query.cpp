/// @file mesh_query.cpp  Ray, shape and mesh–mesh queries against a triangle mesh.
///
/// Every query has one per-triangle decision (the geometry layer's exact test) shared by the
/// BVH path and the brute-force path; the BVH path only adds node culling, which is
/// conservative (node_tests.hpp), so both paths give identical answers. Ray queries traverse
/// front to back (mesh_detail::walkOrdered with the entry distance as key) and prune subtrees that start
/// beyond the best hit. Closest, any and boolean queries allocate nothing.

#include <crux/mesh/mesh_query.hpp>
#include <crux/precondition.hpp>

#include <crux/geometry/axis_aligned.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/predicates.hpp>

#include "geometry/unchecked.hpp"
#include "geometry/ray_triangle.hpp"
#include "mesh_walk.hpp"
#include "node_tests.hpp"
#include "ray_kernel.hpp"
#include "relative_frame.hpp"

#include <algorithm>
#include <cmath>

namespace crux {
namespace {

using mesh_detail::kNodeBoxPad;
using mesh_detail::maxAbs;

// ---- rays ------------------------------------------------------------------------------------

/// Back-face test of RayQueryOptions::cullBackFaces: ((b-a)×(c-a))·dir > 0, in Wide. Zero for
/// degenerate and edge-on triangles, which are therefore never culled.
bool backFacing(const Triangle& t, const Vec3& dir) {
  const WVec3 a = wide(t.a);
  return (wide(t.b) - a).cross(wide(t.c) - a).dot(wide(dir)) > 0;
}

using geometry_detail::RayCrossing;

/// The one per-triangle ray decision of every ray query (BVH and brute force): the float
/// filter (ray_kernel.hpp) rejects most misses and proves most hits a proper crossing, whose
/// side and parameter the filter-stage arithmetic then settles (properRayTriangleCrossing);
/// anything else takes raycast's own path (rayTriangleCrossing: exact decision, the exact
/// stage for slivers). A candidate keeps its crossing; only the hit a query reports is formed
/// (hit()), so point, unit normal and square roots are computed for the winner alone.
class TriangleRayTest {
 public:
  /// A triangle the ray hits within maxDistance: its world distance t and its crossing.
  struct Candidate {
    Real t;
    RayCrossing crossing;
  };

  /// The filter's products are taken about the line's point nearest the mesh's box centre
  /// (RayTriangleFilter's anchored form: fewer triangles left undecided, for near origins too:
  /// without it 0.62 % instead of 0.10 % of the tested triangles took the exact path on
  /// bench_scaling's 10k torus). The filter and the ray's length are made at the first triangle: a ray that reaches no leaf
  /// (most candidates of a scene ray) never pays for them.
  TriangleRayTest(const Ray& ray, const RayQueryOptions& options, const Mesh& mesh)
      : ray_(ray), options_(options), mesh_(mesh) {}

  /// Whether the ray hits triangle t within maxDistance (then `out` is set).
  bool operator()(const Triangle& t, Candidate& out) const { return test(t, setup().filter.classify(t), out); }

  /// Tests the triangles of slots [first, first + count) of mesh's BVH, four at a time through
  /// the filter (the same verdict per triangle as one at a time), calling f(slot, candidate)
  /// for each hit; false when f stopped it.
  template <class F>
  bool slots(const Mesh& mesh, std::uint32_t first, std::uint32_t count, F&& f) const {
    return mesh_detail::filterSlots(setup().filter, mesh, first, count,
                                    [&](std::uint32_t k, const Triangle& t, mesh_detail::RayTriangleFilter::Verdict v) {
                                      Candidate cand;
                                      return !test(t, v, cand) || f(k, cand);
                                    });
  }

  bool test(const Triangle& t, mesh_detail::RayTriangleFilter::Verdict v, Candidate& out) const {
    if (v == mesh_detail::RayTriangleFilter::kMisses) return false;
    if (options_.cullBackFaces && backFacing(t, ray_.dir)) return false;
    int decided = -1;
    if (v != mesh_detail::RayTriangleFilter::kUnknown) {
      const int det = v == mesh_detail::RayTriangleFilter::kCrossesBack ? 1 : -1;
      decided = geometry_detail::properRayTriangleCrossing(ray_, t, det, out.crossing);
      if (counters_) ++counters_->certified;
      if (decided == 0) return false;
    }
    if (decided < 0) {
      if (counters_) ++counters_->exactPath;
      const std::optional<RayCrossing> c = geometry_detail::rayTriangleCrossing(ray_, t);
      if (!c) return false;
      out.crossing = *c;
    }
    // the distance rayHitAt (makeHit) reports; beyond maxDistance or not finite: no hit
    out.t = Real(out.crossing.s * setup().length);
    return out.t <= options_.maxDistance && std::isfinite(out.t);
  }

  /// The reported hit of a candidate (the same as raycast(ray, triangle) but for a parameter
  /// certified by the filter stage alone).
  MeshRayHit hit(const Candidate& c, std::uint32_t tri) const {
    // (never empty: the candidate's t was formed by the same rule and checked against maxDistance)
    const std::optional<RayHit> h = geometry_detail::rayHitAt(ray_, c.crossing, options_.maxDistance, setup().length);
    return {h->t, h->point, h->normal, tri};
  }

  void count(RayQueryCounters* counters) { counters_ = counters; }

 private:
  struct Setup {
    mesh_detail::RayTriangleFilter filter;
    Wide length;  // rayLength(dir): a crossing's parameter times it is its world distance
  };
  const Setup& setup() const {
    if (!setup_) setup_.emplace(Setup{mesh_detail::RayTriangleFilter(ray_, mesh_.bounds().center()),
                                      geometry_detail::rayLength(ray_.dir)});
    return *setup_;
  }

  const Ray& ray_;
  const RayQueryOptions& options_;
  const Mesh& mesh_;
  mutable std::optional<Setup> setup_;  // made by the first triangle test (one query, one thread)
  RayQueryCounters* counters_ = nullptr;
};

/// Orders hits by t, then by triangle index.
bool before(Real t, std::uint32_t tri, Real bestT, std::uint32_t bestTri) {
  return t < bestT || (t == bestT && tri < bestTri);
}

mesh_detail::RayBoxTest rayBoxTest(const Mesh& mesh, const Ray& ray) {
  return mesh_detail::meshRayBoxTest(mesh.scale(), ray.origin, ray.dir);
}

/// Visitor for closest / any hit: keeps the best (t, index), prunes beyond it. kCounted: it
/// counts nodes and triangles into `counters` (a separate instance, so the uncounted walk has
/// no stores through a pointer that might alias the ray's constants).
template <bool kCounted>
struct RayVisitor {
  const Mesh& mesh;
  const mesh_detail::RayBoxTest& box;
  const TriangleRayTest& test;
  bool stopAtFirst;
  Real sLimit;  // parameter limit: max distance, lowered to the best hit's t
  RayQueryCounters* counters;
  TriangleRayTest::Candidate best{};
  std::uint32_t bestTriangle = 0;
  bool found = false;

  bool entry(const Aabb& b, Real& key) const {
    if constexpr (kCounted) ++counters->nodes;
    return box.enter(b, sLimit, key);
  }
  unsigned entry4(const WideBvhNode& node, Real (&keys)[4]) const {
    if constexpr (kCounted) ++counters->nodes;
    return box.enter4(node, sLimit, keys);
  }
  bool keep(Real key) const { return box.keep(key, sLimit); }
  bool leaf(std::uint32_t first, std::uint32_t count) {
    if constexpr (kCounted) counters->triangles += count;
    return test.slots(mesh, first, count,
                      [&](std::uint32_t k, const TriangleRayTest::Candidate& c) { return offer(c, mesh.bvh().primIndices[k]); });
  }
  /// The brute-force path's visit of triangle i.
  bool triangle(std::uint32_t i) {
    if constexpr (kCounted) ++counters->triangles;
    TriangleRayTest::Candidate c;
    return !test(mesh.triangle(i), c) || offer(c, i);
  }
  bool offer(const TriangleRayTest::Candidate& c, std::uint32_t tri) {
    if (!found || before(c.t, tri, best.t, bestTriangle)) {
      best = c;
      bestTriangle = tri;
      found = true;
      sLimit = std::min(sLimit, box.parameterLimit(c.t));
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

  bool entry(const Aabb& b, Real& key) const { return box.enter(b, sLimit, key); }
  unsigned entry4(const WideBvhNode& node, Real (&keys)[4]) const { return box.enter4(node, sLimit, keys); }
  bool keep(Real) const { return true; }
  bool leaf(std::uint32_t first, std::uint32_t count) {
    return test.slots(mesh, first, count, [&](std::uint32_t k, const TriangleRayTest::Candidate& c) {
      hits.push_back(test.hit(c, mesh.bvh().primIndices[k]));
      return true;
    });
  }
};

/// The closest hit, or with stopAtFirst the first hit found (raycastAny), whose point and normal are
/// then left zero: a yes/no answer needs no hit formed.
std::optional<MeshRayHit> raycastBest(const Mesh& mesh, const Ray& ray, const RayQueryOptions& options,
                                      QueryPath path, bool stopAtFirst) {
  if (!detail::entryPreconditions(stopAtFirst ? "raycastAny(Mesh, Ray)" : "raycastClosest(Mesh, Ray)", detail::rule::kRay, ray))
    return std::nullopt;
  TriangleRayTest test(ray, options, mesh);
  test.count(options.counters);
  const mesh_detail::RayBoxTest box = rayBoxTest(mesh, ray);
  const auto run = [&](auto v) -> std::optional<MeshRayHit> {
    if (path == QueryPath::BruteForce) {
      for (std::uint32_t i = 0, n = std::uint32_t(mesh.triangleCount()); i < n; ++i)
        if (!v.triangle(i)) break;
    } else {
      mesh_detail::walkOrdered(mesh, v);
    }
    if (!v.found) return std::nullopt;
    if (stopAtFirst) return MeshRayHit{v.best.t, Vec3::Zero(), Vec3::Zero(), v.bestTriangle};  // (raycastAny: yes/no)
    return test.hit(v.best, v.bestTriangle);
  };
  const Real sLimit = box.parameterLimit(options.maxDistance);
  if (options.counters) return run(RayVisitor<true>{mesh, box, test, stopAtFirst, sLimit, options.counters});
  return run(RayVisitor<false>{mesh, box, test, stopAtFirst, sLimit, nullptr});
}

// ---- shapes ----------------------------------------------------------------------------------

/// Runs a shape query: `nodeTest(box)` culls subtrees conservatively (mesh_walk.hpp: over the
/// mesh's wide or binary BVH), `triTest(triangle)` is the exact per-triangle decision.
/// With `out == nullptr` it stops at the first touching triangle and reports whether there was
/// one; otherwise it appends every touching index (ascending). Optional: `laneTest(node)`, the
/// node test on a wide node's four lanes; `slotsTest(first, count, touched)`, triTest on a
/// leaf's slots together, calling touched(k) for each slot k whose triangle passes (in slot
/// order; false from it stops the test, which then returns false).
template <class NodeTest, class TriTest, class LaneTest = std::nullptr_t, class SlotsTest = std::nullptr_t>
bool shapeQuery(const Mesh& mesh, QueryPath path, const NodeTest& nodeTest, const TriTest& triTest,
                std::vector<std::uint32_t>* out, const LaneTest& laneTest = nullptr,
                const SlotsTest& slotsTest = nullptr) {
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
    const LaneTest& laneTest;
    bool touches(const Aabb& b) const { return nodeTest(b); }
    unsigned touches4(const WideBvhNode& n) const {
      if constexpr (std::is_same_v<LaneTest, std::nullptr_t>) return mesh_detail::eachLane(n, nodeTest);
      else return laneTest(n);
    }
    const SlotsTest& slotsTest;
    bool slot(std::uint32_t k) { return !triTest(mesh.slotTriangle(k)) || touched(k); }
    bool leaf(std::uint32_t first, std::uint32_t count) {
      if constexpr (std::is_same_v<SlotsTest, std::nullptr_t>) {
        for (std::uint32_t k = first, end = first + count; k < end; ++k)
          if (!slot(k)) return false;
        return true;
      } else {
        return slotsTest(first, count, [&](std::uint32_t k) { return touched(k); });
      }
    }
    bool touched(std::uint32_t k) {
      any = true;
      if (!out) return false;
      out->push_back(mesh.bvh().primIndices[k]);
      return true;
    }
  } v{mesh, nodeTest, triTest, out, false, laneTest, slotsTest};
  mesh_detail::walkSlots(mesh, v);
  if (out) std::sort(out->begin(), out->end());
  return v.any;
}

/// Coordinate scale of a query (the node pads scale with it): the largest magnitude among the
/// mesh bounds and the query shape's coordinates.
Real shapeScale(const Mesh& mesh, std::initializer_list<Real> magnitudes) {
  Real s = mesh.scale();
  for (Real m : magnitudes) s = std::max(s, m);
  return s;
}

Real absMax(const Vec3& v) { return v.cwiseAbs().maxCoeff(); }

bool segmentQuery(const Mesh& mesh, const Segment& s, QueryPath path, std::vector<std::uint32_t>* out) {
  if (!detail::entryPreconditions("intersects / touchingTriangles(Mesh, Segment)", detail::rule::kSegment, s)) return false;
  const Real scale = shapeScale(mesh, {absMax(s.start), absMax(s.end)});
  const Vec3 d = s.end - s.start;
  const mesh_detail::RayBoxTest box(s.start, d, scale);
  // The segment is the ray from start through end up to world distance |end - start|.
  const Real sLimit = box.parameterLimit(d.norm());
  auto node = [&](const Aabb& b) {
    Real key;
    return box.enter(b, sLimit, key);
  };
  auto lanes = [&](const WideBvhNode& n) {
    Real keys[4];
    return box.enter4(n, sLimit, keys);
  };
  // The float filter of the segment's line in front of the exact test. Its direction end −
  // start is rounded in Real, which moves each edge product by at most 2ε·|ℓ|₁·|d|∞·|u|∞, far
  // inside the filter's margin (64ε on the same terms). A zero-length segment gives zero
  // products, which it never rejects; a direction that overflows Real is not filtered.
  const mesh_detail::RayTriangleFilter filter(Ray{s.start, d});
  auto tri = [&](const Triangle& t) {
    return filter.classify(t) != mesh_detail::RayTriangleFilter::kMisses && unchecked::intersects(s, t);
  };
  auto slots = [&](std::uint32_t first, std::uint32_t count, auto&& touched) {
    return mesh_detail::filterSlots(filter, mesh, first, count,
                                    [&](std::uint32_t k, const Triangle& t, mesh_detail::RayTriangleFilter::Verdict) {
                                      return !unchecked::intersects(s, t) || touched(k);
                                    });
  };
  if (!d.allFinite()) {  // (a direction that overflows Real is not filtered)
    auto exactOnly = [&](const Triangle& t) { return unchecked::intersects(s, t); };
    return shapeQuery(mesh, path, node, exactOnly, out, lanes);
  }
  return shapeQuery(mesh, path, node, tri, out, lanes, slots);
}

bool sphereQuery(const Mesh& mesh, const Sphere& s, QueryPath path, std::vector<std::uint32_t>* out) {
  if (!detail::entryPreconditions("overlaps / touchingTriangles(Mesh, Sphere)", detail::rule::kSphere, s)) return false;
  const Real pad = kNodeBoxPad * shapeScale(mesh, {absMax(s.center), s.radius});
  auto node = [&](const Aabb& b) { return mesh_detail::sphereTouchesBox(s.center, s.radius, b, pad); };
  auto tri = [&](const Triangle& t) { return unchecked::overlaps(t, s); };
  return shapeQuery(mesh, path, node, tri, out);
}

bool aabbQuery(const Mesh& mesh, const Aabb& q, QueryPath path, std::vector<std::uint32_t>* out) {
  if (!detail::entryPreconditions("overlaps / touchingTriangles(Mesh, Aabb)", detail::rule::kAabb, q)) return false;
  const Real pad = kNodeBoxPad * shapeScale(mesh, {maxAbs(q)});
  auto node = [&](const Aabb& b) { return mesh_detail::boxTouchesBox(q, b, pad); };
  auto tri = [&](const Triangle& t) { return unchecked::overlaps(t, q); };
  return shapeQuery(mesh, path, node, tri, out);
}

bool obbQuery(const Mesh& mesh, const Obb& q, QueryPath path, std::vector<std::uint32_t>* out) {
  if (!detail::entryPreconditions("overlaps / touchingTriangles(Mesh, Obb)", detail::rule::kObb, q)) return false;
  const Real pad = kNodeBoxPad * shapeScale(mesh, {absMax(q.center) + q.half.sum()});
  const mesh_detail::ObbBoxTest box(q.axes, pad);
  const mesh_detail::ObbBoxTest::Placed placed = box.place(q.center, q.half);
  auto node = [&](const Aabb& b) { return box.touches(placed, b); };
  auto lanes = [&](const WideBvhNode& n) { return box.touches4(placed, n); };
  auto tri = [&](const Triangle& t) { return unchecked::overlaps(t, q); };
  return shapeQuery(mesh, path, node, tri, out, lanes);
}

bool planeQuery(const Mesh& mesh, const Plane& p, QueryPath path, std::vector<std::uint32_t>* out) {
  if (!detail::entryPreconditions("overlaps / touchingTriangles(Mesh, Plane)", detail::rule::kPlane, p)) return false;
  const Real scale = mesh.scale();
  auto node = [&](const Aabb& b) { return mesh_detail::planeTouchesBox(p.normal, p.d, b, kNodeBoxPad, scale); };
  auto tri = [&](const Triangle& t) { return unchecked::overlaps(t, p); };
  return shapeQuery(mesh, path, node, tri, out);
}

bool triangleQuery(const Mesh& mesh, const Triangle& q, QueryPath path, std::vector<std::uint32_t>* out) {
  if (!detail::entryPreconditions("overlaps / touchingTriangles(Mesh, Triangle)", detail::rule::kTriangle, q)) return false;
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
  auto tri = [&](const Triangle& t) { return unchecked::overlaps(t, q); };
  return shapeQuery(mesh, path, node, tri, out);
}

// ---- mesh vs mesh ----------------------------------------------------------------------------

using mesh_detail::RelativeFrame;

/// Triangle pair decision (BVH and brute force): exact bounding-box rejection, then the exact
/// triangle–triangle test.
bool trianglePair(const Triangle& ta, const Aabb& boxA, const Triangle& tbMapped, const Aabb& boxB) {
  if ((boxA.min.array() > boxB.max.array()).any() || (boxB.min.array() > boxA.max.array()).any()) return false;
  return unchecked::overlaps(ta, tbMapped);
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

/// Simultaneous descent of both wide BVHs (RTCD 6.3.2: descend the larger subtree, its four
/// lanes tested at once; subtree pairs as an AABB of a against b's box mapped into a's frame, an
/// OBB, RTCD 4.4.1). Leaf pairs map b's triangles in chunks into a fixed buffer. Explicit fixed
/// stack of subtree ids (wideSubtree): each step pushes at most three more pairs than it pops,
/// per level of either tree.
bool meshMeshBvh(const Mesh& a, const Mesh& b, const RelativeFrame& frame, PairList* out) {
  const WideBvh& ba = a.bvh();
  const WideBvh& bb = b.bvh();
  if (ba.empty() || bb.empty()) return false;
  const Real scale = std::max(a.scale(), b.scale() + frame.transform().translation.cwiseAbs().maxCoeff());
  const Real pad = kNodeBoxPad * scale;

  const mesh_detail::ObbBoxTest obb(frame.rotation(), pad);
  // b's box placed in a's frame: an OBB.
  auto place = [&](const Aabb& boxB) { return obb.place(frame.mapPoint(boxB.center()), boxB.half()); };
  auto touches = [&](const Aabb& boxA, const Aabb& boxB) {
    if (frame.identity()) return mesh_detail::boxTouchesBox(boxA, boxB, 0);
    return obb.touches(place(boxB), boxA);
  };
  // Which subtree to descend: the larger (sum of extents; subtrees are never empty).
  auto size = [](const Aabb& box) { return (box.max - box.min).sum(); };

  constexpr std::uint32_t kChunk = 16;
  Triangle mapped[kChunk];
  Aabb mappedBox[kChunk];
  auto leafPair = [&](const WideSubtree& sa, const WideSubtree& sb) {
    bool any = false;
    for (std::uint32_t j0 = sb.first, je = sb.first + sb.count; j0 < je; j0 += kChunk) {
      const std::uint32_t m = std::min(kChunk, je - j0);
      for (std::uint32_t k = 0; k < m; ++k) {
        mapped[k] = frame.map(b.slotTriangle(j0 + k));
        mappedBox[k] = bounds(mapped[k]);
      }
      for (std::uint32_t i = sa.first, ie = sa.first + sa.count; i < ie; ++i) {
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
  Pair stack[2 * kWideBvhStackSize];
  int top = 0;
  bool any = false;
  if (!touches(a.bounds(), b.bounds())) return false;
  stack[top++] = {0, 0};
  while (top > 0) {
    const Pair p = stack[--top];
    const WideSubtree sa = wideSubtree(ba, p.a), sb = wideSubtree(bb, p.b);
    if (sa.isLeaf() && sb.isLeaf()) {
      if (leafPair(sa, sb)) {
        any = true;
        if (!out) return true;
      }
      continue;
    }
    const Aabb boxA = wideSubtreeBounds(ba, p.a), boxB = wideSubtreeBounds(bb, p.b);
    // Push the last lane first so the first lane is visited first.
    if (sb.isLeaf() || (!sa.isLeaf() && size(boxA) >= size(boxB))) {
      const WideBvhNode& node = ba.nodes[sa.first];
      const unsigned lanes = frame.identity()
                                 ? mesh_detail::eachLane(node, [&](const Aabb& box) { return mesh_detail::boxTouchesBox(box, boxB, 0); })
                                 : obb.touches4(place(boxB), node);  // b's box placed once for a's four lanes
      for (int i = 4; i-- > 0;)
        if (lanes >> i & 1u) stack[top++] = {wideLaneId(sa.first, i), p.b};
    } else {
      const WideBvhNode& node = bb.nodes[sb.first];
      for (int i = 4; i-- > 0;)
        if (node.used(i) && touches(boxA, node.laneBounds(i))) stack[top++] = {p.a, wideLaneId(sb.first, i)};
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
  if (!detail::entryPreconditions("raycastAll(Mesh, Ray)", detail::rule::kRay, ray)) return {};
  std::vector<MeshRayHit> hits;
  const TriangleRayTest test(ray, options, mesh);
  if (path == QueryPath::BruteForce) {
    TriangleRayTest::Candidate c;
    for (std::uint32_t i = 0, n = std::uint32_t(mesh.triangleCount()); i < n; ++i)
      if (test(mesh.triangle(i), c)) hits.push_back(test.hit(c, i));
  } else {
    const mesh_detail::RayBoxTest box = rayBoxTest(mesh, ray);
    RayAllVisitor v{mesh, box, test, box.parameterLimit(options.maxDistance), hits};
    mesh_detail::walkOrdered(mesh, v);
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
  if (!detail::entryPreconditions("overlaps(Mesh, Mesh)", detail::rule::kPoses, ta, tb)) return false;
  const RelativeFrame frame(ta, tb);
  return path == QueryPath::BruteForce ? meshMeshBrute(a, b, frame, nullptr) : meshMeshBvh(a, b, frame, nullptr);
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> touchingTrianglePairs(const Mesh& a, const Transform& ta,
                                                                           const Mesh& b, const Transform& tb,
                                                                           QueryPath path) {
  if (!detail::entryPreconditions("touchingTrianglePairs(Mesh, Mesh)", detail::rule::kPoses, ta, tb)) return {};
  const RelativeFrame frame(ta, tb);
  PairList out;
  if (path == QueryPath::BruteForce) meshMeshBrute(a, b, frame, &out);
  else meshMeshBvh(a, b, frame, &out);
  return out;
}

}  // namespace crux
