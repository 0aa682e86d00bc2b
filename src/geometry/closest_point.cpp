/// @file closest_point.cpp  Closest points and squared distances (Ericson, RTCD chapter 5.1).
///
/// Everything is computed in Wide (double) from the exactly promoted inputs and rounded to Real
/// once at the end. Region decisions use inclusive comparisons; reported points are computed
/// by the best-conditioned formula for the region found (projection onto an edge's line or the
/// triangle's plane), never by a division that can be 0/0.

#include <algorithm>
#include <cmath>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/predicates.hpp>

namespace crux {
namespace {

Vec3 narrow(const WVec3& v) { return v.cast<Real>(); }

/// Closest point of the segment [a, b] to p (RTCD 5.1.2); a == b is the point a.
WVec3 closestOnSegment(const WVec3& a, const WVec3& b, const WVec3& p) {
  const WVec3 ab = b - a;
  const Wide t = (p - a).dot(ab);
  if (t <= 0) return a;
  const Wide len2 = ab.squaredNorm();
  if (t >= len2) return b;
  return a + ab * (t / len2);  // 0 < t < len2, so len2 > 0
}

/// Height / longest edge below which closestOnTriangle also takes the boundary's nearest point
/// (the region tests of a thinner triangle can pick the wrong region).
constexpr Wide kSliverHeightRelative = Wide(1e-3);

/// The nearest of the three edges' closest points: the fallback for a triangle too thin for its
/// plane normal to be formed in Wide (|n|² underflows), where the boundary is the whole set up
/// to rounding.
WVec3 closestOnBoundary(const WVec3& a, const WVec3& b, const WVec3& c, const WVec3& p) {
  const WVec3 q[3] = {closestOnSegment(a, b, p), closestOnSegment(b, c, p), closestOnSegment(c, a, p)};
  int best = 0;
  Wide bestD2 = (q[0] - p).squaredNorm();
  for (int i = 1; i < 3; ++i) {
    const Wide d2 = (q[i] - p).squaredNorm();
    if (d2 < bestD2) bestD2 = d2, best = i;
  }
  return q[best];
}

/// Closest point of a proper (non-collinear) triangle: RTCD 5.1.5 ClosestPtPointTriangle.
/// The vertex tests come first and are inclusive (<=, >=), so where an edge test would tie
/// with a vertex test the vertex wins (the errata's (2,-0.5,0) case).
WVec3 closestOnProperTriangle(const WVec3& a, const WVec3& b, const WVec3& c, const WVec3& p) {
  const WVec3 ab = b - a, ac = c - a, ap = p - a;
  const Wide d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;  // vertex region A

  const WVec3 bp = p - b;
  const Wide d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;  // vertex region B

  const Wide vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return closestOnSegment(a, b, p);  // edge region AB

  const WVec3 cp = p - c;
  const Wide d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;  // vertex region C

  const Wide vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return closestOnSegment(a, c, p);  // edge region AC

  const Wide va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return closestOnSegment(b, c, p);  // edge BC

  // Face region: the orthogonal projection onto the plane. Computed from the normal rather than
  // from va/vb/vc, whose cancellation grows with the distance of p.
  const WVec3 n = ab.cross(ac);
  const Wide nn = n.squaredNorm();
  if (!(nn > 0)) return closestOnBoundary(a, b, c, p);
  return p - n * (n.dot(ap) / nn);
}

WVec3 closestOnTriangle(const Triangle& t, const WVec3& p) {
  const predicates::TriangleShape shape = predicates::classify(t);
  switch (shape.kind) {
    case predicates::TriangleKind::Point:
      return shape.p;
    case predicates::TriangleKind::Segment:
      return closestOnSegment(shape.p, shape.q, p);
    case predicates::TriangleKind::Triangle:
      break;
  }
  const WVec3 a = wide(t.a), b = wide(t.b), c = wide(t.c);
  const WVec3 q = closestOnProperTriangle(a, b, c, p);
  // A sliver (height below kSliverHeightRelative of its longest edge): the region tests' products
  // cancel (fuzz_geometry: an edge of 1.6e-28 against edges of 75 read its dot products with
  // p − a and p − b, ±|ab|² exactly, as 0, and the tiny edge's region was taken, 110 from p with
  // a corner 66 from it). Every point of a sliver is within its height of the boundary, so the
  // nearer of q and the nearest boundary point is the answer.
  const Wide longest2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  if ((b - a).cross(c - a).squaredNorm() <= kSliverHeightRelative * kSliverHeightRelative * longest2 * longest2) {
    const WVec3 r = closestOnBoundary(a, b, c, p);
    if ((r - p).squaredNorm() < (q - p).squaredNorm()) return r;
  }
  return q;
}

WVec3 closestOnRay(const Ray& r, const WVec3& p) {
  const WVec3 o = wide(r.origin), d = wide(r.dir);
  const Wide t = (p - o).dot(d);
  if (t <= 0) return o;
  return o + d * (t / d.squaredNorm());
}

WVec3 closestOnSphere(const Sphere& s, const WVec3& p) {
  const WVec3 c = wide(s.center);
  const WVec3 v = p - c;
  const Wide r = s.radius;
  const Wide len2 = v.squaredNorm();
  if (len2 <= r * r) return p;
  return c + v * (r / std::sqrt(len2));  // len2 > r² >= 0
}

WVec3 closestOnAabb(const Aabb& b, const WVec3& p) {
  WVec3 q;
  for (int i = 0; i < 3; ++i) q[i] = std::clamp(p[i], Wide(b.min[i]), Wide(b.max[i]));
  return q;
}

/// Clamp in box coordinates (RTCD 5.1.4), applied as a correction to p so that the components
/// already inside the slab are not re-synthesised (a point inside the box is returned exactly).
WVec3 closestOnObb(const Obb& b, const WVec3& p) {
  const WVec3 d = p - wide(b.center);
  WVec3 q = p;
  for (int i = 0; i < 3; ++i) {
    const WVec3 u = wide(Vec3(b.axes.col(i)));
    const Wide s = d.dot(u), h = b.half[i];
    if (s > h) {
      q -= u * (s - h);
    } else if (s < -h) {
      q -= u * (s + h);
    }
  }
  return q;
}

}  // namespace

Vec3 closestPoint(const Triangle& t, const Vec3& p) { return narrow(closestOnTriangle(t, wide(p))); }

Vec3 closestPoint(const Segment& s, const Vec3& p) {
  return narrow(closestOnSegment(wide(s.start), wide(s.end), wide(p)));
}

Vec3 closestPoint(const Ray& r, const Vec3& p) { return narrow(closestOnRay(r, wide(p))); }

Vec3 closestPoint(const Sphere& s, const Vec3& p) { return narrow(closestOnSphere(s, wide(p))); }

Vec3 closestPoint(const Aabb& b, const Vec3& p) {
  return p.cwiseMax(b.min).cwiseMin(b.max);  // per axis, each axis against its own bounds
}

Vec3 closestPoint(const Obb& b, const Vec3& p) { return narrow(closestOnObb(b, wide(p))); }

Vec3 closestPoint(const Plane& pl, const Vec3& p) {
  const WVec3 n = wide(pl.normal), x = wide(p);
  return narrow(x - n * ((n.dot(x) - Wide(pl.d)) / n.squaredNorm()));
}

Real squaredDistance(const Triangle& t, const Vec3& p) {
  const WVec3 x = wide(p);
  return Real((closestOnTriangle(t, x) - x).squaredNorm());
}

Real squaredDistance(const Segment& s, const Vec3& p) {
  const WVec3 x = wide(p);
  return Real((closestOnSegment(wide(s.start), wide(s.end), x) - x).squaredNorm());
}

Real squaredDistance(const Ray& r, const Vec3& p) {
  const WVec3 x = wide(p);
  return Real((closestOnRay(r, x) - x).squaredNorm());
}

Real squaredDistance(const Sphere& s, const Vec3& p) {
  const Wide gap = (wide(p) - wide(s.center)).norm() - Wide(s.radius);
  return gap > 0 ? Real(gap * gap) : Real(0);
}

Real squaredDistance(const Aabb& b, const Vec3& p) {
  const WVec3 x = wide(p);
  return Real((closestOnAabb(b, x) - x).squaredNorm());
}

Real squaredDistance(const Obb& b, const Vec3& p) {
  // Σ of the squared per-axis excesses (the axes are orthonormal).
  const WVec3 d = wide(p) - wide(b.center);
  Wide d2 = 0;
  for (int i = 0; i < 3; ++i) {
    const Wide excess = std::abs(d.dot(wide(Vec3(b.axes.col(i))))) - Wide(b.half[i]);
    if (excess > 0) d2 += excess * excess;
  }
  return Real(d2);
}

Real squaredDistance(const Plane& pl, const Vec3& p) {
  const WVec3 n = wide(pl.normal);
  const Wide s = n.dot(wide(p)) - Wide(pl.d);
  return Real(s * s / n.squaredNorm());
}

}  // namespace crux
