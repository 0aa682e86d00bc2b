/// @file exact_triangle.cpp  Exact (CGAL Epeck) overlap of a triangle with a triangle, sphere,
/// AABB, OBB and plane. Degenerate triangles are the CGAL point/segment they collapse to
/// (detail::toSimplex); a flat OBB is the parallelogram, segment or point it collapses to.

#include "exact/exact.hpp"
#include "exact/exact_kernel.hpp"

#include <CGAL/intersections.h>
#include <CGAL/squared_distance_3.h>

#include <array>
#include <variant>

namespace crux::exact {

using namespace detail;

namespace {

/// do_intersect of a simplex (point, segment, triangle) with any CGAL object.
template <class Object>
bool simplexIntersects(const Simplex& s, const Object& o) {
  return std::visit([&o](const auto& x) { return CGAL::do_intersect(x, o); }, s);
}

/// The closed parallelepiped of an OBB as a union of exact pieces: six tetrahedra (the Kuhn
/// triangulation along the diagonal from corner 0 to corner 7), or, when some half extents
/// are zero, the two triangles of the parallelogram, the segment or the point it collapses to.
struct Parallelepiped {
  std::array<Tetra, 6> tetras;
  int tetraCount = 0;
  std::array<Triangle3, 2> triangles;
  int triangleCount = 0;
  std::variant<std::monostate, Segment3, Point> lower;
};

Parallelepiped decompose(const Obb& b) {
  const std::array<Point, 8> p = corners(b);
  int live[3], n = 0;
  for (int i = 0; i < 3; ++i) {
    if (b.half[i] != 0) live[n++] = i;
  }
  Parallelepiped out;
  if (n == 3) {
    static constexpr int kPermutations[6][2] = {{0, 1}, {0, 2}, {1, 0}, {1, 2}, {2, 0}, {2, 1}};
    for (const auto& perm : kPermutations) {
      const int first = 1 << perm[0];
      const int second = first | (1 << perm[1]);
      out.tetras[out.tetraCount++] = Tetra(p[0], p[first], p[second], p[7]);
    }
  } else if (n == 2) {
    const int i = 1 << live[0], j = 1 << live[1];
    out.triangles[out.triangleCount++] = Triangle3(p[0], p[i], p[i | j]);
    out.triangles[out.triangleCount++] = Triangle3(p[0], p[i | j], p[j]);
  } else if (n == 1) {
    out.lower = Segment3(p[0], p[1 << live[0]]);
  } else {
    out.lower = p[0];
  }
  return out;
}

}  // namespace

namespace detail {

bool overlapsSimplex(const Simplex& a, const Simplex& b) {
  return std::visit([](const auto& x, const auto& y) { return CGAL::do_intersect(x, y); }, a, b);
}

bool overlapsSimplex(const Simplex& s, const Sphere& sphere) {
  const Point center = toPoint(sphere.center);
  const FT r(double(sphere.radius));
  return std::visit([&](const auto& x) { return CGAL::squared_distance(x, center) <= r * r; }, s);
}

bool overlapsSimplex(const Simplex& s, const Aabb& b) {
  // Iso_cuboid_3 accepts zero extents; its tests with points, segments and triangles are
  // separating-axis / slab tests that stay exact for flat boxes (cross-checked in the tests
  // against the OBB decomposition below).
  return simplexIntersects(s, Cuboid(toPoint(b.min), toPoint(b.max)));
}

bool overlapsSimplex(const Simplex& s, const Obb& b) {
  const Parallelepiped box = decompose(b);
  for (int i = 0; i < box.tetraCount; ++i) {
    if (simplexIntersects(s, box.tetras[i])) return true;
  }
  for (int i = 0; i < box.triangleCount; ++i) {
    if (simplexIntersects(s, box.triangles[i])) return true;
  }
  if (const auto* seg = std::get_if<Segment3>(&box.lower)) return simplexIntersects(s, *seg);
  if (const auto* pt = std::get_if<Point>(&box.lower)) return simplexIntersects(s, *pt);
  return false;
}

bool overlapsSimplex(const Simplex& s, const Plane& p) {
  const Plane3 plane(FT(double(p.normal.x())), FT(double(p.normal.y())), FT(double(p.normal.z())),
                     -FT(double(p.d)));
  return simplexIntersects(s, plane);
}

bool overlapsCuboid(const Cuboid& c, const Obb& b) {
  // The same decomposition of the parallelepiped; CGAL decides each piece against the box.
  const Parallelepiped box = decompose(b);
  for (int i = 0; i < box.tetraCount; ++i) {
    if (CGAL::do_intersect(c, box.tetras[i])) return true;
  }
  for (int i = 0; i < box.triangleCount; ++i) {
    if (CGAL::do_intersect(c, box.triangles[i])) return true;
  }
  if (const auto* seg = std::get_if<Segment3>(&box.lower)) return CGAL::do_intersect(c, *seg);
  if (const auto* pt = std::get_if<Point>(&box.lower)) return CGAL::do_intersect(c, *pt);
  return false;
}

}  // namespace detail

bool overlaps(const Triangle& a, const Triangle& b) { return overlapsSimplex(toSimplex(a), toSimplex(b)); }
bool overlaps(const Triangle& t, const Sphere& s) { return overlapsSimplex(toSimplex(t), s); }
bool overlaps(const Triangle& t, const Aabb& b) { return overlapsSimplex(toSimplex(t), b); }
bool overlaps(const Triangle& t, const Obb& b) { return overlapsSimplex(toSimplex(t), b); }
bool overlaps(const Triangle& t, const Plane& p) { return overlapsSimplex(toSimplex(t), p); }

}  // namespace crux::exact
