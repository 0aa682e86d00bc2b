// Contact manifolds of convex pairs: GJK/EPA normal, supporting features, reference-feature
// clipping (Sutherland–Hodgman), coincident points merged (the deepest kept), reduction to 4
// points. Fixed-size buffers only.

#include <crux/geometry/contact.hpp>

#include <crux/error.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/predicates.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <crux/precondition.hpp>

#include "geometry/contact/clip.hpp"
#include "geometry/contact/margin.hpp"
#include "geometry/contact/reduce.hpp"
#include "geometry/contact/supporting_feature.hpp"
#include "geometry/gjk_internal.hpp"

namespace crux {
namespace {

using detail::M3;
using detail::Placed;
using detail::V3;

/// Hull faces with more vertices than this are not clipped (one contact point instead).
constexpr int kMaxFeatureVerts = 32;
constexpr int kMaxClipVerts = 2 * kMaxFeatureVerts + 4;

// From src/geometry/contact/ (shared with triangle_contact.cpp and box_triangle_contact.cpp): the
// supporting-feature rule, the rounding budget (coincidenceTolerance), the reference clipping with
// its coincident-point merge (clipToReference) and the 4-point reduction.

/// A supporting feature: 1 vertex, 2 (an edge), or a face loop counter-clockwise around `normal`.
struct Feature {
  V3 v[kMaxFeatureVerts];
  std::uint32_t vid[kMaxFeatureVerts];
  int n = 0;
  V3 normal = V3::Zero();  // outward unit normal of a face (n >= 3)
  double align = 0;        // normal·d for a face
  std::uint32_t id = 0;    // featureId of the whole feature
  bool sliver = false;     // a triangle face too thin to be a reference face (kTriangleFaceRelative)
};

void setVertex(Feature& f, const V3& v, int index) {
  f.n = 1;
  f.v[0] = v;
  f.vid[0] = featureId(FeatureKind::Vertex, static_cast<std::uint32_t>(index));
  f.id = f.vid[0];
}

/// Supporting vertex `is` or, when one of the edges (is, other[k]) is perpendicular to d within
/// the feature angle, that edge (contact_detail::vertexOrEdge).
void vertexOrEdge(const Placed& P, const V3& d, int is, const int* others, int nOthers, std::uint32_t edgeBase,
                  Feature& f) {
  contact_detail::vertexOrEdge([&P](int i) { return P.vertex(i); }, d, is, others, nOthers, edgeBase, f);
}

/// A face whose loop has coincident corners (a box with a zero half extent across it, e.g. the
/// end face of a segment-like box) bounds no area there: its zero-length edges would clip
/// nothing and leave points off the shape, and its coincident corners would be duplicate
/// contact points. Consecutive corners within the rounding budget are merged (the first kept);
/// a loop left with two corners is that edge, with one that vertex.
void collapseFace(Feature& f) {
  if (f.n < 3) return;
  const double tol = contact_detail::coincidenceTolerance(f.v, f.n, 0);
  int k = 0;
  for (int i = 0; i < f.n; ++i) {
    if (k > 0 && (f.v[i] - f.v[k - 1]).norm() <= tol) continue;
    f.v[k] = f.v[i];
    f.vid[k] = f.vid[i];
    ++k;
  }
  while (k > 1 && (f.v[k - 1] - f.v[0]).norm() <= tol) --k;
  if (k >= 3) {
    f.n = k;
    return;
  }
  f.n = k;
  if (k == 1) {
    f.id = f.vid[0];
    return;
  }
  f.id = contact_detail::edgeFeatureId(int(f.vid[0] & 0xFFFFFFu), int(f.vid[1] & 0xFFFFFFu));
}

/// The feature of P's core that supports direction d (unit, world). With allowFace false a
/// triangle gives its supporting vertex or edge, never its face.
void supportingFeature(const Placed& P, const V3& d, Feature& f, bool allowFace = true) {
  const ConvexShape& s = *P.shape;
  const double cosTol = double(kContactFaceAngleCos);
  int is = 0;
  P.support(d, &is);
  f.sliver = false;
  switch (s.kind) {
    case ConvexKind::Sphere: setVertex(f, P.p[0], 0); return;
    case ConvexKind::Capsule: {
      const int other[1] = {1 - is};
      vertexOrEdge(P, d, is, other, 1, 0, f);
      return;
    }
    case ConvexKind::Triangle: {
      V3 m = (P.p[1] - P.p[0]).cross(P.p[2] - P.p[0]);
      const double len = m.norm();
      const double longest2 = std::max({(P.p[1] - P.p[0]).squaredNorm(), (P.p[2] - P.p[1]).squaredNorm(),
                                        (P.p[0] - P.p[2]).squaredNorm()});
      if (allowFace && len > 0 && contact_detail::faceSupports(m.dot(d), len)) {
        f.sliver = !classifyTriangle(len, longest2).referenceFace;
        m /= len;
        const bool front = m.dot(d) > 0;
        f.n = 3;
        const int order[3] = {0, front ? 1 : 2, front ? 2 : 1};
        for (int k = 0; k < 3; ++k) {
          f.v[k] = P.p[order[k]];
          f.vid[k] = featureId(FeatureKind::Vertex, static_cast<std::uint32_t>(order[k]));
        }
        f.normal = front ? m : V3(-m);
        f.align = std::abs(m.dot(d));
        f.id = featureId(FeatureKind::Face, front ? 0 : 1);
        return;
      }
      const int others[2] = {(is + 1) % 3, (is + 2) % 3};
      vertexOrEdge(P, d, is, others, 2, 0, f);
      return;
    }
    case ConvexKind::Box: {
      const V3 l = P.axes.transpose() * d;
      int k = 0;
      l.cwiseAbs().maxCoeff(&k);
      if (contact_detail::faceSupports(l[k], 1)) {
        const bool pos = l[k] > 0;
        int idx[4];
        contact_detail::boxFaceLoop(k, pos, idx);
        f.n = 4;
        for (int q = 0; q < 4; ++q) {
          f.v[q] = P.vertex(idx[q]);
          f.vid[q] = featureId(FeatureKind::Vertex, static_cast<std::uint32_t>(idx[q]));
        }
        f.normal = pos ? V3(P.axes.col(k)) : V3(-P.axes.col(k));
        f.align = std::abs(l[k]);
        f.id = featureId(FeatureKind::Face, static_cast<std::uint32_t>(2 * k + (pos ? 1 : 0)));
        collapseFace(f);
        return;
      }
      const int others[3] = {is ^ 1, is ^ 2, is ^ 4};
      vertexOrEdge(P, d, is, others, 3, 0, f);
      return;
    }
    case ConvexKind::Hull: {
      const ConvexHull& h = *s.hull;
      const V3 l = P.R.transpose() * d;
      int bestFace = -1;
      double bestAlign = cosTol;
      for (std::size_t i = 0; i < h.faces().size(); ++i) {
        const double a = h.faces()[i].normal.cast<double>().dot(l);
        if (a >= bestAlign) {
          bestAlign = a;
          bestFace = static_cast<int>(i);
        }
      }
      if (bestFace >= 0 && h.faces()[static_cast<std::size_t>(bestFace)].count <= std::uint32_t(kMaxFeatureVerts)) {
        const HullFace& hf = h.faces()[static_cast<std::size_t>(bestFace)];
        f.n = static_cast<int>(hf.count);
        for (std::uint32_t q = 0; q < hf.count; ++q) {
          const std::uint32_t vi = h.faceVertices()[hf.first + q];
          f.v[q] = P.vertex(static_cast<int>(vi));
          f.vid[q] = featureId(FeatureKind::Vertex, vi);
        }
        f.normal = P.R * hf.normal.cast<double>();
        f.align = bestAlign;
        f.id = featureId(FeatureKind::Face, static_cast<std::uint32_t>(bestFace));
        collapseFace(f);
        return;
      }
      // Neighbours of the support vertex along face loops.
      int others[kMaxFeatureVerts];
      int no = 0;
      for (const HullFace& hf : h.faces())
        for (std::uint32_t q = 0; q < hf.count && no + 2 <= kMaxFeatureVerts; ++q)
          if (h.faceVertices()[hf.first + q] == std::uint32_t(is)) {
            others[no++] = static_cast<int>(h.faceVertices()[hf.first + (q + 1) % hf.count]);
            others[no++] = static_cast<int>(h.faceVertices()[hf.first + (q + hf.count - 1) % hf.count]);
          }
      if (h.dimension() == 1) others[no++] = 1 - is;
      vertexOrEdge(P, d, is, others, no, 0, f);
      return;
    }
  }
}

}  // namespace

Real ContactManifold::depth() const {
  Real d = 0;
  for (int i = 0; i < count; ++i) d = std::max(d, -points[i].separation);
  return d;
}

void validateContactMargin(Real margin) {
  if (!(margin >= 0) || !std::isfinite(margin))
    throw InvalidInput("margin: expected a finite contact margin >= 0, got " + std::to_string(double(margin)));
}

namespace {

/// Calls f(a, b, c) on the triangles of a placed polytope's boundary (a box's 12, each face of a
/// hull fanned from its first vertex), in world coordinates, until f returns true; returns
/// whether it did.
template <class F>
bool anyBoundaryTriangle(const Placed& s, const F& f) {
  if (s.shape->kind == ConvexKind::Box) {
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      for (int side = 0; side < 2; ++side) {
        const int base = side << a;  // corner i: bit k set for +half along axis k (Placed::vertex)
        const V3 q0 = s.vertex(base), q1 = s.vertex(base | 1 << b), q2 = s.vertex(base | 1 << b | 1 << c),
                 q3 = s.vertex(base | 1 << c);
        if (f(q0, q1, q2) || f(q0, q2, q3)) return true;
      }
    }
    return false;
  }
  const ConvexHull& h = *s.shape->hull;
  const auto& loop = h.faceVertices();
  for (const HullFace& face : h.faces()) {
    const V3 q0 = s.vertex(int(loop[face.first]));
    for (std::uint32_t i = 1; i + 1 < face.count; ++i)
      if (f(q0, s.vertex(int(loop[face.first + i])), s.vertex(int(loop[face.first + i + 1])))) return true;
  }
  return false;
}

/// Whether the placed polytope (a box or a solid hull) holds x, its boundary included, by the
/// exact side of x against every boundary triangle's plane compared with an interior point's.
/// False for a polytope without interior (a flat box, a planar hull): its boundary triangles
/// then cover all of it.
bool polytopeHolds(const Placed& s, const V3& x) {
  V3 centre = V3::Zero();
  if (s.shape->kind == ConvexKind::Box) {
    if (!(s.half.minCoeff() > 0)) return false;
    centre = s.p[0];
  } else {
    if (s.shape->hull->dimension() < 3) return false;
    for (int i = 0; i < s.vertexCount(); ++i) centre += s.vertex(i);
    centre /= double(s.vertexCount());
  }
  return !anyBoundaryTriangle(s, [&](const V3& a, const V3& b, const V3& c) {
    const int sx = predicates::orient3dExact(a, b, c, x);
    return sx != 0 && sx != predicates::orient3dExact(a, b, c, centre);  // beyond this face's plane
  });
}

/// Calls f(a, b, c) on the boundary triangles of the placed polytope P whose box meets [lo, hi]
/// (anyBoundaryTriangle's order), until f returns true; returns whether it did.
template <class F>
bool anyBoundaryTriangleIn(const Placed& P, const V3& lo, const V3& hi, const F& f) {
  return anyBoundaryTriangle(P, [&](const V3& a, const V3& b, const V3& c) {
    if ((a.cwiseMin(b).cwiseMin(c).array() > hi.array()).any() || (a.cwiseMax(b).cwiseMax(c).array() < lo.array()).any())
      return false;
    return f(a, b, c);
  });
}

/// Whether a boundary triangle of the placed polytope P lies within rP + rQ + margin of the core
/// q (1-3 points) by withinDistance; triangles whose box is beyond that reach (a conservative
/// box test with `slack`) are skipped.
bool boundaryWithin(const Placed& P, const V3* q, int nq, double rP, double rQ, double margin, double slack) {
  V3 lo = q[0], hi = q[0];
  for (int i = 1; i < nq; ++i) lo = lo.cwiseMin(q[i]), hi = hi.cwiseMax(q[i]);
  const double reach = rP + rQ + margin + slack;
  return anyBoundaryTriangleIn(P, lo.array() - reach, hi.array() + reach, [&](const V3& a, const V3& b, const V3& c) {
    const V3 t[3] = {a, b, c};
    return withinDistance(t, 3, q, nq, rP, rQ, margin);
  });
}

/// The exact margin decision of a polytope (box or hull) P against a core of 1-3 points q: within
/// rP + rQ + margin of each other. q's first point inside P, or a boundary triangle of P within
/// that distance of q (boundaryWithin).
bool polytopeWithin(const Placed& P, const V3* q, int nq, double rP, double rQ, double margin, double slack) {
  return polytopeHolds(P, q[0]) || boundaryWithin(P, q, nq, rP, rQ, margin, slack);
}

/// The exact margin decision of two polytopes (boxes or hulls of more than 3 vertices): within
/// rP + rQ + margin of each other. One holding a vertex of the other (containment; otherwise
/// their boundaries meet), or a boundary triangle of P and one of Q within that distance
/// (boundaryWithin on each of P's triangles near Q's box).
bool polytopesWithin(const Placed& P, const Placed& Q, double rP, double rQ, double margin, double slack) {
  if (polytopeHolds(P, Q.vertex(0)) || polytopeHolds(Q, P.vertex(0))) return true;
  V3 lo = Q.vertex(0), hi = lo;
  Q.growCoreBox(lo, hi);
  const double reach = rP + rQ + margin + slack;
  return anyBoundaryTriangleIn(P, lo.array() - reach, hi.array() + reach, [&](const V3& a, const V3& b, const V3& c) {
    const V3 t[3] = {a, b, c};
    return boundaryWithin(Q, t, 3, rQ, rP, margin, slack);
  });
}

}  // namespace

bool contacts(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb, Real margin,
              ContactManifold& out) {
  out.count = 0;
  validateContactMargin(margin);
  if (!detail::entryPreconditions("contacts(ConvexShape, ConvexShape)", detail::rule::kShapesAtPoses,
                                  detail::ShapesAtPoses{a, ta, b, tb}))
    return false;
  const Placed A(a, ta), B(b, tb);
  const DistanceResult dr = detail::coreQuery(A, B);
  out.normal = dr.normal;
  // The margin decision. Every pair is decided exactly (withinDistance, overlap.hpp, on the cores'
  // points or the polytopes' boundary triangles) when the distance is within its rounding of the
  // margin, so that touching on integer grids is reported exactly (a capsule's foot on a triangle
  // corner at an unrepresentable parameter, or GJK's distance between a hull and a box, puts the
  // double distance an ulp off); a pair found within the margin but computed beyond it gets the
  // margin as its separation.
  bool clampToMargin = false;
  {
    // the core's points (the placed vertices) and their count, 0 for larger cores
    auto cores = [](const Placed& s, V3 (&pts)[3]) {
      const ConvexKind k = s.shape->kind;
      const int n = k == ConvexKind::Sphere ? 1 : k == ConvexKind::Capsule ? 2 : k == ConvexKind::Triangle ? 3
                    : k == ConvexKind::Hull && s.vertexCount() <= 3 ? s.vertexCount() : 0;
      for (int i = 0; i < n; ++i) pts[i] = s.vertex(i);
      return n;
    };
    V3 pa[3], pb[3];
    const int na = cores(A, pa), nb = cores(B, pb);
    const double m = double(margin),
                 band = kGjkScaleTolerance * (detail::pairScale(A, B) + A.t.cwiseAbs().maxCoeff() +
                                              B.t.cwiseAbs().maxCoeff() + m) +
                        4 * double(std::numeric_limits<Real>::epsilon()) * m;
    if (na > 0 && nb > 0) {
      if (!contact_detail::withinMargin(
              double(dr.distance), m, band, [&] { return withinDistance(pa, na, pb, nb, A.radius, B.radius, m); },
              clampToMargin))
        return false;
    } else if (na > 0 || nb > 0) {
      // a box or larger hull against a core of 1-3 points: its boundary triangles (and whether it
      // holds the core) decide exactly
      const bool polytopeIsA = na == 0;
      if (!contact_detail::withinMargin(
              double(dr.distance), m, band,
              [&] {
                return polytopeIsA ? polytopeWithin(A, pb, nb, A.radius, B.radius, m, band)
                                   : polytopeWithin(B, pa, na, B.radius, A.radius, m, band);
              },
              clampToMargin))
        return false;
    } else if (!contact_detail::withinMargin(
                   double(dr.distance), m, band,
                   [&] { return polytopesWithin(A, B, A.radius, B.radius, m, band); }, clampToMargin)) {
      return false;  // two polytopes: their boundary triangles (or containment) decide exactly
    }
  }
  V3 n = dr.normal.cast<double>();
  const double rA = A.radius, rB = B.radius, m = double(margin);

  Feature fa, fb;
  supportingFeature(A, -n, fa);
  supportingFeature(B, n, fb);
  // A sliver triangle face is never the reference: when the other feature is no usable face,
  // the sliver is clipped as its supporting edge (or touches at a vertex) instead.
  const bool faceA = fa.n >= 3 && !fa.sliver, faceB = fb.n >= 3 && !fb.sliver;
  if (fa.sliver && !faceB) supportingFeature(A, -n, fa, false);
  if (fb.sliver && !faceA) supportingFeature(B, n, fb, false);
  // Two edges are clipped only when parallel (within the feature angle); crossing edges touch at
  // one point, the GJK/EPA one.
  bool clipFeatures = fa.n >= 2 && fb.n >= 2;
  if (clipFeatures && fa.n == 2 && fb.n == 2) {
    const V3 ea = fa.v[1] - fa.v[0], eb = fb.v[1] - fb.v[0];
    clipFeatures = contact_detail::edgesParallel(ea, eb);
  }
  if (clipFeatures) {
    // Reference: the better aligned (non-sliver) face; else (two edges) B's edge.
    bool refIsA = faceA && (!faceB || fa.align >= fb.align - 1e-9);
    if (!faceA && faceB) refIsA = false;
    const Feature& ref = refIsA ? fa : fb;
    const Feature& inc = refIsA ? fb : fa;
    V3 u = refIsA ? V3(-n) : n;  // outward from the reference body
    if (ref.n >= 3) {
      u = ref.normal.normalized();
      n = refIsA ? V3(-u) : u;
    }
    // The pair's rounding budget: also the distance within which two points are one.
    double scale = rA + rB + m;
    for (int i = 0; i < ref.n; ++i) scale = std::max(scale, ref.v[i].cwiseAbs().maxCoeff());
    const double tol = contact_detail::coincidenceTolerance(inc.v, inc.n, scale);
    ContactPoint pts[kMaxClipVerts];
    int np = contact_detail::clipToReference<kMaxClipVerts>(ref, inc, refIsA, u, n, rA, rB, m, tol, pts);
    if (np > 0 && !contact_detail::keepsClosest(pts, np, double(dr.distance), tol)) np = 0;  // the pair below
    if (np > 0) {
      contact_detail::reduceToFour(
          pts, np, u, tol, [](const ContactPoint& p) { return V3(p.pointB.template cast<double>()); },
          [](const ContactPoint& p) { return p.separation; });
      out.normal = n.cast<Real>();
      out.count = np;
      for (int i = 0; i < np; ++i) out.points[i] = pts[i];
      return true;
    }
  }
  // One point: the GJK/EPA closest (deepest) pair.
  out.normal = dr.normal;
  out.count = 1;
  ContactPoint& c = out.points[0];
  c.pointA = dr.pointA;
  c.pointB = dr.pointB;
  c.separation = clampToMargin ? margin : dr.distance;
  c.featureA = fa.id;
  c.featureB = fb.id;
  return true;
}

}  // namespace crux
