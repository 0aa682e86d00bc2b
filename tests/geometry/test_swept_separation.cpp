// Tests of src/geometry/swept_separation.cpp, the per-triangle cull of the mesh casts: whenever the
// pair cast (cast.hpp) hits a triangle at t, the separating-axis bound keeps the triangle with an
// entry no later than t (seeded random pairs of every convex kind, degenerate triangles included,
// and the named contact cases); and it rejects most missing box casts (the bound is exact for
// polytope pairs up to its pad).

#include "geometry/swept_separation.hpp"

#include <gtest/gtest.h>

#include <crux/geometry/cast.hpp>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "support/scene_fixtures.hpp"

namespace crux {
namespace {

using Rng = std::mt19937_64;

/// The pad a caller gives: twice the cast's contact tolerance (cast.hpp's S, the triangle at the
/// identity), which covers the rounding of the double arithmetic on both sides.
double padFor(const ConvexShape& a, const Transform& ta, const Triangle& tri, const Vec3& motion) {
  const double scale = double(a.size()) + double(ConvexShape(tri).size()) + ta.translation.cast<double>().norm() +
                       motion.cast<double>().norm();
  return 2 * kCastRelativeTolerance * scale;
}

/// The cull must keep every triangle the cast hits, with an entry at or before the reported t
/// (t is rounded down to Real: one ulp).
void expectKept(const ConvexShape& a, const Transform& ta, const Vec3& motion, const Triangle& tri, int i) {
  const CastResult r = cast(a, ta, motion, ConvexShape(tri), Transform::identity());
  const detail::SweptSeparation cull(a, ta, motion, padFor(a, ta, tri, motion));
  double entry = -1;
  const bool kept = cull.enter(tri, 2, entry);
  if (!r.hit) return;
  ASSERT_TRUE(kept) << "case " << i << ": the cast hits at t = " << r.t;
  EXPECT_LE(entry, double(r.t) + double(std::numeric_limits<Real>::epsilon())) << "case " << i;
  // Asked only for entries up to the hit's time, it still keeps the triangle.
  EXPECT_TRUE(cull.enter(tri, double(r.t) + double(std::numeric_limits<Real>::epsilon()), entry)) << "case " << i;
}

struct Shapes {
  std::vector<std::unique_ptr<ConvexHull>> hulls;
  ConvexShape make(int kind, Rng& rng) {
    std::uniform_real_distribution<double> u(-1, 1), s(0.05, 0.5);
    auto vec = [&](double k) { return Vec3(Real(k * u(rng)), Real(k * u(rng)), Real(k * u(rng))); };
    switch (kind) {
      case 0: return Sphere{vec(0.1), Real(s(rng))};
      case 1: return Capsule{vec(0.4), vec(0.4), Real(s(rng) / 2)};
      case 2:
        return Obb{vec(0.1), Vec3(Real(s(rng)), Real(s(rng)), Real(s(rng))),
                   test::randomRotation(rng).toRotationMatrix()};
      case 3: return Triangle{vec(0.5), vec(0.5), vec(0.5)};
      default: {
        std::vector<Vec3> pts;
        for (int i = 0; i < 12; ++i) pts.push_back(vec(0.4));
        hulls.push_back(std::make_unique<ConvexHull>(ConvexHull::build(pts)));
        return *hulls.back();
      }
    }
  }
};

/// A random triangle near the origin; every seventh a point or a segment (degenerate triangles
/// are the segments or points they span).
Triangle randomTriangle(Rng& rng, int i) {
  std::uniform_real_distribution<double> u(-1, 1);
  auto vec = [&] { return Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))); };
  Triangle t{vec(), vec(), vec()};
  if (i % 7 == 3) t.c = t.a;                                     // a segment
  if (i % 7 == 5) t.c = t.b = t.a;                               // a point
  if (i % 7 == 6) t.c = (t.a + t.b) * Real(0.5);                 // collinear
  return t;
}

TEST(SweptSeparation, KeepsEveryTriangleTheCastHitsNoLaterThanItsTime) {
  Rng rng(2027);
  Shapes shapes;
  std::uniform_real_distribution<double> u(-1, 1), len(0.2, 2.5);
  int hits = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const ConvexShape a = shapes.make(i % 5, rng);
    const Triangle tri = randomTriangle(rng, i);
    const Transform ta = test::randomPose(rng, 2.5);
    // aimed at a point near the triangle's centroid, or beyond it
    const Vec3 aim = (tri.a + tri.b + tri.c) / 3 + Vec3(Real(0.6 * u(rng)), Real(0.6 * u(rng)), Real(0.6 * u(rng)));
    const Vec3 motion = (aim - ta.translation) * Real(len(rng));
    expectKept(a, ta, motion, tri, i);
    hits += cast(a, ta, motion, ConvexShape(tri), Transform::identity()).hit;
  }
  EXPECT_GT(hits, n * 3 / 10);
  EXPECT_LT(hits, n * 7 / 10);
}

TEST(SweptSeparation, ABoxRestingOnTheTriangleAndSlidingIsKeptAtZero) {
  const Triangle tri{Vec3(-2, -2, 0), Vec3(2, -2, 0), Vec3(0, 2, 0)};
  const ConvexShape box = Obb{Vec3::Zero(), Vec3(Real(0.5), Real(0.25), Real(0.125)), Mat3::Identity()};
  const Transform pose = Transform{Quat::Identity(), Vec3(0, 0, Real(0.125))};  // face on the plane
  for (const Vec3& m : {Vec3(1, 0, 0), Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(Real(0.3), Real(-0.2), Real(-0.5))})
    expectKept(box, pose, m, tri, 0);
  const detail::SweptSeparation cull(box, pose, Vec3(1, 0, 0), padFor(box, pose, tri, Vec3(1, 0, 0)));
  double entry = -1;
  ASSERT_TRUE(cull.enter(tri, 2, entry));
  EXPECT_EQ(entry, 0);
}

TEST(SweptSeparation, AGapWithinTheContactToleranceIsKept) {
  // The box slides parallel to the triangle's plane at 0.4 × the contact tolerance above it:
  // a hit at t = 0 for the cast (within δ counts as touching), so the pad must keep it.
  const ConvexShape box = Obb{Vec3::Zero(), Vec3(Real(0.5), Real(0.25), Real(0.125)), Mat3::Identity()};
  const Transform pose = Transform{Quat::Identity(), Vec3(0, 0, Real(0.125))};
  const Vec3 m(1, 0, 0);
  const Triangle flat{Vec3(-2, -2, 0), Vec3(2, -2, 0), Vec3(0, 2, 0)};
  const double g = 0.4 * padFor(box, pose, flat, m) / 2;
  const Real z = -Real(g);
  const Triangle tri{Vec3(-2, -2, z), Vec3(2, -2, z), Vec3(0, 2, z)};
  ASSERT_TRUE(cast(box, pose, m, ConvexShape(tri), Transform::identity()).hit);
  expectKept(box, pose, m, tri, 0);
}

TEST(SweptSeparation, AnEdgeGrazingABoxEdgeIsKept) {
  // The triangle's edge x = 1, z = 0 (along y) and the box's top edge along x meet when the box,
  // rising along z, reaches it: a grazing edge-edge contact on a cross-product axis.
  const Triangle tri{Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(3, 0, 0)};
  const ConvexShape box = Obb{Vec3::Zero(), Vec3(Real(0.5), Real(0.5), Real(0.5)), Mat3::Identity()};
  const Transform pose{Quat(Eigen::AngleAxis<Real>(Real(M_PI / 4), Vec3::UnitY())), Vec3(1, 0, Real(-2))};
  expectKept(box, pose, Vec3(0, 0, 3), tri, 0);
  EXPECT_TRUE(cast(box, pose, Vec3(0, 0, 3), ConvexShape(tri), Transform::identity()).hit);
}

TEST(SweptSeparation, RejectsMostBoxCastsThatMiss) {
  Rng rng(11);
  Shapes shapes;
  std::uniform_real_distribution<double> u(-1, 1), len(0.2, 2.5);
  int misses = 0, rejected = 0;
  for (int i = 0; i < 1000; ++i) {
    const ConvexShape a = shapes.make(2, rng);
    const Triangle tri = randomTriangle(rng, 1);
    const Transform ta = test::randomPose(rng, 2.5);
    const Vec3 aim = (tri.a + tri.b + tri.c) / 3 + Vec3(Real(0.6 * u(rng)), Real(0.6 * u(rng)), Real(0.6 * u(rng)));
    const Vec3 motion = (aim - ta.translation) * Real(len(rng));
    if (cast(a, ta, motion, ConvexShape(tri), Transform::identity()).hit) continue;
    ++misses;
    double entry;
    rejected += !detail::SweptSeparation(a, ta, motion, padFor(a, ta, tri, motion)).enter(tri, 2, entry);
  }
  ASSERT_GT(misses, 200);
  // Exact up to the pad: only misses closer than the pad (none at this seed) may be kept.
  EXPECT_EQ(rejected, misses);
}

}  // namespace
}  // namespace crux
