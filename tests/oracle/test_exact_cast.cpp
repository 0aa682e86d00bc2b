// Linear casts against the exact backend (oracle/exact/exact_cast.cpp): on integer-grid inputs
// (corners, centres, half extents and motions on the grid; box axes signed permutations) native's
// hit or miss equals the exact one on every case, and for polytopes (boxes, triangles including
// degenerate ones, hulls) native's t is never later than the exact rational t* and the shapes
// placed at native's t are within the documented contact tolerance (exact distance). Rounded
// shapes (spheres, capsules with integer and half-integer radii) get the exact hit decision.
// The small grid makes grazing, sliding along faces, starting in contact and thin (degenerate)
// triangles common. Also closed-form checks of the exact solver itself.

#include <gtest/gtest.h>

#include <crux/geometry/cast.hpp>
#include <exact/exact.hpp>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <vector>

namespace crux {
namespace {

using Rng = std::mt19937;

/// The 24 axis-aligned rotations as quaternions with components in {0, ±1, ±½, ±√½}.
std::vector<Quat> axisAlignedRotations() {
  std::vector<Quat> out;
  for (int a = 0; a < 3; ++a)
    for (int s = 0; s < 4; ++s) {
      Vec3 axis = Vec3::Zero();
      axis[a] = 1;
      out.push_back(Quat(Eigen::AngleAxis<Real>(Real(s * M_PI / 2), axis)));
    }
  return out;  // 12 distinct (with duplicates of the identity): enough variety for the grid
}

struct GridShapes {
  Rng rng;
  std::vector<std::unique_ptr<ConvexHull>> hulls;
  std::vector<Quat> rotations = axisAlignedRotations();
  explicit GridShapes(unsigned seed) : rng(seed) {}
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
  Vec3 point(int k) { return Vec3(Real(integer(-k, k)), Real(integer(-k, k)), Real(integer(-k, k))); }
  Transform pose() {
    Transform t;
    t.rotation = rotations[std::size_t(integer(0, int(rotations.size()) - 1))];
    t.translation = point(3);
    return t;
  }
  /// Polytopes: box, triangle (degenerate one time in four), hull.
  ConvexShape polytope(int kind) {
    switch (kind) {
      case 0: return Obb{point(1), Vec3(Real(integer(0, 2)), Real(integer(0, 2)), Real(integer(0, 2))), Mat3::Identity()};
      case 1: {
        const Vec3 a = point(2), b = point(2);
        const Vec3 c = integer(0, 3) == 0 ? Vec3(a + (b - a) * Real(integer(0, 2))) : point(2);
        return Triangle{a, b, c};
      }
      default: {
        std::vector<Vec3> pts;
        for (int i = 0; i < 6; ++i) pts.push_back(point(2));
        hulls.push_back(std::make_unique<ConvexHull>(ConvexHull::build(pts)));
        return *hulls.back();
      }
    }
  }
  ConvexShape rounded(int kind) {
    const Real r = Real(integer(0, 4)) / 2;
    if (kind == 0) return Sphere{point(1), r};
    return Capsule{point(2), point(2), r};
  }
};

double scaleOf(const ConvexShape& a, const Transform& ta, const ConvexShape& b, const Transform& tb, const Vec3& m) {
  return double(a.size()) + double(b.size()) + (ta.translation - tb.translation).cast<double>().norm() +
         m.cast<double>().norm();
}

TEST(ExactCast, SolverMatchesClosedForms) {
  const Obb box{Vec3::Zero(), Vec3(1, 1, 1), Mat3::Identity()};
  // face meets face at t = 3/7
  exact::ExactCastResult r = exact::cast(box, Transform{Quat::Identity(), Vec3(-5, 0, 0)}, Vec3(7, 0, 0), box, Transform{});
  ASSERT_TRUE(r.hit && r.timeExact);
  EXPECT_LE(r.tLower, 3.0 / 7);
  EXPECT_GE(r.tUpper, 3.0 / 7);
  // edge meets edge at one instant (t = 1/2), a hit; shifted by one, a miss
  r = exact::cast(box, Transform{Quat::Identity(), Vec3(-1, 7, 0)}, Vec3(8, -8, 0), box, Transform{Quat::Identity(), Vec3(5, 5, 0)});
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.t, 0.5);
  EXPECT_FALSE(exact::cast(box, Transform{Quat::Identity(), Vec3(-1, 5, 0)}, Vec3(8, -8, 0), box,
                           Transform{Quat::Identity(), Vec3(5, 5, 0)}).hit);
  // starting in contact: t = 0
  r = exact::cast(box, Transform{Quat::Identity(), Vec3(2, 0, 0)}, Vec3(5, 0, 0), box, Transform{});
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.t, 0);
  // a ball sliding along the box's face y = 1 (tangent) touches it; passing its edge at √2 > r misses
  const Sphere ball{Vec3::Zero(), 1};
  EXPECT_TRUE(exact::cast(ball, Transform{Quat::Identity(), Vec3(-5, 2, 0)}, Vec3(10, 0, 0), box, Transform{}).hit);
  EXPECT_FALSE(exact::cast(ball, Transform{Quat::Identity(), Vec3(-5, 2, 2)}, Vec3(10, 0, 0), box, Transform{}).hit);
}

TEST(ExactCast, NativePolytopeCastsContainTheExactTime) {
  GridShapes g(1234);
  int hits = 0, misses = 0, starts = 0;
  const int n = 800;
  for (int i = 0; i < n; ++i) {
    const ConvexShape a = g.polytope(i % 3), b = g.polytope((i / 3) % 3);
    const Transform ta = g.pose(), tb = g.pose();
    const Vec3 m = g.point(6);
    const exact::ExactCastResult ex = exact::cast(a, ta, m, b, tb);
    const CastResult nat = cast(a, ta, m, b, tb);
    ASSERT_EQ(nat.hit, ex.hit) << "case " << i;
    if (!ex.hit) {
      ++misses;
      continue;
    }
    ++hits;
    starts += ex.t == 0;
    ASSERT_TRUE(ex.timeExact);
    // never late
    EXPECT_LE(double(nat.t), ex.tUpper) << "case " << i;
    EXPECT_EQ(nat.startsOverlapping, ex.tUpper == 0) << "case " << i;
    // within the contact tolerance at native's t (exact distance of the shapes placed there)
    const double scale = scaleOf(a, ta, b, tb, m);
    Transform at = ta;
    at.translation += nat.t * m;
    const double gap = exact::distance(a, at, b, tb).distance;
    EXPECT_LE(gap, kCastRelativeTolerance * scale * (1 + 1e-6) + 16 * std::numeric_limits<Real>::epsilon() * scale)
        << "case " << i << " t " << nat.t << " exact " << ex.t;
  }
  EXPECT_GT(hits, n / 5);
  EXPECT_GT(misses, n / 5);
  EXPECT_GT(starts, n / 50);
}

TEST(ExactCast, NativeRoundedHitOrMissIsExact) {
  GridShapes g(99);
  int hits = 0, misses = 0;
  const int n = 600;
  for (int i = 0; i < n; ++i) {
    const ConvexShape a = g.rounded(i % 2);
    const ConvexShape b = (i / 2) % 2 ? g.rounded((i / 4) % 2) : g.polytope((i / 4) % 3);
    const Transform ta = g.pose(), tb = g.pose();
    const Vec3 m = g.point(6);
    const exact::ExactCastResult ex = exact::cast(a, ta, m, b, tb);
    const CastResult nat = cast(a, ta, m, b, tb);
    ASSERT_EQ(nat.hit, ex.hit) << "case " << i;
    (ex.hit ? hits : misses)++;
  }
  EXPECT_GT(hits, n / 5);
  EXPECT_GT(misses, n / 5);
}

}  // namespace
}  // namespace crux
