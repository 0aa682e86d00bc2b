// Tests of src/geometry/closest_point.cpp: regression tests named after the case they pin down,
// seeded property tests of the triangle against CGAL's exact closest point, and optimality
// checks (the variational inequality of a projection onto a convex set) for the other shapes.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/predicates.hpp>
#include <crux/geometry/triangle_class.hpp>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>

#include "exact/exact.hpp"
#include "support/test_scale.hpp"  // CRUX_TEST_SCALE: fewer cases in the sanitizer stage
#include <crux/precondition.hpp>
#include "geometry/unchecked.hpp"
#include "support/bad_inputs.hpp"

namespace crux {
namespace {

constexpr double kEps = std::numeric_limits<Real>::epsilon();
constexpr double kWideEps = std::numeric_limits<Wide>::epsilon();

/// Accuracy budget of a reported closest point or distance, in units of the error model below.
/// The worst case observed in the property tests below is 0.7 units (both precisions).
constexpr double kAccuracyUnits = 4;

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

std::string str(const Triangle& t) { return "triangle {" + str(t.a) + ", " + str(t.b) + ", " + str(t.c) + "}"; }

double scaleOf(std::initializer_list<Vec3> points) {
  double s = 1;
  for (const Vec3& p : points) s = std::max(s, double(p.cwiseAbs().maxCoeff()));
  return s;
}

/// Error model of a triangle closest point, the unit of kAccuracyUnits: eps_Real·S for rounding
/// the answer to Real (S = the largest coordinate magnitude, at least 1), plus eps_Wide·S·κ for
/// the evaluation in Wide. κ is the condition of the face-region projection
/// q = p - n(n·ap)/|n|²: the computed normal n = ab × ac is off in direction by about
/// eps_Wide·(|ab||ac| + S(|ab| + |ac|))/|n| (the products, and the edge differences, which round
/// when Real = Wide), and that tilt moves q by |ap| times it. The second term is what a
/// backward-stable algorithm must be allowed on slivers (|n| small against the edge lengths);
/// in float builds it is negligible against the first.
double errorUnit(const Triangle& t, const Vec3& p) {
  const double s = scaleOf({t.a, t.b, t.c, p});
  const Eigen::Vector3d a = t.a.cast<double>(), ab = t.b.cast<double>() - a, ac = t.c.cast<double>() - a;
  const double ap = (p.cast<double>() - a).norm(), n = ab.cross(ac).norm();
  const double kappa = n > 0 ? 1 + ap * (ab.norm() * ac.norm() + s * (ab.norm() + ac.norm())) / (n * s) : 1 + ap / s;
  return kEps * s + kWideEps * s * kappa;
}

::testing::AssertionResult near(const Vec3& got, const Vec3& want, Real tolerance) {
  if ((got - want).norm() <= tolerance) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got " << str(got) << ", want " << str(want) << " (|diff| "
                                       << (got - want).norm() << " > " << tolerance << ")";
}

const Triangle kUnit{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};

// ---- triangle regressions -------------------------------------------------------------------

TEST(ClosestPointTriangle, VertexRegionTieGoesToTheVertex) {
  // The errata's example: the book's strict '<' between edge distances returned (0,0,0).
  EXPECT_EQ(closestPoint(kUnit, Vec3(2, Real(-0.5), 0)), Vec3(1, 0, 0));
  EXPECT_EQ(squaredDistance(kUnit, Vec3(2, Real(-0.5), 0)), Real(1.25));
}

TEST(ClosestPointTriangle, EachVoronoiRegion) {
  // Vertex regions.
  EXPECT_EQ(closestPoint(kUnit, Vec3(-1, -2, 3)), Vec3(0, 0, 0));
  EXPECT_EQ(closestPoint(kUnit, Vec3(3, -1, -1)), Vec3(1, 0, 0));
  EXPECT_EQ(closestPoint(kUnit, Vec3(-1, 4, 2)), Vec3(0, 1, 0));
  // Edge regions: AB (y < 0), AC (x < 0), BC (x + y > 1).
  EXPECT_EQ(closestPoint(kUnit, Vec3(Real(0.25), -3, 1)), Vec3(Real(0.25), 0, 0));
  EXPECT_EQ(closestPoint(kUnit, Vec3(-2, Real(0.75), -1)), Vec3(0, Real(0.75), 0));
  EXPECT_TRUE(near(closestPoint(kUnit, Vec3(1, 1, 5)), Vec3(Real(0.5), Real(0.5), 0), Real(4 * kEps)));
  EXPECT_TRUE(near(closestPoint(kUnit, Vec3(Real(1.5), Real(0.5), 0)), Vec3(1, 0, 0), Real(4 * kEps)));
  // Face region, above and below.
  EXPECT_EQ(closestPoint(kUnit, Vec3(Real(0.25), Real(0.25), 7)), Vec3(Real(0.25), Real(0.25), 0));
  EXPECT_EQ(closestPoint(kUnit, Vec3(Real(0.25), Real(0.5), -2)), Vec3(Real(0.25), Real(0.5), 0));
  EXPECT_EQ(squaredDistance(kUnit, Vec3(Real(0.25), Real(0.5), -2)), Real(4));
}

TEST(ClosestPointTriangle, PointOnTheTriangleIsItsOwnClosestPoint) {
  for (const Vec3& p : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(Real(0.5), Real(0.5), 0), Vec3(Real(0.25), 0, 0),
                        Vec3(Real(0.125), Real(0.25), 0)}) {
    EXPECT_EQ(closestPoint(kUnit, p), p);
    EXPECT_EQ(squaredDistance(kUnit, p), Real(0));
  }
}

TEST(ClosestPointTriangle, TiltedTriangleFaceRegion) {
  // Plane x + y + z = 1; p = (1,1,1) projects to its centroid (1/3, 1/3, 1/3).
  const Triangle t{Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  const Real third = Real(1) / 3;
  EXPECT_TRUE(near(closestPoint(t, Vec3(1, 1, 1)), Vec3(third, third, third), Real(4 * kEps)));
  EXPECT_NEAR(squaredDistance(t, Vec3(1, 1, 1)), Real(4) / 3, 8 * kEps);
}

TEST(ClosestPointTriangle, CollinearTriangleIsTheSegmentOfItsFarthestCorners) {
  // Corner c lies between a and b: the set is the segment [a, b].
  const Triangle t{Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(1, 0, 0)};
  EXPECT_EQ(closestPoint(t, Vec3(6, 1, 0)), Vec3(4, 0, 0));
  EXPECT_EQ(closestPoint(t, Vec3(-3, 0, 2)), Vec3(0, 0, 0));
  EXPECT_EQ(closestPoint(t, Vec3(3, 5, -5)), Vec3(3, 0, 0));
  EXPECT_EQ(squaredDistance(t, Vec3(3, 5, -5)), Real(50));
  // Diagonal, with the middle corner listed first.
  const Triangle d{Vec3(1, 1, 1), Vec3(2, 2, 2), Vec3(0, 0, 0)};
  EXPECT_EQ(closestPoint(d, Vec3(3, 3, 3)), Vec3(2, 2, 2));
  EXPECT_EQ(closestPoint(d, Vec3(-1, -1, -1)), Vec3(0, 0, 0));
  EXPECT_TRUE(near(closestPoint(d, Vec3(1, 0, 2)), Vec3(1, 1, 1), Real(4 * kEps)));
}

TEST(ClosestPointTriangle, RepeatedCornerTriangleIsASegment) {
  const Triangle t{Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0, 2, 0)};
  EXPECT_EQ(closestPoint(t, Vec3(1, 1, 0)), Vec3(0, 1, 0));
  EXPECT_EQ(closestPoint(t, Vec3(0, -1, 0)), Vec3(0, 0, 0));
  EXPECT_EQ(squaredDistance(t, Vec3(1, 1, 0)), Real(1));
}

TEST(ClosestPointTriangle, AllCornersEqualIsAPoint) {
  const Triangle t{Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3)};
  EXPECT_EQ(closestPoint(t, Vec3(5, 5, 5)), Vec3(1, 2, 3));
  EXPECT_EQ(closestPoint(t, Vec3(1, 2, 3)), Vec3(1, 2, 3));
  EXPECT_EQ(squaredDistance(t, Vec3(2, 2, 3)), Real(1));
}

TEST(ClosestPointTriangle, NearlyCollinearSliverIsFinite) {
  // Not exactly collinear (so not classified as a segment), but far too thin for its shape to
  // matter: the answer must be finite and on the segment up to rounding.
  const Triangle t{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, Real(1e-30), 0)};
  const Vec3 q = closestPoint(t, Vec3(1, 1, 0));
  ASSERT_TRUE(q.allFinite());
  EXPECT_TRUE(near(q, Vec3(1, 0, 0), Real(4 * kEps)));
  EXPECT_TRUE(std::isfinite(squaredDistance(t, Vec3(1, 1, 0))));
}

TEST(ClosestPointTriangle, SliverWithATinyEdgeIsNotTakenForThatEdge) {
  // Found by fuzz_geometry: an edge of ~1.6e-28 against edges of ~75. In double the region tests'
  // products for the tiny edge (its dot products with p − a and p − b, exactly ±|ab|² in exact
  // arithmetic) round to 0, and RTCD's edge-AB test took the tiny edge's region: the answer was
  // corner a, 110 from p, while corner c is 66 from it.
  const Triangle t{Vec3(Real(-1.4012984643248171e-45), Real(1.1443742118159064e-28), Real(1.1443742118159064e-28)),
                   Vec3(Real(1.1443742118159064e-28), Real(1.1443742118159064e-28), Real(-1.4012984643248171e-45)),
                   Vec3(Real(0.049000002443790436), -53, -53)};
  const Vec3 p(-64, -64, -64);
  const Vec3 q = closestPoint(t, p);
  const double dq = (q - p).cast<double>().norm();
  for (int i = 0; i < 3; ++i) EXPECT_LE(dq, (t[i] - p).cast<double>().norm() * (1 + 1e-6)) << "corner " << i;
  // the triangle is within 1e-27 of its long edge a → c: the closest point of that segment
  const Vec3 s = closestPoint(Segment{t.a, t.c}, p);
  EXPECT_NEAR(dq, (s - p).cast<double>().norm(), 1e-4);
  EXPECT_NEAR(double(squaredDistance(t, p)), (s - p).cast<double>().squaredNorm(), 1e-2);
}

TEST(ClosestPointTriangle, TinyTriangleFarFromThePointGivesACorner) {
  // Found by fuzz_geometry (corners at ±1.4e-45, p 64 away; here ±1e-30, the same in both
  // precisions): p − a and p − b round to one vector, so the edge region's parameter was 0/0 and
  // the answer NaN. Every point of the triangle is as near as rounding can tell: the answer is
  // within the triangle's size of its corners.
  const Real m = Real(1e-30);
  const Triangle t{Vec3(-m, -m, m), Vec3(-m, m, -m), Vec3(-m, -m, -m)};
  const Vec3 p(-m, -64, -64);
  const Vec3 q = closestPoint(t, p);
  ASSERT_TRUE(q.allFinite());
  EXPECT_LE(q.cwiseAbs().maxCoeff(), m);
  EXPECT_NEAR(double(squaredDistance(t, p)), 2.0 * 64 * 64, 1e-9);
}

// Slivers with a tiny edge (needles). (1) Found by a scratch search (the fuzz
// check skipped slivers' in-triangle test): a tiny edge near the origin (1e-17) against edges of
// 0.07; RTCD's products vc, vb, va cancelled, the face region was taken and p was projected onto
// the plane 0.016 off the triangle, nearer to p than any point of it. (2) Found by fuzz_geometry
// with the sliver check added: the fix's first inside test (each edge's half-plane within a
// slack) let through p's projection 2.7 beyond the sharp corner of a needle 6e-14 wide, where the
// two long edges' half-planes stay within the slack. Every point of a triangle lies within half
// its height of the boundary, so the answer is on the triangle when it is that near the boundary,
// and it is no nearer to p than the boundary's nearest point minus that half height.
TEST(ClosestPointTriangle, SliverWithATinyEdgeGivesAPointOnIt) {
  auto f = [](double x, double y, double z) { return Vec3(Real(float(x)), Real(float(y)), Real(float(z))); };
  const std::pair<Triangle, Vec3> cases[] = {
      {{f(0.0665027276, 0.00491674384, -0.0257796571), f(3.0587098e-18, -1.37824486e-17, -5.48197045e-19),
        f(-2.65880437e-18, -1.47912483e-17, -1.12998703e-17)},
       f(0.0375160649, -0.047955174, 0.00895366911)},
      {{f(4, 0, 0), f(62, 5.8999998625835354e-14, -64), f(62, 0, -64)}, f(0, 0, 0)}};
  for (const auto& tp : cases) {
    const Triangle& t = tp.first;  // (named, not a structured binding: the lambda below captures it)
    const Vec3& p = tp.second;
    const Vec3 q = closestPoint(t, p);
    auto boundary = [&](const Vec3& x) {
      double d = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 3; ++i)
        d = std::min(d, (closestPoint(Segment{t[i], t[(i + 1) % 3]}, x) - x).cast<double>().norm());
      return d;
    };
    const Eigen::Vector3d a = t.a.cast<double>(), b = t.b.cast<double>(), c = t.c.cast<double>();
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const double height = (b - a).cross(c - a).norm() / longest;
    const double tol = 1e-6 * longest;
    EXPECT_LE(boundary(q), height / 2 + tol) << "q off the triangle, p " << p.transpose();
    EXPECT_GE((q - p).cast<double>().norm(), boundary(p) - height / 2 - tol) << "nearer to p than the triangle";
  }
}

// ---- other shapes: regressions ----------------------------------------------------------------

TEST(ClosestPointSegment, StartEqualsEndIsAPoint) {
  const Segment s{Vec3(1, 1, 1), Vec3(1, 1, 1)};
  EXPECT_EQ(closestPoint(s, Vec3(4, 5, 1)), Vec3(1, 1, 1));
  EXPECT_EQ(squaredDistance(s, Vec3(4, 5, 1)), Real(25));
}

TEST(ClosestPointSegment, ClampsToTheEndpointsAndProjectsBetween) {
  const Segment s{Vec3(0, 0, 0), Vec3(0, 0, 4)};
  EXPECT_EQ(closestPoint(s, Vec3(1, 0, -3)), Vec3(0, 0, 0));
  EXPECT_EQ(closestPoint(s, Vec3(1, 0, 9)), Vec3(0, 0, 4));
  EXPECT_EQ(closestPoint(s, Vec3(3, 4, 1)), Vec3(0, 0, 1));
  EXPECT_EQ(squaredDistance(s, Vec3(3, 4, 1)), Real(25));
}

TEST(ClosestPointRay, PointBehindTheOriginGetsTheOrigin) {
  const Ray r{Vec3(1, 0, 0), Vec3(2, 0, 0)};  // non-unit direction
  EXPECT_EQ(closestPoint(r, Vec3(-5, 3, 0)), Vec3(1, 0, 0));
  EXPECT_EQ(squaredDistance(r, Vec3(-5, 3, 0)), Real(45));
  EXPECT_EQ(closestPoint(r, Vec3(7, 3, 0)), Vec3(7, 0, 0));
  EXPECT_EQ(squaredDistance(r, Vec3(7, 3, 0)), Real(9));
}

TEST(ClosestPointSphere, PointInsideIsItsOwnClosestPoint) {
  const Sphere s{Vec3(1, 1, 1), 2};
  EXPECT_EQ(closestPoint(s, Vec3(2, 1, 0)), Vec3(2, 1, 0));
  EXPECT_EQ(squaredDistance(s, Vec3(2, 1, 0)), Real(0));
  EXPECT_EQ(closestPoint(s, Vec3(1, 1, 3)), Vec3(1, 1, 3));  // on the surface
  EXPECT_EQ(closestPoint(s, Vec3(1, 1, 7)), Vec3(1, 1, 3));
  EXPECT_EQ(squaredDistance(s, Vec3(1, 1, 7)), Real(16));
}

TEST(ClosestPointSphere, ZeroRadiusIsItsCentre) {
  const Sphere s{Vec3(1, 2, 3), 0};
  EXPECT_EQ(closestPoint(s, Vec3(1, 2, 5)), Vec3(1, 2, 3));
  EXPECT_EQ(closestPoint(s, Vec3(1, 2, 3)), Vec3(1, 2, 3));
  EXPECT_EQ(squaredDistance(s, Vec3(1, 2, 5)), Real(4));
}

TEST(ClosestPointAabb, EachAxisUsesItsOwnBounds) {
  // The book clamped y and z against min.x/max.x: with these disjoint per-axis ranges that
  // would give (1, 1, 1).
  const Aabb b{Vec3(0, 10, 20), Vec3(1, 11, 21)};
  EXPECT_EQ(closestPoint(b, Vec3(5, 5, 25)), Vec3(1, 10, 21));
  EXPECT_EQ(squaredDistance(b, Vec3(5, 5, 25)), Real(16 + 25 + 16));
  EXPECT_EQ(closestPoint(b, Vec3(Real(0.5), Real(10.5), 0)), Vec3(Real(0.5), Real(10.5), 20));
}

TEST(ClosestPointAabb, PointInsideIsItsOwnClosestPoint) {
  const Aabb b{Vec3(-1, -1, -1), Vec3(1, 2, 3)};
  EXPECT_EQ(closestPoint(b, Vec3(Real(0.3), 2, -1)), Vec3(Real(0.3), 2, -1));
  EXPECT_EQ(squaredDistance(b, Vec3(Real(0.3), 2, -1)), Real(0));
}

TEST(ClosestPointObb, PointInsideIsItsOwnClosestPoint) {
  const Mat3 r = Quat(Eigen::AngleAxis<Real>(Real(0.6), Vec3(1, -2, 2).normalized())).toRotationMatrix();
  const Obb b{Vec3(1, 2, 3), Vec3(1, 2, 3), r};
  const Vec3 p = b.center + r * Vec3(Real(0.5), Real(-1.5), Real(2.9));
  EXPECT_EQ(closestPoint(b, p), p);
  EXPECT_EQ(squaredDistance(b, p), Real(0));
}

TEST(ClosestPointObb, RotatedBoxClampsInItsOwnFrame) {
  // Box rotated 90° about z: its local x is world y. Half extents (1, 2, 3).
  Mat3 r;
  r << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Obb b{Vec3(0, 0, 0), Vec3(1, 2, 3), r};
  // World (5, 5, 5) is local (5, -5, 5): clamped to (1, -2, 3), world (2, 1, 3).
  EXPECT_EQ(closestPoint(b, Vec3(5, 5, 5)), Vec3(2, 1, 3));
  EXPECT_EQ(squaredDistance(b, Vec3(5, 5, 5)), Real(9 + 16 + 4));
}

TEST(ClosestPointPlane, ProjectsWithANonUnitNormal) {
  const Plane pl{Vec3(0, 0, 2), 4};  // z = 2
  EXPECT_EQ(closestPoint(pl, Vec3(3, -1, 7)), Vec3(3, -1, 2));
  EXPECT_EQ(squaredDistance(pl, Vec3(3, -1, 7)), Real(25));
  EXPECT_EQ(closestPoint(pl, Vec3(3, -1, 2)), Vec3(3, -1, 2));
}

// ---- triangle property tests against the exact oracle -----------------------------------------

/// Which kind of set a triangle is, for coverage counts.
predicates::TriangleKind kindOf(const Triangle& t) { return predicates::classify(t).kind; }

struct Coverage {
  long cases = 0, degenerate = 0, onTriangle = 0;
};

/// The exact answer for one case.
struct ExactAnswer {
  exact::Vec3d point;
  double squaredDistance;
};

ExactAnswer exactAnswer(const Triangle& t, const Vec3& p) {
  return {exact::closestPoint(t, p), exact::squaredDistance(t, p)};
}

/// Compares crux with the exact answer on one case; returns false (after reporting) on a
/// mismatch. worstUnits tracks the largest error seen, in units of errorUnit().
bool agreesWithExact(const Triangle& t, const Vec3& p, const ExactAnswer& want, double& worstUnits) {
  const Vec3 got = closestPoint(t, p);
  const double gotD = std::sqrt(double(squaredDistance(t, p)));
  const double wantD = std::sqrt(want.squaredDistance);
  const double unit = errorUnit(t, p);
  const double pointErr = (got.cast<double>() - want.point).norm();
  const double distErr = std::abs(gotD - wantD);
  worstUnits = std::max({worstUnits, pointErr / unit, distErr / unit});
  if (got.allFinite() && pointErr <= kAccuracyUnits * unit && distErr <= kAccuracyUnits * unit) return true;
  ADD_FAILURE() << str(t) << ", p = " << str(p) << ": crux " << str(got) << " (distance " << gotD << "), exact "
                << str(Vec3(want.point.cast<Real>())) << " (distance " << wantD << "), tolerance "
                << kAccuracyUnits * unit;
  return false;
}

TEST(ClosestPointTriangleProperty, IntegerGridMatchesExact) {
  // Small integer coordinates so that ties between regions (p on a region boundary), points on
  // the triangle and degenerate triangles are all frequent.
  std::mt19937_64 rng(0xC105E57);
  std::uniform_int_distribution<int> coord(-4, 4);
  std::uniform_int_distribution<int> pick(0, 9);
  const auto v = [&] { return Vec3(Real(coord(rng)), Real(coord(rng)), Real(coord(rng))); };
  Coverage cov;
  double worst = 0;
  int failures = 0;
  const int cases = test::scaledCases(100000);
  for (int i = 0; i < cases && failures < 10; ++i) {
    Triangle t{v(), v(), v()};
    const int shape = pick(rng);
    if (shape == 0) t.c = t.a;                                   // repeated corner
    if (shape == 1) t.c = t.a + (t.b - t.a) * Real(coord(rng));  // collinear (any order)
    if (shape == 2) t.b = t.c = t.a;                             // a point
    if (shape == 3) t.c = t.a + (t.b - t.a) * Real(0.5);         // midpoint, collinear
    Vec3 p = v();
    if (pick(rng) == 0) p = Vec3(t.a.x(), p.y(), t.a.z());  // shares coordinates with a corner
    const ExactAnswer want = exactAnswer(t, p);
    failures += !agreesWithExact(t, p, want, worst);
    ++cov.cases;
    cov.degenerate += kindOf(t) != predicates::TriangleKind::Triangle;
    cov.onTriangle += want.squaredDistance == 0;
  }
  EXPECT_EQ(failures, 0);
  std::printf("integer grid: %ld cases, %ld degenerate, %ld points on the triangle, worst error %.3g units\n",
              cov.cases, cov.degenerate, cov.onTriangle, worst);
  EXPECT_GE(cov.degenerate, cov.cases / 5);
  EXPECT_GE(cov.onTriangle, cov.cases / 100);
}

TEST(ClosestPointTriangleProperty, GeneralPositionMatchesExact) {
  std::mt19937_64 rng(0xF10A7);
  std::uniform_real_distribution<double> coord(-10, 10), bary(-0.25, 1), offset(-5, 5), jitter(-1, 1);
  const auto v = [&] { return Vec3(Real(coord(rng)), Real(coord(rng)), Real(coord(rng))); };
  double worst = 0;
  int failures = 0;
  long faceRegion = 0;
  const int cases = test::scaledCases(100000);
  for (int i = 0; i < cases && failures < 10; ++i) {
    const Triangle t{v(), v(), v()};
    // p off a point of the plane near the triangle (affine coordinates around [0, 1]), mostly
    // along the normal, so that face, edge and vertex regions all occur.
    const Vec3 n = (t.b - t.a).cross(t.c - t.a).normalized();
    const Vec3 p = t.a + (t.b - t.a) * Real(bary(rng)) + (t.c - t.a) * Real(bary(rng)) + n * Real(offset(rng)) +
                   Vec3(Real(jitter(rng)), Real(jitter(rng)), Real(jitter(rng)));
    const ExactAnswer want = exactAnswer(t, p);
    failures += !agreesWithExact(t, p, want, worst);
    // Face region iff the closest point is the projection onto the plane (coverage count only).
    const double planeD = std::abs(double(n.dot(p - t.a)));
    faceRegion += std::abs(std::sqrt(want.squaredDistance) - planeD) <= 1e-4 * (1 + planeD);
  }
  EXPECT_EQ(failures, 0);
  std::printf("general position: %d cases, %ld in a face region, worst error %.3g units\n", cases, faceRegion, worst);
  // Every region kind must be exercised: face regions neither absent nor everything.
  EXPECT_GE(faceRegion, cases / 10);
  EXPECT_LE(faceRegion, cases / 10 * 9);
}

/// A proper triangle (a, b, c) whose corner c lies at the thin line's height, kTriangleThinRelative
/// × |ab| × (1 + a draw within ±relative), above a point of ab (its longest edge), rounded to
/// Real; and points around it: off a point near it, partly along its plane's normal, so that every
/// region occurs. `ok` is false when the draw gave no such triangle.
struct ThinLineCase {
  Triangle t;
  Eigen::Vector3d a, ab, d, n;  // corner a, edge ab, the unit direction of the height, the normal
  double area2 = 0, longest2 = 0;  // |(b−a)×(c−a)|² and L² of the rounded triangle, in double
  bool ok = false;

  ThinLineCase(std::mt19937_64& rng, double relative) {
    std::uniform_real_distribution<double> coord(-10, 10), unit(0, 1), close(-relative, relative);
    std::normal_distribution<double> gauss;
    a = Eigen::Vector3d(coord(rng), coord(rng), coord(rng));
    ab = Eigen::Vector3d(coord(rng), coord(rng), coord(rng)) - a;
    d = Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
    d -= ab * (d.dot(ab) / ab.squaredNorm());
    if (!(ab.norm() > 1e-3) || !(d.norm() > 1e-6)) return;
    d.normalize();
    n = d.cross(ab).normalized();
    const Eigen::Vector3d c = a + unit(rng) * ab + (kTriangleThinRelative * (1 + close(rng))) * ab.norm() * d;
    t = Triangle{Vec3(a.cast<Real>()), Vec3((a + ab).cast<Real>()), Vec3(c.cast<Real>())};
    if (kindOf(t) != predicates::TriangleKind::Triangle) return;
    const Eigen::Vector3d ad = t.a.cast<double>(), bd = t.b.cast<double>(), cd = t.c.cast<double>();
    area2 = (bd - ad).cross(cd - ad).squaredNorm();
    longest2 = std::max({(bd - ad).squaredNorm(), (cd - bd).squaredNorm(), (ad - cd).squaredNorm()});
    ok = true;
  }

  Vec3 pointAround(std::mt19937_64& rng) const {
    std::uniform_real_distribution<double> unit(0, 1), offset(-3, 3);
    const Eigen::Vector3d p = a + (unit(rng) * 1.5 - 0.25) * ab + offset(rng) * ab.norm() * 1e-3 * d +
                              offset(rng) * n + Eigen::Vector3d(offset(rng), offset(rng), offset(rng)) * 0.01;
    return p.cast<Real>();
  }
};

// Triangles whose height lies on the thin line (to within 1e-9 relative), with p in every region:
// on either side of the line the closest point comes from a different routine (closestOnSliver
// below it, RTCD 5.1.5's regions above), and either must match the exact one.
TEST(ClosestPointTriangleProperty, TrianglesOnTheThinLineMatchExact) {
  std::mt19937_64 rng(0x7411);
  double worst = 0;
  int failures = 0;
  long below = 0, above = 0;
  const int cases = test::scaledCases(50000);
  for (int i = 0; i < cases && failures < 10; ++i) {
    const ThinLineCase c(rng, 1e-9);
    if (!c.ok) continue;
    (belowThinLine(std::sqrt(c.area2), c.longest2) ? below : above) += 1;
    const Vec3 p = c.pointAround(rng);
    failures += !agreesWithExact(c.t, p, exactAnswer(c.t, p), worst);
  }
  EXPECT_EQ(failures, 0);
  std::printf("thin line: %ld below, %ld above, worst error %.3g units\n", below, above, worst);
  // both sides of the line are exercised
  EXPECT_GE(below, (below + above) / 10);
  EXPECT_GE(above, (below + above) / 10);
}

// The triangles the two forms of the thin line split differently: |m| <= k·L² (belowThinLine)
// against the squared |m|² <= k²·L⁴ that closestPoint once took (about 1 in 20,000 of those
// within 1e-12 of the line). Such a triangle's closest point now comes from the other routine;
// found by search among triangles within 1e-14 of the line (double builds: a few in a thousand;
// float corners move the height by far more than the band where the forms disagree, so the
// search finds none there and only reports it), each checked against the exact closest point
// from points around it.
TEST(ClosestPointTriangleProperty, TrianglesTheSquaredThinTestSplitDifferentlyMatchExact) {
  std::mt19937_64 rng(0x5117);
  double worst = 0;
  int failures = 0, found = 0;
  const int tries = test::scaledCases(200000);
  constexpr double k = kTriangleThinRelative;
  for (int i = 0; i < tries && found < 200 && failures < 10; ++i) {
    const ThinLineCase c(rng, 1e-14);
    if (!c.ok) continue;
    const bool squaredForm = c.area2 <= k * k * c.longest2 * c.longest2;
    if (squaredForm == belowThinLine(std::sqrt(c.area2), c.longest2)) continue;
    ++found;
    for (int j = 0; j < 8; ++j) {
      const Vec3 p = c.pointAround(rng);
      failures += !agreesWithExact(c.t, p, exactAnswer(c.t, p), worst);
    }
  }
  EXPECT_EQ(failures, 0);
  std::printf("split by the squared form: %d triangles, worst error %.3g units\n", found, worst);
  if (std::is_same_v<Real, double>) EXPECT_GT(found, 0);  // the search reaches them in double
}

// Needles whose two near corners b, c lie ~1e-14 apart near the origin, a point p ~3 away almost
// on their bisecting plane (so the two corners are nearly equidistant from it), the third corner
// a unit away on p's far side: the answer is b, c or a point between them, and must be the exact
// one to a few ulps of the scale, with no allowance for the sliver's normal (the triangle is far
// too thin for a face region: closestOnSliver takes its boundary). Found by `crux diff` (session
// 15, seed 15042, double build: tests/regressions/native.crux-wrong.closest_point_triangle.
// 15042-1882900): the edges' candidates were compared by their rounded squared distances (~8,
// rounding ~1e-15 against a difference of ~1e-15) and the farther corner, 5e-14 off, won.
TEST(ClosestPointTriangleProperty, NeedleCornersNearlyEquidistantFromAFarPointMatchExact) {
  std::mt19937_64 rng(0x15042);
  std::uniform_real_distribution<double> U(-1, 1);
  auto dir = [&] {
    Eigen::Vector3d v;
    do v = Eigen::Vector3d(U(rng), U(rng), U(rng));
    while (v.norm() < 0.1 || v.norm() > 1);
    return v.normalized();
  };
  int failures = 0;
  double worst = 0;
  const int cases = test::scaledCases(20000);
  for (int i = 0; i < cases && failures < 10; ++i) {
    const Eigen::Vector3d b = 1e-13 * dir(), w = dir(), c = b + 5e-14 * w, u = w.cross(dir()).normalized();
    // p: off the midpoint of b c along u (⟂ w) by ~3, then along w by up to ~1e-15 either way
    const Eigen::Vector3d p = 0.5 * (b + c) + (2 + U(rng)) * u + 1e-15 * U(rng) * w;
    const Triangle t{Vec3((-u).cast<Real>()), Vec3(b.cast<Real>()), Vec3(c.cast<Real>())};
    const Vec3 pr = p.cast<Real>();
    const Vec3 got = closestPoint(t, pr);
    const Eigen::Vector3d want = exact::closestPoint(t, pr);
    const double unit = kEps * scaleOf({t.a, t.b, t.c, pr});
    const double err = (got.cast<double>() - want).norm();
    worst = std::max(worst, err / unit);
    if (!(err <= kAccuracyUnits * unit) && ++failures)
      ADD_FAILURE() << str(t) << ", p = " << str(pr) << ": crux " << str(got) << ", exact "
                    << str(Vec3(want.cast<Real>())) << " (" << err / unit << " units)";
  }
  EXPECT_EQ(failures, 0);
  std::printf("needles: %d cases, worst error %.3g units\n", cases, worst);
}

// ---- other shapes: optimality of the projection ---------------------------------------------

/// q is the closest point of a convex set C to p iff q ∈ C and (p - q)·(x - q) <= 0 for every
/// x ∈ C; for polytopes it suffices to check the vertices. Tolerances are kAccuracyUnits·kEps
/// relative to the magnitudes involved.
::testing::AssertionResult isProjection(const Vec3& p, const Vec3& q, std::initializer_list<Vec3> vertices,
                                        Real scale) {
  const Real tol = Real(kAccuracyUnits * kEps) * scale;
  for (const Vec3& x : vertices) {
    const Real v = (p - q).dot(x - q);
    if (v > tol * ((p - q).norm() + (x - q).norm()) * 2)
      return ::testing::AssertionFailure()
             << "p = " << str(p) << ", q = " << str(q) << ", vertex " << str(x) << ": (p-q)·(x-q) = " << v;
  }
  return ::testing::AssertionSuccess();
}

Mat3 randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix().cast<Real>();
}

TEST(ClosestPointProperty, SegmentRayAabbObbSphereAndPlaneAreProjections) {
  std::mt19937_64 rng(0x5EED);
  std::uniform_real_distribution<double> coord(-8, 8), ext(0, 4);
  const auto v = [&] { return Vec3(Real(coord(rng)), Real(coord(rng)), Real(coord(rng))); };
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p = v();
    // Bound on the magnitude of every point and difference formed below (coordinates <= 8,
    // extents <= 4, so differences <= 2·(8 + 4)·√3 < 64); the rays' far points are scaled apart.
    const Real scale = 64;
    const Real tol = Real(kAccuracyUnits * kEps) * scale;
    {
      const Segment s{v(), v()};
      const Vec3 q = closestPoint(s, p);
      ASSERT_TRUE(isProjection(p, q, {s.start, s.end}, scale));
      // q on the segment: collinear with the endpoints and between them.
      ASSERT_LE(((q - s.start).cross(s.end - s.start)).norm(), tol * (s.end - s.start).norm() * 4);
      ASSERT_NEAR(squaredDistance(s, p), (p - q).squaredNorm(), tol * scale * 4);
    }
    {
      const Ray r{v(), v()};
      const Vec3 q = closestPoint(r, p);
      ASSERT_TRUE(isProjection(p, q, {r.origin, r.origin + r.dir * 100}, scale * 100));
      ASSERT_NEAR(squaredDistance(r, p), (p - q).squaredNorm(), tol * scale * 4);
    }
    {
      Aabb b{v(), Vec3::Zero()};
      b.max = b.min + Vec3(Real(ext(rng)), Real(ext(rng)), Real(ext(rng)));
      const Vec3 q = closestPoint(b, p);
      ASSERT_TRUE(((q.array() >= b.min.array()) && (q.array() <= b.max.array())).all());
      for (int k = 0; k < 8; ++k) {
        const Vec3 corner((k & 1) ? b.max.x() : b.min.x(), (k & 2) ? b.max.y() : b.min.y(),
                          (k & 4) ? b.max.z() : b.min.z());
        ASSERT_TRUE(isProjection(p, q, {corner}, scale));
      }
      ASSERT_NEAR(squaredDistance(b, p), (p - q).squaredNorm(), tol * scale * 4);
    }
    {
      const Obb b{v(), Vec3(Real(ext(rng)), Real(ext(rng)), Real(ext(rng))), randomRotation(rng)};
      const Vec3 q = closestPoint(b, p);
      const Vec3 local = b.axes.transpose() * (q - b.center);
      ASSERT_TRUE((local.cwiseAbs().array() <= b.half.array() + tol).all())
          << str(local) << " half " << str(b.half) << " p " << str(p) << " q " << str(q) << " c " << str(b.center);
      for (int k = 0; k < 8; ++k) {
        const Vec3 s((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
        ASSERT_TRUE(isProjection(p, q, {Vec3(b.center + b.axes * s.cwiseProduct(b.half))}, scale));
      }
      ASSERT_NEAR(squaredDistance(b, p), (p - q).squaredNorm(), tol * scale * 4);
    }
    {
      const Sphere s{v(), Real(ext(rng))};
      const Vec3 q = closestPoint(s, p);
      ASSERT_LE((q - s.center).norm(), s.radius + tol);
      const Real gap = std::max(Real(0), (p - s.center).norm() - s.radius);
      ASSERT_NEAR((p - q).norm(), gap, tol);
      ASSERT_NEAR(squaredDistance(s, p), gap * gap, tol * scale * 4);
    }
    {
      const Plane pl{v(), Real(coord(rng))};
      if (pl.normal.norm() < Real(0.1)) continue;
      const Vec3 q = closestPoint(pl, p);
      ASSERT_NEAR(pl.normal.dot(q), pl.d, tol * scale * 4);
      ASSERT_LE((p - q).cross(pl.normal).norm(), tol * pl.normal.norm() * 4);
      ASSERT_NEAR(squaredDistance(pl, p), (p - q).squaredNorm(), tol * scale * 4);
    }
  }
}

TEST(BeyondAnEdgeLine, SaysExactlyWhetherSomeEdgeLineIsFartherThanDAndThenTheTriangleIs) {
  // Random triangles (a third of them slivers: one corner within 1e-4 of the opposite edge's
  // line), points placed beyond or inside an edge line at a random in-plane offset and a random
  // height, and d random. Reference: the in-plane signed distances from the edge lines in long
  // double, from the unit inward normals n × e (a different formula from the routine's). The
  // answer must equal "some edge line is more than d away on the outside" wherever that
  // distance is not within 1e-9 relative of d, and a true answer must mean the exact distance
  // to the triangle exceeds d.
  std::mt19937_64 rng(0xED6E);
  std::uniform_real_distribution<double> coord(-8, 8), unit(0, 1), off(-3, 3);
  using L3 = Eigen::Matrix<long double, 3, 1>;
  int beyond = 0, within = 0;
  const int cases = test::scaledCases(20000, 2000);
  for (int i = 0; i < cases; ++i) {
    const auto v = [&] { return Vec3(Real(coord(rng)), Real(coord(rng)), Real(coord(rng))); };
    Triangle t{v(), v(), v()};
    if (i % 3 == 0) {  // a sliver: c near the line through a and b
      const Vec3 dir = t.b - t.a;
      t.c = t.a + Real(unit(rng) * 1.5) * dir + Vec3(Real(1e-4 * unit(rng)), 0, 0);
    }
    const L3 c[3] = {t.a.cast<long double>(), t.b.cast<long double>(), t.c.cast<long double>()};
    const L3 n = (c[1] - c[0]).cross(c[2] - c[0]);
    if (!(n.norm() > 0)) continue;
    // p: a random point of the triangle's plane moved by `off` along edge k's inward normal
    // (negative: outside), plus a height along n
    const int k = int(rng() % 3);
    const L3 e = c[(k + 1) % 3] - c[k];
    const L3 inward = n.cross(e).normalized();
    const long double w = unit(rng);
    const L3 base = c[k] + w * e + inward * (long double)(off(rng)) + n.normalized() * (long double)(off(rng));
    const Vec3 p = base.cast<Real>();
    const Real d = Real(2 * unit(rng));
    long double worst = std::numeric_limits<long double>::infinity();  // smallest inward distance
    for (int j = 0; j < 3; ++j) {
      const L3 ej = c[(j + 1) % 3] - c[j];
      worst = std::min(worst, n.cross(ej).normalized().dot(p.cast<long double>() - c[j]));
    }
    const bool got = beyondAnEdgeLine(t, p, d);
    const long double gap = -worst - (long double)d;  // > 0: some edge line farther than d outside
    if (std::abs(gap) > 1e-9L * (1 + (long double)d)) {
      ASSERT_EQ(got, gap > 0) << str(t) << " p " << str(p) << " d " << d << " edge-line gap " << double(gap);
      (got ? beyond : within) += 1;
    }
    if (got) ASSERT_GT(std::sqrt(exact::squaredDistance(t, p)), double(d) * (1 - 1e-9)) << str(t) << " p " << str(p);
  }
  EXPECT_GT(beyond, cases / 10);
  EXPECT_GT(within, cases / 10);
  // a degenerate triangle (collinear corners) says nothing
  EXPECT_FALSE(beyondAnEdgeLine({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)}, Vec3(0, -5, 0), Real(1)));
  // NaN in d says nothing either (no comparison holds); a NaN point breaks the precondition
  // (with the primitive check on it aborts naming the query; otherwise false, no comparison holds)
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_FALSE(beyondAnEdgeLine(kUnit, Vec3(0, -5, 0), nan));
  if (CRUX_CHECK_PRIMITIVE_PRECONDITIONS)
    EXPECT_DEATH((void)beyondAnEdgeLine(kUnit, Vec3(nan, -5, 0), Real(1)),
                 "precondition violated in beyondAnEdgeLine");
  else
    EXPECT_FALSE(beyondAnEdgeLine(kUnit, Vec3(nan, -5, 0), Real(1)));
  EXPECT_TRUE(beyondAnEdgeLine(kUnit, Vec3(0, -5, 0), Real(1)));  // (the same point, d = 1: 5 beyond)
}

// Non-queryable inputs (precondition.hpp, rule::kPrimitive): the routines behind the public entries
// (geometry/unchecked.hpp, what those entries run in release builds and the mesh, scene and contact
// layers call) give an unspecified answer, but return without undefined behaviour, which the
// sanitizer stage checks here.
TEST(ClosestPointPreconditions, NonQueryableInputsReturnWithoutUndefinedBehaviour) {
  const test_support::BadPrimitives bad = test_support::badPrimitives();
  const Vec3 p(Real(0.2), Real(0.3), 2);
  const Triangle tri{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const Segment seg{Vec3::Zero(), Vec3(1, 0, 0)};
  const Ray ray{Vec3::Zero(), Vec3(1, 0, 0)};
  const Sphere sphere{Vec3::Zero(), 1};
  const Aabb box{Vec3::Constant(-1), Vec3::Constant(1)};
  const Obb obb{Vec3::Zero(), Vec3::Ones(), Mat3::Identity()};
  const Plane plane{};
  int calls = 0;
  const auto at = [&](const auto& shape, const Vec3& q) {
    calls += 2;
    (void)unchecked::closestPoint(shape, q);
    (void)unchecked::squaredDistance(shape, q);
  };
  for (const Vec3& q : bad.points) {
    at(tri, q), at(seg, q), at(ray, q), at(sphere, q), at(box, q), at(obb, q), at(plane, q);
    (void)unchecked::beyondAnEdgeLine(tri, q, 1);
  }
  for (const Triangle& t : bad.triangles) at(t, p), (void)unchecked::beyondAnEdgeLine(t, p, 1);
  for (const Segment& s : bad.segments) at(s, p);
  for (const Ray& r : bad.rays) at(r, p);
  for (const Sphere& s : bad.spheres) at(s, p);
  for (const Aabb& b : bad.aabbs) at(b, p);
  for (const Obb& b : bad.obbs) at(b, p);
  for (const Plane& pl : bad.planes) at(pl, p);
  EXPECT_GT(calls, 200);
  EXPECT_EQ(unchecked::closestPoint(tri, p), Vec3(Real(0.2), Real(0.3), 0));
}

// In debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG) a non-queryable input
// aborts with a message naming the query.
TEST(ClosestPointPreconditions, DebugBuildsAbortNamingTheQuery) {
  if (!CRUX_CHECK_PRIMITIVE_PRECONDITIONS)
    GTEST_SKIP() << "the primitive check is off in this build (NDEBUG)";
  const Real inf = std::numeric_limits<Real>::infinity();
  EXPECT_DEATH((void)closestPoint(Aabb{Vec3::Zero(), Vec3::Ones()}, Vec3(0, inf, 0)),
               "precondition violated in closestPoint\\(Aabb, point\\)");
  EXPECT_DEATH((void)squaredDistance(Plane{Vec3::Zero(), 1}, Vec3::Zero()),
               "precondition violated in squaredDistance\\(Plane, point\\)");
}

}  // namespace
}  // namespace crux
