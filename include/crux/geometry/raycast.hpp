#pragma once
/// @file raycast.hpp  Ray casts and segment tests against the primitive shapes.
///
/// Hit/miss decisions are sign-exact on integer-grid inputs; the reported distance t is
/// computed in floating point afterwards. t is in world units (s·|dir|). A ray whose origin
/// lies in a solid shape (sphere, box) hits at t = 0. Triangles are hit from both faces;
/// a degenerate triangle is hit where the ray meets its segment/point.
///
/// Preconditions: the primitive layer's (precondition.hpp, debugPreconditions): finite inputs,
/// non-zero ray directions and plane normals, radii and half extents >= 0, AABB min <= max.
/// Checked in debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG): an abort
/// naming the query. Unchecked in release builds: an unspecified answer, never undefined behaviour.

#include <crux/geometry/shapes.hpp>

#include <limits>
#include <optional>

namespace crux {

/// A ray hit: distance along the ray in world units, the point, and the unit surface
/// normal facing the ray origin (for a hit at t = 0 inside a solid, and for a hit on a
/// degenerate triangle — a segment or point has no surface normal: -dir/|dir|; for a ray
/// lying in a triangle's or plane's plane: the plane normal, either side).
struct RayHit {
  Real t = 0;
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::Zero();
};

/// Distance that means "no limit" for ray casts.
inline constexpr Real kNoLimit = std::numeric_limits<Real>::infinity();

/// Accuracy of a ray–triangle hit distance: the filter stage's t is kept when its error bound
/// (the filter's own, which is pessimistic: the hits it keeps are far more accurate) is within
/// this many ulps of Real × (S + t) / cos θ (S the larger |coordinate| of the origin and the
/// first corner, θ the angle between the ray and the triangle's normal); otherwise the hit is
/// recomputed by the exact stage. That happens on slivers: a flat cap's normal, the cross
/// product of two nearly antiparallel edges, is tilted by ~eps·L/h (height h, longest edge L),
/// and so is the plane its t comes from (double builds: t off by up to 0.04 on caps ~8 long
/// before this). 128: in double builds 0.06 % of the hits on random triangles in [-4, 4]³ take
/// the exact stage and every flat cap hit lies within test_raycast's 4 ulps·(S + t)/cos θ of the
/// exact one (0.46 of it at worst; 512 let intermediate caps reach 1.5 of it); in float builds
/// the filter runs in double, 2^29 times finer than Real, so only caps about 1e-8 times thinner
/// than float's own rounding of their corners (h/L < ~1e-14) would need it.
inline constexpr int kRayParameterUlps = 128;

/// Ray–triangle, two-sided and watertight: the hit is decided by the signs of the three
/// edge triple products d·((v_i - o) × (v_j - o)) (Plücker tests, evaluated so that an edge
/// shared by two triangles gives exactly opposite values; cf. Woop, Benthin & Wald,
/// "Watertight Ray/Triangle Intersection", JCGT 2013), so no ray passes between triangles
/// sharing an edge. Hits beyond maxT are misses. The distance t is n·a / n·d (n the normal,
/// a = corner − origin, d the direction) from the filter stage, or from the exact stage when
/// the filter cannot bound its error within kRayParameterUlps (slivers).
std::optional<RayHit> raycast(const Ray& ray, const Triangle& t, Real maxT = kNoLimit);
/// Ray–sphere (RTCD 5.3.2; origin inside: t = 0; spheres behind the origin miss).
std::optional<RayHit> raycast(const Ray& ray, const Sphere& s, Real maxT = kNoLimit);
/// Ray–AABB slab test with division-free rational comparison of the slab parameters
/// (RTCD 5.3.3; a direction component of 0 rejects when the origin is outside that slab).
std::optional<RayHit> raycast(const Ray& ray, const Aabb& b, Real maxT = kNoLimit);
/// Ray–OBB: the slab test in the box frame.
std::optional<RayHit> raycast(const Ray& ray, const Obb& b, Real maxT = kNoLimit);
/// Ray–plane (RTCD 5.3.1); a ray lying in the plane hits at t = 0.
std::optional<RayHit> raycast(const Ray& ray, const Plane& p, Real maxT = kNoLimit);

/// Segment–triangle: same exact signs as the ray test restricted to the segment
/// (start == end: point-in-triangle).
bool intersects(const Segment& seg, const Triangle& t);
/// Segment–sphere: squared distance from the centre to the segment <= r².
bool intersects(const Segment& seg, const Sphere& s);
/// Segment–AABB: t_enter <= 1 and t_exit >= 0 (a segment inside the box intersects).
bool intersects(const Segment& seg, const Aabb& b);
/// Segment–OBB: as for the AABB, in the box frame.
bool intersects(const Segment& seg, const Obb& b);
/// Segment–plane: endpoint signed distances take both signs or a zero.
bool intersects(const Segment& seg, const Plane& p);

}  // namespace crux
