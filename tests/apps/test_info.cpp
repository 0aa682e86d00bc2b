// Tests of `crux info` (apps/cli/info.cpp): BVH shape statistics on hand-built trees, the text
// and JSON reports on hand-checked OFF files (closed, open, duplicate and degenerate triangles),
// bad files among good ones, and the `crux` executable on bunny00.off and a missing file.

#include "apps/batch_test_util.hpp"
#include "cli/info.hpp"

#include <crux/mesh/mesh.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace crux::cli {
namespace {

using test::splitLines;

BvhNode leaf(std::uint32_t first, std::uint32_t count) { return {Aabb{}, first, count}; }
BvhNode inner(std::uint32_t firstChild) { return {Aabb{}, firstChild, 0}; }

TEST(InfoBvhShape, EmptyAndSingleLeaf) {
  const BvhShape empty = bvhShape(WideBvh{});
  EXPECT_EQ(empty.nodes, 0u);
  EXPECT_EQ(empty.leaves, 0u);
  EXPECT_EQ(empty.depth, 0u);

  Bvh one;
  one.nodes = {leaf(0, 3)};
  one.primIndices = {0, 1, 2};
  const BvhShape s = bvhShape(widenBvh(one));  // one node, its one lane the leaf
  EXPECT_EQ(s.nodes, 1u);
  EXPECT_EQ(s.leaves, 1u);
  EXPECT_DOUBLE_EQ(s.meanLanes, 1.0);
  EXPECT_EQ(s.depth, 0u);
  EXPECT_EQ(s.maxLeafSize, 3u);
  EXPECT_DOUBLE_EQ(s.meanLeafSize, 3.0);
  EXPECT_DOUBLE_EQ(s.meanLeafDepth, 0.0);
}

TEST(InfoBvhShape, CountsLanesLeavesAndDepthOfTheWideTree) {
  // binary: root(0) -> inner(1), inner(2); inner(1) -> leaf(3) [1], inner(4); inner(2) ->
  // leaf(5) [2], leaf(6) [1]; inner(4) -> leaf(7) [2], inner(8); inner(8) -> leaf(9) [1],
  // leaf(10) [1]. Widened, the root takes four lanes (leaf 3, inner 4, leaf 5, leaf 6), inner 4
  // a node of three (leaf 7, leaf 9, leaf 10): 2 nodes, 7 lanes, 6 leaves, 3 at depth 1.
  Bvh bvh;
  bvh.nodes = {inner(1), inner(3), inner(5), leaf(0, 1), inner(7), leaf(1, 2), leaf(3, 1),
               leaf(4, 2), inner(9), leaf(6, 1), leaf(7, 1)};
  for (std::uint32_t k = 0; k < 8; ++k) bvh.primIndices.push_back(k);
  // areas decide which inner lane opens first: inner 1, then inner 2 (then the root is full)
  const auto cube = [](Real side) { return Aabb{Vec3(0, 0, 0), Vec3(side, side, side)}; };
  bvh.nodes[1].bounds = cube(3);
  bvh.nodes[2].bounds = cube(2);
  bvh.nodes[4].bounds = cube(1);
  bvh.nodes[8].bounds = cube(Real(0.5));
  const BvhShape s = bvhShape(widenBvh(bvh));
  EXPECT_EQ(s.nodes, 2u);
  EXPECT_EQ(s.leaves, 6u);
  EXPECT_DOUBLE_EQ(s.meanLanes, 3.5);
  EXPECT_EQ(s.depth, 1u);
  EXPECT_EQ(s.maxLeafSize, 2u);
  EXPECT_DOUBLE_EQ(s.meanLeafSize, 8.0 / 6.0);
  EXPECT_DOUBLE_EQ(s.meanLeafDepth, 3.0 / 6.0);
}

/// An OFF file in the temporary directory, removed at the end of the test.
class TempOff {
 public:
  TempOff(const std::string& name, const std::vector<std::string>& vertices, const std::vector<std::string>& faces)
      : path_(::testing::TempDir() + "crux_test_info_" + std::to_string(getpid()) + "_" + name + ".off") {
    std::ofstream out(path_);
    out << "OFF\n" << vertices.size() << " " << faces.size() << " 0\n";
    for (const auto& v : vertices) out << v << "\n";
    for (const auto& f : faces) out << "3 " << f << "\n";
  }
  ~TempOff() { std::remove(path_.c_str()); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

const std::vector<std::string> kCubeVertices = {"0 0 0", "1 0 0", "1 1 0", "0 1 0",
                                                "0 0 1", "1 0 1", "1 1 1", "0 1 1"};
const std::vector<std::string> kCubeFaces = {"0 2 1", "0 3 2", "4 5 6", "4 6 7", "0 1 5", "0 5 4",
                                             "1 2 6", "1 6 5", "2 3 7", "2 7 6", "3 0 4", "3 4 7"};

/// Runs `crux info --json` in-process on `paths`; returns the status and the parsed lines.
std::pair<int, std::vector<Json>> infoJson(const std::vector<std::string>& paths, std::string* errText = nullptr) {
  std::ostringstream out, err;
  const int status = runInfo(paths, InfoOptions{true}, out, err);
  std::vector<Json> lines;
  for (const auto& line : splitLines(out.str())) lines.push_back(Json::parse(line));
  if (errText) *errText = err.str();
  return {status, lines};
}

TEST(Info, ClosedCube) {
  const TempOff cube("cube", kCubeVertices, kCubeFaces);
  const auto [status, lines] = infoJson({cube.path()});
  ASSERT_EQ(status, 0);
  ASSERT_EQ(lines.size(), 1u);
  const Json& j = lines[0];
  EXPECT_EQ(j["path"], cube.path());
  EXPECT_EQ(j["triangles"], 12);
  EXPECT_EQ(j["vertices"], 8);
  EXPECT_EQ(j["bounds"]["min"], Json::parse("[0.0,0.0,0.0]"));
  EXPECT_EQ(j["bounds"]["max"], Json::parse("[1.0,1.0,1.0]"));
  EXPECT_EQ(j["degenerate_triangles"], 0);
  EXPECT_EQ(j["duplicate_triangles"], 0);
  EXPECT_EQ(j["non_manifold_edges"], 0);
  EXPECT_EQ(j["boundary_edges"], 0);
  EXPECT_EQ(j["closed"], true);
  EXPECT_GE(j["bvh_build_seconds"].get<double>(), 0.0);
  EXPECT_GE(j["load_seconds"].get<double>(), j["bvh_build_seconds"].get<double>());  // the load includes the build

  // BVH figures are those of the mesh loadMesh builds.
  const Mesh mesh = loadMesh(cube.path());
  const BvhShape shape = bvhShape(mesh.bvh());
  EXPECT_EQ(j["bvh"]["nodes"], mesh.bvh().nodes.size());
  EXPECT_EQ(j["bvh"]["leaves"], shape.leaves);
  EXPECT_EQ(j["bvh"]["mean_lanes"], shape.meanLanes);
  EXPECT_EQ(j["bvh"]["depth"], shape.depth);
  EXPECT_EQ(j["bvh"]["max_leaf_size"], shape.maxLeafSize);
  EXPECT_GE(j["bvh"]["leaves"].get<std::size_t>(), 3u);  // 12 triangles, at most 4 per leaf
  EXPECT_LE(j["bvh"]["max_leaf_size"].get<std::size_t>(), 4u);
  EXPECT_DOUBLE_EQ(j["bvh"]["mean_leaf_size"].get<double>() * j["bvh"]["leaves"].get<double>(), 12.0);
  EXPECT_EQ(j["memory_bytes"], mesh.memoryBytes());
  EXPECT_DOUBLE_EQ(j["bytes_per_triangle"].get<double>(), double(mesh.memoryBytes()) / 12.0);
  // The estimate the loader checks before building bounds what the built mesh holds.
  EXPECT_GE(j["estimated_mesh_bytes"].get<std::size_t>(), mesh.memoryBytes());
  EXPECT_GE(j["estimated_peak_bytes"].get<std::size_t>(), j["estimated_mesh_bytes"].get<std::size_t>());
}

TEST(Info, OpenDuplicateAndDegenerateTriangles) {
  std::vector<std::string> open(kCubeFaces.begin(), kCubeFaces.end() - 1);  // drop "3 4 7"
  std::vector<std::string> duplicated = kCubeFaces;
  duplicated.push_back("2 1 0");  // triangle 0 again, other order: its three edges get a third use
  std::vector<std::string> withMidpoint = kCubeVertices;
  withMidpoint.push_back("0.5 0 0");
  std::vector<std::string> degenerate = kCubeFaces;
  degenerate.push_back("0 8 1");  // collinear along edge 0-1: edges 0-8 and 8-1 are boundary, 0-1 non-manifold
  const TempOff a("open", kCubeVertices, open), b("duplicate", kCubeVertices, duplicated),
      c("degenerate", withMidpoint, degenerate);
  const auto [status, lines] = infoJson({a.path(), b.path(), c.path()});
  ASSERT_EQ(status, 0);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0]["triangles"], 11);
  EXPECT_EQ(lines[0]["boundary_edges"], 3);
  EXPECT_EQ(lines[0]["non_manifold_edges"], 0);
  EXPECT_EQ(lines[0]["closed"], false);
  EXPECT_EQ(lines[1]["triangles"], 13);
  EXPECT_EQ(lines[1]["duplicate_triangles"], 1);
  EXPECT_EQ(lines[1]["non_manifold_edges"], 3);
  EXPECT_EQ(lines[1]["boundary_edges"], 0);
  EXPECT_EQ(lines[1]["closed"], false);
  EXPECT_EQ(lines[2]["triangles"], 13);
  EXPECT_EQ(lines[2]["vertices"], 9);
  EXPECT_EQ(lines[2]["degenerate_triangles"], 1);
  EXPECT_EQ(lines[2]["duplicate_triangles"], 0);
  EXPECT_EQ(lines[2]["boundary_edges"], 2);
  EXPECT_EQ(lines[2]["non_manifold_edges"], 1);
  EXPECT_EQ(lines[2]["closed"], false);
}

TEST(Info, ClosedMeansWhatTheVolumeOpsRequire) {
  // Only a triangle repeating an index: no open edge, but no surface (point_inside refuses it).
  const TempOff collapsed("collapsed", {"0 0 0", "1 0 0", "0 1 0"}, {"0 0 1"});
  std::vector<std::string> flipped = kCubeFaces;
  flipped[0] = "0 1 2";  // triangle 0 reversed: its edges are used twice in one direction
  const TempOff cube("flipped", kCubeVertices, flipped);
  const auto [status, lines] = infoJson({collapsed.path(), cube.path()});
  ASSERT_EQ(status, 0);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0]["boundary_edges"], 0);
  EXPECT_EQ(lines[0]["closed"], false);
  EXPECT_EQ(lines[1]["boundary_edges"], 0);
  EXPECT_EQ(lines[1]["inconsistent_edges"], 3);
  EXPECT_EQ(lines[1]["closed"], false);
}

TEST(Info, TextReport) {
  const TempOff cube("cube_text", kCubeVertices, kCubeFaces);
  std::ostringstream out, err;
  ASSERT_EQ(runInfo({cube.path(), cube.path()}, InfoOptions{}, out, err), 0);
  EXPECT_EQ(err.str(), "");
  const std::string text = out.str();
  const auto lines = splitLines(text);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], cube.path());
  for (const char* row : {"  triangles             12", "  vertices              8", "  closed                yes",
                          "  boundary edges        0", "  bounds                [0, 0, 0] .. [1, 1, 1]"})
    EXPECT_NE(text.find(std::string(row) + "\n"), std::string::npos) << row << " not in\n" << text;
  for (const char* label : {"load time", "BVH build", "nodes", "leaves", "depth", "bytes/triangle"})
    EXPECT_NE(text.find(label), std::string::npos) << label;
  // Two reports separated by one blank line.
  EXPECT_EQ(std::count(lines.begin(), lines.end(), cube.path()), 2);
  EXPECT_EQ(std::count(lines.begin(), lines.end(), ""), 1);
}

TEST(Info, BadFilesAreReportedAndTheOthersStillAre) {
  const TempOff cube("cube_ok", kCubeVertices, kCubeFaces);
  const std::string missing = ::testing::TempDir() + "crux_test_info_missing.off";
  const TempOff malformed("malformed", {"0 0 0", "1 0", "0 1 0"}, {"0 1 2"});
  std::string err;
  const auto [status, lines] = infoJson({missing, cube.path(), malformed.path()}, &err);
  EXPECT_EQ(status, 1);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0]["path"], missing);
  EXPECT_EQ(lines[0]["error"].get<std::string>().rfind(missing + ": ", 0), 0u) << lines[0].dump();
  EXPECT_EQ(lines[1]["triangles"], 12);
  EXPECT_EQ(lines[2]["path"], malformed.path());
  EXPECT_EQ(lines[2]["error"].get<std::string>().rfind(malformed.path() + ":", 0), 0u) << lines[2].dump();
  const auto errLines = splitLines(err);
  ASSERT_EQ(errLines.size(), 2u) << err;
  EXPECT_EQ(errLines[0], "crux info: " + lines[0]["error"].get<std::string>());
  EXPECT_EQ(errLines[1].rfind("crux info: " + malformed.path() + ":", 0), 0u) << err;

  std::ostringstream out, errText;
  EXPECT_EQ(runInfo({missing, cube.path()}, InfoOptions{}, out, errText), 1);
  EXPECT_EQ(splitLines(out.str()).front(), cube.path());  // the text report has no error lines
  EXPECT_EQ(errText.str().rfind("crux info: " + missing + ": ", 0), 0u) << errText.str();
}

TEST(InfoExecutable, BunnyAndAMissingFile) {
  using test::run;
  using test::shellQuoted;
  const std::string crux = test::cruxExecutable();
  if (access(crux.c_str(), X_OK) != 0) GTEST_SKIP() << crux << " not built";
  const std::string missing = ::testing::TempDir() + "crux_test_info_no_such_file.off";
  const std::string errFile = ::testing::TempDir() + "crux_test_info_" + std::to_string(getpid()) + ".err";

  const auto [missingStatus, missingOut] = run(shellQuoted(crux) + " info " + shellQuoted(missing) + " 2>&1");
  EXPECT_EQ(missingStatus, 1);
  EXPECT_EQ(missingOut.rfind("crux info: " + missing + ": ", 0), 0u) << missingOut;

  const auto [noArgs, noArgsOut] = run(shellQuoted(crux) + " info 2>&1");
  EXPECT_NE(noArgs, 0) << noArgsOut;

  const std::string bunny = std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off";
  if (access(bunny.c_str(), R_OK) != 0) GTEST_SKIP() << bunny << " not present";
  const auto [status, text] = run(shellQuoted(crux) + " info " + shellQuoted(bunny));
  EXPECT_EQ(status, 0);
  EXPECT_EQ(text.rfind(bunny + "\n", 0), 0u) << text;
  EXPECT_NE(text.find("  triangles             75408\n"), std::string::npos) << text;

  const auto [jsonStatus, json] = run(shellQuoted(crux) + " info --json " + shellQuoted(missing) + " " +
                                      shellQuoted(bunny) + " 2>" + shellQuoted(errFile));
  EXPECT_EQ(jsonStatus, 1);
  const auto lines = splitLines(json);
  ASSERT_EQ(lines.size(), 2u) << json;
  const Json bad = Json::parse(lines[0]), good = Json::parse(lines[1]);
  EXPECT_EQ(bad["path"], missing);
  EXPECT_TRUE(bad.contains("error"));
  EXPECT_EQ(good["path"], bunny);
  EXPECT_EQ(good["triangles"], 75408);
  // leaves of at most 4 triangles, nodes of at most 4 lanes
  EXPECT_GE(good["bvh"]["leaves"].get<std::size_t>(), 75408u / 4);
  EXPECT_GT(good["bvh"]["nodes"].get<std::size_t>(), good["bvh"]["leaves"].get<std::size_t>() / 4);
  EXPECT_GT(good["bytes_per_triangle"].get<double>(), 0.0);
  std::ifstream errIn(errFile);
  std::stringstream errText;
  errText << errIn.rdbuf();
  std::remove(errFile.c_str());
  EXPECT_EQ(errText.str().rfind("crux info: " + missing + ": ", 0), 0u) << errText.str();
}

}  // namespace
}  // namespace crux::cli
