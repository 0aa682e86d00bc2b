#pragma once
/// @file report.hpp  `crux report`: the main job. Runs the cross-validation (the oracle sanity
/// suite and `crux diff` when they are built) and the benches (bench_mesh, bench_scene,
/// bench_scaling, and bench_parallel / bench_contact when present) as subprocesses, reads their
/// JSON output, and writes DIR/results.json (every raw figure + the machine description),
/// DIR/summary.md and DIR/index.html (tables and inline SVG charts drawn here, no scripts).
/// Documented for users in docs/report.md.

#include <nlohmann/json.hpp>

#include <iosfwd>
#include <string>
#include <vector>

namespace crux::cli {

/// How much work each step of the report does.
enum class ReportBudget {
  Tiny,   ///< seconds in total: the CI test of the report itself (figures are meaningless)
  Quick,  ///< the README default: a few minutes on 2 cores
  Full,   ///< the whole sweep (meshes up to 1M triangles, scenes up to 100k models)
};

/// Options of one `crux report` run.
struct ReportOptions {
  std::string outDir = "report";
  ReportBudget budget = ReportBudget::Quick;
  /// Also run a fixed small ray workload under valgrind's callgrind and report instruction
  /// counts per backend (noise-free comparison).
  bool callgrind = false;
  /// Clock of the single-threaded benches (bench_mesh, bench_scene): "wall", "cpu" (process CPU
  /// time, which a busy machine inflates much less), or "auto": cpu when the 1-minute load
  /// average exceeds half the hardware threads. bench_scaling (1 and N threads) reports wall time.
  std::string clock = "auto";
  /// Directory holding the bench executables, test_sanity and crux itself; empty: the
  /// directory of the running executable.
  std::string binDir;
};

/// Name of a budget ("tiny", "quick", "full").
const char* budgetName(ReportBudget budget);

/// One chart: the ids of the series it draws (keys of results.json["series"]).
struct ChartRef {
  std::string id;
  std::vector<std::string> series;
};

/// Builds results.json["series"] (every plotted figure, keyed by series id) from the raw
/// results (results["benches"]); pure, so tests and the HTML writer share it.
nlohmann::json chartSeries(const nlohmann::json& results);

/// index.html: machine, cross-validation, headline table, one section per bench with its
/// charts (inline SVG; every <svg> carries data-series="id ..." naming its series and every
/// mark data-series/data-x/data-y) and tables.
std::string renderHtml(const nlohmann::json& results);

/// summary.md: the headline table and the cross-validation verdicts, for terminals and PRs.
std::string renderSummary(const nlohmann::json& results);

/// Runs the report; progress lines go to `progress`. Returns 0 when every step that is
/// available ran and the outputs were written, 1 when a step failed (the outputs are still
/// written, with the failure recorded), 2 when the output directory cannot be written.
int runReport(const ReportOptions& options, std::ostream& progress);

}  // namespace crux::cli
