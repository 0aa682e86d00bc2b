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
#include <cstdio>
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

using crux::cli::test::readFile;

std::string binDir() {
  const std::string crux = crux::cli::test::cruxExecutable();
  return crux.substr(0, crux.rfind('/'));
}

bool exists(const std::string& path) { return crux::cli::test::fileExists(path); }

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

TEST_F(ReportRun, WritesTheThreeOutputsAndStaysQuietOffATerminal) {
  EXPECT_TRUE(status_ == 0 || status_ == 1) << "exit status " << status_ << "; progress:\n" << readFile(out_ + "/raw/progress.log");
  ASSERT_FALSE(results_.is_discarded()) << "results.json does not parse";
  EXPECT_TRUE(exists(out_ + "/index.html"));
  EXPECT_TRUE(exists(out_ + "/summary.md"));
  // stderr is a file here: no progress line on it, every step in raw/progress.log.
  EXPECT_EQ(readFile(out_ + "/progress.txt"), "");
  const std::string progress = readFile(out_ + "/raw/progress.log");
  EXPECT_NE(progress.find("crux report ["), std::string::npos) << progress;
  EXPECT_NE(progress.find("bench_mesh"), std::string::npos) << progress;
  EXPECT_EQ(results_["report"]["budget"], "tiny");
}

TEST_F(ReportRun, ScreenshotsTheVerdictWhenChromiumIsInstalled) {
  ASSERT_FALSE(results_.is_discarded());
  const Json& browser = results_["browser"];
  if (!exists("/usr/bin/chromium")) {
    EXPECT_FALSE(browser.value("available", true)) << browser.dump();
    GTEST_SKIP() << "chromium is not installed (scripts/setup installs it)";
  }
  ASSERT_TRUE(browser.value("available", false)) << browser.dump();
  EXPECT_EQ(browser["exit_status"], 0) << readFile(out_ + "/raw/browser.log");
  EXPECT_EQ(browser.value("screenshot", ""), "verdict.png");
  EXPECT_GT(readFile(out_ + "/verdict.png").size(), 1000u);
  EXPECT_NE(readFile(out_ + "/summary.md").find("](verdict.png)"), std::string::npos);
  ASSERT_TRUE(browser["data"].is_object());
  EXPECT_EQ(browser["data"]["console_errors"], Json::array()) << browser["data"]["console_errors"].dump(1);
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

TEST_F(ReportRun, VerdictComesFirstAndCountsWhatTheRunMeasured) {
  ASSERT_FALSE(results_.is_discarded());
  const Json& v = results_["verdict"];
  ASSERT_TRUE(v.is_object());
  EXPECT_EQ(v["correctness"]["crux_wrong"], results_["cross_validation"]["diff"].value("data", Json::object()).value("crux_wrong", 0));
  for (const Json& p : v["performance"])
    EXPECT_EQ(p["crux_faster"].get<int>() + p["crux_slower"].get<int>(), p["workloads"].get<int>()) << p.dump();
  const std::string html = readFile(out_ + "/index.html");
  const auto verdict = html.find("<section id=\"verdict\">"), cross = html.find("<section id=\"cross-validation\">");
  ASSERT_NE(verdict, std::string::npos);
  ASSERT_NE(cross, std::string::npos);
  EXPECT_LT(verdict, cross);
  EXPECT_LT(verdict, html.find("<svg"));
}

TEST_F(ReportRun, SummaryHoldsTheHeadlineTable) {
  const std::string md = readFile(out_ + "/summary.md");
  EXPECT_NE(md.find("| workload | input | crux |"), std::string::npos) << md;
  if (exists(binDir() + "/bench_mesh")) EXPECT_NE(md.find("bench_mesh: closest-hit rays"), std::string::npos) << md;
  EXPECT_NE(md.find("oracle sanity suite"), std::string::npos);
  EXPECT_NE(md.find("crux diff"), std::string::npos);
}

// A campaign's (or any earlier run's) crux diff summary stands in for a fresh crux diff run:
// the report reads it, counts its cases and crux-wrong answers in the verdict, and names it.
// No bench is run here (an empty --bin-dir): only the cross-validation part matters.
TEST(ReportCommand, ShowsAnExistingDiffSummaryInsteadOfRunningCruxDiff) {
  char pattern[] = "/tmp/crux_test_report_summary_XXXXXX";
  const char* dir = mkdtemp(pattern);
  ASSERT_NE(dir, nullptr);
  const std::string tmp = dir, summary = tmp + "/summary.json", empty = tmp + "/bin";
  ASSERT_EQ(std::system(("mkdir -p " + empty).c_str()), 0);
  const std::string crux = crux::cli::test::cruxExecutable();
  const auto diff = crux::cli::test::run(crux + " diff --seed 5 --cases 40 --backends native --quiet --json " +
                                         summary + " 2>&1");
  ASSERT_TRUE(exists(summary)) << diff.second;
  const Json expected = Json::parse(readFile(summary));
  ASSERT_GT(expected.value("cases", 0), 0);
  const auto [status, out] = crux::cli::test::run(crux + " report --budget tiny --bin-dir " + empty + " --out " + tmp +
                                                  "/report --diff-summary " + summary + " 2>&1");
  EXPECT_TRUE(status == 0 || status == 1) << out;
  const Json results = Json::parse(readFile(tmp + "/report/results.json"), nullptr, false);
  ASSERT_FALSE(results.is_discarded()) << out;
  const Json& step = results["cross_validation"]["diff"];
  ASSERT_TRUE(step.value("available", false)) << step.dump();
  EXPECT_EQ(step["summary"], summary);
  EXPECT_EQ(step["data"]["cases"], expected["cases"]);
  EXPECT_EQ(results["verdict"]["correctness"]["diff_cases"], expected["cases"]);
  EXPECT_EQ(results["verdict"]["correctness"]["crux_wrong"], expected.value("crux_wrong", 0));
  EXPECT_FALSE(exists(tmp + "/report/raw/diff.log")) << "crux diff ran";

  // A file that is not a diff summary: the section is "not available", naming the file.
  const std::string bogus = tmp + "/bogus.json";
  ASSERT_EQ(std::system(("echo '{\"cases\": 3}' > " + bogus).c_str()), 0);
  crux::cli::test::run(crux + " report --budget tiny --bin-dir " + empty + " --out " + tmp + "/report2 --diff-summary " +
                       bogus + " 2>&1");
  const Json second = Json::parse(readFile(tmp + "/report2/results.json"), nullptr, false);
  ASSERT_FALSE(second.is_discarded());
  EXPECT_FALSE(second["cross_validation"]["diff"].value("available", true));
  EXPECT_NE(second["cross_validation"]["diff"].value("reason", "").find(bogus), std::string::npos);
  // A missing file is refused on the command line.
  const auto missing = crux::cli::test::run(crux + " report --budget tiny --out " + tmp + "/report3 --diff-summary " + tmp +
                                            "/absent.json 2>&1");
  EXPECT_NE(missing.first, 0);
  EXPECT_NE(missing.second.find("absent.json"), std::string::npos) << missing.second;
  if (!::testing::Test::HasFailure()) std::system(("rm -rf " + tmp).c_str());
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

/// bench_mesh's workload format with one peer: `runs` per engine, crux first.
Json meshWorkload(const std::string& key, double crux, double peer, const std::string& peerName,
                  const std::vector<double>& cruxRuns = {}, const std::vector<double>& peerRuns = {},
                  const std::string& agreement = "agree") {
  Json engines = Json::array();
  engines.push_back({{"name", "crux"}, {"config", ""}, {"wall_seconds_per_query_median", crux},
                     {"wall_seconds_per_query_runs", cruxRuns}, {"agreement", "ref"}});
  engines.push_back({{"name", peerName}, {"config", ""}, {"wall_seconds_per_query_median", peer},
                     {"wall_seconds_per_query_runs", peerRuns}, {"agreement", agreement}});
  return {{"key", key}, {"title", key + " queries"}, {"unit", "query"}, {"engines", engines}};
}

Json withMeshWorkloads(Json r, const Json& workloads) {
  r["benches"]["bench_mesh"]["data"]["workloads"] = workloads;
  r["benches"]["bench_mesh"]["data"]["reported_clock"] = "wall";
  return r;
}

TEST(ReportVerdict, CountsWinsAndLossesWithTheGeometricMeanAndTheWorstRowPerPeer) {
  // Embree: 4x slower than crux on a, 2x faster on b, 2x slower on c; a disagreeing row is not timed.
  const Json r = withMeshWorkloads(handMadeResults(), Json::array({meshWorkload("a", 1e-6, 4e-6, "Embree"),
                                                                   meshWorkload("b", 1e-6, 0.5e-6, "Embree"),
                                                                   meshWorkload("c", 1e-6, 2e-6, "Embree"),
                                                                   meshWorkload("d", 1e-6, 9e-6, "Embree", {}, {}, "DISAGREE")}));
  const Json v = crux::cli::reportVerdict(r);
  const Json* embree = nullptr;
  for (const Json& p : v["performance"])
    if (p["peer"] == "embree") embree = &p;
  ASSERT_NE(embree, nullptr) << v.dump(1);
  EXPECT_EQ((*embree)["workloads"], 3);
  EXPECT_EQ((*embree)["crux_faster"], 2);
  EXPECT_EQ((*embree)["crux_slower"], 1);
  EXPECT_EQ((*embree)["answers_differ"], 1);
  EXPECT_NEAR((*embree)["geomean"].get<double>(), std::cbrt(4.0 * 0.5 * 2.0), 1e-12);
  EXPECT_EQ((*embree)["worst"]["workload"], "bench_mesh/b");
  EXPECT_DOUBLE_EQ((*embree)["worst"]["ratio"].get<double>(), 0.5);
  // bench_mesh's memory row (Embree 1.5x crux's bytes) is not a timed workload: 3, not 4.
  const std::string md = crux::cli::renderSummary(r);
  EXPECT_NE(md.find("| Embree | 2 of 3 | 1 of 3 | 1.59x | bench_mesh: b queries, 1000 triangles: 0.50x (1 more with different answers, not counted) |"), std::string::npos)
      << md;
}

Json diffData() {
  Json table = {{"ray_triangle", {{"native", {{"agree", 90}, {"within_tolerance", 2}}},
                                  {"bullet", {{"agree", 80}, {"peer_wrong", 12}}},
                                  {"fcl", {{"unsupported", 92}}}}},
                {"distance", {{"native", {{"agree", 40}}}, {"fcl", {{"agree", 30}, {"peer_wrong", 7}, {"error", 3}}}}}};
  Json finding = {{"name", "fcl.sphere-local-point.distance.1-7"}, {"family", "general"}, {"seed", 1}, {"index", 7},
                  {"op", "distance"}, {"backend", "fcl"}, {"verdict", "peer_wrong"}, {"cause", "sphere-local-point"},
                  {"exact_grid", false},
                  {"lines", Json::array({R"({"id":"q","op":"distance","a":{"sphere":{"center":[1,2,3],"radius":1}},"b":{"sphere":{"center":[5,2,3],"radius":1}}})"})},
                  {"answers", {{"exact", {{"id", "q"}, {"distance", 2.0}, {"point_a", {2.0, 2.0, 3.0}}}},
                               {"fcl", {{"id", "q"}, {"distance", 2.0}, {"point_a", {1.0, 0.0, 0.0}}}}}}};
  return {{"cases", 92}, {"crux_wrong", 0}, {"table", table},
          {"peer_causes", {{"bullet", {{"margin", 9}, {"touching", 3}}}, {"fcl", {{"sphere-local-point", 7}}}}},
          {"within_tolerance_causes", {{"native", {{"boundary", 2}}}}}, {"findings", Json::array({finding})}};
}

TEST(ReportVerdict, PutsTheCruxWrongCountFirstAndPeerDisagreementsByCause) {
  Json r = handMadeResults();
  r["cross_validation"]["diff"] = {{"available", true}, {"exit_status", 0}, {"command", "crux diff"}, {"data", diffData()}};
  const Json c = crux::cli::reportVerdict(r)["correctness"];
  EXPECT_EQ(c["crux_wrong"], 0);
  EXPECT_EQ(c["diff_cases"], 92);
  EXPECT_EQ(c["backends"]["bullet"]["peer_wrong"], 12);
  EXPECT_EQ(c["backends"]["fcl"]["error"], 3);
  EXPECT_EQ(c["backends"]["fcl"]["peer_wrong_causes"]["sphere-local-point"], 7);
  const std::string md = crux::cli::renderSummary(r);
  EXPECT_NE(md.find("**0 crux-wrong answers** in 92 generated crux diff cases"), std::string::npos) << md;
  EXPECT_NE(md.find("- Bullet: 12 wrong (margin 9, touching 3), 0 within tolerance, 0 errors, of 92 answers compared"), std::string::npos) << md;
  const std::string html = crux::cli::renderHtml(r);
  // The grid: one row per op, a cell per backend with its counts spelled out.
  EXPECT_NE(html.find("<table class=\"grid\">"), std::string::npos);
  EXPECT_NE(html.find("12 peer wrong &middot; 80 agree"), std::string::npos);
  EXPECT_NE(html.find("7 peer wrong &middot; 3 error &middot; 30 agree"), std::string::npos);
  // The finding: vectors as [x, y, z], a copyable crux batch line, the corpus linked.
  EXPECT_NE(html.find("point_a: [1, 0, 0]"), std::string::npos);
  EXPECT_NE(html.find("point_a: [2, 2, 3]"), std::string::npos);
  EXPECT_NE(html.find("| crux batch --backend fcl</pre>"), std::string::npos);
  EXPECT_NE(html.find("oracle/known-peer-disagreements/"), std::string::npos);
  EXPECT_EQ(html.find("<table><tr><th></th>"), std::string::npos) << "a raw JSON table is back";
}

TEST(ReportVerdict, ACruxWrongFindingTurnsTheVerdictRedAndIsListedFirst) {
  Json r = handMadeResults();
  Json data = diffData();
  data["crux_wrong"] = 1;
  data["table"]["distance"]["native"] = {{"agree", 39}, {"crux_wrong", 1}};
  Json wrong = data["findings"][0];
  wrong["name"] = "native.crux-wrong.distance.1-9";
  wrong["backend"] = "native";
  wrong["verdict"] = "crux_wrong";
  wrong["cause"] = "beyond-tolerance";
  data["findings"].push_back(wrong);  // after the peer finding in the file
  r["cross_validation"]["diff"] = {{"available", true}, {"exit_status", 1}, {"command", "crux diff"}, {"data", data}};
  const std::string html = crux::cli::renderHtml(r);
  EXPECT_NE(html.find("<div class=\"card bad\"><h2>Is crux right?</h2>"), std::string::npos);
  EXPECT_NE(html.find(">1 crux-wrong answer<"), std::string::npos);
  const auto cruxWrong = html.find("<h4>CRUX WRONG"), peer = html.find("<h4>FCL");
  ASSERT_NE(cruxWrong, std::string::npos);
  ASSERT_NE(peer, std::string::npos);
  EXPECT_LT(cruxWrong, peer);
  EXPECT_NE(html.find("| crux batch --backend native</pre>"), std::string::npos);
}

TEST(ReportViews, ScalingSeriesCarryTheirLogLogSlope) {
  const Json series = crux::cli::chartSeries(handMadeResults());
  // crux's build time grows 10x from 1k to 10k triangles, Bullet's too: slope 1.
  ASSERT_TRUE(series.contains("bench_scaling.build.scaling.crux-binned-sah")) << series.dump(1);
  EXPECT_NEAR(series["bench_scaling.build.scaling.crux-binned-sah"]["slope"].get<double>(), 1.0, 1e-12);
  // Bullet's bytes per triangle are flat: slope 0.
  EXPECT_NEAR(series["bench_scaling.memory.scaling.bullet-bvh"]["slope"].get<double>(), 0.0, 1e-12);
  Json r = handMadeResults();
  r["series"] = series;
  EXPECT_NE(crux::cli::renderHtml(r).find("crux [binned SAH] (slope 1.00)"), std::string::npos);
}

TEST(ReportViews, LongChartTitlesWrapIntoLinesNarrowerThanTheChart) {
  Json r = handMadeResults();
  r["benches"]["bench_mesh"]["data"]["workloads"] = Json::array(
      {meshWorkload("long", 1e-6, 2e-6, "Embree")});
  r["benches"]["bench_mesh"]["data"]["workloads"][0]["title"] =
      "a workload title long enough to run well past the right edge of any chart that draws it on one line, twice over";
  r["series"] = crux::cli::chartSeries(r);
  const std::string html = crux::cli::renderHtml(r);
  const std::regex svg("<svg[^>]*viewBox=\"0 0 ([0-9.]+) [0-9.]+\"[^>]*data-series=\"bench_mesh.long.ratio\"");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(html, m, svg));
  const double width = std::stod(m[1].str());
  const auto at = html.find("data-series=\"bench_mesh.long.ratio\"");
  const std::regex title("<text class=\"title\"[^>]*>([^<]*)</text>");
  std::size_t lines = 0;
  const std::string chart = html.substr(at, html.find("</svg>", at) - at);
  for (auto it = std::sregex_iterator(chart.begin(), chart.end(), title); it != std::sregex_iterator(); ++it) {
    ++lines;
    // 0.66 em per character at 12.5 px: the renderer's estimate for bold text.
    EXPECT_LT(double((*it)[1].str().size()) * 12.5 * 0.66, width - 20) << (*it)[1].str();
  }
  EXPECT_GE(lines, 2u);
  EXPECT_NE(chart.find("class=\"better\""), std::string::npos) << "the chart does not say what is better";
}

TEST(ReportCompare, FlagsOnlyChangesBeyondTheNoiseTheRunsMeasured) {
  // Old: Embree/crux 4.0 on a, 2.0 on b, crux's runs spread 2 %, Embree's 2 %: noise 4 % per run.
  const Json older = withMeshWorkloads(handMadeResults(), Json::array({meshWorkload("a", 1e-6, 4e-6, "Embree", {0.99e-6, 1e-6, 1.01e-6}, {3.96e-6, 4e-6, 4.04e-6}),
                                                                      meshWorkload("b", 1e-6, 2e-6, "Embree", {0.99e-6, 1e-6, 1.01e-6}, {1.98e-6, 2e-6, 2.02e-6}),
                                                                      meshWorkload("c", 1e-6, 2e-6, "Embree")}));
  // New: a's ratio falls to 3.0 (-25 %, beyond 8 %), b's to 1.9 (-5 %, within), c unmeasured.
  const Json newer = withMeshWorkloads(handMadeResults(), Json::array({meshWorkload("a", 1e-6, 3e-6, "Embree", {0.99e-6, 1e-6, 1.01e-6}, {2.97e-6, 3e-6, 3.03e-6}),
                                                                      meshWorkload("b", 1e-6, 1.9e-6, "Embree", {0.99e-6, 1e-6, 1.01e-6}, {1.881e-6, 1.9e-6, 1.919e-6}),
                                                                      meshWorkload("c", 1e-6, 1e-6, "Embree")}));
  const Json c = crux::cli::compareResults(older, newer);
  std::map<std::string, Json> byRow;
  for (const Json& row : c["rows"]) byRow[row["workload"].get<std::string>() + " " + row["peer"].get<std::string>()] = row;
  ASSERT_EQ(byRow.count("bench_mesh/a embree"), 1u) << c.dump(1);
  EXPECT_EQ(byRow["bench_mesh/a embree"]["flag"], "regression");
  EXPECT_NEAR(byRow["bench_mesh/a embree"]["change"].get<double>(), -0.25, 1e-12);
  EXPECT_NEAR(byRow["bench_mesh/a embree"]["noise"].get<double>(), 0.08, 1e-9);
  EXPECT_EQ(byRow["bench_mesh/b embree"]["flag"], "");
  EXPECT_EQ(byRow["bench_mesh/a crux"]["flag"], "");  // crux's own time did not move
  // c has no runs: it takes the median measured noise of its report, marked as estimated.
  EXPECT_FALSE(byRow["bench_mesh/c embree"]["noise_measured"].get<bool>());
  EXPECT_EQ(byRow["bench_mesh/c embree"]["flag"], "regression");  // -50 % beyond the estimated 8 %
  EXPECT_EQ(c["regressions"], 2);
  Json r = newer;
  r["comparison"] = c;
  EXPECT_NE(crux::cli::renderSummary(r).find("- **regression**: bench_mesh: a queries, Embree / crux: 4.00x -> 3.00x (-25.0%, noise 8.0%)"),
            std::string::npos)
      << crux::cli::renderSummary(r);
  EXPECT_NE(crux::cli::renderHtml(r).find("<section id=\"comparison\">"), std::string::npos);
}

TEST(ReportCommand, RendersAnEarlierResultsJsonAndComparesWithIt) {
  char pattern[] = "/tmp/crux_test_report_render_XXXXXX";
  const char* dir = mkdtemp(pattern);
  ASSERT_NE(dir, nullptr);
  const std::string out = dir;
  Json r = withMeshWorkloads(handMadeResults(), Json::array({meshWorkload("a", 1e-6, 4e-6, "Embree")}));
  {
    std::ofstream(out + "/old.json") << r.dump();
  }
  const auto [status, text] = crux::cli::test::run(crux::cli::test::cruxExecutable() + " report --render " + out +
                                                   "/old.json --compare " + out + "/old.json --out " + out + "/new 2>&1");
  EXPECT_EQ(status, 0) << text;
  const Json rendered = Json::parse(readFile(out + "/new/results.json"), nullptr, false);
  ASSERT_TRUE(rendered.is_object());
  EXPECT_TRUE(rendered["series"].contains("bench_mesh.a.ratio"));
  EXPECT_EQ(rendered["comparison"]["regressions"], 0);
  EXPECT_NE(readFile(out + "/new/index.html").find("<section id=\"verdict\">"), std::string::npos);
  const auto [bad, message] = crux::cli::test::run(crux::cli::test::cruxExecutable() + " report --render " + out +
                                                   "/absent.json --out " + out + "/new 2>&1");
  EXPECT_EQ(bad, 2);
  EXPECT_NE(message.find("absent.json"), std::string::npos) << message;
  std::system(("rm -rf " + out).c_str());
}

TEST(ReportCallgrind, CountsTheCallsOfTheNamedFunctionAcrossCompressedNames) {
  // A callgrind file as valgrind writes it: a name given once with its id, later calls by id
  // alone, a cfi line between a cfn line and its calls line, and another callee's calls.
  const std::string file = "/tmp/crux_test_callgrind." + std::to_string(::getpid()) + ".out";
  {
    std::ofstream out(file);
    out << "events: Ir\n"
        << "fn=(1) cruxRays(crux::Mesh const&)\n"
        << "0 100\n"
        << "cfn=(2) crux::raycastClosest(crux::Mesh const&, crux::Ray const&)\n"
        << "calls=2000 0\n"
        << "0 5000\n"
        << "cfn=(3) crux::other()\n"
        << "calls=7 0\n"
        << "0 70\n"
        << "fn=(4) lambda\n"
        << "cfi=(5) mesh_query.cpp\n"
        << "cfn=(2)\n"
        << "calls=3000 0\n"
        << "0 6000\n"
        << "summary: 11170\n";
  }
  EXPECT_EQ(crux::cli::callgrindCalls(file, "crux::raycastClosest("), 5000);
  EXPECT_EQ(crux::cli::callgrindCalls(file, "crux::other("), 7);
  EXPECT_EQ(crux::cli::callgrindCalls(file, "rtcIntersect1"), 0);
  EXPECT_EQ(crux::cli::callgrindCalls(file + ".absent", "crux::raycastClosest("), -1);
  std::remove(file.c_str());
}

}  // namespace
