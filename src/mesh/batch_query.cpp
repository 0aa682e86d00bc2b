/// @file batch_query.cpp  Mesh query batches: one chunked loop (parallelChunks) over the single
/// queries, run by oneTBB.

#include <crux/error.hpp>
#include <crux/mesh/batch_query.hpp>

#include "tbb_policy.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <string>

namespace crux {

void requireSameSize(const char* function, std::size_t inSize, std::size_t outSize) {
  if (inSize != outSize)
    throw InvalidInput(std::string(function) + ": out has " + std::to_string(outSize) + " elements, the input has " +
                       std::to_string(inSize));
}

void parallelChunks(std::size_t n, const ParallelOptions& parallel,
                    void (*body)(void* context, std::size_t begin, std::size_t end), void* context) {
  if (parallel.threads > kMaxBatchThreads)
    throw InvalidInput("ParallelOptions.threads: " + std::to_string(parallel.threads) + " exceeds " +
                       std::to_string(kMaxBatchThreads));
  if (n == 0) return;
  const std::size_t grain = parallel.grain == 0 ? kDefaultBatchGrain : parallel.grain;
  if (!kTbbParallelAllowed || parallel.threads == 1 || n <= grain) {
    body(context, 0, n);
    return;
  }
  auto run = [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(context, r.begin(), r.end()); });
  };
  if (parallel.threads == 0) {
    run();
  } else {
    tbb::task_arena arena(static_cast<int>(parallel.threads));
    arena.execute(run);
  }
}

namespace {

/// out[i] = query(in[i]) for every i, chunked.
template <class In, class Out, class Query>
void batch(const char* function, Span<const In> in, Span<Out> out, const ParallelOptions& parallel,
           const Query& query) {
  requireSameSize(function, in.size, out.size);
  parallelFor(in.size, parallel, [&](std::size_t begin, std::size_t end) {
    const In* src = in.data;
    Out* dst = out.data;
    for (std::size_t i = begin; i < end; ++i) dst[i] = query(src[i]);
  });
}

}  // namespace

void raycastClosest(const Mesh& mesh, Span<const Ray> rays, Span<std::optional<MeshRayHit>> out,
                    const RayQueryOptions& options, const ParallelOptions& parallel) {
  batch("raycastClosest (batch)", rays, out, parallel, [&](const Ray& r) { return raycastClosest(mesh, r, options); });
}

void raycastAny(const Mesh& mesh, Span<const Ray> rays, Span<std::uint8_t> out, const RayQueryOptions& options,
                const ParallelOptions& parallel) {
  batch("raycastAny (batch)", rays, out, parallel,
        [&](const Ray& r) { return std::uint8_t(raycastAny(mesh, r, options) ? 1 : 0); });
}

void overlaps(const Mesh& mesh, Span<const Sphere> shapes, Span<std::uint8_t> out, const ParallelOptions& parallel) {
  batch("overlaps (batch of spheres)", shapes, out, parallel,
        [&](const Sphere& s) { return std::uint8_t(overlaps(mesh, s) ? 1 : 0); });
}

void overlaps(const Mesh& mesh, Span<const Aabb> shapes, Span<std::uint8_t> out, const ParallelOptions& parallel) {
  batch("overlaps (batch of boxes)", shapes, out, parallel,
        [&](const Aabb& b) { return std::uint8_t(overlaps(mesh, b) ? 1 : 0); });
}

void overlaps(const Mesh& mesh, Span<const Obb> shapes, Span<std::uint8_t> out, const ParallelOptions& parallel) {
  batch("overlaps (batch of oriented boxes)", shapes, out, parallel,
        [&](const Obb& b) { return std::uint8_t(overlaps(mesh, b) ? 1 : 0); });
}

}  // namespace crux
