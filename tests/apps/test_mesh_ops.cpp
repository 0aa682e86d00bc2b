// Tests of the batch protocol's mesh ops (apps/cli/mesh_ops.cpp, docs/batch.md): mesh and
// load_mesh, every mesh_* query on a hand-checked unit cube (rays through face diagonals, edges
// and vertices, touching spheres/boxes/planes/triangles, cubes touching under transforms), the
// extension fields (all, cull, triangles), and every error path.

#include "apps/batch_test_util.hpp"
#include "cli/batch.hpp"
#include "cli/json_codec.hpp"
#include "cli/mesh_ops.hpp"

#include <crux/geometry/overlap.hpp>
#include <crux/mesh/mesh_query.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace crux::cli {
namespace {

using test::errorOf;
using test::isPoint;
using test::kResultTolerance;

// The unit cube [0,1]^3 as 12 integer triangles, counter-clockwise seen from outside:
//   0,1 bottom z=0 (diagonal 0-2)     2,3 top z=1 (diagonal 4-6)
//   4,5 front y=0 (diagonal 0-5)      6,7 right x=1 (diagonal 1-6)
//   8,9 back y=1 (diagonal 2-7)       10,11 left x=0 (diagonal 3-4)
// Within a face the lower index is the triangle on the side of the diagonal listed first:
// 0: x>=y, 2: x>=y, 4: x>=z, 6: y>=z, 8: x+z<=1, 10: y+z<=1.
const std::string kCubeVertices = "[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]";
const std::string kCubeTriangles =
    "[[0,2,1],[0,3,2],[4,5,6],[4,6,7],[0,1,5],[0,5,4],[1,2,6],[1,6,5],[2,3,7],[2,7,6],[3,0,4],[3,4,7]]";
/// Triangles containing the cube's vertex 6 = (1,1,1).
const std::vector<unsigned> kTrianglesAtVertex6 = {2, 3, 6, 7, 9};
/// Triangles containing the cube's vertex 0 = (0,0,0).
const std::vector<unsigned> kTrianglesAtVertex0 = {0, 1, 4, 5, 10};

std::string op(const std::string& name, const std::string& fields) {
  return R"({"id":"q","op":")" + name + R"(",)" + fields + "}";
}

std::string defineCube(const std::string& name) {
  return op("mesh", R"("name":")" + name + R"(","vertices":)" + kCubeVertices + R"(,"triangles":)" + kCubeTriangles);
}

/// A batch with the unit cube defined as "cube".
class MeshOps : public ::testing::Test {
 protected:
  void SetUp() override {
    const Answer a = ask(defineCube("cube"));
    ASSERT_EQ(a.dump(), R"({"id":"q","op":"mesh","triangles":12})");
  }

  Answer ask(const std::string& line) { return answerLine(line, state_); }

  ::testing::AssertionResult answersHit(const std::string& line, bool expected) {
    const Answer a = ask(line);
    if (!errorOf(a).empty()) return ::testing::AssertionFailure() << "error answer " << a.dump() << " to " << line;
    if (!a.contains("hit") || !a["hit"].is_boolean())
      return ::testing::AssertionFailure() << "no boolean hit in " << a.dump();
    if (a["hit"].get<bool>() != expected)
      return ::testing::AssertionFailure() << "hit " << a["hit"] << " expected " << expected << " for " << line;
    return ::testing::AssertionSuccess();
  }

  /// Asserts `line` answers hit == !expected.empty() and "triangles" == expected.
  ::testing::AssertionResult answersTriangles(const std::string& line, const std::vector<unsigned>& expected) {
    const Answer a = ask(line);
    if (!errorOf(a).empty()) return ::testing::AssertionFailure() << "error answer " << a.dump() << " to " << line;
    if (a.value("hit", expected.empty()) != !expected.empty())
      return ::testing::AssertionFailure() << "wrong hit in " << a.dump() << " to " << line;
    if (!a.contains("triangles") || a["triangles"].get<std::vector<unsigned>>() != expected)
      return ::testing::AssertionFailure() << "triangles in " << a.dump() << " != " << Json(expected).dump()
                                           << " for " << line;
    return ::testing::AssertionSuccess();
  }

  /// Asserts the answer to `line` is an error whose message starts with `prefix`.
  ::testing::AssertionResult errorStartsWith(const std::string& line, const std::string& prefix) {
    const Answer a = ask(line);
    const std::string e = errorOf(a);
    if (e.rfind(prefix, 0) != 0)
      return ::testing::AssertionFailure() << "answer " << a.dump() << " to " << line << " lacks error prefix '"
                                           << prefix << "'";
    if (a.contains("hit") || a.contains("triangles") || a.contains("t"))
      return ::testing::AssertionFailure() << "error answer carries results: " << a.dump();
    return ::testing::AssertionSuccess();
  }

  BatchState state_;
};

std::string ray(const std::string& origin, const std::string& dir) {
  return R"("mesh":"cube","ray":{"origin":)" + origin + R"(,"dir":)" + dir + "}";
}

// ---------------------------------------------------------------------------------------------
// mesh and load_mesh

TEST_F(MeshOps, MeshIsStoredInTheBatchState) {
  ASSERT_EQ(state_.meshes.count("cube"), 1u);
  const Mesh& cube = *state_.meshes.at("cube");
  EXPECT_EQ(cube.triangleCount(), 12u);
  EXPECT_EQ(cube.vertexCount(), 8u);
  EXPECT_TRUE(cube.stats().closed());
  EXPECT_EQ(cube.triangles()[9], (TriangleIndices{2, 7, 6}));
  EXPECT_EQ(cube.vertices()[6], Vec3(1, 1, 1));
}

TEST_F(MeshOps, RedefiningANameReplacesTheMesh) {
  const std::string sphereAtCube = op("mesh_sphere", R"("mesh":"cube","sphere":{"center":[0.5,0.5,0.5],"radius":1})");
  ASSERT_TRUE(answersHit(sphereAtCube, true));
  const std::shared_ptr<const Mesh> old = state_.meshes.at("cube");
  EXPECT_EQ(ask(op("mesh", R"("name":"cube","vertices":[[10,10,10],[11,10,10],[10,11,10]],"triangles":[[0,1,2]])"))
                .dump(),
            R"({"id":"q","op":"mesh","triangles":1})");
  EXPECT_TRUE(answersHit(sphereAtCube, false));
  EXPECT_TRUE(answersHit(op("mesh_sphere", R"("mesh":"cube","sphere":{"center":[10,10,10],"radius":0})"), true));
  EXPECT_EQ(old->triangleCount(), 12u);  // a holder of the old mesh keeps it
  // A failed redefinition leaves the current mesh in place.
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"cube","vertices":[[0,0,0]],"triangles":[[0,0,1]])"),
                              "triangles[0][2]: index 1 out of range (1 vertex)"));
  EXPECT_EQ(state_.meshes.at("cube")->triangleCount(), 1u);
}

TEST_F(MeshOps, NamesAreIndependent) {
  ASSERT_EQ(errorOf(ask(op("mesh", R"("name":"Cube 2","vertices":[[5,5,5],[6,5,5],[5,6,5]],"triangles":[[0,1,2]])"))),
            "");
  EXPECT_TRUE(answersHit(op("mesh_plane", R"("mesh":"Cube 2","plane":{"normal":[0,0,1],"d":5})"), true));
  EXPECT_TRUE(answersHit(op("mesh_plane", R"("mesh":"cube","plane":{"normal":[0,0,1],"d":5})"), false));
  EXPECT_TRUE(errorStartsWith(op("mesh_plane", R"("mesh":"cube 2","plane":{"normal":[0,0,1],"d":5})"),
                              R"(mesh: no mesh named "cube 2")"));
}

TEST_F(MeshOps, DegenerateAndUnreferencedAreAccepted) {
  // A zero-area triangle is its segment; vertex 3 is unused.
  EXPECT_EQ(ask(op("mesh", R"("name":"seg","vertices":[[0,0,0],[2,0,0],[1,0,0],[9,9,9]],"triangles":[[0,1,2]])"))
                .dump(),
            R"({"id":"q","op":"mesh","triangles":1})");
  EXPECT_TRUE(answersHit(op("mesh_segment", R"("mesh":"seg","segment":{"start":[1.5,-1,0],"end":[1.5,1,0]})"), true));
  EXPECT_TRUE(answersHit(op("mesh_segment", R"("mesh":"seg","segment":{"start":[2.5,-1,0],"end":[2.5,1,0]})"), false));
}

TEST_F(MeshOps, IndexWrittenMinusZeroIsIndexZero) {
  // JSON's -0 is an integer 0 (the parser reads it as a signed integer).
  EXPECT_EQ(ask(op("mesh", R"("name":"m","vertices":[[0,0,0],[1,0,0],[0,1,0]],"triangles":[[-0,1,2]])")).dump(),
            R"({"id":"q","op":"mesh","triangles":1})");
  EXPECT_TRUE(answersHit(op("mesh_sphere", R"("mesh":"m","sphere":{"center":[0,0,0],"radius":0})"), true));
}

TEST_F(MeshOps, MeshErrorsNameTheField) {
  const std::string v = R"("vertices":)" + kCubeVertices;
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v + R"(,"triangles":[[0,1,2],[0,2,3],[4,5,6],[1,17,2]])"),
                              "triangles[3][1]: index 17 out of range (8 vertices)"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v + R"(,"triangles":[[0,1,2],[0,-1,3]])"),
                              "triangles[1][1]: index -1 out of range (8 vertices)"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v + R"(,"triangles":[[0,1,8]])"),
                              "triangles[0][2]: index 8 out of range (8 vertices)"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v + R"(,"triangles":[[0,1.5,2]])"),
                              "triangles[0][1]: expected an integer vertex index, got 1.5"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v + R"(,"triangles":[[0,1,2.0]])"),
                              "triangles[0][2]: expected an integer vertex index, got 2.0"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v + R"(,"triangles":[[0,"1",2]])"),
                              "triangles[0][1]: expected an integer vertex index, got string"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v + R"(,"triangles":[[0,1,2],[0,1]])"),
                              "triangles[1]: expected [i, j, k], got an array of 2 elements"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v + R"(,"triangles":[{"i":0}])"),
                              "triangles[0]: expected [i, j, k], got object"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v + R"(,"triangles":[])"),
                              "triangles: the mesh has no triangles"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v + R"(,"triangles":{})"),
                              "triangles: expected an array of [i, j, k], got object"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m",)" + v), "triangles: missing field"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m","vertices":[],"triangles":[[0,0,0]])"),
                              "triangles[0][0]: index 0 out of range (0 vertices)"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m","vertices":[],"triangles":[[-0,0,0]])"),
                              "triangles[0][0]: index 0 out of range (0 vertices)"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m","vertices":[[0,0,0],[1,0],[0,1,0]],"triangles":[[0,1,2]])"),
                              "vertices[1]: expected [x, y, z], got an array of 2 elements"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m","vertices":[[0,0,0],[1,0,1e400],[0,1,0]],"triangles":[[0,1,2]])"),
                              "vertices[1][2]: number 1e400 overflows double"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m","vertices":"cube","triangles":[[0,1,2]])"),
                              "vertices: expected an array of [x, y, z], got string"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("vertices":[[0,0,0]],"triangles":[[0,0,0]])"), "name: missing field"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":7,"vertices":[[0,0,0]],"triangles":[[0,0,0]])"),
                              "name: expected a mesh name (string), got number"));
  EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"","vertices":[[0,0,0]],"triangles":[[0,0,0]])"),
                              "name: a mesh name must not be empty"));
  if (sizeof(Real) == sizeof(float)) {
    EXPECT_TRUE(errorStartsWith(op("mesh", R"("name":"m","vertices":[[0,0,0],[1e39,0,0],[0,1,0]],"triangles":[[0,1,2]])"),
                                "vertices[1][0]: number 1e+39 overflows crux::Real (float)"));
  }
  EXPECT_EQ(state_.meshes.count("m"), 0u);  // nothing was defined by the failures
}

/// A file in the temporary directory, removed at the end of the test.
class TempFile {
 public:
  TempFile(const std::string& name, const std::string& content)
      : path_(::testing::TempDir() + "crux_test_mesh_ops_" + std::to_string(getpid()) + "_" + name) {
    std::ofstream(path_) << content;
  }
  ~TempFile() { std::remove(path_.c_str()); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

TEST_F(MeshOps, LoadMeshReadsAFileAndItsQueriesWork) {
  const TempFile off("tetra.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  EXPECT_EQ(ask(op("load_mesh", R"("name":"tetra","path":)" + Json(off.path()).dump())).dump(),
            R"({"id":"q","op":"load_mesh","triangles":4})");
  // The slanted face x + y + z = 1 touched at its centroid by a point sphere.
  EXPECT_TRUE(answersHit(op("mesh_sphere", R"("mesh":"tetra","sphere":{"center":[0.25,0.25,0.5],"radius":0})"),
                         true));
  EXPECT_TRUE(answersHit(op("mesh_sphere", R"("mesh":"tetra","sphere":{"center":[0.5,0.5,0.5],"radius":0})"),
                         false));
}

TEST_F(MeshOps, LoadMeshErrorsNameTheFieldAndTheFile) {
  const std::string missing = ::testing::TempDir() + "crux_no_such_mesh_file.off";
  const Answer a = ask(op("load_mesh", R"("name":"cube","path":)" + Json(missing).dump()));
  EXPECT_EQ(errorOf(a).rfind("path: " + missing + ": ", 0), 0u) << a.dump();

  const TempFile malformed("malformed.off", "OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n");
  const Answer b = ask(op("load_mesh", R"("name":"cube","path":)" + Json(malformed.path()).dump()));
  EXPECT_EQ(errorOf(b).rfind("path: " + malformed.path() + ":", 0), 0u) << b.dump();

  const TempFile truncated("truncated.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n");
  const Answer c = ask(op("load_mesh", R"("name":"cube","path":)" + Json(truncated.path()).dump()));
  EXPECT_EQ(errorOf(c).rfind("path: " + truncated.path() + ":", 0), 0u) << c.dump();

  const Answer d = ask(op("load_mesh", R"("name":"cube","path":)" + Json(::testing::TempDir()).dump()));
  EXPECT_EQ(errorOf(d).rfind("path: ", 0), 0u) << d.dump();

  EXPECT_TRUE(errorStartsWith(op("load_mesh", R"("name":"cube","path":"")"), "path: the file path is empty"));
  EXPECT_TRUE(errorStartsWith(op("load_mesh", R"("name":"cube","path":3)"),
                              "path: expected a file path (string), got number"));
  EXPECT_TRUE(errorStartsWith(op("load_mesh", R"("name":"cube")"), "path: missing field"));
  EXPECT_TRUE(errorStartsWith(op("load_mesh", R"("path":"x.off")"), "name: missing field"));
  // The failures left "cube" as it was.
  EXPECT_EQ(state_.meshes.at("cube")->triangleCount(), 12u);
}

TEST_F(MeshOps, LoadMeshBunny) {
  const std::string path = std::string(CRUX_SOURCE_DIR) + "/data/meshes/bunny00.off";
  if (access(path.c_str(), R_OK) != 0) GTEST_SKIP() << path << " not present";
  EXPECT_EQ(ask(op("load_mesh", R"("name":"bunny","path":)" + Json(path).dump())).dump(),
            R"({"id":"q","op":"load_mesh","triangles":75408})");
  const Mesh& bunny = *state_.meshes.at("bunny");
  // A ray from above at the centre of its bounds goes through the closed surface.
  const Vec3 c = bunny.bounds().center();
  std::ostringstream r;
  r.precision(17);
  r << R"("mesh":"bunny","ray":{"origin":[)" << double(c.x()) << "," << double(c.y()) << ","
    << double(bunny.bounds().max.z()) + 1 << R"(],"dir":[0,0,-1]},"all":true)";
  const Answer a = ask(op("mesh_ray", r.str()));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_EQ(a["hits"].size() % 2, 0u) << "a closed surface is crossed an even number of times: " << a.dump();
  EXPECT_TRUE(answersHit(op("mesh_aabb", R"("mesh":"bunny","aabb":{"min":[5,5,5],"max":[6,6,6]})"), false));
}

// ---------------------------------------------------------------------------------------------
// mesh_ray

TEST_F(MeshOps, RayDownAFaceDiagonalHitsTheLowerIndexedTriangle) {
  const Answer a = ask(op("mesh_ray", ray("[0.5,0.5,5]", "[0,0,-2]")));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_NEAR(a["t"].get<double>(), 4.0, kResultTolerance);  // world distance, dir is not unit
  EXPECT_TRUE(isPoint(a["point"], 0.5, 0.5, 1));
  EXPECT_TRUE(isPoint(a["normal"], 0, 0, 1));
  EXPECT_EQ(a["triangle"], 2);  // triangles 2 and 3 share the diagonal; the lower index wins
}

TEST_F(MeshOps, RayThroughACubeEdgeHits) {
  // (1,1,0.5) lies on the edge x = y = 1, shared by triangle 6 (right face) and 9 (back face).
  const Answer a = ask(op("mesh_ray", ray("[2,2,0.5]", "[-1,-1,0]")));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_NEAR(a["t"].get<double>(), std::sqrt(2.0), kResultTolerance);
  EXPECT_TRUE(isPoint(a["point"], 1, 1, 0.5));
  EXPECT_EQ(a["triangle"], 6);
  EXPECT_TRUE(isPoint(a["normal"], 1, 0, 0));
}

TEST_F(MeshOps, RayThroughACubeVertexHits) {
  const Answer a = ask(op("mesh_ray", ray("[2,2,2]", "[-1,-1,-1]")));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_NEAR(a["t"].get<double>(), std::sqrt(3.0), kResultTolerance);
  EXPECT_TRUE(isPoint(a["point"], 1, 1, 1));
  EXPECT_EQ(a["triangle"], 2);  // lowest of the triangles at vertex 6
  EXPECT_TRUE(isPoint(a["normal"], 0, 0, 1));
}

TEST_F(MeshOps, RaysAtEveryEdgeAndVertexOfAGridAreNeverLost) {
  // Every surface point of the cube on a 1/4 grid (face interiors, face diagonals, cube edges
  // and vertices), aimed at from outside along the line through the cube's centre: the first
  // contact is that point (the cube is convex).
  int cases = 0;
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; j <= 4; ++j)
      for (int k = 0; k <= 4; ++k) {
        if (i % 4 && j % 4 && k % 4) continue;  // not on the surface
        const double p[3] = {i / 4.0, j / 4.0, k / 4.0};
        double origin[3], dir[3], length2 = 0;
        for (int d = 0; d < 3; ++d) {
          dir[d] = 0.5 - p[d];
          origin[d] = p[d] - 2 * dir[d];
          length2 += dir[d] * dir[d];
        }
        std::ostringstream r;
        r << "[" << origin[0] << "," << origin[1] << "," << origin[2] << "]";
        std::ostringstream dr;
        dr << "[" << dir[0] << "," << dir[1] << "," << dir[2] << "]";
        const Answer a = ask(op("mesh_ray", ray(r.str(), dr.str())));
        ASSERT_TRUE(a.value("hit", false)) << r.str() << " " << dr.str() << " -> " << a.dump();
        EXPECT_NEAR(a["t"].get<double>(), 2 * std::sqrt(length2), kResultTolerance) << a.dump();
        EXPECT_TRUE(isPoint(a["point"], p[0], p[1], p[2])) << r.str();
        ++cases;
      }
  EXPECT_EQ(cases, 125 - 27);
}

TEST_F(MeshOps, RayFromInsideHitsABackFaceUnlessCulled) {
  const Answer a = ask(op("mesh_ray", ray("[0.5,0.5,0.5]", "[0,0,1]")));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_NEAR(a["t"].get<double>(), 0.5, kResultTolerance);
  EXPECT_TRUE(isPoint(a["normal"], 0, 0, -1));  // facing the ray origin
  EXPECT_EQ(a["triangle"], 2);
  EXPECT_EQ(ask(op("mesh_ray", ray("[0.5,0.5,0.5]", "[0,0,1]") + R"(,"cull":true)")).dump(),
            R"({"id":"q","op":"mesh_ray","hit":false})");
  // From outside the front face is kept by culling, and the bottom (a back face) is skipped.
  const Answer c = ask(op("mesh_ray", ray("[0.3,0.6,5]", "[0,0,-1]") + R"(,"cull":true,"all":true)"));
  ASSERT_TRUE(c.value("hit", false)) << c.dump();
  ASSERT_EQ(c["hits"].size(), 1u) << c.dump();
  EXPECT_EQ(c["triangle"], 3);
  EXPECT_TRUE(answersHit(op("mesh_ray", ray("[0.5,0.5,0.5]", "[0,0,1]") + R"(,"cull":false)"), true));
}

TEST_F(MeshOps, RayMaxDistanceIsClosed) {
  const std::string r = ray("[0.3,0.6,5]", "[0,0,-2]");
  const Answer a = ask(op("mesh_ray", r + R"(,"max":4)"));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_NEAR(a["t"].get<double>(), 4.0, kResultTolerance);
  EXPECT_EQ(a["triangle"], 3);  // (0.3, 0.6) has y >= x
  EXPECT_TRUE(answersHit(op("mesh_ray", r + R"(,"max":3.5)"), false));
  EXPECT_TRUE(answersHit(op("mesh_ray", r + R"(,"max":0)"), false));
  // From a point on the surface, max 0 still hits at t = 0.
  const Answer z = ask(op("mesh_ray", ray("[0.3,0.6,1]", "[0,0,1]") + R"(,"max":0)"));
  ASSERT_TRUE(z.value("hit", false)) << z.dump();
  EXPECT_EQ(z["t"].get<double>(), 0.0);
}

TEST_F(MeshOps, RayAllReturnsEveryHitSortedAndTheClosestFirst) {
  const Answer a = ask(op("mesh_ray", ray("[0.3,0.6,5]", "[0,0,-1]") + R"(,"all":true)"));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  ASSERT_EQ(a["hits"].size(), 2u) << a.dump();
  EXPECT_EQ(a["hits"][0]["triangle"], 3);  // top
  EXPECT_EQ(a["hits"][1]["triangle"], 1);  // bottom
  EXPECT_NEAR(a["hits"][0]["t"].get<double>(), 4.0, kResultTolerance);
  EXPECT_NEAR(a["hits"][1]["t"].get<double>(), 5.0, kResultTolerance);
  EXPECT_TRUE(isPoint(a["hits"][1]["point"], 0.3, 0.6, 0));
  EXPECT_TRUE(isPoint(a["hits"][1]["normal"], 0, 0, 1));  // bottom face, seen from above
  for (const char* key : {"t", "point", "normal", "triangle"}) EXPECT_EQ(a[key], a["hits"][0][key]) << key;
  // Through the diagonal both triangles of each face are hit.
  const Answer d = ask(op("mesh_ray", ray("[0.5,0.5,5]", "[0,0,-1]") + R"(,"all":true)"));
  ASSERT_EQ(d["hits"].size(), 4u) << d.dump();
  std::vector<int> order;
  for (const auto& h : d["hits"]) order.push_back(h["triangle"].get<int>());
  EXPECT_EQ(order, (std::vector<int>{2, 3, 0, 1}));
  // Limited by max, and a miss gives an empty list.
  EXPECT_EQ(ask(op("mesh_ray", ray("[0.3,0.6,5]", "[0,0,-1]") + R"(,"all":true,"max":4.5)"))["hits"].size(), 1u);
  EXPECT_EQ(ask(op("mesh_ray", ray("[3,3,5]", "[0,0,-1]") + R"(,"all":true)")).dump(),
            R"({"id":"q","op":"mesh_ray","hit":false,"hits":[]})");
}

TEST_F(MeshOps, RayInTheTopFacePlaneHitsWhereItEnters) {
  const Answer a = ask(op("mesh_ray", ray("[-1,0.3,1]", "[1,0,0]")));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_NEAR(a["t"].get<double>(), 1.0, kResultTolerance);
  EXPECT_TRUE(isPoint(a["point"], 0, 0.3, 1));
}

TEST_F(MeshOps, RayMissCarriesOnlyHit) {
  EXPECT_EQ(ask(op("mesh_ray", ray("[2,2,5]", "[0,0,-1]"))).dump(), R"({"id":"q","op":"mesh_ray","hit":false})");
  EXPECT_EQ(ask(op("mesh_ray", ray("[0.5,0.5,5]", "[0,0,1]"))).dump(), R"({"id":"q","op":"mesh_ray","hit":false})");
  // Grazing past the edge x = 1, z = 1 by 1/16.
  EXPECT_TRUE(answersHit(op("mesh_ray", ray("[1.0625,-1,1]", "[0,1,0]")), false));
  EXPECT_TRUE(answersHit(op("mesh_ray", ray("[1,-1,1]", "[0,1,0]")), true));
}

TEST_F(MeshOps, RayAnswersEqualTheMeshLayerBitForBit) {
  // Random rays at the cube through the protocol equal crux::raycastClosest on the same mesh.
  const Mesh& cube = *state_.meshes.at("cube");
  std::mt19937_64 rng(0x3e5e7a1);
  std::uniform_real_distribution<double> coord(-1.0, 2.0);
  const int cases = 400;
  int hits = 0;
  for (int i = 0; i < cases; ++i) {
    const Vec3 origin(Real(coord(rng)), Real(coord(rng)), Real(coord(rng) + 2.0));
    const Vec3 target(Real(coord(rng)), Real(coord(rng)), Real(0.5));
    const Ray r{origin, target - origin};
    std::ostringstream line;
    line.precision(17);
    line << R"({"op":"mesh_ray","mesh":"cube","ray":{"origin":[)" << double(r.origin.x()) << ","
         << double(r.origin.y()) << "," << double(r.origin.z()) << R"(],"dir":[)" << double(r.dir.x()) << ","
         << double(r.dir.y()) << "," << double(r.dir.z()) << "]}}";
    std::ostringstream out;
    writeAnswer(out, ask(line.str()));
    const Json a = Json::parse(out.str());
    const std::optional<MeshRayHit> expected = raycastClosest(cube, r);
    ASSERT_EQ(a.value("hit", !expected), expected.has_value()) << line.str() << " -> " << out.str();
    if (!expected) continue;
    ++hits;
    ASSERT_EQ(a["t"].get<double>(), double(expected->t)) << out.str();
    ASSERT_EQ(a["triangle"].get<std::uint32_t>(), expected->triangle) << out.str();
    for (std::size_t k = 0; k < 3; ++k) {
      ASSERT_EQ(a["point"][k].get<double>(), double(expected->point[Eigen::Index(k)])) << out.str();
      ASSERT_EQ(a["normal"][k].get<double>(), double(expected->normal[Eigen::Index(k)])) << out.str();
    }
  }
  EXPECT_GE(hits, cases / 5);
  EXPECT_LE(hits, cases * 4 / 5);
}

// ---------------------------------------------------------------------------------------------
// mesh_segment, mesh_sphere, mesh_aabb, mesh_obb, mesh_plane, mesh_triangle

TEST_F(MeshOps, SegmentCrossingEndingOnAndInsideTheSurface) {
  const auto seg = [](const std::string& a, const std::string& b) {
    return op("mesh_segment", R"("mesh":"cube","segment":{"start":)" + a + R"(,"end":)" + b + "}");
  };
  EXPECT_TRUE(answersHit(seg("[0.5,0.5,0.5]", "[0.5,0.5,2]"), true));
  EXPECT_TRUE(answersHit(seg("[0.5,0.5,2]", "[0.5,0.5,1]"), true));               // ends on the top face
  EXPECT_TRUE(answersHit(seg("[0.5,0.5,2]", "[0.5,0.5,1.0625]"), false));         // stops short
  EXPECT_TRUE(answersHit(seg("[0.25,0.25,0.25]", "[0.75,0.75,0.75]"), false));    // wholly inside
  EXPECT_TRUE(answersHit(seg("[1,1,0.25]", "[1,1,0.75]"), true));                 // along a cube edge
  EXPECT_TRUE(answersHit(seg("[1.25,0,0]", "[1.25,1,1]"), false));                // parallel to a face
  EXPECT_TRUE(answersHit(seg("[1,1,1]", "[1,1,1]"), true));                       // a point at a vertex
  const std::string atVertex = seg("[1,1,1]", "[1,1,1]");
  EXPECT_TRUE(answersTriangles(atVertex.substr(0, atVertex.size() - 1) + R"(,"triangles":true})", kTrianglesAtVertex6));
}

TEST_F(MeshOps, SphereTouchingAFaceAVertexAndInside) {
  const auto sphere = [](const std::string& center, const std::string& radius, bool list = false) {
    return op("mesh_sphere", R"("mesh":"cube","sphere":{"center":)" + center + R"(,"radius":)" + radius + "}" +
                                 (list ? R"(,"triangles":true)" : ""));
  };
  EXPECT_TRUE(answersTriangles(sphere("[0.3,0.6,3]", "2", true), {3}));  // touches the top face at (0.3,0.6,1)
  EXPECT_TRUE(answersTriangles(sphere("[0.3,0.6,3]", "1.9375", true), {}));
  EXPECT_TRUE(answersTriangles(sphere("[0.5,0.5,3]", "2", true), {2, 3}));  // on the diagonal
  EXPECT_TRUE(answersTriangles(sphere("[1,1,3]", "2", true), kTrianglesAtVertex6));
  EXPECT_TRUE(answersHit(sphere("[1,1,3]", "2"), true));
  EXPECT_TRUE(answersHit(sphere("[1,1,3]", "1.9375"), false));
  // Surface test: a ball inside the cube touches nothing until it reaches the faces.
  EXPECT_TRUE(answersHit(sphere("[0.5,0.5,0.5]", "0.25"), false));
  EXPECT_TRUE(answersTriangles(sphere("[0.5,0.5,0.5]", "0.5", true), {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}));
  EXPECT_TRUE(answersHit(sphere("[0,0,0]", "0"), true));  // a point sphere at a vertex
}

TEST_F(MeshOps, AabbTouchingAnEdgeAndContaining) {
  const auto box = [](const std::string& min, const std::string& max, bool list = false) {
    return op("mesh_aabb", R"("mesh":"cube","aabb":{"min":)" + min + R"(,"max":)" + max + "}" +
                               (list ? R"(,"triangles":true)" : ""));
  };
  // Touches the edge x = y = 1 (vertices 2 and 6): every triangle at vertex 2 or 6.
  EXPECT_TRUE(answersTriangles(box("[1,1,-1]", "[2,2,2]", true), {0, 1, 2, 3, 6, 7, 8, 9}));
  EXPECT_TRUE(answersHit(box("[1,1,-1]", "[2,2,2]"), true));
  EXPECT_TRUE(answersHit(box("[1.0625,1,-1]", "[2,2,2]"), false));
  EXPECT_TRUE(answersHit(box("[-1,-1,-1]", "[2,2,2]"), true));                  // contains the cube
  EXPECT_TRUE(answersHit(box("[0.25,0.25,0.25]", "[0.75,0.75,0.75]"), false));  // inside, not touching
  EXPECT_TRUE(answersTriangles(box("[0.125,0.5,1]", "[0.375,0.875,1]", true), {3}));  // flat, in the top face
  EXPECT_TRUE(answersTriangles(box("[0.25,0.5,1]", "[0.5,0.75,1]", true), {2, 3}));  // corner on the diagonal
}

TEST_F(MeshOps, ObbTouchingAFaceAndRotated) {
  const std::string quarterTurn = R"("axes":[[0,1,0],[-1,0,0],[0,0,1]])";
  // Local x is world y, local y is world -x: half [0.5, 1, 0.5] reaches x = 2 - 1 = 1.
  EXPECT_TRUE(answersHit(
      op("mesh_obb", R"("mesh":"cube","obb":{"center":[2,0.5,0.5],"half":[0.5,1,0.5],)" + quarterTurn + "}"), true));
  EXPECT_TRUE(answersTriangles(op("mesh_obb", R"("mesh":"cube","obb":{"center":[2,0.5,0.5],"half":[0.5,1,0.5],)" +
                                                  quarterTurn + R"(},"triangles":true)"),
                               {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));  // the right face and its edges
  EXPECT_TRUE(answersHit(
      op("mesh_obb", R"("mesh":"cube","obb":{"center":[2,0.5,0.5],"half":[1,0.5,0.5],)" + quarterTurn + "}"), false));
  // Rotated 45 degrees about z, centred at (2,2,0.5): reaches 0.5 or 1.5 towards the edge at
  // distance sqrt(2) ~ 1.41.
  const double s = std::sqrt(0.5);
  std::ostringstream axes;
  axes.precision(17);
  axes << R"("axes":[[)" << s << "," << s << ",0],[" << -s << "," << s << ",0],[0,0,1]]";
  EXPECT_TRUE(answersHit(
      op("mesh_obb", R"("mesh":"cube","obb":{"center":[2,2,0.5],"half":[0.5,0.5,0.5],)" + axes.str() + "}"), false));
  EXPECT_TRUE(answersHit(
      op("mesh_obb", R"("mesh":"cube","obb":{"center":[2,2,0.5],"half":[1.5,0.5,0.5],)" + axes.str() + "}"), true));
}

TEST_F(MeshOps, PlaneThroughAFaceAndTouchingVertices) {
  const auto plane = [](const std::string& normal, const std::string& d) {
    return op("mesh_plane", R"("mesh":"cube","plane":{"normal":)" + normal + R"(,"d":)" + d + R"(},"triangles":true)");
  };
  EXPECT_TRUE(answersTriangles(plane("[0,0,1]", "1"), {2, 3, 4, 5, 6, 7, 8, 9, 10, 11}));  // top + side edges
  EXPECT_TRUE(answersTriangles(plane("[0,0,-3]", "-3"), {2, 3, 4, 5, 6, 7, 8, 9, 10, 11}));  // same plane
  EXPECT_TRUE(answersTriangles(plane("[0,0,1]", "1.5"), {}));
  EXPECT_TRUE(answersTriangles(plane("[1,1,1]", "3"), kTrianglesAtVertex6));
  EXPECT_TRUE(answersTriangles(plane("[1,1,1]", "0"), kTrianglesAtVertex0));
  EXPECT_TRUE(answersTriangles(plane("[1,1,1]", "3.0625"), {}));
  EXPECT_TRUE(answersTriangles(plane("[1,1,1]", "-0.0625"), {}));
  EXPECT_TRUE(answersHit(op("mesh_plane", R"("mesh":"cube","plane":{"normal":[1,1,1],"d":1.5})"), true));
}

TEST_F(MeshOps, TriangleCoplanarWithAFace) {
  const auto tri = [](const std::string& t, bool list = false) {
    return op("mesh_triangle", R"("mesh":"cube","triangle":)" + t + (list ? R"(,"triangles":true)" : ""));
  };
  EXPECT_TRUE(answersHit(tri("[[0.25,0.25,1],[0.75,0.25,1],[0.25,0.75,1]]"), true));     // inside the top face
  EXPECT_TRUE(answersHit(tri("[[2,2,1],[3,2,1],[2,3,1]]"), false));                      // same plane, beside
  EXPECT_TRUE(answersTriangles(tri("[[1,1,1],[2,1,1],[1,2,1]]", true), kTrianglesAtVertex6));  // one vertex
  EXPECT_TRUE(answersHit(tri("[[1.0625,1,1],[2,1,1],[1,2,1]]"), false));
  EXPECT_TRUE(answersHit(tri("[[0,1,1],[1,1,1],[0.5,2,1]]"), true));                     // along a top edge
  EXPECT_TRUE(answersHit(tri("[[0.25,0.25,0.5],[0.75,0.25,0.5],[0.25,0.75,0.5]]"), false));  // inside the cube
  EXPECT_TRUE(answersHit(tri("[[0.5,0.5,0.5],[0.5,0.5,2],[0.5,0.5,1.25]]"), true));      // degenerate, piercing
  EXPECT_TRUE(answersHit(tri("[[0.5,0.5,0.5],[0.5,0.5,0.75],[0.5,0.5,0.625]]"), false));  // degenerate, inside
}

// ---------------------------------------------------------------------------------------------
// mesh_mesh

std::string meshMesh(const std::string& transformA, const std::string& transformB, const std::string& extra = "") {
  std::string fields = R"("a":"cube","b":"cube")";
  if (!transformA.empty()) fields += R"(,"transform_a":)" + transformA;
  if (!transformB.empty()) fields += R"(,"transform_b":)" + transformB;
  return op("mesh_mesh", fields + extra);
}

TEST_F(MeshOps, CubesTouchingAtAFaceUnderTranslations) {
  EXPECT_TRUE(answersHit(meshMesh("", R"({"translation":[1,0,0]})"), true));
  EXPECT_TRUE(answersHit(meshMesh("", R"({"translation":[1.0625,0,0]})"), false));
  EXPECT_TRUE(answersHit(meshMesh("", R"({"translation":[2,0,0]})"), false));
  EXPECT_TRUE(answersHit(meshMesh(R"({"translation":[5,5,5]})", R"({"translation":[5,5,6]})"), true));
  EXPECT_TRUE(answersHit(meshMesh(R"({"translation":[5,5,5]})", R"({"translation":[5,5,6.0625]})"), false));
  EXPECT_TRUE(answersHit(meshMesh(R"({"translation":[-1,-1,-1]})", "{}"), true));  // touching at a vertex
  EXPECT_TRUE(answersHit(meshMesh("", ""), true));                                 // coincident
}

TEST_F(MeshOps, CubesTouchingUnderRotations) {
  // A half turn about z ([w,x,y,z] = [0,0,0,1], exact) maps the cube to [-1,0]x[-1,0]x[0,1];
  // b at [0,1]x[-2,-1]x[0,1] touches it along the edge x = 0, y = -1.
  const std::string halfTurn = R"({"rotation":[0,0,0,1]})";
  EXPECT_TRUE(answersHit(meshMesh(halfTurn, R"({"translation":[0,-2,0]})"), true));
  EXPECT_TRUE(answersHit(meshMesh(halfTurn, R"({"translation":[0.0625,-2,0]})"), false));
  // Half turn plus translation back onto [0,1]^3: b on top touches the face z = 1.
  EXPECT_TRUE(answersHit(meshMesh(R"({"rotation":[0,0,0,1],"translation":[1,1,0]})", R"({"translation":[0,0,1]})"),
                         true));
  // Both turned a quarter about x and b shifted along x: touching at a face whatever the
  // rounding of the quaternion, since the relative transform is a pure translation.
  const double s = std::sqrt(0.5);
  std::ostringstream q;
  q.precision(17);
  q << "[" << s << "," << s << ",0,0]";
  EXPECT_TRUE(answersHit(meshMesh(R"({"rotation":)" + q.str() + "}",
                                  R"({"rotation":)" + q.str() + R"(,"translation":[1,0,0]})"),
                         true));
  EXPECT_TRUE(answersHit(meshMesh(R"({"rotation":)" + q.str() + "}",
                                  R"({"rotation":)" + q.str() + R"(,"translation":[1.0625,0,0]})"),
                         false));
}

TEST_F(MeshOps, QuaternionIsReadAsWXYZ) {
  // [s,0,0,s] is a quarter turn about z: a becomes [-1,0]x[0,1]x[0,1] and crosses b at
  // [-1.5,-0.5]x[0.5,1.5]x[0,1]. Read as [x,y,z,w] it would be a quarter turn about x, giving
  // [0,1]x[-1,0]x[0,1], far from b.
  const double s = std::sqrt(0.5);
  std::ostringstream a;
  a.precision(17);
  a << R"({"rotation":[)" << s << ",0,0," << s << "]}";
  EXPECT_TRUE(answersHit(meshMesh(a.str(), R"({"translation":[-1.5,0.5,0]})"), true));
  EXPECT_TRUE(answersHit(meshMesh(a.str(), R"({"translation":[0.5,-0.5,0]})"), false));
}

TEST_F(MeshOps, CubeInsideABiggerCubeDoesNotTouchItsSurface) {
  ASSERT_EQ(errorOf(ask(op("mesh", R"("name":"big","vertices":[[-1,-1,-1],[2,-1,-1],[2,2,-1],[-1,2,-1],[-1,-1,2],)"
                                   R"([2,-1,2],[2,2,2],[-1,2,2]],"triangles":)" + kCubeTriangles))),
            "");
  EXPECT_TRUE(answersHit(op("mesh_mesh", R"("a":"big","b":"cube")"), false));
  EXPECT_TRUE(answersHit(op("mesh_mesh", R"("a":"cube","b":"big")"), false));
  EXPECT_TRUE(answersHit(op("mesh_mesh", R"("a":"big","b":"cube","transform_b":{"translation":[1,0,0]})"), true));
}

TEST_F(MeshOps, MeshMeshTrianglePairsAreTheTouchingPairs) {
  // Reference: every pair of cube triangles, b's shifted by (1,0,0), by the geometry layer.
  const Mesh& cube = *state_.meshes.at("cube");
  std::vector<std::vector<std::uint32_t>> expected;
  for (std::uint32_t i = 0; i < 12; ++i)
    for (std::uint32_t j = 0; j < 12; ++j) {
      Triangle b = cube.triangle(j);
      for (Vec3* p : {&b.a, &b.b, &b.c}) p->x() += 1;
      if (overlaps(cube.triangle(i), b)) expected.push_back({i, j});
    }
  ASSERT_FALSE(expected.empty());
  const Answer a = ask(meshMesh("", R"({"translation":[1,0,0]})", R"(,"triangles":true)"));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_EQ(a["triangles"].get<std::vector<std::vector<std::uint32_t>>>(), expected) << a.dump();
  // Right face of a (6, 7) against left face of b (10, 11): all four pairs touch.
  for (const auto& pair : {std::vector<std::uint32_t>{6, 10}, {6, 11}, {7, 10}, {7, 11}})
    EXPECT_NE(std::find(expected.begin(), expected.end(), pair), expected.end());
  EXPECT_EQ(ask(meshMesh("", R"({"translation":[3,0,0]})", R"(,"triangles":true)")).dump(),
            R"({"id":"q","op":"mesh_mesh","hit":false,"triangles":[]})");
}

// ---------------------------------------------------------------------------------------------
// Errors shared by the mesh queries

TEST_F(MeshOps, UnknownMeshNamesTheFieldAndTheName) {
  EXPECT_TRUE(errorStartsWith(op("mesh_ray", R"("mesh":"nope","ray":{"origin":[0,0,0],"dir":[1,0,0]})"),
                              R"(mesh: no mesh named "nope")"));
  for (const std::string& q : {std::string(R"("segment":{"start":[0,0,0],"end":[1,0,0]})"),
                               std::string(R"("sphere":{"center":[0,0,0],"radius":1})")}) {
    const std::string name = q.find("segment") != std::string::npos ? "mesh_segment" : "mesh_sphere";
    EXPECT_TRUE(errorStartsWith(op(name, R"("mesh":"Cube",)" + q), R"(mesh: no mesh named "Cube")"));
  }
  EXPECT_TRUE(errorStartsWith(op("mesh_mesh", R"("a":"cube","b":"nope")"), R"(b: no mesh named "nope")"));
  EXPECT_TRUE(errorStartsWith(op("mesh_mesh", R"("a":"x\"y","b":"cube")"), R"(a: no mesh named "x\"y")"));
  EXPECT_TRUE(errorStartsWith(op("mesh_aabb", R"("mesh":3,"aabb":{"min":[0,0,0],"max":[1,1,1]})"),
                              "mesh: expected a mesh name (string), got number"));
  EXPECT_TRUE(errorStartsWith(op("mesh_plane", R"("plane":{"normal":[0,0,1],"d":0})"), "mesh: missing field"));
  EXPECT_TRUE(errorStartsWith(op("mesh_mesh", R"("a":"cube")"), "b: missing field"));
}

TEST_F(MeshOps, SyntaxErrorsWinOverUnknownMeshes) {
  EXPECT_TRUE(errorStartsWith(op("mesh_sphere", R"("mesh":"nope","sphere":{"center":[0,0]})"),
                              "sphere.center: expected [x, y, z]"));
  EXPECT_TRUE(errorStartsWith(op("mesh_obb", R"("mesh":"nope")"), "obb: missing field"));
}

TEST_F(MeshOps, ShapeValidationNamesTheField) {
  EXPECT_TRUE(errorStartsWith(op("mesh_sphere", R"("mesh":"cube","sphere":{"center":[0,0,0],"radius":-1})"),
                              "sphere.radius is negative"));
  EXPECT_TRUE(errorStartsWith(op("mesh_ray", ray("[0,0,0]", "[0,0,0]")), "ray.dir is the zero vector"));
  EXPECT_TRUE(errorStartsWith(op("mesh_aabb", R"("mesh":"cube","aabb":{"min":[0,2,0],"max":[1,1,1]})"),
                              "aabb.min.y > aabb.max.y"));
  EXPECT_TRUE(errorStartsWith(
      op("mesh_obb", R"("mesh":"cube","obb":{"center":[0,0,0],"half":[1,1,1],"axes":[[1,0,0],[1,1,0],[0,0,1]]})"),
      "obb.axes are not orthonormal"));
  EXPECT_TRUE(errorStartsWith(op("mesh_plane", R"("mesh":"cube","plane":{"normal":[0,0,0],"d":1})"),
                              "plane.normal is the zero vector"));
  EXPECT_TRUE(errorStartsWith(op("mesh_triangle", R"("mesh":"cube","triangle":[[0,0,0],[1,0,0]])"),
                              "triangle: expected a triangle"));
  EXPECT_TRUE(errorStartsWith(op("mesh_segment", R"("mesh":"cube","segment":{"start":[0,0,0]})"),
                              "segment.end: missing field"));
}

TEST_F(MeshOps, OptionalFieldsAreTypeChecked) {
  const std::string r = ray("[0.5,0.5,5]", "[0,0,-1]");
  EXPECT_TRUE(errorStartsWith(op("mesh_ray", r + R"(,"max":-1)"), "max is negative: -1"));
  EXPECT_TRUE(errorStartsWith(op("mesh_ray", r + R"(,"max":"far")"), "max: expected a number, got string"));
  EXPECT_TRUE(errorStartsWith(op("mesh_ray", r + R"(,"max":1e400)"), "max: number 1e400 overflows double"));
  EXPECT_TRUE(errorStartsWith(op("mesh_ray", r + R"(,"all":1)"), "all: expected true or false, got number"));
  EXPECT_TRUE(errorStartsWith(op("mesh_ray", r + R"(,"cull":"yes")"), "cull: expected true or false, got string"));
  EXPECT_TRUE(errorStartsWith(op("mesh_sphere", R"("mesh":"cube","sphere":{"center":[0,0,0],"radius":1},"triangles":null)"),
                              "triangles: expected true or false, got null"));
  EXPECT_TRUE(answersHit(op("mesh_sphere", R"("mesh":"cube","sphere":{"center":[0,0,0],"radius":1},"triangles":false)"),
                         true));
}

TEST_F(MeshOps, TransformsAreValidated) {
  EXPECT_TRUE(errorStartsWith(meshMesh(R"({"rotation":[1,1,0,0]})", ""),
                              "transform_a.rotation: not a unit quaternion (|q| = 1.4142135623730951, tolerance 1e-06)"));
  EXPECT_TRUE(errorStartsWith(meshMesh("", R"({"rotation":[0,0,0,0]})"),
                              "transform_b.rotation: not a unit quaternion (|q| = 0.0"));
  EXPECT_TRUE(errorStartsWith(meshMesh("", R"({"rotation":[1.000002,0,0,0]})"),
                              "transform_b.rotation: not a unit quaternion"));
  EXPECT_TRUE(errorStartsWith(meshMesh("", R"({"rotation":[1,0,0]})"),
                              "transform_b.rotation: expected a unit quaternion [w, x, y, z], got an array of 3 elements"));
  EXPECT_TRUE(errorStartsWith(meshMesh(R"({"rotation":[1,0,"0",0]})", ""),
                              "transform_a.rotation[2]: expected a number, got string"));
  EXPECT_TRUE(errorStartsWith(meshMesh(R"({"rotation":[1,0,0,1e400]})", ""),
                              "transform_a.rotation[3]: number 1e400 overflows double"));
  EXPECT_TRUE(errorStartsWith(meshMesh("", R"({"translation":[1,0]})"),
                              "transform_b.translation: expected [x, y, z], got an array of 2 elements"));
  EXPECT_TRUE(errorStartsWith(meshMesh("[1,0,0]", ""), "transform_a: expected a transform"));
  EXPECT_TRUE(errorStartsWith(meshMesh("null", ""), "transform_a: expected a transform"));
  // Within the tolerance: accepted (and normalised).
  EXPECT_TRUE(answersHit(meshMesh(R"({"rotation":[1.0000005,0,0,0],"translation":[0,0,1]})", ""), true));
  EXPECT_TRUE(answersHit(meshMesh(R"({"rotation":[0.7071068,0,0,0.7071068]})", R"({"translation":[-1.5,0.5,0]})"),
                         true));
}

TEST(MeshOpsTransform, ReadTransformDefaultsAndNormalises) {
  const Transform identity = readTransform(Json::object(), "t");
  EXPECT_EQ(identity.rotation.coeffs(), Quat::Identity().coeffs());
  EXPECT_EQ(identity.translation, Vec3::Zero());
  const Transform t = readTransform(Json::parse(R"({"rotation":[0,0,0,1.0000005],"translation":[1,2,3]})"), "t");
  EXPECT_EQ(t.translation, Vec3(1, 2, 3));
  EXPECT_NEAR(double(t.rotation.norm()), 1.0, 4 * std::numeric_limits<Real>::epsilon());
  EXPECT_TRUE(t.apply(Vec3(1, 0, 0)).isApprox(Vec3(0, 2, 3)));  // half turn about z, then translate
}

// `crux import-mesh BUDGET PATH` (isolated mesh loading's import command) refuses a BUDGET that is
// not a byte count before importing anything, naming it.
TEST(ImportMeshCommand, ABudgetThatIsNotAByteCountIsRefused) {
  for (const std::string budget : {"", "12x", "-1", "1e9", "abc"}) {
    std::ostringstream err;
    EXPECT_EQ(runImportMesh(budget, "/nonexistent/mesh.obj", err), 2) << budget;
    EXPECT_NE(err.str().find("BUDGET must be a byte count, got \"" + budget + "\""), std::string::npos) << err.str();
  }
}

}  // namespace
}  // namespace crux::cli
