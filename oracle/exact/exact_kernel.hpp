#pragma once
/// @file exact_kernel.hpp  Internal: CGAL kernel types and exact conversions from crux shapes.
/// Included only by oracle/exact/*.cpp.

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <crux/geometry/shapes.hpp>

#include <array>
#include <optional>
#include <variant>

namespace crux::exact::detail {

using K = CGAL::Exact_predicates_exact_constructions_kernel;
using FT = K::FT;
using Point = K::Point_3;
using Vector = K::Vector_3;
using Segment3 = K::Segment_3;
using Triangle3 = K::Triangle_3;
using Plane3 = K::Plane_3;
using Ray3 = K::Ray_3;
using Sphere3 = K::Sphere_3;
using Cuboid = K::Iso_cuboid_3;
using Tetra = K::Tetrahedron_3;

/// Exact conversion (every float/double is a dyadic rational).
inline Point toPoint(const Vec3& v) { return Point(double(v.x()), double(v.y()), double(v.z())); }
inline Vector toVector(const Vec3& v) { return Vector(double(v.x()), double(v.y()), double(v.z())); }

/// A (possibly degenerate) triangle as the exact object it is.
using Simplex = std::variant<Point, Segment3, Triangle3>;

/// The point / segment / triangle three exact points span: a proper triangle, the longest
/// side of collinear corners, or the point they coincide in.
inline Simplex simplexOf(const Point& a, const Point& b, const Point& c) {
  if (!CGAL::collinear(a, b, c)) return Triangle3(a, b, c);
  if (a == b && b == c) return a;
  const FT ab = CGAL::squared_distance(a, b), bc = CGAL::squared_distance(b, c),
           ca = CGAL::squared_distance(c, a);
  if (ab >= bc && ab >= ca) return Segment3(a, b);
  if (bc >= ca) return Segment3(b, c);
  return Segment3(c, a);
}

/// Classifies a triangle exactly: a proper triangle, the segment its collinear corners span,
/// or a point.
inline Simplex toSimplex(const Triangle& t) { return simplexOf(toPoint(t.a), toPoint(t.b), toPoint(t.c)); }

// ---- the exact predicates on simplices with exact corners ------------------------------------
// The public functions of exact.hpp are these applied to toSimplex(triangle); the exact world
// applies them to mesh triangles placed by exact (rational) transforms, whose corners are in
// general not floating-point numbers.

/// Does the simplex meet the closed ball / box / parallelepiped / plane / other simplex?
bool overlapsSimplex(const Simplex& s, const Sphere& sphere);  // exact_triangle.cpp
bool overlapsSimplex(const Simplex& s, const Aabb& box);
bool overlapsSimplex(const Simplex& s, const Obb& box);
bool overlapsSimplex(const Simplex& s, const Plane& plane);
bool overlapsSimplex(const Simplex& a, const Simplex& b);
/// Does the closed box meet the OBB's parallelepiped (exact_triangle.cpp)?
bool overlapsCuboid(const Cuboid& box, const Obb& obb);
/// Does the segment (a point when start == end) meet the simplex? (exact_raycast.cpp)
bool intersectsSimplex(const Segment& seg, const Simplex& s);
/// First hit of the ray on the simplex: the exact ray parameter s (point = o + s·dir), or
/// nothing (exact_raycast.cpp).
std::optional<FT> rayParamSimplex(const Ray& r, const Simplex& s);
/// World distance s·|dir| of a ray parameter, in double within a few ulps (exact_raycast.cpp).
double rayDistance(const Ray& r, const FT& s);
/// Whether a hit at ray parameter s >= 0 lies within the world distance maxDistance (closed:
/// s·|dir| <= maxDistance), decided exactly (s²|dir|² <= maxDistance²), not on the rounded
/// rayDistance, which can exceed a maxDistance the hit meets exactly (exact_raycast.cpp).
bool withinRayDistance(const Ray& r, const FT& s, double maxDistance);

/// The edge vectors e_i of the box whose axes are `axes` (columns u_i): the dual basis
/// e_i = (u_j × u_k) / (u_i · (u_j × u_k)) ((i, j, k) cyclic), so u_i · e_j = δ_ij exactly. An OBB
/// is {x : |u_i·(x − c)| <= h_i} (exact.hpp), the parallelepiped {c + Σ s_i h_i e_i : |s_i| <= 1};
/// for exactly orthonormal axes e_i = u_i.
inline std::array<Vector, 3> edgeVectors(const Mat3& axes) {
  const Vector u[3] = {toVector(Vec3(axes.col(0))), toVector(Vec3(axes.col(1))), toVector(Vec3(axes.col(2)))};
  const FT det = u[0] * CGAL::cross_product(u[1], u[2]);
  std::array<Vector, 3> e;
  for (int i = 0; i < 3; ++i) e[i] = CGAL::cross_product(u[(i + 1) % 3], u[(i + 2) % 3]) / det;
  return e;
}

/// The 8 corners of an OBB computed exactly: corner k is c + Σ s_i h_i e_i with s_i = ((k >> i)
/// & 1) ? +1 : -1 (edgeVectors).
inline std::array<Point, 8> corners(const Obb& b) {
  std::array<Point, 8> out;
  const Point c = toPoint(b.center);
  const std::array<Vector, 3> e = edgeVectors(b.axes);
  for (int k = 0; k < 8; ++k) {
    Vector off(0, 0, 0);
    for (int i = 0; i < 3; ++i) {
      const FT s = ((k >> i) & 1) ? FT(double(b.half[i])) : FT(-double(b.half[i]));
      off = off + e[i] * s;
    }
    out[k] = c + off;
  }
  return out;
}

}  // namespace crux::exact::detail
