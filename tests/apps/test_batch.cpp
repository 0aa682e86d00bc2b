// Tests of the `crux batch` JSON Lines protocol (apps/cli/batch.hpp, docs/batch.md): every primitive
// op on hand-checked cases, id/op echo, every error path, unsupported ops and backends, line
// accounting, round-trip exact doubles, the shipped examples, and the `crux` executable itself.

#include "apps/batch_test_util.hpp"
#include "cli/batch.hpp"
#include "cli/json_codec.hpp"

#include <crux/geometry/raycast.hpp>
#include <crux/world/collision_world.hpp>
#include <world_factory.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace crux::cli {
namespace {

using test::errorOf;
using test::isPoint;
using test::kResultTolerance;
using test::splitLines;

Answer ask(const std::string& line, Backend backend = Backend::Native) {
  BatchState state(BatchOptions{backend, 1});
  return answerLine(line, state);
}

::testing::AssertionResult answersHit(const std::string& line, bool expected) {
  const Answer a = ask(line);
  if (!errorOf(a).empty()) return ::testing::AssertionFailure() << "error answer " << a.dump() << " to " << line;
  if (!a.contains("hit") || !a["hit"].is_boolean())
    return ::testing::AssertionFailure() << "no boolean hit in " << a.dump();
  if (a["hit"].get<bool>() != expected)
    return ::testing::AssertionFailure() << "hit " << a["hit"] << " expected " << expected << " for " << line;
  return ::testing::AssertionSuccess();
}

/// Asserts the answer to `line` is an error whose message starts with `prefix` (the field path).
::testing::AssertionResult errorStartsWith(const std::string& line, const std::string& prefix,
                                           Backend backend = Backend::Native) {
  const Answer a = ask(line, backend);
  const std::string e = errorOf(a);
  if (e.rfind(prefix, 0) != 0)
    return ::testing::AssertionFailure() << "answer " << a.dump() << " to " << line << " lacks error prefix '"
                                         << prefix << "'";
  if (a.contains("hit") || a.contains("point") || a.contains("t"))
    return ::testing::AssertionFailure() << "error answer carries results: " << a.dump();
  return ::testing::AssertionSuccess();
}

const std::string kUnitTriangle = R"([[0,0,0],[1,0,0],[0,1,0]])";

std::string op(const std::string& name, const std::string& fields) {
  return R"({"id":"q","op":")" + name + R"(",)" + fields + "}";
}

// ---------------------------------------------------------------------------------------------
// Primitive ops, hand-checked.

TEST(BatchClosestPointTriangle, InteriorProjection) {
  const Answer a = ask(op("closest_point_triangle", R"("triangle":[[0,0,0],[4,0,0],[0,4,0]],"point":[1,1,5])"));
  ASSERT_TRUE(isPoint(a["point"], 1, 1, 0)) << a.dump();
}

TEST(BatchClosestPointTriangle, VertexRegionWhereTwoEdgeTestsTie) {
  // The book's strict '<' returned (0,0,0) here (seed errata).
  const Answer a = ask(op("closest_point_triangle", R"("triangle":)" + kUnitTriangle + R"(,"point":[2,-0.5,0])"));
  ASSERT_TRUE(isPoint(a["point"], 1, 0, 0)) << a.dump();
}

TEST(BatchClosestPointTriangle, EdgeRegion) {
  const Answer a = ask(op("closest_point_triangle", R"("triangle":)" + kUnitTriangle + R"(,"point":[2,2,0])"));
  ASSERT_TRUE(isPoint(a["point"], 0.5, 0.5, 0)) << a.dump();
}

TEST(BatchClosestPointTriangle, CollinearTriangleIsItsSegment) {
  const std::string tri = R"("triangle":[[0,0,0],[2,0,0],[1,0,0]])";
  EXPECT_TRUE(isPoint(ask(op("closest_point_triangle", tri + R"(,"point":[1,3,0])"))["point"], 1, 0, 0));
  EXPECT_TRUE(isPoint(ask(op("closest_point_triangle", tri + R"(,"point":[5,1,0])"))["point"], 2, 0, 0));
}

TEST(BatchClosestPointTriangle, RepeatedCornersAreAPoint) {
  const Answer a = ask(op("closest_point_triangle", R"("triangle":[[1,2,3],[1,2,3],[1,2,3]],"point":[-4,0,9])"));
  ASSERT_TRUE(isPoint(a["point"], 1, 2, 3)) << a.dump();
}

TEST(BatchTriangleSphere, TouchingAVertexHits) {
  // Closest point of the triangle to (1,0,3) is the vertex (1,0,0), at distance 3.
  EXPECT_TRUE(answersHit(op("triangle_sphere", R"("triangle":)" + kUnitTriangle +
                                                   R"(,"sphere":{"center":[1,0,3],"radius":3})"),
                         true));
  EXPECT_TRUE(answersHit(op("triangle_sphere", R"("triangle":)" + kUnitTriangle +
                                                   R"(,"sphere":{"center":[1,0,3],"radius":2.5})"),
                         false));
}

TEST(BatchTriangleSphere, ZeroRadiusIsAPoint) {
  EXPECT_TRUE(answersHit(op("triangle_sphere", R"("triangle":)" + kUnitTriangle +
                                                   R"(,"sphere":{"center":[0.25,0.25,0],"radius":0})"),
                         true));
  EXPECT_TRUE(answersHit(op("triangle_sphere", R"("triangle":)" + kUnitTriangle +
                                                   R"(,"sphere":{"center":[0.25,0.25,0.5],"radius":0})"),
                         false));
}

TEST(BatchTriangleAabb, TouchingTheHypotenuseAtABoxCorner) {
  // (0.5, 0.5, 0) is on the edge x + y = 1 and is the box's min corner.
  EXPECT_TRUE(answersHit(op("triangle_aabb", R"("triangle":)" + kUnitTriangle +
                                                 R"(,"aabb":{"min":[0.5,0.5,0],"max":[1,1,1]})"),
                         true));
  EXPECT_TRUE(answersHit(op("triangle_aabb", R"("triangle":)" + kUnitTriangle +
                                                 R"(,"aabb":{"min":[0.75,0.75,-1],"max":[1,1,1]})"),
                         false));
  EXPECT_TRUE(answersHit(op("triangle_aabb", R"("triangle":)" + kUnitTriangle +
                                                 R"(,"aabb":{"min":[0,0,0.5],"max":[1,1,1]})"),
                         false));
}

TEST(BatchTriangleAabb, FlatBoxInTheTrianglePlane) {
  EXPECT_TRUE(answersHit(op("triangle_aabb", R"("triangle":)" + kUnitTriangle +
                                                 R"(,"aabb":{"min":[0.1,0.1,0],"max":[0.2,0.2,0]})"),
                         true));
}

TEST(BatchTriangleObb, RotatedBoxMissesWhereItsAabbWouldHit) {
  // Box centred at (1,1,0) with half extents 0.5, rotated 45 degrees about z: its reach towards
  // the edge x + y = 1 is 0.5 < 1/sqrt(2) (miss); unrotated it touches at (0.5, 0.5, 0).
  const double s = std::sqrt(0.5);
  std::ostringstream rotated;
  rotated.precision(17);
  rotated << R"("obb":{"center":[1,1,0],"half":[0.5,0.5,0.5],"axes":[[)" << s << "," << s << ",0],[" << -s << ","
          << s << ",0],[0,0,1]]}";
  EXPECT_TRUE(answersHit(op("triangle_obb", R"("triangle":)" + kUnitTriangle + "," + rotated.str()), false));
  const std::string permuted = R"("obb":{"center":[1,1,0],"half":[0.5,0.5,0.5],"axes":[[0,1,0],[-1,0,0],[0,0,1]]})";
  EXPECT_TRUE(answersHit(op("triangle_obb", R"("triangle":)" + kUnitTriangle + "," + permuted), true));
}

TEST(BatchTrianglePlane, CoplanarTouchingAndSeparated) {
  const std::string t = R"("triangle":)" + kUnitTriangle;
  EXPECT_TRUE(answersHit(op("triangle_plane", t + R"(,"plane":{"normal":[0,0,2],"d":0})"), true));
  EXPECT_TRUE(answersHit(op("triangle_plane", t + R"(,"plane":{"normal":[0,0,1],"d":1})"), false));
  EXPECT_TRUE(answersHit(op("triangle_plane", t + R"(,"plane":{"normal":[1,0,0],"d":1})"), true));  // vertex
  EXPECT_TRUE(answersHit(op("triangle_plane", t + R"(,"plane":{"normal":[1,0,0],"d":1.5})"), false));
  // Plane 2x = 1 (normal not unit) cuts the triangle.
  EXPECT_TRUE(answersHit(op("triangle_plane", t + R"(,"plane":{"normal":[2,0,0],"d":1})"), true));
}

TEST(BatchTriangleTriangle, CoplanarTrianglesSharingAnEdge) {
  EXPECT_TRUE(answersHit(op("triangle_triangle", R"("a":)" + kUnitTriangle + R"(,"b":[[1,0,0],[0,1,0],[1,1,0]])"),
                         true));
}

TEST(BatchTriangleTriangle, ParallelPlanesAndPiercing) {
  EXPECT_TRUE(answersHit(
      op("triangle_triangle", R"("a":)" + kUnitTriangle + R"(,"b":[[0,0,1],[1,0,1],[0,1,1]])"), false));
  EXPECT_TRUE(answersHit(
      op("triangle_triangle", R"("a":)" + kUnitTriangle + R"(,"b":[[0.25,0.25,-1],[0.25,0.25,1],[3,3,0]])"), true));
  // Same b moved beyond the hypotenuse: disjoint.
  EXPECT_TRUE(answersHit(
      op("triangle_triangle", R"("a":)" + kUnitTriangle + R"(,"b":[[2,2,-1],[2,2,1],[3,3,0]])"), false));
}

TEST(BatchRayTriangle, HitFromAboveWithNonUnitDirectionReportsWorldDistance) {
  const Answer a = ask(op("ray_triangle", R"("triangle":)" + kUnitTriangle +
                                              R"(,"ray":{"origin":[0.25,0.25,5],"dir":[0,0,-2]})"));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_NEAR(a["t"].get<double>(), 5.0, kResultTolerance);
  EXPECT_TRUE(isPoint(a["point"], 0.25, 0.25, 0)) << a.dump();
}

TEST(BatchRayTriangle, BackFaceIsHit) {
  const Answer a = ask(op("ray_triangle", R"("triangle":)" + kUnitTriangle +
                                              R"(,"ray":{"origin":[0.5,0.25,-2],"dir":[0,0,3]})"));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_NEAR(a["t"].get<double>(), 2.0, kResultTolerance);
  EXPECT_TRUE(isPoint(a["point"], 0.5, 0.25, 0)) << a.dump();
}

TEST(BatchRayTriangle, SharedEdgeIsHit) {
  const Answer a = ask(op("ray_triangle", R"("triangle":)" + kUnitTriangle +
                                              R"(,"ray":{"origin":[0.5,0.5,1],"dir":[0,0,-1]})"));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_NEAR(a["t"].get<double>(), 1.0, kResultTolerance);
}

TEST(BatchRayTriangle, OriginOnTheTriangleHitsAtZero) {
  const Answer a = ask(op("ray_triangle", R"("triangle":)" + kUnitTriangle +
                                              R"(,"ray":{"origin":[0.25,0.25,0],"dir":[0,0,1]})"));
  ASSERT_TRUE(a.value("hit", false)) << a.dump();
  EXPECT_NEAR(a["t"].get<double>(), 0.0, kResultTolerance);
  EXPECT_TRUE(isPoint(a["point"], 0.25, 0.25, 0)) << a.dump();
}

TEST(BatchRayTriangle, MissCarriesNoDistance) {
  for (const char* ray : {R"("ray":{"origin":[2,2,5],"dir":[0,0,-1]})",       // beside
                          R"("ray":{"origin":[0.25,0.25,5],"dir":[0,0,1]})"}) {  // pointing away
    const Answer a = ask(op("ray_triangle", R"("triangle":)" + kUnitTriangle + "," + ray));
    ASSERT_TRUE(a.contains("hit")) << a.dump();
    EXPECT_FALSE(a["hit"].get<bool>()) << a.dump();
    EXPECT_FALSE(a.contains("t")) << a.dump();
    EXPECT_FALSE(a.contains("point")) << a.dump();
  }
}

TEST(BatchSegmentTriangle, CrossingTouchingAndShort) {
  const std::string t = R"("triangle":)" + kUnitTriangle;
  EXPECT_TRUE(answersHit(op("segment_triangle", t + R"(,"segment":{"start":[0.25,0.25,-1],"end":[0.25,0.25,1]})"),
                         true));
  EXPECT_TRUE(answersHit(op("segment_triangle", t + R"(,"segment":{"start":[0.25,0.25,1],"end":[0.25,0.25,0]})"),
                         true));
  EXPECT_TRUE(answersHit(op("segment_triangle", t + R"(,"segment":{"start":[0.25,0.25,1],"end":[0.25,0.25,0.5]})"),
                         false));
}

TEST(BatchSegmentTriangle, PointSegment) {
  const std::string t = R"("triangle":)" + kUnitTriangle;
  EXPECT_TRUE(answersHit(op("segment_triangle", t + R"(,"segment":{"start":[0.5,0.5,0],"end":[0.5,0.5,0]})"), true));
  EXPECT_TRUE(answersHit(op("segment_triangle", t + R"(,"segment":{"start":[0.5,0.6,0],"end":[0.5,0.6,0]})"), false));
}

// ---------------------------------------------------------------------------------------------
// Echo and answer shape.

TEST(BatchEcho, IdAndOpComeFirstInTheAnswer) {
  const Answer a = ask(R"({"op":"triangle_plane","plane":{"normal":[0,0,1],"d":0},"id":"abc-1","triangle":)" +
                       kUnitTriangle + "}");
  EXPECT_EQ(a.dump(), R"({"id":"abc-1","op":"triangle_plane","hit":true})");
}

TEST(BatchEcho, NoIdMeansNoIdInTheAnswer) {
  const Answer a = ask(R"({"op":"triangle_plane","plane":{"normal":[0,0,1],"d":3},"triangle":)" + kUnitTriangle + "}");
  EXPECT_EQ(a.dump(), R"({"op":"triangle_plane","hit":false})");
}

TEST(BatchEcho, ErrorAnswersEchoIdAndOp) {
  const Answer a = ask(R"({"id":"e1","op":"triangle_sphere","triangle":[[0,0,0],[1,0,0],[0,1,0]]})");
  EXPECT_EQ(a.dump(), R"({"id":"e1","op":"triangle_sphere","error":"sphere: missing field"})");
}

TEST(BatchEcho, UnknownFieldsAreIgnored) {
  EXPECT_TRUE(answersHit(R"({"op":"triangle_plane","comment":"x","plane":{"normal":[0,0,1],"d":0,"unit":false},)"
                         R"("triangle":)" + kUnitTriangle + "}",
                         true));
}

TEST(BatchEcho, RepeatedKeyLastOneWins) {
  EXPECT_TRUE(answersHit(R"({"op":"triangle_plane","plane":{"normal":[0,0,1],"d":5},"plane":{"normal":[0,0,1],"d":0},)"
                         R"("triangle":)" + kUnitTriangle + "}",
                         true));
}

// ---------------------------------------------------------------------------------------------
// Error paths: each names the field.

TEST(BatchErrors, LinesThatAreNotJsonObjects) {
  EXPECT_TRUE(errorStartsWith("{", "invalid JSON: "));
  EXPECT_TRUE(errorStartsWith(R"({"op":"ray_triangle",})", "invalid JSON: "));
  EXPECT_TRUE(errorStartsWith(R"({"op":"ray_triangle"} {})", "invalid JSON: "));  // trailing garbage
  EXPECT_TRUE(errorStartsWith("nan", "invalid JSON: "));
  EXPECT_TRUE(errorStartsWith(R"({"op":"triangle_sphere","sphere":{"center":[0,0,0],"radius":NaN}})",
                              "invalid JSON: "));
  EXPECT_TRUE(errorStartsWith("[1,2,3]", "request: expected a JSON object, got array"));
  EXPECT_TRUE(errorStartsWith("42", "request: expected a JSON object, got number"));
  EXPECT_TRUE(errorStartsWith(R"("op")", "request: expected a JSON object, got string"));
  EXPECT_TRUE(errorStartsWith("null", "request: expected a JSON object, got null"));
}

TEST(BatchErrors, EmptyAndBlankLinesAnswerAnError) {
  EXPECT_EQ(ask("").dump(), R"({"error":"empty line"})");
  EXPECT_EQ(ask(" \t ").dump(), R"({"error":"empty line"})");
  EXPECT_EQ(ask("\r").dump(), R"({"error":"empty line"})");
}

TEST(BatchErrors, InvalidJsonKeepsIdAndOpParsedBeforeTheFault) {
  const Answer a = ask(R"({"id":"x7","op":"ray_triangle","ray":{"origin":[0,0,0],"dir":[1,0,0]} "triangle")");
  EXPECT_EQ(a.value("id", ""), "x7") << a.dump();
  EXPECT_EQ(a.value("op", ""), "ray_triangle") << a.dump();
  EXPECT_EQ(errorOf(a).rfind("invalid JSON: ", 0), 0u) << a.dump();
}

TEST(BatchErrors, InvalidUtf8StillGivesAValidJsonAnswer) {
  const std::string line = "{\"id\":\"a\",\"op\":\"x\xff\"}";
  const Answer a = ask(line);
  EXPECT_EQ(errorOf(a).rfind("invalid JSON: ", 0), 0u) << a.dump(-1, ' ', false, Answer::error_handler_t::replace);
  std::ostringstream out;
  ASSERT_NO_THROW(writeAnswer(out, a));
  const std::string text = out.str();
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  EXPECT_TRUE(Json::accept(text)) << text;  // accept rejects ill-formed UTF-8
  const std::string bare = "\xfe\xff garbage";
  std::ostringstream out2;
  ASSERT_NO_THROW(writeAnswer(out2, ask(bare)));
  EXPECT_TRUE(Json::accept(out2.str())) << out2.str();
}

TEST(BatchErrors, MissingOrIllTypedOp) {
  EXPECT_EQ(ask(R"({"id":"a"})").dump(), R"({"id":"a","error":"op: missing field"})");
  EXPECT_EQ(ask(R"({"id":"a","op":3})").dump(), R"({"id":"a","op":3,"error":"op: expected a string, got number"})");
  EXPECT_EQ(ask(R"({"op":null})").dump(), R"({"op":null,"error":"op: expected a string, got null"})");
}

TEST(BatchErrors, IdMustBeAString) {
  EXPECT_EQ(ask(R"({"id":12,"op":"scene_pairs"})").dump(),
            R"({"id":12,"op":"scene_pairs","error":"id: expected a string, got number"})");
}

TEST(BatchErrors, DeeplyNestedIdOrOpIsNamedNotEchoed) {
  // Echoing a container copies it recursively: 100,000 levels overflowed the stack.
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  EXPECT_EQ(ask(R"({"id":)" + deep + R"(,"op":"scene_pairs"})").dump(),
            R"({"op":"scene_pairs","error":"id: expected a string, got array"})");
  EXPECT_EQ(ask(R"({"id":"d","op":)" + deep + "}").dump(), R"({"id":"d","error":"op: expected a string, got array"})");
  EXPECT_EQ(errorOf(ask(R"({"id":)" + deep + ",")).rfind("invalid JSON: ", 0), 0u);
}

TEST(BatchErrors, NulByteOutsideAStringIsInvalidJson) {
  // The parser reads a NUL as the end of its input: what follows must not be ignored.
  const Answer a = ask(std::string(R"({"id":"n","op":"scene_pairs"})") + '\0' + "this is not json");
  EXPECT_EQ(a.dump(), R"({"id":"n","op":"scene_pairs","error":"invalid JSON: NUL byte at column 30"})");
  EXPECT_EQ(errorOf(ask(std::string(R"({"id":"n)") + '\0' + R"("})")).rfind("invalid JSON: ", 0), 0u);  // in a string
}

TEST(BatchErrors, UnknownOp) {
  EXPECT_EQ(ask(R"({"id":"u","op":"triangle_cone"})").dump(),
            R"({"id":"u","op":"triangle_cone","error":"op: unknown op \"triangle_cone\""})");
  // Unknown stays unknown on every backend (it is not merely unsupported).
  for (const Backend b : {Backend::Fcl, Backend::Bullet, Backend::Exact})
    EXPECT_TRUE(errorStartsWith(R"({"op":"Ray_Triangle"})", "op: unknown op", b));
}

TEST(BatchErrors, MissingFields) {
  const std::string t = R"("triangle":)" + kUnitTriangle;
  EXPECT_TRUE(errorStartsWith(op("ray_triangle", t + R"(,"rays":{})"), "ray: missing field"));
  EXPECT_TRUE(errorStartsWith(R"({"op":"closest_point_triangle","point":[0,0,0]})", "triangle: missing field"));
  EXPECT_TRUE(errorStartsWith(op("closest_point_triangle", t), "point: missing field"));
  EXPECT_TRUE(errorStartsWith(op("triangle_sphere", t + R"(,"sphere":{"center":[0,0,0]})"),
                              "sphere.radius: missing field"));
  EXPECT_TRUE(errorStartsWith(op("triangle_aabb", t + R"(,"aabb":{"max":[0,0,0]})"), "aabb.min: missing field"));
  EXPECT_TRUE(errorStartsWith(op("triangle_obb", t + R"(,"obb":{"center":[0,0,0],"half":[1,1,1]})"),
                              "obb.axes: missing field"));
  EXPECT_TRUE(errorStartsWith(op("triangle_plane", t + R"(,"plane":{"normal":[0,0,1]})"), "plane.d: missing field"));
  EXPECT_TRUE(errorStartsWith(op("triangle_triangle", R"("a":)" + kUnitTriangle), "b: missing field"));
  EXPECT_TRUE(errorStartsWith(op("segment_triangle", t + R"(,"segment":{"start":[0,0,0]})"),
                              "segment.end: missing field"));
  EXPECT_TRUE(errorStartsWith(op("ray_triangle", t + R"(,"ray":{"dir":[0,0,1]})"), "ray.origin: missing field"));
}

TEST(BatchErrors, WrongTypes) {
  const std::string t = R"("triangle":)" + kUnitTriangle;
  EXPECT_TRUE(errorStartsWith(op("triangle_sphere", t + R"(,"sphere":{"center":[0,0,0],"radius":"1"})"),
                              "sphere.radius: expected a number, got string"));
  EXPECT_TRUE(errorStartsWith(op("triangle_sphere", t + R"(,"sphere":{"center":[0,0,0],"radius":true})"),
                              "sphere.radius: expected a number, got boolean"));
  EXPECT_TRUE(errorStartsWith(op("triangle_sphere", t + R"(,"sphere":[0,0,0,1])"), "sphere: expected a sphere"));
  EXPECT_TRUE(errorStartsWith(op("triangle_plane", t + R"(,"plane":{"normal":[0,null,1],"d":0})"),
                              "plane.normal[1]: expected a number, got null"));
  EXPECT_TRUE(errorStartsWith(op("ray_triangle", R"("triangle":"unit","ray":{"origin":[0,0,0],"dir":[1,0,0]})"),
                              "triangle: expected a triangle"));
  EXPECT_TRUE(errorStartsWith(op("triangle_obb", t + R"(,"obb":{"center":[0,0,0],"half":[1,1,1],"axes":{}})"),
                              "obb.axes: expected three axes"));
  EXPECT_TRUE(errorStartsWith(op("triangle_triangle", R"("a":)" + kUnitTriangle + R"(,"b":[[0,0,0],[1,"0",0],[0,1,0]])"),
                              "b[1][1]: expected a number, got string"));
}

TEST(BatchErrors, WrongVectorLengths) {
  const std::string t = R"("triangle":)" + kUnitTriangle;
  EXPECT_TRUE(errorStartsWith(op("ray_triangle", t + R"(,"ray":{"origin":[0,0,0],"dir":[1,0]})"),
                              "ray.dir: expected [x, y, z], got an array of 2 elements"));
  EXPECT_TRUE(errorStartsWith(op("closest_point_triangle", t + R"(,"point":[0,0,0,0])"),
                              "point: expected [x, y, z], got an array of 4 elements"));
  EXPECT_TRUE(errorStartsWith(op("closest_point_triangle", R"("triangle":[[0,0,0],[1,0,0]],"point":[0,0,0])"),
                              "triangle: expected a triangle"));
  EXPECT_TRUE(errorStartsWith(op("closest_point_triangle", R"("triangle":[[0,0,0],[1,0,0,1],[0,1,0]],"point":[0,0,0])"),
                              "triangle[1]: expected [x, y, z]"));
  EXPECT_TRUE(errorStartsWith(
      op("triangle_obb", t + R"(,"obb":{"center":[0,0,0],"half":[1,1,1],"axes":[[1,0,0],[0,1,0]]})"),
      "obb.axes: expected three axes"));
}

TEST(BatchErrors, NumberLiteralOverflowingDoubleNamesItsField) {
  // JSON has no NaN/Inf, but 1e400 overflows double; it is rejected naming the field, and the
  // id/op read before it are echoed.
  const Answer a = ask(op("triangle_sphere", R"("triangle":[[0,0,0],[1,0,0],[1e400,1,0]],"sphere":{"center":[0,0,0],"radius":1})"));
  EXPECT_EQ(a.value("id", ""), "q") << a.dump();
  EXPECT_EQ(a.value("op", ""), "triangle_sphere") << a.dump();
  EXPECT_EQ(errorOf(a), "triangle[2][0]: number 1e400 overflows double") << a.dump();
  EXPECT_TRUE(errorStartsWith(op("triangle_sphere", "\"triangle\":" + kUnitTriangle +
                                                        R"(,"sphere":{"center":[0,0,0],"radius":-1e400})"),
                              "sphere.radius: number -1e400 overflows double"));
  EXPECT_TRUE(errorStartsWith(R"({"op":"ray_triangle","ray":{"origin":[0,0,0],"dir":[1,0,0]},"triangle":[[0,0,0],[1,0,0],[0,1,1E999]]})",
                              "triangle[2][2]: number 1E999 overflows double"));
  EXPECT_TRUE(errorStartsWith("1e400", "request: number 1e400 overflows double"));
}

TEST(BatchErrors, NumberBeyondTheRangeOfReal) {
  // 1e39 is a finite double but overflows a float Real.
  const std::string line = op("triangle_plane", R"("triangle":[[0,0,0],[1e39,0,0],[0,1,0]],"plane":{"normal":[0,0,1],"d":0})");
  if (sizeof(Real) == sizeof(float)) {
    EXPECT_TRUE(errorStartsWith(line, "triangle[1][0]: number 1e+39 overflows crux::Real (float)"));
  } else {
    EXPECT_TRUE(answersHit(line, true));
  }
  // Underflow is not an error: 1e-400 reads as 0.
  EXPECT_TRUE(answersHit(op("triangle_plane", "\"triangle\":" + kUnitTriangle + R"(,"plane":{"normal":[0,0,1],"d":1e-400})"),
                         true));
}

TEST(BatchErrors, DeeplyNestedLinesDoNotCrash) {
  const std::size_t depth = 100000;
  EXPECT_TRUE(errorStartsWith(std::string(depth, '[') + std::string(depth, ']'),
                              "request: expected a JSON object, got array"));
  EXPECT_TRUE(errorStartsWith(R"({"op":"triangle_plane","triangle":)" + std::string(depth, '['), "invalid JSON: "));
  // An overflow deep inside is still located.
  std::string deep = R"({"op":"triangle_plane","x":)";
  for (int i = 0; i < 3; ++i) deep += R"([0,{"k":)";
  EXPECT_TRUE(errorStartsWith(deep + "1e999", "x[1].k[1].k[1].k: number 1e999 overflows double"));
}

TEST(BatchErrors, NonFiniteResultsAreErrorsNotNull) {
  const Real inf = std::numeric_limits<Real>::infinity();
  try {
    (void)writeReal(inf, "t");
    FAIL() << "writeReal accepted inf";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()), "t: result is not finite (the computation overflowed)");
  }
  EXPECT_THROW((void)writeVec3(Vec3(0, -inf, 0), "point"), InvalidInput);
  EXPECT_THROW((void)writeVec3(Vec3(0, 0, std::numeric_limits<Real>::quiet_NaN()), "point"), InvalidInput);
}

TEST(BatchErrors, SemanticValidationNamesTheField) {
  const std::string t = R"("triangle":)" + kUnitTriangle;
  EXPECT_TRUE(errorStartsWith(op("triangle_sphere", t + R"(,"sphere":{"center":[0,0,0],"radius":-0.5})"),
                              "sphere.radius is negative"));
  EXPECT_TRUE(errorStartsWith(op("ray_triangle", t + R"(,"ray":{"origin":[0,0,1],"dir":[0,0,0]})"),
                              "ray.dir is the zero vector"));
  EXPECT_TRUE(errorStartsWith(op("triangle_aabb", t + R"(,"aabb":{"min":[0,2,0],"max":[1,1,1]})"),
                              "aabb.min.y > aabb.max.y"));
  EXPECT_TRUE(errorStartsWith(op("triangle_obb", t + R"(,"obb":{"center":[0,0,0],"half":[1,1,1],"axes":[[1,0,0],[1,1,0],[0,0,1]]})"),
                              "obb.axes are not orthonormal"));
  EXPECT_TRUE(errorStartsWith(op("triangle_obb", t + R"(,"obb":{"center":[0,0,0],"half":[1,-1,1],"axes":[[1,0,0],[0,1,0],[0,0,1]]})"),
                              "obb.half has a negative extent"));
  EXPECT_TRUE(errorStartsWith(op("triangle_plane", t + R"(,"plane":{"normal":[0,0,0],"d":1})"),
                              "plane.normal is the zero vector"));
}

// ---------------------------------------------------------------------------------------------
// Unsupported ops and backends.

TEST(BatchUnsupported, ProtocolOpsAreTheContractsThirtyThreeTheFiveNarrowPhaseOpsAndTheCasts) {
  const auto& ops = protocolOps();
  EXPECT_EQ(ops.size(), 41u);
  for (const char* name : {"contacts", "distance", "mesh_distance", "model_distance", "point_inside", "cast",
                           "model_cast", "scene_cast"})
    EXPECT_TRUE(std::binary_search(ops.begin(), ops.end(), std::string_view(name))) << name;
  EXPECT_TRUE(std::is_sorted(ops.begin(), ops.end()));
  for (const char* name : {"closest_point_triangle", "segment_triangle", "mesh", "load_mesh", "mesh_mesh",
                           "set_parent", "children", "scene_ray", "scene_query", "scene_pairs", "model_triangle"})
    EXPECT_TRUE(std::binary_search(ops.begin(), ops.end(), std::string_view(name))) << name;
}

TEST(BatchUnsupported, NativeAnswersPrimitivesAndMeshesAndDefersTheRest) {
  const OpTable& native = opTable(Backend::Native);
  EXPECT_EQ(native.size(), 41u);  // every protocol op (model and scene ops: apps/cli/scene_ops.cpp)
  for (const char* name : {"mesh", "load_mesh", "mesh_ray", "mesh_segment", "mesh_sphere", "mesh_aabb", "mesh_obb",
                           "mesh_plane", "mesh_triangle", "mesh_mesh"})
    EXPECT_EQ(native.count(name), 1u) << name;
  for (const auto& [name, handler] : native) {
    EXPECT_TRUE(std::binary_search(protocolOps().begin(), protocolOps().end(), std::string_view(name))) << name;
    EXPECT_TRUE(handler) << name;
  }
  for (const std::string_view name : protocolOps()) {
    if (native.count(name)) continue;
    // No parse validation: the request carries no fields at all.
    const std::string line = R"({"id":"m","op":")" + std::string(name) + R"("})";
    EXPECT_EQ(ask(line).dump(), R"({"id":"m","op":")" + std::string(name) + R"(","error":"unsupported: )" +
                                    std::string(name) + R"( on native"})");
  }
}

/// Every built backend answers "unsupported: <op> on <backend>" for exactly the ops its world
/// does not supports(), before reading any field; the others get past dispatch.
TEST(BatchUnsupported, EachBackendAnswersUnsupportedExactlyForWhatItDoesNotSupport) {
  for (const std::string_view name : builtBackends()) {
    const Backend b = *parseBackend(name);
    const auto world = makeWorld(name);
    for (const std::string_view opName : protocolOps()) {
      const std::string n(opName);
      const Answer a = ask(R"({"op":")" + n + R"(","triangle":)" + kUnitTriangle + "}", b);
      const std::string unsupported = "unsupported: " + n + " on " + std::string(name);
      if (world->supports(*parseOp(opName)))
        EXPECT_NE(errorOf(a), unsupported) << a.dump();
      else
        EXPECT_EQ(errorOf(a), unsupported) << a.dump();
    }
  }
}

TEST(BatchUnsupported, BackendNames) {
  for (const Backend b : {Backend::Native, Backend::Fcl, Backend::Bullet, Backend::Exact})
    EXPECT_EQ(parseBackend(backendName(b)), b);
  EXPECT_EQ(backendNames().size(), 4u);
  EXPECT_FALSE(parseBackend("cuda").has_value());
  EXPECT_FALSE(parseBackend("Native").has_value());
  EXPECT_FALSE(parseBackend("").has_value());
}

// ---------------------------------------------------------------------------------------------
// Whole runs.

TEST(BatchRun, RunContinuesAfterErrorsAndAnswersEveryLineInOrder) {
  const std::vector<std::string> input = {
      R"({"id":"1","op":"triangle_plane","triangle":[[0,0,0],[1,0,0],[0,1,0]],"plane":{"normal":[0,0,1],"d":0}})",
      "not json",
      "",
      R"({"id":"4","op":"nope"})",
      R"({"id":"5","op":"add_model","name":"m"})",
      R"({"id":"6","op":"triangle_sphere","triangle":[[0,0,0],[1,0,0],[0,1,0]],"sphere":{"center":[0,0,0],"radius":-1}})",
      R"({"id":"7","op":"segment_triangle","triangle":[[0,0,0],[1,0,0],[0,1,0]],"segment":{"start":[0.1,0.1,1],"end":[0.1,0.1,-1]}})",
      "[]\r",
      R"({"id":"9","op":"triangle_plane","triangle":[[0,0,0],[1,0,0],[0,1,0]],"plane":{"normal":[0,0,1],"d":1}})"};
  std::string text;
  for (const auto& l : input) text += l + "\n";
  text.pop_back();  // the last line has no terminator
  std::istringstream in(text);
  std::ostringstream out;
  ASSERT_EQ(runBatch(in, out, BatchOptions{}), 0);
  const auto lines = splitLines(out.str());
  ASSERT_EQ(lines.size(), input.size()) << out.str();
  EXPECT_EQ(out.str().back(), '\n');
  std::vector<Json> answers;
  for (const auto& l : lines) answers.push_back(Json::parse(l));
  const bool isError[] = {false, true, true, true, true, true, false, true, false};
  for (std::size_t i = 0; i < answers.size(); ++i) {
    ASSERT_TRUE(answers[i].is_object()) << lines[i];
    EXPECT_EQ(answers[i].contains("error"), isError[i]) << i << ": " << lines[i];
  }
  EXPECT_EQ(answers[0]["id"], "1");
  EXPECT_TRUE(answers[0]["hit"].get<bool>());
  EXPECT_EQ(answers[3]["id"], "4");
  EXPECT_EQ(answers[4]["error"], "mesh: missing field");
  EXPECT_EQ(answers[6]["id"], "7");
  EXPECT_TRUE(answers[6]["hit"].get<bool>());
  EXPECT_EQ(answers[8]["id"], "9");
  EXPECT_FALSE(answers[8]["hit"].get<bool>());
}

TEST(BatchRun, EmptyInputGivesEmptyOutput) {
  std::istringstream in("");
  std::ostringstream out;
  EXPECT_EQ(runBatch(in, out, BatchOptions{}), 0);
  EXPECT_EQ(out.str(), "");
}

TEST(BatchRun, ThreadsMustBePositiveAndDoNotChangeTheOutput) {
  const std::string text = op("triangle_plane", "\"triangle\":" + kUnitTriangle + R"(,"plane":{"normal":[0,0,1],"d":0})") +
                           "\n{}\n" + op("mesh_ray", "\"mesh\":\"m\"") + "\n";
  std::istringstream in0(text);
  std::ostringstream out0;
  EXPECT_THROW(runBatch(in0, out0, BatchOptions{Backend::Native, 0}), InvalidInput);
  std::istringstream in1(text), in4(text);
  std::ostringstream out1, out4;
  EXPECT_EQ(runBatch(in1, out1, BatchOptions{Backend::Native, 1}), 0);
  EXPECT_EQ(runBatch(in4, out4, BatchOptions{Backend::Native, 4}), 0);
  EXPECT_EQ(out1.str(), out4.str());
  EXPECT_EQ(splitLines(out1.str()).size(), 3u);
}

/// Output that keeps what is written pending until flushed, as a pipe's writer buffers it.
class PendingOutput : public std::streambuf {
 public:
  std::string pending, flushed;

 protected:
  int_type overflow(int_type c) override {
    if (c != traits_type::eof()) pending.push_back(char(c));
    return c;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    pending.append(s, std::size_t(n));
    return n;
  }
  int sync() override {
    flushed += pending;
    pending.clear();
    return 0;
  }
};

/// Input handed over one line at a time, as a driver writing a line and waiting for its answer
/// does: each time the reader asks for more (it would block on a pipe), what the output had
/// flushed by then is recorded.
class LineByLineInput : public std::streambuf {
 public:
  LineByLineInput(std::vector<std::string> lines, const PendingOutput& out) : lines_(std::move(lines)), out_(out) {}
  std::vector<std::string> flushedAtEachWait;

 protected:
  int_type underflow() override {
    flushedAtEachWait.push_back(out_.flushed);
    if (next_ == lines_.size()) return traits_type::eof();
    current_ = lines_[next_++] + "\n";
    setg(current_.data(), current_.data(), current_.data() + current_.size());
    return traits_type::to_int_type(current_[0]);
  }
  std::streamsize showmanyc() override { return 0; }  // nothing beyond the line handed over

 private:
  std::vector<std::string> lines_;
  std::size_t next_ = 0;
  std::string current_;
  const PendingOutput& out_;
};

TEST(BatchRun, EveryAnswerIsFlushedBeforeWaitingForTheNextLine) {
  const std::vector<std::string> lines = {
      op("triangle_plane", "\"triangle\":" + kUnitTriangle + R"(,"plane":{"normal":[0,0,1],"d":0})"), "{}",
      op("triangle_plane", "\"triangle\":" + kUnitTriangle + R"(,"plane":{"normal":[0,0,1],"d":5})")};
  PendingOutput outBuf;
  LineByLineInput inBuf(lines, outBuf);
  std::istream in(&inBuf);
  std::ostream out(&outBuf);
  ASSERT_EQ(runBatch(in, out, BatchOptions{}), 0);
  ASSERT_EQ(inBuf.flushedAtEachWait.size(), lines.size() + 1);
  for (std::size_t k = 0; k < inBuf.flushedAtEachWait.size(); ++k)
    EXPECT_EQ(splitLines(inBuf.flushedAtEachWait[k]).size(), k) << "answers flushed before reading line " << k;
}

TEST(BatchRun, FailingOutputIsReported) {
  std::istringstream in("{}\n{}\n");
  std::ostringstream out;
  out.setstate(std::ios::badbit);
  EXPECT_EQ(runBatch(in, out, BatchOptions{}), 1);
}

// ---------------------------------------------------------------------------------------------
// Doubles round-trip exactly.

TEST(BatchNumbers, WrittenDoublesParseBackToTheSameValue) {
  std::mt19937_64 rng(0x5eedba7c4);
  std::uniform_real_distribution<double> uniform(-1000.0, 1000.0);
  std::vector<Real> values = {Real(0.1), Real(1) / Real(3), std::numeric_limits<Real>::max(),
                              std::numeric_limits<Real>::min(), std::numeric_limits<Real>::denorm_min(),
                              -Real(0), Real(16777217), Real(1e-7)};
  for (int i = 0; i < 1000; ++i) values.push_back(static_cast<Real>(uniform(rng)));
  for (const Real x : values) {
    const std::string text = writeVec3(Vec3(x, -x, x * Real(0.5)), "v").dump();
    const Json back = Json::parse(text);
    ASSERT_EQ(back[0].get<double>(), static_cast<double>(x)) << text;
    ASSERT_EQ(back[1].get<double>(), static_cast<double>(-x)) << text;
    ASSERT_EQ(back[2].get<double>(), static_cast<double>(x * Real(0.5))) << text;
    // A Real written and read back through the protocol is the same Real.
    ASSERT_EQ(readReal(back[0], "x"), x) << text;
  }
}

TEST(BatchNumbers, RayHitTravelsThroughTheProtocolBitExactly) {
  // Random rays at a fixed triangle: t and point in the answer equal crux::raycast's, bit for bit.
  std::mt19937_64 rng(0xba7c5);
  std::uniform_real_distribution<double> coord(-2.0, 2.0);
  const Triangle tri{Vec3(Real(0.1), Real(0.2), Real(0.3)), Vec3(Real(1.7), Real(-0.3), Real(0.1)),
                     Vec3(Real(0.2), Real(1.9), Real(-0.4))};
  int hits = 0;
  const int cases = 500;
  for (int i = 0; i < cases; ++i) {
    const Vec3 origin(Real(coord(rng)), Real(coord(rng)), Real(coord(rng)) + Real(3));
    const Vec3 target(Real(coord(rng) * 0.5 + 0.6), Real(coord(rng) * 0.5 + 0.6), Real(0));
    Ray ray{origin, target - origin};
    std::ostringstream line;
    line.precision(17);
    const auto v = [&](const Vec3& p) {
      std::ostringstream s;
      s.precision(17);
      s << "[" << double(p.x()) << "," << double(p.y()) << "," << double(p.z()) << "]";
      return s.str();
    };
    line << R"({"op":"ray_triangle","triangle":[)" << v(tri.a) << "," << v(tri.b) << "," << v(tri.c)
         << R"(],"ray":{"origin":)" << v(ray.origin) << R"(,"dir":)" << v(ray.dir) << "}}";
    std::ostringstream out;
    BatchState state;
    writeAnswer(out, answerLine(line.str(), state));
    const Json a = Json::parse(out.str());
    const auto expected = raycast(ray, tri);
    ASSERT_EQ(a.value("hit", !expected.has_value()), expected.has_value()) << line.str() << " -> " << out.str();
    if (!expected) continue;
    ++hits;
    ASSERT_EQ(a["t"].get<double>(), static_cast<double>(expected->t)) << out.str();
    for (std::size_t k = 0; k < 3; ++k)
      ASSERT_EQ(a["point"][k].get<double>(), static_cast<double>(expected->point[Eigen::Index(k)])) << out.str();
  }
  // The generator must exercise both answers.
  EXPECT_GE(hits, cases / 5);
  EXPECT_LE(hits, cases * 4 / 5);
}

// ---------------------------------------------------------------------------------------------
// The shipped examples and the executable.

/// Runs examples/<name> as one batch and checks every answer against its request's id:
/// "err-..." an error, "hit-..." hit true, "miss-..." hit false, anything else no error.
void checkExampleFile(const std::string& name, std::size_t minLines, std::size_t minErrors) {
  std::ifstream file(std::string(CRUX_SOURCE_DIR) + "/examples/" + name);
  ASSERT_TRUE(file) << "examples/" << name << " not found";
  std::stringstream text;
  text << file.rdbuf();
  const auto input = splitLines(text.str());
  ASSERT_GE(input.size(), minLines);
  std::istringstream in(text.str());
  std::ostringstream out;
  ASSERT_EQ(runBatch(in, out, BatchOptions{}), 0);
  const auto lines = splitLines(out.str());
  ASSERT_EQ(lines.size(), input.size());
  std::size_t errors = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const Json request = Json::parse(input[i]);
    const Json answer = Json::parse(lines[i]);
    const std::string id = request.value("id", "");
    ASSERT_EQ(answer.value("id", ""), id) << lines[i];
    if (id.rfind("err-", 0) == 0) {
      EXPECT_TRUE(answer.contains("error")) << input[i] << " -> " << lines[i];
      ++errors;
    } else {
      EXPECT_FALSE(answer.contains("error")) << input[i] << " -> " << lines[i];
    }
    if (id.rfind("hit-", 0) == 0) EXPECT_EQ(answer.value("hit", false), true) << input[i] << " -> " << lines[i];
    if (id.rfind("miss-", 0) == 0) EXPECT_EQ(answer.value("hit", true), false) << input[i] << " -> " << lines[i];
  }
  EXPECT_GE(errors, minErrors);
}

TEST(BatchExamples, PrimitivesJsonlAnswersAsItsIdsSay) { checkExampleFile("primitives.jsonl", 20, 2); }

TEST(BatchExamples, MeshesJsonlAnswersAsItsIdsSay) { checkExampleFile("meshes.jsonl", 20, 3); }

TEST(BatchExecutable, CommandLine) {
  using test::run;
  const std::string crux = test::cruxExecutable();
  if (access(crux.c_str(), X_OK) != 0) GTEST_SKIP() << crux << " not built";
  const auto [helpStatus, help] = run("'" + crux + "' --help");
  EXPECT_EQ(helpStatus, 0);
  EXPECT_NE(help.find("batch"), std::string::npos) << help;
  EXPECT_NE(help.find("info"), std::string::npos) << help;
  const auto [versionStatus, version] = run("'" + crux + "' --version");
  EXPECT_EQ(versionStatus, 0);
  EXPECT_NE(version.find("crux "), std::string::npos) << version;
  const auto [batchHelpStatus, batchHelp] = run("'" + crux + "' batch --help");
  EXPECT_EQ(batchHelpStatus, 0);
  EXPECT_NE(batchHelp.find("--backend"), std::string::npos) << batchHelp;
  EXPECT_NE(batchHelp.find("--threads"), std::string::npos) << batchHelp;

  const auto [badBackend, badOut] = run("echo '{}' | '" + crux + "' batch --backend cuda 2>&1");
  EXPECT_NE(badBackend, 0);
  EXPECT_NE(badOut.find("unknown backend 'cuda'"), std::string::npos) << badOut;
  const auto [badThreads, threadsOut] = run("echo '{}' | '" + crux + "' batch --threads 0 2>&1");
  EXPECT_NE(badThreads, 0) << threadsOut;
  // Option values are refused naming what is expected, with the value as given.
  for (const auto& [option, message] :
       std::vector<std::pair<std::string, std::string>>{{"--threads abc", "expected a whole number of threads >= 1, got 'abc'"},
                                                        {"--threads 2.5", "expected a whole number of threads >= 1, got '2.5'"},
                                                        {"--timeout 0", "expected a finite number of seconds > 0, got '0'"},
                                                        {"--timeout nan", "expected a finite number of seconds > 0, got 'nan'"},
                                                        {"--timeout inf", "expected a finite number of seconds > 0, got 'inf'"}}) {
    const auto [badStatus, badText] = run("echo '{}' | '" + crux + "' batch " + option + " 2>&1");
    EXPECT_NE(badStatus, 0) << option;
    EXPECT_NE(badText.find(message), std::string::npos) << option << ": " << badText;
    EXPECT_LT(badText.size(), 400u) << option << ": " << badText;
  }

  const std::string request = R"({"id":"p","op":"triangle_plane","triangle":[[0,0,0],[1,0,0],[0,1,0]],"plane":{"normal":[0,0,1],"d":0}})";
  const auto [status, out] = run("printf '%s\\n\\n%s' '" + request + "' '" + request + "' | '" + crux +
                                 "' batch --backend native --threads 2");
  EXPECT_EQ(status, 0);
  EXPECT_EQ(out, R"({"id":"p","op":"triangle_plane","hit":true})" "\n" R"({"error":"empty line"})" "\n"
                 R"({"id":"p","op":"triangle_plane","hit":true})" "\n");
  // Every built backend answers through the executable: a clear crossing, or "unsupported".
  const std::string crossing =
      R"({"id":"p","op":"triangle_plane","triangle":[[0,0,-1],[1,0,1],[0,1,1]],"plane":{"normal":[0,0,1],"d":0}})";
  for (const std::string_view name : builtBackends()) {
    const std::string backend(name);
    const auto [peerStatus, peerOut] = run("printf '%s\\n' '" + crossing + "' | '" + crux + "' batch --backend " + backend);
    EXPECT_EQ(peerStatus, 0) << backend;
    EXPECT_EQ(peerOut, makeWorld(name)->supports(WorldOp::TrianglePlane)
                           ? std::string(R"({"id":"p","op":"triangle_plane","hit":true})" "\n")
                           : R"({"id":"p","op":"triangle_plane","error":"unsupported: triangle_plane on )" + backend +
                                 "\"}\n")
        << backend;
  }
}

// ---------------------------------------------------------------------------------------------
// Every backend through the protocol: the sanity script.

const std::string kCube =
    R"("vertices":[[0,0,0],[1,0,0],[1,1,0],[0,1,0],[0,0,1],[1,0,1],[1,1,1],[0,1,1]],)"
    R"("triangles":[[0,2,1],[0,3,2],[4,5,6],[4,6,7],[0,1,5],[0,5,4],[1,2,6],[1,6,5],[2,3,7],[2,7,6],[3,0,4],[3,4,7]])";
const std::string kT = R"([[0,0,0],[4,0,0],[0,4,0]])";
const std::string kScenePairs = R"({"id":"q","op":"scene_pairs"})";
const std::string kRot45 = R"([[0.7071067811865476,0.7071067811865476,0],[-0.7071067811865476,0.7071067811865476,0],[0,0,1]])";

/// A script covering every protocol op on unambiguous cases: every hit is a clear crossing or
/// penetration, every miss a clear separation (no touching, no shape inside a closed mesh), and
/// every ray meets a face away from its edges.
std::vector<std::string> sanityScript() {
  const auto obb = [](const std::string& center, const std::string& half) {
    return R"({"center":)" + center + R"(,"half":)" + half + R"(,"axes":)" + kRot45 + "}";
  };
  const auto at = [](const std::string& t) { return R"({"translation":)" + t + "}"; };
  return {
      op("closest_point_triangle", R"("triangle":)" + kT + R"(,"point":[1,1,3])"),
      op("triangle_sphere", R"("triangle":)" + kT + R"(,"sphere":{"center":[1,1,1],"radius":2})"),
      op("triangle_sphere", R"("triangle":)" + kT + R"(,"sphere":{"center":[1,1,5],"radius":1})"),
      op("triangle_aabb", R"("triangle":)" + kT + R"(,"aabb":{"min":[0.5,0.5,-1],"max":[1,1,1]})"),
      op("triangle_aabb", R"("triangle":)" + kT + R"(,"aabb":{"min":[5,5,-1],"max":[6,6,1]})"),
      op("triangle_obb", R"("triangle":)" + kT + R"(,"obb":)" + obb("[1,1,0]", "[0.5,0.5,0.5]")),
      op("triangle_obb", R"("triangle":)" + kT + R"(,"obb":)" + obb("[1,1,3]", "[0.5,0.5,0.5]")),
      op("triangle_plane", R"("triangle":)" + kT + R"(,"plane":{"normal":[1,0,0],"d":1})"),
      op("triangle_plane", R"("triangle":)" + kT + R"(,"plane":{"normal":[0,0,1],"d":2})"),
      op("triangle_triangle", R"("a":)" + kT + R"(,"b":[[1,1,-1],[2,1,1],[1,1,1]])"),
      op("triangle_triangle", R"("a":)" + kT + R"(,"b":[[1,1,4],[2,1,6],[1,1,6]])"),
      op("ray_triangle", R"("triangle":)" + kT + R"(,"ray":{"origin":[1,1,5],"dir":[0,0,-1]})"),
      op("ray_triangle", R"("triangle":)" + kT + R"(,"ray":{"origin":[1,1,5],"dir":[0,0,1]})"),
      op("segment_triangle", R"("triangle":)" + kT + R"(,"segment":{"start":[1,1,1],"end":[1,1,-1]})"),
      op("segment_triangle", R"("triangle":)" + kT + R"(,"segment":{"start":[1,1,1],"end":[1,1,2]})"),
      op("mesh", R"("name":"cube",)" + kCube),
      op("load_mesh", R"("name":"tetrahedron","path":")" + std::string(CRUX_SOURCE_DIR) +
                          R"(/data/meshes/reference_tetrahedron.off")"),
      op("mesh_ray", R"("mesh":"cube","ray":{"origin":[0.25,0.75,5],"dir":[0,0,-1]})"),
      op("mesh_ray", R"("mesh":"cube","ray":{"origin":[5,5,5],"dir":[0,0,-1]})"),
      op("mesh_segment", R"("mesh":"cube","segment":{"start":[0.3,0.6,0.5],"end":[0.3,0.6,3]})"),
      op("mesh_segment", R"("mesh":"cube","segment":{"start":[3,3,3],"end":[4,4,4]})"),
      op("mesh_sphere", R"("mesh":"cube","sphere":{"center":[0.3,0.6,1],"radius":0.25})"),
      op("mesh_sphere", R"("mesh":"cube","sphere":{"center":[3,3,3],"radius":0.5})"),
      op("mesh_aabb", R"("mesh":"cube","aabb":{"min":[0.8,0.8,0.8],"max":[1.5,1.5,1.5]})"),
      op("mesh_aabb", R"("mesh":"cube","aabb":{"min":[2,2,2],"max":[3,3,3]})"),
      op("mesh_obb", R"("mesh":"cube","obb":)" + obb("[1,1,1]", "[0.3,0.3,0.3]")),
      op("mesh_obb", R"("mesh":"cube","obb":)" + obb("[3,3,3]", "[0.3,0.3,0.3]")),
      op("mesh_plane", R"("mesh":"cube","plane":{"normal":[0,0,1],"d":0.5})"),
      op("mesh_plane", R"("mesh":"cube","plane":{"normal":[0,0,1],"d":3})"),
      op("mesh_triangle", R"("mesh":"cube","triangle":[[0.5,0.5,0.5],[2,0.6,0.5],[0.6,2,0.5]])"),
      op("mesh_triangle", R"("mesh":"cube","triangle":[[3,3,3],[4,3,3],[3,4,3]])"),
      op("mesh_mesh", R"("a":"cube","b":"cube","transform_b":)" + at("[0.5,0.3,0.2]")),
      op("mesh_mesh", R"("a":"cube","b":"cube","transform_b":)" + at("[3,0,0]")),
      op("add_model", R"("name":"a","mesh":"cube")"),
      op("add_model", R"("name":"b","mesh":"cube","transform":)" + at("[3,0,0]")),
      op("add_model", R"("name":"c","mesh":"cube","parent":"a","transform":)" + at("[0,0,3]")),
      op("children", R"("model":"a")"),
      op("model_ray", R"("model":"c","ray":{"origin":[0.25,0.75,10],"dir":[0,0,-1]})"),
      op("model_ray", R"("model":"b","ray":{"origin":[0.25,0.75,10],"dir":[0,0,-1]})"),
      op("model_segment", R"("model":"a","segment":{"start":[0.3,0.6,0.5],"end":[0.3,0.6,2]})"),
      op("model_segment", R"("model":"b","segment":{"start":[0.3,0.6,0.5],"end":[0.3,0.6,2]})"),
      op("model_sphere", R"("model":"b","sphere":{"center":[3.3,0.6,1],"radius":0.25})"),
      op("model_sphere", R"("model":"a","sphere":{"center":[3.3,0.6,1],"radius":0.25})"),
      op("model_aabb", R"("model":"c","aabb":{"min":[0.8,0.8,3.8],"max":[1.5,1.5,4.5]})"),
      op("model_aabb", R"("model":"a","aabb":{"min":[0.8,0.8,3.8],"max":[1.5,1.5,4.5]})"),
      op("model_obb", R"("model":"a","obb":)" + obb("[1,1,1]", "[0.3,0.3,0.3]")),
      op("model_obb", R"("model":"b","obb":)" + obb("[1,1,1]", "[0.3,0.3,0.3]")),
      op("model_plane", R"("model":"b","plane":{"normal":[1,0,0],"d":3.5})"),
      op("model_plane", R"("model":"a","plane":{"normal":[1,0,0],"d":3.5})"),
      op("model_triangle", R"("model":"a","triangle":[[0.5,0.5,0.5],[2,0.6,0.5],[0.6,2,0.5]])"),
      op("model_triangle", R"("model":"b","triangle":[[0.5,0.5,0.5],[2,0.6,0.5],[0.6,2,0.5]])"),
      op("scene_ray", R"("ray":{"origin":[3.25,0.75,10],"dir":[0,0,-1]})"),
      op("scene_ray", R"("ray":{"origin":[10,10,10],"dir":[0,0,-1]})"),
      op("scene_query", R"("sphere":{"center":[0.5,0.5,2],"radius":1.2})"),
      op("scene_query", R"("aabb":{"min":[2.5,-1,-1],"max":[3.5,2,2]})"),
      op("scene_query", R"("obb":)" + obb("[3.5,0.5,1]", "[0.2,0.2,0.2]")),
      op("scene_query", R"("aabb":{"min":[-1,-1,-1],"max":[10,10,10]},"bounds":true)"),
      kScenePairs,
      op("set_transform", R"("model":"b","transform":)" + at("[0.5,0,0]")),
      kScenePairs,
      op("set_parent", R"("model":"c","parent":null)"),
      op("set_transform", R"("model":"a","transform":)" + at("[0,0,2.5]")),
      kScenePairs,
      op("remove_model", R"("model":"c")"),
      kScenePairs,
      op("children", R"("model":"a")"),
      op("scene_ray", R"("ray":{"origin":[0.25,0.75,10],"dir":[0,0,-1]})"),
  };
}

/// `peer` equals `native` except that numbers may differ by `tolerance`: same keys in the same
/// order, same booleans, strings and integers.
::testing::AssertionResult sameAnswer(const Json& native, const Json& peer, double tolerance) {
  if (native.is_number_float() || peer.is_number_float()) {
    if (!native.is_number() || !peer.is_number() ||
        !(std::fabs(native.get<double>() - peer.get<double>()) <= tolerance))
      return ::testing::AssertionFailure() << peer.dump() << " != " << native.dump() << " within " << tolerance;
    return ::testing::AssertionSuccess();
  }
  if (native.type() != peer.type()) return ::testing::AssertionFailure() << peer.dump() << " != " << native.dump();
  if (native.is_array() || native.is_object()) {
    if (native.size() != peer.size()) return ::testing::AssertionFailure() << peer.dump() << " != " << native.dump();
    if (native.is_object()) {
      for (auto it = native.begin(); it != native.end(); ++it) {
        if (!peer.contains(it.key())) return ::testing::AssertionFailure() << "no " << it.key() << " in " << peer.dump();
        auto r = sameAnswer(*it, peer[it.key()], tolerance);
        if (!r) return r << " (member " << it.key() << ")";
      }
    } else {
      for (std::size_t i = 0; i < native.size(); ++i) {
        auto r = sameAnswer(native[i], peer[i], tolerance);
        if (!r) return r << " (element " << i << ")";
      }
    }
    return ::testing::AssertionSuccess();
  }
  if (native != peer) return ::testing::AssertionFailure() << peer.dump() << " != " << native.dump();
  return ::testing::AssertionSuccess();
}

/// Every built backend answers the sanity script: ops it supports() exactly as native does
/// (numbers within the two backends' declared tolerances), the others "unsupported: <op> on
/// <backend>". Native itself answers every line without an error, with hits and misses as
/// hand-checked.
TEST(BatchBackends, EveryBackendAnswersTheSanityScriptAsNativeDoes) {
  const std::vector<std::string> script = sanityScript();
  BatchState native(BatchOptions{Backend::Native, 1});
  std::vector<Answer> nativeAnswers;
  for (const std::string& line : script) {
    nativeAnswers.push_back(answerLine(line, native));
    EXPECT_EQ(errorOf(nativeAnswers.back()), "") << line << " -> " << nativeAnswers.back().dump();
  }
  // Hand-checked answers: the hits and misses alternate as written, and a few values.
  std::size_t hits = 0, misses = 0;
  for (const Answer& a : nativeAnswers) {
    if (!a.contains("hit")) continue;
    (a["hit"].get<bool>() ? hits : misses) += 1;
  }
  EXPECT_EQ(hits, 24u);
  EXPECT_EQ(misses, 23u);
  EXPECT_TRUE(isPoint(nativeAnswers[0]["point"], 1, 1, 0));
  EXPECT_EQ(nativeAnswers[17]["triangle"], 3);
  EXPECT_EQ(nativeAnswers[36].dump(), R"({"id":"q","op":"children","models":["c"]})");
  EXPECT_EQ(nativeAnswers[51]["model"], "b");
  EXPECT_EQ(nativeAnswers[51]["t"], 9.0);
  EXPECT_EQ(nativeAnswers[53].dump(), R"({"id":"q","op":"scene_query","models":["a","c"]})");
  EXPECT_EQ(nativeAnswers[55].dump(), R"({"id":"q","op":"scene_query","models":["b"]})");
  EXPECT_EQ(nativeAnswers[56].dump(), R"({"id":"q","op":"scene_query","models":["a","b","c"]})");
  EXPECT_EQ(nativeAnswers[57].dump(), R"({"id":"q","op":"scene_pairs","pairs":[]})");
  EXPECT_EQ(nativeAnswers[59].dump(), R"({"id":"q","op":"scene_pairs","pairs":[["a","b"]]})");
  EXPECT_EQ(nativeAnswers[62].dump(), R"({"id":"q","op":"scene_pairs","pairs":[["a","c"]]})");
  EXPECT_EQ(nativeAnswers[64].dump(), R"({"id":"q","op":"scene_pairs","pairs":[]})");
  EXPECT_EQ(nativeAnswers[65].dump(), R"({"id":"q","op":"children","models":[]})");
  EXPECT_TRUE(isPoint(nativeAnswers[66]["point"], 0.25, 0.75, 3.5));

  const double nativeError = makeWorld("native")->tolerance().at(10);
  for (const std::string_view name : builtBackends()) {
    if (name == "native") continue;
    BatchState peer(BatchOptions{*parseBackend(name), 1});
    const double tolerance = nativeError + peer.world->tolerance().at(10);
    std::size_t supported = 0;
    for (std::size_t i = 0; i < script.size(); ++i) {
      const Answer a = answerLine(script[i], peer);
      const std::string opName = Json::parse(script[i])["op"];
      if (peer.world->supports(*parseOp(opName))) {
        ++supported;
        EXPECT_TRUE(sameAnswer(Json::parse(nativeAnswers[i].dump()), Json::parse(a.dump()), tolerance))
            << name << ", line " << i << ": " << script[i];
      } else {
        EXPECT_EQ(a.dump(), R"({"id":"q","op":")" + opName + R"(","error":"unsupported: )" + opName + " on " +
                                std::string(name) + R"("})")
            << script[i];
      }
    }
    std::printf("  %-7s answers %zu of the %zu sanity lines (the others: unsupported)\n", std::string(name).c_str(),
                supported, script.size());
  }
}

// ---------------------------------------------------------------------------------------------
// --threads: parallel runs of query lines, answers identical to one thread.

/// A seeded mixed script of `lines` lines: meshes (the cube and the bunny), models added,
/// moved, re-parented and removed among runs of ray, shape and scene queries, scene_pairs,
/// malformed and empty lines.
std::string mixedScript(std::size_t lines, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  const auto pick = [&](int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); };
  const auto vec = [&](double r) {
    std::ostringstream os;
    os.precision(17);
    os << "[" << uniform(-r, r) << "," << uniform(-r, r) << "," << uniform(-r, r) << "]";
    return os.str();
  };
  std::ostringstream out;
  out << op("mesh", R"("name":"cube",)" + kCube) << "\n";
  out << op("load_mesh", R"("name":"bunny","path":")" + std::string(CRUX_SOURCE_DIR) + R"(/data/meshes/bunny00.off")")
      << "\n";
  int nextModel = 0;
  std::vector<int> live;
  const auto model = [&] { return "\"m" + std::to_string(live[std::size_t(pick(int(live.size())))]) + "\""; };
  for (std::size_t i = 2; i < lines; ++i) {
    const int r = pick(100);
    if (live.size() < 4 || r < 3) {
      const std::string parent = (!live.empty() && pick(3) == 0) ? R"(,"parent":)" + model() : "";
      out << op("add_model", R"("name":"m)" + std::to_string(nextModel) + R"(","mesh":")" +
                                 (pick(4) == 0 ? "bunny" : "cube") + R"(","transform":{"translation":)" + vec(3) + "}" +
                                 parent)
          << "\n";
      live.push_back(nextModel++);
    } else if (r < 6) {
      out << op("set_transform", R"("model":)" + model() + R"(,"transform":{"translation":)" + vec(3) +
                                     R"(,"rotation":[0.7071067811865476,0,0.7071067811865476,0]})")
          << "\n";
    } else if (r < 7) {
      const std::size_t k = std::size_t(pick(int(live.size())));
      out << op("remove_model", R"("model":"m)" + std::to_string(live[k]) + "\"") << "\n";
      live.erase(live.begin() + std::ptrdiff_t(k));
    } else if (r < 8) {
      out << op("set_parent", R"("model":)" + model() + R"(,"parent":)" + (pick(2) ? model() : "null")) << "\n";
    } else if (r < 9) {
      out << kScenePairs << "\n";
    } else if (r < 10) {
      out << (pick(2) ? "" : "{\"op\":") << "\n";
    } else if (r < 40) {
      out << op("scene_ray", R"("ray":{"origin":)" + vec(4) + R"(,"dir":)" + vec(1) + "}") << "\n";
    } else if (r < 60) {
      out << op("mesh_ray", R"("mesh":"bunny","all":true,"ray":{"origin":)" + vec(0.2) + R"(,"dir":)" + vec(1) + "}")
          << "\n";
    } else if (r < 75) {
      out << op("model_ray", R"("model":)" + model() + R"(,"ray":{"origin":)" + vec(4) + R"(,"dir":)" + vec(1) + "}")
          << "\n";
    } else if (r < 85) {
      out << op("scene_query", R"("sphere":{"center":)" + vec(4) + R"(,"radius":0.7})") << "\n";
    } else if (r < 95) {
      out << op("model_sphere", R"("model":)" + model() + R"(,"sphere":{"center":)" + vec(4) + R"(,"radius":0.5})")
          << "\n";
    } else {
      out << op("children", R"("model":)" + model()) << "\n";
    }
  }
  return out.str();
}

std::string runWith(const std::string& text, Backend backend, int threads) {
  std::istringstream in(text);
  std::ostringstream out;
  EXPECT_EQ(runBatch(in, out, BatchOptions{backend, threads}), 0);
  return out.str();
}

TEST(BatchThreads, ParallelRunsAnswerExactlyAsOneThread) {
  const std::string text = mixedScript(6000, 8);  // more than one read-ahead window
  const std::string one = runWith(text, Backend::Native, 1);
  const auto lines = splitLines(one);
  ASSERT_EQ(lines.size(), 6000u);
  std::size_t errors = 0, hits = 0;
  for (const std::string& l : lines) {
    errors += l.find("\"error\"") != std::string::npos;
    hits += l.find("\"hit\":true") != std::string::npos;
  }
  EXPECT_GT(hits, 600u) << "the script should hit often";
  EXPECT_LT(errors, 600u) << "the script should mostly be valid";
  for (const int threads : {2, 8}) EXPECT_EQ(runWith(text, Backend::Native, threads), one) << threads << " threads";
  // A window ending in a barrier, and a last window of one line.
  const std::string edge = op("mesh", R"("name":"cube",)" + kCube) + "\n" +
                           op("mesh_ray", R"("mesh":"cube","ray":{"origin":[0.25,0.75,5],"dir":[0,0,-1]})") + "\n";
  EXPECT_EQ(runWith(edge, Backend::Native, 2), runWith(edge, Backend::Native, 1));
}

TEST(BatchThreads, PeerBackendsAnswerSeriallyWithTheSameOutput) {
  const std::vector<std::string> script = sanityScript();
  std::string text;
  for (const std::string& line : script) text += line + "\n";
  for (const std::string_view name : builtBackends())
    EXPECT_EQ(runWith(text, *parseBackend(name), 4), runWith(text, *parseBackend(name), 1)) << name;
}

TEST(BatchThreads, BarrierOps) {
  for (const char* name : {"mesh", "load_mesh", "add_model", "set_transform", "set_parent", "remove_model", "scene_pairs"})
    EXPECT_TRUE(isBarrierOp(name)) << name;
  std::size_t barriers = 0;
  for (const std::string_view name : protocolOps()) barriers += isBarrierOp(name);
  EXPECT_EQ(barriers, 7u);
}


// ---------------------------------------------------------------------------------------------
// Streaming and isolation: answers are flushed line by line; a peer that aborts, crashes or
// hangs costs its line only.

/// `crux batch ARGS` with its standard input and output connected to this test, so the test can
/// wait for an answer before it sends the next line.
class Interactive {
 public:
  explicit Interactive(const std::vector<std::string>& args) {
    int in[2], out[2];
    EXPECT_EQ(pipe2(in, O_CLOEXEC), 0);
    EXPECT_EQ(pipe2(out, O_CLOEXEC), 0);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, in[0], 0);
    posix_spawn_file_actions_adddup2(&actions, out[1], 1);
    std::vector<std::string> argv = {test::cruxExecutable(), "batch"};
    argv.insert(argv.end(), args.begin(), args.end());
    std::vector<char*> raw;
    for (std::string& a : argv) raw.push_back(a.data());
    raw.push_back(nullptr);
    EXPECT_EQ(posix_spawn(&pid_, raw[0], &actions, nullptr, raw.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    close(in[0]);
    close(out[1]);
    to_ = in[1];
    from_ = out[0];
  }
  ~Interactive() {
    if (to_ >= 0) close(to_);
    close(from_);
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  void send(const std::string& line) {
    const std::string text = line + "\n";
    EXPECT_EQ(write(to_, text.data(), text.size()), ssize_t(text.size()));
  }
  /// The next answer line, or "" when none came within `seconds`.
  std::string readLine(double seconds = 20) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    for (;;) {
      if (const auto eol = buffer_.find('\n'); eol != std::string::npos) {
        std::string line = buffer_.substr(0, eol);
        buffer_.erase(0, eol + 1);
        return line;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      pollfd p{from_, POLLIN, 0};
      if (left.count() <= 0 || poll(&p, 1, int(left.count())) <= 0) return "";
      char chunk[4096];
      const ssize_t n = read(from_, chunk, sizeof chunk);
      if (n <= 0) return "";
      buffer_.append(chunk, std::size_t(n));
    }
  }
  /// Closes standard input and returns the exit status (-1 when killed by a signal).
  int finish() {
    close(to_);
    to_ = -1;
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = 0;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

 private:
  pid_t pid_ = 0;
  int to_ = -1, from_ = -1;
  std::string buffer_;
};

const std::string kTouchingTriangleSphere =
    R"({"id":"ok1","op":"triangle_sphere","triangle":[[0,0,0],[1,0,0],[0,1,0]],"sphere":{"center":[0.2,0.2,0.1],"radius":0.5}})";

bool backendBuilt(std::string_view name) {
  return std::find(builtBackends().begin(), builtBackends().end(), name) != builtBackends().end();
}

TEST(BatchStreaming, EachAnswerIsWrittenBeforeTheNextLineIsRead) {
  std::vector<std::vector<std::string>> runs = {{}, {"--threads", "2"}};
  for (const char* peer : {"fcl", "bullet"})
    if (backendBuilt(peer)) runs.push_back({"--backend", peer});
  for (const auto& args : runs) {
    Interactive crux(args);
    for (int i = 0; i < 3; ++i) {
      crux.send(kTouchingTriangleSphere);
      const std::string answer = crux.readLine();
      ASSERT_FALSE(answer.empty()) << "no answer while the input is still open; args " << ::testing::PrintToString(args);
      EXPECT_EQ(Json::parse(answer)["hit"], true) << answer;
    }
    EXPECT_EQ(crux.finish(), 0);
  }
}

// load_mesh imports through `crux import-mesh`: a file on which assimp crashes (a SEGV in its ASE
// importer, tests/fuzz/regressions) costs that line, and the run goes on.
TEST(BatchStreaming, AMeshFileThatCrashesAssimpCostsItsLineOnly) {
  const std::string ase = std::string(CRUX_SOURCE_DIR) + "/tests/fuzz/regressions/assimp-ase-segv-empty-lists.ase";
  Interactive crux({});
  crux.send(R"({"id":"bad","op":"load_mesh","name":"m","path":")" + ase + R"("})");
  const Json bad = Json::parse(crux.readLine(60));
  EXPECT_EQ(bad["id"], "bad");
  ASSERT_TRUE(bad.contains("error")) << bad.dump();
  EXPECT_NE(bad["error"].get<std::string>().find("assimp crashed importing the file"), std::string::npos)
      << bad.dump();
  crux.send(kTouchingTriangleSphere);
  const Json ok = Json::parse(crux.readLine());
  EXPECT_EQ(ok["hit"], true) << ok.dump();
  EXPECT_EQ(crux.finish(), 0);
}

TEST(BatchStreaming, AnswersWrittenBeforeTheProcessIsKilledAreKept) {
  Interactive crux({});
  crux.send(kTouchingTriangleSphere);
  crux.send(kTouchingTriangleSphere);
  EXPECT_FALSE(crux.readLine().empty());
  EXPECT_FALSE(crux.readLine().empty());
  // the process dies with no chance to flush anything (~Interactive kills it)
}

/// runBatch with a worker that fails on demand (tests/apps/fault_worker.sh) for `backend`.
std::vector<std::string> runWithFaultWorker(const std::string& text, Backend backend, double timeout = 10) {
  BatchOptions options;
  options.backend = backend;
  options.workerExecutable = std::string(CRUX_SOURCE_DIR) + "/tests/apps/fault_worker.sh";
  options.timeoutSeconds = timeout;
  std::istringstream in(text);
  std::ostringstream out;
  EXPECT_EQ(runBatch(in, out, options), 0);
  return splitLines(out.str());
}

TEST(BatchIsolation, APeerThatAbortsOrHangsCostsThatLineOnly) {
  for (const Backend backend : {Backend::Fcl, Backend::Bullet}) {
    if (!backendBuilt(backendName(backend))) continue;
    const std::string name(backendName(backend));
    const auto lines = runWithFaultWorker(
        "{\"id\":\"1\",\"op\":\"distance\"}\n{\"id\":\"2\",\"op\":\"distance\",\"x\":\"ABORT\"}\n"
        "{\"id\":\"3\",\"op\":\"mesh_mesh\",\"x\":\"HANG\"}\n{\"id\":\"4\",\"op\":\"distance\"}\n",
        backend, 0.5);
    ASSERT_EQ(lines.size(), 4u);
    EXPECT_EQ(Json::parse(lines[0])["n"], 1);
    const Json aborted = Json::parse(lines[1]), hung = Json::parse(lines[2]);
    EXPECT_EQ(aborted["id"], "2");
    EXPECT_EQ(errorOf(aborted).rfind(name + " failed on distance: SIGABRT", 0), 0u) << lines[1];
    EXPECT_EQ(hung["id"], "3");
    EXPECT_EQ(errorOf(hung).rfind(name + " failed on mesh_mesh: timeout", 0), 0u) << lines[2];
    EXPECT_EQ(Json::parse(lines[3])["n"], 1);
  }
}

// The failure kinds FCL 0.7 (Debian's libfcl0.7, libccd GJK/EPA) shows on overlapping and
// coincident spheres, through the `crux` executable: each costs its line only.
TEST(BatchIsolation, FclFailureKindsCostTheirLineOnly) {
  if (!backendBuilt("fcl")) GTEST_SKIP() << "fcl not built";
  const std::string lines[] = {
      kTouchingTriangleSphere,
      // aborted in libccd's EPA (isOutsidePolytopeFace) at a GJK tolerance of 1e-12; answered at
      // FCL's default 1e-6
      R"({"id":"a","op":"distance","a":{"sphere":{"center":[0,0,0],"radius":1}},"b":{"sphere":{"center":[0,-1,0],"radius":0.1}}})",
      // two equal spheres at one centre: libccd never returns
      R"({"id":"same","op":"distance","a":{"sphere":{"center":[1,2,3],"radius":0.5}},"b":{"sphere":{"center":[1,2,3],"radius":0.5}}})",
      // zero-radius spheres at one point: libccd's assertion "A is not in region 1" (doSimplex2)
      R"({"id":"zero","op":"distance","a":{"sphere":{"center":[1,1,1],"radius":0}},"b":{"sphere":{"center":[1,1,1],"radius":0}}})",
      R"({"id":"last","op":"distance","a":{"sphere":{"center":[0,0,0],"radius":1}},"b":{"sphere":{"center":[3,0,0],"radius":1}}})"};
  Interactive crux({"--backend", "fcl", "--timeout", "1"});
  for (const std::string& line : lines) crux.send(line);
  std::vector<Json> answers;
  for (std::size_t i = 0; i < std::size(lines); ++i) {
    const std::string text = crux.readLine(30);
    ASSERT_FALSE(text.empty()) << "no answer to line " << i;
    answers.push_back(Json::parse(text));
  }
  EXPECT_EQ(crux.finish(), 0);
  EXPECT_EQ(answers[0]["hit"], true);
  ASSERT_TRUE(answers[1].contains("distance")) << answers[1].dump();
  EXPECT_NEAR(answers[1]["distance"].get<double>(), -0.1, 1e-5);  // FCL's declared tolerance is 1e-6
  EXPECT_EQ(answers[2]["id"], "same");
  EXPECT_EQ(errorOf(answers[2]).rfind("fcl failed on distance: timeout", 0), 0u) << answers[2].dump();
  EXPECT_EQ(answers[3]["id"], "zero");
  EXPECT_EQ(errorOf(answers[3]).rfind("fcl failed on distance: SIGABRT", 0), 0u) << answers[3].dump();
  EXPECT_NEAR(answers[4]["distance"].get<double>(), 1.0, 1e-5) << answers[4].dump();
}

TEST(BatchIsolation, NativeAndExactNeverUseAWorker) {
  // the fault worker would answer {"op":"echo"}: these backends answer in process
  for (const Backend backend : {Backend::Native, Backend::Exact}) {
    if (!backendBuilt(backendName(backend))) continue;
    const auto lines = runWithFaultWorker(kTouchingTriangleSphere + "\n", backend);
    ASSERT_EQ(lines.size(), 1u);
    EXPECT_EQ(Json::parse(lines[0])["hit"], true) << lines[0];
  }
}

TEST(BatchIsolation, TheTimeLimitMustBePositive) {
  BatchOptions options;
  options.timeoutSeconds = 0;
  std::istringstream in("{}\n");
  std::ostringstream out;
  EXPECT_THROW(runBatch(in, out, options), InvalidInput);
}

}  // namespace
}  // namespace crux::cli
