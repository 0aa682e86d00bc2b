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
  /// Re-render: read this results.json instead of running anything, recompute the series, the
  /// verdict (and the comparison) and write the outputs to outDir.
  std::string renderFrom;
  /// An older results.json: per workload, its ratios beside today's, changes beyond the measured
  /// noise flagged (results.json "comparison").
  std::string compareWith;
  /// A crux diff summary to show instead of running crux diff: `crux diff --json`'s output, or
  /// `crux diff merge`'s for a campaign run in shards (docs/fuzzing.md). Its findings are listed
  /// without replay lines (their case files stay with the campaign).
  std::string diffSummary;
  /// Progress on stderr: a redrawn status line (step, how far, time left). Off when stderr is
  /// not a terminal; every step is logged to outDir/raw/progress.log either way.
  bool progressLine = false;
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

/// The verdict at the top of the report (results.json "verdict"): per peer the workloads where
/// crux is faster and slower, the geometric mean of peer time / crux time and the worst row;
/// crux diff's crux-wrong count and per backend its disagreements by cause; machine and build.
nlohmann::json reportVerdict(const nlohmann::json& results);

/// Per workload, an older report's figures beside today's (crux's time, and each peer's ratio):
/// change, noise (relative spread of the timed runs, old + new) and a flag ("regression",
/// "improvement" or "") when the change exceeds the noise (docs/report.md, "Comparing runs").
nlohmann::json compareResults(const nlohmann::json& older, const nlohmann::json& newer);

/// index.html, self-contained and script-free: the verdict (section#verdict), the comparison
/// when results["comparison"] is present, the cross-validation grid and the disagreements by
/// cause, the table of all workloads, one section per bench with its charts (inline SVG; every
/// <svg class="chart"> carries data-series="id ..." naming its series, every mark
/// data-series/data-x/data-y) and tables, and the machine and libraries.
std::string renderHtml(const nlohmann::json& results);

/// summary.md: the verdict, the comparison's flagged rows and the table of all workloads, for
/// terminals and PRs; links verdict.png when results["browser"]["screenshot"] names one.
std::string renderSummary(const nlohmann::json& results);

/// Runs the report (or re-renders options.renderFrom); the progress line and errors go to
/// `progress`. Returns 0 when every step that is
/// available ran and the outputs were written, 1 when a step failed (the outputs are still
/// written, with the failure recorded), 2 when the output directory cannot be written.
int runReport(const ReportOptions& options, std::ostream& progress);

/// The number of calls to functions whose name contains `callee`, read from a callgrind output
/// file (compressed names: "fn=(id) name" or "cfn=(id) name" defines an id, a later "cfn=(id)"
/// reuses it; the "calls=N ..." line of a call follows its cfn line, after any cob/cfi lines).
/// -1 when the file cannot be read. The report's instructions per ray divide by it.
double callgrindCalls(const std::string& file, const std::string& callee);

}  // namespace crux::cli
