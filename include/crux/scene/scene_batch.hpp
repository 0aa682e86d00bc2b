#pragma once
/// @file scene_batch.hpp  Batches of placed-mesh and scene queries (rays, overlaps, region
/// queries) run on all cores.
///
/// As mesh/batch_query.hpp: out[i] is the single Scene query on in[i], computed by the same
/// function the serial path calls, so answers are bitwise identical whatever the thread count.
/// Const Scene queries are thread-safe (docs/threads.md); no mutation of the scene may run
/// while a batch does. Throws InvalidInput when sizes differ or options are out of range.

#include <crux/mesh/batch_query.hpp>
#include <crux/scene/scene.hpp>

#include <optional>
#include <vector>

namespace crux {

/// The mesh batches of mesh/batch_query.hpp on a placed mesh, with world-space rays and shapes
/// (model_query.hpp); booleans as std::uint8_t 1/0.
void raycastClosest(const PlacedMesh& mesh, Span<const Ray> rays, Span<std::optional<MeshRayHit>> out,
                    const RayQueryOptions& options = {}, const ParallelOptions& parallel = {});
void raycastAny(const PlacedMesh& mesh, Span<const Ray> rays, Span<std::uint8_t> out, const RayQueryOptions& options = {},
                const ParallelOptions& parallel = {});
void overlaps(const PlacedMesh& mesh, Span<const Sphere> shapes, Span<std::uint8_t> out, const ParallelOptions& parallel = {});
void overlaps(const PlacedMesh& mesh, Span<const Aabb> shapes, Span<std::uint8_t> out, const ParallelOptions& parallel = {});
void overlaps(const PlacedMesh& mesh, Span<const Obb> shapes, Span<std::uint8_t> out, const ParallelOptions& parallel = {});

/// out[i] = scene.raycast(rays[i], options, path).
void raycast(const Scene& scene, Span<const Ray> rays, Span<std::optional<SceneRayHit>> out,
             const RayQueryOptions& options = {}, const ParallelOptions& parallel = {},
             ScenePath path = ScenePath::BroadPhase);

/// out[i] = scene.query(shapes[i], test, path): ids (ascending) of the models touching shape i.
/// Each output vector is replaced (its storage is that of the single query's result).
void query(const Scene& scene, Span<const Sphere> shapes, Span<std::vector<ModelId>> out,
           RegionTest test = RegionTest::Triangles, const ParallelOptions& parallel = {},
           ScenePath path = ScenePath::BroadPhase);
void query(const Scene& scene, Span<const Aabb> shapes, Span<std::vector<ModelId>> out,
           RegionTest test = RegionTest::Triangles, const ParallelOptions& parallel = {},
           ScenePath path = ScenePath::BroadPhase);
void query(const Scene& scene, Span<const Obb> shapes, Span<std::vector<ModelId>> out,
           RegionTest test = RegionTest::Triangles, const ParallelOptions& parallel = {},
           ScenePath path = ScenePath::BroadPhase);

}  // namespace crux
