#pragma once
/// @file import_command.hpp  The import command of isolated mesh loading for tests and fuzz
/// targets: the `crux` executable built beside them (build/bin/crux), as `crux import-mesh`.

#include <crux/mesh/mesh_io.hpp>

#include <string>
#include <vector>

#include <unistd.h>

namespace crux::test_support {

/// {"<dir of this executable>/crux", "import-mesh"}, or empty when that file is not an
/// executable (CRUX_BUILD_APPS=OFF).
inline std::vector<std::string> cruxImportCommand() {
  char self[4096];
  const ssize_t n = ::readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (n <= 0) return {};
  const std::string path(self, std::size_t(n));
  const std::string crux = path.substr(0, path.rfind('/') + 1) + "crux";
  if (::access(crux.c_str(), X_OK) != 0) return {};
  return {crux, "import-mesh"};
}

/// LoadMeshOptions that import in a `crux import-mesh` child process (importCommand empty when
/// there is no crux executable: callers skip then).
inline LoadMeshOptions isolatedImport() {
  LoadMeshOptions options;
  options.isolation = MeshImportIsolation::Subprocess;
  options.importCommand = cruxImportCommand();
  return options;
}

}  // namespace crux::test_support
