// Tests of src/scene/scene_batch.cpp: placed-mesh batches (rays closest/any, sphere/box/oriented
// box overlaps) and scene ray and region-query batches (spheres, boxes,
// oriented boxes; triangle and bounds tests; broad-phase and brute-force paths) equal the single
// Scene queries bit for bit for each broad phase, 1 and 2 threads and odd grains; hit rates are
// checked; size mismatches throw InvalidInput.

#include <crux/error.hpp>
#include <crux/scene/scene_batch.hpp>
#include "support/scene_fixtures.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace crux {
namespace {

using namespace crux::test;  // bumpySphere, populate, scene shapes, sameHit, str (support/scene_fixtures.hpp)

std::vector<ParallelOptions> settings() {
  return {ParallelOptions{1, 0}, ParallelOptions{2, 0}, ParallelOptions{0, 3}, ParallelOptions{2, 1}};
}

template <class Shape>
void checkRegionBatch(const Scene& scene, const std::vector<Shape>& shapes, const char* name) {
  SCOPED_TRACE(name);
  for (const RegionTest test : {RegionTest::Triangles, RegionTest::Bounds})
    for (const ScenePath path : {ScenePath::BroadPhase, ScenePath::BruteForce}) {
      std::vector<std::vector<ModelId>> serial(shapes.size());
      std::size_t nonEmpty = 0;
      for (std::size_t i = 0; i < shapes.size(); ++i) {
        serial[i] = scene.query(shapes[i], test, path);
        nonEmpty += !serial[i].empty();
      }
      EXPECT_GT(nonEmpty, shapes.size() / 10);
      EXPECT_LT(nonEmpty, shapes.size());
      for (const ParallelOptions& p : settings()) {
        std::vector<std::vector<ModelId>> out(shapes.size(), std::vector<ModelId>{kNoModel});
        query(scene, shapes, out, test, p, path);
        for (std::size_t i = 0; i < shapes.size(); ++i)
          ASSERT_EQ(out[i], serial[i]) << str(shapes[i]) << " test " << int(test) << " path " << int(path)
                                       << " threads " << p.threads << " grain " << p.grain;
      }
    }
}

TEST(PlacedMeshBatch, EqualsSerialBitForBit) {
  std::mt19937_64 rng(0x91ACE);
  const std::shared_ptr<const Mesh> mesh = bumpySphere(40, 80);
  PlacedMesh placed{mesh.get(), randomPose(rng, 0.5)};
  // Scene inputs span [-10, 10]^3; scaled by 0.13 they cover the unit mesh and its surroundings.
  std::vector<Ray> rays = sceneRays(3000, rng);
  for (Ray& r : rays) r.origin *= Real(0.15);
  std::vector<Sphere> spheres = sceneSpheres(2000, rng);
  for (Sphere& x : spheres) x = {x.center * Real(0.13), x.radius * Real(0.1)};
  std::vector<Aabb> boxes = sceneBoxes(2000, rng);
  for (Aabb& b : boxes) b = {b.min * Real(0.13), b.max * Real(0.13)};
  std::vector<Obb> obbs = sceneObbs(2000, rng);
  for (Obb& x : obbs) x.center *= Real(0.13), x.half *= Real(0.1);
  for (const ParallelOptions& p : settings()) {
    std::vector<std::optional<MeshRayHit>> closest(rays.size());
    std::vector<std::uint8_t> any(rays.size()), s(spheres.size()), b(boxes.size()), o(obbs.size());
    raycastClosest(placed, rays, closest, {}, p);
    raycastAny(placed, rays, any, {}, p);
    overlaps(placed, spheres, s, p);
    overlaps(placed, boxes, b, p);
    overlaps(placed, obbs, o, p);
    std::size_t hits = 0, touching[3] = {0, 0, 0};
    for (std::size_t i = 0; i < rays.size(); ++i) {
      ASSERT_TRUE(sameHit(closest[i], raycastClosest(placed, rays[i]))) << i << " " << str(rays[i]);
      ASSERT_EQ(any[i], std::uint8_t(raycastAny(placed, rays[i]))) << i << " " << str(rays[i]);
      hits += any[i];
    }
    for (std::size_t i = 0; i < spheres.size(); ++i) {
      ASSERT_EQ(s[i], std::uint8_t(overlaps(placed, spheres[i]))) << str(spheres[i]);
      touching[0] += s[i];
    }
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      ASSERT_EQ(b[i], std::uint8_t(overlaps(placed, boxes[i]))) << str(boxes[i]);
      touching[1] += b[i];
    }
    for (std::size_t i = 0; i < obbs.size(); ++i) {
      ASSERT_EQ(o[i], std::uint8_t(overlaps(placed, obbs[i]))) << str(obbs[i]);
      touching[2] += o[i];
    }
    EXPECT_GT(hits, rays.size() / 5);
    for (const std::size_t t : touching) EXPECT_GT(t, std::size_t(100));
  }
}

class SceneBatch : public ::testing::TestWithParam<BroadPhaseKind> {};

TEST_P(SceneBatch, RaysEqualSerialBitForBit) {
  std::mt19937_64 rng(0x5CE4E);
  Scene scene(GetParam());
  populate(scene, bumpySphere(12, 24), 12, rng);
  const std::vector<Ray> rays = sceneRays(1500, rng);
  for (const ScenePath path : {ScenePath::BroadPhase, ScenePath::BruteForce}) {
    std::vector<std::optional<SceneRayHit>> serial(rays.size());
    std::size_t hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      serial[i] = scene.raycast(rays[i], {}, path);
      hits += serial[i].has_value();
    }
    EXPECT_GT(hits, rays.size() / 10);
    EXPECT_LT(hits, rays.size());
    for (const ParallelOptions& p : settings()) {
      std::vector<std::optional<SceneRayHit>> out(rays.size());
      raycast(scene, rays, out, {}, p, path);
      for (std::size_t i = 0; i < rays.size(); ++i)
        ASSERT_TRUE(sameHit(out[i], serial[i])) << i << " " << str(rays[i]) << " path " << int(path) << " threads "
                                                << p.threads << " grain " << p.grain;
    }
  }
}

TEST_P(SceneBatch, RegionQueriesEqualSerial) {
  std::mt19937_64 rng(0x4E610);
  Scene scene(GetParam());
  populate(scene, bumpySphere(12, 24), 12, rng);
  checkRegionBatch(scene, sceneSpheres(600, rng), "spheres");
  checkRegionBatch(scene, sceneBoxes(600, rng), "boxes");
  checkRegionBatch(scene, sceneObbs(600, rng), "oriented boxes");
}

INSTANTIATE_TEST_SUITE_P(AllBroadPhases, SceneBatch,
                         ::testing::Values(BroadPhaseKind::DynamicAabbTree, BroadPhaseKind::Octree,
                                           BroadPhaseKind::BruteForce),
                         [](const ::testing::TestParamInfo<BroadPhaseKind>& info) {
                           return std::string(broadPhaseName(info.param));
                         });

TEST(SceneBatchInput, SizeMismatchThrows) {
  Scene scene;
  std::mt19937_64 rng(3);
  const std::vector<Ray> rays = sceneRays(4, rng);
  std::vector<std::optional<SceneRayHit>> out(5);
  EXPECT_THROW(raycast(scene, rays, out), InvalidInput);
  const std::vector<Sphere> spheres = sceneSpheres(2, rng);
  std::vector<std::vector<ModelId>> ids(1);
  EXPECT_THROW(query(scene, spheres, ids), InvalidInput);
}

}  // namespace
}  // namespace crux
