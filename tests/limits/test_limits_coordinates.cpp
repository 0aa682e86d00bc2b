// Limits: coordinates up to 1e15 and beyond (docs/limits.md, "Coordinates").
//
// What is guaranteed: crux's boolean answers are exact on the integer grid (predicates.hpp), and
// that grid may be scaled by a power of two and translated by any multiple of its spacing as long
// as every coordinate stays representable: differences of such coordinates are exact, so a
// configuration far from the origin decides exactly like the same configuration at the origin.
// At 1e15 the spacing is g = 2^(50 - digits) (float: 2^26 ≈ 6.7e7, double: 2^-3), the resolution
// of Real there. Ray hits keep a relative precision: t and the hit point are within a few ulps of
// the largest coordinate magnitude of the query. The tests check both at 1e15 against the exact
// (CGAL) oracle, translated in the vertices and in the model transform, and check that 1e30, 1e38
// (and 1e300 in double builds) give no crash, no NaN and symmetric answers; non-finite input is
// InvalidInput everywhere.
#include <crux/error.hpp>
#include <crux/mesh/mesh_io.hpp>
#include <crux/mesh/mesh_query.hpp>
#include <crux/model/model_query.hpp>
#include <crux/scene/scene.hpp>

#include <exact/exact.hpp>

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <iomanip>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>
#include "support/invalid_input.hpp"

namespace crux {
namespace {

constexpr int kDigits = std::numeric_limits<Real>::digits;
/// Grid spacing at 1e15 (< 2^50): the ulp of Real there.
const double kSpacing = std::ldexp(1.0, 50 - kDigits);
/// 1e15 rounded to a multiple of the spacing (exact in Real).
const double kOffset = std::round(1e15 / kSpacing) * kSpacing;

std::string str(const Vec3& v) {
  std::ostringstream os;
  os.precision(17);
  os << "(" << double(v.x()) << ", " << double(v.y()) << ", " << double(v.z()) << ")";
  return os.str();
}

/// Grid point c·g + offset on every axis.
Vec3 at(const Eigen::Vector3i& c, double offset) {
  return Vec3(Real(offset + c.x() * kSpacing), Real(offset + c.y() * kSpacing), Real(offset + c.z() * kSpacing));
}

/// A random tetrahedron (4 triangles) with grid coordinates in [-12, 12]³ around `centre`.
std::vector<Eigen::Vector3i> randomTetrahedron(std::mt19937& rng, const Eigen::Vector3i& centre) {
  std::uniform_int_distribution<int> d(-6, 6);
  std::vector<Eigen::Vector3i> corners;
  for (int i = 0; i < 4; ++i) corners.push_back(centre + Eigen::Vector3i(d(rng), d(rng), d(rng)));
  return corners;
}

const std::vector<TriangleIndices> kTetraTriangles = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};

std::shared_ptr<const Mesh> tetraMesh(const std::vector<Eigen::Vector3i>& c, double offset) {
  std::vector<Vec3> v;
  for (const auto& p : c) v.push_back(at(p, offset));
  return std::make_shared<const Mesh>(v, kTetraTriangles, "tetra");
}

Transform translation(double offset) {
  Transform t;
  t.translation = Vec3::Constant(Real(offset));
  return t;
}

/// The exact answer (CGAL, brute force over the 16 triangle pairs) at the origin.
bool exactOverlap(const Mesh& a, const Mesh& b) {
  for (std::uint32_t i = 0; i < a.triangleCount(); ++i)
    for (std::uint32_t j = 0; j < b.triangleCount(); ++j)
      if (exact::overlaps(a.triangle(i), b.triangle(j))) return true;
  return false;
}

std::string describe(const std::vector<Eigen::Vector3i>& a, const std::vector<Eigen::Vector3i>& b) {
  std::ostringstream os;
  os << "grid spacing " << kSpacing << ", offset " << std::setprecision(17) << kOffset << "; A:";
  for (const auto& p : a) os << " (" << p.transpose() << ")";
  os << " B:";
  for (const auto& p : b) os << " (" << p.transpose() << ")";
  return os.str();
}

using test_support::invalidInputMessage;

// Mesh–mesh overlap of random grid tetrahedra at 1e15: equal to the exact answer at the origin,
// whether the offset is in the vertices, in both models' transforms, or split between them.
TEST(LimitsCoordinates, MeshMeshOverlapAt1e15IsExactOnTheScaledGrid) {
  std::mt19937 rng(20261122);
  int overlapping = 0;
  const int cases = 1500;
  for (int k = 0; k < cases; ++k) {
    std::uniform_int_distribution<int> shift(-5, 5);
    const auto ca = randomTetrahedron(rng, Eigen::Vector3i::Zero());
    const auto cb = randomTetrahedron(rng, Eigen::Vector3i(shift(rng), shift(rng), shift(rng)));
    const auto a0 = tetraMesh(ca, 0), b0 = tetraMesh(cb, 0);
    const auto aO = tetraMesh(ca, kOffset), bO = tetraMesh(cb, kOffset);
    const bool expected = exactOverlap(*a0, *b0);
    overlapping += expected;
    const Transform id, far = translation(kOffset);
    EXPECT_EQ(overlaps(*a0, id, *b0, id), expected) << "at the origin; " << describe(ca, cb);
    EXPECT_EQ(overlaps(*aO, id, *bO, id), expected) << "offset in the vertices; " << describe(ca, cb);
    EXPECT_EQ(overlaps(PlacedMesh{a0.get(), far}, PlacedMesh{b0.get(), far}), expected)
        << "offset in both transforms; " << describe(ca, cb);
    EXPECT_EQ(overlaps(PlacedMesh{aO.get(), id}, PlacedMesh{b0.get(), far}), expected)
        << "offset in A's vertices and B's transform; " << describe(ca, cb);
    if (::testing::Test::HasFailure()) break;
  }
  // Both answers occur often enough for the comparison to mean something.
  EXPECT_GT(overlapping, cases / 10);
  EXPECT_LT(overlapping, cases * 9 / 10);
}

// Rays at 1e15: hit or miss equals the exact answer, and t is within a few ulps of the
// coordinates' magnitude of the exact t.
TEST(LimitsCoordinates, RayHitsAt1e15MatchTheExactOracle) {
  std::mt19937 rng(15);
  std::uniform_int_distribution<int> d(-3, 3), o(-40, 40);
  int hits = 0;
  const int cases = 3000;
  for (int k = 0; k < cases; ++k) {
    const auto c = randomTetrahedron(rng, Eigen::Vector3i::Zero());
    const auto mesh = tetraMesh(c, kOffset);
    // Aimed near the tetrahedron's centre (jittered by up to 3 grid steps), so about half hit.
    const Eigen::Vector3i origin(o(rng), o(rng), o(rng));
    const Eigen::Vector3i centre = (c[0] + c[1] + c[2] + c[3]) / 4;
    Eigen::Vector3i dir = centre + Eigen::Vector3i(d(rng), d(rng), d(rng)) - origin;
    if (dir.isZero()) dir.x() = 1;
    Ray ray;
    ray.origin = at(origin, kOffset);
    ray.dir = dir.cast<Real>();
    std::optional<double> expected;
    for (std::uint32_t i = 0; i < mesh->triangleCount(); ++i) {
      const std::optional<double> t = exact::raycast(ray, mesh->triangle(i));
      if (t && (!expected || *t < *expected)) expected = t;
    }
    const std::optional<MeshRayHit> hit = raycastClosest(*mesh, ray);
    // The same ray against the mesh at the origin placed by a transform.
    const auto origin0 = tetraMesh(c, 0);
    const std::optional<MeshRayHit> placedHit = raycastClosest(PlacedMesh{origin0.get(), translation(kOffset)}, ray);
    std::ostringstream what;
    what.precision(17);
    what << "ray " << str(ray.origin) << " dir " << str(ray.dir) << "; " << describe(c, {});
    ASSERT_EQ(hit.has_value(), expected.has_value()) << what.str();
    ASSERT_EQ(placedHit.has_value(), expected.has_value()) << what.str();
    if (!expected) continue;
    ++hits;
    // Relative precision: t (a world distance) within 16 ulps of the largest coordinate.
    const double tolerance = 16 * std::numeric_limits<Real>::epsilon() * (kOffset + 64 * kSpacing);
    EXPECT_NEAR(double(hit->t), *expected, tolerance) << what.str();
    EXPECT_NEAR(double(placedHit->t), *expected, tolerance) << what.str();
    EXPECT_TRUE(hit->point.allFinite() && hit->normal.allFinite()) << what.str();
  }
  EXPECT_GT(hits, cases / 5);
  EXPECT_LT(hits, cases * 4 / 5);
}

// A scene whose models sit 1e15 from the origin: rays, region and pair queries agree with the
// same scene at the origin (the answers are ids and distances relative to the ray origin).
TEST(LimitsCoordinates, SceneAt1e15AnswersLikeTheSceneAtTheOrigin) {
  std::mt19937 rng(1015);
  std::uniform_int_distribution<int> o(-60, 60), d(-3, 3);
  Scene near, far;
  std::vector<std::shared_ptr<const Mesh>> meshes;
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector3i centre(o(rng), o(rng), o(rng));
    meshes.push_back(tetraMesh(randomTetrahedron(rng, centre), 0));
    near.add(meshes.back());
    far.add(meshes.back(), translation(kOffset));
  }
  EXPECT_EQ(near.overlappingPairs(), far.overlappingPairs());
  EXPECT_EQ(near.overlappingPairs(), near.overlappingPairs(ScenePath::BruteForce));
  for (int k = 0; k < 300; ++k) {
    Ray r0, r1;
    const Eigen::Vector3i origin(o(rng), o(rng), o(rng));
    Eigen::Vector3i dir(d(rng), d(rng), d(rng));
    if (dir.isZero()) dir.z() = 1;
    r0.origin = at(origin, 0);
    r1.origin = at(origin, kOffset);
    r0.dir = r1.dir = dir.cast<Real>();
    const auto h0 = near.raycast(r0), h1 = far.raycast(r1);
    ASSERT_EQ(h0.has_value(), h1.has_value()) << "ray " << str(r1.origin) << " dir " << str(r1.dir);
    if (h0) {
      EXPECT_EQ(h0->model, h1->model) << "ray " << str(r1.origin) << " dir " << str(r1.dir);
      EXPECT_NEAR(double(h0->hit.t), double(h1->hit.t),
                  16 * std::numeric_limits<Real>::epsilon() * kOffset);
    }
    Sphere s0{at(origin, 0), Real(4 * kSpacing)}, s1{at(origin, kOffset), Real(4 * kSpacing)};
    EXPECT_EQ(near.query(s0), far.query(s1)) << "sphere at " << str(s1.center);
  }
}

// Beyond the documented limit: 1e30 and 1e38 (and in double builds 1e150, 1e300). Meshes build,
// nothing crashes, a reported hit has a finite t and point and a unit normal, and overlaps are
// symmetric. (Exactness is not
// claimed: Wide products of coordinates near the float maximum are still finite, but the SAT
// and slab tests of the BVH round at that magnitude.)
TEST(LimitsCoordinates, HugeCoordinatesGiveFiniteSymmetricAnswers) {
  std::vector<double> magnitudes = {1e20, 1e30, 1e38};
  if (std::numeric_limits<Real>::max() > 1e300) magnitudes.insert(magnitudes.end(), {1e150, 1e300});
  std::mt19937 rng(38);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const double m : magnitudes) {
    for (int k = 0; k < 200; ++k) {
      auto mesh = [&](double scale) {
        std::vector<Vec3> v;
        for (int i = 0; i < 4; ++i)
          v.push_back(Vec3(Real(m * (0.5 + 0.4 * u(rng))), Real(m * 0.4 * u(rng)), Real(scale * u(rng))));
        return std::make_shared<const Mesh>(v, kTetraTriangles, "huge");
      };
      const auto a = mesh(m * 0.3), b = mesh(m * 0.3);
      ASSERT_TRUE(a->bounds().min.allFinite() && a->bounds().max.allFinite());
      const bool ab = overlaps(*a, Transform{}, *b, Transform{}), ba = overlaps(*b, Transform{}, *a, Transform{});
      EXPECT_EQ(ab, ba) << "magnitude " << m;
      Ray ray;
      ray.origin = Vec3(Real(-m * 0.9), Real(m * 0.1 * u(rng)), Real(m * 0.1 * u(rng)));
      ray.dir = Vec3(1, Real(0.1 * u(rng)), Real(0.1 * u(rng)));
      const auto hit = raycastClosest(*a, ray);
      if (hit) {
        EXPECT_TRUE(std::isfinite(double(hit->t)) && hit->t >= 0) << "magnitude " << m << " t " << hit->t;
        EXPECT_TRUE(hit->point.allFinite()) << "magnitude " << m << " point " << str(hit->point);
        // The normal comes from (b - a) × (c - a), which overflows Wide beyond ~1.3e154 (double
        // builds at 1e300): there it is taken from the edges scaled by powers of two.
        EXPECT_TRUE(hit->normal.allFinite()) << "magnitude " << m << " normal " << str(hit->normal);
        EXPECT_NEAR(double(hit->normal.norm()), 1.0, 1e-5) << "magnitude " << m << " normal " << str(hit->normal);
      }
    }
  }
}

// A mesh whose triangles sit at both ends of the range (x = ±0.9 of the largest Real): its
// centroids are farther apart than the largest Real, so the BVH builder cannot bin along x (the
// extent overflows; it used to write out of bounds there), and no split of the root has a finite
// cost: the root is split by count, which separates the two ends, and the SAH splits below it.
// Rays, segments, sphere and box overlaps give the brute-force answers (and, in float builds,
// the hits); mesh–mesh overlap is symmetric.
TEST(LimitsCoordinates, MeshesSpanningBothEndsOfTheRangeBuildAndAnswerAsBruteForce) {
  // Products of two coordinates near the largest float fit in Wide (double); near the largest
  // double they overflow, and only "no crash, same answers on both paths" is claimed.
  constexpr bool kWideHoldsProducts = sizeof(Real) < sizeof(Wide);
  const Real big = Real(0.9) * std::numeric_limits<Real>::max();
  std::vector<Vec3> v;
  std::vector<TriangleIndices> t;
  for (int i = 0; i < 200; ++i) {
    const Real x = i % 2 ? big : -big, y = Real(4 * (i / 2));
    const auto k = static_cast<std::uint32_t>(v.size());
    v.insert(v.end(), {Vec3(x, y, -1), Vec3(x, y + 2, -1), Vec3(x, y + 1, 1)});
    t.push_back({k, k + 1, k + 2});
  }
  const Mesh mesh(v, t, "both ends");
  const Mesh other(v, t, "both ends, again");
  for (int i = 0; i < 200; ++i) {
    const Real x = i % 2 ? big : -big, y = Real(4 * (i / 2)) + Real(1), side = i % 2 ? Real(1) : Real(-1);
    Ray ray;
    ray.origin = Vec3(0, y, 0);
    ray.dir = Vec3(side, 0, 0);
    const auto bvh = raycastClosest(mesh, ray), brute = raycastClosest(mesh, ray, {}, QueryPath::BruteForce);
    ASSERT_EQ(bvh.has_value(), brute.has_value()) << "ray " << i;
    // Hits are claimed where Wide holds the products of coordinates (float builds; see above).
    if (kWideHoldsProducts) {
      ASSERT_TRUE(bvh.has_value()) << "ray " << i;
      EXPECT_EQ(bvh->triangle, std::uint32_t(i));
    }
    if (bvh) {
      EXPECT_EQ(bvh->triangle, brute->triangle);
      EXPECT_EQ(bvh->t, brute->t);
      EXPECT_TRUE(std::isfinite(double(bvh->t)) && bvh->point.allFinite()) << "ray " << i;
    }
    EXPECT_EQ(raycastAny(mesh, ray), raycastAny(mesh, ray, {}, QueryPath::BruteForce));
    const Segment s{Vec3(x, y, -2), Vec3(x, y, 2)};
    if (kWideHoldsProducts) EXPECT_TRUE(intersects(mesh, s));
    EXPECT_EQ(intersects(mesh, s), intersects(mesh, s, QueryPath::BruteForce));
    const Sphere sphere{Vec3(x, y + 2, 0), Real(0.5)};
    EXPECT_EQ(overlaps(mesh, sphere), overlaps(mesh, sphere, QueryPath::BruteForce)) << "sphere " << i;
    const Aabb box{Vec3(x - 1, y - 3, -1), Vec3(x + 1, y - 2, 1)};
    EXPECT_EQ(overlaps(mesh, box), overlaps(mesh, box, QueryPath::BruteForce)) << "box " << i;
  }
  Transform shifted;
  shifted.translation = Vec3(0, 2, 0);
  EXPECT_EQ(overlaps(mesh, Transform{}, other, shifted), overlaps(other, shifted, mesh, Transform{}));
}

// Placements that push a mesh past the largest Real: world coordinates would overflow to
// infinity. The scene refuses them with InvalidInput and stays as it was: the hierarchy and the
// broad phase agree and queries still work (src/scene/scene.cpp: boxes are checked before
// anything is stored, and setTransform(s) undo the hierarchy change).
TEST(LimitsCoordinates, PlacementsOverflowingRealAreRefusedAndUndone) {
  // A quarter of the largest Real: the padded broad-phase box of a mesh reaching max/2 already
  // overflows (magnitude + extent), so max/4 is the practical bound of scene coordinates.
  const Real big = std::numeric_limits<Real>::max() / 4;
  const auto edge = std::make_shared<const Mesh>(
      std::vector<Vec3>{Vec3(big, 0, 0), Vec3(big, 1, 0), Vec3(big, 0, 1), Vec3(0, 0, 0)}, kTetraTriangles, "edge");
  const auto unit = std::make_shared<const Mesh>(
      std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}, kTetraTriangles, "unit");
  auto shifted = [](Real x) {
    Transform t;
    t.translation = Vec3(x, 0, 0);
    return t;
  };
  Scene scene;
  const ModelId root = scene.add(unit, shifted(10));
  const ModelId child = scene.add(edge, Transform{}, root);  // fine: big + 10 is finite
  const Aabb rootBox = scene.bounds(root), childBox = scene.bounds(child);
  auto unchanged = [&](const char* what) {
    EXPECT_EQ(scene.size(), 2u) << what;
    EXPECT_EQ(scene.broadPhase().size(), 2u) << what;
    EXPECT_EQ(scene.models().world(root).translation, Vec3(10, 0, 0)) << what;
    EXPECT_EQ(scene.bounds(root).min, rootBox.min) << what;
    EXPECT_EQ(scene.bounds(child).max, childBox.max) << what;
    Ray ray;
    ray.origin = Vec3(10.25f, 0.25f, -5);
    ray.dir = Vec3(0, 0, 1);
    const auto hit = scene.raycast(ray);
    ASSERT_TRUE(hit.has_value()) << what;
    EXPECT_EQ(hit->model, root) << what;
  };
  Transform far;
  far.translation = Vec3(Real(3.2) * big, 0, 0);  // 3.2·big + big overflows
  std::string m = invalidInputMessage([&] { scene.add(edge, far); });
  EXPECT_NE(m.find("beyond the representable range"), std::string::npos) << m;
  unchanged("after a refused add");
  // Moving the root moves the child past the limit: refused, undone.
  m = invalidInputMessage([&] { scene.setTransform(root, far); });
  EXPECT_NE(m.find("model " + std::to_string(child)), std::string::npos) << m;
  unchanged("after a refused setTransform");
  m = invalidInputMessage([&] { scene.setTransforms({{root, shifted(20)}, {child, far}}); });
  EXPECT_FALSE(m.empty());
  unchanged("after a refused setTransforms");
  const ModelId id = scene.add(unit);  // finite placements are still accepted
  EXPECT_TRUE(scene.models().contains(id));
  EXPECT_EQ(scene.broadPhase().size(), 3u);
}

// ---- non-finite input is InvalidInput ---------------------------------------------------------

TEST(LimitsCoordinates, NonFiniteInputIsInvalidInput) {
  const Real inf = std::numeric_limits<Real>::infinity(), nan = std::numeric_limits<Real>::quiet_NaN();
  const std::vector<TriangleIndices> tri = {{0, 1, 2}};
  for (const Real bad : {inf, -inf, nan}) {
    const std::string m = invalidInputMessage([&] { Mesh({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, bad, 0)}, tri, "m"); });
    EXPECT_NE(m.find("vertex 2"), std::string::npos) << m;
    Ray ray;
    ray.origin = Vec3(bad, 0, 0);
    EXPECT_NE(invalidInputMessage([&] { validate(ray); }).find("ray"), std::string::npos);
    ray.origin = Vec3::Zero();
    ray.dir = Vec3(0, bad, 1);
    EXPECT_NE(invalidInputMessage([&] { validate(ray); }).find("ray"), std::string::npos);
    Transform t;
    t.translation = Vec3(0, 0, bad);
    EXPECT_NE(invalidInputMessage([&] { validate(t); }).find("translation"), std::string::npos);
    Scene scene;
    const auto mesh = std::make_shared<const Mesh>(std::vector<Vec3>{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, tri);
    EXPECT_NE(invalidInputMessage([&] { scene.add(mesh, t); }).find("translation"), std::string::npos);
    const ModelId id = scene.add(mesh);
    EXPECT_NE(invalidInputMessage([&] { scene.setTransform(id, t); }).find("translation"), std::string::npos);
    Sphere s{Vec3(bad, 0, 0), 1};
    EXPECT_FALSE(invalidInputMessage([&] { validate(s); }).empty());
  }
}

TEST(LimitsCoordinates, OffFilesWithNonFiniteOrOutOfRangeNumbersAreInvalidInput) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("crux-test-limits-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string tooBig = std::numeric_limits<Real>::max() > 1e300 ? "1e309" : "1e39";
  for (const std::string& value : {std::string("inf"), std::string("nan"), std::string("-inf"), tooBig}) {
    const auto p = dir / ("bad.off");
    std::ofstream(p) << "OFF\n3 1 0\n0 0 0\n1 " << value << " 0\n0 1 0\n3 0 1 2\n";
    const std::string m = invalidInputMessage([&] { loadMesh(p.string()); });
    EXPECT_NE(m.find("vertex 1"), std::string::npos) << value << ": " << m;
  }
  // The largest finite value loads.
  const auto p = dir / "max.off";
  std::ofstream(p) << "OFF\n3 1 0\n0 0 0\n" << (std::numeric_limits<Real>::max() > 1e300 ? "1e308" : "3e38")
                   << " 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(loadMesh(p.string()).triangleCount(), 1u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace crux
