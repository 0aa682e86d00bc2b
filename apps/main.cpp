/// @file main.cpp  The `crux` command line: argument parsing only; the work is in apps/cli/.

#include "cli/batch.hpp"
#include "cli/info.hpp"

#include <crux/config.hpp>
#include <crux/error.hpp>

#include <CLI/CLI.hpp>

#include <iostream>
#include <limits>
#include <string>
#include <vector>

namespace {

std::string versionText() {
  return std::string("crux ") + CRUX_VERSION_STRING + " (crux::Real = " +
         (CRUX_DOUBLE_PRECISION_ENABLED ? "double" : "float") + ")";
}

std::string joinedBackendNames(const char* separator) {
  std::string s;
  for (const auto name : crux::cli::backendNames()) s += (s.empty() ? "" : separator) + std::string(name);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"crux: collision detection queries (see docs/batch.md)", "crux"};
  app.set_version_flag("--version", versionText());
  app.require_subcommand(1);

  CLI::App* batch = app.add_subcommand(
      "batch",
      "Answer JSON Lines queries: one JSON request object per line on standard input, one JSON "
      "answer object per line on standard output, in input order (protocol: docs/batch.md).");
  std::string backend = "native";
  int threads = 1;
  batch
      ->add_option("--backend", backend,
                   "Library that answers the queries: " + joinedBackendNames(", ") +
                       ". Only native is implemented; the others answer every op with "
                       "\"unsupported: <op> on <backend>\".")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& name) {
            return crux::cli::parseBackend(name)
                       ? std::string()
                       : "unknown backend '" + name + "' (expected one of " + joinedBackendNames(", ") + ")";
          },
          joinedBackendNames("|"), "backend"));
  batch
      ->add_option("--threads", threads,
                   "Worker threads, N >= 1. Accepted; requests are currently answered sequentially "
                   "(the output is the same either way).")
      ->capture_default_str()
      ->check(CLI::Range(1, std::numeric_limits<int>::max()));

  CLI::App* info = app.add_subcommand(
      "info",
      "Load mesh files (any format crux::loadMesh reads) and print, per file: triangle and vertex "
      "counts, bounds, degenerate and duplicate triangles, non-manifold and boundary edges, whether "
      "it is closed, load and BVH build times, BVH nodes/leaves/depth and bytes per triangle. A file "
      "that fails to load is reported on stderr, the others are still reported, and the exit status is 1.");
  std::vector<std::string> meshPaths;
  bool infoJson = false;
  info->add_option("meshes", meshPaths, "Mesh files")->required();
  info->add_flag("--json", infoJson, "One JSON object per file and line instead of the text report");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  if (batch->parsed()) {
    std::ios::sync_with_stdio(false);
    std::cin.tie(nullptr);
    crux::cli::BatchOptions options;
    options.backend = *crux::cli::parseBackend(backend);
    options.threads = threads;
    try {
      const int status = crux::cli::runBatch(std::cin, std::cout, options);
      if (status != 0) std::cerr << "crux batch: reading standard input or writing standard output failed\n";
      return status;
    } catch (const crux::InvalidInput& e) {
      std::cerr << "crux batch: " << e.what() << '\n';
      return 2;
    }
  }
  if (info->parsed()) {
    crux::cli::InfoOptions options;
    options.json = infoJson;
    return crux::cli::runInfo(meshPaths, options, std::cout, std::cerr);
  }
  return 0;
}
