#pragma once
/// @file closest_point.hpp  Closest point of a shape to a point, and squared distances.
///
/// All shapes are closed sets: a point inside a solid (sphere, box) is its own closest point.
///
/// Preconditions: the primitive layer's (precondition.hpp, debugPreconditions): finite inputs,
/// non-zero ray directions and plane normals, radii and half extents >= 0, AABB min <= max.
/// Checked in debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG): an abort
/// naming the query. Unchecked in release builds: an unspecified answer, never undefined behaviour.

#include <crux/geometry/shapes.hpp>

namespace crux {

/// Closest point of triangle t to p by Voronoi-region classification (Ericson, RTCD 5.1.5,
/// ClosestPtPointTriangle), with ties resolved inclusively so a vertex region wins where two
/// edge tests tie. A degenerate triangle is treated as the segment or point it spans. A sliver
/// (kTriangleThinRelative, triangle_class.hpp: height below 1e-3 of its longest edge), whose region tests cancel, takes no region test: its
/// nearest boundary point, or the projection of p onto its plane when that lies inside it and is
/// nearer (docs/geometry.md, "Closest point on a sliver triangle").
Vec3 closestPoint(const Triangle& t, const Vec3& p);
/// Closest point of segment s to p (RTCD 5.1.2); start == end is a point.
Vec3 closestPoint(const Segment& s, const Vec3& p);
/// Closest point of ray r to p (the origin when p is behind it).
Vec3 closestPoint(const Ray& r, const Vec3& p);
/// Closest point of the ball to p (p itself when inside).
Vec3 closestPoint(const Sphere& s, const Vec3& p);
/// Closest point of the box to p: per-axis clamp (RTCD 5.1.3).
Vec3 closestPoint(const Aabb& b, const Vec3& p);
/// Closest point of the oriented box to p: clamp in box coordinates (RTCD 5.1.4).
Vec3 closestPoint(const Obb& b, const Vec3& p);
/// Orthogonal projection of p onto the plane (RTCD 5.1.1).
Vec3 closestPoint(const Plane& pl, const Vec3& p);

/// Whether p lies beyond one of t's edge lines, in t's plane and on the outside, by more than
/// d >= 0: then p is farther than d from t (t lies within each edge's half-plane), whatever p's
/// height above the plane. A cheap conservative "far from the triangle" test (three cross
/// products, no square root, in double from the exact edge differences of the corners: with
/// n = (b − a) × (c − a), (e × (p − v))·n / (|e| |n|) is p's in-plane signed distance from the
/// edge line through v along e); false says nothing. A degenerate triangle (n = 0) gives false.
bool beyondAnEdgeLine(const Triangle& t, const Vec3& p, Real d);

/// Squared Euclidean distance from p to the shape (0 inside solids).
Real squaredDistance(const Triangle& t, const Vec3& p);
Real squaredDistance(const Segment& s, const Vec3& p);
Real squaredDistance(const Ray& r, const Vec3& p);
Real squaredDistance(const Sphere& s, const Vec3& p);
Real squaredDistance(const Aabb& b, const Vec3& p);
Real squaredDistance(const Obb& b, const Vec3& p);
Real squaredDistance(const Plane& pl, const Vec3& p);

}  // namespace crux
