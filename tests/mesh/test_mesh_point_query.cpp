// Tests of src/mesh/mesh_point_query.cpp: the closest surface point of a mesh to a point, BVH
// path against the brute-force path (identical bits), against a closed-form answer on a unit
// cube, with ties resolved to the lowest triangle index and a distance limit.

#include <crux/mesh/mesh_point_query.hpp>

#include <crux/geometry/closest_point.hpp>

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "support/scene_fixtures.hpp"
#include "support/test_scale.hpp"  // CRUX_TEST_SCALE: fewer cases in the sanitizer stage

namespace crux {
namespace {

Mesh unitCube() {
  std::vector<Vec3> v;
  for (int i = 0; i < 8; ++i) v.emplace_back(Real(i & 1), Real((i >> 1) & 1), Real((i >> 2) & 1));
  std::vector<TriangleIndices> t = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                    {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return Mesh(std::move(v), std::move(t), "cube");
}

TEST(MeshClosestPoint, BvhEqualsBruteForceBitForBit) {
  const auto mesh = test::bumpySphere(24, 32);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-2.5, 2.5);
  for (int i = 0, n = test::scaledCases(2000, 300); i < n; ++i) {
    const Vec3 p(Real(u(rng)), Real(u(rng)), Real(u(rng)));
    const MeshClosestPoint a = closestPoint(*mesh, p);
    const MeshClosestPoint b = closestPoint(*mesh, p, kNoLimit, QueryPath::BruteForce);
    ASSERT_TRUE(a.found && b.found);
    ASSERT_EQ(a.triangle, b.triangle) << test::str(p);
    ASSERT_EQ(std::memcmp(&a.distance, &b.distance, sizeof(Real)), 0) << test::str(p);
    ASSERT_TRUE(test::sameBits(a.point, b.point)) << test::str(p);
  }
}

TEST(MeshClosestPoint, PointOutsideACubeGetsTheClampedPoint) {
  const Mesh cube = unitCube();
  const Vec3 p(Real(3), Real(0.5), Real(-2));
  const MeshClosestPoint r = closestPoint(cube, p);
  ASSERT_TRUE(r.found);
  EXPECT_EQ(r.point, Vec3(Real(1), Real(0.5), Real(0)));
  EXPECT_EQ(r.distance, std::sqrt(Real(4 + 4)));
  // the corner-edge point (1, 0.5, 0) lies on four triangles; the lowest index touching it wins
  std::uint32_t lowest = 0xffffffffu;
  for (std::uint32_t i = 0; i < cube.triangleCount() && lowest == 0xffffffffu; ++i)
    if (squaredDistance(cube.triangle(i), r.point) == 0) lowest = i;
  EXPECT_EQ(r.triangle, lowest);
}

TEST(MeshClosestPoint, PointOnTheSurfaceIsAtDistanceZero) {
  const Mesh cube = unitCube();
  const MeshClosestPoint r = closestPoint(cube, Vec3(Real(0.25), Real(0.5), Real(1)));
  ASSERT_TRUE(r.found);
  EXPECT_EQ(r.distance, Real(0));
  EXPECT_EQ(r.point, Vec3(Real(0.25), Real(0.5), Real(1)));
}

TEST(MeshClosestPoint, NothingWithinMaxDistanceIsNotFound) {
  const Mesh cube = unitCube();
  const Vec3 p(Real(3), Real(0.5), Real(0.5));
  EXPECT_FALSE(closestPoint(cube, p, Real(1.5)).found);
  EXPECT_FALSE(closestPoint(cube, p, Real(1.5), QueryPath::BruteForce).found);
  const MeshClosestPoint r = closestPoint(cube, p, Real(2));
  ASSERT_TRUE(r.found);
  EXPECT_EQ(r.distance, Real(2));
}

}  // namespace
}  // namespace crux
