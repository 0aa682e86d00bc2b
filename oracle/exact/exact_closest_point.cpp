/// @file exact_closest_point.cpp  Exact closest point of a (possibly degenerate) triangle (CGAL).
///
/// Independent of RTCD's Voronoi regions: the closest point of a proper triangle is the
/// orthogonal projection onto its plane when that projection lies in the closed triangle, and
/// otherwise the nearest of the three edges' closest points (the boundary is then nearest).
/// A collinear or repeated-corner triangle is the segment or point it spans (toSimplex).
/// The squared distance is CGAL's own Point_3–simplex squared_distance.

#include <CGAL/squared_distance_3.h>

#include <variant>

#include "exact/exact.hpp"
#include "exact/exact_kernel.hpp"

namespace crux::exact {
namespace {

using namespace detail;

/// Closest point of the closed segment [a, b] (a != b) to p, exactly.
Point closestOnSegment(const Point& a, const Point& b, const Point& p) {
  const Vector ab = b - a;
  const FT t = (p - a) * ab;
  if (t <= 0) return a;
  const FT len2 = ab.squared_length();
  if (t >= len2) return b;
  return a + ab * (t / len2);
}

Point closestOnTriangle(const Triangle3& t, const Point& p) {
  const Point q = t.supporting_plane().projection(p);
  if (t.has_on(q)) return q;
  Point best = p;
  FT bestD2 = -1;
  for (int i = 0; i < 3; ++i) {
    const Point c = closestOnSegment(t.vertex(i), t.vertex(i + 1), p);
    const FT d2 = CGAL::squared_distance(c, p);
    if (bestD2 < 0 || d2 < bestD2) best = c, bestD2 = d2;
  }
  return best;
}

Vec3d toVec3d(const Point& p) {
  return {CGAL::to_double(CGAL::exact(p.x())), CGAL::to_double(CGAL::exact(p.y())),
          CGAL::to_double(CGAL::exact(p.z()))};
}

}  // namespace

Vec3d closestPoint(const Triangle& t, const Vec3& p) {
  const Point x = toPoint(p);
  const Simplex s = toSimplex(t);
  if (const auto* point = std::get_if<Point>(&s)) return toVec3d(*point);
  if (const auto* seg = std::get_if<Segment3>(&s)) return toVec3d(closestOnSegment(seg->source(), seg->target(), x));
  return toVec3d(closestOnTriangle(std::get<Triangle3>(s), x));
}

double squaredDistance(const Triangle& t, const Vec3& p) {
  const Point x = toPoint(p);
  const Simplex s = toSimplex(t);
  const FT d2 = std::visit([&](const auto& simplex) { return FT(CGAL::squared_distance(x, simplex)); }, s);
  return CGAL::to_double(CGAL::exact(d2));
}

}  // namespace crux::exact
