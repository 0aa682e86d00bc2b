// Triangle–triangle closest points: 9 edge pairs (RTCD 5.1.9) + 6 vertex–face projections
// (RTCD 5.1.5 restricted to the face region) + an exact intersection test for crossing pairs,
// whose common point comes from the one point–triangle closest point (closest_point_internal.hpp).
// All arithmetic in double; see triangle_distance.hpp.

#include "geometry/unchecked.hpp"

#include <crux/geometry/overlap.hpp>
#include <crux/geometry/triangle_distance.hpp>
#include <crux/geometry/triangle_class.hpp>

#include "geometry/closest_point_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace crux {
namespace {

using V3 = Eigen::Vector3d;

constexpr double kDoubleEps = std::numeric_limits<double>::epsilon();
/// Corner signed distances within this × |n| × (length scale) of a plane count as on it when
/// deciding whether the exact intersection test is needed (a conservative prefilter).
constexpr double kPlaneSideTolerance = 1024 * kDoubleEps;

/// One candidate pair of closest points.
struct Candidate {
  double d2 = std::numeric_limits<double>::infinity();
  V3 pa = V3::Zero(), pb = V3::Zero();
  std::uint32_t fa = 0, fb = 0;
};

/// Feature of a point at parameter s on edge i (corner i → corner i+1).
std::uint32_t edgeFeature(int i, double s) {
  if (s <= 0) return featureId(FeatureKind::Vertex, std::uint32_t(i));
  if (s >= 1) return featureId(FeatureKind::Vertex, std::uint32_t((i + 1) % 3));
  return featureId(FeatureKind::Edge, std::uint32_t(i));
}

double clamp01(double x) { return x < 0 ? 0 : (x > 1 ? 1 : x); }

using closest_detail::segmentSegment;  // RTCD 5.1.9, closest_point_internal.hpp

/// A triangle in double with its edges, (unnormalised) normal and whether it has a face.
struct Tri {
  V3 v[3];
  V3 e[3];  // e[i] = v[i+1] - v[i]
  V3 n;     // e0 × (v2 − v0): |n| = twice the area
  double n2 = 0;
  bool hasFace = false;

  explicit Tri(const Triangle& t) {
    v[0] = t.a.cast<double>();
    v[1] = t.b.cast<double>();
    v[2] = t.c.cast<double>();
    for (int i = 0; i < 3; ++i) e[i] = v[(i + 1) % 3] - v[i];
    n = e[0].cross(v[2] - v[0]);
    n2 = n.squaredNorm();
    const double longest2 = std::max({e[0].squaredNorm(), e[1].squaredNorm(), e[2].squaredNorm()});
    hasFace = n2 > 0 && !classifyTriangle(std::sqrt(n2), longest2).degenerate;  // else its edges carry it
  }
  /// n·(p − v0): signed distance times |n|.
  double side(const V3& p) const { return n.dot(p - v[0]); }
  /// Does p project into the closed face? (closest_detail::projectsInside)
  bool projectsInside(const V3& p) const { return closest_detail::projectsInside(v, n, p); }
};

/// Keeps the candidate when strictly closer (ties keep the earlier, lower-dimensional feature).
void offer(Candidate& best, double d2, const V3& pa, const V3& pb, std::uint32_t fa, std::uint32_t fb) {
  if (d2 < best.d2) best = Candidate{d2, pa, pb, fa, fb};
}

/// Vertex–face candidates: each corner of `from` projected on the face of `to` when it projects
/// inside. `swap` tells that `from` is B (points and features are stored as (A, B)).
void vertexFace(const Tri& from, const Tri& to, bool swap, Candidate& best) {
  if (!to.hasFace) return;
  for (int i = 0; i < 3; ++i) {
    const V3& p = from.v[i];
    const double sd = to.side(p);
    const double d2 = sd * sd / to.n2;
    if (!(d2 < best.d2) || !to.projectsInside(p)) continue;  // the cheap test first
    const V3 q = p - (sd / to.n2) * to.n;
    const std::uint32_t fv = featureId(FeatureKind::Vertex, std::uint32_t(i)), ff = featureId(FeatureKind::Face, 0);
    if (swap) offer(best, d2, q, p, ff, fv);
    else offer(best, d2, p, q, fv, ff);
  }
}

/// Distance from a point x on the plane of `to` to the triangle `to` (which has a face), with
/// its closest point and feature: the one point–triangle closest point
/// (closest_detail::closestOnProperTriangle, as closestPoint(Triangle) takes it: RTCD 5.1.5's
/// regions, a thin triangle by closestOnSliver). An edge region's point at a corner is that
/// vertex (edgeFeature's rule).
double pointToTriangle(const Tri& to, const V3& x, V3& q, std::uint32_t& feature) {
  // thin by classifyTriangle, here rather than in Tri: only crossing pairs come this way
  const double longest2 = std::max({to.e[0].squaredNorm(), to.e[1].squaredNorm(), to.e[2].squaredNorm()});
  const bool thin = classifyTriangle(std::sqrt(to.n2), longest2).thin;
  const int region = closest_detail::closestOnProperTriangle(to.v[0], to.v[1], to.v[2], x, thin, q);
  if (region < 0) {
    feature = featureId(FeatureKind::Face, 0);
    // the plane distance, as vertexFace's: x is on the plane up to rounding, and |q − x| would
    // be quantised to ulps of x where sd's rounding is relative to the residual
    if (!thin) {
      const double sd = to.side(x);
      return sd * sd / to.n2;
    }
  } else if (region >= 3) {
    feature = featureId(FeatureKind::Vertex, std::uint32_t(region - 3));
  } else {
    const int j = (region + 1) % 3;
    feature = q == to.v[region] ? featureId(FeatureKind::Vertex, std::uint32_t(region))
              : q == to.v[j]    ? featureId(FeatureKind::Vertex, std::uint32_t(j))
                                : featureId(FeatureKind::Edge, std::uint32_t(region));
  }
  return (q - x).squaredNorm();
}

/// Intersecting pair: the points where edges of `from` cross the plane of `to`, each with its
/// distance to `to` (0 up to rounding for at least one of them unless the pair is coplanar).
void crossings(const Tri& from, const Tri& to, bool swap, Candidate& best) {
  if (!to.hasFace) return;
  double sd[3];
  for (int i = 0; i < 3; ++i) sd[i] = to.side(from.v[i]);
  for (int i = 0; i < 3; ++i) {
    const double d0 = sd[i], d1 = sd[(i + 1) % 3];
    if ((d0 > 0 && d1 > 0) || (d0 < 0 && d1 < 0) || d0 == d1) continue;
    const double s = clamp01(d0 / (d0 - d1));
    const V3 x = from.v[i] + s * from.e[i];
    V3 q = x;
    std::uint32_t fq = 0;
    const double d2 = pointToTriangle(to, x, q, fq);
    if (swap) offer(best, d2, q, x, fq, edgeFeature(i, s));
    else offer(best, d2, x, q, edgeFeature(i, s), fq);
  }
}

/// Do the corners of `from` lie on both sides of (or on) the plane of `to`, with slack?
bool straddles(const Tri& from, const Tri& to, double scale) {
  if (!to.hasFace) return true;
  const double slack = kPlaneSideTolerance * std::sqrt(to.n2) * scale;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const V3& p : from.v) {
    const double s = to.side(p);
    lo = std::min(lo, s);
    hi = std::max(hi, s);
  }
  return lo <= slack && hi >= -slack;
}

}  // namespace

TriangleDistanceResult unchecked::closestPoints(const Triangle& a, const Triangle& b) {
  const Tri A(a), B(b);
  Candidate best;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0, t = 0;
      const double d2 = segmentSegment(A.v[i], A.e[i], B.v[j], B.e[j], s, t);
      if (d2 < best.d2)
        best = Candidate{d2, A.v[i] + s * A.e[i], B.v[j] + t * B.e[j], edgeFeature(i, s), edgeFeature(j, t)};
    }
  vertexFace(A, B, false, best);
  vertexFace(B, A, true, best);

  TriangleDistanceResult r;
  // Crossing pairs can be far from every edge pair and vertex projection, and touching pairs
  // give a rounded near-zero: whenever the corners straddle both planes, decide exactly.
  double scale = 0;
  for (int i = 0; i < 3; ++i) scale = std::max({scale, A.v[i].cwiseAbs().maxCoeff(), B.v[i].cwiseAbs().maxCoeff()});
  if (straddles(B, A, scale) && straddles(A, B, scale) && unchecked::overlaps(a, b)) {
    r.intersecting = true;
    if (best.d2 > 0) {
      crossings(A, B, false, best);
      crossings(B, A, true, best);
    }
  }
  r.distance = r.intersecting ? Real(0) : Real(std::sqrt(best.d2));
  r.pointA = best.pa.cast<Real>();
  r.pointB = r.intersecting ? r.pointA : Vec3(best.pb.cast<Real>());
  r.featureA = best.fa;
  r.featureB = best.fb;
  return r;
}

Real distance(const Triangle& a, const Triangle& b) { return closestPoints(a, b).distance; }  // (the checked entry)

}  // namespace crux
