/// @file mesh_io.cpp  Memory estimates and the available-memory check of mesh loading
/// (mesh_io.hpp). The estimate adds the sizes of the arrays a Mesh and its BVH build allocate
/// (src/mesh/mesh.cpp, src/mesh/bvh.cpp); docs/limits.md compares it with measured peaks.

#include <crux/mesh/mesh_io.hpp>

#include <crux/error.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#if defined(__unix__) || defined(__APPLE__)
#include <sys/resource.h>
#include <unistd.h>
#endif

namespace crux {
namespace {

constexpr std::size_t kMax = std::numeric_limits<std::size_t>::max();

std::size_t mul(std::size_t a, std::size_t b) { return a != 0 && b > kMax / a ? kMax : a * b; }
std::size_t add(std::size_t a, std::size_t b) { return b > kMax - a ? kMax : a + b; }

/// The builder's per-primitive record (bvh.cpp BuildPrim): two 4-lane boxes corners of Real.
constexpr std::size_t kBuildPrimBytes = 2 * 4 * sizeof(Real);

/// "Key: <number> kB" from a /proc file, in bytes; 0 when absent.
std::size_t procKilobytes(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) != 0) continue;
    std::istringstream fields(line.substr(key.size()));
    unsigned long long kb = 0;
    if (fields >> kb) return mul(std::size_t(kb), 1024);
  }
  return 0;
}

/// A single number from a file (cgroup memory.max / memory.current); false for "max" or absent.
bool readNumber(const char* file, std::size_t& value) {
  std::ifstream in(file);
  unsigned long long v = 0;
  if (!(in >> v)) return false;
  value = std::size_t(v);
  return true;
}

}  // namespace

MeshMemoryEstimate estimateMeshMemory(std::size_t vertices, std::size_t triangles) {
  MeshMemoryEstimate e;
  e.vertices = vertices;
  e.triangles = triangles;
  const std::size_t nodes = triangles == 0 ? 0 : mul(2, triangles) - 1;
  // Wide nodes: a node of fewer than four lanes has only leaf lanes (widenBvh opens inner lanes
  // while it can), so with U four-lane nodes and B others over L <= triangles leaves,
  // 4U + 2B <= (U + B − 1) + L and B <= L/2, hence U + B <= (2L − 1)/3 (and 1 for one leaf).
  const std::size_t wideNodes = triangles == 0 ? 0 : std::max<std::size_t>(1, add(mul(2, triangles), 2) / 3);
  const std::size_t vertexBytes = mul(vertices, sizeof(Vec3));
  const std::size_t indexBytes = mul(triangles, sizeof(TriangleIndices));
  const std::size_t nodeBytes = mul(nodes, sizeof(BvhNode));
  const std::size_t wideBytes = mul(wideNodes, sizeof(WideBvhNode));
  const std::size_t primIndexBytes = mul(triangles, sizeof(std::uint32_t));
  // Built: vertices, triangles, slotTriangles, wide nodes, primIndices.
  e.meshBytes = add(add(add(vertexBytes, mul(2, indexBytes)), wideBytes), primIndexBytes);
  // During the binary build: vertices, triangles, the builder's prims (each triangle's box is
  // read from the vertices) and primIndices, and the node arrays twice (per-task arrays + the
  // final one); then, while the binary tree is widened: vertices, triangles, the binary tree,
  // the wide one, the widening's list of wide nodes (grown by push_back: up to twice its size)
  // and primIndices (moved, not copied).
  // slotTriangles is allocated after the temporaries are freed, in less space than they took.
  const std::size_t buildTemporaries = mul(triangles, kBuildPrimBytes);
  e.peakBytes =
      add(add(add(add(vertexBytes, indexBytes), buildTemporaries), primIndexBytes), mul(2, nodeBytes));
  const std::size_t wideList = mul(2 * sizeof(std::uint32_t), wideNodes);
  const std::size_t widening =
      add(add(add(vertexBytes, indexBytes), add(nodeBytes, wideBytes)), add(primIndexBytes, wideList));
  e.peakBytes = std::max(e.peakBytes, widening);
  e.peakBytes = std::max(e.peakBytes, e.meshBytes);
  return e;
}

std::size_t availableMemoryBytes() {
  std::size_t available = 0;
#if defined(__unix__) || defined(__APPLE__)
  available = procKilobytes("/proc/meminfo", "MemAvailable:");
  if (available == 0) {
#if defined(_SC_AVPHYS_PAGES)
    const long pages = ::sysconf(_SC_AVPHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
    if (pages > 0 && page > 0) available = mul(std::size_t(pages), std::size_t(page));
#endif
  }
  auto cap = [&](std::size_t bytes) { available = available == 0 ? bytes : std::min(available, bytes); };
  std::size_t cgroupMax = 0, cgroupCurrent = 0;
  if (readNumber("/sys/fs/cgroup/memory.max", cgroupMax) && readNumber("/sys/fs/cgroup/memory.current", cgroupCurrent))
    cap(cgroupMax > cgroupCurrent ? cgroupMax - cgroupCurrent : 0);
  rlimit limit{};
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    const std::size_t size = procKilobytes("/proc/self/status", "VmSize:");
    cap(std::size_t(limit.rlim_cur) > size ? std::size_t(limit.rlim_cur) - size : 0);
  }
#endif
  return available;
}

std::string formatBytes(std::size_t bytes) {
  const char* units[] = {"bytes", "kB", "MB", "GB", "TB", "PB", "EB"};
  double value = double(bytes);
  int unit = 0;
  while (value >= 1000 && unit < 6) {
    value /= 1000;
    ++unit;
  }
  char text[48];
  if (unit == 0)
    std::snprintf(text, sizeof text, "%zu bytes", bytes);
  else
    std::snprintf(text, sizeof text, "%.3g %s", value, units[unit]);
  return text;
}

void requireMeshMemory(std::size_t vertices, std::size_t triangles, std::size_t limitBytes, const std::string& name) {
  const std::size_t available = availableMemoryBytes();
  std::size_t budget = limitBytes;
  std::string what = "the memory limit";
  if (budget == 0 || (available != 0 && available < budget)) {
    budget = available;
    what = "the memory available";
  }
  if (budget == 0) return;  // unknown: nothing to check against
  const MeshMemoryEstimate e = estimateMeshMemory(vertices, triangles);
  if (e.peakBytes <= budget) return;
  throw InvalidInput(name + ": a mesh of " + std::to_string(vertices) + " vertices and " + std::to_string(triangles) +
                     " triangles needs about " + formatBytes(e.peakBytes) + " while its BVH is built (" +
                     formatBytes(e.meshBytes) + " once built), more than " + what + " (" + formatBytes(budget) +
                     "); refused before allocating it");
}

}  // namespace crux
