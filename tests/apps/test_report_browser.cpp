// The report as a reader sees it: index.html rendered (`crux report --render`) from a small
// real results.json (tests/apps/data/report_results_tiny.json, a `crux report --budget tiny`
// run) and opened in headless Chromium by the report's browser check
// (apps/cli/report_browser.mjs), compared with itself so that every section is drawn. Skips
// only when /usr/bin/chromium is absent.
// ctest: one process (the tests share one rendering and one browser run)

#include "batch_test_util.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include <unistd.h>

namespace {

using Json = nlohmann::json;

using crux::cli::test::readFile;

bool exists(const std::string& path) { return crux::cli::test::fileExists(path); }

class ReportInBrowser : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!exists("/usr/bin/chromium")) return;
    char pattern[] = "/tmp/crux_test_report_browser_XXXXXX";
    const char* dir = mkdtemp(pattern);
    ASSERT_NE(dir, nullptr);
    out_ = dir;
    const std::string fixture = std::string(CRUX_SOURCE_DIR) + "/tests/apps/data/report_results_tiny.json";
    // Compared with itself, so the page has every section.
    const auto [status, text] = crux::cli::test::run(crux::cli::test::cruxExecutable() + " report --render " + fixture +
                                                     " --compare " + fixture + " --out " + out_ + " 2>&1");
    status_ = status;
    output_ = text;
    results_ = Json::parse(readFile(out_ + "/results.json"), nullptr, false);
    browser_ = Json::parse(readFile(out_ + "/raw/browser.json"), nullptr, false);
  }
  static void TearDownTestSuite() {
    if (!out_.empty() && !::testing::UnitTest::GetInstance()->Failed()) std::system(("rm -rf " + out_).c_str());
  }
  void SetUp() override {
    if (!exists("/usr/bin/chromium")) GTEST_SKIP() << "chromium is not installed (scripts/setup installs it)";
    ASSERT_EQ(status_, 0) << output_;
    ASSERT_TRUE(results_.is_object()) << "results.json does not parse";
    ASSERT_TRUE(browser_.is_object()) << "the browser check wrote nothing: " << readFile(out_ + "/raw/browser.log");
  }

  static std::string out_, output_;
  static int status_;
  static Json results_, browser_;
};
std::string ReportInBrowser::out_, ReportInBrowser::output_;
int ReportInBrowser::status_ = -1;
Json ReportInBrowser::results_, ReportInBrowser::browser_;

TEST_F(ReportInBrowser, LoadsWithoutConsoleErrorsScriptsOrNetworkRequests) {
  ASSERT_TRUE(results_.contains("comparison"));
  EXPECT_EQ(browser_["console_errors"], Json::array()) << browser_["console_errors"].dump(1);
  EXPECT_EQ(browser_["external_requests"], Json::array()) << browser_["external_requests"].dump(1);
  EXPECT_EQ(browser_["screen"]["scripts"], 0);
}

TEST_F(ReportInBrowser, ShowsTheVerdictOnTheFirstScreen) {
  const Json& v = browser_["screen"]["verdict"];
  ASSERT_TRUE(v.is_object()) << "no #verdict in the page";
  const std::string text = v["text"].get<std::string>();
  EXPECT_NE(text.find("Is crux right?"), std::string::npos) << text;
  EXPECT_NE(text.find("Where is crux faster?"), std::string::npos) << text;
  EXPECT_NE(text.find("crux-wrong answer"), std::string::npos) << text;
  for (const Json& p : results_["verdict"]["performance"]) EXPECT_NE(text.find(p["name"].get<std::string>()), std::string::npos) << p["name"];
  // On a 1280x800 laptop screen, the verdict ends within the first screen.
  EXPECT_LE(v["y"].get<double>() + v["height"].get<double>(), browser_["viewport"]["height"].get<double>()) << v.dump();
}

TEST_F(ReportInBrowser, DrawsEveryChartOfResultsJsonWithEverySeries) {
  std::set<std::string> charts, series, drawn;
  for (const auto& [id, s] : results_["series"].items()) {
    series.insert(id);
    charts.insert(s["chart"].get<std::string>());
  }
  ASSERT_GE(series.size(), 5u) << "the fixture should have charts";
  const Json& shown = browser_["screen"]["charts"];
  EXPECT_EQ(shown.size(), charts.size());
  for (const Json& c : shown) {
    std::istringstream ids(c["series"].get<std::string>());
    for (std::string id; ids >> id;) drawn.insert(id);
  }
  EXPECT_EQ(drawn, series);
}

TEST_F(ReportInBrowser, NoChartTextReachesBeyondItsChartOnScreenOrInPrint) {
  for (const char* media : {"screen", "print"}) {
    const Json& charts = browser_[media]["charts"];
    ASSERT_FALSE(charts.empty()) << media;
    for (const Json& c : charts) {
      EXPECT_LE(c["title_width"].get<double>(), c["width"].get<double>()) << media << ": " << c["title"];
      EXPECT_EQ(c["title_overflow"].get<double>(), 0) << media << ": " << c["title"];
      EXPECT_EQ(c["texts_overflowing"], Json::array()) << media << ": " << c["series"];
      EXPECT_FALSE(c["better"].get<std::string>().empty()) << media << ": " << c["title"] << " does not say what is better";
    }
    // Nothing wider than the page (no sideways scrolling).
    EXPECT_LE(browser_[media]["document_width"].get<double>(), media == std::string("print") ? 720.0 : 1280.0) << media;
  }
}

TEST_F(ReportInBrowser, WritesTheVerdictScreenshotLinkedFromTheSummary) {
  const std::string png = readFile(out_ + "/verdict.png");
  ASSERT_GT(png.size(), 1000u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  EXPECT_NE(readFile(out_ + "/summary.md").find("(verdict.png)"), std::string::npos);
}

}  // namespace
