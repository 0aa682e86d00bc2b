/// @file scene_batch.cpp  Placed-mesh and scene query batches over parallelChunks (mesh/batch_query.hpp).

#include <crux/scene/scene_batch.hpp>

namespace crux {
namespace {

/// out[i] = query(in[i]) for every i, chunked.
template <class In, class Out, class Query>
void batch(const char* function, Span<const In> in, Span<Out> out, const ParallelOptions& parallel,
           const Query& query) {
  requireSameSize(function, in.size, out.size);
  parallelFor(in.size, parallel, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) out.data[i] = query(in.data[i]);
  });
}

template <class Shape>
void regionBatch(const char* function, const Scene& scene, Span<const Shape> shapes, Span<std::vector<ModelId>> out,
                 RegionTest test, const ParallelOptions& parallel, ScenePath path) {
  requireSameSize(function, shapes.size, out.size);
  parallelFor(shapes.size, parallel, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) out[i] = scene.query(shapes[i], test, path);
  });
}

}  // namespace

void raycastClosest(const PlacedMesh& mesh, Span<const Ray> rays, Span<std::optional<MeshRayHit>> out,
                    const RayQueryOptions& options, const ParallelOptions& parallel) {
  batch("raycastClosest (batch)", rays, out, parallel, [&](const Ray& r) { return raycastClosest(mesh, r, options); });
}

void raycastAny(const PlacedMesh& mesh, Span<const Ray> rays, Span<std::uint8_t> out, const RayQueryOptions& options,
                const ParallelOptions& parallel) {
  batch("raycastAny (batch)", rays, out, parallel,
        [&](const Ray& r) { return std::uint8_t(raycastAny(mesh, r, options) ? 1 : 0); });
}

void overlaps(const PlacedMesh& mesh, Span<const Sphere> shapes, Span<std::uint8_t> out,
              const ParallelOptions& parallel) {
  batch("overlaps (batch of spheres)", shapes, out, parallel,
        [&](const Sphere& s) { return std::uint8_t(overlaps(mesh, s) ? 1 : 0); });
}

void overlaps(const PlacedMesh& mesh, Span<const Aabb> shapes, Span<std::uint8_t> out,
              const ParallelOptions& parallel) {
  batch("overlaps (batch of boxes)", shapes, out, parallel,
        [&](const Aabb& b) { return std::uint8_t(overlaps(mesh, b) ? 1 : 0); });
}

void overlaps(const PlacedMesh& mesh, Span<const Obb> shapes, Span<std::uint8_t> out,
              const ParallelOptions& parallel) {
  batch("overlaps (batch of oriented boxes)", shapes, out, parallel,
        [&](const Obb& b) { return std::uint8_t(overlaps(mesh, b) ? 1 : 0); });
}

void raycast(const Scene& scene, Span<const Ray> rays, Span<std::optional<SceneRayHit>> out,
             const RayQueryOptions& options, const ParallelOptions& parallel, ScenePath path) {
  requireSameSize("raycast (scene batch)", rays.size, out.size);
  parallelFor(rays.size, parallel, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) out[i] = scene.raycast(rays[i], options, path);
  });
}

void query(const Scene& scene, Span<const Sphere> shapes, Span<std::vector<ModelId>> out, RegionTest test,
           const ParallelOptions& parallel, ScenePath path) {
  regionBatch("query (scene batch of spheres)", scene, shapes, out, test, parallel, path);
}
void query(const Scene& scene, Span<const Aabb> shapes, Span<std::vector<ModelId>> out, RegionTest test,
           const ParallelOptions& parallel, ScenePath path) {
  regionBatch("query (scene batch of boxes)", scene, shapes, out, test, parallel, path);
}
void query(const Scene& scene, Span<const Obb> shapes, Span<std::vector<ModelId>> out, RegionTest test,
           const ParallelOptions& parallel, ScenePath path) {
  regionBatch("query (scene batch of oriented boxes)", scene, shapes, out, test, parallel, path);
}

}  // namespace crux
