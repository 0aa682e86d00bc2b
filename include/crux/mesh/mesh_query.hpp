#pragma once
/// @file mesh_query.hpp  Queries against a triangle mesh, in the mesh's own space.
///
/// Every query runs through the mesh's BVH (QueryPath::Bvh, the default) or over every triangle
/// (QueryPath::BruteForce, the reference the tests compare with); both give identical answers.
/// Per-triangle decisions are the geometry layer's exact tests, so a boolean answer on
/// integer-grid input is exact, and rays through shared edges/vertices are never lost
/// (watertight).
///
/// Preconditions (precondition.hpp): every coordinate of the query shape finite, a ray's
/// direction and a plane's normal non-zero, a radius and half extents >= 0, an AABB's
/// min <= max (queryable(...), geometry/shapes.hpp). An input that fails them gets no answer —
/// no hit, false, an empty list — and, in builds with CRUX_CHECK_PRECONDITIONS (debug builds),
/// an abort naming the query. validate(...) throws InvalidInput naming the field instead.

#include <crux/geometry/raycast.hpp>
#include <crux/mesh/mesh.hpp>

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace crux {

/// Which path a mesh query takes.
enum class QueryPath { Bvh, BruteForce };

/// A ray hit on a mesh: distance (world units), point, unit normal facing the ray origin, and
/// the index of the triangle hit. Among equal t the lowest triangle index is reported.
struct MeshRayHit {
  Real t = 0;
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::Zero();
  std::uint32_t triangle = 0;
};

/// Work counters of ray queries (bench_mesh's instrumentation): what the traversal and the ray
/// kernel did, summed over the queries given them.
struct RayQueryCounters {
  std::uint64_t nodes = 0;      ///< wide BVH nodes whose four lanes were tested
  std::uint64_t triangles = 0;  ///< triangles given to the per-triangle test
  std::uint64_t certified = 0;  ///< of those, proved a proper crossing by the float filter
  std::uint64_t exactPath = 0;  ///< of those, decided by raycast's own (filter, then exact) path
};

/// Ray query options.
struct RayQueryOptions {
  Real maxDistance = kNoLimit;  ///< hits with t > maxDistance are ignored
  /// Skip triangles whose front face (counter-clockwise a, b, c: normal (b-a)×(c-a)) looks away
  /// from the ray (normal·dir > 0). Degenerate and edge-on triangles are never culled.
  bool cullBackFaces = false;
  /// When set, closest and any-hit queries add their work to it (not thread-safe: one per
  /// thread). Does not change any answer.
  RayQueryCounters* counters = nullptr;
};

/// Closest hit: front-to-back BVH traversal pruning nodes beyond the best hit.
std::optional<MeshRayHit> raycastClosest(const Mesh& mesh, const Ray& ray, const RayQueryOptions& options = {},
                                         QueryPath path = QueryPath::Bvh);
/// Any hit within maxDistance (stops at the first one found).
bool raycastAny(const Mesh& mesh, const Ray& ray, const RayQueryOptions& options = {},
                QueryPath path = QueryPath::Bvh);
/// Every hit, sorted by t (then triangle index).
std::vector<MeshRayHit> raycastAll(const Mesh& mesh, const Ray& ray, const RayQueryOptions& options = {},
                                   QueryPath path = QueryPath::Bvh);

/// Does the shape touch any triangle of the mesh? (Surface test: a shape wholly inside a closed
/// mesh does not touch it.)
bool intersects(const Mesh& mesh, const Segment& s, QueryPath path = QueryPath::Bvh);
bool overlaps(const Mesh& mesh, const Sphere& s, QueryPath path = QueryPath::Bvh);
bool overlaps(const Mesh& mesh, const Aabb& b, QueryPath path = QueryPath::Bvh);
bool overlaps(const Mesh& mesh, const Obb& b, QueryPath path = QueryPath::Bvh);
bool overlaps(const Mesh& mesh, const Plane& p, QueryPath path = QueryPath::Bvh);
bool overlaps(const Mesh& mesh, const Triangle& t, QueryPath path = QueryPath::Bvh);

/// Indices (ascending) of every triangle the shape touches.
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Segment& s, QueryPath path = QueryPath::Bvh);
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Sphere& s, QueryPath path = QueryPath::Bvh);
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Aabb& b, QueryPath path = QueryPath::Bvh);
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Obb& b, QueryPath path = QueryPath::Bvh);
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Plane& p, QueryPath path = QueryPath::Bvh);
std::vector<std::uint32_t> touchingTriangles(const Mesh& mesh, const Triangle& t, QueryPath path = QueryPath::Bvh);

/// Mesh–mesh: do the surfaces of a (placed by ta) and b (placed by tb) touch or cross?
/// Simultaneous BVH-vs-BVH descent with node boxes tested as OBBs in a's frame (RTCD 6.5),
/// triangle pairs by the exact triangle–triangle test after mapping b's triangles into a's
/// frame (exact when the relative transform is the identity).
bool overlaps(const Mesh& a, const Transform& ta, const Mesh& b, const Transform& tb,
              QueryPath path = QueryPath::Bvh);
/// Every touching triangle pair (index in a, index in b), sorted.
std::vector<std::pair<std::uint32_t, std::uint32_t>> touchingTrianglePairs(
    const Mesh& a, const Transform& ta, const Mesh& b, const Transform& tb, QueryPath path = QueryPath::Bvh);

}  // namespace crux
