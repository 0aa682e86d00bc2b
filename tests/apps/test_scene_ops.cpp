// Tests of the batch protocol's model and scene ops (apps/cli/scene_ops.cpp, docs/batch.md) on
// hand-checked unit cubes: add_model with transforms and parents, set_transform moving a whole
// subtree, set_parent keeping the world pose (null detaches, cycles rejected), remove_model
// re-parenting children, children (all levels, sorted names), every model_* query in world
// space, scene_ray (closest model), scene_query (exact and bounds-only), scene_pairs (sorted
// names, parent/child pairs included), name reuse, and every error path.

#include "apps/batch_test_util.hpp"
#include "cli/batch.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace crux::cli {
namespace {

using test::errorOf;
using test::isPoint;

const std::string kCubeVertices = "[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]]";
const std::string kCubeTriangles =
    "[[0,2,1],[0,3,2],[4,5,6],[4,6,7],[0,1,5],[0,5,4],[1,2,6],[1,6,5],[2,3,7],[2,7,6],[3,0,4],[3,4,7]]";

std::string op(const std::string& name, const std::string& fields) {
  return R"({"id":"q","op":")" + name + R"(")" + (fields.empty() ? "" : "," + fields) + "}";
}
std::string at(double x, double y, double z) {
  return R"({"translation":[)" + std::to_string(x) + "," + std::to_string(y) + "," + std::to_string(z) + "]}";
}

/// A batch with the unit cube "cube" and models a (at the origin), b (at x = 2), and c, a child
/// of a placed 2 above it.
class SceneOps : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(ask(op("mesh", R"("name":"cube","vertices":)" + kCubeVertices + R"(,"triangles":)" + kCubeTriangles))
                  .dump(),
              R"({"id":"q","op":"mesh","triangles":12})");
    ASSERT_TRUE(ok(op("add_model", R"("name":"a","mesh":"cube")")));
    ASSERT_TRUE(ok(op("add_model", R"("name":"b","mesh":"cube","transform":)" + at(2, 0, 0))));
    ASSERT_TRUE(ok(op("add_model", R"("name":"c","mesh":"cube","parent":"a","transform":)" + at(0, 0, 2))));
  }

  Answer ask(const std::string& line) { return answerLine(line, state_); }

  ::testing::AssertionResult ok(const std::string& line) {
    const Answer a = ask(line);
    if (a.contains("ok") && a["ok"] == true && !a.contains("error")) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << a.dump() << " to " << line;
  }
  ::testing::AssertionResult hit(const std::string& line, bool expected) {
    const Answer a = ask(line);
    if (!errorOf(a).empty() || !a.contains("hit")) return ::testing::AssertionFailure() << a.dump() << " to " << line;
    if (a["hit"].get<bool>() != expected)
      return ::testing::AssertionFailure() << "hit " << a["hit"] << " expected " << expected << " for " << line;
    return ::testing::AssertionSuccess();
  }
  std::vector<std::string> models(const std::string& line) {
    const Answer a = ask(line);
    EXPECT_TRUE(errorOf(a).empty()) << a.dump();
    return a.value("models", std::vector<std::string>{"<none>"});
  }
  ::testing::AssertionResult error(const std::string& line, const std::string& expected) {
    const Answer a = ask(line);
    if (errorOf(a) != expected)
      return ::testing::AssertionFailure() << "answer " << a.dump() << " to " << line << ", expected error '"
                                           << expected << "'";
    if (a.size() != 3) return ::testing::AssertionFailure() << "error answer carries results: " << a.dump();
    return ::testing::AssertionSuccess();
  }
  /// World translation of a model, read back through a model_ray straight down onto its top
  /// face at local (0.25, 0.75).
  ::testing::AssertionResult topAt(const std::string& model, double x, double y, double zTop) {
    const Answer a = ask(op("model_ray", R"("model":")" + model + R"(","ray":{"origin":[)" + std::to_string(x + 0.25) +
                                             "," + std::to_string(y + 0.75) + R"(,50],"dir":[0,0,-1]})"));
    if (!a.value("hit", false)) return ::testing::AssertionFailure() << a.dump();
    return isPoint(a["point"], x + 0.25, y + 0.75, zTop);
  }

  BatchState state_;
};

// ---------------------------------------------------------------------------------------------
// Editing

TEST_F(SceneOps, ModelsArePlacedByParentThenLocalTransforms) {
  EXPECT_TRUE(topAt("a", 0, 0, 1));
  EXPECT_TRUE(topAt("b", 2, 0, 1));
  EXPECT_TRUE(topAt("c", 0, 0, 3));
  EXPECT_EQ(state_.scene.size(), 3u);
  EXPECT_EQ(state_.models.size(), 3u);
}

TEST_F(SceneOps, SetTransformMovesTheModelAndItsDescendants) {
  ASSERT_TRUE(ok(op("add_model", R"("name":"d","mesh":"cube","parent":"c","transform":)" + at(1, 0, 0))));
  ASSERT_TRUE(ok(op("set_transform", R"("model":"a","transform":)" + at(10, 0, 0))));
  EXPECT_TRUE(topAt("a", 10, 0, 1));
  EXPECT_TRUE(topAt("c", 10, 0, 3));
  EXPECT_TRUE(topAt("d", 11, 0, 3));
  EXPECT_TRUE(topAt("b", 2, 0, 1));
  // A quarter turn about z (rotation [cos 45°, 0, 0, sin 45°]): c's local (0, 0, 2) stays above a.
  ASSERT_TRUE(ok(op("set_transform",
                    R"("model":"a","transform":{"translation":[10,0,0],"rotation":[0.7071067811865476,0,0,0.7071067811865476]})")));
  EXPECT_TRUE(hit(op("model_sphere", R"("model":"c","sphere":{"center":[9.5,0.5,3.5],"radius":0.5})"), true));
  EXPECT_TRUE(hit(op("model_sphere", R"("model":"c","sphere":{"center":[10.5,0.5,3.5],"radius":0.4})"), false));
  EXPECT_TRUE(ok(op("set_transform", R"("model":"a","transform":{})")));  // identity
  EXPECT_TRUE(topAt("c", 0, 0, 3));
}

TEST_F(SceneOps, SetParentKeepsTheWorldPoseAndNullDetaches) {
  ASSERT_TRUE(ok(op("set_parent", R"("model":"b","parent":"c")")));  // b stays at x = 2
  EXPECT_TRUE(topAt("b", 2, 0, 1));
  EXPECT_EQ(models(op("children", R"("model":"a")")), (std::vector<std::string>{"b", "c"}));
  ASSERT_TRUE(ok(op("set_transform", R"("model":"a","transform":)" + at(0, 5, 0))));
  EXPECT_TRUE(topAt("b", 2, 5, 1));  // moved with its new grandparent
  ASSERT_TRUE(ok(op("set_parent", R"("model":"b","parent":null)")));
  ASSERT_TRUE(ok(op("set_transform", R"("model":"a","transform":{})")));
  EXPECT_TRUE(topAt("b", 2, 5, 1));  // detached: a no longer moves it
  EXPECT_EQ(models(op("children", R"("model":"a")")), (std::vector<std::string>{"c"}));
}

TEST_F(SceneOps, CyclesAreRejected) {
  EXPECT_TRUE(error(op("set_parent", R"("model":"a","parent":"a")"), R"(parent: "a" is the model itself (a cycle))"));
  EXPECT_TRUE(error(op("set_parent", R"("model":"a","parent":"c")"), R"(parent: "c" descends from "a" (a cycle))"));
  ASSERT_TRUE(ok(op("add_model", R"("name":"g","mesh":"cube","parent":"c")")));
  EXPECT_TRUE(error(op("set_parent", R"("model":"a","parent":"g")"), R"(parent: "g" descends from "a" (a cycle))"));
  EXPECT_TRUE(topAt("a", 0, 0, 1));  // unchanged
  EXPECT_EQ(models(op("children", R"("model":"a")")), (std::vector<std::string>{"c", "g"}));
}

TEST_F(SceneOps, RemoveModelReparentsChildrenKeepingTheirPose) {
  ASSERT_TRUE(ok(op("add_model", R"("name":"root","mesh":"cube","transform":)" + at(0, 0, -5))));
  ASSERT_TRUE(ok(op("set_parent", R"("model":"a","parent":"root")")));
  ASSERT_TRUE(ok(op("remove_model", R"("model":"a")")));
  EXPECT_TRUE(topAt("c", 0, 0, 3));
  EXPECT_EQ(models(op("children", R"("model":"root")")), (std::vector<std::string>{"c"}));
  ASSERT_TRUE(ok(op("set_transform", R"("model":"root","transform":)" + at(0, 0, -4))));
  EXPECT_TRUE(topAt("c", 0, 0, 4));  // c now follows root
  EXPECT_TRUE(error(op("model_ray", R"("model":"a","ray":{"origin":[0,0,5],"dir":[0,0,-1]})"),
                    R"(model: no model named "a" (add it first with add_model))"));
  // The name and (internally) the id can be used again.
  ASSERT_TRUE(ok(op("add_model", R"("name":"a","mesh":"cube","transform":)" + at(7, 7, 0))));
  EXPECT_TRUE(topAt("a", 7, 7, 1));
  const Answer r = ask(op("scene_ray", R"("ray":{"origin":[7.5,7.5,9],"dir":[0,0,-1]})"));
  EXPECT_EQ(r.value("model", ""), "a") << r.dump();
}

TEST_F(SceneOps, ChildrenListsEveryDescendantSortedByName) {
  ASSERT_TRUE(ok(op("add_model", R"("name":"zz","mesh":"cube","parent":"c")")));
  ASSERT_TRUE(ok(op("add_model", R"("name":"b2","mesh":"cube","parent":"zz")")));
  ASSERT_TRUE(ok(op("add_model", R"("name":"Q","mesh":"cube","parent":"a")")));
  EXPECT_EQ(models(op("children", R"("model":"a")")), (std::vector<std::string>{"Q", "b2", "c", "zz"}));
  EXPECT_EQ(models(op("children", R"("model":"zz")")), (std::vector<std::string>{"b2"}));
  EXPECT_EQ(models(op("children", R"("model":"b")")), (std::vector<std::string>{}));
}

TEST_F(SceneOps, ModelsKeepTheirMeshWhenItsNameIsRedefined) {
  ASSERT_EQ(errorOf(ask(op("mesh", R"("name":"cube","vertices":[[0,0,0],[1,0,0],[0,1,0]],"triangles":[[0,1,2]])"))), "");
  EXPECT_TRUE(topAt("a", 0, 0, 1));  // still the cube
  ASSERT_TRUE(ok(op("add_model", R"("name":"flat","mesh":"cube","transform":)" + at(20, 0, 0))));
  EXPECT_TRUE(hit(op("model_aabb", R"("model":"flat","aabb":{"min":[20,0,0.5],"max":[21,1,1]})"), false));
}

// ---------------------------------------------------------------------------------------------
// Model queries (world space)

TEST_F(SceneOps, ModelRayReportsWorldHits) {
  const Answer a = ask(op("model_ray", R"("model":"c","ray":{"origin":[0.5,0.25,10],"dir":[0,0,-2]})"));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_EQ(a["t"].get<double>(), 7.0);  // top of c at z = 3
  EXPECT_TRUE(isPoint(a["point"], 0.5, 0.25, 3));
  EXPECT_TRUE(isPoint(a["normal"], 0, 0, 1));
  EXPECT_EQ(a["triangle"], 2);  // top face, x >= y half
  EXPECT_TRUE(hit(op("model_ray", R"("model":"c","ray":{"origin":[0.5,0.25,10],"dir":[0,0,-2]},"max":6.5)"), false));
  EXPECT_TRUE(hit(op("model_ray", R"("model":"c","ray":{"origin":[0.5,0.25,10],"dir":[0,0,-2]},"max":7)"), true));
  const Answer all = ask(op("model_ray", R"("model":"b","ray":{"origin":[2.5,0.25,10],"dir":[0,0,-1]},"all":true)"));
  ASSERT_EQ(all["hits"].size(), 2u) << all.dump();
  EXPECT_EQ(all["hits"][1]["t"].get<double>(), 10.0);
  const Answer culled =
      ask(op("model_ray", R"("model":"b","ray":{"origin":[2.5,0.25,0.5],"dir":[0,0,-1]},"cull":true)"));
  EXPECT_FALSE(culled.value("hit", true)) << culled.dump();  // from inside: only back faces ahead
}

TEST_F(SceneOps, ModelShapeQueriesTouchInWorldSpace) {
  // c occupies [0,1]x[0,1]x[2,3].
  EXPECT_TRUE(hit(op("model_sphere", R"("model":"c","sphere":{"center":[0.5,0.5,4],"radius":1})"), true));
  EXPECT_TRUE(hit(op("model_sphere", R"("model":"c","sphere":{"center":[0.5,0.5,4],"radius":0.99})"), false));
  EXPECT_TRUE(hit(op("model_aabb", R"("model":"c","aabb":{"min":[1,1,3],"max":[2,2,4]})"), true));  // corner
  EXPECT_TRUE(hit(op("model_aabb", R"("model":"c","aabb":{"min":[0.2,0.2,2.2],"max":[0.8,0.8,2.8]})"), false));
  EXPECT_TRUE(hit(op("model_obb", R"("model":"c","obb":{"center":[2,0.5,2.5],"half":[1,0.1,0.1],"axes":[[0,1,0],[1,0,0],[0,0,1]]})"),
                  false));
  EXPECT_TRUE(hit(op("model_obb", R"("model":"c","obb":{"center":[2,0.5,2.5],"half":[0.1,1,0.1],"axes":[[0,1,0],[1,0,0],[0,0,1]]})"),
                  true));
  EXPECT_TRUE(hit(op("model_plane", R"("model":"c","plane":{"normal":[0,0,2],"d":6})"), true));  // z = 3
  EXPECT_TRUE(hit(op("model_plane", R"("model":"c","plane":{"normal":[0,0,1],"d":3.5})"), false));
  EXPECT_TRUE(hit(op("model_triangle", R"("model":"c","triangle":[[1,1,3],[2,1,3],[1,2,4]])"), true));
  EXPECT_TRUE(hit(op("model_triangle", R"("model":"c","triangle":[[0,0,1],[1,0,1],[0,1,1]])"), false));
  EXPECT_TRUE(hit(op("model_segment", R"("model":"c","segment":{"start":[0.5,0.5,5],"end":[0.5,0.5,3]})"), true));
  EXPECT_TRUE(hit(op("model_segment", R"("model":"c","segment":{"start":[0.5,0.5,2.5],"end":[0.6,0.5,2.5]})"), false));
}

// ---------------------------------------------------------------------------------------------
// Scene queries

TEST_F(SceneOps, SceneRayReportsTheClosestModel) {
  // From above a: c (top at z = 3) hides a (top at z = 1).
  const Answer a = ask(op("scene_ray", R"("ray":{"origin":[0.5,0.5,10],"dir":[0,0,-1]})"));
  EXPECT_EQ(a.value("model", ""), "c") << a.dump();
  EXPECT_EQ(a["t"].get<double>(), 7.0);
  const Answer below = ask(op("scene_ray", R"("ray":{"origin":[0.5,0.5,-10],"dir":[0,0,1]})"));
  EXPECT_EQ(below.value("model", ""), "a") << below.dump();
  const Answer side = ask(op("scene_ray", R"("ray":{"origin":[10,0.5,0.5],"dir":[-1,0,0]})"));
  EXPECT_EQ(side.value("model", ""), "b") << side.dump();
  EXPECT_TRUE(isPoint(side["point"], 3, 0.5, 0.5));
  EXPECT_TRUE(isPoint(side["normal"], 1, 0, 0));
  EXPECT_TRUE(hit(op("scene_ray", R"("ray":{"origin":[10,0.5,0.5],"dir":[-1,0,0]},"max":6.9)"), false));
  EXPECT_TRUE(hit(op("scene_ray", R"("ray":{"origin":[10,0.5,0.5],"dir":[1,0,0]})"), false));
  const Answer miss = ask(op("scene_ray", R"("ray":{"origin":[10,0.5,0.5],"dir":[1,0,0]})"));
  EXPECT_EQ(miss.size(), 3u) << miss.dump();  // id, op, hit
}

TEST_F(SceneOps, SceneQueryExactAndBoundsOnly) {
  // Sphere in the gap between a and b touching both faces: x = 1 and x = 2.
  EXPECT_EQ(models(op("scene_query", R"("sphere":{"center":[1.5,0.5,0.5],"radius":0.5})")),
            (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(models(op("scene_query", R"("sphere":{"center":[1.5,0.5,0.5],"radius":0.49})")),
            (std::vector<std::string>{}));
  // A box inside a touches no triangle, but a's bounds.
  EXPECT_EQ(models(op("scene_query", R"("aabb":{"min":[0.25,0.25,0.25],"max":[0.75,0.75,0.75]})")),
            (std::vector<std::string>{}));
  EXPECT_EQ(models(op("scene_query", R"("aabb":{"min":[0.25,0.25,0.25],"max":[0.75,0.75,0.75]},"bounds":true)")),
            (std::vector<std::string>{"a"}));
  EXPECT_EQ(models(op("scene_query", R"("obb":{"center":[1,0.5,2],"half":[1.5,0.1,0.1],"axes":[[1,0,0],[0,1,0],[0,0,1]]})")),
            (std::vector<std::string>{"c"}));
  // A solid box containing the models contains their triangles: they touch it.
  EXPECT_EQ(models(op("scene_query", R"("aabb":{"min":[-5,-5,-5],"max":[5,5,5]},"bounds":false)")),
            (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(models(op("scene_query", R"("aabb":{"min":[-5,-5,-5],"max":[5,5,5]},"bounds":true)")),
            (std::vector<std::string>{"a", "b", "c"}));
}

TEST_F(SceneOps, ScenePairsAreSortedNamePairsIncludingParentAndChild) {
  EXPECT_EQ(ask(op("scene_pairs", "")).dump(), R"({"id":"q","op":"scene_pairs","pairs":[]})");
  ASSERT_TRUE(ok(op("set_transform", R"("model":"c","transform":)" + at(0, 0, 1))));   // c on top of its parent a
  ASSERT_TRUE(ok(op("add_model", R"("name":"Zed","mesh":"cube","transform":)" + at(1, 0, 0))));  // between a and b
  EXPECT_EQ(ask(op("scene_pairs", "")).dump(),
            R"({"id":"q","op":"scene_pairs","pairs":[["Zed","a"],["Zed","b"],["Zed","c"],["a","c"]]})");
}

// ---------------------------------------------------------------------------------------------
// Errors

TEST_F(SceneOps, EditErrorsNameTheField) {
  EXPECT_TRUE(error(op("add_model", R"("name":"a","mesh":"cube")"),
                    R"(name: a model named "a" already exists (remove_model it first))"));
  EXPECT_TRUE(error(op("add_model", R"("name":"","mesh":"cube")"), "name: a model name must not be empty"));
  EXPECT_TRUE(error(op("add_model", R"("name":"n","mesh":"ball")"),
                    R"(mesh: no mesh named "ball" (define it first with mesh or load_mesh))"));
  EXPECT_TRUE(error(op("add_model", R"("name":"n","mesh":"cube","parent":"p")"),
                    R"(parent: no model named "p" (add it first with add_model))"));
  EXPECT_TRUE(error(op("add_model", R"("name":"n","mesh":"cube","parent":3)"),
                    "parent: expected a model name (string) or null, got number"));
  EXPECT_TRUE(error(op("add_model", R"("name":5,"mesh":"cube")"), "name: expected a model name (string), got number"));
  EXPECT_TRUE(error(op("add_model", R"("name":"n")"), "mesh: missing field"));
  EXPECT_TRUE(error(op("add_model", R"("name":"n","mesh":"cube","transform":{"rotation":[1,1,0,0]})"),
                    "transform.rotation: not a unit quaternion (|q| = 1.4142135623730951, tolerance 1e-06)"));
  EXPECT_TRUE(error(op("set_transform", R"("model":"a")"), "transform: missing field"));
  EXPECT_TRUE(error(op("set_transform", R"("model":"x","transform":{})"),
                    R"(model: no model named "x" (add it first with add_model))"));
  EXPECT_TRUE(error(op("set_parent", R"("model":"a")"), "parent: missing field"));
  EXPECT_TRUE(error(op("set_parent", R"("model":"a","parent":[1])"),
                    "parent: expected a model name (string) or null, got array"));
  EXPECT_TRUE(error(op("remove_model", ""), "model: missing field"));
  EXPECT_TRUE(error(op("children", R"("model":"nobody")"),
                    R"(model: no model named "nobody" (add it first with add_model))"));
  EXPECT_EQ(state_.scene.size(), 3u);  // nothing was added or changed
}

TEST_F(SceneOps, QueryErrorsNameTheField) {
  EXPECT_TRUE(error(op("model_sphere", R"("model":"a","sphere":{"center":[0,0,0],"radius":-1})"),
                    "sphere.radius is negative: -1"));
  EXPECT_TRUE(error(op("model_ray", R"("model":"a","ray":{"origin":[0,0,0],"dir":[0,0,0]})"), "ray.dir is the zero vector"));
  EXPECT_TRUE(error(op("model_ray", R"("model":"a","ray":{"origin":[0,0,0],"dir":[0,0,1]},"max":-1)"), "max is negative: -1"));
  EXPECT_TRUE(error(op("model_plane", R"("model":"a")"), "plane: missing field"));
  EXPECT_TRUE(error(op("scene_ray", R"("ray":{"origin":[0,0,0],"dir":[0,0,1]},"max":-2)"), "max is negative: -2"));
  EXPECT_TRUE(error(op("scene_ray", "\"max\":1"), "ray: missing field"));
  EXPECT_TRUE(error(op("scene_query", ""), "sphere: missing field (scene_query needs one of sphere, aabb, obb)"));
  EXPECT_TRUE(error(op("scene_query", R"("sphere":{"center":[0,0,0],"radius":1},"obb":{})"),
                    "obb: only one of sphere, aabb, obb may be given (got sphere and obb)"));
  EXPECT_TRUE(error(op("scene_query", R"("aabb":{"min":[0,2,0],"max":[1,1,1]})"),
                    "aabb.min.y > aabb.max.y: min [0, 2, 0], max [1, 1, 1]"));
  EXPECT_TRUE(error(op("scene_query", R"("sphere":{"center":[0,0,0],"radius":1},"bounds":1)"),
                    "bounds: expected true or false, got number"));
}

TEST(SceneOpsEmpty, AnEmptySceneAnswersEmpty) {
  BatchState state;
  EXPECT_EQ(answerLine(R"({"op":"scene_ray","ray":{"origin":[0,0,0],"dir":[1,0,0]}})", state).dump(),
            R"({"op":"scene_ray","hit":false})");
  EXPECT_EQ(answerLine(R"({"op":"scene_query","sphere":{"center":[0,0,0],"radius":1}})", state).dump(),
            R"({"op":"scene_query","models":[]})");
  EXPECT_EQ(answerLine(R"({"op":"scene_pairs"})", state).dump(), R"({"op":"scene_pairs","pairs":[]})");
}

}  // namespace
}  // namespace crux::cli
