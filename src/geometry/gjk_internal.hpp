#pragma once

#include "geometry/closest_point_internal.hpp"
// Internal to src/geometry: the double-precision machinery shared by gjk.cpp, epa.cpp and
// contact.cpp (shapes placed in the world, simplices, GJK and EPA entry points).

#include <crux/geometry/gjk.hpp>

namespace crux::detail {

using V3 = Eigen::Vector3d;
using M3 = Eigen::Matrix3d;

/// A ConvexShape placed in the world, in double: core vertices and box axes pre-transformed.
struct Placed {
  const ConvexShape* shape = nullptr;
  M3 R = M3::Identity();  // pose rotation
  V3 t = V3::Zero();      // pose translation
  V3 p[3];                // sphere/capsule/triangle: world vertices; box: world centre
  M3 axes = M3::Identity();  // box: world axes (columns)
  V3 half = V3::Zero();      // box half extents
  double radius = 0;
  double size = 0;  // radius of a ball about t holding the shape

  /// Places s at pose (an axis-aligned rotation is applied as its exact signed permutation).
  Placed(const ConvexShape& s, const Transform& pose);
  /// Places s by the rotation matrix R and translation t, both in double (a pose interpolated in
  /// double by the casts).
  Placed(const ConvexShape& s, const M3& rotation, const V3& translation);
  /// World core vertex maximising dot(x, d); index receives the vertex index.
  V3 support(const V3& d, int* index) const;
  /// World core vertex i.
  V3 vertex(int i) const;
  /// A point inside the core (the centroid of its defining points).
  V3 center() const;
  /// Grows the box [lo, hi] by the world core vertices (the radius not included).
  void growCoreBox(V3& lo, V3& hi) const;
  int vertexCount() const { return shape->vertexCount(); }

 private:
  /// The world core from R and t (both constructors).
  void placeCore(const ConvexShape& s);
};

/// A simplex vertex: w = a - b with a, b the support points of A and B (and their indices).
struct SupportPoint {
  V3 w = V3::Zero(), a = V3::Zero(), b = V3::Zero();
  int ia = 0, ib = 0;
};

/// Support point of the Minkowski difference A - B in direction d.
inline SupportPoint supportOf(const Placed& A, const Placed& B, const V3& d) {
  SupportPoint s;
  s.a = A.support(d, &s.ia);
  s.b = B.support(-d, &s.ib);
  s.w = s.a - s.b;
  return s;
}

/// A simplex with the barycentric coordinates of its point closest to the origin.
struct Simplex {
  SupportPoint v[4];
  double lambda[4] = {0, 0, 0, 0};
  int n = 0;
  V3 closest() const {
    V3 c = V3::Zero();
    for (int i = 0; i < n; ++i) c += lambda[i] * v[i].w;
    return c;
  }
  V3 pointA() const {
    V3 c = V3::Zero();
    for (int i = 0; i < n; ++i) c += lambda[i] * v[i].a;
    return c;
  }
  V3 pointB() const {
    V3 c = V3::Zero();
    for (int i = 0; i < n; ++i) c += lambda[i] * v[i].b;
    return c;
  }
};

/// Result of gjk(): the final simplex, core distance (0 on overlap) and status.
struct GjkResult {
  Simplex simplex;
  double distance = 0;
  bool overlap = false;
  bool capped = false;
  bool separatedBeyondBound = false;  // stopped early: distance > the caller's bound
  int iterations = 0;
};

/// Length scale of a pair: the sizes plus the distance between the origins.
inline double pairScale(const Placed& A, const Placed& B) { return A.size + B.size + (A.t - B.t).norm(); }

/// GJK distance of the cores with the signed-volume subalgorithm. Stops early (with
/// separatedBeyondBound) once a lower bound of the distance exceeds `bound` (inf: never).
GjkResult gjk(const Placed& A, const Placed& B, double bound);

/// Result of epa(): core penetration depth along `n` (unit, in A - B space, pointing from the
/// origin to the nearest boundary point), and the core points on A and B.
struct EpaResult {
  double depth = 0;
  V3 n = V3::UnitZ();
  V3 a = V3::Zero(), b = V3::Zero();
  bool flat = false;
  bool capped = false;
  int iterations = 0;
};

/// EPA from GJK's final simplex (origin within tolerance of A - B).
EpaResult epa(const Placed& A, const Placed& B, const Simplex& start);

/// distance()'s answer in double, before rounding to Real (the casts advance on it).
struct WideDistance {
  double distance = 0;  ///< signed: core distance (or -core depth) minus the radii
  V3 pointA = V3::Zero(), pointB = V3::Zero();  ///< on the rounded surfaces
  V3 normal = V3::UnitZ();                      ///< unit, from B to A
  int iterations = 0;
  GjkStatus status = GjkStatus::Separated;
};

/// Signed distance of the placed shapes (GJK, closed form, or EPA) in double.
WideDistance coreQueryWide(const Placed& A, const Placed& B);
/// coreQueryWide rounded to Real: the body of distance().
DistanceResult coreQuery(const Placed& A, const Placed& B);

/// Closest points of two segments [p1,q1], [p2,q2] (Ericson RTCD 5.1.9), degenerate segments
/// included; returns the squared distance (closest_detail::segmentSegment, the one routine).
inline double closestSegmentSegment(const V3& p1, const V3& q1, const V3& p2, const V3& q2, V3& c1, V3& c2) {
  const V3 d1 = q1 - p1, d2 = q2 - p2;
  double s = 0, t = 0;
  const double dist2 = closest_detail::segmentSegment(p1, d1, p2, d2, s, t);
  c1 = p1 + s * d1;
  c2 = p2 + t * d2;
  return dist2;
}

}  // namespace crux::detail
