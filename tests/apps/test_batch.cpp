// Tests of the `crux batch` JSON Lines protocol (apps/cli/batch.hpp, docs/batch.md): every primitive
// op on hand-checked cases, id/op echo, every error path, unsupported ops and backends, line
// accounting, round-trip exact doubles, the shipped examples, and the `crux` executable itself.

#include "apps/batch_test_util.hpp"
#include "cli/batch.hpp"
#include "cli/json_codec.hpp"

#include <crux/geometry/raycast.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

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

TEST(BatchUnsupported, ProtocolOpsAreTheContractsThirtyThree) {
  const auto& ops = protocolOps();
  EXPECT_EQ(ops.size(), 33u);
  EXPECT_TRUE(std::is_sorted(ops.begin(), ops.end()));
  for (const char* name : {"closest_point_triangle", "segment_triangle", "mesh", "load_mesh", "mesh_mesh",
                           "set_parent", "children", "scene_ray", "scene_query", "scene_pairs", "model_triangle"})
    EXPECT_TRUE(std::binary_search(ops.begin(), ops.end(), std::string_view(name))) << name;
}

TEST(BatchUnsupported, NativeAnswersPrimitivesAndMeshesAndDefersTheRest) {
  const OpTable& native = opTable(Backend::Native);
  EXPECT_EQ(native.size(), 33u);  // every protocol op (model and scene ops: apps/cli/scene_ops.cpp)
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

TEST(BatchUnsupported, OtherBackendsAnswerEveryOpUnsupported) {
  for (const Backend b : {Backend::Fcl, Backend::Bullet, Backend::Exact}) {
    for (const std::string_view name : protocolOps()) {
      const std::string n(name);
      const Answer a = ask(R"({"op":")" + n + R"(","triangle":)" + kUnitTriangle + "}", b);
      EXPECT_EQ(errorOf(a), "unsupported: " + n + " on " + std::string(backendName(b))) << a.dump();
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

  const std::string request = R"({"id":"p","op":"triangle_plane","triangle":[[0,0,0],[1,0,0],[0,1,0]],"plane":{"normal":[0,0,1],"d":0}})";
  const auto [status, out] = run("printf '%s\\n\\n%s' '" + request + "' '" + request + "' | '" + crux +
                                 "' batch --backend native --threads 2");
  EXPECT_EQ(status, 0);
  EXPECT_EQ(out, R"({"id":"p","op":"triangle_plane","hit":true})" "\n" R"({"error":"empty line"})" "\n"
                 R"({"id":"p","op":"triangle_plane","hit":true})" "\n");
  const auto [fclStatus, fclOut] = run("printf '%s\\n' '" + request + "' | '" + crux + "' batch --backend fcl");
  EXPECT_EQ(fclStatus, 0);
  EXPECT_EQ(fclOut, R"({"id":"p","op":"triangle_plane","error":"unsupported: triangle_plane on fcl"})" "\n");
}

}  // namespace
}  // namespace crux::cli
