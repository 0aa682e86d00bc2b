#pragma once
/// @file predicates.hpp  Sign-exact orientation predicates and degeneracy classification.
///
/// Method: every predicate is a low-degree polynomial of the input coordinates evaluated in
/// `Wide` (double) after exact promotion from Real. For integer coordinates of magnitude <= 64
/// every intermediate value is an integer below 2^53, so the sign is exact (no epsilon). For
/// general inputs the result is the correctly-signed value up to double rounding of a
/// degree-3 polynomial, which is far tighter than Real's own precision in float builds.

#include <crux/geometry/shapes.hpp>

namespace crux::predicates {

/// (b-a)·((c-a)×(d-a)) — six times the signed volume of tetrahedron abcd; positive when d
/// lies on the side of plane abc that the counter-clockwise normal points to.
inline Wide orient3d(const WVec3& a, const WVec3& b, const WVec3& c, const WVec3& d) {
  return (b - a).cross(c - a).dot(d - a);
}

/// 2-D orientation of (a, b, c) after dropping coordinate `drop` (0, 1 or 2): twice the
/// signed area, positive for counter-clockwise order in the (u, v) = remaining axes in
/// cyclic order ((y,z), (z,x), (x,y)).
inline Wide orient2d(const WVec3& a, const WVec3& b, const WVec3& c, int drop) {
  const int u = (drop + 1) % 3;
  const int v = (drop + 2) % 3;
  return (b[u] - a[u]) * (c[v] - a[v]) - (b[v] - a[v]) * (c[u] - a[u]);
}

/// Index of the largest-magnitude component of n (ties: lowest index): the axis to drop when
/// projecting a plane with normal n to 2-D without collapsing it.
inline int dominantAxis(const WVec3& n) {
  const WVec3 m = n.cwiseAbs();
  return (m.x() >= m.y() && m.x() >= m.z()) ? 0 : (m.y() >= m.z() ? 1 : 2);
}

/// Sign of x as -1, 0 or +1.
inline int sign(Wide x) { return (x > 0) - (x < 0); }

/// What a triangle's corner set really is.
enum class TriangleKind { Triangle, Segment, Point };

/// A triangle classified exactly: a proper triangle, the segment [p, q] its collinear corners
/// span (the two farthest corners), or the point p its coincident corners are.
struct TriangleShape {
  TriangleKind kind = TriangleKind::Triangle;
  WVec3 p, q;  ///< Segment endpoints (Segment), the point (Point, in p).
};

/// Classifies t exactly: the cross product of its edges is zero iff collinear.
inline TriangleShape classify(const Triangle& t) {
  const WVec3 a = wide(t.a), b = wide(t.b), c = wide(t.c);
  TriangleShape s;
  if (!(b - a).cross(c - a).isZero(0)) {
    s.kind = TriangleKind::Triangle;
    return s;
  }
  if (a == b && b == c) {
    s.kind = TriangleKind::Point;
    s.p = s.q = a;
    return s;
  }
  s.kind = TriangleKind::Segment;
  const Wide ab = (b - a).squaredNorm(), bc = (c - b).squaredNorm(), ca = (a - c).squaredNorm();
  if (ab >= bc && ab >= ca) {
    s.p = a, s.q = b;
  } else if (bc >= ca) {
    s.p = b, s.q = c;
  } else {
    s.p = c, s.q = a;
  }
  return s;
}

}  // namespace crux::predicates
