// The bullet backend's models and scene (oracle/bullet/bullet_world.cpp) against crux's own
// Scene.
//
// The same scene — a three-level hierarchy of rotated models (base -> arm -> hand) and two
// roots (rock, wall) over shared meshes — is built in a crux::Scene and in the bullet world,
// then changed step by step (set_transform, set_parent, remove_model); see
// peer_scene_twin.hpp. After each step:
//  - scene_pairs (GImpact, performDiscreteCollisionDetection) must equal the designed answer
//    (every contact of the design a penetration of at least 0.1 unit, every separation at least
//    0.5 unit) in both;
//  - seeded random model_sphere / aabb / obb / triangle, model_ray, model_segment, scene_ray
//    (closest and any) and scene_query cases are put to both and compared where UNAMBIGUOUS
//    (crux answers the same with the shape shrunk and grown by 5% of its size + 0.02, or the
//    ray shifted sideways by 0.03 — all above Bullet's declared 2e-4·s + 1e-4 and its 0.05
//    minimum feature): booleans must be equal, ray hits on the same model with t and point
//    within 4 × Bullet's tolerance and the same normal;
//  - bounds-only scene_query (btCollisionShape::getAabb at each model's pose) must contain the
//    triangle answer.
// model_plane is Unsupported (no Bullet algorithm for a static plane against a static mesh).

#include "peer_scene_twin.hpp"

namespace crux {
namespace {

class BulletSceneTest : public PeerSceneTest {
 protected:
  BulletSceneTest() : PeerSceneTest("bullet") {}
};

TEST_F(BulletSceneTest, HierarchyMovesReparentingAndRemovalAgreeWithCruxScene) { runScenario(); }

TEST_F(BulletSceneTest, RandomScenesPairsAgreeWithCruxWhereUnambiguous) {
  std::vector<std::string> failures;
  const Tally t = randomPairs(/*seed=*/7, /*scenes=*/120, /*models=*/6, &failures);
  for (const auto& f : failures) ADD_FAILURE() << f;
  EXPECT_GT(t.compared, 1000);
  EXPECT_GT(t.positive, 100);
  EXPECT_LT(t.positive, t.compared - 100);
}

TEST_F(BulletSceneTest, BadHandlesAndNamesAreInvalidInput) { runBadInput(); }

TEST_F(BulletSceneTest, ModelsKeepTheirMeshWhenTheMeshIsRemoved) { runMeshRemoved(); }

TEST_F(BulletSceneTest, ModelPlaneIsUnsupported) {
  EXPECT_FALSE(twin_->peer->supports(WorldOp::ModelPlane));
  EXPECT_THROW(twin_->peer->overlaps(twin_->handles.at("arm"), Plane{Vec3::UnitZ(), 0}), Unsupported);
}

}  // namespace
}  // namespace crux
