#pragma once
/// @file mesh_io.hpp  Loading meshes safely: memory estimates checked before a mesh is built, and
/// assimp imports isolated in a child process with a time and memory limit.
///
/// docs/limits.md gives the figures behind the estimate (measured peaks at 1M and 10M triangles)
/// and docs/fuzzing.md why imports are isolated (assimp 5.2 crashes, aborts or hangs on some
/// malformed files, which no try/catch can contain).

#include <crux/mesh/mesh.hpp>

#include <cstddef>
#include <string>

namespace crux {

/// Bytes a Mesh of `vertices` vertices and `triangles` triangles needs, from the sizes of its
/// arrays (not from a measurement): an upper bound for the default BvhBuildOptions.
struct MeshMemoryEstimate {
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  /// Held by the built Mesh: vertices, the index array and its BVH-ordered copy, the 4-wide
  /// BVH's nodes (at most one per triangle) and primitive indices. Mesh::memoryBytes() never
  /// exceeds it.
  std::size_t meshBytes = 0;
  /// Peak during construction: the vertices and indices, plus the BVH builder's temporaries
  /// (triangle boxes, the builder's primitive array, and binary node arrays counted twice
  /// because the parallel build assembles per-task node arrays before copying them into place),
  /// or, when larger, the widening step (the binary tree and the wide tree at once).
  std::size_t peakBytes = 0;
};

/// The estimate for a mesh of the given size (O(1), never throws; saturates at SIZE_MAX).
MeshMemoryEstimate estimateMeshMemory(std::size_t vertices, std::size_t triangles);

/// Bytes this process can still allocate without swapping or being killed, best effort:
/// the smallest of /proc/meminfo MemAvailable (sysconf(_SC_AVPHYS_PAGES) where that is missing),
/// the cgroup v2 limit minus usage (memory.max - memory.current) and RLIMIT_AS minus the
/// process's current size. 0 when nothing can be read (no check is then possible).
std::size_t availableMemoryBytes();

/// "1.23 GB"-style text for a byte count (decimal units), for messages.
std::string formatBytes(std::size_t bytes);

/// Throws InvalidInput, starting with `name`, when estimateMeshMemory(vertices, triangles).peakBytes
/// exceeds the budget: `limitBytes` when non-zero (capped by availableMemoryBytes() when that is
/// known), else availableMemoryBytes() (no check when that is 0). The message gives the counts,
/// the estimate and the budget.
void requireMeshMemory(std::size_t vertices, std::size_t triangles, std::size_t limitBytes, const std::string& name);

/// How loadMesh runs assimp.
enum class MeshImportIsolation {
  /// In a forked child process (POSIX) that sends the triangles back through a pipe: a crash,
  /// abort, hang or out-of-memory in assimp becomes an InvalidInput in the caller. The default.
  Subprocess,
  /// In the calling process: faster for many small trusted files, but a malformed file can
  /// crash the process (docs/fuzzing.md lists known inputs). The only mode without fork().
  InProcess,
};

/// Options of loadMesh.
struct LoadMeshOptions {
  BvhBuildOptions bvh;
  /// Refuse meshes whose estimated peak (estimateMeshMemory) exceeds this many bytes;
  /// 0: the memory available now (availableMemoryBytes()).
  std::size_t memoryLimitBytes = 0;
  MeshImportIsolation isolation = MeshImportIsolation::Subprocess;
  /// Wall-clock limit of a Subprocess import in seconds; 0: 10 s + 2 s per MB of file.
  double timeLimitSeconds = 0;
};

/// loadMesh (mesh.hpp) with explicit limits: OFF files are read by crux's own strict reader in
/// process; every other format by assimp, isolated as `options.isolation` says. The memory
/// check runs as soon as the counts are known (OFF: after the header, before the vertices are
/// read; assimp: before the parent allocates the triangles it receives) and again before the
/// BVH build. Throws InvalidInput naming the file and the problem.
Mesh loadMesh(const std::string& path, const LoadMeshOptions& options);

}  // namespace crux
