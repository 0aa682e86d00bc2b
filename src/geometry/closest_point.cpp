/// @file closest_point.cpp  Closest points and squared distances (Ericson, RTCD chapter 5.1).
///
/// Everything is computed in Wide (double) from the exactly promoted inputs and rounded to Real
/// once at the end. Region decisions use inclusive comparisons; reported points are computed
/// by the best-conditioned formula for the region found (projection onto an edge's line or the
/// triangle's plane), never by a division that can be 0/0.

#include "geometry/unchecked.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/predicates.hpp>

#include "geometry/closest_point_internal.hpp"

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
  // A proper (non-collinear) triangle: RTCD 5.1.5 by closest_detail::closestOnProperTriangle (the
  // vertex tests come first and are inclusive, so where an edge test would tie with a vertex
  // test the vertex wins: the errata's (2,-0.5,0) case); a thin one by its boundary.
  const WVec3 a = wide(t.a), b = wide(t.b), c = wide(t.c);
  const Wide longest2 = std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  const bool thin = belowThinLine(std::sqrt((b - a).cross(c - a).squaredNorm()), longest2);
  WVec3 q;
  closest_detail::closestOnProperTriangle(a, b, c, p, thin, q);
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

Vec3 unchecked::closestPoint(const Triangle& t, const Vec3& p) {
  return narrow(closestOnTriangle(t, wide(p)));
}

Vec3 unchecked::closestPoint(const Segment& s, const Vec3& p) {
  return narrow(closestOnSegment(wide(s.start), wide(s.end), wide(p)));
}

Vec3 unchecked::closestPoint(const Ray& r, const Vec3& p) {
  return narrow(closestOnRay(r, wide(p)));
}

Vec3 unchecked::closestPoint(const Sphere& s, const Vec3& p) {
  return narrow(closestOnSphere(s, wide(p)));
}

Vec3 unchecked::closestPoint(const Aabb& b, const Vec3& p) {
  return p.cwiseMax(b.min).cwiseMin(b.max);  // per axis, each axis against its own bounds
}

Vec3 unchecked::closestPoint(const Obb& b, const Vec3& p) {
  return narrow(closestOnObb(b, wide(p)));
}

Vec3 unchecked::closestPoint(const Plane& pl, const Vec3& p) {
  const WVec3 n = wide(pl.normal), x = wide(p);
  return narrow(x - n * ((n.dot(x) - Wide(pl.d)) / n.squaredNorm()));
}

bool unchecked::beyondAnEdgeLine(const Triangle& t, const Vec3& p, Real d) {
  const Eigen::Vector3d v[3] = {t.a.cast<double>(), t.b.cast<double>(), t.c.cast<double>()};
  const Eigen::Vector3d n = (v[1] - v[0]).cross(v[2] - v[0]);
  const Eigen::Vector3d q = p.cast<double>();
  const double lim = double(d) * double(d) * n.squaredNorm();
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d e = v[(i + 1) % 3] - v[i];
    const double s = e.cross(q - v[i]).dot(n);  // in-plane signed distance × |e| |n|
    if (s < 0 && s * s > lim * e.squaredNorm()) return true;
  }
  return false;
}

Real unchecked::squaredDistance(const Triangle& t, const Vec3& p) {
  const WVec3 x = wide(p);
  return Real((closestOnTriangle(t, x) - x).squaredNorm());
}

Real unchecked::squaredDistance(const Segment& s, const Vec3& p) {
  const WVec3 x = wide(p);
  return Real((closestOnSegment(wide(s.start), wide(s.end), x) - x).squaredNorm());
}

Real unchecked::squaredDistance(const Ray& r, const Vec3& p) {
  const WVec3 x = wide(p);
  return Real((closestOnRay(r, x) - x).squaredNorm());
}

Real unchecked::squaredDistance(const Sphere& s, const Vec3& p) {
  const Wide gap = (wide(p) - wide(s.center)).norm() - Wide(s.radius);
  return gap > 0 ? Real(gap * gap) : Real(0);
}

Real unchecked::squaredDistance(const Aabb& b, const Vec3& p) {
  const WVec3 x = wide(p);
  return Real((closestOnAabb(b, x) - x).squaredNorm());
}

Real unchecked::squaredDistance(const Obb& b, const Vec3& p) {
  // Σ of the squared per-axis excesses (the axes are orthonormal).
  const WVec3 d = wide(p) - wide(b.center);
  Wide d2 = 0;
  for (int i = 0; i < 3; ++i) {
    const Wide excess = std::abs(d.dot(wide(Vec3(b.axes.col(i))))) - Wide(b.half[i]);
    if (excess > 0) d2 += excess * excess;
  }
  return Real(d2);
}

Real unchecked::squaredDistance(const Plane& pl, const Vec3& p) {
  const WVec3 n = wide(pl.normal);
  const Wide s = n.dot(wide(p)) - Wide(pl.d);
  return Real(s * s / n.squaredNorm());
}

}  // namespace crux

namespace crux::closest_detail {

int closestOnSliver(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& p, Eigen::Vector3d& q) {
  using V = Eigen::Vector3d;
  constexpr double kMinSine = 1e-7, kInsideSlackUlps = 64;
  const V v[3] = {a, b, c};
  const double len2[3] = {(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()};  // edge i: v[i] -> v[i+1]
  // Whether y is nearer to x than z: |y − x|² − |z − x|² = (y − z)·((y − x) + (z − x)) < 0. The
  // difference's rounding error is relative to |y − z|·|x| rather than |x|², so two candidates
  // nearly equidistant from a far point are told apart to a few ulps of their positions (crux
  // diff: a sliver's two corners 5e-14 apart, 2.8 from the point, compared by their rounded
  // squared distances ~8 picked the farther one, tests/regressions/native.crux-wrong.
  // closest_point_triangle.15042-1882900).
  auto nearer = [](const V& y, const V& z, const V& x) { return (y - z).dot((y - x) + (z - x)) < 0; };
  // the nearest point of x on the three edges (RTCD 5.1.2 per edge), its squared distance and region
  auto boundary = [&](const V& x, V& nearest) {
    int region = -1;
    for (int i = 0; i < 3; ++i) {
      const V e = v[(i + 1) % 3] - v[i];
      const double t = (x - v[i]).dot(e);
      V y;
      int r = i;
      if (t <= 0) y = v[i], r = 3 + i;
      else if (t >= len2[i]) y = v[(i + 1) % 3], r = 3 + (i + 1) % 3;
      else y = v[i] + e * (t / len2[i]);  // 0 < t < len2: len2 > 0
      if (region < 0 || nearer(y, nearest, x)) nearest = y, region = r;
    }
    return std::make_pair((nearest - x).squaredNorm(), region);
  };
  const int region = boundary(p, q).second;
  const int longest = len2[0] >= len2[1] ? (len2[0] >= len2[2] ? 0 : 2) : (len2[1] >= len2[2] ? 1 : 2);
  const int o = (longest + 2) % 3;  // the corner opposite the longest edge
  // (v[o+1] − v[o]) × (v[o+2] − v[o]): the normal (b − a) × (c − a), cyclically; |n| = |e||e'|·sine
  const V n = (v[(o + 1) % 3] - v[o]).cross(v[(o + 2) % 3] - v[o]);
  const double nn = n.squaredNorm();
  if (!(nn > kMinSine * kMinSine * len2[(o + 2) % 3] * len2[o])) return region;
  const V f = p - n * (n.dot(p - v[o]) / nn);
  const double scale = std::max({a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff(), c.cwiseAbs().maxCoeff(),
                                 p.cwiseAbs().maxCoeff()});
  const double slack = kInsideSlackUlps * std::numeric_limits<double>::epsilon() * scale;
  for (int i = 0; i < 3; ++i) {
    const V e = v[(i + 1) % 3] - v[i];
    // |e||n| × the signed distance of f from edge i's line, in the plane, positive inside
    if (e.cross(f - v[i]).dot(n) < -slack * std::sqrt(nn * len2[i])) return region;
  }
  // Within the slack of every edge's half-plane is not yet near the triangle: beyond a needle's
  // sharp corner the two long edges' half-planes stay within the slack for a long way (fuzz_geometry:
  // p projected 2.7 beyond the corner of a needle of width 6e-14). Every point of the triangle is
  // within half its height of the boundary.
  V fNearest;
  const double halfHeight = 0.5 * std::sqrt(nn / len2[longest]) + slack;
  if (!(boundary(f, fNearest).first <= halfHeight * halfHeight)) return region;
  if (!nearer(f, q, p)) return region;
  q = f;
  return -1;
}



}  // namespace crux::closest_detail
