/// @file mesh_volume.cpp  Closedness census and exact ray-parity point-in-mesh (see the header
/// for the method and why it terminates).

#include <crux/mesh/mesh_volume.hpp>

#include <crux/error.hpp>
#include <crux/geometry/axis_aligned.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/predicates.hpp>
#include <crux/mesh/mesh_query.hpp>

#include "mesh_walk.hpp"
#include "node_tests.hpp"
#include "relative_frame.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace crux {

// ---- closedness -----------------------------------------------------------------------------

std::string MeshClosedness::reason(const std::string& meshName) const {
  if (closed()) return {};
  std::string head = "mesh \"" + meshName + "\" is not closed: ";
  if (effectiveTriangles == 0) return head + "it has no triangle with three distinct vertex indices";
  std::string why = "edge (" + std::to_string(edgeI) + "," + std::to_string(edgeJ) + ") is used ";
  if (edgeSameDirection)
    why += "twice in the same direction (inconsistent orientation)";
  else
    why += "by " + std::to_string(edgeUses) + (edgeUses == 1 ? " triangle" : " triangles");
  return head + why + " (" + std::to_string(boundaryEdges) + " boundary, " + std::to_string(nonManifoldEdges) +
         " non-manifold, " + std::to_string(inconsistentEdges) + " inconsistently oriented edges)";
}

MeshClosedness closedness(const Mesh& mesh) {
  struct DirectedEdge {
    std::uint32_t lo, hi;
    bool forward;  // lo -> hi in the triangle's order
  };
  MeshClosedness c;
  std::vector<DirectedEdge> edges;
  edges.reserve(mesh.triangleCount() * 3);
  for (const TriangleIndices& t : mesh.triangles()) {
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
      ++c.skippedTriangles;
      continue;
    }
    ++c.effectiveTriangles;
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t i = t[e], j = t[(e + 1) % 3];
      edges.push_back(i < j ? DirectedEdge{i, j, true} : DirectedEdge{j, i, false});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const DirectedEdge& a, const DirectedEdge& b) {
    return a.lo != b.lo ? a.lo < b.lo : a.hi < b.hi;
  });
  bool recorded = false;
  for (std::size_t g = 0; g < edges.size();) {
    std::size_t e = g, forward = 0;
    while (e < edges.size() && edges[e].lo == edges[g].lo && edges[e].hi == edges[g].hi) forward += edges[e++].forward;
    const std::size_t uses = e - g;
    bool bad = true;
    if (uses == 1)
      ++c.boundaryEdges;
    else if (uses > 2)
      ++c.nonManifoldEdges;
    else if (forward != 1)
      ++c.inconsistentEdges;
    else
      bad = false;
    if (bad && !recorded) {
      recorded = true;
      c.edgeI = edges[g].lo, c.edgeJ = edges[g].hi, c.edgeUses = uses;
      c.edgeSameDirection = uses == 2;
    }
    g = e;
  }
  return c;
}

bool isClosed(const Mesh& mesh) { return closedness(mesh).closed(); }

// ---- exact signs ----------------------------------------------------------------------------
namespace {

/// Error-free product (fma): a·b = hi + lo exactly.
inline void twoProduct(Wide a, Wide b, Wide& hi, Wide& lo) {
  hi = a * b;
  lo = std::fma(a, b, -hi);
}

/// Exact sign of a·b - c·d: compares the two exact products as (hi, lo) pairs (rounding is
/// monotone, so unequal his order the products; equal his leave the exact los to decide).
inline int diffOfProductsSign(Wide a, Wide b, Wide c, Wide d) {
  Wide h1, l1, h2, l2;
  twoProduct(a, b, h1, l1);
  twoProduct(c, d, h2, l2);
  if (h1 != h2) return h1 > h2 ? 1 : -1;
  return (l1 > l2) - (l1 < l2);
}

/// Is u × v exactly the zero vector?
inline bool crossIsZero(const WVec3& u, const WVec3& v) {
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    if (diffOfProductsSign(u[j], v[k], u[k], v[j]) != 0) return false;
  }
  return true;
}

/// Forward error bound factor of d·(p×q) evaluated in Wide: |computed - exact| <= bound ·
/// Σ|d_i|(|p_j q_k| + |p_k q_j|); the true factor is about 3u (u = 2^-53), 8u leaves room for
/// the rounding of the magnitude sum itself.
constexpr Wide kTripleFilterBound = Wide(8) * std::numeric_limits<Wide>::epsilon() / 2;

/// Exact sign of the triple product d·(p×q): static filter, then the six products split into
/// four doubles each by error-free products and summed as a floating-point expansion
/// (Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
/// Predicates", 1997: Grow-Expansion with zero elimination); the expansion's sign is that of
/// its largest (last non-zero) component. Exact unless a product under- or overflows.
int tripleSign(const WVec3& d, const WVec3& p, const WVec3& q) {
  Wide value = 0, magnitude = 0;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const Wide t1 = p[j] * q[k], t2 = p[k] * q[j];
    value += d[i] * (t1 - t2);
    magnitude += std::abs(d[i]) * (std::abs(t1) + std::abs(t2));
  }
  if (std::abs(value) > kTripleFilterBound * magnitude) return predicates::sign(value);
  if (magnitude == 0) return 0;
  std::array<Wide, 25> e{};
  int m = 0;
  auto grow = [&](Wide x) {
    int out = 0;
    for (int i = 0; i < m; ++i) {
      const Wide s = x + e[i];
      const Wide bv = s - x, av = s - bv;
      const Wide err = (x - av) + (e[i] - bv);
      if (err != 0) e[out++] = err;
      x = s;
    }
    if (x != 0) e[out++] = x;
    m = out;
  };
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    for (int term = 0; term < 2; ++term) {
      Wide h, l, h1, l1, h2, l2;
      twoProduct(term == 0 ? p[j] : -p[k], term == 0 ? q[k] : q[j], h, l);
      twoProduct(d[i], h, h1, l1);
      twoProduct(d[i], l, h2, l2);
      grow(l2), grow(h2), grow(l1), grow(h1);
    }
  }
  return m == 0 ? 0 : predicates::sign(e[m - 1]);
}

/// Corners of a triangle relative to the query point, in Wide.
struct Relative {
  WVec3 a, b, c;
};
inline Relative relative(const Triangle& t, const WVec3& p) { return {wide(t.a) - p, wide(t.b) - p, wide(t.c) - p}; }

/// Exactly: is the origin (the query point) on the closed triangle (a, b, c)? Coplanar
/// (a·(b×c) = 0), then the cross products a×b, b×c, c×a are all normal to the plane and their
/// signed lengths are the barycentric weights of the origin: per axis, mixed signs mean
/// outside. When they all vanish the origin is collinear with the corners (a segment or a
/// point): it is on it iff, along an axis the line is not orthogonal to, the coordinates of
/// the corners straddle 0.
bool originOnTriangle(const Relative& r) {
  if (tripleSign(r.a, r.b, r.c) != 0) return false;
  const WVec3* v[3] = {&r.a, &r.b, &r.c};
  bool anyNonZero = false;
  for (int axis = 0; axis < 3; ++axis) {
    const int j = (axis + 1) % 3, k = (axis + 2) % 3;
    bool pos = false, neg = false;
    for (int e = 0; e < 3; ++e) {
      const WVec3& u = *v[e];
      const WVec3& w = *v[(e + 1) % 3];
      const int s = diffOfProductsSign(u[j], w[k], u[k], w[j]);
      pos |= s > 0, neg |= s < 0;
    }
    if (pos && neg) return false;
    anyNonZero |= pos || neg;
  }
  if (anyNonZero) return true;
  for (int axis = 0; axis < 3; ++axis) {
    const Wide lo = std::min({r.a[axis], r.b[axis], r.c[axis]});
    const Wide hi = std::max({r.a[axis], r.b[axis], r.c[axis]});
    if (lo != 0 || hi != 0) return lo <= 0 && hi >= 0;
  }
  return true;  // all corners at the query point
}

enum class RayEvent { Miss, Cross, Degenerate };

/// The ray from the origin along d against triangle (a, b, c), for an origin not on the
/// triangle: a proper crossing of the interior, a miss, or a degenerate event (the ray meets
/// an edge or vertex, or lies in the triangle's plane). Line-side signs s_ab = d·(a×b), ...
/// (all equal and non-zero: the line crosses the interior; mixed: it misses), and the side of
/// the origin det = a·(b×c), whose sign against d·n gives the sign of the hit parameter t.
RayEvent rayEvent(const Relative& r, const WVec3& d) {
  const int s1 = tripleSign(d, r.a, r.b), s2 = tripleSign(d, r.b, r.c), s3 = tripleSign(d, r.c, r.a);
  const bool pos = s1 > 0 || s2 > 0 || s3 > 0, neg = s1 < 0 || s2 < 0 || s3 < 0;
  if (pos && neg) return RayEvent::Miss;
  const int det = tripleSign(r.a, r.b, r.c);
  if (!pos && !neg) {
    // d·n = 0: parallel to a proper triangle's plane, or a zero-area triangle.
    if (det != 0) return RayEvent::Miss;
    if (crossIsZero(r.a, r.b) && crossIsZero(r.b, r.c) && crossIsZero(r.c, r.a)) {
      // Origin on the line of a segment/point triangle: met only along a corner's direction.
      return (crossIsZero(d, r.a) || crossIsZero(d, r.b) || crossIsZero(d, r.c)) ? RayEvent::Degenerate
                                                                                  : RayEvent::Miss;
    }
    return RayEvent::Degenerate;  // the ray runs in the triangle's plane
  }
  const int s = pos ? 1 : -1;  // sign of d·n
  if (det == 0) return RayEvent::Degenerate;  // origin on the triangle: excluded by the caller
  if (det != s) return RayEvent::Miss;        // hit behind the origin (t < 0)
  return (s1 != 0 && s2 != 0 && s3 != 0) ? RayEvent::Cross : RayEvent::Degenerate;
}

/// Ray directions d(k) = c0 + k·c1 + k²·c2 with linearly independent integer c0, c1, c2
/// (det = 132969032): any plane or line through the origin holds at most two of them.
WVec3 direction(std::uint64_t k) {
  const WVec3 c0(1009, 1361, 1777), c1(-331, 421, 211), c2(97, -59, 149);
  const Wide x = Wide(k);
  return c0 + x * c1 + (x * x) * c2;
}

/// Slack for the conservative ray–node box test: boxes are widened by this fraction of their
/// extent relative to the query point, far above the few roundings of the slab test.
constexpr Wide kNodeSlack = 1e-9;

/// Does the ray from p along d meet box b (conservatively: never misses a touching box)?
bool rayMayHitBox(const Aabb& b, const WVec3& p, const WVec3& d) {
  Wide tNear = 0, tFar = std::numeric_limits<Wide>::infinity();
  for (int i = 0; i < 3; ++i) {
    Wide lo = Wide(b.min[i]) - p[i], hi = Wide(b.max[i]) - p[i];
    const Wide pad = kNodeSlack * std::max(std::abs(lo), std::abs(hi));
    lo -= pad, hi += pad;
    if (d[i] == 0) {
      if (lo > 0 || hi < 0) return false;
      continue;
    }
    Wide t1 = lo / d[i], t2 = hi / d[i];
    if (t1 > t2) std::swap(t1, t2);
    tNear = std::max(tNear, t1);
    tFar = std::min(tFar, t2);
    if (tNear > tFar) return false;
  }
  return true;
}

bool boxContains(const Aabb& b, const Vec3& p) {
  return (b.min.array() <= p.array()).all() && (p.array() <= b.max.array()).all();
}

}  // namespace

// ---- MeshVolume ---------------------------------------------------------------------------------

MeshVolume::MeshVolume(const Mesh& mesh) : mesh_(&mesh) {
  const MeshClosedness c = closedness(mesh);
  if (!c.closed()) throw InvalidInput(c.reason(mesh.name()));
}

bool MeshVolume::onSurface(const Vec3& p) const {
  struct Visitor {
    const Mesh& mesh;
    Vec3 p;
    WVec3 wp;
    bool found = false;
    bool touches(const Aabb& box) const { return boxContains(box, p); }
    bool slot(std::uint32_t k) {
      const Triangle t = mesh.slotTriangle(k);
      if (!boxContains(bounds(t), p)) return true;
      found = originOnTriangle(relative(t, wp));
      return !found;
    }
  } visitor{*mesh_, p, wide(p)};
  mesh_detail::walkSlots(*mesh_, visitor);
  return visitor.found;
}

bool MeshVolume::contains(const Vec3& p) const {
  if (!boxContains(mesh_->bounds(), p)) return false;  // the solid lies within its vertices' box
  if (onSurface(p)) return true;
  struct Visitor {
    const Mesh& mesh;
    WVec3 p, d;
    // The mesh rays' padded slab test (node_tests.hpp) on four lanes, when d is exact in Real
    // (direction(k) for k < ~400; the first direction nearly always decides): it never misses a
    // box the ray meets, like rayMayHitBox, which serves the other directions.
    std::optional<mesh_detail::RayBoxTest> lanes;
    std::size_t crossings = 0;
    bool degenerate = false;
    bool touches(const Aabb& box) const { return rayMayHitBox(box, p, d); }
    unsigned touches4(const WideBvhNode& n) const {
      if (!lanes) return mesh_detail::eachLane(n, [&](const Aabb& b) { return rayMayHitBox(b, p, d); });
      Real keys[4];
      return lanes->enter4(n, std::numeric_limits<Real>::infinity(), keys);
    }
    bool slot(std::uint32_t k) {
      const RayEvent e = rayEvent(relative(mesh.slotTriangle(k), p), d);
      if (e == RayEvent::Degenerate) {
        degenerate = true;
        return false;
      }
      crossings += e == RayEvent::Cross;
      return true;
    }
  };
  // Bound from the header: each triangle contributes at most 4 bad planes/lines (three edge
  // planes and its own plane), each vertex one line, each met by at most 2 directions.
  const std::uint64_t maxTries = 2 * (4 * std::uint64_t(mesh_->triangleCount()) + mesh_->vertexCount()) + 1;
  const WVec3 wp = wide(p);
  std::size_t crossings = 0;
  for (std::uint64_t k = 0; k < maxTries; ++k) {
    Visitor v{*mesh_, wp, direction(k), std::nullopt};
    const Vec3 dr = v.d.cast<Real>();
    if (dr.cast<Wide>() == v.d) v.lanes = mesh_detail::meshRayBoxTest(mesh_->scale(), p, dr);
    mesh_detail::walkSlots(*mesh_, v);
    crossings = v.crossings;
    if (!v.degenerate) break;
  }
  return crossings % 2 == 1;
}

bool MeshVolume::overlaps(const Sphere& s) const { return crux::overlaps(*mesh_, s) || contains(s.center); }
bool MeshVolume::overlaps(const Aabb& b) const { return crux::overlaps(*mesh_, b) || contains(b.min); }
bool MeshVolume::overlaps(const Obb& b) const { return crux::overlaps(*mesh_, b) || contains(b.center); }
bool MeshVolume::overlaps(const Triangle& t) const { return crux::overlaps(*mesh_, t) || contains(t.a); }

namespace {

using mesh_detail::RelativeFrame;  // the mesh–mesh surface test's mapping (relative_frame.hpp)

/// Is a corner of some triangle of b (one per triangle, consecutive repeats skipped) inside a?
bool someCornerInside(const MeshVolume& a, const Mesh& b, const RelativeFrame& frame) {
  const Aabb& box = a.mesh().bounds();
  std::uint32_t last = std::numeric_limits<std::uint32_t>::max();
  for (const TriangleIndices& t : b.triangles()) {
    if (t[0] == last) continue;
    last = t[0];
    const Vec3 p = frame.map(b.vertices()[t[0]]);
    if (boxContains(box, p) && a.contains(p)) return true;
  }
  return false;
}

}  // namespace

bool overlapsVolume(const MeshVolume& a, const Transform& ta, const Mesh& b, const Transform& tb) {
  return crux::overlaps(a.mesh(), ta, b, tb) || someCornerInside(a, b, RelativeFrame(ta, tb));
}

bool overlapsVolume(const MeshVolume& a, const Transform& ta, const MeshVolume& b, const Transform& tb) {
  return overlapsVolume(a, ta, b.mesh(), tb) || someCornerInside(b, a.mesh(), RelativeFrame(tb, ta));
}

bool pointInside(const Mesh& mesh, const Vec3& p) { return MeshVolume(mesh).contains(p); }
bool overlapsVolume(const Mesh& mesh, const Sphere& s) { return MeshVolume(mesh).overlaps(s); }
bool overlapsVolume(const Mesh& mesh, const Aabb& b) { return MeshVolume(mesh).overlaps(b); }
bool overlapsVolume(const Mesh& mesh, const Obb& b) { return MeshVolume(mesh).overlaps(b); }
bool overlapsVolume(const Mesh& mesh, const Triangle& t) { return MeshVolume(mesh).overlaps(t); }

}  // namespace crux
