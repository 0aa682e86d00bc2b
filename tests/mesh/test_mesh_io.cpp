// Tests of src/mesh/mesh_io.cpp (memory estimate, available memory, the refusal before a build)
// and of the limits loadMesh(path, LoadMeshOptions) enforces (src/mesh/load_mesh.cpp): memory
// refusal on the OFF and assimp paths, the import time limit, in-process vs child-process imports.
// The estimate is checked against the peak RSS measured while a 1M-triangle mesh is built
// (docs/limits.md). Crash inputs of assimp: tests/fuzz/test_fuzz_regressions.cpp.
#include <crux/mesh/mesh_io.hpp>

#include <crux/mesh/bvh.hpp>
#include <crux/error.hpp>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>
#include "support/import_command.hpp"
#include "support/invalid_input.hpp"
#include "support/sanitized.hpp"

namespace crux {
namespace {

namespace fs = std::filesystem;

const fs::path kAssimpModels = "/usr/share/assimp/models";

using test_support::cruxImportCommand;
using test_support::invalidInputMessage;
using test_support::isolatedImport;

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

/// A temporary directory for this test process.
fs::path tempDir() {
  const fs::path dir = fs::temp_directory_path() / ("crux-test-mesh-io-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

fs::path write(const std::string& name, const std::string& text) {
  const fs::path p = tempDir() / name;
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

/// An n×n grid of unit squares in the z = 0 plane as an OFF text: (n+1)² vertices, 2n² triangles.
std::string gridOff(int n) {
  std::ostringstream os;
  os << "OFF\n" << (n + 1) * (n + 1) << " " << 2 * n * n << " 0\n";
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) os << x << " " << y << " 0\n";
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const int a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      os << "3 " << a << " " << b << " " << d << "\n3 " << a << " " << d << " " << c << "\n";
    }
  return os.str();
}

// ---- the estimate -------------------------------------------------------------------------------

TEST(MeshMemoryEstimate, GrowsLinearlyAndBoundsTheBuiltMesh) {
  const MeshMemoryEstimate zero = estimateMeshMemory(0, 0);
  EXPECT_EQ(zero.meshBytes, 0u);
  EXPECT_EQ(zero.peakBytes, 0u);
  const MeshMemoryEstimate a = estimateMeshMemory(1000, 2000), b = estimateMeshMemory(2000, 4000);
  EXPECT_GE(a.peakBytes, a.meshBytes);
  // Linear up to the rounding of the node counts (2T − 1 binary, (2T + 2)/3 wide nodes).
  EXPECT_NEAR(double(b.meshBytes), 2.0 * double(a.meshBytes), double(sizeof(WideBvhNode)) + 1);
  EXPECT_NEAR(double(b.peakBytes), 2.0 * double(a.peakBytes), 2.0 * double(sizeof(WideBvhNode) + sizeof(BvhNode)) + 1);
  // At least the arrays every mesh holds: vertices, two index arrays, primitive indices.
  EXPECT_GE(a.meshBytes, 1000 * sizeof(Vec3) + 2000 * (2 * sizeof(TriangleIndices) + 4));

  // Real meshes of several sizes: memoryBytes() never exceeds the estimate.
  for (const int n : {1, 3, 10, 40}) {
    std::vector<Vec3> vertices;
    std::vector<TriangleIndices> triangles;
    for (int y = 0; y <= n; ++y)
      for (int x = 0; x <= n; ++x) vertices.emplace_back(Real(x), Real(y), Real((x * y) % 3));
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const auto i = std::uint32_t(y * (n + 1) + x), w = std::uint32_t(n + 1);
        triangles.push_back({i, i + 1, i + w + 1});
        triangles.push_back({i, i + w + 1, i + w});
      }
    const Mesh mesh(vertices, triangles);
    const MeshMemoryEstimate e = estimateMeshMemory(mesh.vertexCount(), mesh.triangleCount());
    EXPECT_LE(mesh.memoryBytes(), e.meshBytes) << "n = " << n;
  }
}

TEST(MeshMemoryEstimate, SaturatesInsteadOfOverflowing) {
  const std::size_t huge = std::numeric_limits<std::size_t>::max() / 2;
  const MeshMemoryEstimate e = estimateMeshMemory(huge, huge);
  EXPECT_EQ(e.peakBytes, std::numeric_limits<std::size_t>::max());
  EXPECT_EQ(e.meshBytes, std::numeric_limits<std::size_t>::max());
}

/// Bytes of a "Key: N kB" line of /proc/self/status; 0 when absent.
std::size_t statusBytes(const std::string& key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key, 0) == 0) return std::size_t(std::stoull(line.substr(key.size()))) * 1024;
  return 0;
}

/// Resets the peak RSS (VmHWM) to the current RSS (Linux >= 4.0); false when not permitted.
bool resetPeakRss() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.flush();
  return bool(out);
}

// Builds a 1M-triangle mesh (a 708×708 grid with a bumpy height field) and compares the peak RSS
// increase of the build with the estimate: the estimate must be an upper bound (it is what the
// loader refuses on) and not a wild one (above the peak by no more than its worst-case tree).
TEST(MeshMemoryEstimate, BoundsTheMeasuredPeakOfA1MTriangleBuild) {
  if (CRUX_TEST_SANITIZED) GTEST_SKIP() << "sanitizer allocators (redzones, quarantine) change the footprint";
  const int n = 708;  // 2·708² = 1,002,528 triangles
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  vertices.reserve(std::size_t(n + 1) * (n + 1));
  triangles.reserve(2 * std::size_t(n) * n);
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) vertices.emplace_back(Real(x), Real(y), Real((x * 7 + y * 13) % 5));
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const auto i = std::uint32_t(y * (n + 1) + x), w = std::uint32_t(n + 1);
      triangles.push_back({i, i + 1, i + w + 1});
      triangles.push_back({i, i + w + 1, i + w});
    }
  const std::size_t inputBytes = vertices.size() * sizeof(Vec3) + triangles.size() * sizeof(TriangleIndices);
  const std::size_t nv = vertices.size(), nt = triangles.size();
  if (!resetPeakRss()) GTEST_SKIP() << "/proc/self/clear_refs is not writable: the peak RSS cannot be reset";
  const std::size_t before = statusBytes("VmRSS:");
  // In a two-slot arena the builder takes its parallel path (per-task node arrays, which the
  // estimate counts) on any machine, also on one core, where a serial build peaks lower.
  std::optional<Mesh> built;
  tbb::task_arena(2).execute([&] { built.emplace(std::move(vertices), std::move(triangles)); });
  const Mesh& mesh = *built;
  const std::size_t peak = statusBytes("VmHWM:");
  ASSERT_GT(peak, before);
  // The input arrays were resident before the build and are moved into the mesh: they count.
  const std::size_t measured = peak - before + inputBytes;
  const MeshMemoryEstimate e = estimateMeshMemory(nv, nt);
  std::printf("1M-triangle build: %zu vertices, %zu triangles: measured peak %s (%.1f bytes/triangle), "
              "estimate %s peak / %s built; Mesh::memoryBytes %s\n",
              nv, nt, formatBytes(measured).c_str(), double(measured) / double(nt), formatBytes(e.peakBytes).c_str(),
              formatBytes(e.meshBytes).c_str(), formatBytes(mesh.memoryBytes()).c_str());
  EXPECT_GE(e.peakBytes, measured) << "the estimate is below the measured peak";
  // Nor a wild one: beyond the measured peak it holds only its allowance for the worst-case
  // binary tree (2T − 1 nodes, in each of the two node arrays it counts, where this build made
  // `actual`) and the rounding of the builder's two huge-page mappings (up to 2 MiB each,
  // resident with transparent huge pages, not without them).
  std::vector<Aabb> boxes;
  boxes.reserve(nt);
  for (std::size_t i = 0; i < nt; ++i) boxes.push_back(bounds(mesh.triangle(i)));
  const std::size_t actual = buildBvh(boxes).nodes.size();
  const std::size_t allowance = 2 * (2 * nt - 1 - actual) * sizeof(BvhNode) + 2 * (std::size_t(2) << 20);
  std::printf("binary nodes %zu (%.2f per triangle): worst-case allowance %s\n", actual, double(actual) / double(nt),
              formatBytes(allowance).c_str());
  EXPECT_LE(e.peakBytes, measured + allowance) << "the estimate exceeds the measured peak by more than its allowance";
  EXPECT_LE(mesh.memoryBytes(), e.meshBytes);
}

// ---- available memory and the refusal ----------------------------------------------------------

TEST(AvailableMemory, IsKnownOnLinuxAndBelowPhysicalMemory) {
#if defined(__linux__)
  const std::size_t available = availableMemoryBytes();
  ASSERT_GT(available, 0u) << "no /proc/meminfo MemAvailable?";
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGESIZE);
  EXPECT_LE(available, std::size_t(pages) * std::size_t(page));
#else
  GTEST_SKIP() << "Linux only";
#endif
}

TEST(RequireMeshMemory, RefusesBeyondTheCallerLimitWithCountsAndEstimate) {
  EXPECT_NO_THROW(requireMeshMemory(100, 200, std::size_t(1) << 30, "small"));
  const MeshMemoryEstimate e = estimateMeshMemory(5'000'000, 10'000'000);
  const std::string m =
      invalidInputMessage([&] { requireMeshMemory(5'000'000, 10'000'000, e.peakBytes - 1, "ten-million"); });
  EXPECT_EQ(m.rfind("ten-million: ", 0), 0u) << m;
  EXPECT_TRUE(contains(m, "5000000 vertices and 10000000 triangles")) << m;
  EXPECT_TRUE(contains(m, formatBytes(e.peakBytes))) << m;
  EXPECT_TRUE(contains(m, "refused")) << m;
  EXPECT_NO_THROW(requireMeshMemory(5'000'000, 10'000'000, e.peakBytes, "ten-million")) << "exactly at the limit";
}

TEST(RequireMeshMemory, RefusesMoreThanTheMachineHas) {
  if (availableMemoryBytes() == 0) GTEST_SKIP() << "available memory unknown";
  const std::size_t huge = std::size_t(1) << 40;  // 2^40 triangles: petabytes
  const std::string m = invalidInputMessage([&] { requireMeshMemory(huge, huge, 0, "huge"); });
  EXPECT_TRUE(contains(m, "the memory available")) << m;
}

TEST(FormatBytes, DecimalUnits) {
  EXPECT_EQ(formatBytes(0), "0 bytes");
  EXPECT_EQ(formatBytes(999), "999 bytes");
  EXPECT_EQ(formatBytes(1500), "1.5 kB");
  EXPECT_EQ(formatBytes(2'340'000'000), "2.34 GB");
}

// ---- loadMesh with limits ------------------------------------------------------------------------

TEST(LoadMeshLimits, OffRefusedAfterTheHeaderWhenOverTheLimit) {
  const fs::path p = write("grid30.off", gridOff(30));  // 961 vertices, 1800 triangles
  LoadMeshOptions options;
  EXPECT_EQ(loadMesh(p.string(), options).triangleCount(), 1800u);
  options.memoryLimitBytes = estimateMeshMemory(961, 1800).peakBytes - 1;
  const std::string m = invalidInputMessage([&] { loadMesh(p.string(), options); });
  EXPECT_EQ(m.rfind(p.string() + ": ", 0), 0u) << m;
  EXPECT_TRUE(contains(m, "961 vertices and 1800 triangles")) << m;
  EXPECT_TRUE(contains(m, "the memory limit")) << m;
  options.memoryLimitBytes = estimateMeshMemory(961, 1800).peakBytes;
  EXPECT_EQ(loadMesh(p.string(), options).triangleCount(), 1800u);
}

TEST(LoadMeshLimits, OffHeaderOfAMillionTrianglesRefusedBeforeReadingThem) {
  // The header promises 1M triangles and the lines are there (empty faces would be an error
  // later): the check runs on the counts, before any vertex array is allocated.
  std::string text = "OFF\n3 1000000 0\n0 0 0\n1 0 0\n0 1 0\n";
  text.reserve(text.size() + 1'000'000 * 8);
  for (int i = 0; i < 1'000'000; ++i) text += "3 0 1 2\n";
  const fs::path p = write("ten_million.off", text);
  LoadMeshOptions options;
  options.memoryLimitBytes = 20'000'000;  // 20 MB: a 1M-triangle build needs more than 100 MB
  const std::string m = invalidInputMessage([&] { loadMesh(p.string(), options); });
  EXPECT_TRUE(contains(m, "3 vertices and 1000000 triangles")) << m;
  EXPECT_TRUE(contains(m, "refused")) << m;
  fs::remove(p);
}

TEST(LoadMeshLimits, AssimpImportRefusedInTheParentWhenOverTheLimit) {
  const fs::path obj = kAssimpModels / "OBJ" / "box.obj";
  if (!fs::exists(obj)) GTEST_SKIP() << obj << " is missing (run scripts/setup)";
  if (cruxImportCommand().empty()) GTEST_SKIP() << "no crux executable beside the test (CRUX_BUILD_APPS=OFF)";
  for (const LoadMeshOptions& isolation : {isolatedImport(), LoadMeshOptions{}}) {
    LoadMeshOptions options = isolation;
    const Mesh mesh = loadMesh(obj.string(), options);
    EXPECT_EQ(mesh.triangleCount(), 12u);
    options.memoryLimitBytes = 1000;
    const std::string m = invalidInputMessage([&] { loadMesh(obj.string(), options); });
    EXPECT_TRUE(contains(m, "refused")) << m;
  }
}

TEST(LoadMeshLimits, SubprocessAndInProcessImportsAgree) {
  if (cruxImportCommand().empty()) GTEST_SKIP() << "no crux executable beside the test (CRUX_BUILD_APPS=OFF)";
  for (const char* name : {"OBJ/box.obj", "PLY/cube.ply", "STL/Spider_ascii.stl", "glTF2/Box/glTF/Box.gltf"}) {
    const fs::path p = kAssimpModels / name;
    if (!fs::exists(p)) continue;
    const LoadMeshOptions child = isolatedImport(), inProcess;
    const Mesh a = loadMesh(p.string(), child), b = loadMesh(p.string(), inProcess);
    EXPECT_EQ(a.vertices(), b.vertices()) << name;
    EXPECT_EQ(a.triangles(), b.triangles()) << name;
  }
}

TEST(LoadMeshLimits, ImportTimeLimitStopsTheChild) {
  const fs::path obj = kAssimpModels / "OBJ" / "box.obj";
  if (!fs::exists(obj)) GTEST_SKIP() << obj << " is missing (run scripts/setup)";
  if (cruxImportCommand().empty()) GTEST_SKIP() << "no crux executable beside the test (CRUX_BUILD_APPS=OFF)";
  LoadMeshOptions options = isolatedImport();
  options.timeLimitSeconds = 1e-9;  // expires before the child can answer
  const std::string m = invalidInputMessage([&] { loadMesh(obj.string(), options); });
  EXPECT_EQ(m.rfind(obj.string() + ": ", 0), 0u) << m;
  EXPECT_TRUE(contains(m, "did not finish importing the file within")) << m;
  // The child was reaped: a second load works.
  options.timeLimitSeconds = 0;
  EXPECT_EQ(loadMesh(obj.string(), options).triangleCount(), 12u);
}

TEST(LoadMeshLimits, AssimpErrorsComeBackFromTheChildUnchanged) {
  if (cruxImportCommand().empty()) GTEST_SKIP() << "no crux executable beside the test (CRUX_BUILD_APPS=OFF)";
  const fs::path p = write("garbage.obj", "v 0 0 0\nv 1 0 0\nf 1 2 7\n");
  const std::string a = invalidInputMessage([&] { loadMesh(p.string(), isolatedImport()); });
  const std::string b = invalidInputMessage([&] { loadMesh(p.string()); });
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, b);
}

TEST(LoadMeshLimits, SubprocessNeedsAnImportCommand) {
  const fs::path obj = kAssimpModels / "OBJ" / "box.obj";
  if (!fs::exists(obj)) GTEST_SKIP() << obj << " is missing (run scripts/setup)";
  LoadMeshOptions options;
  options.isolation = MeshImportIsolation::Subprocess;
  std::string m = invalidInputMessage([&] { loadMesh(obj.string(), options); });
  EXPECT_EQ(m.rfind(obj.string() + ": ", 0), 0u) << m;
  EXPECT_TRUE(contains(m, "importCommand is empty")) << m;
  options.importCommand = {"/nonexistent/crux", "import-mesh"};
  m = invalidInputMessage([&] { loadMesh(obj.string(), options); });
  EXPECT_TRUE(contains(m, "cannot start the import command /nonexistent/crux")) << m;
}

// The library starts no process unless asked: the default load of an assimp format runs in
// this process and needs no import command.
TEST(LoadMeshLimits, DefaultLoadRunsAssimpInThisProcess) {
  const fs::path obj = kAssimpModels / "OBJ" / "box.obj";
  if (!fs::exists(obj)) GTEST_SKIP() << obj << " is missing (run scripts/setup)";
  EXPECT_EQ(LoadMeshOptions{}.isolation, MeshImportIsolation::InProcess);
  EXPECT_TRUE(LoadMeshOptions{}.importCommand.empty());
  EXPECT_EQ(loadMesh(obj.string()).triangleCount(), 12u);
}

}  // namespace
}  // namespace crux
