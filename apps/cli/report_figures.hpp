#pragma once
/// @file report_figures.hpp  Internal to `crux report`: the benches' raw JSON (results.json
/// "benches") read into one normalised shape, shared by the views (report_html.cpp) and the
/// verdict and comparison (report_verdict.cpp). Documented for users in docs/report.md.

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace crux::cli::report {

/// How many cases of each crux diff verdict, backend and cause the report shows (and replays on
/// every backend).
constexpr int kFindingsShownPerCause = 2;

/// One engine's time (or memory) on one workload at one size.
struct Entry {
  std::string backend;  ///< crux, embree, fcl, bullet, ... (lower-case first word of the engine name)
  std::string label;    ///< engine [config]
  double seconds = 0;   ///< per query / frame / build (the bench's reported clock); bytes for memory
  std::string agreement;
  double size = 0;           ///< triangles or models (0: one fixed input)
  std::vector<double> runs;  ///< the value of every timed run, when the bench records them (bench_mesh)
};

/// One workload of one bench: entries[0] is the reference (crux).
struct WorkloadFigures {
  std::string bench, key, title, unit, sizeName;
  std::string valueUnit = "seconds";  ///< what Entry::seconds holds: "seconds" or "bytes"
  std::vector<Entry> entries;  ///< at the largest size
  std::vector<Entry> sweep;    ///< every size (scaling benches)
};

/// Every workload of results["benches"], benches in the report's order.
std::vector<WorkloadFigures> figures(const nlohmann::json& results);

/// One headline row: crux's figure on a workload and, per peer, the first engine of that peer
/// the bench lists (Embree robust,medium, the 1-thread rows; docs/report.md "The headline").
struct HeadRow {
  std::string workload;  ///< "<bench>/<key>", as in results.json["workloads"]
  std::string title;     ///< "<bench>: <title>"
  std::string input;     ///< "10000 triangles", "" when unknown
  std::string unit;      ///< per what: query, frame, build, triangle
  std::string valueUnit;
  Entry crux;
  std::vector<std::pair<std::string, Entry>> peers;  ///< (backend, entry)

  /// The peer's entry, or nullptr.
  const Entry* peer(const std::string& backend) const;
};

/// The headline rows, and the peers that appear in them (Embree, Bullet, FCL, libccd first).
std::vector<HeadRow> headRows(const nlohmann::json& results, std::vector<std::string>* peers = nullptr);

/// Whether a bench's agreement verdict says the answers differ ("DISAGREE...", "... differ").
bool answersDiffer(const std::string& agreement);

/// Relative spread (max - min) / median of a run list; NaN with fewer than 2 runs.
double relativeSpread(const std::vector<double>& runs);

// ---- small helpers shared by the views ----

std::string lower(std::string s);
std::string slug(const std::string& s);
std::string str(const nlohmann::json& j, const char* key);
double num(const nlohmann::json& j, const char* key, double fallback = 0);
std::string fmt(const char* format, double v);
/// A duration with its unit (ns, us, ms, s), 3 significant digits.
std::string duration(double seconds);
/// A plotted value in its unit: a duration, or bytes.
std::string valueText(double v, const std::string& valueUnit);
/// Display name of a backend ("embree" -> "Embree", "fcl" -> "FCL").
std::string backendName(const std::string& backend);

}  // namespace crux::cli::report
