#pragma once
/// @file exact.hpp  The exact oracle: CGAL's exact kernel (Epeck) applied to crux shapes.
///
/// Every input coordinate is converted exactly (float/double -> exact rational), so these
/// answers are the true answers for the shapes as given. Slow; used by tests, the `exact`
/// backend and the differential fuzzer. Degenerate inputs (collinear triangles, flat boxes,
/// zero radii) are mapped to the lower-dimensional CGAL objects they are, since CGAL's
/// predicates require non-degenerate arguments.
///
/// An OBB is the parallelepiped {c + Σ s_i h_i u_i : |s_i| <= 1} spanned by its axes exactly as
/// given (not re-orthonormalised).

#include <crux/geometry/shapes.hpp>

#include <optional>

namespace crux::exact {

using Vec3d = Eigen::Vector3d;

// ---- overlaps (exact_overlap.cpp, exact_triangle.cpp) ----
bool overlaps(const Sphere& a, const Sphere& b);
bool overlaps(const Sphere& s, const Aabb& b);
bool overlaps(const Sphere& s, const Obb& b);
bool overlaps(const Sphere& s, const Plane& p);
bool overlaps(const Aabb& a, const Aabb& b);
bool overlaps(const Aabb& a, const Obb& b);
bool overlaps(const Aabb& b, const Plane& p);
bool overlaps(const Obb& a, const Obb& b);
bool overlaps(const Obb& b, const Plane& p);
bool overlaps(const Plane& a, const Plane& b);
bool overlaps(const Triangle& a, const Triangle& b);
bool overlaps(const Triangle& t, const Sphere& s);
bool overlaps(const Triangle& t, const Aabb& b);
bool overlaps(const Triangle& t, const Obb& b);
bool overlaps(const Triangle& t, const Plane& p);

// ---- closest points (exact_closest_point.cpp) ----
/// Exact closest point of the triangle to p, rounded to double at the end.
Vec3d closestPoint(const Triangle& t, const Vec3& p);
/// Exact squared distance from p to the triangle, rounded to double at the end.
double squaredDistance(const Triangle& t, const Vec3& p);

// ---- rays and segments (exact_raycast.cpp) ----
/// Exact first-hit distance along the ray in world units (rounded to double), or nullopt.
std::optional<double> raycast(const Ray& r, const Triangle& t);
std::optional<double> raycast(const Ray& r, const Sphere& s);
std::optional<double> raycast(const Ray& r, const Aabb& b);
std::optional<double> raycast(const Ray& r, const Obb& b);
std::optional<double> raycast(const Ray& r, const Plane& p);
bool intersects(const Segment& s, const Triangle& t);
bool intersects(const Segment& s, const Sphere& sp);
bool intersects(const Segment& s, const Aabb& b);
bool intersects(const Segment& s, const Obb& b);
bool intersects(const Segment& s, const Plane& p);

}  // namespace crux::exact
