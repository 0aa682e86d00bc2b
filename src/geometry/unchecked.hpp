// The primitive layer without its debug check: the routines behind the public primitive queries
// (include/crux/geometry/: overlap, raycast, closest_point, the triangle contacts, triangle_distance).
// Each public query is a two-line entry in checked_primitives.cpp: debugPreconditions
// (precondition.hpp), then the routine here. The mesh, model, scene, contact and world layers call
// these routines directly: they check their own inputs at entry, and the values they derive from
// them (a fattened broad-phase box, a triangle mapped by an extreme pose, a face normal) may
// overflow to ±inf for finite input, which the routines answer conservatively and the entry check
// would abort on. Same contracts and documentation as the public declarations; a non-queryable
// input gets an unspecified answer, never undefined behaviour (the per-family tests call these
// routines; boxTriangleContacts answers them with no contact before its GJK fallback, whose
// public entry would abort on them in debug builds). Pairs are in the public order only (overlap.hpp:
// Triangle < Sphere < Aabb < Obb < Plane); the reversed order exists for the public names alone.
#pragma once

#include <crux/geometry/overlap.hpp>
#include <crux/geometry/raycast.hpp>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/triangle_contact.hpp>
#include <crux/geometry/box_triangle_contact.hpp>
#include <crux/geometry/triangle_distance.hpp>

namespace crux::unchecked {

// Overlap tests and the exact within-distance decisions (overlap.hpp).
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
bool withinDistance(const Triangle& t, const Vec3& x, Real radius, Real margin);
bool withinDistance(const Triangle& t, const Vec3& p, const Vec3& q, Real radius, Real margin);

// Ray casts and segment tests (raycast.hpp).
std::optional<RayHit> raycast(const Ray& ray, const Triangle& t, Real maxT = kNoLimit);
std::optional<RayHit> raycast(const Ray& ray, const Sphere& sp, Real maxT = kNoLimit);
std::optional<RayHit> raycast(const Ray& ray, const Aabb& box, Real maxT = kNoLimit);
std::optional<RayHit> raycast(const Ray& ray, const Obb& box, Real maxT = kNoLimit);
std::optional<RayHit> raycast(const Ray& ray, const Plane& p, Real maxT = kNoLimit);
bool intersects(const Segment& seg, const Triangle& t);
bool intersects(const Segment& seg, const Sphere& sp);
bool intersects(const Segment& seg, const Aabb& box);
bool intersects(const Segment& seg, const Obb& box);
bool intersects(const Segment& seg, const Plane& p);

// Closest points and squared distances to a point (closest_point.hpp).
Vec3 closestPoint(const Triangle& t, const Vec3& p);
Vec3 closestPoint(const Segment& s, const Vec3& p);
Vec3 closestPoint(const Ray& r, const Vec3& p);
Vec3 closestPoint(const Sphere& s, const Vec3& p);
Vec3 closestPoint(const Aabb& b, const Vec3& p);
Vec3 closestPoint(const Obb& b, const Vec3& p);
Vec3 closestPoint(const Plane& pl, const Vec3& p);
bool beyondAnEdgeLine(const Triangle& t, const Vec3& p, Real d);
Real squaredDistance(const Triangle& t, const Vec3& p);
Real squaredDistance(const Segment& s, const Vec3& p);
Real squaredDistance(const Ray& r, const Vec3& p);
Real squaredDistance(const Sphere& s, const Vec3& p);
Real squaredDistance(const Aabb& b, const Vec3& p);
Real squaredDistance(const Obb& b, const Vec3& p);
Real squaredDistance(const Plane& pl, const Vec3& p);

// Sphere and capsule contacts against one triangle (triangle_contact.hpp).
bool sphereTriangleContacts(const Triangle& tri, const Vec3& centre, Real radius, Real margin, ContactManifold& out);
bool sphereTriangleContact(const Triangle& tri, const Vec3& centre, Real radius, Real margin,
                           SphereTriangleContact& out);
bool capsuleTriangleContacts(const Triangle& tri, const Vec3& p0In, const Vec3& p1In, Real radius, Real margin,
                             ContactManifold& out);

// Box contacts against one triangle (box_triangle_contact.hpp).
bool boxTriangleContacts(const Vec3& half, const Triangle& tri, Real margin, ContactManifold& out);

// Triangle–triangle closest points (triangle_distance.hpp).
TriangleDistanceResult closestPoints(const Triangle& a, const Triangle& b);

}  // namespace crux::unchecked
