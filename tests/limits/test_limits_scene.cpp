// Limits: many models in a scene and deep hierarchies (docs/limits.md, "Scenes").
//
//  - Scenes of 10^6 models (a 100×100×100 lattice of unit-size boxes sharing one mesh): add,
//    move 1 %, pairs, rays, region queries, removal. Expected answers come from the lattice
//    geometry, not from crux. The sanitizer stage (CRUX_TEST_SCALE < 1) runs a 20³ lattice;
//    CRUX_LIMITS_LATTICE=N sets the lattice side by hand.
//  - A chain of 10,000 models (each the child of the previous): add, set_transform on the root,
//    queries on the leaf, re-parenting, cycle refusal, removal; no stack overflow (every walk in
//    hierarchy.cpp and the broad phases is an explicit loop; the sanitizer stage runs this too).
#include <crux/error.hpp>
#include <crux/scene/scene.hpp>

#include <support/test_scale.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace crux {
namespace {

/// The closed box [0, 2]³ (12 triangles).
std::shared_ptr<const Mesh> box2() {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.emplace_back(Real(2 * (i & 1)), Real(2 * ((i >> 1) & 1)), Real(2 * ((i >> 2) & 1)));
  const std::vector<TriangleIndices> t = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return std::make_shared<const Mesh>(v, t, "box2");
}

Transform at(Real x, Real y, Real z) {
  Transform t;
  t.translation = Vec3(x, y, z);
  return t;
}

double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

/// Side of the lattice: 100 (10^6 models, ~6 s in Release on a loaded 2-core VM); 20 (8,000
/// models) when CRUX_TEST_SCALE < 1 (the sanitizer stage: adding models is ~25x slower under
/// ASan); CRUX_LIMITS_LATTICE=N sets it by hand.
int latticeSide() {
  if (const char* env = std::getenv("CRUX_LIMITS_LATTICE")) return std::max(2, std::atoi(env));
  return test::scaledCases(1000, 1) < 1000 ? 20 : 100;
}

// Model (i, j, k) is box2 translated to (4k, 4j, 4i): id = (i·n + j)·n + k. Boxes 2 apart: no
// pairs. Then every model with k == 0 moves +3 in x, into its neighbour k == 1 (the boxes'
// surfaces cross): exactly n² pairs (id, id + 1).
TEST(LimitsScene, LatticeOfAMillionModels) {
  const int n = latticeSide();
  const auto mesh = box2();
  Scene scene;
  auto id = [&](int i, int j, int k) { return ModelId((i * n + j) * n + k); };
  auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) ASSERT_EQ(scene.add(mesh, at(Real(4 * k), Real(4 * j), Real(4 * i))), id(i, j, k));
  const double addSeconds = seconds(t0);
  ASSERT_EQ(scene.size(), std::size_t(n) * n * n);

  t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(scene.boundsPairs().empty());
  const double firstPairsSeconds = seconds(t0);

  std::vector<std::pair<ModelId, Transform>> moves;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) moves.push_back({id(i, j, 0), at(3, Real(4 * j), Real(4 * i))});
  t0 = std::chrono::steady_clock::now();
  scene.setTransforms(moves);
  const double moveSeconds = seconds(t0);

  t0 = std::chrono::steady_clock::now();
  const auto pairs = scene.overlappingPairs();
  const double pairsSeconds = seconds(t0);
  ASSERT_EQ(pairs.size(), std::size_t(n) * n);
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const ModelId expected = id(int(p) / n, int(p) % n, 0);
    ASSERT_EQ(pairs[p], std::make_pair(expected, ModelId(expected + 1))) << "pair " << p;
  }

  // Rays along +x through the middle of row (i, j), from x = -10: the moved box (face at x = 3)
  // first, t = 13; from x = 4·(n/2) + 3 (between boxes k = n/2 and n/2 + 1): box n/2 + 1, t = 1.
  t0 = std::chrono::steady_clock::now();
  int rays = 0;
  for (int i = 0; i < n; i += 7)
    for (int j = 0; j < n; j += 5) {
      Ray ray;
      ray.origin = Vec3(-10, Real(4 * j + 1), Real(4 * i + 1));
      ray.dir = Vec3(1, 0, 0);
      auto hit = scene.raycast(ray);
      ASSERT_TRUE(hit.has_value()) << "row " << i << " " << j;
      EXPECT_EQ(hit->model, id(i, j, 0));
      EXPECT_EQ(hit->hit.t, Real(13));
      ray.origin.x() = Real(4 * (n / 2) + 3);
      hit = scene.raycast(ray);
      ASSERT_TRUE(hit.has_value());
      EXPECT_EQ(hit->model, id(i, j, n / 2 + 1));
      EXPECT_EQ(hit->hit.t, Real(1));
      // Along -z from above the lattice: the top box of the column (i = n - 1), face z = 4n - 2.
      Ray down;
      down.origin = Vec3(Real(4 * (n / 3) + 1), Real(4 * j + 1), Real(4 * n + 10));
      down.dir = Vec3(0, 0, -1);
      hit = scene.raycast(down);
      ASSERT_TRUE(hit.has_value());
      EXPECT_EQ(hit->model, id(n - 1, j, n / 3));
      EXPECT_EQ(hit->hit.t, Real(12));
      rays += 3;
    }
  const double raySeconds = seconds(t0);

  // A sphere touching exactly the 8 boxes around a lattice gap corner (radius just over the
  // distance to their nearest corners).
  const int c = n / 2;
  const Sphere sphere{Vec3(Real(4 * c - 1), Real(4 * c - 1), Real(4 * c - 1)), Real(1.8)};
  std::vector<ModelId> expected;
  for (int i = c - 1; i <= c; ++i)
    for (int j = c - 1; j <= c; ++j)
      for (int k = c - 1; k <= c; ++k) expected.push_back(id(i, j, k));
  EXPECT_EQ(scene.query(sphere), expected);

  // Remove a slab and check nothing of it is reported any more.
  t0 = std::chrono::steady_clock::now();
  for (int j = 0; j < n; ++j)
    for (int k = 0; k < n; ++k) scene.remove(id(0, j, k));
  const double removeSeconds = seconds(t0);
  EXPECT_EQ(scene.size(), std::size_t(n) * n * (n - 1));
  EXPECT_EQ(scene.overlappingPairs().size(), std::size_t(n) * (n - 1));
  Ray ray;
  ray.origin = Vec3(-10, 1, 1);
  ray.dir = Vec3(1, 0, 0);
  EXPECT_FALSE(scene.raycast(ray).has_value());

  std::printf("lattice %d^3 = %d models: add %.2f s, first pairs %.2f s, move %d %.3f s, overlapping pairs %.2f s, "
              "%d rays %.3f s, remove %d %.3f s\n",
              n, n * n * n, addSeconds, firstPairsSeconds, n * n, moveSeconds, pairsSeconds, rays, raySeconds, n * n,
              removeSeconds);
}

// A chain of 10,000 models, each translated by (4, 0, 0) from its parent.
TEST(LimitsScene, HierarchyTenThousandDeep) {
  const int depth = 10'000;
  const auto mesh = box2();
  Scene scene;
  std::vector<ModelId> chain;
  chain.push_back(scene.add(mesh, at(1, 0, 0)));
  for (int d = 1; d < depth; ++d) chain.push_back(scene.add(mesh, at(4, 0, 0), chain.back()));
  const ModelId root = chain.front(), leaf = chain.back();
  const Real leafX = Real(1 + 4 * (depth - 1));
  EXPECT_EQ(scene.models().world(leaf).translation, Vec3(leafX, 0, 0));
  EXPECT_EQ(scene.models().descendants(root).size(), std::size_t(depth - 1));
  EXPECT_TRUE(scene.boundsPairs().empty());

  // Move the root: all 10,000 models follow.
  scene.setTransform(root, at(1, 8, 0));
  EXPECT_EQ(scene.models().world(leaf).translation, Vec3(leafX, 8, 0));
  EXPECT_EQ(scene.models().world(chain[depth / 2]).translation, Vec3(Real(1 + 4 * (depth / 2)), 8, 0));
  Ray down;
  down.origin = Vec3(leafX + 1, 9, 10);
  down.dir = Vec3(0, 0, -1);
  auto hit = scene.raycast(down);
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->model, leaf);
  EXPECT_EQ(hit->hit.t, Real(8));
  EXPECT_EQ(scene.query(Sphere{Vec3(leafX + 1, 9, 1), Real(0.5)}, RegionTest::Bounds), std::vector<ModelId>{leaf});
  EXPECT_TRUE(scene.overlappingPairs().empty());

  // A cycle is refused, however deep the would-be parent is.
  EXPECT_THROW(scene.setParent(root, leaf), InvalidInput);
  EXPECT_THROW(scene.setParent(chain[depth / 2], chain[depth - 2]), InvalidInput);

  // Re-parent the leaf to the root (world pose kept), then move the root again: the leaf and the
  // whole chain follow.
  scene.setParent(leaf, root);
  EXPECT_EQ(scene.models().parent(leaf), root);
  EXPECT_EQ(scene.models().world(leaf).translation, Vec3(leafX, 8, 0));
  scene.setTransform(root, at(1, 16, 0));
  EXPECT_EQ(scene.models().world(leaf).translation, Vec3(leafX, 16, 0));
  EXPECT_EQ(scene.models().world(chain[depth - 2]).translation, Vec3(leafX - 4, 16, 0));

  // Detach the middle of the chain: its subtree (about 5,000 models) stays where it is.
  const ModelId middle = chain[depth / 2];
  scene.setParent(middle, kNoModel);
  scene.setTransform(root, at(1, 24, 0));
  EXPECT_EQ(scene.models().world(middle).translation, Vec3(Real(1 + 4 * (depth / 2)), 16, 0));
  EXPECT_EQ(scene.models().world(chain[depth - 2]).translation, Vec3(leafX - 4, 16, 0));
  EXPECT_EQ(scene.models().world(leaf).translation, Vec3(leafX, 24, 0));

  // Remove every other model of the first half (children move to the grandparent, keeping
  // their world pose), then everything from the top down.
  for (int d = 1; d < depth / 2; d += 2) scene.remove(chain[d]);
  EXPECT_EQ(scene.models().world(chain[depth / 2 - 2]).translation, Vec3(Real(1 + 4 * (depth / 2 - 2)), 24, 0));
  EXPECT_EQ(scene.models().parent(chain[2]), root);
  scene.remove(root);
  scene.remove(middle);
  EXPECT_EQ(scene.size(), std::size_t(depth - depth / 4 - 2));
  for (int d = 0; d < depth; ++d)
    if (scene.models().contains(chain[d])) scene.remove(chain[d]);
  EXPECT_EQ(scene.size(), 0u);
}

// The same chain built bottom-up by re-parenting (each new model becomes the parent of the
// previous root), then dropped with the scene: destruction must not recurse either.
TEST(LimitsScene, HierarchyTenThousandDeepBuiltByReparenting) {
  const int depth = 10'000;
  const auto mesh = box2();
  auto scene = std::make_unique<Scene>();
  ModelId top = scene->add(mesh, at(0, 0, 0));
  const ModelId bottom = top;
  for (int d = 1; d < depth; ++d) {
    const ModelId next = scene->add(mesh, at(Real(-4 * d), 0, 0));
    scene->setParent(top, next);
    top = next;
  }
  EXPECT_EQ(scene->models().descendants(top).size(), std::size_t(depth - 1));
  scene->setTransform(top, at(Real(-4 * (depth - 1)), 4, 0));
  EXPECT_EQ(scene->models().world(bottom).translation, Vec3(0, 4, 0));
  scene.reset();
}

}  // namespace
}  // namespace crux
