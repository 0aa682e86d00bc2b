// Replays every crux-wrong case `crux diff` found (tests/regressions/*.jsonl, README there) through
// the native and exact backends: the exact answer must still be the recorded one, and native must
// equal it — except for cases whose sidecar says "status": "open" (a known, reported, unfixed
// bug), which must still disagree (so a fix is noticed and the case flipped to "fixed").

#include "cli/diff.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <fstream>
#include <string>
#include <vector>

namespace crux::cli {
namespace {

namespace fs = std::filesystem;

struct Replay {
  std::vector<std::string> lines;
  Answer native, exact;
};

Answer lastAnswer(const std::vector<std::string>& lines, Backend backend) {
  BatchOptions options;
  options.backend = backend;
  BatchState state(options);
  Answer last;
  for (const auto& line : lines) last = answerLine(line, state);
  last.erase("id");
  return last;
}

std::vector<fs::path> regressionCases() {
  std::vector<fs::path> out;
  for (const auto& entry : fs::directory_iterator(fs::path(CRUX_SOURCE_DIR) / "tests" / "regressions"))
    if (entry.path().extension() == ".jsonl") out.push_back(entry.path());
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Regressions, NativeEqualsExactOnEveryRecordedCase) {
  const auto cases = regressionCases();
  int fixed = 0, open = 0, skipped = 0;
  for (const auto& path : cases) {
    std::vector<std::string> lines;
    std::ifstream in(path);
    for (std::string line; std::getline(in, line);)
      if (!line.empty()) lines.push_back(line);
    ASSERT_FALSE(lines.empty()) << path;
    fs::path sidecarPath = path;
    sidecarPath.replace_extension(".json");
    std::ifstream sidecarFile(sidecarPath);
    ASSERT_TRUE(sidecarFile) << "missing sidecar " << sidecarPath;
    const Answer sidecar = Answer::parse(sidecarFile);
    // "only_in": the precisions (float, double) in which the case is replayed at all; absent:
    // both (a distance whose exact value is irrational cannot meet the 1e-9 below in float builds)
    const std::string precision = sizeof(Real) == sizeof(float) ? "float" : "double";
    if (sidecar.contains("only_in")) {
      const auto& only = sidecar["only_in"];
      if (std::find(only.begin(), only.end(), precision) == only.end()) {
        ++skipped;
        continue;
      }
    }
    const Answer exact = lastAnswer(lines, Backend::Exact);
    const Answer native = lastAnswer(lines, Backend::Native);
    std::string text;
    for (const auto& l : lines) text += "  " + l + "\n";
    // the arbiter still says what it said when the case was found
    EXPECT_TRUE(answersAgree(lines.back(), exact, sidecar["expected"], 1e-9))
        << path.filename() << ": exact now answers " << exact.dump() << ", recorded " << sidecar["expected"].dump()
        << "\n" << text;
    const bool agree = answersAgree(lines.back(), native, exact, 1e-9);
    // "open_in": the precisions (float, double) in which the bug shows; absent: both
    bool openHere = sidecar.value("status", "fixed") == "open";
    if (openHere && sidecar.contains("open_in")) {
      const auto& in = sidecar["open_in"];
      openHere = std::find(in.begin(), in.end(), precision) != in.end();
    }
    if (openHere) {
      ++open;
      EXPECT_FALSE(agree) << path.filename()
                          << ": native now equals exact: the bug is fixed, set \"status\": \"fixed\" in the sidecar";
      std::cout << "[ OPEN     ] " << path.filename().string() << ": native " << native.dump() << ", exact "
                << exact.dump() << '\n';
    } else {
      ++fixed;
      EXPECT_TRUE(agree) << path.filename() << ": native " << native.dump() << " != exact " << exact.dump() << "\n"
                         << text;
    }
  }
  std::cout << cases.size() << " regression cases: " << fixed << " fixed, " << open << " open, " << skipped
            << " not replayed in " << (sizeof(Real) == sizeof(float) ? "float" : "double") << " builds (only_in)\n";
}

}  // namespace
}  // namespace crux::cli
