// Tests of src/mesh/batch_query.cpp: every batch (rays closest/any, sphere/box/oriented-box
// overlaps on a Mesh) equals the serial loop of single queries bit for bit,
// for 1 thread, 2 threads, the default arena and odd grains; hit rates are checked so the
// comparison is not vacuous; bad sizes and options throw InvalidInput before any work.

#include <crux/error.hpp>
#include <crux/mesh/batch_query.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace crux {
namespace {

/// A bumpy UV sphere (radius 1 ± 0.2) of about 2·rings·segments triangles.
Mesh bumpySphere(int rings, int segments) {
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
  return Mesh(std::move(v), std::move(t), "bumpy sphere");
}

std::string str(Real x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", double(x));
  return buf;
}
std::string str(const Vec3& p) { return "(" + str(p.x()) + ", " + str(p.y()) + ", " + str(p.z()) + ")"; }
std::string str(const Ray& r) { return "Ray{" + str(r.origin) + ", " + str(r.dir) + "}"; }

bool sameBits(const Vec3& a, const Vec3& b) { return std::memcmp(a.data(), b.data(), 3 * sizeof(Real)) == 0; }
bool sameHit(const std::optional<MeshRayHit>& a, const std::optional<MeshRayHit>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return std::memcmp(&a->t, &b->t, sizeof(Real)) == 0 && sameBits(a->point, b->point) &&
         sameBits(a->normal, b->normal) && a->triangle == b->triangle;
}

Vec3 randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Vector3d d(n(rng), n(rng), n(rng));
  return d.normalized().cast<Real>();
}

/// Rays from a sphere of radius 3 towards random points of [-1.2, 1.2]^3 (about half hit).
std::vector<Ray> randomRays(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  std::vector<Ray> rays(n);
  for (Ray& r : rays) {
    r.origin = 3 * randomUnit(rng);
    const Vec3 target(Real(u(rng)), Real(u(rng)), Real(u(rng)));
    r.dir = target - r.origin;
  }
  return rays;
}

std::vector<Sphere> randomSpheres(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.3, 1.3), r(0.01, 0.3);
  std::vector<Sphere> out(n);
  for (Sphere& s : out) s = {Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng))), Real(r(rng))};
  return out;
}

std::vector<Aabb> randomBoxes(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.3, 1.3), e(0.01, 0.3);
  std::vector<Aabb> out(n);
  for (Aabb& b : out) {
    const Vec3 c(Real(u(rng)), Real(u(rng)), Real(u(rng)));
    const Vec3 h(Real(e(rng)), Real(e(rng)), Real(e(rng)));
    b = {c - h, c + h};
  }
  return out;
}

std::vector<Obb> randomObbs(std::size_t n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.3, 1.3), e(0.01, 0.3);
  std::normal_distribution<double> g(0, 1);
  std::vector<Obb> out(n);
  for (Obb& b : out) {
    b.center = Vec3(Real(u(rng)), Real(u(rng)), Real(u(rng)));
    b.half = Vec3(Real(e(rng)), Real(e(rng)), Real(e(rng)));
    b.axes = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix().cast<Real>();
  }
  return out;
}

/// The thread/grain settings every batch is run with.
std::vector<ParallelOptions> settings() {
  return {ParallelOptions{1, 0}, ParallelOptions{2, 0}, ParallelOptions{0, 0}, ParallelOptions{2, 1},
          ParallelOptions{2, 7}, ParallelOptions{0, 1000}};
}
std::string str(const ParallelOptions& p) {
  return "threads " + std::to_string(p.threads) + ", grain " + std::to_string(p.grain);
}

/// Fraction of true answers, which must lie in [lo, hi] for a comparison to mean something.
double rate(const std::vector<std::uint8_t>& v) {
  std::size_t k = 0;
  for (const std::uint8_t x : v) k += x;
  return double(k) / double(v.size());
}

class BatchQuery : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { mesh_ = new Mesh(bumpySphere(60, 120)); }
  static void TearDownTestSuite() { delete mesh_; }
  static const Mesh* mesh_;
};
const Mesh* BatchQuery::mesh_ = nullptr;

TEST_F(BatchQuery, RayBatchesEqualSerialBitForBit) {
  std::mt19937_64 rng(0xBA7C4);
  const std::vector<Ray> rays = randomRays(5000, rng);
  RayQueryOptions options;
  std::vector<std::optional<MeshRayHit>> closest(rays.size());
  std::vector<std::uint8_t> any(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    closest[i] = raycastClosest(*mesh_, rays[i], options);
    any[i] = raycastAny(*mesh_, rays[i], options);
  }
  std::vector<std::uint8_t> hit(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) hit[i] = closest[i].has_value();
  EXPECT_GT(rate(hit), 0.3);
  EXPECT_LT(rate(hit), 0.9);
  EXPECT_EQ(hit, any);
  for (const ParallelOptions& p : settings()) {
    SCOPED_TRACE(str(p));
    std::vector<std::optional<MeshRayHit>> outClosest(rays.size());
    std::vector<std::uint8_t> outAny(rays.size(), 7);
    raycastClosest(*mesh_, rays, outClosest, options, p);
    raycastAny(*mesh_, rays, outAny, options, p);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      ASSERT_TRUE(sameHit(closest[i], outClosest[i])) << "ray " << i << " " << str(rays[i]);
      ASSERT_EQ(any[i], outAny[i]) << "ray " << i << " " << str(rays[i]);
    }
  }
}

TEST_F(BatchQuery, RayOptionsArePassedThrough) {
  std::mt19937_64 rng(0x0B7);
  const std::vector<Ray> rays = randomRays(2000, rng);
  RayQueryOptions options;
  options.maxDistance = Real(2.5);
  options.cullBackFaces = true;
  std::vector<std::optional<MeshRayHit>> out(rays.size());
  std::vector<std::uint8_t> any(rays.size());
  raycastClosest(*mesh_, rays, out, options, ParallelOptions{2, 16});
  raycastAny(*mesh_, rays, any, options, ParallelOptions{2, 16});
  std::size_t hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    ASSERT_TRUE(sameHit(out[i], raycastClosest(*mesh_, rays[i], options))) << i << " " << str(rays[i]);
    ASSERT_EQ(any[i], std::uint8_t(raycastAny(*mesh_, rays[i], options))) << i << " " << str(rays[i]);
    hits += out[i].has_value();
    if (out[i]) ASSERT_LE(out[i]->t, options.maxDistance);
  }
  EXPECT_GT(hits, 0u);
}

template <class Shape>
void checkOverlapBatch(const Mesh& mesh, const std::vector<Shape>& shapes, const char* name, double minRate = 0.2) {
  SCOPED_TRACE(name);
  std::vector<std::uint8_t> serial(shapes.size());
  for (std::size_t i = 0; i < shapes.size(); ++i) serial[i] = overlaps(mesh, shapes[i]);
  EXPECT_GT(rate(serial), minRate);
  EXPECT_LT(rate(serial), 0.8);
  for (const ParallelOptions& p : settings()) {
    SCOPED_TRACE(str(p));
    std::vector<std::uint8_t> out(shapes.size(), 7);
    overlaps(mesh, shapes, out, p);
    ASSERT_EQ(out, serial);
  }
}

TEST_F(BatchQuery, OverlapBatchesEqualSerial) {
  std::mt19937_64 rng(0x0E7A);
  checkOverlapBatch(*mesh_, randomSpheres(4000, rng), "spheres");
  checkOverlapBatch(*mesh_, randomBoxes(4000, rng), "boxes");
  checkOverlapBatch(*mesh_, randomObbs(4000, rng), "oriented boxes");
}

TEST_F(BatchQuery, IntegerGridOverlapsMatchTheSingleExactQueries) {
  // Boxes and spheres on the integer grid against an integer-grid mesh: the batch must give the
  // single queries' (exact) answers, including touching contacts.
  const Mesh grid({Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0), Vec3(0, 0, 4)}, {{{0, 1, 2}}, {{0, 1, 3}}, {{0, 2, 3}}, {{1, 2, 3}}},
                  "tetrahedron");
  std::vector<Aabb> boxes;
  std::vector<Sphere> spheres;
  for (int x = -2; x <= 5; ++x)
    for (int y = -2; y <= 5; ++y)
      for (int z = -2; z <= 5; ++z) {
        boxes.push_back({Vec3(Real(x), Real(y), Real(z)), Vec3(Real(x + 1), Real(y + 1), Real(z + 1))});
        spheres.push_back({Vec3(Real(x), Real(y), Real(z)), Real(1)});
      }
  // About a fifth of the cells reach the surface.
  checkOverlapBatch(grid, boxes, "grid boxes", 0.1);
  checkOverlapBatch(grid, spheres, "grid spheres", 0.1);
}

TEST_F(BatchQuery, EmptyBatchesDoNothing) {
  std::vector<Ray> none;
  std::vector<std::optional<MeshRayHit>> out;
  EXPECT_NO_THROW(raycastClosest(*mesh_, none, out));
  EXPECT_NO_THROW(raycastClosest(*mesh_, none, out, {}, ParallelOptions{2, 0}));
}

TEST_F(BatchQuery, BadSizesAndOptionsThrowBeforeAnyWork) {
  std::mt19937_64 rng(1);
  const std::vector<Ray> rays = randomRays(10, rng);
  std::vector<std::optional<MeshRayHit>> shortOut(9);
  std::vector<std::uint8_t> flags(11, 7);
  EXPECT_THROW(raycastClosest(*mesh_, rays, shortOut), InvalidInput);
  EXPECT_THROW(raycastAny(*mesh_, rays, flags), InvalidInput);
  for (const std::uint8_t f : flags) EXPECT_EQ(f, 7);  // untouched
  const std::vector<Sphere> spheres = randomSpheres(3, rng);
  try {
    overlaps(*mesh_, spheres, flags);
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("11"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("3"), std::string::npos) << e.what();
  }
  std::vector<std::optional<MeshRayHit>> out(rays.size());
  EXPECT_THROW(raycastClosest(*mesh_, rays, out, {}, ParallelOptions{kMaxBatchThreads + 1, 0}), InvalidInput);
}

TEST_F(BatchQuery, ParallelForVisitsEveryIndexOnce) {
  for (const ParallelOptions& p : settings()) {
    SCOPED_TRACE(str(p));
    std::vector<int> seen(10007, 0);
    parallelFor(seen.size(), p, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) ++seen[i];
    });
    for (std::size_t i = 0; i < seen.size(); ++i) ASSERT_EQ(seen[i], 1) << i;
  }
}

}  // namespace
}  // namespace crux
