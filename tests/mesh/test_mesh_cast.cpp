// Shape casts against meshes (src/mesh/mesh_cast.cpp): the BVH path against the brute-force
// path (identical answers, bit for bit) and both against the smallest pair cast over every
// triangle, for linear and rigid motions of every convex kind over a posed bumpy sphere; any-hit
// against closest; a fast ball does not tunnel through a thin wall of two triangles.

#include <crux/mesh/mesh_cast.hpp>

#include <gtest/gtest.h>

#include <support/scene_fixtures.hpp>

#include <cmath>
#include <memory>
#include <optional>
#include <random>
#include <vector>
#include <crux/precondition.hpp>
#include "support/bad_inputs.hpp"

namespace crux {
namespace {

using Rng = std::mt19937_64;
using crux::test::randomPose;
using crux::test::randomRotation;

struct Shapes {
  std::vector<std::unique_ptr<ConvexHull>> hulls;
  ConvexShape make(int kind, Rng& rng) {
    std::uniform_real_distribution<double> u(-1, 1), s(0.05, 0.3);
    auto vec = [&](double k) { return Vec3(Real(k * u(rng)), Real(k * u(rng)), Real(k * u(rng))); };
    switch (kind) {
      case 0: return Sphere{vec(0.05), Real(s(rng))};
      case 1: return Capsule{vec(0.3), vec(0.3), Real(s(rng) / 2)};
      case 2: return Obb{vec(0.05), Vec3(Real(s(rng)), Real(s(rng)), Real(s(rng))), randomRotation(rng).toRotationMatrix()};
      case 3: return Triangle{vec(0.4), vec(0.4), vec(0.4)};
      default: {
        std::vector<Vec3> pts;
        for (int i = 0; i < 8; ++i) pts.push_back(vec(0.3));
        hulls.push_back(std::make_unique<ConvexHull>(ConvexHull::build(pts)));
        return *hulls.back();
      }
    }
  }
};

bool same(const std::optional<MeshCastHit>& a, const std::optional<MeshCastHit>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return a->triangle == b->triangle && a->cast.t == b->cast.t && a->cast.pointA == b->cast.pointA &&
         a->cast.pointB == b->cast.pointB && a->cast.normal == b->cast.normal &&
         a->cast.startsOverlapping == b->cast.startsOverlapping;
}

/// The reference: the pair cast against every triangle, smallest t, then lowest index.
template <class CastTriangle>
std::optional<MeshCastHit> everyTriangle(const Mesh& mesh, const CastTriangle& castTriangle) {
  std::optional<MeshCastHit> best;
  for (std::uint32_t i = 0; i < mesh.triangleCount(); ++i) {
    const CastResult r = castTriangle(mesh.triangle(i));
    if (r.hit && (!best || r.t < best->cast.t)) best = MeshCastHit{r, i};
  }
  return best;
}

TEST(MeshCast, LinearBvhEqualsBruteForceAndEveryTriangle) {
  const auto mesh = crux::test::bumpySphere(12, 16);
  Rng rng(31);
  Shapes shapes;
  std::uniform_real_distribution<double> u(-1, 1);
  int hits = 0;
  const int n = 150;
  for (int i = 0; i < n; ++i) {
    const Transform meshPose = randomPose(rng, 1);
    const ConvexShape shape = shapes.make(i % 5, rng);
    const Transform shapePose = randomPose(rng, 4);
    // aim through a point near the mesh, short and long motions
    const Vec3 aim = meshPose.translation + Vec3(Real(1.5 * u(rng)), Real(1.5 * u(rng)), Real(1.5 * u(rng)));
    const Vec3 motion = (aim - shapePose.translation) * Real(i % 3 == 0 ? 0.4 : 1.6);
    const auto bvh = castClosest(*mesh, meshPose, shape, shapePose, motion);
    const auto brute = castClosest(*mesh, meshPose, shape, shapePose, motion, QueryPath::BruteForce);
    ASSERT_TRUE(same(bvh, brute)) << i;
    const auto ref = everyTriangle(*mesh, [&](const Triangle& t) {
      return cast(shape, shapePose, motion, ConvexShape(t), meshPose);
    });
    ASSERT_EQ(bvh.has_value(), ref.has_value()) << i;
    EXPECT_EQ(castAny(*mesh, meshPose, shape, shapePose, motion), ref.has_value()) << i;
    if (!ref) continue;
    ++hits;
    EXPECT_EQ(bvh->cast.t, ref->cast.t) << i;
    EXPECT_EQ(bvh->triangle, ref->triangle) << i;
  }
  EXPECT_GT(hits, n / 5);
  EXPECT_LT(hits, n - n / 5);
}

TEST(MeshCast, RigidBvhEqualsBruteForceAndEveryTriangle) {
  const auto mesh = crux::test::bumpySphere(8, 12);
  Rng rng(57);
  Shapes shapes;
  std::uniform_real_distribution<double> u(-1, 1);
  int hits = 0;
  const int n = 60;
  for (int i = 0; i < n; ++i) {
    const Transform meshPose = randomPose(rng, 1);
    const ConvexShape shape = shapes.make(i % 5, rng);
    RigidMotion motion;
    motion.start = randomPose(rng, 4);
    motion.end = Transform{randomRotation(rng), Vec3(meshPose.translation + Vec3(Real(1.5 * u(rng)), Real(1.5 * u(rng)),
                                                                                 Real(1.5 * u(rng))))};
    const auto bvh = castClosest(*mesh, meshPose, shape, motion);
    const auto brute = castClosest(*mesh, meshPose, shape, motion, QueryPath::BruteForce);
    ASSERT_TRUE(same(bvh, brute)) << i;
    const auto ref = everyTriangle(*mesh, [&](const Triangle& t) { return cast(shape, motion, ConvexShape(t), meshPose); });
    ASSERT_EQ(bvh.has_value(), ref.has_value()) << i;
    EXPECT_EQ(castAny(*mesh, meshPose, shape, motion), ref.has_value()) << i;
    if (!ref) continue;
    ++hits;
    EXPECT_EQ(bvh->cast.t, ref->cast.t) << i;
  }
  EXPECT_GT(hits, n / 5);
  EXPECT_LT(hits, n - n / 5);
}

TEST(MeshCast, FastBallDoesNotTunnelThroughAThinWall) {
  // A wall of two triangles in x = 0; a ball of radius 0.01 moved by 100 units across it.
  const auto wall = std::make_shared<const Mesh>(
      std::vector<Vec3>{Vec3(0, -1, -1), Vec3(0, 1, -1), Vec3(0, 1, 1), Vec3(0, -1, 1)},
      std::vector<TriangleIndices>{{0, 1, 2}, {0, 2, 3}}, "wall");
  const Sphere ball{Vec3::Zero(), Real(0.01)};
  const auto hit = castClosest(*wall, Transform{}, ball, Transform{Quat::Identity(), Vec3(-50, Real(0.2), 0)},
                               Vec3(100, 0, 0));
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(double(hit->cast.t), (50 - 0.01) / 100, 1e-6);
  EXPECT_NEAR(double(hit->cast.normal.x()), -1, 1e-5);  // from the wall towards the ball
  // through the shared diagonal: no gap between the triangles
  const auto diag = castClosest(*wall, Transform{}, ball, Transform{Quat::Identity(), Vec3(-50, 0, 0)}, Vec3(100, 0, 0));
  ASSERT_TRUE(diag.has_value());
  EXPECT_NEAR(double(diag->cast.t), (50 - 0.01) / 100, 1e-6);
  // beside the wall: a miss
  EXPECT_FALSE(castAny(*wall, Transform{}, ball, Transform{Quat::Identity(), Vec3(-50, Real(1.02), 0)}, Vec3(100, 0, 0)));
}


// Non-queryable shapes, poses or motions (precondition.hpp): no hit (an infinite pose used to
// report one).
TEST(MeshCastPreconditions, NonQueryableInputsGetNoHit) {
  if (CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "this build aborts instead (precondition.hpp)";
  const Mesh mesh({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  const ConvexShape box = Obb{Vec3::Constant(Real(0.2)), Vec3::Constant(Real(0.5)), Mat3::Identity()};
  const Transform start{Quat::Identity(), Vec3(0, 0, 3)};
  const Vec3 motion(0, 0, -4);
  for (const Transform& pose : test_support::badPoses()) {
    EXPECT_FALSE(castClosest(mesh, pose, box, start, motion).has_value());
    EXPECT_FALSE(castClosest(mesh, Transform{}, box, pose, motion).has_value());
    EXPECT_FALSE(castAny(mesh, Transform{}, box, pose, motion));
    EXPECT_FALSE(castClosest(mesh, Transform{}, box, RigidMotion{start, pose}).has_value());
    EXPECT_FALSE(castAny(mesh, Transform{}, box, RigidMotion{pose, start}));
  }
  for (const ConvexShape& shape : test_support::badShapes())
    EXPECT_FALSE(castClosest(mesh, Transform{}, shape, start, motion).has_value());
  for (const Real bad : test_support::nonFiniteValues())
    EXPECT_FALSE(castClosest(mesh, Transform{}, box, start, Vec3(0, bad, -4)).has_value());
  EXPECT_TRUE(castClosest(mesh, Transform{}, box, start, motion).has_value());
}

}  // namespace
}  // namespace crux
