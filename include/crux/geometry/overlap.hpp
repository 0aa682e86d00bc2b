#pragma once
/// @file overlap.hpp  Boolean overlap tests between closed shapes.
///
/// Every test is sign-exact on integer-grid inputs (|coordinates| <= 64; OBB axes that are
/// signed unit vectors) in both precisions: predicates are evaluated as division-free
/// polynomials in Wide, e.g. sphere–plane as (n·c - d)² <= r²|n|². Touching intersects.
///
/// One function exists per unordered pair, for the order Triangle < Sphere < Aabb < Obb <
/// Plane; the reversed order is derived by the template at the end of this file.
///
/// Preconditions: the primitive layer's (precondition.hpp, debugPreconditions): finite inputs,
/// non-zero ray directions and plane normals, radii and half extents >= 0, AABB min <= max.
/// Checked in debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG): an abort
/// naming the query. Unchecked in release builds: an unspecified answer, never undefined behaviour.

#include <crux/geometry/shapes.hpp>

#include <type_traits>

namespace crux {

/// Sphere–sphere: |c1 - c2|² <= (r1 + r2)² (RTCD 4.3.1).
bool overlaps(const Sphere& a, const Sphere& b);
/// Sphere–AABB: squared distance from the centre to the box <= r² (RTCD 5.2.5).
bool overlaps(const Sphere& s, const Aabb& b);
/// Sphere–OBB: squared distance from the centre to the box <= r² (RTCD 5.2.6).
bool overlaps(const Sphere& s, const Obb& b);
/// Sphere–plane: (n·c - d)² <= r²|n|² (RTCD 5.2.2, division-free).
bool overlaps(const Sphere& s, const Plane& p);
/// AABB–AABB: interval overlap on each axis (RTCD 4.2.1).
bool overlaps(const Aabb& a, const Aabb& b);
/// AABB–OBB: the separating-axis test of RTCD 4.4.1 with the AABB as an OBB.
bool overlaps(const Aabb& a, const Obb& b);
/// AABB–plane: |n·c - d| <= Σ h_i |n_i| (RTCD 5.2.3).
bool overlaps(const Aabb& b, const Plane& p);
/// OBB–OBB: separating-axis test over the 15 axes A_i, B_j, A_i × B_j (RTCD 4.4.1).
/// Cross axes nearer parallel than kParallelAxisTolerance are skipped (their separation is
/// covered by the face axes up to that tolerance).
bool overlaps(const Obb& a, const Obb& b);
/// OBB–plane: |n·c - d| <= Σ h_i |n·u_i| (RTCD 5.2.3).
bool overlaps(const Obb& b, const Plane& p);
/// Plane–plane: non-parallel planes always meet; parallel ones only when coincident.
bool overlaps(const Plane& a, const Plane& b);

/// Triangle–triangle: Guigue & Devillers, "Fast and robust triangle-triangle overlap test
/// using orientation predicates" (JGT 2003), with exact orientation signs; coplanar pairs by
/// 2-D edge tests in the dominant projection; degenerate triangles as segments/points.
bool overlaps(const Triangle& a, const Triangle& b);
/// Triangle–sphere: squared distance from the centre to the triangle <= r², division-free:
/// plane distance when the centre projects inside (exact orientation signs), else the three
/// edges as segments (RTCD 5.2.7; no region classification by products of dot products, which
/// cancels on slivers). Sliver triangles (sin² of a corner angle < 1e-24) are measured by edges.
bool overlaps(const Triangle& t, const Sphere& s);
/// Triangle–AABB: 13-axis separating-axis test with the box centred at the origin
/// (Akenine-Möller 2001, RTCD 5.2.9).
bool overlaps(const Triangle& t, const Aabb& b);
/// Triangle–OBB: the same 13-axis test in the box's frame.
bool overlaps(const Triangle& t, const Obb& b);
/// Triangle–plane: the corners' signed distances n·v - d take both signs or a zero.
bool overlaps(const Triangle& t, const Plane& p);

/// Whether the closed triangle t (degenerate ones as their segment or point) is within
/// distance radius + margin of point x, decided exactly (the sum, its square and every sign in
/// exact arithmetic when the filter cannot decide, as the overlap tests above). The contact
/// routines (triangle_contact.hpp) ask it when their double distance is within rounding of the
/// margin, so that touching on integer grids is reported exactly.
bool withinDistance(const Triangle& t, const Vec3& x, Real radius, Real margin);
/// The same for the segment [p, q] (a point when p == q): 0 when it meets the triangle, else
/// the nearer of its endpoints' distances and its distances to the triangle's edges (segment
/// pairs by RTCD 5.1.9's parameters, division-free).
bool withinDistance(const Triangle& t, const Vec3& p, const Vec3& q, Real radius, Real margin);
/// The general form: two cores of 1 to 3 points each (a point, a segment, a triangle;
/// coincident or collinear points classified exactly) within radiusA + radiusB + margin of each
/// other (two triangles: 0 when they meet, else a corner against the other or two edges). The
/// convex pair contacts (contact.hpp) ask it near the margin for cores of 1-3 points (spheres,
/// capsules, triangles, hulls of <= 3 vertices), against each other or against a box's or
/// larger hull's boundary triangles.
/// Throws InvalidInput for other point counts.
bool withinDistance(const WVec3* a, int na, const WVec3* b, int nb, Wide radiusA, Wide radiusB, Wide margin);

/// Near-parallel cutoff for cross-product axes in OBB tests: a cross axis L = u × v with
/// |L|² <= kParallelAxisTolerance·|u|²|v|² is skipped.
inline constexpr Wide kParallelAxisTolerance = 1e-12;

namespace detail {
template <class T> struct ShapeRank;
template <> struct ShapeRank<Triangle> : std::integral_constant<int, 0> {};
template <> struct ShapeRank<Sphere> : std::integral_constant<int, 1> {};
template <> struct ShapeRank<Aabb> : std::integral_constant<int, 2> {};
template <> struct ShapeRank<Obb> : std::integral_constant<int, 3> {};
template <> struct ShapeRank<Plane> : std::integral_constant<int, 4> {};
}  // namespace detail

/// (B, A) overlap derived from (A, B): overlap is symmetric.
template <class A, class B,
          std::enable_if_t<(detail::ShapeRank<A>::value > detail::ShapeRank<B>::value), int> = 0>
bool overlaps(const A& a, const B& b) {
  return overlaps(b, a);
}

}  // namespace crux
