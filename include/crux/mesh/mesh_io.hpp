#pragma once
/// @file mesh_io.hpp  Loading meshes safely: memory estimates checked before a mesh is built, and
/// assimp imports, on request, isolated in a child process with a time and memory limit.
///
/// docs/limits.md gives the figures behind the estimate (measured peaks at 1M and 10M triangles)
/// and docs/fuzzing.md why imports may need isolating (assimp 5.2 crashes, aborts or hangs on
/// some malformed files, which no try/catch can contain). The library never forks: a forked copy
/// of a threaded host (locks held by other threads, allocation, assimp's statics) is not safe to
/// run. Isolation starts a separate program instead (posix_spawn of an import command, which
/// execs at once), such as the `crux import-mesh` command the `crux` command line uses for every
/// file it loads.

#include <crux/mesh/mesh.hpp>

#include <cstddef>
#include <string>
#include <vector>

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
  /// (the builder's primitive array, and binary node arrays counted twice
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
  /// In the calling process (the default): no child process. A malformed file can crash the
  /// process inside assimp (docs/fuzzing.md lists known inputs); trusted files only.
  InProcess,
  /// In a child process (POSIX) started by posix_spawn from LoadMeshOptions::importCommand,
  /// which sends the triangles back through a pipe (runMeshImport): a crash, abort, hang or
  /// out-of-memory in assimp becomes an InvalidInput in the caller.
  Subprocess,
};

/// Options of loadMesh.
struct LoadMeshOptions {
  BvhBuildOptions bvh;
  /// Refuse meshes whose estimated peak (estimateMeshMemory) exceeds this many bytes;
  /// 0: the memory available now (availableMemoryBytes()).
  std::size_t memoryLimitBytes = 0;
  MeshImportIsolation isolation = MeshImportIsolation::InProcess;
  /// Subprocess only: the import command, its executable's path first, then its arguments
  /// (e.g. {"/usr/bin/crux", "import-mesh"}). loadMesh appends two arguments, the child's
  /// address-space budget in bytes and the file's path, and reads the child's standard output;
  /// the command answers with runMeshImport. Empty with Subprocess: InvalidInput.
  std::vector<std::string> importCommand;
  /// Wall-clock limit of a Subprocess import in seconds; 0: 10 s + 2 s per MB of file.
  double timeLimitSeconds = 0;
};

/// The child's side of MeshImportIsolation::Subprocess, for an import command's main (the
/// `crux import-mesh BUDGET PATH` command calls it): imports `path` with assimp in this
/// process, after limiting this process's address space to its current size plus
/// `memoryBudgetBytes` (0: no limit; none under sanitizers, which reserve terabytes), and writes
/// the answer to the descriptor `fd` in the form loadMesh reads: the vertices and triangles, or
/// an error message. Returns the exit status for the command (0 once the answer is written).
/// A crash inside assimp kills this process, which is the point.
int runMeshImport(const std::string& path, std::size_t memoryBudgetBytes, int fd);

/// loadMesh (mesh.hpp) with explicit limits: OFF files are read by crux's own strict reader in
/// process; every other format by assimp, in process or isolated as `options.isolation` says. The memory
/// check runs as soon as the counts are known (OFF: after the header, before the vertices are
/// read; assimp: before the parent allocates the triangles it receives) and again before the
/// BVH build. Throws InvalidInput naming the file and the problem.
Mesh loadMesh(const std::string& path, const LoadMeshOptions& options);

}  // namespace crux
