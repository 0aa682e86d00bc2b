// Tests of src/scene/scene_batch.cpp: placed-mesh batches (rays closest/any, sphere/box/oriented
// box overlaps) and scene ray and region-query batches (spheres, boxes,
// oriented boxes; triangle and bounds tests; broad-phase and brute-force paths) equal the single
// Scene queries bit for bit for each broad phase, 1 and 2 threads and odd grains; hit rates are
// checked; size mismatches throw InvalidInput.

#include <crux/error.hpp>
#include <crux/scene/scene_batch.hpp>

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

/// A bumpy UV sphere (radius 1 ± 0.2) of about 2·rings·segments triangles.
std::shared_ptr<const Mesh> bumpySphere(int rings, int segments) {
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  for (int i = 0; i <= rings; ++i) {
    const double theta = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double phi = 2 * M_PI * j / segments;
      const double r = 1 + 0.2 * std::sin(5 * theta) * std::cos(3 * phi);
      v.emplace_back(Real(r * std::sin(theta) * std::cos(phi)), Real(r * std::sin(theta) * std::sin(phi)),
                     Real(r * std::cos(theta)));
    }
  }
  auto at = [&](int i, int j) { return std::uint32_t(i * segments + (j % segments)); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return std::make_shared<const Mesh>(std::move(v), std::move(t), "bumpy sphere");
}

Quat randomRotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Vector4d q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return Quat(Real(q[0]), Real(q[1]), Real(q[2]), Real(q[3]));
}

Transform randomPose(std::mt19937_64& rng, double range) {
  std::uniform_real_distribution<double> u(-range, range);
  Transform t;
  t.rotation = randomRotation(rng);
  t.translation = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
  return t;
}

/// A scene of `roots` families (a root with two children and a grandchild) scattered in
/// [-8, 8]^3, then every root moved once (so the hierarchy's world transforms were recomputed).
void populate(Scene& scene, const std::shared_ptr<const Mesh>& mesh, int roots, std::mt19937_64& rng) {
  std::vector<ModelId> rootIds;
  for (int r = 0; r < roots; ++r) {
    const ModelId root = scene.add(mesh, randomPose(rng, 8));
    const ModelId a = scene.add(mesh, randomPose(rng, 2), root);
    scene.add(mesh, randomPose(rng, 2), root);
    scene.add(mesh, randomPose(rng, 2), a);
    rootIds.push_back(root);
  }
  for (const ModelId root : rootIds) scene.setTransform(root, randomPose(rng, 8));
}

/// Rays from a sphere of radius 20 towards random points of [-10, 10]^3.
std::vector<Ray> sceneRays(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-10, 10);
  std::normal_distribution<double> g(0, 1);
  std::vector<Ray> rays(n);
  for (Ray& r : rays) {
    r.origin = (20 * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized()).cast<Real>();
    r.dir = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))) - r.origin;
  }
  return rays;
}

std::vector<Sphere> sceneSpheres(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-10, 10), r(0.1, 2);
  std::vector<Sphere> out(n);
  for (Sphere& s : out) s = {Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))), Real(r(rng))};
  return out;
}

std::vector<Aabb> sceneBoxes(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-10, 10), e(0.1, 2);
  std::vector<Aabb> out(n);
  for (Aabb& b : out) {
    const Vec3 c(Real(u(rng)), Real(u(rng)), Real(u(rng)));
    const Vec3 h(Real(e(rng)), Real(e(rng)), Real(e(rng)));
    b = {c - h, c + h};
  }
  return out;
}

std::vector<Obb> sceneObbs(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-10, 10), e(0.1, 2);
  std::vector<Obb> out(n);
  for (Obb& b : out) {
    b.center = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
    b.half = Vec3(Real(e(rng)), Real(e(rng)), Real(e(rng)));
    b.axes = randomRotation(rng).toRotationMatrix();
  }
  return out;
}

bool sameBits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), 3 * sizeof(Real)) == 0; }
bool sameHit(const std::optional<MeshRayHit>& a, const std::optional<MeshRayHit>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return std::memcmp(&a->t, &b->t, sizeof(Real)) == 0 && sameBits(a->point, b->point) &&
         sameBits(a->normal, b->normal) && a->triangle == b->triangle;
}
bool sameHit(const std::optional<SceneRayHit>& a, const std::optional<SceneRayHit>& b) {
  if (a.has_value() != b.has_value()) return false;
  return !a || (a->model == b->model && sameHit(std::optional<MeshRayHit>(a->hit), std::optional<MeshRayHit>(b->hit)));
}

std::string str(Real x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", double(x));
  return buf;
}
std::string str(const Vec3& p) { return "(" + str(p.x()) + ", " + str(p.y()) + ", " + str(p.z()) + ")"; }
std::string str(const Ray& r) { return "Ray{" + str(r.origin) + ", " + str(r.dir) + "}"; }
std::string str(const Sphere& s) { return "Sphere{" + str(s.center) + ", " + str(s.radius) + "}"; }
std::string str(const Aabb& b) { return "Aabb{" + str(b.min) + ", " + str(b.max) + "}"; }
std::string str(const Obb& b) {
  return "Obb{" + str(b.center) + ", " + str(b.half) + ", x " + str(Vec3(b.axes.col(0))) + ", y " +
         str(Vec3(b.axes.col(1))) + "}";
}

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
