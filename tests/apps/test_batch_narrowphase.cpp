// `crux batch`: the narrow-phase and volume ops (apps/cli/narrowphase_ops.cpp, the "volume" flag
// of apps/cli/mesh_ops.cpp; docs/batch.md "Contacts, distance and volumes"): round trips of every
// op on hand-checked cases, the operand encodings, errors naming their field, unsupported ops per
// backend, and the same answers through the world API.

#include "apps/batch_test_util.hpp"
#include "cli/batch.hpp"

#include <crux/world/collision_world.hpp>
#include <world_factory.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace crux::cli {
namespace {

using test::errorOf;
using test::isPoint;

/// The unit cube [0,1]^3, 12 outward counter-clockwise triangles (top face: triangles 2, 3).
const std::string kCube =
    R"({"op":"mesh","name":"cube","vertices":[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]],)"
    R"("triangles":[[0,2,1],[0,3,2],[4,5,6],[4,6,7],[0,1,5],[0,5,4],[1,2,6],[1,6,5],[2,3,7],[2,7,6],[3,0,4],[3,4,7]]})";
const std::string kQuad =
    R"({"op":"mesh","name":"quad","vertices":[[0,0,0],[1,0,0],[1,1,0],[0,1,0]],"triangles":[[0,1,2],[0,2,3]]})";
const std::string kAxes = R"("axes":[[1,0,0],[0,1,0],[0,0,1]])";

/// A closed cube [0.25,0.75]^3 wholly inside kCube.
const std::string kSmallCube =
    R"({"op":"mesh","name":"small","vertices":[[0.25,0.25,0.25],[0.75,0.25,0.25],[0.75,0.75,0.25],[0.25,0.75,0.25],)"
    R"([0.25,0.25,0.75],[0.75,0.25,0.75],[0.75,0.75,0.75],[0.25,0.75,0.75]],)"
    R"("triangles":[[0,2,1],[0,3,2],[4,5,6],[4,6,7],[0,1,5],[0,5,4],[1,2,6],[1,6,5],[2,3,7],[2,7,6],[3,0,4],[3,4,7]]})";

/// A batch with the cube and the open quad defined.
struct Batch {
  BatchState state;
  explicit Batch(Backend backend = Backend::Native) : state(BatchOptions{backend, 1}) {
    EXPECT_EQ(errorOf(answerLine(kCube, state)), "");
    EXPECT_EQ(errorOf(answerLine(kQuad, state)), "");
  }
  Answer ask(const std::string& line) { return answerLine(line, state); }
};

bool built(std::string_view backend) {
  const auto& b = builtBackends();
  return std::find(b.begin(), b.end(), backend) != b.end();
}

TEST(BatchNarrowPhase, ContactsOfABoxOnTheCube) {
  Batch b;
  // A box of half extents 0.25, 0.25, 0.5 whose bottom face is 0.125 inside the cube's top.
  const std::string box = R"({"box":{"center":[0.5,0.5,1.375],"half":[0.25,0.25,0.5],)" + kAxes + "}}";
  const Answer a = b.ask(R"({"id":"c","op":"contacts","a":{"mesh":"cube"},"b":)" + box + "}");
  ASSERT_EQ(errorOf(a), "") << a.dump();
  EXPECT_EQ(a["id"], "c");
  ASSERT_EQ(a["contacts"].size(), 4u) << a.dump();
  for (const auto& c : a["contacts"]) {
    EXPECT_TRUE(isPoint(c["normal"], 0, 0, -1)) << c.dump();  // from B (the box, above) to A
    EXPECT_NEAR(c["depth"].get<double>(), 0.125, 1e-6);
    EXPECT_NEAR(c["point_a"][2].get<double>(), 1, 1e-6);
    EXPECT_NEAR(c["point_b"][2].get<double>(), 0.875, 1e-6);
    const auto triangle = c["feature_a"].get<int>();
    EXPECT_TRUE(triangle == 2 || triangle == 3) << c.dump();
    EXPECT_TRUE(c["feature_b"].is_number_integer()) << c.dump();
  }
  // Swapped: same points swapped, normal up.
  const Answer s = b.ask(R"({"op":"contacts","a":)" + box + R"(,"b":{"mesh":"cube"}})");
  ASSERT_EQ(s["contacts"].size(), 4u) << s.dump();
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(s["contacts"][i]["point_a"], a["contacts"][i]["point_b"]);
    EXPECT_TRUE(isPoint(s["contacts"][i]["normal"], 0, 0, 1));
    EXPECT_EQ(s["contacts"][i]["feature_b"], a["contacts"][i]["feature_a"]);
  }
  // A transform on the mesh operand: the cube lifted by 2 no longer touches the box ...
  EXPECT_EQ(b.ask(R"({"op":"contacts","a":{"mesh":"cube","transform":{"translation":[0,0,2]}},"b":)" + box + "}")
                ["contacts"]
                .size(),
            0u);
  // ... and a margin reports speculative contacts (depth < 0) 0.125 apart.
  const std::string above = R"({"box":{"center":[0.5,0.5,1.625],"half":[0.25,0.25,0.5],)" + kAxes + "}}";
  EXPECT_EQ(b.ask(R"({"op":"contacts","a":{"mesh":"cube"},"b":)" + above + "}")["contacts"].size(), 0u);
  const Answer m = b.ask(R"({"op":"contacts","a":{"mesh":"cube"},"b":)" + above + R"(,"margin":0.25})");
  ASSERT_EQ(m["contacts"].size(), 4u) << m.dump();
  EXPECT_NEAR(m["contacts"][0]["depth"].get<double>(), -0.125, 1e-6);
}

TEST(BatchNarrowPhase, ConvexConvexContactsAndDistances) {
  Batch b;
  const std::string unitBox = R"({"box":{"center":[0,0,0],"half":[1,1,1],)" + kAxes + "}}";
  // A sphere of radius 0.5 centred 0.25 above the box's top face (z = 1): 0.25 deep.
  const Answer c = b.ask(R"({"op":"contacts","a":)" + unitBox + R"(,"b":{"sphere":{"center":[0,0,1.25],"radius":0.5}}})");
  ASSERT_EQ(c["contacts"].size(), 1u) << c.dump();
  EXPECT_NEAR(c["contacts"][0]["depth"].get<double>(), 0.25, 1e-6);
  EXPECT_TRUE(isPoint(c["contacts"][0]["point_a"], 0, 0, 1));
  EXPECT_TRUE(isPoint(c["contacts"][0]["point_b"], 0, 0, 0.75));
  // Distance: negative when penetrating, the points, the normal from B to A.
  const Answer d = b.ask(R"({"op":"distance","a":)" + unitBox + R"(,"b":{"sphere":{"center":[0,0,1.25],"radius":0.5}}})");
  EXPECT_NEAR(d["distance"].get<double>(), -0.25, 1e-6) << d.dump();
  EXPECT_TRUE(isPoint(d["normal"], 0, 0, -1));
  EXPECT_FALSE(d.contains("triangle_a"));
  // Separated capsule (along x at height 3, radius 0.5) and a rotated box: distance 1.5.
  const Answer e = b.ask(
      R"({"op":"distance","a":{"capsule":{"a":[-1,0,0],"b":[1,0,0],"radius":0.5},"transform":{"translation":[0,0,3]}},)"
      R"("b":)" + unitBox + "}");
  EXPECT_NEAR(e["distance"].get<double>(), 1.5, 1e-6) << e.dump();
  EXPECT_NEAR(e["point_a"][2].get<double>(), 2.5, 1e-6);
  EXPECT_NEAR(e["point_b"][2].get<double>(), 1, 1e-6);
  EXPECT_TRUE(isPoint(e["normal"], 0, 0, 1));
  // A hull (tetrahedron) moved by 3 along x, vertex (3,0,0) nearest a unit sphere at the origin.
  const Answer h = b.ask(
      R"({"op":"distance","a":{"hull":{"points":[[0,0,0],[1,0,0],[0,1,0],[0,0,1]]},"transform":{"translation":[3,0,0]}},)"
      R"("b":{"sphere":{"center":[0,0,0],"radius":1}}})");
  EXPECT_NEAR(h["distance"].get<double>(), 2, 1e-6) << h.dump();
  EXPECT_TRUE(isPoint(h["point_a"], 3, 0, 0));
  EXPECT_TRUE(isPoint(h["point_b"], 1, 0, 0));
  // A triangle operand against the mesh: 2 above its top face.
  const Answer t = b.ask(R"({"op":"distance","a":{"triangle":[[0,0,3],[1,0,3],[0,1,3]]},"b":{"mesh":"cube"}})");
  EXPECT_NEAR(t["distance"].get<double>(), 2, 1e-6) << t.dump();
  EXPECT_TRUE(t["triangle_b"] == 2 || t["triangle_b"] == 3) << t.dump();
}

TEST(BatchNarrowPhase, MeshAndModelDistance) {
  Batch b;
  const Answer a = b.ask(R"({"op":"mesh_distance","a":"cube","b":"cube","transform_b":{"translation":[3,0.5,0]}})");
  ASSERT_EQ(errorOf(a), "") << a.dump();
  EXPECT_EQ(a["found"], true);
  EXPECT_NEAR(a["distance"].get<double>(), 2, 1e-6);
  EXPECT_NEAR(a["point_a"][0].get<double>(), 1, 1e-6);
  EXPECT_NEAR(a["point_b"][0].get<double>(), 3, 1e-6);
  EXPECT_TRUE(a["triangle_a"].is_number_integer() && a["triangle_b"].is_number_integer());
  EXPECT_EQ(b.ask(R"({"op":"mesh_distance","a":"cube","b":"cube","transform_b":{"translation":[3,0,0]},"max":1.5})")
                .dump(),
            R"({"op":"mesh_distance","found":false})");
  // Overlapping surfaces: distance 0.
  EXPECT_EQ(b.ask(R"({"op":"mesh_distance","a":"cube","b":"cube","transform_b":{"translation":[0.5,0.5,0.5]}})")
                ["distance"]
                .get<double>(),
            0.0);
  EXPECT_EQ(errorOf(b.ask(R"({"op":"add_model","name":"m1","mesh":"cube"})")), "");
  EXPECT_EQ(errorOf(b.ask(R"({"op":"add_model","name":"m2","mesh":"cube","transform":{"translation":[0,0,5]}})")),
            "");
  const Answer m = b.ask(R"({"op":"model_distance","a":"m1","b":"m2"})");
  EXPECT_NEAR(m["distance"].get<double>(), 4, 1e-6) << m.dump();
  EXPECT_NEAR(m["point_b"][2].get<double>(), 5, 1e-6);
  EXPECT_EQ(errorOf(b.ask(R"({"op":"model_distance","a":"m1","b":"zz"})")),
            R"(b: no model named "zz" (add it first with add_model))");
}

TEST(BatchNarrowPhase, PointInsideAndVolumeMode) {
  Batch b;
  const auto inside = [&](const std::string& point) {
    return b.ask(R"({"op":"point_inside","mesh":"cube","point":)" + point + "}")["inside"];
  };
  EXPECT_EQ(inside("[0.5,0.5,0.5]"), true);
  EXPECT_EQ(inside("[1,1,1]"), true);  // a corner: surface points are inside (closed set)
  EXPECT_EQ(inside("[1,0.5,0.5]"), true);
  EXPECT_EQ(inside("[1.5,0.5,0.5]"), false);
  EXPECT_EQ(errorOf(b.ask(R"({"op":"point_inside","mesh":"quad","point":[0,0,0]})")),
            R"(mesh: mesh "quad" is not closed: edge (0,1) is used by 1 triangle (4 boundary, 0 non-manifold, 0 )"
            R"(inconsistently oriented edges))");
  // A small sphere inside: the surface test says no, volume mode says yes.
  const std::string sphere = R"("sphere":{"center":[0.5,0.5,0.5],"radius":0.1})";
  EXPECT_EQ(b.ask(R"({"op":"mesh_sphere","mesh":"cube",)" + sphere + "}")["hit"], false);
  EXPECT_EQ(b.ask(R"({"op":"mesh_sphere","mesh":"cube",)" + sphere + R"(,"volume":true})")["hit"], true);
  EXPECT_EQ(b.ask(R"({"op":"mesh_sphere","mesh":"cube","sphere":{"center":[2.5,0.5,0.5],"radius":0.1},"volume":true})")
                ["hit"],
            false);
  EXPECT_EQ(b.ask(R"({"op":"mesh_aabb","mesh":"cube","aabb":{"min":[0.2,0.2,0.2],"max":[0.3,0.3,0.3]},"volume":true})")
                ["hit"],
            true);
  EXPECT_EQ(b.ask(R"({"op":"mesh_obb","mesh":"cube","obb":{"center":[0.5,0.5,0.5],"half":[0.1,0.1,0.1],)" + kAxes +
                  R"(},"volume":true})")["hit"],
            true);
  EXPECT_EQ(b.ask(R"({"op":"mesh_triangle","mesh":"cube","triangle":[[0.2,0.2,0.2],[0.3,0.2,0.2],[0.2,0.3,0.2]],)"
                  R"("volume":true})")["hit"],
            true);
  EXPECT_EQ(b.ask(R"({"op":"mesh_sphere","mesh":"cube",)" + sphere + R"(,"volume":false})")["hit"], false);
  // Errors.
  EXPECT_EQ(errorOf(b.ask(R"({"op":"mesh_sphere","mesh":"quad",)" + sphere + R"(,"volume":true})")).rfind(
                R"(mesh: mesh "quad" is not closed)", 0),
            0u);
  EXPECT_EQ(errorOf(b.ask(R"({"op":"mesh_sphere","mesh":"cube",)" + sphere + R"(,"volume":1})")),
            "volume: expected true or false, got number");
  EXPECT_EQ(errorOf(b.ask(R"({"op":"mesh_sphere","mesh":"cube",)" + sphere + R"(,"volume":true,"triangles":true})"))
                .rfind("volume: cannot be combined", 0),
            0u);
  EXPECT_EQ(errorOf(b.ask(R"({"op":"mesh_plane","mesh":"cube","plane":{"normal":[0,0,1],"d":0.5},"volume":true})"))
                .rfind("volume: volume mode is defined for", 0),
            0u);
}

/// mesh_mesh with "volume": true: a closed mesh wholly inside another hits only in volume mode;
/// one closed operand suffices; two open ones are an error naming both.
TEST(BatchNarrowPhase, MeshMeshVolumeMode) {
  Batch b;
  ASSERT_EQ(errorOf(b.ask(kSmallCube)), "");
  EXPECT_EQ(b.ask(R"({"op":"mesh_mesh","a":"cube","b":"small"})")["hit"], false);
  EXPECT_EQ(b.ask(R"({"op":"mesh_mesh","a":"cube","b":"small","volume":true})")["hit"], true);
  EXPECT_EQ(b.ask(R"({"op":"mesh_mesh","a":"small","b":"cube","volume":true})")["hit"], true);
  EXPECT_EQ(b.ask(R"({"op":"mesh_mesh","a":"cube","b":"small","transform_b":{"translation":[2,0,0]},"volume":true})")
                ["hit"],
            false);
  // An open tile (a surface) wholly inside the cube: free for the surface test, a hit in volume
  // mode (the cube is the solid).
  ASSERT_EQ(errorOf(b.ask(R"({"op":"mesh","name":"tile","vertices":[[0.25,0.25,0.5],[0.75,0.25,0.5],[0.75,0.75,0.5],)"
                          R"([0.25,0.75,0.5]],"triangles":[[0,1,2],[0,2,3]]})")),
            "");
  EXPECT_EQ(b.ask(R"({"op":"mesh_mesh","a":"tile","b":"cube"})")["hit"], false);
  EXPECT_EQ(b.ask(R"({"op":"mesh_mesh","a":"tile","b":"cube","volume":true})")["hit"], true);
  EXPECT_EQ(b.ask(R"({"op":"mesh_mesh","a":"quad","b":"cube","transform_a":{"translation":[0,0,3]},"volume":true})")
                ["hit"],
            false);
  EXPECT_EQ(errorOf(b.ask(R"({"op":"mesh_mesh","a":"quad","b":"quad","volume":true})"))
                .rfind("a: mesh_mesh volume needs a closed operand: a: mesh \"quad\" is not closed", 0),
            0u);
  EXPECT_EQ(errorOf(b.ask(R"({"op":"mesh_mesh","a":"cube","b":"small","volume":true,"triangles":true})"))
                .rfind("volume: cannot be combined", 0),
            0u);
  EXPECT_EQ(errorOf(b.ask(R"({"op":"mesh_mesh","a":"cube","b":"small","volume":"yes"})")),
            "volume: expected true or false, got string");
}

/// model_<shape> with "volume": true: the model's closed mesh placed by its world transform
/// (through a parent) is a solid; shapes wholly inside hit only in volume mode; open meshes,
/// segments and planes are errors naming the field; peers without volumes say unsupported.
TEST(BatchNarrowPhase, ModelVolumeMode) {
  Batch b;
  // p at (10,0,0) turned a quarter about z; m its child at local (0,0,2): m's cube [0,1]^3 is at
  // world x in [9,10], y in [0,1], z in [2,3] (a point (x,y,z) of the cube maps to (10-y, x, z+2)).
  ASSERT_EQ(errorOf(b.ask(R"({"op":"add_model","name":"p","mesh":"cube","transform":{"translation":[10,0,0],)"
                          R"("rotation":[0.7071067811865476,0,0,0.7071067811865476]}})")),
            "");
  ASSERT_EQ(errorOf(b.ask(R"({"op":"add_model","name":"m","mesh":"cube","parent":"p",)"
                          R"("transform":{"translation":[0,0,2]}})")),
            "");
  ASSERT_EQ(errorOf(b.ask(R"({"op":"add_model","name":"q","mesh":"quad"})")), "");
  const auto hit = [&](const std::string& op, const std::string& shape, const std::string& extra) {
    const Answer a = b.ask(R"({"op":")" + op + R"(","model":"m",)" + shape + extra + "}");
    EXPECT_EQ(errorOf(a), "") << op << " " << shape << extra;
    return a["hit"];
  };
  const std::string in = R"("sphere":{"center":[9.5,0.5,2.5],"radius":0.1})";
  EXPECT_EQ(hit("model_sphere", in, ""), false);
  EXPECT_EQ(hit("model_sphere", in, R"(,"volume":false)"), false);
  EXPECT_EQ(hit("model_sphere", in, R"(,"volume":true)"), true);
  // Inside the cube's local frame without the parent's transform: outside in the world.
  EXPECT_EQ(hit("model_sphere", R"("sphere":{"center":[0.5,0.5,2.5],"radius":0.1})", R"(,"volume":true)"), false);
  EXPECT_EQ(hit("model_aabb", R"("aabb":{"min":[9.25,0.5,2.25],"max":[9.75,0.75,2.5]})", R"(,"volume":true)"), true);
  EXPECT_EQ(hit("model_aabb", R"("aabb":{"min":[9.25,0.5,2.25],"max":[9.75,0.75,2.5]})", ""), false);
  EXPECT_EQ(hit("model_aabb", R"("aabb":{"min":[10.5,0.5,2.25],"max":[10.75,0.75,2.5]})", R"(,"volume":true)"),
            false);
  EXPECT_EQ(hit("model_obb", R"("obb":{"center":[9.5,0.5,2.5],"half":[0.2,0.2,0.2],)" + kAxes + "}",
                R"(,"volume":true)"),
            true);
  EXPECT_EQ(hit("model_triangle", R"("triangle":[[9.2,0.2,2.2],[9.3,0.2,2.2],[9.2,0.3,2.2]])", R"(,"volume":true)"),
            true);
  EXPECT_EQ(hit("model_triangle", R"("triangle":[[9.2,0.2,2.2],[9.3,0.2,2.2],[9.2,0.3,2.2]])", ""), false);
  // Moving the parent moves the solid.
  ASSERT_EQ(errorOf(b.ask(R"({"op":"set_transform","model":"p","transform":{"translation":[20,0,0]}})")), "");
  EXPECT_EQ(hit("model_sphere", in, R"(,"volume":true)"), false);
  EXPECT_EQ(hit("model_sphere", R"("sphere":{"center":[20.5,0.5,2.5],"radius":0.1})", R"(,"volume":true)"), true);
  // Errors.
  const auto err = [&](const std::string& line) { return errorOf(b.ask(line)); };
  EXPECT_EQ(err(R"({"op":"model_sphere","model":"q",)" + in + R"(,"volume":true})"),
            R"(model: model "q": mesh "quad" is not closed: edge (0,1) is used by 1 triangle (4 boundary, 0 )"
            R"(non-manifold, 0 inconsistently oriented edges))");
  EXPECT_EQ(err(R"({"op":"model_sphere","model":"m",)" + in + R"(,"volume":1})"),
            "volume: expected true or false, got number");
  EXPECT_EQ(err(R"({"op":"model_sphere","model":"zz",)" + in + R"(,"volume":true})"),
            R"(model: no model named "zz" (add it first with add_model))");
  EXPECT_EQ(err(R"({"op":"model_sphere","model":"m","sphere":{"center":[0,0,0],"radius":-1},"volume":true})"),
            "sphere.radius is negative: -1");
  EXPECT_EQ(err(R"({"op":"model_plane","model":"m","plane":{"normal":[0,0,1],"d":0.5},"volume":true})")
                .rfind("volume: volume mode is defined for model_sphere, model_aabb, model_obb and model_triangle", 0),
            0u);
  EXPECT_EQ(err(R"({"op":"model_segment","model":"m","segment":{"start":[0,0,0],"end":[1,1,1]},"volume":true})")
                .rfind("volume: volume mode is defined for", 0),
            0u);
  // A model keeps its mesh when the name is redefined: the old (closed) cube stays the solid.
  ASSERT_EQ(errorOf(b.ask(R"({"op":"mesh","name":"cube","vertices":[[0,0,0],[1,0,0],[1,1,0]],"triangles":[[0,1,2]]})")),
            "");
  EXPECT_EQ(hit("model_sphere", R"("sphere":{"center":[20.5,0.5,2.5],"radius":0.1})", R"(,"volume":true)"), true);
  // Peers: exact answers as native, fcl and bullet say unsupported.
  for (const std::string_view name : builtBackends()) {
    if (name == "native") continue;
    Batch peer(*parseBackend(name));
    ASSERT_EQ(errorOf(peer.ask(R"({"op":"add_model","name":"m","mesh":"cube","transform":{"translation":[5,0,0]}})")),
              "");
    const Answer a = peer.ask(R"({"op":"model_obb","model":"m","obb":{"center":[5.5,0.5,0.5],"half":[0.1,0.1,0.1],)" +
                              kAxes + R"(},"volume":true})");
    if (!peer.state.world->supports(WorldOp::ModelObbVolume)) {
      EXPECT_EQ(errorOf(a), "unsupported: model_obb volume on " + std::string(name));
      continue;
    }
    EXPECT_EQ(errorOf(a), "") << name;
    EXPECT_EQ(a["hit"], true) << name;
  }
}

TEST(BatchNarrowPhase, ErrorsNameTheField) {
  Batch b;
  const std::string s = R"({"sphere":{"center":[0,0,3],"radius":1}})";
  const auto err = [&](const std::string& line) { return errorOf(b.ask(line)); };
  const auto startsWith = [](const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; };
  EXPECT_EQ(err(R"({"op":"contacts","a":{"mesh":"cube"},"b":{"mesh":"cube"}})"),
            "b: contacts need at least one convex operand (a and b are both meshes; mesh_distance measures two "
            "meshes)");
  EXPECT_EQ(err(R"({"op":"contacts","a":{"sphere":{"center":[0,0,0],"radius":-1}},"b":{"mesh":"cube"}})"),
            "a.sphere.radius is negative: -1");
  EXPECT_EQ(err(R"({"op":"contacts","a":)" + s + R"(,"b":{"mesh":"cube"},"margin":-1})"),
            "margin: must be finite and >= 0, got -1");
  EXPECT_EQ(err(R"({"op":"contacts","a":)" + s + R"(,"b":{"mesh":"cube"},"margin":"x"})"),
            "margin: expected a number, got string");
  EXPECT_EQ(err(R"({"op":"contacts","a":{"hull":{"points":[]}},"b":{"mesh":"cube"}})"),
            "a.hull.points is empty: a convex hull needs at least one point");
  EXPECT_EQ(err(R"({"op":"contacts","a":{"hull":{"points":[[0,0]]}},"b":)" + s + "}"),
            "a.hull.points[0]: expected [x, y, z], got an array of 2 elements");
  EXPECT_EQ(err(R"({"op":"contacts","a":{"sphere":{"center":[0,0,0],"radius":1},"box":{}},"b":)" + s + "}"),
            R"(a: expected exactly one shape, got both "sphere" and "box")");
  EXPECT_EQ(err(R"({"op":"distance","a":{"cone":{}},"b":)" + s + "}"),
            R"(a: expected one of "sphere", "box", "capsule", "hull", "triangle", "mesh")");
  EXPECT_EQ(err(R"({"op":"distance","a":[1,2],"b":)" + s + "}").rfind("a: expected an operand", 0), 0u);
  EXPECT_EQ(err(R"({"op":"distance","a":)" + s + "}"), "b: missing field");
  EXPECT_EQ(err(R"({"op":"distance","a":{"mesh":"nope"},"b":)" + s + "}"),
            R"(a.mesh: no mesh named "nope" (define it first with mesh or load_mesh))");
  EXPECT_EQ(err(R"({"op":"distance","a":{"capsule":{"a":[0,0,0],"b":[1,0,0]}},"b":)" + s + "}"),
            "a.capsule.radius: missing field");
  EXPECT_TRUE(startsWith(err(R"({"op":"distance","a":{"capsule":{"a":[0,0,0],"b":[1,0,0],"radius":-2}},"b":)" + s +
                             "}"),
                         "a.capsule"));
  EXPECT_TRUE(startsWith(
      err(R"({"op":"distance","a":{"mesh":"cube","transform":{"rotation":[2,0,0,0]}},"b":)" + s + "}"),
      "a.transform.rotation: not a unit quaternion"));
  EXPECT_EQ(err(R"({"op":"distance","a":{"sphere":{"center":[0,0,1e400],"radius":1}},"b":)" + s + "}"),
            "a.sphere.center[2]: number 1e400 overflows double");
  EXPECT_EQ(err(R"({"op":"mesh_distance","a":"cube","b":"cube","max":-1})"), "max: must be >= 0, got -1.0");
  EXPECT_EQ(err(R"({"op":"mesh_distance","a":"cube","b":"x"})"),
            R"(b: no mesh named "x" (define it first with mesh or load_mesh))");
  EXPECT_EQ(err(R"({"op":"point_inside","mesh":"cube"})"), "point: missing field");
  EXPECT_EQ(err(R"({"op":"point_inside","mesh":"cube","point":[0,0]})"),
            "point: expected [x, y, z], got an array of 2 elements");
}

/// Each backend answers exactly the narrow-phase ops its world supports(), and the peers that
/// answer agree with native on these clear cases.
TEST(BatchNarrowPhase, PeersAnswerWhatTheySupportAndAgreeOnClearCases) {
  const std::vector<std::string> lines = {
      R"({"op":"point_inside","mesh":"cube","point":[0.5,0.25,0.75]})",
      R"({"op":"point_inside","mesh":"cube","point":[1.5,0.25,0.75]})",
      R"({"op":"mesh_sphere","mesh":"cube","sphere":{"center":[0.5,0.5,0.5],"radius":0.2},"volume":true})",
      R"({"op":"mesh_aabb","mesh":"cube","aabb":{"min":[2,2,2],"max":[3,3,3]},"volume":true})",
      R"({"op":"mesh_mesh","a":"cube","b":"small","volume":true})",
      R"({"op":"mesh_mesh","a":"quad","b":"cube","transform_b":{"translation":[0,0,3]},"volume":true})",
      R"({"op":"distance","a":{"mesh":"cube"},"b":{"box":{"center":[0.5,0.5,3],"half":[0.5,0.5,0.5],)" + kAxes +
          "}}}",
      R"({"op":"distance","a":{"capsule":{"a":[-1,0,0],"b":[1,0,0],"radius":0.5}},"b":{"sphere":{"center":[0,3,0],"radius":1}}})",
      R"({"op":"mesh_distance","a":"cube","b":"cube","transform_b":{"translation":[0,0,3]}})",
      // one closest pair, so the points are compared too, in both operand orders (FCL measures a
      // shape against its one-triangle BVHModel in the order (triangle, shape), and FCL 0.7
      // reports the shape's point in the shape's own frame there: only the triangle's is compared)
      R"({"op":"distance","a":{"sphere":{"center":[0.25,0.25,2],"radius":0.5}},"b":{"triangle":[[0,0,0],[1,0,0],[0,1,0]]}})",
      R"({"op":"distance","a":{"triangle":[[0,0,0],[1,0,0],[0,1,0]]},"b":{"sphere":{"center":[0.25,0.25,2],"radius":0.5}}})",
  };
  Batch native;
  native.ask(kSmallCube);
  std::vector<Answer> want;
  for (const std::string& l : lines) want.push_back(native.ask(l));
  for (const std::string_view name : builtBackends()) {
    if (name == "native") continue;
    Batch peer(*parseBackend(name));
    peer.ask(kSmallCube);
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const Answer got = peer.ask(lines[i]);
      const std::string op = Json::parse(lines[i])["op"];
      const bool volume = lines[i].find("\"volume\":true") != std::string::npos;
      WorldOp worldOp = *parseOp(op);
      if (volume)
        worldOp = op == "mesh_sphere" ? WorldOp::MeshSphereVolume
                  : op == "mesh_aabb" ? WorldOp::MeshAabbVolume
                                      : WorldOp::MeshMeshVolume;
      if (!peer.state.world->supports(worldOp)) {
        EXPECT_EQ(errorOf(got), "unsupported: " + std::string(opName(worldOp)) + " on " + std::string(name));
        continue;
      }
      ASSERT_EQ(errorOf(got), "") << name << ": " << lines[i];
      if (got.contains("inside")) EXPECT_EQ(got["inside"], want[i]["inside"]) << name << ": " << lines[i];
      if (got.contains("hit")) EXPECT_EQ(got["hit"], want[i]["hit"]) << name << ": " << lines[i];
      if (got.contains("distance"))
        EXPECT_NEAR(got["distance"].get<double>(), want[i]["distance"].get<double>(), 1e-5)
            << name << ": " << lines[i] << " -> " << got.dump();
      if (lines[i].find("\"triangle\"") != std::string::npos)
        for (const char* point : {"point_a", "point_b"}) {
          const bool onTriangle = Json::parse(lines[i])[std::string(point) == "point_a" ? "a" : "b"].contains("triangle");
          if (name == "fcl" && !onTriangle) continue;
          for (std::size_t k = 0; k < 3; ++k)
            EXPECT_NEAR(got[point][k].get<double>(), want[i][point][k].get<double>(), 1e-5)
                << name << ": " << point << " of " << lines[i] << " -> " << got.dump();
        }
    }
  }
  if (built("exact")) EXPECT_TRUE(makeWorld("exact")->supports(WorldOp::PointInside));
  if (built("fcl")) EXPECT_TRUE(makeWorld("fcl")->supports(WorldOp::MeshDistance));
}


TEST(BatchNarrowPhase, CastsOntoTheCubeAgreeWithTheExactBackend) {
  // A box of half extents 0.25 centred 2 above the cube's top, dropped by 3: its bottom (at 1.75)
  // meets the top face (z = 1) after 0.75 of 3, t = 0.25; a box against a box the same.
  const std::string box = R"({"box":{"center":[0,0,0],"half":[0.25,0.25,0.25],)" + kAxes +
                          R"(},"transform":{"translation":[0.5,0.5,2]}})";
  const std::string lines[] = {
      R"({"op":"cast","a":)" + box + R"(,"motion":[0,0,-3],"b":{"mesh":"cube"}})",
      R"({"op":"cast","a":)" + box + R"(,"motion":[0,0,-3],"b":{"box":{"center":[0.5,0.5,0.5],"half":[0.5,0.5,0.5],)" +
          kAxes + "}}}",
      R"({"op":"cast","a":)" + box + R"(,"motion":[3,0,0],"b":{"mesh":"cube"}})",  // sideways: a miss
  };
  std::vector<std::string> backends = {"native"};
  if (built("exact")) backends.push_back("exact");
  for (const std::string& name : backends) {
    Batch b(*parseBackend(name));
    for (int i = 0; i < 2; ++i) {
      const Answer a = b.ask(lines[i]);
      ASSERT_EQ(errorOf(a), "") << name << ": " << a.dump();
      ASSERT_TRUE(a["hit"].get<bool>()) << name << ": " << a.dump();
      EXPECT_LE(a["t"].get<double>(), 0.25) << name;
      EXPECT_NEAR(a["t"].get<double>(), 0.25, 1e-6) << name;
      EXPECT_FALSE(a["starts_overlapping"].get<bool>());
      EXPECT_NEAR(a["point_b"][2].get<double>(), 1, 1e-6) << name << ": " << a.dump();
      // from B (below) to A; a cast's normal is accurate to ~1e-6 (docs/narrowphase.md)
      EXPECT_NEAR(a["normal"][0].get<double>(), 0, 1e-5) << name << ": " << a.dump();
      EXPECT_NEAR(a["normal"][1].get<double>(), 0, 1e-5) << name << ": " << a.dump();
      EXPECT_NEAR(a["normal"][2].get<double>(), 1, 1e-5) << name << ": " << a.dump();
    }
    const Answer first = b.ask(lines[0]);
    EXPECT_TRUE(first["triangle"] == 2 || first["triangle"] == 3) << name << ": " << first.dump();
    EXPECT_FALSE(b.ask(lines[2])["hit"].get<bool>()) << name;
  }
  // A ball (rounded: the exact backend decides hit or miss only, "t": null there) starting in
  // contact with the cube's top face; a rigid motion (native) turning a capsule into the cube.
  Batch native;
  const Answer touching = native.ask(
      R"({"op":"cast","a":{"sphere":{"center":[0.5,0.5,1.5],"radius":0.5}},"motion":[1,0,0],"b":{"mesh":"cube"}})");
  ASSERT_EQ(errorOf(touching), "") << touching.dump();
  EXPECT_EQ(touching["t"].get<double>(), 0);
  EXPECT_TRUE(touching["starts_overlapping"].get<bool>());
  const Answer turning = native.ask(
      R"({"op":"cast","a":{"capsule":{"a":[0,0,0],"b":[0,0,2],"radius":0.1},"transform":{"translation":[2.5,0.5,0]}},)"
      R"("end":{"rotation":[0.70710678118654752,0,-0.70710678118654752,0],"translation":[2.5,0.5,0]},"b":{"mesh":"cube"}})");
  ASSERT_EQ(errorOf(turning), "") << turning.dump();
  EXPECT_TRUE(turning["hit"].get<bool>()) << turning.dump();
  if (built("exact")) {
    Batch exact(Backend::Exact);
    const Answer e = exact.ask(
        R"({"op":"cast","a":{"sphere":{"center":[0.5,0.5,1.5],"radius":0.5}},"motion":[1,0,0],"b":{"mesh":"cube"}})");
    ASSERT_EQ(errorOf(e), "") << e.dump();
    EXPECT_TRUE(e["hit"].get<bool>());
    EXPECT_TRUE(e["t"].is_null());
  }
  // errors name the field
  EXPECT_EQ(errorOf(native.ask(R"({"op":"cast","a":{"mesh":"cube"},"motion":[1,0,0],"b":{"mesh":"quad"}})")).rfind("a:", 0),
            0u);
  EXPECT_EQ(errorOf(native.ask(R"({"op":"cast","a":{"sphere":{"center":[0,0,0],"radius":1}},"b":{"mesh":"quad"}})"))
                .rfind("motion:", 0),
            0u);
  EXPECT_EQ(errorOf(native.ask(
                        R"({"op":"cast","a":{"sphere":{"center":[0,0,0],"radius":-1}},"motion":[1,0,0],"b":{"mesh":"quad"}})"))
                .rfind("a.sphere", 0),
            0u);
}

TEST(BatchNarrowPhase, ModelAndSceneCastsNameTheModelHitOnEveryBackend) {
  // Two unit cubes as models, "high" at the origin and "low" 3 below: a box of half 0.25 from
  // z = -5 up by 10 meets low first (its bottom face, z = -3) at t = 0.175; a ball of radius 0.5
  // cast at high alone meets its bottom (z = 0) at t = 0.45 (exact: t null, a rounded shape).
  const std::string ball = R"({"sphere":{"center":[0.5,0.5,-5],"radius":0.5}})";
  const std::string box = R"({"box":{"center":[0.5,0.5,-5],"half":[0.25,0.25,0.25],)" + kAxes + "}}";
  std::vector<std::string> backends = {"native"};
  for (const char* peer : {"exact", "bullet", "fcl"})
    if (built(peer)) backends.push_back(peer);
  for (const std::string& name : backends) {
    Batch b(*parseBackend(name));
    ASSERT_EQ(errorOf(b.ask(R"({"op":"add_model","name":"high","mesh":"cube"})")), "");
    ASSERT_EQ(errorOf(b.ask(R"({"op":"add_model","name":"low","mesh":"cube","transform":{"translation":[0,0,-3]}})")), "");
    const Answer scene = b.ask(R"({"op":"scene_cast","a":)" + box + R"(,"motion":[0,0,10]})");
    const Answer model = b.ask(R"({"op":"model_cast","a":)" + ball + R"(,"motion":[0,0,10],"model":"high"})");
    const Answer any = b.ask(R"({"op":"scene_cast","a":)" + ball + R"(,"motion":[0,0,10],"any":true})");
    const Answer miss = b.ask(R"({"op":"scene_cast","a":)" + ball + R"(,"motion":[10,0,0],"any":false})");
    if (name == "fcl") {  // FCL's continuous collision against meshes fails (oracle/README.md)
      EXPECT_EQ(errorOf(scene), "unsupported: scene_cast on fcl");
      EXPECT_EQ(errorOf(model), "unsupported: model_cast on fcl");
      continue;
    }
    ASSERT_EQ(errorOf(scene), "") << name << ": " << scene.dump();
    EXPECT_TRUE(scene["hit"].get<bool>()) << name;
    EXPECT_EQ(scene["model"], "low") << name << ": " << scene.dump();
    EXPECT_NEAR(scene["t"].get<double>(), 0.175, 1e-6) << name;  // the box's top: -4.75 + 10t = -3
    ASSERT_EQ(errorOf(model), "") << name << ": " << model.dump();
    EXPECT_TRUE(model["hit"].get<bool>()) << name;
    EXPECT_FALSE(model.contains("model")) << name;  // a model cast names no model: the caller gave it
    if (name == "exact") EXPECT_TRUE(model["t"].is_null());
    else EXPECT_NEAR(model["t"].get<double>(), 0.45, 1e-6) << name << ": " << model.dump();  // -4.5 + 10t = 0
    EXPECT_TRUE(any["hit"].get<bool>()) << name;
    EXPECT_TRUE(any["t"].is_null()) << name << ": " << any.dump();
    EXPECT_FALSE(miss["hit"].get<bool>()) << name;
  }
  Batch native;
  ASSERT_EQ(errorOf(native.ask(R"({"op":"add_model","name":"high","mesh":"cube"})")), "");
  // a rigid motion (a quarter turn about z on the way up) with "any": castAny(Scene, RigidMotion)
  const std::string up = R"(,"end":{"translation":[0,0,5],"rotation":[0.70710678118654752,0,0,0.70710678118654752]})";
  const std::string boxAt = R"({"box":{"center":[0,0,0],"half":[0.25,0.25,0.25],)" + kAxes +
                            R"(},"transform":{"translation":[0.5,0.5,-5]}})";
  const Answer rigidAny = native.ask(R"({"op":"scene_cast","a":)" + boxAt + up + R"(,"any":true})");
  ASSERT_EQ(errorOf(rigidAny), "") << rigidAny.dump();
  EXPECT_TRUE(rigidAny["hit"].get<bool>());
  const Answer rigidClosest = native.ask(R"({"op":"scene_cast","a":)" + boxAt + up + "}");
  EXPECT_TRUE(rigidClosest["hit"].get<bool>());
  EXPECT_EQ(rigidClosest["model"], "high");
  const Answer rigidBeside = native.ask(R"({"op":"scene_cast","a":)" + boxAt +
                                        R"(,"end":{"translation":[5,0,5],"rotation":[0.70710678118654752,0,0,0.70710678118654752]},"any":true})");
  EXPECT_FALSE(rigidBeside["hit"].get<bool>()) << rigidBeside.dump();
  EXPECT_EQ(errorOf(native.ask(R"({"op":"model_cast","a":)" + ball + R"(,"motion":[0,0,1],"model":"nope"})")).rfind("model: no model named", 0), 0u);
  EXPECT_EQ(errorOf(native.ask(R"({"op":"scene_cast","a":)" + ball + R"(,"motion":[0,0,1],"any":1})")),
            "any: expected a boolean, got number");
  EXPECT_EQ(errorOf(native.ask(R"({"op":"scene_cast","a":)" + ball + R"(,"motion":[0,0,1],"end":{}})")).rfind("end:", 0), 0u);
}

}  // namespace
}  // namespace crux::cli
