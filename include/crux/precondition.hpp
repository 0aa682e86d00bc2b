#pragma once
/// @file precondition.hpp  Checking the queries' preconditions at their entry points.
///
/// Every public query states its preconditions (finite inputs, a non-zero ray direction and
/// rotation, a non-negative radius: queryable(...) in geometry/shapes.hpp and convex.hpp). At the
/// entry points of the mesh and scene queries, the convex pair queries (distance, overlaps,
/// contacts, casts), shape–mesh contacts and distance, mesh–mesh overlap and distance, and the
/// mesh and scene casts,
/// an input that fails them is answered with nothing (no hit, no overlap, no contact, an empty
/// list, `found == false`; a convex pair's distance is NaN), never undefined behaviour. In builds with CRUX_CHECK_PRECONDITIONS (on by default when
/// crux itself is compiled without NDEBUG, i.e. debug builds) the entry point aborts instead, with
/// a message naming the query and the rule, so that a bad input is found where it was made.
/// Release callers who want an error rather than an empty answer call validate(...) first: it
/// throws InvalidInput naming the field. The primitive layer (one shape against another or a
/// point) aborts the same way in debug builds (debugPreconditions); in release builds it answers a
/// non-queryable input with an unspecified value, never undefined behaviour.

#include <crux/geometry/shapes.hpp>  // queryable(...): its Vec3 overload must be visible here (no ADL for Eigen)

#ifndef CRUX_CHECK_PRECONDITIONS
#ifdef NDEBUG
#define CRUX_CHECK_PRECONDITIONS 0
#else
#define CRUX_CHECK_PRECONDITIONS 1
#endif
#endif

/// The primitive layer's check (debugPreconditions) follows CRUX_CHECK_PRECONDITIONS: on in debug
/// builds, off with NDEBUG; 0 or 1 overrides it. It guards the public entries of the layer
/// (src/geometry/checked_primitives.cpp; and the test reference detail::boxTriangleContactsFullSat).
/// The mesh, scene, contact and world layers call the
/// unchecked routines behind them (src/geometry/unchecked.hpp): they check their own inputs at
/// entry, and the values they derive from them (a fattened broad-phase box, a triangle mapped by
/// an extreme pose) may overflow to ±inf for finite input, which the routines answer
/// conservatively and the check would abort on.
#ifndef CRUX_CHECK_PRIMITIVE_PRECONDITIONS
#define CRUX_CHECK_PRIMITIVE_PRECONDITIONS CRUX_CHECK_PRECONDITIONS
#endif

namespace crux::detail {

/// Prints "crux: precondition violated in <query>: <rule>" to stderr and aborts.
[[noreturn]] void preconditionFailed(const char* query, const char* rule);

/// The rules as the failure message states them, one text per rule.
namespace rule {
inline constexpr const char* kRay = "a ray with a finite origin and a finite, non-zero direction (validate(Ray))";
inline constexpr const char* kSegment = "a segment with finite ends (validate(Segment))";
inline constexpr const char* kSphere = "a sphere with a finite centre and a finite radius >= 0 (validate(Sphere))";
inline constexpr const char* kAabb = "an AABB with finite min <= max (validate(Aabb))";
inline constexpr const char* kObb = "an OBB with finite centre and axes and finite half extents >= 0 (validate(Obb))";
inline constexpr const char* kPlane = "a plane with a finite, non-zero normal and a finite offset (validate(Plane))";
inline constexpr const char* kTriangle = "a triangle with finite corners (validate(Triangle))";
inline constexpr const char* kPoint = "a point with finite coordinates (validatePoint)";
inline constexpr const char* kRegion =
    "a finite sphere (radius >= 0), AABB (min <= max) or OBB (half extents >= 0): validate(...)";
inline constexpr const char* kPoses = "finite poses with non-zero rotations (validate(Transform))";
inline constexpr const char* kShapesAtPoses =
    "finite shapes (radius and half extents >= 0) at finite poses with non-zero rotations (validate(ConvexShape), "
    "validate(Transform))";
inline constexpr const char* kCast =
    "a finite shape at finite poses, a finite motion (validate(ConvexShape), validate(Transform), validateMotion)";
inline constexpr const char* kPrimitive =
    "finite shapes and points (a ray's direction non-zero, radii >= 0, an AABB's min <= max, an OBB's half extents "
    ">= 0, a plane's normal non-zero): validate(...)";
}  // namespace rule

/// Whether every input (a shape, a point, a pose, a motion) meets the query's cheap preconditions
/// (queryable(...)); when one does not and CRUX_CHECK_PRECONDITIONS is on,
/// preconditionFailed(query, rule) instead of returning false. The one entry check of every query.
template <class... Inputs>
bool entryPreconditions(const char* query, const char* rule, const Inputs&... inputs) {
  using crux::queryable;  // (detail's own overloads, e.g. ShapesAtPoses's, are found by ADL)
  if ((queryable(inputs) && ...)) return true;
  if (CRUX_CHECK_PRECONDITIONS) preconditionFailed(query, rule);
  return false;
}

/// The check of the primitive layer (one shape against another or a point: raycast, intersects,
/// overlaps, withinDistance, closestPoint, squaredDistance, beyondAnEdgeLine, triangle–triangle
/// closest points and the triangle contact routines): with CRUX_CHECK_PRIMITIVE_PRECONDITIONS (on
/// in debug builds) it aborts like entryPreconditions (tested per family); otherwise it is
/// nothing, and a non-queryable input gets an unspecified answer, never undefined behaviour
/// (tested per family on the unchecked routines, also under ASan + UBSan).
template <class... Inputs>
void debugPreconditions([[maybe_unused]] const char* query, [[maybe_unused]] const Inputs&... inputs) {
  if constexpr (CRUX_CHECK_PRIMITIVE_PRECONDITIONS != 0) {
    using crux::queryable;
    if (!(queryable(inputs) && ...)) preconditionFailed(query, rule::kPrimitive);
  }
}

}  // namespace crux::detail
