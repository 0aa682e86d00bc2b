// Shape casts against scenes (src/scene/scene_cast.cpp): the broad-phase path against the brute
// force (identical answers) on every broad phase, for linear and rigid motions and for pure
// rotations (no path: the ball query); any-hit against closest.

#include <crux/scene/scene_cast.hpp>

#include <gtest/gtest.h>

#include <support/scene_fixtures.hpp>
#include "support/bad_inputs.hpp"

#include <crux/precondition.hpp>

#include <memory>
#include <optional>
#include <random>

namespace crux {
namespace {

using Rng = std::mt19937_64;

bool same(const std::optional<SceneCastHit>& a, const std::optional<SceneCastHit>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return a->model == b->model && a->hit.triangle == b->hit.triangle && a->hit.cast.t == b->hit.cast.t &&
         a->hit.cast.pointA == b->hit.cast.pointA && a->hit.cast.normal == b->hit.cast.normal;
}

class SceneCast : public ::testing::TestWithParam<BroadPhaseKind> {};

TEST_P(SceneCast, BroadPhaseEqualsBruteForce) {
  Rng rng(99);
  Scene scene(GetParam());
  crux::test::populate(scene, crux::test::bumpySphere(6, 8), 4, rng);
  std::uniform_real_distribution<double> u(-10, 10), r(0.1, 0.6);
  const Obb box{Vec3::Zero(), Vec3(Real(0.3), Real(0.2), Real(0.5)), Mat3::Identity()};
  const Capsule capsule{Vec3(-1, 0, 0), Vec3(1, 0, 0), Real(0.2)};
  int hits = 0;
  const int n = 40;
  for (int i = 0; i < n; ++i) {
    const ConvexShape shape = i % 2 ? ConvexShape(box) : ConvexShape(capsule);
    const Transform start = crux::test::randomPose(rng, 12);
    // aim near a model (noise of ±2.5: about half the casts hit something)
    const std::vector<ModelId> ids = scene.models().ids();
    const ModelId target = ids[std::size_t(i) % ids.size()];
    const Vec3 aim = scene.placed(target).world.translation + Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))) / 4;
    const Vec3 motion = (aim - start.translation) * Real(1.3);
    const auto fast = castClosest(scene, shape, start, motion);
    const auto brute = castClosest(scene, shape, start, motion, ScenePath::BruteForce);
    ASSERT_TRUE(same(fast, brute)) << i;
    EXPECT_EQ(castAny(scene, shape, start, motion), brute.has_value()) << i;
    hits += brute.has_value();
    if (brute) {  // the model cast of the model hit agrees
      const auto own = castClosest(scene.placed(brute->model), shape, start, motion);
      ASSERT_TRUE(own.has_value());
      EXPECT_EQ(own->cast.t, brute->hit.cast.t);
    }
    RigidMotion rigid{start, crux::test::randomPose(rng, 10)};
    if (i % 4 == 0) rigid.end.translation = rigid.start.translation;  // a pure rotation
    const auto rigidBrute = castClosest(scene, shape, rigid, ScenePath::BruteForce);
    ASSERT_TRUE(same(castClosest(scene, shape, rigid), rigidBrute)) << i;
    EXPECT_EQ(castAny(scene, shape, rigid), rigidBrute.has_value()) << i;
  }
  EXPECT_GT(hits, n / 5);
  EXPECT_LT(hits, n - n / 5);
}

// Non-queryable shapes, poses or motions (precondition.hpp): no hit, on every broad phase (an
// infinite ray origin used to crash their walks; scene casts walk them with the shape's path).
TEST_P(SceneCast, NonQueryableInputsGetNoHit) {
  if (CRUX_CHECK_PRECONDITIONS) GTEST_SKIP() << "this build aborts instead (precondition.hpp)";
  Rng rng(7);
  Scene scene(GetParam());
  crux::test::populate(scene, crux::test::bumpySphere(6, 8), 4, rng);
  const ConvexShape box = Obb{Vec3::Zero(), Vec3::Constant(Real(0.3)), Mat3::Identity()};
  const Transform start{Quat::Identity(), Vec3(-20, 0, 0)};
  const Vec3 motion(40, 0, 0);
  for (const Transform& pose : test_support::badPoses()) {
    EXPECT_FALSE(castClosest(scene, box, pose, motion).has_value());
    EXPECT_FALSE(castAny(scene, box, pose, motion));
    EXPECT_FALSE(castClosest(scene, box, RigidMotion{start, pose}).has_value());
    EXPECT_FALSE(castAny(scene, box, RigidMotion{pose, start}));
  }
  for (const ConvexShape& shape : test_support::badShapes()) EXPECT_FALSE(castAny(scene, shape, start, motion));
  for (const Real bad : test_support::nonFiniteValues())
    EXPECT_FALSE(castClosest(scene, box, start, Vec3(bad, 0, 0)).has_value());
}

INSTANTIATE_TEST_SUITE_P(AllBroadPhases, SceneCast,
                         ::testing::Values(BroadPhaseKind::BruteForce, BroadPhaseKind::Octree,
                                           BroadPhaseKind::DynamicAabbTree));

}  // namespace
}  // namespace crux
