// Named regressions: files that crash, abort or hang assimp 5.2 (found by fuzz_load_mesh and by
// mutating assimp's own test models; docs/fuzzing.md, Findings). Through crux::loadMesh they must
// now give an InvalidInput naming the file when assimp runs in a child process
// (MeshImportIsolation::Subprocess with `crux import-mesh`, src/mesh/load_mesh.cpp). The inputs are in
// tests/fuzz/regressions/; the fast ones are also in the load_mesh replay corpus.
#include <crux/error.hpp>
#include <crux/mesh/mesh_io.hpp>

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <functional>
#include <string>
#include "support/import_command.hpp"
#include "support/invalid_input.hpp"

namespace crux {
namespace {

namespace fs = std::filesystem;

const fs::path kRegressions = fs::path(CRUX_SOURCE_DIR) / "tests" / "fuzz" / "regressions";

using test_support::invalidInputMessage;
using test_support::isolatedImport;

/// Loads tests/fuzz/regressions/`name` and expects an InvalidInput that starts with its path
/// and contains `problem`, within `seconds` (+ 5 s of slack for loaded machines).
void expectRefused(const std::string& name, const std::string& problem, double seconds = 10,
                   std::size_t memoryLimit = 0) {
  const fs::path path = kRegressions / name;
  ASSERT_TRUE(fs::exists(path)) << path;
  LoadMeshOptions options = isolatedImport();
  if (options.importCommand.empty()) GTEST_SKIP() << "no crux executable beside the test (CRUX_BUILD_APPS=OFF)";
  options.timeLimitSeconds = seconds;
  options.memoryLimitBytes = memoryLimit;
  const auto start = std::chrono::steady_clock::now();
  const std::string m = invalidInputMessage([&] { loadMesh(path.string(), options); });
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(m.rfind(path.string() + ": ", 0), 0u) << m;
  EXPECT_NE(m.find(problem), std::string::npos) << "expected '" << problem << "' in: " << m;
  EXPECT_LT(took, seconds + 5) << m;
}

// assimp's ASE importer dereferences a face list it never filled (MESH_NUMFACES 12, empty
// lists): SIGSEGV in the importer.
TEST(LoadMeshRegression, AseWithEmptyFaceListCrashedAssimp) {
  expectRefused("assimp-ase-segv-empty-lists.ase", "assimp crashed importing the file");
}

// A PLY face with zero indices reaches TriangulateProcess, whose ai_assert aborts the process.
TEST(LoadMeshRegression, PlyWithAnEmptyFaceAbortedAssimp) {
  expectRefused("assimp-ply-abort-empty-face.ply", "assimp crashed importing the file");
}

// An AC3D object asking for 30 subdivision steps: assimp subdivides for minutes (and GBs).
TEST(LoadMeshRegression, AcWithDeepSubdivisionHungAssimp) {
  expectRefused("assimp-ac-hang-subdiv.ac", "did not finish importing the file within 1 s", 1);
}

// A PLY header declaring 2·10^9 vertices: assimp allocates for them (5.7 GB after 30 s).
// Stopped by the child's memory cap (RLIMIT_AS) or, under sanitizers, by the time limit.
TEST(LoadMeshRegression, PlyDeclaringTwoBillionVerticesExhaustedMemory) {
  const fs::path path = kRegressions / "assimp-ply-huge-vertex-count.ply";
  LoadMeshOptions options = isolatedImport();
  if (options.importCommand.empty()) GTEST_SKIP() << "no crux executable beside the test (CRUX_BUILD_APPS=OFF)";
  options.timeLimitSeconds = 2;
  options.memoryLimitBytes = 512'000'000;
  const std::string m = invalidInputMessage([&] { loadMesh(path.string(), options); });
  EXPECT_EQ(m.rfind(path.string() + ": ", 0), 0u) << m;
}

// The in-process mode is the one that crashes: not exercised here (it would kill the test).
// The subprocess mode must also leave nothing behind: many refused loads in a row work.
TEST(LoadMeshRegression, RepeatedRefusalsLeaveNoChildBehind) {
  for (int i = 0; i < 20; ++i) expectRefused("assimp-ply-abort-empty-face.ply", "assimp crashed");
  errno = 0;
  EXPECT_EQ(::waitpid(-1, nullptr, WNOHANG), -1) << "a child process is left";
  EXPECT_EQ(errno, ECHILD);
}

}  // namespace
}  // namespace crux
