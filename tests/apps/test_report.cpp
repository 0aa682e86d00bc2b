// Tests of `crux report` (apps/cli/report.cpp, report_html.cpp): runs the real executable on the
// tiny budget in a temporary directory and checks what it wrote: the three outputs exist and
// parse, results.json holds every workload and backend of the benches that are built, and every
// chart in index.html draws only series (and points) present in results.json.
// ctest: one process (the ReportRun tests share one `crux report` run: tests/CMakeLists.txt)

#include "batch_test_util.hpp"
#include "cli/report.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <cctype>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

using Json = nlohmann::json;

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string binDir() {
  const std::string crux = crux::cli::test::cruxExecutable();
  return crux.substr(0, crux.rfind('/'));
}

bool exists(const std::string& path) { return access(path.c_str(), F_OK) == 0; }

std::string unescapeHtml(std::string s) {
  const std::pair<const char*, const char*> entities[] = {{"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}, {"&amp;", "&"}};
  for (const auto& [from, to] : entities)
    for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + 1)) s.replace(at, std::strlen(from), to);
  return s;
}

/// Checks that every chart of `html` names only series of `series` (results.json["series"]) and
/// that every mark (bar or point) is a point of its series (same x, same y to the last digit).
/// Returns the numbers of charts and marks; `drawn` receives the series the charts name.
std::pair<std::size_t, std::size_t> checkCharts(const std::string& html, const Json& series, std::set<std::string>& drawn) {
  const std::regex svg("<svg[^>]*data-series=\"([^\"]*)\"");
  std::size_t charts = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), svg); it != std::sregex_iterator(); ++it) {
    ++charts;
    std::istringstream ids(unescapeHtml((*it)[1].str()));
    for (std::string id; ids >> id;) {
      EXPECT_TRUE(series.contains(id)) << "chart series " << id << " is not in results.json";
      drawn.insert(id);
    }
  }
  const std::regex mark("data-series=\"([^\"]*)\" data-x=\"([^\"]*)\" data-y=\"([^\"]*)\"");
  std::size_t marks = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), mark); it != std::sregex_iterator(); ++it) {
    ++marks;
    const std::string id = unescapeHtml((*it)[1].str()), x = unescapeHtml((*it)[2].str());
    const double y = std::strtod((*it)[3].str().c_str(), nullptr);
    if (!series.contains(id)) {
      ADD_FAILURE() << "mark of unknown series " << id;
      continue;
    }
    EXPECT_EQ(drawn.count(id), 1u) << "mark of series " << id << " outside a chart naming it";
    bool found = false;
    for (const Json& p : series[id]["points"]) {
      const bool sameX = p["x"].is_string() ? p["x"].get<std::string>() == x
                                            : p["x"].get<double>() == std::strtod(x.c_str(), nullptr);
      found = found || (sameX && p["y"].is_number() && p["y"].get<double>() == y);
    }
    EXPECT_TRUE(found) << "mark (" << x << ", " << std::setprecision(17) << y << ") of " << id
                       << " is not a point of results.json";
  }
  return {charts, marks};
}

/// One `crux report --budget tiny` run shared by the tests of this file.
class ReportRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char pattern[] = "/tmp/crux_test_report_XXXXXX";
    const char* dir = mkdtemp(pattern);
    ASSERT_NE(dir, nullptr);
    out_ = dir;
    const std::string command = crux::cli::test::cruxExecutable() + " report --budget tiny --out " + out_ + " 2> " + out_ +
                                "/progress.txt";
    const int raw = std::system(command.c_str());
    status_ = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    results_ = Json::parse(readFile(out_ + "/results.json"), nullptr, false);
  }
  static void TearDownTestSuite() {
    if (!::testing::UnitTest::GetInstance()->Failed()) std::system(("rm -rf " + out_).c_str());
  }

  static std::string out_;
  static int status_;
  static Json results_;
};
std::string ReportRun::out_;
int ReportRun::status_ = -1;
Json ReportRun::results_;

TEST_F(ReportRun, WritesTheThreeOutputsAndShowsProgress) {
  EXPECT_TRUE(status_ == 0 || status_ == 1) << "exit status " << status_ << "; progress:\n" << readFile(out_ + "/progress.txt");
  ASSERT_FALSE(results_.is_discarded()) << "results.json does not parse";
  EXPECT_TRUE(exists(out_ + "/index.html"));
  EXPECT_TRUE(exists(out_ + "/summary.md"));
  const std::string progress = readFile(out_ + "/progress.txt");
  EXPECT_NE(progress.find("crux report ["), std::string::npos) << progress;
  EXPECT_NE(progress.find("bench_mesh"), std::string::npos) << progress;
  EXPECT_EQ(results_["report"]["budget"], "tiny");
}

TEST_F(ReportRun, DescribesTheMachine) {
  ASSERT_FALSE(results_.is_discarded());
  const Json& m = results_["machine"];
  EXPECT_FALSE(m.value("cpu", "").empty()) << m.dump(1);
  EXPECT_GE(m.value("hardware_threads", 0), 1);
  EXPECT_NE(m.value("compiler", "unknown"), "unknown");
  EXPECT_NE(m.value("build_type", "unknown"), "unknown");
  for (const char* lib : {"libfcl-dev", "libbullet-dev", "libembree-dev", "libcgal-dev", "libeigen3-dev", "libtbb-dev"})
    EXPECT_TRUE(m["libraries"].contains(lib)) << lib;
}

TEST_F(ReportRun, EveryBuiltBenchRanAndHoldsEveryWorkloadAndBackend) {
  ASSERT_FALSE(results_.is_discarded());
  // The workloads each bench measures (bench/*.cpp), keyed as "<bench>/<key>".
  const std::vector<std::pair<std::string, std::vector<std::string>>> expected = {
      {"bench_mesh", {"rays", "rays_any", "segments", "sphere_mesh", "box_mesh", "mesh_mesh", "build", "refit", "memory"}},
      {"bench_scene",
       {"update-pairs", "scene-rays", "aabb-region-queries-bounds-only", "sphere-region-queries-exact-triangles",
        "scene-rays-1-and-n-threads"}},
      {"bench_scaling", {"build", "rays", "refit", "memory"}},
  };
  std::set<std::string> workloads, backends;
  bool anyBench = false;
  for (const Json& w : results_["workloads"]) workloads.insert(w.get<std::string>());
  for (const Json& b : results_["backends"]) backends.insert(b.get<std::string>());
  for (const auto& [bench, keys] : expected) {
    const Json& step = results_["benches"][bench];
    if (!exists(binDir() + "/" + bench)) {
      EXPECT_FALSE(step.value("available", true)) << bench;
      continue;
    }
    anyBench = true;
    ASSERT_TRUE(step.value("available", false)) << bench << ": " << step.dump();
    EXPECT_EQ(step["exit_status"], 0) << bench << "\n" << readFile(out_ + "/raw/" + bench + ".log");
    ASSERT_TRUE(step["data"].is_object()) << bench << " wrote no JSON";
    for (const std::string& key : keys) EXPECT_EQ(workloads.count(bench + "/" + key), 1u) << bench << "/" << key;
  }
  // Builds without benches (CRUX_BUILD_BENCH=OFF, e.g. the sanitizer stage of scripts/test)
  // report every bench as unavailable (checked above) and no timed backend.
  if (anyBench) EXPECT_EQ(backends.count("crux"), 1u);
  // Every peer bench_mesh was built with must appear, in every workload it can run (FCL has no
  // ray or segment query), each with an agreement verdict.
  const Json& mesh = results_["benches"]["bench_mesh"];
  if (mesh.value("available", false) && mesh["data"].is_object()) {
    const std::string absent = mesh["data"]["info"].value("peers_absent", "");
    const std::vector<std::pair<std::string, std::vector<std::string>>> peerWorkloads = {
        {"embree", {"rays", "rays_any", "segments", "build", "refit", "memory"}},
        {"bullet", {"rays", "rays_any", "segments", "sphere_mesh", "box_mesh", "build", "refit", "memory"}},
        {"fcl", {"sphere_mesh", "box_mesh", "mesh_mesh", "build", "refit", "memory"}}};
    for (const auto& [peer, keys] : peerWorkloads) {
      std::string capitalised = peer == "fcl" ? "FCL" : std::string(1, char(std::toupper(peer[0]))) + peer.substr(1);
      if (absent.find(capitalised) != std::string::npos) continue;
      EXPECT_EQ(backends.count(peer), 1u) << peer;
      for (const std::string& key : keys) {
        const Json& ratio = results_["series"]["bench_mesh." + key + ".ratio"];
        bool found = false;
        for (const Json& p : ratio.value("points", Json::array()))
          found = found || (p.value("backend", "") == peer && p["y"].is_number() && p["y"].get<double>() > 0 &&
                            (key == "memory" || !p.value("agreement", "").empty()));
        EXPECT_TRUE(found) << peer << " has no point in bench_mesh." << key << ".ratio: " << ratio.dump();
      }
    }
  }
  // bench_contact (when built): every family's crux rows with their peers (libccd, FCL).
  const Json& contact = results_["benches"]["bench_contact"];
  if (exists(binDir() + "/bench_contact")) {
    ASSERT_TRUE(contact.value("available", false)) << contact.dump();
    EXPECT_EQ(contact["exit_status"], 0) << readFile(out_ + "/raw/bench_contact.log");
    std::size_t contactWorkloads = 0;
    for (const std::string& w : workloads) contactWorkloads += w.rfind("bench_contact/", 0) == 0;
    EXPECT_GE(contactWorkloads, 3u) << "bench_contact workloads missing from results.json";
  }
}

TEST_F(ReportRun, EveryChartDrawsOnlySeriesAndPointsOfResultsJson) {
  ASSERT_FALSE(results_.is_discarded());
  if (!exists(binDir() + "/bench_mesh") && !exists(binDir() + "/bench_scene") && !exists(binDir() + "/bench_scaling"))
    GTEST_SKIP() << "no bench built (CRUX_BUILD_BENCH=OFF): the report has no charts to check";
  const std::string html = readFile(out_ + "/index.html");
  const Json& series = results_["series"];
  ASSERT_TRUE(series.is_object());
  std::set<std::string> drawn;
  const auto [charts, marks] = checkCharts(html, series, drawn);
  EXPECT_GE(charts, 3u);
  EXPECT_GE(marks, 5u);
  // Every ratio chart (every bench, memory included) is drawn, and the memory-vs-size lines.
  for (const auto& [id, s] : series.items())
    if (s["kind"] == "bar" || id.rfind("bench_scaling.memory.scaling.", 0) == 0) EXPECT_EQ(drawn.count(id), 1u) << id;
}

TEST_F(ReportRun, SummaryHoldsTheHeadlineTable) {
  const std::string md = readFile(out_ + "/summary.md");
  EXPECT_NE(md.find("| workload | input | crux |"), std::string::npos) << md;
  if (exists(binDir() + "/bench_mesh")) EXPECT_NE(md.find("bench_mesh: closest-hit rays"), std::string::npos) << md;
  EXPECT_NE(md.find("oracle sanity suite"), std::string::npos);
  EXPECT_NE(md.find("crux diff"), std::string::npos);
}

TEST(ReportCommand, RejectsAnUnknownBudget) {
  const auto [status, out] =
      crux::cli::test::run(crux::cli::test::cruxExecutable() + " report --budget huge --out /tmp/x 2>&1");
  EXPECT_NE(status, 0);
  EXPECT_NE(out.find("huge"), std::string::npos) << out;
}

// ---- the views on hand-made results (no bench needed: also runs where benches are not built) ----

/// bench_contact's printed tables (bench/bench_contact.cpp's format) for one pair family.
const char* kContactText =
    "bench_contact (Release build, Real = float)\n"
    "\n== box-box: 100 separated, 100 overlapping pairs\n"
    "check vs fcl::distance: 0 of 100 differ by > 1e-4 (worst 2.4e-07)\n"
    "check vs libccd EPA depth: 3 of 100 differ by > 1e-4 (worst 0.012), libccd failures 0\n"
    "query                                  ns/query  peer/crux\n"
    "crux distance (separated, GJK)            250.0          -\n"
    "fcl::distance (nearest points)           1000.0       4.00\n"
    "crux depth (overlapping, GJK+EPA)         500.0          -\n"
    "libccd ccdGJKPenetration                 3000.0       6.00\n"
    "libccd ccdMPRPenetration                 1500.0       3.00\n"
    "crux overlaps (GJK boolean)               100.0          -\n"
    "libccd ccdGJKIntersect                    200.0       2.00\n";

Json handMadeResults() {
  Json r;
  r["report"] = {{"date", "2026-01-01T00:00:00Z"}, {"budget", "tiny"}, {"seconds", 1.0}};
  r["machine"] = {{"cpu", "test cpu"}, {"hardware_threads", 2}};
  r["cross_validation"] = {{"sanity", {{"available", false}, {"reason", "hand-made"}}},
                           {"diff", {{"available", false}, {"reason", "hand-made"}}}};
  Json benches = Json::object();
  benches["bench_contact"] = {{"available", true}, {"exit_status", 0}, {"data", nullptr}, {"text", kContactText}};
  benches["bench_mesh"] = {
      {"available", true},
      {"exit_status", 0},
      {"data",
       {{"triangles", 1000},
        {"workloads", Json::array()},
        {"memory",
         {{"crux_bytes", 40000.0},
          {"crux_bytes_per_triangle", 40.0},
          {"embree_robust_medium_bytes_per_triangle", 60.0},
          {"fcl_bytes_per_triangle", 200.0}}}}}};
  Json rows = Json::array();
  for (const double triangles : {1000.0, 10000.0}) {
    rows.push_back({{"workload", "build"}, {"triangles", triangles}, {"engine", "crux"}, {"config", "binned SAH"},
                    {"seconds_per_item", 1e-3 * triangles / 1000}, {"bytes_per_triangle", 40.0 + triangles / 1000},
                    {"agreement", "ref"}});
    rows.push_back({{"workload", "build"}, {"triangles", triangles}, {"engine", "bullet"}, {"config", "bvh"},
                    {"seconds_per_item", 3e-3 * triangles / 1000}, {"bytes_per_triangle", 50.0},
                    {"agreement", "n/a"}});
  }
  benches["bench_scaling"] = {{"available", true}, {"exit_status", 0}, {"data", {{"rows", rows}}}};
  r["benches"] = benches;
  return r;
}

TEST(ReportViews, ContactTablesBecomeWorkloadsWithTheirCheckedAgreement) {
  Json r = handMadeResults();
  const Json series = crux::cli::chartSeries(r);
  // Three crux reference rows in the box-box family: distance, depth, overlaps.
  ASSERT_TRUE(series.contains("bench_contact.box-box-distance.ratio")) << series.dump(1);
  ASSERT_TRUE(series.contains("bench_contact.box-box-depth.ratio")) << series.dump(1);
  ASSERT_TRUE(series.contains("bench_contact.box-box-overlaps.ratio")) << series.dump(1);
  const Json& distance = series["bench_contact.box-box-distance.ratio"]["points"];
  ASSERT_EQ(distance.size(), 1u);
  EXPECT_EQ(distance[0]["backend"], "fcl");
  EXPECT_DOUBLE_EQ(distance[0]["y"].get<double>(), 1000.0 / 250.0);
  EXPECT_EQ(distance[0]["agreement"], "agree");  // "0 of 100 differ"
  const Json& depth = series["bench_contact.box-box-depth.ratio"]["points"];
  ASSERT_EQ(depth.size(), 2u);
  EXPECT_EQ(depth[0]["backend"], "libccd");
  EXPECT_DOUBLE_EQ(depth[0]["y"].get<double>(), 3000.0 / 500.0);
  EXPECT_EQ(depth[0]["agreement"].get<std::string>().rfind("DISAGREE", 0), 0u);  // "3 of 100 differ"
  EXPECT_EQ(depth[1]["agreement"], "not checked");  // the bench checks only GJK+EPA depths
  EXPECT_EQ(series["bench_contact.box-box-overlaps.ratio"]["points"][0]["agreement"], "not checked");
}

TEST(ReportViews, ContactJsonKeysBecomeSeriesIdsWithoutSpaces) {
  // bench_contact --json (docs/bench.md): bench_mesh's workload format, keys with spaces and
  // punctuation, engine names like "fcl::distance (...)".
  Json r = handMadeResults();
  Json engines = Json::array();
  engines.push_back({{"name", "crux distance (separated, GJK)"}, {"config", "float"},
                     {"wall_seconds_per_query_median", 2e-6}, {"agreement", "ref"}});
  engines.push_back({{"name", "fcl::distance (nearest points)"}, {"config", ""},
                     {"wall_seconds_per_query_median", 7e-6}, {"agreement", "DISAGREE"}});
  r["benches"]["bench_contact"] = {
      {"available", true},
      {"exit_status", 0},
      {"data",
       {{"reported_clock", "wall"},
        {"workloads",
         Json::array({{{"key", "box-box: crux distance (separated, GJK)"}, {"title", "box-box: distance"},
                       {"unit", "query"}, {"engines", engines}}})}}}};
  r["series"] = crux::cli::chartSeries(r);
  const std::string id = "bench_contact.box-box-crux-distance-separated-GJK.ratio";
  ASSERT_TRUE(r["series"].contains(id)) << r["series"].dump(1);
  const Json& p = r["series"][id]["points"];
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p[0]["backend"], "fcl");
  EXPECT_DOUBLE_EQ(p[0]["y"].get<double>(), 7e-6 / 2e-6);
  for (const auto& [key, value] : r["series"].items()) EXPECT_EQ(key.find(' '), std::string::npos) << key;
  std::set<std::string> drawn;
  checkCharts(crux::cli::renderHtml(r), r["series"], drawn);
  EXPECT_EQ(drawn.count(id), 1u);
  EXPECT_NE(crux::cli::renderSummary(r).find("3.50x (answers differ)"), std::string::npos);
}

TEST(ReportViews, MemoryPerTriangleIsChartedForEveryBackend) {
  Json r = handMadeResults();
  const Json series = crux::cli::chartSeries(r);
  ASSERT_TRUE(series.contains("bench_mesh.memory.ratio")) << series.dump(1);
  const Json& m = series["bench_mesh.memory.ratio"];
  EXPECT_EQ(m["value_unit"], "bytes");
  std::map<std::string, double> byBackend;
  for (const Json& p : m["points"]) byBackend[p["backend"].get<std::string>()] = p["y"].get<double>();
  EXPECT_DOUBLE_EQ(byBackend["embree"], 60.0 / 40.0);
  EXPECT_DOUBLE_EQ(byBackend["fcl"], 200.0 / 40.0);
  EXPECT_EQ(byBackend.count("crux"), 0u);  // the reference is the 1 line, not a bar
  // bench_scaling's build rows give bytes per triangle against size, one line per engine.
  ASSERT_TRUE(series.contains("bench_scaling.memory.scaling.crux-binned-sah")) << series.dump(1);
  const Json& line = series["bench_scaling.memory.scaling.crux-binned-sah"]["points"];
  ASSERT_EQ(line.size(), 2u);
  EXPECT_DOUBLE_EQ(line[1]["x"].get<double>(), 10000.0);
  EXPECT_DOUBLE_EQ(line[1]["y"].get<double>(), 50.0);
  ASSERT_TRUE(series.contains("bench_scaling.memory.ratio"));
  EXPECT_DOUBLE_EQ(series["bench_scaling.memory.ratio"]["points"][0]["y"].get<double>(), 50.0 / 50.0);
}

TEST(ReportViews, HandMadeChartsReferenceOnlyTheirSeriesAndTheSummaryListsThem) {
  Json r = handMadeResults();
  r["series"] = crux::cli::chartSeries(r);
  const std::string html = crux::cli::renderHtml(r);
  std::set<std::string> drawn;
  const auto [charts, marks] = checkCharts(html, r["series"], drawn);
  EXPECT_GE(charts, 6u);
  EXPECT_GE(marks, 10u);
  for (const auto& [id, s] : r["series"].items()) EXPECT_EQ(drawn.count(id), 1u) << id << " is not drawn";
  const std::string md = crux::cli::renderSummary(r);
  EXPECT_NE(md.find("box-box: distance"), std::string::npos) << md;
  EXPECT_NE(md.find("40 bytes/triangle"), std::string::npos) << md;
  EXPECT_NE(md.find("5.00x"), std::string::npos) << md;  // FCL's memory: 200 / 40
}

}  // namespace
