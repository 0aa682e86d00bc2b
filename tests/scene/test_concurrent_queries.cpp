// Concurrent const queries (run it under ThreadSanitizer: -DCRUX_TSAN=ON, docs/threads.md):
// 8 std::threads hammer a Mesh (rays closest/any, sphere/box/oriented-box overlaps; contacts and
// mesh–mesh distance sharing one MeshQueryData), placed
// meshes, a ModelHierarchy right after setLocal (no preparation call: world transforms must
// already be current, reading must not write) and a Scene with each broad phase (rays, region
// queries) all at once, each thread in its own order, and every answer must equal the serial
// one computed beforehand on a copy. Then the batch functions run alongside the threads (on TBB
// workers, or serially under TSan: see kBatchThreads).

#include <crux/mesh/mesh_query_data.hpp>
#include <crux/model/hierarchy.hpp>
#include <crux/scene/dynamic_aabb_tree.hpp>
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
#include <thread>
#include <vector>

namespace crux {
namespace {

using namespace crux::test;  // bumpySphere, populate, scene shapes, sameHit, str (support/scene_fixtures.hpp)

constexpr int kThreads = 8;

#if defined(__SANITIZE_THREAD__)
#define CRUX_TEST_UNDER_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define CRUX_TEST_UNDER_TSAN 1
#endif
#endif
/// Threads of the TBB batches run beside the plain threads. Under ThreadSanitizer they run with
/// 1 (the serial loop, still concurrent with the other 7 threads): Debian's libtbb is not
/// instrumented, so TSan cannot see its internal synchronisation and reports false races inside
/// TBB's own task-arena code (tbb::detail::d1::affinity_slot after task_arena::initialize). The
/// queries the TBB workers would run are the const queries the plain threads hammer here.
#ifdef CRUX_TEST_UNDER_TSAN
constexpr std::uint32_t kBatchThreads = 1;
#else
constexpr std::uint32_t kBatchThreads = 2;
#endif

/// Runs body(thread) on kThreads threads at once (started together) and joins them.
template <class Body>
void onThreads(const Body& body) {
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) threads.emplace_back([&body, t] { body(t); });
  for (std::thread& t : threads) t.join();
}

/// Visits i = 0..n-1 starting at a thread-dependent offset, so threads hit different parts at
/// the same moment.
template <class Visit>
void rotated(std::size_t n, int thread, const Visit& visit) {
  const std::size_t start = n * std::size_t(thread) / kThreads;
  for (std::size_t k = 0; k < n; ++k) visit((start + k) % n);
}

TEST(ConcurrentQueries, MeshAndPlacedMeshQueries) {
  std::mt19937_64 rng(0xC0C0);
  const std::shared_ptr<const Mesh> mesh = bumpySphere(40, 80);
  const PlacedMesh placed{mesh.get(), randomPose(rng, 0.5)};
  std::vector<Ray> rays = sceneRays(400, rng);
  for (Ray& r : rays) r.origin *= Real(0.15);  // radius 3 around the unit mesh
  const std::vector<Sphere> spheres = [&] {
    std::vector<Sphere> s = sceneSpheres(300, rng);
    for (Sphere& x : s) x = {x.center * Real(0.13), x.radius * Real(0.1)};
    return s;
  }();
  const std::vector<Obb> obbs = [&] {
    std::vector<Obb> s = sceneObbs(300, rng);
    for (Obb& x : s) x.center *= Real(0.13), x.half *= Real(0.1);
    return s;
  }();
  std::vector<std::optional<MeshRayHit>> closest(rays.size()), placedClosest(rays.size());
  std::vector<std::uint8_t> any(rays.size()), sphereHit(spheres.size()), obbHit(obbs.size());
  std::size_t hits = 0, touching = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    closest[i] = raycastClosest(*mesh, rays[i]);
    placedClosest[i] = raycastClosest(placed, rays[i]);
    any[i] = raycastAny(*mesh, rays[i]);
    hits += any[i];
  }
  for (std::size_t i = 0; i < spheres.size(); ++i) touching += sphereHit[i] = overlaps(*mesh, spheres[i]);
  for (std::size_t i = 0; i < obbs.size(); ++i) obbHit[i] = overlaps(placed, obbs[i]);
  ASSERT_GT(hits, rays.size() / 5);
  ASSERT_GT(touching, spheres.size() / 10);

  std::vector<int> failures(kThreads, 0);
  onThreads([&](int t) {
    for (int round = 0; round < 3; ++round) {
      rotated(rays.size(), t, [&](std::size_t i) {
        if (!sameHit(raycastClosest(*mesh, rays[i]), closest[i])) ++failures[t];
        if (!sameHit(raycastClosest(placed, rays[i]), placedClosest[i])) ++failures[t];
        if (std::uint8_t(raycastAny(*mesh, rays[i])) != any[i]) ++failures[t];
      });
      rotated(spheres.size(), t, [&](std::size_t i) {
        if (std::uint8_t(overlaps(*mesh, spheres[i])) != sphereHit[i]) ++failures[t];
      });
      rotated(obbs.size(), t, [&](std::size_t i) {
        if (std::uint8_t(overlaps(placed, obbs[i])) != obbHit[i]) ++failures[t];
      });
    }
  });
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(failures[t], 0) << "thread " << t;
}

// A const MeshQueryData is read-only (mesh_query_data.hpp): threads sharing one for contacts
// (internal-edge correction) and mesh–mesh distance (oriented boxes) get the serial answers.
TEST(ConcurrentQueries, ContactsAndMeshDistanceShareConstQueryData) {
  std::mt19937_64 rng(0xDA7A);
  const std::shared_ptr<const Mesh> mesh = bumpySphere(20, 40);
  const MeshQueryData data(*mesh);
  std::vector<Transform> poses;
  for (int i = 0; i < 48; ++i) poses.push_back(randomPose(rng, 1.2));
  const Capsule capsule{Vec3(Real(-0.1), 0, 0), Vec3(Real(0.1), 0, 0), Real(0.08)};
  MeshDistanceOptions withData;
  withData.dataA = withData.dataB = &data;
  std::vector<Real> contactDepth(poses.size()), gap(poses.size());
  auto depthAt = [&](std::size_t i) {
    MeshContactManifold m;
    contacts(*mesh, Transform::identity(), capsule, poses[i], Real(0.01), m, &data);
    return m.count > 0 ? m.points[0].separation : kNoLimit;
  };
  auto gapAt = [&](std::size_t i) {  // the copy 2.5x farther out: some apart, some crossing
    const Transform copy{poses[i].rotation, poses[i].translation * Real(2.5)};
    return distance(*mesh, Transform::identity(), *mesh, copy, withData).distance;
  };
  std::size_t touching = 0, apart = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    contactDepth[i] = depthAt(i), gap[i] = gapAt(i);
    touching += contactDepth[i] != kNoLimit;
    apart += gap[i] > 0;
  }
  std::printf("%zu of %zu capsule poses touch, %zu mesh copies apart\n", touching, poses.size(), apart);
  ASSERT_GT(touching, 0u);
  ASSERT_GT(apart, 0u);
  std::vector<int> failures(kThreads, 0);
  onThreads([&](int t) {
    rotated(poses.size(), t, [&](std::size_t i) {
      if (depthAt(i) != contactDepth[i]) ++failures[t];
      if (gapAt(i) != gap[i]) ++failures[t];
    });
  });
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(failures[t], 0) << "thread " << t;
}

TEST(ConcurrentQueries, HierarchyReadsRightAfterMoves) {
  // Chains of depth 6 under 20 roots; every root is moved, then 8 threads read world transforms
  // and placed meshes with no preparation call. The expected values come from a copy.
  std::mt19937_64 rng(0x41E7);
  const std::shared_ptr<const Mesh> mesh = bumpySphere(4, 8);
  ModelHierarchy h;
  std::vector<ModelId> roots, all;
  for (int r = 0; r < 20; ++r) {
    ModelId parent = h.add(mesh, randomPose(rng, 10));
    roots.push_back(parent);
    all.push_back(parent);
    for (int d = 0; d < 6; ++d) all.push_back(parent = h.add(mesh, randomPose(rng, 1), parent));
  }
  for (int round = 0; round < 5; ++round) {
    for (const ModelId r : roots) h.setLocal(r, randomPose(rng, 10));
    h.setLocal(all[3], randomPose(rng, 1));
    const ModelHierarchy expected = h;
    std::vector<int> failures(kThreads, 0);
    onThreads([&](int t) {
      // Deepest first on odd threads (the old lazy cache refreshed whole chains on a read).
      for (std::size_t k = 0; k < all.size(); ++k) {
        const ModelId id = all[t % 2 ? all.size() - 1 - k : (k + std::size_t(t) * 7) % all.size()];
        const Transform& w = h.world(id);
        const Transform& e = expected.world(id);
        if (!sameBits(w.translation, e.translation) || w.rotation.coeffs() != e.rotation.coeffs()) ++failures[t];
        if (h.placed(id).mesh != mesh.get()) ++failures[t];
      }
    });
    for (int t = 0; t < kThreads; ++t) ASSERT_EQ(failures[t], 0) << "round " << round << " thread " << t;
  }
}

class ConcurrentScene : public ::testing::TestWithParam<BroadPhaseKind> {};

TEST_P(ConcurrentScene, RaysAndRegionQueries) {
  std::mt19937_64 rng(0x5CE7E);
  Scene scene(GetParam());
  populate(scene, bumpySphere(8, 16), 16, rng);
  const std::vector<Ray> rays = sceneRays(200, rng);
  const std::vector<Sphere> spheres = sceneSpheres(100, rng);
  const std::vector<Aabb> boxes = sceneBoxes(100, rng);
  const std::vector<Obb> obbs = sceneObbs(100, rng);
  std::vector<std::optional<SceneRayHit>> hit(rays.size());
  std::vector<std::vector<ModelId>> bySphere(spheres.size()), byBox(boxes.size()), byObb(obbs.size());
  std::size_t hits = 0, nonEmpty = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) hits += (hit[i] = scene.raycast(rays[i])).has_value();
  for (std::size_t i = 0; i < spheres.size(); ++i) nonEmpty += !(bySphere[i] = scene.query(spheres[i])).empty();
  for (std::size_t i = 0; i < boxes.size(); ++i) byBox[i] = scene.query(boxes[i]);
  for (std::size_t i = 0; i < obbs.size(); ++i) byObb[i] = scene.query(obbs[i], RegionTest::Bounds);
  ASSERT_GT(hits, rays.size() / 10);
  ASSERT_GT(nonEmpty, spheres.size() / 20);  // surface contacts: about one sphere in ten

  std::vector<int> failures(kThreads, 0);
  onThreads([&](int t) {
    for (int round = 0; round < 2; ++round) {
      rotated(rays.size(), t, [&](std::size_t i) {
        if (!sameHit(scene.raycast(rays[i]), hit[i])) ++failures[t];
      });
      rotated(spheres.size(), t, [&](std::size_t i) {
        if (scene.query(spheres[i]) != bySphere[i]) ++failures[t];
        if (scene.query(boxes[i]) != byBox[i]) ++failures[t];
        if (scene.query(obbs[i], RegionTest::Bounds) != byObb[i]) ++failures[t];
      });
    }
  });
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(failures[t], 0) << "thread " << t;

  // The TBB batches (kBatchThreads each) while the plain threads keep querying.
  std::vector<std::optional<SceneRayHit>> batchHits(rays.size());
  std::vector<std::vector<ModelId>> batchSpheres(spheres.size());
  std::vector<int> batchFailures(kThreads, 0);
  onThreads([&](int t) {
    if (t == 0) {
      raycast(scene, rays, batchHits, {}, ParallelOptions{kBatchThreads, 4});
      query(scene, spheres, batchSpheres, RegionTest::Triangles, ParallelOptions{kBatchThreads, 4});
      return;
    }
    rotated(rays.size(), t, [&](std::size_t i) {
      if (!sameHit(scene.raycast(rays[i]), hit[i])) ++batchFailures[t];
    });
  });
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(batchFailures[t], 0) << "thread " << t;
  for (std::size_t i = 0; i < rays.size(); ++i) ASSERT_TRUE(sameHit(batchHits[i], hit[i])) << str(rays[i]);
  for (std::size_t i = 0; i < spheres.size(); ++i) ASSERT_EQ(batchSpheres[i], bySphere[i]) << str(spheres[i]);
}

// The dynamic tree builds its wide ray tree lazily, inside a const raycast: threads that reach
// the threshold together must get one build and the same answers (and TSan no race).
TEST(ConcurrentScene, RayTreeBuiltWhileThreadsCastRays) {
  std::mt19937_64 rng(0x7AEE);
  Scene scene(BroadPhaseKind::DynamicAabbTree);
  populate(scene, bumpySphere(8, 16), 16, rng);
  const std::vector<Ray> rays = sceneRays(200, rng);
  std::vector<std::optional<SceneRayHit>> hit(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) hit[i] = scene.raycast(rays[i]);
  const auto& tree = dynamic_cast<const DynamicAabbTree&>(scene.broadPhase());
  ASSERT_TRUE(tree.hasRayTree());
  for (int round = 0; round < 3; ++round) {
    scene.setTransform(0, scene.models().local(0));  // same pose: answers unchanged, ray tree dropped
    ASSERT_FALSE(tree.hasRayTree());
    const std::size_t builds = tree.rayTreeBuilds();
    std::vector<int> failures(kThreads, 0);
    onThreads([&](int t) {
      rotated(rays.size(), t, [&](std::size_t i) {
        if (!sameHit(scene.raycast(rays[i]), hit[i])) ++failures[t];
      });
    });
    for (int t = 0; t < kThreads; ++t) EXPECT_EQ(failures[t], 0) << "round " << round << " thread " << t;
    EXPECT_TRUE(tree.hasRayTree());
    EXPECT_EQ(tree.rayTreeBuilds(), builds + 1);
  }
}

INSTANTIATE_TEST_SUITE_P(AllBroadPhases, ConcurrentScene,
                         ::testing::Values(BroadPhaseKind::DynamicAabbTree, BroadPhaseKind::Octree,
                                           BroadPhaseKind::BruteForce),
                         [](const ::testing::TestParamInfo<BroadPhaseKind>& info) {
                           return std::string(broadPhaseName(info.param));
                         });

}  // namespace
}  // namespace crux
