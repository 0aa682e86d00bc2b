#pragma once
/// @file batch_query.hpp  Batches of mesh queries over spans of inputs, run on all cores.
///
/// Each batch function answers out[i] = the single query on in[i] (mesh_query.hpp) for every
/// i, splitting the index range over oneTBB worker threads (tbb::parallel_for over a
/// blocked_range, auto partitioner). Every answer is computed by the
/// very function the serial path calls, on one thread, so results are bitwise identical to the
/// serial loop whatever the thread count or split. Threads share only const data (the mesh and
/// the inputs) and write disjoint output elements in contiguous chunks of at least `grain`
/// elements, so there is no shared mutable state and false sharing is limited to the cache line
/// at each chunk boundary.
///
/// Preconditions as for the single queries: inputs are valid shapes (validate(Ray) etc.; the
/// queries themselves never throw). The batch functions throw InvalidInput, before any work,
/// when the output span's size differs from the input span's or the options are out of range.
///
/// Batches on placed meshes (model layer) and scenes are in scene/scene_batch.hpp.
///
/// Threads (docs/threads.md): const queries on a Mesh are safe from any number of threads; the
/// batch functions rely on it. The mesh must not be changed (setVertices) while a
/// batch runs.

#include <crux/mesh/mesh_query.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace crux {

/// A minimal C++17 stand-in for std::span: a pointer and a size (no ownership).
template <class T>
struct Span {
  T* data = nullptr;
  std::size_t size = 0;

  constexpr Span() = default;
  constexpr Span(T* d, std::size_t n) : data(d), size(n) {}
  /// From a vector (const or not) of the element type.
  template <class V, class = decltype(static_cast<T*>(std::declval<V&>().data()))>
  Span(V& v) : data(v.data()), size(v.size()) {}  // NOLINT: implicit like std::span
  T& operator[](std::size_t i) const { return data[i]; }
  T* begin() const { return data; }
  T* end() const { return data + size; }
};

/// How a batch runs.
struct ParallelOptions {
  /// Worker threads: 0 = the current task arena (all cores by default); 1 = a plain serial loop
  /// on the calling thread (no TBB); n > 1 = a task arena of n threads. At most kMaxBatchThreads.
  std::uint32_t threads = 0;
  /// Fewest queries per task (0 = kDefaultBatchGrain). Each query costs roughly 0.2–5 µs, so a
  /// grain of 32 keeps a task (~10–100 µs) far above TBB's per-task overhead (~1 µs) while
  /// leaving n/32 tasks to balance over 64 cores.
  std::uint32_t grain = 0;
};

/// Upper limit of ParallelOptions::threads.
inline constexpr std::uint32_t kMaxBatchThreads = 4096;
/// Grain used when ParallelOptions::grain is 0.
inline constexpr std::uint32_t kDefaultBatchGrain = 32;

/// Runs body(begin, end) over [0, n) in chunks as ParallelOptions says (the engine of every
/// batch function; exposed for other layers' batches). Throws InvalidInput for threads above
/// kMaxBatchThreads. Exceptions thrown by body are rethrown on the calling thread.
void parallelChunks(std::size_t n, const ParallelOptions& parallel,
                    void (*body)(void* context, std::size_t begin, std::size_t end), void* context);

/// Type-safe wrapper over parallelChunks for any callable body(begin, end).
template <class Body>
void parallelFor(std::size_t n, const ParallelOptions& parallel, const Body& body) {
  parallelChunks(
      n, parallel, [](void* c, std::size_t b, std::size_t e) { (*static_cast<const Body*>(c))(b, e); },
      const_cast<void*>(static_cast<const void*>(&body)));
}

/// Throws InvalidInput unless out.size == in.size (names the function and both sizes).
void requireSameSize(const char* function, std::size_t inSize, std::size_t outSize);

/// out[i] = raycastClosest(mesh, rays[i], options) (front-to-back BVH traversal per ray).
void raycastClosest(const Mesh& mesh, Span<const Ray> rays, Span<std::optional<MeshRayHit>> out,
                    const RayQueryOptions& options = {}, const ParallelOptions& parallel = {});
/// Boolean answers are written as std::uint8_t (1 = true, 0 = false) so that a
/// std::vector<std::uint8_t> can hold them (std::vector<bool> has no contiguous storage).
///
/// out[i] = raycastAny(mesh, rays[i], options) (stops at the first hit per ray).
void raycastAny(const Mesh& mesh, Span<const Ray> rays, Span<std::uint8_t> out, const RayQueryOptions& options = {},
                const ParallelOptions& parallel = {});
/// out[i] = overlaps(mesh, shapes[i]): does shape i touch the mesh's surface? (exact on
/// integer-grid input, as the single query).
void overlaps(const Mesh& mesh, Span<const Sphere> shapes, Span<std::uint8_t> out, const ParallelOptions& parallel = {});
void overlaps(const Mesh& mesh, Span<const Aabb> shapes, Span<std::uint8_t> out, const ParallelOptions& parallel = {});
void overlaps(const Mesh& mesh, Span<const Obb> shapes, Span<std::uint8_t> out, const ParallelOptions& parallel = {});

}  // namespace crux
