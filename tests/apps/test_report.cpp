// Tests of `crux report` (apps/cli/report.cpp, report_html.cpp): runs the real executable on the
// tiny budget in a temporary directory and checks what it wrote: the three outputs exist and
// parse, results.json holds every workload and backend of the benches that are built, and every
// chart in index.html draws only series (and points) present in results.json.

#include "batch_test_util.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <cctype>
#include <cstdlib>
#include <cstring>
#include <fstream>
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
      {"bench_mesh", {"rays", "sphere_mesh", "box_mesh", "mesh_mesh", "build"}},
      {"bench_scene",
       {"update-pairs", "scene-rays", "aabb-region-queries-bounds-only", "sphere-region-queries-exact-triangles"}},
      {"bench_scaling", {"build", "rays"}},
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
  // Every peer bench_mesh was built with must appear.
  const Json& mesh = results_["benches"]["bench_mesh"];
  if (mesh.value("available", false) && mesh["data"].is_object()) {
    const std::string absent = mesh["data"]["info"].value("peers_absent", "");
    for (const char* peer : {"embree", "fcl", "bullet"}) {
      std::string capitalised = peer;
      capitalised = peer == std::string("fcl") ? "FCL" : std::string(1, char(std::toupper(peer[0]))) + (peer + 1);
      if (absent.find(capitalised) == std::string::npos) EXPECT_EQ(backends.count(peer), 1u) << peer;
    }
  }
}

TEST_F(ReportRun, EveryChartDrawsOnlySeriesAndPointsOfResultsJson) {
  ASSERT_FALSE(results_.is_discarded());
  if (!exists(binDir() + "/bench_mesh") && !exists(binDir() + "/bench_scene") && !exists(binDir() + "/bench_scaling"))
    GTEST_SKIP() << "no bench built (CRUX_BUILD_BENCH=OFF): the report has no charts to check";
  const std::string html = readFile(out_ + "/index.html");
  const Json& series = results_["series"];
  ASSERT_TRUE(series.is_object());
  // Each <svg> names its series.
  const std::regex svg("<svg[^>]*data-series=\"([^\"]*)\"");
  std::size_t charts = 0;
  std::set<std::string> drawn;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), svg); it != std::sregex_iterator(); ++it) {
    ++charts;
    std::istringstream ids(unescapeHtml((*it)[1].str()));
    for (std::string id; ids >> id;) {
      EXPECT_TRUE(series.contains(id)) << "chart series " << id << " is not in results.json";
      drawn.insert(id);
    }
  }
  EXPECT_GE(charts, 3u);
  // Each mark (bar or point) is a point of its series: same x, same y (exact digits).
  const std::regex mark("data-series=\"([^\"]*)\" data-x=\"([^\"]*)\" data-y=\"([^\"]*)\"");
  std::size_t marks = 0;
  for (auto it = std::sregex_iterator(html.begin(), html.end(), mark); it != std::sregex_iterator(); ++it) {
    ++marks;
    const std::string id = unescapeHtml((*it)[1].str()), x = unescapeHtml((*it)[2].str());
    const double y = std::strtod((*it)[3].str().c_str(), nullptr);
    ASSERT_TRUE(series.contains(id)) << id;
    EXPECT_EQ(drawn.count(id), 1u) << "mark of series " << id << " outside a chart naming it";
    bool found = false;
    for (const Json& p : series[id]["points"]) {
      const bool sameX = p["x"].is_string() ? p["x"].get<std::string>() == x
                                            : p["x"].get<double>() == std::strtod(x.c_str(), nullptr);
      found = found || (sameX && p["y"].is_number() && p["y"].get<double>() == y);
    }
    EXPECT_TRUE(found) << "mark (" << x << ", " << y << ") of " << id << " is not a point of results.json";
  }
  EXPECT_GE(marks, 5u);
  // The ratio chart of every bench_mesh workload is drawn.
  for (const auto& [id, s] : series.items())
    if (id.rfind("bench_mesh.", 0) == 0 && s["kind"] == "bar") EXPECT_EQ(drawn.count(id), 1u) << id;
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

}  // namespace
