// The fcl backend's models and scene (oracle/fcl/fcl_world.cpp) against crux's own Scene.
//
// The same scene — a three-level hierarchy of rotated models (base -> arm -> hand) and two
// roots (rock, wall) over shared meshes — is built in a crux::Scene and in the fcl world, then
// changed step by step (set_transform, set_parent, remove_model); see peer_scene_twin.hpp.
// After each step:
//  - scene_pairs must equal the designed answer (every contact of the design is a penetration
//    of at least 0.1 unit, every separation at least 0.5 unit) in both;
//  - seeded random model_sphere / aabb / obb / plane / triangle and scene_query shapes are put to
//    both, and compared where UNAMBIGUOUS (crux answers the same with the shape shrunk and grown
//    by 5% of its size + 0.02, far above FCL's declared 1e-6): FCL must answer exactly as crux;
//  - bounds-only scene_query (FCL's own AABBs, a cube around the bounding sphere for rotated
//    models) must contain the triangle answer.
// FCL has no ray query: model_ray, model_segment and scene_ray must be Unsupported.

#include "peer_scene_twin.hpp"

namespace crux {
namespace {

class FclSceneTest : public PeerSceneTest {
 protected:
  FclSceneTest() : PeerSceneTest("fcl") {}
};

TEST_F(FclSceneTest, HierarchyMovesReparentingAndRemovalAgreeWithCruxScene) { runScenario(); }

TEST_F(FclSceneTest, RandomScenesPairsAgreeWithCruxWhereUnambiguous) {
  std::vector<std::string> failures;
  const Tally t = randomPairs(/*seed=*/7, /*scenes=*/120, /*models=*/6, &failures);
  for (const auto& f : failures) ADD_FAILURE() << f;
  EXPECT_GT(t.compared, 1000);
  EXPECT_GT(t.positive, 100);
  EXPECT_LT(t.positive, t.compared - 100);
}

TEST_F(FclSceneTest, BadHandlesAndNamesAreInvalidInput) { runBadInput(); }

TEST_F(FclSceneTest, ModelsKeepTheirMeshWhenTheMeshIsRemoved) { runMeshRemoved(); }

TEST_F(FclSceneTest, RaysAreUnsupported) {
  CollisionWorld& w = *twin_->peer;
  const ModelHandle arm = twin_->handles.at("arm");
  RayHitCollector hits;
  const Ray ray{Vec3(-5, 0, 0), Vec3(1, 0, 0)};
  EXPECT_FALSE(w.supports(WorldOp::ModelRay));
  EXPECT_FALSE(w.supports(WorldOp::ModelSegment));
  EXPECT_FALSE(w.supports(WorldOp::SceneRay));
  EXPECT_THROW(w.raycast(arm, ray, hits), Unsupported);
  EXPECT_THROW(w.intersects(arm, Segment{Vec3(-5, 0, 0), Vec3(5, 0, 0)}), Unsupported);
  EXPECT_THROW(w.sceneRaycast(ray, hits), Unsupported);
}

}  // namespace
}  // namespace crux
