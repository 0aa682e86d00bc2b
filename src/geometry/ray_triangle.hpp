#pragma once
/// @file ray_triangle.hpp  Internal: raycast(Ray, Triangle) in stages, for queries that test one
/// ray against many triangles (the mesh ray kernel, mesh/mesh_query.cpp).
///
/// raycast(Ray, Triangle) is rayTriangleCrossing (the exact decision and the hit parameter,
/// raycast.cpp) followed by rayHitAt (distance, point and unit normal). A mesh query keeps only
/// the crossing of each candidate and forms the hit of the winner alone. When the caller has
/// already proved that the ray's line crosses the triangle's interior (the float filter of
/// mesh/ray_kernel.hpp: all three edge products strictly of one sign beyond their error bound),
/// properRayTriangleCrossing settles the rest with the filter-stage arithmetic alone: the side
/// of the origin, the parameter and its accuracy bound (kRayParameterUlps), bounded statically
/// (Higham's forward error bounds on the products, not a running bound); it answers
/// "undecided" when those bounds do not settle it, and the caller then runs rayTriangleCrossing.
/// Its decision is exact and its parameter raycast's filter-stage value (test_raycast:
/// CertifiedCrossingIsRaycastsOwnAnswerOrDefers); in double builds raycast itself may take its
/// exact stage for such a crossing (a sign elsewhere unsure), so the two may differ in the last
/// bits, both within kRayParameterUlps.

#include <crux/geometry/predicates.hpp>
#include <crux/geometry/raycast.hpp>

#include <optional>

namespace crux::geometry_detail {

/// A ray–triangle hit before its point and normal are formed: the ray parameter s (the hit is
/// origin + s·dir) and a non-unit normal facing the origin (zero: none, e.g. a degenerate
/// triangle; raycast's RayHit::normal rule applies when the hit is formed).
struct RayCrossing {
  Wide s = 0;
  WVec3 normal = WVec3::Zero();
};

/// raycast(ray, t)'s decision and parameter (exact decision; the parameter from the filter
/// stage, or the exact stage for slivers). nullopt: no hit at any distance.
std::optional<RayCrossing> rayTriangleCrossing(const Ray& ray, const Triangle& t);

/// For a proper triangle whose interior the ray's line is known to cross with d·n of sign
/// `det` (+1 or -1, n = (b − a) × (c − a)): 1 and `out` set when the ray hits it, 0 when the
/// plane lies behind the origin, -1 (undecided) when the origin's side or the parameter's
/// accuracy needs more than the filter stage (then call rayTriangleCrossing). A hit's
/// parameter and normal are those raycast's filter stage computes.
int properRayTriangleCrossing(const Ray& ray, const Triangle& t, int det, RayCrossing& out);

/// |dir| as raycast measures hit distances (finite where |dir|² overflows): a hit at parameter
/// s lies at world distance Real(s · rayLength(dir)).
Wide rayLength(const Vec3& dir);

/// The hit at crossing c: world distance, point and unit normal, exactly as raycast(Ray,
/// Triangle) reports it; nullopt when the distance exceeds maxT or is not finite.
std::optional<RayHit> rayHitAt(const Ray& ray, const RayCrossing& c, Real maxT);
/// rayHitAt with rayLength(ray.dir) already known (a query that tests many triangles forms it
/// once per ray): the same hit, bit for bit.
std::optional<RayHit> rayHitAt(const Ray& ray, const RayCrossing& c, Real maxT, Wide length);

}  // namespace crux::geometry_detail
