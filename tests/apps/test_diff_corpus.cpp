// Replays the known peer disagreements (oracle/known-peer-disagreements/<backend>.<cause>.jsonl,
// written from `crux diff --out` findings; format in the README there): each case must still get
// the recorded answer from the peer AND from exact, and the two must still differ — so a peer
// upgrade that changes or fixes a behaviour is noticed.

#include "cli/diff.hpp"

#include <world_factory.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace crux::cli {
namespace {

namespace fs = std::filesystem;

Answer stripped(Answer a) {
  a.erase("id");
  a.erase("op");
  return a;
}

/// Whether a distance answer's witness is consistent: |point_a − point_b| = |distance| (within
/// 1e-9 of the scale); answers without a witness are. answersAgree compares the numbers only, so
/// a peer whose distance is right but whose points are no witness (nearest-points-in-collision)
/// still differs from exact through this.
bool witnessConsistent(const Answer& a) {
  if (!a.contains("point_a") || !a.contains("point_b") || !a.contains("distance")) return true;
  double gap2 = 0, scale = 1;
  for (int i = 0; i < 3; ++i) {
    const double pa = a["point_a"][i].get<double>(), pb = a["point_b"][i].get<double>();
    gap2 += (pa - pb) * (pa - pb);
    scale = std::max({scale, std::abs(pa), std::abs(pb)});
  }
  return std::abs(std::sqrt(gap2) - std::abs(a["distance"].get<double>())) <= 1e-9 * scale;
}

/// A setup line's `load_mesh` path relative to the repository root (the corpus must not name
/// the checkout it was recorded in: CI replays it from another one), made absolute.
std::string withSourcePaths(const std::string& line) {
  Answer request = Answer::parse(line, nullptr, false);
  if (!request.is_object() || request.value("op", "") != "load_mesh" || !request.contains("path") ||
      !request["path"].is_string())
    return line;
  const fs::path path = request["path"].get<std::string>();
  if (path.is_absolute()) return line;
  request["path"] = (fs::path(CRUX_SOURCE_DIR) / path).string();
  return request.dump();
}

TEST(KnownPeerDisagreements, CorpusNamesMeshFilesRelativeToTheRepository) {
  const fs::path dir = fs::path(CRUX_SOURCE_DIR) / "oracle" / "known-peer-disagreements";
  int meshFiles = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".jsonl") continue;
    std::ifstream in(entry.path());
    for (std::string line; std::getline(in, line);) {
      const Answer request = Answer::parse(line, nullptr, false);
      if (!request.is_object() || request.value("op", "") != "load_mesh") continue;
      ++meshFiles;
      const fs::path path = request.value("path", "");
      EXPECT_FALSE(path.is_absolute()) << entry.path().filename() << ": " << line;
      EXPECT_TRUE(fs::exists(fs::path(CRUX_SOURCE_DIR) / path)) << entry.path().filename() << ": " << line;
    }
  }
  EXPECT_GT(meshFiles, 0);
}

TEST(KnownPeerDisagreements, PeersStillAnswerAsRecorded) {
  const fs::path dir = fs::path(CRUX_SOURCE_DIR) / "oracle" / "known-peer-disagreements";
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().extension() == ".jsonl") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  const auto& built = builtBackends();
  int replayed = 0;
  for (const auto& path : files) {
    const std::string file = path.filename().string();
    const std::string backend = file.substr(0, file.find('.'));
    const auto b = parseBackend(backend);
    ASSERT_TRUE(b) << file << ": the file name must start with a backend name";
    if (std::find(built.begin(), built.end(), backend) == built.end()) continue;  // peer not built here
    std::ifstream in(path);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) {
      if (line.empty()) continue;
      lines.push_back(line);
      const Answer request = Answer::parse(line, nullptr, false);
      ASSERT_TRUE(request.is_object()) << file << ": not JSON: " << line;
      if (!request.contains("recorded")) continue;
      // a case ends at its recorded query line: replay it from a fresh state
      BatchOptions peerOptions, exactOptions;
      peerOptions.backend = *b;
      exactOptions.backend = Backend::Exact;
      BatchState peerState(peerOptions), exactState(exactOptions);
      Answer peer, exact;
      for (const auto& l : lines) {
        const std::string resolved = withSourcePaths(l);
        peer = answerLine(resolved, peerState);
        exact = answerLine(resolved, exactState);
      }
      std::string text;
      for (const auto& l : lines) text += "  " + l + "\n";
      const Answer& recorded = request["recorded"];
      Answer wantExact = recorded["exact"], wantPeer = recorded[backend];
      wantExact["op"] = wantPeer["op"] = request["op"];
      EXPECT_TRUE(answersAgree(line, exact, wantExact, 1e-9))
          << file << ": exact answers " << stripped(exact).dump() << ", recorded " << recorded["exact"].dump() << "\n"
          << text;
      // peers' numbers may differ in the last float digits between float and double builds of crux
      EXPECT_TRUE(answersAgree(line, peer, wantPeer, 1e-5))
          << file << ": " << backend << " answers " << stripped(peer).dump() << ", recorded "
          << recorded[backend].dump() << " (the peer's behaviour changed: update the corpus)\n"
          << text;
      EXPECT_FALSE(answersAgree(line, peer, exact, 1e-9) && witnessConsistent(peer))
          << file << ": " << backend << " now agrees with exact\n" << text;
      ++replayed;
      lines.clear();
    }
  }
  std::cout << replayed << " known peer disagreements replayed from " << files.size() << " files\n";
}

}  // namespace
}  // namespace crux::cli
