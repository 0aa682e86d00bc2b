// Shape casts against placed models (src/model/model_cast.cpp): the cast is invariant under a
// rigid transform applied to the model, the shape and the motion together (same triangle, t
// within the tolerance, points moved by the transform), and equals the mesh cast at the model's
// world pose.

#include <crux/model/model_cast.hpp>

#include <gtest/gtest.h>

#include <support/scene_fixtures.hpp>

#include <random>

namespace crux {
namespace {

TEST(ModelCast, InvariantUnderAMotionOfTheWholeScene) {
  std::mt19937_64 rng(5);
  const auto mesh = crux::test::bumpySphere(8, 12);
  const Sphere ball{Vec3::Zero(), Real(0.2)};
  const Obb box{Vec3::Zero(), Vec3(Real(0.3), Real(0.1), Real(0.2)), Mat3::Identity()};
  std::uniform_real_distribution<double> u(-1, 1);
  int hits = 0;
  for (int i = 0; i < 40; ++i) {
    const ConvexShape shape = i % 2 ? ConvexShape(ball) : ConvexShape(box);
    const PlacedMesh model{mesh.get(), crux::test::randomPose(rng, 2)};
    const Transform start = crux::test::randomPose(rng, 5);
    const Vec3 motion = model.world.translation + Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))) - start.translation;
    const auto hit = castClosest(model, shape, start, motion);
    const auto direct = castClosest(*mesh, model.world, shape, start, motion);
    ASSERT_EQ(hit.has_value(), direct.has_value());
    EXPECT_EQ(castAny(model, shape, start, motion), hit.has_value());
    // the whole scene moved by g
    const Transform g = crux::test::randomPose(rng, 3);
    const PlacedMesh moved{mesh.get(), g * model.world};
    const auto other = castClosest(moved, shape, g * start, g.applyVector(motion));
    ASSERT_EQ(other.has_value(), hit.has_value()) << i;
    if (!hit) continue;
    ++hits;
    EXPECT_EQ(direct->cast.t, hit->cast.t);
    EXPECT_NEAR(double(other->cast.t), double(hit->cast.t), 1e-3) << i;
    EXPECT_NEAR(double((other->cast.pointB - g.apply(hit->cast.pointB)).norm()), 0, 1e-2) << i;
  }
  EXPECT_GT(hits, 5);
}

}  // namespace
}  // namespace crux
