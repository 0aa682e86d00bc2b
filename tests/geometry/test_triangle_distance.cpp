// closestPoints(Triangle, Triangle) (src/geometry/triangle_distance.cpp) against the exact CGAL
// squared distance (Epeck: CGAL 5.5's Triangle_3/Triangle_3 distance for proper triangles;
// degenerate triangles as the exact segments/points they span, segment–triangle built from
// segment–segment + point–triangle + an exact crossing test), on seeded families: general
// position, degenerate (segments, points), coplanar, parallel planes, touching and crossing
// (integer grid), and scaled (1e-3, 1e4).

#include <crux/geometry/closest_point.hpp>
#include <crux/geometry/overlap.hpp>
#include <crux/geometry/triangle_distance.hpp>

#include <exact/exact.hpp>
#include <exact/exact_kernel.hpp>

#include <gtest/gtest.h>

#include <support/test_scale.hpp>

#include <cmath>
#include <iomanip>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <crux/precondition.hpp>
#include "geometry/unchecked.hpp"
#include "support/bad_inputs.hpp"

namespace crux {
namespace {

using namespace crux::exact::detail;

/// Exact squared distance between two exact simplices.
FT exactSquaredDistance(const Simplex& a, const Simplex& b) {
  if (overlapsSimplex(a, b)) return FT(0);
  struct Visitor {
    FT operator()(const Point& x, const Point& y) const { return CGAL::squared_distance(x, y); }
    FT operator()(const Point& x, const Segment3& y) const { return CGAL::squared_distance(x, y); }
    FT operator()(const Point& x, const Triangle3& y) const { return CGAL::squared_distance(x, y); }
    FT operator()(const Segment3& x, const Point& y) const { return CGAL::squared_distance(y, x); }
    FT operator()(const Segment3& x, const Segment3& y) const { return CGAL::squared_distance(x, y); }
    FT operator()(const Segment3& s, const Triangle3& t) const {
      // Disjoint: the minimum is attained at an end of s or on an edge of t.
      FT best = CGAL::squared_distance(s.source(), t);
      best = CGAL::min(best, CGAL::squared_distance(s.target(), t));
      for (int i = 0; i < 3; ++i) best = CGAL::min(best, CGAL::squared_distance(s, Segment3(t[i], t[(i + 1) % 3])));
      return best;
    }
    FT operator()(const Triangle3& t, const Point& p) const { return CGAL::squared_distance(p, t); }
    FT operator()(const Triangle3& t, const Segment3& s) const { return (*this)(s, t); }
    FT operator()(const Triangle3& x, const Triangle3& y) const { return CGAL::squared_distance(x, y); }
  };
  return std::visit(Visitor{}, a, b);
}

std::string show(const Triangle& t) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "[[%.17g,%.17g,%.17g],[%.17g,%.17g,%.17g],[%.17g,%.17g,%.17g]]", double(t.a.x()),
                double(t.a.y()), double(t.a.z()), double(t.b.x()), double(t.b.y()), double(t.b.z()), double(t.c.x()),
                double(t.c.y()), double(t.c.z()));
  return buf;
}

double scaleOf(const Triangle& a, const Triangle& b) {
  double s = 0;
  for (int i = 0; i < 3; ++i) s = std::max({s, double(a[i].cwiseAbs().maxCoeff()), double(b[i].cwiseAbs().maxCoeff())});
  return s;
}

/// Distance budget: 1e-6 relative (the double-build requirement) + an absolute term of
/// 1e-12 × the coordinate scale (the double computation's rounding near touching), plus the
/// rounding of the returned Real (2 ulps of Real, relative to the distance) and, in float builds,
/// of points rounded to float (4 ulps of float × scale) for the point checks.
constexpr double kRelative = 1e-6;
constexpr double kAbsolute = 1e-12;
constexpr double kRealUlps = 4 * double(std::numeric_limits<Real>::epsilon());

/// Is the point on the feature of t it claims (within tol)?
bool onFeature(const Triangle& t, std::uint32_t feature, const Vec3& p, double tol) {
  const std::uint32_t kind = feature >> 24, index = feature & 0xFFFFFF;
  if (index > 2) return false;
  if (kind == std::uint32_t(FeatureKind::Vertex)) return (t[int(index)] - p).cast<double>().norm() <= tol;
  if (kind == std::uint32_t(FeatureKind::Edge))
    return std::sqrt(double(crux::squaredDistance(Segment{t[int(index)], t[int(index + 1) % 3]}, p))) <= tol;
  if (kind == std::uint32_t(FeatureKind::Face)) return index == 0 && std::sqrt(double(crux::squaredDistance(t, p))) <= tol;
  return false;
}

struct Stats {
  int cases = 0, intersecting = 0;
  double worstRelative = 0;
};

/// Checks one pair (both orders) against the exact answer; returns false on a failure.
bool checkPair(const Triangle& a, const Triangle& b, Stats& stats) {
  const Simplex sa = toSimplex(a), sb = toSimplex(b);
  const double exact2 = CGAL::to_double(exactSquaredDistance(sa, sb));
  const double exact = std::sqrt(exact2);
  const bool exactOverlap = overlapsSimplex(sa, sb);
  const double scale = std::max(scaleOf(a, b), 1e-300);
  bool ok = true;
  for (int order = 0; order < 2; ++order) {
    const Triangle& x = order ? b : a;
    const Triangle& y = order ? a : b;
    const TriangleDistanceResult r = closestPoints(x, y);
    const double d = double(r.distance);
    const double budget = kRelative * exact + kAbsolute * scale + kRealUlps * exact;
    const double pointTol = budget + kRealUlps * scale;
    const double gap = (r.pointA - r.pointB).cast<double>().norm();
    const bool good = std::isfinite(d) && std::fabs(d - exact) <= budget && r.intersecting == exactOverlap &&
                      (d == 0) == exactOverlap && std::sqrt(exact::squaredDistance(x, r.pointA)) <= pointTol &&
                      std::sqrt(exact::squaredDistance(y, r.pointB)) <= pointTol && std::fabs(gap - d) <= pointTol &&
                      onFeature(x, r.featureA, r.pointA, pointTol) && onFeature(y, r.featureB, r.pointB, pointTol);
    if (!good) {
      ADD_FAILURE() << "a=" << show(x) << " b=" << show(y) << std::setprecision(17) << "\n crux d=" << d
                    << " exact d=" << exact << " intersecting=" << r.intersecting << " exact overlap=" << exactOverlap
                    << "\n pointA=" << r.pointA.transpose() << " (off A by " << std::sqrt(exact::squaredDistance(x, r.pointA))
                    << ") pointB=" << r.pointB.transpose() << " (off B by " << std::sqrt(exact::squaredDistance(y, r.pointB))
                    << ") |pA-pB|=" << gap << " featureA=" << std::hex << r.featureA << " featureB=" << r.featureB
                    << std::dec;
      ok = false;
    }
    if (exact > 0) stats.worstRelative = std::max(stats.worstRelative, std::fabs(d - exact) / exact);
  }
  ++stats.cases;
  stats.intersecting += exactOverlap;
  return ok;
}

using Rng = std::mt19937_64;

Vec3 uniform(Rng& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  return Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
}
Vec3 grid(Rng& rng, int lo, int hi) {
  std::uniform_int_distribution<int> u(lo, hi);
  return Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
}

/// Runs a family of `cases` pairs from `make` and checks them; stops at 10 failures.
Stats runFamily(const char* name, int cases, std::uint64_t seed, const std::function<void(Rng&, Triangle&, Triangle&)>& make) {
  Rng rng(seed);
  Stats stats;
  int failures = 0;
  for (int i = 0; i < crux::test::scaledCases(cases, 200) && failures < 10; ++i) {
    Triangle a, b;
    make(rng, a, b);
    if (!checkPair(a, b, stats)) ++failures;
  }
  std::printf("%s: %d pairs, %d intersecting, worst relative error %.3g\n", name, stats.cases, stats.intersecting,
              stats.worstRelative);
  return stats;
}

TEST(TriangleDistance, GeneralPositionMatchesExact) {
  const Stats s = runFamily("general", 3000, 101, [](Rng& rng, Triangle& a, Triangle& b) {
    const Vec3 off = uniform(rng, -1.2, 1.2);
    a = {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
    b = {uniform(rng, -1, 1) + off, uniform(rng, -1, 1) + off, uniform(rng, -1, 1) + off};
  });
  // Both separated and crossing pairs occur.
  EXPECT_GT(s.intersecting, s.cases / 20);
  EXPECT_LT(s.intersecting, s.cases * 3 / 4);
}

TEST(TriangleDistance, DegenerateTrianglesAreTheirSegmentsAndPoints) {
  runFamily("degenerate", 2000, 202, [](Rng& rng, Triangle& a, Triangle& b) {
    auto degenerate = [&](Triangle& t, int kind) {
      const Vec3 p = uniform(rng, -1, 1), q = uniform(rng, -1, 1);
      std::uniform_real_distribution<double> u(-0.5, 1.5);
      switch (kind) {
        case 0: t = {p, p, p}; break;                                      // a point
        case 1: t = {p, q, q}; break;                                      // repeated corner
        case 2: t = {p, q, Vec3(p + Real(u(rng)) * (q - p))}; break;       // collinear (rounded)
        case 3: t = {p, Vec3(p + Real(2) * (q - p)), q}; break;            // collinear, middle corner last
        default: t = {p, q, uniform(rng, -1, 1)}; break;                   // proper
      }
    };
    std::uniform_int_distribution<int> kind(0, 4);
    degenerate(a, kind(rng));
    degenerate(b, kind(rng) % 4);
    const Vec3 off = uniform(rng, -0.8, 0.8);
    b = {b.a + off, b.b + off, b.c + off};
  });
}

TEST(TriangleDistance, IntegerGridTouchingAndCrossingAreExact) {
  // Small integer coordinates: many pairs share a vertex, an edge segment or a face point, or
  // cross exactly; intersecting must equal the exact answer and give distance exactly 0.
  const Stats s = runFamily("grid", 4000, 303, [](Rng& rng, Triangle& a, Triangle& b) {
    a = {grid(rng, -3, 3), grid(rng, -3, 3), grid(rng, -3, 3)};
    b = {grid(rng, -3, 3), grid(rng, -3, 3), grid(rng, -3, 3)};
  });
  EXPECT_GT(s.intersecting, s.cases / 10);
}

TEST(TriangleDistance, CoplanarAndParallelPairs) {
  runFamily("coplanar/parallel", 3000, 404, [](Rng& rng, Triangle& a, Triangle& b) {
    std::uniform_int_distribution<int> which(0, 2);
    const int w = which(rng);
    auto flat = [&](Real z) {
      Vec3 p = uniform(rng, -1, 1), q = uniform(rng, -1, 1), r = uniform(rng, -1, 1);
      p.z() = q.z() = r.z() = z;
      return Triangle{p, q, r};
    };
    a = flat(0);
    // 0: same plane (overlapping or apart), 1: parallel planes, 2: same plane, integer grid.
    if (w == 2) {
      auto g = [&] { Vec3 v = grid(rng, -3, 3); v.z() = 0; return v; };
      a = {g(), g(), g()};
      b = {g(), g(), g()};
    } else {
      b = flat(w == 0 ? Real(0) : Real(std::uniform_real_distribution<double>(-0.5, 0.5)(rng)));
      const Vec3 shift(Real(std::uniform_real_distribution<double>(-1.5, 1.5)(rng)), 0, 0);
      b = {b.a + shift, b.b + shift, b.c + shift};
    }
  });
}

TEST(TriangleDistance, NearlyParallelEdgesAndFaces) {
  runFamily("near-parallel", 2000, 505, [](Rng& rng, Triangle& a, Triangle& b) {
    a = {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
    std::uniform_real_distribution<double> tiny(-1e-5, 1e-5), far(0.01, 1.0);
    // b = a translated along its normal and slightly tilted: face–face and edge–edge near ties.
    const Vec3 n = (a.b - a.a).cross(a.c - a.a).normalized();
    const Real h = Real(far(rng));
    auto jitter = [&] { return Vec3(Real(tiny(rng)), Real(tiny(rng)), Real(tiny(rng))); };
    const Vec3 slide = uniform(rng, -0.5, 0.5);
    b = {a.a + h * n + slide + jitter(), a.b + h * n + slide + jitter(), a.c + h * n + slide + jitter()};
  });
}

TEST(TriangleDistance, ScaledPairsKeepRelativeAccuracy) {
  for (const double s : {1e-3, 1e4}) {
    runFamily(s < 1 ? "scaled 1e-3" : "scaled 1e4", 1000, 606 + std::uint64_t(s), [s](Rng& rng, Triangle& a, Triangle& b) {
      const Vec3 off = uniform(rng, -2.5 * s, 2.5 * s);
      a = {uniform(rng, -s, s), uniform(rng, -s, s), uniform(rng, -s, s)};
      b = {uniform(rng, -s, s) + off, uniform(rng, -s, s) + off, uniform(rng, -s, s) + off};
    });
  }
}

// ---- named degenerate cases --------------------------------------------------------------------

TEST(TriangleDistance, CrossingTrianglesGiveACommonPointFarFromEdges) {
  // A long thin triangle pierces a large one through its interior: every edge pair and vertex
  // projection is far, yet they intersect.
  const Triangle big{Vec3(-10, -10, 0), Vec3(10, -10, 0), Vec3(0, 10, 0)};
  const Triangle spike{Vec3(0, 0, -5), Vec3(Real(0.5), 0, 5), Vec3(-Real(0.5), 0, 5)};
  const TriangleDistanceResult r = closestPoints(big, spike);
  EXPECT_TRUE(r.intersecting);
  EXPECT_EQ(r.distance, 0);
  EXPECT_NEAR(double(r.pointA.z()), 0, 1e-6);
  EXPECT_LE(std::sqrt(exact::squaredDistance(big, r.pointA)), 1e-6);
  EXPECT_LE(std::sqrt(exact::squaredDistance(spike, r.pointA)), 1e-6);
}

TEST(TriangleDistance, VertexAboveFaceReportsVertexAndFace) {
  const Triangle floor{Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};
  const Triangle above{Vec3(1, 1, 2), Vec3(1, 1, 5), Vec3(2, 1, 5)};
  const TriangleDistanceResult r = closestPoints(floor, above);
  EXPECT_EQ(r.distance, 2);
  EXPECT_EQ(r.featureA, featureId(FeatureKind::Face, 0));
  EXPECT_EQ(r.featureB, featureId(FeatureKind::Vertex, 0));
  EXPECT_EQ(r.pointA, Vec3(1, 1, 0));
}

TEST(TriangleDistance, SkewEdgesReportEdgeFeatures) {
  const Triangle a{Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, -2, -1)};
  const Triangle b{Vec3(1, -1, 1), Vec3(1, 1, 1), Vec3(1, 0, 3)};
  const TriangleDistanceResult r = closestPoints(a, b);
  EXPECT_NEAR(double(r.distance), 1, 1e-6);
  EXPECT_EQ(r.featureA, featureId(FeatureKind::Edge, 0));
  EXPECT_EQ(r.featureB, featureId(FeatureKind::Edge, 0));
}

TEST(TriangleDistance, ParallelOverlappingEdgesAreClamped) {
  // Collinear-direction edges offset by 1 in z and overlapping in x on [1, 2].
  const Triangle a{Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, -2, -3)};
  const Triangle b{Vec3(1, 0, 1), Vec3(3, 0, 1), Vec3(2, -2, 4)};
  const TriangleDistanceResult r = closestPoints(a, b);
  EXPECT_NEAR(double(r.distance), 1, 1e-6);
  EXPECT_NEAR(double((r.pointA - r.pointB).norm()), 1, 1e-6);
  EXPECT_GE(double(r.pointA.x()), 1 - 1e-6);
  EXPECT_LE(double(r.pointA.x()), 2 + 1e-6);
}

TEST(TriangleDistance, PointTrianglesAndIdenticalTriangles) {
  const Triangle p{Vec3(1, 1, 1), Vec3(1, 1, 1), Vec3(1, 1, 1)};
  const Triangle q{Vec3(1, 1, 4), Vec3(1, 1, 4), Vec3(1, 1, 4)};
  EXPECT_EQ(distance(p, q), 3);
  EXPECT_EQ(distance(p, p), 0);
  const Triangle t{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const TriangleDistanceResult r = closestPoints(t, t);
  EXPECT_TRUE(r.intersecting);
  EXPECT_EQ(r.distance, 0);
}

// Non-queryable inputs (precondition.hpp, rule::kPrimitive): the routines behind the public entries
// (geometry/unchecked.hpp, what those entries run in release builds and the mesh, scene and contact
// layers call) give an unspecified answer, but return without undefined behaviour, which the
// sanitizer stage checks here.
TEST(TriangleDistancePreconditions, NonQueryableInputsReturnWithoutUndefinedBehaviour) {
  const test_support::BadPrimitives bad = test_support::badPrimitives();
  const Triangle tri{Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(0, 1, 1)};
  int calls = 0;
  for (const Triangle& t : bad.triangles) {
    (void)unchecked::closestPoints(t, tri), (void)unchecked::closestPoints(tri, t), (void)unchecked::closestPoints(t, t);
    calls += 3;
  }
  EXPECT_GT(calls, 20);
  EXPECT_EQ(distance(tri, Triangle{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}), 1);
}

// In debug builds (CRUX_CHECK_PRIMITIVE_PRECONDITIONS, on without NDEBUG) a non-queryable input
// aborts with a message naming the query.
TEST(TriangleDistancePreconditions, DebugBuildsAbortNamingTheQuery) {
  if (!CRUX_CHECK_PRIMITIVE_PRECONDITIONS)
    GTEST_SKIP() << "the primitive check is off in this build (NDEBUG)";
  const Triangle tri{Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(0, 1, 1)};
  const Real nan = std::numeric_limits<Real>::quiet_NaN();
  EXPECT_DEATH((void)closestPoints(tri, Triangle{Vec3::Zero(), Vec3(nan, 0, 0), Vec3::Ones()}),
               "precondition violated in closestPoints\\(Triangle, Triangle\\)");
}

}  // namespace
}  // namespace crux
