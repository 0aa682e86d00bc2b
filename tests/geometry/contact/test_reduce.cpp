// Tests of src/geometry/contact/reduce.hpp: the one 4-point manifold reduction (selectFour) and its
// in-place form for one pair (reduceToFour): the order of the kept points, ties, the early stops
// within the tolerance, and, over random convex point sets, that the kept quadrilateral is never
// smaller than the best one on the first chord as a diagonal (the rule the pair paths had before).

#include "geometry/contact/reduce.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace crux {
namespace {

using V3 = Eigen::Vector3d;

struct P {
  V3 at;
  double sep;
  int key;
};

const auto kPos = [](const P& p) { return p.at; };
const auto kSep = [](const P& p) { return p.sep; };
const auto kKey = [](const P& p) { return p.key; };
const auto kUp = [](const P&) { return V3::UnitZ(); };

int select(const std::vector<P>& pts, double tol, int sel[4]) {
  return contact_detail::selectFour(pts, int(pts.size()), tol, kPos, kSep, kKey, kUp, sel);
}

/// Twice the area of the polygon a, b, c, d (in that order) about +z.
double quadArea2(const V3& a, const V3& b, const V3& c, const V3& d) {
  return std::abs((a.cross(b) + b.cross(c) + c.cross(d) + d.cross(a)).z());
}

/// Twice the area of the convex hull of four points in the xy plane: the largest of the three
/// orderings' polygon areas.
double hullArea2(const V3& a, const V3& b, const V3& c, const V3& d) {
  return std::max({quadArea2(a, b, c, d), quadArea2(a, c, b, d), quadArea2(a, b, d, c)});
}

TEST(ManifoldReduction, KeepsDeepestFarthestLargestTriangleThenLargestQuadrilateral) {
  // (0,0) is deepest, (10,0) farthest from it; (5,5) spans the largest triangle with them. The
  // fourth is (9,4), beyond the triangle's edge (10,0)-(5,5) (gain 15), not (5,-0.1) on the far
  // side of the first chord (gain 1), which the best quadrilateral on that chord as a diagonal
  // would take.
  const std::vector<P> pts = {{V3(5, -0.1, 0), 0, 0}, {V3(9, 4, 0), 0, 0}, {V3(0, 0, 0), -1, 0},
                              {V3(5, 5, 0), 0, 0},    {V3(10, 0, 0), 0, 0}, {V3(4, 1, 0), 0, 0}};
  int sel[4];
  ASSERT_EQ(select(pts, 0, sel), 4);
  EXPECT_EQ(sel[0], 2);
  EXPECT_EQ(sel[1], 4);
  EXPECT_EQ(sel[2], 3);
  EXPECT_EQ(sel[3], 1);
}

TEST(ManifoldReduction, TiesGoToTheLowerKeyThenTheFirst) {
  std::vector<P> pts = {{V3(0, 0, 0), -1, 7}, {V3(1, 0, 0), -1, 3}, {V3(2, 0, 0), -1, 3}};
  int sel[4];
  select(pts, 0, sel);
  EXPECT_EQ(sel[0], 1);  // key 3 before key 7; of the two with key 3 the first
  pts[1].key = 9;
  select(pts, 0, sel);
  EXPECT_EQ(sel[0], 2);
}

TEST(ManifoldReduction, StopsEarlyOnCoincidentOrCollinearPointsWithinTheTolerance) {
  int sel[4];
  // All within 0.01 of the deepest: one point.
  EXPECT_EQ(select({{V3(0, 0, 0), -1, 0}, {V3(0.005, 0, 0), 0, 0}, {V3(0, 0.009, 0), 0, 0}}, 0.01, sel), 1);
  // On a line up to 0.001 off it: two points (the deepest and the farthest from it).
  const std::vector<P> line = {{V3(0, 0, 0), -1, 0}, {V3(1, 0.001, 0), 0, 0}, {V3(2, -0.001, 0), 0, 0}, {V3(3, 0, 0), 0, 0}};
  EXPECT_EQ(select(line, 0.01, sel), 2);
  EXPECT_EQ(sel[1], 3);
  // With no tolerance every point that adds area is kept.
  EXPECT_EQ(select(line, 0, sel), 4);
  // Nothing in, nothing out.
  EXPECT_EQ(select({}, 0, sel), 0);
}

TEST(ManifoldReduction, PairFormLeavesFourOrFewerPointsAlone) {
  std::vector<P> pts = {{V3(0, 0, 0), 0, 0}, {V3(0, 0, 0), 0, 0}, {V3(1, 0, 0), -1, 0}, {V3(2, 0, 0), 0, 0}};
  int count = 4;
  contact_detail::reduceToFour(pts.data(), count, V3::UnitZ(), 0.0, kPos, kSep);
  EXPECT_EQ(count, 4);
  EXPECT_EQ(pts[0].at, V3(0, 0, 0));  // untouched, coincident points included
  pts.push_back({V3(1, 0.5, 0), 0, 0});
  count = 5;
  contact_detail::reduceToFour(pts.data(), count, V3::UnitZ(), 0.0, kPos, kSep);
  // The deepest, the first of the two farthest, the one off the line, the far end; the second
  // (0,0) adds nothing.
  ASSERT_EQ(count, 4);
  EXPECT_EQ(pts[0].at, V3(1, 0, 0));
  EXPECT_EQ(pts[1].at, V3(0, 0, 0));
  EXPECT_EQ(pts[2].at, V3(1, 0.5, 0));
  EXPECT_EQ(pts[3].at, V3(2, 0, 0));
}

TEST(ManifoldReduction, RandomConvexSetsKeepAtLeastTheBestQuadrilateralOnTheFirstChord) {
  std::mt19937 rng(0x4ed0c3);
  std::uniform_real_distribution<double> U(-1, 1);
  int strictlyLarger = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    // 5 to 12 points on a random ellipse (a clipped polygon's corners), random depths.
    const int n = 5 + trial % 8;
    const double rx = 1 + U(rng) * 0.5, ry = 1 + U(rng) * 0.5;
    std::vector<double> angle(n);
    for (double& a : angle) a = M_PI * (U(rng) + 1);
    std::sort(angle.begin(), angle.end());
    std::vector<P> pts;
    for (int i = 0; i < n; ++i) pts.push_back({V3(rx * std::cos(angle[i]), ry * std::sin(angle[i]), 0), U(rng), 0});
    int sel[4];
    ASSERT_EQ(select(pts, 0, sel), 4) << trial;
    const double kept = hullArea2(pts[sel[0]].at, pts[sel[1]].at, pts[sel[2]].at, pts[sel[3]].at);
    // The best quadrilateral with the deepest-farthest chord as a diagonal, by brute force.
    double hi = 0, lo = 0;
    const V3 a = pts[sel[0]].at, e = pts[sel[1]].at - a;
    for (const P& p : pts) {
      const double s = e.cross(p.at - a).z();
      hi = std::max(hi, s);
      lo = std::min(lo, s);
    }
    const double onChord = hi - lo;
    EXPECT_GE(kept, onChord * (1 - 1e-12)) << trial;
    // Never more than the best of all quadrilaterals (brute force).
    double bestAny = 0;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        for (int k = j + 1; k < n; ++k)
          for (int l = k + 1; l < n; ++l) bestAny = std::max(bestAny, hullArea2(pts[i].at, pts[j].at, pts[k].at, pts[l].at));
    EXPECT_LE(kept, bestAny * (1 + 1e-12)) << trial;
    if (kept > onChord * (1 + 1e-9)) ++strictlyLarger;
  }
  EXPECT_GT(strictlyLarger, 0);  // the greedy fourth point does beat the diagonal rule on some sets
}

}  // namespace
}  // namespace crux
