// Tests of src/geometry/convex.cpp: the convex hull build (cube with interior / duplicate /
// coplanar points, degenerate inputs, random clouds checked for containment, convexity and Euler's
// formula), validation, and the support mapping of every ConvexShape kind against brute force.

#include <gtest/gtest.h>

#include <cmath>
#include <crux/geometry/convex.hpp>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <sstream>

namespace crux {
namespace {

constexpr double kEps = std::numeric_limits<Real>::epsilon();

std::vector<Vec3> cubeCorners(Real h) {
  std::vector<Vec3> p;
  for (int i = 0; i < 8; ++i) p.emplace_back((i & 1) ? h : -h, (i & 2) ? h : -h, (i & 4) ? h : -h);
  return p;
}

/// Structural checks every 3-D hull must pass: faces are planar, convex, counter-clockwise
/// around their outward normal, every input point is inside every face plane, and
/// V - E + F = 2 with each edge shared by exactly two faces.
void checkHull(const ConvexHull& h, const std::vector<Vec3>& input) {
  ASSERT_EQ(h.dimension(), 3);
  double diag = 0;
  for (const Vec3& a : input)
    for (const Vec3& b : input) diag = std::max(diag, (a - b).cast<double>().norm());
  const double tol = 64 * kEps * diag + double(h.tolerance()) * 4;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (const HullFace& f : h.faces()) {
    ASSERT_GE(f.count, 3u);
    EXPECT_NEAR(f.normal.norm(), 1, 8 * kEps);
    for (std::uint32_t k = 0; k < f.count; ++k) {
      const std::uint32_t i = h.faceVertices()[f.first + k], j = h.faceVertices()[f.first + (k + 1) % f.count],
                          l = h.faceVertices()[f.first + (k + 2) % f.count];
      const Eigen::Vector3d a = h.vertices()[i].cast<double>(), b = h.vertices()[j].cast<double>(),
                            c = h.vertices()[l].cast<double>();
      EXPECT_NEAR(f.normal.cast<double>().dot(a), f.offset, tol);
      EXPECT_GE((b - a).cross(c - b).dot(f.normal.cast<double>()), -tol * diag) << "face not convex / CCW";
      ++edges[{i, j}];
    }
    for (const Vec3& p : input) EXPECT_LE(f.normal.cast<double>().dot(p.cast<double>()) - f.offset, tol);
  }
  for (const auto& [e, count] : edges) {
    EXPECT_EQ(count, 1) << "directed edge used twice";
    EXPECT_EQ(edges.count({e.second, e.first}), 1u) << "edge without a twin";
  }
  const long V = long(h.vertices().size()), E = long(edges.size()) / 2, F = long(h.faces().size());
  EXPECT_EQ(V - E + F, 2);
  // Every vertex is an input point.
  for (const Vec3& v : h.vertices()) EXPECT_NE(std::find(input.begin(), input.end(), v), input.end());
}

TEST(ConvexHull, CubeWithInteriorDuplicateAndFacePoints) {
  std::vector<Vec3> pts = cubeCorners(1);
  pts.push_back(Vec3(0, 0, 0));
  pts.push_back(Vec3(Real(0.5), Real(-0.25), Real(0.1)));
  pts.push_back(pts[3]);                               // duplicate corner
  pts.push_back(Vec3(1, 0, 0));                         // centre of a face
  pts.push_back(Vec3(1, 1, 0));                         // middle of an edge
  pts.push_back(Vec3(Real(0.5), 1, Real(-0.5)));       // on a face
  const ConvexHull h = ConvexHull::build(pts);
  checkHull(h, pts);
  EXPECT_EQ(h.vertices().size(), 8u);
  EXPECT_EQ(h.faces().size(), 6u);
  for (const HullFace& f : h.faces()) EXPECT_EQ(f.count, 4u);
  EXPECT_NEAR(h.volume(), 8, 64 * kEps);
}

TEST(ConvexHull, SinglePointAndDuplicates) {
  const ConvexHull h = ConvexHull::build({Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3)});
  EXPECT_EQ(h.dimension(), 0);
  ASSERT_EQ(h.vertices().size(), 1u);
  EXPECT_EQ(h.vertices()[0], Vec3(1, 2, 3));
  EXPECT_TRUE(h.faces().empty());
}

TEST(ConvexHull, CollinearPointsGiveTheirExtremeSegment) {
  const ConvexHull h = ConvexHull::build({Vec3(1, 1, 1), Vec3(3, 3, 3), Vec3(-2, -2, -2), Vec3(0, 0, 0)});
  EXPECT_EQ(h.dimension(), 1);
  ASSERT_EQ(h.vertices().size(), 2u);
  const std::set<Real> xs{h.vertices()[0].x(), h.vertices()[1].x()};
  EXPECT_EQ(xs, (std::set<Real>{-2, 3}));
}

TEST(ConvexHull, CoplanarPointsGiveAPolygonWithTwoFaces) {
  std::vector<Vec3> pts;
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j) pts.emplace_back(Real(i), Real(j), Real(0.5 * i + 0.25 * j));  // tilted plane
  const ConvexHull h = ConvexHull::build(pts);
  EXPECT_EQ(h.dimension(), 2);
  EXPECT_EQ(h.vertices().size(), 4u);  // the four corners; edge points are dropped
  ASSERT_EQ(h.faces().size(), 2u);
  EXPECT_NEAR(h.faces()[0].normal.dot(h.faces()[1].normal), -1, 8 * kEps);
  EXPECT_EQ(h.volume(), 0);
}

TEST(ConvexHull, NearlyCoplanarFaceIsMergedWithinTolerance) {
  std::vector<Vec3> pts = cubeCorners(1);
  pts.push_back(Vec3(Real(0.3), Real(0.2), Real(1 + 1e-3 * kEps)));  // a hair above the top face
  const ConvexHull h = ConvexHull::build(pts);
  checkHull(h, pts);
  EXPECT_EQ(h.faces().size(), 6u);
}

TEST(ConvexHull, RandomCloudsAreValid) {
  std::mt19937_64 rng(314159);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Vec3> pts;
    const int n = 4 + trial % 60;
    const double scale = trial % 3 == 0 ? 1e6 : (trial % 3 == 1 ? 1e-6 : 1);
    for (int i = 0; i < n; ++i) {
      Eigen::Vector3d p(u(rng), u(rng), u(rng));
      if (trial % 2) p.normalize();  // on a sphere: every point is a vertex (many near-coplanar)
      pts.push_back((p * scale).cast<Real>());
    }
    pts.push_back(pts[0]);
    SCOPED_TRACE("trial " + std::to_string(trial));
    const ConvexHull h = ConvexHull::build(pts);
    checkHull(h, pts);
    if (::testing::Test::HasFailure()) return;
  }
}

TEST(ConvexHull, IntegerGridBoxWithManyCoplanarPoints) {
  std::vector<Vec3> pts;
  for (int x = 0; x <= 4; ++x)
    for (int y = 0; y <= 3; ++y)
      for (int z = 0; z <= 2; ++z) pts.emplace_back(Real(x), Real(y), Real(z));
  const ConvexHull h = ConvexHull::build(pts);
  checkHull(h, pts);
  EXPECT_EQ(h.vertices().size(), 8u);
  EXPECT_EQ(h.faces().size(), 6u);
  EXPECT_NEAR(h.volume(), 24, 64 * kEps * 24);
}

// The build is translation invariant on integer points: a cloud moved by up to 2^21 (exact in
// float and double) has the moved hull of the cloud at the origin, vertex for vertex and face for
// face. Earlier the build's plane tests n·p − d ran on the raw coordinates, whose
// rounding far from the origin exceeded its tolerance (100 ulps of the cloud's small diagonal) in
// double builds: hulls came out with missing faces, and touching hulls were not reported
// (ContactsOnTheBoundary.TouchingPolytopesOnTheIntegerGridHaveAContact).
TEST(ConvexHull, IntegerCloudsFarFromTheOriginHaveTheMovedHull) {
  std::mt19937_64 rng(2718);
  auto integer = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  int compared = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<Vec3> pts;
    const int n = 4 + trial % 12;
    for (int i = 0; i < n; ++i) pts.emplace_back(Real(integer(-20, 20)), Real(integer(-20, 20)), Real(integer(-20, 20)));
    const ConvexHull h0 = ConvexHull::build(pts);
    if (h0.dimension() != 3) continue;
    const int big = 1 << integer(10, 21);
    const Vec3 shift(Real(integer(-big, big)), Real(integer(-big, big)), Real(integer(-big, big)));
    std::vector<Vec3> moved;
    for (const Vec3& p : pts) moved.push_back(p + shift);
    const ConvexHull h = ConvexHull::build(moved);
    SCOPED_TRACE("trial " + std::to_string(trial) + ", shift " + std::to_string(double(shift.x())));
    ASSERT_EQ(h.dimension(), 3);
    ASSERT_EQ(h.vertices().size(), h0.vertices().size());
    ASSERT_EQ(h.faces().size(), h0.faces().size());
    for (const Vec3& v : h0.vertices())
      EXPECT_NE(std::find(h.vertices().begin(), h.vertices().end(), Vec3(v + shift)), h.vertices().end());
    // every point on or below every face plane (the offsets carry the shift's rounding)
    const double tol = 64 * kEps * (shift.cwiseAbs().maxCoeff() + 60);
    for (const HullFace& f : h.faces())
      for (const Vec3& p : moved) EXPECT_LE(f.normal.cast<double>().dot(p.cast<double>()) - f.offset, tol);
    EXPECT_NEAR(h.volume(), h0.volume(), 1e-9 * h0.volume());
    ++compared;
  }
  EXPECT_GT(compared, 200);
}

TEST(ConvexHull, InvalidInputNamesTheField) {
  EXPECT_THROW(ConvexHull::build({}), InvalidInput);
  try {
    ConvexHull::build({Vec3(0, 0, 0), Vec3(1, std::numeric_limits<Real>::quiet_NaN(), 0)}, "hull.points");
    FAIL() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("hull.points[1]"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ConvexHull::build({Vec3(std::numeric_limits<Real>::infinity(), 0, 0)}), InvalidInput);
}

TEST(Capsule, Validate) {
  EXPECT_NO_THROW(validate(Capsule{Vec3(0, 0, 0), Vec3(1, 0, 0), 1}));
  EXPECT_NO_THROW(validate(Capsule{Vec3(0, 0, 0), Vec3(0, 0, 0), 0}));
  try {
    validate(Capsule{Vec3(0, 0, 0), Vec3(1, 0, 0), -1}, "cap");
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("cap.radius"), std::string::npos);
  }
  EXPECT_THROW(validate(Capsule{Vec3(0, 0, 0), Vec3(std::numeric_limits<Real>::quiet_NaN(), 0, 0), 1}), InvalidInput);
}

TEST(ConvexShape, SupportMatchesBruteForceForEveryKind) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  auto v = [&] { return Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))); };
  std::vector<Vec3> cloud;
  for (int i = 0; i < 40; ++i) cloud.push_back(v());
  const ConvexHull hull = ConvexHull::build(cloud);
  Obb box{v(), v().cwiseAbs(), Eigen::Quaternion<Real>(Real(u(rng)), Real(u(rng)), Real(u(rng)), Real(u(rng)))
                                   .normalized()
                                   .toRotationMatrix()};
  const ConvexShape shapes[] = {Sphere{v(), Real(0.5)}, Capsule{v(), v(), Real(0.25)}, box, Triangle{v(), v(), v()},
                                hull};
  for (const ConvexShape& s : shapes) {
    for (int k = 0; k < 200; ++k) {
      const Vec3 d = v();
      int idx = -1;
      const Vec3 got = supportCore(s, d, &idx);
      double best = -INFINITY;
      for (int i = 0; i < s.vertexCount(); ++i) best = std::max(best, double(s.vertex(i).dot(d)));
      EXPECT_NEAR(double(got.dot(d)), best, 16 * kEps);
      EXPECT_EQ(got, s.vertex(idx));
      const Vec3 full = support(s, d);
      EXPECT_NEAR(double(full.dot(d)), best + s.radius * d.norm(), 64 * kEps);
      for (int i = 0; i < s.vertexCount(); ++i) EXPECT_LE(s.vertex(i).norm(), s.size() + 16 * kEps);
    }
  }
}

// The pair queries' one entry check (detail::queryable(ShapesAtPoses), which tests all 52
// numbers together) answers exactly as the checks of its four inputs one by one: every number of
// every input made NaN, +inf or -inf in turn, negative radii and half extents, zero rotations.
TEST(ConvexShape, PairEntryCheckEqualsTheChecksOfEachInput) {
  const ConvexHull hull = ConvexHull::build(cubeCorners(1));
  const std::vector<ConvexShape> shapes = {
      Sphere{Vec3(1, 2, 3), 0.5f},
      Capsule{Vec3(0, 0, -1), Vec3(0, 0, 1), 0.25f},
      Obb{Vec3(1, 0, 0), Vec3(0.5f, 0.25f, 1), Mat3::Identity()},
      Triangle{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)},
      ConvexShape(hull),
  };
  const Transform pose{Quat(0.5f, 0.5f, -0.5f, 0.5f), Vec3(3, -2, 1)};
  const Real bad[3] = {std::numeric_limits<Real>::quiet_NaN(), std::numeric_limits<Real>::infinity(),
                       -std::numeric_limits<Real>::infinity()};
  int checked = 0, refused = 0;
  auto expectSame = [&](const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb) {
    const bool each = queryable(a) && queryable(ta) && queryable(b) && queryable(tb);
    EXPECT_EQ(detail::queryable(detail::ShapesAtPoses{a, ta, b, tb}), each);
    ++checked;
    refused += !each;
  };
  for (const ConvexShape& base : shapes) {
    expectSame(base, pose, shapes[2], pose);
    // every Real of the shape (radius, core points, axes) and of the pose, on either side
    for (int k = 0; k < 19; ++k) {
      for (Real v : bad) {
        ConvexShape s = base;
        Real* numbers[19] = {&s.radius};
        for (int i = 0; i < 9; ++i) numbers[1 + i] = &s.p[i / 3][i % 3], numbers[10 + i] = &s.axes(i % 3, i / 3);
        *numbers[k] = v;
        expectSame(s, pose, shapes[1], pose);
        expectSame(shapes[0], pose, s, pose);
      }
    }
    for (int k = 0; k < 7; ++k) {
      for (Real v : bad) {
        Transform t = pose;
        if (k < 4) t.rotation.coeffs()[k] = v;
        else t.translation[k - 4] = v;
        expectSame(base, t, shapes[3], pose);
        expectSame(base, pose, shapes[3], t);
      }
    }
    ConvexShape negative = base;
    negative.radius = -0.0625f;
    expectSame(negative, pose, base, pose);
    negative = base;
    negative.p[1].y() = -0.125f;  // a box's half extent (a point elsewhere)
    expectSame(base, pose, negative, pose);
    Transform zero = pose;
    zero.rotation.coeffs().setZero();
    expectSame(base, zero, base, pose);
    zero.rotation.coeffs() << 0, 0, std::numeric_limits<Real>::denorm_min(), 0;  // tiny, not zero
    expectSame(base, zero, base, pose);
  }
  EXPECT_GT(refused, checked / 2);
}

}  // namespace
}  // namespace crux
