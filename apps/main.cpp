/// @file main.cpp  The `crux` command line: argument parsing only; the work is in apps/cli/.

#include "cli/batch.hpp"
#include "cli/diff.hpp"
#include "cli/info.hpp"
#include "cli/mesh_ops.hpp"
#include "cli/report.hpp"

#include <crux/config.hpp>
#include <crux/error.hpp>

#include <CLI/CLI.hpp>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include <unistd.h>

#ifndef CRUX_DIFF_DEFAULT_MESH_DIR
#define CRUX_DIFF_DEFAULT_MESH_DIR "data/meshes"  // relative to the working directory
#endif

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

/// This executable's path (/proc/self/exe), for the worker processes of `crux batch` and `crux diff`.
std::string selfExecutable() {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  return n > 0 ? std::string(self, std::size_t(n)) : std::string();
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
                       " (a crux::CollisionWorld each). An op the backend cannot answer gets "
                       "\"unsupported: <op> on <backend>\"; a backend not built in exits with status 2.")
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
                   "Worker threads, N >= 1 (oneTBB). Runs of query lines between state changes are "
                   "answered in parallel on native; fcl, bullet and exact answer serially. The output "
                   "is identical for every N.")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& text) {
            char* end = nullptr;
            errno = 0;
            const long n = std::strtol(text.c_str(), &end, 10);
            const bool ok = !text.empty() && *end == '\0' && errno == 0 && n >= 1 && n <= std::numeric_limits<int>::max();
            return ok ? std::string() : "expected a whole number of threads >= 1, got '" + text + "'";
          },
          "N>=1", "threads"));
  double batchTimeout = 30;
  bool batchWorker = false, batchInProcess = false;
  batch
      ->add_option("--timeout", batchTimeout,
                   "Time limit per line, in seconds, of the worker process that answers fcl and bullet: a "
                   "line that takes longer gets \"<backend> failed on <op>: timeout ...\" and the worker is "
                   "restarted")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& text) {
            char* end = nullptr;
            const double seconds = std::strtod(text.c_str(), &end);
            const bool ok = !text.empty() && *end == '\0' && std::isfinite(seconds) && seconds > 0;
            return ok ? std::string() : "expected a finite number of seconds > 0, got '" + text + "'";
          },
          "SECONDS>0", "timeout"));
  batch->add_flag("--in-process", batchInProcess,
                  "Answer fcl and bullet in this process (no worker): faster to start, but a peer library "
                  "that aborts or hangs takes the whole run down");
  batch->add_flag("--worker", batchWorker, "Internal: the worker side of an isolated peer backend")->group("");

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

  // ---- crux diff (the differential fuzzer, docs/diff.md) ----
  CLI::App* diff = app.add_subcommand(
      "diff",
      "Differential fuzzer: generate cases in named families, answer them on every backend through the "
      "batch protocol, classify each answer against the exact backend, shrink and write the "
      "interesting ones, and print an op x backend summary (docs/diff.md). Exit status 1 when a "
      "crux-wrong case was found.");
  crux::cli::DiffOptions diffOptions;
  diffOptions.meshDir = CRUX_DIFF_DEFAULT_MESH_DIR;
  std::string diffFamilies, diffOps, diffBackends;
  diff->add_option("--seed", diffOptions.seed, "Seed of the run (cases derive their seeds from it)")->capture_default_str();
  auto* diffCases = diff->add_option("--cases", diffOptions.cases, "Number of cases")->capture_default_str();
  diff->add_option("--seconds", diffOptions.seconds, "Run for this many seconds instead of --cases")
      ->excludes(diffCases)
      ->check(CLI::PositiveNumber);
  diff->add_option("--families", diffFamilies, "Comma-separated families (default: all)");
  diff->add_option("--ops", diffOps, "Comma-separated query ops (default: all)");
  diff->add_option("--backends", diffBackends, "Comma-separated backends (default: every one built; exact always runs)");
  diff->add_option("--out", diffOptions.outDir, "Write shrunk crux-wrong and peer-wrong cases here (JSON Lines + .json sidecar)");
  diff->add_option("--json", diffOptions.jsonFile, "Write the summary as JSON to this file");
  diff->add_option("--meshes", diffOptions.meshDir, "Directory of the real meshes (bunny00.off, cow.off, ...)")
      ->capture_default_str();
  diff->add_flag("--quiet", diffOptions.quiet, "No text summary");
  diff->add_option("--first-case", diffOptions.firstCase,
                   "Index of the first case: the run answers cases K..K+N-1 (--cases N) of the sequence --seed "
                   "defines, so shards of a campaign are runs of consecutive ranges (docs/diff.md)")
      ->capture_default_str();
  diff->add_option("--shard-dir", diffOptions.shardDir,
                   "Write this run as a campaign shard: DIR/started.json at the start, the shrunk cases to "
                   "DIR/findings, the summary to DIR/summary.json at the end (`crux diff merge` reads them)");
  CLI::App* merge = diff->add_subcommand(
      "merge",
      "Merge the shard directories of a campaign (runs of --first-case/--cases --shard-dir): add the op x "
      "backend tables, join the findings without duplicates, name the shards missing or failed, and print "
      "and write the same summary a serial run gives. Exit 1: crux wrong found; 3: shards missing or failed.");
  std::vector<std::string> mergeDirs;
  std::string mergeJson, mergeOut;
  bool mergeQuiet = false;
  merge->add_option("shards", mergeDirs, "Shard directories")->required();
  merge->add_option("--json", mergeJson, "Write the merged summary as JSON to this file");
  merge->add_option("--out", mergeOut, "Copy the kept findings' files here");
  merge->add_flag("--quiet", mergeQuiet, "No text summary");
  diff->add_option("--peer-timeout", diffOptions.peerTimeoutSeconds,
                   "Time limit per line, in seconds, of the worker processes answering fcl and bullet")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);

  // ---- crux import-mesh (internal: the import command of isolated mesh loading) ----
  CLI::App* importMesh = app.add_subcommand(
      "import-mesh",
      "Internal: import PATH with assimp and write the mesh to standard output in loadMesh's binary "
      "form, within BUDGET bytes of address space (crux's isolated mesh loading starts it; mesh_io.hpp)");
  importMesh->group("");  // not listed in --help
  std::string importBudget, importPath;
  importMesh->add_option("BUDGET", importBudget, "Address-space budget in bytes (0: none)")->required();
  importMesh->add_option("PATH", importPath, "The mesh file")->required();

  // ---- crux report (the main job, docs/report.md) ----
  CLI::App* report = app.add_subcommand(
      "report",
      "The main job: cross-validation (oracle sanity suite, crux diff) and performance against Embree, "
      "FCL and Bullet (bench_mesh, bench_scene, bench_scaling, ...), written to DIR/index.html (SVG "
      "charts), DIR/summary.md and DIR/results.json (docs/report.md). Progress on stderr when it is a terminal.");
  crux::cli::ReportOptions reportOptions;
  bool reportQuick = false, reportFull = false;
  std::string reportBudget;
  report->add_option("--out", reportOptions.outDir, "Output directory")->capture_default_str();
  auto* reportQuickFlag = report->add_flag("--quick", reportQuick, "A few minutes on 2 cores (the default)");
  report->add_flag("--full", reportFull, "The whole sweep: meshes to 1M triangles, scenes to 100k models")
      ->excludes(reportQuickFlag);
  report->add_option("--budget", reportBudget, "tiny|quick|full (tiny: seconds, for tests; overrides --quick/--full)")
      ->check(CLI::IsMember({"tiny", "quick", "full"}));
  report->add_option("--clock", reportOptions.clock,
                     "Clock of the single-threaded benches: wall, cpu, or auto (cpu when the load average "
                     "exceeds half the hardware threads)")
      ->check(CLI::IsMember({"wall", "cpu", "auto"}))
      ->capture_default_str();
  report->add_flag("--callgrind", reportOptions.callgrind,
                   "Also count instructions per ray per backend under valgrind's callgrind");
  report->add_option("--bin-dir", reportOptions.binDir,
                     "Directory of the bench executables and test_sanity (default: next to crux)");
  report->add_option("--render", reportOptions.renderFrom,
                     "Run nothing: re-render DIR's outputs from this results.json (of an earlier run)");
  report->add_option("--diff-summary", reportOptions.diffSummary,
                     "Show this crux diff summary (crux diff --json, or crux diff merge's output for a sharded "
                     "campaign) instead of running crux diff")
      ->check(CLI::ExistingFile);
  report->add_option("--compare", reportOptions.compareWith,
                     "An earlier run's results.json: per workload its figures beside today's, changes beyond "
                     "the measured noise flagged");

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
    options.timeoutSeconds = batchTimeout;
    if (!batchInProcess) options.workerExecutable = selfExecutable();
    try {
      if (batchWorker) return crux::cli::runWorker(std::cin, std::cout, options);
      const int status = crux::cli::runBatch(std::cin, std::cout, options);
      if (status != 0) std::cerr << "crux batch: reading standard input or writing standard output failed\n";
      return status;
    } catch (const std::exception& e) {  // invalid options; a worker that cannot be started
      std::cerr << "crux batch: " << e.what() << '\n';
      return 2;
    }
  }
  if (merge->parsed()) {
    try {
      return crux::cli::runMergeCommand(mergeDirs, mergeJson, mergeOut, mergeQuiet, std::cout);
    } catch (const crux::InvalidInput& e) {
      std::cerr << "crux diff merge: " << e.what() << '\n';
      return 2;
    }
  }
  if (diff->parsed()) {
    auto split = [](const std::string& list) {
      std::vector<std::string> out;
      std::string item;
      for (char ch : list + ",") {
        if (ch == ',') {
          if (!item.empty()) out.push_back(item);
          item.clear();
        } else if (ch != ' ') {
          item += ch;
        }
      }
      return out;
    };
    diffOptions.families = split(diffFamilies);
    diffOptions.ops = split(diffOps);
    diffOptions.backends = split(diffBackends);
    diffOptions.progress = !diffOptions.quiet && isatty(fileno(stderr));
    diffOptions.workerExecutable = selfExecutable();
    try {
      return crux::cli::runDiffCommand(diffOptions, std::cout, std::cerr);
    } catch (const std::exception& e) {  // invalid options; a worker that cannot be started
      std::cerr << "crux diff: " << e.what() << '\n';
      return 2;
    }
  }
  if (report->parsed()) {
    reportOptions.budget = reportFull ? crux::cli::ReportBudget::Full : crux::cli::ReportBudget::Quick;
    if (reportBudget == "tiny") reportOptions.budget = crux::cli::ReportBudget::Tiny;
    if (reportBudget == "full") reportOptions.budget = crux::cli::ReportBudget::Full;
    if (reportBudget == "quick") reportOptions.budget = crux::cli::ReportBudget::Quick;
    reportOptions.progressLine = isatty(fileno(stderr)) && isatty(fileno(stdout));
    return crux::cli::runReport(reportOptions, std::cerr);
  }
  if (importMesh->parsed()) {
    // _exit: no atexit handlers and no leak check of assimp's own leaks (a sanitizer build would
    // turn them into a non-zero status, read by the parent as a failed import).
    const int status = crux::cli::runImportMesh(importBudget, importPath, std::cerr);
    std::fflush(nullptr);
    ::_exit(status);
  }
  if (info->parsed()) {
    crux::cli::InfoOptions options;
    options.json = infoJson;
    options.cruxExecutable = selfExecutable();
    return crux::cli::runInfo(meshPaths, options, std::cout, std::cerr);
  }
  return 0;
}
