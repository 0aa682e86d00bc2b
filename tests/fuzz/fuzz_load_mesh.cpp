/// @file fuzz_load_mesh.cpp  libFuzzer target fuzz_load_mesh: arbitrary bytes into
/// crux::loadMesh (crux's OFF reader, assimp for every other format).
///
/// assimp runs in a child process (MeshImportIsolation::Subprocess: the `crux import-mesh`
/// command of the crux executable built beside this one, limited here to 3 s, and
/// outside the sanitizers to loadMesh's 256 MB floor of address-space growth, so that the
/// fuzzer's own -timeout and -rss_limit_mb never fire on assimp's behalf): its crashes and
/// hangs become InvalidInput. The mesh itself is limited to kMeshMemoryLimit
/// (loadMesh's estimated peak, about 40,000 triangles): a few bytes of a procedural format (an
/// NFF cylinder with `tess 8`: 262,220 triangles) otherwise make a mesh whose BVH build takes
/// longer than the fuzzer's 10 s timeout under ASan + coverage, while the refusal above the
/// limit is itself a path worth fuzzing. With CRUX_FUZZ_IN_PROCESS=1 the import runs in
/// the fuzzer's process instead, to hunt for new assimp crashes (docs/fuzzing.md).
///
/// The first byte chooses the file extension (kExtensions), the rest is written to a temporary
/// file of that name and loaded. Checked: no crash, hang or UB; loadMesh either throws
/// crux::InvalidInput (any other exception escapes and is a crash) or returns a mesh whose
/// vertices are finite and whose triangles index existing vertices.

#include "fuzz_input.hpp"
#include "../support/import_command.hpp"

#include <crux/error.hpp>
#include <crux/mesh/mesh_io.hpp>

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace crux::fuzz {

/// Extensions of the formats the seed corpus covers; the index is the input's first byte
/// modulo the count (tests/fuzz/corpus/load_mesh files start with their format's index).
const char* const kExtensions[] = {"off", "obj", "stl", "ply", "gltf", "glb", "dae", "3ds",
                                   "ase", "x",   "ac",  "ms3d", "lwo", "smd", "md2", "nff",
                                   "raw", "fbx", "amf", "3mf", "blend", "irrmesh", "b3d", "q3o"};
constexpr std::size_t kExtensionCount = sizeof kExtensions / sizeof kExtensions[0];
/// loadMesh's memory limit here (LoadMeshOptions::memoryLimitBytes): about 40,000 triangles.
constexpr std::size_t kMeshMemoryLimit = 8'000'000;

namespace {

std::string tempPath(const char* extension) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir && *dir ? dir : "/tmp") + "/crux-fuzz-load-mesh-" + std::to_string(::getpid()) + "." +
         extension;
}

}  // namespace

void run(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return;
  const std::string path = tempPath(kExtensions[data[0] % kExtensionCount]);
  {
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file.write(reinterpret_cast<const char*>(data + 1), std::streamsize(size - 1));
    if (!file) fail("cannot write " + path);
  }
  static const bool inProcess = [] {
    const char* env = std::getenv("CRUX_FUZZ_IN_PROCESS");
    return env && *env && *env != '0';
  }();
  static const std::vector<std::string> importCommand = test_support::cruxImportCommand();
  if (!inProcess && importCommand.empty())
    fail("fuzz_load_mesh imports through the crux executable beside it (build the crux_app target), "
         "or in process with CRUX_FUZZ_IN_PROCESS=1");
  LoadMeshOptions options;
  options.isolation = inProcess ? MeshImportIsolation::InProcess : MeshImportIsolation::Subprocess;
  options.importCommand = importCommand;
  options.timeLimitSeconds = 3;
  options.memoryLimitBytes = kMeshMemoryLimit;
  try {
    const Mesh mesh = loadMesh(path, options);
    const auto& vertices = mesh.vertices();
    for (const Vec3& v : vertices)
      if (!v.allFinite()) fail("loadMesh returned a non-finite vertex from " + path);
    for (const TriangleIndices& t : mesh.triangles())
      for (int i = 0; i < 3; ++i)
        if (t[i] >= vertices.size()) fail("loadMesh returned an out-of-range index from " + path);
  } catch (const InvalidInput&) {
  }
  std::remove(path.c_str());
}

}  // namespace crux::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  crux::fuzz::run(data, size);
  return 0;
}
